//! A hashed uniform grid over the photons, at one or more cell sizes, for
//! progressive photon mapping's fixed-radius gathers (Hachisuka & Jensen
//! 2009, "Stochastic Progressive Photon Mapping", §4: photons hashed by
//! cell, cell size from the query radius). It answers k-nearest queries
//! exactly too, but more slowly than the k-d tree
//! (docs/benchmarks.md, "What was tried with the caustic gather").
//!
//! The points are sorted along a Z-order (Morton) curve of the finest
//! cells, so every cell of every coarser level, whose Morton code is a
//! prefix of its points' fine codes, is one contiguous slice of the sorted
//! points. Each level keeps an open-addressing hash table from its occupied
//! cells' codes to their slices; empty cells cost nothing. The coarsest
//! level's cells are at least the gather's largest radius `R` wide, each
//! finer level half as wide, down to `R / 2^fine_levels`.
//!
//! A query within radius `s` looks up the at most 3 × 3 × 3 cells of the
//! level whose cells are at least `s` wide that the box `q ± s` overlaps:
//! every point within `s` of `q` is in them. The fixed-radius gather of
//! progressive photon mapping is one such query. A k-nearest query within
//! `R` first counts the points of `q`'s coarsest cell, guesses from that
//! density the radius that holds `k` points, searches it, and, if it holds
//! fewer than `k`, searches the next coarser level's radius, up to `R`:
//! the answer is then every point within `R` when fewer than `k` are, else
//! the `k` nearest (ties at the k-th distance broken by item), whatever
//! the guess.
//!
//! Distances are computed as kiddo computes them (same coordinates, same
//! order of operations), so a query returns the same points with the same
//! distances as the k-d tree's, in another order.

use super::chunked::{distance2, radix_sort_high, Neighbour};
use crate::math::sampling::morton_code;
use rayon::prelude::*;
use std::num::NonZero;

/// Levels finer than the coarsest for k-nearest queries: the finest cells
/// are `R / 2^KNN_FINE_LEVELS` wide, for a caustic's bright core (whose `k`
/// nearest reach a few hundredths of `R`). Fixed-radius queries need none.
pub const KNN_FINE_LEVELS: u32 = 2;

/// Largest cell coordinate: Morton codes interleave 21 bits per axis.
const MAX_COORD: u32 = (1 << 21) - 1;

/// Relative margin by which a query's box is widened, far above the
/// rounding of the cell coordinates it compares.
const MARGIN: f32 = 1e-4;

/// An empty slot of a level's hash table (no cell has this code: codes use
/// 63 bits).
const EMPTY: u64 = u64::MAX;

/// One occupied cell: its Morton code at its level and its points' slice.
#[derive(Clone, Copy, Debug)]
struct Slot {
    code: u64,
    start: u32,
    end: u32,
}

/// The occupied cells of one level, in a hash table with linear probing
/// (at most three quarters full).
#[derive(Debug)]
struct Level {
    /// Cell width.
    size: f32,
    /// A level-`j` cell's code is its points' fine codes shifted by `3j`.
    shift: u32,
    /// Number of slots − 1 (a power of two − 1).
    mask: usize,
    slots: Vec<Slot>,
}

impl Level {
    /// The level whose cells are the fine cells' codes shifted by `shift`,
    /// over `codes` (sorted).
    fn build(codes: &[u64], shift: u32, size: f32) -> Self {
        let mut cells: Vec<Slot> = Vec::new();
        for (i, &c) in codes.iter().enumerate() {
            let code = c >> shift;
            match cells.last_mut() {
                Some(last) if last.code == code => last.end = i as u32 + 1,
                _ => cells.push(Slot {
                    code,
                    start: i as u32,
                    end: i as u32 + 1,
                }),
            }
        }
        // At most three quarters full.
        let slots_len = (cells.len() * 4 / 3 + 1).next_power_of_two().max(2);
        let mask = slots_len - 1;
        let mut slots = vec![
            Slot {
                code: EMPTY,
                start: 0,
                end: 0
            };
            slots_len
        ];
        for cell in cells {
            let mut i = hash(cell.code) & mask;
            while slots[i].code != EMPTY {
                i = (i + 1) & mask;
            }
            slots[i] = cell;
        }
        Self {
            size,
            shift,
            mask,
            slots,
        }
    }

