//! glTF 2.0's metallic-roughness material (the specification's Appendix B,
//! "BRDF Implementation", with `KHR_materials_transmission`, `_volume` and
//! `_clearcoat`), in the local frame (+z outward), with the energy its
//! single-scattering microfacet lobes lose given back (Kulla & Conty 2017)
//! and the base layered under the specular layer by albedo scaling:
//!
//! ```text
//! dielectric = (1 − t)·c/π·(1 − max(E_s(μo), E_s(μi))) + t·c·btdf(α)
//!            + spec(α)·F_d·(1 + (1 − t)(k_d(μo) − 1))
//! metal      = spec(α)·F_schlick(F0 = c)·k_m(μo)
//! material   = (1 − m)·dielectric + m·metal
//! coated     = (1 − k·F_k(n·v))·material + k·F_k(n·v)·spec(α_k)
//! ```
//!
//! with `c` the base colour, `m` metalness, `t` transmission, `k` the clear
//! coat, `α = roughness²`, `spec` GGX (Walter et al. 2007) with the
//! height-correlated Smith masking of glTF's `V_GGX` (Heitz 2014), and `F_d`
//! the exact dielectric Fresnel reflectance at the micro-normal (Cycles'
//! choice; the specification's Schlick is its approximation).
//!
//! `k = 1 + F_ms (1 − E(μo)) / E(μo)`, `F_ms = F_avg E_avg / (1 − F_avg (1 − E_avg))`
//! gives back the energy single scattering loses to the microfacets'
//! missing inter-reflections (Kulla & Conty 2017, in the scaling form of
//! Turquin 2019 that Cycles and Filament use; [`super::energy`] holds the
//! albedos `E`, `E_avg`), with `F_avg` the dielectric's or, per channel,
//! Schlick's hemispherical average: a white rough metal reflects all the
//! light instead of losing up to 60 % of it at roughness 1.
//! `E_s(μ) = E_F(μ) k_d(μ)` is the specular layer's directional albedo
//! (`F_d(μ)` when smooth), and the base receives what the layer reflects
//! neither toward `wo` nor toward `wi`, the reciprocal form of albedo
//! scaling that `KHR_materials_sheen` specifies; the specification's
//! `1 − F(v·h)` lets the sum reflect more than it receives at grazing
//! angles, and `1 − F(n·v)` darkens rough surfaces, whose layer reflects
//! less than `F(n·v)`. The dielectric's compensation is weighted by `1 − t`
//! so that with the transmission it stays within the light it receives.
//! Transmission refracts through a solid (`KHR_materials_volume`) or, on a
//! thin wall, leaves on the other side without bending. Lobes whose `α` is
//! below [`SMOOTH_ALPHA`] are deltas. Seen from inside a solid, the surface
//! is the dielectric interface alone, tinted by the base colour.
//!
//! Each sample picks one of four strategies (coat, specular reflection,
//! transmission, diffuse) with probabilities from their albedos at `wo`;
//! the density is the mixture's (one-sample MIS).

use super::dielectric::{half_vector, refract, RoughDielectric, SmoothDielectric};
use super::energy;
use super::fresnel;
use super::microfacet::{Microfacet, SMOOTH_ALPHA};
use super::{BsdfSample, FresnelModel, Transport};
use crate::math::sampling::cosine_hemisphere;
use crate::math::{Vec2, Vec3A};
use std::f32::consts::PI;

/// Index of refraction of glTF's clear coat.
pub const CLEARCOAT_IOR: f32 = 1.5;

/// The metallic-roughness BSDF at one shading point.
#[derive(Clone, Copy, Debug)]
pub struct Principled {
    /// Base colour: diffuse albedo, metal F0 and transmission tint.
    pub base: Vec3A,
    /// Metalness in [0, 1].
    pub metallic: f32,
    /// Transmitted fraction of the dielectric base.
    pub transmission: f32,
    /// Index of the dielectric part (inside / outside).
    pub eta: f32,
    /// Thin-walled transmission (no bending, no inside).
    pub thin: bool,
    /// The specular layer's microfacets; `None`: smooth.
    pub microfacet: Option<Microfacet>,
    /// Clear coat strength in [0, 1].
    pub clearcoat: f32,
    /// The coat's microfacets; `None`: smooth.
    pub coat_microfacet: Option<Microfacet>,
}

