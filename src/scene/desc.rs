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
    pub camera: Spanned<CameraDesc>,
    /// `[textures.NAME]`.
    #[serde(default)]
    pub textures: BTreeMap<String, Spanned<TextureDesc>>,
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
    /// `[media.NAME]`: homogeneous participating media bounded by objects
    /// (`interior` / `exterior`) or around the camera (`medium`).
    #[serde(default)]
    pub media: BTreeMap<String, Spanned<MediaDesc>>,
}

/// `[media.NAME]`: a homogeneous medium.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MediaDesc {
    /// Extinction coefficient per unit length: a number or `[r, g, b]`.
    pub sigma_t: Option<Spanned<ScaleDesc>>,
    /// Single-scattering albedo in [0, 1]: a number or `[r, g, b]`.
    pub albedo: Option<Spanned<ScaleDesc>>,
    /// Multiplies `sigma_t`.
    pub scale: Option<Spanned<f64>>,
    /// `"isotropic"` or `{ hg = g }`.
    pub phase: Option<Spanned<PhaseDesc>>,
    /// Scattering vertices sample a light (next-event estimation).
    pub sample_emitters: Option<Spanned<bool>>,
}

/// A medium's phase function: a name (`"isotropic"`) or a table naming
/// the Henyey–Greenstein asymmetry (`{ hg = 0.5 }`).
#[derive(Debug)]
pub enum PhaseDesc {
    /// A phase function by name.
    Name(String),
    /// `{ hg = g }`.
    Hg(HgDesc),
}

/// `{ hg = g }`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HgDesc {
    /// Henyey–Greenstein asymmetry, in (−1, 1).
    pub hg: f64,
}

struct PhaseVisitor;

impl<'de> Visitor<'de> for PhaseVisitor {
    type Value = PhaseDesc;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("\"isotropic\" or a table { hg = g }")
    }
    fn visit_str<E: de::Error>(self, s: &str) -> Result<PhaseDesc, E> {
        Ok(PhaseDesc::Name(s.to_string()))
    }
    fn visit_map<A: de::MapAccess<'de>>(self, map: A) -> Result<PhaseDesc, A::Error> {
        HgDesc::deserialize(de::value::MapAccessDeserializer::new(map)).map(PhaseDesc::Hg)
    }
}

impl<'de> Deserialize<'de> for PhaseDesc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(PhaseVisitor)
    }
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
    /// `"spot"`: a point light limited to a cone.
    Spot,
    /// `"directional"`: parallel light from infinitely far.
    Directional,
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
    /// `"disk"`: a flat disk (Mitsuba's `disk`).
    Disk,
    /// `"cylinder"`: an open tube without caps (Mitsuba's `cylinder`).
    Cylinder,
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
    /// Emitters seen directly by the camera are black.
    pub hide_emitters: Option<bool>,
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
    /// `"volpath"`: path tracing through the `[media]`; rays and shadow
    /// rays pass through `null` surfaces without a bounce.
    Volpath,
}

/// `[camera]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    /// Eye position.
    pub position: Spanned<Vec3Desc>,
    /// Point looked at (or give the exact frame: `forward`, `right`, `up`).
    pub look_at: Option<Spanned<Vec3Desc>>,
    /// Instead of `look_at`: the unit viewing direction, taken as written.
    pub forward: Option<Spanned<Vec3Desc>>,
    /// With `forward`: the unit image right vector, taken as written.
    pub right: Option<Spanned<Vec3Desc>>,
    /// Up direction (need not be orthogonal to the view).
    pub up: Option<Spanned<Vec3Desc>>,
    /// Vertical field of view in degrees.
    pub vfov: Option<Spanned<f64>>,
    /// Field of view in degrees across `fov_axis` (instead of `vfov`).
    pub fov: Option<Spanned<f64>>,
    /// `"x"`, `"y"`, `"diagonal"`, `"smaller"` or `"larger"`.
    pub fov_axis: Option<Spanned<String>>,
    /// `"perspective"` (the default) or `"orthographic"`.
    pub projection: Option<Spanned<String>>,
    /// Orthographic: the smallest half width shown (world units).
    pub half_width: Option<Spanned<f64>>,
    /// Orthographic: the smallest half height shown (world units).
    pub half_height: Option<Spanned<f64>>,
    /// Thin-lens radius (0: a pinhole).
    pub aperture_radius: Option<Spanned<f64>>,
    /// Distance of the plane in focus along the view axis.
    pub focus_distance: Option<Spanned<f64>>,
    /// Nothing nearer than this along the view axis is seen.
    pub near_clip: Option<Spanned<f64>>,
    /// Pixel filter: `"box"`, `"tent"` or `"gaussian"`.
    pub filter: Option<Spanned<String>>,
    /// Half width of a box or tent filter in pixels.
    pub filter_radius: Option<Spanned<f64>>,
    /// Standard deviation of a Gaussian filter in pixels.
    pub filter_stddev: Option<Spanned<f64>>,
    /// The `[media]` entry the camera is inside.
    pub medium: Option<Spanned<String>>,
}

