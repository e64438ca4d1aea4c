//! Mitsuba's `.serialized` meshes: a file of zlib-compressed shapes, each
//! `u16 0x041C`, `u16 version` (3 or 4) and a zlib stream holding `u32
//! flags`, the name (version 4), `u64` vertex and triangle counts, then
//! positions, normals, texture coordinates and colours (`f32` or `f64` per
//! the flags) and `u32` (or, past 2³² vertices, `u64`) indices. The file
//! ends with each shape's byte offset (`u64`, or `u32` in version 3) and
//! the shape count (`u32`). Little-endian throughout.

use super::{check_mesh_memory, LoadLimits, MeshError, Place};
use crate::geometry::Mesh;
use crate::math::{Vec2, Vec3};
use flate2::read::ZlibDecoder;
use std::io::Read;
use std::path::Path;

const MAGIC: u16 = 0x041C;
const HAS_NORMALS: u32 = 0x0001;
const HAS_TEXCOORDS: u32 = 0x0002;
const HAS_COLOURS: u32 = 0x0008;
const FACE_NORMALS: u32 = 0x0010;
const SINGLE_PRECISION: u32 = 0x1000;
const DOUBLE_PRECISION: u32 = 0x2000;

/// Most bytes of a `.serialized` file read.
pub const MAX_SERIALIZED_BYTES: u64 = 8 << 30;

/// Most bytes one compressed byte inflates to: DEFLATE's limit is about
/// 1032 : 1 (a 258-byte match per 2 bits), so a shape whose counts need
/// more data than this times its compressed size is refused before
/// anything is inflated or allocated (a zlib bomb, or a lie in the counts).
pub const MAX_INFLATE_RATIO: u64 = 1032;

/// One shape of a `.serialized` file, and whether its flags ask for face
/// normals.
pub fn load_serialized(path: &Path, shape_index: u32, limits: &LoadLimits) -> Result<(Mesh, bool), MeshError> {
    let err = |place: Option<u64>, message: String| MeshError::new(path, place.map(Place::Byte), message);
    let bytes = std::fs::read(path).map_err(|e| err(None, format!("cannot read: {e}")))?;
    if bytes.len() as u64 > MAX_SERIALIZED_BYTES.min(limits.max_input_bytes) {
        return Err(err(None, "the file is larger than the mesh size limit".into()));
    }
    parse_serialized(&bytes, shape_index, &path.display().to_string(), limits).map_err(|(at, m)| err(at, m))
}

type Failure = (Option<u64>, String);

