//! `analysis::crosscheck` on every scene file of `scenes/` and
//! `scenes/test/`, on a synthetic instanced-mesh scene, and on the dragon.
//!
//! Pairs: Embree against the KD-tree is the main pair (both fast on any
//! scene); each is also checked against brute force on small scenes (brute
//! force costs rays × triangles). The rules (what is an agreement, a tie, a
//! disagreement) are the library's: see `caustic::analysis::crosscheck`.
//!
//! Every scene must load (the dragon is found or fetched by `io::assets`);
//! a scene that does not load fails the test.

mod common;

use caustic::accel::{self, Accel, AccelKind, AccelOptions};
use caustic::analysis::crosscheck::{crosscheck, CrosscheckOptions, CrosscheckReport, RayKind};
use caustic::scene::{load_scene, Scene};
use std::path::{Path, PathBuf};

/// Brute force is used only below this many instanced triangles.
const BRUTE_MAX_TRIANGLES: u64 = 5_000;
/// Rays per scene and pair.
const RAYS: u64 = 20_000;

/// Scene files in the directories, sorted.
fn scene_files(dirs: &[&str]) -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    for dir in dirs {
        let entries = std::fs::read_dir(root.join(dir)).unwrap_or_else(|e| panic!("{dir}: {e}"));
        for entry in entries {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "toml") {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

/// Two accelerators built on one scene and the rays to cast through both.
type Pair = (Box<dyn Accel>, Box<dyn Accel>, u64);

/// Triangle tests brute force may spend on one scene and pair
/// (rays × instanced triangles), when it is the only check a large scene has.
const BRUTE_BUDGET: u64 = 200_000_000;

/// The accelerator pairs worth running on `scene`, built, with the rays to
/// cast through each. Embree against the KD-tree on every scene when Embree
/// is compiled in; brute force against each on small scenes with [`RAYS`];
/// and in a build without Embree, a large scene's KD-tree against brute
/// force with as many rays as [`BRUTE_BUDGET`] allows (at least 16). Every
/// scene gets at least one pair: none would be a test that checks nothing.
fn pairs(scene: &Scene, name: &str) -> Vec<Pair> {
    let options = AccelOptions::default();
    let build = |kind| accel::build(scene, kind, &options).unwrap_or_else(|e| panic!("{name}: {e}"));
    let triangles = scene.instanced_triangles();
    let small = triangles <= BRUTE_MAX_TRIANGLES;
    let mut kinds = Vec::new();
    if cfg!(feature = "embree") {
        kinds.push((AccelKind::Embree, AccelKind::KdTree, RAYS));
        if small {
            kinds.push((AccelKind::Embree, AccelKind::Brute, RAYS));
        }
    }
    if small {
        kinds.push((AccelKind::KdTree, AccelKind::Brute, RAYS));
    } else if kinds.is_empty() {
        kinds.push((
            AccelKind::KdTree,
            AccelKind::Brute,
            (BRUTE_BUDGET / triangles.max(1)).clamp(16, RAYS),
        ));
    }
    assert!(!kinds.is_empty(), "{name}: no accelerator pair to cross-check");
    kinds
        .into_iter()
        .map(|(a, b, rays)| (build(a), build(b), rays))
        .collect()
}

/// The report must hold no disagreement; ties must stay rare on the rays
/// that do not aim at edges on purpose (camera and bounds rays).
fn assert_clean(name: &str, report: &CrosscheckReport) {
    eprintln!("{name}\n{report}");
    assert!(report.is_ok(), "{name}: disagreements\n{report}");
    let mut ordinary_rays = 0;
    let mut ordinary_ties = 0;
    for kind in [RayKind::Camera, RayKind::Bounds] {
        let k = report.kind(kind);
        ordinary_rays += k.rays;
        ordinary_ties += k.ties + k.occlusion_ties;
    }
    assert!(
        ordinary_ties * 200 <= ordinary_rays,
        "{name}: {ordinary_ties} ties on {ordinary_rays} camera and bounds rays (more than 0.5%)\n{report}"
    );
}

#[test]
fn every_scene_file_crosschecks() {
    let files = scene_files(&["scenes", "scenes/test"]);
    assert!(!files.is_empty(), "no scene file found");
    let mut checked = 0;
    for path in &files {
        let name = path.display().to_string();
        let scene = load_scene(path).unwrap_or_else(|e| panic!("{name} does not load: {e}"));
        for (a, b, rays) in pairs(&scene.scene, &name) {
            let report = crosscheck(
                &scene.scene,
                a.as_ref(),
                b.as_ref(),
                &CrosscheckOptions {
                    rays,
                    seed: scene.settings.seed,
                    image: (scene.settings.width, scene.settings.height),
                },
            );
            assert_clean(&format!("{name}: {} vs {}", report.a_name, report.b_name), &report);
            assert_eq!(report.total().rays, rays);
            checked += 1;
        }
    }
    assert!(checked > 0, "no scene of {files:?} could be cross-checked");
}

/// Instanced meshes (two BLAS, eight instances with rotations and non-uniform
/// scales), a triangle soup with overlapping and intersecting triangles,
/// spheres and quads: the scene files of this branch have no mesh yet.
#[test]
fn instanced_mesh_scene_crosschecks() {
    let scene = common::scenes::test_scene();
    for (a, b, rays) in pairs(&scene, "instanced test scene") {
        let report = crosscheck(
            &scene,
            a.as_ref(),
            b.as_ref(),
            &CrosscheckOptions {
                rays,
                seed: 2024,
                image: (640, 480),
            },
        );
        let name = format!("instanced test scene, {} vs {}", report.a_name, report.b_name);
        assert_clean(&name, &report);
        // Rays aimed at vertices and edges must mostly reach geometry, or
        // they do not exercise the boundaries.
        let feature = report.kind(RayKind::Feature);
        assert!(
            feature.hits * 2 > feature.rays,
            "{name}: feature rays rarely hit\n{report}"
        );
    }
}

/// A million rays on the dragon, Embree against the KD-tree.
#[test]
#[cfg_attr(
    not(feature = "embree"),
    ignore = "needs Embree: brute force cannot check 1M rays against 871k triangles"
)]
fn dragon_crosschecks_on_a_million_rays() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dragon.toml");
    let scene = load_scene(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let options = AccelOptions::default();
    let embree = accel::build(&scene.scene, AccelKind::Embree, &options).unwrap();
    let kdtree = accel::build(&scene.scene, AccelKind::KdTree, &options).unwrap();
    let report = crosscheck(
        &scene.scene,
        embree.as_ref(),
        kdtree.as_ref(),
        &CrosscheckOptions {
            rays: 1_000_000,
            seed: 1,
            image: (scene.settings.width, scene.settings.height),
        },
    );
    assert_clean("dragon, embree vs kdtree", &report);
}
