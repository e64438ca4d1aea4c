//! End-to-end checks of the Whitted integrator and the render loop on small
//! scenes built in code, against analytic values and against each other.

use caustic::accel::{self, AccelKind, AccelOptions};
use caustic::film::Film;
use caustic::integrator::{render, RenderOutput, RenderPlan, RenderSetup};
use caustic::math::{Vec3, Vec3A};
use caustic::scene::{
    AreaLight, Camera, Dielectric, Light, LoadedScene, Material, Mirror, Object, Quad, RenderSettings, SampleSharing,
    Scene, Shape, Sphere,
};
use std::f32::consts::PI;

fn settings(width: u32, height: u32, spp: u32) -> RenderSettings {
    RenderSettings {
        width,
        height,
        spp,
        seed: 7,
        ..Default::default()
    }
}

fn quad(corner: [f32; 3], u: [f32; 3], v: [f32; 3], material: u32) -> Object {
    Object {
        name: "quad".into(),
        shape: Shape::Quad(Quad::new(corner.into(), u.into(), v.into()).unwrap()),
        material,
    }
}

fn sphere(center: [f32; 3], radius: f32, material: u32) -> Object {
    Object {
        name: "sphere".into(),
        shape: Shape::Sphere(Sphere {
            center: center.into(),
            radius,
        }),
        material,
    }
}

/// A floor in the plane y = 0 spanning [-h, h]², facing +y.
fn floor(h: f32, material: u32) -> Object {
    quad([-h, 0.0, h], [2.0 * h, 0.0, 0.0], [0.0, 0.0, -2.0 * h], material)
}

fn camera(pos: [f32; 3], at: [f32; 3], up: [f32; 3], fov: f32) -> Camera {
    Camera::new(pos.into(), at.into(), up.into(), fov).unwrap()
}

fn render_scene(s: &LoadedScene) -> RenderOutput {
    let accel = accel::build(&s.scene, AccelKind::Brute, &AccelOptions::default()).unwrap();
    let plan = RenderPlan::new(&s.scene, &s.settings);
    render(&s.scene, accel.as_ref(), &plan, RenderSetup::default())
}

/// Film coordinates (pixels, origin top-left) of world point `p`.
fn project(scene: &LoadedScene, p: Vec3A) -> (f32, f32) {
    let c = &scene.scene.camera;
    let (w, h) = (scene.settings.width as f32, scene.settings.height as f32);
    let tan_half = (c.fov_deg.to_radians() * 0.5).tan();
    let d = p - c.position;
    let z = d.dot(c.forward);
    let sx = d.dot(c.right) / z / (tan_half * w / h);
    let sy = d.dot(c.up) / z / tan_half;
    ((sx + 1.0) * 0.5 * w, (1.0 - sy) * 0.5 * h)
}

fn pixel_at(scene: &LoadedScene, film: &Film, p: Vec3A) -> Vec3 {
    let (x, y) = project(scene, p);
    film.get(x as u32, y as u32)
}

fn rel_err(a: Vec3, b: Vec3) -> f32 {
    ((a - b).abs() / b.abs().max(Vec3::splat(1e-12))).max_element()
}

fn albedo() -> Vec3A {
    Vec3A::new(0.6, 0.5, 0.4)
}

fn lit_floor_scene(spp: u32) -> LoadedScene {
    LoadedScene {
        scene: Scene {
            media: Default::default(),
            camera: camera([0.0, 3.0, 3.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0], 40.0),
            materials: vec![Material::diffuse("floor", albedo())],
            lights: vec![Light::Point {
                position: Vec3A::new(0.0, 2.0, 0.0),
                intensity: Vec3A::splat(10.0),
            }],
            meshes: vec![],
            objects: vec![floor(5.0, 0)],
            ambient: Vec3A::ZERO,
            water_medium: None,
        },
        settings: settings(65, 65, spp),
    }
}

