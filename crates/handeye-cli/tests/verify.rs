//! `handeye verify --x SAVED INPUT`: the saved X that `calibrate` wrote (JSON or YAML) against a new
//! recording; exit 0 consistent, 4 inconsistent, 3 when the recording cannot tell, 2 for a bad
//! SAVED file (named, with its line and field).

mod common;

use std::path::{Path, PathBuf};

use common::shared_data::shared_each;
use common::{run, testdata};
use serde_json::Value;

/// The first and second halves of a kinhec recording, written to `dir`.
fn halves(dir: &Path, name: &str) -> (PathBuf, PathBuf) {
    let text = std::fs::read_to_string(testdata(&format!("kinhec/pairs/{name}"))).unwrap();
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    let h = lines.len() / 2;
    let (a, b) = (dir.join("first.jsonl"), dir.join("second.jsonl"));
    std::fs::write(&a, lines[..h].join("\n")).unwrap();
    std::fs::write(&b, lines[h..].join("\n")).unwrap();
    (a, b)
}

/// `calibrate FILE --output FACE` written to `dir/saved.FACE`.
fn save(dir: &Path, input: &Path, setup: &str, face: &str) -> PathBuf {
    let (code, out, err) = run(&[
        "calibrate",
        input.to_str().unwrap(),
        "--setup",
        setup,
        "--pairs",
        "all",
        "--output",
        face,
    ]);
    assert_eq!(code, 0, "{err}");
    let path = dir.join(format!("saved.{face}"));
    std::fs::write(&path, out).unwrap();
    path
}

fn verify(saved: &Path, input: &[&str], extra: &[&str]) -> (i32, Value, String) {
    let mut args = vec!["verify", "--x", saved.to_str().unwrap()];
    args.extend(input);
    args.extend(extra);
    args.extend(["--output", "json"]);
    let (code, out, err) = run(&args);
    let v = serde_json::from_str(&out).unwrap_or(Value::Null);
    (code, v, err)
}

#[test]
fn the_same_rig_passes_from_json_and_yaml_in_both_setups() {
    for (name, setup) in [
        ("nominal_stations_eih_s1.jsonl", "eye-in-hand"),
        ("nominal_continuous_eth_s0.jsonl", "eye-to-hand"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = halves(dir.path(), name);
        for face in ["json", "yaml"] {
            let saved = save(dir.path(), &a, setup, face);
            let (code, v, err) = verify(&saved, &[b.to_str().unwrap(), "--setup", setup], &[]);
            assert_eq!(code, 0, "{name} {face}: {v} {err}");
            assert_eq!(v["verdict"], "consistent");
            assert!(v["sigma"]["rotation_deg"].as_f64().unwrap() > 0.0);
            assert!(v["difference"]["translation"].as_f64().unwrap() >= 0.0);
            // Our YAML carries the one-sigma sizes in a comment: they count.
            assert_eq!(v["saved_uncertainty"], true, "{face}");
        }
        let saved = save(dir.path(), &a, setup, "json");
        let (code, out, _) = run(&[
            "verify",
            "--x",
            saved.to_str().unwrap(),
            b.to_str().unwrap(),
            "--setup",
            setup,
            "--output",
            "text",
        ]);
        assert_eq!(code, 0);
        assert!(out.starts_with("Verdict: consistent"), "{out}");
    }
}

#[test]
fn a_turned_saved_x_is_inconsistent_in_degrees_and_millimetres() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = halves(dir.path(), "nominal_stations_eth_s1.jsonl");
    let saved = save(dir.path(), &a, "eye-to-hand", "json");
    // Turn the saved X by 1° about z: its quaternion and matrix, consistently.
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(&saved).unwrap()).unwrap();
    let m: Vec<Vec<f64>> = serde_json::from_value(v["matrix"].clone()).unwrap();
    let (s, c) = 1f64.to_radians().sin_cos();
    let turned: Vec<Vec<f64>> = (0..4)
        .map(|i| match i {
            0 => (0..4)
                .map(|j| {
                    if j < 3 {
                        c * m[0][j] - s * m[1][j]
                    } else {
                        m[0][j]
                    }
                })
                .collect(),
            1 => (0..4)
                .map(|j| {
                    if j < 3 {
                        s * m[0][j] + c * m[1][j]
                    } else {
                        m[1][j]
                    }
                })
                .collect(),
            _ => m[i].clone(),
        })
        .collect();
    let obj = v.as_object_mut().unwrap();
    obj.insert("matrix".into(), serde_json::to_value(&turned).unwrap());
    obj.remove("quaternion_xyzw");
    obj.remove("translation");
    std::fs::write(&saved, serde_json::to_string(&v).unwrap()).unwrap();
    let (code, v, err) = verify(
        &saved,
        &[b.to_str().unwrap(), "--setup", "eye-to-hand"],
        &[],
    );
    assert_eq!(code, 4, "{v} {err}");
    assert_eq!(v["verdict"], "inconsistent");
    let d = v["difference"]["rotation_deg"].as_f64().unwrap();
    assert!((0.6..1.4).contains(&d), "{d}");
    assert!(err.contains("° and ") && err.contains(" mm"), "{err}");
    assert!(err.contains("the camera moved on its mount"), "{err}");
}

