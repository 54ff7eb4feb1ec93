"""The systematic-error suites: uncalibrated robots and their controls (issue 29; set B, issue 57).

Set A (``systematic/``, the default): every file is a look-at station recording (32 poses) of one
robot in one setup. A *motion* is
(robot, setup, seed index); each motion is recorded with

* ``dh_<level>``: DH parameter errors (0.5 mm / 0.05 deg, 1 mm / 0.1 deg, 2 mm / 0.2 deg, standard
  deviations per parameter) with encoder noise (1e-4 rad), the poses reported through the nominal
  model (kinhec's ``robot_error`` track): an error that follows the robot's configuration;
* ``ctl_robot``: random flange-twist robot noise (kinhec r2), ``ctl_encoder``: encoder noise alone
  (5e-4 rad per joint, through the exact model), ``ctl_pnp``: pixel noise through PnP (1 px) with
  low robot noise (kinhec r1): random errors, the controls.

The camera noise of the ``dh_*``, ``ctl_robot`` and ``ctl_encoder`` files is kinhec's nominal
(c2). The motion's seed is shared by its files (``seed_for(GLOBAL_SEED, motion)``), so that a
DH-error file and its controls visit the same stations. Each record carries ``joints``: the
measured joint angles (radians, the robot's joint order) the reported pose was computed from.

Run: ``/tmp/venv-k/bin/python testdata/kinhec/generate_systematic.py`` (deterministic; writes
``systematic/`` and ``systematic/manifest.json``; about a minute on two cores).

Then ``/tmp/venv-k/bin/python testdata/kinhec/nominal_model_x.py [DIR]`` adds to each DH-error entry
of the manifest the X the robot's nominal model needs (the tests print the error against it beside
the truth's).

Fresh streams for a check on data not tuned on: ``--out DIR --global-seed N`` writes the same suite
with another seed into ``DIR/systematic/``; ``HANDEYE_KINHEC_SUITE=DIR cargo test --release -p handeye
--test systematic -- --nocapture`` runs the suite's tests on them.

Set B (``--set B``, ``systematic_b/``, for the dense-stream systematic test, issue 57): dense
continuous recordings. Four motions, (ur5, eye-in-hand), (panda, eye-to-hand), (irb120,
eye-in-hand), (iiwa14, eye-to-hand), seed index 0, each recorded with the same six kinds and noise
as set A (24 files). kinhec's ``joint_sinusoid`` family (the 60 s multi-sine joint trajectory of
``generate.py``'s continuous files), camera at 15 Hz on the robot's clock (synchronous), and EVERY
frame where the target is visible and the measured camera pose finite is written, in time order (no
keyframe thinning); records as in set A (``{translation, quaternion_xyzw}``, 10 significant
digits, ``joints``). The motion's seed is ``seed_for(GLOBAL_SEED, "systematic_b/<motion>")``; if a
file of the motion has fewer than 300 usable frames the motion is drawn again under the key with
"/1", "/2", ... appended, up to "/40"; if no key gives 300 in every file, the key with the most
(the smallest count over its six files) is taken and its entries say ``min_frames_met: false``
(the ur5 eye-in-hand motion: its wide joint excursions keep the board in view about a quarter of the
time, 275-287 frames under the repository's seed). The files of a motion share kinhec's joint
trajectory q(t) and X; kinhec draws the DH errors before the camera clock's phase and (for this
family) the target's or camera's placement, so the ``dh_*`` files share one placement and time
grid (the target moved by the DH error's shift) and the controls another. Its
``systematic_b/manifest.json`` has set A's entry fields plus ``seed_key``, ``seed_keys_tried``,
``min_frames_met``, ``rate_hz``, ``duration_s`` and ``n_camera_frames`` (``n_poses``: the frames
written). Run: ``KINHEC_WORKERS=2 /tmp/venv-k/bin/python testdata/kinhec/generate_systematic.py --set
B`` (deterministic, whatever the number of workers; about four minutes on two cores), then
``nominal_model_x.py testdata/kinhec/systematic_b``; ``--set B --out DIR --global-seed N`` writes
fresh streams into ``DIR/systematic_b/``.
"""

import argparse

import json
import os
import shutil
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import generate as g  # noqa: E402
from kinhec.config import SequenceConfig  # noqa: E402

