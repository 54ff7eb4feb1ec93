//! Poses as engineers have them (issue 33 items 10 and 11): moveit_calibration's "Save samples"
//! YAML, easy_handeye2's `.samples` (both setups), and JSON Lines transforms written as a flat
//! 16-list, a 3×4 matrix or a translation with a rotation vector. Each is written here in the
//! shape its tool writes (yaml-cpp's block style for moveit, rosidl's `message_to_yaml` for
//! easy_handeye2) from a realistic kinhec recording, read back by format detection alone, and must
//! give the same poses (to the digits printed) and the same X as the recording's JSON Lines.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use handeye::io::{Format, Recording, RecordingOptions, Source};
use handeye::{Error, Options, Pairing, PosePair, Setup, Transform, TransformJson, calibrate};

fn suite() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata/kinhec/pairs")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "handeye-peer-formats-{}-{name}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn read(path: &Path, setup: Setup) -> handeye::Result<Recording> {
    let source = Source::File {
        path: path.to_path_buf(),
        format: Format::Auto,
    };
    Recording::read(
        &source,
        &RecordingOptions {
            setup,
            ..RecordingOptions::default()
        },
    )
}

fn x_of(r: &Recording, setup: Setup) -> [[f64; 4]; 4] {
    calibrate(
        &r.poses,
        setup,
        &Options {
            pairing: Pairing::All,
            written: r.written,
            replicates: 32,
            ..Options::default()
        },
    )
    .map(|r| r.into_hand_eye().expect("the hand–eye report"))
    .unwrap()
    .x
    .matrix
}

fn flat(t: &Transform) -> Vec<f64> {
    TransformJson::from(t)
        .matrix
        .iter()
        .flatten()
        .copied()
        .collect()
}

/// Largest entry difference between two pose lists.
fn difference(a: &[PosePair], b: &[PosePair]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            let d = |s: &Transform, t: &Transform| {
                (s.to_homogeneous() - t.to_homogeneous()).abs().max()
            };
            d(&p.base_from_gripper, &q.base_from_gripper)
                .max(d(&p.camera_from_target, &q.camera_from_target))
        })
        .fold(0.0, f64::max)
}

fn moveit_yaml(poses: &[PosePair]) -> String {
    let mut text = String::new();
    for p in poses {
        for (k, (key, t)) in [
            ("effector_wrt_world", &p.base_from_gripper),
            ("object_wrt_sensor", &p.camera_from_target),
        ]
        .into_iter()
        .enumerate()
        {
            text.push_str(if k == 0 { "- " } else { "  " });
            writeln!(text, "{key}:").unwrap();
            for v in flat(t) {
                writeln!(text, "    - {v:?}").unwrap();
            }
        }
    }
    text
}

fn geometry_transform(text: &mut String, key: &str, t: &Transform, first: bool) {
    let j = TransformJson::from(t);
    text.push_str(if first { "- " } else { "  " });
    writeln!(text, "{key}:\n    translation:").unwrap();
    for (c, v) in ["x", "y", "z"].iter().zip(j.translation) {
        writeln!(text, "      {c}: {v:?}").unwrap();
    }
    text.push_str("    rotation:\n");
    for (c, v) in ["x", "y", "z", "w"].iter().zip(j.quaternion_xyzw) {
        writeln!(text, "      {c}: {v:?}").unwrap();
    }
}

/// easy_handeye2's samples: for `eye_on_base` its robot transform is looked up from the effector
/// to the base (`gripper_from_base`).
fn easy_handeye_samples(poses: &[PosePair], setup: Setup) -> String {
    let kind = match setup {
        Setup::EyeInHand => "eye_in_hand",
        Setup::EyeToHand => "eye_on_base",
    };
    let mut text = format!(
        "parameters:\n  name: cell\n  calibration_type: {kind}\n  robot_base_frame: base_link\n  robot_effector_frame: tool0\n  tracking_base_frame: camera_color_optical_frame\n  tracking_marker_frame: board\n  freehand_robot_movement: false\n  move_group_namespace: /\n  move_group: manipulator\nsamples:\n"
    );
    for p in poses {
        geometry_transform(
            &mut text,
            "robot",
            &setup.hand_pose(&p.base_from_gripper),
            true,
        );
        geometry_transform(&mut text, "tracking", &p.camera_from_target, false);
    }
    text
}

