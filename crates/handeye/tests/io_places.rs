//! Seeded fuzzing of every reader (issue 12, "never a silent wrong answer"): valid files of every
//! format are mutated (bytes changed, inserted, deleted; lines repeated, dropped; numbers made
//! absurd; keys swapped; files renamed) and read. Each read must give either poses that every
//! solver can use without producing a NaN, or an error that names its place: a parse error with
//! the real file, a field and the line (from 1, within the file) whenever the problem is on a
//! line, or an I/O error naming the file. Nothing may panic.
//!
//! Measured on the readers before issue 12: 139 of the 2,800 cases failed (67 moveit and 23
//! OpenCV-YAML errors at line 0, 40 ViSP errors naming a file that is not there, 6 ViSP rotation
//! vectors of 1e308 read as NaN poses, 3 CSV headers naming an empty column), and every text file
//! that is not UTF-8 was an I/O error without a line.

use std::collections::BTreeMap;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

use handeye::io::{Format, PoseReader, Truth, read_pose_file, read_stamped_poses, write_truth};
use handeye::{
    Error, Method, Pairing, PosePair, Setup, Transform, TransformJson, motion_pairs, solve,
};
use nalgebra::Vector3;
use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

/// Mutated files per format.
const MUTATIONS: usize = 400;

/// The formats fuzzed, each read by its own reader.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Kind {
    Jsonl,
    Csv,
    OpencvYaml,
    Moveit,
    MoveitYaml,
    EasyHandeye,
    Visp,
    Stream,
    Truth,
}

const KINDS: [Kind; 9] = [
    Kind::Jsonl,
    Kind::Csv,
    Kind::OpencvYaml,
    Kind::Moveit,
    Kind::MoveitYaml,
    Kind::EasyHandeye,
    Kind::Visp,
    Kind::Stream,
    Kind::Truth,
];

fn random_transform(rng: &mut Xoshiro256PlusPlus) -> Transform {
    let mut v = || {
        Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
    };
    Transform::new(v() * 0.5, v() * 1.5)
}

fn rows(t: &Transform) -> String {
    serde_json::to_string(&TransformJson::from(t).matrix).unwrap()
}

fn flat(t: &Transform) -> Vec<f64> {
    TransformJson::from(t)
        .matrix
        .iter()
        .flatten()
        .copied()
        .collect()
}

