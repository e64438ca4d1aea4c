//! Whole images rendered with Embree and with the KD-tree at the same seed
//! agree pixel for pixel (up to ties at shared edges, which may pick either
//! neighbour, and last-ulp differences in t).

#![cfg(feature = "embree")]

mod common;

use caustic::accel::AccelKind;
use caustic::scene::load_scene;
use std::path::Path;

/// Bounds: mean |Δ| per channel below 1e-3 of the mean radiance, and at
/// most 0.2% of pixels differing by more than 1% of the image's mean.
fn compare(name: &str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(name);
    let mut scene = load_scene(&path).unwrap();
    scene.settings.width = 160;
    scene.settings.height = 90;
    scene.settings.spp = 2;
    scene.settings.photons.count = 20_000;
    let (a, b) = (
        common::render::film(&scene, AccelKind::Embree),
        common::render::film(&scene, AccelKind::KdTree),
    );
    let mean = a.mean();
    let scale = (mean.x + mean.y + mean.z) / 3.0;
    assert!(scale > 0.0, "{name}: black image");
    let (mut sum, mut outliers, mut n) = (0.0f64, 0usize, 0usize);
    for y in 0..a.height {
        for x in 0..a.width {
            let d = (a.get(x, y) - b.get(x, y)).abs().max_element();
            sum += d as f64;
            n += 1;
            if d > 0.01 * scale {
                outliers += 1;
            }
        }
    }
    let mean_diff = sum / n as f64;
    assert!(
        mean_diff < 1e-3 * scale as f64,
        "{name}: mean |Δ| {mean_diff} vs mean radiance {scale}"
    );
    assert!(
        outliers * 500 <= n,
        "{name}: {outliers} of {n} pixels differ by more than 1%"
    );
}

#[test]
fn cornell_is_the_same_image_with_embree_and_the_kdtree() {
    compare("scenes/cornell.toml");
}

#[test]
fn test_scenes_are_the_same_image_with_embree_and_the_kdtree() {
    for name in [
        "scenes/test/mirror.toml",
        "scenes/test/glass.toml",
        "scenes/test/shadow.toml",
    ] {
        compare(name);
    }
}
