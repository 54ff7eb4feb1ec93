#!/usr/bin/env python3
"""Writes the small ROS 2 recordings (rosbag2) of testdata/rosbag with an independent writer.

The recordings are written by the `rosbags` package (MIT licence, https://gitlab.com/ternaris/rosbags),
which serialises the messages (CDR) and writes both rosbag2 storages, MCAP and SQLite3, without ROS.

    python3 -m venv /tmp/rosbags-venv && /tmp/rosbags-venv/bin/pip install rosbags==0.11.9 numpy
    /tmp/rosbags-venv/bin/python testdata/rosbag/make_bags.py    # from the repository root

Every bag is a cell arm filmed by one camera:

- /tf_static (one message at the start): world -> base_link, flange -> tool0 (the robot's static
  chain) and camera_link -> camera_color_optical_frame (the camera's static chain, the usual optical
  rotation).
- /tf at 100 Hz: base_link -> flange (the robot's dynamic transform), a smooth motion rotating by
  tens of degrees about changing axes.
- the target at 10 Hz, stamps between the robot's (so that handeye must interpolate): either in /tf
  (camera_color_optical_frame -> board), or a geometry_msgs/PoseStamped (/board_pose) or a
  geometry_msgs/TransformStamped (/board_transform) whose header names camera_color_optical_frame.
- eye-in-hand: X = tool0_from_camera_link, the board fixed in base_link. Eye-to-hand: X =
  base_link_from_camera_link, the board fixed on tool0.

The robot's pose between two 100 Hz samples is, by construction, their slerp / linear
interpolation, and the camera's observation is made from that interpolated pose: noise-free bags
are then exact for an interpolating reader, and X is recovered to rounding. One bag stamps its
detections with a camera clock 37 ms ahead of the robot's (the clock offset to find). Noisy bags add noise to
every robot sample (0.02 deg, 0.05 mm) and every detection (0.1 deg, 0.5 mm).

The truth of each bag is in `<bag>.truth.json`: X under the names of its frames (from
camera_link and from camera_color_optical_frame), and the target's fixed pose.
"""

import json
import shutil
import sys
from pathlib import Path

import numpy as np
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

OUT = Path(__file__).resolve().parent
TS = get_typestore(Stores.ROS2_HUMBLE)
TFMessage = TS.types["tf2_msgs/msg/TFMessage"]
TransformStamped = TS.types["geometry_msgs/msg/TransformStamped"]
PoseStamped = TS.types["geometry_msgs/msg/PoseStamped"]
Header = TS.types["std_msgs/msg/Header"]
Time = TS.types["builtin_interfaces/msg/Time"]
Transform = TS.types["geometry_msgs/msg/Transform"]
Vector3 = TS.types["geometry_msgs/msg/Vector3"]
Quaternion = TS.types["geometry_msgs/msg/Quaternion"]
Pose = TS.types["geometry_msgs/msg/Pose"]
Point = TS.types["geometry_msgs/msg/Point"]
JointState = TS.types["sensor_msgs/msg/JointState"]

T0_NS = 1_700_000_000_000_000_000  # stamps near 2023-11-14, as a real recording has
ROBOT_HZ = 100
CAMERA_HZ = 10
SECONDS = 8
CAMERA_DELAY_NS = 3_700_000  # detections fall between robot samples


# ---- poses as (quaternion xyzw, translation); all arithmetic in float64 ----
def qmul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return np.array([
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ])


def qconj(q):
    return np.array([-q[0], -q[1], -q[2], q[3]])


def qrot(q, v):
    p = qmul(qmul(q, np.array([v[0], v[1], v[2], 0.0])), qconj(q))
    return p[:3]


def qexp(w):
    angle = np.linalg.norm(w)
    if angle < 1e-15:
        return np.array([0.0, 0.0, 0.0, 1.0])
    axis = w / angle
    return np.concatenate([axis * np.sin(angle / 2), [np.cos(angle / 2)]])


