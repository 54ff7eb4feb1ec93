//! Rigs: several cameras and targets in one calibration (issue 56), on simulated rigs with known
//! truth: exact recovery, the uncertainty against the truth, what is undetermined, loops that
//! name a moved camera, and inputs read wrong.

use handeye::rig::{
    Mount, Mounts, Observation, RigOptions, RigRecording, RigReport, calibrate_rig,
};
use handeye::solve::refine_robot_world;
use handeye::{Error, PosePair, Setup, Transform, Warning};
use nalgebra::{Rotation3, Translation3, Vector3};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal, Uniform};
use rand_xoshiro::Xoshiro256PlusPlus;

/// A simulated rig: its parts' true poses and what it records.
struct Sim {
    parts: Vec<(&'static str, Mount, Transform)>,
    /// Who sees whom: (camera, target, fraction of poses at which it is seen).
    views: Vec<(&'static str, &'static str, f64)>,
    /// Noise of each observation: rotation (radians) and translation (metres), one sigma per axis.
    noise: (f64, f64),
}

fn pose(t: [f64; 3], r: [f64; 3]) -> Transform {
    Transform::from_parts(
        Translation3::new(t[0], t[1], t[2]),
        Rotation3::from_euler_angles(r[0], r[1], r[2]),
    )
}

/// The usual rig: a wrist camera on the gripper sees a board on the table; two fixed cameras see
/// a marker on the gripper, and the first of them sees the board too.
fn three_cameras(noise: (f64, f64)) -> Sim {
    Sim {
        parts: vec![
            (
                "wrist",
                Mount::Gripper,
                pose([0.05, -0.02, 0.08], [0.1, -0.2, 1.5]),
            ),
            ("left", Mount::Base, pose([1.2, 0.6, 0.9], [2.2, 0.3, -2.4])),
            (
                "right",
                Mount::Base,
                pose([1.1, -0.7, 0.8], [2.1, -0.2, 2.6]),
            ),
            (
                "board",
                Mount::Base,
                pose([0.7, 0.05, -0.1], [0.05, 0.02, 0.3]),
            ),
            (
                "marker",
                Mount::Gripper,
                pose([0.0, 0.03, 0.12], [3.0, 0.1, -0.4]),
            ),
        ],
        views: vec![
            ("wrist", "board", 1.0),
            ("left", "marker", 0.9),
            ("left", "board", 0.8),
            ("right", "marker", 0.9),
        ],
        noise,
    }
}

/// Robot poses looking around a working point, rotations about varied axes (up to ±0.5 rad).
fn robot_poses(n: usize, seed: u64) -> Vec<Transform> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let u = Uniform::new(-1.0, 1.0).expect("a range");
    (0..n)
        .map(|_| {
            let t = [
                0.5 + 0.15 * u.sample(&mut rng),
                0.15 * u.sample(&mut rng),
                0.5 + 0.1 * u.sample(&mut rng),
            ];
            let r = [
                std::f64::consts::PI + 0.5 * u.sample(&mut rng),
                0.5 * u.sample(&mut rng),
                0.5 * u.sample(&mut rng),
            ];
            pose(t, r)
        })
        .collect()
}

fn noisy(t: &Transform, (sr, st): (f64, f64), rng: &mut Xoshiro256PlusPlus) -> Transform {
    if sr == 0.0 && st == 0.0 {
        return *t;
    }
    let nr = Normal::new(0.0, sr).expect("sigma");
    let nt = Normal::new(0.0, st).expect("sigma");
    let w = Vector3::new(nr.sample(rng), nr.sample(rng), nr.sample(rng));
    let d = Vector3::new(nt.sample(rng), nt.sample(rng), nt.sample(rng));
    Transform::from_parts(Translation3::from(d), Rotation3::new(w)) * t
}

impl Sim {
    fn truth(&self, name: &str) -> (Mount, Transform) {
        let p = self.parts.iter().find(|p| p.0 == name).expect("a part");
        (p.1, p.2)
    }

