//! The render loop: progressive passes over rayon tiles, one seeded random
//! stream per pixel sample, box-filtered pixels.
//!
//! The per-pixel state is explicit ([`Accumulation`]: running f32 sum, samples
//! taken, samples kept). The image is rendered in passes of sample indices
//! (every pixel to 4, 8, 16, 32, then 16 more samples per pass), so a render
//! stopped early covers the whole frame at a lower sample count instead of
//! leaving black tiles. Every pixel adds its samples in increasing sample
//! index `k` from its own stream `Rng::for_pixel(seed, pixel, k)`, so the
//! sum after `n` samples is the same f32 value whether the pixel got there in
//! one pass, several, or across an interruption and a resume from a saved
//! sum: the final film is bit-identical to an uninterrupted render, for any
//! number of threads. A render can be stopped (cancel flag, sample limit) at
//! any pixel boundary; pixels never hold part of a sample.

use super::aov::{AovTracer, AOV_SAMPLES};
use super::path::PathTracer;
use super::photon::progressive::ProgressiveSchedule;
use super::photon::{
    build_photon_map, photon_pass_with, CausticsSource, GatherMode, GatherParams, PhotonMap, PhotonStats, Precompute,
    SiteCache, TracedPhotons,
};
use super::plan::{Adaptive, PhotonPlan, RenderPlan};
use super::sample::{Integrator, RayCounts, SampleContext};
use super::volpath::VolumePathTracer;
use super::whitted::Whitted;
use crate::accel::Accel;
use crate::film::{Accumulation, Buffers, Film};
use crate::math::rng::Domain;
use crate::math::sampling::{grid_for, permute, stratified};
use crate::math::{Rng, Sampler, SamplerKind, Vec3, Vec3A};
use crate::scene::{AdaptiveGoal, IntegratorKind, Scene};
use rayon::prelude::*;
use std::fmt;
use std::num::NonZero;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

/// Tile edge in pixels: big enough to amortise scheduling, small enough to
/// balance 2-64 threads on a 1080p image.
pub const TILE_SIZE: u32 = 32;

/// Fewest samples per pixel one pass adds (the first pass takes this many).
/// Each pass costs a little per pixel (the pixel's strata keys, its state
/// loaded and stored, one lock per tile), small against a sample's cost
/// (docs/benchmarks-history.md, "Render passes").
pub const MIN_PASS_SAMPLES: u32 = 4;

/// Most samples per pixel one pass adds. Passes double the sample count from
/// [`MIN_PASS_SAMPLES`] up to this step (4, 8, 16, 32, 48, ...): early passes
/// give a quick full-frame preview, later ones keep a tile's pass short (tens
/// of milliseconds on the showcase scenes), so a due checkpoint, which waits
/// for the tiles being rendered, is taken promptly. A cancel does not wait
/// for passes: it is checked before every pixel.
pub const MAX_PASS_SAMPLES: u32 = 16;

/// Sample count every pixel reaches at the end of the pass that starts when
/// the least-sampled pixel has `level` samples (never above `limit`).
pub fn next_pass_target(level: u32, limit: u32) -> u32 {
    level
        .saturating_add(level.clamp(MIN_PASS_SAMPLES, MAX_PASS_SAMPLES))
        .min(limit)
}

/// What a render did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Wall time of the render, photon pass included (not counting the
    /// accelerator build).
    pub wall_time: Duration,
    /// The photon pass, when it ran.
    pub photons: Option<PhotonStats>,
    /// Rays cast, by kind.
    pub rays: RayCounts,
    /// Camera samples taken.
    pub samples: u64,
    /// Samples whose radiance was NaN or infinite: dropped, never on the film.
    pub dropped_samples: u64,
}

impl RenderStats {
    /// Millions of rays per second of wall time.
    pub fn mrays_per_second(&self) -> f64 {
        let s = self.wall_time.as_secs_f64();
        if s > 0.0 {
            self.rays.total() as f64 / s / 1.0e6
        } else {
            0.0
        }
    }
}

impl fmt::Display for RenderStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = &self.rays;
        writeln!(f, "wall time: {:.3} s", self.wall_time.as_secs_f64())?;
        writeln!(
            f,
            "rays cast: {} ({} camera, {} shadow, {} secondary), {:.2} Mrays/s",
            r.total(),
            r.camera,
            r.shadow,
            r.secondary,
            self.mrays_per_second()
        )?;
        if let Some(p) = &self.photons {
            writeln!(f, "{p}")?;
        }
        write!(
            f,
            "samples: {}, dropped (NaN/inf): {}",
            self.samples, self.dropped_samples
        )
    }
}

/// A rendered image and its statistics.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// Linear HDR film (the mean of each pixel's kept samples).
    pub film: Film,
    /// The per-pixel state the film was made from: what a checkpoint saves.
    pub accumulation: Accumulation,
    /// Every pixel has all its samples or has converged (false when
    /// cancelled, stopped at a sample limit or out of time).
    pub complete: bool,
    /// The render stopped at its time limit before completing.
    pub timed_out: bool,
    /// Statistics of this run (a resumed render counts only the samples it
    /// took itself).
    pub stats: RenderStats,
    /// The caustic map used, when the photon pass ran (for the debug overlay).
    pub photon_map: Option<Arc<PhotonMap>>,
}

