//! The accumulation buffer: the explicit per-pixel state of a render in
//! progress (running radiance sum, samples taken, samples kept), from which
//! the film is derived. A render can stop at any pixel boundary and later
//! continue from this state; because every pixel adds its samples in
//! increasing sample index and the sum is kept in the same f32 type the
//! uninterrupted loop uses, a resumed render ends bit-identical to an
//! uninterrupted one (see `integrator::render`).

use super::Film;
use crate::math::{Vec3, Vec3A};

/// Per-pixel running state of a render, row-major from the top-left pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Accumulation {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Sum of the kept (finite) sample radiances of each pixel, added in
    /// increasing sample index, in f32.
    pub sum: Vec<Vec3>,
    /// Samples taken per pixel: the next sample index to draw. Samples
    /// `0..taken` have been evaluated.
    pub taken: Vec<u32>,
    /// Samples kept per pixel (`≤ taken`): those with a finite radiance.
    /// NaN and infinite samples are dropped and never reach the sum.
    pub kept: Vec<u32>,
}

impl Accumulation {
    /// An empty accumulation: no sample taken anywhere.
    pub fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            sum: vec![Vec3::ZERO; n],
            taken: vec![0; n],
            kept: vec![0; n],
        }
    }

    /// Number of pixels.
    pub fn len(&self) -> usize {
        self.taken.len()
    }

    /// True for a zero-sized image.
    pub fn is_empty(&self) -> bool {
        self.taken.is_empty()
    }

    /// Samples taken over all pixels.
    pub fn samples_taken(&self) -> u64 {
        self.taken.iter().map(|&t| t as u64).sum()
    }

    /// Samples dropped (NaN or infinite) over all pixels.
    pub fn samples_dropped(&self) -> u64 {
        self.taken.iter().zip(&self.kept).map(|(&t, &k)| (t - k) as u64).sum()
    }

    /// Fewest and most samples taken by any pixel (`(0, 0)` when empty).
    pub fn taken_range(&self) -> (u32, u32) {
        let min = self.taken.iter().copied().min().unwrap_or(0);
        let max = self.taken.iter().copied().max().unwrap_or(0);
        (min, max)
    }

    /// True when every pixel has taken `spp` samples.
    pub fn is_complete(&self, spp: u32) -> bool {
        self.taken.iter().all(|&t| t >= spp)
    }

    /// Checks the internal consistency of state read from outside (a
    /// checkpoint): array lengths match the size, `kept ≤ taken ≤ spp`, and
    /// sums are finite. Returns a description of the first problem.
    pub fn validate(&self, spp: u32) -> Result<(), String> {
        let n = self.width as usize * self.height as usize;
        if self.sum.len() != n || self.taken.len() != n || self.kept.len() != n {
            return Err(format!(
                "{}×{} pixels but {} sums, {} taken counts and {} kept counts",
                self.width,
                self.height,
                self.sum.len(),
                self.taken.len(),
                self.kept.len()
            ));
        }
        for i in 0..n {
            let (x, y) = (i % self.width as usize, i / self.width as usize);
            if self.kept[i] > self.taken[i] || self.taken[i] > spp {
                return Err(format!(
                    "pixel ({x}, {y}): {} samples kept, {} taken, {spp} spp: need kept ≤ taken ≤ spp",
                    self.kept[i], self.taken[i]
                ));
            }
            if !self.sum[i].is_finite() {
                return Err(format!("pixel ({x}, {y}): the radiance sum is not finite"));
            }
        }
        Ok(())
    }

    /// The film: each pixel the mean of its kept samples (the box filter),
    /// black where none was kept. The division is the same f32 operation the
    /// render loop always used, so the film is bit-identical to it.
    pub fn to_film(&self) -> Film {
        let pixels = self
            .sum
            .iter()
            .zip(&self.kept)
            .map(|(&sum, &kept)| {
                if kept > 0 {
                    Vec3::from(Vec3A::from(sum) / kept as f32)
                } else {
                    Vec3::ZERO
                }
            })
            .collect();
        Film {
            width: self.width,
            height: self.height,
            pixels,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn film_is_the_mean_of_kept_samples() {
        let mut a = Accumulation::new(2, 1);
        a.sum[0] = Vec3::new(3.0, 6.0, 9.0);
        a.taken[0] = 4;
        a.kept[0] = 3;
        let f = a.to_film();
        assert_eq!(f.get(0, 0), Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(f.get(1, 0), Vec3::ZERO);
        assert_eq!(a.samples_taken(), 4);
        assert_eq!(a.samples_dropped(), 1);
        assert_eq!(a.taken_range(), (0, 4));
        assert!(!a.is_complete(4));
        a.taken[1] = 4;
        assert!(a.is_complete(4));
        assert!(a.validate(4).is_ok());
    }

    #[test]
    fn validate_names_the_bad_pixel() {
        let mut a = Accumulation::new(3, 2);
        a.taken[4] = 2;
        a.kept[4] = 3;
        let e = a.validate(8).unwrap_err();
        assert!(e.contains("pixel (1, 1)"), "{e}");
        a.kept[4] = 1;
        a.taken[4] = 9;
        assert!(a.validate(8).unwrap_err().contains("9 taken"));
        a.taken[4] = 1;
        a.sum[5] = Vec3::new(f32::NAN, 0.0, 0.0);
        assert!(a.validate(8).unwrap_err().contains("pixel (2, 1)"));
        a.sum.pop();
        assert!(a.validate(8).unwrap_err().contains("5 sums"));
    }
}
