//! `io::Recording`, the one entry for every input: the same pose pairs, names, clock offset and
//! notes the command line shows (checked against its golden outputs, `testdata/golden`), and a
//! clear error, never a panic, on bad input.

mod shared_data;

use std::path::{Path, PathBuf};

use handeye::io::{
    BagFrames, Format, Note, Recording, RecordingOptions, Source, TimeOffset, read_pose_file,
};
use handeye::{Error, Setup};
use serde_json::Value;

/// A path under the repository's root as the tests see it (they run in `crates/handeye`).
fn repo(path: &str) -> PathBuf {
    Path::new("../..").join(path)
}

/// The golden output of the CLI command `args` (paths relative to the repository's root).
fn golden(args: &str) -> Value {
    let outputs = std::fs::read_to_string(repo("testdata/golden/outputs.jsonl")).unwrap();
    outputs
        .lines()
        .map(|line| serde_json::from_str::<Value>(line).unwrap())
        .find(|e| {
            let words: Vec<&str> = e["args"]
                .as_array()
                .unwrap()
                .iter()
                .map(|w| w.as_str().unwrap())
                .collect();
            words.join(" ") == args
        })
        .unwrap_or_else(|| panic!("no golden output for `{args}`"))
}

/// The first `n` lines the CLI printed on stderr, paths as the tests see them (the shared
/// folder's in place of `{shared}`).
fn golden_notes(entry: &Value, n: usize) -> Vec<String> {
    entry["stderr"]
        .as_str()
        .unwrap()
        .lines()
        .take(n)
        .map(|l| shared_data::unmasked(&l.replace("testdata/", "../../testdata/")))
        .collect()
}

fn texts(notes: &[Note]) -> Vec<String> {
    notes.iter().map(Note::to_string).collect()
}

/// ethz-asl's two streams `name` (`robot_arm_sim`, `prime_sense_1`) in the shared folder, and
/// their paths in the golden commands; `None` when the folder has no ethz-asl.
fn ethz(name: &str) -> Option<(Source, String, String)> {
    let dir = shared_data::shared("ethz-asl")?;
    let source = Source::Streams {
        robot: dir.join(format!("{name}_B_H.csv")),
        camera: dir.join(format!("{name}_W_E.csv")),
    };
    let golden = |side: &str| format!("{}/ethz-asl/{name}_{side}.csv", shared_data::PLACEHOLDER);
    Some((source, golden("B_H"), golden("W_E")))
}

fn auto() -> RecordingOptions {
    RecordingOptions {
        time_offset: Some(TimeOffset::Auto),
        ..RecordingOptions::default()
    }
}

#[test]
fn a_jsonl_file_gives_its_pairs_named_by_line() {
    let path = repo("testdata/opencv/opencv_eye-in-hand_exact_10_11.jsonl");
    let source = Source::File {
        path: path.clone(),
        format: Format::Auto,
    };
    let r = Recording::read(&source, &RecordingOptions::default()).unwrap();
    let series = read_pose_file(&path, Format::Auto).unwrap();
    assert_eq!(r.poses, series.pairs);
    assert_eq!(r.lines, series.lines);
    assert_eq!(r.stamps, series.stamps);
    let expected: Vec<String> = (1..=10)
        .map(|l| format!("{}:{l}", path.display()))
        .collect();
    assert_eq!(r.names, expected);
    assert_eq!(
        (r.time_offset, &r.offset_curve, &r.target_source),
        (None, &None, &None)
    );
    assert!(r.notes.is_empty());
    assert_eq!(r.records().len(), 10);
    assert_eq!(r.records()[3].line, 4);
}

#[test]
fn two_streams_with_auto_give_the_cli_offset_notes_and_names() {
    let Some((source, robot, camera)) = ethz("robot_arm_sim") else {
        return;
    };
    let entry = golden(&format!(
        "calibrate --robot {robot} --camera {camera} --time-offset auto --output json"
    ));
    let mut told = Vec::new();
    let r = Recording::read_telling(&source, &auto(), &mut |n| told.push(n.to_string())).unwrap();
    assert_eq!(told, golden_notes(&entry, 3));
    assert_eq!(texts(&r.notes), told);
    let report: Value = serde_json::from_str(entry["stdout"].as_str().unwrap()).unwrap();
    assert_eq!(r.time_offset, report["time_offset_s"].as_f64());
    assert_eq!(r.poses.len() as u64, report["poses"].as_u64().unwrap());
    assert_eq!(r.names.len(), r.poses.len());
    let stamp = r.stamps[0].unwrap();
    assert_eq!(
        r.names[0],
        format!("{} at t = {stamp:.3} s", shared_data::unmasked(&camera))
    );
    assert_eq!(r.lines[..3], [1, 2, 3]);
    let curve = r.offset_curve.as_ref().unwrap();
    let best = curve
        .iter()
        .copied()
        .max_by(|a, b| a[1].total_cmp(&b[1]))
        .unwrap();
    assert!((best[0] - r.time_offset.unwrap()).abs() < 0.02, "{best:?}");
}

