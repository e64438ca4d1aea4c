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
//! [`Sphere::intersect`] and [`Quad::intersect`]: Embree then reports exactly
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
#![allow(unsafe_code)]

pub mod sys;

use super::{Accel, AccelError, AccelOptions, AccelStats, Hit};
use crate::math::{Aabb, Affine3A, Ray, Vec3A};
use crate::scene::{Mesh, Quad, Scene as CausticScene, Shape, Sphere};
use std::ffi::{c_char, c_void, CStr, CString};
use std::sync::atomic::{AtomicIsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// Where the linked Embree came from (set by `build.rs`): `pkg-config …`,
/// `EMBREE_DIR …` or `wheel embreex==4.4.0.post1 at DIR`.
pub fn source() -> &'static str {
    env!("CAUSTIC_EMBREE_SOURCE")
}

/// Version of the linked library as `major.minor.patch` (from
/// `rtcGetDeviceProperty(RTC_DEVICE_PROPERTY_VERSION)`, e.g. 40400 → 4.4.0),
/// or a description of why no device could be created.
pub fn version() -> String {
    match Device::new(None) {
        Ok(device) => version_string(device.version_number()),
        Err(e) => format!("unavailable ({e})"),
    }
}

/// 40400 → "4.4.0".
fn version_string(v: i64) -> String {
    format!("{}.{}.{}", v / 10000, (v / 100) % 100, v % 100)
}

fn error_name(code: sys::RTCError) -> &'static str {
    match code {
        sys::RTC_ERROR_NONE => "no error",
        sys::RTC_ERROR_UNKNOWN => "unknown error",
        sys::RTC_ERROR_INVALID_ARGUMENT => "invalid argument",
        sys::RTC_ERROR_INVALID_OPERATION => "invalid operation",
        sys::RTC_ERROR_OUT_OF_MEMORY => "out of memory",
        sys::RTC_ERROR_UNSUPPORTED_CPU => "unsupported CPU",
        sys::RTC_ERROR_CANCELLED => "cancelled",
        _ => "unrecognised error code",
    }
}

/// State the device's callbacks write into. Boxed inside [`DeviceInner`], so
/// its address is stable for as long as the device exists.
#[derive(Default)]
struct DeviceShared {
    /// Messages from the error callback not yet reported.
    errors: Mutex<Vec<String>>,
    /// Bytes currently allocated by Embree for this device (memory monitor).
    bytes: AtomicIsize,
    /// High-water mark of `bytes`.
    peak: AtomicIsize,
}

/// `RTCErrorFunction`: queues the message; [`Device::check`] turns it into an
/// [`AccelError::Embree`] at the next check point.
unsafe extern "C" fn on_error(user_ptr: *mut c_void, code: sys::RTCError, message: *const c_char) {
    // SAFETY: `user_ptr` is the `DeviceShared` registered in `Device::new`; it
    // is boxed and outlives the device handle (released first in `Drop`).
    let shared = unsafe { &*(user_ptr as *const DeviceShared) };
    let text = if message.is_null() {
        String::new()
    } else {
        // SAFETY: Embree passes a NUL-terminated string valid for this call.
        unsafe { CStr::from_ptr(message) }.to_string_lossy().into_owned()
    };
    let entry = format!("{} ({})", text.trim(), error_name(code));
    if let Ok(mut errors) = shared.errors.lock() {
        errors.push(entry);
    }
}

/// `RTCMemoryMonitorFunction`: counts the device's bytes; never refuses.
unsafe extern "C" fn on_memory(user_ptr: *mut c_void, bytes: isize, _post: bool) -> bool {
    // SAFETY: as in `on_error`, `user_ptr` is the live boxed `DeviceShared`.
    let shared = unsafe { &*(user_ptr as *const DeviceShared) };
    let now = shared.bytes.fetch_add(bytes, Ordering::Relaxed) + bytes;
    shared.peak.fetch_max(now, Ordering::Relaxed);
    true
}

/// Owns the `RTCDevice` handle and its callback state.
struct DeviceInner {
    raw: sys::RTCDevice,
    shared: Box<DeviceShared>,
}

