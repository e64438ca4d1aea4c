//! The scene file format: serde structs that mirror the TOML file one to one
//! (documented key by key in `docs/scene-format.md`).
//!
//! Nothing here is validated beyond types: `scene::load` turns a
//! [`SceneDesc`] into a `Scene` and checks every value. Fields whose
//! value can be wrong (a negative radius, an unknown material) are kept as
//! [`Spanned`] so that the error can point at the offending value by line and
//! column. Every table rejects unknown keys (`deny_unknown_fields`).
//!
//! Objects and lights are flat structs with a `type` key rather than serde
//! tagged enums: serde buffers tagged enums into an intermediate value, which
//! loses the byte spans (`Spanned` fields would then fail to deserialize and
//! errors would point at the whole table). The loader checks which keys apply
//! to which `type`.

use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::fmt;

pub use toml::Spanned;

/// The whole file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneDesc {
    /// `[render]` (all keys optional).
    #[serde(default)]
    pub render: RenderDesc,
    /// `[camera]` (required).
    pub camera: CameraDesc,
    /// `[materials.NAME]`.
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialDesc>,
    /// `[[lights]]`.
    #[serde(default)]
    pub lights: Vec<LightDesc>,
    /// `[[objects]]`.
    #[serde(default)]
    pub objects: Vec<ObjectDesc>,
    /// `[photons]` (all keys optional).
    #[serde(default)]
    pub photons: PhotonsDesc,
    /// `[medium]`: fog inside the water.
    pub medium: Option<Spanned<MediumDesc>>,
}

/// `[photons]`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhotonsDesc {
    /// Photons emitted.
    pub count: Option<Spanned<i64>>,
    /// Photons gathered per estimate.
    pub k: Option<Spanned<i64>>,
    /// Largest gather radius.
    pub max_radius: Option<Spanned<f64>>,
    /// Cone-filter constant.
    pub cone_k: Option<Spanned<f64>>,
    /// `"precomputed"` or `"direct"`.
    pub gather: Option<GatherName>,
    /// `"path"` or `"map"`.
    pub caustics: Option<CausticsName>,
    /// Progressive photon mapping: a new map and a smaller radius per sample.
    pub progressive: Option<bool>,
    /// Progressive photon mapping's radius reduction `α ∈ (0, 1)`.
    pub alpha: Option<Spanned<f64>>,
}

/// How the path integrator finds caustics.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CausticsName {
    /// `"path"`.
    Path,
    /// `"map"`.
    Map,
}

/// Photon gather modes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum GatherName {
    /// `"precomputed"`.
    Precomputed,
    /// `"direct"`.
    Direct,
}

/// `[medium]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MediumDesc {
    /// Extinction per unit length of the fog.
    pub density: Spanned<f64>,
    /// Fog colour (`color` is accepted too).
    #[serde(alias = "color")]
    pub colour: Option<Spanned<Vec3Desc>>,
    /// Absorption coefficient per channel (path tracing).
    pub absorption: Option<Spanned<Vec3Desc>>,
    /// Scattering coefficient per channel (path tracing).
    pub scattering: Option<Spanned<Vec3Desc>>,
    /// Henyey–Greenstein asymmetry (path tracing).
    pub g: Option<Spanned<f64>>,
}

/// One wave of a water surface (`waves = [{ … }, …]`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WaveDesc {
    /// Crest height above the mean level.
    pub amplitude: Spanned<f64>,
    /// Distance between crests.
    pub wavelength: Spanned<f64>,
    /// Direction of travel `[x, z]`.
    pub direction: Spanned<Vec2Desc>,
    /// Phase in degrees.
    pub phase: Option<Spanned<f64>>,
}

/// Tone mapping names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ToneMapName {
    /// `"aces"`.
    Aces,
    /// `"clamp"`.
    Clamp,
}

/// Ray–triangle test names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TriangleTestName {
    /// `"watertight"`.
    Watertight,
    /// `"moller-trumbore"`.
    MollerTrumbore,
}

/// Sample sharing names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SharingName {
    /// `"spread"`.
    Spread,
    /// `"split"`.
    Split,
}

/// Shading model names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ModelName {
    /// `"phong"`.
    Phong,
    /// `"blinn-phong"`.
    BlinnPhong,
}

/// Light type names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LightKind {
    /// `"point"`.
    Point,
    /// `"area"`.
    Area,
    /// `"environment"`: constant radiance from every direction.
    Environment,
}

/// Object type names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ObjectKind {
    /// `"sphere"`.
    Sphere,
    /// `"quad"`.
    Quad,
    /// `"mesh"`.
    Mesh,
    /// `"water"`: a procedural height-field surface.
    Water,
}

