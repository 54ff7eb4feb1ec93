//! The faces of a batch result besides JSON (SPEC sec. 8): a summary for a person on a terminal,
//! and what ROS users paste: a `static_transform_publisher` line and launch snippet, an
//! easy_handeye2 YAML, a URDF `<joint>`.

use std::fmt::Write as _;

use handeye::Unit;
use handeye::{Error, Setup};
use handeye::{HandEyeReport, RobotWorldReport};
use quick_xml::events::{BytesText, Event};
use yaml_rust2::{Yaml, YamlEmitter};

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

/// The tf frames X connects: `parent_from_child`, each a checked, normalised frame name
/// ([`frame_name`]).
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
    /// The calibration's name (easy_handeye2's `parameters.name`, its file name).
    pub name: String,
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
    /// The input's length unit, when known: a translation in millimetres is published in metres
    /// ([`ros_unit`]).
    pub unit: Option<Unit>,
    /// Why the transform is not X for the frames asked, for a comment
    /// ([`crate::publish::Publication::note`]).
    pub note: Option<&'a str>,
    /// What publishing it breaks in the recording's tf, for a comment
    /// ([`crate::publish::Publication::warning`]).
    pub warning: Option<&'a str>,
}

impl<'a> Published<'a> {
    /// A batch result; `unit` from [`ros_unit`].
    pub fn of(r: &'a HandEyeReport, source: &'a str, unit: Option<Unit>) -> Self {
        Self {
            x: &r.transform,
            frame: &r.frame,
            setup: r.setup,
            source,
            unit,
            note: None,
            warning: None,
        }
    }

    /// The comment lines the note and the warning make, each without its comment sign.
    fn comments(&self) -> Vec<String> {
        let warning = self.warning.map(|w| format!("warning: {w}"));
        self.note
            .map(str::to_string)
            .into_iter()
            .chain(warning)
            .map(|line| line.replace(['\n', '\r'], " "))
            .collect()
    }

    /// What a length of the input is in metres, or 1 when the unit is not known.
    fn scale(&self) -> f64 {
        match self.unit {
            Some(Unit::Millimetre) => 1e-3,
            _ => 1.0,
        }
    }

    /// The unit of the lengths published, for a comment.
    fn unit_words(&self) -> &'static str {
        match self.unit {
            Some(Unit::Millimetre) => "metres (converted from millimetres)",
            Some(Unit::Metre) => "metres",
            _ => "the input's unit (not told by its poses)",
        }
    }

    /// X's translation, in metres when the input's unit is known to be millimetres.
    fn translation(&self) -> [f64; 3] {
        let t = handeye::TransformJson::from(self.x).translation;
        match self.unit {
            Some(Unit::Millimetre) => t.map(|v| v * 1e-3),
            _ => t,
        }
    }

    /// The quaternion as the JSON gives it.
    fn quaternion_xyzw(&self) -> [f64; 4] {
        handeye::TransformJson::from(self.x).quaternion_xyzw
    }
}

/// The input's length unit for the ROS faces, which are in metres whatever the input, saying on
/// stderr what they do: a translation in millimetres is converted, one in a unit that cannot be
/// told is left as it is, with a warning.
pub fn ros_unit(unit: Option<Unit>) -> Option<Unit> {
    match unit {
        Some(Unit::Millimetre) => {
            crate::tell!("translation converted from millimetres to metres for ROS");
            Some(Unit::Millimetre)
        }
        Some(Unit::Metre) => Some(Unit::Metre),
        _ => {
            crate::tell!(
                "warning: the input's length unit cannot be told from its poses; the translation is in the input's unit, and ROS expects metres (divide it by 1000 if the input is in millimetres)"
            );
            None
        }
    }
}

/// The characters a frame name may have, after its leading `/`: see [`frame_name`].
fn frame_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || matches!(c, '_' | '/' | '.' | '-')
}

