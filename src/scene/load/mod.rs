//! Scene description to validated scene.
//!
//! [`load_toml_scene`] reads a TOML file (bounded in size), [`parse_scene`] parses
//! it into a [`SceneDesc`] (serde, every table `deny_unknown_fields`) and then
//! checks every value before building the immutable [`Scene`](crate::scene::Scene). Every error is
//! a [`SceneError`] whose message starts with `file:line:column:` when the
//! problem has a place in the file (toml's byte spans, converted here so that
//! syntax, type and semantic errors all read the same way).
//!
//! Meshes are resolved relative to the scene file (or as `asset:NAME`), keyed
//! by canonical path so that a file used by several objects is loaded once,
//! loaded in parallel, and shared by `Arc`.
//!
//! The checks are split by what they check: `ctx` holds the file being
//! checked and the checks of single values, `settings` the `[render]`,
//! `[photons]` and `[camera]` tables, `materials` and `lights` theirs,
//! `objects` the objects, their mesh files, water surfaces and the
//! `[medium]`; `media` the `[media]` and where they are; `error` defines [`SceneError`] and [`Place`].

mod ctx;
mod disney;
mod error;
mod lights;
mod materials;
mod media;
mod objects;
mod settings;
mod textures;

pub use ctx::MAX_MAGNITUDE;
pub use error::{Place, SceneError};
pub use lights::{DEFAULT_AREA_LIGHT_SAMPLES, MAX_AREA_LIGHT_SAMPLES};
pub use materials::{DEFAULT_DIFFUSE, DEFAULT_IOR, DEFAULT_SHININESS};
pub use media::{DEFAULT_ALBEDO, DEFAULT_SIGMA_T};
pub use objects::DEFAULT_WATER_RESOLUTION;
pub use settings::{DEFAULT_VFOV_DEG, MAX_DEPTH, MAX_EXPOSURE_STOPS, MAX_PHOTON_GATHER};

use crate::geometry::water::WaterSurface;
use crate::scene::desc::{IntegratorName, ObjectKind, SceneDesc};
use crate::scene::{LoadedScene, Object, Origin, SceneBuilder, Shape};
use ctx::Ctx;
use std::io::Read;
use std::path::Path;
use std::sync::Arc;

/// Largest scene file read (bytes). Scene files are small text; the bound
/// keeps a wrong path (`/dev/zero`, a huge binary) from exhausting memory.
pub const MAX_SCENE_FILE_BYTES: u64 = 16 << 20;

/// Loads and validates a scene file (at most [`MAX_SCENE_FILE_BYTES`]).
/// Relative mesh paths are resolved against the scene file's directory.
pub fn load_toml_scene(path: &Path) -> Result<LoadedScene, SceneError> {
    let text = read_scene_text(path)?;
    parse_scene(&text, path)
}

