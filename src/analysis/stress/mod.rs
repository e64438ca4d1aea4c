//! Numerical stress tests (`caustic stress`): rays built to hit the places
//! where floating-point ray tracing breaks — shared edges and vertices,
//! surfaces at extreme scales or far from the origin, rays parallel to the
//! KD-tree's split planes, degenerate and needle triangles, grazing rays on
//! spheres, chains of total internal reflection — and full renders with
//! NaN-producing inputs. Each case and configuration gives one [`StressRow`]
//! with its number of trials and failures.
//!
//! # Default and measured configurations
//!
//! A row is [`Role::Default`] when it measures a configuration the renderer
//! relies on: the KD-tree with the watertight test (the scene default),
//! Embree as built by default (`AccelKind::default_kind()`, not robust) for
//! every case but watertightness, Embree in robust mode for watertightness
//! (the configuration to use when edges matter, `--embree-robust`), and the
//! KD-tree against brute force for both triangle tests on ordinary and
//! split-plane rays (the KD-tree promises the oracle's answers whatever the
//! test). Default rows must show zero failures (the tests and the exit code
//! of `caustic stress` assert it). [`Role::Measured`] rows are reported
//! honestly and never fail the run, each for a stated reason: Möller–Trumbore
//! and Embree's default mode at shared edges, Embree against the watertight
//! oracle on needles (a different, equally valid triangle test), and the
//! Möller–Trumbore KD-tree against Möller–Trumbore brute force on needles
//! (not a default configuration, and there the oracle itself is wrong: see
//! [`degenerate`]).
//!
//! # Determinism
//!
//! Trial `i` of a case draws from `Rng::new(seed, Domain::Analysis, case, i)`;
//! trials run on rayon and the counts are summed, so the table is identical
//! for any thread count.

pub mod degenerate;
pub mod grazing;
pub mod parallel;
pub mod spawn;
pub mod tir;
pub mod watertight;

use crate::accel::{self, Accel, AccelError, AccelKind, AccelOptions, TriangleTest};
use crate::math::rng::{Domain, Rng};
use crate::math::{Vec3, Vec3A};
use crate::scene::{Camera, Material, Mesh, Object, Scene, Shape};
use rayon::prelude::*;
use serde::Serialize;
use std::fmt;
use std::sync::Arc;

/// Whether a row's failures fail the run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Role {
    /// A configuration the renderer relies on: must have zero failures.
    Default,
    /// Measured only (reported, never fails the run).
    Measured,
}

/// One line of the table.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StressRow {
    /// Case, e.g. "1 watertight: torus".
    pub case: String,
    /// Backend and configuration.
    pub config: String,
    /// Default or measured only.
    pub role: Role,
    /// Rays or trials counted.
    pub trials: u64,
    /// Failures among them (see each case's module for what fails).
    pub failures: u64,
    /// Short note: failure breakdown, skipped trials, worst values.
    pub note: String,
}

impl StressRow {
    /// A row.
    pub fn new(case: impl Into<String>, config: impl Into<String>, role: Role, trials: u64, failures: u64) -> Self {
        Self {
            case: case.into(),
            config: config.into(),
            role,
            trials,
            failures,
            note: String::new(),
        }
    }

    /// With a note.
    pub fn note(mut self, note: impl Into<String>) -> Self {
        self.note = note.into();
        self
    }

    /// True when this row fails the run (a default row with failures).
    pub fn fails_run(&self) -> bool {
        self.role == Role::Default && self.failures > 0
    }
}

/// Settings of a stress run.
#[derive(Clone, Debug)]
pub struct StressOptions {
    /// Seed of every random stream.
    pub seed: u64,
    /// Rays (or trials) per case and configuration.
    pub rays: u64,
    /// The dragon asset for the watertightness case (`io::assets` name), or
    /// `None` to leave it out. It is only looked up locally, never fetched.
    pub dragon: Option<String>,
    /// Image width of the full renders of case 7 (height is ¾ of it).
    pub render_width: u32,
    /// Print each case's time on stderr.
    pub progress: bool,
}

impl Default for StressOptions {
    fn default() -> Self {
        Self {
            seed: 0,
            rays: 200_000,
            dragon: Some("dragon_vrip.ply.gz".into()),
            render_width: 128,
            progress: false,
        }
    }
}