/// A frame name as the ROS faces print it, from the flag that gave it; the rule of
/// `docs/DECISIONS.md` (ROS frame names).
///
/// Normalised as the recording's reader keys frames (and as tf2 does): surrounding whitespace
/// trimmed, one leading `/` dropped. Then refused (exit 2, naming the flag and the character)
/// unless it is a ROS name: it starts with a letter or `_` and has only ASCII letters, digits,
/// `_`, `/`, `.` and `-` (tf2 itself takes any string, but a frame name outside ROS names is a
/// typo or a hostile recording: quotes, whitespace, `$`, `;`, `<`, `#`, `:` and control
/// characters would change what the printed YAML, URDF, shell line or launch file means). The
/// whitespace is checked before trimming, so that a name is printed as it was typed or not at all.
pub fn frame_name(flag: &'static str, value: &str) -> Result<String, Error> {
    let refuse = |what: String| Error::InvalidParameter {
        name: flag,
        message: format!(
            "{what}: a frame name starts with a letter or `_` and has only letters, digits, `_`, `/`, `.` and `-` (ROS names; a leading `/` is dropped, as tf2 does)"
        ),
    };
    if let Some(c) = value.chars().find(|&c| !frame_char(c)) {
        return Err(refuse(format!(
            "--{} has {}",
            flag.replace('_', "-"),
            shown(c)
        )));
    }
    let name = value.trim();
    let name = name.strip_prefix('/').unwrap_or(name);
    match name.chars().next() {
        None => Err(refuse(format!("--{} is empty", flag.replace('_', "-")))),
        Some(c) if !(c.is_ascii_alphabetic() || c == '_') => Err(refuse(format!(
            "--{} starts with {}",
            flag.replace('_', "-"),
            shown(c)
        ))),
        Some(_) => Ok(name.to_string()),
    }
}

/// A character for a message: printable ones in backticks, the others as their code point.
fn shown(c: char) -> String {
    if c.is_control() || c.is_whitespace() {
        format!(
            "the character U+{:04X}{}",
            u32::from(c),
            match c {
                '\n' => " (a newline)",
                '\r' => " (a carriage return)",
                '\t' => " (a tab)",
                ' ' => " (a space)",
                _ => "",
            }
        )
    } else {
        format!("`{c}`")
    }
}

/// Checks easy_handeye2's calibration name (`--name`): it names the file easy_handeye2 loads
/// (`~/.ros2/easy_handeye2/calibrations/NAME.calib`), so letters, digits, `_` and `-`, not
/// starting with `-`.
pub fn calibration_name(value: &str) -> Result<String, Error> {
    let bad = value
        .chars()
        .find(|&c| !(c.is_ascii_alphanumeric() || c == '_' || c == '-'));
    let message = match (bad, value.chars().next()) {
        (Some(c), _) => format!("--name has {}", shown(c)),
        (None, None) => "--name is empty".to_string(),
        (None, Some('-')) => "--name starts with `-`".to_string(),
        (None, Some(_)) => return Ok(value.to_string()),
    };
    Err(Error::InvalidParameter {
        name: "name",
        message: format!(
            "{message}: the calibration's name is a file name for easy_handeye2 (letters, digits, `_` and `-`)"
        ),
    })
}

/// The input's length unit as far as the first poses tell (metres or millimetres).
pub fn length_unit(poses: &[handeye::PosePair]) -> Option<Unit> {
    poses.iter().find_map(Unit::infer)
}

/// The unit's symbol for a length printed for a person.
pub fn unit_name(unit: Option<Unit>) -> &'static str {
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

/// A YAML scalar for a number, as Rust prints it (the shortest text that reads back the same).
fn yaml_number(v: f64) -> Yaml {
    if v.is_finite() {
        Yaml::Real(format!("{v}"))
    } else {
        Yaml::Real(
            if v.is_nan() {
                ".nan"
            } else if v > 0.0 {
                ".inf"
            } else {
                "-.inf"
            }
            .into(),
        )
    }
}

/// A translation as geometry_msgs writes it: `{x, y, z}`.
fn yaml_translation([x, y, z]: [f64; 3]) -> Yaml {
    yaml_map([
        ("x", yaml_number(x)),
        ("y", yaml_number(y)),
        ("z", yaml_number(z)),
    ])
}

/// A rotation as geometry_msgs writes it: the quaternion `{x, y, z, w}`.
fn yaml_rotation([x, y, z, w]: [f64; 4]) -> Yaml {
    yaml_map([
        ("x", yaml_number(x)),
        ("y", yaml_number(y)),
        ("z", yaml_number(z)),
        ("w", yaml_number(w)),
    ])
}

/// A YAML mapping of `(key, value)` in order.
fn yaml_map<const N: usize>(entries: [(&str, Yaml); N]) -> Yaml {
    Yaml::Hash(
        entries
            .into_iter()
            .map(|(k, v)| (Yaml::String(k.to_string()), v))
            .collect(),
    )
}

