//! Sharded renders and their merge: tiles shards merge bit-identical to a
//! single-process render for several shard and thread counts (tree merges
//! and resumed shards too); sample shards merge within the stated bound;
//! every refusal of `merge`; `--shard auto`'s environment parsing; photon
//! files (`caustic photons`, `--photon-map`) give the same image and are
//! refused for another render; the command line end to end (exit codes,
//! byte-identical PNG).

mod common;

use caustic::accel::AccelKind;
use caustic::film::shard::samples_merge_bound;
use caustic::film::{read_checkpoint, write_checkpoint, Accumulation, ShardId, ShardMode, ShardSet};
use caustic::job::{self, merge_partials, JobError, JobHooks, MergeRequest, RenderJob, RenderRequest};
use caustic::scene::IntegratorKind;
use common::cli::{caustic_with_env, stderr};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Output;
use std::sync::atomic::{AtomicBool, Ordering};

const SCENE: &str = "scenes/test/caustic.toml";

fn scene_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(SCENE)
}

/// The glass-sphere caustic scene at 64×48: photon pass, Fresnel branches
/// and spread light strata all take part.
fn request(spp: u32, seed: u64) -> RenderRequest {
    let mut r = RenderRequest::new(scene_path());
    r.overrides.width = Some(64);
    r.overrides.height = Some(48);
    r.overrides.spp = Some(spp);
    r.overrides.seed = Some(seed);
    r.overrides.photons = Some(20_000);
    r.accel = Some(AccelKind::KdTree);
    r
}

fn run(request: &RenderRequest, threads: usize) -> job::JobReport {
    let job = RenderJob::prepare(request).unwrap();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| job.run(&JobHooks::silent())).unwrap()
}

/// Renders shard `index` of `count` to `dir/name`.
fn shard(base: &RenderRequest, index: u32, count: u32, mode: ShardMode, threads: usize, path: &Path) {
    let mut r = base.clone();
    r.shard = Some(ShardSet::single(ShardId::new(index, count).unwrap(), mode));
    r.checkpoint = Some(path.to_path_buf());
    let report = run(&r, threads);
    assert!(report.complete(), "shard {index}/{count}");
}

fn single(base: &RenderRequest, threads: usize, png: &Path) -> Accumulation {
    let mut r = base.clone();
    r.png = Some(png.to_path_buf());
    r.exr = Some(png.with_extension("exr"));
    run(&r, threads).output.accumulation
}

fn merge(partials: &[PathBuf], png: Option<&Path>, partial: Option<&Path>) -> Result<job::MergeReport, JobError> {
    merge_partials(&MergeRequest {
        partials: partials.to_vec(),
        png: png.map(Path::to_path_buf),
        exr: None,
        partial: partial.map(Path::to_path_buf),
        denoise: false,
        ..Default::default()
    })
}

#[test]
fn tiles_merge_is_bit_identical_for_any_shard_and_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let base = request(6, 5);
    let reference_png = dir.path().join("single.png");
    let reference = single(&base, 2, &reference_png);
    for (count, threads) in [(1u32, 1usize), (3, 2), (4, 1), (7, 2)] {
        let parts: Vec<PathBuf> = (0..count)
            .map(|i| {
                let p = dir.path().join(format!("n{count}-{i}.exr"));
                shard(&base, i, count, ShardMode::Tiles, threads, &p);
                p
            })
            .collect();
        let png = dir.path().join(format!("merged-{count}.png"));
        let exr = png.with_extension("exr");
        let report = merge_partials(&MergeRequest {
            partials: parts.clone(),
            png: Some(png.clone()),
            exr: Some(exr.clone()),
            partial: None,
            denoise: false,
            ..Default::default()
        })
        .unwrap();
        assert!(report.accumulation == reference, "{count} shards, {threads} threads");
        for (merged, single) in [(&png, &reference_png), (&exr, &reference_png.with_extension("exr"))] {
            let same = std::fs::read(merged).unwrap() == std::fs::read(single).unwrap();
            assert!(same, "{count} shards: {} differs", merged.display());
        }
        if count == 4 {
            // A tree: (0, 2) and (1, 3) into partials, then those two.
            let a = dir.path().join("t02.exr");
            let b = dir.path().join("t13.exr");
            merge(&[parts[0].clone(), parts[2].clone()], None, Some(&a)).unwrap();
            merge(&[parts[3].clone(), parts[1].clone()], None, Some(&b)).unwrap();
            let sub = read_checkpoint(&a).unwrap();
            assert_eq!(sub.meta.shard.as_ref().unwrap().indices, [0, 2]);
            let tree = merge(&[b, a], Some(&png), None).unwrap();
            assert!(tree.accumulation == reference, "tree merge");
        }
    }
}

