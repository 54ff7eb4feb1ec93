//! Issue 34 items 9 to 13 at the command line: `inspect` draws every part of a tf tree (a loop,
//! a chain deeper than it draws, a topic of two types); names from a recording never reach the
//! terminal with their control characters; inputs that never end or cannot be read whole are
//! refused at once; the messages and exit codes of the small cases; the online factors bounded.

#[path = "../../handeye/tests/bags/mod.rs"]
mod bags;
mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use bags::{BagWriter, Pose, T0_NS, tf};
use common::{run, testdata};

/// Runs `handeye` with `args` like [`run`], but never waits past a deadline: a run that blocks
/// (on a pipe no one writes, on an input that never ends) is killed and fails the test. The
/// deadline guards against a hang only; nothing is asserted about time.
fn run_guarded(args: &[&str]) -> (i32, String, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_handeye"))
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(120);
    while child.try_wait().unwrap().is_none() {
        if Instant::now() > deadline {
            child.kill().unwrap();
            panic!("{args:?} did not end");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr,
    )
}

/// A recording whose tf tree has every part `inspect` used to hide: a static chain of 100 frames
/// under `base_link` (deeper than the 64 levels drawn), a loop of three frames with a frame
/// hanging from it, and a topic written under two types; `names` adds frames and a topic with
/// those names (hostile ones) under `tool0`.
fn odd_tree(dir: &Path, names: &[&str]) -> PathBuf {
    let path = dir.join("odd.mcap");
    let mut bag = BagWriter::create(&path, false, None);
    let (robot, target) = bags::eye_in_hand(1);
    bags::write_robot(&mut bag, &robot);
    let mut statics = vec![
        tf("loop_b", "loop_a", T0_NS, Pose::identity()),
        tf("loop_c", "loop_b", T0_NS, Pose::identity()),
        tf("loop_a", "loop_c", T0_NS, Pose::identity()),
        tf("loop_b", "hanging", T0_NS, Pose::identity()),
        tf("tool0", "camera", T0_NS, Pose::identity()),
    ];
    for k in 1..=100 {
        let parent = if k == 1 {
            "world".to_string()
        } else {
            format!("deep{}", k - 1)
        };
        statics.push(tf(&parent, &format!("deep{k}"), T0_NS, Pose::identity()));
    }
    for name in names {
        statics.push(tf("tool0", name, T0_NS, Pose::identity()));
    }
    bag.tf_static(&statics);
    for (stamp, pose) in &target {
        bag.write(
            "/board",
            bags::POSE_STAMPED,
            *stamp,
            bags::pose_stamped("camera", *stamp, pose),
        );
        bag.write(
            "/pose",
            bags::POSE_STAMPED,
            *stamp,
            bags::pose_stamped("camera", *stamp, pose),
        );
        for name in names {
            bag.write(
                &format!("/{name}"),
                bags::POSE_STAMPED,
                *stamp,
                bags::pose_stamped("camera", *stamp, pose),
            );
        }
    }
    for k in 0..7 {
        bag.write(
            "/board",
            "std_msgs/msg/String",
            T0_NS + k,
            vec![0, 1, 0, 0, 1, 0, 0, 0, 0],
        );
    }
    bag.finish();
    path
}

/// Issue 34 item 9: `inspect --output text` hid a tf loop (it has no root), stopped drawing at
/// depth 64 without a mark, and lost the messages of a topic of two types from its totals.
#[test]
fn inspect_text_shows_every_part_of_the_tree() {
    let dir = tempfile::tempdir().unwrap();
    let path = odd_tree(dir.path(), &[]);
    let path = path.to_str().unwrap();
    let (code, text, err) = run(&["inspect", path, "--output", "text"]);
    assert_eq!(code, 0, "{err}");
    // 101 robot + 1 static + 10 + 7 on /board + 10 on /pose, each topic line's count in the
    // total.
    assert!(text.contains("129 message(s)"), "{text}");
    assert!(
        text.contains("geometry_msgs/msg/PoseStamped       10"),
        "{text}"
    );
    assert!(
        text.contains("std_msgs/msg/String                  7"),
        "{text}"
    );
    // The chain is drawn to `deep64`, and the 36 frames below are counted.
    assert!(
        text.contains("└─ deep64  (static)") && !text.contains("deep65  (static)"),
        "{text}"
    );
    assert!(
        text.contains("└─ … 36 more frame(s) below `deep64`"),
        "{text}"
    );
    // The loop is named as a loop, and what hangs from it is drawn.
    assert!(text.contains("a loop of 3 frame(s)"), "{text}");
    assert!(text.contains("loop_a → loop_b → loop_c → loop_a"), "{text}");
    assert!(text.contains("  loop_b\n  └─ hanging  (static)"), "{text}");
    let (_, json, _) = run(&["inspect", path, "--output", "json"]);
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(
        v["loops"],
        serde_json::json!([["loop_a", "loop_b", "loop_c"]])
    );
}

/// Issue 34 item 10: escape sequences in frame and topic names reached the terminal raw, from
/// `inspect` and from `calibrate`'s messages. Every control character is shown escaped; JSON
/// keeps the names, escaped as JSON escapes them.
#[test]
fn names_with_escape_sequences_never_reach_the_terminal_raw() {
    let dir = tempfile::tempdir().unwrap();
    let names = [
        "cam\u{1b}[2J\u{1b}[31mred",
        "title\u{1b}]0;pwned\u{7}",
        "del\u{7f}csi\u{9b}31m",
    ];
    let path = odd_tree(dir.path(), &names);
    let path = path.to_str().unwrap();
    let raw = |s: &str| s.chars().any(|c| c.is_control() && c != '\n' && c != '\t');
    let (code, text, err) = run(&["inspect", path, "--output", "text"]);
    assert_eq!(code, 0, "{err}");
    assert!(!raw(&text), "{text:?}");
    assert!(text.contains("cam\\u{1b}[2J\\u{1b}[31mred"), "{text}");
    assert!(text.contains("/title\\u{1b}]0;pwned\\u{7}"), "{text}");
    // JSON: the names come back whole, and no control character is written raw.
    let (_, json, _) = run(&["inspect", path, "--output", "json"]);
    assert!(!raw(&json), "{json:?}");
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    for name in names {
        assert!(
            v["frames"].as_array().unwrap().iter().any(|f| f == name),
            "{name:?}"
        );
    }
    // calibrate's errors list the recording's frames and topics.
    for flags in [
        ["--camera-frame", "camera_x", "--target-topic", "/pose"],
        ["--camera-frame", "camera", "--target-topic", "/pos"],
    ] {
        let mut args = vec![
            "calibrate",
            path,
            "--base-frame",
            "base_link",
            "--gripper-frame",
            "tool0",
        ];
        args.extend(flags);
        let (code, _, err) = run(&args);
        assert_eq!(code, 2, "{err}");
        assert!(!raw(&err), "{err:?}");
        assert!(err.contains("\\u{1b}"), "{err}");
    }
}

/// Issue 34 item 11: a pipe in a ViSP directory blocked, a link to `/dev/zero` read 2 GB, and
/// `online /dev/zero` read forever without a word. Each is refused at once, named.
#[test]
fn inputs_that_never_end_are_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let visp = dir.path().join("visp");
    std::fs::create_dir(&visp).unwrap();
    let pose =
        "rows: 6\ncols: 1\ndata:\n  - [0.1]\n  - [0]\n  - [0]\n  - [0]\n  - [0]\n  - [0.3]\n";
    for k in 1..=3 {
        std::fs::write(visp.join(format!("pose_cPo_{k}.yaml")), pose).unwrap();
    }
    std::fs::write(visp.join("pose_rPe_2.yaml"), pose).unwrap();
    std::fs::write(visp.join("pose_rPe_3.yaml"), pose).unwrap();
    let fifo = visp.join("pose_rPe_1.yaml");
    let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    let visp = visp.to_str().unwrap();
    let (code, _, err) = run_guarded(&["calibrate", visp]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("pose_rPe_1.yaml") && err.contains("not a regular file"),
        "{err}"
    );
    std::fs::remove_file(&fifo).unwrap();
    std::os::unix::fs::symlink("/dev/zero", &fifo).unwrap();
    let (code, _, err) = run_guarded(&["calibrate", visp]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("pose_rPe_1.yaml") && err.contains("not a regular file"),
        "{err}"
    );
    for args in [&["online", "/dev/zero"][..], &["calibrate", "/dev/zero"]] {
        let (code, _, err) = run_guarded(args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(
            err.contains(
                "/dev/zero:1: field `-`: a line longer than 65536 bytes before any pose record"
            ),
            "{err}"
        );
    }
    for format in ["opencv-yaml", "moveit"] {
        let (code, _, err) = run_guarded(&["calibrate", "--format", format, "/dev/zero"]);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains("a device or a socket, not a file"), "{err}");
    }
}

