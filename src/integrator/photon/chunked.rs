//! A point set split into spatial chunks, one kiddo immutable k-d tree per
//! chunk, built in parallel. kiddo builds a tree on one thread, and its
//! build (median selects through an index array, one random read of the
//! points per comparison) slows down as a tree outgrows the caches (more
//! than twice the time per point at 8.9M points as at 277k;
//! docs/benchmarks-history.md). So large maps are cut
//! into chunks of about [`CHUNK_TARGET`] points, up to 256 chunks, and the
//! chunks' trees built at once with rayon.
//!
//! The cuts are planned on a fixed sample of the points (every
//! `CUT_SAMPLE_STRIDE`-th): median cuts across the longest axis of each
//! part of the sample, ties broken by index, down to [`chunk_depth`] levels.
//! Every point then finds its chunk by walking those cuts, and is scattered
//! into it by a counting sort. The structure is a fixed function of the
//! points, identical for any thread count.
//!
//! Queries walk the cuts nearest side first and skip the chunks whose bounds
//! lie beyond the search radius (or the current k-th distance). Items are
//! indices into the chunks' concatenated order, which [`ChunkedTree::build`]
//! returns so that callers reorder their per-point payloads alike.

use super::map::{PhotonTree, BUCKET};
use crate::math::sampling::morton_code;
use kiddo::SquaredEuclidean;
use rayon::prelude::*;
use std::num::NonZero;

/// Points per chunk the cuts aim at: a chunk's build data (source points and
/// kiddo's index and leaves, ≈ 36 bytes per point) then fits in a few MiB.
pub const CHUNK_TARGET: usize = 1 << 19;

/// The most cut levels: chunk indices fit in a byte.
const MAX_DEPTH: u32 = 8;

/// Levels of median cuts for `n` points: the fewest that bring the chunks
/// down to [`CHUNK_TARGET`] points (none below it; 8, so 256 chunks, from
/// 67M points up).
pub fn chunk_depth(n: usize) -> u32 {
    n.div_ceil(CHUNK_TARGET).next_power_of_two().ilog2().min(MAX_DEPTH)
}

/// One chunk: its points' bounds (tree coordinates), its tree and the
/// concatenated index of its first point.
struct Chunk {
    min: [f32; 3],
    max: [f32; 3],
    tree: PhotonTree,
    offset: u32,
}

impl Chunk {
    /// Squared distance from `q` to the chunk's bounds (infinite for an
    /// empty chunk).
    #[inline]
    fn distance2(&self, q: &[f32; 3]) -> f32 {
        q.iter()
            .zip(self.min.iter().zip(&self.max))
            .map(|(&x, (&lo, &hi))| {
                let d = (lo - x).max(x - hi).max(0.0);
                d * d
            })
            .sum()
    }
}

/// One cut: points whose key along `axis` is below `key` go below. `at` is
/// the cut's coordinate, for the plane distance in queries.
#[derive(Clone, Copy)]
struct Split {
    axis: usize,
    key: u64,
    at: f32,
}

/// A cut that sends every point below (where the sample ran out before
/// `depth` levels): the chunk above stays empty.
const ALL_BELOW: Split = Split {
    axis: 0,
    key: u64::MAX,
    at: f32::INFINITY,
};

/// The cuts: a complete binary tree of `depth` levels in heap order (node
/// `j` has children `2j + 1` below and `2j + 2` above), whose `2^depth`
/// leaves are the chunks, numbered left to right (below before above):
/// their concatenation order. Walked without branches when points are
/// located: the branch at each level is unpredictable.
struct Cuts {
    depth: u32,
    splits: Vec<Split>,
}

impl Cuts {
    /// Plans `depth` levels of cuts on `sample` (points with their indices).
    fn plan(sample: &mut [([f32; 3], u32)], depth: u32) -> Self {
        let mut splits = vec![ALL_BELOW; (1usize << depth) - 1];
        Self::plan_node(sample, 0, &mut splits);
        Self { depth, splits }
    }

