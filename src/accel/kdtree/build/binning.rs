//! Choosing a node's split plane: the exact sweeps of `sah` for small
//! nodes, min-max binning (Shevtsov, Soupikov & Kapustin 2007) for large ones.

use super::sah::{event, order_key, sweep_axis, sweep_two_lists, SplitChoice, SplitGeometry, END, PLANAR, START};
use super::{Builder, Primitives, Ref, PARALLEL_NODE_MIN_PRIMS};
use crate::math::{Aabb, Vec3A};
use rayon::prelude::*;

/// Nodes with at most this many primitives get the exact SAH sweep (sorted
/// events, Wald & Havran Algorithm 4, `O(n log n)` per node); larger ones are
/// binned.
pub(super) const EXACT_MAX_PRIMS: usize = 64;

/// Most bins per axis of a binned node (bin boundaries are the candidate planes).
const BINS: usize = 64;

/// Bins used for a node of `n` primitives. Fewer bins for nodes just above
/// `EXACT_MAX_PRIMS` were tried: their misestimated straddler counts more than
/// doubled the references on the dragon.
#[inline]
fn bins_for(_n: usize) -> usize {
    BINS
}

/// Start/end counts per bin of one axis (Shevtsov, Soupikov, Kapustin 2007,
/// "Highly parallel fast KD-tree construction": min-max binning).
#[derive(Clone)]
struct BinCounts {
    starts: [[u32; BINS]; 3],
    ends: [[u32; BINS]; 3],
}

impl BinCounts {
    fn zero() -> Self {
        Self {
            starts: [[0; BINS]; 3],
            ends: [[0; BINS]; 3],
        }
    }

    fn add(mut self, o: &BinCounts) -> Self {
        for k in 0..3 {
            for b in 0..BINS {
                self.starts[k][b] += o.starts[k][b];
                self.ends[k][b] += o.ends[k][b];
            }
        }
        self
    }
}

