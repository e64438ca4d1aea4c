//! The render plan: what a scene needs, decided once before rendering, so
//! that nothing runs that the scene cannot use (a point light gets one shadow
//! ray, a scene without mirrors or glass spawns no secondary rays, sample
//! spreading only when there are several samples to spread over).
//!
//! The photon pass runs only when a specular object can cast a caustic (and
//! photons are emitted only toward those casters); fog only with a medium.
//! Each pass has its own "ran / skipped because ..." line in the `Display`
//! output.

use super::photon::{PhotonRules, TraceSettings};
use crate::bsdf::{material_flags, whitted_flags, LobeFlags};
use crate::math::SamplerKind;
use crate::scene::{
    AdaptiveGoal, CausticsMode, GatherMode, IntegratorKind, Light, RenderSettings, SampleSharing, Scene,
};
use std::fmt;

/// Bounces before the path integrator's Russian roulette may end a path.
pub const ROULETTE_DEPTH: u32 = 3;

/// Adaptive sampling: pixels stop once their neighbours' estimated relative
/// error is at most `threshold` (see `integrator::render::mark_converged`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adaptive {
    /// Relative standard error at which a pixel stops.
    pub threshold: f32,
    /// Samples every pixel takes before any stops.
    pub min_spp: u32,
    /// What `threshold` bounds.
    pub goal: AdaptiveGoal,
}

/// How the shadow rays of one light are cast.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadowSampling {
    /// Point light: one shadow ray per shading point (hard shadow).
    Hard,
    /// Area light: stratified jittered shadow rays over the rectangle.
    Stratified {
        /// Number of strata of the rectangle (`grid.0 × grid.1`). With
        /// split sampling every camera sample casts them all; with spread
        /// sampling they are shared out between the pixel's samples.
        strata: u32,
        /// Stratum grid from `math::sampling::grid_for(strata)`.
        grid: (u32, u32),
        /// Most shadow rays one camera sample casts toward this light.
        rays_per_sample: u32,
    },
    /// Constant environment: Whitted shows it in rays that leave the scene;
    /// path tracing also samples it.
    Environment,
}

/// The plan for one light.
#[derive(Clone, Debug, PartialEq)]
pub struct LightPlan {
    /// Index in `Scene::lights` (`usize::MAX` for an emitting object).
    pub index: usize,
    /// The emitting object, for an object whose material emits.
    pub object: Option<u32>,
    /// What kind of light it is, in words.
    pub kind: &'static str,
    /// Shadow sampling.
    pub shadow: ShadowSampling,
}

impl LightPlan {
    /// How messages name the light.
    pub fn label(&self) -> String {
        match self.object {
            Some(o) => format!("object {o} (emitting)"),
            None => format!("light {} ({})", self.index, self.kind),
        }
    }
}

/// Why samples do or do not share secondary work.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sharing {
    /// Spread: sample `k` of a pixel takes its own share of the area lights'
    /// strata and one Fresnel-weighted branch at dielectrics.
    Spread,
    /// Split because the settings ask for it.
    SplitRequested,
    /// Split because there is only one sample per pixel.
    SplitSingleSample,
    /// The path integrator draws every sample independently.
    Independent,
}

/// Secondary (reflected / refracted) rays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Secondary {
    /// Traced, up to `max_depth` bounces.
    Traced {
        /// Objects with a mirror or dielectric material.
        specular_objects: usize,
        /// Of which dielectric.
        dielectric_objects: usize,
    },
    /// No object uses a mirror or dielectric material.
    NoSpecularObject,
    /// Specular objects exist but `max_depth = 0`.
    DepthZero,
}

/// The photon pass (caustic map).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PhotonPlan {
    /// Photons are emitted, traced and gathered.
    Run {
        /// Photons emitted.
        count: u64,
        /// Specular objects the emission is restricted to.
        casters: usize,
        /// Photons gathered per estimate.
        k: u32,
        /// Largest gather radius (resolved: the scene's, or 2% of the
        /// scene bounds' diagonal).
        max_radius: f32,
        /// Cone-filter constant.
        cone_k: f32,
        /// How shading points evaluate the estimate (direct gathers whenever
        /// `progressive` is set: see [`ProgressivePlan`]).
        gather: crate::scene::GatherMode,
        /// Progressive photon mapping, when `[photons] progressive = true`:
        /// `count` is then the total over all sample indices.
        progressive: Option<ProgressivePlan>,
    },
    /// No object is a mirror or dielectric: there is no caustic.
    NoSpecularCaster,
    /// No light to emit from.
    NoLights,
    /// `max_depth = 0`: no specular bounce is followed.
    DepthZero,
    /// `[photons] count = 0`.
    CountZero,
    /// The path integrator finds caustics by path tracing.
    PathTraced,
}

