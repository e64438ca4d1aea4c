//! Photon-mapped caustics (Jensen 1996; the original report's §5.2): a
//! first pass emits photons toward the specular objects and stores those
//! that reach a diffuse surface after at least one specular bounce (the
//! caustic map; with the path integrator also a volume map of the light
//! scattered in a medium); the integrators then add the cone-filtered
//! irradiance estimate at diffuse surfaces.
//!
//! - [`emit`]: emission restricted to the specular casters and tracing,
//!   under Whitted's or the path integrator's scattering rules;
//! - [`map`]: the compact photon records and the surface and volume maps;
//! - [`chunked`]: a point set cut into spatial chunks, one kiddo k-d tree
//!   per chunk, built in parallel;
//! - [`gather`]: the k-nearest cone-filter estimate, or every photon
//!   within a fixed radius;
//! - [`neighbourhood`]: exact k-nearest queries answered from a cached
//!   neighbourhood (triangle inequality);
//! - [`site_tree`]: the k-d tree of the precomputed irradiance sites, for
//!   one- and few-nearest queries;
//! - [`precomputed`]: irradiance precomputed at every few stored photons
//!   (Christensen 1999) and the per-thread site cache;
//! - [`mod@file`]: photon files (`caustic photons`, `--photon-map`);
//! - [`progressive`]: progressive photon mapping's schedule (Knaus &
//!   Zwicker 2011): one independent map per sample index and its radius.
//! - [`source`]: where a render's caustics come from (none, one map, a
//!   map per sample index).
//!
//! The pass is parallel (rayon) and deterministic: photon `i` draws from
//! `Rng::new(seed, Domain::Photon, i, 0)` and the photons are concatenated
//! in index order, so the map is identical for any thread count.

pub mod chunked;
pub mod emit;
pub mod file;
pub mod gather;
pub mod grid;
pub mod map;
pub mod neighbourhood;
pub mod precomputed;
pub mod progressive;
pub mod site_tree;
pub mod source;

pub use emit::{delta_casters, specular_casters, Caster, PhotonRules, PhotonTracer, TraceSettings, PHOTON_PATH_DEPTH};
pub use file::{read_photons, write_photons, PhotonFileError};
pub use gather::{GatherParams, Kernel, INDIRECT_GATHER_DIVISOR, VOLUME_RADIUS_SCALE};
pub use map::{Photon, PhotonMap, PhotonRecord, BYTES_PER_PHOTON, PEAK_BYTES_PER_PHOTON};
pub use precomputed::{IrradianceSite, Precompute, SiteCache, SiteSearch, PRECOMPUTE_STRIDE, SITES_PER_PIXEL};
pub use source::CausticsSource;

use crate::accel::Accel;
use crate::scene::Scene;
use rayon::prelude::*;
use std::fmt;
use std::time::{Duration, Instant};

/// Photons traced per rayon task: large enough to amortise scheduling.
const CHUNK: u64 = 4096;
/// Photons traced before their results are copied into the final arrays:
/// bounds the transient memory of the per-chunk vectors (two batches' worth).
const BATCH: u64 = 1 << 20;

/// What one rayon task of the photon pass produced, already packed.
struct TracedChunk {
    positions: Vec<[f32; 3]>,
    records: Vec<PhotonRecord>,
    volume_positions: Vec<[f32; 3]>,
    volume_records: Vec<PhotonRecord>,
    sites: Vec<IrradianceSite>,
    rays: u64,
}

pub use crate::scene::GatherMode;

impl fmt::Display for GatherMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GatherMode::Direct => write!(f, "direct gathers"),
            GatherMode::Precomputed => write!(
                f,
                "precomputed irradiance (1 site per {PRECOMPUTE_STRIDE} photons, at most {SITES_PER_PIXEL} per pixel)"
            ),
        }
    }
}

