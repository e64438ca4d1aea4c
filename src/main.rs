//! The `caustic` command line: parses arguments, calls the library, maps
//! errors to exit codes (2 for bad input, 1 for internal failures).

use anyhow::Context;
use caustic::accel::{self, AccelKind, AccelOptions, TriangleTest};
use caustic::film;
use caustic::integrator::{self, RenderPlan};
use caustic::scene::{self, Scene};
use clap::{Args, Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

/// caustic: a CPU renderer (Whitted, photon-mapped caustics, Embree 4 and an in-house KD-tree).
#[derive(Parser)]
#[command(version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene file to PNG (tone mapped) and/or EXR (linear HDR).
    Render(RenderArgs),
    /// Print scene statistics, the accelerator build and the render plan.
    Info(InfoArgs),
    /// Cast seeded rays through two accelerators (default Embree and the
    /// KD-tree) and compare every hit; exit 1 on any disagreement that is not a tie.
    Crosscheck(CrosscheckArgs),
    /// Render at increasing budgets (spp:photons, spp, or seconds) with each
    /// accelerator and measure RMSE / relMSE against a reference EXR; write a
    /// CSV and a log-log plot of error against time.
    Converge(ConvergeArgs),
    /// Measure each accelerator on each scene: build time and memory, Mrays/s
    /// of camera, shadow and incoherent rays, a full render; table and JSON.
    Bench(BenchArgs),
    /// Numerical stress tests (watertightness, self-intersection at extreme
    /// scales, split-plane rays, degenerate triangles, grazing rays, TIR, NaN
    /// guards); exit 1 when a default configuration fails.
    Stress(StressArgs),
}

#[derive(Clone, Copy, ValueEnum)]
enum AccelArg {
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

#[derive(Clone, Copy, ValueEnum)]
enum TriangleTestArg {
    Watertight,
    MollerTrumbore,
}

#[derive(Clone, Copy, ValueEnum)]
enum QualityArg {
    Low,
    Medium,
    High,
}

/// Accelerator selection, shared by the subcommands.
#[derive(Args)]
struct AccelArgs {
    /// Accelerator (default: embree when compiled in, else kdtree).
    #[arg(long, value_enum)]
    accel: Option<AccelArg>,
    #[command(flatten)]
    backend: BackendArgs,
}

/// How the accelerators are built, shared by the subcommands (those that
/// compare several accelerators take a list instead of `--accel`).
#[derive(Args)]
struct BackendArgs {
    /// Ray–triangle test of the in-house backends (default: the scene's when one
    /// scene is rendered, else watertight).
    #[arg(long, value_enum)]
    triangle_test: Option<TriangleTestArg>,
    /// Embree BVH build quality.
    #[arg(long, value_enum, default_value = "high")]
    embree_quality: QualityArg,
    /// Embree robust traversal mode.
    #[arg(long)]
    embree_robust: bool,
}

impl QualityArg {
    fn name(self) -> &'static str {
        match self {
            QualityArg::Low => "low",
            QualityArg::Medium => "medium",
            QualityArg::High => "high",
        }
    }
}

impl AccelArgs {
    fn kind(&self) -> AccelKind {
        self.accel.map(AccelKind::from).unwrap_or_else(AccelKind::default_kind)
    }

    fn options(&self, scene: &Scene) -> AccelOptions {
        self.backend.options(scene)
    }

    fn apply(&self, scene: &mut Scene) {
        self.backend.apply(scene)
    }
}

impl BackendArgs {
    fn options(&self, scene: &Scene) -> AccelOptions {
        AccelOptions {
            triangle_test: scene.settings.triangle_test,
            embree_quality: self.embree_quality.name().into(),
            embree_robust: self.embree_robust,
        }
    }

    fn triangle_test(&self) -> Option<TriangleTest> {
        self.triangle_test.map(|t| match t {
            TriangleTestArg::Watertight => TriangleTest::Watertight,
            TriangleTestArg::MollerTrumbore => TriangleTest::MollerTrumbore,
        })
    }