/// Periodic saving of the accumulation during a render.
#[derive(Clone, Copy)]
pub struct CheckpointHook<'a> {
    /// Least time between two saves.
    pub every: Duration,
    /// Called with a consistent snapshot (every pixel holds whole samples)
    /// from a worker thread between two tiles, while the other workers go
    /// on; it should report its own errors (a failed save does not stop
    /// the render).
    pub save: &'a (dyn Fn(&Accumulation) + Sync),
}

/// How a render is driven: when it stops early and what it reports.
#[derive(Clone, Copy)]
pub struct RenderControl<'a> {
    /// When set (by a signal handler, another thread, a test), workers stop
    /// before their next pixel; the render returns what it has.
    pub cancel: Option<&'a AtomicBool>,
    /// Stop once every pixel has at least this many samples (previews,
    /// tests); `None`: the plan's spp.
    pub sample_limit: Option<u32>,
    /// Periodic checkpoints.
    pub checkpoint: Option<CheckpointHook<'a>>,
    /// Stop before the next pixel once this instant is past (a time
    /// budget); the render returns what it has.
    pub deadline: Option<Instant>,
    /// `progress(samples_done, samples_total)` over the whole image (samples
    /// of a resumed accumulation included), called after each tile from
    /// worker threads in completion order.
    pub progress: &'a (dyn Fn(u64, u64) + Sync),
}

impl<'a> RenderControl<'a> {
    /// Render every sample, reporting progress only.
    pub fn to_completion(progress: &'a (dyn Fn(u64, u64) + Sync)) -> Self {
        Self {
            cancel: None,
            sample_limit: None,
            checkpoint: None,
            deadline: None,
            progress,
        }
    }

    fn cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(Ordering::Relaxed))
    }
}

#[derive(Clone, Copy)]
struct Tile {
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
}

/// The part of the accumulation one tile owns during a render. Behind a
/// mutex only so a checkpoint can take a snapshot while the render goes on:
/// the lock is uncontended otherwise.
struct TileState {
    tile: Tile,
    acc: Accumulation,
}

#[derive(Default)]
struct PassWork {
    rays: RayCounts,
    samples: u64,
    dropped: u64,
}

/// Runs the photon pass when `plan` asks for it: deterministic for any
/// thread count, so a resumed render re-runs it rather than storing it.
pub fn photon_pass_for(scene: &Scene, accel: &dyn Accel, plan: &RenderPlan) -> Option<(PhotonMap, PhotonStats)> {
    let (count, precompute) = photon_work(plan)?;
    Some(photon_pass_with(
        scene,
        plan.photon_trace(),
        accel,
        count,
        precompute.as_ref(),
        plan.keep_photon_positions,
        plan.photon_rules,
    ))
}

/// The photons `plan` emits and its precompute, when it runs the photon
/// pass before the image (not progressive photon mapping, whose maps the
/// pass loop traces: see [`progressive_schedule`]).
fn photon_work(plan: &RenderPlan) -> Option<(u64, Option<Precompute>)> {
    match plan.photons {
        PhotonPlan::Run {
            count,
            k,
            max_radius,
            cone_k,
            gather,
            progressive: None,
            ..
        } => {
            let precompute = match gather {
                GatherMode::Direct => None,
                GatherMode::Precomputed => Some(Precompute::for_image(
                    GatherParams {
                        k: NonZero::new(k.max(1) as usize).expect("k ≥ 1"),
                        max_radius,
                        cone_k,
                        fixed_radius: None,
                    },
                    plan.width as u64 * plan.height as u64,
                )),
            };
            Some((count, precompute))
        }
        _ => None,
    }
}

/// Progressive photon mapping's schedule, when `plan` runs it: `r_1` is
/// the plan's resolved `max_radius` (see `photon::progressive`).
pub fn progressive_schedule(plan: &RenderPlan) -> Option<ProgressiveSchedule> {
    match plan.photons {
        PhotonPlan::Run {
            max_radius,
            cone_k,
            progressive: Some(p),
            ..
        } => Some(ProgressiveSchedule {
            r1: max_radius,
            alpha: p.alpha,
            photons_per_pass: p.photons_per_pass,
            cone_k,
            keep_positions: plan.keep_photon_positions,
            rules: plan.photon_rules,
            settings: plan.photon_trace(),
        }),
        _ => None,
    }
}

/// Photons `plan` emits before the image, when it runs that photon pass
/// (`None` for progressive photon mapping, which traces one map per sample
/// index during the render).
pub fn planned_photons(plan: &RenderPlan) -> Option<u64> {
    photon_work(plan).map(|(count, _)| count)
}

/// The map `plan` would trace, built from photons traced beforehand (a
/// photon file: the same map, so the same image). `None` when the plan
/// runs no photon pass.
///
/// # Panics
/// If `traced` lacks the sites the plan's precompute needs (photon files
/// always hold them).
pub fn photon_map_from(traced: TracedPhotons, plan: &RenderPlan) -> Option<(PhotonMap, PhotonStats)> {
    let (_, precompute) = photon_work(plan)?;
    Some(build_photon_map(
        traced,
        precompute.as_ref(),
        plan.keep_photon_positions,
        None,
    ))
}

/// Where the photon map of a render whose plan runs a photon pass comes from.
pub enum PhotonInput<'a> {
    /// The render traces it before the image (progressive photon mapping
    /// traces one per sample index during the passes instead).
    Trace,
    /// Built from photons traced beforehand (a photon file: the same map,
    /// so the same image). See [`photon_map_from`].
    Traced(TracedPhotons),
    /// Built by the caller (the viewer keeps one across renders), or
    /// `None`: no photon pass runs and the render has no map.
    Map(Option<&'a PhotonMap>),
}

