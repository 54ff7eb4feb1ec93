//! How far X can be trusted: a bootstrap over the poses' own errors, and what it says about each
//! direction of X.
//!
//! To first order every consistent solver's error in X depends on the data only through each
//! pose's disagreement D_i = Y⁻¹ Y_i with the common fixed frame ([`PoseResiduals`]): a change of
//! the data that keeps every pose consistent with some (X, Y) is solved exactly. So the data's own
//! D_i are a complete noise model, whichever side (robot or camera) the noise came from. The
//! bootstrap rebuilds each pose to agree exactly with (X̂, Ŷ), puts back its own D_i or its inverse
//! (a random sign per pose: the wild bootstrap, which keeps each pose's own noise level),
//! inflated by √(n / (n − 2)) for the 12 fitted parameters, and re-solves with the *same* method and
//! pairing. The spread of the re-solved X about X̂ is the uncertainty: pairs that share poses share
//! their noise in every replicate, so all-pairs and consecutive pairings are both honest, and a
//! direction of X that the motions do not fix spreads as far as the noise pushes it.

use nalgebra::{Matrix3, Matrix6, SymmetricEigen, Vector3, Vector6};
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, Normal, StudentsT};

use crate::check::outliers::{PoseResiduals, translation_scale};
use crate::model::error::{Error, Result};
use crate::model::findings::{Direction, Part, Verdict};
use crate::model::motion::{PosePair, Setup};
use crate::model::pose::{Transform, exp_so3, log_so3};
use crate::model::station::Stations;
use crate::model::warning::Warning;
use crate::solve::residual::PoseResidual;

/// Default number of bootstrap replicates: the one-sigma is known to about ±1/√(2·40) ≈ 11%.
pub const REPLICATES: usize = 40;

/// The bootstrap replicates a calibration accepts: fewer than 8 give no usable one-sigma, and
/// more than 100,000 only cost memory and time (each keeps an X).
pub const REPLICATES_RANGE: std::ops::RangeInclusive<usize> = 8..=100_000;

/// Refuses a number of replicates outside [`REPLICATES_RANGE`] (before any is allocated).
pub(crate) fn check_replicates(replicates: usize) -> Result<()> {
    if REPLICATES_RANGE.contains(&replicates) {
        return Ok(());
    }
    Err(Error::InvalidParameter {
        name: "bootstrap",
        message: format!(
            "{} to {} replicates, got {replicates}",
            REPLICATES_RANGE.start(),
            REPLICATES_RANGE.end()
        ),
    })
}

/// The bootstrap's seed: results are reproducible run to run.
const SEED: u64 = 0x5EED_4A11_0E5E;

/// A direction of X's rotation whose one-sigma exceeds this (degrees) is not determined.
pub const UNDETERMINED_ROTATION_DEG: f64 = 10.0;
/// A direction of X's rotation whose one-sigma exceeds this (degrees) is weakly determined.
pub const WEAK_ROTATION_DEG: f64 = 1.0;
/// A direction of X's translation whose one-sigma exceeds this fraction of the scene's size (RMS
/// spread of the hand positions) is not determined.
pub const UNDETERMINED_TRANSLATION: f64 = 0.5;
/// A direction of X's translation whose one-sigma exceeds this fraction of the scene's size is
/// weakly determined.
pub const WEAK_TRANSLATION: f64 = 0.02;
/// Above this fraction of refused replicates the data is at the edge of degeneracy.
const MAX_REFUSED: f64 = 0.25;

/// The uncertainty of X: one-sigma sizes, the covariance, and the weakest directions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Uncertainty {
    /// RMS size of the rotation error to expect, degrees (√trace of the rotation covariance).
    pub rotation_deg: f64,
    /// RMS size of the translation error to expect, input units.
    pub translation: f64,
    /// The least determined rotation direction (rotation about `axis`).
    pub weakest_rotation: Direction,
    /// The least determined translation direction.
    pub weakest_translation: Direction,
    /// Covariance of (rotation vector in radians, translation) of the error, left-perturbation
    /// in X's reference frame, row-major 6×6.
    pub covariance: [[f64; 6]; 6],
    /// Replicates solved.
    pub replicates: usize,
    /// Replicates the solver refused (degenerate); many means X is at the edge of determinable.
    pub refused: usize,
    /// The error where it matters: how far a point seen by the camera is off once mapped
    /// through X ([`Uncertainty::place`]); absent where no point was chosen.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at_point: Option<AtPoint>,
    /// The bootstrap's replicate errors of X, (log(R_b R̂ᵀ), t_b − t̂) each, already widened by
    /// the few-poses factor; empty for a first-order covariance. Not serialised.
    #[serde(skip)]
    pub samples: Vec<[f64; 6]>,
}