    fn apply(&self, scene: &mut Scene) {
        if let Some(t) = self.triangle_test() {
            scene.settings.triangle_test = t;
        }
    }
}

#[derive(Args)]
struct RenderArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// PNG output (tone mapped). Default: <scene name>.png unless --exr alone is given.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// EXR output (linear HDR).
    #[arg(long)]
    exr: Option<PathBuf>,
    /// Override the image width.
    #[arg(long)]
    width: Option<u32>,
    /// Override the image height.
    #[arg(long)]
    height: Option<u32>,
    /// Override the samples per pixel.
    #[arg(long)]
    spp: Option<u32>,
    /// Override the seed.
    #[arg(long)]
    seed: Option<u64>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Override the number of photons emitted for caustics (0 turns the pass off).
    #[arg(long)]
    photons: Option<u64>,
    /// Overlay a debug view on the image: the photon map as points (the original
    /// report's 'p' key) or the KD-tree's boxes (its 'k' key).
    #[arg(long, value_enum)]
    debug: Option<DebugView>,
    /// Deepest KD-tree level drawn by `--debug kdtree`.
    #[arg(long, default_value_t = 10)]
    debug_depth: u32,
    /// No progress bar.
    #[arg(short, long)]
    quiet: bool,
    /// Save the accumulation (EXR: per-pixel sums and sample counts, seed and a
    /// fingerprint of the scene and settings) to this file, atomically, every
    /// --checkpoint-every seconds and when the render stops.
    #[arg(long)]
    checkpoint: Option<PathBuf>,
    /// Seconds between two checkpoints.
    #[arg(long, default_value_t = 60.0)]
    checkpoint_every: f64,
    /// Continue the render saved in this checkpoint; the result equals an
    /// uninterrupted render bit for bit. Width, height, spp, seed, photons and
    /// accelerator default to the checkpoint's; checkpoints go on to the same
    /// file unless --checkpoint names another.
    #[arg(long)]
    resume: Option<PathBuf>,
    #[command(flatten)]
    accel: AccelArgs,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum DebugView {
    Photons,
    Kdtree,
}

#[derive(Args)]
struct InfoArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    #[command(flatten)]
    accel: AccelArgs,
}

#[derive(Args)]
struct CrosscheckArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Number of rays (a quarter each: camera, through the bounds, at mesh vertices and edges, shadow).
    #[arg(long, default_value_t = 1_000_000)]
    rays: u64,
    /// Seed of the ray streams.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// First accelerator.
    #[arg(long, value_enum, default_value = DEFAULT_A)]
    a: AccelArg,
    /// Second accelerator.
    #[arg(long, value_enum, default_value = "kdtree")]
    b: AccelArg,
    /// Replay one printed ray ("ox,oy,oz,dx,dy,dz[,t_max]") instead of casting seeded rays.
    #[arg(long)]
    replay: Option<String>,
    #[command(flatten)]
    accel: AccelArgs,
}

#[derive(Clone, Copy, ValueEnum)]
enum GatherArg {
    Direct,
    Precomputed,
}