/// What [`render`] starts from and how it is driven. The default renders
/// a fresh image to completion, tracing its photons, reporting nothing.
pub struct RenderSetup<'a> {
    /// The accumulation to continue (a resumed checkpoint, a viewer's
    /// earlier passes); `None`: a fresh one of the plan's size.
    pub start: Option<Accumulation>,
    /// Where the caustic map comes from.
    pub photons: PhotonInput<'a>,
    /// When to stop early, checkpoints and progress.
    pub control: RenderControl<'a>,
}

impl Default for RenderSetup<'_> {
    fn default() -> Self {
        Self {
            start: None,
            photons: PhotonInput::Trace,
            control: RenderControl::to_completion(&no_progress),
        }
    }
}

impl<'a> RenderSetup<'a> {
    /// Continue `start` instead of a fresh accumulation.
    pub fn continuing(self, start: Accumulation) -> Self {
        Self {
            start: Some(start),
            ..self
        }
    }

    /// Take the photon map from `photons`.
    pub fn photons(self, photons: PhotonInput<'a>) -> Self {
        Self { photons, ..self }
    }

    /// Drive the render by `control`.
    pub fn control(self, control: RenderControl<'a>) -> Self {
        Self { control, ..self }
    }

    /// Render to completion, reporting to `progress`.
    pub fn progress(self, progress: &'a (dyn Fn(u64, u64) + Sync)) -> Self {
        self.control(RenderControl::to_completion(progress))
    }
}

fn no_progress(_done: u64, _total: u64) {}

