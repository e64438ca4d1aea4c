//! Alpha cutouts as the accelerators see them: which hits fall in a hole of
//! their material's mask. Every backend asks the same [`Cutouts`] with the
//! same `(object, prim, u, v)` it reports, so Embree (through an
//! intersection filter), the KD-tree and the brute-force oracle agree on
//! every ray: camera, shadow and photon rays alike pass through holes.

use super::material::AlphaMask;
use super::{Scene, Shape};
use crate::geometry::{Cylinder, Disk, Mesh, Quad, Sphere};
use crate::math::{Ray, Vec2};
use std::sync::Arc;

/// The masks of a scene's objects.
#[derive(Debug)]
pub struct Cutouts {
    objects: Vec<Option<ObjectCutout>>,
}

#[derive(Debug)]
struct ObjectCutout {
    mask: AlphaMask,
    /// The mesh whose texture coordinates the mask reads (meshes only).
    mesh: Option<Arc<Mesh>>,
}

impl Cutouts {
    /// The cutouts of `scene`; `None` when no object's material has a mask.
    pub fn of(scene: &Scene) -> Option<Arc<Cutouts>> {
        let objects: Vec<Option<ObjectCutout>> = scene
            .objects
            .iter()
            .map(|o| {
                let mask = scene.materials[o.material as usize].textures.as_ref()?.alpha.clone()?;
                let mesh = match &o.shape {
                    Shape::Mesh { mesh, .. } => Some(scene.meshes[*mesh as usize].clone()),
                    _ => None,
                };
                Some(ObjectCutout { mask, mesh })
            })
            .collect();
        objects
            .iter()
            .any(Option::is_some)
            .then(|| Arc::new(Cutouts { objects }))
    }

    /// True when object `object` has a mask.
    #[inline]
    pub fn has(&self, object: u32) -> bool {
        matches!(self.objects.get(object as usize), Some(Some(_)))
    }

    /// True when the hit on triangle `prim` of mesh object `object` at
    /// barycentrics `(u, v)` is on the surface (not in a hole).
    #[inline]
    pub fn keeps_triangle(&self, object: u32, prim: u32, u: f32, v: f32) -> bool {
        let Some(Some(c)) = self.objects.get(object as usize) else {
            return true;
        };
        let Some(mesh) = &c.mesh else { return true };
        let [t0, t1, t2] = mesh.corner_uvs(prim as usize);
        c.mask.opaque_at(t0 * (1.0 - u - v) + t1 * u + t2 * v)
    }

    /// The quad's hit `(t, a, b)` if it is on the surface.
    #[inline]
    pub fn quad(&self, object: u32, q: &Quad, ray: &Ray, t_max: f32) -> Option<(f32, f32, f32)> {
        let hit = q.intersect(ray, t_max)?;
        match self.objects.get(object as usize) {
            Some(Some(c)) if !c.mask.opaque_at(Vec2::new(hit.1, hit.2)) => None,
            _ => Some(hit),
        }
    }

    /// The disk's hit `(t, x, y)` if it is on the surface (the mask read at
    /// the disk's texture coordinates `(r, φ / 2π)`).
    #[inline]
    pub fn disk(&self, object: u32, d: &Disk, ray: &Ray, t_max: f32) -> Option<(f32, f32, f32)> {
        let hit = d.intersect(ray, t_max)?;
        match self.objects.get(object as usize) {
            Some(Some(c)) if !c.mask.opaque_at(d.uv(hit.1, hit.2).0) => None,
            _ => Some(hit),
        }
    }

    /// The nearest root of the cylinder that is on the surface (the far
    /// one when the near one is in a hole), read at the re-projected point's
    /// texture coordinates as for the sphere.
    #[inline]
    pub fn cylinder(&self, object: u32, cyl: &Cylinder, ray: &Ray, t_max: f32) -> Option<f32> {
        match self.objects.get(object as usize) {
            Some(Some(c)) => cyl.intersect_where(ray, t_max, |t| c.mask.opaque_at(cyl.uv(cyl.surface(ray, t).0).0)),
            _ => cyl.intersect(ray, t_max),
        }
    }

    /// The nearest root of the sphere that is on the surface (the far one
    /// when the near one is in a hole). The texture coordinates are those
    /// of the re-projected point, as `Scene::surface_interaction` computes.
    #[inline]
    pub fn sphere(&self, object: u32, s: &Sphere, ray: &Ray, t_max: f32) -> Option<f32> {
        match self.objects.get(object as usize) {
            Some(Some(c)) => s.intersect_where(ray, t_max, |t| c.mask.opaque_at(s.uv(s.surface(ray, t).0).0)),
            _ => s.intersect(ray, t_max),
        }
    }
}
