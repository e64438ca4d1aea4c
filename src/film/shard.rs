//! Shards: one render split into `N` pieces that separate processes (on
//! separate machines) render independently, and the merge of their
//! partials back into one accumulation.
//!
//! Two ways to split ([`ShardMode`]):
//!
//! * **tiles**: the image is cut into [`SHARD_BLOCK`]² pixel blocks, and
//!   block `(bx, by)` belongs to shard `(bx + by) mod N`: diagonal stripes,
//!   so every shard gets a share of every part of the image and the costs
//!   balance. Each pixel is rendered by exactly one shard with the same
//!   samples as in a single process, so the merge copies per-pixel state and
//!   the merged image is **bit-identical** to a single-process render.
//! * **samples**: every shard renders every pixel, shard `i` the sample
//!   indices `⌊i·spp/N⌋ .. ⌊(i+1)·spp/N⌋`. Each sample is the same as in a
//!   single process; only the order of the f32 additions differs (the merge
//!   adds the shards' sums), so each pixel's mean is within
//!   [`samples_merge_bound`] (relative) of the single-process mean.
//!
//! A partial file (see `film::checkpoint`) records a [`ShardSet`]: the
//! mode, the count and which shard indices it holds (one after a render,
//! several after merging a subset, for tree reductions).

use super::accum::Accumulation;
use crate::math::{Vec3, Vec3A};
use std::fmt;
use std::ops::Range;

/// Edge in pixels of the blocks dealt out to the shards in tiles mode.
pub const SHARD_BLOCK: u32 = 8;

/// Most shards one render may be split into.
pub const MAX_SHARDS: u32 = 65_536;

/// How a render is split.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ShardMode {
    /// Disjoint pixel blocks per shard; the merge is bit-identical to one process.
    Tiles,
    /// Disjoint sample-index ranges of every pixel per shard.
    Samples,
}

impl ShardMode {
    /// The name used on the command line and in partial files.
    pub fn name(self) -> &'static str {
        match self {
            ShardMode::Tiles => "tiles",
            ShardMode::Samples => "samples",
        }
    }

    /// The mode of a name ([`name`](Self::name)).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "tiles" => Some(ShardMode::Tiles),
            "samples" => Some(ShardMode::Samples),
            _ => None,
        }
    }
}

/// Shard `index` of `count`, before a mode is chosen: what `--shard I/N`
/// or a scheduler's environment gives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShardId {
    /// Zero-based index, `< count`.
    pub index: u32,
    /// Number of shards, `1..=MAX_SHARDS`.
    pub count: u32,
}

impl ShardId {
    /// Checks `index < count ≤ MAX_SHARDS`.
    pub fn new(index: u32, count: u32) -> Result<Self, String> {
        if count == 0 || count > MAX_SHARDS {
            return Err(format!("shard count {count}: must be in 1..={MAX_SHARDS}"));
        }
        if index >= count {
            return Err(format!(
                "shard index {index} of {count}: must be in 0..={} (indices start at 0)",
                count - 1
            ));
        }
        Ok(Self { index, count })
    }

    /// Parses `I/N` (zero-based `I`).
    pub fn parse(text: &str) -> Result<Self, String> {
        let bad = || format!("shard {text:?}: expected I/N with 0 ≤ I < N, such as 0/4, or auto");
        let (i, n) = text.split_once('/').ok_or_else(bad)?;
        let i: u32 = i.trim().parse().map_err(|_| bad())?;
        let n: u32 = n.trim().parse().map_err(|_| bad())?;
        Self::new(i, n)
    }
}

impl fmt::Display for ShardId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// The shards a partial holds: a mode, the count the render was split
/// into, and the indices (sorted, distinct).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShardSet {
    /// How the render was split.
    pub mode: ShardMode,
    /// Shards of the whole render.
    pub count: u32,
    /// Indices held, sorted and distinct, each `< count`.
    pub indices: Vec<u32>,
}

impl ShardSet {
    /// One shard.
    pub fn single(id: ShardId, mode: ShardMode) -> Self {
        Self {
            mode,
            count: id.count,
            indices: vec![id.index],
        }
    }

    /// True when every shard of the render is held.
    pub fn is_whole(&self) -> bool {
        self.indices.len() == self.count as usize
    }

    /// The shard owning pixel `(x, y)` in tiles mode.
    pub fn tile_owner(count: u32, x: u32, y: u32) -> u32 {
        ((x / SHARD_BLOCK) as u64 + (y / SHARD_BLOCK) as u64).rem_euclid(count as u64) as u32
    }

