//! The accumulating estimator on the paper's protocol: final error against batch solvers and the
//! paper's adaptive method.
//!
//! `cargo run --release -p handeye --example accumulate_check`

use handeye::AdaptiveParams;
use handeye::errors_against_truth;
use handeye::sim::{SimConfig, simulate};
use handeye::{ErrorSource, Estimator, OnlineCalibrator, OnlineConfig};
use handeye::{Method, Pairing, Setup, motion_pairs, solve};

fn main() -> Result<(), handeye::Error> {
    let series = 20;
    let mut rows = [(0.0, 0.0); 4];
    let mut changes = 0;
    for s in 0..series {
        let sim = simulate(&SimConfig::default(), 1, s);
        let config = OnlineConfig {
            params: AdaptiveParams {
                d_max: 100.0,
                ..AdaptiveParams::default()
            },
            estimator: Estimator::Accumulate,
            error_source: ErrorSource::Truth,
            truth: Some(sim.gripper_from_camera),
            ..OnlineConfig::default()
        };
        let mut calibrator = OnlineCalibrator::new(config)?;
        // The paper's adaptive calibrator runs apart: its selection does not run beside the
        // accumulating estimator.
        let mut adaptive = OnlineCalibrator::new(OnlineConfig {
            estimator: Estimator::Paper,
            ..config
        })?;
        let mut paper = (0.0_f64, 0.0_f64, 0.0_f64);
        for p in &sim.poses {
            let pushed = calibrator.push(p)?;
            for e in adaptive.push(p)?.events {
                let err = errors_against_truth(&e.x, &sim.gripper_from_camera);
                paper = (
                    paper.0 + err.rot_fro,
                    paper.1 + err.trans_rel,
                    paper.2 + 1.0,
                );
            }
            changes += usize::from(pushed.change.is_some());
        }
        let truth = sim.gripper_from_camera;
        let mut add = |k: usize, x: &handeye::Transform| {
            let e = errors_against_truth(x, &truth);
            rows[k].0 += e.rot_fro / series as f64;
            rows[k].1 += e.trans_rel / series as f64;
        };
        add(0, &calibrator.accumulated().expect("estimate").x);
        add(
            1,
            &solve(
                Method::Andreff,
                &motion_pairs(&sim.poses, Pairing::All, Setup::EyeInHand),
            )?
            .x,
        );
        add(
            2,
            &solve(
                Method::Andreff,
                &motion_pairs(&sim.poses, Pairing::Consecutive, Setup::EyeInHand),
            )?
            .x,
        );
        rows[3].0 += paper.0 / paper.2.max(1.0) / series as f64;
        rows[3].1 += paper.1 / paper.2.max(1.0) / series as f64;
    }
    for (name, r) in [
        "accumulate (final)",
        "batch andreff, all pairs",
        "batch andreff, consecutive",
        "paper adaptive (mean per event)",
    ]
    .iter()
    .zip(rows)
    {
        println!("{name:32} ‖ΔR‖_F {:.5}  t_rel {:.4}", r.0, r.1);
    }
    println!("false alarms: {changes} in {} poses", series * 200);
    Ok(())
}
