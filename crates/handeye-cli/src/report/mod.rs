//! `--report FILE.html`: one self-contained page (inline SVG, no external resource) per run.
//!
//! Every page opens with the verdict and the text face's summary (the same words the terminal
//! shows), then X in a form to copy, then the figures of the run: for a calibration, how well each
//! pose is predicted by the others and the motions it used; for a refusal, the motions that were
//! not enough; for `verify`, where the saved X and the recording's own place the target.

mod charts;
mod online;

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Result, anyhow};
use handeye::{
    HandEyeReport, Pairing, PosePair, PoseResiduals, Reading, RobotWorldReport, Setup, Transform,
    Unit, Verification, Written, leave_one_out, transform_from_matrix4,
};
use plotters::style::RGBColor;
use serde_json::{Value, json};

use crate::faces::{rpy, unit_name};
use crate::figures::register_font;
use charts::{Series, angles_figure, axes_figure, corners_figure, motions_used, per_pose_figure};
pub use online::{OnlineTrace, write_online};

/// The poses worst predicted, listed by name under the per-pose figures.
const WORST: usize = 10;
/// The colour of the recording's own X in the verify figure (plotters' blue).
const OWN: RGBColor = RGBColor(0, 0, 255);
/// The colour of the saved X in the verify figure.
const SAVED: RGBColor = RGBColor(230, 120, 0);

/// What every page of a run shows beside its own result: the poses as read, their names, and the
/// text face's summary.
pub struct RunPage<'a> {
    /// The poses as the input wrote them (the result's reading is applied here).
    pub poses: &'a [PosePair],
    /// Each pose's name (`file:line`), or none.
    pub names: &'a [String],
    /// The directions the input wrote the poses in (for the reading).
    pub written: Written,
    /// The setup.
    pub setup: Setup,
    /// The length unit of the poses as solved.
    pub unit: Option<Unit>,
    /// The text face's summary.
    pub summary: String,
}

impl RunPage<'_> {
    /// Pose `i`'s label: its name (`file:line`) or its number.
    fn label(&self, i: usize) -> String {
        match self.names.get(i) {
            Some(name) if !name.is_empty() => name.clone(),
            _ => format!("pose {i}"),
        }
    }

    /// The poses read as the result was solved under.
    fn read(&self, reading: Reading) -> Vec<PosePair> {
        reading.apply(self.poses, self.written)
    }
}

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

/// Writes the page of a batch calibration.
pub fn write_calibrate(path: &Path, run: &RunPage<'_>, r: &HandEyeReport) -> Result<()> {
    register_font();
    let mut page = Page::new("handeye calibrate", Some(r.verdict.name()));
    page.text("Summary", &run.summary);
    page.copyable(
        "X, to copy",
        &transform_json(&r.frame, &r.transform, run.unit),
    );
    let poses = run.read(r.reading.applied);
    let outliers: Vec<usize> = r.outliers.poses.iter().map(|p| p.pose).collect();
    held_out(&mut page, run, &poses, &outliers)?;
    let used: Vec<PosePair> = if r.outliers.rejected {
        without(&poses, &outliers)
    } else {
        poses
    };
    motions(
        &mut page,
        &used,
        r.pairing,
        run.setup,
        r.quality.axis_spread_deg,
    )?;
    page.write(path)
}

