#!/usr/bin/env python3
"""Generate handeye's rig suite (issue 56): several cameras and targets on one robot, with kinhec 1.1.0.

    /tmp/kvenv/bin/python testdata/kinhec/generate_rig.py      (a venv with kinhec==1.1.0)

kinhec simulates one camera; a rig is composed from its parts. One kinhec eye-in-hand sequence
(a robot's look-at stations, forward kinematics, kinhec's robot noise on the reported flange poses,
its wrist camera's board measured through PnP with pixel noise) gives the robot's trajectory and the
wrist camera. Two fixed cameras (placed with kinhec's ``look_at_pose`` at the workspace) observe a
marker on the flange and, for the left one, the board; each of their views is tested with kinhec's
``visibility`` and measured with kinhec's ``camera_pnp`` (pixel noise 0.5 px through PnP), from the
true flange poses of the same stations. So all three cameras share the robot's reported poses (and
its noise), as in a real cell.

Writes ``rig/three_cameras_s<k>.jsonl`` (seeds 0-2) and ``rig/moved_right_s0.jsonl`` (the right
camera knocked by 5 deg and 25 mm half way through), each with ``.truth.json`` (every part's true pose
under its frame name, and the mounts), and ``rig/manifest.json``. Records:
``{"base_from_gripper": 4x4, "observations": [{"camera", "target", "camera_from_target": 4x4}]}``.
Run ``handeye calibrate rig/three_cameras_s0.jsonl --mount wrist=gripper --mount left=base
--mount right=base --mount board=base --mount marker=gripper``.

Frames (kinhec ``T_a_b`` = handeye ``a_from_b``): base_from_gripper = T_base_ee (measured),
wrist: gripper_from_camera = kinhec X (T_ee_cam), board: base_from_target = kinhec Y.
"""
from __future__ import annotations

import json
import os
import sys
from pathlib import Path

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np

import kinhec
from kinhec import camera, noise, se3
from kinhec.config import SequenceConfig, default_camera_noise, default_outliers, default_robot_noise, default_sampling, default_timing
from kinhec.generator import generate_sequence
from kinhec.plans import seed_for

OUT = Path(__file__).resolve().parent / "rig"
GLOBAL_SEED = 20261207
PIXEL_STD = 0.5
CAM = camera.CAMERAS["hd"]
BOARD = camera.TARGETS["checker_9x6_25mm"]
MARKER = camera.TARGETS["marker_3x3_30mm"]
# The right camera's knock half way (moved_right): 5 deg about its y axis and 25 mm along its x;
# kinhec's 3x3 flange marker seen from 1.1 m measures about 1 deg and 1 cm per view, and the two
# fixed cameras see it together at 8 to 10 poses, so a smaller knock is within what the loop can
# tell from noise.
KNOCK_DEG = 5.0
KNOCK_M = 0.025
MOUNTS = {"wrist": "gripper", "left": "base", "right": "base", "board": "base", "marker": "gripper"}


def poses(df, prefix):
    cols = [f"{prefix}_{c}" for c in ("px", "py", "pz", "qw", "qx", "qy", "qz")]
    return se3.pq_to_pose(df[cols].to_numpy(dtype=float))


def kinhec_xy(man):
    cols = ("px", "py", "pz", "qw", "qx", "qy", "qz")
    X = se3.pq_to_pose(np.array([man[f"X_{c}"] for c in cols]))
    Y = se3.pq_to_pose(np.array([man[f"Y_{c}"] for c in cols]))
    return X, Y


def sequence(name, n):
    cn = default_camera_noise()
    cn.update({"model": "pnp", "pixel_std": PIXEL_STD})
    rn = default_robot_noise()
    s = default_sampling()
    s.update({"mode": "stations", "n_stations": int(n)})
    cfg = SequenceConfig(
        sequence_id=name, track="handeye_rig", level=name, seed=seed_for(GLOBAL_SEED, name), robot="ur5e",
        configuration="eye_in_hand", family="lookat", family_params={"n_waypoints": n}, sampling=s,
        timing=default_timing(), robot_noise=rn, camera_noise=cn, outliers=default_outliers(), camera="hd",
        target="checker_9x6_25mm", tags={})
    cfg.validate()
    rec = generate_sequence(cfg)
    return rec.manifest, rec.robot_table.to_pandas(), rec.camera_table.to_pandas()


def fixed_camera(centre, eye_offset):
    """base_from_camera of a camera at centre + offset looking at the centre."""
    return camera.look_at_pose(centre + eye_offset, centre, np.array([0.0, 0.0, 1.0]))


def measure(rng, target, T_cam_target):
    """kinhec's visibility test and PnP measurement of each pose (None where not seen)."""
    vis = np.array([camera.visibility(CAM, target, T)[0] for T in T_cam_target])
    meas, _ = noise.camera_pnp(rng, CAM, target, T_cam_target, PIXEL_STD, vis)
    return [m if v and np.isfinite(m).all() else None for m, v in zip(meas, vis)]


