//! A calibration on the pixels from a ROS 2 recording of a tag's detections
//! (`apriltag_msgs/msg/AprilTagDetectionArray`) and its `CameraInfo`: the bags of
//! testdata/rosbag/make_tag_bags.py, made from testdata/pixels/tag_eih.jsonl, give its X; a bad
//! message costs that message; a recording without intrinsics is refused in words.

use std::path::{Path, PathBuf};

use handeye::io::rosbag::{BagTags, TAG_CORNERS};
use handeye::io::{BagFrames, FrameRecording, RecordingOptions, Source, TimeOffset};
use handeye::{Frame, Options, Setup, Transform};

fn data(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata")
        .join(path)
}

fn frames() -> BagFrames {
    BagFrames {
        base: "base_link".into(),
        gripper: "tool0".into(),
        camera: "camera".into(),
        target: None,
        target_topic: Some("/apriltag/detections".into()),
        tags: None,
    }
}

/// The one entry of recordings on the pixels, on the recording `path` with the tag `tags`.
fn read_bag_frames(
    path: &Path,
    frames: &BagFrames,
    tags: &BagTags,
    options: &RecordingOptions,
) -> handeye::Result<FrameRecording> {
    let frames = BagFrames {
        tags: Some(tags.clone()),
        ..frames.clone()
    };
    let source = Source::Bag {
        path: path.to_path_buf(),
        frames,
    };
    FrameRecording::read(&source, options)
}

/// The frames of a JSON Lines file of records with detections.
fn read_frames(path: &Path) -> handeye::Result<handeye::io::FrameSeries> {
    let source = Source::File {
        path: path.to_path_buf(),
        format: handeye::io::Format::Auto,
    };
    FrameRecording::read(&source, &RecordingOptions::default()).map(|r| handeye::io::FrameSeries {
        frames: r.frames,
        lines: r.lines,
    })
}

fn tags(id: Option<i32>) -> BagTags {
    BagTags {
        size: 0.06,
        id,
        camera_info_topic: None,
    }
}

fn options() -> RecordingOptions {
    RecordingOptions {
        time_offset: Some(TimeOffset::Fixed(0.0)),
        ..RecordingOptions::default()
    }
}

/// The JSON Lines recording's frames, without its PnP poses (the bag has none), but for the
/// records `skip` (line numbers).
fn jsonl_frames(skip: &[usize]) -> Vec<Frame> {
    let series = read_frames(&data("pixels/tag_eih.jsonl")).unwrap();
    series
        .frames
        .into_iter()
        .zip(series.lines)
        .filter(|(_, line)| !skip.contains(line))
        .map(|(f, _)| Frame {
            camera_from_target: None,
            ..f
        })
        .collect()
}

fn x_of(frames: &[Frame], camera: &handeye::Intrinsics) -> Transform {
    handeye::calibrate(
        handeye::Input::Pixels { frames, camera },
        Setup::EyeInHand,
        &Options::default(),
    )
    .map(|r| r.into_hand_eye().expect("the hand–eye report"))
    .unwrap()
    .transform
}

fn entry_gap(a: &Transform, b: &Transform) -> f64 {
    (a.to_homogeneous() - b.to_homogeneous()).abs().max()
}

#[test]
fn both_storages_give_the_x_of_the_json_lines_recording() {
    let intrinsics = handeye::Intrinsics::read(data("pixels/tag_eih.intrinsics.yml")).unwrap();
    let expected = x_of(&jsonl_frames(&[]), &intrinsics);
    for bag in ["rosbag/tag_eih_mcap", "rosbag/tag_eih_sqlite3"] {
        let read = read_bag_frames(&data(bag), &frames(), &tags(None), &options()).unwrap();
        assert_eq!(read.frames.len(), 30, "{bag}");
        assert_eq!(read.lines, (1..=30).collect::<Vec<_>>(), "{bag}");
        // The intrinsics of the recording's camera_info are the file's.
        assert_eq!(read.intrinsics, Some(intrinsics), "{bag}");
        // The corners are AprilTag's, scaled by the tag's side.
        assert_eq!(
            read.frames[0].detections.target[1],
            [0.5 * 0.06, 0.5 * 0.06, 0.0]
        );
        assert_eq!(TAG_CORNERS[3], [-0.5, -0.5, 0.0]);
        let x = x_of(&read.frames, &intrinsics);
        let gap = entry_gap(&x, &expected);
        assert!(gap < 1e-9, "{bag}: {gap:e}");
        assert!(read.names[0].starts_with("/apriltag/detections #1 (t = "));
    }
}

