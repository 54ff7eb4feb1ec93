#!/usr/bin/env python3
"""Generate handeye's kinhec test suite (this folder) with kinhec 1.1.0.

    python -m venv v && v/bin/pip install kinhec==1.1.0 && v/bin/python testdata/kinhec/generate.py

Deterministic: every sequence is seeded from GLOBAL_SEED and its file name (kinhec's own
``seed_for``), so the output depends neither on the number of worker processes nor on the order
in which they finish.  Writes, next to this script:

* ``pairs/<kind>_<variant>_<setup>_s<k>.jsonl`` + ``.truth.json``: synchronised pose pairs
  (JSON Lines, ``base_from_gripper`` / ``camera_from_target``) subsampled from one kinhec sequence;
* ``mistakes/<mistake>_<base>.jsonl`` + ``.truth.json``: nominal files with a typical user mistake;
* ``streams/<name>_robot.txt`` / ``_camera.txt``: TUM streams (``t x y z qx qy qz qw``), robot =
  base_from_gripper, camera = target_from_camera, camera clock shifted by a known offset;
* ``manifest.json``: every file with its kind, setup, robot, seed, noise, truth, kinhec recipe,
  observability descriptors, outlier lines and (for mistakes) what was done and the right answer.

Frame mapping (kinhec ``T_a_b`` = pose of b in a = handeye ``a_from_b``):
  eye-in-hand: base_from_gripper = T_base_ee, camera_from_target = T_cam_target,
               X = gripper_from_camera = T_ee_cam (kinhec X), base_from_target = kinhec Y;
  eye-to-hand: base_from_gripper = T_base_ee, camera_from_target = T_cam_marker,
               X = base_from_camera = T_base_cam (kinhec Y), gripper_from_target = kinhec X.
The script asserts on the ground-truth poses of every file that
base_from_gripper · X · camera_from_target (eye-in-hand) or
gripper_from_base · X · camera_from_target (eye-to-hand) is the constant target pose.
"""
from __future__ import annotations

import json
import os
import pickle
import re

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):  # small matrices: one BLAS thread per worker
    os.environ.setdefault(_v, "1")
import shutil
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

import kinhec
from kinhec import motions, se3
from kinhec.config import (
    SequenceConfig,
    default_camera_noise,
    default_outliers,
    default_robot_noise,
    default_sampling,
    default_timing,
)
from kinhec.generator import generate_sequence
from kinhec.plans import joint_subset, seed_for
from kinhec.robots import ROBOTS

OUT = Path(__file__).resolve().parent
GLOBAL_SEED = 20260101
KINHEC_VERSION = "1.1.0"
DIGITS = 10  # significant digits of the noisy data (the noise-free files get 17)

# Noise levels (kinhec's tier levels r1..r3, c2, c4).
ROBOT_NOMINAL = (0.0005, 0.0003)  # rad, m (kinhec r2)
ROBOT_LOW = (0.0002, 0.0001)  # kinhec r1 (used with PnP, as kinhec's pnp track does)
ROBOT_HIGH = (0.002, 0.001)  # kinhec r3
CAM_NOMINAL = (0.002, [0.001, 0.001, 0.003])  # rad, m (x, y, z = optical axis) (kinhec c2)
CAM_HIGH = (0.01, [0.006, 0.006, 0.02])  # kinhec c4

TARGET_EIH = "checker_9x6_25mm"
TARGET_ETH = "marker_3x3_30mm"
TEMPORAL_EXCITATION = {"n_harmonics": 3, "f_min": 0.1, "f_max": 0.6, "speed_frac": 0.35}  # kinhec's temporal track
ROBOT_STREAM_HZ = 100.0  # robot streams are decimated to this rate (kinhec: native rate capped at 500 Hz)

SETUPS = {"eih": "eye_in_hand", "eth": "eye_to_hand"}
HANDEYE_SETUP = {"eih": "eye-in-hand", "eth": "eye-to-hand"}


# ----------------------------------------------------------------------------------------------
# recipes
# ----------------------------------------------------------------------------------------------
def robot_noise(level=ROBOT_NOMINAL, student_t_dof=None):
    rn = default_robot_noise()
    rot, tr = level
    rn.update({"models": ["se3_gaussian"] if (rot > 0 or tr > 0) else ["none"], "rot_std_rad": float(rot), "trans_std_m": float(tr), "student_t_dof": student_t_dof})
    return rn


def camera_noise(level=CAM_NOMINAL, student_t_dof=None):
    cn = default_camera_noise()
    rot, tr = level
    cn.update({"model": "se3_gaussian" if (rot > 0 or max(tr) > 0) else "none", "rot_std_rad": [float(rot)] * 3, "trans_std_m": [float(v) for v in tr], "student_t_dof": student_t_dof})
    return cn


def stations(n):
    s = default_sampling()
    s.update({"mode": "stations", "n_stations": int(n)})
    return s


def continuous(duration_s, rate_hz, sync="synchronous", robot_rate_hz=None):
    s = default_sampling()
    s.update({"mode": "continuous", "duration_s": float(duration_s), "camera_rate_hz": float(rate_hz), "sync": sync, "robot_rate_hz": robot_rate_hz})
    return s