OUT = g.OUT / "systematic"
N_POSES = 32
ROBOTS = ["ur5", "ur10", "panda", "irb120", "iiwa14", "ur5e"]
SEEDS = 2  # motions per (robot, setup): robots rotate over the seeds
LEVELS = {"dh05": (0.0005, 0.05), "dh1": (0.001, 0.1), "dh2": (0.002, 0.2)}
CONTROLS = ("ctl_robot", "ctl_encoder", "ctl_pnp")

# set B: dense continuous recordings (issue 57)
OUT_B = "systematic_b"
MOTIONS_B = [("ur5", "eih"), ("panda", "eth"), ("irb120", "eih"), ("iiwa14", "eth")]
DURATION_B_S = 60.0
RATE_B_HZ = 15.0
MIN_FRAMES_B = 300  # fewer usable frames in any file of a motion: the motion is drawn again
RETRIES_B = 40
BATCH_B = 4  # seed keys tried at once per motion (parallel workers); the choice does not depend on it
JOINT_DIGITS = 10


def robot_noise_for(kind):
    rn = g.default_robot_noise()
    if kind in LEVELS:
        length, angle_deg = LEVELS[kind]
        rn.update({"models": ["dh_error", "joint_gaussian"], "joint_std_rad": 1e-4, "dh_len_std_m": length, "dh_ang_std_rad": float(np.radians(angle_deg)), "rot_std_rad": 0.0, "trans_std_m": 0.0})
        return rn
    if kind == "ctl_encoder":
        rn.update({"models": ["joint_gaussian"], "joint_std_rad": 5e-4, "rot_std_rad": 0.0, "trans_std_m": 0.0})
        return rn
    if kind == "ctl_pnp":
        return g.robot_noise(g.ROBOT_LOW)
    return g.robot_noise()


def camera_for(kind):
    if kind == "ctl_pnp":
        cn = g.default_camera_noise()
        cn.update({"model": "pnp", "pixel_std": 1.0})
        return cn
    return g.camera_noise()


def jobs():
    out = []
    for setup in ("eih", "eth"):
        for k in range(SEEDS):
            for r in range(3):
                robot = ROBOTS[(r + 2 * k + (1 if setup == "eth" else 0)) % len(ROBOTS)]
                motion = f"{robot}_{setup}_s{k}"
                seed = g.seed_for(g.GLOBAL_SEED, "systematic/" + motion)
                for kind in list(LEVELS) + list(CONTROLS):
                    # the levels on every motion; the controls on every motion too
                    name = f"{kind}_{motion}"
                    cfg = g.make_cfg(name, robot=robot, setup=setup, family="lookat", fp={"n_waypoints": N_POSES}, sampling=g.stations(N_POSES), rn=robot_noise_for(kind), cn=camera_for(kind))
                    cfg = SequenceConfig.from_dict({**cfg.to_dict(), "seed": int(seed)})
                    out.append(dict(name=name, kind=kind, motion=motion, setup=setup, k=k, robot=robot, cfg=cfg))
    return out


def seed_key_b(motion, attempt):
    return "systematic_b/" + motion + (f"/{attempt}" if attempt else "")


def jobs_b(motion, attempt):
    """Set B's six files of ``motion`` (robot_setup_s0) under seed key number ``attempt`` (0: the
    motion's own key, n: key + "/n")."""
    robot, setup, k = motion.split("_")[0], motion.split("_")[1], 0
    key = seed_key_b(motion, attempt)
    seed = g.seed_for(g.GLOBAL_SEED, key)
    out = []
    for kind in list(LEVELS) + list(CONTROLS):
        name = f"{kind}_{motion}"
        cfg = g.make_cfg(name, robot=robot, setup=setup, family="joint_sinusoid", sampling=g.continuous(DURATION_B_S, RATE_B_HZ), rn=robot_noise_for(kind), cn=camera_for(kind))
        cfg = SequenceConfig.from_dict({**cfg.to_dict(), "seed": int(seed)})
        out.append(dict(name=name, kind=kind, motion=motion, setup=setup, k=k, robot=robot, cfg=cfg, dense=True, seed_key=key))
    return out


