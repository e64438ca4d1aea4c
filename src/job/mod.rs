//! A render job: one scene rendered with one accelerator, from a fresh or
//! resumed accumulation, to PNG / EXR / checkpoint files. `caustic render`
//! (whole, resumed or sharded) goes through it, so resume, fingerprints,
//! checkpoints and outputs behave the same for every such render. The measurements
//! (`analysis::bench`, `converge`, `stress`) and the viewer's render thread
//! call the integrator directly: they time or cancel the render alone and
//! write no checkpoint (ARCHITECTURE.md, "Doors to rendering").
//!
//! A job is made in two steps so that bad input is refused before any work:
//! [`RenderJob::prepare`] loads the scene, applies the overrides (checked like
//! the scene file's values), reads and checks a checkpoint to resume, and
//! checks that every output can be written; [`RenderJob::run`] builds the
//! accelerator, renders (photon pass, progressive passes, periodic
//! checkpoints, cancel) and writes the outputs atomically.

pub mod fingerprint;
pub mod interrupt;
pub mod merge;
pub mod photons;
pub mod shard_env;

pub use fingerprint::fingerprint;
pub use interrupt::Interrupt;
pub use merge::{merge_partials, MergeReport, MergeRequest};
pub use photons::{trace_to_file, PhotonsReport, PhotonsRequest};
pub use shard_env::{parse_shard_arg, shard_from_env};

use crate::accel::{self, Accel, AccelError, AccelKind, AccelOptions, AccelStats};
use crate::film::denoise::{self, DenoiseError, DenoiseQuality, DenoiseStats, Guides};
use crate::film::{self, Accumulation, CheckpointError, CheckpointMeta, Film, OutputError, ShardMode, ShardSet};
use crate::geometry::TriangleTest;
use crate::integrator::lint;
use crate::integrator::photon::TracedPhotons;
use crate::integrator::{self, debug, RenderOutput, RenderPlan};
use crate::math::SamplerKind;
use crate::scene::{self, IntegratorKind, LoadedScene, RenderSettings, Scene, SceneError};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};
use thiserror::Error;

/// Values given on the command line (or by a caller) that replace the scene
/// file's. Each is validated like the file's own value.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Overrides {
    /// Image width.
    pub width: Option<u32>,
    /// Image height.
    pub height: Option<u32>,
    /// Samples per pixel.
    pub spp: Option<u32>,
    /// Seed of every random stream.
    pub seed: Option<u64>,
    /// Photons emitted by the caustic pass (0 turns it off).
    pub photons: Option<u64>,
    /// Progressive photon mapping on or off (`[photons] progressive`).
    pub progressive_photons: Option<bool>,
    /// Progressive photon mapping's `α ∈ (0, 1)` (`[photons] alpha`).
    pub ppm_alpha: Option<f32>,
    /// Ray–triangle test of the in-house accelerators.
    pub triangle_test: Option<TriangleTest>,
    /// Light transport algorithm.
    pub integrator: Option<IntegratorKind>,
    /// Sample generator.
    pub sampler: Option<SamplerKind>,
    /// Adaptive sampling's relative error target.
    pub noise_threshold: Option<f32>,
    /// Samples every pixel takes before adaptive sampling stops any.
    pub min_spp: Option<u32>,
    /// What the noise threshold bounds.
    pub adaptive_goal: Option<crate::scene::AdaptiveGoal>,
    /// Denoise the final image (Open Image Denoise).
    pub denoise: Option<bool>,
    /// The denoising filter's quality.
    pub denoise_quality: Option<DenoiseQuality>,
    /// How the path integrator finds caustics.
    pub caustics: Option<crate::scene::CausticsMode>,
    /// `-D name=value` parameters of a Mitsuba scene, used when the file is
    /// read (see [`crate::scene::load_scene_with`]).
    pub defines: Vec<(String, String)>,
    /// A glTF model's camera by name or index (`--camera`), chosen when
    /// the file is read.
    pub camera: Option<String>,
    /// Let a glTF model's URIs name files outside its folder
    /// (`--allow-outside-files`).
    pub allow_outside_files: bool,
    /// A latitude-longitude image (`.hdr`, `.exr`) that replaces the
    /// scene's environment light, or lights a scene without one
    /// (`--environment`).
    pub environment: Option<PathBuf>,
    /// Multiplies the environment light's radiance (`--environment-intensity`).
    pub environment_intensity: Option<f32>,
    /// Turns the environment image about the world's up axis (+y), in
    /// degrees, counter-clockwise seen from above (`--environment-rotation`).
    pub environment_rotation: Option<f32>,
}

