//! What the OpenCV drop-ins (`calibrate_hand_eye`, `calibrate_robot_world_hand_eye`) say, in the
//! names of OpenCV's arguments: their callers have no `fix=` and, unless they pass `setup=`, no
//! setup, so the library's advice (`--fix robot-inverted`, "the file gives …") is worded again for
//! them here, each drop-in in the names of its own arguments ([`DropIn`]).

use handeye::Reading;
use handeye::{Degeneracy, Error, LowDofMissing, Setup, Warning};

/// The arguments of one OpenCV function, as its drop-in's messages name them.
#[derive(Debug, Clone, Copy)]
pub struct DropIn {
    /// The robot poses' argument (`gripper2base`: `R_gripper2base`, `t_gripper2base`).
    robot: &'static str,
    /// What OpenCV takes there, in words.
    robot_is: &'static str,
    /// The camera poses' argument.
    camera: &'static str,
    /// What OpenCV takes there, in words.
    camera_is: &'static str,
    /// Whether the drop-in takes `setup=` (robot-world's is eye-in-hand only).
    takes_setup: bool,
}

/// `cv2.calibrateHandEye`'s arguments.
pub const HAND_EYE: DropIn = DropIn {
    robot: "gripper2base",
    robot_is: "gripper2base, the gripper's pose in the robot base frame, for a camera on the \
               gripper, and base2gripper for a fixed camera",
    camera: "target2cam",
    camera_is: "target2cam, the target's pose in the camera frame, as solvePnP returns it",
    takes_setup: true,
};

/// `cv2.calibrateRobotWorldHandEye`'s arguments.
pub const ROBOT_WORLD: DropIn = DropIn {
    robot: "base2gripper",
    robot_is: "base2gripper, the robot base's pose in the gripper frame",
    camera: "world2cam",
    camera_is: "world2cam, the target's (the world's) pose in the camera frame, as solvePnP \
                returns it",
    takes_setup: false,
};

/// The drop-in's message for a library error: a misread input in OpenCV's terms, any other error
/// as the library words it. `setup` is what the caller said, if anything: without it, readings
/// that fit alike are ordered as for a camera on the gripper, and the message says so.
pub fn error(e: &Error, setup: Option<Setup>, d: DropIn) -> String {
    match e {
        Error::Misread { readings, .. } if !readings.is_empty() => {
            let mut text = misread(readings, d);
            if readings.len() > 1 && setup.is_none() {
                text.push_str(
                    "; which one is meant depends on where the camera is: pass \
                     setup=\"eye-in-hand\" or setup=\"eye-to-hand\" to have the likelier first",
                );
            }
            text
        }
        Error::Degenerate { reason, .. } => degenerate(e, reason, d),
        // What makes X untrusted, each part in the drop-in's terms (the outliers' remedy is to
        // leave them out of the arrays, or `handeye.calibrate(..., reject_outliers=True)`).
        // The order is the library's (`Warning::leads`): what one option fixes first, then "as
        // the input is:" what the motions lack, then the rest.
        Error::Untrusted { refusal, why } => format!(
            "X cannot be trusted: {}",
            handeye::model::error::untrusted_in_order(
                refusal.as_ref().map(|r| error(r, setup, d)),
                why,
                |w, _| warning(w, setup, d),
            )
        ),
        _ => e.to_string(),
    }
}

/// A refusal of the motions, its remedy in the drop-in's terms: OpenCV's arguments carry no prior
/// and no `fix`; `method=` it takes.
fn degenerate(e: &Error, reason: &Degeneracy, d: DropIn) -> String {
    let text = e.to_string();
    let before = |marker: &str| text.find(marker).map_or(text.as_str(), |i| &text[..i]);
    match reason {
        Degeneracy::LowDof {
            missing: LowDofMissing::Prior(c),
            ..
        } => format!(
            "{}; OpenCV's arguments carry no prior: call `handeye.calibrate(base_from_gripper, \
             camera_from_target, prior=\"{n}=VALUE+-SIGMA\")` with the poses as 4×4 matrices",
            before(", `--prior"),
            n = c.name()
        ),
        Degeneracy::LowDof {
            missing: LowDofMissing::Units { .. },
            ..
        } => format!(
            "{}; give t_{} and t_{} in one length unit",
            before("; if one is in millimetres"),
            d.robot,
            d.camera
        ),
        Degeneracy::MethodUndetermined { .. } => {
            format!(
                "{}; pass method=\"andreff\", or another method",
                before("; use `--method")
            )
        }
        _ => text,
    }
}

