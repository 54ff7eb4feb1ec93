//! Recordings a recorder would not write on purpose (issue 34 items 6 to 9), made here by the
//! test writer (`tests/bags`): a long broken tf chain, a compression bomb, repeated stamps, a tf
//! loop and a topic written under two types. Each gives the right answer with a count of what
//! was dropped, or an error that says what and where; the searches are linear in the tree.

mod bags;

use std::path::{Path, PathBuf};

use bags::{BagWriter, Pose, T0_NS, tf};
use handeye::Error;
use handeye::io::rosbag::{BagOptions, read_bag_pairs, tree_steps};

fn options(target_topic: Option<&str>) -> BagOptions {
    BagOptions {
        base_frame: "base_link".into(),
        gripper_frame: "tool0".into(),
        camera_frame: "camera".into(),
        target_frame: Some("board".into()),
        target_topic: target_topic.map(str::to_string),
        ..BagOptions::default()
    }
}

/// A recording whose robot chain `base_link → c1 → … → cN/2`, `dN/2 → … → d1 → tool0` (N
/// static frames in /tf_static) is broken in the middle, with a moving `tool0` and a target.
fn broken_chain(dir: &Path, frames: usize) -> PathBuf {
    let path = dir.join(format!("chain_{frames}.mcap"));
    let mut bag = BagWriter::create(&path, true, None);
    let half = frames / 2;
    let name = |side: &str, k: usize| format!("{side}{k}");
    let mut statics = Vec::with_capacity(frames);
    for k in 1..=half {
        let parent = if k == 1 {
            "base_link".to_string()
        } else {
            name("c", k - 1)
        };
        statics.push(tf(&parent, &name("c", k), T0_NS, Pose::identity()));
        let child = if k == 1 {
            "d0".to_string()
        } else {
            name("d", k - 1)
        };
        statics.push(tf(&name("d", k), &child, T0_NS, Pose::identity()));
    }
    bag.tf_static(&statics);
    let (robot, target) = bags::eye_in_hand(1);
    for r in robot {
        bag.tf(&[tf("d0", "tool0", r.stamp_ns, r.pose)]);
    }
    for (stamp, pose) in target {
        bag.tf(&[tf("camera", "board", stamp, pose)]);
    }
    bag.finish();
    path
}

/// Issue 34 item 6: a 20,000-frame broken chain took 21–32 s and printed a 189 KB error listing
/// every frame. The search is linear (its steps grow as the chain, 10 times for 10 times the
/// frames), and the message names the two trees by their roots with a few of their frames.
#[test]
fn a_long_broken_chain_is_named_by_its_two_trees_in_linear_work() {
    let dir = tempfile::tempdir().unwrap();
    let mut steps = Vec::new();
    for frames in [2_000, 20_000] {
        let path = broken_chain(dir.path(), frames);
        let before = tree_steps();
        let e = read_bag_pairs(&path, &options(None)).unwrap_err();
        let spent = tree_steps() - before;
        let text = e.to_string();
        println!(
            "{frames} frames: {spent} steps, a message of {} bytes",
            text.len()
        );
        assert!(matches!(e, Error::Bag { .. }), "{e:?}");
        assert!(text.contains("not connected"), "{text}");
        assert!(
            text.contains("`base_link`") && text.contains("`tool0`"),
            "{text}"
        );
        // The two trees by their roots (`base_link` and the top of the other half), and their
        // sizes.
        let half = frames / 2;
        assert!(text.contains(&format!("`d{half}`")), "{text}");
        assert!(text.contains(&format!("{} frames", half + 1)), "{text}");
        assert!(text.len() < 1_000, "{} bytes: {text}", text.len());
        steps.push(spent);
    }
    // Linear: ten times the frames, about ten times the steps (quadratic would be a hundred).
    assert!(steps[1] <= 12 * steps[0], "{steps:?}");
    assert!(steps[1] <= 10 * 20_000, "{steps:?}");
}