/// The robot-world result as YAML, written by the YAML emitter: X and the target's pose, each under
/// its frame name (`base_from_camera`, `gripper_from_target`, …) with the parent and child frames
/// it is published between (`--parent-frame`, `--child-frame`, and the target's frames), its
/// one-sigma uncertainty, then the residuals, in the input's unit.
pub fn robot_world_yaml(r: &RobotWorldReport, x: &Frames, target: &Frames) -> String {
    let pose = |t: &handeye::TransformJson, u: &handeye::Uncertainty, f: &Frames| {
        yaml_map([
            ("parent_frame", Yaml::String(f.parent.clone())),
            ("child_frame", Yaml::String(f.child.clone())),
            ("translation", yaml_translation(t.translation)),
            ("rotation", yaml_rotation(t.quaternion_xyzw)),
            (
                "uncertainty",
                yaml_map([
                    ("rotation_deg", yaml_number(u.rotation_deg)),
                    ("translation", yaml_number(u.translation)),
                ]),
            ),
        ])
    };
    let doc = Yaml::Hash(
        [
            (r.frame.as_str(), pose(&r.x, &r.uncertainty, x)),
            (
                r.target.frame.as_str(),
                pose(&r.target.pose, &r.target.uncertainty, target),
            ),
            (
                "residual",
                yaml_map([
                    ("rotation_deg_rms", yaml_number(r.residual.rotation_deg_rms)),
                    ("translation_rms", yaml_number(r.residual.translation_rms)),
                ]),
            ),
            ("poses", Yaml::Integer(r.poses as i64)),
        ]
        .into_iter()
        .map(|(k, v)| (Yaml::String(k.to_string()), v))
        .collect(),
    );
    let mut body = String::new();
    YamlEmitter::new(&mut body)
        .dump(&doc)
        .expect("a YAML emitter writing to a String cannot fail");
    format!(
        "# handeye calibrate --robot-world: method {}, setup {}\n{}\n",
        r.method,
        r.setup.name(),
        body.trim_start_matches("---\n")
    )
}

/// easy_handeye2's calibration file: exactly the fields of its `HandeyeCalibration` message
/// (`parameters` and `transform`, which its loader sets one by one, refusing any other key), in
/// metres, written by a YAML emitter (each frame name quoted where YAML would read it otherwise).
/// handeye's own fields (X's frame name, the parent and child frames, and for a batch result its
/// uncertainty, residuals and motions) are comments above it.
pub fn yaml(p: Published<'_>, f: &Frames, batch: Option<&HandEyeReport>) -> String {
    let kind = match p.setup {
        Setup::EyeInHand => "eye_in_hand",
        Setup::EyeToHand => "eye_on_base",
    };
    let string = |s: &str| Yaml::String(s.to_string());
    let doc = yaml_map([
        (
            "parameters",
            yaml_map([
                ("name", string(&f.name)),
                ("calibration_type", string(kind)),
                ("robot_base_frame", string(&f.base)),
                ("robot_effector_frame", string(&f.gripper)),
                ("tracking_base_frame", string(&f.child)),
                ("tracking_marker_frame", string(&f.target)),
                ("freehand_robot_movement", Yaml::Boolean(true)),
                // The message's defaults, as easy_handeye2 writes them.
                ("move_group_namespace", string("/")),
                ("move_group", string("manipulator")),
            ]),
        ),
        (
            "transform",
            yaml_map([
                ("translation", yaml_translation(p.translation())),
                ("rotation", yaml_rotation(p.quaternion_xyzw())),
            ]),
        ),
    ]);
    let mut body = String::new();
    YamlEmitter::new(&mut body)
        .dump(&doc)
        .expect("a YAML emitter writing to a String cannot fail");
    let mut s = String::new();
    let mut comment = |line: String| {
        // The comment's text is ours and checked frame names; a line break would end it.
        s.push_str("# ");
        s.push_str(&line.replace(['\n', '\r'], " "));
        s.push('\n');
    };
    comment(format!(
        "handeye {}, setup {}: easy_handeye2's calibration file (save it as ~/.ros2/easy_handeye2/calibrations/{}.calib)",
        p.source,
        p.setup.name(),
        f.name
    ));
    comment(format!(
        "frame: {} ({} -> {}); translation in {}",
        p.frame,
        f.parent,
        f.child,
        p.unit_words()
    ));
    for line in p.comments() {
        comment(line);
    }
    if let Some(r) = batch {
        let unit = if p.unit.is_some() { " m" } else { "" };
        comment(format!(
            "uncertainty (one sigma): rotation_deg {}, translation {}{unit}",
            r.uncertainty.rotation_deg,
            r.uncertainty.translation * p.scale()
        ));
        comment(format!(
            "residual: rotation_deg_rms {}, translation_rms {}{unit}; motions {}",
            r.residual.rotation_deg_rms,
            r.residual.translation_rms * p.scale(),
            r.motions
        ));
    }
    s.push_str(&body);
    s.push('\n');
    s
}