    fn plan_node(sample: &mut [([f32; 3], u32)], node: usize, splits: &mut [Split]) {
        if node >= splits.len() || sample.len() < 2 || sample.len() * CUT_SAMPLE_STRIDE < 2 * BUCKET {
            return;
        }
        let (min, max) = sample.iter().fold(EMPTY_BOUNDS, |b, (p, _)| grow(b, p));
        let axis = (0..3)
            .max_by(|&a, &b| (max[a] - min[a]).total_cmp(&(max[b] - min[b])))
            .unwrap_or(0);
        let mid = sample.len() / 2;
        sample.select_nth_unstable_by_key(mid, |(p, i)| key(p, axis, *i));
        let (p, i) = sample[mid];
        splits[node] = Split {
            axis,
            key: key(&p, axis, i),
            at: p[axis],
        };
        let (below, above) = sample.split_at_mut(mid);
        Self::plan_node(below, 2 * node + 1, splits);
        Self::plan_node(above, 2 * node + 2, splits);
    }

    /// Number of chunks.
    fn chunk_count(&self) -> usize {
        1 << self.depth
    }

    /// The chunks of `points` (whose first index is `first`), into `out`.
    /// Eight points descend side by side: one point's descent is a chain
    /// of dependent loads, eight chains overlap.
    fn locate(&self, points: &[[f32; 3]], first: u32, out: &mut Vec<u8>) {
        const LANES: usize = 8;
        let interior = self.splits.len();
        for (g, group) in points.chunks(LANES).enumerate() {
            let base = first + (g * LANES) as u32;
            let mut node = [0usize; LANES];
            for _ in 0..self.depth {
                for (l, p) in group.iter().enumerate() {
                    let s = self.splits[node[l]];
                    let above = key(p, s.axis, base + l as u32) >= s.key;
                    node[l] = 2 * node[l] + 1 + usize::from(above);
                }
            }
            out.extend(node[..group.len()].iter().map(|&j| (j - interior) as u8));
        }
    }

    /// Calls `visit` on each non-empty chunk whose bounds lie within
    /// squared distance `*reach` of `q`, the near side of each cut first;
    /// `visit` returns the new reach, so a shrinking k-th distance prunes
    /// what is left.
    fn walk<'a>(&self, chunks: &'a [Chunk], q: &[f32; 3], reach: &mut f32, visit: &mut impl FnMut(&'a Chunk) -> f32) {
        self.walk_node(0, chunks, q, reach, visit);
    }

    fn walk_node<'a>(
        &self,
        node: usize,
        chunks: &'a [Chunk],
        q: &[f32; 3],
        reach: &mut f32,
        visit: &mut impl FnMut(&'a Chunk) -> f32,
    ) {
        let Some(s) = self.splits.get(node) else {
            let c = &chunks[node - self.splits.len()];
            if c.tree.size() > 0 && c.distance2(q) <= *reach {
                *reach = visit(c);
            }
            return;
        };
        // Points on either side may lie on the plane (ties go by index), so
        // the plane's distance bounds the far side.
        let d = q[s.axis] - s.at;
        let (near, far) = if d < 0.0 {
            (2 * node + 1, 2 * node + 2)
        } else {
            (2 * node + 2, 2 * node + 1)
        };
        self.walk_node(near, chunks, q, reach, visit);
        if d * d <= *reach {
            self.walk_node(far, chunks, q, reach, visit);
        }
    }
}

/// Squared Euclidean distance in kiddo's order of operations (its
/// `SquaredEuclidean` sums the axes' squares from x to z), so that the
/// grid's and the neighbourhood caches' distances equal the tree's bit for
/// bit.
#[inline]
pub(super) fn distance2(a: &[f32; 3], b: &[f32; 3]) -> f32 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
}

/// The `k` nearest of `points` to `q` within squared distance `r2` by brute
/// force, as (distance bits, index) in the total order of answers: what
/// the spatial structures' tests compare against.
#[cfg(test)]
pub(super) fn brute_force_nearest(points: &[[f32; 3]], q: &[f32; 3], r2: f32, k: usize) -> Vec<(u32, u32)> {
    let mut all: Vec<(u32, u32)> = points
        .iter()
        .enumerate()
        .map(|(i, p)| (distance2(q, p), i as u32))
        .filter(|&(d, _)| d <= r2)
        .map(|(d, i)| (d.to_bits(), i))
        .collect();
    all.sort_unstable();
    all.truncate(k);
    all
}

/// A point's key along `axis`: its coordinate's bits mapped to an unsigned
/// integer in the order of `f32::total_cmp`, then its index; a total order
/// compared without branches.
#[inline]
fn key(p: &[f32; 3], axis: usize, i: u32) -> u64 {
    let bits = p[axis].to_bits();
    let ordered = bits ^ (((bits as i32 >> 31) as u32) | 0x8000_0000);
    (u64::from(ordered) << 32) | u64::from(i)
}

