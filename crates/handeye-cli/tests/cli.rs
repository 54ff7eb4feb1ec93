//! The command line end to end.

mod common;

use std::path::{Path, PathBuf};

use common::shared;

use assert_cmd::Command;
use serde_json::Value;

fn testdata(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata")
        .join(rel)
}

fn handeye() -> Command {
    Command::cargo_bin("handeye").unwrap()
}

fn matrix(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .flat_map(|r| r.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()))
        .collect()
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Runs and returns (exit code, stdout, stderr).
fn run(cmd: &mut Command) -> (i32, String, String) {
    let out = cmd.output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr,
    )
}

#[test]
fn calibrate_recovers_the_truth_of_the_exact_fixture() {
    let input = testdata("opencv/opencv_eye-in-hand_exact_10_11.jsonl");
    let expected: Value = serde_json::from_str(
        &std::fs::read_to_string(testdata(
            "opencv/opencv_eye-in-hand_exact_10_11.expected.json",
        ))
        .unwrap(),
    )
    .unwrap();
    for method in [
        "andreff",
        "andreff-joint",
        "tsai",
        "park",
        "horaud",
        "daniilidis",
        "refine",
    ] {
        let (code, out, err) =
            run(handeye().args(["calibrate", input.to_str().unwrap(), "--method", method]));
        assert_eq!(code, 0, "{method}: {err}");
        let v: Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v["method"], method);
        assert_eq!(v["setup"], "eye-in-hand");
        assert_eq!(v["frame"], "gripper_from_camera");
        assert_eq!(v["motions"], 45, "every pair of 10 poses by default");
        for key in ["translation", "quaternion_xyzw", "conditioning", "warnings"] {
            assert!(!v[key].is_null(), "{key}");
        }
        assert!(v["residual"]["rotation_deg_rms"].as_f64().unwrap() < 1e-6);
        assert!(v["units"]["rotation"].as_str().unwrap().contains("degrees"));
        // Noise-free: the bootstrap finds no uncertainty.
        assert!(
            v["uncertainty"]["rotation_deg"].as_f64().unwrap() < 1e-6,
            "{method}"
        );
        let d = max_diff(&matrix(&v["matrix"]), &matrix(&expected["truth"]["matrix"]));
        assert!(d < 1e-9, "{method}: {d:e}");
    }
}

#[test]
fn calibrate_eye_to_hand_and_all_pairs_match_opencv() {
    let input = testdata("opencv/opencv_eye-to-hand_noisy_10_13.jsonl");
    let expected: Value = serde_json::from_str(
        &std::fs::read_to_string(testdata(
            "opencv/opencv_eye-to-hand_noisy_10_13.expected.json",
        ))
        .unwrap(),
    )
    .unwrap();
    let (code, out, err) = run(handeye().args([
        "calibrate",
        input.to_str().unwrap(),
        "--setup",
        "eye-to-hand",
        "--pairs",
        "all",
        "--method",
        "park",
    ]));
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["frame"], "base_from_camera");
    assert_eq!(v["motions"], 45);
    let d = max_diff(
        &matrix(&v["matrix"]),
        &matrix(&expected["opencv"]["park"]["matrix"]),
    );
    assert!(d < 1e-6, "{d:e}");
}

