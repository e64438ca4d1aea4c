//! Interrupt and resume end to end through the `caustic` binary: SIGINT
//! stops a render with a valid partial image and a checkpoint, `--resume`
//! finishes it bit-identical to an uninterrupted render, mismatched
//! resumes and unwritable outputs are refused before rendering (exit 2).

mod common;

use common::cli::{caustic, command, stderr, stdout};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const SCENE: &str = "scenes/test/caustic.toml";

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The settings of the interrupted render: long enough (256 spp, about 3 s on one core of the test build) that the
/// signal, sent right after the first checkpoint, lands well before the end.
const SETTINGS: [&str; 10] = [
    "--width",
    "64",
    "--height",
    "48",
    "--spp",
    "256",
    "--photons",
    "20000",
    "--accel",
    "kdtree",
];

/// Linear RGB of an EXR written by `caustic render --exr`, as raw f32 bits.
fn exr_bits(path: &Path) -> (usize, Vec<[u32; 3]>) {
    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        path,
        |res: Vec2<usize>, _| (res.width(), vec![[0u32; 3]; res.area()]),
        |(w, px): &mut (usize, Vec<[u32; 3]>), pos: Vec2<usize>, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = [r.to_bits(), g.to_bits(), b.to_bits()];
        },
    )
    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    image.layer_data.channel_data.pixels
}

fn leftovers(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".caustic"))
        .collect()
}

