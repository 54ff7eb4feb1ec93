//! A tf buffer: the tree of frames of `/tf` and `/tf_static`, and the pose of one frame in
//! another at any time, composed along the tree.
//!
//! As in tf2, every frame has at most one parent; an edge parent → child holds `parent_from_child`
//! (the pose of the child in the parent), either static or as a time series. A lookup of
//! `a_from_b` at time t walks from both frames up to their nearest common ancestor, interpolating
//! every dynamic edge at t (slerp, linear translation; [`crate::io::sync::interpolate`]).

use std::cell::Cell;
use std::collections::{BTreeMap, BTreeSet, HashMap};

use serde::Serialize;

use crate::io::sync::{Lookup, StampedPose, interpolate};
use crate::model::pose::Transform;

use super::msg::NS;

thread_local! {
    /// Steps of the tree's searches on this thread (see [`tree_steps`]).
    static STEPS: Cell<u64> = const { Cell::new(0) };
}

/// Counts `n` steps of a search of the tree.
fn step(n: usize) {
    STEPS.with(|s| s.set(s.get() + n as u64));
}

/// Steps the tf tree's searches have taken on this thread so far: every parent link followed,
/// every frame compared or listed. For tests that show the searches linear in the tree's size.
pub fn tree_steps() -> u64 {
    STEPS.with(Cell::get)
}

/// One edge of the tree: the parent and what is known of `parent_from_child`.
#[derive(Debug, Clone)]
struct Edge {
    parent: String,
    kind: EdgeKind,
    /// Samples dropped by [`TfBuffer::finish`] for a stamp an earlier sample has.
    repeated: usize,
}

#[derive(Debug, Clone)]
enum EdgeKind {
    Static(Transform),
    /// Samples (stamp in ns, `parent_from_child`), sorted by stamp once the buffer is finished.
    Dynamic(Vec<(i64, Transform)>),
}

/// A summary of one edge of the tree, for `inspect`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TfEdge {
    /// The parent frame.
    pub parent: String,
    /// The child frame.
    pub child: String,
    /// Whether it came from `/tf_static`.
    #[serde(rename = "static")]
    pub is_static: bool,
    /// Samples (1 for a static edge).
    pub samples: usize,
    /// First and last stamp of a dynamic edge, seconds.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stamps: Option<[f64; 2]>,
    /// Mean rate of a dynamic edge, Hz.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rate_hz: Option<f64>,
}

/// Why a lookup cannot be made at all (at any time).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum TfError {
    /// A frame that no transform names; a few of the known frames are listed.
    MissingFrame { frame: String, known: Vec<String> },
    /// The two frames are in different trees.
    Disconnected {
        a: String,
        a_tree: Box<Tree>,
        b: String,
        b_tree: Box<Tree>,
    },
    /// The parent links loop: the frames of the loop, each the parent of the one before.
    Cycle { frames: Vec<String> },
}

/// A tree of the buffer, for messages: its root, its size and its first frames by name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Tree {
    pub root: String,
    pub size: usize,
    pub first: Vec<String>,
}

/// Frames named in a message: a tree or the known frames are shown by this many of theirs.
const SHOWN_FRAMES: usize = 8;

impl std::fmt::Display for Tree {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the tree rooted at `{}` ({} frame{}: {})",
            self.root,
            self.size,
            if self.size == 1 { "" } else { "s" },
            list(&self.first, self.size)
        )
    }
}

impl std::fmt::Display for TfError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::MissingFrame { frame, known } => {
                write!(f, "frame `{frame}` is not in /tf or /tf_static")?;
                if let Some(near) = nearest(frame, known) {
                    write!(f, " (did you mean `{near}`?)")?;
                }
                let shown: Vec<String> = known.iter().take(SHOWN_FRAMES).cloned().collect();
                write!(f, "; the frames there are: {}", list(&shown, known.len()))
            }
            Self::Disconnected {
                a,
                a_tree,
                b,
                b_tree,
            } => write!(
                f,
                "frames `{a}` and `{b}` are not connected in the tf tree: `{a}` is in {a_tree}, `{b}` in {b_tree}"
            ),
            Self::Cycle { frames } => write!(
                f,
                "the tf tree has a loop: {} (each frame the parent of the one before; tf allows none)",
                loop_words(frames)
            ),
        }
    }
}

