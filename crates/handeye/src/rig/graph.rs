//! The rig as a graph, and what its observations determine.
//!
//! Nodes are the cameras and targets, edges the observed (camera, target) pairs. An edge between
//! a part on the gripper and a part on the base whose robot poses rotate about two non-parallel
//! axes determines both its ends (the robot-world closed form accepts it: an *anchor*); every
//! edge determines either end from the other. A connected part of the graph is determined when
//! it holds an anchor; otherwise every node in it is undetermined, with the reason.

use std::collections::BTreeMap;

use crate::check::readings::check_readings;
use crate::model::error::{Error, Result};
use crate::model::findings::Written;
use crate::model::motion::{PosePair, Setup};
use crate::model::pose::Transform;
use crate::rig::{Mount, Mounts, PartKind, RigRecording, Undetermined};
use crate::solve::robot_world::{RobotWorld, shah};

/// Observations an edge needs before its readings are judged (the single-camera check needs a
/// few motions to tell the readings apart).
const MIN_READING_POSES: usize = 6;

/// A camera or a target.
#[derive(Debug, Clone, PartialEq)]
pub struct Node {
    /// Its name.
    pub name: String,
    /// Camera or target.
    pub kind: PartKind,
    /// Where it is fixed.
    pub mount: Mount,
}

/// An observed (camera, target) pair.
#[derive(Debug, Clone, PartialEq)]
pub struct Edge {
    /// The camera's node.
    pub camera: usize,
    /// The target's node.
    pub target: usize,
    /// Its observations (indices into the recording's), in pose order.
    pub observations: Vec<usize>,
}

/// The rig's graph.
#[derive(Debug, Clone, PartialEq)]
pub struct Graph {
    /// Cameras and targets.
    pub nodes: Vec<Node>,
    /// Observed pairs.
    pub edges: Vec<Edge>,
    /// The edge of each observation.
    pub edge_of: Vec<usize>,
    /// Names mounted but never observed.
    pub unobserved: Vec<String>,
}

/// A determined connected part of the graph: its nodes and edges, the anchor edge and the
/// robot-world solution of the anchor (the linear start).
#[derive(Debug, Clone, PartialEq)]
pub struct Component {
    /// Its nodes.
    pub nodes: Vec<usize>,
    /// Its edges.
    pub edges: Vec<usize>,
    /// The edge that determines it.
    pub anchor: usize,
    /// Shah's closed form on the anchor: X of its camera, Y of its target.
    pub start: RobotWorld,
}

/// What the observations determine.
#[derive(Debug, Clone, PartialEq)]
pub struct Solvable {
    /// Determined parts.
    pub determined: Vec<Component>,
    /// Undetermined cameras and targets.
    pub undetermined: Vec<Undetermined>,
}

impl Graph {
    /// The graph of a recording; refuses a name observed without a mount, a name used for a
    /// camera and a target, and an observation at a pose that is not there.
    pub fn build(recording: &RigRecording, mounts: &Mounts) -> Result<Self> {
        let mut nodes: Vec<Node> = Vec::new();
        let mut index: BTreeMap<String, usize> = BTreeMap::new();
        let mut edges: Vec<Edge> = Vec::new();
        let mut edge_index: BTreeMap<(usize, usize), usize> = BTreeMap::new();
        let mut edge_of = Vec::with_capacity(recording.observations.len());
        let mut node = |name: &str, kind: PartKind, nodes: &mut Vec<Node>| -> Result<usize> {
            if let Some(&i) = index.get(name) {
                if nodes[i].kind != kind {
                    return Err(Error::InvalidParameter {
                        name: "mount",
                        message: format!(
                            "`{name}` is named as a camera and as a target: give each camera and target its own name"
                        ),
                    });
                }
                return Ok(i);
            }
            let Some(&mount) = mounts.get(name) else {
                return Err(Error::InvalidParameter {
                    name: "mount",
                    message: format!(
                        "{} `{name}` has no mount: say where it is fixed, `{name}=gripper` or `{name}=base`",
                        kind.name()
                    ),
                });
            };
            nodes.push(Node {
                name: name.to_string(),
                kind,
                mount,
            });
            index.insert(name.to_string(), nodes.len() - 1);
            Ok(nodes.len() - 1)
        };
        for (k, o) in recording.observations.iter().enumerate() {
            if o.pose >= recording.poses.len() {
                return Err(Error::InvalidParameter {
                    name: "observations",
                    message: format!(
                        "observation {k} names robot pose {} of {}",
                        o.pose,
                        recording.poses.len()
                    ),
                });
            }
            let c = node(&o.camera, PartKind::Camera, &mut nodes)?;
            let t = node(&o.target, PartKind::Target, &mut nodes)?;
            let e = *edge_index.entry((c, t)).or_insert_with(|| {
                edges.push(Edge {
                    camera: c,
                    target: t,
                    observations: Vec::new(),
                });
                edges.len() - 1
            });
            edges[e].observations.push(k);
            edge_of.push(e);
        }
        for e in &mut edges {
            e.observations
                .sort_by_key(|&k| (recording.observations[k].pose, k));
        }
        let unobserved = mounts
            .keys()
            .filter(|name| !index.contains_key(*name))
            .cloned()
            .collect();
        Ok(Self {
            nodes,
            edges,
            edge_of,
            unobserved,
        })
    }

    /// Whether an edge joins a part on the gripper and one on the base (the robot's motion then
    /// relates them).
    pub fn crosses(&self, e: usize) -> bool {
        let edge = &self.edges[e];
        self.nodes[edge.camera].mount != self.nodes[edge.target].mount
    }

