//! The work of a calibration over every pair of poses grows as the poses, not as the pairs
//! (issue 58): the solve works from per-pose sums, and every check on the default path is O(n)
//! or bounded. Counted by `handeye::solve::motions::pair_work` (the pairs of poses gone through one
//! by one, on every thread), not timed, so that a loaded machine cannot fail the test.
//!
//! One test in this file, so that no other test of the same process adds to the count meanwhile.

use handeye::check::quality::EXACT_POSES;
use handeye::sim::{SimConfig, simulate};
use handeye::solve::motions::pair_work;
use handeye::{Options, Pairing, Setup, calibrate};

/// The pairs gone through by `calibrate` over every pair (the command line's default pairing;
/// the default method and checks) on `poses` simulated poses.
fn pairs_gone_through(poses: usize) -> u64 {
    let series = simulate(
        &SimConfig {
            poses,
            ..SimConfig::default()
        },
        7,
        0,
    );
    let before = pair_work();
    let options = Options {
        pairing: Pairing::All,
        ..Options::default()
    };
    let report = calibrate(&series.poses, Setup::EyeInHand, &options)
        .expect("a calibration")
        .into_hand_eye()
        .expect("the hand–eye report");
    let spent = pair_work() - before;
    println!(
        "{poses} poses ({} pairs): {spent} pairs gone through one by one; quality sampled over {:?} poses",
        poses * (poses - 1) / 2,
        report.quality.sampled_poses
    );
    assert_eq!(report.poses, poses);
    spent
}

#[test]
fn ten_times_the_poses_take_about_ten_times_the_pairs() {
    // Below EXACT_POSES the quality check goes through every pair (so that the repository's
    // recordings keep their exact maxima); the low-DOF check and the rest are linear from the
    // start: 200 poses against 2,000 shows them so, with the quality check's pairs left aside.
    let small = 200;
    let (a, b) = (pairs_gone_through(small), pairs_gone_through(10 * small));
    // The quality check's pass over the pairs and its second one for the axis spread.
    let quality = |n: u64| 2 * (n * (n - 1) / 2);
    assert!(
        a >= quality(small as u64) && b >= quality(10 * small as u64),
        "{a} {b}"
    );
    let (a_rest, b_rest) = (a - quality(small as u64), b - quality(10 * small as u64));
    println!("besides the quality check: {a_rest} and {b_rest}");
    assert!(b_rest <= 12 * a_rest.max(1), "{a_rest} then {b_rest}");
    // Above it, everything: n and 10 n poses.
    let n = EXACT_POSES + 1;
    let (c, d) = (pairs_gone_through(n), pairs_gone_through(10 * n));
    assert!(c > 0, "nothing counted");
    assert!(d <= 12 * c, "{c} pairs at {n} poses, {d} at {}", 10 * n);
    // And far from every pair: at 10 n poses, under a tenth of them.
    let all = (10 * n as u64) * (10 * n as u64 - 1) / 2;
    assert!(d < all / 10, "{d} of {all} pairs");
}