/// The exact fixture rewritten as CSV with quaternions (and the camera direction inverted).
fn fixture_as_csv(dir: &Path) -> PathBuf {
    use handeye::io::{Format, Recording, RecordingOptions, Source};
    let source = Source::File {
        path: testdata("opencv/opencv_eye-in-hand_exact_10_11.jsonl"),
        format: Format::Auto,
    };
    let series = Recording::read(&source, &RecordingOptions::default()).unwrap();
    let mut text = String::from("stamp");
    for f in ["base_from_gripper", "target_from_camera"] {
        for s in ["x", "y", "z", "qx", "qy", "qz", "qw"] {
            text += &format!(",{f}_{s}");
        }
    }
    text.push('\n');
    for (k, p) in series.poses.iter().enumerate() {
        text += &format!("{k}");
        for t in [p.base_from_gripper, p.camera_from_target.inverse()] {
            let v = t.translation.vector;
            let q = handeye::TransformJson::from(&t).quaternion_xyzw;
            text += &format!(
                ",{},{},{},{},{},{},{}",
                v.x, v.y, v.z, q[0], q[1], q[2], q[3]
            );
        }
        text.push('\n');
    }
    let path = dir.join("poses.csv");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn calibrate_reads_csv() {
    let dir = tempfile::tempdir().unwrap();
    let csv = fixture_as_csv(dir.path());
    let (code, out, err) = run(handeye().args(["calibrate", csv.to_str().unwrap()]));
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    let expected: Value = serde_json::from_str(
        &std::fs::read_to_string(testdata(
            "opencv/opencv_eye-in-hand_exact_10_11.expected.json",
        ))
        .unwrap(),
    )
    .unwrap();
    assert!(max_diff(&matrix(&v["matrix"]), &matrix(&expected["truth"]["matrix"])) < 1e-9);
}

const I: &str = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";

fn good_line(k: usize) -> String {
    // Rotations about alternating axes, so that two motions determine X.
    let (c, s) = ((0.3 * k as f64).cos(), (0.3 * k as f64).sin());
    let r = if k.is_multiple_of(2) {
        format!("[[1,0,0,{k}],[0,{c},{},0],[0,{s},{c},0],[0,0,0,1]]", -s)
    } else {
        format!("[[{c},0,{s},0],[0,1,0,{k}],[{},0,{c},0],[0,0,0,1]]", -s)
    };
    format!("{{\"base_from_gripper\": {r}, \"camera_from_target\": {I}}}")
}

#[test]
fn bad_input_exits_2_naming_file_line_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "malformed.jsonl",
            format!("{}\n{{\"base_from_gripper\": [1, 2\n", good_line(0)),
            "2",
            "-",
        ),
        (
            "rotation.jsonl",
            format!(
                "{}\n{{\"base_from_gripper\": [[2,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]], \"camera_from_target\": {I}}}\n",
                good_line(0)
            ),
            "2",
            "base_from_gripper",
        ),
        (
            "nan.jsonl",
            format!(
                "{}\n{}\n{{\"base_from_gripper\": [[1,0,0,\"NaN\"],[0,1,0,0],[0,0,1,0],[0,0,0,1]], \"camera_from_target\": {I}}}\n",
                good_line(0),
                good_line(1)
            ),
            "3",
            "base_from_gripper[0][3]",
        ),
        (
            "missing.jsonl",
            format!("{}\n{{\"base_from_gripper\": {I}}}\n", good_line(0)),
            "2",
            "camera_from_target",
        ),
    ];
    for (name, text, line, field) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        let (code, _, err) = run(handeye().args(["calibrate", path.to_str().unwrap()]));
        assert_eq!(code, 2, "{name}: {err}");
        assert!(
            err.contains(name) && err.contains(&format!(":{line}:")) && err.contains(field),
            "{name}: {err}"
        );
    }
    // A whole file's fault names the file, not "line 0, field -"; an empty file is said empty.
    for (name, text, words) in [
        ("one.jsonl", format!("{}\n", good_line(0)), "1 pose pair(s)"),
        ("empty.jsonl", String::new(), "the file is empty"),
    ] {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        let (code, _, err) = run(handeye().args(["calibrate", path.to_str().unwrap()]));
        assert_eq!(code, 2, "{name}: {err}");
        assert!(
            err.contains(&format!("{name}: ")) && err.contains(words) && !err.contains(":0:"),
            "{name}: {err}"
        );
    }
    let (code, _, err) = run(handeye().args([
        "calibrate",
        dir.path().join("one.jsonl").to_str().unwrap(),
        "--method",
        "magic",
    ]));
    assert_eq!(code, 2, "{err}");
    let (code, _, err) = run(handeye().args(["calibrate", "no/such/file.jsonl"]));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("no/such/file.jsonl"));
}

/// Standard input has no extension: CSV is told from JSON Lines by its first character that is
/// neither blank nor in a comment, and line numbers still count the comment lines.
#[test]
fn csv_on_stdin_after_comments_is_detected_and_lines_are_counted() {
    let dir = tempfile::tempdir().unwrap();
    let csv = std::fs::read_to_string(fixture_as_csv(dir.path())).unwrap();
    let commented = format!("# exported by hand\r\n\r\n{}", csv.replace('\n', "\r\n"));
    let (code, out, err) = run(handeye()
        .args(["calibrate", "-"])
        .write_stdin(commented.clone()));
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["motions"], 45, "every pair of 10 poses by default");
    // Break the fifth data row (line 2 + 1 + 5 = 8): a NaN in the last column.
    let mut lines: Vec<String> = commented.split("\r\n").map(str::to_string).collect();
    let row = lines[7].rsplit_once(',').unwrap().0.to_string();
    lines[7] = format!("{row},NaN");
    let (code, _, err) = run(handeye()
        .args(["calibrate", "-"])
        .write_stdin(lines.join("\r\n")));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("-:8: field `target_from_camera_qw`"), "{err}");
}

