//! Cases 2 and 3: rays spawned from hit points, as the integrator spawns
//! them, at log-uniform scene scales 1e-4 … 1e5 (case 2) and in a scene
//! translated 1e5 from the origin (case 3, which also checks that shadow
//! rays cannot leak out of a closed box through its edges and corners).
//!
//! # The scene
//!
//! At scale `s` and offset `T`: an analytic sphere of radius `s`, a floor
//! quad of side `12s`, an icosphere (3 subdivisions) and a torus, both mesh
//! instances with smooth normals placed by a `Transform` (scale `s`, a
//! rotation, translation `T + …`). Case 2 uses ten scales: exactly 1e-4 and
//! 1e5, and one log-uniform draw in each decade between.
//!
//! # The rays
//!
//! Primary rays start `4–8 s` from an object and aim at a random point of it
//! (grazing incidences included). At the hit, `Scene::surface_interaction`
//! gives the point, its error bound and normals, and four rays leave from
//! `offset_ray_origin(p, p_error, ng, dir)` exactly as in the Whitted
//! integrator: the reflected and the refracted direction of
//! `DielectricInterface::at` (IOR 1.5, the integrator's own glass code), and
//! two shadow rays toward point-light positions on the incident side — one
//! uniform over the hemisphere, one grazing at 1e-6–1e-1 rad above the
//! tangent plane — tested on `t < dist·(1 − SHADOW_EPSILON)`. As in the
//! integrator, a light that rounding puts on or below the tangent plane
//! (far from the origin, positions are rounded to 0.008) casts no shadow ray.
//!
//! **Failure (false re-hit):** the spawned ray's closest hit is on the
//! object it leaves and is not a hit of the exact ray:
//! - on a flat primitive (a triangle or the quad) it just left, within half
//!   the object's size (`0.5 s`): a ray cannot meet its own plane again;
//! - on another triangle of the convex icosphere within `0.5 s`, for a ray
//!   leaving it to the outside (`dir · ng > 0`, outward winding): a ray
//!   leaving a convex solid outward never meets it again. A ray leaving it
//!   inward must meet it again, so that hit is not judged here;
//! - on the analytic sphere, at any `t`, when the exact ray does not meet
//!   the sphere there. The reference is computed in f64 from the f32 spawned
//!   origin `o` and direction (as case 6): from `|o − c| < r` the ray must
//!   leave through the exit root `t₊`; from outside it can only enter at
//!   `t₋ > 0`, and a ray moving away (`t₋ ≤ 0`, always the case for a ray
//!   leaving the outer side) must not hit at all. The hit must lie within
//!   case 6's tolerance `√(2r·band)/|d| + 1e-5 t` of that root, with `band =
//!   1e-6 r + 8ε|o − c|`.
//!
//! Why the sphere is judged exactly rather than by distance: primary origins
//! are drawn `4–8 s` from the *target's* centre, and the sphere is `3 s` from
//! the icosphere's, so some start inside the sphere and hit its inner side.
//! A shadow ray from there toward a light on the incident side goes into the
//! sphere and must hit its far side at the chord `2r·sin α`, where `α` is its
//! angle to the tangent plane; the grazing shadow rays (`α` down to 1e-6 rad)
//! make that chord arbitrarily short, so a "no re-hit within `0.5 s`" rule
//! would count these correct hits (exit roots of origins inside the sphere,
//! as a replay in f64 confirms) as failures.
//!
//! For shadow rays, an `occluded` answer that disagrees with the closest hit
//! below `t_max` also fails. A non-finite hit point, error bound or normal
//! fails too.
//!
//! # Leaks (case 3)
//!
//! A closed box of side `2` at `T` (six quads sharing their edges exactly,
//! or a 12-triangle mesh instance translated by `T`). From a point on an
//! inner wall (the hit of a ray from inside), a shadow ray goes toward a
//! light outside the box, placed beyond a point on an edge or a corner of
//! the box (or, one time in four, a face) not on the starting wall; as in
//! the integrator, lights behind the starting wall's plane get no shadow ray.
//! **Failure (leak):** `occluded` says the light is visible.
//!
//! The light must be strictly outside the closed box (checked exactly, in
//! f64, on the f32 position used); other trials are skipped. At 1e5 the f32
//! spacing is `2⁻⁷`, so a hit within `2⁻⁸` of an edge is rounded exactly
//! onto it, and the starting point then also lies on the neighbouring face;
//! a target on that face puts the whole segment, light included, *in* the
//! face: the light is on the box's surface, not outside, and a segment lying
//! in a face's plane meets no surface (a coplanar ray has no crossing; the
//! triangle and quad tests, like pbrt-v4's and Embree's, report none). Those
//! trials were the rare "leaks through faces" (3 of 200 000, every backend);
//! replayed, each had its light exactly on the face (`|light − c|∞ = 1`).

