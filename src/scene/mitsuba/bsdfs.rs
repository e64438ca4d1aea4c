//! `<bsdf>`: each plugin as the caustic material that scatters the same,
//! or refused. Mitsuba's BSDFs are one-sided (black from behind) unless
//! wrapped in `twosided`.

use super::props::Plugin;
use super::spectrum::SpectrumUse;
use super::Builder;
use crate::math::Vec3A;
use crate::scene::conductors::CONDUCTORS;
use crate::scene::ior::{ior_names, named_ior};
use crate::scene::load::SceneError;
use crate::scene::{
    Blend, Coating, Conductor, Dielectric, Disney, FresnelModel, Material, MaterialTextures, MicrofacetDistribution,
    NormalMap,
};

/// Mitsuba's default interior index of dielectrics (BK7).
/// Most BSDFs one material may be made of. Blends and masks nest BSDFs
/// that may be `<ref>`s to other blends: a chain of blends each naming the
/// previous one twice doubles the tree at each level (2^30 BSDFs from 30
/// short lines). Real materials hold a few.
pub const MAX_BSDFS_PER_MATERIAL: usize = 256;

const BK7: f32 = 1.5046;
/// Mitsuba's default exterior index (air).
const AIR: f32 = 1.000277;
/// Mitsuba's default interior index of plastics (polypropylene).
const POLYPROPYLENE: f32 = 1.49;

/// A material scattering nothing yet, one-sided: the base every plugin fills.
fn blank(name: String) -> Material {
    Material {
        ambient: Vec3A::ZERO,
        one_sided: true,
        ..Material::diffuse(&name, Vec3A::ZERO)
    }
}

