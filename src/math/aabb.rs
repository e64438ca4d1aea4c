use super::{gamma, Affine3A, Ray, Vec3A};

/// Axis-aligned bounding box. The empty box has `min = +inf`, `max = -inf`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: Vec3A,
    /// Upper corner.
    pub max: Vec3A,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    /// The empty box (identity of `union`).
    pub const EMPTY: Aabb = Aabb {
        min: Vec3A::splat(f32::INFINITY),
        max: Vec3A::splat(f32::NEG_INFINITY),
    };

    /// Box spanning two corners.
    #[inline]
    pub fn new(min: Vec3A, max: Vec3A) -> Self {
        Self { min, max }
    }

    /// Smallest box holding all `points`.
    pub fn from_points(points: impl IntoIterator<Item = Vec3A>) -> Self {
        points.into_iter().fold(Self::EMPTY, |b, p| b.grow(p))
    }

    /// This box grown to hold `p`.
    #[inline]
    pub fn grow(self, p: Vec3A) -> Self {
        Self {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// Smallest box holding both.
    #[inline]
    pub fn union(self, o: Aabb) -> Self {
        Self {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// Overlap of both boxes (may be empty).
    #[inline]
    pub fn intersection(self, o: Aabb) -> Self {
        Self {
            min: self.min.max(o.min),
            max: self.max.min(o.max),
        }
    }

    /// True when the box holds no point.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// Edge lengths.
    #[inline]
    pub fn extent(&self) -> Vec3A {
        self.max - self.min
    }

    /// Centre point.
    #[inline]
    pub fn center(&self) -> Vec3A {
        (self.min + self.max) * 0.5
    }

    /// Surface area (0 for an empty box).
    #[inline]
    pub fn surface_area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let d = self.extent();
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }

    /// Index of the longest axis.
    pub fn longest_axis(&self) -> usize {
        let d = self.extent();
        if d.x >= d.y && d.x >= d.z {
            0
        } else if d.y >= d.z {
            1
        } else {
            2
        }
    }

    /// Box of the eight transformed corners.
    pub fn transformed(&self, m: &Affine3A) -> Aabb {
        if self.is_empty() {
            return *self;
        }
        let mut out = Aabb::EMPTY;
        for i in 0..8 {
            let c = Vec3A::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            );
            out = out.grow(m.transform_point3a(c));
        }
        out
    }

    /// True when `p` lies inside or on the box.
    #[inline]
    pub fn contains(&self, p: Vec3A) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// Slab test: the parametric interval `[t0, t1]` of the ray inside the box,
    /// clipped to `[0, t_max]`. `inv_dir` is `1/dir` (±inf for zero components:
    /// the `max`/`min` below then discard the NaN from `0·inf`, as in pbrt).
    /// `t1` is widened by `1 + 2γ(3)` (Ize 2013) so rays never slip between
    /// boxes that share a face.
    #[inline]
    pub fn intersect_interval(&self, ray: &Ray, inv_dir: Vec3A, t_max: f32) -> Option<(f32, f32)> {
        let ta = (self.min - ray.origin) * inv_dir;
        let tb = (self.max - ray.origin) * inv_dir;
        let tnear = ta.min(tb);
        let tfar = ta.max(tb);
        // f32::max/min ignore NaN, which arises for 0·inf (ray in the slab plane).
        let t0 = tnear.x.max(tnear.y).max(tnear.z).max(0.0);
        let t1 = tfar.x.min(tfar.y).min(tfar.z).min(t_max) * (1.0 + 2.0 * gamma(3));
        if t0 <= t1 {
            Some((t0, t1))
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slab_hits_and_misses() {
        let b = Aabb::new(Vec3A::splat(-1.0), Vec3A::splat(1.0));
        let r = Ray::new(Vec3A::new(-5.0, 0.0, 0.0), Vec3A::X);
        let (t0, t1) = b.intersect_interval(&r, r.dir.recip(), f32::INFINITY).unwrap();
        assert!((t0 - 4.0).abs() < 1e-6 && (t1 - 6.0).abs() < 1e-5);
        let miss = Ray::new(Vec3A::new(-5.0, 2.0, 0.0), Vec3A::X);
        assert!(b.intersect_interval(&miss, miss.dir.recip(), f32::INFINITY).is_none());
        // A ray lying in a face plane, with zero direction components.
        let grazing = Ray::new(Vec3A::new(-5.0, 1.0, 1.0), Vec3A::X);
        assert!(b
            .intersect_interval(&grazing, grazing.dir.recip(), f32::INFINITY)
            .is_some());
    }

    #[test]
    fn surface_area_and_union() {
        let a = Aabb::new(Vec3A::ZERO, Vec3A::ONE);
        assert_eq!(a.surface_area(), 6.0);
        assert_eq!(Aabb::EMPTY.surface_area(), 0.0);
        let u = a.union(Aabb::new(Vec3A::splat(2.0), Vec3A::splat(3.0)));
        assert_eq!(u.extent(), Vec3A::splat(3.0));
        assert!(Aabb::EMPTY.is_empty());
    }
}
