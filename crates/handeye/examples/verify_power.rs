//! What `verify` can see, and whether the uncertainty of small recordings is honest, measured on
//! noisy copies of kinhec's noise-free station recordings (same poses, new noise at kinhec's
//! nominal levels: robot 0.5 mrad / 0.3 mm, camera 2 mrad / 1, 1, 3 mm).
//!
//! For 12, 16, 20 and 40 stations and `copies` copies (default 60):
//! - the one-sigma the bootstrap reports against the spread of the answer over the copies, per
//!   direction (the eigenvectors of the copies' covariance, rotation and translation blocks): the
//!   RMS reported sigma along the direction over the empirical standard deviation along it
//!   (honest: near 1; overconfident: below);
//! - `detectable` against the shifts actually detected: the saved X is the truth shifted by 0.5,
//!   1 and 2 times the copy's `detectable`, along the recording's weakest rotation and translation
//!   directions and along two fixed others, and the share called inconsistent is printed.
//!
//! `cargo run --release -p handeye --example verify_power [copies]`

use std::path::PathBuf;

use handeye::io::{Format, Truth, read_pose_file};
use handeye::{Consistency, Options, PosePair, SavedX, Setup, Transform, calibrate, verify};
use nalgebra::{Matrix3, Matrix6, Rotation3, SymmetricEigen, Translation3, Vector3, Vector6};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use rand_xoshiro::Xoshiro256PlusPlus;

const STATIONS: [usize; 4] = [12, 16, 20, 40];
const SHIFTS: [f64; 3] = [0.5, 1.0, 2.0];

fn main() -> Result<(), handeye::Error> {
    let copies: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(60);
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../testdata/kinhec/pairs");
    for (name, setup) in [
        ("noise_free_stations_eih_s0", Setup::EyeInHand),
        ("noise_free_stations_eth_s0", Setup::EyeToHand),
    ] {
        let poses = read_pose_file(&root.join(format!("{name}.jsonl")), Format::Auto)?.pairs;
        let truth = Truth::read(root.join(format!("{name}.truth.json")))?.x;
        for n in STATIONS {
            measure(name, &poses[..n.min(poses.len())], &truth, setup, copies)?;
        }
    }
    Ok(())
}

fn measure(
    name: &str,
    clean: &[PosePair],
    truth: &Transform,
    setup: Setup,
    copies: usize,
) -> Result<(), handeye::Error> {
    let options = Options {
        replicates: std::env::var("REPLICATES")
            .ok()
            .and_then(|r| r.parse().ok())
            .unwrap_or(Options::default().replicates),
        ..Options::default()
    };
    let mut distances = Vec::new();
    let mut refused = (0, 0);
    let mut errors = Vec::new();
    let mut covariances = Vec::new();
    // [direction][shift] → (detected, tried)
    let mut detected = [[(0usize, 0usize); SHIFTS.len()]; 4];
    let mut detectable = (Vec::new(), Vec::new());
    let mut consistent_at_truth = 0;
    for c in 0..copies {
        let noisy = with_noise(clean, 1000 + c as u64);
        let saved = |x: Transform| SavedX {
            x,
            setup: Some(setup),
            covariance: None,
            unit: None,
        };
        let at_truth = verify(&saved(*truth), &noisy[..], setup, &options)?;
        match at_truth.verdict {
            Consistency::Consistent => consistent_at_truth += 1,
            Consistency::Inconsistent => refused.0 += 1,
            Consistency::Undetermined => refused.1 += 1,
        }
        distances.push(at_truth.distance_sigmas);
        let report = calibrate(&noisy[..], setup, &options)?
            .into_hand_eye()
            .expect("a hand–eye report");
        let cov = Matrix6::from_fn(|i, j| report.uncertainty.covariance[i][j]);
        let err = error_of(&report.transform, truth);
        errors.push(err);
        covariances.push(cov);
        let d = at_truth.detectable;
        detectable.0.push(d.rotation_deg);
        detectable.1.push(d.translation);
        let weakest = |from: usize| {
            let e = SymmetricEigen::new(cov.fixed_view::<3, 3>(from, from).into_owned());
            e.eigenvectors.column(e.eigenvalues.imax()).into_owned()
        };
        let directions = [
            (weakest(0), true),
            (Vector3::new(1.0, 1.0, 0.0).normalize(), true),
            (weakest(3), false),
            (Vector3::new(0.0, 1.0, 1.0).normalize(), false),
        ];
        for (k, (axis, rotation)) in directions.iter().enumerate() {
            for (s, factor) in SHIFTS.iter().enumerate() {
                let shifted = if *rotation {
                    let r = exp_so3(&(axis * (factor * d.rotation_deg).to_radians()))
                        * truth.rotation.matrix();
                    Transform::from_parts(truth.translation, rotation_of(&r))
                } else {
                    Transform::from_parts(
                        Translation3::from(
                            truth.translation.vector + axis * (factor * d.translation),
                        ),
                        truth.rotation,
                    )
                };
                let v = verify(&saved(shifted), &noisy[..], setup, &options)?;
                let cell = &mut detected[k][s];
                cell.1 += 1;
                if v.verdict == Consistency::Inconsistent {
                    cell.0 += 1;
                }
            }
        }
    }
    println!(
        "{name}, {} stations, {copies} copies: the truth consistent in {consistent_at_truth}, inconsistent in {}, undetermined in {}; its distance median {:.2} (χ²₆: 2.31), 90% {:.2} (3.26); detectable median {:.3}° / {:.2} mm",
        clean.len(),
        refused.0,
        refused.1,
        median(&distances),
        quantile(&distances, 0.9),
        median(&detectable.0),
        median(&detectable.1) * 1e3
    );
    honesty(&errors, &covariances);
    let labels = [
        "rotation, weakest",
        "rotation, (1,1,0)",
        "translation, weakest",
        "translation, (0,1,1)",
    ];
    for (label, row) in labels.iter().zip(&detected) {
        let shares: Vec<String> = SHIFTS
            .iter()
            .zip(row)
            .map(|(f, (hit, all))| format!("{f}×: {:.0}%", 100.0 * *hit as f64 / *all as f64))
            .collect();
        println!("  detected, {label}: {}", shares.join(", "));
    }
    Ok(())
}

