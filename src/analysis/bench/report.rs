//! The bench report: the figures per scene and accelerator, each
//! accelerator against the baseline, the table `caustic bench` prints and the
//! JSON it writes.

use super::BenchError;
use crate::analysis::rays::{Query, RayKind};
use serde::Serialize;
use std::fmt;
use std::io::Write;
use std::path::{Path, PathBuf};

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

/// `a / b`, or `None` when either is missing or `b` is zero.
fn ratio(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) if b > 0.0 => Some(a / b),
        _ => None,
    }
}

pub(super) fn compare(a: &AccelBench, base: &AccelBench) -> Comparison {
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
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
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

    #[test]
    fn digits_are_grouped() {
        assert_eq!(grouped(0), "0");
        assert_eq!(grouped(999), "999");
        assert_eq!(grouped(1000), "1,000");
        assert_eq!(grouped(871_414), "871,414");
        assert_eq!(grouped(1_234_567), "1,234,567");
    }
}
