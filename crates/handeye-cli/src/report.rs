//! `--report FILE.html`: one self-contained page (inline SVG, no external resource) that shows a
//! calibration at a glance: how well each pose is predicted by the others, where the rotation axes
//! lie, and how large the motions are.

use std::path::Path;

use anyhow::{Result, anyhow};
use handeye::Report;
use handeye::leave_one_out;
use handeye::{MotionFeatures, MotionPair, PosePair, Setup};
use plotters::prelude::*;

use crate::figures::register_font;

/// Size of one figure (SVG units).
const SIZE: (u32, u32) = (900, 360);
/// Poses the motions of the axis and angle figures are taken between (spread over the input).
const SAMPLE: usize = 60;

/// Checks before the work that the report can be written at `path` (creating it, or opening an
/// existing one to append, then leaving it as it was): a path that cannot be written would
/// otherwise fail after the calibration.
pub fn check_writable(path: &Path) -> Result<()> {
    let existed = path.exists();
    std::fs::OpenOptions::new()
        .append(true)
        .create(true)
        .open(path)
        .map_err(|e| anyhow!("cannot write the report {}: {e}", path.display()))?;
    if !existed {
        let _ = std::fs::remove_file(path);
    }
    Ok(())
}

/// Writes the report page of a batch calibration.
pub fn write_calibrate(
    path: &Path,
    poses: &[PosePair],
    setup: Setup,
    report: &Report,
) -> Result<()> {
    register_font();
    let outliers: Vec<usize> = report.outliers.poses.iter().map(|p| p.pose).collect();
    let motions = sampled_motions(poses, setup);
    let figures = [
        (
            held_out_figure(poses, setup, &outliers)?,
            "Each pose's camera observation predicted from all the other poses (leave-one-out): the gap in degrees. Poses far above the rest (red: outliers by the rigid-motion test) were paired with the wrong robot pose or badly detected.".to_string(),
        ),
        (
            axes_figure(&motions)?,
            format!(
                "Rotation axes of the gripper's motions (between up to {SAMPLE} poses spread over the recording), gripper frame, seen from +z (equal-area; an axis and its opposite are one point). Spread: {:.1}°. Axes crowded in one place leave X's rotation about them weakly determined.",
                report.quality.axis_spread_deg
            ),
        ),
        (
            angles_figure(&motions)?,
            format!(
                "Rotation angles of those motions. Angles below a few degrees carry little information; {:.1}° to {:.1}° between consecutive poses.",
                report.quality.rotation_range_deg[0], report.quality.rotation_range_deg[1]
            ),
        ),
    ];
    let t = report.transform.translation.vector;
    let summary = format!(
        "<p><b>X = {}</b>: translation [{:.5}, {:.5}, {:.5}] (input unit), rotation {:.3}°; one-sigma {:.3}° and {:.5}; {} poses, {} motions, method {}.</p>",
        report.frame,
        t.x,
        t.y,
        t.z,
        report.transform.rotation.angle().to_degrees(),
        report.uncertainty.rotation_deg,
        report.uncertainty.translation,
        report.poses,
        report.motions,
        report.method.name(),
    );
    let warnings: String = report
        .warnings
        .iter()
        .map(|w| format!("<li>{}</li>", escape(&crate::faces::warning(w))))
        .collect();
    let warnings = if warnings.is_empty() {
        "<p>No warnings.</p>".to_string()
    } else {
        format!("<ul class=\"warnings\">{warnings}</ul>")
    };
    std::fs::write(
        path,
        page("handeye calibrate", &summary, &warnings, &figures),
    )
    .map_err(|e| anyhow!("cannot write {}: {e}", path.display()))
}

