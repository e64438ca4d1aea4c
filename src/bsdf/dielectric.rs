//! Dielectric interfaces (glass, water) in the local frame, +z pointing to
//! the outside: smooth (a delta reflection and a delta refraction chosen by
//! the Fresnel reflectance) and rough (Walter et al. 2007, "Microfacet
//! Models for Refraction through Rough Surfaces", with GGX and visible
//! normal sampling; the structure of pbrt-v4's `DielectricBxDF`).
//!
//! Radiance is scaled by `1/η²` across refraction (η = ηt/ηi) when camera
//! paths carry radiance; photons carry power and are not scaled (Veach
//! 1997, §5.2, non-symmetric scattering).

use super::fresnel;
use super::microfacet::Microfacet;
use super::{BsdfSample, FresnelModel, Transport};
use crate::math::{Vec2, Vec3A};

/// Refraction of `w` about the normal `n` (any side) for relative index
/// `eta` = inside / outside of `n`'s side: the refracted direction and the
/// ratio ηt/ηi, or `None` under total internal reflection (pbrt-v4's `Refract`).
pub(super) fn refract(w: Vec3A, n: Vec3A, eta: f32) -> Option<(Vec3A, f32)> {
    let (mut n, mut eta, mut cos_i) = (n, eta, n.dot(w));
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((-w / eta + n * (cos_i / eta - cos_t), eta))
}

fn reflectance(model: FresnelModel, cos_i: f32, eta: f32) -> f32 {
    match model {
        FresnelModel::Exact => fresnel::dielectric(cos_i, eta).0,
        FresnelModel::Schlick => fresnel::schlick(cos_i, eta).0,
    }
}

/// A smooth dielectric interface.
#[derive(Clone, Copy, Debug)]
pub struct SmoothDielectric {
    /// Index of the inside relative to the outside.
    pub eta: f32,
    /// Colour filter on transmitted light.
    pub tint: Vec3A,
    /// Fresnel formula.
    pub fresnel: FresnelModel,
}

impl SmoothDielectric {
    pub(super) fn sample(&self, wo: Vec3A, uc: f32, transport: Transport) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let r = reflectance(self.fresnel, wo.z, self.eta);
        let t = 1.0 - r;
        if uc < r || t <= 0.0 {
            let wi = Vec3A::new(-wo.x, -wo.y, wo.z);
            return Some(BsdfSample::specular(wi, Vec3A::splat(r / wi.z.abs()), r));
        }
        let (wi, etap) = refract(wo, Vec3A::Z, self.eta)?;
        let mut f = self.tint * (t / wi.z.abs());
        if transport == Transport::Radiance {
            f /= etap * etap;
        }
        let mut s = BsdfSample::specular(wi, f, t);
        s.eta = etap;
        s.transmission = true;
        Some(s)
    }
}

/// The reflectance of a thin dielectric sheet (a window pane, a soap
/// film): light bounces between its two parallel faces, each reflecting
/// `R` at the incidence `cos_i`, so the sheet reflects the whole series
/// `R + T² R / (1 − R²)` and transmits the rest straight through (Mitsuba 3's
/// `thindielectric`; absorption inside the sheet is neglected).
pub fn thin_sheet_reflectance(model: FresnelModel, cos_i: f32, eta: f32) -> f32 {
    sheet_series(reflectance(model, cos_i.abs(), eta))
}

/// What a sheet whose faces each reflect `r` reflects in all:
/// `r + (1 − r)² r / (1 − r²)` (1 under total internal reflection).
pub fn sheet_series(r: f32) -> f32 {
    if r < 1.0 {
        let t = 1.0 - r;
        r + t * t * r / (1.0 - r * r)
    } else {
        r
    }
}

/// A thin dielectric sheet: a delta reflection and a delta transmission
/// that does not bend the ray, the same from both sides.
#[derive(Clone, Copy, Debug)]
pub struct ThinDielectric {
    /// Index of the sheet relative to the outside.
    pub eta: f32,
    /// Colour filter on transmitted light.
    pub tint: Vec3A,
    /// Fresnel formula.
    pub fresnel: FresnelModel,
}