/// Writes the page of a robot-world calibration: X and the target's pose, each pose's residual.
pub fn write_robot_world(path: &Path, run: &RunPage<'_>, r: &RobotWorldReport) -> Result<()> {
    register_font();
    let mut page = Page::new("handeye calibrate --robot-world", Some(r.verdict.name()));
    page.text("Summary", &run.summary);
    page.copyable(
        "X and the target's pose, to copy",
        &json!([
            transform_json(&r.frame, &r.transform, run.unit),
            transform_json(&r.target.frame, &r.target_transform, run.unit),
        ]),
    );
    let poses = run.read(r.reading.applied);
    let outliers: Vec<usize> = r.outliers.poses.iter().map(|p| p.pose).collect();
    // The residuals are of the poses solved: without the rejected outliers.
    let solved: Vec<usize> = (0..poses.len())
        .filter(|i| !(r.outliers.rejected && outliers.contains(i)))
        .collect();
    let per_pose: Vec<(usize, f64, f64)> = solved
        .iter()
        .zip(&r.residual.per_pose)
        .map(|(&i, p)| (i, p.angle_deg(), p.distance()))
        .collect();
    per_pose_pages(
        &mut page,
        run,
        &per_pose,
        &outliers,
        "residual of A X = Y B per pose",
        "How far each pose is from A X = Y B under the solved X and target pose (red: outliers by the rigid-motion test). A pose far above the rest was paired with the wrong robot pose or badly detected.",
    )?;
    let used: Vec<PosePair> = solved.iter().map(|&i| poses[i]).collect();
    motions(&mut page, &used, Pairing::All, run.setup, f64::NAN)?;
    page.write(path)
}

/// Writes the page of a calibration on the pixels (`--method reprojection`): X and the target's
/// pose, each frame's reprojection RMS, each detection's residual in the image (`image`: its
/// width and height in pixels, when the intrinsics give them), the robot's motions.
pub fn write_pixels(
    path: &Path,
    run: &RunPage<'_>,
    r: &HandEyeReport,
    image: Option<(f64, f64)>,
) -> Result<()> {
    register_font();
    let mut page = Page::new(
        "handeye calibrate --method reprojection",
        Some(r.verdict.name()),
    );
    page.text("Summary", &run.summary);
    let mut copy = vec![transform_json(&r.frame, &r.transform, run.unit)];
    if let Some(p) = &r.reprojection {
        let target =
            transform_from_matrix4(&nalgebra::Matrix4::from_fn(|i, j| p.target.matrix[i][j]))
                .map_err(|e| anyhow!("the target's pose: {e:?}"))?;
        copy.push(transform_json(&p.target_frame, &target, run.unit));
        let points: Vec<(usize, f64)> = p.per_frame.iter().map(|f| f.rms_px).enumerate().collect();
        page.figure(
            per_pose_figure(
                "reprojection RMS per frame (px)",
                "pixels",
                points.len(),
                &[Series {
                    label: "frame",
                    color: OWN,
                    points: points.clone(),
                    ring: false,
                }],
                &[],
            )?,
            &format!(
                "Each frame's RMS reprojection error over its detections under the solved X and target pose, pixels (all frames: {:.3} px RMS over {} detections, {} left out as mis-detections). A frame far above the rest was detected badly or paired with the wrong robot pose.",
                p.rms_px,
                p.detections,
                p.outlier_detections.len()
            ),
        );
        if !p.corners.is_empty() {
            let (svg, scale, drawn) = corners_figure(p, image)?;
            let shown = if drawn < p.corners.len() {
                format!(
                    "{drawn} of the {} detections, spread over the recording",
                    p.corners.len()
                )
            } else {
                format!("all {} detections", p.corners.len())
            };
            page.figure(
                svg,
                &format!(
                    "Where each detection is in the image, and its residual (detected less projected under the solved X and target pose) as an arrow {scale:.0} times its length ({shown}; red crosses: left out as mis-detections). Random detection noise points every way; arrows that turn about the centre, grow towards the edges or share a direction in one part of the image come from the camera's model (distortion, focal length) or the target's size, which more frames will not average out."
                ),
            );
        }
        let mut worst: Vec<_> = p.per_frame.iter().collect();
        worst.sort_by(|a, b| b.rms_px.total_cmp(&a.rms_px));
        let rows = worst
            .iter()
            .take(WORST)
            .map(|f| vec![f.name.clone(), format!("{:.3}", f.rms_px)])
            .collect();
        page.table(
            &format!("The {} frames worst fitted", worst.len().min(WORST)),
            &["frame", "reprojection RMS (px)"],
            rows,
        );
    }
    page.copyable("X and the target's pose, to copy", &json!(copy));
    let poses = run.read(r.reading.applied);
    motions(&mut page, &poses, Pairing::All, run.setup, f64::NAN)?;
    page.write(path)
}

