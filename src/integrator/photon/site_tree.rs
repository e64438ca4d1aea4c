//! A k-d tree over the precomputed irradiance sites, made for the queries a
//! shading point asks of them: the nearest site, or the few nearest
//! ([`INTERPOLATED_SITES`](super::precomputed::INTERPOLATED_SITES)), within
//! the gather's maximum radius.
//!
//! kiddo's trees, which hold the photons, are built for 64-nearest
//! gathers: leaves of 64 points and a result heap, so a one-site query
//! scans several leaves of 64. Here leaves hold [`LEAF`] points stored axis
//! by axis, every node keeps the bounding box of its points (a query is
//! pruned by its distance to the points, not to a split plane, and one
//! beyond the whole set's reach stops at the root), the search follows the
//! nearer child and defers the farther one, and the answer is a short
//! sorted list. The measurements: `docs/benchmarks.md`, "The sites' own
//! k-d tree".
//!
//! The tree is a balanced median split (Bentley 1975): each node halves its
//! range of points at the median of its longest axis, ties ordered by the
//! points' input index, so the tree is a fixed function of the points. The
//! nodes live in heap order (children `2i + 1`, `2i + 2`) and a node's range
//! is found by halving on the way down, so only the boxes are stored.
//! Items are indices in the tree's point order, which [`SiteTree::build`]
//! returns so that callers reorder their payloads alike.

use super::chunked::{distance2, Neighbour};
use crate::math::Vec3A;

/// Points per leaf at most.
pub const LEAF: usize = 8;

/// Deepest tree a `u32` point count can need, plus the root: bounds the
/// search stack.
const MAX_DEPTH: usize = 33;

/// Ranges above this many points are split on two rayon tasks.
const PARALLEL_SPLIT: usize = 1 << 15;

/// An axis-aligned box: its minimum and maximum corners.
type Bounds = [[f32; 3]; 2];

/// The tree: each node's box in heap order, the points axis by axis in
/// leaf order.
#[derive(Clone, Debug, Default)]
pub struct SiteTree {
    boxes: Vec<Bounds>,
    xs: Vec<f32>,
    ys: Vec<f32>,
    zs: Vec<f32>,
}

/// A node's range of points `[lo, hi)`: a leaf when it holds at most
/// [`LEAF`], else split at `mid` (the right child gets the larger half).
#[inline]
fn mid(lo: usize, hi: usize) -> usize {
    lo + (hi - lo) / 2
}

/// Squared distance from `q` to the box `b` (0 inside).
#[inline]
fn box_distance2(q: &[f32; 3], b: &Bounds) -> f32 {
    let q = Vec3A::from_array(*q);
    let d = (Vec3A::from_array(b[0]) - q)
        .max(q - Vec3A::from_array(b[1]))
        .max(Vec3A::ZERO);
    d.length_squared()
}

impl SiteTree {
    /// Builds the tree over `points`. Returns it and `order`: `order[j]` is
    /// the index in `points` of the point the tree calls `j`.
    pub fn build(points: Vec<[f32; 3]>) -> (Self, Vec<u32>) {
        assert!(points.len() <= u32::MAX as usize, "too many sites for u32 indices");
        let n = points.len();
        let mut tagged: Vec<([f32; 3], u32)> = points.into_iter().zip(0u32..).collect();
        let mut placed: Vec<(usize, Bounds)> = Vec::new();
        if n > 0 {
            split_range(&mut tagged, 0, &mut placed);
        }
        // Heap order with the gaps a ragged last level leaves (never read).
        let slots = placed.iter().map(|&(node, _)| node + 1).max().unwrap_or(0);
        let mut boxes = vec![[[f32::INFINITY; 3], [f32::NEG_INFINITY; 3]]; slots];
        for (node, b) in placed {
            boxes[node] = b;
        }
        let order = tagged.iter().map(|&(_, i)| i).collect();
        let axis = |a: usize| tagged.iter().map(|(p, _)| p[a]).collect::<Vec<f32>>();
        let tree = Self {
            boxes,
            xs: axis(0),
            ys: axis(1),
            zs: axis(2),
        };
        (tree, order)
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.xs.len()
    }

    /// Whether the tree holds no point.
    pub fn is_empty(&self) -> bool {
        self.xs.is_empty()
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.len() * 12 + self.boxes.len() * std::mem::size_of::<Bounds>()
    }

