//! Log-log line plots written as PNG (used by `caustic converge`).
//!
//! Drawn with `plotters` on its bitmap backend into an RGB buffer, then
//! encoded with the `image` crate's PNG encoder and written atomically like
//! the renders (`film::output`). Text goes through plotters' `ab_glyph`
//! feature with a bundled font (a Latin subset of DejaVu Sans,
//! `assets/fonts/`), so drawing a plot needs no fontconfig or freetype on the
//! machine and gives the same pixels everywhere.

use crate::film::OutputError;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use thiserror::Error;

/// Smallest and largest accepted plot side, in pixels.
pub const PLOT_SIDE_RANGE: std::ops::RangeInclusive<u32> = 200..=8192;

/// The bundled font: DejaVu Sans (Bitstream Vera licence, DejaVu changes in
/// the public domain; see `assets/fonts/LICENSE-DejaVu.txt`), cut down to
/// printable ASCII and the few symbols the plots use (− × ² ½ ε · –).
static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans-subset.ttf");

/// Font family name the plots ask plotters for.
const FAMILY: &str = "sans-serif";

/// A plot could not be drawn or written.
#[derive(Debug, Error)]
pub enum PlotError {
    /// Width or height outside [`PLOT_SIDE_RANGE`].
    #[error("plot size {width}×{height}: each side must be in {}..={} pixels", PLOT_SIDE_RANGE.start(), PLOT_SIDE_RANGE.end())]
    Size {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
    },
    /// The bundled font did not parse (a build problem, never user input).
    #[error("the bundled plot font could not be loaded")]
    Font,
    /// plotters failed while drawing.
    #[error("{}: drawing the plot failed: {message}", path.display())]
    Draw {
        /// The target file.
        path: PathBuf,
        /// plotters' message.
        message: String,
    },
    /// Encoding or writing the PNG failed.
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// One line of a panel: points `(x, y)` joined in the given order, with a
/// marker at each point. Points with a non-positive or non-finite coordinate
/// cannot be shown on log axes and are left out.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// The points.
    pub points: Vec<(f64, f64)>,
}

/// A reference line `y ∝ x^slope` drawn through a panel's first point, to
/// compare the curves' slopes with (e.g. −1/2 for a Monte Carlo RMSE).
#[derive(Clone, Debug, PartialEq)]
pub struct Guide {
    /// Log-log slope.
    pub slope: f64,
    /// Legend text.
    pub label: String,
}

/// One log-log chart.
#[derive(Clone, Debug, PartialEq)]
pub struct LogLogPanel {
    /// Caption above the chart.
    pub title: String,
    /// X axis label.
    pub x_label: String,
    /// Y axis label.
    pub y_label: String,
    /// The curves.
    pub series: Vec<Series>,
    /// Optional slope guide.
    pub guide: Option<Guide>,
}

/// Line colours (the "tab10" palette: distinct, and readable by most colour-blind viewers).
const COLORS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

fn register_font() -> Result<(), PlotError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| plotters::style::register_font(FAMILY, FontStyle::Normal, FONT).is_ok());
    if ok {
        Ok(())
    } else {
        Err(PlotError::Font)
    }
}

/// Draws `panels` side by side on a white `width × height` image and writes
/// it to `path` as an RGB PNG, atomically.
pub fn write_loglog_png(path: &Path, panels: &[LogLogPanel], width: u32, height: u32) -> Result<(), PlotError> {
    let rgb = draw_loglog(path, panels, width, height)?;
    let mut png = Vec::new();
    {
        use image::ImageEncoder;
        image::codecs::png::PngEncoder::new(&mut png)
            .write_image(&rgb, width, height, image::ExtendedColorType::Rgb8)
            .map_err(|source| OutputError::Png {
                path: path.to_path_buf(),
                source,
            })?;
    }
    crate::film::output::write_atomically(path, |w| {
        use std::io::Write;
        w.write_all(&png).map_err(|source| OutputError::Io {
            path: path.to_path_buf(),
            what: "writing",
            source,
        })
    })?;
    Ok(())
}

/// Checks a plot size against [`PLOT_SIDE_RANGE`] (callers check before long work).
pub fn check_size(width: u32, height: u32) -> Result<(), PlotError> {
    if PLOT_SIDE_RANGE.contains(&width) && PLOT_SIDE_RANGE.contains(&height) {
        Ok(())
    } else {
        Err(PlotError::Size { width, height })
    }
}

/// Draws the panels into an RGB8 buffer (`width × height × 3` bytes). `path`
/// only names the target in error messages.
pub fn draw_loglog(path: &Path, panels: &[LogLogPanel], width: u32, height: u32) -> Result<Vec<u8>, PlotError> {
    check_size(width, height)?;
    register_font()?;
    let draw_error = |e: &dyn std::fmt::Display| PlotError::Draw {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    let mut buffer = vec![255u8; width as usize * height as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| draw_error(&e))?;
        if !panels.is_empty() {
            let areas = root.split_evenly((1, panels.len()));
            for (area, panel) in areas.iter().zip(panels) {
                draw_panel(area, panel, height).map_err(|e| draw_error(&e))?;
            }
        }
        root.present().map_err(|e| draw_error(&e))?;
    }
    Ok(buffer)
}