/// `--robot R --camera C` of an ethz-asl recording (in the shared folder `ethz`).
fn ethz(ethz: &Path, name: &str) -> [String; 4] {
    let file = |side: &str| {
        ethz.join(format!("{name}_{side}.csv"))
            .to_str()
            .unwrap()
            .to_string()
    };
    [
        "--robot".into(),
        file("B_H"),
        "--camera".into(),
        file("W_E"),
    ]
}

#[test]
fn two_different_real_rigs_are_inconsistent() {
    let found = shared_each(&["ethz-asl", "camodocal/TransformPairsInput.yml"]);
    let [Some(ethz_asl), Some(camodocal)] = [&found[0], &found[1]] else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    // ethz-asl's PrimeSense recording (eye-in-hand) against its robot-arm recording.
    let prime = ethz(ethz_asl, "prime_sense_1");
    let (code, out, err) = run(&[
        "calibrate",
        &prime[0],
        &prime[1],
        &prime[2],
        &prime[3],
        "--output",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    let saved = dir.path().join("prime_sense.json");
    std::fs::write(&saved, out).unwrap();
    let arm = ethz(ethz_asl, "robot_arm_sim");
    let arm: Vec<&str> = arm.iter().map(String::as_str).collect();
    let (code, v, err) = verify(&saved, &arm, &[]);
    assert_eq!(code, 4, "{v} {err}");
    assert_eq!(v["verdict"], "inconsistent");
    assert!(err.contains("a different rig"), "{err}");
    // camodocal's eye-to-hand rig against the PrimeSense recording read as eye-in-hand: an
    // error naming both setups (X is another transform in each).
    let saved = save(dir.path(), camodocal, "eye-to-hand", "json");
    let prime: Vec<&str> = prime.iter().map(String::as_str).collect();
    let (code, v, err) = verify(&saved, &prime, &["--setup", "eye-in-hand"]);
    assert_eq!(code, 2, "{v} {err}");
    assert!(err.contains("the saved X is for eye-to-hand"), "{err}");
    assert!(err.contains("--setup eye-in-hand"), "{err}");
}

#[test]
fn a_recording_about_one_joint_exits_3_and_says_what_to_record() {
    let dir = tempfile::tempdir().unwrap();
    let (a, _) = halves(dir.path(), "nominal_continuous_eih_s0.jsonl");
    let saved = save(dir.path(), &a, "eye-in-hand", "json");
    let degenerate = testdata("kinhec/pairs/degenerate_single_joint_continuous_eih_s0.jsonl");
    let (code, v, err) = verify(&saved, &[degenerate.to_str().unwrap()], &[]);
    assert_eq!(code, 3, "{v} {err}");
    assert_eq!(v["verdict"], "undetermined");
    assert!(err.contains("record motions"), "{err}");
}

/// The recording with its translations in millimetres (4×4 matrices or translation arrays).
fn in_millimetres(input: &Path, output: &Path) {
    let text = std::fs::read_to_string(input).unwrap();
    let mut out = String::new();
    for line in text.lines().filter(|l| !l.trim().is_empty()) {
        let mut v: Value = serde_json::from_str(line).unwrap();
        for key in ["base_from_gripper", "camera_from_target"] {
            let t = &mut v[key];
            if t.is_array() {
                for i in 0..3 {
                    t[i][3] = (t[i][3].as_f64().unwrap() * 1e3).into();
                }
            } else {
                for i in 0..3 {
                    t["translation"][i] = (t["translation"][i].as_f64().unwrap() * 1e3).into();
                }
            }
        }
        out.push_str(&v.to_string());
        out.push('\n');
    }
    std::fs::write(output, out).unwrap();
}

#[test]
fn a_yaml_in_metres_is_converted_for_a_recording_in_millimetres() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = halves(dir.path(), "nominal_stations_eih_s0.jsonl");
    let saved = save(dir.path(), &a, "eye-in-hand", "yaml");
    let mm = dir.path().join("mm.jsonl");
    in_millimetres(&b, &mm);
    let (code, v, err) = verify(&saved, &[mm.to_str().unwrap()], &[]);
    assert_eq!(code, 0, "{v} {err}");
    assert_eq!(v["unit_scale"], 1000.0);
    assert!(
        err.contains("metres, the recording in millimetres"),
        "{err}"
    );
    // The same X in metres, compared without conversion, would be hundreds of sigmas off.
    let t = v["saved"]["translation"][0].as_f64().unwrap();
    assert!(
        t.abs() > 1.0,
        "the saved translation is in millimetres now: {t}"
    );
}

#[test]
fn easy_handeye2s_own_file_without_uncertainty_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = halves(dir.path(), "nominal_stations_eih_s2.jsonl");
    let ours = save(dir.path(), &a, "eye-in-hand", "yaml");
    // easy_handeye2 writes no comments: strip ours.
    let text = std::fs::read_to_string(&ours).unwrap();
    let bare: String = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| format!("{l}\n"))
        .collect();
    let saved = dir.path().join("easy_handeye2.calib");
    std::fs::write(&saved, bare).unwrap();
    let (code, v, err) = verify(&saved, &[b.to_str().unwrap()], &[]);
    assert!(code == 0 || code == 4, "{v} {err}");
    assert_eq!(v["saved_uncertainty"], false);
    assert!(err.contains("no uncertainty"), "{err}");
    let (_, with, _) = verify(&ours, &[b.to_str().unwrap()], &[]);
    assert!(
        v["sigma"]["rotation_deg"].as_f64() < with["sigma"]["rotation_deg"].as_f64(),
        "{v} {with}"
    );
}

