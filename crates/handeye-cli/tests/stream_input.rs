//! Input that cannot lose the stream (issue 13): `handeye online` gives the same events for a
//! clean stream and for the same stream with a byte order mark, a log line first, a stray quote
//! or an overflowing value in one line, through stdin and through a FIFO; an endless bad stream
//! is read with bounded memory, each bad line counted.

mod common;

use std::io::Write;
use std::path::Path;
use std::process::{Command, Stdio};

use common::{run_fed, run_on_fifo, testdata};

use handeye::io::{Format, PoseStream};
use serde_json::Value;

/// `handeye online INPUT --d-max 100 --estimator paper` (the paper's estimator prints an event
/// per calibration, which these tests of streaming count) with `stdin` fed from another thread;
/// returns (exit code, stdout, stderr).
fn online(input: &Path, stdin: Vec<u8>) -> (i32, String, String) {
    run_fed(&online_args(input.to_str().unwrap()), stdin)
}

/// [`online`] on a FIFO fed with `bytes`, or `None` where `mkfifo` is missing.
fn online_fifo(bytes: &[u8]) -> Option<(i32, String, String)> {
    run_on_fifo(&online_args("{}"), bytes)
}

fn online_args(input: &str) -> [&str; 6] {
    ["online", input, "--d-max", "100", "--estimator", "paper"]
}

/// The events of `online`, without their timing.
fn events(out: &str) -> Vec<Value> {
    out.lines()
        .map(|l| {
            let mut v: Value = serde_json::from_str(l).unwrap();
            if let Some(o) = v.as_object_mut() {
                o.remove("seconds");
            }
            v
        })
        .collect()
}

/// The paper fixture as JSON Lines and as CSV (translation and quaternion columns).
fn clean_streams() -> [(Vec<String>, &'static str); 2] {
    let text = std::fs::read_to_string(testdata("paper/series_2007_000_200.jsonl")).unwrap();
    let jsonl: Vec<String> = text.lines().map(str::to_string).collect();
    let mut csv = vec![
        ["base_from_gripper", "camera_from_target"]
            .iter()
            .flat_map(|f| ["x", "y", "z", "qx", "qy", "qz", "qw"].map(move |s| format!("{f}_{s}")))
            .collect::<Vec<_>>()
            .join(","),
    ];
    let input = std::io::Cursor::new(text.clone());
    let stream = PoseStream::from_reader(
        input,
        "-",
        Format::Auto,
        Default::default(),
        handeye::Setup::EyeInHand,
    );
    for r in stream.unwrap() {
        let p = r.unwrap().pose;
        let mut v = Vec::new();
        for t in [p.base_from_gripper, p.camera_from_target] {
            v.extend(t.translation.vector.iter().copied());
            v.extend(handeye::TransformJson::from(&t).quaternion_xyzw);
        }
        csv.push(
            v.iter()
                .map(|x| format!("{x:?}"))
                .collect::<Vec<_>>()
                .join(","),
        );
    }
    [(jsonl, "a stray quote\""), (csv, "1,2,\"3,4,5")]
}

#[test]
fn a_bom_a_log_line_a_stray_quote_or_an_overflow_cost_their_own_line_only() {
    for (clean, stray) in clean_streams() {
        let csv = clean[0].starts_with("base_from");
        let join = |lines: &[String]| format!("{}\n", lines.join("\n")).into_bytes();
        let (code, out, err) = online(Path::new("-"), join(&clean));
        assert_eq!(code, 0, "{err}");
        let want = events(&out);
        assert!(want.len() > 3, "{out}");
        assert!(!err.contains("skipped"), "{err}");

        let mut bom = b"\xef\xbb\xbf".to_vec();
        bom.extend(join(&clean));
        let mut logged = vec!["[INFO] robot driver started".to_string(), String::new()];
        logged.extend(clean.iter().cloned());
        let mut bad = clean.clone();
        // Data line 50 gets a stray quote, line 120 a value whose inverse would overflow.
        bad.insert(50, stray.to_string());
        let overflow = if csv {
            format!("1e300,{}", clean[1].split_once(',').unwrap().1)
        } else {
            "{\"base_from_gripper\": [[1,0,0,1e300],[0,1,0,0],[0,0,1,0],[0,0,0,1]], \"camera_from_target\": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}".to_string()
        };
        bad.insert(120, overflow);
        let cases = [
            ("bom", bom, None),
            (
                "log line",
                join(&logged),
                Some(
                    "skipped 2 line(s) before the first pose record, the first not blank nor a comment at line 1: `[INFO] robot driver started`",
                ),
            ),
            ("bad lines", join(&bad), Some("2 bad line(s) skipped")),
        ];
        for (name, bytes, said) in cases {
            let mut runs = vec![("stdin", online(Path::new("-"), bytes.clone()))];
            runs.extend(online_fifo(&bytes).map(|r| ("fifo", r)));
            for (how, (code, out, err)) in runs {
                let what = format!("{} {name} via {how}", if csv { "CSV" } else { "JSONL" });
                assert_eq!(code, 0, "{what}: {err}");
                assert_eq!(events(&out), want, "{what}: {err}");
                if let Some(said) = said {
                    assert!(err.contains(said), "{what}: {err}");
                }
                if name == "bad lines" {
                    // Their places: the file's line numbers (a CSV header is line 1).
                    assert!(
                        err.contains(":51:") && err.contains(":121:"),
                        "{what}: {err}"
                    );
                }
            }
        }
    }
}

#[test]
fn online_on_a_fifo_reads_every_record() {
    let [(clean, _), _] = clean_streams();
    let text = format!("{}\n", clean.join("\n"));
    let Some((code, _, err)) = online_fifo(text.as_bytes()) else {
        return;
    };
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("from 200 pose(s)"), "{err}");
}

