//! The in-house two-level SAH KD-tree.
//!
//! * Bottom level: one tree per distinct mesh, in object space, shared by all
//!   the objects that instance the mesh. Built with Wald & Havran's O(N log N)
//!   event-sorting SAH build with perfect splits ([`build`]).
//! * Top level: a KD-tree of the same kind over the world bounds of the
//!   objects (mesh instances, spheres, quads, disks, cylinders); an object
//!   straddling a plane is referenced by both sides, and a small mailbox
//!   avoids testing it twice in one query.
//! * Traversal: iterative, front to back for closest hits and back to
//!   front for occlusion, fixed stack (pbrt-v3
//!   `KdTreeAccel::Intersect`), rays moved into object space with
//!   `Transform::ray_to_object` (the direction is not renormalised, so `t`
//!   keeps its world meaning).
//!
//! Results are identical to [`BruteForce`](super::brute::BruteForce): every
//! primitive is tested against the whole ray range with the same test, ties at
//! equal `t` are broken like the oracle's loop (lowest object, then lowest
//! triangle), and traversal intervals carry a rounding margin so no leaf that
//! could hold the closest hit is skipped.

pub mod build;
mod node;

use self::build::{build_tree, clip_triangle, BoxPrims, Primitives, SahParams};
use self::node::{widen, KdTree, LeafResult, TreeShape};
use super::triangle::{moller_trumbore, WatertightRay};
use super::{Accel, AccelOptions, AccelStats, Hit, TriangleTest};
use crate::math::{Aabb, Ray, Transform, Vec3, Vec3A};
use crate::scene::{Cutouts, Cylinder, Disk, Mesh, Quad, Scene, Shape, Sphere};
use arrayvec::ArrayVec;
use rayon::prelude::*;
use std::ops::Range;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// An entry of the top level.
#[derive(Clone, Debug)]
enum TopObject {
    Sphere(Sphere),
    Quad(Quad),
    Disk(Disk),
    Cylinder(Cylinder),
    Mesh { mesh: u32, transform: Transform },
}

/// Two-level KD-tree accelerator.
pub struct KdTreeAccel {
    objects: Vec<TopObject>,
    top: KdTree,
    meshes: Vec<Arc<Mesh>>,
    /// One tree per entry of `meshes` (empty for meshes no object uses).
    blas: Vec<Blas>,
    test: TriangleTest,
    /// Alpha masks, when some material has one.
    cutouts: Option<Arc<Cutouts>>,
    build_time: Duration,
}

/// A triangle as stored in a BLAS leaf: its corners copied in leaf order, so
/// a leaf's triangles are read from one contiguous block instead of through
/// two index indirections (triangle → vertex indices → positions). The
/// corners are the mesh's own values, so tests give the same bits as on the mesh.
#[derive(Clone, Copy, Debug)]
struct LeafTriangle {
    corners: [Vec3; 3],
    prim: u32,
}

/// A mesh's bottom-level tree and its leaf triangles (`tris[i]` is the
/// triangle of reference `i`; the tree's `prim_indices` are dropped).
#[derive(Default)]
struct Blas {
    tree: KdTree,
    tris: Vec<LeafTriangle>,
}

impl Blas {
    fn build(mesh: &Mesh, params: &SahParams) -> Self {
        let mut tree = build_tree(&TrianglePrims(mesh), params);
        let tris = std::mem::take(&mut tree.prim_indices)
            .into_iter()
            .map(|prim| {
                let [a, b, c] = mesh.triangles[prim as usize];
                let p = |v: u32| mesh.positions[v as usize];
                LeafTriangle {
                    corners: [p(a), p(b), p(c)],
                    prim,
                }
            })
            .collect();
        Self { tree, tris }
    }

    fn memory_bytes(&self) -> usize {
        self.tree.memory_bytes() + self.tris.len() * std::mem::size_of::<LeafTriangle>()
    }
}

/// A mesh's triangles as build primitives.
struct TrianglePrims<'a>(&'a Mesh);

impl Primitives for TrianglePrims<'_> {
    fn count(&self) -> usize {
        self.0.triangles.len()
    }
    fn clipped_bounds(&self, i: u32, cell: &Aabb) -> Aabb {
        clip_triangle(self.0.corners(i as usize), cell)
    }
    fn bounds(&self, i: u32) -> Aabb {
        Aabb::from_points(self.0.corners(i as usize))
    }
}

/// Objects remembered per query by the `Mailbox`.
const MAILBOX_SIZE: usize = 8;

