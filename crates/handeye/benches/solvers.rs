//! Every batch solver at 2, 10, 100 and 1,000 motions on the paper's simulated data (fixed seed),
//! the robot-world solvers at 3, 10, 100 and 1,000 poses, and the OpenCV drop-in's path
//! (`solve_poses_checked`: the readings check, the all-pairs solve and the first-order covariance)
//! beside the bare all-pairs solve at 10 and 100 poses.
//!
//! `cargo bench -p handeye --bench solvers`

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use handeye::calibration::{Options, solve_poses, solve_poses_checked};
use handeye::conventions::check_readings;
use handeye::sim::{SimConfig, simulate};
use handeye::solve::{RobotWorldMethod, robot_world};
use handeye::{Method, Pairing, Setup, motion_pairs, solve};
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

fn drop_in(c: &mut Criterion) {
    let mut group = c.benchmark_group("drop_in");
    for poses in [10usize, 100] {
        let sim = simulate(
            &SimConfig {
                poses,
                ..SimConfig::large_motions()
            },
            42,
            0,
        );
        let options = Options {
            method: Method::Tsai,
            pairing: Pairing::All,
            ..Options::default()
        };
        group.bench_with_input(BenchmarkId::new("solve", poses), &sim.poses, |b, p| {
            b.iter(|| solve_poses(black_box(p), Setup::EyeInHand, &options))
        });
        group.bench_with_input(BenchmarkId::new("checked", poses), &sim.poses, |b, p| {
            b.iter(|| solve_poses_checked(black_box(p), Setup::EyeInHand, &options))
        });
        group.bench_with_input(BenchmarkId::new("readings", poses), &sim.poses, |b, p| {
            b.iter(|| check_readings(black_box(p), Setup::EyeInHand))
        });
    }
    group.finish();
}

criterion_group!(benches, solvers, robot_world_solvers, drop_in);
criterion_main!(benches);
