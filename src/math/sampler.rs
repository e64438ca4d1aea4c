//! The random numbers of one pixel sample: either independent (the
//! sample's own PCG stream) or low-discrepancy (Owen-scrambled Sobol points,
//! Burley 2020, "Practical Hash-based Owen Scrambling", through the
//! `sobol_burley` crate: the sampler of Cycles and Psychopath).
//!
//! Every value is a pure function of (seed, pixel, sample index, dimension),
//! so images do not depend on threads, passes, interrupts or shards. With
//! Sobol, sample `k` of a pixel takes point `k` of that pixel's scrambled
//! sequence; successive calls walk the dimensions (2 for the sub-pixel
//! position, then whatever the integrator draws). Beyond 2¹⁶ samples, and
//! beyond the crate's 256 dimensions, further blocks are independently
//! scrambled sequences (still stratified within a block, still unbiased).

use super::rng::{mix64, Rng};
use super::Vec2;

/// Which numbers a sampler draws.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SamplerKind {
    /// Independent uniform numbers from each sample's own PCG stream.
    Independent,
    /// Owen-scrambled Sobol points.
    #[default]
    Sobol,
}

impl SamplerKind {
    /// Name as in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            SamplerKind::Independent => "independent",
            SamplerKind::Sobol => "sobol",
        }
    }
}

const SOBOL_SAMPLES: u64 = 1 << 16;
const SOBOL_DIMENSIONS: u32 = sobol_burley::NUM_DIMENSIONS;
const SOBOL_SETS: usize = sobol_burley::NUM_DIMENSION_SETS_4D as usize;

/// One dimension set's combined direction vectors: `[nibble][value][lane]`.
type NibbleVectors = [[[u32; 4]; 16]; 4];

/// The Sobol direction vectors of each set of four dimensions, combined a
/// nibble of the (bit-reversed, 16-bit) sample index at a time: entry
/// `[set][n][v]` is the XOR of the vectors that the bits of `v` select in
/// nibble `n`. Four table reads then replace the crate's loop over the
/// index's set bits (with its unpredictable trip count) and give the same
/// bits. 64 KiB, built once.
static NIBBLE_VECTORS: std::sync::LazyLock<Box<[NibbleVectors]>> = std::sync::LazyLock::new(|| {
    (0..SOBOL_SETS)
        .map(|set| {
            std::array::from_fn(|n| {
                std::array::from_fn(|v| {
                    let index_rev = (v as u32) << (28 - 4 * n);
                    sobol_burley::parts::sobol_int4_rev(index_rev, set as u32).into()
                })
            })
        })
        .collect()
});

/// Point `index_rev` (the scrambled, bit-reversed sample index) of
/// dimension set `set`, Owen-scrambled under `seed`: bit for bit
/// `sobol_burley::sample_4d`, with the index's scramble done once per
/// sample by the caller.
#[cfg(test)]
fn sobol_4d(index_rev: u32, set: u32, seed: u32) -> [f32; 4] {
    sobol_4d_hashed(index_rev, set, set_scramble(seed, set))
}

/// The hashed Owen-scramble key of dimension set `set` under `seed`, as
/// `sobol_burley::sample_4d` derives it: a function of the pixel's seed and
/// the set alone, so the same for every sample of a pixel.
#[inline]
fn set_scramble(seed: u32, set: u32) -> [u32; 4] {
    use sobol_burley::parts::{hash_int4, Int4};
    // As the crate: the multiply on `seed` avoids cancellation with `set`.
    let scramble = {
        let seed: Int4 = [seed.wrapping_mul(0x9c8f2d3b); 4].into();
        let ds: Int4 = [set; 4].into();
        seed ^ ds ^ [0x912f69ba, 0x174f18ab, 0x691e72ca, 0xb40cc1b8].into()
    };
    hash_int4(scramble).into()
}

/// Point `index_rev` of dimension set `set`, Owen-scrambled with the
/// set's hashed key `scramble` ([`set_scramble`]).
#[inline]
fn sobol_4d_hashed(index_rev: u32, set: u32, scramble: [u32; 4]) -> [f32; 4] {
    use sobol_burley::parts::{owen_scramble_rev, Int4};
    let table = &NIBBLE_VECTORS[set as usize];
    let mut v = [0u32; 4];
    for (n, nibbles) in table.iter().enumerate() {
        let entry = &nibbles[((index_rev >> (28 - 4 * n)) & 15) as usize];
        for lane in 0..4 {
            v[lane] ^= entry[lane];
        }
    }
    // The Owen scramble one lane at a time: the crate's four-lane form is
    // the same arithmetic, but baseline x86-64 (SSE2) has no 32-bit lane
    // multiply, and its emulation costs more than four scalar `imul`s
    // (callgrind: 165 → 152 instructions per refill).
    let scrambled: [u32; 4] = std::array::from_fn(|lane| owen_scramble_rev(v[lane], scramble[lane]));
    Int4::from(scrambled).reverse_bits().to_f32_norm()
}

/// The scramble of the sample index under `seed`, as
/// `sobol_burley::sample_4d` shuffles the index.
#[inline]
fn index_scramble(seed: u32) -> u32 {
    sobol_burley::parts::hash(seed ^ 0x79c68e4a)
}

