//! `verify` on realistic recordings (the kinhec suite, `testdata/kinhec`): a saved X of the same rig
//! fits, a bumped camera or a turned X does not, a recording without motion cannot tell; and the
//! error of a point at the working distance (`uncertainty.at_point`) is as large as it says.
//!
//! `cargo test --release -p handeye --test verify -- --nocapture` prints the measurements.

use std::path::{Path, PathBuf};

use handeye::LengthUnit;
use handeye::io::{Format, read_pose_file, transform_from_json};
use handeye::model::pose::{exp_so3, transform_from_parts};
use handeye::{Consistency, SavedX, Verification, verify};
use handeye::{Options, calibrate};
use handeye::{Pairing, PosePair, Setup, Transform};
use nalgebra::Vector3;
use serde_json::Value;

fn suite() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata/kinhec")
}

/// The manifest's pose-pair entries whose file name starts with `kind`.
fn entries(kind: &str) -> Vec<Value> {
    let text = std::fs::read_to_string(suite().join("manifest.json")).unwrap();
    let manifest: Value = serde_json::from_str(&text).unwrap();
    manifest["files"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| {
            e["type"] == "pose_pairs"
                && e["file"]
                    .as_str()
                    .unwrap()
                    .starts_with(&format!("pairs/{kind}"))
        })
        .cloned()
        .collect()
}

fn setup(e: &Value) -> Setup {
    if e["setup"] == "eye-to-hand" {
        Setup::EyeToHand
    } else {
        Setup::EyeInHand
    }
}

fn poses(e: &Value) -> Vec<PosePair> {
    read_pose_file(&suite().join(e["file"].as_str().unwrap()), Format::Auto)
        .unwrap()
        .pairs
}

fn options() -> Options {
    Options {
        pairing: Pairing::All,
        ..Options::default()
    }
}

/// The X calibrated from `poses` as `calibrate --output json` saves it (with its covariance).
fn saved(poses: &[PosePair], setup: Setup) -> SavedX {
    let r = calibrate(poses, setup, &options())
        .map(|r| r.into_hand_eye().expect("the hand–eye report"))
        .unwrap();
    SavedX {
        x: r.transform,
        setup: Some(setup),
        covariance: Some(r.uncertainty.covariance),
        unit: None,
    }
}

/// The recording as it is after the camera moved on its mount by `delta` (X becomes X·delta):
/// each observation becomes delta⁻¹ · camera_from_target.
fn bumped(poses: &[PosePair], delta: &Transform) -> Vec<PosePair> {
    poses
        .iter()
        .map(|p| PosePair {
            base_from_gripper: p.base_from_gripper,
            camera_from_target: delta.inverse() * p.camera_from_target,
        })
        .collect()
}

fn transform(r: Vector3<f64>, t: Vector3<f64>) -> Transform {
    transform_from_parts(&exp_so3(&r), &t)
}

/// A unit vector from a seed, spread over the sphere.
fn direction(k: usize) -> Vector3<f64> {
    let golden = 2.399_963_229_728_653;
    let z = 1.0 - 2.0 * ((k as f64 + 0.5) / 7.0).fract();
    let r = (1.0 - z * z).sqrt();
    let phi = golden * k as f64;
    Vector3::new(r * phi.cos(), r * phi.sin(), z)
}

/// The kinds whose halves (20 to 25 poses) determine X: realistic noise, several robots.
const SAME_RIG: [&str; 3] = ["nominal", "student_t", "robot_error"];

fn halves(e: &Value) -> (Vec<PosePair>, Vec<PosePair>) {
    let p = poses(e);
    let h = p.len() / 2;
    (p[..h].to_vec(), p[h..].to_vec())
}

fn show(name: &str, v: &Verification) {
    println!(
        "{name:48} {:13} {:5.2} sigmas; difference {:.3}° {:.2} mm; sigma {:.3}° {:.2} mm",
        v.verdict.name(),
        v.distance_sigmas,
        v.difference.rotation_deg,
        v.difference.translation * 1e3,
        v.sigma.rotation_deg,
        v.sigma.translation * 1e3
    );
}

