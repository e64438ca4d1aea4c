//! The `[[lights]]`: point, area and environment lights, with the limit and
//! default of an area light's shadow samples.

use super::ctx::Ctx;
use super::error::SceneError;
use crate::math::{Transform, Vec3, Vec3A};
use crate::scene::desc::{LightDesc, LightKind};
use crate::scene::light::EnvironmentMap;
use crate::scene::{AreaLight, Light};
use crate::texture::ColourSpace;
use std::sync::Arc;

/// Largest number of shadow samples of one area light.
pub const MAX_AREA_LIGHT_SAMPLES: u32 = 4096;
/// Default shadow samples of an area light (the original report used 32).
pub const DEFAULT_AREA_LIGHT_SAMPLES: u32 = 32;

impl Ctx<'_> {
    pub(super) fn light(&self, l: &LightDesc) -> Result<Light, SceneError> {
        let present = [
            ("u", l.u.as_ref().map(|s| s.span())),
            ("v", l.v.as_ref().map(|s| s.span())),
            ("samples", l.samples.as_ref().map(|s| s.span())),
            ("file", l.file.as_ref().map(|s| s.span())),
            ("rotate", l.rotate.as_ref().map(|s| s.span())),
        ];
        let colour = match &l.colour {
            None => Vec3A::ONE,
            Some(s) => self.colour(s, "colour")?,
        };
        let intensity = match &l.intensity {
            None => 1.0,
            Some(s) => {
                let x = self.number(s, "intensity")?;
                if x < 0.0 {
                    return Err(self.invalid(s.span(), format!("`intensity` = {x} must be ≥ 0")));
                }
                x
            }
        };
        let power = colour * intensity;
        if !power.is_finite() {
            let span = l.intensity.as_ref().map_or(l.kind.span(), |s| s.span());
            return Err(self.invalid(span, "`colour` × `intensity` overflows single precision"));
        }
        match l.kind.get_ref() {
            LightKind::Point => {
                self.only_keys("a point light", &present, &["type", "position", "colour", "intensity"])?;
                let position = self.required(&l.position, "position", "a point light", l.kind.span())?;
                Ok(Light::Point {
                    position: self.vec3(position, "position")?,
                    intensity: power,
                })
            }
            LightKind::Environment => {
                let present = [
                    ("u", l.u.as_ref().map(|s| s.span())),
                    ("v", l.v.as_ref().map(|s| s.span())),
                    ("samples", l.samples.as_ref().map(|s| s.span())),
                    ("position", l.position.as_ref().map(|s| s.span())),
                    (
                        "rotate",
                        l.rotate.as_ref().filter(|_| l.file.is_none()).map(|s| s.span()),
                    ),
                ];
                self.only_keys(
                    "an environment light (without `file`)",
                    &present,
                    &["type", "colour", "intensity", "file"],
                )?;
                let map = match &l.file {
                    None => None,
                    Some(file) => {
                        let image = self.image(file, ColourSpace::Srgb)?;
                        let rotate = self.opt_vec3(&l.rotate, "rotate", Vec3A::ZERO)?;
                        let to_world = Transform::from_srt(Vec3::ONE, rotate.into(), Vec3::ZERO)
                            .map(|t| t.to_world.matrix3)
                            .ok_or_else(|| {
                                let span = l.rotate.as_ref().map_or(file.span(), |s| s.span());
                                self.invalid(span, "`rotate` is not a rotation")
                            })?;
                        Some(Arc::new(EnvironmentMap::new(image, to_world)))
                    }
                };
                Ok(Light::Environment { radiance: power, map })
            }
            LightKind::Area => {
                let what = "an area light";
                let position = self.vec3(self.required(&l.position, "position", what, l.kind.span())?, "position")?;
                let u_desc = self.required(&l.u, "u", what, l.kind.span())?;
                let v_desc = self.required(&l.v, "v", what, l.kind.span())?;
                let u = self.direction(u_desc, "u")?;
                let v = self.direction(v_desc, "v")?;
                let samples = match &l.samples {
                    None => DEFAULT_AREA_LIGHT_SAMPLES,
                    Some(s) if (1..=MAX_AREA_LIGHT_SAMPLES).contains(s.get_ref()) => *s.get_ref(),
                    Some(s) => {
                        return Err(self.invalid(
                            s.span(),
                            format!(
                                "`samples` = {} is out of range: it must be in 1..={MAX_AREA_LIGHT_SAMPLES}",
                                s.get_ref()
                            ),
                        ))
                    }
                };
                AreaLight::new(position, u, v, power, samples)
                    .filter(|a| a.area() > 0.0 && a.area().is_finite())
                    .map(Light::Area)
                    .ok_or_else(|| {
                        self.invalid(
                            v_desc.span(),
                            "the area light's edges `u` and `v` are parallel: the rectangle has no area",
                        )
                    })
            }
        }
    }
}
