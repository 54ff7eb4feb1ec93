//! Checks the reported one-sigma uncertainty of X against the actual error on simulated series:
//! the median of actual error / reported one-sigma (calibrated: near 1; required 0.33 … 3) and the
//! share of results within 3 sigma (required ≥ 85%), per pairing and method.
//!
//! `cargo run --release -p handeye --example uncertainty_check [consecutive|all]`

use handeye::errors_against_truth;
use handeye::sim::{SimConfig, simulate};
use handeye::{Method, Pairing, Problem, Setup};
use handeye::{Options, calibrate};

fn main() -> Result<(), handeye::Error> {
    let pairing_of = |p: &str| match p {
        "consecutive" => Pairing::Consecutive,
        _ => Pairing::All,
    };
    let pairings: Vec<Pairing> = match std::env::args().nth(1) {
        Some(p) => vec![pairing_of(&p)],
        None => vec![Pairing::Consecutive, Pairing::All],
    };
    for pairing in pairings {
        for method in Method::ALL {
            let (mut rot, mut trans) = (Vec::new(), Vec::new());
            for s in 0..40 {
                let sim = simulate(&SimConfig::default(), 5, s);
                let options = Options {
                    problem: Problem::HandEye(method),
                    pairing,
                    ..Options::default()
                };
                let r = calibrate(&sim.poses, Setup::EyeInHand, &options)
                    .map(|r| r.into_hand_eye().expect("the hand–eye report"))?;
                let truth = sim.gripper_from_camera;
                let e = errors_against_truth(&r.transform, &truth);
                let t_err = e.trans_rel * truth.translation.vector.norm();
                rot.push(e.rot_deg / r.uncertainty.rotation_deg);
                trans.push(t_err / r.uncertainty.translation);
            }
            println!(
                "{pairing:?} {method}: rotation median {:.2}, within 3σ {:.0}%; translation median {:.2}, within 3σ {:.0}%",
                median(&rot),
                within(&rot),
                median(&trans),
                within(&trans)
            );
        }
    }
    Ok(())
}

fn median(v: &[f64]) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn within(v: &[f64]) -> f64 {
    100.0 * v.iter().filter(|r| **r <= 3.0).count() as f64 / v.len() as f64
}
