//! Volumetric path tracing with Mitsuba 3's `volpath` semantics
//! (`src/integrators/volpath.cpp`) for scenes with media bounded by
//! surfaces ([`crate::scene::Media`]) or with `null` surfaces.
//!
//! - **Media.** The path knows the medium it travels in (the camera's at
//!   first). In a medium every segment takes a free flight
//!   ([`Homogeneous::sample_flight`]: one channel chosen uniformly, the
//!   density averaged over the channels, an unbiased one-sample MIS; Mitsuba
//!   picks its channel once per path, which has the same expectation). A
//!   scattering vertex samples a light through the phase function, weighted
//!   by MIS (power heuristic) against phase sampling, and continues in a
//!   phase-sampled direction.
//! - **Crossing surfaces.** Leaving a surface of an object with a medium
//!   interface, reflected or transmitted, the path travels in the medium on
//!   the side of its new direction (`SurfaceInteraction::target_medium`:
//!   the interior against the geometric normal, else the exterior); a
//!   surface without an interface keeps the medium.
//! - **Null surfaces** pass the path straight on. As in Mitsuba they do not
//!   count as bounces for `max_depth`, do not change which vertex the MIS
//!   weight of a light reached later refers to (the last real scattering),
//!   and let shadow rays through. A thin dielectric's straight-through
//!   transmission is such a null event too (its reflection a delta bounce),
//!   and multiplies shadow rays by `1 − R'`.
//! - **Shadow rays** walk from surface to surface toward the light: through
//!   null surfaces, multiplying the transmittance `exp(−σt d)` of every
//!   medium segment (exact for homogeneous media, where Mitsuba tracks ratio
//!   estimates of it); any other surface blocks them.
//! - **Depth** counts real scattering events, surface or medium: light
//!   sampled at a vertex and light reached after it count as in Mitsuba
//!   (`max_depth` segments: a vertex at depth `max_depth − 1` scatters no
//!   further).
//!
//! With Mitsuba's `path` or `direct` reading the scene
//! ([`PassThrough::SurfaceBounce`]: no media) a null surface or a thin
//! sheet's transmission is instead a delta bounce like a mirror's (Mitsuba's
//! `BSDFFlags::Delta` includes `Null`): it counts toward `max_depth`, and
//! shadow rays stop at it.
//!
//! Every random number comes from the pixel sample's own stream, in an
//! order fixed by the path alone.

use super::aov::FirstHit;
use super::lights::LightSampler;
use super::medium::{Flight, Homogeneous};
use super::path::power_heuristic;
use super::plan::{RenderPlan, ROULETTE_DEPTH};
use super::sample::{Integrator, RayCounts, SampleContext};
use super::whitted::SHADOW_EPSILON;
use crate::accel::Accel;
use crate::bsdf::dielectric::thin_sheet_reflectance;
use crate::bsdf::{Bsdf, FresnelModel, Transport};
use crate::math::{offset_ray_origin, Ray, Sampler, Vec3A};
use crate::scene::{PassThrough, Scene};

/// Most surfaces a shadow ray passes through before it is taken as
/// blocked: a bound on the work, far above any real scene's nesting.
const MAX_SHADOW_CROSSINGS: u32 = 256;

/// Most null surfaces one path segment between two scattering events
/// crosses before the path ends (the same kind of bound).
const MAX_NULL_CROSSINGS: u32 = 1024;

/// The volumetric path tracer over one scene and accelerator.
pub struct VolumePathTracer<'a> {
    scene: &'a Scene,
    accel: &'a dyn Accel,
    lights: LightSampler,
    max_depth: u32,
    /// Emitters seen directly from the camera are black.
    hide_emitters: bool,
    /// The scene's media, ready for sampling (same indices).
    media: Vec<Homogeneous>,
    /// Per medium: its scattering vertices sample a light.
    sample_emitters: Vec<bool>,
    /// Null surfaces and thin sheets' transmission pass paths and shadow
    /// rays without a bounce (`volpath`), or are delta bounces that block
    /// shadow rays (Mitsuba's `path`).
    volumetric: bool,
}

/// Where a shadow ray goes.
#[derive(Clone, Copy)]
enum ShadowTarget {
    /// A point on a light.
    Point(Vec3A),
    /// Toward infinity along a unit direction.
    Direction(Vec3A),
}

