//! Taking the figures: the ray sets built once per scene, each accelerator
//! built, its ray sets timed (best of the repeats) and a full render timed.

use super::report::{
    compare, AccelBench, BenchReport, RayBench, RaySetInfo, RenderBench, RenderSettingsInfo, SceneBench,
};
use super::{BenchError, BenchOptions, DEFAULT_BENCH_PHOTONS, MAX_REPEATS};
use crate::accel::{self, Accel, AccelKind, AccelOptions};
use crate::analysis::rays::{self, RaySet};
use crate::integrator::{self, RenderPlan};
use crate::memory;
use crate::scene::{self, LoadedScene, Scene};
use std::path::{Path, PathBuf};

/// Checks the options that do not depend on a scene.
fn check_options(options: &BenchOptions) -> Result<(), BenchError> {
    if options.accels.is_empty() {
        return Err(BenchError::Options("no accelerator to bench".into()));
    }
    if options.rays == 0 {
        return Err(BenchError::Options("--rays must be at least 1".into()));
    }
    if !(1..=MAX_REPEATS).contains(&options.repeats) {
        return Err(BenchError::Options(format!(
            "--repeats {}: must be in 1..={MAX_REPEATS}",
            options.repeats
        )));
    }
    let r = &options.render;
    crate::limits::check_image_limits(r.width, r.height, r.spp)
        .map_err(|e| BenchError::Options(format!("full render: {e}")))?;
    if let Some(n) = r.photons {
        crate::limits::check_photon_count(n).map_err(|e| BenchError::Options(format!("--photons: {e}")))?;
    }
    Ok(())
}

/// Checks before allocating that the ray sets of `scene` fit the memory
/// budget: `rays` camera and incoherent rays, and up to one shadow ray per
/// light per camera ray.
fn check_ray_memory(path: &Path, scene: &Scene, rays: usize) -> Result<(), BenchError> {
    let per_ray = std::mem::size_of::<(crate::math::Ray, f32)>() as u64;
    let sets = 2 + scene.lights.len() as u64;
    let bytes = (rays as u64).saturating_mul(per_ray).saturating_mul(sets);
    let budget = memory::budget().map_err(BenchError::Options)?;
    match budget {
        Some(b) if bytes > b.bytes => Err(BenchError::SceneOptions {
            scene: path.to_path_buf(),
            message: format!(
                "--rays {rays}: the ray sets would need up to {} ({per_ray} bytes per ray, {sets} sets), {b}",
                memory::format_bytes(bytes)
            ),
        }),
        _ => Ok(()),
    }
}

/// `/proc/loadavg`'s three averages.
pub fn load_average() -> Option<[f64; 3]> {
    let text = std::fs::read_to_string("/proc/loadavg").ok()?;
    let mut it = text.split_whitespace().map(|s| s.parse::<f64>().ok());
    Some([it.next()??, it.next()??, it.next()??])
}

/// Benches every scene of `scenes` (loaded from disk) on the current rayon
/// pool. `progress` receives one line per step (loading, building, timing)
/// for the user to follow a long run.
pub fn run(scenes: &[PathBuf], options: &BenchOptions, progress: &dyn Fn(&str)) -> Result<BenchReport, BenchError> {
    check_options(options)?;
    let load_average_start = load_average();
    let mut results = Vec::with_capacity(scenes.len());
    for path in scenes {
        progress(&format!("{}: loading", path.display()));
        let loaded = scene::load_scene_with(path, &options.defines)?;
        results.push(bench_scene(path, &loaded, options, progress)?);
    }
    Ok(BenchReport {
        caustic_version: env!("CARGO_PKG_VERSION").into(),
        threads: rayon::current_num_threads(),
        seed: options.seed,
        rays_per_kind: options.rays,
        repeats: options.repeats,
        load_average_start,
        load_average_end: load_average(),
        scenes: results,
    })
}

/// The baseline of `accels`: Embree when listed, else the first.
fn baseline_index(accels: &[AccelKind]) -> usize {
    accels.iter().position(|&k| k == AccelKind::Embree).unwrap_or(0)
}