    fn mounts(&self) -> Mounts {
        self.parts
            .iter()
            .map(|(n, m, _)| (n.to_string(), *m))
            .collect()
    }

    /// camera_from_target = X_c⁻¹ B(m_c)⁻¹ B(m_t) Y_t at robot pose q.
    fn sees(&self, camera: &str, target: &str, q: &Transform) -> Transform {
        let (mc, x) = self.truth(camera);
        let (mt, y) = self.truth(target);
        x.inverse() * mc.base_from_mount(q).inverse() * mt.base_from_mount(q) * y
    }

    fn record(&self, poses: &[Transform], seed: u64) -> RigRecording {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0xABCD);
        let u = Uniform::new(0.0, 1.0).expect("a range");
        let mut r = RigRecording {
            poses: poses.to_vec(),
            names: (0..poses.len())
                .map(|i| format!("pose {}", i + 1))
                .collect(),
            observations: Vec::new(),
        };
        for (i, q) in poses.iter().enumerate() {
            for &(c, t, p) in &self.views {
                if u.sample(&mut rng) <= p {
                    r.observations.push(Observation {
                        pose: i,
                        camera: c.into(),
                        target: t.into(),
                        camera_from_target: noisy(&self.sees(c, t, q), self.noise, &mut rng),
                    });
                }
            }
        }
        r
    }
}

/// The angle between two rotations (degrees, from the chord: exact near 0, where acos is not)
/// and the distance between two translations.
fn difference(a: &Transform, b: &Transform) -> (f64, f64) {
    let chord = (a.rotation.matrix() - b.rotation.matrix()).norm();
    let r = (2.0 * (chord / 8f64.sqrt()).min(1.0).asin()).to_degrees();
    (r, (a.translation.vector - b.translation.vector).norm())
}

fn solved(report: &RigReport, name: &str) -> Transform {
    report
        .rig
        .cameras
        .get(name)
        .or_else(|| report.rig.targets.get(name))
        .unwrap_or_else(|| panic!("`{name}` solved"))
        .pose
}

fn options() -> RigOptions {
    RigOptions::default()
}

#[test]
fn noise_free_rig_is_recovered_exactly() {
    let sim = three_cameras((0.0, 0.0));
    let rec = sim.record(&robot_poses(40, 1), 1);
    let report = calibrate_rig(&rec, &sim.mounts(), &options()).expect("solves");
    for (name, _, truth) in &sim.parts {
        let (r, t) = difference(&solved(&report, name), truth);
        assert!(r < 1e-7 && t < 1e-9, "{name}: {r}° {t} m");
    }
    assert!(report.rig.undetermined.is_empty());
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
    // Loops: left/right through the marker, wrist/left through the board, board/marker through left.
    assert_eq!(report.rig.loops.len(), 3, "{:?}", report.rig.loops);
    assert!(
        report
            .rig
            .loops
            .iter()
            .all(|l| l.closes && l.translation < 1e-9)
    );
    // The frame names.
    assert_eq!(report.rig.cameras["wrist"].frame, "gripper_from_camera");
    assert_eq!(report.rig.cameras["left"].frame, "base_from_camera");
    assert_eq!(report.rig.targets["board"].frame, "base_from_target");
    assert_eq!(report.rig.targets["marker"].frame, "gripper_from_target");
}