/// The path integrator's homogeneous medium (`[medium]` with `absorption`
/// and `scattering`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MediumPlan {
    /// Free-flight sampling, transmittance on shadow rays, Henyey–Greenstein
    /// scattering.
    Run {
        /// Absorption coefficient.
        absorption: crate::math::Vec3A,
        /// Scattering coefficient.
        scattering: crate::math::Vec3A,
        /// Henyey–Greenstein asymmetry.
        g: f32,
    },
    /// Media bounded by objects, or null surfaces (Mitsuba's `volpath`):
    /// the volumetric path tracer (`integrator::volpath`).
    Bounded {
        /// Homogeneous media.
        media: usize,
        /// Objects whose material is `null` or a thin dielectric (rays pass
        /// straight through them).
        null_objects: usize,
        /// The camera starts in a medium.
        camera_inside: bool,
        /// `volpath`'s null surfaces (passed without a bounce), or Mitsuba
        /// `path`'s (delta bounces that block shadow rays).
        volumetric: bool,
    },
    /// No `[medium]`, or the Whitted integrator (its exponential fog).
    None,
    /// A `[medium]` with the fog's keys only.
    NoCoefficients,
}

/// Progressive photon mapping (Knaus & Zwicker 2011, "Progressive Photon
/// Mapping: A Probabilistic Approach"): sample index `s` of every pixel
/// gathers from its own independent map of [`photons_per_pass`](Self::photons_per_pass)
/// photons, all of them within the fixed radius `r_{s+1}`, where
/// `r_1 = max_radius` and `r_{i+1}² = r_i² (i + α)/(i + 1)`
/// (`photon::progressive`). A pixel's mean over its samples is then the
/// progressive estimate, whose bias and variance both vanish as samples grow.
/// The precomputed irradiance is skipped (each map serves one sample per
/// pixel: nothing to amortise) and photon files are refused (each pass
/// traces its own map).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProgressivePlan {
    /// Knaus & Zwicker's `α ∈ (0, 1)`.
    pub alpha: f32,
    /// Photons each sample index's map emits: `max(1, count / spp)`.
    pub photons_per_pass: u64,
}

/// Exponential fog.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FogPlan {
    /// Applied to camera and secondary rays (and attenuates photons).
    Run {
        /// Extinction per unit length.
        density: f32,
    },
    /// The scene has no `[medium]`.
    NoMedium,
    /// The exponential fog is the Whitted integrator's model only.
    PathTraced,
}

/// What a render will do, computed from the scene by [`RenderPlan::new`].
#[derive(Clone, Debug, PartialEq)]
pub struct RenderPlan {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Camera samples per pixel.
    pub spp: u32,
    /// Bounce limit (Whitted: specular bounces; path: every bounce,
    /// `u32::MAX` for none).
    pub max_depth: u32,
    /// The light transport algorithm.
    pub integrator: IntegratorKind,
    /// The sample generator.
    pub sampler: SamplerKind,
    /// Adaptive sampling, when a noise threshold is set.
    pub adaptive: Option<Adaptive>,
    /// Seed of the random streams.
    pub seed: u64,
    /// Ambient term active (scene ambient light is not black).
    pub ambient: bool,
    /// Emitters seen directly from the camera are black
    /// ([`RenderSettings::hide_emitters`]).
    pub hide_emitters: bool,
    /// One entry per light, in scene order.
    pub lights: Vec<LightPlan>,
    /// Secondary rays.
    pub secondary: Secondary,
    /// Sample sharing.
    pub sharing: Sharing,
    /// Photon pass.
    pub photons: PhotonPlan,
    /// How the photons scatter: the Whitted integrator's rules, or the path
    /// integrator's BSDFs and medium (`[photons] caustics = "map"`).
    pub photon_rules: PhotonRules,
    /// The path integrator's participating medium in the water.
    pub medium: MediumPlan,
    /// Fog.
    pub fog: FogPlan,
    /// Keep a coarse copy of every photon's position for the debug
    /// overlay (`--debug photons`); off by default: 6 bytes per photon.
    pub keep_photon_positions: bool,
    /// Trace the auxiliary images (albedo, normal) in each pixel's first
    /// samples: an extra camera ray per sample, so only when something
    /// reads them (denoising, an EXR, a checkpoint or a shard's partial,
    /// the viewer). `RenderPlan::new` sets it for a scene that denoises.
    pub aovs: bool,
    /// Keep the odd-sample half sums that estimate each pixel's noise for
    /// an EXR's error layer, checkpoints and partials (adaptive sampling
    /// keeps them regardless, see [`buffers`](Self::buffers)).
    pub noise: bool,
}

