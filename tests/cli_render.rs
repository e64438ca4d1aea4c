//! End-to-end tests of the `caustic` binary: render small scenes, read the
//! PNG back and check what a person would look at (colours, shadows,
//! reflections), plus exit codes and messages for bad input.

mod common;

use caustic::math::Vec3A;
use caustic::scene::{load_scene, Camera};
use common::cli::{caustic, stderr, stdout};
use std::path::{Path, PathBuf};
use std::process::Output;

/// Pixel (x, y) where the camera sees world point `p` (inverse of `Camera::ray`).
fn project(cam: &Camera, p: Vec3A, width: u32, height: u32) -> (u32, u32) {
    let d = p - cam.position;
    let z = d.dot(cam.forward);
    let tan_half = (cam.fov_deg.to_radians() * 0.5).tan();
    let aspect = width as f32 / height as f32;
    let sx = d.dot(cam.right) / z / (tan_half * aspect);
    let sy = d.dot(cam.up) / z / tan_half;
    let x = (sx + 1.0) * 0.5 * width as f32;
    let y = (1.0 - sy) * 0.5 * height as f32;
    (x as u32, y as u32)
}

/// Mean RGB (0..255) of the 3×3 block around (x, y).
fn mean_rgb(img: &image::RgbImage, x: u32, y: u32) -> [f32; 3] {
    let mut sum = [0.0f32; 3];
    let mut n = 0.0;
    for yy in y.saturating_sub(1)..=(y + 1).min(img.height() - 1) {
        for xx in x.saturating_sub(1)..=(x + 1).min(img.width() - 1) {
            let p = img.get_pixel(xx, yy);
            for c in 0..3 {
                sum[c] += p[c] as f32;
            }
            n += 1.0;
        }
    }
    sum.map(|s| s / n)
}

fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

fn render(scene: &Path, out: &Path, extra: &[&str]) -> (image::RgbImage, Output) {
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--quiet",
    ];
    args.extend_from_slice(extra);
    let o = caustic(&args);
    assert!(o.status.success(), "render failed: {}", stderr(&o));
    let img = image::open(out).expect("the PNG reads back").to_rgb8();
    (img, o)
}

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

#[test]
fn cornell_walls_are_red_and_green_with_every_accelerator() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = repo("scenes/cornell.toml");
    let cam = load_scene(&scene_path).unwrap().scene.camera;
    let (w, h) = (192, 108);
    let mut kinds = vec!["kdtree", "brute"];
    if cfg!(feature = "embree") {
        kinds.push("embree");
    }
    for accel in kinds {
        let out = dir.path().join(format!("cornell-{accel}.png"));
        let (img, o) = render(
            &scene_path,
            &out,
            &[
                "--width",
                "192",
                "--height",
                "108",
                "--spp",
                "2",
                "--photons",
                "20000",
                "--accel",
                accel,
            ],
        );
        assert_eq!((img.width(), img.height()), (w, h));
        let (rx, ry) = project(&cam, Vec3A::new(-2.5, 3.0, 0.5), w, h);
        let red = mean_rgb(&img, rx, ry);
        assert!(
            red[0] > 2.0 * red[1] && red[0] > 2.0 * red[2] && red[0] > 40.0,
            "{accel}: left wall {red:?}"
        );
        let (gx, gy) = project(&cam, Vec3A::new(2.5, 3.0, 0.5), w, h);
        let green = mean_rgb(&img, gx, gy);
        assert!(
            green[1] > 1.5 * green[0] && green[1] > 1.5 * green[2] && green[1] > 30.0,
            "{accel}: right wall {green:?}"
        );
        // The summary reports rays and throughput.
        let s = stdout(&o);
        assert!(s.contains("Mrays/s") && s.contains("written:"), "{s}");
    }
}

#[test]
fn shadowed_floor_is_darker_than_lit_floor() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = repo("scenes/test/shadow.toml");
    let scene = load_scene(&scene_path).unwrap();
    let (w, h) = (scene.settings.width, scene.settings.height);
    let (img, _) = render(&scene_path, &dir.path().join("shadow.png"), &["--accel", "kdtree"]);
    // The ball (centre (0,1,0), radius 0.6) under a light straight above.
    let (sx, sy) = project(&scene.scene.camera, Vec3A::new(0.0, 0.0, 0.0), w, h);
    let (lx, ly) = project(&scene.scene.camera, Vec3A::new(2.2, 0.0, 1.5), w, h);
    let (shadow, lit) = (luminance(mean_rgb(&img, sx, sy)), luminance(mean_rgb(&img, lx, ly)));
    assert!(shadow < 0.5 * lit, "shadow {shadow} vs lit {lit}");
}