/// `[materials.NAME]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialDesc {
    /// Specular lobe.
    pub model: Option<ModelName>,
    /// Ambient reflectance.
    pub ambient: Option<Spanned<ParamDesc>>,
    /// Diffuse albedo.
    pub diffuse: Option<Spanned<ParamDesc>>,
    /// Specular reflectance.
    pub specular: Option<Spanned<ParamDesc>>,
    /// Phong exponent.
    pub shininess: Option<Spanned<ParamDesc>>,
    /// Tangent-space normal map (a texture).
    pub normal_map: Option<Spanned<ParamDesc>>,
    /// Scale of the normal map's x and y.
    pub normal_scale: Option<Spanned<f64>>,
    /// A bump map: a scalar height texture.
    pub bump_map: Option<Spanned<ParamDesc>>,
    /// Multiplies the bump map's gradient.
    pub bump_scale: Option<Spanned<f64>>,
    /// Alpha cutout mask (a scalar texture).
    pub alpha: Option<Spanned<ParamDesc>>,
    /// Mask values below it are holes.
    pub alpha_cutoff: Option<Spanned<f64>>,
    /// `[materials.NAME.mirror]`.
    pub mirror: Option<Spanned<MirrorDesc>>,
    /// `[materials.NAME.dielectric]`.
    pub dielectric: Option<Spanned<DielectricDesc>>,
    /// `[materials.NAME.conductor]`.
    pub conductor: Option<Spanned<ConductorDesc>>,
    /// `[materials.NAME.coating]`.
    pub coating: Option<Spanned<CoatingDesc>>,
    /// `[materials.NAME.principled]`.
    pub principled: Option<Spanned<PrincipledDesc>>,
    /// `[materials.NAME.disney]`.
    pub disney: Option<Spanned<DisneyDesc>>,
    /// `[materials.NAME.blend]`.
    pub blend: Option<Spanned<BlendDesc>>,
    /// Emitted radiance: a colour, a number or a texture.
    pub emission: Option<Spanned<ParamDesc>>,
    /// Scale of `emission`.
    pub emission_strength: Option<Spanned<f64>>,
    /// Scatter only on the front side (the side the normal faces).
    pub one_sided: Option<Spanned<bool>>,
    /// `emission` leaves both sides of the surface (else the front only).
    pub emit_both_sides: Option<Spanned<bool>>,
    /// Microfacet distribution of the rough lobes: "ggx" or "beckmann".
    pub microfacet: Option<Spanned<String>>,
    /// Scatters nothing: rays pass straight through (a medium's boundary).
    pub null: Option<Spanned<bool>>,
}

/// `[materials.NAME.mirror]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MirrorDesc {
    /// Fraction of the colour taken from the reflected ray.
    pub reflectivity: Option<Spanned<ParamDesc>>,
    /// Colour filter on the reflection.
    pub tint: Option<Spanned<ParamDesc>>,
}

/// `[materials.NAME.dielectric]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DielectricDesc {
    /// Index of refraction of the inside.
    pub ior: Option<Spanned<f64>>,
    /// Colour filter on transmitted light.
    pub tint: Option<Spanned<ParamDesc>>,
    /// GGX roughness (0: smooth).
    pub roughness: Option<Spanned<ParamDesc>>,
    /// Roughness across the surface's `v` direction (anisotropic; `roughness`
    /// is then the one along `u`).
    pub roughness_v: Option<Spanned<ParamDesc>>,
    /// Fresnel formula.
    pub fresnel: Option<FresnelName>,
    /// A thin sheet: transmitted light passes straight through.
    pub thin: Option<Spanned<bool>>,
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
    pub roughness: Option<Spanned<ParamDesc>>,
    /// Roughness across the surface's `v` direction (anisotropic; `roughness`
    /// is then the one along `u`).
    pub roughness_v: Option<Spanned<ParamDesc>>,
}

/// `[materials.NAME.blend]`: two materials of the scene mixed by a weight.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BlendDesc {
    /// The material that scatters with probability `1 − weight`; absent: a hole.
    pub first: Option<Spanned<String>>,
    /// The material that scatters with probability `weight`; absent: a hole.
    pub second: Option<Spanned<String>>,
    /// Weight of `second`, in [0, 1]: a number or a scalar texture.
    pub weight: Option<Spanned<ParamDesc>>,
}

