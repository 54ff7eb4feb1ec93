//! Time synchronisation of a robot pose stream and a camera pose stream: pairing by interpolation,
//! and estimation of the offset between their clocks.
//!
//! Real recordings (ROS bags, the ethz-asl and TUM layouts) give two streams at different rates.
//! Each camera sample is paired with the robot pose interpolated at its stamp (slerp for the
//! rotation, linear for the translation). The camera stamps are first shifted by the clock offset
//! (`offset` = camera clock − robot clock), which [`estimate_time_offset`] finds by
//! cross-correlating the angular speeds of the two streams: for a rigid X, the gripper and the
//! camera rotate by the same angle over any interval.

use nalgebra::UnitQuaternion;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::model::error::{Error, Result};
use crate::model::findings::{Reading, Written, WrittenAs};
use crate::model::motion::PosePair;
use crate::model::pose::{Transform, rotation_angle_between, transform_from_parts};

/// A pose with its time stamp, seconds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StampedPose {
    /// Time stamp, seconds.
    pub stamp: f64,
    /// The pose (`base_from_gripper` for the robot stream, `camera_from_target` for the camera).
    pub pose: Transform,
}

/// How camera samples are paired with the robot stream; `Default` gives the values on each field.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub(crate) struct SyncOptions {
    /// Camera clock minus robot clock, seconds: a camera stamp t is looked up at t − offset in the
    /// robot stream. Default 0.
    pub time_offset: f64,
    /// A camera sample whose two bracketing robot samples are further apart than this is dropped
    /// (the robot stream has a gap there), seconds. Default 0.1.
    pub max_gap: f64,
}

impl Default for SyncOptions {
    fn default() -> Self {
        Self {
            time_offset: 0.0,
            max_gap: 0.1,
        }
    }
}

/// The result of pairing two streams.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Synced {
    /// Camera stamps of the pairs (camera clock), seconds.
    pub stamps: Vec<f64>,
    /// The pose pairs, in camera order.
    pub pairs: Vec<PosePair>,
    /// Camera samples outside the robot stream's time span.
    pub dropped_outside: usize,
    /// Camera samples in a gap of the robot stream longer than `max_gap`.
    pub dropped_gap: usize,
}

/// What a stream holds at a given time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Lookup {
    /// The interpolated pose.
    Pose(Transform),
    /// The time lies outside the stream.
    Outside,
    /// The time lies in a gap between samples longer than the allowed one.
    Gap,
}

/// Interpolates a stream (sorted by stamp) at time `t`: slerp between the bracketing rotations,
/// linear between the translations.
pub(crate) fn interpolate(stream: &[StampedPose], t: f64, max_gap: f64) -> Lookup {
    let (Some(first), Some(last)) = (stream.first(), stream.last()) else {
        return Lookup::Outside;
    };
    if !(t >= first.stamp && t <= last.stamp) {
        return Lookup::Outside;
    }
    // First sample with stamp > t; its predecessor has stamp ≤ t.
    let k = stream.partition_point(|s| s.stamp <= t);
    if k == stream.len() {
        return Lookup::Pose(last.pose);
    }
    let (a, b) = (&stream[k - 1], &stream[k]);
    let span = b.stamp - a.stamp;
    if span > max_gap {
        return Lookup::Gap;
    }
    let s = if span > 0.0 {
        (t - a.stamp) / span
    } else {
        0.0
    };
    let qa = UnitQuaternion::from_rotation_matrix(&a.pose.rotation);
    let mut qb = UnitQuaternion::from_rotation_matrix(&b.pose.rotation);
    // q and −q are the same rotation: take the one on qa's side, so slerp takes the short way.
    if qa.coords.dot(&qb.coords) < 0.0 {
        qb = UnitQuaternion::new_unchecked(-qb.into_inner());
    }
    // nalgebra's slerp leaves its result unnormalised by up to ~1e-8 between nearly equal
    // rotations (acos near 1): a rotation matrix off orthonormal by 7e-9 on ethz-asl's streams,
    // which a 4×4 copy of the poses (Python's arrays, a JSON Lines dump) then projected, so that
    // the command line on the streams and Python on their poses disagreed (andreff-joint's X by
    // 1e-8).
    let q = UnitQuaternion::new_normalize(qa.slerp(&qb, s).into_inner());
    let p = a
        .pose
        .translation
        .vector
        .lerp(&b.pose.translation.vector, s);
    Lookup::Pose(transform_from_parts(q.to_rotation_matrix().matrix(), &p))
}

