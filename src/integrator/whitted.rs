//! Whitted ray tracing (Whitted 1980) with physically based lights:
//! ambient + Lambert diffuse + a Phong or Blinn-Phong highlight per light,
//! hard shadows for point, spot and directional lights, stratified soft
//! shadows for area lights and emitting objects,
//! mirror reflection, and Fresnel-weighted reflection/refraction at dielectrics.
//!
//! Units. A point light of intensity `I` gives irradiance `E = I cos θ / r²`;
//! an area light of radiance `L` and area `A`, sampled at N stratified points
//! `x_k`, gives `E ≈ (1/N) Σ_k L cos θ_k cos θ'_k A / r_k²` (visibility
//! included). Outgoing radiance is `f(ωi, ωo) · E` summed over lights, with
//! the energy-normalised BRDF of `bsdf::phong`, shared with the path
//! integrator: `f = kd/π + ks · (n+2)/(2π) · (R·V)^n` (Phong; Lafortune &
//! Willems 1994) or Blinn-Phong as a microfacet lobe, the normalised
//! distribution `(n+2)/(2π) (N·H)^n` with V-cavity masking (Cook & Torrance
//! 1982), so a white lobe never reflects more than the incident energy,
//! whatever the exponent or angle.
//!
//! Spawned rays start at `offset_ray_origin` (error-bound offsets, no fixed
//! epsilon); shadow rays stop a relative `SHADOW_EPSILON` short of the light.
//!
//! Conventions worth knowing:
//! - `[[lights]]` are not scene objects. Camera and specular rays test the
//!   area lights' rectangles analytically (emitting side only: seen from
//!   behind a light is transparent); shadow rays only query the
//!   accelerator, so no such light ever occludes another, or itself.
//!   Emitting objects are objects: seen, they add their emission to what
//!   their material reflects, and they cast shadows; their direct light is
//!   `(1/N) Σ_k f L_k cos θ_k / pdf_k` over N stratified samples of the
//!   light interface (`scene::light::Emitter`).
//! - Shadow rays treat every object as opaque, glass included (classic
//!   Whitted): light focused through glass is the photon pass's job.
//! - Beyond `max_depth` bounces the reflected / refracted term is black.
//! - Dielectrics have no diffuse or ambient term; they keep the specular
//!   highlight of delta lights only (a reflected ray never finds a point,
//!   spot or directional light, while area lights show up in the
//!   reflection itself).
//! - Caustics: with a photon map, diffuse surfaces add `ρ/π · E_caustic`,
//!   the cone-filtered irradiance of the caustic photons (`photon::gather`),
//!   so the shadow behind glass stays dark in direct light but receives the
//!   focused light.
//! - Fog: with a medium, every camera and secondary ray segment is blended
//!   toward the fog colour by its length inside the medium (`fog.rs`).

use super::aov::FirstHit;
use super::fog;
use super::photon::{GatherParams, PhotonMap, SiteSearch};
use super::plan::{FogPlan, PhotonPlan, RenderPlan, ShadowSampling};
use super::sample::{Integrator, SampleContext};
use crate::accel::Accel;
use crate::bsdf::phong;
use crate::bsdf::specular::{reflect, DielectricInterface};
use crate::bsdf::{Bsdf, FresnelModel, LobeFlags, WhittedKind, WhittedSurface};
use crate::math::sampling::{stratified, stratum_order};
use crate::math::{offset_ray_origin, Frame, Ray, Vec2, Vec3A};
use crate::scene::light::{bounding_sphere, Emitter, EnvironmentMap};
use crate::scene::{Dielectric, Light, Material, Medium, Quad, Scene, SurfaceInteraction};
use std::f32::consts::PI;
use std::sync::Arc;

/// A shadow ray toward a light sample at distance `d` is tested on
/// `t < d (1 − SHADOW_EPSILON)`: relative, so it is right at every scene
/// scale, and it keeps geometry coplanar with an area light (a ceiling the
/// light is flush with) from occluding it (pbrt's `ShadowEpsilon`).
pub const SHADOW_EPSILON: f32 = 1.0e-4;

