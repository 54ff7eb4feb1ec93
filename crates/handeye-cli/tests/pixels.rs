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
    // Intrinsics with a pose-based robot-world method: not read, so refused.
    let (code, _, err) = run(&["calibrate", &poses, "--robot-world", "--intrinsics", &k]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--method reprojection"), "{err}");
    // --robot-world on the pixels without intrinsics.
    let (code, _, err) = run(&[
        "calibrate",
        &tag,
        "--method",
        "reprojection",
        "--robot-world",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--intrinsics"), "{err}");
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

/// Rotation (degrees) and translation (input unit) between two transforms' JSON objects.
fn gap_of(a: &Value, b: &Value) -> (f64, f64) {
    gap(a, b)
}

/// `calibrate --robot-world --method reprojection` on a recording: the JSON, or the exit code and
/// the error.
fn robot_world_on_pixels(
    file: &str,
    name: &str,
    setup: &str,
    extra: &[&str],
) -> (i32, String, String) {
    let k = path(&format!("{name}.intrinsics.yml"));
    let mut args = vec![
        "calibrate",
        file,
        "--method",
        "reprojection",
        "--robot-world",
        "--intrinsics",
        &k,
        "--setup",
        setup,
    ];
    args.extend_from_slice(extra);
    run(&args)
}

/// A recording rewritten record by record.
fn rewritten(name: &str, edit: impl Fn(usize, &mut Value)) -> (tempfile::TempDir, String) {
    let text = std::fs::read_to_string(path(&format!("{name}.jsonl"))).unwrap();
    let lines: Vec<String> = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            let mut v: Value = serde_json::from_str(l).unwrap();
            edit(i, &mut v);
            v.to_string()
        })
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join(format!("{name}.jsonl"));
    std::fs::write(&file, lines.join("\n")).unwrap();
    let file = file.display().to_string();
    (dir, file)
}

const RECORDINGS: [(&str, &str, &str, &str); 2] = [
    (
        "tag_eih",
        "eye-in-hand",
        "gripper_from_camera",
        "base_from_target",
    ),
    (
        "board_eth",
        "eye-to-hand",
        "base_from_camera",
        "gripper_from_target",
    ),
];

/// X and the target's pose on the pixels, in the robot-world result: each within 3 sigma of the
/// truth and within the stated bounds (X 0.5° and 5 mm, as the hand–eye result on the pixels;
/// the target 1° and 5 mm), X the same as the hand–eye result's.
#[test]
fn robot_world_on_the_pixels_gives_x_and_the_target_within_their_sigma() {
    for (name, setup, x_frame, target_frame) in RECORDINGS {
        let file = path(&format!("{name}.jsonl"));
        let (code, out, err) = robot_world_on_pixels(&file, name, setup, &["--output", "json"]);
        assert_eq!(code, 0, "{name}: {err}");
        let r: Value = serde_json::from_str(&out).unwrap();
        let truth: Value = serde_json::from_str(
            &std::fs::read_to_string(path(&format!("{name}.truth.json"))).unwrap(),
        )
        .unwrap();
        assert_eq!(r["formulation"], "robot-world");
        assert_eq!(r["method"], "reprojection");
        assert_eq!(r["frame"], x_frame);
        assert_eq!(r["target"]["frame"], target_frame);
        for (what, got, truth, bounds) in [
            ("X", &r, &truth[x_frame], (0.5, 0.005)),
            ("target", &r["target"], &truth[target_frame], (1.0, 0.005)),
        ] {
            let (deg, t) = gap_of(got, truth);
            let sigma_deg = got["uncertainty"]["rotation_deg"].as_f64().unwrap();
            let sigma_t = got["uncertainty"]["translation"].as_f64().unwrap();
            assert!(
                deg <= 3.0 * sigma_deg && t <= 3.0 * sigma_t,
                "{name} {what}: {deg}° {t} m against sigma {sigma_deg}° {sigma_t} m"
            );
            assert!(
                deg < bounds.0 && t < bounds.1,
                "{name} {what}: {deg}° {t} m"
            );
        }
        let p = &r["reprojection"];
        assert_eq!(p["per_frame"].as_array().unwrap().len(), 30);
        assert_eq!(
            p["outlier_detections"].as_array().unwrap().len(),
            truth["outliers"].as_array().unwrap().len(),
            "{name}"
        );
        assert_eq!(r["residual"]["per_pose"].as_array().unwrap().len(), 30);
        // The hand–eye result on the pixels: the same solve, the same X.
        let (code, out, err) = run(&[
            "calibrate",
            &file,
            "--method",
            "reprojection",
            "--intrinsics",
            &path(&format!("{name}.intrinsics.yml")),
            "--setup",
            setup,
            "--output",
            "json",
        ]);
        assert_eq!(code, 0, "{err}");
        let h: Value = serde_json::from_str(&out).unwrap();
        assert_eq!(h["translation"], r["translation"], "{name}");
        assert_eq!(h["quaternion_xyzw"], r["quaternion_xyzw"], "{name}");
    }
    // The other faces print the same result: both transforms.
    let file = path("tag_eih.jsonl");
    let (code, out, err) =
        robot_world_on_pixels(&file, "tag_eih", "eye-in-hand", &["--output", "text"]);
    assert_eq!(code, 0, "{err}");
    for words in [
        "robot-world method reprojection",
        "Target = base_from_target",
        "Reprojection: ",
        "over the PnP poses",
    ] {
        assert!(out.contains(words), "{words}: {out}");
    }
    let (code, out, err) =
        robot_world_on_pixels(&file, "tag_eih", "eye-in-hand", &["--output", "ros2"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains(r#""--frame-id", "gripper", "--child-frame-id", "camera""#)
            && out.contains(r#""--frame-id", "base", "--child-frame-id", "target""#),
        "{out}"
    );
}

/// The robot poses inverted: refused on the pixels (exit 3), naming the reading.
#[test]
fn robot_world_on_the_pixels_refuses_inverted_robot_poses() {
    for (name, setup, _, _) in RECORDINGS {
        let (_dir, file) = rewritten(name, |_, v| {
            let pose = v["base_from_gripper"].take();
            v.as_object_mut().unwrap().remove("base_from_gripper");
            v["gripper_from_base"] = pose;
        });
        let (code, _, err) = robot_world_on_pixels(&file, name, setup, &["--output", "json"]);
        assert_eq!(code, 3, "{name}: {err}");
        assert!(err.contains("inverted"), "{err}");
        // `--fix auto` applies it and says so.
        let (code, out, err) =
            robot_world_on_pixels(&file, name, setup, &["--output", "json", "--fix", "auto"]);
        assert_eq!(code, 0, "{name}: {err}");
        let r: Value = serde_json::from_str(&out).unwrap();
        assert_eq!(r["reading"]["applied"], "robot-inverted", "{name}");
    }
}

/// The target's points in millimetres with the robot in metres: refused (exit 3), naming the unit.
#[test]
fn robot_world_on_the_pixels_refuses_a_unit_mismatch() {
    let (name, setup, _, _) = RECORDINGS[0];
    let (_dir, file) = rewritten(name, |_, v| {
        for p in v["detections"]["target"].as_array_mut().unwrap() {
            for c in p.as_array_mut().unwrap() {
                *c = Value::from(c.as_f64().unwrap() * 1000.0);
            }
        }
        v.as_object_mut().unwrap().remove("camera_from_target");
    });
    let (code, out, err) = robot_world_on_pixels(&file, name, setup, &["--output", "text"]);
    assert_eq!(code, 3, "{err}");
    assert!(out.contains("Verdict: refused"), "{out}");
    // The text face prints a refusal once, on stdout.
    assert!(out.contains("1000 times smaller fit"), "{out}");
    assert!(err.contains("refused"), "{err}");
}

/// Mis-detected corners added to a third of the frames: left out and listed, X and the target
/// still within their bounds.
#[test]
fn robot_world_on_the_pixels_lists_and_leaves_out_mis_detections() {
    let (name, setup, x_frame, target_frame) = RECORDINGS[1];
    let (_dir, file) = rewritten(name, |i, v| {
        if i % 3 == 0 {
            let pixel = &mut v["detections"]["pixels"][5];
            pixel[0] = Value::from(pixel[0].as_f64().unwrap() + 40.0);
            pixel[1] = Value::from(pixel[1].as_f64().unwrap() - 25.0);
        }
    });
    let (code, out, err) = robot_world_on_pixels(&file, name, setup, &["--output", "json"]);
    assert_eq!(code, 0, "{err}");
    let r: Value = serde_json::from_str(&out).unwrap();
    let listed: Vec<(String, u64)> = r["reprojection"]["outlier_detections"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| (o[0].as_str().unwrap().to_string(), o[1].as_u64().unwrap()))
        .collect();
    assert_eq!(listed.len(), 10, "{listed:?}");
    for k in (0..30).step_by(3) {
        let line = format!("{}:{}", file, k + 1);
        assert!(listed.contains(&(line.clone(), 5)), "{line}: {listed:?}");
    }
    let truth: Value = serde_json::from_str(
        &std::fs::read_to_string(path(&format!("{name}.truth.json"))).unwrap(),
    )
    .unwrap();
    let (deg, t) = gap_of(&r, &truth[x_frame]);
    assert!(deg < 0.5 && t < 0.005, "X: {deg}° {t} m");
    let (deg, t) = gap_of(&r["target"], &truth[target_frame]);
    assert!(deg < 1.0 && t < 0.005, "target: {deg}° {t} m");
}

/// A saved X for `verify`: the truth of a recording, turned about an axis of X's parent frame by
/// `turn_deg` and shifted by `shift` (input unit).
fn saved_x(
    dir: &std::path::Path,
    name: &str,
    frame: &str,
    setup: &str,
    axis: usize,
    turn_deg: f64,
    shift: f64,
) -> String {
    let truth: Value = serde_json::from_str(
        &std::fs::read_to_string(path(&format!("{name}.truth.json"))).unwrap(),
    )
    .unwrap();
    let t = &truth[frame];
    let q: Vec<f64> = (0..4)
        .map(|i| t["quaternion_xyzw"][i].as_f64().unwrap())
        .collect();
    let half = turn_deg.to_radians() / 2.0;
    let mut d = [0.0, 0.0, 0.0, half.cos()];
    d[axis] = half.sin();
    // d ⊗ q (x, y, z, w).
    let turned = [
        d[3] * q[0] + d[0] * q[3] + d[1] * q[2] - d[2] * q[1],
        d[3] * q[1] - d[0] * q[2] + d[1] * q[3] + d[2] * q[0],
        d[3] * q[2] + d[0] * q[1] - d[1] * q[0] + d[2] * q[3],
        d[3] * q[3] - d[0] * q[0] - d[1] * q[1] - d[2] * q[2],
    ];
    let mut translation: Vec<f64> = (0..3)
        .map(|i| t["translation"][i].as_f64().unwrap())
        .collect();
    translation[axis] += shift;
    let file = dir.join(format!("{name}_{axis}_{turn_deg}_{shift}.json"));
    let saved = serde_json::json!({
        "frame": frame,
        "setup": setup,
        "translation": translation,
        "quaternion_xyzw": turned,
    });
    std::fs::write(&file, saved.to_string()).unwrap();
    file.display().to_string()
}

fn verify_on_pixels(saved: &str, name: &str, setup: &str, extra: &[&str]) -> (i32, String, String) {
    let file = path(&format!("{name}.jsonl"));
    let k = path(&format!("{name}.intrinsics.yml"));
    let mut args = vec![
        "verify",
        "--x",
        saved,
        &file,
        "--intrinsics",
        &k,
        "--setup",
        setup,
    ];
    args.extend_from_slice(extra);
    run(&args)
}

/// `verify --intrinsics` on the committed recordings: the true X is consistent (exit 0), a saved
/// X turned by 1° or shifted by 5 mm along any axis inconsistent (exit 4), with the pixels' RMS
/// of both X in the result.
#[test]
fn verify_on_the_pixels_accepts_the_truth_and_rejects_a_degree_or_five_millimetres() {
    let dir = tempfile::tempdir().unwrap();
    for (name, setup, x_frame, _) in RECORDINGS {
        let truth = saved_x(dir.path(), name, x_frame, setup, 0, 0.0, 0.0);
        let (code, out, err) = verify_on_pixels(&truth, name, setup, &["--output", "json"]);
        assert_eq!(code, 0, "{name}: {err}");
        let v: Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v["verdict"], "consistent", "{name}: {v}");
        assert_eq!(v["recording"]["method"], "reprojection");
        let p = &v["pixels"];
        let (saved_px, own_px) = (
            p["saved_rms_px"].as_f64().unwrap(),
            p["own_rms_px"].as_f64().unwrap(),
        );
        assert!(
            saved_px >= own_px - 1e-9 && saved_px < 1.1 * own_px,
            "{name}: {p}"
        );
        assert_eq!(p["per_frame"].as_array().unwrap().len(), 30);
        for axis in 0..3 {
            for (turn, shift) in [(1.0, 0.0), (0.0, 0.005)] {
                let wrong = saved_x(dir.path(), name, x_frame, setup, axis, turn, shift);
                let (code, out, err) = verify_on_pixels(&wrong, name, setup, &["--output", "json"]);
                assert_eq!(code, 4, "{name} axis {axis} {turn}° {shift} m: {err}");
                let v: Value = serde_json::from_str(&out).unwrap();
                assert_eq!(v["verdict"], "inconsistent");
                assert!(
                    v["message"]
                        .as_str()
                        .unwrap()
                        .starts_with("the saved X does not fit this recording"),
                    "{v}"
                );
                let p = &v["pixels"];
                assert!(
                    p["saved_rms_px"].as_f64().unwrap() > 1.5 * p["own_rms_px"].as_f64().unwrap(),
                    "{name} axis {axis} {turn}° {shift} m: {p}"
                );
            }
        }
    }
    // The text face: the verdict words and both RMS.
    let (name, setup, x_frame, _) = RECORDINGS[0];
    let truth = saved_x(dir.path(), name, x_frame, setup, 0, 0.0, 0.0);
    let (code, out, err) = verify_on_pixels(&truth, name, setup, &["--output", "text"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.starts_with("Verdict: consistent\n  the saved X fits this recording"),
        "{out}"
    );
    assert!(
        out.contains("On the pixels (the target's pose fitted to each X): saved X "),
        "{out}"
    );
}

/// `verify` on the pixels: the flags that do not apply are refused (exit 2), and robot poses that
/// fit the pixels far better inverted are refused as `calibrate` refuses them (exit 3).
#[test]
fn verify_on_the_pixels_refuses_what_it_cannot_read() {
    let dir = tempfile::tempdir().unwrap();
    let (name, setup, x_frame, _) = RECORDINGS[1];
    let truth = saved_x(dir.path(), name, x_frame, setup, 0, 0.0, 0.0);
    let file = path(&format!("{name}.jsonl"));
    let (code, _, err) = run(&[
        "verify",
        "--x",
        &truth,
        &file,
        "--method",
        "reprojection",
        "--setup",
        setup,
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--intrinsics"), "{err}");
    let k = path(&format!("{name}.intrinsics.yml"));
    let (code, _, err) = run(&[
        "verify",
        "--x",
        &truth,
        &file,
        "--intrinsics",
        &k,
        "--method",
        "tsai",
    ]);
    assert_eq!(code, 2, "{err}");
    let (_tmp, inverted) = rewritten(name, |_, v| {
        let pose = v["base_from_gripper"].take();
        v.as_object_mut().unwrap().remove("base_from_gripper");
        v["gripper_from_base"] = pose;
    });
    let (code, _, err) = run(&[
        "verify",
        "--x",
        &truth,
        &inverted,
        "--intrinsics",
        &k,
        "--setup",
        setup,
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("inverted"), "{err}");
}

/// A prior is refused on the pixels, never taken silently: the pixel solve has no low-DOF form,
/// so an answer would carry the data's tz, not the one the user gave (it answered "good", exit 0).
#[test]
fn a_prior_on_the_pixels_is_refused_not_ignored() {
    let (file, k) = (path("tag_eih.jsonl"), path("tag_eih.intrinsics.yml"));
    for extra in [&[][..], &["--robot-world"][..]] {
        let mut args = vec![
            "calibrate",
            file.as_str(),
            "--method",
            "reprojection",
            "--intrinsics",
            k.as_str(),
            "--prior",
            "tz=0.05",
        ];
        args.extend_from_slice(extra);
        let (code, out, err) = run(&args);
        assert_eq!(code, 2, "{extra:?}: {out}{err}");
        assert!(
            err.contains("prior") && err.contains("pixels"),
            "{extra:?}: {err}"
        );
    }
}

/// The arguments of `calibrate --method reprojection` on a ROS 2 recording of a tag
/// (testdata/rosbag/make_tag_bags.py, made from tag_eih.jsonl).
fn bag_args(bag: &str) -> Vec<String> {
    [
        "calibrate",
        &testdata(&format!("rosbag/{bag}")).display().to_string(),
        "--method",
        "reprojection",
        "--base-frame",
        "base_link",
        "--gripper-frame",
        "tool0",
        "--camera-frame",
        "camera",
        "--target-topic",
        "/apriltag/detections",
        "--tag-size",
        "0.06",
        "--output",
        "json",
    ]
    .iter()
    .map(ToString::to_string)
    .collect()
}

#[test]
fn a_recording_of_tag_detections_gives_the_x_of_the_json_lines_file() {
    let (code, out, err) = run(&[
        "calibrate",
        &path("tag_eih.jsonl"),
        "--method",
        "reprojection",
        "--intrinsics",
        &path("tag_eih.intrinsics.yml"),
        "--output",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    let jsonl: Value = serde_json::from_str(&out).unwrap();
    let args = bag_args("tag_eih_mcap");
    let (code, out, err) = run(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 0, "{err}");
    let bag: Value = serde_json::from_str(&out).unwrap();
    // The JSON Lines file starts from its own PnP poses, the bag from handeye's: the same
    // minimum, to the solver's convergence.
    let (deg, t) = gap(&bag, &jsonl);
    assert!(deg < 1e-6 && t < 1e-8, "{deg}° {t} m");
    assert!(
        err.contains("30 image(s) of tag 3") && err.contains("intrinsics from /camera/camera_info"),
        "{err}"
    );
    assert_eq!(
        bag["reprojection"]["per_frame"][0]["name"]
            .as_str()
            .unwrap()
            .split(" (")
            .next(),
        Some("/apriltag/detections #1")
    );
}

#[test]
fn a_recording_of_tag_detections_without_intrinsics_or_method_is_refused_in_words() {
    let args = bag_args("tag_eih_noinfo_sqlite3");
    let (code, _, err) = run(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("--intrinsics FILE") && err.contains("camera_info"),
        "{err}"
    );
    // With the intrinsics given, the same recording is calibrated.
    let mut with = args.clone();
    with.extend(["--intrinsics".to_string(), path("tag_eih.intrinsics.yml")]);
    let (code, _, err) = run(&with.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 0, "{err}");
    // Without --method reprojection: the tag flags and the topic say what they need.
    let pose: Vec<&str> = args
        .iter()
        .map(String::as_str)
        .filter(|a| *a != "--method" && *a != "reprojection")
        .collect();
    let (code, _, err) = run(&pose);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--method reprojection"), "{err}");
    let no_size: Vec<&str> = pose
        .iter()
        .copied()
        .filter(|a| *a != "--tag-size" && *a != "0.06")
        .collect();
    let (code, _, err) = run(&no_size);
    assert_ne!(code, 0, "{err}");
    assert!(err.contains("calibrated on the pixels"), "{err}");
    // A hostile recording: its bad messages are skipped and named, never a panic.
    let args = bag_args("tag_eih_hostile_mcap");
    let mut with_id = args.clone();
    with_id.extend(["--tag-id".to_string(), "3".to_string()]);
    let (code, out, err) = run(&with_id.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("message 3: cannot decode")
            && err.contains("message 9: no detection of tag 3"),
        "{err}"
    );
    let report: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(
        report["reprojection"]["per_frame"]
            .as_array()
            .unwrap()
            .len(),
        27
    );
    let (code, _, err) = run(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--tag-id"), "{err}");
}
