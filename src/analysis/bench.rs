//! `caustic bench`: for each scene and accelerator, the build time and
//! memory, the ray throughput (Mrays/s) of camera, shadow and incoherent
//! rays ([`super::rays`]) and a full render at reduced settings; a table
//! ([`BenchReport`]'s `Display`) and the same figures as JSON
//! ([`BenchReport::to_json`]).
//!
//! How the figures are taken:
//! * **Same work for every accelerator.** The ray sets are built once per
//!   scene, from one seed, before any timing. Shadow rays start at the camera
//!   rays' hit points, found by the *baseline* accelerator (Embree when it is
//!   measured, else the first one listed), which is also what the others'
//!   speed ratios and hit counts are compared with. Hit counts are reported
//!   for every accelerator so that a table visibly compares the same work.
//! * **Throughput** is the best of `repeats` runs of a set (the machine may
//!   be shared; the best run is the least disturbed one), on the current
//!   rayon pool in chunks of [`rays::CHUNK`], wall time; rays per CPU second
//!   are in the JSON too.
//! * **Memory**: the accelerator's own figure (`AccelStats::memory_bytes`),
//!   and the process's resident set: before the build, its peak during the
//!   build, and its peak over the accelerator's whole run (queries and
//!   render, with the film and photon map). The kernel's peak counter is
//!   reset before each accelerator (`/proc/self/clear_refs`), and the
//!   previous accelerator is freed first; `peak_rss_reset` says whether the
//!   reset worked (if not, peaks are those of the whole process so far).
//! * **Full render**: the scene's own integrator at reduced settings (by
//!   default 640×360, 1 spp, at most [`DEFAULT_BENCH_PHOTONS`] photons),
//!   photon pass included; its Mrays/s counts every ray the render cast
//!   (camera, shadow, secondary and photon rays) over its wall time.

use super::rays::{self, Query, RayKind, RaySet};
use crate::accel::{self, Accel, AccelError, AccelKind, AccelOptions};
use crate::integrator::{self, RenderPlan};
use crate::memory;
use crate::scene::{self, Scene, SceneError};
use serde::Serialize;
use std::fmt;
use std::io::Write;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Default number of camera rays and of incoherent rays per scene.
pub const DEFAULT_RAYS: usize = 1_000_000;
/// Default number of timed runs per ray set (the best is reported).
pub const DEFAULT_REPEATS: u32 = 3;
/// Most photons the full render emits unless `--photons` says otherwise
/// (fewer when the scene asks for fewer).
pub const DEFAULT_BENCH_PHOTONS: u64 = 100_000;
/// Largest number of repeats accepted.
pub const MAX_REPEATS: u32 = 1000;

/// Settings of the full render.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOverrides {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Photons emitted; `None`: the scene's count, at most [`DEFAULT_BENCH_PHOTONS`].
    pub photons: Option<u64>,
}

impl Default for RenderOverrides {
    fn default() -> Self {
        Self {
            width: 640,
            height: 360,
            spp: 1,
            photons: None,
        }
    }
}

/// What `caustic bench` measures.
#[derive(Clone, Debug)]
pub struct BenchOptions {
    /// Accelerators, in the order given (the baseline is run first).
    pub accels: Vec<AccelKind>,
    /// Camera rays and incoherent rays per scene (shadow rays: one per light
    /// per camera hit).
    pub rays: usize,
    /// Seed of the ray sets and of the render.
    pub seed: u64,
    /// Timed runs per ray set; the best is reported.
    pub repeats: u32,
    /// The full render.
    pub render: RenderOverrides,
    /// Embree build quality and robust mode (the triangle test comes from each scene).
    pub accel_options: AccelOptions,
}

impl Default for BenchOptions {
    fn default() -> Self {
        Self {
            accels: default_accels(),
            rays: DEFAULT_RAYS,
            seed: 0,
            repeats: DEFAULT_REPEATS,
            render: RenderOverrides::default(),
            accel_options: AccelOptions::default(),
        }
    }
}

/// Every compiled-in accelerator except the brute-force oracle: Embree (with
/// the `embree` feature) and the KD-tree.
pub fn default_accels() -> Vec<AccelKind> {
    if cfg!(feature = "embree") {
        vec![AccelKind::Embree, AccelKind::KdTree]
    } else {
        vec![AccelKind::KdTree]
    }
}