/// Renders `scene` as `plan` says, on the current rayon pool: every render
/// of caustic goes through here (files, resumes, shards, the viewer, the
/// benchmarks).
///
/// The photon pass runs first when the plan has one and `setup` asks for
/// it; a render cancelled before it begins, or with nothing left to render
/// (every pixel still sampling is at the limit, or none is: converged, or
/// another shard's), skips it and returns its start unchanged. Then the
/// pass loop continues the accumulation until every pixel has `plan.spp`
/// samples, the sample limit is reached or the render is stopped.
///
/// With progressive photon mapping ([`progressive_schedule`]) a given map
/// is not used: each pass renders its sample indices `s` one at a time,
/// every pixel's sample `s` with map `s`, traced just before (and dropped
/// once the next is needed, so one map lives at a time) and gathered within
/// `r_{s+1}`. A pixel's sample `s` is then the same whatever the passes,
/// threads, shards or interruptions, as without photons; the passes end at
/// the sample counts of an uninterrupted render's (4, 8, 16, …) even after
/// a resume mid-pass, so adaptive sampling decides at the same counts.
/// The last map is returned in [`RenderOutput::photon_map`] and the maps'
/// totals in the statistics.
///
/// # Panics
/// If `setup.start` is not `plan.width × plan.height` (callers check a
/// resumed checkpoint against the scene first), or as [`photon_map_from`].
pub fn render(scene: &Scene, accel: &dyn Accel, plan: &RenderPlan, setup: RenderSetup) -> RenderOutput {
    let begin = Instant::now();
    let RenderSetup {
        start,
        photons,
        control,
    } = setup;
    let control = &control;
    let (width, height) = (plan.width, plan.height);
    let start = start.unwrap_or_else(|| Accumulation::new(width, height));
    assert!(
        start.width == width && start.height == height && start.len() == width as usize * height as usize,
        "accumulation is {}×{}, the plan {width}×{height}",
        start.width,
        start.height
    );
    let spp = plan.spp.max(1);
    let limit = control.sample_limit.map_or(spp, |l| l.min(spp));
    let total = width as u64 * height as u64 * spp as u64;

    let idle = control.cancelled() || start.active_level().is_none_or(|level| level >= limit);
    let (given, traced) = match photons {
        PhotonInput::Map(map) => (map, None),
        _ if idle => (None, None),
        PhotonInput::Trace => (None, photon_pass_for(scene, accel, plan)),
        PhotonInput::Traced(photons) => (None, photon_map_from(photons, plan)),
    };
    let (traced_map, traced_stats) = match traced {
        Some((map, stats)) => (Some(Arc::new(map)), Some(stats)),
        None => (None, None),
    };
    let caustics = CausticsSource::new(progressive_schedule(plan), given.or(traced_map.as_deref()));
    let integrator = tracer(scene, accel, plan, caustics.fixed_map().map(|m| (m, None)));
    let aovs = AovTracer::new(scene, accel);
    let camera_samples = CameraSamples::new(scene, plan);
    let stop = Stop {
        cancel: control.cancel,
        deadline: control.deadline,
    };
    let done = AtomicU64::new(start.samples_taken());
    // Progressive photon mapping: the maps' totals and the latest map.
    let mut photon_totals: Option<PhotonStats> = None;
    let mut last_map: Option<Arc<PhotonMap>> = None;
    // A fresh render keeps the buffers the plan reads; a continued one
    // also keeps those its state has (a checkpoint goes on holding them).
    let buffers = if start.samples_taken() == 0 {
        plan.buffers()
    } else {
        plan.buffers().union(start.buffers())
    };
    let states = split_into_tiles(&start, buffers);
    // The tiles hold the state now: one copy of the image's buffers lives
    // during the passes, not two.
    drop(start);
    let last_checkpoint = Mutex::new(Instant::now());
    let mut stats = RenderStats::default();

    loop {
        // Between passes every pixel still sampling has the same count: the
        // place of adaptive sampling's decision (also right after a resume
        // from such a state; the decision is idempotent, see `mark_converged`).
        let mut level = active_level(&states).unwrap_or(limit);
        if let Some(a) = plan.adaptive {
            // The decision looks across tiles (a pixel's neighbourhood): on
            // a whole-image copy, made only when a decision is due.
            if level >= a.min_spp && level < limit {
                let mut acc = snapshot(&states, width, height);
                if mark_converged(&mut acc, &a, level) > 0 {
                    // Only the decisions go back to the tiles.
                    for state in &states {
                        let mut s = state.lock().unwrap_or_else(PoisonError::into_inner);
                        let tile = s.tile;
                        let tw = (tile.x1 - tile.x0) as usize;
                        for y in tile.y0..tile.y1 {
                            let row = y as usize * width as usize + tile.x0 as usize;
                            let local = (y - tile.y0) as usize * tw;
                            s.acc.converged[local..local + tw].copy_from_slice(&acc.converged[row..row + tw]);
                        }
                    }
                    level = acc.active_level().unwrap_or(limit);
                }
            }
        }
        if level >= limit || stop.is_due() {
            break;
        }
        let run_pass = |integrator: &dyn Integrator, target: u32| -> Vec<PassWork> {
            states
                .par_iter()
                .map(|state| {
                    let work = {
                        let mut state = state.lock().unwrap_or_else(PoisonError::into_inner);
                        render_tile_pass(&camera_samples, integrator, &aovs, plan, &mut state, target, &stop)
                    };
                    if work.samples > 0 {
                        let now = done.fetch_add(work.samples, Ordering::Relaxed) + work.samples;
                        (control.progress)(now, total);
                    }
                    if let Some(hook) = &control.checkpoint {
                        // One worker saves; the others skip and go on rendering.
                        if let Ok(mut last) = last_checkpoint.try_lock() {
                            if last.elapsed() >= hook.every {
                                (hook.save)(&snapshot(&states, width, height));
                                *last = Instant::now();
                            }
                        }
                    }
                    work
                })
                .collect()
        };
        let work = match &caustics {
            CausticsSource::None | CausticsSource::Map(_) => {
                run_pass(integrator.as_ref(), next_pass_target(level, limit))
            }
            CausticsSource::PerSample(schedule) => {
                // Progressive photon mapping: sample index by sample index,
                // each with its own map and radius. Every pixel still
                // sampling has at least `level` samples and needs every
                // index up to `target`, so each map serves them all.
                let target = aligned_pass_target(level, limit);
                let mut work = Vec::new();
                let mut radii = schedule.radii_from(level);
                for s in level..target {
                    if stop.is_due() {
                        break;
                    }
                    // Free the previous map first: one map lives at a time.
                    drop(last_map.take());
                    let (map, map_stats) = schedule.trace(scene, accel, s);
                    photon_totals.get_or_insert_with(PhotonStats::default).add(&map_stats);
                    let pass_tracer = tracer(scene, accel, plan, Some((&map, Some(schedule.gather_at(&radii)))));
                    work.extend(run_pass(pass_tracer.as_ref(), s + 1));
                    drop(pass_tracer);
                    last_map = Some(Arc::new(map));
                    radii.advance();
                }
                work
            }
        };
        for w in work {
            stats.rays += w.rays;
            stats.samples += w.samples;
            stats.dropped_samples += w.dropped;
        }
        if stop.is_due() {
            break;
        }
    }

    // The integrator borrows the traced map, which the output takes.
    drop(integrator);
    let accumulation = assemble(states, width, height);
    stats.wall_time = begin.elapsed();
    stats.photons = photon_totals.or(traced_stats);
    RenderOutput {
        film: accumulation.to_film(),
        complete: accumulation.is_complete(spp),
        timed_out: control.deadline.is_some_and(|d| Instant::now() >= d) && !accumulation.is_complete(spp),
        accumulation,
        stats,
        photon_map: last_map.or(traced_map),
    }
}

/// The sample count at the end of the pass of an uninterrupted render that
/// `level` falls in: the first of 4, 8, 16, 32, 48, … ([`next_pass_target`]
/// from 0) above `level`, at most `limit`. Progressive photon mapping
/// renders a pass sample index by sample index, so an interrupted render
/// can stop between them; resuming to this target keeps the passes (and
/// adaptive sampling's decisions between them) those of the uninterrupted
/// render.
pub fn aligned_pass_target(level: u32, limit: u32) -> u32 {
    let mut t = 0;
    while t <= level {
        let next = next_pass_target(t, limit);
        if next == t {
            break;
        }
        t = next;
    }
    t.min(limit)
}

