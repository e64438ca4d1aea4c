//! Case 7: chains of total internal reflection, and full renders in which
//! NaN and infinity must never reach the film.
//!
//! **Chains.** Rays start inside a glass object (IOR 1.5) in directions that
//! meet every wall beyond the critical angle (41.8°): in an analytic sphere
//! at distance 0.75–0.95 r from the centre (the incidence angle is the same
//! at every bounce), and in a slab (a 4 × 0.2 × 4 box mesh) with every
//! direction component of magnitude 0.48–0.68 < cos 41.8°. Each chain
//! follows `DielectricInterface::at` (the integrator's glass) for 200
//! bounces, spawning with `offset_ray_origin`. **Failure:** a bounce that
//! finds no hit or another object (the ray escaped through the wall), that
//! refracts (the trapped angle drifted below critical), or a non-finite
//! point or direction.
//!
//! **Depth limit.** `Whitted::radiance` on trapped rays in the glass sphere
//! with `max_depth = 100` must recurse exactly 100 times (one reflected ray
//! per bounce under TIR) and return a finite radiance. **Failure:** another
//! number of secondary rays, or a non-finite result.
//!
//! **Renders.** `scenes/test/glass.toml` (glass sphere: refraction, Fresnel,
//! TIR) with `max_depth = 64`, spread sampling (one Fresnel branch per
//! sample, so paths are chains rather than trees) and a small photon pass, then the same scene
//! with injected NaN sources: a smooth glass mesh whose per-vertex normals
//! are zero, NaN, or alternately opposed (written past `Mesh::new`'s
//! validation); spheres with IOR 0, 1e-30, 1e30, ∞ and NaN; an area light of
//! radiance `f32::MAX` (a pixel's sum of finite samples overflows to ∞: the
//! render loop now clamps each sample at
//! `render::SAMPLE_RADIANCE_LIMIT`, so a `u32` count of samples cannot overflow) and one of radiance NaN. **Failure:** a non-finite film
//! pixel; in the clean scene, also any dropped sample (a clean scene must not
//! produce NaN). Dropped samples of the injected scenes are reported: they
//! show the guard of the render loop at work.

use super::{box_mesh, guarded, random_unit, scene_of, share, tally, trial_rng, unavailable_row};
use super::{Backend, Role, StressOptions, StressRow, Tally};
use crate::accel::{self, Accel, AccelKind, AccelOptions};
use crate::bsdf::DielectricInterface;
use crate::geometry::generate::icosphere;
use crate::integrator::photon::SiteCache;
use crate::integrator::render::render;
use crate::integrator::{Integrator, RayCounts, RenderPlan, RenderSetup, SampleContext, Whitted};
use crate::math::{offset_ray_origin, Ray, Rng, Transform, Vec3, Vec3A};
use crate::scene::{Dielectric, Light, LoadedScene, Material, Object, RenderSettings, Scene, Shape, Sphere};
use std::path::Path;
use std::sync::Arc;

const CASE: u64 = 7;
/// Bounces per chain.
pub const CHAIN_BOUNCES: u32 = 200;
/// `max_depth` of the depth-limit check.
pub const DEPTH_LIMIT: u32 = 100;

fn glass(ior: f32) -> Material {
    Material {
        dielectric: Some(Dielectric::smooth(ior, Vec3A::ONE)),
        ..Material::diffuse("glass", Vec3A::ZERO)
    }
}

/// The glass sphere (object 0) or slab (object 0), alone.
fn trap_scene(slab: bool) -> Scene {
    if slab {
        scene_of(
            vec![Arc::new(box_mesh(
                Vec3::new(-2.0, -0.1, -2.0),
                Vec3::new(2.0, 0.1, 2.0),
            ))],
            vec![(
                Shape::Mesh {
                    mesh: 0,
                    transform: Transform::IDENTITY,
                    smooth: false,
                },
                0,
            )],
            vec![glass(1.5)],
        )
    } else {
        scene_of(
            vec![],
            vec![(
                Shape::Sphere(Sphere {
                    center: Vec3A::ZERO,
                    radius: 1.0,
                }),
                0,
            )],
            vec![glass(1.5)],
        )
    }
}

