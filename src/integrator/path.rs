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
//! `[[lights]]` rectangles are one-sided emitters and, unlike in the
//! Whitted integrator, opaque black surfaces: a path ends where it meets
//! one, and they cast shadows (a ceiling light hung just below the ceiling
//! shades the ceiling above it, as in other physically based renderers).
//! Objects whose material emits add their emission where a path meets
//! their front (MIS-weighted against the light sample's density at the
//! previous vertex) and scatter by their BSDF like any surface. Spawned
//! rays start at `offset_ray_origin`; shadow rays stop `SHADOW_EPSILON`
//! short of the light.
//!
//! **The water's medium** (`[medium]` with `absorption` and `scattering`):
//! inside the water (tracked across refractions by [`MediumTracker`]) each
//! segment takes a free flight (spectral MIS over the channels); a scattering
//! vertex samples a light through the Henyey–Greenstein phase function and
//! continues in a phase-sampled direction; shadow rays carry the water's
//! transmittance.
//!
//! **Photon-mapped caustics** (`[photons] caustics = "map"`, the photons
//! traced with the same BSDFs by `photon::PhotonRules::Physical`): every
//! vertex with a non-delta lobe adds the surface map's BSDF-weighted
//! estimate, and every scattering vertex in the water the volume map's
//! phase-weighted one (the camera path's first such vertex gathers `k`
//! photons, later ones [`INDIRECT_GATHER_DIVISOR`] times fewer: their
//! blur is hidden by the bounce). Where the BSDF is one Lambert lobe and
//! the map has precomputed irradiance (`gather = "precomputed"`, the
//! default), that estimate is `kd/π` times the irradiance interpolated
//! from the sites ([`PhotonMap::caustic_irradiance_with`]) at the first
//! such vertex, and the nearest site's alone at later ones, instead of a
//! gather. The maps hold exactly the light that
//! arrived through one or more delta bounces (L S+ D, L S+ V), so after a
//! vertex samples a non-delta direction, light the path then reaches
//! through delta bounces only (at least one, at most the photons' depth)
//! is not counted again: each light path is counted once, by the map at
//! the vertex next to its delta chain, or as a path. Next-event estimation
//! and light reached with no delta bounce stay path traced.

use super::aov::FirstHit;
use super::lights::LightSampler;
use super::medium::{Flight, MediumTracker, WaterVolume};
use super::photon::{
    GatherParams, Kernel, PhotonMap, SiteCache, SiteSearch, INDIRECT_GATHER_DIVISOR, PHOTON_PATH_DEPTH,
};
use super::plan::{MediumPlan, PhotonPlan, RenderPlan, ROULETTE_DEPTH};
use super::sample::{Integrator, RayCounts, SampleContext};
use super::whitted::SHADOW_EPSILON;
use crate::accel::Accel;
use crate::bsdf::{Bsdf, FresnelModel, Transport};
use crate::math::{offset_ray_origin, Ray, Sampler, Vec3A};
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

pub use super::photon::VOLUME_RADIUS_SCALE;

/// The caustic maps and how to gather them: `[first vertex, later ones]`.
struct Caustics<'a> {
    map: &'a PhotonMap,
    surface: [GatherParams; 2],
    volume: [GatherParams; 2],
}

/// The path tracer over one scene and accelerator.
pub struct PathTracer<'a> {
    scene: &'a Scene,
    accel: &'a dyn Accel,
    lights: LightSampler,
    max_depth: u32,
    gather: Option<GatherParams>,
    caustics: Option<Caustics<'a>>,
    /// Delta bounces after a map vertex within which reached light is a
    /// caustic the map holds (the photons' own depth).
    caustic_depth: u32,
    water: Option<WaterVolume<'a>>,
    hide_emitters: bool,
}

impl<'a> PathTracer<'a> {
    /// Prepares the integrator.
    pub fn new(scene: &'a Scene, accel: &'a dyn Accel, plan: &RenderPlan) -> Self {
        let gather = match plan.photons {
            PhotonPlan::Run {
                k, max_radius, cone_k, ..
            } => Some(GatherParams::k_nearest(
                std::num::NonZero::new(k.max(1) as usize).expect("k ≥ 1"),
                max_radius,
                cone_k,
            )),
            _ => None,
        };
        Self {
            scene,
            accel,
            lights: LightSampler::new(scene),
            max_depth: plan.max_depth,
            gather,
            caustics: None,
            caustic_depth: plan.photon_trace().max_depth.unwrap_or(PHOTON_PATH_DEPTH),
            water: match plan.medium {
                MediumPlan::Run { .. } => WaterVolume::of(scene),
                _ => None,
            },
            hide_emitters: plan.hide_emitters,
        }
    }

