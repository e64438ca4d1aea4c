//! Texture images: PNG, JPEG, Radiance HDR and OpenEXR decoded through the
//! `image` crate into [`crate::texture::Image`], with the decoder's limits on
//! size and allocation (a decompression bomb is refused before its pixels are
//! allocated).

use crate::texture::image::Texels;
use crate::texture::{ColourSpace, Image};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Largest texture width or height.
pub const MAX_TEXTURE_SIDE: u32 = 32768;
/// Most bytes the decoder may allocate for one image (1 GiB: a 16k × 16k
/// RGBA float image).
pub const MAX_TEXTURE_ALLOC: u64 = 4 << 28;

/// A texture image could not be read.
#[derive(Debug, Error)]
#[error("{}: {message}", path.display())]
pub struct ImageError {
    /// The file.
    pub path: PathBuf,
    /// What is wrong.
    pub message: String,
}

/// Reads the image at `path`. 8-bit images keep their bytes, their RGB
/// channels decoded from `space` at lookup; 16-bit and floating-point images
/// become linear `f32` (16-bit ones decoded from `space` once here).
pub fn load_image(path: &Path, space: ColourSpace) -> Result<Image, ImageError> {
    let fail = |message: String| ImageError {
        path: path.to_owned(),
        message,
    };
    let reader = image::ImageReader::open(path)
        .map_err(|e| fail(format!("cannot open: {e}")))?
        .with_guessed_format()
        .map_err(|e| fail(format!("cannot read: {e}")))?;
    if reader.format().is_none() {
        return Err(fail(
            "not a PNG, JPEG, Radiance HDR or OpenEXR image (unknown format)".into(),
        ));
    }
    let decoded = limited(reader).decode().map_err(|e| fail(describe(e)))?;
    Ok(from_dynamic(path.display().to_string(), decoded, space))
}

/// Decodes an in-memory image (an embedded glTF image, a data URI).
pub fn decode_image(name: &str, bytes: &[u8], space: ColourSpace) -> Result<Image, ImageError> {
    let fail = |message: String| ImageError {
        path: PathBuf::from(name),
        message,
    };
    let reader = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| fail(format!("cannot read: {e}")))?;
    if reader.format().is_none() {
        return Err(fail("not a PNG, JPEG, Radiance HDR or OpenEXR image".into()));
    }
    let decoded = limited(reader).decode().map_err(|e| fail(describe(e)))?;
    Ok(from_dynamic(name.to_string(), decoded, space))
}

/// `reader` with the texture limits: a larger image is refused from its header.
fn limited<R: std::io::BufRead + std::io::Seek>(mut reader: image::ImageReader<R>) -> image::ImageReader<R> {
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_TEXTURE_SIDE);
    limits.max_image_height = Some(MAX_TEXTURE_SIDE);
    limits.max_alloc = Some(MAX_TEXTURE_ALLOC);
    reader.limits(limits);
    reader
}

fn describe(e: image::ImageError) -> String {
    match e {
        image::ImageError::Limits(l) => format!(
            "refused: {l} (textures are at most {MAX_TEXTURE_SIDE}×{MAX_TEXTURE_SIDE} texels and {} MiB decoded)",
            MAX_TEXTURE_ALLOC >> 20
        ),
        image::ImageError::Unsupported(u) => format!("unsupported image: {u}"),
        other => format!("cannot decode: {other}"),
    }
}

