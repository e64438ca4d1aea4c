//! `caustic converge` end to end: a reference rendered at many samples and
//! photons (seed 99), convergence runs against it (seed 3), CSV and plot.

mod common;

use common::cli::{caustic, describe};
use std::path::{Path, PathBuf};
use std::process::Output;
use std::sync::OnceLock;

const SCENE: &str = "scenes/test/caustic.toml";
const W: &str = "48";
const H: &str = "36";

/// `caustic converge` on the test scene against the shared reference, at
/// the reference's size, with `extra` arguments.
fn converge(extra: &[&str]) -> Output {
    let mut args = vec![
        "converge",
        SCENE,
        "--reference",
        reference().to_str().unwrap(),
        "--width",
        W,
        "--height",
        H,
    ];
    args.extend_from_slice(extra);
    caustic(&args)
}

/// The reference, rendered once for the whole file: 256 spp, 2M photons, seed 99.
fn reference() -> &'static Path {
    static REF: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    let (_, path) = REF.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("ref.exr");
        let o = caustic(&[
            "render",
            SCENE,
            "--width",
            W,
            "--height",
            H,
            "--spp",
            "256",
            "--photons",
            "2000000",
            "--seed",
            "99",
            "--accel",
            "kdtree",
            "--quiet",
            "--exr",
            path.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", describe(&o));
        (dir, path)
    });
    path
}

struct Row {
    curve: String,
    budget: String,
    spp: u32,
    photons: u64,
    seconds: f64,
    rmse: f64,
    relmse: f64,
    mae: f64,
    within: bool,
}

fn parse_csv(path: &Path) -> Vec<Row> {
    let csv = std::fs::read_to_string(path).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "curve,budget,spp,photons,seconds,rmse,relmse,mae,build_seconds,within_budget,photon_seconds"
    );
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f.len(), 11, "{l}");
            for v in &f[4..9] {
                let x: f64 = v.parse().unwrap();
                assert!(x.is_finite() && x >= 0.0, "{l}");
            }
            Row {
                curve: f[0].into(),
                budget: f[1].into(),
                spp: f[2].parse().unwrap(),
                photons: f[3].parse().unwrap(),
                seconds: f[4].parse().unwrap(),
                rmse: f[5].parse().unwrap(),
                relmse: f[6].parse().unwrap(),
                mae: f[7].parse().unwrap(),
                within: f[9].parse().unwrap(),
            }
        })
        .collect()
}

