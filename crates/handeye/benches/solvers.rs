//! Every batch solver at 2, 10, 100 and 1,000 motions on the paper's simulated data (fixed seed),
//! and the robot-world solvers at 3, 10, 100 and 1,000 poses.
//!
//! `cargo bench -p handeye --bench solvers`

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
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

criterion_group!(benches, solvers, robot_world_solvers);
criterion_main!(benches);