#[test]
fn an_interrupted_shard_resumes_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let base = request(6, 8);
    let reference = single(&base, 2, &dir.path().join("single.png"));
    let count = 3;
    let mut parts = Vec::new();
    for i in 0..count {
        let p = dir.path().join(format!("p{i}.exr"));
        if i == 1 {
            // Stop shard 1 after its first tiles, then resume its partial.
            let mut r = base.clone();
            r.shard = Some(ShardSet::single(ShardId::new(1, count).unwrap(), ShardMode::Tiles));
            r.checkpoint = Some(p.clone());
            let cancel = AtomicBool::new(false);
            let progress = |done: u64, _: u64| {
                if done > 500 {
                    cancel.store(true, Ordering::Relaxed);
                }
            };
            let hooks = JobHooks {
                cancel: Some(&cancel),
                progress: &progress,
                ..JobHooks::silent()
            };
            let report = RenderJob::prepare(&r).unwrap().run(&hooks).unwrap();
            assert!(!report.complete());
            assert!(report.samples_done() > 0 && report.samples_done() < report.total_samples);
            // An unfinished partial is refused by the merge, naming it.
            let others = [dir.path().join("p0.exr"), p.clone()];
            let e = merge(&others, None, Some(&dir.path().join("x.exr")))
                .unwrap_err()
                .to_string();
            assert!(e.contains("p1.exr") && e.contains("not finished"), "{e}");
            let mut resume = RenderRequest::new(scene_path());
            resume.resume = Some(p.clone());
            let report = run(&resume, 1);
            assert!(report.complete());
            // A finished partial resumed again has nothing to do: no photon pass.
            let again = run(&resume, 1);
            assert!(again.complete() && again.output.stats.photons.is_none());
            assert!(again.output.accumulation == report.output.accumulation);
        } else {
            shard(&base, i, count, ShardMode::Tiles, 2, &p);
        }
        parts.push(p);
    }
    let report = merge(&parts, Some(&dir.path().join("m.png")), None).unwrap();
    assert!(report.accumulation == reference);
}

/// Largest relative difference between two films' channels.
fn max_relative_difference(a: &Accumulation, b: &Accumulation) -> f64 {
    let (fa, fb) = (a.to_film(), b.to_film());
    let mut worst = 0.0f64;
    for (p, q) in fa.pixels.iter().zip(&fb.pixels) {
        for c in 0..3 {
            let (x, y) = (p[c] as f64, q[c] as f64);
            if x != y {
                worst = worst.max((x - y).abs() / x.abs().max(y.abs()));
            }
        }
    }
    worst
}

#[test]
fn sample_shards_merge_within_the_bound() {
    let dir = tempfile::tempdir().unwrap();
    for integrator in [IntegratorKind::Whitted, IntegratorKind::Path] {
        let mut base = request(12, 21);
        base.overrides.integrator = Some(integrator);
        let reference = single(&base, 2, &dir.path().join("single.png"));
        let bound = samples_merge_bound(12);
        for count in [2u32, 4, 12] {
            let parts: Vec<PathBuf> = (0..count)
                .map(|i| {
                    let p = dir.path().join(format!("s{count}-{i}.exr"));
                    shard(&base, i, count, ShardMode::Samples, 1 + i as usize % 2, &p);
                    p
                })
                .collect();
            let merged = merge(&parts, Some(&dir.path().join("m.png")), None)
                .unwrap()
                .accumulation;
            // The same samples: counts agree exactly, sums to rounding.
            assert_eq!(merged.taken, reference.taken);
            assert_eq!(merged.kept, reference.kept);
            assert_eq!(merged.odd_kept, reference.odd_kept);
            assert!(reference.sum.iter().all(|s| s.min_element() >= 0.0));
            let worst = max_relative_difference(&merged, &reference);
            println!(
                "{integrator:?}, {count} sample shards: largest relative difference {worst:.3e} (bound {bound:.3e})"
            );
            assert!(worst <= bound, "{count} shards: {worst} > {bound}");
            if count == 12 {
                // One sample per shard: the merge adds in the single render's order.
                assert!(merged == reference, "one sample per shard is bit-identical");
            }
            if count == 4 {
                let a = dir.path().join("s02.exr");
                merge(&[parts[0].clone(), parts[2].clone()], None, Some(&a)).unwrap();
                let tree = merge(
                    &[a, parts[1].clone(), parts[3].clone()],
                    None,
                    Some(&dir.path().join("t.exr")),
                )
                .unwrap()
                .accumulation;
                assert!(max_relative_difference(&tree, &reference) <= bound);
            }
        }
    }
}