impl Overrides {
    /// What the scene's front end needs to read the file (`-D`, `--camera`,
    /// `--allow-outside-files`).
    pub fn load_options(&self) -> scene::LoadOptions {
        scene::LoadOptions {
            defines: self.defines.clone(),
            gltf: scene::gltf::GltfOptions {
                camera: self.camera.as_deref().map(|c| c.parse().expect("infallible")),
                allow_outside_files: self.allow_outside_files,
            },
        }
    }

    /// Applies `--environment`, `--environment-intensity` and
    /// `--environment-rotation` to the scene's lights.
    fn apply_environment(&self, scene: &mut Scene, source: &Path) -> Result<(), JobError> {
        use crate::math::{Mat3A, Vec3A};
        use crate::scene::light::EnvironmentMap;
        use crate::scene::Light;
        if self.environment.is_none() && self.environment_intensity.is_none() && self.environment_rotation.is_none() {
            return Ok(());
        }
        let rotation = match self.environment_rotation {
            Some(deg) if !deg.is_finite() => {
                return Err(JobError::Invalid(format!(
                    "--environment-rotation {deg}: must be finite"
                )))
            }
            Some(deg) => Mat3A::from_rotation_y(deg.to_radians()),
            None => Mat3A::IDENTITY,
        };
        let scale = match self.environment_intensity {
            Some(k) if !(k.is_finite() && k >= 0.0) => {
                return Err(JobError::Invalid(format!("--environment-intensity {k}: must be ≥ 0")))
            }
            Some(k) => k,
            None => 1.0,
        };
        if let Some(path) = &self.environment {
            let image = crate::io::image::load_image(path, crate::texture::ColourSpace::Srgb)
                .map_err(|e| JobError::Invalid(format!("--environment: {e}")))?;
            let map = std::sync::Arc::new(EnvironmentMap::new(std::sync::Arc::new(image), rotation));
            scene.lights.retain(|l| !matches!(l, Light::Environment { .. }));
            scene.lights.push(Light::Environment {
                radiance: Vec3A::splat(scale),
                map: Some(map),
            });
            return Ok(());
        }
        let mut found = false;
        for light in &mut scene.lights {
            if let Light::Environment { radiance, map } = light {
                found = true;
                *radiance *= scale;
                if let (Some(m), Some(_)) = (map.as_mut(), self.environment_rotation) {
                    *m = std::sync::Arc::new(EnvironmentMap::new(m.image.clone(), rotation * m.to_world));
                }
            }
        }
        if !found {
            return Err(JobError::Invalid(format!(
                "{}: --environment-intensity and --environment-rotation need an environment light (the scene has none; give one with --environment)",
                source.display()
            )));
        }
        Ok(())
    }

    /// Applies the overrides to `loaded` (read from `source`): the one
    /// place where the command line's values replace the file's settings
    /// (and its environment light), refusing values beyond the limits with
    /// the file named in the message.
    pub fn apply(&self, loaded: &mut LoadedScene, source: &Path) -> Result<(), JobError> {
        let LoadedScene { scene, settings } = loaded;
        self.apply_environment(scene, source)?;
        // Media and null surfaces are the path integrator's alone.
        let volumetric = scene.is_volumetric();
        let s = settings;
        s.width = self.width.unwrap_or(s.width);
        s.height = self.height.unwrap_or(s.height);
        s.spp = self.spp.unwrap_or(s.spp);
        s.seed = self.seed.unwrap_or(s.seed);
        if let Some(n) = self.photons {
            crate::limits::check_photon_count(n)
                .map_err(|e| JobError::Invalid(format!("{}: --photons: {e}", source.display())))?;
            s.photons.count = n;
        }
        if let Some(p) = self.progressive_photons {
            s.photons.progressive = p;
        }
        if let Some(a) = self.ppm_alpha {
            if !(a > 0.0 && a < 1.0) {
                return Err(JobError::Invalid(format!(
                    "--ppm-alpha {a}: must be in (0, 1) (the fraction of photons each progressive pass keeps; \
                     2/3 by default)"
                )));
            }
            s.photons.alpha = a;
        }
        if let Some(t) = self.triangle_test {
            s.triangle_test = t;
        }
        if let Some(i) = self.integrator {
            if volumetric && i == IntegratorKind::Whitted {
                return Err(JobError::Invalid(format!(
                    "{}: --integrator whitted: the scene has participating media or null / thin-dielectric \
                     surfaces, which only the path integrator renders",
                    source.display()
                )));
            }
            s.integrator = i;
        }
        if let Some(k) = self.sampler {
            s.sampler = Some(k);
        }
        if let Some(e) = self.noise_threshold {
            if !(e > 0.0 && e < 1.0) {
                return Err(JobError::Invalid(format!(
                    "--noise-threshold {e}: must be in (0, 1), a relative error such as 0.02"
                )));
            }
            s.noise_threshold = Some(e);
        }
        if let Some(n) = self.min_spp {
            if n < 2 || n > s.spp.max(2) {
                return Err(JobError::Invalid(format!(
                    "--min-spp {n}: must be in 2..={} (the samples per pixel)",
                    s.spp.max(2)
                )));
            }
            s.min_spp = n;
        }
        if let Some(g) = self.adaptive_goal {
            s.adaptive_goal = g;
        }
        if let Some(d) = self.denoise {
            s.denoise = d;
        }
        if let Some(q) = self.denoise_quality {
            s.denoise_quality = q;
        }
        if let Some(c) = self.caustics {
            if volumetric && c == crate::scene::CausticsMode::Map {
                return Err(JobError::Invalid(format!(
                    "{}: --caustics map: the volumetric path tracer (media, null or thin-dielectric \
                     surfaces) traces caustics as paths",
                    source.display()
                )));
            }
            s.photons.caustics = c;
        }
        crate::limits::check_image_limits(s.width, s.height, s.spp)
            .map_err(|e| JobError::Invalid(format!("{}: with the command-line overrides: {e}", source.display())))
    }
}

