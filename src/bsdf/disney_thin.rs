//! Mitsuba 3.9.1's thin principled BSDF (`principledthin`,
//! `src/bsdfs/principledthin.cpp`), formula for formula: Burley's Disney
//! model for a sheet with no interior (Burley 2015, "Extending the Disney
//! BRDF to a BSDF with Integrated Subsurface Scattering", §5). The
//! `spec_trans` part is a GGX reflection with a Fresnel term blending the
//! exact dielectric and a base-colour-tinted Schlick term (`spec_tint`),
//! plus a transmission that reflects about a microfacet of a roughness
//! scaled by `0.65 η − 0.35` (Burley 2015, figure 15) and continues on the
//! other side without bending, tinted by the base colour and weighted by
//! `1 − F`; the rest is the diffuse base with retro-reflection, fake
//! subsurface (`flatness`) and sheen, of which `diff_trans / 2` is
//! transmitted as a Lambertian lobe. Both sides scatter alike (the
//! directions are turned so that the viewer is above the sheet).
//!
//! Mitsuba's `si.wi` is caustic's `wo` (toward the viewer) and Mitsuba's
//! `wo` is caustic's `wi`; Mitsuba's `eval` includes `|cos θ|` of the
//! light's direction, caustic's does not.

use super::disney::{compatible, lerp, luminance, schlick, schlick_weight};
use super::fresnel;
use super::microfacet::Microfacet;
use super::BsdfSample;
use crate::math::sampling::cosine_hemisphere;
use crate::math::{Vec2, Vec3A};
use crate::scene::Disney as DisneyParams;
use std::f32::consts::PI;

/// The thin Disney BSDF at one shading point.
#[derive(Clone, Copy, Debug)]
pub struct DisneyThin {
    /// The base colour.
    pub base: Vec3A,
    /// The parameters (`thin` set; `diff_trans` in [0, 2]).
    pub params: DisneyParams,
    /// The specular reflection's GGX distribution.
    pub microfacet: Microfacet,
    /// The specular transmission's GGX distribution (roughness scaled by
    /// `0.65 η − 0.35`).
    pub transmission: Microfacet,
}

/// The probabilities of sampling each lobe, normalised.
struct Probabilities {
    specular_reflection: f32,
    specular_transmission: f32,
    diffuse_reflection: f32,
    diffuse_transmission: f32,
}

/// `calc_dist_params`: GGX `alpha` along and across `∂p/∂u` from Burley's
/// roughness and anisotropy (Burley 2012, addendum B.2).
fn distribution(roughness: f32, anisotropic: f32) -> Microfacet {
    let r2 = roughness * roughness;
    let aspect = (1.0 - 0.9 * anisotropic).sqrt();
    Microfacet {
        alpha: (r2 / aspect).max(0.001),
        alpha_y: (r2 * aspect).max(0.001),
        ..Microfacet::ggx(0.001)
    }
}

/// Mitsuba's `mulsign(v, s)`: `v` turned to the side of the sign of `s`.
fn mulsign(v: Vec3A, s: f32) -> Vec3A {
    if s < 0.0 {
        -v
    } else {
        v
    }
}

impl DisneyThin {
    /// The lobe of `params` over `base`.
    pub fn new(base: Vec3A, params: DisneyParams) -> Self {
        let scaled = (0.65 * params.eta - 0.35) * params.roughness;
        Self {
            base,
            params,
            microfacet: distribution(params.roughness, params.anisotropic),
            transmission: distribution(scaled, params.anisotropic),
        }
    }

    /// Has a roughness that differs along and across `∂p/∂u`.
    pub fn is_anisotropic(&self) -> bool {
        self.microfacet.is_anisotropic() || self.transmission.is_anisotropic()
    }

    /// Diffuse (and sheen) and glossy reflection, and transmission through
    /// the sheet when `spec_trans` or `diff_trans` is above 0 (the
    /// roughnesses are clamped to α ≥ 0.001: never a delta).
    pub(super) fn flags(&self) -> super::LobeFlags {
        use super::LobeFlags as F;
        let f = F::DIFFUSE | F::GLOSSY | F::REFLECTION;
        if self.params.spec_trans > 0.0 || self.params.diff_trans > 0.0 {
            f | F::TRANSMISSION
        } else {
            f
        }
    }

