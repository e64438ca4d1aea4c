//! Lights behind one interface: spot and directional lights against their
//! closed forms, emission on any shape (sphere, quad, triangle mesh,
//! textured) in the path and Whitted integrators, photons from every kind,
//! and the scene keys.

mod common;

use caustic::accel::{self, AccelKind, AccelOptions};
use caustic::integrator::photon::{Caster, PhotonTracer, TraceSettings};
use caustic::math::{Vec2, Vec3A};
use caustic::scene::light::{Emitter, SpotFalloff};
use caustic::scene::LoadedScene;
use caustic::scene::{parse_scene, Light};
use std::f32::consts::PI;
use std::path::Path;

fn load(text: &str) -> LoadedScene {
    parse_scene(text, Path::new("lights.toml")).unwrap_or_else(|e| panic!("{e}"))
}

fn load_err(text: &str) -> String {
    parse_scene(text, Path::new("lights.toml")).unwrap_err().to_string()
}

/// The rendered film's pixels (x, y) → linear RGB.
fn film(scene: &LoadedScene) -> caustic::film::Film {
    common::render::film(scene, AccelKind::KdTree)
}

fn mean(f: &caustic::film::Film) -> Vec3A {
    f.pixels.iter().fold(Vec3A::ZERO, |s, p| s + Vec3A::from(*p)) / f.pixels.len() as f32
}

/// A 2 × 2 floor (y = 0) of albedo 0.5 seen straight down from above by a
/// camera that sees only the floor, lit by `light` (path tracing, one
/// bounce: direct light only).
fn floor_scene(light: &str, spp: u32) -> String {
    format!(
        "[render]\nwidth = 32\nheight = 32\nspp = {spp}\nintegrator = \"path\"\nmax_depth = 1\nseed = 3\n\
         [camera]\nposition = [0.0, 3.0, 0.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, -1.0]\nvfov = 30\n\
         [materials.floor]\ndiffuse = 0.5\n\
         [[objects]]\ntype = \"quad\"\ncenter = [0.0, 0.0, 0.0]\nsize = [4.0, 4.0]\nnormal = [0.0, 1.0, 0.0]\n\
         up = [0.0, 0.0, -1.0]\nmaterial = \"floor\"\n{light}\n"
    )
}

/// The floor point pixel `(x, y)`'s centre sees.
fn floor_point(scene: &LoadedScene, x: u32, y: u32) -> Vec3A {
    let s = &scene.settings;
    let ray = scene
        .scene
        .camera
        .ray(x as f32 + 0.5, y as f32 + 0.5, s.width, s.height);
    ray.at(-ray.origin.y / ray.dir.y)
}

#[test]
fn a_spot_light_falls_off_as_mitsubas_spot_or_gltfs() {
    for (key, kind) in [("", SpotFalloff::Mitsuba), ("falloff = \"gltf\"", SpotFalloff::Gltf)] {
        let scene = load(&floor_scene(
            &format!(
                "[[lights]]\ntype = \"spot\"\nposition = [0.0, 1.0, 0.0]\nlook_at = [0.0, 0.0, 0.0]\n\
                 cutoff_angle = 30\nbeam_width = 15\nintensity = 2.0\n{key}"
            ),
            // Enough samples that each pixel's mean is its centre's value
            // on glTF's steeper ramp too.
            64,
        ));
        let Light::Spot(spot) = scene.scene.lights[0] else {
            panic!()
        };
        assert_eq!(spot.falloff, kind);
        assert!((spot.axis - -Vec3A::Y).length() < 1e-6);
        let f = film(&scene);
        let mut checked = 0;
        for y in 0..32 {
            for x in 0..32 {
                let p = floor_point(&scene, x, y);
                let to = p - spot.position;
                let d2 = to.length_squared();
                let dir = to / d2.sqrt();
                let falloff = spot.falloff(dir);
                let expected = 0.5 / PI * 2.0 * falloff * dir.dot(-Vec3A::Y) / d2;
                let got = f.pixels[(y * 32 + x) as usize].x;
                // Pixels away from the cone's edges, where the footprint of a
                // pixel sees one slope of the falloff.
                let angle = dir.dot(spot.axis).acos().to_degrees();
                if (angle - 30.0).abs() > 1.5 && (angle - 15.0).abs() > 1.5 {
                    assert!(
                        (got - expected).abs() <= 0.02 * expected + 0.003,
                        "{kind:?}: pixel {x},{y} at {angle:.1}°: {got} against {expected}"
                    );
                    checked += 1;
                }
            }
        }
        assert!(checked > 600, "{checked}");
    }
    // glTF's ramp is lower than Mitsuba's between the cones (t² ≤ t).
    let mid = |f: SpotFalloff| caustic::scene::light::SpotLight {
        position: Vec3A::ZERO,
        axis: -Vec3A::Y,
        intensity: Vec3A::ONE,
        cutoff: 30f32.to_radians(),
        beam_width: 15f32.to_radians(),
        falloff: f,
    };
    let d = Vec3A::new(22.5f32.to_radians().sin(), -22.5f32.to_radians().cos(), 0.0);
    assert!(mid(SpotFalloff::Gltf).falloff(d) < mid(SpotFalloff::Mitsuba).falloff(d));
}

