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

/// The summary for a person: the topics as a table, the tf tree drawn from each root, then any
/// loop of parent links. Every name from the recording is shown with its control characters
/// escaped.
pub fn render(s: &BagSummary) -> String {
    let mut out = String::new();
    let storage = serde_json::to_value(s.storage)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_default();
    let _ = writeln!(
        out,
        "{}: {storage}, {} file(s), {} message(s)\n\ntopics",
        shown(&s.path),
        s.files.len(),
        s.messages
    );
    let names: Vec<(String, String)> = s
        .topics
        .iter()
        .map(|t| (shown(&t.topic), shown(&t.msg_type)))
        .collect();
    let width = names.iter().map(|t| t.0.chars().count()).max().unwrap_or(0);
    let type_width = names.iter().map(|t| t.1.chars().count()).max().unwrap_or(0);
    for (t, (topic, msg_type)) in s.topics.iter().zip(&names) {
        let note = if s.target_topics.contains(&t.topic) {
            "   a target pose topic (--target-topic)"
        } else {
            ""
        };
        let _ = writeln!(
            out,
            "  {topic:width$}  {msg_type:type_width$}  {:>7}{note}",
            t.count
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
        let _ = writeln!(out, "  {}", shown(root));
        draw(&mut out, &children, root, &[], "  ", 0);
    }
    for frames in &s.loops {
        draw_loop(&mut out, &children, frames);
    }
    let _ = writeln!(
        out,
        "\nCalibrate with --base-frame and --gripper-frame from the robot's tree, --camera-frame, and\n--target-frame (the target in /tf) or --target-topic."
    );
    out
}

/// A name from the recording as it is printed: control characters escaped.
fn shown(name: &str) -> String {
    crate::output::escaped(name).into_owned()
}

/// Levels of the tree drawn; deeper frames are counted, not drawn.
const MAX_DEPTH: usize = 64;

/// A loop of parent links (its frames have no root), then what hangs from its frames.
fn draw_loop(out: &mut String, children: &BTreeMap<&str, Vec<&TfEdge>>, frames: &[String]) {
    let mut words: Vec<String> = frames.iter().map(|f| shown(f)).collect();
    words.extend(frames.first().map(|f| shown(f)));
    let _ = writeln!(
        out,
        "  a loop of {} frame(s), each the child of the next, so without a root (tf allows no loop, and no lookup passes through one):\n  {}",
        frames.len(),
        words.join(" → ")
    );
    for f in frames {
        if children
            .get(f.as_str())
            .is_some_and(|list| list.iter().any(|e| !frames.contains(&e.child)))
        {
            let _ = writeln!(out, "  {}", shown(f));
            draw(out, children, f, frames, "  ", 0);
        }
    }
}

/// Draws the children of `frame` (those in `skip` left out), to [`MAX_DEPTH`] levels; below it a
/// line counts the frames not drawn.
fn draw(
    out: &mut String,
    children: &BTreeMap<&str, Vec<&TfEdge>>,
    frame: &str,
    skip: &[String],
    indent: &str,
    depth: usize,
) {
    let Some(list) = children.get(frame) else {
        return;
    };
    let list: Vec<&&TfEdge> = list.iter().filter(|e| !skip.contains(&e.child)).collect();
    if depth >= MAX_DEPTH {
        let below: usize = list
            .iter()
            .map(|e| 1 + descendants(children, &e.child))
            .sum();
        let _ = writeln!(
            out,
            "{indent}└─ … {below} more frame(s) below `{}`, deeper than {MAX_DEPTH} levels (not drawn; --output json lists every edge)",
            shown(frame)
        );
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
            shown(&e.child)
        );
        let deeper = format!("{indent}{}", if last { "   " } else { "│  " });
        draw(out, children, &e.child, skip, &deeper, depth + 1);
    }
}

/// The frames below `frame` (its children, theirs, …), counted without recursion.
fn descendants(children: &BTreeMap<&str, Vec<&TfEdge>>, frame: &str) -> usize {
    let mut stack = vec![frame];
    let mut count = 0;
    while let Some(f) = stack.pop() {
        for e in children.get(f).into_iter().flatten() {
            count += 1;
            stack.push(&e.child);
        }
    }
    count
}
