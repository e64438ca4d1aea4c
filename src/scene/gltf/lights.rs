//! `KHR_lights_punctual`: point, spot and directional lights, placed by
//! their nodes, with glTF's photometric units converted to caustic's
//! radiometric ones at [`LUMENS_PER_WATT`].

use super::nodes::Graph;
use super::Ctx;
use crate::math::Vec3A;
use crate::scene::light::{SpotFalloff, SpotLight};
use crate::scene::load::SceneError;
use crate::scene::Light;
use glam::Vec3;

/// Lumens per watt of the conversion from glTF's photometric units
/// (candela for point and spot lights, lux for directional ones) to
/// caustic's radiometric ones (W/sr, W/m²): 683 lm/W, the luminous
/// efficacy that defines the candela at 540 THz (SI), and the factor
/// Blender's glTF importer uses in its "standard" lighting mode. A light of
/// `I` cd becomes a point light of `I / 683` W/sr; `E` lux a directional
/// light of `E / 683` W/m².
pub const LUMENS_PER_WATT: f32 = 683.0;

/// Radiance of the uniform environment that lights a model without
/// punctual lights: 1 (W/m²/sr per channel), so that an unshadowed white
/// diffuse surface reflects radiance 1 and a surface of albedo `a` shows
/// `a`, the colours of the model as authored, at exposure 0.
pub const DEFAULT_ENVIRONMENT_RADIANCE: f32 = 1.0;

/// The lights the scene's nodes place.
pub(super) fn lights(ctx: &Ctx, graph: &Graph) -> Result<Vec<Light>, SceneError> {
    let doc = ctx.doc;
    let Some(all) = doc.lights() else {
        return Ok(Vec::new());
    };
    let all: Vec<_> = all.collect();
    let mut out = Vec::new();
    for placed in &graph.lights {
        let light = &all[placed.item];
        let pointer = format!("/extensions/KHR_lights_punctual/lights/{}", placed.item);
        let intensity = light.intensity();
        if !(intensity >= 0.0 && intensity.is_finite()) {
            return Err(ctx.error(format!("{pointer}/intensity"), format!("{intensity}: must be ≥ 0")));
        }
        let colour = Vec3A::from_array(light.color());
        if colour.min_element() < 0.0 || !colour.is_finite() {
            return Err(ctx.error(format!("{pointer}/color"), "the colour must be finite and ≥ 0"));
        }
        let scaled = colour * (intensity / LUMENS_PER_WATT);
        let position = Vec3A::from(placed.world.transform_point3(Vec3::ZERO));
        // Lights shine down their node's −z axis (the extension's definition).
        let axis = Vec3A::from(placed.world.transform_vector3(Vec3::NEG_Z)).try_normalize();
        let node_error = || {
            ctx.error(
                format!("/nodes/{}", placed.node),
                "the node's transform collapses the light's −z axis",
            )
        };
        out.push(match light.kind() {
            gltf::khr_lights_punctual::Kind::Point => Light::Point {
                position,
                intensity: scaled,
            },
            gltf::khr_lights_punctual::Kind::Directional => Light::Directional {
                direction: axis.ok_or_else(node_error)?,
                irradiance: scaled,
            },
            gltf::khr_lights_punctual::Kind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } => {
                let half_pi = std::f32::consts::FRAC_PI_2;
                if !(outer_cone_angle > 0.0 && outer_cone_angle <= half_pi) {
                    return Err(ctx.error(
                        format!("{pointer}/spot/outerConeAngle"),
                        format!("{outer_cone_angle}: must be in (0, π/2]"),
                    ));
                }
                if !(inner_cone_angle >= 0.0 && inner_cone_angle < outer_cone_angle) {
                    return Err(ctx.error(
                        format!("{pointer}/spot/innerConeAngle"),
                        format!("{inner_cone_angle}: must be in [0, outerConeAngle)"),
                    ));
                }
                Light::Spot(SpotLight {
                    position,
                    axis: axis.ok_or_else(node_error)?,
                    intensity: scaled,
                    cutoff: outer_cone_angle,
                    beam_width: inner_cone_angle,
                    falloff: SpotFalloff::Gltf,
                })
            }
        });
    }
    Ok(out)
}