#[test]
fn the_same_rig_is_consistent_and_a_bumped_camera_is_not() {
    let (mut same, mut bumps) = (Vec::new(), Vec::new());
    for kind in SAME_RIG {
        for (k, e) in entries(kind).iter().enumerate() {
            let name = e["file"].as_str().unwrap();
            let (first, second) = halves(e);
            let s = saved(&first, setup(e));
            let v = verify(&s, &second, setup(e), &options()).unwrap();
            show(name, &v);
            same.push((name.to_string(), v.verdict, v.distance_sigmas));
            // The camera knocked by 0.5° about some axis and 2 mm along another.
            let delta = transform(direction(k) * 0.5f64.to_radians(), direction(k + 3) * 0.002);
            let v = verify(&s, &bumped(&second, &delta), setup(e), &options()).unwrap();
            show("  bumped 0.5° / 2 mm", &v);
            bumps.push((name.to_string(), v.verdict, v.distance_sigmas));
        }
    }
    assert!(same.len() >= 20, "{same:?}");
    for (name, verdict, d) in &same {
        assert_eq!(*verdict, Consistency::Consistent, "{name}: {d} sigmas");
    }
    // Recordings at stations see a 0.5° / 2 mm bump at 9 sigmas or more: every one is refused.
    // The continuous ones (X's one sigma up to 0.4°: the bump is about one sigma of X) see most.
    for (name, verdict, d) in &bumps {
        if name.contains("stations") {
            assert_eq!(
                *verdict,
                Consistency::Inconsistent,
                "{name} bumped: {d} sigmas"
            );
        }
    }
    let refused = bumps
        .iter()
        .filter(|b| b.1 == Consistency::Inconsistent)
        .count();
    println!("bumps refused: {refused} of {}", bumps.len());
    assert!(refused * 10 >= bumps.len() * 8, "{bumps:?}");
    // The distances of the same rig follow χ²₆ (median √5.35 = 2.31) roughly: not all tiny.
    let mut d: Vec<f64> = same.iter().map(|s| s.2).collect();
    d.sort_by(f64::total_cmp);
    let median = d[d.len() / 2];
    assert!(
        (1.2..3.5).contains(&median),
        "median distance {median}: {d:?}"
    );
}

#[test]
fn a_saved_x_turned_by_one_degree_is_refused_and_its_cause_named() {
    for (k, e) in entries("nominal").iter().enumerate() {
        let (first, second) = halves(e);
        let mut s = saved(&first, setup(e));
        s.x = transform(direction(k) * 1f64.to_radians(), Vector3::zeros()) * s.x;
        let v = verify(&s, &second, setup(e), &options()).unwrap();
        show(e["file"].as_str().unwrap(), &v);
        assert_eq!(v.verdict, Consistency::Inconsistent);
        assert!((v.difference.rotation_deg - 1.0).abs() < 0.5, "{v:?}");
        assert!(
            v.message.contains("the camera moved on its mount"),
            "{}",
            v.message
        );
    }
}

#[test]
fn a_recording_about_one_joint_cannot_tell() {
    for e in entries("degenerate_single_joint") {
        let all = poses(&e);
        let good = &entries("nominal_continuous")
            .into_iter()
            .find(|n| n["setup"] == e["setup"])
            .unwrap();
        let s = saved(&poses(good), setup(&e));
        let v = verify(&s, &all, setup(&e), &options()).unwrap();
        show(e["file"].as_str().unwrap(), &v);
        assert_eq!(v.verdict, Consistency::Undetermined);
        assert!(v.message.contains("record motions"), "{}", v.message);
    }
}

/// The poses with both translations in millimetres (the recording's in metres).
fn in_millimetres(poses: &[PosePair]) -> Vec<PosePair> {
    poses
        .iter()
        .map(|p| {
            let mut p = *p;
            p.base_from_gripper.translation.vector *= 1e3;
            p.camera_from_target.translation.vector *= 1e3;
            p
        })
        .collect()
}

#[test]
fn a_saved_x_in_metres_is_converted_for_a_recording_in_millimetres() {
    let e = &entries("nominal_stations")[0];
    let (first, second) = halves(e);
    let mut s = saved(&first, setup(e));
    s.unit = Some(LengthUnit::Metre);
    let mm = in_millimetres(&second);
    let v = verify(&s, &mm, setup(e), &options()).unwrap();
    show("metres against millimetres", &v);
    assert_eq!(v.verdict, Consistency::Consistent);
    assert_eq!(v.unit_scale, 1000.0);
    assert!(
        v.notes.iter().any(|n| n.contains("millimetres")),
        "{:?}",
        v.notes
    );
    // The difference is in millimetres now: a thousand times the metres' one.
    let metres = verify(&saved(&first, setup(e)), &second, setup(e), &options()).unwrap();
    let ratio = v.difference.translation / metres.difference.translation;
    assert!((ratio - 1000.0).abs() < 50.0, "{ratio}");
    // A file that does not say its unit is converted by its size.
    s.unit = None;
    let v = verify(&s, &mm, setup(e), &options()).unwrap();
    assert_eq!(v.verdict, Consistency::Consistent, "{v:?}");
    assert_eq!(v.unit_scale, 1000.0);
}