def make_cfg(name, *, robot, setup, family, fp=None, sampling, rn, cn, ol=None, timing=None, camera="hd", target=None, tags=None):
    cfg = SequenceConfig(
        sequence_id=name,
        track="handeye_suite",
        level=name,
        seed=seed_for(GLOBAL_SEED, name),
        robot=robot,
        configuration=SETUPS[setup],
        family=family,
        family_params=dict(fp or {}),
        sampling=sampling,
        timing=timing or default_timing(),
        robot_noise=rn,
        camera_noise=cn,
        outliers=ol or default_outliers(),
        camera=camera,
        target=target or (TARGET_EIH if setup == "eih" else TARGET_ETH),
        tags=dict(tags or {}),
    )
    cfg.validate()
    return cfg


def pose_pair_jobs():
    """(name, kind, variant, setup, seed index, n_poses, cfg, extra) for every pose-pair file."""
    jobs = []

    def add(kind, variant, setup, k, n, cfg, **extra):
        jobs.append(dict(name=cfg.sequence_id, kind=kind, variant=variant, setup=setup, k=k, n=n, cfg=cfg, extra=extra))

    arms = ["ur5", "panda", "iiwa14", "ur10e", "irb120", "ur5e"]
    n_poses = [40, 50, 30]

    # noise-free anchors: the frame check (every solver must recover X exactly)
    for setup in ("eih", "eth"):
        name = f"noise_free_stations_{setup}_s0"
        add("noise_free", "stations", setup, 0, 40, make_cfg(name, robot="ur5e", setup=setup, family="lookat", fp={"n_waypoints": 40}, sampling=stations(40), rn=robot_noise((0, 0)), cn=camera_noise((0, [0, 0, 0]))))
        name = f"noise_free_continuous_{setup}_s0"
        add("noise_free", "continuous", setup, 0, 40, make_cfg(name, robot="panda", setup=setup, family="joint_sinusoid", sampling=continuous(60, 10), rn=robot_noise((0, 0)), cn=camera_noise((0, [0, 0, 0]))))

    for setup in ("eih", "eth"):
        for k in range(3):
            n = n_poses[k]
            # nominal: look-at station captures and continuous joint-space trajectories
            name = f"nominal_stations_{setup}_s{k}"
            add("nominal", "stations", setup, k, n, make_cfg(name, robot=arms[k + (3 if setup == "eth" else 0)], setup=setup, family="lookat", fp={"n_waypoints": n}, sampling=stations(n), rn=robot_noise(), cn=camera_noise()))
            name = f"nominal_continuous_{setup}_s{k}"
            add("nominal", "continuous", setup, k, n, make_cfg(name, robot=arms[(k + 2) % 6], setup=setup, family="joint_sinusoid", sampling=continuous(60, 10), rn=robot_noise(), cn=camera_noise()))
            # high noise (kinhec r3 x c4)
            name = f"high_noise_continuous_{setup}_s{k}"
            add("high_noise", "continuous", setup, k, n, make_cfg(name, robot=arms[(k + 4) % 6], setup=setup, family="joint_sinusoid", sampling=continuous(60, 10), rn=robot_noise(ROBOT_HIGH), cn=camera_noise(CAM_HIGH)))
            # heavy tails: multivariate Student-t camera noise at the nominal scale
            dof = [3.0, 2.5, 5.0][k]
            name = f"student_t_continuous_{setup}_s{k}"
            add("student_t", "continuous", setup, k, n, make_cfg(name, robot=arms[(k + 1) % 6], setup=setup, family="joint_sinusoid", sampling=continuous(60, 10), rn=robot_noise(), cn=camera_noise(student_t_dof=dof)))
            # PnP: pixel noise on the projected target points, LM PnP (kinhec pnp track; robot r1)
            px = [0.5, 1.0, 2.0][k]
            cam = ["hd", "vga", "fhd"][k]
            tgt = (["checker_9x6_25mm", "checker_7x5_20mm", "grid_10x8_60mm"] if setup == "eih" else ["marker_3x3_30mm", "marker_2x2_40mm", "marker_3x3_30mm"])[k]
            cn = default_camera_noise()
            cn.update({"model": "pnp", "pixel_std": px})
            name = f"pnp_stations_{setup}_s{k}"
            add("pnp", "stations", setup, k, n, make_cfg(name, robot=["ur5e", "iiwa7", "panda"][k], setup=setup, family="lookat", fp={"n_waypoints": n}, sampling=stations(n), rn=robot_noise(ROBOT_LOW), cn=cn, camera=cam, target=tgt))
            # degenerate joint subsets (kinhec motion track), both setups
            for sub in ("single", "parallel"):
                robot = ["ur5", "iiwa14", "irb120"][k]
                kind = {"single": "degenerate_single_joint", "parallel": "degenerate_parallel_axes"}[sub]
                name = f"{kind}_continuous_{setup}_s{k}"
                add(kind, "continuous", setup, k, n, make_cfg(name, robot=robot, setup=setup, family="joint_sinusoid", fp={"joints": joint_subset(robot, sub)}, sampling=continuous(60, 10), rn=robot_noise(), cn=camera_noise()), subset=sub, joints=joint_subset(robot, sub))
            # outliers: three models, 10-20 %, look-at stations
            for model in ("random_pose", "planar_flip", "gross"):
                frac = [0.1, 0.15, 0.2][k]
                ol = default_outliers()
                ol.update({"fraction": frac, "model": model})
                name = f"outliers_{model}_stations_{setup}_s{k}"
                add(f"outliers_{model}", "stations", setup, k, 40, make_cfg(name, robot=["ur5e", "ur5", "ur10"][k], setup=setup, family="lookat", fp={"n_waypoints": 40}, sampling=stations(40), rn=robot_noise(), cn=camera_noise(), ol=ol))

    # near-degenerate / minimal joint subsets, setups alternating over the seeds
    for sub, kind in (("two_axes", "near_degenerate_two_axes"), ("wrist", "wrist_only")):
        for k in range(3):
            setup = ["eih", "eth", "eih"][k]
            robot = ["ur5", "iiwa14", "puma560"][k]
            name = f"{kind}_continuous_{setup}_s{k}"
            add(kind, "continuous", setup, k, n_poses[k], make_cfg(name, robot=robot, setup=setup, family="joint_sinusoid", fp={"joints": joint_subset(robot, sub)}, sampling=continuous(60, 10), rn=robot_noise(), cn=camera_noise()), subset=sub, joints=joint_subset(robot, sub))

    # uncalibrated robot: DH errors (1 mm, 0.1 deg) reported through the nominal model (kinhec robot_error track)
    for k in range(3):
        setup = ["eih", "eth", "eih"][k]
        robot = ["ur10", "ur5", "irb120"][k]
        rn = default_robot_noise()
        rn.update({"models": ["dh_error", "joint_gaussian"], "joint_std_rad": 1e-4, "dh_len_std_m": 0.001, "dh_ang_std_rad": float(np.radians(0.1)), "rot_std_rad": 0.0, "trans_std_m": 0.0})
        name = f"robot_error_stations_{setup}_s{k}"
        add("robot_error", "stations", setup, k, 40, make_cfg(name, robot=robot, setup=setup, family="lookat", fp={"n_waypoints": 40}, sampling=stations(40), rn=rn, cn=camera_noise()))
    return jobs


