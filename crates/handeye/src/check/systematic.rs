//! An error that follows the robot's configuration: an uncalibrated robot (DH parameters, joint
//! zero offsets), a wrong TCP or flange offset, camera intrinsics.
//!
//! Random errors of the poses are independent of where the robot is: after the fit, the per-pose
//! disagreement D_i = Y⁻¹ Y_i ([`PoseResiduals`]) of two poses close in configuration is no more
//! alike than that of two poses far apart. A systematic error is a smooth function of the
//! configuration, D_i ≈ g(q_i): neighbours share it. The test:
//!
//! 1. the poses are put in a *neighbour order* of their configuration: a k-d split of the joint
//!    angles (when given) or of the hand pose (position over its spread, rotation vector about the
//!    mean rotation, radians), the widest coordinate split at its median, recursively, the leaves
//!    read in order (O(n log n)); consecutive poses of that order are neighbours, and contiguous
//!    runs of it are regions of the workspace (the k-d cells);
//! 2. along that order, the von Neumann ratio (Durbin–Watson) of the residuals, rotation and
//!    translation each: S = Σ‖D_{o(k+1)} − D_{o(k)}‖² / (2 Σ‖D_i − D̄‖²), ≈ 1 for independent
//!    residuals, ≪ 1 when neighbours share theirs;
//! 3. its null distribution by permutation: the same ratio over [`PERMUTATIONS`] random orders
//!    (exchangeable residuals are what "random" means here), its mean and spread give a z-score
//!    (the ratio is a sum of n − 1 terms, normal to a good approximation from 20 poses); the
//!    smaller of the two blocks' one-sided p-values, doubled (Bonferroni), is the p-value.
//!    O(n · PERMUTATIONS).
//!
//! The residuals are winsorised at `WINSOR` times their median size first, so a few gross
//! outliers (their own check) neither make nor hide the pattern. What the error does to X is
//! measured by the halves of the workspace (the first k-d split): each half solves X on its own
//! and their disagreement is the error's size.

use nalgebra::{DMatrix, Vector3};
use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_xoshiro::Xoshiro256PlusPlus;
use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, Normal};

use crate::check::identification::{KinematicFit, Station, kinematic_fit};
use crate::check::outliers::{PoseResiduals, median};
use crate::check::uncertainty::{Uncertainty, bootstrap_by_region, per_station, stations_of};
use crate::model::error::Result;
use crate::model::kinematics::Kinematics;
use crate::model::motion::{PosePair, Setup};
use crate::model::pose::rotation_angle_between;
use crate::model::pose::{Transform, log_so3};
use crate::model::station::Stations;
use crate::model::warning::Warning;
use crate::solve::residual::PoseResidual;

/// Random orders drawn for the null distribution of the neighbour ratio.
pub const PERMUTATIONS: usize = 200;

/// A p-value below this flags a systematic error.
pub const P_FLAG: f64 = 0.01;

/// The test needs at least this many poses.
pub const MIN_POSES: usize = 12;

/// Residuals larger than this times the median size are clipped to it.
const WINSOR: f64 = 4.0;

/// The permutations' seed: results are reproducible run to run.
const SEED: u64 = 0x5157_E3A7_1C00;

/// What the test found (the report's `systematic`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Systematic {
    /// Whether the residuals follow the configuration (p-value below the threshold).
    pub flagged: bool,
    /// The von Neumann ratio of the rotation residuals along the neighbour order (≈ 1 random).
    pub rotation_ratio: f64,
    /// The same for the translation residuals.
    pub translation_ratio: f64,
    /// The share of the rotation residuals' variance a linear function of the configuration
    /// explains (≈ features / poses for random residuals).
    pub rotation_explained: f64,
    /// The same for the translation residuals.
    pub translation_explained: f64,
    /// The smaller of the two z-scores against the permutation null.
    pub z: f64,
    /// Its one-sided p-value, times four for the two blocks and the two statistics (Bonferroni).
    pub p_value: f64,
    /// The threshold the p-value was judged by.
    pub threshold: f64,
    /// Robot poses tested: the stations (`model::station`), images at one robot pose counted
    /// once.
    pub poses: usize,
    /// Random orders of the null.
    pub permutations: usize,
    /// What the neighbours were found in: `joints` or `hand_pose`.
    pub configuration: String,
    /// A dense stream's poses, which the test took as `poses` stretches of the robot's motion
    /// (`check::systematic::test_stations`); absent for a recording of stations.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stream_poses: Option<usize>,
    /// The two halves of the workspace solved apart, where both determine X.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub halves: Option<Halves>,
    /// The joint whose angle the residual follows most, where joint angles are given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint: Option<JointFollow>,
    /// The residuals along the robot's DH table's directions (`check::identification`), where the
    /// table and the joint angles are given: a fifth statistic, the Bonferroni factor then five.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kinematic: Option<KinematicFit>,
    /// The neighbour order (indices into the poses tested); not serialised.
    #[serde(skip)]
    pub order: Vec<usize>,
    /// Where the first k-d split falls in `order`: the first half of the workspace is
    /// `order[..split]`, half of the stations (not of the poses: a station can hold many poses, a
    /// dense stream's stretch hundreds); not serialised.
    #[serde(skip)]
    pub split: usize,
    /// Whether the halves of the workspace disagree about X beyond what the noise allows
    /// ([`Systematic::weigh`]); a test that finds a pattern of no weight on X is not flagged.
    #[serde(default = "material_default")]
    pub material: bool,
    /// An online test below the threshold that is not yet a finding: a flag of a test before the
    /// end of a stream counts once the next test, on the larger sample, flags too
    /// (`track::systematic`); the batch never sets it.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub unconfirmed: bool,
}