#[test]
fn without_the_saved_uncertainty_the_recordings_alone_counts() {
    let e = &entries("nominal_stations")[1];
    let (first, second) = halves(e);
    let with = saved(&first, setup(e));
    let without = SavedX {
        covariance: None,
        ..with.clone()
    };
    let a = verify(&with, &second, setup(e), &options()).unwrap();
    let b = verify(&without, &second, setup(e), &options()).unwrap();
    assert!(!b.saved_uncertainty && a.saved_uncertainty);
    assert!(b.sigma.rotation_deg < a.sigma.rotation_deg, "{a:?} {b:?}");
    assert!(b.distance_sigmas > a.distance_sigmas);
    assert!(b.notes.iter().any(|n| n.contains("no uncertainty")));
}

#[test]
fn an_inverted_recording_is_refused_as_misread() {
    let e = &entries("nominal_stations")[0];
    let (first, second) = halves(e);
    let inverted: Vec<PosePair> = second
        .iter()
        .map(|p| PosePair {
            base_from_gripper: p.base_from_gripper.inverse(),
            camera_from_target: p.camera_from_target,
        })
        .collect();
    let err = verify(&saved(&first, setup(e)), &inverted, setup(e), &options()).unwrap_err();
    assert!(matches!(err, handeye::Error::Misread { .. }), "{err}");
}

#[test]
fn outliers_in_the_recording_are_named_and_rejecting_them_restores_consistency() {
    for e in entries("outliers_gross") {
        let p = poses(&e);
        // The truth is the reference: the saved X is the true one, without uncertainty.
        let s = SavedX {
            x: transform_from_json(&e["x"]).unwrap(),
            setup: Some(setup(&e)),
            covariance: None,
            unit: None,
        };
        let kept = verify(&s, &p, setup(&e), &options()).unwrap();
        let rejected = verify(
            &s,
            &p,
            setup(&e),
            &Options {
                reject_outliers: true,
                ..options()
            },
        )
        .unwrap();
        show(e["file"].as_str().unwrap(), &kept);
        show("  --reject-outliers", &rejected);
        let r = kept.recording.as_ref().unwrap();
        assert!(!r.outliers.poses.is_empty(), "the outliers are named");
        assert_eq!(kept.quality.name(), "questionable");
        // Kept, they blur X beyond telling, or move it: never a silent "consistent".
        assert_ne!(kept.verdict, Consistency::Consistent, "{kept:?}");
        if kept.verdict == Consistency::Undetermined {
            assert!(
                kept.message.contains("--reject-outliers"),
                "{}",
                kept.message
            );
        }
        assert_eq!(rejected.verdict, Consistency::Consistent);
    }
}

#[test]
fn the_error_at_the_working_distance_is_as_large_as_it_says() {
    // The true error of the median target position mapped through X, over its sigma, on every
    // realistic recording of both setups (three seeds each kind).
    let mut ratios = Vec::new();
    for kind in ["nominal", "student_t", "pnp", "robot_error", "high_noise"] {
        for e in entries(kind) {
            let p = poses(&e);
            let r = match calibrate(&p, setup(&e), &options())
                .map(|r| r.into_hand_eye().expect("the hand–eye report"))
            {
                Ok(r) => r,
                Err(err) => {
                    println!("{}: refused ({err})", e["file"]);
                    continue;
                }
            };
            let at = r.uncertainty.at_point.as_ref().unwrap();
            assert_eq!(at.frame, "camera");
            let truth = transform_from_json(&e["x"]).unwrap();
            let point = nalgebra::Point3::from(Vector3::from(at.point));
            let error = (r.transform * point - truth * point).norm();
            println!(
                "{:48} point at {:.3} m: error {:.2} mm, sigma {:.2} mm",
                e["file"].as_str().unwrap(),
                Vector3::from(at.point).norm(),
                error * 1e3,
                at.sigma * 1e3
            );
            ratios.push(error / at.sigma);
        }
    }
    let (median, within) = summary(&mut ratios, "results");
    assert!(ratios.len() >= 30, "{ratios:?}");
    assert!((0.5..=1.5).contains(&median), "median {median}: {ratios:?}");
    assert!(within >= 0.9, "{within}: {ratios:?}");
}