/// Pairs each camera sample (`camera_from_target`) with the robot pose (`base_from_gripper`)
/// interpolated at its stamp. Both streams must be sorted by stamp.
pub(crate) fn pair_streams(
    robot: &[StampedPose],
    camera: &[StampedPose],
    options: &SyncOptions,
) -> Synced {
    let mut out = Synced {
        stamps: Vec::new(),
        pairs: Vec::new(),
        dropped_outside: 0,
        dropped_gap: 0,
    };
    for c in camera {
        match interpolate(robot, c.stamp - options.time_offset, options.max_gap) {
            Lookup::Outside => out.dropped_outside += 1,
            Lookup::Gap => out.dropped_gap += 1,
            Lookup::Pose(base_from_gripper) => {
                out.stamps.push(c.stamp);
                out.pairs.push(PosePair {
                    base_from_gripper,
                    camera_from_target: c.pose,
                });
            }
        }
    }
    out
}

/// The largest clock offset taken, seconds (about 127 years): more than any two clocks differ,
/// a camera stamping from its boot and a robot in Unix time included (1.7e9 s), and small enough
/// for nanosecond stamps (a ROS 2 recording's) to hold it.
pub const MAX_TIME_OFFSET: f64 = 4e9;

/// The clock offset to pair two streams with.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum TimeOffset {
    /// Camera clock minus robot clock, seconds.
    Fixed(f64),
    /// Estimated: angular-speed correlation, refined by the agreement of the paired poses.
    Auto,
}

impl TimeOffset {
    /// The largest clock offset taken, seconds (about 127 years): more than any two clocks
    /// differ, a camera stamping from its boot and a robot in Unix time included (1.7e9 s), and
    /// small enough for nanosecond stamps (a ROS 2 recording's) to hold it.
    pub const MAX_SECONDS: f64 = MAX_TIME_OFFSET;
}

/// Two stream files read and paired ([`pair_stream_files`]).
#[derive(Debug, Clone, PartialEq)]
pub struct StreamPairing {
    /// The pairs, their camera stamps and what was dropped.
    pub synced: Synced,
    /// Offset used, seconds.
    pub time_offset: f64,
    /// With [`TimeOffset::Auto`]: the offset found, its sigma and the correlation's own
    /// estimate before refinement.
    pub correlated: Option<FoundOffset>,
    /// Samples of the robot and the camera file that were out of time order (put in order).
    pub reordered: [usize; 2],
    /// The largest angles in degrees of each stream (see [`crate::io::DegreeAngles`]).
    pub degrees: crate::io::DegreeAngles,
}

/// Reads a robot stream (`base_from_gripper`) and a camera stream (`target_from_camera`, the
/// ethz-asl and TUM layout) and pairs them at the camera stamps, with the given or an estimated
/// clock offset.
///
/// The offset is searched on the streams read as `reading` (the reading the poses will be solved
/// under: a quaternion order mixed up changes the angular speeds); the pairs are as the files give
/// them. Each stream's rotations are read in the convention `rotations` names for its side (a
/// quaternion `x y z w` when none is).
pub fn pair_stream_files(
    robot: &std::path::Path,
    camera: &std::path::Path,
    setup: crate::model::motion::Setup,
    (offset, reading): (TimeOffset, Reading),
    max_gap: f64,
    rotations: crate::model::rotation::Rotations,
) -> Result<StreamPairing> {
    let robot_stream = crate::io::read_stamped_poses(robot, rotations.robot)?;
    let camera_stream = crate::io::read_camera_stream(camera, rotations.camera)?;
    let reordered = [robot_stream.reordered, camera_stream.reordered];
    let degrees = crate::io::DegreeAngles {
        robot: robot_stream.largest_degrees,
        camera: camera_stream.largest_degrees,
    };
    let (robot, camera) = (robot_stream.poses, camera_stream.poses);
    let (time_offset, correlated) = match offset {
        TimeOffset::Fixed(t) => (t, None),
        TimeOffset::Auto => {
            // A camera stream holds `target_from_camera`.
            let written = Written {
                robot: WrittenAs::Named,
                camera: WrittenAs::Inverse,
                frames: false,
            };
            let (r, c) = read_as(reading, written, &robot, &camera);
            let found = find_time_offset(&r, &c, setup, max_gap)?;
            (found.offset, Some(found))
        }
    };
    let synced = pair_streams(
        &robot,
        &camera,
        &SyncOptions {
            time_offset,
            max_gap,
        },
    );
    Ok(StreamPairing {
        synced,
        time_offset,
        correlated,
        reordered,
        degrees,
    })
}

