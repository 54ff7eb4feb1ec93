#!/usr/bin/env python3
"""Which default gives the most accurate X on a pose file? (issue 28)

Runs `handeye calibrate FILE` with each pairing (consecutive, all) and method (andreff, refine) on
the pose files of testdata with a known answer, and prints, per group of files, the median and
worst error of X from the truth (rotation in degrees, translation in the file's unit x 1000, i.e.
millimetres for files in metres) and how often each configuration is the most accurate. Files
whose calibration is refused (degenerate, misread) are counted as refused.

    python3 bench/defaults.py --bin target/release/handeye

Standard library only.
"""
import argparse
import glob
import json
import math
import os
import subprocess
from collections import defaultdict

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CONFIGS = [
    ("andreff", "consecutive"),
    ("andreff", "all"),
    ("refine", "consecutive"),
    ("refine", "all"),
]


def angle_deg(r1, r2):
    tr = sum(r1[i][k] * r2[i][k] for i in range(3) for k in range(3))
    return math.degrees(math.acos(max(-1.0, min(1.0, (tr - 1) / 2))))


def error(matrix, truth):
    r = [row[:3] for row in matrix[:3]]
    rt = [row[:3] for row in truth[:3]]
    dt = math.sqrt(sum((matrix[i][3] - truth[i][3]) ** 2 for i in range(3)))
    return angle_deg(r, rt), dt


def files():
    """(group, path, setup, truth matrix)."""
    for path in sorted(glob.glob(os.path.join(ROOT, "testdata/kinhec/pairs/*.jsonl"))):
        name = os.path.basename(path)
        setup = "eye-to-hand" if "_eth_" in name else "eye-in-hand"
        truth = json.load(open(path.replace(".jsonl", ".truth.json")))
        x = truth["gripper_from_camera" if setup == "eye-in-hand" else "base_from_camera"]
        kind = name.split("_continuous")[0].split("_stations")[0]
        yield f"kinhec {kind}", path, setup, x["matrix"]
    for path in sorted(glob.glob(os.path.join(ROOT, "testdata/opencv/*.jsonl"))):
        expected = json.load(open(path.replace(".jsonl", ".expected.json")))
        yield "opencv", path, expected["setup"], expected["truth"]["matrix"]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--bin", default=os.path.join(ROOT, "target/release/handeye"))
    args = parser.parse_args()
    results = defaultdict(lambda: defaultdict(list))  # group -> config -> [(rot, trans) | None]
    wins = defaultdict(lambda: defaultdict(int))
    for group, path, setup, truth in files():
        errs = {}
        for method, pairs in CONFIGS:
            p = subprocess.run(
                [args.bin, "calibrate", path, "--setup", setup, "--method", method,
                 "--pairs", pairs, "--output", "json"],
                capture_output=True, text=True)
            if p.returncode != 0:
                results[group][(method, pairs)].append(None)
                continue
            e = error(json.loads(p.stdout)["matrix"], truth)
            results[group][(method, pairs)].append(e)
            errs[(method, pairs)] = e
        if errs:
            best = min(errs, key=lambda c: errs[c][0] / max(1e-12, min(v[0] for v in errs.values())) +
                       errs[c][1] / max(1e-12, min(v[1] for v in errs.values())))
            wins[group][best] += 1
    print("| files | configuration | refused | rotation error median / max (°) | translation error median / max (×1000) | most accurate |")
    print("|---|---|---|---|---|---|")
    for group in sorted(results):
        for config in CONFIGS:
            v = results[group][config]
            ok = [e for e in v if e is not None]
            rot = sorted(e[0] for e in ok)
            tr = sorted(e[1] * 1000 for e in ok)
            med = lambda s: s[len(s) // 2] if s else float("nan")
            print(f"| {group} ({len(v)}) | {config[0]} {config[1]} | {len(v) - len(ok)} | "
                  f"{med(rot):.3f} / {max(rot, default=float('nan')):.3f} | "
                  f"{med(tr):.2f} / {max(tr, default=float('nan')):.2f} | {wins[group][config]} |")


if __name__ == "__main__":
    main()