/// A debug view drawn over the finished image (the original report's `p`
/// and `k` keys, offline).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DebugView {
    /// The photon map's photons as points.
    Photons,
    /// The KD-tree's cells, down to this depth.
    KdTree {
        /// Deepest level drawn.
        depth: u32,
    },
}

/// What to render and where the results go.
#[derive(Clone, Debug)]
pub struct RenderRequest {
    /// Scene file.
    pub scene: PathBuf,
    /// Values replacing the scene file's.
    pub overrides: Overrides,
    /// Accelerator (`None`: the checkpoint's when resuming, else the default).
    pub accel: Option<AccelKind>,
    /// Embree build quality: "low", "medium" or "high".
    pub embree_quality: String,
    /// Embree robust traversal.
    pub embree_robust: bool,
    /// Tone-mapped PNG output.
    pub png: Option<PathBuf>,
    /// Linear EXR output.
    pub exr: Option<PathBuf>,
    /// Checkpoint file, saved periodically and when the render stops
    /// (default when resuming: the resumed file).
    pub checkpoint: Option<PathBuf>,
    /// Least time between two checkpoints.
    pub checkpoint_every: Duration,
    /// Checkpoint to continue.
    pub resume: Option<PathBuf>,
    /// Debug overlay.
    pub debug: Option<DebugView>,
    /// Stop sampling when this much time has passed since the job started
    /// (the accelerator build and the photon pass included) and write the
    /// image so far.
    pub time_limit: Option<Duration>,
    /// Render only this shard (a [`ShardSet::single`]) and write it as a
    /// partial to `checkpoint` (required then), saved periodically like a
    /// checkpoint. When resuming a partial, `None` takes the partial's shard.
    pub shard: Option<ShardSet>,
    /// Photons traced beforehand (`caustic photons`) to build the caustic
    /// map from instead of tracing it; refused unless its fingerprint is
    /// this render's.
    pub photon_map: Option<PathBuf>,
}

impl RenderRequest {
    /// A request for `scene` with every setting from the scene file, no output.
    pub fn new(scene: impl Into<PathBuf>) -> Self {
        let defaults = AccelOptions::default();
        Self {
            scene: scene.into(),
            overrides: Overrides::default(),
            accel: None,
            embree_quality: defaults.embree_quality,
            embree_robust: defaults.embree_robust,
            png: None,
            exr: None,
            checkpoint: None,
            checkpoint_every: Duration::from_secs(60),
            resume: None,
            debug: None,
            time_limit: None,
            shard: None,
            photon_map: None,
        }
    }
}