def stream_jobs():
    jobs = []
    robots = ["ur10e", "panda", "iiwa14"]
    for setup in ("eih", "eth"):
        for rate in (10, 30):
            for k in range(3):
                name = f"temporal_{rate}hz_{setup}_s{k}"
                rng = np.random.default_rng(seed_for(GLOBAL_SEED, name + "/timing"))
                tim = default_timing()
                tim.update({"time_offset_s": round(float(rng.uniform(-0.05, 0.1)), 4), "jitter_std_s": [0.0, 0.001, 0.003][k], "drop_fraction": [0.05, 0.1, 0.2][k]})
                robot = robots[(k + (1 if setup == "eth" else 0)) % 3]
                rate_r = float(min(500.0, ROBOTS[robot].control_rate_hz))
                dur = 20.0
                cfg = make_cfg(name, robot=robot, setup=setup, family="joint_sinusoid", fp=TEMPORAL_EXCITATION, sampling=continuous(dur, rate, "asynchronous", rate_r), timing=tim, rn=robot_noise(), cn=camera_noise())
                jobs.append(dict(name=name, kind="temporal", setup=setup, k=k, cfg=cfg))
    for k, (model, setup) in enumerate((("random_pose", "eih"), ("planar_flip", "eth"), ("gross", "eih"))):
        name = f"temporal_outliers_{model}_30hz_{setup}_s{k}"
        rng = np.random.default_rng(seed_for(GLOBAL_SEED, name + "/timing"))
        tim = default_timing()
        tim.update({"time_offset_s": round(float(rng.uniform(-0.05, 0.1)), 4), "jitter_std_s": 0.001, "drop_fraction": 0.05})
        ol = default_outliers()
        ol.update({"fraction": [0.1, 0.15, 0.2][k], "model": model})
        robot = ["ur5e", "panda", "ur10e"][k]
        cfg = make_cfg(name, robot=robot, setup=setup, family="joint_sinusoid", fp=TEMPORAL_EXCITATION, sampling=continuous(20.0, 30, "asynchronous", float(min(500.0, ROBOTS[robot].control_rate_hz))), timing=tim, rn=robot_noise(), cn=camera_noise(), ol=ol)
        jobs.append(dict(name=name, kind=f"temporal_outliers_{model}", setup=setup, k=k, cfg=cfg))
    return jobs


# ----------------------------------------------------------------------------------------------
# generation (worker)
# ----------------------------------------------------------------------------------------------
def run_cfg(cfg_dict):
    cfg = SequenceConfig.from_dict(cfg_dict)
    rec = generate_sequence(cfg)
    return rec.manifest, rec.robot_table.to_pandas(), rec.camera_table.to_pandas(), rec.extra


def poses(df, prefix):
    cols = [f"{prefix}_{c}" for c in ("px", "py", "pz", "qw", "qx", "qy", "qz")]
    return se3.pq_to_pose(df[cols].to_numpy(dtype=float))  # NaN rows stay NaN


def kinhec_xy(man):
    cols = ("px", "py", "pz", "qw", "qx", "qy", "qz")
    X = se3.pq_to_pose(np.array([man[f"X_{c}"] for c in cols]))
    Y = se3.pq_to_pose(np.array([man[f"Y_{c}"] for c in cols]))
    return X, Y


