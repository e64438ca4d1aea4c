//! `<medium type="homogeneous">` with its `<phase>` (isotropic, hg), as
//! [`HomogeneousMedium`]s: defined at the top level and referenced by
//! `<ref name="interior|exterior" id="…"/>`, or nested in a shape or the
//! sensor. Mitsuba's homogeneous medium has `σt = scale · sigma_t` and
//! `σs = albedo · σt` (`src/media/homogeneous.cpp`); `sigma_t` and `albedo`
//! are volumes, given as a float, an `<rgb>`, a `<spectrum>`, a
//! `constvolume` or a constant texture.

use super::props::{ColourParam, Plugin};
use super::spectrum::SpectrumUse;
use super::Builder;
use crate::math::Vec3A;
use crate::scene::load::SceneError;
use crate::scene::{HomogeneousMedium, PhaseFunction};
use crate::texture::Texture;

impl Builder<'_> {
    /// The index of a `<medium>` in the scene's list (a medium referenced
    /// from several places is read once and shared).
    pub(super) fn medium(&mut self, p: &Plugin) -> Result<u32, SceneError> {
        if p.element.tag != "medium" {
            return Err(p.error("expected a <medium> here"));
        }
        let key = p.element as *const _ as usize;
        if let Some(&i) = self.medium_index.get(&key) {
            return Ok(i);
        }
        let medium = self.homogeneous(p)?;
        let i = self.media.len() as u32;
        self.media.push(medium);
        self.medium_index.insert(key, i);
        Ok(i)
    }

    fn homogeneous(&self, p: &Plugin) -> Result<HomogeneousMedium, SceneError> {
        match p.kind {
            "homogeneous" => {}
            "heterogeneous" => {
                return Err(p.error(
                    "heterogeneous media (grid volumes) are not supported: caustic renders `homogeneous` media",
                ))
            }
            other => {
                return Err(p.error(format!(
                    "the medium `{other}` is not supported: caustic renders `homogeneous` media"
                )))
            }
        }
        let name = p
            .element
            .attr("id")
            .map_or_else(|| format!("medium@{}", p.origin().place), str::to_string);
        let sigma_t = self.volume_value(p, "sigma_t", Vec3A::ONE)?;
        let albedo = self.volume_value(p, "albedo", Vec3A::splat(0.75))?;
        if albedo.max_element() > 1.0 {
            return Err(p.error(format!("`albedo` = {albedo} must be in [0, 1]")));
        }
        let scale = p.float_checked("scale", 1.0, "≥ 0", |s| s >= 0.0 && s.is_finite())?;
        let sample_emitters = p.boolean("sample_emitters")?.unwrap_or(true);
        // Mitsuba's hint that the extinction varies over the spectrum: the
        // same medium either way, sampled by caustic's spectral MIS.
        p.boolean("has_spectral_extinction")?;
        let phase = match p.single_child("phase")? {
            None => PhaseFunction::Isotropic,
            Some(ph) => phase(&ph)?,
        };
        p.finish()?;
        Ok(HomogeneousMedium {
            name,
            sigma_t: sigma_t * scale,
            albedo,
            phase,
            sample_emitters,
        })
    }

    /// A constant volume parameter: a value, a `constvolume`, or a
    /// constant texture; anything varying in space is refused. Mitsuba
    /// reads a bare `<rgb>` or a `<spectrum>` of wavelengths here as a
    /// reflectance (an `<rgb>` beyond [0, 1] is an error, a spectrum is
    /// clamped); a number is taken as it is, as is a `constvolume`'s `<rgb>`.
    fn volume_value(&self, p: &Plugin, name: &str, default: Vec3A) -> Result<Vec3A, SceneError> {
        let usage = SpectrumUse::Reflectance;
        let value = match p.colour(name, usage)? {
            None => default,
            Some(ColourParam::Value(c)) => {
                let e = p.take(name).expect("a value was read");
                if e.tag == "rgb" && c.max_element() > 1.0 {
                    return Err(e.origin.error(format!(
                        "`{name}` of {} is {c}: Mitsuba reads an <rgb> here as a reflectance, in [0, 1]; give the coefficients' size in `scale`, or use a `constvolume`",
                        p.what()
                    )));
                }
                c
            }
            Some(ColourParam::Texture(v)) if v.element.tag == "volume" => {
                if v.kind != "constvolume" {
                    return Err(v.error(format!(
                        "the volume `{}` is not supported: a homogeneous medium takes constant values (`constvolume`)",
                        v.kind
                    )));
                }
                let (c, texture) = self.colour(&v, "value", Vec3A::ONE, usage)?;
                // Placement in space changes nothing for a constant.
                v.transform("to_world")?;
                v.finish()?;
                constant(&v, texture, c)?
            }
            Some(ColourParam::Texture(t)) => {
                let texture = self.texture(&t)?;
                constant(&t, Some(texture), Vec3A::ZERO)?
            }
        };
        if !value.is_finite() || value.min_element() < 0.0 {
            let at = p.take(name).map_or(p.origin(), |e| &e.origin);
            return Err(at.error(format!("`{name}` of {} is {value}; it must be ≥ 0", p.what())));
        }
        Ok(value)
    }
}

/// The value of a texture that is constant (else an error at `p`).
fn constant(p: &Plugin, texture: Option<Texture>, value: Vec3A) -> Result<Vec3A, SceneError> {
    match texture {
        None => Ok(value),
        Some(Texture::Constant(c)) => Ok(c),
        Some(_) => Err(p.error("a medium's coefficients must be constant (a homogeneous medium)")),
    }
}

/// A `<phase>`: `isotropic`, or `hg` with `g` in (−1, 1).
fn phase(p: &Plugin) -> Result<PhaseFunction, SceneError> {
    let phase = match p.kind {
        "isotropic" => PhaseFunction::Isotropic,
        "hg" => PhaseFunction::HenyeyGreenstein {
            g: p.float_checked("g", 0.8, "in (−1, 1)", |g| g > -1.0 && g < 1.0)?,
        },
        other => {
            return Err(p.error(format!(
                "the phase function `{other}` is not supported: caustic reads `isotropic` and `hg`"
            )))
        }
    };
    p.finish()?;
    Ok(phase)
}
