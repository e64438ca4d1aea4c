//! The Mitsuba 3 scene format (also version 2): `caustic render scene.xml`.
//!
//! [`xml`] reads the file into elements (defaults, `$` parameters and `-D`
//! definitions, includes, `<path>`), [`props`] reads a plugin's properties
//! through typed getters and refuses any it did not read, and one module per
//! plugin class maps each plugin to the scene model: [`sensor`] (camera,
//! film, sampler, integrator), [`shapes`], [`bsdfs`], [`emitters`],
//! [`textures`], [`media`] (homogeneous media and their phase functions,
//! which `volpath` renders and `path` ignores). A plugin either maps exactly (the same image in
//! expectation) or is refused with its file:line:column; wrappers that only
//! add outputs (`moment`, `aov`) are rendered through with a warning.
//! Spectra become RGB as Mitsuba's RGB variants make them ([`spectrum`]).

mod bsdfs;
mod cie;
mod emitters;
mod media;
pub mod props;
mod sensor;
mod shapes;
pub mod spectrum;
mod textures;
pub mod transform;
pub mod values;
pub mod xml;

use crate::geometry::Mesh;
use crate::io::LoadLimits;
use crate::scene::load::SceneError;
use crate::scene::{Light, LoadedScene, Material, Object, RenderSettings, Scene, Shape};
use crate::texture::{ColourSpace, Image};
use props::{Ids, Plugin};
use rayon::prelude::*;
use std::cell::{Cell, RefCell};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use xml::{Document, Origin};

/// A Mitsuba scene, with what was read but not rendered as warnings.
#[derive(Debug)]
pub struct MitsubaScene {
    /// The scene.
    pub scene: Scene,
    /// The render settings its sensor, film, sampler and integrator ask for.
    pub settings: RenderSettings,
    /// Messages about what caustic reads but does not render (output-only
    /// integrator wrappers).
    pub warnings: Vec<String>,
    /// Seconds spent reading the XML and building the scene, mesh files aside.
    pub xml_seconds: f64,
    /// Seconds spent loading the mesh files (in parallel).
    pub mesh_seconds: f64,
}

impl MitsubaScene {
    /// The scene and its settings, the warnings and timings left out.
    pub fn into_loaded(self) -> LoadedScene {
        LoadedScene {
            scene: self.scene,
            settings: self.settings,
        }
    }
}