#[derive(Args)]
struct ConvergeArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Reference image: a linear EXR of the same resolution (e.g. from
    /// `caustic render SCENE --spp 256 --photons 10000000 --seed 7 --exr ref.exr`).
    #[arg(long)]
    reference: PathBuf,
    /// Budgets, comma-separated: SPP:PHOTONS (1:10000), SPP (photons from
    /// --photons-per-spp, else the scene's), or SECONDSs (2s: doubling search).
    #[arg(long, default_value = "1,2,4,8,16")]
    budgets: String,
    /// Accelerators, one curve each (default: embree,kdtree, or kdtree without Embree).
    #[arg(long, value_enum, value_delimiter = ',')]
    accel: Vec<AccelArg>,
    /// Photon gather modes to compare (one curve per accelerator and mode;
    /// default: the scene's mode only).
    #[arg(long, value_enum, value_delimiter = ',')]
    gather: Vec<GatherArg>,
    /// Photons per spp for budgets that give no photon count.
    #[arg(long)]
    photons_per_spp: Option<u64>,
    /// Override the scene's photon count (the default for SPP and time budgets).
    #[arg(long)]
    photons: Option<u64>,
    /// relMSE epsilon: (x - ref)^2 / (ref^2 + epsilon).
    #[arg(long, default_value_t = caustic::analysis::converge::RELMSE_EPSILON)]
    epsilon: f64,
    /// CSV output.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// PNG plot output (log-log error against time).
    #[arg(long)]
    plot: Option<PathBuf>,
    /// Plot size in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "1400x560")]
    plot_size: String,
    /// Override the image width (must match the reference).
    #[arg(long)]
    width: Option<u32>,
    /// Override the image height (must match the reference).
    #[arg(long)]
    height: Option<u32>,
    /// Override the seed (use a different one from the reference's).
    #[arg(long)]
    seed: Option<u64>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    #[command(flatten)]
    backend: BackendArgs,
    /// No progress lines.
    #[arg(short, long)]
    quiet: bool,
}

#[derive(Args)]
struct BenchArgs {
    /// Scene files (TOML). Default: scenes/dragon.toml.
    scenes: Vec<PathBuf>,
    /// Also write the report as JSON to this file.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Accelerators, comma-separated (default: every compiled-in one but brute).
    #[arg(long, value_enum, value_delimiter = ',')]
    accel: Vec<AccelArg>,
    /// Camera rays and incoherent rays per scene (shadow rays: one per light per camera hit).
    #[arg(long, default_value_t = caustic::analysis::bench::DEFAULT_RAYS)]
    rays: usize,
    /// Seed of the ray sets and of the render.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Timed runs per ray set (the best is reported).
    #[arg(long, default_value_t = caustic::analysis::bench::DEFAULT_REPEATS)]
    repeats: u32,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Width of the full render (and aspect of the camera rays).
    #[arg(long, default_value_t = 640)]
    width: u32,
    /// Height of the full render.
    #[arg(long, default_value_t = 360)]
    height: u32,
    /// Samples per pixel of the full render.
    #[arg(long, default_value_t = 1)]
    spp: u32,
    /// Photons of the full render (default: the scene's, at most 100,000).
    #[arg(long)]
    photons: Option<u64>,
    #[command(flatten)]
    backend: BackendArgs,
    /// No progress lines on stderr.
    #[arg(short, long)]
    quiet: bool,
}

#[derive(Args)]
struct StressArgs {
    /// Also write the table as JSON to this file.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Seed of the ray streams.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Rays (or trials) per case and configuration.
    #[arg(long, default_value_t = 200_000)]
    rays: u64,
}

#[cfg(feature = "embree")]
const DEFAULT_A: &str = "embree";
#[cfg(not(feature = "embree"))]
const DEFAULT_A: &str = "brute";

/// An error with its exit code.
struct Failure {
    code: u8,
    error: anyhow::Error,
}

/// Bad input (scene, mesh, arguments, output path): exit code 2.
fn bad_input(error: impl Into<anyhow::Error>) -> Failure {
    Failure {
        code: 2,
        error: error.into(),
    }
}

