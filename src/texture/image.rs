//! Image textures: texels in memory and their lookups.
//!
//! 8-bit images keep their bytes (4 per texel) and decode at lookup, sRGB
//! ones through a 256-entry table; HDR images keep linear `f32` RGBA. A
//! bilinear lookup reads the four texels around `(u·w − ½, v·h − ½)`
//! (texel centres at half-integers), each wrapped on its own.

use super::{luminance, Channel, UvTransform};
use crate::math::{Vec2, Vec3A, Vec4};
use std::sync::{Arc, LazyLock};

/// How a lookup outside `[0, 1]` finds its texel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum WrapMode {
    /// The image tiles the plane.
    #[default]
    Repeat,
    /// The border texels extend outward.
    Clamp,
    /// The image tiles the plane, every other copy mirrored.
    Mirror,
}

impl WrapMode {
    /// Name as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            WrapMode::Repeat => "repeat",
            WrapMode::Clamp => "clamp",
            WrapMode::Mirror => "mirror",
        }
    }

    /// The mode named `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        [WrapMode::Repeat, WrapMode::Clamp, WrapMode::Mirror]
            .into_iter()
            .find(|m| m.name() == name)
    }

    /// Texel index for integer coordinate `i` on an axis of `n` texels.
    #[inline]
    pub fn wrap(self, i: i64, n: u32) -> u32 {
        let n = i64::from(n);
        (match self {
            WrapMode::Repeat => i.rem_euclid(n),
            WrapMode::Clamp => i.clamp(0, n - 1),
            WrapMode::Mirror => {
                let m = i.rem_euclid(2 * n);
                if m >= n {
                    2 * n - 1 - m
                } else {
                    m
                }
            }
        }) as u32
    }
}

/// How texels are interpolated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum FilterMode {
    /// Bilinear interpolation of the four nearest texels.
    #[default]
    Bilinear,
    /// The nearest texel.
    Nearest,
}

impl FilterMode {
    /// Name as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            FilterMode::Bilinear => "bilinear",
            FilterMode::Nearest => "nearest",
        }
    }

    /// The mode named `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        [FilterMode::Bilinear, FilterMode::Nearest]
            .into_iter()
            .find(|m| m.name() == name)
    }
}

/// How an 8-bit image's values map to linear ones.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ColourSpace {
    /// sRGB-encoded colour (the RGB channels; alpha is always linear).
    #[default]
    Srgb,
    /// Linear data (normal maps, roughness, masks) or linear colour.
    Linear,
}

impl ColourSpace {
    /// Name as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            ColourSpace::Srgb => "srgb",
            ColourSpace::Linear => "linear",
        }
    }

    /// The space named `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        [ColourSpace::Srgb, ColourSpace::Linear]
            .into_iter()
            .find(|m| m.name() == name)
    }
}

/// The sRGB electro-optical transfer function (IEC 61966-2-1).
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

static SRGB_TABLE: LazyLock<[f32; 256]> = LazyLock::new(|| std::array::from_fn(|i| srgb_to_linear(i as f32 / 255.0)));

/// Texel storage.
#[derive(Clone, Debug, PartialEq)]
pub enum Texels {
    /// 8-bit RGBA; the RGB channels sRGB-encoded or linear.
    Rgba8 {
        /// Row-major texels, first row at the top (`v = 0`).
        data: Vec<[u8; 4]>,
        /// Encoding of the RGB channels.
        space: ColourSpace,
    },
    /// Linear floating-point RGBA (Radiance HDR, OpenEXR, 16-bit images).
    RgbaF32(Vec<[f32; 4]>),
}

/// A decoded image.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Where it came from, for messages.
    pub name: String,
    /// Width in texels (≥ 1).
    pub width: u32,
    /// Height in texels (≥ 1).
    pub height: u32,
    /// The texels.
    pub texels: Texels,
    /// Largest linear value of each channel (RGBA).
    pub max: Vec4,
    /// SHA-256 of the decoded texels and their layout (the fingerprint's
    /// view of the image: the same pixels hash the same whatever the path).
    pub hash: [u8; 32],
}

