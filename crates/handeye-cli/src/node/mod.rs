//! `handeye node`: the online calibrator on a live ROS 2 system (SPEC sec. 10). It subscribes to
//! `/tf`, `/tf_static` and the target's pose topic, pairs each observation of the target with the
//! robot's pose at its stamp (the bag reader's tf buffer and rules, `LivePairs`), feeds the
//! online calibrator, publishes X on `/tf_static` whenever an estimate is good, and every
//! estimate, change, event and refusal on `/handeye/status` as the JSON line `online` prints (the
//! same lines on stdout). The DDS layer is RustDDS through `ros2-client` (docs/DECISIONS.md).

mod msg;

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context as _, Result, bail};
use clap::Args as ClapArgs;
use handeye::io::StampedPosePair;
use handeye::io::rosbag::{BagOptions, LiveOutcome, LivePairs, LiveTransform};
use handeye::{Estimator, Name, OnlineCalibrator, OnlineSettings, Outputs, Record, Setup, Unit};
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{
    Context, MessageTypeName, Name as RosName, Node, NodeName, NodeOptions, QosProfile,
};
use serde_json::{Value, json};

use crate::faces::Frames;
use crate::values;
use msg::{PoseStamped, StringMsg, TfMessage, TransformStamped};

/// Options of `handeye node`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// The robot's base frame (e.g. `base_link`).
    #[arg(long)]
    base_frame: String,
    /// The gripper's frame (e.g. `tool0`).
    #[arg(long)]
    gripper_frame: String,
    /// The camera frame whose pose X is (an optical frame below `camera_link` is carried to the
    /// root of the camera's subtree when X is published, as `calibrate` does for a recording).
    #[arg(long)]
    camera_frame: String,
    /// The target's frame: needed when its pose is in /tf; with a TransformStamped topic, its
    /// `child_frame_id` must be it.
    #[arg(long, required_unless_present = "target_topic")]
    target_frame: Option<String>,
    /// The topic of the target's pose in the camera (`geometry_msgs/msg/PoseStamped`, e.g.
    /// `/board_pose`); without it, every /tf transform whose child is --target-frame is an
    /// observation.
    #[arg(long)]
    target_topic: Option<String>,
    /// The type of --target-topic.
    #[arg(long, default_value = "PoseStamped", value_parser = ["PoseStamped", "TransformStamped"])]
    target_type: String,
    /// The setup: the camera on the gripper (X = gripper_from_camera) or fixed (X =
    /// base_from_camera).
    #[arg(long, default_value_t = Setup::EyeInHand, value_parser = values::named::<Setup>())]
    setup: Setup,
    /// `online` (every observation, the accumulating estimator with change detection). The
    /// `samples` mode (services) is not built yet and is refused.
    #[arg(long, default_value = "online", value_parser = ["online", "samples"])]
    mode: String,
    /// The estimator, as `online --estimator`; only the accumulating one's X (which carries an
    /// uncertainty) is published on /tf_static.
    #[arg(long, default_value_t = Estimator::Accumulate, value_parser = values::named::<Estimator>())]
    estimator: Estimator,
    /// A prior on a component of X's translation, as `online --prior` (metres).
    #[arg(long, value_name = "NAME=VALUE[+-SIGMA]", value_parser = values::prior)]
    prior: Vec<handeye::Prior>,
    /// Report the estimate at least every N pose pairs, as `online --every`.
    #[arg(long, default_value_t = handeye::TrackOptions::default().every, value_parser = values::count(1, u64::MAX))]
    every: usize,
    /// Camera clock minus robot clock, seconds: the robot is looked up at t − offset for an
    /// observation stamped t.
    #[arg(long, default_value_t = 0.0)]
    time_offset: f64,
    /// A dynamic transform is not interpolated across a gap longer than this, seconds.
    #[arg(long, default_value_t = 0.1, value_parser = values::positive)]
    max_gap: f64,
    /// Write every pose pair taken as a JSON Lines recording (`calibrate`, `verify` read it),
    /// flushed at each pair and at the end.
    #[arg(long, value_name = "FILE.jsonl")]
    record: Option<PathBuf>,
    /// Stop after this many seconds (for tests and scripts); default: until SIGINT or SIGTERM.
    #[arg(long, value_parser = values::positive)]
    duration: Option<f64>,
    /// Stop after this many pose pairs.
    #[arg(long, value_parser = values::count(1, u64::MAX))]
    max_pairs: Option<usize>,
}