def handeye_truth(setup, X, Y):
    """(x_frame, X, target_frame, target) in handeye's names."""
    if setup == "eih":
        return "gripper_from_camera", X, "base_from_target", Y
    return "base_from_camera", Y, "gripper_from_target", X


def check_frames(setup, T_bg_gt, T_ct_gt, Xh, target):
    """The constant-target identity on ground-truth poses; returns the largest deviation."""
    worst = 0.0
    for Q, P in zip(T_bg_gt, T_ct_gt):
        if setup == "eih":
            W = Q @ Xh @ P  # base_from_gripper · gripper_from_camera · camera_from_target
        else:
            W = se3.inverse(Q) @ Xh @ P  # gripper_from_base · base_from_camera · camera_from_target
        worst = max(worst, float(np.abs(W - target).max()))
    assert worst < 1e-9, f"frame mapping broken ({setup}): {worst}"
    return worst


# ----------------------------------------------------------------------------------------------
# writing
# ----------------------------------------------------------------------------------------------
def num(v, digits=DIGITS):
    v = float(v)
    if v == 0.0:
        return "0"
    s = f"{v:.{digits}g}"
    return s


def quat_xyzw(R):
    q = Rotation.from_matrix(R).as_quat()  # x y z w
    if q[3] < 0:
        q = -q
    return q


def mat_json(T, digits=DIGITS, fixed=None):
    rows = []
    for i in range(3):
        if fixed is not None:
            rows.append("[" + ", ".join(f"{T[i, j]:.{fixed}f}" for j in range(4)) + "]")
        else:
            rows.append("[" + ", ".join(num(T[i, j], digits) for j in range(4)) + "]")
    rows.append("[0, 0, 0, 1]")
    return "[" + ", ".join(rows) + "]"


def tq_json(t, q, digits=DIGITS):
    return '{"translation": [' + ", ".join(num(v, digits) for v in t) + '], "quaternion_xyzw": [' + ", ".join(num(v, digits) for v in q) + "]}"


def transform_json(T, form, digits=DIGITS):
    if form == "matrix":
        return mat_json(T, digits)
    return tq_json(T[:3, 3], quat_xyzw(T[:3, :3]), digits)


def full_transform(T):
    """Truth-file transform at full precision (translation, quaternion and matrix agree)."""
    return {"translation": [float(v) for v in T[:3, 3]], "quaternion_xyzw": [float(v) for v in quat_xyzw(T[:3, :3])], "matrix": [[float(v) for v in row] for row in T]}


def tq_plain(T):
    return {"translation": [float(v) for v in T[:3, 3]], "quaternion_xyzw": [float(v) for v in quat_xyzw(T[:3, :3])]}


def write_truth(path, x_frame, Xh, target_frame, target):
    path.write_text(json.dumps({x_frame: full_transform(Xh), target_frame: full_transform(target)}, indent=1) + "\n")


def record_line(stamp, bg, ct, form, digits=DIGITS, robot_key="base_from_gripper", camera_key="camera_from_target"):
    return '{"stamp": ' + f"{stamp:.6f}" + f', "{robot_key}": ' + (bg if isinstance(bg, str) else transform_json(bg, form, digits)) + f', "{camera_key}": ' + (ct if isinstance(ct, str) else transform_json(ct, form, digits)) + "}"


def rel(path):
    return str(path.relative_to(OUT))


def noise_summary(cfg):
    rn, cn = cfg.robot_noise, cfg.camera_noise
    return {
        "robot_models": rn["models"],
        "robot_rot_std_rad": rn["rot_std_rad"] if "se3_gaussian" in rn["models"] else 0.0,
        "robot_trans_std_m": rn["trans_std_m"] if "se3_gaussian" in rn["models"] else 0.0,
        "robot_student_t_dof": rn.get("student_t_dof"),
        "joint_std_rad": rn["joint_std_rad"] if "joint_gaussian" in rn["models"] else 0.0,
        "dh_len_std_m": rn["dh_len_std_m"] if "dh_error" in rn["models"] else 0.0,
        "dh_ang_std_rad": rn["dh_ang_std_rad"] if "dh_error" in rn["models"] else 0.0,
        "camera_model": cn["model"],
        "camera_rot_std_rad": cn["rot_std_rad"] if cn["model"] == "se3_gaussian" else None,
        "camera_trans_std_m_xyz": cn["trans_std_m"] if cn["model"] == "se3_gaussian" else None,
        "pixel_std": cn["pixel_std"] if cn["model"] == "pnp" else None,
        "camera_student_t_dof": cn.get("student_t_dof"),
        "camera": cfg.camera,
        "target": cfg.target,
    }


KINHEC_DESCRIPTORS = ("n_motions", "axis_scatter_lambda2", "axis_scatter_lambda3", "mean_rot_angle_deg", "max_rot_angle_deg", "mean_trans_m", "translation_cond")

OBSERVABILITY_NOTES = {
    "degenerate_single_joint": "only the last joint moves: every gripper rotation is about one axis, so the rotation of X about that axis and its translation along it are unobservable; a solver should refuse (exit 3) or warn, not answer confidently",
    "degenerate_parallel_axes": "two joints with parallel axes move: all gripper rotation axes are parallel, X is not determined (rotation about the axis, translation along it); a solver should refuse or warn",
    "near_degenerate_two_axes": "base joint + one wrist joint: two rotation axes, the minimal observable case (poorly conditioned)",
    "wrist_only": "last three joints only: small translations, rotations about wrist axes; observable but weaker translation",
}


