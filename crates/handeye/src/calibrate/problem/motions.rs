//! The hand–eye problem on pose pairs, A X = X B: X from the pairing's motions by the problem's
//! [`Method`], the bootstrap's replicate solve, and what the motions determine. Returns solutions
//! and refusals; the pipeline words the report.

use crate::calibrate::options::Options;
use crate::check::quality::{QualityReport, quality_report};
use crate::check::uncertainty::{Uncertainty, bootstrap};
use crate::model::error::{Degeneracy, Error, Result};
use crate::model::findings::{Part, Verdict};
use crate::model::motion::{Pairing, PosePair, Setup, motion_pairs};
use crate::model::pose::Transform;
use crate::solve::accumulate::PoseAccumulator;
use crate::solve::motions::{AllPairs, MotionSource};
use crate::solve::{Calibration, Method, RefineOptions, Replicates, refine_from, solve};

/// Per-motion details (`quality.per_motion`) are kept up to this many motions. With every pair of
/// poses the default, 10,000 made a 40-pose report list 780 motions (a 150-pose one 11,175 would
/// not, the cut being arbitrary anyway): a report stays readable, and `--pairs consecutive` lists
/// the motions of up to 500 poses.
pub(crate) const MAX_PER_MOTION: usize = 500;

impl Options {
    /// X from the poses by these options' method, pairing and Tsai options: what
    /// [`calibrate`](crate::calibrate())
    /// solves before its checks (the readings, outliers, uncertainty and held-out poses), and what
    /// the OpenCV drop-in returns. [`solve`] is the solve of motions a caller made. The
    /// hand–eye method is the problem's ([`Method::Andreff`] for the robot-world problem).
    pub fn solve(&self, poses: &[PosePair], setup: Setup) -> Result<Calibration> {
        match self.pairing {
            Pairing::All => solve_motions(&AllPairs::new(poses, setup), self),
            Pairing::Consecutive => {
                solve_motions(&motion_pairs(poses, Pairing::Consecutive, setup), self)
            }
        }
    }
}

/// Bootstrap replicates: the same method and pairing as [`Options::solve`], made cheaper where the
/// answer is the same or bounds it. All-pairs Andreff comes from the O(n) accumulated normal
/// equations ([`PoseAccumulator`], equal to the batch solve to ~1e-12). Refine, Tsai, Park and
/// Horaud over all pairs are bootstrapped by the same O(n) Andreff: their errors over all pairs are
/// Andreff's size, and 40 re-solves over n² motions were 95% of a whole `calibrate` (a minute for
/// refine at 1,000 poses). Measured on 40 simulated series per method
/// (`cargo run --release -p handeye --example uncertainty_check all`): median error/sigma 0.90
/// (park, horaud, as with their own replicates), 1.02 (tsai; 0.81 with its own), every error
/// within 3 sigma. Not andreff-joint and daniilidis: their errors are larger than Andreff's
/// (with Andreff's sigma, median error/sigma 3.3 and only 30% within 3 sigma), so they keep
/// their own replicates. Daniilidis over all pairs is itself O(n) (per-pose sums, the same system
/// as the motions': `daniilidis::pairs_normal`), so its own replicates cost what Andreff's do:
/// median error/sigma 0.89 (rotation), 0.96 (translation), every error within 3 sigma; the whole
/// `calibrate` at 1,000 poses went from 6.7 s to 0.37 s (loaded machine). Consecutive refine
/// starts from the replicate's own Andreff solution (never from X̂, which would hide a direction the data leave free) and takes at most
/// [`REPLICATE_ITERATIONS`] steps. Which way a method goes is its row of the capability table
/// ([`Method::capabilities`]'s `replicates`).
pub(crate) fn solve_replicate(
    poses: &[PosePair],
    setup: Setup,
    options: &Options,
) -> Result<Transform> {
    let replicates = options.hand_eye_method().capabilities().replicates;
    match (replicates, options.pairing) {
        (Replicates::AndreffSums | Replicates::SumsOrBriefRefine, Pairing::All) => {
            accumulated_andreff(poses, setup)
        }
        (Replicates::SumsOrBriefRefine, Pairing::Consecutive) => {
            let motions = motion_pairs(poses, Pairing::Consecutive, setup);
            let start = crate::solve::andreff(&motions)?.x;
            refine_briefly(&motions, &start)
        }
        _ => options.solve(poses, setup).map(|c| c.x),
    }
}

/// Levenberg–Marquardt steps a bootstrap replicate of `refine` takes from its Andreff start.
const REPLICATE_ITERATIONS: usize = 4;

fn refine_briefly(motions: &(impl MotionSource + ?Sized), start: &Transform) -> Result<Transform> {
    let options = RefineOptions {
        max_iterations: REPLICATE_ITERATIONS,
        ..RefineOptions::default()
    };
    refine_from(motions, start, &options).map(|r| r.calibration.x)
}

