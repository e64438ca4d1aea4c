//! Ray-query accelerators behind one contract.
//!
//! Both real backends (Embree and the in-house KD-tree) are two-level: one
//! bottom-level structure per distinct mesh, in object space, and a top level
//! over the objects (mesh instances with their transforms, spheres, quads,
//! disks, cylinders). Embree puts a mesh that only one object uses straight
//! in its top level, in world space (one BVH fewer to traverse).
//! `brute` tests everything and is the oracle of the tests.

pub mod brute;
#[cfg(feature = "embree")]
pub mod embree;
pub mod kdtree;
pub mod triangle;

pub use crate::geometry::{Hit, TriangleTest};
use crate::math::Ray;
use crate::scene::Scene;
use std::time::Duration;
use thiserror::Error;

/// A ray-query accelerator.
pub trait Accel: Send + Sync {
    /// Closest hit with `0 < t < t_max`.
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit>;
    /// True when anything is hit with `0 < t < t_max` (any-hit; shadow rays).
    fn occluded(&self, ray: &Ray, t_max: f32) -> bool;
    /// Closest hits of many rays: `hits[i]` for `rays[i]`, with
    /// `0 < t < t_max` (same length). The default asks
    /// [`intersect`](Self::intersect) for each; Embree traces packets. A
    /// backend may return a `t`, `u` or `v` a few ulps from its one-ray answer.
    fn intersect_many(&self, rays: &[Ray], t_max: f32, hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len());
        for (ray, hit) in rays.iter().zip(hits.iter_mut()) {
            *hit = self.intersect(ray, t_max);
        }
    }
    /// Build statistics.
    fn stats(&self) -> AccelStats;
}

/// Which accelerator to build.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum AccelKind {
    /// Intel Embree 4 (instanced BLAS/TLAS).
    Embree,
    /// The in-house two-level SAH KD-tree.
    KdTree,
    /// Test every primitive (the test oracle).
    Brute,
}

impl AccelKind {
    /// Name as used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            AccelKind::Embree => "embree",
            AccelKind::KdTree => "kdtree",
            AccelKind::Brute => "brute",
        }
    }

    /// The kind named `name` (as on the command line), if any.
    pub fn from_name(name: &str) -> Option<Self> {
        [AccelKind::Embree, AccelKind::KdTree, AccelKind::Brute]
            .into_iter()
            .find(|k| k.name() == name)
    }

    /// The default: Embree when compiled in, else the KD-tree.
    pub fn default_kind() -> Self {
        if cfg!(feature = "embree") {
            AccelKind::Embree
        } else {
            AccelKind::KdTree
        }
    }
}

/// Statistics reported by `caustic info` and the benchmarks.
#[derive(Clone, Debug, Default)]
pub struct AccelStats {
    /// Backend name.
    pub name: String,
    /// Wall time of the build.
    pub build_time: Duration,
    /// Bytes held by the acceleration structures (not counting the scene's meshes).
    pub memory_bytes: usize,
    /// Bottom-level structures built (one per distinct mesh; Embree's only
    /// for meshes that several objects use, the others are in its top level).
    pub blas_count: usize,
    /// Top-level entries (objects).
    pub instances: usize,
    /// Free-form details (node counts, depth, version...).
    pub details: Vec<(String, String)>,
}

/// Accelerator construction failure.
#[derive(Debug, Error)]
pub enum AccelError {
    /// The requested backend is not compiled in.
    #[error("accelerator '{0}' is not available in this build (compiled without the `embree` feature)")]
    Unavailable(&'static str),
    /// Embree reported an error.
    #[error("Embree: {0}")]
    Embree(String),
    /// The scene cannot be indexed by the backend.
    #[error("{0}")]
    Scene(String),
}

/// Build options shared by the backends.
#[derive(Clone, Debug)]
pub struct AccelOptions {
    /// Triangle test (in-house backends).
    pub triangle_test: TriangleTest,
    /// Embree build quality: "low", "medium" or "high".
    pub embree_quality: String,
    /// Embree robust mode (`RTC_SCENE_FLAG_ROBUST`).
    pub embree_robust: bool,
}

impl Default for AccelOptions {
    fn default() -> Self {
        Self {
            triangle_test: TriangleTest::Watertight,
            embree_quality: "high".into(),
            embree_robust: false,
        }
    }
}

impl AccelOptions {
    /// The options that change `kind`'s answers, as text for a render's
    /// fingerprint (the triangle test is part of the scene's settings).
    pub fn fingerprint_text(&self, kind: AccelKind) -> String {
        match kind {
            AccelKind::Embree => format!("quality {:?} robust {}", self.embree_quality, self.embree_robust),
            _ => String::new(),
        }
    }
}

/// Builds the accelerator `kind` over `scene`.
pub fn build(scene: &Scene, kind: AccelKind, options: &AccelOptions) -> Result<Box<dyn Accel>, AccelError> {
    match kind {
        AccelKind::Brute => Ok(Box::new(brute::BruteForce::new(scene, options.triangle_test))),
        AccelKind::KdTree => Ok(Box::new(kdtree::KdTreeAccel::build(scene, options))),
        #[cfg(feature = "embree")]
        AccelKind::Embree => Ok(Box::new(embree::EmbreeAccel::build(scene, options)?)),
        #[cfg(not(feature = "embree"))]
        AccelKind::Embree => Err(AccelError::Unavailable("embree")),
    }
}
