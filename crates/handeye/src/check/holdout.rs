//! A held-out check of a calibration: each camera observation predicted from the others.
//!
//! For pose i, X and the fixed frame Y (the target in the base eye-in-hand, on the gripper
//! eye-to-hand) are solved from every other pose (all-pairs Andreff, [`PoseAccumulator`]), and the
//! observation is predicted as Ĉ_i = X⁻¹ H_i⁻¹ Y. The gap between Ĉ_i and the recorded C_i, in
//! degrees and in the input's unit (where the camera sees the target against where it should),
//! says how well the calibration predicts data it was not fitted to; a pose whose gap is far above
//! the others' is a frame paired with the wrong robot pose or a failed detection.
//!
//! Every pose is left out exactly, in O(n): the sums of the poses before pose i and of those
//! after it are merged (`accumulate::MergeableAccumulator`: the pairs across the cut from three
//! more per-pose sums), which equals adding the n − 1 others in order, to rounding. One pass forward
//! and one backward keep these sums at about √n checkpoints, and each block of √n poses between
//! two checkpoints makes its own (`exact_gaps`), so memory is O(√n): about 1,300 accumulators
//! (2 KB each) at 100,000 poses. Measured (in-process, 2 threads, simulated poses): 1.1 ms at
//! 200 poses, 2.2 ms at 1,000, 60 ms at 10,000, 0.45 s at 100,000 (from 1,000 poses on about 10
//! times the single all-pose solve that stood in for the others' beyond 300 poses before); the
//! whole `calibrate --pairs all` took 4 ms more CPU at 1,000 poses (70 against 66 ms) and 1% more
//! at 10,000 (4.94 against 4.88 s), so no size bound is needed. Until 2026-12-02
//! each pose was left out by adding the n − 1 others afresh (O(n²), exact only up to 300 poses).

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::check::outliers::{OUTLIER_FACTOR, median};
use crate::model::motion::{PosePair, Setup};
use crate::model::pose::{Transform, rotation_angle_between};
use crate::solve::accumulate::{MergeableAccumulator, PoseAccumulator};

/// The held-out gap of one pose.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HeldOutPose {
    /// Index of the pose in the input.
    pub pose: usize,
    /// Rotation between the predicted and the recorded observation, degrees.
    pub rotation_deg: f64,
    /// Distance between the predicted and the recorded target position in the camera, input
    /// units.
    pub translation: f64,
}

/// The held-out check of a set of poses.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeldOutCheck {
    /// Every pose's gap, in input order.
    pub poses: Vec<HeldOutPose>,
    /// Median gaps: the calibration's typical prediction error.
    pub median_rotation_deg: f64,
    /// See `median_rotation_deg`.
    pub median_translation: f64,
    /// Whether each pose was left out exactly: always, at every size (it was `false` beyond 300
    /// poses while the check was O(n²)); kept for the readers of the reports.
    pub exact: bool,
    /// Indices of the poses whose gap is above 6 times the median (rotation or translation).
    pub disagree: Vec<usize>,
}

/// The held-out check (module documentation); `None` when fewer than four poses, or when the
/// others do not determine X for some pose.
pub fn leave_one_out(poses: &[PosePair], setup: Setup) -> Option<HeldOutCheck> {
    let n = poses.len();
    if n < 4 {
        return None;
    }
    Some(summarised(exact_gaps(poses, setup)?, true))
}

