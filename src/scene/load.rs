//! Scene description to validated scene.
//!
//! [`load_scene`] reads a TOML file (bounded in size), [`parse_scene`] parses
//! it into a [`SceneDesc`] (serde, every table `deny_unknown_fields`) and then
//! checks every value before building the immutable [`Scene`]. Every error is
//! a [`SceneError`] whose message starts with `file:line:column:` when the
//! problem has a place in the file (toml's byte spans, converted here so that
//! syntax, type and semantic errors all read the same way).
//!
//! Meshes are resolved relative to the scene file (or as `asset:NAME`), keyed
//! by canonical path so that a file used by several objects is loaded once,
//! loaded in parallel, and shared by `Arc`.

use super::desc::{
    CameraDesc, LightDesc, LightKind, MaterialDesc, MediumDesc, ModelName, ObjectDesc, ObjectKind, PhotonsDesc,
    RenderDesc, ScaleDesc, SceneDesc, SharingName, Spanned, ToneMapName, TriangleTestName, Vec2Desc, Vec3Desc,
};
use super::{
    AreaLight, Camera, Dielectric, Light, Material, Medium, Mesh, Mirror, Object, PhotonSettings, Quad, RenderSettings,
    SampleSharing, Scene, ShadingModel, Shape, Sphere,
};
use crate::film::{OutputSettings, ToneMap};
use crate::geometry::water::{WaterSurface, Wave, MAX_WATER_RESOLUTION};
use crate::geometry::TriangleTest;
use crate::io::MeshError;
use crate::limits::{check_image_limits, check_photon_count, ImageLimit, MAX_IMAGE_SIDE};
use crate::math::{Transform, Vec3, Vec3A};
use rayon::prelude::*;
use std::collections::{BTreeMap, HashMap};
use std::fmt;
use std::io::Read;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use thiserror::Error;

/// Largest scene file read (bytes). Scene files are small text; the bound
/// keeps a wrong path (`/dev/zero`, a huge binary) from exhausting memory.
pub const MAX_SCENE_FILE_BYTES: u64 = 16 << 20;
/// Largest `max_depth`.
pub const MAX_DEPTH: u32 = 64;
/// Largest number of shadow samples of one area light.
pub const MAX_AREA_LIGHT_SAMPLES: u32 = 4096;
/// Largest magnitude of a coordinate, length or colour: squares of such
/// values stay finite in single precision (1e36 < 3.4e38).
pub const MAX_MAGNITUDE: f64 = 1e18;
/// Largest magnitude of `exposure` in stops (2^64 is still finite in f32).
pub const MAX_EXPOSURE_STOPS: f64 = 64.0;

/// Default vertical field of view (degrees).
pub const DEFAULT_VFOV_DEG: f32 = 45.0;
/// Default shadow samples of an area light (the original report used 32).
pub const DEFAULT_AREA_LIGHT_SAMPLES: u32 = 32;
/// Default diffuse albedo of a material.
pub const DEFAULT_DIFFUSE: f32 = 0.8;
/// Default Phong exponent.
pub const DEFAULT_SHININESS: f32 = 32.0;
/// Default index of refraction of a dielectric (glass).
pub const DEFAULT_IOR: f32 = 1.5;

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
    /// The file is larger than [`MAX_SCENE_FILE_BYTES`].
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
            | SceneError::Mesh { path, .. } => path,
        }
    }

    /// Line and column in the scene file, when the problem has one.
    pub fn place(&self) -> Option<Place> {
        match self {
            SceneError::Read { .. } | SceneError::Directory { .. } | SceneError::TooLarge { .. } => None,
            SceneError::Toml { place, .. } => *place,
            SceneError::NotUtf8 { place, .. }
            | SceneError::Invalid { place, .. }
            | SceneError::UnknownMaterial { place, .. }
            | SceneError::Mesh { place, .. } => Some(*place),
        }
    }
}

/// Largest `k` of the photon gather.
pub const MAX_PHOTON_GATHER: u32 = 100_000;
/// Default water grid resolution (cells per side).
pub const DEFAULT_WATER_RESOLUTION: u32 = 256;

/// Loads and validates a scene file (at most [`MAX_SCENE_FILE_BYTES`]).
/// Relative mesh paths are resolved against the scene file's directory.
pub fn load_scene(path: &Path) -> Result<Scene, SceneError> {
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
    let text = String::from_utf8(bytes).map_err(|e| {
        let valid = e.utf8_error().valid_up_to();
        let text = std::str::from_utf8(&e.as_bytes()[..valid]).unwrap_or_default();
        SceneError::NotUtf8 {
            path: path.into(),
            place: Place::of_offset(text, valid),
        }
    })?;
    parse_scene(&text, path)
}

