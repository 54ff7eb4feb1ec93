//! The conventional method (SPEC sec. 4.1): no selection at all.

use serde::{Deserialize, Serialize};

use crate::model::motion::{MotionPair, PosePair, Setup};
use crate::online::select::{Numbered, Selected};

/// Selects every two consecutive motions (A_i, A_{i+1}) = poses (i, i+1, i+2): the paper's
/// "conventional method", Andreff on whatever the robot did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct ConventionalSelector {
    setup: Setup,
    /// The two poses before the current one.
    before: [Option<Numbered>; 2],
}

impl ConventionalSelector {
    /// A fresh selector.
    pub fn new(setup: Setup) -> Self {
        Self {
            setup,
            before: [None, None],
        }
    }

    /// Offers the next pose; from the third pose on, selects the last two motions.
    pub fn offer(&mut self, number: usize, pose: &PosePair) -> Option<Selected> {
        let current = Numbered {
            number,
            pose: *pose,
        };
        let selected = match self.before {
            [Some(a), Some(i)] => Some(Selected {
                poses: [a.number, i.number, number],
                first: MotionPair::between(self.setup, &a.pose, &i.pose),
                second: MotionPair::between(self.setup, &i.pose, pose),
                thresholds: None,
            }),
            _ => None,
        };
        self.before = [self.before[1], Some(current)];
        selected
    }
}
