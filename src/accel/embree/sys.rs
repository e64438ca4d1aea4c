//! Hand-written bindings for the part of Intel Embree 4's C API (`rtcore.h`)
//! that caustic uses. No bindgen: a fresh machine has no libclang, and the
//! headers are not needed at all. Values and layouts follow
//! `embree4/rtcore_{common,device,buffer,geometry,scene,ray}.h` of Embree 4.4;
//! the layout tests below pin them.
//!
//! The library is linked by `build.rs` (`cargo:rustc-link-lib`), which is why
//! the `extern` block carries no `#[link]` attribute: the file name differs
//! between a system Embree (`libembree4.so`) and the wheel (a hashed SONAME).
#![allow(unsafe_code)]
#![allow(non_camel_case_types, non_snake_case, missing_docs)]

use std::ffi::{c_char, c_void};

/// Opaque device handle (`RTCDevice`).
pub type RTCDevice = *mut c_void;
/// Opaque scene handle (`RTCScene`).
pub type RTCScene = *mut c_void;
/// Opaque geometry handle (`RTCGeometry`).
pub type RTCGeometry = *mut c_void;

/// `RTC_INVALID_GEOMETRY_ID`: "no geometry / no instance".
pub const RTC_INVALID_GEOMETRY_ID: u32 = u32::MAX;

/// `enum RTCError`.
pub type RTCError = u32;
pub const RTC_ERROR_NONE: RTCError = 0;
pub const RTC_ERROR_UNKNOWN: RTCError = 1;
pub const RTC_ERROR_INVALID_ARGUMENT: RTCError = 2;
pub const RTC_ERROR_INVALID_OPERATION: RTCError = 3;
pub const RTC_ERROR_OUT_OF_MEMORY: RTCError = 4;
pub const RTC_ERROR_UNSUPPORTED_CPU: RTCError = 5;
pub const RTC_ERROR_CANCELLED: RTCError = 6;

/// `enum RTCDeviceProperty` (only the version is read).
pub type RTCDeviceProperty = u32;
pub const RTC_DEVICE_PROPERTY_VERSION: RTCDeviceProperty = 0;

/// `enum RTCFormat` (the few used).
pub type RTCFormat = u32;
pub const RTC_FORMAT_UINT3: RTCFormat = 0x5003;
pub const RTC_FORMAT_FLOAT3: RTCFormat = 0x9003;
pub const RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR: RTCFormat = 0x9234;

/// `enum RTCBuildQuality`.
pub type RTCBuildQuality = u32;
pub const RTC_BUILD_QUALITY_LOW: RTCBuildQuality = 0;
pub const RTC_BUILD_QUALITY_MEDIUM: RTCBuildQuality = 1;
pub const RTC_BUILD_QUALITY_HIGH: RTCBuildQuality = 2;

/// `enum RTCSceneFlags`.
pub type RTCSceneFlags = u32;
pub const RTC_SCENE_FLAG_NONE: RTCSceneFlags = 0;
pub const RTC_SCENE_FLAG_ROBUST: RTCSceneFlags = 1 << 2;

/// `enum RTCBufferType`.
pub type RTCBufferType = u32;
pub const RTC_BUFFER_TYPE_INDEX: RTCBufferType = 0;
pub const RTC_BUFFER_TYPE_VERTEX: RTCBufferType = 1;

/// `enum RTCGeometryType` (the few used).
pub type RTCGeometryType = u32;
pub const RTC_GEOMETRY_TYPE_TRIANGLE: RTCGeometryType = 0;
pub const RTC_GEOMETRY_TYPE_USER: RTCGeometryType = 120;
pub const RTC_GEOMETRY_TYPE_INSTANCE: RTCGeometryType = 121;

/// `struct RTCRay` (16-byte aligned, 48 bytes).
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default)]
pub struct RTCRay {
    pub org_x: f32,
    pub org_y: f32,
    pub org_z: f32,
    pub tnear: f32,
    pub dir_x: f32,
    pub dir_y: f32,
    pub dir_z: f32,
    pub time: f32,
    pub tfar: f32,
    pub mask: u32,
    pub id: u32,
    pub flags: u32,
}

