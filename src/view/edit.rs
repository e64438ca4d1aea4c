//! The scene as the viewer edits it: the loaded [`Scene`], the orbit camera,
//! each light's colour and intensity kept apart (the scene stores their
//! product), and, for a caustic TOML file, its document. Saving goes
//! through the scene's writers ([`crate::scene::write`]): a TOML file gets
//! the edits written into its document, comments and layout kept
//! ([`TomlDocument`]); a scene of another format (Mitsuba XML, glTF) is
//! written whole as caustic TOML, as `caustic convert` writes it.

use super::orbit::Orbit;
use crate::bsdf::{whitted_flags, LobeFlags};
use crate::math::Vec3A;
use crate::scene::write::{CameraFraming, LightSplit, TomlDocument};
use crate::scene::{self, IntegratorKind, Light, LoadedScene, Projection, RenderSettings, Scene, SceneError};
use std::path::{Path, PathBuf};

/// A light's parameters as the panel shows them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightEdit {
    /// Position (point light) or centre (area light); unused for an
    /// environment.
    pub position: Vec3A,
    /// Colour (the file's `colour`).
    pub colour: Vec3A,
    /// Scale on the colour (the file's `intensity`).
    pub intensity: f32,
    /// Area light: shadow rays per shading point.
    pub samples: u32,
    /// Spot light: the file's `look_at`, which keeps aiming the cone when
    /// the light moves (as the saved file will).
    pub look_at: Option<Vec3A>,
}

/// A scene being edited.
#[derive(Clone)]
pub struct EditableScene {
    /// The scene file.
    pub path: PathBuf,
    /// The scene with every edit applied (what the next pass renders).
    pub scene: Scene,
    /// The render settings, edited in the panel.
    pub settings: RenderSettings,
    /// The camera.
    pub orbit: Orbit,
    /// The camera of the file, for "reset camera".
    pub initial_orbit: Orbit,
    /// One per scene light.
    pub lights: Vec<LightEdit>,
    /// The TOML document of the file; `None` when the scene was read from
    /// another format.
    doc: Option<TomlDocument>,
    /// The file's orthographic half width and half height, which the orbit
    /// scales together (its zoom), so that the rectangle still fits the
    /// viewer's image whatever its aspect ratio.
    orthographic: Option<(f32, f32)>,
}

/// Why the viewer could not save.
#[derive(Debug, thiserror::Error)]
pub enum SaveError {
    /// The scene could not be written as TOML.
    #[error("{0}")]
    Convert(#[from] crate::scene::write::WriteError),
    /// The scene file is not caustic TOML: only a whole scene can be saved.
    #[error("{0} is not a caustic TOML file: save the scene as TOML instead")]
    NotToml(PathBuf),
}

/// Half the vertical field of view of the frustum an orthographic camera's
/// orbit starts with, when the file names no point looked at.
const ORTHOGRAPHIC_ORBIT_HALF_FOV_DEG: f32 = 20.0;

impl EditableScene {
    /// Loads `path` (validated like `caustic render` does).
    pub fn open(path: &Path) -> Result<Self, SceneError> {
        Self::open_with(path, &scene::LoadOptions::default())
    }

    /// [`open`](Self::open) with the command line's options (`-D`, a glTF
    /// model's camera).
    pub fn open_with(path: &Path, options: &scene::LoadOptions) -> Result<Self, SceneError> {
        // The loader checks size, encoding and every value first.
        let loaded = scene::load_scene_options(path, options)?;
        let doc = if scene::is_toml_path(path) {
            Some(TomlDocument::read(path)?)
        } else {
            None
        };
        Ok(Self::from_parts(path, loaded, doc))
    }