fn material_default() -> bool {
    true
}

/// The least disagreement of the halves of the workspace that weighs on X, degrees and a
/// fraction of the scene: below, the pattern is rounding (exact data) and no caution is due.
/// (A bound in the whole's one-sigma was tried: the halves of a workspace split in space are far
/// worse conditioned than random halves, and it left 75% of the 1–2 mm DH errors unflagged.)
pub const MATERIAL_ROTATION_DEG: f64 = 1e-6;
/// See [`MATERIAL_ROTATION_DEG`].
pub const MATERIAL_TRANSLATION_REL: f64 = 1e-9;

impl Systematic {
    /// Adds the DH table's statistic: the smallest of five z-scores, its p-value times five
    /// (`bonferroni`).
    pub fn with_kinematic(&mut self, fit: KinematicFit) {
        self.kinematic = Some(fit);
        self.z = self.z.min(fit.z);
        self.p_value = bonferroni(self.z, STATISTICS + 1);
        self.flagged = self.p_value < self.threshold;
    }

    /// Keeps the flag only where the halves of the workspace disagree about X by more than
    /// rounding ([`MATERIAL_ROTATION_DEG`], [`MATERIAL_TRANSLATION_REL`] of `scene`): a pattern in
    /// the residuals of exact data is the rounding of the printed digits, of no weight on X.
    /// Without the halves (one of them does not determine X) the flag stands.
    pub fn weigh(&mut self, scene: f64) {
        if let Some(h) = self.halves {
            self.material = h.rotation_deg > MATERIAL_ROTATION_DEG
                || h.translation > MATERIAL_TRANSLATION_REL * scene;
            self.flagged &= self.material;
        }
    }
}

/// X from the two halves of the workspace, each solved alone.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Halves {
    /// Angle between the halves' rotations of X, degrees.
    pub rotation_deg: f64,
    /// Distance between the halves' translations of X, input units.
    pub translation: f64,
}

/// The joint whose angle orders the residual best.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct JointFollow {
    /// The joint, 1-based in the robot's joint order.
    pub joint: usize,
    /// The von Neumann ratio of the residuals (rotation and translation standardised, summed)
    /// along that joint's angle alone (≈ 1 when the residual does not follow it).
    pub ratio: f64,
}

/// The configuration of each pose, flat: `dim` numbers per pose.
#[derive(Debug, Clone, PartialEq)]
pub struct Configurations {
    /// The numbers, pose after pose.
    pub values: Vec<f64>,
    /// Numbers per pose.
    pub dim: usize,
    /// `joints` or `hand_pose`.
    pub kind: &'static str,
}

impl Configurations {
    /// The joint angles of each pose (radians), when every pose has the same number of them.
    pub fn of_joints(joints: &[Vec<f64>]) -> Option<Self> {
        let dim = joints.first()?.len();
        if dim == 0 || joints.iter().any(|q| q.len() != dim) {
            return None;
        }
        Some(Self {
            values: joints.iter().flatten().copied().collect(),
            dim,
            kind: "joints",
        })
    }

    /// The hand pose of each pose: position over its RMS spread, and the rotation vector of the
    /// rotation relative to the first pose's, radians.
    pub fn of_hand_poses(poses: &[PosePair]) -> Self {
        let centre = hand_centre(poses);
        let spread = hand_spread(poses);
        let reference = poses
            .first()
            .map(|p| *p.base_from_gripper.rotation.matrix())
            .unwrap_or_else(nalgebra::Matrix3::identity);
        let mut values = Vec::with_capacity(6 * poses.len());
        for p in poses {
            let t = (p.base_from_gripper.translation.vector - centre) / spread;
            let r = log_so3(&(reference.transpose() * p.base_from_gripper.rotation.matrix()));
            values.extend_from_slice(&[t.x, t.y, t.z, r.x, r.y, r.z]);
        }
        Self {
            values,
            dim: 6,
            kind: "hand_pose",
        }
    }

    fn at(&self, i: usize, k: usize) -> f64 {
        self.values[i * self.dim + k]
    }
}

/// The neighbour order of the configurations: a k-d split (widest coordinate at its median,
/// recursively), the leaves read in order. O(n log n).
pub fn neighbour_order(c: &Configurations) -> Vec<usize> {
    let n = c.values.len() / c.dim.max(1);
    let mut order: Vec<usize> = (0..n).collect();
    split(c, &mut order);
    order
}