/// The valid files of a format: (file name, content); one file except for ViSP.
fn valid_files(kind: Kind, rng: &mut Xoshiro256PlusPlus) -> Vec<(String, String)> {
    let mut poses = |n: usize| -> Vec<(Transform, Transform)> {
        (0..n)
            .map(|_| (random_transform(rng), random_transform(rng)))
            .collect()
    };
    match kind {
        Kind::Jsonl => {
            let lines: Vec<String> = poses(4)
                .iter()
                .enumerate()
                .map(|(k, (a, b))| {
                    if k % 2 == 0 {
                        format!("{{\"stamp\": {k}.5, \"base_from_gripper\": {}, \"camera_from_target\": {}}}", rows(a), rows(b))
                    } else {
                        let a = serde_json::to_string(&TransformJson::from(a)).unwrap();
                        format!("{{\"gripper_from_base\": {a}, \"target_from_camera\": {}}}", rows(b))
                    }
                })
                .collect();
            vec![(
                "poses.jsonl".into(),
                format!("# recorded\n{}\n", lines.join("\n\n")),
            )]
        }
        Kind::Csv => {
            let frames = ["base_from_gripper", "target_from_camera"];
            let mut header = vec!["stamp".to_string()];
            for f in frames {
                for s in ["x", "y", "z", "qx", "qy", "qz", "qw"] {
                    header.push(format!("{f}_{s}"));
                }
            }
            let mut text = format!("# exported\n{}\n", header.join(","));
            for (k, (a, b)) in poses(4).iter().enumerate() {
                let mut row = vec![format!("{k}.25")];
                for t in [a, b] {
                    let j = TransformJson::from(t);
                    row.extend(
                        j.translation
                            .iter()
                            .chain(&j.quaternion_xyzw)
                            .map(|v| v.to_string()),
                    );
                }
                text.push_str(&row.join(","));
                text.push('\n');
            }
            vec![("poses.csv".into(), text)]
        }
        Kind::OpencvYaml => {
            let mut text = "%YAML:1.0\n".to_string();
            for (k, (a, b)) in poses(3).iter().enumerate() {
                for (name, t) in [("T1", a), ("T2", b)] {
                    let v: Vec<String> = flat(t).iter().map(|x| format!("{x:.9}")).collect();
                    text.push_str(&format!(
                        "{name}_{k}: !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: d\n   data: [ {},\n       {} ]\n",
                        v[..8].join(", "),
                        v[8..].join(", ")
                    ));
                }
            }
            vec![("pairs.yml".into(), text)]
        }
        Kind::Moveit => {
            let items: Vec<String> = poses(3)
                .iter()
                .enumerate()
                .map(|(k, (a, b))| {
                    let b = if k == 1 {
                        serde_json::to_string(&flat(b)).unwrap()
                    } else {
                        serde_json::to_string_pretty(&TransformJson::from(b).matrix).unwrap()
                    };
                    format!("  [\n    {},\n    {b}\n  ]", rows(a))
                })
                .collect();
            vec![(
                "moveit.json".into(),
                format!("[\n{}\n]\n", items.join(",\n")),
            )]
        }
        Kind::MoveitYaml => {
            // As yaml-cpp's emitter writes moveit_calibration's "Save samples".
            let mut text = String::new();
            for (a, b) in poses(3) {
                for (k, (key, t)) in [("effector_wrt_world", a), ("object_wrt_sensor", b)]
                    .into_iter()
                    .enumerate()
                {
                    text.push_str(if k == 0 { "- " } else { "  " });
                    text.push_str(&format!("{key}:\n"));
                    for v in flat(&t) {
                        text.push_str(&format!("    - {v}\n"));
                    }
                }
            }
            vec![("samples.yaml".into(), text)]
        }
        Kind::EasyHandeye => {
            // As rosidl's message_to_yaml writes easy_handeye2's SampleList.
            let mut text = "parameters:\n  name: cell\n  calibration_type: eye_in_hand\n  robot_base_frame: base_link\nsamples:\n".to_string();
            for (a, b) in poses(3) {
                for (k, (key, t)) in [("robot", a), ("tracking", b)].into_iter().enumerate() {
                    let j = TransformJson::from(&t);
                    text.push_str(if k == 0 { "- " } else { "  " });
                    text.push_str(&format!("{key}:\n    translation:\n"));
                    for (c, v) in ["x", "y", "z"].iter().zip(j.translation) {
                        text.push_str(&format!("      {c}: {v}\n"));
                    }
                    text.push_str("    rotation:\n");
                    for (c, v) in ["x", "y", "z", "w"].iter().zip(j.quaternion_xyzw) {
                        text.push_str(&format!("      {c}: {v}\n"));
                    }
                }
            }
            vec![("cell.samples".into(), text)]
        }
        Kind::Visp => {
            let mut files = Vec::new();
            for (k, (a, b)) in poses(3).iter().enumerate() {
                for (prefix, t) in [("pose_fPe", a), ("pose_cPo", b)] {
                    let u = t.rotation.scaled_axis();
                    let v = t.translation.vector;
                    let data: Vec<String> = [v.x, v.y, v.z, u.x, u.y, u.z]
                        .iter()
                        .map(|x| format!("  - [{x}]"))
                        .collect();
                    files.push((
                        format!("{prefix}_{}.yaml", k + 1),
                        format!("rows: 6\ncols: 1\ndata:\n{}\n", data.join("\n")),
                    ));
                }
            }
            files
        }
        Kind::Stream => {
            let mut text = "# t x y z qx qy qz qw\n".to_string();
            for (k, (a, _)) in poses(5).iter().enumerate() {
                let j = TransformJson::from(a);
                let v: Vec<String> = j
                    .translation
                    .iter()
                    .chain(&j.quaternion_xyzw)
                    .map(|x| x.to_string())
                    .collect();
                text.push_str(&format!("{}.0, {}\n", 100 + k, v.join(", ")));
            }
            vec![("robot.txt".into(), text)]
        }
        Kind::Truth => {
            let (x, target) = poses(1)[0];
            let truth = Truth {
                x,
                frame: "gripper_from_camera".into(),
                target: Some(("base_from_target".into(), target)),
            };
            let dir = scratch("truth-seed");
            let path = dir.join("truth.json");
            write_truth(&path, &truth).unwrap();
            let text = std::fs::read_to_string(&path).unwrap();
            std::fs::remove_dir_all(&dir).unwrap();
            vec![("truth.json".into(), text)]
        }
    }
}

