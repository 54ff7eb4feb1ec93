//! Error metrics: against a known X (simulation) and the A X − X B residuals (real data).
//!
//! SPEC sec. 2. Rotation error `‖R̂ − R‖_F` (the paper's), also as the angle of R̂ᵀR in degrees;
//! relative translation error `‖t − t̂‖ / ‖t‖`; rmsR = `‖R̂ − R‖_F / 3` (RMS of the 9 entries).

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::model::pose::{Transform, rotation_angle_between, rotation_matrix};
use crate::model::warning::Warning;
use crate::solve::motions::{AllPairs, MotionSource, count_pairs};

use crate::solve::residual::{MIN_NORM, PoseUnderX, poses_under};

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
/// use handeye::{Transform, check::quality::errors_against_truth};
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

pub use crate::solve::residual::{MotionResidual, ResidualRms, residual_rms};

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
/// [`crate::check::uncertainty`]'s).
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
    #[serde(serialize_with = "crate::model::warning::described")]
    pub warnings: Vec<Warning>,
    /// Over every pair of more than [`EXACT_POSES`] poses: the poses, spread evenly over the
    /// recording, whose pairs the largest residuals, the range of rotation angles and the axis
    /// spread were taken over ([`SAMPLE_POSES`] of them). Those are then the sample's: its largest
    /// residuals and angle at most the values over every pair, its smallest angle at least the
    /// value, its axis spread about its own dominant axis; the RMS residuals are over every pair
    /// all the same. Absent where every motion was gone through.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sampled_poses: Option<usize>,
}

/// Axis spread below which the report warns, degrees.
pub const WARN_AXIS_SPREAD_DEG: f64 = 8.0;
/// Rotation residual RMS above which the report warns about frame directions, degrees.
pub const WARN_RESIDUAL_DEG: f64 = 5.0;
/// Every pair of up to this many poses is gone through one by one for the largest residuals, the
/// range of rotation angles and the axis spread of [`quality_report`] (the RMS residuals come from
/// per-pose sums, O(n), at any size). Above, the pairs of [`SAMPLE_POSES`] poses spread evenly
/// over the recording stand for them: bounded work (about 2 million pairs, 20 ms on one core)
/// whatever the poses. Every recording of the repository's tests and golden outputs has at most
/// 3,488 poses; the largest pass is then 6 million pairs.
pub const EXACT_POSES: usize = 4096;

/// Poses whose pairs stand for every pair above [`EXACT_POSES`].
pub const SAMPLE_POSES: usize = 2048;

/// Default floor of the per-pose outlier test on the median |θ_A − θ_B| of a pose's motions, degrees.
pub const OUTLIER_DEG: f64 = 3.0;