fn split(c: &Configurations, idx: &mut [usize]) {
    if idx.len() <= 2 {
        return;
    }
    let widest = (0..c.dim)
        .map(|k| {
            let (lo, hi) = idx
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &i| {
                    (lo.min(c.at(i, k)), hi.max(c.at(i, k)))
                });
            (k, hi - lo)
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(0, |(k, _)| k);
    let mid = idx.len() / 2;
    idx.select_nth_unstable_by(mid, |&a, &b| c.at(a, widest).total_cmp(&c.at(b, widest)));
    let (lower, upper) = idx.split_at_mut(mid);
    split(c, lower);
    split(c, upper);
}

/// The von Neumann ratio of `v` along `order`: Σ‖v_{o(k+1)} − v_{o(k)}‖² / (2 Σ‖v_i − v̄‖²).
pub fn neighbour_ratio(v: &[Vector3<f64>], order: &[usize]) -> f64 {
    let n = v.len().max(1) as f64;
    let mean: Vector3<f64> = v.iter().sum::<Vector3<f64>>() / n;
    let total: f64 = v.iter().map(|x| (x - mean).norm_squared()).sum();
    if total <= 0.0 {
        return 1.0;
    }
    let steps: f64 = order
        .windows(2)
        .map(|w| (v[w[1]] - v[w[0]]).norm_squared())
        .sum();
    steps / (2.0 * total)
}

/// The statistics of [`test`]: the neighbour ratio and the explained share, each of the
/// rotation and of the translation.
const STATISTICS: usize = 4;

/// The p-value of the smallest of `statistics` z-scores (each standard normal under the null):
/// Bonferroni's, `statistics` · Φ(z), at most 1.
fn bonferroni(z: f64, statistics: usize) -> f64 {
    (statistics as f64 * Normal::standard().cdf(z)).min(1.0)
}

/// The z-score of the ratio along `order` against the ratios along random orders.
fn z_score(v: &[Vector3<f64>], order: &[usize], rng: &mut Xoshiro256PlusPlus) -> (f64, f64) {
    permutation_z(order, rng, |o| neighbour_ratio(v, o))
}

/// `statistic` at `order`, and its z-score against the statistic at [`PERMUTATIONS`] random
/// shuffles of it (positive above the shuffles' mean): the null of every statistic of the test.
pub(crate) fn permutation_z(
    order: &[usize],
    rng: &mut Xoshiro256PlusPlus,
    statistic: impl Fn(&[usize]) -> f64,
) -> (f64, f64) {
    let observed = statistic(order);
    let mut shuffled = order.to_vec();
    let null: Vec<f64> = (0..PERMUTATIONS)
        .map(|_| {
            shuffled.shuffle(rng);
            statistic(&shuffled)
        })
        .collect();
    let m = null.iter().sum::<f64>() / null.len() as f64;
    let sd = (null.iter().map(|r| (r - m).powi(2)).sum::<f64>() / (null.len() - 1) as f64).sqrt();
    (observed, if sd > 0.0 { (observed - m) / sd } else { 0.0 })
}

/// The share of the residuals' variance a linear function of the configuration explains,
/// R² = ‖H v‖² / ‖v − v̄‖² summed over the three components (H the hat matrix of the features
/// with an intercept), and its z-score against the same share for permuted residuals.
fn explained_z(
    v: &[Vector3<f64>],
    features: &DMatrix<f64>,
    rng: &mut Xoshiro256PlusPlus,
) -> (f64, f64) {
    let n = v.len();
    let gram = features.transpose() * features;
    let Some(inverse) = gram.try_inverse() else {
        return (0.0, 0.0);
    };
    let mean: Vector3<f64> = v.iter().sum::<Vector3<f64>>() / n as f64;
    let total: f64 = v.iter().map(|x| (x - mean).norm_squared()).sum();
    if total <= 0.0 {
        return (0.0, 0.0);
    }
    let dim = features.ncols();
    // One pass over the poses per order: b = Fᵀ (v_perm − v̄), a (features × 3) matrix, and the
    // explained share Σ_c b_cᵀ (FᵀF)⁻¹ b_c.
    let share = |perm: &[usize]| {
        let mut b = DMatrix::<f64>::zeros(dim, 3);
        for (i, &j) in perm.iter().enumerate() {
            let d = v[j] - mean;
            for k in 0..dim {
                let f = features[(i, k)];
                b[(k, 0)] += f * d.x;
                b[(k, 1)] += f * d.y;
                b[(k, 2)] += f * d.z;
            }
        }
        (b.transpose() * &inverse * &b).trace() / total
    };
    let identity: Vec<usize> = (0..n).collect();
    // Large R² is the finding: the sign is turned so that, as for the neighbour ratio, a
    // systematic error gives a negative z.
    let (r2, z) = permutation_z(&identity, rng, share);
    (r2, 0.0 - z) // 0 − z: a z of 0 stays +0
}

/// A coordinate whose spread is below this (relative to its size plus one: radians, or the
/// hand pose's normalised units) never changes: the rounding of a mean of equal numbers.
const STILL: f64 = 1e-9;

/// The features of the linear model: an intercept and the configuration, each coordinate
/// centred and scaled to unit spread. A coordinate that never changes (a gripper's joint, a joint
/// the poses never turn) is left out: its column would make the model singular and silence the
/// test.
fn features(c: &Configurations, n: usize) -> DMatrix<f64> {
    let moving: Vec<(usize, f64, f64)> = (0..c.dim)
        .filter_map(|k| {
            let mean = (0..n).map(|i| c.at(i, k)).sum::<f64>() / n as f64;
            let sd = ((0..n).map(|i| (c.at(i, k) - mean).powi(2)).sum::<f64>() / n as f64).sqrt();
            (sd > STILL * (1.0 + mean.abs())).then_some((k, mean, sd))
        })
        .collect();
    let mut f = DMatrix::from_element(n, moving.len() + 1, 1.0);
    for (column, &(k, mean, sd)) in moving.iter().enumerate() {
        for i in 0..n {
            f[(i, column + 1)] = (c.at(i, k) - mean) / sd;
        }
    }
    f
}

/// Each residual vector clipped to [`WINSOR`] times the median size.
fn winsorised(v: impl Iterator<Item = Vector3<f64>>) -> Vec<Vector3<f64>> {
    let v: Vec<Vector3<f64>> = v.collect();
    let limit = WINSOR * median(v.iter().map(|x| x.norm()).collect());
    v.into_iter()
        .map(|x| {
            let s = x.norm();
            if s > limit && s > 0.0 {
                x * (limit / s)
            } else {
                x
            }
        })
        .collect()
}

/// The rotation and translation residuals of the poses, winsorised.
fn parts(residuals: &[PoseResidual]) -> [Vec<Vector3<f64>>; 2] {
    [
        winsorised(residuals.iter().map(|r| r.rotation)),
        winsorised(residuals.iter().map(|r| r.translation)),
    ]
}

/// Tests whether `residuals` (one per pose) follow `configurations` (same poses, same order).
/// `None` with fewer than [`MIN_POSES`] poses.
pub fn test(residuals: &[PoseResidual], configurations: &Configurations) -> Option<Systematic> {
    let n = residuals.len();
    if n < MIN_POSES || configurations.values.len() != n * configurations.dim {
        return None;
    }
    let order = neighbour_order(configurations);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(SEED);
    let [rot, trans] = parts(residuals);
    let (rotation_ratio, z_rot) = z_score(&rot, &order, &mut rng);
    let (translation_ratio, z_trans) = z_score(&trans, &order, &mut rng);
    let f = features(configurations, n);
    let (rotation_explained, x_rot) = explained_z(&rot, &f, &mut rng);
    let (translation_explained, x_trans) = explained_z(&trans, &f, &mut rng);
    let z = z_rot.min(z_trans).min(x_rot).min(x_trans);
    let p_value = bonferroni(z, STATISTICS);
    Some(Systematic {
        flagged: p_value < P_FLAG,
        material: true,
        unconfirmed: false,
        rotation_ratio,
        translation_ratio,
        rotation_explained,
        translation_explained,
        z,
        p_value,
        threshold: P_FLAG,
        poses: n,
        permutations: PERMUTATIONS,
        configuration: configurations.kind.into(),
        stream_poses: None,
        halves: None,
        joint: (configurations.kind == "joints")
            .then(|| joint_followed(&rot, &trans, configurations))
            .flatten(),
        kinematic: None,
        split: order.len() / 2,
        order,
    })
}

/// The joint along whose angle alone the residuals are most alike between neighbours.
fn joint_followed(
    rot: &[Vector3<f64>],
    trans: &[Vector3<f64>],
    c: &Configurations,
) -> Option<JointFollow> {
    let n = rot.len();
    // A joint that never turns orders nothing (the poses' own order would stand in for it).
    (0..c.dim)
        .filter(|&k| {
            let (lo, hi) = (0..n).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), i| {
                (lo.min(c.at(i, k)), hi.max(c.at(i, k)))
            });
            hi - lo > STILL * (1.0 + lo.abs())
        })
        .map(|k| {
            let mut order: Vec<usize> = (0..n).collect();
            order.sort_by(|&a, &b| c.at(a, k).total_cmp(&c.at(b, k)));
            let ratio = 0.5 * (neighbour_ratio(rot, &order) + neighbour_ratio(trans, &order));
            JointFollow {
                joint: k + 1,
                ratio,
            }
        })
        .min_by(|a, b| a.ratio.total_cmp(&b.ratio))
}

