//! Rotations as engineers write them (issue 33 item 11): every named convention read through every
//! input it applies to (a JSON field, a stamped stream, CSV columns) gives SciPy's matrix for the
//! same numbers (`testdata/rotation/fixtures.json`, made by `make_fixtures.py`), ABB's worked
//! example reads as ABB says, and a realistic recording rewritten in the vendors' conventions
//! calibrates to the X of the original.

use std::path::{Path, PathBuf};

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use serde_json::{Value, json};

use handeye::io::{
    Format, PoseReader, Recording, RecordingOptions, Source, TimeOffset, read_stamped_poses,
    transform_from_json,
};
use handeye::{Options, PosePair, RotationConvention, Rotations, Setup, Transform, calibrate};

fn testdata(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata")
        .join(rel)
}

/// A fixture: the values as written, SciPy's matrix.
type Case = (Vec<f64>, Matrix3<f64>);

/// The fixtures: each convention's cases.
fn fixtures() -> Vec<(RotationConvention, Vec<Case>)> {
    let text = std::fs::read_to_string(testdata("rotation/fixtures.json")).unwrap();
    let doc: Value = serde_json::from_str(&text).unwrap();
    let conventions = doc["conventions"].as_object().unwrap();
    conventions
        .iter()
        .map(|(name, cases)| {
            let convention: RotationConvention = name.parse().unwrap();
            let cases = cases
                .as_array()
                .unwrap()
                .iter()
                .map(|case| {
                    let values: Vec<f64> = serde_json::from_value(case["values"].clone()).unwrap();
                    let rows: [[f64; 3]; 3] =
                        serde_json::from_value(case["matrix"].clone()).unwrap();
                    let m = Matrix3::from_fn(|r, c| rows[r][c]);
                    (values, m)
                })
                .collect();
            (convention, cases)
        })
        .collect()
}

fn rotation_of(t: &Transform) -> Matrix3<f64> {
    *t.rotation.matrix()
}

/// A number as Rust prints it: the shortest text that reads back to the same double.
fn num(v: f64) -> String {
    format!("{v:?}")
}

#[test]
fn every_convention_reads_to_scipys_matrix_in_every_input() {
    let fixtures = fixtures();
    let named: Vec<RotationConvention> = fixtures.iter().map(|(c, _)| *c).collect();
    for c in RotationConvention::ALL {
        assert!(named.contains(&c), "{c} has no fixture");
    }
    let dir = tempfile::tempdir().unwrap();
    let mut worst = 0.0f64;
    for (convention, cases) in &fixtures {
        let parts = convention.components();
        // A JSON transform with the convention's own field: no name needed.
        for (values, want) in cases {
            let t = transform_from_json(
                &json!({"translation": [0.1, -0.2, 0.3], convention.json_field(): values}),
            )
            .unwrap_or_else(|e| panic!("{convention} {values:?}: {e:?}"));
            let d = (rotation_of(&t) - want).abs().max();
            worst = worst.max(d);
            assert!(d < 1e-12, "{convention} JSON {values:?}: {d:e}");
        }
        // A stamped stream `t x y z` and the convention's numbers.
        let stream: String = cases
            .iter()
            .enumerate()
            .map(|(k, (values, _))| {
                let rest: Vec<String> = values.iter().map(|v| num(*v)).collect();
                format!("{k} 0.1 -0.2 0.3 {}\n", rest.join(" "))
            })
            .collect();
        let path = dir.path().join(format!("{convention}.txt"));
        std::fs::write(&path, stream).unwrap();
        let read = read_stamped_poses(&path, Some(*convention)).unwrap();
        assert_eq!(read.poses.len(), cases.len());
        for (pose, (values, want)) in read.poses.iter().zip(cases) {
            let d = (rotation_of(&pose.pose) - want).abs().max();
            worst = worst.max(d);
            assert!(d < 1e-12, "{convention} stream {values:?}: {d:e}");
        }
        // CSV columns named by the convention's letters, both sides.
        let columns = |frame: &str| -> Vec<String> {
            ["x", "y", "z"]
                .iter()
                .chain(parts)
                .map(|s| format!("{frame}_{s}"))
                .collect()
        };
        let mut csv = [columns("base_from_gripper"), columns("camera_from_target")]
            .concat()
            .join(",");
        csv.push('\n');
        for (values, _) in cases {
            let rotation: Vec<String> = values.iter().map(|v| num(*v)).collect();
            let pose = format!("0.1,-0.2,0.3,{}", rotation.join(","));
            csv.push_str(&format!("{pose},{pose}\n"));
        }
        let reader = PoseReader::with_rotations(
            csv.as_bytes(),
            "f.csv",
            Format::Csv,
            Rotations::both(*convention),
        )
        .unwrap();
        let records: Vec<_> = reader.collect::<Result<_, _>>().unwrap();
        for (record, (values, want)) in records.iter().zip(cases) {
            for t in [
                record.pose.base_from_gripper,
                record.pose.camera_from_target,
            ] {
                let d = (rotation_of(&t) - want).abs().max();
                worst = worst.max(d);
                assert!(d < 1e-12, "{convention} CSV {values:?}: {d:e}");
            }
        }
    }
    eprintln!(
        "{} rotations of {} conventions, largest entry difference from SciPy {worst:.1e}",
        fixtures.iter().map(|(_, c)| c.len()).sum::<usize>(),
        fixtures.len()
    );
}

