//! Analytic shapes, stored in world space: spheres, quads, and Mitsuba's
//! disks and open cylinders (their object space mapped to the world by the
//! loaders, see [`Disk`] and [`Cylinder`]).

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

/// Component-wise square root.
#[inline]
fn sqrt3(v: Vec3A) -> Vec3A {
    Vec3A::new(v.x.sqrt(), v.y.sqrt(), v.z.sqrt())
}

/// Mitsuba's `disk`: the unit disk `x² + y² ≤ 1` of its object's `z = 0`
/// plane mapped to the world by an affine map, `p = centre + x·a + y·b`
/// (an ellipse when `a` and `b` differ in length or are not orthogonal).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disk {
    /// Centre (the image of the object's origin).
    pub center: Vec3A,
    /// Image of the object's +x axis (`∂p/∂x`).
    pub a: Vec3A,
    /// Image of the object's +y axis (`∂p/∂y`).
    pub b: Vec3A,
    /// Unit normal of the front side, `±(a × b) / |a × b|`.
    pub normal: Vec3A,
    /// `(a × b) / |a × b|²`: turns a plane offset into local coordinates.
    w: Vec3A,
}

impl Disk {
    /// The disk `centre + x·a + y·b`, facing `a × b`, or `−(a × b)` when
    /// `reversed` (Mitsuba's front is `M⁻ᵀ·ẑ`, which is `−(a × b)` for a
    /// mirroring `M`, and `flip_normals` turns it over); `None` when `a`
    /// and `b` are parallel or not finite.
    pub fn new(center: Vec3A, a: Vec3A, b: Vec3A, reversed: bool) -> Option<Self> {
        let n = a.cross(b);
        let len2 = n.length_squared();
        if len2.is_nan() || len2 <= 0.0 || !len2.is_finite() || !center.is_finite() {
            return None;
        }
        let normal = n / len2.sqrt();
        Some(Self {
            center,
            a,
            b,
            normal: if reversed { -normal } else { normal },
            w: n / len2,
        })
    }

    /// Plane hit, then the local coordinates' test `x² + y² ≤ 1` (Mitsuba's
    /// `disk`). Returns `(t, x, y)` with the hit at `centre + x·a + y·b`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, f32, f32)> {
        let denom = self.normal.dot(ray.dir);
        if denom == 0.0 {
            return None;
        }
        let t = self.normal.dot(self.center - ray.origin) / denom;
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        let rel = ray.at(t) - self.center;
        let x = self.w.dot(rel.cross(self.b));
        let y = self.w.dot(self.a.cross(rel));
        if x * x + y * y <= 1.0 {
            Some((t, x, y))
        } else {
            None
        }
    }

    /// Point at local coordinates `(x, y)` and its absolute error bound
    /// (the quad's: the point is rebuilt on the plane from them).
    pub fn surface(&self, x: f32, y: f32) -> (Vec3A, Vec3A) {
        let p = self.center + self.a * x + self.b * y;
        let err = (self.center.abs() + (self.a * x).abs() + (self.b * y).abs()) * gamma(4);
        (p, err)
    }

    /// Texture coordinates and their derivatives at local coordinates
    /// `(x, y)`, as Mitsuba 3's `disk`: `uv = (r, φ / 2π)` with `r = √(x² +
    /// y²)` and `φ ∈ [0, 2π)` the object-space azimuth from +x toward +y;
    /// `∂p/∂u = M·(cos φ, sin φ, 0)`, `∂p/∂v = 2π r · M·(−sin φ, cos φ, 0)`
    /// (`φ = 0` at the centre).
    pub fn uv(&self, x: f32, y: f32) -> (Vec2, Vec3A, Vec3A) {
        let r = (x * x + y * y).sqrt();
        let mut v = y.atan2(x) / TAU;
        if v < 0.0 {
            v += 1.0;
        }
        let (cos_phi, sin_phi) = if r != 0.0 { (x / r, y / r) } else { (1.0, 0.0) };
        let dpdu = self.a * cos_phi + self.b * sin_phi;
        let dpdv = (self.b * cos_phi - self.a * sin_phi) * (TAU * r);
        (Vec2::new(r, v), dpdu, dpdv)
    }

    /// World bounds: the ellipse's extent `√(aₖ² + bₖ²)` about the centre on each axis.
    pub fn bounds(&self) -> Aabb {
        let extent = sqrt3(self.a * self.a + self.b * self.b);
        Aabb::new(self.center - extent, self.center + extent)
    }

    /// Area `π |a × b|`.
    pub fn area(&self) -> f32 {
        PI * self.a.cross(self.b).length()
    }
}

