//! `caustic convert`: every TOML scene of `scenes/` and every Mitsuba
//! scene of `tests/data/mitsuba/`, written as TOML and read back, is the
//! same scene part by part and renders the same image bit for bit; the
//! command line writes the files it names and refuses an unwritable
//! output with exit code 2, leaving nothing behind.

mod common;

use caustic::scene::compare::first_difference;
use caustic::scene::write::write_toml_scene;
use caustic::scene::{load_scene, load_scene_with, LoadedScene};
use common::same::{assert_same_scene, render_small, Names};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Writes `scene` into a fresh folder, reads it back, and checks both the
/// library's comparison and the tests' own, then a small render of each.
fn round_trip(what: &str, scene: &LoadedScene) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out").join("converted.toml");
    std::fs::create_dir_all(out.parent().unwrap()).unwrap();
    let written = write_toml_scene(scene, &out).unwrap_or_else(|e| panic!("{what}: {e}"));
    assert_eq!(written.scene, out);
    for m in &written.meshes {
        assert!(m.is_file(), "{what}: {}", m.display());
        assert_eq!(m.extension().and_then(|e| e.to_str()), Some("ply"));
    }
    let again = load_scene(&out).unwrap_or_else(|e| panic!("{what}: {e}"));
    assert_eq!(first_difference(scene, &again), None, "{what}");
    assert_same_scene(scene, &again, Names::Same);
    let (a, b) = (render_small(scene, 12, 9, 2), render_small(&again, 12, 9, 2));
    assert!(
        a.iter().any(|p| p.iter().any(|c| *c > 0.0)),
        "{what}: a black image proves little"
    );
    assert!(a == b, "{what}: the converted scene renders differently");
}

#[test]
fn every_toml_scene_converts_to_itself() {
    let mut names: Vec<PathBuf> = std::fs::read_dir(root().join("scenes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    names.sort();
    assert!(names.len() >= 10, "{names:?}");
    for path in names {
        let scene = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
        round_trip(&path.display().to_string(), &scene);
    }
}

#[test]
fn every_mitsuba_scene_converts_to_the_same_scene() {
    let dir = root().join("tests/data/mitsuba");
    let mut scenes = Vec::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "xml") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        if text.contains("<sensor") {
            scenes.push(path);
        } else {
            // Definitions that scenes include: not a scene by itself.
            assert!(text.contains("<bsdf"), "{}", path.display());
        }
    }
    scenes.sort();
    assert!(scenes.len() >= 3, "{scenes:?}");
    for path in scenes {
        let defines = [
            ("res".to_string(), "12".to_string()),
            ("spp".to_string(), "2".to_string()),
        ];
        let scene = load_scene_with(&path, &defines).unwrap_or_else(|e| panic!("{e}"));
        round_trip(&path.display().to_string(), &scene);
    }
}