/// Parses and validates scene text. `path` names the file in messages, and
/// relative mesh paths are resolved against its directory.
pub fn parse_scene(text: &str, path: &Path) -> Result<Scene, SceneError> {
    let ctx = Ctx { text, path };
    let desc: SceneDesc = toml::from_str(text).map_err(|e| SceneError::Toml {
        path: path.into(),
        place: e.span().map(|s| Place::of_offset(text, s.start)),
        // One line, like every other message (toml puts the expectation on a second line).
        message: e.message().trim().lines().map(str::trim).collect::<Vec<_>>().join(": "),
    })?;
    let mut settings = ctx.render(&desc.render)?;
    settings.photons = ctx.photons(&desc.photons)?;
    let camera = ctx.camera(&desc.camera)?;
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
    let mut scene = Scene {
        settings,
        camera,
        materials,
        lights,
        meshes,
        objects,
    };
    if let Some(m) = &desc.medium {
        scene.settings.medium = Some(ctx.medium(m, waters.first().map(|(_, w)| w), scene.bounds())?);
    }
    Ok(scene)
}

fn kind_name(kind: ObjectKind) -> &'static str {
    match kind {
        ObjectKind::Sphere => "sphere",
        ObjectKind::Quad => "quad",
        ObjectKind::Mesh => "mesh",
        ObjectKind::Water => "water",
    }
}

/// The file being checked: turns spans into places.
struct Ctx<'a> {
    text: &'a str,
    path: &'a Path,
}

