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
    // Round away from p so that the rounding of the addition cannot pull the
    // origin back inside the error box.
    let (po, offset) = ((p + offset).to_array(), offset.to_array());
    Vec3A::from_array(std::array::from_fn(|i| next_float_toward(po[i], offset[i])))
}

/// `v` moved one ulp in the direction of `toward`'s sign: the next float
/// up when `toward > 0`, the next float down when `toward < 0`, else `v`
/// itself. The same values, written without
/// branches (both directions as one step up of `±v`), so that
/// [`offset_ray_origin`]'s three coordinates compile to straight-line code.
#[inline]
fn next_float_toward(v: f32, toward: f32) -> f32 {
    // next_float_down(v) = −next_float_up(−v): step `sign · v` up.
    let sign = if toward < 0.0 { -1.0f32 } else { 1.0 };
    // `+ 0.0` turns −0 into +0 (IEEE round to nearest), as next_float_up does.
    let w = sign * v + 0.0;
    let bits = w.to_bits();
    let stepped = f32::from_bits(if w >= 0.0 {
        bits.wrapping_add(1)
    } else {
        bits.wrapping_sub(1)
    });
    // +inf and NaN stay as they are.
    let up = if w == f32::INFINITY || w.is_nan() { w } else { stepped };
    // Not `toward != 0.0`: a NaN `toward` leaves `v` as it is.
    if toward.abs() > 0.0 {
        sign * up
    } else {
        v
    }
}

/// Smallest f32 greater than `v` (identity for +inf and NaN): the
/// reference `next_float_toward` is tested against.
#[cfg(test)]
fn next_float_up(v: f32) -> f32 {
    if v.is_infinite() && v > 0.0 || v.is_nan() {
        return v;
    }
    let v = if v == -0.0 { 0.0 } else { v };
    let bits = v.to_bits();
    let bits = if v >= 0.0 { bits + 1 } else { bits - 1 };
    f32::from_bits(bits)
}

/// Largest f32 smaller than `v`.
#[cfg(test)]
fn next_float_down(v: f32) -> f32 {
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
    fn next_float_toward_is_next_float_up_and_down() {
        let mut values = vec![
            0.0f32,
            -0.0,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            f32::from_bits(1),
            -f32::from_bits(1),
            f32::MAX,
            -f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            1.0,
            -1.0,
        ];
        // Every exponent, a few mantissas each, both signs.
        for bits in (0..=u32::MAX).step_by(65_521) {
            values.push(f32::from_bits(bits));
        }
        let same = |a: f32, b: f32| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
        for &v in &values {
            for toward in [1.0f32, 1e-30, f32::INFINITY] {
                assert!(same(next_float_toward(v, toward), next_float_up(v)), "{v:e} up");
                assert!(same(next_float_toward(v, -toward), next_float_down(v)), "{v:e} down");
            }
            for toward in [0.0f32, -0.0, f32::NAN] {
                assert!(same(next_float_toward(v, toward), v), "{v:e} {toward}");
            }
        }
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
