//! From images to X (issue 54): ViSP's own recordings of images (`visp-hand-eye` in the shared
//! folder: a 9×6 chessboard of 23.6 mm squares eye-in-hand, one 48 mm AprilTag 36h11
//! eye-to-hand, 8 images each) through `handeye detect` and `handeye calibrate --target`.
//!
//! - The corners found are OpenCV's (the converted peers' `poses.jsonl`, made by
//!   `testdata/peers/make_peers.py` from the same images), point for point in the same order:
//!   within half a pixel in the median and one pixel at most.
//! - X from the images is within one of its sigmas of ViSP's published eMc / rMc. It is printed
//!   beside the pose path's X on OpenCV's detections, which is nearer (measured: eye-in-hand
//!   0.049° and 0.09 mm against 0.028° and 0.06 mm; eye-to-hand 1.17° and 0.63 mm against 0.28°
//!   and 0.45 mm: the tag's pose of the smaller pixel error is not always the one the robot's
//!   motion agrees with); that is not asserted, being not yet so.
//! - An image without the board, a board spec of another size and a file that is not an image
//!   each cost one line on stderr, not the run; a bad spec is refused in one line.
//!
//! A set that is not in the shared folder is skipped, said on one line
//! (`HANDEYE_SHARED_REQUIRED=1` makes it a failure).

mod common;

use std::path::{Path, PathBuf};

use common::shared_data::shared_each;
use common::{apart, matrix, run};
use serde_json::Value;

/// The two recordings: (the images' folder, the converted peer set, the setup, the target).
const SETS: [(&str, &str, &str, &str); 2] = [
    (
        "visp-hand-eye/data-eye-in-hand",
        "peers/visp_eye_in_hand",
        "eye-in-hand",
        "chessboard:9x6:0.0236",
    ),
    (
        "visp-hand-eye/data-eye-to-hand",
        "peers/visp_eye_to_hand",
        "eye-to-hand",
        "apriltag36h11:0.048",
    ),
];

/// The sets in the shared folder: (images, peer, setup, target).
fn sets() -> Vec<(PathBuf, PathBuf, &'static str, &'static str)> {
    SETS.iter()
        .filter_map(|(images, peer, setup, target)| {
            let found = shared_each(&[images, peer]);
            Some((found[0].clone()?, found[1].clone()?, *setup, *target))
        })
        .collect()
}

fn records(text: &str) -> Vec<Value> {
    text.lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

fn points(v: &Value) -> Vec<Vec<f64>> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|p| {
            p.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        })
        .collect()
}

fn median_max(mut d: Vec<f64>) -> (f64, f64) {
    d.sort_by(f64::total_cmp);
    (d[d.len() / 2], d[d.len() - 1])
}

#[test]
fn corners_found_are_opencvs() {
    for (images, peer, _, target) in sets() {
        let (code, out, err) = run(&["detect", images.to_str().unwrap(), "--target", target]);
        assert_eq!(code, 0, "{target}: {err}");
        let ours = records(&out);
        let theirs = records(&std::fs::read_to_string(peer.join("poses.jsonl")).unwrap());
        assert_eq!(ours.len(), theirs.len(), "{target}: {err}");
        let mut gaps = Vec::new();
        for (i, (a, b)) in ours.iter().zip(&theirs).enumerate() {
            let (qa, qb) = (
                matrix(&a["base_from_gripper"]),
                matrix(&b["base_from_gripper"]),
            );
            assert!(
                (qa - qb).abs().max() < 1e-6,
                "{target} image {}: robot pose",
                i + 1
            );
            let (ta, tb) = (
                points(&a["detections"]["target"]),
                points(&b["detections"]["target"]),
            );
            assert_eq!(ta.len(), tb.len(), "{target} image {}", i + 1);
            for (p, q) in ta.iter().zip(&tb) {
                assert!(
                    (0..3).all(|k| (p[k] - q[k]).abs() < 1e-9),
                    "{target} image {}: {p:?} {q:?}",
                    i + 1
                );
            }
            let (pa, pb) = (
                points(&a["detections"]["pixels"]),
                points(&b["detections"]["pixels"]),
            );
            gaps.extend(
                pa.iter()
                    .zip(&pb)
                    .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1])),
            );
        }
        let (median, max) = median_max(gaps);
        eprintln!(
            "{target}: corners {median:.3} px from OpenCV's in the median, {max:.3} px at most"
        );
        assert!(
            median < 0.5 && max < 1.0,
            "{target}: {median} px median, {max} px max"
        );
        assert!(
            err.contains(&format!("8 of 8 image(s) with the target ({target})")),
            "{err}"
        );
    }
}

