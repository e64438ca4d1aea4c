//! Checkpoint files: the accumulation of a render in progress, saved so that
//! `caustic render --resume FILE` continues it bit for bit.
//!
//! One OpenEXR file (single part, scan lines, ZIP16: lossless) with the
//! channels
//!
//! | channel | type | meaning |
//! | --- | --- | --- |
//! | `R`, `G`, `B` | f32 | the current image (mean of the kept samples): a preview any EXR viewer shows |
//! | `sum.R`, `sum.G`, `sum.B` | f32 | the running sums of the kept samples (what a resume continues from) |
//! | `samples.taken` | u32 | samples evaluated per pixel (the next sample index) |
//! | `samples.kept` | u32 | of which finite (NaN and infinite samples are dropped) |
//! | `odd.R`, `odd.G`, `odd.B` | f32 | the running sums of the kept samples of odd index (noise estimate) |
//! | `odd.kept` | u32 | kept samples of odd index |
//! | `converged` | u32 | 1 where adaptive sampling stopped the pixel |
//! | `albedo.R`, `albedo.G`, `albedo.B` | f32 | the running sums of the albedo AOV (first samples, see `Accumulation`) |
//! | `normal.X`, `normal.Y`, `normal.Z` | f32 | the running sums of the shading-normal AOV |
//!
//! and the header attributes `caustic.format` (= [`CHECKPOINT_FORMAT`]),
//! `caustic.width`, `caustic.height`, `caustic.spp`, `caustic.seed`,
//! `caustic.photons`, `caustic.accel`, `caustic.fingerprint` and
//! `caustic.fingerprint.format` (all text; the fingerprint is a SHA-256 of
//! the scene and every setting that changes the samples, see
//! `job::fingerprint`, and the format the version of its encoding, 1 when
//! absent), `caustic.tonemap` and
//! `caustic.exposure` (display settings, so that a merge writes the same
//! PNG), and in a **partial** (one or more shards of a split render, see
//! [`super::shard`]) `caustic.shard.mode` (`tiles` or `samples`),
//! `caustic.shard.count` and `caustic.shard.indices` (such as `2` or
//! `0-3,5`). In a tiles partial the pixels of other shards hold zeros; in
//! a samples partial `samples.taken` is the next sample index (the shard's
//! samples start at its range's first index) and the sums hold the shard's
//! samples only. The file is written atomically (temporary file, fsync,
//! rename), like the images. Files of the previous formats are still read:
//! `caustic-checkpoint-3` (no AOV channels: their sums read as zero, and a
//! render resumed from one traces its earlier samples' AOVs again) and
//! `caustic-checkpoint-2` (no display or shard attributes either).

use super::accum::Accumulation;
use super::output::{write_atomically, OutputError};
use super::shard::{ShardMode, ShardSet};
use super::tonemap::{OutputSettings, ToneMap};
use crate::math::Vec3;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Value of the `caustic.format` attribute; bumped when the layout changes.
pub const CHECKPOINT_FORMAT: &str = "caustic-checkpoint-4";

/// The previous format, still read: no AOV channels.
pub const CHECKPOINT_FORMAT_3: &str = "caustic-checkpoint-3";

/// The previous format, still read: the same channels, without the display
/// and shard attributes (its files are whole renders with default display
/// settings).
pub const CHECKPOINT_FORMAT_2: &str = "caustic-checkpoint-2";

/// What a checkpoint records besides the per-pixel state: what a resume
/// needs to continue the same render, and to refuse a different one.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckpointMeta {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Target samples per pixel.
    pub spp: u32,
    /// Seed of every random stream.
    pub seed: u64,
    /// Photons emitted by the (deterministic, re-run on resume) photon pass.
    pub photons: u64,
    /// Accelerator name (`embree`, `kdtree`, `brute`): hits may differ
    /// between backends in the last bits.
    pub accel: String,
    /// Fingerprint of the scene and the effective settings (hex SHA-256).
    pub fingerprint: String,
    /// The version of the fingerprint's encoding (`job::fingerprint`);
    /// 1 in files written before it was recorded.
    pub fingerprint_format: u32,
    /// Tone map and exposure of the render's PNG (display only, not in the
    /// fingerprint).
    pub output: OutputSettings,
    /// The shards a partial holds; `None` for a whole render's checkpoint.
    pub shard: Option<ShardSet>,
}