def even(idx, n):
    idx = np.asarray(idx)
    if len(idx) <= n:
        return idx
    return idx[np.linspace(0, len(idx) - 1, n).round().astype(int)]


def subsample(T_gt, usable_mask, n, stations_mode):
    """Stations: every usable station (up to n).  Continuous: kinhec's keyframes (>= 5 deg or 2 cm
    apart, on the true flange poses) among the frames with a measurement, evenly thinned to n; if
    there are fewer than n keyframes, n frames evenly spaced over the usable ones."""
    usable = np.flatnonzero(usable_mask)
    if stations_mode:
        return even(usable, n), "stations"
    kf = motions.select_keyframes(T_gt, valid=usable_mask, max_keyframes=100000)
    if len(kf) >= n:
        return even(kf, n), "keyframes_5deg_2cm_evenly_thinned"
    return even(usable, n), "evenly_spaced_usable_frames"


def build_pose_pairs(job, result, pairs_dir):
    man, rob, cam, extra = result
    cfg = job["cfg"]
    setup = job["setup"]
    assert np.allclose(rob["t"].to_numpy(), cam["t"].to_numpy()), "synchronous sequence expected"
    T_bg_meas = poses(rob, "base_ee_meas")
    T_bg_gt = poses(cam, "base_ee_gt")
    T_ct_gt = poses(cam, "cam_target_gt")
    T_ct_meas = poses(cam, "cam_target_meas")
    finite = np.isfinite(T_ct_meas).all(axis=(1, 2))
    sel, how = subsample(T_bg_gt, finite & cam["visible"].to_numpy(), job["n"], job["variant"] == "stations")
    if len(sel) < 20:
        raise RuntimeError(f"{job['name']}: only {len(sel)} usable frames")
    X, Y = kinhec_xy(man)
    x_frame, Xh, target_frame, target = handeye_truth(setup, X, Y)
    worst = check_frames(setup, T_bg_gt[sel], T_ct_gt[sel], Xh, target)
    # robot meas at the camera instants equals the robot table row (synchronous clocks)
    noise_free = job["kind"] == "noise_free"
    digits = 17 if noise_free else DIGITS
    form = "matrix" if (job["k"] % 2 == 0) else "tq"
    stem = job["name"]
    path = pairs_dir / f"{stem}.jsonl"
    lines = [record_line(float(cam["t"].iloc[i]), T_bg_meas[i], T_ct_meas[i], form, digits) for i in sel]
    path.write_text("\n".join(lines) + "\n")
    truth = pairs_dir / f"{stem}.truth.json"
    write_truth(truth, x_frame, Xh, target_frame, target)
    outl = cam["outlier"].to_numpy()[sel]
    A = se3.relative_motions(T_bg_gt[sel], motions.motion_pairs(len(sel), "consecutive"))
    desc_sub = motions.descriptors(A)
    entry = {
        "type": "pose_pairs",
        "file": rel(path),
        "truth": rel(truth),
        "kind": job["kind"],
        "variant": job["variant"],
        "setup": HANDEYE_SETUP[setup],
        "handeye_args": ["--setup", "eye-to-hand"] if setup == "eth" else [],
        "robot": cfg.robot,
        "seed_index": job["k"],
        "kinhec_seed": int(cfg.seed),
        "n_poses": int(len(sel)),
        "selection": how,
        "record_form": form,
        "digits": digits,
        "x_frame": x_frame,
        "x": tq_plain(Xh),
        "target_frame": target_frame,
        "target": tq_plain(target),
        "kinhec_X": tq_plain(X),
        "kinhec_Y": tq_plain(Y),
        "noise": noise_summary(cfg),
        "outliers": {
            "model": cfg.outliers["model"] if cfg.outliers["fraction"] > 0 else "none",
            "fraction_requested": cfg.outliers["fraction"],
            "count": int(outl.sum()),
            "indices": [int(i) for i in np.flatnonzero(outl)],
            "lines": [int(i) + 1 for i in np.flatnonzero(outl)],
        },
        "observability_subsample": desc_sub,
        "observability_kinhec_sequence": {k: man[k] for k in KINHEC_DESCRIPTORS},
        "kinhec_frame_indices": [int(i) for i in sel],
        "kinhec_sequence": {"family": man["family"], "sampling_mode": man["sampling_mode"], "duration_s": man["duration_s"], "n_camera_frames": man["n_camera_frames"], "n_visible_frames": man["n_visible_frames"], "joints_excited": extra.get("trajectory_params", {}).get("joints")},
        "frame_check_max_abs": worst,
        "kinhec_recipe": cfg.to_dict(),
    }
    if "dh_error" in cfg.robot_noise["models"]:
        entry["true_dh"] = {k: [float(v) for v in vals] for k, vals in extra.get("true_dh", {}).items()}
    if job["kind"] in OBSERVABILITY_NOTES:
        entry["observability_note"] = OBSERVABILITY_NOTES[job["kind"]]
    if noise_free:
        entry["note"] = "no noise; printed with 17 significant digits: every solver must recover X to ~1e-9 (frame check)"
    data = {"lines": lines, "sel": sel, "T_bg_meas": T_bg_meas[sel], "T_ct_meas": T_ct_meas[sel], "stamps": cam["t"].to_numpy()[sel], "form": form, "truth": (x_frame, Xh, target_frame, target)}
    return entry, data


