//! Issue 52, items 3, 4, 9, 10 and the smaller things: an answer whose own checks say it is not
//! one is a refusal (exit 3) naming its cause, said once; a low-DOF prior's sign is said and its
//! component marked unchecked; a robot that can turn about another axis is told to first.

mod common;

use common::{run, testdata};
use serde_json::Value;

/// `file` with every stamp (first column) moved by `seconds`, written under `dir`.
fn shifted(file: &str, seconds: f64, dir: &std::path::Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string(testdata(file)).unwrap();
    let moved: String = text
        .lines()
        .map(|l| match l.split_once(' ') {
            Some((t, rest)) if !l.starts_with('#') => {
                format!("{:.6} {rest}\n", t.parse::<f64>().unwrap() + seconds)
            }
            _ => format!("{l}\n"),
        })
        .collect();
    let path = dir.join("camera.txt");
    std::fs::write(&path, moved).unwrap();
    path
}

#[test]
fn a_clock_offset_beyond_the_search_is_a_refusal_said_once_not_a_questionable_x() {
    let dir = tempfile::tempdir().unwrap();
    for (stream, setup) in [
        ("temporal_10hz_eih_s0", "eye-in-hand"),
        ("temporal_outliers_planar_flip_30hz_eth_s1", "eye-to-hand"),
    ] {
        let robot = testdata(&format!("kinhec/streams/{stream}_robot.txt"));
        let good = testdata(&format!("kinhec/streams/{stream}_camera.txt"));
        let robot = robot.to_str().unwrap();
        // As recorded, no false alarm.
        let (code, _, err) = run(&[
            "calibrate",
            "--robot",
            robot,
            "--camera",
            good.to_str().unwrap(),
            "--setup",
            setup,
            "--output",
            "json",
        ]);
        assert_eq!(code, 0, "{stream}: {err}");
        for seconds in [3.0, -3.0] {
            let camera = shifted(
                &format!("kinhec/streams/{stream}_camera.txt"),
                seconds,
                dir.path(),
            );
            for auto in [true, false] {
                let mut args = vec![
                    "calibrate",
                    "--robot",
                    robot,
                    "--camera",
                    camera.to_str().unwrap(),
                    "--setup",
                    setup,
                    "--output",
                    "text",
                ];
                if auto {
                    args.extend(["--time-offset", "auto"]);
                }
                let (code, out, err) = run(&args);
                assert_eq!(code, 3, "{stream} {seconds} s: {out}{err}");
                assert!(out.contains("the clock offset was not found"), "{out}");
                assert!(out.contains("--time-offset SECONDS"), "{out}");
                assert!(
                    !err.contains("the clock offset was not found"),
                    "said twice: {err}"
                );
            }
        }
    }
}

#[test]
fn a_forgotten_eye_to_hand_leads_with_the_setup_once_and_online_refuses_it_too() {
    let input = testdata("kinhec/pairs/nominal_stations_eth_s1.jsonl");
    let input = input.to_str().unwrap();
    let (code, out, err) = run(&["calibrate", input, "--output", "text"]);
    assert_eq!(code, 3, "{err}");
    let reason = out.lines().nth(1).unwrap();
    let lead = &reason[..reason.find(". ").unwrap()];
    assert!(
        lead.contains("eye-to-hand setup") && lead.contains("--setup eye-to-hand"),
        "{reason}"
    );
    assert!(!err.contains("--setup eye-to-hand"), "said twice: {err}");
    let (code, _, err) = run(&["online", input, "--output", "text"]);
    assert_eq!(code, 3, "{err}");
    assert_eq!(err.matches("--setup eye-to-hand").count(), 1, "{err}");
}

