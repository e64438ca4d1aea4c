//! Auxiliary images (AOVs): for each camera sample, the albedo and the
//! shading normal of the first non-specular surface it sees. Perfect
//! mirrors and smooth glass are followed (reflection at mirrors, refraction
//! at glass, reflection where it is total), their tints multiplying the
//! albedo, as Open Image Denoise's documentation recommends; the normal is
//! the final surface's, turned toward the ray (unit length). A ray that
//! leaves the scene has albedo and normal zero; a visible area light has
//! its colour (radiance over its largest channel) as albedo.
//!
//! The tracer draws no random numbers, so the image's samples are those of
//! a render without AOVs, and the AOVs of a pixel depend only on its
//! samples' sub-pixel positions: the same for any thread count, across
//! interrupt and resume and across shards. Each pixel's first
//! [`AOV_SAMPLES`] samples trace them (see `film::Accumulation`).

use crate::accel::Accel;
use crate::bsdf::specular::{reflect, refract};
pub use crate::film::accum::AOV_SAMPLES;
use crate::geometry::Hit;
use crate::math::{offset_ray_origin, Ray, Vec3A};
use crate::scene::{Light, Material, Quad, Scene, SurfaceInteraction};

/// Specular surfaces followed before giving up (a ray trapped between
/// mirrors or inside glass then reads as the background).
pub const MAX_SPECULAR_CHAIN: u32 = 8;

/// A camera ray's nearest hit as the AOV tracer found it, for the
/// integrator to start from (`Scene::surface_interaction` is a function of
/// the ray and the hit alone: the same interaction either way).
#[derive(Clone, Copy, Debug)]
pub struct FirstHit {
    /// The nearest hit (`None`: the ray escapes).
    pub hit: Option<Hit>,
    /// The hit's surface interaction, when the tracer reached it (no
    /// emitter in front of it).
    pub interaction: Option<SurfaceInteraction>,
}

/// Traces the AOVs of camera rays.
pub struct AovTracer<'a> {
    scene: &'a Scene,
    accel: &'a dyn Accel,
    /// Area lights as rectangles, with their albedo stand-in.
    emitters: Vec<(Quad, Vec3A)>,
}

/// What the tracer does at a surface.
enum Step {
    /// Continue along the mirror direction, tinted.
    Reflect(Vec3A),
    /// Continue through the interface of index `ior`, tinted.
    Refract(Vec3A, f32),
    /// The first non-specular surface: its albedo.
    Stop(Vec3A),
}

fn step(m: &Material) -> Step {
    if m.null {
        return Step::Refract(Vec3A::ONE, 1.0);
    }
    if let Some(b) = m.blend.as_deref() {
        // The side that weighs more (the guides draw no random number);
        // a hole lets the guide ray through, unchanged.
        let side = if b.weight >= 0.5 { &b.second } else { &b.first };
        return match side {
            Some(m) => step(m),
            None => Step::Refract(Vec3A::ONE, 1.0),
        };
    }
    let surface = (m.diffuse + m.specular).min(Vec3A::ONE);
    if let Some(d) = m.dielectric {
        return if d.thin {
            // Through the sheet, unbent (its index 1 leaves the ray as it is).
            Step::Refract(d.tint, 1.0)
        } else if d.roughness == 0.0 {
            Step::Refract(d.tint, d.ior)
        } else {
            Step::Stop(d.tint.min(Vec3A::ONE))
        };
    }
    if let Some(p) = m.principled {
        // The part that dominates: a sharp metal reflects, sharp glass
        // refracts, anything else is the base colour.
        let base = m.diffuse.min(Vec3A::ONE);
        return match p.roughness == 0.0 {
            true if p.metallic >= 0.5 => Step::Reflect(base),
            true if p.transmission * (1.0 - p.metallic) >= 0.5 => Step::Refract(base, if p.thin { 1.0 } else { p.ior }),
            _ => Step::Stop(base),
        };
    }
    if let Some(c) = m.conductor {
        // Reflectance at normal incidence.
        let one = Vec3A::ONE;
        let f0 = ((c.eta - one) * (c.eta - one) + c.k * c.k) / ((c.eta + one) * (c.eta + one) + c.k * c.k);
        return if c.roughness == 0.0 {
            Step::Reflect(f0)
        } else {
            Step::Stop(f0.min(one))
        };
    }
    match m.mirror {
        Some(mirror) if mirror.reflectivity >= 0.5 => Step::Reflect(mirror.tint * mirror.reflectivity),
        Some(mirror) if mirror.reflectivity > 0.0 => {
            let r = mirror.reflectivity;
            Step::Stop((surface * (1.0 - r) + mirror.tint * r).min(Vec3A::ONE))
        }
        _ => Step::Stop(surface),
    }
}

