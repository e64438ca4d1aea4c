//! Progressive photon mapping (Knaus & Zwicker 2011) end to end: the
//! caustic converges to a high-photon, small-radius reference as samples
//! grow and beats one fixed map of the same total photons; the images are
//! the same for any thread count, across an interruption and a resume
//! (adaptive sampling included), and across tiles and samples shards; bad
//! settings and photon files are refused with exit code 2.

mod common;

use caustic::accel::AccelKind;
use caustic::film::shard::samples_merge_bound;
use caustic::film::{Accumulation, ShardId, ShardMode, ShardSet};
use caustic::integrator::plan::{PhotonPlan, ProgressivePlan};
use caustic::integrator::{render, PhotonInput, RenderControl, RenderPlan, RenderSetup};
use caustic::job::{self, merge_partials, JobHooks, MergeRequest, RenderJob, RenderRequest};
use caustic::math::Vec3A;
use caustic::scene::LoadedScene;
use caustic::scene::{
    load_scene, AreaLight, Camera, Dielectric, GatherMode, Light, Material, Object, Quad, RenderSettings,
    SampleSharing, Scene, Shape, Sphere,
};
use common::cli::caustic;
use common::metrics::{mean_of, rmse};
use common::scenes::build;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

const SCENE: &str = "scenes/test/caustic.toml";

fn scene_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(SCENE)
}

/// A glass sphere over a floor under a small area light (its caustic
/// lands beside the sphere's foot), seen from above.
fn glass_scene(spp: u32, count: u64, seed: u64) -> LoadedScene {
    let glass = Material {
        dielectric: Some(Dielectric::smooth(1.5, Vec3A::ONE)),
        ..Material::diffuse("glass", Vec3A::ZERO)
    };
    let mut settings = RenderSettings {
        width: 40,
        height: 30,
        spp,
        seed,
        // Both Fresnel branches at every dielectric: the camera paths then
        // draw nothing but their sub-pixel positions, so the caustic seen
        // through and in the sphere is compared without their noise.
        sharing: SampleSharing::Split,
        ..Default::default()
    };
    settings.photons.count = count;
    settings.photons.k = 32;
    settings.photons.max_radius = Some(0.04);
    settings.photons.gather = GatherMode::Direct;
    let floor = Object {
        name: "floor".into(),
        shape: Shape::Quad(
            Quad::new([-4.0, 0.0, 4.0].into(), [8.0, 0.0, 0.0].into(), [0.0, 0.0, -8.0].into()).unwrap(),
        ),
        material: 0,
    };
    let scene = Scene {
        media: Default::default(),
        ambient: Vec3A::ZERO,
        water_medium: None,
        camera: Camera::new(Vec3A::new(-0.2, 3.0, 2.0), Vec3A::new(-0.5, 0.0, 0.0), Vec3A::Y, 40.0).unwrap(),
        materials: vec![Material::diffuse("floor", Vec3A::splat(0.8)), glass],
        lights: vec![Light::Area(
            AreaLight::new(
                Vec3A::new(1.2, 3.0, 0.0),
                Vec3A::new(0.2, 0.0, 0.0),
                Vec3A::new(0.0, 0.0, 0.2),
                Vec3A::splat(300.0),
                4,
            )
            .unwrap(),
        )],
        meshes: vec![],
        objects: vec![
            floor,
            Object {
                name: "glass".into(),
                shape: Shape::Sphere(Sphere {
                    center: Vec3A::new(0.0, 0.7, 0.0),
                    radius: 0.6,
                }),
                material: 1,
            },
        ],
    };
    LoadedScene { scene, settings }
}

/// The caustic part of a render: the image minus the same render without
/// photons (the photon gather draws no random numbers, so every other
/// term is the same sample for sample), per channel.
fn caustic_only(scene: &LoadedScene) -> Vec<f64> {
    let accel = build(&scene.scene, AccelKind::KdTree);
    let plan = RenderPlan::new(&scene.scene, &scene.settings);
    assert!(plan.runs_photons());
    let with = render(&scene.scene, accel.as_ref(), &plan, RenderSetup::default()).film;
    let mut dark = plan.clone();
    dark.photons = PhotonPlan::CountZero;
    let without = render(
        &scene.scene,
        accel.as_ref(),
        &dark,
        RenderSetup::default().photons(PhotonInput::Map(None)),
    )
    .film;
    with.pixels
        .iter()
        .zip(&without.pixels)
        .flat_map(|(a, b)| (*a - *b).to_array())
        .map(f64::from)
        .collect()
}

