//! Textures through the whole pipeline: the `[textures]` table and texture
//! parameters of the scene format, texture coordinates on every shape,
//! textured colours in a render, normal maps, alpha cutouts on every
//! accelerator, and the errors bad textures give.

mod common;

use caustic::accel::{self, Accel, AccelKind, AccelOptions};
use caustic::integrator::{render, RenderPlan, RenderSetup};
use caustic::math::{Ray, Vec2, Vec3A};
use caustic::scene::LoadedScene;
use caustic::scene::{parse_scene, SceneError};
use caustic::texture::{Channel, ColourSpace, Texture};
use std::path::{Path, PathBuf};

/// A folder with `red-blue.png` (a 2×1 image: red left, blue right, opaque)
/// and `holes.png` (2×2: alpha 0 in the left column, 255 in the right).
fn image_dir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let img = image::RgbaImage::from_fn(2, 1, |x, _| {
        if x == 0 {
            image::Rgba([255, 0, 0, 255])
        } else {
            image::Rgba([0, 0, 255, 255])
        }
    });
    img.save(dir.path().join("red-blue.png")).unwrap();
    let holes = image::RgbaImage::from_fn(2, 2, |x, _| image::Rgba([200, 200, 200, if x == 0 { 0 } else { 255 }]));
    holes.save(dir.path().join("holes.png")).unwrap();
    std::fs::write(
        dir.path().join("card.obj"),
        "v -0.5 -0.5 0\nv 0.5 -0.5 0\nv 0.5 0.5 0\nv -0.5 0.5 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
         f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("bare.obj"),
        "v -0.5 -0.5 0\nv 0.5 -0.5 0\nv 0.5 0.5 0\nf 1 2 3\n",
    )
    .unwrap();
    dir
}

fn load(dir: &Path, text: &str) -> Result<LoadedScene, SceneError> {
    parse_scene(text, &dir.join("scene.toml"))
}

const CAMERA: &str = "[camera]\nposition = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 40\n";

fn hit(scene: &LoadedScene, accel: &dyn Accel, ray: Ray) -> caustic::scene::SurfaceInteraction {
    let h = accel.intersect(&ray, f32::INFINITY).expect("the ray hits");
    scene.scene.surface_interaction(&ray, &h)
}

