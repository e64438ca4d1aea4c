//! The command-line arguments (clap derive): one struct per subcommand and
//! the groups they share.

use caustic::accel::{AccelKind, AccelOptions, TriangleTest};
use caustic::film::ShardMode;
use caustic::math::SamplerKind;
use caustic::scene::{IntegratorKind, RenderSettings};
use clap::{Args, ValueEnum};
use std::path::PathBuf;

#[derive(Clone, Copy, ValueEnum)]
pub enum AccelArg {
    Embree,
    Kdtree,
    Brute,
}

impl From<AccelArg> for AccelKind {
    fn from(a: AccelArg) -> Self {
        match a {
            AccelArg::Embree => AccelKind::Embree,
            AccelArg::Kdtree => AccelKind::KdTree,
            AccelArg::Brute => AccelKind::Brute,
        }
    }
}

/// The sample generator.
#[derive(Clone, Copy, ValueEnum)]
pub enum SamplerArg {
    /// Owen-scrambled Sobol points (low discrepancy).
    Sobol,
    /// Independent uniform numbers.
    Independent,
}

impl From<SamplerArg> for SamplerKind {
    fn from(a: SamplerArg) -> Self {
        match a {
            SamplerArg::Sobol => SamplerKind::Sobol,
            SamplerArg::Independent => SamplerKind::Independent,
        }
    }
}

/// The light transport algorithm.
#[derive(Clone, Copy, ValueEnum)]
pub enum IntegratorArg {
    /// The original report's Whitted ray tracing with photon-mapped caustics.
    Whitted,
    /// Physically based path tracing (next-event estimation, MIS).
    Path,
}

impl From<IntegratorArg> for IntegratorKind {
    fn from(a: IntegratorArg) -> Self {
        match a {
            IntegratorArg::Whitted => IntegratorKind::Whitted,
            IntegratorArg::Path => IntegratorKind::Path,
        }
    }
}

#[derive(Clone, Copy, ValueEnum)]
pub enum TriangleTestArg {
    Watertight,
    MollerTrumbore,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum QualityArg {
    Low,
    Medium,
    High,
}

/// `-D name=value`: parameters of a Mitsuba scene (its `$name`), as
/// Mitsuba's own `-D`; they take precedence over the file's `<default>`s.
#[derive(Args, Clone, Default)]
pub struct DefineArgs {
    /// Set the Mitsuba scene parameter NAME (`$NAME` in the file) to VALUE.
    #[arg(short = 'D', long = "define", value_name = "NAME=VALUE", value_parser = parse_define)]
    pub defines: Vec<(String, String)>,
}

fn parse_define(text: &str) -> Result<(String, String), String> {
    let (name, value) = text
        .split_once('=')
        .ok_or_else(|| format!("`{text}`: expected NAME=VALUE"))?;
    if !caustic::scene::mitsuba::xml::is_identifier(name) {
        return Err(format!("`{name}` is not a parameter name (letters, digits and _)"));
    }
    Ok((name.to_string(), value.to_string()))
}

/// Accelerator selection, shared by the subcommands.
#[derive(Args)]
pub struct AccelArgs {
    /// Accelerator (default: embree when compiled in, else kdtree).
    #[arg(long, value_enum)]
    pub accel: Option<AccelArg>,
    #[command(flatten)]
    pub backend: BackendArgs,
}

/// How the accelerators are built, shared by the subcommands (those that
/// compare several accelerators take a list instead of `--accel`).
#[derive(Args)]
pub struct BackendArgs {
    /// Ray–triangle test of the in-house backends (default: the scene's when one
    /// scene is rendered, else watertight).
    #[arg(long, value_enum)]
    pub triangle_test: Option<TriangleTestArg>,
    /// Embree BVH build quality.
    #[arg(long, value_enum, default_value = "high")]
    pub embree_quality: QualityArg,
    /// Embree robust traversal mode.
    #[arg(long)]
    pub embree_robust: bool,
}

impl QualityArg {
    pub fn name(self) -> &'static str {
        match self {
            QualityArg::Low => "low",
            QualityArg::Medium => "medium",
            QualityArg::High => "high",
        }
    }
}

impl AccelArgs {
    pub fn kind(&self) -> AccelKind {
        self.accel.map(AccelKind::from).unwrap_or_else(AccelKind::default_kind)
    }

