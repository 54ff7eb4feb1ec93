//! Issue 12 at the command line: errors name the file given (not `-`), rounded rotations are
//! accepted with one note per file, an absurd value is a bad line that `online` skips.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use serde_json::Value;

fn testdata(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata")
        .join(rel)
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

fn handeye() -> Command {
    Command::cargo_bin("handeye").unwrap()
}

/// Every number of `text` with more than `decimals` decimals printed with `decimals`.
fn rounded(text: &str, decimals: usize) -> String {
    let mut out = String::new();
    let mut number = String::new();
    let flush = |number: &mut String, out: &mut String| {
        match number.parse::<f64>() {
            Ok(v) if number.contains('.') => out.push_str(&format!("{v:.decimals$}")),
            _ => out.push_str(number),
        }
        number.clear();
    };
    for c in text.chars() {
        if c.is_ascii_digit() || "-.eE+".contains(c) {
            number.push(c);
        } else {
            flush(&mut number, &mut out);
            out.push(c);
        }
    }
    flush(&mut number, &mut out);
    out
}

#[test]
fn rounded_rotations_are_accepted_with_one_note_per_file() {
    let dir = tempfile::tempdir().unwrap();
    let fixture = testdata("opencv/opencv_eye-in-hand_noisy_10_12.jsonl");
    let text = std::fs::read_to_string(&fixture).unwrap();
    let path = dir.path().join("rounded.jsonl");
    std::fs::write(&path, rounded(&text, 6)).unwrap();
    let (code, out, err) = run(handeye().arg("calibrate").arg(&path));
    assert_eq!(code, 0, "{err}");
    assert_eq!(err.matches("rounded when printed").count(), 1, "{err}");
    assert!(
        err.contains("rounded.jsonl: 20 rotation matrices orthonormal only to"),
        "{err}"
    );
    // The answer moves by no more than the rounding.
    let (_, full, _) = run(handeye().arg("calibrate").arg(&fixture));
    let (a, b): (Value, Value) = (
        serde_json::from_str(&out).unwrap(),
        serde_json::from_str(&full).unwrap(),
    );
    for r in 0..3 {
        for c in 0..3 {
            let d = a["matrix"][r][c].as_f64().unwrap() - b["matrix"][r][c].as_f64().unwrap();
            assert!(d.abs() < 1e-4, "{d}");
        }
    }
    // Printed in full: no note. Online tells the note once, at the end of the stream.
    let (code, _, err) = run(handeye().arg("calibrate").arg(&fixture));
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("rounded when printed"), "{err}");
    let (code, _, err) = run(handeye().arg("online").arg(&path));
    assert_eq!(code, 0, "{err}");
    assert_eq!(err.matches("rounded when printed").count(), 1, "{err}");
    // Two decimals are beyond rounding: refused with the deviation, on the first line.
    std::fs::write(&path, rounded(&text, 2)).unwrap();
    let (code, _, err) = run(handeye().arg("calibrate").arg(&path));
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("rounded.jsonl:1:") && err.contains("not orthonormal"),
        "{err}"
    );
}

#[test]
fn an_absurd_value_is_a_bad_line_that_online_skips() {
    let fixture = testdata("paper/series_2007_000_200.jsonl");
    let mut lines: Vec<String> = std::fs::read_to_string(fixture)
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect();
    // The translation of line 40's robot pose, made 1e308.
    let (head, tail) = lines[39].split_once("], [").unwrap();
    let (before, _) = head.rsplit_once(", ").unwrap();
    lines[39] = format!("{before}, 1e308], [{tail}");
    let input = lines.join("\n");
    let (code, out, err) = run(handeye()
        .args(["online", "-", "--d-max", "100"])
        .write_stdin(input.clone()));
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("-:40: field `base_from_gripper[0][3]`")
            && err.contains("not a plausible length")
            && err.contains("1 bad line(s) skipped"),
        "{err}"
    );
    assert!(!out.is_empty() && !out.contains("NaN"), "{out}");
    let (code, _, err) = run(handeye().args(["calibrate", "-"]).write_stdin(input));
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("-:40: field `base_from_gripper[0][3]`"),
        "{err}"
    );
}

#[test]
fn stream_errors_name_their_files() {
    let dir = tempfile::tempdir().unwrap();
    let robot = dir.path().join("robot.txt");
    let camera = dir.path().join("camera.txt");
    let stream = |t0: f64| -> String {
        (0..3)
            .map(|k| format!("{} 0 0 {k} 0 0 0 1\n", t0 + k as f64))
            .collect()
    };
    std::fs::write(&robot, stream(0.0)).unwrap();
    // Camera samples all after the robot stream: no pairs.
    std::fs::write(&camera, stream(10.0)).unwrap();
    let streams = |cmd: &str| {
        let mut c = handeye();
        c.args([cmd, "--robot"])
            .arg(&robot)
            .arg("--camera")
            .arg(&camera);
        c
    };
    for cmd in ["calibrate", "online"] {
        let (code, _, err) = run(&mut streams(cmd));
        assert_eq!(code, 2, "{err}");
        assert!(
            err.contains("camera.txt:0: field `t`") && err.contains("robot.txt"),
            "{err}"
        );
    }
    // A bad value in a stream names that file and its line.
    std::fs::write(&camera, stream(0.0).replace("1 0 0 1 0", "1 0 0 2e9 0")).unwrap();
    let (code, _, err) = run(&mut streams("calibrate"));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("camera.txt:2: field `z`"), "{err}");
    let mut bytes = stream(0.0).into_bytes();
    bytes.splice(20..20, *b"\xff");
    std::fs::write(&robot, bytes).unwrap();
    let (code, _, err) = run(&mut streams("calibrate"));
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("robot.txt:2:") && err.contains("UTF-8"),
        "{err}"
    );
}
