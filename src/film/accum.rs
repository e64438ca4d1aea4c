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
    /// Sum of the kept samples of odd index (one half of `sum`, the other
    /// half being `sum − odd`): the two half-buffer means estimate each
    /// pixel's noise (Dammertz et al. 2010; Cycles' adaptive sampling).
    /// Empty when the accumulation keeps no noise estimate ([`Buffers`]).
    pub odd: Vec<Vec3>,
    /// Kept samples of odd index (empty with `odd`).
    pub odd_kept: Vec<u32>,
    /// Pixels adaptive sampling has stopped: they take no more samples.
    pub converged: Vec<bool>,
    /// Sum of the albedo AOV of the pixel's first [`AOV_SAMPLES`] samples
    /// (every sample taken counts, in increasing sample index, in f32).
    /// Empty when the accumulation keeps no AOVs ([`Buffers`]).
    pub albedo: Vec<Vec3>,
    /// Sum of the shading-normal AOV of the same samples (empty with `albedo`).
    pub normal: Vec<Vec3>,
}

/// The optional per-pixel buffers of an [`Accumulation`]. Every
/// accumulation keeps the sum and the counts (`sum`, `taken`, `kept`,
/// `converged`: 21 bytes per pixel); the noise estimate adds 16 bytes and
/// the AOVs 24, kept only when something reads them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Buffers {
    /// The odd-sample half sums (`odd`, `odd_kept`): adaptive sampling, the
    /// EXR's error layer, checkpoints and partials.
    pub noise: bool,
    /// The albedo and normal sums: denoising, the EXR's AOV layers,
    /// checkpoints and partials, the viewer.
    pub aovs: bool,
}

impl Buffers {
    /// Every buffer.
    pub const ALL: Buffers = Buffers {
        noise: true,
        aovs: true,
    };

    /// Bytes per pixel of an accumulation with these buffers.
    pub fn bytes_per_pixel(self) -> usize {
        let base = std::mem::size_of::<Vec3>() + 2 * std::mem::size_of::<u32>() + std::mem::size_of::<bool>();
        let noise = std::mem::size_of::<Vec3>() + std::mem::size_of::<u32>();
        let aovs = 2 * std::mem::size_of::<Vec3>();
        base + if self.noise { noise } else { 0 } + if self.aovs { aovs } else { 0 }
    }

    /// The buffers either keeps.
    pub fn union(self, other: Buffers) -> Buffers {
        Buffers {
            noise: self.noise || other.noise,
            aovs: self.aovs || other.aovs,
        }
    }
}

/// Samples per pixel that trace the auxiliary images (albedo, normal): the
/// first ones. They are noise-free apart from the sub-pixel position, so a
/// few dozen antialias them; later samples skip the extra rays.
pub const AOV_SAMPLES: u32 = 64;

/// Floor of the relative error's denominator, in linear radiance (the ε of
/// relMSE in `caustic converge`: `(x − r)² / (r² + ε)`, with ε = 1e-2).
pub const RELATIVE_ERROR_FLOOR: f32 = 1.0e-2;

impl Accumulation {
    /// An empty accumulation with every buffer: no sample taken anywhere.
    pub fn new(width: u32, height: u32) -> Self {
        Self::with_buffers(width, height, Buffers::ALL)
    }

    /// An empty accumulation keeping `buffers`.
    pub fn with_buffers(width: u32, height: u32, buffers: Buffers) -> Self {
        let n = width as usize * height as usize;
        let (noise, aovs) = (if buffers.noise { n } else { 0 }, if buffers.aovs { n } else { 0 });
        Self {
            width,
            height,
            sum: vec![Vec3::ZERO; n],
            taken: vec![0; n],
            kept: vec![0; n],
            odd: vec![Vec3::ZERO; noise],
            odd_kept: vec![0; noise],
            converged: vec![false; n],
            albedo: vec![Vec3::ZERO; aovs],
            normal: vec![Vec3::ZERO; aovs],
        }
    }

    /// The optional buffers this accumulation keeps.
    pub fn buffers(&self) -> Buffers {
        let n = self.len();
        Buffers {
            noise: self.odd.len() == n && self.odd_kept.len() == n,
            aovs: self.albedo.len() == n && self.normal.len() == n,
        }
    }

    /// The pixels of the rectangle `x0..x1 × y0..y1` as an accumulation of
    /// their own (a tile's state during a render), keeping `buffers`.
    pub fn region_with(&self, x0: u32, y0: u32, x1: u32, y1: u32, buffers: Buffers) -> Accumulation {
        let mut part = Accumulation::with_buffers(x1 - x0, y1 - y0, buffers);
        let (w, pw) = (self.width as usize, part.width as usize);
        for (r, y) in (y0..y1).enumerate() {
            let src = y as usize * w + x0 as usize..y as usize * w + x1 as usize;
            let dst = r * pw..(r + 1) * pw;
            part.copy_span(dst, self, src);
        }
        part
    }