#[test]
fn merge_refuses_what_does_not_belong_together_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n);
    let base = request(4, 1);
    for i in 0..3 {
        shard(&base, i, 3, ShardMode::Tiles, 2, &p(&format!("t{i}.exr")));
    }
    let mut other_seed = base.clone();
    other_seed.overrides.seed = Some(2);
    shard(&other_seed, 1, 3, ShardMode::Tiles, 2, &p("seed2.exr"));
    shard(&base, 1, 3, ShardMode::Samples, 2, &p("samples1.exr"));
    shard(&base, 1, 4, ShardMode::Tiles, 2, &p("four1.exr"));
    let mut whole = base.clone();
    whole.checkpoint = Some(p("whole.exr"));
    run(&whole, 2);
    let out = p("out.png");
    let refuse = |inputs: &[&str], png: Option<&Path>, partial: Option<&Path>, expect: &[&str]| {
        let inputs: Vec<PathBuf> = inputs.iter().map(|n| p(n)).collect();
        let e = merge(&inputs, png, partial).unwrap_err();
        assert!(e.is_bad_input(), "{e}");
        let e = e.to_string();
        for part in expect {
            assert!(e.contains(part), "expected {part:?} in: {e}");
        }
        assert!(!out.exists(), "nothing is written on a refusal");
    };
    refuse(
        &["t0.exr", "seed2.exr", "t2.exr"],
        Some(&out),
        None,
        &["seed2.exr", "different render", "seed 1"],
    );
    refuse(
        &["t0.exr", "t1.exr", "t1.exr", "t2.exr"],
        Some(&out),
        None,
        &["t1.exr", "given twice"],
    );
    std::fs::copy(p("t1.exr"), p("t1-copy.exr")).unwrap();
    refuse(
        &["t0.exr", "t1.exr", "t1-copy.exr", "t2.exr"],
        Some(&out),
        None,
        &["t1-copy.exr", "shard 1 of 3", "duplicate"],
    );
    refuse(&["t0.exr", "t2.exr"], Some(&out), None, &["missing shard 1 of 3"]);
    refuse(
        &["t0.exr", "samples1.exr", "t2.exr"],
        Some(&out),
        None,
        &["samples1.exr", "split by samples", "t0.exr"],
    );
    refuse(
        &["t0.exr", "four1.exr"],
        None,
        Some(&p("x.exr")),
        &["four1.exr", "of 4 shards"],
    );
    refuse(
        &["t0.exr", "whole.exr"],
        Some(&out),
        None,
        &["whole.exr", "not a partial"],
    );
    refuse(&["t0.exr", "missing.exr", "t2.exr"], Some(&out), None, &["missing.exr"]);
    std::fs::write(p("junk.exr"), b"not an image").unwrap();
    refuse(&["t0.exr", "junk.exr"], Some(&out), None, &["junk.exr", "cannot read"]);
    refuse(&["t0.exr", "t1.exr", "t2.exr"], None, None, &["nothing to write"]);
    refuse(
        &["t0.exr", "t1.exr", "t2.exr"],
        None,
        Some(&p("t0.exr")),
        &["t0.exr", "one of the partials"],
    );
    // An unfinished partial: counts below the spp.
    let mut c = read_checkpoint(&p("t2.exr")).unwrap();
    let i = c.accumulation.taken.iter().position(|&t| t > 0).unwrap();
    c.accumulation.taken[i] = 1;
    c.accumulation.kept[i] = 1;
    c.accumulation.odd_kept[i] = 0;
    write_checkpoint(&p("short2.exr"), &c.accumulation, &c.meta).unwrap();
    refuse(
        &["t0.exr", "t1.exr", "short2.exr"],
        Some(&out),
        None,
        &["short2.exr", "not finished", "--resume"],
    );
    // A header edited to another size under the same fingerprint.
    let t1 = read_checkpoint(&p("t1.exr")).unwrap();
    let mut meta = t1.meta.clone();
    (meta.width, meta.height) = (32, 24);
    write_checkpoint(&p("edited1.exr"), &Accumulation::new(32, 24), &meta).unwrap();
    refuse(
        &["t0.exr", "edited1.exr", "t2.exr"],
        Some(&out),
        None,
        &["edited1.exr", "damaged or edited", "width 64"],
    );
    // A partial whose fingerprint another format computed (an older
    // caustic's): not comparable, refused saying so.
    let mut meta = t1.meta.clone();
    meta.fingerprint_format = 1;
    write_checkpoint(&p("old1.exr"), &t1.accumulation, &meta).unwrap();
    refuse(
        &["t0.exr", "old1.exr", "t2.exr"],
        Some(&out),
        None,
        &[
            "old1.exr",
            "written by another caustic",
            "fingerprint format 1 here, 2 there",
        ],
    );
    // Partials all of the older format still merge among themselves.
    for i in [0, 2] {
        let c = read_checkpoint(&p(&format!("t{i}.exr"))).unwrap();
        let meta = caustic::film::CheckpointMeta {
            fingerprint_format: 1,
            ..c.meta
        };
        write_checkpoint(&p(&format!("old{i}.exr")), &c.accumulation, &meta).unwrap();
    }
    merge(
        &[p("old0.exr"), p("old1.exr"), p("old2.exr")],
        None,
        Some(&p("old-merged.exr")),
    )
    .unwrap();
    assert_eq!(
        read_checkpoint(&p("old-merged.exr")).unwrap().meta.fingerprint_format,
        1
    );
    // And the good set merges.
    merge(&[p("t2.exr"), p("t0.exr"), p("t1.exr")], Some(&out), None).unwrap();
    assert!(out.exists());
}

