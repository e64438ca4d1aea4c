//! Seeded random streams. Every pixel sample and every photon draws from its
//! own PCG32 stream keyed by (seed, index), so the image does not depend on
//! the number of threads or on the order work is scheduled.

use rand_core::RngCore;
use rand_pcg::Pcg32;

/// SplitMix64 finaliser (Steele et al. 2014): decorrelates nearby keys.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A deterministic random stream.
#[derive(Clone, Debug)]
pub struct Rng(Pcg32);

/// Domains keep streams of different passes apart even for equal indices.
#[derive(Clone, Copy, Debug)]
#[repr(u64)]
pub enum Domain {
    /// Camera samples (pixel index, sample index).
    Pixel = 1,
    /// Photon emission (photon index).
    Photon = 2,
    /// Tests, cross-checks and benchmarks.
    Analysis = 3,
}

impl Rng {
    /// Stream for `(seed, domain, a, b)`.
    pub fn new(seed: u64, domain: Domain, a: u64, b: u64) -> Self {
        let state = mix64(seed ^ mix64(domain as u64 ^ mix64(a ^ mix64(b))));
        let stream = mix64(a.wrapping_mul(0x2545_F491_4F6C_DD1D) ^ b ^ ((domain as u64) << 56));
        Self(Pcg32::new(state, stream))
    }

    /// The stream of PCG state `state` (stream 0), with no hashing: for a
    /// placeholder that is never drawn from, or a fixed test stream.
    pub fn from_state(state: u64) -> Self {
        Self(Pcg32::new(state, 0))
    }

    /// Stream for one sample of one pixel.
    pub fn for_pixel(seed: u64, pixel: u64, sample: u64) -> Self {
        Self::new(seed, Domain::Pixel, pixel, sample)
    }

    /// Uniform f32 in [0, 1) with 24 random bits.
    #[inline]
    pub fn f32(&mut self) -> f32 {
        (self.0.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    /// Two uniform f32 in [0, 1).
    #[inline]
    pub fn f32x2(&mut self) -> (f32, f32) {
        (self.f32(), self.f32())
    }

    /// A uniform point of [0, 1)².
    #[inline]
    pub fn vec2(&mut self) -> glam::Vec2 {
        let (a, b) = self.f32x2();
        glam::Vec2::new(a, b)
    }

    /// Uniform u32.
    #[inline]
    pub fn u32(&mut self) -> u32 {
        self.0.next_u32()
    }

    /// Uniform u64.
    #[inline]
    pub fn u64(&mut self) -> u64 {
        ((self.0.next_u32() as u64) << 32) | self.0.next_u32() as u64
    }

    /// Uniform integer in [0, n) (n > 0), Lemire's multiply-shift.
    #[inline]
    pub fn below(&mut self, n: u32) -> u32 {
        ((self.0.next_u32() as u64 * n as u64) >> 32) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_deterministic_and_distinct() {
        let a: Vec<f32> = (0..4)
            .map(|_| 0.0)
            .scan(Rng::for_pixel(7, 3, 0), |r, _| Some(r.f32()))
            .collect();
        let b: Vec<f32> = (0..4)
            .map(|_| 0.0)
            .scan(Rng::for_pixel(7, 3, 0), |r, _| Some(r.f32()))
            .collect();
        let c: Vec<f32> = (0..4)
            .map(|_| 0.0)
            .scan(Rng::for_pixel(7, 4, 0), |r, _| Some(r.f32()))
            .collect();
        assert_eq!(a, b);
        assert_ne!(a, c);
        assert!(a.iter().all(|x| (0.0..1.0).contains(x)));
    }

    #[test]
    fn mean_is_one_half() {
        let mut r = Rng::new(1, Domain::Analysis, 0, 0);
        let mean: f64 = (0..100_000).map(|_| r.f32() as f64).sum::<f64>() / 100_000.0;
        assert!((mean - 0.5).abs() < 0.005);
    }
}