/// Sampling probabilities of the four strategies at one `wo`.
#[derive(Clone, Copy, Debug, Default)]
struct Strategies {
    coat: f32,
    specular: f32,
    transmission: f32,
    diffuse: f32,
}

impl Strategies {
    /// The strategy `uc` falls in, and `uc` rescaled within it.
    fn choose(&self, uc: f32) -> (usize, f32) {
        let p = [self.coat, self.specular, self.transmission, self.diffuse];
        let mut acc = 0.0;
        for (i, &pi) in p.iter().enumerate() {
            if pi > 0.0 && (uc < acc + pi || i == 3) {
                return (i, ((uc - acc) / pi).clamp(0.0, 1.0 - f32::EPSILON));
            }
            acc += pi;
        }
        // Rounding left `uc` beyond the sum: the last strategy with weight.
        let last = p.iter().rposition(|&x| x > 0.0).unwrap_or(3);
        (last, 1.0 - f32::EPSILON)
    }
}

fn mean(c: Vec3A) -> f32 {
    (c.x + c.y + c.z) / 3.0
}

/// Schlick's `F0 + (1 − F0)(1 − cos)^5` per channel (glTF's
/// `conductor_fresnel`).
#[inline]
fn schlick_rgb(f0: Vec3A, cos: f32) -> Vec3A {
    let m = (1.0 - cos.abs()).clamp(0.0, 1.0);
    let m5 = (m * m) * (m * m) * m;
    f0 + (Vec3A::ONE - f0) * m5
}

/// `D G / (4 |cos θo| |cos θi|)` of a reflection through the micro-normal
/// `wm`, and the density of sampling `wi` by reflecting `wo` about a
/// visible normal.
#[inline]
fn reflection_lobe(mf: &Microfacet, wo: Vec3A, wi: Vec3A, wm: Vec3A) -> (f32, f32) {
    let f = mf.d(wm) * mf.g_correlated(wi, wo, wm) / (4.0 * wo.z * wi.z).abs();
    let pdf = mf.pdf_normal(wo, wm) / (4.0 * wo.dot(wm).abs());
    (f, pdf)
}

/// Mirror image of `w` across the surface (thin-walled transmission).
#[inline]
fn through(w: Vec3A) -> Vec3A {
    Vec3A::new(w.x, w.y, -w.z)
}

impl Principled {
    /// Light inside a solid meets the bare dielectric interface.
    fn solid(&self) -> bool {
        !self.thin && self.transmission > 0.0
    }

    /// True when seen from `wo` the surface is the interior interface.
    fn inside(&self, wo: Vec3A) -> bool {
        self.solid() && wo.z < 0.0
    }

    fn dielectric_fresnel(&self, cos: f32) -> f32 {
        fresnel::dielectric(cos, self.eta).0
    }

    /// `1 − k F_k(n·v)`: what the clear coat lets through to the layers
    /// under it, and `k F_k(n·v)`, what it reflects.
    fn coat_split(&self, wo: Vec3A) -> (f32, f32) {
        if self.clearcoat <= 0.0 {
            return (1.0, 0.0);
        }
        let r = self.clearcoat * fresnel::dielectric(wo.z.abs(), CLEARCOAT_IOR).0;
        (1.0 - r, r)
    }

    /// The dielectric layer's compensation `k_d` at `μ` (1 when smooth).
    fn dielectric_compensation(&self, mu: f32) -> f32 {
        match &self.microfacet {
            Some(mf) if self.metallic < 1.0 => {
                energy::compensation(mf, mu, energy::dielectric_fresnel_average(self.eta))
            }
            _ => 1.0,
        }
    }

