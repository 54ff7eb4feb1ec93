"""handeye: hand-eye calibration (AX = XB) from Python.

Frames: ``base_from_gripper`` is the robot pose (OpenCV ``R/t_gripper2base``), ``camera_from_target``
the camera's observation of the target (OpenCV ``R/t_target2cam``, what PnP returns). X is
``gripper_from_camera`` (OpenCV ``cam2gripper``) for eye-in-hand, ``base_from_camera`` for
eye-to-hand. Quaternions are not used here: 4x4 matrices, 3x3 rotations or 3-vector rotation vectors.

Two faces:

* ``calibrate_hand_eye(...)``: a drop-in for ``cv2.calibrateHandEye`` (same arguments, same
  outputs), which raises ``ValueError`` on degenerate data instead of returning an identity;
  ``calibrate_robot_world_hand_eye(...)`` the same for ``cv2.calibrateRobotWorldHandEye``.
* ``calibrate(...)`` and ``OnlineCalibrator``: arrays of 4x4 transforms in, dicts out.
"""
from __future__ import annotations

import json
import math
import os
import warnings
from collections.abc import Mapping

import numpy as np

from ._handeye import _OnlineCalibrator
from ._handeye import advise_report as _advise_report
from ._handeye import calibrate_report as _calibrate_report
from ._handeye import read_recording as _read_recording
from ._handeye import solve_opencv as _solve_opencv
from ._handeye import solve_opencv_robot_world as _solve_opencv_robot_world
from ._handeye import solve_opencv_sequences as _solve_opencv_sequences
from ._handeye import verify_pixels_report as _verify_pixels_report
from ._handeye import verify_report as _verify_report

__all__ = ["calibrate_hand_eye", "calibrate_robot_world_hand_eye", "calibrate", "calibrate_on_pixels", "advise", "verify", "verify_on_pixels", "read_recording", "OnlineCalibrator", "METHODS"]

#: OpenCV's constants (cv2.CALIB_HAND_EYE_*) and handeye's names.
METHODS = {0: "tsai", 1: "park", 2: "horaud", 3: "andreff-joint", 4: "daniilidis"}

#: OpenCV's robot-world constants (cv2.CALIB_ROBOT_WORLD_HAND_EYE_*) and handeye's names.
ROBOT_WORLD_METHODS = {0: "shah", 1: "li"}


def calibrate_hand_eye(R_gripper2base, t_gripper2base, R_target2cam, t_target2cam, method=0, setup=None):
    """Drop-in for ``cv2.calibrateHandEye``; returns ``(R_cam2gripper, t_cam2gripper)`` as (3,3) and
    (3,1) arrays. ``method`` is an OpenCV constant (``cv2.CALIB_HAND_EYE_TSAI`` = 0, the default) or
    a handeye name ("andreff", "tsai", "park", "horaud", "andreff-joint", "daniilidis", "refine").
    Motions come from every pose pair, as in OpenCV. With OpenCV's constant for Tsai, OpenCV's
    motion filter is applied too (motions whose robot or camera rotation has 2·sin(θ/2) outside
    [0.3, 1.7] are dropped), so the answer is OpenCV's; with the name "tsai" every motion is kept.
    For eye-to-hand pass base2gripper poses, as with OpenCV, and get cam2base.

    ``setup`` ("eye-in-hand" or "eye-to-hand"; not in OpenCV) says which the arrays are. Without
    it the same arrays serve both, as in OpenCV: X and the target's pose of the sizes a fixed
    camera gives are also what a camera on the gripper gives with all four arrays inverted, and a
    ``UserWarning`` says so; an eye-to-hand call with all four arrays inverted looks exactly like a
    correct eye-in-hand one, and only ``setup="eye-to-hand"`` lets it be caught. Pass it.

    The decision is the command line's, made once in the library: the drop-in runs
    ``handeye calibrate --method M --pairs all`` (``--tsai-opencv-filter`` too for OpenCV's Tsai
    constant) and answers, warns or refuses as it does, with the same X. It raises ValueError on
    bad input, on poses that fit far better read another way (inverted arrays, millimetres on one
    side, rotations made from quaternions in the other order: the message says which arrays to
    change) and on motions that leave X undetermined, where OpenCV answers. Every caution of the
    command line's report (poses that disagree with the others, a weakly determined direction of
    X with the bootstrap's one-sigma, poses the others predict poorly, ...) is issued as a
    ``UserWarning``: use ``calibrate`` for the whole report."""
    name = METHODS.get(method, method) if isinstance(method, int) else method
    if not isinstance(name, str):
        raise ValueError(f"unknown method {method!r}")
    opencv_tsai = isinstance(method, int) and name == "tsai"
    # Lists of float64 arrays, as OpenCV's users pass them, are read in place by the extension;
    # anything else is stacked here first (same answer, and the messages for bad shapes).
    x = _solve_opencv_sequences(
        R_gripper2base, t_gripper2base, R_target2cam, t_target2cam, method=name,
        tsai_opencv_filter=opencv_tsai, setup=setup
    )
    if x is None:
        rg, tg = _arrays(R_gripper2base, t_gripper2base, "gripper2base")
        rc, tc = _arrays(R_target2cam, t_target2cam, "target2cam")
        x = _solve_opencv(rg, tg, rc, tc, method=name, tsai_opencv_filter=opencv_tsai, setup=setup)
    rotation, translation, said = x
    for text in said:
        warnings.warn(text, UserWarning, stacklevel=2)
    return rotation, translation