/// The scene benched when none is given: `scenes/dragon.toml` of the current
/// directory, else the one of the source tree this binary was built from.
pub fn default_scene() -> PathBuf {
    let relative = PathBuf::from("scenes/dragon.toml");
    if relative.exists() {
        relative
    } else {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dragon.toml")
    }
}

/// Why a bench could not run.
#[derive(Debug, Error)]
pub enum BenchError {
    /// A scene file could not be loaded (the error names the file and place).
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// An option is out of range.
    #[error("{0}")]
    Options(String),
    /// An option is out of range for one scene.
    #[error("{}: {message}", scene.display())]
    SceneOptions {
        /// The scene file.
        scene: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// An accelerator could not be built.
    #[error("{}: {source}", scene.display())]
    Accel {
        /// The scene file.
        scene: PathBuf,
        /// The accelerator's error.
        source: AccelError,
    },
    /// The JSON output cannot be written.
    #[error("{}: {message}", path.display())]
    Output {
        /// The JSON file.
        path: PathBuf,
        /// What failed.
        message: String,
    },
}

impl BenchError {
    /// True when the error comes from the input (scene, options, output
    /// path, an accelerator that is not compiled in) rather than from a
    /// failure inside the renderer or the system: the CLI exits with 2.
    pub fn is_bad_input(&self) -> bool {
        match self {
            BenchError::Accel { source, .. } => matches!(source, AccelError::Unavailable(_) | AccelError::Scene(_)),
            _ => true,
        }
    }
}

/// The whole report: one entry per scene.
#[derive(Clone, Debug, Serialize)]
pub struct BenchReport {
    /// Version of caustic that measured.
    pub caustic_version: String,
    /// Worker threads of the rayon pool the queries and renders ran on.
    pub threads: usize,
    /// Seed of the ray sets and renders.
    pub seed: u64,
    /// Camera rays and incoherent rays per scene.
    pub rays_per_kind: usize,
    /// Timed runs per ray set (the best is reported).
    pub repeats: u32,
    /// `/proc/loadavg` (1, 5, 15 minutes) when the bench started.
    pub load_average_start: Option<[f64; 3]>,
    /// `/proc/loadavg` when it ended.
    pub load_average_end: Option<[f64; 3]>,
    /// One entry per scene, in the order given.
    pub scenes: Vec<SceneBench>,
}

/// The figures of one scene.
#[derive(Clone, Debug, Serialize)]
pub struct SceneBench {
    /// The scene file as given.
    pub scene: String,
    /// Objects (top-level instances).
    pub objects: usize,
    /// Triangles of the distinct meshes.
    pub triangles: u64,
    /// Triangles counting every instance.
    pub instanced_triangles: u64,
    /// Lights.
    pub lights: usize,
    /// The accelerator the others are compared with, whose camera hits the shadow rays start from.
    pub baseline: String,
    /// The ray sets, identical for every accelerator.
    pub ray_sets: Vec<RaySetInfo>,
    /// Settings of the full render.
    pub render_settings: RenderSettingsInfo,
    /// One entry per accelerator, baseline first.
    pub accelerators: Vec<AccelBench>,
    /// Each other accelerator against the baseline.
    pub comparisons: Vec<Comparison>,
}

/// One ray set.
#[derive(Clone, Debug, Serialize)]
pub struct RaySetInfo {
    /// Kind of ray.
    pub kind: RayKind,
    /// Query it is timed with.
    pub query: Query,
    /// Number of rays.
    pub rays: usize,
}

/// The settings the full render ran with.
#[derive(Clone, Debug, Serialize)]
pub struct RenderSettingsInfo {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Photons emitted when the render plan runs the photon pass.
    pub photons: u64,
    /// Whether the plan ran the photon pass (the scene has a specular caster and lights).
    pub photon_pass: bool,
}

/// The figures of one accelerator on one scene.
#[derive(Clone, Debug, Serialize)]
pub struct AccelBench {
    /// Accelerator name (`embree`, `kdtree`, `brute`).
    pub name: String,
    /// Wall time of the build.
    pub build_seconds: f64,
    /// Bytes held by the acceleration structures (the accelerator's own count).
    pub memory_bytes: u64,
    /// Resident set just before the build (scene, ray sets when already built).
    pub rss_before_build_bytes: Option<u64>,
    /// Peak resident set during the build.
    pub peak_rss_build_bytes: Option<u64>,
    /// Peak resident set over this accelerator's build, queries and render.
    pub peak_rss_bytes: Option<u64>,
    /// Whether the kernel's peak counter was reset before the build.
    pub peak_rss_reset: bool,
    /// Throughput per ray set, in the order of `ray_sets`.
    pub rays: Vec<RayBench>,
    /// The full render.
    pub render: RenderBench,
}

impl AccelBench {
    /// Peak resident set during the build minus the resident set before it:
    /// the memory the build needed at its peak, comparable between
    /// accelerators whatever the process held before (scene, ray sets).
    pub fn build_rss_increase_bytes(&self) -> Option<u64> {
        let (before, peak) = (self.rss_before_build_bytes?, self.peak_rss_build_bytes?);
        self.peak_rss_reset.then(|| peak.saturating_sub(before))
    }
}

/// Throughput of one ray set through one accelerator.
#[derive(Clone, Debug, Serialize)]
pub struct RayBench {
    /// Kind of ray.
    pub kind: RayKind,
    /// Query timed.
    pub query: Query,
    /// Rays cast per run.
    pub rays: usize,
    /// Rays that hit (closest) or were occluded: the same in every run.
    pub hits: usize,
    /// Wall time of the best run.
    pub seconds: f64,
    /// Millions of rays per second of the best run; `None` for an empty set.
    pub mrays_per_s: Option<f64>,
    /// Process CPU time of the best run (10 ms resolution), when known.
    pub cpu_seconds: Option<f64>,
    /// Millions of rays per CPU second of the best run, when measurable.
    pub mrays_per_cpu_s: Option<f64>,
    /// Wall time of every run, in order.
    pub runs_seconds: Vec<f64>,
}

/// The full render with one accelerator.
#[derive(Clone, Debug, Serialize)]
pub struct RenderBench {
    /// Wall time, photon pass included.
    pub seconds: f64,
    /// Wall time of the photon pass (trace, map build, precomputation); 0 when skipped.
    pub photon_seconds: f64,
    /// Rays cast for the image (camera, shadow, secondary).
    pub image_rays: u64,
    /// Rays cast by the photon pass.
    pub photon_rays: u64,
    /// All rays over the wall time, in millions per second.
    pub mrays_per_s: f64,
    /// Camera samples whose radiance was NaN or infinite (dropped).
    pub dropped_samples: u64,
}

/// One accelerator against the baseline.
#[derive(Clone, Debug, Serialize)]
pub struct Comparison {
    /// The accelerator compared.
    pub accel: String,
    /// The baseline it is compared with.
    pub baseline: String,
    /// Build time divided by the baseline's.
    pub build_time_ratio: f64,
    /// Full-render wall time divided by the baseline's.
    pub render_time_ratio: f64,
    /// Per ray set: throughput ratio and hit counts.
    pub rays: Vec<KindComparison>,
}

/// One ray set, one accelerator against the baseline.
#[derive(Clone, Debug, Serialize)]
pub struct KindComparison {
    /// Kind of ray.
    pub kind: RayKind,
    /// Mrays/s divided by the baseline's (`None` for an empty set).
    pub mrays_ratio: Option<f64>,
    /// Hits of the accelerator.
    pub hits: usize,
    /// Hits of the baseline.
    pub baseline_hits: usize,
    /// `hits − baseline_hits`.
    pub hits_difference: i64,
}

impl BenchReport {
    /// The report as pretty-printed JSON (the schema is the `Serialize`
    /// form of these structs; see the README's "Benchmarks" section).
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("the report holds only finite numbers and strings")
    }

