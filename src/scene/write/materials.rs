//! `[materials.NAME]` and their textures: every field written (defaults
//! that depend on other keys, such as `ambient` following `diffuse`, are
//! never relied on), each textured parameter as an inline texture table.

use super::{num, path_from, string, unsupported, vec3, WriteError};
use crate::math::Vec3A;
use crate::scene::{Disney, Material, MaterialTextures, Scene, ShadingModel};
use crate::texture::{ColourSpace, Texture, UvTransform};
use std::collections::BTreeMap;
use std::path::Path;
use toml::{Table, Value};

/// The TOML name of every material the scene uses, the sides of blends
/// included: its own name (names are unique in a scene read from TOML;
/// a Mitsuba scene's differ by id or place).
pub(super) struct Names {
    /// Name → the material written under it.
    pub(super) by_name: BTreeMap<String, Material>,
}

impl Names {
    /// The materials of `scene` by name; two different materials of one
    /// name cannot both be written.
    pub(super) fn of(scene: &Scene) -> Result<Self, WriteError> {
        let mut by_name = BTreeMap::new();
        fn add(by_name: &mut BTreeMap<String, Material>, m: &Material) -> Result<(), WriteError> {
            match by_name.get(&m.name) {
                Some(known) if known == m => return Ok(()),
                Some(_) => {
                    return Err(unsupported(
                        format!("material `{}`", m.name),
                        "two different materials have this name",
                    ))
                }
                None => {
                    by_name.insert(m.name.clone(), m.clone());
                }
            }
            if let Some(b) = &m.blend {
                for side in b.sides() {
                    add(by_name, side)?;
                }
            }
            Ok(())
        }
        for m in &scene.materials {
            add(&mut by_name, m)?;
        }
        Ok(Self { by_name })
    }
}

/// `[materials]`: every material of `names`.
pub(super) fn materials(names: &Names, dir: &Path) -> Result<Table, WriteError> {
    let mut t = Table::new();
    for (name, m) in &names.by_name {
        t.insert(name.clone(), Value::Table(material(m, dir)?));
    }
    Ok(t)
}

