//! Case 1, watertightness: rays aimed exactly at the shared edges and the
//! vertices of closed meshes, from outside, in directions that enter the
//! interior through every face around the target.
//!
//! Targets (one third each): an edge's midpoint, a point at a uniform random
//! parameter along an edge (`a + s(b − a)`, rounded: it lies within an ulp of
//! the edge, on either side), and a vertex. Only manifold edges (exactly two
//! faces, opposite windings, neither degenerate) and vertices whose edges
//! are all manifold are used; the rest are counted in the note. The direction
//! `d` satisfies `d·n < −0.05` for every face normal `n` around the target
//! (the mean inward normal, randomly tilted), so the ray crosses from the
//! outside into the inside exactly at the target. The origin is
//! `target − d·dist` with `dist` log-uniform in 0.01–2 bounding-box diagonals.
//!
//! Default rows: the KD-tree with the watertight test on the closed
//! generated meshes. Measured only: Möller–Trumbore, Embree (default and
//! robust: both miss at some vertices), and every row of the dragon, which
//! is not closed (the note counts its open and non-manifold edges).
//!
//! **Failure (a miss):** no hit at `t ≤ dist·(1 + 1e-4) + 1e-6·diag`: the ray
//! crossed the closed surface at the target without hitting it (it then hits
//! the far side, or nothing). A hit before the target (another part of a
//! non-convex mesh in the way) passes.

use super::{guarded, log_uniform, random_unit, scene_of, share, tally, trial_rng, unavailable_row};
use super::{Backend, Role, StressOptions, StressRow, Tally};
use crate::geometry::generate::{icosphere, torus};
use crate::io::{self, assets};
use crate::math::{Ray, Transform, Vec3A};
use crate::scene::{Mesh, Shape};
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::Arc;

const CASE: u64 = 1;

/// Edges and vertex fans of a mesh, restricted to its manifold part.
pub struct Topology {
    /// Manifold edges `(a, b, face0, face1)`.
    pub edges: Vec<(u32, u32, u32, u32)>,
    /// Unit face normals (zero for degenerate faces).
    pub face_normals: Vec<Vec3A>,
    /// Faces around each vertex (CSR: `fan_start[v]..fan_start[v + 1]` in `fan`).
    fan_start: Vec<u32>,
    fan: Vec<u32>,
    /// Vertices touching a non-manifold or boundary edge (not used as targets).
    bad_vertex: Vec<bool>,
    /// Edges left out (boundary, non-manifold, inconsistent or degenerate).
    pub excluded_edges: usize,
}

impl Topology {
    /// Analyses `mesh`.
    pub fn new(mesh: &Mesh) -> Self {
        let face_normals: Vec<Vec3A> = (0..mesh.triangles.len())
            .into_par_iter()
            .map(|i| {
                let [a, b, c] = mesh.corners(i);
                (b - a).cross(c - a).normalize_or_zero()
            })
            .collect();
        let mut by_edge: HashMap<(u32, u32), Vec<(u32, bool)>> = HashMap::with_capacity(mesh.triangles.len() * 3 / 2);
        for (f, t) in mesh.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                by_edge.entry((a.min(b), a.max(b))).or_default().push((f as u32, a < b));
            }
        }
        let mut bad_vertex = vec![false; mesh.positions.len()];
        let mut edges = Vec::with_capacity(by_edge.len());
        let mut excluded_edges = 0;
        for (&(a, b), faces) in &by_edge {
            let ok = faces.len() == 2
                && faces[0].1 != faces[1].1
                && faces.iter().all(|&(f, _)| face_normals[f as usize] != Vec3A::ZERO);
            if ok {
                edges.push((a, b, faces[0].0, faces[1].0));
            } else {
                excluded_edges += 1;
                bad_vertex[a as usize] = true;
                bad_vertex[b as usize] = true;
            }
        }
        // HashMap order is random: sort for determinism.
        edges.sort_unstable();
        let mut count = vec![0u32; mesh.positions.len() + 1];
        for t in &mesh.triangles {
            for &v in t {
                count[v as usize + 1] += 1;
            }
        }
        for i in 1..count.len() {
            count[i] += count[i - 1];
        }
        let mut fill = count.clone();
        let mut fan = vec![0u32; mesh.triangles.len() * 3];
        for (f, t) in mesh.triangles.iter().enumerate() {
            for &v in t {
                fan[fill[v as usize] as usize] = f as u32;
                fill[v as usize] += 1;
            }
        }
        Self {
            edges,
            face_normals,
            fan_start: count,
            fan,
            bad_vertex,
            excluded_edges,
        }
    }

    fn fan(&self, v: u32) -> &[u32] {
        &self.fan[self.fan_start[v as usize] as usize..self.fan_start[v as usize + 1] as usize]
    }
}

