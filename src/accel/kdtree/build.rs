//! SAH KD-tree construction with perfect splits.
//!
//! Each node holds references to primitives with the bounds of the part of
//! the primitive inside the node's cell. The split plane is chosen under the
//! surface area heuristic (SAH, Wald & Havran 2006 eq. 3):
//! * nodes of more than `EXACT_MAX_PRIMS` references bin their bounds
//!   (min-max binning, Shevtsov, Soupikov & Kapustin 2007: O(n) per node,
//!   no sorting) and evaluate the bin boundaries, plus the faces of the
//!   references' bounds, which cut off empty space exactly;
//! * smaller nodes sort their events and sweep them exactly (Wald & Havran
//!   Algorithm 4).
//!
//! References crossing the plane are clipped to each child cell
//! (Sutherland–Hodgman on the triangle, Wald & Havran §4.2), so the children
//! get tight bounds. Each level is O(n): the build is O(N log N) overall.
//!
//! The two children of large nodes are built in parallel (rayon) into separate
//! buffers that are appended in a fixed order, and large nodes bin and
//! partition in parallel with order-preserving collects and integer counts, so
//! the tree is the same for any number of threads.

use super::node::{KdNode, KdTree, MAX_INDEX, MAX_TREE_DEPTH};
use crate::math::{Aabb, Vec3A};
use rayon::prelude::*;

/// The primitives a tree is built over.
pub(crate) trait Primitives: Sync {
    /// Number of primitives.
    fn count(&self) -> usize;
    /// Bounds of the part of primitive `i` inside `cell`, conservative (it may
    /// be larger than the exact part, never smaller) and inside `cell`.
    fn clipped_bounds(&self, i: u32, cell: &Aabb) -> Aabb;
    /// Full bounds of primitive `i`.
    fn bounds(&self, i: u32) -> Aabb;
}

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
const END: u64 = 0;
const PLANAR: u64 = 1;
const START: u64 = 2;

/// Primitive indices local to a node take the low 30 bits of an event.
#[cfg(test)]
const INDEX_MASK: u64 = (1 << 30) - 1;

