//! Surface materials: a Phong or Blinn-Phong surface, optionally mixed with a
//! mirror reflection, or a dielectric (glass, water), a metal or a coated
//! diffuse; any colour, roughness and weight may be a texture
//! ([`MaterialTextures`]), evaluated at a shading point by [`Material::at`].

use crate::math::{Vec2, Vec3A};
use crate::texture::Texture;
use std::borrow::Cow;

/// Which specular lobe the local model uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadingModel {
    /// `(R·V)^n` (Phong 1975).
    Phong,
    /// `(N·H)^n` with the half vector (Blinn 1977).
    BlinnPhong,
}

/// Perfect mirror reflection mixed with the surface colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mirror {
    /// Fraction of the result taken from the reflected ray, in [0, 1].
    pub reflectivity: f32,
    /// Colour filter on the reflected light.
    pub tint: Vec3A,
}

/// Which Fresnel formula a dielectric uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FresnelModel {
    /// The exact unpolarised reflectance.
    Exact,
    /// Schlick's approximation (the original report's).
    Schlick,
}

/// Dielectric interface (glass, water): Fresnel-weighted reflection and
/// refraction, smooth or rough.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric {
    /// Index of refraction of the inside (the outside is 1).
    pub ior: f32,
    /// Colour filter on transmitted light.
    pub tint: Vec3A,
    /// Microfacet roughness `alpha` (0: smooth). The Whitted integrator treats
    /// every dielectric as smooth.
    pub roughness: f32,
    /// Fresnel formula; `None`: each integrator's own (Whitted: Schlick,
    /// as in the original report; path: exact).
    pub fresnel: Option<FresnelModel>,
    /// A thin sheet (a window pane) rather than the boundary of a solid:
    /// light that is not reflected by the sheet's two faces passes
    /// straight through. Always smooth.
    pub thin: bool,
}

impl Dielectric {
    /// A smooth dielectric of index `ior` with a colour filter.
    pub fn smooth(ior: f32, tint: Vec3A) -> Self {
        Self {
            ior,
            tint,
            roughness: 0.0,
            fresnel: None,
            thin: false,
        }
    }
}

/// A metal: complex index of refraction `eta + i k` per channel, smooth or
/// rough.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    /// Real part of the index.
    pub eta: Vec3A,
    /// Extinction coefficient.
    pub k: Vec3A,
    /// Microfacet roughness `alpha` (0: a perfect mirror).
    pub roughness: f32,
}

/// The microfacet distribution of a material's rough lobes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MicrofacetDistribution {
    /// GGX (Trowbridge–Reitz): long tails.
    #[default]
    Ggx,
    /// Beckmann: a Gaussian distribution of slopes (Mitsuba's default).
    Beckmann,
}

impl MicrofacetDistribution {
    /// Name as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            MicrofacetDistribution::Ggx => "ggx",
            MicrofacetDistribution::Beckmann => "beckmann",
        }
    }
}

/// A clear dielectric coating over the diffuse albedo (plastic, varnish),
/// smooth or rough.
#[derive(Clone, Debug, PartialEq)]
pub struct Coating {
    /// Index of refraction of the coating.
    pub ior: f32,
    /// Microfacet roughness `alpha` of the coating's surface, in the
    /// material's [`MicrofacetDistribution`] (0: smooth, a delta reflection).
    pub roughness: f32,
    /// Light scattered back and forth under the coating is tinted by the
    /// base's colour at every bounce (Mitsuba's `nonlinear`: `kd / (1 − kd
    /// F_dr)` instead of `kd / (1 − F_dr)`), which saturates colours.
    pub nonlinear: bool,
    /// The rough coating's transmittance table, computed from the fields
    /// above on first use.
    pub table: CoatingTableCell,
}

impl Coating {
    /// A smooth, linear coating of index `ior`.
    pub fn smooth(ior: f32) -> Self {
        Self {
            ior,
            roughness: 0.0,
            nonlinear: false,
            table: CoatingTableCell::default(),
        }
    }
}