#[test]
fn render_refuses_shards_it_cannot_split() {
    let mut r = request(4, 1);
    r.shard = Some(ShardSet::single(ShardId::new(0, 2).unwrap(), ShardMode::Tiles));
    r.checkpoint = Some(std::env::temp_dir().join("caustic-never-written.exr"));
    let mut adaptive = r.clone();
    adaptive.overrides.noise_threshold = Some(0.05);
    adaptive.overrides.min_spp = Some(2);
    let e = RenderJob::prepare(&adaptive).err().unwrap().to_string();
    assert!(e.contains("adaptive sampling") && e.contains("shards"), "{e}");
    let mut samples = r.clone();
    samples.shard = Some(ShardSet::single(ShardId::new(0, 5).unwrap(), ShardMode::Samples));
    let e = RenderJob::prepare(&samples).err().unwrap().to_string();
    assert!(e.contains("at least 5 samples per pixel"), "{e}");
    let mut no_file = r.clone();
    no_file.checkpoint = None;
    let e = RenderJob::prepare(&no_file).err().unwrap().to_string();
    assert!(e.contains("-o PART.exr"), "{e}");
}

fn env(pairs: &[(&str, &str)]) -> impl Fn(&str) -> Option<String> {
    let map: HashMap<String, String> = pairs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
    move |k: &str| map.get(k).cloned()
}

