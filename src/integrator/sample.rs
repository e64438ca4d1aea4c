//! The interface every integrator renders through: the radiance of one
//! pixel sample (pbrt-v4's `RayIntegrator::Li`), with the sample's random
//! numbers, strata and counters in a [`SampleContext`]. The render loop
//! (`render`) owns pixels, passes and accumulation; an integrator only
//! answers "how much light arrives along this camera ray".

use super::aov::FirstHit;
use super::photon::SiteCache;
use crate::math::{Ray, Sampler, Vec3A};
use std::ops::AddAssign;

/// A light transport algorithm, as the render loop sees it.
pub trait Integrator: Sync {
    /// Radiance arriving along the camera ray `ray` toward its origin.
    /// `first_hit` is the ray's nearest hit (and perhaps its surface
    /// interaction) when the caller already found it, so the integrator
    /// need not intersect the ray again; integrators that shade the camera
    /// ray otherwise may ignore it.
    fn radiance(&self, ray: &Ray, first_hit: Option<&FirstHit>, ctx: &mut SampleContext) -> Vec3A;
}

/// Rays cast, by kind. Counted per tile and summed at the end (no atomics
/// per ray).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounts {
    /// Primary rays from the camera.
    pub camera: u64,
    /// Shadow (occlusion) rays.
    pub shadow: u64,
    /// Reflected and refracted rays.
    pub secondary: u64,
}

impl RayCounts {
    /// All rays.
    pub fn total(&self) -> u64 {
        self.camera + self.shadow + self.secondary
    }
}

impl AddAssign for RayCounts {
    fn add_assign(&mut self, o: RayCounts) {
        self.camera += o.camera;
        self.shadow += o.shadow;
        self.secondary += o.secondary;
    }
}

/// One pixel sample's state: its random numbers, the strata the render
/// loop assigned it, and the tile's counters and caches.
pub struct SampleContext<'c> {
    /// The sample's own numbers (the pixel's sampler, keyed to the sample).
    pub rng: &'c mut Sampler,
    /// With spread sampling, which share `slot ∈ [0, spp)` of the area
    /// lights' strata this sample takes. Ignored when splitting.
    pub slot: u32,
    /// Key of the order in which the area lights' strata are visited
    /// ([`stratum_order`](crate::math::sampling::stratum_order)), per pixel; each light mixes in its index.
    pub light_seed: u32,
    /// With spread sampling, the stratum in `[0, spp)` of the sample's first
    /// Fresnel choice (reflect or refract at a dielectric); taken by that
    /// choice, later ones draw from `rng`. `None`: every choice draws.
    pub fresnel_stratum: Option<u32>,
    /// Ray counters of the current tile.
    pub counts: &'c mut RayCounts,
    /// Recent caustic site searches of the current tile: speeds up the
    /// caustic lookups of nearby samples without changing their results.
    pub sites: &'c mut SiteCache,
}