    /// The factors that scale the specular reflection seen from `μo`: the
    /// dielectric's `1 + (1 − t)(k_d − 1)` and the metal's `k_m` per channel.
    fn compensation(&self, mu_o: f32) -> (f32, Vec3A) {
        let Some(mf) = &self.microfacet else {
            return (1.0, Vec3A::ONE);
        };
        // One table lookup serves the dielectric and the metal's channels.
        let albedos = energy::Albedos::new(mf, mu_o);
        let k_d = match self.metallic < 1.0 {
            true => albedos.compensation(energy::dielectric_fresnel_average(self.eta)),
            false => 1.0,
        };
        let k_d = 1.0 + (1.0 - self.transmission) * (k_d - 1.0);
        let k_m = match self.metallic > 0.0 {
            true => {
                let f_avg = energy::schlick_fresnel_average(self.base);
                Vec3A::new(
                    albedos.compensation(f_avg.x),
                    albedos.compensation(f_avg.y),
                    albedos.compensation(f_avg.z),
                )
            }
            false => Vec3A::ONE,
        };
        (k_d, k_m)
    }

    /// `E_s(μ)`: the dielectric specular layer's directional albedo with
    /// its multiple scattering (the Fresnel reflectance when smooth).
    fn layer_albedo(&self, mu: f32) -> f32 {
        match &self.microfacet {
            None => self.dielectric_fresnel(mu),
            Some(mf) => (energy::dielectric_albedo(mf, mu, self.eta) * self.dielectric_compensation(mu)).min(1.0),
        }
    }

    fn strategies(&self, wo: Vec3A) -> Strategies {
        let (under, coat) = self.coat_split(wo);
        let f_d = self.dielectric_fresnel(wo.z);
        let dielectric = 1.0 - self.metallic;
        let base = mean(self.base);
        let (k_d, k_m) = self.compensation(wo.z);
        let specular = dielectric * f_d * k_d + self.metallic * mean(schlick_rgb(self.base, wo.z) * k_m);
        let diffuse = dielectric * (1.0 - self.transmission) * (1.0 - self.layer_albedo(wo.z)) * base;
        let mut s = Strategies {
            coat,
            specular: under * specular,
            transmission: under * dielectric * self.transmission * (1.0 - f_d) * base,
            diffuse: under * diffuse,
        };
        let total = s.coat + s.specular + s.transmission + s.diffuse;
        if total > 0.0 {
            s.coat /= total;
            s.specular /= total;
            s.transmission /= total;
            s.diffuse /= total;
        }
        s
    }

    /// The interior interface: the dielectric alone, tinted by the base.
    fn interface(&self) -> Result<SmoothDielectric, RoughDielectric> {
        match self.microfacet {
            None => Ok(SmoothDielectric {
                eta: self.eta,
                tint: self.base,
                fresnel: FresnelModel::Exact,
            }),
            Some(microfacet) => Err(RoughDielectric {
                eta: self.eta,
                tint: self.base,
                microfacet,
            }),
        }
    }

    /// The lobe kinds present: diffuse where the base shows, the specular
    /// layer and the coat (delta when smooth), transmission when any.
    pub(super) fn flags(&self) -> super::LobeFlags {
        use super::LobeFlags as F;
        let mut f = F::REFLECTION;
        if (1.0 - self.metallic) * (1.0 - self.transmission) * self.base.max_element() > 0.0 {
            f |= F::DIFFUSE;
        }
        // The specular layer (metal, dielectric reflection and transmission)
        // is a delta when smooth, else microfacets.
        f |= if self.microfacet.is_some() {
            F::GLOSSY
        } else if self.metallic > 0.0 || self.transmission > 0.0 {
            // Smooth metal or glass: the layer is the body's own reflection.
            F::SPECULAR | F::CASTS_CAUSTICS
        } else {
            // A smooth dielectric layer over the diffuse base: a coat.
            F::SPECULAR
        };
        if self.clearcoat > 0.0 {
            f |= if self.coat_microfacet.is_none() {
                F::SPECULAR
            } else {
                F::GLOSSY
            };
        }
        if self.transmission > 0.0 {
            f |= F::TRANSMISSION;
        }
        f
    }

