"""A ROS 2 peer for `handeye node`'s test, written on Eclipse Cyclone DDS (PyPI `cyclonedds`),
with ROS 2's DDS type names, topic prefixes and QoS: a robot driver publishing base_link → tool0
on rt/tf, the camera's optical frame on rt/tf_static, and a pose detector publishing the
target's pose (geometry_msgs/msg/PoseStamped) on rt/board_pose, from a simulated eye-in-hand
station stream with noise; then a few bad messages (a NaN quaternion, a quaternion of norm 2, a
frame no transform names). It reads rt/handeye/status all along and, once the stream is done,
subscribes to rt/tf_static late (transient local: it must still receive X). It checks that its
own CDR is byte for byte what `rosbags` (PyPI) serialises for the same messages.

Prints one JSON object on stdout: the truth (tool0_from_camera_link), the transforms received on
rt/tf_static, the status lines, and the CDR comparison.

Usage: python node_peer.py --stations 60 --seed 7 [--topic board_pose]
"""

import argparse
import json
import os
import math
import sys
import time
from dataclasses import dataclass

import numpy as np
from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import float64, int32, sequence, uint32
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32
    nanosec: uint32


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time
    frame_id: str


@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: float64
    y: float64
    z: float64


@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: float64
    y: float64
    z: float64


@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: float64
    y: float64
    z: float64
    w: float64


@dataclass
class Transform(IdlStruct, typename="geometry_msgs::msg::dds_::Transform_"):
    translation: Vector3
    rotation: Quaternion


@dataclass
class TransformStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TransformStamped_"):
    header: Header
    child_frame_id: str
    transform: Transform


@dataclass
class TFMessage(IdlStruct, typename="tf2_msgs::msg::dds_::TFMessage_"):
    transforms: sequence[TransformStamped]


