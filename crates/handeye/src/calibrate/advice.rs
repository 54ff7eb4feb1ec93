//! What to record next: the least determined directions of X, and the gripper motions that would
//! shrink its uncertainty most.
//!
//! From the poses so far, [`advise`] solves X (all-pairs Andreff from [`PoseAccumulator`]) and the
//! fixed frame Y, measures the data's noise as the scatter of the poses' own Y_k = H_k X C_k, and
//! takes the first-order covariance of X with each pose one measurement
//! ([`PoseAccumulator::covariance`]). A candidate next pose is the last robot pose turned by an
//! angle about an axis of the gripper frame, with the camera observation that agrees exactly with
//! (X, Y); adding it to a copy of the sums predicts the covariance after recording it, in O(1).
//! The suggestions are chosen greedily, each one assuming the earlier ones were recorded. When X
//! is not determined at all (every rotation about one axis), the first suggestion turns about the
//! axis farthest from the ones seen so far.

use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

use crate::calibrate::low_dof::Plan;
use crate::check::outliers::pose_outliers;
use crate::check::quality::OUTLIER_DEG;
use crate::check::readings::check_readings;
use crate::model::error::{Error, Result};
use crate::model::findings::{Part, Sizes, Written};
use crate::model::motion::{MotionFeatures, Pairing, PosePair, Setup};
use crate::model::pose::{Transform, exp_so3, transform_from_parts};
use crate::model::prior::{Prior, check_priors};
use crate::solve::Method;
use crate::solve::accumulate::PoseAccumulator;

/// Angles a suggestion may turn by, degrees.
const ANGLES_DEG: [f64; 3] = [15.0, 30.0, 60.0];

/// A least determined direction of X.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Weakness {
    /// `rotation` (about the axis) or `translation` (along it).
    pub kind: Part,
    /// The direction in the gripper frame (X's own frame for the translation).
    pub axis_gripper: [f64; 3],
    /// One-sigma along it: degrees for a rotation, input units for a translation.
    pub sigma: f64,
}

/// A motion to record next.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Suggestion {
    /// Axis of the gripper's rotation from its last pose, in the gripper frame.
    pub axis_gripper: [f64; 3],
    /// Angle of that rotation, degrees.
    pub angle_deg: f64,
    /// The point the turn is about: `flange` (the gripper frame's origin stays put) or `target`
    /// (the point where the target is, which then stays where the camera sees it).
    #[serde(default)]
    pub pivot: Pivot,
    /// That point in the gripper frame at the pose the turn starts from (zero for the flange).
    #[serde(default)]
    pub pivot_gripper: [f64; 3],
    /// X's uncertainty once this motion and the ones before it are recorded (`None` while X is not
    /// determined).
    pub predicted: Option<Sizes>,
}

/// The point a suggested turn is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Pivot {
    /// The gripper frame's origin stays put.
    #[default]
    Flange,
    /// The target's position stays put: eye-in-hand, the camera keeps it in view; eye-to-hand,
    /// the target on the gripper stays where the fixed camera sees it.
    Target,
}

/// The advice for a recording.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Advice {
    /// Poses it rests on.
    pub poses: usize,
    /// Poses left out as outliers (the batch's per-pose test).
    pub outliers: usize,
    /// X's uncertainty now (`None` when X is not determined at all).
    pub current: Option<Sizes>,
    /// The least determined rotation and translation directions, weakest first.
    pub weakest: Vec<Weakness>,
    /// The next motions, in the order to record them.
    pub suggestions: Vec<Suggestion>,
    /// When every motion so far rotates about one axis (a low-DOF robot, or a 6-DOF one that
    /// turned one joint): what such motions determine, the prior a low-DOF robot gives instead
    /// (`calibrate --prior`), and that it cannot make the suggested turns, in words; absent
    /// otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub low_dof: Option<String>,
    /// With a goal (`--goal`): whether X is within it now (`done`, and then no suggestion), or
    /// after which suggested motion it is predicted to be.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub goal: Option<GoalReport>,
}

/// What [`advise`] is asked for.
#[derive(Debug, Clone, PartialEq)]
pub struct AdviseOptions {
    /// How many next motions to suggest. Default 3.
    pub count: usize,
    /// Priors on components of X's translation (`--prior`).
    pub priors: Vec<Prior>,
    /// The uncertainty the user needs (`--goal`): reached, the advice says so and suggests
    /// nothing more; else it says after which suggested motion the prediction reaches it.
    pub goal: Option<Sizes>,
}

