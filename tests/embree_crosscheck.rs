//! Embree against the brute-force oracle on seeded random rays.
//!
//! Agreement means: same object (`instance`) and primitive, |Δt| < 1e-5·t +
//! 1e-6·|origin|, |Δu|, |Δv| < 1e-4, same occlusion answer.
//!
//! Why the absolute term in t: both backends move the ray into the instance's
//! object space, each with its own inverse matrix (glam's, Embree's), so the
//! object-space origins differ by a few ulps of |origin| (~1e-7·|o|). For a
//! ray starting next to a surface (t ≪ |o|) that absolute difference is a
//! large relative one; it is a property of f32 transforms, not a wrong hit.
//! Why u, v may also be compared through points: for a grazing ray a Δt
//! within tolerance moves the hit along the surface by about Δt, which can
//! change (u, v) of a small triangle by more than 1e-4; then the two hit
//! points (barycentric reconstruction in world space) must agree within the
//! t tolerance instead.
//!
//! Two kinds of disagreement are
//! genuine ties, counted but allowed:
//! - *same-t ties*: the two hits are different primitives at the same
//!   distance (|Δt| ≤ 1e-6·t): a shared edge or vertex, or overlapping soup
//!   triangles; either answer is right;
//! - *boundary ties*: the nearer of the two hits (or the only one) lies within
//!   1e-5 of its primitive's boundary (a barycentric coordinate, or a quad
//!   coordinate, within 1e-5 of its limit; a ray within 1e-5·r of tangency
//!   for spheres): the two triangle tests round differently there.
//!
//! Ties must stay rare (< 0.1% of the rays); anything else fails the test
//! with the ray printed so it can be replayed.
#![cfg(feature = "embree")]

mod embree_support;

use caustic::accel::brute::BruteForce;
use caustic::accel::embree::EmbreeAccel;
use caustic::accel::{Accel, AccelOptions, Hit, TriangleTest};
use caustic::math::rng::{Domain, Rng};
use caustic::math::{Ray, Vec3A};
use caustic::scene::{Scene, Shape};
use embree_support::{ray, test_scene};
use rayon::prelude::*;

const BOUNDARY: f32 = 1e-5;

/// True when `hit` lies within `BOUNDARY` of its primitive's boundary.
fn on_boundary(scene: &Scene, ray: &Ray, hit: &Hit) -> bool {
    match &scene.objects[hit.instance as usize].shape {
        Shape::Mesh { .. } => {
            let w = 1.0 - hit.u - hit.v;
            hit.u.min(hit.v).min(w) < BOUNDARY
        }
        Shape::Quad(_) => [hit.u, hit.v, 1.0 - hit.u, 1.0 - hit.v].iter().any(|&c| c < BOUNDARY),
        Shape::Sphere(s) => {
            let d = ray.dir.normalize();
            let f = ray.origin - s.center;
            let perp = (f - d * f.dot(d)).length();
            (perp - s.radius).abs() < BOUNDARY * s.radius
        }
    }
}

#[derive(Debug, PartialEq)]
enum Verdict {
    Agree,
    Tie,
    Mismatch(String),
}

fn compare_hits(scene: &Scene, ray: &Ray, e: Option<Hit>, b: Option<Hit>, max_rel: &mut f32) -> Verdict {
    match (e, b) {
        (None, None) => Verdict::Agree,
        (Some(e), Some(b)) if (e.instance, e.prim) == (b.instance, b.prim) => {
            *max_rel = max_rel.max((e.t - b.t).abs() / b.t);
            let tol = 1e-5 * b.t + 1e-6 * ray.origin.length();
            let uv_close = ((e.u - b.u).abs() < 1e-4 && (e.v - b.v).abs() < 1e-4)
                || (scene.surface_interaction(ray, &e).p - scene.surface_interaction(ray, &b).p).length() < tol;
            if (e.t - b.t).abs() < tol && uv_close {
                Verdict::Agree
            } else if on_boundary(scene, ray, &b) {
                Verdict::Tie
            } else {
                Verdict::Mismatch(format!("same primitive, different hit: embree {e:?} brute {b:?}"))
            }
        }
        (Some(e), Some(b)) => {
            let (near, far) = if e.t <= b.t { (e, b) } else { (b, e) };
            if (far.t - near.t) <= 1e-6 * far.t || on_boundary(scene, ray, &near) {
                Verdict::Tie
            } else {
                Verdict::Mismatch(format!("different primitives: embree {e:?} brute {b:?}"))
            }
        }
        (Some(only), None) | (None, Some(only)) => {
            if on_boundary(scene, ray, &only) {
                Verdict::Tie
            } else {
                Verdict::Mismatch(format!("hit/miss: embree {e:?} brute {b:?}"))
            }
        }
    }
}

struct Tally {
    rays: usize,
    ties: usize,
    mismatches: Vec<String>,
    /// Largest |Δt|/t over agreeing same-primitive hits (rays starting next
    /// to a surface dominate it: see the module comment).
    max_rel_t: f32,
    hits: usize,
}

