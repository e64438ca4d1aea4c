//! The inspection and measurement commands: `info`, `crosscheck`,
//! `converge`, `bench` and `stress`.

use crate::args::{BenchArgs, ConvergeArgs, CrosscheckArgs, GatherArg, InfoArgs, StressArgs};
use crate::{bad_input, job_failure, load, Failure};
use anyhow::Context;
use caustic::accel::{self, AccelKind, AccelOptions};
use caustic::film;
use caustic::integrator::RenderPlan;
use caustic::job::Overrides;
use caustic::math::SamplerKind;
use caustic::scene::{self, IntegratorKind, LoadedScene};
use std::time::Instant;

pub fn run_info(args: InfoArgs) -> Result<(), Failure> {
    let mut load_times = None;
    let LoadedScene { scene, mut settings } = if scene::mitsuba::is_mitsuba_path(&args.scene) {
        let loaded = scene::mitsuba::load_mitsuba_scene(&args.scene, &args.defines.defines).map_err(bad_input)?;
        for w in &loaded.warnings {
            eprintln!("warning: {w}");
        }
        load_times = Some((loaded.xml_seconds, loaded.mesh_seconds));
        LoadedScene {
            scene: loaded.scene,
            settings: loaded.settings,
        }
    } else {
        load(&args.scene, &args.defines)?
    };
    args.accel.apply(&mut settings);
    if let Some(i) = args.integrator {
        settings.integrator = i.into();
    }
    let st = &settings;
    let distinct: u64 = scene.meshes.iter().map(|m| m.triangles.len() as u64).sum();
    let b = scene.bounds();
    println!("scene       {}", args.scene.display());
    if let Some((xml, meshes)) = load_times {
        println!("loaded      Mitsuba XML read and built in {xml:.4} s, mesh files in {meshes:.4} s");
    }
    let depth = match (st.max_depth, st.integrator) {
        (Some(d), _) => d.to_string(),
        (None, IntegratorKind::Whitted) => st.whitted_depth().to_string(),
        (None, IntegratorKind::Path) => "unbounded (Russian roulette)".to_string(),
    };
    println!(
        "image       {}×{}, {} spp, max depth {depth}, seed {}",
        st.width, st.height, st.spp, st.seed
    );
    println!("integrator  {}", st.integrator.name());
    let count = |kind: fn(&scene::Shape) -> bool| scene.objects.iter().filter(|o| kind(&o.shape)).count();
    // Disks and cylinders only when present (the line of other scenes is unchanged).
    let analytic: String = [
        ("disk", count(|s| matches!(s, scene::Shape::Disk(_)))),
        ("cylinder", count(|s| matches!(s, scene::Shape::Cylinder(_)))),
    ]
    .iter()
    .filter(|(_, n)| *n > 0)
    .map(|(name, n)| format!(", {n} {name}{}", if *n == 1 { "" } else { "s" }))
    .collect();
    println!(
        "objects     {} ({} mesh instances{analytic})",
        scene.objects.len(),
        count(|s| matches!(s, scene::Shape::Mesh { .. }))
    );
    let mesh_bytes: usize = scene.meshes.iter().map(|m| m.memory_bytes()).sum();
    let with_uvs = scene.meshes.iter().filter(|m| !m.uvs.is_empty()).count();
    println!(
        "meshes      {} distinct, {} triangles ({} instanced), {:.1} MiB, {with_uvs} with texture coordinates",
        scene.meshes.len(),
        distinct,
        scene.instanced_triangles(),
        mesh_bytes as f64 / (1 << 20) as f64
    );
    println!("materials   {}", scene.materials.len());
    let images = scene.texture_images();
    if !images.is_empty() {
        let bytes: usize = images.iter().map(|i| i.memory_bytes()).sum();
        println!(
            "textures    {} images, {:.1} MiB",
            images.len(),
            bytes as f64 / (1 << 20) as f64
        );
    }
    println!("lights      {}", scene.lights.len());
    for light in &scene.lights {
        if let scene::Light::Environment { map: Some(m), .. } = light {
            println!(
                "            environment image {}: {}×{}, {:.1} MiB",
                m.image.name,
                m.image.width,
                m.image.height,
                m.image.memory_bytes() as f64 / (1 << 20) as f64
            );
        }
    }
    let c = &scene.camera;
    let kind = match c.projection {
        caustic::scene::Projection::Orthographic {
            half_width,
            half_height,
        } => format!("orthographic (at least {half_width} × {half_height} half extents)"),
        caustic::scene::Projection::Perspective if c.has_lens() => "thin lens".into(),
        caustic::scene::Projection::Perspective => "pinhole".into(),
    };
    println!(
        "camera      {kind}, pixel filter {} (radius {} px)",
        c.filter.name(),
        c.filter.radius()
    );
    println!(
        "bounds      [{:.4}, {:.4}, {:.4}] – [{:.4}, {:.4}, {:.4}]",
        b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z
    );
    let accel = accel::build(&scene, args.accel.kind(), &args.accel.options(&settings))?;
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
    match caustic::film::denoise::library() {
        Some((version, source)) => println!("denoiser    Open Image Denoise {version} ({source})"),
        None => println!("denoiser    none (built without the `denoise` feature)"),
    }
    if let Some(peak) = caustic::memory::peak_rss_bytes() {
        println!(
            "peak memory {:.1} MiB resident (scene + accelerator)",
            peak as f64 / (1u64 << 20) as f64
        );
    }
    println!("{}", RenderPlan::new(&scene, &settings));
    for w in caustic::integrator::lint::warnings(&scene, &settings) {
        println!("warning: {w}");
    }
    Ok(())
}

