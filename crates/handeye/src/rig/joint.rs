//! The joint solve of a rig: a linear start per determined part of the graph, one
//! Levenberg–Marquardt refinement over every observation, and each part's bootstrap uncertainty.

use nalgebra::{DMatrix, DVector, Matrix3, SMatrix, SVector, Vector3, Vector6};
use rayon::prelude::*;

use crate::check::outliers::{median, translation_scale};
use crate::check::uncertainty::{Uncertainty, few_poses_factor, summarise, wild_signs};
use crate::model::error::Result;
use crate::model::motion::{PosePair, Setup};
use crate::model::pose::{
    Transform, exp_so3, log_so3, proj_so3, rotation_matrix, skew, transform_from_parts,
};
use crate::model::warning::{SHOWN, Warning};
use crate::rig::graph::{Graph, Solvable};
use crate::rig::{Residual, RigOptions, RigRecording};
use crate::solve::RefineOptions;
use crate::solve::lm::{DynLeastSquares, DynLinearisation, levenberg_marquardt_dyn};
use crate::solve::residual::BlockRms;
use crate::solve::robot_world::{pose_length_scale, pose_residual};

/// The bootstrap's seed: results are reproducible run to run.
const SEED: u64 = 0x5EED_0516_0001;

/// An observation is far off when its error exceeds this many times the median of its camera–
/// target pair's (as the held-out check's poorly predicted poses).
pub const FAR_OFF: f64 = 6.0;

/// Observations a pair needs before any of them is called far off.
const MIN_FAR_OFF: usize = 5;

/// Errors below these are rounding, never far off: degrees, and a fraction of the scene.
const FAR_OFF_FLOOR_DEG: f64 = 1e-6;
/// See [`FAR_OFF_FLOOR_DEG`].
const FAR_OFF_FLOOR_RELATIVE: f64 = 1e-9;

/// One solved camera or target.
#[derive(Debug, Clone, PartialEq)]
pub struct PartSolution {
    /// Its pose in its mount's frame.
    pub pose: Transform,
    /// Its bootstrap one-sigma.
    pub uncertainty: Uncertainty,
    /// Observations of it used.
    pub observations: usize,
    /// RMS of its observations' errors at the solution.
    pub residual: Residual,
}

/// The joint solution.
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// Per node: its solution, `None` when undetermined.
    pub parts: Vec<Option<PartSolution>>,
    /// Observations used.
    pub observations: usize,
    /// The observations used (indices into the recording's).
    pub used: Vec<usize>,
    /// Every bootstrap replicate's pose per node (the solution's own for an undetermined node).
    pub replicates: Vec<Vec<Transform>>,
    /// The scene's size: the spread of the hand's positions, input units.
    pub scene: f64,
}

impl Solution {
    /// The pose of a node (identity when undetermined; callers use determined nodes only).
    pub fn pose(&self, node: usize) -> Transform {
        self.parts[node]
            .as_ref()
            .map_or_else(Transform::identity, |p| p.pose)
    }
}

/// H_k = `mount_t_from_mount_c` at the observation's pose: B(m_t, i)⁻¹ B(m_c, i).
fn hand(graph: &Graph, recording: &RigRecording, k: usize) -> Transform {
    let o = &recording.observations[k];
    let e = &graph.edges[graph.edge_of[k]];
    graph.base_from_mount(recording, e.target, o.pose).inverse()
        * graph.base_from_mount(recording, e.camera, o.pose)
}

/// The nearest rotation to the sum of the rotations, and the mean translation.
fn mean_pose(poses: &[Transform]) -> Transform {
    let mut r = Matrix3::zeros();
    let mut t = Vector3::zeros();
    for p in poses {
        r += rotation_matrix(p);
        t += p.translation.vector;
    }
    transform_from_parts(&proj_so3(&r), &(t / poses.len().max(1) as f64))
}

