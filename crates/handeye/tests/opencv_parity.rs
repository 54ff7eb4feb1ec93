//! Parity with OpenCV 4.14's `calibrateHandEye` on testdata/opencv (see testdata/FIXTURES.md):
//! with all pose pairs, each shared method gives OpenCV's answer; on noisy sets our `andreff` and
//! `refine` are compared with OpenCV's methods against the true transform.

use std::path::{Path, PathBuf};

use handeye::io::{Format, read_pose_file, transform_from_json};
use handeye::metrics::errors_against_truth;
use handeye::solve::{TsaiOptions, tsai_with};
use handeye::{Method, Pairing, Setup, Transform, motion_pairs, solve};
use serde_json::Value;

struct Fixture {
    name: String,
    motions: Vec<handeye::MotionPair>,
    expected: Value,
    truth: Transform,
}

fn fixtures() -> Vec<Fixture> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata/opencv");
    let mut names: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "jsonl"))
        .collect();
    names.sort();
    assert_eq!(names.len(), 4);
    names
        .into_iter()
        .map(|path| {
            let expected: Value = serde_json::from_str(
                &std::fs::read_to_string(path.with_extension("expected.json")).unwrap(),
            )
            .unwrap();
            let setup = if expected["setup"] == "eye-to-hand" {
                Setup::EyeToHand
            } else {
                Setup::EyeInHand
            };
            let poses = read_pose_file(&path, Format::Auto).unwrap().pairs;
            Fixture {
                name: path.file_stem().unwrap().to_string_lossy().into_owned(),
                motions: motion_pairs(&poses, Pairing::All, setup),
                truth: transform_from_json(&expected["truth"]).unwrap(),
                expected,
            }
        })
        .collect()
}

fn opencv(f: &Fixture, method: &str) -> Transform {
    transform_from_json(&f.expected["opencv"][method]).unwrap()
}

fn max_difference(a: &Transform, b: &Transform) -> f64 {
    (a.to_homogeneous() - b.to_homogeneous()).abs().max()
}

#[test]
fn shared_methods_give_opencvs_answer() {
    for f in fixtures() {
        let mut methods = vec![
            Method::Park,
            Method::Horaud,
            Method::AndreffJoint,
            Method::Daniilidis,
        ];
        if f.expected["tsai_filter_dropped_motions"] == 0 {
            methods.push(Method::Tsai);
        }
        for method in methods {
            let ours = solve(method, &f.motions).unwrap().x;
            let d = max_difference(&ours, &opencv(&f, method.name()));
            println!("{} {method}: {d:.2e}", f.name);
            assert!(
                d <= 1e-6,
                "{} {method}: differs from OpenCV by {d:e}",
                f.name
            );
        }
    }
}

#[test]
fn tsai_with_opencvs_motion_filter_gives_opencvs_answer() {
    for f in fixtures() {
        let ours = tsai_with(
            &f.motions,
            &TsaiOptions {
                opencv_filter: true,
            },
        );
        let d = ours.map(|c| max_difference(&c.x, &opencv(&f, "tsai")));
        println!("{} tsai (filtered): {d:?}", f.name);
        assert!(d.as_ref().is_ok_and(|d| *d <= 1e-6), "{}: {d:?}", f.name);
    }
}

#[test]
fn andreff_and_refine_are_as_accurate_as_opencv() {
    for f in fixtures().into_iter().filter(|f| f.name.contains("noisy")) {
        let score = |x: &Transform| {
            let e = errors_against_truth(x, &f.truth);
            (e.rot_deg, e.trans_rel)
        };
        let best = ["tsai", "park", "horaud", "andreff-joint", "daniilidis"]
            .iter()
            .map(|m| score(&opencv(&f, m)))
            .fold((f64::INFINITY, f64::INFINITY), |a, b| {
                (a.0.min(b.0), a.1.min(b.1))
            });
        for method in [Method::Andreff, Method::Refine] {
            let ours = score(&solve(method, &f.motions).unwrap().x);
            println!(
                "{} {method}: rotation {:.4}° (best OpenCV {:.4}°), translation {:.4} (best OpenCV {:.4})",
                f.name, ours.0, best.0, ours.1, best.1
            );
            // The best OpenCV error on each measure (often of different methods) is printed for
            // the record; on one noise draw it is not always reached (andreff-joint takes rotation
            // information from the translation rows). What must hold: no worse than 5% above the
            // median OpenCV method on either error.
            let median = |k: usize| {
                let mut v: Vec<f64> = ["tsai", "park", "horaud", "andreff-joint", "daniilidis"]
                    .iter()
                    .map(|m| {
                        let s = score(&opencv(&f, m));
                        if k == 0 { s.0 } else { s.1 }
                    })
                    .collect();
                v.sort_by(f64::total_cmp);
                v[2]
            };
            assert!(
                ours.0 <= 1.05 * median(0) && ours.1 <= 1.05 * median(1),
                "{} {method}: {ours:?} vs median OpenCV ({}, {})",
                f.name,
                median(0),
                median(1)
            );
        }
    }
}
