//! Mesh objects in scene files: relative paths, one load per distinct file,
//! transforms and the smooth flag, and the complete example of
//! `docs/scene-format.md`.
//!
//! These tests need the real mesh loader (`io::load_mesh`, OFF format): they
//! fail on a branch where it is still a stub.

use caustic::math::Vec3A;
use caustic::scene::{load_scene, SceneError, Shape};
use std::path::Path;

/// A unit right triangle in the xy plane.
const TRIANGLE_OFF: &str = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
/// A unit square (two triangles) in the xy plane.
const SQUARE_OFF: &str = "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n";

const HEADER: &str = "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n[materials.m]\n";

fn write(dir: &Path, name: &str, text: &str) {
    let path = dir.join(name);
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(path, text).unwrap();
}

fn mesh_object(file: &str, extra: &str) -> String {
    format!("[[objects]]\ntype = \"mesh\"\nmaterial = \"m\"\nfile = \"{file}\"\n{extra}")
}

#[test]
fn a_file_used_by_several_objects_is_loaded_once() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "meshes/tri.off", TRIANGLE_OFF);
    write(dir.path(), "meshes/square.off", SQUARE_OFF);
    std::fs::create_dir_all(dir.path().join("other")).unwrap();
    let text = [
        HEADER.to_string(),
        mesh_object("meshes/tri.off", ""),
        mesh_object("meshes/square.off", ""),
        mesh_object("./meshes/tri.off", "translate = [3, 0, 0]\n"),
        mesh_object("other/../meshes/tri.off", "scale = 2\n"),
        mesh_object("meshes/square.off", "smooth = true\n"),
    ]
    .concat();
    write(dir.path(), "scene.toml", &text);
    let scene = load_scene(&dir.path().join("scene.toml")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.scene.meshes.len(), 2, "two distinct files");
    // Meshes are numbered in order of first use.
    assert_eq!(scene.scene.meshes[0].triangles.len(), 1);
    assert_eq!(scene.scene.meshes[1].triangles.len(), 2);
    let mesh_of = |i: usize| match &scene.scene.objects[i].shape {
        Shape::Mesh { mesh, smooth, .. } => (*mesh, *smooth),
        s => panic!("{s:?}"),
    };
    assert_eq!(
        (0..5).map(mesh_of).collect::<Vec<_>>(),
        [(0, false), (1, false), (0, false), (0, false), (1, true)]
    );
    assert_eq!(scene.scene.instanced_triangles(), 1 + 2 + 1 + 1 + 2);
    // Transforms: translated and uniformly scaled instances of the triangle.
    let b = scene.scene.object_bounds(2);
    assert!((b.min - Vec3A::new(3.0, 0.0, 0.0)).length() < 1e-5, "{b:?}");
    let b = scene.scene.object_bounds(3);
    assert!((b.max - Vec3A::new(2.0, 2.0, 0.0)).length() < 1e-5, "{b:?}");
}

#[test]
fn mesh_transform_is_scale_then_rotate_then_translate() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tri.off", TRIANGLE_OFF);
    let text = format!(
        "{HEADER}{}",
        mesh_object(
            "tri.off",
            "scale = [2, 3, 1]\nrotate = [0, 0, 90]\ntranslate = [10, 0, 0]\n"
        )
    );
    write(dir.path(), "scene.toml", &text);
    let scene = load_scene(&dir.path().join("scene.toml")).unwrap_or_else(|e| panic!("{e}"));
    let Shape::Mesh { transform, .. } = &scene.scene.objects[0].shape else {
        panic!()
    };
    // (1,0,0) → scale (2,0,0) → 90° about z (0,2,0) → translate (10,2,0).
    let p = transform.point(Vec3A::X);
    assert!((p - Vec3A::new(10.0, 2.0, 0.0)).length() < 1e-5, "{p}");
    let p = transform.point(Vec3A::Y);
    assert!((p - Vec3A::new(7.0, 0.0, 0.0)).length() < 1e-5, "{p}");
}

#[test]
fn malformed_mesh_error_names_the_scene_place_and_the_mesh() {
    let dir = tempfile::tempdir().unwrap();
    // Face index 7 with only 3 vertices.
    write(dir.path(), "bad.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
    let text = format!("{HEADER}{}", mesh_object("bad.off", ""));
    write(dir.path(), "scene.toml", &text);
    let scene_path = dir.path().join("scene.toml");
    let err = load_scene(&scene_path).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.starts_with(&format!("{}:8:8: mesh of object `mesh#0`: ", scene_path.display())),
        "{msg}"
    );
    assert!(msg.contains("bad.off"), "{msg}");
    assert!(matches!(err, SceneError::Mesh { .. }));
}

/// The complete example of the format documentation loads (with a star
/// prism OFF file written beside it).
#[test]
fn documented_example_loads() {
    let doc = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/scene-format.md")).unwrap();
    let start = doc.find("<!-- complete-example -->").expect("marker in docs");
    let body = &doc[start..];
    let begin = body.find("```toml\n").unwrap() + "```toml\n".len();
    let end = body[begin..].find("```").unwrap();
    let example = &body[begin..begin + end];

    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "scene.toml", example);
    write(dir.path(), "meshes/prism.off", &star_prism_off());
    let scene = load_scene(&dir.path().join("scene.toml")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.scene.meshes.len(), 1);
    let meshes = scene
        .scene
        .objects
        .iter()
        .filter(|o| matches!(o.shape, Shape::Mesh { .. }))
        .count();
    assert!(meshes >= 2, "the example shows a shared mesh");
}

/// A closed five-pointed star prism (10 outline vertices, height 1).
fn star_prism_off() -> String {
    let mut v = Vec::new();
    for z in [0.0f32, 1.0] {
        for i in 0..10 {
            let a = std::f32::consts::PI * 2.0 * i as f32 / 10.0;
            let r = if i % 2 == 0 { 1.0 } else { 0.4 };
            v.push(format!("{} {} {}", r * a.cos(), r * a.sin(), z));
        }
    }
    v.push("0 0 0".into());
    v.push("0 0 1".into());
    let mut f = Vec::new();
    for i in 0..10 {
        let j = (i + 1) % 10;
        f.push(format!("3 20 {j} {i}"));
        f.push(format!("3 21 {} {}", 10 + i, 10 + j));
        f.push(format!("4 {i} {j} {} {}", 10 + j, 10 + i));
    }
    format!("OFF\n{} {} 0\n{}\n{}\n", v.len(), f.len(), v.join("\n"), f.join("\n"))
}