/// Why a job could not be prepared or run.
#[derive(Debug, Error)]
pub enum JobError {
    /// The scene file is missing or invalid.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The checkpoint to resume is unreadable or invalid.
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    /// An output cannot be written.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// A setting or override is out of range, or the checkpoint is of
    /// another render.
    #[error("{0}")]
    Invalid(String),
    /// The accelerator could not be built.
    #[error(transparent)]
    Accel(#[from] AccelError),
    /// The image could not be denoised (or this build cannot denoise).
    #[error(transparent)]
    Denoise(#[from] DenoiseError),
    /// Stopped by a signal before the first sample: nothing was written.
    #[error("interrupted before the first sample: nothing written")]
    StoppedBeforeFirstSample,
}

impl JobError {
    /// True for errors in the user's input (exit code 2), false for
    /// failures of the renderer or the machine.
    pub fn is_bad_input(&self) -> bool {
        !matches!(
            self,
            JobError::Accel(_) | JobError::StoppedBeforeFirstSample | JobError::Denoise(DenoiseError::Oidn(_))
        )
    }
}

/// A job ready to run: the scene with its final settings, the accelerator,
/// the accumulation to continue and the outputs, all checked.
///
/// ```
/// use caustic::accel::AccelKind;
/// use caustic::job::{JobHooks, RenderJob, RenderRequest};
///
/// let dir = tempfile::tempdir()?;
/// let mut request = RenderRequest::new(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/test/shadow.toml"));
/// request.overrides.width = Some(32);
/// request.overrides.height = Some(24);
/// request.accel = Some(AccelKind::KdTree);
/// request.png = Some(dir.path().join("shadow.png"));
/// let report = RenderJob::prepare(&request)?.run(&JobHooks::silent())?;
/// assert!(report.output.complete);
/// assert!(dir.path().join("shadow.png").is_file());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct RenderJob {
    /// The scene, with the overrides applied.
    pub scene: Scene,
    /// The render settings, with the overrides applied.
    pub settings: RenderSettings,
    /// Where the scene came from (for messages).
    pub source: PathBuf,
    /// Accelerator.
    pub accel: AccelKind,
    /// How it is built.
    pub accel_options: AccelOptions,
    /// Tone-mapped PNG output.
    pub png: Option<PathBuf>,
    /// Linear EXR output.
    pub exr: Option<PathBuf>,
    /// Checkpoint file and what it records.
    pub checkpoint: Option<(PathBuf, CheckpointMeta)>,
    /// Least time between two checkpoints.
    pub checkpoint_every: Duration,
    /// The accumulation the render continues (empty for a fresh render).
    pub start: Accumulation,
    /// `start` comes from a checkpoint without albedo and normal sums
    /// (format 3 or older): they are traced again before the render goes on.
    pub retrace_aovs: bool,
    /// The checkpoint this job resumes, if any.
    pub resumed_from: Option<PathBuf>,
    /// Debug overlay.
    pub debug: Option<DebugView>,
    /// Time budget of the whole job.
    pub time_limit: Option<Duration>,
    /// The shard this job renders (its partial is the checkpoint file).
    pub shard: Option<ShardSet>,
    /// Photons loaded from a photon file, checked against this render.
    pub photons: Option<TracedPhotons>,
}

/// Reported once the accelerator is built, before the first sample.
pub struct JobStart<'a> {
    /// The accelerator's statistics.
    pub accel: &'a AccelStats,
    /// What the render will do.
    pub plan: &'a RenderPlan,
    /// Samples already in the resumed accumulation.
    pub resumed_samples: u64,
    /// Samples of the whole render.
    pub total_samples: u64,
    /// Material parameters the integrator ignores, and materials that
    /// reflect more than they receive.
    pub warnings: &'a [String],
}

/// How a caller follows and stops a running job.
pub struct JobHooks<'a> {
    /// Set to stop before the next pixel (Ctrl-C, a viewer's change).
    pub cancel: Option<&'a AtomicBool>,
    /// Called once before rendering.
    pub started: &'a dyn Fn(&JobStart),
    /// `progress(samples_done, samples_total)`, from worker threads.
    pub progress: &'a (dyn Fn(u64, u64) + Sync),
    /// Non-fatal problems (a checkpoint that could not be saved, a debug
    /// view with nothing to draw), from any thread.
    pub warn: &'a (dyn Fn(&str) + Sync),
}

impl JobHooks<'_> {
    /// Hooks that report nothing and never cancel.
    pub fn silent() -> JobHooks<'static> {
        JobHooks {
            cancel: None,
            started: &|_| {},
            progress: &|_, _| {},
            warn: &|_| {},
        }
    }
}

