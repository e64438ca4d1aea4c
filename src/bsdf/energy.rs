//! Directional albedos of single-scattering GGX reflection (height-correlated
//! Smith masking), for the multiple-scattering energy compensation of
//! Kulla & Conty 2017 ("Revisiting Physically Based Shading at Imageworks",
//! §2 and its appendix) and for albedo-scaled layering:
//!
//! - `E(μ, α) = ∫ D G / (4 μ μi) μi dωi`: what one bounce on the
//!   microfacets reflects with a white Fresnel term; `1 − E(μ)` is the
//!   energy lost to the single-scattering model's missing inter-reflections.
//! - `E_avg(α) = 2 ∫ E(μ) μ dμ`: its cosine-weighted hemispherical average.
//! - `E_F(μ, α, η)`: the same with the exact dielectric Fresnel term
//!   `F(ωo·m, η)`, the albedo of a rough dielectric's reflection.
//!
//! Tabulated once, at first use, over `μ` (32 nodes), the perceptual
//! roughness `r = √α` (32 nodes) and, for `E_F`, `z = √|(η − 1)/(η + 1)|`
//! (16 nodes, as Cycles parametrises its tables), by a stratified
//! visible-normal quadrature (Heitz 2018: the estimator of `E` is
//! `G(ωi, ωo) / G1(ωo)` for normals drawn from the visible distribution).

use super::fresnel;
use super::microfacet::Microfacet;
use crate::math::{Vec2, Vec3A};
use std::sync::OnceLock;

/// Nodes along `μ = cos θo`.
const MU_NODES: usize = 32;
/// Nodes along the perceptual roughness `r = √α`.
const R_NODES: usize = 32;
/// Nodes along `z = √|(η − 1)/(η + 1)|`.
const Z_NODES: usize = 16;
/// Quadrature nodes per axis of the visible normals.
const QUADRATURE: usize = 32;
/// Smallest `α` tabulated (the lobes below it are deltas anyway).
const MIN_ALPHA: f32 = 1.0e-4;

/// The albedo tables.
struct Tables {
    /// `E(μ, r)`, index `r * MU_NODES + μ`.
    e: Vec<f32>,
    /// `E_avg(r)`.
    e_avg: Vec<f32>,
    /// `E_F(μ, r, z)`, index `(z * R_NODES + r) * MU_NODES + μ`.
    e_f: Vec<f32>,
    /// `F_avg(z) = 2 ∫ F(μ) μ dμ`, the exact dielectric Fresnel term's
    /// hemispherical average.
    f_avg: Vec<f32>,
}

fn node(i: usize, n: usize) -> f32 {
    i as f32 / (n - 1) as f32
}

/// `μ` of node `i`, kept off the grazing singularity.
fn mu_node(i: usize) -> f32 {
    node(i, MU_NODES).max(1.0e-3)
}

/// The index of the `z` node (`z = 1` is a perfect mirror, `η = ∞`).
fn eta_of_z(z: f32) -> Option<f32> {
    let r = z * z;
    (r < 1.0).then(|| (1.0 + r) / (1.0 - r))
}

fn build() -> Tables {
    let mut e = vec![0.0f32; R_NODES * MU_NODES];
    let mut e_f = vec![0.0f32; Z_NODES * R_NODES * MU_NODES];
    let etas: Vec<Option<f32>> = (0..Z_NODES).map(|k| eta_of_z(node(k, Z_NODES))).collect();
    for ri in 0..R_NODES {
        let r = node(ri, R_NODES);
        let mf = Microfacet::ggx((r * r).max(MIN_ALPHA));
        for mi in 0..MU_NODES {
            let mu = mu_node(mi);
            let wo = Vec3A::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
            let mut sum = 0.0f64;
            let mut sum_f = [0.0f64; Z_NODES];
            for i in 0..QUADRATURE {
                for j in 0..QUADRATURE {
                    let u = Vec2::new(
                        (i as f32 + 0.5) / QUADRATURE as f32,
                        (j as f32 + 0.5) / QUADRATURE as f32,
                    );
                    let m = mf.sample_normal(wo, u);
                    let cos_om = wo.dot(m);
                    let wi = 2.0 * cos_om * m - wo;
                    let g1 = mf.g1(wo, m);
                    if wi.z <= 0.0 || cos_om <= 0.0 || g1 <= 0.0 {
                        continue;
                    }
                    let w = (mf.g_correlated(wi, wo, m) / g1) as f64;
                    sum += w;
                    for (s, eta) in sum_f.iter_mut().zip(&etas) {
                        let f = eta.map_or(1.0, |eta| fresnel::dielectric(cos_om, eta).0);
                        *s += w * f as f64;
                    }
                }
            }
            let n = (QUADRATURE * QUADRATURE) as f64;
            e[ri * MU_NODES + mi] = (sum / n) as f32;
            for (k, s) in sum_f.iter().enumerate() {
                e_f[(k * R_NODES + ri) * MU_NODES + mi] = (s / n) as f32;
            }
        }
    }
    let e_avg = (0..R_NODES)
        .map(|ri| cosine_average(|mu| lerp_row(&e[ri * MU_NODES..(ri + 1) * MU_NODES], mu)))
        .collect();
    let f_avg = etas
        .iter()
        .map(|eta| cosine_average(|mu| eta.map_or(1.0, |eta| fresnel::dielectric(mu, eta).0)))
        .collect();
    Tables { e, e_avg, e_f, f_avg }
}

