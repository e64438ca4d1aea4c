//! The render loop: tiles on rayon, one seeded random stream per pixel
//! sample, box-filtered pixels. Each tile is computed independently and the
//! tiles are assembled in a fixed order, so the image is bit-identical for
//! any number of threads.

use super::photon::{photon_pass_with, GatherMode, GatherParams, PhotonMap, PhotonStats};
use super::plan::{PhotonPlan, RenderPlan};
use super::whitted::{RayCounts, SampleContext, Whitted};
use crate::accel::Accel;
use crate::film::Film;
use crate::math::rng::Domain;
use crate::math::sampling::{grid_for, stratified};
use crate::math::{Rng, Vec2, Vec3, Vec3A};
use crate::scene::Scene;
use rayon::prelude::*;
use std::fmt;
use std::num::NonZero;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Tile edge in pixels: big enough to amortise scheduling, small enough to
/// balance 2-64 threads on a 1080p image.
pub const TILE_SIZE: u32 = 32;

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
    /// Linear HDR film.
    pub film: Film,
    /// Statistics.
    pub stats: RenderStats,
    /// The caustic map used, when the photon pass ran (for the debug overlay).
    pub photon_map: Option<Arc<PhotonMap>>,
}

struct Tile {
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
}

struct TileResult {
    pixels: Vec<Vec3>,
    rays: RayCounts,
    samples: u64,
    dropped: u64,
}

/// Renders `scene` as `plan` says, on the current rayon pool: the photon
/// pass first when the plan runs it, then the image.
/// `progress(done_pixels, total_pixels)` is called after each tile (from
/// worker threads, in completion order).
pub fn render(
    scene: &Scene,
    accel: &dyn Accel,
    plan: &RenderPlan,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> RenderOutput {
    let start = Instant::now();
    let photons = match plan.photons {
        PhotonPlan::Run {
            count,
            k,
            max_radius,
            cone_k,
            gather,
            ..
        } => {
            let precompute = match gather {
                GatherMode::Direct => None,
                GatherMode::Precomputed => Some(GatherParams {
                    k: NonZero::new(k.max(1) as usize).expect("k ≥ 1"),
                    max_radius,
                    cone_k,
                }),
            };
            Some(photon_pass_with(scene, accel, count, precompute.as_ref()))
        }
        _ => None,
    };
    let (map, photon_stats) = match photons {
        Some((map, stats)) => (Some(Arc::new(map)), Some(stats)),
        None => (None, None),
    };
    let mut out = render_with_photons(scene, accel, plan, map.as_deref(), progress);
    out.stats.wall_time = start.elapsed();
    out.stats.photons = photon_stats;
    out.photon_map = map;
    out
}

/// Renders the image with a given caustic map (or none), without running
/// the photon pass: for callers that build or reuse the map themselves.
pub fn render_with_photons(
    scene: &Scene,
    accel: &dyn Accel,
    plan: &RenderPlan,
    photons: Option<&PhotonMap>,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> RenderOutput {
    let start = Instant::now();
    let (width, height) = (plan.width, plan.height);
    let total = width as u64 * height as u64;
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
    let mut integrator = Whitted::new(scene, accel, plan);
    if let Some(map) = photons {
        integrator = integrator.with_photons(map);
    }
    let done = AtomicU64::new(0);
    let results: Vec<TileResult> = tiles
        .par_iter()
        .map(|tile| {
            let result = render_tile(scene, &integrator, plan, tile);
            let n = result.pixels.len() as u64;
            let now = done.fetch_add(n, Ordering::Relaxed) + n;
            progress(now, total);
            result
        })
        .collect();

    let mut film = Film::new(width, height);
    let mut stats = RenderStats::default();
    for (tile, result) in tiles.iter().zip(&results) {
        let tw = (tile.x1 - tile.x0) as usize;
        for (i, p) in result.pixels.iter().enumerate() {
            film.set(tile.x0 + (i % tw) as u32, tile.y0 + (i / tw) as u32, *p);
        }
        stats.rays += result.rays;
        stats.samples += result.samples;
        stats.dropped_samples += result.dropped;
    }
    stats.wall_time = start.elapsed();
    RenderOutput {
        film,
        stats,
        photon_map: None,
    }
}

fn render_tile(scene: &Scene, integrator: &Whitted, plan: &RenderPlan, tile: &Tile) -> TileResult {
    let spp = plan.spp.max(1);
    let (gx, gy) = grid_for(spp);
    let seed = plan.seed;
    let camera = &scene.camera;
    let mut out = TileResult {
        pixels: Vec::with_capacity(((tile.x1 - tile.x0) * (tile.y1 - tile.y0)) as usize),
        rays: RayCounts::default(),
        samples: 0,
        dropped: 0,
    };
    for y in tile.y0..tile.y1 {
        for x in tile.x0..tile.x1 {
            let pixel = y as u64 * plan.width as u64 + x as u64;
            // Spread sampling: sample k takes the strata share
            // (k + rotation) mod spp. The per-pixel random rotation decouples
            // the share from the sub-pixel stratum k, so each sub-pixel
            // position sees every share equally often in expectation.
            let rotation = if plan.spread() {
                Rng::new(seed, Domain::Pixel, pixel, u64::MAX).below(spp)
            } else {
                0
            };
            let mut sum = Vec3A::ZERO;
            // The same sum in f64: finite samples near f32::MAX overflow the
            // f32 sum to infinity (found by `caustic stress`, case 7).
            let mut sum64 = glam::DVec3::ZERO;
            let mut kept = 0u32;
            for k in 0..spp {
                let mut rng = Rng::for_pixel(seed, pixel, k as u64);
                let (jx, jy) = rng.f32x2();
                // Stratified jittered sub-pixel position (gx × gy = spp).
                let sub = stratified(k, gx, gy, Vec2::new(jx, jy));
                let ray = camera.ray(x as f32 + sub.x, y as f32 + sub.y, plan.width, plan.height);
                out.rays.camera += 1;
                let mut ctx = SampleContext {
                    rng,
                    slot: (k + rotation) % spp,
                    counts: &mut out.rays,
                };
                let l = integrator.radiance(&ray, 0, &mut ctx);
                out.samples += 1;
                if l.is_finite() {
                    sum += l;
                    sum64 += l.as_dvec3();
                    kept += 1;
                } else {
                    out.dropped += 1;
                }
            }
            // Box filter: the mean of the kept samples.
            let mut value = if kept > 0 { sum / kept as f32 } else { Vec3A::ZERO };
            if !value.is_finite() {
                // A mean of finite f32 values is at most their maximum, so
                // the f64 mean is finite in f32; the f32 result is kept
                // otherwise, so ordinary images do not change by a bit.
                value = (sum64 / kept as f64).as_vec3a();
            }
            out.pixels.push(Vec3::from(value));
        }
    }
    out
}
