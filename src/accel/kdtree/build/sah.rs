//! The surface area heuristic: its constants and costs, split events packed
//! in integers, and the exact sweeps over sorted events (Wald & Havran 2006
//! Algorithm 4).

use crate::accel::kdtree::node::MAX_TREE_DEPTH;
use crate::math::Aabb;

/// SAH constants and termination rules.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SahParams {
    /// Cost of one traversal step (Wald & Havran's K_T).
    pub traversal_cost: f32,
    /// Cost of one primitive test (K_I).
    pub intersect_cost: f32,
    /// Factor applied to the cost of a split with an empty side (< 1 favours
    /// cutting off empty space).
    pub empty_bonus: f32,
    /// Nodes with at most this many primitives become leaves.
    pub leaf_size: usize,
    /// Depth limit; `None` takes `8 + 1.3·log2(N)` (pbrt-v3's rule).
    pub max_depth: Option<u32>,
}

impl Default for SahParams {
    /// Tuned on the Stanford dragon (tests/kdtree_throughput.rs): K_T = 30,
    /// K_I = 20, empty bonus 0.9, leaves of up to 2 primitives. Wald &
    /// Havran's K_T = 15, λ = 0.8 with single-primitive leaves cut slivers of
    /// empty space down to the depth limit (3–4 M nodes, 60 % empty leaves)
    /// for no gain in rays per second and a build three times longer.
    fn default() -> Self {
        Self {
            traversal_cost: 30.0,
            intersect_cost: 20.0,
            empty_bonus: 0.9,
            leaf_size: 2,
            max_depth: None,
        }
    }
}

impl SahParams {
    /// `8 + 1.3·log2(n)` (pbrt-v3), capped so the traversal stack never overflows.
    pub fn depth_limit(&self, n: usize) -> u32 {
        let d = self
            .max_depth
            .unwrap_or_else(|| (8.0 + 1.3 * (n.max(1) as f32).log2()).round() as u32);
        d.min(MAX_TREE_DEPTH)
    }

    /// Wald & Havran eq. (3): `λ(p)·(K_T + K_I·(P_L·N_L + P_R·N_R))`, with
    /// `P = SA(child) / SA(node)` and `λ` the empty-space bonus when a side is empty.
    #[inline]
    pub fn split_cost(&self, p_left: f32, p_right: f32, n_left: usize, n_right: usize) -> f32 {
        let bonus = if n_left == 0 || n_right == 0 {
            self.empty_bonus
        } else {
            1.0
        };
        bonus * (self.traversal_cost + self.intersect_cost * (p_left * n_left as f32 + p_right * n_right as f32))
    }

    /// Cost of not splitting.
    #[inline]
    pub fn leaf_cost(&self, n: usize) -> f32 {
        self.intersect_cost * n as f32
    }
}

/// Event kinds, in the sort order Wald & Havran require at equal positions:
/// ends before planars before starts.
pub(super) const END: u64 = 0;
pub(super) const PLANAR: u64 = 1;
pub(super) const START: u64 = 2;

/// Primitive indices local to a node take the low 30 bits of an event.
#[cfg(test)]
const INDEX_MASK: u64 = (1 << 30) - 1;

/// f32 → u32 whose unsigned order is the float order (−0 is folded onto +0).
#[inline]
pub(super) fn order_key(pos: f32) -> u32 {
    let bits = (pos + 0.0).to_bits();
    if bits & 0x8000_0000 != 0 {
        !bits
    } else {
        bits | 0x8000_0000
    }
}

#[inline]
fn from_order_key(key: u32) -> f32 {
    f32::from_bits(if key & 0x8000_0000 != 0 {
        key & 0x7fff_ffff
    } else {
        !key
    })
}

/// An event packed in a u64 so that integer order is (position, kind, index):
/// position key << 32 | kind << 30 | local primitive index.
#[inline]
pub(super) fn event(pos: f32, kind: u64, index: u32) -> u64 {
    ((order_key(pos) as u64) << 32) | (kind << 30) | index as u64
}

#[inline]
fn event_key(e: u64) -> u32 {
    (e >> 32) as u32
}

#[inline]
fn event_kind(e: u64) -> u64 {
    (e >> 30) & 3
}