/// `2 ∫₀¹ g(μ) μ dμ` by the midpoint rule.
fn cosine_average(g: impl Fn(f32) -> f32) -> f32 {
    const N: usize = 256;
    let sum: f64 = (0..N)
        .map(|i| {
            let mu = (i as f32 + 0.5) / N as f32;
            (g(mu) * mu) as f64
        })
        .sum();
    (2.0 * sum / N as f64) as f32
}

fn tables() -> &'static Tables {
    static TABLES: OnceLock<Tables> = OnceLock::new();
    TABLES.get_or_init(build)
}

/// Position of `x` ∈ [0, 1] on `n` nodes: the lower node and the weight of
/// the upper one.
fn locate(x: f32, n: usize) -> (usize, f32) {
    let t = x.clamp(0.0, 1.0) * (n - 1) as f32;
    let i = (t as usize).min(n - 2);
    (i, t - i as f32)
}

/// Linear interpolation along one row of `μ` nodes.
fn lerp_row(row: &[f32], mu: f32) -> f32 {
    let (i, t) = locate(mu, MU_NODES);
    row[i] * (1.0 - t) + row[i + 1] * t
}

/// Bilinear interpolation over (`r`, `μ`) in one `R_NODES × MU_NODES` slab.
fn lerp_slab(slab: &[f32], r: f32, mu: f32) -> f32 {
    let (ri, t) = locate(r, R_NODES);
    let a = lerp_row(&slab[ri * MU_NODES..(ri + 1) * MU_NODES], mu);
    let b = lerp_row(&slab[(ri + 1) * MU_NODES..(ri + 2) * MU_NODES], mu);
    a * (1.0 - t) + b * t
}

/// The perceptual roughness of an isotropic GGX distribution.
fn roughness(mf: &Microfacet) -> f32 {
    mf.alpha.max(0.0).sqrt()
}

/// `z = √|(η − 1)/(η + 1)|` (an index below 1 is read as its inverse,
/// which has the same normal reflectance).
fn z_of_eta(eta: f32) -> f32 {
    ((eta - 1.0) / (eta + 1.0)).abs().sqrt()
}

/// `E(μ)`: the albedo of single-scattering GGX reflection with `F = 1`.
pub fn albedo(mf: &Microfacet, mu: f32) -> f32 {
    lerp_slab(&tables().e, roughness(mf), mu)
}

/// `E_avg`: the cosine-weighted average of [`albedo`] over the hemisphere.
pub fn average_albedo(mf: &Microfacet) -> f32 {
    let (ri, t) = locate(roughness(mf), R_NODES);
    let e = &tables().e_avg;
    e[ri] * (1.0 - t) + e[ri + 1] * t
}

/// `E_F(μ)`: the albedo of single-scattering GGX reflection weighted by the
/// exact dielectric Fresnel term of index `eta`.
pub fn dielectric_albedo(mf: &Microfacet, mu: f32, eta: f32) -> f32 {
    let tables = tables();
    let (zi, t) = locate(z_of_eta(eta), Z_NODES);
    let slab = R_NODES * MU_NODES;
    let r = roughness(mf);
    let a = lerp_slab(&tables.e_f[zi * slab..(zi + 1) * slab], r, mu);
    let b = lerp_slab(&tables.e_f[(zi + 1) * slab..(zi + 2) * slab], r, mu);
    a * (1.0 - t) + b * t
}