/// Spatially chunked k-d trees (see the module docs).
pub struct ChunkedTree {
    cuts: Cuts,
    chunks: Vec<Chunk>,
}

/// A neighbour: squared distance and concatenated item index.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbour {
    /// Squared Euclidean distance.
    pub distance: f32,
    /// Index in the chunks' concatenated order.
    pub item: u32,
}

impl Neighbour {
    /// The total order of answers, squared distance then item, as one
    /// integer: a squared distance is never negative (nor NaN: positions
    /// are finite), and the bits of non-negative floats are ordered as
    /// their values.
    #[inline]
    pub fn order_key(&self) -> u64 {
        (u64::from(self.distance.to_bits()) << 32) | u64::from(self.item)
    }
}

/// One block's part of one chunk: its points and their input indices.
type Share<'a> = (&'a mut [[f32; 3]], &'a mut [u32]);

/// Points per block of the counting sort's parallel passes.
const SCATTER_BLOCK: usize = 1 << 16;

impl ChunkedTree {
    /// Builds the chunks over `points` with at most `depth` levels of cuts
    /// (capped at 8). Returns the tree and `order`: `order[j]` is the index
    /// in `points` of the point that the tree calls `j`.
    ///
    /// Each chunk's points are sorted along a Z-order curve before kiddo
    /// builds its tree (`morton_sort`): kiddo's build is cache-bound (it
    /// runs about three times faster over coherent points than over
    /// shuffled ones), and the items of a leaf, hence the payloads a query
    /// reads, become neighbours in memory (the figures:
    /// docs/benchmarks-history.md, "The photon pass").
    pub fn build(points: Vec<[f32; 3]>, depth: u32) -> (Self, Vec<u32>) {
        assert!(points.len() <= u32::MAX as usize, "too many points for u32 indices");
        let n = points.len();
        let mut sample: Vec<([f32; 3], u32)> = (0..n)
            .step_by(CUT_SAMPLE_STRIDE)
            .map(|i| (points[i], i as u32))
            .collect();
        let cuts = Cuts::plan(&mut sample, depth.min(MAX_DEPTH));
        drop(sample);

        let (chunk_points, mut order) = scatter(&points, &cuts);
        drop(points);
        // Each chunk's share of `order`, sorted with its points.
        let mut rest = order.as_mut_slice();
        let mut shares = Vec::with_capacity(chunk_points.len());
        let mut offset = 0u32;
        for c in &chunk_points {
            let (head, tail) = std::mem::take(&mut rest).split_at_mut(c.len());
            shares.push((head, offset));
            rest = tail;
            offset += c.len() as u32;
        }
        let chunks = chunk_points
            .into_par_iter()
            .zip(shares)
            .map_init(MortonScratch::default, |scratch, (mut points, (order, offset))| {
                let (min, max) = morton_sort(&mut points, order, scratch);
                Chunk {
                    min,
                    max,
                    tree: PhotonTree::new_from_slice(&points),
                    offset,
                }
            })
            .collect();
        (Self { cuts, chunks }, order)
    }

    /// Every point within squared distance `r2` of `q` (inclusive), in a
    /// fixed order for a given tree and query (chunks nearest side first,
    /// kiddo's traversal within each): the fixed-radius gather of
    /// progressive photon mapping.
    pub fn within(&self, q: &[f32; 3], r2: f32) -> Vec<Neighbour> {
        let mut found: Vec<Neighbour> = Vec::new();
        let mut reach = r2;
        self.cuts.walk(&self.chunks, q, &mut reach, &mut |c| {
            found.extend(
                c.tree
                    .within_unsorted::<SquaredEuclidean>(q, r2)
                    .into_iter()
                    .map(|nb| Neighbour {
                        distance: nb.distance,
                        item: c.offset + nb.item,
                    }),
            );
            r2
        });
        found
    }