/// The expected error of a point seen by the camera, mapped through X (SPEC sec. 9).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AtPoint {
    /// The point, in the camera frame, input unit.
    pub point: [f64; 3],
    /// Its frame: always `camera`.
    pub frame: String,
    /// √trace of the covariance of X·point: the expected distance by which the point is
    /// misplaced, input unit (one sigma).
    pub sigma: f64,
}

impl Uncertainty {
    /// The worse of the two verdicts, with a refusal when too many replicates were refused.
    pub fn verdict(&self) -> Verdict {
        if self.refused as f64 > MAX_REFUSED * (self.replicates + self.refused) as f64 {
            return Verdict::Undetermined;
        }
        match (
            self.weakest_rotation.verdict,
            self.weakest_translation.verdict,
        ) {
            (Verdict::Undetermined, _) | (_, Verdict::Undetermined) => Verdict::Undetermined,
            (Verdict::Weak, _) | (_, Verdict::Weak) => Verdict::Weak,
            _ => Verdict::Determined,
        }
    }

    /// The error of `point` (camera frame) mapped through `x`: the spread of `x_b · point` over
    /// the bootstrap's replicates X_b (each replicate's exact image, not a linearisation), or,
    /// for a first-order covariance without replicates, its first-order image
    /// J C Jᵀ with J = [−[R̂p]ₓ, I].
    pub fn place(&self, x: &Transform, point: [f64; 3]) -> AtPoint {
        let sigma = if self.samples.is_empty() {
            let c = Matrix6::from_fn(|i, j| self.covariance[i][j]);
            point_sigma(&c, x, point)
        } else {
            let rp = x.rotation.matrix() * Vector3::from(point);
            let mut cov = Matrix3::zeros();
            for e in &self.samples {
                let dr = Vector3::new(e[0], e[1], e[2]);
                let dt = Vector3::new(e[3], e[4], e[5]);
                let d = (exp_so3(&dr) - Matrix3::identity()) * rp + dt;
                cov += d * d.transpose();
            }
            (cov / self.samples.len() as f64).trace().max(0.0).sqrt()
        };
        AtPoint {
            point,
            frame: "camera".into(),
            sigma,
        }
    }
}

/// √trace of the first-order image of a covariance `c` of X (rotation vector, translation) at
/// `point` (camera frame): J C Jᵀ with J = [−[R̂p]ₓ, I].
pub fn point_sigma(c: &Matrix6<f64>, x: &Transform, point: [f64; 3]) -> f64 {
    let rp = x.rotation.matrix() * Vector3::from(point);
    let mut jac = nalgebra::Matrix3x6::zeros();
    jac.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(-rp.cross_matrix()));
    jac.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&Matrix3::identity());
    (jac * c * jac.transpose()).trace().max(0.0).sqrt()
}

impl Uncertainty {
    /// This uncertainty widened so that its RMS sizes are at least `rotation_deg` and
    /// `translation` (each block of the covariance, and each replicate's part, scaled by the
    /// same factor; never narrowed); `scene` as in `bootstrap` for the verdicts.
    pub fn at_least(&self, rotation_deg: f64, translation: f64, scene: f64) -> Self {
        let factor = |floor: f64, now: f64| {
            if now > 0.0 && floor > now {
                floor / now
            } else {
                1.0
            }
        };
        let a = factor(rotation_deg, self.rotation_deg);
        let b = factor(translation, self.translation);
        let scale = Vector6::new(a, a, a, b, b, b);
        let cov = Matrix6::from_fn(|i, j| self.covariance[i][j] * scale[i] * scale[j]);
        let mut wider = summarise(cov, self.replicates, self.refused, scene);
        wider.samples = self
            .samples
            .iter()
            .map(|e| std::array::from_fn(|k| e[k] * scale[k]))
            .collect();
        wider.at_point = self.at_point.clone();
        wider
    }
}

