//! Pixel reconstruction filters (Mitsuba's `rfilter`, pbrt-v4 §8.8): box,
//! tent and Gaussian, applied by filter importance sampling (Ernst et al.
//! 2006; pbrt-v4's `FilterSampler`): each camera sample's offset from the
//! pixel centre is drawn from the filter's own density, so every sample
//! stays in its own pixel with weight one. A pixel is then the
//! filter-weighted mean of the radiance around it, and a render is the same
//! for any thread count, across resume and across shards, because no sample
//! is ever shared between pixels.
//!
//! The filters are separable, `f(x, y) = f(x) f(y)`; one uniform number per
//! axis is warped through the inverse of the 1D filter's CDF.

use crate::math::Vec2;

/// Bins of the tabulated CDF a Gaussian is sampled from (the density is
/// constant within a bin).
const GAUSSIAN_TABLE: usize = 512;

/// A separable pixel filter.
#[derive(Clone, Debug, PartialEq)]
pub enum PixelFilter {
    /// Constant over `[−radius, radius]²` (radius 0.5: the pixel itself).
    Box {
        /// Half width in pixels.
        radius: f32,
    },
    /// `max(0, 1 − |x| / radius)` per axis.
    Tent {
        /// Half width in pixels.
        radius: f32,
    },
    /// Mitsuba's Gaussian: `max(0, e^{−x²/2σ²} − e^{−r²/2σ²})` per axis with
    /// `r = 4σ`.
    Gaussian {
        /// Standard deviation σ in pixels.
        stddev: f32,
        /// The CDF of one axis over `GAUSSIAN_TABLE` equal bins of
        /// `[−r, r]` (`GAUSSIAN_TABLE + 1` values from 0 to 1).
        cdf: Vec<f32>,
    },
}

impl Default for PixelFilter {
    /// The box of one pixel: uniform jitter within the pixel.
    fn default() -> Self {
        PixelFilter::Box { radius: 0.5 }
    }
}

impl PixelFilter {
    /// Mitsuba's default radii: a box of 0.5, a tent of 1.
    pub const DEFAULT_BOX_RADIUS: f32 = 0.5;
    /// Mitsuba's default tent radius.
    pub const DEFAULT_TENT_RADIUS: f32 = 1.0;
    /// Mitsuba's default Gaussian standard deviation.
    pub const DEFAULT_STDDEV: f32 = 0.5;

    /// A Gaussian of standard deviation `stddev` (> 0) pixels.
    pub fn gaussian(stddev: f32) -> Self {
        let radius = 4.0 * stddev;
        let alpha = -1.0 / (2.0 * stddev as f64 * stddev as f64);
        let bias = (alpha * radius as f64 * radius as f64).exp();
        let eval = |x: f64| ((alpha * x * x).exp() - bias).max(0.0);
        // The filter's mass over each of GAUSSIAN_TABLE equal bins (midpoint
        // rule on 8 points a bin), summed into a CDF: the density sampled is
        // then the filter averaged over bins of r/256 pixels.
        let h = 2.0 * radius as f64 / GAUSSIAN_TABLE as f64;
        let mut cdf = Vec::with_capacity(GAUSSIAN_TABLE + 1);
        cdf.push(0.0f64);
        for i in 0..GAUSSIAN_TABLE {
            let x0 = -(radius as f64) + i as f64 * h;
            let mass: f64 = (0..8).map(|k| eval(x0 + (k as f64 + 0.5) * h / 8.0)).sum();
            cdf.push(cdf[i] + mass);
        }
        let total = cdf[GAUSSIAN_TABLE];
        let cdf = cdf.iter().map(|c| (c / total) as f32).collect();
        PixelFilter::Gaussian { stddev, cdf }
    }

