#!/usr/bin/env python3
"""OpenCV reference answers for the kinhec stream suite and the ethz-asl recordings.

Independent of handeye: pairs the robot and camera streams itself, subsamples, and runs
cv2.calibrateHandEye (OpenCV, Apache-2.0) with its five methods. Writes opencv_streams.json next to
this script. Needs numpy and opencv-python-headless<5 only:

    python3 -m venv /tmp/cvvenv && /tmp/cvvenv/bin/pip install numpy "opencv-python-headless<5"
    /tmp/cvvenv/bin/python testdata/kinhec/opencv_streams.py [-q] [--handeye target/release/handeye]

(--handeye only prints a comparison with handeye's answers; the JSON does not depend on it.)

Pairing: for each camera frame at camera stamp t, the robot pose at robot time t - offset
(offset = camera clock - robot clock, the TRUE offset from manifest.json `time_offset_s`; 0 for
ethz-asl, which has no truth), rotation by slerp and translation linearly between the bracketing
robot samples (both streams sorted by stamp first, stable); frames outside the robot stream are
dropped. Then 100 frames evenly spaced over the paired ones: index floor(k*(n-1)/99 + 0.5),
k = 0..99 (all frames if n <= 100).

OpenCV input: R/t_gripper2base = base_from_gripper (eye-in-hand) or its inverse gripper_from_base
(eye-to-hand, as OpenCV's documentation says), R/t_target2cam = camera_from_target = inverse of
the camera file's target_from_camera. The result is gripper_from_camera (eye-in-hand) or
base_from_camera (eye-to-hand).
"""

import json
import math
import os
import sys

import cv2
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.dirname(HERE))
import shared_data  # noqa: E402  (testdata/shared_data.py: other projects' data, read in place)

# ethz-asl's recordings are other projects' data, read from the shared folder; the JSON names them
# `{shared}/ethz-asl/...`.
ETHZ = os.path.join(shared_data.shared_dir(), "ethz-asl")
SUBSAMPLE = 100
LAST_OUT_OF_ORDER = 0

METHODS = [
    ("tsai", cv2.CALIB_HAND_EYE_TSAI),
    ("park", cv2.CALIB_HAND_EYE_PARK),
    ("horaud", cv2.CALIB_HAND_EYE_HORAUD),
    ("andreff", cv2.CALIB_HAND_EYE_ANDREFF),
    ("daniilidis", cv2.CALIB_HAND_EYE_DANIILIDIS),
]


# ---------------------------------------------------------------- reading

def read_stream(path):
    """Rows `t x y z qx qy qz qw` (commas or spaces, `#` comments). Returns (t, p, q, file_rows)
    sorted by t (stable); file_rows = 0-based index of each sample among the file's data rows."""
    rows = []
    with open(path) as f:
        for line in f:
            line = line.split("#", 1)[0].strip()
            if not line:
                continue
            vals = [float(v) for v in line.replace(",", " ").split()]
            if len(vals) != 8:
                raise ValueError(f"{path}: expected 8 fields, got {len(vals)}: {line!r}")
            rows.append(vals)
    a = np.array(rows, dtype=float)
    global LAST_OUT_OF_ORDER
    LAST_OUT_OF_ORDER = int(np.sum(np.diff(a[:, 0]) < 0))
    order = np.argsort(a[:, 0], kind="stable")
    a = a[order]
    q = a[:, 4:8] / np.linalg.norm(a[:, 4:8], axis=1, keepdims=True)
    return a[:, 0], a[:, 1:4], q, order


# ---------------------------------------------------------------- rotations

def quat_to_rot(q):
    x, y, z, w = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def slerp(q0, q1, u):
    d = float(np.dot(q0, q1))
    if d < 0.0:
        q1, d = -q1, -d
    if d > 0.9999995:
        q = q0 + u * (q1 - q0)
        return q / np.linalg.norm(q)
    th = math.acos(min(1.0, d))
    s = math.sin(th)
    return (math.sin((1 - u) * th) / s) * q0 + (math.sin(u * th) / s) * q1


