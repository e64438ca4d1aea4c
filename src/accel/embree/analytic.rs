//! The analytic shapes (spheres, quads, disks, cylinders) as Embree user geometries: their
//! bounds, intersect and occluded callbacks, which call the scene's own
//! intersection code.

use super::sys;
use crate::math::{Aabb, Ray, Vec3A};
use crate::scene::{Cutouts, Cylinder, Disk, Quad, Sphere};
use std::ffi::c_void;
use std::sync::Arc;

/// An analytic shape in the TLAS (user geometry data).
#[derive(Clone, Copy, Debug)]
pub(super) enum AnalyticShape {
    Sphere(Sphere),
    Quad(Quad),
    Disk(Disk),
    Cylinder(Cylinder),
}

impl AnalyticShape {
    /// `(t, u, v)` exactly as the other backends report it.
    #[inline]
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, f32, f32)> {
        match self {
            AnalyticShape::Sphere(s) => s.intersect(ray, t_max).map(|t| (t, 0.0, 0.0)),
            AnalyticShape::Quad(q) => q.intersect(ray, t_max),
            AnalyticShape::Disk(d) => d.intersect(ray, t_max),
            AnalyticShape::Cylinder(c) => c.intersect(ray, t_max).map(|t| (t, 0.0, 0.0)),
        }
    }

    fn bounds(&self) -> Aabb {
        match self {
            AnalyticShape::Sphere(s) => s.bounds(),
            AnalyticShape::Quad(q) => q.bounds(),
            AnalyticShape::Disk(d) => d.bounds(),
            AnalyticShape::Cylinder(c) => c.bounds(),
        }
    }
}

/// A user geometry's data: the shape, its object index and the scene's
/// alpha cutouts when its material has a mask.
#[derive(Debug)]
pub(super) struct AnalyticGeometry {
    pub(super) shape: AnalyticShape,
    pub(super) object: u32,
    pub(super) cutouts: Option<Arc<Cutouts>>,
}

impl AnalyticGeometry {
    /// `(t, u, v)` of the nearest hit on the surface; with `MASKED`, holes
    /// are skipped (the callbacks of unmasked shapes are the `false`
    /// instantiation, which never reads `cutouts`).
    #[inline]
    fn intersect<const MASKED: bool>(&self, ray: &Ray, t_max: f32) -> Option<(f32, f32, f32)> {
        match (&self.cutouts, &self.shape) {
            (Some(c), AnalyticShape::Sphere(s)) if MASKED => {
                c.sphere(self.object, s, ray, t_max).map(|t| (t, 0.0, 0.0))
            }
            (Some(c), AnalyticShape::Quad(q)) if MASKED => c.quad(self.object, q, ray, t_max),
            (Some(c), AnalyticShape::Disk(d)) if MASKED => c.disk(self.object, d, ray, t_max),
            (Some(c), AnalyticShape::Cylinder(cyl)) if MASKED => {
                c.cylinder(self.object, cyl, ray, t_max).map(|t| (t, 0.0, 0.0))
            }
            _ => self.shape.intersect(ray, t_max),
        }
    }
}

/// `RTCBoundsFunction`: the shape's box, widened by a few ulps of its
/// magnitude so rounding in the corner sums cannot cull a hit on the boundary.
pub(super) unsafe extern "C" fn analytic_bounds(args: *const sys::RTCBoundsFunctionArguments) {
    // SAFETY: Embree passes valid arguments; `geometryUserPtr` is the
    // `AnalyticGeometry` kept alive by the scene; `bounds_o` is writable.
    let (geometry, out) = unsafe {
        let args = &*args;
        (&*(args.geometryUserPtr as *const AnalyticGeometry), &mut *args.bounds_o)
    };
    let b = geometry.shape.bounds();
    let pad = (b.min.abs().max(b.max.abs())) * (4.0 * f32::EPSILON) + Vec3A::splat(f32::MIN_POSITIVE);
    let (lo, hi) = (b.min - pad, b.max + pad);
    *out = sys::RTCBounds {
        lower_x: lo.x,
        lower_y: lo.y,
        lower_z: lo.z,
        align0: 0.0,
        upper_x: hi.x,
        upper_y: hi.y,
        upper_z: hi.z,
        align1: 0.0,
    };
}

/// Reads ray `i` of an `RTCRayN` with `n` lanes (structure of arrays:
/// field `k` of lane `i` is float `k·n + i`): `(ray, tnear, tfar)`.
///
/// # Safety
/// `base` must point to an `RTCRayN` with at least `n` lanes and `i < n`.
#[inline]
unsafe fn read_ray_n(base: *const f32, n: usize, i: usize) -> (Ray, f32, f32) {
    // SAFETY: per the function contract, indices k·n + i for k ≤ 8 are in bounds.
    unsafe {
        let f = |k: usize| *base.add(k * n + i);
        (
            Ray::new(Vec3A::new(f(0), f(1), f(2)), Vec3A::new(f(4), f(5), f(6))),
            f(3),
            f(8),
        )
    }
}

/// Calls `lane(n, i)` for each of Embree's `n` lanes. `rtcIntersect1` and
/// `rtcOccluded1` call with one lane (`N = 1`): that case is its own copy
/// of the lane's code, with the structure-of-arrays index arithmetic
/// folded away.
#[inline(always)]
fn each_lane(n: usize, mut lane: impl FnMut(usize, usize)) {
    if n == 1 {
        lane(1, 0);
    } else {
        for i in 0..n {
            lane(n, i);
        }
    }
}

