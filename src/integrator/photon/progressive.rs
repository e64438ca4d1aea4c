//! Progressive photon mapping (Knaus & Zwicker 2011, "Progressive Photon
//! Mapping: A Probabilistic Approach", ACM TOG 30(3)): a sequence of
//! independent photon maps, each gathered within a fixed radius that
//! shrinks from one map to the next, whose estimates are averaged.
//!
//! **Schedule.** Sample index `s = 0, 1, …` of every pixel is Knaus &
//! Zwicker's step `i = s + 1`. It gathers from its own map of
//! [`photons_per_pass`] photons (`max(1, count / spp)`, so that a pixel's
//! samples together see `count` photons), photon `j` of it drawing from
//! `Rng::new(seed, Domain::Photon, j, 1 + s)` ([`photon_stream`]; stream 0
//! is the non-progressive map), with the same Morton-stratified emission as
//! any map. Its gather radius is fixed (every photon within `r_i` counts):
//!
//! `r_1 = max_radius`, `r_{i+1}² = r_i² (i + α)/(i + 1)` (their eq. 15),
//!
//! i.e. `r_i² = r_1² Γ(i + α) / (Γ(1 + α) Γ(i + 1)) ~ r_1² i^(α−1) / Γ(1 + α)`.
//! With `α ∈ (0, 1)` the estimate's variance grows as `1/r_i² ~ i^(1−α)`,
//! slower than `i`, and its bias (the kernel's blur) falls as `r_i² → 0`:
//! the mean of the first `N` estimates has variance `O(N^(−α))` and bias
//! `O(N^(α−1))`, both vanishing (their §4). A pixel's running mean over its
//! samples is that mean, so the film converges to the caustic itself.
//!
//! The radius is computed by the recursion itself, in f64 (a product of
//! `s` factors), so every caller gets the same bits for the same `s`:
//! [`RadiusSequence`] steps through it, [`radius_squared`] jumps to `s`.
//!
//! Nothing here depends on an integrator: [`ProgressiveSchedule`] hands
//! out each sample index's map ([`ProgressiveSchedule::trace`]) and
//! [`GatherParams`] ([`ProgressiveSchedule::gather`], a
//! `fixed_radius`), which any integrator's gather takes.

use super::{build_photon_map, trace_photons_with, GatherParams, PhotonMap, PhotonRules, PhotonStats, TraceSettings};
use crate::accel::Accel;
use crate::scene::Scene;
use std::num::NonZero;

/// Photons each sample index's map emits: `count / spp` (integer
/// division), at least 1, so a pixel's `spp` samples see about `count`
/// photons in all.
pub fn photons_per_pass(count: u64, spp: u32) -> u64 {
    (count / u64::from(spp.max(1))).max(1)
}

/// The fourth key of the photon streams of sample index `sample`'s map:
/// `1 + sample` (stream 0 is the non-progressive caustic map).
pub fn photon_stream(sample: u32) -> u64 {
    1 + u64::from(sample)
}

/// `r_{s+1}²`, the squared gather radius of sample index `s`, from
/// `r_1 = r1` by Knaus & Zwicker's recursion `r_{i+1}² = r_i² (i + α)/(i + 1)`
/// (`s` steps, in f64).
pub fn radius_squared(r1: f32, alpha: f32, sample: u32) -> f32 {
    let mut seq = RadiusSequence::new(r1, alpha);
    for _ in 0..sample {
        seq.advance();
    }
    seq.radius_squared()
}

/// Knaus & Zwicker's radius sequence, stepped one sample index at a time:
/// the same bits as [`radius_squared`] at every step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RadiusSequence {
    /// `i` of the current radius `r_i` (1 for `r_1`).
    i: u64,
    /// `r_i²`.
    r2: f64,
    alpha: f64,
}

impl RadiusSequence {
    /// Starts at `r_1 = r1` (sample index 0).
    pub fn new(r1: f32, alpha: f32) -> Self {
        Self {
            i: 1,
            r2: f64::from(r1) * f64::from(r1),
            alpha: f64::from(alpha),
        }
    }