impl KdTreeAccel {
    /// Builds the bottom-level trees (one per mesh used by an object, in
    /// parallel) and the top-level tree over all objects.
    pub fn build(scene: &Scene, options: &AccelOptions) -> Self {
        Self::build_with(scene, options, &SahParams::default())
    }

    /// As [`build`](Self::build) with explicit SAH parameters (benchmarks and tuning).
    pub fn build_with(scene: &Scene, options: &AccelOptions, params: &SahParams) -> Self {
        let start = Instant::now();
        let mut used = vec![false; scene.meshes.len()];
        let objects: Vec<TopObject> = scene
            .objects
            .iter()
            .map(|o| match &o.shape {
                Shape::Sphere(s) => TopObject::Sphere(*s),
                Shape::Quad(q) => TopObject::Quad(*q),
                Shape::Disk(d) => TopObject::Disk(*d),
                Shape::Cylinder(c) => TopObject::Cylinder(*c),
                Shape::Mesh { mesh, transform, .. } => {
                    used[*mesh as usize] = true;
                    TopObject::Mesh {
                        mesh: *mesh,
                        transform: *transform,
                    }
                }
            })
            .collect();
        let blas: Vec<Blas> = scene
            .meshes
            .par_iter()
            .zip(used.par_iter())
            .map(|(mesh, &used)| {
                if used {
                    Blas::build(mesh, params)
                } else {
                    Blas::default()
                }
            })
            .collect();
        // World bounds, widened by a few ulps: transformed corners and the
        // analytic shapes' hit points carry rounding error.
        let bounds: Vec<Aabb> = objects
            .iter()
            .map(|o| match o {
                TopObject::Sphere(s) => widen(s.bounds()),
                TopObject::Quad(q) => widen(q.bounds()),
                TopObject::Disk(d) => widen(d.bounds()),
                TopObject::Cylinder(c) => widen(c.bounds()),
                TopObject::Mesh { mesh, transform } => widen(transform.bounds(&blas[*mesh as usize].tree.bounds)),
            })
            .collect();
        let top = build_tree(&BoxPrims(bounds), params);
        Self {
            objects,
            top,
            meshes: scene.meshes.clone(),
            blas,
            test: options.triangle_test,
            cutouts: Cutouts::of(scene),
            build_time: start.elapsed(),
        }
    }

    /// World-space cells of the top-level tree and of each mesh instance's
    /// bottom-level tree (its object-space cells transformed to world bounds),
    /// down to `max_depth`, each with its depth within its own tree (0 = root).
    /// For the KD-tree debug overlay.
    pub fn node_boxes(&self, max_depth: u32) -> Vec<(Aabb, u32)> {
        let mut out = self.top.cells(max_depth);
        for o in &self.objects {
            if let TopObject::Mesh { mesh, transform } = o {
                out.extend(
                    self.blas[*mesh as usize]
                        .tree
                        .cells(max_depth)
                        .into_iter()
                        .map(|(b, d)| (transform.bounds(&b), d)),
                );
            }
        }
        out
    }

    /// The alpha masks when the query is `MASKED` (the scene has some):
    /// queries of a scene without masks are compiled without the tests.
    #[inline(always)]
    fn masks<const MASKED: bool>(&self) -> Option<&Arc<Cutouts>> {
        if MASKED {
            self.cutouts.as_ref()
        } else {
            None
        }
    }

