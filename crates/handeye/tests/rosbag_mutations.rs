//! A seeded mutation test of the ROS 2 recording readers (issue 34: "keep a fuzz target or a
//! seeded mutation test for the bag readers in CI, bounded time"). Each shipped recording (MCAP
//! and SQLite3) is damaged in a few bytes, cut short, or given a run of copied bytes, by a seeded
//! generator; both readers (`inspect_bag`, `read_bag_pairs`) must then answer or refuse with an
//! error that names the file, never panic. Bounded: 60 mutations per recording, each a file of a
//! few hundred kilobytes read once.

use std::path::{Path, PathBuf};

use handeye::io::rosbag::{BagOptions, inspect_bag, read_bag_pairs};
use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

/// Mutations per recording.
const MUTATIONS: usize = 60;

/// The shipped recordings: (file, frames for `read_bag_pairs`).
fn recordings() -> Vec<(PathBuf, BagOptions)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata/rosbag");
    let frames = |camera: &str, target: Option<&str>, topic: Option<&str>| BagOptions {
        base_frame: "base_link".into(),
        gripper_frame: "tool0".into(),
        camera_frame: camera.into(),
        target_frame: target.map(str::to_string),
        target_topic: topic.map(str::to_string),
        ..BagOptions::default()
    };
    vec![
        (
            dir.join("eih_tf_mcap/eih_tf_mcap.mcap"),
            frames("camera_link", Some("board"), None),
        ),
        (
            dir.join("eih_pose_sqlite3/eih_pose_sqlite3.db3"),
            frames("camera_link", None, Some("/board_pose")),
        ),
        (
            dir.join("eth_transform_mcap/eth_transform_mcap.mcap"),
            frames("camera_link", Some("board"), Some("/board_transform")),
        ),
    ]
}

/// One seeded mutation of `bytes`: a few bytes changed, the file cut short, or a run of bytes
/// copied over another place.
fn mutate(bytes: &[u8], rng: &mut Xoshiro256PlusPlus) -> Vec<u8> {
    let mut out = bytes.to_vec();
    let n = out.len();
    match rng.random_range(0..3) {
        0 => {
            for _ in 0..rng.random_range(1..8) {
                let i = rng.random_range(0..n);
                out[i] = rng.random();
            }
        }
        1 => out.truncate(rng.random_range(0..n)),
        _ => {
            let len = rng.random_range(1..64.min(n));
            let from = rng.random_range(0..n - len);
            let to = rng.random_range(0..n - len);
            let run = out[from..from + len].to_vec();
            out[to..to + len].copy_from_slice(&run);
        }
    }
    out
}

#[test]
fn damaged_recordings_are_answered_or_refused_naming_the_file_never_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(34);
    let (mut answered, mut refused) = (0, 0);
    for (k, (path, options)) in recordings().into_iter().enumerate() {
        let bytes = std::fs::read(&path).unwrap();
        let name = path.file_name().unwrap().to_owned();
        for i in 0..MUTATIONS {
            let case = dir.path().join(format!("{k}_{i}"));
            std::fs::create_dir_all(&case).unwrap();
            let damaged = case.join(&name);
            std::fs::write(&damaged, mutate(&bytes, &mut rng)).unwrap();
            let shown = damaged.display().to_string();
            let read = std::panic::catch_unwind(|| {
                (
                    inspect_bag(&damaged).map(|_| ()),
                    read_bag_pairs(&damaged, &options).map(|_| ()),
                )
            });
            let (inspected, paired) =
                read.unwrap_or_else(|_| panic!("a reader panicked on mutation {i} of {shown}"));
            for result in [inspected, paired] {
                match result {
                    Ok(()) => answered += 1,
                    Err(e) => {
                        let words = e.to_string();
                        assert!(
                            words.contains(&shown) || words.contains(&case.display().to_string()),
                            "mutation {i} of {shown}: the error names no file: {words}"
                        );
                        refused += 1;
                    }
                }
            }
        }
    }
    println!("{answered} reads answered, {refused} refused, none panicked");
    assert!(refused > 0 && answered + refused == 2 * 3 * MUTATIONS);
}
