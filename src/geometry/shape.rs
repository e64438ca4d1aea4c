//! Analytic shapes, stored in world space: spheres and quads.

use crate::math::{gamma, Aabb, Ray, Vec2, Vec3A};
use std::f32::consts::{PI, TAU};

/// A sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre.
    pub center: Vec3A,
    /// Radius (> 0).
    pub radius: f32,
}

impl Sphere {
    /// Nearest root of `|o + t d − c|² = r²` in `(0, t_max)`.
    ///
    /// Numerically stable: the discriminant is computed as `r² − |f − (f·d̂)d̂|²`
    /// (Hearn & Baker; Ray Tracing Gems ch. 7), which avoids the cancellation
    /// of `b² − 4ac` for distant or grazing rays, and the second root comes from
    /// `c / q` rather than a difference of nearly equal numbers.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        self.intersect_where(ray, t_max, |_| true)
    }

    /// The nearest root in `(0, t_max)` that `keep` accepts (an alpha
    /// cutout may reject the near root and keep the far one).
    #[inline]
    pub fn intersect_where(&self, ray: &Ray, t_max: f32, keep: impl Fn(f32) -> bool) -> Option<f32> {
        let f = ray.origin - self.center;
        let a = ray.dir.length_squared();
        let b_half = -f.dot(ray.dir);
        let perp = f + ray.dir * (b_half / a);
        let r2 = self.radius * self.radius;
        let disc = a * (r2 - perp.length_squared());
        if disc < 0.0 {
            return None;
        }
        let c = f.length_squared() - r2;
        let q = b_half + disc.sqrt().copysign(b_half);
        if q == 0.0 {
            return None;
        }
        let (mut t0, mut t1) = (c / q, q / a);
        if t0 > t1 {
            std::mem::swap(&mut t0, &mut t1);
        }
        if t0 > 0.0 && t0 < t_max && keep(t0) {
            Some(t0)
        } else if t1 > 0.0 && t1 < t_max && keep(t1) {
            Some(t1)
        } else {
            None
        }
    }

    /// Texture coordinates and their derivatives at surface point `p`, in
    /// Mitsuba's `sphere` convention about the world's axes: `u = φ / 2π`
    /// with `φ` the azimuth about +z from +x, `v = θ / π` with `θ` the angle
    /// from +z; `∂p/∂u = 2π (−y, x, 0)` and `∂p/∂v = π (z cos φ, z sin φ,
    /// −r sin θ)`, `(x, y, z) = p − centre`.
    pub fn uv(&self, p: Vec3A) -> (Vec2, Vec3A, Vec3A) {
        let l = p - self.center;
        let mut phi = l.y.atan2(l.x);
        if phi < 0.0 {
            phi += TAU;
        }
        let cos_theta = (l.z / self.radius).clamp(-1.0, 1.0);
        let theta = cos_theta.acos();
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let (sin_phi, cos_phi) = phi.sin_cos();
        let dpdu = Vec3A::new(-l.y, l.x, 0.0) * TAU;
        let dpdv = Vec3A::new(l.z * cos_phi, l.z * sin_phi, -self.radius * sin_theta) * PI;
        (Vec2::new(phi / TAU, theta / PI), dpdu, dpdv)
    }

    /// World bounds.
    pub fn bounds(&self) -> Aabb {
        Aabb::new(
            self.center - Vec3A::splat(self.radius),
            self.center + Vec3A::splat(self.radius),
        )
    }

    /// Hit point re-projected on the surface, its outward normal and its
    /// absolute error bound (pbrt-v4 §6.8.5: γ(5)|p| after re-projection).
    pub fn surface(&self, ray: &Ray, t: f32) -> (Vec3A, Vec3A, Vec3A) {
        let local = ray.at(t) - self.center;
        let n = local.normalize_or(Vec3A::Z);
        let local = n * self.radius;
        let err = local.abs() * gamma(5) + self.center.abs() * gamma(1);
        (self.center + local, n, err)
    }
}

/// A parallelogram `corner + a·u + b·v`, `a, b ∈ [0, 1]`, facing `u × v`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quad {
    /// One corner.
    pub corner: Vec3A,
    /// First edge.
    pub u: Vec3A,
    /// Second edge.
    pub v: Vec3A,
    /// Unit normal `u × v / |u × v|`.
    pub normal: Vec3A,
    /// `n / (n · (u × v))` with `n = u × v`: turns a plane offset into local coordinates.
    w: Vec3A,
}

impl Quad {
    /// From a corner and two edges; `None` if the edges are parallel or degenerate.
    pub fn new(corner: Vec3A, u: Vec3A, v: Vec3A) -> Option<Self> {
        let n = u.cross(v);
        let len2 = n.length_squared();
        if len2.is_nan() || len2 <= 0.0 || !len2.is_finite() || !corner.is_finite() {
            return None;
        }
        Some(Self {
            corner,
            u,
            v,
            normal: n / len2.sqrt(),
            w: n / len2,
        })
    }

