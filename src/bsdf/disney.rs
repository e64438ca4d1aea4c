//! Burley's Disney BSDF as Mitsuba 3.9.1's `principled` plugin evaluates,
//! samples and weighs it (`src/bsdfs/principled.cpp` and
//! `principledhelpers.h`), formula for formula: a diffuse base with
//! retro-reflection, Hanrahan–Krueger fake subsurface and sheen; one GGX
//! lobe (visible normals) that reflects with a Fresnel term blending the
//! exact dielectric, a base-colour-tinted Schlick term and a Schlick metal,
//! and refracts the `spec_trans` part tinted by `sqrt(base colour)`; a GTR1
//! clear coat with Schlick's `F0 = 0.04` and a separable GGX masking of
//! `alpha = 0.25`, without the `1 / (4 cos θo cos θi)` of a microfacet lobe
//! (as in Burley's reference code).
//!
//! Mitsuba's `si.wi` is caustic's `wo` (toward the viewer) and Mitsuba's
//! `wo` is caustic's `wi`; Mitsuba's `eval` includes `|cos θ|` of the
//! light's direction, caustic's does not. The surface is one-sided like
//! Mitsuba's: from behind only the refracting part (`spec_trans`) scatters.

use super::fresnel;
use super::microfacet::Microfacet;
use super::{BsdfSample, Transport};
use crate::math::sampling::cosine_hemisphere;
use crate::math::{Vec2, Vec3A};
use crate::scene::Disney as DisneyParams;
use std::f32::consts::PI;

/// The Disney BSDF at one shading point: its base colour and parameters.
#[derive(Clone, Copy, Debug)]
pub struct Disney {
    /// The base colour.
    pub base: Vec3A,
    /// The parameters (weights, index, sampling rates).
    pub params: DisneyParams,
    /// The main specular lobe's GGX distribution.
    pub microfacet: Microfacet,
}

/// The lobes' weights and the probabilities of sampling them from one side.
struct Probabilities {
    diffuse: f32,
    clearcoat: f32,
    transmission: f32,
    reflection: f32,
}

impl Disney {
    /// The lobe of `params` over `base`; its GGX roughness from
    /// `calc_dist_params` (Burley 2012, addendum B.2).
    pub fn new(base: Vec3A, params: DisneyParams) -> Self {
        let r2 = params.roughness * params.roughness;
        let aspect = (1.0 - 0.9 * params.anisotropic).sqrt();
        let microfacet = Microfacet {
            alpha: (r2 / aspect).max(0.001),
            alpha_y: (r2 * aspect).max(0.001),
            ..Microfacet::ggx(0.001)
        };
        Self {
            base,
            params,
            microfacet,
        }
    }

    /// The lobe kinds present: the diffuse base, sheen and retro-reflection,
    /// the glossy specular and clear-coat lobes (roughness is clamped to
    /// α ≥ 0.001, never a delta), and refraction when `spec_trans > 0`.
    pub(super) fn flags(&self) -> super::LobeFlags {
        use super::LobeFlags as F;
        let f = F::DIFFUSE | F::GLOSSY | F::REFLECTION;
        if self.params.spec_trans > 0.0 {
            f | F::TRANSMISSION
        } else {
            f
        }
    }

    /// Weight of the diffuse base, `(1 − metallic)(1 − spec_trans)`.
    fn brdf_weight(&self) -> f32 {
        (1.0 - self.params.metallic) * (1.0 - self.params.spec_trans)
    }

    /// Weight of the refraction, `(1 − metallic) spec_trans`.
    fn bsdf_weight(&self) -> f32 {
        (1.0 - self.params.metallic) * self.params.spec_trans
    }