    /// [`with_photons`](Self::with_photons) gathering as `gather` says
    /// (progressive photon mapping's fixed radius of one sample index; the
    /// volume map's radius is [`VOLUME_RADIUS_SCALE`] times larger).
    pub fn with_photons_gathered(mut self, map: &'a PhotonMap, gather: GatherParams) -> Self {
        self.gather = Some(gather);
        self.with_photons(map)
    }

    /// Adds the caustics of `map` (traced with `PhotonRules::Physical`), when
    /// the plan runs the photon pass.
    pub fn with_photons(mut self, map: &'a PhotonMap) -> Self {
        if let Some(first) = self.gather {
            let later = GatherParams {
                k: std::num::NonZero::new((first.k.get() / INDIRECT_GATHER_DIVISOR).max(1)).expect("≥ 1"),
                ..first
            };
            let volume = |g: GatherParams| GatherParams {
                max_radius: g.max_radius * VOLUME_RADIUS_SCALE,
                fixed_radius: g.fixed_radius.map(|r| r * VOLUME_RADIUS_SCALE),
                ..g
            };
            self.caustics = Some(Caustics {
                map,
                surface: [first, later],
                volume: [volume(first), volume(later)],
            });
        }
        self
    }

    /// Transmittance of the water along a shadow ray leaving `origin` in
    /// the water, over `length` (any surface it crosses occludes it).
    fn shadow_transmittance(&self, in_water: bool, origin: Vec3A, dir: Vec3A, length: f32) -> Vec3A {
        match &self.water {
            Some(w) if in_water => {
                let exit = w.exit_distance(&Ray::new(origin, dir));
                w.coefficients.transmittance(length.min(exit))
            }
            _ => Vec3A::ONE,
        }
    }

