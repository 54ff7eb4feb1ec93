"""Times handeye.calibrate_hand_eye against cv2.calibrateHandEye in one Python process.

    python crates/handeye-py/bench_vs_opencv.py [--json]   (with handeye and opencv-python-headless<5 installed)

OpenCV's own test protocol (tests/test_handeye.py's random_problem) at 10 and 100 poses, every
OpenCV method by its constant. The two calls take turns, REPEAT times (default 41), each turn
timing a batch of calls; each library's time is its median turn. Prints a table, or JSON.
"""
import json
import os
import statistics
import sys
import time

import cv2
import numpy as np

import handeye

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "tests"))
from test_handeye import random_problem  # noqa: E402

CODES = {"tsai": 0, "park": 1, "horaud": 2, "andreff-joint": 3, "daniilidis": 4}


def batch(f, calls):
    t = time.perf_counter()
    for _ in range(calls):
        f()
    return (time.perf_counter() - t) / calls


def main():
    repeat = int(os.environ.get("REPEAT", "41"))
    rows = []
    for n in (10, 100):
        Rg, tg, Rc, tc, _ = random_problem(np.random.default_rng(3), n=n)
        calls = 20 if n <= 10 else 1
        for name, code in CODES.items():
            cv = lambda: cv2.calibrateHandEye(Rg, tg, Rc, tc, method=code)
            he = lambda: handeye.calibrate_hand_eye(Rg, tg, Rc, tc, method=code)
            cv(), he()
            t_cv, t_he = [], []
            for _ in range(repeat):
                t_cv.append(batch(cv, calls))
                t_he.append(batch(he, calls))
            rows.append({"poses": n, "method": name, "opencv_s": statistics.median(t_cv),
                         "handeye_s": statistics.median(t_he)})
    if "--json" in sys.argv:
        print(json.dumps({"rows": rows}))
        return
    for r in rows:
        print(f"{r['poses']:4d} poses {r['method']:14s} OpenCV {r['opencv_s'] * 1e6:9.1f} µs  "
              f"handeye {r['handeye_s'] * 1e6:9.1f} µs  {r['opencv_s'] / r['handeye_s']:5.1f}×")


if __name__ == "__main__":
    main()
