#!/usr/bin/env python3
"""Writes the ROS 2 recordings of a single AprilTag (testdata/rosbag/tag_*) from the recording on
the pixels testdata/pixels/tag_eih.jsonl, with the same independent writer as make_bags.py.

    python3 -m venv /tmp/rosbags-venv && /tmp/rosbags-venv/bin/pip install rosbags==0.11.9 numpy
    /tmp/rosbags-venv/bin/python testdata/rosbag/make_tag_bags.py    # from the repository root

Every bag holds the 30 images of tag_eih.jsonl (one 6 cm tag, eye-in-hand), one a second:

- /tf: base_link -> tool0, the record's robot pose, sampled at 10 Hz from 0.4 s before to 0.4 s
  after the image's stamp (the robot stops for each image), one sample at the stamp itself.
- /apriltag/detections (apriltag_msgs/msg/AprilTagDetectionArray, apriltag_msgs 2.x: Point
  centre, Point[4] corners, float64[9] homography), header frame `camera`, tag 36h11 id 3: the
  record's four pixels as the corners (the record's target points are AprilTag's corner order,
  (-s/2, s/2), (s/2, s/2), (s/2, -s/2), (-s/2, -s/2)), the centre their mean, the homography
  zeros (not read).
- /camera/camera_info (sensor_msgs/msg/CameraInfo) at each image: tag_eih.intrinsics.yml as
  plumb_bob.

The bags:
- tag_eih_mcap (MCAP) and tag_eih_sqlite3 (SQLite3): as above; a calibration on the pixels gives
  the X of tag_eih.jsonl.
- tag_eih_hostile_mcap: the same with image 3 truncated by 40 bytes, image 6 with 5 corners (16
  bytes more than the type defines), image 9 showing tag 7 only, image 12 showing tag 7 beside
  tag 3: a reader skips images 3, 6 and 9 and leaves out tag 7 of image 12.
- tag_eih_noinfo_sqlite3: without camera_info (the intrinsics must be given).

The messages of AprilTagDetectionArray are serialised here by hand (little-endian CDR), checked
against the writer's own serialisation for the well-formed ones.
"""

import json
import re
import shutil
import struct
import sys
from pathlib import Path

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore, get_types_from_msg

OUT = Path(__file__).resolve().parent
PIXELS = OUT.parent / "pixels"
TS = get_typestore(Stores.ROS2_HUMBLE)
# apriltag_msgs 2.x (christianrauch/apriltag_msgs), its field list.
TS.register(get_types_from_msg("float64 x\nfloat64 y\n", "apriltag_msgs/msg/Point"))
TS.register(get_types_from_msg(
    "string family\nint32 id\nint32 hamming\nfloat32 goodness\nfloat32 decision_margin\n"
    "apriltag_msgs/Point centre\napriltag_msgs/Point[4] corners\nfloat64[9] homography\n",
    "apriltag_msgs/msg/AprilTagDetection"))
TS.register(get_types_from_msg(
    "std_msgs/Header header\napriltag_msgs/AprilTagDetection[] detections\n",
    "apriltag_msgs/msg/AprilTagDetectionArray"))
DETECTIONS = "apriltag_msgs/msg/AprilTagDetectionArray"
TFMessage = TS.types["tf2_msgs/msg/TFMessage"]
TransformStamped = TS.types["geometry_msgs/msg/TransformStamped"]
Header = TS.types["std_msgs/msg/Header"]
Time = TS.types["builtin_interfaces/msg/Time"]
Transform = TS.types["geometry_msgs/msg/Transform"]
Vector3 = TS.types["geometry_msgs/msg/Vector3"]
Quaternion = TS.types["geometry_msgs/msg/Quaternion"]
CameraInfo = TS.types["sensor_msgs/msg/CameraInfo"]
RegionOfInterest = TS.types["sensor_msgs/msg/RegionOfInterest"]
TagPoint = TS.types["apriltag_msgs/msg/Point"]
TagDetection = TS.types["apriltag_msgs/msg/AprilTagDetection"]
TagArray = TS.types[DETECTIONS]

T0_NS = 1_700_000_000_000_000_000
TAG_ID = 3
OTHER_ID = 7