/// Writes the page of a refused calibration: why, and the motions that were not enough.
pub fn write_refused(path: &Path, poses: &[PosePair], setup: Setup, why: &str) -> Result<()> {
    register_font();
    let mut page = Page::new("handeye calibrate", Some("refused"));
    page.text("Why", why);
    motions(&mut page, poses, Pairing::All, setup, f64::NAN)?;
    page.write(path)
}

/// Writes the page of `verify`: the verdict, the two X's, and where each places the target.
pub fn write_verify(path: &Path, run: &RunPage<'_>, v: &Verification) -> Result<()> {
    register_font();
    let mut page = Page::new("handeye verify", Some(v.verdict.name()));
    page.text("Summary", &run.summary);
    let saved = transform_from_matrix4(&nalgebra::Matrix4::from_fn(|i, j| v.saved.matrix[i][j]))
        .map_err(|e| anyhow!("the saved X: {e:?}"))?;
    let frame = run.setup.x_frame();
    let mut both = vec![transform_json(&format!("saved {frame}"), &saved, run.unit)];
    let own = v.recording.as_ref();
    if let Some(r) = own {
        both.push(transform_json(
            &format!("the recording's {frame}"),
            &r.transform,
            run.unit,
        ));
    }
    page.copyable("The saved X and the recording's, to copy", &json!(both));
    let reading = own.map_or(Reading::AsGiven, |r| r.reading.applied);
    let poses = run.read(reading);
    let mut series = Vec::new();
    if let Some(r) = own {
        series.push(Series {
            label: "through the recording's own X",
            color: OWN,
            points: target_scatter(&poses, run.setup, &r.transform),
            ring: false,
        });
    }
    series.push(Series {
        label: "through the saved X",
        color: SAVED,
        points: target_scatter(&poses, run.setup, &saved),
        ring: own.is_some(),
    });
    let u = unit_name(run.unit);
    page.figure(
        per_pose_figure(
            &format!("where each pose places the target ({u} from their common place)"),
            u,
            poses.len(),
            &series,
            &[],
        )?,
        "Each pose places the target (in the base for eye-in-hand, in the gripper for eye-to-hand) through X: its distance from their common place (a robust mean). An X that fits the recording places it in one spot up to the noise (blue dots: the recording's own X); a saved X that no longer fits scatters it wider (orange rings).",
    );
    motions(&mut page, &poses, Pairing::All, run.setup, f64::NAN)?;
    page.write(path)
}

/// The held-out figures of a calibration (rotation and translation gap per pose) and the poses
/// the others predict worst, by name.
fn held_out(
    page: &mut Page,
    run: &RunPage<'_>,
    poses: &[PosePair],
    outliers: &[usize],
) -> Result<()> {
    let Some(check) = leave_one_out(poses, run.setup) else {
        page.note("Fewer than four poses: no pose can be predicted from the others.");
        return Ok(());
    };
    let gaps: Vec<(usize, f64, f64)> = check
        .poses
        .iter()
        .map(|g| (g.pose, g.rotation_deg, g.translation))
        .collect();
    per_pose_pages(
        page,
        run,
        &gaps,
        outliers,
        "held-out gap per pose",
        "Each pose's camera observation predicted from all the other poses (leave-one-out): the gap. Poses far above the rest (red: outliers by the rigid-motion test) were paired with the wrong robot pose or badly detected.",
    )
}

