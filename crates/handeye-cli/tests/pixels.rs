//! `calibrate --method reprojection` on the committed simulated recordings of `testdata/pixels`
//! (made by `cargo run --release -p handeye --example pixel_recording -- testdata/pixels`), and
//! its refusals of bad input (issue 35).

mod common;

use common::{run, testdata};
use serde_json::Value;

fn path(name: &str) -> String {
    testdata(&format!("pixels/{name}")).display().to_string()
}

/// Rotation (degrees) and translation (input unit) between X of a report and a truth transform.
fn gap(report: &Value, truth: &Value) -> (f64, f64) {
    let v = |j: &Value, k: &str, i: usize| j[k][i].as_f64().unwrap();
    let t: f64 = (0..3)
        .map(|i| (v(report, "translation", i) - v(truth, "translation", i)).powi(2))
        .sum::<f64>()
        .sqrt();
    let dot: f64 = (0..4)
        .map(|i| v(report, "quaternion_xyzw", i) * v(truth, "quaternion_xyzw", i))
        .sum();
    (2.0 * dot.abs().min(1.0).acos().to_degrees(), t)
}

#[test]
fn the_committed_recordings_are_calibrated_within_millimetres() {
    for (name, setup, x) in [
        ("tag_eih", "eye-in-hand", "gripper_from_camera"),
        ("board_eth", "eye-to-hand", "base_from_camera"),
    ] {
        let (code, out, err) = run(&[
            "calibrate",
            &path(&format!("{name}.jsonl")),
            "--method",
            "reprojection",
            "--intrinsics",
            &path(&format!("{name}.intrinsics.yml")),
            "--setup",
            setup,
            "--output",
            "json",
        ]);
        assert_eq!(code, 0, "{name}: {err}");
        let report: Value = serde_json::from_str(&out).unwrap();
        let truth: Value = serde_json::from_str(
            &std::fs::read_to_string(path(&format!("{name}.truth.json"))).unwrap(),
        )
        .unwrap();
        let (deg, t) = gap(&report, &truth[x]);
        assert!(deg < 0.5 && t < 0.005, "{name}: {deg}° {t} m");
        assert_eq!(report["method"], "reprojection");
        assert!(report["verdict"].is_string());
        assert!(report["uncertainty"]["at_point"]["sigma"].as_f64().unwrap() > 0.0);
        let p = &report["reprojection"];
        assert!(p["rms_px"].as_f64().unwrap() < 2.0, "{p}");
        assert_eq!(p["per_frame"].as_array().unwrap().len(), 30);
        let outliers = truth["outliers"].as_array().unwrap().len();
        assert_eq!(
            p["outlier_detections"].as_array().unwrap().len(),
            outliers,
            "{name}"
        );
    }
}

#[test]
fn the_text_face_prints_the_reprojection_rms() {
    let (code, out, _) = run(&[
        "calibrate",
        &path("tag_eih.jsonl"),
        "--method",
        "reprojection",
        "--intrinsics",
        &path("tag_eih.intrinsics.yml"),
        "--output",
        "text",
    ]);
    assert_eq!(code, 0);
    assert!(
        out.contains("Reprojection: ") && out.contains("px RMS"),
        "{out}"
    );
    // The pose residuals are the PnP poses' (poor on a single tag), and say so: X was fitted to
    // the pixels. Without detections they are X's own.
    assert!(
        out.contains("Residuals of AX = XB of the PnP poses (their noise"),
        "{out}"
    );
    let (code, out, _) = run(&["calibrate", &path("tag_eih.jsonl"), "--output", "text"]);
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("Residuals of AX = XB: "), "{out}");
}

#[test]
fn reprojection_without_detections_or_intrinsics_is_refused() {
    let tag = path("tag_eih.jsonl");
    let k = path("tag_eih.intrinsics.yml");
    // No intrinsics.
    let (code, _, err) = run(&["calibrate", &tag, "--method", "reprojection"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--intrinsics"), "{err}");
    // A pose file without detections.
    let poses = testdata("opencv/opencv_eye-in-hand_noisy_10_12.jsonl")
        .display()
        .to_string();
    let (code, _, err) = run(&[
        "calibrate",
        &poses,
        "--method",
        "reprojection",
        "--intrinsics",
        &k,
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains(":1: field `detections`"), "{err}");
    // Intrinsics without the method that reads them.
    let (code, _, err) = run(&["calibrate", &poses, "--intrinsics", &k]);
    assert_eq!(code, 2, "{err}");
    // With --robot-world: said to be not offered, exit 2.
    let (code, _, err) = run(&[
        "calibrate",
        &tag,
        "--method",
        "reprojection",
        "--intrinsics",
        &k,
        "--robot-world",
    ]);
    assert_eq!(code, 2, "{err}");
}

#[test]
fn bad_input_files_name_the_line_and_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let k = path("tag_eih.intrinsics.yml");
    let text = std::fs::read_to_string(path("tag_eih.jsonl")).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    // Line 5: a NaN pixel; checked in order, so it is the first error.
    lines[4] = lines[4].replacen("\"pixels\": [[", "\"pixels\": [[\"NaN\", ", 1);
    let bad = dir.path().join("bad.jsonl");
    std::fs::write(&bad, lines.join("\n")).unwrap();
    let (code, _, err) = run(&[
        "calibrate",
        bad.to_str().unwrap(),
        "--method",
        "reprojection",
        "--intrinsics",
        &k,
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("bad.jsonl:5: field `detections.pixels[0]"),
        "{err}"
    );
    // An intrinsics file without its distortion.
    let yaml = std::fs::read_to_string(&k).unwrap();
    let cut = yaml.split("distortion_coefficients").next().unwrap();
    let bad_k = dir.path().join("k.yml");
    std::fs::write(&bad_k, cut).unwrap();
    let (code, _, err) = run(&[
        "calibrate",
        &path("tag_eih.jsonl"),
        "--method",
        "reprojection",
        "--intrinsics",
        bad_k.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("field `distortion_coefficients`"), "{err}");
}

/// The robot poses inverted: refused on the pixels (exit 3), naming the reading.
#[test]
fn inverted_robot_poses_are_refused() {
    let text = std::fs::read_to_string(path("board_eth.jsonl")).unwrap();
    let inverted = text.replace("\"base_from_gripper\"", "\"gripper_from_base\"");
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("inv.jsonl");
    std::fs::write(&file, inverted).unwrap();
    let (code, _, err) = run(&[
        "calibrate",
        file.to_str().unwrap(),
        "--method",
        "reprojection",
        "--intrinsics",
        &path("board_eth.intrinsics.yml"),
        "--setup",
        "eye-to-hand",
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("inverted"), "{err}");
}

/// A pose-based method on records with detections that it reads as misread: the refusal (exit 3)
/// points to the check on the pixels.
#[test]
fn a_pose_based_misread_with_detections_points_to_the_pixels() {
    let text = std::fs::read_to_string(path("tag_eih.jsonl")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("inv.jsonl");
    std::fs::write(
        &file,
        text.replace("\"base_from_gripper\"", "\"gripper_from_base\""),
    )
    .unwrap();
    let (code, _, err) = run(&["calibrate", file.to_str().unwrap(), "--output", "json"]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("--method reprojection --intrinsics FILE"),
        "{err}"
    );
}