    /// `diff_trans` on Mitsuba's internal scale, [0, 1].
    fn diff_trans(&self) -> f32 {
        self.params.diff_trans / 2.0
    }

    /// The lobes' sampling probabilities (Mitsuba's `prob_*`).
    fn probabilities(&self) -> Probabilities {
        let p = &self.params;
        let (st, dt) = (p.spec_trans, self.diff_trans());
        let sr = st * p.specular_sampling_rate / 2.0;
        let stp = st * p.specular_transmission_sampling_rate / 2.0;
        let dr = p.diffuse_sampling_rate * (1.0 - st) * (1.0 - dt);
        let dtp = p.diffuse_transmission_sampling_rate * (1.0 - st) * dt;
        let total = sr + stp + dr + dtp;
        if total <= 0.0 {
            return Probabilities {
                specular_reflection: 0.0,
                specular_transmission: 0.0,
                diffuse_reflection: 0.0,
                diffuse_transmission: 0.0,
            };
        }
        Probabilities {
            specular_reflection: sr / total,
            specular_transmission: stp / total,
            diffuse_reflection: dr / total,
            diffuse_transmission: dtp / total,
        }
    }

    /// The half vector of `wo` (above the sheet) and `wi` mirrored above it.
    fn half_vector(wo: Vec3A, wi: Vec3A) -> Vec3A {
        (wo + Vec3A::new(wi.x, wi.y, wi.z.abs())).normalize()
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

    /// `thin_fresnel`: the dielectric's reflectance blended by `spec_tint`
    /// toward a Schlick term of `F0` = tint × `((η − 1)/(η + 1))²`.
    fn fresnel(&self, f_dielectric: f32, cos: f32) -> Vec3A {
        let p = &self.params;
        let f_schlick = if p.spec_tint != 0.0 {
            let r0 = ((p.eta - 1.0) / (p.eta + 1.0)).powi(2);
            schlick(self.tint() * r0, cos, p.eta)
        } else {
            Vec3A::ZERO
        };
        Vec3A::splat(f_dielectric) + (f_schlick - Vec3A::splat(f_dielectric)) * p.spec_tint
    }

    pub(super) fn eval(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        let sign = wo.z;
        if sign == 0.0 || wi.z == 0.0 {
            return Vec3A::ZERO;
        }
        let p = &self.params;
        // The sheet scatters alike from both sides: the viewer above it.
        let (wo, wi) = (mulsign(wo, sign), mulsign(wi, sign));
        let (cos_i, cos_o) = (wo.z, wi.z);
        let reflect = cos_o > 0.0;
        let (st, dt) = (p.spec_trans, self.diff_trans());
        let wh = Self::half_vector(wo, wi);
        let mut value = Vec3A::ZERO;
        if st > 0.0 {
            let f_dielectric = fresnel::dielectric(wo.dot(wh), p.eta).0;
            if reflect && compatible(wh, wo, wi, cos_i, true) {
                let f = self.fresnel(f_dielectric, wo.dot(wh));
                let dg = self.microfacet.d(wh) * self.microfacet.g(wo, wi, wh);
                value += f * (st * dg / (4.0 * cos_i));
            }
            if !reflect && compatible(wh, wo, wi, cos_i, false) {
                let dg = self.transmission.d(wh) * self.transmission.g(wo, wi, wh);
                value += self.base * (st * (1.0 - f_dielectric) * dg / (4.0 * cos_i));
            }
        }
        if reflect && st < 1.0 && dt < 1.0 {
            let (fo, fi) = (schlick_weight(cos_o.abs()), schlick_weight(cos_i));
            let f_diff = (1.0 - 0.5 * fi) * (1.0 - 0.5 * fo);
            let cos_d = wh.dot(wi);
            let rr = 2.0 * p.roughness * cos_d * cos_d;
            let f_retro = rr * (fo + fi + fo * fi * (rr - 1.0));
            let fss90 = rr / 2.0;
            let fss = lerp(1.0, fss90, fo) * lerp(1.0, fss90, fi);
            let f_ss = 1.25 * (fss * (1.0 / (cos_o.abs() + cos_i.abs()) - 0.5) + 0.5);
            let diffuse = lerp(f_diff + f_retro, f_ss, p.flatness);
            value += self.base * ((1.0 - st) * cos_o / PI * (1.0 - dt) * diffuse);
            if p.sheen > 0.0 {
                let fd = schlick_weight(cos_d.abs());
                let c_sheen = Vec3A::ONE + (self.tint() - Vec3A::ONE) * p.sheen_tint;
                value += c_sheen * (p.sheen * (1.0 - st) * fd * (1.0 - dt) * cos_o.abs());
            }
        }
        if !reflect && st < 1.0 && dt > 0.0 {
            value += self.base * ((1.0 - st) * dt / PI * cos_o.abs());
        }
        value / cos_o.abs()
    }

    pub(super) fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        let sign = wo.z;
        if sign == 0.0 {
            return 0.0;
        }
        let (wo, wi) = (mulsign(wo, sign), mulsign(wi, sign));
        let cos_o = wi.z;
        let (reflect, refract) = (cos_o > 0.0, cos_o < 0.0);
        let prob = self.probabilities();
        let mut pdf = 0.0;
        if self.params.spec_trans > 0.0 {
            let wh = Self::half_vector(wo, wi);
            let wi_up = Vec3A::new(wi.x, wi.y, wi.z.abs());
            let dwh_dwi = (1.0 / (4.0 * wi_up.dot(wh))).abs();
            if reflect && compatible(wh, wo, wi, wo.z, true) {
                pdf += prob.specular_reflection * self.microfacet.pdf_normal(wo, wh) * dwh_dwi;
            }
            if refract && compatible(wh, wo, wi, wo.z, false) {
                pdf += prob.specular_transmission * self.transmission.pdf_normal(wo, wh) * dwh_dwi;
            }
        }
        if reflect {
            pdf += prob.diffuse_reflection * cos_o / PI;
        }
        if refract {
            pdf += prob.diffuse_transmission * -cos_o / PI;
        }
        pdf
    }

