"""Times cv2.calibrateHandEye in-process on handeye pose files; prints JSON.

Usage: python opencv_time.py FILE.jsonl [FILE.jsonl ...]  (each with FILE.truth.json beside it)
       python opencv_time.py --once METHOD FILE.jsonl

With --once: what a script using OpenCV does as a whole process (import cv2, read the file, one
calibrateHandEye call, print X), for bench/process_time.py to time from outside.
"""
import json
import sys
import time

import cv2
import numpy as np

METHODS = {
    "tsai": cv2.CALIB_HAND_EYE_TSAI,
    "park": cv2.CALIB_HAND_EYE_PARK,
    "horaud": cv2.CALIB_HAND_EYE_HORAUD,
    "andreff-joint": cv2.CALIB_HAND_EYE_ANDREFF,
    "daniilidis": cv2.CALIB_HAND_EYE_DANIILIDIS,
}


def load(path):
    rg, tg, rc, tc = [], [], [], []
    with open(path) as f:
        for line in f:
            if not line.strip():
                continue
            d = json.loads(line)
            q = np.array(d["base_from_gripper"], dtype=np.float64)
            c = np.array(d["camera_from_target"], dtype=np.float64)
            rg.append(q[:3, :3].copy())
            tg.append(q[:3, 3:4].copy())
            rc.append(c[:3, :3].copy())
            tc.append(c[:3, 3:4].copy())
    return rg, tg, rc, tc


def time_call(f, min_time=0.3):
    samples = []
    start = time.perf_counter()
    while len(samples) < 3 or (time.perf_counter() - start < min_time and len(samples) < 1000):
        t = time.perf_counter()
        f()
        samples.append(time.perf_counter() - t)
    samples.sort()
    return samples[len(samples) // 2], len(samples)


def errors(r, t, truth):
    x = np.array(truth["gripper_from_camera"]["matrix"])
    d = r.T @ x[:3, :3]
    angle = np.degrees(np.arccos(np.clip((np.trace(d) - 1) / 2, -1, 1)))
    rel = np.linalg.norm(t.ravel() - x[:3, 3]) / np.linalg.norm(x[:3, 3])
    return {"rotation_deg": float(angle), "translation_rel": float(rel)}


def once(method, path):
    r, t = cv2.calibrateHandEye(*load(path), method=METHODS[method])
    print(json.dumps({"rotation": r.tolist(), "translation": t.ravel().tolist()}))


def main():
    if sys.argv[1:2] == ["--once"]:
        once(sys.argv[2], sys.argv[3])
        return
    rows = []
    for path in sys.argv[1:]:
        data = load(path)
        truth = json.load(open(path.replace(".jsonl", ".truth.json")))
        for name, method in METHODS.items():
            call = lambda: cv2.calibrateHandEye(*data, method=method)
            r, t = call()
            median, calls = time_call(call)
            rows.append({"dataset": path.split("/")[-1].replace(".jsonl", ""), "poses": len(data[0]),
                         "method": name, "median_s": median, "calls": calls, "error": errors(r, t, truth)})
            print(f"opencv {rows[-1]['dataset']} {name}: {median * 1e6:.1f} µs", file=sys.stderr)
    print(json.dumps({"opencv_version": cv2.__version__, "rows": rows}))


if __name__ == "__main__":
    main()