#[cfg(unix)]
#[test]
fn sigint_writes_partial_image_and_checkpoint_and_resume_is_bit_identical() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| -> PathBuf { dir.path().join(name) };
    let (part_png, part_exr, ckpt) = (p("part.png"), p("part.exr"), p("render.ckpt.exr"));
    let mut args = vec!["render", SCENE, "--quiet", "--threads", "2"];
    args.extend(SETTINGS);
    args.extend([
        "-o",
        s(&part_png),
        "--exr",
        s(&part_exr),
        "--checkpoint",
        s(&ckpt),
        "--checkpoint-every",
        "0.05",
    ]);
    let child = command(&args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Wait for a checkpoint showing the first pass done (every pixel has
    // samples), so the partial image must cover the whole frame.
    let start = Instant::now();
    loop {
        assert!(start.elapsed() < Duration::from_secs(300), "no first pass after 300 s");
        std::thread::sleep(Duration::from_millis(10));
        // Renamed into place atomically: a read sees one whole checkpoint.
        if let Ok(c) = caustic::film::read_checkpoint(&ckpt) {
            if c.accumulation.taken_range().0 > 0 {
                break;
            }
        }
    }
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let out = child.wait_with_output().unwrap();
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(130), "stderr: {err}");
    assert!(err.contains("interrupted by SIGINT"), "{err}");
    assert!(err.contains("samples done"), "{err}");
    assert!(err.contains("--resume"), "{err}");
    assert!(stdout(&out).contains("written:"), "{}", stdout(&out));
    // The partial outputs are whole, valid images; no temporary file is left.
    let png = image::open(&part_png).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), (64, 48));
    assert_eq!(exr_bits(&part_exr).0, 64);
    assert!(leftovers(dir.path()).is_empty(), "{:?}", leftovers(dir.path()));
    let partial = caustic::film::read_checkpoint(&ckpt).unwrap();
    let done = partial.accumulation.samples_taken();
    assert!(done > 0 && done < 64 * 48 * 256, "{done} samples in the checkpoint");
    // The partial image covers the whole frame (passes, not tiles).
    assert!(partial.accumulation.taken_range().0 >= 4);

    // Resume with nothing but the outputs: the settings come from the
    // checkpoint. A different thread count does not matter.
    let resumed = p("resumed.exr");
    let out = caustic(&[
        "render",
        SCENE,
        "--quiet",
        "--threads",
        "1",
        "--resume",
        s(&ckpt),
        "--exr",
        s(&resumed),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let after = caustic::film::read_checkpoint(&ckpt).unwrap();
    assert!(
        after.accumulation.is_complete(256),
        "the resume keeps saving to the checkpoint"
    );

    let reference = p("reference.exr");
    let mut args = vec!["render", SCENE, "--quiet", "--threads", "2"];
    args.extend(SETTINGS);
    args.extend(["--exr", s(&reference)]);
    let out = caustic(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        exr_bits(&resumed) == exr_bits(&reference),
        "the resumed image differs from the uninterrupted render"
    );
    assert!(
        exr_bits(&part_exr) != exr_bits(&reference),
        "the partial image has fewer samples"
    );
}

#[test]
fn resuming_a_different_render_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let ckpt = dir.path().join("c.exr");
    // A small complete render with a checkpoint.
    let out = caustic(&[
        "render",
        "scenes/test/shadow.toml",
        "--quiet",
        "--width",
        "16",
        "--height",
        "12",
        "--spp",
        "2",
        "--accel",
        "kdtree",
        "--exr",
        s(&dir.path().join("a.exr")),
        "--checkpoint",
        s(&ckpt),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stdout(&out).contains("(checkpoint)"));
    let again = dir.path().join("b.exr");
    let resume = |extra: &[&str], scene: &str| {
        let mut args = vec!["render", scene, "--quiet", "--resume", s(&ckpt), "--exr", s(&again)];
        args.extend(extra);
        caustic(&args)
    };
    // Resuming a finished render just writes it again.
    let out = resume(&[], "scenes/test/shadow.toml");
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(exr_bits(&again) == exr_bits(&dir.path().join("a.exr")));
    // Other settings, another scene: exit 2, saying what differs.
    for (extra, scene, needle) in [
        (
            &["--spp", "4"][..],
            "scenes/test/shadow.toml",
            "spp 2 in the checkpoint, 4 now",
        ),
        (&["--seed", "99"][..], "scenes/test/shadow.toml", "seed"),
        (
            &["--accel", "brute"][..],
            "scenes/test/shadow.toml",
            "accelerator kdtree in the checkpoint",
        ),
        (
            &[][..],
            "scenes/test/spheres.toml",
            "the scene file, a mesh or another setting changed",
        ),
    ] {
        let out = resume(extra, scene);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{extra:?} {scene}: {err}");
        assert!(err.contains("different render") && err.contains(needle), "{err}");
        assert!(stdout(&out).is_empty());
    }
    // Not a checkpoint at all.
    let out = resume(&[], "scenes/test/shadow.toml");
    assert!(out.status.success());
    let out = caustic(&["render", "scenes/test/shadow.toml", "--resume", s(&again)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("not a valid caustic checkpoint"),
        "{}",
        stderr(&out)
    );
    // A checkpoint of the first fingerprint format (no
    // `caustic.fingerprint.format`): refused, saying why and what to do.
    write_as_fingerprint_format_1(&ckpt);
    let out = resume(&[], "scenes/test/shadow.toml");
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("written by an older caustic (fingerprint format 1; this one writes format 2")
            && err.contains("render again without it"),
        "{err}"
    );
}

/// Rewrites a checkpoint as caustic wrote it before the fingerprint format
/// was recorded (format 1: no `caustic.fingerprint.format` attribute).
fn write_as_fingerprint_format_1(path: &Path) {
    use exr::prelude::*;
    let mut image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .unwrap();
    let removed = image
        .layer_data
        .attributes
        .other
        .remove(&Text::from("caustic.fingerprint.format"));
    assert!(removed.is_some());
    image.write().to_file(path).unwrap();
}

#[test]
fn unwritable_outputs_are_reported_before_rendering() {
    let dir = tempfile::tempdir().unwrap();
    let ok_png = dir.path().join("ok.png");
    let a_dir = dir.path().join("sub");
    std::fs::create_dir(&a_dir).unwrap();
    // 4096 spp at full size would take many minutes: the refusal must come first.
    let base = ["render", "scenes/test/shadow.toml", "--quiet", "--spp", "4096"];
    for (flag, path) in [
        ("-o", "/nonexistent-dir/x.png"),
        ("--exr", "/nonexistent-dir/x.exr"),
        ("--checkpoint", "/nonexistent-dir/c.exr"),
        ("--checkpoint", s(&a_dir)),
    ] {
        let mut args = base.to_vec();
        if flag != "-o" {
            args.extend(["-o", s(&ok_png)]);
        }
        args.extend([flag, path]);
        let out = caustic(&args);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{flag} {path}: {err}");
        assert!(err.contains(path) && err.contains("cannot write output"), "{err}");
        assert!(stdout(&out).is_empty(), "nothing was rendered");
        assert!(!ok_png.exists());
    }
    let out = caustic(&["render", "scenes/test/shadow.toml", "--checkpoint-every", "0"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("--checkpoint-every"));
}