impl Builder<'_> {
    /// The material of a `<bsdf>`.
    pub(super) fn bsdf(&self, p: &Plugin) -> Result<Material, SceneError> {
        self.bsdfs_read.set(self.bsdfs_read.get() + 1);
        if self.bsdfs_read.get() > MAX_BSDFS_PER_MATERIAL {
            return Err(p.error(format!(
                "the material is made of more than {MAX_BSDFS_PER_MATERIAL} BSDFs (blends naming blends through <ref>s multiply)"
            )));
        }
        let name = p
            .element
            .attr("id")
            .map_or_else(|| format!("{}@{}", p.kind, p.origin().place), str::to_string);
        let mut m = blank(name);
        let mut textures = MaterialTextures::default();
        match p.kind {
            "diffuse" => {
                let (c, t) = self.colour(p, "reflectance", Vec3A::splat(0.5), SpectrumUse::Reflectance)?;
                m.diffuse = c;
                textures.diffuse = t;
            }
            "dielectric" | "roughdielectric" => {
                let eta = interior_over_exterior(p, BK7)?;
                unit_reflectance(p)?;
                let (tint, tint_texture) =
                    self.colour(p, "specular_transmittance", Vec3A::ONE, SpectrumUse::Reflectance)?;
                textures.dielectric_tint = tint_texture;
                let roughness = self.rough_part(p, &mut m, &mut textures, |t| &mut t.dielectric_roughness)?;
                m.dielectric = Some(Dielectric {
                    ior: eta,
                    tint,
                    roughness,
                    fresnel: Some(FresnelModel::Exact),
                    thin: false,
                });
                m.one_sided = false;
            }
            "thindielectric" => {
                let eta = interior_over_exterior(p, BK7)?;
                unit_reflectance(p)?;
                let (tint, tint_texture) =
                    self.colour(p, "specular_transmittance", Vec3A::ONE, SpectrumUse::Reflectance)?;
                textures.dielectric_tint = tint_texture;
                m.dielectric = Some(Dielectric {
                    ior: eta,
                    tint,
                    roughness: 0.0,
                    fresnel: Some(FresnelModel::Exact),
                    thin: true,
                });
                m.one_sided = false;
            }
            "conductor" | "roughconductor" => {
                let (eta, k) = conductor_ior(self, p)?;
                unit_reflectance(p)?;
                let roughness = self.rough_part(p, &mut m, &mut textures, |t| &mut t.conductor_roughness)?;
                m.conductor = Some(Conductor { eta, k, roughness });
            }
            "plastic" | "roughplastic" => {
                let (c, t) = self.colour(p, "diffuse_reflectance", Vec3A::splat(0.5), SpectrumUse::Reflectance)?;
                m.diffuse = c;
                textures.diffuse = t;
                unit_reflectance(p)?;
                let ior = interior_over_exterior(p, POLYPROPYLENE)?;
                let roughness = if p.kind == "roughplastic" {
                    let r = self.roughness(p)?;
                    if r.texture.is_some() {
                        // Mitsuba's roughplastic takes a number: its
                        // transmittance table is computed once.
                        return Err(p.error("a textured `alpha` is not supported by roughplastic"));
                    }
                    if r.v.is_some() {
                        return Err(p.error("roughplastic is isotropic (as in Mitsuba): `alpha_u` must equal `alpha_v`"));
                    }
                    m.microfacet = r.distribution;
                    r.alpha
                } else {
                    0.0
                };
                m.coating = Some(Coating {
                    ior,
                    roughness,
                    nonlinear: p.boolean("nonlinear")?.unwrap_or(false),
                    table: Default::default(),
                });
            }
            "principled" => {
                let (c, t) = self.colour(p, "base_color", Vec3A::splat(0.5), SpectrumUse::Reflectance)?;
                m.diffuse = c;
                textures.diffuse = t;
                m.disney = Some(self.disney(p, &mut textures)?);
            }
            "principledthin" => {
                let (c, t) = self.colour(p, "base_color", Vec3A::splat(0.5), SpectrumUse::Reflectance)?;
                m.diffuse = c;
                textures.diffuse = t;
                m.disney = Some(self.disney_thin(p, &mut textures)?);
                // Both sides scatter alike (`principledthin` turns the
                // directions toward the viewer's side itself).
                m.one_sided = false;
            }
            "blendbsdf" | "mask" => {
                let (weight_name, default) = if p.kind == "mask" {
                    ("opacity", 0.5)
                } else {
                    ("weight", 0.5)
                };
                let (weight, weight_texture) = self.scalar(p, weight_name, default)?;
                if weight_texture.is_none() && !(0.0..=1.0).contains(&weight) {
                    return Err(p.error(format!("`{weight_name}` = {weight} must be in [0, 1]")));
                }
                let inner = p.children_of("bsdf")?;
                let wanted = if p.kind == "mask" { 1 } else { 2 };
                if inner.len() != wanted {
                    return Err(p.error(format!("takes {wanted} nested <bsdf>, not {}", inner.len())));
                }
                let mut sides = Vec::new();
                for (b, _) in &inner {
                    let side = self.bsdf(b)?;
                    if side.textures.as_ref().is_some_and(|t| t.normal_map.is_some() || t.bump_map.is_some()) {
                        return Err(b.error(
                            "a normal map inside a blend is not supported (put the normalmap around the blend)",
                        ));
                    }
                    sides.push(side);
                }
                let mut sides = sides.into_iter();
                let (first, second) = if p.kind == "mask" {
                    // opacity · bsdf + (1 − opacity) · null
                    (None, sides.next())
                } else {
                    (sides.next(), sides.next())
                };
                m.blend = Some(Box::new(Blend {
                    weight,
                    weight_texture,
                    first,
                    second,
                }));
            }
            "null" => {
                // Scatters nothing; rays pass straight through (`src/bsdfs/null.cpp`).
                m.null = true;
                m.one_sided = false;
            }
            "twosided" => {
                let inner = p.children_of("bsdf")?;
                let [(inner, _)] = <[_; 1]>::try_from(inner).map_err(|v: Vec<_>| {
                    p.error(format!(
                        "takes one nested <bsdf> (a different BSDF per side is not supported), not {}",
                        v.len()
                    ))
                })?;
                let mut m = self.bsdf(&inner)?;
                two_sided(&mut m);
                if let Some(id) = p.element.attr("id") {
                    m.name = id.to_string();
                }
                p.finish()?;
                return Ok(m);
            }
            "bumpmap" => {
                // One nested texture (any name) and one nested BSDF
                // (`src/bsdfs/bumpmap.cpp`).
                let textures = p.children_of("texture")?;
                let [(map, _)] = <[_; 1]>::try_from(textures).map_err(|v: Vec<_>| {
                    p.error(format!("takes one nested <texture> (the height field), not {}", v.len()))
                })?;
                let texture = self.texture(&map)?;
                if matches!(texture, crate::texture::Texture::Checkerboard(_)) {
                    return Err(map.error("a bump map's height field must be a `bitmap` (Mitsuba's checkerboard has no gradient)"));
                }
                let scale = p.float("scale")?.unwrap_or(1.0);
                if !scale.is_finite() {
                    return Err(p.error(format!("`scale` = {scale} must be finite")));
                }
                let inner = p
                    .single_child("bsdf")?
                    .ok_or_else(|| p.error("needs a nested <bsdf>"))?;
                let mut m = self.bsdf(&inner)?;
                if m.textures.as_ref().is_some_and(|t| t.normal_map.is_some() || t.bump_map.is_some()) {
                    return Err(p.error("a bump map around a normal or bump map is not supported"));
                }
                m.textures.get_or_insert_with(Default::default).bump_map =
                    Some(crate::scene::BumpMap { texture, scale });
                if let Some(id) = p.element.attr("id") {
                    m.name = id.to_string();
                }
                p.finish()?;
                return Ok(m);
            }
            "normalmap" => {
                let map = p
                    .child_named("normalmap")?
                    .ok_or_else(|| p.error("needs a <texture name=\"normalmap\">"))?;
                let map = self.texture(&map)?;
                let inner = p
                    .single_child("bsdf")?
                    .ok_or_else(|| p.error("needs a nested <bsdf>"))?;
                let mut m = self.bsdf(&inner)?;
                if m.textures.as_ref().is_some_and(|t| t.normal_map.is_some() || t.bump_map.is_some()) {
                    return Err(p.error("nested normal maps (or a normal map around a bump map) are not supported"));
                }
                m.textures.get_or_insert_with(Default::default).normal_map =
                    Some(NormalMap { texture: map, scale: 1.0 });
                if let Some(id) = p.element.attr("id") {
                    m.name = id.to_string();
                }
                p.finish()?;
                return Ok(m);
            }
            other => {
                return Err(p.error(format!(
                    "the BSDF `{other}` is not supported: caustic reads diffuse, dielectric, thindielectric, roughdielectric, conductor, roughconductor, plastic, roughplastic, principled, principledthin, blendbsdf, mask, null, twosided, normalmap and bumpmap"
                )))
            }
        }
        p.finish()?;
        if textures.has_any() {
            m.textures = Some(Box::new(textures));
        }
        Ok(m)
    }

    /// The parameters of `principled` (`src/bsdfs/principled.cpp`), each
    /// scalar one a number or a texture, into their `disney_*` slots.
    fn disney(&self, p: &Plugin, textures: &mut MaterialTextures) -> Result<Disney, SceneError> {
        type Slot = fn(&mut MaterialTextures) -> &mut Option<crate::texture::Texture>;
        type Field = fn(&mut Disney) -> &mut f32;
        // Mitsuba's `get_flag`: the refraction is on when `spec_trans` is
        // given, unless as the number 0.
        let mut has_spec_trans = false;
        let mut d = Disney::default();
        let weights: [(&str, f32, Field, Slot); 10] = [
            ("roughness", 0.5, |d| &mut d.roughness, |t| &mut t.disney_roughness),
            (
                "anisotropic",
                0.0,
                |d| &mut d.anisotropic,
                |t| &mut t.disney_anisotropic,
            ),
            ("metallic", 0.0, |d| &mut d.metallic, |t| &mut t.disney_metallic),
            ("spec_trans", 0.0, |d| &mut d.spec_trans, |t| &mut t.disney_spec_trans),
            ("spec_tint", 0.0, |d| &mut d.spec_tint, |t| &mut t.disney_spec_tint),
            ("sheen", 0.0, |d| &mut d.sheen, |t| &mut t.disney_sheen),
            ("sheen_tint", 0.0, |d| &mut d.sheen_tint, |t| &mut t.disney_sheen_tint),
            ("flatness", 0.0, |d| &mut d.flatness, |t| &mut t.disney_flatness),
            ("clearcoat", 0.0, |d| &mut d.clearcoat, |t| &mut t.disney_clearcoat),
            (
                "clearcoat_gloss",
                0.0,
                |d| &mut d.clearcoat_gloss,
                |t| &mut t.disney_clearcoat_gloss,
            ),
        ];
        for (name, default, field, slot) in &weights {
            let given = p.has(name);
            let (value, texture) = self.scalar(p, name, *default)?;
            if *name == "spec_trans" {
                has_spec_trans = given && (texture.is_some() || value != 0.0);
            }
            *field(&mut d) = value;
            *slot(textures) = texture;
        }
        let rate = |name: &str| p.float_checked(name, 1.0, "a sampling rate ≥ 0", |r| r >= 0.0);
        d.diffuse_sampling_rate = rate("diffuse_reflectance_sampling_rate")?;
        d.specular_sampling_rate = rate("main_specular_sampling_rate")?;
        d.clearcoat_sampling_rate = rate("clearcoat_sampling_rate")?;
        if p.has("eta") && p.has("specular") {
            return Err(p.error("give `eta` or `specular`, not both (as in Mitsuba)"));
        }
        d.eta = if p.has("eta") {
            let eta = p.float_checked("eta", 1.5, "an index > 0", |e| e > 0.0)?;
            // Mitsuba: an index of 1 cannot refract.
            if has_spec_trans && eta == 1.0 {
                1.001
            } else {
                eta
            }
        } else {
            let mut specular = p.float_checked("specular", 0.5, "in [0, 12.5) (12.5 is an infinite index)", |s| {
                (0.0..12.5).contains(&s)
            })?;
            // Mitsuba: a specular of 0 (an index of 1) cannot refract.
            if has_spec_trans && specular == 0.0 {
                specular = 1.0e-3;
            }
            2.0 / (1.0 - (0.08 * specular).sqrt()) - 1.0
        };
        Ok(d)
    }

    /// The parameters of `principledthin` (`src/bsdfs/principledthin.cpp`),
    /// each but the sampling rates a number or a texture.
    fn disney_thin(&self, p: &Plugin, textures: &mut MaterialTextures) -> Result<Disney, SceneError> {
        type Slot = fn(&mut MaterialTextures) -> &mut Option<crate::texture::Texture>;
        type Field = fn(&mut Disney) -> &mut f32;
        let mut d = Disney::thin_default();
        let weights: [(&str, f32, Field, Slot); 9] = [
            ("roughness", 0.5, |d| &mut d.roughness, |t| &mut t.disney_roughness),
            (
                "anisotropic",
                0.0,
                |d| &mut d.anisotropic,
                |t| &mut t.disney_anisotropic,
            ),
            ("spec_trans", 0.0, |d| &mut d.spec_trans, |t| &mut t.disney_spec_trans),
            ("spec_tint", 0.0, |d| &mut d.spec_tint, |t| &mut t.disney_spec_tint),
            ("sheen", 0.0, |d| &mut d.sheen, |t| &mut t.disney_sheen),
            ("sheen_tint", 0.0, |d| &mut d.sheen_tint, |t| &mut t.disney_sheen_tint),
            ("flatness", 0.0, |d| &mut d.flatness, |t| &mut t.disney_flatness),
            ("diff_trans", 0.0, |d| &mut d.diff_trans, |t| &mut t.disney_diff_trans),
            ("eta", 1.5, |d| &mut d.eta, |t| &mut t.disney_eta),
        ];
        for (name, default, field, slot) in &weights {
            let (value, texture) = self.scalar(p, name, *default)?;
            *field(&mut d) = value;
            *slot(textures) = texture;
        }
        if textures.disney_eta.is_none() && d.eta <= 0.0 {
            return Err(p.error(format!("`eta` = {} must be > 0", d.eta)));
        }
        let rate = |name: &str| p.float_checked(name, 1.0, "a sampling rate ≥ 0", |r| r >= 0.0);
        d.diffuse_sampling_rate = rate("diffuse_reflectance_sampling_rate")?;
        d.specular_sampling_rate = rate("specular_reflectance_sampling_rate")?;
        d.specular_transmission_sampling_rate = rate("specular_transmittance_sampling_rate")?;
        d.diffuse_transmission_sampling_rate = rate("diffuse_transmittance_sampling_rate")?;
        Ok(d)
    }

    /// The roughness of `rough*` plugins (0 for the smooth ones): sets the
    /// material's distribution, its roughness across `v` when anisotropic,
    /// and the roughness texture `slot` (the `v` one in `textures`).
    fn rough_part(
        &self,
        p: &Plugin,
        m: &mut Material,
        textures: &mut MaterialTextures,
        slot: fn(&mut MaterialTextures) -> &mut Option<crate::texture::Texture>,
    ) -> Result<f32, SceneError> {
        if !p.kind.starts_with("rough") {
            return Ok(0.0);
        }
        let r = self.roughness(p)?;
        *slot(textures) = r.texture;
        m.microfacet = r.distribution;
        if let Some((v, v_texture)) = r.v {
            m.roughness_v = Some(v);
            textures.roughness_v = v_texture;
        }
        Ok(r.alpha)
    }

    /// The `alpha` (or `alpha_u` and `alpha_v`) and distribution of a rough plugin.
    fn roughness(&self, p: &Plugin) -> Result<Roughness, SceneError> {
        let distribution = match p.choice("distribution", "beckmann", &["beckmann", "ggx"])? {
            "ggx" => MicrofacetDistribution::Ggx,
            _ => MicrofacetDistribution::Beckmann,
        };
        // Visible-normal sampling or not: the same BSDF, another sampling.
        p.boolean("sample_visible")?;
        if p.has("alpha_u") || p.has("alpha_v") {
            if p.has("alpha") {
                return Err(p.error("give `alpha` or `alpha_u` and `alpha_v`, not both"));
            }
            let (u, tu) = self.scalar(p, "alpha_u", 0.1)?;
            let (v, tv) = self.scalar(p, "alpha_v", 0.1)?;
            check_alpha(p, u)?;
            check_alpha(p, v)?;
            let isotropic = u == v && tu == tv;
            return Ok(Roughness {
                alpha: u,
                texture: tu,
                v: (!isotropic).then_some((v, tv)),
                distribution,
            });
        }
        let (alpha, texture) = self.scalar(p, "alpha", 0.1)?;
        check_alpha(p, alpha)?;
        Ok(Roughness {
            alpha,
            texture,
            v: None,
            distribution,
        })
    }
}

