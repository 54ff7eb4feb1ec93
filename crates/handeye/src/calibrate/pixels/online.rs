//! The online calibrator on the pixels (`handeye online --intrinsics`): the records of a stream
//! calibrated by the batch pixel calibration of the parent module, on a doubling schedule.

use super::{not_on_pixels, pose_pairs, report, solved};
use crate::calibrate::batch::Options;
use crate::calibrate::robot_world::PoseResidualSummary;
use crate::model::camera::{Frame, Intrinsics};
use crate::model::error::{Error, Result};
use crate::model::motion::Setup;
use crate::solve::pose_residuals;
use crate::track::{PixelFit, Reason, Report as TrackReport, TrackEstimate};

#[cfg(doc)]
use super::calibrate_on_pixels;

/// Frames at which [`OnlinePixels`] first solves on the pixels (then at each doubling).
const FIRST_ONLINE_SOLVE: usize = 16;

/// The online calibrator on the pixels (`handeye online --intrinsics`): records with detections
/// pushed one at a time, calibrated by [`calibrate_on_pixels`] itself, with its checks (the
/// reading of the robot poses on the pixels, a fit far above noise refused), never from PnP
/// poses alone (a planar target's flipped PnP pose would give a wrong X). An estimate is reported
/// at 16, 32, 64, … frames (each solve over every frame so far: the solves cost at most twice the
/// last one) and at the end, in the accumulating estimator's report ([`crate::TrackReport`]) with
/// the fit on the pixels in `estimate.reprojection`. The end's X is the batch's on the same
/// records.
#[derive(Debug, Clone)]
pub struct OnlinePixels {
    camera: Intrinsics,
    setup: Setup,
    options: Options,
    frames: Vec<Frame>,
    /// Frames at which the next estimate is solved.
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
    /// A calibrator on the pixels of `camera`: `options` as [`calibrate_on_pixels`] takes them
    /// (`point`, `fix`; `pose_names` is filled by [`OnlinePixels::push`]).
    ///
    /// Errors: [`Error::InvalidParameter`] for unusable intrinsics, a prior or
    /// `reject_outliers`.
    pub fn new(camera: Intrinsics, setup: Setup, options: Options) -> Result<Self> {
        not_on_pixels(options.reject_outliers, &options.priors)?;
        camera.check().map_err(|(field, message)| Error::InvalidParameter {
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
        if self.frames.len() < self.next_solve {
            return None;
        }
        self.next_solve = self.next_solve.saturating_mul(2);
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
    /// and X, as [`calibrate_on_pixels`] on them), reported with `reason` `end`.
    ///
    /// Errors: those of [`calibrate_on_pixels`] (too few frames, degenerate motions, robot poses
    /// that fit the pixels far better inverted, a fit far above detection noise).
    pub fn finish(&mut self) -> Result<TrackReport> {
        if let Some((n, last)) = &self.last
            && *n == self.frames.len()
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
        let (used, solution, applied, reading_check, choice) =
            solved(
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
        let residual = PoseResidualSummary::of(pose_residuals(
            &poses,
            setup,
            &batch.transform,
            &target,
        ));
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
            pose: self.frames.len(),
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
        self.last = Some((self.frames.len(), report.clone()));
        Ok(report)
    }
}
