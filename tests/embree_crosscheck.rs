//! Embree against the brute-force oracle on seeded rays, through the shared
//! cross-check (`caustic::analysis::crosscheck`, also behind `caustic
//! crosscheck`): its module documentation gives the rules (same object and
//! primitive, |Δt| within 1e-5·t plus an absolute term scaled by the
//! coordinates' magnitude, (u, v) within 1e-4, and which differences are
//! ties: same distance, on a primitive's boundary, at an interval end).
//!
//! Ties must stay rare (< 0.1%) on camera and bounds rays; the rays aimed at
//! vertices and edges on purpose tie often, by design. Any disagreement fails
//! the test with the ray printed so it can be replayed.
#![cfg(feature = "embree")]

mod common;

use caustic::accel::brute::BruteForce;
use caustic::accel::embree::EmbreeAccel;
use caustic::accel::{Accel, AccelOptions, TriangleTest};
use caustic::analysis::crosscheck::{crosscheck, CrosscheckOptions, CrosscheckReport, RayKind};
use caustic::math::{Ray, Vec3A};
use caustic::scene::{Scene, Shape};
use common::scenes::test_scene;

fn run(scene: &Scene, options: &AccelOptions, rays: u64, seed: u64) -> CrosscheckReport {
    let embree = EmbreeAccel::build(scene, options).unwrap();
    let brute = BruteForce::new(scene, TriangleTest::Watertight);
    crosscheck(
        scene,
        &embree,
        &brute,
        &CrosscheckOptions {
            rays,
            seed,
            image: (640, 480),
        },
    )
}

fn assert_clean(name: &str, report: &CrosscheckReport) {
    eprintln!("{name}\n{report}");
    assert!(report.is_ok(), "{name}: disagreements\n{report}");
    let total = report.total();
    for kind in [RayKind::Camera, RayKind::Bounds] {
        let k = report.kind(kind);
        assert!(
            (k.ties + k.occlusion_ties) * 1000 < k.rays,
            "{name}: too many ties on {kind:?} rays\n{report}"
        );
    }
    // The rays must actually exercise the geometry.
    assert!(
        total.hits * 2 > total.rays,
        "{name}: only {} of {} rays hit",
        total.hits,
        total.rays
    );
}

#[test]
fn embree_matches_brute_force_on_100k_rays() {
    let scene = test_scene();
    let report = run(&scene, &AccelOptions::default(), 100_000, 2024);
    assert_clean("high quality", &report);
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
        let report = run(&scene, &options, 15_000, 7);
        assert_clean(&format!("{quality} robust={robust}"), &report);
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

/// A mesh that one object alone uses is in the top level, in world space
/// (no instance), and still answers as the oracle does, object and
/// primitive included.
#[test]
fn meshes_used_once_are_in_the_top_level() {
    let mut scene = test_scene();
    // "soup 1" and "ico 5" get meshes of their own (the same data under new
    // indices): the first soup, the second and the last icosphere are then
    // each the only user of their mesh; five icospheres share mesh 0.
    for (name, source) in [("soup 1", 1usize), ("ico 5", 0)] {
        let index = scene.meshes.len() as u32;
        scene.meshes.push(scene.meshes[source].clone());
        let object = scene.objects.iter_mut().find(|o| o.name == name).unwrap();
        let Shape::Mesh { mesh, .. } = &mut object.shape else {
            panic!("{name} is not a mesh")
        };
        *mesh = index;
    }
    let accel = EmbreeAccel::build(&scene, &AccelOptions::default()).unwrap();
    let stats = accel.stats();
    assert_eq!(stats.blas_count, 1, "only the shared icosphere is instanced");
    let top = stats.details.iter().find(|(k, _)| k == "meshes in the top level");
    assert_eq!(top.map(|(_, v)| v.as_str()), Some("3"), "{:?}", stats.details);
    for robust in [false, true] {
        let options = AccelOptions {
            embree_robust: robust,
            ..Default::default()
        };
        let report = run(&scene, &options, 40_000, 11);
        assert_clean(&format!("top-level meshes, robust={robust}"), &report);
    }
    let brute = BruteForce::new(&scene, TriangleTest::Watertight);
    let ico5 = scene.objects.iter().position(|o| o.name == "ico 5").unwrap();
    let r = Ray::new(scene.object_bounds(ico5).center(), -Vec3A::Y);
    let (e, b) = (
        accel.intersect(&r, f32::INFINITY).unwrap(),
        brute.intersect(&r, f32::INFINITY).unwrap(),
    );
    assert_eq!((e.instance, e.prim), (b.instance, b.prim));
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

/// Packets (`intersect_many`, `rtcIntersect16`) find the same surfaces as
/// one-ray queries, on coherent camera rays and on incoherent rays, in
/// batches of every length 1..=40 (full packets and partial last ones), with
/// `t` within 1e-5 relative (the packet kernels may round differently).
#[test]
fn packets_match_single_rays() {
    use caustic::analysis::rays::{camera_rays, incoherent_rays};
    let scene = test_scene();
    let accel = EmbreeAccel::build(&scene, &AccelOptions::default()).unwrap();
    for (name, set) in [
        ("camera", camera_rays(&scene, 20_000, 1.5, 3)),
        ("incoherent", incoherent_rays(&scene, 20_000, 4)),
    ] {
        let rays: Vec<Ray> = set.iter().map(|(r, _)| *r).collect();
        let (mut start, mut len, mut hits, mut compared) = (0, 1, 0, 0);
        while start < rays.len() {
            let batch = &rays[start..(start + len).min(rays.len())];
            let mut many = vec![None; batch.len()];
            accel.intersect_many(batch, f32::INFINITY, &mut many);
            for (ray, got) in batch.iter().zip(&many) {
                let want = accel.intersect(ray, f32::INFINITY);
                compared += 1;
                match (got, want) {
                    (None, None) => {}
                    (Some(g), Some(w)) => {
                        hits += 1;
                        assert_eq!((g.instance, g.prim), (w.instance, w.prim), "{name}: {ray:?}");
                        assert!(
                            (g.t - w.t).abs() <= 1e-5 * w.t,
                            "{name}: t {} vs {} for {ray:?}",
                            g.t,
                            w.t
                        );
                    }
                    _ => panic!("{name}: packet {got:?} vs single {want:?} for {ray:?}"),
                }
            }
            start += batch.len();
            len = len % 40 + 1;
        }
        assert_eq!(compared, rays.len());
        assert!(hits * 4 > compared, "{name}: only {hits} of {compared} rays hit");
    }
}