/// A loop's frames as `` `a` → `b` → `c` → `a` ``, shortened in the middle when long.
pub(crate) fn loop_words(frames: &[String]) -> String {
    let named = |f: &String| format!("`{f}`");
    let mut words: Vec<String> = if frames.len() <= SHOWN_FRAMES {
        frames.iter().map(named).collect()
    } else {
        let mut w: Vec<String> = frames[..SHOWN_FRAMES / 2].iter().map(named).collect();
        w.push(format!("… {} more …", frames.len() - SHOWN_FRAMES));
        w.extend(frames[frames.len() - SHOWN_FRAMES / 2..].iter().map(named));
        w
    };
    if let Some(first) = frames.first() {
        words.push(named(first));
    }
    words.join(" → ")
}

/// The name of `known` closest to `name`, when it is within a couple of edits (a typo, a
/// missing prefix such as `/`), ignoring case.
pub(crate) fn nearest<'a>(name: &str, known: &'a [String]) -> Option<&'a str> {
    let name = name.to_ascii_lowercase();
    known
        .iter()
        .map(|k| (edit_distance(&name, &k.to_ascii_lowercase()), k))
        .filter(|(d, k)| *d <= 2.max(k.len() / 5))
        .min_by_key(|(d, _)| *d)
        .map(|(_, k)| k.as_str())
}

/// Levenshtein distance.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut previous = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let current = row[j + 1];
            row[j + 1] = (previous + usize::from(ca != *cb))
                .min(row[j] + 1)
                .min(current + 1);
            previous = current;
        }
    }
    row[b.len()]
}

/// Frames as `a, b, c` (none: `(none)`), said to be the first of `all` when there are more.
fn list(frames: &[String], all: usize) -> String {
    if frames.is_empty() {
        return "(none)".into();
    }
    let names = frames
        .iter()
        .map(|f| format!("`{f}`"))
        .collect::<Vec<_>>()
        .join(", ");
    if all > frames.len() {
        format!("{names}, … ({} more)", all - frames.len())
    } else {
        names
    }
}

/// The path between two frames a and b, as the child frames of the edges walked.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct TfPath {
    /// From `a` up to the common ancestor (children of the edges walked, `a` first).
    pub up: Vec<String>,
    /// From `b` up to the common ancestor.
    pub down: Vec<String>,
}

/// The buffer.
#[derive(Debug, Clone, Default)]
pub(crate) struct TfBuffer {
    edges: BTreeMap<String, Edge>,
    /// Every frame an edge names, as parent or child.
    names: BTreeSet<String>,
}

impl TfBuffer {
    /// Adds `parent_from_child`; `stamp_ns` is ignored for a static transform. Errs when the
    /// child already has another parent, or is static in one topic and dynamic in the other.
    pub fn add(
        &mut self,
        parent: &str,
        child: &str,
        stamp_ns: i64,
        parent_from_child: Transform,
        is_static: bool,
    ) -> Result<(), String> {
        if parent == child {
            return Err(format!("transform from frame `{child}` to itself"));
        }
        if child.is_empty() || parent.is_empty() {
            return Err(format!(
                "an empty frame name (parent `{parent}`, child `{child}`)"
            ));
        }
        match self.edges.get_mut(child) {
            None => {
                let kind = if is_static {
                    EdgeKind::Static(parent_from_child)
                } else {
                    EdgeKind::Dynamic(vec![(stamp_ns, parent_from_child)])
                };
                for name in [parent, child] {
                    if !self.names.contains(name) {
                        self.names.insert(name.to_string());
                    }
                }
                self.edges.insert(
                    child.to_string(),
                    Edge {
                        parent: parent.to_string(),
                        kind,
                        repeated: 0,
                    },
                );
                Ok(())
            }
            Some(edge) if edge.parent != parent => Err(format!(
                "frame `{child}` has two parents, `{}` and `{parent}` (tf allows one)",
                edge.parent
            )),
            Some(edge) => match (&mut edge.kind, is_static) {
                (EdgeKind::Static(t), true) => {
                    *t = parent_from_child;
                    Ok(())
                }
                (EdgeKind::Dynamic(samples), false) => {
                    samples.push((stamp_ns, parent_from_child));
                    Ok(())
                }
                (EdgeKind::Static(_), false) => Err(format!(
                    "`{parent}` → `{child}` is in /tf_static and in /tf"
                )),
                (EdgeKind::Dynamic(_), true) => Err(format!(
                    "`{parent}` → `{child}` is in /tf and in /tf_static"
                )),
            },
        }
    }

