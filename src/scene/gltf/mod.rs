//! glTF 2.0 models (`.gltf` with its buffers and images, or one `.glb`):
//! `caustic render model.glb`.
//!
//! [`document`] reads the file (the GLB container, the JSON, the
//! specification's validation of every index, the extensions it requires)
//! and its buffers (embedded, data URIs, or files beside the model);
//! [`accessors`] reads typed vertex and index data with every offset and
//! count checked against its buffer before anything is allocated;
//! [`meshes`] turns primitives into caustic meshes (MikkTSpace tangents where
//! a normal map needs them); [`textures`] decodes images and maps samplers
//! and `KHR_texture_transform`; [`materials`] maps the metallic-roughness
//! model and its extensions onto [`crate::scene::Material`]; [`cameras`] and
//! [`lights`] map cameras and `KHR_lights_punctual`; [`nodes`] walks the
//! scene graph, composing transforms and instancing meshes. Every error
//! names the file and the JSON pointer (RFC 6901) of the value at fault.

mod accessors;
pub mod cameras;
mod document;
pub mod lights;
mod materials;
mod meshes;
mod nodes;
mod textures;

use crate::scene::load::SceneError;
use crate::scene::{IntegratorKind, Light, Media, Origin, RenderSettings, Scene, SceneBuilder};
use crate::texture::{ColourSpace, Image};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

pub use cameras::{CameraChoice, DEFAULT_FRAMING_FOV_DEG};
pub use lights::{DEFAULT_ENVIRONMENT_RADIANCE, LUMENS_PER_WATT};

/// Extensions caustic reads; a file that requires any other is refused.
pub const IMPLEMENTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_materials_clearcoat",
    "KHR_texture_transform",
];

/// How a glTF model is read.
#[derive(Clone, Debug, Default)]
pub struct GltfOptions {
    /// The camera to render (`--camera`); `None`: the first camera the
    /// scene's nodes place, or a camera framing the model when there is none.
    pub camera: Option<CameraChoice>,
    /// Let buffer and image URIs name files outside the model's folder
    /// (`--allow-outside-files`); refused otherwise.
    pub allow_outside_files: bool,
}

/// A glTF model as a scene, with what was read but not rendered as warnings.
#[derive(Debug)]
pub struct GltfScene {
    /// The scene.
    pub scene: Scene,
    /// The render settings (the chosen camera's image size, the defaults).
    pub settings: RenderSettings,
    /// Messages about what caustic reads but ignores (extensions used but
    /// not required, attributes it does not render, …).
    pub warnings: Vec<String>,
    /// The file placed no camera: the scene's camera frames the model.
    pub framed_camera: bool,
    /// The file has no punctual light: the scene is lit by the default
    /// environment ([`DEFAULT_ENVIRONMENT_RADIANCE`]).
    pub default_environment: bool,
}

/// True when `path` names a glTF model (by its `.gltf` or `.glb` extension).
pub fn is_gltf_path(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

impl GltfScene {
    /// The scene and its settings, the warnings left out.
    pub fn into_loaded(self) -> crate::scene::LoadedScene {
        crate::scene::LoadedScene {
            scene: self.scene,
            settings: self.settings,
        }
    }
}

/// Reads a glTF 2.0 model as a scene.
pub fn load_gltf_scene(path: &Path, options: &GltfOptions) -> Result<GltfScene, SceneError> {
    let file = document::read(path, options)?;
    let mut ctx = Ctx {
        path,
        dir: path.parent().map_or_else(|| PathBuf::from("."), Path::to_path_buf),
        doc: &file.document,
        buffers: &file.buffers,
        options,
        warnings: file.warnings.clone(),
        images: HashMap::new(),
    };
    let graph = nodes::walk(&mut ctx)?;
    let built = nodes::build(&mut ctx, &graph)?;
    let mut settings = RenderSettings {
        integrator: IntegratorKind::Path,
        width: cameras::DEFAULT_WIDTH,
        height: cameras::DEFAULT_HEIGHT,
        spp: DEFAULT_SPP,
        ..Default::default()
    };
    let mut lights = lights::lights(&ctx, &graph)?;
    let default_environment = lights.is_empty();
    if default_environment {
        lights.push(Light::Environment {
            radiance: glam::Vec3A::splat(DEFAULT_ENVIRONMENT_RADIANCE),
            map: None,
        });
    }
    let media = Media {
        pass_through: if built.media.is_empty() {
            crate::scene::PassThrough::SurfaceBounce
        } else {
            crate::scene::PassThrough::Volumetric
        },
        interfaces: if built.media.is_empty() {
            Vec::new()
        } else {
            built.interfaces
        },
        list: built.media,
        camera: None,
    };
    let mut builder = SceneBuilder::new(path);
    for (material, origin) in built.materials {
        builder.add_material(material, origin);
    }
    for mesh in built.meshes {
        builder.add_mesh(mesh);
    }
    if built.objects.is_empty() {
        return Err(ctx.error(
            "",
            "the model has no triangle to render (no node of its scene places a mesh)",
        ));
    }
    for (object, origin) in built.objects {
        builder.add_object(object, origin);
    }
    for light in lights {
        let pointer = if matches!(light, Light::Environment { .. }) {
            ""
        } else {
            "/extensions/KHR_lights_punctual/lights"
        };
        builder.add_light(light, ctx.origin(pointer));
    }
    builder.set_media(media);
    // The camera may frame the scene's bounds: it is chosen once the scene is built.
    builder.set_camera(cameras::placeholder());
    let mut scene = builder.build()?.scene;
    let mut camera = cameras::placeholder();
    let framed_camera = cameras::choose(&ctx, &graph, &scene, &mut settings, &mut camera)?;
    scene.camera = camera;
    Ok(GltfScene {
        scene,
        settings,
        warnings: ctx.warnings,
        framed_camera,
        default_environment,
    })
}

/// Samples per pixel of a model's render unless the command line says
/// otherwise: enough for a recognisable image of a model in an environment.
pub const DEFAULT_SPP: u32 = 64;

/// What the modules share while the scene is built.
pub(crate) struct Ctx<'a> {
    /// The model file, for messages.
    path: &'a Path,
    /// Its folder: relative URIs resolve against it.
    dir: PathBuf,
    doc: &'a gltf::Document,
    /// Each buffer's bytes (exactly `byteLength` of them).
    buffers: &'a [Vec<u8>],
    options: &'a GltfOptions,
    warnings: Vec<String>,
    /// Decoded images by (image index, colour space).
    images: HashMap<(usize, ColourSpace), Arc<Image>>,
}

