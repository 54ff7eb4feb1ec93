"""The most any test could flag: an oracle for the systematic-error suite (issue 29).

handeye's systematic-error test sees only the recording: poses, joint angles, nothing of the robot's
model or of the noise. This script asks how often a test that knows *both* could flag the suite's
DH-error files, so that the test's rate is judged against what the data allow, not against 100 %.

The oracle knows
* the noise: kinhec's encoder noise (joint angles through the nominal model) and camera noise (c2:
  rotation on the target's orientation, translation in the camera frame), propagated to first
  order to each pose's 6-vector residual Y⁻¹ L_i (L_i = A_i X B_i eye-in-hand, A_i⁻¹ X B_i
  eye-to-hand), which whitens the residuals exactly;
* the form of the error: the robot's nominal DH model, so the residual's derivative with respect
  to every DH parameter (a, d, alpha, theta offset of each joint) at the recorded joint angles.

Its test is the likelihood-ratio test of "the DH parameters are the nominal ones" (X and the
target's pose fitted in both): the drop in the whitened sum of squares when the DH parameters are
freed, against chi-square with as many degrees of freedom as the DH directions X and the target's
pose do not already absorb. With Gaussian noise and a small error that is the most powerful
invariant test of the hypothesis (it is the F/chi-square test of a linear model with known
variance), so no test built on the recording alone can flag more often at the same level.

The level is checked, not assumed: for each file, null recordings on its own joint angles (the
nominal model exact, the same noise) are drawn and tested the same way.

Run: ``/tmp/venv-k/bin/python testdata/kinhec/oracle_power.py [DIR] [--nulls K]`` (kinhec 1.1.0,
scipy; DIR holds ``systematic/``, by default this directory). Prints a line per DH-error file and
a table by level and setup.
"""

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation
from scipy.stats import chi2
from scipy.stats import f as f_dist

sys.path.insert(0, str(Path(__file__).resolve().parent))
import kinhec.kinematics as kinematics  # noqa: E402
from kinhec_poses import inverse, matrix4  # noqa: E402
import kinhec.robots as robots  # noqa: E402

LEVEL = 0.01
ENCODER_STD = 1e-4  # rad, generate_systematic.py's DH-error files
CAMERA_ROT_STD = 0.002  # rad (kinhec c2)
CAMERA_TRANS_STD = np.array([0.001, 0.001, 0.003])  # m, camera frame
STEP = 1e-7
DH_FIELDS = ("a", "d", "alpha", "theta_offset")


def se3(rotvec, t):
    m = np.eye(4)
    m[:3, :3] = Rotation.from_rotvec(rotvec).as_matrix()
    m[:3, 3] = t
    return m


def log(m):
    return np.concatenate([Rotation.from_matrix(m[:3, :3]).as_rotvec(), m[:3, 3]])


def exp(v):
    return se3(v[:3], v[3:])


def read(path):
    records = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    a = np.stack([matrix4(r["base_from_gripper"]) for r in records])
    b = np.stack([matrix4(r["camera_from_target"]) for r in records])
    q = np.array([r["joints"] for r in records], dtype=float)
    return a, b, q


def chain(eye_in_hand, a, x, b):
    return a @ x @ b if eye_in_hand else inverse(a) @ x @ b


def residual(eye_in_hand, a, x, y, b):
    """Per pose, log(Y⁻¹ L_i): (n, 6), rotation in radians, translation in metres."""
    return np.stack([log(inverse(y) @ chain(eye_in_hand, ai, x, bi)) for ai, bi in zip(a, b)])


def noise_jacobians(eye_in_hand, robot, q, a, x, y, b):
    """Per pose, the covariance of its residual under the encoder and camera noise."""
    covs = []
    for qi, ai, bi in zip(q, a, b):
        r0 = log(inverse(y) @ chain(eye_in_hand, ai, x, bi))
        cols = []
        for j in range(len(qi)):
            dq = qi.copy()
            dq[j] += STEP
            aj = kinematics.forward_kinematics(robot, dq)
            cols.append((log(inverse(y) @ chain(eye_in_hand, aj, x, bi)) - r0) / STEP * ENCODER_STD)
        for k in range(3):
            dr = np.zeros(3)
            dr[k] = STEP
            bj = bi.copy()
            bj[:3, :3] = bi[:3, :3] @ Rotation.from_rotvec(dr).as_matrix()
            cols.append((log(inverse(y) @ chain(eye_in_hand, ai, x, bj)) - r0) / STEP * CAMERA_ROT_STD)
        for k in range(3):
            bj = bi.copy()
            bj[k, 3] += STEP
            cols.append((log(inverse(y) @ chain(eye_in_hand, ai, x, bj)) - r0) / STEP * CAMERA_TRANS_STD[k])
        g = np.array(cols).T
        covs.append(g @ g.T)
    return np.stack(covs)


def whiteners(covs):
    return np.stack([np.linalg.inv(np.linalg.cholesky(c)) for c in covs])


