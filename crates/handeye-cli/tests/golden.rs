//! Golden outputs: every command of `testdata/golden/commands.txt` (`calibrate`, `online`,
//! `advise` and `inspect` over the repository's real and realistic testdata, the ways users run
//! them, refusals and bad input included) must give byte for byte the exit code, stdout and stderr
//! recorded in `testdata/golden/outputs.jsonl`. It guards behaviour-preserving changes (a
//! refactor, a faster path) against any change of an output, down to the last digit of a number
//! or a word of a message.
//!
//! Masked, here and in `record.py` alike: the wall-clock timing `"seconds": <number>` of
//! `online`'s events (and of their `optimal` transform) becomes `"seconds":"*"`; and in `online`'s
//! stderr the note on rotation matrices projected onto SO(3), printed by the reader thread when
//! the input ends at a moment that races with the calibrating thread's messages, is moved to the
//! end. The commands run from the repository root with an empty environment.
//!
//! Other projects' data is read in place from the shared folder (`../shared/data`, or
//! `$HANDEYE_SHARED_DATA`; `crates/handeye/tests/shared_data`): a command names it `{shared}`,
//! runs with the folder's path in its place, and its outputs name it `{shared}` again before they
//! are compared, so that the baseline does not depend on where the folder is. The commands whose
//! set is missing are skipped, said on one line (a failure with `HANDEYE_SHARED_REQUIRED=1`).
//!
//! A change meant to change an output re-records the baseline in the same commit:
//!
//! ```sh
//! cargo build --release -p handeye-cli && python3 testdata/golden/record.py --bin target/release/handeye
//! ```
//!
//! and `git diff testdata/golden/outputs.jsonl` shows what changed. `record.py --check --bin B`
//! compares another binary with the baseline without writing it.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};

use serde_json::Value;

mod common;
use common::shared_data;

/// How to re-record the baseline, for the failure messages.
const RERECORD: &str = "cargo build --release -p handeye-cli && python3 testdata/golden/record.py --bin target/release/handeye";

/// Failing commands shown in full.
const SHOWN: usize = 20;

/// The key of `online`'s wall-clock timings.
const SECONDS: &str = "\"seconds\":";

/// The end of the note that rotation matrices were projected onto SO(3).
const PROJECTED: &str = "(rounded when printed): projected onto the nearest rotation";