/// The median error/sigma and the share within 3 sigma, printed with `label`.
fn summary(ratios: &mut [f64], label: &str) -> (f64, f64) {
    ratios.sort_by(f64::total_cmp);
    let median = ratios[ratios.len() / 2];
    let within = ratios.iter().filter(|r| **r <= 3.0).count() as f64 / ratios.len() as f64;
    println!(
        "{} {label}: error/sigma median {median:.2}, {:.0}% within 3 sigma",
        ratios.len(),
        within * 100.0
    );
    (median, within)
}

#[test]
fn the_online_estimate_says_its_error_at_the_working_distance_too() {
    // The accumulating estimator's last report on the same recordings: `at_point` at the mean
    // target position seen, from its covariance scaled to the reported uncertainty; and the
    // verdict every report carries.
    use handeye::track::{TrackOptions, Tracker};
    let mut ratios = Vec::new();
    for kind in ["nominal", "student_t", "pnp", "robot_error", "high_noise"] {
        for e in entries(kind) {
            let mut tracker = Tracker::new(setup(&e), TrackOptions::default());
            let mut last = None;
            for pose in &poses(&e) {
                last = tracker.push(pose).report.or(last);
            }
            let Some(report) = tracker.finish().or(last) else {
                println!("{}: no estimate ({:?})", e["file"], tracker.pending());
                continue;
            };
            let (point, sigma) = report.estimate.at_point.expect("an estimate has at_point");
            let json = report.json(setup(&e), None);
            assert_eq!(json["uncertainty"]["at_point"]["sigma"], sigma);
            assert!(["good", "questionable"].contains(&json["verdict"].as_str().unwrap()));
            let truth = transform_from_json(&e["x"]).unwrap();
            let p = nalgebra::Point3::from(Vector3::from(point));
            let error = (report.estimate.x * p - truth * p).norm();
            println!(
                "{:48} online: error {:.2} mm, sigma {:.2} mm",
                e["file"].as_str().unwrap(),
                error * 1e3,
                sigma * 1e3
            );
            ratios.push(error / sigma);
        }
    }
    let (median, within) = summary(&mut ratios, "online estimates");
    assert!(ratios.len() >= 30, "{ratios:?}");
    assert!(within >= 0.9, "{within}: {ratios:?}");
    // Not inflated beyond use: the error is a fair fraction of the sigma.
    assert!(median >= 0.2, "median {median}: {ratios:?}");
}

#[test]
fn the_point_can_be_chosen_and_its_sigma_grows_with_its_distance() {
    let e = &entries("nominal_stations")[0];
    let p = poses(e);
    let near = calibrate(
        &p,
        setup(e),
        &Options {
            point: Some([0.0, 0.0, 0.1]),
            ..options()
        },
    )
    .map(|r| r.into_hand_eye().expect("the hand–eye report"))
    .unwrap();
    let far = calibrate(
        &p,
        setup(e),
        &Options {
            point: Some([0.0, 0.0, 3.0]),
            ..options()
        },
    )
    .map(|r| r.into_hand_eye().expect("the hand–eye report"))
    .unwrap();
    let (a, b) = (
        near.uncertainty.at_point.clone().unwrap(),
        far.uncertainty.at_point.unwrap(),
    );
    assert_eq!(a.point, [0.0, 0.0, 0.1]);
    // Beyond the working distance the rotation's error adds to the translation's.
    let working = calibrate(&p, setup(e), &options())
        .map(|r| r.into_hand_eye().expect("the hand–eye report"))
        .unwrap();
    let w = working.uncertainty.at_point.unwrap();
    assert!(b.sigma > w.sigma && a.sigma > 0.0, "{a:?} {w:?} {b:?}");
    // The first-order image of the covariance agrees with the replicates' own.
    let mut u = near.uncertainty.clone();
    u.samples.clear();
    let linear = u.place(&near.transform, [0.0, 0.0, 3.0]);
    assert!(
        (linear.sigma / b.sigma - 1.0).abs() < 0.05,
        "{linear:?} {b:?}"
    );
}