def calibrate_robot_world_hand_eye(R_world2cam, t_world2cam, R_base2gripper, t_base2gripper, method=0):
    """Drop-in for ``cv2.calibrateRobotWorldHandEye``; returns ``(R_base2world, t_base2world,
    R_gripper2cam, t_gripper2cam)`` as (3,3) and (3,1) arrays. OpenCV's problem is A X = Z B with
    A = world2cam (what PnP returns for a target that defines the world), B = base2gripper, X =
    base2world, Z = gripper2cam: a camera on the gripper. ``method`` is an OpenCV constant
    (``cv2.CALIB_ROBOT_WORLD_HAND_EYE_SHAH`` = 0, the default, or ``..._LI`` = 1) or a handeye
    name ("shah", "li", or "refine": both transforms refined together on every pose, the most
    accurate).

    The decision is the command line's (``handeye calibrate --robot-world --method M``), made once
    in the library: it answers with OpenCV's X and Z for Shah; for Li, OpenCV weighs rotations
    against translations in the input's unit (its answer changes with the unit), handeye in the
    poses' RMS translation, which is OpenCV's answer for the data expressed in that unit. It
    raises ValueError on bad input, on fewer than 3 poses, on poses that fit far better read
    another way (inverted arrays, millimetres on one side) and on motions that leave X or the
    target's pose undetermined, where OpenCV answers; every caution of the command line's report
    is issued as a ``UserWarning``: use ``calibrate(..., robot_world=True)`` for the whole report."""
    name = ROBOT_WORLD_METHODS.get(method, method) if isinstance(method, int) else method
    if not isinstance(name, str):
        raise ValueError(f"unknown method {method!r}")
    rc, tc = _arrays(R_world2cam, t_world2cam, "world2cam")
    rb, tb = _arrays(R_base2gripper, t_base2gripper, "base2gripper")
    r_w, t_w, r_z, t_z, said = _solve_opencv_robot_world(rc, tc, rb, tb, method=name)
    for text in said:
        warnings.warn(text, UserWarning, stacklevel=2)
    return r_w, t_w, r_z, t_z


def _arrays(rotations, translations, name: str):
    """(N, 3, 3) rotations or (N, 3) rotation vectors, and (N, 3) translations, as float arrays
    (the rotation vectors become matrices in the extension: R = I + sin θ [k]× + (1 − cos θ) [k]×²)."""
    try:
        r = np.asarray(rotations, dtype=np.float64)
    except ValueError as e:
        raise ValueError(f"{name}: rotations of mixed shapes ({e})") from None
    if r.ndim >= 2 and r.shape[0] > 0 and r.shape[1:] != (3, 3) and r[0].size == 3:
        r = r.reshape(len(r), 3)
    elif r.ndim != 3 or r.shape[1:] != (3, 3):
        raise ValueError(f"{name}: a rotation must be a 3x3 matrix or a rotation vector, got shape {r.shape[1:]}")
    try:
        t = np.asarray(translations, dtype=np.float64)
    except ValueError as e:
        raise ValueError(f"{name}: translations of mixed shapes ({e})") from None
    if len(t) != len(r) or t.size != 3 * len(r):
        raise ValueError(f"{name}: {len(r)} rotations need {len(r)} translations of 3 entries, got shape {t.shape}")
    return r, t.reshape(len(r), 3)


