//! Intel Embree 4 behind the [`Accel`] contract: a safe RAII wrapper over the
//! hand-written FFI in [`sys`], and [`EmbreeAccel`], the two-level structure.
//!
//! Two levels, as in the KD-tree: one BLAS (an Embree scene holding one
//! triangle geometry) per distinct mesh that several objects use, in object
//! space; a TLAS holding one instance geometry per object of such a mesh
//! (its `to_world` transform), the triangles of each mesh that only one
//! object uses (in world space: a ray traverses one BVH instead of two and
//! is not transformed), and one user geometry per analytic sphere, quad,
//! disk or cylinder. TLAS geometry IDs equal object indices
//! (`rtcAttachGeometryByID`), so a hit maps to `Hit::instance` without a
//! table.
//!
//! Analytic shapes are user geometries whose callbacks call the scene's own
//! [`Sphere::intersect`](crate::scene::Sphere::intersect),
//! [`Quad::intersect`](crate::scene::Quad::intersect),
//! [`Disk::intersect`](crate::scene::Disk::intersect) and
//! [`Cylinder::intersect`](crate::scene::Cylinder::intersect): Embree then reports exactly
//! the `(t, a, b)` of the other backends, bit for bit, so cross-checks need no
//! tolerance for them and the robust-offset reasoning of the integrator (built
//! around those functions' error bounds) holds unchanged. Embree's native
//! spheres and quads were both slower here and less exact (their roots
//! carry more rounding: the figures are in `docs/benchmarks-history.md`);
//! scenes hold a handful of analytic shapes, so exactness wins and costs
//! nothing. An analytic shape whose material has an alpha mask gets the
//! masked callbacks, which skip its holes through `scene::Cutouts`.
//!
//! In robust mode (the default) Embree's `(u, v)` can be off the point at
//! its own `t` on rays through a vertex or along a sliver's edge (rare: see
//! `docs/benchmarks-history.md`), and the integrator builds the shading
//! point and its error bound from `(u, v)`. Each mesh hit is therefore re-intersected with the in-house
//! watertight test on the triangle Embree found, whose `(t, u, v)` are
//! consistent by construction. When that test misses Embree's triangle (a
//! ray within rounding of an edge that it gives to the neighbour), `(u, v)`
//! become the barycentrics of the point at Embree's `t`, projected onto the
//! triangle and clamped into it.
//!
//! The wrapper is split by what it does: `device` owns the device and its
//! error and memory callbacks, `scene` builds geometries and scenes,
//! `analytic` holds the user-geometry callbacks of the analytic shapes, and
//! `query` casts rays through a committed scene; this module holds the
//! backend, [`EmbreeAccel`].
#![allow(unsafe_code)]

mod analytic;
mod device;
mod query;
mod scene;
pub mod sys;

pub use device::{source, version, Device};
pub use scene::{CommittedScene, Geometry, Scene};

use super::triangle::WatertightRay;
use super::{Accel, AccelError, AccelOptions, AccelStats, Hit};
use crate::math::{Ray, Transform, Vec3A};
use crate::scene::{Cutouts, Mesh, Scene as CausticScene, Shape};
use analytic::{AnalyticGeometry, AnalyticShape};
use device::version_string;
use query::hit_record;
use std::sync::Arc;
use std::time::Instant;

/// Maps `"low" | "medium" | "high"` to Embree's build quality.
pub fn build_quality(name: &str) -> Result<sys::RTCBuildQuality, AccelError> {
    match name {
        "low" => Ok(sys::RTC_BUILD_QUALITY_LOW),
        "medium" => Ok(sys::RTC_BUILD_QUALITY_MEDIUM),
        "high" => Ok(sys::RTC_BUILD_QUALITY_HIGH),
        other => Err(AccelError::Scene(format!(
            "unknown Embree build quality '{other}' (expected low, medium or high)"
        ))),
    }
}

/// The Embree backend: a TLAS over per-mesh BLAS instances and analytic shapes.
pub struct EmbreeAccel {
    // Field order is drop order: the TLAS goes before the BLAS it instances,
    // and the device (inside `device`) goes last.
    tlas: CommittedScene,
    blas: Vec<CommittedScene>,
    device: Device,
    stats: AccelStats,
    /// Per object, its mesh and transform when hits are re-intersected
    /// (robust mode; module docs), else `None`.
    refine: Vec<Option<(Arc<Mesh>, Transform)>>,
}

