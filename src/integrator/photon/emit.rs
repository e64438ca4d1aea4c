//! Photon emission and tracing (Jensen 1996), restricted to the specular
//! casters.
//!
//! **Only caustic paths (L S+ D) are traced.** A photon whose first hit is
//! not specular never enters the caustic map, so photons are emitted only
//! toward the bounding spheres of the specular objects ("projection maps",
//! Jensen §5.1.2), with their power renormalised so the estimate stays
//! unbiased:
//!
//! Let the casters' bounding spheres be seen from the emission point `x`
//! under cones `C_j` of half-angle `θ_j` (`sin θ_j = r_j / |c_j − x|`) and
//! solid angle `Ω_j = 2π(1 − cos θ_j)`. A cone is chosen with probability
//! `Ω_j / ΣΩ` and a direction uniformly inside it, so the direction density
//! on the sphere is `p(ω) = n(ω) / ΣΩ`, where `n(ω)` counts the cones that
//! contain `ω` (overlapping cones are the one-sample balance heuristic).
//! Every direction that can reach a caster has `p > 0`. The photon's power is
//! the emitted radiant intensity toward `ω` divided by the densities:
//!
//! - point light of intensity `I` (power `4πI`):
//!   `Φ_p = I · ΣΩ / (n(ω) · N · P_light)`; for one cone that is
//!   `Φ · (Ω/4π) / N`: the light's power times the solid-angle fraction
//!   covered, shared by the `N` photons;
//! - spot light: the same with `I` times the falloff toward `ω`;
//! - area light (a rectangle or an emitting object) of radiance `L`, area
//!   `A`, the point `x` uniform on it (density `1/A`):
//!   `Φ_p = L · A · max(0, cos θ) · ΣΩ / (n(ω) · N · P_light)` (the cosine
//!   of the one-sided emitter is applied to the power, and a direction
//!   behind the light carries nothing);
//! - directional light of irradiance `E`: `x` uniform on the disk of the
//!   scene's bounding sphere facing the light, the one direction of the
//!   light, `Φ_p = E · π r² / (N · P_light)` (no cones).
//!
//! When `x` lies inside a caster's bounding sphere the cone is the whole
//! sphere: that photon uses the light's full distribution instead (uniform
//! sphere for a point light, `Φ_p = 4πI / (N P)`; the cutoff cone for a
//! spot light; cosine-weighted hemisphere for an area light,
//! `Φ_p = π L A / (N P)`), which is also
//! unbiased since the choice depends on `x` only. A light is chosen with
//! probability `P_light` proportional to its power, among the lights that
//! have a caster in front of them (the others cannot light a caustic).
//!
//! **Tracing.** Mirrors: with probability `reflectivity` the photon reflects
//! with its power times the tint (Russian roulette keeps the power
//! otherwise constant); else, if the surface is also diffuse, it is stored
//! with power / (1 − reflectivity) (the expected stored flux is then the
//! incident flux, which Whitted weighs by `1 − reflectivity` as it does the
//! surface colour). Dielectrics: Fresnel–Schlick `R` chooses reflection
//! (probability `R`) or refraction (power × tint), with the entering /
//! leaving rules of `whitted.rs`; total internal reflection always
//! reflects. At a diffuse surface reached after at least one specular
//! bounce the photon is stored and stops. At most `max_depth` specular
//! bounces. Inside a medium the power is attenuated by `exp(−σ d)`.
//!
//! **Physically based rules** ([`PhotonRules::Physical`], for the path
//! integrator's caustic map): the casters are the objects whose BSDF has a
//! delta lobe, and each hit samples the path integrator's own BSDF
//! (exact Fresnel, importance transport): a delta lobe continues the
//! photon with the sample's weight; otherwise the photon is stored (after
//! at least one delta bounce) with its power divided by the probability of
//! not picking a delta lobe, and stops. "Specular" means exactly "a delta
//! lobe" on both sides, so the camera paths the map replaces are known
//! (see `integrator::path`). In the water's medium the photon takes a free
//! flight ([`crate::integrator::medium::Homogeneous::sample_flight`]); one that scatters after a delta
//! bounce is stored in the volume map (light shafts: L S+ V) and stops.

