//! The `[[lights]]`: point, spot, directional, area and environment lights,
//! with the limit and default of an area light's shadow samples.

use super::ctx::Ctx;
use super::error::SceneError;
use crate::math::{Transform, Vec3, Vec3A};
use crate::scene::desc::{LightDesc, LightKind};
use crate::scene::light::{EnvironmentMap, SpotFalloff, SpotLight};
use crate::scene::{AreaLight, Light};
use crate::texture::ColourSpace;
use std::sync::Arc;

/// Largest number of shadow samples of one area light.
pub const MAX_AREA_LIGHT_SAMPLES: u32 = 4096;
/// Default shadow samples of an area light (the original report used 32).
pub const DEFAULT_AREA_LIGHT_SAMPLES: u32 = 32;
/// Default half-angle of a spot light's cone, degrees (Mitsuba's `spot`).
pub const DEFAULT_SPOT_CUTOFF_DEG: f32 = 20.0;

impl Ctx<'_> {
    pub(super) fn light(&self, l: &LightDesc) -> Result<Light, SceneError> {
        let present = [
            ("position", l.position.as_ref().map(|s| s.span())),
            ("u", l.u.as_ref().map(|s| s.span())),
            ("v", l.v.as_ref().map(|s| s.span())),
            ("samples", l.samples.as_ref().map(|s| s.span())),
            ("file", l.file.as_ref().map(|s| s.span())),
            ("rotate", l.rotate.as_ref().map(|s| s.span())),
            ("look_at", l.look_at.as_ref().map(|s| s.span())),
            ("direction", l.direction.as_ref().map(|s| s.span())),
            ("cutoff_angle", l.cutoff_angle.as_ref().map(|s| s.span())),
            ("beam_width", l.beam_width.as_ref().map(|s| s.span())),
            ("falloff", l.falloff.as_ref().map(|s| s.span())),
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
                // `rotate` turns an image: without `file` it is refused.
                let mut present = present.clone();
                if l.file.is_some() {
                    present[5].1 = None;
                }
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
            LightKind::Spot => {
                let what = "a spot light";
                self.only_keys(
                    what,
                    &present,
                    &[
                        "type",
                        "position",
                        "look_at",
                        "direction",
                        "cutoff_angle",
                        "beam_width",
                        "falloff",
                        "colour",
                        "intensity",
                    ],
                )?;
                let position = self.vec3(self.required(&l.position, "position", what, l.kind.span())?, "position")?;
                let axis = match (&l.look_at, &l.direction) {
                    (Some(t), None) => (self.vec3(t, "look_at")? - position)
                        .try_normalize()
                        .ok_or_else(|| self.invalid(t.span(), "`look_at` is the spot light's `position`"))?,
                    (None, Some(d)) => self.direction(d, "direction")?.normalize(),
                    (Some(_), Some(d)) => {
                        return Err(self.invalid(d.span(), "a spot light takes `look_at` or `direction`, not both"))
                    }
                    (None, None) => {
                        return Err(self.invalid(l.kind.span(), "a spot light needs `look_at` or `direction`"))
                    }
                };
                let cutoff = match &l.cutoff_angle {
                    None => DEFAULT_SPOT_CUTOFF_DEG,
                    Some(s) => {
                        let x = self.number(s, "cutoff_angle")?;
                        if !(x > 0.0 && x <= 90.0) {
                            return Err(
                                self.invalid(s.span(), format!("`cutoff_angle` = {x} must be in (0, 90] degrees"))
                            );
                        }
                        x
                    }
                };
                let beam_width = match &l.beam_width {
                    None => 0.75 * cutoff,
                    Some(s) => {
                        let x = self.number(s, "beam_width")?;
                        if !(0.0..=cutoff).contains(&x) {
                            return Err(self.invalid(
                                s.span(),
                                format!("`beam_width` = {x} must be in [0, cutoff_angle = {cutoff}] degrees"),
                            ));
                        }
                        x
                    }
                };
                let falloff = match &l.falloff {
                    None => SpotFalloff::Mitsuba,
                    Some(f) => SpotFalloff::from_name(f.get_ref()).ok_or_else(|| {
                        self.invalid(
                            f.span(),
                            format!("unknown `falloff` `{}`: expected mitsuba or gltf", f.get_ref()),
                        )
                    })?,
                };
                Ok(Light::Spot(SpotLight {
                    position,
                    axis,
                    intensity: power,
                    cutoff: cutoff.to_radians(),
                    beam_width: beam_width.to_radians(),
                    falloff,
                }))
            }
            LightKind::Directional => {
                let what = "a directional light";
                self.only_keys(what, &present, &["type", "direction", "colour", "intensity"])?;
                let d = self.required(&l.direction, "direction", what, l.kind.span())?;
                Ok(Light::Directional {
                    direction: self.direction(d, "direction")?.normalize(),
                    irradiance: power,
                })
            }
            LightKind::Area => {
                let what = "an area light";
                self.only_keys(
                    what,
                    &present,
                    &["type", "position", "u", "v", "samples", "colour", "intensity"],
                )?;
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
