//! A point set split into spatial chunks, one kiddo immutable k-d tree per
//! chunk, built in parallel: kiddo builds a tree on one thread (≈ 20 s for
//! 10M photons here), so large maps are first cut at the median of the
//! longest axis, recursively ([`chunk_depth`] levels: 4 chunks from 1M
//! points, 8 from 16M), and the chunks' trees built at once with rayon.
//! The cut is a fixed function of the points (a sampled median, ties
//! broken by index), so the structure is identical for any thread count.
//!
//! Queries visit the chunks nearest first and skip those whose bounds lie
//! beyond the search radius (or the current k-th distance). Items are
//! indices into the chunks' concatenated order, which [`ChunkedTree::build`]
//! returns so that callers reorder their per-point payloads alike.

use super::map::{PhotonTree, BUCKET};
use kiddo::SquaredEuclidean;
use rayon::prelude::*;
use std::num::NonZero;

/// Levels of median cuts for `n` points: none below 1M points (one tree
/// builds fast enough), then 2 (4 chunks), 3 from 16M (8 chunks: more
/// chunks than cores keeps both cores busy when the chunks' build times
/// differ).
pub fn chunk_depth(n: usize) -> u32 {
    if n < 1 << 20 {
        0
    } else if n < 1 << 24 {
        2
    } else {
        3
    }
}

/// One chunk: its points' bounds (tree coordinates), its tree, the
/// concatenated index of its first point, and, when kept, its points in
/// item order.
struct Chunk {
    min: [f32; 3],
    max: [f32; 3],
    tree: PhotonTree,
    offset: u32,
    points: Vec<[f32; 3]>,
}

impl Chunk {
    /// Squared distance from `q` to the chunk's bounds.
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

/// Spatially chunked k-d trees (see the module docs).
pub struct ChunkedTree {
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

impl ChunkedTree {
    /// Builds the chunks over `points` with `depth` levels of median cuts.
    /// Returns the tree and `order`: `order[j]` is the index in `points` of
    /// the point that the tree calls `j`.
    ///
    /// The cuts are stable partitions: each chunk keeps its points in their
    /// input order. Photons arrive in emission order, which is spatially
    /// coherent (Morton-ordered strata), and kiddo's build (median selects
    /// through an index array) runs about three times faster over coherent
    /// points than over shuffled ones.
    ///
    /// With `keep_points`, each chunk keeps its points in item order (12
    /// bytes each) for [`within_points`](Self::within_points).
    pub fn build(points: Vec<[f32; 3]>, depth: u32, keep_points: bool) -> (Self, Vec<u32>) {
        assert!(points.len() <= u32::MAX as usize, "too many points for u32 indices");
        let all: Vec<u32> = (0..points.len() as u32).into_par_iter().collect();
        let parts = cut(&points, all, depth);
        let mut offsets = Vec::with_capacity(parts.len());
        let mut total = 0usize;
        for p in &parts {
            offsets.push(total as u32);
            total += p.len();
        }
        let slices: Vec<Vec<[f32; 3]>> = parts
            .par_iter()
            .map(|idx| idx.iter().map(|&i| points[i as usize]).collect())
            .collect();
        drop(points);
        // The order (a serial copy of 4 bytes per point) is concatenated
        // while the trees build.
        let (chunks, order) = rayon::join(
            || {
                slices
                    .into_par_iter()
                    .zip(offsets.par_iter())
                    .map(|(points, &offset)| {
                        let (min, max) = bounds(&points);
                        Chunk {
                            min,
                            max,
                            tree: PhotonTree::new_from_slice(&points),
                            offset,
                            points: if keep_points { points } else { Vec::new() },
                        }
                    })
                    .collect()
            },
            || parts.concat(),
        );
        (Self { chunks }, order)
    }

    /// Bytes held by the kept copies of the points.
    pub fn points_bytes(&self) -> usize {
        self.chunks.iter().map(|c| c.points.len() * 12).sum()
    }

    /// Every point within squared distance `r2` of `q` (inclusive) with its
    /// position, in no particular order, into `out` (cleared first). Needs
    /// the points kept (`build`).
    pub fn within_points(&self, q: &[f32; 3], r2: f32, out: &mut Vec<([f32; 3], u32)>) {
        out.clear();
        for c in &self.chunks {
            if c.distance2(q) <= r2 {
                debug_assert!(c.points.len() == c.tree.size(), "points forgotten");
                out.extend(
                    c.tree
                        .within_unsorted::<SquaredEuclidean>(q, r2)
                        .into_iter()
                        .filter_map(|nb| Some((*c.points.get(nb.item as usize)?, c.offset + nb.item))),
                );
            }
        }
    }