    pub(super) fn sample(&self, wo: Vec3A, uc: f32, u: Vec2) -> Option<BsdfSample> {
        let sign = wo.z;
        if sign == 0.0 {
            return None;
        }
        let up = mulsign(wo, sign);
        let prob = self.probabilities();
        let reflect = |m: Vec3A| 2.0 * up.dot(m) * m - up;
        let transmission_from = prob.specular_reflection;
        let diffuse_from = transmission_from + prob.specular_transmission;
        let wi = if uc < transmission_from {
            let m = self.microfacet.sample_normal(up, u);
            let wi = reflect(m);
            (wi.z > 0.0 && compatible(m, up, wi, up.z, true)).then_some(wi)
        } else if uc < diffuse_from {
            // Reflected about the microfacet, then through the sheet.
            let m = self.transmission.sample_normal(up, u);
            let r = reflect(m);
            let wi = Vec3A::new(r.x, r.y, -r.z);
            (wi.z < 0.0 && compatible(m, up, wi, up.z, false)).then_some(wi)
        } else if uc < diffuse_from + prob.diffuse_reflection {
            Some(cosine_hemisphere(u))
        } else if prob.diffuse_transmission > 0.0 {
            Some(-cosine_hemisphere(u))
        } else {
            None
        }?;
        let wi = mulsign(wi, sign);
        BsdfSample::scattered(wo, wi, self.pdf(wo, wi), || self.eval(wo, wi), 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn direction(theta: f32, phi: f32) -> Vec3A {
        Vec3A::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
    }

    /// Values of Mitsuba 3.9.1's `principledthin` (scalar_rgb), `eval`
    /// (which includes `|cos θ|` of the light's direction) and `pdf`,
    /// printed as for `disney::tests::disney_agrees_with_mitsuba` with
    /// sets `a`: base_color (0.7, 0.1, 0.1), roughness 0.3, anisotropic
    /// 0.5, spec_trans 0.6, diff_trans 0.8, eta 1.33, sheen 0.5, sheen_tint
    /// 0.4, flatness 0.3, spec_tint 0.2; `b`: base_color (0.3, 0.6, 0.8),
    /// roughness 0.6, spec_trans 0.9, eta 1.5; `c`: base_color
    /// (0.5, 0.7, 0.2), the rest Mitsuba's defaults; rounded to 6 digits.
    /// Directions below the sheet (θ > π/2) cover the back side and the
    /// transmission.
    #[test]
    fn thin_disney_agrees_with_mitsuba() {
        let set = |name: &str| match name {
            "a" => DisneyThin::new(
                Vec3A::new(0.7, 0.1, 0.1),
                DisneyParams {
                    roughness: 0.3,
                    anisotropic: 0.5,
                    spec_trans: 0.6,
                    diff_trans: 0.8,
                    eta: 1.33,
                    sheen: 0.5,
                    sheen_tint: 0.4,
                    flatness: 0.3,
                    spec_tint: 0.2,
                    ..DisneyParams::thin_default()
                },
            ),
            "b" => DisneyThin::new(
                Vec3A::new(0.3, 0.6, 0.8),
                DisneyParams {
                    roughness: 0.6,
                    spec_trans: 0.9,
                    eta: 1.5,
                    ..DisneyParams::thin_default()
                },
            ),
            _ => DisneyThin::new(Vec3A::new(0.5, 0.7, 0.2), DisneyParams::thin_default()),
        };
        // (set, [θv, φv, θl, φl], Mitsuba's eval, Mitsuba's pdf)
        type Case = (&'static str, [f32; 4], [f32; 3], f32);
        #[rustfmt::skip]
        let cases: [Case; 15] = [
            ("a", [0.3, 0.2, 0.5, 2.0], [4.31143e-02, 6.48081e-03, 6.48081e-03], 7.86692e-02),
            ("a", [0.7, 0.0, 0.7, 3.1], [2.52546e-01, 1.48379e-01, 1.48379e-01], 3.42482e+00),
            ("a", [0.4, 0.3, 2.7, 3.3], [4.13553e+00, 5.90791e-01, 5.90791e-01], 3.03835e+00),
            ("a", [0.9, 1.0, 2.2, 4.5], [3.65062e-02, 5.21517e-03, 5.21517e-03], 4.14750e-02),
            ("a", [2.6, 0.3, 2.4, 3.5], [8.29833e-02, 3.54388e-02, 3.54388e-02], 8.10905e-01),
            ("a", [2.7, 1.0, 0.5, 4.0], [6.75707e+00, 9.65295e-01, 9.65295e-01], 4.95063e+00),
            ("a", [0.2, 0.0, 2.9, 0.1], [6.05575e-02, 8.65107e-03, 8.65107e-03], 6.83602e-02),
            ("b", [0.3, 0.2, 0.5, 2.0], [1.90007e-02, 2.73811e-02, 3.29680e-02], 1.61368e-01),
            ("b", [0.6, 0.4, 0.65, 3.3], [3.28127e-02, 4.04159e-02, 4.54847e-02], 3.22006e-01),
            ("b", [0.4, 0.0, 2.6, 3.0], [6.57160e-01, 1.31432e+00, 1.75243e+00], 1.14406e+00),
            ("b", [2.8, 0.2, 0.3, 3.0], [7.96336e-01, 1.59267e+00, 2.12356e+00], 1.38343e+00),
            ("b", [2.5, 0.5, 2.5, 3.6], [3.67488e-02, 4.44005e-02, 4.95016e-02], 3.63281e-01),
            ("c", [0.3, 0.2, 0.5, 2.0], [1.39673e-01, 1.95542e-01, 5.58693e-02], 2.79343e-01),
            ("c", [1.0, 0.0, 1.0, 3.0], [8.52712e-02, 1.19380e-01, 3.41085e-02], 1.71984e-01),
            ("c", [2.0, 1.0, 1.0, 3.0], [0.0, 0.0, 0.0], 0.0),
        ];
        let close = |a: f32, b: f32| (a - b).abs() <= 5e-3 * b.abs() + 1e-7;
        for (name, [tv, pv, tl, pl], eval, pdf) in cases {
            let lobe = set(name);
            let (wo, wi) = (direction(tv, pv), direction(tl, pl));
            let f = lobe.eval(wo, wi) * wi.z.abs();
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
