#!/usr/bin/env python3
"""Writes testdata/rotation/fixtures.json: rotations written in each of handeye's rotation
conventions (`handeye::RotationConvention`) with the matrix SciPy's `Rotation` gives for them;
and a realistic recording (testdata/kinhec/pairs/nominal_stations_eih_s0.jsonl) rewritten by
SciPy in vendors' conventions: `kuka_abc_stations_eih_s0.csv` (both sides KUKA A, B, C, read
with `--rotation kuka-abc`) and `vendor_fields_stations_eih_s0.jsonl` (the robot's
`kuka_abc_deg`, the camera's `target_from_camera` as ABB's `quaternion_wxyz`: no flag needed).

    python3 -m venv /tmp/venv-scipy && /tmp/venv-scipy/bin/pip install scipy
    /tmp/venv-scipy/bin/python testdata/rotation/make_fixtures.py

The reference is SciPy's, a library independent of handeye; each convention maps to SciPy as
below (upper-case axes: intrinsic, turning about the axes already turned; lower-case: extrinsic,
about the fixed axes). Before writing, the script checks SciPy's matrices against the vendors'
own formulas where they are published (the quaternion formulas of Roboception's "pose formats"
appendix, the matrix products of RoboDK's `robomath`, rewritten here from their equations) and
against ABB's worked example, so the fixtures rest on two sources, not one.

Deterministic (a fixed seed); the JSON numbers are Python's shortest round-trip reprs, so the
Rust test reads exactly the doubles SciPy was given.
"""

import json
import math
import os

import numpy as np
import scipy
from scipy.spatial.transform import Rotation

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "fixtures.json")
SEED = 33011


def deg_euler(seq):
    return lambda v: Rotation.from_euler(seq, v, degrees=True)


# handeye's name -> (SciPy constructor from the values as the file writes them, unit).
SCIPY = {
    "quaternion-xyzw": (lambda v: Rotation.from_quat(v), None),
    "quaternion-wxyz": (lambda v: Rotation.from_quat(v, scalar_first=True), None),
    "rvec": (lambda v: Rotation.from_rotvec(v), "rad"),
    # KUKA A, B, C: z-y'-x'' intrinsic, R = Rz(A) Ry(B) Rx(C).
    "kuka-abc": (deg_euler("ZYX"), "deg"),
    # Mitsubishi A, B, C: about the fixed x, y, z, R = Rz(C) Ry(B) Rx(A).
    "mitsubishi-abc": (deg_euler("xyz"), "deg"),
    # FANUC W, P, R: about the fixed x, y, z, R = Rz(R) Ry(P) Rx(W).
    "fanuc-wpr": (deg_euler("xyz"), "deg"),
    # Yaskawa Rx, Ry, Rz: FANUC's formula, R = Rz(Rz) Ry(Ry) Rx(Rx).
    "yaskawa-rxryrz": (deg_euler("xyz"), "deg"),
    # Staubli Rx, Ry, Rz: x-y'-z'' intrinsic, R = Rx Ry Rz.
    "staubli-xyz": (deg_euler("XYZ"), "deg"),
    # Kawasaki O, A, T: z-y'-z'' intrinsic, R = Rz(O) Ry(A) Rz(T).
    "kawasaki-oat": (deg_euler("ZYZ"), "deg"),
    # ROS roll, pitch, yaw: about the fixed x, y, z, R = Rz(yaw) Ry(pitch) Rx(roll).
    "rpy": (lambda v: Rotation.from_euler("xyz", v), "rad"),
    "rpy-deg": (deg_euler("xyz"), "deg"),
}


def special(name):
    """Values at the edges of each convention: gimbal lock, half turns, the identity."""
    if name == "quaternion-xyzw":
        return [[0, 0, 0, 1], [0, 0, 0, -1], [1, 0, 0, 0], [0.5, -0.5, 0.5, -0.5],
                [0.0, 0.70710678118654757, 0.0, 0.70710678118654757]]
    if name == "quaternion-wxyz":
        return [[1, 0, 0, 0], [-1, 0, 0, 0], [0, 0, 0, 1], [-0.5, 0.5, -0.5, 0.5],
                [0.70710678118654757, 0.0, 0.70710678118654757, 0.0]]
    if name == "rvec":
        return [[0, 0, 0], [math.pi, 0, 0], [0, 0, -math.pi], [1e-9, -2e-9, 3e-9],
                [2.0, -1.5, 1.0]]
    deg = SCIPY[name][1] == "deg"
    quarter, half = (90.0, 180.0) if deg else (math.pi / 2, math.pi)
    # The middle angle of every Euler convention is its gimbal-lock angle (±90°, or 0 and 180°
    # for the z-y-z convention), the outer two then turn about one axis.
    middles = [0.0, half] if name == "kawasaki-oat" else [quarter, -quarter]
    out = [[0.0, 0.0, 0.0], [half, 0.0, 0.0], [0.0, 0.0, -half], [-half, 0.0, half]]
    for m in middles:
        out += [[0.0, m, 0.0], [0.3 * half, m, -0.2 * half], [-0.7 * half, m, 0.9 * half]]
    return out


