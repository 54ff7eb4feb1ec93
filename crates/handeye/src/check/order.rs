//! A change over the recording's order: the camera slipped on its mount (or the target was
//! bumped) at some pose, and every pose after it sees another X.
//!
//! After a slip D at pose k, camera_from_target ← D⁻¹ · camera_from_target from then on, and
//! each pose's disagreement with X and the fixed frame Y, taken in the camera frame,
//! F_i = (X⁻¹ H_i⁻¹ Y) · C_i⁻¹ (H_i the hand pose, C_i `camera_from_target`), is the identity
//! before k and D after: a step in the recording's order, whatever the configuration. Random
//! errors have no order; an error of the robot's kinematics follows the configuration, not the
//! order (the systematic-error test's, `check::systematic`). The test:
//!
//! 1. the residuals F_i of the stations (images at one robot pose counted once, their mean), in
//!    recording order, rotation vector and translation each winsorised at `WINSOR` times their
//!    median size and whitened by their covariance (a PnP pose's depth is far noisier than its
//!    other directions);
//! 2. the share of each block's variance a single step explains, at its best place k (each side
//!    at least [`MIN_SIDE`] stations): n ‖S_k‖² / (k (n − k) Σ‖v_i − v̄‖²), S_k the sum of the
//!    first k centred residuals (the CUSUM statistic); the two blocks' shares summed;
//! 3. its null distribution by permutation: the same statistic over [`PERMUTATIONS`] random
//!    orders of the stations; the p-value is the share of them at or above it, the draws stopped
//!    once enough are above it that the p-value cannot fall to [`P_FLAG`] (Besag and Clifford's
//!    sequential p-value; the verdict is the full run's);
//! 4. a p-value below [`P_FLAG`] is confirmed by solving X on each side of the step apart: a
//!    change is found where both sides determine X and their X differ by more than [`Z_FLAG`]
//!    times the one-sigma of the difference (each side's bootstrap, the wider of the ordinary one
//!    and the one resampled by workspace region, in quadrature), in rotation or in translation.
//!
//! Measured (`crates/handeye/tests/order_change.rs`): no change found on any of the 215 clean
//! kinhec pose-pair recordings tested (the largest z 3.66, an uncalibrated robot's recording that
//! sweeps its workspace in order); slips of 0.5°/2 mm found at z 4.9–5.9 in the station
//! recordings with the robot's noise.
//!
//! A dense stream (consecutive poses nearly alike, `check::systematic::dense_stream`) is not
//! tested: its neighbours' errors are alike by the interpolation, not by a change (the online
//! engine's change detection follows a stream).

use nalgebra::{Matrix3, Vector3};
use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_xoshiro::Xoshiro256PlusPlus;
use serde::{Deserialize, Serialize};

use crate::check::outliers::{PoseResiduals, median};
use crate::check::systematic::{Configurations, dense_stream, neighbour_order, wider};
use crate::check::uncertainty::{bootstrap, bootstrap_by_region, stations_of};
use crate::model::error::Result;
use crate::model::findings::Verdict;
use crate::model::motion::{PosePair, Setup};
use crate::model::pose::{Transform, log_so3, rotation_angle_between};

/// Random orders drawn for the null distribution.
pub const PERMUTATIONS: usize = 2000;

/// A p-value at or below this is confirmed by solving each side apart.
pub const P_FLAG: f64 = 0.002;

/// Random orders at or above the statistic after which the permutations stop: the p-value is
/// then Besag and Clifford's sequential one, this count over the orders drawn, at least
/// `STOP_AFTER / PERMUTATIONS` > [`P_FLAG`]; and the full run's (more of them above, the p-value
/// at least (`STOP_AFTER` + 1) / ([`PERMUTATIONS`] + 1)) is above it too. The verdict is the
/// full run's, and a p-value at or below [`P_FLAG`] (the only one a report shows) is the full
/// run's to the last digit: the permutations stop early only where the test finds nothing, after
/// about `STOP_AFTER / p` orders (10 at p = 0.5) instead of [`PERMUTATIONS`].
const STOP_AFTER: usize = 5;

const _: () = assert!(STOP_AFTER as f64 / PERMUTATIONS as f64 > P_FLAG);

/// The difference of the two sides' X, in its one-sigma, that confirms a change.
pub const Z_FLAG: f64 = 4.0;

/// The test needs at least this many stations.
pub const MIN_STATIONS: usize = 12;