    /// The point the tree calls `item`.
    #[inline]
    pub fn point(&self, item: usize) -> [f32; 3] {
        [self.xs[item], self.ys[item], self.zs[item]]
    }
    /// The `k` nearest points to `q` within squared distance `r2`
    /// (inclusive) into `out`, nearest first, ties at equal distance by
    /// item: the same total order as [`Neighbour::order_key`].
    pub fn nearest_n_within(&self, q: &[f32; 3], r2: f32, k: usize, out: &mut Vec<Neighbour>) {
        out.clear();
        if k == 0 {
            return;
        }
        if k == 1 {
            out.extend(self.nearest_within(q, r2));
            return;
        }
        let mut bound = r2;
        self.search(q, r2, |item, d2| {
            let cand = Neighbour {
                distance: d2,
                item: item as u32,
            };
            let key = cand.order_key();
            if out.len() == k {
                if key >= out[k - 1].order_key() {
                    return bound;
                }
                out[k - 1] = cand;
            } else {
                out.push(cand);
            }
            // One step of insertion sort: the rest is sorted.
            let mut at = out.len() - 1;
            while at > 0 && out[at - 1].order_key() > key {
                out.swap(at - 1, at);
                at -= 1;
            }
            if out.len() == k {
                bound = out[k - 1].distance;
            }
            bound
        });
    }

    /// The nearest point to `q` within squared distance `r2` (inclusive),
    /// ties by item.
    pub fn nearest_within(&self, q: &[f32; 3], r2: f32) -> Option<Neighbour> {
        let mut best: Option<Neighbour> = None;
        self.search(q, r2, |item, d2| {
            let cand = Neighbour {
                distance: d2,
                item: item as u32,
            };
            if best.is_none_or(|b| cand.order_key() < b.order_key()) {
                best = Some(cand);
            }
            best.map_or(r2, |b| b.distance)
        });
        best
    }

    /// Every point within squared distance `r2` of `q` (inclusive) with its
    /// position, in the tree's order, into `out` (cleared first).
    pub fn within_points(&self, q: &[f32; 3], r2: f32, out: &mut Vec<([f32; 3], u32)>) {
        out.clear();
        self.search(q, r2, |item, _| {
            out.push((self.point(item), item as u32));
            r2
        });
    }

    /// Calls `visit(item, squared distance)` on the points within `bound`
    /// of `q` in every leaf whose box lies within it: down the nearer child
    /// of each node, the farther one kept for later when its box is within
    /// the bound; `visit` returns the new bound (it may only shrink).
    #[inline]
    fn search(&self, q: &[f32; 3], mut bound: f32, mut visit: impl FnMut(usize, f32) -> f32) {
        let n = self.len();
        if n == 0 || box_distance2(q, &self.boxes[0]) > bound {
            return;
        }
        // Deferred far children: (node, lo, hi, squared distance to its box).
        let mut stack = [(0u32, 0u32, 0u32, 0.0f32); MAX_DEPTH];
        let mut top = 0;
        let (mut node, mut lo, mut hi) = (0usize, 0usize, n);
        loop {
            if hi - lo <= LEAF {
                for j in lo..hi {
                    let d = distance2(q, &self.point(j));
                    if d <= bound {
                        bound = visit(j, d);
                    }
                }
                // The next deferred child still within the bound.
                loop {
                    if top == 0 {
                        return;
                    }
                    top -= 1;
                    let (f, flo, fhi, gap) = stack[top];
                    if gap <= bound {
                        (node, lo, hi) = (f as usize, flo as usize, fhi as usize);
                        break;
                    }
                }
                continue;
            }
            let m = mid(lo, hi);
            let (l, r) = (2 * node + 1, 2 * node + 2);
            let (dl, dr) = (box_distance2(q, &self.boxes[l]), box_distance2(q, &self.boxes[r]));
            let (near, far) = if dl <= dr {
                ((l, lo, m, dl), (r, m, hi, dr))
            } else {
                ((r, m, hi, dr), (l, lo, m, dl))
            };
            if far.3 <= bound {
                stack[top] = (far.0 as u32, far.1 as u32, far.2 as u32, far.3);
                top += 1;
            }
            if near.3 <= bound {
                (node, lo, hi) = (near.0, near.1, near.2);
                continue;
            }
            // Neither child is within reach; resume from the deferred ones.
            (node, lo, hi) = (0, 0, 0);
        }
    }
}

/// The box of `points`.
fn bounds(points: &[([f32; 3], u32)]) -> Bounds {
    points
        .iter()
        .fold([[f32::INFINITY; 3], [f32::NEG_INFINITY; 3]], |[lo, hi], (p, _)| {
            [
                [lo[0].min(p[0]), lo[1].min(p[1]), lo[2].min(p[2])],
                [hi[0].max(p[0]), hi[1].max(p[1]), hi[2].max(p[2])],
            ]
        })
}

