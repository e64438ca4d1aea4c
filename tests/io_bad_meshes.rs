//! Malformed and hostile mesh files: each must give an error naming the file,
//! the place and the problem — never a panic, a hang or a giant allocation.

use caustic::io::{load_mesh, load_mesh_with, LoadLimits, MeshError, Place};
use std::io::Write;
use std::path::{Path, PathBuf};

struct Dir(tempfile::TempDir);

impl Dir {
    fn new() -> Self {
        Self(tempfile::tempdir().unwrap())
    }
    fn write(&self, name: &str, bytes: &[u8]) -> PathBuf {
        let path = self.0.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        path
    }
    fn write_gz(&self, name: &str, bytes: &[u8]) -> PathBuf {
        let path = self.0.path().join(name);
        let mut enc = flate2::write::GzEncoder::new(std::fs::File::create(&path).unwrap(), flate2::Compression::fast());
        enc.write_all(bytes).unwrap();
        enc.finish().unwrap();
        path
    }
}

/// Loads `path`, expecting an error whose text names the file and contains `needle`.
fn fails_with(path: &Path, needle: &str) -> MeshError {
    check(path, load_mesh(path), needle)
}

fn check(path: &Path, result: Result<caustic::scene::Mesh, MeshError>, needle: &str) -> MeshError {
    let e = match result {
        Ok(m) => panic!(
            "{} loaded ({} triangles), expected an error with {needle:?}",
            path.display(),
            m.triangles.len()
        ),
        Err(e) => e,
    };
    let text = e.to_string();
    assert!(
        text.starts_with(&path.display().to_string()),
        "no file name in {text:?}"
    );
    assert!(text.contains(needle), "{text:?} does not contain {needle:?}");
    e
}

const PLY_TRI_HEADER: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n\
    property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

#[test]
fn off_header_counts_exceed_the_file_size() {
    let d = Dir::new();
    let p = d.write("a.off", b"OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n");
    let e = fails_with(&p, "the header announces 4 vertices and 1 faces");
    assert!(e.message.contains("but the file has only 28 bytes"), "{e}");
    assert_eq!(e.place, Some(Place::Line(2)));
}

#[test]
fn off_missing_face_line() {
    let d = Dir::new();
    // Four vertex lines are present (the face line is read as the fourth
    // vertex), so the face is missing at the end of the file.
    let p = d.write(
        "a.off",
        b"OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n# padding to pass the size check\n",
    );
    fails_with(
        &p,
        "unexpected end of file: face 0 of the 1 the header announces is missing",
    );
}

#[test]
fn off_more_faces_than_announced() {
    let d = Dir::new();
    let p = d.write("a.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 2 1 0\n");
    let e = fails_with(&p, "unexpected data after the last of the 1 faces");
    assert_eq!(e.place, Some(Place::Line(7)));
}

#[test]
fn off_index_out_of_range_and_negative() {
    let d = Dir::new();
    let p = d.write("a.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n");
    let e = fails_with(&p, "face 0 uses vertex index 5, but there are only 3 vertices");
    assert_eq!(e.place, Some(Place::Line(6)));
    let p = d.write("b.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n");
    fails_with(&p, "face 0 uses vertex index -1");
}

#[test]
fn off_nan_and_inf_coordinates() {
    let d = Dir::new();
    let p = d.write("a.off", b"OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n");
    let e = fails_with(&p, "vertex 1 has a non-finite value (NaN)");
    assert_eq!(e.place, Some(Place::Line(4)));
    let p = d.write("b.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 -inf\n3 0 1 2\n");
    fails_with(&p, "vertex 2 has a non-finite value (-inf)");
}