/// A trapped ray for trial `i`.
fn trapped_ray(slab: bool, rng: &mut Rng) -> Ray {
    if slab {
        let sign = |rng: &mut Rng| if rng.f32() < 0.5 { -1.0 } else { 1.0 };
        let d = Vec3A::new(
            sign(rng) * (1.0 + 0.3 * rng.f32()),
            sign(rng) * (1.0 + 0.3 * rng.f32()),
            sign(rng) * (1.0 + 0.3 * rng.f32()),
        )
        .normalize();
        let o = Vec3A::new(3.8 * rng.f32() - 1.9, 0.18 * rng.f32() - 0.09, 3.8 * rng.f32() - 1.9);
        Ray::new(o, d)
    } else {
        let e = random_unit(rng);
        let d = e.any_orthonormal_vector();
        let f = e.cross(d);
        let a = std::f32::consts::TAU * rng.f32();
        let d = d * a.cos() + f * a.sin();
        Ray::new(e * (0.75 + 0.2 * rng.f32()), d)
    }
}

/// One chain: `extra` `[escaped, refracted, non-finite]`.
fn chain(scene: &Scene, accel: &dyn Accel, mut ray: Ray) -> Tally {
    let mut extra = [0u64; 6];
    for _ in 0..CHAIN_BOUNCES {
        let Some(hit) = accel.intersect(&ray, f32::INFINITY) else {
            extra[0] += 1;
            break;
        };
        let si = scene.surface_interaction(&ray, &hit);
        if !(si.p.is_finite() && si.ng.is_finite() && hit.t.is_finite()) {
            extra[2] += 1;
            break;
        }
        let iface = DielectricInterface::at(ray.dir, &si, 1.5);
        if iface.refracted.is_some() {
            extra[1] += 1;
            break;
        }
        // Under TIR all the light is reflected (Fresnel R = 1): the energy
        // check is the Whitted one below, on the radiance itself.
        let dir = iface.reflected.normalize_or_zero();
        if !dir.is_finite() || dir == Vec3A::ZERO {
            extra[2] += 1;
            break;
        }
        ray = Ray::new(offset_ray_origin(si.p, si.p_error, si.ng, dir), dir);
    }
    Tally {
        trials: 1,
        failures: u64::from(extra.iter().any(|&e| e > 0)),
        extra,
    }
}

/// Whitted on a trapped ray: `(secondary rays, radiance finite)`.
fn whitted_depth(scene: &Scene, accel: &dyn Accel, ray: &Ray, seed: u64, i: u64) -> (u64, bool) {
    let settings = RenderSettings {
        max_depth: Some(DEPTH_LIMIT),
        ..RenderSettings::default()
    };
    let plan = RenderPlan::new(scene, &settings);
    let integrator = Whitted::new(scene, accel, &plan);
    let mut counts = RayCounts::default();
    let mut ctx = SampleContext {
        rng: &mut crate::math::Sampler::independent(trial_rng(seed, CASE, 1 << 40 | i)),
        slot: 0,
        light_seed: 0,
        fresnel_stratum: None,
        counts: &mut counts,
        sites: &mut SiteCache::default(),
    };
    let l = integrator.radiance(ray, None, &mut ctx);
    (counts.secondary, l.is_finite())
}