/// The reported sigma over the copies' spread, per eigen-direction of the spread.
fn honesty(errors: &[Vector6<f64>], covariances: &[Matrix6<f64>]) {
    let n = errors.len() as f64;
    let mean = errors.iter().sum::<Vector6<f64>>() / n;
    let mut spread = Matrix6::zeros();
    for e in errors {
        spread += (e - mean) * (e - mean).transpose();
    }
    spread /= n - 1.0;
    for (from, label, unit) in [(0, "rotation", 1f64.to_degrees()), (3, "translation", 1e3)] {
        let block: Matrix3<f64> = spread.fixed_view::<3, 3>(from, from).into_owned();
        let eigen = SymmetricEigen::new(block);
        let mut parts = Vec::new();
        let mut order: Vec<usize> = (0..3).collect();
        order.sort_by(|a, b| eigen.eigenvalues[*b].total_cmp(&eigen.eigenvalues[*a]));
        for k in order {
            let v = eigen.eigenvectors.column(k);
            let empirical = eigen.eigenvalues[k].max(0.0).sqrt();
            let reported = (covariances
                .iter()
                .map(|c| {
                    let b: Matrix3<f64> = c.fixed_view::<3, 3>(from, from).into_owned();
                    (v.transpose() * b * v)[(0, 0)]
                })
                .sum::<f64>()
                / n)
                .sqrt();
            let each: Vec<f64> = covariances
                .iter()
                .map(|c| {
                    let b: Matrix3<f64> = c.fixed_view::<3, 3>(from, from).into_owned();
                    (v.transpose() * b * v)[(0, 0)].sqrt() / empirical
                })
                .collect();
            parts.push(format!(
                "spread {:.4} σ {:.4} ratio {:.2} (copies 10%–90% {:.2}–{:.2})",
                empirical * unit,
                reported * unit,
                reported / empirical,
                quantile(&each, 0.1),
                quantile(&each, 0.9)
            ));
        }
        let bias = mean.fixed_rows::<3>(from).norm() * unit;
        println!(
            "  {label} ({}; weakest first): {} | bias {bias:.4}",
            if from == 0 { "deg" } else { "mm" },
            parts.join("; ")
        );
    }
}

/// The clean poses with kinhec's nominal SE(3) Gaussian noise: the robot's on the right of
/// base_from_gripper, the camera's on camera_from_target (its translation in the camera frame).
fn with_noise(clean: &[PosePair], seed: u64) -> Vec<PosePair> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let unit = Normal::new(0.0, 1.0).expect("a normal law");
    let mut draw = |s: [f64; 3]| Vector3::from_fn(|i, _| unit.sample(&mut rng) * s[i]);
    clean
        .iter()
        .map(|p| {
            let (rr, rt) = (draw([5e-4; 3]), draw([3e-4; 3]));
            let (cr, ct) = (draw([2e-3; 3]), draw([1e-3, 1e-3, 3e-3]));
            let g = p.base_from_gripper;
            let robot = Transform::from_parts(
                Translation3::from(g.translation.vector + g.rotation * rt),
                rotation_of(&(g.rotation.matrix() * exp_so3(&rr))),
            );
            let c = p.camera_from_target;
            let camera = Transform::from_parts(
                Translation3::from(c.translation.vector + ct),
                rotation_of(&(exp_so3(&cr) * c.rotation.matrix())),
            );
            PosePair {
                base_from_gripper: robot,
                camera_from_target: camera,
            }
        })
        .collect()
}

fn exp_so3(w: &Vector3<f64>) -> Matrix3<f64> {
    *Rotation3::from_scaled_axis(*w).matrix()
}

fn log_so3(r: &Matrix3<f64>) -> Vector3<f64> {
    Rotation3::from_matrix_unchecked(*r).scaled_axis()
}

fn rotation_of(m: &Matrix3<f64>) -> Rotation3<f64> {
    Rotation3::from_matrix_unchecked(*m)
}

/// (log(R R_truthᵀ), t − t_truth): the bootstrap's convention.
fn error_of(x: &Transform, truth: &Transform) -> Vector6<f64> {
    let dr = log_so3(&(x.rotation.matrix() * truth.rotation.matrix().transpose()));
    let dt = x.translation.vector - truth.translation.vector;
    Vector6::new(dr.x, dr.y, dr.z, dt.x, dt.y, dt.z)
}

fn quantile(v: &[f64], q: f64) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v[((v.len() as f64 * q) as usize).min(v.len() - 1)]
}

fn median(v: &[f64]) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}