def xy_jacobian(eye_in_hand, a, x, y, b, r0):
    cols = []
    for k in range(12):
        d = np.zeros(6)
        d[k % 6] = STEP
        xk, yk = (x @ exp(d), y) if k < 6 else (x, y @ exp(d))
        cols.append(((residual(eye_in_hand, a, xk, yk, b) - r0) / STEP).ravel())
    return np.array(cols).T


def dh_jacobian(eye_in_hand, robot, q, x, y, b, r0):
    cols = []
    for field in DH_FIELDS:
        for j in range(robot.dof):
            values = list(getattr(robot, field))
            values[j] += STEP
            model = replace(robot, **{field: values})
            a = np.stack([kinematics.forward_kinematics(model, qi) for qi in q])
            cols.append(((residual(eye_in_hand, a, x, y, b) - r0) / STEP).ravel())
    return np.array(cols).T


def whiten(w, m):
    """Apply each pose's whitener to a stacked (6n, k) or (6n,) array."""
    n = len(w)
    if m.ndim == 1:
        return np.einsum("nij,nj->ni", w, m.reshape(n, 6)).ravel()
    return np.einsum("nij,njk->nik", w, m.reshape(n, 6, -1)).reshape(6 * n, -1)


def fit(eye_in_hand, a, b, x, y, w, rounds=8):
    """Whitened Gauss–Newton for X and the target's pose."""
    for _ in range(rounds):
        r0 = residual(eye_in_hand, a, x, y, b)
        j = whiten(w, xy_jacobian(eye_in_hand, a, x, y, b, r0))
        step = np.linalg.lstsq(j, -whiten(w, r0.ravel()), rcond=None)[0]
        x, y = x @ exp(step[:6]), y @ exp(step[6:])
        if np.linalg.norm(step) < 1e-12:
            break
    return x, y


def rank_of(m, tol=1e-8):
    s = np.linalg.svd(m, compute_uv=False)
    return int(np.sum(s > tol * s[0]))


def oracle(eye_in_hand, robot, a, b, q, x, y):
    """(likelihood-ratio statistic, degrees of freedom, whitened sum of squares, its dof)."""
    w = whiteners(noise_jacobians(eye_in_hand, robot, q, a, x, y, b))
    x, y = fit(eye_in_hand, a, b, x, y, w)
    r0 = residual(eye_in_hand, a, x, y, b)
    e = whiten(w, r0.ravel())
    jxy = whiten(w, xy_jacobian(eye_in_hand, a, x, y, b, r0))
    jdh = whiten(w, dh_jacobian(eye_in_hand, robot, q, x, y, b, r0))
    drop, k = free_drop(e, jxy, jdh)
    return drop, k, float(e @ e), len(e) - rank_of(jxy)


def free_drop(e, jxy, extra):
    """The drop in e's sum of squares along the columns of ``extra`` that ``jxy`` (X's and the
    target's pose) does not absorb, and how many such directions."""
    basis, _ = np.linalg.qr(jxy)
    free = extra - basis @ (basis.T @ extra)
    u, s, _ = np.linalg.svd(free, full_matrices=False)
    k = int(np.sum(s > 1e-6 * s[0]))
    u = u[:, :k]
    return float(np.sum((u.T @ e) ** 2)), k


def null_recording(eye_in_hand, robot, q, x, y, rng):
    """Joint angles and camera poses of a recording whose nominal model is exact."""
    a_true = np.stack([kinematics.forward_kinematics(robot, qi) for qi in q])
    if eye_in_hand:
        b = np.stack([inverse(x) @ inverse(ai) @ y for ai in a_true])
    else:
        b = np.stack([inverse(x) @ ai @ y for ai in a_true])
    noisy_q = q + rng.normal(0.0, ENCODER_STD, q.shape)
    a = np.stack([kinematics.forward_kinematics(robot, qi) for qi in noisy_q])
    for bi in b:
        bi[:3, :3] = bi[:3, :3] @ Rotation.from_rotvec(rng.normal(size=3) * CAMERA_ROT_STD).as_matrix()
        bi[:3, 3] += rng.normal(size=3) * CAMERA_TRANS_STD
    return a, b, noisy_q


def truth_of(root, entry, eye_in_hand):
    truth = json.loads((root / entry["truth"]).read_text())
    if eye_in_hand:
        return np.array(truth["gripper_from_camera"]["matrix"]), np.array(truth["base_from_target"]["matrix"])
    return np.array(truth["base_from_camera"]["matrix"]), np.array(truth["gripper_from_target"]["matrix"])


def plain_weights(b, n):
    """The same weight for every pose: rotation in radians, translation over the scene's size."""
    scene = np.median(np.linalg.norm(b[:, :3, 3], axis=1))
    w = np.diag([1.0, 1.0, 1.0, 1 / scene, 1 / scene, 1 / scene])
    return np.repeat(w[None], n, axis=0)


