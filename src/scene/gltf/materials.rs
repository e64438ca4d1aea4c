//! Materials (glTF 2.0 §3.9): the metallic-roughness model as
//! [`Principled`] with the base colour as [`Material::diffuse`], the normal
//! map, emission (`KHR_materials_emissive_strength`), alpha modes, and
//! `KHR_materials_transmission`, `_ior`, `_volume` and `_clearcoat`.

use super::textures::TextureRef;
use super::Ctx;
use crate::math::Vec3A;
use crate::scene::load::SceneError;
use crate::scene::{
    AlphaMask, Blend, HomogeneousMedium, Material, MaterialTextures, NormalMap, PhaseFunction, Principled,
};
use crate::texture::{Channel, ColourSpace, Texture};

/// A material as caustic reads it, and the medium its objects enclose.
pub(super) struct Built {
    pub material: Material,
    /// `KHR_materials_volume` with a finite attenuation distance: the
    /// absorbing medium inside the objects.
    pub medium: Option<HomogeneousMedium>,
    /// The material has a normal map (its meshes need tangents).
    pub normal_mapped: bool,
}

/// The material glTF gives primitives without one (§3.9.6): white,
/// fully metallic and fully rough.
pub(super) fn default_material() -> Material {
    let mut m = Material::diffuse("glTF default", Vec3A::ONE);
    m.ambient = Vec3A::ZERO;
    m.principled = Some(Principled::default());
    m
}

