//! What the fuzz targets share: the mesh loaders' call under fixed limits,
//! and the Mitsuba front end's setting ([`mitsuba`]).

pub mod mitsuba;

use caustic::io::{parse_mesh_bytes, LoadLimits, MeshFormat};
use caustic::memory::MemoryBudget;

/// The mesh targets' limits. A fixed memory budget (not MemAvailable) keeps
/// runs reproducible, and a 64 MiB input cap bounds a gzip bomb's
/// decompression time.
pub fn fuzz_limits() -> LoadLimits {
    LoadLimits {
        max_input_bytes: 64 << 20,
        memory: Some(MemoryBudget {
            bytes: 256 << 20,
            source: "fuzz",
        }),
        ..LoadLimits::default()
    }
}

/// Parses `data` as a mesh of `format` (gzip included: inputs starting with
/// the gzip magic bytes are decompressed first). Any panic, hang or
/// oversized allocation is a bug; `Err` is the expected outcome for garbage.
pub fn fuzz_mesh(data: &[u8], format: MeshFormat, name: &str) {
    let _ = parse_mesh_bytes(data, format, name, &fuzz_limits());
}