impl<E: Into<anyhow::Error>> From<E> for Failure {
    fn from(error: E) -> Self {
        Failure {
            code: 1,
            error: error.into(),
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    // A mistyped memory limit must not silently fall back to MemAvailable.
    if let Err(e) = caustic::analysis::memory::budget() {
        eprintln!("error: {e}");
        return ExitCode::from(2);
    }
    let result = match cli.command {
        Command::Render(args) => run_render(args),
        Command::Info(args) => run_info(args),
        Command::Crosscheck(args) => run_crosscheck(args),
        Command::Converge(args) => run_converge(args),
        Command::Bench(args) => run_bench(args),
        Command::Stress(args) => run_stress(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            eprintln!("error: {:#}", f.error);
            ExitCode::from(f.code)
        }
    }
}

fn load(path: &Path) -> Result<Scene, Failure> {
    scene::load_scene(path).map_err(bad_input)
}

/// Applies a `--photons` override, checked like the scene file's count.
fn override_photons(settings: &mut scene::RenderSettings, path: &Path, photons: Option<u64>) -> Result<(), Failure> {
    if let Some(n) = photons {
        scene::load::check_photon_count(n)
            .map_err(|e| bad_input(anyhow::anyhow!("{}: --photons: {e}", path.display())))?;
        settings.photons.count = n;
    }
    Ok(())
}

fn run_render(mut args: RenderArgs) -> Result<(), Failure> {
    let mut scene = load(&args.scene)?;
    if !(args.checkpoint_every.is_finite() && args.checkpoint_every > 0.0) {
        return Err(bad_input(anyhow::anyhow!(
            "--checkpoint-every {}: must be a positive number of seconds",
            args.checkpoint_every
        )));
    }
    let resumed = match &args.resume {
        Some(path) => Some(film::read_checkpoint(path).map_err(bad_input)?),
        None => None,
    };
    if let Some(c) = &resumed {
        // The checkpoint's settings are the defaults; explicit overrides
        // that differ are refused by the fingerprint check below.
        let m = &c.meta;
        args.width.get_or_insert(m.width);
        args.height.get_or_insert(m.height);
        args.spp.get_or_insert(m.spp);
        args.seed.get_or_insert(m.seed);
        args.photons.get_or_insert(m.photons);
        if args.accel.accel.is_none() {
            args.accel.accel = AccelArg::from_str(&m.accel, true).ok();
        }
    }
    let s = &mut scene.settings;
    s.width = args.width.unwrap_or(s.width);
    s.height = args.height.unwrap_or(s.height);
    s.spp = args.spp.unwrap_or(s.spp);
    s.seed = args.seed.unwrap_or(s.seed);
    override_photons(s, &args.scene, args.photons)?;
    scene::load::check_image_limits(s.width, s.height, s.spp).map_err(|e| {
        bad_input(anyhow::anyhow!(
            "{}: with the command-line overrides: {e}",
            args.scene.display()
        ))
    })?;
    args.accel.apply(&mut scene);

    let png = match (&args.output, &args.exr) {
        (Some(p), _) => Some(p.clone()),
        (None, Some(_)) => None,
        (None, None) => Some(PathBuf::from(format!(
            "{}.png",
            args.scene
                .file_stem()
                .map(|s| s.to_string_lossy())
                .unwrap_or_else(|| "render".into())
        ))),
    };
    let checkpoint = args.checkpoint.clone().or_else(|| args.resume.clone());
    let kind = args.accel.kind();
    let meta = checkpoint.as_ref().map(|_| {
        let st = &scene.settings;
        let options = match kind {
            AccelKind::Embree => format!(
                "quality {:?} robust {}",
                args.accel.options(&scene).embree_quality,
                args.accel.backend.embree_robust
            ),
            _ => String::new(),
        };
        film::CheckpointMeta {
            width: st.width,
            height: st.height,
            spp: st.spp,
            seed: st.seed,
            photons: st.photons.count,
            accel: kind.name().to_string(),
            fingerprint: integrator::resume::fingerprint(&scene, kind, &options),
        }
    });
    if let (Some(c), Some(now), Some(path)) = (&resumed, &meta, &args.resume) {
        if c.meta.fingerprint != now.fingerprint {
            return Err(bad_input(anyhow::anyhow!(
                "{}: the checkpoint is of a different render ({}); resume with the scene and settings it was started with",
                path.display(),
                checkpoint_differences(&c.meta, now)
            )));
        }
    }
    // Fail before hours of rendering, not after.
    for out in png.iter().chain(args.exr.iter()).chain(checkpoint.iter()) {
        film::check_writable(out).map_err(bad_input)?;
    }
    let interrupt = integrator::resume::Interrupt::install().context("cannot install the Ctrl-C handler")?;
    let start = match resumed {
        Some(c) => c.accumulation,
        None => film::Accumulation::new(scene.settings.width, scene.settings.height),
    };
    let long_run = LongRun {
        checkpoint: checkpoint.as_deref().zip(meta.as_ref()),
        start,
        interrupt: &interrupt,
    };

    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .context("cannot start the worker threads")?;
    pool.install(|| render_with(&scene, &args, png.as_deref(), long_run))
}

/// What differs between a checkpoint's recorded settings and this run's.
fn checkpoint_differences(then: &film::CheckpointMeta, now: &film::CheckpointMeta) -> String {
    let mut diffs = Vec::new();
    let mut field = |name: &str, a: String, b: String| {
        if a != b {
            diffs.push(format!("{name} {a} in the checkpoint, {b} now"));
        }
    };
    field("width", then.width.to_string(), now.width.to_string());
    field("height", then.height.to_string(), now.height.to_string());
    field("spp", then.spp.to_string(), now.spp.to_string());
    field("seed", then.seed.to_string(), now.seed.to_string());
    field("photons", then.photons.to_string(), now.photons.to_string());
    field("accelerator", then.accel.clone(), now.accel.clone());
    if diffs.is_empty() {
        "the scene file, a mesh or another setting changed".to_string()
    } else {
        diffs.join(", ")
    }
}

/// Checkpointing, resume state and the stop flag of one `render` run.
struct LongRun<'a> {
    checkpoint: Option<(&'a Path, &'a film::CheckpointMeta)>,
    start: film::Accumulation,
    interrupt: &'a integrator::resume::Interrupt,
}

fn render_with(scene: &Scene, args: &RenderArgs, png: Option<&Path>, run: LongRun) -> Result<(), Failure> {
    let kind = args.accel.kind();
    let accel = accel::build(scene, kind, &args.accel.options(scene))?;
    let stats = accel.stats();
    let mut plan = RenderPlan::new(scene);
    plan.keep_photon_positions = matches!(args.debug, Some(DebugView::Photons));
    let st = &scene.settings;
    if !args.quiet {
        eprintln!(
            "caustic: {} — {}×{}, {} spp, accelerator {} built in {:.3} s",
            args.scene.display(),
            st.width,
            st.height,
            st.spp,
            stats.name,
            stats.build_time.as_secs_f64()
        );
        eprintln!("{plan}");
    }

    let total_samples = st.width as u64 * st.height as u64 * st.spp as u64;
    let resumed_samples = run.start.samples_taken();
    if let Some(path) = &args.resume {
        let (lo, hi) = run.start.taken_range();
        eprintln!(
            "resuming {}: {resumed_samples} of {total_samples} samples done ({lo}–{hi} of {} spp per pixel)",
            path.display(),
            st.spp
        );
    }
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(total_samples)
    };
    bar.set_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}% ETA {eta}")
            .expect("static template"),
    );
    bar.set_position(resumed_samples);
    bar.reset_eta();
    let save = |acc: &film::Accumulation| {
        if let Some((path, meta)) = run.checkpoint {
            if let Err(e) = film::write_checkpoint(path, acc, meta) {
                bar.suspend(|| eprintln!("warning: checkpoint not saved (the render goes on): {e}"));
            }
        }
    };
    let progress = |done, _total| bar.set_position(done);
    let control = integrator::RenderControl {
        cancel: Some(run.interrupt.flag()),
        sample_limit: None,
        checkpoint: run.checkpoint.map(|_| integrator::CheckpointHook {
            every: Duration::from_secs_f64(args.checkpoint_every),
            save: &save,
        }),
        progress: &progress,
    };
    let start = Instant::now();
    let mut out = integrator::render_with_control(scene, accel.as_ref(), &plan, run.start, &control);
    bar.finish_and_clear();
    let samples_done = out.accumulation.samples_taken();
    if samples_done == 0 {
        // Stopped before the first sample: keep whatever files are there.
        return Err(Failure {
            code: run.interrupt.exit_code(),
            error: anyhow::anyhow!(
                "interrupted by {} before the first sample: nothing written",
                run.interrupt.signal_name().unwrap_or("a signal")
            ),
        });
    }
    let wall = start.elapsed();
    match args.debug {
        Some(DebugView::Photons) => match out.photon_map.clone() {
            Some(map) => integrator::debug::overlay_photons(&mut out.film, scene, &map),
            None => eprintln!("--debug photons: no photon map (the plan skipped the photon pass)"),
        },
        Some(DebugView::Kdtree) => {
            let tree = accel::kdtree::KdTreeAccel::build(scene, &args.accel.options(scene));
            integrator::debug::overlay_boxes(&mut out.film, &scene.camera, &tree.node_boxes(args.debug_depth));
        }
        None => {}
    }

    if let Some(p) = png {
        film::write_png(p, &out.film, st).map_err(bad_input)?;
    }
    if let Some(p) = &args.exr {
        film::write_exr(p, &out.film).map_err(bad_input)?;
    }
    if let Some((path, meta)) = run.checkpoint {
        film::write_checkpoint(path, &out.accumulation, meta)?;
    }
    let written: Vec<String> = png
        .iter()
        .map(|p| p.display().to_string())
        .chain(args.exr.iter().map(|p| p.display().to_string()))
        .chain(run.checkpoint.map(|(p, _)| format!("{} (checkpoint)", p.display())))
        .collect();
    println!("{}", out.stats.to_string().trim_end());
    println!(
        "total time: {:.3} s (accelerator build {:.3} s, render {:.3} s)",
        (wall + stats.build_time).as_secs_f64(),
        stats.build_time.as_secs_f64(),
        wall.as_secs_f64()
    );
    let plan_text = plan.to_string();
    let skipped: Vec<&str> = plan_text
        .lines()
        .filter(|l| l.contains("skipped"))
        .map(str::trim)
        .collect();
    println!(
        "skipped: {}",
        if skipped.is_empty() {
            "nothing".to_string()
        } else {
            skipped.join("; ")
        }
    );
    println!("written: {}", written.join(", "));
    if !out.complete {
        let (lo, hi) = out.accumulation.taken_range();
        let how_to_resume = match run.checkpoint {
            Some((path, _)) => format!(
                "; continue with: caustic render {} --resume {}",
                args.scene.display(),
                path.display()
            ),
            None => " (no --checkpoint: it cannot be resumed)".to_string(),
        };
        return Err(Failure {
            code: run.interrupt.exit_code(),
            error: anyhow::anyhow!(
                "interrupted by {}: {samples_done} of {total_samples} samples done ({lo}–{hi} of {} spp per pixel), \
                 partial image written{how_to_resume}",
                run.interrupt.signal_name().unwrap_or("a signal"),
                st.spp
            ),
        });
    }
    Ok(())
}