fn chain_rows(options: &StressOptions) -> Vec<StressRow> {
    let mut rows = Vec::new();
    for (slab, name) in [(false, "sphere"), (true, "slab")] {
        let case = format!("7 TIR chains ({CHAIN_BOUNCES} bounces): {name}");
        let scene = trap_scene(slab);
        let role = Role::Default;
        for backend in Backend::defaults() {
            rows.extend(guarded(&case, backend.name(), role, || {
                let accel = match backend.build(&scene) {
                    Ok(a) => a,
                    Err(e) => return vec![unavailable_row(&case, backend, role, &e.to_string())],
                };
                let chains = (options.rays / CHAIN_BOUNCES as u64).max(1);
                let t = tally(chains, |i| {
                    let mut rng = trial_rng(options.seed, CASE, i * 2 + u64::from(slab));
                    chain(&scene, accel.as_ref(), trapped_ray(slab, &mut rng))
                });
                vec![
                    StressRow::new(&case, backend.name(), role, t.trials, t.failures).note(format!(
                        "{} chains failed — escaped {}, refracted {}, non-finite {}",
                        share(t.failures, t.trials),
                        t.extra[0],
                        t.extra[1],
                        t.extra[2]
                    )),
                ]
            }));
        }
    }
    let case = format!("7 Whitted depth limit (max_depth {DEPTH_LIMIT})");
    let mut scene = trap_scene(false);
    scene.lights.push(Light::Point {
        position: Vec3A::new(0.0, 5.0, 3.0),
        intensity: Vec3A::splat(10.0),
    });
    for backend in Backend::defaults() {
        rows.extend(guarded(&case, backend.name(), Role::Default, || {
            let accel = match backend.build(&scene) {
                Ok(a) => a,
                Err(e) => return vec![unavailable_row(&case, backend, Role::Default, &e.to_string())],
            };
            let n = (options.rays / DEPTH_LIMIT as u64).max(1);
            let t = tally(n, |i| {
                let mut rng = trial_rng(options.seed, CASE, 1 << 41 | i);
                let ray = trapped_ray(false, &mut rng);
                let (secondary, finite) = whitted_depth(&scene, accel.as_ref(), &ray, options.seed, i);
                let wrong_depth = secondary != DEPTH_LIMIT as u64;
                Tally {
                    trials: 1,
                    failures: u64::from(wrong_depth || !finite),
                    extra: [u64::from(wrong_depth), u64::from(!finite), 0, 0, 0, 0],
                }
            });
            vec![
                StressRow::new(&case, backend.name(), Role::Default, t.trials, t.failures).note(format!(
                    "{} — secondary-ray count ≠ {DEPTH_LIMIT}: {}, non-finite radiance: {}",
                    share(t.failures, t.trials),
                    t.extra[0],
                    t.extra[1]
                )),
            ]
        }));
    }
    rows
}

/// `scenes/test/glass.toml`, sized for the stress run.
pub fn glass_scene(width: u32) -> Result<LoadedScene, String> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/test/glass.toml");
    let mut loaded = crate::scene::load_scene(&path).map_err(|e| e.to_string())?;
    let s = &mut loaded.settings;
    s.width = width.max(8);
    s.height = (width * 3 / 4).max(6);
    s.max_depth = Some(64);
    // One branch per dielectric hit (spread sampling): with the scene's
    // split sampling every hit spawns both branches, 2^64 rays at this depth.
    s.sharing = crate::scene::SampleSharing::Spread;
    s.spp = s.spp.max(2);
    s.photons.count = (width as u64 * width as u64 * 2).max(1000);
    Ok(loaded)
}

/// Adds a smooth glass icosphere whose normals `corrupt` rewrites (past
/// `Mesh::new`'s validation, as a buggy loader or generator could).
fn with_corrupt_mesh(mut scene: Scene, corrupt: impl Fn(usize, &mut Vec3)) -> Scene {
    let mut mesh = icosphere(3);
    for (i, n) in mesh.normals.iter_mut().enumerate() {
        corrupt(i, n);
    }
    let glass_index = scene.materials.len() as u32;
    scene.materials.push(glass(1.5));
    scene.meshes.push(Arc::new(mesh));
    scene.objects.push(Object {
        name: "corrupt glass mesh".into(),
        shape: Shape::Mesh {
            mesh: (scene.meshes.len() - 1) as u32,
            transform: Transform::from_srt(Vec3::splat(0.6), Vec3::ZERO, Vec3::new(-1.4, 0.8, 0.8))
                .expect("invertible"),
            smooth: true,
        },
        material: glass_index,
    });
    scene
}

/// The injected scenes: `(name, scene)`.
fn injected(base: &Scene) -> Vec<(&'static str, Scene)> {
    let mut out = vec![
        (
            "zero vertex normals",
            with_corrupt_mesh(base.clone(), |i, n| {
                if i % 2 == 0 {
                    *n = Vec3::ZERO
                }
            }),
        ),
        (
            "NaN vertex normals",
            with_corrupt_mesh(base.clone(), |i, n| {
                if i % 3 == 0 {
                    *n = Vec3::splat(f32::NAN)
                }
            }),
        ),
        (
            "opposed vertex normals",
            with_corrupt_mesh(base.clone(), |i, n| {
                if i % 2 == 1 {
                    *n = -*n
                }
            }),
        ),
    ];
    let mut iors = base.clone();
    for (k, ior) in [0.0, 1e-30, 1e30, f32::INFINITY, f32::NAN].into_iter().enumerate() {
        let m = iors.materials.len() as u32;
        iors.materials.push(glass(ior));
        iors.objects.push(Object {
            name: format!("sphere ior {ior}"),
            shape: Shape::Sphere(Sphere {
                center: Vec3A::new(-2.0 + k as f32, 0.3, 1.5),
                radius: 0.3,
            }),
            material: m,
        });
    }
    out.push(("IOR 0, 1e-30, 1e30, inf, NaN", iors));
    let mut hot = base.clone();
    for l in &mut hot.lights {
        if let Light::Area(a) = l {
            a.radiance = Vec3A::splat(f32::MAX);
        }
    }
    out.push(("area light radiance f32::MAX", hot));
    let mut nan = base.clone();
    for l in &mut nan.lights {
        if let Light::Area(a) = l {
            a.radiance = Vec3A::splat(f32::NAN);
        }
    }
    out.push(("area light radiance NaN", nan));
    out
}

