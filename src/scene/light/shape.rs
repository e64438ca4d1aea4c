//! Area emission on a scene object: a sphere, a quad, a disk, a cylinder or
//! a triangle mesh whose material emits (Mitsuba's `area` emitter nested in a shape). The
//! surface emits from the side its geometric normal faces and keeps its
//! BSDF, so it reflects too.

use crate::geometry::{Cylinder, Disk, Mesh, Quad, Sphere};
use crate::math::distribution::Distribution1D;
use crate::math::sampling::{concentric_disk, uniform_cone};
use crate::math::{Frame, Ray, Transform, Vec2, Vec3A};
use crate::scene::{Scene, Shape};
use std::f32::consts::PI;
use std::sync::Arc;

/// A point on an emitting surface.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    /// Position.
    pub p: Vec3A,
    /// Unit normal of the emitting side.
    pub n: Vec3A,
    /// Texture coordinates (for a textured emission).
    pub uv: Vec2,
}

#[derive(Clone, Debug)]
enum Geometry {
    Sphere(Sphere),
    Quad(Quad),
    Disk(Disk),
    Cylinder(Cylinder),
    Mesh {
        mesh: Arc<Mesh>,
        transform: Transform,
        /// Triangles in proportion to their world-space area.
        triangles: Distribution1D,
    },
}

/// The sampling data of one emitting object.
#[derive(Clone, Debug)]
pub struct ShapeEmitter {
    /// Index of the object in `Scene::objects`.
    pub object: u32,
    /// Surface area in world space.
    pub area: f32,
    geometry: Geometry,
}

impl ShapeEmitter {
    /// The emitter of object `object` of `scene`; `None` when its area is
    /// zero or not finite.
    pub fn new(scene: &Scene, object: u32) -> Option<Self> {
        let (geometry, area) = match &scene.objects[object as usize].shape {
            Shape::Sphere(s) => (Geometry::Sphere(*s), 4.0 * PI * s.radius * s.radius),
            Shape::Quad(q) => (Geometry::Quad(*q), q.area()),
            Shape::Disk(d) => (Geometry::Disk(*d), d.area()),
            Shape::Cylinder(c) => (Geometry::Cylinder(*c), c.area()),
            Shape::Mesh { mesh, transform, .. } => {
                let mesh = scene.meshes[*mesh as usize].clone();
                let areas: Vec<f32> = (0..mesh.triangles.len())
                    .map(|i| {
                        let [p0, p1, p2] = mesh.corners(i).map(|p| transform.point(p));
                        0.5 * (p1 - p0).cross(p2 - p0).length()
                    })
                    .collect();
                let area = areas.iter().map(|&a| f64::from(a)).sum::<f64>() as f32;
                let triangles = Distribution1D::new(&areas);
                (
                    Geometry::Mesh {
                        mesh,
                        transform: *transform,
                        triangles,
                    },
                    area,
                )
            }
        };
        (area > 0.0 && area.is_finite()).then_some(Self { object, area, geometry })
    }

