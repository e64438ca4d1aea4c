//! Case 4: rays parallel to the KD-tree's split planes and rays with zero
//! direction components (+0.0 and −0.0), compared against brute force.
//!
//! The scene is built to be axis-aligned: a flat grid, a box, the star prism
//! (translated), an icosphere (scaled by 2 and translated: exact in binary),
//! a stepped height field, an axis-aligned quad and a sphere. The candidate
//! planes on each axis are every face of every KD-tree cell (top and bottom
//! levels, from `KdTreeAccel::node_boxes`), every vertex coordinate and every
//! object's bounds. Rays (one third each):
//!
//! - axis-aligned directions (the two other components ±0.0 at random), the
//!   origin on planes of the two other axes (80% each), from outside the
//!   scene or from inside it;
//! - directions with one ±0.0 component, the origin exactly in a plane of
//!   that axis (the ray lies in it), the other components random or exactly
//!   ±1 (45°);
//! - rays starting exactly at a vertex, axis-aligned or in a vertex plane.
//!
//! `t_max` is ∞ (70%) or random. **Failure (disagreement):** the closest hits
//! differ (hit against miss, different `t`, or a different object or
//! primitive at a different `t`), `occluded` answers differ, or a `t` is
//! NaN. Equal `t` on different primitives is a tie (counted in the note).

use super::{box_mesh, Backend, Role, StressOptions, StressRow, Tally};
use super::{guarded, scene_of, share, tally, trial_rng, unavailable_row};
use crate::accel::kdtree::KdTreeAccel;
use crate::accel::{AccelOptions, Hit, TriangleTest};
use crate::geometry::generate::{cornell_star, grid, heightfield, icosphere};
use crate::math::{Aabb, Ray, Rng, Transform, Vec3, Vec3A};
use crate::scene::{Quad, Scene, Shape, Sphere};
use std::sync::Arc;

const CASE: u64 = 4;

/// The axis-aligned scene.
pub fn axis_scene() -> Scene {
    let translate =
        |x: f32, y: f32, z: f32| Transform::from_srt(Vec3::ONE, Vec3::ZERO, Vec3::new(x, y, z)).expect("invertible");
    let mesh = |mesh: u32, transform: Transform| Shape::Mesh {
        mesh,
        transform,
        smooth: false,
    };
    scene_of(
        vec![
            Arc::new(grid(8, 8, 4.0, 4.0)),
            Arc::new(box_mesh(Vec3::new(2.0, 0.0, -1.0), Vec3::new(4.0, 2.0, 1.0))),
            Arc::new(cornell_star()),
            Arc::new(icosphere(2)),
            Arc::new(heightfield(6, 6, 3.0, 3.0, |x, _| (x * 2.0).floor() * 0.25)),
        ],
        vec![
            (mesh(0, Transform::IDENTITY), 0),
            (mesh(1, Transform::IDENTITY), 0),
            (mesh(2, translate(0.0, 1.0, -3.0)), 0),
            (
                mesh(
                    3,
                    Transform::from_srt(Vec3::splat(2.0), Vec3::ZERO, Vec3::new(-3.0, 1.0, 0.0)).expect("invertible"),
                ),
                0,
            ),
            (mesh(4, translate(0.0, 0.0, 3.0)), 0),
            (
                Shape::Quad(
                    Quad::new(Vec3A::new(-4.0, 0.0, -4.0), Vec3A::X * 8.0, Vec3A::Y * 4.0).expect("valid quad"),
                ),
                0,
            ),
            (
                Shape::Sphere(Sphere {
                    center: Vec3A::new(0.0, 3.0, 0.0),
                    radius: 0.5,
                }),
                0,
            ),
        ],
        vec![],
    )
}

/// Sorted distinct plane positions per axis, and the world vertices.
fn planes(scene: &Scene) -> ([Vec<f32>; 3], Vec<Vec3A>) {
    let tree = KdTreeAccel::build(scene, &AccelOptions::default());
    let mut out: [Vec<f32>; 3] = Default::default();
    let push_box = |b: &Aabb, out: &mut [Vec<f32>; 3]| {
        for (a, axis) in out.iter_mut().enumerate() {
            axis.extend([b.min[a], b.max[a]].into_iter().filter(|v| v.is_finite()));
        }
    };
    for (b, _) in tree.node_boxes(64) {
        push_box(&b, &mut out);
    }
    let mut vertices = Vec::new();
    for (i, o) in scene.objects.iter().enumerate() {
        push_box(&scene.object_bounds(i), &mut out);
        if let Shape::Mesh { mesh, transform, .. } = &o.shape {
            for p in &scene.meshes[*mesh as usize].positions {
                vertices.push(transform.point(Vec3A::from(*p)));
            }
        }
    }
    for v in &vertices {
        for a in 0..3 {
            out[a].push(v[a]);
        }
    }
    for axis in &mut out {
        axis.sort_by(f32::total_cmp);
        axis.dedup();
    }
    (out, vertices)
}

