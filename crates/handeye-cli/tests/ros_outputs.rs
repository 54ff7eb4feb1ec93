//! The ROS outputs (`calibrate|online --output yaml|ros2|urdf`, and the `publish X in tf with:`
//! line for recordings) are safe, load where users put them and are in metres (issue 34 item 1,
//! issue 33 items 8 and 9): frame names a ROS frame may not have are refused naming the flag; the
//! legal ones come back verbatim through a YAML parser, an XML parser, a shell-word splitter and
//! Python's literal reader; the YAML has exactly easy_handeye2's keys; millimetres become metres.

mod common;
use common::{run, testdata};

use quick_xml::XmlVersion;
use quick_xml::events::Event;
use serde_json::Value;
use yaml_rust2::{Yaml, YamlLoader};

const NOISY: &str = "opencv/opencv_eye-in-hand_noisy_10_12.jsonl";
/// A recording: its frames base_link, tool0, camera_link (camera_color_optical_frame), board.
const BAG: &str = "rosbag/eih_tf_mcap";
/// A pose-pair file in millimetres.
const MM: &str = "paper/series_2007_000_200.jsonl";

fn path(rel: &str) -> String {
    testdata(rel).to_str().unwrap().to_string()
}

/// An eye-to-hand recording with the same frames.
const BAG_EYE_TO_HAND: &str = "rosbag/eth_tf_noisy_sqlite3";

/// The recording's four frame flags, `flag` set to `value` (as `--flag=value`, so that a value
/// starting with `-` is a value).
fn bag_args(flag: &str, value: &str) -> Vec<String> {
    bag_of(BAG, flag, value)
}

fn bag_of(bag: &str, flag: &str, value: &str) -> Vec<String> {
    let mut args = vec![path(bag)];
    for (f, v) in [
        ("--base-frame", "base_link"),
        ("--gripper-frame", "tool0"),
        ("--camera-frame", "camera_link"),
        ("--target-frame", "board"),
    ] {
        args.push(format!("{f}={}", if f == flag { value } else { v }));
    }
    args
}

fn run_owned(args: &[String]) -> (i32, String, String) {
    run(&args.iter().map(String::as_str).collect::<Vec<_>>())
}

/// Names no ROS frame may have: each refused, whatever the flag and the face.
const REFUSED: &[&str] = &[
    "base\nfoo: bar",
    "base\n",
    "~",
    "#x",
    "*a",
    "&a",
    "a: b",
    "\"",
    "<link name=\"x\"/>",
    "base link",
    ";rm -rf ~",
    "$(touch /tmp/pwned)",
    "`touch /tmp/pwned`",
    "a'b",
    "1abc",
    "-x",
    "",
    "/",
];

#[test]
fn frame_names_no_ros_frame_may_have_are_refused_naming_the_flag() {
    for name in REFUSED {
        for flag in [
            "--base-frame",
            "--gripper-frame",
            "--camera-frame",
            "--target-frame",
        ] {
            for (command, face) in [
                ("calibrate", "urdf"),
                ("calibrate", "json"),
                ("online", "yaml"),
            ] {
                let mut args = vec![command.to_string()];
                args.extend(bag_args(flag, name));
                args.extend(["--output".into(), face.into()]);
                let (code, out, err) = run_owned(&args);
                assert_eq!(code, 2, "{args:?}: {err}");
                assert!(out.is_empty(), "{args:?}: {out}");
                assert!(err.contains(flag), "{args:?}: {err}");
                assert!(!err.contains("publish X"), "{args:?}: {err}");
            }
        }
        for flag in ["--parent-frame", "--child-frame"] {
            for face in ["yaml", "ros2", "urdf"] {
                let args = [
                    "calibrate".into(),
                    path(NOISY),
                    format!("{flag}={name}"),
                    "--output".into(),
                    face.into(),
                ];
                let (code, out, err) = run_owned(&args);
                assert_eq!(code, 2, "{args:?}: {err}");
                assert!(out.is_empty(), "{args:?}: {out}");
                assert!(err.contains(flag), "{args:?}: {err}");
            }
        }
    }
    // The message names the character, a control character by its code point.
    let (_, _, err) = run(&[
        "calibrate",
        &path(NOISY),
        "--child-frame",
        "cam\nera",
        "--output",
        "urdf",
    ]);
    assert!(err.contains("U+000A (a newline)"), "{err}");
    let (_, _, err) = run(&[
        "calibrate",
        &path(NOISY),
        "--parent-frame",
        "a;b",
        "--output",
        "ros2",
    ]);
    assert!(err.contains("`;`"), "{err}");
}