/// `[render]`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderDesc {
    /// Image width in pixels.
    pub width: Option<Spanned<u32>>,
    /// Image height in pixels.
    pub height: Option<Spanned<u32>>,
    /// Samples per pixel.
    pub spp: Option<Spanned<u32>>,
    /// Maximum number of specular bounces.
    pub max_depth: Option<Spanned<u32>>,
    /// Seed of every random stream.
    pub seed: Option<u64>,
    /// Tone mapping for 8-bit output.
    pub tone_map: Option<ToneMapName>,
    /// Exposure in stops.
    pub exposure: Option<Spanned<f64>>,
    /// Ambient light colour.
    pub ambient: Option<Spanned<Vec3Desc>>,
    /// Ray–triangle test.
    pub triangle_test: Option<TriangleTestName>,
    /// Sample sharing between a pixel's samples.
    pub sharing: Option<SharingName>,
    /// Light transport algorithm.
    pub integrator: Option<IntegratorName>,
    /// Sample generator.
    pub sampler: Option<SamplerName>,
    /// Adaptive sampling's relative error target.
    pub noise_threshold: Option<Spanned<f64>>,
    /// Samples before adaptive sampling stops a pixel.
    pub min_spp: Option<Spanned<u32>>,
    /// What the noise threshold bounds.
    pub adaptive_goal: Option<AdaptiveGoalName>,
    /// Denoise the final image (Open Image Denoise).
    pub denoise: Option<bool>,
    /// The denoising filter's quality.
    pub denoise_quality: Option<DenoiseQualityName>,
}

/// Denoising filter quality names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DenoiseQualityName {
    /// `"high"`.
    High,
    /// `"balanced"`.
    Balanced,
    /// `"fast"`.
    Fast,
}

/// Adaptive goal names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum AdaptiveGoalName {
    /// `"pixel"`.
    Pixel,
    /// `"image"`.
    Image,
}

/// Sampler names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SamplerName {
    /// `"sobol"`.
    Sobol,
    /// `"independent"`.
    Independent,
}

/// Integrator names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum IntegratorName {
    /// `"whitted"`.
    Whitted,
    /// `"path"`.
    Path,
}

/// `[camera]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    /// Eye position.
    pub position: Spanned<Vec3Desc>,
    /// Point looked at.
    pub look_at: Spanned<Vec3Desc>,
    /// Up direction (need not be orthogonal to the view).
    pub up: Option<Spanned<Vec3Desc>>,
    /// Vertical field of view in degrees.
    pub vfov: Option<Spanned<f64>>,
}

/// `[materials.NAME]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialDesc {
    /// Specular lobe.
    pub model: Option<ModelName>,
    /// Ambient reflectance.
    pub ambient: Option<Spanned<Vec3Desc>>,
    /// Diffuse albedo.
    pub diffuse: Option<Spanned<Vec3Desc>>,
    /// Specular reflectance.
    pub specular: Option<Spanned<Vec3Desc>>,
    /// Phong exponent.
    pub shininess: Option<Spanned<f64>>,
    /// `[materials.NAME.mirror]`.
    pub mirror: Option<Spanned<MirrorDesc>>,
    /// `[materials.NAME.dielectric]`.
    pub dielectric: Option<Spanned<DielectricDesc>>,
    /// `[materials.NAME.conductor]`.
    pub conductor: Option<Spanned<ConductorDesc>>,
    /// `[materials.NAME.coating]`.
    pub coating: Option<Spanned<CoatingDesc>>,
}

/// `[materials.NAME.mirror]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MirrorDesc {
    /// Fraction of the colour taken from the reflected ray.
    pub reflectivity: Option<Spanned<f64>>,
    /// Colour filter on the reflection.
    pub tint: Option<Spanned<Vec3Desc>>,
}

/// `[materials.NAME.dielectric]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DielectricDesc {
    /// Index of refraction of the inside.
    pub ior: Option<Spanned<f64>>,
    /// Colour filter on transmitted light.
    pub tint: Option<Spanned<Vec3Desc>>,
    /// GGX roughness (0: smooth).
    pub roughness: Option<Spanned<f64>>,
    /// Fresnel formula.
    pub fresnel: Option<FresnelName>,
}

/// Fresnel formula names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FresnelName {
    /// `"exact"`.
    Exact,
    /// `"schlick"`.
    Schlick,
}

/// `[materials.NAME.conductor]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConductorDesc {
    /// A named metal (`gold`, `silver`, `copper`, `aluminium`).
    pub metal: Option<Spanned<String>>,
    /// Real part of the index, per channel.
    pub eta: Option<Spanned<Vec3Desc>>,
    /// Extinction coefficient, per channel.
    pub k: Option<Spanned<Vec3Desc>>,
    /// GGX roughness (0: smooth).
    pub roughness: Option<Spanned<f64>>,
}

/// `[materials.NAME.coating]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CoatingDesc {
    /// Index of refraction of the coating.
    pub ior: Option<Spanned<f64>>,
}

/// `[[lights]]`: the keys of every light type (the loader checks which
/// apply to `type`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightDesc {
    /// `"point"` or `"area"`.
    #[serde(rename = "type")]
    pub kind: Spanned<LightKind>,
    /// Position (point) or centre of the rectangle (area).
    pub position: Option<Spanned<Vec3Desc>>,
    /// Colour (`color` is accepted too).
    #[serde(alias = "color")]
    pub colour: Option<Spanned<Vec3Desc>>,
    /// Scale applied to the colour.
    pub intensity: Option<Spanned<f64>>,
    /// Area: first edge.
    pub u: Option<Spanned<Vec3Desc>>,
    /// Area: second edge.
    pub v: Option<Spanned<Vec3Desc>>,
    /// Area: shadow rays per shading point.
    pub samples: Option<Spanned<u32>>,
}

