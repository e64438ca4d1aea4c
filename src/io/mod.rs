//! File formats: mesh loaders (OFF, OBJ, PLY, gzip of any) and image writers.

use crate::scene::Mesh;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// A mesh file could not be loaded.
#[derive(Debug, Error)]
#[error("{}: {message}", path.display())]
pub struct MeshError {
    /// The file.
    pub path: PathBuf,
    /// What is wrong, and where (line or byte offset) when known.
    pub message: String,
}

/// Loads a mesh, choosing the format from the extension (`.off`, `.obj`, `.ply`, optionally `.gz`).
pub fn load_mesh(path: &Path) -> Result<Mesh, MeshError> {
    Err(MeshError {
        path: path.into(),
        message: "mesh loading is not implemented yet".into(),
    })
}

/// Resolves a mesh reference from a scene file: `asset:NAME` names a fetched
/// asset (see `io::assets`); anything else is a path relative to `scene_dir`.
pub fn resolve_mesh_path(scene_dir: &Path, file: &str) -> Result<PathBuf, MeshError> {
    Ok(scene_dir.join(file))
}
