//! Run time against error (`caustic converge`): a scene is rendered at
//! increasing budgets, once per curve (an accelerator, optionally crossed
//! with a photon gather mode), and every image is compared with a reference
//! EXR on linear HDR values.
//!
//! # Budgets
//!
//! - `SPP:PHOTONS` (e.g. `4:100000`): that many samples per pixel and photons;
//! - `SPP` (e.g. `4`): that many samples per pixel; the photon count is
//!   `--photons-per-spp × SPP` when that option is given, else the scene's
//!   (fixed, so the photon map's bias shows as a floor);
//! - `SECONDS` followed by `s` (e.g. `2s`, `0.5s`): a wall-time budget,
//!   resolved by a **doubling search**. Each curve renders at 1, 2, 4, … spp
//!   (photons chosen as for `SPP` budgets) until the next render is predicted
//!   to exceed the largest time budget; the prediction extrapolates the last
//!   two times linearly in spp (`t(2s) ≈ t(s) + 2 (t(s) − t(s/2))`, which
//!   accounts for a fixed photon pass), or doubles the first. Each time budget
//!   then takes the largest spp whose *measured* time fits in it; when even
//!   1 spp does not fit, the 1-spp render is reported with
//!   `within_budget = false`. The ladder is shared by all time budgets of a
//!   curve (renders are deterministic: the same spp gives the same image).
//!
//! # What is measured
//!
//! `seconds` is the wall time of `integrator::render`: the photon pass plus
//! the image, on the current rayon pool. Scene loading and the accelerator
//! build are excluded (the build is timed once per curve and reported as
//! `build_seconds`), as is the error computation.
//!
//! # Error metrics
//!
//! Over all pixels `p` and channels `c` (N = 3 × pixels), with `x` the render
//! and `r` the reference, both linear radiance:
//! - `RMSE = sqrt(Σ (x − r)² / N)`;
//! - `relMSE = Σ (x − r)² / (r² + ε) / N`, the relative MSE of Rousselle,
//!   Knaus and Zwicker 2011 ("Adaptive sampling and reconstruction using
//!   greedy error minimization"), with [`RELMSE_EPSILON`] = 1e-2 by default:
//!   ε keeps black reference pixels from dominating;
//! - `MAE = Σ |x − r| / N`.
//!
//! Accumulated in f64. For an unbiased estimator, RMSE falls as t^(−1/2) and
//! relMSE (a squared error) as t^(−1).

use super::plot::{self, Guide, LogLogPanel, PlotError, Series};
use crate::accel::{self, Accel, AccelError, AccelKind, AccelOptions};
use crate::film::{Film, OutputError};
use crate::integrator::{render, RenderPlan};
use crate::limits::{check_image_limits, check_photon_count, MAX_SPP};
use crate::math::Vec3;
use crate::scene::{GatherMode, Scene};
use std::fmt;
use std::path::{Path, PathBuf};
use std::time::Instant;
use thiserror::Error;

/// Default ε of relMSE (Rousselle et al. 2011 use 1e-2 as well).
pub const RELMSE_EPSILON: f64 = 1e-2;

/// Most budgets one run accepts.
pub const MAX_BUDGETS: usize = 64;

/// Longest accepted time budget, in seconds (a day).
pub const MAX_SECONDS_BUDGET: f64 = 86_400.0;

