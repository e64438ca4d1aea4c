//! Environment images: their orientation, importance sampling (the density
//! integrates to 1 and matches what is sampled), agreement with a constant
//! environment, and their scene keys.

mod common;

use caustic::accel::{self, AccelKind, AccelOptions};
use caustic::math::{Mat3A, Vec2, Vec3A};
use caustic::scene::light::EnvironmentMap;
use caustic::scene::{parse_scene, Light, LoadedScene};
use caustic::texture::image::Texels;
use caustic::texture::Image;
use std::f32::consts::PI;
use std::sync::Arc;

/// A `w × h` linear image whose texel `(x, y)` is `f(x, y)` in every channel.
fn image(w: u32, h: u32, f: impl Fn(u32, u32) -> f32) -> Arc<Image> {
    let texels = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let v = f(x, y);
            [v, v, v, 1.0]
        })
        .collect();
    Arc::new(Image::new("test", w, h, Texels::RgbaF32(texels)))
}

/// Directions over the sphere, stratified in (cos θ, φ): `n × n` of them.
fn sphere_directions(n: usize) -> impl Iterator<Item = Vec3A> {
    (0..n * n).map(move |i| {
        let (a, b) = ((i % n) as f32 + 0.5, (i / n) as f32 + 0.5);
        let z = 1.0 - 2.0 * a / n as f32;
        let phi = 2.0 * PI * b / n as f32;
        let r = (1.0 - z * z).sqrt();
        Vec3A::new(r * phi.cos(), r * phi.sin(), z)
    })
}

#[test]
fn the_map_is_oriented_as_mitsubas_envmap() {
    // Bright top rows (the sky), dark bottom; one bright column at u ≈ 0.
    let sky = image(64, 32, |x, y| {
        if y < 8 {
            4.0
        } else if x == 0 {
            2.0
        } else {
            0.1
        }
    });
    let map = EnvironmentMap::new(sky.clone(), Mat3A::IDENTITY);
    assert!(map.eval(Vec3A::Y).x > 3.9);
    // Near the bottom pole, away from the bright column (at the pole itself
    // every u meets).
    assert!((map.eval(Vec3A::new(0.2, -0.97, 0.1)).x - 0.1).abs() < 1e-3);
    // u = atan2(x, −z) / 2π: −z is u = 0, the bright column's edge.
    let at_minus_z = map.eval(Vec3A::new(0.0, -0.3, -1.0));
    let at_plus_z = map.eval(Vec3A::new(0.0, -0.3, 1.0));
    assert!(
        at_minus_z.x > 0.5 && (at_plus_z.x - 0.1).abs() < 1e-3,
        "{at_minus_z} {at_plus_z}"
    );
    // Turned upside down about x, the sky comes from below.
    let turned = EnvironmentMap::new(sky, Mat3A::from_rotation_x(PI));
    assert!(turned.eval(-Vec3A::Y).x > 3.9 && turned.eval(Vec3A::new(0.2, 0.97, 0.1)).x < 0.2);
}

