//! A diffuse base under a smooth clear coating (plastic, varnish): the
//! coating reflects a delta lobe with the exact dielectric Fresnel
//! reflectance; the light it transmits is scattered by the base, reflected
//! back and forth between base and coating (the geometric series
//! `1 / (1 − F_dr)` with the coating's hemispherical internal reflectance
//! `F_dr`), and leaves through the coating again. This is the model of
//! Mitsuba 3's `plastic` (linear variant):
//! `f = kd / (1 − F_dr(1/η)) · (1 − F(θi)) (1 − F(θo)) / (η² π)`, or with
//! `kd / (1 − kd F_dr)` in the nonlinear variant.

use super::fresnel;
use super::BsdfSample;
use crate::math::sampling::cosine_hemisphere;
use crate::math::{Vec2, Vec3A};
use std::f32::consts::PI;

/// A coated diffuse surface.
#[derive(Clone, Copy, Debug)]
pub struct Plastic {
    /// Albedo of the base.
    pub kd: Vec3A,
    /// Index of the coating relative to the outside.
    pub eta: f32,
    /// The base's colour tints every inter-reflection (Mitsuba's `nonlinear`).
    pub nonlinear: bool,
}

/// The base's albedo `kd` with the light that bounces between base and a
/// coating of internal reflectance `f_dr`: `kd / (1 − F_dr)`, or `kd / (1 −
/// kd F_dr)` when every bounce is tinted (`nonlinear`).
pub(super) fn inter_reflected(kd: Vec3A, f_dr: f32, nonlinear: bool) -> Vec3A {
    if nonlinear {
        kd / (Vec3A::ONE - kd * f_dr)
    } else {
        kd / (1.0 - f_dr)
    }
}

impl Plastic {
    /// Probability of sampling the coating's reflection when `F` of it is
    /// reflected (Mitsuba's weighting by the mean reflectances).
    fn specular_probability(&self, f: f32) -> f32 {
        let d_mean = (self.kd.x + self.kd.y + self.kd.z) / 3.0;
        let weight = 1.0 / (1.0 + d_mean);
        let spec = f * weight;
        let diff = (1.0 - f) * (1.0 - weight);
        if spec + diff > 0.0 {
            spec / (spec + diff)
        } else {
            1.0
        }
    }

    /// Probability that [`sample`](Self::sample) picks the coating's
    /// reflection from `wo`.
    pub(super) fn delta_probability(&self, wo: Vec3A) -> f32 {
        if wo.z <= 0.0 {
            return 0.0;
        }
        self.specular_probability(fresnel::dielectric(wo.z, self.eta).0)
    }

    fn base(&self) -> Vec3A {
        inter_reflected(self.kd, fresnel::diffuse_reflectance(1.0 / self.eta), self.nonlinear)
    }

    pub(super) fn eval(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Vec3A::ZERO;
        }
        let t_o = 1.0 - fresnel::dielectric(wo.z, self.eta).0;
        let t_i = 1.0 - fresnel::dielectric(wi.z, self.eta).0;
        self.base() * (t_i * t_o / (self.eta * self.eta * PI))
    }

    pub(super) fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let f = fresnel::dielectric(wo.z, self.eta).0;
        (1.0 - self.specular_probability(f)) * wi.z / PI
    }

    pub(super) fn sample(&self, wo: Vec3A, uc: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let f = fresnel::dielectric(wo.z, self.eta).0;
        let p_spec = self.specular_probability(f);
        if uc < p_spec {
            let wi = Vec3A::new(-wo.x, -wo.y, wo.z);
            return Some(BsdfSample::specular(wi, Vec3A::splat(f / wi.z), p_spec));
        }
        let wi = cosine_hemisphere(u);
        if wi.z <= 0.0 {
            return None;
        }
        Some(BsdfSample::glossy(wi, self.eval(wo, wi), self.pdf(wo, wi)))
    }
}