def compose(a, b):
    """a_from_c = a_from_b * b_from_c."""
    return (qmul(a[0], b[0]), qrot(a[0], b[1]) + a[1])


def inverse(a):
    qi = qconj(a[0])
    return (qi, -qrot(qi, a[1]))


def slerp(qa, qb, s):
    d = float(np.dot(qa, qb))
    if d < 0:
        qb, d = -qb, -d
    d = min(1.0, d)
    theta = np.arccos(d)
    if theta < 1e-12:
        q = qa + s * (qb - qa)
    else:
        q = (np.sin((1 - s) * theta) * qa + np.sin(s * theta) * qb) / np.sin(theta)
    return q / np.linalg.norm(q)


def interpolate(a, b, s):
    return (slerp(a[0], b[0], s), a[1] + s * (b[1] - a[1]))


def pose(rotvec, t):
    return (qexp(np.array(rotvec, dtype=float)), np.array(t, dtype=float))


def noisy(p, rng, rot_deg, trans):
    w = rng.normal(0.0, np.radians(rot_deg) / np.sqrt(3), 3)
    return (qmul(p[0], qexp(w)), p[1] + rng.normal(0.0, trans / np.sqrt(3), 3))


def matrix(p):
    q, t = p
    x, y, z, w = q
    r = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])
    m = np.eye(4)
    m[:3, :3] = r
    m[:3, 3] = t
    return m.tolist()


# ---- the scene ----
WORLD_FROM_BASE = pose([0.0, 0.0, 0.3], [1.0, 0.5, 0.0])
FLANGE_FROM_TOOL0 = pose([0.0, 0.0, 0.7], [0.0, 0.0, 0.05])
# The usual optical frame: z forward, x right, y down (rpy = -90°, 0, -90°), a few mm off.
LINK_FROM_OPTICAL = (
    np.array([-0.5, 0.5, -0.5, 0.5]),
    np.array([0.0, 0.015, 0.0]),
)
X_EYE_IN_HAND = pose([0.1, -0.2, 0.3], [0.05, -0.03, 0.08])  # tool0_from_camera_link
BASE_FROM_BOARD = pose([2.9, 0.2, 0.1], [0.55, 0.05, -0.05])
X_EYE_TO_HAND = pose([0.3, 2.0, -0.2], [1.2, 0.1, 0.6])  # base_link_from_camera_link
TOOL0_FROM_BOARD = pose([0.2, 0.1, -0.3], [0.0, 0.02, 0.12])


def base_from_flange(tau):
    """The robot's motion at tau seconds from the start."""
    w = [
        0.45 * np.sin(0.7 * tau) + 0.1,
        0.40 * np.sin(1.1 * tau + 1.0),
        0.50 * np.sin(0.5 * tau + 2.0),
    ]
    t = [
        0.40 + 0.08 * np.sin(0.9 * tau),
        0.05 * np.cos(0.6 * tau),
        0.50 + 0.06 * np.sin(0.4 * tau + 0.5),
    ]
    return pose(w, t)


def stamp(ns):
    return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def transform_stamped(ns, parent, child, p):
    q, t = p
    return TransformStamped(
        header=Header(stamp=stamp(ns), frame_id=parent),
        child_frame_id=child,
        transform=Transform(
            translation=Vector3(x=t[0], y=t[1], z=t[2]),
            rotation=Quaternion(x=q[0], y=q[1], z=q[2], w=q[3]),
        ),
    )