#[test]
fn the_density_integrates_to_one_and_matches_the_samples() {
    let img = image(40, 20, |x, y| {
        0.05 + ((x * 13 + y * 7) % 11) as f32 + if y == 3 { 30.0 } else { 0.0 }
    });
    let map = EnvironmentMap::new(img, Mat3A::from_rotation_y(0.7));
    // ∫ pdf dω over the sphere, by stratified quadrature.
    let n = 400;
    let integral: f64 =
        sphere_directions(n).map(|d| f64::from(map.pdf(d))).sum::<f64>() * 4.0 * std::f64::consts::PI / (n * n) as f64;
    assert!((integral - 1.0).abs() < 0.01, "∫ pdf = {integral}");
    // Each sample's density is the density at its direction, and the
    // estimate ∫ L dω ≈ mean(L / pdf) agrees with the quadrature.
    let mut rng = caustic::math::Rng::new(3, caustic::math::rng::Domain::Analysis, 0, 0);
    let (mut sum, count, mut off) = (0.0f64, 100_000, 0);
    for _ in 0..count {
        // Only a sample exactly at a pole gives none (it then adds nothing).
        let Some((dir, pdf)) = map.sample(Vec2::new(rng.f32(), rng.f32())) else {
            off += 1;
            continue;
        };
        assert!((dir.length() - 1.0).abs() < 1e-4);
        // Equal but for directions on a cell's edge, which rounding may
        // give to the neighbouring cell.
        if (pdf - map.pdf(dir)).abs() > 1e-3 * pdf {
            off += 1;
        }
        sum += f64::from(map.eval(dir).x / pdf);
    }
    assert!(off < count / 1000, "{off} samples lost or whose density differs");
    let sampled = sum / f64::from(count);
    let quadrature: f64 =
        sphere_directions(n).map(|d| f64::from(map.eval(d).x)).sum::<f64>() * 4.0 * std::f64::consts::PI
            / (n * n) as f64;
    assert!(
        (sampled / quadrature - 1.0).abs() < 0.01,
        "{sampled} against {quadrature}"
    );
    assert!((f64::from(map.mean().x) * 4.0 * std::f64::consts::PI / quadrature - 1.0).abs() < 0.02);
}

fn furnace(environment: Light) -> f32 {
    let mut scene: LoadedScene = parse_scene(
        "[render]\nwidth = 24\nheight = 24\nspp = 64\nintegrator = \"path\"\nseed = 5\n\
         [camera]\nposition = [0.0, 0.0, 4.0]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 20\n\
         [materials.white]\ndiffuse = 0.8\n\
         [[objects]]\ntype = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\nmaterial = \"white\"\n",
        std::path::Path::new("furnace.toml"),
    )
    .unwrap();
    scene.scene.lights = vec![environment];
    let film = common::render::film(&scene, AccelKind::KdTree);
    film.pixels.iter().map(|c| c.x).sum::<f32>() / film.pixels.len() as f32
}

/// A uniform image lights a sphere as the constant environment of the same
/// radiance does (a furnace: the image's sampling is exact in expectation).
#[test]
fn a_uniform_map_lights_like_a_constant_environment() {
    let constant = furnace(Light::Environment {
        radiance: Vec3A::splat(0.5),
        map: None,
    });
    let map = EnvironmentMap::new(image(16, 8, |_, _| 1.0), Mat3A::IDENTITY);
    let mapped = furnace(Light::Environment {
        radiance: Vec3A::splat(0.5),
        map: Some(Arc::new(map)),
    });
    assert!((mapped / constant - 1.0).abs() < 0.01, "{mapped} against {constant}");
    // A convex sphere never sees itself: its radiance is albedo × L = 0.4.
    assert!((constant - 0.4).abs() < 0.01, "{constant}");
}