/// Benches one loaded scene (`path` names it in the report and in errors).
pub fn bench_scene(
    path: &Path,
    loaded: &LoadedScene,
    options: &BenchOptions,
    progress: &dyn Fn(&str),
) -> Result<SceneBench, BenchError> {
    let scene = &loaded.scene;
    check_options(options)?;
    check_ray_memory(path, scene, options.rays)?;
    let name = path.display().to_string();

    // The render's scene: the file's, at the bench's reduced settings.
    let mut render_settings = loaded.settings.clone();
    {
        let s = &mut render_settings;
        s.width = options.render.width;
        s.height = options.render.height;
        s.spp = options.render.spp;
        s.seed = options.seed;
        s.photons.count = options
            .render
            .photons
            .unwrap_or_else(|| s.photons.count.min(DEFAULT_BENCH_PHOTONS));
    }
    let plan = RenderPlan::new(scene, &render_settings);
    let render_info = RenderSettingsInfo {
        width: plan.width,
        height: plan.height,
        spp: plan.spp,
        photons: render_settings.photons.count,
        photon_pass: matches!(plan.photons, integrator::plan::PhotonPlan::Run { .. }),
    };

    let accel_options = AccelOptions {
        triangle_test: loaded.settings.triangle_test,
        ..options.accel_options.clone()
    };
    // Baseline first: its camera hits seed the shadow rays.
    let mut order: Vec<AccelKind> = Vec::with_capacity(options.accels.len());
    let base = baseline_index(&options.accels);
    order.push(options.accels[base]);
    order.extend(
        options
            .accels
            .iter()
            .enumerate()
            .filter(|&(i, _)| i != base)
            .map(|(_, &k)| k),
    );

    let aspect = options.render.width as f32 / options.render.height as f32;
    let mut sets: Vec<RaySet> = Vec::new();
    let mut accelerators = Vec::with_capacity(order.len());
    for (i, &kind) in order.iter().enumerate() {
        progress(&format!("{name}: building {}", kind.name()));
        let peak_rss_reset = memory::reset_peak_rss();
        let rss_before_build_bytes = memory::current_rss_bytes();
        let accel = accel::build(scene, kind, &accel_options).map_err(|source| BenchError::Accel {
            scene: path.to_path_buf(),
            source,
        })?;
        let peak_rss_build_bytes = memory::peak_rss_bytes();
        let stats = accel.stats();
        if i == 0 {
            progress(&format!(
                "{name}: generating the ray sets ({} camera rays, their hits found with {})",
                options.rays,
                kind.name()
            ));
            sets = rays::standard_ray_sets(scene, accel.as_ref(), options.rays, aspect, options.seed);
        }
        let mut ray_results = Vec::with_capacity(sets.len());
        for set in &sets {
            progress(&format!(
                "{name}: {} {} rays through {}",
                set.rays.len(),
                set.kind,
                kind.name()
            ));
            ray_results.push(time_set(accel.as_ref(), set, options.repeats));
        }
        progress(&format!(
            "{name}: rendering {}×{}, {} spp with {}",
            plan.width,
            plan.height,
            plan.spp,
            kind.name()
        ));
        let render = time_render(scene, accel.as_ref(), &plan);
        accelerators.push(AccelBench {
            name: kind.name().into(),
            build_seconds: stats.build_time.as_secs_f64(),
            memory_bytes: stats.memory_bytes as u64,
            rss_before_build_bytes,
            peak_rss_build_bytes,
            peak_rss_bytes: memory::peak_rss_bytes(),
            peak_rss_reset,
            rays: ray_results,
            render,
        });
        // Freed before the next build, so that its memory figures do not include this one.
        drop(accel);
    }

    let comparisons = accelerators[1..].iter().map(|a| compare(a, &accelerators[0])).collect();
    Ok(SceneBench {
        scene: name,
        objects: scene.objects.len(),
        triangles: scene.meshes.iter().map(|m| m.triangles.len() as u64).sum(),
        instanced_triangles: scene.instanced_triangles(),
        lights: scene.lights.len(),
        baseline: order[0].name().into(),
        ray_sets: sets
            .iter()
            .map(|s| RaySetInfo {
                kind: s.kind,
                query: s.query(),
                rays: s.rays.len(),
            })
            .collect(),
        render_settings: render_info,
        accelerators,
        comparisons,
    })
}