/// How often the subscriptions are read when nothing arrives.
const POLL: Duration = Duration::from_millis(1);

/// Runs the node until SIGINT/SIGTERM, --duration or --max-pairs.
pub fn run(args: Args) -> Result<()> {
    if args.mode == "samples" {
        bail!(
            "--mode samples (the services /handeye/take_sample, /handeye/compute, /handeye/save) is not built yet: use --mode online"
        );
    }
    let options = BagOptions {
        base_frame: args.base_frame.clone(),
        gripper_frame: args.gripper_frame.clone(),
        camera_frame: args.camera_frame.clone(),
        target_frame: args.target_frame.clone(),
        target_topic: args.target_topic.clone(),
        time_offset: args.time_offset,
        max_gap: args.max_gap,
        setup: args.setup,
    };
    let mut live = LivePairs::new(&options)?;
    let mut calibrator = OnlineSettings {
        setup: args.setup,
        estimator: args.estimator,
        unit: Unit::Metre,
        every: Some(args.every),
        priors: args.prior.clone(),
        written: handeye::Written::FRAMES,
        ..OnlineSettings::default()
    }
    .calibrator()?;
    let frames = Frames {
        parent: match args.setup {
            Setup::EyeInHand => crate::faces::frame_name("gripper_frame", &args.gripper_frame)?,
            Setup::EyeToHand => crate::faces::frame_name("base_frame", &args.base_frame)?,
        },
        child: crate::faces::frame_name("camera_frame", &args.camera_frame)?,
        base: crate::faces::frame_name("base_frame", &args.base_frame)?,
        gripper: crate::faces::frame_name("gripper_frame", &args.gripper_frame)?,
        target: args.target_frame.clone().unwrap_or_else(|| "target".into()),
        name: "handeye".into(),
    };
    let mut record = match &args.record {
        Some(path) => {
            Some(BufWriter::new(File::create(path).with_context(|| {
                format!("cannot write {}", path.display())
            })?))
        }
        None => None,
    };

    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = stop.clone();
        ctrlc::set_handler(move || stop.store(true, Ordering::SeqCst))
            .context("cannot install the SIGINT/SIGTERM handler")?;
    }

    let ros = Ros::open(&args)?;
    crate::tell!(
        "handeye node: listening on /tf, /tf_static{} (domain {}); X on /tf_static, status on /handeye/status",
        args.target_topic
            .as_deref()
            .map_or(String::new(), |t| format!(", {t}")),
        ros.domain
    );
    let mut node = Running {
        ros,
        setup: args.setup,
        frames,
        published: None,
        pairs: 0,
        source: args
            .target_topic
            .clone()
            .unwrap_or_else(|| "/tf".to_string()),
    };
    let start = Instant::now();
    let deadline = args.duration.map(Duration::from_secs_f64);
    loop {
        if stop.load(Ordering::SeqCst) || deadline.is_some_and(|d| start.elapsed() >= d) {
            break;
        }
        if args.max_pairs.is_some_and(|n| node.pairs >= n) {
            break;
        }
        let took = node.read(&mut live);
        for outcome in live.ready() {
            node.outcome(outcome, &mut calibrator, record.as_mut(), &live)?;
        }
        if !took {
            std::thread::sleep(POLL);
        }
    }
    // The end: the observations still waiting are decided, the last report made and published.
    for outcome in live.finish() {
        node.outcome(outcome, &mut calibrator, record.as_mut(), &live)?;
    }
    if calibrator.poses() > 0 {
        let o = calibrator.finish()?;
        node.outputs(&o, &live)?;
    }
    if let Some(r) = record.as_mut() {
        r.flush().context("cannot write the record file")?;
    }
    crate::tell!(
        "handeye node: stopped after {:.1} s: {} observation(s), {} pose pair(s)",
        start.elapsed().as_secs_f64(),
        live.observations(),
        node.pairs
    );
    Ok(())
}

/// The DDS side: the node, its subscriptions and publishers.
struct Ros {
    _node: Node,
    domain: u16,
    tf: ros2_client::Subscription<TfMessage>,
    tf_static: ros2_client::Subscription<TfMessage>,
    target_pose: Option<ros2_client::Subscription<PoseStamped>>,
    target_transform: Option<ros2_client::Subscription<TransformStamped>>,
    static_out: ros2_client::Publisher<TfMessage>,
    status: ros2_client::Publisher<StringMsg>,
    /// Messages read per topic, for the status lines.
    counts: [usize; 3],
}

