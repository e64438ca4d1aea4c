//! Fuzzes the ply mesh loader (see `caustic_fuzz::fuzz_mesh`).
#![no_main]

use caustic::io::MeshFormat;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| caustic_fuzz::fuzz_mesh(data, MeshFormat::Ply, "fuzz.ply"));