    /// The slice of the cell with code `code` (empty when the cell is).
    #[inline]
    fn find(&self, code: u64) -> std::ops::Range<usize> {
        let mut i = hash(code) & self.mask;
        loop {
            let s = &self.slots[i];
            if s.code == code {
                return s.start as usize..s.end as usize;
            }
            if s.code == EMPTY {
                return 0..0;
            }
            i = (i + 1) & self.mask;
        }
    }
}

/// Fibonacci hashing of a cell code (Knuth, TAOCP vol. 3, §6.4): its high
/// bits, well mixed, index the table.
#[inline]
fn hash(code: u64) -> usize {
    (code.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 32) as usize
}

/// The grid (see the module docs).
#[derive(Debug)]
pub struct PhotonGrid {
    origin: [f32; 3],
    /// `1 /` the finest cell width.
    inv_fine: f32,
    /// Finest first; the last one's cells are at least `R` wide.
    levels: Vec<Level>,
    /// The points' coordinates, axis by axis (x, y, z), sorted by fine
    /// Morton code: a cell's distances are computed four at a time.
    coords: [Vec<f32>; 3],
}

impl PhotonGrid {
    /// The grid over `points` for gathers within `radius`, with
    /// `fine_levels` levels of finer cells ([`KNN_FINE_LEVELS`] for
    /// k-nearest queries, 0 for fixed-radius ones). Returns the grid and
    /// `order`: `order[j]` is the index in `points` of the point that
    /// answers call item `j` (callers reorder their per-point payloads
    /// alike, which then lie in the cells' order too).
    ///
    /// # Panics
    /// If `radius` is not positive and finite, or there are more than
    /// `u32::MAX` points.
    pub fn build(points: &[[f32; 3]], radius: f32, fine_levels: u32) -> (Self, Vec<u32>) {
        assert!(radius.is_finite() && radius > 0.0, "grid radius {radius}");
        assert!(points.len() <= u32::MAX as usize, "too many points for u32 items");
        let (min, max) = points
            .iter()
            .fold(([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]), |(lo, hi), p| {
                (
                    std::array::from_fn(|a| lo[a].min(p[a])),
                    std::array::from_fn(|a| hi[a].max(p[a])),
                )
            });
        let origin = if points.is_empty() { [0.0; 3] } else { min };
        let extent = (0..3).fold(0.0f32, |e, a| e.max(max[a] - min[a]));
        // The finest cells are R / 2^fine_levels wide, wider when the
        // points would span more than 2^21 of them.
        let mut fine = radius / (1u32 << fine_levels.min(20)) as f32;
        fine = fine.max(extent / (MAX_COORD - 1) as f32);
        let inv_fine = 1.0 / fine;
        let mut levels_above = 0;
        while fine * (1u32 << levels_above) as f32 * (1.0 - MARGIN) < radius && levels_above < 20 {
            levels_above += 1;
        }
        let fine_codes: Vec<u64> = points
            .par_iter()
            .map(|p| morton_code(fine_cell(p, &origin, inv_fine)))
            .collect();
        let (codes, order): (Vec<u64>, Vec<u32>) = if fine_codes.iter().all(|&c| c < 1 << 30) {
            // At most 10 bits per axis (the usual case: R is a fiftieth of
            // the scene or more): three radix passes, stable.
            let mut keys: Vec<u64> = fine_codes
                .iter()
                .enumerate()
                .map(|(i, &c)| (c << 32) | i as u64)
                .collect();
            radix_sort_high(&mut keys, &mut Vec::new());
            keys.iter().map(|&k| (k >> 32, k as u32)).unzip()
        } else {
            let mut pairs: Vec<(u64, u32)> = fine_codes.iter().enumerate().map(|(i, &c)| (c, i as u32)).collect();
            pairs.par_sort_unstable();
            pairs.into_iter().unzip()
        };
        let levels = (0..=levels_above)
            .into_par_iter()
            .map(|j| Level::build(&codes, 3 * j, fine * (1u32 << j) as f32))
            .collect();
        let grid = Self {
            origin,
            inv_fine,
            levels,
            coords: std::array::from_fn(|a| order.iter().map(|&i| points[i as usize][a]).collect()),
        };
        (grid, order)
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.coords[0].len()
    }