def write_bag(name, storage, setup, target, noise, seed, compress=False, extra_topic=False, clock_offset_ns=0):
    path = OUT / name
    if path.exists():
        shutil.rmtree(path)
    rng = np.random.default_rng(seed)
    n_robot = SECONDS * ROBOT_HZ + 1
    robot_ns = [T0_NS + k * (1_000_000_000 // ROBOT_HZ) for k in range(n_robot)]
    robot_true = [base_from_flange((ns - T0_NS) * 1e-9) for ns in robot_ns]
    robot_published = [
        noisy(p, rng, 0.02, 0.00005) if noise else p for p in robot_true
    ]
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    writer = Writer(path, version=9, storage_plugin=plugin)
    if compress:
        writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
    messages = []  # (log time ns, connection key, message, type)

    statics = [
        transform_stamped(T0_NS, "world", "base_link", WORLD_FROM_BASE),
        transform_stamped(T0_NS, "flange", "tool0", FLANGE_FROM_TOOL0),
        transform_stamped(T0_NS, "camera_link", "camera_color_optical_frame", LINK_FROM_OPTICAL),
    ]
    messages.append((T0_NS, "/tf_static", TFMessage(transforms=statics), TFMessage.__msgtype__))
    for ns, p in zip(robot_ns, robot_published):
        msg = TFMessage(transforms=[transform_stamped(ns, "base_link", "flange", p)])
        messages.append((ns, "/tf", msg, TFMessage.__msgtype__))

    x = X_EYE_IN_HAND if setup == "eye-in-hand" else X_EYE_TO_HAND
    optical_from_link = inverse(LINK_FROM_OPTICAL)
    step = 1_000_000_000 // CAMERA_HZ
    n_camera = 0
    for k in range(SECONDS * CAMERA_HZ):
        ns = T0_NS + 50_000_000 + k * step + CAMERA_DELAY_NS
        # The robot between its two samples, as an interpolating reader sees it (noise-free).
        i = (ns - T0_NS) // (1_000_000_000 // ROBOT_HZ)
        s = (ns - robot_ns[i]) / (robot_ns[i + 1] - robot_ns[i])
        base_from_tool0 = compose(interpolate(robot_true[i], robot_true[i + 1], s), FLANGE_FROM_TOOL0)
        if setup == "eye-in-hand":
            link_from_board = compose(compose(inverse(x), inverse(base_from_tool0)), BASE_FROM_BOARD)
        else:
            link_from_board = compose(compose(inverse(x), base_from_tool0), TOOL0_FROM_BOARD)
        optical_from_board = compose(optical_from_link, link_from_board)
        if noise:
            optical_from_board = noisy(optical_from_board, rng, 0.1, 0.0005)
        # A camera clock ahead of the robot's by clock_offset_ns stamps the detection later.
        ns += clock_offset_ns
        log_ns = ns + 20_000_000  # the detector publishes 20 ms after the exposure
        if target == "tf":
            msg = TFMessage(transforms=[transform_stamped(ns, "camera_color_optical_frame", "board", optical_from_board)])
            messages.append((log_ns, "/tf", msg, TFMessage.__msgtype__))
        elif target == "pose":
            q, t = optical_from_board
            msg = PoseStamped(
                header=Header(stamp=stamp(ns), frame_id="camera_color_optical_frame"),
                pose=Pose(
                    position=Point(x=t[0], y=t[1], z=t[2]),
                    orientation=Quaternion(x=q[0], y=q[1], z=q[2], w=q[3]),
                ),
            )
            messages.append((log_ns, "/board_pose", msg, PoseStamped.__msgtype__))
        else:
            msg = transform_stamped(ns, "camera_color_optical_frame", "board", optical_from_board)
            messages.append((log_ns, "/board_transform", msg, TransformStamped.__msgtype__))
        n_camera += 1
    if extra_topic:
        for k in range(SECONDS * CAMERA_HZ):
            ns = T0_NS + k * step
            msg = JointState(
                header=Header(stamp=stamp(ns), frame_id=""),
                name=["joint_1"], position=np.array([0.1 * k]), velocity=np.array([], dtype=float),
                effort=np.array([], dtype=float),
            )
            messages.append((ns, "/joint_states", msg, JointState.__msgtype__))

    messages.sort(key=lambda m: m[0])
    with writer:
        connections = {}
        for _, topic, _, msgtype in messages:
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, msgtype, typestore=TS)
        for log_ns, topic, msg, msgtype in messages:
            writer.write(connections[topic], log_ns, TS.serialize_cdr(msg, msgtype))

    frames = {
        "eye-in-hand": ("tool0_from_camera_link", "tool0_from_camera_color_optical_frame"),
        "eye-to-hand": ("base_link_from_camera_link", "base_link_from_camera_color_optical_frame"),
    }[setup]
    truth = {
        "setup": setup,
        "noise": noise,
        "target": target,
        "storage": storage,
        "robot_samples": n_robot,
        "detections": n_camera,
        "clock_offset_s": clock_offset_ns / 1e9,
        frames[0]: matrix(x),
        frames[1]: matrix(compose(x, LINK_FROM_OPTICAL)),
    }
    if setup == "eye-in-hand":
        truth["base_link_from_board"] = matrix(BASE_FROM_BOARD)
    else:
        truth["tool0_from_board"] = matrix(TOOL0_FROM_BOARD)
    (OUT / f"{name}.truth.json").write_text(json.dumps(truth, indent=1) + "\n")
    print(f"{name}: {storage}, {setup}, target in {target}, noise {noise}", file=sys.stderr)


BAGS = [
    # name, storage, setup, target, noise, seed, options
    ("eih_tf_mcap", "mcap", "eye-in-hand", "tf", False, 1, {}),
    ("eih_pose_sqlite3", "sqlite3", "eye-in-hand", "pose", False, 2, {"extra_topic": True}),
    ("eth_tf_sqlite3", "sqlite3", "eye-to-hand", "tf", False, 3, {}),
    ("eth_transform_mcap", "mcap", "eye-to-hand", "transform", False, 4, {"compress": True}),
    ("eih_pose_noisy_mcap", "mcap", "eye-in-hand", "pose", True, 5, {"extra_topic": True}),
    ("eth_tf_noisy_sqlite3", "sqlite3", "eye-to-hand", "tf", True, 6, {}),
    # The detector stamps with a clock 37 ms ahead of the robot's.
    ("eih_pose_offset_mcap", "mcap", "eye-in-hand", "pose", False, 8, {"clock_offset_ns": 37_000_000}),
]

def write_cdr_fixtures():
    """Single messages in both byte orders (the decoder's unit tests): a TFMessage of two
    transforms with frame names of every length modulo 4, and a PoseStamped."""
    out = OUT / "cdr"
    out.mkdir(exist_ok=True)
    tf = TFMessage(transforms=[
        transform_stamped(1_700_000_000_123_456_789, "base_link", "flange", pose([0.1, -0.2, 0.3], [0.4, -0.5, 0.6])),
        transform_stamped(5, "/odom", "tool", pose([0.0, 0.0, 1.0], [7.0, 8.0, 9.0])),
    ])
    q, t = pose([-0.3, 0.2, 0.1], [0.25, 0.5, 1.5])
    ps = PoseStamped(
        header=Header(stamp=Time(sec=-2, nanosec=999_999_999), frame_id="camera_color_optical_frame"),
        pose=Pose(position=Point(x=t[0], y=t[1], z=t[2]), orientation=Quaternion(x=q[0], y=q[1], z=q[2], w=q[3])),
    )
    for msg, name in [(tf, "tf_message"), (ps, "pose_stamped")]:
        for little, suffix in [(True, "le"), (False, "be")]:
            data = bytes(TS.serialize_cdr(msg, msg.__msgtype__, little_endian=little))
            (out / f"{name}_{suffix}.cdr").write_bytes(data)


if __name__ == "__main__":
    for name, storage, setup, target, noise, seed, options in BAGS:
        write_bag(name, storage, setup, target, noise, seed, **options)
    write_cdr_fixtures()
