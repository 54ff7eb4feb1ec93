//! ViSP's pose files as its hand-eye apps write them today (`<prefix>pose_rPe_<i>.yaml` and
//! `pose_cPo_<i>.yaml`) and as its older tutorials did (`pose_fPe_<i>.yaml`): a directory of them
//! calibrates as the same poses in JSON Lines do, for nominal, outlier-laden, degenerate,
//! inverted and millimetre data (kinhec's sets written in ViSP's format here; ViSP's own data are
//! GPL and not copied).

mod common;

use common::{run, testdata};
use serde_json::Value;
use std::path::Path;

/// A pose of kinhec's files (a 4×4 row-major matrix, or `translation` and `quaternion_xyzw`) as
/// ViSP's pose vector `tx ty tz θux θuy θuz`.
fn pose_vector(m: &Value) -> [f64; 6] {
    let number = |v: &Value| v.as_f64().expect("a number");
    let (t, (w, x, y, z)) = match m.get("quaternion_xyzw") {
        Some(q) => (
            [0, 1, 2].map(|k| number(&m["translation"][k])),
            (number(&q[3]), number(&q[0]), number(&q[1]), number(&q[2])),
        ),
        None => ([0, 1, 2].map(|k| number(&m[k][3])), quaternion(m)),
    };
    let (w, x, y, z) = if w < 0.0 {
        (-w, -x, -y, -z)
    } else {
        (w, x, y, z)
    };
    let v = (x * x + y * y + z * z).sqrt();
    let scale = if v > 1e-300 {
        2.0 * v.atan2(w) / v
    } else {
        2.0
    };
    [t[0], t[1], t[2], x * scale, y * scale, z * scale]
}

/// The quaternion (w, x, y, z) of a 4×4 matrix's rotation (Shepperd: the largest of w, x, y, z
/// first).
fn quaternion(m: &Value) -> (f64, f64, f64, f64) {
    let e = |r: usize, c: usize| m[r][c].as_f64().expect("a 4×4 matrix");
    let trace = e(0, 0) + e(1, 1) + e(2, 2);
    let candidates = [trace, e(0, 0), e(1, 1), e(2, 2)];
    let k = (0..4)
        .max_by(|&a, &b| candidates[a].total_cmp(&candidates[b]))
        .unwrap();
    match k {
        0 => {
            let s = 2.0 * (1.0 + trace).sqrt();
            (
                s / 4.0,
                (e(2, 1) - e(1, 2)) / s,
                (e(0, 2) - e(2, 0)) / s,
                (e(1, 0) - e(0, 1)) / s,
            )
        }
        1 => {
            let s = 2.0 * (1.0 + e(0, 0) - e(1, 1) - e(2, 2)).sqrt();
            (
                (e(2, 1) - e(1, 2)) / s,
                s / 4.0,
                (e(0, 1) + e(1, 0)) / s,
                (e(0, 2) + e(2, 0)) / s,
            )
        }
        2 => {
            let s = 2.0 * (1.0 + e(1, 1) - e(0, 0) - e(2, 2)).sqrt();
            (
                (e(0, 2) - e(2, 0)) / s,
                (e(0, 1) + e(1, 0)) / s,
                s / 4.0,
                (e(1, 2) + e(2, 1)) / s,
            )
        }
        _ => {
            let s = 2.0 * (1.0 + e(2, 2) - e(0, 0) - e(1, 1)).sqrt();
            (
                (e(1, 0) - e(0, 1)) / s,
                (e(0, 2) + e(2, 0)) / s,
                (e(1, 2) + e(2, 1)) / s,
                s / 4.0,
            )
        }
    }
}

/// vpPoseVector's YAML, as `saveYAML` writes it (full precision here, so that the two readings agree
/// to rounding).
fn visp_yaml(m: &Value) -> String {
    let values: String = pose_vector(m)
        .iter()
        .map(|v| format!("  - [{v:e}]\n"))
        .collect();
    format!("rows: 6\ncols: 1\ndata: \n{values}")
}

/// The poses of a JSON Lines file written as ViSP files into `dir`, under the given names.
fn write_visp(jsonl: &Path, dir: &Path, robot: &str, camera: &str) {
    std::fs::create_dir_all(dir).unwrap();
    let text = std::fs::read_to_string(jsonl).unwrap();
    for (i, line) in text.lines().filter(|l| !l.trim().is_empty()).enumerate() {
        let v: Value = serde_json::from_str(line).unwrap();
        std::fs::write(
            dir.join(format!("{robot}{}.yaml", i + 1)),
            visp_yaml(&v["base_from_gripper"]),
        )
        .unwrap();
        std::fs::write(
            dir.join(format!("{camera}{}.yaml", i + 1)),
            visp_yaml(&v["camera_from_target"]),
        )
        .unwrap();
    }
}