def random_values(name, rng, count):
    if name.startswith("quaternion"):
        q = rng.normal(size=(count, 4))
        q /= np.linalg.norm(q, axis=1)[:, None]
        return q.tolist()
    if name == "rvec":
        axis = rng.normal(size=(count, 3))
        axis /= np.linalg.norm(axis, axis=1)[:, None]
        angle = rng.uniform(0.0, math.pi, size=(count, 1))
        return (axis * angle).tolist()
    deg = SCIPY[name][1] == "deg"
    half = 180.0 if deg else math.pi
    v = rng.uniform(-half, half, size=(count, 3))
    return v.tolist()


# --- Independent formulas, from the vendors' documentation --------------------------------------

def quat_matrix(x, y, z, w):
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def roboception_zyx(yaw, pitch, roll):
    """Roboception's pose formats: the quaternion of rz(yaw) ry(pitch) rx(roll), angles in degrees
    (their KUKA A, B, C; FANUC R, P, W; Mitsubishi C, B, A)."""
    a, b, c = (math.radians(t) / 2 for t in (yaw, pitch, roll))
    x = math.cos(a) * math.cos(b) * math.sin(c) - math.sin(a) * math.sin(b) * math.cos(c)
    y = math.cos(a) * math.sin(b) * math.cos(c) + math.sin(a) * math.cos(b) * math.sin(c)
    z = math.sin(a) * math.cos(b) * math.cos(c) - math.cos(a) * math.sin(b) * math.sin(c)
    w = math.cos(a) * math.cos(b) * math.cos(c) + math.sin(a) * math.sin(b) * math.sin(c)
    return quat_matrix(x, y, z, w)


def roboception_oat(o, a, t):
    """Roboception's Kawasaki XYZ-OAT: the quaternion of rz(O) ry(A) rz(T), degrees."""
    o, a, t = (math.radians(v) / 2 for v in (o, a, t))
    x = math.cos(o) * math.sin(a) * math.sin(t) - math.sin(o) * math.sin(a) * math.cos(t)
    y = math.cos(o) * math.sin(a) * math.cos(t) + math.sin(o) * math.sin(a) * math.sin(t)
    z = math.sin(o) * math.cos(a) * math.cos(t) + math.cos(o) * math.cos(a) * math.sin(t)
    w = math.cos(o) * math.cos(a) * math.cos(t) - math.sin(o) * math.cos(a) * math.sin(t)
    return quat_matrix(x, y, z, w)


def elementary(axis, degrees):
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    return {
        "x": np.array([[1, 0, 0], [0, c, -s], [0, s, c]]),
        "y": np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]),
        "z": np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]),
    }[axis]


def robodk_txyzrxyz(rx, ry, rz):
    """RoboDK's Staubli pose (Pose_2_Staubli = TxyzRxyz): rotx(rx) roty(ry) rotz(rz), degrees."""
    return elementary("x", rx) @ elementary("y", ry) @ elementary("z", rz)


def vendor_reference(name, v):
    if name == "kuka-abc":
        return roboception_zyx(v[0], v[1], v[2])
    if name == "mitsubishi-abc":
        return roboception_zyx(v[2], v[1], v[0])
    if name in ("fanuc-wpr", "yaskawa-rxryrz"):
        return roboception_zyx(v[2], v[1], v[0])
    if name == "kawasaki-oat":
        return roboception_oat(*v)
    if name == "staubli-xyz":
        return robodk_txyzrxyz(*v)
    return None


