//! `--rotation` on the command line (issue 33 item 11): vendor conventions are read when named,
//! refused with the flag named when not, and every mix-up (a wrong convention, radians for degrees,
//! degrees for radians, a field of another convention) ends in words that name the fix, never in
//! a silent answer.

mod common;

use std::path::{Path, PathBuf};

use common::{run, shared, testdata};
use nalgebra::{Quaternion, Rotation3, UnitQuaternion, Vector3};

/// A pose as `x y z` and its rotation in `convention` (KUKA A, B, C or roll, pitch, yaw, from
/// nalgebra's `euler_angles`: R = Rz(yaw)·Ry(pitch)·Rx(roll)), joined by `sep`.
fn written(t: &Vector3<f64>, r: &Rotation3<f64>, convention: &str, sep: &str) -> String {
    let (roll, pitch, yaw) = r.euler_angles();
    let angles = match convention {
        "kuka-abc" => [yaw, pitch, roll].map(f64::to_degrees),
        "kuka-abc-in-radians" => [yaw, pitch, roll],
        "rpy-deg" => [roll, pitch, yaw].map(f64::to_degrees),
        other => panic!("{other}"),
    };
    [t.x, t.y, t.z]
        .into_iter()
        .chain(angles)
        .map(|v| format!("{v:?}"))
        .collect::<Vec<_>>()
        .join(sep)
}

/// A TUM stream's samples: stamp, translation, rotation.
fn tum(path: &Path) -> Vec<(f64, Vector3<f64>, Rotation3<f64>)> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .map(|l| {
            let v: Vec<f64> = l
                .split(|c: char| c == ',' || c.is_whitespace())
                .filter(|s| !s.is_empty())
                .map(|s| s.parse().unwrap())
                .collect();
            let q = UnitQuaternion::from_quaternion(Quaternion::new(v[7], v[4], v[5], v[6]));
            (v[0], Vector3::new(v[1], v[2], v[3]), q.to_rotation_matrix())
        })
        .collect()
}

/// The robot stream of a kinhec recording rewritten in `convention`, in `dir`.
fn robot_stream(dir: &Path, convention: &str) -> PathBuf {
    let text: String = tum(&testdata("kinhec/streams/temporal_10hz_eih_s0_robot.txt"))
        .iter()
        .map(|(t, p, r)| format!("{t:?} {}\n", written(p, r, convention, " ")))
        .collect();
    let path = dir.join(format!("robot_{convention}.txt"));
    std::fs::write(&path, text).unwrap();
    path
}

/// A kinhec pose file rewritten as CSV, both sides in `convention`, its columns lettered `letters`.
fn csv(dir: &Path, convention: &str, letters: [&str; 3]) -> PathBuf {
    csv_sides(dir, [convention, convention], letters)
}

/// [`csv`] with the robot's and the camera's conventions.
fn csv_sides(dir: &Path, conventions: [&str; 2], letters: [&str; 3]) -> PathBuf {
    let source = handeye::io::Source::File {
        path: testdata("kinhec/pairs/nominal_stations_eih_s0.jsonl"),
        format: handeye::io::Format::Auto,
    };
    let series = handeye::io::Recording::read(&source, &Default::default()).unwrap();
    let columns = |frame: &str| {
        ["x", "y", "z"]
            .iter()
            .chain(&letters)
            .map(|s| format!("{frame}_{s}"))
            .collect::<Vec<_>>()
            .join(",")
    };
    let mut text = format!(
        "{},{}\n",
        columns("base_from_gripper"),
        columns("camera_from_target")
    );
    for p in &series.poses {
        let side = |t: &handeye::Transform, convention: &str| {
            written(&t.translation.vector, &t.rotation, convention, ",")
        };
        text.push_str(&format!(
            "{},{}\n",
            side(&p.base_from_gripper, conventions[0]),
            side(&p.camera_from_target, conventions[1])
        ));
    }
    let path = dir.join(format!(
        "{}_{}.csv",
        conventions.join("_"),
        letters.concat()
    ));
    std::fs::write(&path, text).unwrap();
    path
}