#[test]
fn bad_saved_files_exit_2_naming_the_file_and_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let input = testdata("kinhec/pairs/nominal_stations_eih_s0.jsonl");
    let cases = [
        ("no_x.json", "{\"verdict\": \"good\"}", "matrix"),
        ("broken.json", "{\"matrix\": [[1, 0]", "malformed JSON"),
        (
            "covariance.json",
            "{\"matrix\": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]],\n \"uncertainty\": {\"covariance\": [[1]]}}",
            "uncertainty.covariance",
        ),
        (
            "word.calib",
            "transform:\n  translation:\n    x: one\n    y: 0\n    z: 0\n  rotation: {x: 0, y: 0, z: 0, w: 1}\n",
            "transform.translation.x",
        ),
        (
            "no_rotation.calib",
            "transform:\n  translation: {x: 0, y: 0, z: 0}\n",
            "transform.rotation.x",
        ),
        (
            "zero_quaternion.calib",
            "transform:\n  translation: {x: 0, y: 0, z: 0}\n  rotation: {x: 0, y: 0, z: 0, w: 0}\n",
            "transform.rotation",
        ),
    ];
    for (name, text, field) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        let (code, _, err) = verify(&path, &[input.to_str().unwrap()], &[]);
        assert_eq!(code, 2, "{name}: {err}");
        assert!(err.contains(name) && err.contains(field), "{name}: {err}");
    }
    let (code, _, err) = verify(
        &dir.path().join("missing.json"),
        &[input.to_str().unwrap()],
        &[],
    );
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("missing.json"), "{err}");
}