use super::{box_mesh, Backend, Role, StressOptions, StressRow, Tally};
use super::{guarded, log_uniform, random_unit, scene_of, share, tally, trial_rng, unavailable_row};
use crate::accel::{Accel, Hit};
use crate::bsdf::DielectricInterface;
use crate::geometry::generate::{icosphere, torus};
use crate::integrator::whitted::SHADOW_EPSILON;
use crate::math::{offset_ray_origin, Ray, Rng, Transform, Vec3, Vec3A};
use crate::scene::{Quad, Scene, Shape, Sphere, SurfaceInteraction};
use glam::DVec3;
use std::sync::Arc;

const CASE_SCALES: u64 = 2;
const CASE_TRANSLATED: u64 = 3;
const CASE_LEAK: u64 = 33;

/// What the failure test needs to know about an object.
#[derive(Clone, Copy, Debug)]
struct Target {
    /// Centre of the object (world).
    center: Vec3A,
    /// Its size `s`: re-hits closer than `0.5 s` are suspect.
    size: f32,
    /// Convex: a ray leaving its surface outward cannot hit it again.
    convex: bool,
    /// For the quad: its corner and edges, to aim at points of it.
    quad: Option<Quad>,
}

/// The test scene at scale `s`, offset `offset`.
fn spawn_scene(s: f32, offset: Vec3) -> (Scene, Vec<Target>) {
    let at = |x: f32, y: f32, z: f32| Vec3A::from(offset) + Vec3A::new(x, y, z) * s;
    let sphere = Sphere {
        center: at(-3.0, 1.0, 0.0),
        radius: s,
    };
    let floor = Quad::new(at(-6.0, 0.0, -6.0), Vec3A::Z * (12.0 * s), Vec3A::X * (12.0 * s)).expect("valid quad");
    let ico = Transform::from_srt(
        Vec3::splat(s),
        Vec3::new(17.0, 33.0, 5.0),
        offset + Vec3::new(0.0, 1.0, 0.0) * s,
    )
    .expect("invertible");
    let tor = Transform::from_srt(
        Vec3::splat(s),
        Vec3::new(60.0, 10.0, 20.0),
        offset + Vec3::new(3.0, 1.2, 0.0) * s,
    )
    .expect("invertible");
    let scene = scene_of(
        vec![Arc::new(icosphere(3)), Arc::new(torus(1.0, 0.35, 48, 24))],
        vec![
            (Shape::Sphere(sphere), 0),
            (Shape::Quad(floor), 0),
            (
                Shape::Mesh {
                    mesh: 0,
                    transform: ico,
                    smooth: true,
                },
                0,
            ),
            (
                Shape::Mesh {
                    mesh: 1,
                    transform: tor,
                    smooth: true,
                },
                0,
            ),
        ],
        vec![],
    );
    let targets = vec![
        Target {
            center: sphere.center,
            size: s,
            convex: true,
            quad: None,
        },
        Target {
            center: at(0.0, 0.0, 0.0),
            size: s,
            convex: true,
            quad: Some(floor),
        },
        Target {
            center: at(0.0, 1.0, 0.0),
            size: s,
            convex: true,
            quad: None,
        },
        Target {
            center: at(3.0, 1.2, 0.0),
            size: s,
            convex: false,
            quad: None,
        },
    ];
    (scene, targets)
}

