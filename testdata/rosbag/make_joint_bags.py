#!/usr/bin/env python3
"""Writes the ROS 2 recordings with joint states (issue 29) of testdata/rosbag, with the same
independent writer as make_bags.py (the `rosbags` package, MIT licence):

    python3 -m venv /tmp/rosbags-venv && /tmp/rosbags-venv/bin/pip install rosbags==0.11.9 numpy
    /tmp/rosbags-venv/bin/python testdata/rosbag/make_joint_bags.py    # from the repository root

Each bag is a kinhec stream of testdata/kinhec/systematic (an uncalibrated robot: its DH errors
reported through the nominal model, eye-in-hand) played as a stop-and-go calibration: pose k at
k seconds, the robot standing still from 10 ms before to 10 ms after it:

- /tf: base_link -> tool0 at k s - 10 ms and k s + 10 ms (the same pose), so that the reader
  interpolates between two equal samples;
- /board_pose (geometry_msgs/PoseStamped, frame camera_link): the target at k s;
- /joint_states (sensor_msgs/msg/JointState): the robot's joint angles of the record, at k s -
  10 ms and k s + 10 ms, each message naming the joints in another order (reversed on odd k), a
  gripper joint among them, as a real robot's driver may; and one message with more names than
  positions, one without positions (skipped by the reader, which says so).

X (tool0_from_camera_link) and the target are those of the stream's truth file, copied as
`<bag>.truth.json`. The pose pairs of the bag are the records of the stream, to the digits the
stream prints, so that `calibrate` gives the same answer on both.
"""

import json
import shutil
import sys
from pathlib import Path

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer

sys.path.insert(0, str(Path(__file__).resolve().parent))
from make_bags import OUT, T0_NS, TS, Header, JointState, Point, Pose, PoseStamped, Quaternion, TFMessage, stamp, transform_stamped  # noqa: E402

STREAM = OUT.parent / "kinhec" / "systematic" / "dh2_iiwa14_eih_s1.jsonl"
STILL_NS = 10_000_000


def joint_state(ns, names, position):
    return JointState(
        header=Header(stamp=stamp(ns), frame_id=""),
        name=list(names),
        position=np.array(position, dtype=float),
        velocity=np.array([], dtype=float),
        effort=np.array([], dtype=float),
    )


def write(name, storage):
    path = OUT / name
    if path.exists():
        shutil.rmtree(path)
    records = [json.loads(line) for line in STREAM.read_text().splitlines() if line.strip()]
    joints = [f"iiwa_joint_{j + 1}" for j in range(len(records[0]["joints"]))]
    messages = []
    for k, r in enumerate(records):
        t_ns = T0_NS + (k + 1) * 1_000_000_000
        hand = r["base_from_gripper"]
        p = (np.array(hand["quaternion_xyzw"]), np.array(hand["translation"]))
        for ns in (t_ns - STILL_NS, t_ns + STILL_NS):
            messages.append((ns, "/tf", TFMessage(transforms=[transform_stamped(ns, "base_link", "tool0", p)]), TFMessage.__msgtype__))
            names = joints + ["gripper_finger_joint"]
            position = list(r["joints"]) + [0.04]
            if k % 2 == 1:
                names, position = names[::-1], position[::-1]
            messages.append((ns, "/joint_states", joint_state(ns, names, position), JointState.__msgtype__))
        cam = r["camera_from_target"]
        q, t = cam["quaternion_xyzw"], cam["translation"]
        msg = PoseStamped(
            header=Header(stamp=stamp(t_ns), frame_id="camera_link"),
            pose=Pose(position=Point(x=t[0], y=t[1], z=t[2]), orientation=Quaternion(x=q[0], y=q[1], z=q[2], w=q[3])),
        )
        messages.append((t_ns + 20_000_000, "/board_pose", msg, PoseStamped.__msgtype__))
    # Two bad joint states between poses 1 and 2 (skipped, and told): more names than positions,
    # and no positions at all.
    bad_ns = T0_NS + 1_500_000_000
    messages.append((bad_ns, "/joint_states", joint_state(bad_ns, joints, records[0]["joints"][:-1]), JointState.__msgtype__))
    messages.append((bad_ns + 1, "/joint_states", joint_state(bad_ns + 1, joints, []), JointState.__msgtype__))
    messages.sort(key=lambda m: m[0])
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    writer = Writer(path, version=9, storage_plugin=plugin)
    with writer:
        connections = {}
        for _, topic, _, msgtype in messages:
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, msgtype, typestore=TS)
        for log_ns, topic, msg, msgtype in messages:
            writer.write(connections[topic], log_ns, TS.serialize_cdr(msg, msgtype))
    truth = json.loads(STREAM.with_suffix("").with_suffix(".truth.json").read_text())
    truth = {
        "setup": "eye-in-hand",
        "stream": str(STREAM.relative_to(OUT.parent.parent)),
        "storage": storage,
        "joints": joints,
        "tool0_from_camera_link": truth["gripper_from_camera"]["matrix"],
        "base_link_from_board": truth["base_from_target"]["matrix"],
    }
    (OUT / f"{name}.truth.json").write_text(json.dumps(truth, indent=1) + "\n")
    print(f"{name}: {storage}, {len(records)} poses with joint states", file=sys.stderr)


if __name__ == "__main__":
    write("eih_joints_dh2_mcap", "mcap")
    write("eih_joints_dh2_sqlite3", "sqlite3")