#[test]
fn two_streams_without_an_offset_flag_are_searched_by_default_with_its_sigma() {
    let Some((source, robot, camera)) = ethz("prime_sense_1") else {
        return;
    };
    let r = Recording::read(&source, &RecordingOptions::default()).unwrap();
    let entry = golden(&format!(
        "calibrate --robot {robot} --camera {camera} --output json"
    ));
    let report: Value = serde_json::from_str(entry["stdout"].as_str().unwrap()).unwrap();
    // The default is the search: the same offset and sigma as the command line's.
    assert_eq!(r.time_offset, report["time_offset_s"].as_f64());
    assert_eq!(r.time_offset_sigma, report["time_offset_sigma_s"].as_f64());
    assert!(r.time_offset_sigma.unwrap() > 0.0 && r.offset_curve.is_some());
    assert_eq!(r.poses.len() as u64, report["poses"].as_u64().unwrap());
    let notes = golden_notes(&entry, r.notes.len());
    assert_eq!(texts(&r.notes), notes);
    // Asked for 0 s: paired at 0 s, no sigma, no curve.
    let zero = RecordingOptions {
        time_offset: Some(TimeOffset::Fixed(0.0)),
        ..RecordingOptions::default()
    };
    let r = Recording::read(&source, &zero).unwrap();
    assert_eq!(r.time_offset, Some(0.0));
    assert!(r.time_offset_sigma.is_none() && r.offset_curve.is_none());
}

fn offset_bag() -> Source {
    Source::Bag {
        path: repo("testdata/rosbag/eih_pose_offset_mcap"),
        frames: BagFrames {
            base: "base_link".into(),
            gripper: "tool0".into(),
            camera: "camera_link".into(),
            target: None,
            target_topic: Some("/board_pose".into()),
            tags: None,
        },
    }
}

#[test]
fn a_bag_with_auto_gives_the_cli_offset_and_notes() {
    let entry = golden(
        "calibrate testdata/rosbag/eih_pose_offset_mcap --base-frame base_link --gripper-frame tool0 --camera-frame camera_link --target-topic /board_pose --time-offset auto --pairs consecutive --output json",
    );
    let r = Recording::read(&offset_bag(), &auto()).unwrap();
    assert_eq!(texts(&r.notes), golden_notes(&entry, 2));
    let report: Value = serde_json::from_str(entry["stdout"].as_str().unwrap()).unwrap();
    assert_eq!(r.time_offset, report["time_offset_s"].as_f64());
    assert_eq!(r.poses.len(), 80);
    assert_eq!(r.target_source.as_deref(), Some("/board_pose"));
    assert!(r.offset_curve.is_some());
    assert!(r.stamps.iter().all(Option::is_some));
    assert_eq!(r.names.len(), 80);
}

#[test]
fn a_bag_finds_its_offset_by_default_and_keeps_a_given_one() {
    let found = Recording::read(&offset_bag(), &RecordingOptions::default()).unwrap();
    // The recording's camera is stamped 37 ms late; it is noise-free.
    assert!(
        (found.time_offset.unwrap() - 0.037).abs() < 1e-6,
        "{found:?}"
    );
    assert!(found.time_offset_sigma.unwrap() < 1e-6);
    let fixed = RecordingOptions {
        time_offset: Some(TimeOffset::Fixed(0.037)),
        ..RecordingOptions::default()
    };
    let r = Recording::read(&offset_bag(), &fixed).unwrap();
    assert_eq!(r.time_offset, Some(0.037));
    assert!(r.offset_curve.is_none());
    // The offset moves the robot's lookups, so the pairs at 0 s differ.
    let zero = RecordingOptions {
        time_offset: Some(TimeOffset::Fixed(0.0)),
        ..RecordingOptions::default()
    };
    let zero = Recording::read(&offset_bag(), &zero).unwrap();
    assert_eq!(zero.time_offset, Some(0.0));
    assert_ne!(r.poses, zero.poses);
}

#[test]
fn a_missing_file_names_it() {
    let path = repo("testdata/no_such_file.jsonl");
    let source = Source::File {
        path: path.clone(),
        format: Format::Auto,
    };
    match Recording::read(&source, &RecordingOptions::default()) {
        Err(Error::Io { file, .. }) => assert_eq!(file, path.display().to_string()),
        other => panic!("expected an Io error, got {other:?}"),
    }
    let missing = Source::Streams {
        robot: repo("testdata/no_such_robot.txt"),
        camera: repo("testdata/no_such_camera.txt"),
    };
    let e = Recording::read(&missing, &RecordingOptions::default()).unwrap_err();
    assert!(e.to_string().contains("no_such_robot.txt"), "{e}");
}

#[test]
fn an_unknown_frame_is_named_with_the_known_ones() {
    let Source::Bag { path, mut frames } = offset_bag() else {
        unreachable!()
    };
    frames.base = "base_lnk".into();
    let e =
        Recording::read(&Source::Bag { path, frames }, &RecordingOptions::default()).unwrap_err();
    assert!(matches!(e, Error::Bag { .. }), "{e:?}");
    let text = e.to_string();
    assert!(
        text.contains("base_lnk") && text.contains("base_link"),
        "{text}"
    );
}

