"""Reading a pose of the kinhec pair files (numpy only): shared by the fixture scripts here and the
Python tests (crates/handeye-py/tests)."""

import numpy as np


def matrix4(v):
    """A pose of a kinhec file as a 4x4: a matrix, {"matrix": ...}, or translation and quaternion_xyzw."""
    if isinstance(v, list):
        return np.array(v, dtype=float)
    if "matrix" in v:
        return np.array(v["matrix"], dtype=float)
    x, y, z, w = v["quaternion_xyzw"]
    m = np.eye(4)
    m[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                 [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                 [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    m[:3, 3] = v["translation"]
    return m


def inverse(m):
    """The inverse of a rigid 4x4 transform."""
    out = np.eye(4)
    out[:3, :3] = m[:3, :3].T
    out[:3, 3] = -m[:3, :3].T @ m[:3, 3]
    return out
