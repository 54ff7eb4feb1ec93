#!/usr/bin/env python3
"""Run handeye on every file of manifest.json and compare its X with the truth.

    python3 testdata/kinhec/survey.py [--handeye PATH] [--out FILE] [--filter SUBSTRING]

Needs only the Python standard library.  For each pose-pair and mistake file: `--method refine
--pairs all` and the default (`andreff`, consecutive pairs); for each stream pair: both methods with
the true `--time-offset`, and the default method with `--time-offset auto`.  Prints one line per run:
exit code, rotation error (deg, angle of R_estᵀ R_true), translation error (mm), residuals,
conditioning and warnings; `WRONG!` marks a run that exits 0 without any warning but is more than
1 deg or 10 mm off (a confident wrong answer).
"""
from __future__ import annotations

import argparse
import json
import math
import statistics
import subprocess
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def mat(t):
    if "matrix" in t:
        return [row[:] for row in t["matrix"]]
    x, y, z, w = t["quaternion_xyzw"]
    n = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    R = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]
    tr = t["translation"]
    return [R[0] + [tr[0]], R[1] + [tr[1]], R[2] + [tr[2]], [0, 0, 0, 1]]


def errors(est, true):
    """(rotation error deg, translation error mm) of two 4x4 transforms in metres."""
    # angle of R_estᵀ R_true from the chord ‖R_est − R_true‖_F = 2√2 sin(θ/2) (accurate near 0)
    chord = math.sqrt(sum((est[i][k] - true[i][k]) ** 2 for i in range(3) for k in range(3)))
    rot = math.degrees(2.0 * math.asin(min(1.0, chord / (2.0 * math.sqrt(2.0)))))
    dt = math.sqrt(sum((est[i][3] - true[i][3]) ** 2 for i in range(3)))
    return rot, 1000.0 * dt


def run(handeye, args, timeout=120):
    t0 = time.time()
    try:
        p = subprocess.run([handeye, "calibrate", *args], cwd=HERE, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"exit": "timeout", "seconds": timeout}
    out = {"exit": p.returncode, "seconds": time.time() - t0, "stderr": p.stderr.strip()}
    if p.returncode == 0:
        try:
            out["json"] = json.loads(p.stdout)
        except json.JSONDecodeError as e:
            out["exit"] = f"0 (bad JSON: {e})"
    return out


def describe(r, true_x, literal=None):
    if "json" not in r:
        msg = r.get("stderr", "").splitlines()
        return f"exit={r['exit']:<3} {'':>9} {'':>10}  " + (msg[-1][:150] if msg else ""), None
    j = r["json"]
    try:
        rot, tr = errors(mat(j), true_x)
    except Exception as e:  # overflowing, NaN or missing fields: exit 0 with an unusable X
        return f"exit=0   unreadable X ({e})  WRONG!", (float("inf"), float("inf"), bool(j.get("warnings")), True)
    res = j.get("residual", {})
    warn = j.get("warnings") or []
    bits = [f"exit=0  rot={rot:9.4f}° t={tr:10.3f}mm", f"res={res.get('rotation_deg_rms', float('nan')):.3g}°/{res.get('translation_rms', float('nan')):.3g}", f"cond={j.get('conditioning', float('nan')):.3g}", f"motions={j.get('motions')}"]
    if "time_offset_s" in j:
        bits.append(f"offset={j['time_offset_s']:.4f}")
    if literal is not None:
        lr, lt = errors(mat(j), literal)
        bits.append(f"vs-literal rot={lr:.3g}° t={lt:.3g}mm")
    wrong = (rot > 1.0 or tr > 10.0) and not warn
    if warn:
        bits.append("warnings=" + " | ".join(w if isinstance(w, str) else json.dumps(w) for w in warn)[:300])
    if wrong:
        bits.append("WRONG!")
    return "  ".join(bits), (rot, tr, bool(warn), wrong)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--handeye", default=str(HERE.parent.parent / "target" / "release" / "handeye"))
    ap.add_argument("--out", default=None)
    ap.add_argument("--filter", default="")
    a = ap.parse_args()
    man = json.loads((HERE / "manifest.json").read_text())
    lines, stats = [], {}

    def emit(s):
        print(s, flush=True)
        lines.append(s)

    emit(f"handeye survey of testdata/kinhec ({a.handeye})")
    emit("rot = angle of R_estᵀR_true (deg), t = |t_est - t_true| (mm); WRONG! = exit 0, no warning, > 1 deg or > 10 mm off")
    for e in man["files"]:
        name = e.get("file") or e["robot_file"].replace("_robot.txt", "")
        if a.filter not in name:
            continue
        truth = json.loads((HERE / e["truth"]).read_text())
        true_x = mat(truth[e["x_frame"]])
        literal = mat(e["literal_answer"]["transform"]) if "literal_answer" in e else None
        setup = ["--setup", "eye-to-hand"] if e["setup"] == "eye-to-hand" else []
        emit(f"\n{name}  [{e['kind']}, {e['setup']}, {e['robot']}]")
        if e["type"] == "stream_pair":
            base = ["--robot", e["robot_file"], "--camera", e["camera_file"], *setup]
            off = repr(e["time_offset_s"])
            runs = [(f"refine/all  offset={off}", base + ["--method", "refine", "--pairs", "all", f"--time-offset={off}"]),
                    (f"andreff/con offset={off}", base + [f"--time-offset={off}"]),
                    ("andreff/con offset=auto", base + ["--time-offset", "auto"]),
                    ("andreff/con offset=0", base)]
        else:
            runs = [("refine/all", [e["file"], *setup, "--method", "refine", "--pairs", "all"]), ("andreff/con", [e["file"], *setup])]
        for label, args in runs:
            r = run(a.handeye, args)
            text, st = describe(r, true_x, literal)
            emit(f"  {label:24s} {text}")
            stats.setdefault((e["kind"], label.split()[0] + (" auto" if "auto" in label else "")), []).append((r["exit"], st))
    emit("\nSummary per kind and method: runs, exit codes, median rot/t error, warned, WRONG!")
    for (kind, label), v in sorted(stats.items()):
        ok = [s for _, s in v if s]
        codes = sorted({str(x) for x, _ in v})
        med = f"{statistics.median(s[0] for s in ok):9.4f}° {statistics.median(s[1] for s in ok):10.3f}mm" if ok else f"{'-':>10} {'-':>12}"
        emit(f"  {kind:36s} {label:16s} n={len(v):2d} exit={','.join(codes):8s} median {med}  warned={sum(s[2] for s in ok)}  WRONG!={sum(s[3] for s in ok)}")
    if a.out:
        Path(a.out).write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