impl Drop for DeviceInner {
    fn drop(&mut self) {
        // SAFETY: `raw` came from `rtcNewDevice` and is released exactly once;
        // every scene and geometry holds an `Arc<DeviceInner>`, so none outlives it.
        unsafe { sys::rtcReleaseDevice(self.raw) };
    }
}

// SAFETY: Embree devices may be used from any thread (its API is thread-safe
// for distinct objects, and the callbacks' shared state is a Mutex/atomics).
unsafe impl Send for DeviceInner {}
// SAFETY: see `Send`; `&DeviceInner` only exposes thread-safe calls.
unsafe impl Sync for DeviceInner {}

impl DeviceInner {
    /// Reads the device error and the queued callback messages.
    fn check(&self, what: &str) -> Result<(), AccelError> {
        // SAFETY: `raw` is a live device.
        let code = unsafe { sys::rtcGetDeviceError(self.raw) };
        let messages: Vec<String> = self
            .shared
            .errors
            .lock()
            .map(|mut e| std::mem::take(&mut *e))
            .unwrap_or_default();
        if code == sys::RTC_ERROR_NONE && messages.is_empty() {
            return Ok(());
        }
        let detail = if messages.is_empty() {
            error_name(code).to_string()
        } else {
            messages.join("; ")
        };
        Err(AccelError::Embree(format!("{what}: {detail}")))
    }
}

/// An Embree device (`RTCDevice`): owns the handle, releases it when the last
/// scene or geometry made from it is gone. Not `Clone`.
pub struct Device {
    inner: Arc<DeviceInner>,
}

impl Device {
    /// Creates a device. `config` is Embree's configuration string (e.g.
    /// `"threads=2"`); `None` takes the defaults. An invalid configuration is
    /// an [`AccelError::Embree`].
    pub fn new(config: Option<&str>) -> Result<Self, AccelError> {
        let config_c = match config {
            Some(c) => Some(
                CString::new(c).map_err(|_| AccelError::Embree(format!("device config {c:?} contains a NUL byte")))?,
            ),
            None => None,
        };
        let ptr = config_c.as_ref().map_or(std::ptr::null(), |c| c.as_ptr());
        // SAFETY: `ptr` is null or a NUL-terminated string alive for the call.
        let raw = unsafe { sys::rtcNewDevice(ptr) };
        if raw.is_null() {
            // SAFETY: with a null device, rtcGetDeviceError reads the
            // thread-local error of the failed rtcNewDevice.
            let code = unsafe { sys::rtcGetDeviceError(std::ptr::null_mut()) };
            return Err(AccelError::Embree(format!(
                "rtcNewDevice({:?}) failed: {}",
                config.unwrap_or(""),
                error_name(code)
            )));
        }
        let shared = Box::new(DeviceShared::default());
        let user_ptr = &*shared as *const DeviceShared as *mut c_void;
        // SAFETY: `raw` is live; `user_ptr` points into a Box that lives in
        // `DeviceInner` until after `rtcReleaseDevice`, so the callbacks never
        // see a dangling pointer.
        unsafe {
            sys::rtcSetDeviceErrorFunction(raw, Some(on_error), user_ptr);
            sys::rtcSetDeviceMemoryMonitorFunction(raw, Some(on_memory), user_ptr);
        }
        let device = Self {
            inner: Arc::new(DeviceInner { raw, shared }),
        };
        device.check("rtcNewDevice")?;
        Ok(device)
    }

    /// `RTC_DEVICE_PROPERTY_VERSION` (e.g. 40400).
    pub fn version_number(&self) -> i64 {
        // SAFETY: live device; reading a property has no other precondition.
        unsafe { sys::rtcGetDeviceProperty(self.inner.raw, sys::RTC_DEVICE_PROPERTY_VERSION) as i64 }
    }

    /// Turns a pending device error (code or callback message) into an error
    /// naming `what` was being done.
    pub fn check(&self, what: &str) -> Result<(), AccelError> {
        self.inner.check(what)
    }

    /// Bytes Embree currently holds for this device, and the peak
    /// (from the memory-monitor callback).
    pub fn memory_bytes(&self) -> (usize, usize) {
        let now = self.inner.shared.bytes.load(Ordering::Relaxed).max(0) as usize;
        let peak = self.inner.shared.peak.load(Ordering::Relaxed).max(0) as usize;
        (now, peak)
    }
}

