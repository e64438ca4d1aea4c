//! The participating medium inside the water (`[medium]`): the Whitted
//! integrator's exponential fog, and the path integrator's homogeneous
//! absorbing and scattering medium.

use crate::geometry::WaterSurface;
use crate::math::{Aabb, Vec3A};

/// The medium that fills the water.
///
/// Whitted: exponential fog (the original report's "brouillard", §5.3):
/// along a path of length `d` inside `region`, radiance becomes
/// `T·L + (1 − T)·colour` with transmittance `T = exp(−density · d)`. The
/// region is a box (the water's (x, z) extent, from the bottom of the scene
/// up to the *mean* water level), not the volume under the wavy surface
/// itself; crests and troughs shift the true boundary by at most the waves'
/// amplitude.
///
/// Path tracing: a homogeneous medium with absorption and scattering
/// coefficients and a Henyey–Greenstein phase function, filling the volume
/// under the water surface (a path enters it by refracting through the
/// water object and leaves it the same way).
#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    /// Extinction per unit length (≥ 0) of the fog.
    pub density: f32,
    /// Colour the fog tends to (in-scattered radiance).
    pub colour: Vec3A,
    /// The box the fog fills.
    pub region: Aabb,
    /// The physically based medium, when the scene gives its coefficients.
    pub volume: Option<VolumeCoefficients>,
    /// The water surface the medium lies under.
    pub surface: WaterSurface,
    /// Index of the water object (its surface is the medium's boundary).
    pub boundary: u32,
}

/// Coefficients of a homogeneous participating medium, per unit length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeCoefficients {
    /// Absorption coefficient σa per channel.
    pub absorption: Vec3A,
    /// Scattering coefficient σs per channel.
    pub scattering: Vec3A,
    /// Henyey–Greenstein asymmetry `g` in (−1, 1) (0: isotropic, > 0:
    /// forward scattering, as in water).
    pub g: f32,
}

impl Medium {
    /// True when `p` lies in the water: inside the surface's (x, z) extent
    /// and below its height there (above the box's floor).
    pub fn contains(&self, p: Vec3A) -> bool {
        let s = &self.surface;
        let (dx, dz) = (p.x - s.center.x, p.z - s.center.z);
        dx.abs() <= 0.5 * s.size.x
            && dz.abs() <= 0.5 * s.size.y
            && p.y >= self.region.min.y
            && p.y <= s.center.y + s.height(p.x, p.z)
    }
}
