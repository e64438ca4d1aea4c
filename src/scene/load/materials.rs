//! The `[materials]` table: each material's shading model, reflectances,
//! mirror, dielectric, conductor and coating, with their defaults.

use super::ctx::Ctx;
use super::error::SceneError;
use super::textures::Usage;
use crate::math::Vec3A;
use crate::scene::desc::{FresnelName, MaterialDesc, ModelName, ParamDesc, Spanned};
use crate::scene::material::{AlphaMask, MaterialTextures, NormalMap};
use crate::scene::metals;
use crate::scene::{
    Blend, Coating, Conductor, Dielectric, FresnelModel, Material, MicrofacetDistribution, Mirror, Principled,
    ShadingModel,
};
use crate::texture::Texture;
use std::collections::BTreeMap;

/// Default diffuse albedo of a material.
pub const DEFAULT_DIFFUSE: f32 = 0.8;
/// Default Phong exponent.
pub const DEFAULT_SHININESS: f32 = 32.0;
/// Default index of refraction of a dielectric (glass).
pub const DEFAULT_IOR: f32 = 1.5;

impl Ctx<'_> {
    pub(super) fn materials(
        &self,
        descs: &BTreeMap<String, MaterialDesc>,
    ) -> Result<(Vec<Material>, BTreeMap<String, u32>), SceneError> {
        let mut materials = Vec::with_capacity(descs.len());
        let mut index = BTreeMap::new();
        for (name, m) in descs {
            index.insert(name.clone(), materials.len() as u32);
            materials.push(self.material(name, m)?);
        }
        // Blends take copies of the materials they name, blends among them,
        // so they are filled in once every material exists.
        let in_order: Vec<&MaterialDesc> = descs.values().collect();
        let mut done: Vec<bool> = in_order.iter().map(|m| m.blend.is_none()).collect();
        for i in 0..materials.len() {
            self.fill_blend(i, &in_order, &index, &mut materials, &mut done, &mut Vec::new())?;
        }
        Ok((materials, index))
    }

    /// Fills in the blend of material `i` (and first of the blends it
    /// names), refusing unknown names and blends that contain themselves.
    fn fill_blend(
        &self,
        i: usize,
        descs: &[&MaterialDesc],
        index: &BTreeMap<String, u32>,
        materials: &mut [Material],
        done: &mut [bool],
        stack: &mut Vec<usize>,
    ) -> Result<(), SceneError> {
        if done[i] {
            return Ok(());
        }
        let desc = descs[i];
        let b = desc.blend.as_ref().expect("not done: a blend").get_ref();
        stack.push(i);
        let mut side = |s: &Option<Spanned<String>>| -> Result<Option<Material>, SceneError> {
            let Some(s) = s else { return Ok(None) };
            let j = *index.get(s.get_ref()).ok_or_else(|| {
                self.invalid(
                    s.span(),
                    format!(
                        "blend names `{}`, which is not a material; the materials are: {}",
                        s.get_ref(),
                        index.keys().cloned().collect::<Vec<_>>().join(", ")
                    ),
                )
            })? as usize;
            if stack.contains(&j) {
                return Err(self.invalid(s.span(), format!("blend `{}` contains itself", s.get_ref())));
            }
            self.fill_blend(j, descs, index, materials, done, stack)?;
            let m = materials[j].clone();
            if m.textures
                .as_ref()
                .is_some_and(|t| t.normal_map.is_some() || t.bump_map.is_some() || t.alpha.is_some())
            {
                return Err(self.invalid(
                    s.span(),
                    format!(
                        "`{}` has a normal map, a bump map or an alpha cutout: give them to the blend itself",
                        s.get_ref()
                    ),
                ));
            }
            Ok(Some(m))
        };
        let first = side(&b.first)?;
        let second = side(&b.second)?;
        let at = desc.blend.as_ref().expect("a blend").span();
        if first.is_none() && second.is_none() {
            return Err(self.invalid(at, "a blend needs `first`, `second` or both (a missing side is a hole)"));
        }
        let (weight, weight_texture) =
            self.scalar_param(&b.weight, "weight", 0.5, ("in [0, 1]", |w| (0.0..=1.0).contains(&w)))?;
        materials[i].blend = Some(Box::new(Blend {
            weight,
            weight_texture,
            first,
            second,
        }));
        done[i] = true;
        stack.pop();
        Ok(())
    }

    fn material(&self, name: &str, m: &MaterialDesc) -> Result<Material, SceneError> {
        // Glass and metals have no diffuse term: absent, it is black.
        let default_diffuse = if m.dielectric.is_some() || m.conductor.is_some() {
            Vec3A::ZERO
        } else if m.disney.is_some() {
            // Mitsuba's default base colour.
            Vec3A::splat(0.5)
        } else {
            Vec3A::splat(DEFAULT_DIFFUSE)
        };
        let mut textures = MaterialTextures::default();
        let (diffuse, diffuse_tex) = self.colour_param(&m.diffuse, "diffuse", default_diffuse, Some(1.0))?;
        // The ambient reflectance follows the diffuse albedo, texture included.
        let (ambient, ambient_tex) = match &m.ambient {
            None => (diffuse, diffuse_tex.clone()),
            a => self.colour_param(a, "ambient", diffuse, Some(1.0))?,
        };
        let (specular, specular_tex) = self.colour_param(&m.specular, "specular", Vec3A::ZERO, Some(1.0))?;
        let (shininess, shininess_tex) =
            self.scalar_param(&m.shininess, "shininess", DEFAULT_SHININESS, ("> 0", |n| n > 0.0))?;
        (
            textures.diffuse,
            textures.ambient,
            textures.specular,
            textures.shininess,
        ) = (diffuse_tex, ambient_tex, specular_tex, shininess_tex);
        let mirror = match &m.mirror {
            None => None,
            Some(s) => {
                let d = s.get_ref();
                let (reflectivity, reflectivity_tex) = self.scalar_param(
                    &d.reflectivity,
                    "reflectivity",
                    1.0,
                    ("in [0, 1]", |x| (0.0..=1.0).contains(&x)),
                )?;
                let (tint, tint_tex) = self.colour_param(&d.tint, "tint", Vec3A::ONE, Some(1.0))?;
                (textures.mirror_reflectivity, textures.mirror_tint) = (reflectivity_tex, tint_tex);
                Some(Mirror { reflectivity, tint })
            }
        };
        // Anisotropic roughness, of the dielectric or the conductor.
        let mut roughness_v = None;
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
                let (tint, tint_tex) = self.colour_param(&d.tint, "tint", Vec3A::ONE, Some(1.0))?;
                let (roughness, roughness_tex) = self.roughness(&d.roughness)?;
                let thin = d.thin.as_ref().is_some_and(|t| *t.get_ref());
                if thin && (roughness > 0.0 || roughness_tex.is_some()) {
                    let at = d.thin.as_ref().expect("thin is set").span();
                    return Err(self.invalid(at, "a thin dielectric is smooth: remove `roughness` or `thin`"));
                }
                (textures.dielectric_tint, textures.dielectric_roughness) = (tint_tex, roughness_tex);
                if let Some(r) = &d.roughness_v {
                    if thin {
                        return Err(self.invalid(r.span(), "a thin dielectric is smooth: remove `roughness_v`"));
                    }
                    let (v, v_tex) = self.roughness(&d.roughness_v)?;
                    (roughness_v, textures.roughness_v) = (Some(v), v_tex);
                }
                Some(Dielectric {
                    thin,
                    ior,
                    tint,
                    roughness,
                    fresnel: d.fresnel.map(|f| match f {
                        FresnelName::Exact => FresnelModel::Exact,
                        FresnelName::Schlick => FresnelModel::Schlick,
                    }),
                })
            }
        };
        let conductor = match &m.conductor {
            None => None,
            Some(s) => {
                self.exclusive(
                    name,
                    "conductor",
                    s.span(),
                    &[("mirror", m.mirror.is_some()), ("dielectric", m.dielectric.is_some())],
                )?;
                let c = s.get_ref();
                let (eta, k) =
                    match (&c.metal, &c.eta, &c.k) {
                        (Some(metal), None, None) => metals::metal(metal.get_ref()).ok_or_else(|| {
                            let names: Vec<&str> = metals::METALS.iter().map(|m| m.name).collect();
                            self.invalid(
                                metal.span(),
                                format!(
                                    "unknown metal `{}`: expected one of {}",
                                    metal.get_ref(),
                                    names.join(", ")
                                ),
                            )
                        })?,
                        (None, Some(eta), Some(k)) => {
                            let eta_v = self.vec3(eta, "eta")?;
                            let k_v = self.vec3(k, "k")?;
                            if eta_v.min_element() <= 0.0 {
                                return Err(self.invalid(eta.span(), "`eta` must be > 0 in every channel"));
                            }
                            if k_v.min_element() < 0.0 {
                                return Err(self.invalid(k.span(), "`k` must be ≥ 0 in every channel"));
                            }
                            (eta_v, k_v)
                        }
                        _ => return Err(self.invalid(
                            s.span(),
                            "a conductor needs either `metal` (gold, silver, copper, aluminium) or both `eta` and `k`",
                        )),
                    };
                let (roughness, roughness_tex) = self.roughness(&c.roughness)?;
                textures.conductor_roughness = roughness_tex;
                if c.roughness_v.is_some() {
                    let (v, v_tex) = self.roughness(&c.roughness_v)?;
                    (roughness_v, textures.roughness_v) = (Some(v), v_tex);
                }
                Some(Conductor { eta, k, roughness })
            }
        };
        let coating = match &m.coating {
            None => None,
            Some(s) => {
                self.exclusive(
                    name,
                    "coating",
                    s.span(),
                    &[
                        ("mirror", m.mirror.is_some()),
                        ("dielectric", m.dielectric.is_some()),
                        ("conductor", m.conductor.is_some()),
                    ],
                )?;
                let ior = match &s.get_ref().ior {
                    None => DEFAULT_IOR,
                    Some(r) => {
                        let x = self.number(r, "ior")?;
                        if x <= 1.0 {
                            return Err(self.invalid(r.span(), format!("coating `ior` = {x} must be > 1")));
                        }
                        x
                    }
                };
                let roughness = match &s.get_ref().roughness {
                    None => 0.0,
                    Some(r) => {
                        let x = self.number(r, "roughness")?;
                        if !(0.0..=1.0).contains(&x) {
                            return Err(self.invalid(r.span(), format!("coating `roughness` = {x} must be in [0, 1]")));
                        }
                        x
                    }
                };
                Some(Coating {
                    ior,
                    roughness,
                    nonlinear: s.get_ref().nonlinear.unwrap_or(false),
                    table: Default::default(),
                })
            }
        };
        let principled = match &m.principled {
            None => None,
            Some(s) => {
                self.exclusive(
                    name,
                    "principled",
                    s.span(),
                    &[
                        ("mirror", m.mirror.is_some()),
                        ("dielectric", m.dielectric.is_some()),
                        ("conductor", m.conductor.is_some()),
                        ("coating", m.coating.is_some()),
                    ],
                )?;
                let p = s.get_ref();
                let unit = ("in [0, 1]", (|x| (0.0..=1.0).contains(&x)) as fn(f32) -> bool);
                let (metallic, metallic_tex) = self.scalar_param(&p.metallic, "metallic", 0.0, unit)?;
                let (roughness, roughness_tex) = self.scalar_param(&p.roughness, "roughness", 0.5, unit)?;
                let (transmission, transmission_tex) = self.scalar_param(&p.transmission, "transmission", 0.0, unit)?;
                let (clearcoat, clearcoat_tex) = self.scalar_param(&p.clearcoat, "clearcoat", 0.0, unit)?;
                let (clearcoat_roughness, clearcoat_roughness_tex) =
                    self.scalar_param(&p.clearcoat_roughness, "clearcoat_roughness", 0.0, unit)?;
                let ior = match &p.ior {
                    None => DEFAULT_IOR,
                    Some(r) => {
                        let x = self.number(r, "ior")?;
                        if !(1.0..=10.0).contains(&x) {
                            return Err(self.invalid(r.span(), format!("principled `ior` = {x} must be in [1, 10]")));
                        }
                        x
                    }
                };
                (
                    textures.principled_metallic,
                    textures.principled_roughness,
                    textures.principled_transmission,
                    textures.principled_clearcoat,
                    textures.principled_clearcoat_roughness,
                ) = (
                    metallic_tex,
                    roughness_tex,
                    transmission_tex,
                    clearcoat_tex,
                    clearcoat_roughness_tex,
                );
                Some(Principled {
                    metallic,
                    roughness,
                    ior,
                    transmission,
                    thin: p.thin.as_ref().is_none_or(|t| *t.get_ref()),
                    clearcoat,
                    clearcoat_roughness,
                })
            }
        };
        let disney = match &m.disney {
            None => None,
            Some(s) => {
                self.exclusive(
                    name,
                    "disney",
                    s.span(),
                    &[
                        ("mirror", m.mirror.is_some()),
                        ("dielectric", m.dielectric.is_some()),
                        ("conductor", m.conductor.is_some()),
                        ("coating", m.coating.is_some()),
                        ("principled", m.principled.is_some()),
                    ],
                )?;
                Some(self.disney(s, &mut textures)?)
            }
        };
        if let Some(n) = m.null.as_ref().filter(|n| *n.get_ref()) {
            self.exclusive(
                name,
                "null",
                n.span(),
                &[
                    ("mirror", m.mirror.is_some()),
                    ("dielectric", m.dielectric.is_some()),
                    ("conductor", m.conductor.is_some()),
                    ("coating", m.coating.is_some()),
                    ("principled", m.principled.is_some()),
                    ("disney", m.disney.is_some()),
                    ("blend", m.blend.is_some()),
                ],
            )?;
        }
        let (emission, emission_tex) = self.colour_param(&m.emission, "emission", Vec3A::ZERO, None)?;
        let strength = match &m.emission_strength {
            None => 1.0,
            Some(s) if m.emission.is_none() => {
                return Err(self.invalid(s.span(), "`emission_strength` without an `emission`"));
            }
            Some(s) => {
                let x = self.number(s, "emission_strength")?;
                if x < 0.0 {
                    return Err(self.invalid(s.span(), format!("`emission_strength` = {x} must be ≥ 0")));
                }
                x
            }
        };
        // A textured emission keeps its texels and scales them by the strength.
        let emission = if emission_tex.is_some() {
            Vec3A::splat(strength)
        } else {
            emission * strength
        };
        if !emission.is_finite() {
            let span = m
                .emission_strength
                .as_ref()
                .or(None)
                .map_or_else(|| m.emission.as_ref().map_or(0..0, |s| s.span()), |s| s.span());
            return Err(self.invalid(span, "`emission` × `emission_strength` overflows single precision"));
        }
        textures.emission = emission_tex;
        if let Some(n) = &m.normal_map {
            let scale = match &m.normal_scale {
                None => 1.0,
                Some(s) => self.number(s, "normal_scale")?,
            };
            textures.normal_map = Some(NormalMap {
                texture: self.texture_param(n, "normal_map", Usage::Normal)?,
                scale,
            });
        } else if let Some(s) = &m.normal_scale {
            return Err(self.invalid(s.span(), "`normal_scale` without a `normal_map`"));
        }
        if let Some(b) = &m.bump_map {
            if m.normal_map.is_some() {
                return Err(self.invalid(b.span(), "a material takes `normal_map` or `bump_map`, not both"));
            }
            let scale = match &m.bump_scale {
                None => 1.0,
                Some(s) => self.number(s, "bump_scale")?,
            };
            textures.bump_map = Some(crate::scene::BumpMap {
                texture: self.texture_param(b, "bump_map", Usage::Scalar)?,
                scale,
            });
        } else if let Some(s) = &m.bump_scale {
            return Err(self.invalid(s.span(), "`bump_scale` without a `bump_map`"));
        }
        if let Some(a) = &m.alpha {
            let cutoff = match &m.alpha_cutoff {
                None => 0.5,
                Some(s) => {
                    let x = self.number(s, "alpha_cutoff")?;
                    if !(0.0..=1.0).contains(&x) {
                        return Err(self.invalid(s.span(), format!("`alpha_cutoff` = {x} must be in [0, 1]")));
                    }
                    x
                }
            };
            let texture = match a.get_ref() {
                // A constant alpha is a surface that is there or not.
                ParamDesc::Number(x) => Texture::scalar(self.check_finite(*x, a.span(), "alpha")?),
                _ => self.texture_param(a, "alpha", Usage::Alpha)?,
            };
            textures.alpha = Some(AlphaMask { texture, cutoff });
        } else if let Some(s) = &m.alpha_cutoff {
            return Err(self.invalid(s.span(), "`alpha_cutoff` without an `alpha` mask"));
        }
        let microfacet = match &m.microfacet {
            None => MicrofacetDistribution::Ggx,
            Some(d) => match d.get_ref().as_str() {
                "ggx" => MicrofacetDistribution::Ggx,
                "beckmann" => MicrofacetDistribution::Beckmann,
                other => {
                    return Err(self.invalid(
                        d.span(),
                        format!("unknown `microfacet` distribution `{other}`: expected ggx or beckmann"),
                    ))
                }
            },
        };
        Ok(Material {
            textures: textures.has_any().then(|| Box::new(textures)),
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
            conductor,
            coating,
            emission,
            one_sided: m.one_sided.as_ref().is_some_and(|s| *s.get_ref()),
            emits_both_sides: m.emit_both_sides.as_ref().is_some_and(|s| *s.get_ref()),
            microfacet,
            roughness_v,
            null: m.null.as_ref().is_some_and(|n| *n.get_ref()),
            principled,
            disney,
            blend: None,
        })
    }

    /// GGX roughness `alpha` in [0, 1] (0 when absent: smooth), or a texture.
    fn roughness(&self, r: &Option<Spanned<ParamDesc>>) -> Result<(f32, Option<Texture>), SceneError> {
        self.scalar_param(r, "roughness", 0.0, ("in [0, 1]", |x| (0.0..=1.0).contains(&x)))
    }

    /// Refuses `component` next to any of `others` that is present.
    fn exclusive(
        &self,
        name: &str,
        component: &str,
        at: std::ops::Range<usize>,
        others: &[(&str, bool)],
    ) -> Result<(), SceneError> {
        match others.iter().find(|(_, present)| *present) {
            Some((other, _)) => Err(self.invalid(
                at,
                format!("material `{name}` has both `{other}` and `{component}`: keep one of them"),
            )),
            None => Ok(()),
        }
    }
}