    /// Writes [`to_json`](Self::to_json) to `path` atomically (temporary
    /// file in the same directory, fsync, rename).
    pub fn write_json(&self, path: &Path) -> Result<(), BenchError> {
        let fail = |message: String| BenchError::Output {
            path: path.to_path_buf(),
            message,
        };
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let mut tmp = tempfile::Builder::new()
            .prefix(".caustic-bench-")
            .suffix(".tmp")
            .tempfile_in(&dir)
            .map_err(|e| fail(format!("cannot create a temporary file in {}: {e}", dir.display())))?;
        tmp.write_all(self.to_json().as_bytes())
            .and_then(|()| tmp.write_all(b"\n"))
            .and_then(|()| tmp.as_file().sync_all())
            .map_err(|e| fail(format!("writing: {e}")))?;
        tmp.persist(path)
            .map_err(|e| fail(format!("renaming the temporary file over it: {}", e.error)))?;
        Ok(())
    }
}

/// Checks the options that do not depend on a scene.
fn check_options(options: &BenchOptions) -> Result<(), BenchError> {
    if options.accels.is_empty() {
        return Err(BenchError::Options("no accelerator to bench".into()));
    }
    if options.rays == 0 {
        return Err(BenchError::Options("--rays must be at least 1".into()));
    }
    if !(1..=MAX_REPEATS).contains(&options.repeats) {
        return Err(BenchError::Options(format!(
            "--repeats {}: must be in 1..={MAX_REPEATS}",
            options.repeats
        )));
    }
    let r = &options.render;
    crate::limits::check_image_limits(r.width, r.height, r.spp)
        .map_err(|e| BenchError::Options(format!("full render: {e}")))?;
    if let Some(n) = r.photons {
        crate::limits::check_photon_count(n).map_err(|e| BenchError::Options(format!("--photons: {e}")))?;
    }
    Ok(())
}