/// The linear start: each component's anchor from Shah's closed form, every other node from its
/// observations of a known one (H X C = Y, averaged over them), until all are known.
fn start(graph: &Graph, recording: &RigRecording, solvable: &Solvable) -> Vec<Option<Transform>> {
    let mut known: Vec<Option<Transform>> = vec![None; graph.nodes.len()];
    for c in &solvable.determined {
        let anchor = &graph.edges[c.anchor];
        known[anchor.camera] = Some(c.start.x);
        known[anchor.target] = Some(c.start.target);
        loop {
            let mut progress = false;
            for &e in &c.edges {
                let edge = &graph.edges[e];
                let hc = |k: usize| {
                    (
                        hand(graph, recording, k),
                        recording.observations[k].camera_from_target,
                    )
                };
                match (known[edge.camera], known[edge.target]) {
                    (Some(x), None) => {
                        let ys: Vec<Transform> = edge
                            .observations
                            .iter()
                            .map(|&k| {
                                let (h, c) = hc(k);
                                h * x * c
                            })
                            .collect();
                        known[edge.target] = Some(mean_pose(&ys));
                        progress = true;
                    }
                    (None, Some(y)) => {
                        let xs: Vec<Transform> = edge
                            .observations
                            .iter()
                            .map(|&k| {
                                let (h, c) = hc(k);
                                h.inverse() * y * c.inverse()
                            })
                            .collect();
                        known[edge.camera] = Some(mean_pose(&xs));
                        progress = true;
                    }
                    _ => {}
                }
            }
            if !progress {
                break;
            }
        }
    }
    known
}

/// The least-squares problem in the data's length unit.
struct Problem {
    /// Per observation used: (H, C) scaled, the camera's and the target's parameter slot, and
    /// its edge's weights.
    terms: Vec<Term>,
    /// Parameter slots (determined nodes).
    slots: usize,
}

#[derive(Clone, Copy)]
struct Term {
    h: Transform,
    c: Transform,
    camera: usize,
    target: usize,
    weights: [f64; 2],
}

type State = Vec<(Matrix3<f64>, Vector3<f64>)>;

impl Term {
    fn residual(&self, s: &State) -> (Matrix3<f64>, Vector3<f64>) {
        let (r_x, t_x) = &s[self.camera];
        let (r_y, t_y) = &s[self.target];
        pose_residual(&self.h, &self.c, (r_x, t_x), (r_y, t_y))
    }

    /// The weighted 12×12 Jacobian over (δ_X, t_X, δ_Y, t_Y) and the weighted residuals, as the
    /// robot-world refinement's: ∂ΔR/∂δ_X,m = R_H R_X [e_m]× R_C, ∂ΔR/∂δ_Y,m = −R_Y [e_m]×,
    /// ∂ΔT/∂δ_X,m = R_H R_X [e_m]× t_C, ∂ΔT/∂t_X = R_H, ∂ΔT/∂t_Y = −I.
    fn jacobian(&self, s: &State) -> (SMatrix<f64, 12, 12>, SVector<f64, 12>) {
        let (r_x, _) = &s[self.camera];
        let (r_y, _) = &s[self.target];
        let r_h = rotation_matrix(&self.h);
        let r_c = rotation_matrix(&self.c);
        let t_c = self.c.translation.vector;
        let hx = r_h * r_x;
        let (dr, dt) = self.residual(s);
        let w = self.weights;
        let mut j = SMatrix::<f64, 12, 12>::zeros();
        let mut r = SVector::<f64, 12>::zeros();
        for m in 0..3 {
            let e = skew(&Vector3::ith(m, 1.0));
            let dx_r = hx * e * r_c * w[0];
            let dy_r = -(r_y * e) * w[0];
            let dx_t = hx * e * t_c * w[1];
            for row in 0..3 {
                for col in 0..3 {
                    j[(3 * row + col, m)] = dx_r[(row, col)];
                    j[(3 * row + col, 6 + m)] = dy_r[(row, col)];
                }
                j[(9 + row, m)] = dx_t[row];
            }
        }
        j.fixed_view_mut::<3, 3>(9, 3).copy_from(&(r_h * w[1]));
        j.fixed_view_mut::<3, 3>(9, 9)
            .copy_from(&(-Matrix3::identity() * w[1]));
        for row in 0..3 {
            for col in 0..3 {
                r[3 * row + col] = dr[(row, col)] * w[0];
            }
            r[9 + row] = dt[row] * w[1];
        }
        (j, r)
    }
}