    /// Sorts every time series by stamp and keeps one sample per stamp: the first read, as tf2
    /// does (it ignores a sample whose stamp it has); the others are counted
    /// ([`TfBuffer::repeated`]).
    pub fn finish(&mut self) {
        for edge in self.edges.values_mut() {
            if let EdgeKind::Dynamic(samples) = &mut edge.kind {
                // Stable: of equal stamps, the first read comes first.
                samples.sort_by_key(|s| s.0);
                let before = samples.len();
                samples.dedup_by_key(|s| s.0);
                edge.repeated += before - samples.len();
            }
        }
    }

    /// Drops the samples of every dynamic edge older than `before_ns`, keeping the last one
    /// before it (a lookup at `before_ns` still interpolates): the bound of a live buffer, as
    /// tf2's cache keeps its last seconds. Call after [`TfBuffer::finish`].
    pub fn prune(&mut self, before_ns: i64) {
        for edge in self.edges.values_mut() {
            if let EdgeKind::Dynamic(samples) = &mut edge.kind {
                let k = samples.partition_point(|s| s.0 < before_ns);
                if k > 1 {
                    samples.drain(..k - 1);
                }
            }
        }
    }

    /// The newest stamp of the dynamic edge whose child is `child`.
    pub fn newest(&self, child: &str) -> Option<i64> {
        match self.edges.get(child).map(|e| &e.kind) {
            Some(EdgeKind::Dynamic(s)) => s.iter().map(|s| s.0).max(),
            _ => None,
        }
    }

    /// Samples of the dynamic edge whose child is `child` dropped by [`TfBuffer::finish`] for a
    /// stamp an earlier sample has.
    pub fn repeated(&self, child: &str) -> usize {
        self.edges.get(child).map_or(0, |e| e.repeated)
    }

    /// Every frame named by a transform, sorted.
    pub fn frames(&self) -> Vec<String> {
        self.names.iter().cloned().collect()
    }

    /// The parent of `child`, if it has one.
    pub fn parent_of(&self, child: &str) -> Option<&str> {
        self.edges.get(child).map(|e| e.parent.as_str())
    }

    /// Whether a transform names `frame`.
    pub fn has_frame(&self, frame: &str) -> bool {
        self.names.contains(frame)
    }

    /// `parent_from_child` of the edge of `child` when it is static (from `/tf_static`).
    pub fn static_edge(&self, child: &str) -> Option<Transform> {
        match self.edges.get(child).map(|e| &e.kind) {
            Some(EdgeKind::Static(t)) => Some(*t),
            _ => None,
        }
    }

    /// `frame` and its ancestors, up to its root; a loop is an error naming it.
    pub fn ancestors(&self, frame: &str) -> Result<Vec<String>, TfError> {
        let mut chain = vec![frame.to_string()];
        let mut seen: HashMap<&str, usize> = HashMap::from([(frame, 0)]);
        let mut current = frame;
        while let Some(edge) = self.edges.get(current) {
            step(1);
            if let Some(&at) = seen.get(edge.parent.as_str()) {
                return Err(TfError::Cycle {
                    frames: chain[at..].to_vec(),
                });
            }
            seen.insert(&edge.parent, chain.len());
            chain.push(edge.parent.clone());
            current = &edge.parent;
        }
        Ok(chain)
    }

    /// The root of every frame's tree (`None` for a frame in a loop or below one), each parent
    /// link followed once; and the loops found, each as its frames, the parent of each the next.
    fn trees(&self) -> (HashMap<&str, Option<&str>>, Vec<Vec<String>>) {
        let mut root: HashMap<&str, Option<&str>> = HashMap::new();
        let mut loops = Vec::new();
        let frames = self
            .edges
            .iter()
            .flat_map(|(child, edge)| [child.as_str(), edge.parent.as_str()]);
        for start in frames {
            // Up from `start` to a frame whose root is known, a root, or a frame of this walk.
            let mut walk: Vec<&str> = Vec::new();
            let mut on_walk: HashMap<&str, usize> = HashMap::new();
            let mut current = start;
            let found = loop {
                step(1);
                if let Some(known) = root.get(current) {
                    break *known;
                }
                if let Some(&at) = on_walk.get(current) {
                    loops.push(walk[at..].iter().map(|f| f.to_string()).collect());
                    break None;
                }
                on_walk.insert(current, walk.len());
                walk.push(current);
                match self.edges.get(current) {
                    Some(edge) => current = &edge.parent,
                    None => break Some(current),
                }
            };
            for f in walk {
                root.insert(f, found);
            }
        }
        (root, loops)
    }