/// Mitsuba's `cylinder`: an open tube (no caps) of radius `radius` about
/// the segment from `base` along the unit `axis` for `length`. `s` and `t`
/// are the object's x and y axes in the world (`s`, `t`, `axis`
/// orthonormal; left-handed when the object-to-world map mirrors), from
/// which the azimuth `φ` of the texture coordinates is measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cylinder {
    /// Centre of the `v = 0` end.
    pub base: Vec3A,
    /// Unit direction of `φ = 0`.
    pub s: Vec3A,
    /// Unit direction of `φ = π/2`.
    pub t: Vec3A,
    /// Unit axis, from the `v = 0` end to the `v = 1` end.
    pub axis: Vec3A,
    /// Radius (> 0).
    pub radius: f32,
    /// Length (> 0).
    pub length: f32,
    /// The normals point toward the axis (Mitsuba's `flip_normals`).
    pub inward: bool,
}

impl Cylinder {
    /// A cylinder; `None` when the frame is not orthonormal (to 1e-4), the
    /// radius or length not positive, or a value not finite.
    pub fn new(base: Vec3A, [s, t, axis]: [Vec3A; 3], radius: f32, length: f32, inward: bool) -> Option<Self> {
        let unit = |v: Vec3A| (v.length() - 1.0).abs() <= 1e-4;
        let orthogonal = s.dot(t).abs() <= 1e-4 && s.dot(axis).abs() <= 1e-4 && t.dot(axis).abs() <= 1e-4;
        let finite = base.is_finite() && radius.is_finite() && length.is_finite();
        (unit(s) && unit(t) && unit(axis) && orthogonal && finite && radius > 0.0 && length > 0.0).then_some(Self {
            base,
            s,
            t,
            axis,
            radius,
            length,
            inward,
        })
    }

