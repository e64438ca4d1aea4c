//! Every BSDF's sampling against its own `eval` and `pdf`: a chi-square test
//! of the sampled directions against the density integrated over a grid of
//! the sphere (as pbrt and Mitsuba test theirs), the value and density a
//! sample reports against `eval` / `pdf`, reciprocity, and energy (no
//! BSDF reflects more than it receives).

use caustic::bsdf::energy;
use caustic::bsdf::microfacet::Microfacet;
use caustic::bsdf::{Bsdf, FresnelModel, Transport};
use caustic::math::rng::Domain;
use caustic::math::{Rng, Vec3A};
use caustic::scene::{
    Coating, Conductor, Dielectric, Disney, Material, MicrofacetDistribution, Mirror, Principled, ShadingModel,
};
use statrs::distribution::{ChiSquared, ContinuousCDF};
use std::f32::consts::PI;

const THETA_BINS: usize = 16;
const PHI_BINS: usize = 32;
const SAMPLES: usize = 400_000;
/// Significance of one test, before the correction for the number of tests.
const ALPHA: f64 = 0.01;
const TESTS: f64 = 16.0;

fn direction(theta: f32, phi: f32) -> Vec3A {
    Vec3A::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
}

fn bin_of(w: Vec3A) -> usize {
    let theta = w.z.clamp(-1.0, 1.0).acos();
    let mut phi = w.y.atan2(w.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let t = ((theta / PI * THETA_BINS as f32) as usize).min(THETA_BINS - 1);
    let p = ((phi / (2.0 * PI) * PHI_BINS as f32) as usize).min(PHI_BINS - 1);
    t * PHI_BINS + p
}

/// Chi-square test of `bsdf`'s non-delta samples from `wo` against `pdf`.
fn chi2(name: &str, bsdf: &Bsdf, wo: Vec3A) {
    let mut rng = Rng::new(7, Domain::Analysis, name.len() as u64, (wo.z * 1000.0) as u64);
    let mut observed = vec![0.0f64; THETA_BINS * PHI_BINS];
    for _ in 0..SAMPLES {
        let (uc, u) = (rng.f32(), rng.vec2());
        if let Some(s) = bsdf.sample(wo, uc, u) {
            if !s.delta {
                observed[bin_of(s.wi)] += 1.0;
                // The sample's value and density are the BSDF's own.
                let (f, pdf) = (bsdf.eval(wo, s.wi), bsdf.pdf(wo, s.wi));
                assert!(
                    (s.pdf - pdf).abs() <= 1e-3 * pdf.max(1.0),
                    "{name}: sample pdf {} vs pdf() {pdf} at {}",
                    s.pdf,
                    s.wi
                );
                assert!(
                    (s.f - f).abs().max_element() <= 1e-3 * f.max_element().max(1.0),
                    "{name}: sample f {} vs eval() {f}",
                    s.f
                );
            }
        }
    }
    // Expected counts: the density integrated over each bin (midpoint rule
    // on a sub-grid, sin θ dθ dφ).
    let sub = 32;
    let (dt, dp) = (PI / THETA_BINS as f32, 2.0 * PI / PHI_BINS as f32);
    let mut expected = vec![0.0f64; THETA_BINS * PHI_BINS];
    for t in 0..THETA_BINS {
        for p in 0..PHI_BINS {
            let mut sum = 0.0f64;
            for i in 0..sub {
                for j in 0..sub {
                    let theta = (t as f32 + (i as f32 + 0.5) / sub as f32) * dt;
                    let phi = (p as f32 + (j as f32 + 0.5) / sub as f32) * dp;
                    let w = direction(theta, phi);
                    sum += (bsdf.pdf(wo, w) * theta.sin()) as f64;
                }
            }
            expected[t * PHI_BINS + p] = sum * (dt * dp) as f64 / (sub * sub) as f64 * SAMPLES as f64;
        }
    }
    // Pool the bins with few expected samples (Cochran's rule).
    let mut order: Vec<usize> = (0..expected.len()).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let (mut chi, mut dof) = (0.0f64, 0i64);
    let (mut pool_e, mut pool_o) = (0.0, 0.0);
    for &i in &order {
        if expected[i] == 0.0 {
            assert!(
                observed[i] == 0.0,
                "{name}: {} samples in bin {i} where the density is zero",
                observed[i]
            );
            continue;
        }
        if expected[i] < 5.0 {
            pool_e += expected[i];
            pool_o += observed[i];
            continue;
        }
        chi += (observed[i] - expected[i]).powi(2) / expected[i];
        dof += 1;
    }
    if pool_e > 0.0 {
        chi += (pool_o - pool_e).powi(2) / pool_e;
        dof += 1;
    }
    let dof = (dof - 1).max(1) as f64;
    let p_value = 1.0 - ChiSquared::new(dof).unwrap().cdf(chi);
    assert!(
        p_value > ALPHA / TESTS,
        "{name} from {wo}: chi² = {chi:.1} with {dof} degrees of freedom, p = {p_value:.2e}"
    );
}

fn report(diffuse: f32, specular: f32, shininess: f32, model: ShadingModel) -> Material {
    let mut m = Material::diffuse("m", Vec3A::splat(diffuse));
    m.specular = Vec3A::splat(specular);
    m.shininess = shininess;
    m.model = model;
    m
}

fn gold(roughness: f32) -> Material {
    let mut m = Material::diffuse("gold", Vec3A::ZERO);
    m.conductor = Some(Conductor {
        eta: Vec3A::new(0.143, 0.375, 1.442),
        k: Vec3A::new(3.983, 2.386, 1.603),
        roughness,
    });
    m
}

fn glass(roughness: f32) -> Material {
    let mut m = Material::diffuse("glass", Vec3A::ZERO);
    m.dielectric = Some(Dielectric {
        roughness,
        ..Dielectric::smooth(1.5, Vec3A::ONE)
    });
    m
}

fn beckmann(mut m: Material) -> Material {
    m.microfacet = MicrofacetDistribution::Beckmann;
    m
}

fn plastic(albedo: f32) -> Material {
    let mut m = Material::diffuse("plastic", Vec3A::new(albedo, 0.5 * albedo, 0.2));
    m.coating = Some(Coating::smooth(1.5));
    m
}

fn anisotropic(mut m: Material, roughness_v: f32) -> Material {
    m.roughness_v = Some(roughness_v);
    m
}

fn rough_plastic(albedo: f32, alpha: f32, nonlinear: bool) -> Material {
    let mut m = Material::diffuse("rough plastic", Vec3A::new(albedo, 0.5 * albedo, 0.2));
    m.coating = Some(Coating {
        roughness: alpha,
        nonlinear,
        ..Coating::smooth(1.5)
    });
    m
}

fn thin_glass() -> Material {
    let mut m = Material::diffuse("thin glass", Vec3A::ZERO);
    m.dielectric = Some(Dielectric {
        thin: true,
        ..Dielectric::smooth(1.5, Vec3A::new(1.0, 0.8, 0.6))
    });
    m
}

/// glTF's metallic-roughness material.
fn principled(base: Vec3A, p: Principled) -> Material {
    let mut m = Material::diffuse("principled", base);
    m.principled = Some(p);
    m
}

fn metal_rough(metallic: f32, roughness: f32) -> Principled {
    Principled {
        metallic,
        roughness,
        ..Principled::default()
    }
}

/// The principled materials the sampling and energy tests cover: dielectric,
/// metal and mixed, coated, thin and solid transmission.
fn principled_cases(base: Vec3A) -> Vec<(&'static str, Material)> {
    vec![
        ("principled dielectric 0.5", principled(base, metal_rough(0.0, 0.5))),
        ("principled metal 0.4", principled(base, metal_rough(1.0, 0.4))),
        ("principled mixed 0.3", principled(base, metal_rough(0.4, 0.3))),
        (
            "principled coated",
            principled(
                base,
                Principled {
                    clearcoat: 0.7,
                    clearcoat_roughness: 0.25,
                    ..metal_rough(0.2, 0.6)
                },
            ),
        ),
        (
            "principled smooth coat over rough base",
            principled(
                base,
                Principled {
                    clearcoat: 1.0,
                    ..metal_rough(0.0, 0.7)
                },
            ),
        ),
        ("principled smooth dielectric", principled(base, metal_rough(0.0, 0.0))),
        (
            "principled thin transmission 0.5",
            principled(
                base,
                Principled {
                    transmission: 0.8,
                    ..metal_rough(0.0, 0.5)
                },
            ),
        ),
        (
            "principled solid transmission 0.5",
            principled(
                base,
                Principled {
                    transmission: 1.0,
                    thin: false,
                    ..metal_rough(0.0, 0.5)
                },
            ),
        ),
    ]
}

fn disney(base: Vec3A, d: Disney) -> Material {
    let mut m = Material::diffuse("disney", base);
    m.disney = Some(d);
    m.one_sided = true;
    m
}

/// Mitsuba `principled` materials for the sampling tests: every lobe on, a
/// metal, anisotropic refraction, uneven sampling rates, a matte base.
fn disney_cases(base: Vec3A) -> Vec<(&'static str, Material)> {
    vec![
        (
            "disney everything",
            disney(
                base,
                Disney {
                    roughness: 0.4,
                    metallic: 0.3,
                    spec_tint: 0.4,
                    sheen: 0.7,
                    sheen_tint: 0.5,
                    clearcoat: 0.8,
                    clearcoat_gloss: 0.6,
                    flatness: 0.3,
                    ..Disney::default()
                },
            ),
        ),
        (
            "disney anisotropic metal",
            disney(
                base,
                Disney {
                    roughness: 0.5,
                    anisotropic: 0.8,
                    metallic: 1.0,
                    ..Disney::default()
                },
            ),
        ),
        (
            "disney glossy coat, uneven rates",
            disney(
                base,
                Disney {
                    roughness: 0.7,
                    clearcoat: 1.0,
                    clearcoat_gloss: 0.9,
                    diffuse_sampling_rate: 0.3,
                    clearcoat_sampling_rate: 3.0,
                    ..Disney::default()
                },
            ),
        ),
        (
            "disney anisotropic transmission",
            disney(
                base,
                Disney {
                    roughness: 0.3,
                    anisotropic: 0.6,
                    spec_trans: 0.7,
                    eta: 1.45,
                    metallic: 0.2,
                    clearcoat: 0.5,
                    sheen: 0.3,
                    ..Disney::default()
                },
            ),
        ),
    ]
}

/// Mitsuba `principledthin` materials for the sampling tests: every lobe
/// on, a specular sheet, a diffuse one that transmits, uneven rates.
fn thin_disney_cases(base: Vec3A) -> Vec<(&'static str, Material)> {
    let thin = |d: Disney| {
        let mut m = disney(base, d);
        m.one_sided = false;
        m
    };
    vec![
        (
            "thin disney everything",
            thin(Disney {
                roughness: 0.3,
                anisotropic: 0.5,
                spec_trans: 0.6,
                diff_trans: 0.8,
                eta: 1.33,
                sheen: 0.5,
                sheen_tint: 0.4,
                flatness: 0.3,
                spec_tint: 0.2,
                ..Disney::thin_default()
            }),
        ),
        (
            "thin disney specular sheet",
            thin(Disney {
                roughness: 0.6,
                spec_trans: 1.0,
                eta: 1.5,
                ..Disney::thin_default()
            }),
        ),
        (
            "thin disney diffuse, uneven rates",
            thin(Disney {
                roughness: 0.4,
                spec_trans: 0.3,
                diff_trans: 1.2,
                eta: 1.2,
                diffuse_sampling_rate: 0.4,
                specular_sampling_rate: 2.0,
                specular_transmission_sampling_rate: 0.5,
                diffuse_transmission_sampling_rate: 3.0,
                ..Disney::thin_default()
            }),
        ),
    ]
}

fn bsdf(m: &Material) -> Bsdf<'_> {
    Bsdf::for_material(m, FresnelModel::Exact, Transport::Radiance)
}