/// The poses of each half of the workspace: `order` (the neighbour order) split at `mid`
/// ([`Systematic::split`]).
pub fn halves(poses: &[PosePair], (order, mid): (&[usize], usize)) -> [Vec<PosePair>; 2] {
    let mid = mid.min(order.len());
    [
        order[..mid].iter().map(|&i| poses[i]).collect(),
        order[mid..].iter().map(|&i| poses[i]).collect(),
    ]
}

/// How far apart the halves' X are, when `solve` determines X from each.
pub fn halves_disagree(
    poses: &[PosePair],
    split: (&[usize], usize),
    solve: &dyn Fn(&[PosePair]) -> crate::model::error::Result<Transform>,
) -> Option<Halves> {
    let [a, b] = halves(poses, split);
    let (xa, xb) = (solve(&a).ok()?, solve(&b).ok()?);
    let r = log_so3(&(xa.rotation.matrix() * xb.rotation.matrix().transpose()));
    Some(Halves {
        rotation_deg: r.norm().to_degrees(),
        translation: (xa.translation.vector - xb.translation.vector).norm(),
    })
}

/// Bootstrap replicates [`halves_determine`] draws for each half: enough for a verdict.
const HALF_REPLICATES: usize = 64;

/// Whether each half of the workspace determines X on its own: its X solved by `solve` and its
/// bootstrap's verdict not undetermined (`scene` as for the whole). A half that leaves a
/// direction free gives an X anywhere along it, and its distance to the other half's X is no
/// measure of a systematic error: a real 15-image circle-grid recording's 7-pose half put it at
/// 51° and 1.4 km, and the whole's uncertainty was widened to that.
pub fn halves_determine(
    poses: &[PosePair],
    setup: Setup,
    split: (&[usize], usize),
    solve: &(dyn Fn(&[PosePair]) -> crate::model::error::Result<Transform> + Sync),
    scene: f64,
) -> bool {
    halves(poses, split).iter().all(|half| {
        solve(half).is_ok_and(|x| {
            let u = crate::check::uncertainty::bootstrap(
                half,
                setup,
                &x,
                solve,
                HALF_REPLICATES,
                scene,
            );
            u.verdict() != crate::model::findings::Verdict::Undetermined
        })
    })
}