/// The arguments of `static_transform_publisher` for X, in metres.
fn publisher_arguments(p: Published<'_>, f: &Frames) -> Vec<String> {
    let [x, y, z] = p.translation();
    let [qx, qy, qz, qw] = p.quaternion_xyzw();
    let mut args = Vec::with_capacity(18);
    for (flag, v) in [
        ("--x", x),
        ("--y", y),
        ("--z", z),
        ("--qx", qx),
        ("--qy", qy),
        ("--qz", qz),
        ("--qw", qw),
    ] {
        args.push(flag.to_string());
        args.push(format!("{v}"));
    }
    args.extend([
        "--frame-id".to_string(),
        f.parent.clone(),
        "--child-frame-id".to_string(),
        f.child.clone(),
    ]);
    args
}

/// The `ros2 run tf2_ros static_transform_publisher` command that puts X in the tf tree: one
/// POSIX shell line, each word quoted where the shell would read it otherwise.
pub fn static_transform_publisher(p: Published<'_>, f: &Frames) -> String {
    let mut argv: Vec<String> = ["ros2", "run", "tf2_ros", "static_transform_publisher"]
        .map(String::from)
        .into();
    argv.extend(publisher_arguments(p, f));
    shlex::try_join(argv.iter().map(String::as_str))
        .expect("checked frame names and numbers have no NUL byte")
}

/// A Python string literal: JSON's string escaping, which Python reads the same for every
/// character (`\"`, `\\`, `\n`, `\uXXXX`, …).
fn python_string(s: &str) -> String {
    serde_json::to_string(s).expect("a string is valid JSON")
}

/// A ROS node name from free text: letters, digits and `_` (the others become `_`).
fn node_name(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}

/// The command line and a Python launch snippet publishing X.
pub fn ros2(p: Published<'_>, f: &Frames) -> String {
    let arguments = publisher_arguments(p, f)
        .iter()
        .map(|a| python_string(a))
        .collect::<Vec<_>>();
    let list = |a: &[String]| a.join(", ");
    let comments: String = p.comments().iter().map(|c| format!("# {c}\n")).collect();
    format!(
        "# handeye {source}: {frame} ({parent} -> {child})\n\
         {comments}{line}\n\
         \n\
         # In a launch file (Python):\n\
         from launch_ros.actions import Node\n\
         \n\
         {variable} = Node(\n    package=\"tf2_ros\",\n    executable=\"static_transform_publisher\",\n    \
         name={name},\n    arguments=[\n        \
         {xyz},\n        \
         {q},\n        \
         {frames},\n    ],\n)\n",
        frame = p.frame,
        parent = f.parent,
        child = f.child,
        source = p.source,
        // X's node, or the target's (robot-world prints both: two names, both pasteable).
        variable = if p.frame.ends_with("_from_target") {
            "handeye_target_tf"
        } else {
            "handeye_tf"
        },
        line = static_transform_publisher(p, f),
        name = python_string(&node_name(&format!("handeye_{}_to_{}", f.parent, f.child))),
        xyz = list(&arguments[0..6]),
        q = list(&arguments[6..14]),
        frames = list(&arguments[14..18]),
    )
}