fn run_info(args: InfoArgs) -> Result<(), Failure> {
    let mut scene = load(&args.scene)?;
    args.accel.apply(&mut scene);
    let st = &scene.settings;
    let distinct: u64 = scene.meshes.iter().map(|m| m.triangles.len() as u64).sum();
    let b = scene.bounds();
    println!("scene       {}", args.scene.display());
    println!(
        "image       {}×{}, {} spp, max depth {}, seed {}",
        st.width, st.height, st.spp, st.max_depth, st.seed
    );
    println!(
        "objects     {} ({} mesh instances)",
        scene.objects.len(),
        scene
            .objects
            .iter()
            .filter(|o| matches!(o.shape, scene::Shape::Mesh { .. }))
            .count()
    );
    println!(
        "meshes      {} distinct, {} triangles ({} instanced)",
        scene.meshes.len(),
        distinct,
        scene.instanced_triangles()
    );
    println!("materials   {}", scene.materials.len());
    println!("lights      {}", scene.lights.len());
    println!(
        "bounds      [{:.4}, {:.4}, {:.4}] – [{:.4}, {:.4}, {:.4}]",
        b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z
    );
    let accel = accel::build(&scene, args.accel.kind(), &args.accel.options(&scene))?;
    let s = accel.stats();
    println!(
        "accelerator {}: built in {:.3} s, {:.1} MiB, {} BLAS, {} instances",
        s.name,
        s.build_time.as_secs_f64(),
        s.memory_bytes as f64 / (1024.0 * 1024.0),
        s.blas_count,
        s.instances
    );
    for (k, v) in &s.details {
        println!("            {k}: {v}");
    }
    if let Some(peak) = caustic::analysis::memory::peak_rss_bytes() {
        println!(
            "peak memory {:.1} MiB resident (scene + accelerator)",
            peak as f64 / (1u64 << 20) as f64
        );
    }
    println!("{}", RenderPlan::new(&scene));
    Ok(())
}

