//! Every batch solver at 2, 10, 100 and 1,000 motions on the paper's simulated data (fixed seed),
//! the robot-world solvers at 3, 10, 100 and 1,000 poses, and the OpenCV drop-in's path (the
//! command line's `calibrate` over all pairs: the readings check, the outlier test, the solve, the
//! bootstrap and the held-out check) beside the bare all-pairs solve and its two first checks
//! alone.
//!
//! `cargo bench -p handeye --bench solvers`

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use handeye::check::outliers::pose_outliers;
use handeye::check::quality::OUTLIER_DEG;
use handeye::check::readings::check_readings;
use handeye::io::{Format, read_pose_file};
use handeye::sim::{SimConfig, simulate};
use handeye::solve::{RobotWorldMethod, robot_world};
use handeye::{Method, Pairing, PosePair, Setup, motion_pairs, solve};
use handeye::{Options, Problem, calibrate};
use std::hint::black_box;

fn solvers(c: &mut Criterion) {
    let mut group = c.benchmark_group("solve");
    for motions in [2usize, 10, 100, 1000] {
        let sim = simulate(
            &SimConfig {
                poses: motions + 1,
                ..SimConfig::default()
            },
            42,
            0,
        );
        let pairs = motion_pairs(&sim.poses, Pairing::Consecutive, Setup::EyeInHand);
        for method in Method::ALL {
            group.bench_with_input(
                BenchmarkId::new(method.name(), motions),
                &pairs,
                |b, pairs| b.iter(|| solve(method, black_box(pairs))),
            );
        }
    }
    group.finish();
}

fn robot_world_solvers(c: &mut Criterion) {
    let mut group = c.benchmark_group("robot_world");
    for poses in [3usize, 10, 100, 1000] {
        let sim = simulate(
            &SimConfig {
                poses,
                ..SimConfig::default()
            },
            42,
            0,
        );
        for method in RobotWorldMethod::ALL {
            group.bench_with_input(
                BenchmarkId::new(method.name(), poses),
                &sim.poses,
                |b, poses| b.iter(|| robot_world(method, black_box(poses), Setup::EyeInHand)),
            );
        }
    }
    group.finish();
}

/// The drop-in's datasets: OpenCV's test protocol at 10 poses (testdata/opencv; the poses fit as
/// given, so the readings check solves one reading), and the simulator's series at 10 poses (its
/// translation residual is 2.9% of the scene, a poor fit: all nine readings are solved) and 100.
fn drop_in_datasets() -> Vec<(&'static str, Vec<PosePair>)> {
    let opencv = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata/opencv/opencv_eye-in-hand_noisy_10_12.jsonl");
    let sim = |poses| {
        simulate(
            &SimConfig {
                poses,
                ..SimConfig::large_motions()
            },
            42,
            0,
        )
        .poses
    };
    vec![
        (
            "opencv-10",
            read_pose_file(&opencv, Format::Auto)
                .expect("testdata/opencv")
                .pairs,
        ),
        ("sim-10", sim(10)),
        ("sim-100", sim(100)),
    ]
}

fn drop_in(c: &mut Criterion) {
    let mut group = c.benchmark_group("drop_in");
    let options = Options {
        problem: Problem::HandEye(Method::Tsai),
        pairing: Pairing::All,
        ..Options::default()
    };
    for (name, poses) in drop_in_datasets() {
        group.bench_with_input(BenchmarkId::new("solve", name), &poses, |b, p| {
            b.iter(|| options.solve(black_box(p), Setup::EyeInHand))
        });
        group.bench_with_input(BenchmarkId::new("calibrate", name), &poses, |b, p| {
            b.iter(|| {
                calibrate(black_box(p), Setup::EyeInHand, &options)
                    .map(|r| r.into_hand_eye().expect("the hand–eye report"))
            })
        });
        group.bench_with_input(BenchmarkId::new("readings", name), &poses, |b, p| {
            b.iter(|| check_readings(black_box(p), Setup::EyeInHand, handeye::Written::NAMED))
        });
        group.bench_with_input(BenchmarkId::new("outliers", name), &poses, |b, p| {
            b.iter(|| pose_outliers(black_box(p), Setup::EyeInHand, OUTLIER_DEG))
        });
    }
    group.finish();
}

criterion_group!(benches, solvers, robot_world_solvers, drop_in);
criterion_main!(benches);