/// Two per-pose figures (degrees, then the length unit) of `(pose, degrees, length)` values and
/// the table of the [`WORST`] poses, labelled as the input names them.
fn per_pose_pages(
    page: &mut Page,
    run: &RunPage<'_>,
    values: &[(usize, f64, f64)],
    outliers: &[usize],
    title: &str,
    caption: &str,
) -> Result<()> {
    let u = unit_name(run.unit);
    let n = run.poses.len();
    for (part, unit, pick) in [("rotation", "degrees", 1usize), ("translation", u, 2usize)] {
        let points = values
            .iter()
            .map(|v| (v.0, if pick == 1 { v.1 } else { v.2 }))
            .collect();
        let series = [Series {
            label: part,
            color: OWN,
            points,
            ring: false,
        }];
        page.figure(
            per_pose_figure(
                &format!("{title}: {part} ({unit})"),
                unit,
                n,
                &series,
                outliers,
            )?,
            caption,
        );
    }
    // Worst first, by the larger of the two gaps measured in their medians.
    let median = |pick: fn(&(usize, f64, f64)) -> f64| {
        let mut v: Vec<f64> = values.iter().map(pick).collect();
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(1.0).max(1e-12)
    };
    let (mr, mt) = (median(|v| v.1), median(|v| v.2));
    let mut worst: Vec<&(usize, f64, f64)> = values.iter().collect();
    worst.sort_by(|a, b| {
        (b.1 / mr)
            .max(b.2 / mt)
            .total_cmp(&(a.1 / mr).max(a.2 / mt))
    });
    let rows = worst
        .iter()
        .take(WORST)
        .map(|&&(i, r, t)| {
            vec![
                run.label(i),
                format!("{r:.4}"),
                crate::faces::short(t),
                if outliers.contains(&i) { "outlier" } else { "" }.to_string(),
            ]
        })
        .collect();
    page.table(
        &format!(
            "The {} poses worst fitted ({title})",
            worst.len().min(WORST)
        ),
        &["pose", "rotation (°)", &format!("translation ({u})"), ""],
        rows,
    );
    Ok(())
}

/// The axis and angle figures of the motions used.
fn motions(
    page: &mut Page,
    poses: &[PosePair],
    pairing: Pairing,
    setup: Setup,
    spread_deg: f64,
) -> Result<()> {
    let (motions, which) = motions_used(poses, pairing, setup);
    let spread = if spread_deg.is_finite() {
        format!(" Spread: {spread_deg:.1}°.")
    } else {
        String::new()
    };
    page.figure(
        axes_figure(&motions)?,
        &format!(
            "Rotation axes of the gripper's motions ({which}), gripper frame, seen from +z (equal-area; an axis and its opposite are one point; dot size grows with the angle).{spread} Axes crowded in one place leave X's rotation about them weakly determined."
        ),
    );
    page.figure(
        angles_figure(&motions)?,
        "Rotation angles of the same motions. Angles below a few degrees carry little information.",
    );
    Ok(())
}

/// The poses but those at `indices`.
fn without(poses: &[PosePair], indices: &[usize]) -> Vec<PosePair> {
    poses
        .iter()
        .enumerate()
        .filter(|(i, _)| !indices.contains(i))
        .map(|(_, p)| *p)
        .collect()
}

/// Where each pose places the target through `x` (Y_i = hand_i · X · camera_from_target_i), as its
/// distance from the common place ([`PoseResiduals`]: a robust mean of the Y_i).
fn target_scatter(poses: &[PosePair], setup: Setup, x: &Transform) -> Vec<(usize, f64)> {
    PoseResiduals::at(poses, setup, x)
        .residuals
        .iter()
        .map(|r| r.distance())
        .enumerate()
        .collect()
}

/// A transform as the page gives it to copy: frame, unit, translation, quaternion (x, y, z, w),
/// roll/pitch/yaw in degrees (fixed axes x, y, z, as URDF) and the 4×4 matrix.
fn transform_json(frame: &str, x: &Transform, unit: Option<Unit>) -> Value {
    let j = handeye::TransformJson::from(x);
    json!({
        "frame": frame,
        "unit": unit_name(unit),
        "translation": j.translation,
        "quaternion_xyzw": j.quaternion_xyzw,
        "rpy_deg": rpy(x).map(f64::to_degrees),
        "matrix": j.matrix,
    })
}

/// An HTML page: a title, the verdict, then blocks in order.
struct Page {
    title: &'static str,
    body: String,
}

impl Page {
    /// A page with its verdict at the top (none for an online run, whose estimates each carry
    /// one).
    fn new(title: &'static str, verdict: Option<&str>) -> Self {
        let mut body = String::new();
        if let Some(v) = verdict {
            let class = match v {
                "good" | "consistent" => "good",
                "questionable" | "undetermined" => "doubt",
                _ => "bad",
            };
            let _ = writeln!(
                body,
                "<p class=\"verdict {class}\">Verdict: {}</p>",
                escape(v)
            );
        }
        Self { title, body }
    }

