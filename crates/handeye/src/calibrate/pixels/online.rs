//! The online calibrator on the pixels (`handeye online --intrinsics`): the records of a stream
//! calibrated by the batch pixel calibration of the parent module, on a doubling schedule.

use crate::calibrate::options::Options;
use crate::calibrate::pipeline::hand_eye_on_pixels as report;
use crate::calibrate::problem::pixels::{not_on_pixels, pose_pairs, solved};
use crate::calibrate::report::robot_world::PoseResidualSummary;
use crate::model::camera::{Frame, Intrinsics};
use crate::model::error::{Error, Result};
use crate::model::motion::Setup;
use crate::model::pose::rotation_angle_between;
use crate::solve::pose_residuals;
use crate::track::{PixelFit, Reason, Report as TrackReport, TrackEstimate};

/// Frames at which [`OnlinePixels`] first solves on the pixels (then at each doubling).
const FIRST_ONLINE_SOLVE: usize = 16;

/// The most frames [`OnlinePixels`] keeps: beyond, one is thinned out per record
/// ([`Thinning`]). A solve over 256 frames of a 54-corner board takes tens of milliseconds.
pub(crate) const MAX_ONLINE_FRAMES: usize = 256;

/// Which frame to drop when the calibrator holds more than it keeps: one of the two whose robot
/// poses are nearest each other (the older), so that the views kept stay spread. The distance of
/// two robot poses is the angle of their relative rotation (radians) plus the distance of their
/// translations over `scale` (the RMS spread of the translations of the frames held when the
/// buffer first filled): unit-free, deterministic. Each frame's nearest neighbour is kept up to
/// date, so a record costs O(n) distances, not O(n²).
#[derive(Debug, Clone, PartialEq)]
struct Thinning {
    scale: f64,
    /// For each frame held: the distance to its nearest other frame, and that frame's index.
    nearest: Vec<(f64, usize)>,
}

impl Thinning {
    fn distance(&self, a: &Frame, b: &Frame) -> f64 {
        let (p, q) = (&a.base_from_gripper, &b.base_from_gripper);
        // Not nalgebra's `angle()`: its acos is NaN for two equal rotations, and a NaN distance
        // is never the nearest, so repeated poses were kept and distinct views thinned out.
        rotation_angle_between(&p.rotation, &q.rotation)
            + (p.translation.vector - q.translation.vector).norm() / self.scale
    }

    /// The nearest other frame of frame `i`.
    fn nearest_of(&self, frames: &[Frame], i: usize) -> (f64, usize) {
        frames
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != i)
            .map(|(j, f)| (self.distance(&frames[i], f), j))
            .fold(
                (f64::INFINITY, i),
                |best, c| if c.0 < best.0 { c } else { best },
            )
    }

    /// Starts on the frames held.
    fn new(frames: &[Frame]) -> Self {
        let n = frames.len().max(1) as f64;
        let mean = frames
            .iter()
            .map(|f| f.base_from_gripper.translation.vector)
            .sum::<nalgebra::Vector3<f64>>()
            / n;
        let spread = (frames
            .iter()
            .map(|f| (f.base_from_gripper.translation.vector - mean).norm_squared())
            .sum::<f64>()
            / n)
            .sqrt();
        let mut t = Self {
            scale: if spread > 0.0 && spread.is_finite() {
                spread
            } else {
                1.0
            },
            nearest: Vec::new(),
        };
        t.nearest = (0..frames.len()).map(|i| t.nearest_of(frames, i)).collect();
        t
    }

    /// Takes in the last frame of `frames`.
    fn add(&mut self, frames: &[Frame]) {
        let new = frames.len() - 1;
        let mut best = (f64::INFINITY, new);
        for (j, f) in frames[..new].iter().enumerate() {
            let d = self.distance(&frames[new], f);
            if d < self.nearest[j].0 {
                self.nearest[j] = (d, new);
            }
            if d < best.0 {
                best = (d, j);
            }
        }
        self.nearest.push(best);
    }

    /// The frame to drop: the older of the two nearest each other.
    fn victim(&self) -> usize {
        self.nearest
            .iter()
            .enumerate()
            .fold(
                (f64::INFINITY, 0),
                |best, (i, (d, _))| {
                    if *d < best.0 { (*d, i) } else { best }
                },
            )
            .1
    }

    /// Forgets frame `r`, already removed from `frames`.
    fn remove(&mut self, frames: &[Frame], r: usize) {
        self.nearest.remove(r);
        // One pass, no allocation per record: a frame whose nearest was `r` finds its nearest
        // again among the frames left; the others' indices past `r` move down by one.
        for i in 0..self.nearest.len() {
            match self.nearest[i].1 {
                n if n == r => self.nearest[i] = self.nearest_of(frames, i),
                n if n > r => self.nearest[i].1 -= 1,
                _ => {}
            }
        }
    }
}