#[test]
fn calibrate_says_the_error_at_the_working_distance_and_takes_a_point() {
    let input = testdata("kinhec/pairs/nominal_stations_eih_s0.jsonl");
    let input = input.to_str().unwrap();
    let (code, out, _) = run(&["calibrate", input, "--output", "json"]);
    assert_eq!(code, 0);
    let v: Value = serde_json::from_str(&out).unwrap();
    let at = &v["uncertainty"]["at_point"];
    assert_eq!(at["frame"], "camera");
    let z = at["point"][2].as_f64().unwrap();
    assert!((0.2..1.0).contains(&z), "the median target position: {at}");
    let (code, out, _) = run(&["calibrate", input, "--point", "0,0,2", "--output", "json"]);
    assert_eq!(code, 0);
    let far: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(far["uncertainty"]["at_point"]["point"][2], 2.0);
    let (code, out, _) = run(&["calibrate", input, "--output", "text"]);
    assert_eq!(code, 0);
    assert!(
        out.contains("m from the camera is placed within ±") && out.contains("mm (one sigma)"),
        "{out}"
    );
    let (code, _, err) = run(&["calibrate", input, "--point", "0,0"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--point"), "{err}");
}

/// `camera_from_target` of one record (a 4×4 row list) turned by `deg` about the camera's x.
fn turned_camera(line: &str, deg: f64) -> String {
    let mut r: Value = serde_json::from_str(line).unwrap();
    let m: Vec<Vec<f64>> = serde_json::from_value(r["camera_from_target"].clone()).unwrap();
    let (c, s) = (deg.to_radians().cos(), deg.to_radians().sin());
    let turn = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, c, -s, 0.0],
        [0.0, s, c, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    let product: Vec<Vec<f64>> = (0..4)
        .map(|i| {
            (0..4)
                .map(|j| (0..4).map(|k| turn[i][k] * m[k][j]).sum())
                .collect()
        })
        .collect();
    r["camera_from_target"] = serde_json::to_value(product).unwrap();
    r.to_string()
}

#[test]
fn strict_exits_5_when_the_saved_x_fits_a_questionable_recording() {
    // The same rig, one frame of the new recording paired with a camera pose turned 8°: the saved
    // X still fits (exit 0), but the recording's own calibration is questionable (its outlier is
    // named), which `--strict` makes exit 5. The clean recording passes `--strict`.
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = halves(dir.path(), "nominal_stations_eih_s0.jsonl");
    let saved = save(dir.path(), &a, "eye-in-hand", "json");
    let b_arg = b.to_str().unwrap();
    let (code, v, err) = verify(&saved, &[b_arg], &["--strict"]);
    assert_eq!(
        (code, v["quality"].as_str()),
        (0, Some("good")),
        "{v} {err}"
    );
    let text = std::fs::read_to_string(&b).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    lines[3] = turned_camera(&lines[3], 8.0);
    let bad = dir.path().join("one_bad_frame.jsonl");
    std::fs::write(&bad, lines.join("\n")).unwrap();
    let bad_arg = bad.to_str().unwrap();
    let (code, v, err) = verify(&saved, &[bad_arg], &[]);
    assert_eq!(code, 0, "{v} {err}");
    assert_eq!(v["verdict"], "consistent");
    assert_eq!(v["quality"], "questionable");
    let codes: Vec<&str> = v["recording"]["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|w| w["code"].as_str())
        .collect();
    assert!(codes.contains(&"outliers"), "{codes:?}");
    let (code, _, err) = verify(&saved, &[bad_arg], &["--strict"]);
    assert_eq!(code, 5, "{err}");
}

/// easy_handeye2's calibration file for X (metres, the rotation as a quaternion): `eye_on_base`
/// or `eye_in_hand`.
fn easy_handeye2(x: &Value, kind: &str) -> String {
    let t = &x["translation"];
    let q = &x["quaternion_xyzw"];
    format!(
        "parameters:\n  calibration_type: {kind}\n  robot_base_frame: base_link\n  tracking_base_frame: camera\ntransform:\n  translation:\n    x: {}\n    y: {}\n    z: {}\n  rotation:\n    x: {}\n    y: {}\n    z: {}\n    w: {}\n",
        t[0], t[1], t[2], q[0], q[1], q[2], q[3]
    )
}

#[test]
fn the_setup_is_read_from_the_saved_file_and_a_conflicting_one_is_an_error_naming_both() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = halves(dir.path(), "nominal_stations_eth_s0.jsonl");
    let json = save(dir.path(), &a, "eye-to-hand", "json");
    let x: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    // easy_handeye2's own .calib (eye_on_base) and a JSON with only X's frame name and matrix.
    let calib = dir.path().join("eye_on_base.calib");
    std::fs::write(&calib, easy_handeye2(&x, "eye_on_base")).unwrap();
    let framed = dir.path().join("framed.json");
    let plain = serde_json::json!({"frame": "base_from_camera", "matrix": x["matrix"]});
    std::fs::write(&framed, plain.to_string()).unwrap();
    for saved in [&json, &calib, &framed] {
        // No --setup: the file's.
        let (code, v, err) = verify(saved, &[b.to_str().unwrap()], &[]);
        assert_eq!(code, 0, "{}: {v} {err}", saved.display());
        assert_eq!(v["verdict"], "consistent");
        assert_eq!(v["recording"]["frame"], "base_from_camera");
        // The same setup given: the same answer.
        let (code, _, err) = verify(saved, &[b.to_str().unwrap(), "--setup", "eye-to-hand"], &[]);
        assert_eq!(code, 0, "{err}");
        // The other one: an error naming both, before anything is calibrated.
        let (code, v, err) = verify(saved, &[b.to_str().unwrap(), "--setup", "eye-in-hand"], &[]);
        assert_eq!(code, 2, "{}: {v} {err}", saved.display());
        assert!(
            err.contains("--setup eye-in-hand") && err.contains("saved X is for eye-to-hand"),
            "{err}"
        );
    }
    // An eye-in-hand .calib against the eye-to-hand recording read as its file says: not a
    // silent eye-to-hand comparison.
    let wrong = dir.path().join("eye_in_hand.calib");
    std::fs::write(&wrong, easy_handeye2(&x, "eye_in_hand")).unwrap();
    let (code, v, err) = verify(&wrong, &[b.to_str().unwrap()], &[]);
    assert_ne!(code, 0, "{v} {err}");
    assert_ne!(v["verdict"], "consistent", "{v}");
}

#[test]
fn verify_says_the_smallest_change_it_sees_and_a_tolerance_it_cannot_resolve_is_undetermined() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = halves(dir.path(), "nominal_stations_eih_s1.jsonl");
    let saved = save(dir.path(), &a, "eye-in-hand", "json");
    let b = b.to_str().unwrap();
    let (code, v, err) = verify(&saved, &[b], &[]);
    assert_eq!(code, 0, "{v} {err}");
    let detectable = |v: &Value| {
        (
            v["detectable"]["rotation_deg"].as_f64().unwrap(),
            v["detectable"]["translation"].as_f64().unwrap(),
        )
    };
    let (rot, trans) = detectable(&v);
    // At least the limit times the one-sigma's largest direction: more than the sizes' average.
    let limit = v["limit_sigmas"].as_f64().unwrap();
    assert!(
        rot >= limit * v["sigma"]["rotation_deg"].as_f64().unwrap() / 3f64.sqrt(),
        "{v}"
    );
    assert!(
        trans >= limit * v["sigma"]["translation"].as_f64().unwrap() / 3f64.sqrt(),
        "{v}"
    );
    let message = v["message"].as_str().unwrap();
    assert!(
        message.contains("no change larger than")
            && message.contains("smaller ones cannot be seen in this recording"),
        "{message}"
    );
    // A tolerance below what the recording sees: undetermined, exit 3, saying both sizes.
    let tight = format!("{},{}", rot / 2.0, trans / 2.0);
    let (code, v, err) = verify(&saved, &[b], &["--tolerance", &tight]);
    assert_eq!(code, 3, "{v} {err}");
    assert_eq!(v["verdict"], "undetermined");
    assert!(err.contains("within your tolerance"), "{err}");
    assert_eq!(v["tolerance"]["rotation_deg"].as_f64().unwrap(), rot / 2.0);
    // One it resolves: consistent, within it.
    let loose = format!("{},{}", rot * 2.0, trans * 2.0);
    let (code, v, err) = verify(&saved, &[b], &["--tolerance", &loose]);
    assert_eq!(code, 0, "{v} {err}");
    assert!(
        v["message"]
            .as_str()
            .unwrap()
            .contains("no change larger than your tolerance")
    );
    // A tolerance that is not two positive sizes is refused by name.
    let (code, _, err) = verify(&saved, &[b], &["--tolerance", "0.5,-1"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--tolerance"), "{err}");
    // A recording that cannot tell at all: no size it can see, and a tolerance changes nothing.
    let degenerate = testdata("kinhec/pairs/degenerate_single_joint_continuous_eih_s0.jsonl");
    let (code, v, _) = verify(
        &saved,
        &[degenerate.to_str().unwrap()],
        &["--tolerance", &loose],
    );
    assert_eq!(code, 3);
    assert!(v["detectable"]["rotation_deg"].is_null(), "{v}");
}

#[test]
fn a_shift_below_what_a_small_recording_sees_is_not_called_a_fit_under_a_tolerance() {
    // The first 12 stations of a recording, and its own X shifted 3 mm: within what 12
    // stations see, so `consistent` says how large a change could hide, and a 1 mm tolerance
    // is undetermined rather than a fit.
    let dir = tempfile::tempdir().unwrap();
    let text =
        std::fs::read_to_string(testdata("kinhec/pairs/nominal_stations_eih_s0.jsonl")).unwrap();
    let small = dir.path().join("small.jsonl");
    std::fs::write(&small, text.lines().take(12).collect::<Vec<_>>().join("\n")).unwrap();
    let saved = save(dir.path(), &small, "eye-in-hand", "json");
    let mut x: Value = serde_json::from_str(&std::fs::read_to_string(&saved).unwrap()).unwrap();
    let obj = x.as_object_mut().unwrap();
    let mut m: Vec<Vec<f64>> = serde_json::from_value(obj["matrix"].clone()).unwrap();
    m[0][3] += 0.003;
    obj.insert("matrix".into(), serde_json::to_value(&m).unwrap());
    obj.remove("quaternion_xyzw");
    obj.remove("translation");
    obj.remove("uncertainty");
    std::fs::write(&saved, x.to_string()).unwrap();
    let small = small.to_str().unwrap();
    let (code, v, err) = verify(&saved, &[small], &[]);
    assert_eq!(code, 0, "{v} {err}");
    let trans = v["detectable"]["translation"].as_f64().unwrap();
    assert!(trans > 0.003, "{v}");
    let (code, v, err) = verify(&saved, &[small], &["--tolerance", "0.1,0.001"]);
    assert_eq!(code, 3, "{v} {err}");
    assert!(
        err.contains("cannot tell whether the saved X is within your tolerance of 0.10° / 1.00 mm"),
        "{err}"
    );
}
