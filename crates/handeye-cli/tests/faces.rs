//! The faces of the command line (issue 17): numeric flags checked before use, a closed pipe is a
//! quiet success, the renamed flags keep their old spellings, the ROS outputs parse back to the
//! transform of the JSON, and the text summary on a terminal.

mod common;
use common::{run, shared, testdata};

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Command as Process, Stdio};

use assert_cmd::Command;
use nalgebra::{Matrix4, Quaternion, Rotation3, UnitQuaternion};
use serde_json::Value;

fn bin() -> PathBuf {
    assert_cmd::cargo::cargo_bin("handeye")
}

const NOISY: &str = "opencv/opencv_eye-in-hand_noisy_10_12.jsonl";

/// A simulated stream (millimetres) in a temporary directory.
fn stream(dir: &Path, poses: usize) -> PathBuf {
    let path = dir.join("s.jsonl");
    let (code, _, err) = run(&[
        "simulate",
        "--poses",
        &poses.to_string(),
        "--out",
        path.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    path
}

#[test]
fn every_numeric_flag_out_of_range_is_exit_2_naming_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let s = stream(dir.path(), 40);
    let s = s.to_str().unwrap();
    let f = testdata(NOISY);
    let f = f.to_str().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (
            &[
                "online",
                s,
                "--selection",
                "fixed",
                "--n-init",
                "4611686018427387904",
            ],
            "--n-init",
        ),
        (&["online", s, "--n-init", "1000000000000"], "--n-init"),
        (&["online", s, "--n-init", "1"], "--n-init"),
        (
            &["simulate", "--poses", "18446744073709551615", "--out", "-"],
            "--poses",
        ),
        (&["demo", "--poses", "18446744073709551615"], "--poses"),
        (&["bench", "--poses", "18446744073709551615"], "--poses"),
        (&["bench", "--min-time", "nan"], "--min-time"),
        (&["bench", "--min-time", "1e308"], "--min-time"),
        (&["calibrate", f, "--max-gap", "nan"], "--max-gap"),
        (&["calibrate", f, "--outlier-deg", "nan"], "--outlier-deg"),
        (&["calibrate", f, "--time-offset", "nan"], "--time-offset"),
        (
            &["calibrate", f, "--bootstrap", "1000000000000"],
            "--bootstrap",
        ),
        (&["online", s, "--outlier-deg", "nan"], "--outlier-deg"),
        (&["online", s, "--time-offset", "inf"], "--time-offset"),
        (&["online", s, "--max-gap", "-1"], "--max-gap"),
        (&["online", s, "--every", "0"], "--every"),
        (&["online", s, "--shrink", "nan"], "--shrink"),
        (&["online", s, "--interval", "0"], "--interval"),
        (&["online", s, "--relax-down", "1.5"], "--relax-down"),
        (&["online", s, "--relax-up", "nan"], "--relax-up"),
        (&["online", s, "--explore", "0"], "--explore"),
        (&["online", s, "--rms-r-max", "nan"], "--rms-r-max"),
        (&["online", s, "--rms-t-max", "-0.1"], "--rms-t-max"),
        (&["online", s, "--alpha-min-deg", "95"], "--alpha-min-deg"),
        (&["online", s, "--alpha-min", "2"], "--alpha-min"),
        (&["online", s, "--beta-min-deg", "nan"], "--beta-min-deg"),
        (&["online", s, "--d-max", "inf"], "--d-max"),
        (&["experiment", "accuracy", "--series", "0"], "--series"),
        (&["advise", f, "--count", "0"], "--count"),
        (&["advise", f, "--count", "18446744073709551616"], "--count"),
    ];
    for (args, flag) in cases {
        let (code, out, err) = run(args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(flag), "{args:?} does not name {flag}: {err}");
        assert!(out.is_empty(), "{args:?} printed {out}");
    }
}

/// Spawns the command, reads `lines` lines of its stdout, closes the pipe and waits.
fn close_early(args: &[&str], lines: usize) -> (i32, String) {
    let mut child = Process::new(bin())
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    {
        let mut out = BufReader::new(child.stdout.take().unwrap());
        let mut line = String::new();
        for _ in 0..lines {
            line.clear();
            out.read_line(&mut line).unwrap();
        }
    }
    let mut err = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    (child.wait().unwrap().code().unwrap_or(-1), err)
}

