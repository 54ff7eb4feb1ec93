//! Error metrics: against a known X (simulation) and the A X − X B residuals (real data).
//!
//! SPEC sec. 2. Rotation error `‖R̂ − R‖_F` (the paper's), also as the angle of R̂ᵀR in degrees;
//! relative translation error `‖t − t̂‖ / ‖t‖`; rmsR = `‖R̂ − R‖_F / 3` (RMS of the 9 entries).

use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

use crate::motion::{MotionPair, MotionSource};
use crate::pose::{Transform, rotation_angle_between, rotation_matrix};
use crate::warning::Warning;

/// Smallest ‖t‖ used as a divisor in relative translation errors (an X with zero translation
/// would otherwise divide by zero).
const MIN_NORM: f64 = 1e-300;

/// Errors of an estimate X̂ against the true X.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TruthErrors {
    /// `‖R̂ − R‖_F` (the paper's rotation error).
    pub rot_fro: f64,
    /// Angle of R̂ᵀR, degrees.
    pub rot_deg: f64,
    /// `‖t − t̂‖ / ‖t‖` (the paper's relative translation error).
    pub trans_rel: f64,
}

impl TruthErrors {
    /// rmsR of the paper: the RMS of the 9 entries of R̂ − R, `‖R̂ − R‖_F / 3`.
    pub fn rms_r(&self) -> f64 {
        self.rot_fro / 3.0
    }

    /// rmsT of the paper: the relative translation error.
    pub fn rms_t(&self) -> f64 {
        self.trans_rel
    }
}

/// Errors of `estimate` against `truth` (both X, in the same frame).
///
/// # Example
/// ```
/// use handeye::{Transform, metrics::errors_against_truth};
/// use nalgebra::Vector3;
/// let x = Transform::new(Vector3::new(0.0, 0.0, 1.0), Vector3::zeros());
/// let e = errors_against_truth(&x, &x);
/// assert_eq!(e.rot_fro, 0.0);
/// assert_eq!(e.trans_rel, 0.0);
/// ```
pub fn errors_against_truth(estimate: &Transform, truth: &Transform) -> TruthErrors {
    let r_hat = rotation_matrix(estimate);
    let r = rotation_matrix(truth);
    let t_hat = estimate.translation.vector;
    let t = truth.translation.vector;
    TruthErrors {
        rot_fro: (r_hat - r).norm(),
        rot_deg: rotation_angle_between(&estimate.rotation, &truth.rotation).to_degrees(),
        trans_rel: (t - t_hat).norm() / t.norm().max(MIN_NORM),
    }
}

/// The residual of one motion pair under X: ΔR = R_a R_x − R_x R_b and
/// ΔT = R_a t_x + t_a − R_x t_b − t_x (the paper's sec. 4.2, `A X − X B`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionResidual {
    /// ΔR, the rotation block of A X − X B.
    pub delta_r: Matrix3<f64>,
    /// ΔT, the translation column of A X − X B (input length units).
    pub delta_t: Vector3<f64>,
    /// Angle between R_a R_x and R_x R_b, degrees.
    pub rotation_deg: f64,
}

impl MotionResidual {
    /// The residual of motion pair `m` under `x`.
    pub fn of(m: &MotionPair, x: &Transform) -> Self {
        let r_x = rotation_matrix(x);
        let r_a = rotation_matrix(&m.a);
        let r_b = rotation_matrix(&m.b);
        let t_x = x.translation.vector;
        let ax = r_a * r_x;
        let xb = r_x * r_b;
        Self {
            delta_r: ax - xb,
            delta_t: r_a * t_x + m.a.translation.vector - r_x * m.b.translation.vector - t_x,
            rotation_deg: rotation_angle_between(
                &(m.a.rotation * x.rotation),
                &(x.rotation * m.b.rotation),
            )
            .to_degrees(),
        }
    }
}

/// The paper's residual form of rmsR and rmsT (SPEC sec. 2), used when no ground truth exists.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ResidualRms {
    /// RMS of all ΔR entries.
    pub rms_r: f64,
    /// RMS of all ΔT entries divided by ‖t̂_x‖ (unit-free like the relative translation error).
    pub rms_t: f64,
}

/// rmsR and rmsT of the residuals of `motions` under `x` (SPEC sec. 2, residual form).
pub fn residual_rms(motions: &(impl MotionSource + ?Sized), x: &Transform) -> ResidualRms {
    let mut sum_r = 0.0;
    let mut sum_t = 0.0;
    motions.for_each_motion(|m| {
        let res = MotionResidual::of(m, x);
        sum_r += res.delta_r.norm_squared();
        sum_t += res.delta_t.norm_squared();
    });
    let n = motions.count().max(1) as f64;
    ResidualRms {
        rms_r: (sum_r / (9.0 * n)).sqrt(),
        rms_t: (sum_t / (3.0 * n)).sqrt() / x.translation.vector.norm().max(MIN_NORM),
    }
}

/// Residual summary with units, as `handeye calibrate` reports it.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ResidualSummary {
    /// RMS over the motions of the angle between R_a R_x and R_x R_b, degrees.
    pub rotation_deg_rms: f64,
    /// RMS over the motions of ‖ΔT_k‖, input length units.
    pub translation_rms: f64,
    /// The largest rotation residual, degrees.
    pub rotation_deg_max: f64,
    /// The largest ‖ΔT_k‖, input length units.
    pub translation_max: f64,
}

