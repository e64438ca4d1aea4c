//! `<emitter>`: point, spot, directional, constant and envmap as lights;
//! `area` is read by the shape it is nested in.

use super::props::Plugin;
use super::spectrum::SpectrumUse;
use super::Builder;
use crate::math::{Vec3, Vec3A};
use crate::scene::light::{EnvironmentMap, SpotFalloff, SpotLight};
use crate::scene::load::SceneError;
use crate::scene::Light;
use crate::texture::ColourSpace;
use glam::{Mat3A, Mat4};
use std::sync::Arc;

impl Builder<'_> {
    /// A constant emission parameter (a texture is refused).
    fn emission(&self, p: &Plugin, name: &str) -> Result<Vec3A, SceneError> {
        let (c, texture) = self.colour(p, name, Vec3A::ONE, SpectrumUse::Emission)?;
        if texture.is_some() {
            return Err(p.error(format!("a textured `{name}` is not supported on this emitter")));
        }
        Ok(c)
    }

    /// A light from a top-level `<emitter>`.
    pub(super) fn emitter(&self, p: &Plugin) -> Result<Light, SceneError> {
        let light = match p.kind {
            "point" => {
                let intensity = self.emission(p, "intensity")?;
                let position = placed(p, "position", |m| m.transform_point3(Vec3::ZERO), Vec3::ZERO)?;
                Light::Point {
                    position: position.into(),
                    intensity,
                }
            }
            "spot" => {
                let intensity = self.emission(p, "intensity")?;
                let cutoff = p.float_checked("cutoff_angle", 20.0, "in (0, 90] degrees", |v| v > 0.0 && v <= 90.0)?;
                let beam = p.float_checked("beam_width", cutoff * 0.75, "in [0, cutoff_angle]", |v| {
                    (0.0..=cutoff).contains(&v)
                })?;
                if p.has("texture") {
                    return Err(p.error("a projected `texture` is not supported"));
                }
                let m = affine(p, &p.transform("to_world")?.unwrap_or(Mat4::IDENTITY))?;
                let axis = m
                    .transform_vector3(Vec3::Z)
                    .try_normalize()
                    .ok_or_else(|| p.error("`to_world` is singular"))?;
                Light::Spot(SpotLight {
                    position: m.transform_point3(Vec3::ZERO).into(),
                    axis: axis.into(),
                    intensity,
                    cutoff: cutoff.to_radians(),
                    beam_width: beam.to_radians(),
                    falloff: SpotFalloff::Mitsuba,
                })
            }
            "directional" => {
                let irradiance = self.emission(p, "irradiance")?;
                let direction = placed(p, "direction", |m| m.transform_vector3(Vec3::Z), Vec3::Z)?;
                let direction = direction
                    .try_normalize()
                    .ok_or_else(|| p.error("the direction is zero"))?;
                Light::Directional {
                    direction: direction.into(),
                    irradiance,
                }
            }
            "constant" => Light::Environment {
                radiance: self.emission(p, "radiance")?,
                map: None,
            },
            "envmap" => {
                let file = p.string("filename")?.ok_or_else(|| p.error("`filename` is required"))?;
                let scale = p.float_checked("scale", 1.0, "≥ 0", |v| v >= 0.0)?;
                if p.boolean("mis_compensation")?.unwrap_or(false) {
                    return Err(p.error("`mis_compensation` is not supported"));
                }
                p.choice("filter_type", "bilinear", &["bilinear"])?;
                let m = p.transform("to_world")?.unwrap_or(Mat4::IDENTITY);
                let rotation = Mat3A::from_mat4(m);
                let orthonormal = (rotation.transpose() * rotation - Mat3A::IDENTITY)
                    .to_cols_array()
                    .iter()
                    .all(|v| v.abs() < 1e-3);
                if !orthonormal || rotation.determinant() < 0.0 {
                    return Err(p.error("`to_world` of an environment map must be a rotation (its translation is ignored)"));
                }
                let image = self.image(p, file, ColourSpace::Srgb)?;
                Light::Environment {
                    radiance: Vec3A::splat(scale),
                    map: Some(Arc::new(EnvironmentMap::new(image, rotation))),
                }
            }
            "area" => {
                return Err(p.error("an area emitter belongs inside a <shape>"));
            }
            other => {
                return Err(p.error(format!(
                    "the emitter `{other}` is not supported: caustic reads area, point, spot, directional, constant and envmap"
                )))
            }
        };
        p.finish()?;
        Ok(light)
    }
}

/// The vector property `name`, or what `to_world` makes of the light's
/// frame (`from_world`), or `default`; both given is an error.
fn placed(
    p: &Plugin,
    name: &str,
    from_world: impl Fn(&glam::Affine3A) -> Vec3,
    default: Vec3,
) -> Result<Vec3, SceneError> {
    match (p.vector(name)?, p.transform("to_world")?) {
        (Some(_), Some(_)) => Err(p.error(format!("give `{name}` or `to_world`, not both"))),
        (Some(v), None) => Ok(v),
        (None, Some(m)) => Ok(from_world(&affine(p, &m)?)),
        (None, None) => Ok(default),
    }
}

/// An affine `to_world` (a projective one is refused).
pub(super) fn affine(p: &Plugin, m: &Mat4) -> Result<glam::Affine3A, SceneError> {
    if m.row(3) != glam::Vec4::W {
        return Err(p.error("`to_world` is a projective matrix; caustic takes affine transforms"));
    }
    Ok(glam::Affine3A::from_mat4(*m))
}
