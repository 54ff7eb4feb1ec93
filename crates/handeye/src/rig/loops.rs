//! Loop closures: where two cameras see one target at the same robot pose (or one camera two
//! targets), the measured relative pose of the two cameras (targets) against the one the solved
//! parts give.
//!
//! For two cameras a, b seeing one target at pose i the measured `a_from_b` is D_i = C_a C_b⁻¹;
//! the solved parts give P_i = X_a⁻¹ B(m_a, i)⁻¹ B(m_b, i) X_b (the target's pose cancels). For two
//! targets seen by one camera, D_i = C_a⁻¹ C_b and P_i = Y_a⁻¹ B(m_a, i)⁻¹ B(m_b, i) Y_b. The
//! closure error of pose i is P_i⁻¹ D_i; a loop reports its RMS over the common poses.
//!
//! What the noise explains: the observations' own noise, from the closures' differences between
//! successive common poses (the median, so that one jump, a camera knocked once, does not count
//! as noise), and the solved parts' uncertainty (the bootstrap replicates' P_i about the
//! solution's), added in quadrature. A loop closes when its RMS is within [`LOOP_LIMIT`] times
//! that, in rotation and in translation.
//!
//! A part whose every loop fails while some loop of each other part closes is named: it does not
//! fit the rest (a camera that moved during the recording). When no single part can be singled
//! out the parts of the failing loops are named together.

use std::collections::BTreeMap;

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::model::pose::{Transform, log_so3, rotation_matrix};
use crate::model::warning::Warning;
use crate::rig::graph::Graph;
use crate::rig::joint::Solution;
use crate::rig::{PartKind, Residual, RigRecording};

/// A loop does not close when its RMS closure exceeds this many times what the noise and the
/// parts' uncertainty explain. The ratio is about 1 on consistent data; on 8 common poses its
/// sampling spread stays well below 3 (χ² with 24 degrees of freedom, its 0.999 quantile 2.3
/// times its mean in squares, 1.5 in the RMS; the median of 7 differences adds its own spread).
pub const LOOP_LIMIT: f64 = 3.0;

/// Common poses a loop needs before its closure is judged.
pub const MIN_LOOP_POSES: usize = 8;

/// A loop does not close when its closure's median changes, between the poses before some pose and
/// those after, by more than this many standard errors (the largest over the splits; rotation or
/// translation). A part knocked once during the recording shifts the closure at that pose, which
/// the RMS hides when the joint solve settles half way; the change is measured against the
/// observations' noise alone (the parts' estimation error is the same on both sides and cancels).
/// Each side holds [`MIN_SEGMENT`] poses or more. For Gaussian noise the statistic of one split is
/// the norm of 3 standard normals (above 6 with probability 1.1e-7).
pub const CHANGE_LIMIT: f64 = 6.0;

/// The fewest poses on either side of a split of [`CHANGE_LIMIT`]'s test.
pub const MIN_SEGMENT: usize = 3;

/// The median of χ² with 3 degrees of freedom: a 3-vector of independent unit normals has
/// ‖v‖² below it half the time.
const MEDIAN_CHI2_3: f64 = 2.365_973_884_375_91;

/// One pose's closure error: its rotation vector (radians) and its translation.
type Closure = (Vector3<f64>, Vector3<f64>);

/// One loop's closure.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LoopClosure {
    /// Its cameras.
    pub cameras: Vec<String>,
    /// Its targets.
    pub targets: Vec<String>,
    /// The two parts whose relative pose the loop measures (two cameras, or two targets); the
    /// third cancels.
    pub compared: [String; 2],
    /// RMS closure rotation over the common poses, degrees.
    pub rotation_deg: f64,
    /// RMS closure translation over the common poses, input units.
    pub translation: f64,
    /// The RMS closure the observations' noise and the parts' uncertainty explain.
    pub expected: Residual,
    /// Common poses.
    pub poses: usize,
    /// The largest change of the closure between the poses before a pose and those after, in
    /// standard errors of the observations' noise ([`CHANGE_LIMIT`]).
    pub change_sigmas: f64,
    /// The common pose after which that change happens (index into the recording's poses, the
    /// first of the later side).
    pub change_at: usize,
    /// Whether it closes: within [`LOOP_LIMIT`] times `expected` in both, and no change beyond
    /// [`CHANGE_LIMIT`].
    pub closes: bool,
}

/// Each node's first observation per pose, by edge: pose → observation index.
fn by_pose(graph: &Graph, recording: &RigRecording, e: usize) -> BTreeMap<usize, usize> {
    let mut m = BTreeMap::new();
    for &k in &graph.edges[e].observations {
        m.entry(recording.observations[k].pose).or_insert(k);
    }
    m
}