/// A mirror facing the camera, a red ball behind the camera: the mirror's
/// centre shows the red ball; the same quad made diffuse does not.
#[test]
fn mirror_shows_the_reflected_object() {
    let dir = tempfile::tempdir().unwrap();
    let scene = |mirror: bool| {
        format!(
            r#"
[render]
width = 64
height = 64
ambient = [0.05, 0.05, 0.05]
tone_map = "clamp"
[camera]
position = [0.0, 0.0, 0.0]
look_at = [0.0, 0.0, -1.0]
vfov = 30
[materials.surface]
diffuse = [0.5, 0.5, 0.5]
{}
[materials.red]
diffuse = [0.9, 0.05, 0.05]
[[lights]]
type = "point"
position = [0.0, 1.5, 1.5]
intensity = 20.0
[[objects]]
type = "quad"
center = [0.0, 0.0, -3.0]
size = [4.0, 4.0]
normal = [0.0, 0.0, 1.0]
material = "surface"
[[objects]]
type = "sphere"
center = [0.0, 0.0, 3.0]
radius = 1.0
material = "red"
"#,
            if mirror { "mirror = { reflectivity = 1.0 }" } else { "" }
        )
    };
    let mut centre = Vec::new();
    for mirror in [true, false] {
        let path = dir.path().join(format!("mirror-{mirror}.toml"));
        std::fs::write(&path, scene(mirror)).unwrap();
        let (img, _) = render(
            &path,
            &dir.path().join(format!("mirror-{mirror}.png")),
            &["--accel", "kdtree"],
        );
        centre.push(mean_rgb(&img, 32, 32));
    }
    let (m, d) = (centre[0], centre[1]);
    assert!(
        m[0] > 3.0 * m[1] && m[0] > 60.0,
        "mirror centre {m:?} should show the red ball"
    );
    assert!(d[0] < 1.5 * d[1], "diffuse centre {d:?} should be grey");
}

