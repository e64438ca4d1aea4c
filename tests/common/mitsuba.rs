//! Mitsuba scene text written to a temporary folder and read by the front end.

use caustic::scene::mitsuba::{load_mitsuba_scene, MitsubaScene};
use std::path::{Path, PathBuf};

/// Writes `text` to `dir/name` (its folders made) and returns the path.
pub fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(&path, text).unwrap();
    path
}

/// The scene `text` read from `scene.xml` in a temporary folder.
pub fn load(text: &str) -> MitsubaScene {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "scene.xml", text);
    load_mitsuba_scene(&path, &[]).unwrap_or_else(|e| panic!("{e}"))
}

/// The message refusing the scene `text` (read as `scene.xml`); panics if
/// it loads.
pub fn error(text: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "scene.xml", text);
    match load_mitsuba_scene(&path, &[]) {
        Ok(_) => panic!("expected an error for {text}"),
        Err(e) => e.to_string(),
    }
}