/// Renders the injected scene called `name` (as in the table, e.g.
/// `"area light radiance f32::MAX"`) at `width`: `(non-finite film pixels,
/// dropped samples, samples)`.
pub fn render_injected(name: &str, width: u32) -> Result<(u64, u64, u64), String> {
    let base = glass_scene(width)?;
    let (_, scene) = injected(&base.scene)
        .into_iter()
        .find(|(n, _)| *n == name)
        .ok_or_else(|| format!("no injected scene '{name}'"))?;
    render_counts(&scene, &base.settings)
}

/// Renders `scene` with the default accelerator: `(non-finite film pixels, dropped, samples)`.
fn render_counts(scene: &Scene, settings: &RenderSettings) -> Result<(u64, u64, u64), String> {
    let accel = accel::build(scene, AccelKind::default_kind(), &AccelOptions::default()).map_err(|e| e.to_string())?;
    let plan = RenderPlan::new(scene, settings);
    let out = render(scene, accel.as_ref(), &plan, RenderSetup::default());
    let bad = out.film.pixels.iter().filter(|p| !p.is_finite()).count() as u64;
    Ok((bad, out.stats.dropped_samples, out.stats.samples))
}

fn render_rows(options: &StressOptions) -> Vec<StressRow> {
    let config = format!("render, {}", AccelKind::default_kind().name());
    let base = match glass_scene(options.render_width) {
        Ok(s) => s,
        Err(e) => {
            return vec![
                StressRow::new("7 render glass.toml", config, Role::Measured, 0, 0).note(format!("skipped: {e}"))
            ]
        }
    };
    let mut rows = Vec::new();
    let settings = &base.settings;
    let mut scenes = vec![("glass.toml (clean)", base.scene.clone())];
    scenes.extend(injected(&base.scene));
    for (k, (name, scene)) in scenes.iter().enumerate() {
        let case = format!("7 render glass.toml: {name}");
        let clean = k == 0;
        rows.extend(guarded(&case, &config, Role::Default, || {
            match render_counts(scene, settings) {
                Err(e) => vec![StressRow::new(&case, &config, Role::Default, 0, 1).note(e)],
                Ok((bad, dropped, samples)) => {
                    let failures = bad + if clean { dropped } else { 0 };
                    let pixels = (settings.width * settings.height) as u64;
                    vec![
                        StressRow::new(&case, &config, Role::Default, pixels, failures).note(format!(
                            "non-finite pixels {bad}; dropped samples {} of {samples}{}",
                            dropped,
                            if clean { "" } else { " (counted, never on the film)" }
                        )),
                    ]
                }
            }
        }));
    }
    rows
}

/// The rows of case 7.
pub fn run(options: &StressOptions) -> Vec<StressRow> {
    let mut rows = chain_rows(options);
    rows.extend(render_rows(options));
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trapped_rays_are_beyond_the_critical_angle() {
        let critical_cos = (1.0f32 - 1.0 / 2.25).sqrt();
        let mut rng = trial_rng(0, 77, 0);
        for _ in 0..200 {
            let r = trapped_ray(false, &mut rng);
            // Sphere: sin θ = h / r with h the distance of the line to the centre.
            let h = (r.origin - r.dir * r.origin.dot(r.dir)).length();
            assert!(h > 0.7 && h < 0.96 && h > 1.0 / 1.5);
            let s = trapped_ray(true, &mut rng);
            assert!(s.dir.abs().max_element() < critical_cos, "{}", s.dir);
        }
    }
}
