//! Hostile and broken glTF models: each is refused with the file and the
//! JSON pointer of the value at fault (exit code 2 from the command line),
//! never a panic, a hang or an allocation the data does not back. The
//! models are the files of `tests/data/gltf/` with one value changed.

mod common;

use base64::Engine;
use caustic::scene::gltf::{load_gltf_scene, GltfOptions};
use common::cli::{caustic, describe, stderr};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/gltf")
        .join(name)
}

fn document(name: &str) -> Value {
    serde_json::from_slice(&std::fs::read(data(name)).unwrap()).unwrap()
}

/// Writes `doc` as `model.gltf` in `dir`.
fn write(dir: &Path, doc: &Value) -> PathBuf {
    let path = dir.join("model.gltf");
    std::fs::write(&path, serde_json::to_vec(doc).unwrap()).unwrap();
    path
}

/// The error of loading `doc` (after `change`), which must name the file.
fn error_of(name: &str, change: impl FnOnce(&mut Value)) -> String {
    let dir = tempfile::tempdir().unwrap();
    let mut doc = document(name);
    change(&mut doc);
    let path = write(dir.path(), &doc);
    let e = load_gltf_scene(&path, &GltfOptions::default())
        .expect_err("the model must be refused")
        .to_string();
    assert!(e.contains("model.gltf"), "the message names the file: {e}");
    e
}

fn assert_has(e: &str, parts: &[&str]) {
    for p in parts {
        assert!(e.contains(p), "`{p}` missing from: {e}");
    }
}

/// The first buffer's bytes (a base64 data URI).
fn buffer_bytes(doc: &Value) -> Vec<u8> {
    let uri = doc["buffers"][0]["uri"].as_str().unwrap();
    let b64 = uri.split_once(',').unwrap().1;
    base64::engine::general_purpose::STANDARD.decode(b64).unwrap()
}

fn set_buffer_bytes(doc: &mut Value, bytes: &[u8]) {
    let b64 = base64::engine::general_purpose::STANDARD.encode(bytes);
    doc["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{b64}"));
}

