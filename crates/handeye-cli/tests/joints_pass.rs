//! The joint angles are read with the poses, in one pass over any input (issue 59): a JSON Lines
//! recording through a FIFO or standard input gives `calibrate --robot-model`, `advise` and
//! `verify` the same answer as the file, without waiting on a pipe read twice; a log line before
//! the first record and a value `"joints"` in a record change nothing.

mod common;

use std::path::Path;

use common::{run_fed, run_on_fifo, testdata, with_input};

/// The kinhec UR10 recording (32 records, each with its 6 joint angles) and its DH table.
fn ur10() -> (String, String) {
    let p = |rel: &str| testdata(rel).to_str().unwrap().to_owned();
    (
        p("kinhec/systematic/dh1_ur10_eth_s0.jsonl"),
        p("kinhec/robots/ur10.json"),
    )
}

/// The report's numbers and structure, its words left out (they name the input, which differs
/// between a file, a FIFO and `-`).
fn report(out: &str) -> serde_json::Value {
    fn numbers(v: serde_json::Value) -> serde_json::Value {
        use serde_json::Value;
        match v {
            Value::String(_) => Value::Null,
            Value::Array(a) => Value::Array(a.into_iter().map(numbers).collect()),
            Value::Object(o) => {
                Value::Object(o.into_iter().map(|(k, v)| (k, numbers(v))).collect())
            }
            v => v,
        }
    }
    numbers(serde_json::from_str(out).unwrap_or_else(|e| panic!("not JSON ({e})")))
}

/// Asserts that `a` and `b` agree, naming the first place where they do not (not the reports).
fn same(a: &serde_json::Value, b: &serde_json::Value, what: &str) {
    assert!(
        a == b,
        "{what}: the reports differ ({} against {} bytes)",
        a.to_string().len(),
        b.to_string().len()
    );
}

#[test]
fn joints_through_stdin_or_a_fifo_give_the_files_answer() {
    let (file, table) = ur10();
    let text = std::fs::read(&file).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let saved = dir.path().join("x.json");
    let calibrate = [
        "calibrate",
        "{}",
        "--setup",
        "eye-to-hand",
        "--robot-model",
        &table,
        "--output",
        "json",
    ];
    let (code, from_file, err) = run_fed(&with_input(&calibrate, &file), Vec::new());
    assert_eq!(code, 0, "{err}");
    // The table was used: the kinematic test ran on all 32 poses' joints.
    let v: serde_json::Value = serde_json::from_str(&from_file).unwrap();
    assert!(
        v["systematic"]["kinematic"].is_object(),
        "{}",
        v["systematic"]
    );
    std::fs::write(&saved, &from_file).unwrap();
    let saved = saved.to_str().unwrap();
    let verify = [
        "verify",
        "--x",
        saved,
        "{}",
        "--setup",
        "eye-to-hand",
        "--output",
        "json",
    ];
    let advise = ["advise", "{}", "--setup", "eye-to-hand"];
    for args in [&calibrate[..], &verify[..], &advise[..]] {
        let (code, expected, err) = run_fed(&with_input(args, &file), Vec::new());
        assert_eq!(code, 0, "{args:?}: {err}");
        let expected = report(&expected);
        let (code, out, err) = run_fed(&with_input(args, "-"), text.clone());
        assert_eq!(code, 0, "{args:?} on stdin: {err}");
        same(&report(&out), &expected, &format!("{args:?} on stdin"));
        if let Some((code, out, err)) = run_on_fifo(args, &text) {
            assert_eq!(code, 0, "{args:?} on a FIFO: {err}");
            same(&report(&out), &expected, &format!("{args:?} on a FIFO"));
        }
    }
}

/// The recording with `edit` applied to its text, written to `dir/name`.
fn edited(dir: &Path, name: &str, edit: impl Fn(&str) -> String) -> String {
    let (file, _) = ur10();
    let path = dir.join(name);
    std::fs::write(&path, edit(&std::fs::read_to_string(file).unwrap())).unwrap();
    path.to_str().unwrap().to_owned()
}

#[test]
fn a_log_line_first_or_a_value_joints_changes_nothing() {
    let (file, table) = ur10();
    let dir = tempfile::tempdir().unwrap();
    let args = |input: &str| {
        run_fed(
            &[
                "calibrate",
                input,
                "--setup",
                "eye-to-hand",
                "--robot-model",
                &table,
                "--output",
                "json",
            ],
            Vec::new(),
        )
    };
    let (code, expected, err) = args(&file);
    assert_eq!(code, 0, "{err}");
    let expected = report(&expected);
    let logged = edited(dir.path(), "logged.jsonl", |t| {
        format!("recorder started at 12:00\n{t}")
    });
    let (code, out, err) = args(&logged);
    assert_eq!(code, 0, "a log line first: {err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(v["systematic"]["kinematic"].is_object(), "{out}");
    // The records' lines moved by one; the answer did not.
    assert_eq!(report(&out)["matrix"], expected["matrix"]);

    // No joint angles, and a value "joints": the table is refused for want of them, not the file.
    let noted = edited(dir.path(), "noted.jsonl", |t| {
        t.lines()
            .map(|l| {
                let mut v: serde_json::Value = serde_json::from_str(l).unwrap();
                let o = v.as_object_mut().unwrap();
                o.remove("joints");
                o.insert("note".into(), "joints".into());
                v.to_string()
            })
            .collect::<Vec<_>>()
            .join("\n")
    });
    let (code, _, err) = args(&noted);
    assert_ne!(code, 0);
    assert!(err.contains("0 of 32 poses carry them"), "{err}");
    let (code, _, err) = run_fed(&["calibrate", &noted, "--setup", "eye-to-hand"], Vec::new());
    assert_eq!(code, 0, "a value \"joints\" without joint angles: {err}");

    // The key written with an escape is the key.
    let escaped = edited(dir.path(), "escaped.jsonl", |t| {
        t.replace("\"joints\"", "\"\\u006aoints\"")
    });
    let (code, out, err) = args(&escaped);
    assert_eq!(code, 0, "{err}");
    same(&report(&out), &expected, "the key written with an escape");
}