/// X's translation and quaternion from `calibrate`'s JSON.
fn x_of(stdout: &str) -> Vec<f64> {
    let v: serde_json::Value = serde_json::from_str(stdout).unwrap();
    let mut x: Vec<f64> = serde_json::from_value(v["translation"].clone()).unwrap();
    x.extend(serde_json::from_value::<Vec<f64>>(v["quaternion_xyzw"].clone()).unwrap());
    x
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn a_kuka_stream_needs_the_flag_and_then_gives_the_x_of_the_original() {
    let dir = tempfile::tempdir().unwrap();
    let kuka = robot_stream(dir.path(), "kuka-abc");
    let tum_robot = testdata("kinhec/streams/temporal_10hz_eih_s0_robot.txt");
    let camera = testdata("kinhec/streams/temporal_10hz_eih_s0_camera.txt");
    let (code, _, err) = run(&["calibrate", "--robot", s(&kuka), "--camera", s(&camera)]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("7 values, expected 8"), "{err}");
    assert!(err.contains("`--rotation NAME`"), "{err}");
    assert!(err.contains("robot=NAME"), "{err}");
    let (code, original, err) = run(&[
        "calibrate",
        "--robot",
        s(&tum_robot),
        "--camera",
        s(&camera),
    ]);
    assert_eq!(code, 0, "{err}");
    for args in [
        vec!["--rotation", "robot=kuka-abc"],
        vec![
            "--rotation",
            "robot=kuka-abc",
            "--rotation",
            "camera=quaternion-xyzw",
        ],
    ] {
        let mut all = vec!["calibrate", "--robot", s(&kuka), "--camera", s(&camera)];
        all.extend(args);
        let (code, out, err) = run(&all);
        assert_eq!(code, 0, "{err}");
        let (a, b) = (x_of(&original), x_of(&out));
        let d = a
            .iter()
            .zip(&b)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(d < 1e-9, "{all:?}: {a:?} {b:?}");
    }
    // The same flag on every command that reads poses.
    let (code, _, err) = run(&[
        "online",
        "--robot",
        s(&kuka),
        "--camera",
        s(&camera),
        "--rotation",
        "robot=kuka-abc",
    ]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = run(&[
        "advise",
        "--robot",
        s(&kuka),
        "--camera",
        s(&camera),
        "--rotation",
        "robot=kuka-abc",
    ]);
    assert_eq!(code, 0, "{err}");
}

#[test]
fn columns_of_angles_name_the_conventions_they_may_be() {
    let dir = tempfile::tempdir().unwrap();
    let abc = csv(dir.path(), "kuka-abc", ["a", "b", "c"]);
    let (code, _, err) = run(&["calibrate", s(&abc)]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains(":1: field `base_from_gripper_a`"), "{err}");
    for words in [
        "`--rotation kuka-abc`",
        "`--rotation mitsubishi-abc`",
        "`rotation=\"kuka-abc\"` in Python",
    ] {
        assert!(err.contains(words), "{words}: {err}");
    }
    let rxyz = csv(dir.path(), "kuka-abc", ["rx", "ry", "rz"]);
    let (code, _, err) = run(&["calibrate", s(&rxyz)]);
    assert_eq!(code, 2, "{err}");
    for name in ["rvec", "yaskawa-rxryrz", "staubli-xyz"] {
        assert!(
            err.contains(&format!("`--rotation {name}`")),
            "{name}: {err}"
        );
    }
    // Named, they are read.
    let (code, _, err) = run(&["calibrate", s(&abc), "--rotation", "kuka-abc"]);
    assert_eq!(code, 0, "{err}");
    // Quaternion columns under an Euler name: the columns expected are named.
    let quaternion_csv = dir.path().join("q.csv");
    std::fs::write(
        &quaternion_csv,
        "base_from_gripper_x,base_from_gripper_y,base_from_gripper_z,base_from_gripper_qx,base_from_gripper_qy,base_from_gripper_qz,base_from_gripper_qw,camera_from_target_x,camera_from_target_y,camera_from_target_z,camera_from_target_qx,camera_from_target_qy,camera_from_target_qz,camera_from_target_qw\n0,0,0,0,0,0,1,0,0,1,0,0,0,1\n0,0,1,0,0,0,1,0,0,2,0,0,0,1\n",
    )
    .unwrap();
    let (code, _, err) = run(&["calibrate", s(&quaternion_csv), "--rotation", "kuka-abc"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("field `base_from_gripper_qx`")
            && err.contains("named kuka-abc, which reads `base_from_gripper_a`, `_b`, `_c`"),
        "{err}"
    );
}

#[test]
fn a_json_field_of_another_convention_is_refused_under_a_name() {
    let file = testdata("kinhec/pairs/nominal_stations_eih_s1.jsonl");
    let (code, _, err) = run(&["calibrate", s(&file), "--rotation", "kuka-abc"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains(":1: field `base_from_gripper.quaternion_xyzw`")
            && err.contains("write it as `kuka_abc_deg`")
            && err.contains("a field named for its convention needs none"),
        "{err}"
    );
    // A matrix has no convention: read under any name.
    let matrices = testdata("kinhec/pairs/nominal_stations_eih_s0.jsonl");
    let (code, _, err) = run(&["calibrate", s(&matrices), "--rotation", "kuka-abc"]);
    assert_eq!(code, 0, "{err}");
}

#[test]
fn the_wrong_convention_is_refused_naming_the_right_one() {
    let dir = tempfile::tempdir().unwrap();
    // KUKA's A, B, C read as Mitsubishi's (the same letters, the other order).
    let abc = csv(dir.path(), "kuka-abc", ["a", "b", "c"]);
    let (code, out, err) = run(&["calibrate", s(&abc), "--rotation", "mitsubishi-abc"]);
    assert_eq!(code, 3, "{err}");
    assert!(out.is_empty(), "{out}");
    assert!(
        err.contains("numbers read as kuka-abc")
            && err.contains("rather than mitsubishi-abc")
            && err.contains("`--rotation kuka-abc`"),
        "{err}"
    );
    // KUKA's A, B, C under FANUC's letters and name.
    let wpr = csv(dir.path(), "kuka-abc", ["w", "p", "r"]);
    let (code, _, err) = run(&["calibrate", s(&wpr), "--rotation", "fanuc-wpr"]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("`--rotation kuka-abc`")
            && err.contains("the robot and camera columns then end in `_a`, `_b`, `_c`"),
        "{err}"
    );
    // KUKA robot poses and a camera's roll, pitch, yaw under one name: the camera's side alone is
    // named otherwise, the robot's kept.
    let mixed = csv_sides(dir.path(), ["kuka-abc", "rpy-deg"], ["a", "b", "c"]);
    let (code, _, err) = run(&["calibrate", s(&mixed), "--rotation", "kuka-abc"]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("the camera poses' numbers read as mitsubishi-abc")
            && err.contains("`--rotation robot=kuka-abc --rotation camera=mitsubishi-abc`")
            && err.contains("`rotation=[\"robot=kuka-abc\", \"camera=mitsubishi-abc\"]` in Python"),
        "{err}"
    );
    // A KUKA robot stream named FANUC's: the robot's side is named.
    let kuka = robot_stream(dir.path(), "kuka-abc");
    let camera = testdata("kinhec/streams/temporal_10hz_eih_s0_camera.txt");
    let (code, _, err) = run(&[
        "calibrate",
        "--robot",
        s(&kuka),
        "--camera",
        s(&camera),
        "--rotation",
        "robot=fanuc-wpr",
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("`--rotation robot=kuka-abc`"), "{err}");
}

#[test]
fn radians_for_degrees_and_degrees_for_radians_are_told() {
    let dir = tempfile::tempdir().unwrap();
    // Radians under a convention in degrees: every angle within ±2π, the poses turn by a few
    // degrees; a note says so before the refusal of motions that small.
    let radians = csv(dir.path(), "kuka-abc-in-radians", ["a", "b", "c"]);
    let (code, _, err) = run(&["calibrate", s(&radians), "--rotation", "kuka-abc"]);
    assert_ne!(code, 0, "{err}");
    assert!(
        err.contains("every robot angle given in degrees is within ±3.1")
            && err.contains("if these are radians, convert them to degrees"),
        "{err}"
    );
    // Degrees under a convention in radians: refused at the first angle beyond a turn.
    let degrees = csv(dir.path(), "rpy-deg", ["roll", "pitch", "yaw"]);
    let (code, _, err) = run(&["calibrate", s(&degrees), "--rotation", "rpy"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("is more than a turn: `rpy` is in radians (degrees given? `rpy-deg`"),
        "{err}"
    );
    let (code, _, err) = run(&["calibrate", s(&degrees), "--rotation", "rpy-deg"]);
    assert_eq!(code, 0, "{err}");
}

#[test]
fn inputs_that_fix_their_own_rotations_refuse_a_name() {
    for args in [
        vec![
            "calibrate",
            "testdata-bag",
            "--base-frame",
            "base_link",
            "--gripper-frame",
            "tool0",
            "--camera-frame",
            "camera_color_optical_frame",
            "--target-frame",
            "board",
            "--rotation",
            "kuka-abc",
        ],
        vec!["calibrate", "testdata-yaml", "--rotation", "rvec"],
    ] {
        let bag = testdata("rosbag/eih_tf_mcap");
        let yaml = if args.contains(&"testdata-yaml") {
            let Some(yaml) = shared("camodocal/TransformPairsInput.yml") else {
                continue;
            };
            yaml
        } else {
            Default::default()
        };
        let args: Vec<&str> = args
            .iter()
            .map(|a| match *a {
                "testdata-bag" => s(&bag),
                "testdata-yaml" => s(&yaml),
                a => a,
            })
            .collect();
        let (code, _, err) = run(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains("drop `--rotation`"), "{err}");
    }
    let (code, _, err) = run(&[
        "calibrate",
        s(&testdata("kinhec/pairs/nominal_stations_eih_s0.jsonl")),
        "--rotation",
        "kuka-abc",
        "--rotation",
        "camera=rvec",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("given twice"), "{err}");
}