#[test]
fn diffuse_floor_under_a_point_light_has_the_analytic_radiance() {
    let scene = lit_floor_scene(16);
    let out = render_scene(&scene);
    let light = Vec3A::new(0.0, 2.0, 0.0);
    // L = albedo/π · I cos θ / r² at floor points seen through pixel centres.
    for p in [Vec3A::ZERO, Vec3A::new(0.8, 0.0, 0.3), Vec3A::new(-1.2, 0.0, -0.5)] {
        let (x, y) = project(&scene, p);
        // The point seen through the exact centre of that pixel.
        let ray = scene.scene.camera.ray(x.floor() + 0.5, y.floor() + 0.5, 65, 65);
        let t = -ray.origin.y / ray.dir.y;
        let q = ray.at(t);
        let to = light - q;
        let cos = to.y / to.length();
        let expected = Vec3::from(albedo() / PI * 10.0 * cos / to.length_squared());
        let got = out.film.get(x as u32, y as u32);
        assert!(rel_err(got, expected) < 0.01, "at {p}: got {got}, expected {expected}");
    }
    assert_eq!(out.stats.dropped_samples, 0);
    assert_eq!(out.stats.rays.camera, 65 * 65 * 16);
    assert_eq!(out.stats.rays.secondary, 0);
}

#[test]
fn shadowed_region_is_darker_than_the_lit_floor() {
    let mut scene = lit_floor_scene(4);
    scene.scene.ambient = Vec3A::splat(0.1);
    scene.scene.lights[0] = Light::Point {
        position: Vec3A::new(0.0, 4.0, 0.0),
        intensity: Vec3A::splat(20.0),
    };
    scene.scene.objects.push(sphere([0.0, 1.0, 0.0], 0.5, 0));
    let out = render_scene(&scene);
    let shadow = pixel_at(&scene, &out.film, Vec3A::new(0.0, 0.0, 0.0));
    let lit = pixel_at(&scene, &out.film, Vec3A::new(1.5, 0.0, 0.0));
    // In the umbra only the ambient term remains: ambient × material ambient.
    let ambient = Vec3::from(Vec3A::splat(0.1) * albedo());
    assert!(rel_err(shadow, ambient) < 1e-4, "shadow {shadow} vs ambient {ambient}");
    assert!(lit.x > 3.0 * shadow.x, "lit {lit} vs shadow {shadow}");
}

#[test]
fn a_mirror_shows_the_reflected_objects_colour() {
    let red = Material::diffuse("red", Vec3A::new(0.8, 0.05, 0.05));
    let mirror = Material {
        mirror: Some(Mirror {
            reflectivity: 1.0,
            tint: Vec3A::ONE,
        }),
        ..Material::diffuse("mirror", Vec3A::splat(0.5))
    };
    let mut scene = LoadedScene {
        scene: Scene {
            media: Default::default(),
            camera: camera([0.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0], 30.0),
            materials: vec![red, mirror],
            lights: vec![Light::Point {
                position: Vec3A::new(0.0, 1.5, -1.0),
                intensity: Vec3A::splat(5.0),
            }],
            meshes: vec![],
            // The mirror faces the camera; the red sphere is behind the camera.
            objects: vec![
                quad([-2.0, -2.0, -3.0], [4.0, 0.0, 0.0], [0.0, 4.0, 0.0], 1),
                sphere([0.0, 0.0, 2.0], 0.5, 0),
            ],
            ambient: Vec3A::ZERO,
            water_medium: None,
        },
        settings: settings(33, 33, 1),
    };
    let out = render_scene(&scene);
    let c = out.film.get(16, 16);
    assert!(c.x > 0.01 && c.x > 5.0 * c.y && c.x > 5.0 * c.z, "centre {c}");
    assert!(out.stats.rays.secondary > 0);
    // The same wall without the mirror is grey, not red.
    scene.scene.materials[1].mirror = None;
    let grey = render_scene(&scene).film.get(16, 16);
    assert!(grey.x < 2.0 * grey.y, "{grey}");
}

fn glass() -> Material {
    Material {
        dielectric: Some(Dielectric::smooth(1.5, Vec3A::ONE)),
        specular: Vec3A::ZERO,
        ..Material::diffuse("glass", Vec3A::ZERO)
    }
}

