//! Figures of the experiments (the paper's Fig. 2, Fig. 3 and a Table I chart; the tracking
//! study's error curves), as SVG and PNG.
//!
//! Text is drawn with an embedded DejaVu Sans (assets/, Bitstream Vera licence), so no system font
//! library is needed.

use std::path::{Path, PathBuf};
use std::sync::Once;

use anyhow::{Context, Result, anyhow};
use handeye::experiment::ExperimentReport;
use plotters::coord::Shift;
use plotters::prelude::*;

/// The embedded font.
static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

/// Registers the embedded font once (a font that does not parse leaves text undrawn; the figures
/// are still written).
pub fn register_font() {
    REGISTER.call_once(|| {
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// A number read off a method's summary (the real-time panels).
#[derive(Clone, Copy)]
enum Summary {
    /// Time per calibration, µs.
    Time,
    /// Mean ‖R_est − R‖_F.
    Rotation,
    /// Mean ‖t − t_est‖ / ‖t‖.
    Translation,
}

/// A number read off each series of a method (the accuracy and adaptability curves).
#[derive(Clone, Copy)]
enum PerSeries {
    /// ‖R_est − R‖_F.
    Rotation,
    /// ‖t − t_est‖ / ‖t‖.
    Translation,
    /// Calibrations made.
    Calibrations,
}

/// Figure size in pixels (SVG units).
const SIZE: (u32, u32) = (1000, 420);

/// One curve: a label, its values and its colour.
struct Curve<'a> {
    label: &'a str,
    values: Vec<f64>,
    color: RGBColor,
    dotted: bool,
}

/// Writes the experiment's figure(s) into `dir` as SVG and PNG; returns the files written (none
/// for the advice study).
pub fn write_figures(report: &ExperimentReport, dir: &Path) -> Result<Vec<PathBuf>> {
    REGISTER.call_once(|| {
        // A font that does not parse leaves text undrawn; the figures are still written.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
    let stem = match report {
        ExperimentReport::Accuracy(_) => "fig2_accuracy",
        ExperimentReport::Adaptability(_) => "fig3_adaptability",
        ExperimentReport::Realtime(_) => "table1_realtime",
        ExperimentReport::Tracking(_) => "fig_tracking",
        ExperimentReport::Advice(_) => return Ok(Vec::new()),
    };
    let svg = dir.join(format!("{stem}.svg"));
    let png = dir.join(format!("{stem}.png"));
    draw(report, SVGBackend::new(&svg, SIZE).into_drawing_area())?;
    draw(report, BitMapBackend::new(&png, SIZE).into_drawing_area())?;
    Ok(vec![svg, png])
}

/// Draws the figure of `report` on any backend.
fn draw<DB: DrawingBackend>(report: &ExperimentReport, root: DrawingArea<DB, Shift>) -> Result<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
    // The paper's experiments' summaries, one per method.
    let methods = match report {
        ExperimentReport::Accuracy(r)
        | ExperimentReport::Adaptability(r)
        | ExperimentReport::Realtime(r) => Some(r),
        ExperimentReport::Tracking(_) | ExperimentReport::Advice(_) => None,
    };
    let per = |name: &str, of: PerSeries| -> Vec<f64> {
        let value = |r: f64, t: f64, n: usize| match of {
            PerSeries::Rotation => r,
            PerSeries::Translation => t,
            PerSeries::Calibrations => n as f64,
        };
        methods
            .and_then(|r| r.method(name))
            .map(|m| {
                (m.per_series.iter())
                    .map(|s| value(s.rot_fro, s.trans_rel, s.calibrations))
                    .collect()
            })
            .unwrap_or_default()
    };
    let curve = |label, name: &'static str, f, color, dotted| Curve {
        label,
        values: per(name, f),
        color,
        dotted,
    };
    match report {
        ExperimentReport::Accuracy(_) => {
            let (left, right) = root.split_horizontally(SIZE.0 / 2);
            let (rot, trans) = (PerSeries::Rotation, PerSeries::Translation);
            lines(
                &left,
                "(a) mean rotation error ‖R_est − R‖_F per series",
                &[
                    curve("conventional (O)", "conventional", rot, RED, false),
                    curve("adaptive (*)", "adaptive", rot, BLUE, true),
                ],
            )?;
            lines(
                &right,
                "(b) mean ‖t − t_est‖ / ‖t‖ per series",
                &[
                    curve("conventional (O)", "conventional", trans, RED, false),
                    curve("adaptive (*)", "adaptive", trans, BLUE, true),
                ],
            )?;
        }
        ExperimentReport::Adaptability(_) => {
            let n = PerSeries::Calibrations;
            lines(
                &root,
                "calibrations per series",
                &[
                    curve("adaptive (O)", "adaptive", n, BLUE, false),
                    curve("fixed thresholds (*)", "fixed", n, RED, true),
                ],
            )?;
        }
        ExperimentReport::Realtime(report) => {
            let methods: Vec<_> = ["adaptive", "optimal"]
                .iter()
                .filter_map(|m| report.method(m))
                .collect();
            let areas = root.split_evenly((1, 3));
            let panels = [
                ("time per calibration (µs)", Summary::Time),
                ("mean ‖R_est − R‖_F", Summary::Rotation),
                ("mean ‖t − t_est‖ / ‖t‖", Summary::Translation),
            ];
            for (area, (title, summary)) in areas.iter().zip(panels) {
                let bars_of: Vec<(&str, f64)> = (methods.iter())
                    .map(|m| {
                        let value = match summary {
                            Summary::Time => m.time_per_calibration_s * 1e6,
                            Summary::Rotation => m.rot_fro_mean,
                            Summary::Translation => m.trans_rel_mean,
                        };
                        (m.method.as_str(), value)
                    })
                    .collect();
                bars(area, title, &bars_of)?;
            }
        }
        ExperimentReport::Tracking(report) => {
            let (left, right) = root.split_horizontally(SIZE.0 / 2);
            for (area, title, rotation) in [
                (&left, "mean ‖R_est − R‖_F vs poses seen", true),
                (&right, "mean ‖t − t_est‖ / ‖t‖ vs poses seen", false),
            ] {
                let curves: Vec<(&str, Vec<(f64, f64)>)> = (report.curves.iter())
                    .map(|c| {
                        let values = if rotation { &c.rot_fro } else { &c.trans_rel };
                        let points = (c.poses.iter().zip(values))
                            .filter(|(_, v)| v.is_finite() && **v > 0.0)
                            .map(|(p, v)| (*p as f64, *v))
                            .collect();
                        (c.method.as_str(), points)
                    })
                    .collect();
                log_lines(area, title, report.config.poses as f64, &curves)?;
            }
        }
        ExperimentReport::Advice(_) => {}
    }
    root.present().map_err(|e| anyhow!("{e}"))?;
    Ok(())
}

/// A line chart of per-series values.
fn lines<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    curves: &[Curve<'_>],
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let n = curves
        .iter()
        .map(|c| c.values.len())
        .max()
        .unwrap_or(0)
        .max(1);
    let top = curves
        .iter()
        .flat_map(|c| c.values.iter().copied())
        .filter(|v| v.is_finite())
        .fold(0.0_f64, f64::max);
    let top = if top > 0.0 { top * 1.1 } else { 1.0 };
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(30)
        .y_label_area_size(60)
        .build_cartesian_2d(1f64..n as f64, 0f64..top)
        .map_err(|e| anyhow!("{e}"))?;
    chart
        .configure_mesh()
        .x_desc("series")
        .label_style(("sans-serif", 12))
        .draw()
        .map_err(|e| anyhow!("{e}"))?;
    for c in curves {
        let points: Vec<(f64, f64)> = c
            .values
            .iter()
            .enumerate()
            .filter(|(_, v)| v.is_finite())
            .map(|(i, v)| (i as f64 + 1.0, *v))
            .collect();
        let color = c.color;
        let style = if c.dotted {
            color.stroke_width(1)
        } else {
            color.stroke_width(2)
        };
        chart
            .draw_series(LineSeries::new(points.clone(), style))
            .map_err(|e| anyhow!("{e}"))?
            .label(c.label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
        if c.dotted {
            chart
                .draw_series(points.iter().map(|p| Cross::new(*p, 4, color)))
                .map_err(|e| anyhow!("{e}"))?;
        } else {
            chart
                .draw_series(points.iter().map(|p| Circle::new(*p, 3, color)))
                .map_err(|e| anyhow!("{e}"))?;
        }
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .draw()
        .map_err(|e| anyhow!("{e}"))?;
    Ok(())
}

/// A bar chart of one value per method.
fn bars<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    values: &[(&str, f64)],
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let top = values
        .iter()
        .map(|v| v.1)
        .filter(|v| v.is_finite())
        .fold(0.0_f64, f64::max);
    let top = if top > 0.0 { top * 1.2 } else { 1.0 };
    let names: Vec<String> = values.iter().map(|v| v.0.to_string()).collect();
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 16))
        .margin(12)
        .x_label_area_size(30)
        .y_label_area_size(60)
        .build_cartesian_2d(0..values.len(), 0f64..top)
        .map_err(|e| anyhow!("{e}"))?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(values.len())
        .x_label_formatter(&|i| names.get(*i).cloned().unwrap_or_default())
        .label_style(("sans-serif", 12))
        .draw()
        .map_err(|e| anyhow!("{e}"))?;
    let colors = [BLUE, GREEN];
    chart
        .draw_series(values.iter().enumerate().map(|(i, (_, v))| {
            let c = colors[i % colors.len()];
            Rectangle::new(
                [(i, 0.0), (i + 1, if v.is_finite() { *v } else { 0.0 })],
                c.mix(0.6).filled(),
            )
        }))
        .map_err(|e| anyhow!("{e}"))?;
    Ok(())
}

/// Writes a file, naming it in the error.
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))
}