/// The Whitted integrator over one scene and accelerator.
pub struct Whitted<'a> {
    scene: &'a Scene,
    accel: &'a dyn Accel,
    plan: &'a RenderPlan,
    /// Area lights as rectangles, tested analytically by camera and specular
    /// rays (lights are not scene objects, so shadow rays never hit them).
    emitters: Vec<(Quad, Vec3A)>,
    /// The scene's lights behind the light interface, by index.
    light_emitters: Vec<Emitter>,
    /// The emitter of each object whose material emits.
    object_emitters: Vec<Option<Emitter>>,
    /// The caustic map and how to gather from it (none without photon pass).
    caustics: Option<(&'a PhotonMap, GatherParams)>,
    /// The fog, when the plan runs it.
    medium: Option<&'a Medium>,
    /// Radiance of the constant environment lights, seen by rays that leave the scene.
    environment: Vec3A,
    /// The environment images and their scales, seen likewise.
    environment_maps: Vec<(Vec3A, Arc<EnvironmentMap>)>,
}

impl<'a> Whitted<'a> {
    /// Prepares the integrator.
    pub fn new(scene: &'a Scene, accel: &'a dyn Accel, plan: &'a RenderPlan) -> Self {
        let emitters = scene
            .lights
            .iter()
            .filter_map(|l| match l {
                Light::Area(a) => Quad::new(a.center - (a.u + a.v) * 0.5, a.u, a.v).map(|q| (q, a.radiance)),
                _ => None,
            })
            .collect();
        let (center, radius) = bounding_sphere(scene);
        let light_emitters = scene
            .lights
            .iter()
            .map(|l| Emitter::of_light(l, center, radius))
            .collect();
        let mut object_emitters = vec![None; scene.objects.len()];
        for lp in &plan.lights {
            if let Some(o) = lp.object {
                object_emitters[o as usize] = Emitter::of_object(scene, o);
            }
        }
        let environment = scene.lights.iter().fold(Vec3A::ZERO, |sum, l| match l {
            Light::Environment { radiance, map: None } => sum + *radiance,
            _ => sum,
        });
        let environment_maps = scene
            .lights
            .iter()
            .filter_map(|l| match l {
                Light::Environment { radiance, map: Some(m) } => Some((*radiance, m.clone())),
                _ => None,
            })
            .collect();
        let medium = match plan.fog {
            FogPlan::Run { .. } => scene.water_medium.as_ref(),
            FogPlan::NoMedium | FogPlan::PathTraced => None,
        };
        Self {
            scene,
            accel,
            plan,
            emitters,
            light_emitters,
            object_emitters,
            environment,
            environment_maps,
            caustics: None,
            medium,
        }
    }

    /// Adds the caustic radiance estimate from `map` at diffuse surfaces,
    /// with the plan's gather settings (no effect when the plan skips the
    /// photon pass).
    pub fn with_photons(mut self, map: &'a PhotonMap) -> Self {
        if let PhotonPlan::Run {
            k, max_radius, cone_k, ..
        } = self.plan.photons
        {
            self.caustics = Some((
                map,
                GatherParams {
                    k: std::num::NonZero::new(k.max(1) as usize).expect("k ≥ 1"),
                    max_radius,
                    cone_k,
                    fixed_radius: None,
                },
            ));
        }
        self
    }

    /// Adds the caustic radiance estimate from `map` gathered with `g`
    /// instead of the plan's gather (progressive photon mapping: the fixed
    /// radius of the map's sample index); no effect when the plan skips the
    /// photon pass.
    pub fn with_photons_gathered(mut self, map: &'a PhotonMap, g: GatherParams) -> Self {
        if self.plan.runs_photons() {
            self.caustics = Some((map, g));
        }
        self
    }

