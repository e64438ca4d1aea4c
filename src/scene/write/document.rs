//! A caustic TOML scene file written back with edits, its comments and
//! layout kept: the TOML front end's save for a scene that was read from
//! TOML (the viewer's "save" and "save camera"). A scene of another format
//! is written whole by [`super::write_toml_scene`].
//!
//! Only what an edit can change is written: the camera's framing, the
//! samples per pixel, the bounce limit and the photon count, each light's
//! position, colour, intensity and shadow samples, and the Phong and
//! dielectric parameters of each material. A saved file is read back and
//! must load to the scene it was saved from (its camera is the framing
//! given), or nothing is written.

use super::WriteError;
use crate::math::Vec3A;
use crate::scene::{Light, LoadedScene, Material, SceneError, ShadingModel};
use std::path::{Path, PathBuf};
use toml_edit::{value, Array, DocumentMut, Item, Table, TableLike, Value};

/// A caustic TOML scene file as read, text and layout kept.
#[derive(Clone, Debug)]
pub struct TomlDocument {
    path: PathBuf,
    doc: DocumentMut,
}

/// The camera as a viewer frames it: where it is, the point it looks at,
/// its up direction, and its extent (a vertical field of view, or an
/// orthographic camera's half width and half height).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraFraming {
    /// The eye.
    pub eye: Vec3A,
    /// The point looked at.
    pub target: Vec3A,
    /// The up direction.
    pub up: Vec3A,
    /// Vertical field of view in degrees (perspective cameras).
    pub vfov_deg: f32,
    /// Half width and half height of an orthographic camera's rectangle.
    pub orthographic: Option<(f32, f32)>,
}

/// A light's emission as the file splits it, `colour × intensity` (the
/// scene stores the product).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSplit {
    /// The file's `colour`.
    pub colour: Vec3A,
    /// The file's `intensity`.
    pub intensity: f32,
}

/// What the file says of light `i`, where it says it: its `colour`, its
/// `intensity` and the point its cone aims at (`look_at`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LightKeys {
    /// `colour` (or `color`).
    pub colour: Option<Vec3A>,
    /// `intensity`.
    pub intensity: Option<f32>,
    /// `look_at`.
    pub look_at: Option<Vec3A>,
}

impl TomlDocument {
    /// Reads the TOML document of `path` (a file the loader has accepted).
    pub fn read(path: &Path) -> Result<Self, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|error| SceneError::Read {
            path: path.to_path_buf(),
            error,
        })?;
        let doc: DocumentMut = text.parse().map_err(|e: toml_edit::TomlError| SceneError::Toml {
            path: path.to_path_buf(),
            place: None,
            message: e.message().to_string(),
        })?;
        Ok(Self {
            path: path.to_path_buf(),
            doc,
        })
    }

    /// The file the document was read from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// A point or direction of the `[camera]` table (`look_at`, `up`).
    pub fn camera_vec3(&self, key: &str) -> Option<Vec3A> {
        vec3_of(self.doc.get("camera")?.get(key))
    }

    /// The keys of the `i`-th `[[lights]]` table, `None` when it has none.
    pub fn light_keys(&self, i: usize) -> Option<LightKeys> {
        let t = self.doc.get("lights")?.as_array_of_tables()?.get(i)?;
        Some(LightKeys {
            colour: vec3_of(t.get("colour").or_else(|| t.get("color"))),
            intensity: number_of(t.get("intensity")),
            look_at: vec3_of(t.get("look_at")),
        })
    }

    /// The document with only its camera changed to `framing`.
    pub fn with_camera(&self, framing: &CameraFraming) -> String {
        let mut doc = self.doc.clone();
        write_camera(&mut doc, framing);
        doc.to_string()
    }

    /// The document with `loaded`'s editable values written in: the
    /// camera as `framing`, lights split as `lights` (one per scene light).
    pub fn with_scene(&self, loaded: &LoadedScene, framing: &CameraFraming, lights: &[LightSplit]) -> String {
        self.edited(loaded, framing, lights).to_string()
    }

    fn edited(&self, loaded: &LoadedScene, framing: &CameraFraming, lights: &[LightSplit]) -> DocumentMut {
        let mut doc = self.doc.clone();
        write_camera(&mut doc, framing);
        write_values(&mut doc, loaded, lights);
        doc
    }

    /// Writes the document with `loaded`'s values to `out` atomically (see
    /// [`Self::with_scene`]); mesh files are named so that they are found
    /// from `out`'s directory. The text must load back to `loaded` (its
    /// camera aside, which is `framing`'s), or nothing is written and the
    /// difference is the error.
    pub fn save(
        &self,
        loaded: &LoadedScene,
        framing: &CameraFraming,
        lights: &[LightSplit],
        out: &Path,
    ) -> Result<(), WriteError> {
        let mut doc = self.edited(loaded, framing, lights);
        rebase_mesh_files(&mut doc, &self.path, out);
        let text = doc.to_string();
        let mut again = crate::scene::parse_scene(&text, out).map_err(|e| WriteError::Reload(Box::new(e)))?;
        // The camera is written as `framing` says, which a viewer's orbit
        // gives to the last bits of its own arithmetic: the rest must match.
        again.scene.camera = loaded.scene.camera.clone();
        if let Some(d) = crate::scene::compare::first_difference(loaded, &again) {
            return Err(WriteError::Differs(d));
        }
        Ok(super::write_text(out, &text)?)
    }

    /// Writes `framing` into the file's `[camera]`, nothing else changed,
    /// atomically.
    pub fn save_camera(&self, framing: &CameraFraming) -> Result<(), WriteError> {
        Ok(super::write_text(&self.path, &self.with_camera(framing))?)
    }
}