use super::map::Photon;
use crate::accel::{Accel, Hit};
use crate::bsdf::{reflect, DielectricInterface};
use crate::bsdf::{Bsdf, LobeFlags, Transport, WhittedKind, WhittedSurface};
use crate::integrator::fog;
use crate::integrator::medium::{Flight, MediumTracker, WaterVolume};
use crate::math::rng::{Domain, Rng};
use crate::math::sampling::{morton_stratified, uniform_cone};
use crate::math::{offset_ray_origin, Frame, Ray, Vec2, Vec3A};
use crate::scene::FresnelModel;
use crate::scene::{RenderSettings, Scene, Shape};
use std::f32::consts::PI;

/// Bounding sphere of a specular object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Caster {
    /// Centre.
    pub center: Vec3A,
    /// Radius.
    pub radius: f32,
}

/// The bounding spheres of the objects that cast caustics in Whitted's
/// model (a mirror, glass, a smooth metal: `LobeFlags::CASTS_CAUSTICS`
/// in `bsdf::whitted_flags`): exact for spheres, the box's circumscribed
/// sphere else.
pub fn specular_casters(scene: &Scene) -> Vec<Caster> {
    casters_where(scene, |m| {
        crate::bsdf::whitted_flags(m).contains(LobeFlags::CASTS_CAUSTICS)
    })
}

/// The bounding spheres of the objects whose material passes `keep`.
pub fn casters_where(scene: &Scene, keep: impl Fn(&crate::scene::Material) -> bool) -> Vec<Caster> {
    scene
        .objects
        .iter()
        .enumerate()
        .filter(|(_, o)| keep(&scene.materials[o.material as usize]))
        .map(|(i, o)| match &o.shape {
            Shape::Sphere(s) => Caster {
                center: s.center,
                radius: s.radius,
            },
            _ => {
                let b = scene.object_bounds(i);
                // Widened by a relative 1e-4 so rounding never puts a
                // surface point just outside.
                Caster {
                    center: b.center(),
                    radius: b.extent().length() * 0.5 * (1.0 + 1e-4),
                }
            }
        })
        .collect()
}

/// The objects whose BSDF has a delta lobe somewhere (its lobe flags,
/// `bsdf::material_flags`: either side of a blend, a textured roughness
/// that may be smooth): the casters of the physically based caustic map.
pub fn delta_casters(scene: &Scene) -> Vec<Caster> {
    casters_where(scene, |m| crate::bsdf::material_flags(m).is_specular())
}

/// Delta bounces the path integrator's caustic photons follow, and the most
/// a camera path may take after its map vertex for the light it then
/// reaches to count as a caustic (the same bound on both sides), when
/// `max_depth` is not set.
pub const PHOTON_PATH_DEPTH: u32 = 16;

/// How photons scatter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhotonRules {
    /// The Whitted integrator's rules (Schlick Fresnel, mirror
    /// reflectivity, stored at diffuse surfaces, fog attenuation).
    Whitted,
    /// The path integrator's BSDFs and the water's participating medium.
    Physical,
}

/// One light as an emitter: its casters (those not entirely behind an
/// area light) and its selection probability.
#[derive(Clone, Debug)]
struct Emitter {
    light: crate::scene::light::Emitter,
    casters: Vec<Caster>,
    probability: f32,
}

/// What photon tracing takes from the render settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TraceSettings {
    /// Seed of every photon's random stream.
    pub seed: u64,
    /// The render's bounce limit (`None`: the rules' default).
    pub max_depth: Option<u32>,
}

impl TraceSettings {
    /// The photon tracing of a render with `settings`.
    pub fn of(settings: &RenderSettings) -> Self {
        Self {
            seed: settings.seed,
            max_depth: settings.max_depth,
        }
    }
}

/// Emits and traces photons for one scene.
pub struct PhotonTracer<'a> {
    scene: &'a Scene,
    accel: &'a dyn Accel,
    emitters: Vec<Emitter>,
    /// Cumulative selection probabilities of `emitters`.
    cdf: Vec<f32>,
    /// Photons emitted in total (`N` in the power normalisation).
    count: u64,
    seed: u64,
    /// Fourth key of every photon's stream: 0 for the caustic map of a
    /// render, `1 + s` for progressive photon mapping's map of sample index
    /// `s` (see [`with_stream`](Self::with_stream)).
    stream: u64,
    max_depth: u32,
    rules: PhotonRules,
    /// The water's medium (physically based rules only).
    water: Option<WaterVolume<'a>>,
}

