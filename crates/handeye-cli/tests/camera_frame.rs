//! Issue 33 item 12: `--camera-frame` naming a frame the recording's tf gives a parent already (an
//! optical frame under `camera_link`). X is still that frame's, but tf gives a frame one parent,
//! so every face that publishes (`--output ros2|urdf|yaml`, the `publish X in tf with:` line, the
//! JSON's `publish`) offers X for the root of the camera's subtree, `X · optical_from_camera_link`,
//! with a warning and the reason, in both setups and in `online`; the truth's X of `camera_link`
//! comes back. A camera placed in the robot's tf already (calibrated before) is compared, not
//! published. `--child-frame` is respected, with a warning when the recording gives it a parent.

#[path = "../../handeye/tests/bags/mod.rs"]
mod bags;
mod common;

use std::path::{Path, PathBuf};

use bags::{BagWriter, Pose, T0_NS, tf};
use common::{run, testdata};
use handeye::Transform;
use nalgebra::{Matrix4, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde_json::Value;
use yaml_rust2::{Yaml, YamlLoader};

const OPTICAL: &str = "camera_color_optical_frame";

/// The noise-free recordings of both setups, with X's parent frame.
const CASES: [(&str, &str, &str); 2] = [
    ("eih_tf_mcap", "eye-in-hand", "tool0"),
    ("eth_tf_sqlite3", "eye-to-hand", "base_link"),
];

fn bag(name: &str) -> String {
    testdata(&format!("rosbag/{name}")).display().to_string()
}

/// A transform of the truth file of recording `name`.
fn truth(name: &str, key: &str) -> Transform {
    let text = std::fs::read_to_string(testdata(&format!("rosbag/{name}.truth.json"))).unwrap();
    let v: Value = serde_json::from_str(&text).unwrap();
    matrix(&v[key])
}

/// A transform from a JSON 4×4 matrix.
fn matrix(v: &Value) -> Transform {
    let rows: Vec<Vec<f64>> = serde_json::from_value(v.clone()).unwrap_or_else(|_| panic!("{v}"));
    handeye::transform_from_matrix4(&Matrix4::from_fn(|i, j| rows[i][j])).unwrap()
}

/// A transform from a translation and an `x, y, z, w` quaternion.
fn from_quaternion(t: [f64; 3], [x, y, z, w]: [f64; 4]) -> Transform {
    let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(w, x, y, z));
    Transform::from_parts(Translation3::new(t[0], t[1], t[2]), q.to_rotation_matrix())
}

fn diff(a: &Transform, b: &Transform) -> f64 {
    (a.to_homogeneous() - b.to_homogeneous()).abs().max()
}

/// `calibrate` on a recording's four frames, `extra` flags after them.
fn calibrate(path: &str, camera: &str, setup: &str, extra: &[&str]) -> (i32, String, String) {
    let mut args = vec![
        "calibrate",
        path,
        "--base-frame",
        "base_link",
        "--gripper-frame",
        "tool0",
        "--camera-frame",
        camera,
        "--target-frame",
        "board",
        "--setup",
        setup,
    ];
    args.extend(extra);
    run(&args)
}

/// The transform and frames (parent, child) of a `static_transform_publisher` line in `text`.
fn published_line(text: &str) -> (Transform, String, String) {
    let line = text
        .lines()
        .find_map(|l| l.find("ros2 run").map(|at| &l[at..]))
        .unwrap_or_else(|| panic!("no publish line: {text}"));
    let words = shlex::split(line).unwrap();
    let value = |flag: &str| {
        let at = words.iter().position(|w| w == flag).unwrap();
        words[at + 1].clone()
    };
    let number = |flag: &str| value(flag).parse::<f64>().unwrap();
    let x = from_quaternion(
        [number("--x"), number("--y"), number("--z")],
        [
            number("--qx"),
            number("--qy"),
            number("--qz"),
            number("--qw"),
        ],
    );
    (x, value("--frame-id"), value("--child-frame-id"))
}

/// An attribute's value in a URDF snippet (`<child link="…"/>`: `attribute(u, "child link")`).
fn attribute<'a>(urdf: &'a str, name: &str) -> &'a str {
    let at = urdf.find(&format!("{name}=\"")).unwrap() + name.len() + 2;
    &urdf[at..at + urdf[at..].find('"').unwrap()]
}