    /// Radiance arriving along `ray` (toward its origin) after `depth`
    /// specular bounces.
    fn trace(&self, ray: &Ray, depth: u32, ctx: &mut SampleContext) -> Vec3A {
        let hit = self.accel.intersect(ray, f32::INFINITY);
        // A visible area light nearer than the surface: its emitting side
        // returns its radiance; seen from behind it is not there.
        let mut t_nearest = hit.map_or(f32::INFINITY, |h| h.t);
        let mut emitted = None;
        for (quad, radiance) in &self.emitters {
            if ray.dir.dot(quad.normal) < 0.0 {
                if let Some((t, _, _)) = quad.intersect(ray, t_nearest) {
                    t_nearest = t;
                    emitted = Some(*radiance);
                }
            }
        }
        // Emitters the camera sees directly, when the scene hides them.
        let hidden = depth == 0 && self.plan.hide_emitters;
        let l = match (emitted, hit) {
            (Some(_), _) if hidden => Vec3A::ZERO,
            (Some(l), _) => l,
            (None, None) if hidden => Vec3A::ZERO,
            (None, Some(hit)) => self.shade(ray, &hit, depth, ctx),
            (None, None) => self
                .environment_maps
                .iter()
                .fold(self.environment, |l, (scale, map)| l + *scale * map.eval(ray.dir)),
        };
        match self.medium {
            Some(m) => fog::apply(m, ray, t_nearest, l),
            None => l,
        }
    }

    /// Radiance leaving the surface hit by `ray` toward its origin.
    fn shade(&self, ray: &Ray, hit: &crate::geometry::Hit, depth: u32, ctx: &mut SampleContext) -> Vec3A {
        let si = self.scene.surface_interaction(ray, hit);
        let m = &*self.scene.materials[si.material as usize].at(si.uv);
        // An emitting surface seen from a side it emits from.
        let hidden = depth == 0 && self.plan.hide_emitters;
        let emitted = if m.emits_toward(ray.dir, si.ng) && !hidden {
            m.emission
        } else {
            Vec3A::ZERO
        };
        if m.blend.is_none() {
            return emitted + self.scatter(ray, &si, m, depth, ctx);
        }
        // A blend scatters as one of its sides; a hole lets the ray through.
        match m.resolve(si.uv, || ctx.rng.f32()) {
            Some(side) => emitted + self.scatter(ray, &si, &side, depth, ctx),
            None => emitted + self.trace_on(&si, ray.dir, depth, ctx),
        }
    }

    /// Radiance the surface at `si` reflects or transmits toward the ray's origin.
    fn scatter(&self, ray: &Ray, si: &SurfaceInteraction, m: &Material, depth: u32, ctx: &mut SampleContext) -> Vec3A {
        let si = *si;
        let (surface, bsdf) = WhittedSurface::with_bsdf(m);
        let mirror = match (surface.kind, bsdf) {
            (WhittedKind::Dielectric(d), _) => return self.dielectric(ray, &si, m, d, depth, ctx),
            (WhittedKind::Layered { .. }, Some(bsdf)) => {
                return self.layered(ray, &si, m, &bsdf, surface.flags, depth, ctx)
            }
            (WhittedKind::PassThrough, _) => return self.trace_on(&si, ray.dir, depth, ctx),
            (WhittedKind::Phong { mirror }, _) => mirror,
            (WhittedKind::Layered { .. }, None) => unreachable!("a layered surface comes with its BSDF"),
        };
        let local = self.direct(ray, &si, m, Local::Surface, surface.flags, ctx);
        match mirror {
            Some(mirror) if mirror.reflectivity > 0.0 => {
                let r = mirror.reflectivity;
                let reflected = if self.can_bounce(depth) {
                    let (ng, ns) = facing(&si, -ray.dir);
                    let mut dir = reflect(ray.dir, ns);
                    if dir.dot(ng) <= 0.0 {
                        // The shading normal would send the ray under the
                        // surface: reflect about the geometric one instead.
                        dir = reflect(ray.dir, ng);
                    }
                    self.trace_secondary(&si, dir, depth, ctx)
                } else {
                    Vec3A::ZERO // beyond the depth limit the reflection is black
                };
                local * (1.0 - r) + mirror.tint * reflected * r
            }
            _ => local,
        }
    }

