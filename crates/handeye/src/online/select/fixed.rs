//! Shi et al.'s motion selection with fixed thresholds (SPEC sec. 4.2, the paper's sec. 2).

use serde::{Deserialize, Serialize};

use crate::model::motion::{MotionFeatures, MotionPair, PosePair, Setup};
use crate::online::select::{FirstMotion, InitialStats, Numbered, Selected, gripper_motion};

/// Fixed thresholds (α₀ as an angle, β₀, d₀), the means of the first motions.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub(crate) struct FixedThresholds {
    /// α₀: the least angle between the axes of A' and A'', radians.
    pub alpha: f64,
    /// β₀: the least rotation angle, radians.
    pub beta: f64,
    /// d₀: the largest translation, input units.
    pub d: f64,
}

/// Shi et al.'s 13-step listing with anchor Q_1 and the typo of step 10 fixed (j ← j + 1).
///
/// The thresholds are the means of the first `n_init` motions (poses 1..n_init+1): β₀ = mean θ,
/// d₀ = mean ‖t_a‖, α₀ = mean ∠(k_n, k_{n+1}) (the angle itself, not its sine). Since the search
/// starts at pose 2, the first n_init+1 poses are kept until the thresholds are known and then
/// searched at once (a bounded buffer: memory stays constant).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct FixedSelector {
    setup: Setup,
    n_init: usize,
    /// Poses 1..n_init+1, kept until the thresholds are known.
    window: Vec<PosePair>,
    stats: InitialStats,
    thresholds: Option<FixedThresholds>,
    /// Pose a (the anchor of A'): pose 1, then each i that ended an A'.
    anchor: Option<Numbered>,
    /// A' once found.
    first: Option<FirstMotion>,
}

impl FixedSelector {
    /// A fresh selector; thresholds from the first `n_init` motions.
    pub fn new(setup: Setup, n_init: usize) -> Self {
        Self {
            setup,
            n_init,
            // Grown as poses come: never allocated from `n_init`, which the caller sets.
            window: Vec::new(),
            stats: InitialStats::default(),
            thresholds: None,
            anchor: None,
            first: None,
        }
    }

    /// Offers the next pose.
    pub fn offer(&mut self, number: usize, pose: &PosePair) -> Vec<Selected> {
        if self.thresholds.is_some() {
            return self.search(number, pose).into_iter().collect();
        }
        if let Some(previous) = self.window.last() {
            self.stats.add(gripper_motion(self.setup, previous, pose));
        }
        self.window.push(*pose);
        if self.stats.motions() < self.n_init {
            return Vec::new();
        }
        let means = self.stats.means();
        self.thresholds = Some(FixedThresholds {
            alpha: means.alpha,
            beta: means.beta,
            d: means.d,
        });
        // Steps 1–2: anchor Q_1, then search the buffered poses 2..n_init+1 in order.
        let window = std::mem::take(&mut self.window);
        self.anchor = Some(Numbered {
            number: 1,
            pose: window[0],
        });
        window
            .iter()
            .enumerate()
            .skip(1)
            .filter_map(|(k, p)| self.search(k + 1, p))
            .collect()
    }

    /// Steps 2–13 for one new pose.
    fn search(&mut self, number: usize, pose: &PosePair) -> Option<Selected> {
        let t = self.thresholds?;
        let current = Numbered {
            number,
            pose: *pose,
        };
        match self.first {
            None => {
                // Steps 2–5: A' = Q_1⁻¹ Q_i until θ' ≥ β₀ and ‖t'_a‖ ≤ d₀.
                let anchor = self.anchor?;
                let f = gripper_motion(self.setup, &anchor.pose, pose);
                if f.angle >= t.beta && f.translation_norm <= t.d {
                    self.first = Some(FirstMotion {
                        end: current,
                        motion: MotionPair::between(self.setup, &anchor.pose, pose),
                        features: f,
                    });
                }
                None
            }
            Some(first) => {
                // Steps 7–9: A'' = Q_i⁻¹ Q_j until ∠(k', k'') ≥ α₀, θ'' ≥ β₀, ‖t''_a‖ ≤ d₀.
                let f: MotionFeatures = gripper_motion(self.setup, &first.end.pose, pose);
                let accept = first.features.axis_angle_to(&f) >= t.alpha
                    && f.angle >= t.beta
                    && f.translation_norm <= t.d;
                if !accept {
                    return None;
                }
                let anchor = self.anchor?;
                let second = MotionPair::between(self.setup, &first.end.pose, pose);
                // Steps 11–13: calibrate, then A' ← A'', the anchor becomes i, i ← j.
                self.anchor = Some(first.end);
                self.first = Some(FirstMotion {
                    end: current,
                    motion: second,
                    features: f,
                });
                Some(Selected {
                    poses: [anchor.number, first.end.number, number],
                    first: first.motion,
                    second,
                    thresholds: None,
                })
            }
        }
    }
}