#[test]
fn every_offered_format_is_accepted_and_errors_are_said_once() {
    if let Some(camodocal) = shared("camodocal/TransformPairsInput.yml") {
        let (code, out, err) = run(handeye()
            .args([
                "calibrate",
                "--setup",
                "eye-to-hand",
                "--format",
                "opencv-yaml",
            ])
            .arg(&camodocal));
        assert_eq!(code, 0, "{err}");
        let v: Value = serde_json::from_str(&out).unwrap();
        assert!(v["motions"].as_u64().unwrap() > 2);
    }
    let (code, _, err) = run(handeye().args(["calibrate", "no/such/file.jsonl"]));
    assert_eq!(code, 2, "{err}");
    assert_eq!(err.matches("No such file").count(), 1, "{err}");
    // A line that is not UTF-8 is bad input on its line, skipped by `online`.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("binary.jsonl");
    let mut bytes = format!("{}\n", good_line(0)).into_bytes();
    bytes.extend_from_slice(b"\xff\xfe\n");
    bytes.extend_from_slice(format!("{}\n", good_line(1)).as_bytes());
    std::fs::write(&path, bytes).unwrap();
    let (code, _, err) = run(handeye().arg("calibrate").arg(&path));
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("binary.jsonl:2: field `-`") && err.contains("UTF-8"),
        "{err}"
    );
    let (code, _, err) = run(handeye().arg("online").arg(&path));
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("1 bad line(s) skipped"), "{err}");
}

#[test]
fn degenerate_input_exits_3_with_what_to_do() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("one_axis.jsonl");
    let text: String = (0..5)
        .map(|k| {
            let (c, s) = ((0.3 * k as f64).cos(), (0.3 * k as f64).sin());
            format!("{{\"base_from_gripper\": [[{c},{},0,{k}],[{s},{c},0,0],[0,0,1,0],[0,0,0,1]], \"camera_from_target\": {I}}}\n", -s)
        })
        .collect();
    std::fs::write(&path, text).unwrap();
    let (code, _, err) = run(handeye().args(["calibrate", path.to_str().unwrap()]));
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("parallel") && err.contains("rotate about"),
        "{err}"
    );
}

/// The paper fixture's adaptive events, from the CLI reading standard input.
#[test]
fn online_reproduces_the_paper_fixture_from_stdin() {
    let input = std::fs::read_to_string(testdata("paper/series_2007_000_200.jsonl")).unwrap();
    let expected: Value = serde_json::from_str(
        &std::fs::read_to_string(testdata("paper/series_2007_000_200.expected.json")).unwrap(),
    )
    .unwrap();
    let truth = testdata("paper/series_2007_000_200.truth.json");
    for (selection, key) in [
        ("adaptive", "adaptive"),
        ("fixed", "fixed"),
        ("none", "conventional"),
    ] {
        let (code, out, err) = run(handeye()
            .args([
                "online",
                "-",
                "--estimator",
                "paper",
                "--selection",
                selection,
                "--error-source",
                "truth",
                "--d-max",
                "100",
                "--truth",
            ])
            .arg(&truth)
            .write_stdin(input.clone()));
        assert_eq!(code, 0, "{err}");
        let events: Vec<Value> = out
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        let expected = expected[key].as_array().unwrap();
        assert_eq!(events.len(), expected.len(), "{selection}");
        for (e, x) in events.iter().zip(expected) {
            assert_eq!(e["poses"], x["poses"]);
            // Rotation entries absolutely, translation relative to its length (mm, and large
            // for the conventional method's poor calibrations).
            let (a, b) = (matrix(&e["matrix"]), matrix(&x["matrix"]));
            let rot = [0, 1, 2, 4, 5, 6, 8, 9, 10]
                .iter()
                .map(|&k| (a[k] - b[k]).abs())
                .fold(0.0, f64::max);
            let dt: f64 = [3, 7, 11]
                .iter()
                .map(|&k| (a[k] - b[k]).powi(2))
                .sum::<f64>()
                .sqrt();
            let nt: f64 = [3, 7, 11].iter().map(|&k| b[k].powi(2)).sum::<f64>().sqrt();
            let d = rot.max(dt / nt);
            assert!(d < 1e-9, "{selection} {}: {d:e}", e["poses"]);
            assert_eq!(e["thresholds"].is_null(), selection != "adaptive");
            assert!(e["rms_r"].is_number());
        }
        assert!(err.contains("calibration(s) from 200 pose(s)"), "{err}");
    }
}