    /// The ray continuing unchanged through a surface that lets it pass
    /// (a hole, a `null` surface); black beyond the depth limit.
    fn trace_on(&self, si: &SurfaceInteraction, dir: Vec3A, depth: u32, ctx: &mut SampleContext) -> Vec3A {
        if self.can_bounce(depth) {
            self.trace_secondary(si, dir, depth, ctx)
        } else {
            Vec3A::ZERO
        }
    }

    fn can_bounce(&self, depth: u32) -> bool {
        self.plan.traces_secondary() && depth < self.plan.max_depth
    }

    fn trace_secondary(&self, si: &SurfaceInteraction, dir: Vec3A, depth: u32, ctx: &mut SampleContext) -> Vec3A {
        let dir = dir.normalize();
        let origin = offset_ray_origin(si.p, si.p_error, si.ng, dir);
        ctx.counts.secondary += 1;
        self.trace(&Ray::new(origin, dir), depth + 1, ctx)
    }

    /// Local shading: ambient and direct light from every light, with
    /// shadow rays. `highlights_only` (dielectrics) keeps only the specular
    /// lobe of point lights, the one light a reflected ray can never find
    /// (area lights appear in the reflection itself).
    fn direct(
        &self,
        ray: &Ray,
        si: &SurfaceInteraction,
        m: &Material,
        local: Local,
        flags: LobeFlags,
        ctx: &mut SampleContext,
    ) -> Vec3A {
        let highlights_only = matches!(local, Local::Highlights);
        let wo = -ray.dir;
        let (ng, ns) = facing(si, wo);
        let has_ambient = match local {
            Local::Surface => true,
            Local::Highlights => false,
            Local::Bsdf(_) => m.coating.is_some(),
        };
        let mut out = if !has_ambient || !self.plan.ambient {
            Vec3A::ZERO
        } else {
            self.scene.ambient * m.ambient
        };
        let frame = match local {
            Local::Bsdf(b) => b.frame(ns, si.dpdu),
            _ => Frame::from_normal(ns),
        };
        let f = |wi: Vec3A| match local {
            Local::Surface => brdf(m, ns, wi, wo),
            Local::Highlights => specular_lobe(m, ns, wi, wo),
            Local::Bsdf(b) => b.eval(frame.to_local(wo), frame.to_local(wi)),
        };
        if highlights_only && m.specular.max_element() <= 0.0 {
            return out;
        }
        for lp in &self.plan.lights {
            if let Some(object) = lp.object {
                if let (false, Some(e), ShadowSampling::Stratified { strata, grid, .. }) =
                    (highlights_only, &self.object_emitters[object as usize], lp.shadow)
                {
                    let seed = object.wrapping_add(0x5bd1_e995);
                    out += self.stratified_emitter(si, (ng, ns), e, strata, grid, seed, &f, ctx);
                }
                continue;
            }
            match (&self.scene.lights[lp.index], lp.shadow) {
                (Light::Spot(_) | Light::Directional { .. }, _) => {
                    let Some(ls) = self.light_emitters[lp.index].sample_li(si.p, Vec2::ZERO) else {
                        continue;
                    };
                    let cos = ns.dot(ls.wi);
                    if ls.wi.dot(ng) <= 0.0 || cos <= 0.0 {
                        continue;
                    }
                    let visible = match ls.target {
                        Some(q) => self.unoccluded(si, q, ctx),
                        None => self.unoccluded_toward(si, ls.wi, ctx),
                    };
                    if visible {
                        out += f(ls.wi) * ls.li * cos;
                    }
                }
                (Light::Point { position, intensity }, _) => {
                    let to = *position - si.p;
                    let d2 = to.length_squared();
                    let wi = to / d2.sqrt();
                    let cos = ns.dot(wi);
                    // Light under the geometric surface, or behind the
                    // shading normal: no contribution (and no shadow ray).
                    if !d2.is_normal() || wi.dot(ng) <= 0.0 || cos <= 0.0 {
                        continue;
                    }
                    if !self.unoccluded(si, *position, ctx) {
                        continue;
                    }
                    out += f(wi) * *intensity * (cos / d2);
                }
                (Light::Area(_), _) if highlights_only => {}
                // Seen in rays that leave the scene only (the ambient term
                // stands for diffuse light in this model).
                (Light::Environment { .. }, _) | (_, ShadowSampling::Environment) => {}
                (
                    Light::Area(a),
                    ShadowSampling::Stratified {
                        strata, grid: (nx, ny), ..
                    },
                ) => {
                    // Which strata this sample evaluates and the weight of
                    // each: all N with weight 1/N (split), or the strata
                    // s ≡ slot (mod spp) with weight spp/N (spread: summed
                    // over the pixel's samples, every stratum once, and the
                    // pixel average is (1/N) Σ_s, the same estimator).
                    let (first, step, weight) = if self.plan.spread() {
                        (ctx.slot, self.plan.spp, self.plan.spp as f32 / strata as f32)
                    } else {
                        (0, 1, 1.0 / strata as f32)
                    };
                    let area = a.area();
                    let light_seed = ctx.light_seed ^ (lp.index as u32).wrapping_mul(0x9e37_79b9);
                    let mut sum = Vec3A::ZERO;
                    let mut s = first;
                    while s < strata {
                        let (jx, jy) = ctx.rng.f32x2();
                        let cell = stratum_order(s, nx, ny, light_seed);
                        let q = a.point(stratified(cell, nx, ny, Vec2::new(jx, jy)));
                        s += step;
                        let to = q - si.p;
                        let d2 = to.length_squared();
                        let wi = to / d2.sqrt();
                        let cos = ns.dot(wi);
                        let cos_light = -wi.dot(a.normal); // one-sided emitter
                        if !d2.is_normal() || cos_light <= 0.0 || wi.dot(ng) <= 0.0 || cos <= 0.0 {
                            continue;
                        }
                        if !self.unoccluded(si, q, ctx) {
                            continue;
                        }
                        sum += f(wi) * (cos * cos_light / d2);
                    }
                    out += sum * a.radiance * (area * weight);
                }
                (Light::Area(_), ShadowSampling::Hard) => {
                    unreachable!("RenderPlan gives every area light stratified sampling")
                }
            }
        }
        if !highlights_only && flags.contains(LobeFlags::DIFFUSE) {
            if let Some((map, g)) = &self.caustics {
                out += m.diffuse * (1.0 / PI) * map.caustic_irradiance_with(si.p, ng, g, SiteSearch::Cached, ctx.sites);
            }
        }
        out
    }