/// Checks before allocating that the ray sets of `scene` fit the memory
/// budget: `rays` camera and incoherent rays, and up to one shadow ray per
/// light per camera ray.
fn check_ray_memory(path: &Path, scene: &Scene, rays: usize) -> Result<(), BenchError> {
    let per_ray = std::mem::size_of::<(crate::math::Ray, f32)>() as u64;
    let sets = 2 + scene.lights.len() as u64;
    let bytes = (rays as u64).saturating_mul(per_ray).saturating_mul(sets);
    let budget = memory::budget().map_err(BenchError::Options)?;
    match budget {
        Some(b) if bytes > b.bytes => Err(BenchError::SceneOptions {
            scene: path.to_path_buf(),
            message: format!(
                "--rays {rays}: the ray sets would need up to {} ({per_ray} bytes per ray, {sets} sets), {b}",
                memory::format_bytes(bytes)
            ),
        }),
        _ => Ok(()),
    }
}

/// `/proc/loadavg`'s three averages.
pub fn load_average() -> Option<[f64; 3]> {
    let text = std::fs::read_to_string("/proc/loadavg").ok()?;
    let mut it = text.split_whitespace().map(|s| s.parse::<f64>().ok());
    Some([it.next()??, it.next()??, it.next()??])
}

/// Benches every scene of `scenes` (loaded from disk) on the current rayon
/// pool. `progress` receives one line per step (loading, building, timing)
/// for the user to follow a long run.
pub fn run(scenes: &[PathBuf], options: &BenchOptions, progress: &dyn Fn(&str)) -> Result<BenchReport, BenchError> {
    check_options(options)?;
    let load_average_start = load_average();
    let mut results = Vec::with_capacity(scenes.len());
    for path in scenes {
        progress(&format!("{}: loading", path.display()));
        let scene = scene::load_scene(path)?;
        results.push(bench_scene(path, &scene, options, progress)?);
    }
    Ok(BenchReport {
        caustic_version: env!("CARGO_PKG_VERSION").into(),
        threads: rayon::current_num_threads(),
        seed: options.seed,
        rays_per_kind: options.rays,
        repeats: options.repeats,
        load_average_start,
        load_average_end: load_average(),
        scenes: results,
    })
}

/// The baseline of `accels`: Embree when listed, else the first.
fn baseline_index(accels: &[AccelKind]) -> usize {
    accels.iter().position(|&k| k == AccelKind::Embree).unwrap_or(0)
}