/// The points of a series that log axes can show.
fn plottable(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    points
        .iter()
        .copied()
        .filter(|(x, y)| x.is_finite() && y.is_finite() && *x > 0.0 && *y > 0.0)
        .collect()
}

/// `[lo, hi]` widened by `factor` on each side (a log-axis margin), or a
/// decade around 1 when there is no value.
fn log_range(values: impl Iterator<Item = f64>, factor: f64) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, 0.0f64), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if lo.is_finite() && hi > 0.0 {
        (lo / factor, hi * factor)
    } else {
        (0.1, 10.0)
    }
}

/// `m × 10^k` for every `m` in `mantissas` that lies in `[lo, hi]`.
fn decade_points(lo: f64, hi: f64, mantissas: &[f64]) -> Vec<f64> {
    if !(lo > 0.0 && hi >= lo && hi.is_finite()) {
        return Vec::new();
    }
    let mut out = Vec::new();
    for k in lo.log10().floor() as i32..=hi.log10().ceil() as i32 {
        for m in mantissas {
            let v = m * 10f64.powi(k);
            if v >= lo && v <= hi {
                out.push(v);
            }
        }
    }
    out
}

/// Labelled ticks of a log axis: the powers of ten when there are at least
/// three (every other one past twelve), else 1-2-5 steps, else 1…9 steps, so
/// a range narrower than a decade still gets labels.
pub fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let decades = decade_points(lo, hi, &[1.0]);
    if decades.len() >= 3 {
        let step = decades.len().div_ceil(12);
        return decades.into_iter().step_by(step).collect();
    }
    let steps = decade_points(lo, hi, &[1.0, 2.0, 5.0]);
    if steps.len() >= 3 {
        return steps;
    }
    decade_points(lo, hi, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0])
}

/// Light grid lines of a log axis: 1…9 × 10^k.
fn log_minor_ticks(lo: f64, hi: f64) -> Vec<f64> {
    decade_points(lo, hi, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0])
}