#[test]
fn a_few_poses_of_the_same_rig_are_never_called_inconsistent() {
    // A bootstrap over 4 to 8 poses gives a covariance of unreliable shape: the distance alone
    // called windows of the same recording "inconsistent" (up to 18 sigmas at 4 poses, for a
    // difference of a fifth of the sizes). Every window of every realistic kind, both setups:
    // consistent or undetermined but at the test's design rate (0.1% per block, rotation and
    // translation: at most 1% allowed; measured 1 of 519, 9.3 sigmas and 3.4 sizes at 5 poses,
    // was 147 of 519 with the distance alone); a 10° turn is still found.
    let (mut windows, mut inconsistent, mut turned_found, mut turned) = (0, 0, 0, 0);
    for kind in ["nominal", "pnp"] {
        for (k, e) in entries(kind).iter().enumerate() {
            let p = poses(e);
            let s = saved(&p, setup(e));
            for n in [4, 5, 6, 8] {
                for start in (0..p.len().saturating_sub(n)).step_by(5) {
                    let window = &p[start..start + n];
                    let Ok(v) = verify(&s, window, setup(e), &options()) else {
                        continue;
                    };
                    windows += 1;
                    if v.verdict == Consistency::Inconsistent {
                        inconsistent += 1;
                        show(&format!("{} [{start}..+{n}]", e["file"]), &v);
                    }
                }
            }
            let mut moved = s.clone();
            moved.x = transform(direction(k) * 10f64.to_radians(), Vector3::zeros()) * moved.x;
            match verify(&moved, &p[..6], setup(e), &options()) {
                Ok(v) => {
                    turned += 1;
                    turned_found += usize::from(v.verdict == Consistency::Inconsistent);
                    if v.verdict != Consistency::Inconsistent {
                        show(&format!("{} 10° turn, 6 poses", e["file"]), &v);
                        println!("  {}", v.message);
                    }
                    // Never a silent pass: a turn not found is one the poses cannot tell.
                    assert_ne!(
                        v.verdict,
                        Consistency::Consistent,
                        "{}: {}",
                        e["file"],
                        v.message
                    );
                }
                Err(err) => println!("{}: 10° turn, refused: {err}", e["file"]),
            }
        }
    }
    println!(
        "{windows} windows, {inconsistent} inconsistent; 10° turns found {turned_found} of {turned}"
    );
    assert!(windows >= 100, "{windows}");
    assert!(inconsistent * 100 <= windows, "{inconsistent} of {windows}");
    // Measured: 15 of 18, then 14 once the systematic-error test flagged pnp_stations_eih_s1 and
    // widened its saved X's covariance (the turn is then 3.26 sizes, the bound 3.29); the others
    // missed are undetermined with their reason (a degenerate window, sizes within the bound),
    // never consistent (asserted above).
    assert!(turned_found * 4 >= turned * 3, "{turned_found} of {turned}");
}

/// A low-DOF recording (`testdata/low_dof`: simulated SCARAs, every motion about one axis) and its
/// setup.
fn low_dof(name: &str) -> (Vec<PosePair>, Setup, Value) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata/low_dof");
    let poses = read_pose_file(&dir.join(format!("{name}.jsonl")), Format::Auto)
        .unwrap()
        .pairs;
    let truth: Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join(format!("{name}.truth.json"))).unwrap(),
    )
    .unwrap();
    let setup = if truth["setup"] == "eye-to-hand" {
        Setup::EyeToHand
    } else {
        Setup::EyeInHand
    };
    (poses, setup, truth)
}

