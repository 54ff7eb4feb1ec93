//! The accumulating estimator on data handeye did not make (issue 13): the ethz-asl recordings and
//! the realistic kinhec streams (10 and 30 Hz, clock offsets, jitter, drops, both setups, three
//! outlier models), against the batch answer, the truth and OpenCV on 100 subsampled frames
//! (`testdata/kinhec/opencv_streams.json`, made by `opencv_streams.py`).

mod shared_data;

use std::path::{Path, PathBuf};

use handeye::io::sync::{StreamPairing, TimeOffset, pair_stream_files};
use handeye::model::pose::rotation_angle_between;
use handeye::track::{Report, TrackEstimate, TrackOptions, Tracker};
use handeye::{Method, Pairing, PosePair, Setup, Transform, motion_pairs, solve};
use serde_json::Value;

fn testdata() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata")
}

/// What the tracker did with a whole stream.
struct Run {
    alarms: usize,
    reports: Vec<Report>,
    last: TrackEstimate,
    /// Pose numbers (from 1) held out.
    held: Vec<usize>,
    /// The poses counted: all but those at the robot pose of the pose before (`Step::repeat`).
    counted: Vec<PosePair>,
}

fn track(pairing: &StreamPairing, setup: Setup) -> Run {
    let mut tracker = Tracker::new(setup, TrackOptions::default());
    let (mut alarms, mut reports, mut held, mut counted) = (0, Vec::new(), Vec::new(), Vec::new());
    for pose in &pairing.synced.pairs {
        let step = tracker.push(pose);
        if !step.repeat {
            counted.push(*pose);
        }
        alarms += usize::from(step.change.is_some());
        reports.extend(step.report);
        held.extend(step.held_out.map(|_| step.pose));
        held.extend(step.earlier.iter().map(|(p, _)| *p));
    }
    reports.extend(tracker.finish());
    Run {
        alarms,
        reports,
        last: tracker.estimate().expect("an estimate"),
        held,
        counted,
    }
}

/// Rotation (degrees) and translation between two transforms.
fn gap(a: &Transform, b: &Transform) -> (f64, f64) {
    (
        rotation_angle_between(&a.rotation, &b.rotation).to_degrees(),
        (a.translation.vector - b.translation.vector).norm(),
    )
}

/// The largest error/sigma over the reports, against `reference`.
fn worst_ratio(reports: &[Report], reference: &Transform) -> f64 {
    reports
        .iter()
        .map(|r| {
            let (dr, dt) = gap(&r.estimate.x, reference);
            let e = &r.estimate;
            (dr / e.uncertainty_rotation_deg.unwrap()).max(dt / e.uncertainty_translation.unwrap())
        })
        .fold(0.0, f64::max)
}

#[test]
fn the_ethz_recordings_raise_no_alarm_and_end_at_the_batch_answer() {
    let Some(dir) = shared_data::shared("ethz-asl") else {
        return;
    };
    for name in ["robot_arm_sim", "prime_sense_1"] {
        let pairing = pair_stream_files(
            &dir.join(format!("{name}_B_H.csv")),
            &dir.join(format!("{name}_W_E.csv")),
            Setup::EyeInHand,
            (TimeOffset::Auto, handeye::Reading::AsGiven),
            0.1,
            handeye::Rotations::default(),
        )
        .unwrap();
        let run = track(&pairing, Setup::EyeInHand);
        let poses = &pairing.synced.pairs;
        // The batch all-pairs answer on the robot poses the tracker counts: robot_arm_sim holds 6
        // poses for 641 of its 1,050 images, which weigh those 6 poses 100-fold in the all-pairs
        // sums of every image (that answer is 0.39° / 23 mm away, within its own sigma of 0.58° /
        // 24 mm).
        let batch = solve(
            Method::Andreff,
            &motion_pairs(&run.counted, Pairing::All, Setup::EyeInHand),
        )
        .unwrap()
        .x;
        let (dr, dt) = gap(&run.last.x, &batch);
        let worst = worst_ratio(&run.reports, &batch);
        println!(
            "{name}: {} poses, {} alarm(s), {} held out, {} report(s); final {dr:.3}° / {:.2} mm from the batch all-pairs answer; worst report error/sigma {worst:.2}",
            poses.len(),
            run.alarms,
            run.held.len(),
            run.reports.len(),
            1e3 * dt
        );
        assert_eq!(run.alarms, 0, "{name}");
        assert!(dr < 0.3 && dt < 0.005, "{name}: {dr}° {dt}");
        // Every report is right within its uncertainty (against the batch answer, itself noisy).
        assert!(worst < 3.0, "{name}: a report {worst:.1} sigma off");
    }
}