impl RenderPlan {
    /// Decides what runs for `scene` rendered with `settings`.
    pub fn new(scene: &Scene, settings: &RenderSettings) -> RenderPlan {
        let s = settings;
        let spp = s.spp.max(1);
        let sharing = if s.integrator == IntegratorKind::Path {
            Sharing::Independent
        } else if spp == 1 {
            Sharing::SplitSingleSample
        } else if s.sharing == SampleSharing::Split {
            Sharing::SplitRequested
        } else {
            Sharing::Spread
        };
        let spread = sharing == Sharing::Spread;
        let stratified = |n: u32| {
            let n = n.max(1);
            // Spreading needs at least one stratum per sample: with fewer
            // strata than samples the grid is refined to `spp` strata (one
            // shadow ray per sample).
            let strata = if spread { n.max(spp) } else { n };
            let rays_per_sample = if spread { strata.div_ceil(spp) } else { strata };
            ShadowSampling::Stratified {
                strata,
                grid: crate::math::sampling::grid_for(strata),
                rays_per_sample,
            }
        };
        let mut lights: Vec<LightPlan> = scene
            .lights
            .iter()
            .enumerate()
            .map(|(index, light)| {
                let (kind, shadow) = match light {
                    Light::Point { .. } => ("point", ShadowSampling::Hard),
                    Light::Spot(_) => ("spot", ShadowSampling::Hard),
                    Light::Directional { .. } => ("directional", ShadowSampling::Hard),
                    Light::Environment { .. } => ("environment", ShadowSampling::Environment),
                    Light::Area(a) => ("area", stratified(a.samples)),
                };
                LightPlan {
                    index,
                    object: None,
                    kind,
                    shadow,
                }
            })
            .collect();
        // Objects whose material emits: area lights of the object's shape.
        for (i, o) in scene.objects.iter().enumerate() {
            if scene.materials[o.material as usize].emits() {
                lights.push(LightPlan {
                    index: usize::MAX,
                    object: Some(i as u32),
                    kind: "area",
                    shadow: stratified(crate::scene::load::DEFAULT_AREA_LIGHT_SAMPLES),
                });
            }
        }
        let mut specular_objects = 0;
        let mut delta_objects = 0;
        let mut secondary_objects = 0;
        let mut dielectric_objects = 0;
        for o in &scene.objects {
            let m = &scene.materials[o.material as usize];
            // Whitted's model of the material (a rough dielectric is one
            // smooth interface there) and its BSDF's.
            let whitted = whitted_flags(m);
            if whitted.contains(LobeFlags::CASTS_CAUSTICS) {
                specular_objects += 1;
            }
            if material_flags(m).is_specular() {
                delta_objects += 1;
            }
            if whitted.intersects(LobeFlags::SPECULAR | LobeFlags::PASS_THROUGH) {
                secondary_objects += 1;
            }
            if whitted.contains(LobeFlags::SPECULAR | LobeFlags::TRANSMISSION) {
                dielectric_objects += 1;
            }
        }
        let path = s.integrator == IntegratorKind::Path;
        let max_depth = if path {
            s.max_depth.unwrap_or(u32::MAX)
        } else {
            s.whitted_depth()
        };
        let secondary = if secondary_objects == 0 {
            Secondary::NoSpecularObject
        } else if max_depth == 0 {
            Secondary::DepthZero
        } else {
            Secondary::Traced {
                specular_objects: secondary_objects,
                dielectric_objects,
            }
        };
        let ps = &s.photons;
        let physical = path && ps.caustics == CausticsMode::Map;
        let casters = if physical { delta_objects } else { specular_objects };
        let photons = if path && !physical {
            PhotonPlan::PathTraced
        } else if casters == 0 {
            PhotonPlan::NoSpecularCaster
        } else if !scene.lights.iter().any(Light::emits_photons) && !lights.iter().any(|l| l.object.is_some()) {
            PhotonPlan::NoLights
        } else if max_depth == 0 {
            PhotonPlan::DepthZero
        } else if ps.count == 0 {
            PhotonPlan::CountZero
        } else {
            PhotonPlan::Run {
                count: ps.count,
                casters,
                k: ps.k.max(1),
                max_radius: ps.max_radius.unwrap_or_else(|| default_gather_radius(scene)),
                cone_k: ps.cone_k,
                // Progressive maps serve one sample per pixel each:
                // nothing to precompute.
                gather: if ps.progressive { GatherMode::Direct } else { ps.gather },
                progressive: ps.progressive.then(|| ProgressivePlan {
                    alpha: ps.alpha,
                    photons_per_pass: super::photon::progressive::photons_per_pass(ps.count, spp),
                }),
            }
        };
        let medium = match scene.water_medium.as_ref().map(|m| m.volume) {
            Some(Some(v)) if path => MediumPlan::Run {
                absorption: v.absorption,
                scattering: v.scattering,
                g: v.g,
            },
            Some(None) if path => MediumPlan::NoCoefficients,
            _ if path && scene.is_volumetric() => MediumPlan::Bounded {
                media: scene.media.list.len(),
                null_objects: scene
                    .objects
                    .iter()
                    .filter(|o| {
                        let m = &scene.materials[o.material as usize];
                        m.null || m.is_thin_sheet()
                    })
                    .count(),
                camera_inside: scene.media.camera.is_some(),
                volumetric: scene.media.pass_through == crate::scene::PassThrough::Volumetric,
            },
            _ => MediumPlan::None,
        };
        let fog = match &scene.water_medium {
            Some(_) if path => FogPlan::PathTraced,
            Some(m) => FogPlan::Run { density: m.density },
            None => FogPlan::NoMedium,
        };
        RenderPlan {
            width: s.width,
            height: s.height,
            spp,
            max_depth,
            integrator: s.integrator,
            sampler: s.sampler_kind(),
            adaptive: s.noise_threshold.map(|threshold| Adaptive {
                threshold,
                min_spp: s.min_spp.clamp(2, spp.max(2)),
                goal: s.adaptive_goal,
            }),
            seed: s.seed,
            ambient: !path && scene.ambient.max_element() > 0.0,
            hide_emitters: s.hide_emitters,
            lights,
            secondary,
            sharing,
            photons,
            photon_rules: if physical {
                PhotonRules::Physical
            } else {
                PhotonRules::Whitted
            },
            medium,
            fog,
            keep_photon_positions: false,
            aovs: s.denoise,
            noise: false,
        }
    }