impl<P: Primitives> Builder<'_, P> {
    /// The cheapest plane of a node: the exact sweep for small nodes; for
    /// large ones the binned estimate, plus the planes on the faces of the
    /// primitives' bounds (they cut off empty space exactly, which bins only
    /// approximate).
    pub(super) fn find_split(&self, refs: &[Ref], cell: &Aabb) -> Option<SplitChoice> {
        let n = refs.len();
        let mut candidates: [Option<SplitChoice>; 3] = [None; 3];
        if n <= EXACT_MAX_PRIMS {
            // Start and end keys on the stack (no allocation per node); the
            // rare axis with flat references takes the tagged-event sweep.
            let mut starts = [0u32; EXACT_MAX_PRIMS];
            let mut ends = [0u32; EXACT_MAX_PRIMS];
            let (starts, ends) = (&mut starts[..n], &mut ends[..n]);
            for (axis, slot) in candidates.iter_mut().enumerate() {
                let mut flat = false;
                for ((s, e), r) in starts.iter_mut().zip(ends.iter_mut()).zip(refs) {
                    let (lo, hi) = (r.bounds.min[axis], r.bounds.max[axis]);
                    flat |= lo == hi;
                    *s = order_key(lo);
                    *e = order_key(hi);
                }
                *slot = if flat {
                    let mut events = Vec::with_capacity(2 * n);
                    for r in refs {
                        let (lo, hi) = (r.bounds.min[axis], r.bounds.max[axis]);
                        if lo == hi {
                            events.push(event(lo, PLANAR, 0));
                        } else {
                            events.push(event(lo, START, 0));
                            events.push(event(hi, END, 0));
                        }
                    }
                    events.sort_unstable();
                    sweep_axis(&self.params, cell, axis, &events, n)
                } else {
                    starts.sort_unstable();
                    ends.sort_unstable();
                    sweep_two_lists(&self.params, cell, axis, starts, ends)
                };
            }
        } else {
            let bins = bins_for(n);
            let counts = if n >= PARALLEL_NODE_MIN_PRIMS {
                refs.par_chunks(16_384)
                    .map(|c| bin_refs(c, cell, bins))
                    .reduce(BinCounts::zero, |a, b| a.add(&b))
            } else {
                bin_refs(refs, cell, bins)
            };
            let content = if n >= PARALLEL_NODE_MIN_PRIMS {
                refs.par_iter().map(|r| r.bounds).reduce(|| Aabb::EMPTY, Aabb::union)
            } else {
                refs.iter().fold(Aabb::EMPTY, |a, r| a.union(r.bounds))
            };
            for (axis, slot) in candidates.iter_mut().enumerate() {
                *slot = self.sweep_bins(&counts, bins, cell, &content, axis, n);
            }
        }
        // Lowest cost; ties go to the lower axis (fixed order: deterministic).
        candidates
            .into_iter()
            .flatten()
            .fold(None, |best: Option<SplitChoice>, c| match best {
                Some(b) if b.cost <= c.cost => Some(b),
                _ => Some(c),
            })
    }

    /// SAH over the bin boundaries of one axis, and over the faces of the
    /// content bounds (`content`), which split off empty space: all `n`
    /// primitives on one side.
    fn sweep_bins(
        &self,
        counts: &BinCounts,
        bins: usize,
        cell: &Aabb,
        content: &Aabb,
        axis: usize,
        n: usize,
    ) -> Option<SplitChoice> {
        let geometry = SplitGeometry::new(cell, axis)?;
        let (lo, hi) = (geometry.lo, geometry.hi);
        let mut best: Option<SplitChoice> = None;
        let mut consider = |pos: f32, n_left: usize, n_right: usize, planar_left: bool| {
            if !(pos > lo && pos < hi) {
                return;
            }
            let (pl, pr) = geometry.probabilities(pos);
            let cost = self.params.split_cost(pl, pr, n_left, n_right);
            if best.is_none_or(|b| cost < b.cost) {
                best = Some(SplitChoice {
                    cost,
                    axis,
                    pos,
                    planar_left,
                });
            }
        };
        // Empty space below / above the primitives (primitives lying in the
        // plane go to the non-empty side).
        consider(content.min[axis], 0, n, false);
        consider(content.max[axis], n, 0, true);
        let width = hi - lo;
        let (mut n_left, mut n_right) = (0usize, n);
        for bin in 1..bins {
            // Plane at the lower boundary of `bin`: primitives starting in a
            // lower bin reach its left, those ending in a lower bin are
            // entirely left of it (an estimate: exact sides are decided by
            // comparing with the chosen plane).
            n_left += counts.starts[axis][bin - 1] as usize;
            n_right -= counts.ends[axis][bin - 1] as usize;
            let pos = lo + width * (bin as f32 / bins as f32);
            consider(pos, n_left, n_right, true);
        }
        best
    }
}

/// Min-max bin counts of `refs` in `bins` bins on the three axes of `cell`.
fn bin_refs(refs: &[Ref], cell: &Aabb, bins: usize) -> BinCounts {
    let mut counts = BinCounts::zero();
    let ext = cell.extent();
    let lo = cell.min;
    let scale = Vec3A::select(ext.cmpgt(Vec3A::ZERO), Vec3A::splat(bins as f32) / ext, Vec3A::ZERO);
    // Bin of a scaled coordinate: its integer part clamped to the bins (NaN
    // to the first, as the `as` conversion does). Clamping in floats, three
    // lanes at once, leaves a conversion of a value known to be in range.
    let last = Vec3A::splat((bins - 1) as f32);
    for r in refs {
        let s = ((r.bounds.min - lo) * scale).max(Vec3A::ZERO).min(last).to_array();
        let e = ((r.bounds.max - lo) * scale).max(Vec3A::ZERO).min(last).to_array();
        for axis in 0..3 {
            counts.starts[axis][s[axis] as usize % BINS] += 1;
            counts.ends[axis][e[axis] as usize % BINS] += 1;
        }
    }
    counts
}