#[test]
fn a_low_dof_prior_is_signed_along_its_axis_and_marked_unchecked() {
    let input = testdata("low_dof/scara_eye-in-hand_s0.jsonl");
    let input = input.to_str().unwrap();
    let (code, out, err) = run(&["calibrate", input, "--output", "text"]);
    assert_eq!(code, 3, "{err}");
    assert!(
        out.contains("+z (for a flange frame, out of the flange towards the tool)"),
        "{out}"
    );
    assert!(
        out.contains("signed") && out.contains("its sign included"),
        "{out}"
    );
    // The wrong sign (the camera is at -0.1075): the answer is still "good", so the result says
    // which way the prior points and that nothing checked it.
    for value in ["0.1075", "-0.1075"] {
        let prior = format!("tz={value}+-0.001");
        let (code, out, err) = run(&["calibrate", input, "--prior", &prior, "--output", "json"]);
        assert_eq!(code, 0, "{err}");
        let v: Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v["low_dof"]["unchecked"], serde_json::json!(["tz"]));
        assert!(v["low_dof"]["direction"].as_str().unwrap().contains("+z"));
        let (_, text, _) = run(&["calibrate", input, "--prior", &prior, "--output", "text"]);
        let line = text.lines().find(|l| l.starts_with("Prior: tz")).unwrap();
        let signed = if value.starts_with('-') {
            "= -0.1075 m (-107.5 mm)"
        } else {
            "= +0.1075 m (+107.5 mm)"
        };
        assert!(
            line.contains(signed) && line.contains("unchecked"),
            "{line}"
        );
    }
}

/// The SCARA recording with each record's joint angles (`n` of them), written under `dir`.
fn with_joints(n: usize, dir: &std::path::Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string(testdata("low_dof/scara_eye-in-hand_s0.jsonl")).unwrap();
    let joints = vec!["0.1"; n].join(", ");
    let out: String = text
        .lines()
        .map(|l| {
            format!(
                "{}, \"joints\": [{joints}]}}\n",
                l.trim_end().strip_suffix('}').unwrap()
            )
        })
        .collect();
    let path = dir.join(format!("joints{n}.jsonl"));
    std::fs::write(&path, out).unwrap();
    path
}

#[test]
fn a_six_axis_arm_turning_about_one_axis_is_told_to_turn_about_another_first() {
    let dir = tempfile::tempdir().unwrap();
    let first = |path: &str| {
        let (code, out, err) = run(&["calibrate", path, "--output", "text"]);
        assert_eq!(code, 3, "{err}");
        out.lines().nth(1).unwrap().to_string()
    };
    let six = first(with_joints(6, dir.path()).to_str().unwrap());
    assert!(six.starts_with("  - degenerate motions: record turns about another axis: the records give 6 joint angles"), "{six}");
    let none = first(
        testdata("low_dof/scara_eye-in-hand_s0.jsonl")
            .to_str()
            .unwrap(),
    );
    assert!(
        none.starts_with(
            "  - degenerate motions: record turns about another axis, if the robot can"
        ),
        "{none}"
    );
    // A 4-joint robot cannot: the prior leads.
    let four = first(with_joints(4, dir.path()).to_str().unwrap());
    assert!(
        !four.contains("record turns") && four.contains("--prior tz="),
        "{four}"
    );
}

#[test]
fn nan_in_json_is_said_as_nan_and_a_1e_10_matrix_is_projected_without_a_note() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nan.jsonl");
    std::fs::write(
        &path,
        "{\"base_from_gripper\": {\"translation\": [NaN, 0, 0], \"quaternion_xyzw\": [0, 0, 0, 1]}, \"camera_from_target\": {\"translation\": [0, 0, 0], \"quaternion_xyzw\": [0, 0, 0, 1]}}\n",
    )
    .unwrap();
    let (code, _, err) = run(&["calibrate", path.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("nan.jsonl:1:") && err.contains("NaN at column"),
        "{err}"
    );
    let clean = testdata("kinhec/pairs/nominal_stations_eih_s0.jsonl");
    let (_, _, err) = run(&["calibrate", clean.to_str().unwrap(), "--output", "json"]);
    assert!(!err.contains("orthonormal only to"), "{err}");
    let rounded = testdata("kinhec/mistakes/matrix_6dp__nominal_stations_eih_s0.jsonl");
    let (_, _, err) = run(&["calibrate", rounded.to_str().unwrap(), "--output", "json"]);
    assert!(err.contains("orthonormal only to"), "{err}");
}