fn finite_si(si: &SurfaceInteraction) -> bool {
    si.p.is_finite() && si.p_error.is_finite() && si.ng.is_finite() && si.ns.is_finite()
}

/// Index of the failure kinds in `Tally::extra`.
const REFLECT: usize = 0;
const REFRACT: usize = 1;
const LIGHT: usize = 2;
const NAN: usize = 3;

/// One primary ray and the rays spawned at its hit.
fn spawn_trial(scene: &Scene, targets: &[Target], accel: &dyn Accel, rng: &mut Rng, k: usize) -> Tally {
    let target = targets[k];
    let s = target.size;
    let origin = target.center + random_unit(rng) * (4.0 * s * (1.0 + rng.f32()));
    let aim = match target.quad {
        Some(q) => q.corner + q.u * (rng.f32() * 1.1 - 0.05) + q.v * (rng.f32() * 1.1 - 0.05),
        None => target.center + random_unit(rng) * (1.3 * s * rng.f32().sqrt()),
    };
    let dir = (aim - origin).normalize_or_zero();
    let mut t = Tally::default();
    if dir == Vec3A::ZERO {
        return t;
    }
    let ray = Ray::new(origin, dir);
    let Some(hit) = accel.intersect(&ray, f32::INFINITY) else {
        return t;
    };
    let si = scene.surface_interaction(&ray, &hit);
    if !finite_si(&si) || !hit.t.is_finite() {
        t.trials += 1;
        t.failures += 1;
        t.extra[NAN] += 1;
        return t;
    }
    let hit_target = targets[hit.instance as usize];
    let left_shape = &scene.objects[hit.instance as usize].shape;
    // A false re-hit of the object the spawned ray `r` leaves (module docs).
    let is_rehit = |r: &Ray, h: &Hit| {
        if h.instance != hit.instance {
            return false;
        }
        match left_shape {
            Shape::Sphere(sphere) => !exact_sphere_hit(sphere, r, h.t),
            _ => {
                let outward = r.dir.dot(si.ng) > 0.0;
                (h.prim == hit.prim || (hit_target.convex && outward)) && h.t < 0.5 * hit_target.size
            }
        }
    };
    let check = |dir: Vec3A, kind: usize, t: &mut Tally| {
        let dir = dir.normalize_or_zero();
        if dir == Vec3A::ZERO || !dir.is_finite() {
            t.trials += 1;
            t.failures += 1;
            t.extra[NAN] += 1;
            return;
        }
        let o = offset_ray_origin(si.p, si.p_error, si.ng, dir);
        let spawned = Ray::new(o, dir);
        let h = accel.intersect(&spawned, f32::INFINITY);
        t.trials += 1;
        if h.is_some_and(|h| !h.t.is_finite() || is_rehit(&spawned, &h)) {
            t.failures += 1;
            t.extra[kind] += 1;
        }
    };
    let iface = DielectricInterface::at(ray.dir, &si, 1.5);
    check(iface.reflected, REFLECT, &mut t);
    if let Some((refracted, _, _)) = iface.refracted {
        check(refracted, REFRACT, &mut t);
    }
    // Shadow rays toward point lights on the incident side.
    let wn = if si.ng.dot(ray.dir) > 0.0 { -si.ng } else { si.ng };
    let uniform = {
        let w = random_unit(rng);
        if w.dot(wn) < 0.0 {
            -w
        } else {
            w
        }
    };
    let grazing = {
        let r = random_unit(rng);
        let tangent = (r - wn * r.dot(wn)).normalize_or(wn.any_orthonormal_vector());
        let alpha = log_uniform(rng, -6.0, -1.0);
        tangent * alpha.cos() + wn * alpha.sin()
    };
    for w in [uniform, grazing] {
        let light = si.p + w * (s * (1.0 + 9.0 * rng.f32()));
        // As the integrator: a light that rounding put on or below the
        // tangent plane gets no shadow ray.
        if (light - si.p).dot(wn) <= 0.0 {
            continue;
        }
        let o = offset_ray_origin(si.p, si.p_error, si.ng, light - si.p);
        let to = light - o;
        let dist = to.length();
        t.trials += 1;
        if !(dist > 0.0 && dist.is_finite()) {
            t.failures += 1;
            t.extra[NAN] += 1;
            continue;
        }
        let shadow = Ray::new(o, to / dist);
        let t_max = dist * (1.0 - SHADOW_EPSILON);
        let closest = accel.intersect(&shadow, t_max);
        let occluded = accel.occluded(&shadow, t_max);
        if closest.is_some_and(|h| is_rehit(&shadow, &h)) || occluded != closest.is_some() {
            t.failures += 1;
            t.extra[LIGHT] += 1;
        }
    }
    t
}

