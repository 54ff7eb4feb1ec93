//! The systematic-error test (`check::systematic`) at 1,000, 10,000 and 100,000 poses of the
//! simulator: the neighbour order (a k-d split, O(n log n)) and the statistics against their
//! permutation nulls (O(n) each for a fixed number of permutations), without the halves' solves;
//! beside it, in the same run, a plain all-pairs solve of the same poses (the accumulated sums of
//! every pair, `solve::accumulate`, O(n)), the reference for its cost. And the online estimator's
//! test step (`track::test_step`: the test, the halves' solves and, flagged, the region
//! bootstrap) on its sample of at most 512 poses. And the statistic of the robot's DH table
//! (`check::identification::kinematic_fit`, `--robot-model`) at the same counts of UR10 stations:
//! its cost stops growing at its 1,024 stations.
//!
//! `cargo bench -p handeye --bench systematic`

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use handeye::check::outliers::PoseResiduals;
use handeye::check::systematic::{Configurations, test};
use handeye::sim::{SimConfig, simulate};
use handeye::solve::accumulate::PoseAccumulator;
use handeye::{Method, Pairing, Setup, motion_pairs, solve};
use std::hint::black_box;

fn systematic(c: &mut Criterion) {
    let mut group = c.benchmark_group("systematic");
    group.sample_size(10);
    for poses in [1_000usize, 10_000, 100_000] {
        let sim = simulate(
            &SimConfig {
                poses,
                ..SimConfig::large_motions()
            },
            42,
            0,
        );
        let pairs = motion_pairs(&sim.poses, Pairing::Consecutive, Setup::EyeInHand);
        let x = solve(Method::Andreff, &pairs)
            .expect("the simulator's motions determine X")
            .x;
        let residuals = PoseResiduals::at(&sim.poses, Setup::EyeInHand, &x).residuals;
        let configurations = Configurations::of_hand_poses(&sim.poses);
        group.bench_with_input(BenchmarkId::new("test", poses), &poses, |b, _| {
            b.iter(|| test(black_box(&residuals), black_box(&configurations)))
        });
        group.bench_with_input(
            BenchmarkId::new("all_pairs_solve", poses),
            &poses,
            |b, _| {
                b.iter(|| {
                    let mut sums = PoseAccumulator::new(Setup::EyeInHand);
                    black_box(&sim.poses).iter().for_each(|p| sums.add(p));
                    sums.estimate().map(|e| e.x)
                })
            },
        );
        if poses == 1_000 {
            // The online step tests the tracker's sample: at most 512 of the poses.
            group.bench_with_input(BenchmarkId::new("online_step", 512), &poses, |b, _| {
                b.iter(|| handeye::track::test_step(black_box(&sim.poses), Setup::EyeInHand, &x))
            });
        }
    }
    group.finish();
}

/// UR10 stations at random joint angles (the repository's table), X and the target fixed, exact.
fn ur10_stations(n: usize) -> (handeye::Kinematics, Vec<handeye::PosePair>, Vec<Vec<f64>>) {
    use rand::{RngExt, SeedableRng};
    let table: handeye::Kinematics =
        serde_json::from_str(include_str!("../../../testdata/kinhec/robots/ur10.json"))
            .expect("the repository's UR10 table");
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(7);
    let x = handeye::transform_from_matrix4(&nalgebra::Matrix4::new(
        0.0, -1.0, 0.0, 0.03, 1.0, 0.0, 0.0, 0.01, 0.0, 0.0, 1.0, 0.08, 0.0, 0.0, 0.0, 1.0,
    ))
    .expect("a rigid X");
    let y = handeye::transform_from_matrix4(&nalgebra::Matrix4::new(
        1.0, 0.0, 0.0, 0.6, 0.0, 1.0, 0.0, 0.2, 0.0, 0.0, 1.0, -0.1, 0.0, 0.0, 0.0, 1.0,
    ))
    .expect("a rigid target pose");
    let joints: Vec<Vec<f64>> = (0..n)
        .map(|_| {
            (0..table.dof())
                .map(|_| rng.random_range(-2.5..2.5))
                .collect()
        })
        .collect();
    let poses = joints
        .iter()
        .map(|q| {
            let base_from_gripper = table.forward(q);
            handeye::PosePair {
                base_from_gripper,
                camera_from_target: (base_from_gripper * x).inverse() * y,
            }
        })
        .collect();
    (table, poses, joints)
}

fn kinematic(c: &mut Criterion) {
    use handeye::check::identification::{Station, kinematic_fit};
    use rand::SeedableRng;
    let mut group = c.benchmark_group("systematic_kinematic");
    group.sample_size(10);
    for n in [1_000usize, 10_000, 100_000] {
        let (table, poses, joints) = ur10_stations(n);
        let x = poses_x(&poses);
        let residuals = PoseResiduals::at(&poses, Setup::EyeInHand, &x);
        let stations: Vec<Station<'_>> = poses
            .iter()
            .zip(&joints)
            .zip(&residuals.residuals)
            .map(|((pose, joints), residual)| Station {
                pose,
                joints,
                residual,
            })
            .collect();
        let fit = || {
            let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(1);
            kinematic_fit(
                black_box(&stations),
                (Setup::EyeInHand, &x, &residuals.y),
                &table,
                1.0,
                &mut rng,
            )
        };
        // The whole statistic, permutations included, is what is timed (not an early `None`).
        assert!(fit().is_some(), "the statistic ran on {n} stations");
        group.bench_with_input(BenchmarkId::new("kinematic_fit", n), &n, |b, _| b.iter(fit));
        // The reference in the same run: the all-pairs solve of the same stations (O(n)).
        group.bench_with_input(BenchmarkId::new("all_pairs_solve", n), &n, |b, _| {
            b.iter(|| poses_x(black_box(&poses)))
        });
    }
    group.finish();
}

/// X solved from all pairs of `poses` (exact here).
fn poses_x(poses: &[handeye::PosePair]) -> handeye::Transform {
    let mut sums = PoseAccumulator::new(Setup::EyeInHand);
    poses.iter().for_each(|p| sums.add(p));
    sums.estimate().expect("UR10 stations determine X").x
}

criterion_group!(benches, systematic, kinematic);
criterion_main!(benches);
