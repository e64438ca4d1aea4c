//! The measurements written out: CSV, the terminal table, and the log-log
//! convergence plot.

use super::metrics::ErrorMetrics;
use super::run::Measurement;
use super::ConvergeError;
use crate::analysis::plot::{self, Guide, LogLogPanel, Series};
use crate::film::OutputError;
use std::path::Path;

/// CSV header of [`csv_text`].
pub const CSV_HEADER: &str =
    "curve,budget,spp,photons,seconds,rmse,relmse,mae,build_seconds,within_budget,photon_seconds";

/// The measurements as CSV: [`CSV_HEADER`], then one row per measurement.
/// `seconds` excludes the accelerator build (`build_seconds`).
pub fn csv_text(measurements: &[Measurement]) -> String {
    let mut s = String::from(CSV_HEADER);
    s.push('\n');
    for m in measurements {
        s.push_str(&format!(
            "{},{},{},{},{:.6},{:.6e},{:.6e},{:.6e},{:.6},{},{:.6}\n",
            m.curve,
            m.budget,
            m.spp,
            m.photons,
            m.seconds,
            m.error.rmse,
            m.error.relmse,
            m.error.mae,
            m.build_seconds,
            m.within_budget,
            m.photon_seconds
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
/// against seconds, log-log, one curve per [`CurveSpec`](super::run::CurveSpec)
/// in order of first appearance, written to `path` as a `width × height` PNG.
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
                points: {
                    let mut p: Vec<(f64, f64)> = measurements
                        .iter()
                        .filter(|m| m.curve == name)
                        .map(|m| (m.seconds, metric(&m.error)))
                        .collect();
                    p.sort_by(|a, b| a.0.total_cmp(&b.0));
                    p
                },
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
    use crate::analysis::converge::Budget;

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
            photon_seconds: 0.0,
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
            "kdtree,2:100,2,100,0.500000,2.500000e-1,1.250000e-1,2.000000e-1,0.100000,true,0.000000"
        );
    }
}
