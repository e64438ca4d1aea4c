//! Mrays/s of the KD-tree against Embree on the Stanford dragon scene for
//! camera, shadow and incoherent rays, plus the KD-tree build time. Long and
//! needs the dragon asset: run in release with
//! `CAUSTIC_ASSETS=/path/to/assets cargo test --release --test kdtree_throughput -- --ignored --nocapture`
//! (`KDTREE_BENCH_SIZE=WxH` changes the 640×360 image the rays come from).

use caustic::accel::kdtree::build::SahParams;
use caustic::accel::kdtree::KdTreeAccel;
use caustic::accel::{build, Accel, AccelKind, AccelOptions};
use caustic::analysis::rays::{process_cpu_seconds, standard_ray_sets, throughput};
use caustic::scene::load_scene;
use std::path::Path;
use std::time::Instant;

#[test]
#[ignore = "release-mode measurement on the dragon asset"]
fn dragon_throughput_kdtree_vs_embree() {
    let scene = load_scene(Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/dragon.toml"))).unwrap();
    let (w, h) = std::env::var("KDTREE_BENCH_SIZE")
        .ok()
        .and_then(|s| {
            let (a, b) = s.split_once('x')?;
            Some((a.parse().ok()?, b.parse().ok()?))
        })
        .unwrap_or((640u32, 360u32));
    let options = AccelOptions::default();
    let mut kinds = vec![AccelKind::KdTree];
    if cfg!(feature = "embree") && std::env::var_os("KD_ONLY").is_none() {
        kinds.push(AccelKind::Embree);
    }
    // KD_PARAMS="K_T,K_I,bonus,leaf_size" overrides the SAH constants (tuning).
    let params = std::env::var("KD_PARAMS").ok().map(|s| {
        let v: Vec<f32> = s.split(',').map(|x| x.parse().unwrap()).collect();
        SahParams {
            traversal_cost: v[0],
            intersect_cost: v[1],
            empty_bonus: v[2],
            leaf_size: v[3] as usize,
            max_depth: None,
        }
    });
    let accels: Vec<Box<dyn Accel>> = kinds
        .iter()
        .map(|&k| {
            let t = Instant::now();
            let cpu = process_cpu_seconds();
            let a: Box<dyn Accel> = match (k, params) {
                (AccelKind::KdTree, Some(p)) => Box::new(KdTreeAccel::build_with(&scene.scene, &options, &p)),
                _ => build(&scene.scene, k, &options).unwrap(),
            };
            println!(
                "{}: built in {:.3} s wall, {:.2} s CPU",
                k.name(),
                t.elapsed().as_secs_f64(),
                cpu.zip(process_cpu_seconds()).map_or(f64::NAN, |(a, b)| b - a)
            );
            for (key, v) in &a.stats().details {
                println!("    {key}: {v}");
            }
            a
        })
        .collect();
    let reference = accels.last().unwrap();
    let sets = standard_ray_sets(
        &scene.scene,
        reference.as_ref(),
        (w * h) as usize,
        w as f32 / h as f32,
        1,
    );
    println!("threads: {}", rayon::current_num_threads());
    for set in &sets {
        let mut hits = Vec::new();
        for (kind, accel) in kinds.iter().zip(&accels) {
            // Best of three runs: the machine may be shared.
            let best = (0..3)
                .map(|_| throughput(accel.as_ref(), &set.rays, set.query()))
                .max_by(|a, b| a.mrays_per_s().total_cmp(&b.mrays_per_s()))
                .unwrap();
            println!(
                "{:>10} {:>7}: {:8.2} Mrays/s, {:6.2} Mrays/CPU-s ({} rays, {} hits)",
                set.kind.name(),
                kind.name(),
                best.mrays_per_s(),
                best.mrays_per_cpu_s().unwrap_or(f64::NAN),
                best.rays,
                best.hits
            );
            hits.push(best.hits);
        }
        // Both backends must agree on the counts up to a few edge cases.
        let (lo, hi) = (*hits.iter().min().unwrap(), *hits.iter().max().unwrap());
        assert!(
            hi - lo <= set.rays.len() / 1000 + 5,
            "{}: hit counts {hits:?}",
            set.kind.name()
        );
    }
    println!(
        "loadavg: {}",
        std::fs::read_to_string("/proc/loadavg").unwrap_or_default().trim()
    );
}