#[test]
fn off_negative_count() {
    let d = Dir::new();
    let p = d.write("a.off", b"OFF\n-3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    fails_with(&p, "line 2: negative vertex count -3");
    let p = d.write("b.off", b"OFF\n1000000000000 1 0\n0 0 0\n");
    fails_with(
        &p,
        "line 2: the header announces 1000000000000 vertices, more than the limit",
    );
    let p = d.write("c.off", b"OFF\n3 x 0\n0 0 0\n");
    fails_with(&p, "line 2: the face count 'x' is not an integer");
}

#[test]
fn off_degenerate_polygon_and_huge_polygon() {
    let d = Dir::new();
    let p = d.write("a.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n");
    fails_with(&p, "face 0 has 2 vertices; a face needs at least 3");
    let p = d.write("b.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n70000 0 1 2\n");
    fails_with(&p, "face 0 has 70000 vertices, more than the 65536 supported");
}

#[test]
fn off_garbage_tokens() {
    let d = Dir::new();
    let p = d.write("a.off", b"OFF\n3 1 0\n0 0 0\n1 abc 0\n0 1 0\n3 0 1 2\n");
    fails_with(&p, "line 4: vertex 1: expected a number, found 'abc'");
    let long = format!("OFF\n3 1 0\n0 0 0\n1 {} 0\n0 1 0\n3 0 1 2\n", "9".repeat(1000));
    let p = d.write("b.off", long.as_bytes());
    fails_with(&p, "line 4: a token longer than 64 bytes");
}

#[test]
fn off_not_utf8_text() {
    let d = Dir::new();
    let p = d.write("a.off", b"OFF\n3 1 0\n0 0 0\n1 \xff\xfe 0\n0 1 0\n3 0 1 2\n");
    fails_with(&p, "line 4: vertex 1: expected a number, found '\u{fffd}\u{fffd}'");
}

#[test]
fn off_empty_and_faceless() {
    let d = Dir::new();
    let p = d.write("a.off", b"");
    fails_with(&p, "empty file: no OFF header or counts");
    let p = d.write("b.off", b"OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n");
    fails_with(&p, "the mesh has no faces");
}

#[test]
fn ply_header_announcing_a_trillion_vertices_fails_fast() {
    let d = Dir::new();
    let text = PLY_TRI_HEADER.replace("vertex 3", "vertex 1000000000000") + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    let start = std::time::Instant::now();
    let p = d.write("a.ply", text.as_bytes());
    let e = fails_with(
        &p,
        "element 'vertex' announces 1000000000000 items, more than the limit",
    );
    assert_eq!(e.place, Some(Place::Line(3)));
    // The same inside gzip, where the file size says nothing about the content.
    let p = d.write_gz("a.ply.gz", text.as_bytes());
    fails_with(&p, "element 'vertex' announces 1000000000000 items");
    // A bound on a hang, not a speed test: a loader that walked the
    // announced items would take hours. Speed is measured in benches/.
    assert!(start.elapsed().as_secs() < 60, "took {:?}", start.elapsed());
}

/// A binary little-endian PLY: 4 vertices, a triangle and a quad.
fn binary_ply() -> Vec<u8> {
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\n\
        property float y\nproperty float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
        .to_vec();
    for p in [[0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]] {
        for c in p {
            b.extend(c.to_le_bytes());
        }
    }
    b.push(3);
    for i in [0i32, 1, 2] {
        b.extend(i.to_le_bytes());
    }
    b.push(4);
    for i in [0i32, 1, 2, 3] {
        b.extend(i.to_le_bytes());
    }
    b
}

#[test]
fn ply_binary_valid_then_truncated() {
    let d = Dir::new();
    let full = binary_ply();
    let ok = d.write("ok.ply", &full);
    assert_eq!(load_mesh(&ok).unwrap().triangles.len(), 3);
    // Cut 3 bytes: still large enough for the minimal records (the size
    // check passes), so the parser meets the end inside the quad.
    let header_len = full.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let p = d.write("cut.ply", &full[..full.len() - 3]);
    let e = fails_with(&p, "truncated binary data: the file ends in face 1 of 2");
    let Some(Place::Byte(at)) = e.place else {
        panic!("{e}: no byte offset")
    };
    assert_eq!(at as usize, full.len() - 3);
    assert!(at as usize > header_len);
    // Cut into the vertices: refused before parsing.
    let p = d.write("short.ply", &full[..header_len + 20]);
    fails_with(&p, "which need at least 74 bytes, but only 20 bytes follow the header");
    // Truncated inside gzip: no size check possible, the parser finds it.
    let p = d.write_gz("cut.ply.gz", &full[..header_len + 20]);
    fails_with(&p, "truncated binary data: the file ends in vertex 1 of 4");
}

#[test]
fn ply_index_out_of_range_and_nan() {
    let d = Dir::new();
    let p = d.write(
        "a.ply",
        (PLY_TRI_HEADER.to_string() + "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n").as_bytes(),
    );
    fails_with(
        &p,
        "line 13: face 0 of 1 uses vertex index 3, but there are only 3 vertices",
    );
    let p = d.write(
        "b.ply",
        (PLY_TRI_HEADER.to_string() + "0 0 0\nNaN 0 0\n0 1 0\n3 0 1 2\n").as_bytes(),
    );
    fails_with(&p, "line 11: vertex 1 of 3 has a non-finite value (NaN)");
}

#[test]
fn ply_bad_headers() {
    let d = Dir::new();
    let p = d.write(
        "a.ply",
        PLY_TRI_HEADER.replace("ascii", "binary_middle_endian").as_bytes(),
    );
    fails_with(&p, "line 2: unknown PLY format 'binary_middle_endian'");
    let p = d.write(
        "b.ply",
        PLY_TRI_HEADER
            .replace("property float y", "property float128 y")
            .as_bytes(),
    );
    fails_with(&p, "line 5: unknown property type 'float128'");
    let p = d.write("c.ply", PLY_TRI_HEADER.replace("end_header\n", "").as_bytes());
    fails_with(&p, "the file ends inside the header (no 'end_header')");
    let p = d.write("d.ply", b"solid cube\nfacet normal 0 0 1\n");
    fails_with(&p, "line 1: not a PLY file");
    let p = d.write(
        "e.ply",
        PLY_TRI_HEADER
            .replace("element vertex 3", "element vertex -3")
            .as_bytes(),
    );
    fails_with(&p, "line 3: element 'vertex' has a negative count -3");
    let mut latin1 = b"ply\nformat ascii 1.0\ncomment caf\xe9\n".to_vec();
    latin1.extend_from_slice(&PLY_TRI_HEADER.as_bytes()[21..]);
    let p = d.write("f.ply", &latin1);
    fails_with(&p, "line 3: header line is not ASCII/UTF-8 text");
}

#[test]
fn a_directory_is_not_a_mesh() {
    let d = Dir::new();
    let p = d.0.path().join("dir.off");
    std::fs::create_dir(&p).unwrap();
    fails_with(&p, "is a directory, not a mesh file");
}

#[cfg(unix)]
#[test]
fn dev_zero_is_refused() {
    let d = Dir::new();
    let p = d.0.path().join("zero.ply");
    std::os::unix::fs::symlink("/dev/zero", &p).unwrap();
    fails_with(&p, "is not a regular file");
}

#[test]
fn gzip_bomb_is_bounded() {
    let d = Dir::new();
    // 3 vertices announced, then 64 MiB of blanks: the reader stops at the limit.
    let mut bomb = PLY_TRI_HEADER
        .replace("element vertex 3", "element vertex 100000000")
        .into_bytes();
    bomb.extend(std::iter::repeat_n(b' ', 64 << 20));
    let p = d.write_gz("bomb.ply.gz", &bomb);
    let limits = LoadLimits {
        max_input_bytes: 8 << 20,
        ..LoadLimits::default()
    };
    check(
        &p,
        load_mesh_with(&p, &limits),
        "more than 8388608 bytes after decompression",
    );
    // Valid data followed by 64 MiB of zero bytes: the counts are met, the
    // zeros are found after reading one chunk, not all of them.
    let mut bomb = (PLY_TRI_HEADER.to_string() + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").into_bytes();
    bomb.extend(std::iter::repeat_n(0u8, 64 << 20));
    let p = d.write_gz("zeros.ply.gz", &bomb);
    fails_with(&p, "unexpected data after the last element the header announces");
}

#[test]
fn corrupt_gzip() {
    let d = Dir::new();
    let p = d.write("a.off.gz", b"\x1f\x8b\x08\x00garbage that is not deflate data at all");
    fails_with(&p, "cannot decompress (corrupt or truncated gzip data)");
}

#[test]
fn unknown_format_and_missing_file() {
    let d = Dir::new();
    let p = d.write("a.stl", b"solid\n");
    fails_with(&p, "unknown mesh format");
    fails_with(&d.0.path().join("missing.off"), "No such file");
}

#[test]
fn obj_bad_files() {
    let d = Dir::new();
    let p = d.write("a.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
    fails_with(&p, "line 4: invalid OBJ");
    let p = d.write("b.obj", b"v 0 0 0\nv 1 \xff 0\n");
    fails_with(&p, "line 2: not UTF-8 text");
    let p = d.write("c.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    fails_with(&p, "the mesh has no faces");
}

#[test]
fn obj_hostile_indices_and_values() {
    let d = Dir::new();
    let p = d.write("a.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
    fails_with(&p, "line 4: invalid OBJ");
    let p = d.write("b.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -10 1 2\n");
    fails_with(&p, "line 4: invalid OBJ");
    let p = d.write("c.obj", b"v 0 0 0\nv 1e40 0 0\nv 0 1 0\nf 1 2 3\n");
    fails_with(
        &p,
        "vertex 1 (counting from 0 in file order) has a non-finite coordinate",
    );
    let p = d.write("d.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//7\n");
    fails_with(&p, "line 5: invalid OBJ");
}

/// Seeded random corruptions (byte changes, insertions, truncations) of valid
/// files in every format: each load must return, Ok or Err, without panicking.
#[test]
fn random_corruptions_never_panic() {
    let d = Dir::new();
    let ascii_ply = PLY_TRI_HEADER.to_string() + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    let seeds: [(&str, Vec<u8>); 4] = [
        ("m.ply", binary_ply()),
        ("a.ply", ascii_ply.into_bytes()),
        (
            "m.off",
            b"OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n4 0 1 2 3\n".to_vec(),
        ),
        (
            "m.obj",
            b"v 0 0 0\nv 1 0 0\nv 1 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\nf 1 3 2\n".to_vec(),
        ),
    ];
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let interesting = [b'0', b'9', b'-', b' ', b'\n', b'.', b'e', 0, 0xff, b'#', b'/', 0x7f];
    let (mut loaded, mut refused) = (0, 0);
    for (name, original) in &seeds {
        for round in 0..300 {
            let mut bytes = original.clone();
            for _ in 0..1 + next() % 4 {
                let i = (next() % bytes.len() as u64) as usize;
                let value = if next() % 2 == 0 {
                    interesting[(next() % interesting.len() as u64) as usize]
                } else {
                    next() as u8
                };
                match next() % 4 {
                    0 => bytes.insert(i, value),
                    1 => bytes.truncate(i.max(1)),
                    _ => bytes[i] = value,
                }
            }
            // A new file each time: rewriting one file makes ext4 flush it on close.
            let p = d.write(&format!("{round}{name}"), &bytes);
            match load_mesh(&p) {
                Ok(_) => loaded += 1,
                Err(e) => {
                    assert!(e.to_string().starts_with(&p.display().to_string()), "{e}");
                    refused += 1;
                }
            }
        }
    }
    println!("{loaded} corrupted files still loaded, {refused} refused");
    assert!(loaded > 0 && refused > 600, "{loaded} loaded, {refused} refused");
}