#[test]
fn a_glass_sphere_refracts_and_is_not_black_at_its_centre() {
    let light = Vec3A::new(0.0, 2.5, -4.5);
    let mut scene = LoadedScene {
        scene: Scene {
            media: Default::default(),
            camera: camera([0.0, 0.0, 2.0], [0.0, 0.0, -2.0], [0.0, 1.0, 0.0], 40.0),
            materials: vec![Material::diffuse("wall", Vec3A::splat(0.8)), glass()],
            lights: vec![Light::Point {
                position: light,
                intensity: Vec3A::splat(20.0),
            }],
            meshes: vec![],
            objects: vec![
                quad([-10.0, -10.0, -5.0], [20.0, 0.0, 0.0], [0.0, 20.0, 0.0], 0),
                sphere([0.0, 0.0, -2.0], 0.7, 1),
            ],
            ambient: Vec3A::ZERO,
            water_medium: None,
        },
        settings: settings(33, 33, 4),
    };
    let out = render_scene(&scene);
    // Straight through the centre the ray crosses two interfaces at normal
    // incidence: about (1 − 0.04)² of the wall behind.
    let to = light - Vec3A::new(0.0, 0.0, -5.0);
    let wall = 0.8 / PI * 20.0 * (to.z / to.length()) / to.length_squared();
    // The mean of the 3×3 central pixels (36 samples): at 4 spp one pixel
    // alone is at the mercy of its samples' Fresnel choices (a sample that
    // reflects at either interface sees black: 1 or 2 of 4 often do).
    let mut c = Vec3::ZERO;
    for y in 15..18 {
        for x in 15..18 {
            c += out.film.get(x, y) / 9.0;
        }
    }
    assert!(c.x > 0.6 * wall && c.x < 1.05 * wall, "centre {c}, wall {wall}");
    // The rim reflects at grazing angles and is not empty either; and the
    // glass really is what makes the centre bright: no bounces → black.
    scene.settings.max_depth = Some(0);
    let flat = render_scene(&scene).film.get(16, 16);
    assert_eq!(flat, Vec3::ZERO);
}

#[test]
fn a_glass_ball_lens_inverts_the_wall_behind_it() {
    // Wall: red left half (x < 0), green right half. A glass ball (n = 1.5,
    // focal length nD / 4(n − 1) = 1.05 from its centre) focuses well in
    // front of the wall, so the view through it is flipped: right of the
    // centre one sees red. An inverted IOR ratio would make it diverge and
    // show green there.
    let scene = LoadedScene {
        scene: Scene {
            media: Default::default(),
            camera: camera([0.0, 0.0, 2.0], [0.0, 0.0, -2.0], [0.0, 1.0, 0.0], 40.0),
            materials: vec![
                Material::diffuse("red", Vec3A::new(0.8, 0.05, 0.05)),
                Material::diffuse("green", Vec3A::new(0.05, 0.8, 0.05)),
                glass(),
            ],
            lights: vec![Light::Point {
                position: Vec3A::new(0.0, 2.5, -3.5),
                intensity: Vec3A::splat(20.0),
            }],
            meshes: vec![],
            objects: vec![
                quad([-10.0, -10.0, -5.0], [10.0, 0.0, 0.0], [0.0, 20.0, 0.0], 0),
                quad([0.0, -10.0, -5.0], [10.0, 0.0, 0.0], [0.0, 20.0, 0.0], 1),
                sphere([0.0, 0.0, -2.0], 0.7, 2),
            ],
            ambient: Vec3A::ZERO,
            water_medium: None,
        },
        settings: settings(33, 33, 4),
    };
    let out = render_scene(&scene);
    let through_right = pixel_at(&scene, &out.film, Vec3A::new(0.3, 0.0, -2.0));
    let through_left = pixel_at(&scene, &out.film, Vec3A::new(-0.3, 0.0, -2.0));
    let beside_right = pixel_at(&scene, &out.film, Vec3A::new(1.5, 0.0, -5.0));
    assert!(through_right.x > 3.0 * through_right.y, "{through_right}");
    assert!(through_left.y > 3.0 * through_left.x, "{through_left}");
    assert!(beside_right.y > 3.0 * beside_right.x, "{beside_right}");
}

