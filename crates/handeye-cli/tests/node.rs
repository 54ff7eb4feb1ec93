//! `handeye node` against an independent DDS (issue 55): a peer written on Eclipse Cyclone DDS
//! (`tests/node_peer.py`, PyPI `cyclonedds`, with ROS 2's type names, topics and QoS) publishes a
//! simulated eye-in-hand stream on rt/tf, rt/tf_static and rt/board_pose, and bad messages; the
//! node calibrates, publishes X on rt/tf_static (the peer subscribes late: transient local) and
//! its lines on rt/handeye/status. Loopback only.
//!
//! The peer needs a Python with `cyclonedds`, `rosbags` and `numpy`: `$HANDEYE_ROS2_PYTHON`, else
//! `/tmp/venv55/bin/python`. Without one the test says so and passes, unless
//! `HANDEYE_ROS2_REQUIRED` is set (CI sets it, and makes the environment).
#![cfg(feature = "ros2")]

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use serde_json::Value;

/// The Python of the peer, or why there is none.
fn peer_python() -> Result<PathBuf, String> {
    let python = std::env::var_os("HANDEYE_ROS2_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/tmp/venv55/bin/python"));
    if !python.exists() {
        return Err(format!("no Python at {}", python.display()));
    }
    let ok = Command::new(&python)
        .args(["-c", "import cyclonedds, rosbags, numpy"])
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if ok {
        Ok(python)
    } else {
        Err(format!(
            "{} lacks cyclonedds, rosbags or numpy",
            python.display()
        ))
    }
}

fn skip_or_fail(why: &str) -> bool {
    if std::env::var_os("HANDEYE_ROS2_REQUIRED").is_some() {
        panic!("HANDEYE_ROS2_REQUIRED is set and the ROS 2 peer cannot run: {why}");
    }
    println!(
        "skipped: {why} (python3 -m venv /tmp/venv55 && /tmp/venv55/bin/pip install cyclonedds rosbags)"
    );
    true
}

fn quaternion(v: &Value) -> UnitQuaternion<f64> {
    let q: Vec<f64> = serde_json::from_value(v.clone()).unwrap();
    UnitQuaternion::from_quaternion(Quaternion::new(q[3], q[0], q[1], q[2]))
}

fn translation(v: &Value) -> Vector3<f64> {
    let t: Vec<f64> = serde_json::from_value(v.clone()).unwrap();
    Vector3::new(t[0], t[1], t[2])
}

/// Sends SIGTERM to the node (a clean stop, as `kill` or systemd stops it).
fn terminate(pid: u32) {
    let status = Command::new("kill")
        .args(["-TERM", &pid.to_string()])
        .status()
        .expect("kill runs");
    assert!(status.success());
}