/// Each side of a step has at least this many stations, and at least this share of them.
pub const MIN_SIDE: usize = 5;

/// Bootstrap replicates of each side's X.
const SIDE_REPLICATES: usize = 64;

/// Residuals larger than this times the median size are clipped to it.
const WINSOR: f64 = 4.0;

/// The permutations' seed: results are reproducible run to run.
const SEED: u64 = 0x0D0E_C4A6_E000;

/// What the test found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OrderChange {
    /// Whether a change is found: the p-value below [`P_FLAG`] and the two sides' X apart by more
    /// than [`Z_FLAG`] one-sigmas.
    pub flagged: bool,
    /// The first pose after the change, an index into the poses tested.
    pub at: usize,
    /// The share of the residuals' variance the step explains (rotation and translation summed).
    pub explained: f64,
    /// The share of random orders that explain as much.
    pub p_value: f64,
    /// X of the poses before the change, where they determine it.
    pub before: Option<Transform>,
    /// X of the poses from the change on, where they determine it.
    pub after: Option<Transform>,
    /// Angle between the two, degrees.
    pub rotation_deg: f64,
    /// Distance between their translations, input units.
    pub translation: f64,
    /// One-sigma of the angle (the two sides' bootstraps in quadrature), degrees.
    pub sigma_rotation_deg: f64,
    /// One-sigma of the distance, input units.
    pub sigma_translation: f64,
}

impl OrderChange {
    /// The larger of the difference's two parts, in their one-sigmas.
    pub fn z(&self) -> f64 {
        let part = |d: f64, s: f64| if s > 0.0 { d / s } else { 0.0 };
        part(self.rotation_deg, self.sigma_rotation_deg)
            .max(part(self.translation, self.sigma_translation))
    }
}

/// Each station's residual F_i = (X⁻¹ H_i⁻¹ Y) C_i⁻¹ in the camera frame (rotation vector,
/// translation), in recording order, and the first pose of each station.
fn camera_residuals(
    poses: &[PosePair],
    setup: Setup,
    x: &Transform,
) -> (Vec<Vector3<f64>>, Vec<Vector3<f64>>, Vec<usize>) {
    let y = PoseResiduals::at(poses, setup, x).y;
    let (rot, trans): (Vec<_>, Vec<_>) = poses
        .iter()
        .map(|p| {
            let predicted = x.inverse() * setup.hand_pose(&p.base_from_gripper).inverse() * y;
            let f = predicted * p.camera_from_target.inverse();
            (log_so3(f.rotation.matrix()), f.translation.vector)
        })
        .unzip();
    let stations = stations_of(poses);
    if stations.distinct() {
        return (rot, trans, (0..poses.len()).collect());
    }
    (
        stations.means(&rot),
        stations.means(&trans),
        stations.first_poses(),
    )
}

/// `v` (centred, clipped: [`winsorised`]) in the coordinates its covariance makes isotropic,
/// clipped again: the camera's errors are larger along its line of sight (the depth of a PnP pose)
/// than across it, and a step across it would drown in the depth's noise counted alike.
fn whitened(v: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    let clipped = winsorised(v);
    let n = clipped.len().max(1) as f64;
    let covariance: Matrix3<f64> = clipped
        .iter()
        .map(|x| x * x.transpose())
        .sum::<Matrix3<f64>>()
        / n;
    // A direction without spread (exact data) is kept at a small share of the others'.
    let floor = 1e-9 * covariance.trace() / 3.0;
    let regular = covariance + Matrix3::identity() * floor;
    let Some(l) = regular.cholesky() else {
        return clipped;
    };
    let unmix = l.l().try_inverse().unwrap_or_else(Matrix3::identity);
    winsorised(&clipped.iter().map(|x| unmix * x).collect::<Vec<_>>())
}

/// `v` centred at its mean and clipped at [`WINSOR`] times its median size.
fn winsorised(v: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    let n = v.len().max(1) as f64;
    let mean: Vector3<f64> = v.iter().sum::<Vector3<f64>>() / n;
    let centred: Vec<Vector3<f64>> = v.iter().map(|x| x - mean).collect();
    let limit = WINSOR * median(centred.iter().map(|x| x.norm()).collect());
    centred
        .iter()
        .map(|x| {
            let size = x.norm();
            if limit > 0.0 && size > limit {
                x * (limit / size)
            } else {
                *x
            }
        })
        .collect()
}

