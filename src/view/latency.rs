//! The viewer's interaction latency, measured without a window
//! (`caustic view SCENE --latency-bench N`): the time to open the scene and
//! to its first image; after a warm-up render, N camera
//! moves and N diffuse-material edits, each timed from the change to its
//! first image (the preview pass) and to its first full-resolution pass;
//! plus the time of each of the first full-resolution passes (frames per
//! second while refining).

use super::{EditableScene, ViewerCore};
use crate::accel::AccelKind;
use crate::scene::SceneError;
use serde::Serialize;
use std::path::Path;
use std::time::{Duration, Instant};

/// Median and extremes of a set of durations, in milliseconds.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Millis {
    /// Median.
    pub median: f64,
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
}

impl Millis {
    fn of(mut xs: Vec<Duration>) -> Self {
        if xs.is_empty() {
            return Self::default();
        }
        xs.sort();
        let ms = |d: Duration| d.as_secs_f64() * 1e3;
        Self {
            median: ms(xs[xs.len() / 2]),
            min: ms(xs[0]),
            max: ms(xs[xs.len() - 1]),
        }
    }
}

/// One full-resolution pass of the warm-up render.
#[derive(Clone, Debug, Serialize)]
pub struct PassTime {
    /// Samples per pixel after the pass.
    pub spp: u32,
    /// Time of the pass, milliseconds.
    pub ms: f64,
    /// Its rate, Mrays/s.
    pub mrays_per_second: f64,
}

/// What `--latency-bench` measured.
#[derive(Clone, Debug, Serialize)]
pub struct LatencyReport {
    /// Scene file.
    pub scene: String,
    /// Accelerator.
    pub accel: String,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Changes of each kind measured.
    pub repeats: usize,
    /// Time to read the scene file (and its meshes and textures) into the
    /// editable scene, before the first render request.
    pub load_ms: f64,
    /// Time from the first request to the first image of any kind (the
    /// preview pass; accelerator build included).
    pub first_image_ms: f64,
    /// Time from the first request to the first full-resolution image
    /// (accelerator build and photon pass included).
    pub startup_ms: f64,
    /// Camera move → first image (the preview pass).
    pub camera_first_image: Millis,
    /// Camera move → first full-resolution pass (1 spp, full shading).
    pub camera_first_full: Millis,
    /// Diffuse material edit → first image.
    pub material_first_image: Millis,
    /// Diffuse material edit → first full-resolution pass.
    pub material_first_full: Millis,
    /// Rebuilds of the photon map caused by those edits (0: skipped).
    pub photon_reruns: u32,
    /// The first full-resolution passes of the warm-up render.
    pub passes: Vec<PassTime>,
}

/// Measures the viewer's latency on `path` at `size` with `accel`.
pub fn measure(path: &Path, size: (u32, u32), accel: AccelKind, repeats: usize) -> Result<LatencyReport, SceneError> {
    let opening = Instant::now();
    let edit = EditableScene::open(path)?;
    let load_ms = opening.elapsed().as_secs_f64() * 1e3;
    let mut core = ViewerCore::new(edit, size, accel, || {});
    let timeout = Duration::from_secs(600);
    let t0 = Instant::now();
    core.sync();
    let mut passes = Vec::new();
    // The warm-up: record the first full passes (1, 2, 4, 8, 16 spp).
    let mut seen_pass = 0;
    let mut startup_ms = None;
    let mut first_image_ms = None;
    while passes.len() < 5 && t0.elapsed() < timeout {
        core.wait(timeout);
        if let Some(f) = &core.frame {
            first_image_ms.get_or_insert(t0.elapsed().as_secs_f64() * 1e3);
            if !f.preview && f.pass != seen_pass {
                seen_pass = f.pass;
                startup_ms.get_or_insert(t0.elapsed().as_secs_f64() * 1e3);
                passes.push(PassTime {
                    spp: f.spp,
                    ms: f.pass_time.as_secs_f64() * 1e3,
                    mrays_per_second: f.mrays_per_second,
                });
                if f.complete {
                    break;
                }
            }
        }
    }
    let photons_before = core.photon_version();
    let run = |core: &mut ViewerCore, change: &dyn Fn(&mut EditableScene, usize), i: usize| {
        change(&mut core.edit, i);
        let submitted = Instant::now();
        core.sync();
        let generation = core.generation();
        let mut first = None;
        loop {
            core.wait(timeout);
            let Some(f) = &core.frame else { continue };
            if f.generation != generation {
                continue;
            }
            first.get_or_insert(submitted.elapsed());
            if !f.preview {
                return (first.unwrap_or_default(), submitted.elapsed());
            }
        }
    };
    let (mut cam_first, mut cam_full, mut mat_first, mut mat_full) = (vec![], vec![], vec![], vec![]);
    let diffuse = core.edit.scene.materials.iter().position(|m| {
        let f = crate::bsdf::whitted_flags(m);
        f.contains(crate::bsdf::LobeFlags::DIFFUSE) && !f.contains(crate::bsdf::LobeFlags::CASTS_CAUSTICS)
    });
    for i in 0..repeats {
        let (a, b) = run(
            &mut core,
            &|e, i| e.orbit.rotate(if i % 2 == 0 { 8.0 } else { -8.0 }, 2.0, 540.0),
            i,
        );
        cam_first.push(a);
        cam_full.push(b);
        if let Some(m) = diffuse {
            let (a, b) = run(
                &mut core,
                &|e, i| {
                    let d = &mut e.scene.materials[m].diffuse;
                    *d = (*d * if i % 2 == 0 { 0.95 } else { 1.0 / 0.95 }).min(crate::math::Vec3A::ONE);
                },
                i,
            );
            mat_first.push(a);
            mat_full.push(b);
        }
    }
    Ok(LatencyReport {
        scene: path.display().to_string(),
        accel: accel.name().into(),
        width: size.0,
        height: size.1,
        repeats,
        load_ms,
        first_image_ms: first_image_ms.unwrap_or(f64::NAN),
        startup_ms: startup_ms.unwrap_or(f64::NAN),
        camera_first_image: Millis::of(cam_first),
        camera_first_full: Millis::of(cam_full),
        material_first_image: Millis::of(mat_first),
        material_first_full: Millis::of(mat_full),
        photon_reruns: (core.photon_version() - photons_before) as u32,
        passes,
    })
}