/// A URDF fixed `<joint>` from the parent to the child link, in metres, written by an XML writer
/// (attribute values escaped).
pub fn urdf(p: Published<'_>, f: &Frames) -> String {
    let [x, y, z] = p.translation();
    let [roll, pitch, yaw] = rpy(p.x);
    let mut w = quick_xml::Writer::new_with_indent(Vec::new(), b' ', 2);
    let comment = format!(" handeye {}: {} ", p.source, p.frame).replace("--", "- -");
    let xyz = format!("{x} {y} {z}");
    let rpy = format!("{roll} {pitch} {yaw}");
    let joint = format!("{}_to_{}", f.parent, f.child);
    let comments: Vec<String> = p
        .comments()
        .iter()
        .map(|c| format!(" {c} ").replace("--", "- -"))
        .collect();
    let written: std::io::Result<()> = (|| {
        w.write_event(Event::Comment(BytesText::from_escaped(comment.as_str())))?;
        for c in &comments {
            w.write_event(Event::Comment(BytesText::from_escaped(c.as_str())))?;
        }
        w.create_element("joint")
            .with_attributes([("name", joint.as_str()), ("type", "fixed")])
            .write_inner_content(|w| {
                w.create_element("parent")
                    .with_attribute(("link", f.parent.as_str()))
                    .write_empty()?;
                w.create_element("child")
                    .with_attribute(("link", f.child.as_str()))
                    .write_empty()?;
                w.create_element("origin")
                    .with_attributes([("xyz", xyz.as_str()), ("rpy", rpy.as_str())])
                    .write_empty()?;
                Ok(())
            })?;
        Ok(())
    })();
    written.expect("an XML writer writing to memory cannot fail");
    let mut s = String::from_utf8(w.into_inner()).expect("the XML written is UTF-8");
    s.push('\n');
    s
}

/// The error where it matters, in one line: "a point at 0.45 m from the camera is placed within
/// ±0.8 mm (one sigma)".
pub fn at_point(point: [f64; 3], sigma: f64, unit: Option<Unit>) -> String {
    let distance = nalgebra::Vector3::from(point).norm();
    let (far, within) = match unit {
        Some(Unit::Metre) => (format!("{distance:.3} m"), format!("{:.2} mm", sigma * 1e3)),
        Some(Unit::Millimetre) => (
            format!("{:.3} m", distance * 1e-3),
            format!("{:.2} mm", sigma),
        ),
        _ => (
            format!("{} (input units)", short(distance)),
            format!("{} (input units)", short(sigma)),
        ),
    };
    format!("A point at {far} from the camera is placed within ±{within} (one sigma)")
}

/// The summary for a person: X, the verdict and its reasons, the uncertainty, the residuals, and
/// what to do next.
pub fn text(r: &HandEyeReport, f: &Frames, unit: Option<Unit>) -> String {
    let u = unit_name(unit);
    let mut s = String::new();
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
    transform_lines(&mut s, &r.transform, unit);
    verdict_lines(
        &mut s,
        (r.verdict, r.goal.as_ref(), u),
        &r.warnings,
        (r.outliers.poses.len(), r.outliers.rejected),
    );
    let _ = writeln!(
        s,
        "\nUncertainty (one sigma): rotation {:.4}°, translation {} {u}",
        r.uncertainty.rotation_deg,
        short(r.uncertainty.translation)
    );
    if let Some(p) = &r.uncertainty.at_point {
        let _ = writeln!(s, "{}", at_point(p.point, p.sigma, unit));
    }
    low_dof_lines(&mut s, r.low_dof.as_ref(), &r.prior, u);
    if let Some(p) = &r.reprojection {
        reprojection_lines(&mut s, p);
    }
    let _ = writeln!(
        s,
        "Residuals of AX = XB{}: rotation {:.4}° RMS ({:.4}° max), translation {} {u} RMS ({} {u} max)",
        if r.reprojection.is_some() {
            // X was fitted to the pixels: these are the PnP poses' noise, not X's error.
            " of the PnP poses (their noise: X was fitted to the pixels)"
        } else {
            ""
        },
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
    systematic_line(
        &mut s,
        r.systematic.as_ref(),
        r.systematic_untested.as_deref(),
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
            "  the input is in millimetres: the ros2, urdf and yaml outputs give the translation in metres"
        );
    }
    s
}

/// A transform's lines in the text face: its translation (and in millimetres when it is in
/// metres), its roll, pitch, yaw and its quaternion.
pub fn transform_lines(s: &mut String, x: &handeye::Transform, unit: Option<Unit>) {
    let u = unit_name(unit);
    let json = handeye::TransformJson::from(x);
    let [tx, ty, tz] = json.translation;
    let [qx, qy, qz, qw] = json.quaternion_xyzw;
    let [roll, pitch, yaw] = rpy(x).map(f64::to_degrees);
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
}

