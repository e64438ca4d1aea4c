//! File formats: mesh loaders (OFF, OBJ, PLY, gzip of any) and image writers.
//!
//! The mesh loaders stream the file (decompressing on the fly), never trust a
//! count from a header for an allocation, and report every problem with the
//! file, the place (line for text, byte offset for binary) and what is wrong.

pub mod assets;
pub mod image;
pub mod obj;
pub mod off;
pub mod ply;
pub mod serialized;
mod source;

use crate::geometry::Mesh;
use crate::geometry::MeshDataError;
use crate::memory::MemoryBudget;
use std::fmt;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Where in a file a problem is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Place {
    /// 1-based line of a text file.
    Line(u64),
    /// Byte offset in the (decompressed) data of a binary file.
    Byte(u64),
}

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Place::Line(l) => write!(f, "line {l}"),
            Place::Byte(b) => write!(f, "byte {b}"),
        }
    }
}

/// A mesh file could not be loaded. Displays as `"<path>: <message>"`, where
/// the message starts with the place when one is known (`line 7: ...`).
#[derive(Debug, Error)]
#[error("{}: {message}", path.display())]
pub struct MeshError {
    /// The file.
    pub path: PathBuf,
    /// Where the problem is, when known (also written at the start of `message`).
    pub place: Option<Place>,
    /// What is wrong, and where (line or byte offset) when known.
    pub message: String,
}

impl MeshError {
    /// An error at an optional place: the message becomes `"<place>: <problem>"`.
    pub fn new(path: impl Into<PathBuf>, place: Option<Place>, problem: impl fmt::Display) -> Self {
        let message = match &place {
            Some(p) => format!("{p}: {problem}"),
            None => problem.to_string(),
        };
        Self {
            path: path.into(),
            place,
            message,
        }
    }
}

/// A parser's error before the file name is attached.
#[derive(Debug)]
pub(crate) struct ParseError {
    pub(crate) place: Option<Place>,
    pub(crate) problem: String,
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.place {
            Some(p) => write!(f, "{p}: {}", self.problem),
            None => f.write_str(&self.problem),
        }
    }
}

impl ParseError {
    pub(crate) fn new(place: Option<Place>, problem: String) -> Self {
        Self { place, problem }
    }

    fn with_path(self, path: &Path) -> MeshError {
        MeshError::new(path, self.place, self.problem)
    }
}

impl From<MeshDataError> for ParseError {
    fn from(e: MeshDataError) -> Self {
        Self::new(None, e.to_string())
    }
}

/// Bounds on what a mesh file may make the loader read and allocate.
#[derive(Clone, Debug)]
pub struct LoadLimits {
    /// Most bytes read from a file, counted after decompression (a gzip bomb
    /// stops here); also the largest file accepted on disk.
    pub max_input_bytes: u64,
    /// Most vertices or faces a header may announce (vertex indices are `u32`).
    pub max_elements: u64,
    /// Memory the mesh (and its KD-tree) may take: a header whose counts need
    /// more is refused before anything is allocated. `None`: not checked.
    pub memory: Option<MemoryBudget>,
}

impl Default for LoadLimits {
    /// 8 GiB of input, 2^28 vertices or faces (about 6 GiB of vertex and index
    /// data), and the memory budget of [`crate::memory::budget`]
    /// (`CAUSTIC_MEMORY_LIMIT`, else the kernel's `MemAvailable`; an
    /// unparsable variable is reported by the CLI at start-up).
    fn default() -> Self {
        Self {
            max_input_bytes: 8 << 30,
            max_elements: 1 << 28,
            memory: crate::memory::budget().ok().flatten(),
        }
    }
}

/// Memory per vertex of a loaded mesh: position and normal, 3 × f32 each.
pub const MESH_BYTES_PER_VERTEX: u64 = 24;
/// Memory per triangle: three `u32` indices, plus about 64 bytes for the
/// KD-tree built over it (nodes and triangle-index lists; the SAH tree
/// references each triangle from ~2-3 leaves), plus the 36 bytes of corner
/// normals computed while loading.
pub const MESH_BYTES_PER_TRIANGLE: u64 = 12 + 64 + 36;

/// Estimated memory of a mesh with these counts once loaded and indexed.
pub fn mesh_memory_bytes(vertices: u64, triangles: u64) -> u128 {
    u128::from(vertices) * u128::from(MESH_BYTES_PER_VERTEX)
        + u128::from(triangles) * u128::from(MESH_BYTES_PER_TRIANGLE)
}

