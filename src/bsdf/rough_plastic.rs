//! A diffuse base under a rough dielectric coating: Mitsuba 3's
//! `roughplastic`. The coating reflects a microfacet lobe (Walter et al.
//! 2007) with the exact dielectric Fresnel term; the base is seen through
//! the coating's directional transmittance `t(μ)`, tabulated once per
//! material by [`coating_table`], and light bounces between base and
//! coating by the geometric series of the coating's internal
//! reflectance `F_dr`:
//! `f = F D G / (4 cos θo cos θi) + kd' t(cos θi) t(cos θo) / (η² π)`,
//! with `kd' = kd / (1 − F_dr)`, or `kd / (1 − kd F_dr)` when nonlinear.

use super::fresnel;
use super::microfacet::{Microfacet, MicrofacetDistribution};
use super::BsdfSample;
use crate::math::sampling::cosine_hemisphere;
use crate::math::{Vec2, Vec3A};
use crate::scene::{CoatingTable, COATING_TABLE_SIZE};
use std::f32::consts::PI;

/// A coated diffuse surface with a rough coating.
#[derive(Clone, Copy, Debug)]
pub struct RoughPlastic<'a> {
    /// The base's albedo divided by the inter-reflection series.
    pub base: Vec3A,
    /// Probability weight of the coating's lobe (Mitsuba's
    /// `specular_sampling_weight`: `1 / (1 + mean(kd))`).
    pub specular_weight: f32,
    /// Index of the coating relative to the outside.
    pub eta: f32,
    /// The coating's microfacets.
    pub microfacet: Microfacet,
    /// The coating's transmittance.
    pub table: &'a CoatingTable,
}

impl<'a> RoughPlastic<'a> {
    /// The lobe of a base of albedo `kd` under a coating of index `eta`.
    pub fn new(kd: Vec3A, eta: f32, microfacet: Microfacet, nonlinear: bool, table: &'a CoatingTable) -> Self {
        let base = super::plastic::inter_reflected(kd, table.internal_reflectance, nonlinear);
        let d_mean = (kd.x + kd.y + kd.z) / 3.0;
        Self {
            base,
            specular_weight: 1.0 / (1.0 + d_mean),
            eta,
            microfacet,
            table,
        }
    }

    /// Probability of sampling the coating's lobe seen from `wo`.
    fn specular_probability(&self, wo: Vec3A) -> f32 {
        let t = self.table.transmittance_at(wo.z);
        let spec = (1.0 - t) * self.specular_weight;
        let diff = t * (1.0 - self.specular_weight);
        if spec + diff > 0.0 {
            spec / (spec + diff)
        } else {
            1.0
        }
    }

    pub(super) fn eval(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Vec3A::ZERO;
        }
        let h = (wo + wi).normalize();
        let f = fresnel::dielectric(wo.dot(h), self.eta).0;
        let specular = f * self.microfacet.d(h) * self.microfacet.g(wi, wo, h) / (4.0 * wo.z * wi.z);
        let t = self.table.transmittance_at(wo.z) * self.table.transmittance_at(wi.z);
        Vec3A::splat(specular) + self.base * (t / (self.eta * self.eta * PI))
    }

    pub(super) fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let p_spec = self.specular_probability(wo);
        let h = (wo + wi).normalize();
        let dot = wo.dot(h);
        let specular = if dot > 0.0 {
            self.microfacet.pdf_normal(wo, h) / (4.0 * dot)
        } else {
            0.0
        };
        p_spec * specular + (1.0 - p_spec) * wi.z / PI
    }

    pub(super) fn sample(&self, wo: Vec3A, uc: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = if uc < self.specular_probability(wo) {
            let m = self.microfacet.sample_normal(wo, u);
            2.0 * wo.dot(m) * m - wo
        } else {
            cosine_hemisphere(u)
        };
        if wi.z <= 0.0 {
            return None;
        }
        Some(BsdfSample::glossy(wi, self.eval(wo, wi), self.pdf(wo, wi)))
    }
}

/// Nodes per axis of the quadrature over microfacet normals.
const QUADRATURE_NODES: usize = 128;