/// Reads a Mitsuba XML scene; `defines` are `-D name=value` parameters,
/// which take precedence over the file's `<default>`s.
pub fn load_mitsuba_scene(path: &Path, defines: &[(String, String)]) -> Result<MitsubaScene, SceneError> {
    let start = std::time::Instant::now();
    let doc = xml::read_document(path, defines)?;
    let ids = Ids::collect(&doc.root)?;
    let mut b = Builder {
        doc: &doc,
        materials: Vec::new(),
        material_index: HashMap::new(),
        mesh_sources: Vec::new(),
        mesh_index: HashMap::new(),
        generated_index: HashMap::new(),
        objects: Vec::new(),
        interfaces: Vec::new(),
        media: Vec::new(),
        medium_index: HashMap::new(),
        images: RefCell::new(HashMap::new()),
        bsdfs_read: Cell::new(0),
    };
    let mut settings = RenderSettings {
        integrator: crate::scene::IntegratorKind::Path,
        ..Default::default()
    };
    let mut warnings = Vec::new();
    let mut lights = Vec::new();
    let mut sensor = None;
    let mut integrator_seen: Option<&Origin> = None;
    // Mitsuba's default integrator is `path`, which ignores media.
    let mut media_handling = sensor::MediaHandling::Ignored;
    let mut camera_medium = None;
    for e in &doc.root.children {
        if ids.is_referenced(e) {
            // A definition, instantiated where it is referenced.
            continue;
        }
        match e.tag.as_str() {
            "sensor" => {
                if sensor.is_some() {
                    return Err(e
                        .origin
                        .error("the scene has several sensors; caustic renders one camera"));
                }
                let plugin = Plugin::new(e, &ids)?;
                // The medium the camera is in: Mitsuba takes any one medium
                // object of the sensor, whatever its name.
                let media = plugin.children_of("medium")?;
                if let Some((_, second)) = media.get(1) {
                    return Err(second.origin.error("a sensor takes at most one <medium>"));
                }
                if let Some((m, _)) = media.first() {
                    camera_medium = Some(b.medium(m)?);
                }
                sensor = Some(sensor::sensor(&plugin)?);
            }
            "integrator" => {
                if let Some(first) = integrator_seen {
                    return Err(e.origin.error(format!(
                        "a second <integrator> (the first is at line {})",
                        first.place.line
                    )));
                }
                integrator_seen = Some(&e.origin);
                media_handling = sensor::integrator(&Plugin::new(e, &ids)?, &mut settings, &mut warnings)?;
            }
            "shape" => b.shape(&Plugin::new(e, &ids)?)?,
            "emitter" => lights.push((b.emitter(&Plugin::new(e, &ids)?)?, e.origin.part())),
            // Definitions, used through <ref>.
            "bsdf" | "texture" | "spectrum" | "rfilter" | "film" | "sampler" => {}
            "medium" | "phase" | "volume" => {
                return Err(e.origin.error(format!(
                    "<{}> is not referenced: a medium is used through a shape's `interior` / `exterior` or the sensor",
                    e.tag
                )))
            }
            other => {
                return Err(e.origin.error(format!(
                    "unexpected <{other}> in <scene>: expected sensor, integrator, shape, emitter, bsdf, texture"
                )))
            }
        }
    }
    let sensor = sensor.ok_or_else(|| {
        doc.root
            .origin
            .error("the scene has no <sensor>: caustic needs a camera")
    })?;
    if lights
        .iter()
        .filter(|(l, _)| matches!(l, Light::Environment { .. }))
        .count()
        > 1
    {
        return Err(doc
            .root
            .origin
            .error("the scene has several environment emitters (constant, envmap); caustic takes one"));
    }
    settings.width = sensor.size.0;
    settings.height = sensor.size.1;
    settings.spp = sensor.spp;
    settings.seed = sensor.seed;
    let meshes_start = std::time::Instant::now();
    let meshes = b.load_meshes()?;
    let mesh_seconds = meshes_start.elapsed().as_secs_f64();
    let Builder {
        materials,
        mut objects,
        interfaces,
        media,
        ..
    } = b;
    let media = match media_handling {
        sensor::MediaHandling::Rendered => crate::scene::Media {
            interfaces: if media.is_empty() { Vec::new() } else { interfaces },
            list: media,
            camera: camera_medium,
            pass_through: crate::scene::PassThrough::Volumetric,
        },
        sensor::MediaHandling::Ignored => {
            let at = integrator_seen.unwrap_or(&doc.root.origin);
            if !media.is_empty() {
                warnings.push(format!(
                    "{}:{}: the integrator ignores participating media (as Mitsuba's `path` and `direct` do); `volpath` renders them",
                    at.file.display(),
                    at.place
                ));
            }
            // Null surfaces (and thin sheets) as Mitsuba's `path` meets them.
            crate::scene::Media {
                pass_through: crate::scene::PassThrough::SurfaceBounce,
                ..Default::default()
            }
        }
    };
    // A `.serialized` shape's flags may ask for face normals.
    for (o, _) in &mut objects {
        if let Shape::Mesh { mesh, smooth, .. } = &mut o.shape {
            *smooth &= !meshes.face_normals[*mesh as usize];
        }
    }
    let mut builder = crate::scene::SceneBuilder::new(&doc.root.origin.file);
    // Materials are made for the shapes that use them (and keyed by them).
    for material in materials {
        builder.add_material(material, doc.root.origin.part());
    }
    for mesh in meshes.meshes {
        builder.add_mesh(mesh);
    }
    for (object, origin) in objects {
        builder.add_object(object, origin);
    }
    for (light, origin) in lights {
        builder.add_light(light, origin);
    }
    builder.set_media(media);
    builder.set_camera(sensor.camera);
    builder.set_settings(settings);
    let LoadedScene { scene, settings } = builder.build()?;
    if scene.objects.is_empty() && scene.lights.is_empty() {
        return Err(doc.root.origin.error("the scene has no shape and no emitter"));
    }
    let bounds = scene.bounds();
    if !bounds.is_empty() {
        // The farthest corner of the bounds.
        let far = (bounds.center() - scene.camera.position).abs() + bounds.extent() * 0.5;
        let far = far.length();
        if far > sensor.far_clip {
            return Err(doc.root.origin.error(format!(
                "the sensor's `far_clip` ({}) cuts the scene, which reaches {far} away; caustic has no far clip: raise it",
                sensor.far_clip
            )));
        }
    }
    Ok(MitsubaScene {
        scene,
        settings,
        warnings,
        xml_seconds: start.elapsed().as_secs_f64() - mesh_seconds,
        mesh_seconds,
    })
}