impl ThinDielectric {
    pub(super) fn sample(&self, wo: Vec3A, uc: f32) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let r = thin_sheet_reflectance(self.fresnel, wo.z, self.eta);
        let t = 1.0 - r;
        if uc < r || t <= 0.0 {
            let wi = Vec3A::new(-wo.x, -wo.y, wo.z);
            return Some(BsdfSample::specular(wi, Vec3A::splat(r / wi.z.abs()), r));
        }
        let wi = -wo;
        let mut s = BsdfSample::specular(wi, self.tint * (t / wi.z.abs()), t);
        s.transmission = true;
        Some(s)
    }
}

/// A rough dielectric interface (GGX).
#[derive(Clone, Copy, Debug)]
pub struct RoughDielectric {
    /// Index of the inside relative to the outside.
    pub eta: f32,
    /// Colour filter on transmitted light.
    pub tint: Vec3A,
    /// Microfacet distribution.
    pub microfacet: Microfacet,
}

/// The generalised half vector of `wo` and `wi` (pointing to +z) and the
/// ratio ηt/ηi (1 for reflection); `None` when degenerate.
pub(super) fn half_vector(wo: Vec3A, wi: Vec3A, eta: f32) -> Option<(Vec3A, f32, bool)> {
    if wo.z == 0.0 || wi.z == 0.0 {
        return None;
    }
    let reflect = wo.z * wi.z > 0.0;
    let etap = if reflect {
        1.0
    } else if wo.z > 0.0 {
        eta
    } else {
        1.0 / eta
    };
    let wm = wi * etap + wo;
    if wm.length_squared() == 0.0 {
        return None;
    }
    let wm = wm.normalize();
    let wm = if wm.z < 0.0 { -wm } else { wm };
    // Microfacets seen from behind contribute nothing.
    if wm.dot(wi) * wi.z < 0.0 || wm.dot(wo) * wo.z < 0.0 {
        return None;
    }
    Some((wm, etap, reflect))
}

impl RoughDielectric {
    pub(super) fn eval(&self, wo: Vec3A, wi: Vec3A, transport: Transport) -> Vec3A {
        let Some((wm, etap, reflect)) = half_vector(wo, wi, self.eta) else {
            return Vec3A::ZERO;
        };
        let f = fresnel::dielectric(wo.dot(wm), self.eta).0;
        let dg = self.microfacet.d(wm) * self.microfacet.g(wi, wo, wm);
        if reflect {
            return Vec3A::splat(dg * f / (4.0 * wi.z * wo.z).abs());
        }
        let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2) * wi.z * wo.z;
        let mut ft = dg * (1.0 - f) * (wi.dot(wm) * wo.dot(wm) / denom).abs();
        if transport == Transport::Radiance {
            ft /= etap * etap;
        }
        self.tint * ft
    }

    pub(super) fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        let Some((wm, etap, reflect)) = half_vector(wo, wi, self.eta) else {
            return 0.0;
        };
        let r = fresnel::dielectric(wo.dot(wm), self.eta).0;
        let visible = self.microfacet.pdf_normal(wo, wm);
        if reflect {
            visible / (4.0 * wo.dot(wm).abs()) * r
        } else {
            let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2);
            visible * wi.dot(wm).abs() / denom * (1.0 - r)
        }
    }

    pub(super) fn sample(&self, wo: Vec3A, uc: f32, u: Vec2, transport: Transport) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let wm = self.microfacet.sample_normal(wo, u);
        let r = fresnel::dielectric(wo.dot(wm), self.eta).0;
        let wi = if uc < r {
            let wi = 2.0 * wo.dot(wm) * wm - wo;
            if wi.z * wo.z <= 0.0 {
                return None;
            }
            wi
        } else {
            let (wi, _) = refract(wo, wm, self.eta)?;
            if wi.z * wo.z >= 0.0 {
                return None;
            }
            wi
        };
        let eta = if wo.z > 0.0 { self.eta } else { 1.0 / self.eta };
        BsdfSample::scattered(wo, wi, self.pdf(wo, wi), || self.eval(wo, wi, transport), eta)
    }
}