/// Options of the clock-offset search; `Default` gives the values on each field.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct OffsetOptions {
    /// Largest offset considered, either sign, seconds. Default 1.0.
    pub max_offset: f64,
    /// Resampling step of the angular speeds, seconds; 0 picks the camera's median period / 2.
    /// Default 0.
    pub step: f64,
}

impl Default for OffsetOptions {
    fn default() -> Self {
        Self {
            max_offset: 1.0,
            step: 0.0,
        }
    }
}

/// An estimated clock offset.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OffsetEstimate {
    /// Camera clock minus robot clock, seconds.
    pub offset: f64,
    /// Normalised cross-correlation of the angular speeds at that offset (1 = identical shapes).
    pub correlation: f64,
    /// The correlation at every offset searched, `[offset s, correlation]` (offsets where the
    /// streams overlap too little are left out): what a report draws.
    pub curve: Vec<[f64; 2]>,
}

/// Estimates the clock offset (camera − robot) by cross-correlating the angular speeds of the two
/// streams, resampled on a common grid, over offsets within ±`max_offset`; the peak is refined by
/// a parabola through its neighbours.
///
/// Errors when the streams are too short or overlap too little, or when neither rotates.
pub fn estimate_time_offset(
    robot: &[StampedPose],
    camera: &[StampedPose],
    options: &OffsetOptions,
) -> Result<OffsetEstimate> {
    let bad = |message: &str| {
        Err(Error::InvalidParameter {
            name: "time_offset",
            message: message.to_string(),
        })
    };
    if robot.len() < 4 || camera.len() < 4 {
        return bad("too few samples to estimate a time offset (need at least 4 in each stream)");
    }
    let step = if options.step > 0.0 {
        options.step
    } else {
        median_period(camera) / 2.0
    };
    if !(step.is_finite() && step > 0.0) {
        return bad("camera stamps do not increase");
    }
    // The grids are sized by the streams' time spans: a stamp far from the others (seconds among
    // nanoseconds, a corrupt value) must not size an allocation.
    let most = GRID_PER_SAMPLE * (robot.len() + camera.len());
    for (name, s) in [("robot", robot), ("camera", camera)] {
        let span = s[s.len() - 1].stamp - s[0].stamp;
        let grid = span / step;
        if grid.is_nan() || grid > most as f64 {
            return Err(Error::InvalidParameter {
                name: "time_offset",
                message: format!(
                    "the {name} stream's stamps span {span:.6e} s for {} samples taken every {:.3e} s or so: a stamp far from the others (milli- or nanoseconds among seconds?); fix the stamps or give --time-offset in seconds",
                    s.len(),
                    2.0 * step
                ),
            });
        }
    }
    let speed_r = angular_speed_grid(robot, step);
    let speed_c = angular_speed_grid(camera, step);
    let max_lag = (options.max_offset / step).ceil() as i64;
    // Camera grid index i is at time c0 + i·step (camera clock) = c0 − offset + i·step (robot clock).
    let (r0, c0) = (robot[0].stamp, camera[0].stamp);
    let mut best: Option<(i64, f64)> = None;
    let mut scores = Vec::with_capacity((2 * max_lag + 1) as usize);
    for lag in -max_lag..=max_lag {
        let offset = lag as f64 * step;
        let score = correlation(&speed_r, r0, &speed_c, c0 - offset, step);
        scores.push(score);
        if let Some(s) = score
            && best.is_none_or(|(_, b)| s > b)
        {
            best = Some((lag, s));
        }
    }
    let Some((lag, score)) = best else {
        return bad(
            "the streams overlap too little, or neither rotates, within the offsets searched",
        );
    };
    // Parabolic refinement through the neighbouring scores.
    let k = (lag + max_lag) as usize;
    let mut offset = lag as f64 * step;
    if k > 0
        && let (Some(Some(l)), Some(Some(r))) = (scores.get(k - 1), scores.get(k + 1))
    {
        let denom = l - 2.0 * score + r;
        if denom < 0.0 {
            offset += 0.5 * (l - r) / denom * step;
        }
    }
    let curve = scores
        .iter()
        .enumerate()
        .filter_map(|(k, s)| s.map(|s| [(k as i64 - max_lag) as f64 * step, s]))
        .collect();
    Ok(OffsetEstimate {
        offset,
        correlation: score,
        curve,
    })
}

