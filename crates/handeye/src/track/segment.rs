//! One segment of the stream: its all-pairs sums, the halves of the split-half uncertainty and
//! the checkpoints of the drift term.

use serde::{Deserialize, Serialize};

use super::{Pending, RobotWorldPair, TrackEstimate, TrackOptions, TrackPrior};
use crate::check::precision::{resolution, rotation_resolution};
use crate::check::readings::LEAST_TURN_DEG;
use crate::check::uncertainty::point_sigma;
use crate::model::motion::{PosePair, Setup};
use crate::model::pose::{Transform, rotation_angle_between};
use crate::model::prior::Prior;
use crate::solve::accumulate::{PoseAccumulator, Scatter};
use crate::solve::low_dof_accumulate::{LowDofAccumulator, OneAxis};
use crate::solve::robot_world_accumulate::RobotWorldAccumulator;

/// The low-DOF sums of a segment, kept when the tracker was given priors: the pose-form sums of
/// all poses and of the two halves ([`LowDofAccumulator`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(super) struct LowDofSums {
    all: LowDofAccumulator,
    halves: [LowDofAccumulator; 2],
    /// The priors in the poses' length unit; `None` until the unit is told.
    pub(super) priors: Option<Vec<Prior>>,
}

/// An estimate with what the tracker needs to judge by it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub(super) struct Snapshot {
    pub(super) estimate: TrackEstimate,
    pub(super) scatter: Scatter,
    /// The uncertainty without the drift term (split-half and first-order), rotation in degrees
    /// and translation: whether the poses so far fix X at all, as a challenger needs.
    pub(super) local: Option<(f64, f64)>,
}

/// All-pairs sums of one segment, with the two halves of the split-half uncertainty.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(super) struct Segment {
    pub(super) all: PoseAccumulator,
    pub(super) halves: [PoseAccumulator; 2],
    /// Shah's robot-world sums over the same poses.
    pub(super) robot_world: RobotWorldAccumulator,
    pub(super) since: usize,
    /// The first accepted hand rotation and the largest rotation from it (radians).
    pub(super) first: Option<Transform>,
    pub(super) largest: f64,
    /// Earlier estimates (pose count, X), each at 1.5 times the count of the one before, those of
    /// at least a quarter of the poses now.
    pub(super) checkpoints: Vec<(usize, Transform)>,
    /// The local uncertainty of each checkpoint's estimate (rotation in degrees, translation), in
    /// the order of `checkpoints`, when it was above the reporting bounds: a checkpoint whose own
    /// estimate was not determined (the poses before it stood still or turned about one axis)
    /// differs from the estimate now by its own error, which is no drift. (Empty in a state saved
    /// before it: every checkpoint counts as determined.)
    #[serde(default)]
    pub(super) checkpoint_local: Vec<Option<(f64, f64)>>,
    /// The low-DOF sums, when the tracker has priors (`None` without: nothing more per pose).
    #[serde(default)]
    pub(super) low: Option<LowDofSums>,
}

impl Segment {
    /// `priors`: `None` without priors; else the priors in the poses' unit once it is told
    /// (`Some(None)` before).
    pub(super) fn new(setup: Setup, since: usize, priors: Option<Option<Vec<Prior>>>) -> Self {
        Self {
            all: PoseAccumulator::new(setup),
            halves: [PoseAccumulator::new(setup), PoseAccumulator::new(setup)],
            robot_world: RobotWorldAccumulator::new(setup),
            since,
            first: None,
            largest: 0.0,
            checkpoints: Vec::new(),
            checkpoint_local: Vec::new(),
            low: priors.map(|priors| LowDofSums {
                all: LowDofAccumulator::new(setup),
                halves: [LowDofAccumulator::new(setup), LowDofAccumulator::new(setup)],
                priors,
            }),
        }
    }

    pub(super) fn add(&mut self, pose: &PosePair) {
        let hand = self.all.setup().hand_pose(&pose.base_from_gripper);
        let first = *self.first.get_or_insert(hand);
        self.largest = self
            .largest
            .max(rotation_angle_between(&first.rotation, &hand.rotation));
        self.all.add(pose);
        self.halves[self.all.poses() % 2].add(pose);
        if let Some(low) = &mut self.low {
            low.all.add(pose);
            low.halves[self.all.poses() % 2].add(pose);
        }
        self.robot_world.add(pose);
    }

