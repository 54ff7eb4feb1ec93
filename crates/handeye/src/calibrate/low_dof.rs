//! Calibration of a low-DOF robot (a SCARA, a 4-axis arm, a gantry with one wrist joint): every
//! motion rotates about the same axis, so the motions determine X's rotation and its translation
//! across that axis ([`crate::solve::low_dof`]) and a prior (`--prior tz=…`) gives the rest.
//!
//! `plan` recognises the case from the data (every motion that rotates at least
//! [`LOW_DOF_MIN_ANGLE_DEG`](crate::solve::low_dof::LOW_DOF_MIN_ANGLE_DEG) rotates about one axis
//! within [`LOW_DOF_SPREAD_DEG`](crate::solve::low_dof::LOW_DOF_SPREAD_DEG)) and refuses it,
//! naming the prior to give, when no prior covers the free direction
//! ([`Degeneracy::LowDof`]).

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::check::uncertainty::Uncertainty;
use crate::model::error::{Degeneracy, Error, LowDofMissing, Result};
use crate::model::motion::{Pairing, PosePair, Setup, motion_pairs};
use crate::model::pose::Transform;
use crate::model::prior::{Component, Prior, PriorsUsed};
use crate::model::warning::Warning;
use crate::solve::low_dof::{
    CommonAxis, axes_surely_apart, common_axis, solve_low_dof, with_component,
};
use crate::solve::motions::{AllPairs, MotionSource};
use crate::solve::{Calibration, Method, RefineOptions, refine_unchecked};

/// A prior disagreeing with the data's value of a component they determine by more than this
/// many combined sigmas is a warning ([`Warning::PriorDisagrees`]).
pub const PRIOR_DISAGREES_SIGMAS: f64 = 3.0;

/// What a report says about a low-DOF recording (`"low_dof"` in the JSON).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LowDofReport {
    /// The common rotation axis, in X's parent frame.
    pub axis: [f64; 3],
    /// The largest angle between a motion's rotation axis and it, degrees.
    pub spread_deg: f64,
    /// The component of X's translation the motions leave free (`tx`, `ty`, `tz`), taken from the
    /// prior.
    pub free: Component,
    /// Conditioning of the translation system that fixes X's rotation about the axis and its
    /// translation across it (1 is ideal); the report's `conditioning` gives the same.
    pub conditioning: f64,
    /// The components of X taken from the prior, which the data cannot check (its sign
    /// included): `["tz"]` for a SCARA.
    pub unchecked: Vec<Component>,
    /// Which way the free component's axis points, in words (a prior is signed along it).
    pub direction: String,
}

/// A low-DOF recording with the prior that covers its free direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Plan {
    /// The motions' common axis.
    pub(crate) axis: CommonAxis,
    /// The prior on the free component.
    pub(crate) prior: Prior,
}

impl Plan {
    /// The direction along which the prior moves X's translation per unit of its value: k / k_i.
    pub(crate) fn gain(&self) -> Vector3<f64> {
        let k = self.axis.hand;
        k / k[self.prior.component.index()]
    }

    /// The common axis in X's parent frame, its largest component positive (as reports give it).
    pub(crate) fn axis(&self) -> [f64; 3] {
        upward(&self.axis.hand).into()
    }

    /// The report's `low_dof`.
    pub(crate) fn report(&self, conditioning: f64, setup: Setup) -> LowDofReport {
        LowDofReport {
            axis: self.axis(),
            spread_deg: self.axis.spread.to_degrees(),
            free: self.prior.component,
            conditioning,
            unchecked: vec![self.prior.component],
            direction: crate::model::prior::direction_words(setup, self.prior.component),
        }
    }
}

/// `Ok(None)` when the motions are not low-DOF; the plan when they are and a prior covers the
/// free direction; else the refusal that names the prior to give (or says none can be given).
pub(crate) fn plan(
    poses: &[PosePair],
    setup: Setup,
    pairing: Pairing,
    priors: &[Prior],
) -> Result<Option<Plan>> {
    // Most recordings turn about many axes: two witnesses tell it in O(n), where the common axis
    // over every pair would take the axis of each of the n(n − 1)/2 motions.
    if pairing == Pairing::All && axes_surely_apart(&AllPairs::new(poses, setup)) {
        return Ok(None);
    }
    let Some(axis) = on_motions(poses, setup, pairing, common_axis) else {
        return Ok(None);
    };
    if !axis.is_low_dof() {
        return Ok(None);
    }
    if let Some(ratio) = on_motions(poses, setup, pairing, |m| pitch_ratio(m, &axis))
        && !(1.0 / UNIT_RATIO..=UNIT_RATIO).contains(&ratio)
    {
        return Err(refusal(&axis, setup, LowDofMissing::Units { ratio }));
    }
    let Some(free) = axis.free_component() else {
        return Err(refusal(&axis, setup, LowDofMissing::NotStatable));
    };
    match priors.iter().find(|p| p.component == free) {
        Some(prior) => Ok(Some(Plan {
            axis,
            prior: *prior,
        })),
        None => Err(refusal(&axis, setup, LowDofMissing::Prior(free))),
    }
}