/// A JSON Lines pose file of the repository (10 noisy poses, metres).
fn poses() -> String {
    testdata("opencv/opencv_eye-in-hand_noisy_10_12.jsonl")
        .display()
        .to_string()
}

/// Issue 34 item 12: the messages and exit codes of small cases, each said plainly.
#[test]
fn small_cases_have_the_right_words_and_exit_codes() {
    let dir = tempfile::tempdir().unwrap();
    let file = |name: &str, bytes: &[u8]| {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        path.display().to_string()
    };
    let jsonl = std::fs::read_to_string(poses()).unwrap();
    // A NUL in a CSV header was "the input is empty".
    let csv = file(
        "nul.csv",
        b"stamp,base_from_gripper_x\0,base_from_gripper_y\n1,2,3\n",
    );
    let (code, _, err) = run(&["calibrate", &csv]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("nul.csv:1:") && err.contains("no CSV header") && err.contains("NUL"),
        "{err}"
    );
    // UTF-16: online exited 0 having read no pose (calibrate 2).
    let utf16: Vec<u8> = [0xff, 0xfe]
        .into_iter()
        .chain(jsonl.encode_utf16().flat_map(u16::to_le_bytes))
        .collect();
    let utf16 = file("utf16.jsonl", &utf16);
    for command in ["calibrate", "online"] {
        let (code, _, err) = run(&[command, &utf16]);
        assert_eq!(code, 2, "{command}: {err}");
        assert!(
            err.contains("utf16.jsonl:1:") && err.contains("UTF-16"),
            "{command}: {err}"
        );
    }
    // A stream without a pose record: online says so, exit 2, as calibrate.
    let comments = file("comments.jsonl", b"# nothing recorded\n\n");
    let (code, _, err) = run(&["online", &comments]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("no pose pair in the input"), "{err}");
    // A BOM was refused in moveit JSON only.
    let lines: Vec<serde_json::Value> = jsonl
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let moveit: Vec<serde_json::Value> = lines
        .iter()
        .map(|v| serde_json::json!([v["base_from_gripper"], v["camera_from_target"]]))
        .collect();
    let moveit = serde_json::to_string(&moveit).unwrap();
    let plain = file("plain.json", moveit.as_bytes());
    let bom = file("bom.json", format!("\u{feff}{moveit}").as_bytes());
    let (code, with_bom, err) = run(&["calibrate", &bom, "--output", "json"]);
    assert_eq!(code, 0, "{err}");
    let (_, without, _) = run(&["calibrate", &plain, "--output", "json"]);
    let matrix =
        |text: &str| serde_json::from_str::<serde_json::Value>(text).unwrap()["matrix"].clone();
    assert_eq!(matrix(&with_bom), matrix(&without));
    // --time-offset and --max-gap on a pose file were ignored without a word.
    for flags in [["--time-offset", "5"], ["--max-gap", "0.5"]] {
        for command in ["calibrate", "online"] {
            let mut args = vec![command, &plain];
            args.extend(flags);
            let (code, _, err) = run(&args);
            assert_eq!(code, 2, "{args:?}: {err}");
            assert!(
                err.contains(&format!("{} pairs two stamped streams", flags[0])),
                "{err}"
            );
        }
    }
    // An offset of 1e308 printed its 309 digits, and an error "at line 0".
    let (robot, camera) = (
        testdata("kinhec/streams/temporal_10hz_eih_s0_robot.txt"),
        testdata("kinhec/streams/temporal_10hz_eih_s0_camera.txt"),
    );
    for offset in ["1e308", "-1e308"] {
        let (code, _, err) = run(&[
            "calibrate",
            "--robot",
            robot.to_str().unwrap(),
            "--camera",
            camera.to_str().unwrap(),
            "--time-offset",
            offset,
        ]);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains("at most 4e9"), "{err}");
        assert!(err.len() < 400, "{err}");
    }
    let (code, _, err) = run(&[
        "calibrate",
        "--robot",
        robot.to_str().unwrap(),
        "--camera",
        camera.to_str().unwrap(),
        "--time-offset",
        "4e9",
    ]);
    assert_eq!(code, 2, "{err}");
    // No pair at that offset: the message says the offset was applied.
    assert!(
        err.contains("0 camera sample(s) within")
            && err.contains("shifted by the clock offset of 4e9 s"),
        "{err}"
    );
    // An unwritable --report lost the computed result: it is checked before the work.
    let report = dir.path().join("no such dir/report.html");
    for command in ["calibrate", "online"] {
        let (code, out, err) = run(&[command, &plain, "--report", report.to_str().unwrap()]);
        assert_eq!(code, 1, "{command}: {err}");
        assert!(
            out.is_empty() && err.contains("cannot write the report"),
            "{command}: {err}"
        );
        assert!(
            !err.contains("pose"),
            "{command}: nothing read before: {err}"
        );
    }
}