/// JSON Lines with each transform in another shape: a flat 16-list, a 3×4 matrix, or a
/// translation and a rotation vector.
fn jsonl_shapes(poses: &[PosePair]) -> String {
    let mut text = String::new();
    for (k, p) in poses.iter().enumerate() {
        let shape = |t: &Transform, which: usize| -> String {
            match (k + which) % 3 {
                0 => format!("{:?}", flat(t)),
                1 => format!("{:?}", flat(t)[..12].chunks(4).collect::<Vec<_>>()),
                _ => {
                    let w = t.rotation.scaled_axis();
                    let v = t.translation.vector;
                    format!(
                        "{{\"translation\": [{:?}, {:?}, {:?}], \"rvec\": [{:?}, {:?}, {:?}]}}",
                        v.x, v.y, v.z, w.x, w.y, w.z
                    )
                }
            }
        };
        writeln!(
            text,
            "{{\"base_from_gripper\": {}, \"camera_from_target\": {}}}",
            shape(&p.base_from_gripper, 0),
            shape(&p.camera_from_target, 1)
        )
        .unwrap();
    }
    text
}

#[test]
fn every_shape_gives_the_recordings_poses_and_its_x() {
    for (name, setup) in [
        ("nominal_stations_eih_s0", Setup::EyeInHand),
        ("nominal_stations_eth_s1", Setup::EyeToHand),
    ] {
        let original = read(&suite().join(format!("{name}.jsonl")), setup).unwrap();
        let x = x_of(&original, setup);
        let dir = scratch(name);
        for (file, text) in [
            ("samples.yaml", moveit_yaml(&original.poses)),
            ("cell.samples", easy_handeye_samples(&original.poses, setup)),
            ("shapes.jsonl", jsonl_shapes(&original.poses)),
        ] {
            let path = dir.join(file);
            std::fs::write(&path, text).unwrap();
            let read_back = read(&path, setup).unwrap_or_else(|e| panic!("{name} {file}: {e}"));
            let poses = difference(&read_back.poses, &original.poses);
            assert!(poses < 1e-12, "{name} {file}: poses differ by {poses}");
            let other = x_of(&read_back, setup);
            let dx = (0..16)
                .map(|k| (other[k / 4][k % 4] - x[k / 4][k % 4]).abs())
                .fold(0.0, f64::max);
            assert!(dx < 1e-9, "{name} {file}: X differs by {dx}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

#[test]
fn a_sample_file_for_the_other_setup_is_refused_with_its_line() {
    let original = read(
        &suite().join("nominal_stations_eth_s1.jsonl"),
        Setup::EyeToHand,
    )
    .unwrap();
    let dir = scratch("setup");
    let path = dir.join("cell.samples");
    std::fs::write(
        &path,
        easy_handeye_samples(&original.poses, Setup::EyeToHand),
    )
    .unwrap();
    match read(&path, Setup::EyeInHand) {
        Err(Error::Parse {
            line,
            field,
            message,
            ..
        }) => {
            assert_eq!((line, field.as_str()), (3, "parameters.calibration_type"));
            assert!(
                message.contains("declares eye-to-hand (a fixed camera)"),
                "{message}"
            );
        }
        other => panic!("{other:?}"),
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_empty_calibration_type_is_undeclared_and_an_unknown_one_is_refused() {
    // easy_handeye2 writes `calibration_type: ''` when its parameter was never set: the file then
    // declares no setup, and the run's setup decides (it used to be refused, exit 2). Its sampler
    // then looks the robot up effector-to-base, as for `eye_on_base`, whatever the setup is.
    let original = read(
        &suite().join("nominal_stations_eih_s0.jsonl"),
        Setup::EyeInHand,
    )
    .unwrap();
    let dir = scratch("empty-type");
    let declared = easy_handeye_samples(&original.poses, Setup::EyeInHand);
    let as_sampled = easy_handeye_samples(&original.poses, Setup::EyeToHand);
    for (file, kind) in [("quoted.samples", "''"), ("double.samples", "\"\"")] {
        let path = dir.join(file);
        let text = as_sampled.replace(
            "calibration_type: eye_on_base",
            &format!("calibration_type: {kind}"),
        );
        assert_ne!(text, as_sampled);
        std::fs::write(&path, text).unwrap();
        let read_back = read(&path, Setup::EyeInHand).unwrap_or_else(|e| panic!("{file}: {e}"));
        let poses = difference(&read_back.poses, &original.poses);
        assert!(poses < 1e-12, "{file}: poses differ by {poses}");
        // Undeclared: the other setup is not refused for what the file says.
        read(&path, Setup::EyeToHand).unwrap_or_else(|e| panic!("{file} eye-to-hand: {e}"));
    }
    let path = dir.join("unknown.samples");
    std::fs::write(
        &path,
        declared.replace(
            "calibration_type: eye_in_hand",
            "calibration_type: eye_on_table",
        ),
    )
    .unwrap();
    match read(&path, Setup::EyeInHand) {
        Err(Error::Parse { line, field, .. }) => {
            assert_eq!((line, field.as_str()), (3, "parameters.calibration_type"))
        }
        other => panic!("{other:?}"),
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