#[test]
fn online_skips_or_stops_at_a_bad_line() {
    let mut lines: Vec<String> =
        std::fs::read_to_string(testdata("paper/series_2007_000_200.jsonl"))
            .unwrap()
            .lines()
            .map(str::to_string)
            .collect();
    lines.insert(50, "{\"oops\": 1}".to_string());
    let input = lines.join("\n");
    let (code, out, err) = run(handeye()
        .args(["online", "-", "--d-max", "100"])
        .write_stdin(input.clone()));
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("-:51:") && err.contains("1 bad line(s) skipped"),
        "{err}"
    );
    assert!(!out.is_empty());
    let (code, _, err) = run(handeye()
        .args(["online", "-", "--d-max", "100", "--on-bad-line", "stop"])
        .write_stdin(input));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("-:51:"), "{err}");
}

#[test]
fn simulate_then_calibrate_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let poses = dir.path().join("sim.jsonl");
    let truth = dir.path().join("truth.json");
    let (code, _, err) = run(handeye()
        .args([
            "simulate",
            "--poses",
            "50",
            "--seed",
            "3",
            "--noise-free",
            "--out",
        ])
        .arg(&poses)
        .arg("--truth")
        .arg(&truth));
    assert_eq!(code, 0, "{err}");
    let (code, out, err) =
        run(handeye().args(["calibrate", poses.to_str().unwrap(), "--method", "tsai"]));
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    let t: Value = serde_json::from_str(&std::fs::read_to_string(&truth).unwrap()).unwrap();
    assert!(
        max_diff(
            &matrix(&v["matrix"]),
            &matrix(&t["gripper_from_camera"]["matrix"])
        ) < 1e-8
    );
}

#[test]
fn experiment_writes_tables_and_figures() {
    let dir = tempfile::tempdir().unwrap();
    let (code, out, err) = run(handeye()
        .args(["experiment", "all", "--series", "3", "--out"])
        .arg(dir.path()));
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("| **adaptive** |"));
    for f in [
        "accuracy.md",
        "accuracy.json",
        "adaptability.json",
        "realtime.json",
        "fig2_accuracy.svg",
        "fig2_accuracy.png",
        "fig3_adaptability.svg",
        "table1_realtime.png",
        "tracking.md",
        "fig_tracking.svg",
    ] {
        let meta = std::fs::metadata(dir.path().join(f)).unwrap_or_else(|_| panic!("{f} missing"));
        assert!(meta.len() > 100, "{f} is empty");
    }
    let svg = std::fs::read_to_string(dir.path().join("fig2_accuracy.svg")).unwrap();
    assert!(svg.contains("conventional"));
}

#[test]
fn demo_runs_without_files() {
    let (code, out, err) = run(handeye().args(["demo", "--poses", "200"]));
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("adaptive") && out.contains("conventional") && out.contains("True X"));
}