    /// The normalised probabilities of each lobe, with `f` the dielectric
    /// reflectance at the microfacet (Mitsuba's `prob_*`): from inside only
    /// reflection and refraction, in the dielectric's proportions.
    fn probabilities(&self, front: bool, f: f32) -> Probabilities {
        let p = &self.params;
        let (brdf, bsdf) = (self.brdf_weight(), self.bsdf_weight());
        let (reflection, transmission, clearcoat, diffuse) = if front {
            (
                p.specular_sampling_rate * (1.0 - bsdf * (1.0 - f)),
                p.specular_sampling_rate * bsdf * (1.0 - f),
                0.25 * p.clearcoat * p.clearcoat_sampling_rate,
                brdf * p.diffuse_sampling_rate,
            )
        } else {
            (f, 1.0 - f, 0.0, 0.0)
        };
        let total = reflection + transmission + clearcoat + diffuse;
        Probabilities {
            diffuse: diffuse / total,
            clearcoat: clearcoat / total,
            transmission: transmission / total,
            reflection: reflection / total,
        }
    }

    /// The half vector of `wo` and `wi` (generalised for refraction),
    /// turned outward, and the index ratio along the path.
    fn half_vector(&self, wo: Vec3A, wi: Vec3A) -> (Vec3A, f32) {
        let eta_path = if wo.z > 0.0 {
            self.params.eta
        } else {
            1.0 / self.params.eta
        };
        let reflect = wo.z * wi.z > 0.0;
        let wh = (wo + wi * if reflect { 1.0 } else { eta_path }).normalize();
        (if wh.z < 0.0 { -wh } else { wh }, eta_path)
    }

    pub(super) fn eval(&self, wo: Vec3A, wi: Vec3A, transport: Transport) -> Vec3A {
        let (cos_i, cos_o) = (wo.z, wi.z);
        if cos_i == 0.0 || cos_o == 0.0 {
            return Vec3A::ZERO;
        }
        let p = &self.params;
        let (brdf, bsdf) = (self.brdf_weight(), self.bsdf_weight());
        let reflect = cos_i * cos_o > 0.0;
        let refract = cos_i * cos_o < 0.0;
        let front = cos_i > 0.0;
        let (wh, eta_path) = self.half_vector(wo, wi);
        let f_dielectric = fresnel::dielectric(wo.dot(wh), p.eta).0;
        let reflection_compatible = compatible(wh, wo, wi, cos_i, true);
        let refraction_compatible = compatible(wh, wo, wi, cos_i, false);
        let d = self.microfacet.d(wh);
        let g = self.microfacet.g(wo, wi, wh);
        // Mitsuba's value, which includes |cos θ| of the light's direction.
        let mut value = Vec3A::ZERO;
        if reflect && reflection_compatible && f_dielectric > 0.0 {
            let f = self.principled_fresnel(f_dielectric, wo.dot(wh), front);
            value += f * (d * g / (4.0 * cos_i.abs()));
        }
        if bsdf > 0.0 && refract && refraction_compatible && f_dielectric < 1.0 {
            // Solid-angle compression for radiance (Veach 1997, §5.2).
            let scale = match transport {
                Transport::Radiance => 1.0 / (eta_path * eta_path),
                Transport::Importance => 1.0,
            };
            let (dot_o, dot_i) = (wo.dot(wh), wi.dot(wh));
            let t = scale * (1.0 - f_dielectric) * d * g * eta_path * eta_path * dot_o * dot_i
                / (cos_i * (dot_o + eta_path * dot_i).powi(2));
            value += sqrt3(self.base) * (bsdf * t.abs());
        }
        if p.clearcoat > 0.0 && reflect && reflection_compatible && front {
            let f_cc = schlick(Vec3A::splat(0.04), wo.dot(wh), p.eta).x;
            let d_cc = gtr1_d(clearcoat_alpha(p.clearcoat_gloss), wh);
            let g_cc = smith_ggx1(wo, wh, 0.25) * smith_ggx1(wi, wh, 0.25);
            value += Vec3A::splat(p.clearcoat * 0.25 * f_cc * d_cc * g_cc * cos_o.abs());
        }
        if brdf > 0.0 && reflect && front {
            let (fo, fi) = (schlick_weight(cos_o.abs()), schlick_weight(cos_i.abs()));
            let f_diff = (1.0 - 0.5 * fi) * (1.0 - 0.5 * fo);
            let cos_d = wh.dot(wi);
            let rr = 2.0 * p.roughness * cos_d * cos_d;
            let f_retro = rr * (fo + fi + fo * fi * (rr - 1.0));
            let fss90 = rr / 2.0;
            let fss = lerp(1.0, fss90, fo) * lerp(1.0, fss90, fi);
            let f_ss = 1.25 * (fss * (1.0 / (cos_o.abs() + cos_i.abs()) - 0.5) + 0.5);
            let diffuse = lerp(f_diff + f_retro, f_ss, p.flatness);
            value += self.base * (brdf * cos_o.abs() / PI * diffuse);
            // Mitsuba's scalar variants add the sheen only where the diffuse
            // base is active (it is nested in that branch).
            if p.sheen > 0.0 && 1.0 - p.metallic > 0.0 {
                let fd = schlick_weight(cos_d.abs());
                let tint = self.tint();
                let c_sheen = Vec3A::ONE + (tint - Vec3A::ONE) * p.sheen_tint;
                value += c_sheen * (p.sheen * (1.0 - p.metallic) * fd * cos_o.abs());
            }
        }
        value / cos_o.abs()
    }

