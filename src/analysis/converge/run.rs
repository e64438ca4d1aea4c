//! Running the curves: one accelerator per kind, a warm-up render, the sample
//! budgets, and the doubling search that resolves the time budgets; every
//! render timed and measured against the reference.

use super::budget::Budget;
use super::metrics::{check_same_size, error_metrics, ErrorMetrics};
use super::ConvergeError;
use crate::accel::{self, Accel, AccelKind, AccelOptions};
use crate::film::denoise::DenoiseQuality;
use crate::film::Film;
use crate::integrator::{render, RenderPlan};
use crate::limits::{check_image_limits, check_photon_count, MAX_SPP};
use crate::math::SamplerKind;
use crate::scene::{GatherMode, LoadedScene, RenderSettings, Scene};
use std::time::Instant;

/// One curve: an accelerator, optionally a photon gather mode and a sampler
/// that override the scene's, and fixed or adaptive sampling.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CurveSpec {
    /// Accelerator.
    pub accel: AccelKind,
    /// Gather mode (`None`: the scene's `[photons] gather`).
    pub gather: Option<GatherMode>,
    /// Sampler (`None`: the scene's, see `RenderSettings::sampler_kind`).
    pub sampler: Option<SamplerKind>,
    /// Adaptive sampling: the curve's points are noise thresholds, not spp.
    pub adaptive: bool,
    /// Each image is denoised (Open Image Denoise) before it is measured,
    /// the denoising timed with the render.
    pub denoise: bool,
}

impl CurveSpec {
    /// A fixed-spp curve with the scene's gather mode and sampler.
    pub fn fixed(accel: AccelKind) -> Self {
        Self {
            accel,
            gather: None,
            sampler: None,
            adaptive: false,
            denoise: false,
        }
    }

    /// `"embree"`, then `/direct` or `/precomputed` with a gather mode,
    /// `/sobol` or `/independent` with a sampler, `/adaptive` when adaptive.
    pub fn name(&self) -> String {
        let mut name = self.accel.name().to_string();
        match self.gather {
            None => {}
            Some(GatherMode::Direct) => name.push_str("/direct"),
            Some(GatherMode::Precomputed) => name.push_str("/precomputed"),
        }
        if let Some(s) = self.sampler {
            name.push('/');
            name.push_str(s.name());
        }
        if self.adaptive {
            name.push_str("/adaptive");
        }
        if self.denoise {
            name.push_str("/denoised");
        }
        name
    }

    /// These curves, each followed by its denoised copy when `denoise`.
    pub fn with_denoise(curves: &[CurveSpec], denoise: bool) -> Vec<CurveSpec> {
        curves
            .iter()
            .flat_map(|&c| {
                let copy = denoise.then_some(CurveSpec { denoise: true, ..c });
                std::iter::once(c).chain(copy)
            })
            .collect()
    }

    /// Every accelerator crossed with every gather mode (`gathers` empty:
    /// the scene's mode only), accelerators outermost.
    pub fn cross(accels: &[AccelKind], gathers: &[GatherMode]) -> Vec<CurveSpec> {
        let mut out = Vec::new();
        for &accel in accels {
            if gathers.is_empty() {
                out.push(CurveSpec::fixed(accel));
            }
            for &g in gathers {
                out.push(CurveSpec {
                    gather: Some(g),
                    ..CurveSpec::fixed(accel)
                });
            }
        }
        out
    }

    /// These curves crossed with every sampler (`samplers` empty: as they
    /// are), each also as an adaptive curve when `adaptive`.
    pub fn with_samplers(curves: &[CurveSpec], samplers: &[SamplerKind], adaptive: bool) -> Vec<CurveSpec> {
        let mut out = Vec::new();
        for c in curves {
            let sampled: Vec<CurveSpec> = if samplers.is_empty() {
                vec![*c]
            } else {
                samplers.iter().map(|&s| CurveSpec { sampler: Some(s), ..*c }).collect()
            };
            for s in sampled {
                out.push(s);
                if adaptive {
                    out.push(CurveSpec { adaptive: true, ..s });
                }
            }
        }
        out
    }
}

/// What a convergence run does.
#[derive(Clone, Debug)]
pub struct ConvergeOptions {
    /// The budgets, in the order they are reported.
    pub budgets: Vec<Budget>,
    /// The curves.
    pub curves: Vec<CurveSpec>,
    /// Photons per spp for budgets without an explicit count (`None`: the
    /// scene's photon count for every such budget).
    pub photons_per_spp: Option<u64>,
    /// ε of relMSE.
    pub epsilon: f64,
    /// Accelerator build options.
    pub accel: AccelOptions,
    /// Noise thresholds of the adaptive curves (their budgets).
    pub thresholds: Vec<f32>,
    /// Most samples per pixel of an adaptive render.
    pub max_spp: u32,
    /// Search each curve for the time at which its relMSE reaches this.
    pub target_relmse: Option<f64>,
}