impl<'a> AovTracer<'a> {
    /// A tracer over `scene`.
    pub fn new(scene: &'a Scene, accel: &'a dyn Accel) -> Self {
        let emitters = scene
            .lights
            .iter()
            .filter_map(|l| match l {
                Light::Area(a) => Quad::new(a.center - (a.u + a.v) * 0.5, a.u, a.v).map(|q| {
                    let peak = a.radiance.max_element();
                    let colour = if peak > 0.0 { a.radiance / peak } else { Vec3A::ZERO };
                    (q, colour)
                }),
                _ => None,
            })
            .collect();
        Self { scene, accel, emitters }
    }

    /// `(albedo, normal)` seen along the camera ray `ray`.
    pub fn trace(&self, ray: &Ray) -> (Vec3A, Vec3A) {
        let (albedo, normal, _) = self.trace_keeping_hit(ray);
        (albedo, normal)
    }

    /// [`trace`](Self::trace), and the camera ray's own nearest hit, which
    /// the integrator then starts from instead of tracing the ray again
    /// (the same query of the same ray: the same hit), with the hit's
    /// surface interaction when the tracer computed it.
    pub fn trace_keeping_hit(&self, ray: &Ray) -> (Vec3A, Vec3A, FirstHit) {
        let hit = self.accel.intersect(ray, f32::INFINITY);
        let mut interaction = None;
        let (albedo, normal) = self.trace_from(ray, hit, &mut interaction);
        (albedo, normal, FirstHit { hit, interaction })
    }

    /// The albedo and normal along `ray`, whose nearest hit is `first`;
    /// `first_interaction` receives that hit's surface interaction when
    /// the walk computes it.
    fn trace_from(
        &self,
        ray: &Ray,
        first: Option<Hit>,
        first_interaction: &mut Option<SurfaceInteraction>,
    ) -> (Vec3A, Vec3A) {
        let mut ray = *ray;
        let mut weight = Vec3A::ONE;
        for bounce in 0..=MAX_SPECULAR_CHAIN {
            let hit = match bounce {
                0 => first,
                _ => self.accel.intersect(&ray, f32::INFINITY),
            };
            let mut t_nearest = hit.map_or(f32::INFINITY, |h| h.t);
            let mut light = None;
            for (quad, colour) in &self.emitters {
                if ray.dir.dot(quad.normal) < 0.0 {
                    if let Some((t, _, _)) = quad.intersect(&ray, t_nearest) {
                        t_nearest = t;
                        light = Some((*colour, quad.normal));
                    }
                }
            }
            if let Some((colour, normal)) = light {
                return (weight * colour, normal);
            }
            let Some(hit) = hit else {
                return (Vec3A::ZERO, Vec3A::ZERO);
            };
            let si = self.scene.surface_interaction(&ray, &hit);
            if bounce == 0 {
                *first_interaction = Some(si);
            }
            let entering = si.ng.dot(ray.dir) < 0.0;
            let (ng, ns) = if entering { (si.ng, si.ns) } else { (-si.ng, -si.ns) };
            let mirror = |d: Vec3A| {
                let r = reflect(d, ns);
                if r.dot(ng) <= 0.0 {
                    reflect(d, ng)
                } else {
                    r
                }
            };
            let (dir, tint) = match step(&self.scene.materials[si.material as usize].at(si.uv)) {
                Step::Stop(albedo) => return (weight * albedo, ns),
                Step::Reflect(tint) => (mirror(ray.dir), tint),
                Step::Refract(tint, ior) => {
                    let eta = if entering { 1.0 / ior } else { ior };
                    match refract(ray.dir, ns, eta) {
                        Some((t, _, _)) => (t, tint),
                        None => (mirror(ray.dir), Vec3A::ONE),
                    }
                }
            };
            weight *= tint;
            let dir = dir.normalize();
            ray = Ray::new(offset_ray_origin(si.p, si.p_error, si.ng, dir), dir);
        }
        (Vec3A::ZERO, Vec3A::ZERO)
    }
}
