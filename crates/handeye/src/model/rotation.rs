//! How an input writes the rotation of a pose (issue 33 item 11): a quaternion in either order, a
//! rotation vector, or three angles in a robot vendor's convention. Each [`RotationConvention`]
//! is named, its unit is part of its definition (degrees where the vendor's controller shows
//! degrees), and its formula is written below with the source it was checked against.
//!
//! Notation: `Rx(θ)`, `Ry(θ)`, `Rz(θ)` are the right-handed rotations by θ about the x, y and z
//! axes; a product applies its right-most factor first about the fixed axes, which is the same
//! as applying the left-most first about the axes already turned (intrinsic). The rotation is
//! that of the pose as the file names it (`base_from_gripper`: the gripper's axes in the base
//! frame).
//!
//! Every formula is checked in `tests/rotation.rs` against SciPy's `Rotation` on the fixtures of
//! `testdata/rotation/` (within 1e-12), and the vendors' worked examples where one is published.

use nalgebra::{Matrix3, Quaternion, Rotation3, UnitQuaternion, Vector3};

use crate::model::error::{Error, Result};
use crate::model::pose::QUATERNION_NORM_TOL;

/// How a pose's rotation is written: the numbers, their order, their unit and their formula.
///
/// Positional inputs (the stamped streams `t x y z …`, CSV columns) cannot tell these apart
/// (three angles may be any of the Euler conventions, in degrees or radians), so they are read
/// as a quaternion `x y z w` unless the convention is named ([`Rotations`]). A JSON transform
/// names its own: the field is [`RotationConvention::json_field`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RotationConvention {
    /// A unit quaternion `x, y, z, w` (scalar last): ROS `geometry_msgs/Quaternion`, the TUM and
    /// ethz-asl stream layouts, Eigen's `coeffs()`. The default.
    QuaternionXyzw,
    /// A unit quaternion `w, x, y, z` (scalar first): ABB's `orient` `[q1, q2, q3, q4]` with q1
    /// the real part (ABB RAPID Reference Manual, data type `orient`; Roboception's "ABB pose
    /// format": `(x, y, z, w) = (Q2, Q3, Q4, Q1)`), Eigen's `Quaternion(w, x, y, z)` constructor,
    /// SciPy's `scalar_first=True`. Its components are `q1 … q4`.
    QuaternionWxyz,
    /// A rotation vector `rx, ry, rz` in radians: the axis times the angle, `R = exp([r]×)`
    /// (Rodrigues), as OpenCV's `solvePnP` and `Rodrigues` return it and Universal Robots'
    /// controllers report a pose `p[x, y, z, rx, ry, rz]` (Roboception's "Universal Robots pose
    /// format"). One longer than a turn (2π) is refused: degrees.
    Rvec,
    /// KUKA's `A, B, C` in degrees: A about z, then B about the new y, then C about the newest
    /// x (z-y′-x″): `R = Rz(A)·Ry(B)·Rx(C)`. Sources: Roboception's "KUKA XYZ-ABC format"
    /// ("computed by rz(A) ry(B) rx(C)"), RoboDK's `robomath.KUKA_2_Pose`.
    KukaAbc,
    /// Mitsubishi's `A, B, C` in degrees: the same letters as KUKA's, the other way round: A
    /// about the fixed x, B about the fixed y, C about the fixed z: `R = Rz(C)·Ry(B)·Rx(A)`.
    /// Source: Roboception's "Mitsubishi XYZ-ABC format" ("computed by rz(C) ry(B) rx(A)").
    MitsubishiAbc,
    /// FANUC's `W, P, R` in degrees: W about the fixed x, P about the fixed y, R about the fixed
    /// z: `R = Rz(R)·Ry(P)·Rx(W)`. Sources: Roboception's "FANUC XYZ-WPR format" ("computed by
    /// rz(R) ry(P) rx(W)"), RoboDK's `robomath.Fanuc_2_Pose` (`rotz(R)·roty(P)·rotx(W)`).
    FanucWpr,
    /// Yaskawa (Motoman) `Rx, Ry, Rz` in degrees: FANUC's formula under Yaskawa's letters, Rx
    /// about the fixed x, Ry about the fixed y, Rz about the fixed z: `R = Rz(Rz)·Ry(Ry)·Rx(Rx)`.
    /// Source: RoboDK's `robomath.Motoman_2_Pose` (the same product as `Fanuc_2_Pose`). Not
    /// Stäubli's `Rx, Ry, Rz`, which turn the other way round.
    YaskawaRxryrz,
    /// Stäubli's `Rx, Ry, Rz` (VAL3 `trsf`) in degrees: Rx about x, then Ry about the new y,
    /// then Rz about the newest z (x-y′-z″): `R = Rx(Rx)·Ry(Ry)·Rz(Rz)`. Source: RoboDK's
    /// `robomath.Pose_2_Staubli` (= `Pose_2_TxyzRxyz`: `rotx(rx)·roty(ry)·rotz(rz)`, "the same
    /// representation used by Mecademic or Staubli robot controllers").
    StaubliXyz,
    /// Kawasaki's `O, A, T` in degrees: O about z, then A about the new y, then T about the
    /// newest z (z-y′-z″): `R = Rz(O)·Ry(A)·Rz(T)`. Source: Roboception's "Kawasaki XYZ-OAT
    /// format" ("computed by rz(O) ry(A) rz(T)").
    KawasakiOat,
    /// ROS roll, pitch, yaw in radians: roll about the fixed x, pitch about the fixed y, yaw about
    /// the fixed z: `R = Rz(yaw)·Ry(pitch)·Rx(roll)` (REP 103; tf2's `Quaternion::setRPY`, "fixed
    /// axis RPY"). An angle beyond a turn (2π) is refused: degrees.
    Rpy,
    /// Roll, pitch, yaw as [`RotationConvention::Rpy`], in degrees (a teach pendant's RPY).
    RpyDeg,
}