    /// Probability that [`sample`](Self::sample) returns a delta direction.
    pub(super) fn delta_probability(&self, wo: Vec3A) -> f32 {
        if self.inside(wo) {
            return if self.microfacet.is_none() { 1.0 } else { 0.0 };
        }
        let s = self.strategies(wo);
        let mut p = 0.0;
        if self.coat_microfacet.is_none() {
            p += s.coat;
        }
        if self.microfacet.is_none() {
            p += s.specular + s.transmission;
        }
        p
    }

    pub(super) fn eval(&self, wo: Vec3A, wi: Vec3A, transport: Transport) -> Vec3A {
        if wo.z == 0.0 || wi.z == 0.0 {
            return Vec3A::ZERO;
        }
        if self.inside(wo) {
            return match self.interface() {
                Ok(_) => Vec3A::ZERO,
                Err(rough) => rough.eval(wo, wi, transport),
            };
        }
        if wo.z < 0.0 {
            return Vec3A::ZERO;
        }
        let (under, coat) = self.coat_split(wo);
        let dielectric = 1.0 - self.metallic;
        if wi.z > 0.0 {
            let wm = (wo + wi).normalize();
            // Albedo scaling, reciprocal: the base gets what the specular
            // layer reflects neither toward `wo` nor toward `wi`.
            let scaling = if dielectric * (1.0 - self.transmission) > 0.0 {
                1.0 - self.layer_albedo(wo.z).max(self.layer_albedo(wi.z))
            } else {
                0.0
            };
            let mut layers = self.base * (dielectric * (1.0 - self.transmission) * scaling / PI);
            if let Some(mf) = &self.microfacet {
                let (dg, _) = reflection_lobe(mf, wo, wi, wm);
                let f_d = self.dielectric_fresnel(wo.dot(wm));
                let (k_d, k_m) = self.compensation(wo.z);
                let f = Vec3A::splat(dielectric * f_d * k_d) + self.metallic * schlick_rgb(self.base, wo.dot(wm)) * k_m;
                layers += f * dg;
            }
            let mut out = layers * under;
            if let (Some(mf), true) = (&self.coat_microfacet, coat > 0.0) {
                out += Vec3A::splat(coat * reflection_lobe(mf, wo, wi, wm).0);
            }
            return out;
        }
        let Some(mf) = &self.microfacet else {
            return Vec3A::ZERO;
        };
        let weight = under * dielectric * self.transmission;
        if weight <= 0.0 {
            return Vec3A::ZERO;
        }
        if self.thin {
            let wr = through(wi);
            let wm = (wo + wr).normalize();
            let f_d = self.dielectric_fresnel(wo.dot(wm));
            return self.base * (weight * (1.0 - f_d) * reflection_lobe(mf, wo, wr, wm).0);
        }
        let rough = RoughDielectric {
            eta: self.eta,
            tint: self.base,
            microfacet: *mf,
        };
        rough.eval(wo, wi, transport) * weight
    }

