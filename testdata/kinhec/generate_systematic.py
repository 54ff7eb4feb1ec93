"""The systematic-error suite: uncalibrated robots and their controls (issue 29).

Every file is a look-at station recording (32 poses) of one robot in one setup. A *motion* is
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


def joints_json(q):
    return "[" + ", ".join(g.num(v, 10) for v in q) + "]"


def build(job, result):
    man, rob, cam, extra = result
    setup = job["setup"]
    T_bg_meas = g.poses(rob, "base_ee_meas")
    T_bg_gt = g.poses(cam, "base_ee_gt")
    T_ct_gt = g.poses(cam, "cam_target_gt")
    T_ct_meas = g.poses(cam, "cam_target_meas")
    finite = np.isfinite(T_ct_meas).all(axis=(1, 2))
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
    if "dh_error" in job["cfg"].robot_noise["models"]:
        entry["true_dh"] = {k: [float(v) for v in vals] for k, vals in extra.get("true_dh", {}).items()}
    return entry


def main():
    global OUT
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", help="write DIR/systematic/ instead of the repository's suite")
    ap.add_argument("--global-seed", type=int, default=g.GLOBAL_SEED)
    args = ap.parse_args()
    if args.out:
        g.OUT = Path(args.out).resolve()
        OUT = g.OUT / "systematic"
    g.GLOBAL_SEED = args.global_seed
    if OUT.exists():
        shutil.rmtree(OUT)
    OUT.mkdir(parents=True)
    js = jobs()
    workers = int(os.environ.get("KINHEC_WORKERS", os.cpu_count() or 1))
    with ProcessPoolExecutor(max_workers=workers) as ex:
        results = list(ex.map(g.run_cfg, [j["cfg"].to_dict() for j in js]))
    entries = [build(j, r) for j, r in zip(js, results)]
    manifest = {
        "description": "issue 29's suite: DH-error recordings at three levels and their controls on the same motions (see generate_systematic.py)",
        "generator": {"package": "kinhec", "version": g.kinhec.__version__, "script": "testdata/kinhec/generate_systematic.py", "global_seed": g.GLOBAL_SEED},
        "files": entries,
    }
    (OUT / "manifest.json").write_text(json.dumps(g.clean(manifest), indent=1, allow_nan=False) + "\n")
    print(f"wrote {len(entries)} files", file=sys.stderr)


if __name__ == "__main__":
    main()