def rot_angle_deg(R):
    """Rotation angle of R, accurate at small and large angles."""
    v = 0.5 * np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    c = 0.5 * (np.trace(R) - 1.0)
    return math.degrees(math.atan2(np.linalg.norm(v), c))


def hom(R, t):
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = t
    return T


def inv(T):
    R, t = T[:3, :3], T[:3, 3]
    return hom(R.T, -R.T @ t)


def pose_from_dict(d):
    return np.array(d["matrix"], dtype=float)


# ---------------------------------------------------------------- pairing

def pair_streams(robot, camera, offset):
    """For each camera frame at camera stamp t: robot pose at t - offset (slerp + linear).
    Returns list of dicts with camera_row, camera_stamp, robot_time, gap, A (base_from_gripper),
    C (target_from_camera as in the file)."""
    rt, rp, rq, _ = robot
    ct, cp, cq, crow = camera
    out = []
    for k in range(len(ct)):
        tr = ct[k] - offset
        if tr < rt[0] or tr > rt[-1]:
            continue
        j = int(np.searchsorted(rt, tr, side="right"))  # rt[j-1] <= tr < rt[j]
        if j >= len(rt):  # tr == last stamp
            i0 = i1 = len(rt) - 1
            u = 0.0
        else:
            i0, i1 = j - 1, j
            u = (tr - rt[i0]) / (rt[i1] - rt[i0])
        q = slerp(rq[i0], rq[i1], u)
        p = (1 - u) * rp[i0] + u * rp[i1]
        out.append({
            "camera_row": int(crow[k]),
            "camera_stamp": float(ct[k]),
            "robot_time": float(tr),
            "gap": float(rt[i1] - rt[i0]),
            "A": hom(quat_to_rot(q), p),
            "C": hom(quat_to_rot(cq[k]), cp[k]),
        })
    return out


def subsample(n, m=SUBSAMPLE):
    if n <= m:
        return list(range(n))
    return [int(math.floor(k * (n - 1) / (m - 1) + 0.5)) for k in range(m)]


# ---------------------------------------------------------------- OpenCV

def tsai_dropped(As, Bs):
    """Motions (all pairs i<j, as OpenCV) that OpenCV's Tsai drops: 2 sin(th/2) outside [0.3, 1.7]
    for the robot or the camera motion."""
    def bad(T):
        s = 2 * math.sin(math.radians(rot_angle_deg(T[:3, :3])) / 2)
        return s < 0.3 or s > 1.7
    n = 0
    for i in range(len(As)):
        for j in range(i + 1, len(As)):
            if bad(inv(As[j]) @ As[i]) or bad(Bs[j] @ inv(Bs[i])):
                n += 1
    return n


def run_opencv(robot_in, cam_from_target):
    Rg = [T[:3, :3].copy() for T in robot_in]
    tg = [T[:3, 3].reshape(3, 1).copy() for T in robot_in]
    Rc = [T[:3, :3].copy() for T in cam_from_target]
    tc = [T[:3, 3].reshape(3, 1).copy() for T in cam_from_target]
    res = {}
    for name, flag in METHODS:
        try:
            R, t = cv2.calibrateHandEye(Rg, tg, Rc, tc, method=flag)
        except cv2.error as e:  # e.g. Andreff's normalizeRotation on a null determinant
            res[name] = " ".join(str(e).split())
            continue
        res[name] = hom(np.asarray(R, dtype=float), np.asarray(t, dtype=float).ravel())
    return res


def errors(Xh, X):
    return rot_angle_deg(Xh[:3, :3].T @ X[:3, :3]), float(np.linalg.norm(Xh[:3, 3] - X[:3, 3]))