/// A hand pitch over camera pitch ratio beyond this (or below its inverse) is a unit mix-up: the
/// two are one length seen by both sides, equal but for noise; a mm/m mix-up makes it 1000. Not
/// 10: a single joint turning (pitches of noise and timing only, on kinhec's continuous
/// recordings) gave 0.099.
pub const UNIT_RATIO: f64 = 100.0;

/// The hand's pitches are judged only when their RMS is at least this fraction of the RMS hand
/// translation (a robot that never moves along the axis has pitches of noise only).
const LEAST_PITCH: f64 = 0.05;

/// RMS of the hand's pitches k_A · t_A over RMS of the camera's k_B · t_B, over the motions that
/// rotate (the pitch of a screw motion is the same seen from either side: t_A's component along
/// the axis is R_X's image of t_B's); `None` when the hand barely moves along the axis.
fn pitch_ratio(motions: &(impl MotionSource + ?Sized), axis: &CommonAxis) -> Option<f64> {
    let (mut hand, mut eye, mut moved) = (0.0, 0.0, 0.0);
    motions.for_each_motion(|m| {
        let ta = m.a.translation.vector;
        hand += axis.hand.dot(&ta).powi(2);
        eye += axis.eye.dot(&m.b.translation.vector).powi(2);
        moved += ta.norm_squared();
    });
    (hand > LEAST_PITCH.powi(2) * moved && eye > 0.0).then(|| (hand / eye).sqrt())
}

/// The refusal of a low-DOF recording for what it lacks.
pub(crate) fn refusal(axis: &CommonAxis, setup: Setup, missing: LowDofMissing) -> Error {
    Error::Degenerate {
        reason: Degeneracy::LowDof {
            axis: upward(&axis.hand).into(),
            spread_deg: axis.spread.to_degrees(),
            setup,
            missing,
            joints: None,
        },
        conditioning: 0.0,
    }
}

/// A low-DOF refusal with the number of joint angles the records give (which tells a 6-axis arm
/// from a SCARA); any other error as it is.
pub(crate) fn with_joints(e: Error, joints: &[Vec<f64>]) -> Error {
    match e {
        Error::Degenerate {
            reason:
                Degeneracy::LowDof {
                    axis,
                    spread_deg,
                    setup,
                    missing,
                    ..
                },
            conditioning,
        } => Error::Degenerate {
            reason: Degeneracy::LowDof {
                axis,
                spread_deg,
                setup,
                missing,
                joints: joints.first().map(Vec::len).filter(|&n| n > 0),
            },
            conditioning,
        },
        e => e,
    }
}

/// The axis pointing along its largest coordinate's positive direction (up, for a SCARA), with
/// rounding's −0 made 0: reads better, means the same.
fn upward(k: &Vector3<f64>) -> Vector3<f64> {
    let k = k * k[k.iamax()].signum();
    k.map(|v| if v == 0.0 { 0.0 } else { v })
}

/// The warnings of the quality check that describe the very case a low-DOF solve handles (every
/// axis in one direction, a weak rotation system): they would advise rotations a low-DOF robot
/// cannot make.
pub(crate) fn handled(w: &Warning) -> bool {
    matches!(
        w,
        Warning::OneAxis { .. } | Warning::WeakConditioning { .. }
    )
}

/// Runs `f` on the pairing's motions (every pair on the fly, or the consecutive ones stored).
fn on_motions<T>(
    poses: &[PosePair],
    setup: Setup,
    pairing: Pairing,
    f: impl Fn(&AllPairsOrSlice) -> T,
) -> T {
    match pairing {
        Pairing::All => f(&AllPairsOrSlice::All(Box::new(AllPairs::new(poses, setup)))),
        Pairing::Consecutive => f(&AllPairsOrSlice::Slice(motion_pairs(poses, pairing, setup))),
    }
}

/// The pairing's motions as one [`MotionSource`].
pub(crate) enum AllPairsOrSlice {
    /// Every pair, made on the fly.
    All(Box<AllPairs>),
    /// Stored motions.
    Slice(Vec<crate::model::motion::MotionPair>),
}

impl MotionSource for AllPairsOrSlice {
    fn count(&self) -> usize {
        match self {
            Self::All(a) => a.count(),
            Self::Slice(s) => s.len(),
        }
    }