fn progressive(mut scene: LoadedScene) -> LoadedScene {
    scene.settings.photons.progressive = true;
    scene
}

/// One map gathered within a fixed radius: every photon within
/// `max_radius` (k as large as allowed), the radius progressive photon
/// mapping starts from.
fn fixed_radius(mut scene: LoadedScene) -> LoadedScene {
    scene.settings.photons.k = caustic::scene::load::MAX_PHOTON_GATHER;
    scene
}

/// Photons per sample index in the comparisons: a fixed map of
/// `spp · PER_PASS` photons against progressive maps of `PER_PASS` each.
const PER_PASS: u64 = 4_000;

#[test]
fn progressive_caustic_converges_and_beats_a_fixed_map_of_equal_photons() {
    // Reference: 3M photons, a 0.02 radius (k = 128 nearest within it),
    // the same seed and spp as the 64 spp renders below (the same sub-pixel
    // positions).
    let mut reference_scene = glass_scene(64, 3_000_000, 5);
    reference_scene.settings.photons.k = 128;
    reference_scene.settings.photons.max_radius = Some(0.02);
    let reference = caustic_only(&reference_scene);
    let energy = (reference.iter().map(|x| x * x).sum::<f64>() / reference.len() as f64).sqrt();
    println!(
        "reference caustic: rms {energy:.4}, largest {:.3}",
        reference.iter().fold(0.0f64, |m, &x| m.max(x))
    );
    assert!(energy > 0.01, "the reference shows a caustic (rms {energy})");

    let mut errors = Vec::new();
    for spp in [4u32, 16, 64] {
        let count = spp as u64 * PER_PASS;
        let ppm = rmse(&caustic_only(&progressive(glass_scene(spp, count, 5))), &reference);
        let fixed = rmse(&caustic_only(&fixed_radius(glass_scene(spp, count, 5))), &reference);
        println!("{spp} spp, {count} photons: progressive rmse {ppm:.4}, fixed radius {fixed:.4}");
        errors.push((ppm, fixed));
    }
    // Progressive: the error falls as the samples (and maps) grow.
    assert!(errors[0].0 > errors[1].0 && errors[1].0 > errors[2].0, "{errors:?}");
    assert!(errors[2].0 < 0.6 * errors[0].0, "{errors:?}");
    // From 16 spp on it is below the fixed radius's with the same photons
    // in one map (measured: 0.0081 against 0.0102 at 16 spp, 0.0043 against
    // 0.0082 at 64).
    assert!(errors[1].0 < errors[1].1 && errors[2].0 < errors[2].1, "{errors:?}");
    assert!(errors[2].0 < 0.75 * errors[2].1, "{errors:?}");

    // Bias at 64 spp: the mean of independent renders (seeds) keeps only
    // the bias (and a variance divided by their number).
    let seeds = 6u64;
    let spp = 64;
    let count = spp as u64 * PER_PASS;
    let ppm: Vec<Vec<f64>> = (0..seeds)
        .map(|s| caustic_only(&progressive(glass_scene(spp, count, 100 + s))))
        .collect();
    let fixed: Vec<Vec<f64>> = (0..seeds)
        .map(|s| caustic_only(&fixed_radius(glass_scene(spp, count, 100 + s))))
        .collect();
    let (ppm_bias, fixed_bias) = (rmse(&mean_of(&ppm), &reference), rmse(&mean_of(&fixed), &reference));
    println!("64 spp, mean of {seeds} seeds: progressive {ppm_bias:.4}, fixed radius {fixed_bias:.4}");
    assert!(
        ppm_bias < fixed_bias,
        "bias: progressive {ppm_bias}, fixed {fixed_bias}"
    );
}

