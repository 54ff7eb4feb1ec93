//! Python bindings of handeye (module `handeye._handeye`; the public face is the `handeye` Python
//! package beside it, which converts OpenCV-style inputs).
//!
//! Conventions: `base_from_gripper` (OpenCV `gripper2base`), `camera_from_target` (`target2cam`),
//! X = `gripper_from_camera` (`cam2gripper`) for eye-in-hand, `base_from_camera` for eye-to-hand.

use std::path::PathBuf;

use handeye::io::rosbag::BagTags;
use handeye::io::{
    BagFrames, CameraMount, Format, FrameRecording, Recording, RecordingOptions, Source, TimeOffset,
};
use handeye::transform_from_matrix4;
use handeye::{AlphaMin, OnlineCalibrator, OnlineSettings, Outputs, Record, Tell, Unit};
use handeye::{Method, Pairing, PosePair, Setup, Transform};
use nalgebra::{Matrix3, Matrix4, Vector3};
use numpy::{
    IntoPyArray, PyArray2, PyArrayMethods, PyReadonlyArray2, PyReadonlyArray3, PyReadonlyArrayDyn,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};

/// A library error as a Python `ValueError` with the library's message.
fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// A reading error, with the call that reads the line in Python's words where the library leaves
/// the wording to the face (a record with `detections` alone: [`handeye::Remedy::Pixels`]).
fn read_error(e: handeye::Error) -> PyErr {
    match e.remedy() {
        Some(handeye::Remedy::Pixels) => value_error(format!(
            "{e}; pass `intrinsics=FILE` {}: calibrate_on_pixels(path, intrinsics=FILE), or OnlineCalibrator(intrinsics=FILE) online",
            handeye::Remedy::Pixels.purpose()
        )),
        _ => value_error(e),
    }
}

/// A 4×4 transform from a numpy view, refusing non-rigid ones with `what` in the message.
fn transform(m: ndarray_view::View<'_>, what: &str) -> PyResult<Transform> {
    rigid(m).map_err(|p| value_error(format!("{what}: {p}")))
}

/// [`transform`] of the `k`-th pose, named `what[k]` (the name is made only for a message).
fn transform_at(m: ndarray_view::View<'_>, what: &str, k: usize) -> PyResult<Transform> {
    rigid(m).map_err(|p| value_error(format!("{what}[{k}]: {p}")))
}

/// A 4×4 view as a rigid transform, or what is wrong with it.
fn rigid(m: ndarray_view::View<'_>) -> Result<Transform, String> {
    if m.shape() != [4, 4] {
        return Err(format!("expected a 4×4 array, got shape {:?}", m.shape()));
    }
    let mat = Matrix4::from_fn(|r, c| m[[r, c]]);
    transform_from_matrix4(&mat).map_err(|p| p.to_string())
}

mod opencv_words;

mod ndarray_view {
    /// A 4×4 view of a numpy array.
    pub type View<'a> = numpy::ndarray::ArrayView2<'a, f64>;
}

/// Pose pairs from (N, 4, 4) arrays of `base_from_gripper` and `camera_from_target`.
fn poses(
    base_from_gripper: &PyReadonlyArray3<'_, f64>,
    camera_from_target: &PyReadonlyArray3<'_, f64>,
) -> PyResult<Vec<PosePair>> {
    let (g, c) = (base_from_gripper.as_array(), camera_from_target.as_array());
    if g.shape() != c.shape() || g.shape()[1..] != [4, 4] {
        return Err(value_error(format!(
            "expected two (N, 4, 4) arrays of the same N, got {:?} and {:?}",
            g.shape(),
            c.shape()
        )));
    }
    (0..g.shape()[0])
        .map(|k| {
            Ok(PosePair {
                base_from_gripper: transform_at(
                    g.index_axis(numpy::ndarray::Axis(0), k),
                    "base_from_gripper",
                    k,
                )?,
                camera_from_target: transform_at(
                    c.index_axis(numpy::ndarray::Axis(0), k),
                    "camera_from_target",
                    k,
                )?,
            })
        })
        .collect()
}

fn matrix<'py>(py: Python<'py>, x: &Transform) -> Bound<'py, PyArray2<f64>> {
    let h = x.to_homogeneous();
    numpy::ndarray::Array2::from_shape_fn((4, 4), |(r, c)| h[(r, c)]).into_pyarray(py)
}

/// X alone, as `calibrate_hand_eye` (the OpenCV drop-in) returns it: the 4×4 matrix. All pairs
/// are made on the fly (memory O(poses)).
#[pyfunction]
#[pyo3(signature = (base_from_gripper, camera_from_target, method="andreff", setup="eye-in-hand", pairs="consecutive", tsai_opencv_filter=false))]
fn solve_x<'py>(
    py: Python<'py>,
    base_from_gripper: PyReadonlyArray3<'py, f64>,
    camera_from_target: PyReadonlyArray3<'py, f64>,
    method: &str,
    setup: &str,
    pairs: &str,
    tsai_opencv_filter: bool,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let options = calibration_options(method, pairs, tsai_opencv_filter)?;
    let setup = parse_setup(setup)?;
    let poses = poses(&base_from_gripper, &camera_from_target)?;
    // As `handeye::calibrate` solves X before its checks.
    let c = py
        .allow_threads(|| options.solve(&poses, setup))
        .map_err(value_error)?;
    Ok(matrix(py, &c.x))
}

/// X alone from OpenCV's arguments, as `calibrate_hand_eye` (the OpenCV drop-in) returns it:
/// `(R_cam2gripper (3, 3), t_cam2gripper (3, 1))`. Rotations are (N, 3, 3) matrices or (N, 3)
/// rotation vectors, translations (N, 3); every pose pair is a motion (made on the fly, memory
/// O(poses)), read as eye-in-hand unless `setup` says otherwise ([`solve_opencv_poses`]). The
/// whole conversion is here, not in numpy: at ten poses numpy's per-call cost on small arrays was
/// twice the solve.
#[pyfunction]
#[pyo3(signature = (r_gripper2base, t_gripper2base, r_target2cam, t_target2cam, method="tsai", tsai_opencv_filter=false, setup=None))]
// OpenCV's four arrays, then the drop-in's keywords: the signature Python sees.
#[allow(clippy::too_many_arguments)]
fn solve_opencv<'py>(
    py: Python<'py>,
    r_gripper2base: PyReadonlyArrayDyn<'py, f64>,
    t_gripper2base: PyReadonlyArray2<'py, f64>,
    r_target2cam: PyReadonlyArrayDyn<'py, f64>,
    t_target2cam: PyReadonlyArray2<'py, f64>,
    method: &str,
    tsai_opencv_filter: bool,
    setup: Option<&str>,
) -> PyResult<RotationTranslation<'py>> {
    let robot = transforms(&r_gripper2base, &t_gripper2base, "base_from_gripper")?;
    let camera = transforms(&r_target2cam, &t_target2cam, "camera_from_target")?;
    solve_opencv_poses(py, robot, camera, method, tsai_opencv_filter, setup)
}

