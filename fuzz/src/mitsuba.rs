//! The Mitsuba XML front end's fuzzing harness, shared by the `mitsuba` fuzz
//! target and `tests/fuzz_regressions.rs` (which includes this file by
//! path, so both run an input in the same folder with the same files).
//!
//! The input is written as `scene.xml` into a folder that also holds the
//! files a scene may name, so that includes, meshes and textures resolve
//! and their readers run: `inc.xml` and `room-materials.xml` (includes
//! defining BSDFs), `parts/inc.xml` (for `<path value="parts"/>`),
//! `mesh.obj`, `cone.obj`, `mesh.ply`, `mesh.serialized` (two shapes) and
//! `tex.png`.

use std::path::PathBuf;

/// An include defining a BSDF, a texture and a default.
const INC_XML: &str = r#"<scene version="3.0.0">
    <default name="inc_spp" value="2"/>
    <bsdf type="diffuse" id="inc-bsdf">
        <rgb name="reflectance" value="0.2, 0.5, 0.8"/>
    </bsdf>
    <texture type="checkerboard" id="inc-tex">
        <rgb name="color0" value="0.1"/>
        <rgb name="color1" value="0.9"/>
    </texture>
</scene>
"#;

/// An include in a subfolder, found through `<path value="parts"/>`.
const PARTS_INC_XML: &str = r#"<scene version="3.0.0">
    <shape type="sphere" id="parts-sphere">
        <float name="radius" value="0.25"/>
    </shape>
</scene>
"#;

const MESH_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\n\
f 1/1 2/2 3/3\nf 2/2 4/4 3/3\n";

const MESH_PLY: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
property float z\nproperty float u\nproperty float v\nelement face 1\n\
property list uchar int vertex_indices\nend_header\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n";

/// A folder holding the fixed files beside which inputs are written.
pub struct Setting {
    dir: tempfile::TempDir,
}

impl Setting {
    /// Creates the folder and its files.
    pub fn new() -> Self {
        let dir = tempfile::tempdir().expect("temporary directory");
        let put = |name: &str, bytes: &[u8]| {
            let path = dir.path().join(name);
            std::fs::create_dir_all(path.parent().expect("a parent")).expect("folder");
            std::fs::write(path, bytes).expect("fixed fuzz file");
        };
        put("inc.xml", INC_XML.as_bytes());
        put(
            "room-materials.xml",
            include_bytes!("../../tests/data/mitsuba/room-materials.xml"),
        );
        put("parts/inc.xml", PARTS_INC_XML.as_bytes());
        put("mesh.obj", MESH_OBJ.as_bytes());
        put("cone.obj", include_bytes!("../../scenes/shapes/cone.obj"));
        put("mesh.ply", MESH_PLY.as_bytes());
        put("mesh.serialized", &serialized_mesh());
        put("tex.png", include_bytes!("../../scenes/textures/leaf.png"));
        Self { dir }
    }

    /// The scene file's path (the input is written there).
    pub fn scene_path(&self) -> PathBuf {
        self.dir.path().join("scene.xml")
    }
}

impl Default for Setting {
    fn default() -> Self {
        Self::new()
    }
}

/// Two shapes (a triangle, and a quad with texture coordinates) as a
/// version-4 `.serialized` file.
fn serialized_mesh() -> Vec<u8> {
    use caustic::geometry::Mesh;
    use caustic::math::{Vec2, Vec3};
    let tri = Mesh::new("tri", vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]], None).expect("a valid mesh");
    let quad = Mesh::new(
        "quad",
        vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
        vec![[0, 1, 2], [0, 2, 3]],
        None,
    )
    .and_then(|m| m.with_uvs(vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y]))
    .expect("a valid mesh");
    caustic::io::serialized::write_serialized(&[&tri, &quad])
}

/// Why an input is not run: it names a device or kernel file
/// (`/dev/stdin` would block, `/dev/zero` never ends), which says nothing
/// about the front end and is not something to fuzz on a shared machine.
pub fn skipped(data: &[u8]) -> bool {
    [&b"/dev"[..], b"/proc", b"/sys"]
        .iter()
        .any(|needle| data.windows(needle.len()).any(|w| w == *needle))
}

/// Writes `data` as the scene and loads it with `-D fuzz_res=8`. Any `Err`
/// is a normal outcome; the caller checks for panics, hangs and memory.
pub fn load(
    setting: &Setting,
    data: &[u8],
) -> Result<caustic::scene::mitsuba::MitsubaScene, caustic::scene::SceneError> {
    let path = setting.scene_path();
    std::fs::write(&path, data).expect("writing the fuzz input");
    caustic::scene::mitsuba::load_mitsuba_scene(&path, &[("fuzz_res".to_string(), "8".to_string())])
}