    /// The pixels of the rectangle `x0..x1 × y0..y1` as an accumulation of
    /// their own, with this one's buffers.
    pub fn region(&self, x0: u32, y0: u32, x1: u32, y1: u32) -> Accumulation {
        self.region_with(x0, y0, x1, y1, self.buffers())
    }

    /// Writes `part` (from [`region`](Self::region)) back at `(x0, y0)`.
    pub fn put_region(&mut self, x0: u32, y0: u32, part: &Accumulation) {
        let (w, pw) = (self.width as usize, part.width as usize);
        for r in 0..part.height as usize {
            let y = y0 as usize + r;
            let dst = y * w + x0 as usize..y * w + x0 as usize + pw;
            self.copy_span(dst, part, r * pw..(r + 1) * pw);
        }
    }

    /// Copies pixels `from` of `src` to `dst`: the buffers both keep (one
    /// that `src` lacks stays zero here).
    fn copy_span(&mut self, dst: std::ops::Range<usize>, src: &Accumulation, from: std::ops::Range<usize>) {
        self.sum[dst.clone()].copy_from_slice(&src.sum[from.clone()]);
        self.taken[dst.clone()].copy_from_slice(&src.taken[from.clone()]);
        self.kept[dst.clone()].copy_from_slice(&src.kept[from.clone()]);
        self.converged[dst.clone()].copy_from_slice(&src.converged[from.clone()]);
        let (mine, theirs) = (self.buffers(), src.buffers());
        if mine.noise && theirs.noise {
            self.odd[dst.clone()].copy_from_slice(&src.odd[from.clone()]);
            self.odd_kept[dst.clone()].copy_from_slice(&src.odd_kept[from.clone()]);
        }
        if mine.aovs && theirs.aovs {
            self.albedo[dst.clone()].copy_from_slice(&src.albedo[from.clone()]);
            self.normal[dst].copy_from_slice(&src.normal[from]);
        }
    }