/// The online calibrator on the pixels (`handeye online --intrinsics`): records with detections
/// pushed one at a time, calibrated by [`calibrate`](crate::calibrate()) on the pixels itself
/// ([`Input::Pixels`](crate::Input::Pixels)), with its checks (the
/// reading of the robot poses on the pixels, a fit far above noise refused), never from PnP
/// poses alone (a planar target's flipped PnP pose would give a wrong X). An estimate is reported
/// at 16, 32, 64, 128, 256 records and then every 256 records (each solve over the frames kept) and
/// at the end, in the accumulating estimator's report ([`crate::TrackReport`]) with the fit on the
/// pixels in `estimate.reprojection`. At most 256 frames are kept: beyond, one of the two frames
/// whose robot poses are nearest each other is dropped per record (the older), so that memory and
/// each solve's cost stay bounded on an endless stream and the views kept stay spread. On up to 256
/// records the end's X is the batch's on the same records; beyond, the batch's on the frames kept.
#[derive(Debug, Clone, PartialEq)]
pub struct OnlinePixels {
    camera: Intrinsics,
    setup: Setup,
    options: Options,
    /// The frames kept, at most `max_frames`.
    frames: Vec<Frame>,
    /// Records pushed.
    pushed: usize,
    /// The most frames kept.
    max_frames: usize,
    /// Which frame to drop, once more than `max_frames` were pushed.
    thinning: Option<Thinning>,
    /// Records pushed at which the next estimate is solved.
    next_solve: usize,
    /// Reports made so far.
    reports: usize,
    /// The last estimate and the number of frames it was solved on.
    last: Option<(usize, TrackReport)>,
    /// The cautions of the last solve, in words.
    warnings: Vec<crate::model::warning::Warning>,
    /// Why the last solve made no estimate.
    refused: Option<String>,
}

impl OnlinePixels {
    /// A calibrator on the pixels of `camera`: `options` as [`calibrate`](crate::calibrate())
    /// takes them on the pixels
    /// (`point`, `fix`; `pose_names` is filled by [`OnlinePixels::push`]).
    ///
    /// Errors: [`Error::InvalidParameter`] for unusable intrinsics, a prior or
    /// `reject_outliers`.
    pub fn new(camera: Intrinsics, setup: Setup, options: Options) -> Result<Self> {
        not_on_pixels(
            options.reject_outliers,
            &options.priors,
            options.robot_model.as_ref(),
        )?;
        camera
            .check()
            .map_err(|(field, message)| Error::InvalidParameter {
                name: "intrinsics",
                message: format!("{field}: {message}"),
            })?;
        Ok(Self {
            camera,
            setup,
            options: Options {
                pose_names: Vec::new(),
                ..options
            },
            frames: Vec::new(),
            pushed: 0,
            max_frames: MAX_ONLINE_FRAMES,
            thinning: None,
            next_solve: FIRST_ONLINE_SOLVE,
            reports: 0,
            last: None,
            warnings: Vec::new(),
            refused: None,
        })
    }

    /// Pushes one record, named `name` (`file:line`); returns the estimate when one is solved at
    /// this frame (16, 32, 64, … frames) and the calibration on the pixels makes one.
    pub fn push(&mut self, frame: Frame, name: String) -> Option<TrackReport> {
        self.frames.push(frame);
        self.options.pose_names.push(name);
        self.pushed += 1;
        if self.frames.len() > self.max_frames {
            let thinning = match &mut self.thinning {
                Some(t) => {
                    t.add(&self.frames);
                    t
                }
                None => self.thinning.insert(Thinning::new(&self.frames)),
            };
            let r = thinning.victim();
            self.frames.remove(r);
            self.options.pose_names.remove(r);
            thinning.remove(&self.frames, r);
        }
        if self.pushed < self.next_solve {
            return None;
        }
        // Doubling while the frames kept grow; then once every `max_frames` records, each solve
        // over the frames kept: a bounded cost per record.
        self.next_solve = self
            .pushed
            .saturating_mul(2)
            .min(self.pushed.saturating_add(self.max_frames));
        let reason = if self.last.is_some() {
            Reason::Every
        } else {
            Reason::Determined
        };
        match self.estimate(reason) {
            Ok(report) => Some(report),
            Err(e) => {
                self.refused = Some(e.to_string());
                None
            }
        }
    }