#[test]
fn an_endless_bad_stream_is_read_with_bounded_memory() {
    let [(clean, _), _] = clean_streams();
    let good = format!("{}\n", clean[..20].join("\n"));

    // 50 MB without a newline, after good records: one bad line, never buffered.
    let mut bytes = good.clone().into_bytes();
    bytes.extend(std::iter::repeat_n(b'x', 50_000_000));
    bytes.push(b'\n');
    bytes.extend(good.bytes());
    let (code, _, err) = online(Path::new("-"), bytes);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("-:21: field `-`: line longer than 65536 bytes")
            && err.contains("from 40 pose(s), 1 bad line(s) skipped"),
        "{err}"
    );

    // Nothing but zero bytes: one over-long line before any record, which ends the run as soon
    // as it passes the limit (issue 34 item 11: `/dev/zero` was read forever without a word).
    let (code, _, err) = online(Path::new("-"), vec![0; 20_000_000]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("-:1: field `-`: a line longer than 65536 bytes before any pose record"),
        "{err}"
    );

    // A million lines of garbage after good records: each one counted, few shown.
    let mut bytes = good.into_bytes();
    for _ in 0..1_000_000 {
        bytes.extend_from_slice(b"garbage \"\n");
    }
    let (code, _, err) = online(Path::new("-"), bytes);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("from 20 pose(s), 1000000 bad line(s) skipped"),
        "{err}"
    );
    assert!(err.lines().count() < 200, "{} lines", err.lines().count());
}

/// Output is buffered, but every event line is out before `online` waits for the next pose: a
/// reader at the other end of the pipe sees the events of the poses written so far while the
/// input is still open.
#[test]
fn events_come_out_before_the_next_pose_is_awaited() {
    use std::io::BufRead;
    let [(clean, _), _] = clean_streams();
    let (code, out, err) = online(Path::new("-"), format!("{}\n", clean.join("\n")).into());
    assert_eq!(code, 0, "{err}");
    let all = events(&out);
    assert!(all.len() > 3, "{out}");
    let mut child = Command::new(env!("CARGO_BIN_EXE_handeye"))
        .args([
            "online",
            "-",
            "--d-max",
            "100",
            "--estimator",
            "paper",
            "--output",
            "json",
        ])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let stdout = std::io::BufReader::new(child.stdout.take().unwrap());
    let (sender, received) = std::sync::mpsc::channel();
    let reader = std::thread::spawn(move || {
        for line in stdout.lines() {
            if sender.send(line.unwrap()).is_err() {
                return;
            }
        }
    });
    // All the poses but the last, the input left open: every event but those of the last pose
    // must arrive (the bound is only against a hang).
    stdin
        .write_all(format!("{}\n", clean[..clean.len() - 1].join("\n")).as_bytes())
        .unwrap();
    stdin.flush().unwrap();
    let last_pose = clean.len() - 1;
    let before_last: Vec<Value> = all
        .iter()
        .filter(|e| {
            e["poses"][2]
                .as_u64()
                .is_some_and(|p| (p as usize) < last_pose)
        })
        .cloned()
        .collect();
    assert!(before_last.len() > 3);
    let mut got = Vec::new();
    while got.len() < before_last.len() {
        let line = received
            .recv_timeout(std::time::Duration::from_secs(60))
            .expect("an event line was held back while the input was open");
        got.push(line);
    }
    assert_eq!(events(&got.join("\n")), before_last);
    drop(stdin);
    assert!(child.wait().unwrap().success());
    reader.join().unwrap();
}