/// The scrambled, bit-reversed index of sample `index` under `seed`, as
/// `sobol_burley::sample_4d` shuffles it: the same for every dimension of
/// the sample.
#[inline]
fn shuffled_index_rev(index: u32, seed: u32) -> u32 {
    sobol_burley::parts::owen_scramble_rev(index.reverse_bits(), index_scramble(seed))
}

/// Dimension sets (of four dimensions) whose hashed scramble keys a Sobol
/// sampler keeps across the samples of its pixel: the first 64 dimensions,
/// about nine bounces of a path.
const KEPT_SETS: usize = 16;

/// The numbers of one pixel sample.
///
/// [`restart`](Self::restart) re-keys a sampler to another sample of the
/// same pixel, keeping what depends on the pixel alone (its scramble seed,
/// the index shuffle's key, the hashed keys of the first [`KEPT_SETS`]
/// dimension sets), so a pixel's samples do not derive them again.
#[derive(Clone, Debug)]
pub struct Sampler {
    kind: SamplerKind,
    /// The render's seed.
    render_seed: u64,
    /// The pixel (the random streams' key).
    pixel: u64,
    /// Block of 2¹⁶ samples that `seed` and the kept keys belong to
    /// (`u64::MAX` before the first sample).
    block: u64,
    /// Scrambling seed of this pixel and block of samples.
    seed: u32,
    /// [`index_scramble`] of `seed`.
    index_scramble: u32,
    /// Index within the block of 2¹⁶ samples, scrambled under `seed` and
    /// bit-reversed (the first block of dimensions' shuffle).
    index_rev: u32,
    /// Index within the block of 2¹⁶ samples.
    index: u32,
    /// Next dimension.
    dimension: u32,
    /// Dimensions `4·(dimension/4) ..` of the current point, computed four
    /// at a time (`sobol_burley::sample_4d`, SIMD on x86-64).
    batch: [f32; 4],
    /// How many of `set_scrambles` hold their set's key under `seed`.
    kept_sets: u32,
    /// [`set_scramble`] of `seed` and each of the first [`KEPT_SETS`]
    /// dimension sets, filled as the samples first reach them.
    set_scrambles: [[u32; 4]; KEPT_SETS],
    /// The independent stream (also the one `Rng`-based code keeps using).
    rng: Rng,
}

impl Sampler {
    /// Sample `sample` of pixel `pixel` under `seed`.
    pub fn new(kind: SamplerKind, seed: u64, pixel: u64, sample: u64) -> Self {
        // The stream is never drawn from with Sobol, which draws every number.
        let mut sampler = Self::unkeyed(kind, seed, pixel, Rng::from_state(0));
        sampler.restart(sample);
        sampler
    }

    /// A sampler of `pixel` under `render_seed` that no sample has keyed
    /// yet, drawing independent numbers from `rng`.
    fn unkeyed(kind: SamplerKind, render_seed: u64, pixel: u64, rng: Rng) -> Self {
        Self {
            kind,
            render_seed,
            pixel,
            block: u64::MAX,
            seed: 0,
            index_scramble: 0,
            index_rev: 0,
            index: 0,
            dimension: 0,
            batch: [0.0; 4],
            kept_sets: 0,
            set_scrambles: [[0; 4]; KEPT_SETS],
            rng,
        }
    }

    /// Re-keys this sampler to sample `sample` of its pixel: the same
    /// numbers as `Sampler::new` for that sample, bit for bit. (A sampler
    /// made by [`independent`](Self::independent) restarts as pixel 0's
    /// under seed 0.)
    pub fn restart(&mut self, sample: u64) {
        self.dimension = 0;
        match self.kind {
            SamplerKind::Sobol => {
                let block = sample / SOBOL_SAMPLES;
                if block != self.block {
                    self.block = block;
                    self.seed = mix64(self.render_seed ^ mix64(self.pixel ^ mix64(block))) as u32;
                    self.index_scramble = index_scramble(self.seed);
                    self.kept_sets = 0;
                }
                self.index = (sample % SOBOL_SAMPLES) as u32;
                self.index_rev = sobol_burley::parts::owen_scramble_rev(self.index.reverse_bits(), self.index_scramble);
            }
            SamplerKind::Independent => self.rng = Rng::for_pixel(self.render_seed, self.pixel, sample),
        }
    }

    /// An independent sampler drawing from `rng`.
    pub fn independent(rng: Rng) -> Self {
        Self::unkeyed(SamplerKind::Independent, 0, 0, rng)
    }

    /// Which numbers this sampler draws.
    pub fn kind(&self) -> SamplerKind {
        self.kind
    }

    /// The next number in [0, 1).
    #[inline(always)]
    pub fn f32(&mut self) -> f32 {
        match self.kind {
            SamplerKind::Independent => self.rng.f32(),
            SamplerKind::Sobol => {
                let d = self.dimension;
                self.dimension += 1;
                if d.is_multiple_of(4) {
                    self.refill(d);
                }
                self.batch[(d % 4) as usize]
            }
        }
    }

