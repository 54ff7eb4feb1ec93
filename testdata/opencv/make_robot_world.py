"""OpenCV's robot-world answers (calibrateRobotWorldHandEye, SHAH and LI) on testdata/opencv/*.jsonl.

    python3 -m venv /tmp/cvvenv && /tmp/cvvenv/bin/pip install numpy "opencv-python-headless<5"
    /tmp/cvvenv/bin/python testdata/opencv/make_robot_world.py

Writes testdata/opencv/robot_world/NAME.expected.json for every pose file NAME.jsonl next to this
script (their setup is read from NAME.expected.json). OpenCV's problem is A_i X = Z B_i with
A_i = R/t_world2cam (camera_from_target), B_i = R/t_base2gripper, X = base2world, Z = gripper2cam.
handeye's Q_i (base_from_gripper eye-in-hand, gripper_from_base eye-to-hand) enters as B_i = Q_i^-1;
then handeye's X (gripper_from_camera / base_from_camera) = Z^-1 and the target pose
(base_from_target / gripper_from_target) = X^-1. Both the raw OpenCV outputs and the converted
transforms are written.
"""
import json
import pathlib

import cv2
import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
METHODS = {"shah": cv2.CALIB_ROBOT_WORLD_HAND_EYE_SHAH, "li": cv2.CALIB_ROBOT_WORLD_HAND_EYE_LI}


def matrix(v):
    m = np.array(v["matrix"] if isinstance(v, dict) else v, dtype=float)
    assert m.shape == (4, 4)
    return m


def homogeneous(r, t):
    m = np.eye(4)
    m[:3, :3] = r
    m[:3, 3] = np.asarray(t).ravel()
    return m


def main():
    out_dir = HERE / "robot_world"
    out_dir.mkdir(exist_ok=True)
    for path in sorted(HERE.glob("*.jsonl")):
        expected = json.loads(path.with_suffix(".expected.json").read_text())
        setup = expected["setup"]
        poses = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
        base_from_gripper = [matrix(p["base_from_gripper"]) for p in poses]
        camera_from_target = [matrix(p["camera_from_target"]) for p in poses]
        hand = base_from_gripper if setup == "eye-in-hand" else [np.linalg.inv(m) for m in base_from_gripper]
        b = [np.linalg.inv(q) for q in hand]
        answers = {}
        for name, flag in METHODS.items():
            r_x, t_x, r_z, t_z = cv2.calibrateRobotWorldHandEye(
                [m[:3, :3] for m in camera_from_target],
                [m[:3, 3].reshape(3, 1) for m in camera_from_target],
                [m[:3, :3] for m in b],
                [m[:3, 3].reshape(3, 1) for m in b],
                method=flag,
            )
            base2world = homogeneous(r_x, t_x)
            gripper2cam = homogeneous(r_z, t_z)
            answers[name] = {
                "base2world": base2world.tolist(),
                "gripper2cam": gripper2cam.tolist(),
                "x": np.linalg.inv(gripper2cam).tolist(),
                "target": np.linalg.inv(base2world).tolist(),
            }
        doc = {
            "source": path.name,
            "setup": setup,
            "frame": "gripper_from_camera" if setup == "eye-in-hand" else "base_from_camera",
            "target_frame": "base_from_target" if setup == "eye-in-hand" else "gripper_from_target",
            "opencv_version": cv2.__version__,
            "opencv": answers,
        }
        out = out_dir / (path.stem + ".expected.json")
        out.write_text(json.dumps(doc, indent=1) + "\n")
        print(out.relative_to(HERE.parent.parent))


if __name__ == "__main__":
    main()
