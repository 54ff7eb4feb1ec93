//! MCAP containers a recorder may write, or damage (issue 34 items 2 and 3): a chunk whose
//! header claims no data is not skipped in silence, and a camera image larger than the whole
//! (compressed) file is read, not refused. The files are made here from a shipped recording with
//! the `mcap` crate's own reader and writer.

use std::borrow::Cow;
use std::path::{Path, PathBuf};

use handeye::Error;
use handeye::io::rosbag::{BagOptions, read_bag_pairs};

fn recording() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata/rosbag/eth_transform_mcap/eth_transform_mcap.mcap")
}

fn options() -> BagOptions {
    BagOptions {
        base_frame: "base_link".into(),
        gripper_frame: "tool0".into(),
        camera_frame: "camera_link".into(),
        target_frame: Some("board".into()),
        target_topic: Some("/board_transform".into()),
        ..BagOptions::default()
    }
}

/// The byte offsets of the records of an MCAP file's data section: (opcode, start of its data,
/// its length).
fn records(bytes: &[u8]) -> Vec<(u8, usize, usize)> {
    let mut out = Vec::new();
    let mut at = 8;
    while at + 9 <= bytes.len() {
        let opcode = bytes[at];
        let len = u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
        out.push((opcode, at + 9, len));
        if opcode == 0x0f {
            break; // the data end: the summary follows
        }
        at += 9 + len;
    }
    out
}

/// The recording with the header of its `n`-th chunk claiming an uncompressed size of 0 (the
/// linear reader then skips the chunk whole), and its CRC cleared too when `clear_crc`.
fn with_empty_chunk(n: usize, clear_crc: bool) -> (tempfile::TempDir, PathBuf) {
    // The recording rewritten in small chunks, so that one chunk holds a few of its messages.
    let (dir, small, _) = rewritten(None, Some(4096));
    let mut bytes = std::fs::read(&small).unwrap();
    let chunks: Vec<usize> = records(&bytes)
        .into_iter()
        .filter(|r| r.0 == 0x06)
        .map(|r| r.1)
        .collect();
    assert!(chunks.len() > n, "{} chunks", chunks.len());
    // Chunk: start time u64, end time u64, uncompressed size u64, uncompressed CRC u32, …
    let data = chunks[n];
    bytes[data + 16..data + 24].copy_from_slice(&0u64.to_le_bytes());
    if clear_crc {
        bytes[data + 24..data + 28].copy_from_slice(&0u32.to_le_bytes());
    }
    let path = dir.path().join("damaged.mcap");
    std::fs::write(&path, bytes).unwrap();
    (dir, path)
}

#[test]
fn a_chunk_that_claims_no_data_is_an_error_not_a_silent_loss() {
    let whole = read_bag_pairs(&recording(), &options()).unwrap();
    assert_eq!(whole.pairs.len(), 80);
    // Rewritten in small chunks, undamaged, it reads as the original.
    let (_dir, small, _) = rewritten(None, Some(4096));
    assert_eq!(read_bag_pairs(&small, &options()).unwrap(), whole);
    for clear_crc in [false, true] {
        let (_dir, path) = with_empty_chunk(1, clear_crc);
        let e = read_bag_pairs(&path, &options()).unwrap_err();
        let text = e.to_string();
        assert!(matches!(e, Error::Bag { .. }), "{e:?}");
        assert!(text.contains(path.to_str().unwrap()), "{text}");
        if clear_crc {
            // No CRC to catch it: the chunk's message indexes or the statistics do.
            assert!(text.contains("could be read: a chunk is damaged"), "{text}");
        } else {
            assert!(text.to_lowercase().contains("crc"), "{text}");
        }
        // And `inspect` says so too, rather than totals short of what the file holds.
        assert!(handeye::io::rosbag::inspect_bag(&path).is_err());
    }
}