def matrix(T):
    return [[float(f"{v:.10g}") for v in row] for row in T]


def build(name, k, moved=False):
    man, rob, cam = sequence(f"{name}_s{k}", 40)
    T_bg_meas = poses(rob, "base_ee_meas")
    T_bg_gt = poses(cam, "base_ee_gt")
    T_ct_meas = poses(cam, "cam_target_meas")
    X, Y = kinhec_xy(man)
    rng = np.random.default_rng(seed_for(GLOBAL_SEED, f"{name}_s{k}_fixed"))
    # The workspace: the flange positions' centre; the fixed cameras 1.1 m away on either side.
    centre = T_bg_gt[:, :3, 3].mean(axis=0)
    left = fixed_camera(centre, np.array([0.3, 0.8, 0.6]))
    right = fixed_camera(centre, np.array([0.4, -0.8, 0.5]))
    # A marker on the flange, facing along the tool's -z (away from the wrist camera's board side).
    marker = se3.make_pose(se3.rotvec_to_matrix(np.array([np.pi, 0.0, 0.0])), np.array([0.0, 0.05, 0.02])) if hasattr(se3, "make_pose") else None
    if marker is None:
        marker = np.eye(4)
        marker[:3, :3] = np.diag([1.0, -1.0, -1.0])
        marker[:3, 3] = [0.0, 0.05, 0.02]
    parts = {"wrist": X, "left": left, "right": right, "board": Y, "marker": marker}
    n = len(T_bg_gt)
    half = n // 2
    knock = np.eye(4)
    if moved:
        c, s = np.cos(np.radians(KNOCK_DEG)), np.sin(np.radians(KNOCK_DEG))
        knock[:3, :3] = [[c, 0, s], [0, 1, 0], [-s, 0, c]]
        knock[:3, 3] = [KNOCK_M, 0.0, 0.0]

    def right_at(i):
        return right @ knock if (moved and i >= half) else right

    seen = {
        ("left", "marker"): measure(rng, MARKER, np.array([np.linalg.inv(left) @ T @ marker for T in T_bg_gt])),
        ("left", "board"): measure(rng, BOARD, np.array([np.linalg.inv(left) @ Y for _ in T_bg_gt])),
        ("right", "marker"): measure(rng, MARKER, np.array([np.linalg.inv(right_at(i)) @ T @ marker for i, T in enumerate(T_bg_gt)])),
    }
    lines = []
    counts = {}
    for i in range(n):
        if not np.isfinite(T_bg_meas[i]).all():
            continue
        obs = []
        if np.isfinite(T_ct_meas[i]).all() and bool(cam["visible"].iloc[i]):
            obs.append({"camera": "wrist", "target": "board", "camera_from_target": matrix(T_ct_meas[i])})
        for (c, t), m in seen.items():
            if m[i] is not None:
                obs.append({"camera": c, "target": t, "camera_from_target": matrix(m[i])})
        for o in obs:
            counts[f"{o['camera']}/{o['target']}"] = counts.get(f"{o['camera']}/{o['target']}", 0) + 1
        lines.append(json.dumps({"base_from_gripper": matrix(T_bg_meas[i]), "observations": obs}))
    stem = f"{name}_s{k}"
    (OUT / f"{stem}.jsonl").write_text("\n".join(lines) + "\n")
    frames = {"wrist": "gripper_from_camera", "left": "base_from_camera", "right": "base_from_camera",
              "board": "base_from_target", "marker": "gripper_from_target"}
    truth = {"mounts": MOUNTS, "parts": {p: {"frame": frames[p], "matrix": matrix(T)} for p, T in parts.items()}}
    if moved:
        truth["moved"] = {"part": "right", "from_record": half + 1, "matrix_after": matrix(right @ knock)}
    (OUT / f"{stem}.truth.json").write_text(json.dumps(truth, indent=1) + "\n")
    return {"file": f"{stem}.jsonl", "records": len(lines), "observations": counts, "moved": moved,
            "noise": {"robot": {k: default_robot_noise()[k] for k in ("rot_std_rad", "trans_std_m")}, "pixel_std": PIXEL_STD}}


def main():
    OUT.mkdir(exist_ok=True)
    manifest = {"kinhec": kinhec.__version__, "global_seed": GLOBAL_SEED, "files": []}
    for k in range(3):
        manifest["files"].append(build("three_cameras", k))
    manifest["files"].append(build("moved_right", 0, moved=True))
    (OUT / "manifest.json").write_text(json.dumps(manifest, indent=1) + "\n")
    print(json.dumps(manifest, indent=1))


if __name__ == "__main__":
    sys.exit(main())