impl Default for AdviseOptions {
    fn default() -> Self {
        Self {
            count: 3,
            priors: Vec::new(),
            goal: None,
        }
    }
}

/// How the advice stands against the user's goal.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GoalReport {
    /// The goal: one-sigma rotation in degrees and translation in the input unit.
    pub goal: Sizes,
    /// X's uncertainty now is within the goal in both: record no more for it.
    pub done: bool,
    /// The number of suggested motions after which the prediction is within the goal (`None`
    /// when done, or when the suggestions do not reach it).
    pub after: Option<usize>,
}

/// The advice for `poses` (module documentation): `options.count` suggestions, from the poses
/// that agree with the others (outliers by the batch's own test are left out and counted in
/// `outliers`).
///
/// Errors with [`Error::TooFewMotions`] for fewer than two poses, and with [`Error::Misread`]
/// when the poses fit far better read another way (an inverted pose, `w, x, y, z` quaternions,
/// millimetres on one side): no advice from data read wrongly. `written` is the directions in
/// which the input wrote its poses (`io::PoseSeries::written`; [`Written::NAMED`] for poses as
/// handeye names them). `priors` (`--prior`) are measurements of components of X's translation:
/// they enter the covariance with their sigma, and on a low-DOF recording (every motion about one
/// axis) they make X determined: the advice is then for that robot, turns about its one axis.
pub fn advise(
    poses: &[PosePair],
    setup: Setup,
    written: Written,
    options: &AdviseOptions,
) -> Result<Advice> {
    check_priors(&options.priors)?;
    let priors = &crate::check::units::in_poses_unit(&options.priors, poses)?[..];
    let count = options.count;
    check_goal(options.goal)?;
    if poses.len() < 2 {
        return Err(Error::TooFewMotions {
            got: poses.len().saturating_sub(1),
            need: 2,
        });
    }
    let outliers = pose_outliers(poses, setup, OUTLIER_DEG).indices();
    let kept: Vec<PosePair> = (0..poses.len())
        .filter(|i| !outliers.contains(i))
        .map(|i| poses[i])
        .collect();
    let check = check_readings(&kept, setup, written);
    if let Some(misread) = check.misread(setup) {
        return Err(misread);
    }
    let poses = &kept[..];
    let mut acc = PoseAccumulator::new(setup);
    poses.iter().for_each(|p| acc.add(p));
    let last = poses[poses.len() - 1].base_from_gripper;
    let plan = match crate::calibrate::low_dof::plan(poses, setup, Pairing::All, priors) {
        Ok(plan) => plan,
        // A low-DOF recording without its prior: the words say which to give (below).
        Err(e) if crate::calibrate::low_dof::missing(&e).is_some() => None,
        Err(e) => return Err(e),
    };
    let (x, low_dof, candidates) = turns(plan.as_ref(), poses, setup, (&acc, &last))?;
    let Some((x, (y, noise))) = x.and_then(|x| Some((x, noise_of(&acc, &x)?))) else {
        return Ok(Advice {
            outliers: outliers.len(),
            low_dof,
            goal: options.goal.map(|goal| GoalReport {
                goal,
                done: false,
                after: None,
            }),
            ..undetermined(poses, setup, count)
        });
    };
    let model = Model {
        x,
        y,
        noise,
        priors,
    };
    let current = model.predicted(&acc);
    let weakest = current.map(|_| model.weakest(&acc)).unwrap_or_default();
    let done = options
        .goal
        .zip(current)
        .is_some_and(|(goal, now)| now.within(&goal));
    let mut suggestions = Vec::with_capacity(count);
    let mut from = last;
    for _ in 0..if done { 0 } else { count } {
        let Some((turn, next, after)) = model.best_next(&acc, setup, &from, &candidates) else {
            break;
        };
        acc.add(&next);
        suggestions.push(Suggestion {
            axis_gripper: turn.axis.into(),
            angle_deg: turn.angle_deg,
            pivot: turn.pivot,
            pivot_gripper: model.pivot_point(setup, &from, turn.pivot).into(),
            predicted: Some(after),
        });
        from = next.base_from_gripper;
    }
    let goal = options.goal.map(|goal| GoalReport {
        goal,
        done,
        after: (!done)
            .then(|| {
                suggestions
                    .iter()
                    .position(|s| s.predicted.is_some_and(|p| p.within(&goal)))
                    .map(|k| k + 1)
            })
            .flatten(),
    });
    Ok(Advice {
        poses: poses.len(),
        outliers: outliers.len(),
        current,
        weakest,
        suggestions,
        low_dof,
        goal,
    })
}