    /// Tests one object (all its triangles for a mesh, through its tree)
    /// against `ray` below `limit`, reporting every hit to `found` (which may
    /// lower `limit`). With `any`, a mesh stops at its first hit.
    #[inline]
    fn test_object<const MASKED: bool>(
        &self,
        ray: &Ray,
        instance: u32,
        limit: &mut f32,
        any: bool,
        found: &mut impl FnMut(Hit, &mut f32),
    ) {
        match &self.objects[instance as usize] {
            TopObject::Sphere(s) => {
                let t = match self.masks::<MASKED>() {
                    Some(c) => c.sphere(instance, s, ray, *limit),
                    None => s.intersect(ray, *limit),
                };
                if let Some(t) = t {
                    let hit = Hit {
                        t,
                        instance,
                        prim: 0,
                        u: 0.0,
                        v: 0.0,
                    };
                    found(hit, limit);
                }
            }
            TopObject::Quad(q) => {
                let h = match self.masks::<MASKED>() {
                    Some(c) => c.quad(instance, q, ray, *limit),
                    None => q.intersect(ray, *limit),
                };
                if let Some((t, u, v)) = h {
                    found(
                        Hit {
                            t,
                            instance,
                            prim: 0,
                            u,
                            v,
                        },
                        limit,
                    );
                }
            }
            TopObject::Disk(d) => {
                let h = match self.masks::<MASKED>() {
                    Some(c) => c.disk(instance, d, ray, *limit),
                    None => d.intersect(ray, *limit),
                };
                if let Some((t, u, v)) = h {
                    found(
                        Hit {
                            t,
                            instance,
                            prim: 0,
                            u,
                            v,
                        },
                        limit,
                    );
                }
            }
            TopObject::Cylinder(cyl) => {
                let t = match self.masks::<MASKED>() {
                    Some(c) => c.cylinder(instance, cyl, ray, *limit),
                    None => cyl.intersect(ray, *limit),
                };
                if let Some(t) = t {
                    let hit = Hit {
                        t,
                        instance,
                        prim: 0,
                        u: 0.0,
                        v: 0.0,
                    };
                    found(hit, limit);
                }
            }
            TopObject::Mesh { mesh, transform } => {
                let local = transform.ray_to_object(ray);
                let blas = &self.blas[*mesh as usize];
                let watertight = WatertightRay::new(&local);
                let test = self.test;
                let start_limit = *limit;
                let cutouts = self.masks::<MASKED>().filter(|c| c.has(instance));
                let leaf = |range: Range<usize>| {
                    for tri in &blas.tris[range] {
                        let prim = tri.prim;
                        let [p0, p1, p2] = tri.corners.map(Vec3A::from);
                        let result = match test {
                            TriangleTest::Watertight => watertight.intersect(p0, p1, p2, *limit),
                            TriangleTest::MollerTrumbore => moller_trumbore(&local, p0, p1, p2, *limit),
                        };
                        let kept = |&(_, u, v): &(f32, f32, f32)| {
                            cutouts.is_none_or(|c| c.keeps_triangle(instance, prim, u, v))
                        };
                        if let Some((t, u, v)) = result.filter(kept) {
                            found(
                                Hit {
                                    t,
                                    instance,
                                    prim,
                                    u,
                                    v,
                                },
                                limit,
                            );
                            if any {
                                return LeafResult::Stop;
                            }
                        }
                    }
                    LeafResult::Continue(*limit)
                };
                // Any-hit queries go back to front (see `KdTree::traverse`).
                if any {
                    blas.tree.traverse::<true>(&local, start_limit, leaf);
                } else {
                    blas.tree.traverse::<false>(&local, start_limit, leaf);
                }
            }
        }
    }

    /// Re-tests one primitive of one object below `limit` (tie resolution).
    fn test_prim(&self, ray: &Ray, instance: u32, prim: u32, limit: f32) -> Option<(f32, f32, f32)> {
        match &self.objects[instance as usize] {
            TopObject::Sphere(s) => match &self.cutouts {
                Some(c) => c.sphere(instance, s, ray, limit),
                None => s.intersect(ray, limit),
            }
            .map(|t| (t, 0.0, 0.0)),
            TopObject::Quad(q) => match &self.cutouts {
                Some(c) => c.quad(instance, q, ray, limit),
                None => q.intersect(ray, limit),
            },
            TopObject::Disk(d) => match &self.cutouts {
                Some(c) => c.disk(instance, d, ray, limit),
                None => d.intersect(ray, limit),
            },
            TopObject::Cylinder(cyl) => match &self.cutouts {
                Some(c) => c.cylinder(instance, cyl, ray, limit),
                None => cyl.intersect(ray, limit),
            }
            .map(|t| (t, 0.0, 0.0)),
            TopObject::Mesh { mesh, transform } => {
                let local = transform.ray_to_object(ray);
                let [p0, p1, p2] = self.meshes[*mesh as usize].corners(prim as usize);
                let hit = match self.test {
                    TriangleTest::Watertight => WatertightRay::new(&local).intersect(p0, p1, p2, limit),
                    TriangleTest::MollerTrumbore => moller_trumbore(&local, p0, p1, p2, limit),
                };
                hit.filter(|&(_, u, v)| {
                    self.cutouts
                        .as_ref()
                        .is_none_or(|c| c.keeps_triangle(instance, prim, u, v))
                })
            }
        }
    }

