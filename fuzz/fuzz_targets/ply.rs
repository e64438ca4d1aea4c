//! Fuzzes the ply mesh loader (gzip included: inputs starting with the gzip
//! magic bytes are decompressed first). Any panic, hang or oversized
//! allocation is a bug; `Err` is the expected outcome for garbage.
#![no_main]

use caustic::analysis::memory::MemoryBudget;
use caustic::io::{parse_mesh_bytes, LoadLimits, MeshFormat};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // A fixed memory budget (not MemAvailable) keeps runs reproducible, and
    // a 64 MiB input cap bounds a gzip bomb's decompression time.
    let limits = LoadLimits {
        max_input_bytes: 64 << 20,
        memory: Some(MemoryBudget {
            bytes: 256 << 20,
            source: "fuzz",
        }),
        ..LoadLimits::default()
    };
    let _ = parse_mesh_bytes(data, MeshFormat::Ply, "fuzz.ply", &limits);
});