#[test]
fn a_closed_pipe_exits_0_quietly() {
    let dir = tempfile::tempdir().unwrap();
    let s = stream(dir.path(), 3000);
    let s = s.to_str().unwrap();
    let f = testdata(NOISY);
    for (args, lines) in [
        (vec!["demo", "--poses", "200"], 1),
        (vec!["demo", "--poses", "200"], 0),
        (vec!["simulate", "--poses", "20000", "--out", "-"], 1),
        (vec!["online", s, "--selection", "none"], 1),
        (
            vec!["online", s, "--estimator", "accumulate", "--every", "1"],
            1,
        ),
        (
            vec!["calibrate", f.to_str().unwrap(), "--output", "json"],
            0,
        ),
    ] {
        let (code, err) = close_early(&args, lines);
        assert_eq!(code, 0, "{args:?}: {err}");
        for word in ["Broken pipe", "panicked", "error"] {
            assert!(!err.contains(word), "{args:?} said {word}: {err}");
        }
    }
}

#[test]
fn the_renamed_flags_keep_their_old_spellings() {
    let dir = tempfile::tempdir().unwrap();
    let s = stream(dir.path(), 300);
    let s = s.to_str().unwrap();
    let timeless = |out: &str| -> Vec<Value> {
        out.lines()
            .map(|l| {
                let mut v: Value = serde_json::from_str(l).unwrap();
                v.as_object_mut().unwrap().remove("seconds");
                v
            })
            .collect()
    };
    let sine = 15f64.to_radians().sin().to_string();
    let (code, old, err) = run(&["online", s, "--alpha-min", &sine]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("deprecated") && err.contains("--alpha-min-deg"),
        "{err}"
    );
    let (code, new, err) = run(&["online", s, "--alpha-min-deg", "15"]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("deprecated"), "{err}");
    let (code, default, _) = run(&["online", s]);
    assert_eq!(code, 0);
    assert!(!new.is_empty());
    assert_eq!(timeless(&old), timeless(&new));
    assert_eq!(timeless(&default), timeless(&new));
    let (code, _, err) = run(&["online", s, "--alpha-min", "0.2", "--alpha-min-deg", "12"]);
    assert_eq!(code, 2, "both spellings at once: {err}");

    // bench's lists: comma- or space-separated, as its help shows the defaults.
    let quick = [
        "--min-time",
        "0.001",
        "--pairs",
        "consecutive",
        "--methods",
        "andreff",
    ];
    let datasets = |out: &str| -> Vec<String> {
        let v: Value = serde_json::from_str(out).unwrap();
        v["solvers"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| r["dataset"].as_str().unwrap().to_string())
            .collect()
    };
    let mut comma = vec!["bench", "--quiet", "--poses", "10,20"];
    comma.extend(quick);
    let mut space = vec!["bench", "--quiet", "--poses", "10", "20"];
    space.extend(quick);
    let (code, a, err) = run(&comma);
    assert_eq!(code, 0, "{err}");
    let (code, b, err) = run(&space);
    assert_eq!(code, 0, "{err}");
    assert_eq!(datasets(&a), ["sim10", "sim20"]);
    assert_eq!(datasets(&a), datasets(&b));

    // The YAML is easy_handeye2's (its `transform`), X's frame name in a comment.
    let (code, yaml, err) = run(&[
        "calibrate",
        testdata(NOISY).to_str().unwrap(),
        "--output",
        "yaml",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(yaml.contains("\n# frame: gripper_from_camera "), "{yaml}");
    let doc = &yaml_rust2::YamlLoader::load_from_str(&yaml).unwrap()[0];
    assert!(
        doc["transform"]["translation"]["x"].as_f64().is_some(),
        "{yaml}"
    );
    assert!(
        doc["transform"]["rotation"]["w"].as_f64().is_some(),
        "{yaml}"
    );
}

#[test]
fn simulate_out_dash_writes_to_stdout() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(bin())
        .current_dir(dir.path())
        .args(["simulate", "--poses", "25", "--out", "-"])
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert_eq!(text.lines().count(), 25);
    for line in text.lines() {
        let v: Value = serde_json::from_str(line).unwrap();
        assert!(v.get("base_from_gripper").is_some());
    }
    assert!(
        !dir.path().join("-").exists(),
        "a file named `-` was written"
    );
}

#[test]
fn every_help_lists_the_exit_codes_and_the_units_of_the_accuracies() {
    for command in [
        "calibrate",
        "online",
        "inspect",
        "advise",
        "simulate",
        "experiment",
        "demo",
        "bench",
    ] {
        let (code, out, _) = run(&[command, "--help"]);
        assert_eq!(code, 0);
        assert!(out.contains("Exit codes: 0 success"), "{command}: {out}");
        assert!(
            out.contains("2 bad input") && out.contains("3 valid input"),
            "{command}"
        );
    }
    let (_, top, _) = run(&["--help"]);
    assert!(top.contains("Exit codes"));
    let (_, online, _) = run(&["online", "--help"]);
    assert!(online.contains("unit-free"), "{online}");
    assert!(online.contains("--alpha-min-deg"), "{online}");
}

/// The JSON result of `calibrate` and its transform.
fn json_result(args: &[&str]) -> (Value, Matrix4<f64>) {
    let mut all = vec!["calibrate"];
    all.extend(args);
    all.extend(["--output", "json"]);
    let (code, out, err) = run(&all);
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    let m: Vec<f64> = v["matrix"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|r| r.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()))
        .collect();
    (v, Matrix4::from_row_slice(&m))
}