/// The robot and camera streams read as `reading`, from an input that wrote them `written`.
pub(crate) fn read_as(
    reading: Reading,
    written: Written,
    robot: &[StampedPose],
    camera: &[StampedPose],
) -> (Vec<StampedPose>, Vec<StampedPose>) {
    let map = |s: &[StampedPose], f: &dyn Fn(&Transform) -> Transform| -> Vec<StampedPose> {
        s.iter()
            .map(|p| StampedPose {
                stamp: p.stamp,
                pose: f(&p.pose),
            })
            .collect()
    };
    (
        map(robot, &|t| reading.robot(t, written.robot)),
        map(camera, &|t| reading.camera(t, written.camera)),
    )
}

/// A clock offset found by [`find_time_offset`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FoundOffset {
    /// Camera clock minus robot clock, seconds: the correlation's, refined by the agreement of
    /// the paired poses ([`refine_time_offset`]).
    pub offset: f64,
    /// Its one-sigma, seconds ([`time_offset_sigma`]); infinite when the poses do not pin it.
    pub sigma: f64,
    /// The angular speeds' correlation, before refinement.
    pub correlated: OffsetEstimate,
    /// How well the poses paired at `offset` agree on one X: the RMS of their per-pose rotation
    /// residuals over the best 80% of them, degrees (infinite when they cannot be solved). Above
    /// [`OFFSET_AGREEMENT_DEG`] the search failed ([`FoundOffset::failed`]).
    pub agreement_deg: f64,
}

/// The largest [`FoundOffset::agreement_deg`] of an offset found. The repository's 17 streams
/// (kinhec's 15, ethz-asl's 2) agree to 0.14–2.4° at the offset found (2.4° with planar flips
/// among the poses); offsets of 1.5, ±3 and 10 s outside the ±1 s searched left 13.4–28.3° on
/// three of them (docs/DECISIONS.md, "A clock offset not found is a refusal").
pub const OFFSET_AGREEMENT_DEG: f64 = 6.0;

impl FoundOffset {
    /// Whether the search failed: no offset searched pairs the poses into an agreement on one X,
    /// or the best lies at the edge of the offsets searched, beyond which the best may lie (the
    /// clocks differ by more than the ±1 s searched, or the streams are not of one motion).
    pub fn failed(&self) -> bool {
        offset_failed(self.offset, self.agreement_deg)
    }
}

/// [`FoundOffset::failed`] of an offset and its agreement: above [`OFFSET_AGREEMENT_DEG`], or at
/// least 95% of the default search's ±1 s (offsets of 1.5 s and more, refined, landed at
/// 1.015–1.043 s on ethz-asl's streams; the repository's streams are found within 0.1 s).
pub fn offset_failed(offset: f64, agreement_deg: f64) -> bool {
    // Written so that a NaN fails: a comparison with NaN is false.
    let agrees = agreement_deg <= OFFSET_AGREEMENT_DEG;
    !agrees || at_search_edge(offset)
}

/// Whether an offset found lies at the edge of the default search's ±1 s (within 5 % of it, or
/// not a number), beyond which the best may lie.
pub fn at_search_edge(offset: f64) -> bool {
    let inside = offset.abs() < 0.95 * OffsetOptions::default().max_offset;
    !inside
}

/// The clock offset of two streams (camera − robot, seconds) and its sigma: the angular speeds'
/// correlation ([`estimate_time_offset`], within about a camera period), refined by how well the
/// paired poses agree on one X ([`refine_time_offset`]).
///
/// Errors as [`estimate_time_offset`].
pub fn find_time_offset(
    robot: &[StampedPose],
    camera: &[StampedPose],
    setup: crate::model::motion::Setup,
    max_gap: f64,
) -> Result<FoundOffset> {
    // Stamps since the epoch (1.7e9 s) are resolved to 2.4e-7 s in f64: searched from the first
    // robot stamp, an offset resolves to rounding (a common shift changes no offset).
    let t0 = robot.first().map_or(0.0, |p| p.stamp);
    let shifted = |s: &[StampedPose]| -> Vec<StampedPose> {
        s.iter()
            .map(|p| StampedPose {
                stamp: p.stamp - t0,
                pose: p.pose,
            })
            .collect()
    };
    let (robot, camera) = (&shifted(robot)[..], &shifted(camera)[..]);
    let search = OffsetOptions::default();
    let correlated = estimate_time_offset(robot, camera, &search)?;
    let offset = refine_time_offset(
        robot,
        camera,
        setup,
        correlated.offset,
        search.max_offset,
        max_gap,
    );
    // The pairing at the offset found, fitted once: its cost is the agreement, and the centre of
    // the parabola the sigma is read from.
    let at = offset_fit(robot, camera, setup, offset, max_gap);
    Ok(FoundOffset {
        offset,
        sigma: at.map_or(f64::INFINITY, |at| {
            sigma_at(robot, camera, setup, (offset, at), max_gap)
        }),
        correlated,
        agreement_deg: at.map_or(f64::INFINITY, |(cost, _)| cost.sqrt().to_degrees()),
    })
}