    fn from_parts(path: &Path, loaded: LoadedScene, doc: Option<TomlDocument>) -> Self {
        let LoadedScene { scene, settings } = loaded;
        let cam = &scene.camera;
        let scene_projection = cam.projection;
        let s = &settings;
        let aspect = s.width as f32 / s.height as f32;
        // An orthographic camera orbits a target placed where a 40° frustum
        // spans its image height, unless the file names the point looked at.
        let half_height = cam.half_extents(aspect).1;
        let ahead = if cam.is_orthographic() {
            half_height / ORTHOGRAPHIC_ORBIT_HALF_FOV_DEG.to_radians().tan()
        } else {
            1.0
        };
        let target = doc
            .as_ref()
            .and_then(|d| d.camera_vec3("look_at"))
            .unwrap_or(cam.position + cam.forward * ahead);
        let up = doc
            .as_ref()
            .and_then(|d| d.camera_vec3("up"))
            .unwrap_or(if doc.is_some() { Vec3A::Y } else { cam.up });
        // The orbit keeps a vertical field of view: the file's, whatever axis
        // it spans; for an orthographic camera, the one whose frustum spans
        // the image height at the target (zooming then scales the image).
        let vfov = if cam.is_orthographic() {
            2.0 * (half_height / (target - cam.position).length()).atan().to_degrees()
        } else {
            cam.vertical_fov_deg(aspect)
        };
        let orbit = Orbit::looking_at(cam.position, target, up, vfov)
            .or_else(|| Orbit::looking_at(cam.position, cam.position + cam.forward, cam.up, vfov))
            .expect("a valid camera has a view direction");
        let lights = scene
            .lights
            .iter()
            .enumerate()
            .map(|(i, light)| {
                let keys = doc.as_ref().and_then(|d| d.light_keys(i));
                // Without the file's split, the colour is the light's own
                // product and the intensity 1.
                let colour = keys.and_then(|k| k.colour).unwrap_or_else(|| {
                    if keys.is_some() {
                        Vec3A::ONE
                    } else {
                        light_power(light)
                    }
                });
                let intensity = keys.and_then(|k| k.intensity).unwrap_or(1.0);
                let position = light.position().unwrap_or(Vec3A::ZERO);
                let samples = match light {
                    Light::Area(a) => a.samples,
                    _ => 1,
                };
                LightEdit {
                    position,
                    colour,
                    intensity,
                    samples,
                    look_at: keys.and_then(|k| k.look_at),
                }
            })
            .collect();
        Self {
            path: path.to_path_buf(),
            scene,
            settings,
            orbit,
            initial_orbit: orbit,
            orthographic: match scene_projection {
                Projection::Orthographic {
                    half_width,
                    half_height,
                } => Some((half_width, half_height)),
                Projection::Perspective => None,
            },
            lights,
            doc,
        }
    }

    /// The file's orthographic half extents scaled by the orbit's zoom
    /// against the file's; `None` for a perspective camera.
    fn orthographic_halves(&self) -> Option<(f32, f32)> {
        let (w, h) = self.orthographic?;
        let k = self.orbit.orthographic_half_height() / self.initial_orbit.orthographic_half_height();
        let k = if k.is_finite() && k > 0.0 { k } else { 1.0 };
        Some((w * k, h * k))
    }

    /// Copies the camera and the light edits into [`Self::scene`]; call after
    /// changing [`Self::orbit`] or [`Self::lights`].
    pub fn apply(&mut self) {
        if let Some(cam) = self.orbit.camera() {
            let old = &self.scene.camera;
            // The lens (its focus included), the near plane and the pixel
            // filter are the file's; the orbit moves the eye.
            let focus_distance = if old.has_lens() {
                old.focus_distance
            } else {
                cam.focus_distance
            };
            let projection = match self.orthographic_halves() {
                Some((half_width, half_height)) => Projection::Orthographic {
                    half_width,
                    half_height,
                },
                None => Projection::Perspective,
            };
            self.scene.camera = crate::scene::Camera {
                projection,
                aperture_radius: old.aperture_radius,
                focus_distance,
                near_clip: old.near_clip,
                filter: old.filter.clone(),
                ..cam
            };
        }
        for (light, edit) in self.scene.lights.iter_mut().zip(&self.lights) {
            // The loader's product, in the same order, so a saved file
            // loads to the same f32 values.
            let power = edit.colour * edit.intensity;
            match light {
                Light::Point { position, intensity } => {
                    *position = edit.position;
                    *intensity = power;
                }
                Light::Area(a) => {
                    a.center = edit.position;
                    a.radiance = power;
                    a.samples = edit.samples.max(1);
                }
                Light::Spot(s) => {
                    s.position = edit.position;
                    s.intensity = power;
                    if let Some(axis) = edit.look_at.and_then(|t| (t - edit.position).try_normalize()) {
                        s.axis = axis;
                    }
                }
                Light::Directional { irradiance, .. } => *irradiance = power,
                Light::Environment { radiance, .. } => *radiance = power,
            }
        }
    }

    /// The scene and its settings as edited (what the next pass renders).
    pub fn snapshot(&self) -> LoadedScene {
        LoadedScene {
            scene: self.scene.clone(),
            settings: self.settings.clone(),
        }
    }