/// Each pose's gap under X and Y from every other pose, in O(n) adds and merges (module
/// documentation). The poses are cut into blocks of about √n; one pass forward keeps the sums
/// before each block, one pass backward those after it. Each block then makes the sums after
/// each of its poses (merging one pose at a time in front of the block's suffix) and runs
/// forward with the sums before: for pose i, (poses 0..i) ⊕ (poses i+1..n) is exactly the n − 1
/// others in order. The blocks are spread over the threads and the gaps collected in input order
/// (the same result on any number of threads). Memory: about 2√n accumulators (~2 KB each) plus
/// √n per thread.
fn exact_gaps(poses: &[PosePair], setup: Setup) -> Option<Vec<HeldOutPose>> {
    let n = poses.len();
    let size = ((n as f64).sqrt().ceil() as usize).max(1);
    let blocks: Vec<&[PosePair]> = poses.chunks(size).collect();
    let sums_of = |block: &[PosePair]| {
        let mut acc = MergeableAccumulator::new(setup);
        block.iter().for_each(|p| acc.add(p));
        acc
    };
    // before[k]: the poses before block k; after[k]: the poses after it.
    let mut before = Vec::with_capacity(blocks.len());
    let mut running = MergeableAccumulator::new(setup);
    for block in &blocks {
        before.push(running.clone());
        running.merge(&sums_of(block));
    }
    let mut after = vec![MergeableAccumulator::new(setup); blocks.len()];
    for k in (1..blocks.len()).rev() {
        let mut sums = sums_of(blocks[k]);
        sums.merge(&after[k]);
        after[k - 1] = sums;
    }
    let per_block: Vec<Vec<HeldOutPose>> = blocks
        .par_iter()
        .enumerate()
        .map(|(k, block)| {
            // suffixes[j]: the block's poses after its j-th, then every later block.
            let mut suffixes = vec![after[k].clone(); block.len()];
            for j in (0..block.len() - 1).rev() {
                let mut sums = MergeableAccumulator::new(setup);
                sums.add(&block[j + 1]);
                sums.merge(&suffixes[j + 1]);
                suffixes[j] = sums;
            }
            let mut prefix = before[k].clone();
            block
                .iter()
                .zip(&suffixes)
                .enumerate()
                .map(|(j, (pose, suffix))| {
                    let mut others = prefix.clone();
                    others.merge(suffix);
                    prefix.add(pose);
                    let (x, y) = solution(others.accumulator())?;
                    Some(gap(k * size + j, pose, setup, &x, &y))
                })
                .collect()
        })
        .collect::<Option<_>>()?;
    Some(per_block.into_iter().flatten().collect())
}

/// Pose i's gap: its recorded observation against the one X and Y predict.
fn gap(i: usize, pose: &PosePair, setup: Setup, x: &Transform, y: &Transform) -> HeldOutPose {
    let hand = setup.hand_pose(&pose.base_from_gripper);
    let predicted: Transform = x.inverse() * hand.inverse() * y;
    HeldOutPose {
        pose: i,
        rotation_deg: rotation_angle_between(
            &predicted.rotation,
            &pose.camera_from_target.rotation,
        )
        .to_degrees(),
        translation: (predicted.translation.vector - pose.camera_from_target.translation.vector)
            .norm(),
    }
}

/// The check from every pose's gap.
fn summarised(gaps: Vec<HeldOutPose>, exact: bool) -> HeldOutCheck {
    let median_rotation_deg = median(gaps.iter().map(|g| g.rotation_deg).collect());
    let median_translation = median(gaps.iter().map(|g| g.translation).collect());
    let disagree = gaps
        .iter()
        .filter(|g| {
            g.rotation_deg > OUTLIER_FACTOR * median_rotation_deg.max(1e-9)
                || g.translation > OUTLIER_FACTOR * median_translation.max(1e-12)
        })
        .map(|g| g.pose)
        .collect();
    HeldOutCheck {
        poses: gaps,
        median_rotation_deg,
        median_translation,
        exact,
        disagree,
    }
}