#[test]
fn shard_auto_reads_slurm_and_kubernetes() {
    let id = |index, count| Ok(ShardId { index, count });
    let auto = |pairs: &[(&str, &str)], count| job::shard_from_env(&env(pairs), count);
    // Slurm: --array=0-3 (Slurm sets ID, COUNT, MIN, MAX, STEP).
    let slurm = |task: &str| {
        vec![
            ("SLURM_ARRAY_TASK_ID", task.to_string()),
            ("SLURM_ARRAY_TASK_COUNT", "4".into()),
            ("SLURM_ARRAY_TASK_MIN", "0".into()),
            ("SLURM_ARRAY_TASK_MAX", "3".into()),
            ("SLURM_ARRAY_TASK_STEP", "1".into()),
        ]
    };
    for task in 0..4u32 {
        let v = slurm(&task.to_string());
        let pairs: Vec<(&str, &str)> = v.iter().map(|(k, v)| (*k, v.as_str())).collect();
        assert_eq!(auto(&pairs, None), id(task, 4));
        assert_eq!(auto(&pairs, Some(4)), id(task, 4));
        assert!(auto(&pairs, Some(5)).unwrap_err().contains("4 tasks"));
    }
    // --array=1-4, MIN and MAX only (no COUNT).
    let one_based = [
        ("SLURM_ARRAY_TASK_ID", "4"),
        ("SLURM_ARRAY_TASK_MIN", "1"),
        ("SLURM_ARRAY_TASK_MAX", "4"),
    ];
    assert_eq!(auto(&one_based, None), id(3, 4));
    // --array=0-30:10.
    let stepped = [
        ("SLURM_ARRAY_TASK_ID", "20"),
        ("SLURM_ARRAY_TASK_MIN", "0"),
        ("SLURM_ARRAY_TASK_MAX", "30"),
        ("SLURM_ARRAY_TASK_STEP", "10"),
    ];
    assert_eq!(auto(&stepped, None), id(2, 4));
    let off_step = [
        ("SLURM_ARRAY_TASK_ID", "25"),
        ("SLURM_ARRAY_TASK_MAX", "30"),
        ("SLURM_ARRAY_TASK_STEP", "10"),
    ];
    assert!(auto(&off_step, None).unwrap_err().contains("SLURM_ARRAY_TASK_ID=25"));
    // A task id without any count: --shard-count decides, else an error.
    assert_eq!(auto(&[("SLURM_ARRAY_TASK_ID", "2")], Some(3)), id(2, 3));
    assert!(auto(&[("SLURM_ARRAY_TASK_ID", "2")], None)
        .unwrap_err()
        .contains("--shard-count"));
    assert!(auto(&[("SLURM_ARRAY_TASK_ID", "x")], None)
        .unwrap_err()
        .contains("\"x\""));
    assert!(
        auto(&[("SLURM_ARRAY_TASK_ID", "7"), ("SLURM_ARRAY_TASK_COUNT", "4")], None)
            .unwrap_err()
            .contains("0..=3")
    );
    // Kubernetes: the index from the environment, the count from the command line.
    assert_eq!(auto(&[("JOB_COMPLETION_INDEX", "3")], Some(8)), id(3, 8));
    assert!(auto(&[("JOB_COMPLETION_INDEX", "3")], None)
        .unwrap_err()
        .contains("--shard-count"));
    assert!(auto(&[("JOB_COMPLETION_INDEX", "8")], Some(8))
        .unwrap_err()
        .contains("0..=7"));
    // Neither.
    assert!(auto(&[], Some(4)).unwrap_err().contains("--shard I/N"));
    // --shard I/N itself, with --shard-count agreeing or not.
    let none = env(&[]);
    assert_eq!(job::parse_shard_arg("1/4", None, &none), id(1, 4));
    assert_eq!(job::parse_shard_arg("1/4", Some(4), &none), id(1, 4));
    assert!(job::parse_shard_arg("1/4", Some(3), &none).is_err());
    assert!(job::parse_shard_arg("4/4", None, &none).unwrap_err().contains("0..=3"));
    assert_eq!(
        job::parse_shard_arg("auto", Some(2), &env(&[("JOB_COMPLETION_INDEX", "1")])),
        id(1, 2)
    );
}