/// `struct RTCHit` with `RTC_MAX_INSTANCE_LEVEL_COUNT == 1`.
///
/// Embree ≥ 4.3 built with `EMBREE_GEOMETRY_INSTANCE_ARRAY` (the default, and
/// the embreex wheel: its own `.pxd` declares the field) appends
/// `instPrimID[1]`, which makes `RTCHit` 48 bytes and `RTCRayHit` 96 bytes,
/// not the 80 bytes of builds without instance arrays. Declaring the field
/// is safe for both: a library without it never touches those 4 bytes (plus
/// padding), while a library with it would write past an 80-byte struct.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default)]
pub struct RTCHit {
    pub Ng_x: f32,
    pub Ng_y: f32,
    pub Ng_z: f32,
    pub u: f32,
    pub v: f32,
    pub primID: u32,
    pub geomID: u32,
    pub instID: [u32; 1],
    pub instPrimID: [u32; 1],
}

/// `struct RTCRayHit`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct RTCRayHit {
    pub ray: RTCRay,
    pub hit: RTCHit,
}

/// `struct RTCBounds` (16-byte aligned).
/// Lanes of the packets caustic traces (`rtcIntersect16`).
pub const PACKET_SIZE: usize = 16;

/// `RTCRayHit16`: a ray packet and its hits in structure-of-arrays layout
/// (`RTCRay16` then `RTCHit16`, each field an array over the lanes), 64-byte
/// aligned as `rtcIntersect16` requires. `instPrimID` is present as in
/// [`RTCHit`] (see there).
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug)]
pub struct RTCRayHit16 {
    pub org_x: [f32; PACKET_SIZE],
    pub org_y: [f32; PACKET_SIZE],
    pub org_z: [f32; PACKET_SIZE],
    pub tnear: [f32; PACKET_SIZE],
    pub dir_x: [f32; PACKET_SIZE],
    pub dir_y: [f32; PACKET_SIZE],
    pub dir_z: [f32; PACKET_SIZE],
    pub time: [f32; PACKET_SIZE],
    pub tfar: [f32; PACKET_SIZE],
    pub mask: [u32; PACKET_SIZE],
    pub id: [u32; PACKET_SIZE],
    pub flags: [u32; PACKET_SIZE],
    pub Ng_x: [f32; PACKET_SIZE],
    pub Ng_y: [f32; PACKET_SIZE],
    pub Ng_z: [f32; PACKET_SIZE],
    pub u: [f32; PACKET_SIZE],
    pub v: [f32; PACKET_SIZE],
    pub primID: [u32; PACKET_SIZE],
    pub geomID: [u32; PACKET_SIZE],
    pub instID: [[u32; PACKET_SIZE]; 1],
    pub instPrimID: [[u32; PACKET_SIZE]; 1],
}

#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default)]
pub struct RTCBounds {
    pub lower_x: f32,
    pub lower_y: f32,
    pub lower_z: f32,
    pub align0: f32,
    pub upper_x: f32,
    pub upper_y: f32,
    pub upper_z: f32,
    pub align1: f32,
}

/// `struct RTCBoundsFunctionArguments`.
#[repr(C)]
pub struct RTCBoundsFunctionArguments {
    pub geometryUserPtr: *mut c_void,
    pub primID: u32,
    pub timeStep: u32,
    pub bounds_o: *mut RTCBounds,
}

/// `struct RTCIntersectFunctionNArguments`. `rayhit` points at an
/// `RTCRayHitN`: structure-of-arrays with `N` lanes (for `N == 1` the same
/// bytes as [`RTCRayHit`]); `context` is opaque here (never read).
#[repr(C)]
pub struct RTCIntersectFunctionNArguments {
    pub valid: *mut i32,
    pub geometryUserPtr: *mut c_void,
    pub primID: u32,
    pub context: *mut c_void,
    pub rayhit: *mut c_void,
    pub N: u32,
    pub geomID: u32,
}

/// `struct RTCOccludedFunctionNArguments` (`ray` is an `RTCRayN`).
#[repr(C)]
pub struct RTCOccludedFunctionNArguments {
    pub valid: *mut i32,
    pub geometryUserPtr: *mut c_void,
    pub primID: u32,
    pub context: *mut c_void,
    pub ray: *mut c_void,
    pub N: u32,
    pub geomID: u32,
}

/// `struct RTCFilterFunctionNArguments`: `ray` is an `RTCRayN` and `hit`
/// an `RTCHitN` of `N` lanes (structure of arrays); setting `valid[i]` to 0
/// rejects lane `i`'s hit.
#[repr(C)]
pub struct RTCFilterFunctionNArguments {
    pub valid: *mut i32,
    pub geometryUserPtr: *mut c_void,
    pub context: *mut c_void,
    pub ray: *mut c_void,
    pub hit: *mut c_void,
    pub N: u32,
}