/// The caustic test scene, small, progressive.
fn caustic_scene(spp: u32) -> LoadedScene {
    let mut scene = load_scene(&scene_path()).unwrap();
    let s = &mut scene.settings;
    s.width = 40;
    s.height = 30;
    s.spp = spp;
    s.seed = 11;
    s.photons.count = 20_000;
    s.photons.progressive = true;
    scene
}

#[test]
fn plan_shares_the_photons_and_says_what_it_skips() {
    let scene = caustic_scene(11);
    let plan = RenderPlan::new(&scene.scene, &scene.settings);
    let PhotonPlan::Run {
        progressive, gather, ..
    } = plan.photons
    else {
        panic!("{plan}")
    };
    assert_eq!(
        progressive,
        Some(ProgressivePlan {
            alpha: 2.0 / 3.0,
            photons_per_pass: 20_000 / 11
        })
    );
    // The scene's precomputed gather does not apply to progressive maps.
    assert_eq!(scene.settings.photons.gather, GatherMode::Precomputed);
    assert_eq!(gather, GatherMode::Direct);
    let text = plan.to_string();
    assert!(
        text.contains("photon pass: ran, progressive, 1818 photons per pass (one map per sample index, 11 passes), r₁ = 0.1500, α = 0.6666667"),
        "{text}"
    );
    assert!(text.contains("precomputed irradiance skipped"), "{text}");
    // Rendering traces one map per sample index and counts them all.
    let accel = build(&scene.scene, AccelKind::KdTree);
    let out = render(&scene.scene, accel.as_ref(), &plan, RenderSetup::default());
    let stats = out.stats.photons.as_ref().unwrap();
    assert_eq!((stats.maps, stats.emitted), (11, 11 * 1818));
    assert!(
        stats.to_string().starts_with("photon passes (progressive): 11 maps"),
        "{stats}"
    );
    assert!(out.photon_map.is_some(), "the last map is kept for the debug overlay");
}

#[test]
fn same_image_on_one_and_three_threads() {
    let scene = caustic_scene(6);
    let accel = build(&scene.scene, AccelKind::KdTree);
    let plan = RenderPlan::new(&scene.scene, &scene.settings);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| render(&scene.scene, accel.as_ref(), &plan, RenderSetup::default()))
    };
    let (one, three) = (run(1), run(3));
    assert!(one.film == three.film);
    assert_eq!(one.accumulation, three.accumulation);
    // And not the non-progressive image.
    let mut fixed = scene.clone();
    fixed.settings.photons.progressive = false;
    let other = render(
        &fixed.scene,
        accel.as_ref(),
        &RenderPlan::new(&fixed.scene, &fixed.settings),
        RenderSetup::default(),
    );
    assert!(other.film != one.film);
}

/// Stops a render after `stop_at` samples (mid-pass: the progress callback
/// runs after each tile), then resumes it.
fn interrupt_and_resume(scene: &LoadedScene, stop_at: u64) -> (Accumulation, Accumulation) {
    let accel = build(&scene.scene, AccelKind::KdTree);
    let plan = RenderPlan::new(&scene.scene, &scene.settings);
    let cancel = AtomicBool::new(false);
    let progress = |done: u64, _total: u64| {
        if done >= stop_at {
            cancel.store(true, Ordering::Relaxed);
        }
    };
    let control = RenderControl {
        cancel: Some(&cancel),
        ..RenderControl::to_completion(&progress)
    };
    let first = render(
        &scene.scene,
        accel.as_ref(),
        &plan,
        RenderSetup::default().control(control),
    );
    assert!(!first.complete, "stopped at {stop_at}");
    let partial = first.accumulation.clone();
    let resumed = render(
        &scene.scene,
        accel.as_ref(),
        &plan,
        RenderSetup::default().continuing(first.accumulation),
    );
    assert!(resumed.complete);
    (partial, resumed.accumulation)
}