/// Issue 34 item 7: 114 KB of zstd chunks unpacked to 5 million tf messages (27 s, 520 MB). A
/// file may unpack to at most 100,000 messages plus one per byte it stores (a recording stores
/// a tf message in about 80 bytes): reading stops there with an error that says why.
#[test]
fn a_compression_bomb_is_refused_once_it_passes_its_size() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bomb.mcap");
    let mut bag = BagWriter::bomb(&path);
    let (robot, target) = bags::eye_in_hand(8);
    bags::write_robot(&mut bag, &robot);
    for (stamp, pose) in &target {
        bag.tf(&[tf("camera", "board", *stamp, *pose)]);
    }
    // The same message again and again: zstd stores each in a fraction of a byte.
    let same = bags::tf_message(&[tf("base_link", "tool0", T0_NS, Pose::identity())]);
    let messages = 400_000;
    for _ in 0..messages {
        bag.write("/tf", bags::TF_MESSAGE, T0_NS, same.clone());
    }
    bag.finish();
    let size = std::fs::metadata(&path).unwrap().len();
    println!("{messages} messages in {size} bytes");
    assert!((messages as u64) > 100_000 + size, "{size} bytes");
    for e in [
        read_bag_pairs(&path, &options(None)).unwrap_err(),
        handeye::io::rosbag::inspect_bag(&path).unwrap_err(),
    ] {
        let text = e.to_string();
        assert!(matches!(e, Error::Bag { .. }), "{e:?}");
        assert!(text.contains(path.to_str().unwrap()), "{text}");
        let limit = 100_000 + size;
        assert!(
            text.contains(&format!("unpack to more than {limit} messages")),
            "{text}"
        );
        assert!(text.contains("compression bomb"), "{text}");
        // Stopped where the limit was passed, not at the end: the place is the message count.
        assert!(
            text.contains(&format!("after {limit} message(s)")),
            "{text}"
        );
    }
}

/// The eye-in-hand recording of `bags::eye_in_hand(8)` (80 detections) with the target's pose in
/// /tf (`topic` none) or on `topic` as `PoseStamped`, each detection in `repeats` written again
/// after the others with the same stamp (`exact`: the same pose, else a pose off by 10 cm).
fn with_repeats(dir: &Path, topic: Option<&str>, repeats: &[usize], exact: bool) -> PathBuf {
    let path = dir.join(format!("repeats_{}.mcap", repeats.len()));
    let mut bag = BagWriter::create(&path, false, None);
    let (robot, target) = bags::eye_in_hand(8);
    bags::write_robot(&mut bag, &robot);
    let again = repeats.iter().map(|&k| {
        let (stamp, pose) = target[k];
        let off = Pose::translation(0.1, 0.0, 0.0);
        (stamp, if exact { pose } else { off * pose })
    });
    let all: Vec<(i64, Pose)> = target.iter().copied().chain(again).collect();
    for (stamp, pose) in all {
        match topic {
            None => bag.tf(&[tf("camera", "board", stamp, pose)]),
            Some(topic) => bag.write(
                topic,
                bags::POSE_STAMPED,
                stamp,
                bags::pose_stamped("camera", stamp, &pose),
            ),
        }
    }
    bag.finish();
    path
}

