//! A [`LoadedScene`] (a scene and its settings) written as caustic's TOML
//! (`caustic convert`): whatever front end read it, the file written loads
//! back to the same scene.
//!
//! A scene read from a TOML file can instead be written back into that
//! file's document, its comments and layout kept ([`TomlDocument`], the
//! viewer's save).
//!
//! Each kind of thing has one function that writes it: `settings` the
//! `[render]`, `[photons]` and `[camera]` tables, `materials` the materials
//! and their textures, `lights` the lights, `objects` the objects and
//! their meshes, `media` the media and the water's `[medium]`. Numbers are
//! written so that they read back to the same single-precision value. A
//! mesh read from a file whose content is exactly the loaded mesh is
//! referenced by path; any other mesh (built by a front end, transformed
//! when read) is written as a binary PLY file beside the output.
//!
//! Nothing is left half written: the PLY files and the TOML file are each
//! written atomically, the TOML last, after the scene it describes has been
//! read back from the text and found equal to the original
//! ([`super::compare::first_difference`]); when it is not, the meshes
//! written are removed and the difference is the error.

mod document;
mod lights;
mod materials;
mod media;
mod objects;
mod settings;

pub use document::{CameraFraming, LightKeys, LightSplit, TomlDocument};

use super::LoadedScene;
use crate::film::output::OutputError;
use std::path::{Component, Path, PathBuf};
use thiserror::Error;
use toml::{Table, Value};

/// What [`write_toml_scene`] wrote.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Written {
    /// The TOML file.
    pub scene: PathBuf,
    /// The PLY files written beside it (meshes built in memory).
    pub meshes: Vec<PathBuf>,
    /// Meshes referenced by the path they were read from.
    pub referenced: Vec<PathBuf>,
}

