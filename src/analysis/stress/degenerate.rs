//! Case 5: degenerate and needle triangles inside a mesh.
//!
//! The mesh mixes ordinary triangles with exactly zero-area ones (three
//! distinct collinear vertices with dyadic coordinates, so collinear in exact
//! arithmetic; a repeated index; one point three times; two indices at the
//! same position) and needles of aspect ratio 1e-7 (length 1, width 1e-7) in
//! random orientations. Per-vertex normals are given: random, some zero (the
//! loader's fallback) — so smooth shading runs on needles too. The mesh is
//! used twice: as is, and rotated and scaled.
//!
//! Rays (one quarter each): random rays through the bounds; rays aimed at a
//! point of a zero-area triangle; rays aimed at a random point inside a
//! needle; rays grazing along a needle.
//!
//! **Validity failure** (row "validity"): a NaN or infinite `t`, `u` or `v`;
//! a hit on a zero-area triangle; a non-finite `surface_interaction` (point,
//! error, normals) at a hit; a panic. **Agreement failure** (row "needles vs
//! brute"): on the needle rays, the closest hit differs from brute force
//! with the same triangle test (the rules of case 4); Embree is compared with
//! the watertight oracle, a different test, so its row is measured only.
//!
//! # The Möller–Trumbore row is measured, and its oracle is wrong
//!
//! The KD-tree with Möller–Trumbore is not a default configuration (scenes
//! default to the watertight test; Möller–Trumbore runs only when a scene
//! asks for `triangle_test = "moller-trumbore"`), so its needle row is
//! measured. Its disagreements are the oracle's error, not the KD-tree's:
//! Möller–Trumbore computes `t = (e₂·q)/det` with `det` of the order of the
//! needle's width (1e-7), so the rounding of `e₂·q` becomes an error of
//! order 1 in `t` (replayed: brute force returned `t = 1.0` for a needle
//! whose plane the ray crosses at 3.32 in f64, and `2.67` for 4.88). Brute
//! force keeps such a needle as "closest" in front of a triangle that is
//! truly nearer; the KD-tree visits cells front to back, finds the truly
//! nearer triangle (its `t` equal to the f64 value) and stops before the
//! needle's cell. The note counts the disagreements in which the KD-tree's
//! triangle is, in f64 (the ray's exact crossing of each triangle's plane),
//! no farther than the oracle's: the watertight test, whose `t` is computed
//! with bounded error, has none.

use super::parallel::{compare_hits, Agreement};
use super::{guarded, random_unit, scene_of, share, tally, trial_rng, unavailable_row};
use super::{Backend, Role, StressOptions, StressRow, Tally};
use crate::accel::{Accel, Hit};
use crate::math::{Ray, Rng, Transform, Vec3, Vec3A};
use crate::scene::{Mesh, Scene, Shape};
use std::sync::Arc;

const CASE: u64 = 5;

/// The test mesh and its triangle classes.
pub struct DegenerateMesh {
    /// The mesh.
    pub mesh: Mesh,
    /// Triangles of exactly zero area.
    pub zero_area: Vec<u32>,
    /// Needle triangles (aspect 1e-7).
    pub needles: Vec<u32>,
}

/// A dyadic value in [-1, 1) with 10 fractional bits (exact in f32).
fn dyadic(rng: &mut Rng) -> f32 {
    (rng.below(2048) as f32 - 1024.0) / 1024.0
}