/// A photon in flight: its next ray, its power and its own random stream.
#[derive(Clone, Debug)]
pub struct PhotonPath {
    /// Emission index (orders the stored photons).
    pub index: u64,
    pub(super) rng: Rng,
    pub(super) ray: Ray,
    pub(super) power: Vec3A,
    pub(super) bounces: u32,
    /// In the water or not (physically based rules).
    pub(super) medium: MediumTracker,
}

impl PhotonPath {
    /// The ray the photon travels along next.
    pub fn ray(&self) -> &Ray {
        &self.ray
    }

    /// The power the photon carries.
    pub fn power(&self) -> Vec3A {
        self.power
    }
}

/// What a photon did at the end of its current ray.
#[derive(Clone, Copy, Debug)]
pub enum Step {
    /// Bounced off a specular surface: the path holds the next ray.
    Continue,
    /// Reached a diffuse surface after a specular bounce: stored.
    Stored(Photon),
    /// Scattered in the medium after a specular bounce: stored in the
    /// volume map (`normal` is unused).
    Scattered(Photon),
    /// Escaped, absorbed, or ended on a surface before any specular bounce.
    Done,
}

/// Photons traced together by [`PhotonTracer::trace_range`]: their rays go
/// to the accelerator as one batch per bounce.
const WAVEFRONT: usize = 256;

impl<'a> PhotonTracer<'a> {
    /// Prepares emission of `count` photons in total.
    pub fn new(scene: &'a Scene, settings: TraceSettings, accel: &'a dyn Accel, count: u64) -> Self {
        Self::with_casters(scene, settings, accel, count, specular_casters(scene))
    }

    /// Prepares emission of `count` photons under `rules`.
    pub fn with_rules(
        scene: &'a Scene,
        settings: TraceSettings,
        accel: &'a dyn Accel,
        count: u64,
        rules: PhotonRules,
    ) -> Self {
        match rules {
            PhotonRules::Whitted => Self::new(scene, settings, accel, count),
            PhotonRules::Physical => {
                let mut t = Self::with_casters(scene, settings, accel, count, delta_casters(scene));
                t.rules = rules;
                t.water = WaterVolume::of(scene);
                t.max_depth = settings.max_depth.unwrap_or(PHOTON_PATH_DEPTH);
                t
            }
        }
    }

    /// Like [`new`](Self::new), with emission restricted to `casters`.
    pub fn with_casters(
        scene: &'a Scene,
        settings: TraceSettings,
        accel: &'a dyn Accel,
        count: u64,
        casters: Vec<Caster>,
    ) -> Self {
        use crate::scene::light::Emitter as Light;
        let mut emitters: Vec<Emitter> = Light::all(scene)
            .into_iter()
            .map(|light| {
                let casters = match &light {
                    // Entirely behind the emitting plane: every direction to
                    // it has cos θ ≤ 0 and carries no power.
                    Light::Rect(a) => casters
                        .iter()
                        .copied()
                        .filter(|c| (c.center - a.center).dot(a.normal) > -c.radius)
                        .collect(),
                    _ => casters.clone(),
                };
                Emitter {
                    light,
                    casters,
                    probability: 0.0,
                }
            })
            .filter(|e| !e.casters.is_empty() && e.light.power().element_sum() > 0.0)
            .collect();
        let total: f32 = emitters.iter().map(|e| e.light.power().element_sum()).sum();
        let mut cdf = Vec::with_capacity(emitters.len());
        let mut acc = 0.0;
        for e in &mut emitters {
            e.probability = e.light.power().element_sum() / total;
            acc += e.probability;
            cdf.push(acc);
        }
        Self {
            scene,
            accel,
            emitters,
            cdf,
            count,
            seed: settings.seed,
            stream: 0,
            max_depth: settings.max_depth.unwrap_or(crate::scene::DEFAULT_WHITTED_DEPTH),
            rules: PhotonRules::Whitted,
            water: None,
        }
    }

    /// The same emission with every photon `i` drawing from
    /// `Rng::new(seed, Domain::Photon, i, stream)` instead of stream 0:
    /// an independent map with the same Morton-stratified emission
    /// (progressive photon mapping traces one per sample index).
    pub fn with_stream(mut self, stream: u64) -> Self {
        self.stream = stream;
        self
    }