#[test]
fn noisy_parts_lie_within_their_sigma_and_loops_close() {
    let mut within = 0;
    let mut parts = 0;
    let mut false_alarms = 0;
    for seed in 0..6u64 {
        let sim = three_cameras((0.1f64.to_radians(), 0.0005));
        let rec = sim.record(&robot_poses(40, 100 + seed), 100 + seed);
        let report = calibrate_rig(&rec, &sim.mounts(), &options()).expect("solves");
        for (name, _, truth) in &sim.parts {
            let part = report
                .rig
                .cameras
                .get(*name)
                .or_else(|| report.rig.targets.get(*name))
                .expect("solved");
            let (r, t) = difference(&part.pose, truth);
            let u = &part.uncertainty;
            parts += 1;
            if r <= 3.0 * u.rotation_deg && t <= 3.0 * u.translation {
                within += 1;
            } else {
                eprintln!(
                    "seed {seed} {name}: {r:.4}° vs sigma {:.4}°, {t:.5} vs {:.5}",
                    u.rotation_deg, u.translation
                );
            }
            assert!(u.rotation_deg > 0.0 && u.translation > 0.0);
        }
        if report
            .warnings
            .iter()
            .any(|w| matches!(w, Warning::LoopMisfit { .. }))
        {
            false_alarms += 1;
            eprintln!("seed {seed}: {:?}", report.rig.loops);
        }
    }
    eprintln!("{within} of {parts} parts within 3 sigma; {false_alarms} false loop alarms");
    assert!(within as f64 >= 0.95 * parts as f64, "{within} of {parts}");
    assert_eq!(false_alarms, 0);
}

#[test]
fn a_disconnected_camera_and_an_unobserved_name_are_undetermined_the_rest_solved() {
    let mut sim = three_cameras((0.0, 0.0));
    // A second wrist camera that only sees a tag on the gripper: no robot motion relates them.
    sim.parts.push((
        "tool_cam",
        Mount::Gripper,
        pose([0.0, 0.1, 0.05], [0.3, 0.2, 0.1]),
    ));
    sim.parts.push((
        "tool_tag",
        Mount::Gripper,
        pose([0.0, 0.1, 0.25], [3.1, 0.0, 0.0]),
    ));
    sim.views.push(("tool_cam", "tool_tag", 1.0));
    let rec = sim.record(&robot_poses(30, 2), 2);
    let mut mounts = sim.mounts();
    mounts.insert("spare".into(), Mount::Base);
    let report = calibrate_rig(&rec, &mounts, &options()).expect("solves the rest");
    let names: Vec<&str> = report
        .rig
        .undetermined
        .iter()
        .map(|u| u.name.as_str())
        .collect();
    assert_eq!(
        names,
        ["spare", "tool_cam", "tool_tag"],
        "{:?}",
        report.rig.undetermined
    );
    assert!(!report.rig.cameras.contains_key("tool_cam"));
    assert!(
        report.rig.undetermined[1]
            .reason
            .contains("fixed to the gripper")
    );
    for name in ["wrist", "left", "right", "board", "marker"] {
        let (r, t) = difference(&solved(&report, name), &sim.truth(name).1);
        assert!(r < 1e-7 && t < 1e-9, "{name}");
    }
    let undetermined: Vec<&Warning> = report
        .warnings
        .iter()
        .filter(|w| w.code() == "undetermined")
        .collect();
    assert_eq!(undetermined.len(), 3);
    assert!(undetermined[1].to_string().contains("`tool_cam`"));
}