fn signed_zero(rng: &mut Rng) -> f32 {
    if rng.f32() < 0.5 {
        0.0
    } else {
        -0.0
    }
}

/// Ray `i` of the case and its `t_max`.
fn make_ray(i: u64, seed: u64, planes: &[Vec<f32>; 3], vertices: &[Vec3A], bounds: &Aabb) -> (Ray, f32) {
    let mut rng = trial_rng(seed, CASE, i);
    let lo = bounds.min - Vec3A::ONE;
    let hi = bounds.max + Vec3A::ONE;
    let uniform = |rng: &mut Rng, a: usize| lo[a] + (hi[a] - lo[a]) * rng.f32();
    let plane = |rng: &mut Rng, a: usize| planes[a][rng.below(planes[a].len() as u32) as usize];
    let sign = |rng: &mut Rng| if rng.f32() < 0.5 { -1.0f32 } else { 1.0 };
    let axis_dir = |rng: &mut Rng, a: usize| {
        let mut d = Vec3A::new(signed_zero(rng), signed_zero(rng), signed_zero(rng));
        d[a] = sign(rng);
        d
    };
    let in_plane_dir = |rng: &mut Rng, z: usize| {
        let mut d = Vec3A::ZERO;
        let exact45 = rng.f32() < 0.2;
        for a in 0..3 {
            d[a] = if exact45 { sign(rng) } else { rng.f32() * 2.0 - 1.0 };
        }
        d[z] = signed_zero(rng);
        // Normalising keeps the ±0.0 (0 · k = 0 with the sign of 0).
        let n = d.length();
        if n > 1e-3 {
            d / n
        } else {
            axis_dir(rng, (z + 1) % 3)
        }
    };
    let (origin, dir) = match i % 3 {
        0 => {
            let a = rng.below(3) as usize;
            let dir = axis_dir(&mut rng, a);
            let mut o = Vec3A::ZERO;
            for b in 0..3 {
                o[b] = if b != a && rng.f32() < 0.8 {
                    plane(&mut rng, b)
                } else {
                    uniform(&mut rng, b)
                };
            }
            if rng.f32() < 0.5 {
                o[a] = if dir[a] > 0.0 { lo[a] } else { hi[a] };
            }
            (o, dir)
        }
        1 => {
            let z = rng.below(3) as usize;
            let dir = in_plane_dir(&mut rng, z);
            let mut o = Vec3A::ZERO;
            for b in 0..3 {
                o[b] = if b == z && rng.f32() < 0.9 {
                    plane(&mut rng, b)
                } else {
                    uniform(&mut rng, b)
                };
            }
            (o, dir)
        }
        _ => {
            let o = vertices[rng.below(vertices.len() as u32) as usize];
            let a = rng.below(3) as usize;
            let dir = if rng.f32() < 0.5 {
                axis_dir(&mut rng, a)
            } else {
                in_plane_dir(&mut rng, a)
            };
            (o, dir)
        }
    };
    let t_max = if rng.f32() < 0.7 {
        f32::INFINITY
    } else {
        0.1 + 10.0 * rng.f32()
    };
    (Ray::new(origin, dir), t_max)
}

/// How two closest hits compare.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Agreement {
    /// Both miss, or the same object and primitive at the same `t`.
    Same,
    /// Equal `t` on different primitives (a shared edge, coplanar faces).
    Tie,
    /// Hit against miss, different `t`, or a NaN `t`.
    Disagree,
}

/// Compares two closest hits.
pub fn compare_hits(a: Option<Hit>, b: Option<Hit>) -> Agreement {
    match (a, b) {
        (None, None) => Agreement::Same,
        (Some(x), Some(y)) => {
            if x.t.is_nan() || y.t.is_nan() || x.t != y.t {
                Agreement::Disagree
            } else if x.instance == y.instance && x.prim == y.prim {
                Agreement::Same
            } else {
                Agreement::Tie
            }
        }
        _ => Agreement::Disagree,
    }
}