    pub fn options(&self, settings: &RenderSettings) -> AccelOptions {
        self.backend.options(settings)
    }

    pub fn apply(&self, settings: &mut RenderSettings) {
        self.backend.apply(settings)
    }
}

impl BackendArgs {
    pub fn options(&self, settings: &RenderSettings) -> AccelOptions {
        AccelOptions {
            triangle_test: settings.triangle_test,
            embree_quality: self.embree_quality.name().into(),
            embree_robust: self.embree_robust,
        }
    }

    pub fn triangle_test(&self) -> Option<TriangleTest> {
        self.triangle_test.map(|t| match t {
            TriangleTestArg::Watertight => TriangleTest::Watertight,
            TriangleTestArg::MollerTrumbore => TriangleTest::MollerTrumbore,
        })
    }

    pub fn apply(&self, settings: &mut RenderSettings) {
        if let Some(t) = self.triangle_test() {
            settings.triangle_test = t;
        }
    }
}

#[derive(Args)]
pub struct RenderArgs {
    /// Scene file: caustic TOML, Mitsuba XML (`.xml`) or a glTF 2.0 model (`.gltf`, `.glb`).
    pub scene: PathBuf,
    #[command(flatten)]
    pub defines: DefineArgs,
    /// A glTF model's camera to render, by name (the camera's or its
    /// node's) or index (default: the first the scene places, else one
    /// framing the model).
    #[arg(long, value_name = "NAME|INDEX")]
    pub camera: Option<String>,
    /// Let a glTF model's buffers and images be read from outside its folder.
    #[arg(long)]
    pub allow_outside_files: bool,
    /// A latitude-longitude environment image (.hdr or .exr) that lights
    /// the scene, replacing its environment light (a glTF model without
    /// lights is otherwise lit by a uniform white environment).
    #[arg(long, value_name = "FILE")]
    pub environment: Option<PathBuf>,
    /// Multiplies the environment light's radiance (default 1).
    #[arg(long, value_name = "SCALE")]
    pub environment_intensity: Option<f32>,
    /// Turns the environment image about the up axis (+y), in degrees.
    #[arg(long, value_name = "DEGREES", allow_negative_numbers = true)]
    pub environment_rotation: Option<f32>,
    /// PNG output (tone mapped), or the EXR output (linear HDR) when the
    /// name ends in .exr. Default: <scene name>.png unless --exr alone is given.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// EXR output (linear HDR).
    #[arg(long)]
    pub exr: Option<PathBuf>,
    /// Light transport algorithm (default: the scene's `[render] integrator`, else whitted).
    #[arg(long, value_enum)]
    pub integrator: Option<IntegratorArg>,
    /// Sample generator (default: the scene's, else sobol for path and independent for whitted).
    #[arg(long, value_enum)]
    pub sampler: Option<SamplerArg>,
    /// Adaptive sampling: stop each pixel once the estimated relative error
    /// of its neighbourhood is at most this (e.g. 0.02); --spp is then the most
    /// a pixel takes.
    #[arg(long)]
    pub noise_threshold: Option<f32>,
    /// Samples every pixel takes before adaptive sampling stops any (default 16).
    #[arg(long)]
    pub min_spp: Option<u32>,
    /// What --noise-threshold bounds: every pixel's error (pixel, the
    /// default) or the image's mean relative squared error per sample
    /// (image: samples in proportion to each pixel's noise).
    #[arg(long, value_enum)]
    pub adaptive_goal: Option<AdaptiveGoalArg>,
    /// How the path integrator finds caustics: as paths (path, unbiased) or
    /// from photon maps of light through mirrors, glass and water (map).
    /// Also `[photons] caustics`.
    #[arg(long, value_enum)]
    pub caustics: Option<CausticsArg>,
    /// Most samples per pixel (the same as --spp).
    #[arg(long, conflicts_with = "spp")]
    pub max_spp: Option<u32>,
    /// Denoise the PNG and the EXR's main layer with Open Image Denoise,
    /// guided by the albedo and normal images (the raw image stays in the
    /// EXR as noisy.R/G/B; checkpoints stay raw). Also `[render] denoise = true`.
    #[arg(long)]
    pub denoise: bool,
    /// The denoising filter's quality (default high). Also `[render] denoise_quality`.
    #[arg(long, value_enum)]
    pub denoise_quality: Option<DenoiseQualityArg>,
    /// Render progressively until this many seconds have passed, then write
    /// the image so far (with --noise-threshold: whichever comes first).
    #[arg(long)]
    pub time_limit: Option<f64>,
    /// Override the image width.
    #[arg(long)]
    pub width: Option<u32>,
    /// Override the image height.
    #[arg(long)]
    pub height: Option<u32>,
    /// Override the samples per pixel.
    #[arg(long)]
    pub spp: Option<u32>,
    /// Override the seed.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Override the number of photons emitted for caustics (0 turns the pass off).
    #[arg(long)]
    pub photons: Option<u64>,
    /// Progressive photon mapping (also `[photons] progressive = true`): every
    /// sample index traces its own map of photons/spp photons, gathered within
    /// a radius that shrinks from sample to sample, so caustics converge.
    #[arg(long)]
    pub progressive_photons: bool,
    /// Progressive photon mapping's alpha in (0, 1) (default the scene's
    /// `[photons] alpha`, else 2/3): r_{i+1}² = r_i² (i + alpha)/(i + 1).
    #[arg(long)]
    pub ppm_alpha: Option<f32>,
    /// Overlay a debug view on the image: the photon map as points (the original
    /// report's 'p' key) or the KD-tree's boxes (its 'k' key).
    #[arg(long, value_enum)]
    pub debug: Option<DebugView>,
    /// Deepest KD-tree level drawn by `--debug kdtree`.
    #[arg(long, default_value_t = 10)]
    pub debug_depth: u32,
    /// No progress bar.
    #[arg(short, long)]
    pub quiet: bool,
    /// Save the accumulation (EXR: per-pixel sums and sample counts, seed and a
    /// fingerprint of the scene and settings) to this file, atomically, every
    /// --checkpoint-every seconds and when the render stops.
    #[arg(long)]
    pub checkpoint: Option<PathBuf>,
    /// Seconds between two checkpoints.
    #[arg(long, default_value_t = 60.0)]
    pub checkpoint_every: f64,
    /// Continue the render saved in this checkpoint; the result equals an
    /// uninterrupted render bit for bit. Width, height, spp, seed, photons and
    /// accelerator default to the checkpoint's; checkpoints go on to the same
    /// file unless --checkpoint names another.
    #[arg(long)]
    pub resume: Option<PathBuf>,
    /// Render only shard I of N (0-based, e.g. 2/4) and write it as a partial
    /// (an EXR of per-pixel sums, merged by `caustic merge`) to -o, saved every
    /// --checkpoint-every seconds; `auto` reads the index (and count) from a
    /// Slurm array (SLURM_ARRAY_TASK_*) or a Kubernetes Indexed Job
    /// (JOB_COMPLETION_INDEX, with --shard-count).
    #[arg(long, value_name = "I/N|auto")]
    pub shard: Option<String>,
    /// How shards split the render: tiles (disjoint pixel blocks; the merge is
    /// bit-identical to one process) or samples (disjoint sample ranges of every
    /// pixel). Default: tiles.
    #[arg(long, value_enum, requires = "shard")]
    pub shard_by: Option<ShardByArg>,
    /// Number of shards, for --shard auto where the scheduler does not say
    /// (Kubernetes: the Job's completions).
    #[arg(long, requires = "shard")]
    pub shard_count: Option<u32>,
    /// Build the caustic map from photons traced beforehand by `caustic photons`
    /// (refused unless they are this render's: same scene, photons, seed and
    /// accelerator) instead of tracing them.
    #[arg(long, value_name = "FILE")]
    pub photon_map: Option<PathBuf>,
    #[command(flatten)]
    pub accel: AccelArgs,
}

