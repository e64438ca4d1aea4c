//! `[[lights]]`: one table per light, its power as `colour` (the
//! loader's `colour × intensity` with `intensity = 1` is exact).

use super::{degrees_for, int, num, path_from, string, unsupported, vec3, WriteError};
use crate::scene::light::SpotFalloff;
use crate::scene::Light;
use std::path::Path;
use toml::{Table, Value};

/// Light `i` as a `[[lights]]` table; an environment image is referenced
/// by its path relative to `dir`.
pub(super) fn light(i: usize, l: &Light, dir: &Path) -> Result<Table, WriteError> {
    let part = || format!("light {i} ({})", l.kind_name());
    let mut t = Table::new();
    let kind = l.kind_name();
    t.insert("type".into(), string(kind));
    match l {
        Light::Point { position, intensity } => {
            t.insert("position".into(), vec3(*position));
            t.insert("colour".into(), vec3(*intensity));
        }
        Light::Spot(s) => {
            t.insert("position".into(), vec3(s.position));
            t.insert("direction".into(), vec3(exact_direction(s.axis, &part)?));
            t.insert("colour".into(), vec3(s.intensity));
            let angle = |r: f32, key: &str| {
                degrees_for(r)
                    .map(num)
                    .ok_or_else(|| unsupported(part(), format!("`{key}` of {r} radians has no exact degrees")))
            };
            t.insert("cutoff_angle".into(), angle(s.cutoff, "cutoff_angle")?);
            t.insert("beam_width".into(), angle(s.beam_width, "beam_width")?);
            if s.falloff != SpotFalloff::Mitsuba {
                t.insert("falloff".into(), string(s.falloff.name()));
            }
        }
        Light::Directional { direction, irradiance } => {
            t.insert("direction".into(), vec3(exact_direction(*direction, &part)?));
            t.insert("colour".into(), vec3(*irradiance));
        }
        Light::Area(a) => {
            t.insert("position".into(), vec3(a.center));
            t.insert("u".into(), vec3(a.u));
            t.insert("v".into(), vec3(a.v));
            t.insert("colour".into(), vec3(a.radiance));
            t.insert("samples".into(), int(a.samples));
        }
        Light::Environment { radiance, map } => {
            t.insert("colour".into(), vec3(*radiance));
            if let Some(map) = map {
                if map.to_world != crate::math::Mat3A::IDENTITY {
                    return Err(unsupported(
                        part(),
                        "a rotated environment image (caustic's TOML rotates it by Euler angles, which would round the rotation)",
                    ));
                }
                t.insert("file".into(), Value::String(path_from(dir, Path::new(&map.image.name))));
            }
        }
    }
    Ok(t)
}

/// The direction to write: the loader normalises it, so a vector that
/// normalises to `d` exactly.
fn exact_direction(d: crate::math::Vec3A, part: &dyn Fn() -> String) -> Result<crate::math::Vec3A, WriteError> {
    super::normalizes_to(d).ok_or_else(|| {
        unsupported(
            part(),
            format!("the direction {d} is not the normalisation of any vector near it in single precision"),
        )
    })
}
