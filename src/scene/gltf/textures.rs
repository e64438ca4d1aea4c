//! Textures (glTF 2.0 §3.8): images decoded within the texture limits
//! (from a buffer view, a data URI or a file beside the model), samplers'
//! wrap modes and magnification filter, and `KHR_texture_transform`.

use super::document::{resolve_uri, UriTarget};
use super::Ctx;
use crate::math::Vec2;
use crate::scene::load::SceneError;
use crate::texture::{Channel, ColourSpace, FilterMode, Image, ImageTexture, UvTransform, WrapMode};
use std::sync::Arc;

/// A texture reference as a material names it (a `textureInfo`, typed or
/// read from an extension's JSON).
pub(super) struct TextureRef {
    /// Index into `textures`.
    pub index: usize,
    /// The texture coordinate set (`texCoord`, or the transform's).
    pub tex_coord: u32,
    /// `KHR_texture_transform`: offset, rotation (radians), scale.
    pub transform: Option<([f32; 2], f32, [f32; 2])>,
    /// JSON pointer of the reference, for messages.
    pub pointer: String,
}

impl TextureRef {
    /// The reference of a typed `textureInfo`.
    pub fn of_info(info: &gltf::texture::Info, pointer: String) -> Self {
        let t = info.texture_transform();
        Self {
            index: info.texture().index(),
            tex_coord: t.as_ref().and_then(|t| t.tex_coord()).unwrap_or(info.tex_coord()),
            transform: t.map(|t| (t.offset(), t.rotation(), t.scale())),
            pointer,
        }
    }

    /// The reference in raw JSON (an extension's `textureInfo`, or a normal
    /// texture's, whose transform gltf reads only as JSON).
    pub fn of_json(ctx: &Ctx, value: &serde_json::Value, pointer: String) -> Result<Self, SceneError> {
        let index = value.get("index").and_then(serde_json::Value::as_u64).ok_or_else(|| {
            ctx.error(
                format!("{pointer}/index"),
                "a texture reference needs an integer `index`",
            )
        })?;
        if index >= ctx.doc.textures().len() as u64 {
            return Err(ctx.error(
                format!("{pointer}/index"),
                format!("texture {index} out of range ({} textures)", ctx.doc.textures().len()),
            ));
        }
        let tex_coord = value.get("texCoord").and_then(serde_json::Value::as_u64).unwrap_or(0);
        let mut r = Self {
            index: index as usize,
            tex_coord: tex_coord.min(u64::from(u32::MAX)) as u32,
            transform: None,
            pointer: pointer.clone(),
        };
        if let Some(t) = value.get("extensions").and_then(|e| e.get("KHR_texture_transform")) {
            let pair = |key: &str, default: [f32; 2]| -> Result<[f32; 2], SceneError> {
                match t.get(key) {
                    None => Ok(default),
                    Some(v) => {
                        let a = v.as_array().filter(|a| a.len() == 2);
                        let x = a.and_then(|a| Some([a[0].as_f64()? as f32, a[1].as_f64()? as f32]));
                        x.ok_or_else(|| {
                            ctx.error(
                                format!("{pointer}/extensions/KHR_texture_transform/{key}"),
                                "expected two numbers",
                            )
                        })
                    }
                }
            };
            let rotation = t.get("rotation").and_then(serde_json::Value::as_f64).unwrap_or(0.0) as f32;
            if let Some(tc) = t.get("texCoord").and_then(serde_json::Value::as_u64) {
                r.tex_coord = tc.min(u64::from(u32::MAX)) as u32;
            }
            r.transform = Some((pair("offset", [0.0, 0.0])?, rotation, pair("scale", [1.0, 1.0])?));
        }
        Ok(r)
    }
}