/// A checkpoint read back.
#[derive(Clone, Debug, PartialEq)]
pub struct Checkpoint {
    /// The recorded settings.
    pub meta: CheckpointMeta,
    /// The per-pixel state.
    pub accumulation: Accumulation,
    /// False for a file of format 3 or older, which holds no albedo and
    /// normal sums (the accumulation's are zero; a resume traces them again,
    /// `integrator::render::retrace_aovs`).
    pub has_aovs: bool,
}

/// A checkpoint could not be read.
#[derive(Debug, Error)]
pub enum CheckpointError {
    /// The EXR reader failed (missing file, not an EXR, truncated data).
    #[error("{}: cannot read the checkpoint: {cause}", path.display())]
    Exr {
        /// The file.
        path: PathBuf,
        /// The cause (in the message already, so not chained as a source).
        cause: exr::error::Error,
    },
    /// The file is an EXR but not a valid caustic checkpoint.
    #[error("{}: not a valid caustic checkpoint: {problem}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        problem: String,
    },
}

const SUM: [&str; 3] = ["sum.R", "sum.G", "sum.B"];
const PREVIEW: [&str; 3] = ["R", "G", "B"];
const TAKEN: &str = "samples.taken";
const KEPT: &str = "samples.kept";
const ODD: [&str; 3] = ["odd.R", "odd.G", "odd.B"];
const ODD_KEPT: &str = "odd.kept";
const CONVERGED: &str = "converged";
const ALBEDO: [&str; 3] = ["albedo.R", "albedo.G", "albedo.B"];
const NORMAL: [&str; 3] = ["normal.X", "normal.Y", "normal.Z"];

/// Writes `accumulation` and `meta` to `path` atomically. A checkpoint
/// holds every buffer: those `accumulation` does not keep are written as
/// zeros (a render that checkpoints keeps them all, see `job`).
pub fn write_checkpoint(path: &Path, accumulation: &Accumulation, meta: &CheckpointMeta) -> Result<(), OutputError> {
    use exr::prelude::*;
    let full;
    let accumulation = if accumulation.buffers() == super::Buffers::ALL {
        accumulation
    } else {
        full = accumulation.region_with(0, 0, accumulation.width, accumulation.height, super::Buffers::ALL);
        &full
    };
    let size = (accumulation.width as usize, accumulation.height as usize);
    let film = accumulation.to_film();
    let component =
        |values: &[Vec3], c: usize| -> FlatSamples { FlatSamples::F32(values.iter().map(|v| v[c]).collect()) };
    let mut channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for c in 0..3 {
        channels.push(AnyChannel::new(PREVIEW[c], component(&film.pixels, c)));
        channels.push(AnyChannel::new(SUM[c], component(&accumulation.sum, c)));
        channels.push(AnyChannel::new(ODD[c], component(&accumulation.odd, c)));
        channels.push(AnyChannel::new(ALBEDO[c], component(&accumulation.albedo, c)));
        channels.push(AnyChannel::new(NORMAL[c], component(&accumulation.normal, c)));
    }
    channels.push(AnyChannel::new(TAKEN, FlatSamples::U32(accumulation.taken.clone())));
    channels.push(AnyChannel::new(KEPT, FlatSamples::U32(accumulation.kept.clone())));
    channels.push(AnyChannel::new(
        ODD_KEPT,
        FlatSamples::U32(accumulation.odd_kept.clone()),
    ));
    let converged = accumulation.converged.iter().map(|&c| c as u32).collect();
    channels.push(AnyChannel::new(CONVERGED, FlatSamples::U32(converged)));

    let mut attributes = LayerAttributes::default();
    let tone = match meta.output.tone_map {
        ToneMap::Aces => "aces",
        ToneMap::Clamp => "clamp",
    };
    let mut fields = vec![
        ("caustic.format", CHECKPOINT_FORMAT.to_string()),
        ("caustic.width", meta.width.to_string()),
        ("caustic.height", meta.height.to_string()),
        ("caustic.spp", meta.spp.to_string()),
        ("caustic.seed", meta.seed.to_string()),
        ("caustic.photons", meta.photons.to_string()),
        ("caustic.accel", meta.accel.clone()),
        ("caustic.fingerprint", meta.fingerprint.clone()),
        ("caustic.fingerprint.format", meta.fingerprint_format.to_string()),
        ("caustic.tonemap", tone.to_string()),
        // Debug output of f32 is the shortest text that round-trips.
        ("caustic.exposure", format!("{:?}", meta.output.exposure)),
    ];
    if let Some(set) = &meta.shard {
        fields.push(("caustic.shard.mode", set.mode.name().to_string()));
        fields.push(("caustic.shard.count", set.count.to_string()));
        fields.push(("caustic.shard.indices", set.indices_text()));
    }
    for (key, value) in fields {
        // Only ASCII is written (numbers, hex, accelerator names), which EXR text accepts.
        let value = Text::new_or_none(&value).unwrap_or_else(|| Text::from("?"));
        attributes.other.insert(Text::from(key), AttributeValue::Text(value));
    }
    // ZIP is lossless on f32 and u32 and much smaller than RLE on noisy data.
    let encoding = Encoding::SMALL_LOSSLESS;
    let layer = Layer::new(size, attributes, encoding, AnyChannels::sort(channels));
    let image = Image::from_layer(layer);
    write_atomically(path, |w| {
        image.write().to_buffered(w).map_err(|source| OutputError::Exr {
            path: path.to_path_buf(),
            source,
        })
    })
}