    /// Any hit with `0 < t < t_max`.
    fn any_hit<const MASKED: bool>(&self, ray: &Ray, t_max: f32) -> bool {
        if !Self::is_queryable(ray, t_max) {
            return false;
        }
        let mut hit = false;
        let mut mailbox = Mailbox::default();
        self.top.traverse::<true>(ray, t_max, |range| {
            for &instance in &self.top.prim_indices[range] {
                if mailbox.seen(instance) {
                    continue;
                }
                let mut limit = t_max;
                self.test_object::<MASKED>(ray, instance, &mut limit, true, &mut |_, _| hit = true);
                if hit {
                    return LeafResult::Stop;
                }
            }
            LeafResult::Continue(t_max)
        });
        hit
    }

    /// The oracle finds nothing for these rays (every test compares NaN or
    /// divides by a zero direction); the traversal's interval arithmetic
    /// assumes a real ray, so they are answered before it.
    fn is_queryable(ray: &Ray, t_max: f32) -> bool {
        t_max > 0.0 && ray.origin.is_finite() && ray.dir.is_finite() && ray.dir != Vec3A::ZERO
    }

    /// Closest hit with `0 < t < t_max`, identical to the brute-force loop's.
    ///
    /// The oracle visits objects and triangles in index order and accepts a
    /// hit only below the best `t` found so far. Triangle tests decide `t <
    /// limit` on `t·det` before dividing, so a hit may be rejected by a limit
    /// that is up to a few ulps above its own `t`: when two surfaces are hit
    /// within ulps of each other, the oracle's answer depends on their order.
    /// The traversal therefore collects every hit within `TIE_ULPS` of the
    /// best and, when there are several, replays the oracle's ordered loop on
    /// them alone. (Hits further away cannot change that loop's outcome: any
    /// limit more than 8 ulps above a hit's `t` accepts it.)
    fn closest_hit<const MASKED: bool>(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        if !Self::is_queryable(ray, t_max) {
            return None;
        }
        let mut near = NearHits::default();
        let mut best_t = f32::INFINITY;
        let mut mailbox = Mailbox::default();
        let mut window = |t: f32| ulps_above(t, TIE_ULPS).min(t_max);
        self.top.traverse::<false>(ray, t_max, |range| {
            for &instance in &self.top.prim_indices[range] {
                if mailbox.seen(instance) {
                    continue;
                }
                let mut limit = if best_t.is_finite() { window(best_t) } else { t_max };
                self.test_object::<MASKED>(ray, instance, &mut limit, false, &mut |hit, limit| {
                    if hit.t < best_t {
                        best_t = hit.t;
                        *limit = window(best_t);
                    }
                    near.push(hit);
                });
            }
            LeafResult::Continue(if best_t.is_finite() { window(best_t) } else { t_max })
        });
        near.resolve(
            best_t,
            &mut window,
            |h, limit| self.test_prim(ray, h.instance, h.prim, limit),
            t_max,
        )
    }
}

/// Hits are gathered within this many ulps above the best `t` (see
/// `closest_hit`): twice the largest gap, 8 ulps, between a hit's `t` and the
/// lowest limit that accepts it (Woop et al.'s division-free range test:
/// two roundings in `t`, one in `limit·det`).
const TIE_ULPS: u32 = 16;

/// Positive `t` moved up by `n` ulps (saturating at +inf).
#[inline]
fn ulps_above(t: f32, n: u32) -> f32 {
    debug_assert!(t >= 0.0);
    f32::from_bits((t + 0.0).to_bits().saturating_add(n).min(f32::INFINITY.to_bits()))
}

/// Recently tested objects (mailboxing, Amanatides & Woo 1987): an object
/// several top-level leaves reference is tested once per query. Empty slots
/// hold [`Mailbox::EMPTY`], which no object index reaches (a scene holds far
/// fewer objects), so a lookup compares the whole fixed-size array.
struct Mailbox {
    ids: [u32; MAILBOX_SIZE],
    next: usize,
}

impl Default for Mailbox {
    fn default() -> Self {
        Self {
            ids: [Self::EMPTY; MAILBOX_SIZE],
            next: 0,
        }
    }
}

impl Mailbox {
    /// The id of an empty slot.
    const EMPTY: u32 = u32::MAX;

    /// True when `id` was tested already; else remembers it.
    #[inline]
    fn seen(&mut self, id: u32) -> bool {
        if self.ids.contains(&id) {
            return true;
        }
        self.ids[self.next % MAILBOX_SIZE] = id;
        self.next += 1;
        false
    }
}