    pub(super) fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        let (cos_i, cos_o) = (wo.z, wi.z);
        let front = cos_i > 0.0;
        // From behind without refraction `sample` gives nothing (Mitsuba's
        // `pdf` would still answer there, for a BSDF value of 0).
        if cos_i == 0.0 || (!front && self.bsdf_weight() <= 0.0) {
            return 0.0;
        }
        let reflect = cos_i * cos_o > 0.0;
        let refract = cos_i * cos_o < 0.0;
        let (wh, eta_path) = self.half_vector(wo, wi);
        let f = fresnel::dielectric(wo.dot(wh), self.params.eta).0;
        let prob = self.probabilities(front, f);
        let (dot_o, dot_i) = (wo.dot(wh), wi.dot(wh));
        let dwh_dwi = if reflect {
            1.0 / (4.0 * dot_i)
        } else {
            eta_path * eta_path * dot_i / (dot_o + eta_path * dot_i).powi(2)
        }
        .abs();
        let wo_up = if front { wo } else { -wo };
        let mut pdf = 0.0;
        if reflect && compatible(wh, wo, wi, cos_i, true) {
            pdf += prob.reflection * self.microfacet.pdf_normal(wo_up, wh) * dwh_dwi;
            if self.params.clearcoat > 0.0 {
                pdf += prob.clearcoat * gtr1_pdf(clearcoat_alpha(self.params.clearcoat_gloss), wh) * dwh_dwi;
            }
        }
        if reflect {
            pdf += prob.diffuse * cos_o / PI;
        }
        if refract && compatible(wh, wo, wi, cos_i, false) {
            pdf += prob.transmission * self.microfacet.pdf_normal(wo_up, wh) * dwh_dwi;
        }
        pdf
    }

    pub(super) fn sample(&self, wo: Vec3A, uc: f32, u: Vec2, transport: Transport) -> Option<BsdfSample> {
        let cos_i = wo.z;
        let front = cos_i > 0.0;
        if cos_i == 0.0 || (!front && self.bsdf_weight() <= 0.0) {
            return None;
        }
        let wo_up = if front { wo } else { -wo };
        let m = self.microfacet.sample_normal(wo_up, u);
        let (f, cos_t) = fresnel::dielectric(wo.dot(m), self.params.eta);
        let prob = self.probabilities(front, f);
        let (wi, compatible_and_sided) = if uc < prob.diffuse {
            let wi = cosine_hemisphere(u);
            (wi, cos_i * wi.z > 0.0)
        } else if uc < prob.diffuse + prob.clearcoat {
            let m_cc = gtr1_sample(clearcoat_alpha(self.params.clearcoat_gloss), u);
            let wi = 2.0 * wo.dot(m_cc) * m_cc - wo;
            (wi, cos_i * wi.z > 0.0 && compatible(m_cc, wo, wi, cos_i, true))
        } else if uc < prob.diffuse + prob.clearcoat + prob.transmission {
            // Mitsuba's `refract(wi, m, cos θt, η_ti)`.
            let eta_ti = if wo.dot(m) >= 0.0 {
                1.0 / self.params.eta
            } else {
                self.params.eta
            };
            let wi = m * (wo.dot(m) * eta_ti + cos_t) - wo * eta_ti;
            (wi, cos_i * wi.z < 0.0 && compatible(m, wo, wi, cos_i, false))
        } else {
            let wi = 2.0 * wo.dot(m) * m - wo;
            (wi, cos_i * wi.z > 0.0 && compatible(m, wo, wi, cos_i, true))
        };
        if !compatible_and_sided {
            return None;
        }
        let eta = if front { self.params.eta } else { 1.0 / self.params.eta };
        BsdfSample::scattered(wo, wi, self.pdf(wo, wi), || self.eval(wo, wi, transport), eta)
    }

    /// The base colour over its luminance (white when black).
    fn tint(&self) -> Vec3A {
        let lum = luminance(self.base);
        if lum > 0.0 {
            self.base / lum
        } else {
            Vec3A::ONE
        }
    }

    /// `principled_fresnel`: the dielectric's reflectance mixed with a
    /// Schlick metal of `F0` = base colour and, for `spec_tint`, a Schlick
    /// dielectric tinted toward the base colour; from inside the plain
    /// dielectric, weighted by the refracting part.
    fn principled_fresnel(&self, f_dielectric: f32, cos: f32, front: bool) -> Vec3A {
        let p = &self.params;
        if !front {
            return Vec3A::splat(self.bsdf_weight() * f_dielectric);
        }
        let eta_it = if cos >= 0.0 { p.eta } else { 1.0 / p.eta };
        let mut f_schlick = p.metallic * schlick(self.base, cos, p.eta);
        if p.spec_tint > 0.0 {
            let r0 = ((eta_it - 1.0) / (eta_it + 1.0)).powi(2);
            f_schlick += (1.0 - p.metallic) * p.spec_tint * schlick(self.tint() * r0, cos, p.eta);
        }
        Vec3A::splat((1.0 - p.metallic) * (1.0 - p.spec_tint) * f_dielectric) + f_schlick
    }
}

