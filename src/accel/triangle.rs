//! Ray–triangle tests: watertight (default) and Möller–Trumbore.

use crate::math::{Ray, Vec3A};
use glam::Vec4;

/// Per-ray constants of the watertight test (Woop, Benthin, Wald 2013,
/// "Watertight Ray/Triangle Intersection", JCGT 2(1)): the ray is sheared so
/// that it points along +z, and edge functions are evaluated in 2D. Edges
/// shared by two triangles give the same edge function with opposite sign, so
/// no ray passes between them. Computed once per ray.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    origin: Vec3A,
    dir: Vec3A,
    k: [usize; 3],
    shear: Vec3A,
}

impl WatertightRay {
    /// Precomputes the permutation and shear of `ray`.
    #[inline]
    pub fn new(ray: &Ray) -> Self {
        let d = ray.dir;
        let a = d.abs();
        let kz = if a.x > a.y && a.x > a.z {
            0
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        // Keep the winding: swap when the dominant component is negative.
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let shear = Vec3A::new(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]);
        Self {
            origin: ray.origin,
            dir: ray.dir,
            k: [kx, ky, kz],
            shear,
        }
    }

    /// `(t, u, v)` with `0 < t < t_max`, `u`, `v` the weights of `p1`, `p2`.
    #[inline]
    pub fn intersect(&self, p0: Vec3A, p1: Vec3A, p2: Vec3A, t_max: f32) -> Option<(f32, f32, f32)> {
        // The permuted coordinates are read from 4-lane arrays with the axis
        // masked to 0..=3: no bounds checks, no per-lane `match` (glam's
        // `Vec3A` index), the same values.
        let [kx, ky, kz] = self.k.map(|k| k & 3);
        let lanes = |v: Vec3A| Vec4::from((v - self.origin, 0.0)).to_array();
        let (a, b, c) = (lanes(p0), lanes(p1), lanes(p2));
        let (sx, sy, sz) = (self.shear.x, self.shear.y, self.shear.z);
        let ax = a[kx] - sx * a[kz];
        let ay = a[ky] - sy * a[kz];
        let bx = b[kx] - sx * b[kz];
        let by = b[ky] - sy * b[kz];
        let cx = c[kx] - sx * c[kz];
        let cy = c[ky] - sy * c[kz];
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        // Exactly zero edge functions: redo in f64 (the paper's fallback).
        if u == 0.0 || v == 0.0 || w == 0.0 {
            u = (cx as f64 * by as f64 - cy as f64 * bx as f64) as f32;
            v = (ax as f64 * cy as f64 - ay as f64 * cx as f64) as f32;
            w = (bx as f64 * ay as f64 - by as f64 * ax as f64) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let az = sz * a[kz];
        let bz = sz * b[kz];
        let cz = sz * c[kz];
        let t_scaled = u * az + v * bz + w * cz;
        // Sign-aware range test on t·det, avoiding the division for misses.
        if det > 0.0 {
            if t_scaled <= 0.0 || t_scaled >= t_max * det {
                return None;
            }
        } else if t_scaled >= 0.0 || t_scaled <= t_max * det {
            return None;
        }
        let inv = 1.0 / det;
        let t = t_scaled * inv;
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        // t is only known to δt (pbrt-v3 §3.9.2, "Conservative Ray–Triangle
        // t Tests"): a ray leaving a surface (origin a few ulps above the
        // triangle's plane, as `offset_ray_origin` leaves it) can get a false
        // re-hit at t ≈ 1e-8 (seen on total-internal-reflection chains,
        // `caustic stress` case 7). pbrt rejects every t ≤ δt, but the bound
        // grows as 1/det and would drop real hits on distant slivers; below
        // δt the sign of t is decided instead by the plane distance in f64.
        let max_zt = az.abs().max(bz.abs()).max(cz.abs());
        let max_xt = ax.abs().max(bx.abs()).max(cx.abs());
        let max_yt = ay.abs().max(by.abs()).max(cy.abs());
        let delta_z = crate::math::gamma(3) * max_zt;
        let delta_x = crate::math::gamma(5) * (max_xt + max_zt);
        let delta_y = crate::math::gamma(5) * (max_yt + max_zt);
        let delta_e = 2.0 * (crate::math::gamma(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
        let max_e = u.abs().max(v.abs()).max(w.abs());
        let delta_t = 3.0 * (crate::math::gamma(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * inv.abs();
        if t <= delta_t {
            let t_plane = plane_t_f64(self.origin, self.dir, p0, p1, p2);
            if t_plane.is_nan() || t_plane <= 0.0 {
                return None;
            }
        }
        // A zero-area triangle (collinear or repeated corners) is never hit
        // (pbrt-v4's degenerate test): rounding in the shear can give it a
        // tiny non-zero determinant. Checked on hits only, so it costs nothing
        // on the misses that dominate traversal.
        if (p1 - p0).cross(p2 - p0) == Vec3A::ZERO {
            return None;
        }
        // u, v, w are the weights of p0, p1, p2.
        Some((t, v * inv, w * inv))
    }
}

/// Ray parameter of the plane through `p0, p1, p2` in f64: differences and
/// products of f32 values are exact or nearly so in f64, so its sign is right
/// where the f32 `t` of a ray starting next to the plane is not.
#[inline(never)]
fn plane_t_f64(o: Vec3A, d: Vec3A, p0: Vec3A, p1: Vec3A, p2: Vec3A) -> f64 {
    let (o, d, p0) = (o.as_dvec3(), d.as_dvec3(), p0.as_dvec3());
    let n = (p1.as_dvec3() - p0).cross(p2.as_dvec3() - p0);
    n.dot(p0 - o) / n.dot(d)
}

/// Möller–Trumbore 1997 (Cramer's rule on `[-D E1 E2][t u v]ᵀ = O − V0`).
#[inline]
pub fn moller_trumbore(ray: &Ray, p0: Vec3A, p1: Vec3A, p2: Vec3A, t_max: f32) -> Option<(f32, f32, f32)> {
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let pvec = ray.dir.cross(e2);
    let det = e1.dot(pvec);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let tvec = ray.origin - p0;
    let u = tvec.dot(pvec) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qvec = tvec.cross(e1);
    let v = ray.dir.dot(qvec) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(qvec) * inv;
    // Zero-area triangles are never hit (checked on hits only).
    if t > 0.0 && t < t_max && e1.cross(e2) != Vec3A::ZERO {
        Some((t, u, v))
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::{Domain, Rng};

    const P: [Vec3A; 3] = [
        Vec3A::new(0.0, 0.0, 0.0),
        Vec3A::new(1.0, 0.0, 0.0),
        Vec3A::new(0.0, 1.0, 0.0),
    ];

    #[test]
    fn both_tests_agree_on_a_simple_hit() {
        let r = Ray::new(Vec3A::new(0.25, 0.5, 1.0), -Vec3A::Z);
        let a = WatertightRay::new(&r)
            .intersect(P[0], P[1], P[2], f32::INFINITY)
            .unwrap();
        let b = moller_trumbore(&r, P[0], P[1], P[2], f32::INFINITY).unwrap();
        for (x, y) in [(a.0, b.0), (a.1, b.1), (a.2, b.2)] {
            assert!((x - y).abs() < 1e-6);
        }
        assert!((a.0 - 1.0).abs() < 1e-6 && (a.1 - 0.25).abs() < 1e-6 && (a.2 - 0.5).abs() < 1e-6);
        // Both faces hit (no culling), t range respected.
        let back = Ray::new(Vec3A::new(0.25, 0.25, -1.0), Vec3A::Z);
        assert!(WatertightRay::new(&back)
            .intersect(P[0], P[1], P[2], f32::INFINITY)
            .is_some());
        assert!(WatertightRay::new(&r).intersect(P[0], P[1], P[2], 0.5).is_none());
    }

    #[test]
    fn no_hit_just_behind_the_origin_nor_on_zero_area_triangles() {
        // A ray leaving the plane y = -0.1 one ulp above it (the TIR chain
        // found by `caustic stress`): no re-hit of the plane at t ≈ 1e-8;
        // but a ray starting 6e-6 below the plane y = 0.1 hits it.
        let q = [
            Vec3A::new(-2.0, -0.1, -2.0),
            Vec3A::new(2.0, -0.1, -2.0),
            Vec3A::new(2.0, -0.1, 2.0),
        ];
        let r = Ray::new(
            Vec3A::new(-0.6425538, -0.09999994, -0.5575255),
            Vec3A::new(-0.6059984, 0.55000025, -0.5746875),
        );
        assert_eq!(WatertightRay::new(&r).intersect(q[0], q[2], q[1], f32::INFINITY), None);
        let top = [
            Vec3A::new(-2.0, 0.1, -2.0),
            Vec3A::new(2.0, 0.1, 2.0),
            Vec3A::new(-2.0, 0.1, 2.0),
        ];
        let near = Ray::new(
            Vec3A::new(-1.9345872, 0.099994324, 1.9),
            Vec3A::new(0.59848577, 0.592923, -0.5387553),
        );
        let hit = WatertightRay::new(&near).intersect(top[0], top[1], top[2], f32::INFINITY);
        assert!(hit.is_some_and(|(t, _, _)| t > 0.0 && t < 2e-5), "{hit:?}");
        // Collinear corners: no hit by either test.
        let line = [Vec3A::ZERO, Vec3A::new(1.0, 1.0, 0.0), Vec3A::new(2.0, 2.0, 0.0)];
        let mut rng = Rng::new(5, Domain::Analysis, 0, 0);
        for _ in 0..2_000 {
            let s = rng.f32() * 2.0;
            let o = Vec3A::new(rng.f32() - 0.5, rng.f32() - 0.5, 1.0);
            let r = Ray::new(o, (Vec3A::new(s, s, 0.0) - o).normalize());
            assert_eq!(
                WatertightRay::new(&r).intersect(line[0], line[1], line[2], f32::INFINITY),
                None
            );
            assert_eq!(moller_trumbore(&r, line[0], line[1], line[2], f32::INFINITY), None);
        }
    }

    #[test]
    fn watertight_never_misses_a_shared_edge() {
        // Two triangles sharing the diagonal of the unit square; rays aimed at
        // the diagonal must hit at least one of them.
        let q = [
            Vec3A::new(0.0, 0.0, 0.0),
            Vec3A::new(1.0, 0.0, 0.0),
            Vec3A::new(1.0, 1.0, 0.0),
            Vec3A::new(0.0, 1.0, 0.0),
        ];
        let mut rng = Rng::new(11, Domain::Analysis, 0, 0);
        for _ in 0..20_000 {
            let s = rng.f32();
            let target = Vec3A::new(s, s, 0.0);
            let origin = Vec3A::new(rng.f32() * 4.0 - 2.0, rng.f32() * 4.0 - 2.0, 1.0 + rng.f32() * 3.0);
            let r = Ray::new(origin, (target - origin).normalize());
            let w = WatertightRay::new(&r);
            let hit = w.intersect(q[0], q[1], q[2], f32::INFINITY).is_some()
                || w.intersect(q[0], q[2], q[3], f32::INFINITY).is_some();
            assert!(hit, "ray through the shared edge missed: {r:?}");
        }
    }
}
