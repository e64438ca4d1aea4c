//! Fuzzes the glTF 2.0 front end (`load_gltf_scene`): the input is written
//! as `model.glb` when it starts with the GLB magic, else `model.gltf`, in an
//! empty temporary directory (so external buffers and images name files
//! that do not exist; data URIs carry the rest). Any `Err` is fine; a panic,
//! a hang or an oversized allocation is a bug.
#![no_main]

use caustic::scene::gltf::{load_gltf_scene, GltfOptions};
use libfuzzer_sys::fuzz_target;
use std::sync::OnceLock;

static DIR: OnceLock<tempfile::TempDir> = OnceLock::new();

fuzz_target!(|data: &[u8]| {
    let dir = DIR.get_or_init(|| tempfile::tempdir().expect("temporary directory"));
    let name = if data.starts_with(b"glTF") { "model.glb" } else { "model.gltf" };
    let path = dir.path().join(name);
    if std::fs::write(&path, data).is_err() {
        return;
    }
    let _ = load_gltf_scene(&path, &GltfOptions::default());
});