def measured_camera(cam):
    """``g.poses(cam, "cam_target_meas")`` with the frames without a measurement (NaN, e.g. PnP on a
    target not seen) left NaN without passing them to scipy (recent versions refuse NaN quaternions)."""
    pq = cam[[f"cam_target_meas_{c}" for c in ("px", "py", "pz", "qw", "qx", "qy", "qz")]].to_numpy(dtype=float)
    ok = np.isfinite(pq).all(axis=1)
    if ok.all():
        return g.se3.pq_to_pose(pq)
    T = np.full((len(pq), 4, 4), np.nan)
    T[ok] = g.se3.pq_to_pose(pq[ok])
    return T


def usable(cam):
    """Frames where the target is visible and the measured camera pose is finite."""
    finite = np.isfinite(measured_camera(cam)).all(axis=(1, 2))
    return finite & cam["visible"].to_numpy()


def joints_json(q):
    return "[" + ", ".join(g.num(v, JOINT_DIGITS) for v in q) + "]"


def build(job, result):
    man, rob, cam, extra = result
    setup = job["setup"]
    T_bg_meas = g.poses(rob, "base_ee_meas")
    T_bg_gt = g.poses(cam, "base_ee_gt")
    T_ct_gt = g.poses(cam, "cam_target_gt")
    T_ct_meas = measured_camera(cam)
    finite = np.isfinite(T_ct_meas).all(axis=(1, 2))
    if job.get("dense"):  # set B: every usable frame, in time order
        sel = np.flatnonzero(finite & cam["visible"].to_numpy())
        assert (np.diff(cam["t"].to_numpy()[sel]) > 0).all(), "camera stamps out of order"
    else:
        sel, _ = g.subsample(T_bg_gt, finite & cam["visible"].to_numpy(), N_POSES, True)
    if len(sel) < 20:
        raise RuntimeError(f"{job['name']}: only {len(sel)} usable frames")
    X, Y = g.kinhec_xy(man)
    x_frame, Xh, target_frame, target = g.handeye_truth(setup, X, Y)
    g.check_frames(setup, T_bg_gt[sel], T_ct_gt[sel], Xh, target)
    q_meas = rob["q_meas"].to_numpy()
    lines = []
    for i in sel:
        line = g.record_line(float(cam["t"].iloc[i]), T_bg_meas[i], T_ct_meas[i], "tq")
        lines.append(line[:-1] + ', "joints": ' + joints_json(np.asarray(q_meas[i], dtype=float)) + "}")
    path = OUT / f"{job['name']}.jsonl"
    path.write_text("\n".join(lines) + "\n")
    truth = OUT / f"{job['name']}.truth.json"
    g.write_truth(truth, x_frame, Xh, target_frame, target)
    level = LEVELS.get(job["kind"])
    entry = {
        "file": str(path.relative_to(g.OUT)),
        "truth": str(truth.relative_to(g.OUT)),
        "kind": job["kind"],
        "systematic": job["kind"] in LEVELS,
        "dh_level": {"length_std_m": level[0], "angle_std_deg": level[1]} if level else None,
        "motion": job["motion"],
        "setup": g.HANDEYE_SETUP[setup],
        "robot": job["robot"],
        "seed_index": job["k"],
        "kinhec_seed": int(job["cfg"].seed),
        "n_poses": int(len(sel)),
        "noise": g.noise_summary(job["cfg"]),
    }
    if job.get("dense"):
        entry["seed_key"] = job["seed_key"]
        entry["seed_keys_tried"] = job["seed_keys_tried"]
        entry["min_frames_met"] = job["min_frames_met"]
        entry["rate_hz"] = float(job["cfg"].sampling["camera_rate_hz"])
        entry["duration_s"] = float(job["cfg"].sampling["duration_s"])
        entry["n_camera_frames"] = int(len(cam))
    if "dh_error" in job["cfg"].robot_noise["models"]:
        entry["true_dh"] = {k: [float(v) for v in vals] for k, vals in extra.get("true_dh", {}).items()}
    return entry