/// Reads only the header of a checkpoint or partial: its settings, checked
/// (format, attributes, size within the image limits), without the pixels.
pub fn read_checkpoint_meta(path: &Path) -> Result<CheckpointMeta, CheckpointError> {
    read_header(path).map(|(meta, _)| meta)
}

fn read_header(path: &Path) -> Result<(CheckpointMeta, exr::meta::header::Header), CheckpointError> {
    let invalid = |problem: String| CheckpointError::Invalid {
        path: path.to_path_buf(),
        problem,
    };
    let header_meta = exr::meta::MetaData::read_from_file(path, false).map_err(|cause| CheckpointError::Exr {
        path: path.to_path_buf(),
        cause,
    })?;
    let header = match header_meta.headers.as_slice() {
        [h] => h.clone(),
        hs => return Err(invalid(format!("{} layers, expected 1", hs.len()))),
    };
    let meta = parse_meta(&header.own_attributes.other).map_err(invalid)?;
    if let Err(e) = crate::limits::check_image_limits(meta.width, meta.height, meta.spp) {
        return Err(invalid(format!("recorded image size: {e}")));
    }
    Ok((meta, header))
}

/// Reads a checkpoint written by [`write_checkpoint`]. The header is read and
/// checked first (format, size within the image limits, channel types), so a
/// hostile file cannot make the reader allocate more than its stated size.
pub fn read_checkpoint(path: &Path) -> Result<Checkpoint, CheckpointError> {
    use exr::prelude::*;
    let invalid = |problem: String| CheckpointError::Invalid {
        path: path.to_path_buf(),
        problem,
    };
    let exr_error = |cause| CheckpointError::Exr {
        path: path.to_path_buf(),
        cause,
    };
    let (meta, header) = read_header(path)?;
    let has_aovs = header.own_attributes.other.iter().any(|(k, v)| {
        *k == *"caustic.format"
            && matches!(v, exr::meta::attribute::AttributeValue::Text(t) if *t == *CHECKPOINT_FORMAT)
    });
    let size = (meta.width as usize, meta.height as usize);
    if header.layer_size.0 != size.0 || header.layer_size.1 != size.1 || header.deep {
        return Err(invalid(format!(
            "the pixel data is {}×{}{} but the header records {}×{}",
            header.layer_size.0,
            header.layer_size.1,
            if header.deep { " (deep)" } else { "" },
            size.0,
            size.1
        )));
    }
    let aov_channels: &[&str] = if has_aovs {
        &[&ALBEDO[..], &NORMAL[..]].concat()
    } else {
        &[]
    };
    for (name, ty) in SUM
        .iter()
        .chain(&ODD)
        .chain(aov_channels)
        .map(|n| (*n, SampleType::F32))
        .chain([
            (TAKEN, SampleType::U32),
            (KEPT, SampleType::U32),
            (ODD_KEPT, SampleType::U32),
            (CONVERGED, SampleType::U32),
        ])
    {
        let found = header.channels.list.iter().find(|c| c.name == *name);
        match found {
            Some(c) if c.sample_type == ty => {}
            Some(c) => {
                return Err(invalid(format!(
                    "channel {name} holds {:?} samples, expected {ty:?}",
                    c.sample_type
                )))
            }
            None => return Err(invalid(format!("channel {name} is missing"))),
        }
    }

    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(exr_error)?;
    let channels = &image.layer_data.channel_data.list;
    let find = |name: &str| channels.iter().find(|c| c.name == *name).map(|c| &c.sample_data);
    let f32s = |name: &str| match find(name) {
        Some(FlatSamples::F32(v)) => Ok(v),
        _ => Err(invalid(format!("channel {name} is missing or not f32"))),
    };
    let u32s = |name: &str| match find(name) {
        Some(FlatSamples::U32(v)) => Ok(v.clone()),
        _ => Err(invalid(format!("channel {name} is missing or not u32"))),
    };
    let vec3s = |names: &[&str; 3]| -> std::result::Result<Vec<Vec3>, CheckpointError> {
        let (r, g, b) = (f32s(names[0])?, f32s(names[1])?, f32s(names[2])?);
        Ok(r.iter()
            .zip(g)
            .zip(b)
            .map(|((&r, &g), &b)| Vec3::new(r, g, b))
            .collect())
    };
    let converged = u32s(CONVERGED)?;
    if let Some(i) = converged.iter().position(|&c| c > 1) {
        return Err(invalid(format!(
            "channel {CONVERGED}: value {} is not 0 or 1",
            converged[i]
        )));
    }
    let accumulation = Accumulation {
        width: meta.width,
        height: meta.height,
        sum: vec3s(&SUM)?,
        taken: u32s(TAKEN)?,
        kept: u32s(KEPT)?,
        odd: vec3s(&ODD)?,
        odd_kept: u32s(ODD_KEPT)?,
        converged: converged.into_iter().map(|c| c == 1).collect(),
        albedo: if has_aovs {
            vec3s(&ALBEDO)?
        } else {
            vec![Vec3::ZERO; size.0 * size.1]
        },
        normal: if has_aovs {
            vec3s(&NORMAL)?
        } else {
            vec![Vec3::ZERO; size.0 * size.1]
        },
    };
    accumulation.validate(meta.spp).map_err(invalid)?;
    if let Some(set) = &meta.shard {
        set.validate(&accumulation, meta.spp).map_err(invalid)?;
    }
    Ok(Checkpoint {
        meta,
        accumulation,
        has_aovs,
    })
}