/// One command's exit code (-1 when killed by a signal) and its output, masked.
#[derive(Debug, PartialEq)]
struct Outcome {
    exit: i64,
    stdout: String,
    stderr: String,
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The words of one line, split as the shell (and Python's `shlex.split`) does: blanks separate
/// words; `'…'` is literal; in `"…"` a backslash escapes only `"` and `\`; outside quotes it
/// escapes any character.
fn split_words(line: &str) -> Result<Vec<String>, String> {
    let mut words = Vec::new();
    let mut word = String::new();
    let mut in_word = false;
    let mut chars = line.chars();
    while let Some(c) = chars.next() {
        match c {
            ' ' | '\t' | '\r' | '\n' => {
                if in_word {
                    words.push(std::mem::take(&mut word));
                    in_word = false;
                }
            }
            '\'' => {
                in_word = true;
                loop {
                    match chars.next() {
                        Some('\'') => break,
                        Some(c) => word.push(c),
                        None => return Err("no closing quotation".into()),
                    }
                }
            }
            '"' => {
                in_word = true;
                loop {
                    match chars.next() {
                        Some('"') => break,
                        Some('\\') => match chars.next() {
                            Some(c @ ('"' | '\\')) => word.push(c),
                            Some(c) => {
                                word.push('\\');
                                word.push(c);
                            }
                            None => return Err("no closing quotation".into()),
                        },
                        Some(c) => word.push(c),
                        None => return Err("no closing quotation".into()),
                    }
                }
            }
            '\\' => {
                in_word = true;
                match chars.next() {
                    Some(c) => word.push(c),
                    None => return Err("no escaped character".into()),
                }
            }
            c => {
                in_word = true;
                word.push(c);
            }
        }
    }
    if in_word {
        words.push(word);
    }
    Ok(words)
}

/// The commands of commands.txt: every line not blank nor starting with `#`, split into words.
fn commands(path: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.lines()
        .enumerate()
        .filter(|(_, line)| !line.trim().is_empty() && !line.trim().starts_with('#'))
        .map(|(k, line)| {
            split_words(line.trim()).unwrap_or_else(|e| panic!("{}:{}: {e}", path.display(), k + 1))
        })
        .collect()
}

/// The recorded commands and outcomes of outputs.jsonl.
fn baseline(path: &Path) -> Vec<(Vec<String>, Outcome)> {
    let text = std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: {e}; record it with `{RERECORD}`", path.display()));
    text.lines()
        .enumerate()
        .filter(|(_, line)| !line.trim().is_empty())
        .map(|(k, line)| {
            let bad = |what: &str| -> ! {
                panic!(
                    "{}:{}: {what}; re-record it with `{RERECORD}`",
                    path.display(),
                    k + 1
                )
            };
            let v: Value = serde_json::from_str(line).unwrap_or_else(|e| bad(&e.to_string()));
            let text = |key: &str| match v.get(key).and_then(Value::as_str) {
                Some(s) => s.to_string(),
                None => bad(&format!("no string `{key}`")),
            };
            let args = match v.get("args").and_then(Value::as_array) {
                Some(a) => a
                    .iter()
                    .map(|w| match w.as_str() {
                        Some(w) => w.to_string(),
                        None => bad("an argument that is not a string"),
                    })
                    .collect(),
                None => bad("no array `args`"),
            };
            let Some(exit) = v.get("exit").and_then(Value::as_i64) else {
                bad("no integer `exit`")
            };
            let outcome = Outcome {
                exit,
                stdout: text("stdout"),
                stderr: text("stderr"),
            };
            (args, outcome)
        })
        .collect()
}

/// `"seconds": <number>` with the number replaced by `"*"` (the spaces after the colon kept).
fn mask(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(at) = rest.find(SECONDS) {
        let key_end = at + SECONDS.len();
        let spaces = rest[key_end..].len() - rest[key_end..].trim_start_matches([' ', '\t']).len();
        out.push_str(&rest[..key_end + spaces]);
        rest = &rest[key_end + spaces..];
        let b = rest.as_bytes();
        let mut n = usize::from(b.first() == Some(&b'-'));
        if b.get(n).is_some_and(u8::is_ascii_digit) {
            while b
                .get(n)
                .is_some_and(|c| c.is_ascii_digit() || b".eE+-".contains(c))
            {
                n += 1;
            }
            out.push_str("\"*\"");
            rest = &rest[n..];
        }
    }
    out.push_str(rest);
    out
}

/// `online`'s stderr with the notes on projected rotation matrices moved to the end, in order.
fn normalize_stderr(args: &[String], text: String) -> String {
    if args.first().map(String::as_str) != Some("online") {
        return text;
    }
    let mut lines: Vec<&str> = text.split('\n').collect();
    let tail = lines.pop().unwrap_or("");
    let (notes, mut others): (Vec<&str>, Vec<&str>) = lines
        .into_iter()
        .partition(|line| line.ends_with(PROJECTED));
    others.extend(notes);
    others.push(tail);
    others.join("\n")
}

/// The shared sets a command reads (`{shared}/SET/...`) that are missing.
fn sets_missing(args: &[String]) -> Vec<&str> {
    let prefix = format!("{}/", shared_data::PLACEHOLDER);
    let mut sets: Vec<&str> = args
        .iter()
        .filter_map(|w| w.split_once(&prefix))
        .map(|(_, rest)| rest.split('/').next().unwrap_or(rest))
        .collect();
    sets.sort_unstable();
    sets.dedup();
    sets.retain(|set| shared_data::missing(set));
    sets
}

fn run(args: &[String]) -> Outcome {
    let out = Command::new(env!("CARGO_BIN_EXE_handeye"))
        .args(args.iter().map(|w| shared_data::unmasked(w)))
        .current_dir(root())
        .env_clear()
        .stdin(Stdio::null())
        .output()
        .unwrap_or_else(|e| panic!("handeye {}: {e}", args.join(" ")));
    let text = |bytes: Vec<u8>| {
        String::from_utf8(bytes).unwrap_or_else(|e| String::from_utf8_lossy(e.as_bytes()).into())
    };
    Outcome {
        exit: out.status.code().map_or(-1, i64::from),
        stdout: mask(&shared_data::masked(&text(out.stdout))),
        stderr: normalize_stderr(args, mask(&shared_data::masked(&text(out.stderr)))),
    }
}

/// Every command run on 2 to 4 threads; the outcomes in the commands' order (`None`: skipped,
/// its shared set missing).
fn run_all(commands: &[Vec<String>]) -> Vec<Option<Outcome>> {
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get().clamp(2, 4));
    let next = AtomicUsize::new(0);
    let mut done: Vec<(usize, Option<Outcome>)> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                s.spawn(|| {
                    let mut mine = Vec::new();
                    loop {
                        let k = next.fetch_add(1, Ordering::Relaxed);
                        let Some(args) = commands.get(k) else {
                            return mine;
                        };
                        let outcome = sets_missing(args).is_empty().then(|| run(args));
                        mine.push((k, outcome));
                    }
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().unwrap())
            .collect()
    });
    done.sort_by_key(|(k, _)| *k);
    done.into_iter().map(|(_, outcome)| outcome).collect()
}

