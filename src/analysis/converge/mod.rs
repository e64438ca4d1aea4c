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
//! the image, on the current rayon pool, and for a denoised curve
//! (`/denoised`, `--denoise`) the denoising of the image with Open Image
//! Denoise, guided by its albedo and normal. Scene loading and the accelerator
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
//!
//! This module holds the errors; `budget` parses the budgets, `run` renders
//! the curves at them, `metrics` reads the reference and compares images
//! with it, and `report` writes the measurements as CSV, a table and a plot.

mod budget;
mod metrics;
mod report;
mod run;

pub use budget::{parse_budgets, Budget, MAX_BUDGETS, MAX_SECONDS_BUDGET};
pub use metrics::{error_metrics, read_exr, ErrorMetrics, RELMSE_EPSILON};
pub use report::{csv_text, table_text, write_csv, write_plot, CSV_HEADER};
pub use run::{pick_within, predict_next, run, time_to_error, ConvergeOptions, CurveSpec, Measurement};

use super::plot::PlotError;
use crate::accel::AccelError;
use crate::film::OutputError;
use std::path::PathBuf;
use thiserror::Error;

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
    /// A denoised curve's image could not be denoised.
    #[error(transparent)]
    Denoise(#[from] crate::film::denoise::DenoiseError),
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