/// Something went wrong in a convergence run.
#[derive(Debug, Error)]
pub enum ConvergeError {
    /// The reference EXR could not be read.
    #[error("{}: cannot read the reference EXR: {source}", path.display())]
    ReadReference {
        /// The reference file.
        path: PathBuf,
        /// The decoder's error.
        source: exr::error::Error,
    },
    /// The reference is not the render's resolution.
    #[error(
        "{}: the reference is {ref_width}×{ref_height} but the render is {width}×{height}: \
         render the reference at the same resolution (same --width/--height)",
        path.display()
    )]
    ResolutionMismatch {
        /// The reference file.
        path: PathBuf,
        /// Reference width.
        ref_width: usize,
        /// Reference height.
        ref_height: usize,
        /// Render width.
        width: u32,
        /// Render height.
        height: u32,
    },
    /// The reference has no usable image (no layer, or too large to hold).
    #[error("{}: {reason}", path.display())]
    BadReference {
        /// The reference file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A reference pixel is NaN or infinite.
    #[error("{}: pixel ({x}, {y}) of the reference is not finite ({value:?})", path.display())]
    NonFiniteReference {
        /// The reference file.
        path: PathBuf,
        /// Column.
        x: u32,
        /// Row.
        y: u32,
        /// The pixel.
        value: [f32; 3],
    },
    /// Two images of different sizes were compared.
    #[error("images of different sizes: {0}×{1} against {2}×{3}")]
    SizeMismatch(u32, u32, u32, u32),
    /// `--budgets` is malformed.
    #[error("--budgets {text:?}: {reason}")]
    Budget {
        /// The whole option value.
        text: String,
        /// What is wrong.
        reason: String,
    },
    /// The curve list is empty or repeats a curve.
    #[error("curves: {0}")]
    Curves(String),
    /// The relMSE ε is not a positive finite number.
    #[error("--epsilon {0}: must be a positive finite number")]
    Epsilon(f64),
    /// An accelerator could not be built.
    #[error("building the {kind} accelerator: {source}")]
    Accel {
        /// Which.
        kind: &'static str,
        /// Why.
        source: AccelError,
    },
    /// The CSV could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The plot could not be drawn or written.
    #[error(transparent)]
    Plot(#[from] PlotError),
}

/// One budget of a convergence run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// A fixed number of samples per pixel, with a photon count (`None`: the
    /// default rule, see the module documentation).
    Samples {
        /// Samples per pixel.
        spp: u32,
        /// Photons emitted.
        photons: Option<u64>,
    },
    /// A wall-time budget in seconds, resolved by the doubling search.
    Seconds(f64),
}

impl fmt::Display for Budget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Budget::Samples { spp, photons: None } => write!(f, "{spp}"),
            Budget::Samples { spp, photons: Some(p) } => write!(f, "{spp}:{p}"),
            Budget::Seconds(s) => write!(f, "{s}s"),
        }
    }
}

/// Parses a comma-separated budget list: `1:10000,2:30000`, `1,2,4`,
/// `0.5s,1s,2s` (kinds may be mixed). Every spp must be in `1..=MAX_SPP`, every
/// photon count pass [`check_photon_count`], every time be in
/// `(0, MAX_SECONDS_BUDGET]`.
pub fn parse_budgets(text: &str) -> Result<Vec<Budget>, ConvergeError> {
    let fail = |reason: String| ConvergeError::Budget {
        text: text.to_string(),
        reason,
    };
    let items: Vec<&str> = text.split(',').map(str::trim).collect();
    if items.len() > MAX_BUDGETS {
        return Err(fail(format!("{} budgets: at most {MAX_BUDGETS}", items.len())));
    }
    let mut budgets = Vec::with_capacity(items.len());
    for (i, item) in items.iter().enumerate() {
        let place = |what: String| fail(format!("budget {} ({item:?}): {what}", i + 1));
        if item.is_empty() {
            return Err(place("empty".into()));
        }
        if let Some(secs) = item.strip_suffix('s') {
            let s: f64 = secs
                .trim()
                .parse()
                .map_err(|_| place("expected seconds such as 2s or 0.5s".into()))?;
            if !(s.is_finite() && s > 0.0 && s <= MAX_SECONDS_BUDGET) {
                return Err(place(format!("seconds must be in (0, {MAX_SECONDS_BUDGET}]")));
            }
            budgets.push(Budget::Seconds(s));
            continue;
        }
        let (spp_text, photons_text) = match item.split_once(':') {
            Some((a, b)) => (a.trim(), Some(b.trim())),
            None => (*item, None),
        };
        let spp: u32 = spp_text
            .parse()
            .map_err(|_| place("expected SPP, SPP:PHOTONS or SECONDSs".into()))?;
        if spp == 0 || spp > MAX_SPP {
            return Err(place(format!("spp must be in 1..={MAX_SPP}")));
        }
        let photons = match photons_text {
            None => None,
            Some(t) => {
                let n: u64 = t.parse().map_err(|_| place(format!("{t:?} is not a photon count")))?;
                check_photon_count(n).map_err(place)?;
                Some(n)
            }
        };
        budgets.push(Budget::Samples { spp, photons });
    }
    Ok(budgets)
}

/// One curve: an accelerator, and optionally a photon gather mode that
/// overrides the scene's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CurveSpec {
    /// Accelerator.
    pub accel: AccelKind,
    /// Gather mode (`None`: the scene's `[photons] gather`).
    pub gather: Option<GatherMode>,
}