/// X and Y from accumulated sums.
fn solution(acc: &PoseAccumulator) -> Option<(Transform, Transform)> {
    let x = acc.estimate()?.x;
    Some((x, acc.residual_scatter(&x)?.y))
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use nalgebra::Matrix4;
    use serde_json::Value;

    use super::*;
    use crate::model::pose::{transform_from_matrix4, transform_from_xyz_quat_xyzw};
    use crate::sim::{SimConfig, simulate};

    /// The pose pairs of a kinhec JSON Lines file (4×4 matrices, or translation and quaternion
    /// objects), read here rather than through `io`, a layer above this one; `None` for a file
    /// with a pose that is not a rigid transform (which the readers refuse too).
    fn read_kinhec(path: &Path) -> Option<Vec<PosePair>> {
        let transform = |v: &Value| match v {
            Value::Array(rows) => {
                let m: Vec<f64> = rows
                    .iter()
                    .flat_map(|r| r.as_array().into_iter().flatten().filter_map(Value::as_f64))
                    .collect();
                (m.len() == 16)
                    .then(|| transform_from_matrix4(&Matrix4::from_row_slice(&m)).ok())?
            }
            Value::Object(o) => {
                let numbers = |key: &str| -> Option<Vec<f64>> {
                    o.get(key)?.as_array()?.iter().map(Value::as_f64).collect()
                };
                let (t, q) = (numbers("translation")?, numbers("quaternion_xyzw")?);
                transform_from_xyz_quat_xyzw([t[0], t[1], t[2]], [q[0], q[1], q[2], q[3]]).ok()
            }
            _ => None,
        };
        let text = std::fs::read_to_string(path).ok()?;
        text.lines()
            .filter(|l| !l.trim().is_empty())
            .map(|line| {
                let v: Value = serde_json::from_str(line).ok()?;
                Some(PosePair {
                    base_from_gripper: transform(&v["base_from_gripper"])?,
                    camera_from_target: transform(&v["camera_from_target"])?,
                })
            })
            .collect()
    }

    /// X and Y from the poses.
    fn solved(poses: &[PosePair], setup: Setup) -> Option<(Transform, Transform)> {
        solution(&PoseAccumulator::of(poses, setup))
    }

    /// The check as it was made before the O(n) one: each pose left out by adding the n − 1
    /// others to a fresh accumulator (O(n²); exact up to the old bound of 300 poses).
    fn leave_one_out_quadratic(poses: &[PosePair], setup: Setup) -> Option<HeldOutCheck> {
        let n = poses.len();
        if n < 4 {
            return None;
        }
        let exact = n <= 300;
        let all = solved(poses, setup);
        let gaps: Vec<HeldOutPose> = poses
            .par_iter()
            .enumerate()
            .map(|(i, pose)| {
                let (x, y) = if exact {
                    let others: Vec<PosePair> = poses
                        .iter()
                        .enumerate()
                        .filter(|(k, _)| *k != i)
                        .map(|(_, p)| *p)
                        .collect();
                    solved(&others, setup)?
                } else {
                    all?
                };
                Some(gap(i, pose, setup, &x, &y))
            })
            .collect::<Option<_>>()?;
        Some(summarised(gaps, exact))
    }

    /// camodocal's OpenCV-YAML pairs as `io` reads them: `T1_i` = `gripper_from_base` and
    /// `T2_i` = `target_from_camera`, inverted into a pose pair.
    fn read_camodocal(path: &Path) -> Vec<PosePair> {
        let text = std::fs::read_to_string(path).unwrap();
        let matrices: Vec<Transform> = text
            .split("data: [")
            .skip(1)
            .map(|block| {
                let numbers: Vec<f64> = block[..block.find(']').unwrap()]
                    .split(',')
                    .map(|v| v.trim().parse().unwrap())
                    .collect();
                transform_from_matrix4(&Matrix4::from_row_slice(&numbers)).unwrap()
            })
            .collect();
        assert!(text.contains("T1_0") && matrices.len().is_multiple_of(2));
        matrices
            .chunks(2)
            .map(|m| PosePair {
                base_from_gripper: m[0].inverse(),
                camera_from_target: m[1].inverse(),
            })
            .collect()
    }

    /// Real and simulated series with their setups: the kinhec suite (its pose files and its
    /// mistakes, which have poses that disagree), the camodocal recording, and simulated series
    /// of 4 to 300 poses, one of them with a pose paired with the wrong robot pose.
    fn series() -> Vec<(String, Vec<PosePair>, Setup)> {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata");
        let mut out = Vec::new();
        for dir in ["kinhec/pairs", "kinhec/mistakes"] {
            let mut files: Vec<_> = std::fs::read_dir(root.join(dir))
                .unwrap()
                .map(|e| e.unwrap().path())
                .filter(|p| p.extension().is_some_and(|e| e == "jsonl"))
                .collect();
            files.sort();
            for path in files {
                let name = path.file_name().unwrap().to_string_lossy().into_owned();
                let setup = if name.contains("_eth") {
                    Setup::EyeToHand
                } else {
                    Setup::EyeInHand
                };
                if let Some(pairs) = read_kinhec(&path) {
                    out.push((name, pairs, setup));
                }
            }
        }
        if let Some(camodocal) =
            crate::model::shared_data::shared("camodocal/TransformPairsInput.yml")
        {
            out.push((
                "camodocal".into(),
                read_camodocal(&camodocal),
                Setup::EyeInHand,
            ));
        }
        for (poses, seed) in [(4, 1), (5, 2), (17, 3), (120, 4), (300, 5)] {
            let config = SimConfig {
                poses,
                ..SimConfig::default()
            };
            let mut noisy = simulate(&config, seed, 0).poses;
            out.push((format!("sim {poses}"), noisy.clone(), Setup::EyeInHand));
            let flipped = noisy
                .iter()
                .map(|q| PosePair {
                    base_from_gripper: q.base_from_gripper.inverse(),
                    camera_from_target: q.camera_from_target,
                })
                .collect();
            out.push((
                format!("sim {poses} eye-to-hand"),
                flipped,
                Setup::EyeToHand,
            ));
            if poses > 10 {
                noisy[poses / 3].base_from_gripper = noisy[poses / 2].base_from_gripper;
                out.push((format!("sim {poses} mispaired"), noisy, Setup::EyeInHand));
            }
        }
        out
    }

    fn solved_conditioning(poses: &[PosePair], setup: Setup) -> f64 {
        PoseAccumulator::of(poses, setup)
            .rotation_system()
            .solve()
            .conditioning
    }

    #[test]
    fn equals_leaving_each_pose_out_by_adding_the_others() {
        let mut compared = 0;
        let mut disagreeing = 0;
        let mut worst = 0.0f64;
        for (name, poses, setup) in series() {
            let ours = leave_one_out(&poses, setup);
            let reference = leave_one_out_quadratic(&poses, setup);
            let (Some(ours), Some(reference)) = (&ours, &reference) else {
                assert_eq!(ours.is_some(), reference.is_some(), "{name}");
                continue;
            };
            assert_eq!(ours.exact, reference.exact, "{name}");
            assert_eq!(ours.disagree, reference.disagree, "{name}");
            assert_eq!(ours.poses.len(), reference.poses.len(), "{name}");
            // Relative, with a floor for the noise-free series, whose gaps are themselves rounding:
            // 1e-3 degrees and 1e-3 input units (a micrometre in millimetres).
            let relative = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-3);
            let conditioning = solved_conditioning(&poses, setup);
            let mut series_worst = 0.0f64;
            for (a, b) in ours.poses.iter().zip(&reference.poses) {
                assert_eq!(a.pose, b.pose, "{name}");
                let d = relative(a.rotation_deg, b.rotation_deg)
                    .max(relative(a.translation, b.translation));
                assert!(
                    d.is_finite(),
                    "{name}, pose {}: {a:?} against {b:?}",
                    a.pose
                );
                series_worst = series_worst.max(d);
            }
            // Measured: at most 7e-11 where the rotation system's conditioning is 1e-2 or more
            // (88 of the 100 series); up to 1.1e-7 on the kinhec suite's degenerate series
            // (parallel axes, a single joint: conditioning 3e-3 to 8e-3), where X's translation
            // along the common axis is not determined and rounding is amplified by the inverse
            // conditioning squared, as for every linear solve (tests/all_pairs.rs).
            let tolerance = if conditioning >= 1e-2 { 1e-9 } else { 1e-6 };
            assert!(
                series_worst <= tolerance,
                "{name} (conditioning {conditioning:e}): gaps differ by {series_worst:e}"
            );
            worst = worst.max(series_worst);
            compared += 1;
            disagreeing += usize::from(!ours.disagree.is_empty());
        }
        eprintln!(
            "{compared} series compared, {disagreeing} with poses that disagree; worst relative difference {worst:e}"
        );
        assert!(
            compared >= 90 && disagreeing >= 10,
            "{compared} {disagreeing}"
        );
    }

    #[test]
    fn every_block_size_gives_the_gaps_in_input_order() {
        // n = 4..=12 covers blocks that divide n and the last block being short.
        let s = simulate(&SimConfig::default(), 8, 0);
        for n in 4..=12 {
            let poses = &s.poses[..n];
            let ours = leave_one_out(poses, Setup::EyeInHand).unwrap();
            let reference = leave_one_out_quadratic(poses, Setup::EyeInHand).unwrap();
            let order: Vec<usize> = ours.poses.iter().map(|g| g.pose).collect();
            assert_eq!(order, (0..n).collect::<Vec<_>>());
            for (a, b) in ours.poses.iter().zip(&reference.poses) {
                assert!(
                    (a.translation - b.translation).abs() <= 1e-9 * b.translation,
                    "{n}: {a:?} {b:?}"
                );
            }
        }
    }
}