/// Issue 34 item 12: "no calibration in the last N poses" came every 200 poses of a stuck
/// stream; it comes at 200, 400, 800, … poses without one.
#[test]
fn a_stuck_stream_is_told_so_at_growing_intervals() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(poses()).unwrap();
    let first: Vec<&str> = text.lines().take(7).collect();
    let mut stuck = first.join("\n");
    for _ in 0..1_000 {
        stuck.push('\n');
        stuck.push_str(first[6]);
    }
    let path = dir.path().join("stuck.jsonl");
    std::fs::write(&path, stuck).unwrap();
    let (code, _, err) = run(&[
        "online",
        path.to_str().unwrap(),
        "--estimator",
        "paper",
        "--output",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    let told: Vec<&str> = err
        .lines()
        .filter(|l| l.starts_with("no calibration in"))
        .collect();
    // At 200, 400 and 800 poses, then once in the summary (1007 poses).
    assert_eq!(told.len(), 4, "{err}");
    for (line, poses) in told.iter().zip(["200", "400", "800", "1007"]) {
        assert!(
            line.starts_with(&format!("no calibration in {poses} poses")),
            "{line}"
        );
    }
}

/// Issue 34 item 13: `--relax-up 1e308` and `--explore 1e-320` made every event's `"d"` null.
/// The factors are bounded (exit 2, the range named); at their bounds every threshold is a
/// number.
#[test]
fn the_online_factors_are_bounded_and_keep_the_thresholds_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let stream = dir.path().join("sim.jsonl");
    let (code, _, err) = run(&[
        "simulate",
        "--poses",
        "300",
        "--seed",
        "1",
        "--out",
        stream.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let stream = stream.to_str().unwrap();
    for (flag, value, range) in [
        ("--relax-up", "1e308", "[1, 10]"),
        ("--explore", "1e-320", "[0.1, 10]"),
        ("--relax-down", "1e-320", "[0.1, 1]"),
    ] {
        let (code, out, err) = run(&["online", stream, "--estimator", "paper", flag, value]);
        assert_eq!(code, 2, "{flag}: {err}");
        assert!(
            out.is_empty() && err.contains(flag) && err.contains(range),
            "{err}"
        );
    }
    for (flag, value) in [
        ("--relax-up", "10"),
        ("--explore", "0.1"),
        ("--explore", "10"),
    ] {
        let (code, out, err) = run(&[
            "online",
            stream,
            "--estimator",
            "paper",
            flag,
            value,
            "--output",
            "json",
        ]);
        assert_eq!(code, 0, "{flag} {value}: {err}");
        let events: Vec<serde_json::Value> = out
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        assert!(!events.is_empty(), "{flag} {value}: {err}");
        for e in &events {
            for t in ["sin_alpha", "beta", "d"] {
                assert!(
                    e["thresholds"][t].as_f64().is_some_and(f64::is_finite),
                    "{flag} {value}: {e}"
                );
            }
        }
    }
}