/// The verdict, its cautions and the poses that disagree.
fn verdict_lines(
    s: &mut String,
    (verdict, goal, u): (handeye::Assessment, Option<&handeye::GoalCheck>, &str),
    warnings: &[handeye::Warning],
    (disagree, rejected): (usize, bool),
) {
    let _ = writeln!(
        s,
        "\nVerdict: {}{}",
        verdict.name(),
        good_means(verdict, goal, u)
    );
    for w in warnings {
        let _ = writeln!(s, "  - {}", warning(w));
    }
    if disagree > 0 {
        let _ = writeln!(
            s,
            "  - {disagree} pose(s) disagree with the others{}",
            if rejected { " and were left out" } else { "" }
        );
    }
}

/// What a `good` verdict means, after it: X within the user's goal (`--goal`), or else within the
/// uncertainty printed with it; nothing after `questionable` (its cautions follow).
fn good_means(verdict: handeye::Assessment, goal: Option<&handeye::GoalCheck>, u: &str) -> String {
    if verdict != handeye::Assessment::Good {
        return String::new();
    }
    match goal {
        Some(g) => format!(
            " (within your goal of {}° and {} {u}, one sigma)",
            g.goal.rotation_deg, g.goal.translation
        ),
        None => " (trust X to the uncertainty printed below, one sigma)".into(),
    }
}

/// The robot-world summary for a person: X and the target's pose, the verdict, the uncertainty
/// of both, the residuals, and what to do next.
pub fn robot_world_text(r: &RobotWorldReport, f: &Frames, unit: Option<Unit>) -> String {
    let u = unit_name(unit);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "X = {} ({} -> {}), robot-world method {} on {} poses ({})",
        r.frame,
        f.parent,
        f.child,
        r.method,
        r.poses,
        r.setup.name()
    );
    transform_lines(&mut s, &r.transform, unit);
    let (parent, child) = target_frames(r.setup, f);
    let _ = writeln!(s, "Target = {} ({parent} -> {child})", r.target.frame);
    transform_lines(&mut s, &r.target_transform, unit);
    verdict_lines(
        &mut s,
        (r.verdict, r.goal.as_ref(), u),
        &r.warnings,
        (r.outliers.poses.len(), r.outliers.rejected),
    );
    let _ = writeln!(
        s,
        "\nUncertainty (one sigma): X rotation {:.4}°, translation {} {u}; target rotation {:.4}°, translation {} {u}",
        r.uncertainty.rotation_deg,
        short(r.uncertainty.translation),
        r.target.uncertainty.rotation_deg,
        short(r.target.uncertainty.translation)
    );
    if let Some(p) = &r.uncertainty.at_point {
        let _ = writeln!(s, "{}", at_point(p.point, p.sigma, unit));
    }
    low_dof_lines(&mut s, r.low_dof.as_ref(), &r.prior, u);
    if let Some(low) = &r.low_dof {
        let _ = writeln!(
            s,
            "The target's translation along that axis follows from X's {}: the poses leave the two free together",
            low.free.name()
        );
    }
    if let Some(p) = &r.reprojection {
        reprojection_lines(&mut s, p);
    }
    let _ = writeln!(
        s,
        "Residuals of A X = Y B over the{} poses: rotation {:.4}° RMS ({:.4}° max), translation {} {u} RMS ({} {u} max)",
        if r.reprojection.is_some() {
            // X and the target were fitted to the pixels: these are the PnP poses' noise.
            " PnP"
        } else {
            ""
        },
        r.residual.rotation_deg_rms,
        r.residual.rotation_deg_max,
        short(r.residual.translation_rms),
        short(r.residual.translation_max)
    );
    systematic_line(
        &mut s,
        r.systematic.as_ref(),
        r.systematic_untested.as_deref(),
    );
    let _ = writeln!(s, "\nNext:");
    if r.warnings.is_empty() {
        let _ = writeln!(
            s,
            "  publish X and the target: --output ros2 (tf), --output urdf (two <joint>s); --output json for everything"
        );
    } else {
        let _ = writeln!(
            s,
            "  act on the cautions above (each says what to do), then calibrate again; --output json for everything"
        );
    }
    s
}

/// The systematic-error test's line: what it found on how many stations (a dense stream's
/// stretches), or why it did not run.
fn systematic_line(s: &mut String, found: Option<&handeye::Systematic>, untested: Option<&str>) {
    let line = match (found, untested) {
        (Some(f), _) => {
            let on = match f.stream_poses {
                Some(m) => format!("{} stretches of the robot's motion over {m} poses", f.poses),
                None => format!("{} robot stations", f.poses),
            };
            let what = if f.flagged {
                "the residuals follow the robot's configuration (the caution above)"
            } else {
                "none found"
            };
            format!("{what}; p {:.2e} on {on}", f.p_value)
        }
        (None, Some(why)) => format!("not run: {why}"),
        (None, None) => return,
    };
    let _ = writeln!(s, "Systematic-error test: {line}");
}