fn crosscheck(scene: &Scene, options: &AccelOptions, rays: u64, seed: u64) -> Tally {
    let embree = EmbreeAccel::build(scene, options).unwrap();
    let brute = BruteForce::new(scene, TriangleTest::Watertight);
    let per_ray: Vec<(Verdict, Verdict, f32, bool)> = (0..rays)
        .into_par_iter()
        .map(|i| {
            let r = ray(scene, seed, i);
            let mut max_rel = 0.0f32;
            let full = brute.intersect(&r, f32::INFINITY);
            let closest = compare_hits(scene, &r, embree.intersect(&r, f32::INFINITY), full, &mut max_rel);
            // Shadow-ray style query with a t_max kept away from the hit
            // distance (a t_max equal to it would be a tie by construction).
            let mut rng = Rng::new(seed, Domain::Analysis, i, 2);
            let t_max = match (rng.below(3), full) {
                (0, _) | (_, None) => f32::INFINITY,
                (1, Some(h)) => h.t * (0.2 + 0.78 * rng.f32()),
                (_, Some(h)) => h.t * (1.02 + 2.0 * rng.f32()),
            };
            let (eo, bo) = (embree.occluded(&r, t_max), brute.occluded(&r, t_max));
            let occlusion = if eo == bo {
                Verdict::Agree
            } else {
                // Any disagreement must come from a boundary primitive
                // before t_max: the closest hits below t_max say which.
                let near = embree.intersect(&r, t_max).or(brute.intersect(&r, t_max));
                match near {
                    Some(h) if on_boundary(scene, &r, &h) => Verdict::Tie,
                    _ => Verdict::Mismatch(format!("occluded(t_max = {t_max}): embree {eo} brute {bo}")),
                }
            };
            (closest, occlusion, max_rel, full.is_some())
        })
        .collect();
    let mut tally = Tally {
        rays: rays as usize,
        ties: 0,
        mismatches: Vec::new(),
        max_rel_t: 0.0,
        hits: 0,
    };
    for (i, (closest, occlusion, rel, hit)) in per_ray.into_iter().enumerate() {
        tally.max_rel_t = tally.max_rel_t.max(rel);
        tally.hits += hit as usize;
        for v in [closest, occlusion] {
            match v {
                Verdict::Agree => {}
                Verdict::Tie => tally.ties += 1,
                Verdict::Mismatch(m) => tally
                    .mismatches
                    .push(format!("ray {i} {:?}: {m}", ray(scene, seed, i as u64))),
            }
        }
    }
    tally
}

fn assert_clean(name: &str, t: &Tally) {
    eprintln!(
        "{name}: {} rays, {} hits, {} ties, {} mismatches, max |Δt|/t = {:.3e}",
        t.rays,
        t.hits,
        t.ties,
        t.mismatches.len(),
        t.max_rel_t
    );
    for m in t.mismatches.iter().take(10) {
        eprintln!("  {m}");
    }
    assert!(t.mismatches.is_empty(), "{name}: {} disagreements", t.mismatches.len());
    assert!(t.ties * 1000 < t.rays, "{name}: too many ties ({})", t.ties);
    // The rays must actually exercise the geometry.
    assert!(t.hits * 2 > t.rays, "{name}: only {} of {} rays hit", t.hits, t.rays);
}

#[test]
fn embree_matches_brute_force_on_100k_rays() {
    let scene = test_scene();
    let tally = crosscheck(&scene, &AccelOptions::default(), 100_000, 2024);
    assert_clean("high quality", &tally);
}

#[test]
fn embree_robust_and_low_quality_match_brute_force() {
    let scene = test_scene();
    for (quality, robust) in [("low", true), ("medium", false)] {
        let options = AccelOptions {
            embree_quality: quality.into(),
            embree_robust: robust,
            ..Default::default()
        };
        let tally = crosscheck(&scene, &options, 15_000, 7);
        assert_clean(&format!("{quality} robust={robust}"), &tally);
    }
}

#[test]
fn instances_share_one_blas_per_mesh() {
    let scene = test_scene();
    let accel = EmbreeAccel::build(&scene, &AccelOptions::default()).unwrap();
    let stats = accel.stats();
    assert_eq!(stats.blas_count, 2, "one BLAS per distinct mesh");
    assert_eq!(stats.instances, scene.objects.len());
    assert!(stats.memory_bytes > 0, "memory monitor counted nothing");
    // Rays from each icosphere instance's centre straight down leave through
    // that instance (unless a soup triangle inside it is nearer): Embree must
    // agree with the oracle, and name the instance by its object index.
    let brute = BruteForce::new(&scene, TriangleTest::Watertight);
    let mut own = 0;
    for k in 5..11 {
        let r = Ray::new(scene.object_bounds(k).center(), -Vec3A::Y);
        let (e, b) = (
            accel.intersect(&r, f32::INFINITY).unwrap(),
            brute.intersect(&r, f32::INFINITY).unwrap(),
        );
        assert_eq!((e.instance, e.prim), (b.instance, b.prim), "{}", scene.objects[k].name);
        own += (e.instance as usize == k) as usize;
    }
    assert!(own >= 4, "only {own} of 6 instances hit from their centre");
}

#[test]
fn t_range_is_open_and_respected() {
    let scene = test_scene();
    let accel = EmbreeAccel::build(&scene, &AccelOptions::default()).unwrap();
    // Straight down onto the floor (y = -1.5) from y = 10, away from other objects.
    let r = Ray::new(Vec3A::new(5.5, 10.0, 5.5), -Vec3A::Y);
    let hit = accel.intersect(&r, f32::INFINITY).unwrap();
    assert_eq!(hit.instance, 0);
    assert!((hit.t - 11.5).abs() < 1e-5, "{hit:?}");
    assert!(accel.intersect(&r, 11.4).is_none());
    assert!(accel.occluded(&r, 11.6) && !accel.occluded(&r, 11.4));
    // Empty or NaN intervals hit nothing.
    assert!(accel.intersect(&r, 0.0).is_none() && !accel.occluded(&r, 0.0));
    assert!(accel.intersect(&r, f32::NAN).is_none() && !accel.occluded(&r, f32::NAN));
    // A ray starting exactly on the floor going down sees nothing (t > 0 only).
    let on = Ray::new(Vec3A::new(5.5, -1.5, 5.5), -Vec3A::Y);
    assert!(accel.intersect(&on, f32::INFINITY).is_none());
}
