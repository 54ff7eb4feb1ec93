//! Every message the README quotes is what the tool prints today, with the exit code it says
//! (issue 33 item 14): each quote is found in the README (whitespace aside), and its command,
//! run on the repository's data, prints every part of it (in order, the README's "…" eliding the
//! rest) and exits as the README says. A message no shipped file provokes is checked against the
//! source that words it. The quick start is checked whole: each of its commands runs as written
//! (from the repository's root, on the repository's own files) and exits as its `# exit N` comment
//! says, and each output it shows is an excerpt of what that command prints.

mod common;
use common::{shared, testdata};

/// Runs `handeye` in `testdata/` and returns (exit code, stdout, stderr).
fn run(args: &[&str]) -> (i32, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_handeye"))
        .current_dir(testdata(""))
        .args(args)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr,
    )
}

/// One quote: the README's words, the parts the output must hold in order, the command and its
/// exit code.
struct Quote {
    readme: &'static str,
    parts: &'static [&'static str],
    args: &'static [&'static str],
    exit: i32,
}

const QUOTES: &[Quote] = &[
    Quote {
        readme: "\"no change larger than 0.15° / 3.80 mm; smaller ones cannot be seen in this recording\"",
        parts: &[
            "no change larger than 0.15° / 3.80 mm; smaller ones cannot be seen in this recording",
        ],
        args: &[
            "verify",
            "--x",
            "golden/saved_nominal_stations_eih_s0.calib",
            "kinhec/pairs/nominal_stations_eih_s0.jsonl",
            "--output",
            "json",
        ],
        exit: 0,
    },
    Quote {
        readme: "\"you are done\" when X's one-sigma is within 0.1° and 1 mm",
        parts: &["you are done: X is within your goal"],
        args: &[
            "advise",
            "kinhec/pairs/nominal_stations_eih_s1.jsonl",
            "--goal",
            "1,0.01",
        ],
        exit: 0,
    },
    Quote {
        readme: "\"every motion rotates about the same axis (the\n  gripper's z, (0.000, 0.000, 1.000) in the gripper frame, within 0.96°): a SCARA or 4-axis robot,\n  or a gantry with one wrist joint. X's rotation about the axis and its translation across it come\n  from the motions' translations across the axis and their turns about it, and these motions do\n  not fix them\"",
        parts: &[
            "every motion rotates about the same axis (the gripper's z, (0.000, 0.000, 1.000) in the gripper frame, within 0.96°): a SCARA or 4-axis robot, or a gantry with one wrist joint. X's rotation about the axis and its translation across it come from the motions' translations across the axis and their turns about it, and these motions do not fix them",
        ],
        args: &[
            "calibrate",
            "kinhec/pairs/degenerate_single_joint_continuous_eih_s0.jsonl",
            "--robot-world",
        ],
        exit: 3,
    },
    Quote {
        readme: "\"the poses fit far better read as the robot poses inverted: either the file gives gripper_from_base under the name base_from_gripper, or the setup is eye-to-hand … correct the input, or pass `--fix robot-inverted` …; if the setup is eye-to-hand, pass `--setup eye-to-hand`\"",
        parts: &[
            "the poses fit far better read as the robot poses inverted: either the file gives gripper_from_base under the name base_from_gripper, or the setup is eye-to-hand",
            "correct the input, or pass `--fix robot-inverted`",
            "; if the setup is eye-to-hand, pass `--setup eye-to-hand`",
        ],
        args: &[
            "calibrate",
            "kinhec/mistakes/robot_inverted__nominal_stations_eih_s0.jsonl",
        ],
        exit: 3,
    },
    Quote {
        readme: "\"if the camera is fixed (eye-to-hand), pass `--setup eye-to-hand` …; if the camera rides on the gripper (eye-in-hand) instead, its camera poses are inverted: correct the input, or pass `--fix camera-inverted`\"",
        parts: &[
            "if the camera is fixed (eye-to-hand), pass `--setup eye-to-hand`",
            "; if the camera rides on the gripper (eye-in-hand) instead, its camera poses are inverted: correct the input, or pass `--fix camera-inverted`",
        ],
        args: &["calibrate", "kinhec/pairs/nominal_stations_eth_s1.jsonl"],
        exit: 3,
    },
    Quote {
        readme: "(exit 3: `the poses fit far better with the robot and camera poses' numbers read as kuka-abc … rather than mitsubishi-abc …: name the convention the file uses, --rotation kuka-abc`)",
        parts: &[
            "the poses fit far better with the robot and camera poses' numbers read as kuka-abc",
            "rather than mitsubishi-abc",
            ": name the convention the file uses, `--rotation kuka-abc`",
        ],
        args: &[
            "calibrate",
            "rotation/kuka_abc_stations_eih_s0.csv",
            "--rotation",
            "mitsubishi-abc",
        ],
        exit: 3,
    },
    Quote {
        readme: "exit 2, \"swap the two frame flags\"",
        parts: &["swap the two frame flags"],
        args: &[
            "calibrate",
            "rosbag/eih_tf_mcap",
            "--base-frame",
            "tool0",
            "--gripper-frame",
            "base_link",
            "--camera-frame",
            "camera_link",
            "--target-frame",
            "board",
        ],
        exit: 2,
    },
    Quote {
        readme: "exits 2 saying \"the paper's estimator gives X without an uncertainty … the accumulating estimator's X carries one\"",
        parts: &[
            "the paper's estimator gives X without an uncertainty",
            "the accumulating estimator's X carries one",
        ],
        args: &[
            "online",
            "kinhec/pairs/nominal_stations_eih_s0.jsonl",
            "--estimator",
            "paper",
            "--output",
            "ros2",
        ],
        exit: 2,
    },
    Quote {
        readme: "exits 3 with `no X to publish from N pose(s): <why>`",
        parts: &["no X to publish from 40 pose(s): record turns about another axis"],
        args: &[
            "online",
            "kinhec/pairs/degenerate_single_joint_continuous_eih_s0.jsonl",
            "--output",
            "ros2",
        ],
        exit: 3,
    },
    Quote {
        readme: "\"every motion rotates about the same axis (the gripper's z, (0.000, 0.000, 1.000) in the\n  gripper frame, within 0.13°): a SCARA or 4-axis robot, …\"",
        parts: &[
            "every motion rotates about the same axis (the gripper's z, (0.000, 0.000, 1.000) in the gripper frame, within 0.13°): a SCARA or 4-axis robot",
            "`--prior tz=VALUE+-SIGMA`",
        ],
        args: &[
            "online",
            "kinhec/pairs/degenerate_single_joint_continuous_eih_s0.jsonl",
        ],
        exit: 0,
    },
];