/// What the photon pass did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PhotonStats {
    /// Photons emitted (paths traced).
    pub emitted: u64,
    /// Photons stored in the caustic map.
    pub stored: u64,
    /// Photons stored in the volume map (path integrator, in a medium).
    pub volume_stored: u64,
    /// Rays cast while tracing photons.
    pub rays: u64,
    /// Wall time of emission and tracing.
    pub trace_time: Duration,
    /// Wall time of the k-d tree build.
    pub build_time: Duration,
    /// Sites with a precomputed irradiance estimate (0: direct gathers).
    pub precomputed_sites: u64,
    /// Wall time of the precomputation (estimates and the sites' tree).
    pub precompute_time: Duration,
    /// Bytes held by the map (progressive: the largest of the maps, of
    /// which one lives at a time).
    pub memory_bytes: usize,
    /// Maps traced: 1, or progressive photon mapping's one per sample index
    /// rendered (the other fields are then totals over the maps).
    pub maps: u64,
}

impl PhotonStats {
    /// Adds another map's statistics to these totals (progressive photon
    /// mapping: times and counts add up, memory is the largest map's).
    pub fn add(&mut self, other: &PhotonStats) {
        self.emitted += other.emitted;
        self.stored += other.stored;
        self.rays += other.rays;
        self.trace_time += other.trace_time;
        self.build_time += other.build_time;
        self.precomputed_sites += other.precomputed_sites;
        self.precompute_time += other.precompute_time;
        self.memory_bytes = self.memory_bytes.max(other.memory_bytes);
        self.maps += other.maps;
    }
}

impl fmt::Display for PhotonStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.maps > 1 {
            let total = self.trace_time + self.build_time + self.precompute_time;
            return write!(
                f,
                "photon passes (progressive): {} maps, {:.3} s in total ({:.3} s traced, {:.3} s k-d tree builds), \
                 {} emitted, {} stored, {} rays, {:.1} MiB for the largest map",
                self.maps,
                total.as_secs_f64(),
                self.trace_time.as_secs_f64(),
                self.build_time.as_secs_f64(),
                self.emitted,
                self.stored,
                self.rays,
                self.memory_bytes as f64 / (1024.0 * 1024.0),
            );
        }
        write!(
            f,
            "photon pass: {} emitted, {} stored{}, {} rays, traced in {:.3} s, k-d tree built in {:.3} s, \
             {} irradiance sites precomputed in {:.3} s, {:.1} MiB ({:.1} bytes per photon)",
            self.emitted,
            self.stored,
            if self.volume_stored > 0 {
                format!(" (+ {} in the volume map)", self.volume_stored)
            } else {
                String::new()
            },
            self.rays,
            self.trace_time.as_secs_f64(),
            self.build_time.as_secs_f64(),
            self.precomputed_sites,
            self.precompute_time.as_secs_f64(),
            self.memory_bytes as f64 / (1024.0 * 1024.0),
            if self.stored + self.volume_stored > 0 {
                self.memory_bytes as f64 / (self.stored + self.volume_stored) as f64
            } else {
                0.0
            }
        )
    }
}

/// Emits `count` photons, traces them and builds the caustic map, on the
/// current rayon pool (direct gathers: no precomputation; no coarse
/// positions, as in a render without `--debug photons`).
pub fn photon_pass(scene: &Scene, settings: TraceSettings, accel: &dyn Accel, count: u64) -> (PhotonMap, PhotonStats) {
    photon_pass_with(scene, settings, accel, count, None, false, PhotonRules::Whitted)
}

/// [`photon_pass`], then, with `precompute`, the irradiance at the stored
/// photons whose emission index is a multiple of [`PRECOMPUTE_STRIDE`]
/// (emission indices are Morton-ordered strata, so these are a stratified
/// subset), thinned further to at most `precompute.max_sites` sites
/// (Christensen 1999; see [`precomputed`]). With `keep_positions`, the map
/// keeps coarse positions for the debug overlay
/// ([`PhotonMap::coarse_position`]).
pub fn photon_pass_with(
    scene: &Scene,
    settings: TraceSettings,
    accel: &dyn Accel,
    count: u64,
    precompute: Option<&Precompute>,
    keep_positions: bool,
    rules: PhotonRules,
) -> (PhotonMap, PhotonStats) {
    let traced = trace_photons_with(scene, settings, accel, count, precompute.is_some(), rules, 0);
    build_photon_map(traced, precompute, keep_positions, None)
}