/// What a finished (or stopped) job did.
pub struct JobReport {
    /// The accelerator's statistics (its build time included).
    pub accel: AccelStats,
    /// The plan the render followed.
    pub plan: RenderPlan,
    /// The image, its accumulation and the render statistics.
    pub output: RenderOutput,
    /// Wall time from the first sample (photon pass included) to the
    /// outputs written.
    pub render_time: Duration,
    /// The files written, as shown to the user.
    pub written: Vec<String>,
    /// Samples of the whole render (of the shard, for a shard).
    pub total_samples: u64,
    /// The shard rendered, if any.
    pub shard: Option<ShardSet>,
    /// What denoising the final image cost, when it was denoised
    /// (`output.film` is then the denoised image).
    pub denoise: Option<DenoiseStats>,
}

impl JobReport {
    /// Samples every pixel was meant to receive.
    pub fn spp(&self) -> u32 {
        self.plan.spp
    }

    /// Every pixel has all its samples.
    pub fn complete(&self) -> bool {
        self.output.complete
    }

    /// Samples taken so far, resumed ones included (a shard's own only).
    pub fn samples_done(&self) -> u64 {
        let offset = sample_offset(self.shard.as_ref(), &self.plan);
        self.output.accumulation.samples_taken() - offset
    }
}

impl RenderJob {
    /// Loads and checks everything a render needs; nothing is rendered and no
    /// file is written.
    pub fn prepare(request: &RenderRequest) -> Result<Self, JobError> {
        let mut loaded = scene::load_scene_options(&request.scene, &request.overrides.load_options())?;
        let resumed = match &request.resume {
            Some(path) => Some(film::read_checkpoint(path)?),
            None => None,
        };
        let mut overrides = request.overrides.clone();
        let mut accel = request.accel;
        if let Some(c) = &resumed {
            // The checkpoint's settings are the defaults; explicit overrides
            // that differ are refused by the fingerprint check below.
            let m = &c.meta;
            overrides.width.get_or_insert(m.width);
            overrides.height.get_or_insert(m.height);
            overrides.spp.get_or_insert(m.spp);
            overrides.seed.get_or_insert(m.seed);
            overrides.photons.get_or_insert(m.photons);
            if accel.is_none() {
                accel = AccelKind::from_name(&m.accel);
            }
        }
        overrides.apply(&mut loaded, &request.scene)?;
        let LoadedScene { scene, settings } = loaded;
        let shard = shard_of(request, resumed.as_ref().map(|c| &c.meta), &settings)?;
        if settings.denoise {
            denoise::require()?;
            if shard.is_some() {
                return Err(JobError::Invalid(
                    "--denoise filters a whole image: denoise when merging the partials (caustic merge --denoise), \
                     not in a shard"
                        .to_string(),
                ));
            }
        }
        let accel = accel.unwrap_or_else(AccelKind::default_kind);
        let accel_options = AccelOptions {
            triangle_test: settings.triangle_test,
            embree_quality: request.embree_quality.clone(),
            embree_robust: request.embree_robust,
        };
        let checkpoint_path = request.checkpoint.clone().or_else(|| request.resume.clone());
        let mut meta = checkpoint_meta(&scene, &settings, accel, &accel_options);
        meta.shard = shard.clone();
        if shard.is_some() && checkpoint_path.is_none() {
            return Err(JobError::Invalid(
                "a shard needs a file to write its partial to (-o PART.exr)".to_string(),
            ));
        }
        if let (Some(c), Some(path)) = (&resumed, &request.resume) {
            if let Some(why) = fingerprint::format_refusal(c.meta.fingerprint_format) {
                return Err(JobError::Invalid(format!(
                    "{}: the checkpoint was {why}",
                    path.display()
                )));
            }
            if c.meta.fingerprint != meta.fingerprint {
                return Err(JobError::Invalid(format!(
                    "{}: the checkpoint is of a different render ({}); resume with the scene and settings it was started with",
                    path.display(),
                    fingerprint::differences(&c.meta, &meta)
                )));
            }
        }
        if request.photon_map.is_some() && settings.photons.progressive {
            return Err(JobError::Invalid(format!(
                "--photon-map: {} renders with progressive photon mapping ([photons] progressive = true or \
                 --progressive-photons), which traces a new map for every sample index; it cannot use a photon \
                 file",
                request.scene.display()
            )));
        }
        let photons = match &request.photon_map {
            Some(path) => Some(photons::load_for(path, &scene, &settings, accel, &accel_options)?),
            None => None,
        };
        // Fail before hours of rendering, not after.
        for out in request.png.iter().chain(&request.exr).chain(&checkpoint_path) {
            film::check_writable(out)?;
        }
        let (w, h, spp) = (settings.width, settings.height, settings.spp);
        let (mut start, retrace_aovs) = match resumed {
            Some(c) => (c.accumulation, !c.has_aovs),
            None => (Accumulation::new(w, h), false),
        };
        if let Some(set) = &shard {
            set.prepare_for_render(&mut start, spp);
        }
        Ok(Self {
            source: request.scene.clone(),
            accel,
            accel_options,
            png: request.png.clone(),
            exr: request.exr.clone(),
            checkpoint: checkpoint_path.map(|p| (p, meta)),
            checkpoint_every: request.checkpoint_every,
            start,
            retrace_aovs,
            resumed_from: request.resume.clone(),
            debug: request.debug,
            time_limit: request.time_limit,
            shard,
            photons,
            scene,
            settings,
        })
    }