#[test]
fn an_accessor_index_out_of_range_is_named_by_its_pointer() {
    let e = error_of("textured_quad.gltf", |d| {
        d["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(99)
    });
    assert_has(&e, &["/meshes/0/primitives/0/attributes/POSITION", "out of range"]);
}

#[test]
fn an_accessor_past_its_buffer_view_is_refused() {
    let e = error_of("textured_quad.gltf", |d| d["accessors"][0]["byteOffset"] = json!(1000));
    assert_has(
        &e,
        &[
            "/meshes/0/primitives/0/attributes/POSITION",
            "accessor 0",
            "buffer view 0 has 48",
        ],
    );
    // A stride that makes the elements overrun the view.
    let e = error_of("nodes.gltf", |d| d["bufferViews"][0]["byteStride"] = json!(48));
    assert_has(&e, &["attributes/POSITION", "every 48"]);
    // A view past its buffer.
    let e = error_of("textured_quad.gltf", |d| {
        d["bufferViews"][3]["byteOffset"] = json!(1 << 20)
    });
    assert_has(&e, &["/bufferViews/3"]);
}

#[test]
fn wrong_component_types_and_counts_are_refused() {
    let e = error_of("textured_quad.gltf", |d| {
        d["accessors"][0]["componentType"] = json!(5121)
    });
    assert_has(&e, &["attributes/POSITION", "UNSIGNED_BYTE", "FLOAT"]);
    let e = error_of("textured_quad.gltf", |d| d["accessors"][0]["type"] = json!("VEC2"));
    assert_has(&e, &["attributes/POSITION", "needs 3 components"]);
    let e = error_of("textured_quad.gltf", |d| {
        d["meshes"][0]["primitives"][0]["indices"] = json!(0)
    });
    assert_has(&e, &["/meshes/0/primitives/0/indices"]);
    // NORMAL with fewer elements than POSITION.
    let e = error_of("textured_quad.gltf", |d| d["accessors"][1]["count"] = json!(3));
    assert_has(&e, &["attributes/NORMAL", "3 elements, POSITION has 4"]);
}

#[test]
fn vertex_indices_out_of_range_are_refused() {
    let e = error_of("textured_quad.gltf", |d| {
        let mut bytes = buffer_bytes(d);
        // The index data starts at byte 128: index 2 becomes 7.
        bytes[128 + 4..128 + 6].copy_from_slice(&7u16.to_le_bytes());
        set_buffer_bytes(d, &bytes);
    });
    assert_has(&e, &["/meshes/0/primitives/0/indices", "is 7", "4 vertices"]);
}

#[test]
fn absurd_counts_are_refused_before_allocating() {
    let e = error_of("textured_quad.gltf", |d| {
        d["accessors"][0]["count"] = json!(4_000_000_000u64)
    });
    assert_has(&e, &["/accessors/0/count", "more than the limit"]);
    // Below the limit but beyond the data: the bounds say so before any allocation.
    let e = error_of("textured_quad.gltf", |d| {
        for a in 0..3 {
            d["accessors"][a]["count"] = json!(200_000_000u64);
        }
    });
    assert_has(&e, &["attributes/POSITION", "200000000 elements"]);
    // A buffer announcing more bytes than the limit.
    let e = error_of("textured_quad.gltf", |d| {
        d["buffers"][0]["byteLength"] = json!(1u64 << 40)
    });
    assert_has(&e, &["/buffers/0/byteLength", "more than the limit"]);
}

#[test]
fn a_truncated_bin_or_glb_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mut doc = document("textured_quad.gltf");
    let bytes = buffer_bytes(&doc);
    std::fs::write(dir.path().join("model.bin"), &bytes[..bytes.len() / 2]).unwrap();
    doc["buffers"][0]["uri"] = json!("model.bin");
    let path = write(dir.path(), &doc);
    let e = load_gltf_scene(&path, &GltfOptions::default()).unwrap_err().to_string();
    assert_has(&e, &["model.gltf", "/buffers/0/byteLength", "truncated"]);
    // The whole file reads.
    std::fs::write(dir.path().join("model.bin"), &bytes).unwrap();
    load_gltf_scene(&path, &GltfOptions::default()).unwrap();

    let glb = std::fs::read(data("emissive_quad.glb")).unwrap();
    for cut in [glb.len() - 1, glb.len() / 2, 20, 13, 5] {
        let p = dir.path().join("cut.glb");
        std::fs::write(&p, &glb[..cut]).unwrap();
        let e = load_gltf_scene(&p, &GltfOptions::default())
            .expect_err("a cut GLB is refused")
            .to_string();
        assert!(
            e.contains("cut.glb") && (e.contains("truncated") || e.contains("JSON")),
            "{cut}: {e}"
        );
    }
    // A binary chunk (and file) 8 bytes shorter than the buffer.
    let mut short = glb[..glb.len() - 8].to_vec();
    let total = short.len() as u32;
    short[8..12].copy_from_slice(&total.to_le_bytes());
    let json_len = u32::from_le_bytes(short[12..16].try_into().unwrap()) as usize;
    let bin_at = 20 + json_len;
    let bin_len = u32::from_le_bytes(short[bin_at..bin_at + 4].try_into().unwrap());
    short[bin_at..bin_at + 4].copy_from_slice(&(bin_len - 8).to_le_bytes());
    let p = dir.path().join("short.glb");
    std::fs::write(&p, &short).unwrap();
    let e = load_gltf_scene(&p, &GltfOptions::default()).unwrap_err().to_string();
    assert_has(&e, &["short.glb", "/buffers/0/byteLength", "truncated"]);
}

#[test]
fn undecodable_data_uris_are_refused() {
    let e = error_of("textured_quad.gltf", |d| {
        d["buffers"][0]["uri"] = json!("data:application/octet-stream;base64,@@not base64@@")
    });
    assert_has(&e, &["/buffers/0/uri", "does not decode"]);
    let e = error_of("textured_quad.gltf", |d| {
        d["images"][0]["uri"] = json!("data:image/png;base64,AAAA")
    });
    assert_has(&e, &["/images/0"]);
}

#[test]
fn missing_images_and_decompression_bombs_are_refused() {
    let e = error_of("textured_quad.gltf", |d| d["images"][0]["uri"] = json!("missing.png"));
    assert_has(&e, &["/images/0", "missing.png"]);
    let bomb = base64::engine::general_purpose::STANDARD.encode(common::images::huge_png_header());
    let e = error_of("textured_quad.gltf", |d| {
        d["images"][0]["uri"] = json!(format!("data:image/png;base64,{bomb}"))
    });
    assert_has(&e, &["/images/0", "refused"]);
}