/// Something an Embree object reads through a raw pointer, kept alive by the
/// object that uses it (shared buffers, user data, instanced scenes).
enum KeepAlive {
    /// A mesh whose index buffer is shared with Embree.
    Mesh(#[allow(dead_code)] Arc<Mesh>),
    /// User data of an analytic-shape geometry.
    Shape(#[allow(dead_code)] Arc<AnalyticShape>),
    /// A BLAS referenced by an instance.
    Scene(#[allow(dead_code)] Arc<SceneHandle>),
}

/// An Embree geometry (`RTCGeometry`) not yet attached to a scene. Owns its
/// handle (released in `Drop`) and whatever memory Embree reads from it.
pub struct Geometry {
    raw: sys::RTCGeometry,
    device: Arc<DeviceInner>,
    keep: Vec<KeepAlive>,
}

impl Drop for Geometry {
    fn drop(&mut self) {
        // SAFETY: `raw` came from rtcNewGeometry and is released once. A scene
        // it was attached to holds its own reference (and took `keep`).
        unsafe { sys::rtcReleaseGeometry(self.raw) };
    }
}

impl Geometry {
    fn new(device: &Device, kind: sys::RTCGeometryType) -> Result<Self, AccelError> {
        // SAFETY: live device; `kind` is one of the sys constants.
        let raw = unsafe { sys::rtcNewGeometry(device.inner.raw, kind) };
        device.check("rtcNewGeometry")?;
        if raw.is_null() {
            return Err(AccelError::Embree("rtcNewGeometry returned no geometry".into()));
        }
        Ok(Self {
            raw,
            device: device.inner.clone(),
            keep: Vec::new(),
        })
    }

    /// A triangle geometry over `mesh` (object space).
    ///
    /// Vertices are copied into a buffer Embree allocates
    /// (`rtcSetNewGeometryBuffer`): Embree loads every vertex with a 16-byte
    /// SSE load, so the last one of a tightly packed `Vec<Vec3>` would be read
    /// 4 bytes past the allocation. The copy costs 12 bytes per vertex (the
    /// dragon: 5.2 MB, a few ms) against a BVH several times that size.
    /// Indices need no padding and are shared in place; the mesh is kept
    /// alive by the geometry and then by the scene it is attached to.
    pub fn triangles(device: &Device, mesh: &Arc<Mesh>, quality: sys::RTCBuildQuality) -> Result<Self, AccelError> {
        let name = &mesh.name;
        let vertex_count = mesh.positions.len();
        let tri_count = mesh.triangles.len();
        if u32::try_from(tri_count).is_err() || u32::try_from(vertex_count).is_err() {
            return Err(AccelError::Scene(format!(
                "mesh {name}: {tri_count} triangles / {vertex_count} vertices exceed Embree's 32-bit indices"
            )));
        }
        let mut geometry = Self::new(device, sys::RTC_GEOMETRY_TYPE_TRIANGLE)?;
        // SAFETY: live geometry; Embree allocates `vertex_count` items of 12
        // bytes (plus its padding) and returns a pointer valid until release.
        let dst = unsafe {
            sys::rtcSetNewGeometryBuffer(
                geometry.raw,
                sys::RTC_BUFFER_TYPE_VERTEX,
                0,
                sys::RTC_FORMAT_FLOAT3,
                12,
                vertex_count,
            )
        } as *mut f32;
        device.check(&format!("vertex buffer of mesh {name}"))?;
        if dst.is_null() {
            return Err(AccelError::Embree(format!("no vertex buffer for mesh {name}")));
        }
        // SAFETY: `dst` holds `3 * vertex_count` floats (checked non-null),
        // and `Vec3` is three packed f32 (glam's `#[repr(C)]` Vec3).
        unsafe {
            std::ptr::copy_nonoverlapping(mesh.positions.as_ptr() as *const f32, dst, 3 * vertex_count);
        }
        // SAFETY: `[u32; 3]` items, stride 12, `tri_count` of them; the mesh is
        // kept alive (below) for as long as Embree can read the buffer.
        unsafe {
            sys::rtcSetSharedGeometryBuffer(
                geometry.raw,
                sys::RTC_BUFFER_TYPE_INDEX,
                0,
                sys::RTC_FORMAT_UINT3,
                mesh.triangles.as_ptr() as *const c_void,
                0,
                12,
                tri_count,
            );
            sys::rtcSetGeometryBuildQuality(geometry.raw, quality);
        }
        geometry.keep.push(KeepAlive::Mesh(mesh.clone()));
        geometry.commit(&format!("triangle geometry of mesh {name}"))?;
        Ok(geometry)
    }

    /// An instance of the committed `blas` placed by `to_world`.
    pub fn instance(device: &Device, blas: &CommittedScene, to_world: &Affine3A) -> Result<Self, AccelError> {
        let mut geometry = Self::new(device, sys::RTC_GEOMETRY_TYPE_INSTANCE)?;
        let m = to_world.matrix3;
        let t = to_world.translation;
        // RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR: the three linear columns, then the translation.
        let xfm: [f32; 12] = [
            m.x_axis.x, m.x_axis.y, m.x_axis.z, m.y_axis.x, m.y_axis.y, m.y_axis.z, m.z_axis.x, m.z_axis.y, m.z_axis.z,
            t.x, t.y, t.z,
        ];
        // SAFETY: live handles; Embree copies the 12 floats during the call.
        unsafe {
            sys::rtcSetGeometryInstancedScene(geometry.raw, blas.inner.raw);
            sys::rtcSetGeometryTransform(
                geometry.raw,
                0,
                sys::RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR,
                xfm.as_ptr() as *const c_void,
            );
        }
        geometry.keep.push(KeepAlive::Scene(blas.inner.clone()));
        geometry.commit("instance geometry")?;
        Ok(geometry)
    }

    /// A user geometry with one primitive: `shape`, intersected by the
    /// scene's own analytic code.
    fn analytic(device: &Device, shape: AnalyticShape) -> Result<Self, AccelError> {
        let mut geometry = Self::new(device, sys::RTC_GEOMETRY_TYPE_USER)?;
        let shape = Arc::new(shape);
        let user_ptr = Arc::as_ptr(&shape) as *mut c_void;
        // SAFETY: live geometry; `user_ptr` stays valid because the Arc is
        // kept by this geometry and then by the scene it is attached to; the
        // callbacks only read through it.
        unsafe {
            sys::rtcSetGeometryUserPrimitiveCount(geometry.raw, 1);
            sys::rtcSetGeometryUserData(geometry.raw, user_ptr);
            sys::rtcSetGeometryBoundsFunction(geometry.raw, Some(analytic_bounds), std::ptr::null_mut());
            sys::rtcSetGeometryIntersectFunction(geometry.raw, Some(analytic_intersect));
            sys::rtcSetGeometryOccludedFunction(geometry.raw, Some(analytic_occluded));
        }
        geometry.keep.push(KeepAlive::Shape(shape));
        geometry.commit("user geometry")?;
        Ok(geometry)
    }

    /// Commits the geometry and reports any error Embree raised while it was set up.
    pub fn commit(&mut self, what: &str) -> Result<(), AccelError> {
        // SAFETY: live geometry.
        unsafe { sys::rtcCommitGeometry(self.raw) };
        self.device.check(what)
    }
}

/// Owns an `RTCScene` and what its geometries read.
struct SceneHandle {
    raw: sys::RTCScene,
    keep: Vec<KeepAlive>,
    _device: Arc<DeviceInner>,
}

impl Drop for SceneHandle {
    fn drop(&mut self) {
        // SAFETY: `raw` came from rtcNewScene and is released once, before
        // `keep` (field drop runs after this body), so Embree never reads a
        // freed buffer.
        unsafe { sys::rtcReleaseScene(self.raw) };
    }
}

// SAFETY: Embree scenes are thread-safe for queries after commit, and the
// kept data is immutable (Arc<Mesh>, Arc<AnalyticShape>, Arc<SceneHandle>).
unsafe impl Send for SceneHandle {}
// SAFETY: see `Send`; only committed scenes (CommittedScene) are shared.
unsafe impl Sync for SceneHandle {}

/// A scene under construction: geometries are attached, then [`Scene::commit`].
pub struct Scene {
    inner: SceneHandle,
    device: Device,
}

impl Scene {
    /// A new empty scene with the given build quality and robust flag.
    pub fn new(device: &Device, quality: sys::RTCBuildQuality, robust: bool) -> Result<Self, AccelError> {
        // SAFETY: live device.
        let raw = unsafe { sys::rtcNewScene(device.inner.raw) };
        device.check("rtcNewScene")?;
        if raw.is_null() {
            return Err(AccelError::Embree("rtcNewScene returned no scene".into()));
        }
        let scene = Self {
            inner: SceneHandle {
                raw,
                keep: Vec::new(),
                _device: device.inner.clone(),
            },
            device: Device {
                inner: device.inner.clone(),
            },
        };
        let flags = if robust {
            sys::RTC_SCENE_FLAG_ROBUST
        } else {
            sys::RTC_SCENE_FLAG_NONE
        };
        // SAFETY: live scene; valid flag and quality values.
        unsafe {
            sys::rtcSetSceneFlags(raw, flags);
            sys::rtcSetSceneBuildQuality(raw, quality);
        }
        scene.device.check("scene settings")?;
        Ok(scene)
    }

    /// Attaches `geometry` under the ID `id`; the scene takes over what the
    /// geometry needs kept alive, and our handle on it is released.
    pub fn attach(&mut self, mut geometry: Geometry, id: u32) -> Result<(), AccelError> {
        // SAFETY: both handles live and from the same device.
        unsafe { sys::rtcAttachGeometryByID(self.inner.raw, geometry.raw, id) };
        self.inner.keep.append(&mut geometry.keep);
        drop(geometry);
        self.device.check(&format!("attaching geometry {id}"))
    }

    /// Builds the acceleration structure; only a committed scene is queried.
    pub fn commit(self) -> Result<CommittedScene, AccelError> {
        // SAFETY: live scene; every attached geometry was committed.
        unsafe { sys::rtcCommitScene(self.inner.raw) };
        self.device.check("rtcCommitScene")?;
        Ok(CommittedScene {
            inner: Arc::new(self.inner),
        })
    }
}

/// A committed (immutable, queryable) scene.
pub struct CommittedScene {
    inner: Arc<SceneHandle>,
}

impl CommittedScene {
    /// Closest hit with `0 < t < t_max` as Embree reports it: `(t, geomID,
    /// primID, instID[0], u, v)`.
    #[inline]
    fn intersect_raw(&self, ray: &Ray, t_max: f32) -> Option<sys::RTCRayHit> {
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
    fn intersect_packet(&self, rays: &[Ray], t_max: f32, out: &mut [Option<Hit>]) {
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
    fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
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

/// The [`Hit`] of an Embree hit record: a mesh hit is reported through its
/// instance (the TLAS geometry ID of the object), an analytic shape by its
/// own geometry ID (no enclosing instance, primitive 0).
#[inline]
fn hit_record(t: f32, geom_id: u32, prim_id: u32, inst_id: u32, u: f32, v: f32) -> Hit {
    let (instance, prim) = if inst_id != sys::RTC_INVALID_GEOMETRY_ID {
        (inst_id, prim_id)
    } else {
        (geom_id, 0)
    };
    Hit {
        t,
        instance,
        prim,
        u,
        v,
    }
}

/// An analytic shape in the TLAS (user geometry data).
#[derive(Clone, Copy, Debug)]
enum AnalyticShape {
    Sphere(Sphere),
    Quad(Quad),
}

impl AnalyticShape {
    /// `(t, u, v)` exactly as the other backends report it.
    #[inline]
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, f32, f32)> {
        match self {
            AnalyticShape::Sphere(s) => s.intersect(ray, t_max).map(|t| (t, 0.0, 0.0)),
            AnalyticShape::Quad(q) => q.intersect(ray, t_max),
        }
    }

    fn bounds(&self) -> Aabb {
        match self {
            AnalyticShape::Sphere(s) => s.bounds(),
            AnalyticShape::Quad(q) => q.bounds(),
        }
    }
}

/// `RTCBoundsFunction`: the shape's box, widened by a few ulps of its
/// magnitude so rounding in the corner sums cannot cull a hit on the boundary.
unsafe extern "C" fn analytic_bounds(args: *const sys::RTCBoundsFunctionArguments) {
    // SAFETY: Embree passes valid arguments; `geometryUserPtr` is the
    // `AnalyticShape` kept alive by the scene; `bounds_o` is writable.
    let (shape, out) = unsafe {
        let args = &*args;
        (&*(args.geometryUserPtr as *const AnalyticShape), &mut *args.bounds_o)
    };
    let b = shape.bounds();
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

/// `RTCIntersectFunctionN` of the analytic shapes.
unsafe extern "C" fn analytic_intersect(args: *const sys::RTCIntersectFunctionNArguments) {
    // SAFETY: Embree passes valid arguments: `valid` has `N` entries,
    // `rayhit` is an RTCRayHitN with `N` lanes (ray: floats 0..12N, hit:
    // from float 12N), and `geometryUserPtr` is our live `AnalyticShape`.
    unsafe {
        let args = &*args;
        let shape = &*(args.geometryUserPtr as *const AnalyticShape);
        let n = args.N as usize;
        let base = args.rayhit as *mut f32;
        for i in 0..n {
            if *args.valid.add(i) == 0 {
                continue;
            }
            let (ray, tnear, tfar) = read_ray_n(base, n, i);
            let Some((t, u, v)) = shape.intersect(&ray, tfar) else {
                continue;
            };
            if t < tnear {
                continue;
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
}

/// `RTCOccludedFunctionN` of the analytic shapes: tfar = −inf on a hit.
unsafe extern "C" fn analytic_occluded(args: *const sys::RTCOccludedFunctionNArguments) {
    // SAFETY: as in `analytic_intersect`, with `ray` an RTCRayN of `N` lanes.
    unsafe {
        let args = &*args;
        let shape = &*(args.geometryUserPtr as *const AnalyticShape);
        let n = args.N as usize;
        let base = args.ray as *mut f32;
        for i in 0..n {
            if *args.valid.add(i) == 0 {
                continue;
            }
            let (ray, tnear, tfar) = read_ray_n(base, n, i);
            if let Some((t, _, _)) = shape.intersect(&ray, tfar) {
                if t >= tnear {
                    *base.add(8 * n + i) = f32::NEG_INFINITY;
                }
            }
        }
    }
}

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
    fn version_is_embree_4() {
        let device = Device::new(None).unwrap();
        let v = device.version_number();
        assert!((40000..50000).contains(&v), "{v}");
        assert!(version().starts_with("4."), "{}", version());
        assert!(!source().is_empty());
    }

    #[test]
    fn callback_errors_surface_as_rust_errors() {
        let device = Device::new(None).unwrap();
        let geometry = Geometry::new(&device, sys::RTC_GEOMETRY_TYPE_TRIANGLE).unwrap();
        let xfm = [0.0f32; 12];
        // A transform on a triangle geometry is an invalid operation: Embree
        // reports it through the error callback.
        // SAFETY: live geometry, 12 readable floats.
        unsafe {
            sys::rtcSetGeometryTransform(
                geometry.raw,
                0,
                sys::RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR,
                xfm.as_ptr() as *const c_void,
            )
        };
        let err = device.check("setting a transform").unwrap_err();
        let AccelError::Embree(message) = &err else {
            panic!("{err}")
        };
        assert!(message.starts_with("setting a transform: "), "{message}");
        assert!(message.len() > "setting a transform: ".len() + 5, "{message}");
        // Reported once: the device is clean afterwards.
        device.check("after").unwrap();
    }

    #[test]
    fn bad_device_config_is_an_error() {
        let err = Device::new(Some("verbose=abc"))
            .err()
            .expect("Embree rejects verbose=abc");
        assert!(err.to_string().contains("verbose=abc"), "{err}");
        assert!(Device::new(Some("threads=1")).is_ok());
    }

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
            Geometry::triangles(&device, &mesh, sys::RTC_BUILD_QUALITY_HIGH).unwrap(),
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

    #[test]
    fn unknown_quality_is_rejected() {
        assert!(build_quality("ultra").is_err());
        assert_eq!(build_quality("low").unwrap(), sys::RTC_BUILD_QUALITY_LOW);
    }
}