/// True when a hit at `t` on `sphere` is a hit of the exact ray: computed in
/// f64 from the f32 ray actually traced, the ray starts inside and `t` is its
/// exit root, or it starts outside, enters ahead and `t` is its entry root,
/// within case 6's tolerance (module docs). A ray leaving the outer side
/// moves away from the sphere and has no root ahead: any hit is false.
fn exact_sphere_hit(sphere: &Sphere, ray: &Ray, t: f32) -> bool {
    let o = ray.origin.as_dvec3();
    let d = ray.dir.as_dvec3();
    let c = sphere.center.as_dvec3();
    let r = sphere.radius as f64;
    let f: DVec3 = c - o;
    let dd = d.length_squared();
    let t_mid = f.dot(d) / dd;
    let h = (f - d * t_mid).length();
    let band = 1e-6 * r + 8.0 * f32::EPSILON as f64 * f.length();
    let half_chord = (r * r - h * h).max(0.0).sqrt() / dd.sqrt();
    let inside = f.length_squared() < r * r;
    let root = if inside {
        t_mid + half_chord
    } else if h < r + band && t_mid - half_chord > 0.0 {
        t_mid - half_chord
    } else {
        return false;
    };
    let tol = (2.0 * r * band).sqrt() / dd.sqrt() + 1e-5 * root;
    t.is_finite() && (t as f64 - root).abs() <= tol
}

/// Spawned-ray trials over several scenes; `(tally, failures per scene)`.
fn run_spawn(
    scenes: &[(Scene, Vec<Target>)],
    backend: Backend,
    n: u64,
    seed: u64,
    case: u64,
) -> Result<(Tally, Vec<u64>), String> {
    let mut total = Tally::default();
    let mut per_scene = Vec::new();
    let per = n.div_ceil(scenes.len() as u64).max(1);
    for (j, (scene, targets)) in scenes.iter().enumerate() {
        let accel = backend.build(scene).map_err(|e| e.to_string())?;
        let t = tally(per, |i| {
            let index = j as u64 * per + i;
            let mut rng = trial_rng(seed, case, index);
            spawn_trial(
                scene,
                targets,
                accel.as_ref(),
                &mut rng,
                (index % targets.len() as u64) as usize,
            )
        });
        per_scene.push(t.failures);
        total = total + t;
    }
    Ok((total, per_scene))
}

fn spawn_rows(
    case: &str,
    case_id: u64,
    scenes: &[(Scene, Vec<Target>)],
    labels: &[String],
    options: &StressOptions,
) -> Vec<StressRow> {
    let configs = [
        (Backend::KdWatertight, Role::Default),
        (Backend::Embree, Role::Default),
        (Backend::KdMoller, Role::Measured),
        (Backend::EmbreeRobust, Role::Measured),
    ];
    // About 4.5 spawned rays per primary ray.
    let primaries = (options.rays * 2 / 9).max(1);
    let mut rows = Vec::new();
    for (backend, role) in configs {
        if !backend.available() {
            rows.push(unavailable_row(case, backend, role, "not compiled in"));
            continue;
        }
        rows.extend(guarded(case, backend.name(), role, || {
            match run_spawn(scenes, backend, primaries, options.seed, case_id) {
                Err(e) => vec![unavailable_row(case, backend, role, &e)],
                Ok((t, per_scene)) => {
                    let failing: Vec<String> = per_scene
                        .iter()
                        .zip(labels)
                        .filter(|(f, _)| **f > 0)
                        .map(|(f, l)| format!("{l}: {f}"))
                        .collect();
                    let mut note = format!(
                        "{} — reflected {}, refracted {}, shadow {}, non-finite {}",
                        share(t.failures, t.trials),
                        t.extra[REFLECT],
                        t.extra[REFRACT],
                        t.extra[LIGHT],
                        t.extra[NAN]
                    );
                    if !failing.is_empty() {
                        note += &format!("; by scale {}", failing.join(", "));
                    }
                    vec![StressRow::new(case, backend.name(), role, t.trials, t.failures).note(note)]
                }
            }
        }));
    }
    rows
}