/// Best of `repeats` timed runs of `set`.
fn time_set(accel: &dyn Accel, set: &RaySet, repeats: u32) -> RayBench {
    let runs: Vec<rays::Throughput> = (0..repeats.max(1))
        .map(|_| rays::throughput(accel, &set.rays, set.query()))
        .collect();
    let best = *runs
        .iter()
        .min_by(|a, b| a.seconds.total_cmp(&b.seconds))
        .expect("at least one run");
    RayBench {
        kind: set.kind,
        query: set.query(),
        rays: best.rays,
        hits: best.hits,
        seconds: best.seconds,
        mrays_per_s: (best.rays > 0).then(|| best.mrays_per_s()),
        cpu_seconds: best.cpu_seconds,
        mrays_per_cpu_s: (best.rays > 0).then(|| best.mrays_per_cpu_s()).flatten(),
        runs_seconds: runs.iter().map(|r| r.seconds).collect(),
    }
}

/// One full render of `scene` as `plan` says.
fn time_render(scene: &Scene, accel: &dyn Accel, plan: &RenderPlan) -> RenderBench {
    let out = integrator::render(scene, accel, plan, integrator::RenderSetup::default());
    let s = &out.stats;
    let (photon_seconds, photon_rays) = s.photons.as_ref().map_or((0.0, 0), |p| {
        ((p.trace_time + p.build_time + p.precompute_time).as_secs_f64(), p.rays)
    });
    let seconds = s.wall_time.as_secs_f64();
    let image_rays = s.rays.total();
    RenderBench {
        seconds,
        photon_seconds,
        image_rays,
        photon_rays,
        mrays_per_s: (image_rays + photon_rays) as f64 / seconds.max(1e-9) / 1e6,
        dropped_samples: s.dropped_samples,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::bench::RenderOverrides;
    use crate::math::{Vec3, Vec3A};
    use crate::scene::{Camera, Light, Material, Object, Quad, RenderSettings, Shape, Sphere};

    fn ball_scene() -> LoadedScene {
        let scene = Scene {
            media: Default::default(),
            ambient: Vec3A::ZERO,
            water_medium: None,
            camera: Camera::new(Vec3A::new(0.0, 1.0, 5.0), Vec3A::new(0.0, 0.5, 0.0), Vec3A::Y, 40.0).unwrap(),
            materials: vec![Material::diffuse("white", Vec3A::ONE)],
            lights: vec![Light::Point {
                position: Vec3A::new(0.0, 3.0, 0.0),
                intensity: Vec3A::ONE,
            }],
            meshes: vec![],
            objects: vec![
                Object {
                    name: "floor".into(),
                    shape: Shape::Quad(
                        Quad::new(
                            Vec3A::new(-5.0, 0.0, -5.0),
                            Vec3A::from(Vec3::new(10.0, 0.0, 0.0)),
                            Vec3A::new(0.0, 0.0, 10.0),
                        )
                        .unwrap(),
                    ),
                    material: 0,
                },
                Object {
                    name: "ball".into(),
                    shape: Shape::Sphere(Sphere {
                        center: Vec3A::new(0.0, 1.0, 0.0),
                        radius: 0.5,
                    }),
                    material: 0,
                },
            ],
        };
        LoadedScene {
            scene,
            settings: RenderSettings::default(),
        }
    }

    fn small_options(accels: Vec<AccelKind>) -> BenchOptions {
        BenchOptions {
            accels,
            rays: 3000,
            repeats: 2,
            render: RenderOverrides {
                width: 32,
                height: 18,
                spp: 1,
                photons: Some(0),
            },
            ..BenchOptions::default()
        }
    }

    #[test]
    fn kdtree_against_brute_same_work_and_a_table() {
        let scene = ball_scene();
        // Brute listed first is the baseline (no Embree listed).
        let options = small_options(vec![AccelKind::Brute, AccelKind::KdTree]);
        let s = bench_scene(Path::new("ball.toml"), &scene, &options, &|_| {}).unwrap();
        assert_eq!(s.baseline, "brute");
        assert_eq!(s.accelerators.len(), 2);
        assert_eq!(s.ray_sets.len(), 3);
        assert_eq!(s.ray_sets[0].rays, 3000);
        assert_eq!(s.ray_sets[2].rays, 3000);
        // One shadow ray per camera hit (one light).
        assert_eq!(s.ray_sets[1].rays, s.accelerators[0].rays[0].hits);
        for a in &s.accelerators {
            assert!(a.build_seconds >= 0.0);
            for r in &a.rays {
                assert!(r.hits > 0 && r.hits < r.rays, "{r:?}");
                assert!(r.mrays_per_s.unwrap() > 0.0 && r.mrays_per_s.unwrap().is_finite());
                assert_eq!(r.runs_seconds.len(), 2);
            }
            // One camera ray per pixel, one shadow ray per camera hit, no secondary rays (all diffuse).
            assert!(
                a.render.image_rays > 32 * 18 && a.render.image_rays < 32 * 18 * 2,
                "{:?}",
                a.render
            );
            assert_eq!(a.render.photon_rays, 0);
        }
        let c = &s.comparisons[0];
        assert_eq!((c.accel.as_str(), c.baseline.as_str()), ("kdtree", "brute"));
        assert!(c.rays.iter().all(|k| k.hits_difference == 0), "{c:?}");

        let report = BenchReport {
            caustic_version: "test".into(),
            threads: 1,
            seed: 0,
            rays_per_kind: 3000,
            repeats: 2,
            load_average_start: None,
            load_average_end: Some([0.5, 1.0, 1.5]),
            scenes: vec![s],
        };
        let table = report.to_string();
        assert!(table.contains("kdtree/brute"), "{table}");
        assert!(table.contains("(=)"), "{table}");
        let json: serde_json::Value = serde_json::from_str(&report.to_json()).unwrap();
        assert_eq!(json["scenes"][0]["accelerators"][1]["name"], "kdtree");
        assert_eq!(json["scenes"][0]["ray_sets"][1]["query"], "occluded");
        assert_eq!(json["load_average_end"][2], 1.5);
    }

    #[test]
    fn embree_is_the_baseline_when_listed() {
        assert_eq!(baseline_index(&[AccelKind::KdTree, AccelKind::Embree]), 1);
        assert_eq!(baseline_index(&[AccelKind::KdTree, AccelKind::Brute]), 0);
    }

    #[test]
    fn bad_options_are_errors() {
        let scene = ball_scene();
        let mut o = small_options(vec![AccelKind::KdTree]);
        o.rays = 0;
        let e = bench_scene(Path::new("x.toml"), &scene, &o, &|_| {}).unwrap_err();
        assert!(e.to_string().contains("--rays"), "{e}");
        let mut o = small_options(vec![]);
        o.rays = 10;
        assert!(bench_scene(Path::new("x.toml"), &scene, &o, &|_| {}).is_err());
        let mut o = small_options(vec![AccelKind::KdTree]);
        o.render.width = 0;
        assert!(bench_scene(Path::new("x.toml"), &scene, &o, &|_| {})
            .unwrap_err()
            .to_string()
            .contains("full render"));
        let mut o = small_options(vec![AccelKind::KdTree]);
        o.rays = usize::MAX / 64;
        let e = bench_scene(Path::new("x.toml"), &scene, &o, &|_| {}).unwrap_err();
        assert!(e.to_string().contains("would need"), "{e}");
        assert!(e.is_bad_input());
    }
}