/// The table.
#[derive(Clone, Debug, Serialize)]
pub struct StressReport {
    /// Seed used.
    pub seed: u64,
    /// Rays per case and configuration.
    pub rays: u64,
    /// The rows, case by case.
    pub rows: Vec<StressRow>,
}

impl StressReport {
    /// Failures summed over the default rows.
    pub fn default_failures(&self) -> u64 {
        self.rows
            .iter()
            .filter(|r| r.role == Role::Default)
            .map(|r| r.failures)
            .sum()
    }

    /// The report as pretty-printed JSON.
    pub fn to_json(&self) -> String {
        #[derive(Serialize)]
        struct Json<'a> {
            #[serde(flatten)]
            report: &'a StressReport,
            default_failures: u64,
        }
        serde_json::to_string_pretty(&Json {
            report: self,
            default_failures: self.default_failures(),
        })
        .expect("plain data serialises")
    }
}

impl StressReport {
    /// Writes [`to_json`](Self::to_json) to `path` atomically (temporary
    /// file in the same directory, fsync, rename).
    pub fn write_json(&self, path: &std::path::Path) -> std::io::Result<()> {
        use std::io::Write;
        let dir = path
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
            .unwrap_or(std::path::Path::new("."));
        let mut file = tempfile::NamedTempFile::new_in(dir)?;
        file.write_all(self.to_json().as_bytes())?;
        file.write_all(b"\n")?;
        file.as_file().sync_all()?;
        file.persist(path).map_err(|e| e.error)?;
        Ok(())
    }
}

impl fmt::Display for StressReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let wc = self
            .rows
            .iter()
            .map(|r| r.case.chars().count())
            .max()
            .unwrap_or(4)
            .max(4);
        let wg = self
            .rows
            .iter()
            .map(|r| r.config.chars().count())
            .max()
            .unwrap_or(6)
            .max(6);
        writeln!(
            f,
            "{:<wc$}  {:<wg$}  {:<8}  {:>9}  {:>8}  note",
            "case", "config", "role", "trials", "failures"
        )?;
        for r in &self.rows {
            let role = match r.role {
                Role::Default => "default",
                Role::Measured => "measured",
            };
            writeln!(
                f,
                "{:<wc$}  {:<wg$}  {:<8}  {:>9}  {:>8}  {}",
                r.case, r.config, role, r.trials, r.failures, r.note
            )?;
        }
        write!(
            f,
            "default-configuration failures: {} (seed {}, {} rays per case and configuration)",
            self.default_failures(),
            self.seed,
            self.rays
        )
    }
}

/// Runs every case.
pub fn run_stress(options: &StressOptions) -> StressReport {
    type Case = fn(&StressOptions) -> Vec<StressRow>;
    let cases: [(&str, Case); 7] = [
        ("1 watertightness", watertight::run),
        ("2 self-intersection at scales", spawn::run_scales),
        ("3 translated scene", spawn::run_translated),
        ("4 split-plane rays", parallel::run),
        ("5 degenerate triangles", degenerate::run),
        ("6 grazing rays", grazing::run),
        ("7 TIR and NaN guards", tir::run),
    ];
    let mut rows = Vec::new();
    for (name, case) in cases {
        let start = std::time::Instant::now();
        rows.extend(case(options));
        if options.progress {
            eprintln!("stress: case {name} done in {:.1} s", start.elapsed().as_secs_f64());
        }
    }
    StressReport {
        seed: options.seed,
        rays: options.rays,
        rows,
    }
}

/// An accelerator configuration under test.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    /// KD-tree, watertight triangle test (the scene default).
    KdWatertight,
    /// KD-tree, Möller–Trumbore.
    KdMoller,
    /// Brute force, watertight (the oracle).
    BruteWatertight,
    /// Brute force, Möller–Trumbore.
    BruteMoller,
    /// Embree with the default options (not robust).
    Embree,
    /// Embree with `RTC_SCENE_FLAG_ROBUST`.
    EmbreeRobust,
}