    pub(super) fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z == 0.0 || wi.z == 0.0 {
            return 0.0;
        }
        if self.inside(wo) {
            return match self.interface() {
                Ok(_) => 0.0,
                Err(rough) => rough.pdf(wo, wi),
            };
        }
        if wo.z < 0.0 {
            return 0.0;
        }
        let s = self.strategies(wo);
        if wi.z > 0.0 {
            let wm = (wo + wi).normalize();
            let mut pdf = s.diffuse * wi.z / PI;
            if let Some(mf) = &self.microfacet {
                pdf += s.specular * reflection_lobe(mf, wo, wi, wm).1;
            }
            if let Some(mf) = &self.coat_microfacet {
                pdf += s.coat * reflection_lobe(mf, wo, wi, wm).1;
            }
            return pdf;
        }
        let Some(mf) = &self.microfacet else {
            return 0.0;
        };
        if self.thin {
            let wr = through(wi);
            let wm = (wo + wr).normalize();
            return s.transmission * reflection_lobe(mf, wo, wr, wm).1;
        }
        // The refraction's density alone: the strategy, not the Fresnel
        // split of the rough dielectric, chose to transmit.
        let Some((wm, etap, false)) = half_vector(wo, wi, self.eta) else {
            return 0.0;
        };
        let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2);
        s.transmission * mf.pdf_normal(wo, wm) * wi.dot(wm).abs() / denom
    }

    pub(super) fn sample(&self, wo: Vec3A, uc: f32, u: Vec2, transport: Transport) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        if self.inside(wo) {
            return match self.interface() {
                Ok(smooth) => smooth.sample(wo, uc, transport),
                Err(rough) => rough.sample(wo, uc, u, transport),
            };
        }
        if wo.z < 0.0 {
            return None;
        }
        let s = self.strategies(wo);
        let (strategy, _) = s.choose(uc);
        let (under, coat) = self.coat_split(wo);
        let dielectric = 1.0 - self.metallic;
        let wi = match strategy {
            0 => match &self.coat_microfacet {
                None => {
                    let wi = Vec3A::new(-wo.x, -wo.y, wo.z);
                    return Some(BsdfSample::specular(wi, Vec3A::splat(coat / wi.z), s.coat));
                }
                Some(mf) => reflect(wo, mf.sample_normal(wo, u))?,
            },
            1 => match &self.microfacet {
                None => {
                    let wi = Vec3A::new(-wo.x, -wo.y, wo.z);
                    let f = Vec3A::splat(dielectric * self.dielectric_fresnel(wo.z))
                        + self.metallic * schlick_rgb(self.base, wo.z);
                    return Some(BsdfSample::specular(wi, f * (under / wi.z), s.specular));
                }
                Some(mf) => reflect(wo, mf.sample_normal(wo, u))?,
            },
            2 => match &self.microfacet {
                None => {
                    let t = under * dielectric * self.transmission * (1.0 - self.dielectric_fresnel(wo.z));
                    let (wi, etap) = if self.thin {
                        (-wo, 1.0)
                    } else {
                        refract(wo, Vec3A::Z, self.eta)?
                    };
                    let mut f = self.base * (t / wi.z.abs());
                    if transport == Transport::Radiance {
                        f /= etap * etap;
                    }
                    let mut sample = BsdfSample::specular(wi, f, s.transmission);
                    sample.transmission = true;
                    sample.eta = etap;
                    return Some(sample);
                }
                Some(mf) => {
                    let wm = mf.sample_normal(wo, u);
                    if self.thin {
                        through(reflect(wo, wm)?)
                    } else {
                        let (wi, _) = refract(wo, wm, self.eta)?;
                        if wi.z >= 0.0 {
                            return None;
                        }
                        wi
                    }
                }
            },
            _ => cosine_hemisphere(u),
        };
        // Here `wo` is outside (wo.z > 0).
        let eta = if self.thin { 1.0 } else { self.eta };
        BsdfSample::scattered(wo, wi, self.pdf(wo, wi), || self.eval(wo, wi, transport), eta)
    }

    /// The delta reflection's weight from `wo` (what a mirror-like
    /// reflected ray carries), zero when the reflection lobes are rough.
    pub fn delta_reflectance(&self, wo: Vec3A) -> Vec3A {
        if wo.z <= 0.0 {
            return Vec3A::ZERO;
        }
        let (under, coat) = self.coat_split(wo);
        let mut r = Vec3A::ZERO;
        if self.microfacet.is_none() {
            r += under
                * (Vec3A::splat((1.0 - self.metallic) * self.dielectric_fresnel(wo.z))
                    + self.metallic * schlick_rgb(self.base, wo.z));
        }
        if self.coat_microfacet.is_none() {
            r += Vec3A::splat(coat);
        }
        r
    }
}

/// `wo` reflected about the micro-normal `wm`, when it stays above the surface.
#[inline]
fn reflect(wo: Vec3A, wm: Vec3A) -> Option<Vec3A> {
    let wi = 2.0 * wo.dot(wm) * wm - wo;
    (wi.z > 0.0).then_some(wi)
}

/// The microfacets of perceptual roughness `r` (`α = r²`), or `None` when
/// smooth.
pub fn microfacets(r: f32) -> Option<Microfacet> {
    let alpha = r * r;
    (alpha >= SMOOTH_ALPHA).then(|| Microfacet::ggx(alpha))
}