def calibrate(
    base_from_gripper=None,
    camera_from_target=None,
    method=None,
    setup="eye-in-hand",
    pairs=None,
    reject_outliers=False,
    fix=None,
    bootstrap=40,
    robot_world=False,
    tsai_opencv_filter=False,
    point=None,
    joints=None,
    prior=None,
    robot_model=None,
    *,
    path=None,
    intrinsics=None,
    refine_intrinsics=False,
    base_frame=None,
    gripper_frame=None,
    camera_frame=None,
    target_topic=None,
    tag_size=None,
    tag_id=None,
    camera_info_topic=None,
    time_offset=None,
    max_gap=0.1,
    goal=None,
) -> dict:
    """Batch calibration from (N,4,4) arrays, with its uncertainty, or a ValueError that says why
    X cannot be trusted and what to do. Returns the same object ``handeye calibrate`` prints, as a
    dict: ``verdict`` ("good", or "questionable" while a caution of ``warnings`` stands, as every
    face says it), ``matrix`` (X, a (4,4) array), ``translation``, ``quaternion_xyzw``, ``frame``,
    ``method``, ``setup``, ``poses``, ``motions``, ``conditioning``, ``uncertainty``
    (``rotation_deg`` and ``translation``: one-sigma sizes of the error; ``weakest_rotation``,
    ``weakest_translation``, ``covariance``, ``at_point``: the one-sigma error of the median target
    position mapped through X), ``reading`` (the readings of the input tried),
    ``outliers`` (poses that disagree with the others), ``residual``, ``quality`` and
    ``warnings`` (each a dict: ``code``, its data, ``message`` in words and, when one argument
    of this call would fix it, ``remedy``: ``option`` (the keyword), ``value`` and ``purpose``). ``fix`` reads the input another way ("auto", "as-given", "robot-inverted",
    "camera-inverted", "both-inverted", "robot-wxyz", "camera-wxyz", "both-wxyz", "robot-mm",
    "camera-mm"). ``method`` defaults to "andreff", ``pairs`` to "all" (every pair of poses, as
    ``handeye calibrate``; "consecutive" for the paper's pairing). ``tsai_opencv_filter`` (with
    ``method="tsai"``) drops the motions OpenCV's Tsai drops, as ``--tsai-opencv-filter`` does.
    ``point`` (X, Y, Z in the camera frame, the input's unit) is where ``uncertainty.at_point``
    gives the error, as ``--point`` does (default: the median target position seen). ``joints``
    (every pose's joint angles, radians: what ``read_recording`` returns under ``joints``) orders
    the poses for the systematic-error test and names the joint the residual follows, as the
    command line does with a JSON Lines file's ``joints``. ``prior`` states components of X's
    translation a low-DOF robot (a SCARA, a 4-axis arm: every motion turns about one axis) cannot
    determine, as ``--prior`` does: ``"tz=0.12+-0.002"`` (or ``"tz=0.12"``, exact), a list of
    such, or a dict ``{"tz": 0.12}`` / ``{"tz": (0.12, 0.002)}``; ``tx``, ``ty``, ``tz`` in X's
    parent frame and the input's length unit. The report then has ``prior`` and ``low_dof``.
    ``robot_model`` (a path to the robot's DH table, JSON, as ``--robot-model``; with ``joints``)
    lets the systematic-error test ask whether the residuals follow an error of the table's
    parameters (``systematic["kinematic"]``): an uncalibrated robot is then seen at 1 mm. A table
    that does not turn the hand as the poses do, or in another unit, raises a ValueError.
    ``goal`` (``(degrees, length)``: the one-sigma rotation and translation you need, the input's
    unit, as ``advise(goal=...)`` and ``--goal``): an X whose one-sigma uncertainty is above it in
    either is not "good" (warning ``goal_missed``); the report's ``goal`` says whether it is met.

    With ``robot_world=True`` X and the target's pose are solved together from every pose once
    (A X = Z B; ``method`` "shah", "li" or "refine", the default; ``pairs`` does not apply): the same object ``handeye calibrate --robot-world`` prints,
    with ``target`` (``frame`` "base_from_target" or "gripper_from_target", ``matrix`` as a (4,4)
    array, ``translation``, ``quaternion_xyzw``, ``uncertainty``) and ``residual`` per pose. On a
    low-DOF robot ``prior`` gives X's free component as above; the target's coupled component
    follows from it (``calibrate --robot-world --prior``).

    On the pixels: ``calibrate(path, intrinsics=...)`` (or ``path=``) calibrates a recording whose
    records carry the target's detections, as ``calibrate_on_pixels`` describes (its keywords:
    ``intrinsics``, ``refine_intrinsics``, ``base_frame`` … ``max_gap``); ``method`` is then the fit
    to the pixels ("reprojection"), for either problem. One function for every problem and input
    kind: the same object ``handeye calibrate`` prints for the same input and flags."""
    if path is None and camera_from_target is None and isinstance(base_from_gripper, (str, os.PathLike)):
        path, base_from_gripper = base_from_gripper, None
    if path is not None:
        if robot_world and pairs is not None:
            raise ValueError("pairs does not apply to robot_world=True, which uses every pose once")
        if base_from_gripper is not None or camera_from_target is not None:
            raise ValueError("give either the poses (base_from_gripper, camera_from_target) or a path, not both")
        if method not in (None, "reprojection"):
            raise ValueError(f"method={method!r}: a recording with detections is calibrated on its pixels (method \"reprojection\")")
        report = _calibrate_report(
            path=str(path),
            intrinsics=None if intrinsics is None else str(intrinsics),
            setup=setup,
            robot_world=robot_world,
            reject_outliers=reject_outliers,
            fix=fix,
            point=_point(point),
            prior=_priors(prior),
            refine_intrinsics=bool(refine_intrinsics),
            base_frame=base_frame,
            gripper_frame=gripper_frame,
            camera_frame=camera_frame,
            target_topic=target_topic,
            tag_size=None if tag_size is None else float(tag_size),
            tag_id=None if tag_id is None else int(tag_id),
            camera_info_topic=camera_info_topic,
            time_offset=time_offset,
            max_gap=float(max_gap),
            goal=_goal(goal),
        )
    else:
        g, c = _transforms(base_from_gripper, camera_from_target)
        if robot_world and pairs is not None:
            raise ValueError("pairs does not apply to robot_world=True, which uses every pose once")
        report = _calibrate_report(
            g,
            c,
            method=method or None,
            setup=setup,
            robot_world=robot_world,
            pairs=pairs or "all",
            tsai_opencv_filter=tsai_opencv_filter,
            reject_outliers=reject_outliers,
            fix=fix,
            bootstrap=bootstrap,
            point=_point(point),
            joints=joints,
            prior=_priors(prior),
            robot_model=robot_model,
            goal=_goal(goal),
        )
    result = json.loads(report)
    result["matrix"] = np.array(result["matrix"], dtype=np.float64)
    if robot_world:
        result["target"]["matrix"] = np.array(result["target"]["matrix"], dtype=np.float64)
    return result


