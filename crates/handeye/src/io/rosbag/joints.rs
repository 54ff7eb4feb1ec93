//! The robot's joint angles at each pose pair of a recording, from its `sensor_msgs/msg/JointState`
//! messages (`/joint_states`): the systematic-error test orders the poses by them and names the
//! joint whose angle the residual follows (`check::systematic`).
//!
//! The joints are those the first usable message names, in its order. A later message gives
//! their positions by name, in any order, with joints of its own besides; a message that lacks one
//! of them, has no positions, has as many names as positions not, or a position that is not
//! finite, is skipped and told (topic and message number). At a pose pair's stamp (robot clock)
//! the angles are interpolated linearly between the two messages around it, when they are at most
//! `max_gap` apart (as tf is), or else taken from the nearest message within a tenth of `max_gap`
//! (a pose just after the last message). Unless every pose pair has its angles, none are used
//! (the test needs every pose's) and the reason is told.

use super::JointSample;
use super::tf::seconds;

/// The joint angles of a recording's pose pairs (see the module documentation).
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct BagJoints {
    /// The topic they came from; `None` when the recording has no joint-state topic.
    pub(crate) topic: Option<String>,
    /// The joints' names, in the order of the angles.
    pub(crate) names: Vec<String>,
    /// The angles at each pose pair (radians for revolute joints), in the order of the pairs;
    /// empty unless every pair has them.
    pub(crate) angles: Vec<Vec<f64>>,
    /// What was skipped or left out, and why (topic and message number).
    pub(crate) skipped: Vec<String>,
}

/// Messages skipped that [`BagJoints::skipped`] names one by one before it counts the rest.
const NAMED: usize = 5;

/// The angles at `stamps` (nanoseconds, robot clock) from the joint-state messages `samples`.
pub(super) fn joints_at(samples: &[JointSample], stamps: &[i64], max_gap_ns: i64) -> BagJoints {
    let mut out = BagJoints::default();
    let mut topics: Vec<&str> = samples.iter().map(|s| s.topic.as_str()).collect();
    topics.sort_unstable();
    topics.dedup();
    let topic = match topics.as_slice() {
        [] => return out,
        [one] => *one,
        several if several.contains(&super::JOINT_STATES_TOPIC) => super::JOINT_STATES_TOPIC,
        several => {
            out.skipped.push(format!(
                "several joint-state topics ({}): none is used",
                several.join(", ")
            ));
            return out;
        }
    };
    out.topic = Some(topic.to_string());
    let mut skipped = 0usize;
    let mut skip = |out: &mut BagJoints, why: String| {
        skipped += 1;
        if out.skipped.len() < NAMED {
            out.skipped.push(why);
        }
    };
    // (stamp, angles in the order of `names`).
    let mut series: Vec<(i64, Vec<f64>)> = Vec::new();
    for s in samples.iter().filter(|s| s.topic == topic) {
        let at = format!("topic {topic}, message {}", s.index);
        let m = match &s.decoded {
            Ok(m) => m,
            Err(e) => {
                skip(&mut out, format!("{at}: {e}"));
                continue;
            }
        };
        if m.position.is_empty() {
            skip(&mut out, format!("{at}: no positions"));
            continue;
        }
        if m.position.len() != m.name.len() {
            skip(
                &mut out,
                format!(
                    "{at}: {} name(s) but {} position(s)",
                    m.name.len(),
                    m.position.len()
                ),
            );
            continue;
        }
        if let Some(k) = m.position.iter().position(|q| !q.is_finite()) {
            skip(
                &mut out,
                format!("{at}: the position of `{}` is {}", m.name[k], m.position[k]),
            );
            continue;
        }
        if out.names.is_empty() {
            out.names = m.name.clone();
        }
        let angles: Option<Vec<f64>> = out
            .names
            .iter()
            .map(|n| m.name.iter().position(|g| g == n).map(|k| m.position[k]))
            .collect();
        match angles {
            Some(q) => series.push((m.header.stamp_ns, q)),
            None => {
                let missing = out
                    .names
                    .iter()
                    .find(|n| !m.name.contains(n))
                    .cloned()
                    .unwrap_or_default();
                skip(&mut out, format!("{at}: no position of joint `{missing}`"));
            }
        }
    }
    if skipped > NAMED {
        out.skipped.push(format!(
            "{} more message(s) of {topic} skipped",
            skipped - NAMED
        ));
    }
    // In time order, one message per stamp (the first read, as tf keeps a transform's).
    series.sort_by_key(|s| s.0);
    series.dedup_by_key(|s| s.0);
    let angles: Vec<Option<Vec<f64>>> = stamps
        .iter()
        .map(|&t| interpolate(&series, t, max_gap_ns))
        .collect();
    let missing = angles.iter().filter(|a| a.is_none()).count();
    if missing > 0 {
        if !series.is_empty() {
            out.skipped.push(format!(
                "{missing} of {} pose pair(s) have no joint state of {topic} around them (interpolated across at most {} s, or the nearest within {} s): the joint angles are not used",
                stamps.len(),
                seconds(max_gap_ns),
                seconds(max_gap_ns / 10)
            ));
        }
        return out;
    }
    out.angles = angles.into_iter().flatten().collect();
    out
}