/// Tick labels: plain decimals with two significant digits from 0.001 to
/// 99999, else `1.0e-4` style.
pub fn format_tick(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if (1e-3..1e5).contains(&a) {
        let decimals = (1 - a.log10().floor() as i32).clamp(0, 6) as usize;
        let s = format!("{v:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        format!("{v:.1e}")
    }
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panel: &LogLogPanel,
    image_height: u32,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    // Text sizes follow the image height, so large plots stay legible.
    let scale = (image_height as f64 / 520.0).clamp(0.6, 4.0);
    let px = |v: f64| (v * scale).round() as i32;
    let series: Vec<(String, Vec<(f64, f64)>)> = panel
        .series
        .iter()
        .map(|s| (s.label.clone(), plottable(&s.points)))
        .collect();
    let (x0, x1) = log_range(series.iter().flat_map(|(_, p)| p.iter().map(|q| q.0)), 1.3);
    let (y0, y1) = log_range(series.iter().flat_map(|(_, p)| p.iter().map(|q| q.1)), 1.6);
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, (FAMILY, px(20.0)))
        .margin(px(12.0))
        .x_label_area_size(px(48.0))
        .y_label_area_size(px(72.0))
        .build_cartesian_2d(
            (x0..x1)
                .log_scale()
                .with_key_points(log_ticks(x0, x1))
                .with_light_points(log_minor_ticks(x0, x1)),
            (y0..y1)
                .log_scale()
                .with_key_points(log_ticks(y0, y1))
                .with_light_points(log_minor_ticks(y0, y1)),
        )?;
    chart
        .configure_mesh()
        .x_desc(&panel.x_label)
        .y_desc(&panel.y_label)
        .axis_desc_style((FAMILY, px(16.0)))
        .label_style((FAMILY, px(13.0)))
        .x_label_formatter(&|v| format_tick(*v))
        .y_label_formatter(&|v| format_tick(*v))
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(205, 205, 205))
        .draw()?;

    if let (Some(guide), Some(&(ax, ay))) = (&panel.guide, series.first().and_then(|(_, p)| p.first())) {
        // y = ay (x / ax)^slope through the first curve's first point.
        let n = 32;
        let line: Vec<(f64, f64)> = (0..=n)
            .map(|i| {
                let x = x0 * (x1 / x0).powf(i as f64 / n as f64);
                (x, ay * (x / ax).powf(guide.slope))
            })
            .filter(|&(_, y)| y >= y0 && y <= y1)
            .collect();
        let gray = RGBColor(120, 120, 120);
        chart
            .draw_series(DashedLineSeries::new(
                line,
                px(6.0).max(2) as u32,
                px(5.0).max(2) as u32,
                gray.stroke_width(px(1.5).max(1) as u32),
            ))?
            .label(&guide.label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], gray.stroke_width(1)));
    }

    let stroke = px(2.0).max(1) as u32;
    let marker = px(5.0).max(3);
    for (i, (label, points)) in series.iter().enumerate() {
        let color = COLORS[i % COLORS.len()];
        let line = chart
            .draw_series(LineSeries::new(points.iter().copied(), color.stroke_width(stroke)))?
            .label(label);
        // Legend entries: a short line with the curve's marker on it.
        let legend_line = move |(x, y): (i32, i32)| {
            EmptyElement::at((x, y)) + PathElement::new(vec![(0, 0), (24, 0)], color.stroke_width(2))
        };
        // A different marker shape per curve (circle, triangle, square), in the
        // legend too, so that curves stay apart in grey print.
        match i % 3 {
            0 => {
                line.legend(move |(x, y)| legend_line((x, y)) + Circle::new((12, 0), 4, color.filled()));
                chart.draw_series(points.iter().map(|&p| Circle::new(p, marker, color.filled())))?;
            }
            1 => {
                line.legend(move |(x, y)| legend_line((x, y)) + TriangleMarker::new((12, 0), 5, color.filled()));
                chart.draw_series(
                    points
                        .iter()
                        .map(|&p| TriangleMarker::new(p, marker + 1, color.filled())),
                )?;
            }
            _ => {
                line.legend(move |(x, y)| legend_line((x, y)) + Rectangle::new([(8, -4), (16, 4)], color.filled()));
                let m = marker - 1;
                chart.draw_series(
                    points
                        .iter()
                        .map(|&p| EmptyElement::at(p) + Rectangle::new([(-m, -m), (m, m)], color.filled())),
                )?;
            }
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FAMILY, px(14.0)))
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(160, 160, 160))
        .draw()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn panel() -> LogLogPanel {
        LogLogPanel {
            title: "RMSE".into(),
            x_label: "seconds".into(),
            y_label: "error".into(),
            series: vec![
                Series {
                    label: "a".into(),
                    points: vec![(0.1, 1.0), (0.4, 0.5), (1.6, 0.25)],
                },
                Series {
                    label: "b".into(),
                    points: vec![(0.2, 1.0), (0.0, 0.3), (f64::NAN, 1.0), (0.8, 0.6)],
                },
            ],
            guide: Some(Guide {
                slope: -0.5,
                label: "slope −1/2".into(),
            }),
        }
    }

    #[test]
    fn draws_something_of_the_requested_size() {
        let rgb = draw_loglog(Path::new("t.png"), &[panel(), panel()], 640, 300).unwrap();
        assert_eq!(rgb.len(), 640 * 300 * 3);
        // The first curve's colour appears, and so does dark text/axis ink.
        let has = |c: [u8; 3]| rgb.chunks_exact(3).any(|p| p == c);
        assert!(has([31, 119, 180]));
        assert!(has([214, 39, 40]));
        assert!(rgb.chunks_exact(3).filter(|p| p.iter().all(|&v| v < 80)).count() > 200);
    }

    #[test]
    fn rejects_absurd_sizes() {
        for (w, h) in [(10, 300), (640, 0), (100_000, 300)] {
            let e = draw_loglog(Path::new("t.png"), &[panel()], w, h).unwrap_err();
            assert!(matches!(e, PlotError::Size { .. }), "{e}");
        }
    }

    #[test]
    fn log_ranges_and_ticks() {
        assert_eq!(log_range([2.0, 8.0].into_iter(), 2.0), (1.0, 16.0));
        assert_eq!(log_range(std::iter::empty(), 2.0), (0.1, 10.0));
        assert_eq!(plottable(&[(1.0, 0.0), (1.0, 2.0), (-1.0, 1.0)]), vec![(1.0, 2.0)]);
        assert_eq!(format_tick(0.5), "0.5");
        assert_eq!(format_tick(100.0), "100");
        assert_eq!(format_tick(0.002), "0.002");
        assert_eq!(format_tick(0.05), "0.05");
        assert_eq!(format_tick(2.5), "2.5");
        assert_eq!(format_tick(0.0001), "1.0e-4");
        let close = |a: &[f64], b: &[f64]| a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-9 * y);
        assert!(close(&log_ticks(0.5, 500.0), &[1.0, 10.0, 100.0]));
        assert!(close(&log_ticks(0.5, 50.0), &[0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0]));
        assert!(close(&log_ticks(0.031, 0.055), &[0.04, 0.05]));
        // 60 decades: thinned to at most 12 labels.
        let wide = log_ticks(1.5e-30, 1.5e30);
        assert!((6..=12).contains(&wide.len()), "{wide:?}");
        assert!(log_ticks(0.0, 1.0).is_empty());
    }

    #[test]
    fn writes_a_png() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.png");
        write_loglog_png(&path, &[panel()], 400, 250).unwrap();
        let img = image::open(&path).unwrap();
        assert_eq!((img.width(), img.height()), (400, 250));
    }
}
