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
//!   rayon pool in chunks of [`rays::CHUNK`](super::rays::CHUNK), wall time; rays per CPU second
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
//!
//! This module holds the options and errors; `measure` takes the figures and
//! `report` holds them, with their comparisons, table and JSON.

mod measure;
mod report;

pub use measure::{bench_scene, load_average, run};
pub use report::{
    AccelBench, BenchReport, Comparison, KindComparison, RayBench, RaySetInfo, RenderBench, RenderSettingsInfo,
    SceneBench,
};

use crate::accel::{AccelError, AccelKind, AccelOptions};
use crate::scene::SceneError;
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
    /// `-D name=value` parameters of Mitsuba scenes.
    pub defines: Vec<(String, String)>,
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
            defines: Vec::new(),
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

/// The scenes benched when none is given: the dragon showcase
/// (`scenes/dragon.toml`) and the dragon mesh alone
/// (`scenes/dragon-mesh.toml`, where every ray that hits anything hits
/// triangles), from the current directory, else from the source tree this
/// binary was built from.
pub fn default_scenes() -> Vec<PathBuf> {
    ["scenes/dragon.toml", "scenes/dragon-mesh.toml"]
        .into_iter()
        .map(|name| {
            let relative = PathBuf::from(name);
            if relative.exists() {
                relative
            } else {
                Path::new(env!("CARGO_MANIFEST_DIR")).join(name)
            }
        })
        .collect()
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_scenes_are_the_dragon_showcase_and_the_mesh_alone() {
        let scenes = default_scenes();
        assert_eq!(scenes.len(), 2);
        assert!(scenes.iter().all(|p| p.exists()), "{scenes:?}");
        let mesh_only = crate::scene::load_scene(&scenes[1]).unwrap().scene;
        assert!(mesh_only
            .objects
            .iter()
            .all(|o| matches!(o.shape, crate::scene::Shape::Mesh { .. })));
    }
}