/// A ROS name (`/a/b/c`) as its namespace and base name.
fn ros_name(topic: &str) -> Result<RosName> {
    let topic = if topic.starts_with('/') {
        topic.to_string()
    } else {
        format!("/{topic}")
    };
    let (namespace, base) = topic.rsplit_once('/').unwrap_or(("", &topic));
    let namespace = if namespace.is_empty() { "/" } else { namespace };
    RosName::new(namespace, base).map_err(|e| anyhow::anyhow!("topic `{topic}`: {e:?}"))
}

impl Ros {
    fn open(args: &Args) -> Result<Self> {
        let domain = match std::env::var("ROS_DOMAIN_ID") {
            Ok(v) if !v.trim().is_empty() => v
                .trim()
                .parse::<u16>()
                .ok()
                .filter(|d| *d <= 232)
                .with_context(|| format!("ROS_DOMAIN_ID is `{v}`: a number from 0 to 232"))?,
            _ => 0,
        };
        let context = Context::with_options(ros2_client::ContextOptions::new().domain_id(domain))
            .map_err(|e| anyhow::anyhow!("cannot start DDS on domain {domain}: {e:?}"))?;
        let mut node = context
            .new_node(
                NodeName::new("/", "handeye").map_err(|e| anyhow::anyhow!("{e:?}"))?,
                NodeOptions::new().enable_rosout(false),
            )
            .map_err(|e| anyhow::anyhow!("cannot create the ROS 2 node: {e:?}"))?;
        // tf2's QoS: /tf reliable, volatile, depth 100; /tf_static reliable, transient local,
        // depth 1 (a late subscriber still receives it).
        let reliable = |depth| {
            QosProfile::default()
                .reliability_reliable(WhenFull::DEFAULT)
                .durability(Durability::Volatile)
                .history(History::KeepLast { depth })
        };
        let latched = QosProfile::default()
            .reliability_reliable(WhenFull::DEFAULT)
            .durability(Durability::TransientLocal)
            .history(History::KeepLast { depth: 1 });
        let dds = |e| anyhow::anyhow!("DDS: {e:?}");
        let tf_type = || MessageTypeName::new("tf2_msgs", "TFMessage");
        let tf_topic = node
            .create_topic(&ros_name("/tf")?, tf_type(), &reliable(100))
            .map_err(dds)?;
        let static_topic = node
            .create_topic(&ros_name("/tf_static")?, tf_type(), &latched)
            .map_err(dds)?;
        let status_topic = node
            .create_topic(
                &ros_name("/handeye/status")?,
                MessageTypeName::new("std_msgs", "String"),
                &reliable(100),
            )
            .map_err(dds)?;
        let tf = node.create_subscription(&tf_topic, None).map_err(dds)?;
        let tf_static = node
            .create_subscription(&static_topic, Some(latched.clone()))
            .map_err(dds)?;
        let static_out = node
            .create_publisher(&static_topic, Some(latched))
            .map_err(dds)?;
        let status = node.create_publisher(&status_topic, None).map_err(dds)?;
        let (mut target_pose, mut target_transform) = (None, None);
        if let Some(t) = &args.target_topic {
            let is_pose = args.target_type == "PoseStamped";
            let type_name = MessageTypeName::new(
                "geometry_msgs",
                if is_pose {
                    "PoseStamped"
                } else {
                    "TransformStamped"
                },
            );
            let topic = node
                .create_topic(&ros_name(t)?, type_name, &reliable(100))
                .map_err(dds)?;
            if is_pose {
                target_pose = Some(node.create_subscription(&topic, None).map_err(dds)?);
            } else {
                target_transform = Some(node.create_subscription(&topic, None).map_err(dds)?);
            }
        }
        Ok(Self {
            _node: node,
            domain,
            tf,
            tf_static,
            target_pose,
            target_transform,
            static_out,
            status,
            counts: [0; 3],
        })
    }
}

/// The node's state while it runs.
struct Running {
    ros: Ros,
    setup: Setup,
    frames: Frames,
    /// The transform last published on /tf_static (parent, child, parent_from_child).
    published: Option<(String, String, handeye::Transform)>,
    pairs: usize,
    source: String,
}