    /// A point uniformly distributed over the surface (density `1 / area`).
    pub fn sample_point(&self, u: Vec2, wants_uv: bool) -> SurfacePoint {
        match &self.geometry {
            Geometry::Sphere(s) => {
                let n = crate::math::sampling::uniform_sphere(u);
                let p = s.center + n * s.radius;
                let uv = if wants_uv { s.uv(p).0 } else { Vec2::ZERO };
                SurfacePoint { p, n, uv }
            }
            Geometry::Quad(q) => SurfacePoint {
                p: q.corner + q.u * u.x + q.v * u.y,
                n: q.normal,
                uv: u,
            },
            Geometry::Disk(d) => {
                // The concentric map is uniform on the unit disk, and the
                // affine map to the world scales every area by |a × b|:
                // uniform on the ellipse, density 1 / (π |a × b|).
                let local = concentric_disk(u);
                let (p, _) = d.surface(local.x, local.y);
                let uv = if wants_uv { d.uv(local.x, local.y).0 } else { Vec2::ZERO };
                SurfacePoint { p, n: d.normal, uv }
            }
            Geometry::Cylinder(c) => {
                // dA = r dφ dz: uniform in (φ, z) is uniform in area.
                let uv = Vec2::new(u.y, u.x);
                let (p, n) = c.point_at(uv);
                SurfacePoint {
                    p,
                    n,
                    uv: if wants_uv { uv } else { Vec2::ZERO },
                }
            }
            Geometry::Mesh {
                mesh,
                transform,
                triangles,
            } => {
                // The cell's choice leaves `x` uniform within the cell: reuse it.
                let (x, _, i) = triangles.sample(u.x);
                let ux = (x * triangles.len() as f32 - i as f32).clamp(0.0, 1.0 - f32::EPSILON);
                // Uniform barycentrics (pbrt-v4 `SampleUniformTriangle`).
                let r = ux.sqrt();
                let (b1, b2) = (1.0 - r, u.y * r);
                let b0 = 1.0 - b1 - b2;
                let [p0, p1, p2] = mesh.corners(i);
                let p = transform.point(p0 * b0 + p1 * b1 + p2 * b2);
                let n = transform.normal((p1 - p0).cross(p2 - p0)).normalize_or(Vec3A::Z);
                let uv = if wants_uv {
                    let [t0, t1, t2] = mesh.corner_uvs(i);
                    t0 * b0 + t1 * b1 + t2 * b2
                } else {
                    Vec2::ZERO
                };
                SurfacePoint { p, n, uv }
            }
        }
    }

    /// Cosine of the cone a sphere fills seen from `p`, when `p` is outside
    /// it (pbrt-v4 §6.2.4: sampling the cone beats sampling the area).
    #[inline]
    fn sphere_cone(s: &Sphere, p: Vec3A) -> Option<f32> {
        let d2 = (s.center - p).length_squared();
        let r2 = s.radius * s.radius;
        // Just outside, the cone degenerates to the hemisphere: sample the area.
        if d2 <= r2 * 1.0001 {
            return None;
        }
        Some((1.0 - r2 / d2).max(0.0).sqrt())
    }

    /// A point on the surface seen from `p`, and the density of its
    /// direction in solid angle: the visible cone for a sphere seen from
    /// outside, the area elsewhere. `None` when the sample is degenerate.
    pub fn sample_from(&self, p: Vec3A, u: Vec2, wants_uv: bool) -> Option<(SurfacePoint, f32)> {
        if let Geometry::Sphere(s) = &self.geometry {
            if let Some(cos_max) = Self::sphere_cone(s, p) {
                let axis = (s.center - p).normalize();
                let wi = Frame::from_normal(axis).to_world(uniform_cone(u, cos_max));
                let ray = Ray::new(p, wi);
                // A direction of the cone meets the sphere (grazing ones may
                // miss by rounding: the tangent point).
                let t = s
                    .intersect(&ray, f32::INFINITY)
                    .unwrap_or_else(|| (s.center - p).dot(wi));
                let q = p + wi * t;
                let n = (q - s.center).normalize_or(-wi);
                let uv = if wants_uv { s.uv(q).0 } else { Vec2::ZERO };
                return Some((SurfacePoint { p: q, n, uv }, 1.0 / (2.0 * PI * (1.0 - cos_max))));
            }
        }
        let q = self.sample_point(u, wants_uv);
        let to = q.p - p;
        let d2 = to.length_squared();
        let cos = (to.dot(q.n) / d2.sqrt()).abs();
        if !d2.is_normal() || cos <= 0.0 {
            return None;
        }
        Some((q, d2 / (cos * self.area)))
    }

