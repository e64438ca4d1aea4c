//! `[materials.NAME.disney]`: Burley's Disney BSDF as Mitsuba 3 writes it
//! (`principled`, or `principledthin` with `thin = true`), with Mitsuba's
//! defaults and the parameters each variant has.

use super::ctx::Ctx;
use super::error::SceneError;
use crate::scene::desc::{DisneyDesc, ParamDesc, Spanned};
use crate::scene::material::MaterialTextures;
use crate::scene::Disney;

impl Ctx<'_> {
    /// The Disney parameters of `s`, their textures put into `textures`.
    pub(super) fn disney(
        &self,
        s: &Spanned<DisneyDesc>,
        textures: &mut MaterialTextures,
    ) -> Result<Disney, SceneError> {
        let d = s.get_ref();
        let thin = d.thin.as_ref().is_some_and(|t| *t.get_ref());
        // Keys the other variant has and this one does not.
        let foreign: &[(&str, bool)] = if thin {
            &[
                ("metallic", d.metallic.is_some()),
                ("clearcoat", d.clearcoat.is_some()),
                ("clearcoat_gloss", d.clearcoat_gloss.is_some()),
                ("specular", d.specular.is_some()),
                ("clearcoat_sampling_rate", d.clearcoat_sampling_rate.is_some()),
            ]
        } else {
            &[
                ("diff_trans", d.diff_trans.is_some()),
                (
                    "specular_transmission_sampling_rate",
                    d.specular_transmission_sampling_rate.is_some(),
                ),
                (
                    "diffuse_transmission_sampling_rate",
                    d.diffuse_transmission_sampling_rate.is_some(),
                ),
            ]
        };
        if let Some((key, _)) = foreign.iter().find(|(_, present)| *present) {
            let variant = if thin { "a thin" } else { "a (not thin)" };
            return Err(self.invalid(s.span(), format!("`{key}` is not a parameter of {variant} Disney BSDF")));
        }
        let mut p = if thin {
            Disney::thin_default()
        } else {
            Disney::default()
        };
        let unit = ("in [0, 1]", (|x| (0.0..=1.0).contains(&x)) as fn(f32) -> bool);
        type Slot = fn(&mut MaterialTextures) -> &mut Option<crate::texture::Texture>;
        type Field = fn(&mut Disney) -> &mut f32;
        let weights: [(&str, &Option<Spanned<ParamDesc>>, Field, Slot); 11] = [
            (
                "roughness",
                &d.roughness,
                |p| &mut p.roughness,
                |t| &mut t.disney_roughness,
            ),
            (
                "anisotropic",
                &d.anisotropic,
                |p| &mut p.anisotropic,
                |t| &mut t.disney_anisotropic,
            ),
            ("metallic", &d.metallic, |p| &mut p.metallic, |t| &mut t.disney_metallic),
            (
                "spec_trans",
                &d.spec_trans,
                |p| &mut p.spec_trans,
                |t| &mut t.disney_spec_trans,
            ),
            (
                "spec_tint",
                &d.spec_tint,
                |p| &mut p.spec_tint,
                |t| &mut t.disney_spec_tint,
            ),
            ("sheen", &d.sheen, |p| &mut p.sheen, |t| &mut t.disney_sheen),
            (
                "sheen_tint",
                &d.sheen_tint,
                |p| &mut p.sheen_tint,
                |t| &mut t.disney_sheen_tint,
            ),
            ("flatness", &d.flatness, |p| &mut p.flatness, |t| &mut t.disney_flatness),
            (
                "clearcoat",
                &d.clearcoat,
                |p| &mut p.clearcoat,
                |t| &mut t.disney_clearcoat,
            ),
            (
                "clearcoat_gloss",
                &d.clearcoat_gloss,
                |p| &mut p.clearcoat_gloss,
                |t| &mut t.disney_clearcoat_gloss,
            ),
            (
                "diff_trans",
                &d.diff_trans,
                |p| &mut p.diff_trans,
                |t| &mut t.disney_diff_trans,
            ),
        ];
        for (key, desc, field, slot) in weights {
            let valid = if key == "diff_trans" {
                ("in [0, 2]", (|x| (0.0..=2.0).contains(&x)) as fn(f32) -> bool)
            } else {
                unit
            };
            let default = *field(&mut p);
            let (value, texture) = self.scalar_param(desc, key, default, valid)?;
            *field(&mut p) = value;
            *slot(textures) = texture;
        }
        let rate = |r: &Option<Spanned<f64>>, key: &str| -> Result<f32, SceneError> {
            let Some(r) = r else { return Ok(1.0) };
            let x = self.number(r, key)?;
            if x < 0.0 {
                return Err(self.invalid(r.span(), format!("`{key}` = {x} must be ≥ 0")));
            }
            Ok(x)
        };
        p.diffuse_sampling_rate = rate(&d.diffuse_sampling_rate, "diffuse_sampling_rate")?;
        p.specular_sampling_rate = rate(&d.specular_sampling_rate, "specular_sampling_rate")?;
        p.clearcoat_sampling_rate = rate(&d.clearcoat_sampling_rate, "clearcoat_sampling_rate")?;
        p.specular_transmission_sampling_rate = rate(
            &d.specular_transmission_sampling_rate,
            "specular_transmission_sampling_rate",
        )?;
        p.diffuse_transmission_sampling_rate = rate(
            &d.diffuse_transmission_sampling_rate,
            "diffuse_transmission_sampling_rate",
        )?;
        let positive = ("> 0", (|x| x > 0.0) as fn(f32) -> bool);
        if thin {
            let (eta, texture) = self.scalar_param(&d.eta, "eta", p.eta, positive)?;
            (p.eta, textures.disney_eta) = (eta, texture);
            return Ok(p);
        }
        // Mitsuba's `get_flag`: the refraction is on when `spec_trans` is
        // given, unless as the number 0; an index of 1 cannot refract.
        let refracts = textures.disney_spec_trans.is_some() || p.spec_trans != 0.0;
        match (&d.eta, &d.specular) {
            (Some(e), Some(_)) => {
                return Err(self.invalid(e.span(), "give `eta` or `specular`, not both (as in Mitsuba)"));
            }
            (Some(e), None) => {
                if !matches!(e.get_ref(), ParamDesc::Number(_)) {
                    return Err(self.invalid(e.span(), "`eta` is a number (only a thin Disney BSDF takes a texture)"));
                }
                let (eta, _) = self.scalar_param(&d.eta, "eta", p.eta, positive)?;
                p.eta = if refracts && eta == 1.0 { 1.001 } else { eta };
            }
            (None, Some(sp)) => {
                let mut specular = self.number(sp, "specular")?;
                if !(0.0..12.5).contains(&specular) {
                    return Err(self.invalid(
                        sp.span(),
                        format!("`specular` = {specular} must be in [0, 12.5) (12.5 is an infinite index)"),
                    ));
                }
                if refracts && specular == 0.0 {
                    specular = 1.0e-3;
                }
                p.eta = 2.0 / (1.0 - (0.08 * specular).sqrt()) - 1.0;
            }
            (None, None) => {}
        }
        Ok(p)
    }
}
