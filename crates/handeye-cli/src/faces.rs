//! The faces of a batch result besides JSON (SPEC sec. 8): a summary for a person on a terminal,
//! and what ROS users paste: a `static_transform_publisher` line and launch snippet, an
//! easy_handeye2 YAML, a URDF `<joint>`.

use std::fmt::Write as _;

use handeye::Report;
use handeye::Unit;
use handeye::{Error, Setup};

use crate::input::InputArgs;

/// One of `--output`'s faces.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Face {
    /// The JSON object (the default when stdout is not a terminal).
    Json,
    /// A summary for a person (the default on a terminal).
    Text,
    /// easy_handeye2's calibration YAML.
    Yaml,
    /// A `static_transform_publisher` line and a launch snippet.
    Ros2,
    /// A URDF `<joint>`.
    Urdf,
}

handeye::named_enum!(Face, "output", "output" {
    Json => "json",
    Text => "text",
    Yaml => "yaml",
    Ros2 => "ros2",
    Urdf => "urdf",
});

impl Face {
    /// The face named on the command line, or the default for where stdout goes.
    pub fn chosen(face: Option<Face>) -> Self {
        match face {
            Some(face) => face,
            None if std::io::IsTerminal::is_terminal(&std::io::stdout()) => Self::Text,
            None => Self::Json,
        }
    }
}

/// The tf frames X connects: `parent_from_child`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Frames {
    /// The parent frame (the gripper's for eye-in-hand, the base's for eye-to-hand).
    pub parent: String,
    /// The child frame (the camera's).
    pub child: String,
    /// The robot's base frame (easy_handeye2's `robot_base_frame`).
    pub base: String,
    /// The gripper's frame (`robot_effector_frame`).
    pub gripper: String,
    /// The target's frame (`tracking_marker_frame`).
    pub target: String,
}

/// X as the ROS faces publish it: the transform, its frame name and where it came from.
#[derive(Debug, Clone, Copy)]
pub struct Published<'a> {
    /// X.
    pub x: &'a handeye::Transform,
    /// X's frame name (`gripper_from_camera` or `base_from_camera`).
    pub frame: &'a str,
    /// The setup.
    pub setup: Setup,
    /// What made it, for the comment line (e.g. `calibrate, method andreff`).
    pub source: &'a str,
}

impl<'a> Published<'a> {
    /// A batch result.
    pub fn of(r: &'a Report, source: &'a str) -> Self {
        Self {
            x: &r.transform,
            frame: &r.frame,
            setup: r.setup,
            source,
        }
    }

    fn translation(&self) -> [f64; 3] {
        handeye::TransformJson::from(self.x).translation
    }

    /// The quaternion as the JSON gives it.
    fn quaternion_xyzw(&self) -> [f64; 4] {
        handeye::TransformJson::from(self.x).quaternion_xyzw
    }
}

/// The input's length unit as far as the first poses tell (metres or millimetres).
pub fn length_unit(poses: &[handeye::PosePair]) -> Option<Unit> {
    poses.iter().find_map(Unit::infer)
}

fn unit_name(unit: Option<Unit>) -> &'static str {
    match unit {
        Some(Unit::Metre) => "m",
        Some(Unit::Millimetre) => "mm",
        _ => "(input units)",
    }
}

/// X's roll, pitch, yaw in radians: fixed axes x, then y, then z (R = Rz(yaw) Ry(pitch) Rx(roll)),
/// as URDF's `rpy` and tf's `setRPY`.
pub fn rpy(x: &handeye::Transform) -> [f64; 3] {
    let (roll, pitch, yaw) = x.rotation.euler_angles();
    [roll, pitch, yaw]
}

