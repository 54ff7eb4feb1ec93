//! Input that cannot lose the stream (issue 13), at the library: a pose stream read through
//! [`PoseReader`] or [`open_poses`] gives the same records for a clean stream and for the same
//! stream with a byte order mark, log lines first, a stray quote or an overflowing value in one
//! line, or an over-long line; each bad line is one error with its number; a FIFO is read once.

use std::io::Write;

use handeye::Error;
use handeye::io::{Format, MAX_LINE, PoseInput, PoseReader, StampedPosePair, open_poses};

const I: &str = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";
const HEADER: &str = "stamp,base_from_gripper_x,base_from_gripper_y,base_from_gripper_z,base_from_gripper_qx,base_from_gripper_qy,base_from_gripper_qz,base_from_gripper_qw,camera_from_target_x,camera_from_target_y,camera_from_target_z,camera_from_target_qx,camera_from_target_qy,camera_from_target_qz,camera_from_target_qw";

fn jsonl(n: usize) -> Vec<String> {
    (0..n)
        .map(|k| {
            format!(
                "{{\"stamp\": {k}, \"base_from_gripper\": [[1,0,0,{k}],[0,1,0,0],[0,0,1,0],[0,0,0,1]], \"camera_from_target\": {I}}}"
            )
        })
        .collect()
}

fn csv(n: usize) -> Vec<String> {
    let mut lines = vec![HEADER.to_string()];
    lines.extend((0..n).map(|k| format!("{k},{k},0,0,0,0,0.6,0.8,1,2,3,0,0,0,1")));
    lines
}

/// Records (Ok) and the places of errors of a whole input.
fn read(bytes: &[u8], source: &str) -> (Vec<StampedPosePair>, Vec<(usize, String)>, Option<usize>) {
    // A small buffer, so that lines span reads.
    let input = std::io::BufReader::with_capacity(7, bytes);
    let mut reader = PoseReader::new(input, source, Format::Auto).unwrap();
    let preamble = reader.preamble().map(|p| p.lines);
    let (mut ok, mut bad) = (Vec::new(), Vec::new());
    for r in reader.by_ref() {
        match r {
            Ok(r) => ok.push(r),
            Err(Error::Parse { line, field, .. }) => bad.push((line, field)),
            Err(e) => panic!("{e}"),
        }
    }
    (ok, bad, preamble)
}

fn poses(records: &[StampedPosePair]) -> Vec<(Option<f64>, handeye::PosePair)> {
    records.iter().map(|r| (r.stamp, r.pose)).collect()
}

#[test]
fn bom_log_lines_stray_quotes_overflows_and_long_lines_cost_their_own_line() {
    for (clean, stray, overflow) in [
        (
            jsonl(30),
            "{\"base_from_gripper\": \"".to_string(),
            format!(
                "{{\"base_from_gripper\": [[1,0,0,1e300],[0,1,0,0],[0,0,1,0],[0,0,0,1]], \"camera_from_target\": {I}}}"
            ),
        ),
        (
            csv(30),
            "1,2,\"3,4,5".to_string(),
            "1,1e300,0,0,0,0,0.6,0.8,1,2,3,0,0,0,1".to_string(),
        ),
    ] {
        let join = |lines: &[String]| format!("{}\n", lines.join("\n")).into_bytes();
        let (want, bad, preamble) = read(&join(&clean), "-");
        assert_eq!((want.len(), bad.len(), preamble), (30, 0, None));

        let mut bom = b"\xef\xbb\xbf".to_vec();
        bom.extend(join(&clean));
        let (got, bad, preamble) = read(&bom, "-");
        assert_eq!(poses(&got), poses(&want));
        assert_eq!((bad.len(), preamble), (0, None));

        let mut logged = vec![
            "\u{feff}[INFO] robot driver started".to_string(),
            "# a comment".to_string(),
            String::new(),
            "2024-05-01 12:00:00,123 connected".to_string(),
        ];
        logged.extend(clean.iter().cloned());
        let (got, bad, preamble) = read(&join(&logged), "-");
        assert_eq!(poses(&got), poses(&want));
        assert_eq!((bad.len(), preamble), (0, Some(4)));
        // Line numbers count the skipped lines.
        assert_eq!(got[0].line, want[0].line + 4);

        let mut broken = clean.clone();
        broken.insert(10, stray.clone());
        broken.insert(20, overflow.clone());
        broken.insert(25, "x".repeat(MAX_LINE + 1));
        let (got, bad, _) = read(&join(&broken), "-");
        assert_eq!(poses(&got), poses(&want));
        let lines: Vec<usize> = bad.iter().map(|b| b.0).collect();
        assert_eq!(lines, [11, 21, 26], "{bad:?}");
    }
}

#[test]
fn an_input_without_newlines_is_refused_at_its_first_line_never_buffered() {
    // Endless zero bytes (`/dev/zero`): one over-long line before any record, said as soon as it
    // passes the limit (issue 34 item 11: `online /dev/zero` read forever without a word).
    let read = std::rc::Rc::new(std::cell::Cell::new(0u64));
    let zeros = Counted {
        input: std::io::repeat(0),
        read: read.clone(),
    };
    let e = PoseReader::new(std::io::BufReader::new(zeros), "-", Format::Auto)
        .err()
        .unwrap();
    let text = e.to_string();
    assert!(
        text.starts_with("-:1: field `-`: a line longer than 65536 bytes before any pose record"),
        "{text}"
    );
    // Read up to the limit (and a buffer), not on.
    assert!(
        read.get() <= 2 * MAX_LINE as u64,
        "{} bytes read",
        read.get()
    );
}

/// A reader that counts the bytes read from it.
struct Counted<R> {
    input: R,
    read: std::rc::Rc<std::cell::Cell<u64>>,
}

impl<R: std::io::Read> std::io::Read for Counted<R> {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        let n = self.input.read(out)?;
        self.read.set(self.read.get() + n as u64);
        Ok(n)
    }
}

#[cfg(unix)]
#[test]
fn a_fifo_is_read_once_and_whole() {
    let dir = std::env::temp_dir().join(format!("handeye-fifo-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, lines) in [("jsonl", jsonl(500)), ("csv", csv(500))] {
        let fifo = dir.join(name);
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if !made.is_ok_and(|s| s.success()) {
            eprintln!("mkfifo is missing: skipped");
            return;
        }
        // Over 4 KB before the first record: the head read to tell the format is not lost.
        let mut text = format!("# {}\n", "c".repeat(5000));
        text.push_str("[INFO] driver started\n");
        text.push_str(&lines.join("\n"));
        let path = fifo.clone();
        let writer = std::thread::spawn(move || {
            let mut f = std::fs::OpenOptions::new().write(true).open(&path).unwrap();
            f.write_all(text.as_bytes()).unwrap();
        });
        let PoseInput::Stream(mut reader) =
            open_poses(&fifo, Format::Auto, handeye::Rotations::default()).unwrap()
        else {
            panic!("{name}: not streamed");
        };
        assert_eq!(reader.preamble().map(|p| p.lines), Some(2));
        let records: Vec<_> = reader.by_ref().collect::<Result<_, _>>().unwrap();
        writer.join().unwrap();
        assert_eq!(records.len(), 500, "{name}");
        assert_eq!(records[0].line, if name == "csv" { 4 } else { 3 });
        assert_eq!(records[0].stamp, Some(0.0));
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