pub fn run_crosscheck(args: CrosscheckArgs) -> Result<(), Failure> {
    use caustic::analysis::crosscheck::{compare_one, crosscheck, parse_ray, CrosscheckOptions};
    let LoadedScene { scene, mut settings } = load(&args.scene, &args.defines)?;
    args.accel.apply(&mut settings);
    let options = args.accel.options(&settings);
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
            image: (settings.width, settings.height),
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

pub fn run_converge(args: ConvergeArgs) -> Result<(), Failure> {
    use caustic::analysis::converge::{self, ConvergeOptions, CurveSpec};
    let mut loaded = load(&args.scene, &args.defines)?;
    Overrides {
        width: args.width,
        height: args.height,
        seed: args.seed,
        photons: args.photons,
        progressive_photons: args.progressive_photons.then_some(true),
        ppm_alpha: args.ppm_alpha,
        triangle_test: args.backend.triangle_test(),
        integrator: args.integrator.map(Into::into),
        sampler: args.sampler.map(Into::into),
        noise_threshold: None,
        min_spp: None,
        adaptive_goal: args.adaptive_goal.map(Into::into),
        caustics: args.caustics.map(Into::into),
        ..Overrides::default()
    }
    .apply(&mut loaded, &args.scene)
    .map_err(job_failure)?;
    let settings = &mut loaded.settings;
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
    let samplers: Vec<SamplerKind> = args.samplers.iter().map(|&s| s.into()).collect();
    for &t in &args.adaptive {
        if !(t > 0.0 && t < 1.0) {
            return Err(bad_input(anyhow::anyhow!(
                "--adaptive {t}: noise thresholds must be in (0, 1)"
            )));
        }
    }
    if let Some(t) = args.target_relmse {
        if !(t.is_finite() && t > 0.0) {
            return Err(bad_input(anyhow::anyhow!(
                "--target-relmse {t}: must be a positive number"
            )));
        }
    }
    if args.denoise {
        film::denoise::require().map_err(bad_input)?;
    }
    if let Some(q) = args.denoise_quality {
        settings.denoise_quality = q.into();
    }
    let max_spp = args.max_spp.unwrap_or(1024);
    caustic::limits::check_image_limits(settings.width, settings.height, max_spp)
        .map_err(|e| bad_input(anyhow::anyhow!("--max-spp {max_spp}: {e}")))?;
    if let Some(n) = args.min_spp {
        if n < 2 || n > max_spp.max(2) {
            return Err(bad_input(anyhow::anyhow!(
                "--min-spp {n}: must be in 2..={} (--max-spp)",
                max_spp.max(2)
            )));
        }
        settings.min_spp = n;
    }
    let options = ConvergeOptions {
        budgets: converge::parse_budgets(&args.budgets).map_err(bad_input)?,
        curves: CurveSpec::with_denoise(
            &CurveSpec::with_samplers(
                &CurveSpec::cross(&accels, &gathers),
                &samplers,
                !args.adaptive.is_empty() || args.adaptive_search,
            ),
            args.denoise,
        ),
        photons_per_spp: args.photons_per_spp,
        epsilon: args.epsilon,
        accel: args.backend.options(settings),
        thresholds: args.adaptive.clone(),
        max_spp,
        target_relmse: args.target_relmse,
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
    let reference = converge::read_exr(&args.reference, Some((settings.width, settings.height))).map_err(bad_input)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .context("cannot start the worker threads")?;
    let quiet = args.quiet;
    let results = pool
        .install(|| {
            converge::run(&loaded, &reference, &options, &mut |line| {
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
    if let Some(target) = options.target_relmse {
        println!("time to relMSE {target:e}:");
        for (curve, seconds) in converge::time_to_error(&results, target) {
            match seconds {
                Some(s) => println!("  {curve:<28} {s:.3} s"),
                None => println!("  {curve:<28} not reached"),
            }
        }
    }
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

pub fn run_bench(args: BenchArgs) -> Result<(), Failure> {
    use caustic::analysis::bench::{self, BenchOptions, RenderOverrides};
    let scenes = if args.scenes.is_empty() {
        bench::default_scenes()
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
        defines: args.defines.defines.clone(),
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

pub fn run_stress(args: StressArgs) -> Result<(), Failure> {
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
