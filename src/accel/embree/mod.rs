//! Intel Embree 4 behind the [`Accel`] contract: a safe RAII wrapper over the
//! hand-written FFI in [`sys`], and [`EmbreeAccel`], the two-level structure.
//!
//! Two levels, as in the KD-tree: one BLAS (an Embree scene holding one
//! triangle geometry) per distinct mesh, in object space; a TLAS holding one
//! instance geometry per mesh object (its `to_world` transform) and one user
//! geometry per analytic sphere or quad. TLAS geometry IDs equal object
//! indices (`rtcAttachGeometryByID`), so a hit maps to `Hit::instance`
//! without a table.
//!
//! Analytic shapes are user geometries whose callbacks call the scene's own
//! [`Sphere::intersect`](crate::scene::Sphere::intersect) and
//! [`Quad::intersect`](crate::scene::Quad::intersect): Embree then reports exactly
//! the `(t, a, b)` of the other backends, bit for bit, so cross-checks need no
//! tolerance for them and the robust-offset reasoning of the integrator (built
//! around those functions' error bounds) holds unchanged. Measured against
//! the native types (1M rays, one thread, 200 shapes, this 2-core machine
//! under load): spheres 4.1 Mrays/s as user geometry vs 1.8–2.5 with
//! `RTC_GEOMETRY_TYPE_SPHERE_POINT`, whose `t = proj − √(r² − l²)` also
//! differed from the analytic root by up to 6.2e-4 relative (56% of hits
//! beyond 1e-5: the cancellation our `c / q` form avoids for rays starting
//! near a sphere); quads 2.35 Mrays/s vs 1.28 with `RTC_GEOMETRY_TYPE_QUAD`
//! (two triangles with their own rounding). Scenes hold a handful of
//! analytic shapes, so exactness wins and costs nothing.
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

use super::{Accel, AccelError, AccelOptions, AccelStats, Hit};
use crate::math::Ray;
use crate::scene::{Scene as CausticScene, Shape};
use analytic::AnalyticShape;
use device::version_string;
use query::hit_record;
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
        // One BLAS per distinct mesh that some object uses.
        let mut blas_of_mesh: Vec<Option<usize>> = vec![None; scene.meshes.len()];
        let mut blas = Vec::new();
        for object in &scene.objects {
            if let Shape::Mesh { mesh, .. } = &object.shape {
                let index = *mesh as usize;
                let Some(mesh_arc) = scene.meshes.get(index) else {
                    return Err(AccelError::Scene(format!(
                        "object {} uses mesh {index}, but the scene has {} meshes",
                        object.name,
                        scene.meshes.len()
                    )));
                };
                if blas_of_mesh[index].is_none() {
                    let mut bottom = Scene::new(&device, quality, options.embree_robust)?;
                    bottom.attach(Geometry::triangles(&device, mesh_arc, quality)?, 0)?;
                    blas_of_mesh[index] = Some(blas.len());
                    blas.push(bottom.commit()?);
                }
            }
        }
        let mut top = Scene::new(&device, quality, options.embree_robust)?;
        for (id, object) in scene.objects.iter().enumerate() {
            let geometry = match &object.shape {
                Shape::Sphere(s) => Geometry::analytic(&device, AnalyticShape::Sphere(*s))?,
                Shape::Quad(q) => Geometry::analytic(&device, AnalyticShape::Quad(*q))?,
                Shape::Mesh { mesh, transform, .. } => {
                    let b = blas_of_mesh[*mesh as usize].expect("BLAS built above for every used mesh");
                    Geometry::instance(&device, &blas[b], &transform.to_world)?
                }
            };
            top.attach(geometry, id as u32)?;
        }
        let tlas = top.commit()?;
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
                ("peak build memory".into(), format!("{peak} bytes")),
            ],
        };
        Ok(Self {
            tlas,
            blas,
            device,
            stats,
        })
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
        Some(hit_record(
            rh.ray.tfar,
            rh.hit.geomID,
            rh.hit.primID,
            rh.hit.instID[0],
            rh.hit.u,
            rh.hit.v,
        ))
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_quality_is_rejected() {
        assert!(build_quality("ultra").is_err());
        assert_eq!(build_quality("low").unwrap(), sys::RTC_BUILD_QUALITY_LOW);
    }
}