/// A scratch directory of this test process.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("handeye-recording-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A stream of `n` samples every 0.1 s from `t0`, turning about z by `turn` radians a sample.
fn stream(path: &Path, t0: f64, n: usize, turn: f64) {
    let text: String = (0..n)
        .map(|k| {
            let half = 0.5 * turn * k as f64;
            format!(
                "{:.3} {} 0 0 0 0 {} {}\n",
                t0 + 0.1 * k as f64,
                0.01 * k as f64,
                half.sin(),
                half.cos()
            )
        })
        .collect();
    std::fs::write(path, text).unwrap();
}

#[test]
fn streams_that_never_rotate_refuse_auto_naming_both_files() {
    let dir = scratch("still");
    let (robot, camera) = (dir.join("robot.txt"), dir.join("camera.txt"));
    stream(&robot, 0.0, 30, 0.0);
    stream(&camera, 0.0, 30, 0.0);
    let source = Source::Streams {
        robot: robot.clone(),
        camera: camera.clone(),
    };
    let e = Recording::read(&source, &auto()).unwrap_err();
    std::fs::remove_dir_all(&dir).unwrap();
    let Error::TimeOffset { streams, source } = &e else {
        panic!("expected a TimeOffset error, got {e:?}")
    };
    assert_eq!(
        streams,
        &format!("{} and {}", robot.display(), camera.display())
    );
    assert!(
        matches!(**source, Error::InvalidParameter { .. }),
        "{source:?}"
    );
}

#[test]
fn streams_that_do_not_overlap_name_the_camera_file() {
    let dir = scratch("apart");
    let (robot, camera) = (dir.join("robot.txt"), dir.join("camera.txt"));
    stream(&robot, 0.0, 20, 0.1);
    stream(&camera, 100.0, 20, 0.1);
    let source = Source::Streams {
        robot: robot.clone(),
        camera: camera.clone(),
    };
    let mut told = Vec::new();
    let e = Recording::read_telling(&source, &RecordingOptions::default(), &mut |n| {
        told.push(n.clone())
    })
    .unwrap_err();
    std::fs::remove_dir_all(&dir).unwrap();
    match e {
        Error::Parse {
            file, line, field, ..
        } => assert_eq!(
            (file, line, field.as_str()),
            (camera.display().to_string(), 0, "t")
        ),
        other => panic!("expected a Parse error, got {other:?}"),
    }
    // What was found before the error is told all the same: the offset could not be searched
    // (the streams do not overlap), and the camera samples were dropped.
    assert!(
        matches!(&told[0], Note::NoTimeOffset { why } if why.contains("overlap")),
        "{told:?}"
    );
    assert_eq!(
        told[1..],
        [Note::Dropped {
            outside: 20,
            gap: 0,
            max_gap: 0.1
        }]
    );
}

#[test]
fn a_stream_in_reverse_order_is_put_in_order_and_told() {
    let dir = scratch("reversed");
    let (robot, camera, reversed) = (
        dir.join("robot.txt"),
        dir.join("camera.txt"),
        dir.join("reversed.txt"),
    );
    stream(&robot, 0.0, 20, 0.1);
    stream(&camera, 0.05, 10, 0.1);
    let text = std::fs::read_to_string(&robot).unwrap();
    let lines: Vec<&str> = text.lines().rev().collect();
    std::fs::write(&reversed, lines.join("\n") + "\n").unwrap();
    let read = |robot: &Path| {
        let source = Source::Streams {
            robot: robot.to_path_buf(),
            camera: camera.clone(),
        };
        Recording::read(&source, &RecordingOptions::default()).unwrap()
    };
    let (sorted, put_in_order) = (read(&robot), read(&reversed));
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(put_in_order.poses, sorted.poses);
    assert!(matches!(
        &put_in_order.notes[0],
        Note::Reordered { file, count } if file == &reversed.display().to_string() && *count > 0
    ));
}

#[test]
fn a_file_of_one_pair_and_bad_options_are_refused() {
    let dir = scratch("short");
    let one = dir.join("one.jsonl");
    let first =
        std::fs::read_to_string(repo("testdata/opencv/opencv_eye-in-hand_exact_10_11.jsonl"))
            .unwrap();
    std::fs::write(&one, first.lines().next().unwrap()).unwrap();
    let source = Source::File {
        path: one.clone(),
        format: Format::Jsonl,
    };
    let e = Recording::read(&source, &RecordingOptions::default()).unwrap_err();
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(
        matches!(&e, Error::Parse { file, line: 0, .. } if file == &one.display().to_string()),
        "{e:?}"
    );
    assert!(e.to_string().contains("at least 2"), "{e}");
    for options in [
        RecordingOptions {
            time_offset: Some(TimeOffset::Fixed(f64::NAN)),
            ..RecordingOptions::default()
        },
        RecordingOptions {
            max_gap: 0.0,
            setup: Setup::EyeToHand,
            ..RecordingOptions::default()
        },
    ] {
        let e = Recording::read(&offset_bag(), &options).unwrap_err();
        assert!(matches!(e, Error::InvalidParameter { .. }), "{e:?}");
    }
}