impl Ctx<'_> {
    /// An error about the value at `pointer`.
    fn error(&self, pointer: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError::Gltf {
            path: self.path.to_path_buf(),
            pointer: pointer.into(),
            message: message.into(),
        }
    }

    /// The value at `pointer` as the origin of a part of the scene.
    fn origin(&self, pointer: impl Into<String>) -> Origin {
        Origin::Json {
            path: self.path.to_path_buf(),
            pointer: pointer.into(),
        }
    }

    /// A warning about the value at `pointer`, said once.
    fn warn(&mut self, pointer: &str, message: impl Into<String>) {
        let w = if pointer.is_empty() {
            format!("{}: {}", self.path.display(), message.into())
        } else {
            format!("{}: {pointer}: {}", self.path.display(), message.into())
        };
        if !self.warnings.contains(&w) {
            self.warnings.push(w);
        }
    }
}

/// A JSON pointer from gltf-json's validation path (`meshes[0].primitives[1].attributes["POSITION"]`
/// becomes `/meshes/0/primitives/1/attributes/POSITION`).
fn json_pointer(path: &str) -> String {
    let mut out = String::new();
    let mut chars = path.chars().peekable();
    let mut segment = String::new();
    let flush = |out: &mut String, segment: &mut String| {
        if !segment.is_empty() {
            out.push('/');
            // RFC 6901 escapes.
            out.push_str(&segment.replace('~', "~0").replace('/', "~1"));
            segment.clear();
        }
    };
    while let Some(c) = chars.next() {
        match c {
            '.' => flush(&mut out, &mut segment),
            '[' => {
                flush(&mut out, &mut segment);
                if chars.peek() == Some(&'"') {
                    chars.next();
                    for c in chars.by_ref() {
                        if c == '"' {
                            break;
                        }
                        segment.push(c);
                    }
                    // The closing bracket.
                    chars.next();
                } else {
                    for c in chars.by_ref() {
                        if c == ']' {
                            break;
                        }
                        segment.push(c);
                    }
                }
                flush(&mut out, &mut segment);
            }
            // gltf-json appends ` = "value"` to some paths.
            ' ' => break,
            c => segment.push(c),
        }
    }
    flush(&mut out, &mut segment);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validation_paths_become_json_pointers() {
        assert_eq!(
            json_pointer("meshes[0].primitives[1].attributes[\"POSITION\"]"),
            "/meshes/0/primitives/1/attributes/POSITION"
        );
        assert_eq!(json_pointer("nodes[3].children[0]"), "/nodes/3/children/0");
        assert_eq!(json_pointer("extensionsRequired[0] = \"X\""), "/extensionsRequired/0");
        assert_eq!(json_pointer(""), "");
    }

    #[test]
    fn extensions_name_gltf_files() {
        assert!(is_gltf_path(Path::new("a/b.glTF")));
        assert!(is_gltf_path(Path::new("m.glb")));
        assert!(!is_gltf_path(Path::new("m.xml")));
    }
}