/// Replacement text for a number: absurd, special or merely wrong.
const ODD_NUMBERS: [&str; 9] = [
    "1e308", "-1e308", "NaN", "1e9999", "inf", "2e9", "0.5", "-3", "1.7e18",
];
/// Bytes that matter to some format.
const ODD_BYTES: &[u8] = b"0123456789-+.eE,:[]{}\" \n\t#xN_\xff\xc3";

/// Applies 1 to 3 random mutations to `text`.
fn mutate(text: &[u8], rng: &mut Xoshiro256PlusPlus) -> Vec<u8> {
    let mut out = text.to_vec();
    for _ in 0..rng.random_range(1..=3) {
        if out.is_empty() {
            break;
        }
        let at = rng.random_range(0..out.len());
        let byte = ODD_BYTES[rng.random_range(0..ODD_BYTES.len())];
        match rng.random_range(0..8) {
            0 => out[at] = byte,
            1 => {
                out.remove(at);
            }
            2 => out.insert(at, byte),
            3 => out.truncate(at),
            4 | 5 => {
                // A whole number token replaced.
                let is_num = |b: u8| b.is_ascii_digit() || b"-+.eE".contains(&b);
                if let Some(start) = (at..out.len()).find(|&k| out[k].is_ascii_digit()) {
                    let mut s = start;
                    while s > 0 && is_num(out[s - 1]) {
                        s -= 1;
                    }
                    let mut e = start;
                    while e < out.len() && is_num(out[e]) {
                        e += 1;
                    }
                    let odd = ODD_NUMBERS[rng.random_range(0..ODD_NUMBERS.len())];
                    out.splice(s..e, odd.bytes());
                }
            }
            6 => {
                // A line repeated or dropped.
                let lines: Vec<&[u8]> = out.split(|&b| b == b'\n').collect();
                let k = rng.random_range(0..lines.len());
                let mut next: Vec<Vec<u8>> = lines.iter().map(|l| l.to_vec()).collect();
                if rng.random_bool(0.5) {
                    next.insert(k, lines[k].to_vec());
                } else {
                    next.remove(k);
                }
                out = next.join(&b'\n');
            }
            _ => {
                // A key or name replaced by another of the file.
                let text = String::from_utf8_lossy(&out).into_owned();
                let words: Vec<&str> = text
                    .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                    .filter(|w| w.len() > 2 && w.chars().any(|c| c.is_ascii_alphabetic()))
                    .collect();
                if words.len() >= 2 {
                    let a = words[rng.random_range(0..words.len())];
                    let b = words[rng.random_range(0..words.len())];
                    out = text.replacen(a, b, 1).into_bytes();
                }
            }
        }
    }
    out
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("handeye-places-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// What one read gave.
#[derive(Debug, Default, Clone, Copy)]
struct Tally {
    accepted: usize,
    on_a_line: usize,
    whole_file: usize,
    io: usize,
}

/// Messages of the problems that concern a whole file, the only ones reported at line 0.
const WHOLE_FILE: [&str; 10] = [
    "the file is empty",
    "at least 2",
    "missing (moveit_calibration's samples",
    "missing (easy_handeye2's samples",
    "missing: give",
    "no ViSP robot pose files",
    "missing `data:`",
    "given twice: `pose_",
    "to pair it with",
    "is not a pose number",
];

/// Checks an error against the place it must name; `files` are the paths it may name with their
/// line counts.
fn check_error(e: &Error, files: &BTreeMap<String, usize>, tally: &mut Tally, what: &str) {
    match e {
        Error::Parse {
            file,
            line,
            field,
            message,
            ..
        } => {
            let lines = files
                .get(file)
                .unwrap_or_else(|| panic!("{what}: names `{file}`, not the file read: {e}"));
            assert!(!field.is_empty() && !message.is_empty(), "{what}: {e}");
            if *line == 0 {
                assert!(
                    WHOLE_FILE.iter().any(|m| message.contains(m)),
                    "{what}: no line for a problem on a line: {e}"
                );
                tally.whole_file += 1;
            } else {
                assert!(
                    line <= lines,
                    "{what}: line {line} of a {lines}-line file: {e}"
                );
                tally.on_a_line += 1;
            }
        }
        Error::Io { file, source } => {
            assert!(files.contains_key(file), "{what}: names `{file}`: {e}");
            // Bad content (such as bytes that are not UTF-8) is a parse error on its line.
            assert_ne!(
                source.kind(),
                std::io::ErrorKind::InvalidData,
                "{what}: {e}"
            );
            tally.io += 1;
        }
        other => panic!("{what}: not a parse or I/O error: {other:?}"),
    }
}

/// Every solver on accepted poses: an answer without NaN, or an error.
fn check_usable(pairs: &[PosePair], what: &str) {
    for p in pairs {
        for t in [&p.base_from_gripper, &p.camera_from_target] {
            assert!(t.to_homogeneous().iter().all(|v| v.is_finite()), "{what}");
        }
    }
    let motions = motion_pairs(pairs, Pairing::All, Setup::EyeInHand);
    for method in Method::ALL {
        if let Ok(c) = solve(method, &motions) {
            let x = c.x.to_homogeneous();
            assert!(
                x.iter().all(|v| v.is_finite()),
                "{what}: {method:?} gave {x}"
            );
        }
    }
}

/// Reads the mutated input at `path` as `kind` and checks the outcome.
fn read_and_check(
    kind: Kind,
    path: &Path,
    files: &BTreeMap<String, usize>,
    tally: &mut Tally,
    what: &str,
) {
    let outcome = catch_unwind(AssertUnwindSafe(|| -> Result<Vec<PosePair>, Error> {
        Ok(match kind {
            Kind::Jsonl => read_pose_file(path, Format::Jsonl)?.pairs,
            Kind::Csv => read_pose_file(path, Format::Csv)?.pairs,
            Kind::OpencvYaml => read_pose_file(path, Format::OpencvYaml)?.pairs,
            Kind::Moveit => read_pose_file(path, Format::Moveit)?.pairs,
            Kind::MoveitYaml => read_pose_file(path, Format::MoveitYaml)?.pairs,
            Kind::EasyHandeye => read_pose_file(path, Format::EasyHandeye)?.pairs,
            Kind::Visp => read_pose_file(path, Format::Visp)?.pairs,
            Kind::Stream => {
                let s = read_stamped_poses(path, None)?;
                assert!(s.poses.iter().all(|p| p.stamp.is_finite()));
                s.poses
                    .iter()
                    .map(|p| PosePair {
                        base_from_gripper: p.pose,
                        camera_from_target: p.pose.inverse(),
                    })
                    .collect()
            }
            Kind::Truth => {
                let t = Truth::read(path)?;
                let target = t.target.map_or(t.x, |(_, t)| t);
                vec![PosePair {
                    base_from_gripper: t.x,
                    camera_from_target: target,
                }]
            }
        })
    }));
    match outcome {
        Err(_) => panic!("{what}: the reader panicked"),
        Ok(Ok(pairs)) => {
            check_usable(&pairs, what);
            tally.accepted += 1;
        }
        Ok(Err(e)) => check_error(&e, files, tally, what),
    }
}

/// The streaming readers report every bad record on its own line and go on.
fn stream_and_check(bytes: &[u8], format: Format, name: &str, lines: usize, what: &str) {
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        let Ok(reader) = PoseReader::new(bytes, name, format) else {
            return;
        };
        for record in reader.take(10_000) {
            match record {
                Ok(r) => check_usable(&[r.pose], what),
                Err(Error::Parse {
                    file, line, field, ..
                }) => {
                    assert_eq!(file, name, "{what}");
                    assert!(
                        line >= 1 && line <= lines && !field.is_empty(),
                        "{what}: line {line}"
                    );
                }
                Err(other) => panic!("{what}: {other:?}"),
            }
        }
    }));
    assert!(outcome.is_ok(), "{what}: the streaming reader panicked");
}