impl Backend {
    /// Name in the table.
    pub fn name(self) -> &'static str {
        match self {
            Backend::KdWatertight => "kdtree watertight",
            Backend::KdMoller => "kdtree moller-trumbore",
            Backend::BruteWatertight => "brute watertight",
            Backend::BruteMoller => "brute moller-trumbore",
            Backend::Embree => "embree",
            Backend::EmbreeRobust => "embree robust",
        }
    }

    /// True for the Embree configurations.
    pub fn is_embree(self) -> bool {
        matches!(self, Backend::Embree | Backend::EmbreeRobust)
    }

    /// True when this build can construct it.
    pub fn available(self) -> bool {
        !self.is_embree() || cfg!(feature = "embree")
    }

    /// Builds it over `scene`.
    pub fn build(self, scene: &Scene) -> Result<Box<dyn Accel>, AccelError> {
        let (kind, test, robust) = match self {
            Backend::KdWatertight => (AccelKind::KdTree, TriangleTest::Watertight, false),
            Backend::KdMoller => (AccelKind::KdTree, TriangleTest::MollerTrumbore, false),
            Backend::BruteWatertight => (AccelKind::Brute, TriangleTest::Watertight, false),
            Backend::BruteMoller => (AccelKind::Brute, TriangleTest::MollerTrumbore, false),
            Backend::Embree => (AccelKind::Embree, TriangleTest::Watertight, false),
            Backend::EmbreeRobust => (AccelKind::Embree, TriangleTest::Watertight, true),
        };
        let options = AccelOptions {
            triangle_test: test,
            embree_robust: robust,
            ..AccelOptions::default()
        };
        accel::build(scene, kind, &options)
    }

    /// The backends the renderer uses by default: the KD-tree (watertight)
    /// and, when compiled in, Embree with its default options.
    pub fn defaults() -> Vec<Backend> {
        [Backend::KdWatertight, Backend::Embree]
            .into_iter()
            .filter(|b| b.available())
            .collect()
    }
}

/// A row for a configuration that could not run (not compiled in, or the
/// build failed): no trials, the reason as note; default rows that cannot
/// build count one failure.
pub fn unavailable_row(case: &str, backend: Backend, role: Role, reason: &str) -> StressRow {
    let failures = u64::from(role == Role::Default && backend.available());
    StressRow::new(case, backend.name(), role, 0, failures).note(reason)
}

/// Runs `f`, turning a panic into a failed row: a panic is a failure of the
/// case, reported rather than aborting the whole table.
pub fn guarded(case: &str, config: &str, role: Role, f: impl FnOnce() -> Vec<StressRow>) -> Vec<StressRow> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)) {
        Ok(rows) => rows,
        Err(payload) => {
            let msg = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            vec![StressRow::new(case, config, role, 1, 1).note(format!("PANIC: {msg}"))]
        }
    }
}

/// Counters summed over trials (commutative sums: thread-count independent).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Tally {
    /// Trials counted.
    pub trials: u64,
    /// Failures.
    pub failures: u64,
    /// Case-specific extra counters (meaning documented by each case).
    pub extra: [u64; 6],
}

impl std::ops::Add for Tally {
    type Output = Tally;
    fn add(self, o: Tally) -> Tally {
        let mut extra = self.extra;
        for (e, x) in extra.iter_mut().zip(o.extra) {
            *e += x;
        }
        Tally {
            trials: self.trials + o.trials,
            failures: self.failures + o.failures,
            extra,
        }
    }
}

/// Runs trials `0..n` in parallel and sums their tallies.
pub fn tally(n: u64, trial: impl Fn(u64) -> Tally + Sync + Send) -> Tally {
    (0..n).into_par_iter().map(trial).reduce(Tally::default, |a, b| a + b)
}

/// The random stream of trial `i` of case `case`.
pub fn trial_rng(seed: u64, case: u64, i: u64) -> Rng {
    Rng::new(seed, Domain::Analysis, 0x5757_0000 + case, i)
}

/// A uniform direction on the unit sphere.
pub fn random_unit(rng: &mut Rng) -> Vec3A {
    let z = 1.0 - 2.0 * rng.f32();
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * rng.f32();
    Vec3A::new(r * phi.cos(), r * phi.sin(), z)
}

