//! Textures' encoding: by what they compute, an image by its texels'
//! content (`Image::hash`: SHA-256 of the decoded texels, their size and
//! colour space), never by its path or name.

use super::encoder::{Encoder, Fingerprint};
use crate::texture::{Channel, Checkerboard, FilterMode, Image, ImageTexture, Texture, UvTransform, WrapMode};

impl Fingerprint for Texture {
    fn encode(&self, e: &mut Encoder) {
        e.tag("texture");
        match self {
            Texture::Constant(c) => {
                e.u8(0);
                e.put(c);
            }
            Texture::Image(i) => {
                e.u8(1);
                e.put(i);
            }
            Texture::Checkerboard(c) => {
                e.u8(2);
                e.put(c);
            }
        }
    }
}

impl Fingerprint for Image {
    fn encode(&self, e: &mut Encoder) {
        // The hash covers width, height, colour space and every texel; the
        // rest follows from them (`max`) or names the file (`name`).
        let Image {
            name: _,
            width: _,
            height: _,
            texels: _,
            max: _,
            hash,
        } = self;
        e.tag("image");
        e.bytes(hash);
    }
}

impl Fingerprint for UvTransform {
    fn encode(&self, e: &mut Encoder) {
        e.floats(&self.0.to_cols_array());
    }
}

impl Fingerprint for ImageTexture {
    fn encode(&self, e: &mut Encoder) {
        let ImageTexture {
            image,
            transform,
            wrap,
            filter,
            factor,
            alpha_factor,
            channel,
        } = self;
        e.put(image.as_ref());
        e.put(transform);
        for w in wrap {
            e.u8(match w {
                WrapMode::Repeat => 0,
                WrapMode::Clamp => 1,
                WrapMode::Mirror => 2,
            });
        }
        e.u8(match filter {
            FilterMode::Bilinear => 0,
            FilterMode::Nearest => 1,
        });
        e.put(factor);
        e.f32(*alpha_factor);
        e.u8(match channel {
            Channel::Luminance => 0,
            Channel::R => 1,
            Channel::G => 2,
            Channel::B => 3,
            Channel::A => 4,
        });
    }
}

impl Fingerprint for Checkerboard {
    fn encode(&self, e: &mut Encoder) {
        let Checkerboard {
            colour0,
            colour1,
            transform,
        } = self;
        e.put(colour0);
        e.put(colour1);
        e.put(transform);
    }
}
