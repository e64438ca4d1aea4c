//! Compact KD-tree nodes and the single-tree traversal shared by both levels.

use crate::math::{gamma, Aabb, Ray, Vec3A};
use glam::Vec4;
use std::ops::Range;

/// Low two bits of `KdNode::flags` for a leaf (0, 1, 2 are split axes).
const LEAF: u32 = 3;

/// Largest child index or primitive count the 30 free bits of a node can hold.
pub(crate) const MAX_INDEX: usize = (1 << 30) - 1;

/// Entries of the traversal stack. The build caps the depth below this
/// (`MAX_TREE_DEPTH`): each level pushes at most one far child. A power of
/// two: the traversal indexes it modulo its size (no bounds check; the
/// depth cap keeps the index below it).
const STACK_SIZE: usize = 64;
const _: () = assert!(STACK_SIZE.is_power_of_two() && MAX_TREE_DEPTH < STACK_SIZE as u32);

/// Deepest level the builder may create (keeps the traversal stack bounded).
pub(crate) const MAX_TREE_DEPTH: u32 = 60;

/// An 8-byte node, laid out like pbrt-v3's `KdAccelNode`.
///
/// * interior: `data` = split position (f32 bits), `flags` = axis (2 bits) |
///   index of the above child << 2; the below child is the next node
///   (depth-first layout), so one index suffices;
/// * leaf: `flags` = 3 | primitive count << 2, `data` = the offset of the
///   leaf's list in `KdTree::prim_indices` (and in any per-reference data
///   stored alongside, such as the BLAS's leaf triangles).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C)]
pub(crate) struct KdNode {
    data: u32,
    flags: u32,
}

impl KdNode {
    /// An interior node; its above child is set later by `set_above`.
    pub(crate) fn interior(axis: usize, split: f32) -> Self {
        debug_assert!(axis < 3);
        Self {
            data: split.to_bits(),
            flags: axis as u32,
        }
    }

    /// A leaf holding `count` primitives listed from offset `data`.
    pub(crate) fn leaf(count: usize, data: u32) -> Self {
        debug_assert!(count <= MAX_INDEX);
        Self {
            data,
            flags: ((count as u32) << 2) | LEAF,
        }
    }

    pub(crate) fn set_above(&mut self, index: usize) {
        debug_assert!(!self.is_leaf() && index <= MAX_INDEX);
        self.flags = (self.flags & 3) | ((index as u32) << 2);
    }

    #[inline]
    pub(crate) fn is_leaf(&self) -> bool {
        self.flags & 3 == LEAF
    }

    #[inline]
    pub(crate) fn axis(&self) -> usize {
        (self.flags & 3) as usize
    }

    #[inline]
    pub(crate) fn split(&self) -> f32 {
        f32::from_bits(self.data)
    }

    #[inline]
    pub(crate) fn above(&self) -> usize {
        (self.flags >> 2) as usize
    }

    #[inline]
    pub(crate) fn count(&self) -> usize {
        (self.flags >> 2) as usize
    }

    #[inline]
    pub(crate) fn data(&self) -> u32 {
        self.data
    }

    /// Shifts the indices of a node built in a separate buffer (parallel build)
    /// once that buffer is appended at `node_base` / `prim_base`.
    pub(crate) fn rebased(mut self, node_base: usize, prim_base: usize) -> Self {
        if self.is_leaf() {
            self.data += prim_base as u32;
        } else {
            let above = self.above() + node_base;
            self.set_above(above);
        }
        self
    }
}

/// One KD-tree (a mesh's BLAS in object space, or the TLAS over objects).
#[derive(Clone, Debug, Default)]
pub(crate) struct KdTree {
    /// Nodes in depth-first order; node 0 is the root (absent for an empty tree).
    pub(crate) nodes: Vec<KdNode>,
    /// Primitive lists of the leaves, one after the other in node order.
    pub(crate) prim_indices: Vec<u32>,
    /// Bounds of the primitives (the root cell).
    pub(crate) bounds: Aabb,
}

/// What a leaf visitor tells the traversal.
pub(crate) enum LeafResult {
    /// Keep going; nodes whose interval starts after this `t` are skipped.
    Continue(f32),
    /// Stop now (any-hit query satisfied).
    Stop,
}

/// Safety margin, in units of `f32::EPSILON · (distance + size)` (origin to the
/// tree's centre, and the tree's extent). Primitive tests round their
/// coordinates relative to the ray origin: a computed hit may lie a few such
/// ulps outside the primitive (Möller–Trumbore accepts barycentrics rounded
/// into range) and its `t` carries a similar error; split-plane distances carry
/// a relative error of γ(3). Every cell is treated as this much larger (the
/// root slab test, rays parallel to a plane), and every ray interval is
/// widened by the margin converted to `t`, so no primitive is skipped because
/// of rounding. Results then match the brute-force oracle bit for bit.
const SLACK_ULPS: f32 = 64.0;