#[test]
fn a_directional_light_gives_its_irradiance_times_the_cosine() {
    let scene = load(&floor_scene(
        "[[lights]]\ntype = \"directional\"\ndirection = [1.0, -1.7320508, 0.0]\ncolour = [1.0, 0.5, 0.25]\nintensity = 3.0",
        2,
    ));
    let m = mean(&film(&scene));
    // L = ρ/π · E cos 30° (the light comes 30° off the vertical).
    let expected = Vec3A::new(1.0, 0.5, 0.25) * (0.5 / PI * 3.0 * 0.75f32.sqrt());
    assert!(
        (m - expected).abs().max_element() < 1e-3 * expected.max_element(),
        "{m} {expected}"
    );
}

/// An emitting sphere of radiance L and radius r whose centre is at
/// distance d and angle α from a floor point's normal lights it with
/// `E = π L (r/d)² cos α`.
#[test]
fn an_emitting_sphere_lights_the_floor_by_its_solid_angle() {
    let scene = load(&floor_scene(
        "[materials.lamp]\ndiffuse = 0.0\nemission = [4.0, 4.0, 4.0]\n\
         [[objects]]\ntype = \"sphere\"\ncenter = [1.5, 1.0, 0.0]\nradius = 0.25\nmaterial = \"lamp\"",
        64,
    ));
    let f = film(&scene);
    // The sphere is out of the camera's view, above every floor point's horizon.
    let (mut sum, mut sum_expected, mut n) = (0.0f64, 0.0f64, 0);
    for y in 0..32 {
        for x in 0..32 {
            let p = floor_point(&scene, x, y);
            let c = Vec3A::new(1.5, 1.0, 0.0);
            let to = c - p;
            let d2 = to.length_squared();
            // A sphere above the horizon: E = π L sin²θ cos α, α the angle of its centre.
            let expected = 0.5 / PI * (PI * 4.0 * (0.0625 / d2) * to.normalize().y);
            sum += f64::from(f.pixels[(y * 32 + x) as usize].x);
            sum_expected += f64::from(expected);
            n += 1;
        }
    }
    assert_eq!(n, 1024);
    assert!(
        (sum / sum_expected - 1.0).abs() < 0.01,
        "{} against {}",
        sum,
        sum_expected
    );
}

/// A ceiling panel over a floor: a `[[lights]]` rectangle, an emitting quad
/// and the same quad as a two-triangle mesh.
fn panel_scene(dir: &Path, integrator: &str, panel: &str) -> LoadedScene {
    let obj = dir.join("panel.obj");
    std::fs::write(
        &obj,
        "v -0.5 1.5 -0.5\nv 0.5 1.5 -0.5\nv 0.5 1.5 0.5\nv -0.5 1.5 0.5\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    let text = format!(
        "[render]\nwidth = 24\nheight = 24\nspp = 64\nintegrator = \"{integrator}\"\nseed = 9\n\
         [camera]\nposition = [0.0, 1.0, 4.0]\nlook_at = [0.0, 0.5, 0.0]\nvfov = 40\n\
         [materials.floor]\ndiffuse = 0.6\n\
         [materials.lamp]\ndiffuse = 0.0\nemission = [3.0, 3.0, 3.0]\n\
         [[objects]]\ntype = \"quad\"\ncenter = [0.0, 0.0, 0.0]\nsize = [4.0, 4.0]\nnormal = [0.0, 1.0, 0.0]\n\
         up = [0.0, 0.0, -1.0]\nmaterial = \"floor\"\n{panel}\n"
    );
    parse_scene(&text, &dir.join("panel.toml")).unwrap_or_else(|e| panic!("{e}"))
}