/// The scales of case 2: 1e-4, one log-uniform draw in each decade, 1e5.
pub fn scales(seed: u64) -> Vec<f32> {
    let mut rng = trial_rng(seed, CASE_SCALES, u64::MAX);
    let mut out = vec![1e-4f32];
    for decade in -4..4 {
        out.push(10f32.powf(decade as f32 + rng.f32()));
    }
    out.push(1e5);
    out
}

/// The rows of case 2.
pub fn run_scales(options: &StressOptions) -> Vec<StressRow> {
    let scales = scales(options.seed);
    let scenes: Vec<_> = scales.iter().map(|&s| spawn_scene(s, Vec3::ZERO)).collect();
    let labels: Vec<String> = scales.iter().map(|s| format!("{s:.1e}")).collect();
    spawn_rows(
        "2 self-intersection: 10 scales 1e-4..1e5",
        CASE_SCALES,
        &scenes,
        &labels,
        options,
    )
}

/// Offset of case 3.
pub const FAR: Vec3 = Vec3::new(1.0e5, 1.0e5, 1.0e5);

/// The rows of case 3.
pub fn run_translated(options: &StressOptions) -> Vec<StressRow> {
    let scenes = vec![spawn_scene(1.0, FAR)];
    let mut rows = spawn_rows(
        "3 translated 1e5: spawned rays",
        CASE_TRANSLATED,
        &scenes,
        &["1e5".to_string()],
        options,
    );
    rows.extend(leak_rows(options, FAR));
    rows
}

/// A closed box `[c − 1, c + 1]` of six quads (faces −x, +x, −y, +y, −z, +z).
fn quad_box(c: Vec3A) -> Scene {
    let (m, big) = (c - Vec3A::ONE, c + Vec3A::ONE);
    let (x, y, z) = (Vec3A::X * 2.0, Vec3A::Y * 2.0, Vec3A::Z * 2.0);
    let faces = [
        Quad::new(m, y, z),
        Quad::new(Vec3A::new(big.x, m.y, m.z), y, z),
        Quad::new(m, z, x),
        Quad::new(Vec3A::new(m.x, big.y, m.z), z, x),
        Quad::new(m, x, y),
        Quad::new(Vec3A::new(m.x, m.y, big.z), x, y),
    ];
    scene_of(
        vec![],
        faces
            .into_iter()
            .map(|q| (Shape::Quad(q.expect("valid quad")), 0))
            .collect(),
        vec![],
    )
}

/// The same box as a 12-triangle mesh instance translated by `c`.
fn mesh_box(c: Vec3) -> Scene {
    scene_of(
        vec![Arc::new(box_mesh(Vec3::splat(-1.0), Vec3::ONE))],
        vec![(
            Shape::Mesh {
                mesh: 0,
                transform: Transform::from_srt(Vec3::ONE, Vec3::ZERO, c).expect("invertible"),
                smooth: false,
            },
            0,
        )],
        vec![],
    )
}

/// Which face (0..6: −x, +x, −y, +y, −z, +z) a box hit is on.
fn box_face(scene: &Scene, hit: &Hit) -> usize {
    match scene.objects[hit.instance as usize].shape {
        Shape::Quad(_) => hit.instance as usize,
        _ => hit.prim as usize / 2,
    }
}