    /// True when the grid holds no point.
    pub fn is_empty(&self) -> bool {
        self.coords[0].is_empty()
    }

    /// Bytes held: the sorted points and every level's hash table.
    pub fn memory_bytes(&self) -> usize {
        self.len() * 12
            + self
                .levels
                .iter()
                .map(|l| l.slots.len() * std::mem::size_of::<Slot>())
                .sum::<usize>()
    }

    /// Every point within squared distance `r2` of `q` (inclusive), in a
    /// fixed order for a given grid and query, appended to `out`.
    pub fn within(&self, q: &[f32; 3], r2: f32, out: &mut Vec<Neighbour>) {
        let r = r2.sqrt();
        if self.is_empty() || r.is_nan() {
            return;
        }
        let level = self
            .levels
            .iter()
            .position(|l| l.size >= r)
            .unwrap_or(self.levels.len() - 1);
        self.collect(level, q, r, r2, out);
    }

    /// The `k` nearest points within squared distance `r2` of `q` (ties at
    /// the k-th distance broken by item), or every point within it when
    /// fewer than `k` are, into `out` (cleared first) in no particular
    /// order.
    pub fn nearest_n_within(&self, q: &[f32; 3], r2: f32, k: NonZero<usize>, out: &mut Vec<Neighbour>) {
        out.clear();
        let r = r2.sqrt();
        if self.is_empty() || r.is_nan() {
            return;
        }
        let k = k.get();
        let top = self.levels.len() - 1;
        // The density around q from its coarsest cell's count: on a surface
        // through a cell of width h holding n points, k points cover about
        // π ρ² = k h² / n.
        let coarse = &self.levels[top];
        let mut s = match self.cell_of(q, top) {
            Some(cell) => {
                let n = coarse.find(morton_code(cell)).len();
                (coarse.size * (k as f32 / (std::f32::consts::PI * n as f32)).sqrt() * GUESS_MARGIN).min(r)
            }
            None => r,
        };
        loop {
            // Cells at least as wide as the search radius: at most 3 per axis.
            let level = self.levels.iter().position(|l| l.size >= s).unwrap_or(top);
            out.clear();
            self.collect(level, q, s, s * s, out);
            if out.len() >= k || s >= r {
                break;
            }
            s = (2.0 * s).min(r);
        }
        if out.len() > k {
            out.select_nth_unstable_by_key(k - 1, Neighbour::order_key);
            out.truncate(k);
        }
    }

    /// The coarsest-level cell of `q`, when inside the grid's range.
    fn cell_of(&self, q: &[f32; 3], level: usize) -> Option<[u32; 3]> {
        let shift = self.levels[level].shift / 3;
        let mut cell = [0u32; 3];
        for a in 0..3 {
            let x = (q[a] - self.origin[a]) * self.inv_fine;
            if !(0.0..=MAX_COORD as f32).contains(&x) {
                return None;
            }
            cell[a] = (x as u32) >> shift;
        }
        Some(cell)
    }