/// Material `m` mapped onto caustic's model.
pub(super) fn material(ctx: &mut Ctx, m: &gltf::Material) -> Result<Built, SceneError> {
    let index = m.index().expect("a material of the document");
    let pointer = format!("/materials/{index}");
    let name = m.name().map_or_else(|| format!("material {index}"), str::to_string);
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, alpha] = pbr.base_color_factor();
    let base_colour = Vec3A::new(r, g, b);
    let mut out = Material::diffuse(&name, base_colour);
    out.ambient = Vec3A::ZERO;
    let mut textures = MaterialTextures::default();
    let mut principled = Principled {
        metallic: pbr.metallic_factor(),
        roughness: pbr.roughness_factor(),
        ..Principled::default()
    };
    // The base colour texture, kept for the alpha modes, which read its alpha.
    let mut base_texture = None;
    if let Some(info) = pbr.base_color_texture() {
        let r = TextureRef::of_info(&info, format!("{pointer}/pbrMetallicRoughness/baseColorTexture"));
        let mut t = ctx.texture(&r, ColourSpace::Srgb, Channel::A)?;
        t.factor = base_colour;
        t.alpha_factor = alpha;
        base_texture = Some(t.clone());
        textures.diffuse = Some(Texture::Image(t));
    }
    if let Some(info) = pbr.metallic_roughness_texture() {
        let r = TextureRef::of_info(
            &info,
            format!("{pointer}/pbrMetallicRoughness/metallicRoughnessTexture"),
        );
        // Roughness is the green channel, metalness the blue (§3.9.2).
        let mut metal = ctx.texture(&r, ColourSpace::Linear, Channel::B)?;
        metal.factor = Vec3A::splat(principled.metallic);
        let mut rough = metal.clone();
        rough.channel = Channel::G;
        rough.factor = Vec3A::splat(principled.roughness);
        textures.principled_metallic = Some(Texture::Image(metal));
        textures.principled_roughness = Some(Texture::Image(rough));
    }
    let mut normal_mapped = false;
    if let Some(n) = m.normal_texture() {
        let at = format!("{pointer}/normalTexture");
        let r = match n.extension_value("KHR_texture_transform") {
            Some(tt) => {
                let json = serde_json::json!({
                    "index": n.texture().index(),
                    "texCoord": n.tex_coord(),
                    "extensions": { "KHR_texture_transform": tt },
                });
                TextureRef::of_json(ctx, &json, at)?
            }
            None => TextureRef {
                index: n.texture().index(),
                tex_coord: n.tex_coord(),
                transform: None,
                pointer: at,
            },
        };
        let t = ctx.texture(&r, ColourSpace::Linear, Channel::Luminance)?;
        textures.normal_map = Some(NormalMap {
            texture: Texture::Image(t),
            scale: n.scale(),
        });
        normal_mapped = true;
    }
    if m.occlusion_texture().is_some() {
        // Ambient occlusion approximates what a path tracer computes.
        ctx.warn(
            &format!("{pointer}/occlusionTexture"),
            "ignored: a path tracer computes occlusion from the geometry",
        );
    }
    let strength = m.emissive_strength().unwrap_or(1.0);
    out.emission = Vec3A::from_array(m.emissive_factor()) * strength;
    if let Some(info) = m.emissive_texture() {
        let r = TextureRef::of_info(&info, format!("{pointer}/emissiveTexture"));
        let t = ctx.texture(&r, ColourSpace::Srgb, Channel::Luminance)?;
        textures.emission = Some(Texture::Image(t));
    }
    if let Some(tr) = m.transmission() {
        principled.transmission = tr.transmission_factor();
        if let Some(info) = tr.transmission_texture() {
            let r = TextureRef::of_info(
                &info,
                format!("{pointer}/extensions/KHR_materials_transmission/transmissionTexture"),
            );
            let mut t = ctx.texture(&r, ColourSpace::Linear, Channel::R)?;
            t.factor = Vec3A::splat(principled.transmission);
            textures.principled_transmission = Some(Texture::Image(t));
        }
    }
    if let Some(ior) = m.ior() {
        // KHR_materials_ior: 0 is the legacy value of a perfect reflector;
        // otherwise at least 1.
        if !(ior == 0.0 || ior >= 1.0) || !ior.is_finite() {
            return Err(ctx.error(
                format!("{pointer}/extensions/KHR_materials_ior/ior"),
                format!("{ior}: the index of refraction must be ≥ 1 (or 0)"),
            ));
        }
        principled.ior = if ior == 0.0 { 1.0e4 } else { ior };
    }
    let mut medium = None;
    if let Some(v) = m.volume() {
        let at = format!("{pointer}/extensions/KHR_materials_volume");
        // A thickness of 0 keeps the surface thin-walled (the extension's default).
        principled.thin = v.thickness_factor() <= 0.0 && v.thickness_texture().is_none();
        if v.thickness_texture().is_some() {
            ctx.warn(
                &format!("{at}/thicknessTexture"),
                "ignored: caustic traces the real thickness of the mesh",
            );
        }
        let distance = v.attenuation_distance();
        let colour = Vec3A::from_array(v.attenuation_color());
        if distance.is_nan() || distance <= 0.0 {
            return Err(ctx.error(format!("{at}/attenuationDistance"), format!("{distance}: must be > 0")));
        }
        if !principled.thin && distance.is_finite() && colour != Vec3A::ONE {
            // Beer–Lambert: σa = −ln(c) / d, so that light travelling d
            // inside keeps the fraction c (the extension's definition).
            let sigma = Vec3A::from_array(colour.to_array().map(|c| -(c.clamp(1e-6, 1.0)).ln() / distance));
            medium = Some(HomogeneousMedium {
                name: format!("{name} (KHR_materials_volume)"),
                sigma_t: sigma,
                albedo: Vec3A::ZERO,
                phase: PhaseFunction::Isotropic,
                sample_emitters: true,
            });
        }
    }
    if let Some(cc) = m.extension_value("KHR_materials_clearcoat") {
        let at = format!("{pointer}/extensions/KHR_materials_clearcoat");
        let number = |key: &str, default: f32| -> Result<f32, SceneError> {
            match cc.get(key) {
                None => Ok(default),
                Some(v) => v
                    .as_f64()
                    .map(|x| x as f32)
                    .filter(|x| (0.0..=1.0).contains(x))
                    .ok_or_else(|| ctx.error(format!("{at}/{key}"), "expected a number in [0, 1]")),
            }
        };
        principled.clearcoat = number("clearcoatFactor", 0.0)?;
        principled.clearcoat_roughness = number("clearcoatRoughnessFactor", 0.0)?;
        if let Some(v) = cc.get("clearcoatTexture") {
            let r = TextureRef::of_json(ctx, v, format!("{at}/clearcoatTexture"))?;
            let mut t = ctx.texture(&r, ColourSpace::Linear, Channel::R)?;
            t.factor = Vec3A::splat(principled.clearcoat);
            textures.principled_clearcoat = Some(Texture::Image(t));
        }
        if let Some(v) = cc.get("clearcoatRoughnessTexture") {
            let r = TextureRef::of_json(ctx, v, format!("{at}/clearcoatRoughnessTexture"))?;
            let mut t = ctx.texture(&r, ColourSpace::Linear, Channel::G)?;
            t.factor = Vec3A::splat(principled.clearcoat_roughness);
            textures.principled_clearcoat_roughness = Some(Texture::Image(t));
        }
        if cc.get("clearcoatNormalTexture").is_some() {
            ctx.warn(
                &format!("{at}/clearcoatNormalTexture"),
                "ignored: the clear coat shares the base's shading normal",
            );
        }
    }
    out.principled = Some(principled);
    // glTF's doubleSided only tells rasterisers whether to cull back faces;
    // caustic, like Cycles, shades both sides of every surface.
    out.one_sided = false;
    // Emission too leaves both sides, as from Cycles' emission shader and a
    // rasteriser's double-sided material.
    out.emits_both_sides = true;
    let alpha_mask = match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => None,
        gltf::material::AlphaMode::Mask => Some(AlphaMask {
            texture: base_texture
                .clone()
                .map_or_else(|| Texture::scalar(alpha), Texture::Image),
            cutoff: m.alpha_cutoff().unwrap_or(0.5),
        }),
        gltf::material::AlphaMode::Blend => {
            // Stochastic transparency: the surface scatters with
            // probability α and is a hole otherwise; the mean over samples
            // is the blend a rasteriser draws.
            let inner_textures = MaterialTextures {
                normal_map: None,
                ..textures.clone()
            };
            let mut inner = out.clone();
            inner.textures = inner_textures.has_any().then(|| Box::new(inner_textures));
            let mut outer = out.clone();
            outer.blend = Some(Box::new(Blend {
                weight: alpha,
                weight_texture: base_texture.clone().map(Texture::Image),
                first: None,
                second: Some(inner),
            }));
            let outer_textures = MaterialTextures {
                normal_map: textures.normal_map.take(),
                emission: textures.emission.take(),
                ..Default::default()
            };
            outer.textures = outer_textures.has_any().then(|| Box::new(outer_textures));
            return Ok(Built {
                material: outer,
                medium,
                normal_mapped,
            });
        }
    };
    textures.alpha = alpha_mask;
    out.textures = textures.has_any().then(|| Box::new(textures));
    Ok(Built {
        material: out,
        medium,
        normal_mapped,
    })
}