#[test]
fn interrupted_and_resumed_is_bit_identical() {
    let scene = caustic_scene(11);
    let accel = build(&scene.scene, AccelKind::KdTree);
    let plan = RenderPlan::new(&scene.scene, &scene.settings);
    let reference = render(&scene.scene, accel.as_ref(), &plan, RenderSetup::default()).accumulation;
    let total = 40 * 30 * 11;
    for stop_at in [1, total / 7, total / 3, total * 2 / 3] {
        let (partial, resumed) = interrupt_and_resume(&scene, stop_at);
        let (lo, hi) = partial.taken_range();
        println!("stop at {stop_at}: pixels at {lo}..={hi} samples");
        assert!(resumed == reference, "stop at {stop_at}: the resumed render differs");
    }
    // Stopped between two sample indices of a pass (pixels at s and s + 1,
    // s not a pass boundary), resumed with adaptive sampling deciding
    // between passes: still the uninterrupted image.
    let mut adaptive = caustic_scene(24);
    adaptive.settings.noise_threshold = Some(0.05);
    adaptive.settings.min_spp = 8;
    let accel = build(&adaptive.scene, AccelKind::KdTree);
    let plan = RenderPlan::new(&adaptive.scene, &adaptive.settings);
    let reference = render(&adaptive.scene, accel.as_ref(), &plan, RenderSetup::default()).accumulation;
    assert!(reference.converged.iter().any(|&c| c), "some pixels stop early");
    assert!(reference.taken.contains(&24), "some pixels sample on");
    let stop_at = 40 * 30 * 5 + 100;
    let (partial, resumed) = interrupt_and_resume(&adaptive, stop_at);
    assert_eq!(partial.taken_range(), (5, 6), "stopped inside the second pass");
    assert!(resumed == reference, "adaptive: the resumed render differs");
}

fn request(spp: u32) -> RenderRequest {
    let mut r = RenderRequest::new(scene_path());
    r.overrides.width = Some(48);
    r.overrides.height = Some(40);
    r.overrides.spp = Some(spp);
    r.overrides.seed = Some(21);
    r.overrides.photons = Some(12_000);
    r.overrides.progressive_photons = Some(true);
    r.accel = Some(AccelKind::KdTree);
    r
}

fn run(request: &RenderRequest, threads: usize) -> job::JobReport {
    let job = RenderJob::prepare(request).unwrap();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| job.run(&JobHooks::silent())).unwrap()
}

fn shards(base: &RenderRequest, count: u32, mode: ShardMode, dir: &Path) -> Accumulation {
    let parts: Vec<PathBuf> = (0..count)
        .map(|i| {
            let mut r = base.clone();
            let path = dir.join(format!("{mode:?}-{count}-{i}.exr"));
            r.shard = Some(ShardSet::single(ShardId::new(i, count).unwrap(), mode));
            r.checkpoint = Some(path.clone());
            assert!(run(&r, 1 + i as usize % 2).complete());
            path
        })
        .collect();
    merge_partials(&MergeRequest {
        partials: parts,
        png: Some(dir.join("merged.png")),
        exr: None,
        partial: None,
        denoise: false,
        ..Default::default()
    })
    .unwrap()
    .accumulation
}

#[test]
fn shards_merge_to_the_single_render() {
    let dir = tempfile::tempdir().unwrap();
    let base = request(8);
    let mut single = base.clone();
    single.exr = Some(dir.path().join("single.exr"));
    let reference = run(&single, 2).output.accumulation;
    // Tiles shards re-trace the same maps: bit-identical.
    for count in [2u32, 3] {
        let merged = shards(&base, count, ShardMode::Tiles, dir.path());
        assert!(merged == reference, "{count} tiles shards");
    }
    // Samples shards trace the maps of their own sample range: the same
    // samples, added in another order.
    let bound = samples_merge_bound(8);
    let merged = shards(&base, 4, ShardMode::Samples, dir.path());
    assert_eq!(merged.taken, reference.taken);
    let worst = merged
        .sum
        .iter()
        .zip(&reference.sum)
        .flat_map(|(a, b)| (*a - *b).abs().to_array().into_iter().zip(b.abs().to_array()))
        .map(|(d, r)| if r > 0.0 { d / r } else { d })
        .fold(0.0f32, f32::max);
    assert!((worst as f64) <= bound, "samples shards: {worst} > {bound}");
    // One sample per shard: each shard traces one map, the merge adds in order.
    let merged = shards(&base, 8, ShardMode::Samples, dir.path());
    assert!(merged == reference, "one sample per shard");
}