fn run_crosscheck(args: CrosscheckArgs) -> Result<(), Failure> {
    use caustic::analysis::crosscheck::{compare_one, crosscheck, parse_ray, CrosscheckOptions};
    let mut scene = load(&args.scene)?;
    args.accel.apply(&mut scene);
    let options = args.accel.options(&scene);
    let a = accel::build(&scene, args.a.into(), &options)?;
    let b = accel::build(&scene, args.b.into(), &options)?;
    let (sa, sb) = (a.stats(), b.stats());
    println!(
        "crosscheck {}: {} (built in {:.3} s) vs {} (built in {:.3} s)",
        args.scene.display(),
        sa.name,
        sa.build_time.as_secs_f64(),
        sb.name,
        sb.build_time.as_secs_f64()
    );
    if let Some(text) = &args.replay {
        let (ray, t_max) = parse_ray(text).map_err(bad_input)?;
        let c = compare_one(&scene, a.as_ref(), b.as_ref(), &ray, t_max);
        println!("{}", c.describe(&scene));
        return if c.is_ok() {
            Ok(())
        } else {
            Err(anyhow::anyhow!("the accelerators disagree on this ray").into())
        };
    }
    let start = Instant::now();
    let report = crosscheck(
        &scene,
        a.as_ref(),
        b.as_ref(),
        &CrosscheckOptions {
            rays: args.rays,
            seed: args.seed,
        },
    );
    println!("{report}");
    println!("{} rays in {:.2} s", args.rays, start.elapsed().as_secs_f64());
    if report.is_ok() {
        Ok(())
    } else {
        Err(anyhow::anyhow!("{} disagreement(s) that are not ties", report.disagreement_count()).into())
    }
}