def trig_design(q, n):
    """Per residual component, 1 and the cosine and sine of each joint's angle."""
    phi = np.concatenate([np.ones((n, 1)), np.cos(q), np.sin(q)], axis=1)
    out = np.zeros((6 * n, 6 * phi.shape[1]))
    for c in range(6):
        out[c::6, c * phi.shape[1]:(c + 1) * phi.shape[1]] = phi
    return out


def f_test(e, jxy, extra):
    drop, k = free_drop(e, jxy, extra)
    dof = len(e) - rank_of(jxy) - k
    return f_dist.sf((drop / k) / ((e @ e - drop) / dof), k, dof)


def variants(eye_in_hand, robot, a, b, q, x, y):
    """p-values of the oracle and of weaker tests on one recording."""
    n = len(a)
    out = {}
    for name, w in (("white", whiteners(noise_jacobians(eye_in_hand, robot, q, a, x, y, b))), ("plain", plain_weights(b, n))):
        xf, yf = fit(eye_in_hand, a, b, x, y, w)
        r0 = residual(eye_in_hand, a, xf, yf, b)
        e = whiten(w, r0.ravel())
        jxy = whiten(w, xy_jacobian(eye_in_hand, a, xf, yf, b, r0))
        jdh = whiten(w, dh_jacobian(eye_in_hand, robot, q, xf, yf, b, r0))
        out[f"dh_F_{name}"] = f_test(e, jxy, jdh)
        out[f"trig_F_{name}"] = f_test(e, jxy, whiten(w, trig_design(q, n)))
        if name == "white":
            drop, k, ss, dof = oracle(eye_in_hand, robot, a, b, q, x, y)
            out["oracle"] = chi2.sf(drop, k)
            out["fit_known_noise"] = chi2.sf(ss, dof)
    return out


def survey(root):
    manifest = json.loads((root / "systematic" / "manifest.json").read_text())
    rows = []
    for entry in manifest["files"]:
        eye_in_hand = entry["setup"] == "eye-in-hand"
        robot = robots.get_robot(entry["robot"])
        a, b, q = read(root / entry["file"])
        x, y = truth_of(root, entry, eye_in_hand)
        p = variants(eye_in_hand, robot, a, b, q, x, y)
        rows.append((entry["kind"], entry["setup"], p))
        print(Path(entry["file"]).stem, " ".join(f"{k}={v:.1e}" for k, v in p.items()), flush=True)
    names = list(rows[0][2])
    print("| kind | " + " | ".join(names) + " |")
    for kind in sorted({r[0] for r in rows}):
        sel = [r[2] for r in rows if r[0] == kind]
        print(f"| {kind} ({len(sel)}) | " + " | ".join(f"{sum(s[n] < LEVEL for s in sel)}" for n in names) + " |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("root", nargs="?", default=str(Path(__file__).resolve().parent))
    ap.add_argument("--nulls", type=int, default=4, help="null recordings per DH-error file")
    ap.add_argument("--survey", action="store_true")
    args = ap.parse_args()
    root = Path(args.root)
    if args.survey:
        return survey(root)
    manifest = json.loads((root / "systematic" / "manifest.json").read_text())
    rng = np.random.default_rng(29)
    table = {}
    null_flags, null_count = 0, 0
    for entry in manifest["files"]:
        if not entry.get("true_dh"):
            continue
        eye_in_hand = entry["setup"] == "eye-in-hand"
        robot = robots.get_robot(entry["robot"])
        a, b, q = read(root / entry["file"])
        x, y = truth_of(root, entry, eye_in_hand)
        drop, k, ss, dof = oracle(eye_in_hand, robot, a, b, q, x, y)
        p = chi2.sf(drop, k)
        p_fit = chi2.sf(ss, dof)
        for _ in range(args.nulls):
            na, nb, nq = null_recording(eye_in_hand, robot, q, x, y, rng)
            nd, nk, _, _ = oracle(eye_in_hand, robot, na, nb, nq, x, y)
            null_flags += chi2.sf(nd, nk) < LEVEL
            null_count += 1
        key = (entry["kind"], entry["setup"])
        table.setdefault(key, []).append(p < LEVEL)
        print(f"{Path(entry['file']).stem:28} dof {k:2} p {p:9.2e} {'FLAG' if p < LEVEL else '    '}  whitened fit p {p_fit:9.2e}", flush=True)
    print(f"\nnull recordings flagged at {LEVEL}: {null_flags} of {null_count}")
    print("\n| level | setup | flagged by the oracle |\n|---|---|---|")
    for (kind, setup), flags in sorted(table.items()):
        print(f"| {kind} | {setup} | {sum(flags)} of {len(flags)} |")
    strong = [f for (kind, _), fl in table.items() if kind in ("dh1", "dh2") for f in fl]
    print(f"\n1 and 2 mm: {sum(strong)} of {len(strong)} ({100 * sum(strong) / len(strong):.0f} %)")


if __name__ == "__main__":
    main()