#[test]
fn bad_settings_and_photon_files_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(scene_path()).unwrap();
    // `[photons]` is on line 17 of the scene, its `cone_k` on line 21.
    assert_eq!(text.lines().nth(16), Some("[photons]"));
    for (alpha, col) in [("1.0", 9), ("0", 9), ("-0.5", 9), ("nan", 9)] {
        let bad = text.replace("cone_k = 1.1", &format!("cone_k = 1.1\nalpha = {alpha}"));
        let path = dir.path().join("bad.toml");
        std::fs::write(&path, bad).unwrap();
        let out = caustic(&["render", path.to_str().unwrap(), "--quiet", "-o", "/dev/null"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "alpha = {alpha}: {err}");
        assert!(err.contains(&format!("bad.toml:22:{col}")), "alpha = {alpha}: {err}");
        assert!(err.contains("alpha"), "{err}");
    }
    let good = text.replace("cone_k = 1.1", "cone_k = 1.1\nprogressive = true\nalpha = 0.5");
    let path = dir.path().join("good.toml");
    std::fs::write(&path, good).unwrap();
    let scene = load_scene(&path).unwrap();
    assert!(scene.settings.photons.progressive);
    assert_eq!(scene.settings.photons.alpha, 0.5);

    let scene = SCENE;
    let png = dir.path().join("x.png");
    let png = png.to_str().unwrap();
    for alpha in ["1", "0", "1.5", "NaN"] {
        let out = caustic(&[
            "render",
            scene,
            "--progressive-photons",
            "--ppm-alpha",
            alpha,
            "-o",
            png,
            "--quiet",
        ]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "--ppm-alpha {alpha}: {err}");
        assert!(err.contains("--ppm-alpha"), "{err}");
    }
    // A photon file cannot feed progressive maps.
    let photons = dir.path().join("p.photons");
    let out = caustic(&[
        "photons",
        scene,
        "-o",
        photons.to_str().unwrap(),
        "--photons",
        "1000",
        "--accel",
        "kdtree",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let out = caustic(&[
        "render",
        scene,
        "--progressive-photons",
        "--photon-map",
        photons.to_str().unwrap(),
        "--photons",
        "1000",
        "--accel",
        "kdtree",
        "-o",
        png,
        "--quiet",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("progressive photon mapping"), "{err}");
    let out = caustic(&["photons", path.to_str().unwrap(), "-o", photons.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    // The plan printout says what runs.
    let out = caustic(&[
        "render",
        scene,
        "--progressive-photons",
        "--width",
        "32",
        "--height",
        "24",
        "--spp",
        "4",
        "--photons",
        "4000",
        "--accel",
        "kdtree",
        "-o",
        png,
    ]);
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "{text}");
    assert!(
        text.contains("photon pass: ran, progressive, 1000 photons per pass"),
        "{text}"
    );
    assert!(text.contains("photon passes (progressive): 4 maps"), "{text}");
}

#[test]
fn a_checkpoint_of_another_photon_mode_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let ckpt = dir.path().join("c.exr");
    let mut fixed = request(4);
    fixed.overrides.progressive_photons = Some(false);
    fixed.checkpoint = Some(ckpt.clone());
    assert!(run(&fixed, 2).complete());
    let mut resume = request(4);
    resume.resume = Some(ckpt.clone());
    let err = RenderJob::prepare(&resume).err().expect("refused");
    assert!(err.is_bad_input());
    assert!(err.to_string().contains("different render"), "{err}");
    // Another α is another render too.
    let mut ppm = request(4);
    ppm.checkpoint = Some(ckpt.clone());
    assert!(run(&ppm, 2).complete());
    let mut other = request(4);
    other.overrides.ppm_alpha = Some(0.5);
    other.resume = Some(ckpt.clone());
    assert!(RenderJob::prepare(&other).is_err());
    let mut same = request(4);
    same.resume = Some(ckpt);
    assert!(RenderJob::prepare(&same).is_ok());
}
