//! Interrupt and resume through the library API: a render stopped at any
//! point (cancel flag mid-pass, sample limit, periodic checkpoint snapshot,
//! checkpoint file round trip) and continued ends bit-identical to an
//! uninterrupted render with the same seed.

mod common;

use caustic::accel::{Accel, AccelKind};
use caustic::film::{read_checkpoint, write_checkpoint, Accumulation, CheckpointMeta};
use caustic::integrator::photon::{PhotonMap, SiteCache};
use caustic::integrator::render::PixelStrata;
use caustic::integrator::{
    render, CheckpointHook, Integrator, RayCounts, RenderControl, RenderOutput, RenderPlan, RenderSetup, SampleContext,
    Whitted,
};
use caustic::math::rng::mix64;
use caustic::math::sampling::{grid_for, permute, stratified};
use caustic::math::{Rng, Sampler, Vec3, Vec3A};
use caustic::scene::load_scene;
use caustic::scene::LoadedScene;
use common::scenes::build;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use std::time::Duration;

/// The glass-sphere caustic scene, small: photon pass, dielectric Fresnel
/// branches and spread area-light strata all take part.
fn caustic_scene(spp: u32) -> LoadedScene {
    let mut scene = load_scene(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/test/caustic.toml")).unwrap();
    let s = &mut scene.settings;
    s.width = 40;
    s.height = 30;
    s.spp = spp;
    s.seed = 11;
    s.photons.count = 20_000;
    scene
}

fn continue_from(scene: &LoadedScene, accel: &dyn Accel, plan: &RenderPlan, start: Accumulation) -> RenderOutput {
    render(&scene.scene, accel, plan, RenderSetup::default().continuing(start))
}

#[test]
fn cancelled_mid_pass_then_resumed_equals_uninterrupted() {
    let scene = caustic_scene(11);
    let accel = build(&scene.scene, AccelKind::KdTree);
    let plan = RenderPlan::new(&scene.scene, &scene.settings);
    assert!(plan.spread(), "the test should cover spread sampling");
    let reference = render(&scene.scene, accel.as_ref(), &plan, RenderSetup::default());
    assert!(reference.complete);
    assert!(reference.stats.photons.is_some(), "the photon pass should run");

    // Stop at several points, most of them in the middle of a pass (the
    // progress callback runs after each tile): pixels then hold different
    // sample counts, and the resume must continue each from its own. Passes
    // go to 4, 8 and 11 spp; every stop point is reached by the end of the
    // second pass at the latest, so the third never runs.
    let total = 40 * 30 * 11;
    for stop_at in [1, total / 7, total / 3, total * 2 / 3] {
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
        let taken = first.accumulation.samples_taken();
        assert!(
            taken >= stop_at && taken < total,
            "{taken} samples for a stop at {stop_at}"
        );
        assert_eq!(first.stats.samples, taken);
        assert_ne!(first.film, reference.film);

        let resumed = continue_from(&scene, accel.as_ref(), &plan, first.accumulation);
        assert!(resumed.complete);
        assert_eq!(
            resumed.stats.samples,
            total - taken,
            "only the missing samples are taken"
        );
        assert!(
            resumed.film == reference.film,
            "stop at {stop_at}: the resumed film differs"
        );
        assert_eq!(resumed.accumulation, reference.accumulation);
    }
}

#[test]
fn sample_limit_gives_a_full_frame_and_resumes_through_a_checkpoint_file() {
    let scene = caustic_scene(6);
    let accel = build(&scene.scene, AccelKind::KdTree);
    let mut plan = RenderPlan::new(&scene.scene, &scene.settings);
    // A render that checkpoints keeps every buffer (as `caustic render`'s job does).
    (plan.aovs, plan.noise) = (true, true);
    let reference = render(&scene.scene, accel.as_ref(), &plan, RenderSetup::default());

    // A limit off the pass boundaries (passes go to 4, 6): the resume
    // then groups the samples into other passes than the reference did.
    let control = RenderControl {
        sample_limit: Some(3),
        ..RenderControl::to_completion(&|_, _| {})
    };
    let preview = render(
        &scene.scene,
        accel.as_ref(),
        &plan,
        RenderSetup::default().control(control),
    );
    // The partial image covers the whole frame at 3 spp: no black tiles.
    assert_eq!(preview.accumulation.taken_range(), (3, 3));
    assert!(!preview.complete);

    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("preview.ckpt.exr");
    let meta = CheckpointMeta {
        width: 40,
        height: 30,
        spp: 6,
        seed: 11,
        photons: 20_000,
        accel: "kdtree".into(),
        fingerprint: caustic::job::fingerprint(&scene.scene, &scene.settings, AccelKind::KdTree, ""),
        fingerprint_format: caustic::job::fingerprint::FINGERPRINT_FORMAT,
        output: Default::default(),
        shard: None,
    };
    write_checkpoint(&path, &preview.accumulation, &meta).unwrap();
    let back = read_checkpoint(&path).unwrap();
    assert_eq!(back.meta, meta);
    assert_eq!(back.accumulation, preview.accumulation);

    let resumed = continue_from(&scene, accel.as_ref(), &plan, back.accumulation);
    assert!(resumed.film == reference.film);

    // A complete accumulation resumes to itself without new samples.
    let again = continue_from(&scene, accel.as_ref(), &plan, resumed.accumulation.clone());
    assert_eq!(again.stats.samples, 0);
    assert!(again.film == reference.film);
}

#[test]
fn every_periodic_snapshot_resumes_to_the_same_image() {
    let scene = caustic_scene(9);
    let accel = build(&scene.scene, AccelKind::KdTree);
    let plan = RenderPlan::new(&scene.scene, &scene.settings);
    let snapshots = Mutex::new(Vec::new());
    let save = |acc: &Accumulation| snapshots.lock().unwrap().push(acc.clone());
    let progress = |_: u64, _: u64| {};
    let control = RenderControl {
        checkpoint: Some(CheckpointHook {
            every: Duration::ZERO,
            save: &save,
        }),
        ..RenderControl::to_completion(&progress)
    };
    // Two threads: snapshots are taken while the other worker renders.
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    let full = pool.install(|| {
        render(
            &scene.scene,
            accel.as_ref(),
            &plan,
            RenderSetup::default().control(control),
        )
    });
    let reference = render(&scene.scene, accel.as_ref(), &plan, RenderSetup::default());
    assert!(full.film == reference.film, "checkpointing must not change the image");

    let snapshots = snapshots.into_inner().unwrap();
    // 2 tiles × passes to 4, 8, 9 spp: up to 6 snapshots (a worker skips
    // saving while the other one saves).
    assert!(
        !snapshots.is_empty() && snapshots.len() <= 6,
        "{} snapshots",
        snapshots.len()
    );
    let mut previous = 0;
    for (i, snap) in snapshots.iter().enumerate() {
        let taken = snap.samples_taken();
        assert!(taken >= previous, "snapshots only grow");
        previous = taken;
        let resumed = continue_from(&scene, accel.as_ref(), &plan, snap.clone());
        assert!(resumed.film == reference.film, "snapshot {i} ({taken} samples)");
    }
}

#[test]
fn a_render_cancelled_before_it_starts_takes_no_sample() {
    let scene = caustic_scene(4);
    let accel = build(&scene.scene, AccelKind::KdTree);
    let plan = RenderPlan::new(&scene.scene, &scene.settings);
    let cancel = AtomicBool::new(true);
    let control = RenderControl {
        cancel: Some(&cancel),
        ..RenderControl::to_completion(&|_, _| {})
    };
    let out = render(
        &scene.scene,
        accel.as_ref(),
        &plan,
        RenderSetup::default().control(control),
    );
    assert_eq!(out.accumulation.samples_taken(), 0);
    assert!(out.stats.photons.is_none(), "the photon pass is skipped too");
    assert!(!out.complete);
}

/// The film as the single-loop renderer computed it before passes existed:
/// each pixel sums its samples 0..spp in one go, then divides by the kept
/// count. The pass loop must give exactly these values.
fn single_loop_film(scene: &LoadedScene, accel: &dyn Accel, plan: &RenderPlan, map: Option<&PhotonMap>) -> Vec<Vec3> {
    let mut integrator = Whitted::new(&scene.scene, accel, plan);
    if let Some(map) = map {
        integrator = integrator.with_photons(map);
    }
    let spp = plan.spp;
    let (gx, gy) = grid_for(spp);
    let mut counts = RayCounts::default();
    let mut pixels = Vec::new();
    for y in 0..plan.height {
        for x in 0..plan.width {
            let pixel = y as u64 * plan.width as u64 + x as u64;
            let strata = PixelStrata::new(plan, plan.seed, pixel);
            let (mut sum, mut kept) = (Vec3A::ZERO, 0u32);
            for k in 0..spp {
                let mut rng = Sampler::independent(Rng::for_pixel(plan.seed, pixel, k as u64));
                let pixel_seed = mix64(plan.seed ^ mix64(pixel)) as u32;
                let sub = stratified(permute(k, spp, pixel_seed), gx, gy, rng.vec2());
                let ray = scene
                    .scene
                    .camera
                    .ray(x as f32 + sub.x, y as f32 + sub.y, plan.width, plan.height);
                let mut ctx = SampleContext {
                    rng: &mut rng,
                    slot: strata.slot(k),
                    light_seed: strata.light_seed(),
                    fresnel_stratum: strata.fresnel_stratum(k),
                    counts: &mut counts,
                    sites: &mut SiteCache::default(),
                };
                let l = integrator.radiance(&ray, None, &mut ctx);
                if l.is_finite() {
                    sum += l;
                    kept += 1;
                }
            }
            pixels.push(Vec3::from(if kept > 0 { sum / kept as f32 } else { Vec3A::ZERO }));
        }
    }
    pixels
}

#[test]
fn passes_give_the_single_loop_image_bit_for_bit() {
    let scene = caustic_scene(13);
    let accel = build(&scene.scene, AccelKind::KdTree);
    let plan = RenderPlan::new(&scene.scene, &scene.settings);
    let out = render(&scene.scene, accel.as_ref(), &plan, RenderSetup::default());
    let expected = single_loop_film(&scene, accel.as_ref(), &plan, out.photon_map.as_deref());
    assert!(out.film.pixels == expected, "the pass loop changed the image");
}

/// Rewrites a checkpoint as the previous format wrote it: no albedo and
/// normal channels, `caustic.format` = `caustic-checkpoint-3`.
fn downgrade_to_format_3(path: &Path) {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .unwrap();
    let layer = image.layer_data;
    let channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = layer
        .channel_data
        .list
        .into_iter()
        .filter(|c| !c.name.to_string().starts_with("albedo.") && !c.name.to_string().starts_with("normal."))
        .collect();
    assert_eq!(channels.len(), 13, "the format-4 file had 6 AOV channels among 19");
    let mut attributes = layer.attributes;
    attributes.other.insert(
        Text::from("caustic.format"),
        AttributeValue::Text(Text::from(caustic::film::checkpoint::CHECKPOINT_FORMAT_3)),
    );
    let layer = Layer::new(
        layer.size,
        attributes,
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(channels),
    );
    Image::from_layer(layer).write().to_file(path).unwrap();
}

/// A checkpoint of the format before the auxiliary images (no albedo and
/// normal sums) resumes with them traced again for its samples: the image,
/// its albedo and normal sums and the EXR equal an uninterrupted render's.
#[test]
fn a_format_3_checkpoint_resumes_with_its_auxiliary_images_traced_again() {
    use caustic::job::{JobHooks, RenderJob, RenderRequest};
    let dir = tempfile::tempdir().unwrap();
    let request = |exr: &str| {
        let mut r = RenderRequest::new(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/test/caustic.toml"));
        r.overrides.width = Some(40);
        r.overrides.height = Some(30);
        r.overrides.spp = Some(6);
        r.overrides.seed = Some(11);
        r.overrides.photons = Some(20_000);
        r.accel = Some(AccelKind::KdTree);
        r.exr = Some(dir.path().join(exr));
        r
    };
    let run = |r: &RenderRequest, hooks: &JobHooks| RenderJob::prepare(r).unwrap().run(hooks).unwrap();
    let reference = run(&request("reference.exr"), &JobHooks::silent());
    assert!(reference.output.complete);

    // Stopped mid-render: the checkpoint holds a part of the samples.
    let checkpoint = dir.path().join("ck.exr");
    let mut first = request("first.exr");
    first.checkpoint = Some(checkpoint.clone());
    let cancel = AtomicBool::new(false);
    let progress = |done: u64, _total: u64| {
        if done >= 40 * 30 * 2 {
            cancel.store(true, Ordering::Relaxed);
        }
    };
    let hooks = JobHooks {
        cancel: Some(&cancel),
        progress: &progress,
        ..JobHooks::silent()
    };
    let stopped = run(&first, &hooks);
    assert!(!stopped.output.complete);
    let held = read_checkpoint(&checkpoint).unwrap();
    assert!(held.has_aovs && held.accumulation.albedo.iter().any(|a| *a != Vec3::ZERO));

    downgrade_to_format_3(&checkpoint);
    let old = read_checkpoint(&checkpoint).unwrap();
    assert!(!old.has_aovs);
    assert!(old.accumulation.albedo.iter().all(|a| *a == Vec3::ZERO));
    assert_eq!(old.accumulation.sum, held.accumulation.sum);

    let mut resume = request("resumed.exr");
    resume.resume = Some(checkpoint.clone());
    let resumed = run(&resume, &JobHooks::silent());
    assert!(resumed.output.complete);
    assert!(resumed.output.film == reference.output.film);
    // Without the retrace, the albedo sums would miss the first samples'.
    assert_eq!(resumed.output.accumulation, reference.output.accumulation);
    assert_eq!(
        std::fs::read(dir.path().join("resumed.exr")).unwrap(),
        std::fs::read(dir.path().join("reference.exr")).unwrap()
    );
}
