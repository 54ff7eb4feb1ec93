//! What errors, warnings and reports carry about X and the poses: how well a direction of X is
//! determined ([`Verdict`], [`Direction`], [`Part`]), how the poses may have been read
//! ([`Reading`]), and which poses disagree ([`OutlierPose`]). Plain data of the bottom layer, so
//! that the layers that raise them and the faces that word them share one type.

use nalgebra::{Quaternion, UnitQuaternion};
use serde::{Deserialize, Serialize};

use crate::model::motion::{PosePair, Setup};
use crate::model::pose::Transform;

/// How well one direction of X is determined.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Within the thresholds.
    Determined,
    /// Uncertain enough to warn.
    Weak,
    /// Not determined by the data: refused.
    Undetermined,
}

/// The least determined direction of X's rotation or translation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Direction {
    /// Unit axis in X's reference frame (the gripper for eye-in-hand, the robot base for
    /// eye-to-hand).
    pub axis: [f64; 3],
    /// One-sigma along the axis: degrees for rotation, input units for translation.
    pub sigma: f64,
    /// How well it is determined.
    pub verdict: Verdict,
}

/// A rotation and a translation size of X (an error, its one-sigma, a difference, a goal).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Sizes {
    /// Rotation, degrees.
    pub rotation_deg: f64,
    /// Translation, the recording's length unit.
    pub translation: f64,
}

/// X's uncertainty against the user's goal (`Options::goal`, `--goal`): a one-sigma rotation and
/// translation, as `advise --goal` takes it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GoalCheck {
    /// The goal: one-sigma rotation (degrees) and translation (input unit).
    pub goal: Sizes,
    /// Whether X's one-sigma uncertainty is within it in both.
    pub met: bool,
}

impl Sizes {
    /// Within `goal` in both sizes.
    pub fn within(&self, goal: &Sizes) -> bool {
        self.rotation_deg <= goal.rotation_deg && self.translation <= goal.translation
    }
}

/// Rotation or translation of X.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Part {
    /// X's rotation (about an axis).
    Rotation,
    /// X's translation (along an axis).
    Translation,
}

/// What to tell the user about a direction of X: what is (weakly or not) determined, and what to
/// record to fix it.
pub fn advice(part: Part, d: &Direction, setup: Setup) -> String {
    let frame = reference_frame(setup);
    let (name, others) = axis_names(&d.axis);
    let [x, y, z] = d.axis;
    let how = match d.verdict {
        Verdict::Determined => "determined",
        Verdict::Weak => "weakly determined",
        Verdict::Undetermined => "not determined",
    };
    match part {
        Part::Rotation => format!(
            "the rotation of X about the {frame} {name} axis ({x:.2}, {y:.2}, {z:.2}) is {how} (one-sigma {:.2}° under the data's own noise): the motions rotate mostly about this axis; add motions that rotate about the {frame} {others} axis",
            d.sigma
        ),
        Part::Translation => format!(
            "the translation of X along the {frame} {name} axis ({x:.2}, {y:.2}, {z:.2}) is {how} (one-sigma {:.3} in the input's length unit under the data's own noise): add larger rotations, rotations about the {frame} {others} axis, or more poses",
            d.sigma
        ),
    }
}

/// [`advice`] for a low-DOF robot, whose motions all turn about `common` (X's reference frame):
/// it cannot turn about another axis, so what helps is what it can record.
pub fn one_axis_advice(part: Part, d: &Direction, setup: Setup, common: &[f64; 3]) -> String {
    let frame = reference_frame(setup);
    let (name, _) = axis_names(&d.axis);
    let [x, y, z] = d.axis;
    let [kx, ky, kz] = common.map(|v| if v.abs() < 5e-4 { 0.0 } else { v });
    let (what, sigma) = match part {
        Part::Rotation => ("rotation of X about", format!("{:.2}°", d.sigma)),
        Part::Translation => (
            "translation of X along",
            format!("{:.3} in the input's length unit", d.sigma),
        ),
    };
    format!(
        "the {what} the {frame} {name} axis ({x:.2}, {y:.2}, {z:.2}) is weakly determined (one-sigma {sigma} under the data's own noise): every motion turns about one axis ({kx:.3}, {ky:.3}, {kz:.3}), as a low-DOF robot's do, so X comes from the motions' translations across that axis and their turns about it: add poses that move the gripper further across the axis and turn it through larger angles about it, or more poses"
    )
}

/// The frame X is expressed in, in words: where the undetermined axis lies.
pub(crate) fn reference_frame(setup: Setup) -> &'static str {
    match setup {
        Setup::EyeInHand => "gripper",
        Setup::EyeToHand => "robot base",
    }
}

/// The name of the coordinate axis closest to `axis` and the two others: ("z", "x or y").
fn axis_names(axis: &[f64; 3]) -> (&'static str, &'static str) {
    let i = (0..3)
        .max_by(|&a, &b| axis[a].abs().total_cmp(&axis[b].abs()))
        .unwrap_or(2);
    [("x", "y or z"), ("y", "x or z"), ("z", "x or y")][i]
}

