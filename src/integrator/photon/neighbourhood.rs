//! Exact k-nearest queries answered from cached neighbourhoods.
//!
//! A `Neighbourhood` holds every point within `R` of a centre `c`. For a
//! query at distance `d` from `c`, every point within `R − d` of the query
//! is in it (triangle inequality). So if the `k` nearest among the cached
//! points reach only `ρ ≤ R − d` (or, with fewer than `k` within the
//! maximum radius, `ρ` is that radius), no point outside can be nearer and
//! the answer is exact: the `k` nearest within the maximum radius, ties at
//! the k-th distance broken by item. Queries that follow each other in
//! space (the samples of one pixel, neighbouring irradiance sites) then
//! re-rank a few cached points instead of walking the tree.
//!
//! The cache changes only how fast a query is, never its answer, so any
//! sequence of queries may share one (a tile, a rayon task) without
//! affecting determinism.

use super::chunked::{distance2, Neighbour};
use super::site_tree::SiteTree;
use std::num::NonZero;

/// Relative margin of the exactness test, far above the rounding of the
/// distances it compares (the tree's and ours).
const MARGIN: f32 = 1e-4;

/// Every point within `radius` of `center` (tree coordinates), with its
/// position, and how far the answer at `center` reached.
#[derive(Clone, Debug, Default)]
struct Neighbourhood {
    center: [f32; 3],
    radius: f32,
    reach: f32,
    points: Vec<([f32; 3], u32)>,
}

/// Recently searched neighbourhoods, reused by nearby queries.
#[derive(Clone, Debug)]
pub struct NeighbourCache {
    entries: Vec<Neighbourhood>,
    capacity: usize,
    next: usize,
    /// A miss caches every point within this factor of its answer's reach:
    /// the entry then answers queries up to `(factor − 1)·reach` away.
    factor: f32,
    /// Queries answered from an entry, and by the tree.
    pub hits: u64,
    /// Queries that searched the tree.
    pub misses: u64,
}

impl NeighbourCache {
    /// A cache of `capacity` neighbourhoods, each `factor` (> 1) times its
    /// answer's reach.
    pub fn new(capacity: usize, factor: f32) -> Self {
        assert!(capacity > 0 && factor > 1.0);
        Self {
            entries: Vec::with_capacity(capacity),
            capacity,
            next: 0,
            factor,
            hits: 0,
            misses: 0,
        }
    }

    /// What [`nearest`](Self::nearest) answers, from the tree alone (the
    /// same distances, computed alike, and the same order): for queries in
    /// no particular order (a path's vertices), where an entry would rarely
    /// answer and every miss would search twice.
    pub fn nearest_uncached(
        tree: &SiteTree,
        q: &[f32; 3],
        max_radius: f32,
        k: NonZero<usize>,
        out: &mut Vec<Neighbour>,
    ) {
        tree.nearest_n_within(q, max_radius * max_radius, k.get(), out);
    }

    /// The `k` nearest points of `tree` to `q` within
    /// `max_radius`, into `out` nearest first (sorted, so that sums over the
    /// answer never depend on the cache): exactly, whatever
    /// the cache holds (ties at the k-th distance broken by item). A miss
    /// first searches within `factor` times the reach of the nearest
    /// entry's answer, a guess of this one's, and keeps it when exact; else
    /// it asks the tree for the answer's reach.
    pub fn nearest(
        &mut self,
        tree: &SiteTree,
        q: &[f32; 3],
        max_radius: f32,
        k: NonZero<usize>,
        out: &mut Vec<Neighbour>,
    ) {
        // The entry whose ball reaches farthest beyond q: the one most
        // likely to answer exactly.
        let best = self
            .entries
            .iter()
            .enumerate()
            .map(|(i, e)| (i, e.radius - distance2(q, &e.center).sqrt()))
            .max_by(|a, b| a.1.total_cmp(&b.1));
        let mut guess = None;
        if let Some((i, slack)) = best {
            let e = &self.entries[i];
            if slack > 0.0 && rank(q, &e.points, max_radius, k, out) <= slack - e.radius * MARGIN {
                self.hits += 1;
                return;
            }
            guess = Some(e.reach);
        }
        self.misses += 1;
        let slot = if self.entries.len() < self.capacity {
            self.entries.push(Neighbourhood::default());
            self.entries.len() - 1
        } else {
            let slot = self.next;
            self.next = (self.next + 1) % self.capacity;
            slot
        };
        let entry = &mut self.entries[slot];
        if let Some(reach) = guess {
            if fill(entry, tree, q, reach * self.factor, max_radius, k, out) {
                return;
            }
        }
        // `out` is overwritten by `fill` below.
        tree.nearest_n_within(q, max_radius * max_radius, k.get(), out);
        let reach = if out.len() == k.get() {
            out.last().map_or(max_radius, |nb| nb.distance.sqrt())
        } else {
            max_radius
        };
        let exact = fill(entry, tree, q, reach * self.factor, max_radius, k, out);
        debug_assert!(exact, "a radius beyond the answer's reach is exact");
    }
}