/// easy_handeye2's own reading of the YAML (PyYAML's `full_load`, YAML 1.1, where `yes` and `on`
/// are booleans unless quoted), as JSON, when python3 with PyYAML is there.
fn pyyaml(yaml: &str) -> Option<Value> {
    let out = std::process::Command::new("python3")
        .args([
            "-c",
            "import json, sys, yaml; print(json.dumps(yaml.full_load(sys.argv[1])))",
            yaml,
        ])
        .output()
        .ok()?;
    out.status
        .success()
        .then(|| serde_json::from_slice(&out.stdout).unwrap())
}

/// The faces of one calibration: (yaml, ros2, urdf) and the JSON's X.
fn faces(args: &[&str]) -> (Yaml, String, String, Value) {
    let face = |name: &str| {
        let mut all = vec!["calibrate"];
        all.extend(args);
        all.extend(["--output", name]);
        let (code, out, err) = run(&all);
        assert_eq!(code, 0, "{all:?}: {err}");
        out
    };
    let yaml = face("yaml");
    if let Some(v) = pyyaml(&yaml) {
        let p = &v["parameters"];
        let parent_key = if p["calibration_type"] == "eye_in_hand" {
            "robot_effector_frame"
        } else {
            "robot_base_frame"
        };
        let expected: Vec<&str> = args
            .windows(2)
            .filter(|w| w[0] == "--parent-frame" || w[0] == "--child-frame")
            .map(|w| w[1].trim_start_matches('/'))
            .collect();
        if let [parent, child] = expected[..] {
            assert_eq!(p[parent_key], parent, "{yaml}");
            assert_eq!(p["tracking_base_frame"], child, "{yaml}");
        }
        assert!(v["transform"]["translation"]["x"].is_f64(), "{yaml}");
    }
    let mut docs = YamlLoader::load_from_str(&yaml).unwrap_or_else(|e| panic!("{e}: {yaml}"));
    assert_eq!(docs.len(), 1, "{yaml}");
    let json: Value = serde_json::from_str(&face("json")).unwrap();
    (docs.remove(0), face("ros2"), face("urdf"), json)
}

/// The keys of a YAML mapping, in order.
fn keys(y: &Yaml) -> Vec<String> {
    y.as_hash()
        .unwrap_or_else(|| panic!("not a mapping: {y:?}"))
        .keys()
        .map(|k| k.as_str().unwrap().to_string())
        .collect()
}

fn f64_of(y: &Yaml) -> f64 {
    match y {
        Yaml::Real(s) => s.parse().unwrap(),
        Yaml::Integer(i) => *i as f64,
        _ => panic!("not a number: {y:?}"),
    }
}

/// The attributes of the elements of a URDF snippet, parsed with an XML reader:
/// (element, [(name, unescaped value)]).
fn xml_elements(urdf: &str) -> Vec<(String, Vec<(String, String)>)> {
    let mut reader = quick_xml::Reader::from_str(urdf);
    let mut out = Vec::new();
    loop {
        match reader
            .read_event()
            .unwrap_or_else(|e| panic!("{e}: {urdf}"))
        {
            Event::Start(e) | Event::Empty(e) => {
                let name = e.name().into_inner().to_string();
                let attributes = e
                    .attributes()
                    .map(|a| {
                        let a = a.unwrap();
                        (
                            a.key.into_inner().to_string(),
                            a.normalized_value(XmlVersion::Implicit1_0)
                                .unwrap()
                                .into_owned(),
                        )
                    })
                    .collect();
                out.push((name, attributes));
            }
            Event::Eof => break,
            _ => {}
        }
    }
    out
}