fn number(v: &Value) -> Option<f64> {
    v.as_float().or_else(|| v.as_integer().map(|i| i as f64))
}

fn vec3_of(item: Option<&Item>) -> Option<Vec3A> {
    let a = item?.as_array()?;
    if a.len() != 3 {
        return None;
    }
    let x: Vec<f64> = a.iter().filter_map(number).collect();
    (x.len() == 3).then(|| Vec3A::new(x[0] as f32, x[1] as f32, x[2] as f32))
}

fn number_of(item: Option<&Item>) -> Option<f32> {
    item?.as_value().and_then(number).map(|x| x as f32)
}

/// The shortest decimal that reads back as `x` through the scene loader
/// (which parses an f64 and rounds it to f32).
fn toml_number(x: f32) -> Value {
    let short: f64 = format!("{x}").parse().unwrap_or(x as f64);
    if short as f32 == x {
        Value::from(short)
    } else {
        Value::from(x as f64)
    }
}

fn toml_vec3(v: Vec3A) -> Item {
    let mut a = Array::new();
    for x in v.to_array() {
        a.push(toml_number(x));
    }
    value(a)
}

/// The table at `key` of `table` (standard or inline), created as a
/// standard table if missing.
fn table_mut<'t>(table: &'t mut dyn TableLike, key: &str) -> &'t mut dyn TableLike {
    if !table.contains_key(key) {
        let mut t = Table::new();
        t.set_implicit(false);
        table.insert(key, Item::Table(t));
    }
    table
        .get_mut(key)
        .and_then(Item::as_table_like_mut)
        .expect("a table (checked by the loader)")
}

/// Sets `key` of `table` to `item`, keeping its place when it exists.
fn set(table: &mut dyn TableLike, key: &str, item: Item) {
    match table.get_mut(key) {
        Some(slot) => *slot = item,
        None => {
            table.insert(key, item);
        }
    }
}

fn write_camera(doc: &mut DocumentMut, f: &CameraFraming) {
    let cam = table_mut(doc.as_table_mut(), "camera");
    set(cam, "position", toml_vec3(f.eye));
    set(cam, "look_at", toml_vec3(f.target));
    set(cam, "up", toml_vec3(f.up));
    if let Some((w, h)) = f.orthographic {
        for (key, x) in [("half_width", w), ("half_height", h)] {
            if x > 0.0 {
                set(cam, key, value(toml_number(x)));
            } else {
                cam.remove(key);
            }
        }
        cam.remove("vfov");
    } else {
        set(cam, "vfov", value(toml_number(f.vfov_deg)));
    }
    // `vfov` (or `half_height`) now says the extent: an axis would contradict it.
    cam.remove("fov");
    cam.remove("fov_axis");
}

fn write_values(doc: &mut DocumentMut, loaded: &LoadedScene, splits: &[LightSplit]) {
    let (scene, s) = (&loaded.scene, &loaded.settings);
    let root = doc.as_table_mut();
    {
        let render = table_mut(root, "render");
        set(render, "spp", value(s.spp as i64));
        if let Some(d) = s.max_depth {
            set(render, "max_depth", value(d as i64));
        }
    }
    set(table_mut(root, "photons"), "count", value(s.photons.count as i64));
    if let Some(tables) = root.get_mut("lights").and_then(|l| l.as_array_of_tables_mut()) {
        for ((t, light), split) in tables.iter_mut().zip(&scene.lights).zip(splits) {
            t.remove("color");
            set(t, "colour", toml_vec3(split.colour));
            set(t, "intensity", value(toml_number(split.intensity)));
            match light {
                Light::Point { position, .. } => set(t, "position", toml_vec3(*position)),
                Light::Spot(spot) => set(t, "position", toml_vec3(spot.position)),
                Light::Area(a) => {
                    set(t, "position", toml_vec3(a.center));
                    set(t, "samples", value(a.samples.max(1) as i64));
                }
                Light::Environment { .. } | Light::Directional { .. } => {}
            }
        }
    }
    let materials = table_mut(root, "materials");
    for m in &scene.materials {
        write_material(table_mut(materials, &m.name), m);
    }
}