/// Makes `entry` every point within `radius` of `q`, ranks them into `out`
/// and tells whether that answer is exact (reaches less far than
/// `radius`). The tree is searched a little wider than `radius`: it
/// compares squared distances, the exactness test their square roots.
fn fill(
    entry: &mut Neighbourhood,
    tree: &SiteTree,
    q: &[f32; 3],
    radius: f32,
    max_radius: f32,
    k: NonZero<usize>,
    out: &mut Vec<Neighbour>,
) -> bool {
    let searched = radius * (1.0 + MARGIN);
    tree.within_points(q, searched * searched, &mut entry.points);
    entry.center = *q;
    entry.radius = radius;
    entry.reach = rank(q, &entry.points, max_radius, k, out);
    let exact = entry.reach <= radius * (1.0 - MARGIN);
    // Beside a dense region (a caustic's edge, where fewer than k points
    // lie within the maximum radius) the ball can hold thousands of points,
    // and every later query would rank them all: keep the nearest
    // `CAP_PER_K·k` only, and shrink the radius to what they cover (every
    // point strictly nearer than the first one dropped). `out` was ranked
    // from all of them.
    let cap = CAP_PER_K * k.get();
    if entry.points.len() > cap {
        let d2 = |p: &[f32; 3]| distance2(q, p);
        entry
            .points
            .select_nth_unstable_by(cap, |a, b| d2(&a.0).total_cmp(&d2(&b.0)));
        entry.radius = d2(&entry.points[cap].0).sqrt() * (1.0 - MARGIN);
        entry.points.truncate(cap);
    }
    exact
}

/// A cached neighbourhood keeps at most this many points per answer point.
const CAP_PER_K: usize = 6;

/// The `k` nearest of `points` to `q` within `max_radius` into `out`,
/// sorted by squared distance, then item, and how far the answer reaches:
/// the k-th distance when `k` were found, else `max_radius` (all within it
/// counted). Selected on [`Neighbour::order_key`]: an insertion into a
/// sorted list per point (a mispredicted branch and a move each) took a
/// quarter of the underwater image's time.
#[inline]
fn rank(q: &[f32; 3], points: &[([f32; 3], u32)], max_radius: f32, k: NonZero<usize>, out: &mut Vec<Neighbour>) -> f32 {
    let max_r2 = max_radius * max_radius;
    let k = k.get();
    out.clear();
    out.extend(points.iter().filter_map(|(p, item)| {
        let d2 = distance2(q, p);
        (d2 <= max_r2).then_some(Neighbour {
            distance: d2,
            item: *item,
        })
    }));
    if out.len() > k {
        out.select_nth_unstable_by_key(k - 1, Neighbour::order_key);
        out.truncate(k);
    }
    out.sort_unstable_by_key(Neighbour::order_key);
    if out.len() < k {
        return max_radius;
    }
    out.last().map_or(max_radius, |nb| nb.distance.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::{Domain, Rng};

    /// Cached answers equal a brute-force k-nearest search (same distances,
    /// same items) and the tree's uncached answer, in the same order, along walks with jumps, for k = 8 and 64, in a point set
    /// whose density varies tenfold; and most queries of a walk hit.
    #[test]
    fn cached_answers_are_exact() {
        let mut rng = Rng::new(21, Domain::Analysis, 0, 0);
        let points: Vec<[f32; 3]> = (0..60_000)
            .map(|_| {
                let (a, b) = rng.f32x2();
                [a * a * 2.0, 0.3 * a + 0.01 * b, b * 2.0]
            })
            .collect();
        let (tree, order) = SiteTree::build(points.clone());
        for (k, max_radius) in [(8usize, 0.2f32), (64, 0.15)] {
            let k = NonZero::new(k).unwrap();
            let mut cache = NeighbourCache::new(3, 1.6);
            let mut out = Vec::new();
            let mut q = [0.0f32; 3];
            for i in 0..3000 {
                let (a, b) = rng.f32x2();
                q = if i % 40 == 0 {
                    [a * 2.2 - 0.1, 0.3 * a, b * 2.2 - 0.1]
                } else {
                    [q[0] + (a - 0.5) * 0.01, q[1], q[2] + (b - 0.5) * 0.01]
                };
                cache.nearest(&tree, &q, max_radius, k, &mut out);
                let mut got: Vec<(u32, u32)> = out.iter().map(|n| (n.distance.to_bits(), n.item)).collect();
                got.sort_unstable();
                let mut all: Vec<(f32, u32)> = (0..points.len())
                    .map(|j| (distance2(&q, &points[order[j] as usize]), j as u32))
                    .filter(|&(d2, _)| d2 <= max_radius * max_radius)
                    .collect();
                all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                all.truncate(k.get());
                let mut want: Vec<(u32, u32)> = all.iter().map(|&(d, j)| (d.to_bits(), j)).collect();
                want.sort_unstable();
                assert_eq!(got, want, "k = {k}, query {i} at {q:?}");
                let mut direct = Vec::new();
                NeighbourCache::nearest_uncached(&tree, &q, max_radius, k, &mut direct);
                assert_eq!(direct, out, "uncached: k = {k}, query {i} at {q:?}");
            }
            assert!(
                cache.hits > 3 * cache.misses,
                "k = {k}: {} hits, {} misses",
                cache.hits,
                cache.misses
            );
        }
    }
}
