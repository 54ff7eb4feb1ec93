#!/usr/bin/env python3
"""How honest is the reported one-sigma on few poses? (issue 33 item 6)

For kinhec recordings with known truth, calibrates random subsets of N poses with the CLI's
defaults and counts, per N, how often an answered X is farther from the truth than 3 reported
sigmas (rotation or translation). With honest sigmas that happens in well under 1% of answers.

    python3 bench/small_n.py --bin target/release/handeye [--subsets 12] [--seeds 3]
"""
import argparse
import json
import math
import os
import random
import subprocess
import tempfile
from collections import defaultdict

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PAIRS = os.path.join(ROOT, "testdata", "kinhec", "pairs")
KINDS = ["nominal_stations", "pnp_stations", "nominal_continuous", "high_noise_continuous"]


def rotation_angle_deg(r1, r2):
    tr = sum(r1[i][k] * r2[i][k] for i in range(3) for k in range(3))
    return math.degrees(math.acos(max(-1.0, min(1.0, (tr - 1) / 2))))


def truth_of(path, setup):
    t = json.load(open(path.replace(".jsonl", ".truth.json")))
    x = t["gripper_from_camera" if setup == "eih" else "base_from_camera"]
    m = x["matrix"]
    return [row[:3] for row in m[:3]], [m[i][3] for i in range(3)]


def run(binary, lines, setup):
    with tempfile.NamedTemporaryFile("w", suffix=".jsonl", delete=False) as f:
        f.writelines(lines)
        name = f.name
    args = [binary, "calibrate", name, "--output", "json"]
    if setup == "eth":
        args += ["--setup", "eye-to-hand"]
    p = subprocess.run(args, capture_output=True, text=True)
    os.unlink(name)
    return p.returncode, (json.loads(p.stdout) if p.returncode == 0 and p.stdout else None)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", default=os.path.join(ROOT, "target", "release", "handeye"))
    ap.add_argument("--subsets", type=int, default=12)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--sizes", default="3,4,5,6,8,10,12")
    a = ap.parse_args()
    rng = random.Random(1)
    stats = defaultdict(lambda: [0, 0, 0, 0])  # runs, answered, beyond 3 sigma, worst ratio
    ratios = defaultdict(list)
    for kind in KINDS:
        for setup in ["eih", "eth"]:
            for seed in range(a.seeds):
                path = os.path.join(PAIRS, f"{kind}_{setup}_s{seed}.jsonl")
                if not os.path.exists(path):
                    continue
                lines = [l for l in open(path) if l.strip()]
                r_true, t_true = truth_of(path, setup)
                for n in map(int, a.sizes.split(",")):
                    for _ in range(a.subsets):
                        pick = sorted(rng.sample(range(len(lines)), n))
                        code, out = run(a.bin, [lines[i] for i in pick], setup)
                        s = stats[n]
                        s[0] += 1
                        if out is None:
                            continue
                        s[1] += 1
                        r = [row[:3] for row in out["matrix"][:3]]
                        t = [out["matrix"][i][3] for i in range(3)]
                        err_r = rotation_angle_deg(r, r_true)
                        err_t = math.dist(t, t_true)
                        u = out["uncertainty"]
                        ratio = max(err_r / max(u["rotation_deg"], 1e-12),
                                    err_t / max(u["translation"], 1e-12))
                        ratios[n].append(ratio)
                        if ratio > 3:
                            s[2] += 1
                        s[3] = max(s[3], ratio)
    print("| poses | runs | answered (exit 0) | beyond 3 sigma | share | error/sigma p99 | worst |")
    print("|---|---|---|---|---|---|---|")
    for n in sorted(stats):
        runs, answered, beyond, worst = stats[n]
        share = beyond / answered if answered else 0
        r = sorted(ratios[n])
        p99 = r[min(len(r) - 1, int(0.99 * len(r)))] if r else float("nan")
        print(f"| {n} | {runs} | {answered} | {beyond} | {100*share:.1f}% | {p99:.1f} | {worst:.1f} |")


if __name__ == "__main__":
    main()