/// The ethz-asl simulation with each robot pose once (the first image of each run the robot held
/// still, within 1e-4 rad and 0.1 mm of the previous image's pose): a dense stream, a slow path through one part of the workspace at a time. Its early
/// reports rest on a short stretch of that path, whose errors are correlated in time: with the
/// first-order covariance (independent poses) alone, the second report was 1.6° off the end with
/// a sigma of 0.19° (8 sigma, "good"), where `calibrate` on the same 134 poses says 1.62°
/// (issue 29). Every report must hold within three sigma of the batch answer on the whole
/// recording.
#[test]
fn a_dense_stream_s_early_reports_hold_within_their_uncertainty() {
    let Some(dir) = shared_data::shared("ethz-asl") else {
        return;
    };
    let pairing = pair_stream_files(
        &dir.join("robot_arm_sim_B_H.csv"),
        &dir.join("robot_arm_sim_W_E.csv"),
        Setup::EyeInHand,
        (TimeOffset::Fixed(0.0), handeye::Reading::AsGiven),
        0.1,
        handeye::Rotations::default(),
    )
    .unwrap();
    let mut once = pairing.clone();
    let pairs = &mut once.synced.pairs;
    let mut previous: Option<Transform> = None;
    pairs.retain(|p| {
        let q = p.base_from_gripper;
        let held = previous.is_some_and(|r| {
            let (dr, dt) = gap(&q, &r);
            dr.to_radians() < 1e-4 && dt < 1e-4
        });
        previous = Some(q);
        !held
    });
    let poses = &once.synced.pairs;
    assert!(
        (350..500).contains(&poses.len()),
        "{} robot poses",
        poses.len()
    );
    let run = track(&once, Setup::EyeInHand);
    let batch = solve(
        Method::Andreff,
        &motion_pairs(&pairing.synced.pairs, Pairing::All, Setup::EyeInHand),
    )
    .unwrap()
    .x;
    for r in &run.reports {
        let (dr, dt) = gap(&r.estimate.x, &batch);
        let e = &r.estimate;
        println!(
            "report {} at {} poses: {dr:.3}° ({:.3}° sigma), {:.1} mm ({:.1} mm sigma)",
            r.number,
            r.pose,
            e.uncertainty_rotation_deg.unwrap(),
            1e3 * dt,
            1e3 * e.uncertainty_translation.unwrap()
        );
    }
    let worst = worst_ratio(&run.reports, &batch);
    assert!(run.reports.len() >= 3, "{} reports", run.reports.len());
    assert!(worst < 3.0, "a report {worst:.1} sigma off");
}

/// The kinhec stream entries of the manifest.
fn streams() -> Vec<Value> {
    let text = std::fs::read_to_string(testdata().join("kinhec/manifest.json")).unwrap();
    let manifest: Value = serde_json::from_str(&text).unwrap();
    manifest["files"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["type"] == "stream_pair")
        .cloned()
        .collect()
}

/// The camera stamps of the planted outliers of a stream (its file lines, from 1).
fn outlier_stamps(entry: &Value) -> Vec<f64> {
    let Some(lines) = entry["outliers"]["camera_file_lines"].as_array() else {
        return Vec::new();
    };
    let path = testdata()
        .join("kinhec")
        .join(entry["camera_file"].as_str().unwrap());
    let text = std::fs::read_to_string(path).unwrap();
    let rows: Vec<&str> = text.lines().collect();
    lines
        .iter()
        .map(|l| {
            let row = rows[l.as_u64().unwrap() as usize - 1];
            row.split_whitespace().next().unwrap().parse().unwrap()
        })
        .collect()
}