/// X from OpenCV's two sides, decided as `handeye calibrate --method M --pairs all` decides it:
/// the library's [`handeye::calibrate`] over every pose pair (the command line's entry), so that
/// the drop-in refuses where the command line refuses (a `ValueError` with the library's
/// reason), warns where it warns (each caution of the report, for a `UserWarning`) and answers the
/// same X; it quotes no sigma but the report's bootstrap. Without a `setup` the arrays are read as
/// eye-in-hand, which serves both setups (OpenCV's eye-to-hand callers pass base2gripper and get
/// cam2base); with `setup="eye-to-hand"` the robot poses are base2gripper, inverted here, and the
/// checks judge the sizes of X and the target for a fixed camera. The messages name OpenCV's
/// arguments where the library's name the command line's options ([`opencv_words`]).
fn solve_opencv_poses<'py>(
    py: Python<'py>,
    robot: Vec<Transform>,
    camera: Vec<Transform>,
    method: &str,
    tsai_opencv_filter: bool,
    setup: Option<&str>,
) -> PyResult<RotationTranslation<'py>> {
    let options = calibration_options(method, "all", tsai_opencv_filter)?;
    let said = setup.map(parse_setup).transpose()?;
    let setup = said.unwrap_or(Setup::EyeInHand);
    if robot.len() != camera.len() {
        return Err(value_error(format!(
            "{} robot poses and {} camera poses: one of each per pose",
            robot.len(),
            camera.len()
        )));
    }
    let poses: Vec<PosePair> = robot
        .into_iter()
        .zip(camera)
        .map(|(hand, camera_from_target)| PosePair {
            base_from_gripper: match setup {
                Setup::EyeInHand => hand,
                Setup::EyeToHand => hand.inverse(),
            },
            camera_from_target,
        })
        .collect();
    let report = py
        .allow_threads(|| handeye::calibrate(&poses, setup, &options))
        .map_err(|e| value_error(opencv_words::error(&e, said, opencv_words::HAND_EYE)))?;
    let Some(report) = report.hand_eye() else {
        unreachable!("the hand–eye problem's report")
    };
    let (r, t) = (
        report.transform.rotation.matrix(),
        report.transform.translation.vector,
    );
    // OpenCV's filter drops motions without a word; the drop-in says how many, and why.
    let filtered = report
        .tsai_filter_note(options.tsai)
        .map(|note| format!("{note}; method=\"tsai\" (the name) keeps every motion"));
    Ok((
        numpy::ndarray::Array2::from_shape_fn((3, 3), |(i, j)| r[(i, j)]).into_pyarray(py),
        numpy::ndarray::Array2::from_shape_fn((3, 1), |(i, _)| t[i]).into_pyarray(py),
        report
            .warnings
            .iter()
            .map(|w| opencv_words::warning(w, said, opencv_words::HAND_EYE))
            .chain(filtered)
            .collect(),
    ))
}

/// The drop-in for `cv2.calibrateRobotWorldHandEye`: OpenCV's A X = Z B with A = world2cam
/// (`camera_from_target`), B = base2gripper (`base_from_gripper⁻¹`), X = base2world (the target
/// pose's inverse) and Z = gripper2cam (handeye's X's inverse), decided as `handeye calibrate
/// --robot-world --method M` decides it: the same refusals (a `ValueError`), the same cautions
/// (each for a `UserWarning`), the same transforms. Returns base2world's rotation and
/// translation, gripper2cam's, and the cautions.
#[pyfunction]
#[pyo3(signature = (r_world2cam, t_world2cam, r_base2gripper, t_base2gripper, method="shah"))]
fn solve_opencv_robot_world<'py>(
    py: Python<'py>,
    r_world2cam: PyReadonlyArrayDyn<'py, f64>,
    t_world2cam: PyReadonlyArray2<'py, f64>,
    r_base2gripper: PyReadonlyArrayDyn<'py, f64>,
    t_base2gripper: PyReadonlyArray2<'py, f64>,
    method: &str,
) -> PyResult<RobotWorldParts<'py>> {
    let camera = transforms(&r_world2cam, &t_world2cam, "world2cam")?;
    let robot = transforms(&r_base2gripper, &t_base2gripper, "base2gripper")?;
    if robot.len() != camera.len() {
        return Err(value_error(format!(
            "{} world2cam poses and {} base2gripper poses: one of each per pose",
            camera.len(),
            robot.len()
        )));
    }
    let poses: Vec<PosePair> = robot
        .iter()
        .zip(camera)
        .map(|(gripper_from_base, camera_from_target)| PosePair {
            base_from_gripper: gripper_from_base.inverse(),
            camera_from_target,
        })
        .collect();
    let options = handeye::Options {
        problem: handeye::Problem::RobotWorld(method.parse().map_err(value_error)?),
        ..Default::default()
    };
    let said = Some(Setup::EyeInHand);
    let report = py
        .allow_threads(|| handeye::calibrate(&poses, Setup::EyeInHand, &options))
        .map_err(|e| value_error(opencv_words::error(&e, said, opencv_words::ROBOT_WORLD)))?;
    let Some(report) = report.robot_world() else {
        unreachable!("the robot-world problem's report")
    };
    let parts = |t: &Transform| {
        let (r, v) = (t.rotation.matrix(), t.translation.vector);
        (
            numpy::ndarray::Array2::from_shape_fn((3, 3), |(i, j)| r[(i, j)]).into_pyarray(py),
            numpy::ndarray::Array2::from_shape_fn((3, 1), |(i, _)| v[i]).into_pyarray(py),
        )
    };
    let (r_base2world, t_base2world) = parts(&report.target_transform.inverse());
    let (r_gripper2cam, t_gripper2cam) = parts(&report.transform.inverse());
    let said = report
        .warnings
        .iter()
        .map(|w| opencv_words::warning(w, said, opencv_words::ROBOT_WORLD))
        .collect();
    Ok((
        r_base2world,
        t_base2world,
        r_gripper2cam,
        t_gripper2cam,
        said,
    ))
}

/// base2world's rotation and translation, gripper2cam's, and the cautions.
type RobotWorldParts<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Vec<String>,
);