    /// True when this set renders pixel `(x, y)` (always in samples mode).
    pub fn owns_pixel(&self, x: u32, y: u32) -> bool {
        match self.mode {
            ShardMode::Samples => true,
            ShardMode::Tiles => self.indices.binary_search(&Self::tile_owner(self.count, x, y)).is_ok(),
        }
    }

    /// Per pixel (row-major), whether this set renders it.
    pub fn pixel_mask(&self, width: u32, height: u32) -> Vec<bool> {
        (0..height)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .map(|(x, y)| self.owns_pixel(x, y))
            .collect()
    }

    /// The sample indices of shard `index` (samples mode; every index in
    /// tiles mode).
    pub fn sample_range(mode: ShardMode, count: u32, index: u32, spp: u32) -> Range<u32> {
        match mode {
            ShardMode::Tiles => 0..spp,
            ShardMode::Samples => {
                let at = |i: u32| (i as u64 * spp as u64 / count as u64) as u32;
                at(index)..at(index + 1)
            }
        }
    }

    /// Samples this set renders per pixel it owns.
    pub fn samples_per_pixel(&self, spp: u32) -> u32 {
        match self.mode {
            ShardMode::Tiles => spp,
            ShardMode::Samples => self
                .indices
                .iter()
                .map(|&i| Self::sample_range(self.mode, self.count, i, spp).len() as u32)
                .sum(),
        }
    }

    /// Samples this set renders over a `width × height` image.
    pub fn total_samples(&self, width: u32, height: u32, spp: u32) -> u64 {
        let pixels = self.pixel_mask(width, height).iter().filter(|&&m| m).count() as u64;
        pixels * self.samples_per_pixel(spp) as u64
    }

    /// The indices as text: ranges such as `0-3,5,7-9`.
    pub fn indices_text(&self) -> String {
        let mut parts = Vec::new();
        let mut i = 0;
        while i < self.indices.len() {
            let mut j = i;
            while j + 1 < self.indices.len() && self.indices[j + 1] == self.indices[j] + 1 {
                j += 1;
            }
            parts.push(if i == j {
                self.indices[i].to_string()
            } else {
                format!("{}-{}", self.indices[i], self.indices[j])
            });
            i = j + 1;
        }
        parts.join(",")
    }

    /// Parses [`indices_text`](Self::indices_text), checking each index
    /// `< count`, sorted and distinct.
    pub fn parse_indices(text: &str, count: u32) -> Result<Vec<u32>, String> {
        let mut out: Vec<u32> = Vec::new();
        for part in text.split(',') {
            let bad = || format!("shard indices {text:?}: {part:?} is not an index or a range a-b");
            let (a, b) = match part.split_once('-') {
                Some((a, b)) => (a.parse().map_err(|_| bad())?, b.parse().map_err(|_| bad())?),
                None => {
                    let a: u32 = part.parse().map_err(|_| bad())?;
                    (a, a)
                }
            };
            if a > b || b >= count || out.last().is_some_and(|&l| l >= a) {
                return Err(format!(
                    "shard indices {text:?}: not increasing indices below the count {count}"
                ));
            }
            out.extend(a..=b);
        }
        Ok(out)
    }

    /// The first sample index of pixels in a partial of this set that has
    /// not started (samples mode: the range start of a single shard).
    pub fn first_sample(&self, spp: u32) -> u32 {
        Self::sample_range(self.mode, self.count, self.indices[0], spp).start
    }

    /// The sample index every pixel this set owns reaches when complete
    /// (the end of its last range).
    pub fn last_sample(&self, spp: u32) -> u32 {
        Self::sample_range(self.mode, self.count, *self.indices.last().expect("non-empty"), spp).end
    }

    /// The accumulation a render of this single shard starts from: pixels
    /// of other shards are marked converged (the render loop skips them),
    /// and in samples mode every pixel starts at the shard's first sample
    /// index with empty sums.
    pub fn start_accumulation(&self, width: u32, height: u32, spp: u32) -> Accumulation {
        let mut acc = Accumulation::new(width, height);
        self.prepare_for_render(&mut acc, spp);
        acc
    }