/// One render of a convergence run.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    /// Curve name ([`CurveSpec::name`]).
    pub curve: String,
    /// The budget this render answers.
    pub budget: Budget,
    /// Samples per pixel rendered.
    pub spp: u32,
    /// Photons emitted (0 when the render plan skipped the photon pass).
    pub photons: u64,
    /// Wall time of the photon pass and the render, in seconds.
    pub seconds: f64,
    /// The photon pass's part of `seconds` (tracing, the map's tree and
    /// the irradiance precomputation; 0 without a photon pass).
    pub photon_seconds: f64,
    /// Accelerator build time of the curve, in seconds (not in `seconds`).
    pub build_seconds: f64,
    /// Errors against the reference.
    pub error: ErrorMetrics,
    /// False only for a time budget that even 1 spp exceeded.
    pub within_budget: bool,
}

/// A render at one (spp, photons) point.
#[derive(Clone, Copy, Debug)]
struct Run {
    spp: u32,
    photons: u64,
    seconds: f64,
    photon_seconds: f64,
    error: ErrorMetrics,
}

/// For each time budget, the index in `ladder` (spp increasing) of the
/// largest render whose measured time fits, and whether one fits at all (if
/// not: index 0, the cheapest).
pub fn pick_within(ladder_seconds: &[f64], budget: f64) -> (usize, bool) {
    match ladder_seconds.iter().rposition(|&t| t <= budget) {
        Some(i) => (i, true),
        None => (0, false),
    }
}

/// Predicted time of the next ladder step (twice the spp): linear
/// extrapolation in spp from the last two times, or twice the only one.
pub fn predict_next(seconds: &[f64]) -> f64 {
    match seconds {
        [] => 0.0,
        [t] => 2.0 * t,
        [.., a, b] => b + 2.0 * (b - a).max(0.0),
    }
}

/// Renders shorter than this many seconds are timed [`SHORT_RENDER_RUNS`] times.
const SHORT_RENDER_SECONDS: f64 = 1.0;

/// Runs of a short render; the fastest is reported.
const SHORT_RENDER_RUNS: usize = 3;

/// Photons of the untimed warm-up render (at most).
const WARM_UP_PHOTONS: u64 = 100_000;

struct Renderer<'a> {
    scene: Scene,
    settings: RenderSettings,
    reference: &'a Film,
    epsilon: f64,
    photons_per_spp: Option<u64>,
    /// The scene's own photon count: `configure` overwrites the scene's
    /// for each render (the warm-up's included), so it is kept apart.
    scene_photons: u64,
}