/// One material.
fn material(m: &Material, dir: &Path) -> Result<Table, WriteError> {
    let part = || format!("material `{}`", m.name);
    let none = MaterialTextures::default();
    let tex = m.textures.as_deref().unwrap_or(&none);
    let texture = |t: &Option<Texture>| -> Result<Option<Value>, WriteError> {
        t.as_ref().map(|t| texture(t, dir, &part)).transpose()
    };
    let colour = |value: Vec3A, t: &Option<Texture>| -> Result<Value, WriteError> {
        Ok(texture(t)?.unwrap_or_else(|| vec3(value)))
    };
    let scalar = |value: f32, t: &Option<Texture>| -> Result<Value, WriteError> {
        Ok(texture(t)?.unwrap_or_else(|| num(value)))
    };
    let mut t = Table::new();
    let model = match m.model {
        ShadingModel::Phong => "phong",
        ShadingModel::BlinnPhong => "blinn-phong",
    };
    t.insert("model".into(), string(model));
    t.insert("ambient".into(), colour(m.ambient, &tex.ambient)?);
    t.insert("diffuse".into(), colour(m.diffuse, &tex.diffuse)?);
    t.insert("specular".into(), colour(m.specular, &tex.specular)?);
    t.insert("shininess".into(), scalar(m.shininess, &tex.shininess)?);
    if let Some(mirror) = &m.mirror {
        let mut s = Table::new();
        s.insert(
            "reflectivity".into(),
            scalar(mirror.reflectivity, &tex.mirror_reflectivity)?,
        );
        s.insert("tint".into(), colour(mirror.tint, &tex.mirror_tint)?);
        t.insert("mirror".into(), Value::Table(s));
    }
    if let Some(d) = &m.dielectric {
        let mut s = Table::new();
        s.insert("ior".into(), num(d.ior));
        s.insert("tint".into(), colour(d.tint, &tex.dielectric_tint)?);
        if !d.thin {
            s.insert("roughness".into(), scalar(d.roughness, &tex.dielectric_roughness)?);
            if let Some(v) = m.roughness_v {
                s.insert("roughness_v".into(), scalar(v, &tex.roughness_v)?);
            }
        }
        if let Some(f) = d.fresnel {
            let name = match f {
                crate::scene::FresnelModel::Exact => "exact",
                crate::scene::FresnelModel::Schlick => "schlick",
            };
            s.insert("fresnel".into(), string(name));
        }
        s.insert("thin".into(), Value::Boolean(d.thin));
        t.insert("dielectric".into(), Value::Table(s));
    }
    if let Some(c) = &m.conductor {
        let mut s = Table::new();
        s.insert("eta".into(), vec3(c.eta));
        s.insert("k".into(), vec3(c.k));
        s.insert("roughness".into(), scalar(c.roughness, &tex.conductor_roughness)?);
        if let Some(v) = m.roughness_v {
            s.insert("roughness_v".into(), scalar(v, &tex.roughness_v)?);
        }
        t.insert("conductor".into(), Value::Table(s));
    }
    if let Some(d) = &m.disney {
        t.insert("disney".into(), Value::Table(disney(d, tex, &scalar)?));
    }
    if m.roughness_v.is_some() && m.dielectric.is_none() && m.conductor.is_none() && m.disney.is_none() {
        return Err(unsupported(part(), "`roughness_v` without a dielectric or a conductor"));
    }
    if let Some(c) = &m.coating {
        let mut s = Table::new();
        s.insert("ior".into(), num(c.ior));
        s.insert("roughness".into(), num(c.roughness));
        s.insert("nonlinear".into(), Value::Boolean(c.nonlinear));
        t.insert("coating".into(), Value::Table(s));
    }
    if let Some(p) = &m.principled {
        let mut s = Table::new();
        s.insert("metallic".into(), scalar(p.metallic, &tex.principled_metallic)?);
        s.insert("roughness".into(), scalar(p.roughness, &tex.principled_roughness)?);
        s.insert("ior".into(), num(p.ior));
        s.insert(
            "transmission".into(),
            scalar(p.transmission, &tex.principled_transmission)?,
        );
        s.insert("thin".into(), Value::Boolean(p.thin));
        s.insert("clearcoat".into(), scalar(p.clearcoat, &tex.principled_clearcoat)?);
        s.insert(
            "clearcoat_roughness".into(),
            scalar(p.clearcoat_roughness, &tex.principled_clearcoat_roughness)?,
        );
        t.insert("principled".into(), Value::Table(s));
    }
    if let Some(b) = &m.blend {
        let mut s = Table::new();
        if let Some(first) = &b.first {
            s.insert("first".into(), string(&first.name));
        }
        if let Some(second) = &b.second {
            s.insert("second".into(), string(&second.name));
        }
        s.insert("weight".into(), scalar(b.weight, &b.weight_texture)?);
        t.insert("blend".into(), Value::Table(s));
    }
    emission(m, tex, &mut t, dir)?;
    if let Some(n) = &tex.normal_map {
        t.insert(
            "normal_map".into(),
            texture(&Some(n.texture.clone()))?.expect("a texture"),
        );
        t.insert("normal_scale".into(), num(n.scale));
    }
    if let Some(b) = &tex.bump_map {
        t.insert(
            "bump_map".into(),
            texture(&Some(b.texture.clone()))?.expect("a texture"),
        );
        t.insert("bump_scale".into(), num(b.scale));
    }
    if let Some(a) = &tex.alpha {
        let value = match &a.texture {
            Texture::Constant(c) if c.x == c.y && c.y == c.z => num(c.x),
            other => texture(&Some(other.clone()))?.expect("a texture"),
        };
        t.insert("alpha".into(), value);
        t.insert("alpha_cutoff".into(), num(a.cutoff));
    }
    t.insert("one_sided".into(), Value::Boolean(m.one_sided));
    if m.emits_both_sides {
        t.insert("emit_both_sides".into(), Value::Boolean(true));
    }
    t.insert("microfacet".into(), string(m.microfacet.name()));
    t.insert("null".into(), Value::Boolean(m.null));
    Ok(t)
}

/// A scalar parameter as a number, or its texture when it has one.
type Scalar<'a> = dyn Fn(f32, &Option<Texture>) -> Result<Value, WriteError> + 'a;

/// `[materials.NAME.disney]`: every parameter of its variant.
fn disney(d: &Disney, tex: &MaterialTextures, scalar: &Scalar) -> Result<Table, WriteError> {
    let mut s = Table::new();
    s.insert("thin".into(), Value::Boolean(d.thin));
    let mut weights = vec![
        ("roughness", d.roughness, &tex.disney_roughness),
        ("anisotropic", d.anisotropic, &tex.disney_anisotropic),
        ("spec_trans", d.spec_trans, &tex.disney_spec_trans),
        ("spec_tint", d.spec_tint, &tex.disney_spec_tint),
        ("sheen", d.sheen, &tex.disney_sheen),
        ("sheen_tint", d.sheen_tint, &tex.disney_sheen_tint),
        ("flatness", d.flatness, &tex.disney_flatness),
        ("eta", d.eta, &tex.disney_eta),
    ];
    if d.thin {
        weights.push(("diff_trans", d.diff_trans, &tex.disney_diff_trans));
    } else {
        weights.push(("metallic", d.metallic, &tex.disney_metallic));
        weights.push(("clearcoat", d.clearcoat, &tex.disney_clearcoat));
        weights.push(("clearcoat_gloss", d.clearcoat_gloss, &tex.disney_clearcoat_gloss));
    }
    for (key, value, texture) in weights {
        s.insert(key.into(), scalar(value, texture)?);
    }
    let mut rates = vec![
        ("diffuse_sampling_rate", d.diffuse_sampling_rate),
        ("specular_sampling_rate", d.specular_sampling_rate),
    ];
    if d.thin {
        rates.push((
            "specular_transmission_sampling_rate",
            d.specular_transmission_sampling_rate,
        ));
        rates.push((
            "diffuse_transmission_sampling_rate",
            d.diffuse_transmission_sampling_rate,
        ));
    } else {
        rates.push(("clearcoat_sampling_rate", d.clearcoat_sampling_rate));
    }
    for (key, value) in rates {
        s.insert(key.into(), num(value));
    }
    Ok(s)
}