    /// The filter's name in scene files.
    pub fn name(&self) -> &'static str {
        match self {
            PixelFilter::Box { .. } => "box",
            PixelFilter::Tent { .. } => "tent",
            PixelFilter::Gaussian { .. } => "gaussian",
        }
    }

    /// Half width of the support in pixels.
    pub fn radius(&self) -> f32 {
        match self {
            PixelFilter::Box { radius } | PixelFilter::Tent { radius } => *radius,
            PixelFilter::Gaussian { stddev, .. } => 4.0 * stddev,
        }
    }

    /// The one-pixel box: camera samples stay uniform in their pixel (the
    /// rays of every render before filters existed).
    pub fn is_pixel_box(&self) -> bool {
        matches!(self, PixelFilter::Box { radius } if *radius == 0.5)
    }

    /// The sample position within the pixel's `[0, 1)²` frame (it may leave
    /// the square when the filter is wider than a pixel) for the uniform
    /// numbers `u ∈ [0, 1)²`. The one-pixel box returns `u` unchanged.
    #[inline]
    pub fn sample(&self, u: Vec2) -> Vec2 {
        match self {
            PixelFilter::Box { radius } if *radius == 0.5 => u,
            _ => Vec2::new(0.5 + self.sample_axis(u.x), 0.5 + self.sample_axis(u.y)),
        }
    }

    /// Offset from the pixel centre on one axis, distributed as the filter.
    fn sample_axis(&self, u: f32) -> f32 {
        match self {
            PixelFilter::Box { radius } => (2.0 * u - 1.0) * radius,
            // Inverse CDF of the triangle on [−r, r] (pbrt-v4 `SampleTent`).
            PixelFilter::Tent { radius } => {
                if u < 0.5 {
                    radius * ((2.0 * u).sqrt() - 1.0)
                } else {
                    radius * (1.0 - (2.0 - 2.0 * u).max(0.0).sqrt())
                }
            }
            PixelFilter::Gaussian { stddev, cdf } => {
                let i = cdf.partition_point(|&c| c <= u).clamp(1, cdf.len() - 1) - 1;
                let span = cdf[i + 1] - cdf[i];
                let t = if span > 0.0 {
                    ((u - cdf[i]) / span).clamp(0.0, 1.0)
                } else {
                    0.5
                };
                let r = 4.0 * stddev;
                -r + (i as f32 + t) * (2.0 * r / (cdf.len() - 1) as f32)
            }
        }
    }

    /// The filter's value at offset `x` on one axis (unnormalised).
    pub fn eval_axis(&self, x: f32) -> f32 {
        match self {
            PixelFilter::Box { radius } => f32::from(x.abs() <= *radius),
            PixelFilter::Tent { radius } => (1.0 - x.abs() / radius).max(0.0),
            PixelFilter::Gaussian { stddev, .. } => {
                let alpha = -1.0 / (2.0 * stddev * stddev);
                let r = 4.0 * stddev;
                ((alpha * x * x).exp() - (alpha * r * r).exp()).max(0.0)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Histogram of `n` stratified samples of one axis against the
    /// filter's normalised integral over each bin.
    fn check_distribution(filter: &PixelFilter) {
        let r = filter.radius();
        let bins = 32;
        let n = 200_000;
        let mut hist = vec![0u32; bins];
        for i in 0..n {
            let u = (i as f32 + 0.5) / n as f32;
            let x = filter.sample_axis(u);
            assert!(x.abs() <= r * 1.0001, "{x} outside ±{r}");
            let b = (((x + r) / (2.0 * r)) * bins as f32) as usize;
            hist[b.min(bins - 1)] += 1;
        }
        // Expected mass per bin by a fine midpoint rule.
        let fine = 200;
        let mut mass = vec![0.0f64; bins];
        for (b, m) in mass.iter_mut().enumerate() {
            for k in 0..fine {
                let x = -r + (b as f32 + (k as f32 + 0.5) / fine as f32) * 2.0 * r / bins as f32;
                *m += filter.eval_axis(x) as f64;
            }
        }
        let total: f64 = mass.iter().sum();
        for (b, (&h, m)) in hist.iter().zip(&mass).enumerate() {
            let expected = m / total * n as f64;
            assert!(
                (h as f64 - expected).abs() <= 0.01 * n as f64 / bins as f64 + 2.0,
                "{} bin {b}: {h} samples, expected {expected:.1}",
                filter.name()
            );
        }
    }

    #[test]
    fn samples_follow_each_filter() {
        check_distribution(&PixelFilter::Box { radius: 0.5 });
        check_distribution(&PixelFilter::Box { radius: 1.5 });
        check_distribution(&PixelFilter::Tent { radius: 1.0 });
        check_distribution(&PixelFilter::Tent { radius: 2.0 });
        check_distribution(&PixelFilter::gaussian(0.5));
        check_distribution(&PixelFilter::gaussian(1.25));
    }

    #[test]
    fn tent_variance_is_r2_over_6() {
        let f = PixelFilter::Tent { radius: 2.0 };
        let n = 100_000;
        let var: f64 = (0..n)
            .map(|i| {
                let x = f.sample_axis((i as f32 + 0.5) / n as f32) as f64;
                x * x
            })
            .sum::<f64>()
            / n as f64;
        assert!((var - 4.0 / 6.0).abs() < 1e-3, "{var}");
    }

    #[test]
    fn the_pixel_box_leaves_samples_unchanged() {
        let u = Vec2::new(0.123, 0.987);
        assert_eq!(PixelFilter::default().sample(u), u);
        assert!(PixelFilter::default().is_pixel_box());
        assert!(!PixelFilter::Tent { radius: 0.5 }.is_pixel_box());
    }

    #[test]
    fn gaussian_is_symmetric_and_centred() {
        let f = PixelFilter::gaussian(0.5);
        assert!(f.sample_axis(0.5).abs() < 1e-4);
        for u in [0.01f32, 0.1, 0.3] {
            assert!((f.sample_axis(u) + f.sample_axis(1.0 - u)).abs() < 1e-4, "{u}");
        }
        assert!((f.sample_axis(0.0) + 2.0).abs() < 1e-6);
    }
}
