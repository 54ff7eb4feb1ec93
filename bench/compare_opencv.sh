#!/usr/bin/env bash
# Side-by-side speed and accuracy of handeye and OpenCV's cv2.calibrateHandEye, in one run on the
# same poses (all pose pairs, OpenCV's way). Not part of CI.
#
#   bash bench/compare_opencv.sh [POSES...]        (default: 10 50 200 1000)
#
# Creates its own virtual environment (opencv-python-headless<5: OpenCV 5's wheel lacks
# calibrateHandEye), writes the datasets with `handeye simulate`, times OpenCV in-process in
# Python and handeye with `handeye bench`, and prints one Markdown table.
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

"$work/venv/bin/python" bench/opencv_time.py "${files[@]}" > "$work/opencv.json"
inputs=()
for f in "${files[@]}"; do inputs+=(--input "$f"); done
"$bin" bench --quiet --pairs all --methods andreff,andreff-joint,tsai,park,horaud,daniilidis,refine "${inputs[@]}" > "$work/handeye.json"

python3 - "$work/opencv.json" "$work/handeye.json" <<'PY'
import json, sys, platform, os, datetime
cv = json.load(open(sys.argv[1])); he = json.load(open(sys.argv[2]))
ours = {(r["dataset"], r["method"]): r for r in he["solvers"]}
print(f"{datetime.date.today()}, {platform.processor() or platform.machine()}, {os.cpu_count()} cores, OpenCV {cv['opencv_version']}\n")
print("| method | poses | pairs | OpenCV time | handeye time | speed-up | OpenCV error (°, t_rel) | handeye error (°, t_rel) |")
print("|---|---|---|---|---|---|---|---|")
for r in cv["rows"]:
    h = ours[(r["dataset"], r["method"])]
    e1, e2 = r["error"], h["error"]
    print(f"| {r['method']} | {r['poses']} | all | {r['median_s']*1e6:.1f} µs | {h['median_s']*1e6:.1f} µs | "
          f"{r['median_s']/h['median_s']:.1f}× | {e1['rotation_deg']:.4f}, {e1['translation_rel']:.4f} | "
          f"{e2['rotation_deg']:.4f}, {e2['translation_rel']:.4f} |")
for n in sorted({r["poses"] for r in cv["rows"]}):
    for m in ["andreff", "refine"]:
        h = next(x for x in he["solvers"] if x["poses"] == n and x["method"] == m)
        print(f"| {m} (handeye only) | {n} | all | – | {h['median_s']*1e6:.1f} µs | – | – | "
              f"{h['error']['rotation_deg']:.4f}, {h['error']['translation_rel']:.4f} |")
o = he["online"]
print(f"\nonline: {o['push_per_s']/1e6:.1f} million poses/s through push without calibration; a calibration event {o['calibration_s']*1e6:.2f} µs")
PY