/// `emission` (and `emission_strength` for a textured one, whose texels
/// the loader scales by the strength it stores in `emission`).
fn emission(m: &Material, tex: &MaterialTextures, t: &mut Table, dir: &Path) -> Result<(), WriteError> {
    let part = || format!("material `{}`", m.name);
    match &tex.emission {
        None if m.emission == Vec3A::ZERO => {}
        None => {
            t.insert("emission".into(), vec3(m.emission));
        }
        Some(texture_) => {
            let e = m.emission;
            if !(e.x == e.y && e.y == e.z) {
                return Err(unsupported(
                    part(),
                    format!("a textured emission scaled by the colour {e}"),
                ));
            }
            t.insert("emission".into(), texture(texture_, dir, &part)?);
            t.insert("emission_strength".into(), num(e.x));
        }
    }
    Ok(())
}

/// A texture as an inline table.
fn texture(t: &Texture, dir: &Path, part: &dyn Fn() -> String) -> Result<Value, WriteError> {
    let mut s = Table::new();
    let transform = match t {
        Texture::Constant(c) => {
            return Err(unsupported(
                part(),
                format!("a constant texture {c} where caustic's TOML reads a constant as a plain value"),
            ))
        }
        Texture::Checkerboard(c) => {
            s.insert("type".into(), string("checkerboard"));
            s.insert("colour0".into(), vec3(c.colour0));
            s.insert("colour1".into(), vec3(c.colour1));
            c.transform
        }
        Texture::Image(i) => {
            s.insert("type".into(), string("image"));
            s.insert("file".into(), Value::String(path_from(dir, Path::new(&i.image.name))));
            if let crate::texture::image::Texels::Rgba8 { space, .. } = &i.image.texels {
                let name = match space {
                    ColourSpace::Srgb => "srgb",
                    ColourSpace::Linear => "linear",
                };
                s.insert("colour_space".into(), string(name));
            }
            s.insert(
                "wrap".into(),
                Value::Array(vec![string(i.wrap[0].name()), string(i.wrap[1].name())]),
            );
            s.insert("filter".into(), string(i.filter.name()));
            s.insert("factor".into(), vec3(i.factor));
            s.insert("channel".into(), string(i.channel.name()));
            if i.alpha_factor != 1.0 {
                return Err(unsupported(part(), "an image texture whose alpha is scaled"));
            }
            i.transform
        }
    };
    uv_transform(transform, &mut s, part)?;
    Ok(Value::Table(s))
}

/// `scale`, `rotation` and `offset` of a UV transform, when the loader's
/// composition of them gives it back exactly.
fn uv_transform(t: UvTransform, s: &mut Table, part: &dyn Fn() -> String) -> Result<(), WriteError> {
    if t.is_identity() {
        return Ok(());
    }
    let m = t.0.matrix2;
    let offset = t.0.translation;
    // A scale along the axes is exact; otherwise the angle and the lengths
    // of the columns, checked below.
    let (scale, rotation_deg) = if m.x_axis.y == 0.0 && m.y_axis.x == 0.0 {
        (crate::math::Vec2::new(m.x_axis.x, m.y_axis.y), 0.0)
    } else {
        let angle = m.x_axis.y.atan2(m.x_axis.x);
        let deg = super::degrees_for(angle).unwrap_or(angle.to_degrees());
        (crate::math::Vec2::new(m.x_axis.length(), m.y_axis.length()), deg)
    };
    let again = UvTransform::new(scale, rotation_deg.to_radians(), offset);
    if again != t {
        return Err(unsupported(
            part(),
            format!(
                "the texture coordinates' transform {:?} is not a scale, a rotation and an offset exactly",
                t.0
            ),
        ));
    }
    s.insert("scale".into(), Value::Array(vec![num(scale.x), num(scale.y)]));
    if rotation_deg != 0.0 {
        s.insert("rotation".into(), num(rotation_deg));
    }
    if offset != crate::math::Vec2::ZERO {
        s.insert("offset".into(), Value::Array(vec![num(offset.x), num(offset.y)]));
    }
    Ok(())
}