    /// The optional buffers a render with this plan keeps per pixel:
    /// adaptive sampling reads the noise estimate.
    pub fn buffers(&self) -> crate::film::Buffers {
        crate::film::Buffers {
            noise: self.noise || self.adaptive.is_some(),
            aovs: self.aovs,
        }
    }

    /// The photon paths' seed and bounce limit: the settings' `max_depth`,
    /// which [`max_depth`](Self::max_depth) holds resolved (`u32::MAX` for
    /// none).
    pub fn photon_trace(&self) -> TraceSettings {
        TraceSettings {
            seed: self.seed,
            max_depth: (self.max_depth != u32::MAX).then_some(self.max_depth),
        }
    }

    /// True when the photon pass runs.
    pub fn runs_photons(&self) -> bool {
        matches!(self.photons, PhotonPlan::Run { .. })
    }

    /// Progressive photon mapping's plan, when the photon pass runs
    /// progressively.
    pub fn progressive(&self) -> Option<ProgressivePlan> {
        match self.photons {
            PhotonPlan::Run { progressive, .. } => progressive,
            _ => None,
        }
    }

    /// True when samples spread shadow strata and dielectric branches.
    pub fn spread(&self) -> bool {
        self.sharing == Sharing::Spread
    }

    /// True when reflected / refracted rays are traced.
    pub fn traces_secondary(&self) -> bool {
        matches!(self.secondary, Secondary::Traced { .. })
    }
}

/// Default largest gather radius: 2% of the diagonal of the scene's bounds
/// (a caustic's detail scale in a room-sized scene; the k-nearest search
/// shrinks it wherever photons are dense).
pub fn default_gather_radius(scene: &Scene) -> f32 {
    let d = scene.bounds().extent().length();
    if d.is_finite() && d > 0.0 {
        0.02 * d
    } else {
        1.0
    }
}

/// Whether a stage of the render runs, and why or how.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum StageStatus {
    /// The stage runs; how.
    Ran(String),
    /// The stage is skipped; why.
    Skipped(String),
}

