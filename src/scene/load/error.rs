//! The error of a scene that cannot be loaded, and the place in the file it
//! is about.

use crate::io::MeshError;
use std::fmt;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// A 1-based line and column (in characters) in a scene file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Place {
    /// Line, from 1.
    pub line: usize,
    /// Column in characters, from 1.
    pub column: usize,
}

impl Place {
    /// The place of byte `offset` in `text` (clamped to the text).
    pub fn of_offset(text: &str, offset: usize) -> Place {
        let mut offset = offset.min(text.len());
        while !text.is_char_boundary(offset) {
            offset -= 1;
        }
        let before = &text[..offset];
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        Place {
            line: before.bytes().filter(|&b| b == b'\n').count() + 1,
            column: before[line_start..].chars().count() + 1,
        }
    }
}

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "{}:{}", self.line, self.column)
    }
}

/// `file:line:col`, or `file` when there is no place.
fn located(path: &Path, place: &Option<Place>) -> String {
    match place {
        Some(p) => format!("{}:{p}", path.display()),
        None => path.display().to_string(),
    }
}

/// A scene could not be loaded. The message always names the file, and the
/// line and column when the problem has a place in it.
#[derive(Debug, Error)]
pub enum SceneError {
    /// The file could not be opened or read.
    #[error("{}: cannot read the scene file: {error}", path.display())]
    Read {
        /// The scene file.
        path: PathBuf,
        /// The operating system's error.
        error: std::io::Error,
    },
    /// The path names a directory.
    #[error("{}: is a directory, not a scene file", path.display())]
    Directory {
        /// The path given.
        path: PathBuf,
    },
    /// The file is larger than [`MAX_SCENE_FILE_BYTES`](super::MAX_SCENE_FILE_BYTES).
    #[error("{}: the scene file is larger than {limit} bytes; is this really a scene file?", path.display())]
    TooLarge {
        /// The scene file.
        path: PathBuf,
        /// The limit in bytes.
        limit: u64,
    },
    /// The file is not UTF-8 text.
    #[error("{}:{place}: the scene file is not valid UTF-8 text", path.display())]
    NotUtf8 {
        /// The scene file.
        path: PathBuf,
        /// Where the first invalid byte is.
        place: Place,
    },
    /// TOML syntax error, unknown key, wrong type, unknown enum value or
    /// missing required key (reported by the TOML parser).
    #[error("{}: {message}", located(path, place))]
    Toml {
        /// The scene file.
        path: PathBuf,
        /// Where, when the parser knows.
        place: Option<Place>,
        /// The parser's message.
        message: String,
    },
    /// A value that parses but makes no sense (negative radius, NaN, …).
    #[error("{}:{place}: {message}", path.display())]
    Invalid {
        /// The scene file.
        path: PathBuf,
        /// Where the offending value is.
        place: Place,
        /// What is wrong.
        message: String,
    },
    /// An object names a material that `[materials]` does not define.
    #[error("{}:{place}: unknown material `{name}` (defined: {})", path.display(), list_or_none(known))]
    UnknownMaterial {
        /// The scene file.
        path: PathBuf,
        /// Where the reference is.
        place: Place,
        /// The name used.
        name: String,
        /// The names defined.
        known: Vec<String>,
    },
    /// A mesh file could not be resolved or loaded.
    #[error("{}:{place}: mesh of object `{object}`: {error}", path.display())]
    Mesh {
        /// The scene file.
        path: PathBuf,
        /// Where the `file` key's value is.
        place: Place,
        /// The object's name.
        object: String,
        /// The mesh loader's error (names the mesh file and the place in it).
        error: Box<MeshError>,
    },
    /// A problem of the scene as a whole, with no one place in the file.
    #[error("{}: {message}", path.display())]
    Scene {
        /// The scene file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A glTF model that cannot be rendered: the message names the JSON
    /// pointer (RFC 6901) of the offending value, e.g.
    /// `/meshes/0/primitives/1/attributes/POSITION`.
    #[error("{}: {}{message}", path.display(), pointer_prefix(pointer))]
    Gltf {
        /// The `.gltf` or `.glb` file.
        path: PathBuf,
        /// JSON pointer of the value at fault; empty for the whole file.
        pointer: String,
        /// What is wrong.
        message: String,
    },
}

fn pointer_prefix(pointer: &str) -> String {
    if pointer.is_empty() {
        String::new()
    } else {
        format!("{pointer}: ")
    }
}

fn list_or_none(names: &[String]) -> String {
    if names.is_empty() {
        "none".into()
    } else {
        names.iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ")
    }
}

impl SceneError {
    /// The scene file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            SceneError::Read { path, .. }
            | SceneError::Directory { path }
            | SceneError::TooLarge { path, .. }
            | SceneError::NotUtf8 { path, .. }
            | SceneError::Toml { path, .. }
            | SceneError::Invalid { path, .. }
            | SceneError::UnknownMaterial { path, .. }
            | SceneError::Mesh { path, .. }
            | SceneError::Scene { path, .. }
            | SceneError::Gltf { path, .. } => path,
        }
    }

    /// Line and column in the scene file, when the problem has one.
    pub fn place(&self) -> Option<Place> {
        match self {
            SceneError::Read { .. }
            | SceneError::Directory { .. }
            | SceneError::TooLarge { .. }
            | SceneError::Scene { .. }
            | SceneError::Gltf { .. } => None,
            SceneError::Toml { place, .. } => *place,
            SceneError::NotUtf8 { place, .. }
            | SceneError::Invalid { place, .. }
            | SceneError::UnknownMaterial { place, .. }
            | SceneError::Mesh { place, .. } => Some(*place),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn places_count_lines_and_characters() {
        let text = "a = 1\nbé = 2\n";
        assert_eq!(Place::of_offset(text, 0), Place { line: 1, column: 1 });
        assert_eq!(Place::of_offset(text, 6), Place { line: 2, column: 1 });
        // 'é' is two bytes but one column: `=` is byte 10, column 4.
        assert_eq!(Place::of_offset(text, 10), Place { line: 2, column: 4 });
        // Inside a multi-byte character: clamped back to its start.
        assert_eq!(Place::of_offset(text, 8), Place { line: 2, column: 2 });
        assert_eq!(Place::of_offset(text, 1000), Place { line: 3, column: 1 });
    }
}
