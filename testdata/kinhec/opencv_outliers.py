#!/usr/bin/env python3
"""OpenCV's answers on kinhec's outlier series, away from 180°: the fixture of
crates/handeye/tests/opencv_parity.rs' `outliers_away_from_half_turns_give_opencvs_answer`.

Independent of handeye. For each `pairs/outliers_*` series, the poses are kept in file order, a
pose left out when a motion between it and a pose already kept turns by more than 170° on the
robot's or the camera's side (where the sign of a rotation's quaternion or logarithm is in
question, and handeye takes it from Andreff's estimate of R_x; OpenCV keeps w >= 0). On the poses
kept, every pair of poses is a motion (OpenCV's way), and cv2.calibrateHandEye (OpenCV,
Apache-2.0) answers with Tsai (its own motion filter), Park and Horaud. The outliers stay in: the
test is that handeye's sign rule leaves their motions as OpenCV does. Writes opencv_outliers.json
next to this script. Needs numpy and opencv-python-headless<5 only:

    python3 -m venv /tmp/cvvenv && /tmp/cvvenv/bin/pip install numpy "opencv-python-headless<5"
    /tmp/cvvenv/bin/python testdata/kinhec/opencv_outliers.py

OpenCV input: R/t_gripper2base = base_from_gripper (eye-in-hand) or its inverse (eye-to-hand, as
OpenCV's documentation says), R/t_target2cam = camera_from_target.
"""

import glob
import json
import math
import os

import cv2
import numpy as np

from kinhec_poses import matrix4

HERE = os.path.dirname(os.path.abspath(__file__))
LIMIT_DEG = 170.0
METHODS = {
    "tsai": cv2.CALIB_HAND_EYE_TSAI,
    "park": cv2.CALIB_HAND_EYE_PARK,
    "horaud": cv2.CALIB_HAND_EYE_HORAUD,
}


def angle_deg(r):
    return math.degrees(math.acos(max(-1.0, min(1.0, (np.trace(r) - 1.0) / 2.0))))


def kept_poses(hand, camera):
    """Indices of the poses kept: no motion between two of them turns by more than LIMIT_DEG."""
    kept = []
    for k in range(len(hand)):
        if all(angle_deg(hand[i][:3, :3].T @ hand[k][:3, :3]) <= LIMIT_DEG
               and angle_deg(camera[i][:3, :3] @ camera[k][:3, :3].T) <= LIMIT_DEG for i in kept):
            kept.append(k)
    return kept


def main():
    series = []
    for path in sorted(glob.glob(os.path.join(HERE, "pairs", "outliers_*.jsonl"))):
        name = os.path.basename(path)[:-len(".jsonl")]
        setup = "eye-to-hand" if "_eth_" in name else "eye-in-hand"
        lines = [json.loads(line) for line in open(path) if line.strip()]
        base_from_gripper = [matrix4(p["base_from_gripper"]) for p in lines]
        camera_from_target = [matrix4(p["camera_from_target"]) for p in lines]
        # The hand's pose in OpenCV's "gripper2base" argument: inverted eye-to-hand.
        hand = [h if setup == "eye-in-hand" else np.linalg.inv(h) for h in base_from_gripper]
        kept = kept_poses(hand, camera_from_target)
        answers = {}
        for method, code in METHODS.items():
            r, t = cv2.calibrateHandEye([hand[k][:3, :3] for k in kept], [hand[k][:3, 3] for k in kept],
                                        [camera_from_target[k][:3, :3] for k in kept],
                                        [camera_from_target[k][:3, 3] for k in kept], method=code)
            x = np.eye(4)
            x[:3, :3], x[:3, 3] = r, t.ravel()
            answers[method] = x.tolist()
        series.append({"file": f"pairs/{name}.jsonl", "setup": setup, "poses": kept, "opencv": answers})
    out = {
        "opencv_version": cv2.__version__,
        "generator": "testdata/kinhec/opencv_outliers.py",
        "licence_note": "numbers computed with OpenCV (Apache-2.0) cv2.calibrateHandEye; data: kinhec (MIT, see LICENSE)",
        "limit_deg": LIMIT_DEG,
        "series": series,
    }
    with open(os.path.join(HERE, "opencv_outliers.json"), "w") as f:
        json.dump(out, f, indent=1)
        f.write("\n")
    for s in series:
        print(f"{s['file']}: {len(s['poses'])} poses kept")


if __name__ == "__main__":
    main()