/// [`load_serialized`] on bytes in memory.
pub fn parse_serialized(
    bytes: &[u8],
    shape_index: u32,
    name: &str,
    limits: &LoadLimits,
) -> Result<(Mesh, bool), Failure> {
    let n = bytes.len();
    if n < 4 {
        return Err((None, "too short for a Mitsuba .serialized file".into()));
    }
    let count = u32::from_le_bytes(bytes[n - 4..].try_into().expect("4 bytes"));
    if count == 0 {
        return Err((None, "the file holds no shape".into()));
    }
    if shape_index >= count {
        return Err((
            None,
            format!("`shape_index` {shape_index} is out of range: the file holds {count} shapes"),
        ));
    }
    let header = |offset: usize| -> Result<(u16, u16), Failure> {
        let h = bytes
            .get(offset..offset + 4)
            .ok_or((Some(offset as u64), "a shape offset points past the end".to_string()))?;
        Ok((u16::from_le_bytes([h[0], h[1]]), u16::from_le_bytes([h[2], h[3]])))
    };
    // The version of the first shape tells the width of the offsets.
    let (magic, version) = header(0)?;
    if magic != MAGIC {
        return Err((Some(0), "not a Mitsuba .serialized file (bad magic number)".into()));
    }
    let width = match version {
        3 => 4usize,
        4 => 8,
        v => {
            return Err((
                Some(2),
                format!("unsupported .serialized version {v} (3 and 4 are read)"),
            ))
        }
    };
    let table = (count as usize)
        .checked_mul(width)
        .and_then(|t| (n - 4).checked_sub(t))
        .ok_or((
            None,
            format!("the last 4 bytes announce {count} shapes, whose offsets do not fit the file (a truncated file?)"),
        ))?;
    let at = table + shape_index as usize * width;
    let offset = if width == 4 {
        u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes")) as u64
    } else {
        u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"))
    };
    let start = usize::try_from(offset).ok().filter(|&o| o + 4 <= table).ok_or((
        Some(at as u64),
        format!("shape {shape_index} starts at byte {offset}, outside the file"),
    ))?;
    let (magic, version) = header(start)?;
    if magic != MAGIC || !(3..=4).contains(&version) {
        return Err((Some(start as u64), format!("shape {shape_index} has a bad header")));
    }
    let mut z = Stream {
        inner: ZlibDecoder::new(&bytes[start + 4..table]),
        start: start as u64 + 4,
    };
    let flags = z.u32()?;
    if version == 4 {
        // The shape's name, NUL-terminated.
        let mut len = 0;
        while z.u8()? != 0 {
            len += 1;
            if len > 1 << 16 {
                return Err(z.fail("the shape name is not terminated"));
            }
        }
    }
    let vertices = z.u64()?;
    let triangles = z.u64()?;
    if vertices > limits.max_elements || triangles > limits.max_elements {
        return Err(z.fail(format!(
            "{vertices} vertices and {triangles} triangles exceed the limit of {} elements",
            limits.max_elements
        )));
    }
    let double = match flags & (SINGLE_PRECISION | DOUBLE_PRECISION) {
        SINGLE_PRECISION => false,
        DOUBLE_PRECISION => true,
        _ => return Err(z.fail(format!("flags {flags:#x} give no single precision or double precision"))),
    };
    let reals_per_vertex = 3
        + if flags & HAS_NORMALS != 0 { 3 } else { 0 }
        + if flags & HAS_TEXCOORDS != 0 { 2 } else { 0 }
        + if flags & HAS_COLOURS != 0 { 3 } else { 0 };
    let data = u128::from(vertices) * reals_per_vertex * if double { 8 } else { 4 } + u128::from(triangles) * 12;
    let compressed = (table - start - 4) as u64;
    if data > u128::from(compressed) * u128::from(MAX_INFLATE_RATIO) {
        return Err(z.fail(format!(
            "{vertices} vertices and {triangles} triangles need {data} bytes of data, more than the shape's \
             {compressed} compressed bytes can inflate to (at most {MAX_INFLATE_RATIO} × as many): \
             a truncated file, wrong counts or a zlib bomb"
        )));
    }
    check_mesh_memory(vertices, triangles, limits, None).map_err(|e| (None, e.problem))?;
    let nv = vertices as usize;
    let read_vec3 = |z: &mut Stream| -> Result<Vec<Vec3>, Failure> {
        let mut out = Vec::with_capacity(nv);
        for _ in 0..nv {
            out.push(Vec3::new(z.real(double)?, z.real(double)?, z.real(double)?));
        }
        Ok(out)
    };
    let positions = read_vec3(&mut z)?;
    let normals = if flags & HAS_NORMALS != 0 {
        Some(read_vec3(&mut z)?)
    } else {
        None
    };
    let uvs = if flags & HAS_TEXCOORDS != 0 {
        let mut out = Vec::with_capacity(nv);
        for _ in 0..nv {
            out.push(Vec2::new(z.real(double)?, z.real(double)?));
        }
        out
    } else {
        Vec::new()
    };
    if flags & HAS_COLOURS != 0 {
        for _ in 0..nv * 3 {
            z.real(double)?;
        }
    }
    let wide = vertices > u64::from(u32::MAX);
    if wide {
        return Err(z.fail("more than 2^32 vertices"));
    }
    let mut tris = Vec::with_capacity(triangles as usize);
    for _ in 0..triangles {
        tris.push([z.u32()?, z.u32()?, z.u32()?]);
    }
    let mut mesh =
        Mesh::new(format!("{name}#{shape_index}"), positions, tris, normals).map_err(|e| (None, e.to_string()))?;
    if !uvs.is_empty() {
        mesh = mesh.with_uvs(uvs).map_err(|e| (None, e.to_string()))?;
    }
    Ok((mesh, flags & FACE_NORMALS != 0))
}

struct Stream<'a> {
    inner: ZlibDecoder<&'a [u8]>,
    start: u64,
}