    /// Number of casters emission is restricted to (over all lights, distinct).
    pub fn caster_count(&self) -> usize {
        match self.rules {
            PhotonRules::Whitted => specular_casters(self.scene).len(),
            PhotonRules::Physical => delta_casters(self.scene).len(),
        }
    }

    /// True when some light can light a caster.
    pub fn has_emitters(&self) -> bool {
        !self.emitters.is_empty()
    }

    /// Emits photon `index` from its own random stream: its first ray and
    /// power, or `None` when it carries nothing.
    pub fn emit(&self, index: u64) -> Option<PhotonPath> {
        if self.emitters.is_empty() {
            return None;
        }
        let mut rng = Rng::new(self.seed, Domain::Photon, index, self.stream);
        let u = rng.f32();
        let which = self.cdf.partition_point(|&c| c <= u).min(self.emitters.len() - 1);
        let e = &self.emitters[which];
        let scale = 1.0 / (self.count as f32 * e.probability);
        // Points draw no position (the maps of point lights predate the
        // other kinds and keep their streams).
        let u_origin = if e.light.is_point() {
            Vec2::ZERO
        } else {
            Vec2::from(rng.f32x2())
        };
        // An environment's photon picks its direction first, then where it
        // enters the scene's bounding disk (with the stratified sample).
        let (o, (pick, u)) = if e.light.is_environment() {
            let (pick, u) = self.direction_sample(index, &mut rng);
            (e.light.sample_environment_origin(u_origin, u)?, (pick, u))
        } else {
            let o = e.light.sample_origin(u_origin)?;
            (o, self.direction_sample(index, &mut rng))
        };
        let cones = if o.direction.is_some() {
            None
        } else {
            sample_cones(o.x, &e.casters, pick, u)
        };
        let (dir, power) = match cones {
            Some((dir, solid_angle)) => (dir, e.light.intensity(&o, dir) * solid_angle),
            None => e.light.sample_direction(&o, u),
        };
        if power.max_element() <= 0.0 {
            return None; // behind a one-sided emitter, or outside a spot's cone
        }
        let (origin, power) = (o.x, power * scale);
        let in_water = self.water.as_ref().is_some_and(|w| w.contains(origin));
        Some(PhotonPath {
            index,
            rng,
            ray: Ray::new(origin, dir),
            power,
            bounces: 0,
            medium: MediumTracker::new(in_water),
        })
    }

    /// Traces photons `first..last`, hands each stored one with its
    /// emission index to `store`, in index order, and returns the number of
    /// rays cast. The photons advance together: each bounce's rays (up to
    /// [`WAVEFRONT`] neighbouring photons, in index order, hence coherent)
    /// go to [`Accel::intersect_many`] as one batch. Each photon's path
    /// depends only on its own stream, so the result is the same as tracing
    /// them one by one. The buffers live for the whole range: nothing is
    /// allocated per wavefront, and stored photons go straight to `store`
    /// (the caller's packed arrays) instead of a growing list.
    /// `store` gets `true` with a photon of the volume map.
    pub fn trace_range(&self, first: u64, last: u64, mut store: impl FnMut(u64, Photon, bool)) -> u64 {
        let mut rays = 0u64;
        let mut batch: Vec<Ray> = Vec::with_capacity(WAVEFRONT);
        let mut hits: Vec<Option<Hit>> = Vec::with_capacity(WAVEFRONT);
        let mut paths: Vec<PhotonPath> = Vec::with_capacity(WAVEFRONT);
        let mut wave: Vec<(u64, Photon, bool)> = Vec::with_capacity(WAVEFRONT);
        let mut start = first;
        while start < last {
            let end = (start + WAVEFRONT as u64).min(last);
            paths.clear();
            paths.extend((start..end).filter_map(|i| self.emit(i)));
            wave.clear();
            while !paths.is_empty() {
                batch.clear();
                batch.extend(paths.iter().map(|p| p.ray));
                hits.clear();
                hits.resize(paths.len(), None);
                self.accel.intersect_many(&batch, f32::INFINITY, &mut hits);
                rays += paths.len() as u64;
                let mut kept = 0;
                for i in 0..paths.len() {
                    match self.step(&mut paths[i], hits[i]) {
                        Step::Continue => {
                            paths.swap(kept, i);
                            kept += 1;
                        }
                        Step::Stored(photon) => wave.push((paths[i].index, photon, false)),
                        Step::Scattered(photon) => wave.push((paths[i].index, photon, true)),
                        Step::Done => {}
                    }
                }
                paths.truncate(kept);
            }
            // Photons store in the order their paths ended: back to index order.
            wave.sort_unstable_by_key(|&(index, _, _)| index);
            for &(index, photon, volume) in &wave {
                store(index, photon, volume);
            }
            start = end;
        }
        rays
    }