fn area_light_scene(with_occluder: bool, samples: u32, spp: u32) -> LoadedScene {
    let light = AreaLight::new(
        Vec3A::new(0.0, 3.0, 0.0),
        Vec3A::new(1.0, 0.0, 0.0),
        Vec3A::new(0.0, 0.0, 1.0),
        Vec3A::splat(8.0),
        samples,
    )
    .unwrap();
    assert!(light.normal.y < 0.0, "emits downward");
    let mut objects = vec![floor(6.0, 0)];
    if with_occluder {
        objects.push(sphere([0.0, 1.0, 0.0], 0.5, 0));
    }
    LoadedScene {
        scene: Scene {
            media: Default::default(),
            camera: camera([1.0, 2.0, 5.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 45.0),
            materials: vec![Material::diffuse("floor", albedo())],
            lights: vec![Light::Area(light)],
            meshes: vec![],
            objects,
            ambient: Vec3A::ZERO,
            water_medium: None,
        },
        settings: settings(64, 48, spp),
    }
}

#[test]
fn area_light_soft_shadow_has_a_penumbra() {
    let shadowed = render_scene(&area_light_scene(true, 64, 1));
    let open = render_scene(&area_light_scene(false, 64, 1));
    let scene = area_light_scene(true, 64, 1);
    let ratio = |x: f32| {
        let p = Vec3A::new(x, 0.0, 0.0);
        let a = pixel_at(&scene, &shadowed.film, p);
        let b = pixel_at(&scene, &open.film, p);
        assert!(b.x > 0.0, "open floor lit at x = {x}");
        a.x / b.x
    };
    assert!(ratio(0.0) < 0.02, "umbra {}", ratio(0.0));
    assert!(ratio(2.5) > 0.999, "lit {}", ratio(2.5));
    let steps: Vec<f32> = (0..=50).map(|i| ratio(i as f32 * 0.05)).collect();
    let penumbra = steps.iter().filter(|r| **r > 0.2 && **r < 0.8).count();
    assert!(penumbra >= 3, "no penumbra: {steps:?}");
    // Darkness decreases away from the occluder (up to noise).
    for w in steps.windows(2) {
        assert!(w[1] >= w[0] - 0.1, "{steps:?}");
    }
}

#[test]
fn the_area_light_is_visible_from_its_emitting_side_only() {
    let mut scene = area_light_scene(false, 4, 1);
    // Looking up at the light from below: its radiance.
    scene.scene.camera = camera([0.0, 0.5, 0.0], [0.0, 3.0, 0.0], [0.0, 0.0, -1.0], 20.0);
    let out = render_scene(&scene);
    assert_eq!(out.film.get(32, 24), Vec3::splat(8.0));
    // From above, looking down through its back: the lit floor, not 8.
    scene.scene.camera = camera([0.0, 5.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, -1.0], 20.0);
    let c = render_scene(&scene).film.get(32, 24);
    assert!(c.x > 0.0 && c.x < 2.0, "{c}");
}

/// Area light, occluder, glass sphere and a mirror: every random decision.
fn mixed_scene(sharing: SampleSharing, spp: u32) -> LoadedScene {
    let mut scene = area_light_scene(true, 16, spp);
    scene.settings.sharing = sharing;
    scene.settings.width = 40;
    scene.settings.height = 30;
    scene.scene.materials.push(glass());
    scene.scene.materials.push(Material {
        mirror: Some(Mirror {
            reflectivity: 0.6,
            tint: Vec3A::new(0.9, 0.9, 1.0),
        }),
        specular: Vec3A::splat(0.3),
        shininess: 40.0,
        ..Material::diffuse("mirror", Vec3A::new(0.2, 0.4, 0.2))
    });
    scene.scene.objects.push(sphere([1.6, 0.6, 0.8], 0.6, 1));
    scene.scene.objects.push(sphere([-0.9, 0.5, 1.5], 0.5, 2));
    scene
}

#[test]
fn spread_and_split_converge_to_the_same_image() {
    let spread = render_scene(&mixed_scene(SampleSharing::Spread, 16));
    let split = render_scene(&mixed_scene(SampleSharing::Split, 16));
    let (a, b) = (spread.film.mean(), split.film.mean());
    assert!(rel_err(a, b) < 0.02, "spread {a} vs split {b}");
    // Per-region means too (quarters of the image).
    for (x0, y0) in [(0, 0), (20, 0), (0, 15), (20, 15)] {
        let a = spread.film.mean_over(x0, y0, x0 + 20, y0 + 15);
        let b = split.film.mean_over(x0, y0, x0 + 20, y0 + 15);
        assert!(
            (a - b).abs().max_element() < 0.03 * b.max_element().max(0.05),
            "{x0},{y0}: {a} vs {b}"
        );
    }
    // ... with far fewer rays: one shadow stratum per sample instead of 16.
    assert!(spread.stats.rays.shadow * 4 < split.stats.rays.shadow);
    assert!(spread.stats.rays.secondary < split.stats.rays.secondary);
    assert_eq!(spread.stats.rays.camera, split.stats.rays.camera);
}

#[test]
fn the_image_is_identical_for_one_and_two_threads() {
    let mut scene = mixed_scene(SampleSharing::Spread, 4);
    scene.settings.width = 70; // several tiles, a partial one at the edge
    scene.settings.height = 40;
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| render_scene(&scene))
    };
    let one = run(1);
    let two = run(2);
    assert!(one
        .film
        .pixels
        .iter()
        .zip(&two.film.pixels)
        .all(|(a, b)| a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits)));
    assert_eq!(one.stats.rays, two.stats.rays);
    // And a different seed gives a different image (the test can fail).
    scene.settings.seed += 1;
    let other = render_scene(&scene);
    assert_ne!(other.film.pixels, one.film.pixels);
}