@dataclass
class Pose(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    position: Point
    orientation: Quaternion


@dataclass
class PoseStamped(IdlStruct, typename="geometry_msgs::msg::dds_::PoseStamped_"):
    header: Header
    pose: Pose


@dataclass
class String(IdlStruct, typename="std_msgs::msg::dds_::String_"):
    data: str


def rotvec(v):
    """The rotation matrix of a rotation vector (Rodrigues)."""
    v = np.asarray(v, dtype=float)
    a = np.linalg.norm(v)
    if a < 1e-15:
        return np.eye(3)
    k = v / a
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(a) * K + (1 - math.cos(a)) * K @ K


def pose(R, t):
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = t
    return T


def quat_xyzw(R):
    """A unit quaternion [x, y, z, w] of a rotation matrix (w >= 0), by its largest component."""
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    if tr > max(R[0, 0], R[1, 1], R[2, 2]):
        w = math.sqrt(1 + tr) / 2
        q = [(R[2, 1] - R[1, 2]) / (4 * w), (R[0, 2] - R[2, 0]) / (4 * w), (R[1, 0] - R[0, 1]) / (4 * w), w]
    elif R[0, 0] >= R[1, 1] and R[0, 0] >= R[2, 2]:
        x = math.sqrt(1 + R[0, 0] - R[1, 1] - R[2, 2]) / 2
        q = [x, (R[0, 1] + R[1, 0]) / (4 * x), (R[0, 2] + R[2, 0]) / (4 * x), (R[2, 1] - R[1, 2]) / (4 * x)]
    elif R[1, 1] >= R[2, 2]:
        y = math.sqrt(1 - R[0, 0] + R[1, 1] - R[2, 2]) / 2
        q = [(R[0, 1] + R[1, 0]) / (4 * y), y, (R[1, 2] + R[2, 1]) / (4 * y), (R[0, 2] - R[2, 0]) / (4 * y)]
    else:
        z = math.sqrt(1 - R[0, 0] - R[1, 1] + R[2, 2]) / 2
        q = [(R[0, 2] + R[2, 0]) / (4 * z), (R[1, 2] + R[2, 1]) / (4 * z), z, (R[1, 0] - R[0, 1]) / (4 * z)]
    if q[3] < 0:
        q = [-v for v in q]
    return [float(v) for v in q]


def quat_matrix(q):
    x, y, z, w = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def stamp(t):
    sec = int(math.floor(t))
    return Time(sec, int(round((t - sec) * 1e9)) % 1_000_000_000)


def transform_msg(T, parent, child, t):
    q = quat_xyzw(T[:3, :3])
    return TransformStamped(
        Header(stamp(t), parent),
        child,
        Transform(Vector3(*T[:3, 3]), Quaternion(*q)),
    )


def pose_msg(T, frame, t, q=None):
    q = quat_xyzw(T[:3, :3]) if q is None else q
    return PoseStamped(Header(stamp(t), frame), Pose(Point(*T[:3, 3]), Quaternion(*q)))


def rosbags_cdr(msg, typename):
    """The CDR `rosbags` serialises for the same message (its own classes, from its typestore)."""
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    T = store.types
    Time_ = T["builtin_interfaces/msg/Time"]
    Header_ = T["std_msgs/msg/Header"]

    def header(h):
        return Header_(stamp=Time_(sec=h.stamp.sec, nanosec=h.stamp.nanosec), frame_id=h.frame_id)

    def vec(v, name):
        return T[name](x=v.x, y=v.y, z=v.z)

    def quat(q):
        return T["geometry_msgs/msg/Quaternion"](x=q.x, y=q.y, z=q.z, w=q.w)

    if typename == "tf2_msgs/msg/TFMessage":
        ts = [
            T["geometry_msgs/msg/TransformStamped"](
                header=header(m.header),
                child_frame_id=m.child_frame_id,
                transform=T["geometry_msgs/msg/Transform"](
                    translation=vec(m.transform.translation, "geometry_msgs/msg/Vector3"),
                    rotation=quat(m.transform.rotation),
                ),
            )
            for m in msg.transforms
        ]
        ros = T[typename](transforms=ts)
    elif typename == "geometry_msgs/msg/PoseStamped":
        ros = T[typename](
            header=header(msg.header),
            pose=T["geometry_msgs/msg/Pose"](
                position=vec(msg.pose.position, "geometry_msgs/msg/Point"),
                orientation=quat(msg.pose.orientation),
            ),
        )
    else:
        ros = T[typename](data=msg.data)
    return bytes(store.serialize_cdr(ros, typename))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--stations", type=int, default=60)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--topic", default="board_pose")
    ap.add_argument("--noise-mm", type=float, default=0.5)
    ap.add_argument("--noise-deg", type=float, default=0.05)
    ap.add_argument("--discovery", type=float, default=30.0)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)

    # The truth: tool0_from_camera_link, and the optical frame under camera_link (REP 103).
    link_from_optical = pose(rotvec([0, 0, -math.pi / 2]) @ rotvec([-math.pi / 2, 0, 0]), [0, 0, 0])
    tool_from_link = pose(rotvec([0.05, -0.1, 0.2]), [0.03, -0.05, 0.08])
    tool_from_optical = tool_from_link @ link_from_optical
    base_from_target = pose(rotvec([0, 0, 0.3]), [0.6, 0.1, 0.0])
    looking_down = rotvec([math.pi, 0, 0])

    dp = DomainParticipant(int(os.environ.get("ROS_DOMAIN_ID") or 0))
    reliable = Qos(
        Policy.Reliability.Reliable(max_blocking_time=1_000_000_000),
        Policy.Durability.Volatile,
        Policy.History.KeepLast(1000),
    )
    latched = Qos(
        Policy.Reliability.Reliable(max_blocking_time=1_000_000_000),
        Policy.Durability.TransientLocal,
        Policy.History.KeepLast(1),
    )
    tf_topic = Topic(dp, "rt/tf", TFMessage)
    static_topic = Topic(dp, "rt/tf_static", TFMessage)
    tf = DataWriter(dp, tf_topic, qos=reliable)
    static = DataWriter(dp, static_topic, qos=latched)
    target = DataWriter(dp, Topic(dp, "rt/" + args.topic, PoseStamped), qos=reliable)
    status = DataReader(dp, Topic(dp, "rt/handeye/status", String), qos=reliable)

    # Wait for the node: its readers matched on the three topics.
    start = time.time()
    while time.time() - start < args.discovery:
        if all(len(w.get_matched_subscriptions()) > 0 for w in (tf, target)):
            break
        time.sleep(0.05)
    else:
        print(json.dumps({"error": "the node was not discovered"}))
        return 1
    time.sleep(0.5)

    lines = []

    def drain():
        for s in status.take(N=1000):
            lines.append(s.data)

    t0 = 1_700_000_000.0
    static.write(
        TFMessage([transform_msg(link_from_optical, "camera_link", "camera_optical_frame", t0)])
    )
    cdr = {}
    for k in range(args.stations):
        t = t0 + 0.1 * k
        R = looking_down @ rotvec(rng.uniform(-0.45, 0.45, 3))
        p = np.array([0.6, 0.1, 0.45]) + rng.uniform(-0.1, 0.1, 3)
        base_from_tool = pose(R, p)
        # The robot stands during the capture: its pose before and after the image's stamp.
        for dt in (-0.01, 0.01):
            m = TFMessage([transform_msg(base_from_tool, "base_link", "tool0", t + dt)])
            tf.write(m)
            if "tf" not in cdr:
                cdr["tf"] = m.serialize() == rosbags_cdr(m, "tf2_msgs/msg/TFMessage")
        optical_from_target = np.linalg.inv(tool_from_optical) @ np.linalg.inv(base_from_tool) @ base_from_target
        noise = pose(
            rotvec(rng.normal(0, math.radians(args.noise_deg), 3)),
            rng.normal(0, args.noise_mm * 1e-3, 3),
        )
        m = pose_msg(optical_from_target @ noise, "camera_optical_frame", t)
        target.write(m)
        if "pose" not in cdr:
            cdr["pose"] = m.serialize() == rosbags_cdr(m, "geometry_msgs/msg/PoseStamped")
        time.sleep(0.005)
        drain()
    cdr["string"] = String("{}").serialize() == rosbags_cdr(String("{}"), "std_msgs/msg/String")

    # Bad messages, each after the stream (its stamps beyond the robot's last one are waited
    # for, so they come with robot transforms around them).
    t = t0 + 0.1 * args.stations
    R = looking_down
    base_from_tool = pose(R, [0.6, 0.1, 0.45])
    bad = {
        "nan_quaternion": pose_msg(base_from_tool, "camera_optical_frame", t, [math.nan, 0, 0, 1]),
        "unknown_frame": pose_msg(base_from_tool, "nowhere_frame", t + 0.05),
    }
    target.write(bad["nan_quaternion"])
    target.write(bad["unknown_frame"])
    tf.write(
        TFMessage(
            [
                TransformStamped(
                    Header(stamp(t + 0.02), "base_link"),
                    "tool0",
                    Transform(Vector3(0.6, 0.1, 0.45), Quaternion(0, 0, 0, 2)),
                )
            ]
        )
    )
    for dt in (0.0, 0.1):
        tf.write(TFMessage([transform_msg(base_from_tool, "base_link", "tool0", t + dt)]))

    # Status lines until they stop for a second.
    quiet = time.time()
    while time.time() - quiet < 1.5:
        before = len(lines)
        drain()
        if len(lines) > before:
            quiet = time.time()
        time.sleep(0.02)

    # Late subscription to /tf_static: X must still come (transient local).
    late = DataReader(dp, static_topic, qos=latched)
    received = []
    start = time.time()
    while time.time() - start < 10 and not any(
        tr.child_frame_id == "camera_link" for m in received for tr in m.transforms
    ):
        for m in late.take(N=100):
            received.append(m)
        time.sleep(0.05)
    drain()

    published = [
        {
            "parent": tr.header.frame_id,
            "child": tr.child_frame_id,
            "translation": [tr.transform.translation.x, tr.transform.translation.y, tr.transform.translation.z],
            "quaternion_xyzw": [
                tr.transform.rotation.x,
                tr.transform.rotation.y,
                tr.transform.rotation.z,
                tr.transform.rotation.w,
            ],
        }
        for m in received
        for tr in m.transforms
    ]
    out = {
        "truth": {
            "parent": "tool0",
            "child": "camera_link",
            "translation": list(tool_from_link[:3, 3]),
            "quaternion_xyzw": quat_xyzw(tool_from_link[:3, :3]),
        },
        "tf_static": published,
        "status": lines,
        "cdr_identical_to_rosbags": cdr,
    }
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