/// How much light a rough dielectric coating lets through, tabulated once
/// per material (Mitsuba's `roughplastic`): the directional transmittance
/// `t(μ)` of the coating seen from outside at cosine `μ`, at
/// [`COATING_TABLE_SIZE`] cosines evenly spaced over [0, 1], and the
/// hemispherical reflectance of its underside `F_dr`.
#[derive(Clone, Debug, PartialEq)]
pub struct CoatingTable {
    /// `t(μ_i)`, `μ_i = i / (COATING_TABLE_SIZE − 1)`.
    pub transmittance: [f32; COATING_TABLE_SIZE],
    /// Internal hemispherical reflectance of the coating.
    pub internal_reflectance: f32,
}

/// Entries of [`CoatingTable::transmittance`] (Mitsuba's resolution).
pub const COATING_TABLE_SIZE: usize = 64;

impl CoatingTable {
    /// `t(μ)` by linear interpolation between the entries.
    #[inline]
    pub fn transmittance_at(&self, mu: f32) -> f32 {
        let x = mu.clamp(0.0, 1.0) * (COATING_TABLE_SIZE - 1) as f32;
        let i = (x as usize).min(COATING_TABLE_SIZE - 2);
        let w = x - i as f32;
        self.transmittance[i] * (1.0 - w) + self.transmittance[i + 1] * w
    }
}

/// A lazily filled, shared [`CoatingTable`]: the table depends only on the
/// coating's index, roughness and distribution, so copies of a material
/// share it, and two cells always compare equal (the table is derived data).
#[derive(Clone, Default)]
pub struct CoatingTableCell(pub std::sync::Arc<std::sync::OnceLock<CoatingTable>>);

impl PartialEq for CoatingTableCell {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl std::fmt::Debug for CoatingTableCell {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("CoatingTableCell")
    }
}

/// glTF 2.0's metallic-roughness material (the specification's Appendix B,
/// with `KHR_materials_transmission`, `_ior`, `_volume` and `_clearcoat`):
/// a Lambertian base under a GGX dielectric specular layer mixed with a
/// metal whose normal-incidence reflectance is the base colour, optionally
/// transmitting and under a clear coat. The base colour is the material's
/// [`Material::diffuse`] (and its texture).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Principled {
    /// Metalness in [0, 1]: 0 a dielectric, 1 a metal (F0 = base colour).
    pub metallic: f32,
    /// Perceptual roughness in [0, 1]; the GGX `alpha` is its square.
    pub roughness: f32,
    /// Index of refraction of the dielectric part (1.5: F0 = 4 %).
    pub ior: f32,
    /// Fraction of the dielectric base that is transmitted (tinted by the
    /// base colour) instead of reflected diffusely, in [0, 1].
    pub transmission: f32,
    /// Transmitted light continues without bending (glTF's thin-walled
    /// default, no `KHR_materials_volume`); else the surface bounds a
    /// refracting solid of index [`ior`](Self::ior).
    pub thin: bool,
    /// Strength of a clear coat of index 1.5 over everything, in [0, 1].
    pub clearcoat: f32,
    /// Perceptual roughness of the clear coat.
    pub clearcoat_roughness: f32,
}

impl Default for Principled {
    /// glTF's defaults: a fully metallic, fully rough surface of index 1.5.
    fn default() -> Self {
        Self {
            metallic: 1.0,
            roughness: 1.0,
            ior: 1.5,
            transmission: 0.0,
            thin: true,
            clearcoat: 0.0,
            clearcoat_roughness: 0.0,
        }
    }
}