    /// Nearest root of `x² + y² = r²` in `(0, t_max)` with `0 ≤ z ≤ length`
    /// (local coordinates), as [`Sphere::intersect`].
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        self.intersect_where(ray, t_max, |_| true)
    }

    /// The nearest root in `(0, t_max)` within the tube's length that `keep`
    /// accepts (an alpha cutout may reject the near root and keep the far one).
    ///
    /// The ray is taken to the cylinder's frame and the quadratic solved in
    /// f64, as Mitsuba does: the discriminant as `r² − |f⊥|²` (the sphere's
    /// stable form, in the plane across the axis), the second root from
    /// `c / q`.
    #[inline]
    pub fn intersect_where(&self, ray: &Ray, t_max: f32, keep: impl Fn(f32) -> bool) -> Option<f32> {
        let dot = |u: [f64; 3], v: Vec3A| u[0] * f64::from(v.x) + u[1] * f64::from(v.y) + u[2] * f64::from(v.z);
        let f = [
            f64::from(ray.origin.x) - f64::from(self.base.x),
            f64::from(ray.origin.y) - f64::from(self.base.y),
            f64::from(ray.origin.z) - f64::from(self.base.z),
        ];
        let d = [f64::from(ray.dir.x), f64::from(ray.dir.y), f64::from(ray.dir.z)];
        let (ox, oy, oz) = (dot(f, self.s), dot(f, self.t), dot(f, self.axis));
        let (dx, dy, dz) = (dot(d, self.s), dot(d, self.t), dot(d, self.axis));
        let a = dx * dx + dy * dy;
        if a == 0.0 {
            // Along the axis: the ray never crosses the tube.
            return None;
        }
        let b_half = -(ox * dx + oy * dy);
        let (px, py) = (ox + dx * (b_half / a), oy + dy * (b_half / a));
        let r = f64::from(self.radius);
        let disc = a * (r * r - (px * px + py * py));
        if disc < 0.0 {
            return None;
        }
        let c = ox * ox + oy * oy - r * r;
        let q = b_half + disc.sqrt().copysign(b_half);
        if q == 0.0 {
            return None;
        }
        let (mut t0, mut t1) = (c / q, q / a);
        if t0 > t1 {
            std::mem::swap(&mut t0, &mut t1);
        }
        let length = f64::from(self.length);
        [t0, t1].into_iter().find_map(|t| {
            let z = oz + dz * t;
            let t32 = t as f32;
            (t32 > 0.0 && t32 < t_max && (0.0..=length).contains(&z) && keep(t32)).then_some(t32)
        })
    }

    /// Local coordinates `(x, y, z)` of a world point.
    #[inline]
    fn local(&self, p: Vec3A) -> (f32, f32, f32) {
        let rel = p - self.base;
        (rel.dot(self.s), rel.dot(self.t), rel.dot(self.axis))
    }

    /// Hit point re-projected on the tube (Mitsuba moves it along the
    /// normal by `r − ρ`), its unit normal (outward, or toward the axis when
    /// `inward`) and its absolute error bound. The radial direction is
    /// recomputed from the point, so its length is off by a few ulps (γ(4)
    /// of the radius) and the sum `base + r·radial + z·axis` adds γ(3) of
    /// its terms; γ(8) of each term covers both.
    pub fn surface(&self, ray: &Ray, t: f32) -> (Vec3A, Vec3A, Vec3A) {
        let (x, y, z) = self.local(ray.at(t));
        let rho = (x * x + y * y).sqrt();
        let (cos_phi, sin_phi) = if rho > 0.0 { (x / rho, y / rho) } else { (1.0, 0.0) };
        let radial = self.s * cos_phi + self.t * sin_phi;
        let p = self.base + radial * self.radius + self.axis * z;
        let err = (self.base.abs() + (self.s.abs() + self.t.abs()) * self.radius + (self.axis * z).abs()) * gamma(8);
        let n = radial.normalize_or(self.s);
        (p, if self.inward { -n } else { n }, err)
    }

    /// Texture coordinates and their derivatives at surface point `p`, as
    /// Mitsuba 3's `cylinder`: `u = φ / 2π` with `φ ∈ [0, 2π)` the azimuth
    /// from `s` toward `t`, `v = z / length`; `∂p/∂u = 2π (−y·s + x·t)`,
    /// `∂p/∂v = length · axis`, `(x, y, z)` the local coordinates.
    pub fn uv(&self, p: Vec3A) -> (Vec2, Vec3A, Vec3A) {
        let (x, y, z) = self.local(p);
        let mut phi = y.atan2(x);
        if phi < 0.0 {
            phi += TAU;
        }
        let dpdu = (self.t * x - self.s * y) * TAU;
        (Vec2::new(phi / TAU, z / self.length), dpdu, self.axis * self.length)
    }

    /// The point at texture coordinates `uv` and its unit normal.
    pub fn point_at(&self, uv: Vec2) -> (Vec3A, Vec3A) {
        let (sin_phi, cos_phi) = (uv.x * TAU).sin_cos();
        let radial = self.s * cos_phi + self.t * sin_phi;
        let p = self.base + radial * self.radius + self.axis * (uv.y * self.length);
        (p, if self.inward { -radial } else { radial })
    }

    /// World bounds: the boxes of the two end circles, each of extent
    /// `r √(sₖ² + tₖ²)` on axis `k`.
    pub fn bounds(&self) -> Aabb {
        let extent = sqrt3(self.s * self.s + self.t * self.t) * self.radius;
        let top = self.base + self.axis * self.length;
        Aabb::new(self.base.min(top) - extent, self.base.max(top) + extent)
    }

    /// Area `2π r · length`.
    pub fn area(&self) -> f32 {
        TAU * self.radius * self.length
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