    /// The scene file's text with every edit written in (`None` for a
    /// scene read from another format).
    pub fn to_toml(&self) -> Option<String> {
        let doc = self.doc.as_ref()?;
        Some(doc.with_scene(&self.snapshot(), &self.framing(), &self.light_splits()))
    }

    /// The scene file's text with only the camera changed (to the view's).
    pub fn camera_toml(&self) -> Option<String> {
        Some(self.doc.as_ref()?.with_camera(&self.framing()))
    }

    /// The view's camera as the file frames it.
    fn framing(&self) -> CameraFraming {
        CameraFraming {
            eye: self.orbit.eye(),
            target: self.orbit.target,
            up: self.orbit.up,
            vfov_deg: self.orbit.vfov_deg,
            orthographic: self.orthographic_halves(),
        }
    }

    fn light_splits(&self) -> Vec<LightSplit> {
        self.lights
            .iter()
            .map(|l| LightSplit {
                colour: l.colour,
                intensity: l.intensity,
            })
            .collect()
    }

    /// Writes the edited scene to `path` atomically, through the scene's
    /// writer; `caustic render path` then renders what the viewer shows. A
    /// TOML file keeps its comments and layout; a scene of another format is
    /// written whole as caustic TOML (meshes it built as PLY files beside
    /// it), as `caustic convert` writes it.
    pub fn save(&self, path: &Path) -> Result<(), SaveError> {
        match &self.doc {
            Some(doc) => doc.save(&self.snapshot(), &self.framing(), &self.light_splits(), path)?,
            None => {
                crate::scene::write::write_toml_scene(&self.snapshot(), path)?;
            }
        }
        Ok(())
    }