#[test]
fn node_calibrates_a_cyclone_dds_stream_and_publishes_x_on_tf_static() {
    let python = match peer_python() {
        Ok(p) => p,
        Err(why) => {
            skip_or_fail(&why);
            return;
        }
    };
    let dir = tempfile::tempdir().unwrap();
    let record = dir.path().join("pairs.jsonl");
    // A domain of its own, so that parallel runs on one machine do not meet.
    let domain = (std::process::id() % 200 + 10).to_string();
    let stations = 60;
    let mut node = Command::new(env!("CARGO_BIN_EXE_handeye"))
        .args([
            "node",
            "--base-frame",
            "base_link",
            "--gripper-frame",
            "tool0",
            "--camera-frame",
            "camera_optical_frame",
            "--target-frame",
            "board",
            "--target-topic",
            "/board_pose",
            "--every",
            "10",
            "--duration",
            "120",
            "--record",
        ])
        .arg(&record)
        .env("ROS_DOMAIN_ID", &domain)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let peer = Command::new(&python)
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/node_peer.py"))
        .args(["--stations", &stations.to_string(), "--seed", "7"])
        .env("ROS_DOMAIN_ID", &domain)
        .output()
        .unwrap();
    let started = Instant::now();
    terminate(node.id());
    let node_out = loop {
        if let Some(_status) = node.try_wait().unwrap() {
            break node.wait_with_output().unwrap();
        }
        assert!(
            started.elapsed() < Duration::from_secs(20),
            "the node did not stop within 20 s of SIGTERM"
        );
        std::thread::sleep(Duration::from_millis(50));
    };
    let node_err = String::from_utf8_lossy(&node_out.stderr);
    let peer_err = String::from_utf8_lossy(&peer.stderr);
    assert!(
        peer.status.success(),
        "peer failed: {peer_err}\n{}\nnode: {node_err}",
        String::from_utf8_lossy(&peer.stdout)
    );
    assert!(
        node_out.status.success(),
        "node exit {:?}: {node_err}",
        node_out.status
    );
    let out: Value = serde_json::from_slice(&peer.stdout).unwrap_or_else(|e| {
        panic!(
            "peer output: {e}: {}",
            String::from_utf8_lossy(&peer.stdout)
        )
    });

    // The peer's CDR is rosbags' byte for byte (so the node read ROS 2's layouts).
    for kind in ["tf", "pose", "string"] {
        assert_eq!(
            out["cdr_identical_to_rosbags"][kind],
            Value::Bool(true),
            "{kind}"
        );
    }

    // Every status line is a JSON object; the reports are `online`'s lines.
    let lines: Vec<Value> = out["status"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| serde_json::from_str(l.as_str().unwrap()).expect("a status line parses"))
        .collect();
    let reports: Vec<&Value> = lines
        .iter()
        .filter(|l| l.get("estimate").is_some())
        .collect();
    assert!(reports.len() >= 3, "reports: {}", reports.len());
    for r in &reports {
        for field in [
            "verdict",
            "uncertainty",
            "translation",
            "quaternion_xyzw",
            "poses",
        ] {
            assert!(r.get(field).is_some(), "{field} missing in {r}");
        }
    }
    // The bad messages: one status line each, and the node carried on.
    let skipped: Vec<&Value> = lines.iter().filter_map(|l| l.get("skipped")).collect();
    let dropped: Vec<&Value> = lines.iter().filter_map(|l| l.get("dropped")).collect();
    assert_eq!(skipped.len(), 2, "skipped: {skipped:?}");
    assert!(
        skipped
            .iter()
            .any(|s| s["topic"] == "/board_pose" && s["why"].as_str().unwrap().contains("finite")),
        "{skipped:?}"
    );
    assert!(
        skipped
            .iter()
            .any(|s| s["topic"] == "/tf" && s["why"].as_str().unwrap().contains("norm")),
        "{skipped:?}"
    );
    assert_eq!(dropped.len(), 1, "dropped: {dropped:?}");
    assert!(
        dropped[0]["why"]
            .as_str()
            .unwrap()
            .contains("nowhere_frame")
    );

    // X on /tf_static, received by a late subscriber, for camera_link (the root of the camera's
    // subtree: the optical frame's parent), within 3 sigma of the truth by the last good report.
    let published: Vec<&Value> = out["tf_static"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|t| t["child"] == "camera_link")
        .collect();
    assert_eq!(published.len(), 1, "{}", out["tf_static"]);
    let x = published[0];
    assert_eq!(x["parent"], "tool0");
    let good = reports
        .iter()
        .rev()
        .find(|r| r["verdict"] == "good")
        .expect("a good report");
    let sigma_r = good["uncertainty"]["rotation_deg"].as_f64().unwrap();
    let sigma_t = good["uncertainty"]["translation"].as_f64().unwrap();
    let truth = &out["truth"];
    let dr = (quaternion(&x["quaternion_xyzw"]).inverse() * quaternion(&truth["quaternion_xyzw"]))
        .angle()
        .to_degrees();
    let dt = (translation(&x["translation"]) - translation(&truth["translation"])).norm();
    println!(
        "X off by {dr:.4}° (sigma {sigma_r:.4}°) and {:.3} mm (sigma {:.3} mm), {} poses",
        dt * 1e3,
        sigma_t * 1e3,
        good["poses"]
    );
    assert!(sigma_r > 0.0 && sigma_r < 0.2, "sigma {sigma_r}°");
    assert!(sigma_t > 0.0 && sigma_t < 2e-3, "sigma {sigma_t} m");
    assert!(dr < 3.0 * sigma_r, "{dr}° vs 3 sigma {}", 3.0 * sigma_r);
    // Translation: 3 sigma of the norm of a 3-vector's error (sigma is the root of the trace).
    assert!(dt < 3.0 * sigma_t, "{dt} m vs 3 sigma {}", 3.0 * sigma_t);

    // The record holds every pair taken, as `calibrate` reads it, and the node's stdout the same
    // lines as the topic.
    let recorded = std::fs::read_to_string(&record).unwrap();
    assert_eq!(recorded.lines().count(), stations, "{recorded}");
    let calibrate = Command::new(env!("CARGO_BIN_EXE_handeye"))
        .args(["calibrate", "--output", "json"])
        .arg(&record)
        .output()
        .unwrap();
    assert!(
        calibrate.status.success(),
        "{}",
        String::from_utf8_lossy(&calibrate.stderr)
    );
    let stdout_lines = String::from_utf8_lossy(&node_out.stdout);
    for l in stdout_lines.lines() {
        let _: Value = serde_json::from_str(l).expect("a stdout line parses");
    }
    assert!(
        stdout_lines.lines().count() >= lines.len(),
        "stdout has every status line"
    );
}