    fn for_each_motion(&self, f: impl FnMut(&crate::model::motion::MotionPair)) {
        match self {
            Self::All(a) => a.for_each_motion(f),
            Self::Slice(s) => s.iter().for_each(f),
        }
    }

    fn all_pairs(&self) -> Option<&AllPairs> {
        match self {
            Self::All(a) => Some(a),
            Self::Slice(_) => None,
        }
    }
}

/// Solves X of a low-DOF recording: the linear solution ([`solve_low_dof`]) for `andreff`, that
/// refined over the same motions and put back on the prior for `refine`. Other methods cannot
/// solve such motions and are refused ([`Error::InvalidParameter`]).
pub(crate) fn solve(
    plan: &Plan,
    poses: &[PosePair],
    setup: Setup,
    pairing: Pairing,
    method: Method,
) -> Result<Calibration> {
    if !method.capabilities().low_dof {
        return Err(Error::InvalidParameter {
            name: "method",
            message: format!(
                "every motion rotates about one axis (a low-DOF robot): `{}` cannot solve such motions; use `andreff` (the default: here the low-DOF linear solution) or `refine`",
                method.name()
            ),
        });
    }
    on_motions(poses, setup, pairing, |motions| {
        let linear = solve_low_dof(
            motions,
            &plan.axis,
            (plan.prior.component, plan.prior.value),
        )
        .map_err(|e| lacking(e, plan, setup))?;
        let x = match method {
            Method::Refine => {
                let refined = refine_unchecked(
                    motions,
                    &linear.x,
                    linear.conditioning,
                    &RefineOptions::default(),
                )
                .calibration
                .x;
                better(motions, linear.x, on_prior(&refined, plan))
            }
            _ => linear.x,
        };
        Ok(Calibration {
            x,
            method,
            motions: motions.count(),
            conditioning: linear.conditioning,
            warnings: Vec::new(),
        })
    })
}

/// A bootstrap replicate: the linear solution on the replicate's own common axis (for `refine`
/// too, as all-pairs `refine` is bootstrapped by the linear `andreff`).
pub(crate) fn solve_replicate(
    plan: &Plan,
    poses: &[PosePair],
    setup: Setup,
    pairing: Pairing,
) -> Result<Transform> {
    on_motions(poses, setup, pairing, |motions| {
        let axis = common_axis(motions).ok_or(Error::Degenerate {
            reason: Degeneracy::IllConditioned,
            conditioning: 0.0,
        })?;
        solve_low_dof(motions, &axis, (plan.prior.component, plan.prior.value)).map(|s| s.x)
    })
}

/// The refined X unless the linear one fits the motions better (a refiner never returns a worse
/// fit than its start): the refinement's weights are each block's RMS at the start, which on
/// exact data is rounding, and a step along the free direction then moves X by rounding's
/// amplification. Each block's sum of squares, Σ‖R_A R_X − R_X R_B‖² and
/// Σ‖R_A t_X + t_A − R_X t_B − t_X‖², is compared relative to the linear start's.
fn better(
    motions: &(impl MotionSource + ?Sized),
    linear: Transform,
    refined: Transform,
) -> Transform {
    let blocks = |x: &Transform| {
        let (r_x, t_x) = (x.rotation.matrix(), x.translation.vector);
        let mut sums = [0.0; 2];
        motions.for_each_motion(|m| {
            let (r_a, r_b) = (m.a.rotation.matrix(), m.b.rotation.matrix());
            sums[0] += (r_a * r_x - r_x * r_b).norm_squared();
            sums[1] += (r_a * t_x + m.a.translation.vector - r_x * m.b.translation.vector - t_x)
                .norm_squared();
        });
        sums
    };
    let start = blocks(&linear);
    let end = blocks(&refined);
    let relative = |s: [f64; 2]| {
        s[0] / start[0].max(f64::MIN_POSITIVE) + s[1] / start[1].max(f64::MIN_POSITIVE)
    };
    if relative(end) < relative(start) {
        refined
    } else {
        linear
    }
}

/// X with its translation moved along the axis until the prior's component holds.
fn on_prior(x: &Transform, plan: &Plan) -> Transform {
    let t = with_component(
        &x.translation.vector,
        &plan.axis.hand,
        (plan.prior.component, plan.prior.value),
    );
    crate::model::pose::transform_from_parts(x.rotation.matrix(), &t)
}

/// A degenerate low-DOF solve blames what the motions lack, in words a low-DOF robot can follow.
fn lacking(e: Error, plan: &Plan, setup: Setup) -> Error {
    match e {
        Error::Degenerate { .. } => refusal(&plan.axis, setup, LowDofMissing::Motions),
        other => other,
    }
}