/// What a rough plugin's roughness parameters say.
struct Roughness {
    /// `alpha`, or `alpha_u` along `∂p/∂u`.
    alpha: f32,
    /// Its texture.
    texture: Option<crate::texture::Texture>,
    /// `alpha_v` and its texture, when they differ from `alpha_u`.
    v: Option<(f32, Option<crate::texture::Texture>)>,
    /// The microfacet distribution.
    distribution: MicrofacetDistribution,
}

/// Makes `m` and every side of its blends scatter on both sides.
fn two_sided(m: &mut Material) {
    m.one_sided = false;
    if let Some(b) = m.blend.as_deref_mut() {
        for side in [&mut b.first, &mut b.second].into_iter().flatten() {
            two_sided(side);
        }
    }
}

fn check_alpha(p: &Plugin, alpha: f32) -> Result<(), SceneError> {
    if alpha >= 0.0 {
        Ok(())
    } else {
        Err(p.error(format!("the roughness `alpha` = {alpha} must be ≥ 0")))
    }
}

/// Refuses a `specular_reflectance` other than 1 (caustic's lobes have no
/// such factor).
fn unit_reflectance(p: &Plugin) -> Result<(), SceneError> {
    match p.colour("specular_reflectance", SpectrumUse::Reflectance)? {
        None => Ok(()),
        Some(super::props::ColourParam::Value(c)) if c == Vec3A::ONE => Ok(()),
        Some(_) => Err(p.error("a `specular_reflectance` other than 1 is not supported")),
    }
}