fn homogeneous(t: [f64; 3], r: Rotation3<f64>) -> Matrix4<f64> {
    let mut m = r.to_homogeneous();
    m[(0, 3)] = t[0];
    m[(1, 3)] = t[1];
    m[(2, 3)] = t[2];
    m
}

fn quaternion(t: [f64; 3], [x, y, z, w]: [f64; 4]) -> Matrix4<f64> {
    let q = UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z));
    homogeneous(t, q.to_rotation_matrix())
}

/// The number after `key` up to the next separator.
fn number_after(text: &str, key: &str) -> f64 {
    let start = text
        .find(key)
        .unwrap_or_else(|| panic!("no {key} in {text}"))
        + key.len();
    let rest = text[start..].trim_start_matches([' ', '"', ':']);
    let end = rest
        .find(|c: char| !(c.is_ascii_digit() || "+-.eE".contains(c)))
        .unwrap_or(rest.len());
    rest[..end].parse().unwrap()
}

fn attribute(text: &str, name: &str) -> Vec<f64> {
    let start = text.find(&format!("{name}=\"")).unwrap() + name.len() + 2;
    let end = start + text[start..].find('"').unwrap();
    text[start..end]
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect()
}

#[test]
fn ros2_yaml_and_urdf_parse_back_to_the_transform() {
    let f = testdata(NOISY);
    let f = f.to_str().unwrap();
    let camodocal = shared("camodocal/TransformPairsInput.yml");
    let camodocal = camodocal.as_deref().map(|p| p.to_str().unwrap());
    let faces = [
        Some((f, "eye-in-hand", "gripper", vec![])),
        camodocal.map(|c| (c, "eye-to-hand", "base", vec![])),
        Some((
            f,
            "eye-in-hand",
            "tool0",
            vec!["--parent-frame", "tool0", "--child-frame", "camera_optical"],
        )),
    ];
    for (input, setup, parent, frames) in faces.into_iter().flatten() {
        let child = if frames.is_empty() {
            "camera"
        } else {
            "camera_optical"
        };
        let mut args = vec![input, "--setup", setup];
        args.extend(&frames);
        let (_, x) = json_result(&args);
        let face = |name: &str| {
            let mut all = vec!["calibrate"];
            all.extend(&args);
            all.extend(["--output", name]);
            let (code, out, err) = run(&all);
            assert_eq!(code, 0, "{err}");
            out
        };

        let ros2 = face("ros2");
        let line = ros2
            .lines()
            .find(|l| l.starts_with("ros2 run tf2_ros static_transform_publisher"))
            .unwrap();
        let get = |key: &str| number_after(line, key);
        let from_line = quaternion(
            [get("--x "), get("--y "), get("--z ")],
            [get("--qx "), get("--qy "), get("--qz "), get("--qw ")],
        );
        assert!((from_line - x).abs().max() < 1e-12, "{line}");
        assert!(
            line.ends_with(&format!("--frame-id {parent} --child-frame-id {child}")),
            "{line}"
        );
        let launch = &ros2[ros2.find("Node(").unwrap()..];
        let from_launch = quaternion(
            [
                number_after(launch, "\"--x\", \""),
                number_after(launch, "\"--y\", \""),
                number_after(launch, "\"--z\", \""),
            ],
            [
                number_after(launch, "\"--qx\", \""),
                number_after(launch, "\"--qy\", \""),
                number_after(launch, "\"--qz\", \""),
                number_after(launch, "\"--qw\", \""),
            ],
        );
        assert!((from_launch - x).abs().max() < 1e-12, "{launch}");
        assert!(launch.contains(&format!(
            "\"--frame-id\", \"{parent}\", \"--child-frame-id\", \"{child}\""
        )));

        let yaml = face("yaml");
        let doc = &yaml_rust2::YamlLoader::load_from_str(&yaml).unwrap()[0];
        let number = |section: &str, key: &str| {
            doc["transform"][section][key]
                .as_f64()
                .unwrap_or_else(|| panic!("{section}.{key}: {yaml}"))
        };
        let from_yaml = quaternion(
            [
                number("translation", "x"),
                number("translation", "y"),
                number("translation", "z"),
            ],
            [
                number("rotation", "x"),
                number("rotation", "y"),
                number("rotation", "z"),
                number("rotation", "w"),
            ],
        );
        assert!((from_yaml - x).abs().max() < 1e-12, "{yaml}");
        let kind = if setup == "eye-in-hand" {
            "eye_in_hand"
        } else {
            "eye_on_base"
        };
        assert!(
            yaml.contains(&format!("\n  calibration_type: {kind}\n")),
            "{yaml}"
        );
        let parent_key = if setup == "eye-in-hand" {
            "robot_effector_frame"
        } else {
            "robot_base_frame"
        };
        assert!(
            yaml.contains(&format!("\n  {parent_key}: {parent}\n")),
            "{yaml}"
        );
        assert!(
            yaml.contains(&format!("\n  tracking_base_frame: {child}\n")),
            "{yaml}"
        );

        let urdf = face("urdf");
        let xyz = attribute(&urdf, "xyz");
        let rpy = attribute(&urdf, "rpy");
        // URDF: fixed axes, R = Rz(yaw) Ry(pitch) Rx(roll).
        let r = Rotation3::from_axis_angle(&nalgebra::Vector3::z_axis(), rpy[2])
            * Rotation3::from_axis_angle(&nalgebra::Vector3::y_axis(), rpy[1])
            * Rotation3::from_axis_angle(&nalgebra::Vector3::x_axis(), rpy[0]);
        let from_urdf = homogeneous([xyz[0], xyz[1], xyz[2]], r);
        assert!((from_urdf - x).abs().max() < 1e-12, "{urdf}");
        assert!(
            urdf.contains(&format!("<parent link=\"{parent}\"/>")),
            "{urdf}"
        );
        assert!(
            urdf.contains(&format!("<child link=\"{child}\"/>")),
            "{urdf}"
        );
    }
}