impl KdTree {
    /// Bytes held by the nodes and the primitive lists.
    pub(crate) fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<KdNode>() + self.prim_indices.len() * 4
    }

    /// Front-to-back traversal (pbrt-v3 `KdTreeAccel::Intersect`), calling
    /// `visit` on the range of `prim_indices` of each non-empty leaf the ray
    /// passes through, nearest first. `visit` returns the closest hit
    /// distance found so far (nodes that start beyond it are skipped) or
    /// `Stop`.
    ///
    /// With `FAR_FIRST` the leaves come back to front instead, for any-hit
    /// queries, whose answer does not depend on the order. A shadow ray
    /// starts on a surface, among the triangles around its origin that it
    /// leaves behind, while an occluder is met at its first surface from
    /// the far end, so fewer triangles are tested before it
    /// (docs/benchmarks-history.md, "KD-tree shadow rays against Embree").
    ///
    /// Rays with zero direction components are exact: a ray parallel to a split
    /// plane visits only the side holding its origin, or both sides when it lies
    /// in the plane. Primitives must be tested by `visit` against the whole ray
    /// range, not the node's interval, so a primitive met in several leaves
    /// always gives the same answer.
    #[inline]
    pub(crate) fn traverse<const FAR_FIRST: bool>(
        &self,
        ray: &Ray,
        t_max: f32,
        mut visit: impl FnMut(Range<usize>) -> LeafResult,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let inv_dir = ray.dir.recip();
        // Spatial margin: a few ulps of the coordinates the primitive tests
        // work with (relative to the ray origin). Across a plane of axis k it
        // is worth `tol·|1/d_k|` in t, plus the error of t itself.
        let size = self.bounds.extent().max_element();
        let distance = (ray.origin - self.bounds.center()).abs().max_element();
        let tol = SLACK_ULPS * f32::EPSILON * (distance + size);
        let slack_t = tol / ray.dir.abs().max_element();
        let axis_slack = Vec4::from((inv_dir.abs() * tol + Vec3A::splat(slack_t), 0.0)).to_array();
        let root = Aabb::new(self.bounds.min - Vec3A::splat(tol), self.bounds.max + Vec3A::splat(tol));
        let Some((t0, t1)) = root.intersect_interval(ray, inv_dir, t_max + slack_t) else {
            return;
        };
        // Four lanes, so that indexing by a node's 2-bit axis field needs no
        // bounds check (the fourth lane is never read for an interior node).
        let origin = Vec4::from((ray.origin, 0.0)).to_array();
        let dir = Vec4::from((ray.dir, 0.0)).to_array();
        let inv = Vec4::from((inv_dir, 0.0)).to_array();

        let mut stack = [(0u32, 0f32, 0f32); STACK_SIZE];
        let mut top = 0usize;
        let mut best = t_max;
        let (mut node_index, mut t_min, mut t_max) = (0usize, t0 - slack_t, t1 + slack_t);
        loop {
            if t_min <= best {
                let node = self.nodes[node_index];
                if !node.is_leaf() {
                    let axis = node.axis();
                    let split = node.split();
                    let below = node_index + 1;
                    let above = node.above();
                    if dir[axis] == 0.0 {
                        // Parallel to the plane: t is unbounded by it; within
                        // the margin of the plane, both sides are visited.
                        if origin[axis] < split - tol {
                            node_index = below;
                        } else if origin[axis] > split + tol {
                            node_index = above;
                        } else {
                            stack[top % STACK_SIZE] = (above as u32, t_min, t_max);
                            top += 1;
                            node_index = below;
                        }
                        continue;
                    }
                    let t_split = (split - origin[axis]) * inv[axis];
                    // The side the ray comes from is met first (for t < t_split).
                    let (first, second) = if dir[axis] > 0.0 {
                        (below, above)
                    } else {
                        (above, below)
                    };
                    let slack = axis_slack[axis];
                    // Plain comparisons, not f32::min/max (whose NaN rules cost
                    // several instructions): no operand is NaN here (finite
                    // ray, non-zero direction component, finite slack).
                    let first_end = min_f32(t_max, t_split + slack);
                    let second_start = max_f32(t_min, t_split - slack);
                    let visit_first = t_min <= first_end;
                    let visit_second = second_start <= t_max;
                    match (visit_first, visit_second) {
                        // Both sides: the one not taken now waits on the stack.
                        (true, true) if FAR_FIRST => {
                            stack[top % STACK_SIZE] = (first as u32, t_min, first_end);
                            top += 1;
                            node_index = second;
                            t_min = second_start;
                        }
                        (true, true) => {
                            stack[top % STACK_SIZE] = (second as u32, second_start, t_max);
                            top += 1;
                            node_index = first;
                            t_max = first_end;
                        }
                        (true, false) => {
                            node_index = first;
                            t_max = first_end;
                        }
                        (false, true) => {
                            node_index = second;
                            t_min = second_start;
                        }
                        (false, false) => {}
                    }
                    if visit_first || visit_second {
                        continue;
                    }
                } else {
                    let count = node.count();
                    if count > 0 {
                        let start = node.data() as usize;
                        match visit(start..start + count) {
                            LeafResult::Continue(t) => best = t,
                            LeafResult::Stop => return,
                        }
                    }
                }
            }
            if top == 0 {
                return;
            }
            top -= 1;
            let (n, a, b) = stack[top % STACK_SIZE];
            node_index = n as usize;
            t_min = a;
            t_max = b;
        }
    }

    /// Cells of the nodes down to `max_depth`, depth-first, with their depth.
    pub(crate) fn cells(&self, max_depth: u32) -> Vec<(Aabb, u32)> {
        let mut out = Vec::new();
        if self.nodes.is_empty() {
            return out;
        }
        let mut stack = vec![(0usize, self.bounds, 0u32)];
        while let Some((index, cell, depth)) = stack.pop() {
            out.push((cell, depth));
            let node = self.nodes[index];
            if node.is_leaf() || depth >= max_depth {
                continue;
            }
            let (axis, split) = (node.axis(), node.split());
            let mut below = cell;
            let mut above = cell;
            below.max[axis] = split;
            above.min[axis] = split;
            stack.push((node.above(), above, depth + 1));
            stack.push((index + 1, below, depth + 1));
        }
        out
    }

    /// Node, leaf, empty-leaf and reference counts and the deepest leaf.
    pub(crate) fn shape(&self) -> TreeShape {
        let mut shape = TreeShape::default();
        if self.nodes.is_empty() {
            return shape;
        }
        let mut stack = vec![(0usize, 0u32)];
        while let Some((index, depth)) = stack.pop() {
            let node = self.nodes[index];
            shape.nodes += 1;
            if node.is_leaf() {
                shape.leaves += 1;
                shape.references += node.count();
                if node.count() == 0 {
                    shape.empty_leaves += 1;
                }
                shape.max_depth = shape.max_depth.max(depth);
            } else {
                stack.push((node.above(), depth + 1));
                stack.push((index + 1, depth + 1));
            }
        }
        shape
    }
}