def constancy(pairs, X, eth, target=None):
    """base_from_gripper·X·camera_from_target (eye-in-hand) or gripper_from_base·X·camera_from_target
    (eye-to-hand) over the frames: deviation from the true target pose (or, without one, from
    the first frame's). Returns rotation deg rms/max and translation rms/max."""
    Ts = []
    for p in pairs:
        A = inv(p["A"]) if eth else p["A"]
        Ts.append(A @ X @ inv(p["C"]))
    ref = target if target is not None else Ts[0]
    r = np.array([rot_angle_deg(ref[:3, :3].T @ T[:3, :3]) for T in Ts])
    t = np.array([np.linalg.norm(T[:3, 3] - ref[:3, 3]) for T in Ts])
    return {
        "rotation_deg_rms": float(np.sqrt(np.mean(r ** 2))),
        "rotation_deg_max": float(r.max()),
        "translation_rms": float(np.sqrt(np.mean(t ** 2))),
        "translation_max": float(t.max()),
    }


def mat_list(T):
    return [[float(v) for v in row] for row in T]


# ---------------------------------------------------------------- streams

def repo_name(path):
    """A stream's path as the JSON names it: `{shared}/...` in the shared folder, else from the root."""
    masked = shared_data.masked(os.path.abspath(path))
    return masked if masked.startswith(shared_data.PLACEHOLDER) else os.path.relpath(path, ROOT)


def process(name, robot_path, camera_path, setup, offset, truth=None, target=None, report=None,
            outlier_rows=None):
    eth = setup == "eye-to-hand"
    robot = read_stream(robot_path)
    robot_ooo = LAST_OUT_OF_ORDER
    camera = read_stream(camera_path)
    pairs = pair_streams(robot, camera, offset)
    sel = subsample(len(pairs))
    sub = [pairs[i] for i in sel]
    robot_in = [inv(p["A"]) if eth else p["A"] for p in sub]
    cam = [inv(p["C"]) for p in sub]
    sols = run_opencv(robot_in, cam)
    entry = {
        "setup": setup,
        "frame": "base_from_camera" if eth else "gripper_from_camera",
        "robot_file": repo_name(robot_path),
        "camera_file": repo_name(camera_path),
        "offset_s": offset,
        "offset_source": "manifest.json time_offset_s (true)" if truth is not None else "none (0)",
        "robot_samples": int(len(robot[0])),
        "robot_samples_out_of_order": robot_ooo,
        "camera_frames": int(len(camera[0])),
        "frames_paired": len(pairs),
        "frames_used": len(sub),
        "max_bracket_gap_s": float(max(p["gap"] for p in sub)),
        "camera_rows": [p["camera_row"] for p in sub],
        "camera_stamps": [p["camera_stamp"] for p in sub],
        "tsai_filter_dropped_motions": tsai_dropped([p["A"] for p in sub], cam),
        # OpenCV's Daniilidis takes each motion's quaternion sign from rot2quat, which is arbitrary
        # once the rotation exceeds 120 deg (trace <= 0): such motions can corrupt its answer
        "robot_motions_over_120deg": sum(
            1 for i in range(len(sub)) for j in range(i + 1, len(sub))
            if np.trace((inv(robot_in[j]) @ robot_in[i])[:3, :3]) <= 0),
        "motions": len(sub) * (len(sub) - 1) // 2,
    }
    if outlier_rows is not None:
        entry["outlier_camera_rows"] = sorted(outlier_rows)
        entry["outliers_paired"] = sum(p["camera_row"] in outlier_rows for p in pairs)
        entry["outliers_used"] = sum(p["camera_row"] in outlier_rows for p in sub)
    if truth is not None:
        entry["truth"] = mat_list(truth)
        entry["truth_rotation_angle_deg"] = rot_angle_deg(truth[:3, :3])  # Tsai's parameter is singular at 180
        entry["sanity_truth_x_constancy"] = constancy(pairs, truth, eth, target)
        if outlier_rows:
            entry["sanity_truth_x_constancy_inliers"] = constancy(
                [p for p in pairs if p["camera_row"] not in outlier_rows], truth, eth, target)
    methods = {}
    for m, X in sols.items():
        if isinstance(X, str):
            methods[m] = {"matrix": None, "opencv_error": X}
            continue
        d = {"matrix": mat_list(X)}
        if truth is not None:
            d["rotation_error_deg"], d["translation_error"] = errors(X, truth)
        methods[m] = d
    entry["methods"] = methods
    if report is not None:
        report(name, entry, pairs, robot, camera)
    return entry