/// f32 → u32 whose unsigned order is the float order (−0 is folded onto +0).
#[inline]
fn order_key(pos: f32) -> u32 {
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
fn event(pos: f32, kind: u64, index: u32) -> u64 {
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
fn sweep_two_lists(params: &SahParams, cell: &Aabb, axis: usize, starts: &[u32], ends: &[u32]) -> Option<SplitChoice> {
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
struct SplitGeometry {
    lo: f32,
    hi: f32,
    /// Edge lengths across the axis.
    a: f32,
    b: f32,
    inv_sa: f32,
}

impl SplitGeometry {
    /// `None` for a flat or NaN cell (no split can be costed).
    fn new(cell: &Aabb, axis: usize) -> Option<Self> {
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
    fn probabilities(&self, pos: f32) -> (f32, f32) {
        let (a, b) = (self.a, self.b);
        let (dl, dr) = (pos - self.lo, self.hi - pos);
        (
            2.0 * (a * b + (a + b) * dl) * self.inv_sa,
            2.0 * (a * b + (a + b) * dr) * self.inv_sa,
        )
    }
}

/// Triangle clipped to a box (Sutherland & Hodgman 1974, one plane at a time),
/// returned as the bounds of the clipped polygon, or the triangle's bounds
/// when it lies inside. The intersection points carry rounding error, so
/// their coordinates are widened by a few ulps and the result clamped to both
/// the cell and the triangle's bounds: conservative, and exact for untouched
/// coordinates (a triangle lying in an axis plane stays planar).
pub fn clip_triangle(p: [Vec3A; 3], cell: &Aabb) -> Aabb {
    let tri = Aabb::from_points(p);
    if tri.min.cmpge(cell.min).all() && tri.max.cmple(cell.max).all() {
        return tri;
    }
    // Vertices with a flag: true for the triangle's own (exact) corners,
    // false for computed intersection points.
    let mut poly = [(Vec3A::ZERO, true); 9];
    let mut next = [(Vec3A::ZERO, true); 9];
    for (slot, &v) in poly.iter_mut().zip(&p) {
        *slot = (v, true);
    }
    let mut len = 3;
    for axis in 0..3 {
        for (plane, keep_above) in [(cell.min[axis], true), (cell.max[axis], false)] {
            let outside_exists = if keep_above {
                tri.min[axis] < plane
            } else {
                tri.max[axis] > plane
            };
            if !outside_exists || len == 0 {
                continue;
            }
            let inside = |v: Vec3A| if keep_above { v[axis] >= plane } else { v[axis] <= plane };
            let mut out = 0;
            for i in 0..len {
                let a = poly[i];
                let b = poly[(i + 1) % len];
                let (ina, inb) = (inside(a.0), inside(b.0));
                if ina {
                    next[out] = a;
                    out += 1;
                }
                if ina != inb {
                    let t = (plane - a.0[axis]) / (b.0[axis] - a.0[axis]);
                    let mut x = a.0 + (b.0 - a.0) * t;
                    x[axis] = plane;
                    next[out] = (x, false);
                    out += 1;
                }
            }
            // A convex polygon cut by a plane gains at most one vertex: out ≤ 9.
            len = out;
            poly[..len].copy_from_slice(&next[..len]);
        }
    }
    let fallback = tri.intersection(*cell);
    if len == 0 {
        return fallback;
    }
    // Only computed points are widened: a corner lying on a later split
    // plane keeps its exact coordinate, so the triangle is not duplicated.
    let err = tri.min.abs().max(tri.max.abs()) * (32.0 * f32::EPSILON);
    let b = poly[..len].iter().fold(Aabb::EMPTY, |b, &(v, exact)| {
        if exact {
            b.grow(v)
        } else {
            b.union(Aabb::new(v - err, v + err))
        }
    });
    b.intersection(fallback)
}

/// A primitive reference of a node under construction: the bounds of the
/// part of primitive `prim` inside the node's cell.
#[derive(Clone, Copy, Debug)]
struct Ref {
    bounds: Aabb,
    prim: u32,
}

/// Nodes and primitive lists of a (sub)tree.
#[derive(Default)]
struct Output {
    nodes: Vec<KdNode>,
    prim_indices: Vec<u32>,
}

impl Output {
    /// A leaf over `refs`; its primitives are stored at `KdNode::data()` in
    /// `prim_indices` (ascending, as `refs` keeps the input order).
    fn push_leaf(&mut self, refs: &[Ref]) {
        self.nodes
            .push(KdNode::leaf(refs.len(), self.prim_indices.len() as u32));
        self.prim_indices.extend(refs.iter().map(|r| r.prim));
    }

    fn append(&mut self, sub: Output) {
        let (node_base, prim_base) = (self.nodes.len(), self.prim_indices.len());
        self.nodes
            .extend(sub.nodes.into_iter().map(|n| n.rebased(node_base, prim_base)));
        self.prim_indices.extend(sub.prim_indices);
    }
}

/// Nodes with more primitives than this build their children in parallel.
const PARALLEL_MIN_PRIMS: usize = 4096;

/// Nodes with more primitives than this bin and partition in parallel.
const PARALLEL_NODE_MIN_PRIMS: usize = 65_536;

/// Nodes with at most this many primitives get the exact SAH sweep (sorted
/// events, Wald & Havran Algorithm 4, `O(n log n)` per node); larger ones are
/// binned.
const EXACT_MAX_PRIMS: usize = 64;

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

struct Builder<'a, P: Primitives> {
    prims: &'a P,
    params: SahParams,
    max_depth: u32,
}

/// Builds a SAH KD-tree over `prims`.
///
/// Primitive and node counts are limited to 2^30 − 1 by the 8-byte node
/// layout; callers split larger inputs (meshes are far below it in practice:
/// 2^30 triangles would hold 12 GiB of indices alone).
pub(crate) fn build_tree<P: Primitives>(prims: &P, params: &SahParams) -> KdTree {
    let n = prims.count();
    let mut tree = KdTree::default();
    if n == 0 {
        return tree;
    }
    assert!(n <= MAX_INDEX, "KD-tree input of {n} primitives exceeds 2^30 - 1");
    let refs: Vec<Ref> = (0..n as u32)
        .into_par_iter()
        .map(|prim| Ref {
            bounds: prims.bounds(prim),
            prim,
        })
        .collect();
    let cell = refs.par_iter().map(|r| r.bounds).reduce(|| Aabb::EMPTY, Aabb::union);
    let builder = Builder {
        prims,
        params: *params,
        max_depth: params.depth_limit(n),
    };
    let mut out = Output::default();
    builder.build_node(refs, cell, 0, &mut out);
    tree.nodes = out.nodes;
    tree.prim_indices = out.prim_indices;
    tree.bounds = cell;
    tree
}

impl<P: Primitives> Builder<'_, P> {
    /// The cheapest plane of a node: the exact sweep for small nodes; for
    /// large ones the binned estimate, plus the planes on the faces of the
    /// primitives' bounds (they cut off empty space exactly, which bins only
    /// approximate).
    fn find_split(&self, refs: &[Ref], cell: &Aabb) -> Option<SplitChoice> {
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

    fn build_node(&self, refs: Vec<Ref>, cell: Aabb, depth: u32, out: &mut Output) {
        let n = refs.len();
        let split = if n <= self.params.leaf_size || depth >= self.max_depth {
            None
        } else {
            self.find_split(&refs, &cell)
                .filter(|s| s.cost < self.params.leaf_cost(n))
        };
        let Some(split) = split else {
            out.push_leaf(&refs);
            return;
        };
        let (axis, pos) = (split.axis, split.pos);
        let mut left_cell = cell;
        let mut right_cell = cell;
        left_cell.max[axis] = pos;
        right_cell.min[axis] = pos;
        let (left, right) = if n >= PARALLEL_NODE_MIN_PRIMS {
            rayon::join(
                || {
                    refs.par_iter()
                        .filter_map(|r| self.child_ref(r, &split, &left_cell, true))
                        .collect()
                },
                || {
                    refs.par_iter()
                        .filter_map(|r| self.child_ref(r, &split, &right_cell, false))
                        .collect()
                },
            )
        } else {
            let mut left = Vec::with_capacity(n);
            let mut right = Vec::with_capacity(n);
            for r in &refs {
                match split_sides(r, &split) {
                    (true, false) => left.push(*r),
                    (false, true) => right.push(*r),
                    _ => {
                        left.extend(self.child_ref(r, &split, &left_cell, true));
                        right.extend(self.child_ref(r, &split, &right_cell, false));
                    }
                }
            }
            (left, right)
        };
        drop(refs);
        let index = out.nodes.len();
        out.nodes.push(KdNode::interior(axis, pos));
        if n >= PARALLEL_MIN_PRIMS {
            let (left_out, right_out) = rayon::join(
                || {
                    let mut o = Output::default();
                    self.build_node(left, left_cell, depth + 1, &mut o);
                    o
                },
                || {
                    let mut o = Output::default();
                    self.build_node(right, right_cell, depth + 1, &mut o);
                    o
                },
            );
            out.append(left_out);
            let above = out.nodes.len();
            out.nodes[index].set_above(above);
            out.append(right_out);
        } else {
            self.build_node(left, left_cell, depth + 1, out);
            let above = out.nodes.len();
            out.nodes[index].set_above(above);
            self.build_node(right, right_cell, depth + 1, out);
        }
    }

    /// The reference `r` as seen by the child on one side of `split` (cell
    /// `child_cell`), or `None` when it lies entirely on the other side.
    /// Primitives ending at the plane are on its left, those starting at it on
    /// its right, and those lying in it on the side the split chose; the ones
    /// crossing it are clipped to the child's cell ("perfect splits", Wald &
    /// Havran §4.2).
    #[inline]
    fn child_ref(&self, r: &Ref, split: &SplitChoice, child_cell: &Aabb, left: bool) -> Option<Ref> {
        let (goes_left, goes_right) = split_sides(r, split);
        if left && !goes_left || !left && !goes_right {
            return None;
        }
        if goes_left && goes_right {
            let clipped = self.prims.clipped_bounds(r.prim, child_cell).intersection(r.bounds);
            if clipped.is_empty() {
                return None;
            }
            return Some(Ref {
                bounds: clipped,
                prim: r.prim,
            });
        }
        Some(*r)
    }
}

/// Whether reference `r` reaches the left and the right side of `split`:
/// primitives ending at the plane are on its left, those starting at it on its
/// right, and those lying in it on the side the split chose.
#[inline]
fn split_sides(r: &Ref, split: &SplitChoice) -> (bool, bool) {
    let (lo, hi) = (r.bounds.min[split.axis], r.bounds.max[split.axis]);
    let pos = split.pos;
    let in_plane = lo == pos && hi == pos;
    (
        lo < pos || (in_plane && split.planar_left),
        hi > pos || (in_plane && !split.planar_left),
    )
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

/// Object bounds as build primitives: clipping is the box intersection.
pub(crate) struct BoxPrims(pub(crate) Vec<Aabb>);

impl Primitives for BoxPrims {
    fn count(&self) -> usize {
        self.0.len()
    }
    fn clipped_bounds(&self, i: u32, cell: &Aabb) -> Aabb {
        self.0[i as usize].intersection(*cell)
    }
    fn bounds(&self, i: u32) -> Aabb {
        self.0[i as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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

    #[test]
    fn clip_keeps_inside_triangles_and_planar_ones_exact() {
        let cell = Aabb::new(Vec3A::splat(-1.0), Vec3A::splat(1.0));
        let inside = [
            Vec3A::new(0.0, 0.0, 0.0),
            Vec3A::new(0.5, 0.0, 0.0),
            Vec3A::new(0.0, 0.5, 0.25),
        ];
        assert_eq!(clip_triangle(inside, &cell), Aabb::from_points(inside));
        // A large triangle in the plane z = 0.5 across the cell.
        let big = [
            Vec3A::new(-10.0, -10.0, 0.5),
            Vec3A::new(10.0, -10.0, 0.5),
            Vec3A::new(0.0, 10.0, 0.5),
        ];
        let b = clip_triangle(big, &cell);
        assert_eq!((b.min.z, b.max.z), (0.5, 0.5));
        assert_eq!((b.min.x, b.max.x, b.min.y, b.max.y), (-1.0, 1.0, -1.0, 1.0));
    }

    #[test]
    fn clip_is_tight_and_conservative() {
        // Triangle (0,0,0) (4,0,0) (0,4,0) clipped to x ≥ 3 keeps the corner
        // x ∈ [3, 4], y ∈ [0, 1]: much tighter than the triangle's bounds.
        let t = [Vec3A::ZERO, Vec3A::new(4.0, 0.0, 0.0), Vec3A::new(0.0, 4.0, 0.0)];
        let cell = Aabb::new(Vec3A::new(3.0, -1.0, -1.0), Vec3A::new(5.0, 5.0, 1.0));
        let b = clip_triangle(t, &cell);
        assert_eq!((b.min.x, b.max.x, b.min.y, b.min.z, b.max.z), (3.0, 4.0, 0.0, 0.0, 0.0));
        assert!(b.max.y >= 1.0 && b.max.y < 1.0 + 1e-4, "{b:?}");
        // A triangle outside the cell (touching nothing) clips to nothing.
        let far = Aabb::new(Vec3A::splat(10.0), Vec3A::splat(11.0));
        assert!(clip_triangle(t, &far).is_empty());
    }

    /// Random boxes; every point of every box must be in a leaf listing it.
    #[test]
    fn every_primitive_is_in_every_leaf_it_overlaps() {
        use crate::math::rng::{Domain, Rng};
        let mut rng = Rng::new(5, Domain::Analysis, 0, 0);
        let boxes: Vec<Aabb> = (0..3000)
            .map(|_| {
                let c = Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 10.0;
                let e = Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 0.3;
                Aabb::new(c - e, c + e)
            })
            .collect();
        let prims = BoxPrims(boxes.clone());
        let tree = build_tree(&prims, &SahParams::default());
        assert!(tree.nodes.len() > 100);
        for (i, b) in boxes.iter().enumerate() {
            for _ in 0..8 {
                let p = b.min + b.extent() * Vec3A::new(rng.f32(), rng.f32(), rng.f32());
                // Descend to every leaf containing p (both sides on a plane).
                let mut stack = vec![0usize];
                let mut found = false;
                while let Some(index) = stack.pop() {
                    let node = tree.nodes[index];
                    if node.is_leaf() {
                        let list = tree.prim_indices[node.data() as usize..][..node.count()].to_vec();
                        assert!(list.windows(2).all(|w| w[0] < w[1]), "leaf lists ascend");
                        found |= list.contains(&(i as u32));
                        assert!(found, "box {i} missing from a leaf holding {p}");
                        found = false;
                        continue;
                    }
                    let (axis, split) = (node.axis(), node.split());
                    if p[axis] <= split {
                        stack.push(index + 1);
                    }
                    if p[axis] >= split {
                        stack.push(node.above());
                    }
                }
            }
        }
    }

    #[test]
    fn build_is_identical_for_any_thread_count() {
        use crate::math::rng::{Domain, Rng};
        let mut rng = Rng::new(6, Domain::Analysis, 0, 0);
        let boxes: Vec<Aabb> = (0..20_000)
            .map(|_| {
                let c = Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 100.0;
                Aabb::new(c, c + Vec3A::splat(0.5))
            })
            .collect();
        let prims = BoxPrims(boxes);
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let three = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
        let a = one.install(|| build_tree(&prims, &SahParams::default()));
        let b = three.install(|| build_tree(&prims, &SahParams::default()));
        assert_eq!(a.nodes, b.nodes);
        assert_eq!(a.prim_indices, b.prim_indices);
    }
}