impl EmbreeAccel {
    /// Builds the two levels over `scene` with `options.embree_quality` and
    /// `options.embree_robust`.
    pub fn build(scene: &CausticScene, options: &AccelOptions) -> Result<Self, AccelError> {
        let start = Instant::now();
        let quality = build_quality(&options.embree_quality)?;
        let device = Device::new(None)?;
        if scene.objects.len() >= sys::RTC_INVALID_GEOMETRY_ID as usize {
            return Err(AccelError::Scene(format!(
                "{} objects exceed Embree's geometry IDs",
                scene.objects.len()
            )));
        }
        let cutouts = Cutouts::of(scene);
        // Meshes that some masked object uses get the cutout filter.
        let mut masked = vec![false; scene.meshes.len()];
        for (i, object) in scene.objects.iter().enumerate() {
            if let (Shape::Mesh { mesh, .. }, Some(c)) = (&object.shape, &cutouts) {
                if c.has(i as u32) {
                    if let Some(m) = masked.get_mut(*mesh as usize) {
                        *m = true;
                    }
                }
            }
        }
        // How many objects use each mesh: one alone goes in the top level.
        let mut users = vec![0usize; scene.meshes.len()];
        for object in &scene.objects {
            if let Shape::Mesh { mesh, .. } = &object.shape {
                let index = *mesh as usize;
                let Some(count) = users.get_mut(index) else {
                    return Err(AccelError::Scene(format!(
                        "object {} uses mesh {index}, but the scene has {} meshes",
                        object.name,
                        scene.meshes.len()
                    )));
                };
                *count += 1;
            }
        }
        // One BLAS per distinct mesh that several objects use.
        let mut blas_of_mesh: Vec<Option<usize>> = vec![None; scene.meshes.len()];
        let mut blas = Vec::new();
        for object in &scene.objects {
            if let Shape::Mesh { mesh, .. } = &object.shape {
                let index = *mesh as usize;
                let mesh_arc = &scene.meshes[index];
                if users[index] > 1 && blas_of_mesh[index].is_none() {
                    let mut bottom = Scene::new(&device, quality, options.embree_robust)?;
                    let filter = cutouts.as_ref().filter(|_| masked[index]);
                    bottom.attach(Geometry::triangles(&device, mesh_arc, None, quality, filter)?, 0)?;
                    blas_of_mesh[index] = Some(blas.len());
                    blas.push(bottom.commit()?);
                }
            }
        }
        let mut top = Scene::new(&device, quality, options.embree_robust)?;
        let mut flattened = 0usize;
        for (id, object) in scene.objects.iter().enumerate() {
            let analytic = |shape| {
                let object = id as u32;
                let cutouts = cutouts.clone().filter(|c| c.has(object));
                Geometry::analytic(&device, AnalyticGeometry { shape, object, cutouts })
            };
            let geometry = match &object.shape {
                Shape::Sphere(s) => analytic(AnalyticShape::Sphere(*s))?,
                Shape::Quad(q) => analytic(AnalyticShape::Quad(*q))?,
                Shape::Disk(d) => analytic(AnalyticShape::Disk(*d))?,
                Shape::Cylinder(c) => analytic(AnalyticShape::Cylinder(*c))?,
                Shape::Mesh { mesh, transform, .. } => match blas_of_mesh[*mesh as usize] {
                    Some(b) => Geometry::instance(&device, &blas[b], &transform.to_world)?,
                    None => {
                        let filter = cutouts.as_ref().filter(|c| c.has(id as u32));
                        let to_world = (!transform.is_identity()).then_some(&transform.to_world);
                        flattened += 1;
                        Geometry::triangles(&device, &scene.meshes[*mesh as usize], to_world, quality, filter)?
                    }
                },
            };
            top.attach(geometry, id as u32)?;
        }
        let tlas = top.commit()?;
        let refine = scene
            .objects
            .iter()
            .map(|object| match &object.shape {
                Shape::Mesh { mesh, transform, .. } if options.embree_robust => {
                    Some((scene.meshes[*mesh as usize].clone(), *transform))
                }
                _ => None,
            })
            .collect();
        let (bytes, peak) = device.memory_bytes();
        let stats = AccelStats {
            name: "embree".into(),
            build_time: start.elapsed(),
            memory_bytes: bytes,
            blas_count: blas.len(),
            instances: scene.objects.len(),
            details: vec![
                ("version".into(), version_string(device.version_number())),
                ("source".into(), source().into()),
                ("quality".into(), options.embree_quality.clone()),
                ("robust".into(), options.embree_robust.to_string()),
                ("meshes in the top level".into(), flattened.to_string()),
                ("peak build memory".into(), format!("{peak} bytes")),
            ],
        };
        Ok(Self {
            tlas,
            blas,
            device,
            stats,
            refine,
        })
    }

