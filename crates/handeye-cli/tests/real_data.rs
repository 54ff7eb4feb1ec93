//! Real recordings of other projects, read in place from the shared folder (`ethz-asl/`,
//! `camodocal/`, each with its licence; skipped, one line each, where the folder is not):
//! the ethz-asl streams and the camodocal OpenCV-YAML pairs, end to end.

mod common;
use common::{run, shared};

use std::path::Path;

use serde_json::Value;

fn calibrate(args: &[&str]) -> Value {
    let mut all = vec!["calibrate"];
    all.extend_from_slice(args);
    let (code, out, err) = run(&all);
    assert_eq!(code, 0, "{err}");
    serde_json::from_str(&out).unwrap()
}

#[test]
fn ethz_streams_calibrate_and_run_online() {
    let Some(ethz) = shared("ethz-asl") else {
        return;
    };
    let robot = ethz.join("robot_arm_sim_B_H.csv");
    let camera = ethz.join("robot_arm_sim_W_E.csv");
    let (r, c) = (robot.to_str().unwrap(), camera.to_str().unwrap());
    let v = calibrate(&["--robot", r, "--camera", c, "--method", "refine"]);
    assert!(v["motions"].as_u64().unwrap() > 1000);
    // Both streams agree on one X: rotation residuals a fraction of a degree, translations mm.
    assert!(
        v["residual"]["rotation_deg_rms"].as_f64().unwrap() < 0.5,
        "{}",
        v["residual"]
    );
    assert!(
        v["residual"]["translation_rms"].as_f64().unwrap() < 0.01,
        "{}",
        v["residual"]
    );
    // The clock offset is searched by default: a simulation's streams share a clock to within a
    // fraction of their 100 Hz period.
    let offset = v["time_offset_s"].as_f64().unwrap();
    assert!(offset.abs() < 0.005, "{offset}");
    assert!(v["time_offset_sigma_s"].as_f64().unwrap() > 0.0);
    let (code, out, err) = run(&["online", "--robot", r, "--camera", c, "--d-max", "0.1"]);
    assert_eq!(code, 0, "{err}");
    let events: Vec<Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert!(!events.is_empty(), "{err}");
    assert!(
        events
            .iter()
            .all(|e| e["time_offset_s"] == offset && e["matrix"].is_array())
    );
}

#[test]
fn the_accumulating_estimators_reports_carry_the_clock_offset_found() {
    // kinhec's 30 Hz stream, its camera clock offset from the robot's (testdata/kinhec).
    let streams = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata/kinhec/streams");
    let robot = streams.join("temporal_30hz_eih_s0_robot.txt");
    let camera = streams.join("temporal_30hz_eih_s0_camera.txt");
    let (code, out, err) = run(&[
        "online",
        "--robot",
        robot.to_str().unwrap(),
        "--camera",
        camera.to_str().unwrap(),
        "--estimator",
        "accumulate",
        "--time-offset",
        "auto",
    ]);
    assert_eq!(code, 0, "{err}");
    let reports: Vec<Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert!(reports.len() >= 2, "{err}");
    let offset = reports[0]["time_offset_s"].as_f64().unwrap();
    assert!(offset.abs() > 0.01, "{offset}");
    assert!(
        reports
            .iter()
            .all(|v| v["estimate"].is_u64() && v["time_offset_s"] == offset),
        "{out}"
    );
}

#[test]
fn a_known_clock_offset_is_recovered_within_a_camera_period() {
    let Some(ethz) = shared("ethz-asl") else {
        return;
    };
    let robot = ethz.join("robot_arm_sim_B_H.csv");
    let camera = ethz.join("robot_arm_sim_W_E.csv");
    let camera_text = std::fs::read_to_string(&camera).unwrap();
    let stamps: Vec<f64> = camera_text
        .lines()
        .filter_map(|l| l.split(',').next()?.trim().parse().ok())
        .collect();
    let mut periods: Vec<f64> = stamps.windows(2).map(|w| w[1] - w[0]).collect();
    periods.sort_by(f64::total_cmp);
    let period = periods[periods.len() / 2];
    let dir = tempfile::tempdir().unwrap();
    // The recording's own offset, then the same camera stream shifted by a known amount.
    let base = calibrate(&[
        "--robot",
        robot.to_str().unwrap(),
        "--camera",
        camera.to_str().unwrap(),
        "--time-offset",
        "auto",
    ]);
    let own = base["time_offset_s"].as_f64().unwrap();
    for shift in [0.25, -0.4] {
        let shifted: String = camera_text
            .lines()
            .map(|l| {
                let (t, rest) = l.split_once(',').unwrap();
                format!("{},{rest}\n", t.trim().parse::<f64>().unwrap() + shift)
            })
            .collect();
        let path = dir.path().join("shifted.csv");
        std::fs::write(&path, shifted).unwrap();
        let v = calibrate(&[
            "--robot",
            robot.to_str().unwrap(),
            "--camera",
            path.to_str().unwrap(),
            "--time-offset",
            "auto",
        ]);
        let found = v["time_offset_s"].as_f64().unwrap();
        assert!(
            (found - own - shift).abs() < period,
            "shift {shift}: found {found}, own {own}, period {period}"
        );
        assert!(v["residual"]["rotation_deg_rms"].as_f64().unwrap() < 0.5);
    }
}