/// One way to read the poses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Reading {
    /// As the files name them.
    AsGiven,
    /// The robot poses are `gripper_from_base` (or the setup is the other one).
    RobotInverted,
    /// The camera poses are `target_from_camera`.
    CameraInverted,
    /// Both inverted.
    BothInverted,
    /// The robot quaternions were written `w, x, y, z` into `x, y, z, w` fields.
    RobotWxyz,
    /// The camera quaternions were written `w, x, y, z`.
    CameraWxyz,
    /// Both sides' quaternions were written `w, x, y, z`.
    BothWxyz,
    /// The robot translations are millimetres (the camera's metres): divided by 1000.
    RobotMm,
    /// The camera translations are millimetres (the robot's metres): divided by 1000.
    CameraMm,
}

impl Reading {
    /// What the reading means, in words.
    pub fn meaning(self, setup: Setup) -> String {
        let other = match setup {
            Setup::EyeInHand => Setup::EyeToHand,
            Setup::EyeToHand => Setup::EyeInHand,
        };
        match self {
            Self::AsGiven => "the poses as given".into(),
            Self::RobotInverted => format!(
                "the robot poses inverted: either the file gives gripper_from_base under the name base_from_gripper, or the setup is {other}"
            ),
            Self::CameraInverted => "the camera poses inverted: the file gives target_from_camera under the name camera_from_target (or the reverse)".into(),
            Self::BothInverted => "both poses inverted: each file gives the inverse of the transform it names".into(),
            Self::RobotWxyz => "the robot quaternions in the order w, x, y, z: handeye reads x, y, z, w".into(),
            Self::CameraWxyz => "the camera quaternions in the order w, x, y, z: handeye reads x, y, z, w".into(),
            Self::BothWxyz => "all quaternions in the order w, x, y, z: handeye reads x, y, z, w".into(),
            Self::RobotMm => "the robot translations in millimetres and the camera's in metres".into(),
            Self::CameraMm => "the camera translations in millimetres and the robot's in metres".into(),
        }
    }

    /// What this reading means of poses looked up between named frames ([`Written::frames`]),
    /// whose directions are right as named: an inversion means two frame names swapped.
    pub fn meaning_in_frames(self, setup: Setup) -> String {
        let other = setup.other();
        match self {
            Self::RobotInverted => format!(
                "the robot poses inverted: either the base and gripper frame names are swapped, or the setup is {other}"
            ),
            Self::CameraInverted => {
                "the camera poses inverted: the camera and target frame names are swapped".into()
            }
            Self::BothInverted => {
                "both poses inverted: the base and gripper frame names are swapped, and so are the camera and target frame names".into()
            }
            other_reading => other_reading.meaning(setup),
        }
    }

    /// Whether this reading inverts a pose (what a swap of two frame names does).
    pub fn inverts(self) -> bool {
        matches!(
            self,
            Self::RobotInverted | Self::CameraInverted | Self::BothInverted
        )
    }

    /// The poses read this way, from an input that wrote them in the directions `written`.
    ///
    /// A quaternion-order mix-up happened to the transform as the file wrote it: on a
    /// `target_from_camera` input the order is undone on that transform, before the inversion that
    /// made it `camera_from_target` (undone after it, the fix gives a wrong rotation). The other
    /// readings commute with inversion. A side written in both directions ([`WrittenAs::Mixed`])
    /// cannot be read in the other order: see [`Reading::applies_to`].
    pub fn apply(self, poses: &[PosePair], written: Written) -> Vec<PosePair> {
        poses.iter().map(|p| self.apply_one(p, written)).collect()
    }

    /// Whether this reading can be applied to an input written as `written`: the quaternion-order
    /// readings need each side they touch written in one direction.
    pub fn applies_to(self, written: Written) -> bool {
        let mixed = |side: WrittenAs| side != WrittenAs::Mixed;
        match self {
            Self::RobotWxyz => mixed(written.robot),
            Self::CameraWxyz => mixed(written.camera),
            Self::BothWxyz => mixed(written.robot) && mixed(written.camera),
            _ => true,
        }
    }

    fn apply_one(self, p: &PosePair, written: Written) -> PosePair {
        PosePair {
            base_from_gripper: self.robot(&p.base_from_gripper, written.robot),
            camera_from_target: self.camera(&p.camera_from_target, written.camera),
        }
    }

    /// A robot pose (`base_from_gripper`) read this way, from an input that wrote it `written`.
    pub fn robot(self, t: &Transform, written: WrittenAs) -> Transform {
        match self {
            Self::RobotInverted | Self::BothInverted => t.inverse(),
            Self::RobotWxyz | Self::BothWxyz => written.undo_wxyz(t),
            Self::RobotMm => scaled(t, 1e-3),
            _ => *t,
        }
    }

