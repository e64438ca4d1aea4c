//! Adaptive sampling, the Sobol sampler and the time budget: pixels stop
//! where the noise is low, the image keeps its expected value, and renders
//! stay deterministic across thread counts and across interrupt and resume.

mod common;

use caustic::accel::AccelKind;
use caustic::film::{read_checkpoint, write_checkpoint, Accumulation, CheckpointMeta};
use caustic::integrator::{render, RenderControl, RenderOutput, RenderPlan, RenderSetup};
use caustic::math::{SamplerKind, Vec3A};
use caustic::scene::LoadedScene;
use caustic::scene::{load_scene, AdaptiveGoal, IntegratorKind, Light};
use common::cli::caustic;
use common::scenes::build;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

/// The test Cornell-like scene with glass and an area light, path traced,
/// adaptive: noise differs a lot between the walls and the caustic.
fn adaptive_scene(threshold: f32) -> LoadedScene {
    let mut scene = load_scene(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/test/caustic.toml")).unwrap();
    let s = &mut scene.settings;
    s.width = 36;
    s.height = 28;
    s.spp = 256;
    s.seed = 4;
    s.integrator = IntegratorKind::Path;
    s.noise_threshold = Some(threshold);
    s.min_spp = 8;
    scene
}

#[test]
fn pixels_stop_where_the_noise_is_low_and_the_error_estimate_follows_the_noise() {
    let scene = adaptive_scene(0.08);
    let accel = build(&scene.scene, AccelKind::KdTree);
    let plan = RenderPlan::new(&scene.scene, &scene.settings);
    assert_eq!(plan.sampler, SamplerKind::Sobol);
    let out = render(&scene.scene, accel.as_ref(), &plan, RenderSetup::default());
    let acc = &out.accumulation;
    assert!(out.complete);
    let (lo, hi) = acc.taken_range();
    assert!(lo >= 8 && lo < hi, "sample counts {lo}..{hi}: nothing adapted");
    let converged = acc.converged.iter().filter(|&&c| c).count();
    assert!(
        converged > acc.len() / 4,
        "only {converged} of {} pixels stopped",
        acc.len()
    );
    // The noisiest pixels took the most samples.
    let mut by_spp: Vec<(u32, f32)> = (0..acc.len()).map(|i| (acc.taken[i], acc.relative_error(i))).collect();
    by_spp.sort_by_key(|p| p.0);
    assert!(by_spp.iter().all(|p| p.1.is_finite()), "every pixel has both halves");
}

/// The image mean of adaptive renders is the mean of a long fixed-spp
/// render: stopping does not bias it (several seeds; a diffuse scene with
/// soft shadows, whose samples have no heavy tail to hide a bias).
#[test]
fn adaptive_stopping_does_not_bias_the_image() {
    let mut reference_scene =
        load_scene(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/test/shadow.toml")).unwrap();
    let s = &mut reference_scene.settings;
    s.integrator = IntegratorKind::Path;
    s.spp = 4096;
    s.width = 24;
    s.height = 18;
    s.min_spp = 8;
    let accel = build(&reference_scene.scene, AccelKind::KdTree);
    let reference = render(
        &reference_scene.scene,
        accel.as_ref(),
        &RenderPlan::new(&reference_scene.scene, &reference_scene.settings),
        RenderSetup::default(),
    );
    let mean = |o: &RenderOutput| o.film.pixels.iter().map(|p| (p.x + p.y + p.z) as f64).sum::<f64>();
    let truth = mean(&reference);
    // Both goals (the image goal's stops are looser), over several seeds.
    for (goal, first_seed) in [(AdaptiveGoal::Pixel, 100), (AdaptiveGoal::Image, 200)] {
        let seeds = 6;
        let sum: f64 = (0..seeds)
            .map(|seed| {
                let mut s = reference_scene.clone();
                s.settings.spp = 512;
                s.settings.noise_threshold = Some(0.05);
                s.settings.adaptive_goal = goal;
                s.settings.seed = first_seed + seed;
                let out = render(
                    &s.scene,
                    accel.as_ref(),
                    &RenderPlan::new(&s.scene, &s.settings),
                    RenderSetup::default(),
                );
                assert!(out.accumulation.converged.iter().any(|&c| c));
                mean(&out)
            })
            .sum();
        let ratio = sum / seeds as f64 / truth;
        assert!(
            (ratio - 1.0).abs() < 0.01,
            "{goal:?} goal: adaptive mean / reference mean = {ratio}"
        );
    }
}

/// With the same threshold, the image goal (Neyman allocation) stops the
/// noisy pixels earlier than the pixel goal: fewer samples, and the noisy
/// pixels still take more than the quiet ones.
#[test]
fn image_goal_spends_samples_in_proportion_to_the_noise() {
    let scene = adaptive_scene(0.08);
    let accel = build(&scene.scene, AccelKind::KdTree);
    let pixel = render(
        &scene.scene,
        accel.as_ref(),
        &RenderPlan::new(&scene.scene, &scene.settings),
        RenderSetup::default(),
    );
    let mut image_scene = scene.clone();
    image_scene.settings.adaptive_goal = AdaptiveGoal::Image;
    let image = render(
        &image_scene.scene,
        accel.as_ref(),
        &RenderPlan::new(&image_scene.scene, &image_scene.settings),
        RenderSetup::default(),
    );
    let (p, i) = (pixel.accumulation.samples_taken(), image.accumulation.samples_taken());
    assert!(i < p, "image goal took {i} samples, pixel goal {p}");
    let (lo, hi) = image.accumulation.taken_range();
    assert!(
        lo >= 8 && hi > 2 * lo,
        "image goal's sample counts {lo}..{hi}: nothing adapted"
    );
    // Per pixel, never more than the pixel goal (its stops come later or equal).
    let more = (0..image.accumulation.len())
        .filter(|&k| image.accumulation.taken[k] > pixel.accumulation.taken[k])
        .count();
    assert!(
        more < image.accumulation.len() / 20,
        "{more} pixels took more samples with the image goal"
    );
}

/// A Whitted pixel that stops early (here after 4 of 256 planned samples)
/// has its few light samples spread over the area light: its soft shadow
/// is about as accurate as a render planned for 4 samples. (The light's
/// strata used to be taken row by row, so 4 samples of 256 saw one strip
/// of the light and the error was several times larger.)
#[test]
fn early_stopped_whitted_pixels_sample_the_whole_light() {
    let mut scene = load_scene(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/test/shadow.toml")).unwrap();
    scene.settings.width = 48;
    scene.settings.height = 36;
    // One shadow ray per sample either way (the light's strata are the
    // samples), so both renders cast the same number of rays.
    for light in &mut scene.scene.lights {
        if let Light::Area(a) = light {
            a.samples = 1;
        }
    }
    let accel = build(&scene.scene, AccelKind::KdTree);
    let rendered = |spp: u32, limit: Option<u32>, seed: u64| {
        let mut s = scene.clone();
        s.settings.spp = spp;
        s.settings.seed = seed;
        s.settings.sampler = Some(SamplerKind::Sobol);
        let progress = |_, _| {};
        let control = RenderControl {
            sample_limit: limit,
            ..RenderControl::to_completion(&progress)
        };
        let start = Accumulation::new(s.settings.width, s.settings.height);
        render(
            &s.scene,
            accel.as_ref(),
            &RenderPlan::new(&s.scene, &s.settings),
            RenderSetup::default().continuing(start).control(control),
        )
        .film
    };
    let reference = rendered(1024, None, 1);
    let mse = |spp: u32, limit: Option<u32>| -> f64 {
        (0..4)
            .map(|seed| {
                let f = rendered(spp, limit, 10 + seed);
                f.pixels
                    .iter()
                    .zip(&reference.pixels)
                    .map(|(a, b)| ((*a - *b).length_squared()) as f64)
                    .sum::<f64>()
            })
            .sum()
    };
    let planned = mse(4, None);
    let stopped = mse(256, Some(4));
    assert!(
        stopped < 1.5 * planned,
        "4 of 256 samples: squared error {stopped:.4}, a 4-sample render {planned:.4}"
    );
}

#[test]
fn adaptive_renders_are_deterministic_across_threads_and_resume() {
    let scene = adaptive_scene(0.08);
    let accel = build(&scene.scene, AccelKind::KdTree);
    let mut plan = RenderPlan::new(&scene.scene, &scene.settings);
    // A render that checkpoints keeps every buffer (as `caustic render`'s job does).
    plan.aovs = true;
    let pool = |n| rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap();
    let a = pool(1).install(|| render(&scene.scene, accel.as_ref(), &plan, RenderSetup::default()));
    let b = pool(3).install(|| render(&scene.scene, accel.as_ref(), &plan, RenderSetup::default()));
    assert_eq!(a.accumulation, b.accumulation);

    // Stop mid-way (after some tiles of a later pass), save a checkpoint,
    // read it back, continue: the same image, bit for bit.
    let total = a.accumulation.samples_taken();
    for stop_at in [total / 5, total / 2] {
        let cancel = AtomicBool::new(false);
        let progress = |done: u64, _| {
            if done >= stop_at {
                cancel.store(true, Ordering::Relaxed);
            }
        };
        let control = RenderControl {
            cancel: Some(&cancel),
            ..RenderControl::to_completion(&progress)
        };
        let start = Accumulation::new(scene.settings.width, scene.settings.height);
        let part = render(
            &scene.scene,
            accel.as_ref(),
            &plan,
            RenderSetup::default().continuing(start).control(control),
        );
        assert!(!part.complete);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.exr");
        let meta = CheckpointMeta {
            width: scene.settings.width,
            height: scene.settings.height,
            spp: scene.settings.spp,
            seed: scene.settings.seed,
            photons: 0,
            accel: "kdtree".into(),
            fingerprint: "0".repeat(64),
            fingerprint_format: caustic::job::fingerprint::FINGERPRINT_FORMAT,
            output: Default::default(),
            shard: None,
        };
        write_checkpoint(&path, &part.accumulation, &meta).unwrap();
        let resumed = read_checkpoint(&path).unwrap().accumulation;
        let done = pool(2).install(|| {
            render(
                &scene.scene,
                accel.as_ref(),
                &plan,
                RenderSetup::default().continuing(resumed),
            )
        });
        assert_eq!(done.accumulation, a.accumulation, "stopped at {stop_at} of {total}");
    }
}

/// In a uniform environment an albedo-1 object looks like the environment;
/// with adaptive sampling every pixel still does (within its threshold).
#[test]
fn adaptive_white_furnace_renders_the_environment() {
    let mut scene = adaptive_scene(0.02);
    scene.scene.lights = vec![Light::Environment {
        radiance: Vec3A::splat(0.5),
        map: None,
    }];
    for m in &mut scene.scene.materials {
        *m = caustic::scene::Material::diffuse(&m.name, Vec3A::ONE);
    }
    let accel = build(&scene.scene, AccelKind::KdTree);
    let out = render(
        &scene.scene,
        accel.as_ref(),
        &RenderPlan::new(&scene.scene, &scene.settings),
        RenderSetup::default(),
    );
    let mean = out.film.pixels.iter().map(|p| p.x as f64).sum::<f64>() / out.film.pixels.len() as f64;
    assert!((mean - 0.5).abs() < 0.005, "{mean}");
}

/// `--exr` carries each pixel's estimated error and sample count;
/// `--time-limit` ends a render early with the image so far (exit 0).
#[test]
fn cli_writes_error_and_spp_channels_and_honours_the_time_limit() {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("a.exr");
    let o = caustic(&[
        "render",
        "scenes/test/caustic.toml",
        "--integrator",
        "path",
        "--width",
        "24",
        "--height",
        "16",
        "--spp",
        "64",
        "--noise-threshold",
        "0.1",
        "--min-spp",
        "8",
        "--accel",
        "kdtree",
        "--exr",
        exr.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("adaptive sampling:"));
    let image = exr::prelude::read_all_flat_layers_from_file(&exr).unwrap();
    let channels = &image.layer_data[0].channel_data.list;
    let names: Vec<String> = channels.iter().map(|c| c.name.to_string()).collect();
    for want in ["R", "G", "B", "error", "spp"] {
        assert!(names.iter().any(|n| n == want), "{names:?}");
    }
    let spp = channels.iter().find(|c| c.name.to_string() == "spp").unwrap();
    let values: Vec<f32> = spp.sample_data.values_as_f32().collect();
    assert!(values.iter().all(|&v| (8.0..=64.0).contains(&v)), "{values:?}");
    assert!(values.iter().any(|&v| v < 64.0), "no pixel stopped early");

    // A render far too long for its budget stops on time and succeeds.
    let png = dir.path().join("t.png");
    let start = std::time::Instant::now();
    let o = caustic(&[
        "render",
        "scenes/test/caustic.toml",
        "--integrator",
        "path",
        "--width",
        "64",
        "--height",
        "48",
        "--spp",
        "100000",
        "--time-limit",
        "1.5",
        "--accel",
        "kdtree",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("time limit reached"));
    assert!(png.exists());
    // Generous: the budget is not a timing test, only a bound on a hang.
    assert!(start.elapsed().as_secs() < 60);
    let bad = caustic(&["render", "scenes/test/caustic.toml", "--time-limit", "-1"]);
    assert_eq!(bad.status.code(), Some(2));
    let bad = caustic(&["render", "scenes/test/caustic.toml", "--noise-threshold", "2"]);
    assert_eq!(bad.status.code(), Some(2));
}
