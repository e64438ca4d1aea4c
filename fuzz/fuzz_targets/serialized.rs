//! Fuzzes Mitsuba's `.serialized` mesh reader (zlib-compressed shapes) on
//! arbitrary bytes, reading shapes 0 and 1, under the mesh targets' limits.
//! Any `Err` is fine; a panic, a hang or an oversized allocation is a bug.
#![no_main]

use caustic::io::serialized::parse_serialized;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let limits = caustic_fuzz::fuzz_limits();
    for shape in 0..2 {
        let _ = parse_serialized(data, shape, "fuzz.serialized", &limits);
    }
});