fn run_converge(args: ConvergeArgs) -> Result<(), Failure> {
    use caustic::analysis::converge::{self, ConvergeOptions, CurveSpec};
    let mut scene = load(&args.scene)?;
    let s = &mut scene.settings;
    s.width = args.width.unwrap_or(s.width);
    s.height = args.height.unwrap_or(s.height);
    s.seed = args.seed.unwrap_or(s.seed);
    override_photons(s, &args.scene, args.photons)?;
    args.backend.apply(&mut scene);
    let accels: Vec<AccelKind> = if args.accel.is_empty() {
        caustic::analysis::bench::default_accels()
    } else {
        args.accel.iter().map(|&a| a.into()).collect()
    };
    let gathers: Vec<scene::GatherMode> = args
        .gather
        .iter()
        .map(|g| match g {
            GatherArg::Direct => scene::GatherMode::Direct,
            GatherArg::Precomputed => scene::GatherMode::Precomputed,
        })
        .collect();
    let options = ConvergeOptions {
        budgets: converge::parse_budgets(&args.budgets).map_err(bad_input)?,
        curves: CurveSpec::cross(&accels, &gathers),
        photons_per_spp: args.photons_per_spp,
        epsilon: args.epsilon,
        accel: args.backend.options(&scene),
    };
    let plot_size = args
        .plot_size
        .split_once('x')
        .and_then(|(w, h)| Some((w.parse::<u32>().ok()?, h.parse::<u32>().ok()?)))
        .ok_or_else(|| {
            bad_input(anyhow::anyhow!(
                "--plot-size {:?}: expected WIDTHxHEIGHT",
                args.plot_size
            ))
        })?;
    caustic::analysis::plot::check_size(plot_size.0, plot_size.1)
        .map_err(|e| bad_input(anyhow::anyhow!("--plot-size: {e}")))?;
    for out in args.csv.iter().chain(args.plot.iter()) {
        film::check_writable(out).map_err(bad_input)?;
    }
    let reference =
        converge::read_exr(&args.reference, Some((scene.settings.width, scene.settings.height))).map_err(bad_input)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .context("cannot start the worker threads")?;
    let quiet = args.quiet;
    let results = pool
        .install(|| {
            converge::run(&scene, &reference, &options, &mut |line| {
                if !quiet {
                    eprintln!("{line}");
                }
            })
        })
        .map_err(|e| match e {
            converge::ConvergeError::Accel { .. } => Failure::from(e),
            other => bad_input(other),
        })?;
    print!("{}", converge::table_text(&results, options.epsilon));
    if let Some(p) = &args.csv {
        converge::write_csv(p, &results).map_err(bad_input)?;
        println!("written: {}", p.display());
    }
    if let Some(p) = &args.plot {
        let title = args.scene.file_stem().map(|s| s.to_string_lossy()).unwrap_or_default();
        converge::write_plot(p, &results, &title, options.epsilon, plot_size.0, plot_size.1).map_err(bad_input)?;
        println!("written: {}", p.display());
    }
    Ok(())
}