/// One leak trial: `(failed, kind)` with kind 0 edge, 1 corner, 2 face; `None` when no wall was hit.
fn leak_trial(scene: &Scene, accel: &dyn Accel, c: Vec3A, rng: &mut Rng) -> Option<(bool, usize)> {
    let start = c + random_unit(rng) * 0.5;
    let ray = Ray::new(start, random_unit(rng));
    let hit = accel.intersect(&ray, f32::INFINITY)?;
    let si = scene.surface_interaction(&ray, &hit);
    let face = box_face(scene, &hit);
    let (axis, side) = (face / 2, if face.is_multiple_of(2) { -1.0f32 } else { 1.0 });
    // A target on the box surface, off the starting face: coordinates in
    // {−1, +1} on the fixed axes, free in (−1, 1) on the others.
    let kind = match rng.below(4) {
        0 | 1 => 0,
        2 => 1,
        _ => 2,
    };
    let local = loop {
        let mut p = Vec3A::ZERO;
        let free = match kind {
            0 => rng.below(3) as usize,
            1 => 3,
            _ => usize::MAX,
        };
        let face_axis = rng.below(3) as usize;
        for a in 0..3 {
            let fixed = match kind {
                0 => a != free,
                1 => true,
                _ => a == face_axis,
            };
            p[a] = if fixed {
                if rng.f32() < 0.5 {
                    -1.0
                } else {
                    1.0
                }
            } else {
                rng.f32() * 2.0 - 1.0
            };
        }
        let on_start_face = p[axis] == side;
        if !on_start_face {
            break p;
        }
    };
    let target = c + local;
    let light = target + (target - si.p).normalize_or_zero() * (0.5 + 2.5 * rng.f32());
    // Only a light strictly outside the closed box must be occluded (module
    // docs: at 1e5 a start rounded onto an edge can put the light on a face).
    let outside = (light.as_dvec3() - c.as_dvec3()).abs().max_element() > 1.0;
    if !outside {
        return None;
    }
    // As the integrator: no shadow ray toward a light behind the wall
    // (the light can be beyond the starting wall's plane when the target is
    // on a neighbouring face).
    let wn = if si.ng.dot(ray.dir) > 0.0 { -si.ng } else { si.ng };
    if (light - si.p).dot(wn) <= 0.0 {
        return None;
    }
    let o = offset_ray_origin(si.p, si.p_error, si.ng, light - si.p);
    let to = light - o;
    let dist = to.length();
    let shadow = Ray::new(o, to / dist);
    let leak = !accel.occluded(&shadow, dist * (1.0 - SHADOW_EPSILON));
    Some((leak, kind))
}