/// The turns a suggestion may take, and X to predict with: on a low-DOF recording with its prior,
/// X in the low-DOF form and turns about the robot's one axis (with the words saying so);
/// otherwise all-pairs Andreff's X (from `acc`) and turns about the candidate axes, about the
/// flange only when a low-DOF recording lacks its prior. `last` is the last robot pose.
fn turns(
    plan: Option<&Plan>,
    poses: &[PosePair],
    setup: Setup,
    (acc, last): (&PoseAccumulator, &Transform),
) -> Result<(Option<Transform>, Option<String>, Vec<Turn>)> {
    Ok(match plan {
        Some(plan) => {
            let x = crate::calibrate::low_dof::solve(
                plan,
                poses,
                setup,
                Pairing::All,
                Method::Andreff,
            )?
            .x;
            let axis = match setup {
                Setup::EyeInHand => plan.axis.hand,
                Setup::EyeToHand => last.rotation.inverse() * plan.axis.hand,
            };
            let words = format!(
                "every motion rotates about one axis (a low-DOF robot): X's {} is the prior's ({}), the motions determine the rest; the next motions turn about the robot's axis ({:.2}, {:.2}, {:.2}) in the gripper frame, the only one it turns about",
                plan.prior.component.name(),
                plan.prior,
                axis.x,
                axis.y,
                axis.z
            );
            let turns = ANGLES_DEG
                .iter()
                .flat_map(|&a| [a, -a])
                .flat_map(|angle_deg| Turn::about(axis, angle_deg, &[Pivot::Flange, Pivot::Target]))
                .collect();
            (Some(x), Some(words), turns)
        }
        None => {
            let words = low_dof_words(poses, setup);
            // A low-DOF recording without its prior leaves X's translation along the axis free,
            // and with it where the target is in the gripper frame: turns about the flange only.
            let pivots: &[Pivot] = if words.is_some() {
                &[Pivot::Flange]
            } else {
                &[Pivot::Flange, Pivot::Target]
            };
            let turns = candidate_axes()
                .into_iter()
                .flat_map(|axis| ANGLES_DEG.map(|a| (axis, a)))
                .flat_map(|(axis, angle_deg)| Turn::about(axis, angle_deg, pivots))
                .collect();
            (acc.estimate().map(|e| e.x), words, turns)
        }
    })
}

/// Refuses a goal that is not two positive finite sizes.
pub(crate) fn check_goal(goal: Option<Sizes>) -> Result<()> {
    match goal {
        Some(g)
            if !(g.rotation_deg.is_finite()
                && g.rotation_deg > 0.0
                && g.translation.is_finite()
                && g.translation > 0.0) =>
        {
            Err(Error::InvalidParameter {
                name: "goal",
                message: format!(
                    "expected a one-sigma rotation in degrees and a translation in the input's unit, both positive, found {} and {}",
                    g.rotation_deg, g.translation
                ),
            })
        }
        _ => Ok(()),
    }
}

/// What the predictions rest on: X, the fixed frame Y, the noise of the poses and the priors.
struct Model<'a> {
    x: Transform,
    y: Transform,
    noise: (f64, f64),
    priors: &'a [Prior],
}

