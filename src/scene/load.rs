//! Scene description to validated scene.
use super::Scene;
use std::path::Path;
use thiserror::Error;

/// A scene file could not be loaded.
#[derive(Debug, Error)]
#[error("{0}")]
pub struct SceneError(pub String);

/// Loads and validates a scene file.
pub fn load_scene(path: &Path) -> Result<Scene, SceneError> {
    Err(SceneError(format!(
        "{}: scene loading is not implemented yet",
        path.display()
    )))
}