#[test]
fn the_kinhec_streams_raise_no_alarm_hold_out_the_outliers_and_beat_opencv() {
    let text = std::fs::read_to_string(testdata().join("kinhec/opencv_streams.json")).unwrap();
    let opencv: Value = serde_json::from_str(&text).unwrap();
    let all = streams();
    assert_eq!(all.len(), 15);
    let (mut planted, mut found, mut good_held, mut good) = (0, 0, 0, 0);
    for e in &all {
        let setup = match e["setup"].as_str().unwrap() {
            "eye-to-hand" => Setup::EyeToHand,
            _ => Setup::EyeInHand,
        };
        let kinhec = testdata().join("kinhec");
        let file = |key: &str| kinhec.join(e[key].as_str().unwrap());
        let pairing = pair_stream_files(
            &file("robot_file"),
            &file("camera_file"),
            setup,
            (TimeOffset::Auto, handeye::Reading::AsGiven),
            0.1,
            handeye::Rotations::default(),
        )
        .unwrap();
        let truth = handeye::io::Truth::read(file("truth")).unwrap().x;
        let run = track(&pairing, setup);
        let name = e["truth"]
            .as_str()
            .unwrap()
            .trim_start_matches("streams/")
            .trim_end_matches(".truth.json");
        let (dr, dt) = gap(&run.last.x, &truth);
        // OpenCV's five methods on 100 subsampled frames: their median error.
        let methods = opencv["streams"][name]["methods"].as_object().unwrap();
        let median = |key: &str| {
            let mut v: Vec<f64> = methods.values().filter_map(|m| m[key].as_f64()).collect();
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let (cv_r, cv_t) = (median("rotation_error_deg"), median("translation_error"));
        let worst = worst_ratio(&run.reports, &truth);
        println!(
            "{name}: {} alarm(s), {} held out; X {dr:.3}° / {:.2} mm off (OpenCV median {cv_r:.3}° / {:.2} mm); worst report {worst:.2} sigma",
            run.alarms,
            run.held.len(),
            1e3 * dt,
            1e3 * cv_t
        );
        assert_eq!(run.alarms, 0, "{name}: false alarm");
        assert!(
            dr <= 2.0 * cv_r && dt <= 2.0 * cv_t,
            "{name}: worse than OpenCV"
        );
        assert!(worst < 3.0, "{name}: a report {worst:.1} sigma off");
        let bad = outlier_stamps(e);
        if !bad.is_empty() {
            assert!(dr < 0.5 && dt < 0.010, "{name}: {dr}° {dt}");
        }
        let stamps = &pairing.synced.stamps;
        let is_bad = |pose: usize| bad.iter().any(|b| (b - stamps[pose - 1]).abs() < 1e-9);
        planted += (1..=stamps.len()).filter(|&p| is_bad(p)).count();
        found += run.held.iter().filter(|&&p| is_bad(p)).count();
        good += (1..=stamps.len()).filter(|&p| !is_bad(p)).count();
        good_held += run.held.iter().filter(|&&p| !is_bad(p)).count();
    }
    println!(
        "planted outliers held out: {found} of {planted}; good poses held out: {good_held} of {good}"
    );
    assert!(found * 10 >= planted * 9, "{found} of {planted}");
    assert!(good_held * 50 <= good, "{good_held} of {good}");
}

#[test]
fn on_the_kinhec_pose_files_every_report_holds_and_bad_input_reports_nothing() {
    // The synchronised files (30–50 keyframes): heavy-tailed, PnP and high camera noise, outliers,
    // one-joint and parallel-axis motion, both setups, three seeds each; and the mistakes users
    // make (an inverted pose, w-x-y-z quaternions, millimetres on one side): nothing is reported
    // from them, and the tracker says why.
    let text = std::fs::read_to_string(testdata().join("kinhec/manifest.json")).unwrap();
    let manifest: Value = serde_json::from_str(&text).unwrap();
    let kinds = [
        "nominal",
        "high_noise",
        "student_t",
        "pnp",
        "outliers_random_pose",
        "outliers_planar_flip",
        "outliers_gross",
        "near_degenerate_two_axes",
        "wrist_only",
        "degenerate_single_joint",
        "degenerate_parallel_axes",
        "robot_error",
        "mistake_robot_inverted",
        "mistake_camera_inverted",
        "mistake_robot_mm",
        "mistake_quat_wxyz_robot",
        "mistake_quat_wxyz_camera",
        "mistake_both_inverted",
    ];
    let (mut files, mut reported, mut worst) = (0, 0, 0.0f64);
    for e in manifest["files"].as_array().unwrap() {
        let kind = e["kind"].as_str().unwrap_or("");
        if !(e["type"] == "pose_pairs" || e["type"] == "mistake") || !kinds.contains(&kind) {
            continue;
        }
        let setup = match e["setup"].as_str().unwrap() {
            "eye-to-hand" => Setup::EyeToHand,
            _ => Setup::EyeInHand,
        };
        let kinhec = testdata().join("kinhec");
        let series = handeye::io::read_pose_file(
            &kinhec.join(e["file"].as_str().unwrap()),
            handeye::io::Format::Auto,
        )
        .unwrap();
        let truth = handeye::io::Truth::read(kinhec.join(e["truth"].as_str().unwrap()))
            .unwrap()
            .x;
        let mut tracker = Tracker::new(setup, TrackOptions::default());
        let mut reports = Vec::new();
        for pose in &series.pairs {
            let step = tracker.push(pose);
            assert!(step.change.is_none(), "{}: false alarm", e["file"]);
            reports.extend(step.report);
        }
        reports.extend(tracker.finish());
        files += 1;
        // Both inputs inverted fit exactly with X and the target swapped: the sizes and the camera
        // poses tell, as in batch (tests/both_inverted.rs), and nothing is reported either.
        if kind.starts_with("degenerate") || kind.starts_with("mistake") {
            assert!(
                reports.is_empty(),
                "{}: reported {:?}",
                e["file"],
                reports.last().map(|r| r.estimate.uncertainty_rotation_deg)
            );
            assert!(tracker.pending().is_some(), "{}", e["file"]);
            continue;
        }
        reported += usize::from(!reports.is_empty());
        let w = worst_ratio(&reports, &truth);
        println!(
            "{}: {} report(s), worst {w:.2} sigma",
            e["file"],
            reports.len()
        );
        if kind == "robot_error" {
            // A robot model off by 1 mm / 0.1° per joint is not noise: a known gap (4–7 sigma).
            continue;
        }
        assert!(w < 3.0, "{}: a report {w:.1} sigma off", e["file"]);
        worst = worst.max(w);
    }
    println!(
        "{files} files, {reported} with a report; worst report {worst:.2} sigma from the truth"
    );
    assert!(files >= 60, "{files}");
}