/// The joint of the URDF face: its transform and frames.
fn urdf_joint(urdf: &str) -> (Transform, String, String) {
    let numbers = |name: &str| -> Vec<f64> {
        attribute(urdf, name)
            .split(' ')
            .map(|v| v.parse().unwrap())
            .collect()
    };
    let (t, rpy) = (numbers("xyz"), numbers("rpy"));
    let rotation = Rotation3::from_euler_angles(rpy[0], rpy[1], rpy[2]);
    let x = Transform::from_parts(Translation3::new(t[0], t[1], t[2]), rotation);
    let (parent, child) = (
        attribute(urdf, "parent link"),
        attribute(urdf, "child link"),
    );
    (x, parent.to_string(), child.to_string())
}

/// The transform and the (effector or base, tracking base) frames of the YAML face.
fn yaml_calibration(yaml: &str, setup: &str) -> (Transform, String, String) {
    let doc = &YamlLoader::load_from_str(yaml).unwrap()[0];
    let number = |y: &Yaml| match y {
        Yaml::Real(s) => s.parse::<f64>().unwrap(),
        Yaml::Integer(i) => *i as f64,
        _ => panic!("{y:?}"),
    };
    let (t, r) = (
        &doc["transform"]["translation"],
        &doc["transform"]["rotation"],
    );
    let x = from_quaternion(
        [number(&t["x"]), number(&t["y"]), number(&t["z"])],
        [
            number(&r["x"]),
            number(&r["y"]),
            number(&r["z"]),
            number(&r["w"]),
        ],
    );
    let p = &doc["parameters"];
    let parent = match setup {
        "eye-in-hand" => &p["robot_effector_frame"],
        _ => &p["robot_base_frame"],
    };
    let child = p["tracking_base_frame"].as_str().unwrap().to_string();
    (x, parent.as_str().unwrap().to_string(), child)
}

/// Asserts that a face publishes `expected` from `parent` to `child`.
fn assert_publishes(face: (Transform, String, String), expected: &Transform, frames: [&str; 2]) {
    let (x, parent, child) = face;
    assert_eq!([parent.as_str(), child.as_str()], frames);
    let d = diff(&x, expected);
    assert!(d < 1e-9, "{frames:?}: off by {d:e}");
}

#[test]
fn an_optical_camera_frame_is_warned_and_published_for_camera_link_in_every_face() {
    for (name, setup, parent) in CASES {
        let path = bag(name);
        let root_x = truth(name, &format!("{parent}_from_camera_link"));
        let optical_x = truth(name, &format!("{parent}_from_{OPTICAL}"));
        let (code, out, err) = calibrate(&path, OPTICAL, setup, &["--output", "json"]);
        assert_eq!(code, 0, "{name}: {err}");
        // The warning names the problem, and the publish line says why it is for camera_link.
        for words in [
            format!(
                "warning: {path}: the camera frame `{OPTICAL}` has a parent in tf already (`camera_link` → `{OPTICAL}`), and tf gives a frame one parent: X is found for `{OPTICAL}`; publish it for `camera_link`, the root of the camera's subtree, as {parent}_from_camera_link = X · {OPTICAL}_from_camera_link"
            ),
            format!(
                "publish {parent}_from_camera_link = X · {OPTICAL}_from_camera_link in tf with: ros2 run"
            ),
        ] {
            assert!(err.contains(&words), "{name}: {words}\n---\n{err}");
        }
        assert_publishes(published_line(&err), &root_x, [parent, "camera_link"]);
        // The X reported stays the optical frame's; `publish` gives camera_link's.
        let v: Value = serde_json::from_str(&out).unwrap();
        let d = diff(&matrix(&v["matrix"]), &optical_x);
        assert!(d < 1e-9, "{name}: X off by {d:e}");
        let p = &v["publish"];
        assert_eq!(
            (&p["parent_frame"], &p["child_frame"]),
            (&parent.into(), &"camera_link".into())
        );
        let d = diff(&matrix(&p["matrix"]), &root_x);
        assert!(d < 1e-9, "{name}: publish off by {d:e}");
        let note = p["note"].as_str().unwrap();
        assert!(
            note.contains(&format!(
                "X is published for `camera_link`, the root of the camera's subtree, not for `{OPTICAL}`: tf gives a frame one parent, and the recording's /tf_static gives `{OPTICAL}` one already (`camera_link`); {parent}_from_camera_link = X · {OPTICAL}_from_camera_link, and X itself stays {parent}_from_{OPTICAL}"
            )),
            "{note}"
        );
        // ros2, urdf and yaml publish camera_link's transform, saying why in a comment.
        let face = |output: &str| {
            let (code, out, err) = calibrate(&path, OPTICAL, setup, &["--output", output]);
            assert_eq!(code, 0, "{name} {output}: {err}");
            assert!(err.contains("has a parent in tf already"), "{err}");
            assert!(out.contains("X is published for `camera_link`"), "{out}");
            out
        };
        assert_publishes(
            published_line(&face("ros2")),
            &root_x,
            [parent, "camera_link"],
        );
        assert_publishes(urdf_joint(&face("urdf")), &root_x, [parent, "camera_link"]);
        let yaml = yaml_calibration(&face("yaml"), setup);
        assert_publishes(yaml, &root_x, [parent, "camera_link"]);
    }
}