crate::named_enum!(RotationConvention, "rotation convention", "rotation" {
    QuaternionXyzw => "quaternion-xyzw",
    QuaternionWxyz => "quaternion-wxyz",
    Rvec => "rvec",
    KukaAbc => "kuka-abc",
    MitsubishiAbc => "mitsubishi-abc",
    FanucWpr => "fanuc-wpr",
    YaskawaRxryrz => "yaskawa-rxryrz",
    StaubliXyz => "staubli-xyz",
    KawasakiOat => "kawasaki-oat",
    Rpy => "rpy",
    RpyDeg => "rpy-deg",
});

/// Largest angle of a convention in radians, and largest rotation vector: one turn. A longer one
/// is almost always degrees (`solvePnP` returns at most π, and tf at most π per angle).
pub(crate) const MAX_RADIANS: f64 = std::f64::consts::TAU;

/// Largest angle of a convention in degrees: one turn. Controllers show ±180°; a larger number
/// is another column (a position, say) read as an angle.
pub(crate) const MAX_DEGREES: f64 = 360.0;

/// What is wrong with the numbers of a rotation: which of them (its index, `None` for all) and
/// why.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct RotationProblem {
    /// The component at fault, or `None` for the rotation as a whole.
    pub component: Option<usize>,
    /// What is wrong.
    pub message: String,
}