#[test]
fn online_accumulate_reports_the_running_estimate_and_a_change() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("jump.jsonl");
    // A simulated stream whose X jumps at pose 150, written as the CLI reads it.
    let jump = handeye::sim::Jump {
        at: 150,
        rotation_deg: 2.0,
        translation: 10.0,
    };
    let sim = handeye::sim::simulate(
        &handeye::sim::SimConfig {
            poses: 300,
            jump: Some(jump),
            ..Default::default()
        },
        3,
        0,
    );
    let text: String = sim
        .poses
        .iter()
        .map(|p| {
            let m = |t: &handeye::Transform| {
                let h = t.to_homogeneous();
                (0..4).map(|r| (0..4).map(|c| h[(r, c)]).collect::<Vec<_>>()).collect::<Vec<_>>()
            };
            serde_json::json!({"base_from_gripper": m(&p.base_from_gripper), "camera_from_target": m(&p.camera_from_target)}).to_string() + "\n"
        })
        .collect();
    std::fs::write(&path, text).unwrap();
    let (code, out, err) = run(handeye().args([
        "online",
        path.to_str().unwrap(),
        "--estimator",
        "accumulate",
    ]));
    assert_eq!(code, 0, "{err}");
    // The unit is inferred from the data and said.
    assert!(err.contains("length unit: millimetres"), "{err}");
    let lines: Vec<Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let changes: Vec<&Value> = lines.iter().filter(|l| l["change"].is_number()).collect();
    assert_eq!(changes.len(), 1, "{out}");
    let at = changes[0]["change"].as_u64().unwrap();
    assert!((145..=160).contains(&at), "change at {at}");
    assert!(changes[0]["confirmed"].as_u64().unwrap() < 190);
    // Estimates come on their own schedule, each with its uncertainty and the target pose, and
    // the last one at the end of the stream.
    let estimates: Vec<&Value> = lines.iter().filter(|l| l["estimate"].is_number()).collect();
    assert!(estimates.len() >= 3, "{out}");
    assert!(estimates.iter().all(|e| e["estimator"] == "accumulate"
        && e["uncertainty"]["rotation_deg"].is_number()
        && e["target"]["frame"] == "base_from_target"
        && e["matrix"].is_array()));
    let last = estimates.last().unwrap();
    assert_eq!(last["reason"], "end");
    assert_eq!(last["pose"], 300);
    assert!(last["since"].as_u64().unwrap() >= 145);
    // No estimate between the change and the new segment's first determined one.
    assert!(
        estimates
            .iter()
            .filter(|e| e["pose"].as_u64().unwrap() > at)
            .all(|e| e["since"].as_u64().unwrap() == last["since"].as_u64().unwrap()),
        "{out}"
    );
    // The summary shows the estimate the last line shows.
    let t = last["translation"].as_array().unwrap();
    assert!(
        err.contains(&format!("{:.6}", t[0].as_f64().unwrap())),
        "{err}"
    );
}

#[test]
fn online_infers_the_unit_and_refuses_to_guess() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, scale: f64| {
        let sim = handeye::sim::simulate(&handeye::sim::SimConfig::default(), 4, 0);
        let path = dir.path().join(name);
        let text: String = sim
            .poses
            .iter()
            .map(|p| {
                let m = |t: &handeye::Transform| {
                    let mut h = t.to_homogeneous();
                    for r in 0..3 {
                        h[(r, 3)] *= scale;
                    }
                    (0..4).map(|r| (0..4).map(|c| h[(r, c)]).collect::<Vec<_>>()).collect::<Vec<_>>()
                };
                serde_json::json!({"base_from_gripper": m(&p.base_from_gripper), "camera_from_target": m(&p.camera_from_target)}).to_string() + "\n"
            })
            .collect();
        std::fs::write(&path, text).unwrap();
        path
    };
    let poses = |out: &str| -> Vec<Value> {
        out.lines()
            .map(|l| serde_json::from_str::<Value>(l).unwrap()["poses"].clone())
            .collect()
    };
    let mm = write("mm.jsonl", 1.0);
    let m = write("m.jsonl", 1e-3);
    let (code, by_mm, err) =
        run(handeye().args(["online", mm.to_str().unwrap(), "--estimator", "paper"]));
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("millimetres") && err.contains("d_max = 100"),
        "{err}"
    );
    let (_, given, _) = run(handeye().args([
        "online",
        mm.to_str().unwrap(),
        "--d-max",
        "100",
        "--estimator",
        "paper",
    ]));
    let (code, by_m, err) =
        run(handeye().args(["online", m.to_str().unwrap(), "--estimator", "paper"]));
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("metres") && err.contains("d_max = 0.1"),
        "{err}"
    );
    // The same calibrations whichever unit the same motions are written in.
    assert!(poses(&by_mm).len() > 10);
    assert_eq!(poses(&by_mm), poses(&given));
    assert_eq!(poses(&by_mm), poses(&by_m));
    // Sizes that fit neither unit are flagged with what to pass, at the start and in the summary.
    let tiny = write("tiny.jsonl", 1e-5);
    let (code, _, err) = run(handeye().args(["online", tiny.to_str().unwrap()]));
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("warning: cannot tell the length unit") && err.contains("--unit m"),
        "{err}"
    );
    assert!(err.contains("the length unit was never told"), "{err}");
    let (code, _, err) = run(handeye().args(["online", tiny.to_str().unwrap(), "--unit", "mm"]));
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("length unit: millimetres (--unit)"), "{err}");
}