/// Messages read per pass, per topic, at most (the others wait for the next pass).
const BATCH: usize = 1000;

impl Running {
    /// Reads what has arrived on every subscription; whether anything had.
    fn read(&mut self, live: &mut LivePairs) -> bool {
        let mut took = false;
        for (k, is_static) in [(1, true), (0, false)] {
            for _ in 0..BATCH {
                let sub = if is_static {
                    &self.ros.tf_static
                } else {
                    &self.ros.tf
                };
                let topic = if is_static { "/tf_static" } else { "/tf" };
                match sub.take() {
                    Ok(Some((m, _))) => {
                        took = true;
                        self.ros.counts[k] += 1;
                        let n = self.ros.counts[k];
                        for (j, t) in m.transforms.iter().enumerate() {
                            if self.is_own(t) {
                                continue;
                            }
                            if let Err(why) = tf_transform(t, live, is_static) {
                                self.skipped(topic, n, Some(j), &why);
                            }
                        }
                    }
                    Ok(None) => break,
                    Err(e) => {
                        took = true;
                        self.ros.counts[k] += 1;
                        let n = self.ros.counts[k];
                        self.skipped(topic, n, None, &format!("does not decode: {e:?}"));
                    }
                }
            }
        }
        let topic = self.source.clone();
        for _ in 0..BATCH {
            let taken = if let Some(s) = &self.ros.target_pose {
                s.take().map(|m| {
                    m.map(|(m, _)| {
                        let p = m.pose;
                        (
                            m.header,
                            None,
                            [p.position.x, p.position.y, p.position.z],
                            p.orientation.xyzw(),
                        )
                    })
                })
            } else if let Some(s) = &self.ros.target_transform {
                s.take().map(|m| {
                    m.map(|(m, _)| {
                        let t = m.transform;
                        (
                            m.header,
                            Some(m.child_frame_id),
                            [t.translation.x, t.translation.y, t.translation.z],
                            t.rotation.xyzw(),
                        )
                    })
                })
            } else {
                break;
            };
            match taken {
                Ok(Some((header, child, translation, q))) => {
                    took = true;
                    self.ros.counts[2] += 1;
                    let n = self.ros.counts[2];
                    let result = header.stamp.ns().and_then(|stamp_ns| {
                        live.observation(
                            &header.frame_id,
                            child.as_deref(),
                            stamp_ns,
                            translation,
                            q,
                        )
                    });
                    if let Err(why) = result {
                        self.skipped(&topic, n, None, &why);
                    }
                }
                Ok(None) => break,
                Err(e) => {
                    took = true;
                    self.ros.counts[2] += 1;
                    let n = self.ros.counts[2];
                    self.skipped(&topic, n, None, &format!("does not decode: {e:?}"));
                }
            }
        }
        took
    }

    /// Whether `t` is the transform this node publishes (it comes back on /tf_static).
    fn is_own(&self, t: &TransformStamped) -> bool {
        self.published.as_ref().is_some_and(|(parent, child, _)| {
            t.header.frame_id.trim_start_matches('/') == parent
                && t.child_frame_id.trim_start_matches('/') == child
        })
    }

    /// One line on /handeye/status and stdout.
    fn status(&self, line: &Value) {
        let text = line.to_string();
        println!("{text}");
        let _ = std::io::stdout().flush();
        if let Err(e) = self.ros.status.publish(StringMsg { data: text }) {
            crate::tell!("warning: /handeye/status not published: {e:?}");
        }
    }

    /// A message (or one transform of it) refused: one status line, nothing else changes.
    fn skipped(&self, topic: &str, message: usize, transform: Option<usize>, why: &str) {
        let mut s = json!({"topic": topic, "message": message, "why": why});
        if let Some(j) = transform {
            s["transform"] = j.into();
        }
        self.status(&json!({ "skipped": s }));
    }