fn outgoing() -> [Vec3A; 3] {
    [Vec3A::new(0.0, 0.0, 1.0), direction(0.7, 0.4), direction(1.3, 2.0)]
}

#[test]
fn diffuse_and_report_lobes_sample_their_density() {
    for wo in outgoing() {
        chi2("lambert", &bsdf(&Material::diffuse("d", Vec3A::splat(0.7))), wo);
        chi2("phong", &bsdf(&report(0.4, 0.5, 20.0, ShadingModel::Phong)), wo);
        chi2(
            "blinn-phong",
            &bsdf(&report(0.3, 0.6, 40.0, ShadingModel::BlinnPhong)),
            wo,
        );
    }
    // A mirror mixed with the surface: only the non-delta part is tested.
    let mut m = report(0.5, 0.3, 30.0, ShadingModel::Phong);
    m.mirror = Some(Mirror {
        reflectivity: 0.4,
        tint: Vec3A::ONE,
    });
    chi2("phong + mirror", &bsdf(&m), direction(0.5, 1.0));
}

#[test]
fn microfacet_lobes_sample_their_density() {
    for wo in outgoing() {
        chi2("rough gold 0.3", &bsdf(&gold(0.3)), wo);
        chi2("rough gold 0.6", &bsdf(&gold(0.6)), wo);
        chi2("beckmann gold 0.3", &bsdf(&beckmann(gold(0.3))), wo);
        chi2("beckmann gold 0.6", &bsdf(&beckmann(gold(0.6))), wo);
        chi2("plastic", &bsdf(&plastic(0.8)), wo);
        chi2("anisotropic gold 0.2/0.6", &bsdf(&anisotropic(gold(0.2), 0.6)), wo);
        chi2(
            "anisotropic beckmann gold 0.5/0.15",
            &bsdf(&beckmann(anisotropic(gold(0.5), 0.15))),
            wo,
        );
        chi2("rough plastic 0.1", &bsdf(&rough_plastic(0.8, 0.1, false)), wo);
        chi2("rough plastic 0.5", &bsdf(&rough_plastic(0.3, 0.5, true)), wo);
        chi2(
            "beckmann rough plastic 0.3",
            &bsdf(&beckmann(rough_plastic(0.6, 0.3, false))),
            wo,
        );
    }
    // Rough glass from outside and from inside (transmission included).
    for wo in [
        direction(0.3, 0.1),
        direction(1.0, 1.0),
        direction(PI - 0.4, 3.0),
        direction(PI - 1.1, 0.5),
    ] {
        chi2("rough glass 0.3", &bsdf(&glass(0.3)), wo);
        chi2("rough glass 0.6", &bsdf(&glass(0.6)), wo);
        chi2("beckmann glass 0.3", &bsdf(&beckmann(glass(0.3))), wo);
        chi2("beckmann glass 0.6", &bsdf(&beckmann(glass(0.6))), wo);
        chi2("anisotropic glass 0.2/0.5", &bsdf(&anisotropic(glass(0.2), 0.5)), wo);
        chi2(
            "anisotropic beckmann glass 0.4/0.1",
            &bsdf(&beckmann(anisotropic(glass(0.4), 0.1))),
            wo,
        );
    }
}

