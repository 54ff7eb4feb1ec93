//! Several cameras and targets in one calibration: the rig as a pose graph (SPEC sec. 10).
//!
//! # The problem
//! A rig recording gives, with each robot pose Q_i = `base_from_gripper`, observations
//! C = `camera_from_target` of any camera of any target. Each camera and each target is fixed to
//! the gripper or to the robot's base ([`Mount`]); its unknown is its pose in that frame:
//! `gripper_from_camera` / `base_from_camera` for a camera (X_c), `gripper_from_target` /
//! `base_from_target` for a target (Y_t). With B(gripper, i) = Q_i and B(base, i) = I, every
//! observation says
//!
//! **B(m_t, i)⁻¹ B(m_c, i) · X_c · C = Y_t**,
//!
//! the robot-world equation Q X C = Y ([`crate::solve::shah`]) when the camera and the target are
//! on different parts (the hand pose Q_i eye-in-hand, Q_i⁻¹ eye-to-hand), and X_c C = Y_t when
//! both ride on the same part (the observation then ties the two poses to each other, and the
//! robot's motion says nothing of either).
//!
//! Cameras and targets are the nodes of a graph, each observed (camera, target) pair an edge.
//!
//! # Identifiability first ([`graph`])
//! An edge between different parts whose robot poses rotate about at least two non-parallel axes
//! determines both its ends (the robot-world solve accepts it); any edge determines one end from
//! the other. So a connected part of the graph is determined when it holds one such edge, and
//! then every node in it is. A node in a part without one (a camera that only sees a target fixed
//! to the same part, a camera whose motions all turn about one axis, a target seen by no camera)
//! is reported as undetermined with the reason, never given a number. Conservative: several
//! degenerate edges that would determine a part only together are not tried.
//!
//! # Solve ([`joint`])
//! A linear start per determined part (Shah's robot-world closed form on its best edge, then each
//! other node from its edges to known ones, averaged over their observations), then one
//! Levenberg–Marquardt refinement over every observation of every determined part: the per-pose
//! residual of the robot-world refinement (ΔR = R_H R_X R_C − R_Y, ΔT = …, defined once in
//! `solve::robot_world`), each edge's two blocks divided by their RMS at the start. A rig of one
//! camera and one target is then exactly the robot-world refinement. Each part's uncertainty is
//! a wild bootstrap of the observations' own residuals (one random sign per robot pose, shared by
//! every observation at that pose, as the single-camera bootstrap of `check::uncertainty`).
//!
//! # Loops ([`loops`])
//! Where two cameras see one target at the same robot pose (or one camera two targets), the
//! measured relative pose of the two cameras (targets) closes a loop with the solved parts. Each
//! loop's closure error is compared with what the noise explains; a loop that does not close
//! names the part to blame: the one whose loops all fail while the others' close.

pub mod graph;
pub mod joint;
pub mod loops;

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::check::uncertainty::Uncertainty;
use crate::model::error::{Error, Result};
use crate::model::findings::Assessment;
use crate::model::pose::{Transform, TransformJson};
use crate::model::warning::Warning;

pub use loops::LoopClosure;

/// Where a camera or a target is fixed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Mount {
    /// On the gripper (the robot's flange): it moves with every robot pose.
    Gripper,
    /// On the robot's base (the world): it stays.
    Base,
}

crate::named_enum!(Mount, "mount", "mount" {
    Gripper => "gripper",
    Base => "base",
});

impl Mount {
    /// `base_from_mount` at the robot pose `base_from_gripper`: Q for the gripper, I for the base.
    pub fn base_from_mount(self, base_from_gripper: &Transform) -> Transform {
        match self {
            Mount::Gripper => *base_from_gripper,
            Mount::Base => Transform::identity(),
        }
    }
}

/// A camera or a target.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PartKind {
    /// A camera.
    Camera,
    /// A target.
    Target,
}

impl PartKind {
    /// `camera` or `target`.
    pub fn name(self) -> &'static str {
        match self {
            PartKind::Camera => "camera",
            PartKind::Target => "target",
        }
    }
}

