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
use std::time::Instant;

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
    /// Ray–triangle test of the in-house backends (default: the scene's, watertight).
    #[arg(long, value_enum)]
    triangle_test: Option<TriangleTestArg>,
    /// Embree BVH build quality.
    #[arg(long, value_enum, default_value = "high")]
    embree_quality: QualityArg,
    /// Embree robust traversal mode.
    #[arg(long)]
    embree_robust: bool,
}

impl AccelArgs {
    fn kind(&self) -> AccelKind {
        self.accel.map(AccelKind::from).unwrap_or_else(AccelKind::default_kind)
    }

    fn options(&self, scene: &Scene) -> AccelOptions {
        AccelOptions {
            triangle_test: scene.settings.triangle_test,
            embree_quality: match self.embree_quality {
                QualityArg::Low => "low",
                QualityArg::Medium => "medium",
                QualityArg::High => "high",
            }
            .into(),
            embree_robust: self.embree_robust,
        }
    }

    fn apply(&self, scene: &mut Scene) {
        if let Some(t) = self.triangle_test {
            scene.settings.triangle_test = match t {
                TriangleTestArg::Watertight => TriangleTest::Watertight,
                TriangleTestArg::MollerTrumbore => TriangleTest::MollerTrumbore,
            };
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

fn run_render(args: RenderArgs) -> Result<(), Failure> {
    let mut scene = load(&args.scene)?;
    let s = &mut scene.settings;
    s.width = args.width.unwrap_or(s.width);
    s.height = args.height.unwrap_or(s.height);
    s.spp = args.spp.unwrap_or(s.spp);
    s.seed = args.seed.unwrap_or(s.seed);
    if let Some(n) = args.photons {
        scene::load::check_photon_count(n)
            .map_err(|e| bad_input(anyhow::anyhow!("{}: --photons: {e}", args.scene.display())))?;
        s.photons.count = n;
    }
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
    // Fail before hours of rendering, not after.
    for out in png.iter().chain(args.exr.iter()) {
        film::check_writable(out).map_err(bad_input)?;
    }

    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .context("cannot start the worker threads")?;
    pool.install(|| render_with(&scene, &args, png.as_deref()))
}

fn render_with(scene: &Scene, args: &RenderArgs, png: Option<&Path>) -> Result<(), Failure> {
    let kind = args.accel.kind();
    let accel = accel::build(scene, kind, &args.accel.options(scene))?;
    let stats = accel.stats();
    let plan = RenderPlan::new(scene);
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

    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new((st.width * st.height) as u64)
    };
    bar.set_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}% ETA {eta}")
            .expect("static template"),
    );
    let start = Instant::now();
    let mut out = integrator::render::render(scene, accel.as_ref(), &plan, &|done, _total| bar.set_position(done));
    bar.finish_and_clear();
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
    let written: Vec<String> = png
        .iter()
        .map(|p| p.display().to_string())
        .chain(args.exr.iter().map(|p| p.display().to_string()))
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