/// The statistic of both blocks along `order`: the shares of each block's variance a step after
/// place k explains, summed, at the best k (each side at least `side` long), and that k.
fn statistic(
    rot: &[Vector3<f64>],
    trans: &[Vector3<f64>],
    order: &[usize],
    side: usize,
) -> (f64, usize) {
    let n = order.len();
    let total = |v: &[Vector3<f64>]| {
        let mean: Vector3<f64> = v.iter().sum::<Vector3<f64>>() / n as f64;
        v.iter().map(|x| (x - mean).norm_squared()).sum::<f64>()
    };
    let (tr, tt) = (total(rot), total(trans));
    let mr: Vector3<f64> = rot.iter().sum::<Vector3<f64>>() / n as f64;
    let mt: Vector3<f64> = trans.iter().sum::<Vector3<f64>>() / n as f64;
    let (mut sr, mut st) = (Vector3::zeros(), Vector3::zeros());
    let mut best = (0.0, n / 2);
    for (k, &i) in order.iter().enumerate().take(n - side) {
        sr += rot[i] - mr;
        st += trans[i] - mt;
        let k = k + 1;
        if k < side {
            continue;
        }
        let w = n as f64 / (k * (n - k)) as f64;
        let share = |s: &Vector3<f64>, t: f64| {
            if t > 0.0 {
                w * s.norm_squared() / t
            } else {
                0.0
            }
        };
        let both = share(&sr, tr) + share(&st, tt);
        if both > best.0 {
            best = (both, k);
        }
    }
    best
}

/// The p-value of `explained` against the statistic over random orders of the stations, the draws
/// stopped once `stop_after` of them are at or above it ([`STOP_AFTER`]).
fn permutation_p(
    rot: &[Vector3<f64>],
    trans: &[Vector3<f64>],
    side: usize,
    explained: f64,
    stop_after: usize,
) -> f64 {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(SEED);
    let mut shuffled: Vec<usize> = (0..rot.len()).collect();
    let (mut above, mut drawn) = (0, 0);
    while drawn < PERMUTATIONS && above < stop_after {
        shuffled.shuffle(&mut rng);
        drawn += 1;
        above += usize::from(statistic(rot, trans, &shuffled, side).0 >= explained);
    }
    if above >= stop_after {
        above as f64 / drawn as f64
    } else {
        (above + 1) as f64 / (PERMUTATIONS + 1) as f64
    }
}