const RECT: &str = "[[lights]]\ntype = \"area\"\nposition = [0.0, 1.5, 0.0]\nu = [1.0, 0.0, 0.0]\n\
                    v = [0.0, 0.0, 1.0]\ncolour = [3.0, 3.0, 3.0]";
const QUAD: &str = "[[objects]]\ntype = \"quad\"\ncenter = [0.0, 1.5, 0.0]\nsize = [1.0, 1.0]\n\
                    normal = [0.0, -1.0, 0.0]\nup = [0.0, 0.0, -1.0]\nmaterial = \"lamp\"";
// The OBJ's winding faces −y, the floor.
const MESH: &str = "[[objects]]\ntype = \"mesh\"\nfile = \"panel.obj\"\nmaterial = \"lamp\"";

#[test]
fn emitting_quads_and_meshes_light_as_a_rectangle_light_does() {
    let dir = tempfile::tempdir().unwrap();
    for integrator in ["path", "whitted"] {
        let rect = mean(&film(&panel_scene(dir.path(), integrator, RECT)));
        for (what, panel) in [("quad", QUAD), ("mesh", MESH)] {
            let scene = panel_scene(dir.path(), integrator, panel);
            let emitter = Emitter::of_object(&scene.scene, 1).expect("the panel emits");
            assert!((emitter.power() - Vec3A::splat(3.0 * PI)).length() < 1e-3, "{what}");
            let m = mean(&film(&scene));
            assert!(
                (m / rect - Vec3A::ONE).abs().max_element() < 0.02,
                "{integrator} {what}: {m} against the rectangle's {rect}"
            );
        }
    }
}

/// A textured emission: the radiance follows the texture, and its mean
/// lights the floor as a constant of the same mean does.
#[test]
fn a_textured_emission_follows_its_texture() {
    let dir = tempfile::tempdir().unwrap();
    let textured = format!(
        "{QUAD}\n[textures.stripes]\ntype = \"checkerboard\"\ncolour0 = [0.0, 0.0, 0.0]\ncolour1 = [2.0, 2.0, 2.0]\n\
         scale = [4.0, 4.0]"
    )
    .replace("material = \"lamp\"", "material = \"striped\"");
    let with_material = format!(
        "[render]\nwidth = 24\nheight = 24\nspp = 64\nintegrator = \"path\"\nseed = 9\n\
         [camera]\nposition = [0.0, 1.0, 4.0]\nlook_at = [0.0, 0.5, 0.0]\nvfov = 40\n\
         [materials.floor]\ndiffuse = 0.6\n\
         [materials.striped]\ndiffuse = 0.0\nemission = \"stripes\"\nemission_strength = 3.0\n\
         [[objects]]\ntype = \"quad\"\ncenter = [0.0, 0.0, 0.0]\nsize = [4.0, 4.0]\nnormal = [0.0, 1.0, 0.0]\n\
         up = [0.0, 0.0, -1.0]\nmaterial = \"floor\"\n{textured}\n"
    );
    let scene = parse_scene(&with_material, &dir.path().join("striped.toml")).unwrap_or_else(|e| panic!("{e}"));
    let lamp = &scene.scene.materials[scene.scene.objects[1].material as usize];
    assert!(lamp.emits());
    assert_eq!(lamp.emission_at(Vec2::new(0.1, 0.1)), Vec3A::ZERO);
    assert_eq!(lamp.emission_at(Vec2::new(0.15, 0.1)), Vec3A::splat(6.0));
    let striped = mean(&film(&scene));
    let constant = mean(&film(&panel_scene(dir.path(), "path", QUAD)));
    assert!(
        (striped / constant - Vec3A::ONE).abs().max_element() < 0.03,
        "{striped} {constant}"
    );
}