    /// The final estimate: the calibration on the pixels of every record pushed (the same solve,
    /// and X, as [`calibrate`](crate::calibrate()) on them), reported with `reason` `end`.
    ///
    /// Errors: those of [`calibrate`](crate::calibrate()) on the pixels (too few frames,
    /// degenerate motions, robot poses
    /// that fit the pixels far better inverted, a fit far above detection noise).
    pub fn finish(&mut self) -> Result<TrackReport> {
        if let Some((n, last)) = &self.last
            && *n == self.pushed
        {
            let n = *n;
            let mut report = last.clone();
            self.reports += 1;
            report.number = self.reports;
            report.reason = Reason::End;
            self.last = Some((n, report.clone()));
            return Ok(report);
        }
        self.estimate(Reason::End)
    }

    /// Records pushed so far.
    pub fn frames(&self) -> usize {
        self.pushed
    }

    /// Keeps at most `max_frames` frames (default 256; at least 16): beyond, one of the two frames
    /// whose robot poses are nearest each other is dropped per record, so that memory and the
    /// cost of a solve stay bounded on an endless stream and the views kept stay spread.
    ///
    /// Errors: [`Error::InvalidParameter`] below 16.
    pub fn with_max_frames(mut self, max_frames: usize) -> Result<Self> {
        // More than the 12 parameters of the pixel solve, and the first solve's frames.
        if max_frames < FIRST_ONLINE_SOLVE {
            return Err(Error::InvalidParameter {
                name: "max_frames",
                message: format!("{max_frames}: at least {FIRST_ONLINE_SOLVE} frames are kept"),
            });
        }
        self.max_frames = max_frames;
        Ok(self)
    }

    /// Frames kept (at most `max_frames`).
    pub fn kept_frames(&self) -> usize {
        self.frames.len()
    }

    /// The cautions of the last estimate (its verdict `questionable` when any).
    pub fn warnings(&self) -> &[crate::model::warning::Warning] {
        &self.warnings
    }

    /// Why the last solve made no estimate, or `None`.
    pub fn refused(&self) -> Option<&str> {
        self.refused.as_deref()
    }

    /// The last estimate reported, or `None`.
    pub fn last_report(&self) -> Option<TrackReport> {
        self.last.as_ref().map(|(_, r)| r.clone())
    }

    /// Solves on every frame so far and reports it.
    fn estimate(&mut self, reason: Reason) -> Result<TrackReport> {
        let setup = self.setup;
        let (used, solution, applied, reading_check, choice) = solved(
            &self.frames,
            &self.camera,
            setup,
            self.options.fix,
            self.options.refine_intrinsics,
        )?;
        let poses = pose_pairs(&used, &solution.start_poses);
        let target = solution.target;
        let batch = report(
            &used,
            setup,
            &self.options,
            solution,
            (applied, reading_check),
            &choice,
        )?;
        let residual =
            PoseResidualSummary::of(pose_residuals(&poses, setup, &batch.transform, &target));
        let u = &batch.uncertainty;
        let reprojection = batch.reprojection.as_ref().map(|r| PixelFit {
            rms_px: r.rms_px,
            sigma_px: r.sigma_px,
            detections: r.detections,
            outlier_detections: r.outlier_detections.len(),
            flips_resolved: r.flips_resolved,
            verdict: batch.verdict,
        });
        self.reports += 1;
        let report = TrackReport {
            number: self.reports,
            pose: self.pushed,
            reason,
            estimate: TrackEstimate {
                x: batch.transform,
                target,
                poses: batch.poses,
                since: 1,
                conditioning: batch.conditioning,
                noise_rotation_deg: residual.rotation_deg_rms,
                noise_translation: residual.translation_rms,
                uncertainty_rotation_deg: Some(u.rotation_deg),
                uncertainty_translation: Some(u.translation),
                covariance: Some(u.covariance),
                at_point: u.at_point.as_ref().map(|a| (a.point, a.sigma)),
                robot_world: None,
                prior: None,
                reprojection,
            },
            weak: None,
            implausible: false,
            // The pixel solve's cautions are the calibrator's (`warnings()`), its verdict the
            // estimate's `reprojection.verdict`.
            systematic: None,
            warnings: Vec::new(),
        };
        self.warnings = batch.warnings;
        self.refused = None;
        self.last = Some((self.pushed, report.clone()));
        Ok(report)
    }
}