/// One stage of the render plan, as `caustic info` and `caustic render` report it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Stage {
    /// What the stage is ("photon pass", "light 0 (area)", ...).
    pub name: String,
    /// Whether it runs.
    pub status: StageStatus,
}

impl Stage {
    fn ran(name: impl Into<String>, how: String) -> Self {
        Self {
            name: name.into(),
            status: StageStatus::Ran(how),
        }
    }

    fn skipped(name: impl Into<String>, why: &str) -> Self {
        Self {
            name: name.into(),
            status: StageStatus::Skipped(why.to_string()),
        }
    }
}

impl fmt::Display for Stage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.status {
            StageStatus::Ran(how) if how.is_empty() => write!(f, "{}: ran", self.name),
            StageStatus::Ran(how) => write!(f, "{}: ran, {how}", self.name),
            StageStatus::Skipped(why) => write!(f, "{}: skipped ({why})", self.name),
        }
    }
}

impl RenderPlan {
    /// Every stage, in the order the render meets them.
    pub fn stages(&self) -> Vec<Stage> {
        let pixels = self.width as u64 * self.height as u64;
        let mut stages = vec![Stage::ran(
            "camera rays",
            format!(
                "{}x{} pixels x {} spp = {} rays (seed {}, {} sampler)",
                self.width,
                self.height,
                self.spp,
                pixels * self.spp as u64,
                self.seed,
                self.sampler.name()
            ),
        )];
        if self.integrator == IntegratorKind::Path {
            let depth = if self.max_depth == u32::MAX {
                "no depth limit".to_string()
            } else {
                format!("at most {} bounces", self.max_depth)
            };
            stages.push(Stage::ran(
                "path tracing",
                format!(
                    "next-event estimation with multiple importance sampling (power heuristic), \
                     Russian roulette after {} bounces, {depth}",
                    ROULETTE_DEPTH
                ),
            ));
            stages.push(Stage::skipped(
                "ambient term",
                "the path integrator computes indirect light",
            ));
        } else {
            stages.push(if self.ambient {
                Stage::ran("ambient term", String::new())
            } else {
                Stage::skipped("ambient term", "scene ambient light is black")
            });
        }
        if self.lights.is_empty() {
            stages.push(Stage::skipped("direct light and shadow rays", "no lights"));
        }
        for l in &self.lights {
            if self.integrator == IntegratorKind::Path {
                let how = match l.shadow {
                    ShadowSampling::Hard => "sampled by next-event estimation",
                    ShadowSampling::Stratified { .. } => "sampled by next-event estimation and hit by paths (MIS)",
                    ShadowSampling::Environment => {
                        "sampled (an image by its luminance) and hit by escaping paths (MIS)"
                    }
                };
                stages.push(Stage::ran(l.label(), how.into()));
                continue;
            }
            stages.push(match l.shadow {
                ShadowSampling::Environment => Stage::ran(l.label(), "seen by rays that leave the scene".into()),
                ShadowSampling::Hard => Stage::ran(l.label(), "hard shadow, 1 shadow ray per shading point".into()),
                ShadowSampling::Stratified {
                    strata,
                    grid,
                    rays_per_sample,
                } => Stage::ran(
                    l.label(),
                    if self.spread() {
                        format!(
                            "soft shadow, {strata} stratified jittered shadow rays per pixel ({}x{} strata) \
                             spread over {} samples, at most {rays_per_sample} per sample",
                            grid.0, grid.1, self.spp
                        )
                    } else {
                        format!(
                            "soft shadow, {strata} stratified jittered shadow rays per shading point ({}x{} strata)",
                            grid.0, grid.1
                        )
                    },
                ),
            });
        }
        // Path tracing's bounces are part of its own stage.
        if self.integrator == IntegratorKind::Whitted {
            stages.push(match self.secondary {
                Secondary::Traced {
                    specular_objects,
                    dielectric_objects,
                } => Stage::ran(
                    "secondary rays",
                    format!(
                        "{specular_objects} mirror/glass object(s) ({dielectric_objects} refracting), depth limit {}",
                        self.max_depth
                    ),
                ),
                Secondary::NoSpecularObject => Stage::skipped("secondary rays", "no mirror or dielectric object"),
                Secondary::DepthZero => Stage::skipped("secondary rays", "max depth is 0"),
            });
        }
        stages.push(match self.photons {
            PhotonPlan::Run {
                count,
                casters,
                k,
                max_radius,
                cone_k,
                gather,
                progressive,
            } if self.photon_rules == PhotonRules::Physical => Stage::ran(
                "photon pass",
                format!(
                    "{} through the path integrator's BSDFs, emission restricted to \
                     {casters} caster(s) with a delta lobe; caustics (L S+ D{}) from the map at every \
                     non-specular vertex, {}, cone filter k = {cone_k}, BSDF-weighted{}",
                    match progressive {
                        Some(p) => format!(
                            "progressive, {} photons per pass (one map per sample index, {} passes)",
                            p.photons_per_pass, self.spp
                        ),
                        None => format!("{count} photons"),
                    },
                    if matches!(self.medium, MediumPlan::Run { .. }) {
                        ", and L S+ V in the water"
                    } else {
                        ""
                    },
                    match progressive {
                        Some(p) => format!(
                            "every photon within r_i, r₁ = {max_radius:.4}, r_{{i+1}}² = r_i² (i + α)/(i + 1), α = {}",
                            p.alpha
                        ),
                        None => format!(
                            "gather {k} nearest ({} after the first) within {max_radius:.4}",
                            (k as usize / super::photon::INDIRECT_GATHER_DIVISOR).max(1)
                        ),
                    },
                    match gather {
                        GatherMode::Precomputed => format!("; on Lambert surfaces {gather}"),
                        GatherMode::Direct => String::new(),
                    }
                ),
            ),
            PhotonPlan::Run {
                count,
                casters,
                k,
                max_radius,
                cone_k,
                gather,
                progressive: None,
            } => Stage::ran(
                "photon pass",
                format!(
                    "{count} photons, emission restricted to {casters} specular caster(s); \
                     gather {k} nearest within {max_radius:.4}, cone filter k = {cone_k}, {gather}"
                ),
            ),
            PhotonPlan::Run {
                casters,
                max_radius,
                cone_k,
                progressive: Some(p),
                ..
            } => Stage::ran(
                "photon pass",
                format!(
                    "progressive, {} photons per pass (one map per sample index, {} passes), r₁ = {max_radius:.4}, \
                     α = {}, emission restricted to {casters} specular caster(s); gather every photon within \
                     r_i (r_{{i+1}}² = r_i² (i + α)/(i + 1)), cone filter k = {cone_k}, direct gathers \
                     (precomputed irradiance skipped: each map serves one sample per pixel)",
                    p.photons_per_pass, self.spp, p.alpha
                ),
            ),
            PhotonPlan::NoSpecularCaster => Stage::skipped("photon pass", "no specular caster"),
            PhotonPlan::NoLights => Stage::skipped("photon pass", "no lights"),
            PhotonPlan::DepthZero => Stage::skipped("photon pass", "max depth is 0"),
            PhotonPlan::CountZero => Stage::skipped("photon pass", "photon count is 0"),
            PhotonPlan::PathTraced => Stage::skipped(
                "photon pass",
                "the path integrator traces caustics as paths ([photons] caustics = \"path\")",
            ),
        });
        match self.medium {
            MediumPlan::Run {
                absorption,
                scattering,
                g,
            } => stages.push(Stage::ran(
                "medium",
                format!(
                    "homogeneous in the water: absorption {absorption:.3}, scattering {scattering:.3}, \
                     Henyey–Greenstein g = {g}; free flights, transmittance on shadow rays"
                ),
            )),
            MediumPlan::NoCoefficients => stages.push(Stage::skipped(
                "medium",
                "[medium] gives no `absorption` and `scattering` (the fog is the Whitted integrator's)",
            )),
            MediumPlan::Bounded {
                null_objects,
                volumetric: false,
                ..
            } => stages.push(Stage::ran(
                "media",
                format!(
                    "none (Mitsuba's `path` ignores them); {null_objects} null or thin-dielectric object(s) as \
                     `path` meets them: delta bounces that block shadow rays"
                ),
            )),
            MediumPlan::Bounded {
                media,
                null_objects,
                camera_inside,
                ..
            } => stages.push(Stage::ran(
                "media",
                format!(
                    "{media} homogeneous medium(s), {null_objects} null or thin-dielectric object(s), the camera in {}; \
                     volumetric path tracing: free flights, phase-function and light sampling, shadow rays \
                     through null and thin-dielectric surfaces",
                    if camera_inside { "a medium" } else { "vacuum" }
                ),
            )),
            MediumPlan::None => {}
        }
        stages.push(match self.fog {
            FogPlan::Run { density } => {
                Stage::ran("fog", format!("density {density} per unit length inside the water"))
            }
            FogPlan::NoMedium => Stage::skipped("fog", "no medium"),
            FogPlan::PathTraced => Stage::skipped("fog", "the exponential fog is the Whitted integrator's"),
        });
        stages.push(match self.sharing {
            Sharing::Spread => Stage::ran(
                "sample spreading",
                "area-light strata shared out over the pixel's samples; one Fresnel-weighted branch per sample \
                 at dielectrics, the first stratified over the pixel"
                    .into(),
            ),
            Sharing::SplitRequested => Stage::skipped(
                "sample spreading",
                "sharing = split: every sample casts all shadow rays and follows both branches",
            ),
            Sharing::SplitSingleSample => Stage::skipped("sample spreading", "1 sample per pixel: full splitting"),
            Sharing::Independent => Stage::skipped("sample spreading", "the path integrator samples independently"),
        });
        stages
    }

