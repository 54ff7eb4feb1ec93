"""The X an uncalibrated robot's nominal model needs, for the systematic suite's DH-error files (issue 29).

A DH error is partly a constant transform at the base and at the flange: the true pose is
``F_true(q) = E_base · F_nominal(q) · E_flange · (a configuration-dependent rest)``. No hand-eye data
can tell E_base or E_flange from X and the target's pose: in eye-in-hand, base_from_target =
F_true X C = E_base F_nominal (E_flange X) C, so the poses are explained exactly by X' = E_flange X;
in eye-to-hand, camera_from_target = X⁻¹ F_true Y = (E_base⁻¹ X)⁻¹ F_nominal (E_flange Y), so by
X' = E_base⁻¹ X. X' is also the X the robot needs: it is commanded through its nominal model, and
a point seen by the camera, mapped by F_nominal and X', is where the nominal model sends the robot
(the constant parts cancel). What is left, the configuration-dependent rest, is what the
systematic-error test can see and what makes the robot miss.

For each entry with ``true_dh``, this fits E_base and E_flange by least squares over the file's
poses (F_true from the true DH parameters and F_nominal from kinhec's nominal model, both at the
recorded joint angles; rotation in radians, translation in decimetres) and writes into the
manifest entry:

* ``nominal_model_x``: X' under the truth file's frame name (translation, quaternion, matrix);
* ``configuration_dependent_m``: the RMS translation of the rest, metres.

Run: ``/tmp/venv-k/bin/python testdata/kinhec/nominal_model_x.py [DIR]`` (kinhec 1.1.0, scipy;
DIR the directory holding ``systematic/``, by default this one, or a suite directory itself such as
``systematic_b/`` (set B, issue 57), or its ``manifest.json``; deterministic).
"""

import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

sys.path.insert(0, str(Path(__file__).resolve().parent))
import generate as g  # noqa: E402
import kinhec.kinematics as kinematics  # noqa: E402
from kinhec_poses import inverse, matrix4  # noqa: E402
import kinhec.robots as robots  # noqa: E402

DECIMETRES = 10.0


def transform(v):
    m = np.eye(4)
    m[:3, :3] = Rotation.from_rotvec(v[:3]).as_matrix()
    m[:3, 3] = v[3:]
    return m


def twist(m):
    return np.concatenate([Rotation.from_matrix(m[:3, :3]).as_rotvec(), DECIMETRES * m[:3, 3]])


def nominal_model_x(root, entry):
    records = [json.loads(line) for line in (root / entry["file"]).read_text().splitlines() if line.strip()]
    nominal = robots.get_robot(entry["robot"])
    true = replace(nominal, **entry["true_dh"])
    joints = [np.asarray(r["joints"], dtype=float) for r in records]
    f_nominal = [kinematics.forward_kinematics(nominal, q) for q in joints]
    f_true = [kinematics.forward_kinematics(true, q) for q in joints]
    reported = matrix4(records[0]["base_from_gripper"])
    if not np.allclose(reported, f_nominal[0], atol=1e-6):
        raise SystemExit(f"{entry['file']}: the reported pose is not the nominal model's at the recorded joints")

    def residuals(p):
        base, flange = transform(p[:6]), transform(p[6:])
        return np.concatenate([twist(inverse(t) @ base @ n @ flange) for n, t in zip(f_nominal, f_true)])

    fit = least_squares(residuals, np.zeros(12), xtol=1e-14, ftol=1e-14, gtol=1e-14)
    base, flange = transform(fit.x[:6]), transform(fit.x[6:])
    rest = fit.fun.reshape(-1, 6)[:, 3:] / DECIMETRES
    truth = json.loads((root / entry["truth"]).read_text())
    if entry["setup"] == "eye-in-hand":
        frame, x = "gripper_from_camera", flange @ matrix4(truth["gripper_from_camera"])
    else:
        frame, x = "base_from_camera", inverse(base) @ matrix4(truth["base_from_camera"])
    return frame, x, float(np.sqrt(np.mean(np.sum(rest**2, axis=1))))


def main():
    arg = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parent
    if arg.is_file():  # a suite's manifest
        path = arg
    elif (arg / "systematic" / "manifest.json").exists():  # the directory holding systematic/
        path = arg / "systematic" / "manifest.json"
    else:  # a suite directory itself (systematic_b/)
        path = arg / "manifest.json"
    root = path.parent.parent  # the manifest's file names are relative to it
    manifest = json.loads(path.read_text())
    for entry in manifest["files"]:
        if not entry.get("true_dh"):
            continue
        frame, x, rest = nominal_model_x(root, entry)
        entry["nominal_model_x"] = {frame: g.full_transform(x)}
        entry["configuration_dependent_m"] = rest
        print(f"{entry['file']:42} rest {1e3 * rest:.2f} mm")
    path.write_text(json.dumps(g.clean(manifest), indent=1, allow_nan=False) + "\n")


if __name__ == "__main__":
    main()