/// [`solve_opencv`] on OpenCV's usual arguments, four lists (or tuples) of float64 arrays: (3, 3)
/// rotation matrices or rotation vectors of 3 entries, translations of 3 entries, each array in
/// any layout (a view `T[:3, :3]` too). Each array is read where it lies, so that ten poses cost
/// no stacking in numpy (`np.asarray` of the lists took 14 of the 56 µs at ten poses). `None` for any other
/// input, which the Python layer then stacks and passes to [`solve_opencv`]: the same answer, and
/// its messages for bad shapes.
#[pyfunction]
#[pyo3(signature = (r_gripper2base, t_gripper2base, r_target2cam, t_target2cam, method="tsai", tsai_opencv_filter=false, setup=None))]
// OpenCV's four arrays, then the drop-in's keywords: the signature Python sees.
#[allow(clippy::too_many_arguments)]
fn solve_opencv_sequences<'py>(
    py: Python<'py>,
    r_gripper2base: &Bound<'py, PyAny>,
    t_gripper2base: &Bound<'py, PyAny>,
    r_target2cam: &Bound<'py, PyAny>,
    t_target2cam: &Bound<'py, PyAny>,
    method: &str,
    tsai_opencv_filter: bool,
    setup: Option<&str>,
) -> PyResult<Option<RotationTranslation<'py>>> {
    let Some((robot, camera)) = sequence_parts(r_gripper2base, t_gripper2base)
        .zip(sequence_parts(r_target2cam, t_target2cam))
    else {
        return Ok(None);
    };
    let robot = checked_transforms(robot, "base_from_gripper")?;
    let camera = checked_transforms(camera, "camera_from_target")?;
    solve_opencv_poses(py, robot, camera, method, tsai_opencv_filter, setup).map(Some)
}

/// The rotations and translations of one side, from lists or tuples of float64 arrays; `None`
/// when they are not that, or their shapes are not OpenCV's, or the counts differ.
fn sequence_parts(
    rotations: &Bound<'_, PyAny>,
    translations: &Bound<'_, PyAny>,
) -> Option<Vec<(Matrix3<f64>, Vector3<f64>)>> {
    let (rotations, translations) = (sequence(rotations)?, sequence(translations)?);
    if rotations.len() != translations.len() {
        return None;
    }
    let mut matrices = None;
    rotations
        .iter()
        .zip(translations.iter())
        .map(|(r, t)| {
            let (r, t) = (FloatArray::of(r)?, FloatArray::of(t)?);
            // All rotations matrices, or all rotation vectors, as one stacked array would be.
            let is_matrix = *matrices.get_or_insert(r.is_3x3);
            let rotation = if is_matrix && r.is_3x3 {
                Matrix3::from_row_slice(&r.entries)
            } else if !is_matrix && r.entries.len() == 3 && r.ndim <= 2 {
                rodrigues(&Vector3::from_column_slice(&r.entries))
            } else {
                return None;
            };
            if t.entries.len() != 3 || t.ndim > 2 {
                return None;
            }
            Some((rotation, Vector3::from_column_slice(&t.entries)))
        })
        .collect()
}

/// The entries of a float64 numpy array in row-major order, with its shape's two facts that the
/// drop-in needs.
struct FloatArray {
    entries: Vec<f64>,
    is_3x3: bool,
    ndim: usize,
}

impl FloatArray {
    /// A copy of a float64 array's entries; `None` for anything else. A C-contiguous array (the
    /// usual case) is copied as the slice it is: an ndarray view of a dynamic shape, as
    /// `as_array` and `to_owned_array` make, was most of the 9 µs that reading ten poses' 40 arrays
    /// took.
    fn of(object: &Bound<'_, PyAny>) -> Option<Self> {
        let array = object.downcast::<numpy::PyArrayDyn<f64>>().ok()?;
        let entries = if array.is_c_contiguous() {
            array.to_vec().ok()?
        } else {
            array.to_owned_array().iter().copied().collect()
        };
        Some(Self {
            entries,
            is_3x3: array.shape() == [3, 3],
            ndim: array.ndim(),
        })
    }
}

/// The items of a list or a tuple.
fn sequence<'py>(object: &Bound<'py, PyAny>) -> Option<Vec<Bound<'py, PyAny>>> {
    if let Ok(list) = object.downcast::<PyList>() {
        Some(list.iter().collect())
    } else if let Ok(tuple) = object.downcast::<PyTuple>() {
        Some(tuple.iter().collect())
    } else {
        None
    }
}

/// Each rotation and translation checked as a 4×4 of `what[k]` is ([`transform`]).
fn checked_transforms(
    parts: Vec<(Matrix3<f64>, Vector3<f64>)>,
    what: &str,
) -> PyResult<Vec<Transform>> {
    parts
        .iter()
        .enumerate()
        .map(|(k, (rotation, translation))| {
            let mut m = Matrix4::identity();
            m.fixed_view_mut::<3, 3>(0, 0).copy_from(rotation);
            m.fixed_view_mut::<3, 1>(0, 3).copy_from(translation);
            transform_from_matrix4(&m).map_err(|p| value_error(format!("{what}[{k}]: {p}")))
        })
        .collect()
}

/// A rotation (3, 3) and a translation (3, 1), as OpenCV returns X, and the warnings in words
/// (the Python layer issues them).
type RotationTranslation<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Vec<String>,
);

/// Transforms from rotations ((N, 3, 3) matrices or (N, 3) rotation vectors) and (N, 3)
/// translations, each checked as a 4×4 of `what[k]` is ([`transform`]).
fn transforms(
    rotations: &PyReadonlyArrayDyn<'_, f64>,
    translations: &PyReadonlyArray2<'_, f64>,
    what: &str,
) -> PyResult<Vec<Transform>> {
    let (r, t) = (rotations.as_array(), translations.as_array());
    // A 0-d array has no first axis to count the poses on.
    let Some(&n) = r.shape().first() else {
        return Err(value_error(format!(
            "{what}: expected (N, 3, 3) rotations or (N, 3) rotation vectors, got a 0-d array"
        )));
    };
    let matrices = r.shape()[1..] == [3, 3];
    if !(matrices || r.shape()[1..] == [3]) || t.shape() != [n, 3] {
        return Err(value_error(format!(
            "{what}: expected (N, 3, 3) rotations or (N, 3) rotation vectors and (N, 3) translations, got {:?} and {:?}",
            r.shape(),
            t.shape()
        )));
    }
    let parts = (0..n)
        .map(|k| {
            let rotation = if matrices {
                Matrix3::from_fn(|i, j| r[[k, i, j]])
            } else {
                rodrigues(&Vector3::from_fn(|i, _| r[[k, i]]))
            };
            (rotation, Vector3::from_fn(|i, _| t[[k, i]]))
        })
        .collect();
    checked_transforms(parts, what)
}

/// The rotation of a rotation vector w = θ k (Rodrigues): R = I + sin θ [k]× + (1 − cos θ) [k]×²,
/// the identity for w = 0 (as OpenCV's `Rodrigues`).
fn rodrigues(w: &Vector3<f64>) -> Matrix3<f64> {
    let theta = w.norm();
    let k = if theta > 1e-300 { w / theta } else { *w };
    let kx = k.cross_matrix();
    Matrix3::identity() + kx * theta.sin() + kx * kx * (1.0 - theta.cos())
}

