//! `caustic bench` end to end on small scenes with tiny ray counts: the JSON
//! report's structure, every figure positive and finite, and the same hit
//! counts from every accelerator. No timing is asserted.

mod common;

use common::cli::command;
use serde_json::Value;
use std::path::Path;

/// The accelerators compared: both real ones when Embree is compiled in,
/// else the KD-tree against the brute-force oracle.
fn accels() -> (&'static str, [&'static str; 2]) {
    if cfg!(feature = "embree") {
        ("embree,kdtree", ["embree", "kdtree"])
    } else {
        ("kdtree,brute", ["kdtree", "brute"])
    }
}

fn number(v: &Value, what: &str) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("{what} is not a number: {v}"))
}

fn positive(v: &Value, what: &str) -> f64 {
    let x = number(v, what);
    assert!(x.is_finite() && x > 0.0, "{what} = {x}");
    x
}

#[test]
fn bench_writes_a_consistent_report() {
    let dir = tempfile::tempdir().unwrap();
    let json_path = dir.path().join("bench.json");
    let (list, names) = accels();
    let out = command(&[])
        .args(["bench", "scenes/test/shadow.toml", "scenes/cornell.toml"])
        .args(["--accel", list, "--rays", "3000", "--repeats", "2", "--seed", "5"])
        .args([
            "--width",
            "48",
            "--height",
            "27",
            "--spp",
            "2",
            "--photons",
            "2000",
            "--threads",
            "2",
        ])
        .arg("--json")
        .arg(&json_path)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "stdout:\n{stdout}\nstderr:\n{stderr}");

    let report: Value = serde_json::from_str(&std::fs::read_to_string(&json_path).unwrap()).unwrap();
    assert_eq!(report["threads"], 2);
    assert_eq!(report["seed"], 5);
    assert_eq!(report["rays_per_kind"], 3000);
    assert_eq!(report["repeats"], 2);
    let scenes = report["scenes"].as_array().unwrap();
    assert_eq!(scenes.len(), 2);
    assert_eq!(scenes[0]["scene"], "scenes/test/shadow.toml");
    assert_eq!(scenes[1]["scene"], "scenes/cornell.toml");
    assert!(
        scenes[1]["triangles"].as_u64().unwrap() > 0,
        "the Cornell box has the star mesh"
    );

    for s in scenes {
        let name = s["scene"].as_str().unwrap();
        assert_eq!(s["baseline"], names[0], "{name}");
        let sets = s["ray_sets"].as_array().unwrap();
        let kinds: Vec<&str> = sets.iter().map(|r| r["kind"].as_str().unwrap()).collect();
        assert_eq!(kinds, ["camera", "shadow", "incoherent"], "{name}");
        let queries: Vec<&str> = sets.iter().map(|r| r["query"].as_str().unwrap()).collect();
        assert_eq!(queries, ["closest", "occluded", "closest"], "{name}");
        assert_eq!(sets[0]["rays"], 3000);
        assert_eq!(sets[2]["rays"], 3000);
        assert!(sets[1]["rays"].as_u64().unwrap() > 0, "{name}: shadow rays");
        let rs = &s["render_settings"];
        assert_eq!(
            (rs["width"].as_u64(), rs["height"].as_u64(), rs["spp"].as_u64()),
            (Some(48), Some(27), Some(2))
        );

        let accels = s["accelerators"].as_array().unwrap();
        let got: Vec<&str> = accels.iter().map(|a| a["name"].as_str().unwrap()).collect();
        assert_eq!(got, names, "{name}");
        for a in accels {
            let what = format!("{name} {}", a["name"]);
            assert!(number(&a["build_seconds"], &what) >= 0.0);
            // The brute-force oracle holds no structure of its own.
            if a["name"] != "brute" {
                positive(&a["memory_bytes"], &format!("{what} memory_bytes"));
            }
            if cfg!(target_os = "linux") {
                let before = positive(&a["rss_before_build_bytes"], &what);
                let peak_build = positive(&a["peak_rss_build_bytes"], &what);
                let peak = positive(&a["peak_rss_bytes"], &what);
                if a["peak_rss_reset"] == true {
                    assert!(
                        peak_build >= before && peak >= peak_build,
                        "{what}: {before} {peak_build} {peak}"
                    );
                }
            }
            let rays = a["rays"].as_array().unwrap();
            assert_eq!(rays.len(), 3, "{what}");
            for (r, set) in rays.iter().zip(sets) {
                let what = format!("{what} {}", r["kind"]);
                assert_eq!(r["kind"], set["kind"], "{what}");
                assert_eq!(r["rays"], set["rays"], "{what}");
                let hits = r["hits"].as_u64().unwrap();
                assert!(hits <= r["rays"].as_u64().unwrap(), "{what}");
                positive(&r["seconds"], &what);
                positive(&r["mrays_per_s"], &what);
                assert_eq!(r["runs_seconds"].as_array().unwrap().len(), 2, "{what}");
            }
            // The camera sees the floor and walls: not every ray escapes.
            assert!(rays[0]["hits"].as_u64().unwrap() > 0, "{what}");
            let render = &a["render"];
            positive(&render["seconds"], &what);
            positive(&render["mrays_per_s"], &what);
            assert!(render["image_rays"].as_u64().unwrap() >= 48 * 27 * 2, "{what}");
            assert_eq!(render["dropped_samples"], 0, "{what}");
        }
        // The Cornell box has glass and a mirror: the photon pass ran, with its rays counted.
        if name.contains("cornell") {
            assert_eq!(rs["photon_pass"], true);
            assert_eq!(rs["photons"], 2000);
            assert!(accels.iter().all(|a| a["render"]["photon_rays"].as_u64().unwrap() > 0));
        }

        let comparisons = s["comparisons"].as_array().unwrap();
        assert_eq!(comparisons.len(), 1, "{name}");
        let c = &comparisons[0];
        assert_eq!(
            (c["accel"].as_str(), c["baseline"].as_str()),
            (Some(names[1]), Some(names[0]))
        );
        // The brute-force oracle builds nothing: its build time may be 0.
        let build_ratio = number(&c["build_time_ratio"], name);
        assert!(build_ratio.is_finite() && build_ratio >= 0.0, "{name}: {build_ratio}");
        positive(&c["render_time_ratio"], name);
        for k in c["rays"].as_array().unwrap() {
            let what = format!("{name} {}", k["kind"]);
            positive(&k["mrays_ratio"], &what);
            assert_eq!(k["hits_difference"], 0, "{what}: {k}");
            assert_eq!(k["hits"], k["baseline_hits"], "{what}");
        }
    }

    // The table carries the same figures.
    assert!(stdout.contains("scenes/cornell.toml"), "{stdout}");
    assert!(stdout.contains(&format!("{}/{}", names[1], names[0])), "{stdout}");
    assert!(
        stdout.contains("camera Mr/s") && stdout.contains("render Mr/s"),
        "{stdout}"
    );
    assert!(stdout.contains("(=)"), "{stdout}");
    assert!(
        stdout.contains(&format!("written: {}", json_path.display())),
        "{stdout}"
    );
}

#[test]
fn bad_bench_input_exits_2_before_running() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&[&str], &str); 4] = [
        (&["bench", "scenes/test/missing.toml", "--rays", "10"], "missing.toml"),
        (&["bench", "scenes/test/shadow.toml", "--rays", "0"], "--rays"),
        (
            &["bench", "scenes/test/shadow.toml", "--rays", "10", "--width", "0"],
            "full render",
        ),
        (&["bench", "scenes/test/shadow.toml", "--repeats", "0"], "--repeats"),
    ];
    for (args, expected) in cases {
        let out = command(&[]).args(args).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
    }
    // An unwritable JSON path is reported before any measurement.
    let json = dir.path().join("no/such/dir/out.json");
    let out = command(&[])
        .args(["bench", "scenes/test/shadow.toml", "--rays", "10", "--json"])
        .arg(&json)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(!stderr.contains("bench: "), "nothing ran: {stderr}");
    assert!(!Path::new(&json).exists());
}