/// Disagreements of `test`'s KD-tree against its brute force (`extra[0]`:
/// closest-hit disagreements, `extra[1]`: occlusion, `extra[2]`: ties).
pub fn kd_vs_brute(scene: &Scene, test: TriangleTest, n: u64, seed: u64) -> Tally {
    let (kd, brute) = match test {
        TriangleTest::Watertight => (Backend::KdWatertight, Backend::BruteWatertight),
        TriangleTest::MollerTrumbore => (Backend::KdMoller, Backend::BruteMoller),
    };
    let kd = kd.build(scene).expect("the KD-tree always builds");
    let brute = brute.build(scene).expect("brute force always builds");
    let (planes, vertices) = planes(scene);
    let bounds = scene.bounds();
    tally(n, |i| {
        let (ray, t_max) = make_ray(i, seed, &planes, &vertices, &bounds);
        let mut t = Tally {
            trials: 1,
            ..Tally::default()
        };
        match compare_hits(kd.intersect(&ray, t_max), brute.intersect(&ray, t_max)) {
            Agreement::Same => {}
            Agreement::Tie => t.extra[2] += 1,
            Agreement::Disagree => t.extra[0] += 1,
        }
        if kd.occluded(&ray, t_max) != brute.occluded(&ray, t_max) {
            t.extra[1] += 1;
        }
        t.failures = u64::from(t.extra[0] + t.extra[1] > 0);
        t
    })
}

/// The rows of case 4.
pub fn run(options: &StressOptions) -> Vec<StressRow> {
    let case = "4 parallel/zero-component rays vs brute";
    let scene = axis_scene();
    let mut rows = Vec::new();
    for (test, backend) in [
        (TriangleTest::Watertight, Backend::KdWatertight),
        (TriangleTest::MollerTrumbore, Backend::KdMoller),
    ] {
        if !backend.available() {
            rows.push(unavailable_row(case, backend, Role::Default, "not compiled in"));
            continue;
        }
        rows.extend(guarded(case, backend.name(), Role::Default, || {
            let t = kd_vs_brute(&scene, test, options.rays, options.seed);
            vec![
                StressRow::new(case, backend.name(), Role::Default, t.trials, t.failures).note(format!(
                    "{} — closest hit {}, occlusion {}; equal-t ties {}",
                    share(t.failures, t.trials),
                    t.extra[0],
                    t.extra[1],
                    t.extra[2]
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
    fn rays_have_exact_zero_components_and_lie_in_planes() {
        let scene = axis_scene();
        let (planes, vertices) = planes(&scene);
        assert!(planes.iter().all(|p| p.len() > 10));
        let bounds = scene.bounds();
        let mut zeros = 0;
        let mut negative_zeros = 0;
        for i in 0..300 {
            let (r, _) = make_ray(i, 1, &planes, &vertices, &bounds);
            zeros += (0..3).filter(|&a| r.dir[a] == 0.0).count();
            negative_zeros += (0..3)
                .filter(|&a| r.dir[a] == 0.0 && r.dir[a].is_sign_negative())
                .count();
            assert!((r.dir.length() - 1.0).abs() < 1e-5);
        }
        assert!(zeros >= 300 && negative_zeros > 50, "{zeros} {negative_zeros}");
    }

    #[test]
    fn compare_hits_rules() {
        let h = |t: f32, prim: u32| {
            Some(Hit {
                t,
                instance: 0,
                prim,
                u: 0.0,
                v: 0.0,
            })
        };
        assert_eq!(compare_hits(None, None), Agreement::Same);
        assert_eq!(compare_hits(h(1.0, 0), h(1.0, 0)), Agreement::Same);
        assert_eq!(compare_hits(h(1.0, 0), h(1.0, 1)), Agreement::Tie);
        assert_eq!(compare_hits(h(1.0, 0), h(1.5, 0)), Agreement::Disagree);
        assert_eq!(compare_hits(h(1.0, 0), None), Agreement::Disagree);
        assert_eq!(compare_hits(h(f32::NAN, 0), h(f32::NAN, 0)), Agreement::Disagree);
    }
}