/// Mitsuba 3's `principled` BSDF (Burley 2012/2015, "Physically Based
/// Shading at Disney" and "Extending the Disney BRDF to a BSDF with
/// Integrated Subsurface Scattering", as `src/bsdfs/principled.cpp`
/// implements it): a diffuse base with retro-reflection, fake subsurface
/// (`flatness`) and sheen, a GGX specular lobe that blends a dielectric
/// (index [`eta`](Self::eta)), a tinted Schlick term and a metal, a rough
/// refraction, and a GTR1 clear coat. The base colour is the material's
/// [`Material::diffuse`] (and its texture). A weight of 0 turns its lobe off.
///
/// With [`thin`](Self::thin) it is Mitsuba's `principledthin` instead
/// (`src/bsdfs/principledthin.cpp`): a two-sided sheet with no interior,
/// whose specular part (`spec_trans`) reflects and passes straight
/// through (reflected, then mirrored to the other side), the rest a
/// diffuse base with sheen split between reflection and Lambertian
/// transmission by [`diff_trans`](Self::diff_trans); `metallic`,
/// `clearcoat` and `clearcoat_gloss` are then unused (0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disney {
    /// Burley's roughness: the GGX `alpha` is its square (at least 0.001).
    pub roughness: f32,
    /// Anisotropy: `alpha` stretched along `∂p/∂u` by `1 / sqrt(1 − 0.9 a)`.
    pub anisotropic: f32,
    /// Metalness: blends toward a Schlick metal whose `F0` is the base colour.
    pub metallic: f32,
    /// Fraction of the dielectric that refracts instead of scattering diffusely.
    pub spec_trans: f32,
    /// Index of the inside relative to the outside (Mitsuba's `eta`, or from
    /// `specular` as `2 / (1 − sqrt(0.08 specular)) − 1`).
    pub eta: f32,
    /// Tints the dielectric's specular reflection toward the base colour.
    pub spec_tint: f32,
    /// Strength of the sheen at grazing angles.
    pub sheen: f32,
    /// Tints the sheen toward the base colour.
    pub sheen_tint: f32,
    /// Blends the diffuse toward Hanrahan–Krueger's fake subsurface.
    pub flatness: f32,
    /// Strength of the clear coat.
    pub clearcoat: f32,
    /// Glossiness of the clear coat: its GTR1 `alpha` goes from 0.1 to 0.001.
    pub clearcoat_gloss: f32,
    /// Relative rate of sampling the diffuse lobe.
    pub diffuse_sampling_rate: f32,
    /// Relative rate of sampling the main specular lobe.
    pub specular_sampling_rate: f32,
    /// Relative rate of sampling the clear coat.
    pub clearcoat_sampling_rate: f32,
    /// Mitsuba's `principledthin`: a thin two-sided sheet.
    pub thin: bool,
    /// Thin only: the share of the diffuse base transmitted, in [0, 2]
    /// (2: all of it; Mitsuba halves it).
    pub diff_trans: f32,
    /// Thin only: relative rate of sampling the specular transmission
    /// ([`specular_sampling_rate`](Self::specular_sampling_rate) is then
    /// that of the specular reflection).
    pub specular_transmission_sampling_rate: f32,
    /// Thin only: relative rate of sampling the diffuse transmission.
    pub diffuse_transmission_sampling_rate: f32,
}

impl Default for Disney {
    /// Mitsuba's defaults: roughness 0.5, `specular` 0.5, everything else off.
    fn default() -> Self {
        Self {
            roughness: 0.5,
            anisotropic: 0.0,
            metallic: 0.0,
            spec_trans: 0.0,
            eta: 2.0 / (1.0 - (0.08f32 * 0.5).sqrt()) - 1.0,
            spec_tint: 0.0,
            sheen: 0.0,
            sheen_tint: 0.0,
            flatness: 0.0,
            clearcoat: 0.0,
            clearcoat_gloss: 0.0,
            diffuse_sampling_rate: 1.0,
            specular_sampling_rate: 1.0,
            clearcoat_sampling_rate: 1.0,
            thin: false,
            diff_trans: 0.0,
            specular_transmission_sampling_rate: 1.0,
            diffuse_transmission_sampling_rate: 1.0,
        }
    }
}

impl Disney {
    /// Mitsuba's `principledthin` defaults: roughness 0.5, `eta` 1.5,
    /// everything else off.
    pub fn thin_default() -> Self {
        Self {
            eta: 1.5,
            thin: true,
            ..Self::default()
        }
    }
}