#[cfg(test)]
fn event_index(e: u64) -> usize {
    (e & INDEX_MASK) as usize
}

/// Pushes the events of bounds `b` of local primitive `index` on each axis.
#[cfg(test)]
fn push_events(events: &mut [Vec<u64>; 3], b: &Aabb, index: u32) {
    for (axis, list) in events.iter_mut().enumerate() {
        let (lo, hi) = (b.min[axis], b.max[axis]);
        if lo == hi {
            list.push(event(lo, PLANAR, index));
        } else {
            list.push(event(lo, START, index));
            list.push(event(hi, END, index));
        }
    }
}

/// The best plane of a node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct SplitChoice {
    pub(crate) cost: f32,
    pub(crate) axis: usize,
    pub(crate) pos: f32,
    /// Where primitives lying in the plane go.
    pub(crate) planar_left: bool,
}

/// Wald & Havran Algorithm 4 on one axis: sweeps the sorted events, keeping
/// the counts left (N_L), in the plane (N_P) and right (N_R) of each
/// candidate position, and returns the cheapest plane strictly inside the cell
/// (planes on the cell's faces would only create flat empty cells).
pub(crate) fn sweep_axis(
    params: &SahParams,
    cell: &Aabb,
    axis: usize,
    events: &[u64],
    n: usize,
) -> Option<SplitChoice> {
    let geometry = SplitGeometry::new(cell, axis)?;
    let (lo, hi) = (geometry.lo, geometry.hi);
    let (mut n_left, mut n_right) = (0usize, n);
    let mut best: Option<SplitChoice> = None;
    let mut i = 0;
    while i < events.len() {
        let key = event_key(events[i]);
        let (mut ending, mut planar, mut starting) = (0usize, 0usize, 0usize);
        while i < events.len() && event_key(events[i]) == key && event_kind(events[i]) == END {
            ending += 1;
            i += 1;
        }
        while i < events.len() && event_key(events[i]) == key && event_kind(events[i]) == PLANAR {
            planar += 1;
            i += 1;
        }
        while i < events.len() && event_key(events[i]) == key && event_kind(events[i]) == START {
            starting += 1;
            i += 1;
        }
        let n_planar = planar;
        n_right -= planar + ending;
        let pos = from_order_key(key);
        if pos > lo && pos < hi {
            let (p_left, p_right) = geometry.probabilities(pos);
            let cost_l = params.split_cost(p_left, p_right, n_left + n_planar, n_right);
            let cost_r = params.split_cost(p_left, p_right, n_left, n_right + n_planar);
            let (cost, planar_left) = if cost_l <= cost_r {
                (cost_l, true)
            } else {
                (cost_r, false)
            };
            if best.is_none_or(|b| cost < b.cost) {
                best = Some(SplitChoice {
                    cost,
                    axis,
                    pos,
                    planar_left,
                });
            }
        }
        n_left += starting + n_planar;
    }
    best
}

/// Algorithm 4 of Wald & Havran for an axis without flat references (almost
/// every node), with no data-dependent branches: the sorted start and end
/// keys are merged (ends first at equal positions) and every event is costed
/// as it is taken, with `N_L` = starts taken before it and `N_R` = `n` − ends
/// taken up to and including it. At the last end of a position, and at its
/// first start, these are the sweep's exact counts (`N_L = #{lo < p}`,
/// `N_R = #{hi > p}`); at the other events of the position they are larger,
/// so the cost is no lower (it rises with the counts, and the empty-side bonus
/// only applies to smaller counts). The first event of the lowest cost is
/// therefore at the lowest position of the lowest exact cost, with that cost:
/// the same choice as `sweep_axis` (with no planar references, both planar
/// sides cost the same and `sweep_axis` puts them left).
pub(super) fn sweep_two_lists(
    params: &SahParams,
    cell: &Aabb,
    axis: usize,
    starts: &[u32],
    ends: &[u32],
) -> Option<SplitChoice> {
    let geometry = SplitGeometry::new(cell, axis)?;
    let n = ends.len();
    debug_assert_eq!(starts.len(), n);
    if n == 0 {
        return None;
    }
    let (mut i, mut j) = (0usize, 0usize);
    let (mut found, mut best_cost, mut best_pos) = (false, 0f32, 0f32);
    // Every start key is at most its own end key, so the starts never run
    // out after the ends: the loop takes exactly 2n events.
    while j < n {
        let next_start = starts[i.min(n - 1)];
        let take_end = (i == n) | (ends[j] <= next_start);
        let key = if take_end { ends[j] } else { next_start };
        let (n_left, n_right) = (i, n - j - usize::from(take_end));
        let pos = from_order_key(key);
        let (p_left, p_right) = geometry.probabilities(pos);
        let cost = params.split_cost(p_left, p_right, n_left, n_right);
        let better = (pos > geometry.lo) & (pos < geometry.hi) & (!found | (cost < best_cost));
        found |= better;
        best_cost = if better { cost } else { best_cost };
        best_pos = if better { pos } else { best_pos };
        i += usize::from(!take_end);
        j += usize::from(take_end);
    }
    found.then_some(SplitChoice {
        cost: best_cost,
        axis,
        pos: best_pos,
        planar_left: true,
    })
}