def stamp(ns):
    return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def cdr_detections(ns, frame, tags):
    """AprilTagDetectionArray, little-endian CDR; tags: (id, corners) with any number of corners."""
    out = bytearray(b"\x00\x01\x00\x00")

    def pad(a):
        while (len(out) - 4) % a:
            out.append(0)

    def u32(v):
        pad(4)
        out.extend(struct.pack("<I", v))

    def i32(v):
        pad(4)
        out.extend(struct.pack("<i", v))

    def f32(v):
        pad(4)
        out.extend(struct.pack("<f", v))

    def f64(v):
        pad(8)
        out.extend(struct.pack("<d", v))

    def string(s):
        b = s.encode() + b"\x00"
        u32(len(b))
        out.extend(b)

    i32(ns // 1_000_000_000)
    u32(ns % 1_000_000_000)
    string(frame)
    u32(len(tags))
    for tag_id, corners in tags:
        string("36h11")
        i32(tag_id)
        i32(0)
        f32(0.0)
        f32(50.0)
        centre = np.mean(np.array(corners), axis=0)
        f64(centre[0])
        f64(centre[1])
        for c in corners:
            f64(c[0])
            f64(c[1])
        for _ in range(9):
            f64(0.0)
    return bytes(out)


def writer_detections(ns, frame, tags):
    """The same message serialised by the writer's type system (4 corners only)."""
    msg = TagArray(
        header=Header(stamp=stamp(ns), frame_id=frame),
        detections=[
            TagDetection(
                family="36h11", id=tag_id, hamming=0, goodness=0.0, decision_margin=50.0,
                centre=TagPoint(x=float(np.mean([c[0] for c in corners])), y=float(np.mean([c[1] for c in corners]))),
                corners=[TagPoint(x=c[0], y=c[1]) for c in corners],
                homography=np.zeros(9),
            )
            for tag_id, corners in tags
        ],
    )
    return bytes(TS.serialize_cdr(msg, DETECTIONS))


def transform_stamped(ns, parent, child, translation, q):
    return TransformStamped(
        header=Header(stamp=stamp(ns), frame_id=parent),
        child_frame_id=child,
        transform=Transform(
            translation=Vector3(x=translation[0], y=translation[1], z=translation[2]),
            rotation=Quaternion(x=q[0], y=q[1], z=q[2], w=q[3]),
        ),
    )


def read_intrinsics(path):
    text = path.read_text()
    data = re.findall(r"data:\s*\[([^\]]*)\]", text)
    k = [float(x) for x in data[0].split(",")]
    d = [float(x) for x in data[1].split(",")]
    width = int(re.search(r"image_width:\s*(\d+)", text).group(1))
    height = int(re.search(r"image_height:\s*(\d+)", text).group(1))
    return k, d, width, height


def camera_info(ns, intrinsics):
    k, d, width, height = intrinsics
    return CameraInfo(
        header=Header(stamp=stamp(ns), frame_id="camera"),
        height=height, width=width, distortion_model="plumb_bob",
        d=np.array(d), k=np.array(k), r=np.eye(3).flatten(),
        p=np.array([k[0], 0, k[2], 0, 0, k[4], k[5], 0, 0, 0, 1, 0], dtype=float),
        binning_x=0, binning_y=0,
        roi=RegionOfInterest(x_offset=0, y_offset=0, height=0, width=0, do_rectify=False),
    )


def write_bag(name, storage, records, intrinsics, hostile=False, with_info=True):
    path = OUT / name
    if path.exists():
        shutil.rmtree(path)
    messages = []  # (log ns, topic, raw bytes, type)
    for k, r in enumerate(records):
        ns = T0_NS + k * 1_000_000_000 + 500_000_000
        q = r["base_from_gripper"]["quaternion_xyzw"]
        t = r["base_from_gripper"]["translation"]
        for j in range(-4, 5):
            s = ns + j * 100_000_000
            msg = TFMessage(transforms=[transform_stamped(s, "base_link", "tool0", t, q)])
            messages.append((s, "/tf", bytes(TS.serialize_cdr(msg, TFMessage.__msgtype__)), TFMessage.__msgtype__))
        corners = [list(p) for p in r["detections"]["pixels"]]
        tags = [(TAG_ID, corners)]
        number = k + 1
        if hostile and number == 9:
            tags = [(OTHER_ID, corners)]
        if hostile and number == 12:
            tags = [(OTHER_ID, [[c[0] + 200.0, c[1]] for c in corners]), (TAG_ID, corners)]
        data = cdr_detections(ns, "camera", tags)
        assert data == writer_detections(ns, "camera", tags), "hand serialisation differs"
        if hostile and number == 3:
            data = data[:-40]
        if hostile and number == 6:
            data = cdr_detections(ns, "camera", [(TAG_ID, corners + [corners[0]])])
        log = ns + 20_000_000
        messages.append((log, "/apriltag/detections", data, DETECTIONS))
        if with_info:
            info = camera_info(ns, intrinsics)
            messages.append((ns, "/camera/camera_info", bytes(TS.serialize_cdr(info, CameraInfo.__msgtype__)), CameraInfo.__msgtype__))
    messages.sort(key=lambda m: m[0])
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    writer = Writer(path, version=9, storage_plugin=plugin)
    with writer:
        connections = {}
        for _, topic, _, msgtype in messages:
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, msgtype, typestore=TS)
        for log_ns, topic, data, _ in messages:
            writer.write(connections[topic], log_ns, data)
    print(f"{name}: {storage}, {len(records)} images, hostile {hostile}, camera_info {with_info}", file=sys.stderr)


if __name__ == "__main__":
    records = [json.loads(line) for line in (PIXELS / "tag_eih.jsonl").read_text().splitlines() if line.strip()]
    intrinsics = read_intrinsics(PIXELS / "tag_eih.intrinsics.yml")
    write_bag("tag_eih_mcap", "mcap", records, intrinsics)
    write_bag("tag_eih_sqlite3", "sqlite3", records, intrinsics)
    write_bag("tag_eih_hostile_mcap", "mcap", records, intrinsics, hostile=True)
    write_bag("tag_eih_noinfo_sqlite3", "sqlite3", records, intrinsics, with_info=False)