/// The one batch calibration ([`handeye::calibrate`]) for every problem and input kind: pose
/// pairs (`base_from_gripper`, `camera_from_target`) or, with `path`, a recording with detections
/// and the camera's `intrinsics` (the calibration on the pixels, [`pixel_recording`]); X alone
/// (hand–eye) or, with `robot_world`, X and the target's pose together. Its report as JSON, the
/// same object `handeye calibrate` prints for the same input and flags (the Python layer parses
/// it); on the pixels the records are named as there.
#[pyfunction]
#[pyo3(signature = (base_from_gripper=None, camera_from_target=None, path=None, intrinsics=None, method=None, setup="eye-in-hand", robot_world=false, pairs="all", tsai_opencv_filter=false, reject_outliers=false, fix=None, bootstrap=handeye::Options::default().replicates, point=None, joints=None, prior=None, robot_model=None, refine_intrinsics=false, base_frame=None, gripper_frame=None, camera_frame=None, target_topic=None, tag_size=None, tag_id=None, camera_info_topic=None, time_offset=None, max_gap=0.1, goal=None))]
#[allow(clippy::too_many_arguments)]
fn calibrate_report<'py>(
    py: Python<'py>,
    base_from_gripper: Option<PyReadonlyArray3<'py, f64>>,
    camera_from_target: Option<PyReadonlyArray3<'py, f64>>,
    path: Option<PathBuf>,
    intrinsics: Option<PathBuf>,
    method: Option<&str>,
    setup: &str,
    robot_world: bool,
    pairs: &str,
    tsai_opencv_filter: bool,
    reject_outliers: bool,
    fix: Option<&str>,
    bootstrap: usize,
    point: Option<[f64; 3]>,
    joints: Option<Vec<Vec<f64>>>,
    prior: Option<Vec<String>>,
    robot_model: Option<std::path::PathBuf>,
    refine_intrinsics: bool,
    base_frame: Option<String>,
    gripper_frame: Option<String>,
    camera_frame: Option<String>,
    target_topic: Option<String>,
    tag_size: Option<f64>,
    tag_id: Option<i32>,
    camera_info_topic: Option<String>,
    time_offset: Option<&Bound<'_, PyAny>>,
    max_gap: f64,
    goal: Option<(f64, f64)>,
) -> PyResult<String> {
    let goal = goal.map(|(rotation_deg, translation)| handeye::Sizes {
        rotation_deg,
        translation,
    });
    if let Some(path) = path {
        let bag = TagBag {
            frames: [base_frame, gripper_frame, camera_frame],
            target_topic,
            tag_size,
            tag_id,
            camera_info_topic,
        };
        let setup = parse_setup(setup)?;
        let options = handeye::Options {
            problem: if robot_world {
                handeye::Problem::RobotWorld(handeye::RobotWorldMethod::Reprojection)
            } else {
                handeye::Problem::HandEye(handeye::Method::Reprojection)
            },
            // As the command line's report says it (every face prints one object).
            pairing: handeye::Pairing::All,
            fix: parse_fix(fix)?,
            point: checked_point(point)?,
            refine_intrinsics,
            reject_outliers,
            priors: priors(prior)?,
            ..Default::default()
        };
        let reading = RecordingOptions {
            setup,
            time_offset: self::time_offset(time_offset)?,
            max_gap,
            ..RecordingOptions::default()
        };
        let (camera, read) =
            py.allow_threads(|| pixel_recording(path, intrinsics, bag, &reading))?;
        let options = handeye::Options {
            pose_names: read.names,
            goal,
            ..options
        };
        let input = handeye::Input::Pixels {
            frames: &read.frames,
            camera: &camera,
        };
        let report = py
            .allow_threads(|| handeye::calibrate(input, setup, &options))
            .map_err(value_error)?;
        return serde_json::to_string(&report).map_err(value_error);
    }
    let (Some(base_from_gripper), Some(camera_from_target)) =
        (base_from_gripper, camera_from_target)
    else {
        return Err(value_error(
            "give the poses (base_from_gripper and camera_from_target) or a recording with detections (path)",
        ));
    };
    let options = if robot_world {
        handeye::Options {
            joints: checked_joints(joints)?,
            robot_model: read_robot_model(robot_model)?,
            priors: priors(prior)?,
            problem: handeye::Problem::RobotWorld(
                method.unwrap_or("refine").parse().map_err(value_error)?,
            ),
            fix: parse_fix(fix)?,
            replicates: bootstrap,
            reject_outliers,
            point: checked_point(point)?,
            ..Default::default()
        }
    } else {
        handeye::Options {
            joints: checked_joints(joints)?,
            robot_model: read_robot_model(robot_model)?,
            priors: priors(prior)?,
            reject_outliers,
            fix: parse_fix(fix)?,
            replicates: bootstrap,
            point: checked_point(point)?,
            ..calibration_options(method.unwrap_or("andreff"), pairs, tsai_opencv_filter)?
        }
    };
    let options = handeye::Options { goal, ..options };
    let setup = parse_setup(setup)?;
    let poses = poses(&base_from_gripper, &camera_from_target)?;
    let report = py
        .allow_threads(|| handeye::calibrate(&poses, setup, &options))
        .map_err(value_error)?;
    serde_json::to_string(&report).map_err(value_error)
}

/// A ROS 2 recording of a tag's detections, as the keywords of `calibrate` on a path name it
/// (the command line's `--base-frame … --target-topic … --tag-size …`).
struct TagBag {
    frames: [Option<String>; 3],
    target_topic: Option<String>,
    tag_size: Option<f64>,
    tag_id: Option<i32>,
    camera_info_topic: Option<String>,
}

/// The frames of a calibration on the pixels (the library's `FrameRecording`, its one entry) and
/// the camera's intrinsics: a JSON Lines file with `detections` and `intrinsics`, or a ROS 2
/// recording of a tag's detections whose `CameraInfo` topic gives them when `intrinsics` does not.
fn pixel_recording(
    path: PathBuf,
    intrinsics: Option<PathBuf>,
    bag: TagBag,
    options: &RecordingOptions,
) -> PyResult<(handeye::Intrinsics, FrameRecording)> {
    let [base, gripper, camera] = bag.frames;
    let tag_keywords = [
        ("tag_size", bag.tag_size.is_some()),
        ("tag_id", bag.tag_id.is_some()),
        ("camera_info_topic", bag.camera_info_topic.is_some()),
    ];
    let mut source = recording_source(
        Some(path),
        "auto",
        None,
        None,
        [base, gripper, camera, None, bag.target_topic],
    )?;
    match &mut source {
        Source::Bag { frames, .. } => {
            let Some(size) = bag.tag_size else {
                return Err(value_error(
                    "a ROS 2 recording is calibrated on the pixels from a tag's detections: give target_topic (apriltag_msgs/AprilTagDetectionArray) and tag_size (metres)",
                ));
            };
            frames.tags = Some(BagTags {
                size,
                id: bag.tag_id,
                camera_info_topic: bag.camera_info_topic,
            });
        }
        Source::File { path, .. } => {
            if let Some((name, _)) = tag_keywords.iter().find(|(_, given)| *given) {
                return Err(value_error(format!(
                    "{name} is for a ROS 2 recording of a tag's detections, and {} is not one",
                    path.display()
                )));
            }
        }
        Source::Streams { .. } => unreachable!("a single path is never two streams"),
    }
    let read = FrameRecording::read(&source, options).map_err(read_error)?;
    let camera = match (intrinsics, &read.intrinsics) {
        (Some(file), _) => handeye::Intrinsics::read(&file).map_err(value_error)?,
        (None, Some(camera)) => *camera,
        (None, None) => {
            return Err(value_error(match source {
                Source::Bag { .. } => {
                    "reprojection needs the camera's intrinsics: the recording has no sensor_msgs/CameraInfo topic (…camera_info); give intrinsics=FILE (OpenCV YAML or ROS camera_info) or camera_info_topic"
                }
                _ => {
                    "reprojection needs the camera's intrinsics: intrinsics=FILE (OpenCV YAML or ROS camera_info)"
                }
            }));
        }
    };
    Ok((camera, read))
}

