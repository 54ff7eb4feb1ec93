//! The figures of the report pages: per-pose values, the motions' rotation axes and angles,
//! drawn by plotters into inline SVG.

use anyhow::{Result, anyhow};
use handeye::{MotionFeatures, MotionPair, Pairing, PosePair, Setup, motion_pairs};
use plotters::prelude::*;

/// Size of one figure (SVG units).
pub(super) const SIZE: (u32, u32) = (900, 360);
/// Poses the motions of the axis and angle figures are taken between when every pair is used
/// (spread over the input): 1770 motions at most.
pub(super) const SAMPLE: usize = 60;

/// A motion as the figures draw it: its angle in degrees and its axis (gripper frame).
pub(super) type Drawn = (f64, Option<[f64; 3]>);

/// The motions a calibration used, as drawn, and the words that say which: consecutive ones
/// (every one, up to `SAMPLE²/2` spread over the recording), or those between every pair of up
/// to [`SAMPLE`] poses spread over it.
pub(super) fn motions_used(
    poses: &[PosePair],
    pairing: Pairing,
    setup: Setup,
) -> (Vec<Drawn>, String) {
    let drawn = |m: &MotionPair| {
        let f = MotionFeatures::of(&m.a);
        (f.angle.to_degrees(), f.axis.map(|k| [k.x, k.y, k.z]))
    };
    let n = poses.len();
    match pairing {
        Pairing::Consecutive => {
            let all = motion_pairs(poses, Pairing::Consecutive, setup);
            let most = SAMPLE * (SAMPLE - 1) / 2;
            let step = all.len().div_ceil(most).max(1);
            let shown: Vec<Drawn> = all.iter().step_by(step).map(drawn).collect();
            let words = if step == 1 {
                format!("the {} motions between consecutive poses", all.len())
            } else {
                format!(
                    "{} of the {} motions between consecutive poses (every {step}th)",
                    shown.len(),
                    all.len()
                )
            };
            (shown, words)
        }
        _ => {
            let idx: Vec<usize> = if n <= SAMPLE {
                (0..n).collect()
            } else {
                (0..SAMPLE).map(|k| k * (n - 1) / (SAMPLE - 1)).collect()
            };
            let mut shown = Vec::new();
            for (a, &i) in idx.iter().enumerate() {
                for &j in &idx[a + 1..] {
                    shown.push(drawn(&MotionPair::between(setup, &poses[i], &poses[j])));
                }
            }
            let words = if n <= SAMPLE {
                format!(
                    "the {} motions between every pair of the {n} poses",
                    shown.len()
                )
            } else {
                format!(
                    "the {} motions between every pair of {SAMPLE} of the {n} poses, spread over the recording",
                    shown.len()
                )
            };
            (shown, words)
        }
    }
}

/// One series of a per-pose figure: its legend, colour and (pose index, value) points.
pub(super) struct Series<'a> {
    pub label: &'a str,
    pub color: RGBColor,
    pub points: Vec<(usize, f64)>,
    /// Drawn as rings around the dots of the other series (so that equal values stay visible).
    pub ring: bool,
}

/// Values per pose (input order), one dot each; the poses in `marked` drawn in red.
pub(super) fn per_pose_figure(
    title: &str,
    y_desc: &str,
    poses: usize,
    series: &[Series<'_>],
    marked: &[usize],
) -> Result<String> {
    let top = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1))
        .filter(|v| v.is_finite())
        .fold(1e-9, f64::max)
        * 1.1;
    svg(SIZE, |root| {
        let mut chart = chart(&root, title, (36, 70))
            .build_cartesian_2d(0f64..poses.max(1) as f64, 0f64..top)
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc("pose (input order, from 0)")
            .y_desc(y_desc)
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        for s in series {
            let color = s.color;
            let style = move |c: RGBColor| -> (u32, ShapeStyle) {
                if s.ring {
                    (6, c.stroke_width(2))
                } else {
                    (3, c.filled())
                }
            };
            chart
                .draw_series(s.points.iter().filter(|p| p.1.is_finite()).map(|&(i, v)| {
                    let (size, shape) = style(if marked.contains(&i) { RED } else { color });
                    Circle::new((i as f64, v), size, shape)
                }))
                .map_err(|e| anyhow!("{e}"))?
                .label(s.label)
                .legend(move |(x, y)| {
                    let (size, shape) = style(color);
                    Circle::new((x + 10, y), size, shape)
                });
        }
        if series.len() > 1 {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()
                .map_err(|e| anyhow!("{e}"))?;
        }
        Ok(())
    })
}