/// Builds the mesh (`seed` fixes it).
pub fn degenerate_mesh(seed: u64) -> DegenerateMesh {
    let mut rng = trial_rng(seed, CASE, u64::MAX);
    let mut p: Vec<Vec3> = Vec::new();
    let mut n: Vec<Vec3> = Vec::new();
    let mut tris: Vec<[u32; 3]> = Vec::new();
    let (mut zero_area, mut needles) = (Vec::new(), Vec::new());
    let push = |p: &mut Vec<Vec3>, n: &mut Vec<Vec3>, rng: &mut Rng, v: Vec3| {
        p.push(v);
        // Random normals, one in eight zero (recomputed by Mesh::new).
        n.push(if rng.below(8) == 0 {
            Vec3::ZERO
        } else {
            Vec3::from(random_unit(rng))
        });
        (p.len() - 1) as u32
    };
    for k in 0..600u32 {
        let c = Vec3::new(dyadic(&mut rng), dyadic(&mut rng), dyadic(&mut rng));
        match k % 6 {
            0 => {
                // Ordinary triangle.
                let a = push(&mut p, &mut n, &mut rng, c);
                let pb = c + Vec3::from(random_unit(&mut rng)) * 0.1;
                let b = push(&mut p, &mut n, &mut rng, pb);
                let pd = c + Vec3::from(random_unit(&mut rng)) * 0.1;
                let d = push(&mut p, &mut n, &mut rng, pd);
                tris.push([a, b, d]);
            }
            1 => {
                // Three distinct collinear vertices: c + k·e with dyadic e.
                let e = Vec3::new(
                    (rng.below(9) as f32 - 4.0) / 64.0,
                    (rng.below(9) as f32 - 4.0) / 64.0,
                    (rng.below(9) as f32 - 4.0) / 64.0 + 1.0 / 128.0,
                );
                let (k1, k2) = (1 + rng.below(3), 4 + rng.below(3));
                let a = push(&mut p, &mut n, &mut rng, c);
                let b = push(&mut p, &mut n, &mut rng, c + e * k1 as f32);
                let d = push(&mut p, &mut n, &mut rng, c + e * k2 as f32);
                zero_area.push(tris.len() as u32);
                tris.push(if k % 12 == 1 { [a, b, d] } else { [b, a, d] });
            }
            2 => {
                // Repeated index, one point three times, two indices at one position.
                let a = push(&mut p, &mut n, &mut rng, c);
                let pb = c + Vec3::from(random_unit(&mut rng)) * 0.2;
                let b = push(&mut p, &mut n, &mut rng, pb);
                let b2 = push(&mut p, &mut n, &mut rng, pb);
                for t in [[a, a, b], [a, a, a], [a, b, b2]] {
                    zero_area.push(tris.len() as u32);
                    tris.push(t);
                }
            }
            _ => {
                // Needle: length 1, width 1e-7, random orientation.
                let u = Vec3::from(random_unit(&mut rng));
                let w = u.any_orthonormal_vector();
                let a = push(&mut p, &mut n, &mut rng, c - u * 0.5);
                let b = push(&mut p, &mut n, &mut rng, c + u * 0.5);
                let d = push(&mut p, &mut n, &mut rng, c + w * 1e-7);
                needles.push(tris.len() as u32);
                tris.push([a, b, d]);
            }
        }
    }
    let mesh = Mesh::new("degenerate", p, tris, Some(n)).expect("finite data, valid indices");
    // Keep only the triangles whose area is exactly zero in f64 (the
    // construction guarantees it; this checks the claim).
    zero_area.retain(|&t| {
        let [a, b, c] = mesh.corners(t as usize).map(|v| v.as_dvec3());
        (b - a).cross(c - a) == glam::DVec3::ZERO
    });
    DegenerateMesh {
        mesh,
        zero_area,
        needles,
    }
}

fn degenerate_scene(mesh: Mesh) -> Scene {
    scene_of(
        vec![Arc::new(mesh)],
        vec![
            (
                Shape::Mesh {
                    mesh: 0,
                    transform: Transform::IDENTITY,
                    smooth: true,
                },
                0,
            ),
            (
                Shape::Mesh {
                    mesh: 0,
                    transform: Transform::from_srt(
                        Vec3::splat(0.7),
                        Vec3::new(30.0, 45.0, 10.0),
                        Vec3::new(4.0, 0.0, 0.0),
                    )
                    .expect("invertible"),
                    smooth: true,
                },
                0,
            ),
        ],
        vec![],
    )
}