    /// The cone choice and the 2-D direction sample of photon `index`:
    /// a Morton-ordered stratified sample over all the photons
    /// ([`morton_stratified`]), so that the photons of one rayon chunk leave
    /// in neighbouring directions and hit neighbouring geometry (coherent
    /// traversal and cache use, and a stored map already in spatial order),
    /// while the photons together stratify the directions.
    fn direction_sample(&self, index: u64, rng: &mut Rng) -> (f32, Vec2) {
        let xi = rng.u64();
        let m = morton_stratified(index, self.count.max(index + 1), xi, [rng.f32(), rng.f32(), rng.f32()]);
        (m[0], Vec2::new(m[1], m[2]))
    }

    /// Advances `path` past `hit`, the end of its current ray (`None`: it
    /// left the scene).
    pub fn step(&self, path: &mut PhotonPath, hit: Option<Hit>) -> Step {
        if self.rules == PhotonRules::Physical {
            return self.step_physical(path, hit);
        }
        let Some(hit) = hit else {
            return Step::Done;
        };
        let ray = path.ray;
        if let Some(m) = self.scene.water_medium.as_ref() {
            path.power *= fog::transmittance(m, &ray, hit.t);
        }
        let si = self.scene.surface_interaction(&ray, &hit);
        let wrapper = &*self.scene.materials[si.material as usize].at(si.uv);
        // A blend scatters as one of its sides; a hole lets the photon through.
        let side = if wrapper.blend.is_some() {
            wrapper.resolve(si.uv, || path.rng.f32())
        } else {
            Some(std::borrow::Cow::Borrowed(wrapper))
        };
        let surface = side.as_deref().map(WhittedSurface::of);
        let Some(surface) = surface.filter(|s| !matches!(s.kind, WhittedKind::PassThrough)) else {
            if path.bounces >= self.max_depth {
                return Step::Done;
            }
            path.bounces += 1;
            path.ray = Ray::new(offset_ray_origin(si.p, si.p_error, si.ng, ray.dir), ray.dir);
            return Step::Continue;
        };
        let dir = match surface.kind {
            WhittedKind::Dielectric(d) => {
                if path.bounces >= self.max_depth {
                    return Step::Done;
                }
                let interface = DielectricInterface::of(ray.dir, &si, &d);
                let DielectricInterface {
                    reflected, refracted, ..
                } = interface;
                match refracted {
                    None => reflected,
                    Some((t, cos_i, cos_t)) => {
                        let model = d.fresnel.unwrap_or(FresnelModel::Schlick);
                        if path.rng.f32() < interface.reflectance(model, cos_i, cos_t) {
                            reflected
                        } else {
                            path.power *= d.tint;
                            t
                        }
                    }
                }
            }
            WhittedKind::Layered {
                smooth_metal: Some(c), ..
            } => {
                // A smooth metal reflects with its Fresnel colour.
                if path.bounces >= self.max_depth {
                    return Step::Done;
                }
                let (ng, ns) = if si.ng.dot(ray.dir) > 0.0 {
                    (-si.ng, -si.ns)
                } else {
                    (si.ng, si.ns)
                };
                path.power *= crate::bsdf::fresnel::conductor(-ray.dir.dot(ns), c.eta, c.k);
                let mut dir = reflect(ray.dir, ns);
                if dir.dot(ng) <= 0.0 {
                    dir = reflect(ray.dir, ng);
                }
                dir
            }
            // (Pass-through surfaces were let through above.)
            kind => {
                // A mirror part reflects with probability `reflectivity`;
                // otherwise the photon ends here, stored on a diffuse part
                // after at least one bounce.
                let mirror = match kind {
                    WhittedKind::Phong { mirror } => mirror.filter(|mm| mm.reflectivity > 0.0),
                    _ => None,
                };
                let r = mirror.map_or(0.0, |mm| mm.reflectivity);
                let reflects = r > 0.0 && (r >= 1.0 || path.rng.f32() < r);
                let Some(mirror) = mirror.filter(|_| reflects) else {
                    if path.bounces >= 1 && surface.flags.contains(LobeFlags::DIFFUSE) {
                        let incoming = -ray.dir;
                        return Step::Stored(Photon {
                            position: si.p,
                            incoming,
                            // The side the photon arrived on: where the
                            // precomputed irradiance at this photon applies.
                            normal: if si.ng.dot(incoming) >= 0.0 { si.ng } else { -si.ng },
                            power: path.power / (1.0 - r),
                        });
                    }
                    return Step::Done;
                };
                if path.bounces >= self.max_depth {
                    return Step::Done;
                }
                path.power *= mirror.tint;
                let (ng, ns) = if si.ng.dot(ray.dir) > 0.0 {
                    (-si.ng, -si.ns)
                } else {
                    (si.ng, si.ns)
                };
                let mut dir = reflect(ray.dir, ns);
                if dir.dot(ng) <= 0.0 {
                    dir = reflect(ray.dir, ng);
                }
                dir
            }
        };
        if !path.power.is_finite() || path.power.max_element() <= 0.0 {
            return Step::Done;
        }
        path.bounces += 1;
        let dir = dir.normalize();
        path.ray = Ray::new(offset_ray_origin(si.p, si.p_error, si.ng, dir), dir);
        Step::Continue
    }
}