    /// `hit` with `(t, u, v)` from the watertight test on its triangle, in
    /// robust mode, or with the barycentrics of its point when that test
    /// finds no hit below `t_max` (module docs).
    #[inline]
    fn refined(&self, ray: &Ray, t_max: f32, hit: Hit) -> Hit {
        let Some(Some((mesh, transform))) = self.refine.get(hit.instance as usize) else {
            return hit;
        };
        let Some(&[a, b, c]) = mesh.triangles.get(hit.prim as usize) else {
            return hit;
        };
        let p = |i: u32| mesh.positions[i as usize].into();
        let local = transform.ray_to_object(ray);
        let (a, b, c) = (p(a), p(b), p(c));
        match WatertightRay::new(&local).intersect(a, b, c, t_max) {
            Some((t, u, v)) => Hit { t, u, v, ..hit },
            None => {
                let (u, v) = clamped_barycentrics(local.at(hit.t), a, b, c);
                Hit { u, v, ..hit }
            }
        }
    }

    /// Bytes Embree holds now (memory monitor).
    pub fn memory_bytes(&self) -> usize {
        self.device.memory_bytes().0
    }

    /// Number of bottom-level scenes.
    pub fn blas_count(&self) -> usize {
        self.blas.len()
    }
}

impl Accel for EmbreeAccel {
    #[inline]
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let rh = self.tlas.intersect_raw(ray, t_max)?;
        let hit = hit_record(
            rh.ray.tfar,
            rh.hit.geomID,
            rh.hit.primID,
            rh.hit.instID[0],
            rh.hit.u,
            rh.hit.v,
        );
        Some(self.refined(ray, t_max, hit))
    }

    /// Packets of 16 rays (`rtcIntersect16`); a lone ray goes alone. For
    /// coherent rays (photons leaving one light in neighbouring directions)
    /// Embree's packet traversal shares the node tests across the lanes.
    fn intersect_many(&self, rays: &[Ray], t_max: f32, hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len());
        for (rays, hits) in rays.chunks(sys::PACKET_SIZE).zip(hits.chunks_mut(sys::PACKET_SIZE)) {
            if let [ray] = rays {
                hits[0] = self.intersect(ray, t_max);
            } else {
                self.tlas.intersect_packet(rays, t_max, hits);
                for (ray, hit) in rays.iter().zip(hits.iter_mut()) {
                    if let Some(h) = *hit {
                        *hit = Some(self.refined(ray, t_max, h));
                    }
                }
            }
        }
    }

    #[inline]
    fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.tlas.occluded(ray, t_max)
    }

    fn stats(&self) -> AccelStats {
        self.stats.clone()
    }
}

/// Barycentric weights `(u, v)` of `p1`, `p2` for the projection of `q` onto
/// the triangle's plane, clamped into the triangle (f64: the point is within
/// rounding of an edge).
fn clamped_barycentrics(q: Vec3A, p0: Vec3A, p1: Vec3A, p2: Vec3A) -> (f32, f32) {
    let (e1, e2, w) = ((p1 - p0).as_dvec3(), (p2 - p0).as_dvec3(), (q - p0).as_dvec3());
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (w1, w2) = (w.dot(e1), w.dot(e2));
    let det = d11 * d22 - d12 * d12;
    if det.is_nan() || det <= 0.0 {
        return (0.0, 0.0);
    }
    let u = ((d22 * w1 - d12 * w2) / det).max(0.0);
    let v = ((d11 * w2 - d12 * w1) / det).max(0.0);
    let sum = u + v;
    let (u, v) = if sum > 1.0 { (u / sum, v / sum) } else { (u, v) };
    (u as f32, v as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clamped_barycentrics_recover_points_and_clamp_outside() {
        let (p0, p1, p2) = (Vec3A::ZERO, Vec3A::X, Vec3A::Y);
        let (u, v) = clamped_barycentrics(Vec3A::new(0.25, 0.5, 0.3), p0, p1, p2);
        assert!((u - 0.25).abs() < 1e-7 && (v - 0.5).abs() < 1e-7);
        assert_eq!(clamped_barycentrics(Vec3A::new(-0.1, 0.5, 0.0), p0, p1, p2), (0.0, 0.5));
        let (u, v) = clamped_barycentrics(Vec3A::new(1.0, 1.0, 0.0), p0, p1, p2);
        assert!((u - 0.5).abs() < 1e-7 && (v - 0.5).abs() < 1e-7);
    }

    #[test]
    fn unknown_quality_is_rejected() {
        assert!(build_quality("ultra").is_err());
        assert_eq!(build_quality("low").unwrap(), sys::RTC_BUILD_QUALITY_LOW);
    }
}