/// easy_handeye2's calibration file (`parameters` and `transform`), with handeye's own fields
/// after it (`frame`, `parent_frame`, `child_frame`, and for a batch result its uncertainty and
/// residual).
pub fn yaml(p: Published<'_>, f: &Frames, batch: Option<&Report>) -> String {
    let [tx, ty, tz] = p.translation();
    let [qx, qy, qz, qw] = p.quaternion_xyzw();
    let kind = match p.setup {
        Setup::EyeInHand => "eye_in_hand",
        Setup::EyeToHand => "eye_on_base",
    };
    let mut s = format!(
        "# handeye {source}, setup {setup}; easy_handeye2's layout\n\
         parameters:\n  name: handeye\n  calibration_type: {kind}\n  robot_base_frame: {base}\n  \
         robot_effector_frame: {gripper}\n  tracking_base_frame: {camera}\n  \
         tracking_marker_frame: {target}\n  freehand_robot_movement: true\n\
         transform:\n  translation: {{x: {tx}, y: {ty}, z: {tz}}}\n  \
         rotation: {{x: {qx}, y: {qy}, z: {qz}, w: {qw}}}\n\
         frame: {frame}\nparent_frame: {parent}\nchild_frame: {camera}\n\
         translation: {{x: {tx}, y: {ty}, z: {tz}}}\nrotation: {{x: {qx}, y: {qy}, z: {qz}, w: {qw}}}\n",
        source = p.source,
        setup = p.setup.name(),
        base = f.base,
        gripper = f.gripper,
        camera = f.child,
        target = f.target,
        parent = f.parent,
        frame = p.frame,
    );
    if let Some(r) = batch {
        let _ = write!(
            s,
            "uncertainty: {{rotation_deg: {}, translation: {}}}\n\
             residual: {{rotation_deg_rms: {}, translation_rms: {}}}\nmotions: {}\n",
            r.uncertainty.rotation_deg,
            r.uncertainty.translation,
            r.residual.rotation_deg_rms,
            r.residual.translation_rms,
            r.motions,
        );
    }
    s
}

/// The `ros2 run tf2_ros static_transform_publisher` command that puts X in the tf tree.
pub fn static_transform_publisher(p: Published<'_>, f: &Frames) -> String {
    let [x, y, z] = p.translation();
    let [qx, qy, qz, qw] = p.quaternion_xyzw();
    format!(
        "ros2 run tf2_ros static_transform_publisher --x {x} --y {y} --z {z} --qx {qx} --qy {qy} --qz {qz} --qw {qw} --frame-id {} --child-frame-id {}",
        f.parent, f.child
    )
}

/// The command line and a Python launch snippet publishing X.
pub fn ros2(p: Published<'_>, f: &Frames) -> String {
    let [x, y, z] = p.translation();
    let [qx, qy, qz, qw] = p.quaternion_xyzw();
    format!(
        "# handeye {source}: {frame} ({parent} -> {child})\n\
         {line}\n\
         \n\
         # In a launch file (Python):\n\
         from launch_ros.actions import Node\n\
         \n\
         handeye_tf = Node(\n    package=\"tf2_ros\",\n    executable=\"static_transform_publisher\",\n    \
         name=\"handeye_{parent}_to_{child}\",\n    arguments=[\n        \
         \"--x\", \"{x}\", \"--y\", \"{y}\", \"--z\", \"{z}\",\n        \
         \"--qx\", \"{qx}\", \"--qy\", \"{qy}\", \"--qz\", \"{qz}\", \"--qw\", \"{qw}\",\n        \
         \"--frame-id\", \"{parent}\", \"--child-frame-id\", \"{child}\",\n    ],\n)\n",
        frame = p.frame,
        parent = f.parent,
        child = f.child,
        source = p.source,
        line = static_transform_publisher(p, f),
    )
}

/// A URDF fixed `<joint>` from the parent to the child link.
pub fn urdf(p: Published<'_>, f: &Frames) -> String {
    let [x, y, z] = p.translation();
    let [roll, pitch, yaw] = rpy(p.x);
    format!(
        "<!-- handeye {source}: {frame} -->\n\
         <joint name=\"{parent}_to_{child}\" type=\"fixed\">\n  \
         <parent link=\"{parent}\"/>\n  <child link=\"{child}\"/>\n  \
         <origin xyz=\"{x} {y} {z}\" rpy=\"{roll} {pitch} {yaw}\"/>\n</joint>\n",
        frame = p.frame,
        source = p.source,
        parent = f.parent,
        child = f.child,
    )
}