/// Issue 34 item 8: target transforms in /tf of equal stamps collapsed without a word (80 → 61),
/// and a target topic kept exact repeats (90 pairs of 80 detections). One rule for both: one
/// pose per stamp, the first read (as tf2 keeps), and the note counts the others.
#[test]
fn repeated_stamps_keep_the_first_pose_and_are_counted_in_both_target_sources() {
    use handeye::io::{BagFrames, Recording, RecordingOptions, Source, TimeOffset};
    let dir = tempfile::tempdir().unwrap();
    let repeats: Vec<usize> = (0..80).step_by(4).take(19).collect();
    for (topic, exact) in [
        (None, false),
        (Some("/board_pose"), true),
        (Some("/board_pose"), false),
    ] {
        let path = with_repeats(dir.path(), topic, &repeats, exact);
        let pairs = read_bag_pairs(&path, &options(topic)).unwrap();
        assert_eq!(pairs.pairs.len(), 80, "{topic:?}");
        assert_eq!(pairs.observations, 99, "{topic:?}");
        assert_eq!(pairs.dropped_repeated, 19, "{topic:?}");
        // The first of each stamp is kept: every pair closes the loop through the true X.
        for p in &pairs.pairs {
            let closed = p.pose.base_from_gripper * bags::true_x() * p.pose.camera_from_target;
            let d = (closed.to_homogeneous() - bags::base_from_board().to_homogeneous())
                .abs()
                .max();
            assert!(d < 1e-9, "{topic:?}: {d:e}");
        }
        let source = Source::Bag {
            path: path.clone(),
            frames: BagFrames {
                base: "base_link".into(),
                gripper: "tool0".into(),
                camera: "camera".into(),
                target: Some("board".into()),
                target_topic: topic.map(str::to_string),
                tags: None,
            },
        };
        let options = RecordingOptions {
            time_offset: Some(TimeOffset::Fixed(0.0)),
            ..RecordingOptions::default()
        };
        let recording = Recording::read(&source, &options).unwrap();
        let notes: Vec<String> = recording.notes.iter().map(ToString::to_string).collect();
        let note = notes.join("\n");
        assert!(
            note.contains("80 pose pair(s) from 99 observation(s)")
                && note.contains("dropped 19 observation(s) stamped like an earlier one"),
            "{note}"
        );
    }
}

/// Issue 34 item 9: `inspect` hid parts of the tree. A loop of parent links (no root) is listed
/// as a loop, and a lookup through it is refused naming it; a topic written under two types
/// keeps both counts in the totals.
#[test]
fn a_tf_loop_is_named_and_a_topic_of_two_types_keeps_its_messages() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("loop.mcap");
    let mut bag = BagWriter::create(&path, false, None);
    let (robot, target) = bags::eye_in_hand(1);
    bags::write_robot(&mut bag, &robot);
    bag.tf_static(&[
        tf("tool0", "camera", T0_NS, Pose::identity()),
        tf("loop_b", "loop_a", T0_NS, Pose::identity()),
        tf("loop_c", "loop_b", T0_NS, Pose::identity()),
        tf("loop_a", "loop_c", T0_NS, Pose::identity()),
        tf("loop_b", "hanging", T0_NS, Pose::identity()),
    ]);
    for (stamp, pose) in &target {
        bag.write(
            "/board",
            bags::POSE_STAMPED,
            *stamp,
            bags::pose_stamped("camera", *stamp, pose),
        );
        bag.tf(&[tf("camera", "board", *stamp, *pose)]);
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
    let summary = handeye::io::rosbag::inspect_bag(&path).unwrap();
    let board: Vec<(String, usize)> = summary
        .topics
        .iter()
        .filter(|t| t.topic == "/board")
        .map(|t| (t.msg_type.clone(), t.count))
        .collect();
    assert_eq!(
        board,
        [
            (bags::POSE_STAMPED.to_string(), 10),
            ("std_msgs/msg/String".to_string(), 7)
        ]
    );
    let listed: usize = summary.topics.iter().map(|t| t.count).sum();
    assert_eq!(summary.messages, listed);
    assert_eq!(summary.messages, 101 + 10 + 1 + 17);
    assert_eq!(summary.target_topics, ["/board"]);
    // The same in SQLite3, where the second row of a name replaced the first in the totals.
    let db3 = dir.path().join("two_types.db3");
    let db = rusqlite::Connection::open(&db3).unwrap();
    db.execute_batch(
        "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT, type TEXT, serialization_format TEXT, offered_qos_profiles TEXT);
         CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER, timestamp INTEGER, data BLOB);
         INSERT INTO topics VALUES (1, '/board', 'geometry_msgs/msg/PoseStamped', 'cdr', ''), (2, '/board', 'std_msgs/msg/String', 'cdr', '');
         INSERT INTO messages(topic_id, timestamp, data) VALUES (1, 1, x'00'), (1, 2, x'00'), (1, 3, x'00'), (2, 4, x'00'), (2, 5, x'00');",
    )
    .unwrap();
    drop(db);
    let summary = handeye::io::rosbag::inspect_bag(&db3).unwrap();
    let counts: Vec<(&str, usize)> = summary
        .topics
        .iter()
        .map(|t| (t.msg_type.as_str(), t.count))
        .collect();
    assert_eq!(
        counts,
        [(bags::POSE_STAMPED, 3), ("std_msgs/msg/String", 2)]
    );
    assert_eq!(summary.messages, 5);
    let summary = handeye::io::rosbag::inspect_bag(&path).unwrap();
    assert_eq!(summary.loops, [["loop_a", "loop_b", "loop_c"]]);
    assert!(!summary.roots.iter().any(|r| r.starts_with("loop")));
    // A lookup through the loop names it.
    let mut o = options(None);
    o.base_frame = "hanging".into();
    let e = read_bag_pairs(&path, &o).unwrap_err().to_string();
    assert!(e.contains("loop"), "{e}");
    // Walked up from `hanging`: each frame the parent of the one before.
    assert!(
        e.contains("a loop: `loop_b` → `loop_c` → `loop_a` → `loop_b`"),
        "{e}"
    );
}

