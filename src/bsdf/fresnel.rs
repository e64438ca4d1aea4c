//! Fresnel reflectance: exact for dielectrics and conductors (unpolarised
//! light, the average of the s and p terms), Schlick's approximation, and
//! the hemispherical average used by the coated diffuse.

use crate::math::Vec3A;

/// Exact Fresnel reflectance of a smooth dielectric interface for light
/// arriving with `cos_i` (positive: from the outside, negative: from the
/// inside) on an interface of relative index `eta` = inside / outside.
/// Returns `(R, cos θt)` with `cos θt` signed like the transmitted
/// direction's z (0 under total internal reflection, where `R = 1`).
/// Formulas: pbrt-v4 §9.3.3 (`FrDielectric`), Mitsuba 3's `fresnel`.
pub fn dielectric(cos_i: f32, eta: f32) -> (f32, f32) {
    if eta == 1.0 {
        return (0.0, -cos_i);
    }
    let (eta_it, eta_ti) = if cos_i >= 0.0 {
        (eta, 1.0 / eta)
    } else {
        (1.0 / eta, eta)
    };
    let cos_i_abs = cos_i.abs().min(1.0);
    let cos_t2 = 1.0 - (1.0 - cos_i_abs * cos_i_abs) * eta_ti * eta_ti;
    if cos_t2 <= 0.0 {
        return (1.0, 0.0);
    }
    if cos_i_abs == 0.0 {
        return (1.0, 0.0);
    }
    let cos_t = cos_t2.sqrt();
    let a_s = (cos_i_abs - eta_it * cos_t) / (cos_i_abs + eta_it * cos_t);
    let a_p = (eta_it * cos_i_abs - cos_t) / (eta_it * cos_i_abs + cos_t);
    let r = 0.5 * (a_s * a_s + a_p * a_p);
    (r.clamp(0.0, 1.0), if cos_i >= 0.0 { -cos_t } else { cos_t })
}

/// Schlick's approximation with the same arguments and results as
/// [`dielectric`] (the original report's choice): `R0 + (1 − R0)(1 − c)^5`,
/// where `c` is the cosine on the less dense side (Schlick 1994; pbrt-v3
/// §8.2), so that the curve reaches 1 at the critical angle.
pub fn schlick(cos_i: f32, eta: f32) -> (f32, f32) {
    let (exact_r, cos_t) = dielectric(cos_i, eta);
    if exact_r >= 1.0 {
        return (1.0, 0.0);
    }
    let (n1, n2) = if cos_i >= 0.0 { (1.0, eta) } else { (eta, 1.0) };
    let r = fresnel_schlick(n1, n2, cos_i.abs(), cos_t.abs());
    (r, cos_t)
}

/// Schlick's approximation of the Fresnel reflectance from medium `n1` into
/// `n2`: `R = R0 + (1 − R0)(1 − cos θ)^5`, `R0 = ((n1 − n2)/(n1 + n2))²`.
/// From the denser medium (`n1 > n2`) the angle is the transmitted one,
/// `θt` (Schlick 1994; pbrt §8.2): with `θi` the curve would not reach 1 at
/// the critical angle. Total internal reflection must be handled before.
#[inline]
pub fn fresnel_schlick(n1: f32, n2: f32, cos_i: f32, cos_t: f32) -> f32 {
    let r0 = ((n1 - n2) / (n1 + n2)).powi(2);
    let c = if n1 > n2 { cos_t } else { cos_i };
    let m = (1.0 - c).clamp(0.0, 1.0);
    r0 + (1.0 - r0) * m * m * m * m * m
}

