//! Mitsuba's `thindielectric`: a thin sheet of glass (a window, a soap
//! film) whose two parallel interfaces reflect and transmit without
//! displacing the ray. With `R` the Fresnel reflectance of one interface,
//! the internal reflections add up to `R' = R + T R T + T R³ T + … =
//! 2R / (1 + R)`; the sheet reflects `R'` specularly and lets `1 − R'`
//! straight through (Mitsuba's `src/bsdfs/thindielectric.cpp`). Both sides
//! behave the same.

use super::fresnel;
use super::BsdfSample;
use crate::math::Vec3A;

/// The sheet, of relative index `eta` (inside over outside).
#[derive(Clone, Copy, Debug)]
pub struct ThinDielectric {
    /// Relative index of one interface.
    pub eta: f32,
}

impl ThinDielectric {
    /// The sheet's reflectance `R' = 2R / (1 + R)` for light arriving at
    /// `|cos θ|` (either side).
    pub fn reflectance(&self, cos: f32) -> f32 {
        let (r, _) = fresnel::dielectric(cos.abs(), self.eta);
        if r < 1.0 {
            2.0 * r / (1.0 + r)
        } else {
            1.0
        }
    }

    /// Reflection with probability `R'`, else straight on; the throughput
    /// factor is 1 either way.
    pub fn sample(&self, wo: Vec3A, uc: f32) -> Option<BsdfSample> {
        let cos = wo.z.abs();
        if cos == 0.0 {
            return None;
        }
        let r = self.reflectance(cos);
        let (wi, pdf, transmission) = if uc < r {
            (Vec3A::new(-wo.x, -wo.y, wo.z), r, false)
        } else {
            (-wo, 1.0 - r, true)
        };
        Some(BsdfSample {
            wi,
            f: Vec3A::splat(pdf / cos),
            pdf,
            delta: true,
            transmission,
            eta: 1.0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sheet_reflects_the_sum_of_its_internal_reflections() {
        let sheet = ThinDielectric { eta: 1.5 };
        // At normal incidence R = 0.04, so R' = 0.08 / 1.04.
        assert!((sheet.reflectance(1.0) - 0.08 / 1.04).abs() < 1e-6);
        assert_eq!(sheet.reflectance(-1.0), sheet.reflectance(1.0));
        let wo = Vec3A::new(0.3, 0.1, -0.8).normalize();
        let r = sheet.reflectance(wo.z);
        let reflected = sheet.sample(wo, r * 0.5).unwrap();
        assert!(!reflected.transmission && reflected.wi.z == wo.z);
        let through = sheet.sample(wo, r + 0.5 * (1.0 - r)).unwrap();
        assert!(through.transmission && through.wi == -wo);
        for s in [reflected, through] {
            assert!((s.weight() - Vec3A::ONE).abs().max_element() < 1e-6);
        }
    }
}
