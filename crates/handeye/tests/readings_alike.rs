//! Readings the motions cannot tell apart, and estimates that stop being the current X.
//!
//! On `testdata/rosbag/eih_tf_mcap` with the camera and target frame names swapped, the first 16
//! poses (rotations of 2–28°) fit as given about as well as read the right way round (0.18° and
//! 1.0% against 0.16° and 0.6%): a batch calibration of them said "good" with an X 149° and 0.6 m
//! off, and the accumulating estimator, judging the readings on those poses only, published that X.
//! The whole recording fits far better read right, as the batch check says on it.
//!
//! `cargo test --release -p handeye --test readings_alike -- --nocapture` prints the fits.

mod shared_data;

use std::path::{Path, PathBuf};

use handeye::check::readings::check_readings;
use handeye::io::{BagFrames, Format, Recording, RecordingOptions, Source};
use handeye::model::pose::rotation_angle_between;
use handeye::track::{TrackOptions, Tracker};
use handeye::{Assessment, Error, Pairing, Reading, Setup, Warning, Written};
use handeye::{Options, calibrate};

fn testdata() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata")
}

/// The pose pairs of a recording with the camera frame and the target frame named.
fn bag(name: &str, setup: Setup, camera: &str, target: &str) -> Recording {
    let source = Source::Bag {
        path: testdata().join("rosbag").join(name),
        frames: BagFrames {
            base: "base_link".into(),
            gripper: "tool0".into(),
            camera: camera.into(),
            target: Some(target.into()),
            target_topic: None,
            tags: None,
        },
    };
    let options = RecordingOptions {
        setup,
        ..RecordingOptions::default()
    };
    Recording::read(&source, &options).unwrap()
}

/// The recording with the camera and target frame names swapped (the mistake).
fn swapped() -> Recording {
    bag("eih_tf_mcap", Setup::EyeInHand, "board", "camera_link")
}

fn options(written: Written) -> Options {
    Options {
        pairing: Pairing::All,
        written,
        ..Options::default()
    }
}

#[test]
fn swapped_frames_on_small_first_motions_are_questionable_not_good() {
    let r = swapped();
    assert_eq!(r.written, Written::FRAMES);
    let first = &r.poses[..16];
    let check = check_readings(first, Setup::EyeInHand, r.written);
    println!("{check:?}");
    assert!(check.better.is_none(), "{check:?}");
    let alike: Vec<Reading> = check.alike.iter().map(|f| f.reading).collect();
    assert!(alike.contains(&Reading::CameraInverted), "{check:?}");
    let report = calibrate(first, Setup::EyeInHand, &options(r.written))
        .map(|r| r.into_hand_eye().expect("the hand–eye report"))
        .unwrap();
    assert_eq!(report.verdict, Assessment::Questionable);
    let warning = report
        .warnings
        .iter()
        .find(|w| matches!(w, Warning::ReadingsAlike { .. }))
        .expect("a readings_alike warning");
    let words = warning.to_string();
    assert!(
        words.contains("the camera and target frame names are swapped"),
        "{words}"
    );
    assert!(words.contains("too small or too alike"), "{words}");
    // The whole recording tells: refused as misread.
    match calibrate(&r.poses, Setup::EyeInHand, &options(r.written))
        .map(|r| r.into_hand_eye().expect("the hand–eye report"))
    {
        Err(Error::Misread { readings, .. }) => {
            assert!(readings.contains(&Reading::CameraInverted), "{readings:?}")
        }
        other => panic!("expected a misread, got {other:?}"),
    }
}

#[test]
fn the_right_frames_on_the_same_motions_raise_nothing() {
    for (name, setup) in [
        ("eih_tf_mcap", Setup::EyeInHand),
        ("eth_tf_sqlite3", Setup::EyeToHand),
    ] {
        let r = bag(name, setup, "camera_color_optical_frame", "board");
        for n in [16, 32, r.poses.len()] {
            let check = check_readings(&r.poses[..n], setup, r.written);
            assert!(check.alike.is_empty(), "{name} n={n}: {check:?}");
            let report = calibrate(&r.poses[..n], setup, &options(r.written))
                .map(|r| r.into_hand_eye().expect("the hand–eye report"))
                .unwrap();
            assert_eq!(report.verdict, Assessment::Good, "{name} n={n}: {report:?}");
        }
    }
}

