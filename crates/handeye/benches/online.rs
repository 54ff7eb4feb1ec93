//! The online calibrator: `push` on a stream with no calibration, and a calibration event.
//!
//! `cargo bench -p handeye --bench online`

use criterion::{Criterion, criterion_group, criterion_main};
use handeye::online::select::{AdaptiveParams, Selection};
use handeye::online::{OnlineCalibrator, OnlineConfig};
use handeye::sim::{SimConfig, simulate};
use handeye::solve::andreff;
use handeye::{PosePair, Transform};
use std::hint::black_box;

/// The poses both benches run on: one simulated series of 1,000 poses (fixed seed).
fn series() -> Vec<PosePair> {
    simulate(
        &SimConfig {
            poses: 1000,
            ..SimConfig::default()
        },
        42,
        0,
    )
    .poses
}

fn push(c: &mut Criterion) {
    let poses = series();
    // Thresholds no motion can meet (β₀ above any rotation, no relaxation in reach): every push
    // searches and none calibrates.
    let params = AdaptiveParams {
        d_max: 100.0,
        interval: usize::MAX / 2,
        ..AdaptiveParams::default()
    };
    let config = OnlineConfig {
        selection: Selection::Adaptive,
        params,
        ..OnlineConfig::default()
    };
    let mut warm = OnlineCalibrator::new(config).unwrap();
    let still = PosePair {
        base_from_gripper: Transform::identity(),
        camera_from_target: Transform::identity(),
    };
    for _ in 0..6 {
        warm.push(&still).unwrap();
    }
    c.bench_function("push/no_calibration", |b| {
        let mut cal = warm.clone();
        let mut k = 0;
        b.iter(|| {
            k = (k + 1) % poses.len();
            black_box(cal.push(black_box(&poses[k])).unwrap())
        })
    });
    let pairs = handeye::motion_pairs(
        &poses[..3],
        handeye::Pairing::Consecutive,
        handeye::Setup::EyeInHand,
    );
    c.bench_function("calibration/andreff_two_motions", |b| {
        b.iter(|| andreff(black_box(&pairs)))
    });
    c.bench_function("push/conventional_every_pose", |b| {
        let config = OnlineConfig {
            selection: Selection::None,
            ..OnlineConfig::default()
        };
        let mut cal = OnlineCalibrator::new(config).unwrap();
        let mut k = 0;
        b.iter(|| {
            k = (k + 1) % poses.len();
            black_box(cal.push(black_box(&poses[k])).unwrap())
        })
    });
}

criterion_group!(benches, push);

fn accumulator(c: &mut Criterion) {
    use handeye::solve::accumulate::PoseAccumulator;
    let poses = series();
    c.bench_function("accumulate/add_pose", |b| {
        let mut acc = PoseAccumulator::new(handeye::Setup::EyeInHand);
        let mut k = 0;
        b.iter(|| {
            k = (k + 1) % poses.len();
            acc.add(black_box(&poses[k]));
        })
    });
    let mut acc = PoseAccumulator::new(handeye::Setup::EyeInHand);
    for p in &poses {
        acc.add(p);
    }
    c.bench_function("accumulate/estimate", |b| {
        b.iter(|| black_box(&acc).estimate())
    });
}

criterion_group!(accumulate_benches, accumulator);
criterion_main!(benches, accumulate_benches);