impl Renderer<'_> {
    fn default_photons(&self, spp: u32) -> u64 {
        match self.photons_per_spp {
            Some(r) => r.saturating_mul(spp as u64),
            None => self.scene_photons,
        }
    }

    /// Sets the scene to `curve`'s gather mode and sampler, `spp`,
    /// `photons` and the noise threshold (adaptive curves); its plan.
    fn configure(&mut self, curve: &CurveSpec, spp: u32, photons: u64, threshold: Option<f32>) -> RenderPlan {
        let s = &mut self.settings;
        s.spp = spp;
        s.photons.count = photons;
        if let Some(g) = curve.gather {
            s.photons.gather = g;
        }
        if let Some(k) = curve.sampler {
            s.sampler = Some(k);
        }
        s.noise_threshold = threshold;
        s.min_spp = s.min_spp.min(spp).max(2);
        let mut plan = RenderPlan::new(&self.scene, &self.settings);
        // Only the denoised curves pay for the auxiliary images.
        plan.aovs = curve.denoise;
        plan
    }

    /// One untimed render at 1 spp and at most [`WARM_UP_PHOTONS`] photons.
    fn warm_up(&mut self, accel: &dyn Accel, curve: &CurveSpec) {
        let photons = self.default_photons(1).min(WARM_UP_PHOTONS);
        let plan = self.configure(curve, 1, photons, None);
        let out = render::render(&self.scene, accel, &plan, render::RenderSetup::default());
        if curve.denoise {
            // The first filter loads OIDN's device module.
            let _ = denoised(&out, self.settings.denoise_quality);
        }
    }

    fn render(
        &mut self,
        accel: &dyn Accel,
        curve: &CurveSpec,
        spp: u32,
        photons: u64,
        threshold: Option<f32>,
    ) -> Result<Run, ConvergeError> {
        let plan = self.configure(curve, spp, photons, threshold);
        let start = Instant::now();
        let out = render::render(&self.scene, accel, &plan, render::RenderSetup::default());
        let film = match curve.denoise {
            true => denoised(&out, self.settings.denoise_quality)?,
            false => out.film.clone(),
        };
        let photon_seconds_of = |o: &render::RenderOutput| {
            o.stats
                .photons
                .as_ref()
                .map_or(0.0, |p| (p.trace_time + p.build_time + p.precompute_time).as_secs_f64())
        };
        let mut seconds = start.elapsed().as_secs_f64();
        let mut photon_seconds = photon_seconds_of(&out);
        // A short render is timed again and the fastest run kept: at a tenth
        // of a second, one run's jitter (scheduling, page faults) is as large
        // as the gap between budgets. The image is the same every time (same
        // seed), so only the time is taken from the repeats.
        for _ in 1..SHORT_RENDER_RUNS {
            if seconds >= SHORT_RENDER_SECONDS {
                break;
            }
            let again = Instant::now();
            let repeat = render::render(&self.scene, accel, &plan, render::RenderSetup::default());
            if curve.denoise {
                denoised(&repeat, self.settings.denoise_quality)?;
            }
            let s = again.elapsed().as_secs_f64();
            if s < seconds {
                seconds = s;
                photon_seconds = photon_seconds_of(&repeat);
            }
        }
        let error = error_metrics(&film, self.reference, self.epsilon)?;
        // An adaptive render reports the mean samples per pixel it took.
        let spp = match threshold {
            None => spp,
            Some(_) => (out.accumulation.samples_taken() as f64 / out.accumulation.len().max(1) as f64).round() as u32,
        };
        Ok(Run {
            spp,
            photons: if plan.runs_photons() { photons } else { 0 },
            seconds,
            photon_seconds,
            error,
        })
    }
}

/// The render's image denoised at high quality, guided by its albedo and normal.
/// The image of `out` through the scene's denoising filter quality.
fn denoised(out: &render::RenderOutput, quality: DenoiseQuality) -> Result<Film, ConvergeError> {
    let (film, _) = crate::job::denoise_accumulation(&out.film, &out.accumulation, quality)?;
    Ok(film)
}

fn check_budget(width: u32, height: u32, spp: u32, photons: u64) -> Result<(), String> {
    check_image_limits(width, height, spp).map_err(|e| e.to_string())?;
    check_photon_count(photons)
}