#[test]
fn a_terminal_gets_the_summary_and_a_pipe_the_json() {
    let f = testdata(NOISY);
    let (json, _) = json_result(&[f.to_str().unwrap()]);
    // Piped, without --output: the JSON, the same as --output json.
    let (code, piped, err) = run(&["calibrate", f.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let piped: Value = serde_json::from_str(&piped).unwrap();
    assert_eq!(piped["matrix"], json["matrix"]);
    assert_eq!(piped["warnings"], json["warnings"]);

    // On a pseudo-terminal (util-linux `script`).
    let command = format!("'{}' calibrate '{}'", bin().display(), f.display());
    let Ok(out) = Process::new("script")
        .args(["-qec", &command, "/dev/null"])
        .stdin(Stdio::null())
        .output()
    else {
        eprintln!("skipped: no `script` to make a pseudo-terminal");
        return;
    };
    assert!(out.status.success(), "{out:?}");
    let text = String::from_utf8_lossy(&out.stdout).replace('\r', "");
    assert!(
        !text.trim_start().starts_with('{'),
        "JSON on a terminal: {text}"
    );
    assert!(text.contains("X = gripper_from_camera"), "{text}");
    assert!(
        text.contains("translation") && text.contains(" mm"),
        "{text}"
    );
    assert!(text.contains("roll") && text.contains("pitch") && text.contains("yaw"));
    assert!(text.contains("quaternion"));
    assert!(text.contains("Verdict: good") || text.contains("Verdict: questionable"));
    assert!(text.contains("Uncertainty (one sigma)"));
    assert!(text.contains("Residuals"));
    assert!(text.contains("Next:"));
    // The numbers are the JSON's.
    let t = json["translation"].as_array().unwrap()[0].as_f64().unwrap();
    assert!(text.contains(&format!("{t:.6}")), "{text}");

    // `--output text` when piped; a refusal says so.
    let (code, text, _) = run(&["calibrate", f.to_str().unwrap(), "--output", "text"]);
    assert_eq!(code, 0);
    assert!(text.contains("Verdict: "));
    let dir = tempfile::tempdir().unwrap();
    let still = dir.path().join("still.jsonl");
    let eye = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";
    let line = format!("{{\"base_from_gripper\": {eye}, \"camera_from_target\": {eye}}}\n");
    std::fs::write(&still, line.repeat(4)).unwrap();
    let (code, text, err) = run(&["calibrate", still.to_str().unwrap(), "--output", "text"]);
    assert_eq!(code, 3, "{text}{err}");
    assert!(text.starts_with("Verdict: refused"), "{text}");
}

#[test]
fn online_writes_its_last_x_for_ros_and_a_line_per_calibration_for_a_person() {
    let dir = tempfile::tempdir().unwrap();
    let s = stream(dir.path(), 300);
    let s = s.to_str().unwrap();
    for estimator in ["paper", "accumulate"] {
        let (code, json, err) = run(&["online", s, "--estimator", estimator]);
        assert_eq!(code, 0, "{err}");
        let last: Value =
            serde_json::from_str(json.lines().rfind(|l| !l.contains("\"change\"")).unwrap())
                .unwrap();
        let m: Vec<f64> = last["matrix"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(|r| r.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()))
            .collect();
        let x = Matrix4::from_row_slice(&m);
        let (code, urdf, err) = run(&[
            "online",
            s,
            "--estimator",
            estimator,
            "--output",
            "urdf",
            "--child-frame",
            "cam",
        ]);
        // The paper's calibrations carry no uncertainty: they are not published (issue 33).
        if estimator == "paper" {
            assert_eq!(code, 2, "{err}");
            assert!(
                urdf.is_empty() && err.contains("--estimator accumulate"),
                "{err}"
            );
            continue;
        }
        assert_eq!(code, 0, "{err}");
        assert!(
            err.contains("translation converted from millimetres to metres for ROS"),
            "{err}"
        );
        // In metres: the millimetres of the JSON / 1000.
        let xyz: Vec<f64> = attribute(&urdf, "xyz").iter().map(|v| v * 1e3).collect();
        let rpy = attribute(&urdf, "rpy");
        let r = Rotation3::from_euler_angles(rpy[0], rpy[1], rpy[2]);
        let from_urdf = homogeneous([xyz[0], xyz[1], xyz[2]], r);
        assert!((from_urdf - x).abs().max() < 1e-9, "{estimator}: {urdf}");
        assert!(urdf.contains("<child link=\"cam\"/>"), "{urdf}");
        let (code, text, err) = run(&["online", s, "--estimator", estimator, "--output", "text"]);
        assert_eq!(code, 0, "{err}");
        // A line per calibration, then (issue 52) the estimate to copy, from its `X = ` line on.
        assert_eq!(
            text.lines().take_while(|l| !l.starts_with("X = ")).count(),
            json.lines().filter(|l| !l.contains("\"change\"")).count()
        );
        assert!(text.lines().all(|l| !l.starts_with('{')), "{text}");
    }
}