    /// Up to `k` nearest points within squared distance `r2` of `q`, in no
    /// particular order.
    pub fn nearest_n_within(&self, q: &[f32; 3], r2: f32, k: NonZero<usize>) -> Vec<Neighbour> {
        let mut found: Vec<Neighbour> = Vec::new();
        let mut reach = r2;
        // Once k points are found, a later chunk is searched only within the
        // k-th distance (inclusive, so ties still compete): nothing beyond
        // it can enter the result.
        let mut bound = r2;
        self.cuts.walk(&self.chunks, q, &mut reach, &mut |c| {
            found.extend(
                c.tree
                    .nearest_n_within::<SquaredEuclidean>(q, bound, k, false)
                    .into_iter()
                    .map(|nb| Neighbour {
                        distance: nb.distance,
                        item: c.offset + nb.item,
                    }),
            );
            if found.len() < k.get() {
                return r2;
            }
            if found.len() > k.get() {
                // Keep the k nearest, ties by item: deterministic.
                found.select_nth_unstable_by_key(k.get() - 1, Neighbour::order_key);
                found.truncate(k.get());
            }
            // The k-th distance bounds what another chunk could add.
            bound = found.iter().fold(0.0f32, |m, n| m.max(n.distance));
            bound
        });
        found
    }
}

/// The points of each chunk of `cuts`, in input order, and the concatenated
/// order (`order[j]` is the input index of the `j`-th point of the chunks
/// one after the other): a counting sort in parallel blocks.
fn scatter(points: &[[f32; 3]], cuts: &Cuts) -> (Vec<Vec<[f32; 3]>>, Vec<u32>) {
    let n = points.len();
    let chunk_count = cuts.chunk_count();
    // Counting sort: each block's chunk of every point and its counts...
    let (labels, counts): (Vec<Vec<u8>>, Vec<Vec<usize>>) = (0..n.div_ceil(SCATTER_BLOCK))
        .into_par_iter()
        .map(|b| {
            let range = b * SCATTER_BLOCK..((b + 1) * SCATTER_BLOCK).min(n);
            let mut labels = Vec::with_capacity(range.len());
            cuts.locate(&points[range.clone()], range.start as u32, &mut labels);
            let mut count = vec![0usize; chunk_count];
            for &c in &labels {
                count[c as usize] += 1;
            }
            (labels, count)
        })
        .unzip();
    let sizes: Vec<usize> = (0..chunk_count).map(|c| counts.iter().map(|k| k[c]).sum()).collect();
    // ... then every block's share of every chunk's arrays (disjoint
    // slices, in block order, so each chunk keeps the input order) ...
    let mut chunk_points: Vec<Vec<[f32; 3]>> = sizes.iter().map(|&s| vec![[0.0; 3]; s]).collect();
    let mut order = vec![0u32; n];
    let mut shares: Vec<Vec<Share>> = counts.iter().map(|_| Vec::with_capacity(chunk_count)).collect();
    let mut order_rest = order.as_mut_slice();
    for (c, chunk) in chunk_points.iter_mut().enumerate() {
        let (mut order_chunk, tail) = std::mem::take(&mut order_rest).split_at_mut(sizes[c]);
        order_rest = tail;
        let mut points_chunk = chunk.as_mut_slice();
        for (share, count) in shares.iter_mut().zip(&counts) {
            let (p, p_tail) = std::mem::take(&mut points_chunk).split_at_mut(count[c]);
            let (o, o_tail) = std::mem::take(&mut order_chunk).split_at_mut(count[c]);
            points_chunk = p_tail;
            order_chunk = o_tail;
            share.push((p, o));
        }
    }
    // ... filled in parallel.
    shares
        .into_par_iter()
        .zip(labels)
        .enumerate()
        .for_each(|(b, (mut share, labels))| {
            let mut fill = vec![0usize; chunk_count];
            for (j, c) in labels.into_iter().enumerate() {
                let i = b * SCATTER_BLOCK + j;
                let (p, o) = &mut share[c as usize];
                let k = &mut fill[c as usize];
                p[*k] = points[i];
                o[*k] = i as u32;
                *k += 1;
            }
        });
    (chunk_points, order)
}

/// Scratch arrays of [`morton_sort`], kept by each worker thread across
/// chunks (nothing is allocated per chunk).
#[derive(Default)]
struct MortonScratch {
    keys: Vec<u64>,
    buffer: Vec<u64>,
    points: Vec<[f32; 3]>,
    order: Vec<u32>,
}