/// Where a mesh comes from.
enum MeshSource {
    /// A file, read once per distinct (file, shape, flips).
    File {
        path: PathBuf,
        /// The shape of a `.serialized` file.
        serialized: Option<u32>,
        flip_normals: bool,
        /// Turn `v` into `1 − v`.
        flip_v: bool,
        /// The `filename` property, for errors.
        origin: Origin,
        /// The first object using it.
        object: String,
    },
    /// Built by the front end (cube, flipped rectangle).
    Ready(Mesh),
}

struct LoadedMeshes {
    meshes: Vec<Arc<Mesh>>,
    /// Per mesh: its file asks for face normals.
    face_normals: Vec<bool>,
}

/// What the plugins add to, in file order.
struct Builder<'a> {
    doc: &'a Document,
    materials: Vec<Material>,
    /// (BSDF element, emitter element) → material.
    material_index: HashMap<(usize, usize), u32>,
    mesh_sources: Vec<MeshSource>,
    mesh_index: HashMap<(PathBuf, Option<u32>, bool, bool), u32>,
    /// (shape element, flip) → generated mesh (cube, flipped rectangle).
    generated_index: HashMap<(usize, bool), u32>,
    /// The objects, each with the `<shape>` it comes from.
    objects: Vec<(Object, crate::scene::Origin)>,
    /// Per object, the media on its sides.
    interfaces: Vec<crate::scene::MediumInterface>,
    /// The media the shapes and the sensor name.
    media: Vec<crate::scene::HomogeneousMedium>,
    /// `<medium>` element → index in `media`.
    medium_index: HashMap<usize, u32>,
    images: RefCell<HashMap<(PathBuf, ColourSpace), Arc<Image>>>,
    /// BSDFs read for the material being built (see [`bsdfs::MAX_BSDFS_PER_MATERIAL`]).
    bsdfs_read: Cell<usize>,
}

impl Builder<'_> {
    /// The mesh index of a file (loaded later, once, in parallel).
    fn mesh_file(&mut self, source: MeshSource) -> u32 {
        let MeshSource::File {
            path,
            serialized,
            flip_normals,
            flip_v,
            ..
        } = &source
        else {
            return self.mesh_ready_source(source);
        };
        let key = (
            std::fs::canonicalize(path).unwrap_or(path.clone()),
            *serialized,
            *flip_normals,
            *flip_v,
        );
        if let Some(&i) = self.mesh_index.get(&key) {
            return i;
        }
        let i = self.mesh_ready_source(source);
        self.mesh_index.insert(key, i);
        i
    }

    fn mesh_ready_source(&mut self, source: MeshSource) -> u32 {
        self.mesh_sources.push(source);
        (self.mesh_sources.len() - 1) as u32
    }

    /// The mesh index of a generated mesh.
    fn mesh_ready(&mut self, mesh: Mesh) -> u32 {
        self.mesh_ready_source(MeshSource::Ready(mesh))
    }

    /// Loads the files in parallel.
    fn load_meshes(&mut self) -> Result<LoadedMeshes, SceneError> {
        let sources = std::mem::take(&mut self.mesh_sources);
        let limits = LoadLimits::default();
        let loaded: Vec<Result<(Mesh, bool), SceneError>> = sources
            .into_par_iter()
            .map(|s| match s {
                MeshSource::Ready(m) => Ok((m, false)),
                MeshSource::File {
                    path,
                    serialized,
                    flip_normals,
                    flip_v,
                    origin,
                    object,
                } => {
                    let result = match serialized {
                        Some(index) => crate::io::serialized::load_serialized(&path, index, &limits),
                        None => crate::io::load_mesh_with(&path, &limits).map(|m| (m, false)),
                    };
                    let (mut mesh, face) = result.map_err(|error| SceneError::Mesh {
                        path: origin.file.to_path_buf(),
                        place: origin.place,
                        object,
                        error: Box::new(error),
                    })?;
                    if flip_normals {
                        mesh = shapes::flipped(mesh);
                    }
                    if flip_v {
                        for uv in &mut mesh.uvs {
                            uv.y = 1.0 - uv.y;
                        }
                    }
                    Ok((mesh, face))
                }
            })
            .collect();
        let mut meshes = Vec::with_capacity(loaded.len());
        let mut face_normals = Vec::with_capacity(loaded.len());
        for r in loaded {
            let (m, f) = r?;
            meshes.push(Arc::new(m));
            face_normals.push(f);
        }
        Ok(LoadedMeshes { meshes, face_normals })
    }
}

/// True when `path` names a Mitsuba scene (by its `.xml` extension).
pub fn is_mitsuba_path(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("xml"))
}