/// All-pairs Andreff from the accumulated normal equations.
fn accumulated_andreff(poses: &[PosePair], setup: Setup) -> Result<Transform> {
    PoseAccumulator::of(poses, setup)
        .estimate()
        .map(|e| e.x)
        .ok_or(Error::Degenerate {
            reason: Degeneracy::IllConditioned,
            conditioning: 0.0,
        })
}

fn solve_motions(motions: &(impl MotionSource + ?Sized), options: &Options) -> Result<Calibration> {
    match options.hand_eye_method() {
        Method::Tsai => options.tsai.solve(motions),
        method => solve(method, motions),
    }
}

/// `andreff`'s bootstrap on the same motions, for a method other than `andreff` (`None` for
/// `andreff` itself, or when it cannot solve them).
fn andreff_uncertainty(
    poses: &[PosePair],
    setup: Setup,
    options: &Options,
    scene: f64,
) -> Option<Uncertainty> {
    if options.hand_eye_method() == Method::Andreff {
        return None;
    }
    // `andreff` with the same pairing: the same motions.
    let andreff_options = options.with_method(Method::Andreff);
    let x = andreff_options.solve(poses, setup).ok()?.x;
    let solve_x = |p: &[PosePair]| solve_replicate(p, setup, &andreff_options);
    Some(bootstrap(
        poses,
        setup,
        &x,
        &solve_x,
        options.replicates,
        scene,
    ))
}

/// Refuses X when the motions leave a direction of it undetermined although the method's own
/// bootstrap did not see it: Daniilidis answered the single-joint recordings (about one axis, which
/// every other method refuses) 113° and 3 m off with a verdict of questionable, its bootstrap
/// blind to the degeneracy. Whether the motions determine X is judged by `andreff`'s bootstrap on
/// the same motions (a linear solve that sees every direction the motions leave free).
pub(crate) fn motions_determine(
    poses: &[PosePair],
    setup: Setup,
    options: &Options,
    scene: f64,
    conditioning: f64,
) -> Result<()> {
    match andreff_uncertainty(poses, setup, options, scene) {
        Some(andreff) if andreff.verdict() == Verdict::Undetermined => {
            refuse_if_undetermined(&andreff, setup, conditioning)
        }
        _ => Ok(()),
    }
}

/// A refusal of X as undetermined by a method other than `andreff` blames the motions ("add
/// motions about …"); when `andreff` determines X from the same motions (the same pairing; its
/// bootstrap judged with the same bounds), the method is at fault instead
/// ([`Degeneracy::MethodUndetermined`]). Measured on testdata's real and realistic sets: 15 of
/// them had andreff-joint, Daniilidis or Tsai refuse with advice to add motions that `andreff`
/// (and most other methods) did not need.
pub(crate) fn method_at_fault(
    refusal: Error,
    poses: &[PosePair],
    setup: Setup,
    options: &Options,
    scene: f64,
) -> Error {
    let Some(andreff) = andreff_uncertainty(poses, setup, options, scene) else {
        return refusal;
    };
    if andreff.verdict() == Verdict::Undetermined {
        return refusal;
    }
    match refusal {
        Error::Degenerate { conditioning, .. } => Error::Degenerate {
            reason: Degeneracy::MethodUndetermined {
                method: options.hand_eye_method().name(),
                rotation_deg: andreff.rotation_deg,
                translation: andreff.translation,
            },
            conditioning,
        },
        other => other,
    }
}

/// Refuses a result whose uncertainty leaves a direction of X undetermined.
pub(crate) fn refuse_if_undetermined(
    u: &Uncertainty,
    setup: Setup,
    conditioning: f64,
) -> Result<()> {
    if u.verdict() != Verdict::Undetermined {
        return Ok(());
    }
    let reason = if u.weakest_rotation.verdict == Verdict::Undetermined {
        undetermined(Part::Rotation, &u.weakest_rotation, setup)
    } else if u.weakest_translation.verdict == Verdict::Undetermined {
        undetermined(Part::Translation, &u.weakest_translation, setup)
    } else {
        Degeneracy::Unstable {
            refused: u.refused,
            tried: u.refused + u.replicates,
        }
    };
    Err(Error::Degenerate {
        reason,
        conditioning,
    })
}

fn undetermined(part: Part, d: &crate::model::findings::Direction, setup: Setup) -> Degeneracy {
    Degeneracy::Undetermined {
        part,
        axis: d.axis,
        sigma: d.sigma,
        setup,
    }
}

/// The quality report over the pairing's motions.
pub(crate) fn quality_of(
    poses: &[PosePair],
    setup: Setup,
    pairing: Pairing,
    c: &Calibration,
) -> QualityReport {
    match pairing {
        Pairing::All => quality_report(&AllPairs::new(poses, setup), &c.x, MAX_PER_MOTION),
        Pairing::Consecutive => {
            quality_report(&motion_pairs(poses, pairing, setup), &c.x, MAX_PER_MOTION)
        }
    }
}