#[test]
fn abbs_worked_example_reads_as_abb_says() {
    // ABB RAPID Reference Manual, data type `orient`, example 1: the tool's z axis along the base
    // x axis, its y axis the base y axis, is [q1, q2, q3, q4] = [0.707107, 0, 0.707107, 0].
    // As ABB prints it, six decimals (a norm 2e-7 off 1: normalised).
    let abb = r#"{"translation": [0, 0, 0], "quaternion_wxyz": [0.707107, 0, 0.707107, 0]}"#;
    let t = transform_from_json(&serde_json::from_str(abb).unwrap()).unwrap();
    let r = rotation_of(&t);
    let z_tool = r.column(2).into_owned();
    let y_tool = r.column(1).into_owned();
    assert!((z_tool - Vector3::x()).norm() < 1e-6, "{r}");
    assert!((y_tool - Vector3::y()).norm() < 1e-6, "{r}");
    // The same numbers in x, y, z, w order are another rotation (about x and z): the order matters.
    let xyzw = abb.replace("quaternion_wxyz", "quaternion_xyzw");
    let wrong = transform_from_json(&serde_json::from_str(&xyzw).unwrap()).unwrap();
    assert!((rotation_of(&wrong) - r).abs().max() > 0.5);
}

#[test]
fn gimbal_lock_reads_one_rotation_for_its_many_angles() {
    // KUKA's B = ±90° (and FANUC's P): A and C turn about one axis, and only A − C (B = 90°) or
    // A + C (B = −90°) matter. The reading is a product of three rotations, which has no
    // singularity: every triple gives its rotation exactly.
    let read = |c: RotationConvention, v: [f64; 3]| {
        rotation_of(
            &transform_from_json(&json!({"translation": [0, 0, 0], c.json_field(): v})).unwrap(),
        )
    };
    let kuka = RotationConvention::KukaAbc;
    let d = (read(kuka, [30.0, 90.0, 10.0]) - read(kuka, [50.0, 90.0, 30.0]))
        .abs()
        .max();
    assert!(d < 1e-12, "{d:e}");
    let d = (read(kuka, [30.0, -90.0, 10.0]) - read(kuka, [50.0, -90.0, -10.0]))
        .abs()
        .max();
    assert!(d < 1e-12, "{d:e}");
    // And it is the rotation of the gripper whose x axis points along the base's −z (B = 90°).
    let r = read(kuka, [0.0, 90.0, 0.0]);
    assert!(
        (r.column(0) - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-15,
        "{r}"
    );
    let fanuc = RotationConvention::FanucWpr;
    let d = (read(fanuc, [10.0, 90.0, 30.0]) - read(fanuc, [30.0, 90.0, 50.0]))
        .abs()
        .max();
    assert!(d < 1e-12, "{d:e}");
}

/// A rotation written in `convention` by nalgebra's own decompositions (independent of the
/// readers, which compose): Euler angles from `Rotation3::euler_angles` (roll about x, pitch about
/// y, yaw about z, fixed axes), the quaternion of `UnitQuaternion`, the rotation vector from it.
fn written(convention: RotationConvention, r: &Matrix3<f64>) -> Vec<f64> {
    let rotation = Rotation3::from_matrix_unchecked(*r);
    let (roll, pitch, yaw) = rotation.euler_angles();
    let deg = |v: [f64; 3]| v.map(f64::to_degrees).to_vec();
    match convention {
        RotationConvention::KukaAbc => deg([yaw, pitch, roll]),
        RotationConvention::FanucWpr => deg([roll, pitch, yaw]),
        RotationConvention::QuaternionWxyz => {
            let q = UnitQuaternion::from_rotation_matrix(&rotation);
            vec![q.w, q.i, q.j, q.k]
        }
        RotationConvention::Rvec => {
            // From the quaternion with atan2: `scaled_axis` takes an acos, 1e-8 off near 0 and π.
            let q = UnitQuaternion::from_rotation_matrix(&rotation);
            let (w, v) = if q.w < 0.0 {
                (-q.w, -q.imag())
            } else {
                (q.w, q.imag())
            };
            let s = v.norm();
            let w = if s > 0.0 {
                v * (2.0 * s.atan2(w) / s)
            } else {
                v * 2.0
            };
            vec![w.x, w.y, w.z]
        }
        other => panic!("no writer for {other}"),
    }
}

/// The four conventions of the end-to-end test.
const REWRITTEN: [RotationConvention; 4] = [
    RotationConvention::KukaAbc,
    RotationConvention::FanucWpr,
    RotationConvention::QuaternionWxyz,
    RotationConvention::Rvec,
];

fn read(source: &Source, rotations: Rotations) -> Recording {
    // Two streams are paired at a clock offset of 0 (the test's files share one clock); a pose
    // file takes none.
    let options = RecordingOptions {
        rotations,
        time_offset: matches!(source, Source::Streams { .. }).then_some(TimeOffset::Fixed(0.0)),
        ..RecordingOptions::default()
    };
    Recording::read(source, &options).unwrap_or_else(|e| panic!("{source:?}: {e}"))
}

fn x_of(recording: &Recording) -> Transform {
    let options = Options {
        written: recording.written,
        replicates: 8,
        ..Options::default()
    };
    let report = calibrate(&recording.poses, Setup::EyeInHand, &options)
        .map(|r| r.into_hand_eye().expect("the hand–eye report"))
        .unwrap();
    transform_from_json(&serde_json::to_value(&report.x).unwrap()).unwrap()
}

/// The rotation between two X (radians) and their translations' difference over the first's
/// length.
fn difference(a: &Transform, b: &Transform) -> (f64, f64) {
    let angle = handeye::model::pose::rotation_angle_between(&a.rotation, &b.rotation);
    let t = (a.translation.vector - b.translation.vector).norm() / a.translation.vector.norm();
    (angle, t)
}

fn pose_text(t: &Transform, convention: RotationConvention, sep: &str) -> String {
    let v = t.translation.vector;
    [v.x, v.y, v.z]
        .into_iter()
        .chain(written(convention, &rotation_of(t)))
        .map(num)
        .collect::<Vec<_>>()
        .join(sep)
}

#[test]
fn a_recording_rewritten_in_each_vendors_convention_calibrates_to_the_same_x() {
    let dir = tempfile::tempdir().unwrap();
    let original = Source::File {
        path: testdata("kinhec/pairs/nominal_stations_eih_s0.jsonl"),
        format: Format::Auto,
    };
    let recording = read(&original, Rotations::default());
    let x = x_of(&recording);
    let poses: &[PosePair] = &recording.poses;
    let mut worst = (0.0f64, 0.0f64);
    let mut check = |what: &str, r: &Recording| {
        assert_eq!(r.poses.len(), poses.len(), "{what}");
        let (angle, t) = difference(&x, &x_of(r));
        worst = (worst.0.max(angle), worst.1.max(t));
        assert!(angle < 1e-9 && t < 1e-9, "{what}: {angle:e} rad, {t:e}");
    };
    for convention in REWRITTEN {
        // CSV, both sides in the convention, named.
        let letters = |frame: &str| -> Vec<String> {
            ["x", "y", "z"]
                .iter()
                .chain(convention.components())
                .map(|s| format!("{frame}_{s}"))
                .collect()
        };
        let mut csv = [letters("base_from_gripper"), letters("camera_from_target")]
            .concat()
            .join(",");
        csv.push('\n');
        for p in poses {
            csv.push_str(&format!(
                "{},{}\n",
                pose_text(&p.base_from_gripper, convention, ","),
                pose_text(&p.camera_from_target, convention, ",")
            ));
        }
        let path = dir.path().join(format!("{convention}.csv"));
        std::fs::write(&path, csv).unwrap();
        let source = Source::File {
            path,
            format: Format::Auto,
        };
        check(
            &format!("{convention} CSV"),
            &read(&source, Rotations::both(convention)),
        );
        // JSON Lines with the convention's field, the camera inverted (`target_from_camera`):
        // no name needed.
        let field = |t: &Transform| {
            let v = t.translation.vector;
            json!({"translation": [v.x, v.y, v.z], convention.json_field(): written(convention, &rotation_of(t))})
        };
        let jsonl: String = poses
            .iter()
            .map(|p| {
                format!(
                    "{}\n",
                    json!({
                        "base_from_gripper": field(&p.base_from_gripper),
                        "target_from_camera": field(&p.camera_from_target.inverse()),
                    })
                )
            })
            .collect();
        let path = dir.path().join(format!("{convention}.jsonl"));
        std::fs::write(&path, jsonl).unwrap();
        let source = Source::File {
            path,
            format: Format::Auto,
        };
        check(
            &format!("{convention} JSON Lines"),
            &read(&source, Rotations::default()),
        );
        // With the name given too, the field must be the named one's.
        check(
            &format!("{convention} JSON Lines, named"),
            &read(&source, Rotations::both(convention)),
        );
    }
    // The same recording as SciPy rewrote it (`testdata/rotation/make_fixtures.py`): KUKA columns,
    // and JSON fields of KUKA angles and ABB-ordered quaternions.
    for (file, rotations) in [
        (
            "rotation/kuka_abc_stations_eih_s0.csv",
            Rotations::both(RotationConvention::KukaAbc),
        ),
        (
            "rotation/vendor_fields_stations_eih_s0.jsonl",
            Rotations::default(),
        ),
    ] {
        let source = Source::File {
            path: testdata(file),
            format: Format::Auto,
        };
        check(file, &read(&source, rotations));
    }
    // Two stamped streams: a KUKA robot and a camera as ABB-ordered quaternions, against the same
    // streams as TUM writes them.
    let streams = |robot: &Path, camera: &Path| Source::Streams {
        robot: robot.to_path_buf(),
        camera: camera.to_path_buf(),
    };
    let tum_robot = testdata("kinhec/streams/temporal_10hz_eih_s0_robot.txt");
    let tum_camera = testdata("kinhec/streams/temporal_10hz_eih_s0_camera.txt");
    let tum = read(&streams(&tum_robot, &tum_camera), Rotations::default());
    let x_tum = x_of(&tum);
    for (named, convention, file) in [
        (Some(true), RotationConvention::KukaAbc, &tum_robot),
        (Some(false), RotationConvention::QuaternionWxyz, &tum_camera),
    ] {
        let stream = read_stamped_poses(file, None).unwrap();
        let text: String = stream
            .poses
            .iter()
            .map(|s| format!("{} {}\n", num(s.stamp), pose_text(&s.pose, convention, " ")))
            .collect();
        let path = dir.path().join(format!("{named:?}.txt"));
        std::fs::write(&path, text).unwrap();
    }
    let kuka_robot = dir.path().join("Some(true).txt");
    let abb_camera = dir.path().join("Some(false).txt");
    let rotations = Rotations::parse(&["robot=kuka-abc", "camera=quaternion-wxyz"]).unwrap();
    let rewritten = read(&streams(&kuka_robot, &abb_camera), rotations);
    assert_eq!(rewritten.poses.len(), tum.poses.len());
    let (angle, t) = difference(&x_tum, &x_of(&rewritten));
    assert!(angle < 1e-9 && t < 1e-9, "streams: {angle:e} rad, {t:e}");
    eprintln!(
        "X of the rewritten recordings: at most {:.1e} rad and {:.1e} (relative) from the original's; streams {angle:.1e} rad, {t:.1e}",
        worst.0, worst.1
    );
    // Unnamed, the KUKA stream's 7 columns are refused, naming the flag.
    let e = Recording::read(
        &streams(&kuka_robot, &tum_camera),
        &RecordingOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("7 values") && e.contains("--rotation"), "{e}");
}