impl Image {
    /// An image from row-major texels. Panics if the count is not
    /// `width × height` or a side is 0 (the loaders check both first).
    pub fn new(name: impl Into<String>, width: u32, height: u32, texels: Texels) -> Self {
        use sha2::{Digest, Sha256};
        let count = match &texels {
            Texels::Rgba8 { data, .. } => data.len(),
            Texels::RgbaF32(data) => data.len(),
        };
        assert!(width > 0 && height > 0 && count == width as usize * height as usize);
        let mut h = Sha256::new();
        h.update(width.to_le_bytes());
        h.update(height.to_le_bytes());
        let mut max = Vec4::splat(f32::NEG_INFINITY);
        match &texels {
            Texels::Rgba8 { data, space } => {
                h.update([0, *space as u8]);
                for t in data {
                    h.update(t);
                }
                let mut hi = [0u8; 4];
                for t in data {
                    for k in 0..4 {
                        hi[k] = hi[k].max(t[k]);
                    }
                }
                max = decode8(hi, *space);
            }
            Texels::RgbaF32(data) => {
                h.update([1, 0]);
                for t in data {
                    for v in t {
                        h.update(v.to_le_bytes());
                    }
                    max = max.max(Vec4::from(*t));
                }
            }
        }
        Self {
            name: name.into(),
            width,
            height,
            texels,
            max,
            hash: h.finalize().into(),
        }
    }

    /// Linear RGBA of texel `(x, y)`.
    #[inline]
    pub fn texel(&self, x: u32, y: u32) -> Vec4 {
        let i = y as usize * self.width as usize + x as usize;
        match &self.texels {
            Texels::Rgba8 { data, space } => decode8(data[i], *space),
            Texels::RgbaF32(data) => Vec4::from(data[i]),
        }
    }

    /// Bytes held by the texels.
    pub fn memory_bytes(&self) -> usize {
        match &self.texels {
            Texels::Rgba8 { data, .. } => data.len() * 4,
            Texels::RgbaF32(data) => data.len() * 16,
        }
    }

    /// The four texels a bilinear lookup at `uv` blends (`(x, y)`,
    /// `(x + 1, y)`, `(x, y + 1)`, `(x + 1, y + 1)`) and the weights
    /// `(fx, fy)` of the second column and row.
    pub fn bilinear_corners(&self, uv: Vec2, wrap: [WrapMode; 2]) -> ([Vec4; 4], Vec2) {
        let finite = |f: f32| if f.is_finite() { f } else { 0.0 };
        let (x, y) = (
            finite(uv.x * self.width as f32 - 0.5),
            finite(uv.y * self.height as f32 - 0.5),
        );
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let xs = [wrap[0].wrap(x0, self.width), wrap[0].wrap(x0 + 1, self.width)];
        let ys = [wrap[1].wrap(y0, self.height), wrap[1].wrap(y0 + 1, self.height)];
        (
            [
                self.texel(xs[0], ys[0]),
                self.texel(xs[1], ys[0]),
                self.texel(xs[0], ys[1]),
                self.texel(xs[1], ys[1]),
            ],
            Vec2::new(fx, fy),
        )
    }

    /// Linear RGBA at `uv` (no transform), with `wrap` on each axis.
    pub fn lookup(&self, uv: Vec2, wrap: [WrapMode; 2], filter: FilterMode) -> Vec4 {
        let x = uv.x * self.width as f32;
        let y = uv.y * self.height as f32;
        // Non-finite coordinates (a degenerate UV transform) read texel 0.
        let finite = |f: f32| if f.is_finite() { f } else { 0.0 };
        match filter {
            FilterMode::Nearest => {
                let (xi, yi) = (finite(x).floor() as i64, finite(y).floor() as i64);
                self.texel(wrap[0].wrap(xi, self.width), wrap[1].wrap(yi, self.height))
            }
            FilterMode::Bilinear => {
                let (x, y) = (finite(x - 0.5), finite(y - 0.5));
                let (x0, y0) = (x.floor(), y.floor());
                let (fx, fy) = (x - x0, y - y0);
                let (x0, y0) = (x0 as i64, y0 as i64);
                let xs = [wrap[0].wrap(x0, self.width), wrap[0].wrap(x0 + 1, self.width)];
                let ys = [wrap[1].wrap(y0, self.height), wrap[1].wrap(y0 + 1, self.height)];
                let top = self.texel(xs[0], ys[0]) * (1.0 - fx) + self.texel(xs[1], ys[0]) * fx;
                let bottom = self.texel(xs[0], ys[1]) * (1.0 - fx) + self.texel(xs[1], ys[1]) * fx;
                top * (1.0 - fy) + bottom * fy
            }
        }
    }
}

#[inline]
fn decode8(t: [u8; 4], space: ColourSpace) -> Vec4 {
    let a = f32::from(t[3]) / 255.0;
    match space {
        ColourSpace::Srgb => {
            let table = &*SRGB_TABLE;
            Vec4::new(table[t[0] as usize], table[t[1] as usize], table[t[2] as usize], a)
        }
        ColourSpace::Linear => Vec4::new(f32::from(t[0]), f32::from(t[1]), f32::from(t[2]), f32::from(t[3])) / 255.0,
    }
}

