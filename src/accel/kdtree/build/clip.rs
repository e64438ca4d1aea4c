//! Clipping a triangle to a cell ("perfect splits"): the bounds of the part
//! of the triangle inside the cell.

use crate::math::{Aabb, Vec3A};

/// Triangle clipped to a box (Sutherland & Hodgman 1974, one plane at a time),
/// returned as the bounds of the clipped polygon, or the triangle's bounds
/// when it lies inside. The intersection points carry rounding error, so
/// their coordinates are widened by a few ulps and the result clamped to both
/// the cell and the triangle's bounds: conservative, and exact for untouched
/// coordinates (a triangle lying in an axis plane stays planar).
pub fn clip_triangle(p: [Vec3A; 3], cell: &Aabb) -> Aabb {
    let tri = Aabb::from_points(p);
    if tri.min.cmpge(cell.min).all() && tri.max.cmple(cell.max).all() {
        return tri;
    }
    // Vertices with a flag: true for the triangle's own (exact) corners,
    // false for computed intersection points.
    let mut poly = [(Vec3A::ZERO, true); 9];
    let mut next = [(Vec3A::ZERO, true); 9];
    for (slot, &v) in poly.iter_mut().zip(&p) {
        *slot = (v, true);
    }
    let mut len = 3;
    for axis in 0..3 {
        for (plane, keep_above) in [(cell.min[axis], true), (cell.max[axis], false)] {
            let outside_exists = if keep_above {
                tri.min[axis] < plane
            } else {
                tri.max[axis] > plane
            };
            if !outside_exists || len == 0 {
                continue;
            }
            let inside = |v: Vec3A| if keep_above { v[axis] >= plane } else { v[axis] <= plane };
            let mut out = 0;
            for i in 0..len {
                let a = poly[i];
                let b = poly[(i + 1) % len];
                let (ina, inb) = (inside(a.0), inside(b.0));
                if ina {
                    next[out] = a;
                    out += 1;
                }
                if ina != inb {
                    let t = (plane - a.0[axis]) / (b.0[axis] - a.0[axis]);
                    let mut x = a.0 + (b.0 - a.0) * t;
                    x[axis] = plane;
                    next[out] = (x, false);
                    out += 1;
                }
            }
            // A convex polygon cut by a plane gains at most one vertex: out ≤ 9.
            len = out;
            poly[..len].copy_from_slice(&next[..len]);
        }
    }
    let fallback = tri.intersection(*cell);
    if len == 0 {
        return fallback;
    }
    // Only computed points are widened: a corner lying on a later split
    // plane keeps its exact coordinate, so the triangle is not duplicated.
    let err = tri.min.abs().max(tri.max.abs()) * (32.0 * f32::EPSILON);
    let b = poly[..len].iter().fold(Aabb::EMPTY, |b, &(v, exact)| {
        if exact {
            b.grow(v)
        } else {
            b.union(Aabb::new(v - err, v + err))
        }
    });
    b.intersection(fallback)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clip_keeps_inside_triangles_and_planar_ones_exact() {
        let cell = Aabb::new(Vec3A::splat(-1.0), Vec3A::splat(1.0));
        let inside = [
            Vec3A::new(0.0, 0.0, 0.0),
            Vec3A::new(0.5, 0.0, 0.0),
            Vec3A::new(0.0, 0.5, 0.25),
        ];
        assert_eq!(clip_triangle(inside, &cell), Aabb::from_points(inside));
        // A large triangle in the plane z = 0.5 across the cell.
        let big = [
            Vec3A::new(-10.0, -10.0, 0.5),
            Vec3A::new(10.0, -10.0, 0.5),
            Vec3A::new(0.0, 10.0, 0.5),
        ];
        let b = clip_triangle(big, &cell);
        assert_eq!((b.min.z, b.max.z), (0.5, 0.5));
        assert_eq!((b.min.x, b.max.x, b.min.y, b.max.y), (-1.0, 1.0, -1.0, 1.0));
    }

    #[test]
    fn clip_is_tight_and_conservative() {
        // Triangle (0,0,0) (4,0,0) (0,4,0) clipped to x ≥ 3 keeps the corner
        // x ∈ [3, 4], y ∈ [0, 1]: much tighter than the triangle's bounds.
        let t = [Vec3A::ZERO, Vec3A::new(4.0, 0.0, 0.0), Vec3A::new(0.0, 4.0, 0.0)];
        let cell = Aabb::new(Vec3A::new(3.0, -1.0, -1.0), Vec3A::new(5.0, 5.0, 1.0));
        let b = clip_triangle(t, &cell);
        assert_eq!((b.min.x, b.max.x, b.min.y, b.min.z, b.max.z), (3.0, 4.0, 0.0, 0.0, 0.0));
        assert!(b.max.y >= 1.0 && b.max.y < 1.0 + 1e-4, "{b:?}");
        // A triangle outside the cell (touching nothing) clips to nothing.
        let far = Aabb::new(Vec3A::splat(10.0), Vec3A::splat(11.0));
        assert!(clip_triangle(t, &far).is_empty());
    }
}