#[test]
fn error_falls_with_budget_and_csv_and_plot_are_written() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("c.csv");
    let png = dir.path().join("c.png");
    let o = converge(&[
        "--seed",
        "3",
        "--budgets",
        "1:5000,4:40000,16:160000",
        "--accel",
        "kdtree,brute",
        "--gather",
        "direct,precomputed",
        "--csv",
        csv.to_str().unwrap(),
        "--plot",
        png.to_str().unwrap(),
        "--plot-size",
        "700x300",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", describe(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("relMSE ε = 1e-2"), "{stdout}");

    let rows = parse_csv(&csv);
    let curves = [
        "kdtree/direct",
        "kdtree/precomputed",
        "brute/direct",
        "brute/precomputed",
    ];
    assert_eq!(rows.len(), curves.len() * 3);
    for (c, chunk) in curves.iter().zip(rows.chunks(3)) {
        assert!(chunk.iter().all(|r| r.curve == *c && r.within));
        assert_eq!(
            chunk
                .iter()
                .map(|r| (r.budget.as_str(), r.spp, r.photons))
                .collect::<Vec<_>>(),
            [("1:5000", 1, 5000), ("4:40000", 4, 40000), ("16:160000", 16, 160000)]
        );
        let (lo, hi) = (&chunk[0], &chunk[2]);
        // MAE, not RMSE or relMSE: those are dominated by a few pixels of
        // the glass ball's small, very bright highlight, where one sample of
        // 16 reaching the light's reflection (a 0.15 chance per render) sets
        // the pixel to 3.9 against 0.58 and moves RMSE 4× (measured, seed 3).
        // MAE falls 0.24–0.69× here (measured, seeds 3–7; 0.69 at seed 3).
        assert!(hi.mae < 0.8 * lo.mae, "{c}: MAE {} → {}", lo.mae, hi.mae);
        assert!(hi.rmse.is_finite() && hi.relmse.is_finite());
        assert!(lo.seconds > 0.0);
    }
    // The accelerators give the same images: brute force and the KD-tree agree.
    for i in 0..6 {
        let (k, b) = (&rows[i], &rows[i + 6]);
        assert!((k.rmse - b.rmse).abs() <= 1e-3 * k.rmse, "{} vs {}", k.rmse, b.rmse);
    }

    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let img = image::load_from_memory(&bytes).unwrap();
    assert_eq!((img.width(), img.height()), (700, 300));
}

#[test]
fn time_budgets_use_the_doubling_search() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("t.csv");
    let o = converge(&[
        "--budgets",
        "0.000001s,0.5s",
        "--accel",
        "kdtree",
        "--photons-per-spp",
        "5000",
        "--threads",
        "1",
        "--csv",
        csv.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", describe(&o));
    let rows = parse_csv(&csv);
    assert_eq!(rows.len(), 2);
    // Nothing fits in a microsecond: the 1-spp render is reported, flagged.
    assert_eq!((rows[0].spp, rows[0].photons, rows[0].within), (1, 5000, false));
    // The other budget takes a power of two within it, photons scaled.
    let r = &rows[1];
    assert!(r.spp.is_power_of_two());
    assert_eq!(r.photons, 5000 * r.spp as u64);
    assert!(!r.within || r.seconds <= 0.5, "{}", r.seconds);
    assert!(r.spp >= rows[0].spp);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("search ≤0.5s"), "{stderr}");
}

#[test]
fn bad_inputs_exit_2_with_a_clear_message() {
    let dir = tempfile::tempdir().unwrap();
    let r = reference().to_str().unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        // Resolution mismatch: the scene's own 160×120 against the 48×36 reference.
        (
            vec!["converge", SCENE, "--reference", r],
            "the reference is 48×36 but the render is 160×120",
        ),
        (
            vec!["converge", SCENE, "--reference", r, "--width", "40", "--height", H],
            "48×36 but the render is 40×36",
        ),
        (
            vec![
                "converge",
                SCENE,
                "--reference",
                "no/such.exr",
                "--width",
                W,
                "--height",
                H,
            ],
            "no/such.exr: cannot read the reference EXR",
        ),
        (
            vec![
                "converge",
                SCENE,
                "--reference",
                r,
                "--width",
                W,
                "--height",
                H,
                "--budgets",
                "1,x",
            ],
            "budget 2 (\"x\")",
        ),
        (
            vec![
                "converge",
                SCENE,
                "--reference",
                r,
                "--width",
                W,
                "--height",
                H,
                "--plot-size",
                "5x5",
            ],
            "--plot-size",
        ),
        (
            vec![
                "converge",
                SCENE,
                "--reference",
                r,
                "--width",
                W,
                "--height",
                H,
                "--epsilon",
                "0",
            ],
            "--epsilon 0",
        ),
        (
            vec![
                "converge",
                SCENE,
                "--reference",
                r,
                "--width",
                W,
                "--height",
                H,
                "--accel",
                "kdtree,kdtree",
            ],
            "kdtree is given twice",
        ),
    ];
    let png = dir.path().join("x.png");
    std::fs::write(&png, b"not an exr").unwrap();
    let junk = vec![
        "converge",
        SCENE,
        "--reference",
        png.to_str().unwrap(),
        "--width",
        W,
        "--height",
        H,
    ];
    for (args, want) in cases
        .into_iter()
        .chain([(junk, "x.png: cannot read the reference EXR")])
    {
        let o = caustic(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}\n{}", describe(&o));
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(stderr.contains(want), "{args:?}: want {want:?}\n{stderr}");
    }
}

#[test]
fn sample_budgets_without_a_photon_count_use_the_given_count_not_the_warm_ups() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("p.csv");
    let o = converge(&[
        "--budgets",
        "1",
        "--accel",
        "kdtree",
        "--photons",
        "150000",
        "--threads",
        "1",
        "--csv",
        csv.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", describe(&o));
    let rows = parse_csv(&csv);
    // The untimed warm-up emits at most 100,000 photons; the measured
    // render emits what was asked for.
    assert_eq!(rows[0].photons, 150_000);
}