def _priors(prior):
    """Priors in the command line's syntax ("tz=0.12+-0.002"), from a string, a list of strings or
    a dict of name -> value or (value, sigma); None for none."""
    if prior is None:
        return None
    if isinstance(prior, str):
        return [prior]
    if isinstance(prior, dict):
        out = []
        for name, v in prior.items():
            if np.ndim(v) == 0:
                value, sigma = v, 0.0
            elif np.shape(v) == (2,):
                value, sigma = v
            else:
                raise ValueError(f"prior {name!r}: expected a value or (value, sigma), got {v!r}")
            out.append(f"{name}={float(value)!r}+-{float(sigma)!r}")
        return out
    if isinstance(prior, (list, tuple)) and all(isinstance(p, str) for p in prior):
        return list(prior)
    raise ValueError(f"prior: expected \"tz=VALUE+-SIGMA\", a list of such, or a dict, got {prior!r}")


def _rotations(rotation):
    """Rotation conventions in the command line's syntax ("kuka-abc", "robot=rvec"), from a
    string, a list of strings or a dict of side -> name; None for none."""
    if rotation is None:
        return None
    if isinstance(rotation, str):
        return [rotation]
    if isinstance(rotation, dict):
        return [f"{side}={name}" for side, name in rotation.items()]
    if isinstance(rotation, (list, tuple)) and all(isinstance(r, str) for r in rotation):
        return list(rotation)
    raise ValueError(
        f"rotation: expected a name (\"kuka-abc\"), \"robot=NAME\" or \"camera=NAME\", a list of such, or a dict, got {rotation!r}"
    )


def _point(point):
    """A point as three floats, or None."""
    if point is None:
        return None
    p = np.asarray(point, dtype=np.float64).reshape(-1)
    if p.shape != (3,):
        raise ValueError(f"point: expected three numbers (X, Y, Z in the camera frame), got shape {np.shape(point)}")
    return [float(v) for v in p]


def verify(saved, base_from_gripper, camera_from_target, *, setup=None, method=None, pairs=None, reject_outliers=False, bootstrap=40, joints=None, prior=None, fix=None, tolerance=None):
    """Whether a saved X still fits a new recording, as ``handeye verify --x SAVED`` decides it.
    ``saved`` is the path of what ``handeye calibrate --output json`` or ``--output yaml`` wrote
    (easy_handeye2's calibration file too; metres converted to the recording's millimetres when
    the sizes say so). Takes (N, 4, 4) arrays of the new recording.

    Returns the command line's object as a dict: ``verdict`` ("consistent", "inconsistent" or
    "undetermined"), ``difference`` and ``sigma`` (``rotation_deg``, ``translation``: the saved X
    minus the recording's, and one sigma of that difference from the uncertainty of both),
    ``distance_sigmas`` against ``limit_sigmas``, ``saved`` (the saved X, ``matrix`` a (4,4)
    array), ``quality`` of the recording's own calibration, ``message`` (what the verdict means and
    what to do) and ``notes``. A recording that cannot be read or solved at all raises ValueError.
    ``prior`` is ``calibrate``'s; without one, the component of X a low-DOF recording leaves free
    is taken from the saved X and the rest is checked (a note says so). ``fix`` reads the new
    recording another way, as ``calibrate``'s (``verify --fix``). ``setup`` is the saved file's
    when it declares one (a different one raises ValueError naming both), else eye-in-hand.
    ``detectable`` (``rotation_deg``, ``translation``) is the smallest change of X the recording
    would call inconsistent; ``tolerance=(degrees, length)`` (the recording's unit, as
    ``verify --tolerance``) makes a consistent X whose recording could not see a change of that
    size ``undetermined``."""
    g, c = _transforms(base_from_gripper, camera_from_target)
    result = json.loads(
        _verify_report(
            str(saved),
            g,
            c,
            setup=setup,
            method=method or "andreff",
            pairs=pairs or "all",
            reject_outliers=reject_outliers,
            bootstrap=bootstrap,
            joints=joints,
            prior=_priors(prior),
            fix=fix,
            tolerance=_tolerance(tolerance),
        )
    )
    result["saved"]["matrix"] = np.array(result["saved"]["matrix"], dtype=np.float64)
    if isinstance(result.get("recording"), dict) and "matrix" in result["recording"]:
        result["recording"]["matrix"] = np.array(result["recording"]["matrix"], dtype=np.float64)
    return result