/// A line chart on a log scale of points (poses seen, a positive error) per labelled curve, one
/// colour each (the tracking figure's panels).
fn log_lines<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    max_x: f64,
    curves: &[(&str, Vec<(f64, f64)>)],
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let colors = [BLUE, RED, MAGENTA, BLACK];
    let (lo, hi) = (curves.iter())
        .flat_map(|(_, points)| points.iter().map(|p| p.1))
        .fold((f64::INFINITY, 0.0_f64), |(a, b), v| (a.min(v), b.max(v)));
    let (lo, hi) = if lo < hi {
        (lo / 1.5, hi * 1.5)
    } else {
        (1e-4, 1.0)
    };
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 16))
        .margin(12)
        .x_label_area_size(30)
        .y_label_area_size(60)
        .build_cartesian_2d(0f64..max_x, (lo..hi).log_scale())
        .map_err(|e| anyhow!("{e}"))?;
    chart
        .configure_mesh()
        .x_desc("poses")
        .label_style(("sans-serif", 12))
        .draw()
        .map_err(|e| anyhow!("{e}"))?;
    for ((label, points), color) in curves.iter().zip(colors) {
        chart
            .draw_series(LineSeries::new(points.clone(), color.stroke_width(2)))
            .map_err(|e| anyhow!("{e}"))?
            .label(*label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 12))
        .draw()
        .map_err(|e| anyhow!("{e}"))?;
    Ok(())
}