/// `calibrate` of `input` with `args`: the exit code, the JSON report (when it answers) and stderr.
fn calibrate(input: &Path, args: &[&str]) -> (i32, Option<Value>, String) {
    let mut all = vec!["calibrate", input.to_str().unwrap(), "--output", "json"];
    all.extend_from_slice(args);
    let (code, out, err) = run(&all);
    (code, serde_json::from_str(&out).ok(), err)
}

fn matrix(v: &Value) -> Vec<f64> {
    v["matrix"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|r| r.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()))
        .collect()
}

#[test]
fn visp_directories_calibrate_as_their_poses_do() {
    let tmp = tempfile::tempdir().unwrap();
    for (set, args, expect) in [
        ("pairs/nominal_stations_eih_s0", &[][..], 0),
        (
            "pairs/nominal_stations_eth_s1",
            &["--setup", "eye-to-hand"][..],
            0,
        ),
        ("pairs/outliers_random_pose_stations_eih_s0", &[][..], 0),
        (
            "pairs/degenerate_single_joint_continuous_eih_s0",
            &["--pairs", "all"][..],
            3,
        ),
        (
            "mistakes/robot_inverted__nominal_stations_eih_s0",
            &[][..],
            3,
        ),
        ("mistakes/robot_mm__nominal_stations_eih_s0", &[][..], 3),
    ] {
        let jsonl = testdata(&format!("kinhec/{set}.jsonl"));
        let (code, want, want_err) = calibrate(&jsonl, args);
        assert_eq!(code, expect, "{set} (JSON Lines): {want_err}");
        for (k, (robot, camera)) in [
            ("franka_pose_rPe_", "pose_cPo_"),
            ("pose_rPe_", "pose_cPo_"),
            ("pose_fPe_", "pose_cPo_"),
        ]
        .into_iter()
        .enumerate()
        {
            let dir = tmp.path().join(format!("{}-{k}", set.replace('/', "-")));
            write_visp(&jsonl, &dir, robot, camera);
            let (got_code, got, err) = calibrate(&dir, args);
            assert_eq!(got_code, code, "{set} as {robot}<i>.yaml: {err}");
            match (&want, &got) {
                (Some(want), Some(got)) => {
                    assert_eq!(want["verdict"], got["verdict"], "{set}");
                    assert_eq!(want["poses"], got["poses"], "{set}");
                    for (a, b) in matrix(want).iter().zip(matrix(got)) {
                        assert!((a - b).abs() < 1e-9, "{set} as {robot}<i>.yaml: {a} {b}");
                    }
                    let codes = |v: &Value| -> Vec<Value> {
                        v["warnings"]
                            .as_array()
                            .unwrap()
                            .iter()
                            .map(|w| w["code"].clone())
                            .collect()
                    };
                    assert_eq!(codes(want), codes(got), "{set}");
                }
                (None, None) => {
                    // The same refusal, in the same words up to the input's name.
                    let reason = |e: &str| {
                        e.lines()
                            .last()
                            .unwrap_or("")
                            .split(": ")
                            .nth(1)
                            .map(str::to_owned)
                    };
                    assert_eq!(reason(&want_err), reason(&err), "{set}: {err}");
                }
                _ => panic!("{set}: {want:?} / {got:?}"),
            }
        }
    }
}

#[test]
fn a_directory_of_two_namings_or_no_robot_poses_is_refused_naming_them() {
    let tmp = tempfile::tempdir().unwrap();
    let jsonl = testdata("kinhec/pairs/nominal_stations_eih_s0.jsonl");
    let dir = tmp.path().join("two");
    write_visp(&jsonl, &dir, "franka_pose_rPe_", "pose_cPo_");
    write_visp(&jsonl, &dir, "pose_fPe_", "pose_cPo_");
    let (code, _, err) = calibrate(&dir, &[]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("two ViSP namings") && err.contains("franka_pose_rPe_<i>.yaml"),
        "{err}"
    );
    let empty = tmp.path().join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let (code, _, err) = calibrate(&empty, &[]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("pose_rPe_<i>.yaml"), "{err}");
}