    /// Sample index of the current radius (`i − 1`).
    pub fn sample(&self) -> u64 {
        self.i - 1
    }

    /// The current `r_i²`.
    pub fn radius_squared(&self) -> f32 {
        self.r2 as f32
    }

    /// The current `r_i` (the square root of [`radius_squared`](Self::radius_squared)).
    pub fn radius(&self) -> f32 {
        self.radius_squared().sqrt()
    }

    /// Steps to `r_{i+1}² = r_i² (i + α)/(i + 1)`.
    pub fn advance(&mut self) {
        let i = self.i as f64;
        self.r2 *= (i + self.alpha) / (i + 1.0);
        self.i += 1;
    }
}

/// What progressive photon mapping needs to trace and gather the map of any
/// sample index: resolved once from the render plan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProgressiveSchedule {
    /// `r_1`, the first sample index's gather radius.
    pub r1: f32,
    /// Knaus & Zwicker's `α ∈ (0, 1)`.
    pub alpha: f32,
    /// Photons each map emits ([`photons_per_pass`]).
    pub photons_per_pass: u64,
    /// Cone-filter constant of the gather.
    pub cone_k: f32,
    /// Keep coarse photon positions (the `--debug photons` overlay).
    pub keep_positions: bool,
    /// How the photons scatter (the integrator's rules).
    pub rules: PhotonRules,
    /// The seed and bounce limit of the tracing.
    pub settings: TraceSettings,
}

impl ProgressiveSchedule {
    /// Traces sample index `sample`'s map on the current rayon pool
    /// (deterministic for any thread count): [`photons_per_pass`] photons
    /// from stream [`photon_stream`]`(sample)`, no precomputed irradiance.
    pub fn trace(&self, scene: &Scene, accel: &dyn Accel, sample: u32) -> (PhotonMap, PhotonStats) {
        let traced = trace_photons_with(
            scene,
            self.settings,
            accel,
            self.photons_per_pass,
            false,
            self.rules,
            photon_stream(sample),
        );
        // The path integrator's maps (physical rules) are gathered within
        // this sample index's radius: a grid answers those gathers.
        let grid_radius =
            (self.rules == PhotonRules::Physical).then(|| radius_squared(self.r1, self.alpha, sample).sqrt());
        build_photon_map(traced, None, self.keep_positions, grid_radius)
    }

    /// The gather of the sample index whose radius `seq` holds: every
    /// photon within `r_i`, cone-filtered.
    pub fn gather_at(&self, seq: &RadiusSequence) -> GatherParams {
        let r = seq.radius();
        GatherParams {
            k: NonZero::<usize>::MIN,
            max_radius: r,
            cone_k: self.cone_k,
            fixed_radius: Some(r),
        }
    }

    /// The gather of sample index `sample` ([`radius_squared`]).
    pub fn gather(&self, sample: u32) -> GatherParams {
        let mut seq = RadiusSequence::new(self.r1, self.alpha);
        for _ in 0..sample {
            seq.advance();
        }
        self.gather_at(&seq)
    }