    /// A job over a scene built in memory: no files, no checkpoint.
    pub fn in_memory(loaded: LoadedScene, accel: AccelKind, accel_options: AccelOptions) -> Self {
        let LoadedScene { scene, settings } = loaded;
        let start = Accumulation::new(settings.width, settings.height);
        Self {
            scene,
            settings,
            source: PathBuf::from("<memory>"),
            accel,
            accel_options,
            png: None,
            exr: None,
            checkpoint: None,
            checkpoint_every: Duration::from_secs(60),
            start,
            retrace_aovs: false,
            resumed_from: None,
            debug: None,
            time_limit: None,
            shard: None,
            photons: None,
        }
    }

    /// The render plan of this job.
    pub fn plan(&self) -> RenderPlan {
        let mut plan = RenderPlan::new(&self.scene, &self.settings);
        plan.keep_photon_positions = matches!(self.debug, Some(DebugView::Photons));
        // Every EXR this job writes (output, checkpoint, partial) holds them.
        let every_buffer = self.exr.is_some() || self.checkpoint.is_some() || self.shard.is_some();
        plan.aovs |= every_buffer;
        // So do the noise estimate's half sums (the EXR's error layer).
        plan.noise |= every_buffer;
        plan
    }

    /// Builds the accelerator, renders and writes the outputs. A stopped
    /// render still writes its partial image and checkpoint (check
    /// [`JobReport::complete`]).
    pub fn run(mut self, hooks: &JobHooks) -> Result<JobReport, JobError> {
        let started = Instant::now();
        let accel = accel::build(&self.scene, self.accel, &self.accel_options)?;
        // The budget counts from the job's start, the build included.
        self.time_limit = self.time_limit.map(|t| t.saturating_sub(started.elapsed()));
        self.run_with(accel.as_ref(), hooks)
    }