#[test]
fn a_low_dof_recording_checks_what_it_determines_and_takes_tz_from_the_saved_x() {
    for name in ["scara_eye-in-hand_s0", "scara_eye-to-hand_s1"] {
        let (all, setup, truth) = low_dof(name);
        let x_key = if setup == Setup::EyeInHand {
            "gripper_from_camera"
        } else {
            "base_from_camera"
        };
        let tz = truth[x_key]["translation"][2].as_f64().unwrap();
        let h = all.len() / 2;
        let (first, second) = (&all[..h], &all[h..]);
        let with_prior = Options {
            priors: vec![format!("tz={tz}+-0.001").parse().unwrap()],
            ..options()
        };
        let r = calibrate(first, setup, &with_prior)
            .map(|r| r.into_hand_eye().expect("the hand–eye report"))
            .unwrap();
        let saved = SavedX {
            x: r.transform,
            setup: Some(setup),
            covariance: Some(r.uncertainty.covariance),
            unit: None,
        };
        // Without a prior the recording alone would be refused; verify takes tz from the saved X.
        let v = verify(&saved, second, setup, &options()).unwrap();
        show(name, &v);
        assert_eq!(v.verdict, Consistency::Consistent, "{}", v.message);
        assert!(
            v.notes.iter().any(|n| n.contains("cannot check X's tz")),
            "{:?}",
            v.notes
        );
        // The camera bumped on its mount by 1° and 3 mm across the axis: found.
        let delta = transform(
            Vector3::new(1f64.to_radians(), 0.0, 0.0),
            Vector3::new(0.003, 0.0, 0.0),
        );
        let v = verify(&saved, &bumped(second, &delta), setup, &options()).unwrap();
        show("  bumped 1° and 3 mm", &v);
        assert_eq!(v.verdict, Consistency::Inconsistent, "{}", v.message);
        // A saved X in millimetres against this recording in metres: converted, and consistent.
        let mut mm = saved.clone();
        mm.x.translation.vector *= 1e3;
        let c = mm.covariance.as_mut().unwrap();
        for (i, row) in c.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v *= if i >= 3 { 1e3 } else { 1.0 } * if j >= 3 { 1e3 } else { 1.0 };
            }
        }
        let v = verify(&mm, second, setup, &options()).unwrap();
        show("  saved in millimetres", &v);
        assert_eq!(v.verdict, Consistency::Consistent, "{}", v.message);
        assert_eq!(v.unit_scale, 1e-3);
        // A user's own prior is used as given: a wrong one is found.
        let wrong = Options {
            priors: vec![format!("tz={}", tz + 0.02).parse().unwrap()],
            ..options()
        };
        let v = verify(&saved, second, setup, &wrong).unwrap();
        show("  a prior 20 mm off", &v);
        assert_eq!(v.verdict, Consistency::Inconsistent, "{}", v.message);
        // The robot poses inverted: never consistent.
        let inverted: Vec<PosePair> = second
            .iter()
            .map(|p| PosePair {
                base_from_gripper: p.base_from_gripper.inverse(),
                camera_from_target: p.camera_from_target,
            })
            .collect();
        match verify(&saved, &inverted, setup, &options()) {
            Ok(v) => {
                show("  robot poses inverted", &v);
                println!("    {}", v.message);
                assert_ne!(v.verdict, Consistency::Consistent, "{}", v.message);
                assert!(
                    v.message.contains("if the robot can turn about other axes"),
                    "{}",
                    v.message
                );
            }
            Err(e) => println!("  robot poses inverted: {e}"),
        }
        // Two frames paired with the wrong camera pose (turned 20°): never silently consistent;
        // left out, the saved X fits again.
        let mut outliers = second.to_vec();
        for k in [2, 7] {
            let turn = transform(Vector3::new(0.0, 20f64.to_radians(), 0.0), Vector3::zeros());
            outliers[k].camera_from_target = turn * outliers[k].camera_from_target;
        }
        let v = verify(&saved, &outliers, setup, &options()).unwrap();
        show("  two outlier frames", &v);
        let named = v
            .recording
            .as_ref()
            .is_some_and(|r| r.outliers.poses.len() >= 2);
        assert!(
            v.verdict != Consistency::Consistent || named,
            "{}",
            v.message
        );
        let rejecting = Options {
            reject_outliers: true,
            ..options()
        };
        let v = verify(&saved, &outliers, setup, &rejecting).unwrap();
        show("  ... left out", &v);
        assert_eq!(v.verdict, Consistency::Consistent, "{}", v.message);
    }
    // An axis off the coordinate axes: no prior can state the free direction, so it cannot tell.
    let (all, setup, _) = low_dof("tilted_wrist_eye-in-hand_s2");
    let v = verify(
        &SavedX {
            x: transform(Vector3::zeros(), Vector3::new(0.03, -0.04, -0.1)),
            setup: Some(setup),
            covariance: None,
            unit: None,
        },
        &all,
        setup,
        &options(),
    )
    .unwrap();
    assert_eq!(v.verdict, Consistency::Undetermined, "{}", v.message);
}