#[test]
fn the_command_line_converts_with_defines_and_refuses_an_unwritable_output() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("room.toml");
    let xml = root().join("tests/data/mitsuba/room.xml");
    let o = common::cli::caustic(&[
        "convert",
        xml.to_str().unwrap(),
        "-D",
        "res=10",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", common::cli::describe(&o));
    let scene = load_scene(&out).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((scene.settings.width, scene.settings.height), (10, 10));
    // The cube Mitsuba builds in memory is written beside the output.
    let ply = dir.path().join("room-mesh-0.ply");
    assert!(ply.is_file(), "{}", common::cli::stdout(&o));
    assert!(common::cli::stdout(&o).contains("room-mesh-0.ply"));

    let missing = dir.path().join("no-such-folder").join("x.toml");
    let o = common::cli::caustic(&["convert", xml.to_str().unwrap(), "-o", missing.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", common::cli::describe(&o));
    assert!(
        common::cli::stderr(&o).contains("no-such-folder"),
        "{}",
        common::cli::describe(&o)
    );
    assert!(!missing.parent().unwrap().exists());

    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 5]\n").unwrap();
    let out2 = dir.path().join("out2.toml");
    let o = common::cli::caustic(&["convert", bad.to_str().unwrap(), "-o", out2.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", common::cli::describe(&o));
    assert!(
        common::cli::stderr(&o).contains("bad.toml:3:11"),
        "{}",
        common::cli::describe(&o)
    );
    assert!(!out2.exists());
}

/// What caustic's TOML cannot spell is refused by name, and nothing is written.
#[test]
fn a_part_without_a_toml_spelling_is_refused_and_nothing_is_written() {
    let mut scene = load_scene(&root().join("scenes/lamps.toml")).unwrap();
    let light = scene
        .scene
        .lights
        .iter_mut()
        .find(|l| matches!(l, caustic::scene::Light::Directional { .. }))
        .expect("lamps.toml has a directional light");
    if let caustic::scene::Light::Directional { direction, .. } = light {
        // Not a unit vector: the loader would normalise it.
        *direction = caustic::math::Vec3A::new(0.6, -0.9, 0.0);
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.toml");
    let e = write_toml_scene(&scene, &out).unwrap_err();
    assert!(e.is_input(), "{e}");
    assert!(e.to_string().contains("directional"), "{e}");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn meshes_read_from_files_are_referenced_by_path() {
    let path = root().join("scenes/textured.toml");
    let scene = load_scene(&path).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t.toml");
    let written = write_toml_scene(&scene, &out).unwrap();
    assert!(written.meshes.is_empty(), "{:?}", written.meshes);
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.contains("scenes/meshes/card.obj"), "{text}");
    assert!(text.contains("scenes/textures/bricks.png"), "{text}");
    assert!(Path::new(&written.referenced[0]).ends_with("scenes/meshes/card.obj"));
}

/// The keys `convert` writes for exactness (the camera's frame, a mesh's
/// `matrix`, a disk's semi-axes) load what they say and refuse bad values
/// at their place.
#[test]
fn the_exact_keys_load_and_are_checked_at_their_place() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dir.path().join("tri.off");
    std::fs::write(&mesh, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").unwrap();
    let text = r#"[camera]
position = [0, 0, 5]
forward = [0, 0, -1]
right = [1, 0, 0]
up = [0, 1, 0]

[[objects]]
type = "mesh"
file = "tri.off"
matrix = [[2, 0, 0, 1], [0, 3, 0, 2], [0, 0, 4, 3]]
material = "m"

[[objects]]
type = "disk"
center = [0, 0, 0]
u = [2, 0, 0]
v = [0, 1, 0]
flip_normals = true
material = "m"

[materials.m]
"#;
    let path = dir.path().join("s.toml");
    let parse = |t: &str| caustic::scene::parse_scene(t, &path).map_err(|e| e.to_string());
    let scene = parse(text).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.scene.camera.right, caustic::math::Vec3A::X);
    assert_eq!(scene.scene.camera.forward, -caustic::math::Vec3A::Z);
    match &scene.scene.objects[0].shape {
        caustic::scene::Shape::Mesh { transform, .. } => {
            let p = transform.point(caustic::math::Vec3A::ONE);
            assert_eq!(p, caustic::math::Vec3A::new(3.0, 5.0, 7.0));
        }
        other => panic!("{other:?}"),
    }
    match &scene.scene.objects[1].shape {
        caustic::scene::Shape::Disk(d) => {
            assert_eq!(
                (d.a, d.b),
                (caustic::math::Vec3A::new(2.0, 0.0, 0.0), caustic::math::Vec3A::Y)
            );
            assert_eq!(d.normal, -caustic::math::Vec3A::Z);
        }
        other => panic!("{other:?}"),
    }
    let cases = [
        (
            "right = [1, 0, 0]",
            "right = [1, 0.5, 0]",
            "s.toml:4:9",
            "`right` = [1, 0.5, 0] must be a unit vector",
        ),
        (
            "right = [1, 0, 0]",
            "right = [0, 1, 0]",
            "s.toml:4:9",
            "must be orthogonal",
        ),
        ("right = [1, 0, 0]\n", "", "s.toml:3:11", "needs `right`"),
        (
            "forward = [0, 0, -1]",
            "look_at = [0, 0, 0]",
            "s.toml:4:9",
            "`right` goes with `forward`",
        ),
        (
            "[0, 0, 4, 3]]",
            "[0, 0, 0, 3]]",
            "s.toml:10:10",
            "the mesh `matrix` is singular",
        ),
        (
            "matrix = [[2",
            "scale = 2\nmatrix = [[2",
            "s.toml:10:9",
            "`scale` with `matrix`",
        ),
        (
            "[0, 0, 4, 3]]",
            "[0, 0, 4]]",
            "s.toml:10:",
            "expected an array of 4 numbers, found 3",
        ),
        (
            "v = [0, 1, 0]",
            "v = [4, 0, 0]",
            "s.toml:17:5",
            "`u` and `v` are parallel",
        ),
        ("v = [0, 1, 0]\n", "", "s.toml:16:5", "needs `v`"),
        (
            "u = [2, 0, 0]",
            "radius = 1\nu = [2, 0, 0]",
            "s.toml:16:10",
            "`radius` does not apply",
        ),
    ];
    for (from, to, place, message) in cases {
        assert!(text.contains(from), "{from}");
        let e = parse(&text.replacen(from, to, 1)).expect_err(to);
        assert!(e.contains(place) && e.contains(message), "{to}: {e}");
    }
}

/// An orthographic camera and a spot light with glTF's falloff keep their
/// keys through `caustic convert`.
#[test]
fn an_orthographic_camera_and_a_gltf_spot_convert_to_themselves() {
    let text = r#"[render]
width = 24
height = 12
integrator = "path"

[camera]
position = [0, 1, 5]
look_at = [0, 0, 0]
projection = "orthographic"
half_width = 2.5
half_height = 1.0
near_clip = 0.5

[materials.m]
diffuse = 0.6

[[lights]]
type = "spot"
position = [0, 3, 0]
look_at = [0, 0, 0]
cutoff_angle = 40
beam_width = 10
falloff = "gltf"
intensity = 20

[[objects]]
type = "quad"
center = [0, 0, 0]
size = [6, 6]
normal = [0, 1, 0]
up = [0, 0, -1]
material = "m"
"#;
    let scene = caustic::scene::parse_scene(text, Path::new("ortho.toml")).unwrap_or_else(|e| panic!("{e}"));
    assert!(scene.scene.camera.is_orthographic());
    round_trip("orthographic camera, glTF spot", &scene);
}