    /// Appends to `out` the points within squared distance `r2` of `q`
    /// from the cells of level `level` that the box `q ± r` overlaps (at
    /// most 3 per axis when `r` is at most the level's cell width).
    fn collect(&self, level: usize, q: &[f32; 3], r: f32, r2: f32, out: &mut Vec<Neighbour>) {
        let l = &self.levels[level];
        let shift = l.shift / 3;
        let reach = r * (1.0 + MARGIN) + f32::MIN_POSITIVE;
        let mut lo = [0u32; 3];
        let mut hi = [0u32; 3];
        for a in 0..3 {
            let top = MAX_COORD >> shift;
            // The fine coordinate of the box's faces, computed as the
            // points' are (monotone in x), then the level's.
            let f = |x: f32| (((x - self.origin[a]) * self.inv_fine).max(0.0) as u32).min(MAX_COORD) >> shift;
            let (below, above) = (q[a] - reach, q[a] + reach);
            // Entirely below or above the grid (or NaN): no cell.
            if above.is_nan() || above < self.origin[a] || (below - self.origin[a]) * self.inv_fine > MAX_COORD as f32 {
                return;
            }
            lo[a] = f(below);
            hi[a] = f(above).min(top);
        }
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let range = l.find(morton_code([x, y, z]));
                    self.scan(range, q, r2, out);
                }
            }
        }
    }
}

impl PhotonGrid {
    /// Appends to `out` the points of `range` within squared distance `r2`
    /// of `q`: distances a block at a time (a loop the compiler
    /// vectorises), then the block's points within `r2` written without
    /// branches.
    #[inline]
    fn scan(&self, range: std::ops::Range<usize>, q: &[f32; 3], r2: f32, out: &mut Vec<Neighbour>) {
        const BLOCK: usize = 32;
        let [xs, ys, zs] = &self.coords;
        let mut d = [0.0f32; BLOCK];
        let mut start = range.start;
        while start < range.end {
            let n = (range.end - start).min(BLOCK);
            let (x, y, z) = (&xs[start..start + n], &ys[start..start + n], &zs[start..start + n]);
            for (i, d) in d[..n].iter_mut().enumerate() {
                *d = distance2(q, &[x[i], y[i], z[i]]);
            }
            let base = out.len();
            out.resize(base + n, Neighbour { distance: 0.0, item: 0 });
            let mut w = base;
            for (i, &d) in d[..n].iter().enumerate() {
                out[w] = Neighbour {
                    distance: d,
                    item: (start + i) as u32,
                };
                w += usize::from(d <= r2);
            }
            out.truncate(w);
            start += n;
        }
    }
}

/// How much wider than the density's guess the first k-nearest search is:
/// a search that finds fewer than `k` is repeated one level coarser.
const GUESS_MARGIN: f32 = 1.25;

/// The fine cell of `p`.
#[inline]
fn fine_cell(p: &[f32; 3], origin: &[f32; 3], inv_fine: f32) -> [u32; 3] {
    std::array::from_fn(|a| (((p[a] - origin[a]) * inv_fine).max(0.0) as u32).min(MAX_COORD))
}

#[cfg(test)]
mod tests {
    use super::super::chunked::brute_force_nearest as brute;
    use super::*;
    use crate::math::rng::{Domain, Rng};

    /// The answer as (distance bits, input index), sorted.
    fn sorted(found: &[Neighbour], order: &[u32]) -> Vec<(u32, u32)> {
        let mut v: Vec<(u32, u32)> = found
            .iter()
            .map(|n| (n.distance.to_bits(), order[n.item as usize]))
            .collect();
        v.sort_unstable();
        v
    }

