//! Queries on a committed scene: closest hit of one ray or of a 16-ray
//! packet, occlusion, and the translation between [`Ray`] / [`Hit`] and
//! Embree's ray and hit records.

use super::scene::CommittedScene;
use super::sys;
use crate::accel::Hit;
use crate::math::Ray;

impl CommittedScene {
    /// Closest hit with `0 < t < t_max` as Embree reports it: `(t, geomID,
    /// primID, instID[0], u, v)`.
    #[inline]
    pub(super) fn intersect_raw(&self, ray: &Ray, t_max: f32) -> Option<sys::RTCRayHit> {
        let mut rayhit = sys::RTCRayHit {
            ray: make_ray(ray, t_max)?,
            hit: sys::RTCHit {
                geomID: sys::RTC_INVALID_GEOMETRY_ID,
                primID: sys::RTC_INVALID_GEOMETRY_ID,
                instID: [sys::RTC_INVALID_GEOMETRY_ID],
                instPrimID: [sys::RTC_INVALID_GEOMETRY_ID],
                ..Default::default()
            },
        };
        // SAFETY: committed scene; `rayhit` is a fully initialised, 16-byte
        // aligned RTCRayHit large enough for either hit layout; null
        // arguments select Embree's defaults.
        unsafe { sys::rtcIntersect1(self.inner.raw, &mut rayhit, std::ptr::null_mut()) };
        (rayhit.hit.geomID != sys::RTC_INVALID_GEOMETRY_ID).then_some(rayhit)
    }

    /// Closest hits of up to [`sys::PACKET_SIZE`] rays with `0 < t < t_max`,
    /// traced as one packet (`rtcIntersect16`): `out[i]` for `rays[i]`.
    pub(super) fn intersect_packet(&self, rays: &[Ray], t_max: f32, out: &mut [Option<Hit>]) {
        assert!(rays.len() <= sys::PACKET_SIZE && out.len() == rays.len());
        let n = sys::PACKET_SIZE;
        let mut packet = sys::RTCRayHit16 {
            org_x: [0.0; 16],
            org_y: [0.0; 16],
            org_z: [0.0; 16],
            tnear: [0.0; 16],
            dir_x: [0.0; 16],
            dir_y: [0.0; 16],
            dir_z: [0.0; 16],
            time: [0.0; 16],
            tfar: [0.0; 16],
            mask: [u32::MAX; 16],
            id: [0; 16],
            flags: [0; 16],
            Ng_x: [0.0; 16],
            Ng_y: [0.0; 16],
            Ng_z: [0.0; 16],
            u: [0.0; 16],
            v: [0.0; 16],
            primID: [sys::RTC_INVALID_GEOMETRY_ID; 16],
            geomID: [sys::RTC_INVALID_GEOMETRY_ID; 16],
            instID: [[sys::RTC_INVALID_GEOMETRY_ID; 16]; 1],
            instPrimID: [[sys::RTC_INVALID_GEOMETRY_ID; 16]; 1],
        };
        let mut valid = [0i32; 16];
        for (i, ray) in rays.iter().enumerate() {
            if let Some(r) = make_ray(ray, t_max) {
                packet.org_x[i] = r.org_x;
                packet.org_y[i] = r.org_y;
                packet.org_z[i] = r.org_z;
                packet.tnear[i] = r.tnear;
                packet.dir_x[i] = r.dir_x;
                packet.dir_y[i] = r.dir_y;
                packet.dir_z[i] = r.dir_z;
                packet.tfar[i] = r.tfar;
                valid[i] = -1;
            }
        }
        debug_assert_eq!(n, valid.len());
        // SAFETY: committed scene; `valid` has 16 entries and `packet` is a
        // fully initialised, 64-byte aligned RTCRayHit16 (layout pinned by
        // the sys tests) that Embree writes only in valid lanes; null
        // arguments select Embree's defaults.
        unsafe { sys::rtcIntersect16(valid.as_ptr(), self.inner.raw, &mut packet, std::ptr::null_mut()) };
        for (i, hit) in out.iter_mut().enumerate() {
            *hit = (valid[i] != 0 && packet.geomID[i] != sys::RTC_INVALID_GEOMETRY_ID).then(|| {
                hit_record(
                    packet.tfar[i],
                    packet.geomID[i],
                    packet.primID[i],
                    packet.instID[0][i],
                    packet.u[i],
                    packet.v[i],
                )
            });
        }
    }

    /// Any hit with `0 < t < t_max`.
    #[inline]
    pub(super) fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        let Some(mut r) = make_ray(ray, t_max) else {
            return false;
        };
        // SAFETY: committed scene; `r` is a fully initialised, aligned RTCRay;
        // Embree sets tfar to −inf when something is hit.
        unsafe { sys::rtcOccluded1(self.inner.raw, &mut r, std::ptr::null_mut()) };
        r.tfar == f32::NEG_INFINITY
    }
}