/// Issue 34 item 14: every input translation within the plausibility bound (1e9 in any unit),
/// and yet X solved at 2e9 was answered with exit 0. Here the camera turns about its own centre,
/// which sits 2e9 from the gripper: the robot's translations stay under 7e8, the target's under
/// 2, and the exact X is refused for its translation, naming it.
#[test]
fn an_x_beyond_the_bound_of_its_inputs_is_refused() {
    use handeye::{Options, Setup, calibrate};
    use nalgebra::Vector3;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("far.mcap");
    let x = Pose::new(Vector3::new(0.0, 0.0, 2e9), Vector3::new(0.2, -0.1, 0.3));
    let base_from_camera0 = bags::robot_pose(0) * x;
    let base_from_board =
        base_from_camera0 * Pose::new(Vector3::new(0.1, 0.2, 1.5), Vector3::new(3.0, 0.0, 0.1));
    let mut bag = BagWriter::create(&path, false, None);
    let mut largest: f64 = 0.0;
    for k in 0..=800usize {
        let stamp = T0_NS + k as i64 * 10_000_000;
        // The camera turns about its centre: base_from_camera = (R_k, c0).
        let s = k as f64 * 0.01;
        let turn = Vector3::new(
            0.2 * (0.9 * s).sin(),
            0.2 * (1.3 * s).cos() - 0.2,
            0.15 * s.sin(),
        );
        let base_from_camera = Pose::from_parts(
            base_from_camera0.translation,
            base_from_camera0.rotation * nalgebra::Rotation3::new(turn),
        );
        let base_from_tool0 = base_from_camera * x.inverse();
        largest = largest.max(base_from_tool0.translation.vector.abs().max());
        bag.tf(&[tf("base_link", "tool0", stamp, base_from_tool0)]);
        if k % 10 == 5 {
            let camera_from_board = base_from_camera.inverse() * base_from_board;
            bag.tf(&[tf("camera", "board", stamp, camera_from_board)]);
        }
    }
    bag.finish();
    println!("largest robot translation {largest:e}");
    assert!(largest < 1e9, "{largest:e}");
    let pairs = read_bag_pairs(&path, &options(None)).unwrap();
    let e = calibrate(&pairs.poses(), Setup::EyeInHand, &Options::default())
        .map(|r| r.into_hand_eye().expect("the hand–eye report"))
        .unwrap_err();
    let text = e.to_string();
    assert!(matches!(e, Error::InvalidTransform { .. }), "{e:?}");
    assert!(text.starts_with("X as solved"), "{text}");
    assert!(
        text.contains("translation 1.99999") && text.contains("is not a plausible length"),
        "{text}"
    );
}