    /// The setup of an edge that crosses: eye-in-hand for a camera on the gripper.
    pub fn setup(&self, e: usize) -> Setup {
        match self.nodes[self.edges[e].camera].mount {
            Mount::Gripper => Setup::EyeInHand,
            Mount::Base => Setup::EyeToHand,
        }
    }

    /// The pose pairs of an edge (robot pose, camera's observation), in pose order.
    pub fn pose_pairs(&self, recording: &RigRecording, e: usize) -> Vec<PosePair> {
        self.edges[e]
            .observations
            .iter()
            .map(|&k| {
                let o = &recording.observations[k];
                PosePair {
                    base_from_gripper: recording.poses[o.pose],
                    camera_from_target: o.camera_from_target,
                }
            })
            .collect()
    }

    /// `camera `a` seeing `b``.
    pub fn edge_words(&self, e: usize) -> String {
        let edge = &self.edges[e];
        format!(
            "camera `{}` seeing `{}`",
            self.nodes[edge.camera].name, self.nodes[edge.target].name
        )
    }

    /// Refuses an edge whose observations fit far better read another way (inverted, another
    /// quaternion order, another length unit), naming its camera: the single-camera check of the
    /// readings ([`check_readings`]) on each edge that crosses.
    pub fn check_readings(&self, recording: &RigRecording) -> Result<()> {
        for e in 0..self.edges.len() {
            if !self.crosses(e) || self.edges[e].observations.len() < MIN_READING_POSES {
                continue;
            }
            let setup = self.setup(e);
            let check = check_readings(&self.pose_pairs(recording, e), setup, Written::default());
            if check.misread(setup).is_some() {
                let edge = &self.edges[e];
                let finding = check.finding(setup).unwrap_or_else(|| {
                    "the robot poses and the camera's observations both fit far better inverted"
                        .to_string()
                });
                return Err(Error::RigMisread {
                    camera: self.nodes[edge.camera].name.clone(),
                    target: self.nodes[edge.target].name.clone(),
                    finding: format!("{finding}{}", fit_words(&check)),
                });
            }
        }
        Ok(())
    }

    /// The connected parts, each with an anchor when one of its edges determines it.
    pub fn identify(&self, recording: &RigRecording) -> Solvable {
        let mut parent: Vec<usize> = (0..self.nodes.len()).collect();
        fn root(parent: &mut [usize], mut i: usize) -> usize {
            while parent[i] != i {
                parent[i] = parent[parent[i]];
                i = parent[i];
            }
            i
        }
        for e in &self.edges {
            let (a, b) = (root(&mut parent, e.camera), root(&mut parent, e.target));
            parent[a] = b;
        }
        let mut parts: BTreeMap<usize, (Vec<usize>, Vec<usize>)> = BTreeMap::new();
        for n in 0..self.nodes.len() {
            let r = root(&mut parent, n);
            parts.entry(r).or_default().0.push(n);
        }
        for (e, edge) in self.edges.iter().enumerate() {
            let r = root(&mut parent, edge.camera);
            parts.entry(r).or_default().1.push(e);
        }
        let mut determined = Vec::new();
        let mut undetermined: Vec<Undetermined> = self
            .unobserved
            .iter()
            .map(|name| Undetermined {
                name: name.clone(),
                kind: "camera or target".into(),
                reason: "mounted but never observed".into(),
            })
            .collect();
        for (nodes, edges) in parts.into_values() {
            let mut candidates: Vec<usize> =
                edges.iter().copied().filter(|&e| self.crosses(e)).collect();
            candidates.sort_by_key(|&e| (std::cmp::Reverse(self.edges[e].observations.len()), e));
            let mut refusals = Vec::new();
            let mut anchor = None;
            for &e in &candidates {
                match shah(&self.pose_pairs(recording, e), self.setup(e)) {
                    Ok(start) => {
                        anchor = Some((e, start));
                        break;
                    }
                    Err(why) => refusals.push(format!("{}: {why}", self.edge_words(e))),
                }
            }
            match anchor {
                Some((anchor, start)) => determined.push(Component {
                    nodes,
                    edges,
                    anchor,
                    start,
                }),
                None => {
                    let reason = if candidates.is_empty() {
                        let mount = self.nodes[nodes[0]].mount;
                        format!(
                            "every camera and target joined to it by observations is fixed to the {}: no robot motion relates them to the robot, only to each other",
                            mount.name()
                        )
                    } else {
                        format!(
                            "no camera–target pair joined to it moves about two non-parallel rotation axes ({})",
                            refusals.join("; ")
                        )
                    };
                    undetermined.extend(nodes.iter().map(|&n| Undetermined {
                        name: self.nodes[n].name.clone(),
                        kind: self.nodes[n].kind.name().into(),
                        reason: reason.clone(),
                    }));
                }
            }
        }
        Solvable {
            determined,
            undetermined,
        }
    }

    /// `base_from_camera_c(i)` or `base_from_target_t(i)`'s mount part at pose `pose`:
    /// B(m, i) = Q_i for the gripper, I for the base.
    pub fn base_from_mount(&self, recording: &RigRecording, node: usize, pose: usize) -> Transform {
        self.nodes[node]
            .mount
            .base_from_mount(&recording.poses[pose])
    }
}

/// ", median residual … against … as given", when the check has the numbers.
fn fit_words(check: &crate::check::readings::ReadingCheck) -> String {
    check
        .fit_words()
        .map(|w| format!(" ({w})"))
        .unwrap_or_default()
}
