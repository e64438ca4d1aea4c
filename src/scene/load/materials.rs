//! The `[materials]` table: each material's shading model, reflectances,
//! mirror, dielectric, conductor and coating, with their defaults.

use super::ctx::Ctx;
use super::error::SceneError;
use crate::math::Vec3A;
use crate::scene::desc::{FresnelName, MaterialDesc, ModelName, Spanned};
use crate::scene::metals;
use crate::scene::{Coating, Conductor, Dielectric, FresnelModel, Material, Mirror, ShadingModel};
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
        Ok((materials, index))
    }

    fn material(&self, name: &str, m: &MaterialDesc) -> Result<Material, SceneError> {
        // Glass and metals have no diffuse term: absent, it is black.
        let default_diffuse = if m.dielectric.is_some() || m.conductor.is_some() {
            Vec3A::ZERO
        } else {
            Vec3A::splat(DEFAULT_DIFFUSE)
        };
        let diffuse = self.reflectance(&m.diffuse, "diffuse", default_diffuse)?;
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
                Some(Dielectric {
                    ior,
                    tint,
                    roughness: self.roughness(&d.roughness)?,
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
                Some(Conductor {
                    eta,
                    k,
                    roughness: self.roughness(&c.roughness)?,
                })
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
                Some(Coating { ior })
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
            conductor,
            coating,
        })
    }

    /// GGX roughness `alpha` in [0, 1] (0 when absent: smooth).
    fn roughness(&self, r: &Option<Spanned<f64>>) -> Result<f32, SceneError> {
        match r {
            None => Ok(0.0),
            Some(s) => {
                let x = self.number(s, "roughness")?;
                if !(0.0..=1.0).contains(&x) {
                    return Err(self.invalid(s.span(), format!("`roughness` = {x} must be in [0, 1]")));
                }
                Ok(x)
            }
        }
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