/// The recording rewritten by the `mcap` writer with zstd chunks of `chunk_size` bytes (the
/// writer's default when `None`), with one more message on a camera topic when `image` is given:
/// that many bytes of zeros (a dark frame compresses to almost nothing).
fn rewritten(image: Option<usize>, chunk_size: Option<u64>) -> (tempfile::TempDir, PathBuf, u64) {
    let bytes = std::fs::read(recording()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rewritten.mcap");
    let file = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
    let mut options = mcap::WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .profile("ros2");
    if chunk_size.is_some() {
        options = options.chunk_size(chunk_size);
    }
    let mut writer = options.create(file).unwrap();
    let mut first = None;
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        first.get_or_insert(m.log_time);
        writer.write(&m).unwrap();
    }
    let camera = std::sync::Arc::new(mcap::Channel {
        id: 0,
        topic: "/camera/image_raw".into(),
        schema: Some(std::sync::Arc::new(mcap::Schema {
            id: 0,
            name: "sensor_msgs/msg/Image".into(),
            encoding: "ros2msg".into(),
            data: Cow::Borrowed(b""),
        })),
        message_encoding: "cdr".into(),
        metadata: Default::default(),
    });
    if let Some(image) = image {
        writer
            .write(&mcap::Message {
                channel: camera,
                sequence: 0,
                log_time: first.unwrap(),
                publish_time: first.unwrap(),
                data: Cow::Owned(vec![0u8; image]),
            })
            .unwrap();
    }
    writer.finish().unwrap();
    drop(writer);
    let size = std::fs::metadata(&path).unwrap().len();
    (dir, path, size)
}

#[test]
fn a_camera_image_larger_than_the_compressed_file_is_read() {
    let (_dir, path, size) = rewritten(Some(8 << 20), None);
    // The image alone is larger than the file that holds it.
    assert!(size < 8 << 20, "{size}");
    let read = read_bag_pairs(&path, &options()).unwrap();
    let whole = read_bag_pairs(&recording(), &options()).unwrap();
    assert_eq!(read.pairs.len(), whole.pairs.len());
    for (a, b) in read.pairs.iter().zip(&whole.pairs) {
        assert_eq!(a.pose, b.pose);
    }
    let summary = handeye::io::rosbag::inspect_bag(&path).unwrap();
    let image = summary
        .topics
        .iter()
        .find(|t| t.topic == "/camera/image_raw")
        .unwrap();
    assert_eq!(image.count, 1);
}

/// Issue 34 item 4: an 8 KB SQLite3 file whose `messages` is a view over an endless recursive
/// query hung every command. Only plain tables are read.
#[test]
fn a_recording_whose_messages_are_a_view_is_refused_not_run() {
    let dir = tempfile::tempdir().unwrap();
    for (name, schema) in [
        (
            "view.db3",
            "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT, type TEXT, serialization_format TEXT, offered_qos_profiles TEXT);
             INSERT INTO topics VALUES (1, '/tf', 'tf2_msgs/msg/TFMessage', 'cdr', '');
             CREATE VIEW messages AS WITH RECURSIVE r(id, topic_id, timestamp, data) AS
               (SELECT 1, 1, 0, x'00' UNION ALL SELECT id + 1, 1, timestamp + 1, data FROM r)
               SELECT * FROM r;",
        ),
        (
            "topics_view.db3",
            "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER, timestamp INTEGER, data BLOB);
             CREATE VIEW topics AS SELECT 1 AS id, '/tf' AS name, 'tf2_msgs/msg/TFMessage' AS type, 'cdr' AS serialization_format;",
        ),
        (
            "no_messages.db3",
            "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT, type TEXT, serialization_format TEXT);",
        ),
    ] {
        let path = dir.path().join(name);
        let db = rusqlite::Connection::open(&path).unwrap();
        db.execute_batch(schema).unwrap();
        drop(db);
        let e = read_bag_pairs(&path, &options()).unwrap_err();
        let text = e.to_string();
        assert!(matches!(e, Error::Bag { .. }), "{name}: {e:?}");
        assert!(
            text.contains("not a rosbag2 SQLite3 recording"),
            "{name}: {text}"
        );
        assert!(handeye::io::rosbag::inspect_bag(&path).is_err(), "{name}");
    }
}
