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
//!
//! `sah` holds the cost model and the exact event sweeps, `binning` the
//! choice of a node's plane (binned for large nodes), `clip` the clipping of
//! triangles to a cell; this module builds the nodes recursively and lays
//! them out depth first in one array.

mod binning;
mod clip;
mod sah;

pub use clip::clip_triangle;
pub use sah::SahParams;

use super::node::{KdNode, KdTree, MAX_INDEX};
use crate::math::Aabb;
use rayon::prelude::*;
use sah::SplitChoice;

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
    use crate::math::Vec3A;

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
