//! `caustic render` (a [`RenderJob`] with a progress bar, Ctrl-C and a summary), `caustic merge` and `caustic photons`.

use crate::args::{DebugView, MergeArgs, PhotonsArgs, RenderArgs};
use crate::{bad_input, job_failure, Failure};
use anyhow::Context;
use caustic::accel::AccelKind;
use caustic::film::{self, ShardMode, ShardSet};
use caustic::job::{self, JobError, Overrides, RenderJob, RenderRequest};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;
use std::time::Duration;

pub fn run_render(args: RenderArgs) -> Result<(), Failure> {
    if !(args.checkpoint_every.is_finite() && args.checkpoint_every > 0.0) {
        return Err(bad_input(anyhow::anyhow!(
            "--checkpoint-every {}: must be a positive number of seconds",
            args.checkpoint_every
        )));
    }
    let shard = shard_request(&args)?;
    // `-o NAME.exr` asks for the linear EXR, not a PNG under that name.
    let (output, exr) = match (&args.output, &args.exr) {
        (Some(o), Some(e)) if shard.is_none() && is_exr(o) => {
            return Err(bad_input(anyhow::anyhow!(
                "-o {} and --exr {}: -o names the EXR when it ends in .exr; give one of them",
                o.display(),
                e.display()
            )));
        }
        (Some(o), None) if shard.is_none() && is_exr(o) => (None, Some(o.clone())),
        _ => (args.output.clone(), args.exr.clone()),
    };
    let png = match (&output, &exr) {
        _ if shard.is_some() => None,
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
    let request = RenderRequest {
        scene: args.scene.clone(),
        overrides: Overrides {
            width: args.width,
            height: args.height,
            spp: args.spp.or(args.max_spp),
            seed: args.seed,
            photons: args.photons,
            progressive_photons: args.progressive_photons.then_some(true),
            ppm_alpha: args.ppm_alpha,
            triangle_test: args.accel.backend.triangle_test(),
            integrator: args.integrator.map(Into::into),
            sampler: args.sampler.map(Into::into),
            noise_threshold: args.noise_threshold,
            min_spp: args.min_spp,
            adaptive_goal: args.adaptive_goal.map(Into::into),
            denoise: args.denoise.then_some(true),
            denoise_quality: args.denoise_quality.map(Into::into),
            caustics: args.caustics.map(Into::into),
            defines: args.defines.defines.clone(),
            camera: args.camera.clone(),
            allow_outside_files: args.allow_outside_files,
            environment: args.environment.clone(),
            environment_intensity: args.environment_intensity,
            environment_rotation: args.environment_rotation,
        },
        accel: args.accel.accel.map(AccelKind::from),
        embree_quality: args.accel.backend.embree_quality.name().into(),
        embree_robust: args.accel.backend.embree_robust,
        png,
        exr,
        checkpoint: match &shard {
            // A shard's partial is its checkpoint: -o, or the resumed file.
            Some(_) => args.output.clone().or_else(|| args.resume.clone()),
            None => args.checkpoint.clone(),
        },
        checkpoint_every: Duration::from_secs_f64(args.checkpoint_every),
        resume: args.resume.clone(),
        time_limit: time_limit(args.time_limit)?,
        debug: args.debug.map(|d| match d {
            DebugView::Photons => job::DebugView::Photons,
            DebugView::Kdtree => job::DebugView::KdTree {
                depth: args.debug_depth,
            },
        }),
        shard: shard.flatten(),
        photon_map: args.photon_map.clone(),
    };
    let job = RenderJob::prepare(&request).map_err(job_failure)?;
    let interrupt = job::Interrupt::install().context("cannot install the Ctrl-C handler")?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .context("cannot start the worker threads")?;
    pool.install(|| render_job(job, &args, &interrupt))
}

/// The shard to render: `Some(Some(set))` for `--shard`, `Some(None)` when
/// resuming a partial without `--shard` (its own shard is used), `None`
/// for a whole render.
fn shard_request(args: &RenderArgs) -> Result<Option<Option<ShardSet>>, Failure> {
    let mode = args.shard_by.map_or(ShardMode::Tiles, ShardMode::from);
    let shard = match &args.shard {
        Some(text) => {
            let var = |name: &str| std::env::var(name).ok();
            let id = job::parse_shard_arg(text, args.shard_count, &var).map_err(|e| bad_input(anyhow::anyhow!(e)))?;
            Some(Some(ShardSet::single(id, mode)))
        }
        None => match &args.resume {
            Some(path) => {
                let meta = film::read_checkpoint_meta(path).map_err(bad_input)?;
                meta.shard.map(|_| None)
            }
            None => None,
        },
    };
    if shard.is_some() {
        if args.exr.is_some() || args.checkpoint.is_some() {
            return Err(bad_input(anyhow::anyhow!(
                "a shard writes only its partial (-o PART.exr), saved every --checkpoint-every seconds: \
                 --exr and --checkpoint do not apply; merge the partials with caustic merge"
            )));
        }
        if let Some(out) = args.output.as_ref().filter(|p| !is_exr(p)) {
            return Err(bad_input(anyhow::anyhow!(
                "-o {}: a shard writes its partial as an EXR: name it PART.exr (merge the partials into a PNG \
                 with caustic merge)",
                out.display()
            )));
        }
        if args.output.is_none() && args.resume.is_none() {
            return Err(bad_input(anyhow::anyhow!(
                "--shard needs -o PART.exr: the file its partial is written to"
            )));
        }
    }
    Ok(shard)
}

/// `caustic merge`: partials into an image or a new partial.
pub fn run_merge(args: MergeArgs) -> Result<(), Failure> {
    let request = job::MergeRequest {
        partials: args.partials,
        png: args.output,
        exr: args.exr,
        partial: args.partial,
        denoise: args.denoise,
        denoise_quality: args.denoise_quality.into(),
    };
    let report = job::merge_partials(&request).map_err(job_failure)?;
    if !args.quiet {
        let m = &report.meta;
        if let Some(set) = &m.shard {
            println!(
                "merged {set}: {}×{}, {} spp, seed {}, {} samples",
                m.width,
                m.height,
                m.spp,
                m.seed,
                report.accumulation.samples_taken()
            );
        }
        if let Some(d) = &report.denoise {
            println!("denoised in {:.3} s", d.time.as_secs_f64());
        }
        println!("written: {}", report.written.join(", "));
    }
    Ok(())
}

/// `caustic photons`: the traced photons of a scene into a file.
pub fn run_photons(args: PhotonsArgs) -> Result<(), Failure> {
    let request = job::PhotonsRequest {
        scene: args.scene.clone(),
        overrides: Overrides {
            width: args.width,
            height: args.height,
            spp: args.spp,
            seed: args.seed,
            photons: args.photons,
            triangle_test: args.accel.backend.triangle_test(),
            integrator: args.integrator.map(Into::into),
            defines: args.defines.defines.clone(),
            ..Overrides::default()
        },
        accel: args.accel.accel.map(AccelKind::from),
        accel_options: caustic::accel::AccelOptions {
            embree_quality: args.accel.backend.embree_quality.name().into(),
            embree_robust: args.accel.backend.embree_robust,
            ..Default::default()
        },
        output: args.output.clone(),
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .context("cannot start the worker threads")?;
    let report = pool.install(|| job::trace_to_file(&request)).map_err(job_failure)?;
    if !args.quiet {
        println!(
            "photons: {} emitted, {} stored, {} rays, traced in {:.3} s; written {} ({:.1} MiB in {:.3} s)",
            report.emitted,
            report.stored,
            report.rays,
            report.trace_time.as_secs_f64(),
            args.output.display(),
            report.bytes as f64 / (1024.0 * 1024.0),
            report.write_time.as_secs_f64()
        );
    }
    Ok(())
}

/// `--time-limit SECONDS` as a duration (positive and finite).
fn time_limit(seconds: Option<f64>) -> Result<Option<Duration>, Failure> {
    match seconds {
        None => Ok(None),
        Some(s) if s.is_finite() && s > 0.0 && s < 1.0e9 => Ok(Some(Duration::from_secs_f64(s))),
        Some(s) => Err(bad_input(anyhow::anyhow!(
            "--time-limit {s}: must be a positive number of seconds"
        ))),
    }
}

fn render_job(job: RenderJob, args: &RenderArgs, interrupt: &job::Interrupt) -> Result<(), Failure> {
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(1)
    };
    bar.set_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}% ETA {eta}")
            .expect("static template"),
    );
    let (scene_path, resumed_from) = (job.source.clone(), job.resumed_from.clone());
    let checkpoint = job.checkpoint.as_ref().map(|(p, _)| p.clone());
    let shard = job.shard.clone();
    let started = |start: &job::JobStart| {
        let st = start.plan;
        if !args.quiet {
            eprintln!(
                "caustic: {} — {}×{}, {} spp, accelerator {} built in {:.3} s",
                scene_path.display(),
                st.width,
                st.height,
                st.spp,
                start.accel.name,
                start.accel.build_time.as_secs_f64()
            );
            eprintln!("{}", start.plan);
            if let Some(set) = &shard {
                eprintln!("rendering {set}: {} samples", start.total_samples);
            }
        }
        for w in start.warnings {
            eprintln!("warning: {w}");
        }
        if let Some(path) = &resumed_from {
            eprintln!(
                "resuming {}: {} of {} samples done",
                path.display(),
                start.resumed_samples,
                start.total_samples
            );
        }
        bar.set_length(start.total_samples);
        bar.set_position(start.resumed_samples);
        bar.reset_eta();
    };
    let progress = |done, _total| bar.set_position(done);
    let warn = |message: &str| bar.suspend(|| eprintln!("warning: {message}"));
    let hooks = job::JobHooks {
        cancel: Some(interrupt.flag()),
        started: &started,
        progress: &progress,
        warn: &warn,
    };
    let signal = || interrupt.signal_name().unwrap_or("a signal");
    let report = match job.run(&hooks) {
        Ok(r) => r,
        Err(JobError::StoppedBeforeFirstSample) => {
            return Err(Failure {
                code: interrupt.exit_code(),
                error: anyhow::anyhow!("interrupted by {} before the first sample: nothing written", signal()),
            })
        }
        Err(e) => return Err(job_failure(e)),
    };
    bar.finish_and_clear();
    let build = report.accel.build_time;
    println!("{}", report.output.stats.to_string().trim_end());
    println!(
        "total time: {:.3} s (accelerator build {:.3} s, render {:.3} s)",
        (report.render_time + build).as_secs_f64(),
        build.as_secs_f64(),
        report.render_time.as_secs_f64()
    );
    if let Some(d) = &report.denoise {
        let memory = d
            .peak_memory
            .map_or("not measured".to_string(), caustic::memory::format_bytes);
        println!(
            "denoised: Open Image Denoise {} ({} quality, albedo and normal) in {:.3} s, peak memory +{memory} \
             for {}×{}",
            film::denoise::library().map_or("?", |l| l.0),
            d.quality.name(),
            d.time.as_secs_f64(),
            report.plan.width,
            report.plan.height
        );
    }
    let skipped: Vec<String> = report.plan.skipped().iter().map(ToString::to_string).collect();
    println!(
        "skipped: {}",
        if skipped.is_empty() {
            "nothing".to_string()
        } else {
            skipped.join("; ")
        }
    );
    println!("written: {}", report.written.join(", "));
    let acc = &report.output.accumulation;
    if report.plan.adaptive.is_some() {
        let converged = acc.converged.iter().filter(|&&c| c).count();
        println!(
            "adaptive sampling: {converged} of {} pixels converged, {:.1} samples per pixel on average",
            acc.len(),
            acc.samples_taken() as f64 / acc.len().max(1) as f64
        );
    }
    if report.output.timed_out {
        println!(
            "time limit reached: {} of {} samples done ({}–{} per pixel)",
            report.samples_done(),
            report.total_samples,
            acc.taken_range().0,
            acc.taken_range().1
        );
        return Ok(());
    }
    if !report.complete() {
        let (lo, hi) = report.output.accumulation.taken_range();
        let how_to_resume = match &checkpoint {
            Some(path) => format!(
                "; continue with: caustic render {} --resume {}",
                scene_path.display(),
                path.display()
            ),
            None => " (no --checkpoint: it cannot be resumed)".to_string(),
        };
        return Err(Failure {
            code: interrupt.exit_code(),
            error: anyhow::anyhow!(
                "interrupted by {}: {} of {} samples done ({lo}–{hi} of {} spp per pixel), \
                 partial image written{how_to_resume}",
                signal(),
                report.samples_done(),
                report.total_samples,
                report.spp()
            ),
        });
    }
    Ok(())
}

/// True when `p` names an EXR file.
fn is_exr(p: &std::path::Path) -> bool {
    p.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"))
}
