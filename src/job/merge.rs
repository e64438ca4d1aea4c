//! `caustic merge`: partials of the shards of one render back into one
//! image, or a subset of them into a new partial (tree reductions).
//!
//! Every header is read and checked before any pixel data: the partials
//! must be of the same render (fingerprint), split the same way (mode and
//! count), with display settings that agree, hold no shard twice, and be
//! finished; an image output needs every shard. Each refusal names the
//! file. The pixel data is then read one partial at a time (in order of
//! shard index) and merged (see `film::shard`): tiles copy per-pixel state,
//! so the image is bit-identical to a single-process render; samples add
//! the shards' sums, within `film::shard::samples_merge_bound` of it.
//! Outputs are written atomically.

use super::fingerprint;
use super::{write_exr_output, JobError};
use crate::film::{self, shard, Accumulation, CheckpointMeta, ShardSet};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// What to merge and where to.
#[derive(Clone, Debug, Default)]
pub struct MergeRequest {
    /// The partials.
    pub partials: Vec<PathBuf>,
    /// Tone-mapped PNG of the merged image (needs every shard).
    pub png: Option<PathBuf>,
    /// Linear EXR of the merged image, with error and sample-count channels
    /// as `caustic render --exr` writes (needs every shard).
    pub exr: Option<PathBuf>,
    /// A new partial holding the shards of all the inputs.
    pub partial: Option<PathBuf>,
    /// Denoise the PNG and the EXR's main layer (the partial stays raw).
    pub denoise: bool,
    /// The denoising filter's quality.
    pub denoise_quality: crate::film::denoise::DenoiseQuality,
}

/// What a merge did.
#[derive(Clone, Debug)]
pub struct MergeReport {
    /// The settings of the render, with the merged shard set.
    pub meta: CheckpointMeta,
    /// The merged accumulation.
    pub accumulation: Accumulation,
    /// The files written.
    pub written: Vec<String>,
    /// What denoising cost, when the image was denoised.
    pub denoise: Option<crate::film::denoise::DenoiseStats>,
}

fn invalid(message: String) -> JobError {
    JobError::Invalid(message)
}

