//! The robot's stations: the poses of a recording at one robot pose. A camera that keeps taking
//! images while the robot stands still, or a robot program that comes back to its poses, gives
//! several images of one robot pose. They share that pose's error (a robot's error follows its
//! configuration), which no number of images of it averages out: each check that takes the
//! poses' errors as independent counts a station once.

use std::collections::BTreeMap;

use nalgebra::{Matrix3, Vector3};

use crate::model::motion::PosePair;
use crate::model::pose::log_so3;

/// The largest difference of two robot poses taken as one station: 1e-4 rad (0.006°) in
/// rotation, and 1e-4 of the caller's length scale in translation (0.05 mm at 0.5 m), below an
/// industrial robot's repeatability.
pub(crate) const SAME_STATION: f64 = 1e-4;

/// Whether two robot poses, as rotation and translation, are one station: within
/// [`SAME_STATION`] radians and `translation_tolerance`.
pub(crate) fn same_station(
    (ra, ta): (&Matrix3<f64>, &Vector3<f64>),
    (rb, tb): (&Matrix3<f64>, &Vector3<f64>),
    translation_tolerance: f64,
) -> bool {
    (ta - tb).norm() <= translation_tolerance
        && log_so3(&(ra * rb.transpose())).norm() < SAME_STATION
}

/// How far apart (in the projection of [`Stations::of_motions`]) two poses of one station can be:
/// 2√3, with room for rounding.
const REACH: f64 = 3.5;

/// An `f64` ordered by `total_cmp`, as a key of the sorted stations.
#[derive(Debug, Clone, Copy)]
struct OrderedKey(f64);

impl PartialEq for OrderedKey {
    fn eq(&self, other: &Self) -> bool {
        self.0.total_cmp(&other.0).is_eq()
    }
}

impl Eq for OrderedKey {}

impl PartialOrd for OrderedKey {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for OrderedKey {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// Each pose's station, numbered from 0 in the order of their first pose.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Stations {
    /// The station of each pose.
    pub of: Vec<usize>,
    /// How many there are.
    pub count: usize,
}

impl Stations {
    /// The stations of robot poses given as rotation and translation, in recording order: a pose
    /// within [`SAME_STATION`] radians and `translation_tolerance` of a station's first pose
    /// joins it (the earliest such station), else it starts one. Every pose of a station is within
    /// the tolerance of its first, so a robot that moves slowly past a fast camera is not chained
    /// into one station. O(n log n) for distinct poses: the stations' first poses are kept sorted
    /// by a projection of the pose that moves by at most [`REACH`] between poses of one station,
    /// and a pose is compared with those within that reach only.
    pub fn of_motions(
        motions: &[(Matrix3<f64>, Vector3<f64>)],
        translation_tolerance: f64,
    ) -> Self {
        let same = |a: usize, b: usize| {
            let ((ra, ta), (rb, tb)) = (&motions[a], &motions[b]);
            same_station((ra, ta), (rb, tb), translation_tolerance)
        };
        // The projection: the sum of the translation's and the rotation vector's coordinates,
        // each over its tolerance; two poses of one station are within 2√3 of each other in it
        // (away from rotations of π, where the rotation vector turns over).
        let t_scale = translation_tolerance.max(f64::MIN_POSITIVE);
        let key = |(r, t): &(Matrix3<f64>, Vector3<f64>)| {
            let w = log_so3(r);
            (t.x + t.y + t.z) / t_scale + (w.x + w.y + w.z) / SAME_STATION
        };
        let mut firsts: BTreeMap<(OrderedKey, usize), usize> = BTreeMap::new();
        let mut of = Vec::with_capacity(motions.len());
        let mut count = 0;
        for (i, m) in motions.iter().enumerate() {
            let k = key(m);
            let window = (OrderedKey(k - REACH), 0)..=(OrderedKey(k + REACH), usize::MAX);
            let joined = firsts
                .range(window)
                .filter(|((_, first), _)| same(i, *first))
                .min_by_key(|((_, first), _)| *first)
                .map(|(_, &station)| station);
            of.push(joined.unwrap_or_else(|| {
                firsts.insert((OrderedKey(k), i), count);
                count += 1;
                count - 1
            }));
        }
        Self { of, count }
    }

    /// The stations of the robot poses (`base_from_gripper`) of `poses`, with translations
    /// compared to [`SAME_STATION`] of `scale` (the robot's own unit: a camera pose in another
    /// unit does not move the tolerance).
    pub fn of_poses(poses: &[PosePair], scale: f64) -> Self {
        let motions: Vec<(Matrix3<f64>, Vector3<f64>)> = poses
            .iter()
            .map(|p| {
                let q = &p.base_from_gripper;
                (*q.rotation.matrix(), q.translation.vector)
            })
            .collect();
        Self::of_motions(&motions, SAME_STATION * scale)
    }

    /// Whether every pose is its own station (then each check runs as on independent poses).
    pub fn distinct(&self) -> bool {
        self.count == self.of.len()
    }

    /// The first pose of each station, in station order.
    pub fn first_poses(&self) -> Vec<usize> {
        let mut first = vec![usize::MAX; self.count];
        for (i, &s) in self.of.iter().enumerate() {
            if first[s] == usize::MAX {
                first[s] = i;
            }
        }
        first
    }

