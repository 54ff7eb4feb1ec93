//! The systematic-error test (`check::systematic`) at 1,000, 10,000 and 100,000 poses of the
//! simulator: the neighbour order (a k-d split, O(n log n)) and the statistics against their
//! permutation nulls (O(n) each for a fixed number of permutations), without the halves' solves;
//! beside it, in the same run, a plain all-pairs solve of the same poses (the accumulated sums of
//! every pair, `solve::accumulate`, O(n)), the reference for its cost. And the online estimator's
//! test step (`track::test_step`: the test, the halves' solves and, flagged, the region
//! bootstrap) on its sample of at most 512 poses.
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

criterion_group!(benches, systematic);
criterion_main!(benches);