/// An index given as a number or one of Mitsuba's names.
fn ior(p: &Plugin, name: &str, default: f32) -> Result<f32, SceneError> {
    let Some(e) = p.take(name) else { return Ok(default) };
    let value = e.attr("value").unwrap_or("");
    let v = match e.tag.as_str() {
        "string" => named_ior(value).ok_or_else(|| {
            e.origin.error(format!(
                "`{name}` = `{value}` is not a known index; the names are: {}",
                ior_names()
            ))
        })?,
        _ => p.float(name)?.unwrap_or(default),
    };
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(e.origin.error(format!("`{name}` = {v} must be > 0")))
    }
}

/// `int_ior / ext_ior`.
fn interior_over_exterior(p: &Plugin, interior: f32) -> Result<f32, SceneError> {
    let eta = ior(p, "int_ior", interior)? / ior(p, "ext_ior", AIR)?;
    if eta == 1.0 {
        return Err(p.error("`int_ior` equals `ext_ior`: the surface is invisible (use a `null` BSDF)"));
    }
    Ok(eta)
}

/// A conductor's `(eta, k)`: a named `material` or explicit values, over
/// `ext_eta`.
fn conductor_ior(b: &Builder, p: &Plugin) -> Result<(Vec3A, Vec3A), SceneError> {
    let explicit = p.has("eta") || p.has("k");
    let (eta, k) = if explicit {
        if p.has("material") {
            return Err(p.error("give `material` or `eta` and `k`, not both"));
        }
        let (eta, t1) = b.colour(p, "eta", Vec3A::ZERO, SpectrumUse::Unbounded)?;
        let (k, t2) = b.colour(p, "k", Vec3A::ONE, SpectrumUse::Unbounded)?;
        if t1.is_some() || t2.is_some() {
            return Err(p.error("textured `eta` or `k` is not supported"));
        }
        (eta, k)
    } else {
        match p.string("material")?.unwrap_or("none") {
            // A perfect mirror: |r| = 1 at every angle for η = 0 + 1i.
            "none" => (Vec3A::ZERO, Vec3A::ONE),
            name => {
                let (_, eta, k) = CONDUCTORS.iter().find(|(n, _, _)| *n == name).ok_or_else(|| {
                    let names: Vec<&str> = CONDUCTORS.iter().map(|(n, _, _)| *n).collect();
                    let at = p.take("material").map_or(p.origin(), |e| &e.origin);
                    at.error(format!(
                        "`material` = `{name}` is not one of Mitsuba's conductors: none, {}",
                        names.join(", ")
                    ))
                })?;
                (Vec3A::from_array(*eta), Vec3A::from_array(*k))
            }
        }
    };
    let ext = ior(p, "ext_eta", 1.0)?;
    Ok((eta / ext, k / ext))
}