impl<'a> VolumePathTracer<'a> {
    /// Prepares the integrator.
    pub fn new(scene: &'a Scene, accel: &'a dyn Accel, plan: &RenderPlan) -> Self {
        Self {
            scene,
            accel,
            lights: LightSampler::new(scene),
            max_depth: plan.max_depth,
            hide_emitters: plan.hide_emitters,
            media: scene.media.list.iter().map(Homogeneous::of_medium).collect(),
            sample_emitters: scene.media.list.iter().map(|m| m.sample_emitters).collect(),
            volumetric: scene.media.pass_through == PassThrough::Volumetric,
        }
    }

    /// Transmittance from `origin`, in `medium`, to the light: the product
    /// of the media's transmittances over the segments and of the thin
    /// sheets' `1 − R'`; zero when any other surface than a null one or a
    /// thin sheet is in the way.
    fn transmittance(
        &self,
        origin: Vec3A,
        mut medium: Option<u32>,
        target: ShadowTarget,
        counts: &mut RayCounts,
    ) -> Vec3A {
        let mut tr = Vec3A::ONE;
        let mut o = origin;
        for _ in 0..MAX_SHADOW_CROSSINGS {
            let (ray, t_max, scale) = match target {
                ShadowTarget::Point(q) => {
                    let d = q - o;
                    (Ray::new(o, d), 1.0 - SHADOW_EPSILON, d.length())
                }
                ShadowTarget::Direction(w) => (Ray::new(o, w), f32::INFINITY, 1.0),
            };
            counts.shadow += 1;
            if self.lights.nearest_hit(&ray, t_max).is_some() {
                return Vec3A::ZERO;
            }
            let hit = self.accel.intersect(&ray, t_max);
            if let Some(m) = medium {
                let t = hit.map_or(t_max, |h| h.t);
                tr *= self.media[m as usize].transmittance(t * scale);
            }
            let Some(hit) = hit else { return tr };
            if tr.max_element() <= 0.0 {
                return Vec3A::ZERO;
            }
            let si = self.scene.surface_interaction(&ray, &hit);
            let material = &self.scene.materials[si.material as usize];
            if !self.volumetric {
                // Mitsuba's `path`: every surface blocks shadow rays.
                return Vec3A::ZERO;
            }
            if let Some(d) = material.dielectric.filter(|d| d.thin) {
                // What a thin sheet lets straight through (Mitsuba's
                // `eval_null_transmission`), at the shading normal's cosine.
                let cos = ray.dir.normalize().dot(si.ns);
                tr *= d.tint * (1.0 - thin_sheet_reflectance(FresnelModel::Exact, cos, d.ior));
            } else {
                // Null surfaces, and the holes of blends and masks.
                let pass = material.hole_probability(si.uv);
                if pass <= 0.0 {
                    return Vec3A::ZERO;
                }
                tr *= pass;
            }
            let interface = self.scene.media.interface(si.object);
            if interface.is_transition() {
                medium = interface.target(ray.dir, si.ng);
            }
            o = offset_ray_origin(si.p, si.p_error, si.ng, ray.dir);
        }
        Vec3A::ZERO
    }