/// Every realistic pose file of the suite (all of its kinds but the gross outliers, which the
/// batch removes before this check) and the real recordings: no reading fits as well as the
/// right one, so none is flagged.
#[test]
fn correct_data_has_no_alike_reading() {
    let dir = testdata().join("kinhec/pairs");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "jsonl"))
        .collect();
    files.sort();
    let mut checked = 0;
    for path in files {
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        if name.starts_with("outliers") {
            continue;
        }
        let setup = if name.contains("_eth_") {
            Setup::EyeToHand
        } else {
            Setup::EyeInHand
        };
        let source = Source::File {
            path: path.clone(),
            format: Format::Auto,
        };
        let r = Recording::read(&source, &RecordingOptions::default()).unwrap();
        let check = check_readings(&r.poses, setup, r.written);
        assert!(check.alike.is_empty(), "{name}: {check:?}");
        checked += 1;
    }
    if let Some(path) = shared_data::shared("camodocal/TransformPairsInput.yml") {
        let camodocal = Source::File {
            path,
            format: Format::Auto,
        };
        let r = Recording::read(&camodocal, &RecordingOptions::default()).unwrap();
        for n in [8, 16, r.poses.len()] {
            let check = check_readings(&r.poses[..n], Setup::EyeInHand, r.written);
            assert!(check.alike.is_empty(), "camodocal n={n}: {check:?}");
        }
    }
    assert!(checked >= 50, "{checked}");
}

#[test]
fn the_tracker_never_reports_from_swapped_frames() {
    let r = swapped();
    let mut tracker =
        Tracker::new(Setup::EyeInHand, TrackOptions::default()).with_written(r.written);
    for (k, pose) in r.poses.iter().enumerate() {
        let step = tracker.push(pose);
        assert!(step.report.is_none(), "pose {}: {:?}", k + 1, step.report);
    }
    assert!(tracker.finish().is_none());
    assert!(tracker.last_report().is_none());
    let why = tracker.pending().expect("a reason").to_string();
    assert!(
        why.contains("swap the camera and target frame names"),
        "{why}"
    );
    assert!(!why.contains("--fix"), "{why}");
}

#[test]
fn a_change_withdraws_the_estimate_from_before_it() {
    // Two recordings of the same robot, the second after the camera moved by 8° and 40 mm.
    let dir = testdata().join("kinhec/pairs");
    let read = |name: &str| {
        let source = Source::File {
            path: dir.join(name),
            format: Format::Auto,
        };
        Recording::read(&source, &RecordingOptions::default())
            .unwrap()
            .poses
    };
    let before = [
        read("nominal_stations_eih_s1.jsonl"),
        read("nominal_stations_eih_s1.jsonl"),
    ]
    .concat();
    let delta = handeye::model::pose::transform_from_parts(
        &handeye::model::pose::exp_so3(&nalgebra::Vector3::new(0.0, 0.14, 0.0)),
        &nalgebra::Vector3::new(0.04, 0.0, 0.0),
    );
    // The camera moved on its mount by `delta` before the second recording.
    let after = handeye::sim::slipped(&before, 0, &delta);
    let mut tracker = Tracker::new(Setup::EyeInHand, TrackOptions::default());
    let mut first = None;
    for pose in &before {
        first = tracker.push(pose).report.or(first);
    }
    let first = first.expect("a report before the change");
    assert_eq!(tracker.last_report(), Some(first.clone()));
    let mut changed = false;
    for pose in &after {
        let step = tracker.push(pose);
        if step.change.is_some() {
            changed = true;
            assert!(
                tracker.last_report().is_none_or(|r| r.pose == step.pose),
                "the estimate from before the change is still offered"
            );
        }
    }
    tracker.finish();
    assert!(changed, "no change found");
    let last = tracker.last_report().expect("an estimate after the change");
    let old_x = first.estimate.x;
    let new_x = last.estimate.x;
    let moved = rotation_angle_between(&old_x.rotation, &new_x.rotation).to_degrees();
    println!("X moved by {moved:.2}° (8.02° applied)");
    assert!((moved - 8.02).abs() < 1.0, "{moved}");
}