/// The text of a scene file: at most [`MAX_SCENE_FILE_BYTES`], UTF-8.
pub(crate) fn read_scene_text(path: &Path) -> Result<String, SceneError> {
    let read_error = |error| SceneError::Read {
        path: path.into(),
        error,
    };
    let meta = std::fs::metadata(path).map_err(read_error)?;
    if meta.is_dir() {
        return Err(SceneError::Directory { path: path.into() });
    }
    let file = std::fs::File::open(path).map_err(read_error)?;
    let mut bytes = Vec::new();
    file.take(MAX_SCENE_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(read_error)?;
    if bytes.len() as u64 > MAX_SCENE_FILE_BYTES {
        return Err(SceneError::TooLarge {
            path: path.into(),
            limit: MAX_SCENE_FILE_BYTES,
        });
    }
    String::from_utf8(bytes).map_err(|e| {
        let valid = e.utf8_error().valid_up_to();
        let text = std::str::from_utf8(&e.as_bytes()[..valid]).unwrap_or_default();
        SceneError::NotUtf8 {
            path: path.into(),
            place: Place::of_offset(text, valid),
        }
    })
}

/// Parses and validates scene text. `path` names the file in messages, and
/// relative mesh paths are resolved against its directory.
pub fn parse_scene(text: &str, path: &Path) -> Result<LoadedScene, SceneError> {
    let desc: SceneDesc = toml::from_str(text).map_err(|e| SceneError::Toml {
        path: path.into(),
        place: e.span().map(|s| Place::of_offset(text, s.start)),
        // One line, like every other message (toml puts the expectation on a second line).
        message: e.message().trim().lines().map(str::trim).collect::<Vec<_>>().join(": "),
    })?;
    let ctx = Ctx {
        text,
        path,
        textures: &desc.textures,
        images: Default::default(),
    };
    let mut settings = ctx.render(&desc.render)?;
    settings.photons = ctx.photons(&desc.photons)?;
    let camera = ctx.camera(desc.camera.get_ref(), desc.camera.span())?;
    let (materials, material_index) = ctx.materials(&desc.materials)?;
    let lights = desc
        .lights
        .iter()
        .map(|l| ctx.light(l))
        .collect::<Result<Vec<_>, _>>()?;

    // Objects: everything but the meshes' contents, so that cheap mistakes
    // are reported before any mesh file is read.
    let mut objects = Vec::with_capacity(desc.objects.len());
    let mut mesh_refs = Vec::new();
    let mut waters: Vec<(usize, WaterSurface)> = Vec::new();
    for (i, o) in desc.objects.iter().enumerate() {
        let material =
            *material_index
                .get(o.material.get_ref().as_str())
                .ok_or_else(|| SceneError::UnknownMaterial {
                    path: path.into(),
                    place: ctx.place(o.material.span()),
                    name: o.material.get_ref().clone(),
                    known: material_index.keys().map(|k| k.to_string()).collect(),
                })?;
        let name = o
            .name
            .clone()
            .unwrap_or_else(|| format!("{}#{i}", kind_name(*o.kind.get_ref())));
        let shape = match o.kind.get_ref() {
            ObjectKind::Sphere => ctx.sphere(o)?,
            ObjectKind::Quad => ctx.quad(o)?,
            ObjectKind::Disk => ctx.disk(o)?,
            ObjectKind::Cylinder => ctx.cylinder(o)?,
            ObjectKind::Water => {
                waters.push((i, ctx.water(o)?));
                // The generated mesh is appended after the files' meshes.
                Shape::Mesh {
                    mesh: u32::MAX,
                    transform: crate::math::Transform::IDENTITY,
                    smooth: true,
                }
            }
            ObjectKind::Mesh => {
                let (file, transform, smooth) = ctx.mesh_instance(o)?;
                mesh_refs.push((i, file));
                // The mesh index is filled in once the distinct files are known.
                Shape::Mesh {
                    mesh: u32::MAX,
                    transform,
                    smooth,
                }
            }
        };
        objects.push(Object { name, shape, material });
    }
    let mut meshes = ctx.load_meshes(&mut objects, &mesh_refs)?;
    for (object, surface) in &waters {
        let mesh = surface.mesh(&objects[*object].name).map_err(|e| {
            ctx.invalid(
                desc.objects[*object].kind.span(),
                format!("water surface `{}`: {e}", objects[*object].name),
            )
        })?;
        if let Shape::Mesh { mesh: index, .. } = &mut objects[*object].shape {
            *index = meshes.len() as u32;
        }
        meshes.push(Arc::new(mesh));
    }
    // The parts, with their places, checked together by the builder.
    let text_origin = |span: std::ops::Range<usize>| Origin::Text {
        path: path.into(),
        place: ctx.place(span),
    };
    let mut builder = SceneBuilder::new(path);
    let mut material_origins = vec![Origin::File { path: path.into() }; materials.len()];
    // A material's origin is where the first object using it names it.
    for o in desc.objects.iter().rev() {
        if let Some(&m) = material_index.get(o.material.get_ref().as_str()) {
            material_origins[m as usize] = text_origin(o.material.span());
        }
    }
    for (material, origin) in materials.into_iter().zip(material_origins) {
        builder.add_material(material, origin);
    }
    for mesh in meshes {
        builder.add_mesh(mesh);
    }
    // An object's origin is its `material` key: what the builder checks of
    // an object is what its material needs from its shape.
    for (object, o) in objects.into_iter().zip(&desc.objects) {
        builder.add_object(object, text_origin(o.material.span()));
    }
    for (light, l) in lights.into_iter().zip(&desc.lights) {
        builder.add_light(light, text_origin(l.kind.span()));
    }
    builder.set_media(ctx.scene_media(&desc, desc.render.integrator == Some(IntegratorName::Volpath))?);
    builder.set_camera(camera);
    builder.set_settings(settings);
    builder.set_ambient(ctx.ambient(&desc.render)?);
    let mut loaded = builder.build()?;
    if let Some(m) = &desc.medium {
        let scene = &mut loaded.scene;
        scene.water_medium = Some(ctx.medium(m, waters.first().map(|(i, w)| (*i, w)), scene.bounds())?);
    }
    Ok(loaded)
}

fn kind_name(kind: ObjectKind) -> &'static str {
    match kind {
        ObjectKind::Sphere => "sphere",
        ObjectKind::Quad => "quad",
        ObjectKind::Disk => "disk",
        ObjectKind::Cylinder => "cylinder",
        ObjectKind::Mesh => "mesh",
        ObjectKind::Water => "water",
    }
}