fn line_count(bytes: &[u8]) -> usize {
    1 + bytes.iter().filter(|&&b| b == b'\n').count()
}

#[test]
fn every_error_of_a_mutated_file_names_its_place() {
    let mut totals: BTreeMap<Kind, Tally> = BTreeMap::new();
    let mut failures: Vec<String> = Vec::new();
    for (k, kind) in KINDS.into_iter().enumerate() {
        let dir = scratch(&format!("{kind:?}"));
        let tally = totals.entry(kind).or_default();
        for i in 0..MUTATIONS {
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(12_000 + (k * MUTATIONS + i) as u64);
            let valid = valid_files(kind, &mut rng);
            let case_dir = dir.join(format!("{i}"));
            std::fs::create_dir_all(&case_dir).unwrap();
            // One file mutated; for ViSP, sometimes a file renamed (a second spelling of its
            // index) or removed instead.
            let target = rng.random_range(0..valid.len());
            let mut files = BTreeMap::new();
            let mut written = Vec::new();
            for (j, (name, text)) in valid.iter().enumerate() {
                let mut name = name.clone();
                let mut bytes = text.as_bytes().to_vec();
                if j == target {
                    match (kind, rng.random_range(0..6)) {
                        (Kind::Visp, 0) => name = name.replace('_', "_0").replacen("_0", "_", 1),
                        (Kind::Visp, 1) => continue,
                        _ => bytes = mutate(&bytes, &mut rng),
                    }
                }
                let path = case_dir.join(&name);
                std::fs::write(&path, &bytes).unwrap();
                files.insert(path.display().to_string(), line_count(&bytes));
                written.push((name, bytes));
            }
            if kind == Kind::Visp {
                // A renamed file is a second spelling: keep the original too.
                for (name, text) in &valid {
                    let path = case_dir.join(name);
                    if !path.exists()
                        && written.iter().all(|(n, _)| n != name)
                        && rng.random_bool(0.5)
                    {
                        std::fs::write(&path, text).unwrap();
                        files.insert(path.display().to_string(), line_count(text.as_bytes()));
                    }
                }
                files.insert(case_dir.display().to_string(), 0);
            }
            let path = if kind == Kind::Visp {
                case_dir.clone()
            } else {
                case_dir.join(&written[0].0)
            };
            let what = format!(
                "{kind:?} case {i}: {:?}",
                written
                    .iter()
                    .map(|(n, b)| (n, String::from_utf8_lossy(b)))
                    .collect::<Vec<_>>()
            );
            // Every failing case is reported (the panic hook prints it), not only the first.
            let case = catch_unwind(AssertUnwindSafe(|| {
                read_and_check(kind, &path, &files, tally, &what);
                if matches!(kind, Kind::Jsonl | Kind::Csv) {
                    let format = if kind == Kind::Jsonl {
                        Format::Jsonl
                    } else {
                        Format::Csv
                    };
                    let bytes = &written[0].1;
                    stream_and_check(bytes, format, "-", line_count(bytes), &what);
                }
            }));
            if case.is_err() {
                failures.push(format!("{kind:?} case {i}"));
            }
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
    for (kind, t) in &totals {
        eprintln!(
            "{kind:?}: {} accepted, {} errors on a line, {} whole-file errors, {} I/O errors",
            t.accepted, t.on_a_line, t.whole_file, t.io
        );
        // The mutations must reach the readers' error paths, not only their happy path.
        assert!(
            failures.is_empty(),
            "{} failing cases: {failures:?}",
            failures.len()
        );
        assert!(t.on_a_line > MUTATIONS / 4, "{kind:?}: {t:?}");
    }
}