/// Benches one loaded scene (`path` names it in the report and in errors).
pub fn bench_scene(
    path: &Path,
    scene: &Scene,
    options: &BenchOptions,
    progress: &dyn Fn(&str),
) -> Result<SceneBench, BenchError> {
    check_options(options)?;
    check_ray_memory(path, scene, options.rays)?;
    let name = path.display().to_string();

    // The render's scene: the file's, at the bench's reduced settings.
    let mut render_scene = scene.clone();
    {
        let s = &mut render_scene.settings;
        s.width = options.render.width;
        s.height = options.render.height;
        s.spp = options.render.spp;
        s.seed = options.seed;
        s.photons.count = options
            .render
            .photons
            .unwrap_or_else(|| s.photons.count.min(DEFAULT_BENCH_PHOTONS));
    }
    let plan = RenderPlan::new(&render_scene);
    let render_settings = RenderSettingsInfo {
        width: plan.width,
        height: plan.height,
        spp: plan.spp,
        photons: render_scene.settings.photons.count,
        photon_pass: matches!(plan.photons, integrator::plan::PhotonPlan::Run { .. }),
    };

    let accel_options = AccelOptions {
        triangle_test: scene.settings.triangle_test,
        ..options.accel_options.clone()
    };
    // Baseline first: its camera hits seed the shadow rays.
    let mut order: Vec<AccelKind> = Vec::with_capacity(options.accels.len());
    let base = baseline_index(&options.accels);
    order.push(options.accels[base]);
    order.extend(
        options
            .accels
            .iter()
            .enumerate()
            .filter(|&(i, _)| i != base)
            .map(|(_, &k)| k),
    );

    let aspect = options.render.width as f32 / options.render.height as f32;
    let mut sets: Vec<RaySet> = Vec::new();
    let mut accelerators = Vec::with_capacity(order.len());
    for (i, &kind) in order.iter().enumerate() {
        progress(&format!("{name}: building {}", kind.name()));
        let peak_rss_reset = memory::reset_peak_rss();
        let rss_before_build_bytes = memory::current_rss_bytes();
        let accel = accel::build(scene, kind, &accel_options).map_err(|source| BenchError::Accel {
            scene: path.to_path_buf(),
            source,
        })?;
        let peak_rss_build_bytes = memory::peak_rss_bytes();
        let stats = accel.stats();
        if i == 0 {
            progress(&format!(
                "{name}: generating the ray sets ({} camera rays, their hits found with {})",
                options.rays,
                kind.name()
            ));
            sets = rays::standard_ray_sets(scene, accel.as_ref(), options.rays, aspect, options.seed);
        }
        let mut ray_results = Vec::with_capacity(sets.len());
        for set in &sets {
            progress(&format!(
                "{name}: {} {} rays through {}",
                set.rays.len(),
                set.kind,
                kind.name()
            ));
            ray_results.push(time_set(accel.as_ref(), set, options.repeats));
        }
        progress(&format!(
            "{name}: rendering {}×{}, {} spp with {}",
            plan.width,
            plan.height,
            plan.spp,
            kind.name()
        ));
        let render = time_render(&render_scene, accel.as_ref(), &plan);
        accelerators.push(AccelBench {
            name: kind.name().into(),
            build_seconds: stats.build_time.as_secs_f64(),
            memory_bytes: stats.memory_bytes as u64,
            rss_before_build_bytes,
            peak_rss_build_bytes,
            peak_rss_bytes: memory::peak_rss_bytes(),
            peak_rss_reset,
            rays: ray_results,
            render,
        });
        // Freed before the next build, so that its memory figures do not include this one.
        drop(accel);
    }

    let comparisons = accelerators[1..].iter().map(|a| compare(a, &accelerators[0])).collect();
    Ok(SceneBench {
        scene: name,
        objects: scene.objects.len(),
        triangles: scene.meshes.iter().map(|m| m.triangles.len() as u64).sum(),
        instanced_triangles: scene.instanced_triangles(),
        lights: scene.lights.len(),
        baseline: order[0].name().into(),
        ray_sets: sets
            .iter()
            .map(|s| RaySetInfo {
                kind: s.kind,
                query: s.query(),
                rays: s.rays.len(),
            })
            .collect(),
        render_settings,
        accelerators,
        comparisons,
    })
}

/// Best of `repeats` timed runs of `set`.
fn time_set(accel: &dyn Accel, set: &RaySet, repeats: u32) -> RayBench {
    let runs: Vec<rays::Throughput> = (0..repeats.max(1))
        .map(|_| rays::throughput(accel, &set.rays, set.query()))
        .collect();
    let best = *runs
        .iter()
        .min_by(|a, b| a.seconds.total_cmp(&b.seconds))
        .expect("at least one run");
    RayBench {
        kind: set.kind,
        query: set.query(),
        rays: best.rays,
        hits: best.hits,
        seconds: best.seconds,
        mrays_per_s: (best.rays > 0).then(|| best.mrays_per_s()),
        cpu_seconds: best.cpu_seconds,
        mrays_per_cpu_s: (best.rays > 0).then(|| best.mrays_per_cpu_s()).flatten(),
        runs_seconds: runs.iter().map(|r| r.seconds).collect(),
    }
}

