//! All pairs of poses from the per-pose sums (O(n)) give the answers of going through the
//! n(n − 1)/2 motions: `AllPairs` (which the solvers recognise) against the same motions stored
//! in a `Vec` (which they go through one by one), on the kinhec suite, the camodocal recording and
//! simulated series, both setups, with and without noise.

mod shared_data;

use std::path::Path;

use handeye::check::quality::quality_report;
use handeye::io::{Format, read_pose_file};
use handeye::solve::{covariance_at, refine};
use handeye::{AllPairs, Method, Pairing, PosePair, Setup, Transform, motion_pairs, solve};

/// Relative difference of two transforms: rotation matrices apart (Frobenius), and translations
/// apart over the translation's length.
fn difference(a: &Transform, b: &Transform) -> (f64, f64) {
    let rotation = (a.rotation.matrix() - b.rotation.matrix()).norm();
    let t = b.translation.vector;
    let translation = (a.translation.vector - t).norm() / t.norm().max(1e-300);
    (rotation, translation)
}

/// Every kinhec pose file with its setup, the camodocal recording, and simulated series.
fn datasets() -> Vec<(String, Vec<PosePair>, Setup)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata");
    let mut out = Vec::new();
    let mut files: Vec<_> = std::fs::read_dir(root.join("kinhec/pairs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "jsonl"))
        .collect();
    files.sort();
    for path in files {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let setup = if name.contains("_eth") {
            Setup::EyeToHand
        } else {
            Setup::EyeInHand
        };
        out.push((
            name,
            read_pose_file(&path, Format::Auto).unwrap().pairs,
            setup,
        ));
    }
    if let Some(camodocal) = shared_data::shared("camodocal/TransformPairsInput.yml") {
        out.push((
            "camodocal".into(),
            read_pose_file(&camodocal, Format::Auto).unwrap().pairs,
            Setup::EyeInHand,
        ));
    }
    for (poses, seed) in [(30, 1), (120, 2)] {
        let config = handeye::sim::SimConfig {
            poses,
            ..Default::default()
        };
        for setup in [Setup::EyeInHand, Setup::EyeToHand] {
            let noisy = handeye::sim::simulate(&config, seed, 0).poses;
            let exact = handeye::sim::simulate(&config.noise_free(), seed, 0).poses;
            let flip = |p: &[PosePair]| -> Vec<PosePair> {
                match setup {
                    Setup::EyeInHand => p.to_vec(),
                    // The same hand poses read as gripper_from_base: a valid eye-to-hand series.
                    Setup::EyeToHand => p
                        .iter()
                        .map(|q| PosePair {
                            base_from_gripper: q.base_from_gripper.inverse(),
                            camera_from_target: q.camera_from_target,
                        })
                        .collect(),
                }
            };
            out.push((format!("sim {poses} noisy {setup:?}"), flip(&noisy), setup));
            out.push((
                format!("sim {poses} noise-free {setup:?}"),
                flip(&exact),
                setup,
            ));
        }
    }
    out
}

/// How far the O(n) answer may be from the motion-by-motion one (relative).
///
/// The linear solvers' answers agree to 1e-9 relative; on the kinhec suite's weakly conditioned
/// series (conditioning below 1e-2, which carry a `WeakConditioning` warning) rounding is amplified
/// by the inverse conditioning squared and they agree to 7e-9 (measured). `refine` stops on a
/// relative cost drop of 1e-15, which fixes X only to about √1e-15 in its weakest direction: the
/// motion-by-motion refine itself moves by up to 2.1e-7 when the same motions are given in reverse
/// order (measured on this suite: degenerate_parallel_axes_continuous_eih_s1, conditioning 5.6e-3),
/// and the O(n) refine must land within twice that spread ([`refine_limit`]).
fn tolerance(method: Method, conditioning: f64) -> f64 {
    match method {
        Method::Refine => 2e-7,
        _ if conditioning < handeye::solve::WARN_CONDITIONING => 1e-8,
        _ => 1e-9,
    }
}

/// The bound for the O(n) refine: [`tolerance`], or twice the motion-by-motion refine's own
/// movement when its motions are reversed, whichever is larger (the stopping rule's spread).
fn refine_limit(stored: &[handeye::MotionPair], x: &Transform, conditioning: f64) -> f64 {
    let mut reversed = stored.to_vec();
    reversed.reverse();
    let spread = solve(Method::Refine, &reversed).map_or(0.0, |r| {
        let (r, t) = difference(&r.x, x);
        r.max(t)
    });
    tolerance(Method::Refine, conditioning).max(2.0 * spread)
}

#[test]
fn every_method_gives_the_motion_by_motion_answer() {
    let mut compared = 0;
    for (name, poses, setup) in datasets() {
        let sums = AllPairs::new(&poses, setup);
        let stored = motion_pairs(&poses, Pairing::All, setup);
        for method in [
            Method::Andreff,
            Method::AndreffJoint,
            Method::Daniilidis,
            Method::Refine,
            Method::Tsai,
            Method::Park,
        ] {
            let (a, b) = (solve(method, &sums), solve(method, &stored));
            match (&a, &b) {
                (Ok(a), Ok(b)) => {
                    let (r, t) = difference(&a.x, &b.x);
                    let limit = match method {
                        Method::Refine => refine_limit(&stored, &b.x, b.conditioning),
                        _ => tolerance(method, b.conditioning),
                    };
                    assert!(
                        r < limit && t < limit,
                        "{name} {method}: X differs by {r:e} (rotation), {t:e} (translation)"
                    );
                    assert_eq!(a.warnings.len(), b.warnings.len(), "{name} {method}");
                    let c = (a.conditioning - b.conditioning).abs() / b.conditioning;
                    assert!(c < 1e-9, "{name} {method}: conditioning {c:e} apart");
                    compared += 1;
                }
                (Err(a), Err(b)) => assert_eq!(
                    std::mem::discriminant(a),
                    std::mem::discriminant(b),
                    "{name} {method}"
                ),
                _ => panic!("{name} {method}: {a:?} against {b:?}"),
            }
        }
    }
    assert!(compared > 200, "only {compared} solves compared");
}

#[test]
fn refine_reports_the_same_costs_scales_and_covariance() {
    for (name, poses, setup) in datasets() {
        let sums = AllPairs::new(&poses, setup);
        let stored = motion_pairs(&poses, Pairing::All, setup);
        let (Ok(a), Ok(b)) = (refine(&sums), refine(&stored)) else {
            continue;
        };
        let relative = |x: f64, y: f64| (x - y).abs() / x.abs().max(y.abs()).max(1e-300);
        // Noise-free data leave residuals at rounding level, where the sums (differences of
        // large terms) no longer resolve them: only X is compared there.
        if b.scales[0] > 1e-9 && b.scales[1] > 1e-9 {
            assert!(
                relative(a.scales[0], b.scales[0]) < 1e-6,
                "{name}: {:?} {:?}",
                a.scales,
                b.scales
            );
            assert!(
                relative(a.scales[1], b.scales[1]) < 1e-6,
                "{name}: {:?} {:?}",
                a.scales,
                b.scales
            );
            assert!(relative(a.initial_cost, b.initial_cost) < 1e-6, "{name}");
            assert!(relative(a.final_cost, b.final_cost) < 1e-6, "{name}");
            let (ca, cb) = (a.covariance.unwrap(), b.covariance.unwrap());
            for k in 0..6 {
                assert!(
                    relative(ca[(k, k)], cb[(k, k)]) < 1e-6,
                    "{name}: covariance {k}"
                );
            }
            let at = covariance_at(&sums, &b.calibration.x).unwrap();
            assert!(
                relative(at[(0, 0)], cb[(0, 0)]) < 1e-6,
                "{name}: covariance_at"
            );
        }
        let (r, t) = difference(&a.calibration.x, &b.calibration.x);
        let limit = refine_limit(&stored, &b.calibration.x, b.calibration.conditioning);
        assert!(r < limit && t < limit, "{name}: {r:e} {t:e}");
    }
}

#[test]
fn the_quality_report_has_the_same_verdicts_and_values() {
    for (name, poses, setup) in datasets() {
        let sums = AllPairs::new(&poses, setup);
        let stored = motion_pairs(&poses, Pairing::All, setup);
        let Ok(c) = solve(Method::Andreff, &stored) else {
            continue;
        };
        // A limit of 0 keeps no per-motion entries: the per-pose path for `AllPairs`.
        let a = quality_report(&sums, &c.x, 0);
        let b = quality_report(&stored, &c.x, 0);
        assert_eq!(a.warnings, b.warnings, "{name}");
        // Residuals of noise-free data are rounding noise: below 1e-12 of X's length (or 1e-10°)
        // both are zero to the data's precision.
        let floor = 1e-12 * c.x.translation.vector.norm();
        let close = |x: f64, y: f64, what: &str, tolerance: f64| {
            assert!(
                (x - y).abs() <= tolerance * y.abs() || x.max(y) < floor.max(1e-10),
                "{name} {what}: {x:e} vs {y:e}"
            )
        };
        close(
            a.residual.translation_rms,
            b.residual.translation_rms,
            "translation RMS",
            1e-6,
        );
        close(
            a.residual.translation_max,
            b.residual.translation_max,
            "translation max",
            1e-6,
        );
        close(
            a.residual.rotation_deg_max,
            b.residual.rotation_deg_max,
            "rotation max",
            1e-6,
        );
        // The RMS angle from the chordal residuals: below the exact one, within 1 + θ_max²/48.
        let bound = 1.0 + (b.residual.rotation_deg_max.to_radians().powi(2)) / 40.0;
        assert!(
            b.residual.rotation_deg_rms < 1e-10
                || a.residual.rotation_deg_rms <= b.residual.rotation_deg_rms * (1.0 + 1e-9)
                    && a.residual.rotation_deg_rms * bound >= b.residual.rotation_deg_rms,
            "{name}: rotation RMS {} vs {}",
            a.residual.rotation_deg_rms,
            b.residual.rotation_deg_rms
        );
        close(a.axis_spread_deg, b.axis_spread_deg, "axis spread", 1e-6);
        close(
            a.rotation_range_deg[0],
            b.rotation_range_deg[0],
            "smallest angle",
            1e-6,
        );
        close(
            a.rotation_range_deg[1],
            b.rotation_range_deg[1],
            "largest angle",
            1e-6,
        );
    }
}
