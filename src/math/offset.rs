use super::Vec3A;

/// Moves a surface point off the surface before spawning a ray, with no fixed
/// epsilon: the offset is the point's absolute error bound `p_error` projected
/// on the geometric normal, then pushed one ulp further away (pbrt-v4
/// `OffsetRayOrigin`, §6.8.6). Because `p_error` scales with the magnitudes
/// that produced `p`, the same code is right for scenes of size 1e-4 and 1e5.
///
/// `ng` is the geometric normal (either side), `w` the new ray's direction.
#[inline]
pub fn offset_ray_origin(p: Vec3A, p_error: Vec3A, ng: Vec3A, w: Vec3A) -> Vec3A {
    let d = ng.abs().dot(p_error);
    let mut offset = ng * d;
    if w.dot(ng) < 0.0 {
        offset = -offset;
    }
    let mut po = p + offset;
    // Round away from p so that the rounding of the addition cannot pull the
    // origin back inside the error box.
    for i in 0..3 {
        if offset[i] > 0.0 {
            po[i] = next_float_up(po[i]);
        } else if offset[i] < 0.0 {
            po[i] = next_float_down(po[i]);
        }
    }
    po
}

/// Smallest f32 greater than `v` (identity for +inf and NaN).
#[inline]
pub fn next_float_up(v: f32) -> f32 {
    if v.is_infinite() && v > 0.0 || v.is_nan() {
        return v;
    }
    let v = if v == -0.0 { 0.0 } else { v };
    let bits = v.to_bits();
    let bits = if v >= 0.0 { bits + 1 } else { bits - 1 };
    f32::from_bits(bits)
}

/// Largest f32 smaller than `v`.
#[inline]
pub fn next_float_down(v: f32) -> f32 {
    -next_float_up(-v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn next_float_moves_one_ulp() {
        assert!(next_float_up(1.0) > 1.0 && next_float_up(1.0) - 1.0 < 2e-7);
        assert!(next_float_down(1.0) < 1.0);
        assert!(next_float_up(0.0) > 0.0 && next_float_down(0.0) < 0.0);
        assert!(next_float_up(-1.0) > -1.0);
    }

    #[test]
    fn offset_goes_to_the_side_of_w_and_scales_with_error() {
        let n = Vec3A::Y;
        let p = Vec3A::new(1e5, 0.0, 0.0);
        let err = Vec3A::splat(1e-2);
        let up = offset_ray_origin(p, err, n, Vec3A::Y);
        let down = offset_ray_origin(p, err, n, -Vec3A::Y);
        assert!(up.y >= 1e-2 && down.y <= -1e-2);
        let tiny = offset_ray_origin(Vec3A::ZERO, Vec3A::splat(1e-12), n, Vec3A::Y);
        assert!(tiny.y > 0.0 && tiny.y < 1e-11);
    }
}