#[test]
fn a_bad_message_costs_that_message() {
    let intrinsics = handeye::Intrinsics::read(data("pixels/tag_eih.intrinsics.yml")).unwrap();
    let path = data("rosbag/tag_eih_hostile_mcap");
    let read = read_bag_frames(&path, &frames(), &tags(Some(3)), &options()).unwrap();
    // Image 3 truncated, image 6 with 5 corners, image 9 without tag 3: skipped and named.
    assert_eq!(read.frames.len(), 27);
    let note = read
        .notes
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join("\n");
    for words in [
        "message 3: cannot decode",
        "message 6: cannot decode",
        "past the last field",
        "message 9: no detection of tag 3",
        "2 detection(s) of other tags left out",
    ] {
        assert!(note.contains(words), "{words}: {note}");
    }
    // The other images are the recording's: the same X as the JSON Lines file without them.
    let expected = x_of(&jsonl_frames(&[3, 6, 9]), &intrinsics);
    let gap = entry_gap(&x_of(&read.frames, &intrinsics), &expected);
    assert!(gap < 1e-9, "{gap:e}");
    // Two tag ids and none chosen: refused, naming them.
    let e = read_bag_frames(&path, &frames(), &tags(None), &options())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("--tag-id") && e.contains("7 (2 detection(s))"),
        "{e}"
    );
    // An id never seen: refused, naming those seen.
    let e = read_bag_frames(&path, &frames(), &tags(Some(5)), &options())
        .unwrap_err()
        .to_string();
    assert!(e.contains("tag id 5 is in no detection"), "{e}");
}

#[test]
fn refusals_name_what_is_missing() {
    let path = data("rosbag/tag_eih_noinfo_sqlite3");
    // No camera_info: read, without intrinsics (the face asks for --intrinsics).
    let read = read_bag_frames(&path, &frames(), &tags(None), &options()).unwrap();
    assert_eq!(read.intrinsics, None);
    assert_eq!(read.frames.len(), 30);
    // A camera_info topic named but absent.
    let named = BagTags {
        camera_info_topic: Some("/camera/camera_info".into()),
        ..tags(None)
    };
    let e = read_bag_frames(&path, &frames(), &named, &options())
        .unwrap_err()
        .to_string();
    assert!(e.contains("no topic `/camera/camera_info`"), "{e}");
    // A tag size that is no length, a camera frame other than the detections'.
    for size in [0.0, -0.06, f64::NAN] {
        let bad = BagTags { size, ..tags(None) };
        let e = read_bag_frames(&path, &frames(), &bad, &options()).unwrap_err();
        assert!(e.to_string().contains("tag side"), "{e}");
    }
    let other = BagFrames {
        camera: "camera_link".into(),
        ..frames()
    };
    let e = read_bag_frames(&path, &other, &tags(None), &options())
        .unwrap_err()
        .to_string();
    assert!(e.contains("--camera-frame camera"), "{e}");
    // `auto` cannot be found from detections.
    let auto = RecordingOptions {
        time_offset: Some(TimeOffset::Auto),
        ..RecordingOptions::default()
    };
    let e = read_bag_frames(&path, &frames(), &tags(None), &auto).unwrap_err();
    assert!(e.to_string().contains("auto"), "{e}");
    // A pose topic read as detections, and detections read as poses.
    let poses = BagFrames {
        target_topic: Some("/tf".into()),
        ..frames()
    };
    let e = read_bag_frames(&path, &poses, &tags(None), &options()).unwrap_err();
    assert!(e.to_string().contains("AprilTagDetectionArray"), "{e}");
}

/// One [`Source`] names the input of both entries: a recording of a tag's detections is read on
/// the pixels only, a tag-less recording or two pose streams carry no detections, and a file's
/// records are paired already (no clock offset) and are JSON Lines.
#[test]
fn each_entry_refuses_the_sources_of_the_other() {
    let bag = data("rosbag/tag_eih_mcap");
    let tagged = Source::Bag {
        path: bag.clone(),
        frames: BagFrames {
            tags: Some(tags(None)),
            ..frames()
        },
    };
    let e = handeye::io::Recording::read(&tagged, &options()).unwrap_err();
    assert!(e.to_string().contains("calibrated on their pixels"), "{e}");
    let untagged = Source::Bag {
        path: bag,
        frames: frames(),
    };
    let e = FrameRecording::read(&untagged, &options()).unwrap_err();
    assert!(
        matches!(e, handeye::Error::InvalidParameter { name: "tags", .. }),
        "{e}"
    );
    let streams = Source::Streams {
        robot: data("pixels/tag_eih.jsonl"),
        camera: data("pixels/tag_eih.jsonl"),
    };
    let e = FrameRecording::read(&streams, &RecordingOptions::default()).unwrap_err();
    assert!(e.to_string().contains("carry no detections"), "{e}");
    let file = |format| Source::File {
        path: data("pixels/tag_eih.jsonl"),
        format,
    };
    let e = FrameRecording::read(
        &file(handeye::io::Format::Csv),
        &RecordingOptions::default(),
    )
    .unwrap_err();
    assert!(
        matches!(e, handeye::Error::InvalidParameter { name: "format", .. }),
        "{e}"
    );
    let e = FrameRecording::read(&file(handeye::io::Format::Auto), &options()).unwrap_err();
    assert!(
        matches!(
            e,
            handeye::Error::InvalidParameter {
                name: "time_offset",
                ..
            }
        ),
        "{e}"
    );
    let read = FrameRecording::read(
        &file(handeye::io::Format::Jsonl),
        &RecordingOptions::default(),
    )
    .unwrap();
    assert_eq!(read.names.len(), read.frames.len());
    assert!(
        read.names[0].ends_with("tag_eih.jsonl:1"),
        "{}",
        read.names[0]
    );
    assert_eq!((read.intrinsics, read.time_offset), (None, None));
}
