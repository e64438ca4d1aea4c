//! The original report's surface, as energy-conserving lobes: Lambertian
//! diffuse, the normalised Phong and Blinn-Phong highlights with importance
//! sampling, and a tinted perfect mirror. Local frame, reflection only
//! (both directions on the +z side).
//!
//! - Phong (Lafortune & Willems 1994): `f = ks (n+2)/(2π) cos^n α`, `α`
//!   between `wi` and the mirror direction of `wo`; sampled with density
//!   `(n+1)/(2π) cos^n α` about the mirror direction. Its albedo is `ks` at
//!   normal incidence and less elsewhere.
//! - Blinn-Phong as a microfacet lobe (Cook & Torrance 1982): the
//!   normalised Blinn distribution `D = (n+2)/(2π) cos^n θh` with the
//!   V-cavity masking `G = min(1, 2 cos θh cos θo / (wo·h), 2 cos θh cos θi / (wo·h))`,
//!   `f = ks D G / (4 cos θi cos θo)`; the half vector is sampled with
//!   density `D cos θh`. Since `G ≤ G1(wo)` and the V-cavity masking is
//!   normalised, the lobe never reflects more than `ks`, at any angle.

use super::BsdfSample;
use crate::math::sampling::cosine_hemisphere;
use crate::math::{Frame, Vec2, Vec3A};
use crate::scene::{Material, ShadingModel};
use std::f32::consts::PI;

/// The highlight of the report's material `m` (local directions).
pub fn highlight(m: &Material, wo: Vec3A, wi: Vec3A) -> Vec3A {
    if m.specular.max_element() <= 0.0 {
        return Vec3A::ZERO;
    }
    Highlight {
        ks: m.specular,
        n: m.shininess,
        model: m.model,
    }
    .eval(wo, wi)
}

/// The diffuse and highlight lobes of the report's material `m` (local
/// directions; the mirror part is the caller's).
pub fn surface(m: &Material, wo: Vec3A, wi: Vec3A) -> Vec3A {
    Lambert { kd: m.diffuse }.eval(wo, wi) + highlight(m, wo, wi)
}

/// Lambertian reflection `kd / π`.
#[derive(Clone, Copy, Debug)]
pub struct Lambert {
    /// Albedo.
    pub kd: Vec3A,
}

impl Lambert {
    pub(super) fn eval(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        if wo.z > 0.0 && wi.z > 0.0 {
            self.kd * (1.0 / PI)
        } else {
            Vec3A::ZERO
        }
    }

    pub(super) fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z > 0.0 && wi.z > 0.0 {
            wi.z / PI
        } else {
            0.0
        }
    }

    pub(super) fn sample(&self, wo: Vec3A, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = cosine_hemisphere(u);
        (wi.z > 0.0).then(|| BsdfSample::glossy(wi, self.kd * (1.0 / PI), wi.z / PI))
    }
}

/// A normalised Phong or Blinn-Phong highlight (module docs).
#[derive(Clone, Copy, Debug)]
pub struct Highlight {
    /// Specular reflectance.
    pub ks: Vec3A,
    /// Exponent.
    pub n: f32,
    /// Which lobe.
    pub model: ShadingModel,
}

fn mirror_of(wo: Vec3A) -> Vec3A {
    Vec3A::new(-wo.x, -wo.y, wo.z)
}

impl Highlight {
    pub(super) fn eval(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Vec3A::ZERO;
        }
        let n = self.n.max(0.0);
        match self.model {
            ShadingModel::Phong => {
                let cos_a = wi.dot(mirror_of(wo)).max(0.0);
                self.ks * ((n + 2.0) / (2.0 * PI) * cos_a.powf(n))
            }
            ShadingModel::BlinnPhong => {
                let h = (wi + wo).normalize_or_zero();
                let wo_h = wo.dot(h);
                if h.z <= 0.0 || wo_h <= 0.0 {
                    return Vec3A::ZERO;
                }
                let d = (n + 2.0) / (2.0 * PI) * h.z.powf(n);
                let g = (2.0 * h.z * wo.z.min(wi.z) / wo_h).min(1.0);
                self.ks * (d * g / (4.0 * wi.z * wo.z))
            }
        }
    }

    pub(super) fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let n = self.n.max(0.0);
        match self.model {
            ShadingModel::Phong => (n + 1.0) / (2.0 * PI) * wi.dot(mirror_of(wo)).max(0.0).powf(n),
            ShadingModel::BlinnPhong => {
                let h = (wi + wo).normalize_or_zero();
                let wo_h = wo.dot(h);
                if h.z <= 0.0 || wo_h <= 0.0 {
                    return 0.0;
                }
                (n + 2.0) / (2.0 * PI) * h.z.powf(n + 1.0) / (4.0 * wo_h)
            }
        }
    }

    pub(super) fn sample(&self, wo: Vec3A, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let n = self.n.max(0.0);
        // A direction at angle acos(u^(1/e)) about `axis`: density
        // (e/2π) cos^(e−1) θ.
        let about = |axis: Vec3A, e: f32| {
            let cos = u.x.powf(1.0 / e);
            let sin = (1.0 - cos * cos).max(0.0).sqrt();
            let phi = 2.0 * PI * u.y;
            Frame::from_normal(axis).to_world(Vec3A::new(sin * phi.cos(), sin * phi.sin(), cos))
        };
        let wi = match self.model {
            ShadingModel::Phong => about(mirror_of(wo), n + 1.0),
            ShadingModel::BlinnPhong => {
                let h = about(Vec3A::Z, n + 2.0);
                2.0 * wo.dot(h) * h - wo
            }
        };
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf(wo, wi);
        (pdf > 0.0).then(|| BsdfSample::glossy(wi, self.eval(wo, wi), pdf))
    }
}

/// A perfect mirror with a colour filter (a delta lobe).
#[derive(Clone, Copy, Debug)]
pub struct Mirror {
    /// Reflected fraction per channel.
    pub tint: Vec3A,
}

impl Mirror {
    pub(super) fn sample(&self, wo: Vec3A) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = mirror_of(wo);
        Some(BsdfSample::specular(wi, self.tint / wi.z, 1.0))
    }
}