/// Quotes of messages no shipped file provokes (a still robot, a damaged recording): each must be
/// words of the source that prints it.
const WORDED: &[(&str, &str)] = &[
    (
        "\"no rotation above 2° yet\"",
        "../handeye/src/track/events.rs",
    ),
    (
        "\"all rotation axes parallel so far\"",
        "../handeye/src/track/events.rs",
    ),
    (
        "could be read: a chunk is damaged",
        "../handeye/src/io/rosbag/storage.rs",
    ),
    (
        "(exit 2, `degrees given?`)",
        "../handeye/src/model/rotation.rs",
    ),
];

/// Whitespace runs as one space.
fn flat(text: &str) -> String {
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

fn readme() -> String {
    flat(&std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../README.md")).unwrap())
}

#[test]
fn every_quoted_message_is_printed_as_quoted() {
    let readme = readme();
    for q in QUOTES {
        assert!(
            readme.contains(&flat(q.readme)),
            "not in the README: {}",
            q.readme
        );
        let (code, out, err) = run(q.args);
        assert_eq!(code, q.exit, "{:?}: {err}", q.args);
        let printed = flat(&format!("{out}\n{err}"));
        let mut from = 0;
        for part in q.parts {
            let part = flat(part);
            let Some(at) = printed[from..].find(&part) else {
                panic!(
                    "{:?} does not print {part:?} (in order):\n{printed}",
                    q.args
                );
            };
            from += at + part.len();
        }
    }
}

#[test]
fn messages_without_a_reproducer_are_the_sources_words() {
    let readme = readme();
    for (quote, source) in WORDED {
        assert!(readme.contains(&flat(quote)), "not in the README: {quote}");
        let words = quote
            .trim_start_matches("(exit 2, `")
            .trim_end_matches("`)")
            .trim_matches('"');
        let path = format!("{}/{source}", env!("CARGO_MANIFEST_DIR"));
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.contains(words), "{source} does not word {words:?}");
    }
}

/// `verify` of a saved low-DOF X: the note the README quotes (two commands: the X is saved first).
#[test]
fn the_low_dof_verify_note_is_printed_as_quoted() {
    let quote = "\"it cannot check X's tz\"";
    assert!(readme().contains(quote), "not in the README: {quote}");
    let dir = std::env::temp_dir().join(format!("handeye-readme-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let saved = dir.join("scara.json");
    let scara = "low_dof/scara_eye-in-hand_s0.jsonl";
    let (code, out, err) = run(&[
        "calibrate",
        scara,
        "--prior",
        "tz=-0.1075+-0.002",
        "--output",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    std::fs::write(&saved, out).unwrap();
    let (code, _, err) = run(&["verify", "--x", saved.to_str().unwrap(), scara]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("it cannot check X's tz"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The README's camodocal row: the setup it names gives a questionable X whose caution names the
/// fix the row adds; with the fix, X has the sizes of a fixed camera (1.5 m from the base, the
/// tag 0.1 m from the gripper) and no size caution.
#[test]
fn the_camodocal_row_is_what_the_tool_advises() {
    let row = "`handeye calibrate ../shared/data/camodocal/TransformPairsInput.yml --setup eye-to-hand --fix both-inverted`";
    assert!(readme().contains(row), "not in the README: {row}");
    let Some(file) = shared("camodocal/TransformPairsInput.yml") else {
        return;
    };
    let file = file.to_str().unwrap();
    let (code, out, err) = run(&[
        "calibrate",
        file,
        "--setup",
        "eye-to-hand",
        "--output",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    let report: serde_json::Value = serde_json::from_str(&out).unwrap();
    let sizes = report["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .find(|w| w["code"] == "swapped_sizes")
        .expect("a size caution");
    assert_eq!(sizes["remedy"]["value"], "both-inverted", "{sizes}");
    let (code, out, err) = run(&[
        "calibrate",
        file,
        "--setup",
        "eye-to-hand",
        "--fix",
        "both-inverted",
        "--output",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    let report: serde_json::Value = serde_json::from_str(&out).unwrap();
    let codes: Vec<&str> = report["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w["code"].as_str().unwrap())
        .collect();
    assert!(!codes.contains(&"swapped_sizes"), "{codes:?}");
    let t: Vec<f64> = report["translation"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let distance = t.iter().map(|v| v * v).sum::<f64>().sqrt();
    assert!((1.0..2.5).contains(&distance), "{distance}");
}

/// One command of the quick start: its words after `handeye`, the file its stdout is redirected to
/// (`> FILE`), and the exit code its `# exit N` comment says.
struct Step {
    args: Vec<String>,
    into: Option<String>,
    exit: i32,
}

/// The `sh` blocks of the README's quick start, each with the `text` block that follows it (the
/// excerpt of its last command's output), if any.
fn quick_start() -> Vec<(Vec<Step>, Option<String>)> {
    let text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../README.md")).unwrap();
    let start = text
        .find("\n## Quick start\n")
        .expect("a quick start in the README");
    let section = &text[start + 1..];
    let section = &section[..section[3..].find("\n## ").map_or(section.len(), |e| e + 3)];
    let mut lines = section.lines().peekable();
    let mut blocks = Vec::new();
    let block = |lines: &mut std::iter::Peekable<std::str::Lines>| {
        let mut body = Vec::new();
        for line in lines.by_ref() {
            if line == "```" {
                break;
            }
            body.push(line);
        }
        body.join("\n")
    };
    while let Some(line) = lines.next() {
        if line != "```sh" {
            continue;
        }
        let commands = block(&mut lines).replace("\\\n", " ");
        let steps = commands
            .lines()
            .filter(|l| !l.trim().is_empty())
            .map(|l| {
                let (command, comment) = l
                    .split_once('#')
                    .unwrap_or_else(|| panic!("no `# exit N` after {l:?}"));
                let exit = comment
                    .trim()
                    .strip_prefix("exit ")
                    .and_then(|n| n.parse().ok())
                    .unwrap_or_else(|| panic!("no `# exit N` after {l:?}"));
                let (command, into) = match command.split_once(" > ") {
                    Some((c, file)) => (c, Some(file.trim().to_string())),
                    None => (command, None),
                };
                assert!(
                    !command.contains(['\'', '"', '|', '<', '$']),
                    "a quick-start command is plain words: {l:?}"
                );
                let mut words = command.split_whitespace().map(String::from);
                assert_eq!(words.next().as_deref(), Some("handeye"), "{l:?}");
                Step {
                    args: words.collect(),
                    into,
                    exit,
                }
            })
            .collect();
        let excerpt = (lines.peek() == Some(&"```text")).then(|| {
            lines.next();
            block(&mut lines)
        });
        blocks.push((steps, excerpt));
    }
    blocks
}

/// The README's quick start: every command of its `sh` blocks runs from the repository's root
/// and exits as its `# exit N` comment says; the `text` block after a `sh` block is an excerpt of
/// the block's last command's output: its lines, in order, in stdout then stderr (whitespace
/// aside; a line `...` leaves lines out, a `…` part of a line). Its inputs are the repository's own
/// files (no other project's data); a `> FILE` goes to a scratch folder.
#[test]
fn the_quick_start_prints_what_it_shows() {
    let blocks = quick_start();
    let jobs = [
        "calibrate",
        "verify",
        "--prior",
        "--intrinsics",
        "online",
        "--base-frame",
    ];
    for job in jobs {
        assert!(
            blocks.iter().any(|(steps, text)| text.is_some()
                && steps.iter().any(|s| s.args.iter().any(|a| a == job))),
            "the quick start shows no `{job}` with its output"
        );
    }
    let root = testdata("..");
    let scratch = tempfile::tempdir().unwrap();
    for (steps, excerpt) in &blocks {
        let mut printed = String::new();
        for step in steps {
            let args: Vec<String> = step
                .args
                .iter()
                .map(|a| {
                    let made = scratch.path().join(a);
                    if made.exists() {
                        return made.to_str().unwrap().to_string();
                    }
                    assert!(
                        !a.starts_with("../")
                            && (!a.starts_with("testdata/") || root.join(a).exists()),
                        "the quick start reads {a}, not a file of the repository's testdata"
                    );
                    a.clone()
                })
                .collect();
            let out = std::process::Command::new(env!("CARGO_BIN_EXE_handeye"))
                .current_dir(&root)
                .args(&args)
                .output()
                .unwrap();
            let (stdout, stderr) = (
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr),
            );
            assert_eq!(
                out.status.code(),
                Some(step.exit),
                "handeye {}: {stderr}",
                step.args.join(" ")
            );
            if let Some(file) = &step.into {
                std::fs::write(scratch.path().join(file), stdout.as_bytes()).unwrap();
            }
            printed = flat(&format!("{stdout}\n{stderr}"));
        }
        let Some(excerpt) = excerpt else { continue };
        let mut from = 0;
        let parts = excerpt
            .lines()
            .filter(|l| l.trim() != "...")
            .flat_map(|l| l.split('…'))
            .map(flat)
            .filter(|p| !p.is_empty());
        for part in parts {
            let Some(at) = printed[from..].find(&part) else {
                panic!(
                    "the quick start's excerpt of `handeye {}` says {part:?}, not printed (in order):\n{printed}",
                    steps.last().unwrap().args.join(" ")
                );
            };
            from += at + part.len();
        }
    }
}
