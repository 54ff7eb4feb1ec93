"""Joint attribution against truth (issue 29): robots with exactly ONE wrong DH parameter.

Every file is a look-at station recording (32 poses) of one robot in one setup, reported through
the nominal model while the true robot differs from it in one parameter of one joint:

* ``offset``: the joint's zero offset (``theta_offset``) is off by 0.3 deg;
* ``link``: the joint's link length (``a`` or ``d``, whichever is the longer nominally) is off by
  2 mm.

Only the middle joints are made wrong: a wrong first joint moves the base (absorbed by the
target's pose in eye-in-hand, by X in eye-to-hand) and a wrong last joint's offset moves the
flange (absorbed by X in eye-in-hand, by the target's pose in eye-to-hand), so neither leaves a
residual to attribute. Encoder noise 1e-4 rad and kinhec's nominal camera noise, as the ``dh_*``
files of ``generate_systematic.py``. Each record carries ``joints`` (measured, radians); the
manifest names the wrong joint (1-based) and the parameter.

Run: ``/tmp/venv-k/bin/python testdata/kinhec/generate_joint.py`` (deterministic; writes
``joint/`` and ``joint/manifest.json``). ``--out DIR --global-seed N`` writes fresh streams.
"""

import argparse
import json
import shutil
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import generate as g  # noqa: E402
import generate_systematic as gs  # noqa: E402
import kinhec.generator as kgen  # noqa: E402
from kinhec.config import SequenceConfig  # noqa: E402

N_POSES = 32
ROBOTS = ["ur5", "panda", "irb120", "iiwa14"]
OFFSET_RAD = float(np.radians(0.3))
LINK_M = 0.002

WRONG = {}  # the one parameter the next sequence gets wrong: (joint index, kind)


def one_wrong(robot, rng, len_std_m, ang_std_rad):
    """Replaces kinhec's ``perturbed_model``: the nominal robot with one parameter off."""
    j, kind = WRONG["joint"], WRONG["kind"]
    if kind == "offset":
        t = list(robot.theta_offset)
        t[j] += OFFSET_RAD
        return replace(robot, theta_offset=t)
    a, d = list(robot.a), list(robot.d)
    if abs(a[j]) >= abs(d[j]):
        a[j] += LINK_M
    else:
        d[j] += LINK_M
    return replace(robot, a=a, d=d)


def jobs(dof):
    out = []
    for robot in ROBOTS:
        for setup in ("eih", "eth"):
            for j in range(1, dof[robot] - 1):
                kinds = ["offset"] + (["link"] if j % 2 == 1 else [])
                for kind in kinds:
                    name = f"{kind}_j{j + 1}_{robot}_{setup}"
                    seed = g.seed_for(g.GLOBAL_SEED, "joint/" + name)
                    rn = gs.robot_noise_for("dh1")
                    cfg = g.make_cfg(name, robot=robot, setup=setup, family="lookat", fp={"n_waypoints": N_POSES}, sampling=g.stations(N_POSES), rn=rn, cn=g.camera_noise())
                    cfg = SequenceConfig.from_dict({**cfg.to_dict(), "seed": int(seed)})
                    out.append(dict(name=name, kind=kind, joint=j, setup=setup, robot=robot, cfg=cfg))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", help="write DIR/joint/ instead of the repository's streams")
    ap.add_argument("--global-seed", type=int, default=g.GLOBAL_SEED)
    args = ap.parse_args()
    if args.out:
        g.OUT = Path(args.out).resolve()
    g.GLOBAL_SEED = args.global_seed
    out = g.OUT / "joint"
    gs.OUT = out
    gs.N_POSES = N_POSES
    if out.exists():
        shutil.rmtree(out)
    out.mkdir(parents=True)
    kgen.perturbed_model = one_wrong
    from kinhec.robots import get_robot

    dof = {r: get_robot(r).dof for r in ROBOTS}
    entries = []
    for job in jobs(dof):
        WRONG.update(joint=job["joint"], kind=job["kind"])
        result = g.run_cfg(job["cfg"].to_dict())
        entry = gs.build({**job, "kind": "dh1", "motion": job["name"], "k": 0}, result)
        entry.pop("dh_level", None)
        entry.update(kind=job["kind"], wrong_joint=job["joint"] + 1, dof=dof[job["robot"]])
        entries.append(entry)
    manifest = {
        "description": "joint attribution: one wrong DH parameter (a joint's zero offset by 0.3 deg, or its link length by 2 mm) per recording (see generate_joint.py)",
        "generator": {"package": "kinhec", "version": g.kinhec.__version__, "script": "testdata/kinhec/generate_joint.py", "global_seed": g.GLOBAL_SEED},
        "files": entries,
    }
    (out / "manifest.json").write_text(json.dumps(g.clean(manifest), indent=1, allow_nan=False) + "\n")
    print(f"wrote {len(entries)} files", file=sys.stderr)


if __name__ == "__main__":
    main()
