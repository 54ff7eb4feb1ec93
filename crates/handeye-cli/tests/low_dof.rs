//! `--prior` and low-DOF recordings on the command line (issue 30), on the simulated recordings
//! of `testdata/low_dof` (made by `cargo run --release -p handeye --example low_dof_recordings`):
//! a SCARA without a prior is refused (exit 3) naming the prior to give; with the true height X is
//! within 3 sigma of the truth and `"prior"` says which component came from it; a free direction
//! off the frame's axes is refused naming it; bad priors are exit 2.

mod common;

use common::{run, testdata};
use serde_json::Value;

fn truth(name: &str) -> (Vec<f64>, Vec<f64>) {
    let text = std::fs::read_to_string(testdata(&format!("low_dof/{name}.truth.json"))).unwrap();
    let t: Value = serde_json::from_str(&text).unwrap();
    let x = t
        .as_object()
        .unwrap()
        .iter()
        .find(|(k, _)| k.ends_with("_from_camera"))
        .unwrap()
        .1;
    let v = |f: &str| -> Vec<f64> {
        x[f].as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    (v("translation"), v("quaternion_xyzw"))
}

fn file(name: &str) -> String {
    testdata(&format!("low_dof/{name}.jsonl"))
        .to_str()
        .unwrap()
        .to_string()
}

/// `calibrate INPUT --setup SETUP --prior PRIOR --output FACE`: (exit code, stdout, stderr).
fn with_prior(input: &str, setup: &str, prior: &str, face: &str) -> (i32, String, String) {
    run(&[
        "calibrate",
        input,
        "--setup",
        setup,
        "--prior",
        prior,
        "--output",
        face,
    ])
}

const RECORDINGS: [(&str, &str); 2] = [
    ("scara_eye-in-hand_s0", "eye-in-hand"),
    ("scara_eye-to-hand_s1", "eye-to-hand"),
];

#[test]
fn scara_without_a_prior_is_refused_naming_it() {
    for (name, setup) in RECORDINGS {
        let (code, out, err) = run(&[
            "calibrate",
            &file(name),
            "--setup",
            setup,
            "--output",
            "json",
        ]);
        assert_eq!(code, 3, "{name}: {out}{err}");
        assert!(err.contains("--prior tz="), "{err}");
        assert!(err.contains("SCARA"), "{err}");
        assert!(!err.contains("rotate about the gripper x"), "{err}");
        // Which way the prior's axis points, and that its sign is unchecked (issue 52 item 3).
        let direction = if setup == "eye-in-hand" {
            "along the gripper frame's +z"
        } else {
            "along the robot base's +z"
        };
        assert!(err.contains(direction), "{err}");
        assert!(err.contains("its sign included"), "{err}");
    }
}

#[test]
fn scara_with_the_true_height_is_within_three_sigma() {
    for (name, setup) in RECORDINGS {
        let (t, q) = truth(name);
        let prior = format!("tz={}", t[2]);
        let (code, out, err) = with_prior(&file(name), setup, &prior, "json");
        assert_eq!(code, 0, "{name}: {err}");
        let r: Value = serde_json::from_str(&out).unwrap();
        assert_eq!(r["verdict"], "good", "{name}: {err}");
        assert_eq!(r["prior"]["tz"]["value"].as_f64(), Some(t[2]));
        assert_eq!(r["prior"]["tz"]["sigma"].as_f64(), Some(0.0));
        assert_eq!(r["translation"][2].as_f64(), Some(t[2]));
        assert_eq!(r["low_dof"]["free"], "tz");
        let got: Vec<f64> = (0..3)
            .map(|i| r["translation"][i].as_f64().unwrap())
            .collect();
        let dt = (0..3).map(|i| (got[i] - t[i]).powi(2)).sum::<f64>().sqrt();
        let gq: Vec<f64> = (0..4)
            .map(|i| r["quaternion_xyzw"][i].as_f64().unwrap())
            .collect();
        let dot = (0..4).map(|i| gq[i] * q[i]).sum::<f64>().abs().min(1.0);
        let dr = (2.0 * dot.acos()).to_degrees();
        let (sr, st) = (
            r["uncertainty"]["rotation_deg"].as_f64().unwrap(),
            r["uncertainty"]["translation"].as_f64().unwrap(),
        );
        println!("{name}: {dr:.4}° ({sr:.4}° sigma), {dt:.6} ({st:.6} sigma)");
        assert!(dr <= 3.0 * sr && dt <= 3.0 * st, "{name}");
    }
}

#[test]
fn a_prior_sigma_is_the_reported_sigma_of_tz() {
    let (name, setup) = RECORDINGS[1];
    let (t, _) = truth(name);
    let prior = format!("tz={}+-0.002", t[2]);
    let (code, out, err) = with_prior(&file(name), setup, &prior, "json");
    assert_eq!(code, 0, "{err}");
    let r: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(r["prior"]["tz"]["sigma"].as_f64(), Some(0.002));
    let tz_sigma = r["uncertainty"]["covariance"][5][5]
        .as_f64()
        .unwrap()
        .sqrt();
    assert!((tz_sigma - 0.002).abs() < 1e-9, "{tz_sigma}");
    assert!(r["uncertainty"]["at_point"]["sigma"].as_f64().unwrap() >= 0.002);
    // The text face says which component came from the prior.
    let (code, out, _) = with_prior(&file(name), setup, &prior, "text");
    assert_eq!(code, 0);
    assert!(
        out.contains("Prior: tz = ") && out.contains("+- 0.002"),
        "{out}"
    );
}

#[test]
fn a_free_direction_off_the_axes_is_refused_naming_it() {
    let name = "tilted_wrist_eye-in-hand_s2";
    for extra in [vec![], vec!["--prior", "tz=0.1"]] {
        let mut args = vec!["calibrate".to_string(), file(name)];
        args.extend(extra.iter().map(|s| s.to_string()));
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, _, err) = run(&args);
        assert_eq!(code, 3, "{err}");
        assert!(
            err.contains("no prior on tx, ty or tz can state it"),
            "{err}"
        );
        assert!(err.contains("(0.000, -0.500, 0.866)"), "{err}");
    }
}