/// `10^U(lo, hi)`: log-uniform.
pub fn log_uniform(rng: &mut Rng, lo_exp: f32, hi_exp: f32) -> f32 {
    10f32.powf(lo_exp + (hi_exp - lo_exp) * rng.f32())
}

/// A scene around hand-made objects: one diffuse material (index 0) unless
/// more are given, a camera that nothing here uses, no lights.
pub fn scene_of(meshes: Vec<Arc<Mesh>>, objects: Vec<(Shape, u32)>, materials: Vec<Material>) -> Scene {
    let materials = if materials.is_empty() {
        vec![Material::diffuse("grey", Vec3A::splat(0.5))]
    } else {
        materials
    };
    Scene {
        media: Default::default(),
        ambient: Vec3A::ZERO,
        water_medium: None,
        camera: Camera::new(Vec3A::new(0.0, 0.0, 10.0), Vec3A::ZERO, Vec3A::Y, 45.0).expect("valid camera"),
        materials,
        lights: Vec::new(),
        meshes,
        objects: objects
            .into_iter()
            .enumerate()
            .map(|(i, (shape, material))| Object {
                name: format!("object {i}"),
                shape,
                material,
            })
            .collect(),
    }
}

/// A closed axis-aligned box mesh `[min, max]` (12 triangles, outward).
pub fn box_mesh(min: Vec3, max: Vec3) -> Mesh {
    let p: Vec<Vec3> = (0..8)
        .map(|i| {
            Vec3::new(
                if i & 1 == 0 { min.x } else { max.x },
                if i & 2 == 0 { min.y } else { max.y },
                if i & 4 == 0 { min.z } else { max.z },
            )
        })
        .collect();
    // Faces as quads (a, b, c, d) counter-clockwise seen from outside.
    let quads = [
        [0, 4, 6, 2], // -x
        [1, 3, 7, 5], // +x
        [0, 1, 5, 4], // -y
        [2, 6, 7, 3], // +y
        [0, 2, 3, 1], // -z
        [4, 5, 7, 6], // +z
    ];
    let tris = quads.iter().flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]]).collect();
    Mesh::new("box", p, tris, None).expect("a box is a valid mesh")
}

/// Formats a count with its share of `of`.
pub fn share(n: u64, of: u64) -> String {
    if of == 0 {
        format!("{n}")
    } else {
        format!("{n} ({:.3}%)", 100.0 * n as f64 / of as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_mesh_is_closed_and_outward() {
        let m = box_mesh(Vec3::splat(-1.0), Vec3::splat(1.0));
        let volume: f32 = (0..m.triangles.len())
            .map(|i| {
                let [a, b, c] = m.corners(i);
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        assert!((volume - 8.0).abs() < 1e-5, "{volume}");
    }

    #[test]
    fn tally_is_thread_count_independent() {
        let f = |i: u64| Tally {
            trials: 1,
            failures: u64::from(trial_rng(3, 1, i).f32() < 0.1),
            extra: [i % 2, 0, 0, 0, 0, 0],
        };
        let a = tally(10_000, f);
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let b = one.install(|| tally(10_000, f));
        assert_eq!(a, b);
        assert_eq!(a.trials, 10_000);
        assert_eq!(a.extra[0], 5_000);
    }

    #[test]
    fn a_panic_becomes_a_failed_row() {
        // (The default hook prints the panic message; that is expected.)
        let rows = guarded("c", "k", Role::Default, || panic!("boom"));
        assert_eq!(rows.len(), 1);
        assert!(rows[0].fails_run() && rows[0].note.contains("boom"));
    }

    #[test]
    fn report_json_and_table_name_every_row() {
        let report = StressReport {
            seed: 1,
            rays: 10,
            rows: vec![
                StressRow::new("a", "kdtree", Role::Default, 10, 0),
                StressRow::new("b", "embree", Role::Measured, 10, 3).note("three"),
            ],
        };
        let json: serde_json::Value = serde_json::from_str(&report.to_json()).unwrap();
        assert_eq!(json["rows"][1]["failures"], 3);
        assert_eq!(json["rows"][1]["role"], "measured");
        assert_eq!(json["default_failures"], 0);
        let table = report.to_string();
        assert!(table.contains("three") && table.contains("default-configuration failures: 0"));
    }
}