/// `[materials.NAME.coating]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CoatingDesc {
    /// Index of refraction of the coating.
    pub ior: Option<Spanned<f64>>,
    /// Microfacet roughness `alpha` of the coating (0: smooth), in the
    /// material's `microfacet` distribution.
    pub roughness: Option<Spanned<f64>>,
    /// The base's colour tints every inter-reflection under the coating.
    pub nonlinear: Option<bool>,
}

/// `[materials.NAME.principled]`: glTF's metallic-roughness model, with
/// the material's `diffuse` as its base colour.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrincipledDesc {
    /// Metalness in [0, 1]: a number or a scalar texture.
    pub metallic: Option<Spanned<ParamDesc>>,
    /// Perceptual roughness in [0, 1] (`alpha` is its square).
    pub roughness: Option<Spanned<ParamDesc>>,
    /// Index of refraction of the dielectric part.
    pub ior: Option<Spanned<f64>>,
    /// Transmitted fraction of the dielectric base, in [0, 1].
    pub transmission: Option<Spanned<ParamDesc>>,
    /// Transmission through a thin wall (no bending) rather than into a solid.
    pub thin: Option<Spanned<bool>>,
    /// Strength of the clear coat, in [0, 1].
    pub clearcoat: Option<Spanned<ParamDesc>>,
    /// Perceptual roughness of the clear coat, in [0, 1].
    pub clearcoat_roughness: Option<Spanned<ParamDesc>>,
}

/// `[materials.NAME.disney]`: Burley's Disney BSDF as Mitsuba 3 writes
/// it (its `principled`, or with `thin` its `principledthin`), with the
/// material's `diffuse` as its base colour. Weights are numbers in [0, 1]
/// or scalar textures.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DisneyDesc {
    /// Mitsuba's `principledthin`: a two-sided sheet with no interior.
    pub thin: Option<Spanned<bool>>,
    /// Burley's roughness (GGX `alpha` is its square).
    pub roughness: Option<Spanned<ParamDesc>>,
    /// Stretches the roughness along `∂p/∂u`.
    pub anisotropic: Option<Spanned<ParamDesc>>,
    /// Metalness (not thin).
    pub metallic: Option<Spanned<ParamDesc>>,
    /// Fraction of the dielectric that refracts (thin: that is specular).
    pub spec_trans: Option<Spanned<ParamDesc>>,
    /// Tints the dielectric reflection toward the base colour.
    pub spec_tint: Option<Spanned<ParamDesc>>,
    /// Strength of the sheen.
    pub sheen: Option<Spanned<ParamDesc>>,
    /// Tints the sheen toward the base colour.
    pub sheen_tint: Option<Spanned<ParamDesc>>,
    /// Blends the diffuse toward a fake subsurface.
    pub flatness: Option<Spanned<ParamDesc>>,
    /// Strength of the clear coat (not thin).
    pub clearcoat: Option<Spanned<ParamDesc>>,
    /// Glossiness of the clear coat (not thin).
    pub clearcoat_gloss: Option<Spanned<ParamDesc>>,
    /// Thin only: the share of the diffuse base transmitted, in [0, 2].
    pub diff_trans: Option<Spanned<ParamDesc>>,
    /// Index of the inside over the outside (thin: also a scalar texture).
    pub eta: Option<Spanned<ParamDesc>>,
    /// Instead of `eta` (not thin): `eta = 2 / (1 − sqrt(0.08 specular)) − 1`.
    pub specular: Option<Spanned<f64>>,
    /// Relative rate of sampling the diffuse reflection.
    pub diffuse_sampling_rate: Option<Spanned<f64>>,
    /// Relative rate of sampling the specular reflection.
    pub specular_sampling_rate: Option<Spanned<f64>>,
    /// Relative rate of sampling the clear coat (not thin).
    pub clearcoat_sampling_rate: Option<Spanned<f64>>,
    /// Thin only: relative rate of sampling the specular transmission.
    pub specular_transmission_sampling_rate: Option<Spanned<f64>>,
    /// Thin only: relative rate of sampling the diffuse transmission.
    pub diffuse_transmission_sampling_rate: Option<Spanned<f64>>,
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
    /// Environment: a latitude-longitude image (HDR, EXR, PNG, JPEG).
    pub file: Option<Spanned<String>>,
    /// Environment: rotation of the image, degrees about x then y then z.
    pub rotate: Option<Spanned<Vec3Desc>>,
    /// Spot: the point the cone's axis goes through.
    pub look_at: Option<Spanned<Vec3Desc>>,
    /// Spot: the cone's axis; directional: the direction light travels in.
    pub direction: Option<Spanned<Vec3Desc>>,
    /// Spot: half-angle of the cone, degrees.
    pub cutoff_angle: Option<Spanned<f64>>,
    /// Spot: half-angle of full intensity, degrees.
    pub beam_width: Option<Spanned<f64>>,
    /// Spot: the ramp between `beam_width` and `cutoff_angle`, `"mitsuba"`
    /// (linear in the angle, the default) or `"gltf"` (squared, linear in
    /// the cosine).
    pub falloff: Option<Spanned<String>>,
}