def recording():
    """The kinhec recording's stamps and (robot, camera) 4x4 matrices."""
    path = os.path.join(HERE, "..", "kinhec", "pairs", "nominal_stations_eih_s0.jsonl")
    out = []
    with open(path, encoding="utf-8") as f:
        for line in f:
            if line.strip().startswith("{"):
                r = json.loads(line)
                out.append((r["stamp"], np.array(r["base_from_gripper"]), np.array(r["camera_from_target"])))
    return out


def rewrite():
    """The recording in vendors' conventions, written by SciPy."""
    def kuka(m):
        return [*m[:3, 3], *Rotation.from_matrix(m[:3, :3]).as_euler("ZYX", degrees=True)]

    pairs = recording()
    columns = [f"{frame}_{s}" for frame in ("base_from_gripper", "camera_from_target") for s in "xyzabc"]
    with open(os.path.join(HERE, "kuka_abc_stations_eih_s0.csv"), "w", encoding="utf-8") as f:
        f.write("# testdata/kinhec/pairs/nominal_stations_eih_s0.jsonl in KUKA A, B, C (degrees): --rotation kuka-abc\n")
        f.write(",".join(["stamp", *columns]) + "\n")
        for stamp, robot, camera in pairs:
            f.write(",".join(repr(float(v)) for v in [stamp, *kuka(robot), *kuka(camera)]) + "\n")
    with open(os.path.join(HERE, "vendor_fields_stations_eih_s0.jsonl"), "w", encoding="utf-8") as f:
        for stamp, robot, camera in pairs:
            target_from_camera = np.linalg.inv(camera)
            record = {
                "stamp": stamp,
                "base_from_gripper": {
                    "translation": robot[:3, 3].tolist(),
                    "kuka_abc_deg": Rotation.from_matrix(robot[:3, :3]).as_euler("ZYX", degrees=True).tolist(),
                },
                "target_from_camera": {
                    "translation": target_from_camera[:3, 3].tolist(),
                    "quaternion_wxyz": Rotation.from_matrix(target_from_camera[:3, :3]).as_quat(scalar_first=True).tolist(),
                },
            }
            f.write(json.dumps(record) + "\n")


def main():
    rewrite()
    rng = np.random.default_rng(SEED)
    fixtures = {}
    for name, (make, unit) in SCIPY.items():
        cases = []
        for values in special(name) + random_values(name, rng, 40):
            values = [float(x) for x in values]
            matrix = make(values).as_matrix()
            ref = vendor_reference(name, values)
            if ref is not None:
                assert np.abs(ref - matrix).max() < 1e-12, (name, values)
            cases.append({"values": values, "matrix": matrix.tolist()})
        fixtures[name] = cases

    # ABB RAPID Reference Manual, data type `orient`, example 1: a tool whose z axis points along
    # the base x axis and whose y axis is the base y axis is [q1, q2, q3, q4] = [0.707, 0, 0.707, 0].
    abb = Rotation.from_quat([0.707107, 0, 0.707107, 0], scalar_first=True).as_matrix()
    assert np.abs(abb - np.array([[0, 0, 1], [0, 1, 0], [-1, 0, 0]])).max() < 1e-6

    document = {
        "generator": "testdata/rotation/make_fixtures.py",
        "scipy": scipy.__version__,
        "seed": SEED,
        "note": "values as the file writes them (degrees for the *-deg conventions and the vendor "
                "Euler angles); matrix: SciPy's Rotation(...).as_matrix(), row-major",
        "conventions": fixtures,
    }
    # One rotation per line.
    head = {k: v for k, v in document.items() if k != "conventions"}
    lines = ["{"] + [f" {json.dumps(k)}: {json.dumps(v)}," for k, v in head.items()]
    lines.append(' "conventions": {')
    names = list(fixtures)
    for i, name in enumerate(names):
        lines.append(f"  {json.dumps(name)}: [")
        cases = fixtures[name]
        for j, case in enumerate(cases):
            lines.append("   " + json.dumps(case) + ("," if j + 1 < len(cases) else ""))
        lines.append("  ]" + ("," if i + 1 < len(names) else ""))
    lines += [" }", "}"]
    with open(OUT, "w", encoding="utf-8") as f:
        f.write("\n".join(lines) + "\n")
    with open(OUT, encoding="utf-8") as f:
        assert json.load(f) == document
    print(f"wrote {OUT}: {sum(len(c) for c in fixtures.values())} rotations")


if __name__ == "__main__":
    main()
