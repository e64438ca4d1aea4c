//! Latitude-longitude environment images and their importance sampling.

use crate::math::distribution::Distribution2D;
use crate::math::{Mat3A, Vec2, Vec3A};
use crate::texture::{luminance, Image};
use std::f32::consts::PI;
use std::sync::Arc;

/// A latitude-longitude environment image (Mitsuba's `envmap`, y up): the
/// direction `d` (in the map's frame) reads `u = atan2(d.x, −d.z) / 2π`,
/// `v = acos(d.y) / π`, bilinearly, and is importance-sampled in proportion
/// to the texels' luminance (the largest of each 3 × 3 neighbourhood)
/// times `sin θ` (pbrt-v4 §12.5.2).
pub struct EnvironmentMap {
    /// The linear image (`v = 0`, the top row, is straight up).
    pub image: Arc<Image>,
    /// Map frame to world (a rotation).
    pub to_world: Mat3A,
    distribution: Distribution2D,
    /// `∫ L dω` over the sphere of the image's values, per channel.
    integral: Vec3A,
}

impl std::fmt::Debug for EnvironmentMap {
    /// The image by its texels' hash (what the fingerprint reads), not its texels.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let hash: String = self.image.hash.iter().map(|b| format!("{b:02x}")).collect();
        f.debug_struct("EnvironmentMap")
            .field("image", &hash)
            .field("to_world", &self.to_world)
            .finish()
    }
}

impl PartialEq for EnvironmentMap {
    fn eq(&self, other: &Self) -> bool {
        self.image.hash == other.image.hash && self.to_world == other.to_world
    }
}

impl EnvironmentMap {
    /// The map of `image` turned by `to_world` (a rotation).
    pub fn new(image: Arc<Image>, to_world: Mat3A) -> Self {
        let (w, h) = (image.width as usize, image.height as usize);
        let colour = |x: usize, y: usize| Vec3A::from(image.texel(x as u32, y as u32).truncate()).max(Vec3A::ZERO);
        let lum: Vec<f32> = (0..w * h).map(|i| luminance(colour(i % w, i / w))).collect();
        let mut func = Vec::with_capacity(w * h);
        let mut integral = Vec3A::ZERO;
        // Solid angle of a texel of row y: (2π / w)(π / h) sin θ.
        let texel = 2.0 * PI * PI / (w * h) as f32;
        for y in 0..h {
            let sin_theta = (PI * (y as f32 + 0.5) / h as f32).sin();
            for x in 0..w {
                // The largest luminance a bilinear lookup in this cell can
                // reach (its 3 × 3 neighbourhood): where the map is bright,
                // the density is too, so a bright texel's neighbours do
                // not give fireflies to paths that find it by chance.
                let mut m = 0.0f32;
                for dy in [-1i64, 0, 1] {
                    let yy = (y as i64 + dy).clamp(0, h as i64 - 1) as usize;
                    for dx in [-1i64, 0, 1] {
                        let xx = (x as i64 + dx).rem_euclid(w as i64) as usize;
                        m = m.max(lum[yy * w + xx]);
                    }
                }
                func.push(m * sin_theta);
                integral += colour(x, y) * (sin_theta * texel);
            }
        }
        Self {
            distribution: Distribution2D::new(&func, w, h),
            image,
            to_world,
            integral,
        }
    }

    /// `(u, v)` of world direction `dir`, and `sin θ`.
    #[inline]
    fn uv(&self, dir: Vec3A) -> (Vec2, f32) {
        let d = self.to_world.transpose() * dir.normalize_or(Vec3A::Y);
        let mut u = d.x.atan2(-d.z) / (2.0 * PI);
        if u < 0.0 {
            u += 1.0;
        }
        let cos_theta = d.y.clamp(-1.0, 1.0);
        let v = cos_theta.acos() / PI;
        (Vec2::new(u, v), (1.0 - cos_theta * cos_theta).max(0.0).sqrt())
    }

    /// The image's radiance arriving from direction `dir` (toward the scene
    /// along `−dir`), before the light's scale: bilinear between texels
    /// placed as Mitsuba 3's `envmap` places them (fitted to its `eval`):
    /// column `i` at `u = (i + ½) / w`, periodic in `u`, and row `j` at
    /// `v = j / (h − 1)`, the first and last rows on the poles.
    #[inline]
    pub fn eval(&self, dir: Vec3A) -> Vec3A {
        let (uv, _) = self.uv(dir);
        let (w, h) = (self.image.width, self.image.height);
        let x = uv.x * w as f32 - 0.5;
        let y = uv.y * h.saturating_sub(1) as f32;
        let xf = x.floor();
        let fx = (x - xf).clamp(0.0, 1.0);
        let x0 = (xf as i64).rem_euclid(i64::from(w)) as u32;
        let y0 = (y.floor().max(0.0) as u32).min(h.saturating_sub(2));
        let fy = (y - y0 as f32).clamp(0.0, 1.0);
        let x1 = (x0 + 1) % w;
        let y1 = (y0 + 1).min(h - 1);
        let t = |x: u32, y: u32| Vec3A::from(self.image.texel(x, y).truncate());
        let top = t(x0, y0) * (1.0 - fx) + t(x1, y0) * fx;
        let bottom = t(x0, y1) * (1.0 - fx) + t(x1, y1) * fx;
        (top * (1.0 - fy) + bottom * fy).max(Vec3A::ZERO)
    }

    /// A direction toward the environment for `u ∈ [0, 1)²` and its density
    /// in solid angle; `None` at the poles (where the density is infinite).
    pub fn sample(&self, u: Vec2) -> Option<(Vec3A, f32)> {
        let (uv, pdf_uv) = self.distribution.sample(u);
        let (theta, phi) = (uv.y * PI, uv.x * 2.0 * PI);
        let (sin_theta, cos_theta) = theta.sin_cos();
        let (sin_phi, cos_phi) = phi.sin_cos();
        let local = Vec3A::new(sin_theta * sin_phi, cos_theta, -sin_theta * cos_phi);
        // sin θ as `pdf` computes it from the direction, so that both agree.
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        if sin_theta <= 0.0 || pdf_uv <= 0.0 {
            return None;
        }
        Some((self.to_world * local, pdf_uv / (2.0 * PI * PI * sin_theta)))
    }

    /// The density in solid angle with which [`sample`](Self::sample) picks `dir`.
    pub fn pdf(&self, dir: Vec3A) -> f32 {
        let (uv, sin_theta) = self.uv(dir);
        if sin_theta <= 0.0 {
            return 0.0;
        }
        self.distribution.pdf(uv) / (2.0 * PI * PI * sin_theta)
    }

    /// The mean radiance over the sphere, per channel (`∫ L dω / 4π`).
    pub fn mean(&self) -> Vec3A {
        self.integral / (4.0 * PI)
    }
}