#[test]
fn nan_samples_are_dropped_and_counted() {
    let mut scene = lit_floor_scene(2);
    scene.settings.width = 20;
    scene.settings.height = 20;
    scene.scene.lights.push(Light::Point {
        position: Vec3A::new(0.0, 2.0, 0.0),
        intensity: Vec3A::splat(f32::NAN),
    });
    let out = render_scene(&scene);
    assert!(out.film.pixels.iter().all(|p| p.is_finite()));
    // Every sample that hits the floor is poisoned; misses are black and finite.
    assert!(out.stats.dropped_samples > 0);
    assert!(out.stats.dropped_samples <= out.stats.samples);
    assert!(out
        .stats
        .to_string()
        .contains(&format!("dropped (NaN/inf): {}", out.stats.dropped_samples)));
}

#[test]
fn progress_reports_every_pixel() {
    let scene = area_light_scene(true, 4, 1);
    let accel = accel::build(&scene.scene, AccelKind::Brute, &AccelOptions::default()).unwrap();
    let plan = RenderPlan::new(&scene.scene, &scene.settings);
    let calls = std::sync::Mutex::new(Vec::new());
    render(
        &scene.scene,
        accel.as_ref(),
        &plan,
        RenderSetup::default().progress(&|done, total| calls.lock().unwrap().push((done, total))),
    );
    let mut calls = calls.into_inner().unwrap();
    calls.sort();
    // 64×48 pixels in 32×32 tiles: 2 × 2 tiles.
    assert_eq!(calls.len(), 4);
    assert_eq!(*calls.last().unwrap(), (64 * 48, 64 * 48));
}

/// The same scene at scale `s` (lengths × s, point intensities × s² so the
/// radiance is unchanged): floor, occluding sphere, mirror sphere.
fn scaled_scene(s: f32) -> LoadedScene {
    let mirror = Material {
        mirror: Some(Mirror {
            reflectivity: 0.7,
            tint: Vec3A::ONE,
        }),
        ..Material::diffuse("mirror", Vec3A::splat(0.3))
    };
    // Without the photon pass: its k-nearest estimate is scale-invariant
    // only up to rank ties between equidistant photons, and this test is
    // about the Whitted rays' offsets.
    let mut settings = settings(48, 48, 1);
    settings.photons.count = 0;
    LoadedScene {
        scene: Scene {
            media: Default::default(),
            camera: camera([0.0, 3.0 * s, 3.0 * s], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0], 50.0),
            materials: vec![Material::diffuse("floor", albedo()), mirror],
            lights: vec![Light::Point {
                position: Vec3A::new(0.3 * s, 3.0 * s, 0.2 * s),
                intensity: Vec3A::splat(10.0 * s * s),
            }],
            meshes: vec![],
            objects: vec![
                floor(5.0 * s, 0),
                sphere([0.0, 0.5 * s, 0.0], 0.5 * s, 0),
                sphere([1.2 * s, 0.4 * s, 0.6 * s], 0.4 * s, 1),
            ],
            ambient: Vec3A::ZERO,
            water_medium: None,
        },
        settings,
    }
}

#[test]
fn no_acne_or_leaks_from_1e_minus_4_to_1e5_units() {
    let reference = render_scene(&scaled_scene(1.0)).film;
    for s in [1.0e-4f32, 1.0e5] {
        let film = render_scene(&scaled_scene(s)).film;
        // Self-shadowing (acne) would darken pixels, leaking would brighten
        // the shadow: allow only rounding-level differences, on a handful of
        // pixels at most (silhouette pixels may flip).
        let differing = film
            .pixels
            .iter()
            .zip(&reference.pixels)
            .filter(|(a, b)| (**a - **b).abs().max_element() > 1e-3 * b.max_element().max(1e-3))
            .count();
        assert!(differing <= 10, "scale {s}: {differing} pixels differ");
        assert!(rel_err(film.mean(), reference.mean()) < 2e-3, "scale {s}");
    }
    // The sphere's lower half is shadowed by itself, the floor is in its
    // shadow, and both are exactly black (no ambient): light does not leak.
    let scene = scaled_scene(1.0);
    assert_eq!(pixel_at(&scene, &reference, Vec3A::new(-0.25, 0.0, 0.35)), Vec3::ZERO);
}