/// The integrator of a render, with `caustics` (a map and, when given, the
/// gather to use instead of the plan's: progressive photon mapping's fixed
/// radius) when the plan runs a photon pass.
fn tracer<'a>(
    scene: &'a Scene,
    accel: &'a dyn Accel,
    plan: &'a RenderPlan,
    caustics: Option<(&'a PhotonMap, Option<GatherParams>)>,
) -> Box<dyn Integrator + 'a> {
    match plan.integrator {
        IntegratorKind::Whitted => {
            let mut w = Whitted::new(scene, accel, plan);
            match caustics {
                Some((map, None)) => w = w.with_photons(map),
                Some((map, Some(g))) => w = w.with_photons_gathered(map, g),
                None => {}
            }
            Box::new(w)
        }
        // Media bounded by surfaces, or null surfaces (Mitsuba's `volpath`).
        IntegratorKind::Path if scene.is_volumetric() => Box::new(VolumePathTracer::new(scene, accel, plan)),
        IntegratorKind::Path => {
            let mut p = PathTracer::new(scene, accel, plan);
            match caustics {
                Some((map, None)) => p = p.with_photons(map),
                Some((map, Some(g))) => p = p.with_photons_gathered(map, g),
                None => {}
            }
            Box::new(p)
        }
    }
}

/// When workers stop before their next pixel: a cancel flag, a deadline.
struct Stop<'a> {
    cancel: Option<&'a AtomicBool>,
    deadline: Option<Instant>,
}

impl Stop<'_> {
    fn is_due(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(Ordering::Relaxed)) || self.deadline.is_some_and(|d| Instant::now() >= d)
    }
}

fn tiles_of(width: u32, height: u32) -> Vec<Tile> {
    let mut tiles = Vec::new();
    for y0 in (0..height).step_by(TILE_SIZE as usize) {
        for x0 in (0..width).step_by(TILE_SIZE as usize) {
            tiles.push(Tile {
                x0,
                y0,
                x1: (x0 + TILE_SIZE).min(width),
                y1: (y0 + TILE_SIZE).min(height),
            });
        }
    }
    tiles
}

fn split_into_tiles(acc: &Accumulation, buffers: Buffers) -> Vec<Mutex<TileState>> {
    tiles_of(acc.width, acc.height)
        .into_iter()
        .map(|tile| {
            Mutex::new(TileState {
                tile,
                acc: acc.region_with(tile.x0, tile.y0, tile.x1, tile.y1, buffers),
            })
        })
        .collect()
}

/// The whole accumulation, tile by tile (each tile locked while copied, so
/// every pixel holds whole samples).
fn snapshot(states: &[Mutex<TileState>], width: u32, height: u32) -> Accumulation {
    let mut acc = Accumulation::with_buffers(width, height, tile_buffers(states));
    for state in states {
        let s = state.lock().unwrap_or_else(PoisonError::into_inner);
        acc.put_region(s.tile.x0, s.tile.y0, &s.acc);
    }
    acc
}

/// The buffers the tiles keep (all alike).
fn tile_buffers(states: &[Mutex<TileState>]) -> Buffers {
    states.first().map_or(Buffers::ALL, |s| {
        s.lock().unwrap_or_else(PoisonError::into_inner).acc.buffers()
    })
}

/// The whole accumulation from the tiles, each freed once copied.
fn assemble(states: Vec<Mutex<TileState>>, width: u32, height: u32) -> Accumulation {
    let mut acc = Accumulation::with_buffers(width, height, tile_buffers(&states));
    for state in states {
        let s = state.into_inner().unwrap_or_else(PoisonError::into_inner);
        acc.put_region(s.tile.x0, s.tile.y0, &s.acc);
    }
    acc
}

/// Fewest samples taken by a pixel still sampling, over every tile (`None`
/// when every pixel has converged): [`Accumulation::active_level`] without
/// a whole-image copy.
fn active_level(states: &[Mutex<TileState>]) -> Option<u32> {
    states
        .iter()
        .filter_map(|state| state.lock().unwrap_or_else(PoisonError::into_inner).acc.active_level())
        .min()
}

/// Adaptive sampling's decision between two passes, when every pixel still
/// sampling has `level` samples: such a pixel (with at least `min_spp`)
/// stops when the root mean square of the estimated relative errors of the
/// pixels sampling up to `level` in its 5 × 5 neighbourhood (itself
/// excluded) is at most the threshold: `threshold` for
/// [`AdaptiveGoal::Pixel`], `threshold · √(level / min_spp)` for
/// [`AdaptiveGoal::Image`] (Neyman allocation: a pixel of variance σ² goes
/// on while σ²/n², what one more sample removes from its squared error,
/// exceeds a fixed price, so it ends with n ∝ σ). Returns the number of
/// pixels stopped.
///
/// The decision never looks at the pixel's own samples: its sample count
/// is then independent of the samples it averages, which keeps its mean
/// unbiased (Kirk & Arvo 1991, "Unbiased Sampling Techniques for Image
/// Synthesis": a pixel's sample count must not depend on its own samples).
/// The neighbours' estimates (`Accumulation::relative_error`, from the two
/// half buffers) stand in for the pixel's, since noise varies smoothly
/// across an image; each one is a single noisy draw of its pixel's error,
/// so their mean square over the neighbourhood is the estimate (a pixel
/// next to a caustic or a glass edge keeps sampling while its neighbourhood
/// is noisy). Pixels that stopped at an earlier level no longer count:
/// their estimates are frozen, and one stopped early would hold its
/// neighbours back forever. Pixels stopped at `level` itself still count,
/// which makes the decision idempotent: a render resumed from a checkpoint
/// taken just after it decides the same again (bit-exact resume).
///
/// Does nothing unless every pixel still sampling has exactly `level`
/// samples (a render stopped in the middle of a pass finishes the pass first).
pub fn mark_converged(acc: &mut Accumulation, adaptive: &Adaptive, level: u32) -> usize {
    let min_spp = adaptive.min_spp;
    let threshold = match adaptive.goal {
        AdaptiveGoal::Pixel => adaptive.threshold,
        AdaptiveGoal::Image => adaptive.threshold * (level as f32 / min_spp.max(1) as f32).sqrt(),
    };
    let sampling = |i: usize| !acc.converged[i] || acc.taken[i] == level;
    if (0..acc.len()).any(|i| !acc.converged[i] && acc.taken[i] != level) {
        return 0;
    }
    let (w, h) = (acc.width as i64, acc.height as i64);
    let errors = acc.error_map();
    let counted: Vec<bool> = (0..acc.len()).map(sampling).collect();
    let mut stopped = 0;
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            if acc.converged[i] || acc.taken[i] < min_spp {
                continue;
            }
            let mut squares = 0.0f32;
            let mut neighbours = 0;
            for dy in -2..=2 {
                for dx in -2..=2 {
                    let (nx, ny) = (x + dx, y + dy);
                    if (dx, dy) == (0, 0) || nx < 0 || ny < 0 || nx >= w || ny >= h {
                        continue;
                    }
                    let j = (ny * w + nx) as usize;
                    if !counted[j] {
                        continue;
                    }
                    squares += errors[j] * errors[j];
                    neighbours += 1;
                }
            }
            if neighbours == 0 || (squares / neighbours as f32).sqrt() <= threshold {
                acc.converged[i] = true;
                stopped += 1;
            }
        }
    }
    stopped
}

