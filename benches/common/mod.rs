//! Scenes shared by the Criterion benches: a generated mid-size mesh that
//! every checkout has, and the Stanford dragon when its asset is already on
//! disk (never fetched from a bench).

#![allow(dead_code)] // Each bench binary uses its own part of this module.

use caustic::geometry::generate;
use caustic::io::assets;
use caustic::math::{Transform, Vec3, Vec3A};
use caustic::scene::{self, AreaLight, Camera, Light, Material, Object, Quad, Scene, Shape};
use criterion::Criterion;
use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

/// Criterion settings that keep `cargo bench` to a few minutes: 10 samples,
/// 1 s of warm-up and `seconds` of measurement per benchmark.
pub fn quick(seconds: u64) -> Criterion {
    Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(seconds))
}

/// A torus of 131,072 triangles (512 × 128 segments, smooth) standing on a
/// floor quad in front of a backdrop, lit by an area light and a point light:
/// the dragon scene's layout with a mesh every checkout can generate.
pub fn torus_scene() -> Scene {
    let torus = generate::torus(1.0, 0.35, 512, 128);
    Scene {
        media: Default::default(),
        ambient: Vec3A::ZERO,
        water_medium: None,
        camera: Camera::new(Vec3A::new(0.0, 1.6, 4.3), Vec3A::new(0.0, 0.5, 0.0), Vec3A::Y, 40.0)
            .expect("valid camera"),
        materials: vec![
            Material::diffuse("white", Vec3A::new(0.7, 0.7, 0.7)),
            Material::diffuse("blue", Vec3A::new(0.3, 0.4, 0.6)),
        ],
        lights: vec![
            Light::Area(
                AreaLight::new(
                    Vec3A::new(0.6, 4.0, 1.2),
                    Vec3A::new(1.6, 0.0, 0.0),
                    Vec3A::new(0.0, 0.0, 1.6),
                    Vec3A::splat(10.0),
                    16,
                )
                .expect("valid light"),
            ),
            Light::Point {
                position: Vec3A::new(-3.0, 2.5, 3.0),
                intensity: Vec3A::splat(1.5),
            },
        ],
        meshes: vec![Arc::new(torus)],
        objects: vec![
            Object {
                name: "floor".into(),
                shape: Shape::Quad(
                    Quad::new(
                        Vec3A::new(-7.0, 0.0, -6.0),
                        Vec3A::new(14.0, 0.0, 0.0),
                        Vec3A::new(0.0, 0.0, 10.0),
                    )
                    .expect("valid quad"),
                ),
                material: 0,
            },
            Object {
                name: "backdrop".into(),
                shape: Shape::Quad(
                    Quad::new(
                        Vec3A::new(-7.0, 0.0, -3.0),
                        Vec3A::new(14.0, 0.0, 0.0),
                        Vec3A::new(0.0, 6.0, 0.0),
                    )
                    .expect("valid quad"),
                ),
                material: 1,
            },
            Object {
                name: "torus".into(),
                shape: Shape::Mesh {
                    mesh: 0,
                    // Standing up on the floor, tilted towards the camera.
                    transform: Transform::from_srt(Vec3::ONE, Vec3::new(70.0, 0.0, 0.0), Vec3::new(0.0, 1.36, 0.0))
                        .expect("valid transform"),
                    smooth: true,
                },
                material: 0,
            },
        ],
    }
}

/// `scenes/dragon.toml` when `dragon_vrip.ply.gz` is already in one of the
/// asset directories (or the cache); `None` otherwise, with a note on
/// stderr, so a bench without the asset skips the dragon instead of
/// downloading it.
pub fn dragon_scene() -> Option<Scene> {
    const NAME: &str = "dragon_vrip.ply.gz";
    let present = assets::search_dirs()
        .into_iter()
        .chain(assets::cache_dir())
        .any(|d| d.join(NAME).is_file());
    if !present {
        eprintln!("the dragon asset ({NAME}) is not on disk: dragon benches skipped");
        return None;
    }
    match scene::load_scene(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dragon.toml")) {
        Ok(s) => Some(s.scene),
        Err(e) => {
            eprintln!("dragon benches skipped: {e}");
            None
        }
    }
}