/// Renders `scene` (its settings give resolution, seed, base photon count)
/// at every budget for every curve and measures each image against
/// `reference`, on the current rayon pool. `log` receives one line per
/// render. Results are ordered by curve, then budget.
pub fn run(
    loaded: &LoadedScene,
    reference: &Film,
    options: &ConvergeOptions,
    log: &mut dyn FnMut(&str),
) -> Result<Vec<Measurement>, ConvergeError> {
    let LoadedScene { scene, settings: st } = loaded;
    check_same_size((st.width, st.height), reference)?;
    if !(options.epsilon.is_finite() && options.epsilon > 0.0) {
        return Err(ConvergeError::Epsilon(options.epsilon));
    }
    if options.curves.is_empty() {
        return Err(ConvergeError::Curves("no curve to run".into()));
    }
    for (i, c) in options.curves.iter().enumerate() {
        if options.curves[..i].contains(c) {
            return Err(ConvergeError::Curves(format!("{} is given twice", c.name())));
        }
    }
    if options.budgets.is_empty() {
        return Err(ConvergeError::Budget {
            text: String::new(),
            reason: "no budget".into(),
        });
    }
    let mut renderer = Renderer {
        scene: scene.clone(),
        settings: st.clone(),
        reference,
        epsilon: options.epsilon,
        photons_per_spp: options.photons_per_spp,
        scene_photons: st.photons.count,
    };
    // Sample budgets are checked against the limits before anything renders.
    for b in &options.budgets {
        if let Budget::Samples { spp, photons } = *b {
            let p = photons.unwrap_or_else(|| renderer.default_photons(spp));
            check_budget(st.width, st.height, spp, p).map_err(|reason| ConvergeError::Budget {
                text: b.to_string(),
                reason,
            })?;
        }
    }

    // One accelerator per kind, built once.
    let mut accels: Vec<(AccelKind, Box<dyn Accel>, f64)> = Vec::new();
    for c in &options.curves {
        if accels.iter().all(|(k, _, _)| *k != c.accel) {
            let a = accel::build(scene, c.accel, &options.accel).map_err(|source| ConvergeError::Accel {
                kind: c.accel.name(),
                source,
            })?;
            let build = a.stats().build_time.as_secs_f64();
            log(&format!("accelerator {} built in {build:.3} s", c.accel.name()));
            accels.push((c.accel, a, build));
        }
    }
    // One untimed 1-spp render per accelerator first: the process's first
    // render pays for the thread pool's start, page faults of fresh buffers
    // and cold caches, and made the smallest budget slower than the next.
    for (kind, a, _) in &accels {
        let curve = options
            .curves
            .iter()
            .find(|c| c.accel == *kind)
            .expect("built for a curve");
        renderer.warm_up(a.as_ref(), curve);
    }
    let accel_of = |kind: AccelKind| {
        let (_, a, b) = accels.iter().find(|(k, _, _)| *k == kind).expect("built above");
        (a.as_ref(), *b)
    };
    let describe = |curve: &CurveSpec, budget: &str, r: &Run| {
        format!(
            "{:<20} {:<16} {:>6} spp {:>10} photons {:>9.3} s  RMSE {:.4e}  relMSE {:.4e}",
            curve.name(),
            budget,
            r.spp,
            r.photons,
            r.seconds,
            r.error.rmse,
            r.error.relmse
        )
    };

    // results[curve][budget]
    let mut results: Vec<Vec<Option<Measurement>>> = vec![vec![None; options.budgets.len()]; options.curves.len()];
    let measurement = |curve: &CurveSpec, budget: Budget, r: &Run, build: f64, within: bool| Measurement {
        curve: curve.name(),
        budget,
        spp: r.spp,
        photons: r.photons,
        seconds: r.seconds,
        photon_seconds: r.photon_seconds,
        build_seconds: build,
        error: r.error,
        within_budget: within,
    };

    // Sample budgets: budget-major, so that a change in machine load during
    // the run affects all curves alike at each budget.
    for (bi, budget) in options.budgets.iter().enumerate() {
        let Budget::Samples { spp, photons } = *budget else {
            continue;
        };
        for (ci, curve) in options.curves.iter().enumerate() {
            if curve.adaptive {
                continue;
            }
            let (a, build) = accel_of(curve.accel);
            let p = photons.unwrap_or_else(|| renderer.default_photons(spp));
            let r = renderer.render(a, curve, spp, p, None)?;
            log(&describe(curve, &format!("budget {budget}"), &r));
            results[ci][bi] = Some(measurement(curve, *budget, &r, build, true));
        }
    }

    // Time budgets: one doubling ladder per curve.
    let max_seconds = options
        .budgets
        .iter()
        .filter_map(|b| match b {
            Budget::Seconds(s) => Some(*s),
            _ => None,
        })
        .fold(None, |m: Option<f64>, s| Some(m.map_or(s, |m| m.max(s))));
    if let Some(max_seconds) = max_seconds {
        for (ci, curve) in options.curves.iter().enumerate() {
            if curve.adaptive {
                continue;
            }
            let (a, build) = accel_of(curve.accel);
            let mut ladder: Vec<Run> = Vec::new();
            let mut spp = 1u32;
            loop {
                let photons = renderer.default_photons(spp);
                if let Err(reason) = check_budget(st.width, st.height, spp, photons) {
                    if ladder.is_empty() {
                        return Err(ConvergeError::Budget {
                            text: format!("{max_seconds}s"),
                            reason,
                        });
                    }
                    log(&format!(
                        "{}: doubling search stops at {spp} spp: {reason}",
                        curve.name()
                    ));
                    break;
                }
                let r = renderer.render(a, curve, spp, photons, None)?;
                log(&describe(curve, &format!("search ≤{max_seconds}s"), &r));
                ladder.push(r);
                let times: Vec<f64> = ladder.iter().map(|r| r.seconds).collect();
                if r.seconds > max_seconds || predict_next(&times) > max_seconds || spp >= MAX_SPP {
                    break;
                }
                spp *= 2;
            }
            let times: Vec<f64> = ladder.iter().map(|r| r.seconds).collect();
            for (bi, budget) in options.budgets.iter().enumerate() {
                if let Budget::Seconds(s) = *budget {
                    let (i, within) = pick_within(&times, s);
                    results[ci][bi] = Some(measurement(curve, *budget, &ladder[i], build, within));
                }
            }
        }
    }
    let mut out: Vec<Measurement> = results.into_iter().flatten().flatten().collect();

    // Adaptive curves: one render per noise threshold, at most `max_spp`.
    let max_spp = options.max_spp.max(2);
    for curve in options.curves.iter().filter(|c| c.adaptive) {
        let (a, build) = accel_of(curve.accel);
        for &t in &options.thresholds {
            let photons = renderer.default_photons(max_spp);
            let r = renderer.render(a, curve, max_spp, photons, Some(t))?;
            log(&describe(curve, &format!("noise<{t}"), &r));
            out.push(measurement(curve, Budget::Threshold(t), &r, build, true));
        }
    }

    // Time to a target error: each curve goes on (doubling spp, or halving
    // the threshold) until its relMSE is at or below the target.
    if let Some(target) = options.target_relmse {
        for curve in &options.curves {
            let (a, build) = accel_of(curve.accel);
            let reached = |out: &[Measurement]| out.iter().any(|m| m.curve == curve.name() && m.error.relmse <= target);
            let mut step = 0;
            while !reached(&out) {
                let (budget, r) = if curve.adaptive {
                    let t = 0.5f32.powi(step + 1);
                    if t < 1.0e-4 {
                        break;
                    }
                    let photons = renderer.default_photons(max_spp);
                    (
                        Budget::Threshold(t),
                        renderer.render(a, curve, max_spp, photons, Some(t))?,
                    )
                } else {
                    let spp = 1u32 << step;
                    let photons = renderer.default_photons(spp);
                    if spp > MAX_SPP || check_budget(st.width, st.height, spp, photons).is_err() {
                        break;
                    }
                    (
                        Budget::Samples { spp, photons: None },
                        renderer.render(a, curve, spp, photons, None)?,
                    )
                };
                log(&describe(curve, &format!("to relMSE {target:e}"), &r));
                out.push(measurement(curve, budget, &r, build, true));
                step += 1;
                if step > 30 {
                    break;
                }
            }
        }
    }
    Ok(out)
}

