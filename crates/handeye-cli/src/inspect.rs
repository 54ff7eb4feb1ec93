//! `handeye inspect BAG`: what a ROS 2 recording holds (topics, types, counts, the tf tree), so
//! that the frames and the target topic of `calibrate` / `online` can be chosen.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::Result;
use clap::Args as ClapArgs;
use handeye::io::rosbag::{BagSummary, TfEdge, inspect_bag};

use crate::faces::Face;
use crate::output::{print_json, print_text};

/// Options of `handeye inspect`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// The recording: a rosbag2 directory (with its metadata.yaml), an .mcap or a .db3 file.
    #[arg(value_name = "BAG")]
    bag: PathBuf,
    /// Output: JSON, or text for a person [default: text on a terminal, JSON otherwise].
    #[arg(long, value_parser = crate::values::named_of(&[Face::Json, Face::Text]))]
    output: Option<Face>,
}

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    let summary = inspect_bag(&args.bag)?;
    if Face::chosen(args.output) == Face::Text {
        print_text(&render(&summary))
    } else {
        print_json(&summary)
    }
}

/// The summary for a person: the topics as a table, the tf tree drawn from each root.
pub fn render(s: &BagSummary) -> String {
    let mut out = String::new();
    let storage = serde_json::to_value(s.storage)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_default();
    let _ = writeln!(
        out,
        "{}: {storage}, {} file(s), {} message(s)\n\ntopics",
        s.path,
        s.files.len(),
        s.messages
    );
    let width = s.topics.iter().map(|t| t.topic.len()).max().unwrap_or(0);
    let type_width = s.topics.iter().map(|t| t.msg_type.len()).max().unwrap_or(0);
    for t in &s.topics {
        let note = if s.target_topics.contains(&t.topic) {
            "   a target pose topic (--target-topic)"
        } else {
            ""
        };
        let _ = writeln!(
            out,
            "  {:width$}  {:type_width$}  {:>7}{note}",
            t.topic, t.msg_type, t.count
        );
    }
    let _ = writeln!(out, "\ntf tree");
    if s.tf.is_empty() {
        let _ = writeln!(out, "  (no transforms in /tf or /tf_static)");
    }
    let mut children: BTreeMap<&str, Vec<&TfEdge>> = BTreeMap::new();
    for e in &s.tf {
        children.entry(e.parent.as_str()).or_default().push(e);
    }
    for root in &s.roots {
        let _ = writeln!(out, "  {root}");
        draw(&mut out, &children, root, "  ", 0);
    }
    let _ = writeln!(
        out,
        "\nCalibrate with --base-frame and --gripper-frame from the robot's tree, --camera-frame, and\n--target-frame (the target in /tf) or --target-topic."
    );
    out
}

fn draw(
    out: &mut String,
    children: &BTreeMap<&str, Vec<&TfEdge>>,
    frame: &str,
    indent: &str,
    depth: usize,
) {
    let Some(list) = children.get(frame) else {
        return;
    };
    // A loop cannot come from one parent per frame, but a bound costs nothing.
    if depth > 64 {
        return;
    }
    for (k, e) in list.iter().enumerate() {
        let last = k + 1 == list.len();
        let what = if e.is_static {
            "static".to_string()
        } else {
            format!(
                "dynamic, {} sample(s){}",
                e.samples,
                e.rate_hz.map_or(String::new(), |r| format!(", {r:.1} Hz"))
            )
        };
        let _ = writeln!(
            out,
            "{indent}{}{}  ({what})",
            if last { "└─ " } else { "├─ " },
            e.child
        );
        let deeper = format!("{indent}{}", if last { "   " } else { "│  " });
        draw(out, children, &e.child, &deeper, depth + 1);
    }
}