def _tolerance(tolerance):
    """A tolerance as two floats (degrees, length), or None."""
    if tolerance is None:
        return None
    t = [float(v) for v in tolerance]
    if len(t) != 2:
        raise ValueError(f"tolerance: expected (degrees, length), got {tolerance!r}")
    return (t[0], t[1])


def verify_on_pixels(saved, path, intrinsics, *, setup=None, fix=None, tolerance=None) -> dict:
    """Whether a saved X still fits a new recording with detections, checked on its pixels as
    ``handeye verify --x SAVED PATH --intrinsics INTRINSICS`` does: the recording calibrated on
    the pixels (``calibrate_on_pixels``) and its X compared with the saved one by ``verify``'s test
    and words. The dict is ``verify``'s plus ``pixels``: ``saved_rms_px`` and ``own_rms_px`` (the
    reprojection RMS of the recording's detections with the saved X and with its own, the target's
    pose fitted to each) and ``per_frame`` (``name``, ``saved_px``, ``own_px``)."""
    result = json.loads(_verify_pixels_report(str(saved), str(path), str(intrinsics), setup=setup, fix=fix, tolerance=_tolerance(tolerance)))
    result["saved"]["matrix"] = np.array(result["saved"]["matrix"], dtype=np.float64)
    if isinstance(result.get("recording"), dict) and "matrix" in result["recording"]:
        result["recording"]["matrix"] = np.array(result["recording"]["matrix"], dtype=np.float64)
    return result


def _transforms(base_from_gripper, camera_from_target):
    """The two pose lists as contiguous (N, 4, 4) float arrays."""
    g = np.ascontiguousarray(base_from_gripper, dtype=np.float64)
    c = np.ascontiguousarray(camera_from_target, dtype=np.float64)
    if g.ndim != 3 or c.ndim != 3:
        raise ValueError("expected (N, 4, 4) arrays of transforms")
    return g, c


def advise(base_from_gripper, camera_from_target, setup="eye-in-hand", count=3, prior=None, goal=None):
    """What to record next, as ``handeye advise`` prints it: X's one-sigma now (``current``), its
    least determined directions (``weakest``) and the next gripper motions (``suggestions``: an
    axis of the gripper frame, an angle, and the uncertainty predicted once recorded). Takes
    (N, 4, 4) arrays. ``prior`` as for ``calibrate`` (``"tz=0.12+-0.002"``, a list, or a dict): it
    enters the uncertainty with its sigma, and on a low-DOF recording (every motion about one axis)
    the advice is then for that robot (``low_dof`` says so): turns about its one axis. ``goal``
    (degrees, length in the input's unit: the one-sigma X you need) adds ``goal``: ``done`` when X
    is within it now (and no suggestion), else ``after``: the suggested motion after which the
    prediction is."""
    g, c = _transforms(base_from_gripper, camera_from_target)
    return json.loads(_advise_report(g, c, setup=setup, count=count, prior=_priors(prior), goal=_goal(goal)))


def _goal(goal):
    """``goal`` as the library takes it: ``(degrees, length)`` as two floats, or None."""
    if goal is None:
        return None
    goal = tuple(float(v) for v in goal)
    if len(goal) != 2:
        raise ValueError("goal: expected (degrees, length), a one-sigma rotation and translation")
    return goal


