//! The page of `online --report`: the estimate's convergence, the paper's thresholds and, for
//! two streams, the clock offset's correlation curve.

use std::path::Path;

use anyhow::{Result, anyhow};
use plotters::prelude::*;

use super::Page;
use super::charts::{SIZE, chart, svg};
use crate::figures::register_font;

/// One of the paper's calibrations: pose j, X, and the thresholds (β₀, α₀ in degrees) in force.
type Calibration = (usize, handeye::Transform, Option<(f64, f64)>);

/// What `online --report` keeps of a run (a few numbers per event, not the poses).
#[derive(Default)]
pub struct OnlineTrace {
    /// The paper's calibrations.
    pub calibrations: Vec<Calibration>,
    /// The accumulating estimator's reports: pose, X, uncertainty (degrees, input units).
    pub reports: Vec<(usize, handeye::Transform, f64, f64)>,
    /// Poses where a change was confirmed, and where it began.
    pub changes: Vec<(usize, usize)>,
    /// Poses held out.
    pub held_out: Vec<usize>,
    /// Poses pushed.
    pub poses: usize,
    /// For two streams with `--time-offset auto`: the offset used and the correlation curve.
    pub offset: Option<(f64, Vec<[f64; 2]>)>,
}

impl OnlineTrace {
    /// Keeps what a record (or the end) made happen: the paper's calibrations, the tracker's
    /// reports, changes and held-out poses.
    pub fn outputs(&mut self, o: &handeye::Outputs) {
        for e in &o.events {
            let thresholds = e.thresholds.map(|t| {
                (
                    t.beta.to_degrees(),
                    t.sin_alpha.clamp(-1.0, 1.0).asin().to_degrees(),
                )
            });
            self.calibrations.push((e.poses[2], e.x, thresholds));
        }
        if let Some(r) = &o.report {
            let e = &r.estimate;
            self.reports.push((
                r.pose,
                e.x,
                e.uncertainty_rotation_deg.unwrap_or(f64::NAN),
                e.uncertainty_translation.unwrap_or(f64::NAN),
            ));
        }
        if let Some(c) = &o.change {
            self.changes.push((c.change.confirmed, c.change.at));
        }
        self.held_out.extend(o.held_out.iter().map(|h| h.pose));
    }
}

/// Writes the report page of an online run: the estimate's convergence in rotation and in
/// translation (with its uncertainty band, changes and held-out poses), and the paper's thresholds.
pub fn write_online(path: &Path, trace: &OnlineTrace, summary: &str) -> Result<()> {
    register_font();
    // The estimates the run printed: the tracker's reports, or the paper's calibrations.
    let series: Vec<(usize, handeye::Transform, f64, f64)> = if trace.reports.is_empty() {
        trace
            .calibrations
            .iter()
            .map(|(p, x, _)| (*p, *x, f64::NAN, f64::NAN))
            .collect()
    } else {
        trace.reports.clone()
    };
    let last = series.last().map(|s| s.1);
    let gaps: Vec<(f64, f64, f64)> = series
        .iter()
        .map(|(p, x, _, _)| {
            let (dr, dt) = last.map_or((0.0, 0.0), |l| {
                (
                    handeye::errors_against_truth(x, &l).rot_deg,
                    (x.translation.vector - l.translation.vector).norm(),
                )
            });
            (*p as f64, dr, dt)
        })
        .collect();
    let rotation: Vec<(f64, f64, f64)> = series
        .iter()
        .zip(&gaps)
        .map(|((_, _, ur, _), g)| (g.0, g.1, *ur))
        .collect();
    let translation: Vec<(f64, f64, f64)> = series
        .iter()
        .zip(&gaps)
        .map(|((_, _, _, ut), g)| (g.0, g.2, *ut))
        .collect();
    let mut figures = vec![
        (
            convergence_figure("rotation from the last estimate (°)", &rotation, trace)?,
            "How far each reported estimate is from the last one, degrees, with its one-sigma band (shaded); red lines: a confirmed change of X or the target (dashed where it began); ticks at the bottom: poses held out.".to_string(),
        ),
        (
            convergence_figure("translation from the last estimate (input unit)", &translation, trace)?,
            "The same for the translation, in the input's unit.".to_string(),
        ),
    ];
    // The paper's thresholds where its selection ran (the accumulating estimator runs alone).
    if trace.reports.is_empty() {
        figures.push((
            thresholds_figure(trace)?,
            "The paper's adaptive thresholds at each of its calibrations: β₀ (least rotation of a selected motion) and α₀ (least angle between the two motions' axes), degrees.".to_string(),
        ));
    }
    if let Some((used, curve)) = &trace.offset {
        figures.push((
            offset_figure(*used, curve)?,
            format!(
                "Two streams: how well the gripper's and the camera's angular speeds correlate at each clock offset (camera − robot) searched; the line marks the offset used, {:.4} s (the correlation's peak, refined by how well the paired poses agree on one X).",
                used
            ),
        ));
    }
    let mut page = Page::new("handeye online", None);
    page.text("Summary", summary);
    for (svg, caption) in figures {
        page.figure(svg, &caption);
    }
    page.write(path)
}