/// `[[objects]]`: the keys of every object type (the loader checks which
/// apply to `type`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectDesc {
    /// `"sphere"`, `"quad"`, `"disk"`, `"cylinder"`, `"mesh"` or `"water"`.
    #[serde(rename = "type")]
    pub kind: Spanned<ObjectKind>,
    /// Name used in messages.
    pub name: Option<String>,
    /// Material name (a key of `[materials]`).
    pub material: Spanned<String>,
    /// Sphere, disk or quad centre (a quad's with `size`), or water centre
    /// (its `y` is the mean water level).
    pub center: Option<Spanned<Vec3Desc>>,
    /// Sphere, disk or cylinder radius.
    pub radius: Option<Spanned<f64>>,
    /// Cylinder: centre of the end where `v = 0`.
    pub p0: Option<Spanned<Vec3Desc>>,
    /// Cylinder: centre of the end where `v = 1`.
    pub p1: Option<Spanned<Vec3Desc>>,
    /// Cylinder: the normals point toward the axis (Mitsuba's `flip_normals`);
    /// disk given by `u` and `v`: it faces `−(u × v)`.
    pub flip_normals: Option<Spanned<bool>>,
    /// Quad corner (with `u` and `v`).
    pub corner: Option<Spanned<Vec3Desc>>,
    /// Quad first edge, or a disk's first semi-axis (the image of its local x).
    pub u: Option<Spanned<Vec3Desc>>,
    /// Quad second edge, or a disk's second semi-axis (the image of its local y).
    pub v: Option<Spanned<Vec3Desc>>,
    /// Quad `[width, height]` (with `center`), or water extent `[x, z]`.
    pub size: Option<Spanned<Vec2Desc>>,
    /// Quad or disk facing direction (a quad's with `center` and `size`).
    pub normal: Option<Spanned<Vec3Desc>>,
    /// Quad height direction, or the direction of a disk's `φ = π/2`
    /// (with `normal`).
    pub up: Option<Spanned<Vec3Desc>>,
    /// Quad, disk or mesh rotation, degrees about x then y then z.
    pub rotate: Option<Spanned<Vec3Desc>>,
    /// Mesh file (relative to the scene file) or `asset:NAME`.
    pub file: Option<Spanned<String>>,
    /// Mesh translation.
    pub translate: Option<Spanned<Vec3Desc>>,
    /// Mesh object-to-world affine matrix, three rows of four numbers
    /// (instead of `translate`, `rotate`, `scale`).
    pub matrix: Option<Spanned<MatrixDesc>>,
    /// Mesh scale: one number or `[x, y, z]`.
    pub scale: Option<Spanned<ScaleDesc>>,
    /// Mesh smooth shading.
    pub smooth: Option<Spanned<bool>>,
    /// Water: the sine waves of the height field.
    pub waves: Option<Spanned<Vec<WaveDesc>>>,
    /// Water: grid cells `[along x, along z]`.
    pub resolution: Option<Spanned<Vec2Desc>>,
    /// The `[media]` entry inside the object (against its normals).
    pub interior: Option<Spanned<String>>,
    /// The `[media]` entry outside the object (where its normals point).
    pub exterior: Option<Spanned<String>>,
}

