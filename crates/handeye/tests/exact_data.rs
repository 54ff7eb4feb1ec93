//! Exact data through the tracker and the batch checks (issue 32): the noise unit has a floor at
//! the data's numerical precision, so rounding errors are not "k times the typical residual".
//! No alarm, no held-out pose, the last estimate from every pose, X to 1e-9; and no outlier in the
//! batch.

use std::path::{Path, PathBuf};

use handeye::check::outliers::pose_outliers;
use handeye::io::read_pose_file;
use handeye::model::pose::{rotation_angle_between, transform_from_matrix4};
use handeye::sim::{SimConfig, simulate};
use handeye::track::{Pending, TrackOptions, Tracker};
use handeye::{Options, PosePair, Setup, Transform, calibrate};

fn testdata() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata")
}

/// The exact streams: `handeye simulate --noise-free` (both presets, 1,200 poses, millimetres)
/// and the kinhec noise-free pairs (metres, both setups), with their true X.
fn exact_streams() -> Vec<(String, Setup, Vec<PosePair>, Transform)> {
    let mut all = Vec::new();
    for seed in 1..=4 {
        for (preset, config) in [
            ("paper", SimConfig::default()),
            ("large", SimConfig::large_motions()),
        ] {
            let config = SimConfig {
                poses: 1200,
                ..config.noise_free()
            };
            let s = simulate(&config, seed, 0);
            all.push((
                format!("simulate {preset} seed {seed}"),
                Setup::EyeInHand,
                s.poses,
                s.gripper_from_camera,
            ));
        }
    }
    for (kind, setup, frame) in [
        ("eih", Setup::EyeInHand, "gripper_from_camera"),
        ("eth", Setup::EyeToHand, "base_from_camera"),
    ] {
        for motion in ["continuous", "stations"] {
            let stem = testdata().join(format!("kinhec/pairs/noise_free_{motion}_{kind}_s0"));
            let poses = read_pose_file(&stem.with_extension("jsonl"), Default::default())
                .unwrap()
                .pairs;
            let truth: serde_json::Value = serde_json::from_str(
                &std::fs::read_to_string(stem.with_extension("truth.json")).unwrap(),
            )
            .unwrap();
            let m: Vec<f64> = truth[frame]["matrix"]
                .as_array()
                .unwrap()
                .iter()
                .flat_map(|r| r.as_array().unwrap().iter().map(|v| v.as_f64().unwrap()))
                .collect();
            let x = transform_from_matrix4(&nalgebra::Matrix4::from_row_slice(&m)).unwrap();
            all.push((format!("kinhec {motion} {kind}"), setup, poses, x));
        }
    }
    all
}

#[test]
fn exact_streams_give_the_exact_answer_from_every_pose() {
    for (name, setup, poses, truth) in exact_streams() {
        let mut tracker = Tracker::new(setup, TrackOptions::default());
        let (mut alarms, mut held) = (0, 0);
        let mut last = None;
        for pose in &poses {
            let step = tracker.push(pose);
            alarms += usize::from(step.change.is_some());
            held += usize::from(step.held_out.is_some()) + step.earlier.len();
            last = step.report.or(last);
        }
        last = tracker.finish().or(last);
        assert_eq!(alarms, 0, "{name}: a change alarmed on a fixed rig");
        assert_eq!(held, 0, "{name}: exact poses held out");
        assert_eq!(tracker.held_out(), 0, "{name}");
        let report = last.unwrap_or_else(|| panic!("{name}: no report: {:?}", tracker.pending()));
        assert!(report.weak.is_none(), "{name}: {:?}", report.weak);
        let e = report.estimate;
        assert_eq!(
            e.poses,
            poses.len(),
            "{name}: the last estimate is not from every pose"
        );
        let scale = truth.translation.vector.norm();
        let dr = rotation_angle_between(&e.x.rotation, &truth.rotation);
        let dt = (e.x.translation.vector - truth.translation.vector).norm();
        assert!(dr < 1e-9 && dt < 1e-9 * scale, "{name}: {dr:e} rad, {dt:e}");
        // The uncertainty is reported, and it is at the data's precision, not noise.
        let (ur, ut) = (
            e.uncertainty_rotation_deg.unwrap(),
            e.uncertainty_translation.unwrap(),
        );
        assert!(ur < 1e-5 && ut < 1e-6 * scale, "{name}: {ur:e}° {ut:e}");
    }
}

#[test]
fn the_batch_flags_no_outlier_on_exact_data() {
    for (name, setup, poses, truth) in exact_streams() {
        let found = pose_outliers(&poses, setup, 3.0);
        assert!(found.poses.is_empty(), "{name}: {:?}", found.poses);
        let report = calibrate(&poses, setup, &Options::default())
            .map(|r| r.into_hand_eye().expect("the hand–eye report"))
            .unwrap();
        assert!(
            report.outliers.poses.is_empty(),
            "{name}: {:?}",
            report.outliers
        );
        let dt = (report.transform.translation.vector - truth.translation.vector).norm();
        assert!(
            dt < 1e-9 * truth.translation.vector.norm(),
            "{name}: {dt:e}"
        );
    }
}

/// A stream read wrongly, or with no motion to judge by, is never reported (the readings checks
/// of the batch, run by the tracker), and says why.
#[test]
fn exact_streams_read_wrongly_are_not_reported() {
    let config = SimConfig {
        poses: 400,
        ..SimConfig::large_motions().noise_free()
    };
    let good = simulate(&config, 3, 0).poses;
    let inverted: Vec<PosePair> = good
        .iter()
        .map(|p| PosePair {
            base_from_gripper: p.base_from_gripper,
            camera_from_target: p.camera_from_target.inverse(),
        })
        .collect();
    let metres_camera: Vec<PosePair> = good
        .iter()
        .map(|p| {
            let mut c = p.camera_from_target;
            c.translation.vector /= 1000.0;
            PosePair {
                base_from_gripper: p.base_from_gripper,
                camera_from_target: c,
            }
        })
        .collect();
    // A still robot: the first pose again and again (the readings cannot be judged).
    let still = vec![good[0]; 300];
    for (name, poses, misread) in [
        ("camera inverted", inverted, true),
        ("camera in metres, robot in mm", metres_camera, true),
        ("still", still, false),
    ] {
        let mut tracker = Tracker::new(Setup::EyeInHand, TrackOptions::default());
        let mut reports = 0;
        for pose in &poses {
            reports += usize::from(tracker.push(pose).report.is_some());
        }
        reports += usize::from(tracker.finish().is_some());
        assert_eq!(reports, 0, "{name}");
        let why = tracker.pending().unwrap();
        assert_eq!(
            matches!(why, Pending::Misread { .. }),
            misread,
            "{name}: {why}"
        );
    }
}