/// The smaller of two non-NaN values (one `minss`).
#[inline(always)]
fn min_f32(a: f32, b: f32) -> f32 {
    if b < a {
        b
    } else {
        a
    }
}

/// The larger of two non-NaN values (one `maxss`).
#[inline(always)]
fn max_f32(a: f32, b: f32) -> f32 {
    if b > a {
        b
    } else {
        a
    }
}

/// Counts that describe a tree's shape.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct TreeShape {
    pub(crate) nodes: usize,
    pub(crate) leaves: usize,
    pub(crate) empty_leaves: usize,
    pub(crate) references: usize,
    pub(crate) max_depth: u32,
}

/// `b` grown by a few ulps of its coordinates (conservative against the
/// rounding of transformed or computed bounds).
pub(crate) fn widen(b: Aabb) -> Aabb {
    if b.is_empty() {
        return b;
    }
    let e = (b.min.abs().max(b.max.abs())) * gamma(4) + Vec3A::splat(f32::MIN_POSITIVE);
    Aabb::new(b.min - e, b.max + e)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_packs_into_eight_bytes() {
        assert_eq!(std::mem::size_of::<KdNode>(), 8);
        let mut n = KdNode::interior(2, -1.5);
        n.set_above(12345);
        assert!(!n.is_leaf());
        assert_eq!((n.axis(), n.split(), n.above()), (2, -1.5, 12345));
        let l = KdNode::leaf(7, 99);
        assert!(l.is_leaf());
        assert_eq!((l.count(), l.data()), (7, 99));
        assert_eq!(l.rebased(10, 5).data(), 104);
        assert_eq!(KdNode::leaf(0, 99).rebased(10, 5).data(), 104);
        assert_eq!(n.rebased(3, 5).above(), 12348);
    }
}