fn attribute<'a>(
    elements: &'a [(String, Vec<(String, String)>)],
    element: &str,
    name: &str,
) -> &'a str {
    let (_, attributes) = elements
        .iter()
        .find(|(e, _)| e == element)
        .unwrap_or_else(|| panic!("no <{element}>"));
    &attributes.iter().find(|(a, _)| a == name).unwrap().1
}

/// The `ros2 run` line of the ros2 face, split as a POSIX shell splits it.
fn argv(ros2: &str) -> Vec<String> {
    let line = ros2.lines().find(|l| l.starts_with("ros2 run")).unwrap();
    shlex::split(line).unwrap_or_else(|| panic!("not shell words: {line}"))
}

/// The Python launch snippet's `arguments` list and `name`, read by Python's literal reader when
/// python3 is there, else by a JSON parser (the literals are JSON strings).
fn launch(ros2: &str) -> (Vec<String>, String) {
    let start = ros2.find("arguments=[").unwrap() + "arguments=".len();
    let end = start + ros2[start..].find("\n    ],").unwrap() + "\n    ]".len();
    let list = ros2[start..end].replace(",\n    ]", "\n    ]");
    let name_at = ros2.find("name=").unwrap() + "name=".len();
    let name = &ros2[name_at..name_at + ros2[name_at..].find(",\n").unwrap()];
    let from_json = |text: &str| -> Value { serde_json::from_str(text).unwrap() };
    let python = std::process::Command::new("python3")
        .args([
            "-c",
            "import ast, json, sys; print(json.dumps([ast.literal_eval(sys.argv[1]), ast.literal_eval(sys.argv[2])]))",
            &ros2[start..end],
            name,
        ])
        .output();
    let (list, name) = match python {
        Ok(out) if out.status.success() => {
            let v = from_json(&String::from_utf8(out.stdout).unwrap());
            (v[0].clone(), v[1].clone())
        }
        _ => (from_json(&list), from_json(name)),
    };
    (
        list.as_array()
            .unwrap()
            .iter()
            .map(|a| a.as_str().unwrap().to_string())
            .collect(),
        name.as_str().unwrap().to_string(),
    )
}

