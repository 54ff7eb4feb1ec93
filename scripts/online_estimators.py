#!/usr/bin/env python3
"""Measures the online estimators against the truth on the realistic streams.

For every stream of testdata/kinhec/streams (with `--time-offset auto`: they have clock offsets of
-50 to +100 ms), and a few `handeye simulate` streams, runs
`handeye online --estimator E --output json` for E in paper and accumulate and compares the
last X each publishes (the paper's last calibration, the accumulating estimator's last report)
with the true X: rotation error (degrees), translation error (mm), and for the accumulating
estimator the reported one-sigma (its error in sigmas). Prints a Markdown table, and the medians.

    python3 scripts/online_estimators.py --bin $CARGO_TARGET_DIR/release/handeye
"""
import argparse, glob, json, math, os, statistics, subprocess, sys, tempfile


def quat_mat(q):
    x, y, z, w = q
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]


def errors(x, truth):
    """Rotation error (deg) and translation error (same unit) of X against the truth."""
    ra, rb = quat_mat(x["quaternion_xyzw"]), quat_mat(truth["quaternion_xyzw"])
    trace = sum(ra[k][i] * rb[k][i] for i in range(3) for k in range(3))
    angle = math.degrees(math.acos(max(-1.0, min(1.0, (trace - 1) / 2))))
    dt = math.dist(x["translation"], truth["translation"])
    return angle, dt


def last_x(binary, args, estimator):
    run = subprocess.run([binary, "online", *args, "--estimator", estimator, "--output", "json"],
                         capture_output=True, text=True)
    last = None
    for line in run.stdout.splitlines():
        v = json.loads(line)
        if "translation" in v:
            last = v
    return last, run.returncode


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--bin", required=True)
    a = p.parse_args()
    rows = []
    streams = sorted(glob.glob("testdata/kinhec/streams/*_robot.txt"))
    cases = []
    for robot in streams:
        stem = robot[: -len("_robot.txt")]
        truth = json.load(open(stem + ".truth.json"))
        setup = "eye-to-hand" if "_eth_" in stem else "eye-in-hand"
        x_key = "base_from_camera" if setup == "eye-to-hand" else "gripper_from_camera"
        cases.append((os.path.basename(stem), ["--robot", robot, "--camera", stem + "_camera.txt",
                                               "--setup", setup, "--time-offset", "auto"], truth[x_key], 1000.0))
    tmp = tempfile.mkdtemp()
    for seed in range(3):
        path = os.path.join(tmp, f"sim{seed}.jsonl")
        tpath = os.path.join(tmp, f"sim{seed}.truth.json")
        subprocess.run([a.bin, "simulate", "--seed", str(seed), "--poses", "600", "--out", path,
                        "--truth", tpath], check=True, capture_output=True)
        truth = json.load(open(tpath))
        x = truth.get("gripper_from_camera", truth.get("x", truth))
        cases.append((f"simulate seed {seed}", [path], x, 1.0))
    for name, args, truth, mm in cases:
        row = [name]
        for est in ["paper", "accumulate"]:
            x, code = last_x(a.bin, args, est)
            if x is None:
                row.append(None)
                continue
            r, t = errors(x, truth)
            sig = None
            if "uncertainty" in x:
                u = x["uncertainty"]
                sig = (u["rotation_deg"], u["translation"] * mm)
            row.append((r, t * mm, sig))
        rows.append(row)
    print("| stream | paper: rotation error | paper: translation error | accumulate: rotation error (σ) | accumulate: translation error (σ) |")
    print("|---|---|---|---|---|")
    for name, paper, acc in rows:
        ps = f"{paper[0]:.3f}° | {paper[1]:.2f} mm" if paper else "no X | no X"
        if acc:
            s = acc[2]
            ac = f"{acc[0]:.3f}° ({acc[0] / s[0]:.1f}σ) | {acc[1]:.2f} mm ({acc[1] / s[1]:.1f}σ)" if s else f"{acc[0]:.3f}° | {acc[1]:.2f} mm"
        else:
            ac = "no X | no X"
        print(f"| {name} | {ps} | {ac} |")
    for k, est in [(1, "paper"), (2, "accumulate")]:
        got = [r[k] for r in rows if r[k]]
        if got:
            print(f"{est}: {len(got)}/{len(rows)} streams give an X; median error "
                  f"{statistics.median(g[0] for g in got):.3f}° / {statistics.median(g[1] for g in got):.2f} mm; "
                  f"max {max(g[0] for g in got):.3f}° / {max(g[1] for g in got):.2f} mm")


if __name__ == "__main__":
    main()
