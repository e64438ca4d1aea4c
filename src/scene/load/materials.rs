//! The `[materials]` table: each material's shading model, reflectances,
//! mirror and dielectric, with their defaults.

use super::ctx::Ctx;
use super::error::SceneError;
use crate::math::Vec3A;
use crate::scene::desc::{MaterialDesc, ModelName};
use crate::scene::{Dielectric, Material, Mirror, ShadingModel};
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
}
