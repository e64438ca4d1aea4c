//! The photon pass end to end: energy of a mirror caustic against the
//! analytic value, convergence toward a high-photon reference, determinism
//! across thread counts, and the plan skipping the pass.

mod common;

use caustic::accel::AccelKind;
use caustic::film::Film;
use caustic::integrator::photon::{photon_pass, PhotonMap, TraceSettings};
use caustic::integrator::plan::PhotonPlan;
use caustic::integrator::{render, PhotonInput, RenderPlan, RenderSetup};
use caustic::math::Vec3A;
use caustic::scene::LoadedScene;
use caustic::scene::{
    AreaLight, Camera, Dielectric, Light, Material, Mirror, Object, RenderSettings, Scene, Shape, Sphere,
};
use common::metrics::film_rmse;
use common::scenes::{build, quad};

/// A floor in the plane y = 0 spanning [-h, h]², facing +y.
fn floor(h: f32, material: u32) -> Object {
    quad([-h, 0.0, h], [2.0 * h, 0.0, 0.0], [0.0, 0.0, -2.0 * h], material)
}

/// A point light at y = 1 under a horizontal 1×1 mirror at y = 3 facing
/// down; the reflection lands on a large floor.
fn mirror_scene(reflectivity: f32, count: u64) -> LoadedScene {
    let mirror = Material {
        mirror: Some(Mirror {
            reflectivity,
            tint: Vec3A::ONE,
        }),
        ..Material::diffuse("mirror", Vec3A::ZERO)
    };
    let mut settings = RenderSettings {
        width: 32,
        height: 32,
        seed: 3,
        ..Default::default()
    };
    settings.photons.count = count;
    LoadedScene {
        scene: Scene {
            media: Default::default(),
            camera: Camera::new(Vec3A::new(0.0, 2.0, 8.0), Vec3A::ZERO, Vec3A::Y, 40.0).unwrap(),
            materials: vec![Material::diffuse("floor", Vec3A::splat(0.5)), mirror],
            lights: vec![Light::Point {
                position: Vec3A::new(0.0, 1.0, 0.0),
                intensity: Vec3A::new(2.0, 1.0, 0.5),
            }],
            meshes: vec![],
            // The mirror faces −y: u × v = (1,0,0) × (0,0,1) = (0,−1,0).
            objects: vec![
                floor(200.0, 0),
                quad([-0.5, 3.0, -0.5], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0], 1),
            ],
            ambient: Vec3A::ZERO,
            water_medium: None,
        },
        settings,
    }
}

/// Solid angle of an `a × b` rectangle seen from a point at distance `h`
/// on its axis: `4 asin(ab / sqrt((a² + 4h²)(b² + 4h²)))`.
fn rectangle_solid_angle(a: f64, b: f64, h: f64) -> f64 {
    4.0 * (a * b / ((a * a + 4.0 * h * h) * (b * b + 4.0 * h * h)).sqrt()).asin()
}

/// Every photon that hits the mirror is reflected with probability
/// `reflectivity` and lands on the floor: the stored power is
/// `I · Ω_mirror · reflectivity`. With 200k photons the binomial noise of
/// the count is about 0.2% (1σ); the tolerance is 1.5%.
#[test]
fn mirror_caustic_carries_the_expected_energy() {
    for reflectivity in [1.0f32, 0.6] {
        let scene = mirror_scene(reflectivity, 200_000);
        let accel = build(&scene.scene, AccelKind::Brute);
        let (map, stats) = photon_pass(
            &scene.scene,
            TraceSettings::of(&scene.settings),
            accel.as_ref(),
            200_000,
        );
        assert_eq!(stats.emitted, 200_000);
        assert!(stats.stored > 50_000, "{stats}");
        let omega = rectangle_solid_angle(1.0, 1.0, 2.0);
        let expected = [2.0 * omega * reflectivity as f64, omega * reflectivity as f64];
        let got = map.total_power();
        for c in 0..2 {
            let rel = got[c] / expected[c] - 1.0;
            assert!(
                rel.abs() < 0.015,
                "reflectivity {reflectivity}, channel {c}: {} vs {}",
                got[c],
                expected[c]
            );
        }
        // Every stored photon arrived from above (reflected down).
        for i in 0..map.len().min(1000) {
            assert!(map.record(i).incoming().y > 0.0);
        }
    }
}