/// Why a scene could not be written.
#[derive(Debug, Error)]
pub enum WriteError {
    /// Part of the scene has no TOML spelling.
    #[error("{part}: {why}")]
    Unsupported {
        /// The part (`object 3 (`name`)`, `material `glass``).
        part: String,
        /// What cannot be written.
        why: String,
    },
    /// A file could not be written.
    #[error("{0}")]
    Output(#[from] OutputError),
    /// The text written does not read back (a bug of the writer: the
    /// scene it describes is refused).
    #[error("the scene written does not load back: {0}")]
    Reload(Box<super::SceneError>),
    /// The text written reads back as another scene.
    #[error("the scene written loads back differently: {0}")]
    Differs(String),
}

impl WriteError {
    /// True when the cause is the input or the output place (exit code 2):
    /// a scene caustic cannot write, an output it cannot create.
    pub fn is_input(&self) -> bool {
        matches!(self, WriteError::Unsupported { .. } | WriteError::Output(_))
    }
}

/// Writes `scene` to `out` as caustic's TOML, meshes built in memory as
/// PLY files named after `out` in its directory (`out-mesh-3.ply`), and
/// checks that the text loads back to the same scene before writing it.
pub fn write_toml_scene(loaded: &LoadedScene, out: &Path) -> Result<Written, WriteError> {
    let LoadedScene { scene, settings } = loaded;
    crate::film::output::check_writable(out)?;
    let dir = output_dir(out);
    let stem = out
        .file_stem()
        .map_or_else(|| "scene".to_string(), |s| s.to_string_lossy().into_owned());
    let meshes = objects::plan_meshes(scene, &dir, &stem)?;
    let mut doc = Table::new();
    doc.insert(
        "render".into(),
        Value::Table(settings::render(settings, scene.ambient, &scene.media)?),
    );
    doc.insert("photons".into(), Value::Table(settings::photons(&settings.photons)));
    doc.insert("camera".into(), Value::Table(settings::camera(&scene.camera, scene)?));
    let names = materials::Names::of(scene)?;
    doc.insert("materials".into(), Value::Table(materials::materials(&names, &dir)?));
    let lights = scene
        .lights
        .iter()
        .enumerate()
        .map(|(i, l)| lights::light(i, l, &dir).map(Value::Table))
        .collect::<Result<Vec<_>, _>>()?;
    doc.insert("lights".into(), Value::Array(lights));
    let objects = scene
        .objects
        .iter()
        .enumerate()
        .map(|(i, o)| Value::Table(objects::object(scene, i, o, &names, &meshes)))
        .collect();
    doc.insert("objects".into(), Value::Array(objects));
    if !scene.media.list.is_empty() {
        doc.insert("media".into(), Value::Table(media::media(scene)?));
    }
    if let Some(m) = &scene.water_medium {
        doc.insert("medium".into(), Value::Table(media::water_medium(m)));
    }
    let text = format!(
        "# Written by `caustic convert`: numbers are single-precision values written exactly.\n\n{}",
        toml::to_string(&doc).map_err(|e| WriteError::Differs(format!("TOML serialisation: {e}")))?
    );
    let written = objects::write_meshes(scene, &meshes)?;
    let check = super::parse_scene(&text, out)
        .map_err(|e| WriteError::Reload(Box::new(e)))
        .and_then(|again| match super::compare::first_difference(loaded, &again) {
            None => Ok(()),
            Some(d) => Err(WriteError::Differs(d)),
        });
    if let Err(e) = check {
        for p in &written {
            // Best effort: the error says what went wrong; a file left
            // here is complete, not half written.
            let _ = std::fs::remove_file(p);
        }
        return Err(e);
    }
    write_text(out, &text)?;
    Ok(Written {
        scene: out.to_path_buf(),
        meshes: written,
        referenced: meshes.referenced(),
    })
}

/// The directory `out` is written in (`.` for a bare file name).
/// Writes `text` to `path` atomically (complete or not at all).
fn write_text(path: &Path, text: &str) -> Result<(), OutputError> {
    crate::film::output::write_atomically(path, |w| {
        use std::io::Write;
        w.write_all(text.as_bytes()).map_err(|source| OutputError::Io {
            path: path.to_path_buf(),
            what: "writing",
            source,
        })
    })
}

fn output_dir(out: &Path) -> PathBuf {
    match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// `target` as the file written in `dir` names it: relative to `dir` when
/// both resolve on the file system, else absolute.
fn path_from(dir: &Path, target: &Path) -> String {
    let (Ok(dir), Ok(target)) = (std::fs::canonicalize(dir), std::fs::canonicalize(target)) else {
        return target.display().to_string();
    };
    let d: Vec<Component> = dir.components().collect();
    let t: Vec<Component> = target.components().collect();
    let common = d.iter().zip(&t).take_while(|(a, b)| a == b).count();
    if common == 0 {
        return target.display().to_string();
    }
    let mut rel = PathBuf::new();
    for _ in common..d.len() {
        rel.push("..");
    }
    for c in &t[common..] {
        rel.push(c);
    }
    // TOML and the loaders take `/` on every platform.
    rel.to_string_lossy().replace('\\', "/")
}

/// `x` as a TOML number that reads back as the same `f32`: the shortest
/// decimal when it does, else the exact double.
fn num(x: f32) -> Value {
    let short: f64 = format!("{x}").parse().unwrap_or(f64::from(x));
    Value::Float(if short as f32 == x { short } else { f64::from(x) })
}

/// `[x, y, z]`.
fn vec3(v: crate::math::Vec3A) -> Value {
    Value::Array(vec![num(v.x), num(v.y), num(v.z)])
}

/// A whole number written as an integer.
fn int(x: impl Into<i64>) -> Value {
    Value::Integer(x.into())
}

/// A string value.
fn string(s: &str) -> Value {
    Value::String(s.to_string())
}

/// The error for a part with no TOML spelling.
fn unsupported(part: impl Into<String>, why: impl Into<String>) -> WriteError {
    WriteError::Unsupported {
        part: part.into(),
        why: why.into(),
    }
}

/// The `f32` number of degrees whose conversion to radians, as the loader
/// does it, gives `radians` exactly (the nearest candidates to the
/// mathematical value are tried), or `None`.
fn degrees_for(radians: f32) -> Option<f32> {
    let d = radians.to_degrees();
    (0..=8)
        .flat_map(|k| [ulps(d, k), ulps(d, -k)])
        .find(|c| c.to_radians() == radians)
}

/// `x` moved by `steps` units in the last place.
fn ulps(x: f32, steps: i32) -> f32 {
    let mut y = x;
    for _ in 0..steps.unsigned_abs() {
        y = if steps > 0 { y.next_up() } else { y.next_down() };
    }
    y
}

/// A vector the loader's normalisation turns into `unit` exactly: `unit`
/// itself, or `unit` scaled so that its largest or smallest component is
/// ±1 (how directions are usually written), each tried with its
/// components moved by up to two units in the last place.
fn normalizes_to(unit: crate::math::Vec3A) -> Option<crate::math::Vec3A> {
    let steps = [0, 1, -1, 2, -2];
    starts(&unit.to_array()).into_iter().find_map(|s| {
        let s = crate::math::Vec3A::from_array([s[0], s[1], s[2]]);
        steps.iter().find_map(|&dx| {
            steps.iter().find_map(|&dy| {
                steps.iter().find_map(|&dz| {
                    let v = crate::math::Vec3A::new(ulps(s.x, dx), ulps(s.y, dy), ulps(s.z, dz));
                    (v.normalize() == unit).then_some(v)
                })
            })
        })
    })
}

/// [`normalizes_to`] in the plane (a water wave's direction).
fn normalizes_to_2d(unit: crate::math::Vec2) -> Option<crate::math::Vec2> {
    let steps = [0, 1, -1, 2, -2];
    starts(&unit.to_array()).into_iter().find_map(|s| {
        steps.iter().find_map(|&dx| {
            steps.iter().find_map(|&dy| {
                let v = crate::math::Vec2::new(ulps(s[0], dx), ulps(s[1], dy));
                (v.try_normalize() == Some(unit)).then_some(v)
            })
        })
    })
}

/// Where [`normalizes_to`] searches: the unit vector, and it divided by
/// its largest and by its smallest non-zero component's magnitude.
fn starts(c: &[f32]) -> Vec<Vec<f32>> {
    let mut out = vec![c.to_vec()];
    let abs = c.iter().map(|x| x.abs()).filter(|x| *x > 0.0);
    let (max, min) = abs.fold((0f32, f32::INFINITY), |(a, b), x| (a.max(x), b.min(x)));
    for k in [max, min] {
        if k > 0.0 && k.is_finite() {
            out.push(c.iter().map(|x| x / k).collect());
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_read_back_as_the_same_single_precision_value() {
        for x in [0.1f32, 1.0 / 3.0, 1e-8, 3.4e38, -0.0, 12.5, 0.95] {
            let Value::Float(f) = num(x) else { panic!() };
            assert_eq!((f as f32).to_bits(), x.to_bits(), "{x}");
        }
    }

    #[test]
    fn directions_are_found_that_normalise_to_a_unit_vector() {
        let u = crate::math::Vec2::new(0.1, 1.0).normalize();
        assert_eq!(normalizes_to_2d(u).and_then(|v| v.try_normalize()), Some(u));
        let d = crate::math::Vec3A::new(0.3, -0.5, -1.0).normalize();
        assert_eq!(normalizes_to(d).map(|v| v.normalize()), Some(d));
    }

    #[test]
    fn degrees_are_found_for_radians() {
        for deg in [20.0f32, 15.0, 33.3, 90.0, 0.0, -45.0] {
            let r = deg.to_radians();
            assert_eq!(degrees_for(r).map(f32::to_radians), Some(r));
        }
    }

    #[test]
    fn paths_are_written_relative_to_the_output() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(dir.path().join("a/b")).unwrap();
        std::fs::create_dir_all(dir.path().join("c")).unwrap();
        std::fs::write(dir.path().join("c/m.ply"), "").unwrap();
        assert_eq!(
            path_from(&dir.path().join("a/b"), &dir.path().join("c/m.ply")),
            "../../c/m.ply"
        );
        assert_eq!(path_from(&dir.path().join("c"), &dir.path().join("c/m.ply")), "m.ply");
    }
}