#[test]
fn bad_priors_are_usage_errors() {
    let f = file(RECORDINGS[0].0);
    for bad in [
        "rz=0.1",
        "tz",
        "tz=abc",
        "tz=0.1+-",
        "tz=0.1+--0.5",
        "tz=inf",
    ] {
        let (code, _, err) = run(&["calibrate", &f, "--prior", bad]);
        assert_eq!(code, 2, "{bad}: {err}");
        assert!(err.contains("--prior"), "{bad}: {err}");
    }
    let (code, _, err) = run(&["calibrate", &f, "--prior", "tz=0.1", "--prior", "tz=0.2"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("twice"), "{err}");
}

/// A unit mix-up (the camera in millimetres, the robot in metres) is named, not solved.
#[test]
fn a_unit_mismatch_is_refused_naming_the_fix() {
    let (name, setup) = RECORDINGS[0];
    let (t, _) = truth(name);
    let text = std::fs::read_to_string(file(name)).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let mm = dir.path().join("camera_mm.jsonl");
    let lines: Vec<String> = text
        .lines()
        .map(|l| {
            let mut v: Value = serde_json::from_str(l).unwrap();
            for k in 0..3 {
                let x = v["camera_from_target"]["translation"][k].as_f64().unwrap();
                v["camera_from_target"]["translation"][k] = (x * 1000.0).into();
            }
            v.to_string()
        })
        .collect();
    std::fs::write(&mm, lines.join("\n")).unwrap();
    let prior = format!("tz={}", t[2]);
    let mm = mm.to_str().unwrap();
    let (code, _, err) = run(&["calibrate", mm, "--setup", setup, "--prior", &prior]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("--fix camera-mm"), "{err}");
    let (code, out, err) = run(&[
        "calibrate",
        mm,
        "--setup",
        setup,
        "--prior",
        &prior,
        "--fix",
        "camera-mm",
        "--output",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    let r: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(r["prior"]["tz"]["value"].as_f64(), Some(t[2]));
}

/// `advise` on a SCARA recording names the prior, and says a low-DOF robot cannot make the turns
/// it suggests (a 6-DOF robot that turned one joint can).
#[test]
fn advise_names_the_prior_and_what_a_low_dof_robot_cannot_make() {
    for (name, setup) in RECORDINGS {
        let (code, out, err) = run(&["advise", &file(name), "--setup", setup]);
        assert_eq!(code, 0, "{err}");
        assert!(out.contains("--prior tz="), "{out}");
        assert!(out.contains("a low-DOF robot cannot make them"), "{out}");
        let json = &out[out.find('{').unwrap()..];
        let a: Value = serde_json::from_str(json).unwrap();
        assert!(a["low_dof"].as_str().unwrap().contains("SCARA"));
    }
}

/// `advise --prior` on a SCARA recording: X's uncertainty with the prior's, and turns about the
/// robot's one axis.
#[test]
fn advise_with_a_prior_advises_turns_the_robot_makes() {
    for (name, setup) in RECORDINGS {
        let tz = truth(name).0[2];
        let prior = format!("tz={tz}+-0.001");
        let (code, out, err) = run(&["advise", &file(name), "--setup", setup, "--prior", &prior]);
        assert_eq!(code, 0, "{err}");
        assert!(out.contains("X's tz is the prior's"), "{out}");
        let json = &out[out.find('{').unwrap()..];
        let a: Value = serde_json::from_str(json).unwrap();
        // The height's sigma is the prior's: the translation's one-sigma is at least 1 mm and
        // not far above it.
        let t = a["current"]["translation"].as_f64().unwrap();
        assert!((0.001..0.005).contains(&t), "{name}: {t}");
        for s in a["suggestions"].as_array().unwrap() {
            let k: Vec<f64> = s["axis_gripper"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect();
            assert!(k[2].abs() > 0.999, "{name}: {k:?}");
        }
        // A prior in millimetres on this recording in metres: exit 2, naming the unit.
        let (code, _, err) = run(&[
            "advise",
            &file(name),
            "--setup",
            setup,
            "--prior",
            &format!("tz={}", tz * 1000.0),
        ]);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains("another length unit"), "{err}");
    }
}

#[test]
fn verify_checks_a_saved_scara_x_and_takes_the_free_height_from_it() {
    let dir = std::env::temp_dir().join(format!("handeye-low-dof-verify-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, setup) in RECORDINGS {
        let tz = truth(name).0[2];
        let (code, out, err) = with_prior(&file(name), setup, &format!("tz={tz}+-0.001"), "json");
        assert_eq!(code, 0, "{name}: {err}");
        let saved = dir.join(format!("{name}.json"));
        std::fs::write(&saved, out).unwrap();
        let saved = saved.to_str().unwrap();
        // No prior: the height comes from the saved X, the rest is checked, and a note says so.
        let (code, out, err) = run(&["verify", "--x", saved, &file(name), "--setup", setup]);
        assert_eq!(code, 0, "{name}: {out}{err}");
        let v: Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v["verdict"], "consistent");
        let notes = v["notes"].to_string();
        assert!(notes.contains("cannot check X's tz"), "{notes}");
        // The user's own prior is used as given: 20 mm off, the saved X does not fit.
        let (code, out, err) = run(&[
            "verify",
            "--x",
            saved,
            &file(name),
            "--setup",
            setup,
            "--prior",
            &format!("tz={}", tz + 0.02),
        ]);
        assert_eq!(code, 4, "{name}: {out}{err}");
        // A prior in millimetres on a recording in metres: a usage error naming the unit.
        let (code, _, err) = run(&[
            "verify",
            "--x",
            saved,
            &file(name),
            "--setup",
            setup,
            "--prior",
            &format!("tz={}", tz * 1e3),
        ]);
        assert_eq!(code, 2, "{name}: {err}");
        assert!(err.contains("another length unit"), "{err}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `online INPUT --setup SETUP [--prior PRIOR] --output json`: (exit code, the JSON lines).
fn online(input: &str, setup: &str, prior: Option<&str>) -> (i32, Vec<Value>, String) {
    let mut args = vec!["online", input, "--setup", setup, "--output", "json"];
    if let Some(p) = prior {
        args.extend(["--prior", p]);
    }
    let (code, out, err) = run(&args);
    let lines = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    (code, lines, err)
}

#[test]
fn online_with_the_true_height_is_within_three_sigma() {
    for (name, setup) in RECORDINGS {
        let (t, q) = truth(name);
        let prior = format!("tz={}", t[2]);
        let (code, lines, err) = online(&file(name), setup, Some(&prior));
        assert_eq!(code, 0, "{name}: {err}");
        let r = lines
            .iter()
            .rfind(|l| l.get("estimate").is_some())
            .unwrap_or_else(|| panic!("{name}: no estimate: {err}"));
        assert_eq!(r["verdict"], "good", "{name}: {err}");
        assert_eq!(r["poses"].as_u64(), Some(25));
        assert_eq!(r["prior"]["tz"]["value"].as_f64(), Some(t[2]));
        assert_eq!(r["prior"]["tz"]["sigma"].as_f64(), Some(0.0));
        assert_eq!(r["low_dof"]["free"], "tz");
        assert_eq!(r["translation"][2].as_f64(), Some(t[2]));
        let dt = (0..3)
            .map(|i| (r["translation"][i].as_f64().unwrap() - t[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        let dot = (0..4)
            .map(|i| r["quaternion_xyzw"][i].as_f64().unwrap() * q[i])
            .sum::<f64>()
            .abs()
            .min(1.0);
        let dr = (2.0 * dot.acos()).to_degrees();
        let (sr, st) = (
            r["uncertainty"]["rotation_deg"].as_f64().unwrap(),
            r["uncertainty"]["translation"].as_f64().unwrap(),
        );
        println!("online {name}: {dr:.4}° ({sr:.4}° sigma), {dt:.6} ({st:.6} sigma)");
        assert!(dr <= 3.0 * sr && dt <= 3.0 * st, "{name}");
    }
}

#[test]
fn online_prior_sigma_is_added_to_the_translation_uncertainty() {
    let (name, setup) = RECORDINGS[0];
    let (t, _) = truth(name);
    let last = |prior: &str| {
        let (code, lines, err) = online(&file(name), setup, Some(prior));
        assert_eq!(code, 0, "{err}");
        lines
            .into_iter()
            .rfind(|l| l.get("estimate").is_some())
            .unwrap()
    };
    let exact = last(&format!("tz={}", t[2]));
    let loose = last(&format!("tz={}+-0.002", t[2]));
    assert_eq!(loose["prior"]["tz"]["sigma"].as_f64(), Some(0.002));
    let u = |r: &Value| r["uncertainty"]["translation"].as_f64().unwrap();
    // The data's part is the same; the prior's sigma is added in quadrature (SCARA: g = z).
    let expected = (u(&exact).powi(2) + 0.002f64.powi(2)).sqrt();
    assert!(
        (u(&loose) - expected).abs() < 1e-9,
        "{} {expected}",
        u(&loose)
    );
    assert!(u(&loose) >= 0.002);
    assert!(loose["uncertainty"]["at_point"]["sigma"].as_f64().unwrap() >= 0.002);
    // The text face says which component came from the prior.
    let (code, out, _) = run(&[
        "online",
        &file(name),
        "--setup",
        setup,
        "--prior",
        &format!("tz={}+-0.002", t[2]),
        "--output",
        "text",
    ]);
    assert_eq!(code, 0);
    assert!(out.contains("tz from the prior"), "{out}");
}

#[test]
fn online_without_a_prior_publishes_nothing_and_names_it() {
    for (name, setup) in RECORDINGS {
        let (code, lines, err) = online(&file(name), setup, None);
        assert_eq!(code, 0, "{name}: {err}");
        assert!(
            lines.iter().all(|l| l.get("estimate").is_none()),
            "{name}: {lines:?}"
        );
        assert!(err.contains("--prior tz="), "{name}: {err}");
        // A prior on another component than the free one names the one to give.
        let (_, lines, err) = online(&file(name), setup, Some("tx=0.03"));
        assert!(lines.iter().all(|l| l.get("estimate").is_none()));
        assert!(err.contains("--prior tz="), "{name}: {err}");
    }
}

#[test]
fn online_prior_in_another_unit_is_refused_or_converted() {
    let (name, setup) = RECORDINGS[0];
    let (t, _) = truth(name);
    // Millimetres on a recording in metres: refused (exit 2), naming the unit.
    let mm = format!("tz={}", t[2] * 1000.0);
    let (code, lines, err) = online(&file(name), setup, Some(&mm));
    assert_eq!(code, 2, "{err}");
    assert!(lines.iter().all(|l| l.get("estimate").is_none()));
    assert!(err.contains("another length unit"), "{err}");
    // The same with its unit: converted.
    let (code, lines, err) = online(&file(name), setup, Some(&format!("{mm}mm")));
    assert_eq!(code, 0, "{err}");
    let r = lines.iter().rfind(|l| l.get("estimate").is_some()).unwrap();
    assert!((r["translation"][2].as_f64().unwrap() - t[2]).abs() < 1e-12);
    // The paper's estimator has no low-DOF solve.
    let (code, _, err) = run(&[
        "online",
        &file(name),
        "--setup",
        setup,
        "--estimator",
        "paper",
        "--prior",
        "tz=0.1",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("accumulating estimator"), "{err}");
}

/// The truth file's X (`*_from_camera`) or target pose (`*_from_target`): translation, quaternion.
fn truth_of(name: &str, suffix: &str) -> (Vec<f64>, Vec<f64>) {
    let text = std::fs::read_to_string(testdata(&format!("low_dof/{name}.truth.json"))).unwrap();
    let t: Value = serde_json::from_str(&text).unwrap();
    let x = t
        .as_object()
        .unwrap()
        .iter()
        .find(|(k, _)| k.ends_with(suffix))
        .unwrap()
        .1;
    let v = |f: &str| -> Vec<f64> {
        x[f].as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    (v("translation"), v("quaternion_xyzw"))
}

/// Rotation (degrees) and translation error of a printed pose against a truth.
fn pose_errors(r: &Value, (t, q): &(Vec<f64>, Vec<f64>)) -> (f64, f64) {
    let dt = (0..3)
        .map(|i| (r["translation"][i].as_f64().unwrap() - t[i]).powi(2))
        .sum::<f64>()
        .sqrt();
    let dot = (0..4)
        .map(|i| r["quaternion_xyzw"][i].as_f64().unwrap() * q[i])
        .sum::<f64>()
        .abs()
        .min(1.0);
    ((2.0 * dot.acos()).to_degrees(), dt)
}

/// `calibrate --robot-world` with a prior: X's tz is the prior's, the target's height follows,
/// both within 3 sigma of the truth; a prior's sigma widens both.
#[test]
fn robot_world_with_the_true_height_is_within_three_sigma() {
    for (name, setup) in RECORDINGS {
        let x = truth_of(name, "_from_camera");
        let target = truth_of(name, "_from_target");
        let prior = format!("tz={}", x.0[2]);
        let f = file(name);
        let args = [
            "calibrate",
            &f,
            "--setup",
            setup,
            "--robot-world",
            "--prior",
            &prior,
            "--output",
            "json",
        ];
        let (code, out, err) = run(&args);
        assert_eq!(code, 0, "{name}: {err}");
        let r: Value = serde_json::from_str(&out).unwrap();
        assert_eq!(r["formulation"], "robot-world");
        assert_eq!(r["prior"]["tz"]["value"].as_f64(), Some(x.0[2]));
        assert_eq!(r["prior"]["tz"]["sigma"].as_f64(), Some(0.0));
        assert_eq!(r["translation"][2].as_f64(), Some(x.0[2]));
        assert_eq!(r["low_dof"]["free"], "tz");
        let (xr, xt) = pose_errors(&r, &x);
        let (yr, yt) = pose_errors(&r["target"], &target);
        let sigma = |u: &Value| {
            (
                u["rotation_deg"].as_f64().unwrap(),
                u["translation"].as_f64().unwrap(),
            )
        };
        let ((sxr, sxt), (syr, syt)) =
            (sigma(&r["uncertainty"]), sigma(&r["target"]["uncertainty"]));
        println!(
            "{name}: X {xr:.4}° ({sxr:.4}°) {xt:.6} ({sxt:.6}); target {yr:.4}° ({syr:.4}°) {yt:.6} ({syt:.6})"
        );
        assert!(xr <= 3.0 * sxr && xt <= 3.0 * sxt, "{name}");
        assert!(yr <= 3.0 * syr && yt <= 3.0 * syt, "{name}");
        // With a sigma: X's tz and the target's coupled component at least that uncertain.
        let prior = format!("tz={}+-0.002", x.0[2]);
        let mut args = args;
        args[6] = &prior;
        let (code, out, err) = run(&args);
        assert_eq!(code, 0, "{name}: {err}");
        let r: Value = serde_json::from_str(&out).unwrap();
        let tz = r["uncertainty"]["covariance"][5][5]
            .as_f64()
            .unwrap()
            .sqrt();
        assert!(tz >= 0.002 - 1e-12, "{name}: {tz}");
        // The SCARA's axis is the base's z: eye-in-hand, the target's height.
        let c = &r["target"]["uncertainty"]["covariance"];
        let target_sigma = (3..6)
            .map(|i| c[i][i].as_f64().unwrap())
            .sum::<f64>()
            .sqrt();
        assert!(target_sigma >= 0.002, "{name}: {target_sigma}");
        if setup == "eye-in-hand" {
            assert!(c[5][5].as_f64().unwrap().sqrt() >= 0.002, "{name}");
        }
        args[args.len() - 1] = "text";
        let (code, out, _) = run(&args);
        assert_eq!(code, 0);
        assert!(out.contains("X's tz is the prior's"), "{out}");
        assert!(
            out.contains("Prior: tz = ") && out.contains("+- 0.002"),
            "{out}"
        );
        assert!(
            out.contains("The target's translation along that axis follows"),
            "{out}"
        );
    }
}

/// Without a prior, `--robot-world` refuses a SCARA recording in the hand–eye refusal's words; a
/// prior in the wrong unit is refused as for hand–eye.
#[test]
fn robot_world_without_a_prior_is_refused_as_hand_eye_is() {
    for (name, setup) in RECORDINGS {
        let f = file(name);
        let (code, out, hand_eye) = run(&["calibrate", &f, "--setup", setup]);
        assert_eq!(code, 3, "{out}");
        let (code, out, err) = run(&["calibrate", &f, "--setup", setup, "--robot-world"]);
        assert_eq!(code, 3, "{name}: {out}");
        assert_eq!(err, hand_eye);
        assert!(err.contains("--prior tz="), "{err}");
        let (t, _) = truth(name);
        let mm = format!("tz={}", t[2] * 1000.0);
        let (code, _, hand_eye) = run(&["calibrate", &f, "--setup", setup, "--prior", &mm]);
        let (rw_code, _, err) = run(&[
            "calibrate",
            &f,
            "--setup",
            setup,
            "--robot-world",
            "--prior",
            &mm,
        ]);
        assert_eq!((rw_code, &err), (code, &hand_eye), "{name}");
        assert!(err.contains("another length unit"), "{err}");
    }
}