    /// Plane hit, then bounds on the local axes (the original report's method).
    /// Returns `(t, a, b)` with the hit at `corner + a·u + b·v`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, f32, f32)> {
        let denom = self.normal.dot(ray.dir);
        if denom == 0.0 {
            return None;
        }
        let t = self.normal.dot(self.corner - ray.origin) / denom;
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        let rel = ray.at(t) - self.corner;
        let a = self.w.dot(rel.cross(self.v));
        let b = self.w.dot(self.u.cross(rel));
        if (0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b) {
            Some((t, a, b))
        } else {
            None
        }
    }

    /// Point at local coordinates `(a, b)` and its absolute error bound.
    pub fn surface(&self, a: f32, b: f32) -> (Vec3A, Vec3A) {
        let p = self.corner + self.u * a + self.v * b;
        let err = (self.corner.abs() + (self.u * a).abs() + (self.v * b).abs()) * gamma(4);
        (p, err)
    }

    /// World bounds.
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points([
            self.corner,
            self.corner + self.u,
            self.corner + self.v,
            self.corner + self.u + self.v,
        ])
    }

    /// Area.
    pub fn area(&self) -> f32 {
        self.u.cross(self.v).length()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_hit_distances() {
        let s = Sphere {
            center: Vec3A::new(0.0, 0.0, 10.0),
            radius: 2.0,
        };
        let r = Ray::new(Vec3A::ZERO, Vec3A::Z);
        assert_eq!(s.intersect(&r, f32::INFINITY), Some(8.0));
        // From inside: the far root.
        let inside = Ray::new(Vec3A::new(0.0, 0.0, 10.0), Vec3A::Z);
        assert_eq!(s.intersect(&inside, f32::INFINITY), Some(2.0));
        // Behind: none; beyond t_max: none.
        assert_eq!(s.intersect(&Ray::new(Vec3A::ZERO, -Vec3A::Z), f32::INFINITY), None);
        assert_eq!(s.intersect(&r, 7.9), None);
        // Grazing miss just outside the silhouette.
        let graze = Ray::new(Vec3A::new(2.0001, 0.0, 0.0), Vec3A::Z);
        assert_eq!(s.intersect(&graze, f32::INFINITY), None);
    }

    #[test]
    fn far_sphere_is_stable() {
        // A small sphere far away: the naive quadratic loses all digits here.
        let s = Sphere {
            center: Vec3A::new(0.0, 0.0, 1.0e5),
            radius: 0.01,
        };
        let r = Ray::new(Vec3A::ZERO, Vec3A::Z);
        let t = s.intersect(&r, f32::INFINITY).unwrap();
        assert!((t - (1.0e5 - 0.01)).abs() < 0.01, "{t}");
    }

    #[test]
    fn sphere_uv_follows_mitsuba() {
        let s = Sphere {
            center: Vec3A::new(1.0, 2.0, 3.0),
            radius: 2.0,
        };
        // +x: φ = 0, θ = π/2.
        let (uv, dpdu, dpdv) = s.uv(s.center + Vec3A::X * 2.0);
        assert!((uv - Vec2::new(0.0, 0.5)).length() < 1e-6, "{uv}");
        assert!((dpdu - Vec3A::new(0.0, 2.0 * TAU, 0.0)).length() < 1e-4);
        assert!((dpdv - Vec3A::new(0.0, 0.0, -2.0 * PI)).length() < 1e-4);
        // +y: φ = π/2; −y: φ = 3π/2 (u in [0, 1)); +z: v = 0; −z: v = 1.
        assert!((s.uv(s.center + Vec3A::Y * 2.0).0.x - 0.25).abs() < 1e-6);
        assert!((s.uv(s.center - Vec3A::Y * 2.0).0.x - 0.75).abs() < 1e-6);
        assert!(s.uv(s.center + Vec3A::Z * 2.0).0.y.abs() < 1e-6);
        assert!((s.uv(s.center - Vec3A::Z * 2.0).0.y - 1.0).abs() < 1e-6);
        // The derivatives are those of the map: a small step in u moves p by dpdu·du.
        let p = s.center + Vec3A::new(1.0, 1.0, 2.0f32.sqrt()).normalize() * 2.0;
        let (uv, dpdu, _) = s.uv(p);
        let (phi, theta) = (uv.x * TAU + 1e-3 * TAU, uv.y * PI);
        let q = s.center + Vec3A::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()) * 2.0;
        assert!(((q - p) - dpdu * 1e-3).length() < 1e-4);
    }

    #[test]
    fn quad_hits_inside_only() {
        let q = Quad::new(Vec3A::ZERO, Vec3A::X * 2.0, Vec3A::Y).unwrap();
        let r = Ray::new(Vec3A::new(1.5, 0.5, 1.0), -Vec3A::Z);
        let (t, a, b) = q.intersect(&r, f32::INFINITY).unwrap();
        assert!((t - 1.0).abs() < 1e-6 && (a - 0.75).abs() < 1e-6 && (b - 0.5).abs() < 1e-6);
        let out = Ray::new(Vec3A::new(2.5, 0.5, 1.0), -Vec3A::Z);
        assert!(q.intersect(&out, f32::INFINITY).is_none());
        assert!(Quad::new(Vec3A::ZERO, Vec3A::X, Vec3A::X * 2.0).is_none());
    }
}