/// The camera rays of a render's pixel samples: what is shared by every
/// pixel, computed once per render.
struct CameraSamples<'a> {
    camera: &'a crate::scene::Camera,
    /// The camera's rays of this image size.
    image: crate::scene::ImageRays<'a>,
    sampler: SamplerKind,
    seed: u64,
    width: u32,
    spp: u32,
    grid: (u32, u32),
}

/// The camera rays of one pixel's samples.
struct PixelSamples<'a> {
    render: &'a CameraSamples<'a>,
    x: u32,
    y: u32,
    /// Row-major pixel index (the random streams' key).
    pixel: u64,
    /// Seed of the pixel's order of sub-pixel strata.
    order_seed: u32,
}

impl<'a> CameraSamples<'a> {
    fn new(scene: &'a Scene, plan: &RenderPlan) -> Self {
        let spp = plan.spp.max(1);
        Self {
            camera: &scene.camera,
            image: scene.camera.image(plan.width, plan.height),
            sampler: plan.sampler,
            seed: plan.seed,
            width: plan.width,
            spp,
            grid: grid_for(spp),
        }
    }

    fn pixel(&'a self, x: u32, y: u32) -> PixelSamples<'a> {
        let pixel = y as u64 * self.width as u64 + x as u64;
        PixelSamples {
            render: self,
            x,
            y,
            pixel,
            order_seed: crate::math::rng::mix64(self.seed ^ crate::math::rng::mix64(pixel)) as u32,
        }
    }
}

impl PixelSamples<'_> {
    /// A sampler of this pixel, which [`ray`](Self::ray) re-keys to each
    /// sample (what depends on the pixel alone is derived once).
    fn sampler(&self) -> Sampler {
        let r = self.render;
        Sampler::new(r.sampler, r.seed, self.pixel, 0)
    }

    /// Sample `k`'s camera ray, `rng` (this pixel's sampler) re-keyed to
    /// sample `k` and the ray's two dimensions drawn from it.
    fn ray(&self, k: u32, rng: &mut Sampler) -> crate::math::Ray {
        let r = self.render;
        rng.restart(k as u64);
        let sub = match r.sampler {
            // Stratified jittered sub-pixel position (gx × gy = spp), the
            // strata visited in a per-pixel random order: a pixel stopped
            // before its last sample is still unbiased.
            SamplerKind::Independent => stratified(permute(k, r.spp, self.order_seed), r.grid.0, r.grid.1, rng.vec2()),
            // Sobol points are stratified over the pixel's samples.
            SamplerKind::Sobol => rng.vec2(),
        };
        // The pixel filter places the sample (filter importance sampling).
        let sub = r.camera.filter.sample(sub);
        let (x, y) = (self.x as f32 + sub.x, self.y as f32 + sub.y);
        // A thin lens draws its two dimensions next; a pinhole none.
        if r.camera.has_lens() {
            r.image.ray_through_lens(x, y, rng.vec2())
        } else {
            r.image.ray(x, y)
        }
    }
}

/// Traces the albedo and normal of the samples `acc` already holds, for an
/// accumulation read from a checkpoint without them (format 3 or older):
/// the same camera rays as the render's, added in increasing sample index
/// from zero, so the sums are bit for bit those of an uninterrupted render.
/// Replaces whatever AOV sums `acc` held.
pub fn retrace_aovs(scene: &Scene, accel: &dyn Accel, plan: &RenderPlan, acc: &mut Accumulation) {
    let aovs = AovTracer::new(scene, accel);
    let width = acc.width as usize;
    let camera_samples = CameraSamples::new(scene, plan);
    let sums: Vec<(Vec3, Vec3)> = (0..acc.len())
        .into_par_iter()
        .map(|i| {
            let samples = camera_samples.pixel((i % width) as u32, (i / width) as u32);
            let (mut albedo, mut normal) = (Vec3A::ZERO, Vec3A::ZERO);
            let mut rng = samples.sampler();
            for k in 0..acc.taken[i].min(AOV_SAMPLES) {
                let (a, n) = aovs.trace(&samples.ray(k, &mut rng));
                albedo += a;
                normal += n;
            }
            (Vec3::from(albedo), Vec3::from(normal))
        })
        .collect();
    (acc.albedo, acc.normal) = sums.into_iter().unzip();
}

