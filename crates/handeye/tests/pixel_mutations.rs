//! A seeded mutation test of the pixel path's readers (issue 59: "a seeded mutation test like the
//! bag readers' for the pixel and intrinsics readers"). The repository's recordings of detections
//! and their intrinsics files are damaged by a seeded generator: a number made absurd (1e308,
//! 1e20, 0, negative), a field dropped, a line doubled or cut, a few characters changed. Then:
//! - the intrinsics reader answers with intrinsics that pass their own check, or refuses with a
//!   parse error naming the file and a line;
//! - the records reader answers, or refuses a record with an error naming the file and its line
//!   (one bad record costs that record);
//! - the calibration on the pixels of the records read is answered or refused, never a panic, and
//!   an answer called `good` is within 5 sigma of the undamaged recording's truth: never a silent
//!   wrong answer.
//!
//! Bounded: 40 mutations of each recording and each intrinsics file.

use std::path::{Path, PathBuf};

use handeye::io::FrameRecording;
use handeye::io::parse_intrinsics;
use handeye::{
    Assessment, Error, Frame, Input, Intrinsics, Method, Options, Problem, Report, Setup,
};
use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

/// Mutations per file.
const MUTATIONS: usize = 40;

/// The recordings on the pixels: (records, intrinsics, truth, setup).
fn recordings() -> Vec<(PathBuf, PathBuf, PathBuf, Setup)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata/pixels");
    [
        ("board_eth", Setup::EyeToHand),
        ("tag_eih", Setup::EyeInHand),
    ]
    .into_iter()
    .map(|(name, setup)| {
        (
            dir.join(format!("{name}.jsonl")),
            dir.join(format!("{name}.intrinsics.yml")),
            dir.join(format!("{name}.truth.json")),
            setup,
        )
    })
    .collect()
}

/// One seeded mutation of a text: a number made absurd, a line doubled, cut or dropped, or a
/// few characters changed.
fn mutate(text: &str, rng: &mut Xoshiro256PlusPlus) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let at = rng.random_range(0..lines.len());
    let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    match rng.random_range(0..5) {
        0 => {
            // A number of the line replaced.
            let line = &out[at];
            let starts: Vec<usize> = line
                .char_indices()
                .filter(|(i, c)| {
                    (c.is_ascii_digit() || *c == '-')
                        && (*i == 0 || !line.as_bytes()[i - 1].is_ascii_alphanumeric())
                        && !line[..*i].ends_with('.')
                })
                .map(|(i, _)| i)
                .collect();
            if let Some(&s) = starts.get(rng.random_range(0..starts.len().max(1))) {
                let end = line[s..]
                    .find(|c: char| !(c.is_ascii_digit() || "+-.eE".contains(c)))
                    .map_or(line.len(), |e| s + e);
                let value = ["1e308", "-1e308", "1e20", "0", "-905", "1e-300", "3.5"]
                    [rng.random_range(0..7)];
                out[at] = format!("{}{value}{}", &line[..s], &line[end..]);
            }
        }
        1 => out.insert(at, out[at].clone()),
        2 => {
            let cut = rng.random_range(0..out[at].len().max(1));
            out[at].truncate(cut);
        }
        3 => {
            out.remove(at);
        }
        _ => {
            let mut bytes = out[at].clone().into_bytes();
            for _ in 0..rng.random_range(1..4) {
                if !bytes.is_empty() {
                    let i = rng.random_range(0..bytes.len());
                    bytes[i] = b" ,:[]{}\"0123456789.-eax"[rng.random_range(0..23)];
                }
            }
            out[at] = String::from_utf8(bytes).unwrap_or_default();
        }
    }
    out.join("\n") + "\n"
}

/// The records read from `text`: the frames of the good ones; each bad one's error must name
/// the file and its line.
fn frames_of(text: &str, file: &str) -> Vec<Frame> {
    let mut frames = Vec::new();
    for record in FrameRecording::records(std::io::Cursor::new(text.as_bytes()), file) {
        match record {
            Ok((_, frame)) => frames.push(frame),
            Err(Error::Parse {
                file: named, line, ..
            }) => assert!(named == file && line >= 1, "{named}:{line}"),
            Err(other) => panic!("a bad record gave {other:?}, not its file and line"),
        }
    }
    frames
}