/// Checks every face of one run carries `parent` and `child` verbatim and X as the JSON gives it
/// (times `scale`).
fn check_faces(args: &[&str], parent: &str, child: &str, scale: f64) -> Yaml {
    let (yaml, ros2, urdf, json) = faces(args);
    let t: Vec<f64> = json["translation"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap() * scale)
        .collect();
    let q: Vec<f64> = json["quaternion_xyzw"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1e-3);

    // YAML: exactly easy_handeye2's keys (its HandeyeCalibration message).
    assert_eq!(keys(&yaml), ["parameters", "transform"], "{yaml:?}");
    assert_eq!(
        keys(&yaml["parameters"]),
        [
            "name",
            "calibration_type",
            "robot_base_frame",
            "robot_effector_frame",
            "tracking_base_frame",
            "tracking_marker_frame",
            "freehand_robot_movement",
            "move_group_namespace",
            "move_group",
        ]
    );
    assert_eq!(keys(&yaml["transform"]), ["translation", "rotation"]);
    assert_eq!(keys(&yaml["transform"]["translation"]), ["x", "y", "z"]);
    assert_eq!(keys(&yaml["transform"]["rotation"]), ["x", "y", "z", "w"]);
    let p = &yaml["parameters"];
    let parent_key = if p["calibration_type"].as_str() == Some("eye_in_hand") {
        "robot_effector_frame"
    } else {
        "robot_base_frame"
    };
    assert_eq!(p[parent_key].as_str(), Some(parent), "{yaml:?}");
    assert_eq!(p["tracking_base_frame"].as_str(), Some(child), "{yaml:?}");
    assert_eq!(p["freehand_robot_movement"].as_bool(), Some(true));
    for (k, v) in ["x", "y", "z"].iter().zip(&t) {
        assert!(
            close(f64_of(&yaml["transform"]["translation"][*k]), *v),
            "{k}: {yaml:?}"
        );
    }
    for (k, v) in ["x", "y", "z", "w"].iter().zip(&q) {
        assert!(
            close(f64_of(&yaml["transform"]["rotation"][*k]), *v),
            "{k}: {yaml:?}"
        );
    }

    // The shell line: the argv static_transform_publisher gets.
    let words = argv(&ros2);
    let mut expected: Vec<String> = ["ros2", "run", "tf2_ros", "static_transform_publisher"]
        .map(String::from)
        .into();
    for (flag, v) in ["--x", "--y", "--z", "--qx", "--qy", "--qz", "--qw"]
        .iter()
        .zip(t.iter().chain(&q))
    {
        let at = words.iter().position(|w| w == flag).unwrap();
        assert!(
            close(words[at + 1].parse().unwrap(), *v),
            "{flag}: {words:?}"
        );
        expected.extend([flag.to_string(), words[at + 1].clone()]);
    }
    expected.extend(["--frame-id", parent, "--child-frame-id", child].map(String::from));
    assert_eq!(words, expected);

    // The launch snippet: the same arguments as Python reads them.
    let (arguments, name) = launch(&ros2);
    assert_eq!(arguments, words[4..], "{ros2}");
    assert!(
        name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_'),
        "a node name: {name}"
    );

    // The URDF, as an XML reader reads it.
    let elements = xml_elements(&urdf);
    assert_eq!(attribute(&elements, "parent", "link"), parent, "{urdf}");
    assert_eq!(attribute(&elements, "child", "link"), child, "{urdf}");
    assert_eq!(attribute(&elements, "joint", "type"), "fixed", "{urdf}");
    let xyz: Vec<f64> = attribute(&elements, "origin", "xyz")
        .split(' ')
        .map(|v| v.parse().unwrap())
        .collect();
    for (a, b) in xyz.iter().zip(&t) {
        assert!(close(*a, *b), "{urdf}");
    }
    yaml
}

#[test]
fn legal_names_come_back_verbatim_through_each_language() {
    let noisy = path(NOISY);
    // Words YAML would read as a boolean, a null or a number unless quoted; a namespaced frame.
    for (parent, child) in [
        ("yes", "null"),
        ("on", "No"),
        ("y", "true"),
        ("ur5e/tool0", "cam.era-1_x"),
        ("_private", "Null"),
    ] {
        check_faces(
            &[&noisy, "--parent-frame", parent, "--child-frame", child],
            parent,
            child,
            1.0,
        );
    }
    // A leading `/` is dropped, as tf2 and the recording's reader do.
    check_faces(
        &[&noisy, "--parent-frame", "/tool0", "--child-frame", "/cam"],
        "tool0",
        "cam",
        1.0,
    );
}

