//! Error metrics: against a known X (simulation) and the A X − X B residuals (real data).
//!
//! SPEC sec. 2. Rotation error `‖R̂ − R‖_F` (the paper's), also as the angle of R̂ᵀR in degrees;
//! relative translation error `‖t − t̂‖ / ‖t‖`; rmsR = `‖R̂ − R‖_F / 3` (RMS of the 9 entries).

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::motion::{AllPairs, MotionSource};
use crate::pose::{Transform, rotation_angle_between, rotation_matrix};
use crate::warning::Warning;

use crate::residual::{MIN_NORM, PoseUnderX, poses_under};

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

pub use crate::residual::{MotionResidual, ResidualRms, residual_rms};

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
    let (residual, per_motion, axis_spread, rotation_range_deg) = match motions.all_pairs() {
        Some(pairs) if !keep => {
            let (residual, spread, range) = pairs_quality(pairs, motions, x);
            (residual, Vec::new(), spread, range)
        }
        _ => {
            let (residual, per_motion, range) = motion_quality(motions, x, keep);
            let spread = crate::motion::axis_spread(motions);
            (residual, per_motion, spread, range)
        }
    };
    let axis_spread_deg = axis_spread.to_degrees();
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

/// The residual summary, the per-motion entries (when `keep`) and the range of rotation angles
/// (degrees), motion by motion.
fn motion_quality(
    motions: &(impl MotionSource + ?Sized),
    x: &Transform,
    keep: bool,
) -> (ResidualSummary, Vec<MotionQuality>, [f64; 2]) {
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
    (
        residual.finish(motions.count()),
        per_motion,
        [smallest, largest],
    )
}

/// The quality of X over every pair of poses, from per-pose quantities ([`crate::residual`]'s `PoseUnderX`).
///
/// The residual of the motion from pose j to pose i is the disagreement of the two poses' fixed
/// frames: `R_j ΔR S_i = W_i − W_j` and `R_j ΔT = g_i − e_j + D_j o_i` with D = W − W̄,
/// e = y − ȳ and g = e − D o. So:
/// - Σ‖ΔT‖² over the pairs comes from prefix sums over the poses in O(n), exactly (up to rounding,
///   and without the cancellation of large terms: every factor is a deviation from a mean);
/// - Σ‖ΔR‖²_F = n Σ‖D_k‖² in O(n). Each pair's chordal residual u = ‖ΔR‖²_F = 8 sin²(θ/2) gives
///   its angle, θ = 2 asin √(u/8); the reported RMS angle is that of the mean u. θ² is convex in
///   u, so it is the exact RMS when every pair has the same residual and below it otherwise, by
///   at most a factor √(θ²(u_max)/u_max / θ²(ū)/ū) (about 1 + u_max/48). When the warning's
///   threshold is below the top of that bracket (the warning may fire, and then quotes the RMS)
///   the RMS is computed motion by motion instead, so the verdict and its message are always the
///   exact ones; data whose residuals are well below the threshold stay O(n).
/// - The largest residuals, the range of rotation angles and the axis spread are maxima over the
///   pairs, with no O(n) form: two passes over the pairs of per-pose matrices (a 3×3 product per
///   pair and, in the first, an arc tangent for the angle of each motion), never composing the
///   motions, in parallel blocks combined in a fixed order (the result does not depend on the
///   number of threads).
fn pairs_quality(
    pairs: &AllPairs,
    motions: &(impl MotionSource + ?Sized),
    x: &Transform,
) -> (ResidualSummary, f64, [f64; 2]) {
    let poses = poses_under(pairs, &rotation_matrix(x), &x.translation.vector);
    let n = poses.len();
    let count = motions.count().max(1) as f64;
    let g: Vec<Vector3<f64>> = poses.iter().map(|p| p.e - p.d * p.o).collect();
    // Σ_{i<j} ‖g_i − e_j + D_j o_i‖², pose j against the prefix sums over i < j.
    let mut translation_sum = 0.0;
    let (mut g2, mut sum_g, mut sum_o) = (0.0, Vector3::zeros(), Vector3::zeros());
    let (mut oo, mut og) = (Matrix3::zeros(), Matrix3::zeros());
    for (j, (p, g_j)) in poses.iter().zip(&g).enumerate() {
        translation_sum +=
            g2 + j as f64 * p.e.norm_squared() + (p.d.transpose() * p.d * oo).trace()
                - 2.0 * p.e.dot(&sum_g)
                + 2.0 * (p.d * og).trace()
                - 2.0 * p.e.dot(&(p.d * sum_o));
        g2 += g_j.norm_squared();
        sum_g += g_j;
        sum_o += p.o;
        oo += p.o * p.o.transpose();
        og += p.o * g_j.transpose();
    }
    let chordal_mean = n as f64 * poses.iter().map(|p| p.d.norm_squared()).sum::<f64>() / count;
    // The pass over the pairs: the widest residual rotation (smallest ⟨W_i, W_j⟩), the largest
    // ‖ΔT‖, the rotation angles of A and the scatter of their axes.
    // ‖ΔR‖²_F = ‖W_i − W_j‖²_F = ‖D_i − D_j‖²_F.
    // Rows i of the pairs in fixed blocks, in parallel; the blocks' results are combined in
    // block order, so that the sums do not depend on the number of threads.
    let blocks: Vec<usize> = (0..n).step_by(PAIR_ROWS).collect();
    let rows = |start: usize| start..(start + PAIR_ROWS).min(n);
    let passes: Vec<PairPass> = blocks
        .par_iter()
        .map(|&start| {
            let mut pass = PairPass::default();
            for i in rows(start) {
                pass.add_row(&poses[i], &g[i], &poses[i + 1..]);
            }
            pass
        })
        .collect();
    let pass = passes
        .into_iter()
        .fold(PairPass::default(), PairPass::merge);
    let (widest_u, translation_max) = (pass.widest_u, pass.translation_max);
    let (smallest, largest) = (pass.smallest, pass.largest);
    let eigen = pass.scatter.symmetric_eigen();
    let dominant: Vector3<f64> = eigen
        .eigenvectors
        .column(eigen.eigenvalues.imax())
        .into_owned();
    let closest = blocks
        .par_iter()
        .map(|&start| {
            rows(start)
                .map(|i| closest_axis(&poses[i], &poses[i + 1..], &dominant))
                .fold(1.0_f64, f64::min)
        })
        .reduce(|| 1.0, f64::min);
    let spread = closest.min(1.0).acos();
    let angle_of = |u: f64| 2.0 * (u / 8.0).clamp(0.0, 1.0).sqrt().asin();
    let mut rotation_rms = angle_of(chordal_mean).to_degrees();
    // θ²/u grows with u: at most θ²(u_max)/u_max for every pair.
    let ratio = if widest_u > 0.0 {
        angle_of(widest_u).powi(2) / widest_u
    } else {
        0.5
    };
    let upper = (ratio * chordal_mean).sqrt().to_degrees();
    if WARN_RESIDUAL_DEG < upper {
        rotation_rms = motion_quality(motions, x, false).0.rotation_deg_rms;
    }
    let residual = ResidualSummary {
        rotation_deg_rms: rotation_rms,
        translation_rms: (translation_sum.max(0.0) / count).sqrt(),
        rotation_deg_max: angle_of(widest_u).to_degrees(),
        translation_max: translation_max.sqrt(),
    };
    (
        residual,
        spread,
        [smallest.to_degrees(), largest.to_degrees()],
    )
}