/// A named material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name in the scene file.
    pub name: String,
    /// Specular lobe.
    pub model: ShadingModel,
    /// Ambient reflectance (multiplies the scene's ambient light).
    pub ambient: Vec3A,
    /// Diffuse albedo in [0, 1] (Lambertian BRDF `diffuse / π`).
    pub diffuse: Vec3A,
    /// Specular reflectance of the highlight lobe.
    pub specular: Vec3A,
    /// Phong exponent.
    pub shininess: f32,
    /// Optional mirror component.
    pub mirror: Option<Mirror>,
    /// Optional dielectric: the surface then reflects and refracts.
    pub dielectric: Option<Dielectric>,
    /// Optional metal: the surface is then a (rough) conductor.
    pub conductor: Option<Conductor>,
    /// Optional clear coating over the diffuse albedo.
    pub coating: Option<Coating>,
    /// Optional metallic-roughness model (glTF's): the surface then scatters
    /// by it, with [`diffuse`](Self::diffuse) as its base colour.
    pub principled: Option<Principled>,
    /// Mitsuba's `principled` (Burley's Disney BSDF).
    pub disney: Option<Disney>,
    /// Radiance emitted from the front of every surface with this material
    /// (W/m²/sr per channel; the side the geometric normal faces). Non-zero
    /// makes each object using it an area light that also reflects by the
    /// rest of the material, as Mitsuba's `area` emitter on a shape.
    pub emission: Vec3A,
    /// [`emission`](Self::emission) leaves both sides of the surface, as
    /// Cycles' emission shader and glTF's double-sided materials do (Mitsuba's
    /// `area` emitter and caustic's TOML emit from the front only).
    pub emits_both_sides: bool,
    /// Scatters only on the front, the side the shading normal faces, and
    /// is black from behind (Mitsuba's BSDFs without `twosided`); else an
    /// opaque surface reflects the same on both sides. Dielectrics always
    /// tell the sides apart.
    pub one_sided: bool,
    /// The distribution of the rough conductor's or dielectric's microfacets.
    pub microfacet: MicrofacetDistribution,
    /// Anisotropic roughness: the rough conductor's or dielectric's `alpha`
    /// across the surface's `v` direction, its `roughness` then being the
    /// one along `∂p/∂u` (Mitsuba's `alpha_v` and `alpha_u`); `None`:
    /// isotropic.
    pub roughness_v: Option<f32>,
    /// Mitsuba's `null` BSDF: the surface scatters nothing and every ray
    /// passes straight through it (a delta transmission of weight 1 and
    /// index ratio 1), the index-matched boundary of a medium. The other
    /// scattering fields are then unused.
    pub null: bool,
    /// Textures that replace the constant values above at shading points,
    /// a normal map and an alpha cutout; `None` for an untextured material
    /// (one test on the hot paths).
    pub textures: Option<Box<MaterialTextures>>,
    /// A mix of two materials (Mitsuba's `blendbsdf` and `mask`): when set,
    /// this material scatters as one of the blend's sides, chosen per
    /// shading point by [`Material::resolve`], and its own scattering
    /// fields above are not read; its emission, normal map and alpha
    /// cutout still apply.
    pub blend: Option<Box<Blend>>,
}

/// Two sides mixed by a weight: the surface scatters as `(1 − w) · first +
/// w · second`. A side that is `None` is a hole: light passes straight
/// through it (Mitsuba's `null` BSDF, which `mask` mixes in).
#[derive(Clone, Debug, PartialEq)]
pub struct Blend {
    /// Weight `w` of `second`, in [0, 1].
    pub weight: f32,
    /// Replaces `weight` at shading points (a scalar texture).
    pub weight_texture: Option<Texture>,
    /// Scatters with probability `1 − w`.
    pub first: Option<Material>,
    /// Scatters with probability `w`.
    pub second: Option<Material>,
}

impl Blend {
    /// `w` at texture coordinates `uv`, clamped to [0, 1].
    #[inline]
    pub fn weight_at(&self, uv: Vec2) -> f32 {
        self.weight_texture
            .as_ref()
            .map_or(self.weight, |t| t.eval_scalar(uv))
            .clamp(0.0, 1.0)
    }

    /// The sides that are materials.
    pub fn sides(&self) -> impl Iterator<Item = &Material> {
        self.first.iter().chain(self.second.iter())
    }
}

/// A tangent-space normal map (`n = 2·rgb − 1`, linear data), on the
/// tangent frame of the shading point (the mesh's tangents, else `∂p/∂u`).
#[derive(Clone, Debug, PartialEq)]
pub struct NormalMap {
    /// The map.
    pub texture: Texture,
    /// Scales the map's x and y (glTF's `normalTexture.scale`).
    pub scale: f32,
}

/// A bump map (Mitsuba's `bumpmap`): a scalar height texture whose
/// gradient in texture space, times `scale`, tilts the shading normal.
#[derive(Clone, Debug, PartialEq)]
pub struct BumpMap {
    /// The height field (its scalar value).
    pub texture: Texture,
    /// Multiplies the gradient (Mitsuba's `scale`).
    pub scale: f32,
}