#[test]
fn a_leading_slash_names_the_frame_the_recording_reader_keys() {
    let bag = |flag: &str, value: &str, setup: &str| {
        let recording = if setup == "eye-in-hand" {
            BAG
        } else {
            BAG_EYE_TO_HAND
        };
        let mut a = bag_of(recording, flag, value);
        a.extend(["--setup".into(), setup.into()]);
        a
    };
    for (setup, flag, frame) in [
        ("eye-in-hand", "--gripper-frame", "tool0"),
        ("eye-in-hand", "--camera-frame", "camera_link"),
        ("eye-to-hand", "--base-frame", "base_link"),
    ] {
        let plain = bag(flag, frame, setup);
        let slashed = bag(flag, &format!("/{frame}"), setup);
        for face in ["json", "yaml", "ros2", "urdf"] {
            let with = |args: &[String]| {
                let mut all = vec!["calibrate".to_string()];
                all.extend(args.iter().cloned());
                all.extend(["--output".into(), face.into()]);
                run_owned(&all)
            };
            let (code, a, err_a) = with(&plain);
            assert_eq!(code, 0, "{err_a}");
            let (code, b, err_b) = with(&slashed);
            assert_eq!(code, 0, "{err_b}");
            // The reader read the same frames; the faces name them the same.
            assert_eq!(a, b, "{setup} {flag} /{frame} --output {face}");
            assert_eq!(err_a, err_b, "{setup} {flag} /{frame} --output {face}");
        }
        let mut args: Vec<&str> = slashed.iter().map(String::as_str).collect();
        args.insert(0, "calibrate");
        let (_, _, err) = run(&args);
        let line = err
            .lines()
            .find_map(|l| l.strip_prefix("publish X in tf with: "))
            .unwrap();
        let words = shlex::split(line).unwrap();
        let at = |f: &str| &words[words.iter().position(|w| w == f).unwrap() + 1];
        let (parent, child) = match setup {
            "eye-in-hand" => ("tool0", "camera_link"),
            _ => ("base_link", "camera_link"),
        };
        assert_eq!(
            (at("--frame-id").as_str(), at("--child-frame-id").as_str()),
            (parent, child)
        );
    }
}

#[test]
fn the_yaml_has_easy_handeye2s_keys_and_the_name() {
    let noisy = path(NOISY);
    let yaml = check_faces(&[&noisy, "--name", "cell_3-left"], "gripper", "camera", 1.0);
    assert_eq!(yaml["parameters"]["name"].as_str(), Some("cell_3-left"));
    let (code, out, _) = run(&["calibrate", &noisy, "--output", "yaml"]);
    assert_eq!(code, 0);
    let doc = &YamlLoader::load_from_str(&out).unwrap()[0];
    assert_eq!(doc["parameters"]["name"].as_str(), Some("handeye"));
    // handeye's own fields are comments.
    assert!(
        out.contains("\n# frame: gripper_from_camera (gripper -> camera)"),
        "{out}"
    );
    assert!(out.contains("# uncertainty (one sigma): "), "{out}");
    for name in ["../x", "a b", "", "-a", "a/b", "a\nb"] {
        let (code, out, err) = run(&[
            "calibrate",
            &noisy,
            &format!("--name={name}"),
            "--output",
            "yaml",
        ]);
        assert_eq!(code, 2, "{name:?}: {err}");
        assert!(out.is_empty());
        assert!(err.contains("--name"), "{err}");
    }
    // online writes the same layout.
    let (code, out, err) = run(&[
        "online",
        &path(MM),
        "--estimator",
        "accumulate",
        "--name",
        "cell",
        "--output",
        "yaml",
    ]);
    assert_eq!(code, 0, "{err}");
    let doc = &YamlLoader::load_from_str(&out).unwrap()[0];
    assert_eq!(keys(doc), ["parameters", "transform"]);
    assert_eq!(doc["parameters"]["name"].as_str(), Some("cell"));
}