/// The drop-in's text for a warning: the sizes of X and the target in OpenCV's terms (`setup` is
/// what the caller said, if anything), any other warning as the library words it.
pub fn warning(w: &Warning, setup: Option<Setup>, d: DropIn) -> String {
    match w {
        Warning::SwappedSizes {
            x_translation,
            y_translation,
            ..
        } if d.takes_setup => swapped_sizes(*x_translation, *y_translation, setup),
        Warning::SwappedSizes { .. } => format!(
            "{w}; all four arrays are likely inverted: pass {} and {} as OpenCV defines them",
            d.robot, d.camera
        ),
        Warning::Outliers { .. } => format!(
            "{w}; X follows them: leave them out of the arrays, or call \
             `handeye.calibrate(..., reject_outliers=True)`"
        ),
        _ => w.to_string(),
    }
}

/// "the input looks misread: …" with what to pass instead, the likeliest reading first.
fn misread(readings: &[Reading], d: DropIn) -> String {
    if readings == [Reading::BothInverted] {
        // Both readings fit exactly as well: the sizes and the camera poses tell (the library's
        // `ReadingCheck::both_inverted`).
        return format!(
            "the input looks misread: all four arrays look inverted (X and the target have the \
             sizes of each other, and R_{camera}, t_{camera} put the target off the camera's \
             axis where their inverses put it in view): {}",
            reading(Reading::BothInverted, d),
            camera = d.camera
        );
    }
    let mut text = format!(
        "the input looks misread: the poses fit far better with {}",
        reading(readings[0], d)
    );
    for other in &readings[1..] {
        text.push_str(&format!("; they fit as well with {}", reading(*other, d)));
    }
    text
}

/// One reading as the mistake in OpenCV's arguments, and the remedy.
fn reading(r: Reading, d: DropIn) -> String {
    let (robot, camera) = (d.robot, d.camera);
    let reordered = "made from quaternions in the other order (w, x, y, z taken for x, y, z, w, \
                     or the reverse)";
    match r {
        Reading::AsGiven => "the arrays as given".into(),
        Reading::RobotInverted => format!(
            "the robot poses inverted: pass the inverses of R_{robot} and t_{robot} (OpenCV takes \
             {})",
            d.robot_is
        ),
        Reading::CameraInverted => format!(
            "the camera poses inverted: pass the inverses of R_{camera} and t_{camera} (OpenCV \
             takes {})",
            d.camera_is
        ),
        Reading::BothInverted => {
            "the robot and the camera poses inverted: pass the inverses of all four arrays".into()
        }
        Reading::RobotWxyz => format!(
            "the robot rotations {reordered}: make R_{robot} with the order its source uses"
        ),
        Reading::CameraWxyz => format!(
            "the camera rotations {reordered}: make R_{camera} with the order its source uses"
        ),
        Reading::BothWxyz => format!(
            "the robot and camera rotations {reordered}: make R_{robot} and R_{camera} with the \
             order their sources use"
        ),
        Reading::RobotMm => {
            format!("t_{robot} in millimetres and t_{camera} in metres: give both in one unit")
        }
        Reading::CameraMm => {
            format!("t_{camera} in millimetres and t_{robot} in metres: give both in one unit")
        }
    }
}

/// X and the target of sizes that fit one setup with all four arrays inverted, or the other
/// setup as given: which, only the caller knows.
fn swapped_sizes(x: f64, y: f64, setup: Option<Setup>) -> String {
    let swapped = "the same data fit exactly with X and the target's pose swapped";
    match setup {
        None => format!(
            "X's translation is {x:.3} long and the target pose's {y:.3}: what a fixed camera \
             gives (eye-to-hand, base2gripper passed: X is cam2base, the target rides on the \
             gripper), and what a camera on the gripper gives only with all four arrays inverted \
             ({swapped}); pass setup=\"eye-to-hand\" or setup=\"eye-in-hand\" to say which"
        ),
        Some(Setup::EyeInHand) => format!(
            "X puts the camera {x:.3} from the gripper and the target {y:.3} from the robot base, \
             the reverse of a camera on the gripper: all four arrays are likely inverted \
             ({swapped}); pass gripper2base and target2cam, or setup=\"eye-to-hand\" if the \
             camera is fixed"
        ),
        Some(Setup::EyeToHand) => format!(
            "X puts the camera {x:.3} from the robot base and the target {y:.3} from the gripper, \
             the reverse of a fixed camera: all four arrays are likely inverted ({swapped}); pass \
             base2gripper and target2cam, or setup=\"eye-in-hand\" if the camera rides on the \
             gripper"
        ),
    }
}
