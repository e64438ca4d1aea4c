//! Seeded ray generation: the four ray kinds (camera, bounds, feature,
//! shadow) described in the `crosscheck` module documentation.

use super::compare::invalid_hit;
use crate::accel::Accel;
use crate::math::rng::Rng;
use crate::math::sampling::uniform_sphere;
use crate::math::{offset_ray_origin, Aabb, Frame, Ray, Vec2, Vec3A};
use crate::scene::{Light, Scene, Shape};

/// How a ray was generated (see the `crosscheck` module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RayKind {
    /// Camera rays over the image.
    Camera = 0,
    /// Random rays through the scene bounds.
    Bounds = 1,
    /// Rays aimed exactly at vertices, edges and silhouettes.
    Feature = 2,
    /// Shadow rays from surface points towards lights.
    Shadow = 3,
}

impl RayKind {
    /// All kinds, in the order rays cycle through them.
    pub const ALL: [RayKind; 4] = [RayKind::Camera, RayKind::Bounds, RayKind::Feature, RayKind::Shadow];

    /// The kind of ray `index`.
    pub fn of_ray(index: u64) -> RayKind {
        Self::ALL[(index % 4) as usize]
    }

    /// Short name for tables.
    pub fn name(self) -> &'static str {
        match self {
            RayKind::Camera => "camera",
            RayKind::Bounds => "bounds",
            RayKind::Feature => "feature",
            RayKind::Shadow => "shadow",
        }
    }
}

/// Seeded ray generation (see the `crosscheck` module documentation).
pub(super) struct RayGenerator<'s> {
    pub(super) scene: &'s Scene,
    pub(super) seed: u64,
    /// The image camera rays go through.
    image: (u32, u32),
    bounds: Aabb,
    center: Vec3A,
    outer_radius: f32,
}

impl<'s> RayGenerator<'s> {
    pub(super) fn new(scene: &'s Scene, seed: u64, image: (u32, u32)) -> Self {
        let mut bounds = scene.bounds();
        if bounds.is_empty() || !bounds.min.is_finite() || !bounds.max.is_finite() {
            bounds = Aabb::new(Vec3A::splat(-1.0), Vec3A::splat(1.0));
        }
        let center = bounds.center();
        let half_diagonal = (bounds.extent().length() * 0.5).max(1e-3 * (1.0 + center.length()));
        Self {
            scene,
            seed,
            image,
            bounds,
            center,
            outer_radius: 1.5 * half_diagonal,
        }
    }

    fn in_box(b: &Aabb, rng: &mut Rng) -> Vec3A {
        b.min + b.extent() * Vec3A::new(rng.f32(), rng.f32(), rng.f32())
    }

    fn on_outer_sphere(&self, rng: &mut Rng) -> Vec3A {
        self.center + uniform_sphere(Vec2::new(rng.f32(), rng.f32())) * self.outer_radius
    }

    fn towards(origin: Vec3A, target: Vec3A) -> Ray {
        Ray::new(origin, (target - origin).normalize_or(Vec3A::Z))
    }

    /// Ray and closest-hit `t_max` of the given kind.
    pub(super) fn ray(&self, kind: RayKind, rng: &mut Rng, a: &dyn Accel) -> (Ray, f32) {
        match kind {
            RayKind::Camera => {
                let (w, h) = (self.image.0.max(1), self.image.1.max(1));
                let ray = self.scene.camera.ray(rng.f32() * w as f32, rng.f32() * h as f32, w, h);
                (ray, f32::INFINITY)
            }
            RayKind::Bounds => (self.bounds_ray(rng), f32::INFINITY),
            RayKind::Feature => (self.feature_ray(rng), f32::INFINITY),
            RayKind::Shadow => self.shadow_ray(rng, a),
        }
    }

    fn bounds_ray(&self, rng: &mut Rng) -> Ray {
        if rng.below(2) == 0 {
            let origin = self.on_outer_sphere(rng);
            Self::towards(origin, Self::in_box(&self.bounds, rng))
        } else {
            let origin = Self::in_box(&self.bounds, rng);
            Ray::new(origin, uniform_sphere(Vec2::new(rng.f32(), rng.f32())))
        }
    }