impl Model<'_> {
    /// The covariance of X from the poses in `acc` and the priors.
    fn covariance(&self, acc: &PoseAccumulator) -> Option<nalgebra::SMatrix<f64, 6, 6>> {
        acc.covariance_given(&self.x, self.noise.0, self.noise.1, self.priors)
    }

    /// The one-sigma sizes from the covariance.
    fn predicted(&self, acc: &PoseAccumulator) -> Option<Sizes> {
        let c = self.covariance(acc)?;
        Some(Sizes {
            rotation_deg: (c[(0, 0)] + c[(1, 1)] + c[(2, 2)]).sqrt().to_degrees(),
            translation: (c[(3, 3)] + c[(4, 4)] + c[(5, 5)]).sqrt(),
        })
    }

    /// The weakest rotation and translation directions (the largest eigenvalue of each block).
    fn weakest(&self, acc: &PoseAccumulator) -> Vec<Weakness> {
        let Some(c) = self.covariance(acc) else {
            return Vec::new();
        };
        let block = |k: usize| -> Matrix3<f64> { c.fixed_view::<3, 3>(k, k).into_owned() };
        let mut out = Vec::new();
        for (kind, k) in [(Part::Rotation, 0), (Part::Translation, 3)] {
            let e = block(k).symmetric_eigen();
            let i = e.eigenvalues.imax();
            let sigma = e.eigenvalues[i].max(0.0).sqrt();
            let v: Vector3<f64> = e.eigenvectors.column(i).into_owned();
            out.push(Weakness {
                kind,
                axis_gripper: v.into(),
                sigma: match kind {
                    Part::Rotation => sigma.to_degrees(),
                    Part::Translation => sigma,
                },
            });
        }
        out
    }

    /// The point `pivot` names, in the gripper frame at `from`: the origin for the flange; the
    /// target's position (eye-in-hand: `from⁻¹ · Y`, Y = `base_from_target`; eye-to-hand: Y's own,
    /// Y = `gripper_from_target`).
    fn pivot_point(&self, setup: Setup, from: &Transform, pivot: Pivot) -> Vector3<f64> {
        match (pivot, setup) {
            (Pivot::Flange, _) => Vector3::zeros(),
            (Pivot::Target, Setup::EyeInHand) => (from.inverse() * self.y).translation.vector,
            (Pivot::Target, Setup::EyeToHand) => self.y.translation.vector,
        }
    }

    /// The candidate turn that leaves the smallest uncertainty (rotation and translation each
    /// relative to now), with the pose it makes and the prediction.
    fn best_next(
        &self,
        acc: &PoseAccumulator,
        setup: Setup,
        from: &Transform,
        candidates: &[Turn],
    ) -> Option<(Turn, PosePair, Sizes)> {
        let now = self.predicted(acc)?;
        let mut best: Option<(f64, Turn, PosePair, Sizes)> = None;
        for &turn in candidates {
            let pivot = self.pivot_point(setup, from, turn.pivot);
            // The target's place in the gripper frame comes through X: offered only when X's
            // translation is known to a tenth of that distance (not while a direction is free).
            if turn.pivot == Pivot::Target && now.translation > 0.1 * pivot.norm() {
                continue;
            }
            let moved = turned(from, &turn.axis, turn.angle_deg, &pivot);
            let next = consistent_pose(setup, &self.x, &self.y, &moved);
            let mut trial = acc.clone();
            trial.add(&next);
            let Some(p) = self.predicted(&trial) else {
                continue;
            };
            let score = p.rotation_deg / now.rotation_deg + p.translation / now.translation;
            if best.as_ref().is_none_or(|b| score < b.0) {
                best = Some((score, turn, next, p));
            }
        }
        best.map(|(_, turn, next, p)| (turn, next, p))
    }
}

/// A candidate turn of the gripper: an axis of the gripper frame, an angle, and the point it is
/// about.
#[derive(Debug, Clone, Copy)]
struct Turn {
    axis: Vector3<f64>,
    angle_deg: f64,
    pivot: Pivot,
}

impl Turn {
    /// The turns by `angle_deg` about `axis`, one about each of `pivots`.
    fn about(axis: Vector3<f64>, angle_deg: f64, pivots: &[Pivot]) -> Vec<Self> {
        pivots
            .iter()
            .map(|&pivot| Self {
                axis,
                angle_deg,
                pivot,
            })
            .collect()
    }
}

/// Y and the noise (per-axis rotation in radians, per-axis translation) of the poses under X. A
/// noise of zero (exact data) is floored, so that predictions stay finite.
fn noise_of(acc: &PoseAccumulator, x: &Transform) -> Option<(Transform, (f64, f64))> {
    let scatter = acc.residual_scatter(x)?;
    let scale = acc.scene_scale().max(acc.viewing_distance()).max(1e-12);
    let r = (scatter.rotation / 3f64.sqrt()).max(1e-6);
    let t = (scatter.translation / 3f64.sqrt()).max(1e-6 * scale);
    Some((scatter.y, (r, t)))
}

