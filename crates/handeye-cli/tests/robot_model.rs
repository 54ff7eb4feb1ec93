//! `calibrate --robot-model FILE` end to end (issue 29): the robot's DH table turns the
//! systematic-error test toward what an uncalibrated robot does to the residuals, and a table that
//! is not the one the poses were reported through is refused by name, as is a table in another
//! unit, a recording without joint angles and a broken file.

mod common;

use std::path::Path;

use common::{run, testdata};
use serde_json::Value;

fn robot(name: &str) -> String {
    path(&testdata(&format!("kinhec/robots/{name}.json")))
}

fn recording(name: &str) -> String {
    path(&testdata(&format!("kinhec/systematic/{name}.jsonl")))
}

fn path(p: &Path) -> String {
    p.to_str().expect("a UTF-8 path").to_owned()
}

/// Runs `handeye calibrate ARGS --output json`: (exit code, stdout, stderr).
fn calibrate(args: &[&str]) -> (i32, String, String) {
    run(&[&["calibrate"], args, &["--output", "json"]].concat())
}

/// `file` with each JSON Lines record changed by `edit`, written to `to`.
fn rewrite(file: &str, to: &Path, edit: impl Fn(&mut Value)) {
    let text = std::fs::read_to_string(file).unwrap();
    let lines: Vec<String> = text
        .lines()
        .map(|line| {
            let mut v: Value = serde_json::from_str(line).unwrap();
            edit(&mut v);
            v.to_string()
        })
        .collect();
    std::fs::write(to, lines.join("\n")).unwrap();
}

/// The warning `systematic_error` of a report.
fn systematic_warning(report: &Value) -> &Value {
    report["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .find(|w| w["code"] == "systematic_error")
        .unwrap_or_else(|| panic!("no systematic_error in {report}"))
}

/// `calibrate --setup eye-to-hand` of `file` with `extra` arguments, its report (exit 0).
fn calibrate_eth(file: &str, extra: &[&str]) -> Value {
    let (code, out, err) = calibrate(&[&[file, "--setup", "eye-to-hand"], extra].concat());
    assert_eq!(code, 0, "{err}");
    serde_json::from_str(&out).unwrap()
}

/// A 1 mm / 0.1° DH error of a UR10 seen from outside (kinhec, `generate_systematic.py`): with
/// the table the residuals lie along the table's directions far beyond chance and the warning
/// names the robot's kinematics. Random robot noise on the same motions stays unflagged; PnP noise
/// that grows with the view, flagged by the neighbour test, is not explained by the table, and
/// the warning says to look at the camera first.
#[test]
fn the_robots_table_shows_an_uncalibrated_robot_and_leaves_noise_alone() {
    let table = robot("ur10");
    let file = recording("dh1_ur10_eth_s0");
    let without = calibrate_eth(&file, &[]);
    assert!(without["systematic"].get("kinematic").is_none());
    let with = calibrate_eth(&file, &["--robot-model", &table]);
    let systematic = &with["systematic"];
    assert!(
        systematic["kinematic"]["z"].as_f64().unwrap() < -5.0,
        "{systematic}"
    );
    assert!(
        systematic["kinematic"]["parameters"].as_u64().unwrap() > 0,
        "{systematic}"
    );
    assert_eq!(systematic["flagged"], true, "{systematic}");
    let p = |r: &Value| r["p_value"].as_f64().unwrap();
    assert!(p(systematic) < p(&without["systematic"]), "{systematic}");
    assert_eq!(with["verdict"], "questionable");
    let message = systematic_warning(&with)["message"].as_str().unwrap();
    assert!(
        message.contains("lies along what errors of the robot's DH table do"),
        "{message}"
    );

    let control = calibrate_eth(
        &recording("ctl_robot_ur10_eth_s0"),
        &["--robot-model", &table],
    );
    assert!(
        control["systematic"]["kinematic"]["z"].as_f64().unwrap() > -3.0,
        "{control}"
    );
    assert_eq!(control["systematic"]["flagged"], false, "{control}");

    let camera = calibrate_eth(
        &recording("ctl_pnp_ur10_eth_s0"),
        &["--robot-model", &table],
    );
    assert!(
        camera["systematic"]["kinematic"]["z"].as_f64().unwrap() > -3.0,
        "{camera}"
    );
    let warning = systematic_warning(&camera);
    let message = warning["message"].as_str().unwrap();
    assert!(
        message.contains("does not lie along what errors of the robot's DH table do"),
        "{message}"
    );
    assert!(warning["kinematic_z"].as_f64().is_some(), "{warning}");
}

/// Another robot's table, joint angles in degrees, a table in millimetres for poses in metres, a
/// recording without joint angles: exit 2, naming `--robot-model` and what is wrong.
#[test]
fn a_table_that_is_not_the_robots_is_refused_by_name() {
    let file = recording("dh1_ur10_eth_s0");
    let refused = |file: &str, table: &str, words: &str| {
        let (code, _, err) = calibrate(&[file, "--setup", "eye-to-hand", "--robot-model", table]);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains("robot-model") && err.contains(words), "{err}");
    };
    // A seven-joint arm's table for a six-joint recording.
    refused(
        &file,
        &robot("panda"),
        "the table has 7 joints, pose 1 carries 6",
    );
    // Six joints, but another arm's geometry: the hand does not turn as the table says.
    refused(
        &file,
        &robot("irb120"),
        "does not turn the hand as the poses do",
    );

    let dir = tempfile::tempdir().unwrap();
    // The joint angles in degrees (a unit mistake in the recording).
    let degrees = dir.path().join("degrees.jsonl");
    rewrite(&file, &degrees, |v| {
        let q: Vec<f64> = v["joints"]
            .as_array()
            .unwrap()
            .iter()
            .map(|q| q.as_f64().unwrap().to_degrees())
            .collect();
        v["joints"] = serde_json::json!(q);
    });
    refused(&path(&degrees), &robot("ur10"), "joint angles in degrees");
    // The same poses without their joint angles.
    let bare = dir.path().join("bare.jsonl");
    rewrite(&file, &bare, |v| {
        v.as_object_mut().unwrap().remove("joints");
    });
    refused(
        &path(&bare),
        &robot("ur10"),
        "needs the joint angles of every pose",
    );

    // The table's lengths in millimetres.
    let mut table: Value =
        serde_json::from_str(&std::fs::read_to_string(robot("ur10")).unwrap()).unwrap();
    for column in ["a", "d"] {
        let mm: Vec<f64> = table[column]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| 1000.0 * v.as_f64().unwrap())
            .collect();
        table[column] = serde_json::json!(mm);
    }
    let millimetres = dir.path().join("ur10_mm.json");
    std::fs::write(&millimetres, table.to_string()).unwrap();
    refused(&file, &path(&millimetres), "give them in the poses' unit");
}

