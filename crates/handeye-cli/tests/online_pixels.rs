//! `handeye online --intrinsics` on the committed recordings of `testdata/pixels` (issue 35): the
//! stream's final X is `calibrate --method reprojection`'s on the same records, a bad record
//! costs its line, and what `calibrate` refuses is refused with its exit code.

mod common;

use std::io::Write;
use std::process::{Command, Stdio};

use common::{run, testdata};
use serde_json::Value;

fn path(name: &str) -> String {
    testdata(&format!("pixels/{name}")).display().to_string()
}

const RECORDINGS: [(&str, &str); 2] = [("board_eth", "eye-to-hand"), ("tag_eih", "eye-in-hand")];

fn online(file: &str, name: &str, setup: &str, extra: &[&str]) -> (i32, String, String) {
    let intrinsics = path(&format!("{name}.intrinsics.yml"));
    let mut args = vec![
        "online",
        file,
        "--intrinsics",
        &intrinsics,
        "--setup",
        setup,
    ];
    args.extend_from_slice(extra);
    if !extra.contains(&"--output") {
        args.extend_from_slice(&["--output", "json"]);
    }
    run(&args)
}

fn calibrate(file: &str, name: &str, setup: &str) -> (i32, String, String) {
    run(&[
        "calibrate",
        file,
        "--method",
        "reprojection",
        "--intrinsics",
        &path(&format!("{name}.intrinsics.yml")),
        "--setup",
        setup,
        "--output",
        "json",
    ])
}

fn lines(out: &str) -> Vec<Value> {
    out.lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// The largest difference of X's matrix entries of two JSON objects.
fn matrix_gap(a: &Value, b: &Value) -> f64 {
    (0..4)
        .flat_map(|i| (0..4).map(move |j| (i, j)))
        .map(|(i, j)| {
            (a["matrix"][i][j].as_f64().unwrap() - b["matrix"][i][j].as_f64().unwrap()).abs()
        })
        .fold(0.0, f64::max)
}

/// The recording rewritten line by line.
fn rewritten(
    name: &str,
    edit: impl Fn(usize, &str) -> Option<String>,
) -> (tempfile::TempDir, String) {
    let text = std::fs::read_to_string(path(&format!("{name}.jsonl"))).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join(format!("{name}.jsonl"));
    let out: Vec<String> = text
        .lines()
        .enumerate()
        .filter_map(|(i, l)| edit(i, l))
        .collect();
    std::fs::write(&file, out.join("\n") + "\n").unwrap();
    (dir, file.display().to_string())
}

#[test]
fn the_final_estimate_is_calibrates_x_on_the_pixels() {
    for (name, setup) in RECORDINGS {
        let file = path(&format!("{name}.jsonl"));
        let (code, out, err) = online(&file, name, setup, &[]);
        assert_eq!(code, 0, "{name}: {err}");
        assert!(err.contains("on the pixels"), "{err}");
        let events = lines(&out);
        // At 16 records and at the end.
        assert_eq!(events.len(), 2, "{name}: {out}");
        assert_eq!(events[0]["pose"], 16);
        assert_eq!(events[0]["reason"], "determined");
        let last = &events[1];
        assert_eq!(last["reason"], "end");
        assert_eq!(last["estimator"], "reprojection");
        assert_eq!(last["poses"], 30);
        let (code, out, err) = calibrate(&file, name, setup);
        assert_eq!(code, 0, "{name}: {err}");
        let batch: Value = serde_json::from_str(&out).unwrap();
        assert!(matrix_gap(last, &batch) < 1e-9, "{name}");
        assert_eq!(
            last["reprojection"]["rms_px"],
            batch["reprojection"]["rms_px"]
        );
        assert_eq!(last["verdict"], batch["verdict"]);
        assert_eq!(
            last["uncertainty"]["rotation_deg"],
            batch["uncertainty"]["rotation_deg"]
        );
    }
}

#[test]
fn standard_input_is_read_as_a_stream() {
    let (name, setup) = RECORDINGS[1];
    let text = std::fs::read(path(&format!("{name}.jsonl"))).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_handeye"))
        .args([
            "online",
            "-",
            "--intrinsics",
            &path(&format!("{name}.intrinsics.yml")),
            "--setup",
            setup,
            "--output",
            "json",
        ])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child.stdin.take().unwrap().write_all(&text).unwrap();
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(0));
    let from_stdin = lines(&String::from_utf8(out.stdout).unwrap());
    let (_, file_out, _) = online(&path(&format!("{name}.jsonl")), name, setup, &[]);
    assert_eq!(from_stdin, lines(&file_out));
}