fn write_material(t: &mut dyn TableLike, m: &Material) {
    let model = match m.model {
        ShadingModel::Phong => "phong",
        ShadingModel::BlinnPhong => "blinn-phong",
    };
    set(t, "model", value(model));
    set(t, "ambient", toml_vec3(m.ambient));
    set(t, "diffuse", toml_vec3(m.diffuse));
    set(t, "specular", toml_vec3(m.specular));
    set(t, "shininess", value(toml_number(m.shininess)));
    match m.mirror {
        Some(mirror) => {
            let mt = table_mut(t, "mirror");
            set(mt, "reflectivity", value(toml_number(mirror.reflectivity)));
            set(mt, "tint", toml_vec3(mirror.tint));
        }
        None => {
            t.remove("mirror");
        }
    }
    if let Some(d) = m.dielectric {
        let dt = table_mut(t, "dielectric");
        set(dt, "ior", value(toml_number(d.ior)));
        set(dt, "tint", toml_vec3(d.tint));
    }
}

/// Mesh files are relative to the scene file: a scene saved into another
/// directory names them by absolute path (`asset:` names stay).
fn rebase_mesh_files(doc: &mut DocumentMut, from: &Path, to: &Path) {
    let dir = |p: &Path| {
        let d = p
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        d.canonicalize().unwrap_or_else(|_| d.to_path_buf())
    };
    let (from_dir, to_dir) = (dir(from), dir(to));
    if from_dir == to_dir {
        return;
    }
    let Some(objects) = doc.get_mut("objects").and_then(|o| o.as_array_of_tables_mut()) else {
        return;
    };
    for o in objects.iter_mut() {
        let Some(file) = o.get("file").and_then(|f| f.as_str()) else {
            continue;
        };
        if file.starts_with("asset:") || Path::new(file).is_absolute() {
            continue;
        }
        let absolute = from_dir.join(file).display().to_string();
        set(o, "file", value(absolute));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCENE: &str = r#"
# kept when saved
[render]
width = 32
height = 24

[camera]
position = [0, 1, 4]
look_at = [0, 0, 0]
vfov = 40

[materials.white]
diffuse = [0.7, 0.7, 0.7]

[[lights]]
type = "point"
position = [0, 3, 0]
colour = [1, 0.5, 0.25]
intensity = 4

[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = 1
material = "white"
"#;

    fn framing() -> CameraFraming {
        CameraFraming {
            eye: Vec3A::new(0.0, 1.0, 4.0),
            target: Vec3A::ZERO,
            up: Vec3A::Y,
            vfov_deg: 40.0,
            orthographic: None,
        }
    }

    fn open(dir: &Path) -> (TomlDocument, LoadedScene) {
        let p = dir.join("s.toml");
        std::fs::write(&p, SCENE).unwrap();
        (TomlDocument::read(&p).unwrap(), crate::scene::load_scene(&p).unwrap())
    }

    #[test]
    fn the_files_split_of_a_light_is_read() {
        let dir = tempfile::tempdir().unwrap();
        let (doc, _) = open(dir.path());
        let k = doc.light_keys(0).unwrap();
        assert_eq!(k.colour, Some(Vec3A::new(1.0, 0.5, 0.25)));
        assert_eq!(k.intensity, Some(4.0));
        assert_eq!(doc.light_keys(1), None);
        assert_eq!(doc.camera_vec3("look_at"), Some(Vec3A::ZERO));
    }

    #[test]
    fn edits_are_saved_with_the_comments_and_load_back_to_the_scene() {
        let dir = tempfile::tempdir().unwrap();
        let (doc, mut loaded) = open(dir.path());
        loaded.scene.materials[0].diffuse = Vec3A::new(0.1, 0.2, 0.3);
        let split = LightSplit {
            colour: Vec3A::ONE,
            intensity: 2.0,
        };
        if let Light::Point { intensity, .. } = &mut loaded.scene.lights[0] {
            *intensity = split.colour * split.intensity;
        }
        let out = dir.path().join("out.toml");
        doc.save(&loaded, &framing(), &[split], &out).unwrap();
        let text = std::fs::read_to_string(&out).unwrap();
        assert!(text.contains("# kept when saved"));
        let again = crate::scene::load_scene(&out).unwrap();
        assert_eq!(crate::scene::compare::first_difference(&loaded, &again), None);
    }

    #[test]
    fn a_scene_the_document_cannot_say_is_refused_and_nothing_is_written() {
        let dir = tempfile::tempdir().unwrap();
        let (doc, mut loaded) = open(dir.path());
        // Emission is not one of the edits written back.
        loaded.scene.materials[0].emission = Vec3A::ONE;
        let split = LightSplit {
            colour: Vec3A::new(1.0, 0.5, 0.25),
            intensity: 4.0,
        };
        let out = dir.path().join("out.toml");
        let err = doc.save(&loaded, &framing(), &[split], &out).unwrap_err();
        assert!(matches!(err, WriteError::Differs(_)), "{err}");
        assert!(!out.exists());
    }
}