/// One full render of `scene` as `plan` says.
fn time_render(scene: &Scene, accel: &dyn Accel, plan: &RenderPlan) -> RenderBench {
    let out = integrator::render::render(scene, accel, plan, &|_, _| {});
    let s = &out.stats;
    let (photon_seconds, photon_rays) = s.photons.as_ref().map_or((0.0, 0), |p| {
        ((p.trace_time + p.build_time + p.precompute_time).as_secs_f64(), p.rays)
    });
    let seconds = s.wall_time.as_secs_f64();
    let image_rays = s.rays.total();
    RenderBench {
        seconds,
        photon_seconds,
        image_rays,
        photon_rays,
        mrays_per_s: (image_rays + photon_rays) as f64 / seconds.max(1e-9) / 1e6,
        dropped_samples: s.dropped_samples,
    }
}

/// `a / b`, or `None` when either is missing or `b` is zero.
fn ratio(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) if b > 0.0 => Some(a / b),
        _ => None,
    }
}

fn compare(a: &AccelBench, base: &AccelBench) -> Comparison {
    Comparison {
        accel: a.name.clone(),
        baseline: base.name.clone(),
        build_time_ratio: a.build_seconds / base.build_seconds.max(1e-9),
        render_time_ratio: a.render.seconds / base.render.seconds.max(1e-9),
        rays: a
            .rays
            .iter()
            .zip(&base.rays)
            .map(|(x, y)| KindComparison {
                kind: x.kind,
                mrays_ratio: ratio(x.mrays_per_s, y.mrays_per_s),
                hits: x.hits,
                baseline_hits: y.hits,
                hits_difference: x.hits as i64 - y.hits as i64,
            })
            .collect(),
    }
}

/// `1234567` → `"1,234,567"`.
fn grouped(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}

fn mib(bytes: Option<u64>) -> String {
    bytes.map_or("-".into(), |b| format!("{:.1}", b as f64 / (1u64 << 20) as f64))
}

fn opt(x: Option<f64>, decimals: usize) -> String {
    x.map_or("-".into(), |v| format!("{v:.decimals$}"))
}

fn load(l: Option<[f64; 3]>) -> String {
    l.map_or("unknown".into(), |[a, b, c]| format!("{a:.2} {b:.2} {c:.2}"))
}

