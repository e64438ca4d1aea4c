//! Metals: a smooth conductor (a delta mirror tinted by the exact Fresnel
//! reflectance of its complex index `eta + i k`) and a rough one (the
//! Cook–Torrance microfacet BRDF with GGX, separable Smith masking and
//! visible normal sampling, as Mitsuba 3's `roughconductor`). Named presets
//! of `eta` and `k` are in `scene::metals`.

use super::fresnel;
use super::microfacet::Microfacet;
use super::BsdfSample;
use crate::math::{Vec2, Vec3A};

/// A smooth metal.
#[derive(Clone, Copy, Debug)]
pub struct SmoothConductor {
    /// Real part of the index, per channel.
    pub eta: Vec3A,
    /// Extinction coefficient, per channel.
    pub k: Vec3A,
}

impl SmoothConductor {
    pub(super) fn sample(&self, wo: Vec3A) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = Vec3A::new(-wo.x, -wo.y, wo.z);
        Some(BsdfSample::specular(
            wi,
            fresnel::conductor(wo.z, self.eta, self.k) / wi.z,
            1.0,
        ))
    }
}

/// A rough metal.
#[derive(Clone, Copy, Debug)]
pub struct RoughConductor {
    /// Real part of the index, per channel.
    pub eta: Vec3A,
    /// Extinction coefficient, per channel.
    pub k: Vec3A,
    /// Microfacet distribution.
    pub microfacet: Microfacet,
}

impl RoughConductor {
    pub(super) fn eval(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Vec3A::ZERO;
        }
        let m = (wo + wi).normalize_or_zero();
        if m.z <= 0.0 {
            return Vec3A::ZERO;
        }
        let dg = self.microfacet.d(m) * self.microfacet.g(wi, wo, m);
        fresnel::conductor(wo.dot(m), self.eta, self.k) * (dg / (4.0 * wi.z * wo.z))
    }

    pub(super) fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let m = (wo + wi).normalize_or_zero();
        if m.z <= 0.0 || wo.dot(m) <= 0.0 {
            return 0.0;
        }
        self.microfacet.pdf_normal(wo, m) / (4.0 * wo.dot(m))
    }

    pub(super) fn sample(&self, wo: Vec3A, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let m = self.microfacet.sample_normal(wo, u);
        let wi = 2.0 * wo.dot(m) * m - wo;
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf(wo, wi);
        (pdf > 0.0).then(|| BsdfSample::glossy(wi, self.eval(wo, wi), pdf))
    }
}