impl DynLeastSquares for Problem {
    type State = State;

    fn linearise(&self, s: &State) -> DynLinearisation {
        let n = 6 * self.slots;
        let mut jtj = DMatrix::zeros(n, n);
        let mut jtr = DVector::zeros(n);
        let mut cost = 0.0;
        for term in &self.terms {
            let (j, r) = term.jacobian(s);
            let jtj_local = j.transpose() * j;
            let jtr_local = j.transpose() * r;
            let at = [6 * term.camera, 6 * term.target];
            for (bi, &oi) in at.iter().enumerate() {
                for a in 0..6 {
                    jtr[oi + a] += jtr_local[6 * bi + a];
                    for (bj, &oj) in at.iter().enumerate() {
                        for b in 0..6 {
                            jtj[(oi + a, oj + b)] += jtj_local[(6 * bi + a, 6 * bj + b)];
                        }
                    }
                }
            }
            cost += 0.5 * r.norm_squared();
        }
        DynLinearisation { jtj, jtr, cost }
    }

    fn step(&self, s: &State, delta: &DVector<f64>) -> State {
        s.iter()
            .enumerate()
            .map(|(i, (r, t))| {
                let d = delta.fixed_rows::<3>(6 * i).into_owned();
                (
                    proj_so3(&(r * exp_so3(&d))),
                    t + delta.fixed_rows::<3>(6 * i + 3),
                )
            })
            .collect()
    }

    fn cost(&self, s: &State) -> f64 {
        0.5 * self
            .terms
            .iter()
            .map(|term| {
                let (dr, dt) = term.residual(s);
                let w = term.weights;
                w[0] * w[0] * dr.norm_squared() + w[1] * w[1] * dt.norm_squared()
            })
            .sum::<f64>()
    }

    fn size(&self, s: &State) -> f64 {
        1.0 + s.iter().map(|(_, t)| t.norm()).sum::<f64>()
    }
}

/// The observation's error at the solution: E = Ĉ⁻¹ C (the predicted against the seen
/// `camera_from_target`, in the target's frame), with Ĉ = X⁻¹ H⁻¹ Y.
fn predicted(h: &Transform, x: &Transform, y: &Transform) -> Transform {
    x.inverse() * h.inverse() * y
}

