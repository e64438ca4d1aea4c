//! The `[media]` table (homogeneous participating media), the objects'
//! `interior` / `exterior` and the camera's `medium`: the same model as
//! Mitsuba's `<medium type="homogeneous">`, rendered by `integrator =
//! "volpath"`.

use super::ctx::Ctx;
use super::error::SceneError;
use crate::math::Vec3A;
use crate::scene::desc::{MediaDesc, PhaseDesc, ScaleDesc, SceneDesc, Spanned};
use crate::scene::{HomogeneousMedium, Media, MediumInterface, PassThrough, PhaseFunction};
use std::collections::BTreeMap;
use std::ops::Range;

/// Default extinction coefficient of a medium (Mitsuba's).
pub const DEFAULT_SIGMA_T: f32 = 1.0;
/// Default single-scattering albedo of a medium (Mitsuba's).
pub const DEFAULT_ALBEDO: f32 = 0.75;

impl Ctx<'_> {
    /// The scene's [`Media`]: `[media]`, the objects' interfaces and the
    /// camera's medium, and how null surfaces are crossed (`volpath`).
    pub(super) fn scene_media(&self, desc: &SceneDesc, volpath: bool) -> Result<Media, SceneError> {
        let mut list = Vec::with_capacity(desc.media.len());
        let mut index = BTreeMap::new();
        for (name, m) in &desc.media {
            if !volpath {
                return Err(self.needs_volpath(m.span(), &format!("`[media.{name}]`")));
            }
            index.insert(name.as_str(), list.len() as u32);
            list.push(self.homogeneous(name, m.get_ref())?);
        }
        let lookup = |s: &Option<Spanned<String>>, key: &str| -> Result<Option<u32>, SceneError> {
            let Some(s) = s else { return Ok(None) };
            if !volpath {
                return Err(self.needs_volpath(s.span(), &format!("`{key}`")));
            }
            index.get(s.get_ref().as_str()).copied().map(Some).ok_or_else(|| {
                let known: Vec<&str> = index.keys().copied().collect();
                self.invalid(
                    s.span(),
                    format!(
                        "`{key}` names `{}`, which is not in `[media]` (the media are: {})",
                        s.get_ref(),
                        if known.is_empty() {
                            "none".to_string()
                        } else {
                            known.join(", ")
                        }
                    ),
                )
            })
        };
        let mut interfaces = Vec::with_capacity(desc.objects.len());
        for o in &desc.objects {
            interfaces.push(MediumInterface {
                interior: lookup(&o.interior, "interior")?,
                exterior: lookup(&o.exterior, "exterior")?,
            });
        }
        let camera = lookup(&desc.camera.get_ref().medium, "medium")?;
        if volpath {
            if let Some(m) = &desc.medium {
                return Err(self.invalid(
                    m.span(),
                    "`[medium]` (the water's) is traced by `integrator = \"path\"`; with `volpath`, describe media in `[media.NAME]`",
                ));
            }
        }
        let referenced = |i: u32| {
            camera == Some(i)
                || interfaces
                    .iter()
                    .any(|f| f.interior == Some(i) || f.exterior == Some(i))
        };
        if let Some((name, m)) = desc
            .media
            .iter()
            .zip(0u32..)
            .find(|(_, i)| !referenced(*i))
            .map(|(e, _)| e)
        {
            return Err(self.invalid(
                m.span(),
                format!("`[media.{name}]` is not used: name it in an object's `interior` / `exterior` or the camera's `medium`"),
            ));
        }
        Ok(Media {
            interfaces: if list.is_empty() { Vec::new() } else { interfaces },
            list,
            camera,
            pass_through: if volpath {
                PassThrough::Volumetric
            } else {
                PassThrough::SurfaceBounce
            },
        })
    }

    fn needs_volpath(&self, span: Range<usize>, what: &str) -> SceneError {
        self.invalid(
            span,
            format!("{what}: participating media are rendered by `integrator = \"volpath\"` (set it in `[render]`)"),
        )
    }

    /// One `[media.NAME]`.
    fn homogeneous(&self, name: &str, m: &MediaDesc) -> Result<HomogeneousMedium, SceneError> {
        let sigma_t = self.coefficients(&m.sigma_t, "sigma_t", DEFAULT_SIGMA_T, f32::INFINITY)?;
        let albedo = self.coefficients(&m.albedo, "albedo", DEFAULT_ALBEDO, 1.0)?;
        let scale = match &m.scale {
            None => 1.0,
            Some(s) => {
                let x = self.number(s, "scale")?;
                if x < 0.0 {
                    return Err(self.invalid(s.span(), format!("`scale` = {x} must be ≥ 0")));
                }
                x
            }
        };
        let sigma_t = sigma_t * scale;
        if !sigma_t.is_finite() {
            let span = m.scale.as_ref().map_or(0..0, |s| s.span());
            return Err(self.invalid(span, "`sigma_t` × `scale` overflows single precision"));
        }
        let phase = match &m.phase {
            None => PhaseFunction::Isotropic,
            Some(p) => match p.get_ref() {
                PhaseDesc::Name(n) if n == "isotropic" => PhaseFunction::Isotropic,
                PhaseDesc::Name(n) => {
                    return Err(self.invalid(
                        p.span(),
                        format!("unknown `phase` `{n}`: expected \"isotropic\" or {{ hg = g }} with g in (−1, 1)"),
                    ))
                }
                PhaseDesc::Hg(hg) => {
                    let g = self.check_finite(hg.hg, p.span(), "hg")?;
                    if !(g > -1.0 && g < 1.0) {
                        return Err(self.invalid(p.span(), format!("`hg` = {g} must be in (−1, 1)")));
                    }
                    PhaseFunction::HenyeyGreenstein { g }
                }
            },
        };
        Ok(HomogeneousMedium {
            name: name.to_string(),
            sigma_t,
            albedo,
            phase,
            sample_emitters: m.sample_emitters.as_ref().is_none_or(|s| *s.get_ref()),
        })
    }

    /// A number or `[r, g, b]`, each in `[0, max]`.
    fn coefficients(
        &self,
        s: &Option<Spanned<ScaleDesc>>,
        key: &str,
        default: f32,
        max: f32,
    ) -> Result<Vec3A, SceneError> {
        let Some(s) = s else { return Ok(Vec3A::splat(default)) };
        let c = |x: f64| self.check_finite(x, s.span(), key);
        let v = match *s.get_ref() {
            ScaleDesc::Uniform(x) => Vec3A::splat(c(x)?),
            ScaleDesc::PerAxis([r, g, b]) => Vec3A::new(c(r)?, c(g)?, c(b)?),
        };
        if v.min_element() < 0.0 || v.max_element() > max {
            let range = if max.is_finite() {
                format!("in [0, {max}]")
            } else {
                "≥ 0".to_string()
            };
            return Err(self.invalid(s.span(), format!("`{key}` = {v} must be {range} in every channel")));
        }
        Ok(v)
    }
}