/// `[textures.NAME]`, or a texture written inline as a parameter's value:
/// the keys of every texture type (the loader checks which apply to `type`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TextureDesc {
    /// `"image"` or `"checkerboard"`.
    #[serde(rename = "type")]
    pub kind: Spanned<TextureKind>,
    /// Image: the file (relative to the scene file).
    pub file: Option<Spanned<String>>,
    /// Image: `"srgb"` or `"linear"` (default: sRGB for colours, linear for data).
    pub colour_space: Option<Spanned<String>>,
    /// Image: `"repeat"`, `"clamp"`, `"mirror"`, or `[along u, along v]`.
    pub wrap: Option<Spanned<WrapDesc>>,
    /// Image: `"bilinear"` or `"nearest"`.
    pub filter: Option<Spanned<String>>,
    /// Image: multiplies the colour (a number or `[r, g, b]`).
    pub factor: Option<Spanned<ScaleDesc>>,
    /// Image: which channel a scalar parameter reads.
    pub channel: Option<Spanned<String>>,
    /// Checkerboard: the colour (or number) of the squares at the origin.
    #[serde(alias = "color0")]
    pub colour0: Option<Spanned<ScaleDesc>>,
    /// Checkerboard: the other colour (or number).
    #[serde(alias = "color1")]
    pub colour1: Option<Spanned<ScaleDesc>>,
    /// UV scale: one number or `[u, v]`.
    pub scale: Option<Spanned<Scale2Desc>>,
    /// UV rotation in degrees, counter-clockwise.
    pub rotation: Option<Spanned<f64>>,
    /// UV offset `[u, v]`.
    pub offset: Option<Spanned<Vec2Desc>>,
}

/// Texture type names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TextureKind {
    /// `"image"`.
    Image,
    /// `"checkerboard"`.
    Checkerboard,
}

/// A wrap mode for both axes, or one per axis.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum WrapDesc {
    /// The same mode along u and v.
    Both(String),
    /// `[along u, along v]`.
    PerAxis([String; 2]),
}

/// A uniform UV scale or one per axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scale2Desc {
    /// The same factor along u and v.
    Uniform(f64),
    /// `[u, v]`.
    PerAxis([f64; 2]),
}

/// A material parameter's value: a number, a colour, the name of a
/// `[textures]` entry, or an inline texture table.
#[derive(Debug)]
pub enum ParamDesc {
    /// A number (a scalar, or a grey colour).
    Number(f64),
    /// `[r, g, b]`.
    Colour([f64; 3]),
    /// A key of `[textures]`.
    Texture(String),
    /// A texture described in place.
    Inline(Box<TextureDesc>),
}

/// An array of exactly three numbers (integers or floats; validity is
/// checked by the loader).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vec3Desc(pub [f64; 3]);

/// Three rows of four numbers: an affine matrix `[linear | translation]`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
pub struct MatrixDesc(pub [Vec4Desc; 3]);

/// An array of exactly four numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vec4Desc(pub [f64; 4]);

impl<'de> Deserialize<'de> for Vec4Desc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_seq(NumbersVisitor::<4>).map(Vec4Desc)
    }
}

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

struct Scale2Visitor;

impl<'de> Visitor<'de> for Scale2Visitor {
    type Value = Scale2Desc;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a number or an array of 2 numbers")
    }
    fn visit_f64<E: de::Error>(self, x: f64) -> Result<Scale2Desc, E> {
        Ok(Scale2Desc::Uniform(x))
    }
    fn visit_i64<E: de::Error>(self, x: i64) -> Result<Scale2Desc, E> {
        Ok(Scale2Desc::Uniform(x as f64))
    }
    fn visit_u64<E: de::Error>(self, x: u64) -> Result<Scale2Desc, E> {
        Ok(Scale2Desc::Uniform(x as f64))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Scale2Desc, A::Error> {
        visit_numbers::<A, 2>(seq).map(Scale2Desc::PerAxis)
    }
}

impl<'de> Deserialize<'de> for Scale2Desc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(Scale2Visitor)
    }
}

struct ParamVisitor;

impl<'de> Visitor<'de> for ParamVisitor {
    type Value = ParamDesc;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a number, an array of 3 numbers, a texture name or a texture table")
    }
    fn visit_f64<E: de::Error>(self, x: f64) -> Result<ParamDesc, E> {
        Ok(ParamDesc::Number(x))
    }
    fn visit_i64<E: de::Error>(self, x: i64) -> Result<ParamDesc, E> {
        Ok(ParamDesc::Number(x as f64))
    }
    fn visit_u64<E: de::Error>(self, x: u64) -> Result<ParamDesc, E> {
        Ok(ParamDesc::Number(x as f64))
    }
    fn visit_str<E: de::Error>(self, s: &str) -> Result<ParamDesc, E> {
        Ok(ParamDesc::Texture(s.to_string()))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<ParamDesc, A::Error> {
        visit_numbers::<A, 3>(seq).map(ParamDesc::Colour)
    }
    fn visit_map<A: de::MapAccess<'de>>(self, map: A) -> Result<ParamDesc, A::Error> {
        TextureDesc::deserialize(de::value::MapAccessDeserializer::new(map)).map(|t| ParamDesc::Inline(Box::new(t)))
    }
}

impl<'de> Deserialize<'de> for ParamDesc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(ParamVisitor)
    }
}