/// The shape and ray `(ray, tnear, tfar)` of lane `i` of `n`, or `None`
/// when the lane is not valid.
///
/// # Safety
/// `valid` has `n` entries, `user` is a live `AnalyticGeometry`, `base`
/// points to an `RTCRayN` of `n` lanes, and `i < n`.
#[inline(always)]
unsafe fn lane_ray<'a>(
    valid: *const i32,
    user: *const c_void,
    base: *const f32,
    n: usize,
    i: usize,
) -> Option<(&'a AnalyticGeometry, Ray, f32, f32)> {
    // SAFETY: per the function contract.
    unsafe {
        if *valid.add(i) == 0 {
            return None;
        }
        let (ray, tnear, tfar) = read_ray_n(base, n, i);
        Some((&*(user as *const AnalyticGeometry), ray, tnear, tfar))
    }
}

/// `RTCIntersectFunctionN` of the analytic shapes.
pub(super) unsafe extern "C" fn analytic_intersect<const MASKED: bool>(
    args: *const sys::RTCIntersectFunctionNArguments,
) {
    // SAFETY: Embree passes valid arguments: `valid` has `N` entries,
    // `rayhit` is an RTCRayHitN with `N` lanes (ray: floats 0..12N, hit:
    // from float 12N), and `geometryUserPtr` is our live `AnalyticGeometry`.
    unsafe {
        let args = &*args;
        each_lane(args.N as usize, |n, i| intersect_lane::<MASKED>(args, n, i));
    }
}

/// Lane `i` of [`analytic_intersect`]'s `n` lanes.
///
/// # Safety
/// `args` as Embree passes them to an intersect function of `n` lanes, `i < n`.
#[inline(always)]
unsafe fn intersect_lane<const MASKED: bool>(args: &sys::RTCIntersectFunctionNArguments, n: usize, i: usize) {
    // SAFETY: per the function contract (see `analytic_intersect`).
    unsafe {
        let base = args.rayhit as *mut f32;
        let Some((shape, ray, tnear, tfar)) = lane_ray(args.valid, args.geometryUserPtr, base, n, i) else {
            return;
        };
        let Some((t, u, v)) = shape.intersect::<MASKED>(&ray, tfar) else {
            return;
        };
        if t < tnear {
            return;
        }
        *base.add(8 * n + i) = t;
        let hit = base.add(12 * n);
        // Geometric normal is not used by caustic (the scene recomputes it).
        *hit.add(i) = 0.0;
        *hit.add(n + i) = 0.0;
        *hit.add(2 * n + i) = 0.0;
        *hit.add(3 * n + i) = u;
        *hit.add(4 * n + i) = v;
        let ids = hit as *mut u32;
        *ids.add(5 * n + i) = args.primID;
        *ids.add(6 * n + i) = args.geomID;
        // Analytic shapes live only in the TLAS: no enclosing instance.
        *ids.add(7 * n + i) = sys::RTC_INVALID_GEOMETRY_ID;
    }
}

/// `RTCOccludedFunctionN` of the analytic shapes: tfar = −inf on a hit.
pub(super) unsafe extern "C" fn analytic_occluded<const MASKED: bool>(args: *const sys::RTCOccludedFunctionNArguments) {
    // SAFETY: as in `analytic_intersect`, with `ray` an RTCRayN of `N` lanes.
    unsafe {
        let args = &*args;
        each_lane(args.N as usize, |n, i| occluded_lane::<MASKED>(args, n, i));
    }
}

/// Lane `i` of [`analytic_occluded`]'s `n` lanes.
///
/// # Safety
/// `args` as Embree passes them to an occluded function of `n` lanes, `i < n`.
#[inline(always)]
unsafe fn occluded_lane<const MASKED: bool>(args: &sys::RTCOccludedFunctionNArguments, n: usize, i: usize) {
    // SAFETY: per the function contract (see `analytic_occluded`).
    unsafe {
        let base = args.ray as *mut f32;
        let Some((shape, ray, tnear, tfar)) = lane_ray(args.valid, args.geometryUserPtr, base, n, i) else {
            return;
        };
        if let Some((t, _, _)) = shape.intersect::<MASKED>(&ray, tfar) {
            if t >= tnear {
                *base.add(8 * n + i) = f32::NEG_INFINITY;
            }
        }
    }
}

/// `RTCFilterFunctionN` of triangle geometries whose instances may have an
/// alpha mask: rejects the hits that fall in a hole (for closest-hit and
/// any-hit queries alike). The object is the hit's `instID[0]` (so one
/// BLAS shared by masked and unmasked objects works), or its `geomID` for a
/// mesh attached straight to the top level.
pub(super) unsafe extern "C" fn cutout_filter(args: *const sys::RTCFilterFunctionNArguments) {
    // SAFETY: Embree passes valid arguments: `valid` has `N` entries, `hit`
    // is an RTCHitN of `N` lanes (u at float 3N, v at 4N, primID at 5N,
    // geomID at 6N, instID[0] at 7N), and `geometryUserPtr` is the `Cutouts` the BLAS
    // geometry keeps alive.
    unsafe {
        let args = &*args;
        let cutouts = &*(args.geometryUserPtr as *const Cutouts);
        let n = args.N as usize;
        let hit = args.hit as *const f32;
        let ids = hit as *const u32;
        for i in 0..n {
            if *args.valid.add(i) == 0 {
                continue;
            }
            let (u, v) = (*hit.add(3 * n + i), *hit.add(4 * n + i));
            let (prim, inst) = (*ids.add(5 * n + i), *ids.add(7 * n + i));
            let object = if inst != sys::RTC_INVALID_GEOMETRY_ID {
                inst
            } else {
                *ids.add(6 * n + i)
            };
            if !cutouts.keeps_triangle(object, prim, u, v) {
                *args.valid.add(i) = 0;
            }
        }
    }
}