/// The test on the poses under `x`, with the halves' disagreement measured by `solve`.
pub fn systematic_error(
    poses: &[PosePair],
    setup: Setup,
    x: &Transform,
    (joints, model, scene): (Option<&[Vec<f64>]>, Option<&Kinematics>, f64),
    solve: &dyn Fn(&[PosePair]) -> crate::model::error::Result<Transform>,
) -> std::result::Result<Systematic, Untested> {
    // Images at one robot pose share its error: the test is on the stations, each its first
    // pose's configuration and its poses' mean residual (repeats of a pose are neighbours alike
    // by their shared random error, and would look like a pattern). A dense stream's stations are
    // its stretches ([`test_stations`]).
    let (stations, stream) = test_stations(poses);
    let first = stations.first_poses();
    let representatives: Vec<PosePair> = first.iter().map(|&i| poses[i]).collect();
    let residuals = PoseResiduals::at(poses, setup, x);
    let joints = joints.filter(|j| j.len() == poses.len());
    let configurations = joints
        .and_then(|j| {
            Configurations::of_joints(&first.iter().map(|&i| j[i].clone()).collect::<Vec<_>>())
        })
        .unwrap_or_else(|| Configurations::of_hand_poses(&representatives));
    // A station's residual is its poses' mean; a stretch's is its first pose's: the mean of a
    // stretch's poses would average their random errors down and leave what they share by being
    // close in time (the interpolation at the camera's stamps, a smooth path's share of the
    // camera error), which the test would take for a pattern (the repository's noisy ROS 2 bags
    // were flagged so; measured in docs/DECISIONS.md).
    let station_residuals = if stream {
        first.iter().map(|&i| residuals.residuals[i]).collect()
    } else {
        per_station(&stations, &residuals.residuals)
    };
    let too_few = Untested::TooFewStations {
        stations: stations.count,
        poses: poses.len(),
        stream,
    };
    let mut found = test(&station_residuals, &configurations).ok_or(too_few)?;
    found.stream_poses = stream.then_some(poses.len());
    if let (Some(model), Some(joints)) = (model, joints) {
        let tested: Vec<Station<'_>> = first
            .iter()
            .zip(&station_residuals)
            .map(|(&i, residual)| Station {
                pose: &poses[i],
                joints: &joints[i],
                residual,
            })
            .collect();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(SEED ^ 0x1D);
        if let Some(fit) = kinematic_fit(&tested, (setup, x, &residuals.y), model, scene, &mut rng)
        {
            found.with_kinematic(fit);
        }
    }
    // The order of the poses, each station's together: the halves and regions keep a station whole.
    found.split = stations.expand(&found.order[..found.split]).len();
    found.order = stations.expand(&found.order);
    found.halves = halves_disagree(poses, (&found.order, found.split), solve);
    Ok(found)
}

/// Why the test did not run: the report's `systematic_untested`, in these words.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Untested {
    /// Poses that disagree with the others are kept: they pull X, and the residuals of a wrong X
    /// follow the pose; the test waits for them to be left out.
    OutliersKept,
    /// Fewer stations than the test needs ([`MIN_POSES`]).
    TooFewStations {
        /// The robot stations (a dense stream's stretches) there were.
        stations: usize,
        /// The poses they came from.
        poses: usize,
        /// Whether the poses were a dense stream, thinned into stretches of the robot's motion.
        stream: bool,
    },
}

impl std::fmt::Display for Untested {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Self::OutliersKept => write!(
                f,
                "poses that disagree with the others are kept (--reject-outliers leaves them out): \
                 the residuals of the X they pull follow the pose"
            ),
            Self::TooFewStations {
                stations,
                poses,
                stream,
            } => {
                let what = if stream {
                    format!(
                        "the robot's motion over this dense stream's {poses} poses makes {stations} distinct stretches"
                    )
                } else if stations < poses {
                    format!("{poses} poses at {stations} robot stations")
                } else {
                    format!("{poses} robot stations")
                };
                write!(f, "{what}; the test needs {MIN_POSES}")
            }
        }
    }
}

/// The stations the test takes as independent, and whether the poses are a dense stream.
///
/// A recording of distinct robot poses, or of repeats of them: its robot stations
/// ([`stations_of`]). A dense stream ([`dense_stream`]): its neighbours in time share errors that
/// are not the robot's (the robot poses interpolated at the camera's stamps, a clock offset's
/// residue, a smooth trajectory's share of the camera error), which the permutation null takes
/// for a pattern; so the stream is thinned by how far the robot moves, not by its frame count,
/// into *stretches*: consecutive robot stations over which the hand stays within a step of the
/// stretch's first pose ([`hand_step`]). The step is the least, of steps √2 apart from the
/// stream's median move, whose stretches are no longer a dense stream (or are too few for the
/// test, which then does not run). Each stretch is a station: its first pose's configuration
/// and residual (not its poses' mean: [`systematic_error`]). O(n log n) per step tried.
pub(crate) fn test_stations(poses: &[PosePair]) -> (Stations, bool) {
    let stations = stations_of(poses);
    let first = stations.first_poses();
    let representatives: Vec<PosePair> = first.iter().map(|&i| poses[i]).collect();
    if !dense_motion(&representatives) {
        return (stations, false);
    }
    let spread = hand_spread(&representatives);
    let moves: Vec<f64> = representatives
        .windows(2)
        .map(|w| hand_step(&w[0], &w[1], spread))
        .collect();
    let mut step = median(moves).max(f64::MIN_POSITIVE);
    let mut stretches = stretches_of(&representatives, step, spread);
    for _ in 0..MAX_STEPS {
        if stretches.count < MIN_POSES
            || !dense_motion(&stretch_firsts(&stretches, &representatives))
        {
            break;
        }
        step *= std::f64::consts::SQRT_2;
        stretches = stretches_of(&representatives, step, spread);
    }
    let of = stations.of.iter().map(|&s| stretches.of[s]).collect();
    (
        Stations {
            of,
            count: stretches.count,
        },
        true,
    )
}