impl Uncertainty {
    /// The uncertainty with a prior's: X's translation also moves by `g` δ, δ ~ N(0, σ²)
    /// independent of the data (a prior on one component of X's translation, taken along the
    /// free direction k: g = k / k_i). Adds σ² g gᵀ to the translation covariance, re-judges the
    /// directions against `scene`, and widens `at_point` by the same σ|g| (a translation moves
    /// every point alike). The bootstrap's samples are kept (the data's part).
    pub fn with_prior(&self, g: &Vector3<f64>, sigma: f64, scene: f64) -> Uncertainty {
        let mut cov = Matrix6::from_fn(|i, j| self.covariance[i][j]);
        let add = g * g.transpose() * (sigma * sigma);
        let block = cov.fixed_view::<3, 3>(3, 3) + add;
        cov.fixed_view_mut::<3, 3>(3, 3).copy_from(&block);
        let mut u = summarise(cov, self.replicates, self.refused, scene);
        u.samples = self.samples.clone();
        u.at_point = self.at_point.as_ref().map(|a| AtPoint {
            sigma: (a.sigma.powi(2) + add.trace()).sqrt(),
            ..a.clone()
        });
        u
    }
}

/// The default point of [`Uncertainty::place`]: the median target position seen by the camera
/// (per coordinate, over `camera_from_target`'s translations), the data's working distance.
pub fn median_target(poses: &[PosePair]) -> [f64; 3] {
    let coordinate = |k: usize| {
        crate::check::outliers::median(
            poses
                .iter()
                .map(|p| p.camera_from_target.translation.vector[k])
                .collect(),
        )
    };
    [coordinate(0), coordinate(1), coordinate(2)]
}

/// The bootstrap uncertainty of `x` (solved from `poses` by `solve`) with `replicates` re-solves.
///
/// `solve` must be the same method and pairing that produced `x`; `scene` is the length scale the
/// translation verdicts are relative to (`consistency::translation_scale`).
pub fn bootstrap(
    poses: &[PosePair],
    setup: Setup,
    x: &Transform,
    solve: &(dyn Fn(&[PosePair]) -> Result<Transform> + Sync),
    replicates: usize,
    scene: f64,
) -> Uncertainty {
    let residuals = PoseResiduals::at(poses, setup, x);
    // A station's poses (images at one robot pose) share one sign: their errors are one. The
    // blocks are runs of consecutive stations.
    let stations = stations_of(poses);
    let block = block_length(&per_station(&stations, &residuals.residuals));
    let groups: Vec<usize> = stations.of.iter().map(|&s| s / block).collect();
    resample(
        poses,
        setup,
        x,
        solve,
        (replicates, scene),
        (&residuals, &groups),
    )
}

/// The bootstrap of [`bootstrap`] with the signs shared by regions of the workspace instead of
/// runs of consecutive poses: `order` is a neighbour order of the poses' configurations
/// ([`crate::check::systematic::neighbour_order`]); the residuals along it are cut into blocks
/// as long as their correlation along it (`block_length`), each block a region of the workspace
/// whose poses share one sign.
///
/// An error that follows the configuration is alike within a region and adds up there, as it
/// does in X; independent signs per pose would average it away and report a sigma many times
/// smaller than the error. For independent errors the regions change nothing on average.
pub fn bootstrap_by_region(
    poses: &[PosePair],
    setup: Setup,
    x: &Transform,
    solve: &(dyn Fn(&[PosePair]) -> Result<Transform> + Sync),
    (replicates, scene): (usize, f64),
    order: &[usize],
) -> Uncertainty {
    let residuals = PoseResiduals::at(poses, setup, x);
    // Regions of stations (images at one robot pose share one sign), in the order's station order.
    let stations = stations_of(poses);
    let station_order = stations.order_of(order);
    let of_station = per_station(&stations, &residuals.residuals);
    let along: Vec<PoseResidual> = station_order.iter().map(|&s| of_station[s]).collect();
    let block = block_length(&along).max(region_floor(stations.count));
    let mut rank_of = vec![0; stations.count];
    for (rank, &s) in station_order.iter().enumerate() {
        rank_of[s] = rank;
    }
    let groups: Vec<usize> = stations.of.iter().map(|&s| rank_of[s] / block).collect();
    resample(
        poses,
        setup,
        x,
        solve,
        (replicates, scene),
        (&residuals, &groups),
    )
}