/// Hits collected by a closest-hit query: a fixed buffer (not initialised
/// up front), spilling to the heap only when a ray meets many surfaces at
/// almost the same `t`.
#[derive(Default)]
struct NearHits {
    fixed: ArrayVec<Hit, 8>,
    spill: Vec<Hit>,
}

impl NearHits {
    #[inline]
    fn push(&mut self, hit: Hit) {
        if let Err(full) = self.fixed.try_push(hit) {
            self.spill.push(full.element());
        }
    }

    /// The oracle's answer among the collected hits within the window of `best_t`.
    fn resolve(
        self,
        best_t: f32,
        window: &mut impl FnMut(f32) -> f32,
        mut retest: impl FnMut(&Hit, f32) -> Option<(f32, f32, f32)>,
        t_max: f32,
    ) -> Option<Hit> {
        // The first hit found is the best so far, so a lone hit is the answer.
        match (self.fixed.as_slice(), self.spill.is_empty()) {
            ([], _) => return None,
            ([only], true) => return Some(*only),
            _ => {}
        }
        let top = window(best_t);
        let mut candidates: Vec<Hit> = Vec::new();
        let mut single: Option<Hit> = None;
        let mut count = 0;
        for h in self.fixed.iter().chain(self.spill.iter()) {
            if h.t <= top {
                count += 1;
                if count == 1 {
                    single = Some(*h);
                } else {
                    if count == 2 {
                        candidates.push(single.unwrap());
                    }
                    candidates.push(*h);
                }
            }
        }
        if count <= 1 {
            return single;
        }
        // Replay the oracle's loop: object order, then triangle order, each
        // accepted only below the last accepted t.
        candidates.sort_by_key(|h| (h.instance, h.prim));
        candidates.dedup_by_key(|h| (h.instance, h.prim));
        let mut limit = t_max;
        let mut answer = None;
        for h in candidates {
            if let Some((t, u, v)) = retest(&h, limit) {
                limit = t;
                answer = Some(Hit { t, u, v, ..h });
            }
        }
        answer
    }
}

impl Accel for KdTreeAccel {
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        match self.cutouts {
            Some(_) => self.closest_hit::<true>(ray, t_max),
            None => self.closest_hit::<false>(ray, t_max),
        }
    }

    fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        match self.cutouts {
            Some(_) => self.any_hit::<true>(ray, t_max),
            None => self.any_hit::<false>(ray, t_max),
        }
    }

    fn stats(&self) -> AccelStats {
        let top = self.top.shape();
        let mut bottom = TreeShape::default();
        let mut triangles = 0usize;
        let mut blas_count = 0usize;
        for (blas, mesh) in self.blas.iter().zip(&self.meshes) {
            let tree = &blas.tree;
            if tree.nodes.is_empty() {
                continue;
            }
            blas_count += 1;
            triangles += mesh.triangles.len();
            let s = tree.shape();
            bottom.nodes += s.nodes;
            bottom.leaves += s.leaves;
            bottom.empty_leaves += s.empty_leaves;
            bottom.references += s.references;
            bottom.max_depth = bottom.max_depth.max(s.max_depth);
        }
        let memory_bytes = self.top.memory_bytes()
            + self.blas.iter().map(Blas::memory_bytes).sum::<usize>()
            + self.objects.len() * std::mem::size_of::<TopObject>();
        let full_leaves = (bottom.leaves - bottom.empty_leaves).max(1);
        let details = vec![
            ("top nodes".to_string(), top.nodes.to_string()),
            ("top leaves".to_string(), top.leaves.to_string()),
            ("top depth".to_string(), top.max_depth.to_string()),
            ("bottom nodes".to_string(), bottom.nodes.to_string()),
            ("bottom leaves".to_string(), bottom.leaves.to_string()),
            ("bottom empty leaves".to_string(), bottom.empty_leaves.to_string()),
            ("bottom depth".to_string(), bottom.max_depth.to_string()),
            ("triangles".to_string(), triangles.to_string()),
            ("triangle references".to_string(), bottom.references.to_string()),
            (
                "triangles per non-empty leaf".to_string(),
                format!("{:.2}", bottom.references as f64 / full_leaves as f64),
            ),
            (
                "triangle test".to_string(),
                match self.test {
                    TriangleTest::Watertight => "watertight".to_string(),
                    TriangleTest::MollerTrumbore => "moller-trumbore".to_string(),
                },
            ),
        ];
        AccelStats {
            name: "kdtree".into(),
            build_time: self.build_time,
            memory_bytes,
            blas_count,
            instances: self.objects.len(),
            details,
        }
    }
}