#[test]
fn command_line_shards_merge_to_the_same_png_and_refusals_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let settings = [
        "--width",
        "48",
        "--height",
        "32",
        "--spp",
        "4",
        "--photons",
        "10000",
        "--accel",
        "kdtree",
        "--quiet",
    ];
    let with = |extra: &[&str]| -> Vec<String> {
        let mut v: Vec<String> = vec!["render".into(), SCENE.into()];
        v.extend(settings.iter().map(|s| s.to_string()));
        v.extend(extra.iter().map(|s| s.to_string()));
        v
    };
    let run = |args: Vec<String>, envs: &[(&str, &str)]| {
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        caustic_with_env(&refs, envs)
    };
    let single = run(with(&["-o", &p("single.png")]), &[]);
    assert!(single.status.success(), "{}", stderr(&single));
    // Shards 0 and 2 from a Slurm array's environment, 1 from --shard.
    for task in ["0", "2"] {
        let envs = [("SLURM_ARRAY_TASK_ID", task), ("SLURM_ARRAY_TASK_COUNT", "3")];
        let o = run(with(&["--shard", "auto", "-o", &p(&format!("part-{task}.exr"))]), &envs);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let o = run(with(&["--shard", "1/3", "--threads", "1", "-o", &p("part-1.exr")]), &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let meta = caustic::film::read_checkpoint_meta(Path::new(&p("part-2.exr"))).unwrap();
    assert_eq!(meta.shard.unwrap().indices, [2]);
    let o = caustic_with_env(
        &[
            "merge",
            &p("part-0.exr"),
            &p("part-1.exr"),
            &p("part-2.exr"),
            "-o",
            &p("merged.png"),
        ],
        &[],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read(p("merged.png")).unwrap(),
        std::fs::read(p("single.png")).unwrap()
    );

    // Refusals: exit code 2 and a message, never a panic.
    let refused = |o: Output, expect: &str| {
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{e}");
        assert!(
            e.contains(expect) && !e.contains("panicked"),
            "expected {expect:?} in: {e}"
        );
    };
    refused(
        caustic_with_env(&["merge", &p("part-0.exr"), &p("part-2.exr"), "-o", &p("x.png")], &[]),
        "missing shard 1 of 3",
    );
    refused(
        caustic_with_env(
            &[
                "merge",
                &p("part-0.exr"),
                &p("part-1.exr"),
                &p("single.png"),
                "-o",
                &p("x.png"),
            ],
            &[],
        ),
        "single.png",
    );
    refused(
        run(with(&["--shard", "auto", "-o", &p("a.exr")]), &[]),
        "SLURM_ARRAY_TASK_ID",
    );
    refused(
        run(
            with(&["--shard", "auto", "-o", &p("a.exr")]),
            &[("JOB_COMPLETION_INDEX", "0")],
        ),
        "--shard-count",
    );
    refused(run(with(&["--shard", "3/3", "-o", &p("a.exr")]), &[]), "0..=2");
    refused(run(with(&["--shard", "0/3"]), &[]), "-o PART.exr");
    refused(
        run(with(&["--shard", "0/3", "-o", &p("a.png")]), &[]),
        "name it PART.exr",
    );
    refused(
        run(with(&["--resume", &p("part-1.exr"), "-o", &p("a.png")]), &[]),
        "name it PART.exr",
    );
    refused(
        run(
            with(&[
                "--shard",
                "0/3",
                "--noise-threshold",
                "0.05",
                "--min-spp",
                "2",
                "-o",
                &p("a.exr"),
            ]),
            &[],
        ),
        "adaptive sampling",
    );
    refused(
        run(with(&["--shard", "0/3", "--exr", &p("b.exr"), "-o", &p("a.exr")]), &[]),
        "--exr",
    );
    refused(
        run(with(&["--shard", "0/2", "--resume", &p("part-1.exr")]), &[]),
        "not shard 0/2",
    );

    // A photon file traced once, loaded by a shard; refused for another seed.
    let o = caustic_with_env(
        &[
            "photons",
            SCENE,
            "--photons",
            "10000",
            "--accel",
            "kdtree",
            "--quiet",
            "-o",
            &p("map.bin"),
        ],
        &[],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let o = run(
        with(&["--shard", "1/3", "--photon-map", &p("map.bin"), "-o", &p("map-1.exr")]),
        &[],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let o = caustic_with_env(
        &[
            "merge",
            &p("part-0.exr"),
            &p("map-1.exr"),
            &p("part-2.exr"),
            "-o",
            &p("merged-map.png"),
        ],
        &[],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read(p("merged-map.png")).unwrap(),
        std::fs::read(p("single.png")).unwrap()
    );
    refused(
        run(
            with(&["--seed", "9", "--photon-map", &p("map.bin"), "-o", &p("x.png")]),
            &[],
        ),
        "map.bin: photons of another scene",
    );
}

#[test]
fn a_photon_file_gives_the_same_image_and_is_refused_for_another_render() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n);
    let base = request(4, 3);
    let reference = single(&base, 2, &p("single.png"));
    let photons = |path: &Path, overrides: &job::Overrides| {
        let request = job::PhotonsRequest {
            scene: scene_path(),
            overrides: overrides.clone(),
            accel: Some(AccelKind::KdTree),
            accel_options: Default::default(),
            output: path.to_path_buf(),
        };
        job::trace_to_file(&request)
    };
    let report = photons(&p("map.bin"), &base.overrides).unwrap();
    assert_eq!(report.emitted, 20_000);
    assert!(report.stored > 1000, "{report:?}");
    // Every shard loads the file: the merge is the single render, bit for bit.
    let mut with_map = base.clone();
    with_map.photon_map = Some(p("map.bin"));
    let parts: Vec<PathBuf> = (0..3)
        .map(|i| {
            let part = p(&format!("m{i}.exr"));
            shard(&with_map, i, 3, ShardMode::Tiles, 1 + i as usize % 2, &part);
            part
        })
        .collect();
    assert!(merge(&parts, Some(&p("m.png")), None).unwrap().accumulation == reference);
    assert_eq!(
        std::fs::read(p("m.png")).unwrap(),
        std::fs::read(p("single.png")).unwrap()
    );
    // The image size and samples do not matter to the photons.
    let mut bigger = with_map.clone();
    bigger.overrides.width = Some(80);
    bigger.overrides.spp = Some(2);
    assert!(RenderJob::prepare(&bigger).is_ok());
    // Another photon count, seed or accelerator, no photon pass, a bad file: refused.
    let mut other = with_map.clone();
    other.overrides.photons = Some(30_000);
    let e = RenderJob::prepare(&other).err().unwrap();
    assert!(e.is_bad_input() && e.to_string().contains("map.bin"), "{e}");
    assert!(e.to_string().contains("20000 photons in the file, 30000 here"), "{e}");
    let mut other = with_map.clone();
    other.overrides.seed = Some(4);
    assert!(RenderJob::prepare(&other)
        .err()
        .unwrap()
        .to_string()
        .contains("another scene or other settings"));
    let mut other = with_map.clone();
    other.accel = Some(AccelKind::Brute);
    assert!(RenderJob::prepare(&other).is_err());
    let mut none = with_map.clone();
    none.overrides.photons = Some(0);
    assert!(RenderJob::prepare(&none)
        .err()
        .unwrap()
        .to_string()
        .contains("no photon pass"));
    std::fs::write(p("junk.bin"), b"caustic-photon1\n").unwrap();
    let mut junk = base.clone();
    junk.photon_map = Some(p("junk.bin"));
    let e = RenderJob::prepare(&junk).err().unwrap().to_string();
    assert!(
        e.contains("junk.bin") && e.contains("not a valid caustic photon file"),
        "{e}"
    );
    let mut no_pass = base.overrides.clone();
    no_pass.photons = Some(0);
    assert!(photons(&p("none.bin"), &no_pass)
        .unwrap_err()
        .to_string()
        .contains("no photon pass"));
}

#[test]
fn a_gaussian_filtered_render_merges_and_resumes_bit_for_bit() {
    // The filter moves samples out of their pixel's square but never into
    // another pixel's accumulation: tiles still merge exactly.
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(scene_path()).unwrap();
    let filtered = dir.path().join("filtered.toml");
    std::fs::write(
        &filtered,
        text.replacen(
            "vfov = 40\n",
            "vfov = 40\nfilter = \"gaussian\"\nfilter_stddev = 0.8\n",
            1,
        ),
    )
    .unwrap();
    let mut base = request(4, 3);
    base.scene = filtered;
    let reference = single(&base, 2, &dir.path().join("single.png"));
    let unfiltered = single(&request(4, 3), 2, &dir.path().join("box.png"));
    assert!(reference != unfiltered, "the filter changed no sample");
    let parts: Vec<PathBuf> = (0..3)
        .map(|i| {
            let p = dir.path().join(format!("g{i}.exr"));
            shard(&base, i, 3, ShardMode::Tiles, 1 + i as usize % 2, &p);
            p
        })
        .collect();
    let merged = merge(&parts, Some(&dir.path().join("merged.png")), None).unwrap();
    assert!(merged.accumulation == reference, "merged tiles differ");
    // Interrupted part way and resumed from the checkpoint.
    let mut r = base.clone();
    let checkpoint = dir.path().join("resume.exr");
    r.checkpoint = Some(checkpoint.clone());
    let cancel = AtomicBool::new(false);
    let progress = |done: u64, _: u64| {
        if done > 2000 {
            cancel.store(true, Ordering::Relaxed);
        }
    };
    let hooks = JobHooks {
        cancel: Some(&cancel),
        progress: &progress,
        ..JobHooks::silent()
    };
    let first = RenderJob::prepare(&r).unwrap().run(&hooks).unwrap();
    assert!(!first.complete(), "the render was not interrupted");
    let mut resume = RenderRequest::new(base.scene.clone());
    resume.resume = Some(checkpoint);
    let resumed = run(&resume, 1);
    assert!(resumed.complete());
    assert!(resumed.output.accumulation == reference, "resumed render differs");
}