fn calibrate(args: &[&str]) -> Value {
    let mut all = vec!["calibrate"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--output", "json"]);
    let (code, out, err) = run(&all);
    assert_eq!(code, 0, "{all:?}: {err}");
    serde_json::from_str(&out).unwrap()
}

#[test]
fn x_from_images_is_within_a_sigma_of_visps() {
    for (images, peer, setup, target) in sets() {
        let published: Value =
            serde_json::from_str(&std::fs::read_to_string(peer.join("peer.json")).unwrap())
                .unwrap();
        let visp = matrix(&published["x"]);
        let camera = images.join("franka_camera.xml");
        let ours = calibrate(&[
            images.to_str().unwrap(),
            "--target",
            target,
            "--intrinsics",
            camera.to_str().unwrap(),
            "--setup",
            setup,
        ]);
        let poses = peer.join("poses.jsonl");
        let opencv = calibrate(&[poses.to_str().unwrap(), "--setup", setup]);
        let (deg, dist) = apart(&matrix(&ours["matrix"]), &visp);
        let (cv_deg, cv_dist) = apart(&matrix(&opencv["matrix"]), &visp);
        let sigma = &ours["uncertainty"];
        let (r, t) = (
            deg / sigma["rotation_deg"].as_f64().unwrap(),
            dist / sigma["translation"].as_f64().unwrap(),
        );
        eprintln!(
            "{setup}: X from the images is {deg:.3}° and {:.2} mm from ViSP's ({r:.2}, {t:.2} sigma); on OpenCV's detections {cv_deg:.3}° and {:.2} mm",
            dist * 1e3,
            cv_dist * 1e3
        );
        assert!(
            r < 1.0 && t < 1.0,
            "{setup}: {r:.3}, {t:.3} sigma from ViSP's X"
        );
    }
}

/// A ViSP folder in `dir` of the given images (each with the first robot pose of `from`).
fn folder(dir: &Path, from: &Path, images: &[(&str, &[u8])]) {
    let pose = std::fs::read(from.join("franka_pose_rPe_1.yaml")).unwrap();
    for (i, (name, bytes)) in images.iter().enumerate() {
        std::fs::write(dir.join(format!("{name}_image-{}.png", i + 1)), bytes).unwrap();
        std::fs::write(dir.join(format!("{name}_pose_rPe_{}.yaml", i + 1)), &pose).unwrap();
    }
}

#[test]
fn a_bad_image_costs_its_line() {
    let [Some(board), Some(tag)] = &shared_each(&[SETS[0].0, SETS[1].0])[..] else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let board_png = std::fs::read(board.join("franka_image-1.png")).unwrap();
    let tag_png = std::fs::read(tag.join("franka_image-1.png")).unwrap();
    folder(
        tmp.path(),
        board,
        &[("a", &board_png), ("a", &tag_png), ("a", b"not an image\n")],
    );
    let dir = tmp.path().to_str().unwrap();
    let (code, out, err) = run(&["detect", dir, "--target", "chessboard:9x6:0.0236"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(records(&out).len(), 1, "{err}");
    let line = |n: usize| {
        err.lines()
            .find(|l| l.contains(&format!("a_image-{n}.png")))
            .unwrap_or_else(|| panic!("no line on image {n}: {err}"))
            .to_owned()
    };
    assert!(
        line(1).ends_with("54 points of chessboard:9x6:0.0236"),
        "{err}"
    );
    assert!(line(2).contains("no chessboard found"), "{err}");
    assert!(line(3).contains("not a readable image"), "{err}");
    assert!(err.contains("1 of 3 image(s) with the target"), "{err}");
    // A spec of another size: each image says what it found; none left, the run is refused.
    let (code, out, err) = run(&["detect", dir, "--target", "chessboard:7x6:0.0236"]);
    assert_eq!(code, 2, "{err}");
    assert!(out.is_empty());
    assert!(
        line_of(&err, "a_image-1.png")
            .contains("54 corners found in a 9x6 grid, the target has 7x6"),
        "{err}"
    );
    assert!(err.contains("no image of"), "{err}");
    // A spec that cannot be right: refused before any image is read.
    let (code, _, err) = run(&["detect", dir, "--target", "chessboard:8x6:0.0236"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("half a turn") && !err.contains("a_image-1"),
        "{err}"
    );
}

fn line_of(text: &str, word: &str) -> String {
    text.lines()
        .find(|l| l.contains(word))
        .unwrap_or_default()
        .to_owned()
}