fn from_dynamic(name: String, img: image::DynamicImage, space: ColourSpace) -> Image {
    use image::DynamicImage as D;
    let (width, height) = (img.width(), img.height());
    let texels = match img {
        D::ImageLuma8(_) | D::ImageLumaA8(_) | D::ImageRgb8(_) | D::ImageRgba8(_) => Texels::Rgba8 {
            data: img.into_rgba8().pixels().map(|p| p.0).collect(),
            space,
        },
        D::ImageLuma16(_) | D::ImageLumaA16(_) | D::ImageRgb16(_) | D::ImageRgba16(_) => {
            let decode = |v: u16| {
                let c = f32::from(v) / 65535.0;
                match space {
                    ColourSpace::Srgb => crate::texture::image::srgb_to_linear(c),
                    ColourSpace::Linear => c,
                }
            };
            Texels::RgbaF32(
                img.into_rgba16()
                    .pixels()
                    .map(|p| {
                        [
                            decode(p.0[0]),
                            decode(p.0[1]),
                            decode(p.0[2]),
                            f32::from(p.0[3]) / 65535.0,
                        ]
                    })
                    .collect(),
            )
        }
        // Floating-point images (HDR, EXR) are linear already.
        other => Texels::RgbaF32(other.into_rgba32f().pixels().map(|p| p.0).collect()),
    };
    Image::new(name, width, height, texels)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_round_trip_and_errors() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.png");
        let img = image::RgbaImage::from_fn(3, 2, |x, y| image::Rgba([(x * 100) as u8, (y * 200) as u8, 7, 255]));
        img.save(&path).unwrap();
        let t = load_image(&path, ColourSpace::Linear).unwrap();
        assert_eq!((t.width, t.height), (3, 2));
        assert!((t.texel(2, 1).x - 200.0 / 255.0).abs() < 1e-6);
        assert!((t.texel(2, 1).y - 200.0 / 255.0).abs() < 1e-6);

        let missing = load_image(&dir.path().join("none.png"), ColourSpace::Srgb).unwrap_err();
        assert!(missing.to_string().contains("none.png: cannot open"), "{missing}");
        let junk = dir.path().join("junk.png");
        std::fs::write(&junk, b"not an image at all").unwrap();
        let e = load_image(&junk, ColourSpace::Srgb).unwrap_err();
        assert!(e.to_string().contains("junk.png"), "{e}");
        // A truncated PNG.
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&junk, &bytes[..bytes.len() / 2]).unwrap();
        assert!(load_image(&junk, ColourSpace::Srgb).is_err());
    }

    #[test]
    fn a_huge_header_is_refused_before_allocating() {
        // A valid PNG header announcing 100000 × 100000 pixels, no data.
        let mut png = Vec::new();
        png.extend_from_slice(b"\x89PNG\r\n\x1a\n");
        let mut ihdr = Vec::new();
        ihdr.extend_from_slice(&100_000u32.to_be_bytes());
        ihdr.extend_from_slice(&100_000u32.to_be_bytes());
        ihdr.extend_from_slice(&[8, 6, 0, 0, 0]);
        png.extend_from_slice(&(ihdr.len() as u32).to_be_bytes());
        let mut chunk = b"IHDR".to_vec();
        chunk.extend_from_slice(&ihdr);
        png.extend_from_slice(&chunk);
        png.extend_from_slice(&crc32(&chunk).to_be_bytes());
        let e = decode_image("bomb.png", &png, ColourSpace::Srgb).unwrap_err();
        assert!(e.to_string().contains("refused"), "{e}");
    }

    fn crc32(data: &[u8]) -> u32 {
        let mut c = 0xffff_ffffu32;
        for &b in data {
            c ^= u32::from(b);
            for _ in 0..8 {
                c = if c & 1 != 0 { 0xedb8_8320 ^ (c >> 1) } else { c >> 1 };
            }
        }
        !c
    }

    #[test]
    fn hdr_and_exr_stay_linear() {
        let dir = tempfile::tempdir().unwrap();
        let img = image::Rgb32FImage::from_fn(2, 1, |x, _| image::Rgb([4.0 + x as f32, 0.5, 0.25]));
        for ext in ["hdr", "exr"] {
            let path = dir.path().join(format!("t.{ext}"));
            image::DynamicImage::ImageRgb32F(img.clone()).save(&path).unwrap();
            let t = load_image(&path, ColourSpace::Srgb).unwrap();
            let c = t.texel(1, 0);
            assert!((c.x - 5.0).abs() < 0.05 && (c.y - 0.5).abs() < 0.01, "{ext}: {c}");
            assert!((t.max.x - 5.0).abs() < 0.05);
        }
    }
}