/// The time at which each curve's relMSE reaches `target`: interpolated
/// log-log between the two renders of the curve that bracket it (ordered by
/// time); `None` when no render reached it.
pub fn time_to_error(measurements: &[Measurement], target: f64) -> Vec<(String, Option<f64>)> {
    let mut names: Vec<&str> = Vec::new();
    for m in measurements {
        if !names.contains(&m.curve.as_str()) {
            names.push(&m.curve);
        }
    }
    names
        .into_iter()
        .map(|name| {
            let mut points: Vec<(f64, f64)> = measurements
                .iter()
                .filter(|m| m.curve == name && m.seconds > 0.0 && m.error.relmse > 0.0)
                .map(|m| (m.seconds, m.error.relmse))
                .collect();
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            let crossing = points.iter().position(|p| p.1 <= target).map(|i| {
                if i == 0 {
                    return points[0].0;
                }
                let ((t0, e0), (t1, e1)) = (points[i - 1], points[i]);
                if e0 <= e1 {
                    return t1;
                }
                let f = (target.ln() - e0.ln()) / (e1.ln() - e0.ln());
                (t0.ln() + f * (t1.ln() - t0.ln())).exp()
            });
            (name.to_string(), crossing)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn doubling_search_picks() {
        let ladder = [0.1, 0.25, 0.6, 1.3];
        assert_eq!(pick_within(&ladder, 1.0), (2, true));
        assert_eq!(pick_within(&ladder, 1.3), (3, true));
        assert_eq!(pick_within(&ladder, 5.0), (3, true));
        assert_eq!(pick_within(&ladder, 0.05), (0, false));
        assert_eq!(predict_next(&[0.3]), 0.6);
        // Fixed photon pass of 1 s plus 0.1 s per spp: t(1)=1.1, t(2)=1.2 → t(4)=1.4.
        assert!((predict_next(&[1.1, 1.2]) - 1.4).abs() < 1e-12);
        // Noise making the time drop does not predict a drop.
        assert_eq!(predict_next(&[1.0, 0.9]), 0.9);
    }

    #[test]
    fn curves_cross_and_name() {
        let c = CurveSpec::cross(&[AccelKind::KdTree, AccelKind::Brute], &[]);
        assert_eq!(c.iter().map(CurveSpec::name).collect::<Vec<_>>(), ["kdtree", "brute"]);
        let c = CurveSpec::cross(&[AccelKind::KdTree], &[GatherMode::Direct, GatherMode::Precomputed]);
        assert_eq!(
            c.iter().map(CurveSpec::name).collect::<Vec<_>>(),
            ["kdtree/direct", "kdtree/precomputed"]
        );
    }
}