/// The photons of a pass as traced, before the map is built: what
/// `caustic photons` saves and `--photon-map` loads
/// ([`build_photon_map`] makes the same map from them either way).
#[derive(Clone, Debug, PartialEq)]
pub struct TracedPhotons {
    /// Photons emitted.
    pub emitted: u64,
    /// Positions of the stored photons, in emission order.
    pub positions: Vec<[f32; 3]>,
    /// Their packed power and direction, in the same order.
    pub records: Vec<PhotonRecord>,
    /// Positions of the photons stored in the volume map (physically
    /// based rules in a medium; empty otherwise), in emission order.
    pub volume_positions: Vec<[f32; 3]>,
    /// Their packed power and direction of travel reversed.
    pub volume_records: Vec<PhotonRecord>,
    /// Candidate irradiance sites: each stored photon whose emission index
    /// is a multiple of [`PRECOMPUTE_STRIDE`], in order (empty when not
    /// collected).
    pub sites: Vec<IrradianceSite>,
    /// True when `sites` were collected.
    pub has_sites: bool,
    /// Rays cast while tracing.
    pub rays: u64,
    /// Wall time of the tracing (zero for photons loaded from a file).
    pub trace_time: Duration,
}

/// Emits and traces `count` photons on the current rayon pool
/// (deterministic for any thread count), collecting the candidate
/// irradiance sites when `with_sites`.
pub fn trace_photons(
    scene: &Scene,
    settings: TraceSettings,
    accel: &dyn Accel,
    count: u64,
    with_sites: bool,
) -> TracedPhotons {
    trace_photons_with(scene, settings, accel, count, with_sites, PhotonRules::Whitted, 0)
}

/// [`trace_photons`] under the given scattering rules, with photon `i`
/// drawing from `Rng::new(seed, Domain::Photon, i, stream)`
/// ([`PhotonTracer::with_stream`]; stream 0 is [`trace_photons`]' map):
/// progressive photon mapping's independent maps ([`progressive`]).
pub fn trace_photons_with(
    scene: &Scene,
    settings: TraceSettings,
    accel: &dyn Accel,
    count: u64,
    with_sites: bool,
    rules: PhotonRules,
    stream: u64,
) -> TracedPhotons {
    let start = Instant::now();
    let tracer = PhotonTracer::with_rules(scene, settings, accel, count, rules).with_stream(stream);
    // A path stores at most one photon, so `count` bounds the arrays:
    // reserved at once (address space only, pages are touched as photons
    // arrive), they never move while growing; growth by doubling would
    // copy and page-fault them anew at every step.
    let capacity = usize::try_from(count).unwrap_or(usize::MAX);
    let mut positions: Vec<[f32; 3]> = Vec::with_capacity(capacity);
    let mut records: Vec<PhotonRecord> = Vec::with_capacity(capacity);
    let mut sites: Vec<IrradianceSite> = if with_sites {
        Vec::with_capacity(capacity / PRECOMPUTE_STRIDE + 1)
    } else {
        Vec::new()
    };
    let mut volume_positions: Vec<[f32; 3]> = Vec::new();
    let mut volume_records: Vec<PhotonRecord> = Vec::new();
    let mut rays = 0u64;
    // Tracing and packing run in parallel; the copies of one batch into the
    // final arrays (memcpy of 20 bytes per photon, and the page faults of
    // their first touch) run on one thread while the next batch is traced,
    // so no core waits for them. Batches are appended in emission order.
    let trace_batch = |batch_start: u64| -> Vec<TracedChunk> {
        let batch_end = (batch_start + BATCH).min(count);
        let chunks = (batch_end - batch_start).div_ceil(CHUNK);
        (0..chunks)
            .into_par_iter()
            .map(|c| {
                let first = batch_start + c * CHUNK;
                let last = (first + CHUNK).min(batch_end);
                // A path stores at most one photon: the task's arrays are
                // reserved for all of them and never grow.
                let most = (last - first) as usize;
                let mut out = TracedChunk {
                    positions: Vec::with_capacity(most),
                    records: Vec::with_capacity(most),
                    volume_positions: Vec::new(),
                    volume_records: Vec::new(),
                    sites: Vec::new(),
                    rays: 0,
                };
                out.rays = tracer.trace_range(first, last, |i, p, volume| {
                    if volume {
                        if p.position.is_finite() && p.power.is_finite() {
                            out.volume_positions.push(p.position.to_array());
                            out.volume_records.push(PhotonRecord::new(p.power, p.incoming));
                        }
                    } else if p.position.is_finite() && p.power.is_finite() {
                        out.positions.push(p.position.to_array());
                        out.records.push(PhotonRecord::new(p.power, p.incoming));
                        if with_sites && i % PRECOMPUTE_STRIDE as u64 == 0 {
                            out.sites.push(IrradianceSite {
                                position: p.position,
                                normal: p.normal,
                            });
                        }
                    }
                });
                out
            })
            .collect()
    };
    let mut append = |results: Vec<TracedChunk>| {
        for chunk in results {
            rays += chunk.rays;
            positions.extend_from_slice(&chunk.positions);
            records.extend_from_slice(&chunk.records);
            volume_positions.extend_from_slice(&chunk.volume_positions);
            volume_records.extend_from_slice(&chunk.volume_records);
            sites.extend_from_slice(&chunk.sites);
        }
    };
    let mut pending: Vec<TracedChunk> = Vec::new();
    let mut batch_start = 0u64;
    while batch_start < count {
        let previous = std::mem::take(&mut pending);
        let (traced, ()) = rayon::join(|| trace_batch(batch_start), || append(previous));
        pending = traced;
        batch_start = (batch_start + BATCH).min(count);
    }
    append(pending);
    positions.shrink_to_fit();
    records.shrink_to_fit();
    TracedPhotons {
        emitted: count,
        positions,
        records,
        volume_positions,
        volume_records,
        sites,
        has_sites: with_sites,
        rays,
        trace_time: start.elapsed(),
    }
}

