//! File formats: mesh loaders (OFF, OBJ, PLY, gzip of any) and image writers.
//!
//! The mesh loaders stream the file (decompressing on the fly), never trust a
//! count from a header for an allocation, and report every problem with the
//! file, the place (line for text, byte offset for binary) and what is wrong.

pub mod assets;
pub mod obj;
pub mod off;
pub mod ply;
mod source;

use crate::scene::mesh::MeshDataError;
use crate::scene::Mesh;
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
}

impl Default for LoadLimits {
    /// 8 GiB of input, 2^28 vertices or faces (about 6 GiB of vertex and index data).
    fn default() -> Self {
        Self {
            max_input_bytes: 8 << 30,
            max_elements: 1 << 28,
        }
    }
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
        MeshFormat::Obj => obj::parse(&mut src, name),
    });
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

    #[test]
    fn relative_and_asset_paths() {
        let p = resolve_mesh_path(Path::new("/s"), "meshes/star.off").unwrap();
        assert_eq!(p, Path::new("/s/meshes/star.off"));
        let e = resolve_mesh_path(Path::new("/s"), "asset:teapot.ply").unwrap_err();
        assert!(e.to_string().contains("unknown asset"), "{e}");
    }
}