/// A glass sphere over a floor under a point light: its caustic.
fn glass_scene(count: u64) -> LoadedScene {
    let glass = Material {
        dielectric: Some(Dielectric::smooth(1.5, Vec3A::ONE)),
        ..Material::diffuse("glass", Vec3A::ZERO)
    };
    let mut settings = RenderSettings {
        width: 40,
        height: 30,
        spp: 1,
        seed: 11,
        ..Default::default()
    };
    settings.photons.count = count;
    settings.photons.k = 32;
    settings.photons.max_radius = Some(0.25);
    LoadedScene {
        scene: Scene {
            media: Default::default(),
            camera: Camera::new(Vec3A::new(-1.0, 3.0, 3.0), Vec3A::new(-0.3, 0.0, 0.0), Vec3A::Y, 50.0).unwrap(),
            materials: vec![Material::diffuse("floor", Vec3A::splat(0.8)), glass],
            lights: vec![Light::Area(
                AreaLight::new(
                    Vec3A::new(1.2, 3.0, 0.0),
                    Vec3A::new(0.2, 0.0, 0.0),
                    Vec3A::new(0.0, 0.0, 0.2),
                    Vec3A::splat(300.0),
                    4,
                )
                .unwrap(),
            )],
            meshes: vec![],
            objects: vec![
                floor(4.0, 0),
                Object {
                    name: "glass".into(),
                    shape: Shape::Sphere(Sphere {
                        center: Vec3A::new(0.0, 0.7, 0.0),
                        radius: 0.6,
                    }),
                    material: 1,
                },
            ],
            ambient: Vec3A::ZERO,
            water_medium: None,
        },
        settings,
    }
}

#[test]
fn more_photons_give_lower_error_against_a_reference() {
    let reference = render_caustic(400_000);
    let errors: Vec<f64> = [2_000u64, 10_000, 50_000]
        .iter()
        .map(|&n| film_rmse(&render_caustic(n), &reference))
        .collect();
    assert!(errors[0] > errors[1] && errors[1] > errors[2], "{errors:?}");
    assert!(errors[2] < 0.5 * errors[0], "{errors:?}");
    // The caustic is really there: brighter than the same floor without photons.
    let mut dark = glass_scene(0);
    dark.settings.photons.count = 0;
    let accel = build(&dark.scene, AccelKind::Brute);
    let plan = RenderPlan::new(&dark.scene, &dark.settings);
    assert_eq!(plan.photons, PhotonPlan::CountZero);
    let without = render(
        &dark.scene,
        accel.as_ref(),
        &plan,
        RenderSetup::default().photons(PhotonInput::Map(None)),
    )
    .film;
    // Under the sphere, its shadow in direct light holds the focused caustic.
    let brighter = reference
        .pixels
        .iter()
        .zip(&without.pixels)
        .filter(|(a, b)| a.x > 2.0 * b.x + 0.05)
        .count();
    if std::env::var_os("CAUSTIC_TEST_PNG").is_some() {
        let st = RenderSettings::default();
        caustic::film::write_png(std::path::Path::new("/tmp/t_ref.png"), &reference, &st.output).unwrap();
        caustic::film::write_png(std::path::Path::new("/tmp/t_dark.png"), &without, &st.output).unwrap();
    }
    assert!(brighter >= 4, "{brighter} pixels show a caustic");
}

fn render_caustic(count: u64) -> Film {
    let scene = glass_scene(count);
    let accel = build(&scene.scene, AccelKind::Brute);
    let plan = RenderPlan::new(&scene.scene, &scene.settings);
    render(&scene.scene, accel.as_ref(), &plan, RenderSetup::default()).film
}

#[test]
fn photon_maps_and_images_are_identical_for_one_and_two_threads() {
    let scene = glass_scene(30_000);
    let accel = build(&scene.scene, AccelKind::Brute);
    let plan = RenderPlan::new(&scene.scene, &scene.settings);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| render(&scene.scene, accel.as_ref(), &plan, RenderSetup::default()))
    };
    let (one, two) = (run(1), run(2));
    assert_eq!(one.film, two.film);
    let (m1, m2): (&PhotonMap, &PhotonMap) = (one.photon_map.as_ref().unwrap(), two.photon_map.as_ref().unwrap());
    assert_eq!(m1.len(), m2.len());
    assert!((0..m1.len()).all(|i| m1.record(i) == m2.record(i)));
    assert_eq!(one.stats.photons.as_ref().unwrap().stored, m1.len() as u64);
}

#[test]
fn no_photon_pass_without_a_specular_caster() {
    let mut scene = glass_scene(10_000);
    scene.scene.materials[1] = Material::diffuse("not glass", Vec3A::splat(0.5));
    let accel = build(&scene.scene, AccelKind::Brute);
    let plan = RenderPlan::new(&scene.scene, &scene.settings);
    assert_eq!(plan.photons, PhotonPlan::NoSpecularCaster);
    assert!(plan.to_string().contains("photon pass: skipped (no specular caster)"));
    let out = render(&scene.scene, accel.as_ref(), &plan, RenderSetup::default());
    assert!(out.photon_map.is_none() && out.stats.photons.is_none());
}