/// Up to 200 characters of `line` around the character `at` (where it first differs).
fn excerpt(line: &str, at: usize) -> String {
    const WIDTH: usize = 200;
    let chars: Vec<char> = line.chars().collect();
    if chars.len() <= WIDTH {
        return line.to_string();
    }
    let start = at.saturating_sub(40).min(chars.len() - WIDTH);
    let end = start + WIDTH;
    format!(
        "{}{}{}",
        if start > 0 { "…" } else { "" },
        chars[start..end].iter().collect::<String>(),
        if end < chars.len() { "…" } else { "" }
    )
}

/// Where two texts first differ: a line saying where, then the recorded and the actual line
/// around the first differing character.
fn first_difference(expected: &str, actual: &str) -> Option<String> {
    let (a, b): (Vec<&str>, Vec<&str>) =
        (expected.split('\n').collect(), actual.split('\n').collect());
    let k = (0..a.len().max(b.len())).find(|&k| a.get(k) != b.get(k))?;
    let (x, y) = (a.get(k).copied(), b.get(k).copied());
    let (x_chars, y_chars) = (x.unwrap_or("").chars(), y.unwrap_or("").chars());
    let column = x_chars.zip(y_chars).take_while(|(p, q)| p == q).count();
    let show = |l: Option<&str>| l.map_or("<no line>".to_string(), |l| excerpt(l, column));
    let length = |l: Option<&str>| l.map_or(0, |l| l.chars().count());
    Some(format!(
        "first differing line {}, column {} (lines of {} and {} characters):\n    recorded: {}\n    now:      {}",
        k + 1,
        column + 1,
        length(x),
        length(y),
        show(x),
        show(y)
    ))
}

/// How one command's outcome differs from the recorded one, or `None`.
fn differences(expected: &Outcome, actual: &Outcome) -> Option<String> {
    let mut notes = Vec::new();
    if expected.exit != actual.exit {
        notes.push(format!(
            "  exit code: recorded {}, now {}",
            expected.exit, actual.exit
        ));
    }
    for (stream, x, y) in [
        ("stdout", &expected.stdout, &actual.stdout),
        ("stderr", &expected.stderr, &actual.stderr),
    ] {
        if let Some(place) = first_difference(x, y) {
            notes.push(format!("  {stream}, {place}"));
        }
    }
    (!notes.is_empty()).then(|| notes.join("\n"))
}