    /// An observation decided: a pair fed to the calibrator (and recorded), or dropped.
    fn outcome(
        &mut self,
        outcome: LiveOutcome,
        calibrator: &mut OnlineCalibrator,
        record: Option<&mut BufWriter<File>>,
        live: &LivePairs,
    ) -> Result<()> {
        match outcome {
            LiveOutcome::Dropped { number, stamp, why } => {
                self.status(&json!({"dropped": {"topic": self.source, "observation": number, "stamp": stamp, "why": why}}));
                Ok(())
            }
            LiveOutcome::Pair(pair) => {
                self.pairs += 1;
                if let Some(r) = record {
                    write_pair(r, &pair)?;
                }
                let name = Name::Stamp {
                    source: &self.source,
                    line: pair.line,
                    seconds: pair.stamp.unwrap_or_default(),
                };
                match calibrator.push(Record::pose(&pair.pose).named(name)) {
                    Ok(o) => self.outputs(&o, live),
                    Err(e) => {
                        self.status(&json!({"skipped": {"topic": self.source, "observation": pair.line, "why": e.to_string()}}));
                        Ok(())
                    }
                }
            }
        }
    }

    /// What the calibrator said: status lines, and X published when the report is good.
    fn outputs(&mut self, o: &Outputs, live: &LivePairs) -> Result<()> {
        for h in &o.held_out {
            self.status(
                &json!({"held_out": {"pose": h.name.to_string(), "why": h.why.to_string()}}),
            );
        }
        if let Some(c) = &o.change {
            self.status(&c.change.json());
        }
        if let Some(r) = &o.report {
            let line = r.json(self.setup, None);
            let good = line.get("verdict").and_then(Value::as_str) == Some("good");
            self.status(&line);
            if good {
                self.publish(&r.estimate.x, live.camera_mount())?;
            }
        }
        for event in &o.events {
            self.status(&serde_json::to_value(event)?);
        }
        if let Some(why) = &o.stuck {
            self.status(&json!({ "stuck": why }));
        }
        Ok(())
    }

    /// X on /tf_static, for the root of the camera's subtree when tf gives the camera frame a
    /// parent (the bag reader's optical-frame rule).
    fn publish(
        &mut self,
        x: &handeye::Transform,
        mount: Option<handeye::io::CameraMount>,
    ) -> Result<()> {
        let publication = crate::publish::publication(x, &self.frames, mount.as_ref(), false);
        if !publication.offered {
            if let Some(w) = publication.warning.or(publication.instead) {
                self.status(&json!({ "not_published": w }));
            }
            return Ok(());
        }
        let (parent, child) = (
            publication.frames.parent.clone(),
            publication.frames.child.clone(),
        );
        let now = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap_or_default();
        let message = TfMessage {
            transforms: vec![TransformStamped {
                header: msg::Header {
                    stamp: msg::Time {
                        sec: i32::try_from(now.as_secs()).unwrap_or(i32::MAX),
                        nanosec: now.subsec_nanos(),
                    },
                    frame_id: parent.clone(),
                },
                child_frame_id: child.clone(),
                transform: msg::transform(&publication.x),
            }],
        };
        self.ros
            .static_out
            .publish(message)
            .map_err(|e| anyhow::anyhow!("/tf_static not published: {e:?}"))?;
        let mut line = json!({"parent": parent, "child": child});
        let t = handeye::TransformJson::from(&publication.x);
        line["translation"] = json!(t.translation);
        line["quaternion_xyzw"] = json!(t.quaternion_xyzw);
        if let Some(note) = &publication.note {
            line["note"] = note.clone().into();
        }
        self.status(&json!({ "published": line }));
        self.published = Some((parent, child, publication.x));
        Ok(())
    }
}

/// One pose pair as a JSON Lines record (`stamp`, `base_from_gripper`, `camera_from_target`),
/// flushed so that the file holds it at once.
fn write_pair(out: &mut BufWriter<File>, pair: &StampedPosePair) -> Result<()> {
    let line = json!({
        "stamp": pair.stamp,
        "base_from_gripper": handeye::TransformJson::from(&pair.pose.base_from_gripper),
        "camera_from_target": handeye::TransformJson::from(&pair.pose.camera_from_target),
    });
    writeln!(out, "{line}")
        .and_then(|()| out.flush())
        .context("cannot write the record file")
}

/// One transform of a tf message into the buffer.
fn tf_transform(t: &TransformStamped, live: &mut LivePairs, is_static: bool) -> Result<(), String> {
    let stamp_ns = t.header.stamp.ns()?;
    let tr = t.transform.translation;
    live.transform(
        LiveTransform {
            parent: &t.header.frame_id,
            child: &t.child_frame_id,
            stamp_ns,
            translation: [tr.x, tr.y, tr.z],
            quaternion_xyzw: t.transform.rotation.xyzw(),
        },
        is_static,
    )
}