/// `F_avg = 2 ∫ F(μ) μ dμ` of the exact dielectric Fresnel term of index
/// `eta` (interpolated over `z`).
pub fn dielectric_fresnel_average(eta: f32) -> f32 {
    let (zi, t) = locate(z_of_eta(eta), Z_NODES);
    let f = &tables().f_avg;
    f[zi] * (1.0 - t) + f[zi + 1] * t
}

/// `F_avg` of Schlick's term with normal reflectance `f0`:
/// `f0 + (1 − f0)/21`, since `2 ∫ (1 − μ)^5 μ dμ = 1/21`.
pub fn schlick_fresnel_average(f0: Vec3A) -> Vec3A {
    f0 + (Vec3A::ONE - f0) / 21.0
}

/// The factor by which single-scattering GGX reflection seen from `μo` is
/// scaled to add its multiple scattering, `1 + F_ms (1 − E(μo)) / E(μo)`
/// with `F_ms = F_avg E_avg / (1 − F_avg (1 − E_avg))`: Kulla & Conty's
/// series of inter-reflections, each losing `1 − F_avg`, with one Fresnel
/// bounce taken out since the scaled lobe already holds it, applied to the
/// single-scattering lobe's own shape (Turquin 2019, as Cycles and Filament
/// do). With `F = 1` the lobe's albedo `E(μo)` becomes exactly 1.
pub fn compensation(mf: &Microfacet, mu_o: f32, f_avg: f32) -> f32 {
    Albedos::new(mf, mu_o).compensation(f_avg)
}

/// `E(μo)` and `E_avg` of one distribution, looked up once for the
/// [`compensation`] of several Fresnel averages (a metal's three channels).
#[derive(Clone, Copy, Debug)]
pub struct Albedos {
    e: f32,
    e_avg: f32,
}

impl Albedos {
    /// The albedos of `mf` seen from `μo`.
    pub fn new(mf: &Microfacet, mu_o: f32) -> Self {
        Self {
            e: albedo(mf, mu_o).clamp(1.0e-3, 1.0),
            e_avg: average_albedo(mf).min(1.0),
        }
    }

    /// [`compensation`] for the Fresnel average `f_avg`.
    pub fn compensation(self, f_avg: f32) -> f32 {
        let (e, e_avg) = (self.e, self.e_avg);
        let f_ms = f_avg * e_avg / (1.0 - f_avg * (1.0 - e_avg)).max(1.0e-6);
        1.0 + f_ms * (1.0 - e) / e
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_nearly_smooth_surface_reflects_everything() {
        let mf = Microfacet::ggx(MIN_ALPHA);
        for i in 2..MU_NODES {
            let mu = node(i, MU_NODES);
            assert!((albedo(&mf, mu) - 1.0).abs() < 2e-3, "μ {mu}: {}", albedo(&mf, mu));
            let f = fresnel::dielectric(mu, 1.5).0;
            assert!((dielectric_albedo(&mf, mu, 1.5) - f).abs() < 3e-3, "μ {mu}");
        }
    }

    #[test]
    fn rough_surfaces_lose_energy_and_fresnel_averages_match_known_values() {
        // Kulla & Conty: single-scattering GGX loses up to 60 % at α = 1.
        let e = average_albedo(&Microfacet::ggx(1.0));
        assert!((0.38..0.5).contains(&e), "E_avg(1) = {e}");
        assert!(average_albedo(&Microfacet::ggx(0.25)) > e);
        // d'Eon's fit of F_avg for η = 1.5: (η − 1)/(4.08567 + 1.00071 η) = 0.0909.
        let f = dielectric_fresnel_average(1.5);
        assert!((f - 0.0909).abs() < 3e-3, "F_avg(1.5) = {f}");
        // A white lobe's compensated albedo is 1.
        let mf = Microfacet::ggx(0.8);
        for mu in [0.1, 0.5, 1.0] {
            let a = albedo(&mf, mu) * compensation(&mf, mu, 1.0);
            assert!((a - 1.0).abs() < 1e-5, "μ {mu}: {a}");
        }
    }
}