/// A saved X checked on the pixels of a JSON Lines file with `detections`
/// ([`handeye::verify`] on [`handeye::Input::Pixels`]): its result as JSON, the same object `handeye verify --x SAVED
/// FILE --intrinsics I` prints.
#[pyfunction]
#[pyo3(signature = (saved, path, intrinsics, setup=None, fix=None, tolerance=None))]
fn verify_pixels_report(
    py: Python<'_>,
    saved: PathBuf,
    path: PathBuf,
    intrinsics: PathBuf,
    setup: Option<&str>,
    fix: Option<&str>,
    tolerance: Option<(f64, f64)>,
) -> PyResult<String> {
    let fix = parse_fix(fix)?;
    let saved = handeye::SavedX::read(&saved).map_err(value_error)?;
    let setup = saved_setup(&saved, setup)?;
    let bag = TagBag {
        frames: [None, None, None],
        target_topic: None,
        tag_size: None,
        tag_id: None,
        camera_info_topic: None,
    };
    let (camera, read) =
        pixel_recording(path, Some(intrinsics), bag, &RecordingOptions::default())?;
    let options = handeye::Options {
        problem: handeye::Problem::HandEye(handeye::Method::Reprojection),
        pairing: handeye::Pairing::All,
        fix,
        pose_names: read.names,
        ..Default::default()
    };
    let v = py
        .allow_threads(|| {
            let input = handeye::Input::Pixels {
                frames: &read.frames,
                camera: &camera,
            };
            handeye::verify(&saved, input, setup, &options)
        })
        .map_err(value_error)?;
    let v = within(v, tolerance)?;
    serde_json::to_string(&v).map_err(value_error)
}

/// A point given for `uncertainty.at_point`: three finite numbers (the camera frame, the input's
/// unit), as `--point` checks them.
fn checked_point(point: Option<[f64; 3]>) -> PyResult<Option<[f64; 3]>> {
    match point {
        Some(p) if p.iter().any(|v| !v.is_finite()) => Err(value_error(format!(
            "point: expected three finite numbers (X, Y, Z in the camera frame), found {p:?}"
        ))),
        p => Ok(p),
    }
}

/// A count given to the online calibrator: a negative one is a `ValueError` naming it (as a
/// `usize` argument it was an `OverflowError` that named nothing).
fn count(name: &str, value: Option<i64>) -> PyResult<Option<usize>> {
    value
        .map(|v| {
            usize::try_from(v)
                .map_err(|_| PyValueError::new_err(format!("{name} must not be negative, got {v}")))
        })
        .transpose()
}

/// The robot's DH table at `path` (`robot_model=`, as `--robot-model`), read.
fn read_robot_model(path: Option<std::path::PathBuf>) -> PyResult<Option<handeye::Kinematics>> {
    path.map(handeye::Kinematics::read)
        .transpose()
        .map_err(value_error)
}

/// Joint angles given to a calibration: every pose's, finite, one count (as JSON Lines gives them).
fn checked_joints(joints: Option<Vec<Vec<f64>>>) -> PyResult<Vec<Vec<f64>>> {
    let joints = joints.unwrap_or_default();
    let count = joints.first().map_or(0, Vec::len);
    for (i, q) in joints.iter().enumerate() {
        if q.is_empty() || q.len() != count || q.iter().any(|v| !v.is_finite()) {
            return Err(value_error(format!(
                "joints[{i}]: expected {count} finite joint angles in radians (as every pose's), found {q:?}"
            )));
        }
    }
    Ok(joints)
}

/// Priors given to a calibration, in the command line's syntax (`"tz=0.12+-0.002"`), parsed with
/// the library's words (the calibration checks that each component comes once).
fn priors(prior: Option<Vec<String>>) -> PyResult<Vec<handeye::Prior>> {
    prior
        .unwrap_or_default()
        .iter()
        .map(|p| p.parse::<handeye::Prior>().map_err(value_error))
        .collect()
}

/// Whether a saved X still fits a new recording (`handeye verify`): the library's
/// `Verification` as JSON text, the same object the command line prints.
#[pyfunction]
#[pyo3(signature = (saved, base_from_gripper, camera_from_target, setup=None, method="andreff", pairs="all", reject_outliers=false, bootstrap=handeye::Options::default().replicates, joints=None, prior=None, fix=None, tolerance=None))]
#[allow(clippy::too_many_arguments)]
fn verify_report<'py>(
    py: Python<'py>,
    saved: &str,
    base_from_gripper: PyReadonlyArray3<'py, f64>,
    camera_from_target: PyReadonlyArray3<'py, f64>,
    setup: Option<&str>,
    method: &str,
    pairs: &str,
    reject_outliers: bool,
    bootstrap: usize,
    joints: Option<Vec<Vec<f64>>>,
    prior: Option<Vec<String>>,
    fix: Option<&str>,
    tolerance: Option<(f64, f64)>,
) -> PyResult<String> {
    let saved = handeye::SavedX::read(saved).map_err(value_error)?;
    let setup = saved_setup(&saved, setup)?;
    let options = handeye::Options {
        joints: checked_joints(joints)?,
        priors: priors(prior)?,
        fix: parse_fix(fix)?,
        reject_outliers,
        replicates: bootstrap,
        ..calibration_options(method, pairs, false)?
    };
    let poses = poses(&base_from_gripper, &camera_from_target)?;
    let verification = py
        .allow_threads(|| handeye::verify(&saved, &poses, setup, &options))
        .map_err(value_error)?;
    let verification = within(verification, tolerance)?;
    serde_json::to_string(&verification).map_err(value_error)
}

/// The setup to verify in: `setup` when given (it must be the saved file's, when the file says),
/// else the file's, else eye-in-hand ([`handeye::SavedX::setup_for`]).
fn saved_setup(saved: &handeye::SavedX, setup: Option<&str>) -> PyResult<handeye::Setup> {
    let given = setup.map(parse_setup).transpose()?;
    saved.setup_for(given).map_err(value_error)
}

/// The verification against `tolerance` (degrees, the recording's length unit), when given
/// ([`handeye::Verification::within`]).
fn within(
    v: handeye::Verification,
    tolerance: Option<(f64, f64)>,
) -> PyResult<handeye::Verification> {
    match tolerance {
        Some((rotation_deg, translation)) => v
            .within(handeye::Sizes {
                rotation_deg,
                translation,
            })
            .map_err(value_error),
        None => Ok(v),
    }
}