    /// Marks the pixels of other shards converged, and in samples mode
    /// brings untouched pixels to the shard's first sample index: what the
    /// render loop continues (also for a resumed partial).
    pub fn prepare_for_render(&self, acc: &mut Accumulation, spp: u32) {
        let mask = self.pixel_mask(acc.width, acc.height);
        let first = self.first_sample(spp);
        for (i, owned) in mask.into_iter().enumerate() {
            if !owned {
                acc.converged[i] = true;
            } else if self.mode == ShardMode::Samples {
                acc.taken[i] = acc.taken[i].max(first);
            }
        }
    }

    /// The accumulation as a partial file stores it: the pixels of other
    /// shards cleared (no samples, not converged).
    pub fn for_file(&self, acc: &Accumulation) -> Accumulation {
        let mut out = acc.clone();
        for (i, owned) in self.pixel_mask(acc.width, acc.height).into_iter().enumerate() {
            if !owned {
                out.converged[i] = false;
            }
        }
        out
    }

    /// True when every pixel this set owns has all its samples.
    pub fn is_complete(&self, acc: &Accumulation, spp: u32) -> bool {
        let last = self.last_sample(spp);
        let mask = self.pixel_mask(acc.width, acc.height);
        acc.taken.iter().zip(mask).all(|(&t, owned)| !owned || t >= last)
    }

    /// Checks a partial's accumulation against this set: pixels of other
    /// shards hold nothing, and in samples mode every owned pixel's counts
    /// fit its sample range (`first ≤ taken ≤ last`, kept within the
    /// samples of the range; a partial of several shards is complete).
    pub fn validate(&self, acc: &Accumulation, spp: u32) -> Result<(), String> {
        if self.mode == ShardMode::Samples && self.count > spp.max(1) {
            return Err(format!(
                "{} sample shards of {spp} samples per pixel: at most one shard per sample",
                self.count
            ));
        }
        let (first, last) = (self.first_sample(spp), self.last_sample(spp));
        let per_pixel = self.samples_per_pixel(spp);
        let mask = self.pixel_mask(acc.width, acc.height);
        for (i, owned) in mask.into_iter().enumerate() {
            let (x, y) = (i % acc.width as usize, i / acc.width as usize);
            if !owned {
                if acc.taken[i] != 0
                    || acc.kept[i] != 0
                    || acc.sum[i] != Vec3::ZERO
                    || acc.albedo[i] != Vec3::ZERO
                    || acc.normal[i] != Vec3::ZERO
                    || acc.converged[i]
                {
                    return Err(format!("pixel ({x}, {y}) belongs to another shard but holds samples"));
                }
                continue;
            }
            if self.mode == ShardMode::Samples {
                let taken = acc.taken[i];
                let done = if self.indices.len() == 1 {
                    taken.saturating_sub(first)
                } else {
                    per_pixel
                };
                if taken < first || taken > last || (self.indices.len() > 1 && taken != last) || acc.kept[i] > done {
                    return Err(format!(
                        "pixel ({x}, {y}): {} samples kept, next sample {taken}, but the shards' samples are {first}..{last}",
                        acc.kept[i]
                    ));
                }
            }
        }
        Ok(())
    }
}

impl fmt::Display for ShardSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.indices.len() == 1 {
            write!(f, "shard {}/{} by {}", self.indices[0], self.count, self.mode.name())
        } else {
            write!(
                f,
                "shards {} of {} by {}",
                self.indices_text(),
                self.count,
                self.mode.name()
            )
        }
    }
}

/// Relative bound on the difference between a pixel's mean merged from
/// sample shards and the single-process mean, per channel, for `spp`
/// samples: both are f32 sums of the same non-negative samples in
/// different orders, each within `γ(spp−1)·S` of the exact sum `S`
/// (`γ(n) = n·u / (1 − n·u)`, `u = 2⁻²⁴`; Higham, *Accuracy and Stability
/// of Numerical Algorithms*, §4.2), and the division by the count rounds
/// once more each: `2·γ(spp−1) + 2u`, up to second-order terms (the bound
/// returned adds 1 % for them). It holds for any merge tree. Observed
/// differences are far smaller (a few ulps).
pub fn samples_merge_bound(spp: u32) -> f64 {
    let u = f64::powi(2.0, -24);
    let n = spp.saturating_sub(1) as f64;
    let gamma = n * u / (1.0 - n * u);
    (2.0 * gamma + 2.0 * u) * 1.01
}