#[test]
fn online_with_the_papers_estimator_warns_about_misread_and_degenerate_input() {
    let kinhec = testdata("kinhec");
    let warnings = |file: &str, setup: &str| {
        let (code, _, err) = run(handeye().arg("online").arg(kinhec.join(file)).args([
            "--setup",
            setup,
            "--estimator",
            "paper",
        ]));
        assert_eq!(code, 0, "{err}");
        err.lines()
            .filter(|l| l.starts_with("warning:"))
            .map(str::to_string)
            .collect::<Vec<_>>()
    };
    for (file, setup) in [
        ("pairs/nominal_stations_eih_s0.jsonl", "eye-in-hand"),
        (
            "pairs/outliers_planar_flip_stations_eih_s0.jsonl",
            "eye-in-hand",
        ),
        ("pairs/pnp_stations_eth_s0.jsonl", "eye-to-hand"),
    ] {
        assert!(warnings(file, setup).is_empty(), "{file}");
    }
    let misread = warnings(
        "mistakes/robot_inverted__nominal_stations_eih_s0.jsonl",
        "eye-in-hand",
    );
    assert!(
        misread.iter().any(|w| w.contains("--fix robot-inverted")),
        "{misread:?}"
    );
    let mm = warnings(
        "mistakes/robot_mm__nominal_stations_eih_s0.jsonl",
        "eye-in-hand",
    );
    assert!(mm.iter().any(|w| w.contains("millimetres")), "{mm:?}");
    let one_axis = warnings(
        "pairs/degenerate_single_joint_continuous_eih_s0.jsonl",
        "eye-in-hand",
    );
    assert!(
        one_axis.iter().any(|w| w.contains("about one axis")),
        "{one_axis:?}"
    );
}

#[test]
fn opencvs_tsai_filter_says_what_it_dropped() {
    // Issue 33 item 19: OpenCV's filter drops motions without a word; a note says how many and why.
    let file = testdata("opencv/opencv_eye-in-hand_noisy_10_12.jsonl");
    let args = ["--pairs", "all", "--method", "tsai", "--output", "json"];
    let (code, out, err) = run(handeye()
        .arg("calibrate")
        .arg(&file)
        .args(args)
        .arg("--tsai-opencv-filter"));
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("note: OpenCV's Tsai motion filter kept 44 of 45 motions"),
        "{err}"
    );
    let report: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(report["motions"], 44);
    let (code, _, err) = run(handeye().arg("calibrate").arg(&file).args(args));
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("motion filter"), "{err}");
}

#[test]
fn advise_gives_lengths_in_the_input_unit_and_the_pivot_of_each_turn() {
    // Issue 33 item 16 (in part): the sizes carry the recording's unit, and each turn says where
    // it pivots (the flange: the poses the advice predicts turn the gripper frame about its origin).
    let file = testdata("kinhec/pairs/nominal_stations_eih_s0.jsonl");
    let (code, _, err) = run(handeye().arg("advise").arg(&file));
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("(input unit)"), "{err}");
    let sigma = err
        .lines()
        .find(|l| l.starts_with("X from 40 poses"))
        .unwrap();
    assert!(sigma.ends_with(" m"), "{sigma}");
    let next = err.lines().filter(|l| l.starts_with("next motion")).count();
    assert_eq!(next, 3, "{err}");
    // Each turn says its pivot: the flange, or the target (where it is in the gripper frame, in
    // the unit), so that the camera keeps it in view.
    assert!(
        err.lines()
            .filter(|l| l.starts_with("next motion"))
            .all(|l| (l.contains("through the flange")
                || l.contains(") m in the gripper frame (it stays where the camera sees it)"))
                && l.ends_with(" m")),
        "{err}"
    );
    let (code, out, err) = run(handeye().args(["advise", "--count", "3"]).arg(&file));
    assert_eq!(code, 0, "{err}");
    let advice: serde_json::Value = serde_json::from_str(&out[out.find('{').unwrap()..]).unwrap();
    for s in advice["suggestions"].as_array().unwrap() {
        let pivot = s["pivot_gripper"].as_array().unwrap();
        match s["pivot"].as_str().unwrap() {
            "flange" => assert!(pivot.iter().all(|v| v.as_f64() == Some(0.0))),
            "target" => {
                // About the target: 0.2 to 1.5 m from the flange on this rig.
                let d = pivot
                    .iter()
                    .map(|v| v.as_f64().unwrap().powi(2))
                    .sum::<f64>()
                    .sqrt();
                assert!((0.2..1.5).contains(&d), "{d}");
            }
            other => panic!("pivot {other}"),
        }
    }
}

