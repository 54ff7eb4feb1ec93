//! The pixel path's inputs (issue 59): each bad thing costs what it spoils and is named where it
//! is. A pixel no camera could have seen (1e20 or 1e308) is one mis-detection, left out and listed,
//! the same answer either way; a record whose target points are on one line is refused at its line
//! (`calibrate`) or skipped with a line (`online`); absurd intrinsics are refused at their field;
//! a robot's table, which feeds a test on the poses' residuals, is refused on the pixels; and the
//! faces: `--robot-world --output yaml` names the frames it is given, `verify --help` offers only
//! the outputs it prints.

mod common;

use common::{run, testdata};
use serde_json::Value;

fn file(rel: &str) -> String {
    testdata(rel).to_str().unwrap().to_owned()
}

/// board_eth's records with record `line` (from 1) changed by `change`.
fn board_with(
    dir: &std::path::Path,
    name: &str,
    line: usize,
    change: impl Fn(&mut Value),
) -> String {
    let text = std::fs::read_to_string(testdata("pixels/board_eth.jsonl")).unwrap();
    let lines: Vec<String> = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            let mut v: Value = serde_json::from_str(l).unwrap();
            if i + 1 == line {
                change(&mut v);
            }
            v.to_string()
        })
        .collect();
    let path = dir.join(name);
    std::fs::write(&path, lines.join("\n") + "\n").unwrap();
    path.to_str().unwrap().to_owned()
}

fn on_pixels<'a>(input: &'a str, intrinsics: &'a str) -> Vec<&'a str> {
    vec![
        "calibrate",
        input,
        "--setup",
        "eye-to-hand",
        "--method",
        "reprojection",
        "--intrinsics",
        intrinsics,
        "--output",
        "json",
    ]
}

#[test]
fn a_pixel_no_camera_could_see_is_one_mis_detection_named_by_its_line() {
    let dir = tempfile::tempdir().unwrap();
    let intrinsics = file("pixels/board_eth.intrinsics.yml");
    let mut answers = Vec::new();
    for value in [1e20, 1e308, -1e308] {
        let input = board_with(dir.path(), &format!("{value:e}.jsonl"), 8, |v| {
            v["detections"]["pixels"][3][0] = value.into();
        });
        let (code, out, err) = run(&on_pixels(&input, &intrinsics));
        assert_eq!(code, 0, "{value}: {err}");
        let v: Value = serde_json::from_str(&out).unwrap();
        let left_out = &v["reprojection"]["outlier_detections"];
        assert_eq!(
            left_out.as_array().map(Vec::len),
            Some(1),
            "{value}: {left_out}"
        );
        assert!(
            left_out[0][0].as_str().unwrap().ends_with(".jsonl:8") && left_out[0][1] == 3,
            "{value}: {left_out}"
        );
        // Every frame's RMS is a number (none is `null`), the left-out pixel in none.
        for f in v["reprojection"]["per_frame"].as_array().unwrap() {
            let rms = f["rms_px"].as_f64().unwrap_or(f64::NAN);
            assert!(rms.is_finite() && rms < 5.0, "{value}: {f}");
        }
        answers.push(v["x"].clone());
    }
    assert!(answers.windows(2).all(|w| w[0] == w[1]), "{answers:?}");
}

#[test]
fn a_record_on_one_line_is_named_by_its_line_and_costs_one_record_online() {
    let dir = tempfile::tempdir().unwrap();
    let intrinsics = file("pixels/board_eth.intrinsics.yml");
    let input = board_with(dir.path(), "collinear.jsonl", 8, |v| {
        let n = v["detections"]["target"].as_array().unwrap().len();
        v["detections"]["target"] = (0..n).map(|k| vec![0.01 * k as f64, 0.0, 0.0]).collect();
    });
    let (code, _, err) = run(&on_pixels(&input, &intrinsics));
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("collinear.jsonl:8")
            && err.contains("detections.target")
            && err.contains("one line"),
        "{err}"
    );
    let online = [
        "online",
        &input,
        "--setup",
        "eye-to-hand",
        "--intrinsics",
        &intrinsics,
        "--output",
        "text",
    ];
    let (code, out, err) = run(&online);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("collinear.jsonl:8"), "{err}");
    assert!(err.contains("29 record(s), 1 bad line(s) skipped"), "{err}");
    assert!(out.contains("estimate"), "{out}");
}