/// The motions' rotation axes on the upper hemisphere (Lambert equal-area), dot size by angle.
pub(super) fn axes_figure(motions: &[Drawn]) -> Result<String> {
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
pub(super) fn angles_figure(motions: &[Drawn]) -> Result<String> {
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

/// Detections drawn in the residual figure at most (spread over the recording).
pub(super) const CORNERS_DRAWN: usize = 4000;

/// Each detection where it is in the image, with its reprojection residual as an arrow scaled
/// so that the 95th percentile is 4 % of the image's width (`scale`, returned with the number
/// drawn); mis-detections the solve left out as red crosses. A pattern (arrows that turn about the
/// centre, grow towards the edges, or all point one way in part of the image) is what a wrong
/// distortion, focal length or target size leaves; random noise leaves none.
pub(super) fn corners_figure(
    fit: &handeye::ReprojectionSummary,
    size: Option<(f64, f64)>,
) -> Result<(String, f64, usize)> {
    let corners = &fit.corners;
    let step = corners.len().div_ceil(CORNERS_DRAWN).max(1);
    let drawn: Vec<_> = corners.iter().step_by(step).collect();
    let (width, height) = size.unwrap_or_else(|| {
        let top = |k: usize| corners.iter().map(|c| c.pixel[k]).fold(1.0, f64::max);
        (top(0) * 1.05, top(1) * 1.05)
    });
    let mut lengths: Vec<f64> = drawn
        .iter()
        .filter(|c| c.kept)
        .map(|c| c.residual_px[0].hypot(c.residual_px[1]))
        .collect();
    lengths.sort_by(f64::total_cmp);
    let p95 = lengths
        .get((lengths.len() * 95 / 100).min(lengths.len().saturating_sub(1)))
        .copied()
        .unwrap_or(0.0);
    let scale = if p95 > 0.0 { 0.04 * width / p95 } else { 1.0 };
    // The image's aspect ratio, within a 900-unit-wide figure.
    let tall = (900.0 * height / width).clamp(300.0, 900.0) as u32;
    let text = svg((900, tall + 60), |root| {
        let mut chart = chart(
            &root,
            &format!("reprojection residual of each detection (arrows ×{scale:.0})"),
            (36, 60),
        )
        .build_cartesian_2d(0f64..width, height..0f64)
        .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc("u (px)")
            .y_desc("v (px)")
            .disable_mesh()
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        let (kept, left_out): (Vec<_>, Vec<_>) = drawn.iter().copied().partition(|c| c.kept);
        chart
            .draw_series(kept.iter().map(|c| {
                let [u, v] = c.pixel;
                let [du, dv] = c.residual_px;
                PathElement::new(
                    vec![(u, v), (u + scale * du, v + scale * dv)],
                    BLUE.stroke_width(1),
                )
            }))
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .draw_series(
                kept.iter()
                    .map(|c| Circle::new((c.pixel[0], c.pixel[1]), 1, BLUE.filled())),
            )
            .map_err(|e| anyhow!("{e}"))?;
        // A mis-detection's residual is off the scale: a cross where it was detected.
        chart
            .draw_series(
                left_out
                    .iter()
                    .map(|c| Cross::new((c.pixel[0], c.pixel[1]), 4, RED.stroke_width(2))),
            )
            .map_err(|e| anyhow!("{e}"))?;
        Ok(())
    })?;
    Ok((text, scale, drawn.len()))
}

/// An SVG figure drawn by `draw` into a string.
pub(super) fn svg(
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

/// A chart builder with the report's title style, margin and label areas (x, y).
pub(super) fn chart<'a, 'b>(
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