# ----------------------------------------------------------------------------------------------
# mistakes
# ----------------------------------------------------------------------------------------------
def build_mistakes(base_entry, data, mistakes_dir, which):
    out = []
    x_frame, Xh, target_frame, target = data["truth"]
    setup = "eih" if x_frame == "gripper_from_camera" else "eth"
    base = Path(base_entry["file"]).stem
    n = len(data["sel"])
    st, Q, P = data["stamps"], data["T_bg_meas"], data["T_ct_meas"]
    rng = np.random.default_rng(seed_for(GLOBAL_SEED, "mistakes/" + base))

    def write(mistake, lines, done, right, literal=None, **more):
        stem = f"{mistake}__{base}"
        path = mistakes_dir / f"{stem}.jsonl"
        path.write_text("\n".join(lines) + "\n")
        truth = mistakes_dir / f"{stem}.truth.json"
        write_truth(truth, x_frame, Xh, target_frame, target)
        e = {
            "type": "mistake",
            "file": rel(path),
            "truth": rel(truth),
            "kind": f"mistake_{mistake}",
            "mistake": mistake,
            "derived_from": base_entry["file"],
            "setup": base_entry["setup"],
            "handeye_args": base_entry["handeye_args"],
            "robot": base_entry["robot"],
            "kinhec_seed": base_entry["kinhec_seed"],
            "n_poses": n,
            "what_was_done": done,
            "right_answer": right,
            "x_frame": x_frame,
            "x": tq_plain(Xh),
        }
        if literal is not None:
            e["literal_answer"] = literal
        e.update(more)
        out.append(e)

    inv = se3.inverse
    tq_lines = lambda fq, fp: [record_line(st[i], fq(Q[i]), fp(P[i]), "tq") for i in range(n)]

    def swapped(T):  # quaternion w,x,y,z written into the x,y,z,w fields
        q = quat_xyzw(T[:3, :3])
        wxyz = [q[3], q[0], q[1], q[2]]
        return tq_json(T[:3, 3], wxyz)

    right_x = f"the true X of the truth file ({x_frame}); a tool should detect the inconsistency (large residual, rotation angles of A and B disagree) rather than answer confidently"
    if "quat_wxyz_robot" in which:
        write("quat_wxyz_robot", tq_lines(swapped, lambda T: T), "robot quaternions written in w,x,y,z order into the quaternion_xyzw fields (camera side correct); records in {translation, quaternion_xyzw} form", right_x + "; read as x,y,z,w the robot rotations are wrong")
    if "quat_wxyz_camera" in which:
        write("quat_wxyz_camera", tq_lines(lambda T: T, swapped), "camera quaternions written in w,x,y,z order into the quaternion_xyzw fields (robot side correct); records in {translation, quaternion_xyzw} form", right_x)
    form = data["form"]
    if "robot_inverted" in which:
        lines = [record_line(st[i], inv(Q[i]), P[i], form) for i in range(n)]
        write("robot_inverted", lines, "every robot pose written inverted (gripper_from_base) under the name base_from_gripper", right_x + "; no X fits the data as written")
    if "camera_inverted" in which:
        lines = [record_line(st[i], Q[i], inv(P[i]), form) for i in range(n)]
        write("camera_inverted", lines, "every camera pose written inverted (target_from_camera) under the name camera_from_target", right_x + "; no X fits the data as written")
    if "both_inverted" in which:
        lines = [record_line(st[i], inv(Q[i]), inv(P[i]), form) for i in range(n)]
        lit = {"frame": target_frame, "transform": tq_plain(target), "why": f"with both sides inverted the data are exactly consistent with X' = {target_frame} (the target pose), so a solver finds it with a small residual: a confident wrong answer unless flagged"}
        write("both_inverted", lines, "robot and camera poses both written inverted under their names", f"the true X of the truth file ({x_frame})", literal=lit)
    if "robot_mm" in which:
        Qmm = Q.copy()
        Qmm[:, :3, 3] *= 1000.0
        lines = [record_line(st[i], Qmm[i], P[i], form) for i in range(n)]
        write("robot_mm", lines, "robot translations in millimetres, camera translations in metres (mixed units)", right_x + f"; with the robot converted to metres X's translation is {[float(v) for v in Xh[:3, 3]]} m; the rotation of X is unaffected by the units")
    if "typo_x1000" in which:
        k = int(rng.integers(3, n - 3))
        Qt = Q.copy()
        Qt[k, 0, 3] *= 1000.0
        lines = [record_line(st[i], Qt[i], P[i], form) for i in range(n)]
        write("typo_x1000", lines, f"on line {k + 1} only, the robot x translation (base_from_gripper[0][3]) multiplied by 1000 (a mis-typed unit)", f"the true X ({x_frame}); the bad line should be detected/dropped, the rest of the file is nominal", bad_lines=[k + 1], bad_field="base_from_gripper[0][3]", original_value=float(Q[k, 0, 3]), written_value=float(Qt[k, 0, 3]))
    if "huge_1e308" in which:
        k = int(rng.integers(3, n - 3))
        lines = [record_line(st[i], Q[i], P[i], "matrix") for i in range(n)]
        Pk = P[k].copy()
        Pk[2, 3] = 1e308
        lines[k] = record_line(st[k], Q[k], mat_json(Pk).replace(num(1e308), "1e308"), "matrix")
        write("huge_1e308", lines, f"on line {k + 1} only, camera_from_target[2][3] (the depth) set to 1e308 (finite, but overflows when squared or multiplied); records as matrices", f"the true X ({x_frame}); the line should be refused (exit 2 naming line and field) or dropped, never produce inf/NaN output", bad_lines=[k + 1], bad_field="camera_from_target[2][3]", original_value=float(P[k, 2, 3]))
    if "matrix_6dp" in which:
        lines, dev = [], []
        for i in range(n):
            lines.append(record_line(st[i], mat_json(Q[i], fixed=6), mat_json(P[i], fixed=6), "matrix"))
            for T in (Q[i], P[i]):
                R = np.round(T[:3, :3], 6)
                dev.append(float(np.abs(R.T @ R - np.eye(3)).max()))
        dev = np.array(dev).reshape(n, 2)
        over = [int(i) + 1 for i in np.flatnonzero(dev.max(axis=1) > 1e-6)]
        write("matrix_6dp", lines, "every matrix (robot and camera) printed with 6 decimals, as a C++/OpenCV dump with default precision would; rotations are orthonormal only to ~1e-6", f"the true X ({x_frame}), essentially as for the source file (rounding is far below the noise); handeye's 1e-6 orthonormality check may refuse lines", max_orthonormality_error=float(dev.max()), lines_over_1e6=over)
    return out