    /// A block of preformatted text under a heading (the text face's words).
    fn text(&mut self, heading: &str, text: &str) {
        let _ = writeln!(
            self.body,
            "<h2>{}</h2>\n<pre class=\"summary\">{}</pre>",
            escape(heading),
            escape(text)
        );
    }

    /// A value as JSON to copy: an object's fields (or a list's objects' fields) one per line.
    fn copyable(&mut self, heading: &str, value: &Value) {
        let text = lines_json(value);
        let _ = writeln!(
            self.body,
            "<h2>{}</h2>\n<pre class=\"copy\">{}</pre>",
            escape(heading),
            escape(&text)
        );
    }

    /// A short paragraph.
    fn note(&mut self, text: &str) {
        let _ = writeln!(self.body, "<p>{}</p>", escape(text));
    }

    /// A table under a heading.
    fn table(&mut self, heading: &str, header: &[&str], rows: Vec<Vec<String>>) {
        let cells = |tag: &str, row: &[String]| -> String {
            row.iter()
                .map(|c| format!("<{tag}>{}</{tag}>", escape(c)))
                .collect()
        };
        let header: Vec<String> = header.iter().map(|h| h.to_string()).collect();
        let _ = writeln!(
            self.body,
            "<h3>{}</h3>\n<table><tr>{}</tr>",
            escape(heading),
            cells("th", &header)
        );
        for row in rows {
            let _ = writeln!(self.body, "<tr>{}</tr>", cells("td", &row));
        }
        self.body.push_str("</table>\n");
    }

    /// A figure (inline SVG) and its caption.
    fn figure(&mut self, svg: String, caption: &str) {
        let _ = writeln!(
            self.body,
            "<figure>{svg}<figcaption>{}</figcaption></figure>",
            escape(caption)
        );
    }

    /// Writes the page.
    fn write(self, path: &Path) -> Result<()> {
        let title = self.title;
        let html = format!(
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{title}</title>\n<style>body{{font-family:sans-serif;max-width:960px;margin:2em auto;color:#222}}pre{{background:#f6f6f6;padding:0.6em;overflow-x:auto;font-size:0.85em}}pre.summary{{white-space:pre-wrap}}pre.copy{{user-select:all}}figure{{margin:1.5em 0}}figcaption{{font-size:0.9em;color:#444}}table{{border-collapse:collapse;font-size:0.9em}}td,th{{border:1px solid #ccc;padding:0.2em 0.6em;text-align:left}}.verdict{{font-size:1.3em;font-weight:bold;padding:0.3em 0.6em;display:inline-block}}.good{{background:#dfd}}.doubt{{background:#ffd9a0}}.bad{{background:#fcc}}</style></head>\n<body><h1>{title}</h1>\n{}</body></html>\n",
            self.body
        );
        std::fs::write(path, html).map_err(|e| anyhow!("cannot write {}: {e}", path.display()))
    }
}

/// JSON with one line per field of an object (and per object of a list): short enough to read,
/// exact to copy.
fn lines_json(value: &Value) -> String {
    let object = |o: &serde_json::Map<String, Value>, indent: &str| -> String {
        let fields: Vec<String> = o
            .iter()
            .map(|(k, v)| format!("{indent}  {}: {v}", Value::from(k.as_str())))
            .collect();
        format!("{indent}{{\n{}\n{indent}}}", fields.join(",\n"))
    };
    match value {
        Value::Object(o) => object(o, ""),
        Value::Array(items) => {
            let inner: Vec<String> = items
                .iter()
                .map(|v| match v {
                    Value::Object(o) => object(o, "  "),
                    other => format!("  {other}"),
                })
                .collect();
            format!("[\n{}\n]", inner.join(",\n"))
        }
        other => other.to_string(),
    }
}

/// Escapes text for HTML.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}