    /// The tree whose root is `root`: its size and first frames by name.
    fn tree(&self, root: &str, roots: &HashMap<&str, Option<&str>>) -> Tree {
        let mut tree = Tree {
            root: root.to_string(),
            size: 0,
            first: Vec::new(),
        };
        for f in &self.names {
            step(1);
            if roots.get(f.as_str()).copied().flatten() == Some(root) {
                tree.size += 1;
                if tree.first.len() < SHOWN_FRAMES {
                    tree.first.push(f.clone());
                }
            }
        }
        tree
    }

    /// The path between `a` and `b` through their nearest common ancestor.
    pub fn path(&self, a: &str, b: &str) -> Result<TfPath, TfError> {
        for f in [a, b] {
            if !self.has_frame(f) {
                return Err(TfError::MissingFrame {
                    frame: f.to_string(),
                    known: self.frames(),
                });
            }
        }
        let up_a = self.ancestors(a)?;
        let up_b = self.ancestors(b)?;
        let mut on_b: HashMap<&str, usize> = HashMap::with_capacity(up_b.len());
        for (j, f) in up_b.iter().enumerate() {
            step(1);
            on_b.entry(f).or_insert(j);
        }
        let common = up_a.iter().enumerate().find_map(|(i, f)| {
            step(1);
            on_b.get(f.as_str()).map(|&j| (i, j))
        });
        let Some((i, j)) = common else {
            let (roots, _) = self.trees();
            let root_of = |chain: &[String]| chain.last().cloned().unwrap_or_default();
            return Err(TfError::Disconnected {
                a: a.to_string(),
                a_tree: Box::new(self.tree(&root_of(&up_a), &roots)),
                b: b.to_string(),
                b_tree: Box::new(self.tree(&root_of(&up_b), &roots)),
            });
        };
        Ok(TfPath {
            up: up_a[..i].to_vec(),
            down: up_b[..j].to_vec(),
        })
    }

    /// The loops of the tree, each as its frames (the parent of each the next) from its first
    /// by name; sorted.
    pub fn loops(&self) -> Vec<Vec<String>> {
        let mut loops = self.trees().1;
        for l in &mut loops {
            let first = (0..l.len()).min_by_key(|&k| &l[k]).unwrap_or(0);
            l.rotate_left(first);
        }
        loops.sort();
        loops
    }

    /// The children of the dynamic edges on a path, from `b`'s side (nearest `b` first), then
    /// from `a`'s side (nearest `a` first).
    pub fn dynamic_on(&self, path: &TfPath) -> Vec<String> {
        path.down
            .iter()
            .chain(&path.up)
            .filter(|c| {
                matches!(
                    self.edges.get(c.as_str()).map(|e| &e.kind),
                    Some(EdgeKind::Dynamic(_))
                )
            })
            .cloned()
            .collect()
    }

    /// The stamps (ns) of the dynamic edge whose child is `child`.
    pub fn stamps_of(&self, child: &str) -> Vec<i64> {
        match self.edges.get(child).map(|e| &e.kind) {
            Some(EdgeKind::Dynamic(s)) => s.iter().map(|s| s.0).collect(),
            _ => Vec::new(),
        }
    }

    /// `parent_from_child` of the edge of `child` at `t_ns`.
    fn edge_at(&self, child: &str, t_ns: i64, max_gap_ns: i64) -> Lookup {
        match self.edges.get(child).map(|e| &e.kind) {
            None => Lookup::Outside,
            Some(EdgeKind::Static(t)) => Lookup::Pose(*t),
            Some(EdgeKind::Dynamic(samples)) => sample_at(samples, t_ns, max_gap_ns),
        }
    }

    /// `a_from_b` at `t_ns` along `path` (from [`TfBuffer::path`]`(a, b)`).
    pub fn lookup(&self, path: &TfPath, t_ns: i64, max_gap_ns: i64) -> Lookup {
        // common_from_x for x = a and x = b, walking down from the common ancestor.
        let chain = |children: &[String]| {
            let mut common_from_x = Transform::identity();
            for child in children.iter().rev() {
                match self.edge_at(child, t_ns, max_gap_ns) {
                    Lookup::Pose(parent_from_child) => {
                        common_from_x *= parent_from_child;
                    }
                    other => return Err(other),
                }
            }
            Ok(common_from_x)
        };
        match (chain(&path.up), chain(&path.down)) {
            (Ok(common_from_a), Ok(common_from_b)) => {
                Lookup::Pose(common_from_a.inverse() * common_from_b)
            }
            (Err(e), _) | (_, Err(e)) => e,
        }
    }