# ----------------------------------------------------------------------------------------------
# streams
# ----------------------------------------------------------------------------------------------
def tum_line(t, T):
    q = quat_xyzw(T[:3, :3])
    return f"{t:.6f} " + " ".join(num(v) for v in (*T[:3, 3], *q))


def build_stream(job, result, streams_dir):
    man, rob, cam, extra = result
    cfg = job["cfg"]
    setup = job["setup"]
    rate_r = cfg.sampling["robot_rate_hz"]
    step = max(1, int(round(rate_r / ROBOT_STREAM_HZ)))
    rob_d = rob.iloc[::step]
    T_bg = poses(rob_d, "base_ee_meas")
    T_ct_meas = poses(cam, "cam_target_meas")
    T_ct_gt = poses(cam, "cam_target_gt")
    T_bg_gt = poses(cam, "base_ee_gt")
    finite = np.isfinite(T_ct_meas).all(axis=(1, 2))
    vis = cam["visible"].to_numpy()
    keep = np.flatnonzero(finite & vis)
    X, Y = kinhec_xy(man)
    x_frame, Xh, target_frame, target = handeye_truth(setup, X, Y)
    worst = check_frames(setup, T_bg_gt[keep], T_ct_gt[keep], Xh, target)
    name = job["name"]
    rpath = streams_dir / f"{name}_robot.txt"
    cpath = streams_dir / f"{name}_camera.txt"
    rpath.write_text("# t x y z qx qy qz qw  (base_from_gripper, robot clock, s / m)\n" + "\n".join(tum_line(t, T) for t, T in zip(rob_d["t"].to_numpy(), T_bg)) + "\n")
    tc = cam["t"].to_numpy()
    cpath.write_text("# t x y z qx qy qz qw  (target_from_camera, camera clock, s / m)\n" + "\n".join(tum_line(tc[i], se3.inverse(T_ct_meas[i])) for i in keep) + "\n")
    truth = streams_dir / f"{name}.truth.json"
    write_truth(truth, x_frame, Xh, target_frame, target)
    outl = cam["outlier"].to_numpy()[keep]
    tim = cfg.timing
    entry = {
        "type": "stream_pair",
        "robot_file": rel(rpath),
        "camera_file": rel(cpath),
        "truth": rel(truth),
        "kind": job["kind"],
        "setup": HANDEYE_SETUP[setup],
        "handeye_args": ["--robot", rel(rpath), "--camera", rel(cpath)] + (["--setup", "eye-to-hand"] if setup == "eth" else []),
        "robot": cfg.robot,
        "seed_index": job["k"],
        "kinhec_seed": int(cfg.seed),
        "time_offset_s": float(tim["time_offset_s"]),
        "time_offset_meaning": "camera clock minus robot clock (handeye --time-offset): camera stamp = true capture time (robot clock) + offset + jitter",
        "jitter_std_s": float(tim["jitter_std_s"]),
        "drop_fraction": float(tim["drop_fraction"]),
        "camera_rate_hz": float(cfg.sampling["camera_rate_hz"]),
        "robot_rate_hz_kinhec": float(rate_r),
        "robot_rate_hz_file": float(rate_r / step),
        "duration_s": float(cfg.sampling["duration_s"]),
        "n_robot_samples": int(len(rob_d)),
        "n_camera_samples": int(len(keep)),
        "n_camera_frames_not_visible_left_out": int((~vis).sum()),
        "x_frame": x_frame,
        "x": tq_plain(Xh),
        "target_frame": target_frame,
        "target": tq_plain(target),
        "kinhec_X": tq_plain(X),
        "kinhec_Y": tq_plain(Y),
        "noise": noise_summary(cfg),
        "outliers": {
            "model": cfg.outliers["model"] if cfg.outliers["fraction"] > 0 else "none",
            "fraction_requested": cfg.outliers["fraction"],
            "count": int(outl.sum()),
            "camera_file_lines": [int(i) + 2 for i in np.flatnonzero(outl)],  # line 1 is the comment
        },
        "observability_kinhec_sequence": {k: man[k] for k in KINHEC_DESCRIPTORS},
        "frame_check_max_abs": worst,
        "kinhec_recipe": cfg.to_dict(),
    }
    return entry