    /// Radiance arriving along `ray` toward its origin, from the path's own
    /// random stream.
    fn trace(&self, ray: &Ray, rng: &mut Sampler, counts: &mut RayCounts) -> Vec3A {
        let mut l = Vec3A::ZERO;
        let mut beta = Vec3A::ONE;
        let mut ray = *ray;
        // The last real scattering was a delta lobe (or the camera): light it
        // reaches has no competing light sample.
        let mut specular = true;
        // Density of the direction chosen at the last real scattering vertex,
        // and where that vertex is (null surfaces change neither).
        let mut scatter_pdf = 0.0f32;
        let mut scatter_point = ray.origin;
        let mut eta_scale = 1.0f32;
        let mut depth = 0u32;
        let mut medium = self.scene.media.camera;
        let mut null_crossings = 0u32;
        loop {
            let hit = self.accel.intersect(&ray, f32::INFINITY);
            let t_hit = hit.map_or(f32::INFINITY, |h| h.t);
            let emitter = self.lights.nearest_hit(&ray, t_hit);
            // Emitters the camera sees directly (through null surfaces too,
            // which are not bounces), when the scene hides them.
            let hidden = depth == 0 && self.hide_emitters;

            if let Some(m) = medium {
                let h = &self.media[m as usize];
                let len = ray.dir.length();
                let dir = ray.dir / len;
                let t_end = emitter.map_or(t_hit, |e| e.t);
                match h.sample_flight(t_end * len, rng.f32(), rng.f32()) {
                    Flight::Surface { weight } => beta *= weight,
                    Flight::Scatter { t, weight } => {
                        // A scattering event is a bounce: at the last one
                        // allowed nothing more is gathered.
                        if depth >= self.max_depth {
                            break;
                        }
                        beta *= weight;
                        if beta.max_element() <= 0.0 {
                            // A pure absorber: nothing scatters.
                            break;
                        }
                        let x = ray.origin + dir * t;
                        let wo = -dir;
                        // Next-event estimation through the phase function
                        // (not in a medium with `sample_emitters` = false:
                        // light the phase-sampled direction reaches then
                        // counts in full, as after a delta bounce).
                        let nee = self.sample_emitters[m as usize];
                        if let Some(ls) = nee.then(|| self.lights.sample(x, rng.f32(), rng.vec2())).flatten() {
                            let f = h.phase(wo, ls.wi);
                            if f > 0.0 {
                                let target = match ls.target {
                                    Some(q) => ShadowTarget::Point(q),
                                    None => ShadowTarget::Direction(ls.wi),
                                };
                                let tr = self.transmittance(x, medium, target, counts);
                                if tr.max_element() > 0.0 {
                                    let w = if ls.delta { 1.0 } else { power_heuristic(ls.pdf, f) };
                                    l += beta * tr * ls.li * (f * w / ls.pdf);
                                }
                            }
                        }
                        let (wi, pdf) = h.sample_phase(wo, rng.vec2());
                        specular = !nee;
                        scatter_pdf = pdf;
                        scatter_point = x;
                        null_crossings = 0;
                        depth += 1;
                        if !self.roulette(&mut beta, eta_scale, depth, rng) {
                            break;
                        }
                        ray = Ray::new(x, wi);
                        counts.secondary += 1;
                        continue;
                    }
                }
            }

            if let Some(e) = emitter {
                if e.radiance != Vec3A::ZERO && !hidden {
                    let w = if specular {
                        1.0
                    } else {
                        let q = ray.at(e.t);
                        power_heuristic(
                            scatter_pdf,
                            self.lights.pdf_point(e.light, scatter_point, q, Vec3A::ZERO),
                        )
                    };
                    l += beta * e.radiance * w;
                }
                break;
            }
            let Some(hit) = hit else {
                let (le, light_pdf) = self.lights.environment(ray.dir.normalize());
                if le != Vec3A::ZERO && !hidden {
                    let w = if specular {
                        1.0
                    } else {
                        power_heuristic(scatter_pdf, light_pdf)
                    };
                    l += beta * le * w;
                }
                break;
            };
            let si = self.scene.surface_interaction(&ray, &hit);
            let material = &*self.scene.materials[si.material as usize].at(si.uv);
            if let Some(light) = self.lights.object_emitter(si.object) {
                if material.emits_toward(ray.dir, si.ng) && !hidden {
                    let w = if specular {
                        1.0
                    } else {
                        power_heuristic(scatter_pdf, self.lights.pdf_point(light, scatter_point, si.p, si.ng))
                    };
                    l += beta * material.emission * w;
                }
            }
            let interface = self.scene.media.interface(si.object);
            // A blend scatters as one of its sides (a hole: straight on).
            let scattering = if material.blend.is_some() {
                material.resolve(si.uv, || rng.f32())
            } else {
                Some(std::borrow::Cow::Borrowed(material))
            };
            let passes = scattering.as_deref().is_none_or(|m| m.null);
            if passes && self.volumetric {
                // Straight on, in the medium on the far side; not a bounce.
                null_crossings += 1;
                if null_crossings > MAX_NULL_CROSSINGS {
                    break;
                }
                if interface.is_transition() {
                    medium = interface.target(ray.dir, si.ng);
                }
                let origin = offset_ray_origin(si.p, si.p_error, si.ng, ray.dir);
                ray = Ray::new(origin, ray.dir);
                continue;
            }
            // A thin sheet is sampled at any depth: going straight through
            // it is a null event, not a bounce.
            let sheet = scattering.as_deref().is_some_and(|m| m.is_thin_sheet()) && self.volumetric;
            if depth >= self.max_depth && !sheet {
                break;
            }
            let bsdf = Bsdf::for_resolved(scattering.as_deref(), FresnelModel::Exact, Transport::Radiance);
            if bsdf.is_black() {
                break;
            }
            let frame = bsdf.frame(si.ns, si.dpdu);
            let wo_world = -ray.dir.normalize();
            let wo = frame.to_local(wo_world);
            // Which side of the geometric surface a direction leaves on,
            // against which side the shading frame says: they must agree,
            // or light would leak through the surface.
            let consistent = |wi_world: Vec3A, wi: Vec3A| {
                let geometric = wi_world.dot(si.ng) * wo_world.dot(si.ng) > 0.0;
                let shading = wi.z * wo.z > 0.0;
                geometric == shading
            };
            let medium_toward = |dir: Vec3A| {
                if interface.is_transition() {
                    interface.target(dir, si.ng)
                } else {
                    medium
                }
            };

            if bsdf.has_smooth_lobe() {
                if let Some(ls) = self.lights.sample(si.p, rng.f32(), rng.vec2()) {
                    let wi = frame.to_local(ls.wi);
                    let f = bsdf.eval(wo, wi) * wi.z.abs();
                    if f.max_element() > 0.0 && consistent(ls.wi, wi) {
                        let origin = offset_ray_origin(si.p, si.p_error, si.ng, ls.wi);
                        let target = match ls.target {
                            Some(q) => ShadowTarget::Point(q),
                            None => ShadowTarget::Direction(ls.wi),
                        };
                        let tr = self.transmittance(origin, medium_toward(ls.wi), target, counts);
                        if tr.max_element() > 0.0 {
                            let w = if ls.delta {
                                1.0
                            } else {
                                power_heuristic(ls.pdf, bsdf.pdf(wo, wi))
                            };
                            l += beta * f * tr * ls.li * (w / ls.pdf);
                        }
                    }
                }
            }

            let Some(s) = bsdf.sample(wo, rng.f32(), rng.vec2()) else {
                break;
            };
            let wi_world = frame.to_world(s.wi).normalize();
            if !consistent(wi_world, s.wi) {
                break;
            }
            beta *= s.weight();
            if sheet && s.transmission {
                // Through the sheet, unchanged: as a null surface.
                null_crossings += 1;
                if null_crossings > MAX_NULL_CROSSINGS {
                    break;
                }
                medium = medium_toward(wi_world);
                let origin = offset_ray_origin(si.p, si.p_error, si.ng, wi_world);
                ray = Ray::new(origin, wi_world);
                continue;
            }
            if depth >= self.max_depth {
                break;
            }
            specular = s.delta;
            scatter_pdf = s.pdf;
            scatter_point = si.p;
            null_crossings = 0;
            medium = medium_toward(wi_world);
            if s.transmission {
                eta_scale *= s.eta * s.eta;
            }
            if !beta.is_finite() || beta.max_element() <= 0.0 {
                break;
            }
            depth += 1;
            if !self.roulette(&mut beta, eta_scale, depth, rng) {
                break;
            }
            let origin = offset_ray_origin(si.p, si.p_error, si.ng, wi_world);
            ray = Ray::new(origin, wi_world);
            counts.secondary += 1;
        }
        l
    }

    /// Russian roulette past [`ROULETTE_DEPTH`] bounces (as the path
    /// tracer's): false when the path ends, else `beta` is divided by the
    /// survival probability.
    fn roulette(&self, beta: &mut Vec3A, eta_scale: f32, depth: u32, rng: &mut Sampler) -> bool {
        if depth > ROULETTE_DEPTH {
            let survive = (*beta * eta_scale).max_element().min(1.0);
            if rng.f32() >= survive {
                return false;
            }
            *beta /= survive;
        }
        true
    }
}
impl Integrator for VolumePathTracer<'_> {
    /// The camera ray's radiance, its hit found again (the ray may start
    /// inside a medium, which the first query's hit does not tell).
    fn radiance(&self, ray: &Ray, _first_hit: Option<&FirstHit>, ctx: &mut SampleContext) -> Vec3A {
        self.trace(ray, ctx.rng, ctx.counts)
    }
}