    /// Direct light from an emitting object by `strata` stratified samples
    /// of its light interface (spread over the pixel's samples as a
    /// rectangle's are): `Σ f · Li · cos θ / pdf`, weighted. `ng` and `ns`
    /// face the viewer.
    #[allow(clippy::too_many_arguments)]
    fn stratified_emitter(
        &self,
        si: &SurfaceInteraction,
        (ng, ns): (Vec3A, Vec3A),
        e: &Emitter,
        strata: u32,
        (nx, ny): (u32, u32),
        seed: u32,
        f: &dyn Fn(Vec3A) -> Vec3A,
        ctx: &mut SampleContext,
    ) -> Vec3A {
        let (first, step, weight) = if self.plan.spread() {
            (ctx.slot, self.plan.spp, self.plan.spp as f32 / strata as f32)
        } else {
            (0, 1, 1.0 / strata as f32)
        };
        let light_seed = ctx.light_seed ^ seed.wrapping_mul(0x9e37_79b9);
        let mut sum = Vec3A::ZERO;
        let mut s = first;
        while s < strata {
            let (jx, jy) = ctx.rng.f32x2();
            let cell = stratum_order(s, nx, ny, light_seed);
            let u = stratified(cell, nx, ny, Vec2::new(jx, jy));
            s += step;
            let Some(ls) = e.sample_li(si.p, u) else { continue };
            let Some(q) = ls.target else { continue };
            let cos = ns.dot(ls.wi);
            if ls.wi.dot(ng) <= 0.0 || cos <= 0.0 || !self.unoccluded(si, q, ctx) {
                continue;
            }
            sum += f(ls.wi) * ls.li * (cos / ls.pdf);
        }
        sum * weight
    }