/// Solves every determined part jointly, with each part's bootstrap uncertainty.
pub fn solve(
    recording: &RigRecording,
    graph: &Graph,
    solvable: &Solvable,
    options: &RigOptions,
) -> Result<Solution> {
    let start = start(graph, recording, solvable);
    // Parameter slots of the determined nodes.
    let mut slot = vec![usize::MAX; graph.nodes.len()];
    let mut slots = 0;
    for (n, s) in start.iter().enumerate() {
        if s.is_some() {
            slot[n] = slots;
            slots += 1;
        }
    }
    let used: Vec<usize> = (0..recording.observations.len())
        .filter(|&k| {
            let e = &graph.edges[graph.edge_of[k]];
            start[e.camera].is_some() && start[e.target].is_some()
        })
        .collect();
    let hc: Vec<(Transform, Transform)> = used
        .iter()
        .map(|&k| {
            (
                hand(graph, recording, k),
                recording.observations[k].camera_from_target,
            )
        })
        .collect();
    let unit = pose_length_scale(&hc);
    let scaled = |t: &Transform| {
        let mut t = *t;
        t.translation.vector /= unit;
        t
    };
    let state: State = start
        .iter()
        .flatten()
        .map(|p| (rotation_matrix(p), p.translation.vector / unit))
        .collect();
    // Each edge's blocks weighted by their RMS at the start (SPEC sec. 3's two blocks).
    let mut rms = vec![BlockRms::default(); graph.edges.len()];
    let mut terms: Vec<Term> = used
        .iter()
        .zip(&hc)
        .map(|(&k, (h, c))| {
            let e = &graph.edges[graph.edge_of[k]];
            Term {
                h: scaled(h),
                c: scaled(c),
                camera: slot[e.camera],
                target: slot[e.target],
                weights: [1.0, 1.0],
            }
        })
        .collect();
    for (term, &k) in terms.iter().zip(&used) {
        let (dr, dt) = term.residual(&state);
        rms[graph.edge_of[k]].add(&dr, &dt);
    }
    for (term, &k) in terms.iter_mut().zip(&used) {
        let s = rms[graph.edge_of[k]].scales();
        term.weights = [1.0 / s[0], 1.0 / s[1]];
    }
    let problem = Problem { terms, slots };
    let lm = RefineOptions::default();
    let end = levenberg_marquardt_dyn(&problem, state, &lm).state;
    let unscale = |s: &State| -> Vec<Transform> {
        s.iter()
            .map(|(r, t)| transform_from_parts(r, &(t * unit)))
            .collect()
    };
    let solved = unscale(&end);

    // The wild bootstrap: each observation rebuilt to agree with the solution, its own error put
    // back or inverted, one sign per robot pose (shared by every observation made there).
    let errors: Vec<Transform> = problem
        .terms
        .iter()
        .map(|t| {
            predicted(
                &t.h,
                &transform_of(&end, t.camera),
                &transform_of(&end, t.target),
            )
            .inverse()
                * t.c
        })
        .collect();
    let poses_used = {
        let mut p: Vec<usize> = used
            .iter()
            .map(|&k| recording.observations[k].pose)
            .collect();
        p.sort_unstable();
        p.dedup();
        p.len()
    };
    let n = used.len() as f64;
    let inflate = if n > slots as f64 + 1.0 {
        (n / (n - slots as f64)).sqrt()
    } else {
        2.0
    };
    let replicates: Vec<Vec<Transform>> = (0..options.replicates)
        .into_par_iter()
        .map(|b| {
            let signs = wild_signs(SEED ^ b as u64, recording.poses.len(), inflate);
            let terms: Vec<Term> = problem
                .terms
                .iter()
                .zip(&errors)
                .zip(&used)
                .map(|((t, e), &k)| {
                    let s = signs[recording.observations[k].pose];
                    let w = log_so3(&rotation_matrix(e)) * s;
                    let e = transform_from_parts(&exp_so3(&w), &(e.translation.vector * s));
                    Term {
                        c: predicted(
                            &t.h,
                            &transform_of(&end, t.camera),
                            &transform_of(&end, t.target),
                        ) * e,
                        ..*t
                    }
                })
                .collect();
            let replicate = Problem { terms, slots };
            unscale(&levenberg_marquardt_dyn(&replicate, end.clone(), &lm).state)
        })
        .collect();

    let hands: Vec<PosePair> = recording
        .poses
        .iter()
        .map(|q| PosePair {
            base_from_gripper: *q,
            camera_from_target: Transform::identity(),
        })
        .collect();
    let scene = translation_scale(&hands, Setup::EyeInHand);
    let widen = few_poses_factor(poses_used);
    let mut parts: Vec<Option<PartSolution>> = vec![None; graph.nodes.len()];
    for node in 0..graph.nodes.len() {
        if slot[node] == usize::MAX {
            continue;
        }
        let x = solved[slot[node]];
        let mut cov = nalgebra::Matrix6::zeros();
        for r in &replicates {
            let e = error_of(&r[slot[node]], &x) * widen;
            cov += e * e.transpose();
        }
        cov /= replicates.len().max(1) as f64;
        let mut uncertainty = summarise(cov, replicates.len(), 0, scene);
        uncertainty.samples = replicates
            .iter()
            .map(|r| {
                let e = error_of(&r[slot[node]], &x) * widen;
                [e[0], e[1], e[2], e[3], e[4], e[5]]
            })
            .collect();
        let mut sum = [0.0; 2];
        let mut count = 0usize;
        for (&k, e) in used.iter().zip(&errors) {
            let edge = &graph.edges[graph.edge_of[k]];
            if edge.camera == node || edge.target == node {
                let (angle, t) = error_sizes(e, unit);
                sum[0] += angle * angle;
                sum[1] += t * t;
                count += 1;
            }
        }
        let c = count.max(1) as f64;
        parts[node] = Some(PartSolution {
            pose: x,
            uncertainty,
            observations: count,
            residual: Residual {
                rotation_deg: (sum[0] / c).sqrt(),
                translation: (sum[1] / c).sqrt(),
            },
        });
    }
    let by_node = |poses: &[Transform]| -> Vec<Transform> {
        (0..graph.nodes.len())
            .map(|n| {
                if slot[n] == usize::MAX {
                    Transform::identity()
                } else {
                    poses[slot[n]]
                }
            })
            .collect()
    };
    Ok(Solution {
        parts,
        observations: used.len(),
        used,
        replicates: replicates.iter().map(|r| by_node(r)).collect(),
        scene,
    })
}

