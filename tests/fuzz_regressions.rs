//! Inputs found by the fuzzers (`scripts/fuzz.sh`), kept in
//! `tests/data/fuzz/<target>/`: each went through the same entry point as its
//! fuzz target and once made it panic, hang or allocate too much. Every one
//! must now give a clean `Ok` or `Err`, within the fuzz targets' memory
//! limits. Names ending in `.ok` must load; every other input must be
//! refused.

use caustic::io::{parse_mesh_bytes, LoadLimits, MeshFormat};
use caustic::memory::MemoryBudget;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The `mitsuba` target's setting (the folder of fixed files an input is
/// written into), the fuzz crate's own file.
#[path = "../fuzz/src/mitsuba.rs"]
mod fuzz_mitsuba;

/// The limits of the fuzz targets (`caustic_fuzz::fuzz_limits`).
fn fuzz_limits() -> LoadLimits {
    LoadLimits {
        max_input_bytes: 64 << 20,
        memory: Some(MemoryBudget {
            bytes: 256 << 20,
            source: "fuzz",
        }),
        ..LoadLimits::default()
    }
}

fn inputs(target: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/fuzz")
        .join(target);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    files
}

/// Longest an input may take: a bound on a hang (the fuzzers' timeouts
/// were inputs that looped without end), generous enough that a loaded
/// machine never reaches it. The kept inputs' memory is bounded by
/// [`fuzz_limits`], and their speed is no part of this test.
const HANG: Duration = Duration::from_secs(60);

/// Checks the outcome's kind against the name, and that it came back.
#[track_caller]
fn check<T, E: std::fmt::Display>(path: &Path, started: Instant, result: Result<T, E>) {
    let elapsed = started.elapsed();
    assert!(elapsed < HANG, "{}: took {elapsed:?}", path.display());
    let must_load = path.extension().is_some_and(|e| e == "ok");
    match result {
        Ok(_) => assert!(must_load, "{}: accepted", path.display()),
        Err(e) => {
            assert!(!must_load, "{}: refused: {e}", path.display());
            let msg = e.to_string();
            assert!(
                !msg.is_empty() && !msg.contains('\n'),
                "{}: message `{msg}`",
                path.display()
            );
        }
    }
}

fn mesh_target(target: &str, format: MeshFormat) {
    let files = inputs(target);
    assert!(!files.is_empty(), "no kept inputs for {target}");
    for path in files {
        let bytes = std::fs::read(&path).unwrap();
        let started = Instant::now();
        let result = parse_mesh_bytes(&bytes, format, &format!("fuzz.{target}"), &fuzz_limits());
        check(&path, started, result);
    }
}

#[test]
fn ply_inputs() {
    mesh_target("ply", MeshFormat::Ply);
}

#[test]
fn off_inputs() {
    mesh_target("off", MeshFormat::Off);
}

#[test]
fn obj_inputs() {
    mesh_target("obj", MeshFormat::Obj);
}

#[test]
fn scene_inputs() {
    let files = inputs("scene");
    assert!(!files.is_empty(), "no kept inputs for scene");
    let dir = tempfile::tempdir().unwrap();
    for path in files {
        let bytes = std::fs::read(&path).unwrap();
        let Ok(text) = std::str::from_utf8(&bytes) else {
            panic!("{}: the scene target only sees UTF-8", path.display());
        };
        let started = Instant::now();
        let result = caustic::scene::parse_scene(text, &dir.path().join("fuzz.toml"));
        check(&path, started, result);
    }
}

#[test]
fn serialized_inputs() {
    let files = inputs("serialized");
    assert!(!files.is_empty(), "no kept inputs for serialized");
    for path in files {
        let bytes = std::fs::read(&path).unwrap();
        let started = Instant::now();
        // As the target does: shape 0, then shape 1. The outcome of shape 0
        // is what the name tells; shape 1 must only come back cleanly.
        let result =
            caustic::io::serialized::parse_serialized(&bytes, 0, "fuzz.serialized", &fuzz_limits()).map_err(|(_, m)| m);
        let second = caustic::io::serialized::parse_serialized(&bytes, 1, "fuzz.serialized", &fuzz_limits());
        if let Err((_, m)) = second {
            assert!(!m.is_empty() && !m.contains('\n'), "{}: shape 1: `{m}`", path.display());
        }
        check(&path, started, result);
    }
}

#[test]
fn mitsuba_inputs() {
    let files = inputs("mitsuba");
    assert!(!files.is_empty(), "no kept inputs for mitsuba");
    let setting = fuzz_mitsuba::Setting::new();
    for path in files {
        let bytes = std::fs::read(&path).unwrap();
        assert!(
            !fuzz_mitsuba::skipped(&bytes),
            "{}: the target skips it",
            path.display()
        );
        let started = Instant::now();
        let result = fuzz_mitsuba::load(&setting, &bytes);
        check(&path, started, result);
    }
}

/// The seeds of the `mitsuba` target load: a seed the front end refuses
/// early would leave the plugins it was written for unfuzzed.
#[test]
fn mitsuba_seeds_load() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus/mitsuba");
    let setting = fuzz_mitsuba::Setting::new();
    let mut seeds = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let bytes = std::fs::read(&path).unwrap();
        if let Err(e) = fuzz_mitsuba::load(&setting, &bytes) {
            panic!("{}: {e}", path.display());
        }
        seeds += 1;
    }
    assert!(seeds >= 10, "{seeds} seeds");
}

#[test]
fn gltf_inputs() {
    let files = inputs("gltf");
    assert!(!files.is_empty(), "no kept inputs for gltf");
    let dir = tempfile::tempdir().unwrap();
    for path in files {
        let bytes = std::fs::read(&path).unwrap();
        // As the target does: a .glb when the bytes say so, else a .gltf.
        let name = if bytes.starts_with(b"glTF") {
            "model.glb"
        } else {
            "model.gltf"
        };
        let model = dir.path().join(name);
        std::fs::write(&model, &bytes).unwrap();
        let started = Instant::now();
        let result = caustic::scene::gltf::load_gltf_scene(&model, &Default::default());
        check(&path, started, result);
    }
}