    /// k-nearest and fixed-radius answers equal a brute-force search: on a
    /// surface whose density varies a hundredfold (so the density's guess
    /// is often wrong), with points on cell borders, queries far outside
    /// the grid and in its empty cells, and k above the point count.
    #[test]
    fn queries_match_brute_force() {
        let mut rng = Rng::new(17, Domain::Analysis, 0, 0);
        let radius = 0.2f32;
        let mut points: Vec<[f32; 3]> = (0..30_000)
            .map(|_| {
                let (a, b) = rng.f32x2();
                let a = a * a * a;
                [a * 3.0, 0.5 + 0.2 * b, b * 3.0 - 0.3 * a]
            })
            .collect();
        // Points exactly on the borders of the fine cells (multiples of
        // R/8 from the origin, which is the points' minimum: 0 on x).
        for i in 0..200 {
            let x = (i % 20) as f32 * radius / 8.0;
            points.push([x, 0.6, 1.0 + (i / 20) as f32 * radius / 8.0]);
        }
        // Coincident points: ties broken by item.
        points.extend(std::iter::repeat_n([1.5, 0.55, 1.5], 30));
        let (grid, order) = PhotonGrid::build(&points, radius, KNN_FINE_LEVELS);
        let mut out = Vec::new();
        let mut queries: Vec<[f32; 3]> = (0..2000)
            .map(|_| {
                let (a, b) = rng.f32x2();
                [a * 3.4 - 0.2, 0.5 + 0.3 * rng.f32(), b * 3.4 - 0.2]
            })
            .collect();
        queries.extend([
            [1.5, 0.55, 1.5],
            [0.0, 0.6, 1.0],
            [radius / 8.0, 0.6, 1.0 + radius / 4.0],
            [100.0, -50.0, 3.0],
            [-1e30, 0.0, 0.0],
            [1.5, 5.0, 1.5],
        ]);
        for (qi, q) in queries.iter().enumerate() {
            for k in [1usize, 8, 16, 64, 40_000] {
                let r2 = radius * radius;
                grid.nearest_n_within(q, r2, NonZero::new(k).unwrap(), &mut out);
                assert_eq!(
                    sorted(&out, &order),
                    brute(&points, q, r2, k),
                    "k = {k}, query {qi} at {q:?}"
                );
            }
            for r in [radius, radius * 0.3, radius * 0.05] {
                out.clear();
                grid.within(q, r * r, &mut out);
                assert_eq!(
                    sorted(&out, &order),
                    brute(&points, q, r * r, usize::MAX),
                    "r = {r}, query {qi}"
                );
            }
        }
    }

    /// An empty grid answers nothing; a grid of one point or of points all
    /// at one place answers as a brute-force search; a radius larger than
    /// the grid was built for is still answered exactly.
    #[test]
    fn degenerate_grids_match_brute_force() {
        let (empty, _) = PhotonGrid::build(&[], 0.1, KNN_FINE_LEVELS);
        let mut out = Vec::new();
        empty.nearest_n_within(&[0.0; 3], 1.0, NonZero::new(4).unwrap(), &mut out);
        assert!(out.is_empty());
        empty.within(&[0.0; 3], 1.0, &mut out);
        assert!(out.is_empty());
        let one = [[2.0f32, -1.0, 0.5]];
        let (grid, order) = PhotonGrid::build(&one, 0.1, KNN_FINE_LEVELS);
        assert_eq!(order, [0]);
        grid.nearest_n_within(&[2.05, -1.0, 0.5], 0.01, NonZero::new(4).unwrap(), &mut out);
        assert_eq!(out.len(), 1);
        assert_eq!(out[0].item, 0);
        grid.nearest_n_within(&[2.2, -1.0, 0.5], 0.01, NonZero::new(4).unwrap(), &mut out);
        assert!(out.is_empty());
        let same = vec![[0.25f32, 0.5, 0.75]; 100];
        let (grid, order) = PhotonGrid::build(&same, 0.05, 0);
        grid.nearest_n_within(&[0.25, 0.5, 0.76], 0.0025, NonZero::new(10).unwrap(), &mut out);
        assert_eq!(sorted(&out, &order), brute(&same, &[0.25, 0.5, 0.76], 0.0025, 10));
        out.clear();
        grid.within(&[0.25, 0.5, 0.9], 1.0, &mut out);
        assert_eq!(out.len(), 100);
    }
}