/// Trial `i`: the ray and whether it targets a needle.
fn make_ray(i: u64, seed: u64, d: &DegenerateMesh, scene: &Scene) -> (Ray, bool) {
    let mut rng = trial_rng(seed, CASE, i);
    let object = rng.below(2) as usize;
    let Shape::Mesh { transform, .. } = &scene.objects[object].shape else {
        unreachable!("both objects are meshes")
    };
    let bounds = scene.object_bounds(object);
    let to_world = |p: Vec3A| transform.point(p);
    let from_outside = |rng: &mut Rng, target: Vec3A| {
        let o = target + random_unit(rng) * (bounds.extent().length() * (0.2 + rng.f32()));
        Ray::new(o, (target - o).normalize())
    };
    match i % 4 {
        0 => {
            let target = bounds.min + bounds.extent() * Vec3A::new(rng.f32(), rng.f32(), rng.f32());
            (from_outside(&mut rng, target), false)
        }
        1 => {
            let t = d.zero_area[rng.below(d.zero_area.len() as u32) as usize];
            let [a, b, c] = d.mesh.corners(t as usize);
            let s = rng.f32();
            let target = if rng.f32() < 0.5 {
                a + (b - a) * s
            } else {
                a + (c - a) * s
            };
            (from_outside(&mut rng, to_world(target)), false)
        }
        2 => {
            let t = d.needles[rng.below(d.needles.len() as u32) as usize];
            let [a, b, c] = d.mesh.corners(t as usize);
            let (s, r) = (rng.f32(), rng.f32());
            let (s, r) = if s + r > 1.0 { (1.0 - s, 1.0 - r) } else { (s, r) };
            let target = a + (b - a) * s + (c - a) * r;
            (from_outside(&mut rng, to_world(target)), true)
        }
        _ => {
            let t = d.needles[rng.below(d.needles.len() as u32) as usize];
            let [a, b, c] = d.mesh.corners(t as usize);
            // Along the needle, tilted by up to 1e-3 rad out of its plane.
            let along = (b - a).normalize();
            let normal = (b - a).cross(c - a).normalize_or(along.any_orthonormal_vector());
            let dir = (along + normal * (1e-3 * (rng.f32() * 2.0 - 1.0))).normalize();
            let o = a - along * 0.5 + (c - a) * rng.f32();
            let (o, p) = (to_world(o), to_world(o + dir));
            (Ray::new(o, (p - o).normalize()), true)
        }
    }
}

/// The exact (f64) `t` at which `ray` crosses the plane of the triangle of
/// `hit`, from the f32 ray and corners actually used (in object space: the
/// instance transform keeps the ray's parameter).
fn exact_plane_t(scene: &Scene, d: &DegenerateMesh, ray: &Ray, hit: &Hit) -> f64 {
    let Shape::Mesh { transform, .. } = &scene.objects[hit.instance as usize].shape else {
        unreachable!("both objects are meshes")
    };
    let local = transform.ray_to_object(ray);
    let (o, dir) = (local.origin.as_dvec3(), local.dir.as_dvec3());
    let [a, b, c] = d.mesh.corners(hit.prim as usize).map(|v| v.as_dvec3());
    let n = (b - a).cross(c - a);
    n.dot(a - o) / n.dot(dir)
}