/// The summary for a person: X, the verdict and its reasons, the uncertainty, the residuals, and
/// what to do next.
pub fn text(r: &Report, f: &Frames, unit: Option<Unit>) -> String {
    let u = unit_name(unit);
    let mut s = String::new();
    let [tx, ty, tz] = r.x.translation;
    let [qx, qy, qz, qw] = r.x.quaternion_xyzw;
    let [roll, pitch, yaw] = rpy(&r.transform).map(f64::to_degrees);
    let _ = writeln!(
        s,
        "X = {} ({} -> {}), {} on {} motions of {} poses ({})",
        r.frame,
        f.parent,
        f.child,
        r.method,
        r.motions,
        r.poses,
        r.setup.name()
    );
    let mm = if unit == Some(Unit::Metre) {
        format!("  = [{:.2}, {:.2}, {:.2}] mm", tx * 1e3, ty * 1e3, tz * 1e3)
    } else {
        String::new()
    };
    let _ = writeln!(s, "  translation  [{tx:.6}, {ty:.6}, {tz:.6}] {u}{mm}");
    let _ = writeln!(
        s,
        "  rotation     roll {roll:.4}°, pitch {pitch:.4}°, yaw {yaw:.4}° (fixed axes x, y, z, as URDF)"
    );
    let _ = writeln!(
        s,
        "  quaternion   x {qx:.8}, y {qy:.8}, z {qz:.8}, w {qw:.8}"
    );
    let verdict = if r.warnings.is_empty() {
        "good"
    } else {
        "questionable"
    };
    let _ = writeln!(s, "\nVerdict: {verdict}");
    for w in &r.warnings {
        let _ = writeln!(s, "  - {}", warning(w));
    }
    if !r.outliers.poses.is_empty() {
        let _ = writeln!(
            s,
            "  - {} pose(s) disagree with the others{}",
            r.outliers.poses.len(),
            if r.outliers.rejected {
                " and were left out"
            } else {
                ""
            }
        );
    }
    let _ = writeln!(
        s,
        "\nUncertainty (one sigma): rotation {:.4}°, translation {} {u}",
        r.uncertainty.rotation_deg,
        short(r.uncertainty.translation)
    );
    let _ = writeln!(
        s,
        "Residuals of AX = XB: rotation {:.4}° RMS ({:.4}° max), translation {} {u} RMS ({} {u} max)",
        r.residual.rotation_deg_rms,
        r.residual.rotation_deg_max,
        short(r.residual.translation_rms),
        short(r.residual.translation_max)
    );
    let _ = writeln!(
        s,
        "Motions: rotations of {:.1}° to {:.1}°, axes spread over {:.1}°; conditioning {:.3}",
        r.quality.rotation_range_deg[0],
        r.quality.rotation_range_deg[1],
        r.quality.axis_spread_deg,
        r.conditioning
    );
    let _ = writeln!(s, "\nNext:");
    if r.warnings.is_empty() {
        let _ = writeln!(
            s,
            "  publish X: --output ros2 (tf), --output urdf (a <joint>), --output yaml (easy_handeye2); --output json for everything"
        );
    } else {
        let _ = writeln!(
            s,
            "  act on the cautions above (each says what to do), then calibrate again; --output json for everything"
        );
    }
    if unit == Some(Unit::Millimetre) {
        let _ = writeln!(
            s,
            "  the input is in millimetres: ROS expects metres (divide the translation by 1000)"
        );
    }
    s
}

/// A refusal as the text face gives it: the verdict, the reason and what to do.
pub fn refused(e: &Error) -> String {
    format!("Verdict: refused\n  - {e}\n\nNext:\n  the reason above says what to do\n")
}

/// A length to four significant digits.
fn short(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = (3 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.digits$}")
}

/// The frames of X: `--parent-frame`/`--child-frame`, else the recording's names, else the
/// frames of X's name.
pub fn frames(input: &InputArgs, parent: Option<&str>, child: Option<&str>) -> Frames {
    let named = |flag: &Option<String>, generic: &str| {
        flag.clone()
            .filter(|_| input.is_bag())
            .unwrap_or_else(|| generic.to_string())
    };
    let base = named(&input.base_frame, "base");
    let gripper = named(&input.gripper_frame, "gripper");
    let camera = named(&input.camera_frame, "camera");
    let target = named(&input.target_frame, "target");
    let parent = parent.map_or_else(
        || match input.setup() {
            Setup::EyeInHand => gripper.clone(),
            Setup::EyeToHand => base.clone(),
        },
        str::to_string,
    );
    let child = child.map_or(camera, str::to_string);
    let (base, gripper) = match input.setup() {
        Setup::EyeInHand => (base, parent.clone()),
        Setup::EyeToHand => (parent.clone(), gripper),
    };
    Frames {
        parent,
        child,
        base,
        gripper,
        target,
    }
}

/// A warning as the command line says it: its words, then its remedy as a flag
/// ("…; pass `--reject-outliers` to leave them out").
pub fn warning(w: &handeye::Warning) -> String {
    let Some(remedy) = w.remedy() else {
        return w.to_string();
    };
    let flag = format!("--{}", remedy.option().replace('_', "-"));
    let flag = match remedy.value() {
        serde_json::Value::String(value) => format!("{flag} {value}"),
        _ => flag,
    };
    format!("{w}; pass `{flag}` {}", remedy.purpose())
}