/// The (rotation vector, translation) of a transform.
fn split(t: &Transform) -> Closure {
    (log_so3(&rotation_matrix(t)), t.translation.vector)
}

/// Every loop of two edges that share a node, between determined parts, with at least
/// [`MIN_LOOP_POSES`] common poses.
pub fn closures(
    recording: &RigRecording,
    graph: &Graph,
    solution: &Solution,
    limit: f64,
) -> Vec<LoopClosure> {
    let solved = |n: usize| solution.parts[n].is_some();
    let mut out = Vec::new();
    let edges: Vec<usize> = (0..graph.edges.len())
        .filter(|&e| solved(graph.edges[e].camera) && solved(graph.edges[e].target))
        .collect();
    let poses: Vec<BTreeMap<usize, usize>> = (0..graph.edges.len())
        .map(|e| by_pose(graph, recording, e))
        .collect();
    for (i, &e1) in edges.iter().enumerate() {
        for &e2 in &edges[i + 1..] {
            let (a, b) = (&graph.edges[e1], &graph.edges[e2]);
            // Two cameras seeing one target, or one camera seeing two targets.
            let (kind, n1, n2) = if a.target == b.target {
                (PartKind::Camera, a.camera, b.camera)
            } else if a.camera == b.camera {
                (PartKind::Target, a.target, b.target)
            } else {
                continue;
            };
            let common: Vec<(usize, usize, usize)> = poses[e1]
                .iter()
                .filter_map(|(&p, &k1)| poses[e2].get(&p).map(|&k2| (p, k1, k2)))
                .collect();
            if common.len() < MIN_LOOP_POSES {
                continue;
            }
            let model = |parts: &[Transform], p: usize| -> Transform {
                parts[n1].inverse()
                    * graph.base_from_mount(recording, n1, p).inverse()
                    * graph.base_from_mount(recording, n2, p)
                    * parts[n2]
            };
            let solved_parts: Vec<Transform> =
                (0..graph.nodes.len()).map(|n| solution.pose(n)).collect();
            let closure: Vec<Closure> = common
                .iter()
                .map(|&(p, k1, k2)| {
                    let c1 = recording.observations[k1].camera_from_target;
                    let c2 = recording.observations[k2].camera_from_target;
                    let measured = match kind {
                        PartKind::Camera => c1 * c2.inverse(),
                        PartKind::Target => c1.inverse() * c2,
                    };
                    split(&(model(&solved_parts, p).inverse() * measured))
                })
                .collect();
            let n = closure.len() as f64;
            let rms = |f: &dyn Fn(&Closure) -> f64| {
                (closure.iter().map(|c| f(c).powi(2)).sum::<f64>() / n).sqrt()
            };
            let rms_r = rms(&|c| c.0.norm()).to_degrees();
            let rms_t = rms(&|c| c.1.norm());
            let noise = |f: &dyn Fn(&Closure) -> Vector3<f64>| {
                let d: Vec<f64> = closure
                    .windows(2)
                    .map(|w| (f(&w[1]) - f(&w[0])).norm_squared())
                    .collect();
                (3.0 * crate::check::outliers::median(d) / (2.0 * MEDIAN_CHI2_3)).sqrt()
            };
            let noise_r = noise(&|c| c.0).to_degrees();
            let noise_t = noise(&|c| c.1);
            // The parts' uncertainty: the replicates' P_i about the solution's.
            let mut est = [0.0; 2];
            let mut count = 0usize;
            for r in &solution.replicates {
                for &(p, _, _) in &common {
                    let (dr, dt) = split(&(model(&solved_parts, p).inverse() * model(r, p)));
                    est[0] += dr.norm_squared();
                    est[1] += dt.norm_squared();
                    count += 1;
                }
            }
            let c = count.max(1) as f64;
            let est_r = (est[0] / c).sqrt().to_degrees();
            let est_t = (est[1] / c).sqrt();
            let expected = Residual {
                rotation_deg: noise_r.hypot(est_r).max(1e-9),
                translation: noise_t
                    .hypot(est_t)
                    .max(1e-12 * solution.scene.max(f64::MIN_POSITIVE)),
            };
            let (change_sigmas, split) = change(&closure, [1e-9, 1e-9 * solution.scene]);
            let change_at = common[split.min(common.len() - 1)].0;
            let closes = rms_r <= limit * expected.rotation_deg
                && rms_t <= limit * expected.translation
                && change_sigmas <= CHANGE_LIMIT;
            let name = |n: usize| graph.nodes[n].name.clone();
            let (cameras, targets) = match kind {
                PartKind::Camera => (vec![name(n1), name(n2)], vec![name(a.target)]),
                PartKind::Target => (vec![name(a.camera)], vec![name(n1), name(n2)]),
            };
            out.push(LoopClosure {
                cameras,
                targets,
                compared: [name(n1), name(n2)],
                rotation_deg: rms_r,
                translation: rms_t,
                expected,
                poses: common.len(),
                change_sigmas,
                change_at,
                closes,
            });
        }
    }
    out
}