/// A direction entering through every face normal of `normals` (each
/// `d·n < −0.05`), tilted at random; `None` when 16 tries fail.
fn entering_direction(normals: &[Vec3A], rng: &mut crate::math::Rng) -> Option<Vec3A> {
    let sum: Vec3A = normals.iter().copied().sum();
    let base = -sum.normalize_or_zero();
    if base == Vec3A::ZERO {
        return None;
    }
    for attempt in 0..16 {
        let tilt = if attempt == 15 { 0.0 } else { 0.7 * rng.f32() };
        let d = (base + random_unit(rng) * tilt).normalize_or_zero();
        if d != Vec3A::ZERO && normals.iter().all(|n| d.dot(*n) < -0.05) {
            return Some(d);
        }
    }
    None
}

/// A ray aimed at a shared edge or vertex, and the distance to it.
#[derive(Clone, Copy, Debug)]
pub struct AimedRay {
    /// The ray (unit direction).
    pub ray: Ray,
    /// Distance from the origin to the target.
    pub t_target: f32,
    /// 0: edge midpoint, 1: random point on an edge, 2: vertex.
    pub kind: u8,
}

/// `n` aimed rays at `mesh` (fewer when targets had no entering direction).
pub fn aimed_rays(mesh: &Mesh, topo: &Topology, n: u64, seed: u64) -> Vec<AimedRay> {
    if topo.edges.is_empty() {
        return Vec::new();
    }
    let diag = mesh.bounds().extent().length();
    (0..n)
        .into_par_iter()
        .filter_map(|i| {
            let mut rng = trial_rng(seed, CASE, i);
            let kind = (i % 3) as u8;
            let (a, b, f0, f1) = topo.edges[rng.below(topo.edges.len() as u32) as usize];
            let pa = Vec3A::from(mesh.positions[a as usize]);
            let pb = Vec3A::from(mesh.positions[b as usize]);
            let (target, d) = match kind {
                0 | 1 => {
                    let s = if kind == 0 { 0.5 } else { rng.f32() };
                    let target = if kind == 0 { (pa + pb) * 0.5 } else { pa + (pb - pa) * s };
                    let normals = [topo.face_normals[f0 as usize], topo.face_normals[f1 as usize]];
                    (target, entering_direction(&normals, &mut rng)?)
                }
                _ => {
                    let v = if rng.f32() < 0.5 { a } else { b };
                    if topo.bad_vertex[v as usize] {
                        return None;
                    }
                    let normals: Vec<Vec3A> = topo.fan(v).iter().map(|&f| topo.face_normals[f as usize]).collect();
                    (
                        Vec3A::from(mesh.positions[v as usize]),
                        entering_direction(&normals, &mut rng)?,
                    )
                }
            };
            let dist = diag * log_uniform(&mut rng, -2.0, 0.3);
            Some(AimedRay {
                ray: Ray::new(target - d * dist, d),
                t_target: dist,
                kind,
            })
        })
        .collect()
}

/// Misses of `accel` on `rays` (`extra[k]`: misses of kind k; `extra[3]`:
/// rays with no hit at all).
pub fn count_misses(accel: &dyn crate::accel::Accel, rays: &[AimedRay], diag: f32) -> Tally {
    tally(rays.len() as u64, |i| {
        let r = &rays[i as usize];
        let hit = accel.intersect(&r.ray, f32::INFINITY);
        let ok = hit.is_some_and(|h| h.t <= r.t_target * (1.0 + 1e-4) + 1e-6 * diag);
        let mut extra = [0; 6];
        if !ok {
            extra[r.kind as usize] += 1;
            extra[3] += u64::from(hit.is_none());
        }
        Tally {
            trials: 1,
            failures: u64::from(!ok),
            extra,
        }
    })
}

