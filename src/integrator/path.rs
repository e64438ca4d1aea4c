//! Unidirectional path tracing (Kajiya 1986) with next-event estimation and
//! multiple importance sampling (Veach & Guibas 1995, power heuristic with
//! β = 2): at every vertex with a non-delta lobe one light is sampled (in
//! proportion to power) and one BSDF direction; light reached by the BSDF
//! direction is weighted against the light sample's density, so each path
//! is counted once. An iterative loop carries the throughput; Russian
//! roulette after [`ROULETTE_DEPTH`] bounces keeps the estimate unbiased
//! (pbrt-v4 §13.1.1, survival `min(1, max βᵢ)` with the refraction scaling
//! taken out); `max_depth`, when set, caps the bounces.
//!
//! Area lights are one-sided emitting rectangles and, unlike in the Whitted
//! integrator, opaque black surfaces: a path ends where it meets one, and
//! they cast shadows (a ceiling light hung just below the ceiling shades
//! the ceiling above it, as in other physically based renderers). Spawned
//! rays start at `offset_ray_origin`; shadow rays stop `SHADOW_EPSILON`
//! short of the light.

use super::lights::LightSampler;
use super::plan::{RenderPlan, ROULETTE_DEPTH};
use super::whitted::{RayCounts, SHADOW_EPSILON};
use crate::accel::Accel;
use crate::bsdf::{Bsdf, FresnelModel, Transport};
use crate::math::{offset_ray_origin, Frame, Ray, Sampler, Vec3A};
use crate::scene::Scene;

/// Power heuristic weight of a strategy of density `a` against one of density `b`.
#[inline]
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2.is_infinite() {
        return 1.0;
    }
    if a2 + b2 > 0.0 {
        a2 / (a2 + b2)
    } else {
        0.0
    }
}

/// The path tracer over one scene and accelerator.
pub struct PathTracer<'a> {
    scene: &'a Scene,
    accel: &'a dyn Accel,
    lights: LightSampler,
    max_depth: u32,
}

impl<'a> PathTracer<'a> {
    /// Prepares the integrator.
    pub fn new(scene: &'a Scene, accel: &'a dyn Accel, plan: &RenderPlan) -> Self {
        Self {
            scene,
            accel,
            lights: LightSampler::new(scene),
            max_depth: plan.max_depth,
        }
    }

    /// Radiance arriving along `ray` toward its origin, from the path's own
    /// random stream.
    pub fn radiance(&self, ray: &Ray, rng: &mut Sampler, counts: &mut RayCounts) -> Vec3A {
        let mut l = Vec3A::ZERO;
        let mut beta = Vec3A::ONE;
        let mut ray = *ray;
        // The previous bounce was a delta lobe (or the camera): light it
        // reaches has no competing light sample.
        let mut specular = true;
        let mut bsdf_pdf = 0.0f32;
        let mut eta_scale = 1.0f32;
        let mut depth = 0u32;
        loop {
            let hit = self.accel.intersect(&ray, f32::INFINITY);
            let t_hit = hit.map_or(f32::INFINITY, |h| h.t);
            if let Some(e) = self.lights.nearest_hit(&ray, t_hit) {
                if e.radiance != Vec3A::ZERO {
                    let w = if specular {
                        1.0
                    } else {
                        power_heuristic(bsdf_pdf, self.lights.pdf_area(e.light, &ray, e.t))
                    };
                    l += beta * e.radiance * w;
                }
                break;
            }
            let Some(hit) = hit else {
                let (le, light_pdf) = self.lights.environment();
                if le != Vec3A::ZERO {
                    let w = if specular {
                        1.0
                    } else {
                        power_heuristic(bsdf_pdf, light_pdf)
                    };
                    l += beta * le * w;
                }
                break;
            };
            if depth >= self.max_depth {
                break;
            }
            let si = self.scene.surface_interaction(&ray, &hit);
            let material = &self.scene.materials[si.material as usize];
            let bsdf = Bsdf::for_material(material, FresnelModel::Exact, Transport::Radiance);
            if bsdf.is_black() {
                break;
            }
            let frame = Frame::from_normal(si.ns);
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

            // Next-event estimation.
            if bsdf.has_smooth_lobe() {
                if let Some(ls) = self.lights.sample(si.p, rng.f32(), rng.vec2()) {
                    let wi = frame.to_local(ls.wi);
                    let f = bsdf.eval(wo, wi) * wi.z.abs();
                    if f.max_element() > 0.0 && consistent(ls.wi, wi) {
                        let origin = offset_ray_origin(si.p, si.p_error, si.ng, ls.wi);
                        let (shadow, t_max) = match ls.target {
                            Some(q) => (Ray::new(origin, q - origin), 1.0 - SHADOW_EPSILON),
                            None => (Ray::new(origin, ls.wi), f32::INFINITY),
                        };
                        counts.shadow += 1;
                        let light_between = self.lights.nearest_hit(&shadow, t_max).is_some();
                        if !light_between && !self.accel.occluded(&shadow, t_max) {
                            let w = if ls.delta {
                                1.0
                            } else {
                                power_heuristic(ls.pdf, bsdf.pdf(wo, wi))
                            };
                            l += beta * f * ls.li * (w / ls.pdf);
                        }
                    }
                }
            }

            // The next direction.
            let Some(s) = bsdf.sample(wo, rng.f32(), rng.vec2()) else {
                break;
            };
            let wi_world = frame.to_world(s.wi).normalize();
            if !consistent(wi_world, s.wi) {
                break;
            }
            beta *= s.weight();
            specular = s.delta;
            bsdf_pdf = s.pdf;
            if s.transmission {
                eta_scale *= s.eta * s.eta;
            }
            if !beta.is_finite() || beta.max_element() <= 0.0 {
                break;
            }
            depth += 1;
            if depth > ROULETTE_DEPTH {
                let survive = (beta * eta_scale).max_element().min(1.0);
                if rng.f32() >= survive {
                    break;
                }
                beta /= survive;
            }
            let origin = offset_ray_origin(si.p, si.p_error, si.ng, wi_world);
            ray = Ray::new(origin, wi_world);
            counts.secondary += 1;
        }
        l
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn power_heuristic_weights_sum_to_one() {
        for (a, b) in [(1.0f32, 1.0f32), (0.3, 7.0), (1e-6, 5.0), (12.0, 0.0)] {
            let s = power_heuristic(a, b) + power_heuristic(b, a);
            assert!((s - 1.0).abs() < 1e-6, "{a} {b}: {s}");
        }
        assert_eq!(power_heuristic(0.0, 0.0), 0.0);
        assert_eq!(power_heuristic(f32::INFINITY, 1.0), 1.0);
    }
}
