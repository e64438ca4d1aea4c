//! Small math vocabulary shared by every module: rays, boxes, transforms,
//! orthonormal frames, sampling, seeded random streams, the per-sample
//! sampler (independent or Sobol) and robust ray offsets.

mod aabb;
pub mod distribution;
mod frame;
mod offset;
mod ray;
pub mod rng;
pub mod sampler;
pub mod sampling;
mod transform;

pub use aabb::Aabb;
pub use frame::Frame;
pub use glam::{Affine2, Affine3A, Mat2, Mat3A, Vec2, Vec3, Vec3A, Vec4};
pub use offset::offset_ray_origin;
pub use ray::Ray;
pub use rng::Rng;
pub use sampler::{Sampler, SamplerKind};
pub use transform::Transform;

/// `gamma(n) = n·ε / (1 − n·ε)`, the rounding-error bound of pbrt-v3 §3.9.1
/// (ε = f32 machine epsilon / 2), used to widen boxes and bound errors.
#[inline]
pub const fn gamma(n: i32) -> f32 {
    let e = f32::EPSILON * 0.5;
    (n as f32 * e) / (1.0 - n as f32 * e)
}

/// True when every component is finite (no NaN, no ±inf).
#[inline]
pub fn is_finite3(v: Vec3A) -> bool {
    v.is_finite()
}