/// The UV map of `KHR_texture_transform`: `uv' = T · R · S · uv`, whose
/// rotation matrix turns `(1, 0)` into `(cos r, −sin r)` (the extension's
/// `rotation` turns the UVs counter-clockwise as seen with `v` down the
/// image, i.e. by `−r` in the `(u, v)` plane).
pub(super) fn uv_transform(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> UvTransform {
    UvTransform::new(Vec2::from_array(scale), -rotation, Vec2::from_array(offset))
}

impl Ctx<'_> {
    /// The image texture `r` names, its texels decoded in `space`, read as
    /// `channel` by scalar lookups.
    pub(super) fn texture(
        &mut self,
        r: &TextureRef,
        space: ColourSpace,
        channel: Channel,
    ) -> Result<ImageTexture, SceneError> {
        if r.tex_coord != 0 {
            self.warn(
                &r.pointer,
                format!(
                    "uses TEXCOORD_{}; caustic reads TEXCOORD_0 for every texture",
                    r.tex_coord
                ),
            );
        }
        let doc = self.doc;
        let texture = doc
            .textures()
            .nth(r.index)
            .ok_or_else(|| self.error(&r.pointer, format!("texture {} out of range", r.index)))?;
        let image = self.image(texture.source().index(), space)?;
        let sampler = texture.sampler();
        let wrap = |m: gltf::texture::WrappingMode| match m {
            gltf::texture::WrappingMode::ClampToEdge => WrapMode::Clamp,
            gltf::texture::WrappingMode::MirroredRepeat => WrapMode::Mirror,
            gltf::texture::WrappingMode::Repeat => WrapMode::Repeat,
        };
        let mut t = ImageTexture::new(image);
        t.wrap = [wrap(sampler.wrap_s()), wrap(sampler.wrap_t())];
        // Path tracing samples the pixel footprint with many rays: the
        // magnification filter decides nearest or bilinear; minification
        // (mipmaps) has no counterpart.
        t.filter = match sampler.mag_filter() {
            Some(gltf::texture::MagFilter::Nearest) => FilterMode::Nearest,
            _ => FilterMode::Bilinear,
        };
        t.channel = channel;
        if let Some((offset, rotation, scale)) = r.transform {
            t.transform = uv_transform(offset, rotation, scale);
        }
        Ok(t)
    }

    /// Image `index` decoded in `space` (once per space).
    fn image(&mut self, index: usize, space: ColourSpace) -> Result<Arc<Image>, SceneError> {
        if let Some(i) = self.images.get(&(index, space)) {
            return Ok(i.clone());
        }
        let doc = self.doc;
        let image = doc.images().nth(index).expect("validated image index");
        let pointer = format!("/images/{index}");
        let name = image.name().map_or_else(|| format!("image {index}"), str::to_string);
        let decoded = match image.source() {
            gltf::image::Source::View { view, .. } => {
                let buffer = &self.buffers[view.buffer().index()];
                let bytes = view
                    .offset()
                    .checked_add(view.length())
                    .and_then(|end| buffer.get(view.offset()..end))
                    .ok_or_else(|| {
                        self.error(
                            format!("/bufferViews/{}", view.index()),
                            format!("the view lies outside buffer {}", view.buffer().index()),
                        )
                    })?;
                crate::io::image::decode_image(&name, bytes, space)
            }
            gltf::image::Source::Uri { uri, .. } => {
                let at = format!("{pointer}/uri");
                match resolve_uri(self.path, &self.dir, uri, &at, self.options)? {
                    UriTarget::Data(bytes) => crate::io::image::decode_image(&name, &bytes, space),
                    UriTarget::File(file) => crate::io::image::load_image(&file, space),
                }
            }
        }
        .map_err(|e| self.error(&pointer, e.to_string()))?;
        let decoded = Arc::new(decoded);
        self.images.insert((index, space), decoded.clone());
        Ok(decoded)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texture_transform_follows_the_extension_example() {
        // The extension's example: offset (0, 1), rotation π/2, scale ½
        // reads the lower-left quadrant of the image.
        let t = uv_transform([0.0, 1.0], std::f32::consts::FRAC_PI_2, [0.5, 0.5]);
        for (uv, expected) in [
            ((0.0, 0.0), (0.0, 1.0)),
            ((1.0, 0.0), (0.0, 0.5)),
            ((0.0, 1.0), (0.5, 1.0)),
            ((1.0, 1.0), (0.5, 0.5)),
        ] {
            let p = t.apply(Vec2::new(uv.0, uv.1));
            assert!((p - Vec2::new(expected.0, expected.1)).length() < 1e-6, "{uv:?} → {p}");
        }
    }
}