/// `points` (and `order` alike) sorted along a Z-order curve over their
/// bounds (10 bits per axis; ties keep their input order): kiddo's build
/// then reads neighbouring memory at every level, and the leaves' items,
/// hence the photon records a gather reads, are neighbours in memory.
/// Returns the points' bounds.
fn morton_sort(points: &mut [[f32; 3]], order: &mut [u32], scratch: &mut MortonScratch) -> Bounds {
    let (min, max) = bounds(points);
    let scale: [f32; 3] = std::array::from_fn(|a| {
        let extent = max[a] - min[a];
        if extent > 0.0 {
            1023.0 / extent
        } else {
            0.0
        }
    });
    let MortonScratch {
        keys,
        buffer,
        points: old_points,
        order: old_order,
    } = scratch;
    keys.clear();
    keys.extend(points.iter().enumerate().map(|(i, p)| {
        let cell = std::array::from_fn(|a| (((p[a] - min[a]) * scale[a]) as u32).min(1023));
        (morton_code(cell) << 32) | i as u64
    }));
    radix_sort_high(keys, buffer);
    old_points.clear();
    old_points.extend_from_slice(points);
    old_order.clear();
    old_order.extend_from_slice(order);
    for ((p, o), &k) in points.iter_mut().zip(order.iter_mut()).zip(keys.iter()) {
        let from = k as u32 as usize;
        *p = old_points[from];
        *o = old_order[from];
    }
    (min, max)
}

/// Sorts `keys` by their high 30 bits (stable): three passes of a
/// least-significant-digit radix sort, 10 bits each, through `buffer`.
pub(super) fn radix_sort_high(keys: &mut Vec<u64>, buffer: &mut Vec<u64>) {
    buffer.clear();
    buffer.resize(keys.len(), 0);
    for pass in 0..3 {
        let shift = 32 + 10 * pass;
        let digit = |k: u64| ((k >> shift) & 1023) as usize;
        let mut start = [0usize; 1024];
        for &k in keys.iter() {
            start[digit(k)] += 1;
        }
        let mut sum = 0;
        for s in start.iter_mut() {
            let count = *s;
            *s = sum;
            sum += count;
        }
        for &k in keys.iter() {
            let d = digit(k);
            buffer[start[d]] = k;
            start[d] += 1;
        }
        std::mem::swap(keys, buffer);
    }
}

/// Every this many points, one goes into the sample whose medians and
/// bounds choose the cuts (exact medians of 71M points took seconds).
const CUT_SAMPLE_STRIDE: usize = 64;

type Bounds = ([f32; 3], [f32; 3]);

const EMPTY_BOUNDS: Bounds = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);

fn grow((mut min, mut max): Bounds, p: &[f32; 3]) -> Bounds {
    for a in 0..3 {
        min[a] = min[a].min(p[a]);
        max[a] = max[a].max(p[a]);
    }
    (min, max)
}