/// Mitsuba's `luminance` of linear sRGB (Rec. 709 weights).
pub(super) fn luminance(c: Vec3A) -> f32 {
    0.212671 * c.x + 0.715160 * c.y + 0.072169 * c.z
}

fn sqrt3(c: Vec3A) -> Vec3A {
    Vec3A::new(c.x.sqrt(), c.y.sqrt(), c.z.sqrt())
}

/// Dr.Jit's `lerp(a, b, t)`.
pub(super) fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + (b - a) * t
}

/// `(1 − cos)^5`, clamped (`schlick_weight`).
pub(super) fn schlick_weight(cos: f32) -> f32 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    m * m * m * m * m
}

/// `calc_schlick`: `R0 + (1 − R0)(1 − c)^5` with `c` the cosine on the
/// less dense side of an interface of index `eta` (the transmitted one from
/// the denser side).
pub(super) fn schlick(r0: Vec3A, cos: f32, eta: f32) -> Vec3A {
    let eta_it = if cos >= 0.0 { eta } else { 1.0 / eta };
    let eta_ti = 1.0 / eta_it;
    let cos_t = (1.0 - (1.0 - cos * cos) * eta_ti * eta_ti).max(0.0).sqrt();
    let w = if eta_it > 1.0 {
        schlick_weight(cos.abs())
    } else {
        schlick_weight(cos_t)
    };
    Vec3A::splat(w) * (Vec3A::ONE - r0) + r0
}

/// `mac_mic_compatibility`: `wo` and `wi` on the sides of the microfacet `m`
/// (turned toward `wo`'s side of the surface) that reflection or
/// refraction requires.
pub(super) fn compatible(m: Vec3A, wo: Vec3A, wi: Vec3A, cos_i: f32, reflection: bool) -> bool {
    let m = if cos_i < 0.0 { -m } else { m };
    let wi_side = if reflection { wi.dot(m) } else { -wi.dot(m) };
    wo.dot(m) > 0.0 && wi_side > 0.0
}

/// The clear coat's GTR1 `alpha`: `lerp(0.1, 0.001, gloss)`.
fn clearcoat_alpha(gloss: f32) -> f32 {
    lerp(0.1, 0.001, gloss)
}