impl Ctx<'_> {
    fn place(&self, span: Range<usize>) -> Place {
        Place::of_offset(self.text, span.start)
    }

    fn invalid(&self, span: Range<usize>, message: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            path: self.path.into(),
            place: self.place(span),
            message: message.into(),
        }
    }

    /// A finite number of bounded magnitude, as f32.
    fn number(&self, s: &Spanned<f64>, key: &str) -> Result<f32, SceneError> {
        self.check_finite(*s.get_ref(), s.span(), key)
    }

    /// The two finite numbers of a `size = [w, h]` value.
    fn finite_size(&self, size: &Spanned<Vec2Desc>) -> Result<(f32, f32), SceneError> {
        let Vec2Desc([w, h]) = *size.get_ref();
        Ok((
            self.check_finite(w, size.span(), "size")?,
            self.check_finite(h, size.span(), "size")?,
        ))
    }

    fn check_finite(&self, x: f64, span: Range<usize>, key: &str) -> Result<f32, SceneError> {
        if x.is_nan() {
            return Err(self.invalid(span, format!("`{key}` is NaN: numbers must be finite")));
        }
        if x.is_infinite() {
            return Err(self.invalid(span, format!("`{key}` is infinite: numbers must be finite")));
        }
        if x.abs() > MAX_MAGNITUDE {
            return Err(self.invalid(
                span,
                format!("`{key}` = {x:e} is too large (limit ±{MAX_MAGNITUDE:e}, so that squares stay finite)"),
            ));
        }
        Ok(x as f32)
    }

    fn vec3(&self, s: &Spanned<Vec3Desc>, key: &str) -> Result<Vec3A, SceneError> {
        let [x, y, z] = s.get_ref().0;
        let c = |v| self.check_finite(v, s.span(), key);
        Ok(Vec3A::new(c(x)?, c(y)?, c(z)?))
    }

    fn opt_vec3(&self, s: &Option<Spanned<Vec3Desc>>, key: &str, default: Vec3A) -> Result<Vec3A, SceneError> {
        s.as_ref().map_or(Ok(default), |s| self.vec3(s, key))
    }

    /// A vector that must have a direction.
    fn direction(&self, s: &Spanned<Vec3Desc>, key: &str) -> Result<Vec3A, SceneError> {
        let v = self.vec3(s, key)?;
        if v.length_squared() == 0.0 {
            return Err(self.invalid(
                s.span(),
                format!("`{key}` is the zero vector: it must have a direction"),
            ));
        }
        Ok(v)
    }

    /// A colour: finite, non-negative.
    fn colour(&self, s: &Spanned<Vec3Desc>, key: &str) -> Result<Vec3A, SceneError> {
        let c = self.vec3(s, key)?;
        if c.min_element() < 0.0 {
            return Err(self.invalid(s.span(), format!("`{key}` has a negative component: colours are ≥ 0")));
        }
        Ok(c)
    }

    /// A reflectance: a colour with components in [0, 1] (a surface cannot
    /// reflect more light than it receives).
    fn reflectance(&self, s: &Option<Spanned<Vec3Desc>>, key: &str, default: Vec3A) -> Result<Vec3A, SceneError> {
        let Some(s) = s else { return Ok(default) };
        let c = self.colour(s, key)?;
        if c.max_element() > 1.0 {
            return Err(self.invalid(
                s.span(),
                format!("`{key}` has a component above 1: reflectances are in [0, 1]"),
            ));
        }
        Ok(c)
    }

    fn render(&self, r: &RenderDesc) -> Result<RenderSettings, SceneError> {
        let d = RenderSettings::default();
        let int = |s: &Option<Spanned<u32>>, default: u32, key: &str, min: u32, max: u32| match s {
            None => Ok(default),
            Some(s) if (min..=max).contains(s.get_ref()) => Ok(*s.get_ref()),
            Some(s) => Err(self.invalid(
                s.span(),
                format!("`{key}` = {} is out of range: it must be in {min}..={max}", s.get_ref()),
            )),
        };
        let width = int(&r.width, d.width, "width", 1, MAX_IMAGE_SIDE)?;
        let height = int(&r.height, d.height, "height", 1, MAX_IMAGE_SIDE)?;
        let spp = int(&r.spp, d.spp, "spp", 1, u32::MAX)?;
        let max_depth = int(&r.max_depth, d.max_depth, "max_depth", 0, MAX_DEPTH)?;
        // Point at the key that makes the product too large (the first given).
        let size_span = [&r.width, &r.height, &r.spp]
            .into_iter()
            .flatten()
            .map(|s| s.span())
            .next()
            .unwrap_or(0..0);
        if let Err(e) = check_image_limits(width, height, spp) {
            let span = match e {
                ImageLimit::Samples(_) => r.spp.as_ref().map_or(size_span, |s| s.span()),
                ImageLimit::Film(_) => size_span,
            };
            return Err(self.invalid(span, e.to_string()));
        }
        let exposure = match &r.exposure {
            None => d.output.exposure,
            Some(s) => {
                let e = self.number(s, "exposure")?;
                if f64::from(e).abs() > MAX_EXPOSURE_STOPS {
                    return Err(self.invalid(
                        s.span(),
                        format!("`exposure` = {e} stops is out of range (±{MAX_EXPOSURE_STOPS})"),
                    ));
                }
                e
            }
        };
        let ambient = match &r.ambient {
            None => d.ambient,
            Some(s) => self.colour(s, "ambient")?,
        };
        Ok(RenderSettings {
            width,
            height,
            spp,
            max_depth,
            seed: r.seed.unwrap_or(d.seed),
            output: OutputSettings {
                tone_map: match r.tone_map {
                    None => d.output.tone_map,
                    Some(ToneMapName::Aces) => ToneMap::Aces,
                    Some(ToneMapName::Clamp) => ToneMap::Clamp,
                },
                exposure,
            },
            ambient,
            triangle_test: match r.triangle_test {
                None => d.triangle_test,
                Some(TriangleTestName::Watertight) => TriangleTest::Watertight,
                Some(TriangleTestName::MollerTrumbore) => TriangleTest::MollerTrumbore,
            },
            sharing: match r.sharing {
                None => d.sharing,
                Some(SharingName::Spread) => SampleSharing::Spread,
                Some(SharingName::Split) => SampleSharing::Split,
            },
            photons: d.photons,
            medium: None,
        })
    }

    fn camera(&self, c: &CameraDesc) -> Result<Camera, SceneError> {
        let position = self.vec3(&c.position, "position")?;
        let look_at = self.vec3(&c.look_at, "look_at")?;
        let forward = (look_at - position).try_normalize().ok_or_else(|| {
            self.invalid(
                c.look_at.span(),
                "`look_at` equals the camera `position`: the camera has no viewing direction",
            )
        })?;
        let up = match &c.up {
            Some(s) => self.direction(s, "up")?,
            None => Vec3A::Y,
        };
        // Parallel when the sine of the angle is below ~1e-4 (0.006°): the
        // right vector would then be dominated by rounding.
        if forward.cross(up.normalize()).length() < 1e-4 {
            let (span, what) = match &c.up {
                Some(s) => (s.span(), "`up`"),
                None => (c.look_at.span(), "the default `up` [0, 1, 0]"),
            };
            return Err(self.invalid(
                span,
                format!("{what} is parallel to the viewing direction (`look_at` − `position`): choose another `up`"),
            ));
        }
        let vfov = match &c.vfov {
            None => DEFAULT_VFOV_DEG,
            Some(s) => {
                let v = self.number(s, "vfov")?;
                if !(v > 0.0 && v < 180.0) {
                    return Err(self.invalid(s.span(), format!("`vfov` = {v}° must be in (0, 180) degrees")));
                }
                v
            }
        };
        Camera::new(position, look_at, up, vfov)
            .ok_or_else(|| self.invalid(c.position.span(), "the camera is degenerate"))
    }

    fn materials(
        &self,
        descs: &BTreeMap<String, MaterialDesc>,
    ) -> Result<(Vec<Material>, BTreeMap<String, u32>), SceneError> {
        let mut materials = Vec::with_capacity(descs.len());
        let mut index = BTreeMap::new();
        for (name, m) in descs {
            index.insert(name.clone(), materials.len() as u32);
            materials.push(self.material(name, m)?);
        }
        Ok((materials, index))
    }

    fn material(&self, name: &str, m: &MaterialDesc) -> Result<Material, SceneError> {
        let diffuse = self.reflectance(&m.diffuse, "diffuse", Vec3A::splat(DEFAULT_DIFFUSE))?;
        let ambient = self.reflectance(&m.ambient, "ambient", diffuse)?;
        let specular = self.reflectance(&m.specular, "specular", Vec3A::ZERO)?;
        let shininess = match &m.shininess {
            None => DEFAULT_SHININESS,
            Some(s) => {
                let n = self.number(s, "shininess")?;
                if n <= 0.0 {
                    return Err(self.invalid(s.span(), format!("`shininess` = {n} must be > 0")));
                }
                n
            }
        };
        let mirror = match &m.mirror {
            None => None,
            Some(s) => {
                let d = s.get_ref();
                let reflectivity = match &d.reflectivity {
                    None => 1.0,
                    Some(r) => {
                        let x = self.number(r, "reflectivity")?;
                        if !(0.0..=1.0).contains(&x) {
                            return Err(self.invalid(r.span(), format!("`reflectivity` = {x} must be in [0, 1]")));
                        }
                        x
                    }
                };
                let tint = self.reflectance(&d.tint, "tint", Vec3A::ONE)?;
                Some(Mirror { reflectivity, tint })
            }
        };
        let dielectric = match &m.dielectric {
            None => None,
            Some(s) => {
                if m.mirror.is_some() {
                    return Err(self.invalid(
                        s.span(),
                        format!(
                            "material `{name}` has both `mirror` and `dielectric`: a dielectric already \
                             reflects (Fresnel), keep one of them"
                        ),
                    ));
                }
                let d = s.get_ref();
                let ior = match &d.ior {
                    None => DEFAULT_IOR,
                    Some(r) => {
                        let x = self.number(r, "ior")?;
                        if x <= 0.0 {
                            return Err(self.invalid(r.span(), format!("`ior` = {x} must be > 0")));
                        }
                        x
                    }
                };
                let tint = self.reflectance(&d.tint, "tint", Vec3A::ONE)?;
                Some(Dielectric { ior, tint })
            }
        };
        Ok(Material {
            name: name.into(),
            model: match m.model {
                None | Some(ModelName::BlinnPhong) => ShadingModel::BlinnPhong,
                Some(ModelName::Phong) => ShadingModel::Phong,
            },
            ambient,
            diffuse,
            specular,
            shininess,
            mirror,
            dielectric,
        })
    }

    /// Rejects keys that exist for another `type` but not this one.
    fn only_keys(
        &self,
        what: &str,
        present: &[(&str, Option<Range<usize>>)],
        allowed: &[&str],
    ) -> Result<(), SceneError> {
        for (key, span) in present {
            if let Some(span) = span {
                if !allowed.contains(key) {
                    return Err(self.invalid(
                        span.clone(),
                        format!("`{key}` does not apply to {what} (its keys: {})", allowed.join(", ")),
                    ));
                }
            }
        }
        Ok(())
    }

    fn required<'d, T>(
        &self,
        value: &'d Option<Spanned<T>>,
        key: &str,
        what: &str,
        at: Range<usize>,
    ) -> Result<&'d Spanned<T>, SceneError> {
        value
            .as_ref()
            .ok_or_else(|| self.invalid(at, format!("{what} needs `{key}`")))
    }

    fn light(&self, l: &LightDesc) -> Result<Light, SceneError> {
        let present = [
            ("u", l.u.as_ref().map(|s| s.span())),
            ("v", l.v.as_ref().map(|s| s.span())),
            ("samples", l.samples.as_ref().map(|s| s.span())),
        ];
        let position = self.vec3(&l.position, "position")?;
        let colour = match &l.colour {
            None => Vec3A::ONE,
            Some(s) => self.colour(s, "colour")?,
        };
        let intensity = match &l.intensity {
            None => 1.0,
            Some(s) => {
                let x = self.number(s, "intensity")?;
                if x < 0.0 {
                    return Err(self.invalid(s.span(), format!("`intensity` = {x} must be ≥ 0")));
                }
                x
            }
        };
        let power = colour * intensity;
        if !power.is_finite() {
            let span = l.intensity.as_ref().map_or(l.position.span(), |s| s.span());
            return Err(self.invalid(span, "`colour` × `intensity` overflows single precision"));
        }
        match l.kind.get_ref() {
            LightKind::Point => {
                self.only_keys("a point light", &present, &["type", "position", "colour", "intensity"])?;
                Ok(Light::Point {
                    position,
                    intensity: power,
                })
            }
            LightKind::Area => {
                let what = "an area light";
                let u_desc = self.required(&l.u, "u", what, l.kind.span())?;
                let v_desc = self.required(&l.v, "v", what, l.kind.span())?;
                let u = self.direction(u_desc, "u")?;
                let v = self.direction(v_desc, "v")?;
                let samples = match &l.samples {
                    None => DEFAULT_AREA_LIGHT_SAMPLES,
                    Some(s) if (1..=MAX_AREA_LIGHT_SAMPLES).contains(s.get_ref()) => *s.get_ref(),
                    Some(s) => {
                        return Err(self.invalid(
                            s.span(),
                            format!(
                                "`samples` = {} is out of range: it must be in 1..={MAX_AREA_LIGHT_SAMPLES}",
                                s.get_ref()
                            ),
                        ))
                    }
                };
                AreaLight::new(position, u, v, power, samples)
                    .filter(|a| a.area() > 0.0 && a.area().is_finite())
                    .map(Light::Area)
                    .ok_or_else(|| {
                        self.invalid(
                            v_desc.span(),
                            "the area light's edges `u` and `v` are parallel: the rectangle has no area",
                        )
                    })
            }
        }
    }

    fn object_keys(o: &ObjectDesc) -> [(&'static str, Option<Range<usize>>); 15] {
        fn s<T>(x: &Option<Spanned<T>>) -> Option<Range<usize>> {
            x.as_ref().map(|x| x.span())
        }
        [
            ("center", s(&o.center)),
            ("radius", s(&o.radius)),
            ("corner", s(&o.corner)),
            ("u", s(&o.u)),
            ("v", s(&o.v)),
            ("size", s(&o.size)),
            ("normal", s(&o.normal)),
            ("up", s(&o.up)),
            ("rotate", s(&o.rotate)),
            ("file", s(&o.file)),
            ("translate", s(&o.translate)),
            ("scale", s(&o.scale)),
            ("smooth", s(&o.smooth)),
            ("waves", s(&o.waves)),
            ("resolution", s(&o.resolution)),
        ]
    }

    /// `[photons]`.
    fn photons(&self, p: &PhotonsDesc) -> Result<PhotonSettings, SceneError> {
        let d = PhotonSettings::default();
        let count = match &p.count {
            None => d.count,
            Some(c) => {
                let n = *c.get_ref();
                if n < 0 {
                    return Err(self.invalid(c.span(), format!("photon `count` = {n} must be ≥ 0")));
                }
                check_photon_count(n as u64).map_err(|e| self.invalid(c.span(), e))?;
                n as u64
            }
        };
        let k = match &p.k {
            None => d.k,
            Some(k) if (1..=MAX_PHOTON_GATHER as i64).contains(k.get_ref()) => *k.get_ref() as u32,
            Some(k) => {
                return Err(self.invalid(
                    k.span(),
                    format!("photon `k` = {} must be in 1..={MAX_PHOTON_GATHER}", k.get_ref()),
                ))
            }
        };
        let max_radius = match &p.max_radius {
            None => d.max_radius,
            Some(r) => {
                let x = self.number(r, "max_radius")?;
                if x <= 0.0 {
                    return Err(self.invalid(r.span(), format!("`max_radius` = {x} must be > 0")));
                }
                Some(x)
            }
        };
        let cone_k = match &p.cone_k {
            None => d.cone_k,
            Some(c) => {
                let x = self.number(c, "cone_k")?;
                if x < 1.0 {
                    return Err(self.invalid(
                        c.span(),
                        format!("`cone_k` = {x} must be ≥ 1 (the cone filter's weight 1 − d/(k·r) must stay ≥ 0)"),
                    ));
                }
                x
            }
        };
        Ok(PhotonSettings {
            count,
            k,
            max_radius,
            cone_k,
            gather: match p.gather {
                None => d.gather,
                Some(super::desc::GatherName::Precomputed) => super::GatherMode::Precomputed,
                Some(super::desc::GatherName::Direct) => super::GatherMode::Direct,
            },
        })
    }

    /// `[medium]`: fills the (first) water object's volume.
    fn medium(
        &self,
        m: &Spanned<MediumDesc>,
        water: Option<&WaterSurface>,
        bounds: crate::math::Aabb,
    ) -> Result<Medium, SceneError> {
        let d = m.get_ref();
        let density = self.number(&d.density, "density")?;
        if density < 0.0 {
            return Err(self.invalid(d.density.span(), format!("`density` = {density} must be ≥ 0")));
        }
        let colour = match &d.colour {
            None => Vec3A::ZERO,
            Some(c) => self.colour(c, "colour")?,
        };
        let Some(water) = water else {
            return Err(self.invalid(
                m.span(),
                "`[medium]` fills the water: the scene needs an object of `type = \"water\"`",
            ));
        };
        Ok(Medium {
            density,
            colour,
            region: water.volume(bounds.min.y),
        })
    }

    /// A water surface: `center`, `size`, `resolution`, `waves`.
    fn water(&self, o: &ObjectDesc) -> Result<WaterSurface, SceneError> {
        let what = "a water surface";
        self.only_keys(what, &Self::object_keys(o), &["center", "size", "resolution", "waves"])?;
        let center = self.vec3(self.required(&o.center, "center", what, o.kind.span())?, "center")?;
        let size_desc = self.required(&o.size, "size", what, o.kind.span())?;
        let (w, h) = self.finite_size(size_desc)?;
        if !(w > 0.0 && h > 0.0) {
            return Err(self.invalid(size_desc.span(), format!("water `size` = [{w}, {h}] must be positive")));
        }
        let resolution = match &o.resolution {
            None => (DEFAULT_WATER_RESOLUTION, DEFAULT_WATER_RESOLUTION),
            Some(r) => {
                let Vec2Desc([a, b]) = *r.get_ref();
                let ok = |x: f64| x.fract() == 0.0 && (1.0..=MAX_WATER_RESOLUTION as f64).contains(&x);
                if !(ok(a) && ok(b)) {
                    return Err(self.invalid(
                        r.span(),
                        format!("water `resolution` = [{a}, {b}]: both must be integers in 1..={MAX_WATER_RESOLUTION}"),
                    ));
                }
                (a as u32, b as u32)
            }
        };
        let mut waves = Vec::new();
        if let Some(list) = &o.waves {
            for wd in list.get_ref() {
                let amplitude = self.number(&wd.amplitude, "amplitude")?;
                let wavelength = self.number(&wd.wavelength, "wavelength")?;
                if wavelength <= 0.0 {
                    return Err(self.invalid(wd.wavelength.span(), format!("`wavelength` = {wavelength} must be > 0")));
                }
                let Vec2Desc([dx, dz]) = *wd.direction.get_ref();
                let dir = crate::math::Vec2::new(
                    self.check_finite(dx, wd.direction.span(), "direction")?,
                    self.check_finite(dz, wd.direction.span(), "direction")?,
                );
                let Some(direction) = dir.try_normalize() else {
                    return Err(self.invalid(
                        wd.direction.span(),
                        "wave `direction` is the zero vector: it must have a direction",
                    ));
                };
                let phase = match &wd.phase {
                    None => 0.0,
                    Some(p) => self.number(p, "phase")?.to_radians(),
                };
                waves.push(Wave {
                    amplitude,
                    wavelength,
                    direction,
                    phase,
                });
            }
        }
        Ok(WaterSurface {
            center,
            size: crate::math::Vec2::new(w, h),
            resolution,
            waves,
        })
    }

    fn sphere(&self, o: &ObjectDesc) -> Result<Shape, SceneError> {
        let what = "a sphere";
        self.only_keys(what, &Self::object_keys(o), &["center", "radius"])?;
        let center = self.vec3(self.required(&o.center, "center", what, o.kind.span())?, "center")?;
        let r = self.required(&o.radius, "radius", what, o.kind.span())?;
        let radius = self.number(r, "radius")?;
        if radius <= 0.0 {
            return Err(self.invalid(r.span(), format!("sphere `radius` = {radius} must be > 0")));
        }
        Ok(Shape::Sphere(Sphere { center, radius }))
    }

    /// A quad, either `corner` + `u` + `v`, or `center` + `size` with an
    /// orientation (`normal` + optional `up`, or `rotate`).
    fn quad(&self, o: &ObjectDesc) -> Result<Shape, SceneError> {
        let keys = Self::object_keys(o);
        let degenerate = |span: Range<usize>, why: &str| self.invalid(span, format!("degenerate quad: {why}"));
        if let Some(corner_desc) = &o.corner {
            self.only_keys("a quad given by `corner`", &keys, &["corner", "u", "v"])?;
            let what = "a quad given by `corner`";
            let corner = self.vec3(corner_desc, "corner")?;
            let u_desc = self.required(&o.u, "u", what, corner_desc.span())?;
            let v_desc = self.required(&o.v, "v", what, corner_desc.span())?;
            let u = self.vec3(u_desc, "u")?;
            let v = self.vec3(v_desc, "v")?;
            if u.length_squared() == 0.0 {
                return Err(degenerate(u_desc.span(), "`u` is the zero vector"));
            }
            if v.length_squared() == 0.0 {
                return Err(degenerate(v_desc.span(), "`v` is the zero vector"));
            }
            return Quad::new(corner, u, v)
                .filter(|q| q.area() > 0.0 && q.area().is_finite())
                .map(Shape::Quad)
                .ok_or_else(|| degenerate(v_desc.span(), "`u` and `v` are parallel (zero area)"));
        }
        let what = "a quad given by `center` (or give `corner`, `u`, `v`)";
        self.only_keys(what, &keys, &["center", "size", "normal", "up", "rotate"])?;
        let center = self.vec3(self.required(&o.center, "center", what, o.kind.span())?, "center")?;
        let size_desc = self.required(&o.size, "size", what, o.kind.span())?;
        let (w, h) = self.finite_size(size_desc)?;
        if !(w > 0.0 && h > 0.0) {
            return Err(degenerate(
                size_desc.span(),
                &format!("`size` = [{w}, {h}] must be positive"),
            ));
        }
        // Unit edge directions (e_u, e_v) with e_u × e_v = facing normal.
        let (e_u, e_v) = match (&o.normal, &o.rotate) {
            (Some(_), Some(r)) => {
                return Err(self.invalid(
                    r.span(),
                    "give the quad's orientation either as `normal` (+ `up`) or as `rotate`, not both",
                ))
            }
            (Some(n_desc), None) => {
                let n = self.direction(n_desc, "normal")?.normalize();
                let up = match &o.up {
                    Some(u) => self.direction(u, "up")?.normalize(),
                    // +y, unless the quad faces up or down (a floor or a
                    // ceiling): then its height runs along −z, away from a
                    // camera on the +z side.
                    None if n.y.abs() > 0.999 => -Vec3A::Z,
                    None => Vec3A::Y,
                };
                let e_v = (up - n * up.dot(n))
                    .try_normalize()
                    .filter(|_| n.cross(up).length() > 1e-4);
                let Some(e_v) = e_v else {
                    let span = o.up.as_ref().map_or(n_desc.span(), |u| u.span());
                    return Err(self.invalid(span, "the quad's `up` is parallel to its `normal`"));
                };
                // e_u × e_v = (e_v × n) × e_v = n (e_v ⟂ n, |e_v| = 1).
                (e_v.cross(n), e_v)
            }
            (None, rotate) => {
                if let Some(up) = &o.up {
                    return Err(self.invalid(up.span(), "`up` needs `normal` (it orients a quad given by `normal`)"));
                }
                let deg = self.opt_vec3(rotate, "rotate", Vec3A::ZERO)?;
                let r = euler_xyz(deg);
                (r * Vec3A::X, r * Vec3A::Y)
            }
        };
        let (u, v) = (e_u * w, e_v * h);
        Quad::new(center - (u + v) * 0.5, u, v)
            .filter(|q| q.area() > 0.0 && q.area().is_finite())
            .map(Shape::Quad)
            .ok_or_else(|| degenerate(size_desc.span(), "zero or overflowing area"))
    }

    /// A mesh object's file reference, transform and shading flag.
    fn mesh_instance<'d>(&self, o: &'d ObjectDesc) -> Result<(&'d Spanned<String>, Transform, bool), SceneError> {
        let what = "a mesh";
        self.only_keys(
            what,
            &Self::object_keys(o),
            &["file", "translate", "rotate", "scale", "smooth"],
        )?;
        let file = self.required(&o.file, "file", what, o.kind.span())?;
        let translate = self.opt_vec3(&o.translate, "translate", Vec3A::ZERO)?;
        let rotate = self.opt_vec3(&o.rotate, "rotate", Vec3A::ZERO)?;
        let scale = match &o.scale {
            None => Vec3A::ONE,
            Some(s) => {
                let v = match *s.get_ref() {
                    ScaleDesc::Uniform(x) => Vec3A::splat(self.check_finite(x, s.span(), "scale")?),
                    ScaleDesc::PerAxis([x, y, z]) => Vec3A::new(
                        self.check_finite(x, s.span(), "scale")?,
                        self.check_finite(y, s.span(), "scale")?,
                        self.check_finite(z, s.span(), "scale")?,
                    ),
                };
                if v.abs().min_element() == 0.0 {
                    return Err(self.invalid(s.span(), "`scale` is zero on an axis: the mesh would be flat"));
                }
                v
            }
        };
        let transform =
            Transform::from_srt(Vec3::from(scale), Vec3::from(rotate), Vec3::from(translate)).ok_or_else(|| {
                let span = o.scale.as_ref().map_or(o.kind.span(), |s| s.span());
                self.invalid(span, "the mesh transform is singular (scale too small)")
            })?;
        Ok((file, transform, o.smooth.as_ref().is_some_and(|s| *s.get_ref())))
    }

    /// Resolves the mesh files, loads each distinct one once (in parallel),
    /// and points the objects at them.
    fn load_meshes(
        &self,
        objects: &mut [Object],
        refs: &[(usize, &Spanned<String>)],
    ) -> Result<Vec<Arc<Mesh>>, SceneError> {
        let scene_dir = self.path.parent().unwrap_or(Path::new(""));
        let mesh_error = |object: usize, file: &Spanned<String>, error| SceneError::Mesh {
            path: self.path.into(),
            place: self.place(file.span()),
            object: objects[object].name.clone(),
            error: Box::new(error),
        };
        // Distinct files in order of first use; `first_user` reports errors
        // at the first object that names the file.
        let mut by_key: HashMap<PathBuf, usize> = HashMap::new();
        let mut files: Vec<(PathBuf, usize, &Spanned<String>)> = Vec::new();
        let mut mesh_of_object = Vec::with_capacity(refs.len());
        for &(object, file) in refs {
            let resolved =
                crate::io::resolve_mesh_path(scene_dir, file.get_ref()).map_err(|e| mesh_error(object, file, e))?;
            // Canonical path as the key: `a/../m.off` and `m.off` are one mesh.
            // A file that does not exist keeps its resolved path and is
            // reported by the loader.
            let key = std::fs::canonicalize(&resolved).unwrap_or_else(|_| resolved.clone());
            let index = *by_key.entry(key).or_insert_with(|| {
                files.push((resolved, object, file));
                files.len() - 1
            });
            mesh_of_object.push((object, index));
        }
        let loaded: Vec<Result<Mesh, MeshError>> = files
            .par_iter()
            .map(|(path, _, _)| crate::io::load_mesh(path))
            .collect();
        let mut meshes = Vec::with_capacity(loaded.len());
        for (result, (_, object, file)) in loaded.into_iter().zip(&files) {
            meshes.push(Arc::new(result.map_err(|e| mesh_error(*object, file, e))?));
        }
        for (object, index) in mesh_of_object {
            if let Shape::Mesh { mesh, .. } = &mut objects[object].shape {
                *mesh = index as u32;
            }
        }
        Ok(meshes)
    }
}

/// Rotation by `deg` degrees about x, then y, then z (the convention of
/// [`Transform::from_srt`], so quads and meshes rotate alike).
fn euler_xyz(deg: Vec3A) -> glam::Mat3A {
    glam::Mat3A::from_quat(glam::Quat::from_euler(
        glam::EulerRot::ZYX,
        deg.z.to_radians(),
        deg.y.to_radians(),
        deg.x.to_radians(),
    ))
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

    #[test]
    fn euler_matches_the_mesh_transform() {
        let deg = Vec3A::new(30.0, -45.0, 60.0);
        let t = Transform::from_srt(Vec3::ONE, Vec3::from(deg), Vec3::ZERO).unwrap();
        let r = euler_xyz(deg);
        for v in [Vec3A::X, Vec3A::Y, Vec3A::Z] {
            assert!((t.point(v) - r * v).length() < 1e-6);
        }
    }
}