/// The closed meshes: an icosphere, a torus and, when found locally, the dragon.
fn closed_meshes(options: &StressOptions) -> (Vec<(String, Arc<Mesh>)>, Option<String>) {
    let mut meshes = vec![
        ("icosphere(4)".to_string(), Arc::new(icosphere(4))),
        ("torus(64x32)".to_string(), Arc::new(torus(2.0, 0.5, 64, 32))),
    ];
    let mut skipped = None;
    if let Some(name) = &options.dragon {
        // Local copies only (search directories and the cache): a stress run
        // never downloads.
        let mut dirs = assets::search_dirs();
        dirs.extend(assets::cache_dir());
        match assets::resolve_asset_in(name, &dirs, None)
            .map_err(|e| e.to_string())
            .and_then(|p| io::load_mesh(&p).map_err(|e| e.to_string()))
        {
            Ok(mesh) => meshes.push((format!("dragon {name}"), Arc::new(mesh))),
            Err(e) => skipped = Some(format!("dragon skipped: {}", e.lines().next().unwrap_or(""))),
        }
    }
    (meshes, skipped)
}

/// The rows of case 1.
pub fn run(options: &StressOptions) -> Vec<StressRow> {
    let (meshes, skipped) = closed_meshes(options);
    let mut rows = Vec::new();
    if let Some(note) = skipped {
        rows.push(StressRow::new("1 watertight: dragon", "-", Role::Measured, 0, 0).note(note));
    }
    let configs = [
        (Backend::KdWatertight, Role::Default),
        (Backend::EmbreeRobust, Role::Measured),
        (Backend::KdMoller, Role::Measured),
        (Backend::Embree, Role::Measured),
    ];
    for (name, mesh) in meshes {
        let case = format!("1 watertight: {name}");
        let is_dragon = name.starts_with("dragon");
        let topo = Topology::new(&mesh);
        let rays = aimed_rays(&mesh, &topo, options.rays, options.seed);
        let diag = mesh.bounds().extent().length();
        let scene = scene_of(
            vec![mesh.clone()],
            vec![(
                Shape::Mesh {
                    mesh: 0,
                    transform: Transform::IDENTITY,
                    smooth: false,
                },
                0,
            )],
            vec![],
        );
        for (backend, role) in configs {
            // The dragon is not a closed mesh (thousands of boundary and
            // non-manifold edges from the range-scan reconstruction): its
            // rows are measured only; the closed generated meshes are the
            // default check.
            let role = if is_dragon { Role::Measured } else { role };
            if !backend.available() {
                rows.push(unavailable_row(&case, backend, role, "not compiled in"));
                continue;
            }
            rows.extend(guarded(&case, backend.name(), role, || {
                let accel = match backend.build(&scene) {
                    Ok(a) => a,
                    Err(e) => return vec![unavailable_row(&case, backend, role, &e.to_string())],
                };
                let t = count_misses(accel.as_ref(), &rays, diag);
                let mut note = format!(
                    "misses at midpoints {}, edge points {}, vertices {}; no hit at all {}",
                    t.extra[0], t.extra[1], t.extra[2], t.extra[3]
                );
                if topo.excluded_edges > 0 {
                    note += &format!("; {} non-manifold/boundary edges not aimed at", topo.excluded_edges);
                }
                if (rays.len() as u64) < options.rays {
                    note += &format!(
                        "; {} targets without an entering direction",
                        options.rays - rays.len() as u64
                    );
                }
                vec![StressRow::new(&case, backend.name(), role, t.trials, t.failures)
                    .note(format!("{} — {note}", share(t.failures, t.trials)))]
            }));
        }
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn icosphere_topology_is_all_manifold() {
        let m = icosphere(2);
        let t = Topology::new(&m);
        assert_eq!(t.excluded_edges, 0);
        assert_eq!(t.edges.len(), m.triangles.len() * 3 / 2);
        assert!(t.fan(0).len() >= 5);
    }

    #[test]
    fn aimed_rays_reach_their_target_through_the_surface() {
        let m = icosphere(2);
        let t = Topology::new(&m);
        let rays = aimed_rays(&m, &t, 300, 4);
        assert!(rays.len() > 250, "{}", rays.len());
        for r in &rays {
            // The target is on the unit sphere's tessellation (|p| ≤ 1) and
            // the ray comes from outside it.
            let p = r.ray.at(r.t_target);
            assert!(p.length() <= 1.0 + 1e-4 && p.length() > 0.9, "{p}");
            assert!(r.ray.origin.length() > 1.0 - 1e-4);
        }
    }
}