/// Photons leave every kind of light with the light's power in all: a
/// caster around the light takes the light's own distribution, and a
/// directional light's photons cross the scene's disk in parallel.
#[test]
fn photons_carry_the_power_of_every_kind_of_light() {
    let cases = [
        (
            "[[lights]]\ntype = \"spot\"\nposition = [0.0, 1.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\ncutoff_angle = 40\nintensity = 5.0",
            None,
        ),
        (
            "[[lights]]\ntype = \"directional\"\ndirection = [0.0, -1.0, 0.0]\nintensity = 2.0",
            Some(-Vec3A::Y),
        ),
        (
            "[materials.lamp]\ndiffuse = 0.0\nemission = [1.5, 1.5, 1.5]\n\
             [[objects]]\ntype = \"sphere\"\ncenter = [0.0, 1.0, 0.0]\nradius = 0.3\nmaterial = \"lamp\"",
            None,
        ),
    ];
    for (light, parallel) in cases {
        let scene = load(&floor_scene(light, 1));
        let emitter = Emitter::all(&scene.scene)
            .into_iter()
            .find(|e| e.power().x > 0.0)
            .unwrap();
        let accel = accel::build(&scene.scene, AccelKind::KdTree, &AccelOptions::default()).unwrap();
        let everything = Caster {
            center: Vec3A::ZERO,
            radius: 100.0,
        };
        let n = 50_000;
        let tracer = PhotonTracer::with_casters(
            &scene.scene,
            TraceSettings::of(&scene.settings),
            accel.as_ref(),
            n,
            vec![everything],
        );
        let mut total = Vec3A::ZERO;
        for i in 0..n {
            if let Some(p) = tracer.emit(i) {
                if let Some(d) = parallel {
                    assert!((p.ray().dir.normalize() - d).length() < 1e-5);
                }
                total += p.power();
            }
        }
        let expected = emitter.power();
        assert!(
            (total / expected - Vec3A::ONE).abs().max_element() < 0.01,
            "{light}: {total} against {expected}"
        );
    }
}

#[test]
fn light_keys_are_read_and_checked() {
    let base = |light: &str| floor_scene(light, 1);
    let e = load_err(&base(
        "[[lights]]\ntype = \"spot\"\nposition = [0.0, 1.0, 0.0]\nlook_at = [0.0, 0.0, 0.0]\ndirection = [0.0, -1.0, 0.0]",
    ));
    assert!(e.contains("lights.toml:") && e.contains("not both"), "{e}");
    let e = load_err(&base(
        "[[lights]]\ntype = \"spot\"\nposition = [0.0, 1.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\ncutoff_angle = 20\nbeam_width = 25",
    ));
    assert!(e.contains("`beam_width` = 25"), "{e}");
    let e = load_err(&base(
        "[[lights]]\ntype = \"spot\"\nposition = [0.0, 1.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\ncutoff_angle = 120",
    ));
    assert!(e.contains("`cutoff_angle` = 120"), "{e}");
    let e = load_err(&base("[[lights]]\ntype = \"spot\"\nposition = [0.0, 1.0, 0.0]"));
    assert!(e.contains("needs `look_at` or `direction`"), "{e}");
    let e = load_err(&base("[[lights]]\ntype = \"directional\"\nintensity = 1.0"));
    assert!(e.contains("needs `direction`"), "{e}");
    let e = load_err(&base(
        "[[lights]]\ntype = \"point\"\nposition = [0.0, 1.0, 0.0]\ncutoff_angle = 20",
    ));
    assert!(e.contains("`cutoff_angle` does not apply to a point light"), "{e}");
    let e = load_err(&base(
        "[[lights]]\ntype = \"area\"\nposition = [0.0, 1.0, 0.0]\nu = [1.0, 0.0, 0.0]\nv = [0.0, 0.0, 1.0]\ndirection = [0.0, -1.0, 0.0]",
    ));
    assert!(e.contains("`direction` does not apply to an area light"), "{e}");
    let e = load_err(&base("[materials.lamp]\nemission_strength = 2.0"));
    assert!(e.contains("`emission_strength` without an `emission`"), "{e}");
    let e = load_err(&base("[materials.lamp]\nemission = [1.0, -1.0, 1.0]"));
    assert!(e.contains("negative"), "{e}");
    // Defaults: Mitsuba's 20° cutoff and a beam of three quarters of it.
    let s = load(&base(
        "[[lights]]\ntype = \"spot\"\nposition = [0.0, 1.0, 0.0]\ndirection = [0.0, -2.0, 0.0]",
    ));
    let Light::Spot(spot) = s.scene.lights[0] else { panic!() };
    assert!((spot.cutoff.to_degrees() - 20.0).abs() < 1e-4 && (spot.beam_width.to_degrees() - 15.0).abs() < 1e-4);
}

