#!/usr/bin/env bash
# Side-by-side speed and accuracy of handeye and OpenCV's cv2.calibrateHandEye, in one run on the
# same poses (all pose pairs, OpenCV's way). Not part of CI.
#
#   bash bench/compare_opencv.sh [POSES...]        (default: 10 50 200 1000)
#
# Creates its own virtual environment (opencv-python-headless<5: OpenCV 5's wheel lacks
# calibrateHandEye), writes the datasets with `handeye simulate`, times OpenCV in-process in
# Python and handeye with `handeye bench`, and prints one Markdown table. The two take turns on
# each dataset, ROUNDS times (default 2), and each time is the best median over the rounds.
set -euo pipefail
cd "$(dirname "$0")/.."
poses=("${@:-10 50 200 1000}")
read -r -a poses <<< "${poses[*]}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

python3 -m venv "$work/venv"
"$work/venv/bin/pip" install -q "opencv-python-headless<5" numpy
cargo build --release -q -p handeye-cli
bin=target/release/handeye

files=()
for n in "${poses[@]}"; do
    "$bin" simulate --poses "$n" --seed 7 --out "$work/sim$n.jsonl" --truth "$work/sim$n.truth.json" 2>/dev/null
    files+=("$work/sim$n.jsonl")
done

# The two libraries take turns on each dataset, and every round repeats that: a slower or faster
# spell of the machine then falls on both sides of a ratio. Each time is the best median over
# the rounds.
rounds=${ROUNDS:-2}
for ((round = 1; round <= rounds; round++)); do
    for n in "${poses[@]}"; do
        f="$work/sim$n.jsonl"
        "$work/venv/bin/python" bench/opencv_time.py "$f" > "$work/opencv.$round.$n.json"
        "$bin" bench --quiet --pairs all --methods andreff,andreff-joint,tsai,park,horaud,daniilidis,refine \
            --input "$f" > "$work/handeye.$round.$n.json"
    done
done

python3 - "$work" <<'PY'
import glob, json, sys, platform, os, datetime
work = sys.argv[1]
cv_rows, he_rows, online, version = {}, {}, [], None
for path in glob.glob(f"{work}/opencv.*.json"):
    d = json.load(open(path)); version = d["opencv_version"]
    for r in d["rows"]:
        k = (r["dataset"], r["method"])
        if k not in cv_rows or r["median_s"] < cv_rows[k]["median_s"]:
            cv_rows[k] = r
for path in glob.glob(f"{work}/handeye.*.json"):
    d = json.load(open(path)); online.append(d["online"])
    for r in d["solvers"]:
        k = (r["dataset"], r["method"])
        if k not in he_rows or r["median_s"] < he_rows[k]["median_s"]:
            he_rows[k] = r
print(f"{datetime.date.today()}, {platform.processor() or platform.machine()}, {os.cpu_count()} cores, OpenCV {version}\n")
print("| method | poses | pairs | OpenCV time | handeye time | speed-up | OpenCV error (°, t_rel) | handeye error (°, t_rel) |")
print("|---|---|---|---|---|---|---|---|")
for r in sorted(cv_rows.values(), key=lambda r: (r["poses"], list(cv_rows).index((r["dataset"], r["method"])))):
    h = he_rows[(r["dataset"], r["method"])]
    e1, e2 = r["error"], h["error"]
    print(f"| {r['method']} | {r['poses']} | all | {r['median_s']*1e6:.1f} µs | {h['median_s']*1e6:.1f} µs | "
          f"{r['median_s']/h['median_s']:.1f}× | {e1['rotation_deg']:.4f}, {e1['translation_rel']:.4f} | "
          f"{e2['rotation_deg']:.4f}, {e2['translation_rel']:.4f} |")
for n in sorted({r["poses"] for r in cv_rows.values()}):
    for m in ["andreff", "refine"]:
        h = next(x for x in he_rows.values() if x["poses"] == n and x["method"] == m)
        print(f"| {m} (handeye only) | {n} | all | – | {h['median_s']*1e6:.1f} µs | – | – | "
              f"{h['error']['rotation_deg']:.4f}, {h['error']['translation_rel']:.4f} |")
push = max(o["push_per_s"] for o in online); event = min(o["calibration_s"] for o in online)
print(f"\nonline: {push/1e6:.1f} million poses/s through push without calibration; a calibration event {event*1e6:.2f} µs")
PY
