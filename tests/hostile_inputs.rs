//! A catalogue of hostile inputs run through the `caustic` binary: every one
//! must end with exit code 2, one clear message naming the file and the
//! problem (with the line, column or byte offset where there is one), and no
//! output file. Zero-area faces are the exception: they are legal and must
//! render. The catalogue is mirrored in `docs/hostile-inputs.md` (a test
//! checks that every case is listed there).

mod common;

use common::cli::command;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A small, valid scene (8×8 pixels, one point light) without objects.
const BASE: &str = "[render]\nwidth = 8\nheight = 8\nspp = 1\n\
[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n\
[materials.white]\ndiffuse = [0.8, 0.8, 0.8]\n\
[[lights]]\ntype = \"point\"\nposition = [0, 3, 3]\nintensity = 20\n";

/// Lines of [`BASE`]: objects appended to it start on the next line.
const BASE_LINES: usize = 13;

/// A valid triangle in each format.
const OFF_TRI: &str = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
const OBJ_TRI: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
const PLY_ASCII_HEADER: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n\
property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

/// A binary little-endian PLY header for `vertices` float vertices and `faces` faces.
fn ply_binary_header(vertices: u64, faces: u64) -> Vec<u8> {
    format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {vertices}\nproperty float x\n\
         property float y\nproperty float z\nelement face {faces}\n\
         property list uchar int vertex_indices\nend_header\n"
    )
    .into_bytes()
}

/// A binary PLY triangle: header, three vertices, one face `[0, 1, i2]`.
fn ply_binary_tri(i2: i32) -> Vec<u8> {
    let mut b = ply_binary_header(3, 1);
    for v in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]] {
        for x in v {
            b.extend(x.to_le_bytes());
        }
    }
    b.push(3);
    for i in [0i32, 1, i2] {
        b.extend(i.to_le_bytes());
    }
    b
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

/// [`BASE`] plus one mesh object naming `file`; its `file` value is on line
/// `BASE_LINES + 3`, column 8.
fn mesh_scene(file: &str) -> String {
    format!("{BASE}[[objects]]\ntype = \"mesh\"\nfile = \"{file}\"\nmaterial = \"white\"\n")
}

/// [`BASE`] plus a sphere with the given extra TOML.
fn sphere_scene(extra: &str) -> String {
    format!("{BASE}[[objects]]\ntype = \"sphere\"\n{extra}material = \"white\"\n")
}

const SPHERE: &str = "center = [0, 0, 0]\nradius = 1\n";

/// What a case prepares in its temporary directory.
struct Run {
    /// The scene file given to `caustic render`.
    scene: PathBuf,
    /// Extra arguments (overrides).
    args: Vec<String>,
    /// Extra environment.
    env: Vec<(&'static str, String)>,
}

impl Run {
    fn scene(scene: PathBuf) -> Self {
        Run {
            scene,
            args: Vec::new(),
            env: Vec::new(),
        }
    }
    fn args(mut self, args: &[&str]) -> Self {
        self.args = args.iter().map(|s| s.to_string()).collect();
        self
    }
    fn env(mut self, key: &'static str, value: &str) -> Self {
        self.env.push((key, value.to_string()));
        self
    }
}

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// Writes `mesh` as `name` and a scene `scene.toml` that uses it.
fn with_mesh(dir: &Path, name: &str, mesh: impl AsRef<[u8]>) -> Run {
    write(dir, name, mesh);
    Run::scene(write(dir, "scene.toml", mesh_scene(name)))
}

fn scene_text(dir: &Path, text: &str) -> Run {
    Run::scene(write(dir, "scene.toml", text))
}

/// [`BASE`] plus a sphere whose material's `diffuse` is the image `file`;
/// the `file` value is on line 15.
fn texture_scene(file: &str) -> String {
    format!(
        "{BASE}[materials.tex]\ndiffuse = {{ type = \"image\", file = \"{file}\" }}\n\
         [[objects]]\ntype = \"sphere\"\n{SPHERE}material = \"tex\"\n"
    )
}

/// A Mitsuba scene: a `width` × 8 film (line 3) at `spp` samples (line
/// 4), a point light, then `body` from line 7 on.
fn mitsuba_text(width: &str, spp: &str, body: &str) -> String {
    format!(
        "<scene version=\"3.0.0\">\n\
         <sensor type=\"perspective\">\n\
         <film type=\"hdrfilm\"><integer name=\"width\" value=\"{width}\"/><integer name=\"height\" value=\"8\"/></film>\n\
         <sampler type=\"independent\"><integer name=\"sample_count\" value=\"{spp}\"/></sampler>\n\
         </sensor>\n\
         <emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"3\" z=\"3\"/></emitter>\n\
         {body}\n</scene>\n"
    )
}

/// [`mitsuba_text`] with an 8 × 8 film and 1 sample, written as `scene.xml`.
fn mitsuba(dir: &Path, body: &str) -> Run {
    Run::scene(write(dir, "scene.xml", mitsuba_text("8", "1", body)))
}

/// A `.serialized` file of one version-4 shape whose zlib stream holds
/// `data` after the flags (single precision), the name and the counts.
fn serialized(vertices: u64, triangles: u64, data: &[u8]) -> Vec<u8> {
    let mut body = 0x1000u32.to_le_bytes().to_vec();
    body.extend(b"m\0");
    body.extend(vertices.to_le_bytes());
    body.extend(triangles.to_le_bytes());
    body.extend(data);
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
    z.write_all(&body).unwrap();
    let mut file = vec![0x1C, 0x04, 4, 0];
    file.extend(z.finish().unwrap());
    file.extend(0u64.to_le_bytes());
    file.extend(1u32.to_le_bytes());
    file
}

/// A `.serialized` triangle.
fn serialized_tri() -> Vec<u8> {
    let mut data = Vec::new();
    for x in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        data.extend(x.to_le_bytes());
    }
    for i in [0u32, 1, 2] {
        data.extend(i.to_le_bytes());
    }
    serialized(3, 1, &data)
}

/// A shape reading `file` as `kind` (`obj`, `ply`, `serialized`), its
/// `filename` property right after the `<shape>` tag.
fn mitsuba_mesh(kind: &str, file: &str) -> String {
    format!("<shape type=\"{kind}\"><string name=\"filename\" value=\"{file}\"/></shape>")
}

/// A committed glTF model (`tests/data/gltf/`).
fn gltf_data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gltf").join(name)
}

/// `tests/data/gltf/textured_quad.gltf` changed by `change`, as `model.gltf`.
fn gltf_model(dir: &Path, change: impl FnOnce(&mut serde_json::Value)) -> Run {
    let mut doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(gltf_data("textured_quad.gltf")).unwrap()).unwrap();
    change(&mut doc);
    Run::scene(write(dir, "model.gltf", serde_json::to_vec(&doc).unwrap()))
}

fn base64_decode(text: &str) -> Vec<u8> {
    use base64::Engine;
    base64::engine::general_purpose::STANDARD.decode(text).unwrap()
}

