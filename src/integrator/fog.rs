//! Exponential fog along ray segments inside a [`Medium`] (the original
//! report's underwater "brouillard", §5.3).
//!
//! A segment of length `d` inside the medium's box transmits
//! `T = exp(−σ d)` (Beer–Lambert, σ = `density`) and adds `(1 − T)` of the
//! fog colour, the closed form of a homogeneous medium whose in-scattered
//! radiance is the constant `colour`: `L = T·L_surface + (1 − T)·colour`.
//! Camera and reflected/refracted rays get both terms; photons only the
//! attenuation `T` (the in-scattered part is the fog colour itself, already
//! added by the camera rays). Shadow rays are not attenuated: under the
//! water they are blocked by the (opaque-to-shadow-rays) water surface, so
//! all light there arrives through the photon map, which is attenuated.

use crate::math::{Ray, Vec3A};
use crate::scene::Medium;

/// Length of the part of `ray` (unit direction) with `0 < t < t_end` that
/// lies inside the medium's box. `t_end` may be infinite (a ray that
/// escapes); the box is bounded, so the length stays finite.
#[inline]
pub fn length_inside(medium: &Medium, ray: &Ray, t_end: f32) -> f32 {
    match medium.region.intersect_interval(ray, ray.dir.recip(), t_end) {
        Some((t0, t1)) => (t1.min(t_end) - t0).max(0.0),
        None => 0.0,
    }
}

/// Transmittance `exp(−σ d)` of the segment `(0, t_end)` of `ray`.
#[inline]
pub fn transmittance(medium: &Medium, ray: &Ray, t_end: f32) -> f32 {
    let d = length_inside(medium, ray, t_end);
    if d > 0.0 {
        (-medium.density * d).exp()
    } else {
        1.0
    }
}

/// Radiance `l` arriving at the ray origin from distance `t_end`, seen
/// through the fog: `T·l + (1 − T)·colour`.
#[inline]
pub fn apply(medium: &Medium, ray: &Ray, t_end: f32, l: Vec3A) -> Vec3A {
    let t = transmittance(medium, ray, t_end);
    if t < 1.0 {
        l * t + medium.colour * (1.0 - t)
    } else {
        l
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Aabb;

    fn medium() -> Medium {
        Medium {
            density: 0.5,
            colour: Vec3A::new(0.0, 0.2, 0.4),
            region: Aabb::new(Vec3A::new(-1.0, -1.0, -1.0), Vec3A::new(1.0, 0.0, 1.0)),
            volume: None,
            surface: crate::geometry::WaterSurface {
                center: Vec3A::ZERO,
                size: crate::math::Vec2::new(2.0, 2.0),
                resolution: (1, 1),
                waves: vec![],
            },
            boundary: 0,
        }
    }

    #[test]
    fn length_is_the_clipped_chord() {
        let m = medium();
        // Horizontal ray through the water: chord of length 2.
        let r = Ray::new(Vec3A::new(-5.0, -0.5, 0.0), Vec3A::X);
        assert!((length_inside(&m, &r, f32::INFINITY) - 2.0).abs() < 1e-5);
        // Stopping at x = 0.5, three quarters through.
        assert!((length_inside(&m, &r, 5.5) - 1.5).abs() < 1e-5);
        // Above the water level: nothing.
        let above = Ray::new(Vec3A::new(-5.0, 0.5, 0.0), Vec3A::X);
        assert_eq!(length_inside(&m, &above, f32::INFINITY), 0.0);
        // Starting inside, going down: 0.5 to the bottom.
        let down = Ray::new(Vec3A::new(0.0, -0.5, 0.0), -Vec3A::Y);
        assert!((length_inside(&m, &down, f32::INFINITY) - 0.5).abs() < 1e-5);
    }

    #[test]
    fn fog_blends_toward_its_colour_by_beer_lambert() {
        let m = medium();
        let r = Ray::new(Vec3A::new(-5.0, -0.5, 0.0), Vec3A::X);
        let t = (-0.5f32 * 2.0).exp();
        assert!((transmittance(&m, &r, f32::INFINITY) - t).abs() < 1e-5);
        let l = apply(&m, &r, f32::INFINITY, Vec3A::ONE);
        assert!((l - (Vec3A::ONE * t + m.colour * (1.0 - t))).length() < 1e-5);
        // A ray that never enters keeps its radiance exactly.
        let above = Ray::new(Vec3A::new(-5.0, 0.5, 0.0), Vec3A::X);
        assert_eq!(apply(&m, &above, f32::INFINITY, Vec3A::ONE), Vec3A::ONE);
    }
}