/// The Embree ray for `0 < t < t_max`; `None` when the interval is empty.
///
/// `tnear = f32::MIN_POSITIVE` is how "t > 0" (the contract of the other
/// backends) is written for Embree, which accepts `tnear <= t`: with
/// `tnear = 0` a ray starting exactly on a surface would report `t = 0`. It
/// only excludes subnormal t (< 1.2e-38), far below any offset the integrator
/// uses. `tfar` is clamped to `f32::MAX` (Embree's documented range).
#[inline]
fn make_ray(ray: &Ray, t_max: f32) -> Option<sys::RTCRay> {
    // NaN fails this test (and `f32::min` would silently drop it).
    if t_max.is_nan() || t_max <= f32::MIN_POSITIVE {
        return None;
    }
    let tfar = t_max.min(f32::MAX);
    Some(sys::RTCRay {
        org_x: ray.origin.x,
        org_y: ray.origin.y,
        org_z: ray.origin.z,
        tnear: f32::MIN_POSITIVE,
        dir_x: ray.dir.x,
        dir_y: ray.dir.y,
        dir_z: ray.dir.z,
        time: 0.0,
        tfar,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    })
}

/// The [`Hit`] of an Embree hit record: an instanced mesh's hit is reported
/// through its instance (the TLAS geometry ID of the object); a mesh in the
/// top level and an analytic shape (one primitive, ID 0) by their own
/// geometry ID.
#[inline]
pub(super) fn hit_record(t: f32, geom_id: u32, prim_id: u32, inst_id: u32, u: f32, v: f32) -> Hit {
    let instance = if inst_id != sys::RTC_INVALID_GEOMETRY_ID {
        inst_id
    } else {
        geom_id
    };
    let prim = prim_id;
    Hit {
        t,
        instance,
        prim,
        u,
        v,
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Device, Geometry, Scene};
    use super::*;
    use crate::math::{Affine3A, Vec3A};
    use crate::scene::Mesh;
    use std::sync::Arc;

    /// One instanced triangle at z = 0 (object space), moved to z = -2.
    fn one_instance_scene() -> (Device, CommittedScene) {
        let device = Device::new(None).unwrap();
        let mesh = Arc::new(
            Mesh::new(
                "tri",
                vec![
                    crate::math::Vec3::new(-1.0, -1.0, 0.0),
                    crate::math::Vec3::new(1.0, -1.0, 0.0),
                    crate::math::Vec3::new(0.0, 1.0, 0.0),
                ],
                vec![[0, 1, 2]],
                None,
            )
            .unwrap(),
        );
        let mut blas = Scene::new(&device, sys::RTC_BUILD_QUALITY_HIGH, false).unwrap();
        blas.attach(
            Geometry::triangles(&device, &mesh, None, sys::RTC_BUILD_QUALITY_HIGH, None).unwrap(),
            0,
        )
        .unwrap();
        let blas = blas.commit().unwrap();
        let mut tlas = Scene::new(&device, sys::RTC_BUILD_QUALITY_HIGH, false).unwrap();
        let to_world = Affine3A::from_translation(crate::math::Vec3::new(0.0, 0.0, -2.0));
        tlas.attach(Geometry::instance(&device, &blas, &to_world).unwrap(), 7)
            .unwrap();
        (device, tlas.commit().unwrap())
    }

    #[test]
    fn instance_hits_fill_the_hit_record() {
        let (_device, tlas) = one_instance_scene();
        let ray = Ray::new(Vec3A::new(0.5, -0.5, 1.0), -Vec3A::Z);
        let rh = tlas.intersect_raw(&ray, f32::INFINITY).expect("hit");
        assert_eq!(rh.hit.instID[0], 7);
        assert_eq!(rh.hit.geomID, 0);
        assert_eq!(rh.hit.primID, 0);
        assert!((rh.ray.tfar - 3.0).abs() < 1e-6);
        // p = 0.5 p0 + ... : (0.5, -0.5) = b0(-1,-1) + b1(1,-1) + b2(0,1)
        // → b2 = 0.25, b1 = 0.625, b0 = 0.125 (u, v weight vertices 1 and 2).
        assert!(
            (rh.hit.u - 0.625).abs() < 1e-6 && (rh.hit.v - 0.25).abs() < 1e-6,
            "{rh:?}"
        );
        // Which RTCHit layout the linked library uses: with instance arrays
        // compiled in, Embree writes instPrimID[0] = 0 for a plain instance,
        // i.e. bytes 80..84 of RTCRayHit, past an 80-byte struct. Either way
        // our 96-byte struct holds it; the value must be 0 or untouched.
        let ipid = rh.hit.instPrimID[0];
        assert!(ipid == 0 || ipid == sys::RTC_INVALID_GEOMETRY_ID, "{ipid}");
        eprintln!(
            "linked Embree writes instPrimID: {}",
            if ipid == 0 {
                "yes (96-byte RTCRayHit)"
            } else {
                "no (80-byte layout)"
            }
        );
        assert!(tlas.occluded(&ray, 3.5) && !tlas.occluded(&ray, 2.5));
    }
}