/// The steps [`test_stations`] tries at most: √2⁸⁰ = 2⁴⁰ times the median move.
const MAX_STEPS: usize = 80;

/// The RMS distance of the hand's positions from their mean (at least the least positive
/// number): the length the hand's moves are measured in.
fn hand_spread(poses: &[PosePair]) -> f64 {
    let n = poses.len().max(1) as f64;
    let centre = hand_centre(poses);
    (poses
        .iter()
        .map(|p| (p.base_from_gripper.translation.vector - centre).norm_squared())
        .sum::<f64>()
        / n)
        .sqrt()
        .max(f64::MIN_POSITIVE)
}

/// The mean of the hand's positions (the origin for no poses).
fn hand_centre(poses: &[PosePair]) -> Vector3<f64> {
    let n = poses.len().max(1) as f64;
    poses
        .iter()
        .map(|p| p.base_from_gripper.translation.vector)
        .sum::<Vector3<f64>>()
        / n
}

/// How far the hand moves from `a` to `b`: √(θ² + (d / spread)²), θ the turn (radians) and d the
/// distance, the configuration's measure of [`Configurations::of_hand_poses`].
fn hand_step(a: &PosePair, b: &PosePair, spread: f64) -> f64 {
    let (ha, hb) = (&a.base_from_gripper, &b.base_from_gripper);
    let turn = rotation_angle_between(&ha.rotation, &hb.rotation);
    let distance = (ha.translation.vector - hb.translation.vector).norm() / spread;
    turn.hypot(distance)
}

/// Consecutive poses in stretches: a pose within `step` ([`hand_step`]) of its stretch's first
/// pose joins it, else it starts the next.
fn stretches_of(poses: &[PosePair], step: f64, spread: f64) -> Stations {
    let mut of = Vec::with_capacity(poses.len());
    let mut start = 0;
    let mut count = 0;
    for (i, p) in poses.iter().enumerate() {
        if i == 0 || hand_step(&poses[start], p, spread) >= step {
            start = i;
            count += 1;
        }
        of.push(count - 1);
    }
    Stations { of, count }
}

/// The first pose of each stretch.
fn stretch_firsts(stretches: &Stations, poses: &[PosePair]) -> Vec<PosePair> {
    stretches.first_poses().iter().map(|&i| poses[i]).collect()
}

/// Whether the poses are a dense stream: consecutive poses turn the hand by less than
/// [`DENSE_SHARE`] of what pairs a fixed stride apart do, in the median. The permutation null
/// takes the poses' errors as independent, which a dense stream's neighbours are not: on the
/// repository's dense recordings (the ROS 2 bags, ethz-asl's simulation, kinhec's continuous
/// recordings) the test flagged random noise at full resolution; [`test_stations`] thins them.
///
/// Judged on the robot's stations ([`stations_of`]): images the camera takes while the robot
/// stands still are one pose of the robot, not a dense stream.
pub(crate) fn dense_stream(poses: &[PosePair]) -> bool {
    let stations = stations_of(poses);
    if stations.distinct() {
        return dense_motion(poses);
    }
    let representatives: Vec<PosePair> = stations.first_poses().iter().map(|&i| poses[i]).collect();
    dense_motion(&representatives)
}

/// [`dense_stream`] on distinct robot poses.
fn dense_motion(poses: &[PosePair]) -> bool {
    let n = poses.len();
    if n < 2 * DENSE_STRIDE {
        return false;
    }
    let turn = |i: usize, j: usize| {
        rotation_angle_between(
            &poses[i].base_from_gripper.rotation,
            &poses[j].base_from_gripper.rotation,
        )
    };
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let near = median((1..n).map(|i| turn(i - 1, i)).collect());
    let far = median(
        (DENSE_STRIDE..n)
            .map(|i| turn(i - DENSE_STRIDE, i))
            .collect(),
    );
    near < DENSE_SHARE * far
}

/// See [`dense_stream`]: the stride of the pairs compared with consecutive ones.
const DENSE_STRIDE: usize = 8;
/// See [`dense_stream`].
const DENSE_SHARE: f64 = 0.35;