/// The angles at `t`: interpolated between the two messages around it when they are at most
/// `max_gap_ns` apart; else (before the first message, after the last, across a longer gap) the
/// nearest message's, when it is within a tenth of `max_gap_ns` (10 ms by default).
fn interpolate(series: &[(i64, Vec<f64>)], t: i64, max_gap_ns: i64) -> Option<Vec<f64>> {
    let after = series.partition_point(|s| s.0 < t);
    let next = series.get(after);
    let previous = after.checked_sub(1).and_then(|k| series.get(k));
    if let Some((t1, q1)) = next
        && *t1 == t
    {
        return Some(q1.clone());
    }
    if let (Some((t0, q0)), Some((t1, q1))) = (previous, next)
        && t1 - t0 <= max_gap_ns
    {
        let w = (t - t0) as f64 / (t1 - t0) as f64;
        return Some(q0.iter().zip(q1).map(|(a, b)| a + w * (b - a)).collect());
    }
    [previous, next]
        .into_iter()
        .flatten()
        .filter(|(ts, _)| (ts - t).abs() <= max_gap_ns / 10)
        .min_by_key(|(ts, _)| (ts - t).abs())
        .map(|(_, q)| q.clone())
}

/// Nanoseconds in a second, for the tests.
#[cfg(test)]
const SECOND: i64 = super::msg::NS;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::rosbag::msg::{Header, JointState};

    fn sample(index: usize, t: i64, names: &[&str], position: &[f64]) -> JointSample {
        JointSample {
            topic: "/joint_states".into(),
            index,
            decoded: Ok(JointState {
                header: Header {
                    stamp_ns: t,
                    frame_id: String::new(),
                },
                name: names.iter().map(|s| s.to_string()).collect(),
                position: position.to_vec(),
            }),
        }
    }

    #[test]
    fn angles_are_put_in_the_first_order_and_interpolated() {
        let samples = [
            sample(1, 0, &["a", "b"], &[0.0, 1.0]),
            // Another order, an extra joint.
            sample(2, SECOND / 10, &["b", "gripper", "a"], &[2.0, 0.5, 1.0]),
        ];
        let j = joints_at(&samples, &[SECOND / 20, SECOND / 10], SECOND / 10);
        assert_eq!(j.names, ["a", "b"]);
        assert_eq!(j.angles.len(), 2);
        assert!((j.angles[0][0] - 0.5).abs() < 1e-12 && (j.angles[0][1] - 1.5).abs() < 1e-12);
        assert_eq!(j.angles[1], [1.0, 2.0]);
        assert!(j.skipped.is_empty());
        // Too far apart: not interpolated, and then none are used, with the reason.
        let j = joints_at(&samples, &[SECOND / 20], SECOND / 100);
        assert!(j.angles.is_empty());
        assert!(
            j.skipped[0].contains("1 of 1 pose pair(s)"),
            "{:?}",
            j.skipped
        );
    }

    #[test]
    fn just_after_the_last_message_its_angles_are_taken_within_a_tenth_of_max_gap() {
        let samples = [
            sample(1, 0, &["a", "b"], &[0.0, 1.0]),
            sample(2, SECOND / 10, &["a", "b"], &[1.0, 2.0]),
        ];
        let j = joints_at(&samples, &[SECOND / 10 + SECOND / 200], SECOND / 10);
        assert_eq!(j.angles, [vec![1.0, 2.0]]);
        let j = joints_at(&samples, &[SECOND / 10 + SECOND / 50], SECOND / 10);
        assert!(j.angles.is_empty());
    }

    #[test]
    fn a_bad_message_is_skipped_naming_its_topic_and_number() {
        let samples = [
            sample(1, 0, &["a", "b"], &[0.0, 1.0]),
            sample(2, SECOND / 20, &["a", "b"], &[0.3]),
            sample(3, SECOND / 20, &["a"], &[0.3]),
            sample(4, SECOND / 20, &["a", "b"], &[]),
            sample(5, SECOND / 20, &["a", "b"], &[f64::NAN, 0.0]),
            JointSample {
                topic: "/joint_states".into(),
                index: 6,
                decoded: Err("cannot decode: truncated".into()),
            },
            sample(7, SECOND / 10, &["a", "b"], &[1.0, 1.0]),
        ];
        let j = joints_at(&samples, &[SECOND / 20], SECOND / 10);
        assert_eq!(j.angles, [vec![0.5, 1.0]]);
        let told = j.skipped.join("\n");
        for want in [
            "topic /joint_states, message 2: 2 name(s) but 1 position(s)",
            "message 3: no position of joint `b`",
            "message 4: no positions",
            "message 5: the position of `a` is NaN",
            "message 6: cannot decode",
        ] {
            assert!(told.contains(want), "{want}: {told}");
        }
    }
}