/// The one-sigma of a clock offset found by [`refine_time_offset`], from the curvature of its
/// cost at the minimum (Gauss–Newton): the cost C(o) is the mean of the m kept per-pose squared
/// rotation residuals (3 components each), so var(o) = σ² / Σ(∂r/∂o)² with σ² = C/3 and
/// Σ(∂r/∂o)² = m C''/2: var(o) = 2C / (3 m C''). C'' is the curvature of a parabola fitted by
/// least squares to C over ±half a camera period (the cost is only piecewise smooth, as pairs
/// change with the offset). C is a trimmed mean (the best 80% of the poses), which underestimates
/// the residuals' variance: for Gaussian residuals ‖r‖²/σ² is χ²(3), and the mean of its lowest
/// 80% is E[χ²(3) | below its 0.8 quantile] = 3 F₅(q₀.₈)/0.8 (F₅ the χ²(5) CDF) ≈ 0.67 of the
/// full mean: σ² is C/3 divided by that fraction. Infinite when the cost does not curve up.
pub fn time_offset_sigma(
    robot: &[StampedPose],
    camera: &[StampedPose],
    setup: crate::model::motion::Setup,
    offset: f64,
    max_gap: f64,
) -> f64 {
    offset_fit(robot, camera, setup, offset, max_gap).map_or(f64::INFINITY, |at| {
        sigma_at(robot, camera, setup, (offset, at), max_gap)
    })
}

/// [`time_offset_sigma`] with the fit at the offset, `(cost, poses kept)`, given.
fn sigma_at(
    robot: &[StampedPose],
    camera: &[StampedPose],
    setup: crate::model::motion::Setup,
    (offset, (c0, kept)): (f64, (f64, usize)),
    max_gap: f64,
) -> f64 {
    let period = median_period(camera);
    if !(period.is_finite() && period > 0.0) {
        return f64::INFINITY;
    }
    // Least-squares parabola C(o + d) ≈ a + b d + c d² over symmetric points d_k (the middle
    // one the fit given).
    const POINTS: usize = 9;
    let half = 0.5 * period;
    let samples: Vec<(f64, f64)> = (0..POINTS)
        .filter_map(|k| {
            if k == POINTS / 2 {
                return Some((0.0, c0));
            }
            let d = -half + 2.0 * half * k as f64 / (POINTS - 1) as f64;
            offset_fit(robot, camera, setup, offset + d, max_gap).map(|(c, _)| (d, c))
        })
        .collect();
    if samples.len() < 5 {
        return f64::INFINITY;
    }
    let design = nalgebra::DMatrix::from_fn(samples.len(), 3, |i, j| samples[i].0.powi(j as i32));
    let costs = nalgebra::DVector::from_iterator(samples.len(), samples.iter().map(|s| s.1));
    let Ok(fit) = design.svd(true, true).solve(&costs, 1e-15) else {
        return f64::INFINITY;
    };
    let curvature = 2.0 * fit[2];
    if curvature.is_nan() || curvature <= 0.0 {
        return f64::INFINITY;
    }
    (2.0 * c0 / (trimmed_fraction_of_mean() * 3.0 * kept as f64 * curvature)).sqrt()
}

/// The mean of the lowest [`KEPT`] of χ²(3) over its full mean (see [`time_offset_sigma`]).
fn trimmed_fraction_of_mean() -> f64 {
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    let q = ChiSquared::new(3.0).map_or(f64::NAN, |c| c.inverse_cdf(KEPT));
    ChiSquared::new(5.0).map_or(f64::NAN, |c| c.cdf(q)) / KEPT
}

/// The fraction of the poses [`offset_cost`] keeps (the best).
const KEPT: f64 = 0.8;