fn leak_rows(options: &StressOptions, offset: Vec3) -> Vec<StressRow> {
    let c = Vec3A::from(offset);
    let boxes = [
        ("3 translated 1e5: shadow leaks, 6-quad box", quad_box(c), true),
        ("3 translated 1e5: shadow leaks, mesh box", mesh_box(offset), false),
    ];
    let mut rows = Vec::new();
    for (case, scene, quads) in &boxes {
        let configs: &[(Backend, Role)] = if *quads {
            &[(Backend::KdWatertight, Role::Default), (Backend::Embree, Role::Default)]
        } else {
            &[
                (Backend::KdWatertight, Role::Default),
                (Backend::EmbreeRobust, Role::Measured),
                (Backend::KdMoller, Role::Measured),
                (Backend::Embree, Role::Measured),
            ]
        };
        for &(backend, role) in configs {
            if !backend.available() {
                rows.push(unavailable_row(case, backend, role, "not compiled in"));
                continue;
            }
            rows.extend(guarded(case, backend.name(), role, || {
                let accel = match backend.build(scene) {
                    Ok(a) => a,
                    Err(e) => return vec![unavailable_row(case, backend, role, &e.to_string())],
                };
                let t = tally(options.rays, |i| {
                    let mut rng = trial_rng(options.seed, CASE_LEAK, i);
                    match leak_trial(scene, accel.as_ref(), c, &mut rng) {
                        None => Tally::default(),
                        Some((leak, kind)) => {
                            let mut extra = [0; 6];
                            extra[kind] = u64::from(leak);
                            Tally {
                                trials: 1,
                                failures: u64::from(leak),
                                extra,
                            }
                        }
                    }
                });
                vec![
                    StressRow::new(*case, backend.name(), role, t.trials, t.failures).note(format!(
                        "{} — through edges {}, corners {}, faces {}",
                        share(t.failures, t.trials),
                        t.extra[0],
                        t.extra[1],
                        t.extra[2]
                    )),
                ]
            }));
        }
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scales_span_1e_minus_4_to_1e5_log_uniformly() {
        let s = scales(0);
        assert_eq!(s.len(), 10);
        assert_eq!((s[0], s[9]), (1e-4, 1e5));
        for (k, v) in s[1..9].iter().enumerate() {
            let e = v.log10();
            assert!(e >= k as f32 - 4.0 - 1e-4 && e <= k as f32 - 3.0 + 1e-4, "{v}");
        }
    }

    #[test]
    fn sphere_rehits_are_judged_against_the_exact_ray() {
        let sphere = Sphere {
            center: Vec3A::new(1.0, 2.0, 3.0),
            radius: 2.0,
        };
        // From 1e-6 inside, grazing into the sphere at α = 1e-3 rad: the
        // exit is a chord of about 2r·sin α ≈ 4e-3 (4.8e-3 with the depth),
        // a correct short re-hit.
        let alpha = 1e-3f32;
        let p = sphere.center + Vec3A::Y * (2.0 - 1e-6);
        let into = Ray::new(p, Vec3A::new(alpha.cos(), -alpha.sin(), 0.0));
        let t = sphere.intersect(&into, f32::INFINITY).expect("exits");
        assert!((4e-3..6e-3).contains(&t), "{t}");
        assert!(exact_sphere_hit(&sphere, &into, t));
        // A far-off t for the same ray is not its exit.
        assert!(!exact_sphere_hit(&sphere, &into, 1e-8));
        assert!(!exact_sphere_hit(&sphere, &into, 3.0));
        // From just outside, leaving upward (even grazing): no root ahead,
        // so any hit is a false re-hit.
        let q = sphere.center + Vec3A::Y * (2.0 + 1e-6);
        let away = Ray::new(q, Vec3A::new(1.0, 1e-6, 0.0).normalize());
        assert!(!exact_sphere_hit(&sphere, &away, 1e-7));
        // From outside, aimed at the centre: the entry root.
        let at = Ray::new(sphere.center + Vec3A::X * 5.0, -Vec3A::X);
        assert!(exact_sphere_hit(&sphere, &at, 3.0));
        assert!(!exact_sphere_hit(&sphere, &at, 7.0));
    }

    #[test]
    fn leak_lights_are_strictly_outside_the_box() {
        // Far from the origin, every shadow ray of a leak trial goes to a
        // light strictly outside the box, and none leaks.
        let c = Vec3A::from(FAR);
        let scene = quad_box(c);
        let accel = Backend::BruteWatertight.build(&scene).unwrap();
        let mut trials = 0;
        for i in 0..3_000 {
            let mut rng = trial_rng(5, CASE_LEAK, i);
            if let Some((leak, _)) = leak_trial(&scene, accel.as_ref(), c, &mut rng) {
                trials += 1;
                assert!(!leak, "trial {i} leaks");
            }
        }
        assert!(trials > 2_000, "{trials}");
    }

    #[test]
    fn the_box_is_closed_for_rays_from_inside() {
        let scene = quad_box(Vec3A::ZERO);
        let accel = Backend::BruteWatertight.build(&scene).unwrap();
        let mut rng = trial_rng(1, 99, 0);
        for _ in 0..200 {
            let r = Ray::new(random_unit(&mut rng) * 0.5, random_unit(&mut rng));
            assert!(accel.intersect(&r, f32::INFINITY).is_some());
        }
        let mesh = mesh_box(Vec3::ZERO);
        let faces: Vec<usize> = (0..12)
            .map(|prim| {
                box_face(
                    &mesh,
                    &Hit {
                        t: 1.0,
                        instance: 0,
                        prim,
                        u: 0.0,
                        v: 0.0,
                    },
                )
            })
            .collect();
        assert_eq!(faces, vec![0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5]);
    }
}