impl fmt::Display for BenchReport {
    /// The table printed by `caustic bench`: per scene, one row per
    /// accelerator (build, memory, Mrays/s per ray kind, full render), a
    /// ratio row per accelerator against the baseline, and the hit counts.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "caustic bench {}: {} rayon threads, seed {}, best of {} runs; load average {} at start, {} at end",
            self.caustic_version,
            self.threads,
            self.seed,
            self.repeats,
            load(self.load_average_start),
            load(self.load_average_end)
        )?;
        for s in &self.scenes {
            writeln!(f)?;
            writeln!(
                f,
                "{}: {} objects, {} triangles ({} instanced), {} light{}",
                s.scene,
                s.objects,
                grouped(s.triangles),
                grouped(s.instanced_triangles),
                s.lights,
                if s.lights == 1 { "" } else { "s" }
            )?;
            let sets: Vec<String> = s
                .ray_sets
                .iter()
                .map(|r| format!("{} {} ({})", r.kind, grouped(r.rays as u64), r.query.name()))
                .collect();
            writeln!(
                f,
                "rays, the same for every accelerator (shadow rays from {}'s camera hits): {}",
                s.baseline,
                sets.join(", ")
            )?;
            let r = &s.render_settings;
            writeln!(
                f,
                "full render: {}×{}, {} spp, {}",
                r.width,
                r.height,
                r.spp,
                if r.photon_pass {
                    format!("{} photons", grouped(r.photons))
                } else {
                    "no photon pass".into()
                }
            )?;
            writeln!(f)?;
            write!(
                f,
                "{:<16}{:>9}{:>11}{:>12}",
                "accelerator", "build s", "accel MiB", "build +MiB"
            )?;
            for r in &s.ray_sets {
                write!(f, "{:>13}", format!("{} Mr/s", short(r.kind)))?;
            }
            writeln!(f, "{:>10}{:>13}", "render s", "render Mr/s")?;
            for a in &s.accelerators {
                write!(
                    f,
                    "{:<16}{:>9.3}{:>11}{:>12}",
                    a.name,
                    a.build_seconds,
                    mib(Some(a.memory_bytes)),
                    mib(a.build_rss_increase_bytes())
                )?;
                for r in &a.rays {
                    write!(f, "{:>13}", opt(r.mrays_per_s, 2))?;
                }
                writeln!(f, "{:>10.3}{:>13.2}", a.render.seconds, a.render.mrays_per_s)?;
            }
            for c in &s.comparisons {
                let a = s
                    .accelerators
                    .iter()
                    .find(|a| a.name == c.accel)
                    .expect("compared accelerator");
                let b = &s.accelerators[0];
                let mem = ratio(Some(a.memory_bytes as f64), Some(b.memory_bytes as f64));
                write!(
                    f,
                    "{:<16}{:>9}{:>11}{:>12}",
                    format!("{}/{}", c.accel, c.baseline),
                    format!("{:.2}×", c.build_time_ratio),
                    mem.map_or("-".into(), |x| format!("{x:.2}×")),
                    ""
                )?;
                for k in &c.rays {
                    write!(f, "{:>13}", k.mrays_ratio.map_or("-".into(), |x| format!("{x:.2}×")))?;
                }
                let render_ratio = ratio(Some(a.render.mrays_per_s), Some(b.render.mrays_per_s));
                writeln!(
                    f,
                    "{:>10}{:>13}",
                    format!("{:.2}×", c.render_time_ratio),
                    render_ratio.map_or("-".into(), |x| format!("{x:.2}×"))
                )?;
            }
            writeln!(f)?;
            write!(f, "{:<16}", "hits")?;
            for r in &s.ray_sets {
                write!(f, "{:>22}", r.kind.name())?;
            }
            writeln!(f)?;
            for a in &s.accelerators {
                write!(f, "{:<16}", a.name)?;
                let cmp = s.comparisons.iter().find(|c| c.accel == a.name);
                for (i, r) in a.rays.iter().enumerate() {
                    let mark = match cmp.map(|c| c.rays[i].hits_difference) {
                        None => String::new(),
                        Some(0) => " (=)".into(),
                        Some(d) => format!(" ({d:+})"),
                    };
                    write!(f, "{:>22}", format!("{}{mark}", grouped(r.hits as u64)))?;
                }
                writeln!(f)?;
            }
        }
        Ok(())
    }
}