/// Median difference of consecutive stamps.
fn median_period(s: &[StampedPose]) -> f64 {
    let mut d: Vec<f64> = s
        .windows(2)
        .map(|w| w[1].stamp - w[0].stamp)
        .filter(|d| *d > 0.0)
        .collect();
    if d.is_empty() {
        return f64::NAN;
    }
    d.sort_by(f64::total_cmp);
    d[d.len() / 2]
}

/// Angular speed (rad/s) of a stream on a grid of `step` from its first stamp: the rotation angle
/// between the (interpolated) poses at consecutive grid points, divided by `step`.
/// Refines a clock offset (camera − robot, seconds) to a small fraction of a camera period by
/// minimising how badly the paired poses agree on one X.
///
/// Cross-correlating angular speeds ([`estimate_time_offset`]) finds the offset to within about a
/// camera period, and outlier frames can mislead it entirely; what is left biases X. Here, at each
/// candidate offset (around `initial`, and coarsely over ±`max_offset`) the streams are paired,
/// X is the all-pairs Andreff solution from the accumulated normal equations (O(n)), and the cost
/// is the mean squared per-pose rotation residual (`crate::check::outliers::PoseResiduals`) over the
/// best 80% of the poses (a few bad samples do not steer it). The grids find the basin,
/// golden-section search its bottom. Returns `initial` when no candidate can be solved.
pub fn refine_time_offset(
    robot: &[StampedPose],
    camera: &[StampedPose],
    setup: crate::model::motion::Setup,
    initial: f64,
    max_offset: f64,
    max_gap: f64,
) -> f64 {
    let period = median_period(camera);
    if !(period.is_finite() && period > 0.0) {
        return initial;
    }
    let cost = |offset: f64| offset_cost(robot, camera, setup, offset, max_gap);
    // A fine grid over ±1 period around `initial`, and a coarse one (half-period steps) over
    // ±`max_offset`, in case outlier frames misled the correlation.
    const GRID: usize = 21;
    let fine = (0..GRID).map(|k| initial - period + 2.0 * period * k as f64 / (GRID - 1) as f64);
    let coarse_steps = (2.0 * max_offset / (0.5 * period))
        .ceil()
        .min(MAX_COARSE as f64) as usize;
    let coarse = (0..=coarse_steps)
        .map(|k| -max_offset + 2.0 * max_offset * k as f64 / coarse_steps.max(1) as f64);
    // The grid points are independent, so they are costed in parallel; the best is then taken
    // in grid order, the same point as one by one.
    let grid: Vec<(f64, f64)> = fine
        .map(|o| (o, 2.0 * period / (GRID - 1) as f64))
        .chain(coarse.map(|o| (o, 2.0 * max_offset / coarse_steps.max(1) as f64)))
        .collect();
    let costed: Vec<(f64, f64, f64)> = grid
        .par_iter()
        .map(|&(o, step)| (o, cost(o), step))
        .collect();
    let Some((best, best_cost, step)) = costed
        .into_iter()
        .filter(|c| c.1.is_finite())
        .min_by(|a, b| a.1.total_cmp(&b.1))
    else {
        return initial;
    };
    // Golden-section search between the best grid point's neighbours.
    let (mut lo, mut hi) = (best - step, best + step);
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let (mut a, mut b) = (hi - g * (hi - lo), lo + g * (hi - lo));
    let (mut fa, mut fb) = (cost(a), cost(b));
    // To a picosecond (or 80 steps): on noise-free streams the offset, and so X, is then exact to
    // rounding; 24 steps left 4e-8 s, and X 2e-8 off.
    for _ in 0..80 {
        if hi - lo < 1e-12 {
            break;
        }
        if fa <= fb {
            hi = b;
            (b, fb) = (a, fa);
            a = hi - g * (hi - lo);
            fa = cost(a);
        } else {
            lo = a;
            (a, fa) = (b, fb);
            b = lo + g * (hi - lo);
            fb = cost(b);
        }
    }
    let refined = 0.5 * (lo + hi);
    if cost(refined) <= best_cost {
        refined
    } else {
        best
    }
}

/// Most points of the coarse grid of [`refine_time_offset`].
const MAX_COARSE: usize = 4096;

/// The cost of [`refine_time_offset`] at one offset: infinite when fewer than 10 pairs or no X.
fn offset_cost(
    robot: &[StampedPose],
    camera: &[StampedPose],
    setup: crate::model::motion::Setup,
    offset: f64,
    max_gap: f64,
) -> f64 {
    offset_fit(robot, camera, setup, offset, max_gap).map_or(f64::INFINITY, |(cost, _)| cost)
}