impl Stream<'_> {
    fn fail(&self, message: impl Into<String>) -> Failure {
        (Some(self.start), message.into())
    }

    fn bytes<const N: usize>(&mut self) -> Result<[u8; N], Failure> {
        let mut b = [0u8; N];
        self.inner.read_exact(&mut b).map_err(|e| {
            (
                Some(self.start),
                format!("the compressed shape data ends early or is corrupt: {e}"),
            )
        })?;
        Ok(b)
    }

    fn u8(&mut self) -> Result<u8, Failure> {
        Ok(self.bytes::<1>()?[0])
    }

    fn u32(&mut self) -> Result<u32, Failure> {
        Ok(u32::from_le_bytes(self.bytes()?))
    }

    fn u64(&mut self) -> Result<u64, Failure> {
        Ok(u64::from_le_bytes(self.bytes()?))
    }

    fn real(&mut self, double: bool) -> Result<f32, Failure> {
        Ok(if double {
            f64::from_le_bytes(self.bytes()?) as f32
        } else {
            f32::from_le_bytes(self.bytes()?)
        })
    }
}

/// Writes one shape per mesh as a version-4 `.serialized` file (single
/// precision, normals and texture coordinates when present): the tests'
/// and `convert`'s writer.
pub fn write_serialized(meshes: &[&Mesh]) -> Vec<u8> {
    use flate2::write::ZlibEncoder;
    use std::io::Write;
    let mut out = Vec::new();
    let mut offsets = Vec::new();
    for mesh in meshes {
        offsets.push(out.len() as u64);
        out.extend_from_slice(&MAGIC.to_le_bytes());
        out.extend_from_slice(&4u16.to_le_bytes());
        let mut flags = SINGLE_PRECISION | HAS_NORMALS;
        if !mesh.uvs.is_empty() {
            flags |= HAS_TEXCOORDS;
        }
        let mut z = ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        let mut body = Vec::new();
        body.extend_from_slice(&flags.to_le_bytes());
        body.extend_from_slice(mesh.name.as_bytes());
        body.push(0);
        body.extend_from_slice(&(mesh.positions.len() as u64).to_le_bytes());
        body.extend_from_slice(&(mesh.triangles.len() as u64).to_le_bytes());
        for v in mesh.positions.iter().chain(&mesh.normals) {
            for c in v.to_array() {
                body.extend_from_slice(&c.to_le_bytes());
            }
        }
        for uv in &mesh.uvs {
            for c in uv.to_array() {
                body.extend_from_slice(&c.to_le_bytes());
            }
        }
        for t in &mesh.triangles {
            for i in t {
                body.extend_from_slice(&i.to_le_bytes());
            }
        }
        z.write_all(&body).expect("writing to memory");
        out.extend(z.finish().expect("writing to memory"));
    }
    for o in &offsets {
        out.extend_from_slice(&o.to_le_bytes());
    }
    out.extend_from_slice(&(meshes.len() as u32).to_le_bytes());
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangle(z: f32) -> Mesh {
        Mesh::new(
            "t",
            vec![Vec3::new(0.0, 0.0, z), Vec3::X, Vec3::Y],
            vec![[0, 1, 2]],
            None,
        )
        .unwrap()
    }

    #[test]
    fn written_shapes_read_back() {
        let (a, b) = (triangle(0.0), triangle(2.0));
        let b = b.with_uvs(vec![Vec2::ZERO, Vec2::X, Vec2::Y]).unwrap();
        let bytes = write_serialized(&[&a, &b]);
        let limits = LoadLimits::default();
        let (m, face) = parse_serialized(&bytes, 1, "f", &limits).unwrap();
        assert!(!face);
        assert_eq!(m.positions, b.positions);
        assert_eq!(m.uvs, b.uvs);
        assert_eq!(m.triangles, b.triangles);
        let (m, _) = parse_serialized(&bytes, 0, "f", &limits).unwrap();
        assert_eq!(m.positions, a.positions);
        assert!(m.uvs.is_empty());
        let e = parse_serialized(&bytes, 2, "f", &limits).unwrap_err();
        assert!(e.1.contains("out of range"), "{}", e.1);
    }

    #[test]
    fn truncated_and_corrupt_files_are_errors() {
        let bytes = write_serialized(&[&triangle(0.0)]);
        let limits = LoadLimits::default();
        for cut in [0, 3, 10, bytes.len() / 2] {
            assert!(parse_serialized(&bytes[..cut], 0, "f", &limits).is_err());
        }
        let mut bad = bytes.clone();
        bad[8] ^= 0xff;
        assert!(parse_serialized(&bad, 0, "f", &limits).is_err());
        let mut magic = bytes;
        magic[0] = 0;
        assert!(parse_serialized(&magic, 0, "f", &limits)
            .unwrap_err()
            .1
            .contains("magic"));
    }
}