    /// The common axis of the segment's hand rotations when they turn about one axis (a low-DOF
    /// robot), with the prior on its free component when one is given (in the poses' unit); from
    /// the all-pairs sums (Σ R_k and the first rotation), so without priors too.
    pub(super) fn low_dof(&self) -> Option<(OneAxis, Option<Prior>)> {
        let first = self.first?;
        let axis = OneAxis::of_hand(
            &self.all.rotation_sum(),
            first.rotation.matrix(),
            self.all.poses(),
        )
        .filter(OneAxis::is_low_dof)?;
        let prior = self
            .low
            .as_ref()
            .and_then(|l| l.priors.as_ref())
            .zip(axis.common().free_component())
            .and_then(|(priors, c)| priors.iter().find(|p| p.component == c).copied());
        Some((axis, prior))
    }

    /// The low-DOF sums and the prior to solve with, when the segment is low-DOF and a prior
    /// covers its free component: the tracker's low-DOF solve then replaces all-pairs Andreff.
    fn low_dof_plan(&self) -> Option<(&LowDofSums, OneAxis, Prior)> {
        let (axis, prior) = self.low_dof()?;
        Some((self.low.as_ref()?, axis, prior?))
    }

    /// A low-DOF robot with no prior on its free component (once the priors' unit is told, when
    /// some were given): the prior to give, in the batch refusal's words.
    fn wants_prior(&self) -> Option<Pending> {
        let (axis, None) = self.low_dof()? else {
            return None;
        };
        self.low
            .as_ref()
            .is_none_or(|l| l.priors.is_some())
            .then(|| Pending::LowDof {
                axis: axis.common().upward(),
                spread_deg: axis.spread.to_degrees(),
                setup: self.all.setup(),
                prior: axis.common().free_component(),
            })
    }

    /// Whether the segment is solved by the low-DOF solve (a prior covers its free component).
    pub(super) fn solves_low_dof(&self) -> bool {
        self.low_dof_plan().is_some()
    }

    /// The segment's estimate now, kept as a checkpoint when its pose count has grown by half
    /// since the last one.
    pub(super) fn refresh(&mut self, options: &TrackOptions) -> Option<Snapshot> {
        let current = self.estimate();
        let n = self.all.poses();
        let due = self
            .checkpoints
            .last()
            .is_none_or(|(c, _)| 2 * n >= 3 * c && n >= c + 2);
        if let Some(Snapshot {
            estimate: e, local, ..
        }) = current
            && due
            && n >= 6
        {
            // (A state saved before the local uncertainties were kept: none for the old ones.)
            self.checkpoint_local.resize(self.checkpoints.len(), None);
            let bound = self.translation_bound(options);
            let loose = local.filter(|(r, t)| *r > options.max_rotation_deg || *t > bound);
            self.checkpoints.push((n, e.x));
            self.checkpoint_local.push(loose);
            // Those below n/4 are of no more use (constant memory: about four are kept).
            let keep: Vec<bool> = self.checkpoints.iter().map(|(c, _)| 4 * c >= n).collect();
            let mut k = keep.iter();
            self.checkpoints.retain(|_| *k.next().unwrap_or(&true));
            let mut k = keep.iter();
            self.checkpoint_local.retain(|_| *k.next().unwrap_or(&true));
        }
        current
    }