    /// Writes the view's camera into the scene file's `[camera]` (nothing
    /// else of the file changes), atomically; only for a TOML file.
    pub fn save_camera(&self) -> Result<(), SaveError> {
        let doc = self.doc.as_ref().ok_or_else(|| SaveError::NotToml(self.path.clone()))?;
        Ok(doc.save_camera(&self.framing())?)
    }
}

/// A light's emitted colour as the scene stores it (colour × intensity).
fn light_power(light: &Light) -> Vec3A {
    match light {
        Light::Point { intensity, .. } => *intensity,
        Light::Spot(s) => s.intensity,
        Light::Directional { irradiance, .. } => *irradiance,
        Light::Area(a) => a.radiance,
        Light::Environment { radiance, .. } => *radiance,
    }
}

/// True when the photon pass of `a` and of `b` trace the same photons: the
/// lights, the photon settings, the bounce limit, the medium and every
/// specular material (a caster or a surface photons pass through) are the
/// same, and no material changed between diffuse and specular. Camera
/// moves and edits of diffuse materials keep the map.
pub fn same_photons(a: &LoadedScene, b: &LoadedScene) -> bool {
    let (sa, sb) = (&a.settings, &b.settings);
    let (a, b) = (&a.scene, &b.scene);
    a.lights == b.lights
        && sa.photons == sb.photons
        && sa.max_depth == sb.max_depth
        && sa.seed == sb.seed
        && a.water_medium == b.water_medium
        && sa.integrator == sb.integrator
        && (sa.width, sa.height) == (sb.width, sb.height)
        && a.objects == b.objects
        && a.materials.len() == b.materials.len()
        && a.materials.iter().zip(&b.materials).all(|(ma, mb)| {
            let (fa, fb) = (whitted_flags(ma), whitted_flags(mb));
            ma == mb
                || (!fa.contains(LobeFlags::CASTS_CAUSTICS)
                    && !fb.contains(LobeFlags::CASTS_CAUSTICS)
                    // The path integrator's photons reflect off clear
                    // coats with a probability that depends on the colour.
                    && (sa.integrator == IntegratorKind::Whitted || ma.coating.is_none())
                    && fa.contains(LobeFlags::DIFFUSE) == fb.contains(LobeFlags::DIFFUSE)
                    && ma.coating == mb.coating
                    && ma.conductor == mb.conductor
                    && ma.dielectric == mb.dielectric)
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCENE: &str = r#"
# a comment that survives saving
[render]
width = 32
height = 24
spp = 4

[camera]
position = [0, 1, 4]
look_at = [0, 0.5, 0]
vfov = 45

[materials.white]
diffuse = [0.7, 0.7, 0.7]

[materials.glass.dielectric]
ior = 1.5

[[lights]]
type = "point"
position = [0, 2, 1]
color = [1, 0.9, 0.8]
intensity = 3

[[objects]]
type = "sphere"
center = [0, 0.5, 0]
radius = 0.5
material = "glass"

[[objects]]
type = "quad"
center = [0, 0, 0]
size = [4, 4]
normal = [0, 1, 0]
material = "white"
"#;

    fn open_text(dir: &Path, text: &str) -> EditableScene {
        let p = dir.join("s.toml");
        std::fs::write(&p, text).unwrap();
        EditableScene::open(&p).unwrap()
    }

    /// A Mitsuba scene opens, its edits apply, and "save scene" writes it as
    /// caustic TOML that loads back to the edited scene; writing the camera
    /// into the XML file is refused.
    #[test]
    fn a_mitsuba_scene_is_edited_and_saved_as_toml() {
        let xml = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba/room.xml");
        let mut e = EditableScene::open(&xml).unwrap();
        assert!(e.to_toml().is_none());
        let before = e.scene.lights.clone();
        assert!(
            !before.is_empty()
                || e.scene
                    .objects
                    .iter()
                    .any(|o| e.scene.materials[o.material as usize].emits())
        );
        for l in &mut e.lights {
            l.intensity = 2.0;
        }
        e.orbit = e.initial_orbit;
        e.apply();
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("room.toml");
        e.save(&out).unwrap();
        let again = scene::load_scene(&out).unwrap();
        assert_eq!(crate::scene::compare::first_difference(&again, &e.snapshot()), None);
        assert_ne!(again.scene.lights, before, "the edit is saved");
        assert!(matches!(e.save_camera(), Err(SaveError::NotToml(_))));
    }

    #[test]
    fn unedited_scene_saves_to_the_same_scene() {
        let dir = tempfile::tempdir().unwrap();
        let e = open_text(dir.path(), SCENE);
        assert_eq!(e.lights[0].intensity, 3.0);
        assert_eq!(e.lights[0].colour, Vec3A::new(1.0, 0.9, 0.8));
        let out = dir.path().join("saved.toml");
        e.save(&out).unwrap();
        let text = std::fs::read_to_string(&out).unwrap();
        assert!(text.contains("# a comment that survives saving"));
        let again = scene::load_scene(&out).unwrap();
        assert_eq!(again.scene.lights, e.scene.lights);
        assert_eq!(again.scene.materials, e.scene.materials);
        assert!((again.scene.camera.position - e.scene.camera.position).length() < 1e-5);
    }

    #[test]
    fn edits_are_applied_and_saved() {
        let dir = tempfile::tempdir().unwrap();
        let mut e = open_text(dir.path(), SCENE);
        e.lights[0].position = Vec3A::new(0.5, 2.5, 1.25);
        e.lights[0].intensity = 7.3;
        e.orbit.rotate(50.0, 10.0, 100.0);
        e.scene.materials[1].diffuse = Vec3A::new(0.1, 0.2, 0.3);
        e.scene.materials[0].dielectric.as_mut().unwrap().ior = 1.33;
        e.settings.spp = 9;
        e.settings.photons.count = 1234;
        e.apply();
        let out = dir.path().join("edited.toml");
        e.save(&out).unwrap();
        let again = scene::load_scene(&out).unwrap();
        assert_eq!(again.scene.lights, e.scene.lights);
        assert_eq!(again.scene.materials, e.scene.materials);
        assert_eq!(again.settings.spp, 9);
        assert_eq!(again.settings.photons.count, 1234);
        let (a, b) = (again.scene.camera, e.scene.camera);
        assert!((a.position - b.position).length() < 1e-5);
        assert!((a.forward - b.forward).length() < 1e-5);
    }

    #[test]
    fn photon_map_is_kept_for_camera_and_diffuse_edits_only() {
        let dir = tempfile::tempdir().unwrap();
        let e = open_text(dir.path(), SCENE);
        let mut b = e.clone();
        b.orbit.zoom(2.0);
        b.scene
            .materials
            .iter_mut()
            .find(|m| m.name == "white")
            .unwrap()
            .diffuse = Vec3A::splat(0.2);
        b.apply();
        assert!(same_photons(&e.snapshot(), &b.snapshot()));
        let mut c = e.clone();
        c.scene
            .materials
            .iter_mut()
            .find(|m| m.name == "glass")
            .unwrap()
            .dielectric
            .as_mut()
            .unwrap()
            .ior = 1.2;
        assert!(!same_photons(&e.snapshot(), &c.snapshot()));
        let mut d = e.clone();
        d.lights[0].intensity = 1.0;
        d.apply();
        assert!(!same_photons(&e.snapshot(), &d.snapshot()));
    }
}