/// X of a truth file.
fn truth(path: &Path, setup: Setup) -> handeye::Transform {
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    let x = &v[setup.x_frame()];
    let t: Vec<f64> = serde_json::from_value(x["translation"].clone()).unwrap();
    let q: Vec<f64> = serde_json::from_value(x["quaternion_xyzw"].clone()).unwrap();
    let rotation = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
        q[3], q[0], q[1], q[2],
    ));
    handeye::Transform::from_parts(
        nalgebra::Translation3::new(t[0], t[1], t[2]),
        rotation.to_rotation_matrix(),
    )
}

fn options() -> Options {
    Options {
        problem: Problem::HandEye(Method::Reprojection),
        ..Options::default()
    }
}

#[test]
fn damaged_records_are_answered_or_refused_never_a_silent_wrong_x() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(59);
    let (mut good, mut questionable, mut refused) = (0, 0, 0);
    for (records, intrinsics, truth_file, setup) in recordings() {
        let text = std::fs::read_to_string(&records).unwrap();
        let camera: Intrinsics =
            parse_intrinsics(&std::fs::read_to_string(&intrinsics).unwrap(), "i.yml").unwrap();
        let x_true = truth(&truth_file, setup);
        let file = records.file_name().unwrap().to_string_lossy().to_string();
        for i in 0..MUTATIONS {
            let damaged = mutate(&text, &mut rng);
            let frames = frames_of(&damaged, &file);
            let input = Input::Pixels {
                frames: &frames,
                camera: &camera,
            };
            match handeye::calibrate(input, setup, &options()) {
                Ok(Report::HandEye(r)) => {
                    let gap = r.transform.inverse() * x_true;
                    let angle = gap.rotation.angle().to_degrees();
                    let distance = gap.translation.vector.norm();
                    let within = angle <= 5.0 * r.uncertainty.rotation_deg
                        && distance <= 5.0 * r.uncertainty.translation;
                    if r.verdict == Assessment::Good {
                        good += 1;
                        assert!(
                            within,
                            "{file}, mutation {i}: good, but {angle:.4}° and {:.2} mm from the truth (sigma {:.4}°, {:.2} mm)",
                            distance * 1e3,
                            r.uncertainty.rotation_deg,
                            r.uncertainty.translation * 1e3
                        );
                    } else {
                        questionable += 1;
                    }
                }
                Ok(other) => panic!("a hand–eye calibration gave {other:?}"),
                Err(_) => refused += 1,
            }
        }
    }
    println!("pixel records: {good} good, {questionable} questionable, {refused} refused");
    assert_eq!(good + questionable + refused, 2 * MUTATIONS);
    // Most single damages are one bad record or one bad number: the rest still calibrates.
    assert!(good + questionable >= MUTATIONS, "{good} + {questionable}");
}

#[test]
fn damaged_intrinsics_are_read_as_a_camera_or_refused_at_a_line() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(5959);
    let (mut read, mut refused) = (0, 0);
    for (_, intrinsics, _, _) in recordings() {
        let text = std::fs::read_to_string(&intrinsics).unwrap();
        for _ in 0..MUTATIONS {
            let damaged = mutate(&text, &mut rng);
            match parse_intrinsics(&damaged, "c.yml") {
                Ok(camera) => {
                    assert!(camera.check().is_ok(), "{camera:?}");
                    read += 1;
                }
                Err(Error::Parse { file, line, .. }) => {
                    let lines = damaged.lines().count();
                    assert!(file == "c.yml" && line <= lines + 1, "{file}:{line}");
                    refused += 1;
                }
                Err(other) => panic!("{other:?}"),
            }
        }
    }
    println!("intrinsics: {read} read, {refused} refused");
    assert!(refused > 0 && read > 0);
}

/// The readers read line by line: a record cut in the middle of a line is that line's error.
#[test]
fn a_record_cut_short_costs_its_line() {
    let (records, ..) = &recordings()[0];
    let text = std::fs::read_to_string(records).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let cut = lines[4].len() / 2;
    lines[4].truncate(cut);
    let damaged = lines.join("\n") + "\n";
    let reader = std::io::Cursor::new(damaged.as_bytes());
    let bad: Vec<usize> = FrameRecording::records(reader, "r.jsonl")
        .filter_map(|r| match r {
            Err(Error::Parse { line, .. }) => Some(line),
            _ => None,
        })
        .collect();
    assert_eq!(bad, vec![5]);
    assert_eq!(
        frames_of(&damaged, "r.jsonl").len(),
        text.lines().count() - 1
    );
}
