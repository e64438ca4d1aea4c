//! Building Embree scenes: geometries (triangle meshes, instances, analytic
//! user geometries) with what Embree reads from them kept alive, attached to
//! scenes that are then committed.

use super::analytic::{analytic_bounds, analytic_intersect, analytic_occluded, cutout_filter, AnalyticGeometry};
use super::device::{Device, DeviceInner};
use super::sys;
use crate::accel::AccelError;
use crate::math::{Affine3A, Vec3};
use crate::scene::{Cutouts, Mesh};
use std::ffi::c_void;
use std::sync::Arc;

/// Something an Embree object reads through a raw pointer, kept alive by the
/// object that uses it (shared buffers, user data, instanced scenes).
enum KeepAlive {
    /// A mesh whose index buffer is shared with Embree.
    Mesh(#[allow(dead_code)] Arc<Mesh>),
    /// User data of an analytic-shape geometry.
    Shape(#[allow(dead_code)] Arc<AnalyticGeometry>),
    /// User data of a triangle geometry's alpha-cutout filter.
    Cutouts(#[allow(dead_code)] Arc<Cutouts>),
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
    ///
    /// Triangles of exactly zero area (collinear corners, in f64) are left
    /// out of the build: robust traversal reports hits on some of them, and
    /// such a hit has no normal. Their indices point at one extra vertex of
    /// non-finite coordinates, which Embree's build skips (it drops every
    /// primitive with a non-finite vertex), so primitive IDs stay the mesh's
    /// triangle indices.
    ///
    /// With `to_world`, the vertices are placed in world space (a mesh that
    /// only one object uses, attached straight to the top level: no
    /// instance to traverse); barycentrics and primitive IDs are those of
    /// the object-space triangles, as an affine map keeps them. A triangle
    /// of zero area on either side is left out.
    ///
    /// With `cutouts`, hits are filtered through the objects' alpha masks
    /// (an intersection filter for both query kinds).
    pub fn triangles(
        device: &Device,
        mesh: &Arc<Mesh>,
        to_world: Option<&Affine3A>,
        quality: sys::RTCBuildQuality,
        cutouts: Option<&Arc<Cutouts>>,
    ) -> Result<Self, AccelError> {
        let name = &mesh.name;
        let vertex_count = mesh.positions.len();
        let tri_count = mesh.triangles.len();
        if u32::try_from(tri_count).is_err() || u32::try_from(vertex_count).is_err() {
            return Err(AccelError::Scene(format!(
                "mesh {name}: {tri_count} triangles / {vertex_count} vertices exceed Embree's 32-bit indices"
            )));
        }
        let world: Option<Vec<Vec3>> =
            to_world.map(|m| mesh.positions.iter().map(|&p| m.transform_point3(p)).collect());
        let mut degenerate = zero_area_triangles(mesh, &mesh.positions);
        if let Some(world) = &world {
            degenerate.extend(zero_area_triangles(mesh, world));
            degenerate.sort_unstable();
            degenerate.dedup();
        }
        let positions = world.as_deref().unwrap_or(&mesh.positions);
        // One extra vertex, never finite, for the zero-area triangles.
        let buffer_vertices = vertex_count + usize::from(!degenerate.is_empty());
        let mut geometry = Self::new(device, sys::RTC_GEOMETRY_TYPE_TRIANGLE)?;
        // SAFETY: live geometry; Embree allocates `buffer_vertices` items of
        // 12 bytes (plus its padding) and returns a pointer valid until release.
        let dst = unsafe {
            sys::rtcSetNewGeometryBuffer(
                geometry.raw,
                sys::RTC_BUFFER_TYPE_VERTEX,
                0,
                sys::RTC_FORMAT_FLOAT3,
                12,
                buffer_vertices,
            )
        } as *mut f32;
        device.check(&format!("vertex buffer of mesh {name}"))?;
        if dst.is_null() {
            return Err(AccelError::Embree(format!("no vertex buffer for mesh {name}")));
        }
        // SAFETY: `dst` holds `3 * buffer_vertices` floats (checked non-null),
        // and `Vec3` is three packed f32 (glam's `#[repr(C)]` Vec3).
        unsafe {
            std::ptr::copy_nonoverlapping(positions.as_ptr() as *const f32, dst, 3 * vertex_count);
            if buffer_vertices > vertex_count {
                std::ptr::copy_nonoverlapping([f32::NAN; 3].as_ptr(), dst.add(3 * vertex_count), 3);
            }
        }
        if degenerate.is_empty() {
            // SAFETY: `[u32; 3]` items, stride 12, `tri_count` of them; the mesh
            // is kept alive (below) for as long as Embree can read the buffer.
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
            }
        } else {
            // SAFETY: live geometry; Embree allocates `tri_count` items of 12
            // bytes and returns a pointer valid until release.
            let dst = unsafe {
                sys::rtcSetNewGeometryBuffer(
                    geometry.raw,
                    sys::RTC_BUFFER_TYPE_INDEX,
                    0,
                    sys::RTC_FORMAT_UINT3,
                    12,
                    tri_count,
                )
            } as *mut [u32; 3];
            device.check(&format!("index buffer of mesh {name}"))?;
            if dst.is_null() {
                return Err(AccelError::Embree(format!("no index buffer for mesh {name}")));
            }
            let nan = vertex_count as u32;
            // SAFETY: `dst` holds `tri_count` items of `[u32; 3]` (checked
            // non-null); every index written is below `buffer_vertices`.
            unsafe {
                std::ptr::copy_nonoverlapping(mesh.triangles.as_ptr(), dst, tri_count);
                for &t in &degenerate {
                    *dst.add(t as usize) = [nan; 3];
                }
            }
        }
        // SAFETY: live geometry; the quality is one of the sys constants.
        unsafe { sys::rtcSetGeometryBuildQuality(geometry.raw, quality) };
        if let Some(cutouts) = cutouts {
            let user_ptr = Arc::as_ptr(cutouts) as *mut c_void;
            // SAFETY: live geometry; `user_ptr` stays valid because the Arc
            // is kept by this geometry and then by the scene it is attached
            // to; the filter only reads through it.
            unsafe {
                sys::rtcSetGeometryUserData(geometry.raw, user_ptr);
                sys::rtcSetGeometryIntersectFilterFunction(geometry.raw, Some(cutout_filter));
                sys::rtcSetGeometryOccludedFilterFunction(geometry.raw, Some(cutout_filter));
            }
            geometry.keep.push(KeepAlive::Cutouts(cutouts.clone()));
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
    pub(super) fn analytic(device: &Device, shape: AnalyticGeometry) -> Result<Self, AccelError> {
        let mut geometry = Self::new(device, sys::RTC_GEOMETRY_TYPE_USER)?;
        let masked = shape.cutouts.is_some();
        let shape = Arc::new(shape);
        let user_ptr = Arc::as_ptr(&shape) as *mut c_void;
        // SAFETY: live geometry; `user_ptr` stays valid because the Arc is
        // kept by this geometry and then by the scene it is attached to; the
        // callbacks only read through it.
        unsafe {
            sys::rtcSetGeometryUserPrimitiveCount(geometry.raw, 1);
            sys::rtcSetGeometryUserData(geometry.raw, user_ptr);
            sys::rtcSetGeometryBoundsFunction(geometry.raw, Some(analytic_bounds), std::ptr::null_mut());
            if masked {
                sys::rtcSetGeometryIntersectFunction(geometry.raw, Some(analytic_intersect::<true>));
                sys::rtcSetGeometryOccludedFunction(geometry.raw, Some(analytic_occluded::<true>));
            } else {
                sys::rtcSetGeometryIntersectFunction(geometry.raw, Some(analytic_intersect::<false>));
                sys::rtcSetGeometryOccludedFunction(geometry.raw, Some(analytic_occluded::<false>));
            }
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
pub(super) struct SceneHandle {
    pub(super) raw: sys::RTCScene,
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
// kept data is immutable (Arc<Mesh>, Arc<AnalyticGeometry>, Arc<Cutouts>,
// Arc<SceneHandle>).
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
    pub(super) inner: Arc<SceneHandle>,
}

/// Indices of the triangles of `mesh` whose area is exactly zero with the
/// vertex positions `positions`: corners collinear in f64 (products of f32
/// values are exact there).
fn zero_area_triangles(mesh: &Mesh, positions: &[Vec3]) -> Vec<u32> {
    mesh.triangles
        .iter()
        .enumerate()
        .filter(|(_, t)| {
            let [a, b, c] = t.map(|v| positions[v as usize].as_dvec3());
            (b - a).cross(c - a) == glam::DVec3::ZERO
        })
        .map(|(i, _)| i as u32)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