impl RotationConvention {
    /// The names of its numbers, in order: CSV column suffixes (`base_from_gripper_a`) and the
    /// fields of a stream line after `t x y z`.
    pub fn components(self) -> &'static [&'static str] {
        match self {
            Self::QuaternionXyzw => &["qx", "qy", "qz", "qw"],
            Self::QuaternionWxyz => &["q1", "q2", "q3", "q4"],
            Self::Rvec | Self::StaubliXyz | Self::YaskawaRxryrz => &["rx", "ry", "rz"],
            Self::KukaAbc | Self::MitsubishiAbc => &["a", "b", "c"],
            Self::FanucWpr => &["w", "p", "r"],
            Self::KawasakiOat => &["o", "a", "t"],
            Self::Rpy | Self::RpyDeg => &["roll", "pitch", "yaw"],
        }
    }

    /// The field of a JSON transform that gives a rotation in this convention (with
    /// `translation`): its name says the convention and the unit, so it needs no flag.
    pub fn json_field(self) -> &'static str {
        match self {
            Self::QuaternionXyzw => "quaternion_xyzw",
            Self::QuaternionWxyz => "quaternion_wxyz",
            Self::Rvec => "rvec",
            Self::KukaAbc => "kuka_abc_deg",
            Self::MitsubishiAbc => "mitsubishi_abc_deg",
            Self::FanucWpr => "fanuc_wpr_deg",
            Self::YaskawaRxryrz => "yaskawa_rxryrz_deg",
            Self::StaubliXyz => "staubli_xyz_deg",
            Self::KawasakiOat => "kawasaki_oat_deg",
            Self::Rpy => "rpy",
            Self::RpyDeg => "rpy_deg",
        }
    }

    /// Whether its angles are in degrees.
    pub fn in_degrees(self) -> bool {
        matches!(
            self,
            Self::KukaAbc
                | Self::MitsubishiAbc
                | Self::FanucWpr
                | Self::YaskawaRxryrz
                | Self::StaubliXyz
                | Self::KawasakiOat
                | Self::RpyDeg
        )
    }

    /// What it is in a few words, with its unit and formula (for help texts and messages).
    ///
    /// # Example
    /// ```
    /// use handeye::RotationConvention;
    /// assert_eq!(
    ///     RotationConvention::KukaAbc.describe(),
    ///     "KUKA A, B, C in degrees: R = Rz(A)·Ry(B)·Rx(C)"
    /// );
    /// ```
    pub fn describe(self) -> &'static str {
        match self {
            Self::QuaternionXyzw => "a quaternion x, y, z, w (ROS, TUM)",
            Self::QuaternionWxyz => "a quaternion w, x, y, z (ABB's q1 … q4, q1 = w)",
            Self::Rvec => "a rotation vector in radians (OpenCV rvec, Universal Robots)",
            Self::KukaAbc => "KUKA A, B, C in degrees: R = Rz(A)·Ry(B)·Rx(C)",
            Self::MitsubishiAbc => "Mitsubishi A, B, C in degrees: R = Rz(C)·Ry(B)·Rx(A)",
            Self::FanucWpr => "FANUC W, P, R in degrees: R = Rz(R)·Ry(P)·Rx(W)",
            Self::YaskawaRxryrz => "Yaskawa Rx, Ry, Rz in degrees: R = Rz(Rz)·Ry(Ry)·Rx(Rx)",
            Self::StaubliXyz => "Stäubli Rx, Ry, Rz in degrees: R = Rx(Rx)·Ry(Ry)·Rz(Rz)",
            Self::KawasakiOat => "Kawasaki O, A, T in degrees: R = Rz(O)·Ry(A)·Rz(T)",
            Self::Rpy => "roll, pitch, yaw in radians (ROS): R = Rz(yaw)·Ry(pitch)·Rx(roll)",
            Self::RpyDeg => "roll, pitch, yaw in degrees: R = Rz(yaw)·Ry(pitch)·Rx(roll)",
        }
    }

    /// The conventions whose components are exactly `names` (in any order): what a CSV header's
    /// columns could mean.
    pub(crate) fn with_components(names: &[&str]) -> Vec<RotationConvention> {
        Self::ALL
            .iter()
            .copied()
            .filter(|c| {
                c.components().len() == names.len()
                    && c.components().iter().all(|n| names.contains(n))
            })
            .collect()
    }

    /// The rotation matrix of `values` (as many as [`Self::components`], finite). A quaternion
    /// whose norm is within [`QUATERNION_NORM_TOL`] of 1 is normalised, another refused; an angle
    /// (or a rotation vector) longer than a turn is refused, with the likely unit mix-up.
    pub(crate) fn rotation(
        self,
        values: &[f64],
    ) -> std::result::Result<Matrix3<f64>, RotationProblem> {
        let problem = |component, message: String| RotationProblem { component, message };
        if values.len() != self.components().len() {
            return Err(problem(
                None,
                format!(
                    "expected {} numbers ({}), found {}",
                    self.components().len(),
                    self.components().join(", "),
                    values.len()
                ),
            ));
        }
        if let Some(k) = values.iter().position(|v| !v.is_finite()) {
            return Err(problem(Some(k), "not a finite number".into()));
        }
        let angle = |k: usize| -> std::result::Result<f64, RotationProblem> {
            let v = values[k];
            if self.in_degrees() {
                if v.abs() > MAX_DEGREES {
                    return Err(problem(
                        Some(k),
                        format!(
                            "{v}° is more than a turn: not an orientation angle in degrees (a column of another kind?)"
                        ),
                    ));
                }
                Ok(v.to_radians())
            } else {
                if v.abs() > MAX_RADIANS {
                    return Err(problem(
                        Some(k),
                        format!(
                            "{v} rad ({:.0}°) is more than a turn: `{}` is in radians (degrees given? `rpy-deg` reads roll, pitch, yaw in degrees)",
                            v.to_degrees(),
                            self.name()
                        ),
                    ));
                }
                Ok(v)
            }
        };
        let (x, y, z) = (Vector3::x_axis(), Vector3::y_axis(), Vector3::z_axis());
        let about = |axis, k: usize| angle(k).map(|a| Rotation3::from_axis_angle(&axis, a));
        let r = match self {
            Self::QuaternionXyzw => quaternion(values[3], values[0], values[1], values[2])?,
            Self::QuaternionWxyz => quaternion(values[0], values[1], values[2], values[3])?,
            Self::Rvec => {
                let w = Vector3::new(values[0], values[1], values[2]);
                if w.norm() > MAX_RADIANS {
                    return Err(problem(
                        None,
                        format!(
                            "a rotation of {:.1} rad ({:.0}°) is more than a turn: `rvec` is in radians (degrees given?)",
                            w.norm(),
                            w.norm().to_degrees()
                        ),
                    ));
                }
                Rotation3::new(w)
            }
            Self::KukaAbc => about(z, 0)? * about(y, 1)? * about(x, 2)?,
            Self::MitsubishiAbc => about(z, 2)? * about(y, 1)? * about(x, 0)?,
            Self::FanucWpr | Self::YaskawaRxryrz | Self::Rpy | Self::RpyDeg => {
                about(z, 2)? * about(y, 1)? * about(x, 0)?
            }
            Self::StaubliXyz => about(x, 0)? * about(y, 1)? * about(z, 2)?,
            Self::KawasakiOat => about(z, 0)? * about(y, 1)? * about(z, 2)?,
        };
        Ok(*r.matrix())
    }
}