#[test]
fn disney_lobes_sample_their_density() {
    let base = Vec3A::new(0.8, 0.5, 0.2);
    for (name, m) in disney_cases(base) {
        for wo in outgoing() {
            chi2(name, &bsdf(&m), wo);
        }
    }
    // The refracting one from inside: reflection and refraction only.
    let (name, m) = disney_cases(base).pop().unwrap();
    for wo in [direction(PI - 0.4, 3.0), direction(PI - 1.1, 0.5)] {
        chi2(name, &bsdf(&m), wo);
    }
}

#[test]
fn thin_disney_lobes_sample_their_density() {
    let base = Vec3A::new(0.8, 0.5, 0.2);
    for (name, m) in thin_disney_cases(base) {
        // Both sides: the sheet scatters alike from behind.
        for wo in outgoing().into_iter().chain([direction(PI - 0.5, 1.0)]) {
            chi2(name, &bsdf(&m), wo);
        }
    }
}

#[test]
fn thin_disney_reflects_reciprocally_and_alike_from_both_sides() {
    let mut rng = Rng::new(17, Domain::Analysis, 0, 0);
    for (name, m) in thin_disney_cases(Vec3A::new(0.8, 0.5, 0.2)) {
        let b = bsdf(&m);
        for i in 0..2000 {
            let a = caustic::math::sampling::cosine_hemisphere(rng.vec2());
            let mut c = caustic::math::sampling::cosine_hemisphere(rng.vec2());
            if i % 2 == 1 {
                // Through the sheet.
                c = -c;
            }
            let (f1, f2) = (b.eval(a, c), b.eval(c, a));
            let tolerance = 1e-4 * f1.max_element().max(1.0);
            // Reflection is reciprocal; Mitsuba's transmission is not
            // exactly (its masking is gated by the sides of the unmirrored
            // direction: 1.4 % apart at some pairs, in Mitsuba as here).
            assert!(
                i % 2 == 1 || (f1 - f2).abs().max_element() <= tolerance,
                "{name}: f({a}, {c}) = {f1} but f({c}, {a}) = {f2}"
            );
            // The same seen from the other side.
            let f3 = b.eval(-a, -c);
            assert!((f1 - f3).abs().max_element() <= tolerance, "{name}: {f1} against {f3}");
        }
    }
}

