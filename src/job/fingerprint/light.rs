//! Lights' encoding; an environment image by its texels' content.

use super::encoder::{Encoder, Fingerprint};
use crate::scene::light::{EnvironmentMap, SpotFalloff, SpotLight};
use crate::scene::{AreaLight, Light};

impl Fingerprint for Light {
    fn encode(&self, e: &mut Encoder) {
        e.tag("light");
        match self {
            Light::Point { position, intensity } => {
                e.u8(0);
                e.put(position);
                e.put(intensity);
            }
            Light::Spot(s) => {
                e.u8(1);
                let SpotLight {
                    position,
                    axis,
                    intensity,
                    cutoff,
                    beam_width,
                    falloff,
                } = s;
                e.put(position);
                e.put(axis);
                e.put(intensity);
                e.f32(*cutoff);
                e.f32(*beam_width);
                // Mitsuba's falloff, the first, adds nothing.
                if *falloff == SpotFalloff::Gltf {
                    e.tag("gltf falloff");
                }
            }
            Light::Directional { direction, irradiance } => {
                e.u8(2);
                e.put(direction);
                e.put(irradiance);
            }
            Light::Area(a) => {
                e.u8(3);
                let AreaLight {
                    center,
                    u,
                    v,
                    normal,
                    radiance,
                    samples,
                } = a;
                e.put(center);
                e.put(u);
                e.put(v);
                e.put(normal);
                e.put(radiance);
                e.u32(*samples);
            }
            Light::Environment { radiance, map } => {
                e.u8(4);
                e.put(radiance);
                e.option(map.as_deref(), |e, m| e.put(m));
            }
        }
    }
}

impl Fingerprint for EnvironmentMap {
    fn encode(&self, e: &mut Encoder) {
        // The sampling distribution and integral follow from the image.
        e.tag("environment map");
        e.put(self.image.as_ref());
        e.floats(&self.to_world.to_cols_array());
    }
}