/// The HTML page around the figures.
fn page(title: &str, summary: &str, warnings: &str, figures: &[(String, String)]) -> String {
    let body: String = figures
        .iter()
        .map(|(svg, caption)| {
            format!(
                "<figure>{svg}<figcaption>{}</figcaption></figure>\n",
                escape(caption)
            )
        })
        .collect();
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{title}</title>\n<style>body{{font-family:sans-serif;max-width:960px;margin:2em auto;color:#222}}figure{{margin:1.5em 0}}figcaption{{font-size:0.9em;color:#444}}.warnings li{{color:#a33}}</style></head>\n<body><h1>{title}</h1>\n{summary}\n{warnings}\n{body}</body></html>\n"
    )
}

/// Escapes text for HTML.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The motions between up to [`SAMPLE`] poses spread over the input: (angle in degrees, axis).
fn sampled_motions(poses: &[PosePair], setup: Setup) -> Vec<(f64, Option<[f64; 3]>)> {
    let n = poses.len();
    let idx: Vec<usize> = if n <= SAMPLE {
        (0..n).collect()
    } else {
        (0..SAMPLE).map(|k| k * (n - 1) / (SAMPLE - 1)).collect()
    };
    let mut out = Vec::new();
    for (a, &i) in idx.iter().enumerate() {
        for &j in &idx[a + 1..] {
            let f = MotionFeatures::of(&MotionPair::between(setup, &poses[i], &poses[j]).a);
            out.push((f.angle.to_degrees(), f.axis.map(|k| [k.x, k.y, k.z])));
        }
    }
    out
}

/// An SVG figure drawn by `draw` into a string.
fn svg(
    size: (u32, u32),
    draw: impl FnOnce(DrawingArea<SVGBackend, plotters::coord::Shift>) -> Result<()>,
) -> Result<String> {
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
        draw(root)?;
    }
    Ok(text)
}

/// Held-out gap per pose, degrees, outliers in red.
fn held_out_figure(poses: &[PosePair], setup: Setup, outliers: &[usize]) -> Result<String> {
    let gaps: Vec<(usize, f64)> = leave_one_out(poses, setup)
        .map(|c| c.poses.iter().map(|g| (g.pose, g.rotation_deg)).collect())
        .unwrap_or_default();
    let top = gaps.iter().map(|g| g.1).fold(1e-6, f64::max) * 1.1;
    svg(SIZE, |root| {
        let mut chart = chart(&root, "held-out gap per pose (°)", (36, 60))
            .build_cartesian_2d(0f64..poses.len().max(1) as f64, 0f64..top)
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc("pose")
            .y_desc("degrees")
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .draw_series(gaps.iter().map(|&(i, g)| {
                let color = if outliers.contains(&i) { RED } else { BLUE };
                Circle::new((i as f64, g), 3, color.filled())
            }))
            .map_err(|e| anyhow!("{e}"))?;
        Ok(())
    })
}

/// The motions' rotation axes on the upper hemisphere (Lambert equal-area), dot size by angle.
fn axes_figure(motions: &[(f64, Option<[f64; 3]>)]) -> Result<String> {
    let largest = motions.iter().map(|m| m.0).fold(1e-9, f64::max);
    let points: Vec<(f64, f64, f64)> = motions
        .iter()
        .filter_map(|(angle, axis)| {
            let [x, y, z] = (*axis)?;
            // An axis and its opposite are the same line: take the one with z ≥ 0.
            let (x, y, z) = if z < 0.0 { (-x, -y, -z) } else { (x, y, z) };
            let r = (2.0 / (1.0 + z)).sqrt();
            Some((x * r, y * r, angle / largest))
        })
        .collect();
    // Square, so that the hemisphere's rim is a circle.
    svg((500, 500), |root| {
        let mut chart = chart(&root, "rotation axes (gripper frame, from +z)", (30, 40))
            .build_cartesian_2d(-1.5f64..1.5, -1.5f64..1.5)
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc("x")
            .y_desc("y")
            .disable_mesh()
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        let rim = std::f64::consts::SQRT_2;
        chart
            .draw_series(LineSeries::new(
                (0..=100).map(|k| {
                    let a = std::f64::consts::TAU * k as f64 / 100.0;
                    (rim * a.cos(), rim * a.sin())
                }),
                &BLACK,
            ))
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .draw_series(points.iter().map(|&(x, y, w)| {
                Circle::new((x, y), (2.0 + 4.0 * w) as u32, BLUE.mix(0.5).filled())
            }))
            .map_err(|e| anyhow!("{e}"))?;
        Ok(())
    })
}