#[test]
fn camodocal_outliers_are_found_and_rejecting_them_lowers_the_residuals() {
    let Some(file) = shared("camodocal/TransformPairsInput.yml") else {
        return;
    };
    let f = file.to_str().unwrap();
    let with = calibrate(&[f, "--setup", "eye-to-hand"]);
    let without = calibrate(&[f, "--setup", "eye-to-hand", "--reject-outliers"]);
    let outliers = with["outliers"]["poses"].as_array().unwrap();
    assert!(!outliers.is_empty(), "{}", with["outliers"]);
    let warns_outliers = |v: &serde_json::Value| {
        v["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w["code"] == "outliers" && w["remedy"]["option"] == "reject_outliers")
    };
    assert!(warns_outliers(&with));
    // The rejected poses are the ones reported, and the poses kept raise no outlier warning.
    assert_eq!(without["outliers"]["poses"], with["outliers"]["poses"]);
    assert_eq!(without["outliers"]["rejected"], true);
    assert_eq!(
        without["poses"].as_u64().unwrap() + outliers.len() as u64,
        with["poses"].as_u64().unwrap()
    );
    assert!(!warns_outliers(&without));
    for key in ["rotation_deg_rms", "translation_rms"] {
        let (a, b) = (
            with["residual"][key].as_f64().unwrap(),
            without["residual"][key].as_f64().unwrap(),
        );
        assert!(b < 0.9 * a, "{key}: {a} with outliers, {b} without");
    }
    // A higher floor on the angle gap finds no more outliers.
    let loose = calibrate(&[f, "--setup", "eye-to-hand", "--outlier-deg", "30"]);
    let loose_count = loose["outliers"]["poses"].as_array().unwrap().len();
    assert!(loose_count <= outliers.len());
    assert_eq!(warns_outliers(&loose), loose_count > 0);
    // The eye-in-hand reading is inconsistent: refused, naming the readings that fit.
    let (code, _, err) = run(&["calibrate", f]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("--setup eye-to-hand") && err.contains("--fix robot-inverted"),
        "{err}"
    );
    // Kept as given on request, over consecutive motions its own noise leaves X undetermined,
    // and the refusal says why.
    let (code, _, err) = run(&[
        "calibrate",
        f,
        "--fix",
        "as-given",
        "--pairs",
        "consecutive",
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("not determined") && err.contains("--fix robot-inverted"),
        "{err}"
    );
    // Over every pair (the default) X is determined, and answered as questionable: the better
    // reading kept as given comes first among the cautions.
    let kept = calibrate(&[f, "--fix", "as-given"]);
    assert_eq!(kept["verdict"], "questionable");
    assert_eq!(kept["warnings"][0]["code"], "kept_as_given");
    // The outlier is named by its place in the file.
    let name = outliers[0]["name"].as_str().unwrap();
    assert!(
        name.contains("TransformPairsInput.yml:") && !name.ends_with(":0"),
        "{name}"
    );
}

#[test]
fn results_can_be_written_as_ros_yaml() {
    let Some(file) = shared("camodocal/TransformPairsInput.yml") else {
        return;
    };
    let (code, out, err) = run(&[
        "calibrate",
        file.to_str().unwrap(),
        "--setup",
        "eye-to-hand",
        "--output",
        "yaml",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("# frame: base_from_camera "), "{out}");
    let doc = &yaml_rust2::YamlLoader::load_from_str(&out).unwrap()[0];
    assert_eq!(
        doc["parameters"]["calibration_type"].as_str(),
        Some("eye_on_base")
    );
    for key in ["x", "y", "z"] {
        assert!(
            doc["transform"]["translation"][key].as_f64().is_some(),
            "{out}"
        );
    }
    for key in ["x", "y", "z", "w"] {
        assert!(
            doc["transform"]["rotation"][key].as_f64().is_some(),
            "{out}"
        );
    }
}