/// Records the box of `points` (node `node`'s range) in `placed` and, above
/// a leaf, splits them at the median of the box's longest axis and recurses.
fn split_range(points: &mut [([f32; 3], u32)], node: usize, placed: &mut Vec<(usize, Bounds)>) {
    let b = bounds(points);
    placed.push((node, b));
    if points.len() <= LEAF {
        return;
    }
    let extent = [b[1][0] - b[0][0], b[1][1] - b[0][1], b[1][2] - b[0][2]];
    let axis = (0..3).fold(0, |a, c| if extent[c] > extent[a] { c } else { a });
    let m = mid(0, points.len());
    points.select_nth_unstable_by(m, |a, b| a.0[axis].total_cmp(&b.0[axis]).then(a.1.cmp(&b.1)));
    let (left, right) = points.split_at_mut(m);
    if left.len() + right.len() > PARALLEL_SPLIT {
        let mut right_placed = Vec::new();
        rayon::join(
            || split_range(left, 2 * node + 1, placed),
            || split_range(right, 2 * node + 2, &mut right_placed),
        );
        placed.append(&mut right_placed);
    } else {
        split_range(left, 2 * node + 1, placed);
        split_range(right, 2 * node + 2, placed);
    }
}

#[cfg(test)]
mod tests {
    use super::super::chunked::brute_force_nearest as brute;
    use super::*;
    use crate::math::rng::{Domain, Rng};

    /// Queries equal brute force, on points on two planes whose density
    /// varies a hundredfold, with duplicated points (ties), queries on and
    /// off the points, k = 1 and 8 and radii from none to everything.
    #[test]
    fn queries_match_brute_force() {
        let mut rng = Rng::new(5, Domain::Analysis, 0, 0);
        let mut points: Vec<[f32; 3]> = (0..20_000)
            .map(|i| {
                let (a, b) = rng.f32x2();
                if i % 2 == 0 {
                    [a * a * a * 4.0, 0.0, b * 4.0]
                } else {
                    [0.0, a * 4.0, b * b * 4.0]
                }
            })
            .collect();
        points.extend_from_within(..500);
        let (tree, order) = SiteTree::build(points.clone());
        let ordered: Vec<[f32; 3]> = order.iter().map(|&i| points[i as usize]).collect();
        assert!((0..ordered.len()).all(|j| tree.point(j) == ordered[j]));
        let mut out = Vec::new();
        let mut within = Vec::new();
        for i in 0..600 {
            let (a, b) = rng.f32x2();
            let q = if i % 3 == 0 {
                ordered[(a * ordered.len() as f32) as usize % ordered.len()]
            } else {
                [a * 4.4 - 0.2, (b - 0.5) * 0.2, b * 4.4 - 0.2]
            };
            for (k, r2) in [(1, 0.01f32), (8, 0.01), (1, 100.0), (8, 100.0), (8, 0.0), (3, 1e-4)] {
                tree.nearest_n_within(&q, r2, k, &mut out);
                let got: Vec<(u32, u32)> = out.iter().map(|nb| (nb.distance.to_bits(), nb.item)).collect();
                assert_eq!(
                    got,
                    brute(&ordered, &q, r2, k),
                    "k = {k}, r2 = {r2}, query {i} at {q:?}"
                );
            }
            tree.within_points(&q, 0.02, &mut within);
            let mut got: Vec<u32> = within
                .iter()
                .map(|&(p, j)| {
                    assert_eq!(p, ordered[j as usize]);
                    j
                })
                .collect();
            got.sort_unstable();
            let want: Vec<u32> = brute(&ordered, &q, 0.02, usize::MAX)
                .into_iter()
                .map(|(_, j)| j)
                .collect();
            let mut want = want;
            want.sort_unstable();
            assert_eq!(got, want, "within, query {i}");
        }
    }

    #[test]
    fn small_and_empty_trees_answer() {
        let (empty, order) = SiteTree::build(Vec::new());
        assert!(empty.is_empty() && order.is_empty());
        let mut out = vec![Neighbour { distance: 1.0, item: 7 }];
        empty.nearest_n_within(&[0.0; 3], f32::INFINITY, 8, &mut out);
        assert!(out.is_empty());
        for n in [1usize, LEAF, LEAF + 1, 3 * LEAF + 5] {
            let points: Vec<[f32; 3]> = (0..n).map(|i| [i as f32, 0.0, 0.0]).collect();
            let (tree, order) = SiteTree::build(points.clone());
            tree.nearest_n_within(&[n as f32 + 1.0, 0.0, 0.0], f32::INFINITY, 1, &mut out);
            assert_eq!(order[out[0].item as usize] as usize, n - 1, "n = {n}");
            tree.nearest_n_within(&[0.0; 3], f32::INFINITY, n + 3, &mut out);
            assert_eq!(out.len(), n);
        }
    }

    /// The tree, hence its items, is the same for any thread count.
    #[test]
    fn build_is_deterministic_across_threads() {
        let mut rng = Rng::new(9, Domain::Analysis, 0, 0);
        let points: Vec<[f32; 3]> = (0..3 * PARALLEL_SPLIT)
            .map(|_| {
                let (a, b) = rng.f32x2();
                [a, (a * 1000.0).floor() / 1000.0, b]
            })
            .collect();
        let build = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| SiteTree::build(points.clone()).1)
        };
        assert_eq!(build(1), build(3));
    }
}