/// Column heading of a ray kind.
fn short(kind: RayKind) -> &'static str {
    match kind {
        RayKind::Camera => "camera",
        RayKind::Shadow => "shadow",
        RayKind::Incoherent => "incoh.",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Vec3, Vec3A};
    use crate::scene::{Camera, Light, Material, Object, Quad, RenderSettings, Shape, Sphere};

    fn ball_scene() -> Scene {
        Scene {
            settings: RenderSettings::default(),
            camera: Camera::new(Vec3A::new(0.0, 1.0, 5.0), Vec3A::new(0.0, 0.5, 0.0), Vec3A::Y, 40.0).unwrap(),
            materials: vec![Material::diffuse("white", Vec3A::ONE)],
            lights: vec![Light::Point {
                position: Vec3A::new(0.0, 3.0, 0.0),
                intensity: Vec3A::ONE,
            }],
            meshes: vec![],
            objects: vec![
                Object {
                    name: "floor".into(),
                    shape: Shape::Quad(
                        Quad::new(
                            Vec3A::new(-5.0, 0.0, -5.0),
                            Vec3A::from(Vec3::new(10.0, 0.0, 0.0)),
                            Vec3A::new(0.0, 0.0, 10.0),
                        )
                        .unwrap(),
                    ),
                    material: 0,
                },
                Object {
                    name: "ball".into(),
                    shape: Shape::Sphere(Sphere {
                        center: Vec3A::new(0.0, 1.0, 0.0),
                        radius: 0.5,
                    }),
                    material: 0,
                },
            ],
        }
    }

    fn small_options(accels: Vec<AccelKind>) -> BenchOptions {
        BenchOptions {
            accels,
            rays: 3000,
            repeats: 2,
            render: RenderOverrides {
                width: 32,
                height: 18,
                spp: 1,
                photons: Some(0),
            },
            ..BenchOptions::default()
        }
    }

    #[test]
    fn kdtree_against_brute_same_work_and_a_table() {
        let scene = ball_scene();
        // Brute listed first is the baseline (no Embree listed).
        let options = small_options(vec![AccelKind::Brute, AccelKind::KdTree]);
        let s = bench_scene(Path::new("ball.toml"), &scene, &options, &|_| {}).unwrap();
        assert_eq!(s.baseline, "brute");
        assert_eq!(s.accelerators.len(), 2);
        assert_eq!(s.ray_sets.len(), 3);
        assert_eq!(s.ray_sets[0].rays, 3000);
        assert_eq!(s.ray_sets[2].rays, 3000);
        // One shadow ray per camera hit (one light).
        assert_eq!(s.ray_sets[1].rays, s.accelerators[0].rays[0].hits);
        for a in &s.accelerators {
            assert!(a.build_seconds >= 0.0);
            for r in &a.rays {
                assert!(r.hits > 0 && r.hits < r.rays, "{r:?}");
                assert!(r.mrays_per_s.unwrap() > 0.0 && r.mrays_per_s.unwrap().is_finite());
                assert_eq!(r.runs_seconds.len(), 2);
            }
            // One camera ray per pixel, one shadow ray per camera hit, no secondary rays (all diffuse).
            assert!(
                a.render.image_rays > 32 * 18 && a.render.image_rays < 32 * 18 * 2,
                "{:?}",
                a.render
            );
            assert_eq!(a.render.photon_rays, 0);
        }
        let c = &s.comparisons[0];
        assert_eq!((c.accel.as_str(), c.baseline.as_str()), ("kdtree", "brute"));
        assert!(c.rays.iter().all(|k| k.hits_difference == 0), "{c:?}");

        let report = BenchReport {
            caustic_version: "test".into(),
            threads: 1,
            seed: 0,
            rays_per_kind: 3000,
            repeats: 2,
            load_average_start: None,
            load_average_end: Some([0.5, 1.0, 1.5]),
            scenes: vec![s],
        };
        let table = report.to_string();
        assert!(table.contains("kdtree/brute"), "{table}");
        assert!(table.contains("(=)"), "{table}");
        let json: serde_json::Value = serde_json::from_str(&report.to_json()).unwrap();
        assert_eq!(json["scenes"][0]["accelerators"][1]["name"], "kdtree");
        assert_eq!(json["scenes"][0]["ray_sets"][1]["query"], "occluded");
        assert_eq!(json["load_average_end"][2], 1.5);
    }

    #[test]
    fn embree_is_the_baseline_when_listed() {
        assert_eq!(baseline_index(&[AccelKind::KdTree, AccelKind::Embree]), 1);
        assert_eq!(baseline_index(&[AccelKind::KdTree, AccelKind::Brute]), 0);
    }

    #[test]
    fn bad_options_are_errors() {
        let scene = ball_scene();
        let mut o = small_options(vec![AccelKind::KdTree]);
        o.rays = 0;
        let e = bench_scene(Path::new("x.toml"), &scene, &o, &|_| {}).unwrap_err();
        assert!(e.to_string().contains("--rays"), "{e}");
        let mut o = small_options(vec![]);
        o.rays = 10;
        assert!(bench_scene(Path::new("x.toml"), &scene, &o, &|_| {}).is_err());
        let mut o = small_options(vec![AccelKind::KdTree]);
        o.render.width = 0;
        assert!(bench_scene(Path::new("x.toml"), &scene, &o, &|_| {})
            .unwrap_err()
            .to_string()
            .contains("full render"));
        let mut o = small_options(vec![AccelKind::KdTree]);
        o.rays = usize::MAX / 64;
        let e = bench_scene(Path::new("x.toml"), &scene, &o, &|_| {}).unwrap_err();
        assert!(e.to_string().contains("would need"), "{e}");
        assert!(e.is_bad_input());
    }

    #[test]
    fn digits_are_grouped() {
        assert_eq!(grouped(0), "0");
        assert_eq!(grouped(999), "999");
        assert_eq!(grouped(1000), "1,000");
        assert_eq!(grouped(871_414), "871,414");
        assert_eq!(grouped(1_234_567), "1,234,567");
    }
}