#[test]
fn a_thin_disney_sheet_keeps_at_most_the_light_it_receives() {
    let mut rng = Rng::new(19, Domain::Analysis, 0, 0);
    // A specular sheet: Fresnel reflection plus the transmitted rest.
    let (_, specular) = thin_disney_cases(Vec3A::ONE).swap_remove(1);
    // All of the diffuse base transmitted: a white Lambertian transmitter.
    let mut lambert = specular.clone();
    lambert.disney = Some(Disney {
        diff_trans: 2.0,
        ..Disney::thin_default()
    });
    for wo in outgoing()
        .into_iter()
        .chain([direction(1.5, 0.0), direction(PI - 0.4, 1.0)])
    {
        let (a, sigma) = albedo(&bsdf(&specular), wo, &mut rng);
        assert!(
            a.max_element() <= 1.0 + 4.0 * sigma + 2e-3,
            "specular sheet from {wo}: albedo {a} (σ {sigma})"
        );
        let (a, sigma) = albedo(&bsdf(&lambert), wo, &mut rng);
        assert!(
            (a - Vec3A::ONE).abs().max_element() <= 4.0 * sigma + 2e-3,
            "diffuse transmitter from {wo}: albedo {a} (σ {sigma})"
        );
    }
}

#[test]
fn principled_lobes_sample_their_density() {
    let base = Vec3A::new(0.8, 0.5, 0.2);
    for (name, m) in principled_cases(base) {
        for wo in outgoing() {
            chi2(name, &bsdf(&m), wo);
        }
    }
    // Solid transmission seen from inside: the rough interface alone.
    let (name, m) = principled_cases(base).pop().unwrap();
    for wo in [direction(PI - 0.4, 3.0), direction(PI - 1.1, 0.5)] {
        chi2(name, &bsdf(&m), wo);
    }
}