/// The rotation of the quaternion `w + xi + yj + zk`, normalised when its norm is within
/// [`QUATERNION_NORM_TOL`] of 1.
fn quaternion(
    w: f64,
    x: f64,
    y: f64,
    z: f64,
) -> std::result::Result<Rotation3<f64>, RotationProblem> {
    let q = Quaternion::new(w, x, y, z);
    let norm = q.norm();
    if norm.is_nan() || (norm - 1.0).abs() > QUATERNION_NORM_TOL {
        return Err(RotationProblem {
            component: None,
            message: format!("quaternion norm is {norm:.6}, not within 1e-3 of 1"),
        });
    }
    Ok(UnitQuaternion::from_quaternion(q).to_rotation_matrix())
}

/// The rotation conventions of an input's two sides, where they are named: the robot poses
/// (`base_from_gripper` / `gripper_from_base`, the `--robot` stream) and the camera poses
/// (`camera_from_target` / `target_from_camera`, the `--camera` stream). A side not named is read
/// as its numbers say: a quaternion `x y z w` in positional inputs (streams, CSV columns), the
/// field's own convention in JSON.
///
/// # Example
/// ```
/// use handeye::{RotationConvention, Rotations};
/// let r = Rotations::parse(&["robot=kuka-abc", "camera=rvec"])?;
/// assert_eq!(r.robot, Some(RotationConvention::KukaAbc));
/// assert_eq!(r.camera, Some(RotationConvention::Rvec));
/// let both = Rotations::parse(&["fanuc-wpr"])?;
/// assert_eq!(both.robot, both.camera);
/// assert!(Rotations::parse(&["kuka-abc", "camera=rvec"]).is_err());
/// # Ok::<(), handeye::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct Rotations {
    /// The robot poses' convention, if named.
    pub robot: Option<RotationConvention>,
    /// The camera poses' convention, if named.
    pub camera: Option<RotationConvention>,
}

