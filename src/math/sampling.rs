//! Warps from the unit square (pbrt-v4 ch. A.5).

use super::{Vec2, Vec3A};
use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// Concentric map of the square onto the unit disk (Shirley & Chiu 1997).
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, FRAC_PI_4 * (o.y / o.x))
    } else {
        (o.y, FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y))
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

/// Cosine-weighted direction about +z (Malley's method); pdf = cos θ / π.
pub fn cosine_hemisphere(u: Vec2) -> Vec3A {
    let d = concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3A::new(d.x, d.y, z)
}

/// Uniform direction on the unit sphere; pdf = 1 / (4π).
pub fn uniform_sphere(u: Vec2) -> Vec3A {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3A::new(r * phi.cos(), r * phi.sin(), z)
}

/// Uniform direction in the cone of half-angle `acos(cos_max)` about +z;
/// pdf = 1 / (2π (1 − cos_max)).
pub fn uniform_cone(u: Vec2, cos_max: f32) -> Vec3A {
    let cos_t = (1.0 - u.x) + u.x * cos_max;
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3A::new(phi.cos() * sin_t, phi.sin() * sin_t, cos_t)
}

/// Jittered point of stratum `index` in an `nx × ny` grid over the unit square.
pub fn stratified(index: u32, nx: u32, ny: u32, jitter: Vec2) -> Vec2 {
    let (ix, iy) = (index % nx, (index / nx) % ny);
    Vec2::new((ix as f32 + jitter.x) / nx as f32, (iy as f32 + jitter.y) / ny as f32)
}

/// A near-square grid `nx × ny` with `nx·ny = n` exactly when n has such a
/// factorisation, else the closest from below (nx = ⌊√n⌋, ny = ⌈n/nx⌉).
pub fn grid_for(n: u32) -> (u32, u32) {
    let n = n.max(1);
    let mut nx = (n as f32).sqrt() as u32;
    while nx > 1 && n % nx != 0 {
        nx -= 1;
    }
    (nx.max(1), n / nx.max(1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::{Domain, Rng};

    #[test]
    fn cosine_hemisphere_mean_cos_is_two_thirds() {
        let mut r = Rng::new(3, Domain::Analysis, 0, 0);
        let n = 200_000;
        let mean: f64 = (0..n)
            .map(|_| {
                let (a, b) = r.f32x2();
                cosine_hemisphere(Vec2::new(a, b)).z as f64
            })
            .sum::<f64>()
            / n as f64;
        // E[cos θ] under pdf cos θ/π is 2/3.
        assert!((mean - 2.0 / 3.0).abs() < 0.005, "{mean}");
    }

    #[test]
    fn warps_give_unit_vectors() {
        for (a, b) in [(0.1, 0.9), (0.5, 0.5), (0.0, 0.0), (0.99, 0.01)] {
            let u = Vec2::new(a, b);
            assert!((uniform_sphere(u).length() - 1.0).abs() < 1e-5);
            assert!((cosine_hemisphere(u).length() - 1.0).abs() < 1e-5);
            assert!((uniform_cone(u, 0.5).length() - 1.0).abs() < 1e-5);
            assert!(uniform_cone(u, 0.5).z >= 0.5 - 1e-6);
        }
    }

    #[test]
    fn grids_cover_n() {
        assert_eq!(grid_for(32), (4, 8));
        assert_eq!(grid_for(16), (4, 4));
        assert_eq!(grid_for(7), (1, 7));
        assert_eq!(grid_for(1), (1, 1));
    }
}