/// The quality report of X over the motion pairs it was solved from. Per-motion entries are kept
/// for at most `max_per_motion` motions (the summary covers all of them). Outliers are judged per
/// pose ([`crate::check::outliers::pose_outliers`]).
pub fn quality_report(
    motions: &(impl MotionSource + ?Sized),
    x: &Transform,
    max_per_motion: usize,
) -> QualityReport {
    let keep = motions.count() <= max_per_motion;
    let (residual, per_motion, axis_spread, rotation_range_deg, sampled_poses) =
        match motions.all_pairs() {
            Some(pairs) if !keep => {
                let (residual, spread, range, sampled) = pairs_quality(pairs, motions, x);
                (residual, Vec::new(), spread, range, sampled)
            }
            _ => {
                let (residual, per_motion, range) = motion_quality(motions, x, keep);
                let spread = crate::solve::motions::axis_spread(motions);
                (residual, per_motion, spread, range, None)
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
        sampled_poses,
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
        let angle_a = crate::model::motion::MotionFeatures::of(&m.a).angle;
        let angle_b = crate::model::motion::MotionFeatures::of(&m.b).angle;
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
///   pairs, with no O(n) form: two passes over the pairs of per-pose quantities, never composing
///   the motions. The rotation of a motion is the product of the two poses' quaternions (its
///   vector part sin(θ/2) k gives the axis and θ² k kᵀ with one branch-free arc tangent, near π
///   too); the per-pose data are laid out by component so that the loops over the later poses
///   vectorise; parallel blocks of rows are combined in a fixed order (the result does not
///   depend on the number of threads). Above [`EXACT_POSES`] poses, over the pairs of
///   [`SAMPLE_POSES`] poses spread evenly over the recording (the last return value, their
///   number), and the RMS angle where the warning may fire from the same sums with the sample's
///   ratio of the mean squared angle to the mean chordal residual (exact when every pair has the
///   same residual; within the bracket above in any case).
fn pairs_quality(
    pairs: &AllPairs,
    motions: &(impl MotionSource + ?Sized),
    x: &Transform,
) -> (ResidualSummary, f64, [f64; 2], Option<usize>) {
    pairs_quality_over(pairs, motions, x, (EXACT_POSES, SAMPLE_POSES))
}

/// [`pairs_quality`] with every pair gone through up to `exact` poses, and above, the pairs of
/// `sample` poses spread evenly over the recording.
fn pairs_quality_over(
    pairs: &AllPairs,
    motions: &(impl MotionSource + ?Sized),
    x: &Transform,
    (exact, sample): (usize, usize),
) -> (ResidualSummary, f64, [f64; 2], Option<usize>) {
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
    let sampled = (n > exact && sample >= 2).then_some(sample.min(n));
    let rows_of: Vec<usize> = match sampled {
        Some(m) => (0..m).map(|k| k * (n - 1) / (m - 1)).collect(),
        None => (0..n).collect(),
    };
    let columns = PoseColumns::new(&poses, &rows_of);
    let n = rows_of.len();
    let blocks: Vec<usize> = (0..n).step_by(PAIR_ROWS).collect();
    let rows = |start: usize| start..(start + PAIR_ROWS).min(n);
    let passes: Vec<PairPass> = blocks
        .par_iter()
        .map(|&start| {
            let mut pass = PairPass::default();
            for i in rows(start) {
                pass.add_row(&columns, i, n);
            }
            pass
        })
        .collect();
    let (widest_u, translation_max, smallest, largest, scatter) = passes
        .into_iter()
        .fold(PairPass::default(), PairPass::merge)
        .finish();
    let eigen = scatter.symmetric_eigen();
    let dominant: Vector3<f64> = eigen
        .eigenvectors
        .column(eigen.eigenvalues.imax())
        .into_owned();
    let closest = blocks
        .par_iter()
        .map(|&start| {
            rows(start)
                .map(|i| closest_axis(&columns, i, n, &dominant))
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
        rotation_rms = match sampled {
            None => motion_quality(motions, x, false).0.rotation_deg_rms,
            Some(_) => {
                let (angles, chordal) = columns.squared_angles_and_residuals();
                if chordal > 0.0 {
                    (chordal_mean * angles / chordal).sqrt().to_degrees()
                } else {
                    0.0
                }
            }
        };
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
        sampled,
    )
}

/// Rows of pairs per parallel block in [`pairs_quality`].
const PAIR_ROWS: usize = 16;

/// Pairs per chunk of the inner loop: their terms go to short buffers in one loop without
/// branches (which vectorises), and are reduced from there.
const CHUNK: usize = 64;

/// Accumulators side by side in the reductions (combined in lane order at the end, so the sums
/// do not depend on the machine or the number of threads).
const LANES: usize = 4;

/// The per-pose quantities of the pair pass, one array per component, so that the loop over the
/// later poses reads them contiguously.
struct PoseColumns {
    /// D = W − W̄, row-major.
    d: [Vec<f64>; 9],
    /// e = y − ȳ.
    e: [Vec<f64>; 3],
    /// o, the target's origin in the camera's fixed frame (less its mean).
    o: [Vec<f64>; 3],
    /// g = e − D o.
    g: [Vec<f64>; 3],
    /// R_k as a unit quaternion (w, x, y, z): the motion from pose j to pose i has the rotation
    /// R_jᵀ R_i = q_j* q_i, whose vector part is sin(θ/2) k and scalar part cos(θ/2), accurate
    /// over the whole range (near π too, where the skew part of R_a loses the axis).
    q: [Vec<f64>; 4],
}

/// Pose i of a row of pairs.
struct RowPose {
    d: [f64; 9],
    g: [f64; 3],
    o: [f64; 3],
    q: [f64; 4],
}

/// The columns of the later poses of one chunk, all of the same length.
struct Later<'a> {
    d: [&'a [f64]; 9],
    e: [&'a [f64]; 3],
    q: [&'a [f64]; 4],
}

impl PoseColumns {
    /// The columns of `poses[rows]`, in that order.
    fn new(poses: &[PoseUnderX], rows: &[usize]) -> Self {
        let poses: Vec<&PoseUnderX> = rows.iter().map(|&k| &poses[k]).collect();
        let column =
            |f: &dyn Fn(&PoseUnderX) -> f64| poses.iter().map(|p| f(p)).collect::<Vec<f64>>();
        let quaternions: Vec<[f64; 4]> = poses
            .iter()
            .map(|p| {
                let q = nalgebra::UnitQuaternion::from_rotation_matrix(
                    &nalgebra::Rotation3::from_matrix_unchecked(p.r),
                );
                [q.w, q.i, q.j, q.k]
            })
            .collect();
        let g: Vec<Vector3<f64>> = poses.iter().map(|p| p.g()).collect();
        Self {
            d: std::array::from_fn(|k| column(&|p| p.d[(k / 3, k % 3)])),
            e: std::array::from_fn(|k| column(&|p| p.e[k])),
            o: std::array::from_fn(|k| column(&|p| p.o[k])),
            g: std::array::from_fn(|k| g.iter().map(|g| g[k]).collect()),
            q: std::array::from_fn(|k| quaternions.iter().map(|q| q[k]).collect()),
        }
    }

    /// Σ θ² and Σ ‖ΔR‖²_F over the pairs of these poses, θ each pair's residual angle: one by
    /// one (an arc sine each).
    fn squared_angles_and_residuals(&self) -> (f64, f64) {
        let n = self.d[0].len();
        count_pairs(n * n.saturating_sub(1) / 2);
        let (mut angles, mut chordal) = (0.0, 0.0);
        for i in 0..n {
            for j in i + 1..n {
                let u: f64 = (0..9).map(|c| (self.d[c][i] - self.d[c][j]).powi(2)).sum();
                let theta = 2.0 * (u / 8.0).clamp(0.0, 1.0).sqrt().asin();
                angles += theta * theta;
                chordal += u;
            }
        }
        (angles, chordal)
    }

    fn row(&self, i: usize) -> RowPose {
        RowPose {
            d: std::array::from_fn(|k| self.d[k][i]),
            g: std::array::from_fn(|k| self.g[k][i]),
            o: std::array::from_fn(|k| self.o[k][i]),
            q: std::array::from_fn(|k| self.q[k][i]),
        }
    }

    fn later(&self, start: usize, len: usize) -> Later<'_> {
        let range = start..start + len;
        Later {
            d: std::array::from_fn(|k| &self.d[k][range.clone()]),
            e: std::array::from_fn(|k| &self.e[k][range.clone()]),
            q: std::array::from_fn(|k| &self.q[k][range.clone()]),
        }
    }
}

/// The rotation of the motion from later pose k to pose i, q_k* q_i = (w_k w_i + u_k·u_i,
/// w_k u_i − w_i u_k − u_k × u_i): (|cos(θ/2)|, sin(θ/2) k up to sign).
#[inline(always)]
fn relative_rotation(p: &RowPose, later: &Later, k: usize) -> (f64, [f64; 3]) {
    let [wi, xi, yi, zi] = p.q;
    let q = &later.q;
    let (wj, xj, yj, zj) = (q[0][k], q[1][k], q[2][k], q[3][k]);
    let w = wj * wi + xj * xi + yj * yi + zj * zi;
    let v = [
        wj * xi - wi * xj - (yj * zi - zj * yi),
        wj * yi - wi * yj - (zj * xi - xj * zi),
        wj * zi - wi * zj - (xj * yi - yj * xi),
    ];
    (w.abs(), v)
}

/// θ of a rotation from (|cos(θ/2)|, sin(θ/2) k), with ‖sin(θ/2) k‖².
#[inline(always)]
fn angle_of_half(cos_half: f64, v: &[f64; 3]) -> (f64, f64) {
    let s2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    (2.0 * atan_ratio(s2.sqrt(), cos_half), s2)
}

/// atan(s / c) for s, c ≥ 0 (π/2 when c = 0), without a branch, so that the loops calling it
/// vectorise: Cephes' `atan` (a rational function of degree 4/5 after reducing the argument to
/// |x| ≤ 0.66 with π/4 or π/2), accurate to about 2 units in the last place.
#[inline(always)]
fn atan_ratio(s: f64, c: f64) -> f64 {
    const P: [f64; 5] = [
        -8.750_608_600_031_904e-1,
        -1.615_753_718_733_365e1,
        -7.500_855_792_314_705e1,
        -1.228_866_684_490_136e2,
        -6.485_021_904_942_025e1,
    ];
    const Q: [f64; 5] = [
        2.485_846_490_142_306e1,
        1.650_270_098_316_988_5e2,
        4.328_810_604_912_903e2,
        4.853_903_996_359_137e2,
        1.945_506_571_482_614e2,
    ];
    // tan(3π/8), and the low part of π/2.
    const T3P8: f64 = 2.414_213_562_373_095;
    const MOREBITS: f64 = 6.123_233_995_736_766e-17;
    let big = s > T3P8 * c;
    let mid = s > 0.66 * c;
    // x = s / c, reduced: −1/x above tan(3π/8), (x − 1)/(x + 1) above 0.66.
    let num = if big {
        -c
    } else if mid {
        s - c
    } else {
        s
    };
    let den = if big {
        s
    } else if mid {
        s + c
    } else {
        c
    };
    let (base, low) = if big {
        (std::f64::consts::FRAC_PI_2, MOREBITS)
    } else if mid {
        (std::f64::consts::FRAC_PI_4, 0.5 * MOREBITS)
    } else {
        (0.0, 0.0)
    };
    let x = if den > 0.0 { num / den } else { 0.0 };
    let z = x * x;
    let p = (((P[0] * z + P[1]) * z + P[2]) * z + P[3]) * z + P[4];
    let q = ((((z + Q[0]) * z + Q[1]) * z + Q[2]) * z + Q[3]) * z + Q[4];
    base + (x * (z * p / q) + x + low)
}

/// max and min that compile to one instruction (no NaN handling: none of the terms is NaN for
/// finite poses).
#[inline(always)]
fn max(a: f64, b: f64) -> f64 {
    if a > b { a } else { b }
}

#[inline(always)]
fn min(a: f64, b: f64) -> f64 {
    if a < b { a } else { b }
}

/// Folds `xs` into the lanes with `f`, element k into lane k mod [`LANES`].
#[inline(always)]
fn fold_lanes(acc: &mut [f64; LANES], xs: &[f64], f: impl Fn(f64, f64) -> f64) {
    let (chunks, rest) = xs.as_chunks::<LANES>();
    for c in chunks {
        for l in 0..LANES {
            acc[l] = f(acc[l], c[l]);
        }
    }
    for (a, &x) in acc.iter_mut().zip(rest) {
        *a = f(*a, x);
    }
}

/// The maxima and sums of one block of pairs in [`pairs_quality`], lane by lane.
#[derive(Clone, Copy)]
struct PairPass {
    /// Largest ‖ΔR‖²_F.
    widest_u: [f64; LANES],
    /// Largest ‖ΔT‖².
    translation_max: [f64; LANES],
    /// Smallest and largest rotation angle of A, radians.
    smallest: [f64; LANES],
    largest: [f64; LANES],
    /// Σ θ² k kᵀ of the rotations of A: the entries (0,0), (1,1), (2,2), (0,1), (0,2), (1,2).
    scatter: [[f64; LANES]; 6],
}

impl Default for PairPass {
    fn default() -> Self {
        Self {
            widest_u: [0.0; LANES],
            translation_max: [0.0; LANES],
            smallest: [f64::INFINITY; LANES],
            largest: [0.0; LANES],
            scatter: [[0.0; LANES]; 6],
        }
    }
}

impl PairPass {
    /// The pairs of pose i and every later pose.
    fn add_row(&mut self, poses: &PoseColumns, i: usize, n: usize) {
        count_pairs(n - i - 1);
        let p = poses.row(i);
        let mut start = i + 1;
        let (mut u, mut t, mut angle) = ([0.0; CHUNK], [0.0; CHUNK], [0.0; CHUNK]);
        let mut scatter = [[0.0; CHUNK]; 6];
        while start < n {
            let len = (n - start).min(CHUNK);
            let later = poses.later(start, len);
            let (u, t, angle) = (&mut u[..len], &mut t[..len], &mut angle[..len]);
            let mut s = scatter.each_mut().map(|s| &mut s[..len]);
            for k in 0..len {
                // ‖ΔR‖²_F = ‖D_i − D_j‖²_F.
                let mut uk = 0.0;
                for (c, &di) in p.d.iter().enumerate() {
                    let x = di - later.d[c][k];
                    uk += x * x;
                }
                u[k] = uk;
                // ‖ΔT‖² = ‖g_i − e_j + D_j o_i‖².
                let mut tk = 0.0;
                for r in 0..3 {
                    let x = p.g[r] - later.e[r][k]
                        + later.d[3 * r][k] * p.o[0]
                        + later.d[3 * r + 1][k] * p.o[1]
                        + later.d[3 * r + 2][k] * p.o[2];
                    tk += x * x;
                }
                t[k] = tk;
                let (cos_half, v) = relative_rotation(&p, &later, k);
                let (a, s2) = angle_of_half(cos_half, &v);
                angle[k] = a;
                // θ² k kᵀ = (θ² / sin²(θ/2)) v vᵀ, none below crate::model::pose::NO_AXIS_ANGLE.
                let weight = if a >= crate::model::pose::NO_AXIS_ANGLE {
                    a * a / s2
                } else {
                    0.0
                };
                s[0][k] = weight * v[0] * v[0];
                s[1][k] = weight * v[1] * v[1];
                s[2][k] = weight * v[2] * v[2];
                s[3][k] = weight * v[0] * v[1];
                s[4][k] = weight * v[0] * v[2];
                s[5][k] = weight * v[1] * v[2];
            }
            fold_lanes(&mut self.widest_u, u, max);
            fold_lanes(&mut self.translation_max, t, max);
            fold_lanes(&mut self.smallest, angle, min);
            fold_lanes(&mut self.largest, angle, max);
            for (acc, s) in self.scatter.iter_mut().zip(&mut s) {
                fold_lanes(acc, s, |a, x| a + x);
            }
            start += len;
        }
    }

    /// Two blocks' results together.
    fn merge(mut self, other: Self) -> Self {
        for l in 0..LANES {
            self.widest_u[l] = self.widest_u[l].max(other.widest_u[l]);
            self.translation_max[l] = self.translation_max[l].max(other.translation_max[l]);
            self.smallest[l] = self.smallest[l].min(other.smallest[l]);
            self.largest[l] = self.largest[l].max(other.largest[l]);
            for k in 0..6 {
                self.scatter[k][l] += other.scatter[k][l];
            }
        }
        self
    }

    /// The lanes together: (largest ‖ΔR‖²_F, largest ‖ΔT‖², smallest θ, largest θ, Σ θ² k kᵀ).
    fn finish(&self) -> (f64, f64, f64, f64, Matrix3<f64>) {
        let fold_max = |x: &[f64; LANES]| x.iter().copied().fold(0.0, f64::max);
        let smallest = self.smallest.iter().copied().fold(f64::INFINITY, f64::min);
        let sum = |k: usize| self.scatter[k].iter().sum::<f64>();
        let (xy, xz, yz) = (sum(3), sum(4), sum(5));
        let scatter = Matrix3::new(sum(0), xy, xz, xy, sum(1), yz, xz, yz, sum(2));
        (
            fold_max(&self.widest_u),
            fold_max(&self.translation_max),
            smallest,
            fold_max(&self.largest),
            scatter,
        )
    }
}

/// The smallest |k · dominant| over the motions from the later poses to pose i (1 when none has
/// an axis): |v · dominant| / ‖v‖ with v = sin(θ/2) k, for the motions with θ ≥
/// [`crate::model::pose::NO_AXIS_ANGLE`].
fn closest_axis(poses: &PoseColumns, i: usize, n: usize, dominant: &Vector3<f64>) -> f64 {
    count_pairs(n - i - 1);
    let p = poses.row(i);
    let mut closest = [1.0_f64; LANES];
    let mut cos = [0.0; CHUNK];
    let mut start = i + 1;
    while start < n {
        let len = (n - start).min(CHUNK);
        let later = poses.later(start, len);
        let cos = &mut cos[..len];
        for (k, c) in cos.iter_mut().enumerate() {
            let (cos_half, v) = relative_rotation(&p, &later, k);
            let (a, s2) = angle_of_half(cos_half, &v);
            let dot = v[0] * dominant[0] + v[1] * dominant[1] + v[2] * dominant[2];
            *c = if a >= crate::model::pose::NO_AXIS_ANGLE {
                dot.abs() / s2.sqrt()
            } else {
                1.0
            };
        }
        fold_lanes(&mut closest, cos, min);
        start += len;
    }
    closest.iter().copied().fold(1.0, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::motion::{Pairing, PosePair, Setup, motion_pairs};
    use crate::model::pose::{exp_so3, transform_from_parts};
    use crate::sim::{SimConfig, simulate};

    #[test]
    fn the_branch_free_arc_tangent_is_the_libm_one_to_two_units_in_the_last_place() {
        let mut worst = 0.0_f64;
        let mut check = |s: f64, c: f64| {
            let (a, b) = (atan_ratio(s, c), s.atan2(c));
            assert!(
                (a - b).abs() <= 4.5e-16 * b.abs(),
                "atan({s} / {c}): {a:e} vs {b:e}"
            );
            worst = worst.max((a - b).abs() / b.abs().max(f64::MIN_POSITIVE));
        };
        for k in 0..=20_000 {
            // Angles over [0, π/2], and the reduction's boundaries (0.66, tan 3π/8) exactly.
            let t = std::f64::consts::FRAC_PI_2 * k as f64 / 20_000.0;
            check(t.sin(), t.cos());
        }
        for x in [0.66, 2.414_213_562_373_095, 1.0, 1e-300, 1e-20, 1e20] {
            check(x, 1.0);
            check(x * 0.5, 0.5);
        }
        check(0.0, 1.0);
        check(1.0, 0.0);
        assert_eq!(atan_ratio(0.0, 1.0), 0.0);
        assert_eq!(atan_ratio(1.0, 0.0), std::f64::consts::FRAC_PI_2);
        assert!(worst > 0.0, "the comparison saw no rounding at all");
    }

    /// Simulated poses with, besides, a pose a hair (1e-7 rad) from the first, an exact copy of
    /// it (a motion of exactly 0) and poses turned by π − 1e-6 and π from it (motions of nearly
    /// and exactly 180°, where the skew part of R_a loses the axis), their camera poses
    /// consistent with the true X.
    fn poses_with_extreme_motions(setup: Setup, seed: u64) -> Vec<PosePair> {
        let config = SimConfig {
            poses: 40,
            ..SimConfig::default()
        };
        let series = simulate(&config, seed, 0);
        let mut poses = series.poses;
        let x = series.gripper_from_camera;
        let first = poses[0];
        let turned = |angle: f64| {
            let k = Vector3::new(0.3, -0.5, 0.8).normalize();
            let turn = transform_from_parts(&exp_so3(&(k * angle)), &Vector3::zeros());
            PosePair {
                base_from_gripper: first.base_from_gripper * turn,
                camera_from_target: x.inverse() * turn.inverse() * x * first.camera_from_target,
            }
        };
        poses.push(turned(1e-7));
        poses.push(first);
        poses.push(turned(std::f64::consts::PI - 1e-6));
        poses.push(turned(std::f64::consts::PI));
        if setup == Setup::EyeToHand {
            // The same hand poses read as gripper_from_base: a valid eye-to-hand series.
            for p in &mut poses {
                p.base_from_gripper = p.base_from_gripper.inverse();
            }
        }
        poses
    }

    #[test]
    fn above_the_exact_size_a_sample_of_poses_stands_for_every_pair() {
        let poses = simulate(
            &SimConfig {
                poses: 300,
                ..SimConfig::default()
            },
            5,
            0,
        )
        .poses;
        let pairs = AllPairs::new(&poses, Setup::EyeInHand);
        let x = crate::solve::andreff(&pairs).unwrap().x;
        let (all, all_spread, all_range, none) =
            pairs_quality_over(&pairs, &pairs, &x, (usize::MAX, 0));
        assert_eq!(none, None);
        // The exact pass is the default's below EXACT_POSES, to the last digit.
        assert_eq!(pairs_quality(&pairs, &pairs, &x).0, all);
        let (part, spread, range, sampled) = pairs_quality_over(&pairs, &pairs, &x, (100, 60));
        assert_eq!(sampled, Some(60));
        // The RMS values come from every pair either way.
        assert_eq!(part.translation_rms, all.translation_rms);
        assert_eq!(part.rotation_deg_rms, all.rotation_deg_rms);
        // The sample's maxima bound those over every pair from below, its smallest angle from
        // above; on a random walk 60 of 300 poses come within 30 % of the largest (the largest
        // motions are between poses far apart in the walk, which an even spread keeps); the
        // smallest angle, a closest pair, is the sample's own (here 0.98° against 0.075°).
        assert!(part.rotation_deg_max <= all.rotation_deg_max);
        assert!(part.translation_max <= all.translation_max);
        assert!(range[1] <= all_range[1] && range[0] >= all_range[0]);
        assert!(
            part.rotation_deg_max > 0.7 * all.rotation_deg_max,
            "{part:?} {all:?}"
        );
        assert!(
            part.translation_max > 0.7 * all.translation_max,
            "{part:?} {all:?}"
        );
        assert!(range[1] > 0.7 * all_range[1], "{range:?} {all_range:?}");
        assert!(
            (spread - all_spread).abs() < 0.2 * all_spread,
            "{spread} {all_spread}"
        );
        // The whole report says so.
        let report = quality_report(&pairs, &x, 0);
        assert_eq!(report.sampled_poses, None);
    }

    #[test]
    fn the_pair_pass_equals_the_motion_by_motion_quality() {
        for setup in [Setup::EyeInHand, Setup::EyeToHand] {
            for seed in [1, 2] {
                let poses = poses_with_extreme_motions(setup, seed);
                let pairs = AllPairs::new(&poses, setup);
                let stored = motion_pairs(&poses, Pairing::All, setup);
                let x = crate::solve::andreff(&stored).unwrap().x;
                let (residual, spread, range, sampled) = pairs_quality(&pairs, &pairs, &x);
                assert_eq!(sampled, None);
                let (by_motion, _, by_motion_range) = motion_quality(&stored, &x, false);
                let by_motion_spread = crate::solve::motions::axis_spread(&stored);
                let what = format!("{setup:?} seed {seed}");
                // Angles of rotations are rounded to about 1e-16 rad (absolute) either way.
                let close = |a: f64, b: f64, tolerance: f64, name: &str| {
                    assert!(
                        (a - b).abs() <= tolerance * b.abs() + 1e-15,
                        "{what} {name}: {a:e} vs {b:e}"
                    );
                };
                close(range[0], by_motion_range[0], 1e-12, "smallest angle");
                close(range[1], by_motion_range[1], 1e-12, "largest angle");
                assert!(range[0] < 1e-15, "{what}: the copy's motion of 0");
                assert!(
                    (range[1] - 180.0).abs() < 1e-9,
                    "{what}: the motion of π, {}",
                    range[1]
                );
                close(spread, by_motion_spread, 1e-12, "axis spread");
                close(
                    residual.rotation_deg_max,
                    by_motion.rotation_deg_max,
                    1e-9,
                    "rotation max",
                );
                close(
                    residual.translation_max,
                    by_motion.translation_max,
                    1e-9,
                    "translation max",
                );
            }
        }
    }
}
