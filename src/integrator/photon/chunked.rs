//! A point set split into spatial chunks, one kiddo immutable k-d tree per
//! chunk, built in parallel: kiddo builds a tree on one thread (≈ 20 s for
//! 10M photons here), so large maps are first cut at the median of the
//! longest axis, recursively ([`chunk_depth`] levels: 4 chunks from 1M
//! points, 8 from 16M), and the chunks' trees built at once with rayon.
//! The cut is a fixed function of the points (ties broken by index), so
//! the structure is identical for any thread count.
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

/// One chunk: its points' bounds (tree coordinates), its tree and the
/// concatenated index of its first point.
struct Chunk {
    min: [f32; 3],
    max: [f32; 3],
    tree: PhotonTree,
    offset: u32,
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
    pub fn build(points: Vec<[f32; 3]>, depth: u32) -> (Self, Vec<u32>) {
        assert!(points.len() <= u32::MAX as usize, "too many points for u32 indices");
        let mut order: Vec<u32> = (0..points.len() as u32).collect();
        let mut ranges = vec![(0usize, points.len())];
        for _ in 0..depth {
            let mut next = Vec::with_capacity(ranges.len() * 2);
            for &(lo, hi) in &ranges {
                if hi - lo < 2 * BUCKET {
                    next.push((lo, hi));
                    continue;
                }
                let (min, max) = bounds(&points, &order[lo..hi]);
                let axis = (0..3)
                    .max_by(|&a, &b| (max[a] - min[a]).total_cmp(&(max[b] - min[b])))
                    .unwrap_or(0);
                let mid = (hi - lo) / 2;
                // Total order (coordinate, index): a deterministic cut.
                order[lo..hi].select_nth_unstable_by(mid, |&i, &j| {
                    points[i as usize][axis]
                        .total_cmp(&points[j as usize][axis])
                        .then(i.cmp(&j))
                });
                next.push((lo, lo + mid));
                next.push((lo + mid, hi));
            }
            ranges = next;
        }
        let chunks = ranges
            .par_iter()
            .map(|&(lo, hi)| {
                let slice: Vec<[f32; 3]> = order[lo..hi].iter().map(|&i| points[i as usize]).collect();
                let (min, max) = bounds(&points, &order[lo..hi]);
                Chunk {
                    min,
                    max,
                    tree: PhotonTree::new_from_slice(&slice),
                    offset: lo as u32,
                }
            })
            .collect();
        (Self { chunks }, order)
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

/// Bounds of `points[i]` for `i` in `idx`.
fn bounds(points: &[[f32; 3]], idx: &[u32]) -> ([f32; 3], [f32; 3]) {
    let mut min = [f32::INFINITY; 3];
    let mut max = [f32::NEG_INFINITY; 3];
    for &i in idx {
        let p = points[i as usize];
        for a in 0..3 {
            min[a] = min[a].min(p[a]);
            max[a] = max[a].max(p[a]);
        }
    }
    (min, max)
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
            let one = tree.nearest_one(&q).unwrap();
            assert_eq!(one.distance, brute[0]);
        }
    }
}