#[test]
fn exr_output_is_linear_and_png_is_optional() {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("out.exr");
    let o = caustic(&[
        "render",
        "scenes/test/shadow.toml",
        "--exr",
        exr.to_str().unwrap(),
        "--quiet",
        "--accel",
        "kdtree",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let img = exr::prelude::read_first_rgba_layer_from_file(
        &exr,
        |res, _| vec![[0.0f32; 3]; res.width() * res.height()],
        |px: &mut Vec<[f32; 3]>, pos, (r, g, b, _a): (f32, f32, f32, f32)| px[pos.y() * 128 + pos.x()] = [r, g, b],
    )
    .expect("the EXR reads back");
    let px = &img.layer_data.channel_data.pixels;
    assert_eq!(px.len(), 128 * 96);
    assert!(px.iter().all(|p| p.iter().all(|c| c.is_finite() && *c >= 0.0)));
    assert!(px.iter().any(|p| p[0] > 0.05), "the lit floor has radiance");
    // --exr alone writes no PNG.
    assert!(std::fs::read_dir(dir.path()).unwrap().count() == 1);
}

#[test]
fn info_prints_statistics_build_and_plan() {
    let o = caustic(&["info", "scenes/cornell.toml", "--accel", "kdtree"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = stdout(&o);
    for needle in [
        "objects",
        "triangles",
        "accelerator kdtree",
        "built in",
        "render plan",
        "secondary rays: ran",
    ] {
        assert!(s.contains(needle), "missing {needle:?} in:\n{s}");
    }
}

#[test]
fn info_lists_environment_images_and_the_pixel_filter() {
    let o = caustic(&["info", "scenes/environment.toml", "--accel", "kdtree"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = stdout(&o);
    for needle in [
        "environment image scenes/textures/sky.hdr: 256×128",
        "camera      pinhole, pixel filter box (radius 0.5 px)",
    ] {
        assert!(s.contains(needle), "missing {needle:?} in:\n{s}");
    }
}

#[test]
fn bad_input_exits_2_with_a_clear_message() {
    let dir = tempfile::tempdir().unwrap();
    // Missing scene file.
    let o = caustic(&["render", "scenes/does-not-exist.toml"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("scenes/does-not-exist.toml"), "{}", stderr(&o));
    // Malformed scene: file, line and column.
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "[render]\nwidth = \"wide\"\n").unwrap();
    let o = caustic(&["render", bad.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("bad.toml:2:9"), "{}", stderr(&o));
    // Absurd overrides are refused before any allocation.
    let o = caustic(&[
        "render",
        "scenes/test/shadow.toml",
        "--width",
        "60000",
        "--height",
        "60000",
        "--spp",
        "1000",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("GiB"), "{}", stderr(&o));
    // So is an spp that would never finish, even on a tiny image.
    let o = caustic(&[
        "render",
        "scenes/test/shadow.toml",
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "4294967295",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("samples per pixel"), "{}", stderr(&o));
    // An unwritable output is reported before rendering.
    let o = caustic(&[
        "render",
        "scenes/test/shadow.toml",
        "-o",
        "/nonexistent-dir/x.png",
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("/nonexistent-dir"), "{}", stderr(&o));
    assert!(stdout(&o).is_empty(), "nothing was rendered: {}", stdout(&o));
}

/// Parameters the integrator ignores, and materials that reflect more than
/// they receive, are named by `info` and at the start of a render.
#[test]
fn dead_and_energy_gaining_material_parameters_are_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.toml");
    std::fs::write(
        &scene,
        r#"
[render]
width = 8
height = 6
[camera]
position = [0, 0, 5]
look_at = [0, 0, 0]
[materials.chrome]
diffuse = [0.3, 0.3, 0.3]
specular = [0.5, 0.5, 0.5]
mirror = { reflectivity = 1.0 }
[materials.hot]
diffuse = [0.9, 0.9, 0.9]
specular = [0.3, 0.3, 0.3]
[[lights]]
type = "point"
position = [0, 3, 3]
intensity = 10.0
[[objects]]
type = "sphere"
center = [-1, 0, 0]
radius = 0.5
material = "chrome"
[[objects]]
type = "sphere"
center = [1, 0, 0]
radius = 0.5
material = "hot"
"#,
    )
    .unwrap();
    let s = scene.to_str().unwrap();
    let info = caustic(&["info", s, "--accel", "kdtree"]);
    assert!(info.status.success(), "{}", stderr(&info));
    let text = stdout(&info);
    assert!(
        text.contains("material `chrome`: `diffuse`, `specular`, `ambient` are ignored: a perfect mirror"),
        "{text}"
    );
    assert!(
        text.contains("material `hot`: reflects more light than it receives"),
        "{text}"
    );
    let out = dir.path().join("o.png");
    let render = caustic(&["render", s, "--accel", "kdtree", "-o", out.to_str().unwrap()]);
    assert!(render.status.success(), "{}", stderr(&render));
    assert!(
        stderr(&render).contains("warning: material `hot`"),
        "{}",
        stderr(&render)
    );
}

/// The README's first scene is `examples/first.toml`, word for word, and it
/// renders: the photon pass runs (the ball is glass) and the image is written.
#[test]
fn the_readme_scene_is_the_example_file_and_renders() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let file = std::fs::read_to_string(root.join("examples/first.toml")).unwrap();
    let block = readme
        .split("```toml\n")
        .nth(1)
        .and_then(|rest| rest.split("```").next())
        .expect("README.md has a ```toml block");
    assert_eq!(block, file, "README.md's scene differs from examples/first.toml");
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("first.png");
    let o = caustic(&[
        "render",
        "examples/first.toml",
        "--width",
        "96",
        "--height",
        "54",
        "--spp",
        "2",
        "--photons",
        "20000",
        "--accel",
        "kdtree",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("photon pass: 20000 emitted"), "{}", stdout(&o));
    assert!(png.is_file());
}

/// `-o NAME.exr` writes the linear EXR (not a PNG under an EXR name), and
/// naming two EXRs at once is refused.
#[test]
fn an_exr_name_after_o_writes_the_exr() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("shot.exr");
    let scene = repo("scenes/test/shadow.toml");
    let o = caustic(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--width",
        "16",
        "--height",
        "12",
        "--spp",
        "1",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&out).unwrap();
    assert_eq!(&bytes[..4], &[0x76, 0x2f, 0x31, 0x01], "OpenEXR magic number");
    assert!(!dir.path().join("shadow.png").exists());
    let other = dir.path().join("other.exr");
    let o = caustic(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--exr",
        other.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("give one of them"), "{}", stderr(&o));
}