#[test]
fn principled_glass_is_the_rough_dielectric_tinted_by_its_base() {
    // Except for the outside reflection's masking (below).
    let tint = Vec3A::new(0.9, 0.6, 0.3);
    let mut rng = Rng::new(17, Domain::Analysis, 0, 0);
    for roughness in [0.3f32, 0.7] {
        let p = principled(
            tint,
            Principled {
                transmission: 1.0,
                thin: false,
                ..metal_rough(0.0, roughness)
            },
        );
        let mut g = glass(roughness * roughness);
        g.dielectric.as_mut().unwrap().tint = tint;
        let (bp, bg) = (bsdf(&p), bsdf(&g));
        for _ in 0..2000 {
            let wo = caustic::math::sampling::uniform_sphere(rng.vec2());
            let wi = caustic::math::sampling::uniform_sphere(rng.vec2());
            let (fp, fg) = (bp.eval(wo, wi), bg.eval(wo, wi));
            if wo.z > 0.0 && wi.z > 0.0 {
                // Reflection outside: glTF's height-correlated masking
                // hides less than the rough dielectric's separable one.
                assert!(
                    fp.min_element() >= fg.max_element() * (1.0 - 1e-4),
                    "roughness {roughness}: principled {fp} below glass {fg} at {wo} → {wi}"
                );
                continue;
            }
            assert!(
                (fp - fg).abs().max_element() <= 1e-4 * fg.max_element().max(1.0),
                "roughness {roughness}: principled {fp} against glass {fg} at {wo} → {wi}"
            );
        }
    }
}

