//! `caustic convert`: every TOML scene of `scenes/` and every Mitsuba
//! scene of `tests/data/mitsuba/`, written as TOML and read back, is the
//! same scene part by part and renders the same image bit for bit; the
//! command line writes the files it names and refuses an unwritable
//! output with exit code 2, leaving nothing behind.

mod common;

use caustic::scene::compare::first_difference;
use caustic::scene::write::write_toml_scene;
use caustic::scene::{load_scene, load_scene_with, Scene};
use common::same::{assert_same_scene, render_small, Names};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Writes `scene` into a fresh folder, reads it back, and checks both the
/// library's comparison and the tests' own, then a small render of each.
fn round_trip(what: &str, scene: &Scene) {
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
