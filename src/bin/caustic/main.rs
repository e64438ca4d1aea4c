//! The `caustic` command line: parses arguments, calls the library, maps
//! errors to exit codes (2 for bad input, 1 for internal failures).

mod args;
mod measure;
mod render;
mod view;

use args::{
    BenchArgs, ConvergeArgs, ConvertArgs, CrosscheckArgs, InfoArgs, MergeArgs, PhotonsArgs, RenderArgs, StressArgs,
    ViewArgs,
};
use caustic::job::JobError;
use caustic::scene::{self, LoadedScene};
use clap::{Parser, Subcommand};
use std::path::Path;
use std::process::ExitCode;

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
    /// Merge the partials of a render split with `render --shard` into one
    /// image (every shard) or into a new partial (any subset).
    Merge(MergeArgs),
    /// Trace a scene's caustic photons once into a file that renders (every
    /// shard of one) load with --photon-map instead of tracing them.
    Photons(PhotonsArgs),
    /// Print scene statistics, the accelerator build and the render plan.
    Info(InfoArgs),
    /// Write any scene caustic reads (TOML, Mitsuba XML with -D, or a glTF model) as
    /// caustic TOML that loads back to the same scene; meshes built in
    /// memory go beside it as PLY files.
    Convert(ConvertArgs),
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
    /// Open the interactive viewer: a progressive image beside the control
    /// panel (lights, materials, photons, samples, accelerator), camera
    /// navigation with the mouse, `p`/`k` debug views, save image and scene.
    View(ViewArgs),
}

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
    if let Err(e) = caustic::memory::budget() {
        eprintln!("error: {e}");
        return ExitCode::from(2);
    }
    let result = match cli.command {
        Command::Render(args) => render::run_render(args),
        Command::Merge(args) => render::run_merge(args),
        Command::Photons(args) => render::run_photons(args),
        Command::Info(args) => measure::run_info(args),
        Command::Convert(args) => run_convert(args),
        Command::Crosscheck(args) => measure::run_crosscheck(args),
        Command::Converge(args) => measure::run_converge(args),
        Command::Bench(args) => measure::run_bench(args),
        Command::Stress(args) => measure::run_stress(args),
        Command::View(args) => view::run_view(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            eprintln!("error: {:#}", f.error);
            ExitCode::from(f.code)
        }
    }
}

fn load(path: &Path, defines: &args::DefineArgs) -> Result<LoadedScene, Failure> {
    scene::load_scene_with(path, &defines.defines).map_err(bad_input)
}

/// `caustic convert`: the scene read, written as TOML, checked by reading
/// it back.
fn run_convert(args: ConvertArgs) -> Result<(), Failure> {
    let scene = load(&args.scene, &args.defines)?;
    let written = scene::write::write_toml_scene(&scene, &args.output).map_err(|e| Failure {
        code: if e.is_input() { 2 } else { 1 },
        error: e.into(),
    })?;
    println!("wrote {}", written.scene.display());
    for m in &written.meshes {
        println!("wrote {}", m.display());
    }
    for m in &written.referenced {
        println!("references {}", m.display());
    }
    Ok(())
}

/// A job's error with the exit code its kind calls for.
fn job_failure(e: JobError) -> Failure {
    Failure {
        code: if e.is_bad_input() { 2 } else { 1 },
        error: e.into(),
    }
}