/// Burley's GTR1 (`GTR1Isotropic::eval`): `(α² − 1) / (π ln α² (1 + (α² − 1) cos² θ))`.
fn gtr1_d(alpha: f32, m: Vec3A) -> f32 {
    let a2 = alpha * alpha;
    let d = (a2 - 1.0) / (PI * a2.ln() * (1.0 + (a2 - 1.0) * m.z * m.z));
    if d * m.z > 1.0e-20 {
        d
    } else {
        0.0
    }
}

/// Density of [`gtr1_sample`]'s normals: `D(m) cos θm`.
fn gtr1_pdf(alpha: f32, m: Vec3A) -> f32 {
    if m.z < 0.0 {
        0.0
    } else {
        m.z * gtr1_d(alpha, m)
    }
}

/// A GTR1 normal (`GTR1Isotropic::sample`, not restricted to visible ones).
fn gtr1_sample(alpha: f32, u: Vec2) -> Vec3A {
    let (sin_phi, cos_phi) = (2.0 * PI * u.x).sin_cos();
    let a2 = alpha * alpha;
    let cos2 = (1.0 - a2.powf(1.0 - u.y)) / (1.0 - a2);
    let sin = (1.0 - cos2).max(0.0).sqrt();
    let cos = cos2.max(0.0).sqrt();
    Vec3A::new(cos_phi * sin, sin_phi * sin, cos)
}

