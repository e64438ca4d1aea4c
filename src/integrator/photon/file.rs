//! Photon files (`caustic photons SCENE -o map.bin`): the traced photons
//! of a scene, saved once and loaded by every shard of a render
//! (`--photon-map map.bin`) instead of tracing them again.
//!
//! What is saved is the output of the trace, before the k-d trees are
//! built: the stored photons in emission order and the candidate
//! irradiance sites. Loading them and building the map gives the very map a
//! render would have traced (the build is deterministic), so images are
//! bit-identical either way. Little-endian binary:
//!
//! | bytes | content |
//! | --- | --- |
//! | 16 | magic `caustic-photon2\n` |
//! | 64 | the photon fingerprint (hex SHA-256 of the scene and every setting the photons depend on) |
//! | 8 × 4 | photons emitted, rays traced, photons stored `n`, sites `m` |
//! | 12 `n` | positions (3 × f32) |
//! | 8 `n` | records (RGBE power, 2 × u16 octahedral direction) |
//! | 24 `m` | sites (position and normal, 3 × f32 each) |
//!
//! The file is written atomically; a read checks the magic, the counts
//! against the file's length (so a hostile header cannot make it allocate
//! more than the file holds) and that every value is finite.

use super::{IrradianceSite, PhotonRecord, TracedPhotons};
use crate::film::output::{write_atomically, OutputError};
use crate::math::Vec3A;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;
use thiserror::Error;

/// The first bytes of a photon file (format version 2: the layout of
/// version 1, with a fingerprint of `job::fingerprint`'s format 2).
pub const PHOTON_FILE_MAGIC: &[u8; 16] = b"caustic-photon2\n";

/// The first bytes of a version 1 file, whose fingerprint (format 1) this
/// caustic no longer computes: refused with a message that says so.
const PHOTON_FILE_MAGIC_1: &[u8; 16] = b"caustic-photon1\n";

const HEADER_BYTES: u64 = 16 + 64 + 32;

/// A photon file could not be read.
#[derive(Debug, Error)]
pub enum PhotonFileError {
    /// Reading failed (missing file, permissions).
    #[error("{}: cannot read the photon file: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The file is not a valid photon file.
    #[error("{}: not a valid caustic photon file: {problem}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        problem: String,
    },
}

/// Writes `photons` (traced with sites) and their `fingerprint` to `path`
/// atomically.
pub fn write_photons(path: &Path, photons: &TracedPhotons, fingerprint: &str) -> Result<(), OutputError> {
    assert!(photons.has_sites, "a photon file holds the sites");
    assert_eq!(fingerprint.len(), 64, "a hex SHA-256");
    let io = |source| OutputError::Io {
        path: path.to_path_buf(),
        what: "writing",
        source,
    };
    write_atomically(path, |w| {
        w.write_all(PHOTON_FILE_MAGIC).map_err(io)?;
        w.write_all(fingerprint.as_bytes()).map_err(io)?;
        for n in [
            photons.emitted,
            photons.rays,
            photons.positions.len() as u64,
            photons.sites.len() as u64,
        ] {
            w.write_all(&n.to_le_bytes()).map_err(io)?;
        }
        // `w` buffers (1 MiB): small writes cost a copy each.
        for p in &photons.positions {
            for c in p {
                w.write_all(&c.to_le_bytes()).map_err(io)?;
            }
        }
        for r in &photons.records {
            w.write_all(&r.rgbe).map_err(io)?;
            w.write_all(&r.dir[0].to_le_bytes()).map_err(io)?;
            w.write_all(&r.dir[1].to_le_bytes()).map_err(io)?;
        }
        for s in &photons.sites {
            for c in s.position.to_array().into_iter().chain(s.normal.to_array()) {
                w.write_all(&c.to_le_bytes()).map_err(io)?;
            }
        }
        Ok(())
    })
}