    /// Casts a shadow ray from the (offset) shading point along `dir` and
    /// reports whether it leaves the scene.
    fn unoccluded_toward(&self, si: &SurfaceInteraction, dir: Vec3A, ctx: &mut SampleContext) -> bool {
        let origin = offset_ray_origin(si.p, si.p_error, si.ng, dir);
        ctx.counts.shadow += 1;
        !self.accel.occluded(&Ray::new(origin, dir), f32::INFINITY)
    }

    /// Casts a shadow ray from the (offset) shading point toward `target`
    /// and reports whether nothing blocks it before `target`.
    fn unoccluded(&self, si: &SurfaceInteraction, target: Vec3A, ctx: &mut SampleContext) -> bool {
        let origin = offset_ray_origin(si.p, si.p_error, si.ng, target - si.p);
        let to = target - origin;
        let dist = to.length();
        if !(dist > 0.0 && dist.is_finite()) {
            return false;
        }
        ctx.counts.shadow += 1;
        let ray = Ray::new(origin, to / dist);
        !self.accel.occluded(&ray, dist * (1.0 - SHADOW_EPSILON))
    }

    /// A metal or a coated diffuse: direct light on its non-delta lobes
    /// and, when it has one, the mirror reflection weighted by its Fresnel
    /// reflectance (a rough metal or coating shows no reflection in this
    /// model).
    #[allow(clippy::too_many_arguments)]
    fn layered(
        &self,
        ray: &Ray,
        si: &SurfaceInteraction,
        m: &Material,
        bsdf: &Bsdf,
        flags: LobeFlags,
        depth: u32,
        ctx: &mut SampleContext,
    ) -> Vec3A {
        let local = self.direct(ray, si, m, Local::Bsdf(bsdf), flags, ctx);
        let (_, ns) = facing(si, -ray.dir);
        let wo = bsdf.frame(ns, si.dpdu).to_local(-ray.dir);
        let weight = bsdf.delta_reflectance(wo);
        if weight == Vec3A::ZERO {
            return local;
        }
        if !self.can_bounce(depth) {
            return local;
        }
        let (ng, ns) = facing(si, -ray.dir);
        let mut dir = reflect(ray.dir, ns);
        if dir.dot(ng) <= 0.0 {
            dir = reflect(ray.dir, ng);
        }
        local + weight * self.trace_secondary(si, dir, depth, ctx)
    }

    /// A smooth dielectric interface (outside IOR 1, inside `d.ior`).
    fn dielectric(
        &self,
        ray: &Ray,
        si: &SurfaceInteraction,
        m: &Material,
        d: Dielectric,
        depth: u32,
        ctx: &mut SampleContext,
    ) -> Vec3A {
        let highlight = self.direct(ray, si, m, Local::Highlights, LobeFlags::NONE, ctx);
        if !self.can_bounce(depth) {
            return highlight;
        }
        let interface = DielectricInterface::of(ray.dir, si, &d);
        let DielectricInterface {
            reflected: reflected_dir,
            refracted,
            ..
        } = interface;
        let Some((refracted_dir, cos_i, cos_t)) = refracted else {
            // Total internal reflection: all the light is reflected.
            return highlight + self.trace_secondary(si, reflected_dir, depth, ctx);
        };
        let r = interface.reflectance(d.fresnel.unwrap_or(FresnelModel::Schlick), cos_i, cos_t);
        if self.plan.spread() {
            // One branch, chosen with probability R / (1 − R) and divided by
            // that probability: R·L_r / R and (1−R)·tint·L_t / (1−R). The
            // first choice of a sample is stratified over the pixel's
            // samples (u = (stratum + ξ) / spp), so a pixel reflects in
            // R·spp of its samples up to one, not a binomial count of them.
            let xi = ctx.rng.f32();
            let u = match ctx.fresnel_stratum.take() {
                Some(stratum) => (stratum as f32 + xi) / self.plan.spp as f32,
                None => xi,
            };
            if u < r {
                highlight + self.trace_secondary(si, reflected_dir, depth, ctx)
            } else {
                highlight + d.tint * self.trace_secondary(si, refracted_dir, depth, ctx)
            }
        } else {
            let lr = self.trace_secondary(si, reflected_dir, depth, ctx);
            let lt = self.trace_secondary(si, refracted_dir, depth, ctx);
            highlight + lr * r + d.tint * lt * (1.0 - r)
        }
    }
}