#[test]
fn textures_table_and_inline_textures_are_read() {
    let dir = image_dir();
    let text = format!(
        "{CAMERA}
[textures.rb]
type = \"image\"
file = \"red-blue.png\"
wrap = [\"clamp\", \"mirror\"]
filter = \"nearest\"
scale = [2.0, 1.0]
factor = 0.5

[materials.a]
diffuse = \"rb\"
specular = {{ type = \"checkerboard\", colour0 = 0.1, colour1 = [0.2, 0.3, 0.4] }}
shininess = {{ type = \"image\", file = \"red-blue.png\", channel = \"b\" }}

[materials.b]
conductor = {{ metal = \"gold\", roughness = \"rb\" }}
alpha = {{ type = \"image\", file = \"holes.png\" }}
alpha_cutoff = 0.25

[[objects]]
type = \"sphere\"
center = [0.0, 0.0, 0.0]
radius = 1.0
material = \"a\"
"
    );
    let scene = load(dir.path(), &text).unwrap();
    let a = &scene.scene.materials[0];
    let Some(Texture::Image(rb)) = &a.textures.as_ref().unwrap().diffuse else {
        panic!("{:?}", a.textures.as_ref().unwrap().diffuse)
    };
    assert_eq!(rb.wrap[0].name(), "clamp");
    assert_eq!(rb.wrap[1].name(), "mirror");
    assert_eq!(rb.filter.name(), "nearest");
    assert_eq!(rb.factor, Vec3A::splat(0.5));
    // A colour parameter decodes sRGB; the same file as a scalar is linear.
    assert!(matches!(
        &rb.image.texels,
        caustic::texture::image::Texels::Rgba8 {
            space: ColourSpace::Srgb,
            ..
        }
    ));
    let Some(Texture::Image(sh)) = &a.textures.as_ref().unwrap().shininess else {
        panic!()
    };
    assert_eq!(sh.channel, Channel::B);
    assert!(matches!(
        &sh.image.texels,
        caustic::texture::image::Texels::Rgba8 {
            space: ColourSpace::Linear,
            ..
        }
    ));
    // The ambient reflectance follows the diffuse texture.
    assert_eq!(
        a.textures.as_ref().unwrap().ambient,
        a.textures.as_ref().unwrap().diffuse
    );
    // Constants stand for the texture's upper bound.
    assert_eq!(a.diffuse, Vec3A::new(0.5, 0.0, 0.5));
    let b = &scene.scene.materials[1];
    let alpha = b.textures.as_ref().unwrap().alpha.as_ref().unwrap();
    assert_eq!(alpha.cutoff, 0.25);
    let Texture::Image(mask) = &alpha.texture else { panic!() };
    assert_eq!(mask.channel, Channel::A);
    assert!(b.textures.as_ref().unwrap().conductor_roughness.is_some());
    // The looked-up values: the UV transform doubles u, clamping keeps the
    // right texel beyond u = 0.5.
    let at = |u: f32| a.at(Vec2::new(u, 0.5)).diffuse;
    assert!((at(0.1) - Vec3A::new(0.5, 0.0, 0.0)).length() < 1e-6, "{}", at(0.1));
    assert!((at(0.3) - Vec3A::new(0.0, 0.0, 0.5)).length() < 1e-6, "{}", at(0.3));
    assert!((at(0.9) - Vec3A::new(0.0, 0.0, 0.5)).length() < 1e-6, "{}", at(0.9));
}

/// Texture coordinates are computed where the material reads them (here a
/// checkerboard), on every shape.
#[test]
fn texture_coordinates_on_every_shape() {
    let dir = image_dir();
    let text = format!(
        "{CAMERA}
[materials.m]
diffuse = {{ type = \"checkerboard\" }}

[[objects]]
type = \"sphere\"
center = [0.0, 0.0, 0.0]
radius = 1.0
material = \"m\"

[[objects]]
type = \"quad\"
corner = [10.0, 0.0, 0.0]
u = [2.0, 0.0, 0.0]
v = [0.0, 4.0, 0.0]
material = \"m\"

[[objects]]
type = \"mesh\"
file = \"card.obj\"
translate = [20.0, 0.0, 0.0]
material = \"m\"

[[objects]]
type = \"water\"
center = [30.0, 0.0, 0.0]
size = [2.0, 4.0]
resolution = [4, 4]
material = \"m\"
"
    );
    let scene = load(dir.path(), &text).unwrap();
    let accel = accel::build(&scene.scene, AccelKind::Brute, &AccelOptions::default()).unwrap();
    let close = |a: Vec2, b: Vec2| (a - b).length() < 1e-4;
    // Sphere, Mitsuba's convention about the world axes: +x is (0, ½), +y is (¼, ½), +z is v = 0.
    let si = hit(&scene, accel.as_ref(), Ray::new(Vec3A::new(5.0, 0.0, 0.0), -Vec3A::X));
    assert!(close(si.uv, Vec2::new(0.0, 0.5)), "{}", si.uv);
    let si = hit(&scene, accel.as_ref(), Ray::new(Vec3A::new(0.0, 5.0, 0.0), -Vec3A::Y));
    assert!(close(si.uv, Vec2::new(0.25, 0.5)), "{}", si.uv);
    assert!(si.dpdu.dot(Vec3A::X) < 0.0 && si.dpdv.length() > 0.0);
    let si = hit(&scene, accel.as_ref(), Ray::new(Vec3A::new(0.0, 0.0, 5.0), -Vec3A::Z));
    assert!(si.uv.y.abs() < 1e-3, "{}", si.uv);
    // Quad: (a, b) along its edges u and v.
    let si = hit(&scene, accel.as_ref(), Ray::new(Vec3A::new(10.5, 3.0, 5.0), -Vec3A::Z));
    assert!(close(si.uv, Vec2::new(0.25, 0.75)), "{}", si.uv);
    assert_eq!(
        (si.dpdu, si.dpdv),
        (Vec3A::new(2.0, 0.0, 0.0), Vec3A::new(0.0, 4.0, 0.0))
    );
    // OBJ mesh: its v runs up the image, caustic's down, so the file's
    // (0.25, 0.25) near the bottom-left corner reads (0.25, 0.75).
    let si = hit(
        &scene,
        accel.as_ref(),
        Ray::new(Vec3A::new(19.75, -0.25, 5.0), -Vec3A::Z),
    );
    assert!(close(si.uv, Vec2::new(0.25, 0.75)), "{}", si.uv);
    assert!((si.dpdu - Vec3A::X).length() < 1e-5 && (si.dpdv + Vec3A::Y).length() < 1e-5);
    // Water: u along +x and v along +z over its extent.
    let si = hit(&scene, accel.as_ref(), Ray::new(Vec3A::new(29.5, 5.0, 1.0), -Vec3A::Y));
    assert!(close(si.uv, Vec2::new(0.25, 0.75)), "{}", si.uv);
}

/// A quad textured red on its left half and blue on its right, seen head on:
/// the render shows the same halves.
#[test]
fn a_textured_colour_reaches_the_image() {
    let dir = image_dir();
    let text = format!(
        "{CAMERA}
[render]
width = 32
height = 32
spp = 16
integrator = \"path\"

[materials.m]
diffuse = {{ type = \"image\", file = \"red-blue.png\", filter = \"nearest\" }}

[[lights]]
type = \"environment\"
colour = [1.0, 1.0, 1.0]

[[objects]]
type = \"quad\"
corner = [-1.0, -1.0, 0.0]
u = [2.0, 0.0, 0.0]
v = [0.0, 2.0, 0.0]
material = \"m\"
"
    );
    let scene = load(dir.path(), &text).unwrap();
    let accel = accel::build(&scene.scene, AccelKind::KdTree, &AccelOptions::default()).unwrap();
    let out = render(
        &scene.scene,
        accel.as_ref(),
        &RenderPlan::new(&scene.scene, &scene.settings),
        RenderSetup::default(),
    );
    let left = out.film.get(10, 16);
    let right = out.film.get(22, 16);
    // A white sky over a Lambertian quad: the radiance is the albedo (up to noise).
    assert!(left.x > 0.5 && left.y == 0.0 && left.z == 0.0, "left {left}");
    assert!(right.z > 0.5 && right.x == 0.0 && right.y == 0.0, "right {right}");
}

#[test]
fn a_normal_map_tilts_the_shading_normal() {
    let dir = image_dir();
    // A constant map (both squares alike) tilting the normal 45° toward +u.
    let (s, c) = (std::f32::consts::FRAC_1_SQRT_2, std::f32::consts::FRAC_1_SQRT_2);
    let rgb = [0.5 + 0.5 * s, 0.5, 0.5 + 0.5 * c];
    let text = format!(
        "{CAMERA}
[materials.m]
normal_map = {{ type = \"checkerboard\", colour0 = {rgb:?}, colour1 = {rgb:?} }}

[materials.n]
normal_map = {{ type = \"checkerboard\", colour0 = {rgb:?}, colour1 = {rgb:?} }}
normal_scale = 0.0

[[objects]]
type = \"quad\"
corner = [1.0, -1.0, 0.0]
u = [0.0, 2.0, 0.0]
v = [-2.0, 0.0, 0.0]
material = \"m\"

[[objects]]
type = \"mesh\"
file = \"card.obj\"
translate = [10.0, 0.0, 0.0]
material = \"m\"

[[objects]]
type = \"quad\"
corner = [19.0, -1.0, 0.0]
u = [2.0, 0.0, 0.0]
v = [0.0, 2.0, 0.0]
material = \"n\"
"
    );
    let scene = load(dir.path(), &text).unwrap();
    let accel = accel::build(&scene.scene, AccelKind::Brute, &AccelOptions::default()).unwrap();
    // The quad faces +z with u along +y: the normal leans toward +y.
    let si = hit(&scene, accel.as_ref(), Ray::new(Vec3A::new(0.0, 0.0, 5.0), -Vec3A::Z));
    assert_eq!(si.ng, Vec3A::Z);
    assert!((si.ns - Vec3A::new(0.0, s, c)).length() < 1e-2, "{}", si.ns);
    // The card's u runs along +x.
    let si = hit(&scene, accel.as_ref(), Ray::new(Vec3A::new(10.1, 0.1, 5.0), -Vec3A::Z));
    assert!((si.ns - Vec3A::new(s, 0.0, c)).length() < 1e-2, "{}", si.ns);
    // A scale of 0 flattens the map's tilt away.
    let si = hit(&scene, accel.as_ref(), Ray::new(Vec3A::new(20.0, 0.0, 5.0), -Vec3A::Z));
    assert!((si.ns - Vec3A::Z).length() < 1e-5, "{}", si.ns);
}

/// Camera, shadow and photon rays (closest hit, any hit, packets) pass
/// through the holes of a mask, on every accelerator alike.
#[test]
fn alpha_cutouts_on_every_accelerator() {
    let dir = image_dir();
    let text = format!(
        "{CAMERA}
[materials.holes]
diffuse = 0.5
alpha = {{ type = \"image\", file = \"holes.png\", filter = \"nearest\" }}

[materials.back]
diffuse = 0.5

# The left half of each masked shape is a hole.
[[objects]]
type = \"quad\"
corner = [-1.0, -1.0, 1.0]
u = [2.0, 0.0, 0.0]
v = [0.0, 2.0, 0.0]
material = \"holes\"

[[objects]]
type = \"mesh\"
file = \"card.obj\"
scale = 2.0
translate = [0.0, 0.0, 0.5]
material = \"holes\"

[[objects]]
type = \"sphere\"
center = [0.0, 0.0, -2.0]
radius = 0.5
material = \"holes\"

[[objects]]
type = \"quad\"
corner = [-5.0, -5.0, -5.0]
u = [10.0, 0.0, 0.0]
v = [0.0, 10.0, 0.0]
material = \"back\"
"
    );
    let scene = load(dir.path(), &text).unwrap();
    let mut kinds = vec![AccelKind::Brute, AccelKind::KdTree];
    if cfg!(feature = "embree") {
        kinds.push(AccelKind::Embree);
    }
    let accels: Vec<Box<dyn Accel>> = kinds
        .iter()
        .map(|&k| accel::build(&scene.scene, k, &AccelOptions::default()).unwrap())
        .collect();
    let down = -Vec3A::Z;
    for a in &accels {
        // Through the holes of both cards, past the sphere, to the back wall.
        let left = Ray::new(Vec3A::new(-0.6, 0.0, 5.0), down);
        let h = a.intersect(&left, f32::INFINITY).unwrap();
        assert_eq!(h.instance, 3, "{}: {h:?}", a.stats().name);
        // The right halves are solid: the front quad.
        let right = Ray::new(Vec3A::new(0.5, 0.2, 5.0), down);
        assert_eq!(a.intersect(&right, f32::INFINITY).unwrap().instance, 0);
        // The sphere's top (u = ¼) is a hole: the ray meets its far side (u = ¾).
        let top = Ray::new(Vec3A::new(0.0, 5.0, -2.0), -Vec3A::Y);
        let h = a.intersect(&top, f32::INFINITY).unwrap();
        assert_eq!(h.instance, 2, "{}", a.stats().name);
        assert!((h.t - 5.5).abs() < 1e-4, "{}: {h:?}", a.stats().name);
        assert!(a.occluded(&top, 5.6) && !a.occluded(&top, 5.4));
        // Shadow rays: blocked on the right, free on the left up to the wall.
        assert!(a.occluded(&right, 10.0));
        assert!(!a.occluded(&left, 9.9));
        // Packets agree with single rays.
        let rays: Vec<Ray> = (0..40)
            .map(|i| Ray::new(Vec3A::new(-0.95 + i as f32 * 0.0475, 0.3, 5.0), down))
            .collect();
        let mut hits = vec![None; rays.len()];
        a.intersect_many(&rays, f32::INFINITY, &mut hits);
        for (r, h) in rays.iter().zip(&hits) {
            assert_eq!(h.map(|h| h.instance), a.intersect(r, f32::INFINITY).map(|h| h.instance));
        }
    }
    // Every accelerator gives the oracle's answer on a fan of rays.
    for i in 0..2000 {
        let x = -1.2 + 2.4 * (i % 50) as f32 / 49.0;
        let y = -1.2 + 2.4 * (i / 50) as f32 / 39.0;
        let ray = Ray::new(Vec3A::new(0.0, 0.0, 5.0), Vec3A::new(x, y, -3.0));
        let want = accels[0].intersect(&ray, f32::INFINITY).map(|h| (h.instance, h.prim));
        for a in &accels[1..] {
            let got = a.intersect(&ray, f32::INFINITY).map(|h| (h.instance, h.prim));
            assert_eq!(got, want, "{} on ray {i}", a.stats().name);
            assert_eq!(
                a.occluded(&ray, 7.0),
                accels[0].occluded(&ray, 7.0),
                "{} on ray {i}",
                a.stats().name
            );
        }
    }
}

fn error(dir: &Path, text: &str) -> String {
    load(dir, text).unwrap_err().to_string()
}

#[test]
fn bad_textures_are_refused_with_their_place() {
    let dir = image_dir();
    let scene = |material: &str| format!("{CAMERA}\n[materials.m]\n{material}\n");
    let e = error(
        dir.path(),
        &scene("diffuse = { type = \"image\", file = \"missing.png\" }"),
    );
    assert!(
        e.contains("scene.toml:7:") && e.contains("missing.png") && e.contains("cannot open"),
        "{e}"
    );
    let e = error(dir.path(), &scene("diffuse = \"nothing\""));
    assert!(e.contains("scene.toml:7:11") && e.contains("`nothing`"), "{e}");
    let e = error(dir.path(), &scene("shininess = [1.0, 2.0, 3.0]"));
    assert!(e.contains("scene.toml:7:") && e.contains("not a colour"), "{e}");
    let e = error(
        dir.path(),
        &scene("diffuse = { type = \"image\", file = \"red-blue.png\", wrap = \"loop\" }"),
    );
    assert!(e.contains("unknown wrap mode `loop`"), "{e}");
    let e = error(
        dir.path(),
        &scene("diffuse = { type = \"checkerboard\", file = \"red-blue.png\" }"),
    );
    assert!(e.contains("`file` does not apply to a checkerboard"), "{e}");
    let e = error(dir.path(), &scene("diffuse = { type = \"image\" }"));
    assert!(e.contains("an image texture needs `file`"), "{e}");
    let e = error(dir.path(), &scene("diffuse = { type = \"video\" }"));
    assert!(e.contains("scene.toml:7:"), "{e}");
    let e = error(dir.path(), &scene("alpha_cutoff = 0.5"));
    assert!(e.contains("without an `alpha`"), "{e}");
    let e = error(dir.path(), &scene("normal_map = 0.5"));
    assert!(e.contains("must be a texture"), "{e}");
    // Not an image, and a header announcing 100000 × 100000 texels.
    std::fs::write(dir.path().join("text.png"), "hello").unwrap();
    let e = error(
        dir.path(),
        &scene("diffuse = { type = \"image\", file = \"text.png\" }"),
    );
    assert!(e.contains("text.png") && e.contains("scene.toml:7:"), "{e}");
    std::fs::write(dir.path().join("bomb.png"), common::images::huge_png_header()).unwrap();
    let e = error(
        dir.path(),
        &scene("diffuse = { type = \"image\", file = \"bomb.png\" }"),
    );
    assert!(e.contains("refused"), "{e}");
    // A normal map on a mesh without texture coordinates.
    let text = format!(
        "{CAMERA}\n[materials.m]\nnormal_map = {{ type = \"image\", file = \"red-blue.png\" }}\n\
         [[objects]]\ntype = \"mesh\"\nfile = \"bare.obj\"\nmaterial = \"m\"\n"
    );
    let e = error(dir.path(), &text);
    assert!(
        e.contains("scene.toml:11:12") && e.contains("no texture coordinates"),
        "{e}"
    );
}

/// The command line exits with code 2 on a missing texture, and writes nothing.
#[test]
fn the_cli_refuses_a_missing_texture_with_code_2() {
    let dir = image_dir();
    let scene: PathBuf = dir.path().join("s.toml");
    std::fs::write(
        &scene,
        format!(
            "{CAMERA}\n[materials.m]\ndiffuse = {{ type = \"image\", file = \"gone.png\" }}\n\
             [[objects]]\ntype = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\nmaterial = \"m\"\n"
        ),
    )
    .unwrap();
    let out_png = dir.path().join("out.png");
    let out = common::cli::caustic(&["render", scene.to_str().unwrap(), "-o", out_png.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = common::cli::stderr(&out);
    assert!(stderr.contains("s.toml:7:") && stderr.contains("gone.png"), "{stderr}");
    assert!(!out_png.exists());
}