    /// A summary of every edge, sorted by parent then child.
    pub fn summary(&self) -> Vec<TfEdge> {
        let mut out: Vec<TfEdge> = self
            .edges
            .iter()
            .map(|(child, edge)| match &edge.kind {
                EdgeKind::Static(_) => TfEdge {
                    parent: edge.parent.clone(),
                    child: child.clone(),
                    is_static: true,
                    samples: 1,
                    stamps: None,
                    rate_hz: None,
                },
                EdgeKind::Dynamic(s) => {
                    let first = s.first().map_or(0, |s| s.0);
                    let last = s.last().map_or(0, |s| s.0);
                    let span = (last - first) as f64 / NS as f64;
                    TfEdge {
                        parent: edge.parent.clone(),
                        child: child.clone(),
                        is_static: false,
                        samples: s.len(),
                        stamps: Some([seconds(first), seconds(last)]),
                        rate_hz: (s.len() > 1 && span > 0.0).then(|| (s.len() - 1) as f64 / span),
                    }
                }
            })
            .collect();
        out.sort_by(|a, b| (&a.parent, &a.child).cmp(&(&b.parent, &b.child)));
        out
    }

    /// The roots of the trees (frames without a parent), sorted.
    pub fn roots(&self) -> Vec<String> {
        self.frames()
            .into_iter()
            .filter(|f| !self.edges.contains_key(f))
            .collect()
    }
}

/// Nanoseconds as seconds.
pub(crate) fn seconds(ns: i64) -> f64 {
    // Whole seconds and the rest separately, so that the rest keeps its digits.
    (ns.div_euclid(NS)) as f64 + (ns.rem_euclid(NS)) as f64 / NS as f64
}