#[test]
fn uris_leaving_the_models_folder_are_refused_unless_allowed() {
    let outer = tempfile::tempdir().unwrap();
    let inner = outer.path().join("model");
    std::fs::create_dir(&inner).unwrap();
    let mut doc = document("textured_quad.gltf");
    std::fs::write(outer.path().join("outside.bin"), buffer_bytes(&doc)).unwrap();
    doc["buffers"][0]["uri"] = json!("../outside.bin");
    let path = write(&inner, &doc);
    let e = load_gltf_scene(&path, &GltfOptions::default()).unwrap_err().to_string();
    assert_has(
        &e,
        &["/buffers/0/uri", "outside the model's folder", "--allow-outside-files"],
    );
    let allowed = GltfOptions {
        allow_outside_files: true,
        ..Default::default()
    };
    load_gltf_scene(&path, &allowed).unwrap();
    // Absolute paths and URLs are never read.
    doc["buffers"][0]["uri"] = json!("file:///etc/passwd");
    let path = write(&inner, &doc);
    let e = load_gltf_scene(&path, &allowed).unwrap_err().to_string();
    assert_has(&e, &["/buffers/0/uri", "only relative references"]);
}

#[test]
fn required_extensions_are_refused_by_name_and_used_ones_warned_about() {
    let e = error_of("textured_quad.gltf", |d| {
        d["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
        d["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    });
    assert_has(
        &e,
        &[
            "/extensionsRequired/0",
            "KHR_draco_mesh_compression",
            "does not implement",
        ],
    );
    let dir = tempfile::tempdir().unwrap();
    let mut doc = document("textured_quad.gltf");
    doc["extensionsUsed"] = json!(["EXT_meshopt_compression", "KHR_texture_transform"]);
    // A required extension caustic implements (beyond what the gltf crate checks) is fine.
    doc["extensionsRequired"] = json!(["KHR_texture_transform"]);
    let g = load_gltf_scene(&write(dir.path(), &doc), &GltfOptions::default()).unwrap();
    assert!(
        g.warnings.iter().any(|w| w.contains("EXT_meshopt_compression")),
        "{:?}",
        g.warnings
    );
    assert!(!g.warnings.iter().any(|w| w.contains("KHR_texture_transform")));
}

#[test]
fn node_cycles_and_shared_children_are_refused() {
    let e = error_of("nodes.gltf", |d| d["nodes"][1]["children"] = json!([0]));
    assert_has(&e, &["reached twice"]);
    let e = error_of("nodes.gltf", |d| d["nodes"][3]["children"] = json!([1]));
    assert_has(&e, &["/nodes/3/children/0", "reached twice"]);
}

#[test]
fn broken_json_and_bad_values_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("model.gltf");
    std::fs::write(&p, b"{\"asset\": {\"version\": \"2.0\"}, \"meshes\": [").unwrap();
    let e = load_gltf_scene(&p, &GltfOptions::default()).unwrap_err().to_string();
    assert_has(&e, &["model.gltf", "not a valid glTF 2.0 JSON"]);
    let e = error_of("nodes.gltf", |d| {
        d["extensions"]["KHR_lights_punctual"]["lights"][2]["spot"]["outerConeAngle"] = json!(2.0)
    });
    assert_has(&e, &["/extensions/KHR_lights_punctual/lights/2/spot/outerConeAngle"]);
    let e = error_of("nodes.gltf", |d| {
        d["nodes"][5]["extensions"]["KHR_lights_punctual"]["light"] = json!(9)
    });
    assert_has(&e, &["/nodes/5"]);
    let e = error_of("materials.gltf", |d| {
        d["materials"][5]["extensions"]["KHR_materials_clearcoat"]["clearcoatTexture"]["index"] = json!(40)
    });
    assert_has(
        &e,
        &[
            "/materials/5/extensions/KHR_materials_clearcoat/clearcoatTexture/index",
            "out of range",
        ],
    );
}

#[test]
fn the_command_line_exits_2_naming_the_file_and_the_pointer() {
    let dir = tempfile::tempdir().unwrap();
    let mut doc = document("textured_quad.gltf");
    doc["accessors"][0]["byteOffset"] = json!(1000);
    let path = write(dir.path(), &doc);
    let out = dir.path().join("out.png");
    let o = caustic(&["render", path.to_str().unwrap(), "-o", out.to_str().unwrap(), "--quiet"]);
    assert_eq!(o.status.code(), Some(2), "{}", describe(&o));
    assert_has(
        &stderr(&o),
        &["model.gltf", "/meshes/0/primitives/0/attributes/POSITION"],
    );
    assert!(!out.exists(), "nothing is written");
}