/// The stations of `poses` ([`Stations`]): robot poses within [`crate::model::station::SAME_STATION`]
/// in rotation and of the gripper positions' spread in the base frame ([`translation_scale`] of
/// `base_from_gripper` itself, whatever the setup: the robot's own unit) in translation.
pub(crate) fn stations_of(poses: &[PosePair]) -> Stations {
    Stations::of_poses(poses, translation_scale(poses, Setup::EyeInHand))
}

/// The residual of each station, in station order: the mean of its poses' (the residuals
/// themselves where every pose is its own station).
pub(crate) fn per_station(stations: &Stations, residuals: &[PoseResidual]) -> Vec<PoseResidual> {
    if stations.distinct() {
        return residuals.to_vec();
    }
    let rotations: Vec<Vector3<f64>> = residuals.iter().map(|r| r.rotation).collect();
    let translations: Vec<Vector3<f64>> = residuals.iter().map(|r| r.translation).collect();
    stations
        .means(&rotations)
        .into_iter()
        .zip(stations.means(&translations))
        .map(|(rotation, translation)| PoseResidual {
            rotation,
            angle: rotation.norm(),
            translation,
        })
        .collect()
}

/// The shortest region of [`bootstrap_by_region`]: an error that follows the configuration spans
/// the workspace, so at least √n poses share a sign (8 regions or fewer at 64 poses).
fn region_floor(poses: usize) -> usize {
    (poses as f64).sqrt().ceil() as usize
}

/// The wild bootstrap: each replicate puts back every pose's residual with the sign of its
/// group (`groups[i]`, one random sign per group), and re-solves.
fn resample(
    poses: &[PosePair],
    setup: Setup,
    x: &Transform,
    solve: &(dyn Fn(&[PosePair]) -> Result<Transform> + Sync),
    (replicates, scene): (usize, f64),
    (residuals, groups): (&PoseResiduals, &[usize]),
) -> Uncertainty {
    let n = poses.len() as f64;
    let inflate = if n > 3.0 { (n / (n - 2.0)).sqrt() } else { 2.0 };
    let count = groups.iter().max().map_or(0, |g| g + 1);
    let errors: Vec<Option<Vector6<f64>>> = (0..replicates)
        .into_par_iter()
        .map(|b| {
            let signs = wild_signs(SEED ^ b as u64, count, inflate);
            let resampled: Vec<PosePair> = poses
                .iter()
                .zip(&residuals.residuals)
                .zip(groups)
                .map(|((p, d), &g)| {
                    let s = signs[g];
                    PosePair {
                        base_from_gripper: p.base_from_gripper,
                        camera_from_target: residuals.camera_from_target_with(
                            p,
                            setup,
                            x,
                            &(d.rotation * s),
                            &(d.translation * s),
                        ),
                    }
                })
                .collect();
            solve(&resampled).ok().map(|xb| error_of(&xb, x))
        })
        .collect();
    let solved: Vec<Vector6<f64>> = errors.iter().flatten().copied().collect();
    let mut cov = Matrix6::zeros();
    for e in &solved {
        cov += e * e.transpose();
    }
    let widen = few_poses_factor(poses.len());
    cov *= widen.powi(2) / solved.len().max(1) as f64;
    let mut u = summarise(cov, solved.len(), replicates - solved.len(), scene);
    u.samples = solved
        .iter()
        .map(|e| {
            let e = e * widen;
            [e[0], e[1], e[2], e[3], e[4], e[5]]
        })
        .collect();
    u
}

/// The factor that widens a one-sigma the bootstrap estimated from few poses.
///
/// The bootstrap draws its spread from the residuals of `poses` poses, a spread estimated with
/// about `poses − 2` degrees of freedom (consecutive motions less the fit), so X's error divided
/// by it follows Student's t rather than the normal law the verdicts and "within 3 sigma" assume.
/// Scaling the sigma by t₀.₉₉₅(n − 2) / z₀.₉₉₅ keeps 99% of errors within 2.58 reported sigmas at
/// any n: 24.7 at 3 poses, 3.9 at 4, 1.44 at 8, 1.07 at 30, 1.025 at 80.
///
/// Measured on kinhec recordings with known truth (`python3 bench/small_n.py`, 600 random subsets
/// per size): without it, 54% of 3-pose and 17% of 4-pose answers were beyond 3 sigmas (their
/// 99th percentile of error/sigma 39 and 8.2), against 0.3% at 30 poses (2.4); with it, at most
/// 1% at every size from 3 to 30 poses.
pub(crate) fn few_poses_factor(poses: usize) -> f64 {
    const LEVEL: f64 = 0.995;
    let dof = poses.saturating_sub(2).max(1) as f64;
    let t = StudentsT::new(0.0, 1.0, dof).map_or(f64::INFINITY, |t| t.inverse_cdf(LEVEL));
    t / Normal::standard().inverse_cdf(LEVEL)
}