/// The test of a change over the order of `poses` under `x` (solved from them by `solve`);
/// `None` with fewer than [`MIN_STATIONS`] stations or on a dense stream.
pub fn order_change(
    poses: &[PosePair],
    setup: Setup,
    x: &Transform,
    solve: &(dyn Fn(&[PosePair]) -> Result<Transform> + Sync),
    scene: f64,
) -> Option<OrderChange> {
    let (rot, trans, firsts) = camera_residuals(poses, setup, x);
    let n = rot.len();
    if n < MIN_STATIONS || dense_stream(poses) {
        return None;
    }
    let (rot, trans) = (whitened(&rot), whitened(&trans));
    let side = MIN_SIDE.max(n / 5);
    let order: Vec<usize> = (0..n).collect();
    let (explained, k) = statistic(&rot, &trans, &order, side);
    let p_value = permutation_p(&rot, &trans, side, explained, STOP_AFTER);
    let at = firsts[k];
    let mut found = OrderChange {
        flagged: false,
        at,
        explained,
        p_value,
        before: None,
        after: None,
        rotation_deg: 0.0,
        translation: 0.0,
        sigma_rotation_deg: 0.0,
        sigma_translation: 0.0,
    };
    if p_value > P_FLAG {
        return Some(found);
    }
    // Each side's X and its one-sigma: the wider of the ordinary bootstrap and the one resampled
    // by workspace region (`bootstrap_by_region`): an error that follows the configuration, met
    // in one order by a robot that sweeps its workspace, moves each side's X by more than its
    // ordinary bootstrap says, and is not a change.
    let side_of = |part: &[PosePair]| {
        let x = solve(part).ok()?;
        let regions = neighbour_order(&Configurations::of_hand_poses(part));
        let (ordinary, by_region) = rayon::join(
            || bootstrap(part, setup, &x, solve, SIDE_REPLICATES, scene),
            || bootstrap_by_region(part, setup, &x, solve, (SIDE_REPLICATES, scene), &regions),
        );
        let u = wider(ordinary, by_region);
        (u.verdict() != Verdict::Undetermined).then_some((x, u))
    };
    let (before, after) = rayon::join(|| side_of(&poses[..at]), || side_of(&poses[at..]));
    let (Some((xa, ua)), Some((xb, ub))) = (before, after) else {
        return Some(found);
    };
    found.before = Some(xa);
    found.after = Some(xb);
    found.rotation_deg = rotation_angle_between(&xa.rotation, &xb.rotation).to_degrees();
    found.translation = (xa.translation.vector - xb.translation.vector).norm();
    found.sigma_rotation_deg = ua.rotation_deg.hypot(ub.rotation_deg);
    found.sigma_translation = ua.translation.hypot(ub.translation);
    found.flagged = found.z() > Z_FLAG;
    Some(found)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::pose::transform_from_parts;
    use crate::sim::{SimConfig, simulate};

    fn all_pairs(poses: &[PosePair]) -> Result<Transform> {
        let motions = crate::model::motion::motion_pairs(
            poses,
            crate::model::motion::Pairing::All,
            Setup::EyeInHand,
        );
        crate::solve::andreff(&motions).map(|c| c.x)
    }

    fn slipped(poses: &[PosePair], at: usize, deg: f64, mm: f64) -> Vec<PosePair> {
        let d = transform_from_parts(
            &crate::model::pose::exp_so3(
                &(Vector3::new(1.0, 2.0, -1.0).normalize() * deg.to_radians()),
            ),
            &(Vector3::new(-1.0, 1.0, 2.0).normalize() * mm),
        );
        crate::sim::slipped(poses, at, &d)
    }

    /// The paper's simulation, a random walk (a dense stream), 40 poses taken in a random order,
    /// as a station recording is.
    fn walk_in_random_order(seed: u64) -> Vec<PosePair> {
        let config = SimConfig {
            poses: 40,
            ..SimConfig::default()
        };
        let mut poses = simulate(&config, seed, 0).poses;
        poses.shuffle(&mut Xoshiro256PlusPlus::seed_from_u64(seed));
        poses
    }

    fn run(poses: &[PosePair]) -> OrderChange {
        let x = all_pairs(poses).unwrap();
        order_change(poses, Setup::EyeInHand, &x, &all_pairs, 300.0).unwrap()
    }

    #[test]
    fn the_stopped_permutations_give_the_full_run_s_verdict() {
        let (mut stopped_early, mut flagged) = (0, 0);
        for seed in 0..8 {
            let poses = walk_in_random_order(seed);
            for poses in [
                poses.clone(),
                slipped(&poses, 21, 0.3 * seed as f64, seed as f64),
            ] {
                let x = all_pairs(&poses).unwrap();
                let (rot, trans, _) = camera_residuals(&poses, Setup::EyeInHand, &x);
                let (rot, trans) = (whitened(&rot), whitened(&trans));
                let side = MIN_SIDE.max(rot.len() / 5);
                let order: Vec<usize> = (0..rot.len()).collect();
                let explained = statistic(&rot, &trans, &order, side).0;
                let full = permutation_p(&rot, &trans, side, explained, usize::MAX);
                let stopped = permutation_p(&rot, &trans, side, explained, STOP_AFTER);
                assert_eq!(full <= P_FLAG, stopped <= P_FLAG, "{full} {stopped}");
                if full <= P_FLAG {
                    assert_eq!(full, stopped);
                    flagged += 1;
                } else if stopped != full {
                    stopped_early += 1;
                    assert!(stopped > P_FLAG);
                }
            }
        }
        // Both kinds were met: the slips of 1.5° and more flag, the clean recordings stop early.
        assert!(
            flagged >= 3 && stopped_early >= 6,
            "{flagged} {stopped_early}"
        );
    }

    #[test]
    fn a_slip_is_found_where_it_happened_and_noise_is_not() {
        let mut quiet = 0;
        for seed in 0..6 {
            let poses = walk_in_random_order(seed);
            quiet += usize::from(run(&poses).flagged);
            let found = run(&slipped(&poses, 21, 2.0, 6.0));
            assert!(found.flagged, "{found:?}");
            assert!((found.at as i64 - 21).abs() <= 1, "{found:?}");
            assert!((found.rotation_deg - 2.0).abs() < 0.5, "{found:?}");
        }
        assert_eq!(quiet, 0);
    }
}