#[test]
fn absurd_or_conflicting_intrinsics_are_refused_at_their_field() {
    let dir = tempfile::tempdir().unwrap();
    let input = file("pixels/board_eth.jsonl");
    let text = std::fs::read_to_string(testdata("pixels/board_eth.intrinsics.yml")).unwrap();
    for (name, changed, field) in [
        (
            "fx",
            text.replacen("data: [ 905,", "data: [ 1e-300,", 1),
            "camera_matrix.fx",
        ),
        ("cx", text.replacen("641.2", "1e308", 1), "camera_matrix.cx"),
        (
            "k",
            text.replacen("-0.21", "1e300", 1),
            "distortion_coefficients",
        ),
        (
            "both",
            format!("{text}k: [900, 0, 640, 0, 900, 360, 0, 0, 1]\n"),
            "`k`",
        ),
        (
            "rows",
            text.replacen("rows: 3", "rows: three", 1),
            "camera_matrix",
        ),
        ("nul", text.replacen("dt: d", "dt: d\0", 1), "NUL"),
    ] {
        let path = dir.path().join(format!("{name}.yml"));
        std::fs::write(&path, &changed).unwrap();
        let (code, out, err) = run(&on_pixels(&input, path.to_str().unwrap()));
        assert_eq!(code, 2, "{name}: {out}");
        assert!(
            err.contains(&format!("{name}.yml:")) && err.contains(field),
            "{name}: {err}"
        );
    }
}

#[test]
fn a_robot_s_table_is_refused_on_the_pixels() {
    let input = file("pixels/board_eth.jsonl");
    let intrinsics = file("pixels/board_eth.intrinsics.yml");
    let table = file("kinhec/robots/panda.json");
    let mut args = on_pixels(&input, &intrinsics);
    args.extend(["--robot-model", &table]);
    let (code, out, err) = run(&args);
    assert_eq!(code, 2, "{out}");
    assert!(
        err.contains("robot-model") && err.contains("pixels"),
        "{err}"
    );
    let online = [
        "online",
        &input,
        "--setup",
        "eye-to-hand",
        "--intrinsics",
        &intrinsics,
        "--robot-model",
        &table,
    ];
    let (code, _, err) = run(&online);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("robot-model"), "{err}");
}

#[test]
fn the_robot_world_yaml_names_the_frames_it_is_given() {
    let input = file("opencv/opencv_eye-to-hand_noisy_10_13.jsonl");
    let args = [
        "calibrate",
        &input,
        "--setup",
        "eye-to-hand",
        "--robot-world",
        "--output",
        "yaml",
        "--parent-frame",
        "world_base",
        "--child-frame",
        "cam_optical",
    ];
    let (code, out, err) = run(&args);
    assert_eq!(code, 0, "{err}");
    let doc = &yaml_rust2::YamlLoader::load_from_str(&out).unwrap()[0];
    assert_eq!(
        doc["base_from_camera"]["parent_frame"].as_str(),
        Some("world_base"),
        "{out}"
    );
    assert_eq!(
        doc["base_from_camera"]["child_frame"].as_str(),
        Some("cam_optical"),
        "{out}"
    );
    assert!(
        doc["gripper_from_target"]["translation"]["x"]
            .as_f64()
            .is_some(),
        "{out}"
    );
}

#[test]
fn verify_offers_only_the_outputs_it_prints() {
    let (code, out, _) = run(&["verify", "--help"]);
    assert_eq!(code, 0);
    let start = out
        .find("--output <OUTPUT>")
        .expect("--output in verify --help");
    let rest = &out[start + 2..];
    let line = &rest[..rest.find("\n  -").unwrap_or(rest.len())];
    assert!(line.contains("json") && line.contains("text"), "{line}");
    assert!(
        !line.contains("yaml") && !line.contains("urdf") && !line.contains("ros2"),
        "{line}"
    );
    let (code, _, err) = run(&["verify", "--x", "x.json", "--output", "yaml", "r.jsonl"]);
    assert_eq!(code, 2, "{err}");
}