/// The advice when X is not determined: turn about the axis farthest from the rotation axes seen
/// so far (the least eigenvector of Σ θ² k kᵀ over the motions between the poses).
fn undetermined(poses: &[PosePair], setup: Setup, count: usize) -> Advice {
    let mut scatter = Matrix3::zeros();
    let step = (poses.len() / 60).max(1);
    let sample: Vec<&PosePair> = poses.iter().step_by(step).collect();
    for (i, a) in sample.iter().enumerate() {
        for b in &sample[i + 1..] {
            let m = crate::model::motion::MotionPair::between(setup, a, b);
            let f = MotionFeatures::of(&m.a);
            if let Some(k) = f.axis {
                scatter += k * k.transpose() * (f.angle * f.angle);
            }
        }
    }
    let e = scatter.symmetric_eigen();
    let order = {
        let mut idx = [0, 1, 2];
        idx.sort_by(|&a, &b| e.eigenvalues[a].total_cmp(&e.eigenvalues[b]));
        idx
    };
    let suggestions = order
        .iter()
        .take(count.min(2))
        .map(|&i| Suggestion {
            axis_gripper: e.eigenvectors.column(i).into_owned().into(),
            angle_deg: 30.0,
            pivot: Pivot::Flange,
            pivot_gripper: [0.0; 3],
            predicted: None,
        })
        .collect();
    Advice {
        poses: poses.len(),
        outliers: 0,
        current: None,
        weakest: Vec::new(),
        suggestions,
        low_dof: None,
        goal: None,
    }
}

/// The words for a low-DOF recording (every motion rotates about one axis,
/// [`crate::solve::low_dof`]): the refusal `calibrate` gives without a prior, and that advice on
/// the next rotation is for robots that can turn about other axes. `None` for other recordings.
fn low_dof_words(poses: &[PosePair], setup: Setup) -> Option<String> {
    let refusal = crate::calibrate::low_dof::plan(poses, setup, Pairing::All, &[]).err()?;
    let reason = match refusal {
        Error::Degenerate { reason, .. } => reason,
        _ => return None,
    };
    Some(format!(
        "{reason}. The next motions suggested turn about other axes: a robot that can make them determines all of X with them; a low-DOF robot cannot make them, and gives the prior instead (with it, `calibrate` solves X)"
    ))
}

/// 13 axes of the gripper frame, one of each ± pair: the 3 coordinate axes, the 6 face diagonals
/// and the 4 space diagonals.
fn candidate_axes() -> Vec<Vector3<f64>> {
    let mut out = Vec::new();
    for x in [-1.0, 0.0, 1.0] {
        for y in [-1.0, 0.0, 1.0] {
            for z in [-1.0, 0.0, 1.0] {
                let v = Vector3::new(x, y, z);
                // One of each ± pair: the first non-zero coordinate positive.
                let first = [x, y, z].into_iter().find(|c| *c != 0.0);
                if first.is_some_and(|c| c > 0.0) {
                    out.push(v.normalize());
                }
            }
        }
    }
    out
}

/// The robot pose turned by `angle_deg` about `axis` of its own (gripper) frame, through the
/// point `pivot` of that frame.
fn turned(
    base_from_gripper: &Transform,
    axis: &Vector3<f64>,
    angle_deg: f64,
    pivot: &Vector3<f64>,
) -> Transform {
    let r = exp_so3(&(axis * angle_deg.to_radians()));
    // About the point p of the gripper frame: p stays put, q ↦ p + R (q − p).
    base_from_gripper * transform_from_parts(&r, &(pivot - r * pivot))
}

/// The pose pair at `base_from_gripper` that agrees exactly with X and Y: C = X⁻¹ H⁻¹ Y.
fn consistent_pose(
    setup: Setup,
    x: &Transform,
    y: &Transform,
    base_from_gripper: &Transform,
) -> PosePair {
    let hand = setup.hand_pose(base_from_gripper);
    PosePair {
        base_from_gripper: *base_from_gripper,
        camera_from_target: x.inverse() * hand.inverse() * y,
    }
}

/// How many poses each way of moving needs to reach a target uncertainty (issue 16's closed loop):
/// the paper's random walk, turns of the same sizes about random axes, and the advice.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ClosedLoop {
    /// Series simulated.
    pub series: usize,
    /// The target: the rotation one-sigma the paper's walk reaches after `walk_poses` poses
    /// (median over the series), degrees.
    pub target_rotation_deg: f64,
    /// Poses of the walk that set the target.
    pub walk_poses: usize,
    /// Median poses needed: the paper's walk, random turns, the advice (`None` where fewer than
    /// half the series got there within `most` poses).
    pub median_poses: [Option<usize>; 3],
    /// Most poses a series may take.
    pub most: usize,
}

/// The first-order rotation one-sigma of X from `poses` (eye-in-hand, no priors): the closed
/// loop's one measure for every way of moving.
fn rotation_sigma(poses: &[PosePair]) -> Option<f64> {
    let mut acc = PoseAccumulator::new(Setup::EyeInHand);
    poses.iter().for_each(|p| acc.add(p));
    let x = acc.estimate()?.x;
    let (y, noise) = noise_of(&acc, &x)?;
    let model = Model {
        x,
        y,
        noise,
        priors: &[],
    };
    model.predicted(&acc).map(|p| p.rotation_deg)
}

