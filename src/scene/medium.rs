//! The participating medium of the Whitted integrator's water (`[medium]`).

use crate::math::{Aabb, Vec3A};

/// A homogeneous participating medium approximated by exponential fog
/// (the original report's "brouillard", §5.3): along a path of length `d`
/// inside `region`, radiance becomes `T·L + (1 − T)·colour` with
/// transmittance `T = exp(−density · d)`.
///
/// Simplification: the region is a box (the water's (x, z) extent, from
/// the bottom of the scene up to the *mean* water level), not the volume
/// under the wavy surface itself; crests and troughs shift the true boundary
/// by at most the waves' amplitude.
#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    /// Extinction per unit length (≥ 0).
    pub density: f32,
    /// Colour the fog tends to (in-scattered radiance).
    pub colour: Vec3A,
    /// The box the medium fills.
    pub region: Aabb,
}