/// Builds the caustic map from traced photons and, with `precompute`, the
/// irradiance at the thinned sites (which `traced` must hold). With
/// `grid_radius`, the surface map's gathers are answered by a hashed grid
/// for that radius instead of a tree, and the volume map's by one for
/// [`VOLUME_RADIUS_SCALE`] times it ([`PhotonMap::build_with_grid`]:
/// progressive photon mapping's fixed-radius gathers).
///
/// # Panics
/// With `precompute` when `traced.has_sites` is false.
pub fn build_photon_map(
    traced: TracedPhotons,
    precompute: Option<&Precompute>,
    keep_positions: bool,
    grid_radius: Option<f32>,
) -> (PhotonMap, PhotonStats) {
    assert!(
        precompute.is_none() || traced.has_sites,
        "the precompute needs the traced sites"
    );
    let TracedPhotons {
        emitted: count,
        positions,
        records,
        volume_positions,
        volume_records,
        mut sites,
        rays,
        trace_time,
        ..
    } = traced;
    let build_start = Instant::now();
    let stored = positions.len() as u64;
    let volume_stored = volume_positions.len() as u64;
    let mut map = PhotonMap::build_with_grid(positions, records, keep_positions, grid_radius);
    if volume_stored > 0 {
        map.volume = Some(Box::new(PhotonMap::build_with_grid(
            volume_positions,
            volume_records,
            false,
            grid_radius.map(|r| r * VOLUME_RADIUS_SCALE),
        )));
    }
    let build_time = build_start.elapsed();
    let precompute_start = Instant::now();
    if let Some(pre) = precompute {
        sites = pre.thin(sites);
    }
    let precomputed_sites = sites.len() as u64;
    if let Some(pre) = precompute {
        map.precompute_irradiance(sites, &pre.gather);
    }
    let stats = PhotonStats {
        emitted: count,
        stored,
        volume_stored,
        rays,
        trace_time,
        build_time,
        precomputed_sites,
        precompute_time: precompute_start.elapsed(),
        memory_bytes: map.memory_bytes(),
        maps: 1,
    };
    (map, stats)
}