/// What to record next (`handeye advise`): the library's `Advice` as JSON text.
#[pyfunction]
#[pyo3(signature = (base_from_gripper, camera_from_target, setup="eye-in-hand", count=3, prior=None, goal=None))]
fn advise_report<'py>(
    py: Python<'py>,
    base_from_gripper: PyReadonlyArray3<'py, f64>,
    camera_from_target: PyReadonlyArray3<'py, f64>,
    setup: &str,
    count: usize,
    prior: Option<Vec<String>>,
    goal: Option<(f64, f64)>,
) -> PyResult<String> {
    let options = handeye::AdviseOptions {
        count,
        priors: priors(prior)?,
        goal: goal.map(|(rotation_deg, translation)| handeye::Sizes {
            rotation_deg,
            translation,
        }),
    };
    if !(1..=20).contains(&count) {
        return Err(value_error(format!("count must be 1 to 20, found {count}")));
    }
    let setup = parse_setup(setup)?;
    let poses = poses(&base_from_gripper, &camera_from_target)?;
    let advice = py
        .allow_threads(|| handeye::advise(&poses, setup, handeye::Written::NAMED, &options))
        .map_err(value_error)?;
    serde_json::to_string(&advice).map_err(value_error)
}

/// Where `read_recording` reads: two streams, a ROS 2 recording (with its frames) or a pose file.
fn recording_source(
    path: Option<PathBuf>,
    format: &str,
    robot: Option<PathBuf>,
    camera: Option<PathBuf>,
    frames: [Option<String>; 5],
) -> PyResult<Source> {
    let named = [
        "base_frame",
        "gripper_frame",
        "camera_frame",
        "target_frame",
        "target_topic",
    ];
    match (path, robot, camera) {
        (None, Some(robot), Some(camera)) => Ok(Source::Streams { robot, camera }),
        (Some(path), None, None) if handeye::io::rosbag::is_bag(&path) => {
            let [base, gripper, camera, target, target_topic] = frames;
            let missing: Vec<&str> = [&base, &gripper, &camera]
                .iter()
                .zip(named)
                .filter(|(v, _)| v.is_none())
                .map(|(_, name)| name)
                .chain(
                    (target.is_none() && target_topic.is_none())
                        .then_some("target_frame (or target_topic)"),
                )
                .collect();
            if !missing.is_empty() {
                return Err(value_error(format!(
                    "{} is a ROS 2 recording: name its frames with {}",
                    path.display(),
                    missing.join(", ")
                )));
            }
            let frames = BagFrames {
                base: base.unwrap_or_default(),
                gripper: gripper.unwrap_or_default(),
                camera: camera.unwrap_or_default(),
                target,
                target_topic,
                tags: None,
            };
            Ok(Source::Bag { path, frames })
        }
        (Some(path), None, None) => {
            if let Some((_, name)) = frames.iter().zip(named).find(|(v, _)| v.is_some()) {
                return Err(value_error(format!(
                    "{name} is for a ROS 2 recording (a rosbag2 directory, an .mcap or a .db3 file), and {} is not one",
                    path.display()
                )));
            }
            let format = format.parse::<Format>().map_err(value_error)?;
            Ok(Source::File { path, format })
        }
        _ => Err(value_error(
            "give a path (a pose file, a ViSP directory or a ROS 2 recording), or robot and camera (two stamped streams), not both",
        )),
    }
}

/// `time_offset`: none, seconds, or "auto".
fn time_offset(value: Option<&Bound<'_, PyAny>>) -> PyResult<Option<TimeOffset>> {
    let Some(value) = value.filter(|v| !v.is_none()) else {
        return Ok(None);
    };
    if let Ok(text) = value.extract::<String>() {
        return match text.as_str() {
            "auto" => Ok(Some(TimeOffset::Auto)),
            _ => Err(value_error(format!(
                "time_offset: expected \"auto\" or seconds, found \"{text}\""
            ))),
        };
    }
    let seconds: f64 = value
        .extract()
        .map_err(|_| value_error("time_offset: expected \"auto\" or seconds"))?;
    Ok(Some(TimeOffset::Fixed(seconds)))
}

/// (N, 4, 4) arrays of the pose pairs' two transforms.
fn pose_arrays<'py>(py: Python<'py>, poses: &[PosePair]) -> [Bound<'py, numpy::PyArray3<f64>>; 2] {
    let stack = |pick: fn(&PosePair) -> &Transform| {
        let homogeneous: Vec<_> = poses.iter().map(|p| pick(p).to_homogeneous()).collect();
        numpy::ndarray::Array3::from_shape_fn((poses.len(), 4, 4), |(k, r, c)| {
            homogeneous[k][(r, c)]
        })
        .into_pyarray(py)
    };
    [
        stack(|p| &p.base_from_gripper),
        stack(|p| &p.camera_from_target),
    ]
}

/// Where a recording's tf places the camera frame, as a dict: `camera`, `root` (the frame X is
/// published for), `root_from_camera` (a 4x4 array, or None when a transform between them moves),
/// `placed_under` (the robot's frame the root hangs from, or None) and `tf_x` (X as tf has it,
/// when it is placed there through static transforms, or None).
fn camera_mount<'py>(py: Python<'py>, m: &CameraMount) -> PyResult<Bound<'py, PyDict>> {
    let array = |t: Option<Transform>| {
        t.map(|t| {
            let h = t.to_homogeneous();
            numpy::ndarray::Array2::from_shape_fn((4, 4), |(r, c)| h[(r, c)]).into_pyarray(py)
        })
    };
    let d = PyDict::new(py);
    d.set_item("camera", &m.camera)?;
    d.set_item("root", m.root())?;
    d.set_item("root_from_camera", array(m.frame_from_camera(m.root())))?;
    d.set_item("placed_under", &m.placed_under)?;
    d.set_item("tf_x", array(m.tf_x))?;
    Ok(d)
}

