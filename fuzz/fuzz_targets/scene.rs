//! Fuzzes the scene parser and validator on arbitrary UTF-8 text. The scene
//! "lives" in an empty temporary directory, so relative mesh paths name
//! files that do not exist and exercise the error path. Any panic, hang or
//! oversized allocation is a bug.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::sync::OnceLock;

static DIR: OnceLock<tempfile::TempDir> = OnceLock::new();

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    // `asset:NAME` may fetch a model over the network (the npm client):
    // not something a fuzzer should trigger.
    if text.contains("asset:") {
        return;
    }
    let dir = DIR.get_or_init(|| tempfile::tempdir().expect("temporary directory"));
    let _ = caustic::scene::parse_scene(text, &dir.path().join("fuzz.toml"));
});
