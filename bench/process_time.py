"""Times handeye as a whole process (start-up, parsing, every check and the report included);
prints JSON.

Usage: python process_time.py BIN FILE.jsonl [FILE.jsonl ...]
       python process_time.py BIN --online POSES
       python process_time.py BIN --online-file FILE.jsonl
       OPENCV_PYTHON=venv/bin/python python process_time.py BIN FILE.jsonl ...

For each file: `BIN calibrate FILE --pairs all --method M --output json` for every hand–eye
method (a refusal, exit 3, is timed too and marked). With --online: `BIN online -` end to end,
as poses per second, fed through one pipe (`cat`) with POSES poses that `BIN simulate` wrote
beforehand (simulate itself makes fewer poses a second than online reads, so a pipe straight from
it would time the simulation). With --online-file the same on a recorded stream (bench/kinhec_stream.py
writes a realistic one). With OPENCV_PYTHON set (a Python with cv2), OpenCV's script is
timed the same way for the methods it shares: `OPENCV_PYTHON bench/opencv_time.py --once M FILE`
(start-up, `import cv2`, reading the file, one call), the whole process a user of OpenCV runs. Each time is the median wall time of at least three runs
(more while under MIN_TIME seconds, default 1), each timed around the child from Python (a spawn
costs about a millisecond, which stays in handeye's figure).
"""
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

METHODS = ["andreff", "andreff-joint", "tsai", "park", "horaud", "daniilidis", "refine"]
OPENCV = ["andreff-joint", "tsai", "park", "horaud", "daniilidis"]


def wall(argv, min_time, shell=False):
    samples = []
    start = time.perf_counter()
    while len(samples) < 3 or (time.perf_counter() - start < min_time and len(samples) < 50):
        t = time.perf_counter()
        done = subprocess.run(argv, shell=shell, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        samples.append(time.perf_counter() - t)
        if done.returncode not in (0, 3):
            raise SystemExit(f"{argv} failed with exit {done.returncode}")
    return statistics.median(samples), len(samples), done.returncode == 3


def main():
    binary, files = sys.argv[1], sys.argv[2:]
    min_time = float(os.environ.get("MIN_TIME", "1"))
    if files[:1] == ["--online"]:
        print(json.dumps({"online": online(binary, int(files[1]), min_time)}))
        return
    if files[:1] == ["--online-file"]:
        print(json.dumps({"online": online_file(binary, files[1], min_time)}))
        return
    rows = []
    for path in files:
        poses = sum(1 for line in open(path) if line.strip())
        for method in METHODS:
            argv = [binary, "calibrate", path, "--pairs", "all", "--method", method, "--output", "json"]
            median, runs, refused = wall(argv, min_time)
            rows.append({"dataset": os.path.basename(path).replace(".jsonl", ""), "poses": poses,
                         "method": method, "median_s": median, "runs": runs, "refused": refused})
            opencv = os.environ.get("OPENCV_PYTHON")
            if opencv and method in OPENCV:
                script = os.path.join(os.path.dirname(os.path.abspath(__file__)), "opencv_time.py")
                rows[-1]["opencv_process_s"] = wall([opencv, script, "--once", method, path], min_time)[0]
            print(f"process {rows[-1]['dataset']} {method}: {median * 1e3:.1f} ms", file=sys.stderr)
    print(json.dumps({"rows": rows}))


def online(binary, n, min_time):
    """`handeye online -` end to end on `handeye simulate`'s poses, its input through one pipe."""
    with tempfile.TemporaryDirectory() as work:
        poses = os.path.join(work, "poses.jsonl")
        subprocess.run([binary, "simulate", "--poses", str(n), "--seed", "7", "--out", poses],
                       check=True, stderr=subprocess.DEVNULL)
        return dict(online_file(binary, poses, min_time), source="handeye simulate")


def online_file(binary, poses, min_time):
    """`handeye online -` end to end on the poses of a file, through one pipe."""
    n = sum(1 for line in open(poses) if line.strip())
    events = subprocess.run([binary, "online", poses, "--output", "json"], check=True,
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL).stdout.count(b"\n")
    piped, runs, _ = wall(f"cat '{poses}' | '{binary}' online -", min_time, shell=True)
    print(f"online: {n / piped:.0f} poses/s end to end ({events} calibrations)", file=sys.stderr)
    return {"poses": n, "calibrations": events, "piped_s": piped, "runs": runs, "poses_per_s": n / piped,
            "source": os.path.basename(poses)}


if __name__ == "__main__":
    main()