/// Merges the partials of `request` and writes its outputs.
pub fn merge_partials(request: &MergeRequest) -> Result<MergeReport, JobError> {
    if request.partials.is_empty() {
        return Err(invalid("caustic merge: no partials given".to_string()));
    }
    if request.denoise {
        crate::film::denoise::require()?;
    }
    if request.png.is_none() && request.exr.is_none() && request.partial.is_none() {
        return Err(invalid(
            "caustic merge: nothing to write; give -o out.png, --exr out.exr or --partial out.exr".to_string(),
        ));
    }
    for out in request.png.iter().chain(&request.exr).chain(&request.partial) {
        if request.partials.iter().any(|p| same_file(p, out)) {
            return Err(invalid(format!(
                "{}: is one of the partials being merged; write to another file",
                out.display()
            )));
        }
        film::check_writable(out)?;
    }

    // Headers first: every check before any pixel is read.
    let mut metas = Vec::new();
    for path in &request.partials {
        let meta = film::read_checkpoint_meta(path)?;
        let Some(set) = meta.shard.clone() else {
            return Err(invalid(format!(
                "{}: a checkpoint of a whole render, not a partial (render shards with --shard I/N)",
                path.display()
            )));
        };
        metas.push((path, meta, set));
    }
    let (first_path, first, first_set) = metas[0].clone();
    let (first_path, first, first_set) = (first_path.as_path(), &first, &first_set);
    let mut owner: BTreeMap<u32, &Path> = BTreeMap::new();
    for (path, meta, set) in &metas {
        if meta.fingerprint_format != first.fingerprint_format {
            return Err(invalid(format!(
                "{}: written by another caustic than {} (fingerprint format {} here, {} there): partials of one \
                 render come from one caustic",
                path.display(),
                first_path.display(),
                meta.fingerprint_format,
                first.fingerprint_format
            )));
        }
        if meta.fingerprint != first.fingerprint {
            return Err(invalid(format!(
                "{}: a partial of a different render than {} ({})",
                path.display(),
                first_path.display(),
                fingerprint::differences_between(first, &format!("in {}", first_path.display()), meta, "here")
            )));
        }
        let shape = |m: &CheckpointMeta| (m.width, m.height, m.spp, m.seed, m.photons, m.accel.clone());
        if shape(meta) != shape(first) {
            return Err(invalid(format!(
                "{}: the same fingerprint as {} but other recorded settings ({}): a damaged or edited partial",
                path.display(),
                first_path.display(),
                fingerprint::differences_between(first, &format!("in {}", first_path.display()), meta, "here")
            )));
        }
        if set.mode != first_set.mode {
            return Err(invalid(format!(
                "{}: split by {}, but {} is split by {}: shards of one render share a mode",
                path.display(),
                set.mode.name(),
                first_path.display(),
                first_set.mode.name()
            )));
        }
        if set.count != first_set.count {
            return Err(invalid(format!(
                "{}: one of {} shards, but {} is one of {}",
                path.display(),
                set.count,
                first_path.display(),
                first_set.count
            )));
        }
        if meta.output != first.output {
            return Err(invalid(format!(
                "{}: tone map or exposure differ from {} (the scene's display settings changed)",
                path.display(),
                first_path.display()
            )));
        }
        for &i in &set.indices {
            if let Some(other) = owner.insert(i, path) {
                if same_file(other, path) {
                    return Err(invalid(format!("{}: given twice", path.display())));
                }
                return Err(invalid(format!(
                    "{}: shard {i} of {} is also in {} (duplicate)",
                    path.display(),
                    set.count,
                    other.display()
                )));
            }
        }
    }
    let merged_set = ShardSet {
        mode: first_set.mode,
        count: first_set.count,
        indices: owner.keys().copied().collect(),
    };
    if (request.png.is_some() || request.exr.is_some()) && !merged_set.is_whole() {
        let missing: Vec<String> = (0..merged_set.count)
            .filter(|i| !owner.contains_key(i))
            .map(|i| i.to_string())
            .collect();
        let shown = if missing.len() > 20 {
            format!("{}, … ({} in all)", missing[..20].join(", "), missing.len())
        } else {
            missing.join(", ")
        };
        return Err(invalid(format!(
            "missing shard{} {shown} of {}: an image needs every shard (merge a subset with --partial)",
            if missing.len() == 1 { "" } else { "s" },
            merged_set.count
        )));
    }

    // Pixels, one partial at a time, in order of shard index.
    metas.sort_by_key(|(_, _, set)| set.indices[0]);
    let (width, height, spp) = (first.width, first.height, first.spp);
    let mut merged = Accumulation::new(width, height);
    for (path, meta, set) in &metas {
        let part = film::read_checkpoint(path)?;
        if part.meta != *meta {
            return Err(invalid(format!("{}: changed while being merged", path.display())));
        }
        if !set.is_complete(&part.accumulation, spp) {
            let (done, total) = shard_progress(set, &part.accumulation, spp);
            return Err(invalid(format!(
                "{}: {set} is not finished ({done} of {total} samples); continue it with \
                 caustic render SCENE --resume {}",
                path.display(),
                path.display()
            )));
        }
        shard::merge_into(&mut merged, &part.accumulation, set);
    }

    let meta = CheckpointMeta {
        shard: Some(merged_set.clone()),
        ..first.clone()
    };
    let mut written = Vec::new();
    let raw = merged.to_film();
    let (film_image, noisy, denoise) = if request.denoise && (request.png.is_some() || request.exr.is_some()) {
        let (image, stats) = super::denoise_accumulation(&raw, &merged, request.denoise_quality)?;
        (image, Some(raw), Some(stats))
    } else {
        (raw, None, None)
    };
    if let Some(p) = &request.png {
        film::write_png(p, &film_image, &meta.output)?;
        written.push(p.display().to_string());
    }
    if let Some(p) = &request.exr {
        write_exr_output(p, &film_image, &merged, noisy.as_ref())?;
        written.push(p.display().to_string());
    }
    if let Some(p) = &request.partial {
        film::write_checkpoint(p, &merged, &meta)?;
        written.push(format!("{} (partial: {merged_set})", p.display()));
    }
    Ok(MergeReport {
        meta,
        accumulation: merged,
        written,
        denoise,
    })
}

/// Samples a partial holds and should hold.
fn shard_progress(set: &ShardSet, acc: &Accumulation, spp: u32) -> (u64, u64) {
    let first = set.first_sample(spp) as u64;
    let mask = set.pixel_mask(acc.width, acc.height);
    let done = acc
        .taken
        .iter()
        .zip(&mask)
        .filter(|(_, &m)| m)
        .map(|(&t, _)| (t as u64).saturating_sub(first))
        .sum();
    (done, set.total_samples(acc.width, acc.height, spp))
}

/// True when two paths name the same existing file.
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => a == b,
    }
}