    /// Computes dimensions `d .. d + 4` of the Sobol point (`d` a multiple
    /// of 4). Out of line: three draws in four only read `batch`, and
    /// inlining the scramble into every draw made each call save and
    /// restore the registers it needs (callgrind: ≈ 30 instructions of
    /// prologue and epilogue per draw).
    #[inline(never)]
    fn refill(&mut self, d: u32) {
        let (block, set) = (d / SOBOL_DIMENSIONS, (d % SOBOL_DIMENSIONS) / 4);
        self.batch = if block == 0 {
            let scramble = if set < self.kept_sets {
                self.set_scrambles[set as usize]
            } else {
                let key = set_scramble(self.seed, set);
                // A sample walks the sets in order: the first sample to
                // reach a set keeps its key for the pixel's later samples.
                if set == self.kept_sets && (set as usize) < KEPT_SETS {
                    self.set_scrambles[set as usize] = key;
                    self.kept_sets += 1;
                }
                key
            };
            sobol_4d_hashed(self.index_rev, set, scramble)
        } else {
            // Later blocks of dimensions: independently scrambled sequences.
            let seed = mix64(self.seed as u64 ^ mix64(block as u64)) as u32;
            sobol_4d_hashed(shuffled_index_rev(self.index, seed), set, set_scramble(seed, set))
        };
    }

    /// The next two numbers.
    #[inline]
    pub fn f32x2(&mut self) -> (f32, f32) {
        (self.f32(), self.f32())
    }

    /// The next point of [0, 1)².
    #[inline]
    pub fn vec2(&mut self) -> Vec2 {
        let (a, b) = self.f32x2();
        Vec2::new(a, b)
    }

    /// A uniform integer in `[0, n)` (`n > 0`), from one dimension.
    #[inline]
    pub fn below(&mut self, n: u32) -> u32 {
        ((self.f32() * n as f32) as u32).min(n - 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sobol_points_stratify_a_pixel_and_stay_uniform() {
        // 256 samples of one pixel: each 1/16 × 1/16 cell of the first two
        // dimensions holds exactly one (a (0, 2)-sequence in base 2).
        let mut cells = vec![0u32; 256];
        for k in 0..256 {
            let mut s = Sampler::new(SamplerKind::Sobol, 7, 1234, k);
            let (x, y) = s.f32x2();
            cells[(y * 16.0) as usize * 16 + (x * 16.0) as usize] += 1;
        }
        assert!(cells.iter().all(|&c| c == 1), "{cells:?}");
        // Deep dimensions (past the table) and later blocks stay in [0, 1)
        // with the right mean.
        let mut sum = 0.0f64;
        for k in 0..4096u64 {
            let mut s = Sampler::new(SamplerKind::Sobol, 3, 9, k + (1 << 16) * (k % 3));
            for _ in 0..300 {
                let v = s.f32();
                assert!((0.0..1.0).contains(&v));
                sum += v as f64;
            }
        }
        let mean = sum / (4096.0 * 300.0);
        assert!((mean - 0.5).abs() < 0.005, "{mean}");
    }

    #[test]
    fn table_sobol_matches_the_crate_bit_for_bit() {
        for seed in [0u32, 1, 0x9e37_79b9, u32::MAX] {
            for index in (0..1u32 << 16).step_by(97).chain([0, 1, 65535]) {
                let rev = shuffled_index_rev(index, seed);
                for set in 0..SOBOL_SETS as u32 {
                    assert_eq!(
                        sobol_4d(rev, set, seed).map(f32::to_bits),
                        sobol_burley::sample_4d(index, set, seed).map(f32::to_bits),
                        "seed {seed} index {index} set {set}"
                    );
                }
            }
        }
    }

    #[test]
    fn samplers_are_pure_functions_of_their_keys() {
        for kind in [SamplerKind::Independent, SamplerKind::Sobol] {
            let draw = |pixel, k| {
                let mut s = Sampler::new(kind, 5, pixel, k);
                (0..10).map(|_| s.f32()).collect::<Vec<_>>()
            };
            assert_eq!(draw(3, 17), draw(3, 17));
            assert_ne!(draw(3, 17), draw(4, 17));
            assert_ne!(draw(3, 17), draw(3, 18));
        }
    }

    #[test]
    fn a_restarted_sampler_draws_what_a_new_one_draws() {
        // Samples of one pixel in and out of order, across blocks of 2¹⁶
        // samples, each deep enough to pass the kept sets and the first
        // block of dimensions.
        let samples = [0u64, 1, 2, 7, 3, 65_535, 65_536, 65_537, 5, 1 << 20, 4];
        for kind in [SamplerKind::Independent, SamplerKind::Sobol] {
            let mut restarted = Sampler::new(kind, 11, 42, 9);
            for (i, &k) in samples.iter().enumerate() {
                let depth = [3, 70, 300, 1][i % 4];
                restarted.restart(k);
                let mut fresh = Sampler::new(kind, 11, 42, k);
                for _ in 0..depth {
                    assert_eq!(restarted.f32().to_bits(), fresh.f32().to_bits(), "{kind:?} sample {k}");
                }
            }
        }
    }
}