/// An alpha cutout: rays pass through where the mask is below `cutoff`.
#[derive(Clone, Debug, PartialEq)]
pub struct AlphaMask {
    /// The mask (a scalar texture: its channel is part of it).
    pub texture: Texture,
    /// Values below it are holes.
    pub cutoff: f32,
}

impl AlphaMask {
    /// True when the surface is present at `uv`.
    #[inline]
    pub fn opaque_at(&self, uv: Vec2) -> bool {
        self.texture.eval_scalar(uv) >= self.cutoff
    }
}

/// The textured parameters of a material; `None` keeps the constant value.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MaterialTextures {
    /// Replaces [`Material::ambient`].
    pub ambient: Option<Texture>,
    /// Replaces [`Material::diffuse`].
    pub diffuse: Option<Texture>,
    /// Replaces [`Material::specular`].
    pub specular: Option<Texture>,
    /// Replaces [`Material::shininess`] (scalar).
    pub shininess: Option<Texture>,
    /// Replaces the mirror's reflectivity (scalar).
    pub mirror_reflectivity: Option<Texture>,
    /// Replaces the mirror's tint.
    pub mirror_tint: Option<Texture>,
    /// Replaces the dielectric's tint.
    pub dielectric_tint: Option<Texture>,
    /// Replaces the dielectric's roughness (scalar).
    pub dielectric_roughness: Option<Texture>,
    /// Replaces the conductor's roughness (scalar).
    pub conductor_roughness: Option<Texture>,
    /// Replaces [`Material::roughness_v`] (scalar).
    pub roughness_v: Option<Texture>,
    /// Replaces [`Principled::metallic`] (scalar).
    pub principled_metallic: Option<Texture>,
    /// Replaces [`Principled::roughness`] (scalar).
    pub principled_roughness: Option<Texture>,
    /// Replaces [`Principled::transmission`] (scalar).
    pub principled_transmission: Option<Texture>,
    /// Replaces [`Principled::clearcoat`] (scalar).
    pub principled_clearcoat: Option<Texture>,
    /// Replaces [`Principled::clearcoat_roughness`] (scalar).
    pub principled_clearcoat_roughness: Option<Texture>,
    /// Replaces [`Disney::roughness`] (scalar).
    pub disney_roughness: Option<Texture>,
    /// Replaces [`Disney::anisotropic`] (scalar).
    pub disney_anisotropic: Option<Texture>,
    /// Replaces [`Disney::metallic`] (scalar).
    pub disney_metallic: Option<Texture>,
    /// Replaces [`Disney::spec_trans`] (scalar).
    pub disney_spec_trans: Option<Texture>,
    /// Replaces [`Disney::spec_tint`] (scalar).
    pub disney_spec_tint: Option<Texture>,
    /// Replaces [`Disney::sheen`] (scalar).
    pub disney_sheen: Option<Texture>,
    /// Replaces [`Disney::sheen_tint`] (scalar).
    pub disney_sheen_tint: Option<Texture>,
    /// Replaces [`Disney::flatness`] (scalar).
    pub disney_flatness: Option<Texture>,
    /// Replaces [`Disney::clearcoat`] (scalar).
    pub disney_clearcoat: Option<Texture>,
    /// Replaces [`Disney::clearcoat_gloss`] (scalar).
    pub disney_clearcoat_gloss: Option<Texture>,
    /// Replaces [`Disney::diff_trans`] (scalar).
    pub disney_diff_trans: Option<Texture>,
    /// Replaces [`Disney::eta`] (scalar; thin only, as in Mitsuba).
    pub disney_eta: Option<Texture>,
    /// Multiplies [`Material::emission`] (which then holds the strength).
    pub emission: Option<Texture>,
    /// Perturbs the shading normal.
    pub normal_map: Option<NormalMap>,
    /// A bump map (not with a normal map).
    pub bump_map: Option<BumpMap>,
    /// Cuts holes.
    pub alpha: Option<AlphaMask>,
}

