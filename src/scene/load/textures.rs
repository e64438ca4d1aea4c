//! The `[textures]` table and texture-valued material parameters: a
//! parameter is a number, a colour, the name of a `[textures]` entry or an
//! inline texture table. Images are resolved relative to the scene file and
//! decoded once per (file, colour space).

use super::ctx::Ctx;
use super::error::SceneError;
use crate::io::image::load_image;
use crate::math::{Vec2, Vec3A};
use crate::scene::desc::{ParamDesc, Scale2Desc, ScaleDesc, Spanned, TextureDesc, TextureKind, WrapDesc};
use crate::texture::{Channel, Checkerboard, ColourSpace, FilterMode, ImageTexture, Texture, UvTransform, WrapMode};
use std::ops::Range;

/// What a texture feeds, which sets its default colour space and channel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Usage {
    /// A colour (sRGB images by default).
    Colour,
    /// A scalar such as a roughness (linear, luminance).
    Scalar,
    /// A normal map (linear).
    Normal,
    /// An alpha mask (linear, the alpha channel).
    Alpha,
}

impl Ctx<'_> {
    /// A colour parameter: the constant (or, when textured, the texture's
    /// upper bound) and the texture. `max` bounds a constant (reflectances: 1).
    pub(super) fn colour_param(
        &self,
        p: &Option<Spanned<ParamDesc>>,
        key: &str,
        default: Vec3A,
        max: Option<f32>,
    ) -> Result<(Vec3A, Option<Texture>), SceneError> {
        let Some(p) = p else { return Ok((default, None)) };
        let c = match p.get_ref() {
            ParamDesc::Number(x) => Vec3A::splat(self.check_finite(*x, p.span(), key)?),
            ParamDesc::Colour(c) => {
                let f = |v| self.check_finite(v, p.span(), key);
                Vec3A::new(f(c[0])?, f(c[1])?, f(c[2])?)
            }
            _ => {
                let t = self.texture_param(p, key, Usage::Colour)?;
                return Ok((t.max_value(), Some(t)));
            }
        };
        if c.min_element() < 0.0 {
            return Err(self.invalid(p.span(), format!("`{key}` has a negative component: colours are ≥ 0")));
        }
        if let Some(max) = max.filter(|&m| c.max_element() > m) {
            return Err(self.invalid(
                p.span(),
                format!("`{key}` has a component above {max}: reflectances are in [0, {max}]"),
            ));
        }
        Ok((c, None))
    }

    /// A scalar parameter in `range`: the constant (or the texture's upper
    /// bound) and the texture.
    pub(super) fn scalar_param(
        &self,
        p: &Option<Spanned<ParamDesc>>,
        key: &str,
        default: f32,
        valid: (&str, fn(f32) -> bool),
    ) -> Result<(f32, Option<Texture>), SceneError> {
        let Some(p) = p else { return Ok((default, None)) };
        match p.get_ref() {
            ParamDesc::Number(x) => {
                let x = self.check_finite(*x, p.span(), key)?;
                if !(valid.1)(x) {
                    return Err(self.invalid(p.span(), format!("`{key}` = {x} must be {}", valid.0)));
                }
                Ok((x, None))
            }
            ParamDesc::Colour(_) => {
                Err(self.invalid(p.span(), format!("`{key}` is a number or a texture, not a colour")))
            }
            _ => {
                let t = self.texture_param(p, key, Usage::Scalar)?;
                Ok((t.max_value().x, Some(t)))
            }
        }
    }

    /// A parameter that must be a texture (a normal map, an alpha mask).
    pub(super) fn texture_param(&self, p: &Spanned<ParamDesc>, key: &str, usage: Usage) -> Result<Texture, SceneError> {
        match p.get_ref() {
            ParamDesc::Texture(name) => {
                let Some(desc) = self.textures.get(name) else {
                    let known: Vec<&str> = self.textures.keys().map(String::as_str).collect();
                    return Err(self.invalid(
                        p.span(),
                        format!(
                            "`{key}` names the texture `{name}`, which `[textures]` does not define{}",
                            if known.is_empty() {
                                String::new()
                            } else {
                                format!(" (it has: {})", known.join(", "))
                            }
                        ),
                    ));
                };
                self.texture(desc.get_ref(), desc.span(), usage)
            }
            ParamDesc::Inline(desc) => self.texture(desc, p.span(), usage),
            ParamDesc::Number(_) | ParamDesc::Colour(_) => Err(self.invalid(
                p.span(),
                format!("`{key}` must be a texture (a `[textures]` name or a table), not a constant"),
            )),
        }
    }

    fn texture(&self, d: &TextureDesc, at: Range<usize>, usage: Usage) -> Result<Texture, SceneError> {
        let span = |s: &Option<Spanned<_>>| s.as_ref().map(|s: &Spanned<_>| s.span());
        let present = [
            ("file", span(&d.file)),
            ("colour_space", d.colour_space.as_ref().map(|s| s.span())),
            ("wrap", d.wrap.as_ref().map(|s| s.span())),
            ("filter", d.filter.as_ref().map(|s| s.span())),
            ("factor", d.factor.as_ref().map(|s| s.span())),
            ("channel", d.channel.as_ref().map(|s| s.span())),
            ("colour0", d.colour0.as_ref().map(|s| s.span())),
            ("colour1", d.colour1.as_ref().map(|s| s.span())),
        ];
        let transform = self.uv_transform(d)?;
        match d.kind.get_ref() {
            TextureKind::Checkerboard => {
                self.only_keys(
                    "a checkerboard texture",
                    &present,
                    &["colour0", "colour1", "scale", "rotation", "offset"],
                )?;
                // Mitsuba's defaults.
                let colour0 = self.opt_colour(&d.colour0, "colour0", Vec3A::splat(0.4))?;
                let colour1 = self.opt_colour(&d.colour1, "colour1", Vec3A::splat(0.2))?;
                Ok(Texture::Checkerboard(Checkerboard {
                    colour0,
                    colour1,
                    transform,
                }))
            }
            TextureKind::Image => {
                self.only_keys(
                    "an image texture",
                    &present,
                    &[
                        "file",
                        "colour_space",
                        "wrap",
                        "filter",
                        "factor",
                        "channel",
                        "scale",
                        "rotation",
                        "offset",
                    ],
                )?;
                let file = self.required(&d.file, "file", "an image texture", at)?;
                let space = match &d.colour_space {
                    Some(s) => ColourSpace::from_name(s.get_ref()).ok_or_else(|| {
                        self.invalid(
                            s.span(),
                            format!("unknown colour space `{}`: expected srgb or linear", s.get_ref()),
                        )
                    })?,
                    None if usage == Usage::Colour => ColourSpace::Srgb,
                    None => ColourSpace::Linear,
                };
                let wrap = match &d.wrap {
                    None => [WrapMode::Repeat; 2],
                    Some(w) => {
                        let mode = |name: &str| {
                            WrapMode::from_name(name).ok_or_else(|| {
                                self.invalid(
                                    w.span(),
                                    format!("unknown wrap mode `{name}`: expected repeat, clamp or mirror"),
                                )
                            })
                        };
                        match w.get_ref() {
                            WrapDesc::Both(m) => [mode(m)?; 2],
                            WrapDesc::PerAxis([u, v]) => [mode(u)?, mode(v)?],
                        }
                    }
                };
                let filter = match &d.filter {
                    None => FilterMode::Bilinear,
                    Some(f) => FilterMode::from_name(f.get_ref()).ok_or_else(|| {
                        self.invalid(
                            f.span(),
                            format!("unknown filter `{}`: expected bilinear or nearest", f.get_ref()),
                        )
                    })?,
                };
                let channel = match &d.channel {
                    None if usage == Usage::Alpha => Channel::A,
                    None => Channel::Luminance,
                    Some(c) => Channel::from_name(c.get_ref()).ok_or_else(|| {
                        self.invalid(
                            c.span(),
                            format!("unknown channel `{}`: expected luminance, r, g, b or a", c.get_ref()),
                        )
                    })?,
                };
                let factor = match &d.factor {
                    None => Vec3A::ONE,
                    Some(f) => {
                        let v = match *f.get_ref() {
                            ScaleDesc::Uniform(x) => Vec3A::splat(self.check_finite(x, f.span(), "factor")?),
                            ScaleDesc::PerAxis(c) => {
                                let g = |v| self.check_finite(v, f.span(), "factor");
                                Vec3A::new(g(c[0])?, g(c[1])?, g(c[2])?)
                            }
                        };
                        if v.min_element() < 0.0 {
                            return Err(self.invalid(f.span(), "`factor` must be ≥ 0"));
                        }
                        v
                    }
                };
                let image = self.image(file, space)?;
                Ok(Texture::Image(ImageTexture {
                    image,
                    transform,
                    wrap,
                    filter,
                    factor,
                    alpha_factor: 1.0,
                    channel,
                }))
            }
        }
    }

    fn opt_colour(&self, s: &Option<Spanned<ScaleDesc>>, key: &str, default: Vec3A) -> Result<Vec3A, SceneError> {
        let Some(s) = s else { return Ok(default) };
        let c = match *s.get_ref() {
            ScaleDesc::Uniform(x) => Vec3A::splat(self.check_finite(x, s.span(), key)?),
            ScaleDesc::PerAxis([r, g, b]) => {
                let f = |v| self.check_finite(v, s.span(), key);
                Vec3A::new(f(r)?, f(g)?, f(b)?)
            }
        };
        if c.min_element() < 0.0 {
            return Err(self.invalid(s.span(), format!("`{key}` has a negative component: colours are ≥ 0")));
        }
        Ok(c)
    }

    fn uv_transform(&self, d: &TextureDesc) -> Result<UvTransform, SceneError> {
        let scale = match &d.scale {
            None => Vec2::ONE,
            Some(s) => {
                let v = match *s.get_ref() {
                    Scale2Desc::Uniform(x) => Vec2::splat(self.check_finite(x, s.span(), "scale")?),
                    Scale2Desc::PerAxis([u, v]) => Vec2::new(
                        self.check_finite(u, s.span(), "scale")?,
                        self.check_finite(v, s.span(), "scale")?,
                    ),
                };
                if v.x == 0.0 || v.y == 0.0 {
                    return Err(self.invalid(s.span(), "`scale` must not be 0 (the texture would be one texel)"));
                }
                v
            }
        };
        let rotation = match &d.rotation {
            None => 0.0,
            Some(r) => self.number(r, "rotation")?.to_radians(),
        };
        let offset = match &d.offset {
            None => Vec2::ZERO,
            Some(o) => {
                let [u, v] = o.get_ref().0;
                Vec2::new(
                    self.check_finite(u, o.span(), "offset")?,
                    self.check_finite(v, o.span(), "offset")?,
                )
            }
        };
        Ok(UvTransform::new(scale, rotation, offset))
    }

    pub(super) fn image(
        &self,
        file: &Spanned<String>,
        space: ColourSpace,
    ) -> Result<std::sync::Arc<crate::texture::Image>, SceneError> {
        let dir = self.path.parent().unwrap_or(std::path::Path::new("."));
        let path = dir.join(file.get_ref());
        let key = (std::fs::canonicalize(&path).unwrap_or(path.clone()), space);
        if let Some(image) = self.images.borrow().get(&key) {
            return Ok(image.clone());
        }
        let image = load_image(&path, space)
            .map_err(|e| self.invalid(file.span(), format!("texture `{}`: {}", file.get_ref(), e.message)))?;
        let image = std::sync::Arc::new(image);
        self.images.borrow_mut().insert(key, image.clone());
        Ok(image)
    }
}