/// A pose recorded with the protocol's noise: uniform 1e-3 on the rotation matrix entries
/// (projected back onto SO(3)), 1% of each translation.
fn noisy(p: &PosePair, rng: &mut rand_xoshiro::Xoshiro256PlusPlus) -> PosePair {
    use rand::RngExt;
    let mut jitter = |t: &Transform| {
        let n = Matrix3::from_fn(|_, _| rng.random_range(-1e-3..1e-3));
        let r = crate::model::pose::proj_so3(&(t.rotation.matrix() + n));
        let v = t.translation.vector;
        let d = Vector3::from_fn(|_, _| rng.random_range(-0.01..0.01)) * v.norm();
        transform_from_parts(&r, &(v + d))
    };
    PosePair {
        base_from_gripper: jitter(&p.base_from_gripper),
        camera_from_target: jitter(&p.camera_from_target),
    }
}

/// The closed loop of [`ClosedLoop`] on the paper's simulation (millimetres): every series starts
/// from the walk's first three poses; each new pose is recorded with the protocol's noise (uniform
/// 1e-3 on the rotation matrix entries, 1% of each translation), and the uncertainty is the
/// first-order one of the recorded data (the same measure for every way of moving). Calls
/// `progress` after each finished series. Run as the advice study of `experiment::run_experiment`.
pub fn closed_loop(series: usize, seed: u64, progress: impl Fn()) -> ClosedLoop {
    use crate::sim::{SimConfig, simulate};
    use rand::{RngExt, SeedableRng};
    const WALK: usize = 100;
    const MOST: usize = 300;
    const START: usize = 3;
    let sims: Vec<_> = (0..series as u64)
        .map(|s| {
            simulate(
                &SimConfig {
                    poses: MOST,
                    ..SimConfig::default()
                },
                seed,
                s,
            )
        })
        .collect();
    let mut at_walk: Vec<f64> = sims
        .iter()
        .filter_map(|sim| rotation_sigma(&sim.poses[..WALK]))
        .collect();
    at_walk.sort_by(f64::total_cmp);
    let target = at_walk.get(at_walk.len() / 2).copied().unwrap_or(f64::NAN);
    let mut needed: [Vec<usize>; 3] = [Vec::new(), Vec::new(), Vec::new()];
    for (s, sim) in sims.iter().enumerate() {
        // The paper's walk.
        let walk =
            (START..=MOST).find(|&n| rotation_sigma(&sim.poses[..n]).is_some_and(|v| v <= target));
        needed[0].push(walk.unwrap_or(usize::MAX));
        // Random turns and the advice, recorded through the true camera.
        let (x, y) = (sim.gripper_from_camera, sim.base_from_target);
        for (k, advised) in [(1, false), (2, true)] {
            let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed ^ (s as u64) << 8);
            let mut poses = sim.poses[..START].to_vec();
            let mut from = poses[START - 1].base_from_gripper;
            let mut reached = usize::MAX;
            while poses.len() < MOST {
                let (axis, angle) = if advised {
                    match advise(
                        &poses,
                        Setup::EyeInHand,
                        Written::NAMED,
                        &AdviseOptions {
                            count: 1,
                            ..AdviseOptions::default()
                        },
                    )
                    .ok()
                    .and_then(|a| a.suggestions.first().copied())
                    {
                        Some(s) => (Vector3::from(s.axis_gripper), s.angle_deg),
                        None => break,
                    }
                } else {
                    let v = Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0));
                    (
                        v.normalize(),
                        ANGLES_DEG[rng.random_range(0..ANGLES_DEG.len())],
                    )
                };
                let q = turned(&from, &axis, angle, &Vector3::zeros());
                let exact = consistent_pose(Setup::EyeInHand, &x, &y, &q);
                poses.push(noisy(&exact, &mut rng));
                from = q;
                if rotation_sigma(&poses).is_some_and(|v| v <= target) {
                    reached = poses.len();
                    break;
                }
            }
            needed[k].push(reached);
        }
        progress();
    }
    let median = |v: &mut Vec<usize>| {
        v.sort_unstable();
        v.get(v.len() / 2).copied().filter(|n| *n != usize::MAX)
    };
    let [a, b, c] = &mut needed;
    ClosedLoop {
        series,
        target_rotation_deg: target,
        walk_poses: WALK,
        median_poses: [median(a), median(b), median(c)],
        most: MOST,
    }
}