/// Brings every pixel of the tile to `target` samples (pixels already there
/// are left alone), in increasing sample index, the first [`AOV_SAMPLES`]
/// of them also tracing the albedo and normal. Stops before the next pixel
/// once `cancel` is set.
fn render_tile_pass(
    camera_samples: &CameraSamples,
    integrator: &dyn Integrator,
    aovs: &AovTracer,
    plan: &RenderPlan,
    state: &mut TileState,
    target: u32,
    stop: &Stop,
) -> PassWork {
    let seed = plan.seed;
    let tile = state.tile;
    let tw = (tile.x1 - tile.x0) as usize;
    let acc = &mut state.acc;
    let buffers = acc.buffers();
    let mut out = PassWork::default();
    let mut sites = SiteCache::default();
    for y in tile.y0..tile.y1 {
        for x in tile.x0..tile.x1 {
            if stop.is_due() {
                return out;
            }
            let i = (y - tile.y0) as usize * tw + (x - tile.x0) as usize;
            let first = acc.taken[i];
            if first >= target || acc.converged[i] {
                continue;
            }
            let samples = camera_samples.pixel(x, y);
            let strata = PixelStrata::new(plan, seed, samples.pixel);
            // Continue the f32 running sums exactly where they stopped.
            let mut sum = Vec3A::from(acc.sum[i]);
            let mut kept = acc.kept[i];
            let (mut odd, mut odd_kept) = match buffers.noise {
                true => (Vec3A::from(acc.odd[i]), acc.odd_kept[i]),
                false => (Vec3A::ZERO, 0),
            };
            let (mut albedo, mut normal) = match buffers.aovs {
                true => (Vec3A::from(acc.albedo[i]), Vec3A::from(acc.normal[i])),
                false => (Vec3A::ZERO, Vec3A::ZERO),
            };
            let mut rng = samples.sampler();
            for k in first..target {
                let ray = samples.ray(k, &mut rng);
                out.rays.camera += 1;
                // The camera ray's hit, when the AOVs found it first.
                let mut first = None;
                if plan.aovs && buffers.aovs && k < AOV_SAMPLES {
                    // No random numbers: the sample below is unchanged.
                    let (a, n, hit) = aovs.trace_keeping_hit(&ray);
                    albedo += a;
                    normal += n;
                    first = Some(hit);
                }
                let mut ctx = SampleContext {
                    rng: &mut rng,
                    slot: strata.slot(k),
                    light_seed: strata.light_seed(),
                    fresnel_stratum: strata.fresnel_stratum(k),
                    counts: &mut out.rays,
                    sites: &mut sites,
                };
                let l = integrator.radiance(&ray, first.as_ref(), &mut ctx);
                out.samples += 1;
                if l.is_finite() {
                    let l = l.min(Vec3A::splat(SAMPLE_RADIANCE_LIMIT));
                    sum += l;
                    kept += 1;
                    if k % 2 == 1 {
                        odd += l;
                        odd_kept += 1;
                    }
                } else {
                    out.dropped += 1;
                }
            }
            acc.sum[i] = Vec3::from(sum);
            acc.kept[i] = kept;
            if buffers.noise {
                acc.odd[i] = Vec3::from(odd);
                acc.odd_kept[i] = odd_kept;
            }
            if buffers.aovs {
                acc.albedo[i] = Vec3::from(albedo);
                acc.normal[i] = Vec3::from(normal);
            }
            acc.taken[i] = target;
        }
    }
    out
}

/// Largest radiance one sample adds to a pixel's f32 running sum:
/// `f32::MAX / 2³²`, so that a `u32` count of samples can never overflow the
/// sum to infinity (finite samples near `f32::MAX` did; found by
/// `caustic stress`, case 7). Radiance of a real scene is many orders of
/// magnitude below it (≈ 7.9e28), so ordinary images do not change by a bit.
pub const SAMPLE_RADIANCE_LIMIT: f32 = f32::MAX / 4_294_967_296.0;

/// The per-pixel assignments of spread sampling, shared by a pixel's samples
/// (identical however the samples are split into passes).
///
/// * Sample `k` takes the area lights' strata share `k mod spp`; the
///   strata of the light grid are visited in a per-pixel scrambled order
///   ([`stratum_order`](crate::math::sampling::stratum_order), keyed by
///   `light_seed`) that is independent of the sub-pixel position's, so each
///   sub-pixel position sees every stratum equally often in expectation, and
///   the first samples of a pixel cover the light evenly.
/// * Its first Fresnel choice takes the stratum `(a·k + b) mod spp`, with
///   `a` coprime to `spp` and `b` random: a permutation of the samples,
///   independent of the strata share, whose stratum is uniform for every
///   sample (so each choice keeps its probability R: unbiased).
#[derive(Clone, Copy, Debug)]
pub struct PixelStrata {
    spp: u32,
    /// Key of the order in which the area lights' strata are visited.
    light_seed: u32,
    /// `(a, b)` of the Fresnel permutation; `None` when not spreading.
    fresnel: Option<(u32, u32)>,
}