/// Which component of X came from the prior (a low-DOF robot), and the prior itself.
fn low_dof_lines(
    s: &mut String,
    low_dof: Option<&handeye::LowDofReport>,
    prior: &std::collections::BTreeMap<String, handeye::PriorValue>,
    u: &str,
) {
    if let Some(low) = low_dof {
        let [x, y, z] = low.axis.map(|v| if v.abs() < 5e-4 { 0.0 } else { v });
        let _ = writeln!(
            s,
            "Low-DOF robot: every motion rotates about one axis ({x:.3}, {y:.3}, {z:.3}) (within {:.2}°); X's {} is the prior's, the rest is the motions'",
            low.spread_deg,
            low.free.name()
        );
    }
    for (name, p) in prior {
        let sigma = if p.sigma > 0.0 {
            format!(" +- {}", with_unit(p.sigma, u))
        } else {
            " (exact)".into()
        };
        match low_dof.filter(|low| low.unchecked.iter().any(|c| c.name() == name)) {
            // The component the data leave free: its sign and direction said, never checked.
            Some(low) => {
                let _ = writeln!(
                    s,
                    "Prior: {name} = {}{sigma} from your prior, along {}; the data cannot check it (unchecked, its sign included)",
                    with_unit_signed(p.value, u),
                    low.direction
                );
            }
            None => {
                let _ = writeln!(s, "Prior: {name} = {}{sigma}", with_unit(p.value, u));
            }
        }
    }
}

/// A length in the input's unit, with millimetres beside metres ("0.1075 m (107.5 mm)").
fn with_unit(v: f64, u: &str) -> String {
    with_unit_sign(v, u, "")
}

/// [`with_unit`] with its sign always written ("+0.1075 m (+107.5 mm)").
fn with_unit_signed(v: f64, u: &str) -> String {
    with_unit_sign(v, u, if v >= 0.0 { "+" } else { "" })
}

fn with_unit_sign(v: f64, u: &str, sign: &str) -> String {
    if u == "m" {
        format!("{sign}{v} m ({sign}{:.1} mm)", v * 1000.0)
    } else {
        format!("{sign}{v} {u}")
    }
}

/// The fit on the pixels: the RMS, the detections left out, the worst frame, the reading check.
fn reprojection_lines(s: &mut String, p: &handeye::ReprojectionSummary) {
    let worst = p
        .per_frame
        .iter()
        .max_by(|a, b| a.rms_px.total_cmp(&b.rms_px));
    let _ = writeln!(
        s,
        "Reprojection: {:.3} px RMS over {} detections ({} left out as mis-detections){}",
        p.rms_px,
        p.detections,
        p.outlier_detections.len(),
        worst.map_or(String::new(), |w| format!(
            "; worst frame {} at {:.3} px",
            w.name, w.rms_px
        ))
    );
    let _ = writeln!(s, "  readings checked {}", p.reading_check);
    if let Some(k) = &p.intrinsics {
        let g = &k.sigma;
        let d = &k.distortion;
        let sd = |i: usize| g.distortion[i].map_or("held".to_string(), |v| format!("{v:.2e}"));
        let _ = writeln!(
            s,
            "Intrinsics refined (± one sigma): fx {:.2} ± {:.2}, fy {:.2} ± {:.2}, cx {:.2} ± {:.2}, cy {:.2} ± {:.2} px",
            k.fx, g.fx, k.fy, g.fy, k.cx, g.cx, k.cy, g.cy
        );
        let _ = writeln!(
            s,
            "  k1 {:.5} ± {}, k2 {:.5} ± {}, p1 {:.6} ± {}, p2 {:.6} ± {}, k3 {:.5} ({})",
            d[0],
            sd(0),
            d[1],
            sd(1),
            d[2],
            sd(2),
            d[3],
            sd(3),
            d[4],
            if k.held.iter().any(|h| h == "k3") {
                "held as given".to_string()
            } else {
                sd(4)
            }
        );
        let _ = writeln!(
            s,
            "  determined by: {} of 4 image corner cells reached, tilt {:.1}° (RMS) about the weaker image axis",
            k.corner_cells, k.tilt_deg
        );
    }
}