def compare_handeye(binary, out):
    """Optional check (--handeye BIN): run `handeye calibrate --robot R --camera C --time-offset <offset>
    --pairs all --method M [--setup eye-to-hand]` on every stream (all paired frames, handeye's own
    pairing) and print its distance to OpenCV's answer (100 frames) and to the truth. Not written
    to the JSON: the fixture stays independent of handeye."""
    import subprocess
    for name, e in out["streams"].items():
        for m in ("park", "daniilidis"):
            cmd = [binary, "calibrate", "--robot", os.path.join(ROOT, shared_data.unmasked(e["robot_file"])),
                   "--camera", os.path.join(ROOT, shared_data.unmasked(e["camera_file"])), f"--time-offset={e['offset_s']}",
                   "--pairs", "all", "--method", m, "--setup", e["setup"]]
            r = subprocess.run(cmd, capture_output=True, text=True)
            if r.returncode != 0 or not r.stdout.strip():
                print(f"{name} {m}: handeye exit {r.returncode}: {r.stderr.strip()[:200]}")
                continue
            H = np.array(json.loads(r.stdout)["matrix"], dtype=float)
            cv = e["methods"][m]["matrix"]
            line = f"{name:44s} {m:10s}"
            if cv is not None:
                dr, dt = errors(H, np.array(cv))
                line += f" handeye vs opencv {dr:7.3f} deg {dt*1e3:8.2f} mm"
            if "truth" in e:
                hr, ht = errors(H, np.array(e["truth"]))
                line += f" | handeye err {hr:7.3f} deg {ht*1e3:7.2f} mm"
                if cv is not None:
                    line += f" | opencv err {e['methods'][m]['rotation_error_deg']:7.3f} deg {e['methods'][m]['translation_error']*1e3:7.2f} mm"
            print(line)