/// The value slots of [`MaterialTextures`] with their parameter names, by
/// reference (`&`) or mutably (`&mut`): the one list of them.
macro_rules! value_slots {
    ($t:expr, $($r:tt)+) => {
        [
            ("ambient", $($r)+ $t.ambient),
            ("diffuse", $($r)+ $t.diffuse),
            ("specular", $($r)+ $t.specular),
            ("shininess", $($r)+ $t.shininess),
            ("mirror.reflectivity", $($r)+ $t.mirror_reflectivity),
            ("mirror.tint", $($r)+ $t.mirror_tint),
            ("dielectric.tint", $($r)+ $t.dielectric_tint),
            ("dielectric.roughness", $($r)+ $t.dielectric_roughness),
            ("conductor.roughness", $($r)+ $t.conductor_roughness),
            ("roughness_v", $($r)+ $t.roughness_v),
            ("principled.metallic", $($r)+ $t.principled_metallic),
            ("principled.roughness", $($r)+ $t.principled_roughness),
            ("principled.transmission", $($r)+ $t.principled_transmission),
            ("principled.clearcoat", $($r)+ $t.principled_clearcoat),
            ("principled.clearcoat_roughness", $($r)+ $t.principled_clearcoat_roughness),
            ("disney.roughness", $($r)+ $t.disney_roughness),
            ("disney.anisotropic", $($r)+ $t.disney_anisotropic),
            ("disney.metallic", $($r)+ $t.disney_metallic),
            ("disney.spec_trans", $($r)+ $t.disney_spec_trans),
            ("disney.spec_tint", $($r)+ $t.disney_spec_tint),
            ("disney.sheen", $($r)+ $t.disney_sheen),
            ("disney.sheen_tint", $($r)+ $t.disney_sheen_tint),
            ("disney.flatness", $($r)+ $t.disney_flatness),
            ("disney.clearcoat", $($r)+ $t.disney_clearcoat),
            ("disney.clearcoat_gloss", $($r)+ $t.disney_clearcoat_gloss),
            ("disney.diff_trans", $($r)+ $t.disney_diff_trans),
            ("disney.eta", $($r)+ $t.disney_eta),
            ("emission", $($r)+ $t.emission),
        ]
    };
}

impl MaterialTextures {
    /// True when some parameter's value depends on the shading point.
    #[inline]
    pub fn has_values(&self) -> bool {
        self.values().next().is_some()
    }

    /// The value textures that are set, with their parameter names.
    pub fn values(&self) -> impl Iterator<Item = (&'static str, &Texture)> {
        value_slots!(self, &)
            .into_iter()
            .filter_map(|(name, t)| t.as_ref().map(|t| (name, t)))
    }

    /// Every texture, the normal map's and the mask's included.
    pub fn all(&self) -> impl Iterator<Item = (&'static str, &Texture)> {
        self.values()
            .chain(self.normal_map.as_ref().map(|n| ("normal_map", &n.texture)))
            .chain(self.bump_map.as_ref().map(|b| ("bump_map", &b.texture)))
            .chain(self.alpha.as_ref().map(|a| ("alpha", &a.texture)))
    }

    /// [`all`](Self::all), mutable: every texture that is set.
    pub fn all_mut(&mut self) -> impl Iterator<Item = &mut Texture> {
        let maps = [
            self.normal_map.as_mut().map(|n| &mut n.texture),
            self.bump_map.as_mut().map(|b| &mut b.texture),
            self.alpha.as_mut().map(|a| &mut a.texture),
        ];
        value_slots!(self, &mut)
            .into_iter()
            .filter_map(|(_, t)| t.as_mut())
            .chain(maps.into_iter().flatten())
    }

    /// True when the material reads texture coordinates or the tangent
    /// (`SurfaceInteraction::uv`, `dpdu`, `dpdv` are computed only then).
    #[inline]
    pub fn uses_uv(&self) -> bool {
        self.normal_map.is_some() || self.bump_map.is_some() || self.all().any(|(_, t)| !t.is_constant())
    }

    /// True when any texture is set.
    pub fn has_any(&self) -> bool {
        self.all().next().is_some()
    }
}

impl Material {
    /// A plain diffuse material (used by tests and generated scenes).
    pub fn diffuse(name: &str, albedo: Vec3A) -> Self {
        Self {
            name: name.into(),
            model: ShadingModel::BlinnPhong,
            ambient: albedo,
            diffuse: albedo,
            specular: Vec3A::ZERO,
            shininess: 1.0,
            mirror: None,
            dielectric: None,
            conductor: None,
            coating: None,
            principled: None,
            disney: None,
            emission: Vec3A::ZERO,
            emits_both_sides: false,
            one_sided: false,
            microfacet: MicrofacetDistribution::Ggx,
            roughness_v: None,
            null: false,
            textures: None,
            blend: None,
        }
    }

