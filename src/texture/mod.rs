//! Textures: material parameters that vary over a surface, looked up at the
//! shading point's `(u, v)`.
//!
//! A [`Texture`] is a constant, an [`image`] (bilinear or nearest lookups,
//! repeat / clamp / mirror wrapping, an affine UV transform, a factor), or a
//! checkerboard. Colours come out linear; images decoded from sRGB are
//! linearised texel by texel *before* filtering, as the sRGB transfer curve is
//! not linear (pbrt-v4 §10.4.2). The UV convention is glTF's and Mitsuba's:
//! `v = 0` is the image's first (top) row; loaders of formats with the
//! opposite convention (OBJ) flip `v`.

pub mod image;

pub use image::{ColourSpace, FilterMode, Image, ImageTexture, WrapMode};

use crate::math::{Affine2, Vec2, Vec3A};
use std::sync::Arc;

/// An affine map applied to a surface's `(u, v)` before a lookup
/// (Mitsuba's `to_uv`, glTF's `KHR_texture_transform`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform(pub Affine2);

impl Default for UvTransform {
    fn default() -> Self {
        Self(Affine2::IDENTITY)
    }
}

impl UvTransform {
    /// `uv' = offset + R(rotation) · (scale ⊙ uv)`, with `rotation` in
    /// radians, counter-clockwise.
    pub fn new(scale: Vec2, rotation: f32, offset: Vec2) -> Self {
        Self(Affine2::from_scale_angle_translation(scale, rotation, offset))
    }

    /// Applies the map.
    #[inline]
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        self.0.transform_point2(uv)
    }

    /// True for the identity.
    pub fn is_identity(&self) -> bool {
        self.0 == Affine2::IDENTITY
    }
}

/// Which value of a texel a scalar parameter (roughness, a weight, an alpha
/// mask) reads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Channel {
    /// Rec. 709 luminance of the colour (Mitsuba's scalar view of an RGB bitmap).
    #[default]
    Luminance,
    /// Red.
    R,
    /// Green.
    G,
    /// Blue.
    B,
    /// Alpha (1 where the image has none).
    A,
}

impl Channel {
    /// Name as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Channel::Luminance => "luminance",
            Channel::R => "r",
            Channel::G => "g",
            Channel::B => "b",
            Channel::A => "a",
        }
    }

    /// The channel named `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        [Channel::Luminance, Channel::R, Channel::G, Channel::B, Channel::A]
            .into_iter()
            .find(|c| c.name() == name)
    }
}

/// Rec. 709 / sRGB luminance weights.
pub fn luminance(c: Vec3A) -> f32 {
    c.dot(Vec3A::new(0.2126, 0.7152, 0.0722))
}

/// Two colours alternating on the unit squares of `(u, v)`, after a
/// transform (Mitsuba's `checkerboard`): `colour0` where the fractional
/// parts of `u` and `v` are on the same side of ½, else `colour1`.
#[derive(Clone, Debug, PartialEq)]
pub struct Checkerboard {
    /// Colour of the squares at `(0, 0)`.
    pub colour0: Vec3A,
    /// Colour of the other squares.
    pub colour1: Vec3A,
    /// UV transform.
    pub transform: UvTransform,
}

impl Checkerboard {
    /// The colour at `uv`.
    pub fn eval(&self, uv: Vec2) -> Vec3A {
        let uv = self.transform.apply(uv);
        let f = uv - uv.floor();
        if (f.x > 0.5) == (f.y > 0.5) {
            self.colour0
        } else {
            self.colour1
        }
    }
}

/// A material parameter: constant or varying over the surface.
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    /// The same value everywhere (a scalar is stored in all three channels).
    Constant(Vec3A),
    /// An image lookup.
    Image(ImageTexture),
    /// A checkerboard.
    Checkerboard(Checkerboard),
}

impl Texture {
    /// The constant `v` in every channel.
    pub fn scalar(v: f32) -> Self {
        Texture::Constant(Vec3A::splat(v))
    }

    /// Linear colour at `uv`.
    #[inline]
    pub fn eval(&self, uv: Vec2) -> Vec3A {
        match self {
            Texture::Constant(c) => *c,
            Texture::Image(t) => t.eval(uv).truncate().into(),
            Texture::Checkerboard(c) => c.eval(uv),
        }
    }

    /// Scalar value at `uv`: an image's chosen channel, a colour's luminance.
    #[inline]
    pub fn eval_scalar(&self, uv: Vec2) -> f32 {
        match self {
            Texture::Constant(c) => c.x,
            Texture::Image(t) => t.eval_scalar(uv),
            Texture::Checkerboard(c) => luminance(c.eval(uv)),
        }
    }

    /// The gradient `(∂/∂u, ∂/∂v)` of [`eval_scalar`](Self::eval_scalar)
    /// (a bump map's slope): an image's by its bilinear interpolation,
    /// zero for a constant and for a checkerboard (flat between its edges).
    pub fn eval_scalar_grad(&self, uv: Vec2) -> Vec2 {
        match self {
            Texture::Image(t) => t.eval_scalar_grad(uv),
            Texture::Constant(_) | Texture::Checkerboard(_) => Vec2::ZERO,
        }
    }

    /// An upper bound of [`eval`](Self::eval) over the surface, per channel
    /// (what the render plan and the lint may assume without a lookup).
    pub fn max_value(&self) -> Vec3A {
        match self {
            Texture::Constant(c) => *c,
            Texture::Image(t) => t.max_value(),
            Texture::Checkerboard(c) => c.colour0.max(c.colour1),
        }
    }

    /// The image this texture reads, if any (for the fingerprint and `info`).
    pub fn image(&self) -> Option<&Arc<Image>> {
        match self {
            Texture::Image(t) => Some(&t.image),
            _ => None,
        }
    }

    /// True when the value does not depend on `uv`.
    pub fn is_constant(&self) -> bool {
        matches!(self, Texture::Constant(_))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkerboard_alternates_on_half_units() {
        let c = Checkerboard {
            colour0: Vec3A::X,
            colour1: Vec3A::Y,
            transform: UvTransform::new(Vec2::splat(2.0), 0.0, Vec2::ZERO),
        };
        // Scaled by 2: squares of a quarter unit.
        assert_eq!(c.eval(Vec2::new(0.1, 0.1)), Vec3A::X);
        assert_eq!(c.eval(Vec2::new(0.3, 0.1)), Vec3A::Y);
        assert_eq!(c.eval(Vec2::new(0.3, 0.3)), Vec3A::X);
        assert_eq!(c.eval(Vec2::new(-0.1, 0.1)), Vec3A::Y);
    }

    #[test]
    fn uv_transform_scales_then_rotates_then_offsets() {
        let t = UvTransform::new(Vec2::new(2.0, 1.0), std::f32::consts::FRAC_PI_2, Vec2::new(0.5, 0.0));
        let p = t.apply(Vec2::new(1.0, 0.0));
        // (1, 0) → (2, 0) → (0, 2) → (0.5, 2).
        assert!((p - Vec2::new(0.5, 2.0)).length() < 1e-6, "{p}");
        assert!(UvTransform::default().is_identity());
    }

    #[test]
    fn channel_names_round_trip() {
        for c in [Channel::Luminance, Channel::R, Channel::G, Channel::B, Channel::A] {
            assert_eq!(Channel::from_name(c.name()), Some(c));
        }
        assert_eq!(Channel::from_name("x"), None);
    }
}