/// A time series at `t_ns`: the sample itself at its own stamp, else the interpolation of its two
/// neighbours (computed on times relative to the earlier one, so that nanosecond stamps near
/// 1.7e18 lose no precision), [`Lookup::Gap`] when they are more than `max_gap_ns` apart.
fn sample_at(samples: &[(i64, Transform)], t_ns: i64, max_gap_ns: i64) -> Lookup {
    let (Some(first), Some(last)) = (samples.first(), samples.last()) else {
        return Lookup::Outside;
    };
    if t_ns < first.0 || t_ns > last.0 {
        return Lookup::Outside;
    }
    let k = samples.partition_point(|s| s.0 <= t_ns);
    let a = &samples[k - 1];
    if a.0 == t_ns {
        return Lookup::Pose(a.1);
    }
    let b = &samples[k];
    if b.0 - a.0 > max_gap_ns {
        return Lookup::Gap;
    }
    let pair = [
        StampedPose {
            stamp: 0.0,
            pose: a.1,
        },
        StampedPose {
            stamp: (b.0 - a.0) as f64 / NS as f64,
            pose: b.1,
        },
    ];
    interpolate(&pair, (t_ns - a.0) as f64 / NS as f64, f64::INFINITY)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn t(x: f64, angle: f64) -> Transform {
        Transform::new(Vector3::new(x, 0.1, 0.0), Vector3::new(0.0, 0.0, angle))
    }

    fn close(a: &Transform, b: &Transform) -> bool {
        (a.to_homogeneous() - b.to_homogeneous()).abs().max() < 1e-12
    }

    fn buffer() -> TfBuffer {
        let mut tf = TfBuffer::default();
        tf.add("world", "base", 0, t(1.0, 0.3), true).unwrap();
        for k in 0..=10 {
            tf.add(
                "base",
                "flange",
                k * 10_000_000,
                t(0.1 * k as f64, 0.05 * k as f64),
                false,
            )
            .unwrap();
        }
        tf.add("flange", "tool0", 0, t(0.0, 0.7), true).unwrap();
        tf.add("camera_link", "optical", 0, t(0.02, -1.0), true)
            .unwrap();
        tf.finish();
        tf
    }

    #[test]
    fn lookups_compose_static_and_dynamic_edges_and_interpolate() {
        let tf = buffer();
        let path = tf.path("base", "tool0").unwrap();
        assert_eq!(tf.dynamic_on(&path), vec!["flange".to_string()]);
        // At a sample: exactly that sample times the static edge.
        let Lookup::Pose(p) = tf.lookup(&path, 30_000_000, 100_000_000) else {
            panic!()
        };
        assert!(close(&p, &(t(0.3, 0.15) * t(0.0, 0.7))));
        // Halfway: rotation about z is linear in the angle, translation linear.
        let Lookup::Pose(p) = tf.lookup(&path, 35_000_000, 100_000_000) else {
            panic!()
        };
        assert!(close(&p, &(t(0.35, 0.175) * t(0.0, 0.7))));
        // The other way round is the inverse, through the common ancestor.
        let back = tf.path("tool0", "world").unwrap();
        let Lookup::Pose(q) = tf.lookup(&back, 35_000_000, 100_000_000) else {
            panic!()
        };
        assert!(close(&q, &(t(1.0, 0.3) * p).inverse()));
        assert_eq!(tf.lookup(&path, -1, 100_000_000), Lookup::Outside);
        assert_eq!(tf.lookup(&path, 35_000_000, 1_000), Lookup::Gap);
    }

    #[test]
    fn dynamic_edges_at_their_own_rates_on_both_sides_of_the_common_ancestor() {
        // world → a (100 Hz) → b (30 Hz, other stamps); world → c (static) → d (50 Hz).
        // About z every rotation commutes and interpolates linearly in its angle.
        let mut tf = TfBuffer::default();
        let rot =
            |angle: f64, x: f64| Transform::new(Vector3::new(x, 0.0, 0.0), Vector3::z() * angle);
        for k in 0..=100 {
            let t = k * 10_000_000;
            tf.add(
                "world",
                "a",
                t,
                rot(0.01 * k as f64, 0.001 * k as f64),
                false,
            )
            .unwrap();
        }
        for k in 0..=30 {
            let t = 3_000_000 + k * 33_333_333;
            tf.add("a", "b", t, rot(-0.02 * k as f64, 0.0), false)
                .unwrap();
        }
        tf.add("world", "c", 0, rot(0.5, 1.0), true).unwrap();
        for k in 0..=50 {
            tf.add("c", "d", k * 20_000_000, rot(0.004 * k as f64, 0.0), false)
                .unwrap();
        }
        tf.finish();
        let path = tf.path("d", "b").unwrap();
        assert_eq!(tf.dynamic_on(&path), ["b", "a", "d"]);
        let t = 517_000_000i64;
        let s = t as f64 / 1e9;
        let world_from_a = rot(s, 0.1 * s);
        let a_from_b = rot(-0.02 * (t - 3_000_000) as f64 / 33_333_333.0, 0.0);
        let world_from_d = rot(0.5, 1.0) * rot(0.2 * s, 0.0);
        let expected = world_from_d.inverse() * world_from_a * a_from_b;
        let Lookup::Pose(d_from_b) = tf.lookup(&path, t, 100_000_000) else {
            panic!()
        };
        let d = (d_from_b.to_homogeneous() - expected.to_homogeneous())
            .abs()
            .max();
        // slerp of small rotations (nalgebra, through acos) is good to ~1e-11.
        assert!(d < 1e-10, "{d:e}");
        // Outside one edge's span (b's last sample is at 1.003 s) is outside.
        assert_eq!(
            tf.lookup(&path, 1_000_000_000 + 3_000_001, 100_000_000),
            Lookup::Outside
        );
    }

    #[test]
    fn missing_frames_and_disconnected_trees_name_what_exists() {
        let tf = buffer();
        let e = tf.path("base", "tool1").unwrap_err().to_string();
        assert!(e.contains("(did you mean `tool0`?)"), "{e}");
        assert!(
            e.contains("`tool1`") && e.contains("`tool0`") && e.contains("`optical`"),
            "{e}"
        );
        let e = tf.path("base", "camera").unwrap_err().to_string();
        assert!(!e.contains("did you mean"), "{e}");
        let e = tf.path("base", "optical").unwrap_err().to_string();
        assert!(e.contains("not connected"), "{e}");
        assert!(e.contains("`camera_link`, `optical`"), "{e}");
        assert!(e.contains("`base`, `flange`, `tool0`, `world`"), "{e}");
        assert_eq!(
            tf.roots(),
            vec!["camera_link".to_string(), "world".to_string()]
        );
    }

    #[test]
    fn two_parents_and_mixed_static_dynamic_are_refused() {
        let mut tf = buffer();
        assert!(
            tf.add("world", "tool0", 0, t(0.0, 0.0), true)
                .unwrap_err()
                .contains("two parents")
        );
        assert!(tf.add("flange", "tool0", 5, t(0.0, 0.0), false).is_err());
        assert!(tf.add("a", "a", 5, t(0.0, 0.0), false).is_err());
    }
}