/// One observation: at robot pose `pose`, `camera` saw `target` at `camera_from_target`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Observation {
    /// Index of the robot pose in [`RigRecording::poses`].
    pub pose: usize,
    /// The camera's name.
    pub camera: String,
    /// The target's name.
    pub target: String,
    /// What the camera saw (PnP's pose of the target).
    pub camera_from_target: Transform,
}

/// A rig recording: the robot's poses and every observation made at them.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RigRecording {
    /// The robot poses Q_i = `base_from_gripper`.
    pub poses: Vec<Transform>,
    /// A name per pose (`file:line`), for messages.
    pub names: Vec<String>,
    /// The observations, each at one pose.
    pub observations: Vec<Observation>,
}

/// The mount of every camera and target, by name (`--mount NAME=gripper|base`).
pub type Mounts = BTreeMap<String, Mount>;

/// Settings of [`calibrate_rig`]; `Default` gives the values documented on each field.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RigOptions {
    /// Bootstrap replicates behind each part's uncertainty. Default 40 (as the batch).
    pub replicates: usize,
    /// A loop does not close when its closure exceeds this many times what the noise explains.
    /// Default [`loops::LOOP_LIMIT`].
    pub loop_limit: f64,
}

impl Default for RigOptions {
    fn default() -> Self {
        Self {
            replicates: crate::check::uncertainty::REPLICATES,
            loop_limit: loops::LOOP_LIMIT,
        }
    }
}

/// One solved camera or target.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PartPose {
    /// The frame: `gripper_from_camera`, `base_from_camera`, `gripper_from_target` or
    /// `base_from_target`.
    pub frame: String,
    /// The pose, as every transform in output.
    #[serde(flatten)]
    pub transform: TransformJson,
    /// Its bootstrap one-sigma (and covariance).
    pub uncertainty: Uncertainty,
    /// Observations of it used.
    pub observations: usize,
    /// RMS of its observations' residuals at the solution: degrees and input units (the
    /// predicted against the seen `camera_from_target`).
    pub residual: Residual,
    /// The pose itself.
    #[serde(skip)]
    pub pose: Transform,
}

/// RMS residual sizes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Residual {
    /// RMS rotation angle, degrees.
    pub rotation_deg: f64,
    /// RMS translation, input units.
    pub translation: f64,
}

/// A camera or target the data cannot determine, and why.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Undetermined {
    /// Its name.
    pub name: String,
    /// `camera`, `target`, or `camera or target` for a name mounted and never observed.
    pub kind: String,
    /// Why, in words.
    pub reason: String,
}

/// The whole tree: every determined camera and target, the loops, what is undetermined.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Rig {
    /// Solved cameras by name.
    pub cameras: BTreeMap<String, PartPose>,
    /// Solved targets by name.
    pub targets: BTreeMap<String, PartPose>,
    /// Every loop's closure.
    pub loops: Vec<LoopClosure>,
    /// The cameras and targets given no number, with the reason.
    pub undetermined: Vec<Undetermined>,
}

/// The outcome of [`calibrate_rig`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RigReport {
    /// The tree.
    pub rig: Rig,
    /// Robot poses read.
    pub poses: usize,
    /// Observations used in the joint solve.
    pub observations: usize,
    /// Cautions: `undetermined` parts, loops that do not close, observations far off.
    #[serde(serialize_with = "crate::model::warning::described")]
    pub warnings: Vec<Warning>,
    /// `good`, or `questionable` while a caution stands.
    pub verdict: Assessment,
}

/// The frame name of a part's pose.
pub fn frame_name(kind: PartKind, mount: Mount) -> String {
    format!("{}_from_{}", mount.name(), kind.name())
}