impl Rotations {
    /// Parses the conventions as the faces take them: `NAME` for both sides, `robot=NAME` or
    /// `camera=NAME` for one; each side at most once. An unknown name, side or a side named twice
    /// is an [`Error::InvalidParameter`] `rotation`.
    pub fn parse<S: AsRef<str>>(specs: &[S]) -> Result<Self> {
        let mut out = Self::default();
        let invalid = |message: String| Error::InvalidParameter {
            name: "rotation",
            message,
        };
        for spec in specs {
            let spec = spec.as_ref().trim();
            let (sides, name): (&[bool], &str) = match spec.split_once('=') {
                None => (&[true, false], spec),
                Some(("robot", name)) => (&[true], name),
                Some(("camera", name)) => (&[false], name),
                Some((side, _)) => {
                    return Err(invalid(format!(
                        "unknown side `{side}` in `{spec}`: NAME for every pose, or robot=NAME or camera=NAME for one side"
                    )));
                }
            };
            let convention: RotationConvention = name.trim().parse()?;
            for &robot in sides {
                let slot = if robot {
                    &mut out.robot
                } else {
                    &mut out.camera
                };
                if slot.is_some() {
                    return Err(invalid(format!(
                        "the {} poses' convention is given twice (`{spec}` after another): name each side once, e.g. robot=kuka-abc and camera=rvec",
                        if robot { "robot" } else { "camera" }
                    )));
                }
                *slot = Some(convention);
            }
        }
        Ok(out)
    }

    /// Both sides in `convention`.
    pub fn both(convention: RotationConvention) -> Self {
        Self {
            robot: Some(convention),
            camera: Some(convention),
        }
    }

    /// Whether either side is named.
    pub fn is_named(self) -> bool {
        self.robot.is_some() || self.camera.is_some()
    }

    /// How the faces spell naming `convention` for one side, or for both when the other side is
    /// named the same or not at all: the command line's flag and Python's keyword.
    pub(crate) fn flag(convention: RotationConvention, side: Option<bool>) -> String {
        let spec = match side {
            None => convention.name().to_string(),
            Some(true) => format!("robot={}", convention.name()),
            Some(false) => format!("camera={}", convention.name()),
        };
        Self::flag_words(&spec)
    }

    /// How the faces spell naming the conventions `spec` (`kuka-abc`, `robot=rvec`): the command
    /// line's flag and Python's keyword.
    pub(crate) fn flag_words(spec: &str) -> String {
        format!("`--rotation {spec}` (`rotation=\"{spec}\"` in Python)")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &Matrix3<f64>, b: &Matrix3<f64>) -> bool {
        (a - b).abs().max() < 1e-15
    }

