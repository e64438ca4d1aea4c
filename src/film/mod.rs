//! The film: a linear HDR image the integrator fills, the tone mapping that
//! turns it into display values, the (atomic) PNG / EXR writers, and the
//! accumulation buffer with its checkpoint files (interrupt and resume), and
//! the shards of a split render with their merge.

pub mod accum;
pub mod checkpoint;
pub mod denoise;
pub mod filter;
pub mod output;
pub mod shard;
pub mod tonemap;

use crate::math::Vec3;

pub use accum::{Accumulation, Buffers};
pub use checkpoint::{
    read_checkpoint, read_checkpoint_meta, write_checkpoint, Checkpoint, CheckpointError, CheckpointMeta,
};
pub use output::{check_writable, write_exr, write_exr_with, write_png, OutputError};
pub use shard::{ShardId, ShardMode, ShardSet};
pub use tonemap::{aces_fitted, srgb_oetf, tonemap_to_srgb8, OutputSettings, ToneMap};

/// A linear HDR image, row-major from the top-left pixel, one RGB radiance
/// value per pixel (the average of the pixel's samples, placed by the
/// camera's pixel filter).
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height` linear RGB values, row by row.
    pub pixels: Vec<Vec3>,
}

impl Film {
    /// A black film.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            pixels: vec![Vec3::ZERO; width as usize * height as usize],
        }
    }

    /// Value of pixel `(x, y)` (x to the right, y down).
    #[inline]
    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Sets pixel `(x, y)`.
    #[inline]
    pub fn set(&mut self, x: u32, y: u32, value: Vec3) {
        let w = self.width as usize;
        self.pixels[y as usize * w + x as usize] = value;
    }

    /// Mean over the rectangle `[x0, x1) × [y0, y1)` (clipped to the film),
    /// accumulated in f64. Zero for an empty rectangle.
    pub fn mean_over(&self, x0: u32, y0: u32, x1: u32, y1: u32) -> Vec3 {
        let (x1, y1) = (x1.min(self.width), y1.min(self.height));
        let mut sum = [0.0f64; 3];
        let mut n = 0u64;
        for y in y0..y1 {
            for x in x0..x1 {
                let p = self.get(x, y);
                sum[0] += p.x as f64;
                sum[1] += p.y as f64;
                sum[2] += p.z as f64;
                n += 1;
            }
        }
        if n == 0 {
            return Vec3::ZERO;
        }
        let n = n as f64;
        Vec3::new((sum[0] / n) as f32, (sum[1] / n) as f32, (sum[2] / n) as f32)
    }

    /// Mean of the whole film.
    pub fn mean(&self) -> Vec3 {
        self.mean_over(0, 0, self.width, self.height)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn get_set_and_means() {
        let mut f = Film::new(3, 2);
        f.set(2, 1, Vec3::new(6.0, 0.0, 3.0));
        assert_eq!(f.get(2, 1), Vec3::new(6.0, 0.0, 3.0));
        assert_eq!(f.pixels[5], Vec3::new(6.0, 0.0, 3.0));
        assert_eq!(f.mean(), Vec3::new(1.0, 0.0, 0.5));
        assert_eq!(f.mean_over(2, 1, 10, 10), Vec3::new(6.0, 0.0, 3.0));
        assert_eq!(f.mean_over(1, 1, 1, 2), Vec3::ZERO);
    }
}