/// The parts of a cell that SAH split costs need along one axis.
#[derive(Clone, Copy)]
pub(super) struct SplitGeometry {
    pub(super) lo: f32,
    pub(super) hi: f32,
    /// Edge lengths across the axis.
    a: f32,
    b: f32,
    inv_sa: f32,
}

impl SplitGeometry {
    /// `None` for a flat or NaN cell (no split can be costed).
    pub(super) fn new(cell: &Aabb, axis: usize) -> Option<Self> {
        let sa = cell.surface_area();
        if sa.is_nan() || sa <= 0.0 {
            return None;
        }
        let ext = cell.extent();
        Some(Self {
            lo: cell.min[axis],
            hi: cell.max[axis],
            a: ext[(axis + 1) % 3],
            b: ext[(axis + 2) % 3],
            inv_sa: 1.0 / sa,
        })
    }

    /// Probabilities of hitting the left and right children of a split at
    /// `pos`: their surface areas over the cell's (the SAH's area ratios).
    #[inline]
    pub(super) fn probabilities(&self, pos: f32) -> (f32, f32) {
        let (a, b) = (self.a, self.b);
        let (dl, dr) = (pos - self.lo, self.hi - pos);
        (
            2.0 * (a * b + (a + b) * dl) * self.inv_sa,
            2.0 * (a * b + (a + b) * dr) * self.inv_sa,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::kdtree::build::binning::EXACT_MAX_PRIMS;
    use crate::math::Vec3A;

    fn unit_box(x: f32) -> Aabb {
        Aabb::new(Vec3A::new(x, 0.0, 0.0), Vec3A::new(x + 1.0, 1.0, 1.0))
    }

    #[test]
    fn order_key_sorts_like_floats() {
        let xs = [-1e30, -2.5, -0.0, 0.0, 1e-40, 1.0, 3.5, f32::MAX];
        for w in xs.windows(2) {
            assert!(order_key(w[0]) <= order_key(w[1]), "{w:?}");
            assert_eq!(from_order_key(order_key(w[1])), w[1]);
        }
        assert_eq!(order_key(-0.0), order_key(0.0));
        // Kind orders events at one position: end < planar < start.
        assert!(event(1.0, END, 9) < event(1.0, PLANAR, 0));
        assert!(event(1.0, PLANAR, 9) < event(1.0, START, 0));
        assert!(event(1.0, START, 9) < event(1.5, END, 0));
        let e = event(-3.25, START, 77);
        assert_eq!(
            (event_index(e), event_kind(e), from_order_key(event_key(e))),
            (77, START, -3.25)
        );
    }

    #[test]
    fn split_cost_follows_wald_havran() {
        let p = SahParams::default();
        // Both sides used: no bonus.
        assert_eq!(p.split_cost(0.5, 0.5, 10, 10), 30.0 + 20.0 * 10.0);
        // An empty side gets the 0.9 factor.
        assert_eq!(p.split_cost(0.3, 0.7, 0, 10), 0.9 * (30.0 + 20.0 * 7.0));
        assert_eq!(p.leaf_cost(4), 80.0);
        assert_eq!(p.depth_limit(1 << 20), 34);
        assert_eq!(p.depth_limit(usize::MAX), MAX_TREE_DEPTH);
    }

    fn events_of(boxes: &[Aabb], axis: usize) -> Vec<u64> {
        let mut ev: [Vec<u64>; 3] = Default::default();
        for (i, b) in boxes.iter().enumerate() {
            push_events(&mut ev, b, i as u32);
        }
        let mut e = std::mem::take(&mut ev[axis]);
        e.sort_unstable();
        e
    }

    #[test]
    fn sweep_separates_two_clusters() {
        // Two clusters of boxes at x ∈ [0, 2] and [8, 10]: the best x plane
        // lies in the gap, at one of its ends (the empty space is cut off).
        let boxes: Vec<Aabb> = [0.0, 1.0, 8.0, 9.0].iter().map(|&x| unit_box(x)).collect();
        let cell = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
        let best = sweep_axis(&SahParams::default(), &cell, 0, &events_of(&boxes, 0), 4).unwrap();
        assert!(best.pos == 2.0 || best.pos == 8.0, "{best:?}");
        // No plane on y/z: every candidate lies on the cell's faces.
        assert!(sweep_axis(&SahParams::default(), &cell, 1, &events_of(&boxes, 1), 4).is_none());
    }

    #[test]
    fn sweep_counts_planar_primitives() {
        // Many flat boxes in the plane x = 5 plus one big box: planar ones are
        // put on the side that makes the cost lowest, and the counts match a
        // direct evaluation.
        let mut boxes = vec![Aabb::new(Vec3A::ZERO, Vec3A::new(10.0, 1.0, 1.0))];
        for _ in 0..5 {
            boxes.push(Aabb::new(Vec3A::new(5.0, 0.0, 0.0), Vec3A::new(5.0, 1.0, 1.0)));
        }
        let cell = boxes[0];
        let params = SahParams::default();
        let best = sweep_axis(&params, &cell, 0, &events_of(&boxes, 0), 6).unwrap();
        assert_eq!(best.pos, 5.0);
        let sa = cell.surface_area();
        let half = Aabb::new(Vec3A::ZERO, Vec3A::new(5.0, 1.0, 1.0)).surface_area() / sa;
        // Big box straddles (counted both sides), 5 planar on one side.
        assert_eq!(best.cost, params.split_cost(half, half, 6, 1));
    }

    /// The branch-free two-list sweep picks the same plane, cost and side as
    /// the tagged-event sweep on boxes without flat extents, with shared
    /// positions and −0 mixed in.
    #[test]
    fn two_list_sweep_matches_tagged_event_sweep() {
        use crate::math::rng::{Domain, Rng};
        let mut rng = Rng::new(9, Domain::Analysis, 0, 0);
        // Coordinates on a coarse grid so that positions are often shared.
        let coord = |rng: &mut Rng| {
            let k = (rng.f32() * 9.0).floor() - 4.0;
            if k == 0.0 && rng.f32() < 0.5 {
                -0.0
            } else {
                k * 0.5
            }
        };
        let params = SahParams::default();
        let mut checked = 0;
        for case in 0..600 {
            let n = 1 + case % EXACT_MAX_PRIMS;
            let boxes: Vec<Aabb> = (0..n)
                .map(|_| {
                    let (a, b, c) = (coord(&mut rng), coord(&mut rng), coord(&mut rng));
                    let min = Vec3A::new(a, b, c);
                    let e = Vec3A::new(0.5 + rng.f32().floor(), 0.5 * (1.0 + (rng.f32() * 3.0).floor()), 0.5);
                    Aabb::new(min, min + e)
                })
                .collect();
            let cell = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
            for axis in 0..3 {
                let mut starts: Vec<u32> = boxes.iter().map(|b| order_key(b.min[axis])).collect();
                let mut ends: Vec<u32> = boxes.iter().map(|b| order_key(b.max[axis])).collect();
                starts.sort_unstable();
                ends.sort_unstable();
                let fast = sweep_two_lists(&params, &cell, axis, &starts, &ends);
                let reference = sweep_axis(&params, &cell, axis, &events_of(&boxes, axis), n);
                assert_eq!(fast, reference, "case {case} axis {axis}");
                checked += usize::from(reference.is_some());
            }
        }
        assert!(checked > 1000, "{checked}");
    }
}