/// The tf frames of the robot-world target pose: `base_from_target` (eye-in-hand) or
/// `gripper_from_target` (eye-to-hand).
pub fn target_frames(setup: Setup, f: &Frames) -> (String, String) {
    match setup {
        Setup::EyeInHand => (f.base.clone(), f.target.clone()),
        Setup::EyeToHand => (f.gripper.clone(), f.target.clone()),
    }
}

/// A refusal as the text face gives it: the verdict, the reason and what to do.
pub fn refused(e: &Error) -> String {
    refused_message(&e.to_string())
}

/// [`refused`] of a refusal's message (with its context).
pub fn refused_message(message: &str) -> String {
    format!("Verdict: refused\n  - {message}\n\nNext:\n  the reason above says what to do\n")
}

/// A length to four significant digits.
pub fn short(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = (3 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.digits$}")
}

/// The frames of X: `--parent-frame`/`--child-frame`, else the recording's names, else the
/// frames of X's name; each checked and normalised ([`frame_name`]), or refused naming its flag;
/// and the calibration's `--name` ([`calibration_name`]). Checked before the input is read.
pub fn frames(
    input: &InputArgs,
    parent: Option<&str>,
    child: Option<&str>,
    name: &str,
) -> Result<Frames, Error> {
    let name = calibration_name(name)?;
    let named = |flag: &'static str, value: &Option<String>, generic: &str| match value {
        Some(v) if input.is_bag() => frame_name(flag, v),
        _ => Ok(generic.to_string()),
    };
    let base = named("base_frame", &input.base_frame, "base")?;
    let gripper = named("gripper_frame", &input.gripper_frame, "gripper")?;
    let camera = named("camera_frame", &input.camera_frame, "camera")?;
    let target = named("target_frame", &input.target_frame, "target")?;
    let parent = match parent {
        Some(p) => frame_name("parent_frame", p)?,
        None => match input.setup() {
            Setup::EyeInHand => gripper.clone(),
            Setup::EyeToHand => base.clone(),
        },
    };
    let child = match child {
        Some(c) => frame_name("child_frame", c)?,
        None => camera,
    };
    let (base, gripper) = match input.setup() {
        Setup::EyeInHand => (base, parent.clone()),
        Setup::EyeToHand => (parent.clone(), gripper),
    };
    Ok(Frames {
        parent,
        child,
        base,
        gripper,
        target,
        name,
    })
}

/// A warning as the command line says it: its words, then its remedy as a flag
/// ("…; pass `--reject-outliers` to leave them out").
pub fn warning(w: &handeye::Warning) -> String {
    match w.remedy() {
        Some(r) => format!("{w}; {}", remedy(r, "calibrate")),
        None => w.to_string(),
    }
}

/// A remedy as the flags of `command` say it ("pass `--reject-outliers` to leave them out"). On
/// the pixels, `calibrate` needs the method with the intrinsics; `online` and `verify` take the
/// intrinsics alone; another command names the calibration that reads such records.
pub fn remedy(remedy: handeye::Remedy, command: &str) -> String {
    let flag = format!("--{}", remedy.option().replace('_', "-"));
    let call = match (remedy, command) {
        (handeye::Remedy::Pixels, "online" | "verify") => format!("{flag} FILE"),
        (handeye::Remedy::Pixels, "calibrate") => format!("--method reprojection {flag} FILE"),
        (handeye::Remedy::Pixels, _) => {
            return format!(
                "`handeye calibrate --method reprojection {flag} FILE` calibrates the records on their pixels"
            );
        }
        _ => match remedy.value() {
            serde_json::Value::String(value) => format!("{flag} {value}"),
            _ => flag,
        },
    };
    format!("pass `{call}` {}", remedy.purpose())
}

/// An error as `command` says it: a line's error with the flag that reads it, where the library
/// leaves the wording to the face ([`handeye::Error::Parse`]'s remedy); the library's refusals
/// word their remedies themselves.
pub fn error(e: &anyhow::Error, command: &str) -> String {
    let message = crate::output::error_message(e);
    match e.downcast_ref::<handeye::Error>() {
        Some(parse @ handeye::Error::Parse { .. }) => match parse.remedy() {
            Some(r) => format!("{message}; {}", remedy(r, command)),
            None => message,
        },
        _ => message,
    }
}