/// Reads any input (the library's `io::Recording`): a pose file, a ViSP directory, two stamped
/// streams or a ROS 2 recording; a dict of the pose pairs and what reading found.
#[pyfunction]
#[pyo3(signature = (path=None, *, format="auto", robot=None, camera=None, base_frame=None, gripper_frame=None, camera_frame=None, target_frame=None, target_topic=None, setup="eye-in-hand", time_offset=None, max_gap=0.1, rotation=None))]
#[allow(clippy::too_many_arguments)]
fn read_recording<'py>(
    py: Python<'py>,
    path: Option<PathBuf>,
    format: &str,
    robot: Option<PathBuf>,
    camera: Option<PathBuf>,
    base_frame: Option<String>,
    gripper_frame: Option<String>,
    camera_frame: Option<String>,
    target_frame: Option<String>,
    target_topic: Option<String>,
    setup: &str,
    time_offset: Option<&Bound<'py, PyAny>>,
    max_gap: f64,
    rotation: Option<Vec<String>>,
) -> PyResult<Bound<'py, PyDict>> {
    let frames = [
        base_frame,
        gripper_frame,
        camera_frame,
        target_frame,
        target_topic,
    ];
    let source = recording_source(path, format, robot, camera, frames)?;
    let options = RecordingOptions {
        setup: parse_setup(setup)?,
        time_offset: self::time_offset(time_offset)?,
        max_gap,
        rotations: handeye::Rotations::parse(&rotation.unwrap_or_default()).map_err(value_error)?,
        ..RecordingOptions::default()
    };
    let r = py
        .allow_threads(|| Recording::read(&source, &options))
        .map_err(read_error)?;
    let [g, c] = pose_arrays(py, &r.poses);
    let d = PyDict::new(py);
    d.set_item("base_from_gripper", g)?;
    d.set_item("camera_from_target", c)?;
    d.set_item("names", &r.names)?;
    d.set_item("lines", &r.lines)?;
    d.set_item("stamps", &r.stamps)?;
    d.set_item("time_offset", r.time_offset)?;
    d.set_item("time_offset_sigma", r.time_offset_sigma)?;
    let curve = r.offset_curve.as_ref().map(|curve| {
        numpy::ndarray::Array2::from_shape_fn((curve.len(), 2), |(k, j)| curve[k][j])
            .into_pyarray(py)
    });
    d.set_item("offset_curve", curve)?;
    d.set_item("target_source", &r.target_source)?;
    let mount = r
        .camera_mount
        .as_ref()
        .map(|m| camera_mount(py, m))
        .transpose()?;
    d.set_item("camera_mount", mount)?;
    let notes: Vec<String> = r.notes.iter().map(ToString::to_string).collect();
    d.set_item("notes", notes)?;
    d.set_item("joints", (!r.joints.is_empty()).then_some(&r.joints))?;
    Ok(d)
}

/// The method, pairing and Tsai options by name.
fn calibration_options(
    method: &str,
    pairs: &str,
    tsai_opencv_filter: bool,
) -> PyResult<handeye::Options> {
    Ok(handeye::Options {
        problem: handeye::Problem::HandEye(method.parse::<Method>().map_err(value_error)?),
        pairing: pairs.parse::<Pairing>().map_err(value_error)?,
        tsai: handeye::TsaiOptions {
            opencv_filter: tsai_opencv_filter,
        },
        ..Default::default()
    })
}

/// `fix` by name; none: a misread input is refused (the library's default, as on the command line).
fn parse_fix(fix: Option<&str>) -> PyResult<handeye::Fix> {
    fix.map_or(Ok(handeye::Fix::Refuse), |name| {
        name.parse().map_err(value_error)
    })
}

/// The setup by name (the library's names, as on the command line).
fn parse_setup(setup: &str) -> PyResult<Setup> {
    setup.parse::<Setup>().map_err(value_error)
}

/// The online calibrator (see `handeye.OnlineCalibrator`): the library's, built from its
/// settings; each push's outputs converted.
#[pyclass(name = "_OnlineCalibrator")]
struct PyOnline {
    inner: OnlineCalibrator,
    /// What the calibrator found that every face tells (the readings check of the first poses
    /// and a stuck selection, with the paper's estimator; the cautions of the solve on the
    /// pixels; the poses the accumulating estimator held out), until Python takes them as
    /// warnings.
    found: Vec<String>,
}