fn parse_meta(
    attributes: &std::collections::HashMap<exr::meta::attribute::Text, exr::meta::attribute::AttributeValue>,
) -> Result<CheckpointMeta, String> {
    use exr::meta::attribute::AttributeValue;
    let text = |key: &str| -> Result<String, String> {
        match attributes.iter().find(|(k, _)| **k == *key) {
            Some((_, AttributeValue::Text(t))) => Ok(t.to_string()),
            Some(_) => Err(format!("attribute {key} is not text")),
            None => Err(format!("attribute {key} is missing")),
        }
    };
    fn number<T: std::str::FromStr>(key: &str, value: String) -> Result<T, String> {
        value
            .parse()
            .map_err(|_| format!("attribute {key} = {value:?} is not a valid number"))
    }
    let format = text("caustic.format")?;
    if format != CHECKPOINT_FORMAT && format != CHECKPOINT_FORMAT_3 && format != CHECKPOINT_FORMAT_2 {
        return Err(format!(
            "format {format:?}, this caustic reads {CHECKPOINT_FORMAT:?}, {CHECKPOINT_FORMAT_3:?} and {CHECKPOINT_FORMAT_2:?}"
        ));
    }
    let current = format != CHECKPOINT_FORMAT_2;
    let has = |key: &str| attributes.keys().any(|k| *k == *key);
    let output = if current {
        let tone_map = match text("caustic.tonemap")?.as_str() {
            "aces" => ToneMap::Aces,
            "clamp" => ToneMap::Clamp,
            other => return Err(format!("attribute caustic.tonemap = {other:?} is not aces or clamp")),
        };
        let exposure: f32 = number("caustic.exposure", text("caustic.exposure")?)?;
        if !exposure.is_finite() {
            return Err(format!("attribute caustic.exposure = {exposure} is not finite"));
        }
        OutputSettings { tone_map, exposure }
    } else {
        OutputSettings::default()
    };
    let shard = if current && has("caustic.shard.mode") {
        let mode_text = text("caustic.shard.mode")?;
        let mode = ShardMode::from_name(&mode_text)
            .ok_or_else(|| format!("attribute caustic.shard.mode = {mode_text:?} is not tiles or samples"))?;
        let count: u32 = number("caustic.shard.count", text("caustic.shard.count")?)?;
        if count == 0 || count > super::shard::MAX_SHARDS {
            return Err(format!(
                "attribute caustic.shard.count = {count} is not in 1..={}",
                super::shard::MAX_SHARDS
            ));
        }
        let indices = ShardSet::parse_indices(&text("caustic.shard.indices")?, count)?;
        Some(ShardSet { mode, count, indices })
    } else {
        None
    };
    Ok(CheckpointMeta {
        width: number("caustic.width", text("caustic.width")?)?,
        height: number("caustic.height", text("caustic.height")?)?,
        spp: number("caustic.spp", text("caustic.spp")?)?,
        seed: number("caustic.seed", text("caustic.seed")?)?,
        photons: number("caustic.photons", text("caustic.photons")?)?,
        accel: text("caustic.accel")?,
        fingerprint: text("caustic.fingerprint")?,
        // Files written before the format was recorded hashed format 1.
        fingerprint_format: if has("caustic.fingerprint.format") {
            number("caustic.fingerprint.format", text("caustic.fingerprint.format")?)?
        } else {
            1
        },
        output,
        shard,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> (Accumulation, CheckpointMeta) {
        let mut a = Accumulation::new(5, 3);
        for i in 0..a.len() {
            // Values whose last bits matter: a round trip must keep them all.
            a.sum[i] = Vec3::new(0.1 + i as f32 / 3.0, 1.0e-7 * i as f32, 12345.678 + i as f32);
            a.taken[i] = (i % 4) as u32;
            a.kept[i] = (i % 4).saturating_sub(i % 2) as u32;
            a.odd[i] = Vec3::new(0.05 + i as f32 / 7.0, 3.0e-8 * i as f32, 99.5);
            a.odd_kept[i] = a.kept[i].min(a.taken[i] / 2);
            a.converged[i] = i % 3 == 0;
            a.albedo[i] = Vec3::new(0.3 + i as f32 / 11.0, 1.0e-6 * i as f32, 0.7);
            a.normal[i] = Vec3::new(-0.25 * i as f32, 0.5, 1.0 / (i + 1) as f32);
        }
        let meta = CheckpointMeta {
            width: 5,
            height: 3,
            spp: 4,
            seed: u64::MAX - 7,
            photons: 12_345,
            accel: "kdtree".into(),
            fingerprint: "ab".repeat(32),
            fingerprint_format: 2,
            output: OutputSettings {
                tone_map: ToneMap::Clamp,
                exposure: 0.1,
            },
            shard: None,
        };
        (a, meta)
    }

    #[test]
    fn round_trip_is_exact() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.exr");
        let (a, meta) = sample();
        write_checkpoint(&path, &a, &meta).unwrap();
        let c = read_checkpoint(&path).unwrap();
        assert_eq!(c.meta, meta);
        assert_eq!(c.accumulation, a);
        // The preview is the film, readable as a plain RGB image.
        let rgb = exr::prelude::read_first_rgba_layer_from_file(
            &path,
            |res: exr::prelude::Vec2<usize>, _| vec![[0f32; 3]; res.area()],
            |px: &mut Vec<[f32; 3]>, pos: exr::prelude::Vec2<usize>, (r, g, b, _a): (f32, f32, f32, f32)| {
                px[pos.y() * 5 + pos.x()] = [r, g, b];
            },
        )
        .unwrap();
        let film = a.to_film();
        for (i, p) in film.pixels.iter().enumerate() {
            assert_eq!(rgb.layer_data.channel_data.pixels[i], p.to_array());
        }
    }

    #[test]
    fn partials_round_trip_and_are_checked_against_their_shards() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.exr");
        let set = ShardSet {
            mode: ShardMode::Tiles,
            count: 3,
            indices: vec![0, 2],
        };
        let mut a = Accumulation::new(20, 9);
        for (i, owned) in set.pixel_mask(20, 9).into_iter().enumerate() {
            if owned {
                a.sum[i] = Vec3::splat(i as f32 * 0.1);
                a.taken[i] = 4;
                a.kept[i] = 4;
            }
        }
        let (_, mut meta) = sample();
        (meta.width, meta.height, meta.shard) = (20, 9, Some(set.clone()));
        write_checkpoint(&path, &a, &meta).unwrap();
        let c = read_checkpoint(&path).unwrap();
        assert_eq!(c.meta, meta);
        assert_eq!(c.accumulation, a);
        // A pixel of shard 1 holding samples is refused.
        let i = set.pixel_mask(20, 9).iter().position(|&m| !m).unwrap();
        a.taken[i] = 1;
        write_checkpoint(&path, &a, &meta).unwrap();
        let e = read_checkpoint(&path).unwrap_err().to_string();
        assert!(e.contains("belongs to another shard"), "{e}");
    }

    #[test]
    fn bad_files_are_refused_with_the_reason() {
        let dir = tempfile::tempdir().unwrap();
        // Not an EXR at all.
        let junk = dir.path().join("junk.exr");
        std::fs::write(&junk, b"not an image").unwrap();
        let e = read_checkpoint(&junk).unwrap_err().to_string();
        assert!(e.contains("junk.exr") && e.contains("cannot read"), "{e}");
        // A missing file.
        let e = read_checkpoint(&dir.path().join("none.exr")).unwrap_err().to_string();
        assert!(e.contains("none.exr"), "{e}");
        // A plain image (no caustic attributes).
        let plain = dir.path().join("plain.exr");
        super::super::write_exr(&plain, &crate::film::Film::new(2, 2)).unwrap();
        let e = read_checkpoint(&plain).unwrap_err().to_string();
        assert!(e.contains("caustic.format is missing"), "{e}");
        // Counts that contradict the spp.
        let (mut a, meta) = sample();
        a.taken[2] = 9;
        let bad = dir.path().join("bad.exr");
        write_checkpoint(&bad, &a, &meta).unwrap();
        let e = read_checkpoint(&bad).unwrap_err().to_string();
        assert!(e.contains("pixel (2, 0)"), "{e}");
        // A size that does not match the pixel data.
        let (a, mut meta) = sample();
        meta.width = 6;
        write_checkpoint(&bad, &a, &meta).unwrap();
        let e = read_checkpoint(&bad).unwrap_err().to_string();
        assert!(e.contains("5×3") && e.contains("6×3"), "{e}");
        // An absurd recorded size is refused before the pixels are read.
        let (a, mut meta) = sample();
        meta.width = 4_000_000;
        write_checkpoint(&bad, &a, &meta).unwrap();
        let e = read_checkpoint(&bad).unwrap_err().to_string();
        assert!(e.contains("recorded image size"), "{e}");
    }
}