    /// The radius sequence positioned at sample index `sample`.
    pub fn radii_from(&self, sample: u32) -> RadiusSequence {
        let mut seq = RadiusSequence::new(self.r1, self.alpha);
        for _ in 0..sample {
            seq.advance();
        }
        seq
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ln Γ(x) for x > 0 (Lanczos, g = 7, 9 terms: ~1e-15 relative).
    fn ln_gamma(x: f64) -> f64 {
        const G: [f64; 9] = [
            0.999_999_999_999_809_9,
            676.520_368_121_885_1,
            -1_259.139_216_722_402_8,
            771.323_428_777_653_1,
            -176.615_029_162_140_6,
            12.507_343_278_686_905,
            -0.138_571_095_265_720_12,
            9.984_369_578_019_572e-6,
            1.505_632_735_149_311_6e-7,
        ];
        if x < 0.5 {
            let pi = std::f64::consts::PI;
            return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
        }
        let x = x - 1.0;
        let mut a = G[0];
        let t = x + 7.5;
        for (i, g) in G.iter().enumerate().skip(1) {
            a += g / (x + i as f64);
        }
        0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
    }

    #[test]
    fn radius_sequence_follows_the_recursion_and_the_closed_form() {
        for alpha in [0.1f32, 0.5, 2.0 / 3.0, 0.9] {
            let r1 = 0.25f32;
            let a = f64::from(alpha);
            let mut seq = RadiusSequence::new(r1, alpha);
            let mut previous = f64::INFINITY;
            for s in 0..5000u32 {
                assert_eq!(seq.sample(), u64::from(s));
                let r2 = f64::from(seq.radius_squared());
                // The same bits whichever way it is reached.
                assert_eq!(seq.radius_squared(), radius_squared(r1, alpha, s));
                // Recursion: r_{i+1}² / r_i² = (i + α)/(i + 1).
                if s > 0 {
                    let i = f64::from(s);
                    assert!((r2 / previous - (i + a) / (i + 1.0)).abs() < 1e-6, "α {alpha}, s {s}");
                }
                // Closed form r_i² = r_1² Γ(i + α) / (Γ(1 + α) Γ(i + 1)).
                let i = f64::from(s) + 1.0;
                let closed = f64::from(r1).powi(2) * (ln_gamma(i + a) - ln_gamma(1.0 + a) - ln_gamma(i + 1.0)).exp();
                assert!((r2 / closed - 1.0).abs() < 1e-5, "α {alpha}, i {i}: {r2} vs {closed}");
                // Strictly decreasing.
                assert!(r2 < previous, "α {alpha}, s {s}");
                previous = r2;
                seq.advance();
            }
            assert_eq!(radius_squared(r1, alpha, 0), r1 * r1);
            // r_i² ~ r_1² i^(α−1) / Γ(1 + α): the ratio tends to 1.
            let i = 5000.0f64;
            let asymptote = f64::from(r1).powi(2) * i.powf(a - 1.0) / ln_gamma(1.0 + a).exp();
            let ratio = previous / asymptote;
            assert!(
                (ratio - 1.0).abs() < 1e-3,
                "α {alpha}: r_i² / (r_1² i^(α−1)/Γ(1+α)) = {ratio}"
            );
            // And → 0: far down the sequence the radius is a fraction of r_1.
            assert!(radius_squared(r1, alpha, 1_000_000) < 0.3 * r1 * r1, "α {alpha}");
        }
    }

    #[test]
    fn photons_are_shared_over_the_samples() {
        assert_eq!(photons_per_pass(1_000_000, 16), 62_500);
        assert_eq!(photons_per_pass(1_000, 3), 333);
        assert_eq!(photons_per_pass(5, 64), 1);
        assert_eq!(photons_per_pass(5, 0), 5);
        assert_eq!(photon_stream(0), 1);
        assert_ne!(photon_stream(7), photon_stream(8));
    }

    #[test]
    fn gather_is_fixed_radius() {
        let schedule = ProgressiveSchedule {
            r1: 0.5,
            alpha: 0.5,
            photons_per_pass: 10,
            cone_k: 1.1,
            keep_positions: false,
            rules: PhotonRules::Whitted,
            settings: TraceSettings {
                seed: 0,
                max_depth: None,
            },
        };
        let g0 = schedule.gather(0);
        assert_eq!(g0.fixed_radius, Some(0.5));
        let g1 = schedule.gather(1);
        // r_2² = r_1² (1 + α)/2.
        assert!((g1.fixed_radius.unwrap().powi(2) - 0.25 * 0.75).abs() < 1e-7);
        assert_eq!(schedule.gather_at(&schedule.radii_from(9)), schedule.gather(9));
    }
}