def main():
    manifest = json.load(open(os.path.join(HERE, "manifest.json")))
    streams = {}
    verbose = "-q" not in sys.argv[1:]

    def report(name, e, pairs, robot, camera):
        if not verbose:
            return
        msg = f"{name}: {e['setup']}, offset {e['offset_s']:+.4f} s, {e['frames_paired']}/{e['camera_frames']} paired, {e['frames_used']} used, tsai drops {e['tsai_filter_dropped_motions']}/{e['motions']}"
        print(msg)
        if "sanity_truth_x_constancy" in e:
            s = e["sanity_truth_x_constancy"]
            print(f"   truth X constancy (true offset): rot rms {s['rotation_deg_rms']:.4f} max {s['rotation_deg_max']:.4f} deg, trans rms {s['translation_rms']*1e3:.3f} max {s['translation_max']*1e3:.3f} mm")
            if "sanity_truth_x_constancy_inliers" in e:
                s = e["sanity_truth_x_constancy_inliers"]
                print(f"   inliers only ({e['outliers_paired']} outliers paired, {e['outliers_used']} used): rot rms {s['rotation_deg_rms']:.4f} max {s['rotation_deg_max']:.4f} deg, trans rms {s['translation_rms']*1e3:.3f} max {s['translation_max']*1e3:.3f} mm")
            truth = np.array(e["truth"])
            eth = e["setup"] == "eye-to-hand"
            for alt in (0.0, -e["offset_s"]):
                s2 = constancy(pair_streams(robot, camera, alt), truth, eth, target_of[name])
                print(f"   ... with offset {alt:+.4f}: rot rms {s2['rotation_deg_rms']:.4f} deg, trans rms {s2['translation_rms']*1e3:.3f} mm")
            print("   " + "  ".join(f"{m} {d['rotation_error_deg']:.3f}deg/{d['translation_error']*1e3:.2f}mm" if d["matrix"] else f"{m} FAILED"
                                    for m, d in e["methods"].items()))

    target_of = {}
    for f in manifest["files"]:
        if f["type"] != "stream_pair":
            continue
        name = os.path.basename(f["robot_file"])[: -len("_robot.txt")]
        setup = "eye-to-hand" if "_eth_" in name else "eye-in-hand"
        assert setup == f["setup"], (name, f["setup"])
        tj = json.load(open(os.path.join(HERE, f["truth"])))
        xf = "base_from_camera" if setup == "eye-to-hand" else "gripper_from_camera"
        tf = "gripper_from_target" if setup == "eye-to-hand" else "base_from_target"
        truth = pose_from_dict(tj[xf])
        target_of[name] = pose_from_dict(tj[tf])
        # manifest lines are 1-based file lines, the header being line 1
        outliers = {ln - 2 for ln in f["outliers"].get("camera_file_lines", [])}
        streams[name] = process(name, os.path.join(HERE, f["robot_file"]), os.path.join(HERE, f["camera_file"]),
                                setup, float(f["time_offset_s"]), truth, target_of[name], report, outliers)

    for rec in ("robot_arm_sim", "prime_sense_1"):
        name = "ethz-asl/" + rec
        e = process(name, os.path.join(ETHZ, rec + "_B_H.csv"), os.path.join(ETHZ, rec + "_W_E.csv"),
                    "eye-in-hand", 0.0, report=report)
        streams[name] = e
        if verbose:
            print("   " + "  ".join(f"{m} t=({', '.join(f'{v:.4f}' for v in np.array(d['matrix'])[:3, 3])})" if d["matrix"] else f"{m} FAILED"
                                    for m, d in e["methods"].items()))

    out = {
        "opencv_version": cv2.__version__,
        "numpy_version": np.__version__,
        "generator": "testdata/kinhec/opencv_streams.py",
        "licence_note": "numbers computed with OpenCV (Apache-2.0) cv2.calibrateHandEye; data: kinhec streams (MIT, see LICENSE) and ethz-asl/hand_eye_calibration recordings (BSD-3-Clause, the LICENSE beside them in the shared folder)",
        "subsample": SUBSAMPLE,
        "subsample_rule": "frames paired[floor(k*(n-1)/99 + 0.5)], k = 0..99",
        "pairing": "slerp at camera stamp minus true offset",
        "pairing_details": "robot pose at (camera stamp - offset), offset = camera clock - robot clock (manifest.json time_offset_s; 0 for ethz-asl); rotation slerp, translation linear between the bracketing robot samples; both streams sorted by stamp (stable); frames outside the robot stream dropped; no max-gap rule",
        "opencv_input": "R/t_gripper2base = base_from_gripper (eye-in-hand) or gripper_from_base (eye-to-hand); R/t_target2cam = camera_from_target = inverse of the camera file's target_from_camera",
        "error_definitions": "rotation_error_deg = angle of R_opencv^T R_true; translation_error = |t_opencv - t_true| in metres",
        "streams": streams,
    }
    path = os.path.join(HERE, "opencv_streams.json")
    with open(path, "w") as f:
        json.dump(out, f, indent=1)
        f.write("\n")
    if verbose:
        print("wrote", os.path.relpath(path, ROOT))
    if "--handeye" in sys.argv[1:]:
        compare_handeye(sys.argv[sys.argv.index("--handeye") + 1], out)


if __name__ == "__main__":
    main()