/// `verify` checks an X calibrated as hand–eye: the one `Options` naming the robot-world problem is
/// refused, naming the field, rather than verified as if it were hand–eye.
#[test]
fn the_robot_world_problem_is_refused_by_name() {
    let series = handeye::sim::simulate(
        &handeye::sim::SimConfig {
            poses: 20,
            ..handeye::sim::SimConfig::default()
        },
        7,
        0,
    );
    let saved = SavedX {
        x: series.gripper_from_camera,
        setup: Some(Setup::EyeInHand),
        covariance: None,
        unit: None,
    };
    let options = Options {
        problem: handeye::Problem::ROBOT_WORLD,
        ..options()
    };
    let e = verify(&saved, &series.poses, Setup::EyeInHand, &options).unwrap_err();
    assert!(
        matches!(
            e,
            handeye::Error::InvalidParameter {
                name: "problem",
                ..
            }
        ),
        "{e}"
    );
}

/// `detectable` and a tolerance on the inputs that go wrong: a unit mix-up (saved in metres, the
/// recording in millimetres: `detectable` and the tolerance in millimetres), outliers kept (a
/// tolerance never turns their verdict into a fit), a setup the file contradicts (refused by name),
/// a degenerate recording (nothing detectable).
#[test]
fn detectable_and_the_tolerance_on_unit_mixups_outliers_setups_and_degenerate_recordings() {
    let e = &entries("nominal_stations")[0];
    let (first, second) = halves(e);
    let same = verify(&saved(&first, setup(e)), &second, setup(e), &options()).unwrap();
    assert_eq!(same.verdict, Consistency::Consistent);
    let d = same.detectable;
    // The limit times the largest one-sigma: at least the sizes' RMS over the three axes.
    assert!(d.rotation_deg >= same.limit_sigmas * same.sigma.rotation_deg / 3f64.sqrt());
    assert!(d.translation >= same.limit_sigmas * same.sigma.translation / 3f64.sqrt());
    assert!(d.rotation_deg <= same.limit_sigmas * same.sigma.rotation_deg);
    // In millimetres against a saved X in metres: a thousand times the metres' one.
    let mut s = saved(&first, setup(e));
    s.unit = Some(LengthUnit::Metre);
    let mm = in_millimetres(&second);
    let v = verify(&s, &mm, setup(e), &options()).unwrap();
    let ratio = v.detectable.translation / d.translation;
    assert!((ratio - 1000.0).abs() < 100.0, "{ratio}");
    let tight = handeye::Sizes {
        rotation_deg: d.rotation_deg * 2.0,
        translation: d.translation * 1e3 / 4.0,
    };
    let v = v.within(tight).unwrap();
    assert_eq!(v.verdict, Consistency::Undetermined, "{}", v.message);
    assert!(v.message.contains("within your tolerance"), "{}", v.message);
    assert!(
        same.clone()
            .within(handeye::Sizes {
                rotation_deg: -1.0,
                translation: 1.0
            })
            .is_err()
    );
    // The other setup than the file's: refused, naming both.
    let err = verify(
        &saved(&first, setup(e)),
        &second,
        setup(e).other(),
        &options(),
    )
    .unwrap_err();
    let words = err.to_string();
    assert!(
        words.contains(setup(e).name()) && words.contains(setup(e).other().name()),
        "{words}"
    );
    // Outliers kept: a tolerance does not make their verdict a fit.
    for o in entries("outliers_gross") {
        let s = SavedX {
            x: transform_from_json(&o["x"]).unwrap(),
            setup: Some(setup(&o)),
            covariance: None,
            unit: None,
        };
        let v = verify(&s, &poses(&o), setup(&o), &options()).unwrap();
        assert!(v.detectable.rotation_deg > 0.0 && v.detectable.translation > 0.0);
        let loose = handeye::Sizes {
            rotation_deg: 1e3,
            translation: 1e3,
        };
        assert_ne!(v.within(loose).unwrap().verdict, Consistency::Consistent);
    }
    // A recording about one joint: it cannot tell, and sees nothing.
    let one = &entries("degenerate_single_joint")
        .into_iter()
        .find(|o| setup(o) == setup(e))
        .unwrap();
    let v = verify(
        &saved(&first, setup(e)),
        &poses(one),
        setup(one),
        &options(),
    )
    .unwrap();
    assert_eq!(v.verdict, Consistency::Undetermined);
    assert!(v.detectable.rotation_deg.is_infinite());
}