#[derive(Args)]
pub struct PhotonsArgs {
    /// Scene file: caustic TOML, Mitsuba XML (`.xml`) or a glTF 2.0 model (`.gltf`, `.glb`).
    pub scene: PathBuf,
    #[command(flatten)]
    pub defines: DefineArgs,
    /// The photon file to write.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Override the number of photons emitted.
    #[arg(long)]
    pub photons: Option<u64>,
    /// Override the seed.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Light transport algorithm (path tracing has no photon pass).
    #[arg(long, value_enum)]
    pub integrator: Option<IntegratorArg>,
    /// Image width: accepted so that a render's flags can be reused; the
    /// photons do not depend on it.
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height (as --width).
    #[arg(long)]
    pub height: Option<u32>,
    /// Samples per pixel (as --width).
    #[arg(long)]
    pub spp: Option<u32>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
    #[command(flatten)]
    pub accel: AccelArgs,
}

/// How shards split a render.
#[derive(Clone, Copy, ValueEnum)]
pub enum ShardByArg {
    /// Disjoint blocks of pixels per shard.
    Tiles,
    /// Disjoint ranges of sample indices per shard, every pixel.
    Samples,
}

impl From<ShardByArg> for ShardMode {
    fn from(a: ShardByArg) -> Self {
        match a {
            ShardByArg::Tiles => ShardMode::Tiles,
            ShardByArg::Samples => ShardMode::Samples,
        }
    }
}