# ----------------------------------------------------------------------------------------------
def clean(v):
    """JSON-safe copy: numpy scalars to Python, non-finite floats to strings ("inf", "nan")."""
    if isinstance(v, dict):
        return {str(k): clean(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [clean(x) for x in v]
    if isinstance(v, np.ndarray):
        return clean(v.tolist())
    if isinstance(v, (np.integer,)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        v = float(v)
        return v if np.isfinite(v) else str(v)
    return v


def main():
    t0 = time.time()
    if kinhec.__version__ != KINHEC_VERSION:
        print(f"warning: kinhec {kinhec.__version__}, the suite was made with {KINHEC_VERSION}", file=sys.stderr)
    dirs = {d: OUT / d for d in ("pairs", "mistakes", "streams")}
    for d in dirs.values():
        if d.exists():
            shutil.rmtree(d)
        d.mkdir(parents=True)
    pjobs, sjobs = pose_pair_jobs(), stream_jobs()
    all_cfgs = [j["cfg"].to_dict() for j in pjobs + sjobs]
    workers = int(os.environ.get("KINHEC_WORKERS", os.cpu_count() or 1))
    cache = os.environ.get("KINHEC_CACHE")  # development only: reuse sequences of an earlier run with the same recipe
    known = {}
    if cache and Path(cache).exists():
        with open(cache, "rb") as f:
            known = pickle.load(f)
    keys = [json.dumps(c, sort_keys=True) for c in all_cfgs]
    todo = [c for c, k in zip(all_cfgs, keys) if k not in known]
    with ProcessPoolExecutor(max_workers=workers) as ex:
        for c, r in zip(todo, ex.map(run_cfg, todo)):
            known[json.dumps(c, sort_keys=True)] = r
    results = [known[k] for k in keys]
    if cache:
        with open(cache, "wb") as f:
            pickle.dump(known, f)
    print(f"generated {len(results)} sequences in {time.time() - t0:.1f} s", file=sys.stderr)
    entries, data_by_name = [], {}
    for job, res in zip(pjobs, results[: len(pjobs)]):
        e, d = build_pose_pairs(job, res, dirs["pairs"])
        entries.append(e)
        data_by_name[job["name"]] = (e, d)
    every = ["quat_wxyz_robot", "quat_wxyz_camera", "robot_inverted", "camera_inverted", "both_inverted", "robot_mm", "typo_x1000", "huge_1e308", "matrix_6dp"]
    entries += build_mistakes(*data_by_name["nominal_stations_eih_s0"], dirs["mistakes"], every)
    entries += build_mistakes(*data_by_name["nominal_continuous_eth_s1"], dirs["mistakes"], ["quat_wxyz_camera", "robot_inverted", "camera_inverted", "both_inverted", "robot_mm"])
    for job, res in zip(sjobs, results[len(pjobs):]):
        entries.append(build_stream(job, res, dirs["streams"]))
    manifest = {
        "description": "handeye test suite generated with kinhec (see README.md); one entry per file",
        "generator": {"package": "kinhec", "version": kinhec.__version__, "script": "testdata/kinhec/generate.py", "global_seed": GLOBAL_SEED, "seeding": "kinhec.plans.seed_for(global_seed, file stem)"},
        "conventions": {
            "a_from_b": "pose of frame b in frame a (kinhec T_a_b); lengths in metres, stamps in seconds, quaternions x,y,z,w",
            "eye-in-hand": "base_from_gripper = kinhec T_base_ee, camera_from_target = T_cam_target, X = gripper_from_camera = kinhec X (T_ee_cam), base_from_target = kinhec Y",
            "eye-to-hand": "same kinds of records (base_from_gripper, camera_from_target = T_cam_marker); run handeye with --setup eye-to-hand; X = base_from_camera = kinhec Y (T_base_cam), gripper_from_target = kinhec X (T_ee_marker)",
            "streams": "*_robot.txt = base_from_gripper on the robot clock, *_camera.txt = target_from_camera on the camera clock; time_offset_s = camera clock minus robot clock",
            "outlier indices": "0-based record index and 1-based line number in the JSON Lines file",
        },
        "counts": {t: sum(1 for e in entries if e["type"] == t) for t in ("pose_pairs", "mistake", "stream_pair")},
        "files": entries,
    }
    text = json.dumps(clean(manifest), indent=1, allow_nan=False)
    text = re.sub(r"\[[^\[\]{}]*\]", lambda m: re.sub(r"\s+", " ", m.group(0)), text)  # flat lists on one line
    (OUT / "manifest.json").write_text(text + "\n")
    print(f"wrote {len(entries)} entries in {time.time() - t0:.1f} s", file=sys.stderr)


if __name__ == "__main__":
    main()