    /// The drift of the estimate as an uncertainty: with c a checkpoint between n/4 and n/2 poses,
    /// X_c − X_n has the spread of σ_n·√(n/c − 1) when the poses' errors are independent, and
    /// more when the estimate still moves as the robot reaches new parts of the workspace (real
    /// data). The largest over those checkpoints (two or three), so that one lucky agreement
    /// does not pass for certainty.
    ///
    /// The √(n/c − 1) is what independent errors give: σ_c² − σ_n² = σ_n²(n/c − 1) for the
    /// difference of nested estimates. A checkpoint that was not determined when it was taken (its
    /// local uncertainty u_c above the reporting bounds: the poses before it stood still or turned
    /// about one axis) differs by its own error: the difference is then scaled by
    /// √(u_c²/u_n² − 1), per part, when that is larger, so that it counts as drift only beyond
    /// what X_c's own uncertainty explains.
    pub(super) fn drift(&self, x: &Transform, local: Option<(f64, f64)>) -> Option<(f64, f64)> {
        let n = self.all.poses();
        self.checkpoints
            .iter()
            .enumerate()
            .filter(|(_, (c, _))| 2 * c <= n && 4 * c >= n)
            .map(|(k, (c, x_c))| {
                let independent = (n as f64 / *c as f64) - 1.0;
                let own = |part: fn(&(f64, f64)) -> f64| {
                    let u_c = self.checkpoint_local.get(k).copied().flatten();
                    match (u_c, local) {
                        (Some(u_c), Some(u_n)) if part(&u_n) > 0.0 => {
                            (part(&u_c) / part(&u_n)).powi(2) - 1.0
                        }
                        _ => 0.0,
                    }
                };
                let scale_r = independent.max(own(|u| u.0)).max(1e-9).sqrt();
                let scale_t = independent.max(own(|u| u.1)).max(1e-9).sqrt();
                (
                    rotation_angle_between(&x_c.rotation, &x.rotation).to_degrees() / scale_r,
                    (x_c.translation.vector - x.translation.vector).norm() / scale_t,
                )
            })
            .reduce(|a, b| (a.0.max(b.0), a.1.max(b.1)))
    }

    pub(super) fn estimate(&self) -> Option<Snapshot> {
        // A low-DOF segment with its prior: the low-DOF solve, of all poses and of each half.
        let plan = self.low_dof_plan();
        let (e, halves) = match plan {
            Some((low, _, prior)) => {
                let along = (prior.component, prior.value);
                let solved = low.all.solve(along).ok()?;
                let half = |k: usize| low.halves[k].solve(along).ok().map(|s| s.x);
                (
                    crate::solve::accumulate::Estimate {
                        x: solved.x,
                        poses: self.all.poses(),
                        conditioning: solved.conditioning,
                    },
                    (half(0), half(1)),
                )
            }
            None => {
                let e = self.all.estimate()?;
                let half = |k: usize| self.halves[k].estimate().map(|e| e.x);
                (e, (half(0), half(1)))
            }
        };
        let scatter = self.all.residual_scatter(&e.x)?;
        // The largest of three measures: the split-half difference, the first-order covariance
        // with each pose as one measurement at the scatter's noise level, and the drift since
        // half the poses.
        let split = match halves {
            (Some(a), Some(b)) => Some((
                0.5 * rotation_angle_between(&a.rotation, &b.rotation).to_degrees(),
                0.5 * (a.translation.vector - b.translation.vector).norm(),
            )),
            _ => None,
        };
        // At the noise unit: on exact data the scatter is rounding, or 0, which would make the
        // information matrix infinite and leave the estimate without an uncertainty.
        let [noise_rotation, noise_translation] = self.noise_unit(&scatter, &e.x);
        let (noise_r, noise_t) = (
            noise_rotation / 3f64.sqrt(),
            noise_translation / 3f64.sqrt(),
        );
        // A low-DOF X: the data's part, the prior taken as exact (its sigma is added below).
        let linear_covariance = match plan {
            Some((_, _, prior)) => self.all.covariance_given(
                &e.x,
                noise_r,
                noise_t,
                &[Prior {
                    sigma: 0.0,
                    ..prior
                }],
            ),
            None => self.all.covariance(&e.x, noise_r, noise_t),
        };
        let linear = linear_covariance.map(|c| {
            let rotation = (c[(0, 0)] + c[(1, 1)] + c[(2, 2)]).sqrt().to_degrees();
            (rotation, (c[(3, 3)] + c[(4, 4)] + c[(5, 5)]).sqrt())
        });
        let local = split.zip(linear).map(|(a, b)| (a.0.max(b.0), a.1.max(b.1)));
        let drift = self.drift(&e.x, local);
        let (ur, ut) = match (local, drift) {
            (Some(a), Some(b)) => (Some(a.0.max(b.0)), Some(a.1.max(b.1))),
            _ => (None, None),
        };
        // The first-order covariance scaled up until its sizes reach the reported ones (the
        // split-half or the drift term may be the larger): its shape, the reported size.
        let mut covariance = match (linear_covariance, linear, ur.zip(ut)) {
            (Some(c), Some((lr, lt)), Some((ur, ut))) => {
                let scale = (ur / lr.max(f64::MIN_POSITIVE))
                    .max(ut / lt.max(f64::MIN_POSITIVE))
                    .max(1.0);
                Some(c * scale * scale)
            }
            _ => None,
        };
        // The prior's sigma is added, not measured (as the batch's `with_prior`): s² g gᵀ in the
        // translation block, g = k / k_i the direction the prior moves X per unit of its value,
        // and s|g| in quadrature to the translation uncertainty.
        let mut ut = ut;
        let prior = plan.map(|(_, axis, prior)| {
            let k = axis.hand * axis.hand[axis.hand.iamax()].signum();
            let g = k / k[prior.component.index()];
            let add = g * g.transpose() * prior.sigma.powi(2);
            if let Some(c) = &mut covariance {
                let block = c.fixed_view::<3, 3>(3, 3) + add;
                c.fixed_view_mut::<3, 3>(3, 3).copy_from(&block);
            }
            ut = ut.map(|t| (t * t + add.trace()).sqrt());
            TrackPrior {
                component: prior.component,
                value: prior.value,
                sigma: prior.sigma,
                axis: k.map(|v| if v == 0.0 { 0.0 } else { v }).into(),
                spread_deg: axis.spread.to_degrees(),
            }
        });
        let at_point = covariance.zip(self.all.mean_target()).map(|(c, p)| {
            let point = [p.x, p.y, p.z];
            (point, point_sigma(&c, &e.x, point))
        });
        Some(Snapshot {
            estimate: TrackEstimate {
                x: e.x,
                target: scatter.y,
                poses: e.poses,
                since: self.since,
                conditioning: e.conditioning,
                noise_rotation_deg: scatter.rotation.to_degrees(),
                noise_translation: scatter.translation,
                uncertainty_rotation_deg: ur,
                uncertainty_translation: ut,
                covariance: covariance
                    .map(|c| std::array::from_fn(|i| std::array::from_fn(|j| c[(i, j)]))),
                at_point,
                robot_world: self.robot_world.estimate().map(|r| RobotWorldPair {
                    x: r.x,
                    target: r.target,
                }),
                prior,
                reprojection: None,
            },
            scatter,
            local,
        })
    }