def calibrate_on_pixels(
    path,
    intrinsics=None,
    *,
    setup="eye-in-hand",
    robot_world=False,
    fix=None,
    point=None,
    refine_intrinsics=False,
    base_frame=None,
    gripper_frame=None,
    camera_frame=None,
    target_topic=None,
    tag_size=None,
    tag_id=None,
    camera_info_topic=None,
    time_offset=None,
    max_gap=0.1,
) -> dict:
    """Calibration on the pixels of the detections, ``calibrate(path, ...)`` under the name it had
    before ``calibrate`` took every input kind: a JSON Lines file whose records carry
    ``detections`` (``target`` points and their ``pixels``) and the camera's ``intrinsics`` (OpenCV
    FileStorage YAML or a ROS ``camera_info`` YAML). Returns the same object ``handeye calibrate
    PATH --method reprojection --intrinsics INTRINSICS`` prints, as a dict (``matrix`` a (4,4)
    array), with ``reprojection`` (``rms_px``, ``per_frame``, ``outlier_detections``, ...). With
    ``robot_world=True`` the robot-world result of ``calibrate(..., robot_world=True)``
    (``--robot-world``): X and ``target`` (its ``matrix`` a (4,4) array), each with its
    uncertainty from the pixel solve, ``method`` "reprojection". ``fix`` ("auto", "as-given",
    "robot-inverted") and ``point`` as in ``calibrate``. ``refine_intrinsics=True``
    (``--refine-intrinsics``) refines fx, fy, cx, cy, k1, k2, p1, p2 with X (k3 kept as given):
    ``reprojection["intrinsics"]`` gives them with their ``sigma``, and X's uncertainty accounts for
    them. Raises ValueError where the command line refuses (robot poses that fit the pixels far
    better inverted, a fit far above detection noise, frames that do not determine the intrinsics,
    bad input naming the file, line and field).

    ``path`` may also be a ROS 2 recording (a rosbag2 directory, an ``.mcap`` or a ``.db3`` file)
    of a tag's detections, as ``handeye calibrate BAG --method reprojection --target-topic T
    --tag-size S`` reads it: ``base_frame``, ``gripper_frame``, ``camera_frame`` (tf),
    ``target_topic`` (``apriltag_msgs/msg/AprilTagDetectionArray``), ``tag_size`` (the side of
    the tag's black square, metres), ``tag_id`` (when the recording shows several), the
    intrinsics from ``intrinsics`` or else the recording's ``CameraInfo`` topic
    (``camera_info_topic`` when it has several), ``time_offset`` (seconds; 0 by default) and
    ``max_gap`` as in ``read_recording``."""
    return calibrate(
        path=path,
        intrinsics=intrinsics,
        setup=setup,
        robot_world=robot_world,
        fix=fix,
        point=point,
        refine_intrinsics=refine_intrinsics,
        base_frame=base_frame,
        gripper_frame=gripper_frame,
        camera_frame=camera_frame,
        target_topic=target_topic,
        tag_size=tag_size,
        tag_id=tag_id,
        camera_info_topic=camera_info_topic,
        time_offset=time_offset,
        max_gap=max_gap,
    )


def read_recording(
    path=None,
    *,
    format="auto",
    robot=None,
    camera=None,
    base_frame=None,
    gripper_frame=None,
    camera_frame=None,
    target_frame=None,
    target_topic=None,
    setup="eye-in-hand",
    time_offset=None,
    max_gap=0.1,
    rotation=None,
) -> dict:
    """Reads any input as ``handeye calibrate`` does (the library's ``io::Recording``): a pose
    file (``format`` "auto", "jsonl", "csv", "opencv-yaml", "moveit" or "visp"; a directory of
    ViSP pose files), two stamped streams ``robot`` and ``camera`` (``t x y z qx qy qz qw``,
    paired at the camera's stamps), or a ROS 2 recording (a rosbag2 directory, an ``.mcap`` or a
    ``.db3`` file) with ``base_frame``, ``gripper_frame``, ``camera_frame`` and ``target_frame``
    (or ``target_topic``). ``time_offset`` (streams and recordings): camera clock minus robot
    clock in seconds, or "auto" to estimate it (ValueError when the streams cannot tell); None
    (the default) estimates it when the streams allow, else pairs at 0 s with a note; ``max_gap``: the longest gap of the robot's poses
    interpolated across, seconds. ``rotation`` names how the input writes rotations where its
    numbers cannot say (as ``--rotation`` does): the streams' columns after ``t x y z`` and CSV
    columns (``<frame>_a, _b, _c`` for "kuka-abc", …); JSON fields name their own
    (``kuka_abc_deg``, ``rvec``, …). A name for every pose ("kuka-abc"), "robot=NAME" or
    "camera=NAME" for one side, a list of those, or a dict ``{"robot": NAME, "camera": NAME}``;
    NAME one of "quaternion-xyzw" (the default), "quaternion-wxyz" (ABB's q1..q4), "rvec"
    (radians), "kuka-abc", "mitsubishi-abc", "fanuc-wpr", "yaskawa-rxryrz", "staubli-xyz",
    "kawasaki-oat" (degrees), "rpy" (radians) or "rpy-deg".

    Returns a dict: ``base_from_gripper`` and ``camera_from_target`` ((N, 4, 4) arrays, ready for
    ``calibrate``), ``names`` (each pose's name in messages), ``lines`` (its line, sample or
    message number), ``stamps`` (seconds, or None), ``time_offset`` (the offset used, or None for a pose
    file), ``time_offset_sigma`` (its one-sigma in seconds when it was estimated, else None),
    ``offset_curve`` (with "auto": a (K, 2) array of offset and correlation, else None),
    ``target_source`` (a recording's target topic or tf edge, else None), ``camera_mount`` (when
    a recording's tf gives the camera frame a parent, as it gives an optical frame under
    ``camera_link``: a dict of ``camera``, ``root``, the root of the camera's subtree, which X is
    published for as ``X @ inv(root_from_camera)``, ``root_from_camera`` (4x4, or None when a
    transform between them moves), ``placed_under`` (the robot's frame the root hangs from when
    the camera is placed in tf already, else None) and ``tf_x`` (X as tf has it then); else
    None), ``joints`` (each pose's
    joint angles where a JSON Lines file gives them, for ``calibrate(joints=...)``, else None) and ``notes`` (what
    ``handeye`` prints on stderr while reading). Bad input raises ValueError naming the file,
    line and field."""
    return _read_recording(
        None if path is None else str(path),
        format=format,
        robot=None if robot is None else str(robot),
        camera=None if camera is None else str(camera),
        base_frame=base_frame,
        gripper_frame=gripper_frame,
        camera_frame=camera_frame,
        target_frame=target_frame,
        target_topic=target_topic,
        setup=setup,
        time_offset=time_offset,
        max_gap=max_gap,
        rotation=_rotations(rotation),
    )