fn run_bench(args: BenchArgs) -> Result<(), Failure> {
    use caustic::analysis::bench::{self, BenchOptions, RenderOverrides};
    let scenes = if args.scenes.is_empty() {
        vec![bench::default_scene()]
    } else {
        args.scenes
    };
    if let Some(path) = &args.json {
        film::check_writable(path).map_err(bad_input)?;
    }
    let options = BenchOptions {
        accels: if args.accel.is_empty() {
            bench::default_accels()
        } else {
            args.accel.iter().map(|&a| a.into()).collect()
        },
        rays: args.rays,
        seed: args.seed,
        repeats: args.repeats,
        render: RenderOverrides {
            width: args.width,
            height: args.height,
            spp: args.spp,
            photons: args.photons,
        },
        accel_options: AccelOptions {
            triangle_test: args
                .backend
                .triangle_test()
                .unwrap_or(AccelOptions::default().triangle_test),
            embree_quality: args.backend.embree_quality.name().into(),
            embree_robust: args.backend.embree_robust,
        },
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .context("cannot start the worker threads")?;
    let quiet = args.quiet;
    let report = pool
        .install(|| {
            bench::run(&scenes, &options, &|line| {
                if !quiet {
                    eprintln!("bench: {line}");
                }
            })
        })
        .map_err(|e| if e.is_bad_input() { bad_input(e) } else { e.into() })?;
    print!("{report}");
    if let Some(path) = &args.json {
        report.write_json(path).map_err(bad_input)?;
        println!("written: {}", path.display());
    }
    Ok(())
}

fn run_stress(args: StressArgs) -> Result<(), Failure> {
    use caustic::analysis::stress::{run_stress, StressOptions};
    if let Some(path) = &args.json {
        film::check_writable(path).map_err(bad_input)?;
    }
    let start = Instant::now();
    let report = run_stress(&StressOptions {
        seed: args.seed,
        rays: args.rays.max(1),
        progress: true,
        ..StressOptions::default()
    });
    println!("{report}");
    println!("stress run in {:.1} s", start.elapsed().as_secs_f64());
    if let Some(path) = &args.json {
        report
            .write_json(path)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    match report.default_failures() {
        0 => Ok(()),
        n => Err(anyhow::anyhow!("{n} failure(s) in default configurations").into()),
    }
}