/// The transmittance table of a rough coating of index `eta` (Mitsuba's
/// `eval_transmittance` and `eval_reflectance`): `t(μ)` is the fraction of
/// light arriving at cosine `μ` that refracts through a microfacet seen from
/// there and is not masked on its way in, `∫ D_μ(m) (1 − F(μ, m)) G1(ωt, m) dm`
/// over the normals `D_μ` visible from `μ` (Heitz 2014); `F_dr` averages the
/// same reflectance from below the coating (index `1/eta`) over the cosines
/// of the table, `2 mean(R(μ) μ)`, as Mitsuba does. The integrals are over
/// `D(m) cos θm`, each normal weighted by the visible-normal density over
/// it, `G1(ω, m) (ω·m)⁺ / (cos θ cos θm)`.
pub fn coating_table(eta: f32, microfacet: Microfacet) -> CoatingTable {
    let mut transmittance = [0.0f32; COATING_TABLE_SIZE];
    let mut internal = 0.0f64;
    for (i, t) in transmittance.iter_mut().enumerate() {
        let mu = (i as f32 / (COATING_TABLE_SIZE - 1) as f32).max(1.0e-6);
        let w = Vec3A::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
        *t = visible_integral(microfacet, w, |m| {
            let (f, cos_t) = fresnel::dielectric(w.dot(m), eta);
            let eta_ti = 1.0 / eta;
            let wt = m * (w.dot(m) * eta_ti + cos_t) - w * eta_ti;
            if wt.z * w.z >= 0.0 {
                0.0
            } else {
                microfacet.g1(wt, m) * (1.0 - f)
            }
        }) as f32;
        let r = visible_integral(microfacet, w, |m| {
            let wr = 2.0 * w.dot(m) * m - w;
            if wr.z <= 0.0 {
                0.0
            } else {
                microfacet.g1(wr, m) * fresnel::dielectric(w.dot(m), 1.0 / eta).0
            }
        });
        internal += r * mu as f64;
    }
    CoatingTable {
        transmittance,
        internal_reflectance: (2.0 * internal / COATING_TABLE_SIZE as f64) as f32,
    }
}