impl CurveSpec {
    /// `"embree"`, or `"embree/direct"` with a gather mode.
    pub fn name(&self) -> String {
        match self.gather {
            None => self.accel.name().to_string(),
            Some(GatherMode::Direct) => format!("{}/direct", self.accel.name()),
            Some(GatherMode::Precomputed) => format!("{}/precomputed", self.accel.name()),
        }
    }

    /// Every accelerator crossed with every gather mode (`gathers` empty:
    /// the scene's mode only), accelerators outermost.
    pub fn cross(accels: &[AccelKind], gathers: &[GatherMode]) -> Vec<CurveSpec> {
        let mut out = Vec::new();
        for &accel in accels {
            if gathers.is_empty() {
                out.push(CurveSpec { accel, gather: None });
            }
            for &g in gathers {
                out.push(CurveSpec { accel, gather: Some(g) });
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
}

/// Errors of one image against the reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorMetrics {
    /// Root mean squared error.
    pub rmse: f64,
    /// Relative MSE, `(x − r)² / (r² + ε)` averaged.
    pub relmse: f64,
    /// Mean absolute error.
    pub mae: f64,
}

/// [`ConvergeError::SizeMismatch`] unless an image of `size` can be compared
/// with `reference`.
fn check_same_size((width, height): (u32, u32), reference: &Film) -> Result<(), ConvergeError> {
    if (width, height) == (reference.width, reference.height) {
        Ok(())
    } else {
        Err(ConvergeError::SizeMismatch(
            width,
            height,
            reference.width,
            reference.height,
        ))
    }
}

/// Compares `image` with `reference` over all pixels and the three channels
/// (see the module documentation for the formulas).
pub fn error_metrics(image: &Film, reference: &Film, epsilon: f64) -> Result<ErrorMetrics, ConvergeError> {
    check_same_size((image.width, image.height), reference)?;
    let (mut se, mut rel, mut abs) = (0.0f64, 0.0f64, 0.0f64);
    for (x, r) in image.pixels.iter().zip(&reference.pixels) {
        for c in 0..3 {
            let (x, r) = (x[c] as f64, r[c] as f64);
            let d = x - r;
            se += d * d;
            rel += d * d / (r * r + epsilon);
            abs += d.abs();
        }
    }
    let n = (image.pixels.len() * 3).max(1) as f64;
    Ok(ErrorMetrics {
        rmse: (se / n).sqrt(),
        relmse: rel / n,
        mae: abs / n,
    })
}

/// Reads the first RGB(A) layer of an EXR file as a linear film (alpha is
/// ignored). The header is read first: when `expected` is given and the
/// layer's size differs, [`ConvergeError::ResolutionMismatch`] is returned
/// before any pixel is allocated. NaN or infinite pixels are an error.
pub fn read_exr(path: &Path, expected: Option<(u32, u32)>) -> Result<Film, ConvergeError> {
    use exr::prelude::*;
    let read_error = |source| ConvergeError::ReadReference {
        path: path.to_path_buf(),
        source,
    };
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(read_error)?;
    let bad = |reason: String| ConvergeError::BadReference {
        path: path.to_path_buf(),
        reason,
    };
    let size = meta
        .headers
        .first()
        .map(|h| h.layer_size)
        .ok_or_else(|| bad("the file has no image layer".into()))?;
    if let Some((width, height)) = expected {
        if (size.width(), size.height()) != (width as usize, height as usize) {
            return Err(ConvergeError::ResolutionMismatch {
                path: path.to_path_buf(),
                ref_width: size.width(),
                ref_height: size.height(),
                width,
                height,
            });
        }
    }
    let too_large = || bad(format!("{}×{} pixels is too large", size.width(), size.height()));
    let width = u32::try_from(size.width()).map_err(|_| too_large())?;
    let height = u32::try_from(size.height()).map_err(|_| too_large())?;
    // The film is checked against the memory budget before it is allocated.
    check_image_limits(width, height, 1).map_err(|e| bad(format!("reference image: {e}")))?;
    let image = read_first_rgba_layer_from_file(
        path,
        |res: Vec2<usize>, _| Film::new(res.width() as u32, res.height() as u32),
        |film: &mut Film, pos: Vec2<usize>, (r, g, b, _a): (f32, f32, f32, f32)| {
            film.set(pos.x() as u32, pos.y() as u32, Vec3::new(r, g, b));
        },
    )
    .map_err(read_error)?;
    let film = image.layer_data.channel_data.pixels;
    if let Some(i) = film.pixels.iter().position(|p| !p.is_finite()) {
        return Err(ConvergeError::NonFiniteReference {
            path: path.to_path_buf(),
            x: i as u32 % film.width,
            y: i as u32 / film.width,
            value: film.pixels[i].to_array(),
        });
    }
    Ok(film)
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
    reference: &'a Film,
    epsilon: f64,
    photons_per_spp: Option<u64>,
}

impl Renderer<'_> {
    fn default_photons(&self, spp: u32) -> u64 {
        match self.photons_per_spp {
            Some(r) => r.saturating_mul(spp as u64),
            None => self.scene.settings.photons.count,
        }
    }

    /// Sets the scene to `curve`'s gather mode, `spp` and `photons`; its plan.
    fn configure(&mut self, curve: &CurveSpec, spp: u32, photons: u64) -> RenderPlan {
        let s = &mut self.scene.settings;
        s.spp = spp;
        s.photons.count = photons;
        if let Some(g) = curve.gather {
            s.photons.gather = g;
        }
        RenderPlan::new(&self.scene)
    }

    /// One untimed render at 1 spp and at most [`WARM_UP_PHOTONS`] photons.
    fn warm_up(&mut self, accel: &dyn Accel, curve: &CurveSpec) {
        let photons = self.default_photons(1).min(WARM_UP_PHOTONS);
        let plan = self.configure(curve, 1, photons);
        render::render(&self.scene, accel, &plan, &|_, _| {});
    }

    fn render(&mut self, accel: &dyn Accel, curve: &CurveSpec, spp: u32, photons: u64) -> Result<Run, ConvergeError> {
        let plan = self.configure(curve, spp, photons);
        let start = Instant::now();
        let out = render::render(&self.scene, accel, &plan, &|_, _| {});
        let mut seconds = start.elapsed().as_secs_f64();
        // A short render is timed again and the fastest run kept: at a tenth
        // of a second, one run's jitter (scheduling, page faults) is as large
        // as the gap between budgets. The image is the same every time (same
        // seed), so only the time is taken from the repeats.
        for _ in 1..SHORT_RENDER_RUNS {
            if seconds >= SHORT_RENDER_SECONDS {
                break;
            }
            let again = Instant::now();
            render::render(&self.scene, accel, &plan, &|_, _| {});
            seconds = seconds.min(again.elapsed().as_secs_f64());
        }
        let error = error_metrics(&out.film, self.reference, self.epsilon)?;
        Ok(Run {
            spp,
            photons: if plan.runs_photons() { photons } else { 0 },
            seconds,
            error,
        })
    }
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
    scene: &Scene,
    reference: &Film,
    options: &ConvergeOptions,
    log: &mut dyn FnMut(&str),
) -> Result<Vec<Measurement>, ConvergeError> {
    let st = &scene.settings;
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
        reference,
        epsilon: options.epsilon,
        photons_per_spp: options.photons_per_spp,
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
            let (a, build) = accel_of(curve.accel);
            let p = photons.unwrap_or_else(|| renderer.default_photons(spp));
            let r = renderer.render(a, curve, spp, p)?;
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
                let r = renderer.render(a, curve, spp, photons)?;
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
    Ok(results.into_iter().flatten().flatten().collect())
}

/// CSV header of [`csv_text`].
pub const CSV_HEADER: &str = "curve,budget,spp,photons,seconds,rmse,relmse,mae,build_seconds,within_budget";

/// The measurements as CSV: [`CSV_HEADER`], then one row per measurement.
/// `seconds` excludes the accelerator build (`build_seconds`).
pub fn csv_text(measurements: &[Measurement]) -> String {
    let mut s = String::from(CSV_HEADER);
    s.push('\n');
    for m in measurements {
        s.push_str(&format!(
            "{},{},{},{},{:.6},{:.6e},{:.6e},{:.6e},{:.6},{}\n",
            m.curve,
            m.budget,
            m.spp,
            m.photons,
            m.seconds,
            m.error.rmse,
            m.error.relmse,
            m.error.mae,
            m.build_seconds,
            m.within_budget
        ));
    }
    s
}

/// Writes [`csv_text`] to `path` atomically.
pub fn write_csv(path: &Path, measurements: &[Measurement]) -> Result<(), ConvergeError> {
    let text = csv_text(measurements);
    crate::film::output::write_atomically(path, |w| {
        use std::io::Write;
        w.write_all(text.as_bytes()).map_err(|source| OutputError::Io {
            path: path.to_path_buf(),
            what: "writing",
            source,
        })
    })?;
    Ok(())
}

/// A fixed-width table of the measurements for the terminal.
pub fn table_text(measurements: &[Measurement], epsilon: f64) -> String {
    let mut s = format!(
        "{:<20} {:>12} {:>7} {:>11} {:>10} {:>11} {:>11} {:>11}\n",
        "curve", "budget", "spp", "photons", "seconds", "RMSE", "relMSE", "MAE"
    );
    for m in measurements {
        s.push_str(&format!(
            "{:<20} {:>12} {:>7} {:>11} {:>10.3} {:>11.4e} {:>11.4e} {:>11.4e}{}\n",
            m.curve,
            m.budget.to_string(),
            m.spp,
            m.photons,
            m.seconds,
            m.error.rmse,
            m.error.relmse,
            m.error.mae,
            if m.within_budget { "" } else { "  (over budget: 1 spp)" }
        ));
    }
    s.push_str(&format!(
        "seconds: photon pass + render (accelerator build excluded); relMSE ε = {epsilon:e}\n"
    ));
    s
}

/// The convergence plot: RMSE (with a slope −1/2 guide) and relMSE (slope −1)
/// against seconds, log-log, one curve per [`CurveSpec`] in order of first
/// appearance, written to `path` as a `width × height` PNG.
pub fn write_plot(
    path: &Path,
    measurements: &[Measurement],
    title: &str,
    epsilon: f64,
    width: u32,
    height: u32,
) -> Result<(), ConvergeError> {
    let mut names: Vec<&str> = Vec::new();
    for m in measurements {
        if !names.contains(&m.curve.as_str()) {
            names.push(&m.curve);
        }
    }
    let series = |metric: fn(&ErrorMetrics) -> f64| -> Vec<Series> {
        names
            .iter()
            .map(|&name| Series {
                label: name.to_string(),
                points: measurements
                    .iter()
                    .filter(|m| m.curve == name)
                    .map(|m| (m.seconds, metric(&m.error)))
                    .collect(),
            })
            .collect()
    };
    let x_label = "wall time (s): photon pass + render".to_string();
    let panels = [
        LogLogPanel {
            title: format!("{title}: RMSE"),
            x_label: x_label.clone(),
            y_label: "RMSE (linear radiance)".into(),
            series: series(|e| e.rmse),
            guide: Some(Guide {
                slope: -0.5,
                label: "slope −1/2 (Monte Carlo)".into(),
            }),
        },
        LogLogPanel {
            title: format!("{title}: relMSE"),
            x_label,
            y_label: format!("relMSE (ε = {epsilon})"),
            series: series(|e| e.relmse),
            guide: Some(Guide {
                slope: -1.0,
                label: "slope −1 (Monte Carlo)".into(),
            }),
        },
    ];
    plot::write_loglog_png(path, &panels, width, height)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn film(w: u32, h: u32, f: impl Fn(u32, u32) -> Vec3) -> Film {
        let mut film = Film::new(w, h);
        for y in 0..h {
            for x in 0..w {
                film.set(x, y, f(x, y));
            }
        }
        film
    }

    #[test]
    fn metrics_of_a_constant_offset() {
        let reference = film(4, 3, |_, _| Vec3::ONE);
        let image = film(4, 3, |_, _| Vec3::splat(1.5));
        let e = error_metrics(&image, &reference, 0.01).unwrap();
        assert!((e.rmse - 0.5).abs() < 1e-12, "{e:?}");
        assert!((e.mae - 0.5).abs() < 1e-12);
        assert!((e.relmse - 0.25 / 1.01).abs() < 1e-12);
        // Identical images: all zero.
        let z = error_metrics(&reference, &reference, 0.01).unwrap();
        assert_eq!((z.rmse, z.relmse, z.mae), (0.0, 0.0, 0.0));
    }

    #[test]
    fn metrics_per_channel_and_epsilon() {
        // Reference (2, 0, 0) everywhere, image off by (+1, −2, 0): squared
        // errors 1, 4, 0 → MSE 5/3; relMSE = (1/(4+ε) + 4/ε + 0)/3.
        let reference = film(3, 2, |_, _| Vec3::new(2.0, 0.0, 0.0));
        let image = film(3, 2, |_, _| Vec3::new(3.0, -2.0, 0.0));
        for eps in [1e-2, 1.0] {
            let e = error_metrics(&image, &reference, eps).unwrap();
            assert!((e.rmse - (5.0f64 / 3.0).sqrt()).abs() < 1e-12);
            assert!((e.mae - 1.0).abs() < 1e-12);
            let want = (1.0 / (4.0 + eps) + 4.0 / eps) / 3.0;
            assert!((e.relmse - want).abs() < 1e-9 * want, "{} vs {want}", e.relmse);
        }
        // Half the pixels off by 2: MSE 2, RMSE √2.
        let half = film(3, 2, |x, _| Vec3::splat(if x == 0 { 1.0 } else { 0.0 }));
        let zero = film(3, 2, |x, _| Vec3::splat(if x == 0 { 3.0 } else { 0.0 }));
        let e = error_metrics(&zero, &half, 0.01).unwrap();
        assert!((e.rmse - (4.0f64 / 3.0).sqrt()).abs() < 1e-12);
        assert!(matches!(
            error_metrics(&film(2, 2, |_, _| Vec3::ZERO), &half, 0.01),
            Err(ConvergeError::SizeMismatch(2, 2, 3, 2))
        ));
    }

    #[test]
    fn budgets_parse_and_reject() {
        assert_eq!(
            parse_budgets("1:10000, 2:30000,4").unwrap(),
            vec![
                Budget::Samples {
                    spp: 1,
                    photons: Some(10000)
                },
                Budget::Samples {
                    spp: 2,
                    photons: Some(30000)
                },
                Budget::Samples { spp: 4, photons: None },
            ]
        );
        assert_eq!(
            parse_budgets("0.5s,2s").unwrap(),
            vec![Budget::Seconds(0.5), Budget::Seconds(2.0)]
        );
        for bad in [
            "",
            "0",
            "1,,2",
            "x",
            "1:y",
            "-1s",
            "0s",
            "nans",
            "infs",
            "1:99999999999",
            "2000000",
            "1e9s",
        ] {
            let e = parse_budgets(bad).unwrap_err().to_string();
            assert!(e.starts_with("--budgets"), "{bad}: {e}");
        }
        let many = vec!["1"; MAX_BUDGETS + 1].join(",");
        assert!(parse_budgets(&many).is_err());
        for b in parse_budgets("1:5,3,0.25s").unwrap() {
            assert_eq!(parse_budgets(&b.to_string()).unwrap(), vec![b]);
        }
    }

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

    #[test]
    fn exr_reader_round_trips_and_checks_size() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("ref.exr");
        let f = film(5, 3, |x, y| Vec3::new(x as f32 * 0.25, y as f32 + 0.5, 1e-4 * x as f32));
        crate::film::write_exr(&path, &f).unwrap();
        assert_eq!(read_exr(&path, Some((5, 3))).unwrap(), f);
        assert_eq!(read_exr(&path, None).unwrap(), f);
        let e = read_exr(&path, Some((4, 3))).unwrap_err().to_string();
        assert!(e.contains("5×3") && e.contains("4×3") && e.contains("ref.exr"), "{e}");
        // Not an EXR, and a missing file: the path is named.
        let junk = dir.path().join("junk.exr");
        std::fs::write(&junk, b"not an exr at all").unwrap();
        let e = read_exr(&junk, None).unwrap_err().to_string();
        assert!(e.contains("junk.exr"), "{e}");
        let e = read_exr(&dir.path().join("missing.exr"), None).unwrap_err().to_string();
        assert!(e.contains("missing.exr"), "{e}");
        // A NaN pixel is refused.
        let mut nan = f.clone();
        nan.set(2, 1, Vec3::new(0.0, f32::NAN, 0.0));
        crate::film::write_exr(&path, &nan).unwrap();
        let e = read_exr(&path, None).unwrap_err().to_string();
        assert!(e.contains("(2, 1)"), "{e}");
    }

    #[test]
    fn csv_has_one_row_per_measurement() {
        let m = Measurement {
            curve: "kdtree".into(),
            budget: Budget::Samples {
                spp: 2,
                photons: Some(100),
            },
            spp: 2,
            photons: 100,
            seconds: 0.5,
            build_seconds: 0.1,
            error: ErrorMetrics {
                rmse: 0.25,
                relmse: 0.125,
                mae: 0.2,
            },
            within_budget: true,
        };
        let text = csv_text(&[m.clone(), m]);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 3);
        assert_eq!(lines[0], CSV_HEADER);
        assert_eq!(
            lines[1],
            "kdtree,2:100,2,100,0.500000,2.500000e-1,1.250000e-1,2.000000e-1,0.100000,true"
        );
    }
}