/// A glTF orthographic camera of half extents `xmag` × `ymag`.
fn orthographic(xmag: f64, ymag: f64) -> serde_json::Value {
    serde_json::json!({
        "type": "orthographic",
        "orthographic": {"xmag": xmag, "ymag": ymag, "znear": 0.01, "zfar": 100}
    })
}

/// One hostile input.
struct Case {
    /// Identifier, listed in `docs/hostile-inputs.md`.
    name: &'static str,
    /// What the input is (the documentation's second column).
    what: &'static str,
    /// `None`: the input is legal and must render; `Some`: the substrings the
    /// error message must contain (exit code 2).
    expect: Option<&'static [&'static str]>,
    setup: fn(&Path) -> Run,
}

/// The mesh `file` value's place in [`mesh_scene`].
const MESH_AT: &str = "scene.toml:16:8: mesh of object `mesh#0`";
/// The sphere's extra keys start on this line in [`sphere_scene`].
const SPHERE_LINE: usize = BASE_LINES + 3;

fn cases() -> Vec<Case> {
    let _ = SPHERE_LINE;
    vec![
        // ------------------------------------------------------ truncated files
        Case {
            name: "ply-binary-truncated",
            what: "binary PLY cut 21 bytes into its data",
            expect: Some(&[MESH_AT, "m.ply: byte 169: the header announces 3 vertex, 1 face elements, which need at least 49 bytes, but only 21 bytes follow the header (wrong counts or truncated file)"]),
            setup: |d| with_mesh(d, "m.ply", &ply_binary_tri(2)[..190]),
        },
        Case {
            name: "ply-binary-truncated-gzip",
            what: "the same, gzip-compressed (no file size to check the counts against)",
            expect: Some(&["m.ply.gz: byte 190: truncated binary data: the file ends in vertex 1 of 3"]),
            setup: |d| with_mesh(d, "m.ply.gz", gzip(&ply_binary_tri(2)[..190])),
        },
        Case {
            name: "off-truncated",
            what: "OFF whose face lines are missing",
            expect: Some(&[MESH_AT, "m.off: line 6: unexpected end of file: face 0 of the 1 the header announces is missing"]),
            setup: |d| with_mesh(d, "m.off", "OFF\n3 1 0\n0.000 0.000 0.000\n1.000 0 0\n0 1 0\n"),
        },
        Case {
            name: "obj-truncated",
            what: "OBJ cut in the middle of a `v` record",
            expect: Some(&[MESH_AT, "m.obj: line 3: invalid OBJ: position parse error"]),
            setup: |d| with_mesh(d, "m.obj", "v 0 0 0\nv 1 0 0\nv 0 1"),
        },
        // --------------------------------------------------------- wrong counts
        Case {
            name: "off-more-data-than-counts",
            what: "OFF with one face more than its header announces",
            expect: Some(&["m.off: line 7: unexpected data after the last of the 1 faces the header announces"]),
            setup: |d| with_mesh(d, "m.off", format!("{OFF_TRI}3 0 2 1\n")),
        },
        Case {
            name: "ply-ascii-fewer-faces-than-counts",
            what: "ASCII PLY announcing 2 faces, holding 1",
            expect: Some(&["m.ply: line 16: unexpected end of file in face 1 of 2"]),
            setup: |d| {
                let text = PLY_ASCII_HEADER.replace("element face 1", "element face 2")
                    + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n           \n         \n";
                with_mesh(d, "m.ply", text)
            },
        },
        Case {
            name: "off-face-with-two-vertices",
            what: "OFF face with 2 vertices",
            expect: Some(&["m.off: line 6: face 0 has 2 vertices; a face needs at least 3"]),
            setup: |d| with_mesh(d, "m.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1   \n"),
        },
        // ------------------------------------------- negative or huge numbers
        Case {
            name: "off-negative-count",
            what: "OFF vertex count −3",
            expect: Some(&["m.off: line 2: negative vertex count -3"]),
            setup: |d| with_mesh(d, "m.off", "OFF\n-3 1 0\n0 0 0\n"),
        },
        Case {
            name: "off-10e12-vertices",
            what: "OFF header announcing 10^12 vertices",
            expect: Some(&["m.off: line 2: the header announces 1000000000000 vertices, more than the limit"]),
            setup: |d| with_mesh(d, "m.off", "OFF\n1000000000000 1 0\n0 0 0\n"),
        },
        Case {
            name: "ply-10e12-vertices",
            what: "PLY header announcing 10^12 vertices",
            expect: Some(&["m.ply: line 3: element 'vertex' announces 1000000000000 items, more than the limit"]),
            setup: |d| with_mesh(d, "m.ply", ply_binary_header(1_000_000_000_000, 1)),
        },
        Case {
            name: "off-coordinate-1e39",
            what: "OFF coordinate 1e39 (overflows f32)",
            expect: Some(&["m.off: line 3: vertex 0 has a non-finite value (inf)"]),
            setup: |d| with_mesh(d, "m.off", "OFF\n3 1 0\n1e39 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
        },
        Case {
            name: "ply-negative-list-length",
            what: "PLY face list of length −3",
            expect: Some(&["m.ply: line 13: face 0 of 1 has -3 vertices; a face needs at least 3"]),
            setup: |d| with_mesh(d, "m.ply", PLY_ASCII_HEADER.to_string() + "0 0 0\n1 0 0\n0 1 0\n-3 0 1 2\n"),
        },
        // ------------------------------------------------------- NaN and inf
        Case {
            name: "off-nan-coordinate",
            what: "OFF coordinate `nan`",
            expect: Some(&["m.off: line 4: vertex 1 has a non-finite value (NaN)"]),
            setup: |d| with_mesh(d, "m.off", "OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n"),
        },
        Case {
            name: "ply-binary-nan-coordinate",
            what: "binary PLY coordinate NaN",
            expect: Some(&["m.ply: byte 193: vertex 1 of 3 has a non-finite value (NaN)"]),
            setup: |d| {
                let mut b = ply_binary_tri(2);
                let header = ply_binary_header(3, 1).len();
                b[header + 16..header + 20].copy_from_slice(&f32::NAN.to_le_bytes());
                with_mesh(d, "m.ply", b)
            },
        },
        Case {
            name: "obj-inf-coordinate",
            what: "OBJ coordinate `inf`",
            expect: Some(&["m.obj: vertex 2 (counting from 0 in file order) has a non-finite coordinate"]),
            setup: |d| with_mesh(d, "m.obj", "v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n"),
        },
        Case {
            name: "scene-nan-radius",
            what: "scene `radius = nan` (TOML literal)",
            expect: Some(&["scene.toml:17:10: `radius` is NaN: numbers must be finite"]),
            setup: |d| scene_text(d, &sphere_scene("center = [0, 0, 0]\nradius = nan\n")),
        },
        Case {
            name: "scene-inf-position",
            what: "scene camera `position = [inf, 0, 5]`",
            expect: Some(&["scene.toml:6:12: `position` is infinite: numbers must be finite"]),
            setup: |d| scene_text(d, &BASE.replace("position = [0, 0, 5]", "position = [inf, 0, 5]")),
        },
        // ------------------------------------------------ indices out of range
        Case {
            name: "off-index-out-of-range",
            what: "OFF face index 3 with 3 vertices",
            expect: Some(&["m.off: line 6: face 0 uses vertex index 3, but there are only 3 vertices"]),
            setup: |d| with_mesh(d, "m.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"),
        },
        Case {
            name: "off-negative-index",
            what: "OFF face index −1",
            expect: Some(&["m.off: line 6: face 0 uses vertex index -1"]),
            setup: |d| with_mesh(d, "m.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n"),
        },
        Case {
            name: "ply-binary-index-out-of-range",
            what: "binary PLY face index 99",
            expect: Some(&["m.ply: byte 218: face 0 of 1 uses vertex index 99, but there are only 3 vertices"]),
            setup: |d| with_mesh(d, "m.ply", ply_binary_tri(99)),
        },
        Case {
            name: "obj-index-out-of-range",
            what: "OBJ face index 9 with 3 vertices",
            expect: Some(&["m.obj: line 4: invalid OBJ"]),
            setup: |d| with_mesh(d, "m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"),
        },
        // ------------------------------------------- zero-area faces (legal)
        Case {
            name: "zero-area-faces-render",
            what: "OFF with repeated-vertex and collinear (zero-area) faces",
            expect: None,
            setup: |d| {
                // A proper triangle plus two degenerate ones (repeated and collinear vertices).
                let off = "OFF\n4 3 0\n-1 -1 0\n1 -1 0\n0 1 0\n2 -1 0\n3 0 1 2\n3 0 0 1\n3 0 1 3\n";
                with_mesh(d, "m.off", off)
            },
        },
        // --------------------------------------------------------- not UTF-8
        Case {
            name: "scene-not-utf8",
            what: "scene with bytes 0xFF 0xFE",
            expect: Some(&["scene.toml:2:9: the scene file is not valid UTF-8 text"]),
            setup: |d| {
                let mut b = b"[render]\nwidth = ".to_vec();
                b.extend([0xff, 0xfe, b'\n']);
                Run::scene(write(d, "scene.toml", b))
            },
        },
        Case {
            name: "off-not-utf8",
            what: "OFF with bytes 0xFF 0xFE as a coordinate",
            expect: Some(&["m.off: line 3: vertex 0: expected a number, found '\u{fffd}\u{fffd}'"]),
            setup: |d| with_mesh(d, "m.off", b"OFF\n3 1 0\n\xff\xfe 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
        },
        Case {
            name: "obj-not-utf8",
            what: "OBJ with an invalid UTF-8 sequence",
            expect: Some(&["m.obj: line 2: not UTF-8 text (a binary file named .obj?)"]),
            setup: |d| with_mesh(d, "m.obj", b"v 0 0 0\nv \xc3\x28 0 0\n"),
        },
        // ------------------------------------- not a regular file, or itself
        Case {
            name: "scene-is-directory",
            what: "scene path is a directory",
            expect: Some(&["sub: is a directory, not a scene file"]),
            setup: |d| {
                std::fs::create_dir(d.join("sub")).unwrap();
                Run::scene(d.join("sub"))
            },
        },
        Case {
            name: "mesh-is-directory",
            what: "mesh path is a directory",
            expect: Some(&[MESH_AT, "dir.off: is a directory, not a mesh file"]),
            setup: |d| {
                std::fs::create_dir(d.join("dir.off")).unwrap();
                Run::scene(write(d, "scene.toml", mesh_scene("dir.off")))
            },
        },
        Case {
            name: "mesh-is-the-scene-itself",
            what: "scene `self.off` naming itself as its mesh",
            expect: Some(&["self.off:16:8: mesh of object `mesh#0`", "self.off: line 1: the vertex count '[render]' is not an integer"]),
            setup: |d| Run::scene(write(d, "self.off", mesh_scene("self.off"))),
        },
        Case {
            name: "mesh-is-scene-toml",
            what: "mesh `file` naming the scene file `scene.toml`",
            expect: Some(&[MESH_AT, "unknown mesh format: expected a .off, .obj or .ply file"]),
            setup: |d| Run::scene(write(d, "scene.toml", mesh_scene("scene.toml"))),
        },
        Case {
            name: "mesh-is-dev-zero",
            what: "mesh `zero.ply`, a symlink to /dev/zero",
            expect: Some(&[MESH_AT, "zero.ply: is not a regular file"]),
            setup: |d| {
                std::os::unix::fs::symlink("/dev/zero", d.join("zero.ply")).unwrap();
                Run::scene(write(d, "scene.toml", mesh_scene("zero.ply")))
            },
        },
        Case {
            name: "mesh-is-fifo",
            what: "mesh `pipe.off`, a FIFO (would block forever if opened)",
            expect: Some(&[MESH_AT, "pipe.off: is not a regular file"]),
            setup: |d| {
                let ok = Command::new("mkfifo").arg(d.join("pipe.off")).status().unwrap();
                assert!(ok.success(), "mkfifo failed");
                Run::scene(write(d, "scene.toml", mesh_scene("pipe.off")))
            },
        },
        Case {
            name: "mesh-missing",
            what: "mesh file that does not exist",
            expect: Some(&[MESH_AT, "nothere.off: No such file or directory"]),
            setup: |d| Run::scene(write(d, "scene.toml", mesh_scene("nothere.off"))),
        },
        Case {
            name: "scene-missing",
            what: "scene file that does not exist",
            expect: Some(&["nothere.toml: cannot read the scene file: No such file or directory"]),
            setup: |d| Run::scene(d.join("nothere.toml")),
        },
        // -------------------------------------------------------- empty files
        Case {
            name: "off-empty",
            what: "empty OFF file",
            expect: Some(&[MESH_AT, "m.off: line 1: empty file: no OFF header or counts"]),
            setup: |d| with_mesh(d, "m.off", ""),
        },
        Case {
            name: "ply-empty",
            what: "empty PLY file",
            expect: Some(&[MESH_AT, "m.ply: line 1: not a PLY file: the first line must be 'ply'"]),
            setup: |d| with_mesh(d, "m.ply", ""),
        },
        Case {
            name: "scene-empty",
            what: "empty scene file",
            expect: Some(&["scene.toml:1:1: missing field `camera`"]),
            setup: |d| scene_text(d, ""),
        },
        // ------------------------------------------------------- gzip bombs
        Case {
            name: "gzip-bomb-ascii",
            what: "ASCII PLY header + 64 MiB of zero bytes, gzipped (64 KiB)",
            expect: Some(&["m.ply.gz: line 10: a token longer than 64 bytes"]),
            setup: |d| {
                // 64 MiB of zero bytes after the header compress to ~64 KiB.
                let mut b = PLY_ASCII_HEADER.as_bytes().to_vec();
                b.resize(b.len() + (64 << 20), 0);
                with_mesh(d, "m.ply.gz", gzip(&b))
            },
        },
        Case {
            name: "gzip-bomb-binary-counts",
            what: "binary PLY.gz announcing 2×10^8 vertices, 64 MiB of zeros, `CAUSTIC_MEMORY_LIMIT=1G`",
            expect: Some(&[
                "m.ply.gz: byte 177: 200000000 vertices and 1 faces need about 4.470 GiB of memory",
                "(24 bytes per vertex, 112 per triangle with its KD-tree), 1.000 GiB allowed by CAUSTIC_MEMORY_LIMIT",
            ]),
            setup: |d| {
                let mut b = ply_binary_header(200_000_000, 1);
                b.resize(b.len() + (64 << 20), 0);
                with_mesh(d, "m.ply.gz", gzip(&b)).env("CAUSTIC_MEMORY_LIMIT", "1G")
            },
        },
        // ------------------------------------------- absurd resolution or spp
        Case {
            name: "scene-width-out-of-range",
            what: "scene `width = 1000000`",
            expect: Some(&["scene.toml:2:9: `width` = 1000000 is out of range: it must be in 1..=65536"]),
            setup: |d| scene_text(d, &BASE.replace("width = 8", "width = 1000000")),
        },
        Case {
            name: "scene-film-too-large",
            what: "scene 65536×65536",
            expect: Some(&["scene.toml:2:9: 65536×65536 pixels need 256.0 GiB of film", "more than the 16 GiB limit"]),
            setup: |d| scene_text(d, &BASE.replace("width = 8\nheight = 8", "width = 65536\nheight = 65536")),
        },
        Case {
            name: "scene-spp-absurd",
            what: "scene 4096×4096 at `spp = 1000000`",
            expect: Some(&["scene.toml:4:7:", "4096×4096 pixels × 1000000 spp", "more than the limit of 2^40"]),
            setup: |d| {
                scene_text(d, &BASE.replace("width = 8\nheight = 8\nspp = 1", "width = 4096\nheight = 4096\nspp = 1000000"))
            },
        },
        Case {
            name: "scene-spp-negative",
            what: "scene `spp = -1`",
            expect: Some(&["scene.toml:4:7: invalid value: integer `-1`, expected u32"]),
            setup: |d| scene_text(d, &BASE.replace("spp = 1", "spp = -1")),
        },
        Case {
            name: "cli-width-override-absurd",
            what: "`--width 65536 --height 65536`",
            expect: Some(&["scene.toml: with the command-line overrides: 65536×65536 pixels need 256.0 GiB of film"]),
            setup: |d| scene_text(d, BASE).args(&["--width", "65536", "--height", "65536"]),
        },
        Case {
            name: "cli-spp-override-absurd",
            what: "`--width 2048 --height 2048 --spp 1000000`",
            expect: Some(&["with the command-line overrides: 2048×2048 pixels × 1000000 spp"]),
            setup: |d| scene_text(d, BASE).args(&["--width", "2048", "--height", "2048", "--spp", "1000000"]),
        },
        Case {
            name: "cli-width-zero",
            what: "`--width 0`",
            expect: Some(&["with the command-line overrides: 0×8 pixels, 1 spp: width and height must be in 1..=65536"]),
            setup: |d| scene_text(d, BASE).args(&["--width", "0"]),
        },
        // ----------------------------------------------- memory before allocation
        Case {
            name: "film-exceeds-memory-limit",
            what: "1024×1024 film with `CAUSTIC_MEMORY_LIMIT=32M`",
            expect: Some(&["scene.toml:2:9: 1024×1024 pixels need 64.0 MiB of film (64 bytes per pixel), 32.0 MiB allowed by CAUSTIC_MEMORY_LIMIT"]),
            setup: |d| {
                scene_text(d, &BASE.replace("width = 8\nheight = 8", "width = 1024\nheight = 1024"))
                    .env("CAUSTIC_MEMORY_LIMIT", "32M")
            },
        },
        Case {
            name: "mesh-exceeds-memory-limit",
            what: "a triangle with `CAUSTIC_MEMORY_LIMIT=100`",
            expect: Some(&[MESH_AT, "m.off: line 2: 3 vertices and 1 faces need about 184 bytes of memory (24 bytes per vertex, 112 per triangle with its KD-tree), 100 bytes allowed by CAUSTIC_MEMORY_LIMIT"]),
            setup: |d| {
                // A 1×1 film (64 bytes) fits the 100-byte limit; the mesh does not.
                write(d, "m.off", OFF_TRI);
                let text = mesh_scene("m.off").replace("width = 8\nheight = 8", "width = 1\nheight = 1");
                scene_text(d, &text).env("CAUSTIC_MEMORY_LIMIT", "100")
            },
        },
        Case {
            name: "memory-limit-unparsable",
            what: "`CAUSTIC_MEMORY_LIMIT=lots`",
            expect: Some(&["CAUSTIC_MEMORY_LIMIT=\"lots\" is not a byte count"]),
            setup: |d| scene_text(d, BASE).env("CAUSTIC_MEMORY_LIMIT", "lots"),
        },
        // ------------------------------------------------ geometry and camera
        Case {
            name: "scene-negative-radius",
            what: "sphere `radius = -1`",
            expect: Some(&["scene.toml:17:10: sphere `radius` = -1 must be > 0"]),
            setup: |d| scene_text(d, &sphere_scene("center = [0, 0, 0]\nradius = -1\n")),
        },
        Case {
            name: "scene-camera-degenerate",
            what: "camera `look_at` = `position`",
            expect: Some(&["scene.toml:7:11: `look_at` equals the camera `position`"]),
            setup: |d| scene_text(d, &BASE.replace("look_at = [0, 0, 0]", "look_at = [0, 0, 5]")),
        },
        Case {
            name: "scene-camera-up-parallel",
            what: "camera looking straight down the default `up`",
            expect: Some(&["scene.toml:7:11: the default `up` [0, 1, 0] is parallel to the viewing direction"]),
            setup: |d| scene_text(d, &BASE.replace("look_at = [0, 0, 0]", "look_at = [0, -3, 5]")),
        },
        // ------------------------------------------- keys, types, references
        Case {
            name: "scene-unknown-key",
            what: "`widht = 3` in `[render]`",
            expect: Some(&["scene.toml:5:1: unknown field `widht`"]),
            setup: |d| scene_text(d, &BASE.replace("spp = 1\n", "spp = 1\nwidht = 3\n")),
        },
        Case {
            name: "scene-wrong-type",
            what: "`width = \"eight\"`",
            expect: Some(&["scene.toml:2:9: invalid type: string \"eight\", expected u32"]),
            setup: |d| scene_text(d, &BASE.replace("width = 8", "width = \"eight\"")),
        },
        Case {
            name: "scene-missing-material",
            what: "object with `material = \"gold\"` (undefined)",
            expect: Some(&["scene.toml:18:12: unknown material `gold` (defined: `white`)"]),
            setup: |d| scene_text(d, &sphere_scene(SPHERE).replace("material = \"white\"", "material = \"gold\"")),
        },
        Case {
            name: "scene-deeply-nested-array",
            what: "an array nested 100 000 deep",
            expect: Some(&["scene.toml:14:84: recursion limit exceeded"]),
            setup: |d| {
                let depth = 100_000;
                scene_text(d, &format!("{BASE}x = {}{}\n", "[".repeat(depth), "]".repeat(depth)))
            },
        },
        Case {
            name: "scene-huge-array",
            what: "a 2-million-element array (4 MiB)",
            expect: Some(&["scene.toml:14:1: unknown field `x`"]),
            setup: |d| {
                let items = vec!["1"; 2_000_000].join(",");
                scene_text(d, &format!("{BASE}x = [{items}]\n"))
            },
        },
        Case {
            name: "scene-over-16-mib",
            what: "a 17 MiB scene file",
            expect: Some(&["scene.toml: the scene file is larger than 16777216 bytes"]),
            setup: |d| scene_text(d, &format!("{BASE}{}", "#".repeat(17 << 20))),
        },
        Case {
            name: "mesh-unknown-extension",
            what: "mesh `m.stl`",
            expect: Some(&[MESH_AT, "m.stl: unknown mesh format"]),
            setup: |d| with_mesh(d, "m.stl", OFF_TRI),
        },
        Case {
            name: "ply-no-vertex-indices",
            what: "PLY face element without `vertex_indices`",
            expect: Some(&[MESH_AT, "m.ply: the face element has no 'vertex_indices'"]),
            setup: |d| with_mesh(d, "m.ply", PLY_ASCII_HEADER.replace("vertex_indices", "corners") + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
        },
        // ------------------------------------------------------------ textures
        Case {
            name: "texture-missing",
            what: "an image texture whose file does not exist",
            expect: Some(&["scene.toml:15:", "texture `t.png`: cannot open"]),
            setup: |d| scene_text(d, &texture_scene("t.png")),
        },
        Case {
            name: "texture-not-an-image",
            what: "a text file named `t.png`",
            expect: Some(&["scene.toml:15:36: texture `t.png`: cannot decode", "Invalid PNG signature"]),
            setup: |d| {
                write(d, "t.png", "not an image");
                scene_text(d, &texture_scene("t.png"))
            },
        },
        Case {
            name: "texture-truncated-png",
            what: "a PNG cut in its pixel data",
            expect: Some(&["scene.toml:15:", "texture `t.png`: cannot decode"]),
            setup: |d| {
                let mut png = Vec::new();
                image::RgbImage::from_fn(64, 64, |x, y| image::Rgb([x as u8 * 4, y as u8 * 4, (x ^ y) as u8]))
                    .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
                    .unwrap();
                write(d, "t.png", &png[..png.len() / 2]);
                scene_text(d, &texture_scene("t.png"))
            },
        },
        Case {
            name: "texture-decompression-bomb",
            what: "a PNG header announcing 100000 × 100000 texels",
            expect: Some(&["scene.toml:15:", "texture `t.png`: refused", "textures are at most 32768×32768 texels"]),
            setup: |d| {
                write(d, "t.png", common::images::huge_png_header());
                scene_text(d, &texture_scene("t.png"))
            },
        },
        Case {
            name: "texture-unknown-name",
            what: "`diffuse = \"wood\"` with no `[textures.wood]`",
            expect: Some(&["scene.toml:15:11: `diffuse` names the texture `wood`, which `[textures]` does not define"]),
            setup: |d| {
                scene_text(
                    d,
                    &format!("{BASE}[materials.tex]\ndiffuse = \"wood\"\n[[objects]]\ntype = \"sphere\"\n{SPHERE}material = \"tex\"\n"),
                )
            },
        },
        Case {
            name: "normal-map-without-uvs",
            what: "a normal map on a mesh with no texture coordinates",
            expect: Some(&["scene.toml:19:12: material `tex` has a normal map, but mesh", "has no texture coordinates"]),
            setup: |d| {
                image::RgbImage::from_pixel(2, 2, image::Rgb([128, 128, 255]))
                    .save(d.join("n.png"))
                    .unwrap();
                write(d, "m.obj", OBJ_TRI);
                scene_text(
                    d,
                    &format!(
                        "{BASE}[materials.tex]\nnormal_map = {{ type = \"image\", file = \"n.png\" }}\n\
                         [[objects]]\ntype = \"mesh\"\nfile = \"m.obj\"\nmaterial = \"tex\"\n"
                    ),
                )
            },
        },
        Case {
            name: "stoff-missing-texture-coordinates",
            what: "STOFF vertex line without `s t`",
            expect: Some(&[MESH_AT, "m.off: line 3: vertex 0: STOFF needs finite texture coordinates"]),
            setup: |d| with_mesh(d, "m.off", "STOFF\n3 1 0\n0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n"),
        },
        Case {
            name: "ply-nan-texture-coordinate",
            what: "ASCII PLY with `u = nan`",
            expect: Some(&[MESH_AT, "m.ply: line 13: vertex 1 of 3 has a non-finite value (NaN)"]),
            setup: |d| {
                let header = PLY_ASCII_HEADER.replace("property float z\n", "property float z\nproperty float u\nproperty float v\n");
                with_mesh(d, "m.ply", header + "0 0 0 0 0\n1 0 0 nan 0\n0 1 0 0 1\n3 0 1 2\n")
            },
        },
        Case {
            name: "obj-valid-reference",
            what: "a valid OBJ triangle (control case)",
            expect: None,
            setup: |d| with_mesh(d, "m.obj", OBJ_TRI),
        },
        // ------------------------------------------------- Mitsuba XML scenes
        Case {
            name: "xml-malformed",
            what: "Mitsuba scene with an unclosed `<shape>`",
            expect: Some(&["scene.xml:8:1: not a valid XML file: expected 'shape' tag, not 'scene' at 8:1"]),
            setup: |d| mitsuba(d, "<shape type=\"sphere\">"),
        },
        Case {
            name: "xml-billion-laughs-dtd",
            what: "a DTD whose entities expand to 10^9 `lol`s (billion laughs)",
            expect: Some(&["scene.xml:2:1: not a valid XML file: a DTD (`<!DOCTYPE`) is not allowed (its entities could expand without bound)"]),
            setup: |d| {
                let mut dtd = String::from("<?xml version=\"1.0\"?>\n<!DOCTYPE scene [\n<!ENTITY l0 \"lol\">\n");
                for i in 1..10 {
                    dtd += &format!("<!ENTITY l{i} \"{}\">\n", format!("&l{};", i - 1).repeat(10));
                }
                dtd += "]>\n";
                let text = mitsuba_text("8", "1", "<shape type=\"sphere\"><string name=\"x\" value=\"&l9;\"/></shape>");
                Run::scene(write(d, "scene.xml", dtd + &text))
            },
        },
        Case {
            name: "xml-billion-laughs-defaults",
            what: "`<default>`s each naming the previous one ten times (10^10 bytes through `$`)",
            expect: Some(&["scene.xml:7:328: `$l5` makes the value longer than 1 MiB (parameters that repeat each other grow exponentially)"]),
            setup: |d| {
                let mut body = String::from("<default name=\"l0\" value=\"lol\"/>");
                for i in 1..11 {
                    body += &format!("<default name=\"l{i}\" value=\"{}\"/>", format!("$l{}", i - 1).repeat(10));
                }
                mitsuba(d, &(body + "<shape type=\"sphere\"><string name=\"x\" value=\"$l10\"/></shape>"))
            },
        },
        Case {
            name: "xml-include-cycle",
            what: "`a.xml` includes `b.xml`, which includes `a.xml`",
            expect: Some(&["b.xml:2:3: an include cycle: `", "a.xml` is already being read (a.xml → b.xml → a.xml)"]),
            setup: |d| {
                write(d, "a.xml", "<scene version=\"3.0.0\">\n  <include filename=\"b.xml\"/>\n</scene>\n");
                write(d, "b.xml", "<scene version=\"3.0.0\">\n  <include filename=\"a.xml\"/>\n</scene>\n");
                mitsuba(d, "<include filename=\"a.xml\"/>")
            },
        },
        Case {
            name: "xml-include-bomb",
            what: "14 files each including the next twice (32 766 includes)",
            expect: Some(&["i13.xml:1:24: more than 4096 <include>s in all (files including others several times each multiply)"]),
            setup: |d| {
                for i in 0..14 {
                    let next = format!("<include filename=\"i{}.xml\"/>", i + 1);
                    write(d, &format!("i{i}.xml"), format!("<scene version=\"3.0.0\">{next}{next}</scene>"));
                }
                write(d, "i14.xml", "<scene version=\"3.0.0\"/>");
                mitsuba(d, "<include filename=\"i0.xml\"/>")
            },
        },
        Case {
            name: "xml-include-missing",
            what: "`<include>` of a file that does not exist",
            expect: Some(&["scene.xml:7:1: cannot include: ", "nowhere.xml: cannot read the scene file: No such file or directory"]),
            setup: |d| mitsuba(d, "<include filename=\"nowhere.xml\"/>"),
        },
        Case {
            name: "xml-include-dev-zero",
            what: "`<include filename=\"/dev/zero\"/>`",
            expect: Some(&["scene.xml:7:1: cannot include: /dev/zero: the scene file is larger than 16777216 bytes"]),
            setup: |d| mitsuba(d, "<include filename=\"/dev/zero\"/>"),
        },
        Case {
            name: "xml-mesh-missing",
            what: "`<shape type=\"obj\">` naming a file that does not exist",
            expect: Some(&["scene.xml:7:19: mesh of object `obj@7:1`: ", "nowhere.obj: No such file or directory"]),
            setup: |d| mitsuba(d, &mitsuba_mesh("obj", "nowhere.obj")),
        },
        Case {
            name: "xml-ref-unknown-id",
            what: "`<ref id=\"nothing\"/>` with no object of that id",
            expect: Some(&["scene.xml:7:22: <ref id=\"nothing\">: no object has this id"]),
            setup: |d| mitsuba(d, "<shape type=\"sphere\"><ref id=\"nothing\"/></shape>"),
        },
        Case {
            name: "xml-ref-cycle",
            what: "a `twosided` BSDF `a` whose nested BSDF is `<ref id=\"a\"/>`",
            expect: Some(&["scene.xml:7:30: <ref id=\"a\"> is inside the object `a` it names (a reference cycle)"]),
            setup: |d| {
                mitsuba(d, "<bsdf type=\"twosided\" id=\"a\"><ref id=\"a\"/></bsdf><shape type=\"sphere\"><ref id=\"a\"/></shape>")
            },
        },
        Case {
            name: "xml-ref-chain-3000",
            what: "3000 `twosided` BSDFs, each referencing the next",
            expect: Some(&["scene.xml:37:32: objects nested more than 32 deep (each <ref> counted as a level)"]),
            setup: |d| {
                let mut body = String::new();
                for i in 0..3000 {
                    body += &format!("<bsdf type=\"twosided\" id=\"b{i}\"><ref id=\"b{}\"/></bsdf>\n", i + 1);
                }
                body += "<bsdf type=\"diffuse\" id=\"b3000\"/>\n<shape type=\"sphere\"><ref id=\"b0\"/></shape>";
                mitsuba(d, &body)
            },
        },
        Case {
            name: "xml-blend-bomb",
            what: "30 `blendbsdf`s, each blending the previous one with itself (2^30 BSDFs)",
            expect: Some(&["scene.xml:9:1: <bsdf type=\"blendbsdf\">: the material is made of more than 256 BSDFs (blends naming blends through <ref>s multiply)"]),
            setup: |d| {
                let mut body = String::from("<bsdf type=\"diffuse\" id=\"b0\"/>\n");
                for i in 1..=30 {
                    body += &format!("<bsdf type=\"blendbsdf\" id=\"b{i}\"><ref id=\"b{0}\"/><ref id=\"b{0}\"/></bsdf>\n", i - 1);
                }
                mitsuba(d, &(body + "<shape type=\"sphere\"><ref id=\"b30\"/></shape>"))
            },
        },
        Case {
            name: "xml-nested-30000-deep",
            what: "30 000 nested elements inside a shape",
            expect: Some(&["scene.xml:7:211: elements nested more than 64 deep"]),
            setup: |d| mitsuba(d, &format!("<shape type=\"sphere\">{}{}</shape>", "<a>".repeat(30_000), "</a>".repeat(30_000))),
        },
        Case {
            name: "xml-fov-is-a-string",
            what: "`<string name=\"fov\" value=\"x\"/>` on the sensor",
            expect: Some(&["scene.xml:2:28: `fov` of <sensor type=\"perspective\"> is a <string>; expected <float> or <integer>"]),
            setup: |d| {
                let text = mitsuba_text("8", "1", "").replace("<sensor type=\"perspective\">", "<sensor type=\"perspective\"><string name=\"fov\" value=\"x\"/>");
                Run::scene(write(d, "scene.xml", text))
            },
        },
        Case {
            name: "xml-width-is-a-float",
            what: "`<float name=\"width\" value=\"abc\"/>` on the film",
            expect: Some(&["scene.xml:3:22: `width` of <film type=\"hdrfilm\"> is a <float>; expected <integer>"]),
            setup: |d| {
                let text = mitsuba_text("8", "1", "").replace("<integer name=\"width\" value=\"8\"/>", "<float name=\"width\" value=\"abc\"/>");
                Run::scene(write(d, "scene.xml", text))
            },
        },
        Case {
            name: "xml-radius-not-a-number",
            what: "`<float name=\"radius\" value=\"abc\"/>` on a sphere",
            expect: Some(&["scene.xml:7:22: `radius` = `abc` is not a finite number"]),
            setup: |d| mitsuba(d, "<shape type=\"sphere\"><float name=\"radius\" value=\"abc\"/></shape>"),
        },
        Case {
            name: "xml-width-1e9",
            what: "film `width` 10^9",
            expect: Some(&["scene.xml:3:1: <film type=\"hdrfilm\">: `width` = 1000000000: it must be in 1‥65536"]),
            setup: |d| Run::scene(write(d, "scene.xml", mitsuba_text("1000000000", "1", "<shape type=\"sphere\"/>"))),
        },
        Case {
            name: "xml-spp-1e12",
            what: "sampler `sample_count` 10^12",
            expect: Some(&["scene.xml:4:1: <sampler type=\"independent\">: `sample_count` = 1000000000000: it must be in 1‥1048576"]),
            setup: |d| Run::scene(write(d, "scene.xml", mitsuba_text("8", "1000000000000", "<shape type=\"sphere\"/>"))),
        },
        Case {
            name: "xml-define-malformed",
            what: "`-D res=abc` for `<integer name=\"width\" value=\"$res\"/>`",
            expect: Some(&["scene.xml:3:22: `width` = `abc` is not an integer"]),
            setup: |d| Run::scene(write(d, "scene.xml", mitsuba_text("$res", "1", "<shape type=\"sphere\"/>"))).args(&["-D", "res=abc"]),
        },
        Case {
            name: "serialized-truncated",
            what: "a `.serialized` triangle cut in its zlib stream",
            expect: Some(&["scene.xml:7:26: mesh of object `serialized@7:1`: ", "m.serialized: the last 4 bytes announce 1204971900 shapes, whose offsets do not fit the file (a truncated file?)"]),
            setup: |d| {
                let tri = serialized_tri();
                write(d, "m.serialized", &tri[..tri.len() / 2]);
                mitsuba(d, &mitsuba_mesh("serialized", "m.serialized"))
            },
        },
        Case {
            name: "serialized-zlib-bomb",
            what: "a 64 KiB `.serialized` shape: 64 MiB of zeros, zlib-compressed, announcing 2^27 vertices (1.5 GiB)",
            expect: Some(&["scene.xml:7:26: mesh of object `serialized@7:1`: ", "m.serialized: byte 4: 134217728 vertices and 1 triangles need 1610612748 bytes of data, more than the shape's 65209 compressed bytes can inflate to (at most 1032 × as many): a truncated file, wrong counts or a zlib bomb"]),
            setup: |d| {
                write(d, "m.serialized", serialized(1 << 27, 1, &vec![0; 64 << 20]));
                mitsuba(d, &mitsuba_mesh("serialized", "m.serialized"))
            },
        },
        Case {
            name: "xml-serialized-valid-reference",
            what: "a valid `.serialized` triangle in a Mitsuba scene (control case)",
            expect: None,
            setup: |d| {
                write(d, "m.serialized", serialized_tri());
                mitsuba(d, &mitsuba_mesh("serialized", "m.serialized"))
            },
        },
        Case {
            name: "gltf-accessor-out-of-range",
            what: "glTF `POSITION` naming accessor 99 of 4",
            expect: Some(&["model.gltf: /meshes/0/primitives/0/attributes/POSITION: accessor 99 out of range"]),
            setup: |d| gltf_model(d, |m| m["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 99.into()),
        },
        Case {
            name: "gltf-accessor-offset-past-view",
            what: "glTF accessor `byteOffset` 1000 in a 48-byte buffer view",
            expect: Some(&["model.gltf: /meshes/0/primitives/0/attributes/POSITION (accessor 0): 4 elements", "buffer view 0 has 48"]),
            setup: |d| gltf_model(d, |m| m["accessors"][0]["byteOffset"] = 1000.into()),
        },
        Case {
            name: "gltf-wrong-component-type",
            what: "glTF `POSITION` of unsigned bytes",
            expect: Some(&["model.gltf: /meshes/0/primitives/0/attributes/POSITION: POSITION: accessor 0 has component type UNSIGNED_BYTE; glTF allows FLOAT"]),
            setup: |d| gltf_model(d, |m| m["accessors"][0]["componentType"] = 5121.into()),
        },
        Case {
            name: "gltf-wrong-component-count",
            what: "glTF `POSITION` of type `VEC2`",
            expect: Some(&["model.gltf: /meshes/0/primitives/0/attributes/POSITION: POSITION needs 3 components"]),
            setup: |d| gltf_model(d, |m| m["accessors"][0]["type"] = "VEC2".into()),
        },
        Case {
            name: "gltf-absurd-count",
            what: "glTF accessor `count` 4 × 10^9",
            expect: Some(&["model.gltf: /accessors/0/count: 4000000000 elements: more than the limit"]),
            setup: |d| gltf_model(d, |m| m["accessors"][0]["count"] = 4_000_000_000u64.into()),
        },
        Case {
            name: "gltf-truncated-bin",
            what: "glTF buffer in `model.bin` cut to half its `byteLength`",
            expect: Some(&["model.gltf: /buffers/0/byteLength: 142 bytes, but", "model.bin has only 71: truncated"]),
            setup: |d| {
                let run = gltf_model(d, |_| {});
                let mut doc: serde_json::Value = serde_json::from_slice(&std::fs::read(&run.scene).unwrap()).unwrap();
                let uri = doc["buffers"][0]["uri"].as_str().unwrap().to_string();
                let bytes = base64_decode(uri.split_once(',').unwrap().1);
                write(d, "model.bin", &bytes[..bytes.len() / 2]);
                doc["buffers"][0]["uri"] = "model.bin".into();
                Run::scene(write(d, "model.gltf", serde_json::to_vec(&doc).unwrap()))
            },
        },
        Case {
            name: "gltf-truncated-glb",
            what: "a GLB file cut in its binary chunk",
            expect: Some(&["model.glb: truncated GLB file: the header announces"]),
            setup: |d| {
                let glb = std::fs::read(gltf_data("emissive_quad.glb")).unwrap();
                Run::scene(write(d, "model.glb", &glb[..glb.len() - 40]))
            },
        },
        Case {
            name: "gltf-bad-data-uri",
            what: "glTF buffer data URI that is not base64",
            expect: Some(&["model.gltf: /buffers/0/uri: the data URI does not decode as base64"]),
            setup: |d| gltf_model(d, |m| m["buffers"][0]["uri"] = "data:application/octet-stream;base64,@@@".into()),
        },
        Case {
            name: "gltf-orthographic-zero-xmag",
            what: "glTF orthographic camera with `xmag` 0",
            expect: Some(&["model.gltf: /cameras/0/orthographic/xmag: 0: must be a finite number > 0"]),
            setup: |d| gltf_model(d, |m| m["cameras"][0] = orthographic(0.0, 1.0)),
        },
        Case {
            name: "gltf-orthographic-negative-ymag",
            what: "glTF orthographic camera with `ymag` −1",
            expect: Some(&["model.gltf: /cameras/0/orthographic/ymag: -1: must be a finite number > 0"]),
            setup: |d| gltf_model(d, |m| m["cameras"][0] = orthographic(1.0, -1.0)),
        },
        Case {
            name: "gltf-orthographic-infinite-xmag",
            what: "glTF orthographic camera with `xmag` 1e39 (infinite in single precision)",
            expect: Some(&["model.gltf: /cameras/0/orthographic/xmag: inf: must be a finite number > 0"]),
            setup: |d| gltf_model(d, |m| m["cameras"][0] = orthographic(1e39, 1.0)),
        },
        Case {
            name: "gltf-missing-image",
            what: "glTF image `missing.png` that does not exist",
            expect: Some(&["model.gltf: /images/0:", "missing.png: cannot open"]),
            setup: |d| gltf_model(d, |m| m["images"][0]["uri"] = "missing.png".into()),
        },
        Case {
            name: "gltf-image-decompression-bomb",
            what: "glTF image: a PNG header announcing 100000 × 100000 texels",
            expect: Some(&["model.gltf: /images/0:", "bomb.png: refused", "textures are at most 32768×32768 texels"]),
            setup: |d| {
                write(d, "bomb.png", common::images::huge_png_header());
                gltf_model(d, |m| m["images"][0]["uri"] = "bomb.png".into())
            },
        },
        Case {
            name: "gltf-uri-outside-folder",
            what: "glTF buffer URI `../outside.bin` (the file exists)",
            expect: Some(&["model.gltf: /buffers/0/uri: `../outside.bin` leads outside the model's folder", "--allow-outside-files"]),
            setup: |d| {
                let sub = d.join("model");
                std::fs::create_dir(&sub).unwrap();
                write(d, "outside.bin", vec![0u8; 200]);
                let run = gltf_model(&sub, |m| m["buffers"][0]["uri"] = "../outside.bin".into());
                Run::scene(run.scene)
            },
        },
        Case {
            name: "gltf-requires-draco",
            what: "glTF `extensionsRequired: [\"KHR_draco_mesh_compression\"]`",
            expect: Some(&["model.gltf: /extensionsRequired/0: the model requires the extension `KHR_draco_mesh_compression`, which caustic does not implement"]),
            setup: |d| {
                gltf_model(d, |m| {
                    m["extensionsUsed"] = serde_json::json!(["KHR_draco_mesh_compression"]);
                    m["extensionsRequired"] = serde_json::json!(["KHR_draco_mesh_compression"]);
                })
            },
        },
        Case {
            name: "gltf-valid-reference",
            what: "a valid glTF textured quad (control case)",
            expect: None,
            setup: |d| gltf_model(d, |_| {}),
        },
    ]
}

struct Outcome {
    code: Option<i32>,
    stderr: String,
    output_exists: bool,
}

fn run(case: &Case) -> Outcome {
    let dir = tempfile::tempdir().unwrap();
    let run = (case.setup)(dir.path());
    let out_dir = dir.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let png = out_dir.join("image.png");
    let mut cmd = command(&["render"]);
    cmd.arg(&run.scene)
        .arg("-o")
        .arg(&png)
        .args(["--accel", "kdtree", "--quiet", "--threads", "1"])
        .args(&run.args)
        .env_remove("CAUSTIC_MEMORY_LIMIT");
    for (k, v) in &run.env {
        cmd.env(k, v);
    }
    let out = cmd.output().unwrap();
    Outcome {
        code: out.status.code(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
        output_exists: std::fs::read_dir(&out_dir).unwrap().next().is_some(),
    }
}

#[test]
fn hostile_inputs_fail_cleanly() {
    let cases = cases();
    // Run the cases on two threads: each is a separate process.
    let results: Vec<(usize, Outcome)> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..2)
            .map(|t| {
                let cases = &cases;
                s.spawn(move || {
                    (t..cases.len())
                        .step_by(2)
                        .map(|i| (i, run(&cases[i])))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles.into_iter().flat_map(|h| h.join().unwrap()).collect()
    });
    let mut failures = Vec::new();
    for (i, o) in results {
        let case = &cases[i];
        match case.expect {
            None => {
                if o.code != Some(0) || !o.output_exists {
                    failures.push(format!(
                        "{}: expected a render, got {:?}: {}",
                        case.name, o.code, o.stderr
                    ));
                }
            }
            Some(needles) => {
                let lines: Vec<&str> = o.stderr.lines().collect();
                let missing: Vec<&&str> = needles.iter().filter(|n| !o.stderr.contains(**n)).collect();
                if o.code != Some(2) || !missing.is_empty() || o.output_exists || lines.len() != 1 {
                    failures.push(format!(
                        "{}: exit {:?}, output written: {}, missing {:?} in:\n{}",
                        case.name, o.code, o.output_exists, missing, o.stderr
                    ));
                }
                if o.stderr.contains("panicked") {
                    failures.push(format!("{}: panicked", case.name));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} case(s) failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn catalogue_has_at_least_30_distinct_cases() {
    let cases = cases();
    let mut names: Vec<&str> = cases.iter().map(|c| c.name).collect();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), cases.len(), "duplicate case names");
    assert!(cases.iter().filter(|c| c.expect.is_some()).count() >= 30);
}

/// The catalogue as Markdown: `docs/hostile-inputs.md` is this text.
fn catalogue_markdown() -> String {
    let cases = cases();
    let failing = cases.iter().filter(|c| c.expect.is_some()).count();
    let mut md = format!(
        "# Hostile inputs\n\n\
         Generated from `tests/hostile_inputs.rs` (regenerate with\n\
         `UPDATE_HOSTILE_DOC=1 cargo test --test hostile_inputs catalogue_is_documented`).\n\n\
         Each case runs `caustic render SCENE -o out/image.png --accel kdtree` on inputs\n\
         generated in a temporary directory. {failing} of the {} cases must end with exit\n\
         code 2, a one-line message containing every quoted fragment (`…` separates\n\
         fragments; the scene and mesh paths are prefixed by the temporary directory),\n\
         and no output file; the others are legal and must render. Zero-area faces\n\
         are legal: they are kept (never hit by the watertight test) and normals\n\
         ignore them.\n\n\
         | Case | Input | Expected |\n|---|---|---|\n",
        cases.len()
    );
    for c in &cases {
        let expected = match c.expect {
            None => "loads and renders (exit 0, image written)".to_string(),
            Some(needles) => needles
                .iter()
                .map(|n| format!("`{}`", n.replace('|', "\\|").replace('`', "'")))
                .collect::<Vec<_>>()
                .join(" … "),
        };
        md += &format!("| `{}` | {} | {} |\n", c.name, c.what.replace('|', "\\|"), expected);
    }
    md
}

#[test]
fn catalogue_is_documented() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/hostile-inputs.md");
    let want = catalogue_markdown();
    if std::env::var_os("UPDATE_HOSTILE_DOC").is_some() {
        std::fs::write(&path, &want).unwrap();
    }
    let have = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        have == want,
        "docs/hostile-inputs.md is out of date: run UPDATE_HOSTILE_DOC=1 cargo test --test hostile_inputs catalogue_is_documented"
    );
}