/// The systematic-error test (`check::systematic`) of the poses `used` (`solved`: the poses,
/// their setup and X), with the joint angles of the poses kept (`joints` by input index, `kept`,
/// of `read_len` poses read) where the input gives every pose's. It waits while outliers are
/// kept: they pull X, and a wrong X leaves residuals that follow the pose, so their own warning
/// comes first and the test runs once they are left out.
pub(crate) fn systematic_test(
    (used, setup, x): (&[PosePair], Setup, &Transform),
    (joints, kept, read_len): (&[Vec<f64>], &[usize], usize),
    model: Option<&Kinematics>,
    outliers_kept: bool,
    solve_x: &(dyn Fn(&[PosePair]) -> Result<Transform> + Sync),
    scene: f64,
) -> std::result::Result<Systematic, Untested> {
    if outliers_kept {
        return Err(Untested::OutliersKept);
    }
    let joints: Option<Vec<Vec<f64>>> =
        (joints.len() == read_len).then(|| kept.iter().map(|&i| joints[i].clone()).collect());
    let mut found = systematic_error(used, setup, x, (joints.as_deref(), model, scene), solve_x)?;
    found.weigh(scene);
    // The halves count only where each determines X; checked where they would widen the answer.
    if found.flagged
        && found.halves.is_some()
        && !halves_determine(used, setup, (&found.order, found.split), solve_x, scene)
    {
        found.halves = None;
    }
    Ok(found)
}

/// X's uncertainty where the test `found` flags an error that follows the configuration:
/// resampled by workspace region, at least the halves' disagreement, `at_point` placed again
/// at its point; with the caution that says so. Unflagged, the uncertainty as it was.
pub(crate) fn widened_for_systematic(
    uncertainty: Uncertainty,
    found: Option<&Systematic>,
    (used, setup, x): (&[PosePair], Setup, &Transform),
    solve_x: &(dyn Fn(&[PosePair]) -> Result<Transform> + Sync),
    (replicates, scene): (usize, f64),
) -> (Uncertainty, Option<Warning>) {
    let Some(found) = found.filter(|s| s.flagged) else {
        return (uncertainty, None);
    };
    let regions = bootstrap_by_region(used, setup, x, solve_x, (replicates, scene), &found.order);
    let wide = widen_by(uncertainty, &regions, found, x, scene);
    let caution = systematic_warning(found, &wide);
    (wide, Some(caution))
}

/// The uncertainty widened by a flagged test `found`: the region bootstrap's `regions` where it
/// is the wider ([`wider`]), at least the halves' disagreement ([`covering`]), `at_point` placed
/// again at its point under `x`. The accumulating estimator applies it to each estimate after a
/// test, with the region bootstrap of that test.
pub(crate) fn widen_by(
    uncertainty: Uncertainty,
    regions: &Uncertainty,
    found: &Systematic,
    x: &Transform,
    scene: f64,
) -> Uncertainty {
    let at_point = uncertainty.at_point.clone();
    let mut wide = covering(wider(uncertainty, regions.clone()), found, scene);
    wide.at_point = at_point.map(|p| wide.place(x, p.point));
    wide
}

/// The warning of an error that follows the configuration, with its effect on X.
pub(crate) fn systematic_warning(found: &Systematic, regions: &Uncertainty) -> Warning {
    Warning::SystematicError {
        p_value: found.p_value,
        halves_rotation_deg: found.halves.map(|h| h.rotation_deg),
        halves_translation: found.halves.map(|h| h.translation),
        rotation_sigma_deg: regions.rotation_deg,
        translation_sigma: regions.translation,
        joint: found.joint.map(|j| j.joint),
        kinematic_z: found.kinematic.map(|k| k.z),
    }
}

/// An uncertainty that covers what the halves of the workspace disagree by: each half's X is off
/// by the systematic error as it weighs on that half, so half their distance is the least
/// one-sigma an honest answer reports (`check::systematic::Halves`).
pub(crate) fn covering(u: Uncertainty, found: &Systematic, scene: f64) -> Uncertainty {
    match found.halves {
        Some(h) => u.at_least(
            HALVES_SHARE * h.rotation_deg,
            HALVES_SHARE * h.translation,
            scene,
        ),
        None => u,
    }
}

/// The share of the halves' disagreement that [`covering`] takes as the least one-sigma.
const HALVES_SHARE: f64 = 1.0;