/// The cost of [`offset_cost`] and how many poses it keeps; `None` when fewer than 10 pairs or no
/// X.
fn offset_fit(
    robot: &[StampedPose],
    camera: &[StampedPose],
    setup: crate::model::motion::Setup,
    offset: f64,
    max_gap: f64,
) -> Option<(f64, usize)> {
    let synced = pair_streams(
        robot,
        camera,
        &SyncOptions {
            time_offset: offset,
            max_gap,
        },
    );
    if synced.pairs.len() < 10 {
        return None;
    }
    let mut acc = crate::solve::accumulate::PoseAccumulator::new(setup);
    synced.pairs.iter().for_each(|p| acc.add(p));
    let estimate = acc.estimate()?;
    let residuals = crate::check::outliers::PoseResiduals::at(&synced.pairs, setup, &estimate.x);
    let mut squares: Vec<f64> = residuals
        .residuals
        .iter()
        .map(|r| r.rotation.norm_squared())
        .collect();
    squares.sort_by(f64::total_cmp);
    // The best KEPT = 4/5.
    let kept = &squares[..(squares.len() * 4).div_ceil(5)];
    Some((kept.iter().sum::<f64>() / kept.len() as f64, kept.len()))
}

/// Grid points allowed per stream sample in [`estimate_time_offset`].
const GRID_PER_SAMPLE: usize = 64;

fn angular_speed_grid(s: &[StampedPose], step: f64) -> Vec<f64> {
    let (t0, t1) = (s[0].stamp, s[s.len() - 1].stamp);
    let n = ((t1 - t0) / step).floor() as usize;
    let at = |t: f64| match interpolate(s, t, f64::INFINITY) {
        Lookup::Pose(p) => Some(p),
        _ => None,
    };
    let mut out = Vec::with_capacity(n);
    let mut previous = at(t0);
    for i in 1..=n {
        let current = at(t0 + i as f64 * step);
        let speed = match (previous, current) {
            (Some(a), Some(b)) => rotation_angle_between(&a.rotation, &b.rotation) / step,
            _ => f64::NAN,
        };
        out.push(speed);
        previous = current;
    }
    out
}