/// The length of the blocks of consecutive poses that share one sign: the lag at which the
/// residuals' autocorrelation falls below 0.3 (rotation and translation, the longer), at most a
/// fifth of the poses.
///
/// Errors of neighbouring poses in a stream are alike (a time offset, a slowly drifting robot
/// error); consecutive motions cancel most of them. Independent signs would break that and make
/// the noise of small consecutive motions look far larger than it is; within a block the signs
/// agree, so the cancellation stays. For independent errors a block changes nothing on average.
fn block_length(residuals: &[PoseResidual]) -> usize {
    let n = residuals.len();
    let most = (n / 5).max(1);
    let lag = |part: fn(&PoseResidual) -> Vector3<f64>| {
        let energy: f64 = residuals.iter().map(|r| part(r).norm_squared()).sum();
        if energy <= 0.0 {
            return 1;
        }
        (1..most)
            .find(|&k| {
                let c: f64 = residuals
                    .windows(k + 1)
                    .map(|w| part(&w[0]).dot(&part(&w[k])))
                    .sum();
                c < AUTOCORRELATION * energy
            })
            .unwrap_or(most)
    };
    lag(|r| r.rotation).max(lag(|r| r.translation))
}

/// See [`block_length`].
const AUTOCORRELATION: f64 = 0.3;

/// The signs of one wild-bootstrap replicate (Rademacher weights scaled by `inflate`): ±`inflate`
/// with equal odds for each of `count` groups of residuals that share one error (a station, a
/// robot pose), drawn from `seed`, the replicate's own.
pub(crate) fn wild_signs(seed: u64, count: usize, inflate: f64) -> Vec<f64> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    (0..count)
        .map(|_| {
            if rng.next_u64() & 1 == 0 {
                inflate
            } else {
                -inflate
            }
        })
        .collect()
}

/// The error of a replicate: (log(R_b R̂ᵀ), t_b − t̂).
pub(crate) fn error_of(xb: &Transform, x: &Transform) -> Vector6<f64> {
    let dr = log_so3(&(xb.rotation.matrix() * x.rotation.matrix().transpose()));
    let dt = xb.translation.vector - x.translation.vector;
    Vector6::new(dr.x, dr.y, dr.z, dt.x, dt.y, dt.z)
}

/// Sizes, weakest directions and verdicts of a covariance of (rotation vector in radians,
/// translation) of X's error, with `replicates` and `refused` as given (0 for a first-order
/// covariance); `scene` as in [`bootstrap`].
pub(crate) fn summarise(
    cov: Matrix6<f64>,
    replicates: usize,
    refused: usize,
    scene: f64,
) -> Uncertainty {
    let rot: Matrix3<f64> = cov.fixed_view::<3, 3>(0, 0).into_owned();
    let trans: Matrix3<f64> = cov.fixed_view::<3, 3>(3, 3).into_owned();
    let (rot_axis, rot_var) = weakest(&rot);
    let (trans_axis, trans_var) = weakest(&trans);
    let rot_sigma = rot_var.sqrt().to_degrees();
    let trans_sigma = trans_var.sqrt();
    let verdict = |sigma: f64, weak: f64, undetermined: f64| {
        if !sigma.is_finite() || sigma > undetermined {
            Verdict::Undetermined
        } else if sigma > weak {
            Verdict::Weak
        } else {
            Verdict::Determined
        }
    };
    let mut covariance = [[0.0; 6]; 6];
    for (i, row) in covariance.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = cov[(i, j)];
        }
    }
    Uncertainty {
        rotation_deg: rot.trace().max(0.0).sqrt().to_degrees(),
        translation: trans.trace().max(0.0).sqrt(),
        weakest_rotation: Direction {
            axis: rot_axis.into(),
            sigma: rot_sigma,
            verdict: verdict(rot_sigma, WEAK_ROTATION_DEG, UNDETERMINED_ROTATION_DEG),
        },
        weakest_translation: Direction {
            axis: trans_axis.into(),
            sigma: trans_sigma,
            verdict: verdict(
                trans_sigma,
                WEAK_TRANSLATION * scene,
                UNDETERMINED_TRANSLATION * scene,
            ),
        },
        covariance,
        replicates,
        refused,
        at_point: None,
        samples: Vec::new(),
    }
}