    /// The material that scatters at texture coordinates `uv`: itself (its
    /// textures looked up, [`at`](Self::at)), or for a blend one of its
    /// sides, chosen with the blend's weight by the number `u()` (drawn only
    /// for blends, so other materials use no random number), or `None`
    /// where the chosen side is a hole. Nested blends reuse what is left of
    /// the same number.
    pub fn resolve(&self, uv: Vec2, u: impl FnOnce() -> f32) -> Option<Cow<'_, Material>> {
        let Some(blend) = self.blend.as_deref() else {
            return Some(self.at(uv));
        };
        let mut u = u();
        let mut blend = blend;
        loop {
            let w = blend.weight_at(uv);
            let side = if u < w {
                u = if w > 0.0 { u / w } else { 0.0 };
                &blend.second
            } else {
                u = if w < 1.0 { (u - w) / (1.0 - w) } else { 0.0 };
                &blend.first
            };
            match side.as_ref() {
                None => return None,
                Some(m) => match m.blend.as_deref() {
                    Some(inner) => blend = inner,
                    None => return Some(m.at(uv)),
                },
            }
        }
    }

    /// This material and every material of its blends, nested ones included.
    pub fn layers(&self) -> Vec<&Material> {
        let mut out = vec![self];
        let mut i = 0;
        while i < out.len() {
            if let Some(b) = out[i].blend.as_deref() {
                out.extend(b.sides());
            }
            i += 1;
        }
        out
    }

    /// True when some layer of a blend is a hole.
    pub fn has_holes(&self) -> bool {
        self.layers()
            .iter()
            .filter_map(|m| m.blend.as_deref())
            .any(|b| b.first.is_none() || b.second.is_none())
    }

    /// True when shading reads texture coordinates or the tangent, here or
    /// in a blend's layers.
    #[inline]
    pub fn uses_uv(&self) -> bool {
        // Anisotropic roughness is oriented by the tangent.
        let anisotropic = |m: &Material| m.roughness_v.is_some() || m.disney.is_some_and(|d| d.anisotropic != 0.0);
        let own = self.textures.as_deref().is_some_and(|t| t.uses_uv()) || anisotropic(self);
        if self.blend.is_none() {
            return own;
        }
        self.layers().iter().any(|m| {
            m.textures.as_deref().is_some_and(|t| t.uses_uv())
                || anisotropic(m)
                || m.blend
                    .as_deref()
                    .is_some_and(|b| b.weight_texture.as_ref().is_some_and(|t| !t.is_constant()))
        })
    }

    /// The probability that light passes straight through this surface at
    /// `uv` without scattering: 1 for a `null` material, the weight of a
    /// blend's holes (nested blends included), 0 otherwise (Mitsuba's
    /// `eval_null_transmission` of `null`, `mask` and `blendbsdf`).
    pub fn hole_probability(&self, uv: Vec2) -> f32 {
        if self.null {
            return 1.0;
        }
        let Some(b) = self.blend.as_deref() else {
            return 0.0;
        };
        let side = |s: &Option<Material>| s.as_ref().map_or(1.0, |m| m.hole_probability(uv));
        let w = b.weight_at(uv);
        (1.0 - w) * side(&b.first) + w * side(&b.second)
    }

    /// A thin dielectric sheet ([`Dielectric::thin`]).
    #[inline]
    pub fn is_thin_sheet(&self) -> bool {
        self.dielectric.is_some_and(|d| d.thin)
    }

    /// True when surfaces with this material emit light somewhere.
    pub fn emits(&self) -> bool {
        match self.textures.as_deref().and_then(|t| t.emission.as_ref()) {
            Some(t) => (t.max_value() * self.emission).max_element() > 0.0,
            None => self.emission.max_element() > 0.0,
        }
    }

    /// The emitted radiance at texture coordinates `uv` (front side).
    #[inline]
    pub fn emission_at(&self, uv: Vec2) -> Vec3A {
        match self.textures.as_deref().and_then(|t| t.emission.as_ref()) {
            Some(t) => t.eval(uv) * self.emission,
            None => self.emission,
        }
    }

    /// True when a ray of direction `dir` meeting a surface of geometric
    /// normal `ng` with this material sees its emission: from the front,
    /// or from either side when the material
    /// [emits both sides](Self::emits_both_sides).
    #[inline]
    pub fn emits_toward(&self, dir: Vec3A, ng: Vec3A) -> bool {
        let cos = dir.dot(ng);
        cos < 0.0 || (self.emits_both_sides && cos > 0.0)
    }

    /// The material's values at texture coordinates `uv`: itself when no
    /// value is textured, else an unnamed, untextured copy with every
    /// textured parameter looked up (what the BSDF and the Whitted
    /// integrator read at a shading point).
    #[inline]
    pub fn at(&self, uv: Vec2) -> Cow<'_, Material> {
        match self.textures.as_deref() {
            Some(t) if t.has_values() => Cow::Owned(self.looked_up(t, uv)),
            _ => Cow::Borrowed(self),
        }
    }

    /// The values of the textured parameters at `uv`, the rest copied.
    #[inline(never)]
    fn looked_up(&self, t: &MaterialTextures, uv: Vec2) -> Material {
        let colour = |tex: &Option<Texture>, value: Vec3A| tex.as_ref().map_or(value, |t| t.eval(uv));
        let scalar = |tex: &Option<Texture>, value: f32| tex.as_ref().map_or(value, |t| t.eval_scalar(uv));
        Material {
            name: String::new(),
            model: self.model,
            ambient: colour(&t.ambient, self.ambient),
            diffuse: colour(&t.diffuse, self.diffuse),
            specular: colour(&t.specular, self.specular),
            shininess: scalar(&t.shininess, self.shininess),
            mirror: self.mirror.map(|m| Mirror {
                reflectivity: scalar(&t.mirror_reflectivity, m.reflectivity).clamp(0.0, 1.0),
                tint: colour(&t.mirror_tint, m.tint),
            }),
            dielectric: self.dielectric.map(|d| Dielectric {
                tint: colour(&t.dielectric_tint, d.tint),
                roughness: scalar(&t.dielectric_roughness, d.roughness).max(0.0),
                ..d
            }),
            conductor: self.conductor.map(|c| Conductor {
                roughness: scalar(&t.conductor_roughness, c.roughness).max(0.0),
                ..c
            }),
            coating: self.coating.clone(),
            principled: self.principled.map(|p| Principled {
                metallic: scalar(&t.principled_metallic, p.metallic).clamp(0.0, 1.0),
                roughness: scalar(&t.principled_roughness, p.roughness).clamp(0.0, 1.0),
                transmission: scalar(&t.principled_transmission, p.transmission).clamp(0.0, 1.0),
                clearcoat: scalar(&t.principled_clearcoat, p.clearcoat).clamp(0.0, 1.0),
                clearcoat_roughness: scalar(&t.principled_clearcoat_roughness, p.clearcoat_roughness).clamp(0.0, 1.0),
                ..p
            }),
            disney: self.disney.map(|d| Disney {
                roughness: scalar(&t.disney_roughness, d.roughness),
                anisotropic: scalar(&t.disney_anisotropic, d.anisotropic),
                metallic: scalar(&t.disney_metallic, d.metallic),
                spec_trans: scalar(&t.disney_spec_trans, d.spec_trans),
                spec_tint: scalar(&t.disney_spec_tint, d.spec_tint),
                sheen: scalar(&t.disney_sheen, d.sheen),
                sheen_tint: scalar(&t.disney_sheen_tint, d.sheen_tint),
                flatness: scalar(&t.disney_flatness, d.flatness),
                clearcoat: scalar(&t.disney_clearcoat, d.clearcoat),
                clearcoat_gloss: scalar(&t.disney_clearcoat_gloss, d.clearcoat_gloss),
                diff_trans: scalar(&t.disney_diff_trans, d.diff_trans),
                eta: scalar(&t.disney_eta, d.eta),
                ..d
            }),
            emission: self.emission_at(uv),
            emits_both_sides: self.emits_both_sides,
            one_sided: self.one_sided,
            microfacet: self.microfacet,
            roughness_v: self.roughness_v.map(|r| scalar(&t.roughness_v, r).max(0.0)),
            null: self.null,
            textures: None,
            blend: self.blend.clone(),
        }
    }
}