/// The component a low-DOF refusal asks a prior for, if it is that refusal.
pub(crate) fn wants_prior(e: &Error) -> Option<Component> {
    match e {
        Error::Degenerate {
            reason:
                Degeneracy::LowDof {
                    missing: LowDofMissing::Prior(c),
                    ..
                },
            ..
        } => Some(*c),
        _ => None,
    }
}

/// What a low-DOF refusal says is missing, through the refusal an untrusted X carries too; `None`
/// for every other error.
pub(crate) fn missing(e: &Error) -> Option<LowDofMissing> {
    match e {
        Error::Untrusted {
            refusal: Some(r), ..
        } => missing(r),
        Error::Degenerate {
            reason: Degeneracy::LowDof { missing, .. },
            ..
        } => Some(*missing),
        _ => None,
    }
}

/// Whether `e` refuses a low-DOF recording for what its motions lack (alone, or with what in the
/// input explains it).
pub(crate) fn lacks_motions(e: &Error) -> bool {
    missing(e) == Some(LowDofMissing::Motions)
}

/// The refusal of a low-DOF X whose data part is undetermined under the data's own noise.
pub(crate) fn undetermined(plan: &Plan, setup: Setup) -> Error {
    refusal(&plan.axis, setup, LowDofMissing::Motions)
}

/// The uncertainty with the prior's sigma along the free direction, and the report's `prior`.
pub(crate) fn with_prior(plan: &Plan, u: &Uncertainty, scene: f64) -> (Uncertainty, PriorsUsed) {
    let used = PriorsUsed::from([(plan.prior.component.name().to_string(), plan.prior.value())]);
    (u.with_prior(&plan.gain(), plan.prior.sigma, scene), used)
}

/// Priors on components the motions determine: the data's value is kept, and one that disagrees
/// by more than [`PRIOR_DISAGREES_SIGMAS`] combined sigmas is a warning.
pub(crate) fn check_determined(
    priors: &[Prior],
    used: &PriorsUsed,
    x: &Transform,
    u: &Uncertainty,
    warnings: &mut Vec<Warning>,
) {
    for p in priors
        .iter()
        .filter(|p| !used.contains_key(p.component.name()))
    {
        let i = p.component.index();
        let data = x.translation.vector[i];
        let sigma = (u.covariance[3 + i][3 + i].max(0.0) + p.sigma * p.sigma).sqrt();
        let sigmas = (data - p.value).abs() / sigma.max(f64::MIN_POSITIVE);
        if sigmas > PRIOR_DISAGREES_SIGMAS {
            warnings.push(Warning::PriorDisagrees {
                component: p.component.name().into(),
                prior: p.value,
                data,
                sigmas,
            });
        }
    }
}

/// The direction, in the target pose's reference frame (the robot base eye-in-hand, the gripper
/// eye-to-hand), along which the target's translation moves with X's along the axis: Q_i X C_i = Y
/// holds for (t_X + λ k, t_Y + λ R_Q k) at every pose alike, R_Q k being the same for every pose
/// (each hand pose turns about the axis only), so the poses leave that one combination free.
/// The mean of R_Q k over the poses, normalised.
pub(crate) fn target_axis(plan: &Plan, poses: &[PosePair], setup: Setup) -> Vector3<f64> {
    let sum: Vector3<f64> = poses
        .iter()
        .map(|p| setup.hand_pose(&p.base_from_gripper).rotation * plan.axis.hand)
        .sum();
    sum.try_normalize(f64::MIN_POSITIVE)
        .unwrap_or(plan.axis.hand)
}

/// X and the target's pose of a low-DOF robot-world recording: X as the hand–eye low-DOF solve
/// gives it over every pair of poses (its component along the axis the prior's), the target's pose
/// the one that best agrees with every pose at that X ([`crate::solve::target_given`]), its
/// coupled component thereby following from the prior. `refine` only (the default): Shah's and
/// Li's forms cannot solve such poses. The conditioning is the low-DOF translation system's.
pub(crate) fn solve_robot_world(
    plan: &Plan,
    poses: &[PosePair],
    setup: Setup,
    method: crate::solve::RobotWorldMethod,
) -> Result<(Transform, Transform, f64)> {
    if method != crate::solve::RobotWorldMethod::Refine {
        return Err(Error::InvalidParameter {
            name: "method",
            message: format!(
                "every motion rotates about one axis (a low-DOF robot): `{method}` cannot solve such poses; use `refine` (the default)"
            ),
        });
    }
    let solved = solve(plan, poses, setup, Pairing::All, Method::Refine)?;
    let target = crate::solve::target_given(poses, setup, &solved.x);
    Ok((solved.x, target, solved.conditioning))
}