/// A panel whose normal faces away from the floor: one-sided it leaves the
/// floor dark; emitting both sides (`emit_both_sides`, glTF's and Cycles'
/// emission) it lights the floor as the rectangle does, with twice the
/// rectangle's power, and half its photons leave each side.
#[test]
fn a_panel_emitting_both_sides_lights_what_is_behind_it() {
    let dir = tempfile::tempdir().unwrap();
    let up = QUAD.replace("normal = [0.0, -1.0, 0.0]", "normal = [0.0, 1.0, 0.0]");
    let both = format!(
        "[materials.both]\ndiffuse = 0.0\nemission = [3.0, 3.0, 3.0]\nemit_both_sides = true\n{}",
        up.replace("material = \"lamp\"", "material = \"both\"")
    );
    for integrator in ["path", "whitted"] {
        let rect = mean(&film(&panel_scene(dir.path(), integrator, RECT)));
        let one_sided = mean(&film(&panel_scene(dir.path(), integrator, &up)));
        assert!(
            one_sided.max_element() < 0.05 * rect.min_element(),
            "{integrator}: {one_sided}"
        );
        let scene = panel_scene(dir.path(), integrator, &both);
        let emitter = Emitter::of_object(&scene.scene, 1).expect("the panel emits");
        assert!((emitter.power() - Vec3A::splat(6.0 * PI)).length() < 1e-3);
        let m = mean(&film(&scene));
        assert!(
            (m / rect - Vec3A::ONE).abs().max_element() < 0.02,
            "{integrator}: {m} against the rectangle's {rect}"
        );
    }
    // Photons: the panel's power, half of them downward.
    let scene = panel_scene(dir.path(), "path", &both);
    let emitter = Emitter::of_object(&scene.scene, 1).unwrap();
    let accel = accel::build(&scene.scene, AccelKind::KdTree, &AccelOptions::default()).unwrap();
    let everything = Caster {
        center: Vec3A::ZERO,
        radius: 100.0,
    };
    let n = 40_000;
    let tracer = PhotonTracer::with_casters(
        &scene.scene,
        TraceSettings::of(&scene.settings),
        accel.as_ref(),
        n,
        vec![everything],
    );
    let (mut total, mut down) = (Vec3A::ZERO, 0);
    for i in 0..n {
        if let Some(p) = tracer.emit(i) {
            total += p.power();
            down += usize::from(p.ray().dir.y < 0.0);
        }
    }
    assert!(
        (total / emitter.power() - Vec3A::ONE).abs().max_element() < 0.01,
        "{total}"
    );
    assert!((down as f64 / n as f64 - 0.5).abs() < 0.01, "{down} of {n} downward");
}

/// An emitting shape keeps its BSDF: a lone sphere of albedo 0.5 emitting
/// 2 in a uniform environment of radiance 1 shows `2 + 0.5 × 1` at every
/// pixel (a convex Lambert surface under uniform light reflects its albedo
/// times that radiance), and emission alone when its albedo is 0.
#[test]
fn an_emitting_shape_also_reflects_light() {
    let sphere = |albedo: f32| {
        let mut scene = load(&format!(
            "[render]\nwidth = 16\nheight = 16\nspp = 64\nintegrator = \"path\"\nseed = 9\n\
             [camera]\nposition = [0.0, 0.0, 4.0]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 10\n\
             [materials.lamp]\ndiffuse = {albedo}\nemission = 2.0\n\
             [[objects]]\ntype = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\nmaterial = \"lamp\"\n"
        ));
        scene.scene.lights = vec![Light::Environment {
            radiance: Vec3A::ONE,
            map: None,
        }];
        mean(&film(&scene)).x
    };
    let (reflecting, black) = (sphere(0.5), sphere(0.0));
    assert!((black - 2.0).abs() < 1e-3, "emission alone: {black}");
    assert!((reflecting - 2.5).abs() < 0.02, "emission and reflection: {reflecting}");
}