/// `RTCFilterFunctionN`.
pub type RTCFilterFunctionN = Option<unsafe extern "C" fn(args: *const RTCFilterFunctionNArguments)>;

/// `RTCErrorFunction`.
pub type RTCErrorFunction = Option<unsafe extern "C" fn(user_ptr: *mut c_void, code: RTCError, message: *const c_char)>;
/// `RTCMemoryMonitorFunction`: `bytes > 0` allocates, `< 0` frees; return
/// false to make an allocation fail.
pub type RTCMemoryMonitorFunction =
    Option<unsafe extern "C" fn(user_ptr: *mut c_void, bytes: isize, post: bool) -> bool>;
/// `RTCBoundsFunction`.
pub type RTCBoundsFunction = Option<unsafe extern "C" fn(args: *const RTCBoundsFunctionArguments)>;
/// `RTCIntersectFunctionN`.
pub type RTCIntersectFunctionN = Option<unsafe extern "C" fn(args: *const RTCIntersectFunctionNArguments)>;
/// `RTCOccludedFunctionN`.
pub type RTCOccludedFunctionN = Option<unsafe extern "C" fn(args: *const RTCOccludedFunctionNArguments)>;

extern "C" {
    pub fn rtcNewDevice(config: *const c_char) -> RTCDevice;
    pub fn rtcReleaseDevice(device: RTCDevice);
    pub fn rtcGetDeviceProperty(device: RTCDevice, prop: RTCDeviceProperty) -> isize;
    pub fn rtcGetDeviceError(device: RTCDevice) -> RTCError;
    pub fn rtcSetDeviceErrorFunction(device: RTCDevice, error: RTCErrorFunction, user_ptr: *mut c_void);
    pub fn rtcSetDeviceMemoryMonitorFunction(
        device: RTCDevice,
        monitor: RTCMemoryMonitorFunction,
        user_ptr: *mut c_void,
    );

    pub fn rtcNewScene(device: RTCDevice) -> RTCScene;
    pub fn rtcReleaseScene(scene: RTCScene);
    pub fn rtcSetSceneFlags(scene: RTCScene, flags: RTCSceneFlags);
    pub fn rtcSetSceneBuildQuality(scene: RTCScene, quality: RTCBuildQuality);
    pub fn rtcAttachGeometryByID(scene: RTCScene, geometry: RTCGeometry, geom_id: u32);
    pub fn rtcCommitScene(scene: RTCScene);
    /// `args` is a nullable `RTCIntersectArguments*` (null: defaults).
    pub fn rtcIntersect1(scene: RTCScene, rayhit: *mut RTCRayHit, args: *mut c_void);
    /// `args` is a nullable `RTCOccludedArguments*` (null: defaults).
    pub fn rtcOccluded1(scene: RTCScene, ray: *mut RTCRay, args: *mut c_void);
    pub fn rtcIntersect16(valid: *const i32, scene: RTCScene, rayhit: *mut RTCRayHit16, args: *mut c_void);

    pub fn rtcNewGeometry(device: RTCDevice, kind: RTCGeometryType) -> RTCGeometry;
    pub fn rtcReleaseGeometry(geometry: RTCGeometry);
    pub fn rtcCommitGeometry(geometry: RTCGeometry);
    pub fn rtcSetGeometryBuildQuality(geometry: RTCGeometry, quality: RTCBuildQuality);
    pub fn rtcSetSharedGeometryBuffer(
        geometry: RTCGeometry,
        kind: RTCBufferType,
        slot: u32,
        format: RTCFormat,
        ptr: *const c_void,
        byte_offset: usize,
        byte_stride: usize,
        item_count: usize,
    );
    pub fn rtcSetNewGeometryBuffer(
        geometry: RTCGeometry,
        kind: RTCBufferType,
        slot: u32,
        format: RTCFormat,
        byte_stride: usize,
        item_count: usize,
    ) -> *mut c_void;
    pub fn rtcSetGeometryInstancedScene(geometry: RTCGeometry, scene: RTCScene);
    pub fn rtcSetGeometryTransform(geometry: RTCGeometry, time_step: u32, format: RTCFormat, xfm: *const c_void);
    pub fn rtcSetGeometryUserPrimitiveCount(geometry: RTCGeometry, count: u32);
    pub fn rtcSetGeometryUserData(geometry: RTCGeometry, ptr: *mut c_void);
    pub fn rtcSetGeometryBoundsFunction(geometry: RTCGeometry, bounds: RTCBoundsFunction, user_ptr: *mut c_void);
    pub fn rtcSetGeometryIntersectFunction(geometry: RTCGeometry, intersect: RTCIntersectFunctionN);
    pub fn rtcSetGeometryOccludedFunction(geometry: RTCGeometry, occluded: RTCOccludedFunctionN);
    pub fn rtcSetGeometryIntersectFilterFunction(geometry: RTCGeometry, filter: RTCFilterFunctionN);
    pub fn rtcSetGeometryOccludedFilterFunction(geometry: RTCGeometry, filter: RTCFilterFunctionN);
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::{align_of, offset_of, size_of};

    #[test]
    fn ray_layout_matches_rtcore_ray_h() {
        assert_eq!(size_of::<RTCRay>(), 48);
        assert_eq!(align_of::<RTCRay>(), 16);
        assert_eq!(offset_of!(RTCRay, tnear), 12);
        assert_eq!(offset_of!(RTCRay, dir_x), 16);
        assert_eq!(offset_of!(RTCRay, time), 28);
        assert_eq!(offset_of!(RTCRay, tfar), 32);
        assert_eq!(offset_of!(RTCRay, mask), 36);
        assert_eq!(offset_of!(RTCRay, id), 40);
        assert_eq!(offset_of!(RTCRay, flags), 44);
    }

    #[test]
    fn hit_layout_matches_rtcore_ray_h() {
        assert_eq!(align_of::<RTCHit>(), 16);
        assert_eq!(size_of::<RTCHit>(), 48);
        assert_eq!(offset_of!(RTCHit, u), 12);
        assert_eq!(offset_of!(RTCHit, v), 16);
        assert_eq!(offset_of!(RTCHit, primID), 20);
        assert_eq!(offset_of!(RTCHit, geomID), 24);
        assert_eq!(offset_of!(RTCHit, instID), 28);
        assert_eq!(offset_of!(RTCHit, instPrimID), 32);
        // RTCRayHitN with N = 1: the hit starts at float 12 (rtcore_ray.h's
        // RTCRayHitN_HitN), i.e. right after the 48-byte ray.
        assert_eq!(offset_of!(RTCRayHit, hit), 48);
        assert_eq!(size_of::<RTCRayHit>(), 96);
        assert_eq!(align_of::<RTCRayHit>(), 16);
    }

    #[test]
    fn packet_layout_matches_rtcore_ray_h() {
        // RTCRayHitN with N = 16: field k of the ray at float 16·k, the hit
        // from float 12·16 (RTCRayHitN_HitN), its field k at 16·(12 + k).
        assert_eq!(align_of::<RTCRayHit16>(), 64);
        assert_eq!(offset_of!(RTCRayHit16, tnear), 3 * 64);
        assert_eq!(offset_of!(RTCRayHit16, tfar), 8 * 64);
        assert_eq!(offset_of!(RTCRayHit16, flags), 11 * 64);
        assert_eq!(offset_of!(RTCRayHit16, Ng_x), 12 * 64);
        assert_eq!(offset_of!(RTCRayHit16, u), 15 * 64);
        assert_eq!(offset_of!(RTCRayHit16, primID), 17 * 64);
        assert_eq!(offset_of!(RTCRayHit16, geomID), 18 * 64);
        assert_eq!(offset_of!(RTCRayHit16, instID), 19 * 64);
        assert_eq!(size_of::<RTCRayHit16>(), 21 * 64);
    }

    #[test]
    fn callback_argument_layouts() {
        assert_eq!(size_of::<RTCBounds>(), 32);
        assert_eq!(offset_of!(RTCBounds, upper_x), 16);
        assert_eq!(offset_of!(RTCBoundsFunctionArguments, primID), 8);
        assert_eq!(offset_of!(RTCBoundsFunctionArguments, bounds_o), 16);
        assert_eq!(offset_of!(RTCIntersectFunctionNArguments, primID), 16);
        assert_eq!(offset_of!(RTCIntersectFunctionNArguments, context), 24);
        assert_eq!(offset_of!(RTCIntersectFunctionNArguments, rayhit), 32);
        assert_eq!(offset_of!(RTCIntersectFunctionNArguments, N), 40);
        assert_eq!(offset_of!(RTCIntersectFunctionNArguments, geomID), 44);
        assert_eq!(offset_of!(RTCOccludedFunctionNArguments, ray), 32);
        assert_eq!(offset_of!(RTCOccludedFunctionNArguments, N), 40);
    }
}