impl PixelStrata {
    /// The assignments of pixel `pixel` (index `y·width + x`) under `seed`.
    pub fn new(plan: &RenderPlan, seed: u64, pixel: u64) -> Self {
        Self::with(plan.spp, plan.spread(), seed, pixel)
    }

    fn with(spp: u32, spread: bool, seed: u64, pixel: u64) -> Self {
        let spp = spp.max(1);
        if !spread {
            return Self {
                spp,
                light_seed: 0,
                fresnel: None,
            };
        }
        let mut rng = Rng::new(seed, Domain::Pixel, pixel, u64::MAX);
        let light_seed = rng.below(u32::MAX);
        let fresnel_add = rng.below(spp);
        // A multiplier coprime to spp (1 when none is drawn in a few tries).
        let fresnel_mul = (0..4)
            .map(|_| rng.below(spp))
            .find(|&a| a > 0 && gcd(a, spp) == 1)
            .unwrap_or(1);
        Self {
            spp,
            light_seed,
            fresnel: Some((fresnel_mul, fresnel_add)),
        }
    }

    /// The strata share of sample `k` (0 when not spreading).
    pub fn slot(&self, k: u32) -> u32 {
        k % self.spp
    }

    /// The key of the pixel's order of area-light strata.
    pub fn light_seed(&self) -> u32 {
        self.light_seed
    }

    /// The stratum of sample `k`'s first Fresnel choice (`None` when not spreading).
    pub fn fresnel_stratum(&self, k: u32) -> Option<u32> {
        self.fresnel
            .map(|(a, b)| ((a as u64 * k as u64 + b as u64) % self.spp as u64) as u32)
    }
}

/// Greatest common divisor (Euclid).
fn gcd(mut a: u32, mut b: u32) -> u32 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixel_strata_permute_the_samples() {
        for spp in [1u32, 2, 7, 16, 20, 64] {
            for pixel in 0..50u64 {
                let strata = PixelStrata::with(spp, true, 3, pixel);
                let mut slots: Vec<u32> = (0..spp).map(|k| strata.slot(k)).collect();
                let mut fresnel: Vec<u32> = (0..spp).map(|k| strata.fresnel_stratum(k).unwrap()).collect();
                slots.sort_unstable();
                fresnel.sort_unstable();
                let all: Vec<u32> = (0..spp).collect();
                assert_eq!(slots, all, "spp {spp}, pixel {pixel}");
                assert_eq!(fresnel, all, "spp {spp}, pixel {pixel}");
            }
        }
        let split = PixelStrata::with(20, false, 3, 9);
        assert_eq!((split.slot(5), split.fresnel_stratum(5)), (5, None));
    }

    #[test]
    fn stratified_fresnel_choice_keeps_its_probability() {
        // Over many pixels every sample reflects with probability R, and in
        // each pixel the count of reflections is floor or ceil of R·spp.
        let (spp, r) = (20u32, 0.13f32);
        let mut per_sample = vec![0u32; spp as usize];
        let pixels = 20_000u64;
        for pixel in 0..pixels {
            let strata = PixelStrata::with(spp, true, 11, pixel);
            let mut rng = Rng::new(11, Domain::Analysis, 99, pixel);
            let mut count = 0;
            for k in 0..spp {
                let u = (strata.fresnel_stratum(k).unwrap() as f32 + rng.f32()) / spp as f32;
                if u < r {
                    per_sample[k as usize] += 1;
                    count += 1;
                }
            }
            assert!(count == 2 || count == 3, "pixel {pixel}: {count} reflections");
        }
        for (k, &n) in per_sample.iter().enumerate() {
            let p = n as f64 / pixels as f64;
            assert!(
                (p - r as f64).abs() < 0.012,
                "sample {k}: reflects with probability {p}"
            );
        }
    }

    #[test]
    fn passes_double_then_step_by_the_cap() {
        let mut level = 0;
        let mut targets = Vec::new();
        while level < 70 {
            level = next_pass_target(level, 70);
            targets.push(level);
        }
        assert_eq!(targets, [4, 8, 16, 32, 48, 64, 70]);
        assert_eq!(next_pass_target(0, 1), 1);
        assert_eq!(next_pass_target(3, 4), 4);
        assert_eq!(next_pass_target(3, 20), 7);
        assert_eq!(next_pass_target(5, 5), 5);
        // A level inside a pass resumes to that pass's end.
        for (level, limit, target) in [
            (0, 70, 4),
            (5, 70, 8),
            (8, 70, 16),
            (33, 70, 48),
            (65, 70, 70),
            (3, 3, 3),
        ] {
            assert_eq!(
                aligned_pass_target(level, limit),
                target,
                "level {level}, limit {limit}"
            );
        }
        for level in [0u32, 4, 8, 16, 32, 48] {
            assert_eq!(aligned_pass_target(level, 70), next_pass_target(level, 70));
        }
    }

    #[test]
    fn tiles_split_and_snapshot_round_trip() {
        let mut acc = Accumulation::new(70, 33);
        for i in 0..acc.len() {
            acc.sum[i] = Vec3::splat(i as f32);
            acc.taken[i] = i as u32 % 7;
            acc.kept[i] = i as u32 % 5;
        }
        let states = split_into_tiles(&acc, acc.buffers());
        assert_eq!(states.len(), 3 * 2);
        assert_eq!(snapshot(&states, 70, 33), acc);
    }
}
