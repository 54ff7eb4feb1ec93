//! Every number that comes in from outside is checked for what it can mean (issue 59): a prior's
//! sigma that overflows, is larger than the recording or names a unit beyond any length; a point
//! beyond the recording; a saved covariance that is not positive semi-definite or whose sizes are
//! no uncertainty. Each is refused naming it, and `verify` is never "consistent" on a sigma as large
//! as the rig.

mod common;

use std::path::Path;

use common::{run, testdata};
use serde_json::Value;

fn file(rel: &str) -> String {
    testdata(rel).to_str().unwrap().to_owned()
}

#[test]
fn a_prior_beyond_any_length_or_looser_than_the_recording_is_refused_by_name() {
    let scara = file("low_dof/scara_eye-in-hand_s0.jsonl");
    for prior in [
        "tz=-0.1075+-1e160",
        "tz=-0.1075+-100",
        "tz=1e308m",
        "tz=-0.1075+-2000mm",
    ] {
        let (code, out, err) = run(&["calibrate", &scara, "--prior", prior, "--strict"]);
        assert_eq!(code, 2, "{prior}: {out}");
        assert!(err.contains("prior"), "{prior}: {err}");
        assert!(out.is_empty(), "{prior}: no verdict is printed: {out}");
    }
    // A measured height, in either unit, is taken.
    for prior in ["tz=-0.1075+-0.001", "tz=-107.5mm+-1mm"] {
        let (code, _, err) = run(&["calibrate", &scara, "--prior", prior]);
        assert_eq!(code, 0, "{prior}: {err}");
    }
}

#[test]
fn a_point_beyond_the_recording_is_refused_on_both_paths() {
    let poses = file("kinhec/systematic/dh1_ur10_eth_s0.jsonl");
    for point in ["1e160,0,0", "0,0,1e5"] {
        let (code, _, err) = run(&[
            "calibrate",
            &poses,
            "--setup",
            "eye-to-hand",
            "--point",
            point,
        ]);
        assert_eq!(code, 2, "{point}: {err}");
        assert!(err.contains("point"), "{point}: {err}");
        // The pixel path, on a simulated tag recording.
        let (code, _, err) = run(&[
            "calibrate",
            &file("pixels/tag_eih.jsonl"),
            "--method",
            "reprojection",
            "--intrinsics",
            &file("pixels/tag_eih.intrinsics.yml"),
            "--point",
            point,
        ]);
        assert_eq!(code, 2, "pixels, {point}: {err}");
        assert!(err.contains("parameter `point`"), "pixels, {point}: {err}");
    }
    let (code, out, err) = run(&[
        "calibrate",
        &poses,
        "--setup",
        "eye-to-hand",
        "--point",
        "0.1,0,1",
        "--output",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    let sigma = v["uncertainty"]["at_point"]["sigma"].as_f64().unwrap();
    assert!(sigma.is_finite() && sigma > 0.0, "{sigma}");
}

/// `calibrate --output json` of the first half of a recording, and the second half's file.
fn saved_and_second(dir: &Path) -> (Value, String) {
    let name = "kinhec/systematic/dh1_ur10_eth_s0.jsonl";
    let text = std::fs::read_to_string(testdata(name)).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let (a, b) = (dir.join("a.jsonl"), dir.join("b.jsonl"));
    std::fs::write(&a, lines[..16].join("\n")).unwrap();
    std::fs::write(&b, lines[16..].join("\n")).unwrap();
    let (code, out, err) = run(&[
        "calibrate",
        a.to_str().unwrap(),
        "--setup",
        "eye-to-hand",
        "--output",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    (
        serde_json::from_str(&out).unwrap(),
        b.to_str().unwrap().to_owned(),
    )
}

/// `verify --x` of `saved` (written to `dir`) on `second`: (exit code, report, stderr).
fn verify(dir: &Path, saved: &Value, second: &str) -> (i32, Value, String) {
    let path = dir.join("x.json");
    std::fs::write(&path, serde_json::to_string_pretty(saved).unwrap()).unwrap();
    let (code, out, err) = run(&[
        "verify",
        "--x",
        path.to_str().unwrap(),
        second,
        "--setup",
        "eye-to-hand",
        "--output",
        "json",
    ]);
    (code, serde_json::from_str(&out).unwrap_or(Value::Null), err)
}

#[test]
fn a_saved_covariance_that_is_no_covariance_is_refused_and_a_huge_one_tells_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let (saved, second) = saved_and_second(dir.path());
    // The saved X as written: a verdict this recording can give (not "undetermined").
    let (_, honest, err) = verify(dir.path(), &saved, &second);
    assert!(honest["verdict"].is_string(), "{err}");
    assert_ne!(honest["verdict"], "undetermined", "{err}");

    let with = |edit: &dyn Fn(&mut Vec<Vec<f64>>)| {
        let mut s = saved.clone();
        let mut c: Vec<Vec<f64>> =
            serde_json::from_value(s["uncertainty"]["covariance"].clone()).unwrap();
        edit(&mut c);
        s["uncertainty"]["covariance"] = serde_json::to_value(c).unwrap();
        s
    };
    // Not positive semi-definite: a strong negative correlation of two translation axes.
    let indefinite = with(&|c| {
        let big = 10.0 * (c[3][3] * c[4][4]).sqrt();
        c[3][4] = -big;
        c[4][3] = -big;
    });
    // Sizes that are no uncertainty: a rotation sigma of 1e150 rad, a translation one of 1e150.
    let rotation = with(&|c| c[0][0] = 1e300);
    let translation = with(&|c| c[5][5] = 1e300);
    for (what, s) in [
        ("indefinite", indefinite),
        ("rotation", rotation),
        ("translation", translation),
    ] {
        let (code, v, err) = verify(dir.path(), &s, &second);
        assert_eq!(code, 2, "{what}: {v}");
        assert!(err.contains("uncertainty.covariance"), "{what}: {err}");
        assert!(
            err.contains("x.json:"),
            "{what}: the file and line named: {err}"
        );
    }
    // Finite and positive, but a translation sigma of 1000 (the rig is about a metre): the
    // comparison cannot tell, whatever the difference.
    let huge = with(&|c| {
        for (i, row) in c.iter_mut().enumerate().skip(3) {
            row[i] = 1e6;
        }
    });
    let (_, v, err) = verify(dir.path(), &huge, &second);
    assert_eq!(v["verdict"], "undetermined", "{err}");
}
