//! `analysis::crosscheck` on every scene file of `scenes/` and
//! `scenes/test/`, on a synthetic instanced-mesh scene, and on the dragon.
//!
//! Pairs: Embree against the KD-tree is the main pair (both fast on any
//! scene); each is also checked against brute force on small scenes (brute
//! force costs rays × triangles). The rules (what is an agreement, a tie, a
//! disagreement) are the library's: see `caustic::analysis::crosscheck`.
//!
//! A scene is skipped only when a mesh it references cannot be loaded (a
//! missing asset, or a loader not built yet), and the reason is printed; any
//! other load error fails the test.

#[path = "embree_support/mod.rs"]
mod embree_support;

use caustic::accel::{self, Accel, AccelKind, AccelOptions};
use caustic::analysis::crosscheck::{crosscheck, CrosscheckOptions, CrosscheckReport, RayKind};
use caustic::scene::{load_scene, Scene, SceneError};
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
        let Ok(entries) = std::fs::read_dir(root.join(dir)) else {
            eprintln!("no directory {dir}");
            continue;
        };
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

/// True when the KD-tree backend is the brute-force scaffold of a branch
/// where the real tree has not been merged yet (it reports brute's stats).
fn kdtree_is_scaffold(kd: &dyn Accel) -> bool {
    kd.stats().name == "brute"
}

/// The accelerator pairs worth running on `scene`, built.
fn pairs(scene: &Scene, name: &str) -> Vec<(Box<dyn Accel>, Box<dyn Accel>)> {
    let options = AccelOptions::default();
    let build = |kind| accel::build(scene, kind, &options).unwrap_or_else(|e| panic!("{name}: {e}"));
    let small = scene.instanced_triangles() <= BRUTE_MAX_TRIANGLES;
    let mut kinds = Vec::new();
    if cfg!(feature = "embree") {
        kinds.push((AccelKind::Embree, AccelKind::KdTree));
        if small {
            kinds.push((AccelKind::Embree, AccelKind::Brute));
        }
    }
    if small {
        kinds.push((AccelKind::KdTree, AccelKind::Brute));
    }
    let mut built = Vec::new();
    for (a, b) in kinds {
        let (a, b) = (build(a), build(b));
        if !small && (kdtree_is_scaffold(a.as_ref()) || kdtree_is_scaffold(b.as_ref())) {
            eprintln!(
                "{name}: skipped {} vs {}: the KD-tree of this build is the brute-force scaffold and the scene has {} triangles",
                a.stats().name,
                b.stats().name,
                scene.instanced_triangles()
            );
            continue;
        }
        built.push((a, b));
    }
    if built.is_empty() {
        eprintln!("{name}: no accelerator pair can run on this scene in this build");
    }
    built
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
        let scene = match load_scene(path) {
            Ok(scene) => scene,
            Err(e @ SceneError::Mesh { .. }) => {
                eprintln!("SKIPPED {name}: a mesh cannot be loaded: {e}");
                continue;
            }
            Err(e) => panic!("{name} does not load: {e}"),
        };
        for (a, b) in pairs(&scene, &name) {
            let report = crosscheck(
                &scene,
                a.as_ref(),
                b.as_ref(),
                &CrosscheckOptions {
                    rays: RAYS,
                    seed: scene.settings.seed,
                },
            );
            assert_clean(&format!("{name}: {} vs {}", report.a_name, report.b_name), &report);
            assert_eq!(report.total().rays, RAYS);
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
    let scene = embree_support::test_scene();
    for (a, b) in pairs(&scene, "instanced test scene") {
        let report = crosscheck(
            &scene,
            a.as_ref(),
            b.as_ref(),
            &CrosscheckOptions { rays: RAYS, seed: 2024 },
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

/// The requirement: at least 1M rays on the dragon, Embree against
/// the KD-tree.
#[test]
fn dragon_crosschecks_on_a_million_rays() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dragon.toml");
    if !path.exists() {
        eprintln!("SKIPPED: {} does not exist in this build", path.display());
        return;
    }
    let scene = match load_scene(&path) {
        Ok(scene) => scene,
        Err(e @ SceneError::Mesh { .. }) => {
            eprintln!("SKIPPED {}: the dragon mesh cannot be loaded: {e}", path.display());
            return;
        }
        Err(e) => panic!("{}: {e}", path.display()),
    };
    if !cfg!(feature = "embree") {
        eprintln!("SKIPPED dragon: built without Embree, and brute force cannot do 1M rays on 871k triangles");
        return;
    }
    let options = AccelOptions::default();
    let embree = accel::build(&scene, AccelKind::Embree, &options).unwrap();
    let kdtree = accel::build(&scene, AccelKind::KdTree, &options).unwrap();
    if kdtree_is_scaffold(kdtree.as_ref()) {
        eprintln!("SKIPPED dragon: the KD-tree of this build is the brute-force scaffold");
        return;
    }
    let report = crosscheck(
        &scene,
        embree.as_ref(),
        kdtree.as_ref(),
        &CrosscheckOptions {
            rays: 1_000_000,
            seed: 1,
        },
    );
    assert_clean("dragon, embree vs kdtree", &report);
}