def run_b(ex):
    """Set B's jobs and results. A motion takes the first seed key (0, 1, ... RETRIES_B) under which
    every one of its files has at least MIN_FRAMES_B usable frames; if none does, the key with the
    most (the smallest count over its files), flagged ``min_frames_met: false`` in the manifest.
    Keys are tried BATCH_B at a time; the choice depends only on the keys' order."""
    tried = {f"{robot}_{setup}_s0": [] for robot, setup in MOTIONS_B}  # (attempt, jobs, results, counts)
    chosen = {}
    while len(chosen) < len(tried):
        batch = [(m, a) for m in tried if m not in chosen for a in range(len(tried[m]), min(len(tried[m]) + BATCH_B, RETRIES_B + 1))]
        js = [jobs_b(m, a) for m, a in batch]
        flat = [j for six in js for j in six]
        results = list(ex.map(g.run_cfg, [j["cfg"].to_dict() for j in flat]))
        for b, ((m, a), six) in enumerate(zip(batch, js)):
            res = results[6 * b : 6 * b + 6]
            counts = [int(usable(r[2]).sum()) for r in res]
            tried[m].append((a, six, res, counts))
            print(f"{m}: seed key {six[0]['seed_key']}, usable frames {counts}", file=sys.stderr)
        for m in tried:
            if m in chosen:
                continue
            ok = [t for t in tried[m] if min(t[3]) >= MIN_FRAMES_B]
            if ok:
                chosen[m] = (ok[0], True)
            elif len(tried[m]) > RETRIES_B:
                best = max(tried[m], key=lambda t: (min(t[3]), -t[0]))
                chosen[m] = (best, False)
                print(f"{m}: no seed key with {MIN_FRAMES_B} usable frames in every file among {len(tried[m])}; taking {best[1][0]['seed_key']} ({min(best[3])})", file=sys.stderr)
    out_j, out_r = [], []
    for robot, setup in MOTIONS_B:
        m = f"{robot}_{setup}_s0"
        (a, six, res, counts), met = chosen[m]
        for j in six:
            j.update(min_frames_met=met, seed_keys_tried=len(tried[m]) if not met else a + 1)
        out_j += six
        out_r += res
    return out_j, out_r


def main():
    global OUT
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", help="write DIR/systematic/ (DIR/systematic_b/ with --set B) instead of the repository's suite")
    ap.add_argument("--global-seed", type=int, default=g.GLOBAL_SEED)
    ap.add_argument("--set", choices=("A", "B"), default="A", help="A: look-at stations (systematic/); B: dense continuous streams (systematic_b/)")
    args = ap.parse_args()
    if args.out:
        g.OUT = Path(args.out).resolve()
    OUT = g.OUT / ("systematic" if args.set == "A" else OUT_B)
    g.GLOBAL_SEED = args.global_seed
    if OUT.exists():
        shutil.rmtree(OUT)
    OUT.mkdir(parents=True)
    workers = int(os.environ.get("KINHEC_WORKERS", os.cpu_count() or 1))
    with ProcessPoolExecutor(max_workers=workers) as ex:
        if args.set == "A":
            js = jobs()
            results = list(ex.map(g.run_cfg, [j["cfg"].to_dict() for j in js]))
        else:
            js, results = run_b(ex)
    entries = [build(j, r) for j, r in zip(js, results)]
    if args.set == "A":
        manifest = {
            "description": "issue 29's suite: DH-error recordings at three levels and their controls on the same motions (see generate_systematic.py)",
            "generator": {"package": "kinhec", "version": g.kinhec.__version__, "script": "testdata/kinhec/generate_systematic.py", "global_seed": g.GLOBAL_SEED},
            "files": entries,
        }
    else:
        manifest = {
            "description": "issue 57's suite (set B): dense continuous recordings (60 s multi-sine joint motion, camera at 15 Hz, every frame where the target is seen) with DH errors at three levels and their controls on the same motions (see generate_systematic.py)",
            "generator": {"package": "kinhec", "version": g.kinhec.__version__, "script": "testdata/kinhec/generate_systematic.py", "set": "B", "global_seed": g.GLOBAL_SEED, "seeding": "kinhec.plans.seed_for(global_seed, seed_key), shared by the files of a motion"},
            "files": entries,
        }
    (OUT / "manifest.json").write_text(json.dumps(g.clean(manifest), indent=1, allow_nan=False) + "\n")
    print(f"wrote {len(entries)} files", file=sys.stderr)


if __name__ == "__main__":
    main()