    fn feature_ray(&self, rng: &mut Rng) -> Ray {
        let scene = self.scene;
        if scene.objects.is_empty() {
            return self.bounds_ray(rng);
        }
        let k = rng.below(scene.objects.len() as u32) as usize;
        let origin = if rng.below(2) == 0 {
            self.on_outer_sphere(rng)
        } else {
            let ob = scene.object_bounds(k);
            let c = ob.center();
            let half = ob.extent() * 1.5;
            Self::in_box(&Aabb::new(c - half, c + half), rng)
        };
        let on_edge = |rng: &mut Rng, corners: &[Vec3A]| {
            let n = corners.len() as u32;
            let i = rng.below(n) as usize;
            if rng.below(3) == 0 {
                corners[i]
            } else {
                let (p, q) = (corners[i], corners[(i + 1) % corners.len()]);
                p + (q - p) * rng.f32()
            }
        };
        let target = match &scene.objects[k].shape {
            Shape::Mesh { mesh, transform, .. } => {
                let mesh = &scene.meshes[*mesh as usize];
                let tri = rng.below(mesh.triangles.len() as u32) as usize;
                transform.point(on_edge(rng, &mesh.corners(tri)))
            }
            Shape::Quad(q) => on_edge(rng, &[q.corner, q.corner + q.u, q.corner + q.u + q.v, q.corner + q.v]),
            Shape::Disk(d) => {
                // A point of the rim.
                let phi = rng.f32() * std::f32::consts::TAU;
                d.center + d.a * phi.cos() + d.b * phi.sin()
            }
            Shape::Cylinder(c) => {
                let f = origin - c.base;
                let (x, y) = (f.dot(c.s), f.dot(c.t));
                let dist = (x * x + y * y).sqrt();
                let z = if rng.below(2) == 0 {
                    // A rim.
                    c.length * rng.below(2) as f32
                } else {
                    rng.f32() * c.length
                };
                let phi = if dist > c.radius * 1.0001 && rng.below(3) != 0 {
                    // A silhouette line: the tangents from the origin's
                    // projection across the axis, at acos(r/D) from it.
                    let side = if rng.below(2) == 0 { 1.0 } else { -1.0 };
                    y.atan2(x) + side * (c.radius / dist).acos()
                } else {
                    rng.f32() * std::f32::consts::TAU
                };
                c.base + (c.s * phi.cos() + c.t * phi.sin()) * c.radius + c.axis * z
            }
            Shape::Sphere(s) => {
                let f = origin - s.center;
                let dist = f.length();
                if dist <= s.radius * 1.0001 {
                    s.center + uniform_sphere(Vec2::new(rng.f32(), rng.f32())) * s.radius
                } else {
                    // The tangent points from `origin` form a circle at angle
                    // acos(r/D) from the direction to the origin.
                    let w = f / dist;
                    let frame = Frame::from_normal(w);
                    let cos_a = s.radius / dist;
                    let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
                    let phi = rng.f32() * std::f32::consts::TAU;
                    let around = frame.s * phi.cos() + frame.t * phi.sin();
                    s.center + (w * cos_a + around * sin_a) * s.radius
                }
            }
        };
        Self::towards(origin, target)
    }

    fn light_target(&self, rng: &mut Rng) -> Vec3A {
        let lights = &self.scene.lights;
        if lights.is_empty() {
            return Self::in_box(&self.bounds, rng);
        }
        match &lights[rng.below(lights.len() as u32) as usize] {
            Light::Point { position, .. } => *position,
            Light::Spot(s) => s.position,
            Light::Area(area) => area.point(Vec2::new(rng.f32(), rng.f32())),
            Light::Environment { .. } | Light::Directional { .. } => Self::in_box(&self.bounds, rng),
        }
    }

    fn shadow_ray(&self, rng: &mut Rng, a: &dyn Accel) -> (Ray, f32) {
        const ATTEMPTS: usize = 4;
        for _ in 0..ATTEMPTS {
            let origin = self.on_outer_sphere(rng);
            let primary = Self::towards(origin, Self::in_box(&self.bounds, rng));
            let Some(hit) = a.intersect(&primary, f32::INFINITY) else {
                continue;
            };
            if invalid_hit(self.scene, &primary, f32::INFINITY, &hit).is_some() {
                continue;
            }
            let si = self.scene.surface_interaction(&primary, &hit);
            let target = self.light_target(rng);
            let origin = offset_ray_origin(si.p, si.p_error, si.ng, target - si.p);
            let to_light = target - origin;
            let dist = to_light.length();
            if dist > 0.0 && dist.is_finite() {
                return (Ray::new(origin, to_light / dist), dist);
            }
        }
        // Nothing hit: a segment from inside the bounds to a light.
        let origin = Self::in_box(&self.bounds, rng);
        let target = self.light_target(rng);
        let dist = (target - origin).length();
        if dist > 0.0 && dist.is_finite() {
            (Ray::new(origin, (target - origin) / dist), dist)
        } else {
            (self.bounds_ray(rng), f32::INFINITY)
        }
    }
}