/// The largest change of the closures' median between the poses before a split and those after,
/// in standard errors, and the split (the first index of the later side): per component of the
/// rotation vector and of the translation; the norm over the 3 components, the larger of
/// rotation's and translation's.
///
/// Each side's median, as a PnP pose now and then far off (kinhec's small flange marker) moves a
/// mean; each component's noise from the mean square of its successive differences (von
/// Neumann's), a variance estimate that keeps the tails and the poses whose noise is larger (a
/// median of the differences made consistent kinhec loops change by 5.6 and 8.2 standard errors).
/// A step, a part knocked once, is one difference, δ²/(2(n − 1)) in the variance. The standard
/// error of a median of n normal values is √(π/2) σ/√n; for heavier tails it is smaller, so the
/// test is conservative there. `floor`: the noise (rotation radians, translation) below which
/// differences are rounding.
fn change(closure: &[Closure], floor: [f64; 2]) -> (f64, usize) {
    let n = closure.len();
    if n < 2 * MIN_SEGMENT {
        return (0.0, 0);
    }
    let median = crate::check::outliers::median;
    let mut best = (0.0, 0);
    for (part, &floor) in floor.iter().enumerate() {
        let value = |c: &Closure, j: usize| {
            if part == 0 { c.0[j] } else { c.1[j] }
        };
        let sigma: [f64; 3] = std::array::from_fn(|j| {
            let sum: f64 = closure
                .windows(2)
                .map(|w| (value(&w[1], j) - value(&w[0], j)).powi(2))
                .sum();
            (sum / (2.0 * (n - 1) as f64)).sqrt().max(floor)
        });
        for k in MIN_SEGMENT..=(n - MIN_SEGMENT) {
            let (a, b) = (k as f64, (n - k) as f64);
            let se = MEDIAN_EFFICIENCY * (1.0 / a + 1.0 / b).sqrt();
            let z: f64 = (0..3)
                .map(|j| {
                    let before = median(closure[..k].iter().map(|c| value(c, j)).collect());
                    let after = median(closure[k..].iter().map(|c| value(c, j)).collect());
                    ((before - after) / (sigma[j] * se)).powi(2)
                })
                .sum::<f64>()
                .sqrt();
            if z > best.0 {
                best = (z, k);
            }
        }
    }
    best
}

/// √(π/2): a median's standard error over a mean's, for normal values.
const MEDIAN_EFFICIENCY: f64 = 1.253_314_137_315_500_3;

/// The warning for loops that do not close: the part to blame (every loop of it fails, some
/// loop of each other part closes), or the parts of the failing loops together.
pub fn misfits(closures: &[LoopClosure]) -> Option<Warning> {
    let failing: Vec<&LoopClosure> = closures.iter().filter(|l| !l.closes).collect();
    if failing.is_empty() {
        return None;
    }
    let mut closing_parts: Vec<&str> = Vec::new();
    for l in closures.iter().filter(|l| l.closes) {
        closing_parts.extend(l.compared.iter().map(String::as_str));
    }
    let mut suspects: Vec<String> = Vec::new();
    let mut involved: Vec<String> = Vec::new();
    for l in &failing {
        for p in &l.compared {
            if !involved.contains(p) {
                involved.push(p.clone());
            }
            if !closing_parts.contains(&p.as_str()) && !suspects.contains(p) {
                suspects.push(p.clone());
            }
        }
    }
    let singled_out = !suspects.is_empty();
    let ratio = failing
        .iter()
        .map(|l| {
            (l.rotation_deg / l.expected.rotation_deg).max(l.translation / l.expected.translation)
        })
        .fold(0.0, f64::max);
    let change_sigmas = failing.iter().map(|l| l.change_sigmas).fold(0.0, f64::max);
    Some(Warning::LoopMisfit {
        parts: if singled_out { suspects } else { involved },
        singled_out,
        loops: failing
            .iter()
            .map(|l| format!("{} and {}", l.compared[0], l.compared[1]))
            .collect(),
        worst_ratio: ratio,
        change_sigmas,
    })
}