#[test]
fn outputs_are_byte_identical_to_the_recorded_ones() {
    let golden = root().join("testdata/golden");
    let commands = commands(&golden.join("commands.txt"));
    let recorded = baseline(&golden.join("outputs.jsonl"));
    assert!(
        !commands.is_empty(),
        "testdata/golden/commands.txt holds no command"
    );

    // A stale baseline: commands.txt was edited without re-recording.
    let recorded_args: Vec<&Vec<String>> = recorded.iter().map(|(args, _)| args).collect();
    if recorded_args.len() != commands.len()
        || recorded_args.iter().zip(&commands).any(|(a, b)| *a != b)
    {
        let first = (0..commands.len().max(recorded.len()))
            .find(|&k| commands.get(k) != recorded_args.get(k).copied())
            .unwrap_or(0);
        let show = |a: Option<&Vec<String>>| {
            a.map_or("<none>".to_string(), |a| format!("handeye {}", a.join(" ")))
        };
        panic!(
            "testdata/golden/outputs.jsonl is stale: it records {} command(s), commands.txt has {}; \
             the first that differs is number {}:\n  commands.txt:  {}\n  outputs.jsonl: {}\n\
             Re-record the baseline with `{RERECORD}` (after checking that the outputs of the \
             commands that were there have not changed: `python3 testdata/golden/record.py --check \
             --bin target/release/handeye`).",
            recorded.len(),
            commands.len(),
            first + 1,
            show(commands.get(first)),
            show(recorded_args.get(first).copied()),
        );
    }

    // Other projects' data missing: its commands are skipped, said once.
    let mut missing: Vec<&str> = commands.iter().flat_map(|a| sets_missing(a)).collect();
    missing.sort_unstable();
    missing.dedup();
    if !missing.is_empty() {
        let skipped = commands
            .iter()
            .filter(|a| !sets_missing(a).is_empty())
            .count();
        shared_data::skip(&format!(
            "{skipped} of {} golden command(s), which read {}",
            commands.len(),
            missing.join(", ")
        ));
    }

    let started = std::time::Instant::now();
    let outcomes = run_all(&commands);
    let failures: Vec<String> = recorded
        .iter()
        .zip(&outcomes)
        .filter_map(|((args, expected), actual)| {
            let actual = actual.as_ref()?;
            differences(expected, actual).map(|d| format!("handeye {}\n{d}", args.join(" ")))
        })
        .collect();
    println!(
        "{} golden command(s) run in {:.1} s, {} differ",
        outcomes.iter().flatten().count(),
        started.elapsed().as_secs_f64(),
        failures.len()
    );
    assert!(
        failures.is_empty(),
        "{} of {} golden command(s) give other outputs than recorded in \
         testdata/golden/outputs.jsonl (the first {} shown):\n\n{}\n\n\
         If the change is meant, re-record the baseline in the same commit: `{RERECORD}`, \
         and review `git diff testdata/golden/outputs.jsonl`.",
        failures.len(),
        commands.len(),
        failures.len().min(SHOWN),
        failures[..failures.len().min(SHOWN)].join("\n\n"),
    );
}

#[test]
fn words_are_split_as_the_shell_does() {
    let split = |s: &str| split_words(s).unwrap();
    assert_eq!(
        split("  calibrate a.jsonl  --output json "),
        ["calibrate", "a.jsonl", "--output", "json"]
    );
    assert_eq!(
        split(r#"a 'b c' "d \" \\ \e" f\ g ''"#),
        ["a", "b c", r#"d " \ \e"#, "f g", ""]
    );
    assert_eq!(split(r#"x"y z"'w'"#), ["xy zw"]);
    assert!(split_words("'open").is_err() && split_words("\"open").is_err());
}

#[test]
fn timings_are_masked_and_projection_notes_moved() {
    assert_eq!(
        mask(r#"{"seconds":3.335e-6,"x":1}{"seconds": -1.5E+2}{"seconds":"*"}"seconds":x"#),
        r#"{"seconds":"*","x":1}{"seconds": "*"}{"seconds":"*"}"seconds":x"#
    );
    let note = format!("f: 2 rotation matrices orthonormal only to 1e-10 {PROJECTED}");
    let online = vec!["online".to_string()];
    assert_eq!(
        normalize_stderr(&online, format!("{note}\nb\nc\n")),
        format!("b\nc\n{note}\n")
    );
    assert_eq!(normalize_stderr(&online, String::new()), "");
    assert_eq!(
        normalize_stderr(&["calibrate".to_string()], format!("{note}\nb\n")),
        format!("{note}\nb\n")
    );
}