/// An image looked up through a UV transform, with its wrap and filter
/// modes, times a factor (glTF's `baseColorFactor` and friends).
#[derive(Clone, Debug, PartialEq)]
pub struct ImageTexture {
    /// The image (shared by every texture that reads it).
    pub image: Arc<Image>,
    /// Applied to the surface's `(u, v)` first.
    pub transform: UvTransform,
    /// Wrap mode along `u` and along `v`.
    pub wrap: [WrapMode; 2],
    /// Interpolation.
    pub filter: FilterMode,
    /// Multiplies the RGB channels.
    pub factor: Vec3A,
    /// Multiplies the alpha channel.
    pub alpha_factor: f32,
    /// What a scalar lookup reads.
    pub channel: Channel,
}

impl ImageTexture {
    /// `image` with no transform, repeat wrapping, bilinear filtering, factor 1.
    pub fn new(image: Arc<Image>) -> Self {
        Self {
            image,
            transform: UvTransform::default(),
            wrap: [WrapMode::Repeat; 2],
            filter: FilterMode::Bilinear,
            factor: Vec3A::ONE,
            alpha_factor: 1.0,
            channel: Channel::Luminance,
        }
    }

    /// Linear RGBA at `uv`.
    #[inline]
    pub fn eval(&self, uv: Vec2) -> Vec4 {
        let t = self.image.lookup(self.transform.apply(uv), self.wrap, self.filter);
        t * Vec4::from((self.factor, self.alpha_factor))
    }

    /// The channel [`channel`](Self::channel) names, at `uv`.
    #[inline]
    pub fn eval_scalar(&self, uv: Vec2) -> f32 {
        self.scalar_of(self.image.lookup(self.transform.apply(uv), self.wrap, self.filter))
    }

    /// The gradient `(∂f/∂u, ∂f/∂v)` of [`eval_scalar`](Self::eval_scalar)
    /// at `uv`, as Mitsuba 3's `bitmap` gives it to `bumpmap`: the
    /// derivative of the bilinear interpolation between the four texels
    /// around the point, taken through the UV transform (its transpose), in
    /// units of the image per unit of texture coordinate; zero for nearest
    /// lookups, which are piecewise constant.
    pub fn eval_scalar_grad(&self, uv: Vec2) -> Vec2 {
        if self.filter == FilterMode::Nearest {
            return Vec2::ZERO;
        }
        let p = self.transform.apply(uv);
        let (corners, w1) = self.image.bilinear_corners(p, self.wrap);
        let [f00, f10, f01, f11] = corners.map(|t| self.scalar_of(t));
        let w0 = Vec2::ONE - w1;
        // Partials with respect to the texel coordinates x and y.
        let dx = w0.y * (f10 - f00) + w1.y * (f11 - f01);
        let dy = w0.x * (f01 - f00) + w1.x * (f11 - f10);
        let m = self.transform.0.matrix2;
        let duv = Vec2::new(m.x_axis.x * dx + m.x_axis.y * dy, m.y_axis.x * dx + m.y_axis.y * dy);
        duv * Vec2::new(self.image.width as f32, self.image.height as f32)
    }

    /// The scalar a lookup reads from linear RGBA `t` (factor applied).
    fn scalar_of(&self, t: Vec4) -> f32 {
        let t = t * Vec4::from((self.factor, self.alpha_factor));
        match self.channel {
            Channel::Luminance => luminance(t.truncate().into()),
            Channel::R => t.x,
            Channel::G => t.y,
            Channel::B => t.z,
            Channel::A => t.w,
        }
    }

