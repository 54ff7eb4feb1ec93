//! Checks the reported one-sigma uncertainty of X against the actual error on simulated series.
//!
//! `cargo run --release -p handeye --example uncertainty_check`

use handeye::metrics::{errors_against_truth, quality_report};
use handeye::sim::{SimConfig, simulate};
use handeye::{Method, Pairing, Setup, motion_pairs, solve};

fn main() -> Result<(), handeye::Error> {
    let (mut rot_z, mut trans_z, mut n) = (0.0, 0.0, 0.0);
    for s in 0..50 {
        let sim = simulate(&SimConfig::default(), 5, s);
        let motions = motion_pairs(&sim.poses, Pairing::Consecutive, Setup::EyeInHand);
        let c = solve(Method::Refine, &motions)?;
        let e = errors_against_truth(&c.x, &sim.gripper_from_camera);
        let q = quality_report(&motions, &c.x, 0, handeye::metrics::OUTLIER_DEG);
        let t_err = e.trans_rel * sim.gripper_from_camera.translation.vector.norm();
        if let (Some(sr), Some(st)) = (q.rotation_std_deg, q.translation_std) {
            rot_z += (e.rot_deg / sr).powi(2);
            trans_z += (t_err / st).powi(2);
            n += 1.0;
        }
    }
    // For a calibrated one-sigma (largest axis) the RMS ratio of error to sigma is at most about √3.
    println!(
        "RMS of error/sigma over {n} series: rotation {:.2}, translation {:.2}",
        (rot_z / n).sqrt(),
        (trans_z / n).sqrt()
    );
    Ok(())
}