impl Integrator for Whitted<'_> {
    /// The camera ray's radiance, its hit found again (the Whitted
    /// integrator shades from its own query).
    fn radiance(&self, ray: &Ray, _first_hit: Option<&FirstHit>, ctx: &mut SampleContext) -> Vec3A {
        self.trace(ray, 0, ctx)
    }
}

/// Which lobes `Whitted::direct` lights.
#[derive(Clone, Copy)]
enum Local<'b> {
    /// The report's Phong surface: ambient, diffuse and highlight.
    Surface,
    /// The highlight alone, for point lights only (dielectrics).
    Highlights,
    /// The non-delta lobes of a metal or a coated diffuse.
    Bsdf(&'b Bsdf<'b>),
}

/// Geometric and shading normals turned toward `wo` (the viewer), both by
/// the geometric side so that they stay on the same side of the surface.
#[inline]
fn facing(si: &SurfaceInteraction, wo: Vec3A) -> (Vec3A, Vec3A) {
    if si.ng.dot(wo) < 0.0 {
        (-si.ng, -si.ns)
    } else {
        (si.ng, si.ns)
    }
}

/// The highlight of `m` alone, for world directions about the shading
/// normal `ns` (the lobes are `bsdf::phong`'s, written once).
#[inline]
fn specular_lobe(m: &Material, ns: Vec3A, wi: Vec3A, wo: Vec3A) -> Vec3A {
    let frame = Frame::from_normal(ns);
    phong::highlight(m, frame.to_local(wo), frame.to_local(wi))
}

/// Lambert + normalised Phong / Blinn-Phong BRDF of `m` (`bsdf::phong`).
#[inline]
fn brdf(m: &Material, ns: Vec3A, wi: Vec3A, wo: Vec3A) -> Vec3A {
    let frame = Frame::from_normal(ns);
    phong::surface(m, frame.to_local(wo), frame.to_local(wi))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::ShadingModel;

    #[test]
    fn lobes_are_energy_normalised() {
        // Integrate the Blinn-Phong and Phong lobes × cos θi over the
        // hemisphere for normal viewing: about 1 for every exponent
        // (Blinn's normalisation is approximate, within ~15%).
        let mut m = Material::diffuse("m", Vec3A::ZERO);
        m.specular = Vec3A::ONE;
        let n = Vec3A::Z;
        for model in [ShadingModel::Phong, ShadingModel::BlinnPhong] {
            m.model = model;
            for shininess in [1.0f32, 10.0, 100.0] {
                m.shininess = shininess;
                let steps = 400;
                let mut integral = 0.0f64;
                for i in 0..steps {
                    let theta = (i as f32 + 0.5) / steps as f32 * PI / 2.0;
                    for j in 0..steps {
                        let phi = (j as f32 + 0.5) / steps as f32 * 2.0 * PI;
                        let wi = Vec3A::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
                        let f = specular_lobe(&m, n, wi, Vec3A::Z).x;
                        let dw = theta.sin() * (PI / 2.0 / steps as f32) * (2.0 * PI / steps as f32);
                        integral += (f * theta.cos() * dw) as f64;
                    }
                }
                assert!(integral > 0.5 && integral < 1.15, "{model:?} n={shininess}: {integral}");
            }
        }
    }
}