    /// Like [`run`](Self::run), with an accelerator built by the caller
    /// (to time the build apart, or to build it once for several jobs).
    pub fn run_with(self, accel: &dyn Accel, hooks: &JobHooks) -> Result<JobReport, JobError> {
        let stats = accel.stats();
        let plan = self.plan();
        let st = &self.settings;
        let shard = self.shard.clone();
        let total_samples = match &shard {
            Some(set) => set.total_samples(st.width, st.height, st.spp),
            None => st.width as u64 * st.height as u64 * st.spp as u64,
        };
        // Samples mode starts every pixel at its range's first index.
        let offset = sample_offset(shard.as_ref(), &plan);
        let warnings = lint::warnings(&self.scene, &self.settings);
        (hooks.started)(&JobStart {
            accel: &stats,
            plan: &plan,
            resumed_samples: self.start.samples_taken() - offset,
            total_samples,
            warnings: &warnings,
        });
        let checkpoint = self.checkpoint.as_ref();
        let for_file = |acc: &Accumulation| match &shard {
            Some(set) => set.for_file(acc),
            None => acc.clone(),
        };
        let save = |acc: &Accumulation| {
            if let Some((path, meta)) = checkpoint {
                if let Err(e) = film::write_checkpoint(path, &for_file(acc), meta) {
                    (hooks.warn)(&format!("checkpoint not saved (the render goes on): {e}"));
                }
            }
        };
        let progress = |done: u64, _total: u64| (hooks.progress)(done - offset, total_samples);
        let control = integrator::RenderControl {
            cancel: hooks.cancel,
            sample_limit: shard
                .as_ref()
                .filter(|set| set.mode == ShardMode::Samples)
                .map(|set| set.last_sample(st.spp)),
            checkpoint: checkpoint.map(|_| integrator::CheckpointHook {
                every: self.checkpoint_every,
                save: &save,
            }),
            progress: &progress,
            // The denoiser's time is kept within the budget.
            deadline: self.time_limit.map(|t| {
                let reserve = match st.denoise {
                    true => denoise_reserve(st.width, st.height, st.denoise_quality, t),
                    false => Duration::ZERO,
                };
                Instant::now() + t.saturating_sub(reserve)
            }),
        };
        let begin = Instant::now();
        let denoising = st.denoise;
        let mut start = self.start;
        // A samples shard's sums hold only its own range of sample indices,
        // which the retrace (from index 0) does not know: it keeps zeros.
        let samples_shard = self.shard.as_ref().is_some_and(|set| set.mode == ShardMode::Samples);
        if self.retrace_aovs && plan.aovs && !samples_shard {
            integrator::render::retrace_aovs(&self.scene, accel, &plan, &mut start);
        }
        let photons = match self.photons {
            Some(traced) => integrator::PhotonInput::Traced(traced),
            None => integrator::PhotonInput::Trace,
        };
        let setup = integrator::RenderSetup::default()
            .continuing(start)
            .photons(photons)
            .control(control);
        let mut output = integrator::render(&self.scene, accel, &plan, setup);
        if let Some(set) = &shard {
            output.complete = set.is_complete(&output.accumulation, st.spp);
            output.timed_out &= !output.complete;
        }
        if output.accumulation.samples_taken() == offset && !output.complete {
            // Stopped before the first sample: keep whatever files are there.
            return Err(JobError::StoppedBeforeFirstSample);
        }
        // The final outputs are denoised; checkpoints and partials never.
        let (noisy, denoise_stats) = if denoising {
            let (image, stats) = denoise_accumulation(&output.film, &output.accumulation, st.denoise_quality)?;
            (Some(std::mem::replace(&mut output.film, image)), Some(stats))
        } else {
            (None, None)
        };
        match self.debug {
            Some(DebugView::Photons) => match output.photon_map.clone() {
                Some(map) => debug::overlay_photons(&mut output.film, &self.scene, &map),
                None => (hooks.warn)("--debug photons: no photon map (the plan skipped the photon pass)"),
            },
            Some(DebugView::KdTree { depth }) => {
                let tree = accel::kdtree::KdTreeAccel::build(&self.scene, &self.accel_options);
                debug::overlay_boxes(&mut output.film, &self.scene.camera, &tree.node_boxes(depth));
            }
            None => {}
        }
        let mut written = Vec::new();
        if let Some(p) = &self.png {
            film::write_png(p, &output.film, &st.output)?;
            written.push(p.display().to_string());
        }
        if let Some(p) = &self.exr {
            write_exr_output(p, &output.film, &output.accumulation, noisy.as_ref())?;
            written.push(p.display().to_string());
        }
        if let Some((path, meta)) = checkpoint {
            film::write_checkpoint(path, &for_file(&output.accumulation), meta)?;
            written.push(match &shard {
                Some(set) => format!("{} (partial: {set})", path.display()),
                None => format!("{} (checkpoint)", path.display()),
            });
        }
        Ok(JobReport {
            accel: stats,
            plan,
            output,
            render_time: begin.elapsed(),
            written,
            total_samples,
            shard,
            denoise: denoise_stats,
        })
    }
}

/// Denoises `film` (the image of `acc`) with OIDN, guided by the
/// accumulation's albedo and normal images.
pub fn denoise_accumulation(
    film: &Film,
    acc: &Accumulation,
    quality: DenoiseQuality,
) -> Result<(Film, DenoiseStats), DenoiseError> {
    let (albedo, normal) = (acc.albedo_film(), acc.normal_film());
    denoise::denoise(
        film,
        Some(Guides {
            albedo: &albedo,
            normal: &normal,
        }),
        quality,
    )
}

/// Time kept from a render's budget for denoising its image: OIDN's CPU
/// filter takes about [`DenoiseQuality::cpu_seconds_per_megapixel`] per
/// million pixels per core, after about [`DENOISE_SETUP_SECONDS`] to set
/// up; at most a quarter of the budget.
fn denoise_reserve(width: u32, height: u32, quality: DenoiseQuality, budget: Duration) -> Duration {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
    let megapixels = width as f64 * height as f64 / 1.0e6;
    let seconds = DENOISE_SETUP_SECONDS + megapixels * quality.cpu_seconds_per_megapixel() / cores;
    Duration::from_secs_f64(seconds).min(budget / 4)
}

/// Device and filter creation before the first pixel (see `denoise_reserve`).
pub const DENOISE_SETUP_SECONDS: f64 = 0.15;