/// Exact Fresnel reflectance of a conductor of complex index `eta + i k`
/// (per channel) for `cos_i ∈ [0, 1]` (Mitsuba 3's `fresnel_conductor`,
/// after Born & Wolf).
pub fn conductor(cos_i: f32, eta: Vec3A, k: Vec3A) -> Vec3A {
    let c = cos_i.clamp(0.0, 1.0);
    let one = |eta_r: f32, eta_i: f32| {
        let cos2 = c * c;
        let sin2 = 1.0 - cos2;
        let sin4 = sin2 * sin2;
        let temp = eta_r * eta_r - eta_i * eta_i - sin2;
        let a2pb2 = (temp * temp + 4.0 * eta_i * eta_i * eta_r * eta_r).max(0.0).sqrt();
        let a = (0.5 * (a2pb2 + temp)).max(0.0).sqrt();
        let t1 = a2pb2 + cos2;
        let t2 = 2.0 * c * a;
        let r_s = (t1 - t2) / (t1 + t2);
        let t3 = a2pb2 * cos2 + sin4;
        let t4 = t2 * sin2;
        let r_p = r_s * (t3 - t4) / (t3 + t4);
        (0.5 * (r_s + r_p)).clamp(0.0, 1.0)
    };
    Vec3A::new(one(eta.x, k.x), one(eta.y, k.y), one(eta.z, k.z))
}

/// Hemispherical average of the dielectric Fresnel reflectance for light
/// inside a medium of relative index `eta` (the fits of Egan & Hilgeman
/// 1973 for `eta < 1` and d'Eon & Irving 2011 above, as in Mitsuba 3).
pub fn diffuse_reflectance(eta: f32) -> f32 {
    if eta < 1.0 {
        -1.4399 * eta * eta + 0.7099 * eta + 0.6681 + 0.0636 / eta
    } else {
        let x = 1.0 / eta;
        0.919317 + x * (-3.4793 + x * (6.75335 + x * (-7.80989 + x * (4.98554 + x * -1.36881))))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectric_limits() {
        // Normal incidence: ((n − 1)/(n + 1))².
        let (r, ct) = dielectric(1.0, 1.5);
        assert!((r - 0.04).abs() < 1e-6 && (ct + 1.0).abs() < 1e-6);
        // Same from inside.
        let (r2, ct2) = dielectric(-1.0, 1.5);
        assert!((r2 - 0.04).abs() < 1e-6 && (ct2 - 1.0).abs() < 1e-6);
        // Grazing: total reflection.
        assert!((dielectric(1e-7, 1.5).0 - 1.0).abs() < 1e-3);
        // Beyond the critical angle from inside: TIR.
        assert_eq!(dielectric(-0.5, 1.5), (1.0, 0.0));
        // Brewster's angle: the p term vanishes, R = a_s² / 2.
        let theta_b = 1.5f32.atan();
        let (r, _) = dielectric(theta_b.cos(), 1.5);
        let sin_t = theta_b.sin() / 1.5;
        let cos_t = (1.0 - sin_t * sin_t).sqrt();
        let a_s = (theta_b.cos() - 1.5 * cos_t) / (theta_b.cos() + 1.5 * cos_t);
        assert!((r - 0.5 * a_s * a_s).abs() < 1e-5, "{r}");
        // Index matched: nothing reflects.
        assert_eq!(dielectric(0.3, 1.0).0, 0.0);
    }

    #[test]
    fn conductor_with_no_absorption_is_the_dielectric() {
        for c in [0.1f32, 0.5, 0.9, 1.0] {
            let r = conductor(c, Vec3A::splat(1.5), Vec3A::ZERO);
            let (d, _) = dielectric(c, 1.5);
            assert!((r.x - d).abs() < 1e-5, "{c}: {r} {d}");
        }
        // Gold reflects more red than blue at normal incidence; grazing → 1.
        let (eta, k) = (Vec3A::new(0.143, 0.375, 1.442), Vec3A::new(3.983, 2.386, 1.603));
        let f = conductor(1.0, eta, k);
        assert!(f.x > 0.9 && f.z < 0.6, "{f}");
        assert!(conductor(1e-6, eta, k).min_element() > 0.99);
    }

    #[test]
    fn diffuse_reflectance_matches_a_numerical_average() {
        // 2 ∫ R(cos) cos d(cos) over the hemisphere.
        for eta in [1.33f32, 1.5, 1.0 / 1.5] {
            let n = 20000;
            let avg: f64 = (0..n)
                .map(|i| {
                    let c = (i as f32 + 0.5) / n as f32;
                    2.0 * (dielectric(c, eta).0 * c) as f64 / n as f64
                })
                .sum();
            let fit = diffuse_reflectance(eta) as f64;
            assert!((avg - fit).abs() < 0.01 * fit.max(0.05), "{eta}: {avg} vs {fit}");
        }
    }
}