    /// Density in solid angle with which [`sample_from`](Self::sample_from)
    /// at `p` picks the point `q` of normal `n`.
    pub fn pdf_from(&self, p: Vec3A, q: Vec3A, n: Vec3A) -> f32 {
        if let Geometry::Sphere(s) = &self.geometry {
            if let Some(cos_max) = Self::sphere_cone(s, p) {
                return 1.0 / (2.0 * PI * (1.0 - cos_max));
            }
        }
        let to = q - p;
        let d2 = to.length_squared();
        let cos = (to.dot(n) / d2.sqrt()).abs();
        if !d2.is_normal() || cos <= 0.0 {
            return 0.0;
        }
        d2 / (cos * self.area)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::{Domain, Rng};
    use crate::scene::{Material, Object};

    fn scene_with(shape: Shape, meshes: Vec<Arc<Mesh>>) -> Scene {
        Scene {
            media: Default::default(),
            camera: crate::scene::Camera::new(Vec3A::Z * 5.0, Vec3A::ZERO, Vec3A::Y, 40.0).unwrap(),
            materials: vec![Material::diffuse("m", Vec3A::ONE)],
            lights: Vec::new(),
            meshes,
            objects: vec![Object {
                name: "o".into(),
                shape,
                material: 0,
            }],
            ambient: Vec3A::ZERO,
            water_medium: None,
        }
    }

    /// The solid-angle density integrates to the solid angle the shape
    /// covers: `E[1 / pdf]` over the samples is that solid angle, here the
    /// sphere's cone `2π(1 − cos θ)`, and `pdf_from` agrees with `sample_from`.
    #[test]
    fn sphere_cone_sampling_covers_the_cone() {
        let s = Sphere {
            center: Vec3A::new(0.0, 0.0, 4.0),
            radius: 1.0,
        };
        let e = ShapeEmitter::new(&scene_with(Shape::Sphere(s), Vec::new()), 0).unwrap();
        let mut rng = Rng::new(1, Domain::Photon, 0, 0);
        let n = 20_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let (q, pdf) = e.sample_from(Vec3A::ZERO, Vec2::from(rng.f32x2()), false).unwrap();
            assert!(((q.p - s.center).length() - 1.0).abs() < 1e-4);
            assert!(q.n.dot(-q.p.normalize()) >= -1e-3, "a visible point faces p");
            assert!((e.pdf_from(Vec3A::ZERO, q.p, q.n) - pdf).abs() < 1e-6 * pdf);
            sum += 1.0 / f64::from(pdf);
        }
        let cos = (1.0f64 - 1.0 / 16.0).sqrt();
        let cone = 2.0 * std::f64::consts::PI * (1.0 - cos);
        assert!((sum / n as f64 - cone).abs() < 1e-3 * cone);
    }

    /// A mesh's triangles are chosen by area: a two-triangle mesh with one
    /// triangle three times the other gets three quarters of the points.
    #[test]
    fn mesh_points_are_uniform_over_the_area() {
        use crate::math::Vec3;
        let positions = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(5.0, 0.0, 0.0),
            Vec3::new(2.0, 2.0, 0.0),
        ];
        let mesh = Mesh::new("two", positions, vec![[0, 1, 2], [3, 4, 5]], None).unwrap();
        let shape = Shape::Mesh {
            mesh: 0,
            transform: Transform::from_srt(Vec3::splat(2.0), Vec3::ZERO, Vec3::ZERO).unwrap(),
            smooth: false,
        };
        let e = ShapeEmitter::new(&scene_with(shape, vec![Arc::new(mesh)]), 0).unwrap();
        assert!((e.area - 4.0 * 3.5).abs() < 1e-5, "{}", e.area);
        let mut rng = Rng::new(2, Domain::Photon, 0, 0);
        let n = 40_000;
        let in_big = (0..n)
            .filter(|_| {
                let q = e.sample_point(Vec2::from(rng.f32x2()), false);
                assert!((q.n - Vec3A::Z).length() < 1e-6);
                q.p.x >= 4.0
            })
            .count();
        let share = in_big as f64 / n as f64;
        assert!((share - 3.0 / 3.5).abs() < 0.01, "{share}");
    }
}