    /// Radiance arriving along `ray` toward its origin, from the path's own
    /// random stream, starting from the camera ray's nearest hit (and
    /// perhaps its surface interaction) when the AOV tracer already found
    /// it for the same ray.
    fn trace(
        &self,
        ray: &Ray,
        mut first: Option<&FirstHit>,
        rng: &mut Sampler,
        counts: &mut RayCounts,
        sites: &mut SiteCache,
    ) -> Vec3A {
        let mut l = Vec3A::ZERO;
        let mut beta = Vec3A::ONE;
        let mut ray = *ray;
        // The previous bounce was a delta lobe (or the camera): light it
        // reaches has no competing light sample.
        let mut specular = true;
        let mut bsdf_pdf = 0.0f32;
        let mut eta_scale = 1.0f32;
        let mut depth = 0u32;
        let mut medium = MediumTracker::new(self.water.as_ref().is_some_and(|w| w.contains(ray.origin)));
        // Every bounce so far was a delta lobe: a vertex gathers the most photons.
        let mut delta_chain = true;
        // Delta bounces since a map vertex sampled a non-delta direction.
        let mut since_map: Option<u32> = None;
        loop {
            // The camera ray's hit and its interaction, when known: for
            // this ray only.
            let (hit, mut known_interaction) = match first.take() {
                Some(f) => (f.hit, f.interaction.as_ref()),
                None => (self.accel.intersect(&ray, f32::INFINITY), None),
            };
            let t_hit = hit.map_or(f32::INFINITY, |h| h.t);
            // Emitters the camera sees directly, when the scene hides them.
            let hidden = depth == 0 && self.hide_emitters;
            let emitter = self.lights.nearest_hit(&ray, t_hit);

            if let Some(water) = self.water.as_ref().filter(|_| medium.inside()) {
                let len = ray.dir.length();
                let dir = ray.dir / len;
                let t_end = emitter.map_or(t_hit, |e| e.t);
                let exit = water.exit_distance(&Ray::new(ray.origin, dir));
                let flight = water
                    .coefficients
                    .sample_flight((t_end * len).min(exit), rng.f32(), rng.f32());
                match flight {
                    Flight::Surface { weight } => beta *= weight,
                    Flight::Scatter { t, weight } => {
                        if depth >= self.max_depth {
                            break;
                        }
                        let x = ray.origin + dir * t;
                        let wo = -dir;
                        let coefficients = &water.coefficients;
                        if let Some(c) = &self.caustics {
                            if let Some(volume) = &c.map.volume {
                                // The stored powers hold σs: the estimate is
                                // σs·Ls, so divide the flight's σs back out.
                                let tr_over_pdf = Vec3A::select(
                                    coefficients.sigma_s.cmpgt(Vec3A::ZERO),
                                    weight / coefficients.sigma_s,
                                    Vec3A::ZERO,
                                );
                                let g = &c.volume[usize::from(!delta_chain)];
                                let js = volume.weighted_estimate(x, g, Kernel::Ball, |r| {
                                    Vec3A::splat(coefficients.phase(wo, r.incoming())) * r.power()
                                });
                                l += beta * tr_over_pdf * js;
                            }
                        }
                        beta *= weight;
                        // Next-event estimation through the phase function.
                        if let Some(ls) = self.lights.sample(x, rng.f32(), rng.vec2()) {
                            let f = coefficients.phase(wo, ls.wi);
                            let (shadow, t_max, length) = match ls.target {
                                Some(q) => (Ray::new(x, q - x), 1.0 - SHADOW_EPSILON, (q - x).length()),
                                None => (Ray::new(x, ls.wi), f32::INFINITY, f32::INFINITY),
                            };
                            counts.shadow += 1;
                            if f > 0.0
                                && self.lights.nearest_hit(&shadow, t_max).is_none()
                                && !self.accel.occluded(&shadow, t_max)
                            {
                                let w = if ls.delta { 1.0 } else { power_heuristic(ls.pdf, f) };
                                let tr = self.shadow_transmittance(true, x, ls.wi, length);
                                l += beta * tr * ls.li * (f * w / ls.pdf);
                            }
                        }
                        let (wi, pdf) = coefficients.sample_phase(wo, rng.vec2());
                        since_map = self.caustics.is_some().then_some(0);
                        delta_chain = false;
                        specular = false;
                        bsdf_pdf = pdf;
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
                // Light reached through delta bounces after a map vertex is
                // the map's caustic.
                let in_map = since_map.is_some_and(|n| n >= 1 && n <= self.caustic_depth);
                if e.radiance != Vec3A::ZERO && !in_map && !hidden {
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
                // Environments emit no photons: never in the map.
                let (le, light_pdf) = self.lights.environment(ray.dir.normalize());
                if le != Vec3A::ZERO && !hidden {
                    let w = if specular {
                        1.0
                    } else {
                        power_heuristic(bsdf_pdf, light_pdf)
                    };
                    l += beta * le * w;
                }
                break;
            };
            let si = match known_interaction.take() {
                Some(si) => *si,
                None => self.scene.surface_interaction(&ray, &hit),
            };
            let material = &*self.scene.materials[si.material as usize].at(si.uv);
            if let Some(light) = self.lights.object_emitter(si.object) {
                // An emitting surface, seen from a side it emits from.
                let in_map = since_map.is_some_and(|n| n >= 1 && n <= self.caustic_depth);
                if material.emits_toward(ray.dir, si.ng) && !in_map && !hidden {
                    let w = if specular {
                        1.0
                    } else {
                        power_heuristic(bsdf_pdf, self.lights.pdf_point(light, ray.origin, si.p, si.ng))
                    };
                    l += beta * material.emission * w;
                }
            }
            if depth >= self.max_depth {
                break;
            }
            // A blend scatters as one of its sides, chosen here (a hole
            // lets the path through).
            let scattering = if material.blend.is_some() {
                material.resolve(si.uv, || rng.f32())
            } else {
                Some(std::borrow::Cow::Borrowed(material))
            };
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
            let wo_geometric = wo_world.dot(si.ng);
            let consistent = |wi_world: Vec3A, wi_z: f32| {
                let geometric = wi_world.dot(si.ng) * wo_geometric > 0.0;
                let shading = wi_z * wo.z > 0.0;
                geometric == shading
            };

            if bsdf.has_smooth_lobe() {
                // The caustic map's estimate, `Σ f(ωo, ωp) Φp / (π r²)`.
                if let Some(c) = &self.caustics {
                    let g = &c.surface[usize::from(!delta_chain)];
                    let estimate = match bsdf.lambert() {
                        Some(kd) if c.map.precomputed_sites() > 0 => {
                            // One Lambert lobe and precomputed irradiance:
                            // `kd/π · E`, `E` from the photons arriving on the
                            // side the path leaves on.
                            let n = if wo_geometric > 0.0 { si.ng } else { -si.ng };
                            // The first such vertex of a pixel's samples lies
                            // beside the last one's: the site cache answers it.
                            // Later vertices scatter, and a diffuse bounce hides
                            // the nearest site's Voronoi cell.
                            let search = if delta_chain {
                                SiteSearch::Cached
                            } else {
                                SiteSearch::NearestOnly
                            };
                            let e = c.map.caustic_irradiance_with(si.p, n, g, search, sites);
                            kd * (1.0 / std::f32::consts::PI) * e
                        }
                        Some(kd) => {
                            // One Lambert lobe: `f` is `kd/π` wherever it is not
                            // zero, so each photon needs only its side tests
                            // (the lobe's and `consistent`'s, on the same
                            // numbers), not a BSDF evaluation; the sum is the
                            // same, term by term.
                            let f = kd * (1.0 / std::f32::consts::PI);
                            c.map.weighted_estimate(si.p, g, Kernel::Disk, |r| {
                                let wi_world = r.incoming();
                                let wi_z = wi_world.dot(frame.n);
                                if consistent(wi_world, wi_z) && bsdf.lambert_reflects(wo.z, wi_z) {
                                    f * r.power()
                                } else {
                                    Vec3A::ZERO
                                }
                            })
                        }
                        None => c.map.weighted_estimate(si.p, g, Kernel::Disk, |r| {
                            let wi_world = r.incoming();
                            let wi = frame.to_local(wi_world);
                            if consistent(wi_world, wi.z) {
                                bsdf.eval(wo, wi) * r.power()
                            } else {
                                Vec3A::ZERO
                            }
                        }),
                    };
                    l += beta * estimate;
                }

                // Next-event estimation.
                if let Some(ls) = self.lights.sample(si.p, rng.f32(), rng.vec2()) {
                    let wi = frame.to_local(ls.wi);
                    let f = bsdf.eval(wo, wi) * wi.z.abs();
                    if f.max_element() > 0.0 && consistent(ls.wi, wi.z) {
                        let origin = offset_ray_origin(si.p, si.p_error, si.ng, ls.wi);
                        let (shadow, t_max, length) = match ls.target {
                            Some(q) => (
                                Ray::new(origin, q - origin),
                                1.0 - SHADOW_EPSILON,
                                (q - origin).length(),
                            ),
                            None => (Ray::new(origin, ls.wi), f32::INFINITY, f32::INFINITY),
                        };
                        counts.shadow += 1;
                        let light_between = self.lights.nearest_hit(&shadow, t_max).is_some();
                        if !light_between && !self.accel.occluded(&shadow, t_max) {
                            let w = if ls.delta {
                                1.0
                            } else {
                                power_heuristic(ls.pdf, bsdf.pdf(wo, wi))
                            };
                            let tr = self.shadow_transmittance(medium.inside(), origin, ls.wi, length);
                            l += beta * f * tr * ls.li * (w / ls.pdf);
                        }
                    }
                }
            }

            // The next direction.
            let Some(s) = bsdf.sample(wo, rng.f32(), rng.vec2()) else {
                break;
            };
            let wi_world = frame.to_world(s.wi).normalize();
            if !consistent(wi_world, s.wi.z) {
                break;
            }
            beta *= s.weight();
            specular = s.delta;
            bsdf_pdf = s.pdf;
            if s.delta {
                if let Some(n) = since_map.as_mut() {
                    *n += 1;
                }
            } else {
                since_map = self.caustics.is_some().then_some(0);
                delta_chain = false;
            }
            if s.transmission {
                eta_scale *= s.eta * s.eta;
                if let Some(water) = &self.water {
                    let entering = ray.dir.dot(si.ng) < 0.0;
                    medium.transmit(hit.instance, water.medium.boundary, entering);
                }
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

    /// Russian roulette past [`ROULETTE_DEPTH`] bounces: false when the
    /// path ends, else `beta` is divided by the survival probability.
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

impl Integrator for PathTracer<'_> {
    fn radiance(&self, ray: &Ray, first_hit: Option<&FirstHit>, ctx: &mut SampleContext) -> Vec3A {
        self.trace(ray, first_hit, ctx.rng, ctx.counts, ctx.sites)
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