/// `smith_ggx1`: GGX masking of roughness `alpha` for the clear coat.
fn smith_ggx1(v: Vec3A, m: Vec3A, alpha: f32) -> f32 {
    if v.dot(m) * v.z <= 0.0 {
        return 0.0;
    }
    if v.z == 1.0 {
        return 1.0;
    }
    let cos2 = v.z * v.z;
    let tan2 = (1.0 - cos2) / cos2;
    2.0 / (1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn direction(theta: f32, phi: f32) -> Vec3A {
        Vec3A::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
    }

    /// Values of Mitsuba 3.9.1's `principled` (scalar_rgb), `eval` (which
    /// includes `|cos θ|` of the light's direction) and `pdf`, printed by
    /// ```text
    /// import mitsuba as mi, math
    /// mi.set_variant("scalar_rgb")
    /// b = mi.load_dict({"type": "principled", ...the set's parameters...})
    /// d = lambda t, p: mi.Vector3f(math.sin(t)*math.cos(p), math.sin(t)*math.sin(p), math.cos(t))
    /// si = mi.SurfaceInteraction3f(); si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    /// si.wi = d(θv, φv); wo = d(θl, φl)
    /// print(b.eval(mi.BSDFContext(), si, wo), b.pdf(mi.BSDFContext(), si, wo))
    /// ```
    /// with sets `a`: base_color (0.8, 0.4, 0.1), roughness 0.4, metallic
    /// 0.3, specular 0.6, spec_tint 0.4, sheen 0.7, sheen_tint 0.5,
    /// clearcoat 0.8, clearcoat_gloss 0.6, flatness 0.3; `b`: base_color
    /// (0.3, 0.6, 0.8), roughness 0.3, anisotropic 0.6, spec_trans 0.7, eta
    /// 1.45, metallic 0.2, clearcoat 0.5, sheen 0.3; `c`: base_color
    /// (0.5, 0.7, 0.2), the rest Mitsuba's defaults; rounded to 6 digits.
    #[test]
    fn disney_agrees_with_mitsuba() {
        let specular = |s: f32| 2.0 / (1.0 - (0.08 * s).sqrt()) - 1.0;
        let set = |name: &str| match name {
            "a" => Disney::new(
                Vec3A::new(0.8, 0.4, 0.1),
                DisneyParams {
                    roughness: 0.4,
                    metallic: 0.3,
                    eta: specular(0.6),
                    spec_tint: 0.4,
                    sheen: 0.7,
                    sheen_tint: 0.5,
                    clearcoat: 0.8,
                    clearcoat_gloss: 0.6,
                    flatness: 0.3,
                    ..DisneyParams::default()
                },
            ),
            "b" => Disney::new(
                Vec3A::new(0.3, 0.6, 0.8),
                DisneyParams {
                    roughness: 0.3,
                    anisotropic: 0.6,
                    spec_trans: 0.7,
                    eta: 1.45,
                    metallic: 0.2,
                    clearcoat: 0.5,
                    sheen: 0.3,
                    ..DisneyParams::default()
                },
            ),
            _ => Disney::new(Vec3A::new(0.5, 0.7, 0.2), DisneyParams::default()),
        };
        // (set, [θv, φv, θl, φl], Mitsuba's eval, Mitsuba's pdf)
        type Case = (&'static str, [f32; 4], [f32; 3], f32);
        #[rustfmt::skip]
        let cases: [Case; 16] = [
            ("a", [0.3, 0.2, 0.5, 2.0], [2.14885e-01, 1.12309e-01, 3.53772e-02], 2.48944e-01),
            ("a", [0.7, 0.0, 0.7, 3.1], [1.40997e+00, 8.27907e-01, 3.91363e-01], 3.04299e+00),
            ("a", [1.2, 1.0, 0.2, 4.0], [1.95994e-01, 9.98538e-02, 2.77488e-02], 1.66590e-01),
            ("a", [0.1, 0.0, 0.15, 3.0], [1.16338e+00, 6.95061e-01, 3.43823e-01], 2.23582e+00),
            ("a", [0.9, 0.5, 1.3, 3.5], [2.10515e-01, 1.25749e-01, 6.21754e-02], 3.39567e-01),
            ("a", [0.5, 5.0, 0.6, 1.9], [1.03698e+00, 5.86765e-01, 2.49105e-01], 1.98655e+00),
            ("b", [0.3, 0.2, 0.5, 2.0], [2.62960e-02, 4.80748e-02, 6.25939e-02], 7.85085e-02),
            ("b", [0.6, 0.4, 0.65, 3.3], [1.79947e-01, 2.96583e-01, 3.74340e-01], 7.05716e-01),
            ("b", [0.4, 0.0, 2.6, 3.0], [2.48423e-02, 3.51323e-02, 4.05673e-02], 6.99703e-02),
            ("b", [0.8, 1.0, 2.9, 4.5], [2.77073e-03, 3.91841e-03, 4.52459e-03], 7.79231e-03),
            ("b", [2.6, 0.3, 2.4, 3.5], [1.10484e-01, 1.10484e-01, 1.10484e-01], 1.97949e-01),
            ("b", [2.7, 1.0, 0.5, 4.0], [1.12411e-01, 1.58973e-01, 1.83567e-01], 1.74436e-01),
            ("b", [2.8, 0.2, 0.3, 3.0], [1.00498e-01, 1.42125e-01, 1.64112e-01], 1.55902e-01),
            ("c", [0.3, 0.2, 0.5, 2.0], [1.52340e-01, 2.08210e-01, 6.85365e-02], 2.98046e-01),
            ("c", [1.0, 0.0, 1.0, 3.0], [2.06094e-01, 2.40203e-01, 1.54931e-01], 9.02539e-01),
            ("c", [1.4, 2.0, 0.3, 0.5], [1.61411e-01, 2.24421e-01, 6.68945e-02], 1.94742e-01),
        ];
        let close = |a: f32, b: f32| (a - b).abs() <= 5e-3 * b.abs();
        for (name, [tv, pv, tl, pl], eval, pdf) in cases {
            let lobe = set(name);
            let (wo, wi) = (direction(tv, pv), direction(tl, pl));
            let f = lobe.eval(wo, wi, Transport::Radiance) * wi.z.abs();
            let p = lobe.pdf(wo, wi);
            let expected = Vec3A::from_array(eval);
            assert!(
                close(f.x, expected.x) && close(f.y, expected.y) && close(f.z, expected.z),
                "{name} {:?}: eval {f} against Mitsuba's {expected}",
                [tv, pv, tl, pl]
            );
            assert!(
                close(p, pdf),
                "{name} {:?}: pdf {p} against Mitsuba's {pdf}",
                [tv, pv, tl, pl]
            );
        }
    }
}