    /// The noise unit of the poses under `x`: their RMS scatter (rotation in radians, translation
    /// in input units), floored at the data's numerical precision ([`crate::check::precision`]).
    /// The scatter comes from running sums of translations of the size of the camera's distance,
    /// the hand positions and X's translation, and resolves no finer than √(64 ε) of them; on exact
    /// data it is rounding, and a residual measured in it would mean nothing.
    pub(super) fn noise_unit(&self, scatter: &Scatter, x: &Transform) -> [f64; 2] {
        let magnitude = self.all.translation_magnitude() + x.translation.vector.norm();
        [
            scatter.rotation.max(rotation_resolution()),
            scatter.translation.max(resolution(magnitude)),
        ]
    }

    /// The translation bound for `e`, input units.
    pub(super) fn translation_bound(&self, options: &TrackOptions) -> f64 {
        (options.max_translation * self.all.scene_scale())
            .max(options.max_rotation_deg.to_radians() * self.all.viewing_distance())
    }

    /// Why `e` (this segment's estimate, if any) is not reportable; `None` when it is.
    pub(super) fn pending(
        &self,
        e: Option<&TrackEstimate>,
        options: &TrackOptions,
    ) -> Option<Pending> {
        let Some(e) = e else {
            return Some(if self.all.poses() < 3 {
                Pending::FewPoses {
                    poses: self.all.poses(),
                }
            } else if self.largest < LEAST_TURN_DEG.to_radians() {
                Pending::NoRotation {
                    largest_deg: self.largest.to_degrees(),
                }
            } else if let Some(low_dof) = self.wants_prior() {
                low_dof
            } else {
                Pending::ParallelAxes
            });
        };
        let bound_translation = self.translation_bound(options);
        let ok = matches!(
            (e.uncertainty_rotation_deg, e.uncertainty_translation),
            (Some(r), Some(t)) if r <= options.max_rotation_deg && t <= bound_translation
        );
        if !ok && let Some(low_dof) = self.wants_prior() {
            return Some(low_dof);
        }
        (!ok).then_some(Pending::Undetermined {
            rotation_deg: e.uncertainty_rotation_deg,
            translation: e.uncertainty_translation,
            bound_rotation_deg: options.max_rotation_deg,
            bound_translation,
        })
    }
}