/// Histogram of the motions' rotation angles, degrees.
fn angles_figure(motions: &[(f64, Option<[f64; 3]>)]) -> Result<String> {
    const BINS: usize = 36;
    let mut counts = [0u32; BINS];
    for (angle, _) in motions {
        let bin = ((angle / 180.0) * BINS as f64)
            .floor()
            .clamp(0.0, (BINS - 1) as f64) as usize;
        counts[bin] += 1;
    }
    let top = counts.iter().copied().max().unwrap_or(1).max(1);
    svg(SIZE, |root| {
        let mut chart = chart(&root, "rotation angle of the motions (°)", (36, 60))
            .build_cartesian_2d(0f64..180.0, 0u32..top + 1)
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc("degrees")
            .y_desc("motions")
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .draw_series(counts.iter().enumerate().map(|(k, &c)| {
                let w = 180.0 / BINS as f64;
                Rectangle::new(
                    [(k as f64 * w, 0), ((k + 1) as f64 * w, c)],
                    BLUE.mix(0.6).filled(),
                )
            }))
            .map_err(|e| anyhow!("{e}"))?;
        Ok(())
    })
}

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
    /// Keeps what a paper's calibration says.
    pub fn calibration(&mut self, e: &handeye::Event) {
        let thresholds = e.thresholds.map(|t| {
            (
                t.beta.to_degrees(),
                t.sin_alpha.clamp(-1.0, 1.0).asin().to_degrees(),
            )
        });
        self.calibrations.push((e.poses[2], e.x, thresholds));
    }

    /// Keeps what the tracker did with a pose.
    pub fn step(&mut self, step: &handeye::Step) {
        if let Some(r) = &step.report {
            let e = &r.estimate;
            self.reports.push((
                r.pose,
                e.x,
                e.uncertainty_rotation_deg.unwrap_or(f64::NAN),
                e.uncertainty_translation.unwrap_or(f64::NAN),
            ));
        }
        if let Some(c) = &step.change {
            self.changes.push((c.confirmed, c.at));
        }
        self.held_out.extend(step.held_out.map(|_| step.pose));
        self.held_out.extend(step.earlier.iter().map(|(p, _)| *p));
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
                    handeye::rotation_angle_between(&x.rotation, &l.rotation).to_degrees(),
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
    let figures = [
        (
            convergence_figure("rotation from the last estimate (°)", &rotation, trace)?,
            "How far each reported estimate is from the last one, degrees, with its one-sigma band (shaded); red lines: a confirmed change of X or the target (dashed where it began); ticks at the bottom: poses held out.".to_string(),
        ),
        (
            convergence_figure("translation from the last estimate (input unit)", &translation, trace)?,
            "The same for the translation, in the input's unit.".to_string(),
        ),
        (
            thresholds_figure(trace)?,
            "The paper's adaptive thresholds at each of its calibrations: β₀ (least rotation of a selected motion) and α₀ (least angle between the two motions' axes), degrees.".to_string(),
        ),
    ];
    let mut figures = figures.to_vec();
    if let Some((used, curve)) = &trace.offset {
        figures.push((
            offset_figure(*used, curve)?,
            format!(
                "Two streams: how well the gripper's and the camera's angular speeds correlate at each clock offset (camera − robot) searched; the line marks the offset used, {:.4} s (the correlation's peak, refined by how well the paired poses agree on one X).",
                used
            ),
        ));
    }
    let summary = format!("<p>{}</p>", escape(summary));
    std::fs::write(path, page("handeye online", &summary, "", &figures))
        .map_err(|e| anyhow!("cannot write {}: {e}", path.display()))
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

/// A chart builder with the report's title style, margin and label areas (x, y).
fn chart<'a, 'b>(
    root: &'a DrawingArea<SVGBackend<'b>, plotters::coord::Shift>,
    title: &str,
    (x_area, y_area): (u32, u32),
) -> ChartBuilder<'a, 'b, SVGBackend<'b>> {
    let mut builder = ChartBuilder::on(root);
    builder
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(x_area)
        .y_label_area_size(y_area);
    builder
}