#[derive(Args)]
pub struct MergeArgs {
    /// Partials written by `caustic render --shard` (or by --partial).
    #[arg(required = true)]
    pub partials: Vec<PathBuf>,
    /// PNG output (tone mapped as the scene says); needs every shard.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// EXR output (linear HDR, with error and spp channels); needs every shard.
    #[arg(long)]
    pub exr: Option<PathBuf>,
    /// Write the merged shards as a new partial (any subset: tree reductions).
    #[arg(long)]
    pub partial: Option<PathBuf>,
    /// Denoise the PNG and the EXR's main layer (Open Image Denoise; the raw
    /// image stays in the EXR as noisy.R/G/B).
    #[arg(long)]
    pub denoise: bool,
    /// The denoising filter's quality.
    #[arg(long, value_enum, default_value = "high")]
    pub denoise_quality: DenoiseQualityArg,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum DebugView {
    Photons,
    Kdtree,
}

#[derive(Args)]
pub struct ConvertArgs {
    /// Scene file: caustic TOML, Mitsuba XML (`.xml`) or a glTF 2.0 model (`.gltf`, `.glb`).
    pub scene: PathBuf,
    #[command(flatten)]
    pub defines: DefineArgs,
    /// The caustic TOML file to write; meshes built in memory are written
    /// beside it as `STEM-mesh-N.ply`.
    #[arg(short = 'o', long = "output", value_name = "OUT.toml")]
    pub output: PathBuf,
}

#[derive(Args)]
pub struct InfoArgs {
    /// Scene file: caustic TOML, Mitsuba XML (`.xml`) or a glTF 2.0 model (`.gltf`, `.glb`).
    pub scene: PathBuf,
    #[command(flatten)]
    pub defines: DefineArgs,
    /// Light transport algorithm shown in the plan (default: the scene's).
    #[arg(long, value_enum)]
    pub integrator: Option<IntegratorArg>,
    #[command(flatten)]
    pub accel: AccelArgs,
}

#[derive(Args)]
pub struct CrosscheckArgs {
    /// Scene file: caustic TOML, Mitsuba XML (`.xml`) or a glTF 2.0 model (`.gltf`, `.glb`).
    pub scene: PathBuf,
    #[command(flatten)]
    pub defines: DefineArgs,
    /// Number of rays (a quarter each: camera, through the bounds, at mesh vertices and edges, shadow).
    #[arg(long, default_value_t = 1_000_000)]
    pub rays: u64,
    /// Seed of the ray streams.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// First accelerator.
    #[arg(long, value_enum, default_value = DEFAULT_A)]
    pub a: AccelArg,
    /// Second accelerator.
    #[arg(long, value_enum, default_value = "kdtree")]
    pub b: AccelArg,
    /// Replay one printed ray ("ox,oy,oz,dx,dy,dz[,t_max]") instead of casting seeded rays.
    #[arg(long)]
    pub replay: Option<String>,
    #[command(flatten)]
    pub accel: AccelArgs,
}

/// How the path integrator finds caustics.
#[derive(Clone, Copy, ValueEnum)]
pub enum CausticsArg {
    /// As paths.
    Path,
    /// From photon maps.
    Map,
}

impl From<CausticsArg> for caustic::scene::CausticsMode {
    fn from(c: CausticsArg) -> Self {
        match c {
            CausticsArg::Path => Self::Path,
            CausticsArg::Map => Self::Map,
        }
    }
}

/// The denoising filter's quality.
#[derive(Clone, Copy, ValueEnum)]
pub enum DenoiseQualityArg {
    /// OIDN's highest quality (final images).
    High,
    /// OIDN's balanced filter (on the CPU the same as high).
    Balanced,
    /// OIDN's fastest filter, about half the time of high.
    Fast,
}

impl From<DenoiseQualityArg> for caustic::film::denoise::DenoiseQuality {
    fn from(q: DenoiseQualityArg) -> Self {
        match q {
            DenoiseQualityArg::High => Self::High,
            DenoiseQualityArg::Balanced => Self::Balanced,
            DenoiseQualityArg::Fast => Self::Fast,
        }
    }
}

/// What adaptive sampling's threshold bounds.
#[derive(Clone, Copy, ValueEnum)]
pub enum AdaptiveGoalArg {
    /// Every pixel's estimated relative error.
    Pixel,
    /// The image's relMSE per sample (Neyman allocation).
    Image,
}

impl From<AdaptiveGoalArg> for caustic::scene::AdaptiveGoal {
    fn from(g: AdaptiveGoalArg) -> Self {
        match g {
            AdaptiveGoalArg::Pixel => Self::Pixel,
            AdaptiveGoalArg::Image => Self::Image,
        }
    }
}

#[derive(Clone, Copy, ValueEnum)]
pub enum GatherArg {
    Direct,
    Precomputed,
}

#[derive(Args)]
pub struct ConvergeArgs {
    /// Scene file: caustic TOML, Mitsuba XML (`.xml`) or a glTF 2.0 model (`.gltf`, `.glb`).
    pub scene: PathBuf,
    #[command(flatten)]
    pub defines: DefineArgs,
    /// Reference image: a linear EXR of the same resolution (e.g. from
    /// `caustic render SCENE --spp 256 --photons 10000000 --seed 7 --exr ref.exr`).
    #[arg(long)]
    pub reference: PathBuf,
    /// Light transport algorithm (default: the scene's).
    #[arg(long, value_enum)]
    pub integrator: Option<IntegratorArg>,
    /// Sample generator (default: the scene's, else sobol for path and independent for whitted).
    #[arg(long, value_enum)]
    pub sampler: Option<SamplerArg>,
    /// Budgets, comma-separated: SPP:PHOTONS (1:10000), SPP (photons from
    /// --photons-per-spp, else the scene's), or SECONDSs (2s: doubling search).
    #[arg(long, default_value = "1,2,4,8,16")]
    pub budgets: String,
    /// Accelerators, one curve each (default: embree,kdtree, or kdtree without Embree).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub accel: Vec<AccelArg>,
    /// Photon gather modes to compare (one curve per accelerator and mode;
    /// default: the scene's mode only).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub gather: Vec<GatherArg>,
    /// Samplers to compare (one curve per accelerator and sampler; default:
    /// the scene's only).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub samplers: Vec<SamplerArg>,
    /// Also render adaptive curves, one render per noise threshold
    /// (e.g. 0.2,0.1,0.05), each at most --max-spp.
    #[arg(long, value_delimiter = ',')]
    pub adaptive: Vec<f32>,
    /// Add adaptive curves searched by --target-relmse alone (thresholds
    /// halved from 0.5 until the target is met).
    #[arg(long)]
    pub adaptive_search: bool,
    /// Add a denoised copy of every curve (`/denoised`: each image through
    /// Open Image Denoise before it is measured, the filter's time included).
    #[arg(long)]
    pub denoise: bool,
    /// The denoised curves' filter quality (default: the scene's
    /// `[render] denoise_quality`, else high).
    #[arg(long, value_enum)]
    pub denoise_quality: Option<DenoiseQualityArg>,
    /// Most samples per pixel of an adaptive render.
    #[arg(long)]
    pub max_spp: Option<u32>,
    /// Samples every pixel of an adaptive render takes before any stops
    /// (default: the scene's min_spp, else 16).
    #[arg(long)]
    pub min_spp: Option<u32>,
    /// What an adaptive render's threshold bounds (see `render --adaptive-goal`).
    #[arg(long, value_enum)]
    pub adaptive_goal: Option<AdaptiveGoalArg>,
    /// How the path integrator finds caustics (as in `render`).
    #[arg(long, value_enum)]
    pub caustics: Option<CausticsArg>,
    /// For every curve, render on (spp doubled, threshold halved) until
    /// relMSE is at most this, and report the time it took (interpolated).
    #[arg(long)]
    pub target_relmse: Option<f64>,
    /// Photons per spp for budgets that give no photon count.
    #[arg(long)]
    pub photons_per_spp: Option<u64>,
    /// Override the scene's photon count (the default for SPP and time budgets).
    #[arg(long)]
    pub photons: Option<u64>,
    /// Progressive photon mapping for every curve (see `render --progressive-photons`):
    /// a budget's photons are shared out over its samples' maps.
    #[arg(long)]
    pub progressive_photons: bool,
    /// Progressive photon mapping's alpha (see `render --ppm-alpha`).
    #[arg(long)]
    pub ppm_alpha: Option<f32>,
    /// relMSE epsilon: (x - ref)^2 / (ref^2 + epsilon).
    #[arg(long, default_value_t = caustic::analysis::converge::RELMSE_EPSILON)]
    pub epsilon: f64,
    /// CSV output.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// PNG plot output (log-log error against time).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Plot size in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "1400x560")]
    pub plot_size: String,
    /// Override the image width (must match the reference).
    #[arg(long)]
    pub width: Option<u32>,
    /// Override the image height (must match the reference).
    #[arg(long)]
    pub height: Option<u32>,
    /// Override the seed (use a different one from the reference's).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    #[command(flatten)]
    pub backend: BackendArgs,
    /// No progress lines.
    #[arg(short, long)]
    pub quiet: bool,
}

#[derive(Args)]
pub struct BenchArgs {
    /// Scene files (TOML). Default: scenes/dragon.toml and scenes/dragon-mesh.toml (the mesh alone).
    pub scenes: Vec<PathBuf>,
    #[command(flatten)]
    pub defines: DefineArgs,
    /// Also write the report as JSON to this file.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Accelerators, comma-separated (default: every compiled-in one but brute).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub accel: Vec<AccelArg>,
    /// Camera rays and incoherent rays per scene (shadow rays: one per light per camera hit).
    #[arg(long, default_value_t = caustic::analysis::bench::DEFAULT_RAYS)]
    pub rays: usize,
    /// Seed of the ray sets and of the render.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Timed runs per ray set (the best is reported).
    #[arg(long, default_value_t = caustic::analysis::bench::DEFAULT_REPEATS)]
    pub repeats: u32,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Width of the full render (and aspect of the camera rays).
    #[arg(long, default_value_t = 640)]
    pub width: u32,
    /// Height of the full render.
    #[arg(long, default_value_t = 360)]
    pub height: u32,
    /// Samples per pixel of the full render.
    #[arg(long, default_value_t = 1)]
    pub spp: u32,
    /// Photons of the full render (default: the scene's, at most 100,000).
    #[arg(long)]
    pub photons: Option<u64>,
    #[command(flatten)]
    pub backend: BackendArgs,
    /// No progress lines on stderr.
    #[arg(short, long)]
    pub quiet: bool,
}

#[derive(Args)]
pub struct StressArgs {
    /// Also write the table as JSON to this file.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Seed of the ray streams.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Rays (or trials) per case and configuration.
    #[arg(long, default_value_t = 200_000)]
    pub rays: u64,
}

#[cfg(feature = "embree")]
pub const DEFAULT_A: &str = "embree";
#[cfg(not(feature = "embree"))]
pub const DEFAULT_A: &str = "brute";

/// `caustic view`.
#[derive(Args)]
pub struct ViewArgs {
    /// Scene file: caustic TOML, Mitsuba XML (`.xml`) or a glTF 2.0 model (`.gltf`, `.glb`).
    pub scene: PathBuf,
    #[command(flatten)]
    pub defines: DefineArgs,
    /// A glTF model's camera to open, by name (the camera's or its node's)
    /// or index (default: the first the scene places, else one framing the
    /// model).
    #[arg(long, value_name = "NAME|INDEX")]
    pub camera: Option<String>,
    /// Let a glTF model's buffers and images be read from outside its folder.
    #[arg(long)]
    pub allow_outside_files: bool,
    #[command(flatten)]
    pub accel: AccelArgs,
    /// Image width (default 960).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height (default 540).
    #[arg(long)]
    pub height: Option<u32>,
    /// Target samples per pixel (default: the scene's).
    #[arg(long)]
    pub spp: Option<u32>,
    /// Open no window: measure the interaction latency over N camera moves
    /// and N material edits, print a table and JSON.
    #[arg(long, value_name = "N")]
    pub latency_bench: Option<usize>,
    /// With --latency-bench: write the JSON report to this file.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
}