/// Reads a photon file: the traced photons and the fingerprint recorded.
pub fn read_photons(path: &Path) -> Result<(TracedPhotons, String), PhotonFileError> {
    let io = |source| PhotonFileError::Io {
        path: path.to_path_buf(),
        source,
    };
    let invalid = |problem: String| PhotonFileError::Invalid {
        path: path.to_path_buf(),
        problem,
    };
    let file = std::fs::File::open(path).map_err(io)?;
    let length = file.metadata().map_err(io)?.len();
    let mut r = std::io::BufReader::with_capacity(1 << 20, file);
    let mut header = [0u8; HEADER_BYTES as usize];
    if length < HEADER_BYTES {
        return Err(invalid(format!("{length} bytes, shorter than the header")));
    }
    r.read_exact(&mut header).map_err(io)?;
    if &header[..16] == PHOTON_FILE_MAGIC_1 {
        return Err(invalid(
            "written by an older caustic (photon file format 1, fingerprint format 1; this one writes format 2 and \
             cannot check the older fingerprint against the scene): trace the photons again with caustic photons"
                .to_string(),
        ));
    }
    if &header[..16] != PHOTON_FILE_MAGIC {
        return Err(invalid("it does not start with caustic-photon2".to_string()));
    }
    let fingerprint = std::str::from_utf8(&header[16..80])
        .ok()
        .filter(|f| f.bytes().all(|b| b.is_ascii_hexdigit()))
        .ok_or_else(|| invalid("the fingerprint is not hexadecimal".to_string()))?
        .to_string();
    let number = |i: usize| u64::from_le_bytes(header[80 + 8 * i..88 + 8 * i].try_into().expect("8 bytes"));
    let (emitted, rays, stored, sites) = (number(0), number(1), number(2), number(3));
    if let Err(e) = crate::limits::check_photon_count(emitted) {
        return Err(invalid(format!("recorded photon count: {e}")));
    }
    if stored > emitted || sites > stored {
        return Err(invalid(format!(
            "{stored} photons stored and {sites} sites of {emitted} emitted"
        )));
    }
    let expected = HEADER_BYTES + 20 * stored + 24 * sites;
    if length != expected {
        return Err(invalid(format!(
            "{length} bytes, but the header's counts need {expected}"
        )));
    }
    let read_f32s = |r: &mut dyn Read, n: usize, out: &mut Vec<f32>| -> Result<(), PhotonFileError> {
        let mut block = vec![0u8; 1 << 20];
        let mut left = n * 4;
        while left > 0 {
            let take = left.min(block.len());
            r.read_exact(&mut block[..take]).map_err(io)?;
            out.extend(
                block[..take]
                    .chunks_exact(4)
                    .map(|b| f32::from_le_bytes(b.try_into().expect("4"))),
            );
            left -= take;
        }
        Ok(())
    };
    let (stored, sites) = (stored as usize, sites as usize);
    let mut floats = Vec::with_capacity(3 * stored);
    read_f32s(&mut r, 3 * stored, &mut floats)?;
    if floats.iter().any(|f| !f.is_finite()) {
        return Err(invalid("a photon position is not finite".to_string()));
    }
    let positions: Vec<[f32; 3]> = floats.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    drop(floats);
    let mut records = Vec::with_capacity(stored);
    let mut block = vec![0u8; 8 << 17];
    let mut left = stored;
    while left > 0 {
        let take = left.min(block.len() / 8);
        r.read_exact(&mut block[..take * 8]).map_err(io)?;
        records.extend(block[..take * 8].chunks_exact(8).map(|b| PhotonRecord {
            rgbe: [b[0], b[1], b[2], b[3]],
            dir: [u16::from_le_bytes([b[4], b[5]]), u16::from_le_bytes([b[6], b[7]])],
        }));
        left -= take;
    }
    let mut floats = Vec::with_capacity(6 * sites);
    read_f32s(&mut r, 6 * sites, &mut floats)?;
    if floats.iter().any(|f| !f.is_finite()) {
        return Err(invalid("a site is not finite".to_string()));
    }
    let sites = floats
        .chunks_exact(6)
        .map(|c| IrradianceSite {
            position: Vec3A::new(c[0], c[1], c[2]),
            normal: Vec3A::new(c[3], c[4], c[5]),
        })
        .collect();
    let photons = TracedPhotons {
        emitted,
        positions,
        records,
        volume_positions: Vec::new(),
        volume_records: Vec::new(),
        sites,
        has_sites: true,
        rays,
        trace_time: Duration::ZERO,
    };
    Ok((photons, fingerprint))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> TracedPhotons {
        TracedPhotons {
            emitted: 10,
            positions: vec![[1.0, -2.5, 3.25], [0.1, 0.2, 0.3]],
            records: vec![
                PhotonRecord {
                    rgbe: [1, 2, 3, 4],
                    dir: [5, 65535],
                },
                PhotonRecord {
                    rgbe: [9, 8, 7, 6],
                    dir: [0, 1],
                },
            ],
            sites: vec![IrradianceSite {
                position: Vec3A::new(1.0, -2.5, 3.25),
                normal: Vec3A::new(0.0, 1.0, 0.0),
            }],
            volume_positions: Vec::new(),
            volume_records: Vec::new(),
            has_sites: true,
            rays: 33,
            trace_time: Duration::ZERO,
        }
    }

    #[test]
    fn round_trip_is_exact_and_bad_files_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("map.bin");
        let fp = "0123456789abcdef".repeat(4);
        write_photons(&path, &sample(), &fp).unwrap();
        let (back, f) = read_photons(&path).unwrap();
        assert_eq!((back, f), (sample(), fp));
        let bytes = std::fs::read(&path).unwrap();
        let bad = dir.path().join("bad.bin");
        std::fs::write(&bad, &bytes[..bytes.len() - 1]).unwrap();
        let e = read_photons(&bad).unwrap_err().to_string();
        assert!(e.contains("bad.bin") && e.contains("need"), "{e}");
        std::fs::write(&bad, b"caustic-photon0\nxx").unwrap();
        assert!(read_photons(&bad).unwrap_err().to_string().contains("shorter"));
        let mut wrong = bytes.clone();
        wrong[0] = b'x';
        std::fs::write(&bad, &wrong).unwrap();
        assert!(read_photons(&bad).unwrap_err().to_string().contains("does not start"));
        let mut huge = bytes.clone();
        huge[96..104].copy_from_slice(&u64::MAX.to_le_bytes());
        std::fs::write(&bad, &huge).unwrap();
        assert!(read_photons(&bad).unwrap_err().to_string().contains("stored"));
        assert!(read_photons(&dir.path().join("none.bin"))
            .unwrap_err()
            .to_string()
            .contains("none.bin"));
    }
}