    /// The stages that do not run, with the reason.
    pub fn skipped(&self) -> Vec<Stage> {
        self.stages()
            .into_iter()
            .filter(|s| matches!(s.status, StageStatus::Skipped(_)))
            .collect()
    }
}

impl fmt::Display for RenderPlan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "render plan:")?;
        for stage in self.stages() {
            writeln!(f, "  {stage}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3A;
    use crate::scene::{AreaLight, Camera, LoadedScene, Material, Mirror, Object, RenderSettings, Shape, Sphere};

    fn plan_of(s: &LoadedScene) -> RenderPlan {
        RenderPlan::new(&s.scene, &s.settings)
    }

    fn scene(spp: u32, sharing: SampleSharing, mirror_used: bool) -> LoadedScene {
        let mirror = Material {
            mirror: Some(Mirror {
                reflectivity: 1.0,
                tint: Vec3A::ONE,
            }),
            ..Material::diffuse("mirror", Vec3A::ONE)
        };
        let ball = |material| Object {
            name: "ball".into(),
            shape: Shape::Sphere(Sphere {
                center: Vec3A::ZERO,
                radius: 1.0,
            }),
            material,
        };
        let scene = Scene {
            media: Default::default(),
            ambient: Vec3A::ZERO,
            water_medium: None,
            camera: Camera::new(Vec3A::Z * 5.0, Vec3A::ZERO, Vec3A::Y, 40.0).unwrap(),
            materials: vec![Material::diffuse("white", Vec3A::ONE), mirror],
            lights: vec![
                Light::Point {
                    position: Vec3A::Y * 3.0,
                    intensity: Vec3A::ONE,
                },
                Light::Area(AreaLight::new(Vec3A::Y * 3.0, Vec3A::X, Vec3A::Z, Vec3A::ONE, 32).unwrap()),
            ],
            meshes: vec![],
            objects: vec![ball(0), ball(if mirror_used { 1 } else { 0 })],
        };
        LoadedScene {
            scene,
            settings: RenderSettings {
                spp,
                sharing,
                ..Default::default()
            },
        }
    }

    #[test]
    fn point_lights_get_one_ray_and_area_lights_their_strata() {
        let plan = plan_of(&scene(1, SampleSharing::Spread, true));
        assert_eq!(plan.sharing, Sharing::SplitSingleSample);
        assert_eq!(plan.lights[0].shadow, ShadowSampling::Hard);
        assert_eq!(
            plan.lights[1].shadow,
            ShadowSampling::Stratified {
                strata: 32,
                grid: (4, 8),
                rays_per_sample: 32
            }
        );
        let spread = plan_of(&scene(4, SampleSharing::Spread, true));
        assert!(spread.spread());
        assert_eq!(
            spread.lights[1].shadow,
            ShadowSampling::Stratified {
                strata: 32,
                grid: (4, 8),
                rays_per_sample: 8
            }
        );
        // More samples than strata: refined to one stratum per sample.
        let many = plan_of(&scene(64, SampleSharing::Spread, true));
        assert!(matches!(
            many.lights[1].shadow,
            ShadowSampling::Stratified {
                strata: 64,
                rays_per_sample: 1,
                ..
            }
        ));
        let split = plan_of(&scene(4, SampleSharing::Split, true));
        assert_eq!(split.sharing, Sharing::SplitRequested);
        assert!(matches!(
            split.lights[1].shadow,
            ShadowSampling::Stratified {
                strata: 32,
                rays_per_sample: 32,
                ..
            }
        ));
    }

    #[test]
    fn secondary_rays_only_for_used_specular_materials() {
        let with = plan_of(&scene(1, SampleSharing::Split, true));
        assert!(with.traces_secondary());
        assert!(with
            .to_string()
            .contains("secondary rays: ran, 1 mirror/glass object(s)"));
        // The mirror material exists but no object uses it.
        let without = plan_of(&scene(1, SampleSharing::Split, false));
        assert_eq!(without.secondary, Secondary::NoSpecularObject);
        let text = without.to_string();
        assert!(
            text.contains("secondary rays: skipped (no mirror or dielectric object)"),
            "{text}"
        );
        assert!(
            text.contains("light 0 (point): ran, hard shadow, 1 shadow ray"),
            "{text}"
        );
        assert!(text.contains("ambient term: skipped"), "{text}");
        assert!(text.contains("sample spreading: skipped (1 sample per pixel"), "{text}");
        assert_eq!(without.photons, PhotonPlan::NoSpecularCaster);
        assert!(text.contains("photon pass: skipped (no specular caster)"), "{text}");
        assert!(text.contains("fog: skipped (no medium)"), "{text}");
        assert!(with.runs_photons());
        assert!(with
            .to_string()
            .contains("photon pass: ran, 1000000 photons, emission restricted to 1 specular caster(s)"));
        let mut s = scene(4, SampleSharing::Spread, true);
        s.settings.max_depth = Some(0);
        let flat = plan_of(&s);
        assert_eq!(flat.secondary, Secondary::DepthZero);
        assert_eq!(flat.photons, PhotonPlan::DepthZero);
        assert!(flat.to_string().contains("spread over 4 samples, at most 8 per sample"));
        s.scene.lights.clear();
        assert!(plan_of(&s).to_string().contains("skipped (no lights)"));
        assert_eq!(plan_of(&s).photons, PhotonPlan::NoLights);
    }

    /// The path integrator's caustic map is emitted toward the objects whose
    /// lobe flags have a specular lobe somewhere: a blend with a glass
    /// side and glTF's smooth principled glass count, a blend of diffuse
    /// and a hole, a rough principled metal and a diffuse surface do not.
    #[test]
    fn physical_casters_are_chosen_by_lobe_flags() {
        use crate::scene::{Blend, CausticsMode, Dielectric, Principled};
        let mut s = scene(1, SampleSharing::Spread, true);
        s.settings.integrator = IntegratorKind::Path;
        s.settings.photons.caustics = CausticsMode::Map;
        let white = Material::diffuse("white", Vec3A::ONE);
        let glass = Material {
            dielectric: Some(Dielectric::smooth(1.5, Vec3A::ONE)),
            ..Material::diffuse("glass", Vec3A::ZERO)
        };
        let blend = |first: Option<Material>, second: Option<Material>| Material {
            blend: Some(Box::new(Blend {
                weight: 0.3,
                weight_texture: None,
                first,
                second,
            })),
            ..Material::diffuse("blend", Vec3A::ONE)
        };
        let principled = |roughness: f32, metallic: f32, transmission: f32| Material {
            principled: Some(Principled {
                roughness,
                metallic,
                transmission,
                thin: false,
                ..Principled::default()
            }),
            ..Material::diffuse("principled", Vec3A::splat(0.8))
        };
        s.scene.materials = vec![
            white.clone(),
            blend(Some(white.clone()), Some(glass)),
            principled(0.0, 0.0, 1.0),
            blend(Some(white), None),
            principled(0.5, 1.0, 0.0),
        ];
        let ball = |material: u32| Object {
            name: "ball".into(),
            shape: Shape::Sphere(Sphere {
                center: Vec3A::X * material as f32 * 3.0,
                radius: 1.0,
            }),
            material,
        };
        s.scene.objects = (0..5).map(ball).collect();
        let casters = |s: &LoadedScene| match plan_of(s).photons {
            PhotonPlan::Run { casters, .. } => casters,
            other => panic!("no photon pass: {other:?}"),
        };
        assert_eq!(casters(&s), 2);
        assert_eq!(super::super::photon::emit::delta_casters(&s.scene).len(), 2);
        // Without the blend's glass side, one caster is left.
        s.scene.objects.remove(1);
        assert_eq!(casters(&s), 1);
        // Only the hole and the rough metal: no caster, no pass.
        s.scene.objects.remove(1);
        assert_eq!(plan_of(&s).photons, PhotonPlan::NoSpecularCaster);
    }
}