#[test]
fn millimetres_are_published_in_metres() {
    let mm = path(MM);
    // The JSON and the text stay in the input's unit.
    let (code, text, _) = run(&["calibrate", &mm, "--output", "text"]);
    assert_eq!(code, 0);
    assert!(text.contains("] mm"), "{text}");
    assert!(!text.contains("divide"), "{text}");
    check_faces(&[&mm], "gripper", "camera", 1e-3);
    for face in ["yaml", "ros2", "urdf"] {
        let (code, out, err) = run(&["calibrate", &mm, "--output", face]);
        assert_eq!(code, 0, "{err}");
        assert!(
            err.contains("translation converted from millimetres to metres for ROS"),
            "{err}"
        );
        assert!(!err.contains("divide"), "{err}");
        if face == "yaml" {
            assert!(
                out.contains("translation in metres (converted from millimetres)"),
                "{out}"
            );
        }
    }
    // online: the last X, in metres.
    let (code, json, err) = run(&[
        "online",
        &mm,
        "--estimator",
        "accumulate",
        "--output",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    let last: Value =
        serde_json::from_str(json.lines().rfind(|l| !l.contains("\"change\"")).unwrap()).unwrap();
    let (code, urdf, err) = run(&[
        "online",
        &mm,
        "--estimator",
        "accumulate",
        "--output",
        "urdf",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("converted from millimetres to metres"),
        "{err}"
    );
    let elements = xml_elements(&urdf);
    let xyz: Vec<f64> = attribute(&elements, "origin", "xyz")
        .split(' ')
        .map(|v| v.parse().unwrap())
        .collect();
    for (a, b) in xyz.iter().zip(last["translation"].as_array().unwrap()) {
        let b = b.as_f64().unwrap() / 1000.0;
        assert!((a - b).abs() <= 1e-12 * b.abs().max(1e-3), "{urdf}");
    }
}

#[test]
fn hard_inputs_through_the_ros_outputs_keep_their_verdicts() {
    let files = [
        "kinhec/pairs/degenerate_single_joint_continuous_eih_s0.jsonl",
        "kinhec/pairs/degenerate_parallel_axes_continuous_eih_s0.jsonl",
        "kinhec/mistakes/camera_inverted__nominal_stations_eih_s0.jsonl",
        "kinhec/mistakes/robot_inverted__nominal_stations_eih_s0.jsonl",
        "kinhec/mistakes/robot_mm__nominal_stations_eih_s0.jsonl",
        "kinhec/mistakes/typo_x1000__nominal_stations_eih_s0.jsonl",
        "kinhec/mistakes/huge_1e308__nominal_stations_eih_s0.jsonl",
    ];
    let mut outliers: Vec<String> = std::fs::read_dir(testdata("kinhec/pairs"))
        .unwrap()
        .map(|e| e.unwrap().path().to_str().unwrap().to_string())
        .filter(|p| p.contains("outlier") && p.ends_with(".jsonl"))
        .collect();
    outliers.sort();
    outliers.truncate(2);
    let mut inputs: Vec<String> = files
        .iter()
        .map(|f| path(f))
        .filter(|p| std::path::Path::new(p).exists())
        .collect();
    inputs.extend(outliers);
    assert!(inputs.len() >= 6, "{inputs:?}");
    for input in &inputs {
        for extra in [&[][..], &["--fix", "auto"][..], &["--reject-outliers"][..]] {
            let mut base = vec!["calibrate", input.as_str()];
            base.extend(extra);
            let mut json_args = base.clone();
            json_args.extend(["--output", "json"]);
            let (json_code, _, _) = run(&json_args);
            for face in ["yaml", "ros2", "urdf"] {
                let mut args = base.clone();
                args.extend(["--output", face]);
                let (code, out, err) = run(&args);
                // No panic (`run` checks), and the same verdict as the JSON's.
                assert_eq!(code, json_code, "{args:?}: {err}");
                if code == 0 {
                    match face {
                        "yaml" => {
                            YamlLoader::load_from_str(&out).unwrap();
                        }
                        "urdf" => {
                            xml_elements(&out);
                        }
                        _ => {
                            argv(&out);
                        }
                    }
                } else {
                    assert!(out.is_empty(), "{args:?}: {out}");
                }
            }
        }
    }
}

/// The `ros2 run` lines of a ros2 face, each split as a POSIX shell splits it.
fn argvs(ros2: &str) -> Vec<Vec<String>> {
    ros2.lines()
        .filter(|l| l.starts_with("ros2 run"))
        .map(|l| shlex::split(l).unwrap_or_else(|| panic!("not shell words: {l}")))
        .collect()
}

/// The value after `flag` in a split `ros2 run` line.
fn after(argv: &[String], flag: &str) -> String {
    argv[argv.iter().position(|a| a == flag).unwrap() + 1].clone()
}

#[test]
fn robot_world_publishes_x_and_the_target_in_metres_in_every_ros_face() {
    // A recording in millimetres (OpenCV's test data is in metres; the paper's series in mm).
    let (mm, metres) = (path(MM), path(NOISY));
    for (file, scale) in [(&metres, 1.0), (&mm, 1e-3)] {
        let args = ["calibrate", "--robot-world", file.as_str()];
        let (code, out, err) = run(&[&args[..], &["--output", "json"]].concat());
        assert_eq!(code, 0, "{err}");
        let json: Value = serde_json::from_str(&out).unwrap();
        assert!(["good", "questionable"].contains(&json["verdict"].as_str().unwrap()));
        let x = &json["translation"];
        let target = &json["target"]["translation"];
        // ros2: two publisher lines, X then the target, frames as the setup names them.
        let (code, ros2, err) = run(&[&args[..], &["--output", "ros2"]].concat());
        assert_eq!(code, 0, "{err}");
        let lines = argvs(&ros2);
        assert_eq!(lines.len(), 2, "{ros2}");
        // Two launch nodes under two names: both can be pasted into one launch file.
        assert!(
            ros2.contains("\nhandeye_tf = Node(") && ros2.contains("\nhandeye_target_tf = Node(")
        );
        for (argv, (parent, child), t) in [
            (&lines[0], ("gripper", "camera"), x),
            (&lines[1], ("base", "target"), target),
        ] {
            assert_eq!(after(argv, "--frame-id"), parent);
            assert_eq!(after(argv, "--child-frame-id"), child);
            for (k, flag) in ["--x", "--y", "--z"].iter().enumerate() {
                let published: f64 = after(argv, flag).parse().unwrap();
                let given = t[k].as_f64().unwrap() * scale;
                assert!(
                    (published - given).abs() < 1e-12,
                    "{flag}: {published} vs {given}"
                );
            }
        }
        // urdf: two fixed joints, read back by an XML reader.
        let (code, urdf, err) = run(&[&args[..], &["--output", "urdf"]].concat());
        assert_eq!(code, 0, "{err}");
        let elements = xml_elements(&urdf);
        let joints: Vec<&str> = elements
            .iter()
            .filter(|(e, _)| e == "joint")
            .map(|(_, a)| a.iter().find(|(k, _)| k == "name").unwrap().1.as_str())
            .collect();
        assert_eq!(joints, ["gripper_to_camera", "base_to_target"], "{urdf}");
        let origins: Vec<&str> = elements
            .iter()
            .filter(|(e, _)| e == "origin")
            .map(|(_, a)| a.iter().find(|(k, _)| k == "xyz").unwrap().1.as_str())
            .collect();
        let z: f64 = origins[1].split(' ').nth(2).unwrap().parse().unwrap();
        assert!((z - target[2].as_f64().unwrap() * scale).abs() < 1e-12);
        // text: both transforms, the verdict and the uncertainty of both.
        let (code, text, err) = run(&[&args[..], &["--output", "text"]].concat());
        assert_eq!(code, 0, "{err}");
        assert!(
            text.contains("X = gripper_from_camera") && text.contains("Target = base_from_target")
        );
        assert!(text.contains(&format!("Verdict: {}", json["verdict"].as_str().unwrap())));
        assert!(text.contains("target rotation"), "{text}");
    }
}

#[test]
fn robot_world_strict_exits_5_on_a_questionable_verdict() {
    let outliers = path("kinhec/pairs/outliers_gross_stations_eih_s0.jsonl");
    let clean = path("kinhec/pairs/nominal_stations_eih_s1.jsonl");
    for (file, verdict, code) in [(&outliers, "questionable", 5), (&clean, "good", 0)] {
        let (plain, out, err) = run(&["calibrate", "--robot-world", file, "--output", "json"]);
        assert_eq!(plain, 0, "{err}");
        let json: Value = serde_json::from_str(&out).unwrap();
        assert_eq!(json["verdict"], verdict);
        let (strict, _, err) = run(&[
            "calibrate",
            "--robot-world",
            file,
            "--output",
            "json",
            "--strict",
        ]);
        assert_eq!(strict, code, "{err}");
    }
}