/// `∫ D_w(m) g(m) dm` over the normals visible from `w`, by a midpoint
/// rule in variables that make the integrand smooth: `θm` drawn with
/// density `D(m) cos θm` through `u = 1 − s²` (which takes out the
/// `(1 − u)^(−1/2)` growth of the weight in GGX's tail), and `φm` over only
/// the arc of normals that face `w` (`w·m > 0`), so no kink lies inside
/// the grid.
fn visible_integral(microfacet: Microfacet, w: Vec3A, g: impl Fn(Vec3A) -> f32) -> f64 {
    let a2 = (microfacet.alpha as f64).powi(2);
    let (sin_w, cos_w) = (((1.0 - w.z * w.z).max(0.0) as f64).sqrt(), w.z as f64);
    let n = QUADRATURE_NODES;
    let mut sum = 0.0f64;
    for i in 0..n {
        let s = (i as f64 + 0.5) / n as f64;
        let one_minus_u = s * s;
        let tan2 = match microfacet.distribution {
            MicrofacetDistribution::Ggx => a2 * (1.0 - one_minus_u) / one_minus_u,
            MicrofacetDistribution::Beckmann => -a2 * one_minus_u.ln(),
        };
        let cos = 1.0 / (1.0 + tan2).sqrt();
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        // w·m = sin θw sin θm cos φ + cos θw cos θm > 0 on |φ| < φ0.
        let phi0 = if sin_w * sin > 0.0 {
            (-cos_w * cos / (sin_w * sin)).clamp(-1.0, 1.0).acos()
        } else {
            std::f64::consts::PI
        };
        // du = 2s ds, and the arc is 2φ0 of the 2π the density spreads over.
        let row_weight = 2.0 * s * phi0 / std::f64::consts::PI;
        let mut row = 0.0f64;
        for j in 0..n {
            let phi = phi0 * (2.0 * (j as f64 + 0.5) / n as f64 - 1.0);
            let m = Vec3A::new((sin * phi.cos()) as f32, (sin * phi.sin()) as f32, cos as f32);
            let dot = w.dot(m);
            if dot <= 0.0 {
                continue;
            }
            let visible_over_sampled = microfacet.g1(w, m) as f64 * dot as f64 / (cos_w * cos);
            row += visible_over_sampled * g(m) as f64;
        }
        sum += row_weight * row;
    }
    sum / (n * n) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_nearly_smooth_coating_transmits_one_minus_fresnel() {
        let table = coating_table(1.5, Microfacet::ggx(1.0e-3));
        for (i, t) in table.transmittance.iter().enumerate().skip(4) {
            let mu = i as f32 / (COATING_TABLE_SIZE - 1) as f32;
            let expected = 1.0 - fresnel::dielectric(mu, 1.5).0;
            assert!((t - expected).abs() < 2e-3, "μ {mu}: {t} against {expected}");
        }
        // The hemispherical internal reflectance of a smooth interface of
        // index 1/1.5, by the table's own rectangle rule over μ.
        let mut expected = 0.0;
        for i in 0..COATING_TABLE_SIZE {
            let mu = (i as f32 / (COATING_TABLE_SIZE - 1) as f32).max(1e-6);
            expected += fresnel::dielectric(mu, 1.0 / 1.5).0 * mu;
        }
        expected *= 2.0 / COATING_TABLE_SIZE as f32;
        assert!(
            (table.internal_reflectance - expected).abs() < 2e-3,
            "{} against {expected}",
            table.internal_reflectance
        );
    }

    #[test]
    fn tables_are_fractions_for_both_distributions() {
        for distribution in [MicrofacetDistribution::Ggx, MicrofacetDistribution::Beckmann] {
            for alpha in [0.01, 0.3, 1.0] {
                let t = coating_table(1.49, Microfacet::isotropic(distribution, alpha));
                assert!(t.transmittance.iter().all(|x| (0.0..=1.0).contains(x)), "{t:?}");
                assert!((0.0..1.0).contains(&t.internal_reflectance), "{t:?}");
                // Seen head-on, little more than the smooth interface's
                // 1 − F(1) = 0.961 gets through.
                let head_on = t.transmittance[COATING_TABLE_SIZE - 1];
                assert!(
                    head_on <= 0.962 && head_on > 0.85,
                    "{distribution:?} {alpha}: {head_on}"
                );
            }
        }
    }

    /// Values of Mitsuba 3.9.1's `roughplastic` (scalar_rgb, diffuse
    /// reflectance (0.8, 0.4, 0.1), default indices), `eval` (which includes
    /// the cosine of the light's direction) and, for GGX, `pdf`, printed by
    /// `bsdf.eval(ctx, si, wo)` with `si.wi` = (θ, φ) of the viewer.
    #[test]
    fn rough_plastic_agrees_with_mitsuba() {
        let d = |theta: f32, phi: f32| Vec3A::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
        #[rustfmt::skip]
        // (distribution, α, nonlinear, [θo, φo, θi, φi], eval, pdf or −1)
        type Case = (MicrofacetDistribution, f32, bool, [f32; 4], [f32; 3], f32);
        let cases: [Case; 12] = [
            (
                MicrofacetDistribution::Ggx,
                0.1,
                false,
                [0.3, 0.0, 0.5, 3.0],
                [0.280_115_5, 0.178_111_7, 0.101_608_8],
                0.424_235_9,
            ),
            (
                MicrofacetDistribution::Ggx,
                0.1,
                false,
                [1.2, 0.5, 0.2, 2.0],
                [0.202_475_2, 0.101_606_7, 0.025_955_3],
                0.226_131_1,
            ),
            (
                MicrofacetDistribution::Ggx,
                0.1,
                false,
                [0.05, 0.0, 1.4, 1.0],
                [0.028_431_1, 0.014_301_3, 0.003_704_0],
                0.049_817_7,
            ),
            (
                MicrofacetDistribution::Ggx,
                0.1,
                false,
                [0.7, 0.0, 0.7, PI],
                [0.635_699_3, 0.548_033_2, 0.482_283_7],
                1.284_225,
            ),
            (
                MicrofacetDistribution::Beckmann,
                0.3,
                false,
                [0.3, 0.0, 0.5, 3.0],
                [0.227_191_4, 0.129_989_8, 0.057_088_6],
                -1.0,
            ),
            (
                MicrofacetDistribution::Beckmann,
                0.3,
                false,
                [1.2, 0.5, 0.2, 2.0],
                [0.194_893_5, 0.097_811_8, 0.025_000_5],
                -1.0,
            ),
            (
                MicrofacetDistribution::Beckmann,
                0.3,
                false,
                [0.05, 0.0, 1.4, 1.0],
                [0.030_294_5, 0.015_159_5, 0.003_808_2],
                -1.0,
            ),
            (
                MicrofacetDistribution::Beckmann,
                0.3,
                false,
                [0.7, 0.0, 0.7, PI],
                [0.217_754_5, 0.134_543_9, 0.072_135_9],
                -1.0,
            ),
            (
                MicrofacetDistribution::Ggx,
                0.5,
                true,
                [0.3, 0.0, 0.5, 3.0],
                [0.125_418_7, 0.061_388_7, 0.023_217_5],
                0.283_518,
            ),
            (
                MicrofacetDistribution::Ggx,
                0.5,
                true,
                [1.2, 0.5, 0.2, 2.0],
                [0.114_530_6, 0.053_703_3, 0.017_441_5],
                0.254_761_1,
            ),
            (
                MicrofacetDistribution::Ggx,
                0.5,
                true,
                [0.05, 0.0, 1.4, 1.0],
                [0.017_397_1, 0.008_322_4, 0.002_912_6],
                0.054_953_6,
            ),
            (
                MicrofacetDistribution::Ggx,
                0.5,
                true,
                [0.7, 0.0, 0.7, PI],
                [0.110_922_4, 0.057_927_3, 0.026_334_5],
                0.272_686_3,
            ),
        ];
        for (distribution, alpha, nonlinear, [to, po, ti, pi], expected, expected_pdf) in cases {
            let microfacet = Microfacet::isotropic(distribution, alpha);
            let table = coating_table(1.49 / 1.000277, microfacet);
            let kd = Vec3A::new(0.8, 0.4, 0.1);
            let lobe = RoughPlastic::new(kd, 1.49 / 1.000277, microfacet, nonlinear, &table);
            let (wo, wi) = (d(to, po), d(ti, pi));
            let value = lobe.eval(wo, wi) * wi.z;
            let expected = Vec3A::from_array(expected);
            let error = ((value - expected) / expected).abs().max_element();
            assert!(
                error < 5e-3,
                "{distribution:?} α {alpha}: {value} against Mitsuba's {expected}"
            );
            if expected_pdf > 0.0 {
                let pdf = lobe.pdf(wo, wi);
                assert!(
                    (pdf / expected_pdf - 1.0).abs() < 5e-3,
                    "{distribution:?} α {alpha}: pdf {pdf} against Mitsuba's {expected_pdf}"
                );
            }
        }
    }
}
