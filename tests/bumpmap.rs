//! Bump maps (`bump_map`, Mitsuba's `bumpmap`): the shading normal of a
//! quad tilted by a two-texel height ramp against the normal computed by
//! hand, through a UV transform, from TOML and from Mitsuba XML alike; and
//! a bump map written by `caustic convert` reads back the same.

mod common;

use caustic::geometry::Hit;
use caustic::math::{Ray, Vec3A};
use caustic::scene::parse_scene;
use caustic::scene::LoadedScene;
use std::path::Path;

/// A 2 × 1 linear image: height 0 on the left texel, 1 on the right.
fn ramp(dir: &Path) {
    let img = image::RgbImage::from_raw(2, 1, vec![0, 0, 0, 255, 255, 255]).unwrap();
    img.save(dir.join("ramp.png")).unwrap();
}

/// The quad `[-1, 1]²` at z = 0 facing +z (`∂p/∂u = (2, 0, 0)`,
/// `∂p/∂v = (0, 2, 0)`), bumped by the ramp.
fn toml_scene(dir: &Path, texture_extra: &str, channel: &str) -> LoadedScene {
    let text = format!(
        r#"[camera]
position = [0, 0, 5]
look_at = [0, 0, 0]

[materials.bumpy]
bump_map = {{ type = "image", file = "ramp.png", colour_space = "linear", channel = "{channel}"{texture_extra} }}
bump_scale = 0.25

[[objects]]
type = "quad"
corner = [-1, -1, 0]
u = [2, 0, 0]
v = [0, 2, 0]
material = "bumpy"
"#
    );
    parse_scene(&text, &dir.join("scene.toml")).unwrap_or_else(|e| panic!("{e}"))
}

fn normal_at(scene: &LoadedScene, u: f32, v: f32) -> Vec3A {
    let ray = Ray::new(Vec3A::new(0.0, 0.0, 5.0), -Vec3A::Z);
    let hit = Hit {
        t: 5.0,
        instance: 0,
        prim: 0,
        u,
        v,
    };
    scene.scene.surface_interaction(&ray, &hit).ns
}

fn close(a: Vec3A, b: Vec3A) -> bool {
    (a - b).abs().max_element() < 1e-6
}

#[test]
fn a_height_ramp_tilts_the_normal_by_its_gradient() {
    let dir = tempfile::tempdir().unwrap();
    ramp(dir.path());
    let scene = toml_scene(dir.path(), "", "r");
    // At (0.5, 0.5) the lookup sits halfway between the texel centres:
    // ∂h/∂x = 1 per texel, ∂h/∂u = 2 (two texels across), times the scale
    // 0.25: g = (0.5, 0). ∂p/∂u' = (2, 0, 0.5), ∂p/∂v' = (0, 2, 0), and
    // their cross product is (−1, 0, 4).
    let n = normal_at(&scene, 0.5, 0.5);
    assert!(close(n, Vec3A::new(-1.0, 0.0, 4.0).normalize()), "{n}");
    // The ramp is the same along v: no tilt toward y anywhere.
    let n = normal_at(&scene, 0.4, 0.9);
    assert!(close(n, Vec3A::new(-1.0, 0.0, 4.0).normalize()), "{n}");

    // A UV transform doubling u doubles the slope: at u = 0.25 the lookup
    // is where it was, and g = (1, 0): (2, 0, 1) × (0, 2, 0) = (−2, 0, 4).
    let scene = toml_scene(dir.path(), ", scale = [2, 1]", "r");
    let n = normal_at(&scene, 0.25, 0.5);
    assert!(close(n, Vec3A::new(-1.0, 0.0, 2.0).normalize()), "{n}");

    // Nearest lookups are piecewise constant: no tilt.
    let scene = toml_scene(dir.path(), ", filter = \"nearest\"", "r");
    assert_eq!(normal_at(&scene, 0.5, 0.5), Vec3A::Z);
}

#[test]
fn mitsuba_bumpmap_reads_as_the_toml_bump_map() {
    let dir = tempfile::tempdir().unwrap();
    ramp(dir.path());
    let xml = r#"<scene version="3.0.0">
<sensor type="perspective"><transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform></sensor>
<shape type="rectangle">
  <bsdf type="bumpmap">
    <texture type="bitmap" name="height"><string name="filename" value="ramp.png"/><boolean name="raw" value="true"/></texture>
    <float name="scale" value="0.25"/>
    <bsdf type="diffuse"/>
  </bsdf>
</shape>
</scene>
"#;
    let path = common::mitsuba::write(dir.path(), "scene.xml", xml);
    let scene = caustic::scene::mitsuba::load_mitsuba_scene(&path, &[])
        .unwrap_or_else(|e| panic!("{e}"))
        .into_loaded();
    // Mitsuba's scalar lookup of a grey image is its luminance.
    let toml = toml_scene(dir.path(), "", "luminance");
    for (u, v) in [(0.5, 0.5), (0.3, 0.7), (0.9, 0.1)] {
        let (a, b) = (normal_at(&scene, u, v), normal_at(&toml, u, v));
        assert!(close(a, b), "at ({u}, {v}): {a} against {b}");
    }
    assert!(normal_at(&scene, 0.5, 0.5).x < -0.2);

    // A checkerboard has no gradient in Mitsuba: refused, with its place.
    let bad = xml.replace(
        r#"<texture type="bitmap" name="height"><string name="filename" value="ramp.png"/><boolean name="raw" value="true"/></texture>"#,
        r#"<texture type="checkerboard" name="height"/>"#,
    );
    let e = common::mitsuba::error(&bad);
    assert!(e.contains("scene.xml:5:5") && e.contains("checkerboard"), "{e}");
}

#[test]
fn a_bump_map_converts_to_itself_and_is_checked() {
    let dir = tempfile::tempdir().unwrap();
    ramp(dir.path());
    let scene = toml_scene(dir.path(), "", "r");
    let out = dir.path().join("out.toml");
    caustic::scene::write::write_toml_scene(&scene, &out).unwrap_or_else(|e| panic!("{e}"));
    let again = caustic::scene::load_scene(&out).unwrap();
    assert_eq!(caustic::scene::compare::first_difference(&scene, &again), None);
    assert_eq!(normal_at(&scene, 0.5, 0.5), normal_at(&again, 0.5, 0.5));

    let head = "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n\n[materials.m]\n";
    let cases = [
        (
            "bump_scale = 2\n",
            "scene.toml:6:14",
            "`bump_scale` without a `bump_map`",
        ),
        (
            "normal_map = \"t\"\nbump_map = \"t\"\n",
            "scene.toml:7:12",
            "`normal_map` or `bump_map`, not both",
        ),
        ("bump_map = 0.5\n", "scene.toml:6:12", "must be a texture"),
    ];
    for (body, place, message) in cases {
        let text = format!("{head}{body}\n[textures.t]\ntype = \"checkerboard\"\n");
        let e = parse_scene(&text, &dir.path().join("scene.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains(place) && e.contains(message), "{body}: {e}");
    }
}