#[test]
fn principled_matches_its_formula_at_normal_incidence() {
    // wo = wi = n: h = n, F = ((η − 1)/(η + 1))² = 0.04, D = 1/(π α²), G = 1:
    // f = (1 − E_F(1) k(1)) c / π + F k(1) / (4 π α²) for a dielectric,
    // c k_c(1) / (4 π α²) for a metal, with the compensations
    // k = 1 + F_ms (1 − E) / E (docs/scene-format.md).
    let c = Vec3A::new(0.8, 0.4, 0.1);
    let (r, alpha) = (0.5f32, 0.25f32);
    let n = Vec3A::Z;
    let mf = Microfacet::ggx(alpha);
    let k_d = energy::compensation(&mf, 1.0, energy::dielectric_fresnel_average(1.5));
    assert!(k_d > 1.0 && k_d < 1.05, "{k_d}");
    let e_s = energy::dielectric_albedo(&mf, 1.0, 1.5) * k_d;
    let f = bsdf(&principled(c, metal_rough(0.0, r))).eval(n, n);
    let expected = c * ((1.0 - e_s) / PI) + Vec3A::splat(0.04 * k_d / (4.0 * PI * alpha * alpha));
    assert!((f - expected).abs().max_element() < 1e-4, "{f} against {expected}");
    let f_avg = energy::schlick_fresnel_average(c);
    let k_m = Vec3A::new(
        energy::compensation(&mf, 1.0, f_avg.x),
        energy::compensation(&mf, 1.0, f_avg.y),
        energy::compensation(&mf, 1.0, f_avg.z),
    );
    let metal = c * k_m / (4.0 * PI * alpha * alpha);
    let f = bsdf(&principled(c, metal_rough(1.0, r))).eval(n, n);
    assert!((f - metal).abs().max_element() < 1e-4, "{f} against {metal}");
    // A clear coat of strength k reflects k F(1.5) = 0.04 k, and lets 1 − 0.04 k through.
    let coated = principled(
        c,
        Principled {
            clearcoat: 0.5,
            clearcoat_roughness: r,
            ..metal_rough(1.0, r)
        },
    );
    let f = bsdf(&coated).eval(n, n);
    let expected = metal * 0.98 + Vec3A::splat(0.02 / (4.0 * PI * alpha * alpha));
    assert!((f - expected).abs().max_element() < 1e-4, "{f} against {expected}");
}

#[test]
fn compensated_principled_metal_keeps_all_the_light_and_dielectrics_stay_below_one() {
    // White furnace (Kulla & Conty 2017): a white rough metal reflects
    // everything from every direction once its multiple scattering is
    // given back; single scattering alone loses up to 60 % at roughness 1.
    let mut rng = Rng::new(23, Domain::Analysis, 0, 0);
    for roughness in [0.3, 0.6, 1.0] {
        let metal = principled(Vec3A::ONE, metal_rough(1.0, roughness));
        let metal = bsdf(&metal);
        for wo in [
            direction(0.0, 0.0),
            direction(0.8, 0.5),
            direction(1.3, 1.0),
            direction(1.5, 2.0),
        ] {
            let (a, sigma) = albedo(&metal, wo, &mut rng);
            assert!(
                (a - Vec3A::ONE).abs().max_element() < 0.015 + 4.0 * sigma,
                "white metal {roughness} from {wo}: {a} (σ {sigma})"
            );
        }
        // A white dielectric: the base takes what the layer leaves, so the
        // sum stays within 1 and close to it (the base's reciprocal albedo
        // scaling keeps a little back at grazing angles).
        let dielectric = principled(Vec3A::ONE, metal_rough(0.0, roughness));
        let dielectric = bsdf(&dielectric);
        for wo in [direction(0.0, 0.0), direction(0.8, 0.5), direction(1.3, 1.0)] {
            let (a, sigma) = albedo(&dielectric, wo, &mut rng);
            assert!(
                a.max_element() <= 1.0 + 4.0 * sigma + 2e-3 && a.min_element() > 0.85,
                "white dielectric {roughness} from {wo}: {a} (σ {sigma})"
            );
        }
    }
}

