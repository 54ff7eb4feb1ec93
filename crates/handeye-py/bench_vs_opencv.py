"""Times handeye.calibrate_hand_eye against cv2.calibrateHandEye in one Python process.

    python crates/handeye-py/bench_vs_opencv.py        (with handeye and opencv-python-headless<5 installed)
"""
import sys
import time

import cv2
import numpy as np

import handeye

sys.path.insert(0, __file__.rsplit("/", 1)[0] + "/tests")
from test_handeye import random_problem  # noqa: E402

CODES = {"tsai": 0, "park": 1, "horaud": 2, "andreff-joint": 3, "daniilidis": 4}


def best(f, repeat=7):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return min(times)


for n in (10, 100):
    Rg, tg, Rc, tc, _ = random_problem(np.random.default_rng(3), n=n)
    for name, code in CODES.items():
        t_cv = best(lambda: cv2.calibrateHandEye(Rg, tg, Rc, tc, method=code))
        t_he = best(lambda: handeye.calibrate_hand_eye(Rg, tg, Rc, tc, method=code))
        print(f"{n:4d} poses {name:14s} OpenCV {t_cv * 1e3:8.3f} ms  handeye {t_he * 1e3:8.3f} ms  {t_cv / t_he:5.1f}x")
