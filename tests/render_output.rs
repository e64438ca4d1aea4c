//! A rendered film written to PNG and EXR: atomic (no temporary file left)
//! and faithful (the EXR reads back bit for bit, the PNG is the tone-mapped film).

use caustic::accel::{self, AccelKind, AccelOptions};
use caustic::film::{check_writable, tonemap_to_srgb8, write_exr, write_png};
use caustic::integrator::{render, RenderPlan, RenderSetup};
use caustic::math::Vec3A;
use caustic::scene::LoadedScene;
use caustic::scene::{Camera, Light, Material, Object, Quad, RenderSettings, Scene, Shape, Sphere};

fn small_scene() -> LoadedScene {
    LoadedScene {
        scene: Scene {
            media: Default::default(),
            camera: Camera::new(Vec3A::new(0.0, 2.0, 4.0), Vec3A::ZERO, Vec3A::Y, 45.0).unwrap(),
            materials: vec![Material::diffuse("white", Vec3A::splat(0.7))],
            lights: vec![Light::Point {
                position: Vec3A::new(1.0, 3.0, 1.0),
                intensity: Vec3A::new(30.0, 20.0, 10.0),
            }],
            meshes: vec![],
            objects: vec![
                Object {
                    name: "floor".into(),
                    shape: Shape::Quad(Quad::new(Vec3A::new(-3.0, 0.0, 3.0), Vec3A::X * 6.0, Vec3A::Z * -6.0).unwrap()),
                    material: 0,
                },
                Object {
                    name: "ball".into(),
                    shape: Shape::Sphere(Sphere {
                        center: Vec3A::new(0.0, 0.5, 0.0),
                        radius: 0.5,
                    }),
                    material: 0,
                },
            ],
            ambient: Vec3A::ZERO,
            water_medium: None,
        },
        settings: RenderSettings {
            width: 37,
            height: 21,
            spp: 2,
            output: caustic::film::OutputSettings {
                exposure: 1.0,
                ..Default::default()
            },
            ..Default::default()
        },
    }
}

#[test]
fn rendered_film_round_trips_through_exr_and_png() {
    use exr::prelude::*;
    let scene = small_scene();
    let accel = accel::build(&scene.scene, AccelKind::Brute, &AccelOptions::default()).unwrap();
    let out = render(
        &scene.scene,
        accel.as_ref(),
        &RenderPlan::new(&scene.scene, &scene.settings),
        RenderSetup::default(),
    );
    let dir = tempfile::tempdir().unwrap();
    let (png, exr_path) = (dir.path().join("img.png"), dir.path().join("img.exr"));
    check_writable(&png).unwrap();
    write_png(&png, &out.film, &scene.settings.output).unwrap();
    write_exr(&exr_path, &out.film).unwrap();
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["img.exr", "img.png"], "temporary files left behind");

    let decoded = image::open(&png).unwrap().to_rgb8();
    assert_eq!(decoded.dimensions(), (37, 21));
    assert_eq!(decoded.as_raw(), &tonemap_to_srgb8(&out.film, &scene.settings.output));

    let read = read_first_rgba_layer_from_file(
        &exr_path,
        |res: Vec2<usize>, _| vec![[0f32; 3]; res.area()],
        move |px: &mut Vec<[f32; 3]>, pos: Vec2<usize>, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * 37 + pos.x()] = [r, g, b];
        },
    )
    .unwrap();
    let pixels = &read.layer_data.channel_data.pixels;
    assert!(out.film.pixels.iter().any(|p| p.x > 0.0));
    for (a, b) in out.film.pixels.iter().zip(pixels) {
        assert_eq!(a.to_array(), *b);
    }
}