/// Summarises the A X − X B residuals of `motions` under `x`.
pub fn residual_summary(motions: &(impl MotionSource + ?Sized), x: &Transform) -> ResidualSummary {
    let mut s = ResidualSummary::default();
    motions.for_each_motion(|m| {
        let res = MotionResidual::of(m, x);
        s.add(res.rotation_deg, res.delta_t.norm());
    });
    s.finish(motions.count())
}

impl ResidualSummary {
    /// Adds one motion's residuals (sums of squares until [`Self::finish`]).
    fn add(&mut self, rotation_deg: f64, translation: f64) {
        self.rotation_deg_rms += rotation_deg * rotation_deg;
        self.translation_rms += translation * translation;
        self.rotation_deg_max = self.rotation_deg_max.max(rotation_deg);
        self.translation_max = self.translation_max.max(translation);
    }

    /// Turns the sums of squares over `n` motions into RMS values.
    fn finish(mut self, n: usize) -> Self {
        let n = n.max(1) as f64;
        self.rotation_deg_rms = (self.rotation_deg_rms / n).sqrt();
        self.translation_rms = (self.translation_rms / n).sqrt();
        self
    }
}

/// One motion pair in a [`QualityReport`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MotionQuality {
    /// Rotation residual: angle between R_a R_x and R_x R_b, degrees.
    pub rotation_deg: f64,
    /// Translation residual ‖ΔT‖, input units.
    pub translation: f64,
    /// Rotation angle of A, degrees.
    pub angle_deg: f64,
    /// |θ_A − θ_B|, degrees (0 for consistent data).
    pub angle_gap_deg: f64,
}

/// How good a calibration is, and why: residuals and the spread of the data (the uncertainty is
/// [`crate::uncertainty`]'s).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct QualityReport {
    /// RMS and worst of the residuals.
    pub residual: ResidualSummary,
    /// Per motion pair, in input order (empty above the limit given to [`quality_report`]).
    pub per_motion: Vec<MotionQuality>,
    /// Largest angle between a motion's rotation axis (as a line) and the dominant axis, degrees:
    /// small means nearly parallel axes, which leave X's rotation about that axis weak.
    pub axis_spread_deg: f64,
    /// Smallest and largest rotation angle of the motions, degrees.
    pub rotation_range_deg: [f64; 2],
    /// Cautions about the motions and the fit.
    #[serde(serialize_with = "crate::warning::described")]
    pub warnings: Vec<Warning>,
}

/// Axis spread below which the report warns, degrees.
pub const WARN_AXIS_SPREAD_DEG: f64 = 8.0;
/// Rotation residual RMS above which the report warns about frame directions, degrees.
pub const WARN_RESIDUAL_DEG: f64 = 5.0;
/// Default floor of the per-pose outlier test on the median |θ_A − θ_B| of a pose's motions, degrees.
pub const OUTLIER_DEG: f64 = 3.0;

/// The quality report of X over the motion pairs it was solved from. Per-motion entries are kept
/// for at most `max_per_motion` motions (the summary covers all of them). Outliers are judged per
/// pose ([`crate::consistency::pose_outliers`]).
pub fn quality_report(
    motions: &(impl MotionSource + ?Sized),
    x: &Transform,
    max_per_motion: usize,
) -> QualityReport {
    let keep = motions.count() <= max_per_motion;
    let mut per_motion = Vec::new();
    let (mut smallest, mut largest) = (f64::INFINITY, 0.0_f64);
    let mut residual = ResidualSummary::default();
    motions.for_each_motion(|m| {
        let r = MotionResidual::of(m, x);
        let angle_a = crate::motion::MotionFeatures::of(&m.a).angle;
        let angle_b = crate::motion::MotionFeatures::of(&m.b).angle;
        let q = MotionQuality {
            rotation_deg: r.rotation_deg,
            translation: r.delta_t.norm(),
            angle_deg: angle_a.to_degrees(),
            angle_gap_deg: (angle_a - angle_b).abs().to_degrees(),
        };
        residual.add(q.rotation_deg, q.translation);
        smallest = smallest.min(q.angle_deg);
        largest = largest.max(q.angle_deg);
        if keep {
            per_motion.push(q);
        }
    });
    let residual = residual.finish(motions.count());
    let axis_spread_deg = axis_spread(motions).to_degrees();
    let rotation_range_deg = [smallest, largest];
    let mut warnings = Vec::new();
    if axis_spread_deg < WARN_AXIS_SPREAD_DEG {
        warnings.push(Warning::OneAxis { axis_spread_deg });
    }
    if residual.rotation_deg_rms > WARN_RESIDUAL_DEG {
        warnings.push(Warning::RotationResiduals {
            rms_deg: residual.rotation_deg_rms,
        });
    }
    QualityReport {
        residual,
        per_motion,
        axis_spread_deg,
        rotation_range_deg,
        warnings,
    }
}

/// Largest angle between a motion axis (as a line) and the dominant axis of Σ θ² k kᵀ, radians.
pub(crate) fn axis_spread(motions: &(impl MotionSource + ?Sized)) -> f64 {
    let mut scatter = Matrix3::zeros();
    motions.for_each_motion(|m| {
        let f = crate::motion::MotionFeatures::of(&m.a);
        if let Some(k) = f.axis {
            scatter += k * k.transpose() * (f.angle * f.angle);
        }
    });
    let eigen = scatter.symmetric_eigen();
    let dominant: Vector3<f64> = eigen
        .eigenvectors
        .column(eigen.eigenvalues.imax())
        .into_owned();
    let mut spread = 0.0_f64;
    motions.for_each_motion(|m| {
        if let Some(k) = crate::motion::MotionFeatures::of(&m.a).axis {
            spread = spread.max(k.dot(&dominant).abs().min(1.0).acos());
        }
    });
    spread
}
