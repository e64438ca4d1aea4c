//! `<texture>`: `bitmap` and `checkerboard`, with `to_uv`.

use super::props::{ColourParam, Plugin};
use super::spectrum::SpectrumUse;
use super::xml::resolve;
use super::Builder;
use crate::io::image::load_image;
use crate::math::Vec3A;
use crate::scene::load::SceneError;
use crate::texture::{
    Channel, Checkerboard, ColourSpace, FilterMode, Image, ImageTexture, Texture, UvTransform, WrapMode,
};
use glam::{Affine2, Mat2, Mat4, Vec2};
use std::sync::Arc;

impl Builder<'_> {
    /// A colour parameter: the constant, or the texture with its bound.
    pub(super) fn colour(
        &self,
        p: &Plugin,
        name: &str,
        default: Vec3A,
        usage: SpectrumUse,
    ) -> Result<(Vec3A, Option<Texture>), SceneError> {
        match p.colour(name, usage)? {
            None => Ok((default, None)),
            Some(ColourParam::Value(c)) => {
                if c.min_element() < 0.0 {
                    let at = p.take(name).map_or(p.origin(), |e| &e.origin);
                    return Err(at.error(format!("`{name}` of {} has a negative component", p.what())));
                }
                Ok((c, None))
            }
            Some(ColourParam::Texture(t)) => {
                let texture = self.texture(&t)?;
                Ok((texture.max_value(), Some(texture)))
            }
        }
    }

    /// A scalar parameter (a roughness): the constant or the texture.
    pub(super) fn scalar(&self, p: &Plugin, name: &str, default: f32) -> Result<(f32, Option<Texture>), SceneError> {
        match p.colour(name, SpectrumUse::Unbounded)? {
            None => Ok((default, None)),
            Some(ColourParam::Value(c)) => {
                if c.x != c.y || c.y != c.z {
                    let at = p.take(name).map_or(p.origin(), |e| &e.origin);
                    return Err(at.error(format!("`{name}` of {} is a number, not a colour", p.what())));
                }
                Ok((c.x, None))
            }
            Some(ColourParam::Texture(t)) => {
                let texture = match self.texture(&t)? {
                    // Mitsuba 3's checkerboard gives `color1` where its
                    // colour lookup gives `color0` when a scalar is read
                    // (`eval_1`), and the other way round: read as Mitsuba
                    // reads it.
                    Texture::Checkerboard(c) => Texture::Checkerboard(crate::texture::Checkerboard {
                        colour0: c.colour1,
                        colour1: c.colour0,
                        ..c
                    }),
                    texture => texture,
                };
                Ok((texture.max_value().x, Some(texture)))
            }
        }
    }

    /// A `<texture>` plugin.
    pub(super) fn texture(&self, p: &Plugin) -> Result<Texture, SceneError> {
        if p.element.tag != "texture" {
            return Err(p.error("expected a <texture> here"));
        }
        let transform = match p.transform("to_uv")? {
            None => UvTransform::default(),
            Some(m) => uv_transform(&m),
        };
        let texture = match p.kind {
            "bitmap" => {
                let file = p.string("filename")?.ok_or_else(|| p.error("`filename` is required"))?;
                if p.has("data") {
                    return Err(p.error("`data` (an in-memory image) cannot come from a file"));
                }
                let raw = p.boolean("raw")?.unwrap_or(false);
                let filter = match p.choice("filter_type", "bilinear", &["bilinear", "nearest"])? {
                    "nearest" => FilterMode::Nearest,
                    _ => FilterMode::Bilinear,
                };
                let wrap = match p.choice("wrap_mode", "repeat", &["repeat", "mirror", "clamp"])? {
                    "mirror" => WrapMode::Mirror,
                    "clamp" => WrapMode::Clamp,
                    _ => WrapMode::Repeat,
                };
                let space = if raw { ColourSpace::Linear } else { ColourSpace::Srgb };
                let image = self.image(p, file, space)?;
                Texture::Image(ImageTexture {
                    image,
                    transform,
                    wrap: [wrap; 2],
                    filter,
                    factor: Vec3A::ONE,
                    alpha_factor: 1.0,
                    channel: Channel::Luminance,
                })
            }
            "checkerboard" => {
                let colour = |name: &str, default: f32| -> Result<Vec3A, SceneError> {
                    match p.colour(name, SpectrumUse::Reflectance)? {
                        None => Ok(Vec3A::splat(default)),
                        Some(ColourParam::Value(c)) => Ok(c),
                        Some(ColourParam::Texture(_)) => {
                            Err(p.error(format!("`{name}` of a checkerboard must be a colour, not a texture")))
                        }
                    }
                };
                Texture::Checkerboard(Checkerboard {
                    colour0: colour("color0", 0.4)?,
                    colour1: colour("color1", 0.2)?,
                    transform,
                })
            }
            "rawconstant" => {
                // A value used as it is, never converted as a colour.
                let value = match p.take("value").map(|e| e.tag.as_str()) {
                    Some("point" | "vector") => Vec3A::from(p.vector("value")?.expect("present")),
                    Some(_) => Vec3A::splat(p.float("value")?.expect("present")),
                    None => Vec3A::ONE,
                };
                if p.has("to_uv") {
                    p.transform("to_uv")?;
                }
                Texture::Constant(value)
            }
            other => {
                return Err(p.error(format!(
                    "the texture `{other}` is not supported: caustic reads `bitmap`, `checkerboard` and `rawconstant`"
                )))
            }
        };
        p.finish()?;
        Ok(texture)
    }

    /// An image file named by `p`, decoded once per (file, colour space).
    pub(super) fn image(&self, p: &Plugin, file: &str, space: ColourSpace) -> Result<Arc<Image>, SceneError> {
        let at = p.take("filename").unwrap_or(p.element);
        let path = resolve(file, at.dir(), &self.doc.search_path);
        let key = (std::fs::canonicalize(&path).unwrap_or(path.clone()), space);
        if let Some(image) = self.images.borrow().get(&key) {
            return Ok(image.clone());
        }
        let image =
            Arc::new(load_image(&path, space).map_err(|e| at.origin.error(format!("image `{file}`: {}", e.message)))?);
        self.images.borrow_mut().insert(key, image.clone());
        Ok(image)
    }
}

/// Mitsuba's `to_uv`: the 4×4 matrix without its z row and column.
fn uv_transform(m: &Mat4) -> UvTransform {
    UvTransform(Affine2 {
        matrix2: Mat2::from_cols(Vec2::new(m.x_axis.x, m.x_axis.y), Vec2::new(m.y_axis.x, m.y_axis.y)),
        translation: Vec2::new(m.w_axis.x, m.w_axis.y),
    })
}