    /// A camera pose (`camera_from_target`) read this way, from an input that wrote it `written`.
    pub fn camera(self, t: &Transform, written: WrittenAs) -> Transform {
        match self {
            Self::CameraInverted | Self::BothInverted => t.inverse(),
            Self::CameraWxyz | Self::BothWxyz => written.undo_wxyz(t),
            Self::CameraMm => scaled(t, 1e-3),
            _ => *t,
        }
    }
}

crate::named_enum!(Reading, "reading", "fix" {
    AsGiven => "as-given",
    RobotInverted => "robot-inverted",
    CameraInverted => "camera-inverted",
    BothInverted => "both-inverted",
    RobotWxyz => "robot-wxyz",
    CameraWxyz => "camera-wxyz",
    BothWxyz => "both-wxyz",
    RobotMm => "robot-mm",
    CameraMm => "camera-mm",
});

/// The direction in which an input wrote one side's poses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum WrittenAs {
    /// As handeye names it: `base_from_gripper`, `camera_from_target`.
    #[default]
    Named,
    /// The inverse: `gripper_from_base`, `target_from_camera` (the camera stream of `--camera`).
    Inverse,
    /// Some records one way, some the other.
    Mixed,
}

impl WrittenAs {
    /// The direction of a side written `self` in one record and `other` in another.
    pub fn and(self, other: WrittenAs) -> WrittenAs {
        if self == other {
            self
        } else {
            WrittenAs::Mixed
        }
    }

    /// `t` (in handeye's direction) with the quaternion order undone where it was written.
    fn undo_wxyz(self, t: &Transform) -> Transform {
        match self {
            WrittenAs::Inverse => wxyz(&t.inverse()).inverse(),
            WrittenAs::Named | WrittenAs::Mixed => wxyz(t),
        }
    }
}

/// The directions in which an input wrote its robot and camera poses (where a quaternion-order
/// mix-up is undone: [`Reading::apply`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash, Serialize, Deserialize)]
pub struct Written {
    /// The robot poses: `base_from_gripper` ([`WrittenAs::Named`]) or `gripper_from_base`.
    pub robot: WrittenAs,
    /// The camera poses: `camera_from_target` ([`WrittenAs::Named`]) or `target_from_camera`.
    pub camera: WrittenAs,
    /// The poses were looked up between named frames (a ROS 2 recording's tf or pose topics):
    /// their directions are as the frames name them, so a pose that fits inverted means two frame
    /// names were given the wrong way round, not a file that wrote the inverse.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub frames: bool,
}

impl Written {
    /// Both sides as handeye names them.
    pub const NAMED: Written = Written {
        robot: WrittenAs::Named,
        camera: WrittenAs::Named,
        frames: false,
    };

    /// Both sides looked up between named frames, as the frames name them.
    pub const FRAMES: Written = Written {
        frames: true,
        ..Written::NAMED
    };

    /// The directions of an input of which one part was written `self` and another `other`.
    pub fn and(self, other: Written) -> Written {
        Written {
            robot: self.robot.and(other.robot),
            camera: self.camera.and(other.camera),
            frames: self.frames && other.frames,
        }
    }
}

/// The rotation whose `x, y, z, w` fields held `w, x, y, z`: the stored quaternion
/// (x', y', z', w') = (w, x, y, z), so the meant one is (x, y, z, w) = (y', z', w', x').
pub(crate) fn wxyz(t: &Transform) -> Transform {
    let q = UnitQuaternion::from_rotation_matrix(&t.rotation);
    let (x, y, z, w) = (q.i, q.j, q.k, q.w);
    let meant = UnitQuaternion::from_quaternion(Quaternion::new(x, y, z, w));
    Transform::from_parts(t.translation, meant.to_rotation_matrix())
}

pub(crate) fn scaled(t: &Transform, s: f64) -> Transform {
    let mut out = *t;
    out.translation.vector *= s;
    out
}

/// One outlier pose of a batch report: the pose and how far its motions disagree.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OutlierPose {
    /// Index in the input.
    pub pose: usize,
    /// Its name (`file:line` from the CLI).
    pub name: String,
    /// Median |θ_A − θ_B| of its motions, degrees.
    pub angle_gap_deg: f64,
    /// Median |k_A·t_A − k_B·t_B| of its motions, input units.
    pub pitch_gap: f64,
    /// On the pixels: the frame's reprojection RMS (every detection) in the solve over every
    /// frame, pixels (the gaps above are then 0: not measured).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rms_px: Option<f64>,
}

/// The verdict on an X that a job found, the same in every face: good, or questionable while a
/// caution stands (the batch report's `warnings`, a weak online estimate; a refusal is an error,
/// not a verdict).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Assessment {
    /// No caution: X is as good as its uncertainty says.
    Good,
    /// At least one caution: read them before using X.
    Questionable,
}

impl Assessment {
    /// The verdict of a result with these cautions.
    pub fn of(warnings: &[crate::model::warning::Warning]) -> Self {
        if warnings.is_empty() {
            Self::Good
        } else {
            Self::Questionable
        }
    }
}

crate::named_enum!(Assessment, "verdict", "verdict" {
    Good => "good",
    Questionable => "questionable",
});