/// Calibrates a rig: what the observations determine, solved jointly, each part with its
/// uncertainty, every loop's closure; the rest reported as undetermined.
///
/// Refused when a camera or target observed has no mount ([`Error::InvalidParameter`], naming
/// it), when an observation names a pose that is not there, when one camera's observations fit
/// far better read another way ([`Error::RigMisread`], naming the camera), and when nothing is
/// determined ([`Error::RigUndetermined`]).
///
/// # Example
/// ```
/// use handeye::rig::{Mount, Mounts, Observation, RigOptions, RigRecording, calibrate_rig};
/// use handeye::Transform;
/// use nalgebra::Vector3;
/// let x = Transform::new(Vector3::new(0.05, 0.0, 0.1), Vector3::new(0.1, 0.2, 0.3));
/// let base_from_target = Transform::new(Vector3::new(0.8, 0.1, 0.0), Vector3::new(0.0, 3.0, 0.2));
/// let mut recording = RigRecording::default();
/// for (i, &(a, b, c)) in [(0.1, 0.2, 0.3), (-0.4, 0.1, 0.2), (0.3, -0.5, 0.1), (0.2, 0.1, -0.6)].iter().enumerate() {
///     let q = Transform::new(Vector3::new(0.3 * a, 0.2, b), Vector3::new(a, b, c));
///     recording.poses.push(q);
///     recording.names.push(format!("pose {i}"));
///     recording.observations.push(Observation {
///         pose: i,
///         camera: "wrist".into(),
///         target: "board".into(),
///         camera_from_target: (q * x).inverse() * base_from_target,
///     });
/// }
/// let mounts = Mounts::from([("wrist".into(), Mount::Gripper), ("board".into(), Mount::Base)]);
/// let report = calibrate_rig(&recording, &mounts, &RigOptions::default())?;
/// let wrist = &report.rig.cameras["wrist"];
/// assert!((wrist.pose.to_homogeneous() - x.to_homogeneous()).norm() < 1e-9);
/// # Ok::<(), handeye::Error>(())
/// ```
pub fn calibrate_rig(
    recording: &RigRecording,
    mounts: &Mounts,
    options: &RigOptions,
) -> Result<RigReport> {
    crate::check::uncertainty::check_replicates(options.replicates)?;
    if !(options.loop_limit.is_finite() && options.loop_limit > 0.0) {
        return Err(Error::InvalidParameter {
            name: "loop_limit",
            message: format!("a positive number, got {}", options.loop_limit),
        });
    }
    let graph = graph::Graph::build(recording, mounts)?;
    graph.check_readings(recording)?;
    let solvable = graph.identify(recording);
    let mut undetermined = solvable.undetermined.clone();
    undetermined.sort_by(|a, b| a.name.cmp(&b.name));
    if solvable.determined.is_empty() {
        return Err(Error::RigUndetermined {
            parts: undetermined
                .iter()
                .map(|u| format!("{} `{}`: {}", u.kind, u.name, u.reason))
                .collect(),
        });
    }
    let solution = joint::solve(recording, &graph, &solvable, options)?;
    let closures = loops::closures(recording, &graph, &solution, options.loop_limit);
    let mut warnings: Vec<Warning> = undetermined
        .iter()
        .map(|u| Warning::Undetermined {
            part: u.name.clone(),
            kind: u.kind.clone(),
            reason: u.reason.clone(),
        })
        .collect();
    warnings.extend(loops::misfits(&closures));
    warnings.extend(joint::far_off(recording, &graph, &solution));
    let mut cameras = BTreeMap::new();
    let mut targets = BTreeMap::new();
    for (node, part) in solution.parts.iter().enumerate() {
        let Some(part) = part else { continue };
        let n = &graph.nodes[node];
        let pose = PartPose {
            frame: frame_name(n.kind, n.mount),
            transform: TransformJson::from(&part.pose),
            uncertainty: part.uncertainty.clone(),
            observations: part.observations,
            residual: part.residual,
            pose: part.pose,
        };
        match n.kind {
            PartKind::Camera => cameras.insert(n.name.clone(), pose),
            PartKind::Target => targets.insert(n.name.clone(), pose),
        };
    }
    Ok(RigReport {
        rig: Rig {
            cameras,
            targets,
            loops: closures,
            undetermined,
        },
        poses: recording.poses.len(),
        observations: solution.observations,
        verdict: Assessment::of(&warnings),
        warnings,
    })
}
