//! Every message the README quotes is what the tool prints today, with the exit code it says
//! (issue 33 item 14): each quote is found in the README (whitespace aside), and its command,
//! run on the repository's data, prints every part of it (in order, the README's "…" eliding the
//! rest) and exits as the README says. A message no shipped file provokes is checked against the
//! source that words it.

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
        readme: "\"if the camera is fixed (eye-to-hand), pass `--setup eye-to-hand` …; if the camera rides on the gripper (eye-in-hand), correct the input, or pass `--fix camera-inverted`\"",
        parts: &[
            "if the camera is fixed (eye-to-hand), pass `--setup eye-to-hand`",
            "; if the camera rides on the gripper (eye-in-hand), correct the input, or pass `--fix camera-inverted`",
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
        parts: &["no X to publish from 40 pose(s): every motion rotates about the same axis"],
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