/// Tally extra: `[NaN hit, zero-area hit, non-finite shading, needle
/// disagreement, disagreement where the accelerator's triangle is exactly no
/// farther than the oracle's (the oracle is wrong), 0]`.
fn check(scene: &Scene, d: &DegenerateMesh, accel: &dyn Accel, oracle: &dyn Accel, n: u64, seed: u64) -> Tally {
    tally(n, |i| {
        let (ray, needle) = make_ray(i, seed, d, scene);
        let mut extra = [0u64; 6];
        let hit = accel.intersect(&ray, f32::INFINITY);
        let _ = accel.occluded(&ray, f32::INFINITY);
        if let Some(h) = hit {
            if !(h.t.is_finite() && h.u.is_finite() && h.v.is_finite()) {
                extra[0] += 1;
            } else {
                if d.zero_area.binary_search(&h.prim).is_ok() {
                    extra[1] += 1;
                }
                let si = scene.surface_interaction(&ray, &h);
                if !(si.p.is_finite() && si.p_error.is_finite() && si.ng.is_finite() && si.ns.is_finite()) {
                    extra[2] += 1;
                }
            }
        }
        let oracle_hit = if needle {
            oracle.intersect(&ray, f32::INFINITY)
        } else {
            None
        };
        if needle && compare_hits(hit, oracle_hit) == Agreement::Disagree {
            extra[3] += 1;
            if let (Some(h), Some(o)) = (hit, oracle_hit) {
                if exact_plane_t(scene, d, &ray, &h) <= exact_plane_t(scene, d, &ray, &o) {
                    extra[4] += 1;
                }
            }
        }
        Tally {
            trials: 1,
            failures: u64::from(extra[0] + extra[1] + extra[2] > 0),
            extra,
        }
    })
}

/// The rows of case 5.
pub fn run(options: &StressOptions) -> Vec<StressRow> {
    let (validity, agreement) = ("5 degenerate/needle: validity", "5 needles vs brute");
    let d = degenerate_mesh(options.seed);
    let scene = degenerate_scene(d.mesh.clone());
    let configs = [
        (
            Backend::KdWatertight,
            Backend::BruteWatertight,
            Role::Default,
            Role::Default,
        ),
        // Measured: not a default configuration, and the oracle's own t is
        // wrong on needles (module docs).
        (Backend::KdMoller, Backend::BruteMoller, Role::Default, Role::Measured),
        (Backend::Embree, Backend::BruteWatertight, Role::Default, Role::Measured),
        (
            Backend::EmbreeRobust,
            Backend::BruteWatertight,
            Role::Measured,
            Role::Measured,
        ),
    ];
    let mut rows = Vec::new();
    for (backend, oracle_backend, valid_role, agree_role) in configs {
        if !backend.available() {
            rows.push(unavailable_row(validity, backend, valid_role, "not compiled in"));
            continue;
        }
        rows.extend(guarded(validity, backend.name(), valid_role, || {
            let (accel, oracle) = match (backend.build(&scene), oracle_backend.build(&scene)) {
                (Ok(a), Ok(o)) => (a, o),
                (Err(e), _) | (_, Err(e)) => {
                    return vec![unavailable_row(validity, backend, valid_role, &e.to_string())]
                }
            };
            let t = check(&scene, &d, accel.as_ref(), oracle.as_ref(), options.rays, options.seed);
            let needle_rays = options.rays / 2;
            vec![
                StressRow::new(validity, backend.name(), valid_role, t.trials, t.failures).note(format!(
                    "{} — NaN hits {}, zero-area hits {}, non-finite shading {} ({} zero-area, {} needle triangles)",
                    share(t.failures, t.trials),
                    t.extra[0],
                    t.extra[1],
                    t.extra[2],
                    d.zero_area.len(),
                    d.needles.len()
                )),
                StressRow::new(agreement, backend.name(), agree_role, needle_rays, t.extra[3]).note(format!(
                    "{} against {}; in {} of them the accelerator's triangle is exactly (f64) no farther than the oracle's",
                    share(t.extra[3], needle_rays),
                    oracle_backend.name(),
                    t.extra[4]
                )),
            ]
        }));
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mesh_has_every_kind_of_degenerate_triangle() {
        let d = degenerate_mesh(0);
        // 100 collinear + 300 from the repeated-vertex group, all exactly zero area.
        assert_eq!(d.zero_area.len(), 400);
        assert_eq!(d.needles.len(), 300);
        for &t in &d.needles {
            let [a, b, c] = d.mesh.corners(t as usize);
            let area2 = (b - a).cross(c - a).length();
            assert!(area2 > 0.0 && area2 < 1e-6, "{area2}");
        }
        assert!(d
            .mesh
            .normals
            .iter()
            .all(|n| n.is_finite() && (n.length() - 1.0).abs() < 1e-4));
    }
}