/// `[[objects]]`: the keys of every object type (the loader checks which
/// apply to `type`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectDesc {
    /// `"sphere"`, `"quad"`, `"mesh"` or `"water"`.
    #[serde(rename = "type")]
    pub kind: Spanned<ObjectKind>,
    /// Name used in messages.
    pub name: Option<String>,
    /// Material name (a key of `[materials]`).
    pub material: Spanned<String>,
    /// Sphere centre, quad centre (with `size`), or water centre (its `y`
    /// is the mean water level).
    pub center: Option<Spanned<Vec3Desc>>,
    /// Sphere radius.
    pub radius: Option<Spanned<f64>>,
    /// Quad corner (with `u` and `v`).
    pub corner: Option<Spanned<Vec3Desc>>,
    /// Quad first edge.
    pub u: Option<Spanned<Vec3Desc>>,
    /// Quad second edge.
    pub v: Option<Spanned<Vec3Desc>>,
    /// Quad `[width, height]` (with `center`), or water extent `[x, z]`.
    pub size: Option<Spanned<Vec2Desc>>,
    /// Quad facing direction (with `center` and `size`).
    pub normal: Option<Spanned<Vec3Desc>>,
    /// Quad height direction (with `normal`).
    pub up: Option<Spanned<Vec3Desc>>,
    /// Quad or mesh rotation, degrees about x then y then z.
    pub rotate: Option<Spanned<Vec3Desc>>,
    /// Mesh file (relative to the scene file) or `asset:NAME`.
    pub file: Option<Spanned<String>>,
    /// Mesh translation.
    pub translate: Option<Spanned<Vec3Desc>>,
    /// Mesh scale: one number or `[x, y, z]`.
    pub scale: Option<Spanned<ScaleDesc>>,
    /// Mesh smooth shading.
    pub smooth: Option<Spanned<bool>>,
    /// Water: the sine waves of the height field.
    pub waves: Option<Spanned<Vec<WaveDesc>>>,
    /// Water: grid cells `[along x, along z]`.
    pub resolution: Option<Spanned<Vec2Desc>>,
}

/// An array of exactly three numbers (integers or floats; validity is
/// checked by the loader).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vec3Desc(pub [f64; 3]);

/// An array of exactly two numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vec2Desc(pub [f64; 2]);

/// A uniform scale (one number) or a per-axis scale (three numbers).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ScaleDesc {
    /// The same factor on every axis.
    Uniform(f64),
    /// One factor per axis.
    PerAxis([f64; 3]),
}

/// Reads a sequence of numbers and requires exactly `N` of them. Written by
/// hand (rather than serde's `[f64; N]`) so that a wrong length says how
/// many numbers were found, whatever the deserializer does with extras.
fn visit_numbers<'de, A: SeqAccess<'de>, const N: usize>(mut seq: A) -> Result<[f64; N], A::Error> {
    let mut out = [0.0; N];
    let mut count = 0usize;
    while let Some(x) = seq.next_element::<f64>()? {
        if count < N {
            out[count] = x;
        }
        count += 1;
    }
    if count != N {
        return Err(de::Error::custom(format!(
            "expected an array of {N} numbers, found {count} element{}",
            if count == 1 { "" } else { "s" }
        )));
    }
    Ok(out)
}

struct NumbersVisitor<const N: usize>;

impl<'de, const N: usize> Visitor<'de> for NumbersVisitor<N> {
    type Value = [f64; N];
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "an array of {N} numbers")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Self::Value, A::Error> {
        visit_numbers(seq)
    }
}

impl<'de> Deserialize<'de> for Vec3Desc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_seq(NumbersVisitor::<3>).map(Vec3Desc)
    }
}

impl<'de> Deserialize<'de> for Vec2Desc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_seq(NumbersVisitor::<2>).map(Vec2Desc)
    }
}

struct ScaleVisitor;

impl<'de> Visitor<'de> for ScaleVisitor {
    type Value = ScaleDesc;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a number or an array of 3 numbers")
    }
    fn visit_f64<E: de::Error>(self, x: f64) -> Result<ScaleDesc, E> {
        Ok(ScaleDesc::Uniform(x))
    }
    fn visit_i64<E: de::Error>(self, x: i64) -> Result<ScaleDesc, E> {
        Ok(ScaleDesc::Uniform(x as f64))
    }
    fn visit_u64<E: de::Error>(self, x: u64) -> Result<ScaleDesc, E> {
        Ok(ScaleDesc::Uniform(x as f64))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<ScaleDesc, A::Error> {
        visit_numbers::<A, 3>(seq).map(ScaleDesc::PerAxis)
    }
}

impl<'de> Deserialize<'de> for ScaleDesc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(ScaleVisitor)
    }
}