    /// Upper bound of the RGB values.
    pub fn max_value(&self) -> Vec3A {
        Vec3A::from(self.image.max.truncate()) * self.factor
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grey8(values: &[u8], w: u32, space: ColourSpace) -> Image {
        let data = values.iter().map(|&v| [v, v, v, 255]).collect();
        Image::new("test", w, values.len() as u32 / w, Texels::Rgba8 { data, space })
    }

    #[test]
    fn srgb_decode_matches_the_standard() {
        // IEC 61966-2-1 reference points.
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_to_linear(0.5) - 0.214_041).abs() < 1e-5);
        assert!((srgb_to_linear(0.04) - 0.04 / 12.92).abs() < 1e-7);
        let img = grey8(&[128], 1, ColourSpace::Srgb);
        let t = img.texel(0, 0);
        assert!((t.x - srgb_to_linear(128.0 / 255.0)).abs() < 1e-7 && t.w == 1.0);
        let lin = grey8(&[128], 1, ColourSpace::Linear);
        assert!((lin.texel(0, 0).x - 128.0 / 255.0).abs() < 1e-7);
    }

    #[test]
    fn wrap_modes_by_hand() {
        let n = 4;
        let idx = |m: WrapMode| (-5..9).map(|i| m.wrap(i, n)).collect::<Vec<_>>();
        assert_eq!(idx(WrapMode::Repeat), [3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0]);
        assert_eq!(idx(WrapMode::Clamp), [0, 0, 0, 0, 0, 0, 1, 2, 3, 3, 3, 3, 3, 3]);
        assert_eq!(idx(WrapMode::Mirror), [3, 3, 2, 1, 0, 0, 1, 2, 3, 3, 2, 1, 0, 0]);
    }

    #[test]
    fn bilinear_interpolates_between_texel_centres() {
        // Two linear texels, 0 and 1, across u.
        let img = grey8(&[0, 255], 2, ColourSpace::Linear);
        let at = |u: f32, wrap: WrapMode| img.lookup(Vec2::new(u, 0.5), [wrap; 2], FilterMode::Bilinear).x;
        // Texel centres at u = 0.25 and 0.75.
        assert!((at(0.25, WrapMode::Clamp) - 0.0).abs() < 1e-6);
        assert!((at(0.75, WrapMode::Clamp) - 1.0).abs() < 1e-6);
        assert!((at(0.5, WrapMode::Clamp) - 0.5).abs() < 1e-6);
        assert!((at(0.375, WrapMode::Clamp) - 0.25).abs() < 1e-6);
        // At u = 0 the neighbour is texel 1 (repeat) or texel 0 again (clamp, mirror).
        assert!((at(0.0, WrapMode::Repeat) - 0.5).abs() < 1e-6);
        assert!((at(0.0, WrapMode::Clamp) - 0.0).abs() < 1e-6);
        assert!((at(0.0, WrapMode::Mirror) - 0.0).abs() < 1e-6);
        // Nearest: texel 0 below u = 0.5.
        assert_eq!(
            img.lookup(Vec2::new(0.49, 0.0), [WrapMode::Clamp; 2], FilterMode::Nearest)
                .x,
            0.0
        );
    }

    #[test]
    fn srgb_texels_are_linearised_before_filtering() {
        let img = grey8(&[0, 255], 2, ColourSpace::Srgb);
        let mid = img
            .lookup(Vec2::new(0.5, 0.5), [WrapMode::Clamp; 2], FilterMode::Bilinear)
            .x;
        // The mean of linear 0 and 1, not the decode of the mean code value (0.21).
        assert!((mid - 0.5).abs() < 1e-6, "{mid}");
    }

    #[test]
    fn v_zero_is_the_top_row() {
        let img = grey8(&[10, 200], 1, ColourSpace::Linear);
        let top = img
            .lookup(Vec2::new(0.5, 0.1), [WrapMode::Clamp; 2], FilterMode::Nearest)
            .x;
        assert!((top - 10.0 / 255.0).abs() < 1e-6);
    }

    #[test]
    fn same_texels_hash_the_same() {
        let a = grey8(&[1, 2, 3, 4], 2, ColourSpace::Srgb);
        let mut b = grey8(&[1, 2, 3, 4], 2, ColourSpace::Srgb);
        b.name = "elsewhere".into();
        assert_eq!(a.hash, Image::new("x", 2, 2, b.texels.clone()).hash);
        assert_ne!(a.hash, grey8(&[1, 2, 3, 5], 2, ColourSpace::Srgb).hash);
        assert_ne!(a.hash, grey8(&[1, 2, 3, 4], 2, ColourSpace::Linear).hash);
        assert_eq!(a.max.x, srgb_to_linear(4.0 / 255.0));
    }

    #[test]
    fn factor_and_channel() {
        let data = vec![[0.2, 0.4, 0.6, 0.5]];
        let img = Arc::new(Image::new("f", 1, 1, Texels::RgbaF32(data)));
        let mut t = ImageTexture::new(img);
        t.factor = Vec3A::new(2.0, 1.0, 0.5);
        let c = t.eval(Vec2::ZERO);
        assert!((c - Vec4::new(0.4, 0.4, 0.3, 0.5)).abs().max_element() < 1e-6);
        t.channel = Channel::A;
        assert_eq!(t.eval_scalar(Vec2::ZERO), 0.5);
        t.channel = Channel::B;
        assert!((t.eval_scalar(Vec2::ZERO) - 0.3).abs() < 1e-6);
        assert!((t.max_value() - Vec3A::new(0.4, 0.4, 0.3)).abs().max_element() < 1e-6);
    }
}