/// A broken table file: exit 2 with the file, the line and the field.
#[test]
fn a_broken_table_file_names_its_line_and_field() {
    let file = recording("dh1_ur10_eth_s0");
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("{\n\"convention\": \"standard\",\n\"a\": [0, 0.4,\n}", ":4"),
        (
            "{\"convention\": \"standard\", \"a\": [0], \"d\": [0, 1], \"alpha\": [0], \"theta_offset\": [0]}",
            "field `d`",
        ),
        (
            "{\"convention\": \"craig\", \"a\": [0], \"d\": [0], \"alpha\": [0], \"theta_offset\": [0]}",
            "craig",
        ),
    ];
    for (i, (text, words)) in cases.iter().enumerate() {
        let table = dir.path().join(format!("table{i}.json"));
        std::fs::write(&table, text).unwrap();
        let (code, _, err) = calibrate(&[&file, "--robot-model", &path(&table)]);
        assert_eq!(code, 2, "{err}");
        assert!(
            err.contains(&format!("table{i}.json")) && err.contains(words),
            "{words}: {err}"
        );
    }
    let (code, _, err) = calibrate(&[&file, "--robot-model", "/nonexistent/ur10.json"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("/nonexistent/ur10.json"), "{err}");
}

/// `online --robot-model`: the accumulating estimator's test has the table's statistic as
/// `calibrate`'s; the UR10's 1 mm DH error, reported good online without it, is questionable with
/// it; another robot's table stops the stream with exit 2 at the first test, and the paper's
/// estimator, which has no such test, refuses the table.
#[test]
fn online_takes_the_table_as_calibrate_does() {
    let table = robot("ur10");
    let file = recording("dh1_ur10_eth_s0");
    let online = |extra: &[&str]| {
        let (code, out, err) = run(&[
            &[
                "online",
                &file,
                "--setup",
                "eye-to-hand",
                "--output",
                "json",
            ],
            extra,
        ]
        .concat());
        (
            code,
            out.lines()
                .last()
                .map(|l| serde_json::from_str::<Value>(l).unwrap()),
            err,
        )
    };
    let (code, without, err) = online(&[]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(without.unwrap()["verdict"], "good");
    let (code, with, err) = online(&["--robot-model", &table]);
    assert_eq!(code, 0, "{err}");
    let with = with.unwrap();
    assert_eq!(with["verdict"], "questionable", "{with}");
    assert!(
        with["systematic"]["kinematic"]["z"].as_f64().unwrap() < -5.0,
        "{with}"
    );
    let batch = calibrate_eth(&file, &["--robot-model", &table]);
    assert_eq!(
        batch["systematic"]["flagged"],
        with["systematic"]["flagged"]
    );

    let (code, _, err) = online(&["--robot-model", &robot("irb120")]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("robot-model") && err.contains("does not turn the hand"),
        "{err}"
    );
    let (code, _, err) = online(&["--robot-model", &table, "--estimator", "paper"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("accumulating estimator"), "{err}");
}