#[pymethods]
impl PyOnline {
    #[new]
    #[pyo3(signature = (selection="adaptive", setup="eye-in-hand", estimator="accumulate", error_source="residual", truth=None, optimal=false, n_init=None, interval=None, relax_down=None, relax_up=None, explore=None, rms_r_max=None, rms_t_max=None, alpha_min=None, alpha_min_deg=None, beta_min_deg=None, d_max=None, unfreeze=false, unit="auto", every=None, shrink=None, point=None, prior=None, intrinsics=None, robot_model=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        selection: &str,
        setup: &str,
        estimator: &str,
        error_source: &str,
        truth: Option<PyReadonlyArray2<'_, f64>>,
        optimal: bool,
        n_init: Option<i64>,
        interval: Option<i64>,
        relax_down: Option<f64>,
        relax_up: Option<f64>,
        explore: Option<f64>,
        rms_r_max: Option<f64>,
        rms_t_max: Option<f64>,
        alpha_min: Option<f64>,
        alpha_min_deg: Option<f64>,
        beta_min_deg: Option<f64>,
        d_max: Option<f64>,
        unfreeze: bool,
        unit: &str,
        every: Option<i64>,
        shrink: Option<f64>,
        point: Option<[f64; 3]>,
        prior: Option<Vec<String>>,
        intrinsics: Option<PathBuf>,
        robot_model: Option<PathBuf>,
    ) -> PyResult<Self> {
        let truth = truth
            .map(|t| transform(t.as_array(), "truth"))
            .transpose()?;
        // Converted in the order Python's arguments were checked; the library applies the rules.
        let settings = OnlineSettings {
            setup: parse_setup(setup)?,
            selection: selection.parse().map_err(value_error)?,
            n_init: count("n_init", n_init)?,
            interval: count("interval", interval)?,
            error_source: error_source.parse().map_err(value_error)?,
            estimator: estimator.parse().map_err(value_error)?,
            every: count("every", every)?,
            point: checked_point(point)?,
            // The unit is not read when an explicit d_max sets it (as given).
            unit: match d_max {
                Some(_) => Unit::Auto,
                None => unit.parse().map_err(value_error)?,
            },
            truth,
            optimal,
            relax_down,
            relax_up,
            explore,
            rms_r_max,
            rms_t_max,
            alpha_min: alpha_min_deg
                .map(AlphaMin::Degrees)
                .or(alpha_min.map(AlphaMin::Sine)),
            beta_min_deg,
            d_max,
            unfreeze,
            shrink,
            outlier_deg: None,
            // Arrays as handeye names them.
            written: handeye::Written::NAMED,
            priors: priors(prior)?,
            robot_model: read_robot_model(robot_model)?,
            intrinsics: intrinsics
                .map(|path| handeye::Intrinsics::read(&path))
                .transpose()
                .map_err(value_error)?,
        };
        Ok(Self {
            inner: settings.calibrator().map_err(value_error)?,
            found: Vec::new(),
        })
    }

    /// Pushes one pose pair (4×4 arrays), with the joint angles at it if given; returns the list
    /// of what it made happen (usually empty): the accumulating estimator's change and report,
    /// or the paper's calibrations.
    #[pyo3(signature = (base_from_gripper, camera_from_target, joints=None))]
    fn push<'py>(
        &mut self,
        py: Python<'py>,
        base_from_gripper: PyReadonlyArray2<'py, f64>,
        camera_from_target: PyReadonlyArray2<'py, f64>,
        joints: Option<Vec<f64>>,
    ) -> PyResult<Vec<Bound<'py, PyDict>>> {
        if self.inner.on_the_pixels() {
            return Err(value_error(
                "this calibrator is on the pixels (intrinsics given): push records with detections (push_detections, push_record)",
            ));
        }
        let pose = PosePair {
            base_from_gripper: transform(base_from_gripper.as_array(), "base_from_gripper")?,
            camera_from_target: transform(camera_from_target.as_array(), "camera_from_target")?,
        };
        let record = match &joints {
            Some(q) => Record::pose(&pose).with_joints(q),
            None => Record::pose(&pose),
        };
        let outputs = self.inner.push(record).map_err(value_error)?;
        self.tell(&outputs);
        let setup = self.inner.config().setup;
        let lines = outputs
            .change
            .map(|c| c.change.json())
            .into_iter()
            .chain(outputs.report.map(|r| r.json(setup, None)))
            .chain(outputs.events.iter().map(|e| e.json()));
        lines.map(|v| json_dict(py, &v)).collect()
    }

    /// Pushes one record with `detections` (its JSON text, a line of a JSON Lines recording,
    /// SPEC sec. 9), read by the library's reader of such records; returns the estimates it
    /// completes (at 16, 32, 64, … records). A bad record raises `ValueError` naming its field
    /// and is not kept.
    fn push_record<'py>(
        &mut self,
        py: Python<'py>,
        text: &str,
    ) -> PyResult<Vec<Bound<'py, PyDict>>> {
        if !self.inner.on_the_pixels() {
            return Err(value_error(
                "records with detections are calibrated on the pixels: give OnlineCalibrator(intrinsics=FILE)",
            ));
        }
        let number = self.inner.poses() + 1;
        let source = format!("record {number}");
        let frame = match FrameRecording::records(text.as_bytes(), &source).next() {
            Some(Ok((_, frame))) => frame,
            Some(Err(handeye::Error::Parse { field, message, .. })) => {
                return Err(value_error(format!("{source}: field `{field}`: {message}")));
            }
            Some(Err(e)) => return Err(value_error(e)),
            None => return Err(value_error(format!("{source}: an empty record"))),
        };
        let setup = self.inner.config().setup;
        let inner = &mut self.inner;
        // Named by its number, as `record N`.
        let outputs = py
            .allow_threads(|| inner.push(Record::frame(frame)))
            .map_err(value_error)?;
        outputs
            .report
            .map(|r| json_dict(py, &r.json(setup, None)))
            .into_iter()
            .collect()
    }

    /// What the calibrator found since last asked (each once), in words.
    fn take_warnings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.found)
    }

    /// The accumulating estimator's final report (JSON text), or None; a readings check not run
    /// yet runs on a short stream (see `take_warnings`).
    fn finish(&mut self, py: Python<'_>) -> PyResult<Option<String>> {
        let setup = self.inner.config().setup;
        let inner = &mut self.inner;
        // A prior in another length unit than the poses, told only now on a short stream; on
        // the pixels, the calibration's refusal.
        let outputs = py.allow_threads(|| inner.finish()).map_err(value_error)?;
        self.tell(&outputs);
        Ok(outputs.report.map(|r| r.json(setup, None).to_string()))
    }

    /// The estimate to use now (JSON text): the accumulating estimator's last report since the
    /// last change of X, unless the readings were found misread since; None when there is none
    /// (`pending()` says why). A report from before a change is not the current X.
    fn last_report(&self) -> Option<String> {
        let setup = self.inner.config().setup;
        self.inner
            .last_report()
            .map(|r| r.json(setup, None).to_string())
    }

    /// Why the accumulating estimator has nothing to report now, or None.
    fn pending(&self) -> Option<String> {
        self.inner.pending().map(|p| p.to_string())
    }

    /// Poses pushed so far (records, on the pixels).
    fn poses(&self) -> usize {
        self.inner.poses()
    }

    /// Calibrations made so far.
    fn calibrations(&self) -> usize {
        self.inner.calibrations()
    }

    /// The whole state as JSON (restore with `from_state`).
    fn state(&self) -> PyResult<String> {
        if self.inner.on_the_pixels() {
            return Err(value_error(
                "state() is not offered on the pixels (yet): keep the records and push them again",
            ));
        }
        serde_json::to_string(&self.inner).map_err(value_error)
    }

    /// A calibrator restored from `state()`; its settings are checked as the constructor checks
    /// them.
    #[staticmethod]
    fn from_state(state: &str) -> PyResult<Self> {
        let inner: OnlineCalibrator = serde_json::from_str(state).map_err(|e| {
            value_error(format!("not a saved state: {}", shortened(&e.to_string())))
        })?;
        inner.config().validate().map_err(value_error)?;
        Ok(Self {
            inner,
            found: Vec::new(),
        })
    }
}

impl PyOnline {
    /// Keeps what the outputs tell, in the words the command line tells it: a misread, a stuck
    /// selection, the poses held out (thinned by the library's rule), the cautions of the end's
    /// estimate on the pixels.
    fn tell(&mut self, outputs: &Outputs) {
        self.found
            .extend(outputs.misread.as_ref().map(|f| f.to_string()));
        self.found.extend(outputs.stuck.clone());
        for h in &outputs.held_out {
            if h.tell.told() {
                self.found.push(format!("held out: {}: {}", h.name, h.why));
            }
            if h.tell == Tell::NowThenThinned {
                self.found
                    .push("further held-out poses are told only at the 2^k-th".into());
            }
        }
        let words: Vec<String> = outputs.warnings.iter().map(|w| w.to_string()).collect();
        if !words.is_empty() {
            self.found.push(words.join("; "));
        }
    }
}

/// Characters of a message kept by [`shortened`].
const MESSAGE_CHARS: usize = 300;

/// A message of at most [`MESSAGE_CHARS`] characters: JSON's errors quote the value they fail on,
/// which may be the whole (100 MB) input.
fn shortened(message: &str) -> String {
    match message.char_indices().nth(MESSAGE_CHARS) {
        None => message.to_string(),
        Some((at, _)) => format!(
            "{}… ({} characters in all)",
            &message[..at],
            message.chars().count()
        ),
    }
}

/// A JSON object as a dict (through Python's json module, so every face shows the same fields).
fn json_dict<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyDict>> {
    let json = py.import("json")?;
    let d = json.call_method1("loads", (v.to_string(),))?;
    Ok(d.downcast_into::<PyDict>()?)
}

/// The extension module.
#[pymodule]
fn _handeye(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(solve_x, m)?)?;
    m.add_function(wrap_pyfunction!(solve_opencv, m)?)?;
    m.add_function(wrap_pyfunction!(solve_opencv_sequences, m)?)?;
    m.add_function(wrap_pyfunction!(solve_opencv_robot_world, m)?)?;
    m.add_function(wrap_pyfunction!(calibrate_report, m)?)?;
    m.add_function(wrap_pyfunction!(verify_pixels_report, m)?)?;
    m.add_function(wrap_pyfunction!(advise_report, m)?)?;
    m.add_function(wrap_pyfunction!(verify_report, m)?)?;
    m.add_function(wrap_pyfunction!(read_recording, m)?)?;
    m.add_class::<PyOnline>()?;
    Ok(())
}