#[test]
fn environment_keys_are_read_and_checked() {
    let dir = tempfile::tempdir().unwrap();
    image::DynamicImage::ImageRgb32F(image::Rgb32FImage::from_pixel(8, 4, image::Rgb([1.0, 2.0, 3.0])))
        .save(dir.path().join("sky.hdr"))
        .unwrap();
    let scene = |light: &str| {
        format!(
            "[camera]\nposition = [0.0, 0.0, 4.0]\nlook_at = [0.0, 0.0, 0.0]\n\
             [[lights]]\ntype = \"environment\"\n{light}\n"
        )
    };
    let load = |text: &str| parse_scene(text, &dir.path().join("s.toml"));
    let s = load(&scene("file = \"sky.hdr\"\nintensity = 2.0\nrotate = [0.0, 90.0, 0.0]")).unwrap();
    let Light::Environment {
        radiance,
        map: Some(map),
    } = &s.scene.lights[0]
    else {
        panic!("{:?}", s.scene.lights[0])
    };
    assert_eq!(*radiance, Vec3A::splat(2.0));
    assert!((map.to_world * Vec3A::X - -Vec3A::Z).length() < 1e-5);
    assert!((map.eval(Vec3A::Y) - Vec3A::new(1.0, 2.0, 3.0)).length() < 1e-2);
    let e = load(&scene("rotate = [0.0, 90.0, 0.0]")).unwrap_err().to_string();
    assert!(
        e.contains("s.toml:6:10") && e.contains("`rotate` does not apply"),
        "{e}"
    );
    let e = load(&scene("file = \"none.hdr\"")).unwrap_err().to_string();
    assert!(e.contains("s.toml:6:8") && e.contains("none.hdr"), "{e}");
    let e = load(&scene("file = \"sky.hdr\"\nu = [1.0, 0.0, 0.0]"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("`u` does not apply"), "{e}");
}

/// Photons from an environment carry its light into the scene: the power of
/// those whose first ray crosses a sphere of radius `a` is what the sphere
/// receives, `π a² ∫ L dω` (a convex body's cross-section is `π a²` from
/// every direction), for a constant sky and for an image.
#[test]
fn environment_photons_carry_the_light_a_sphere_receives() {
    use caustic::integrator::photon::{PhotonRules, PhotonTracer, TraceSettings};
    let a = 0.7f32;
    let mut scene: LoadedScene = parse_scene(
        "[render]\nintegrator = \"path\"\nseed = 9\n\
         [camera]\nposition = [0.0, 0.0, 4.0]\nlook_at = [0.0, 0.0, 0.0]\n\
         [materials.glass]\ndielectric = { ior = 1.5 }\n[materials.floor]\ndiffuse = 0.5\n\
         [[objects]]\ntype = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 0.7\nmaterial = \"glass\"\n\
         [[objects]]\ntype = \"quad\"\ncenter = [0.0, -2.0, 0.0]\nsize = [6.0, 6.0]\nnormal = [0.0, 1.0, 0.0]\nmaterial = \"floor\"\n",
        std::path::Path::new("sky.toml"),
    )
    .unwrap();
    // A bright band above the horizon on a dim sky.
    let band = Arc::new(EnvironmentMap::new(
        image(32, 16, |_, y| if (4..6).contains(&y) { 20.0 } else { 0.2 }),
        Mat3A::IDENTITY,
    ));
    let n = 400;
    let band_integral =
        (sphere_directions(n).map(|d| f64::from(band.eval(d).x)).sum::<f64>() * 4.0 * std::f64::consts::PI
            / (n * n) as f64) as f32;
    for (light, integral) in [
        (
            Light::Environment {
                radiance: Vec3A::splat(0.5),
                map: None,
            },
            0.5 * 4.0 * PI,
        ),
        (
            Light::Environment {
                radiance: Vec3A::ONE,
                map: Some(band.clone()),
            },
            band_integral,
        ),
    ] {
        scene.scene.lights = vec![light];
        let accel = accel::build(&scene.scene, AccelKind::KdTree, &AccelOptions::default()).unwrap();
        let count = 400_000u64;
        let tracer = PhotonTracer::with_rules(
            &scene.scene,
            TraceSettings::of(&scene.settings),
            accel.as_ref(),
            count,
            PhotonRules::Physical,
        );
        assert!(tracer.has_emitters());
        let mut received = 0.0f64;
        for i in 0..count {
            let Some(path) = tracer.emit(i) else { continue };
            let (o, d) = (path.ray().origin, path.ray().dir);
            // The ray's closest approach to the centre.
            let t = -o.dot(d);
            if t > 0.0 && (o + d * t).length() < a {
                received += f64::from(path.power().x);
            }
        }
        let expected = f64::from(PI * a * a * integral);
        assert!(
            (received / expected - 1.0).abs() < 0.02,
            "{received} against {expected}"
        );
    }
}