    /// Up to `k` nearest points within squared distance `r2` of `q`, in no
    /// particular order.
    pub fn nearest_n_within(&self, q: &[f32; 3], r2: f32, k: NonZero<usize>) -> Vec<Neighbour> {
        let mut near: Vec<(f32, &Chunk)> = self
            .chunks
            .iter()
            .map(|c| (c.distance2(q), c))
            .filter(|(d2, _)| *d2 <= r2)
            .collect();
        if let [(_, c)] = near.as_slice() {
            return c
                .tree
                .nearest_n_within::<SquaredEuclidean>(q, r2, k, false)
                .into_iter()
                .map(|nb| Neighbour {
                    distance: nb.distance,
                    item: c.offset + nb.item,
                })
                .collect();
        }
        near.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut found: Vec<Neighbour> = Vec::new();
        for (d2, c) in near {
            if found.len() >= k.get() {
                // The k-th distance bounds what another chunk could add.
                let kth = found.iter().fold(0.0f32, |m, n| m.max(n.distance));
                if d2 > kth {
                    break;
                }
            }
            found.extend(
                c.tree
                    .nearest_n_within::<SquaredEuclidean>(q, r2, k, false)
                    .into_iter()
                    .map(|nb| Neighbour {
                        distance: nb.distance,
                        item: c.offset + nb.item,
                    }),
            );
            if found.len() > k.get() {
                // Keep the k nearest, ties by item: deterministic.
                found.select_nth_unstable_by(k.get() - 1, |a, b| {
                    a.distance.total_cmp(&b.distance).then(a.item.cmp(&b.item))
                });
                found.truncate(k.get());
            }
        }
        found
    }

    /// The nearest point to `q`, if any (ties by item).
    pub fn nearest_one(&self, q: &[f32; 3]) -> Option<Neighbour> {
        let mut near: Vec<(f32, &Chunk)> = self.chunks.iter().map(|c| (c.distance2(q), c)).collect();
        near.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut best: Option<Neighbour> = None;
        for (d2, c) in near {
            if best.is_some_and(|b| d2 > b.distance) {
                break;
            }
            if c.tree.size() == 0 {
                continue;
            }
            let nb = c.tree.nearest_one::<SquaredEuclidean>(q);
            let cand = Neighbour {
                distance: nb.distance,
                item: c.offset + nb.item,
            };
            if best.is_none_or(|b| (cand.distance, cand.item) < (b.distance, b.item)) {
                best = Some(cand);
            }
        }
        best
    }
}

/// Every this many points of a part, one goes into the sample whose median
/// and bounds choose the cut (exact medians of 71M points took seconds).
const CUT_SAMPLE_STRIDE: usize = 64;

/// `depth` levels of median cuts of `idx` (indices into `points`) across the
/// longest axis, in parallel; each part keeps the order of `idx`. The axis
/// and the median come from a fixed sample (every [`CUT_SAMPLE_STRIDE`]-th
/// point; the median in the total order (coordinate, index)), so the parts
/// are a fixed function of the points and balanced to within the sample's
/// precision.
fn cut(points: &[[f32; 3]], idx: Vec<u32>, depth: u32) -> Vec<Vec<u32>> {
    if depth == 0 || idx.len() < 2 * BUCKET {
        return vec![idx];
    }
    let sample: Vec<u32> = idx.iter().step_by(CUT_SAMPLE_STRIDE).copied().collect();
    let (min, max) = sample.iter().fold(EMPTY_BOUNDS, |b, &i| grow(b, &points[i as usize]));
    let axis = (0..3)
        .max_by(|&a, &b| (max[a] - min[a]).total_cmp(&(max[b] - min[b])))
        .unwrap_or(0);
    let key = |i: u32| (points[i as usize][axis], i);
    let less = |a: (f32, u32), b: (f32, u32)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
    let mut keys: Vec<(f32, u32)> = sample.iter().map(|&i| key(i)).collect();
    let mid = keys.len() / 2;
    let (_, &mut pivot, _) = keys.select_nth_unstable_by(mid, |&a, &b| less(a, b));
    // A stable partition in blocks: each block splits in parallel, then the
    // blocks' halves are concatenated in order.
    let blocks: Vec<(Vec<u32>, Vec<u32>)> = idx
        .par_chunks(1 << 16)
        .map(|block| block.iter().partition(|&&i| less(key(i), pivot).is_lt()))
        .collect();
    drop(idx);
    // The two halves are concatenated side by side (serial copies).
    let (below, above) = rayon::join(
        || concat(blocks.iter().map(|(b, _)| b)),
        || concat(blocks.iter().map(|(_, a)| a)),
    );
    drop(blocks);
    let (mut a, b) = rayon::join(|| cut(points, below, depth - 1), || cut(points, above, depth - 1));
    a.extend(b);
    a
}

/// `parts` one after the other, allocated once.
fn concat<'a>(parts: impl Iterator<Item = &'a Vec<u32>> + Clone) -> Vec<u32> {
    let mut out = Vec::with_capacity(parts.clone().map(Vec::len).sum());
    for p in parts {
        out.extend_from_slice(p);
    }
    out
}

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
        let (tree, order) = ChunkedTree::build(points.clone(), 3, false);
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
            let one = tree.nearest_one(&q).unwrap();
            assert_eq!(one.distance, brute[0]);
        }
    }
}
