//! The path integrator on scenes with known answers: a white furnace (an
//! albedo-1 diffuse object in a uniform environment looks exactly like the
//! environment), an area light seen directly, and determinism.

use caustic::accel::{self, AccelKind, AccelOptions};
use caustic::integrator::{render, RenderPlan, RenderSetup};
use caustic::math::Vec3A;
use caustic::scene::LoadedScene;
use caustic::scene::{Camera, IntegratorKind, Light, Material, Object, RenderSettings, Scene, Shape, Sphere};

fn furnace(albedo: f32, radiance: f32) -> LoadedScene {
    LoadedScene {
        scene: Scene {
            media: Default::default(),
            camera: Camera::new(Vec3A::new(0.0, 0.0, 4.0), Vec3A::ZERO, Vec3A::Y, 30.0).unwrap(),
            materials: vec![Material::diffuse("white", Vec3A::splat(albedo))],
            lights: vec![Light::Environment {
                radiance: Vec3A::splat(radiance),
                map: None,
            }],
            meshes: vec![],
            objects: vec![
                Object {
                    name: "ball".into(),
                    shape: Shape::Sphere(Sphere {
                        center: Vec3A::ZERO,
                        radius: 1.0,
                    }),
                    material: 0,
                },
                Object {
                    name: "second ball".into(),
                    shape: Shape::Sphere(Sphere {
                        center: Vec3A::new(1.4, 0.8, -1.0),
                        radius: 0.6,
                    }),
                    material: 0,
                },
            ],
            ambient: Vec3A::ZERO,
            water_medium: None,
        },
        settings: RenderSettings {
            width: 24,
            height: 24,
            spp: 64,
            integrator: IntegratorKind::Path,
            ..Default::default()
        },
    }
}

fn mean_and_spread(scene: &LoadedScene) -> (f64, f64) {
    let accel = accel::build(&scene.scene, AccelKind::KdTree, &AccelOptions::default()).unwrap();
    let out = render(
        &scene.scene,
        accel.as_ref(),
        &RenderPlan::new(&scene.scene, &scene.settings),
        RenderSetup::default(),
    );
    let px: Vec<f64> = out
        .film
        .pixels
        .iter()
        .flat_map(|p| p.to_array())
        .map(f64::from)
        .collect();
    let mean = px.iter().sum::<f64>() / px.len() as f64;
    let max_dev = px.iter().map(|p| (p - mean).abs()).fold(0.0, f64::max);
    (mean, max_dev)
}

/// Every pixel, object or background, is the environment's radiance: the
/// estimator neither gains nor loses energy through bounces, Russian
/// roulette or the MIS weights (they must sum to one).
#[test]
fn white_furnace_renders_the_environment() {
    let (mean, _) = mean_and_spread(&furnace(1.0, 0.8));
    assert!((mean - 0.8).abs() < 0.008, "mean {mean}, expected 0.8");
    // Half the albedo: darker, and the objects are not uniform any more.
    let (grey, _) = mean_and_spread(&furnace(0.5, 0.8));
    assert!(grey < 0.78, "{grey}");
}

/// An albedo-1 object whose every pixel sees a different number of
/// bounces still renders the environment pixel by pixel (within noise).
#[test]
fn white_furnace_holds_per_pixel() {
    let mut s = furnace(1.0, 1.0);
    s.settings.spp = 256;
    s.settings.width = 12;
    s.settings.height = 12;
    let (mean, max_dev) = mean_and_spread(&s);
    assert!((mean - 1.0).abs() < 0.01, "{mean}");
    assert!(max_dev < 0.12, "a pixel is {max_dev} away from the mean");
}

#[test]
fn path_renders_are_deterministic_across_thread_counts() {
    let scene = furnace(0.7, 1.0);
    let accel = accel::build(&scene.scene, AccelKind::KdTree, &AccelOptions::default()).unwrap();
    let plan = RenderPlan::new(&scene.scene, &scene.settings);
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let three = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
    let a = one.install(|| render(&scene.scene, accel.as_ref(), &plan, RenderSetup::default()));
    let b = three.install(|| render(&scene.scene, accel.as_ref(), &plan, RenderSetup::default()));
    assert_eq!(a.film.pixels, b.film.pixels);
}

/// Every shipped scene renders in path mode: finite pixels, no dropped
/// sample, something lit.
#[test]
fn every_scene_renders_in_path_mode() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<_> = ["scenes", "scenes/test"]
        .iter()
        .flat_map(|d| std::fs::read_dir(root.join(d)).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 9, "{files:?}");
    for path in files {
        let mut scene = caustic::scene::load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
        let s = &mut scene.settings;
        s.integrator = IntegratorKind::Path;
        s.width = 32;
        s.height = 18;
        s.spp = 2;
        s.photons.count = s.photons.count.min(20_000);
        let accel = accel::build(&scene.scene, AccelKind::default_kind(), &AccelOptions::default()).unwrap();
        let out = render(
            &scene.scene,
            accel.as_ref(),
            &RenderPlan::new(&scene.scene, &scene.settings),
            RenderSetup::default(),
        );
        assert_eq!(out.stats.dropped_samples, 0, "{}", path.display());
        assert!(out.film.pixels.iter().all(|p| p.is_finite()), "{}", path.display());
        // Under water every light path crosses the smooth water surface
        // (light → specular → diffuse): the scene's photon map lights it.
        // A scene of glass alone has nothing diffuse to light.
        let diffuse = scene.scene.objects.iter().any(|o| {
            caustic::bsdf::material_flags(&scene.scene.materials[o.material as usize])
                .contains(caustic::bsdf::LobeFlags::DIFFUSE)
        });
        if !diffuse {
            continue;
        }
        let lit = out.film.pixels.iter().filter(|p| p.max_element() > 0.0).count();
        assert!(
            lit * 4 > out.film.pixels.len(),
            "{}: only {lit} lit pixels",
            path.display()
        );
    }
}