/// Distance from the last estimate against the pose, with the uncertainty band, changes and
/// held-out poses.
fn convergence_figure(
    title: &str,
    points: &[(f64, f64, f64)],
    trace: &OnlineTrace,
) -> Result<String> {
    let top = points
        .iter()
        .map(|p| p.1 + if p.2.is_finite() { p.2 } else { 0.0 })
        .fold(1e-9, f64::max)
        * 1.1;
    let width = trace.poses.max(1) as f64;
    svg(SIZE, |root| {
        let mut chart = chart(&root, title, (36, 70))
            .build_cartesian_2d(0f64..width, 0f64..top)
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc("pose")
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        let band: Vec<(f64, f64, f64)> =
            points.iter().filter(|p| p.2.is_finite()).copied().collect();
        if band.len() > 1 {
            let upper = band.iter().map(|p| (p.0, p.1 + p.2));
            let lower = band.iter().rev().map(|p| (p.0, (p.1 - p.2).max(0.0)));
            chart
                .draw_series(std::iter::once(Polygon::new(
                    upper.chain(lower).collect::<Vec<_>>(),
                    BLUE.mix(0.15).filled(),
                )))
                .map_err(|e| anyhow!("{e}"))?;
        }
        chart
            .draw_series(LineSeries::new(points.iter().map(|p| (p.0, p.1)), &BLUE))
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .draw_series(
                points
                    .iter()
                    .map(|p| Circle::new((p.0, p.1), 3, BLUE.filled())),
            )
            .map_err(|e| anyhow!("{e}"))?;
        for &(confirmed, at) in &trace.changes {
            for (pose, style) in [
                (confirmed, RED.stroke_width(2)),
                (at, RED.mix(0.5).stroke_width(1)),
            ] {
                chart
                    .draw_series(LineSeries::new(
                        [(pose as f64, 0.0), (pose as f64, top)],
                        style,
                    ))
                    .map_err(|e| anyhow!("{e}"))?;
            }
        }
        chart
            .draw_series(
                trace
                    .held_out
                    .iter()
                    .map(|&p| PathElement::new([(p as f64, 0.0), (p as f64, top * 0.03)], RED)),
            )
            .map_err(|e| anyhow!("{e}"))?;
        Ok(())
    })
}

/// β₀ and α₀ at each of the paper's calibrations.
fn thresholds_figure(trace: &OnlineTrace) -> Result<String> {
    let beta: Vec<(f64, f64)> = trace
        .calibrations
        .iter()
        .filter_map(|(p, _, t)| t.map(|t| (*p as f64, t.0)))
        .collect();
    let alpha: Vec<(f64, f64)> = trace
        .calibrations
        .iter()
        .filter_map(|(p, _, t)| t.map(|t| (*p as f64, t.1)))
        .collect();
    let top = beta.iter().chain(&alpha).map(|p| p.1).fold(1.0, f64::max) * 1.1;
    let width = trace.poses.max(1) as f64;
    svg(SIZE, |root| {
        let mut chart = chart(&root, "the paper's thresholds (°)", (36, 60))
            .build_cartesian_2d(0f64..width, 0f64..top)
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc("pose")
            .y_desc("degrees")
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .draw_series(LineSeries::new(beta.iter().copied(), &BLUE))
            .map_err(|e| anyhow!("{e}"))?
            .label("β₀")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLUE));
        chart
            .draw_series(LineSeries::new(alpha.iter().copied(), &GREEN))
            .map_err(|e| anyhow!("{e}"))?
            .label("α₀")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], GREEN));
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        Ok(())
    })
}

/// The clock-offset correlation curve, with the offset used.
fn offset_figure(used: f64, curve: &[[f64; 2]]) -> Result<String> {
    let (lo, hi) = curve
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p[0]), hi.max(p[0]))
        });
    let (lo, hi) = if lo < hi {
        (lo, hi)
    } else {
        (used - 1.0, used + 1.0)
    };
    let bottom = curve.iter().map(|p| p[1]).fold(0.0, f64::min);
    svg(SIZE, |root| {
        let mut chart = chart(
            &root,
            "angular-speed correlation against the clock offset",
            (36, 60),
        )
        .build_cartesian_2d(lo..hi, bottom..1.0)
        .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc("camera − robot clock (s)")
            .y_desc("correlation")
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .draw_series(LineSeries::new(curve.iter().map(|p| (p[0], p[1])), &BLUE))
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .draw_series(LineSeries::new(
                [(used, bottom), (used, 1.0)],
                RED.stroke_width(2),
            ))
            .map_err(|e| anyhow!("{e}"))?;
        Ok(())
    })
}