def _with_arrays(event):
    """The event with its ``matrix`` (and its target's, its optimal X's) as 4x4 arrays."""
    for d in (event, event.get("target"), event.get("optimal")):
        if isinstance(d, dict) and isinstance(d.get("matrix"), list):
            d["matrix"] = np.array(d["matrix"], dtype=np.float64)
    return event


def _json_numbers(value):
    """Arrays and nested sequences as JSON lists; a number that is not finite as its text, so that
    the reader of the record names its field rather than failing on the JSON."""
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, Mapping):
        return {str(k): _json_numbers(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_numbers(v) for v in value]
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else str(float(value))
    if isinstance(value, np.integer):
        return int(value)
    return value


class OnlineCalibrator:
    """The online calibrator: ``push`` one pose pair at a time and get what it reports.

    Keyword arguments: ``selection`` ("adaptive", "fixed", "none"), ``setup``, ``estimator``
    ("accumulate", the default as on the command line: every pair of poses, outliers held out,
    each estimate with its uncertainty; or "paper", the paper's method, no uncertainty),
    ``error_source`` ("residual", "truth"), ``truth`` (4x4 X),
    ``optimal`` and the adaptive parameters ``n_init, interval, relax_down, relax_up, explore,
    rms_r_max, rms_t_max, alpha_min_deg, beta_min_deg, d_max`` (``alpha_min_deg`` in degrees,
    (0, 90]; the older ``alpha_min``, its sine, still works with a DeprecationWarning;
    ``d_max`` in your length unit;
    left out, it is 0.1 m in the ``unit``: "auto" infers metres or millimetres from the first
    pose, "m", "mm"), ``unfreeze``; for ``estimator="accumulate"`` also ``every`` and ``shrink``
    (how often it reports) and ``point`` (where each report's ``uncertainty.at_point`` gives the
    error, camera frame; default the mean target position seen) and ``prior``, ``calibrate``'s, for
    a low-DOF robot (a SCARA: every rotation about one axis): ``"tz=0.12+-0.002"``, a list of such
    or a dict; while the rotations are about one axis, X is solved with the prior's component and
    each report has ``prior`` and ``low_dof`` (a prior in another length unit than the poses raises
    ``ValueError`` from ``push`` once the first 16 poses tell the unit, or from ``finish``). With the paper's estimator, the first 64 poses (a shorter stream's, at
    ``finish()``) are checked as ``handeye online`` checks them: a ``UserWarning`` when they fit far
    better read another way, have sizes the setup makes unlikely, or turn about one axis.
    ``robot_model`` (a path to the robot's DH table, as ``calibrate(robot_model=...)``; push the
    poses with their ``joints``) gives the accumulating estimator's systematic-error test the
    table's statistic; a table that is not the robot's raises ``ValueError`` from ``push`` at the
    first test (12 poses) or from ``finish``.
    With ``estimator="accumulate"``, ``push`` returns the estimator's own
    reports (``estimate``, X as ``matrix``, ``uncertainty``, ``target``, ...) and changes
    (``change``), the same fields as ``handeye online --estimator accumulate`` prints.

    On the pixels: with ``intrinsics`` (a path: OpenCV YAML or ROS camera_info) the calibrator
    takes records with detections (``push_detections`` or ``push_record``, not ``push``) and
    calibrates X on their pixels as ``calibrate_on_pixels`` does, reporting an estimate at 16,
    32, 64, ... records and at ``finish()`` (which raises ``ValueError`` when the calibration on
    the pixels refuses the records): the same objects ``handeye online --intrinsics`` prints, with
    ``estimator`` "reprojection" and the fit in ``reprojection`` (``rms_px``, ``sigma_px``, ...).
    ``point`` applies; ``estimator="paper"``, ``optimal``, ``truth`` and ``prior`` are refused."""

    def __init__(self, **params):
        # The library applies the settings' rules (defaults, degrees, d_max as given).
        if "alpha_min_deg" in params:
            if "alpha_min" in params:
                raise ValueError("alpha_min_deg and alpha_min (deprecated) name one parameter: give one")
        elif "alpha_min" in params:
            warnings.warn(
                "alpha_min (a sine) is deprecated: use alpha_min_deg (degrees)",
                DeprecationWarning,
                stacklevel=2,
            )
        truth = params.pop("truth", None)
        if truth is not None:
            truth = np.ascontiguousarray(truth, dtype=np.float64)
        if params.get("prior") is not None:
            params["prior"] = _priors(params["prior"])
        self._inner = _OnlineCalibrator(truth=truth, **params)

    def push(self, base_from_gripper, camera_from_target, joints=None):
        """Pushes one pose pair (4x4 arrays). Returns a list, usually empty: the reports and
        changes of the accumulating estimator, or the events of the calibrations the paper's
        estimator completes (each a dict, X's ``matrix`` a (4,4) array). ``joints``: the robot's
        joint angles at the pose (radians, every pose the same joints); the accumulating
        estimator's systematic-error test then names the joint whose angle the residual follows
        (``warnings`` of a report: ``systematic_error``)."""
        events = self._inner.push(
            np.ascontiguousarray(base_from_gripper, dtype=np.float64),
            np.ascontiguousarray(camera_from_target, dtype=np.float64),
            None if joints is None else [float(q) for q in joints],
        )
        self._warn_readings()
        return [_with_arrays(e) for e in events]

    def push_detections(self, base_from_gripper, detections, camera_from_target=None):
        """Pushes one record on the pixels (needs ``intrinsics``): the robot pose (4x4), the
        detections ``{"target": [[x, y, z], ...], "pixels": [[u, v], ...]}`` (SPEC sec. 9, the
        target's points in the robot's length unit) and optionally the camera pose (4x4). Returns
        the estimates it completes (a list, usually empty). A bad record raises ``ValueError``
        naming its field and is not kept."""
        record = {
            "base_from_gripper": {"matrix": _json_numbers(base_from_gripper)},
            "detections": _json_numbers(detections),
        }
        if camera_from_target is not None:
            record["camera_from_target"] = {"matrix": _json_numbers(camera_from_target)}
        return self.push_record(json.dumps(record))

    def push_record(self, line):
        """Pushes one record on the pixels as its JSON text (a line of a JSON Lines recording
        with ``detections``, as ``handeye online --intrinsics`` reads it). Returns the estimates
        it completes; a bad record raises ``ValueError`` naming its field and is not kept."""
        return [_with_arrays(e) for e in self._inner.push_record(line)]

    def finish(self):
        """The accumulating estimator's final report (a dict), or None: call it at the end of the
        stream (with either estimator: a short stream's readings are checked then). A report whose
        uncertainty is above the reporting bounds carries ``weak``."""
        try:
            text = self._inner.finish()
        finally:
            # What the end found is told even when finish raises (a refusal at the end).
            self._warn_readings()
        return None if text is None else _with_arrays(json.loads(text))

    def _warn_readings(self):
        # What the command line tells: the check of the first 64 poses (of a shorter stream of 16
        # or more, at finish()), data read wrongly, implausible sizes, or rotations about one
        # axis; the paper's selection stuck (no calibration in 200, 400, ... poses); the poses the
        # accumulating estimator held out; on the pixels, the solve's cautions.
        for found in self._inner.take_warnings():
            warnings.warn(found, UserWarning, stacklevel=3)

    def last_report(self):
        """The estimate to use now (a dict, as a report), or None: the accumulating estimator's
        last report since the last change of X, unless the readings were found misread since
        (``pending()`` says why there is none). A report from before a change is not the
        current X: use this, not the last report ``push`` returned."""
        text = self._inner.last_report()
        return None if text is None else _with_arrays(json.loads(text))

    def pending(self):
        """Why the accumulating estimator has nothing to report now (a sentence), or None."""
        return self._inner.pending()

    @property
    def poses(self) -> int:
        return self._inner.poses()

    @property
    def calibrations(self) -> int:
        return self._inner.calibrations()

    def state(self) -> str:
        """The whole state as a JSON string."""
        return self._inner.state()

    @classmethod
    def from_state(cls, state: str) -> "OnlineCalibrator":
        """A calibrator that continues exactly where ``state()`` was taken."""
        obj = cls.__new__(cls)
        obj._inner = _OnlineCalibrator.from_state(state)
        return obj