/// The region bootstrap's uncertainty where it is the wider (the sum of the two parts' ratios),
/// else the ordinary one: a systematic error never narrows what the poses' own noise gives.
pub(crate) fn wider(ordinary: Uncertainty, regions: Uncertainty) -> Uncertainty {
    let ratio = |a: f64, b: f64| if b > 0.0 { a / b } else { 1.0 };
    if ratio(regions.rotation_deg, ordinary.rotation_deg)
        + ratio(regions.translation, ordinary.translation)
        >= 2.0
    {
        regions
    } else {
        ordinary
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::RngExt;

    /// Joint angles of `n` poses on a 2-joint grid, and residuals: independent noise plus
    /// `bias` times a smooth function of the first joint.
    fn case(n: usize, bias: f64, seed: u64) -> (Vec<PoseResidual>, Configurations) {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let joints: Vec<Vec<f64>> = (0..n)
            .map(|_| vec![rng.random_range(-1.5..1.5), rng.random_range(-1.5..1.5)])
            .collect();
        let mut noise =
            || Vector3::new(rng.random::<f64>(), rng.random(), rng.random()) - Vector3::repeat(0.5);
        let residuals = joints
            .iter()
            .map(|q| {
                let smooth = Vector3::new(q[0].sin(), q[0].cos(), 0.0) * bias;
                PoseResidual {
                    rotation: noise() * 1e-3,
                    angle: 0.0,
                    translation: noise() * 1e-3 + smooth * 1e-3,
                }
            })
            .collect();
        (residuals, Configurations::of_joints(&joints).unwrap())
    }

    #[test]
    fn the_neighbour_order_is_a_permutation() {
        let (_, c) = case(1000, 0.0, 1);
        let mut order = neighbour_order(&c);
        order.sort_unstable();
        assert_eq!(order, (0..1000).collect::<Vec<_>>());
    }

    #[test]
    fn independent_residuals_are_not_flagged_and_smooth_ones_are() {
        let quiet = (0..20)
            .filter(|&s| {
                test(&case(40, 0.0, s).0, &case(40, 0.0, s).1)
                    .unwrap()
                    .flagged
            })
            .count();
        assert!(quiet <= 1, "{quiet} of 20 noise-only cases flagged");
        for seed in 0..5 {
            let (r, c) = case(40, 2.0, seed);
            let found = test(&r, &c).unwrap();
            assert!(found.flagged, "{found:?}");
            assert_eq!(found.joint.map(|j| j.joint), Some(1), "{found:?}");
        }
    }

    /// X by the accumulated all-pairs solution, as the batch's bootstrap re-solves it.
    fn all_pairs(poses: &[PosePair]) -> crate::model::error::Result<Transform> {
        let motions = crate::model::motion::motion_pairs(
            poses,
            crate::model::motion::Pairing::All,
            Setup::EyeInHand,
        );
        crate::solve::andreff(&motions).map(|c| c.x)
    }

    #[test]
    fn a_half_that_leaves_a_direction_free_does_not_determine_x() {
        use crate::sim::{LowDofConfig, SimConfig, simulate, simulate_low_dof};
        let spread = simulate(
            &SimConfig {
                poses: 24,
                ..SimConfig::default()
            },
            7,
            0,
        )
        .poses;
        let order: Vec<usize> = (0..24).collect();
        assert!(halves_determine(
            &spread,
            Setup::EyeInHand,
            (&order, 12),
            &all_pairs,
            300.0
        ));
        // A SCARA rotates about one axis only: X's translation along it is free in each half.
        let scara = simulate_low_dof(
            &LowDofConfig {
                poses: 24,
                ..LowDofConfig::default()
            },
            7,
            0,
        );
        assert!(!halves_determine(
            &scara.poses,
            Setup::EyeInHand,
            (&order, 12),
            &all_pairs,
            0.3
        ));
    }

    #[test]
    fn a_joint_that_never_turns_changes_nothing() {
        for seed in 0..5 {
            let (r, c) = case(40, 2.0, seed);
            let with_still = Configurations {
                values: c
                    .values
                    .chunks(2)
                    .flat_map(|q| [q[0], 0.04, q[1]])
                    .collect(),
                dim: 3,
                kind: "joints",
            };
            let (a, b) = (test(&r, &c).unwrap(), test(&r, &with_still).unwrap());
            assert_eq!(a.p_value, b.p_value, "{seed}");
            assert_eq!(a.rotation_explained, b.rotation_explained, "{seed}");
            assert!(b.rotation_explained > 0.0 || b.translation_explained > 0.0);
            assert_eq!(b.joint.map(|j| j.joint), Some(1), "{seed}");
        }
    }

    /// A hand on a smooth path: `n` poses over a few periods of a Lissajous curve, turning as it goes.
    fn smooth_path(n: usize) -> Vec<PosePair> {
        use nalgebra::{Rotation3, Translation3};
        (0..n)
            .map(|i| {
                let t = i as f64 / n as f64 * 2.0 * std::f64::consts::PI;
                let hand = Transform::from_parts(
                    Translation3::new(
                        0.4 * (3.0 * t).sin(),
                        0.3 * (2.0 * t).cos(),
                        0.5 + 0.1 * (5.0 * t).sin(),
                    ),
                    Rotation3::from_euler_angles(0.6 * (2.0 * t).sin(), 0.5 * (3.0 * t).cos(), t),
                );
                PosePair {
                    base_from_gripper: hand,
                    camera_from_target: Transform::identity(),
                }
            })
            .collect()
    }

    #[test]
    fn a_dense_stream_is_thinned_into_stretches_of_its_motion() {
        let poses = smooth_path(3000);
        assert!(dense_stream(&poses));
        let (stations, stream) = test_stations(&poses);
        assert!(stream);
        assert!(
            (MIN_POSES..300).contains(&stations.count),
            "{} stretches",
            stations.count
        );
        // Stretches of consecutive poses, in order; their first poses no longer a dense stream.
        assert!(
            stations
                .of
                .windows(2)
                .all(|w| w[1] == w[0] || w[1] == w[0] + 1)
        );
        let firsts: Vec<PosePair> = stations.first_poses().iter().map(|&i| poses[i]).collect();
        assert!(!dense_motion(&firsts));
        // The same path at a tenth of the frame rate is thinned to about as many stretches: the
        // robot's motion decides, not the frame count.
        let sparse = test_stations(&smooth_path(300)).0.count;
        assert!(
            sparse.abs_diff(stations.count) * 3 <= stations.count,
            "{sparse} against {}",
            stations.count
        );
    }

    #[test]
    fn a_recording_of_stations_is_tested_as_it_is() {
        let poses = crate::sim::simulate(&crate::sim::SimConfig::default(), 3, 0).poses;
        let (stations, stream) = test_stations(&poses);
        assert!(!stream);
        assert_eq!(stations.count, poses.len());
    }

    #[test]
    fn too_few_poses_are_not_tested() {
        let (r, c) = case(MIN_POSES - 1, 2.0, 0);
        assert!(test(&r, &c).is_none());
    }
}