    /// The mean of `values` (one per pose) over each station, in station order.
    pub fn means(&self, values: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        let mut sums = vec![(Vector3::zeros(), 0.0); self.count];
        for (v, &s) in values.iter().zip(&self.of) {
            sums[s].0 += v;
            sums[s].1 += 1.0;
        }
        sums.into_iter()
            .map(|(sum, k)| sum / f64::max(k, 1.0))
            .collect()
    }

    /// An order of the poses from an order of the stations: each station's poses together, in
    /// recording order.
    pub fn expand(&self, station_order: &[usize]) -> Vec<usize> {
        let mut members: Vec<Vec<usize>> = vec![Vec::new(); self.count];
        for (i, &s) in self.of.iter().enumerate() {
            members[s].push(i);
        }
        station_order
            .iter()
            .flat_map(|&s| members[s].iter().copied())
            .collect()
    }

    /// The rank of each station in `order`, an order of the poses in which each station's poses
    /// come together (as [`Stations::expand`] gives): the station order it was expanded from.
    pub fn order_of(&self, order: &[usize]) -> Vec<usize> {
        let mut seen = vec![false; self.count];
        order
            .iter()
            .filter_map(|&i| {
                let s = self.of[i];
                (!std::mem::replace(&mut seen[s], true)).then_some(s)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, Vector3};

    fn motion(angle: f64, x: f64) -> (Matrix3<f64>, Vector3<f64>) {
        (
            *Rotation3::from_axis_angle(&Vector3::z_axis(), angle).matrix(),
            Vector3::new(x, 0.5, 0.0),
        )
    }

    #[test]
    fn repeats_in_a_row_and_as_tours_are_one_station_each() {
        // Three poses, toured twice, the second tour with a jitter below the tolerance.
        let motions = [
            motion(0.0, 0.0),
            motion(0.3, 0.1),
            motion(0.6, 0.2),
            motion(0.0, 0.0),
            motion(0.3 + 5e-5, 0.1 + 5e-5),
            motion(0.6, 0.2),
            motion(0.6, 0.2),
        ];
        let s = Stations::of_motions(&motions, 1e-4);
        assert_eq!(s.of, vec![0, 1, 2, 0, 1, 2, 2]);
        assert_eq!(s.count, 3);
        assert!(!s.distinct());
        assert_eq!(s.first_poses(), vec![0, 1, 2]);
        let expanded = s.expand(&[2, 0, 1]);
        assert_eq!(expanded, vec![2, 5, 6, 0, 3, 1, 4]);
        assert_eq!(s.order_of(&expanded), vec![2, 0, 1]);
    }

    #[test]
    fn poses_apart_by_more_than_the_tolerance_are_distinct() {
        let motions = [
            motion(0.0, 0.0),
            motion(2e-4, 0.0),
            motion(0.0, 2e-4),
            motion(0.0, 0.0),
        ];
        let s = Stations::of_motions(&motions, 1e-4);
        assert_eq!(s.of, vec![0, 1, 2, 0]);
        let distinct = Stations::of_motions(&motions[..3], 1e-4);
        assert!(distinct.distinct());
        assert_eq!(distinct.of, vec![0, 1, 2]);
    }

    #[test]
    fn a_slow_drift_is_not_chained_into_one_station() {
        // Each pose 0.6 of the tolerance from the last: a station holds the poses within the
        // tolerance of its first, never the whole drift.
        let motions: Vec<_> = (0..10).map(|i| motion(0.0, 0.6e-4 * i as f64)).collect();
        let s = Stations::of_motions(&motions, 1e-4);
        assert_eq!(s.of, vec![0, 0, 1, 1, 2, 2, 3, 3, 4, 4]);
        // The same in rotation.
        let turning: Vec<_> = (0..4).map(|i| motion(0.6e-4 * i as f64, 0.0)).collect();
        assert_eq!(Stations::of_motions(&turning, 1e-4).of, vec![0, 0, 1, 1]);
    }

    #[test]
    fn a_pose_joins_the_earliest_station_within_reach() {
        // The third pose is within the tolerance of both stations' first poses.
        let motions = [motion(0.0, 0.0), motion(0.0, 1.5e-4), motion(0.0, 0.75e-4)];
        assert_eq!(Stations::of_motions(&motions, 1e-4).of, vec![0, 1, 0]);
    }

    #[test]
    fn a_flange_turning_in_place_gives_distinct_stations() {
        // One translation, many rotations (the projection still tells them apart).
        let motions: Vec<_> = (0..2000).map(|i| motion(1e-3 * i as f64, 0.3)).collect();
        let s = Stations::of_motions(&motions, 1e-4);
        assert!(s.distinct());
    }

    #[test]
    fn means_are_per_station() {
        let s = Stations {
            of: vec![0, 1, 0],
            count: 2,
        };
        let m = s.means(&[
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(5.0, 0.0, 0.0),
            Vector3::new(3.0, 2.0, 0.0),
        ]);
        assert_eq!(
            m,
            vec![Vector3::new(2.0, 1.0, 0.0), Vector3::new(5.0, 0.0, 0.0)]
        );
    }
}