#[test]
fn each_bad_record_costs_its_line_only() {
    let (name, setup) = RECORDINGS[0];
    // Bad JSON, one pixel too many, a NaN, the target's points missing.
    let bad = |i: usize, l: &str| -> Option<String> {
        Some(match i {
            3 => "{\"base_from_gripper\": {".to_string(),
            7 => l.replacen("\"pixels\": [[", "\"pixels\": [[1, 2], [", 1),
            11 => l.replacen("\"pixels\": [[", "\"pixels\": [[NaN, ", 1),
            19 => l.replacen("\"target\"", "\"targets\"", 1),
            _ => l.to_string(),
        })
    };
    let (_dir, corrupted) = rewritten(name, bad);
    let (code, out, err) = online(&corrupted, name, setup, &[]);
    assert_eq!(code, 0, "{err}");
    let skipped: Vec<&str> = err.lines().filter(|l| l.starts_with("skipped:")).collect();
    assert_eq!(skipped.len(), 4, "{err}");
    for (line, field) in [(4, ""), (8, "detections"), (12, ""), (20, "detections")] {
        let at = format!("{corrupted}:{line}:");
        assert!(
            skipped.iter().any(|s| s.contains(&at) && s.contains(field)),
            "line {line}: {err}"
        );
    }
    assert!(err.contains("4 bad line(s) skipped"), "{err}");
    // The rest is calibrated as calibrate calibrates the recording without those lines.
    let (_dir2, without) = rewritten(name, |i, l| {
        (![3, 7, 11, 19].contains(&i)).then(|| l.to_string())
    });
    let (code, batch, err) = calibrate(&without, name, setup);
    assert_eq!(code, 0, "{err}");
    let batch: Value = serde_json::from_str(&batch).unwrap();
    let last = lines(&out).pop().unwrap();
    assert_eq!(last["poses"], 26);
    assert!(matrix_gap(&last, &batch) < 1e-9);
    // --on-bad-line stop stops at the first, exit 2.
    let (code, _, err) = online(&corrupted, name, setup, &["--on-bad-line", "stop"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains(&format!("{corrupted}:4")), "{err}");
}

#[test]
fn detections_without_intrinsics_are_refused_naming_the_flag() {
    let (name, setup) = RECORDINGS[0];
    let (code, out, err) = run(&[
        "online",
        &path(&format!("{name}.jsonl")),
        "--setup",
        setup,
        "--output",
        "json",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(out.is_empty());
    assert!(err.contains("online --intrinsics FILE"), "{err}");
    // Each skipped line names online's flag, not calibrate's.
    let skipped: Vec<&str> = err.lines().filter(|l| l.starts_with("skipped:")).collect();
    assert!(!skipped.is_empty(), "{err}");
    for line in skipped {
        assert!(
            line.ends_with("pass `--intrinsics FILE` to calibrate the records on their pixels"),
            "{line}"
        );
    }
    // Each command words the library's typed remedy in its own flags.
    for (command, words) in [
        (
            "calibrate",
            "pass `--method reprojection --intrinsics FILE`",
        ),
        (
            "advise",
            "`handeye calibrate --method reprojection --intrinsics FILE` calibrates",
        ),
    ] {
        let (code, _, err) = run(&[command, &path(&format!("{name}.jsonl")), "--setup", setup]);
        assert_eq!(code, 2, "{command}: {err}");
        assert!(
            err.contains(&format!("{name}.jsonl:1:")),
            "{command}: {err}"
        );
        assert!(err.contains(words), "{command}: {err}");
    }
}

#[test]
fn what_calibrate_refuses_online_refuses_with_its_exit_code() {
    for (name, setup) in RECORDINGS {
        let inverted = |_: usize, l: &str| -> Option<String> {
            let mut v: Value = serde_json::from_str(l).unwrap();
            let q = &v["base_from_gripper"]["quaternion_xyzw"];
            let t = &v["base_from_gripper"]["translation"];
            let q = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                q[3].as_f64().unwrap(),
                q[0].as_f64().unwrap(),
                q[1].as_f64().unwrap(),
                q[2].as_f64().unwrap(),
            ));
            let t = nalgebra::Vector3::new(
                t[0].as_f64().unwrap(),
                t[1].as_f64().unwrap(),
                t[2].as_f64().unwrap(),
            );
            let inv = nalgebra::Isometry3::from_parts(t.into(), q).inverse();
            let (t, q) = (inv.translation.vector, inv.rotation);
            v["base_from_gripper"] = serde_json::json!({
                "translation": [t.x, t.y, t.z],
                "quaternion_xyzw": [q.i, q.j, q.k, q.w],
            });
            Some(v.to_string())
        };
        let millimetres = |_: usize, l: &str| -> Option<String> {
            let mut v: Value = serde_json::from_str(l).unwrap();
            for k in 0..3 {
                let t = v["base_from_gripper"]["translation"][k].as_f64().unwrap();
                v["base_from_gripper"]["translation"][k] = (t * 1000.0).into();
            }
            Some(v.to_string())
        };
        let one_view = |_: usize, _: &str| -> Option<String> {
            let text = std::fs::read_to_string(path(&format!("{name}.jsonl"))).unwrap();
            Some(text.lines().next().unwrap().to_string())
        };
        for (what, edit) in [
            (
                "inverted",
                &inverted as &dyn Fn(usize, &str) -> Option<String>,
            ),
            ("millimetres", &millimetres),
            ("one view", &one_view),
        ] {
            let (_dir, file) = rewritten(name, edit);
            let (batch_code, _, batch_err) = calibrate(&file, name, setup);
            let (code, out, err) = online(&file, name, setup, &[]);
            assert_eq!(batch_code, 3, "{name} {what}: calibrate {batch_err}");
            assert_eq!(code, batch_code, "{name} {what}: {err}");
            assert!(out.is_empty(), "{name} {what}: an estimate {out}");
            let last = |e: &str| e.lines().last().unwrap_or_default().to_string();
            assert_eq!(last(&err), last(&batch_err), "{name} {what}");
        }
    }
}

#[test]
fn flags_that_do_not_apply_on_the_pixels_are_refused() {
    let (name, setup) = RECORDINGS[1];
    let file = path(&format!("{name}.jsonl"));
    for extra in [
        &["--estimator", "paper"][..],
        &["--prior", "tz=0.1"],
        &["--optimal"],
    ] {
        let (code, out, err) = online(&file, name, setup, extra);
        assert_eq!(code, 2, "{extra:?}: {err}");
        assert!(out.is_empty());
        assert!(
            err.contains("not offered on the pixels"),
            "{extra:?}: {err}"
        );
    }
}

#[test]
fn the_text_face_and_the_ros_faces() {
    let (name, setup) = RECORDINGS[1];
    let file = path(&format!("{name}.jsonl"));
    let (code, out, err) = online(&file, name, setup, &["--output", "text"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("estimate 2 from 30 poses"), "{out}");
    assert!(out.contains("reprojection RMS"), "{out}");
    let (code, out, err) = online(&file, name, setup, &["--output", "yaml"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("transform:") || out.contains("translation"),
        "{out}"
    );
}