#[test]
fn camera_link_itself_gives_no_warning_and_the_same_numbers() {
    for (name, setup, parent) in CASES {
        let path = bag(name);
        let (code, out, err) = calibrate(&path, "camera_link", setup, &["--output", "json"]);
        assert_eq!(code, 0, "{err}");
        assert!(
            !err.contains("warning") && !err.contains("a parent"),
            "{err}"
        );
        assert!(err.contains("publish X in tf with: ros2 run"), "{err}");
        let root_x = truth(name, &format!("{parent}_from_camera_link"));
        assert_publishes(published_line(&err), &root_x, [parent, "camera_link"]);
        let v: Value = serde_json::from_str(&out).unwrap();
        assert!(v.get("publish").is_none(), "{out}");
        let (_, ros2, _) = calibrate(&path, "camera_link", setup, &["--output", "ros2"]);
        assert!(!ros2.contains("X is published for"), "{ros2}");
    }
}

#[test]
fn online_publishes_for_camera_link_at_the_end_of_the_recording() {
    for (name, setup, parent) in CASES {
        let path = bag(name);
        let root_x = truth(name, &format!("{parent}_from_camera_link"));
        let face = |output: &str| {
            let (code, out, err) = run(&[
                "online",
                &path,
                "--base-frame",
                "base_link",
                "--gripper-frame",
                "tool0",
                "--camera-frame",
                OPTICAL,
                "--target-frame",
                "board",
                "--setup",
                setup,
                "--output",
                output,
            ]);
            assert_eq!(code, 0, "{name} {output}: {err}");
            assert!(err.contains("warning: ") && err.contains("has a parent in tf already"));
            out
        };
        assert_publishes(
            published_line(&face("ros2")),
            &root_x,
            [parent, "camera_link"],
        );
        assert_publishes(urdf_joint(&face("urdf")), &root_x, [parent, "camera_link"]);
        let yaml = yaml_calibration(&face("yaml"), setup);
        assert_publishes(yaml, &root_x, [parent, "camera_link"]);
    }
}

#[test]
fn a_child_frame_given_is_respected_and_warned_when_the_recording_gives_it_a_parent() {
    let (name, setup, parent) = CASES[0];
    let path = bag(name);
    let optical_x = truth(name, &format!("{parent}_from_{OPTICAL}"));
    let root_x = truth(name, &format!("{parent}_from_camera_link"));
    let given = |child: &str| {
        let (code, _, err) = calibrate(
            &path,
            OPTICAL,
            setup,
            &["--child-frame", child, "--output", "json"],
        );
        assert_eq!(code, 0, "{err}");
        err
    };
    // The optical frame named: published for it, as asked, with the warning.
    let err = given(OPTICAL);
    assert!(
        err.contains(&format!(
            "warning: `{OPTICAL}` has a parent in the recording's tf already (`camera_link`): publishing X for it gives it a second parent"
        )),
        "{err}"
    );
    assert_publishes(published_line(&err), &optical_x, [parent, OPTICAL]);
    // camera_link named: carried there, no second warning.
    let err = given("camera_link");
    assert!(!err.contains("in the recording's tf already"), "{err}");
    assert!(
        err.contains(&format!(
            "publish {parent}_from_camera_link = X · {OPTICAL}_from_camera_link in tf with"
        )),
        "{err}"
    );
    assert_publishes(published_line(&err), &root_x, [parent, "camera_link"]);
    // A name the recording does not have (the camera's on the robot): X as it is.
    let err = given("cam0");
    assert!(err.contains("publish X in tf with"), "{err}");
    assert_publishes(published_line(&err), &optical_x, [parent, "cam0"]);
}