#[test]
fn advise_says_you_are_done_when_x_is_within_the_goal() {
    // Issue 33 item 16: "you are done" against the user's goal; a goal within reach names the
    // motion after which it is predicted; a goal that is not two positive sizes exits 2.
    let file = testdata("kinhec/pairs/nominal_stations_eih_s0.jsonl");
    let (code, out, err) = run(handeye().args(["advise", "--goal", "0.2,0.005"]).arg(&file));
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("you are done"), "{err}");
    let a: serde_json::Value = serde_json::from_str(&out[out.find('{').unwrap()..]).unwrap();
    assert_eq!(a["goal"]["done"], true);
    assert!(a["suggestions"].as_array().unwrap().is_empty());
    let (code, out, err) = run(handeye()
        .args(["advise", "--goal", "0.0001,0.000001"])
        .arg(&file));
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("is not reached by the motions suggested"),
        "{err}"
    );
    let a: serde_json::Value = serde_json::from_str(&out[out.find('{').unwrap()..]).unwrap();
    assert_eq!(a["goal"]["done"], false);
    assert_eq!(a["suggestions"].as_array().unwrap().len(), 3);
    for bad in ["0,1", "1", "1,2,3", "x,1", "-1,1"] {
        let (code, _, err) = run(handeye()
            .arg("advise")
            .arg(format!("--goal={bad}"))
            .arg(&file));
        assert_eq!(code, 2, "{bad}: {err}");
        assert!(err.contains("--goal"), "{bad}: {err}");
    }
}

/// `calibrate --goal DEGREES,LENGTH` (issue 52): an X whose one-sigma uncertainty is above the
/// goal is not `good`, the text face says what `good` means, JSON says whether the goal is met.
#[test]
fn calibrate_judges_x_against_the_goal() {
    let file = testdata("kinhec/pairs/nominal_stations_eih_s0.jsonl");
    let json = |goal: &str| {
        let (code, out, _) = run(handeye()
            .arg("calibrate")
            .arg(&file)
            .args(["--goal", goal, "--output", "json"]));
        assert_eq!(code, 0, "{out}");
        serde_json::from_str::<Value>(&out).unwrap()
    };
    let r = json("1,0.01");
    let sigma = (
        r["uncertainty"]["rotation_deg"].as_f64().unwrap(),
        r["uncertainty"]["translation"].as_f64().unwrap(),
    );
    assert_eq!(r["verdict"], "good");
    assert_eq!(r["goal"]["met"], true);
    // A goal below X's one-sigma rotation: questionable, the warning says by how much.
    let r = json(&format!("{},0.01", sigma.0 / 2.0));
    assert_eq!(r["verdict"], "questionable");
    assert_eq!(r["goal"]["met"], false);
    let codes: Vec<&str> = r["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w["code"].as_str().unwrap())
        .collect();
    assert_eq!(codes, ["goal_missed"]);
    // Below the translation's alone, too.
    assert_eq!(json(&format!("1,{}", sigma.1 / 2.0))["goal"]["met"], false);
    // The text face: what good means, with and without a goal.
    let text = |extra: &[&str]| {
        let (code, out, _) = run(handeye()
            .arg("calibrate")
            .arg(&file)
            .args(extra)
            .args(["--output", "text"]));
        assert_eq!(code, 0, "{out}");
        out
    };
    assert!(
        text(&["--goal", "0.2,0.001"])
            .contains("Verdict: good (within your goal of 0.2° and 0.001 m, one sigma)")
    );
    assert!(text(&[]).contains("Verdict: good (trust X to the uncertainty printed below"));
    // A goal that is not two positive sizes is refused when the command line is read.
    let (code, _, err) = run(handeye()
        .arg("calibrate")
        .arg(&file)
        .args(["--goal", "0,1"]));
    assert_eq!(code, 2, "{err}");
}