/// Adds a partial holding `set` to `merged` (which holds `merged_set`, or
/// nothing yet when `None`): tiles mode copies the pixels `set` owns;
/// samples mode adds the sums and counts of every pixel (in the order the
/// partials are given). The caller has checked that the sets are disjoint
/// and of one mode and count.
pub fn merge_into(merged: &mut Accumulation, part: &Accumulation, set: &ShardSet) {
    match set.mode {
        ShardMode::Tiles => {
            let mask = set.pixel_mask(part.width, part.height);
            for (i, owned) in mask.into_iter().enumerate() {
                if owned {
                    merged.sum[i] = part.sum[i];
                    merged.taken[i] = part.taken[i];
                    merged.kept[i] = part.kept[i];
                    merged.odd[i] = part.odd[i];
                    merged.odd_kept[i] = part.odd_kept[i];
                    merged.converged[i] = part.converged[i];
                    merged.albedo[i] = part.albedo[i];
                    merged.normal[i] = part.normal[i];
                }
            }
        }
        ShardMode::Samples => {
            for i in 0..merged.len() {
                merged.sum[i] = Vec3::from(Vec3A::from(merged.sum[i]) + Vec3A::from(part.sum[i]));
                merged.odd[i] = Vec3::from(Vec3A::from(merged.odd[i]) + Vec3A::from(part.odd[i]));
                merged.albedo[i] = Vec3::from(Vec3A::from(merged.albedo[i]) + Vec3A::from(part.albedo[i]));
                merged.normal[i] = Vec3::from(Vec3A::from(merged.normal[i]) + Vec3A::from(part.normal[i]));
                merged.kept[i] += part.kept[i];
                merged.odd_kept[i] += part.odd_kept[i];
                merged.taken[i] = merged.taken[i].max(part.taken[i]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_and_check_ids() {
        assert_eq!(ShardId::parse("2/4").unwrap(), ShardId { index: 2, count: 4 });
        assert!(ShardId::parse("4/4").unwrap_err().contains("0..=3"));
        assert!(ShardId::parse("0/0").is_err());
        assert!(ShardId::parse("1").is_err());
        assert!(ShardId::parse("a/3").is_err());
        assert!(ShardId::parse("-1/3").is_err());
    }

    #[test]
    fn tiles_partition_the_image_and_balance() {
        for count in [1u32, 2, 3, 4, 7] {
            let sets: Vec<ShardSet> = (0..count)
                .map(|i| ShardSet::single(ShardId::new(i, count).unwrap(), ShardMode::Tiles))
                .collect();
            let (w, h) = (100, 61);
            let mut owners = vec![0u32; (w * h) as usize];
            let mut per_shard = vec![0usize; count as usize];
            for (s, set) in sets.iter().enumerate() {
                for (i, &m) in set.pixel_mask(w, h).iter().enumerate() {
                    owners[i] += m as u32;
                    per_shard[s] += m as usize;
                }
            }
            assert!(owners.iter().all(|&o| o == 1), "count {count}");
            let (lo, hi) = (per_shard.iter().min().unwrap(), per_shard.iter().max().unwrap());
            assert!(*hi as f64 <= *lo as f64 * 1.25 + 64.0, "count {count}: {per_shard:?}");
        }
    }

    #[test]
    fn sample_ranges_cover_every_sample_once() {
        for (count, spp) in [(1u32, 5u32), (3, 20), (4, 4), (7, 64)] {
            let mut next = 0;
            for i in 0..count {
                let r = ShardSet::sample_range(ShardMode::Samples, count, i, spp);
                assert_eq!(r.start, next);
                next = r.end;
            }
            assert_eq!(next, spp);
        }
    }

    #[test]
    fn indices_text_round_trips() {
        let set = ShardSet {
            mode: ShardMode::Tiles,
            count: 12,
            indices: vec![0, 1, 2, 3, 5, 7, 8, 9],
        };
        assert_eq!(set.indices_text(), "0-3,5,7-9");
        assert_eq!(ShardSet::parse_indices("0-3,5,7-9", 12).unwrap(), set.indices);
        assert!(ShardSet::parse_indices("3,2", 12).is_err());
        assert!(ShardSet::parse_indices("0-12", 12).is_err());
        assert!(ShardSet::parse_indices("1,1", 12).is_err());
        assert!(ShardSet::parse_indices("x", 12).is_err());
    }

    #[test]
    fn bound_grows_with_the_samples() {
        assert!(samples_merge_bound(1) < 1.3e-7);
        let b = samples_merge_bound(1024);
        assert!(b > 1.2e-4 && b < 1.3e-4, "{b}");
    }
}