/// Refuses counts whose mesh would not fit the memory budget, before any allocation.
pub(crate) fn check_mesh_memory(
    vertices: u64,
    faces: u64,
    limits: &LoadLimits,
    place: Option<Place>,
) -> Result<(), ParseError> {
    let Some(budget) = limits.memory else {
        return Ok(());
    };
    let need = mesh_memory_bytes(vertices, faces);
    if need > u128::from(budget.bytes) {
        return Err(ParseError::new(
            place,
            format!(
                "{vertices} vertices and {faces} faces need about {} of memory ({MESH_BYTES_PER_VERTEX} bytes \
                 per vertex, {MESH_BYTES_PER_TRIANGLE} per triangle with its KD-tree), {}",
                crate::memory::format_bytes(u64::try_from(need).unwrap_or(u64::MAX)),
                budget
            ),
        ));
    }
    Ok(())
}

/// The file formats the loader reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// Object File Format (Geomview), as in the original report.
    Off,
    /// Wavefront OBJ.
    Obj,
    /// Stanford polygon format, ASCII or binary.
    Ply,
}

impl MeshFormat {
    /// The format named by the extension, after removing a final `.gz`.
    pub fn from_path(path: &Path) -> Option<Self> {
        let name = path.file_name()?.to_str()?.to_ascii_lowercase();
        let name = name.strip_suffix(".gz").unwrap_or(&name);
        let ext = Path::new(name).extension()?.to_str()?;
        match ext {
            "off" => Some(Self::Off),
            "obj" => Some(Self::Obj),
            "ply" => Some(Self::Ply),
            _ => None,
        }
    }
}

/// Loads a mesh, choosing the format from the extension (`.off`, `.obj`,
/// `.ply`, optionally `.gz`); gzip is also recognised by its magic bytes.
pub fn load_mesh(path: &Path) -> Result<Mesh, MeshError> {
    load_mesh_with(path, &LoadLimits::default())
}

/// [`load_mesh`] with explicit limits.
pub fn load_mesh_with(path: &Path, limits: &LoadLimits) -> Result<Mesh, MeshError> {
    let format = MeshFormat::from_path(path).ok_or_else(|| {
        MeshError::new(
            path,
            None,
            "unknown mesh format: expected a .off, .obj or .ply file (optionally .gz)",
        )
    })?;
    let name = path.display().to_string();
    let result = source::open(path, limits).and_then(|mut src| match format {
        MeshFormat::Off => off::parse(&mut src, limits, name),
        MeshFormat::Ply => ply::parse(&mut src, limits, name),
        MeshFormat::Obj => obj::parse(&mut src, limits, name),
    });
    result.map_err(|e| e.with_path(path))
}

/// Parses a mesh held in memory (`bytes` may be gzip-compressed: recognised
/// by its magic bytes). `name` stands for the file in messages. The same
/// parsers and limits as [`load_mesh_with`] apply; this is also the fuzzing
/// entry point.
pub fn parse_mesh_bytes(bytes: &[u8], format: MeshFormat, name: &str, limits: &LoadLimits) -> Result<Mesh, MeshError> {
    let path = Path::new(name);
    if bytes.len() as u64 > limits.max_input_bytes {
        return Err(MeshError::new(
            path,
            None,
            format!(
                "{} bytes, more than the {} byte limit for a mesh file",
                bytes.len(),
                limits.max_input_bytes
            ),
        ));
    }
    let mut src = source::from_bytes(bytes.to_vec(), limits);
    let result = match format {
        MeshFormat::Off => off::parse(&mut src, limits, name.to_string()),
        MeshFormat::Ply => ply::parse(&mut src, limits, name.to_string()),
        MeshFormat::Obj => obj::parse(&mut src, limits, name.to_string()),
    };
    result.map_err(|e| e.with_path(path))
}

/// Resolves a mesh reference from a scene file: `asset:NAME` names a fetched
/// asset (see [`assets::resolve_asset`]); anything else is a path relative to
/// `scene_dir` (or absolute).
pub fn resolve_mesh_path(scene_dir: &Path, file: &str) -> Result<PathBuf, MeshError> {
    match file.strip_prefix("asset:") {
        Some(name) => assets::resolve_asset(name).map_err(|e| MeshError::new(file, None, e)),
        None => Ok(scene_dir.join(file)),
    }
}