fn transform_of(s: &State, slot: usize) -> Transform {
    transform_from_parts(&s[slot].0, &s[slot].1)
}

/// An error transform's rotation angle (degrees) and translation length (input units, from the
/// scaled problem's `unit`).
fn error_sizes(e: &Transform, unit: f64) -> (f64, f64) {
    (
        log_so3(&rotation_matrix(e)).norm().to_degrees(),
        e.translation.vector.norm() * unit,
    )
}

/// The error of a replicate: (log(R_b R̂ᵀ), t_b − t̂), as the single-camera bootstrap's.
pub(crate) fn error_of(xb: &Transform, x: &Transform) -> Vector6<f64> {
    let dr = log_so3(&(xb.rotation.matrix() * x.rotation.matrix().transpose()));
    let dt = xb.translation.vector - x.translation.vector;
    Vector6::new(dr.x, dr.y, dr.z, dt.x, dt.y, dt.z)
}

/// Observations far off their pair's others (a bad detection, a pose paired with the wrong
/// image): each error against [`FAR_OFF`] times its camera–target pair's median, as a
/// [`Warning::PoorlyPredicted`] naming them.
pub fn far_off(recording: &RigRecording, graph: &Graph, solution: &Solution) -> Option<Warning> {
    let sizes: Vec<(usize, f64, f64)> = solution
        .used
        .iter()
        .map(|&k| {
            let o = &recording.observations[k];
            let e = &graph.edges[graph.edge_of[k]];
            let h = hand(graph, recording, k);
            let p = predicted(&h, &solution.pose(e.camera), &solution.pose(e.target));
            let err = p.inverse() * o.camera_from_target;
            let (a, t) = error_sizes(&err, 1.0);
            (k, a, t)
        })
        .collect();
    let mut off = Vec::new();
    for (e, edge) in graph.edges.iter().enumerate() {
        let mine: Vec<&(usize, f64, f64)> =
            sizes.iter().filter(|s| graph.edge_of[s.0] == e).collect();
        if mine.len() < MIN_FAR_OFF || edge.observations.len() < MIN_FAR_OFF {
            continue;
        }
        let ma = median(mine.iter().map(|s| s.1).collect());
        let mt = median(mine.iter().map(|s| s.2).collect());
        let limit_a = (FAR_OFF * ma).max(FAR_OFF_FLOOR_DEG);
        let limit_t = (FAR_OFF * mt).max(FAR_OFF_FLOOR_RELATIVE * solution.scene.max(1e-300));
        for s in mine {
            if s.1 > limit_a || s.2 > limit_t {
                off.push(s.0);
            }
        }
    }
    if off.is_empty() {
        return None;
    }
    off.sort_unstable();
    let all_a = median(sizes.iter().map(|s| s.1).collect());
    let all_t = median(sizes.iter().map(|s| s.2).collect());
    Some(Warning::PoorlyPredicted {
        count: off.len(),
        median_rotation_deg: all_a,
        median_translation: all_t,
        shown: off
            .iter()
            .take(SHOWN)
            .map(|&k| {
                let o = &recording.observations[k];
                let name = recording
                    .names
                    .get(o.pose)
                    .cloned()
                    .unwrap_or_else(|| format!("pose {}", o.pose + 1));
                format!("{name} (camera `{}` seeing `{}`)", o.camera, o.target)
            })
            .collect(),
    })
}