/// `camera_link_from_optical` of the recording written by [`placed_bag`] (a camera driver's).
fn link_from_optical() -> Pose {
    Pose::new(
        Vector3::new(0.01, 0.015, 0.0),
        Vector3::new(-1.2, 1.2, -1.2),
    )
}

/// An eye-in-hand recording (the robot `base_link → tool0` in /tf, the board in /tf under
/// `optical`, whose true X is `bags::true_x`) with `statics` in /tf_static.
fn camera_bag(dir: &Path, statics: &[bags::Tf]) -> PathBuf {
    let path = dir.join("camera.mcap");
    let mut bag = BagWriter::create(&path, false, None);
    let (robot, target) = bags::eye_in_hand(8);
    bags::write_robot(&mut bag, &robot);
    bag.tf_static(statics);
    for (stamp, camera_from_board) in &target {
        bag.tf(&[tf("optical", "board", *stamp, *camera_from_board)]);
    }
    bag.finish();
    path
}

/// The camera placed in the robot's tree already: `tool0 → camera_link → optical` in
/// /tf_static (a calibration made before, 1 mm off the true one along tool0's x).
fn placed_bag(dir: &Path) -> PathBuf {
    let off = Pose::new(Vector3::new(0.001, 0.0, 0.0), Vector3::zeros());
    let tool0_from_link = off * bags::true_x() * link_from_optical().inverse();
    camera_bag(
        dir,
        &[
            tf("tool0", "camera_link", T0_NS, tool0_from_link),
            tf("camera_link", "optical", T0_NS, link_from_optical()),
        ],
    )
}

#[test]
fn a_camera_placed_in_the_robots_tf_already_is_compared_not_published() {
    let dir = tempfile::tempdir().unwrap();
    let path = placed_bag(dir.path());
    let path = path.to_str().unwrap();
    for (camera, chain) in [
        ("optical", "`tool0` → `camera_link` → `optical`"),
        ("camera_link", "`tool0` → `camera_link`"),
    ] {
        let (code, out, err) = calibrate(path, camera, "eye-in-hand", &["--output", "json"]);
        assert_eq!(code, 0, "{camera}: {err}");
        for words in [
            format!(
                "warning: {path}: the camera frame `{camera}` is placed in the robot's tf already ({chain}): the camera was calibrated before, and publishing X beside that transform would give `camera_link` a second parent (tf allows one) or close a loop"
            ),
            "`handeye verify --x SAVED`".to_string(),
            format!(
                "tf's tool0_from_{camera} (the calibration the recording has) is 0.0000° and 1.000 mm from X"
            ),
        ] {
            assert!(err.contains(&words), "{camera}: {words}\n---\n{err}");
        }
        assert!(!err.contains("ros2 run"), "nothing to publish: {err}");
        let v: Value = serde_json::from_str(&out).unwrap();
        let p = &v["publish"];
        assert!(p.get("matrix").is_none(), "{p}");
        let warning = p["warning"].as_str().unwrap();
        assert!(
            warning.contains("the recording's tf places `camera_link` under `tool0` already"),
            "{warning}"
        );
        // A face asked for says so above what it prints.
        let (code, ros2, _) = calibrate(path, camera, "eye-in-hand", &["--output", "ros2"]);
        assert_eq!(code, 0);
        assert!(
            ros2.contains(
                "# warning: the recording's tf places `camera_link` under `tool0` already"
            ),
            "{ros2}"
        );
    }
}

/// The root of the camera's subtree named as no ROS frame may be: it is never printed into a
/// face; nothing is offered, and the warning says to name the frame with `--child-frame`.
#[test]
fn a_root_with_a_name_no_ros_frame_may_have_is_not_printed_into_the_faces() {
    let dir = tempfile::tempdir().unwrap();
    let hostile = "cam\nlink: $(touch /tmp/x)";
    let path = camera_bag(
        dir.path(),
        &[tf(hostile, "optical", T0_NS, link_from_optical())],
    );
    let path = path.to_str().unwrap();
    for output in ["json", "ros2", "urdf", "yaml"] {
        let (code, out, err) = calibrate(path, "optical", "eye-in-hand", &["--output", output]);
        assert_eq!(code, 0, "{output}: {err}");
        assert!(
            !out.contains("$(touch") && !out.contains("cam\nlink"),
            "{output}: {out}"
        );
        assert!(
            out.contains("a frame above it has a name no ROS frame may have"),
            "{output}: {out}"
        );
        assert!(err.contains("name it with --child-frame"), "{err}");
        assert!(!err.contains("ros2 run"), "{err}");
    }
}
