"""The DH tables of the suite's robots, as handeye's `--robot-model` reads them (issue 29).

Each file is kinhec's nominal model of one robot (the table its recordings report poses through):
``{"convention", "a", "d", "alpha", "theta_offset", "sign", "tool"}``, metres and radians. The
systematic-error suite's tests give the file of each recording's robot to ``calibrate``.

Run: ``/tmp/venv-k/bin/python testdata/kinhec/robot_models.py`` (kinhec 1.1.0; deterministic;
writes ``robots/``).
"""

import json
from pathlib import Path

import kinhec.robots as robots

ROBOTS = ["ur5", "ur10", "ur5e", "panda", "irb120", "iiwa14"]


def table(name):
    m = robots.get_robot(name)
    out = {"convention": m.convention, "a": list(m.a), "d": list(m.d), "alpha": list(m.alpha), "theta_offset": list(m.theta_offset)}
    if m.q_sign is not None:
        out["sign"] = [float(s) for s in m.q_sign]
    if m.tool is not None:
        out["tool"] = [[float(v) for v in row] for row in m.tool]
    return out


def main():
    out = Path(__file__).resolve().parent / "robots"
    out.mkdir(exist_ok=True)
    for name in ROBOTS:
        (out / f"{name}.json").write_text(json.dumps(table(name), indent=1) + "\n")
        print(out / f"{name}.json")


if __name__ == "__main__":
    main()