/// Pearson correlation of two grids where they overlap: `a` starts at `a0`, `b` at `b0` (same
/// clock after the shift), both with spacing `step`. `None` with fewer than 8 common samples or no
/// variation.
fn correlation(a: &[f64], a0: f64, b: &[f64], b0: f64, step: f64) -> Option<f64> {
    // b index j is at time b0 + j·step; the nearest a index is (b0 − a0)/step + j.
    let shift = ((b0 - a0) / step).round() as i64;
    let (mut n, mut sa, mut sb, mut saa, mut sbb, mut sab) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for (j, &y) in b.iter().enumerate() {
        let i = j as i64 + shift;
        if i < 0 || i as usize >= a.len() {
            continue;
        }
        let x = a[i as usize];
        if !(x.is_finite() && y.is_finite()) {
            continue;
        }
        n += 1.0;
        sa += x;
        sb += y;
        saa += x * x;
        sbb += y * y;
        sab += x * y;
    }
    if n < 8.0 {
        return None;
    }
    let cov = sab - sa * sb / n;
    let va = saa - sa * sa / n;
    let vb = sbb - sb * sb / n;
    if va <= 0.0 || vb <= 0.0 {
        return None;
    }
    Some(cov / (va * vb).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    /// A smooth gripper trajectory with varying angular speed, and the camera it carries.
    fn trajectory(t: f64) -> (Transform, Transform) {
        let q = Transform::new(
            Vector3::new(0.3 * (0.7 * t).sin(), 0.2 * (1.1 * t).cos(), 0.5),
            Vector3::new(
                0.6 * (0.9 * t).sin(),
                0.4 * (1.7 * t).sin(),
                0.3 * (0.5 * t).cos(),
            ),
        );
        let x = Transform::new(Vector3::new(0.05, 0.0, 0.1), Vector3::new(0.1, 0.2, 0.3));
        let base_from_target = Transform::new(Vector3::new(0.0, 0.0, -0.5), Vector3::zeros());
        (q, (base_from_target.inverse() * q * x).inverse())
    }

    #[test]
    fn a_far_stamp_is_refused_not_allocated() {
        for far in [1e11, 1.7e9, 1e300] {
            let (mut robot, camera) = streams(0.02);
            let last = robot.len() - 1;
            robot[last].stamp = far;
            let e = estimate_time_offset(&robot, &camera, &OffsetOptions::default()).unwrap_err();
            assert!(e.to_string().contains("far from the others"), "{e}");
        }
    }

    fn streams(offset: f64) -> (Vec<StampedPose>, Vec<StampedPose>) {
        let robot = (0..3000).map(|k| {
            let t = k as f64 * 0.01;
            StampedPose {
                stamp: t,
                pose: trajectory(t).0,
            }
        });
        // The camera samples at 30 Hz; its clock reads robot time + offset.
        let camera = (0..800).map(|k| {
            let t = 1.0 + k as f64 / 30.0;
            StampedPose {
                stamp: t + offset,
                pose: trajectory(t).1,
            }
        });
        (robot.collect(), camera.collect())
    }

    #[test]
    fn interpolated_rotations_are_orthonormal_between_nearly_equal_poses() {
        // Two rotations 1e-9 rad apart (a robot at rest, read at 100 Hz): the slerp's result was
        // unnormalised by up to ~1e-8.
        let a = crate::model::pose::Transform::new(
            Vector3::new(0.1, 0.2, 0.3),
            Vector3::new(0.4, -1.1, 2.0),
        );
        let b = crate::model::pose::Transform::new(
            Vector3::new(0.1, 0.2, 0.3),
            Vector3::new(0.4, -1.1, 2.0 + 1e-9),
        );
        let stream = [
            StampedPose {
                stamp: 0.0,
                pose: a,
            },
            StampedPose {
                stamp: 0.01,
                pose: b,
            },
        ];
        let mut worst = 0.0_f64;
        for k in 0..100 {
            let Lookup::Pose(p) = interpolate(&stream, 0.0001 * k as f64, 1.0) else {
                panic!("inside the stream");
            };
            let r = p.rotation.matrix();
            worst = worst.max(
                (r * r.transpose() - nalgebra::Matrix3::identity())
                    .abs()
                    .max(),
            );
        }
        assert!(worst < 1e-15, "{worst:e}");
    }

    #[test]
    fn pairing_interpolates_the_robot_at_camera_stamps() {
        let (robot, camera) = streams(0.0);
        let synced = pair_streams(&robot, &camera, &SyncOptions::default());
        assert_eq!(synced.pairs.len() + synced.dropped_outside, camera.len());
        for (t, p) in synced.stamps.iter().zip(&synced.pairs) {
            let truth = trajectory(*t).0;
            // Linear interpolation over 10 ms of a smooth motion.
            assert!(
                (p.base_from_gripper.translation.vector - truth.translation.vector).norm() < 1e-4
            );
            let e = crate::model::pose::rotation_angle_between(
                &p.base_from_gripper.rotation,
                &truth.rotation,
            );
            assert!(e < 1e-4, "t {t}: rotation off by {e}");
        }
    }

    #[test]
    fn gaps_and_the_outside_are_dropped() {
        let (mut robot, camera) = streams(0.0);
        robot.retain(|s| !(10.0..10.5).contains(&s.stamp));
        let synced = pair_streams(&robot, &camera, &SyncOptions::default());
        assert!(
            synced.dropped_gap >= 14 && synced.dropped_gap <= 16,
            "{}",
            synced.dropped_gap
        );
        let late = [StampedPose {
            stamp: 100.0,
            pose: Transform::identity(),
        }];
        assert_eq!(
            pair_streams(&robot, &late, &SyncOptions::default()).dropped_outside,
            1
        );
    }

    #[test]
    fn the_clock_offset_is_recovered_within_a_camera_period() {
        for offset in [-0.37, 0.0, 0.137, 0.5] {
            let (robot, camera) = streams(offset);
            let e = estimate_time_offset(&robot, &camera, &OffsetOptions::default()).unwrap();
            assert!(
                (e.offset - offset).abs() < 1.0 / 30.0,
                "offset {offset}: estimated {}",
                e.offset
            );
            assert!(e.correlation > 0.9);
        }
    }

    #[test]
    fn a_still_stream_has_no_offset() {
        let still: Vec<_> = (0..100)
            .map(|k| StampedPose {
                stamp: k as f64 * 0.01,
                pose: Transform::identity(),
            })
            .collect();
        assert!(estimate_time_offset(&still, &still, &OffsetOptions::default()).is_err());
    }
}