impl PhotonTracer<'_> {
    /// [`step`](PhotonTracer::step) under [`PhotonRules::Physical`].
    fn step_physical(&self, path: &mut PhotonPath, hit: Option<Hit>) -> Step {
        let ray = path.ray; // unit direction (emission and `Continue` normalise)
        if let Some(water) = self.water.as_ref().filter(|_| path.medium.inside()) {
            let exit = water.exit_distance(&ray);
            let d = hit.map_or(exit, |h| h.t.min(exit));
            match water.coefficients.sample_flight(d, path.rng.f32(), path.rng.f32()) {
                Flight::Scatter { t, weight } => {
                    path.power *= weight;
                    if path.bounces == 0 || !path.power.is_finite() || path.power.max_element() <= 0.0 {
                        return Step::Done;
                    }
                    return Step::Scattered(Photon {
                        position: ray.at(t),
                        incoming: -ray.dir,
                        normal: Vec3A::ZERO,
                        power: path.power,
                    });
                }
                Flight::Surface { weight } => path.power *= weight,
            }
            if hit.is_none_or(|h| h.t > exit) {
                return Step::Done; // left the water's box where no surface bounds it
            }
        }
        let Some(hit) = hit else {
            return Step::Done;
        };
        let si = self.scene.surface_interaction(&ray, &hit);
        let m = &*self.scene.materials[si.material as usize].at(si.uv);
        let side = if m.blend.is_some() {
            m.resolve(si.uv, || path.rng.f32())
        } else {
            Some(std::borrow::Cow::Borrowed(m))
        };
        let bsdf = Bsdf::for_resolved(side.as_deref(), FresnelModel::Exact, Transport::Importance);
        if bsdf.is_black() {
            return Step::Done;
        }
        let frame = bsdf.frame(si.ns, si.dpdu);
        let wo_world = -ray.dir;
        let wo = frame.to_local(wo_world);
        let uc = path.rng.f32();
        let u = path.rng.vec2();
        if !bsdf.picks_delta(wo, uc) {
            if path.bounces == 0 || !bsdf.has_smooth_lobe() {
                return Step::Done;
            }
            let p_smooth = 1.0 - bsdf.delta_probability(wo);
            if p_smooth <= 0.0 {
                return Step::Done;
            }
            return Step::Stored(Photon {
                position: si.p,
                incoming: wo_world,
                normal: if si.ng.dot(wo_world) >= 0.0 { si.ng } else { -si.ng },
                power: path.power / p_smooth,
            });
        }
        if path.bounces >= self.max_depth {
            return Step::Done;
        }
        let Some(s) = bsdf.sample(wo, uc, u) else {
            return Step::Done;
        };
        let dir = frame.to_world(s.wi).normalize();
        // The geometric side must agree with the shading one (no leaks).
        if (dir.dot(si.ng) * wo_world.dot(si.ng) > 0.0) != (s.wi.z * wo.z > 0.0) {
            return Step::Done;
        }
        path.power *= s.weight();
        if !path.power.is_finite() || path.power.max_element() <= 0.0 {
            return Step::Done;
        }
        if s.transmission {
            if let Some(water) = &self.water {
                let entering = ray.dir.dot(si.ng) < 0.0;
                path.medium.transmit(hit.instance, water.medium.boundary, entering);
            }
        }
        path.bounces += 1;
        path.ray = Ray::new(offset_ray_origin(si.p, si.p_error, si.ng, dir), dir);
        Step::Continue
    }
}