    #[test]
    fn single_angles_turn_about_their_axes() {
        let rz = |d: f64| *Rotation3::from_axis_angle(&Vector3::z_axis(), d.to_radians()).matrix();
        let ry = |d: f64| *Rotation3::from_axis_angle(&Vector3::y_axis(), d.to_radians()).matrix();
        let rx = |d: f64| *Rotation3::from_axis_angle(&Vector3::x_axis(), d.to_radians()).matrix();
        use RotationConvention::*;
        for (c, values, want) in [
            (KukaAbc, [30.0, 0.0, 0.0], rz(30.0)),
            (KukaAbc, [0.0, 0.0, 30.0], rx(30.0)),
            (MitsubishiAbc, [30.0, 0.0, 0.0], rx(30.0)),
            (MitsubishiAbc, [0.0, 0.0, 30.0], rz(30.0)),
            (FanucWpr, [30.0, 0.0, 0.0], rx(30.0)),
            (FanucWpr, [0.0, 0.0, 30.0], rz(30.0)),
            (StaubliXyz, [0.0, 30.0, 0.0], ry(30.0)),
            (KawasakiOat, [0.0, 0.0, 30.0], rz(30.0)),
            (RpyDeg, [0.0, 30.0, 0.0], ry(30.0)),
            (Rpy, [0.0, 0.0, 30f64.to_radians()], rz(30.0)),
        ] {
            assert!(close(&c.rotation(&values).unwrap(), &want), "{c}");
        }
    }

    #[test]
    fn units_beyond_a_turn_are_named() {
        use RotationConvention::*;
        let e = Rpy.rotation(&[0.1, 90.0, 0.0]).unwrap_err();
        assert_eq!(e.component, Some(1));
        assert!(e.message.contains("degrees given?"), "{e:?}");
        let e = KukaAbc.rotation(&[0.0, 0.0, 450.0]).unwrap_err();
        assert_eq!(e.component, Some(2));
        assert!(e.message.contains("more than a turn"), "{e:?}");
        let e = Rvec.rotation(&[0.0, 90.0, 0.0]).unwrap_err();
        assert!(e.message.contains("degrees given?"), "{e:?}");
        let e = QuaternionWxyz.rotation(&[2.0, 0.0, 0.0, 0.0]).unwrap_err();
        assert!(e.message.contains("norm"), "{e:?}");
        assert!(KukaAbc.rotation(&[0.0, 0.0]).is_err());
        assert_eq!(
            KukaAbc
                .rotation(&[0.0, f64::NAN, 0.0])
                .unwrap_err()
                .component,
            Some(1)
        );
    }

    #[test]
    fn components_tell_candidates() {
        use RotationConvention::*;
        assert_eq!(
            RotationConvention::with_components(&["a", "b", "c"]),
            [KukaAbc, MitsubishiAbc]
        );
        assert_eq!(
            RotationConvention::with_components(&["rz", "ry", "rx"]),
            [Rvec, YaskawaRxryrz, StaubliXyz]
        );
        assert_eq!(
            RotationConvention::with_components(&["w", "p", "r"]),
            [FanucWpr]
        );
        assert!(RotationConvention::with_components(&["a", "b"]).is_empty());
    }

    #[test]
    fn sides_parse_once_each() {
        use RotationConvention::*;
        assert_eq!(Rotations::parse::<&str>(&[]).unwrap(), Rotations::default());
        assert_eq!(
            Rotations::parse(&["camera=quaternion-wxyz"]).unwrap(),
            Rotations {
                robot: None,
                camera: Some(QuaternionWxyz)
            }
        );
        for bad in [
            &["tool=rvec"][..],
            &["kuka"],
            &["robot=rvec", "robot=rvec"],
            &["rvec", "rvec"],
        ] {
            let e = Rotations::parse(bad).unwrap_err();
            assert!(
                matches!(
                    e,
                    Error::InvalidParameter {
                        name: "rotation",
                        ..
                    }
                ),
                "{e:?}"
            );
        }
    }
}