/// Writes the linear EXR of a render: the film and, beside it, where the
/// work went (each pixel's estimated relative error and its sample count),
/// the auxiliary images (`albedo.R/G/B`, `normal.X/Y/Z`) and, when `film`
/// is denoised, the raw image (`noisy.R/G/B`).
pub fn write_exr_output(path: &Path, film: &Film, acc: &Accumulation, noisy: Option<&Film>) -> Result<(), OutputError> {
    let error = acc.error_map();
    let spp: Vec<f32> = acc.taken.iter().map(|&t| t as f32).collect();
    let (albedo, normal) = (acc.albedo_film(), acc.normal_film());
    let channel = |f: &Film, c: usize| -> Vec<f32> { f.pixels.iter().map(|p| p[c]).collect() };
    let mut layers: Vec<(String, Vec<f32>)> = Vec::new();
    for (c, (a, n)) in ["R", "G", "B"].iter().zip(["X", "Y", "Z"]).enumerate() {
        layers.push((format!("albedo.{a}"), channel(&albedo, c)));
        layers.push((format!("normal.{n}"), channel(&normal, c)));
        if let Some(noisy) = noisy {
            layers.push((format!("noisy.{a}"), channel(noisy, c)));
        }
    }
    let mut extra: Vec<(&str, &[f32])> = vec![("error", &error), ("spp", &spp)];
    extra.extend(layers.iter().map(|(name, values)| (name.as_str(), values.as_slice())));
    film::write_exr_with(path, film, &extra)
}

/// Samples a samples-mode shard's accumulation counts before its first:
/// every pixel starts at its range's first index.
fn sample_offset(shard: Option<&ShardSet>, plan: &RenderPlan) -> u64 {
    match shard {
        Some(set) if set.mode == ShardMode::Samples => {
            plan.width as u64 * plan.height as u64 * set.first_sample(plan.spp) as u64
        }
        _ => 0,
    }
}

/// The shard a job renders: the request's, checked against a resumed
/// partial's (which is the default), and refused with adaptive sampling
/// or too few samples to split.
fn shard_of(
    request: &RenderRequest,
    resumed: Option<&CheckpointMeta>,
    settings: &RenderSettings,
) -> Result<Option<ShardSet>, JobError> {
    let path = |p: &Option<PathBuf>| p.as_ref().map(|p| p.display().to_string()).unwrap_or_default();
    let shard = match (resumed.map(|m| &m.shard), &request.shard) {
        (None, shard) => shard.clone(),
        (Some(None), None) => None,
        (Some(None), Some(_)) => {
            return Err(JobError::Invalid(format!(
                "{}: a checkpoint of a whole render, not of a shard: resume it without --shard",
                path(&request.resume)
            )))
        }
        (Some(Some(theirs)), ours) => {
            if let Some(ours) = ours.as_ref().filter(|o| *o != theirs) {
                return Err(JobError::Invalid(format!(
                    "{}: the partial holds {theirs}, not {ours}",
                    path(&request.resume)
                )));
            }
            if theirs.indices.len() != 1 {
                return Err(JobError::Invalid(format!(
                    "{}: a merged partial ({theirs}) is complete and cannot be resumed; merge it with caustic merge",
                    path(&request.resume)
                )));
            }
            Some(theirs.clone())
        }
    };
    let Some(set) = shard else { return Ok(None) };
    let st = settings;
    if st.noise_threshold.is_some() {
        return Err(JobError::Invalid(format!(
            "{}: adaptive sampling (--noise-threshold or the scene's noise_threshold) cannot be split into shards: \
             a pixel's stopping decision reads its neighbours, which other shards render",
            request.scene.display()
        )));
    }
    if set.mode == ShardMode::Samples && set.count > st.spp {
        return Err(JobError::Invalid(format!(
            "{set}: splitting by samples needs at least {} samples per pixel, one per shard (the render has {})",
            set.count, st.spp
        )));
    }
    if request.debug.is_some() {
        return Err(JobError::Invalid(
            "--debug draws over a whole image: it cannot be used with --shard".to_string(),
        ));
    }
    Ok(Some(set))
}

/// What a checkpoint of this render records (its fingerprint included).
pub fn checkpoint_meta(
    scene: &Scene,
    settings: &RenderSettings,
    accel: AccelKind,
    options: &AccelOptions,
) -> CheckpointMeta {
    let st = settings;
    CheckpointMeta {
        width: st.width,
        height: st.height,
        spp: st.spp,
        seed: st.seed,
        photons: st.photons.count,
        accel: accel.name().to_string(),
        fingerprint: fingerprint(scene, settings, accel, &options.fingerprint_text(accel)),
        fingerprint_format: fingerprint::FINGERPRINT_FORMAT,
        output: st.output,
        shard: None,
    }
}