#[test]
fn smooth_principled_glass_and_mirror_keep_all_the_light() {
    let mut rng = Rng::new(19, Domain::Analysis, 0, 0);
    let glass = principled(
        Vec3A::ONE,
        Principled {
            transmission: 1.0,
            thin: false,
            ..metal_rough(0.0, 0.0)
        },
    );
    let thin = principled(
        Vec3A::ONE,
        Principled {
            transmission: 1.0,
            ..metal_rough(0.0, 0.0)
        },
    );
    let mirror = principled(Vec3A::ONE, metal_rough(1.0, 0.0));
    for (name, m) in [("glass", glass), ("thin", thin), ("mirror", mirror)] {
        let b = Bsdf::for_material(&m, FresnelModel::Exact, Transport::Importance);
        assert!(b.is_delta(), "{name}");
        for wo in [direction(0.4, 0.0), direction(1.2, 1.0)] {
            let (a, _) = albedo(&b, wo, &mut rng);
            assert!((a - Vec3A::ONE).abs().max_element() < 1e-3, "{name} from {wo}: {a}");
        }
    }
}

#[test]
fn reflection_is_reciprocal() {
    let mut rng = Rng::new(11, Domain::Analysis, 0, 0);
    let materials = [
        report(0.4, 0.5, 20.0, ShadingModel::Phong),
        report(0.3, 0.6, 40.0, ShadingModel::BlinnPhong),
        gold(0.3),
        beckmann(gold(0.3)),
        beckmann(glass(0.4)),
        plastic(0.7),
        rough_plastic(0.7, 0.2, false),
        beckmann(rough_plastic(0.7, 0.4, true)),
        anisotropic(gold(0.1), 0.4),
        beckmann(anisotropic(gold(0.4), 0.1)),
        glass(0.4),
    ];
    for m in &materials {
        let b = bsdf(m);
        for _ in 0..2000 {
            let a = caustic::math::sampling::cosine_hemisphere(rng.vec2());
            let c = caustic::math::sampling::cosine_hemisphere(rng.vec2());
            let (f1, f2) = (b.eval(a, c), b.eval(c, a));
            assert!(
                (f1 - f2).abs().max_element() <= 1e-4 * f1.max_element().max(1.0),
                "{}: f({a}, {c}) = {f1} but f({c}, {a}) = {f2}",
                m.name
            );
        }
    }
}

/// Mean of `weight()` over many samples: the directional albedo.
fn albedo(b: &Bsdf, wo: Vec3A, rng: &mut Rng) -> (Vec3A, f32) {
    let n = 200_000;
    let mut sum = Vec3A::ZERO;
    let mut sum2 = 0.0f64;
    for _ in 0..n {
        if let Some(s) = b.sample(wo, rng.f32(), rng.vec2()) {
            let w = s.weight();
            sum += w;
            sum2 += (w.max_element() as f64).powi(2);
        }
    }
    let mean = sum / n as f32;
    let var = (sum2 / n as f64 - (mean.max_element() as f64).powi(2)).max(0.0);
    (mean, (var / n as f64).sqrt() as f32)
}