    /// Estimated relative standard error of pixel `i`'s mean: from the two
    /// half-buffer means `Ā` (even samples) and `B̄` (odd samples), the
    /// standard error of the full mean is about `|Ā − B̄| / 2` per channel,
    /// taken relative to the mean as relMSE does,
    /// `sqrt(mean_c(σ_c² / (Ī_c² + ε)))` with ε = [`RELATIVE_ERROR_FLOOR`],
    /// so that dark pixels are judged by an absolute floor and bright ones
    /// relatively. Infinite while either half is empty, and without the
    /// noise buffers.
    pub fn relative_error(&self, i: usize) -> f32 {
        if !self.buffers().noise {
            return f32::INFINITY;
        }
        let (kept, odd_kept) = (self.kept[i], self.odd_kept[i]);
        let even_kept = kept - odd_kept;
        if odd_kept == 0 || even_kept == 0 {
            return f32::INFINITY;
        }
        let (sum, odd) = (Vec3A::from(self.sum[i]), Vec3A::from(self.odd[i]));
        let b = odd / odd_kept as f32;
        let a = (sum - odd) / even_kept as f32;
        let mean = sum / kept as f32;
        let sigma = (a - b).abs() * 0.5;
        let rel = sigma * sigma / (mean * mean + Vec3A::splat(RELATIVE_ERROR_FLOOR));
        ((rel.x + rel.y + rel.z) / 3.0).sqrt()
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

    /// True when every pixel has taken `spp` samples or converged.
    pub fn is_complete(&self, spp: u32) -> bool {
        self.taken.iter().zip(&self.converged).all(|(&t, &c)| t >= spp || c)
    }

    /// Fewest samples taken by a pixel still sampling (`None` when every
    /// pixel has converged).
    pub fn active_level(&self) -> Option<u32> {
        self.taken
            .iter()
            .zip(&self.converged)
            .filter(|(_, &c)| !c)
            .map(|(&t, _)| t)
            .min()
    }

    /// Per-pixel estimated relative error ([`relative_error`](Self::relative_error));
    /// pixels with an empty half read `f32::MAX` (an infinity would upset
    /// image viewers).
    pub fn error_map(&self) -> Vec<f32> {
        (0..self.len()).map(|i| self.relative_error(i).min(f32::MAX)).collect()
    }

    /// Checks the internal consistency of state read from outside (a
    /// checkpoint): array lengths match the size, `kept ≤ taken ≤ spp`, and
    /// sums are finite. Returns a description of the first problem.
    pub fn validate(&self, spp: u32) -> Result<(), String> {
        let n = self.width as usize * self.height as usize;
        if self.odd.len() != n || self.odd_kept.len() != n || self.converged.len() != n {
            return Err(format!(
                "{}×{} pixels but {} odd sums, {} odd counts and {} convergence flags",
                self.width,
                self.height,
                self.odd.len(),
                self.odd_kept.len(),
                self.converged.len()
            ));
        }
        if self.albedo.len() != n || self.normal.len() != n {
            return Err(format!(
                "{}×{} pixels but {} albedo and {} normal sums",
                self.width,
                self.height,
                self.albedo.len(),
                self.normal.len()
            ));
        }
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
            if !self.sum[i].is_finite() || !self.odd[i].is_finite() {
                return Err(format!("pixel ({x}, {y}): the radiance sum is not finite"));
            }
            if !self.albedo[i].is_finite() || !self.normal[i].is_finite() {
                return Err(format!("pixel ({x}, {y}): the albedo or normal sum is not finite"));
            }
            if self.odd_kept[i] > self.kept[i] || self.odd_kept[i] > self.taken[i] / 2 {
                return Err(format!(
                    "pixel ({x}, {y}): {} odd samples kept of {} kept, {} taken",
                    self.odd_kept[i], self.kept[i], self.taken[i]
                ));
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

impl Accumulation {
    /// Samples of pixel `i` in its AOV sums.
    pub fn aov_samples(&self, i: usize) -> u32 {
        self.taken[i].min(AOV_SAMPLES)
    }

    /// The albedo image: each pixel the mean of its AOV samples (black
    /// before any).
    pub fn albedo_film(&self) -> Film {
        self.aov_film(&self.albedo, false)
    }

    /// The shading-normal image: each pixel's mean normal, renormalised to
    /// unit length (zero where every sample escaped or none was taken).
    pub fn normal_film(&self) -> Film {
        self.aov_film(&self.normal, true)
    }

    /// Black without the AOV buffers.
    fn aov_film(&self, sums: &[Vec3], unit: bool) -> Film {
        if sums.len() != self.len() {
            return Film {
                width: self.width,
                height: self.height,
                pixels: vec![Vec3::ZERO; self.len()],
            };
        }
        let pixels = sums
            .iter()
            .enumerate()
            .map(|(i, &sum)| {
                let n = self.aov_samples(i);
                if n == 0 {
                    return Vec3::ZERO;
                }
                let mean = sum / n as f32;
                if unit {
                    mean.normalize_or_zero()
                } else {
                    mean
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

    #[test]
    fn optional_buffers_are_kept_only_when_asked_for() {
        let lean = Buffers {
            noise: false,
            aovs: false,
        };
        let mut a = Accumulation::with_buffers(4, 2, lean);
        assert_eq!(a.buffers(), lean);
        assert!(a.odd.is_empty() && a.albedo.is_empty());
        assert_eq!(lean.bytes_per_pixel(), 21);
        assert_eq!(Buffers::ALL.bytes_per_pixel(), 61);
        a.sum[5] = Vec3::ONE;
        a.taken[5] = 2;
        a.kept[5] = 2;
        // Without the noise buffers the error is unknown, and the AOVs black.
        assert_eq!(a.relative_error(5), f32::INFINITY);
        assert_eq!(a.albedo_film().pixels, vec![Vec3::ZERO; 8]);
        // A region keeps its source's buffers, or the ones asked for.
        let r = a.region(1, 1, 3, 2);
        assert_eq!((r.buffers(), r.sum[0]), (lean, Vec3::ONE));
        let full = a.region_with(0, 0, 4, 2, Buffers::ALL);
        assert_eq!(full.buffers(), Buffers::ALL);
        assert_eq!((full.sum[5], full.odd[5]), (Vec3::ONE, Vec3::ZERO));
        let mut back = Accumulation::new(4, 2);
        back.put_region(1, 1, &r);
        assert_eq!(back.sum[5], Vec3::ONE);
        assert_eq!(back.to_film().pixels, a.to_film().pixels);
    }

    #[test]
    fn aov_images_average_their_samples() {
        let mut a = Accumulation::new(3, 1);
        a.taken = vec![4, AOV_SAMPLES + 36, 0];
        a.albedo[0] = Vec3::new(2.0, 1.0, 0.0);
        a.normal[0] = Vec3::new(0.0, 0.0, -4.0);
        a.albedo[1] = Vec3::splat(AOV_SAMPLES as f32 * 0.5);
        a.normal[1] = Vec3::new(3.0, 4.0, 0.0);
        let (albedo, normal) = (a.albedo_film(), a.normal_film());
        assert_eq!(albedo.pixels, [Vec3::new(0.5, 0.25, 0.0), Vec3::splat(0.5), Vec3::ZERO]);
        assert_eq!(
            normal.pixels,
            [Vec3::new(0.0, 0.0, -1.0), Vec3::new(0.6, 0.8, 0.0), Vec3::ZERO]
        );
        a.normal[2] = Vec3::new(f32::INFINITY, 0.0, 0.0);
        assert!(a.validate(u32::MAX).unwrap_err().contains("pixel (2, 0)"));
    }
}