#[test]
fn a_camera_whose_motions_turn_about_one_axis_is_undetermined() {
    let mut sim = three_cameras((0.0, 0.0));
    sim.parts
        .push(("door", Mount::Base, pose([0.2, 1.0, 0.7], [1.9, 0.0, 3.0])));
    sim.parts.push((
        "flag",
        Mount::Gripper,
        pose([0.05, 0.0, 0.1], [1.6, 0.0, 0.0]),
    ));
    let mut poses = robot_poses(30, 3);
    let mut rec = sim.record(&poses, 3);
    // `door` sees `flag` only at poses turned about the base's z axis.
    let start = poses.len();
    for k in 0..8 {
        let q = pose(
            [0.4, 0.1, 0.5],
            [std::f64::consts::PI, 0.0, 0.15 * k as f64],
        );
        poses.push(q);
        rec.poses.push(q);
        rec.names.push(format!("pose {}", start + k + 1));
        rec.observations.push(Observation {
            pose: start + k,
            camera: "door".into(),
            target: "flag".into(),
            camera_from_target: sim.sees("door", "flag", &q),
        });
    }
    let report = calibrate_rig(&rec, &sim.mounts(), &options()).expect("solves the rest");
    let names: Vec<&str> = report
        .rig
        .undetermined
        .iter()
        .map(|u| u.name.as_str())
        .collect();
    assert_eq!(names, ["door", "flag"]);
    assert!(
        report.rig.undetermined[0]
            .reason
            .contains("two non-parallel"),
        "{}",
        report.rig.undetermined[0].reason
    );
    assert!(report.rig.cameras.contains_key("left"));
    // Nothing else: refused by name.
    let only: RigRecording = RigRecording {
        poses: rec.poses.clone(),
        names: rec.names.clone(),
        observations: rec
            .observations
            .iter()
            .filter(|o| o.camera == "door")
            .cloned()
            .collect(),
    };
    match calibrate_rig(&only, &sim.mounts(), &options()) {
        Err(e @ Error::RigUndetermined { .. }) => {
            let words = e.to_string();
            assert!(
                words.contains("`door`") && words.contains("`flag`"),
                "{words}"
            );
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
}

#[test]
fn a_camera_seen_only_through_a_target_another_determines_is_solved() {
    let mut sim = three_cameras((0.0, 0.0));
    // A fixed camera that sees only the board, which the wrist camera determines.
    sim.parts
        .push(("top", Mount::Base, pose([0.7, 0.0, 1.5], [3.1, 0.05, 0.0])));
    sim.views.push(("top", "board", 1.0));
    let rec = sim.record(&robot_poses(30, 4), 4);
    let report = calibrate_rig(&rec, &sim.mounts(), &options()).expect("solves");
    let (r, t) = difference(&solved(&report, "top"), &sim.truth("top").1);
    assert!(r < 1e-7 && t < 1e-9);
}

#[test]
fn a_moved_camera_is_named_by_its_loops() {
    for seed in 0..3u64 {
        let sim = three_cameras((0.1f64.to_radians(), 0.0005));
        let poses = robot_poses(40, 200 + seed);
        let mut rec = sim.record(&poses, 200 + seed);
        // `right` is knocked half way through: 1° and 5 mm.
        let knock = pose([0.005, 0.0, 0.0], [0.0, 1f64.to_radians(), 0.0]);
        for o in &mut rec.observations {
            if o.camera == "right" && o.pose >= 20 {
                o.camera_from_target = knock.inverse() * o.camera_from_target;
            }
        }
        let report = calibrate_rig(&rec, &sim.mounts(), &options()).expect("solves");
        let misfit = report
            .warnings
            .iter()
            .find_map(|w| match w {
                Warning::LoopMisfit {
                    parts, singled_out, ..
                } => Some((parts.clone(), *singled_out)),
                _ => None,
            })
            .unwrap_or_else(|| panic!("seed {seed}: no misfit in {:?}", report.rig.loops));
        assert_eq!(misfit, (vec!["right".to_string()], true), "seed {seed}");
        let right = report
            .rig
            .loops
            .iter()
            .find(|l| l.compared.contains(&"right".to_string()))
            .expect("a loop");
        eprintln!(
            "seed {seed}: change {:.1} standard errors at pose {}",
            right.change_sigmas, right.change_at
        );
        let words = report
            .warnings
            .iter()
            .find(|w| w.code() == "loop_misfit")
            .expect("a warning")
            .to_string();
        assert!(words.contains("`right` does not fit"), "{words}");
    }
}

#[test]
fn a_one_camera_rig_is_the_robot_world_refinement() {
    let sim = three_cameras((0.2f64.to_radians(), 0.001));
    let poses = robot_poses(30, 5);
    let full = sim.record(&poses, 5);
    let rec = RigRecording {
        observations: full
            .observations
            .into_iter()
            .filter(|o| o.camera == "wrist")
            .collect(),
        ..full
    };
    let report = calibrate_rig(&rec, &sim.mounts(), &options()).expect("solves");
    let pairs: Vec<PosePair> = rec
        .observations
        .iter()
        .map(|o| PosePair {
            base_from_gripper: rec.poses[o.pose],
            camera_from_target: o.camera_from_target,
        })
        .collect();
    let rw = refine_robot_world(&pairs, Setup::EyeInHand).expect("solves");
    let (r, t) = difference(&solved(&report, "wrist"), &rw.solution.x);
    assert!(r < 1e-7 && t < 1e-9, "{r}° {t}");
    let (r, t) = difference(&solved(&report, "board"), &rw.solution.target);
    assert!(r < 1e-7 && t < 1e-9, "{r}° {t}");
    // And not trivially: the noise moved X off the truth.
    let (r, _) = difference(&solved(&report, "wrist"), &sim.truth("wrist").1);
    assert!(r > 1e-4);
}

#[test]
fn a_camera_read_inverted_is_refused_by_name() {
    let sim = three_cameras((0.05f64.to_radians(), 0.0002));
    let mut rec = sim.record(&robot_poses(30, 6), 6);
    for o in &mut rec.observations {
        if o.camera == "left" {
            o.camera_from_target = o.camera_from_target.inverse();
        }
    }
    match calibrate_rig(&rec, &sim.mounts(), &options()) {
        Err(e @ Error::RigMisread { .. }) => {
            let words = e.to_string();
            assert!(words.starts_with("camera `left`"), "{words}");
            assert!(words.contains("invert"), "{words}");
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
}

#[test]
fn a_camera_in_millimetres_is_refused_by_name() {
    let sim = three_cameras((0.05f64.to_radians(), 0.0002));
    let mut rec = sim.record(&robot_poses(30, 7), 7);
    for o in &mut rec.observations {
        if o.camera == "right" {
            o.camera_from_target.translation.vector *= 1000.0;
        }
    }
    match calibrate_rig(&rec, &sim.mounts(), &options()) {
        Err(e @ Error::RigMisread { .. }) => {
            let words = e.to_string();
            assert!(words.starts_with("camera `right`"), "{words}");
            assert!(
                words.contains("mm") || words.contains("millimet"),
                "{words}"
            );
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
}

#[test]
fn outlier_observations_are_named() {
    let sim = three_cameras((0.05f64.to_radians(), 0.0002));
    let mut rec = sim.record(&robot_poses(40, 8), 8);
    let mut spoiled = Vec::new();
    for (k, o) in rec.observations.iter_mut().enumerate() {
        if o.camera == "wrist" && [5, 17, 29].contains(&o.pose) {
            o.camera_from_target = pose([0.01, 0.0, 0.02], [0.0, 0.2, 0.0]) * o.camera_from_target;
            spoiled.push(k);
        }
    }
    assert_eq!(spoiled.len(), 3);
    let report = calibrate_rig(&rec, &sim.mounts(), &options()).expect("solves");
    let Some(Warning::PoorlyPredicted { count, shown, .. }) = report
        .warnings
        .iter()
        .find(|w| w.code() == "poorly_predicted")
    else {
        panic!("no warning: {:?}", report.warnings);
    };
    assert_eq!(*count, 3, "{shown:?}");
    for p in ["pose 6 ", "pose 18 ", "pose 30 "] {
        assert!(shown.iter().any(|s| s.starts_with(p)), "{p} in {shown:?}");
    }
    assert_eq!(report.verdict, handeye::Assessment::Questionable);
}

#[test]
fn an_unmounted_name_is_refused() {
    let sim = three_cameras((0.0, 0.0));
    let rec = sim.record(&robot_poses(10, 9), 9);
    let mut mounts = sim.mounts();
    mounts.remove("right");
    match calibrate_rig(&rec, &mounts, &options()) {
        Err(e @ Error::InvalidParameter { .. }) => {
            assert!(e.to_string().contains("camera `right` has no mount"), "{e}");
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
}

/// The kinhec rig suite (`testdata/kinhec/rig`, made by `generate_rig.py`): a kinhec robot's
/// stations, its wrist camera's board through PnP, two fixed cameras' views of a flange marker
/// (and the board) through kinhec's visibility and PnP.
fn kinhec_rig(stem: &str) -> (RigRecording, Mounts, serde_json::Value) {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata/kinhec/rig");
    let rec = handeye::io::read_rig(&dir.join(format!("{stem}.jsonl"))).expect("reads");
    let truth: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join(format!("{stem}.truth.json"))).expect("a truth file"),
    )
    .expect("JSON");
    let mounts = truth["mounts"]
        .as_object()
        .expect("mounts")
        .iter()
        .map(|(n, m)| {
            (
                n.clone(),
                m.as_str().expect("a name").parse().expect("a mount"),
            )
        })
        .collect();
    (rec, mounts, truth)
}

fn matrix(v: &serde_json::Value) -> Transform {
    let m = nalgebra::Matrix4::from_fn(|r, c| v[r][c].as_f64().expect("a number"));
    handeye::transform_from_matrix4(&m).expect("a rigid transform")
}

#[test]
fn kinhec_rigs_lie_within_their_sigma_and_their_loops_close() {
    let mut within = 0;
    let mut parts = 0;
    for s in 0..3 {
        let (rec, mounts, truth) = kinhec_rig(&format!("three_cameras_s{s}"));
        let report = calibrate_rig(&rec, &mounts, &options()).expect("solves");
        for (name, t) in truth["parts"].as_object().expect("parts") {
            let Some(part) = report
                .rig
                .cameras
                .get(name)
                .or_else(|| report.rig.targets.get(name))
            else {
                panic!("s{s}: `{name}` not solved: {:?}", report.rig.undetermined);
            };
            assert_eq!(part.frame, t["frame"].as_str().expect("a frame"));
            let (r, d) = difference(&part.pose, &matrix(&t["matrix"]));
            parts += 1;
            let ok =
                r <= 3.0 * part.uncertainty.rotation_deg && d <= 3.0 * part.uncertainty.translation;
            within += usize::from(ok);
            eprintln!(
                "s{s} {name}: {r:.4}° ({:.4}°), {:.2} mm ({:.2} mm){}",
                part.uncertainty.rotation_deg,
                1e3 * d,
                1e3 * part.uncertainty.translation,
                if ok { "" } else { "  beyond 3 sigma" }
            );
        }
        for l in &report.rig.loops {
            eprintln!(
                "s{s} loop {} / {}: {:.3}° ({:.3}°) {:.2} mm ({:.2} mm), change {:.2} standard errors",
                l.compared[0],
                l.compared[1],
                l.rotation_deg,
                l.expected.rotation_deg,
                1e3 * l.translation,
                1e3 * l.expected.translation,
                l.change_sigmas
            );
        }
        assert!(
            !report.rig.loops.is_empty() && report.rig.loops.iter().all(|l| l.closes),
            "s{s}: {:?}",
            report.rig.loops
        );
    }
    eprintln!("{within} of {parts} parts within 3 sigma");
    assert!(within as f64 >= 0.95 * parts as f64, "{within} of {parts}");
}

#[test]
fn kinhec_moved_camera_is_named() {
    let (rec, mounts, truth) = kinhec_rig("moved_right_s0");
    assert_eq!(truth["moved"]["part"], "right");
    let report = calibrate_rig(&rec, &mounts, &options()).expect("solves");
    for l in &report.rig.loops {
        eprintln!(
            "loop {} / {}: {:.3}° ({:.3}°), change {:.2} standard errors at pose {}",
            l.compared[0],
            l.compared[1],
            l.rotation_deg,
            l.expected.rotation_deg,
            l.change_sigmas,
            l.change_at
        );
    }
    let misfit = report.warnings.iter().find_map(|w| match w {
        Warning::LoopMisfit {
            parts, singled_out, ..
        } => Some((parts.clone(), *singled_out)),
        _ => None,
    });
    assert_eq!(
        misfit,
        Some((vec!["right".to_string()], true)),
        "{:?}",
        report.rig.loops
    );
}