#[test]
fn no_bsdf_reflects_more_than_it_receives() {
    let mut rng = Rng::new(13, Domain::Analysis, 0, 0);
    let mut white_mirror = report(0.0, 0.0, 1.0, ShadingModel::Phong);
    white_mirror.mirror = Some(Mirror {
        reflectivity: 1.0,
        tint: Vec3A::ONE,
    });
    let cases = [
        ("lambert 1", Material::diffuse("d", Vec3A::ONE)),
        ("phong 0.5+0.5 n=1", report(0.5, 0.5, 1.0, ShadingModel::Phong)),
        ("phong 0+1 n=50", report(0.0, 1.0, 50.0, ShadingModel::Phong)),
        ("blinn 0+1 n=2", report(0.0, 1.0, 2.0, ShadingModel::BlinnPhong)),
        ("blinn 0.3+0.7 n=200", report(0.3, 0.7, 200.0, ShadingModel::BlinnPhong)),
        ("mirror", white_mirror),
        ("rough gold", gold(0.5)),
        ("beckmann gold", beckmann(gold(0.5))),
        ("plastic white", plastic(1.0)),
        ("rough plastic white", rough_plastic(1.0, 0.3, false)),
        ("rough plastic white, nonlinear", rough_plastic(1.0, 0.05, true)),
        ("beckmann rough plastic white", beckmann(rough_plastic(1.0, 0.6, false))),
        ("anisotropic gold", anisotropic(gold(0.1), 0.5)),
    ];
    let cases = cases
        .into_iter()
        .chain(principled_cases(Vec3A::ONE))
        .collect::<Vec<_>>();
    for (name, m) in &cases {
        let b = bsdf(m);
        for wo in outgoing().into_iter().chain([direction(1.5, 0.0)]) {
            let (a, sigma) = albedo(&b, wo, &mut rng);
            assert!(
                a.max_element() <= 1.0 + 4.0 * sigma + 2e-3,
                "{name} from {wo}: albedo {a} (σ {sigma})"
            );
        }
    }
    // Mitsuba's `principled` adds its lobes without layering them (Burley's
    // model: a white matte base reflects 1.04 head-on and more at grazing
    // angles, a clear coat adds on top), so only its metal and its glass
    // are bound by 1.
    let white_metal = disney(
        Vec3A::ONE,
        Disney {
            roughness: 0.5,
            anisotropic: 0.8,
            metallic: 1.0,
            ..Disney::default()
        },
    );
    let white_glass = disney(
        Vec3A::ONE,
        Disney {
            roughness: 0.3,
            spec_trans: 1.0,
            eta: 1.5,
            ..Disney::default()
        },
    );
    for (name, m) in [("disney white metal", white_metal), ("disney white glass", white_glass)] {
        let b = Bsdf::for_material(&m, FresnelModel::Exact, Transport::Importance);
        for wo in outgoing()
            .into_iter()
            .chain([direction(1.5, 0.0), direction(PI - 0.4, 1.0)])
        {
            let (a, sigma) = albedo(&b, wo, &mut rng);
            assert!(
                a.max_element() <= 1.0 + 4.0 * sigma + 2e-3,
                "{name} from {wo}: albedo {a} (σ {sigma})"
            );
        }
    }
    // Glass: reflected + transmitted power is all of it (importance
    // transport: radiance scaling across the interface is not energy).
    for roughness in [0.0, 0.3] {
        let glass = glass(roughness);
        let b = Bsdf::for_material(&glass, FresnelModel::Exact, Transport::Importance);
        for wo in [direction(0.4, 0.0), direction(PI - 0.3, 0.0)] {
            let (a, sigma) = albedo(&b, wo, &mut rng);
            assert!(
                a.max_element() <= 1.0 + 4.0 * sigma + 2e-3,
                "glass {roughness} from {wo}: {a}"
            );
            if roughness == 0.0 {
                assert!((a.x - 1.0).abs() < 1e-3, "smooth glass loses energy: {a}");
            }
        }
    }
}

#[test]
fn a_thin_sheet_reflects_the_series_of_its_faces_and_transmits_the_rest_straight() {
    let m = thin_glass();
    let b = bsdf(&m);
    for wo in [direction(0.2, 0.3), direction(1.3, 2.0), direction(PI - 0.7, 1.0)] {
        let r1 = caustic::bsdf::fresnel::dielectric(wo.z.abs(), 1.5).0;
        let t1 = 1.0 - r1;
        let r = r1 + t1 * t1 * r1 / (1.0 - r1 * r1);
        let (mut reflected, mut transmitted) = (0.0f32, 0.0f32);
        let n = 20_000;
        for i in 0..n {
            let s = b
                .sample(wo, (i as f32 + 0.5) / n as f32, Vec3A::ZERO.truncate())
                .expect("sheets scatter");
            assert!(s.delta && s.eta == 1.0);
            if s.transmission {
                // Unbent, tinted, with all the light that is not reflected.
                assert!((s.wi + wo).length() < 1e-6, "{} from {wo}", s.wi);
                assert!((s.weight() - Vec3A::new(1.0, 0.8, 0.6)).abs().max_element() < 1e-5);
                transmitted += 1.0;
            } else {
                assert!((s.wi - Vec3A::new(-wo.x, -wo.y, wo.z)).length() < 1e-6);
                assert!((s.weight() - Vec3A::ONE).abs().max_element() < 1e-5);
                reflected += 1.0;
            }
        }
        assert!(
            (reflected / n as f32 - r).abs() < 1e-3,
            "{wo}: {} against {r}",
            reflected / n as f32
        );
        assert!((transmitted / n as f32 - (1.0 - r)).abs() < 1e-3);
    }
}