/// Rows of pairs per parallel block in [`pairs_quality`].
const PAIR_ROWS: usize = 16;

/// The maxima and sums of one block of pairs in [`pairs_quality`].
#[derive(Clone, Copy)]
struct PairPass {
    /// Largest ‖ΔR‖²_F.
    widest_u: f64,
    /// Largest ‖ΔT‖².
    translation_max: f64,
    /// Smallest and largest rotation angle of A, radians.
    smallest: f64,
    largest: f64,
    /// Σ θ² k kᵀ of the rotations of A.
    scatter: Matrix3<f64>,
}

impl Default for PairPass {
    fn default() -> Self {
        Self {
            widest_u: 0.0,
            translation_max: 0.0,
            smallest: f64::INFINITY,
            largest: 0.0,
            scatter: Matrix3::zeros(),
        }
    }
}

impl PairPass {
    /// The pairs of pose i (with g_i) and every later pose.
    fn add_row(&mut self, p_i: &PoseUnderX, g_i: &Vector3<f64>, later: &[PoseUnderX]) {
        for p_j in later {
            self.widest_u = self.widest_u.max((p_i.d - p_j.d).norm_squared());
            let dt = g_i - p_j.e + p_j.d * p_i.o;
            self.translation_max = self.translation_max.max(dt.norm_squared());
            let (angle, axis) = crate::pose::axis_angle(&(p_j.r.transpose() * p_i.r));
            self.smallest = self.smallest.min(angle);
            self.largest = self.largest.max(angle);
            if let Some(k) = axis {
                self.scatter += k * k.transpose() * (angle * angle);
            }
        }
    }

    /// Two blocks' results together.
    fn merge(self, other: Self) -> Self {
        Self {
            widest_u: self.widest_u.max(other.widest_u),
            translation_max: self.translation_max.max(other.translation_max),
            smallest: self.smallest.min(other.smallest),
            largest: self.largest.max(other.largest),
            scatter: self.scatter + other.scatter,
        }
    }
}

/// The smallest |k · dominant| over the motions from the later poses to pose i (1 when none has
/// an axis). The axis comes from the skew part sin θ · k of R_a without an angle, away from
/// θ = π where [`crate::pose::axis_angle`] takes it from R_a + R_aᵀ instead.
fn closest_axis(p_i: &PoseUnderX, later: &[PoseUnderX], dominant: &Vector3<f64>) -> f64 {
    let mut closest = 1.0_f64;
    for p_j in later {
        let r_a = p_j.r.transpose() * p_i.r;
        let cos = ((r_a.trace() - 1.0) * 0.5).clamp(-1.0, 1.0);
        let sin_k = Vector3::new(
            r_a[(2, 1)] - r_a[(1, 2)],
            r_a[(0, 2)] - r_a[(2, 0)],
            r_a[(1, 0)] - r_a[(0, 1)],
        ) * 0.5;
        let sin = sin_k.norm();
        let k = if cos > -0.5 {
            // θ = atan2(sin, cos) < NO_AXIS_ANGLE, with tan θ = θ to rounding there.
            (sin >= crate::pose::NO_AXIS_ANGLE * cos).then(|| sin_k / sin)
        } else {
            crate::pose::axis_angle(&r_a).1
        };
        if let Some(k) = k {
            closest = closest.min(k.dot(dominant).abs());
        }
    }
    closest
}
