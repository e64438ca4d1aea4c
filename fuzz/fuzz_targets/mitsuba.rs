//! Fuzzes the Mitsuba XML front end (`load_mitsuba_scene`): the input is
//! written as `scene.xml` beside fixed include, mesh and texture files (see
//! `caustic_fuzz::mitsuba`), so that includes, `<ref>`s, meshes and
//! textures resolve. Any `Err` is fine; a panic, a hang or an oversized
//! allocation is a bug.
#![no_main]

use caustic_fuzz::mitsuba::{load, skipped, Setting};
use libfuzzer_sys::fuzz_target;
use std::sync::OnceLock;

static SETTING: OnceLock<Setting> = OnceLock::new();

fuzz_target!(|data: &[u8]| {
    if skipped(data) {
        return;
    }
    let setting = SETTING.get_or_init(Setting::new);
    let _ = load(setting, data);
});