/// Bounds of `points`.
fn bounds(points: &[[f32; 3]]) -> Bounds {
    points.iter().fold(EMPTY_BOUNDS, grow)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::{Domain, Rng};

    /// Points and their order move together along the curve; ties keep
    /// their order; scratch reuse changes nothing.
    #[test]
    fn morton_sort_orders_along_the_curve_and_keeps_ties_in_order() {
        let mut rng = Rng::new(3, Domain::Analysis, 0, 0);
        let input: Vec<[f32; 3]> = (0..5000)
            .map(|i| {
                if i % 10 == 0 {
                    [0.25, 0.5, 0.75] // ties
                } else {
                    [rng.f32() * 4.0, rng.f32(), -rng.f32() * 2.0]
                }
            })
            .collect();
        let mut points = input.clone();
        let mut order: Vec<u32> = (100..5100).collect();
        let mut scratch = MortonScratch::default();
        morton_sort(&mut points, &mut order, &mut scratch);
        let (min, max) = bounds(&input);
        let code = |p: &[f32; 3]| {
            morton_code(std::array::from_fn(|a| {
                (((p[a] - min[a]) * (1023.0 / (max[a] - min[a]))) as u32).min(1023)
            }))
        };
        for (j, p) in points.iter().enumerate() {
            assert_eq!(*p, input[order[j] as usize - 100], "points and order moved together");
        }
        for w in order.windows(2) {
            let (a, b) = (&input[w[0] as usize - 100], &input[w[1] as usize - 100]);
            assert!(code(a) < code(b) || (code(a) == code(b) && w[0] < w[1]), "{a:?} {b:?}");
        }
        // Reused scratch, a smaller chunk: the same function of its input.
        let mut again = input[..700].to_vec();
        let mut again_order: Vec<u32> = (0..700).collect();
        morton_sort(&mut again, &mut again_order, &mut scratch);
        let mut fresh = input[..700].to_vec();
        let mut fresh_order: Vec<u32> = (0..700).collect();
        morton_sort(&mut fresh, &mut fresh_order, &mut MortonScratch::default());
        assert_eq!((again, again_order), (fresh, fresh_order));
    }

    /// The depth brings chunks to the target size, capped at 256 chunks.
    #[test]
    fn chunk_depth_follows_the_target() {
        assert_eq!(chunk_depth(0), 0);
        assert_eq!(chunk_depth(CHUNK_TARGET), 0);
        assert_eq!(chunk_depth(CHUNK_TARGET + 1), 1);
        assert_eq!(chunk_depth(71_000_000), 8);
        assert_eq!(chunk_depth(usize::MAX / 2), 8);
    }

    /// More levels than the sample can fill leave empty chunks; with
    /// coincident points (ties on every axis) and an empty set, queries
    /// still answer as a brute-force search, and the order is a permutation
    /// that keeps tied points in input order.
    #[test]
    fn sparse_and_tied_points_match_brute_force() {
        let empty = ChunkedTree::build(Vec::new(), 4);
        assert!(empty.1.is_empty());
        let k = NonZero::new(5).unwrap();
        assert!(empty.0.nearest_n_within(&[0.0; 3], 1.0, k).is_empty());
        let mut points: Vec<[f32; 3]> = (0..300).map(|i| [(i % 7) as f32, 0.5, (i % 3) as f32]).collect();
        points.extend(std::iter::repeat_n([2.0, 0.5, 1.0], 200));
        let (tree, order) = ChunkedTree::build(points.clone(), 8);
        assert_eq!(tree.chunks.len(), 256);
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert!(sorted.iter().enumerate().all(|(i, &j)| i as u32 == j));
        for c in &tree.chunks {
            let ids = &order[c.offset as usize..c.offset as usize + c.tree.size()];
            // Equal points keep their input order.
            assert!(
                ids.windows(2)
                    .all(|w| points[w[0] as usize] != points[w[1] as usize] || w[0] < w[1]),
                "a chunk lost the input order of ties"
            );
        }
        for q in [[2.0, 0.5, 1.0], [0.2, 0.4, 2.1], [6.5, 0.5, -1.0]] {
            let d2 = |p: &[f32; 3]| (0..3).map(|i| (p[i] - q[i]) * (p[i] - q[i])).sum::<f32>();
            let mut brute: Vec<f32> = points.iter().map(d2).collect();
            brute.sort_by(|a, b| a.total_cmp(b));
            let mut got: Vec<f32> = tree.nearest_n_within(&q, 2.0, k).iter().map(|n| n.distance).collect();
            got.sort_by(|a, b| a.total_cmp(b));
            let want: Vec<f32> = brute.iter().copied().filter(|&d| d <= 2.0).take(5).collect();
            assert_eq!(got, want);
        }
    }

    /// Chunked queries return what a brute-force search returns.
    #[test]
    fn chunked_queries_match_brute_force() {
        let mut rng = Rng::new(3, Domain::Analysis, 0, 0);
        let points: Vec<[f32; 3]> = (0..20_000)
            .map(|_| {
                let (a, b) = rng.f32x2();
                [a * 4.0, (a * 13.0).fract(), b * 2.0]
            })
            .collect();
        let (tree, order) = ChunkedTree::build(points.clone(), 3);
        assert_eq!(tree.chunks.len(), 8);
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert!(sorted.iter().enumerate().all(|(i, &j)| i as u32 == j));
        let k = NonZero::new(10).unwrap();
        for _ in 0..300 {
            let (a, b) = rng.f32x2();
            let q = [a * 4.0, 0.5, b * 2.0];
            let d2 = |p: &[f32; 3]| (0..3).map(|i| (p[i] - q[i]) * (p[i] - q[i])).sum::<f32>();
            let mut brute: Vec<f32> = points.iter().map(d2).collect();
            brute.sort_by(|a, b| a.total_cmp(b));
            let r2 = 0.01;
            let mut got: Vec<f32> = tree
                .nearest_n_within(&q, r2, k)
                .iter()
                .map(|n| {
                    assert_eq!(n.distance, d2(&points[order[n.item as usize] as usize]));
                    n.distance
                })
                .collect();
            got.sort_by(|a, b| a.total_cmp(b));
            let want: Vec<f32> = brute.iter().copied().filter(|&d| d <= r2).take(10).collect();
            assert_eq!(got, want);
        }
    }
}