/// Warnings for weakly determined directions; `one_axis`: the axis every motion turns about, on a
/// low-DOF recording (its advice is then what such a robot can record). Every face's verdict on a
/// weakly determined direction: the batch's, the pixels', robot-world's and each online report's.
pub(crate) fn warn_weak(
    u: &Uncertainty,
    setup: Setup,
    one_axis: Option<[f64; 3]>,
    warnings: &mut Vec<Warning>,
) {
    for (part, d) in [
        (Part::Rotation, &u.weakest_rotation),
        (Part::Translation, &u.weakest_translation),
    ] {
        // Undetermined here is past a refusal (an online report, or a batch widened for a
        // systematic error after its check): at least weak.
        if d.verdict != Verdict::Determined {
            warnings.push(Warning::WeakDirection {
                part,
                axis: d.axis,
                sigma: d.sigma,
                setup,
                one_axis,
            });
        }
    }
}

/// The eigenvector of the largest eigenvalue of a 3×3 covariance (sign: largest entry positive),
/// and that eigenvalue.
fn weakest(block: &Matrix3<f64>) -> (Vector3<f64>, f64) {
    let eigen = SymmetricEigen::new(*block);
    let i = eigen.eigenvalues.imax();
    let mut v: Vector3<f64> = eigen.eigenvectors.column(i).into_owned();
    if v[v.iamax()] < 0.0 {
        v = -v;
    }
    (v, eigen.eigenvalues[i].max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::motion::{Pairing, motion_pairs};
    use crate::sim::{SimConfig, simulate};
    use crate::solve::{Method, solve};

    fn solver(setup: Setup) -> impl Fn(&[PosePair]) -> Result<Transform> + Sync {
        move |p: &[PosePair]| {
            solve(Method::Andreff, &motion_pairs(p, Pairing::All, setup)).map(|c| c.x)
        }
    }

    #[test]
    fn few_poses_widen_the_sigma_as_students_t_does() {
        let f = few_poses_factor;
        assert!((f(3) - 24.713).abs() < 1e-3, "{}", f(3));
        assert!((f(4) - 3.853).abs() < 1e-3, "{}", f(4));
        assert!((f(80) - 1.0250).abs() < 1e-3, "{}", f(80));
        assert!((1..200).all(|n| f(n + 1) <= f(n)), "shrinks with the poses");
        assert!(f(100_000) > 1.0 && f(100_000) < 1.0001);
    }

    #[test]
    fn noise_free_data_has_no_uncertainty() {
        let s = simulate(&SimConfig::large_motions().noise_free(), 4, 0);
        let solve = solver(Setup::EyeInHand);
        let x = solve(&s.poses).unwrap();
        let u = bootstrap(&s.poses, Setup::EyeInHand, &x, &solve, 8, 1.0);
        assert!(u.rotation_deg < 1e-8 && u.translation < 1e-8, "{u:?}");
        assert_eq!(u.verdict(), Verdict::Determined);
    }

    #[test]
    fn the_one_sigma_matches_the_actual_error_over_many_series() {
        // Over 40 noisy series: actual error / reported one-sigma has a median near 1 (0.33 … 3
        // is the requirement) and nearly all errors are within 3 sigma.
        let solve = solver(Setup::EyeInHand);
        let mut ratios = Vec::new();
        let config = SimConfig {
            poses: 25,
            ..SimConfig::large_motions()
        };
        for seed in 0..40 {
            let s = simulate(&config, seed, 0);
            let x = solve(&s.poses).unwrap();
            let u = bootstrap(&s.poses, Setup::EyeInHand, &x, &solve, REPLICATES, 1.0);
            let e = crate::check::quality::errors_against_truth(&x, &s.gripper_from_camera);
            ratios.push(e.rot_deg / u.rotation_deg);
        }
        let median = crate::check::outliers::median(ratios.clone());
        let within = ratios.iter().filter(|r| **r <= 3.0).count();
        assert!((0.5..2.0).contains(&median), "median {median}: {ratios:?}");
        assert!(within >= 36, "{within} of 40 within 3 sigma: {ratios:?}");
    }
}