/// Reserves room for `count` items but never more than `cap` up front: counts
/// come from headers, which can lie; the vectors grow as real data arrives.
pub(crate) fn bounded_capacity(count: u64, cap: u64) -> usize {
    count.min(cap) as usize
}

/// Fan-triangulates a convex polygon (v0, v1, v2), (v0, v2, v3), ...
pub(crate) fn fan(polygon: &[u32], out: &mut Vec<[u32; 3]>) {
    for k in 1..polygon.len().saturating_sub(1) {
        out.push([polygon[0], polygon[k], polygon[k + 1]]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn format_from_extension() {
        assert_eq!(MeshFormat::from_path(Path::new("a/b.OFF")), Some(MeshFormat::Off));
        assert_eq!(MeshFormat::from_path(Path::new("x.ply.gz")), Some(MeshFormat::Ply));
        assert_eq!(MeshFormat::from_path(Path::new("x.obj")), Some(MeshFormat::Obj));
        assert_eq!(MeshFormat::from_path(Path::new("x.gz")), None);
        assert_eq!(MeshFormat::from_path(Path::new("x.stl")), None);
    }

    #[test]
    fn error_display_is_path_then_message() {
        let e = MeshError::new("m.off", Some(Place::Line(3)), "bad");
        assert_eq!(e.to_string(), "m.off: line 3: bad");
        assert_eq!(e.message, "line 3: bad");
    }

    #[test]
    fn fan_triangulation() {
        let mut out = Vec::new();
        fan(&[4, 5, 6, 7, 8], &mut out);
        assert_eq!(out, vec![[4, 5, 6], [4, 6, 7], [4, 7, 8]]);
    }

    fn budget(bytes: u64) -> LoadLimits {
        LoadLimits {
            memory: Some(MemoryBudget { bytes, source: "test" }),
            ..LoadLimits::default()
        }
    }

    #[test]
    fn bytes_of_every_format_parse_alike() {
        let off = b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        let obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        let ply = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                    property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
                    0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        let limits = budget(1 << 20);
        for (bytes, format) in [
            (&off[..], MeshFormat::Off),
            (&obj[..], MeshFormat::Obj),
            (&ply[..], MeshFormat::Ply),
        ] {
            let m = parse_mesh_bytes(bytes, format, "m", &limits).unwrap();
            assert_eq!(m.triangles, vec![[0, 1, 2]]);
            // gzip is recognised by its magic bytes.
            let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
            std::io::Write::write_all(&mut gz, bytes).unwrap();
            let m = parse_mesh_bytes(&gz.finish().unwrap(), format, "m", &limits).unwrap();
            assert_eq!(m.positions.len(), 3);
        }
    }

    #[test]
    fn memory_is_checked_before_allocation() {
        // One triangle needs 3 × 24 + 112 = 184 bytes.
        assert_eq!(mesh_memory_bytes(3, 1), 184);
        let off = b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        assert!(parse_mesh_bytes(off, MeshFormat::Off, "m.off", &budget(184)).is_ok());
        let e = parse_mesh_bytes(off, MeshFormat::Off, "m.off", &budget(183)).unwrap_err();
        assert_eq!(
            e.to_string(),
            "m.off: line 2: 3 vertices and 1 faces need about 184 bytes of memory (24 bytes per vertex, \
             112 per triangle with its KD-tree), 183 bytes available"
        );
        let obj = b"v 0 0 0\nv 1 0 0\n  v 0 1 0\nf 1 2 3\n";
        let e = parse_mesh_bytes(obj, MeshFormat::Obj, "m.obj", &budget(100)).unwrap_err();
        assert!(
            e.to_string().contains("3 vertices and 1 faces need about 184 bytes"),
            "{e}"
        );
        // An empty-property element could otherwise announce 2^28 zero-byte records.
        let ply = b"ply\nformat binary_little_endian 1.0\nelement junk 268435456\nend_header\n";
        let e = parse_mesh_bytes(ply, MeshFormat::Ply, "m.ply", &budget(1 << 20)).unwrap_err();
        assert!(
            e.to_string()
                .contains("element 'junk' has 268435456 items but no properties"),
            "{e}"
        );
    }

    #[test]
    fn relative_and_asset_paths() {
        let p = resolve_mesh_path(Path::new("/s"), "meshes/star.off").unwrap();
        assert_eq!(p, Path::new("/s/meshes/star.off"));
        let e = resolve_mesh_path(Path::new("/s"), "asset:teapot.ply").unwrap_err();
        assert!(e.to_string().contains("unknown asset"), "{e}");
    }
}