/// Samples a direction from `x` toward one of the casters' cones, chosen in
/// proportion to solid angle with `pick ∈ [0, 1)`, uniformly in the cone
/// with `v`. Returns the direction and `ΣΩ / n(ω)` (the
/// inverse of the direction's density), or `None` when `x` is inside a
/// caster's sphere (the caller then uses the full distribution).
pub fn sample_cones(x: Vec3A, casters: &[Caster], pick: f32, v: Vec2) -> Option<(Vec3A, f32)> {
    // (axis, cos θ, Ω) per caster; 1 − cos θ computed as s²/(1 + cos θ)
    // with s = sin θ, stable for tiny or distant casters.
    let mut total = 0.0f32;
    let mut cones: Vec<(Vec3A, f32, f32)> = Vec::with_capacity(casters.len());
    for c in casters {
        let to = c.center - x;
        let d2 = to.length_squared();
        let r2 = c.radius * c.radius;
        if d2 <= r2 {
            return None;
        }
        let sin2 = r2 / d2;
        let cos = (1.0 - sin2).sqrt();
        let omega = 2.0 * PI * sin2 / (1.0 + cos);
        total += omega;
        cones.push((to / d2.sqrt(), cos, omega));
    }
    // Choose a cone by solid angle.
    let mut pick = pick * total;
    let mut chosen = cones.len() - 1;
    for (j, c) in cones.iter().enumerate() {
        if pick < c.2 {
            chosen = j;
            break;
        }
        pick -= c.2;
    }
    let (axis, cos_max, _) = cones[chosen];
    let dir = Frame::from_normal(axis).to_world(uniform_cone(v, cos_max)).normalize();
    // n(ω): the chosen cone always counts (rounding must not drop it).
    let n = 1 + cones
        .iter()
        .enumerate()
        .filter(|&(j, c)| j != chosen && dir.dot(c.0) >= c.1)
        .count();
    Some((dir, total / n as f32))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::sampling::uniform_sphere;

    #[test]
    fn cone_sampling_density_integrates_to_one() {
        // Two overlapping cones: E[ΣΩ/n(ω) · 1{ω in union}] over the
        // sampled ω equals the solid angle of the union, which is also
        // what a uniform-sphere estimate gives.
        let casters = [
            Caster {
                center: Vec3A::new(0.0, 0.0, 3.0),
                radius: 1.0,
            },
            Caster {
                center: Vec3A::new(0.8, 0.0, 3.0),
                radius: 1.2,
            },
        ];
        let mut rng = Rng::new(9, Domain::Analysis, 0, 0);
        let n = 400_000;
        let mut sampled = 0.0f64;
        let mut uniform = 0.0f64;
        for _ in 0..n {
            let u = Vec2::from(rng.f32x2());
            let v = Vec2::from(rng.f32x2());
            let (dir, w) = sample_cones(Vec3A::ZERO, &casters, u.x, v).unwrap();
            assert!((dir.length() - 1.0).abs() < 1e-4);
            sampled += w as f64;
            let d = uniform_sphere(Vec2::from(rng.f32x2()));
            let inside = casters.iter().any(|c| {
                let a = c.center.normalize();
                let cos = (1.0 - c.radius * c.radius / c.center.length_squared()).sqrt();
                d.dot(a) >= cos
            });
            if inside {
                uniform += 4.0 * std::f64::consts::PI;
            }
        }
        let (sampled, uniform) = (sampled / n as f64, uniform / n as f64);
        assert!((sampled / uniform - 1.0).abs() < 0.02, "{sampled} vs {uniform}");
        // Inside a sphere: no restriction possible.
        assert!(sample_cones(Vec3A::new(0.0, 0.0, 2.5), &casters, 0.0, Vec2::ZERO).is_none());
    }
}
