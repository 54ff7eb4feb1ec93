#!/usr/bin/env python3
"""Converts other projects' hand-eye data sets into handeye's formats (OUT/<set>/).

    python3 testdata/peers/make_peers.py --visp VISP_GIT_DIR --industrial-calibration IC_GIT_DIR --out DIR

The converted sets are other projects' data: they are not committed to this repository, but kept in
the shared folder beside it (../shared/data/peers, made by this script), where the tests read them
in place (testdata/shared_data.py). To make them elsewhere, pass --out SOMEWHERE/peers and point
HANDEYE_SHARED_DATA at SOMEWHERE (which needs the shared folder's other sets too for the rest of
the tests). Each set's README.md (testdata/peers/<set>/README.md) cites its source.

Each source is a git directory (a clone, or a bare copy) of the upstream repository at the commit
pinned below; files are read with `git show COMMIT:PATH`, so no work tree is needed. Needs numpy and
opencv-python-headless<5 (4.14 made the committed detections). What it writes, per set:

- `poses.jsonl`: one frame a line, `base_from_gripper` (the robot's pose, as upstream recorded it),
  `camera_from_target` (OpenCV's `solvePnP`, iterative, on the detections below) and `detections`
  (`target`: the corners' or dots' coordinates on the target in metres, `pixels`: where OpenCV found
  them in the upstream image; the images themselves are not kept);
- `intrinsics.yml`: the camera matrix and distortion the upstream calibration used (OpenCV's FileStorage
  YAML, as `--intrinsics` reads it);
- `peer.json`: the setup, the unit, and what upstream published or asserted (X, the target's pose,
  the upstream test's bounds), with where each came from;
- `LICENSE`: the upstream licence text.

Detections are OpenCV's, not upstream's own detector's: a chessboard (findChessboardCorners with the
flags and cornerSubPix window ViSP's app uses), an AprilTag 36h11 (cv2.aruco, AprilTag corner
refinement), a ChArUco board (cv2.aruco.CharucoDetector) and the modified 10x10 circle grid
(findCirclesGrid with the upstream blob detector's parameters, ordered from its large dot).
"""

import argparse
import json
import math
import os
import re
import subprocess

import cv2
import numpy as np

VISP_COMMIT = "efb30f05ad48e06db9bfd9537203edbe79fcadc3"
IC_COMMIT = "fe62b7c9b7b347ee047a6fee6f417cd8427b2836"


def git_show(git_dir, commit, path, binary=False):
    out = subprocess.run(
        ["git", "--git-dir", git_dir, "show", f"{commit}:{path}"], check=True, capture_output=True
    ).stdout
    return out if binary else out.decode()


def image(git_dir, commit, path):
    data = np.frombuffer(git_show(git_dir, commit, path, binary=True), np.uint8)
    img = cv2.imdecode(data, cv2.IMREAD_COLOR)
    assert img is not None, path
    return img


# ---- poses -------------------------------------------------------------------------------------


def from_thetau(v):
    """ViSP's vpPoseVector [tx ty tz θux θuy θuz] as a 4×4 matrix."""
    m = np.eye(4)
    m[:3, :3] = cv2.Rodrigues(np.array(v[3:6], float))[0]
    m[:3, 3] = v[:3]
    return m


def from_xyz_quat(t, q_xyzw):
    x, y, z, w = q_xyzw
    n = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    m = np.eye(4)
    m[:3, :3] = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]
    m[:3, 3] = t
    return m


def visp_pose_yaml(text):
    """A vpPoseVector YAML file (`rows: 6`, `cols: 1`, `data: - [v]` …) as its six numbers."""
    values = [float(v) for v in re.findall(r"-\s*\[\s*([-+0-9.eE]+)\s*\]", text)]
    assert len(values) == 6, text
    return values


def flat_yaml(text):
    """The `key: number` lines of a flat YAML file (industrial_calibration's pose files)."""
    out = {}
    for line in text.splitlines():
        line = line.split("#")[0]
        m = re.match(r"\s*(\w+)\s*:\s*([-+0-9.eE]+)\s*$", line)
        if m:
            out[m.group(1)] = float(m.group(2))
    return out


def matrix_list(m):
    return [[float(f"{v:.12g}") for v in row] for row in np.asarray(m)]


# ---- detections and PnP ------------------------------------------------------------------------


def pnp(obj, pix, k, dist):
    ok, rvec, tvec = cv2.solvePnP(obj, pix, k, dist, flags=cv2.SOLVEPNP_ITERATIVE)
    assert ok
    m = np.eye(4)
    m[:3, :3] = cv2.Rodrigues(rvec)[0]
    m[:3, 3] = tvec.ravel()
    proj, _ = cv2.projectPoints(obj, rvec, tvec, k, dist)
    rms = float(np.sqrt(np.mean(np.sum((proj.reshape(-1, 2) - pix) ** 2, axis=1))))
    return m, rms


def chessboard(img, cols, rows, square):
    """ViSP's visp-compute-chessboard-poses: corner (i, j) of the (cols × rows) inner corners at
    (j·square, i·square, 0), in OpenCV's order."""
    found, corners = cv2.findChessboardCorners(
        img,
        (cols, rows),
        cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_FAST_CHECK | cv2.CALIB_CB_NORMALIZE_IMAGE,
    )
    assert found
    gray = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    corners = cv2.cornerSubPix(
        gray, corners, (11, 11), (-1, -1), (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 30, 0.1)
    )
    obj = np.array([[j * square, i * square, 0.0] for i in range(rows) for j in range(cols)])
    return obj, corners.reshape(-1, 2).astype(float)


def apriltag(img, size):
    """One AprilTag 36h11 in ViSP's tag frame (its default, not z-aligned: z out of the tag).
    ViSP puts the AprilTag library's corners p[0..3] at (-s/2, s/2), (s/2, s/2), (s/2, -s/2),
    (-s/2, -s/2) and then turns the frame 180° about x, which puts p[0..3] at (-s/2, -s/2),
    (s/2, -s/2), (s/2, s/2), (-s/2, s/2). OpenCV's corners run the other way round: its corners
    0..3 are the library's p[1], p[0], p[3], p[2], at (s/2, -s/2), (-s/2, -s/2), (-s/2, s/2),
    (s/2, s/2). (Checked: the tag poses then agree with ViSP's published eMo through its rMc to
    within ViSP's printed residuals; the order turned by 180° about z is 180° off.)"""
    gray = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    params = cv2.aruco.DetectorParameters()
    params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_APRILTAG
    det = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11), params)
    corners, ids, _ = det.detectMarkers(gray)
    assert ids is not None and len(ids) == 1, ids
    h = size / 2
    obj = np.array([[h, -h, 0.0], [-h, -h, 0.0], [-h, h, 0.0], [h, h, 0.0]])
    return obj, corners[0].reshape(-1, 2).astype(float)


def charuco(img, cols, rows, square, marker, dictionary):
    board = cv2.aruco.CharucoBoard((cols, rows), square, marker, cv2.aruco.getPredefinedDictionary(dictionary))
    det = cv2.aruco.CharucoDetector(board)
    gray = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    corners, ids, _, _ = det.detectBoard(gray)
    assert ids is not None and len(ids) >= 4
    all_obj = board.getChessboardCorners()
    obj = np.array([all_obj[i] for i in ids.ravel()], float)
    return obj, corners.reshape(-1, 2).astype(float)


def modified_circle_grid(img, rows, cols, spacing, blob):
    """industrial_calibration's modified circle grid (dark dots, one larger): findCirclesGrid's
    symmetric grid, turned so the large dot is dot 0 and the frame is right-handed with z into the
    board (x along the first row, y along the first column)."""
    p = cv2.SimpleBlobDetector_Params()
    for k, v in blob.items():
        setattr(p, k, v)
    detector = cv2.SimpleBlobDetector_create(p)
    gray = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    found, centers = cv2.findCirclesGrid(gray, (cols, rows), flags=cv2.CALIB_CB_SYMMETRIC_GRID, blobDetector=detector)
    assert found
    grid = centers.reshape(rows, cols, 2).astype(float)
    keypoints = detector.detect(gray)

    def size_at(pt):
        k = min(keypoints, key=lambda k: np.hypot(k.pt[0] - pt[0], k.pt[1] - pt[1]))
        assert np.hypot(k.pt[0] - pt[0], k.pt[1] - pt[1]) < 2.0
        return k.size

    corners = [(0, 0), (0, cols - 1), (rows - 1, 0), (rows - 1, cols - 1)]
    sizes = sorted((size_at(grid[c]), c) for c in corners)
    assert sizes[-1][0] > 1.25 * sizes[-2][0], f"no dot at a corner of the grid is the large one: {sizes}"
    at = sizes[-1][1]
    if at[0]:
        grid = grid[::-1, :]
    if at[1]:
        grid = grid[:, ::-1]
    # Right-handed with z into the board: in the image (y down), x × y > 0.
    dx, dy = grid[0, 1] - grid[0, 0], grid[1, 0] - grid[0, 0]
    if dx[0] * dy[1] - dx[1] * dy[0] < 0:
        grid = grid.transpose(1, 0, 2)
    obj = np.array([[j * spacing, i * spacing, 0.0] for i in range(rows) for j in range(cols)])
    return obj, grid.reshape(-1, 2)


# ---- writing -----------------------------------------------------------------------------------


def write_intrinsics(path, k, dist, width, height):
    d = list(dist) + [0.0] * (5 - len(dist))
    with open(path, "w") as f:
        f.write("%YAML:1.0\n---\n")
        f.write(f"image_width: {width}\nimage_height: {height}\n")
        f.write("camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n")
        f.write("   data: [ " + ", ".join(f"{v:.12g}" for v in np.asarray(k).ravel()) + " ]\n")
        f.write("distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n")
        f.write("   data: [ " + ", ".join(f"{v:.12g}" for v in d) + " ]\n")


def write_set(out, name, frames, k, dist, size, peer, licence_text):
    d = os.path.join(out, name)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, "poses.jsonl"), "w") as f:
        for fr in frames:
            line = {
                "base_from_gripper": matrix_list(fr["robot"]),
                "camera_from_target": matrix_list(fr["camera"]),
                "detections": {
                    "target": [[float(f"{v:.9g}") for v in p] for p in fr["obj"]],
                    "pixels": [[round(float(v), 4) for v in p] for p in fr["pix"]],
                },
            }
            f.write(json.dumps(line) + "\n")
    write_intrinsics(os.path.join(d, "intrinsics.yml"), k, dist, *size)
    peer = dict(peer)
    peer["frames"] = len(frames)
    peer["pnp_rms_px"] = [round(fr["rms"], 4) for fr in frames]
    peer["corners"] = [len(fr["obj"]) for fr in frames]
    with open(os.path.join(d, "peer.json"), "w") as f:
        json.dump(peer, f, indent=1)
        f.write("\n")
    with open(os.path.join(d, "LICENSE"), "w") as f:
        f.write(licence_text)
    print(f"{name}: {len(frames)} frames, corners {peer['corners']}, PnP RMS max {max(peer['pnp_rms_px']):.3f} px")


# ---- the sets ----------------------------------------------------------------------------------

VISP_DIR = "apps/calibration/hand-eye"
VISP_TUTORIAL = "doc/tutorial/calibration/tutorial-calibration-extrinsic-eye-{}.dox"


def visp_sets(git_dir, out):
    show = lambda p: git_show(git_dir, VISP_COMMIT, p)  # noqa: E731
    licence = show("LICENSE.txt")
    source = f"https://github.com/lagadic/visp/tree/{VISP_COMMIT}/{VISP_DIR}"

    # Eye-in-hand: a 9×6 chessboard of 23.6 mm squares, the camera's factory intrinsics without
    # distortion (franka_camera.xml, as the tutorial used them).
    xml = show(f"{VISP_DIR}/data-eye-in-hand/franka_camera.xml")
    num = lambda tag: float(re.search(rf"<{tag}>([-0-9.eE]+)</{tag}>", xml).group(1))  # noqa: E731
    k = np.array([[num("px"), 0, num("u0")], [0, num("py"), num("v0")], [0, 0, 1.0]])
    dist = np.zeros(5)
    frames = []
    for i in range(1, 9):
        img = image(git_dir, VISP_COMMIT, f"{VISP_DIR}/data-eye-in-hand/franka_image-{i}.png")
        obj, pix = chessboard(img, 9, 6, 0.0236)
        cam, rms = pnp(obj, pix, k, dist)
        robot = from_thetau(visp_pose_yaml(show(f"{VISP_DIR}/data-eye-in-hand/franka_pose_rPe_{i}.yaml")))
        frames.append({"robot": robot, "camera": cam, "obj": obj, "pix": pix, "rms": rms})
    tut = VISP_TUTORIAL.format("in-hand")
    peer = {
        "source": source,
        "commit": VISP_COMMIT,
        "licence": "GPL-2.0-or-later (ViSP)",
        "setup": "eye-in-hand",
        "unit": "m",
        "x": matrix_list(visp_matrix(show(tut), "eMc")),
        "x_from": f"{tut}: 'Estimated eMc transformation' (ViSP's visp-compute-eye-in-hand-calibration on these 8 pose pairs)",
        "target": matrix_list(visp_matrix(show(tut), "rMo")),
        "target_from": f"{tut}: 'Estimated rMo transformation' (the chessboard in the robot's base frame)",
        "target_frame": "ViSP's chessboard frame: inner corner (row i, column j) at (j*0.0236, i*0.0236, 0) m",
        "upstream_residual": {"rotation_deg": 0.455924, "translation_m": 0.00541224},
        "upstream_per_pose": visp_per_pose(show(tut)),
    }
    write_set(out, "visp_eye_in_hand", frames, k, dist, (640, 480), peer, licence)

    # Eye-to-hand: a 48 mm AprilTag 36h11 on the flange; the tutorial computed the tag poses with
    # intrinsics that model distortion (printed in the tutorial; franka_camera.xml in the repository
    # holds the factory ones), so those are the ones used here.
    tut = VISP_TUTORIAL.format("to-hand")
    text = show(tut)
    grab = lambda name: float(re.search(rf"{name} = ([-0-9.eE]+)", text).group(1))  # noqa: E731
    k = np.array([[grab("px"), 0, grab("u0")], [0, grab("py"), grab("v0")], [0, 0, 1.0]])
    dist = np.array([grab("kud"), 0, 0, 0, 0])
    frames = []
    for i in range(1, 9):
        img = image(git_dir, VISP_COMMIT, f"{VISP_DIR}/data-eye-to-hand/franka_image-{i}.png")
        obj, pix = apriltag(img, 0.048)
        cam, rms = pnp(obj, pix, k, dist)
        robot = from_thetau(visp_pose_yaml(show(f"{VISP_DIR}/data-eye-to-hand/franka_pose_rPe_{i}.yaml")))
        frames.append({"robot": robot, "camera": cam, "obj": obj, "pix": pix, "rms": rms})
    peer = {
        "source": source,
        "commit": VISP_COMMIT,
        "licence": "GPL-2.0-or-later (ViSP)",
        "setup": "eye-to-hand",
        "unit": "m",
        "x": matrix_list(visp_matrix(text, "rMc")),
        "x_from": f"{tut}: 'Estimated robot reference to camera frames (rMc) transformation'",
        "target": matrix_list(visp_matrix(text, "eMo")),
        "target_from": f"{tut}: 'Estimated hand-object (eMo) transformation' (the tag in the flange's frame)",
        "target_frame": "ViSP's AprilTag frame (not z-aligned, z out of the tag): OpenCV's corners 0..3 at (s/2, -s/2), (-s/2, -s/2), (-s/2, s/2), (s/2, s/2), s = 0.048 m",
        "intrinsics_from": f"{tut}: the camera parameters printed by visp-compute-apriltag-poses (ViSP's kud = OpenCV's k1)",
        "upstream_residual": {"rotation_deg": 0.511707, "translation_m": 0.00235038},
        "upstream_per_pose": visp_per_pose(text),
    }
    write_set(out, "visp_eye_to_hand", frames, k, dist, (640, 480), peer, licence)


def visp_per_pose(text):
    """The per-pose distances ViSP's calibration prints: each pose's target (rMo eye-in-hand, eMo
    eye-to-hand, through the X found) from the target it reports, in degrees and metres."""
    deg = [float(v) for v in re.findall(r"Distance theta between rMo/rMc\(\d+\) and mean \(deg\) = ([-0-9.eE]+)", text)]
    m = [float(v) for v in re.findall(r"Distance d between rMo/rMc\(\d+\) and mean \(m\) = ([-0-9.eE]+)", text)]
    assert len(deg) == len(m) == 8
    return {"rotation_deg": deg, "translation_m": m}


def visp_matrix(text, name):
    """The 4×4 matrix a ViSP tutorial prints after `NAME[4,4]=`."""
    at = text.index(f"{name}[4,4]=")
    rows = text[at:].splitlines()[1:4]
    m = np.eye(4)
    m[:3, :] = [[float(v) for v in r.split()] for r in rows]
    return m


IC_DATA = "examples/data"
IC_TEST = "examples/extrinsic_hand_eye.cpp"


def ic_sets(git_dir, out):
    show = lambda p: git_show(git_dir, IC_COMMIT, p)  # noqa: E731
    licence = show("LICENSE")
    base = f"https://github.com/ros-industrial/industrial_calibration/tree/{IC_COMMIT}/{IC_DATA}"

    def robot(set_name, i):
        p = flat_yaml(show(f"{IC_DATA}/{set_name}/poses/{i}.yaml"))
        return from_xyz_quat([p["x"], p["y"], p["z"]], [p["qx"], p["qy"], p["qz"], p["qw"]])

    def intrinsics(set_name):
        p = flat_yaml(show(f"{IC_DATA}/{set_name}/cal_data.yaml").split("intrinsics:")[1].split("\n\n")[0])
        return np.array([[p["fx"], 0, p["cx"]], [0, p["fy"], p["cy"]], [0, 0, 1.0]])

    # Camera on the wrist, modified 10×10 circle grid (spacing 25.4 mm), 15 images, nominal
    # intrinsics without distortion.
    cal = show(f"{IC_DATA}/test_set_10x10/cal_data.yaml")
    blob = {}
    for key, kind in [
        ("minThreshold", float), ("maxThreshold", float), ("minRepeatability", int),
        ("minArea", float), ("maxArea", float), ("filterByColor", bool), ("filterByArea", bool),
        ("filterByCircularity", bool), ("filterByInertia", bool), ("filterByConvexity", bool),
        ("minConvexity", float),
    ]:
        v = re.search(rf"\n\s*{key}:\s*(\S+)", cal).group(1)
        blob[key] = (v == "true") if kind is bool else kind(float(v))
    blob["thresholdStep"] = (blob["maxThreshold"] - blob["minThreshold"]) / 20.0  # nThresholds: 20
    blob["blobColor"] = 0
    k = intrinsics("test_set_10x10")
    dist = np.zeros(5)
    frames = []
    for i in range(15):
        img = image(git_dir, IC_COMMIT, f"{IC_DATA}/test_set_10x10/images/{i}.png")
        obj, pix = modified_circle_grid(img, 10, 10, 0.0254, blob)
        cam, rms = pnp(obj, pix, k, dist)
        frames.append({"robot": robot("test_set_10x10", i), "camera": cam, "obj": obj, "pix": pix, "rms": rms})
    peer = {
        "source": f"{base}/test_set_10x10",
        "commit": IC_COMMIT,
        "licence": "Apache-2.0 (industrial_calibration)",
        "setup": "eye-in-hand",
        "unit": "m",
        "x": None,
        "x_from": "no X is published: the upstream test (ExtrinsicHandEyeCalibration.ModifiedCircleGridTarget) bounds the fit",
        "target_frame": "origin at the large dot, x along its row, y along its column, z into the board; dots 25.4 mm apart",
        "bounds": {
            "from": f"{IC_TEST}: TEST(ExtrinsicHandEyeCalibration, ModifiedCircleGridTarget)",
            "rms_px": 1.5,
            "pos_diff_mean_m": 0.02,
            "ori_diff_mean_deg": 3.0,
            "meaning": "per image, the fitted camera_from_target (X^-1 M_i Y) against a PnP of that image's detections; the mean over images",
        },
    }
    write_set(out, "ic_circle_grid_eye_in_hand", frames, k, dist, (640, 480), peer, licence)

    # Static camera, ChArUco board (5 × 7 squares of 36.195 mm, 18.256 mm DICT_6X6_250 markers) on
    # the wrist, 16 images.
    k = intrinsics("test_set_charuco")
    frames = []
    dropped = []
    size = None
    for i in range(16):
        img = image(git_dir, IC_COMMIT, f"{IC_DATA}/test_set_charuco/images/{i}.png")
        size = (img.shape[1], img.shape[0])
        obj, pix = charuco(img, 5, 7, 0.036195, 0.018256, cv2.aruco.DICT_6X6_250)
        if len(obj) < 8:
            # Upstream's homography check samples half the corners and needs 4: it drops the image.
            dropped.append({"image": f"images/{i}.png", "corners": len(obj)})
            continue
        cam, rms = pnp(obj, pix, k, dist)
        frames.append({"robot": robot("test_set_charuco", i), "camera": cam, "obj": obj, "pix": pix, "rms": rms})
    peer = {
        "source": f"{base}/test_set_charuco",
        "commit": IC_COMMIT,
        "licence": "Apache-2.0 (industrial_calibration)",
        "setup": "eye-to-hand",
        "unit": "m",
        "x": None,
        "x_from": "no X is published: the upstream test (ExtrinsicHandEyeCalibration.ChArUcoGridTarget) bounds the fit",
        "dropped": dropped,
        "dropped_why": "fewer than 8 corners found: upstream's RandomCorrespondenceSampler(n, n/2) needs n/2 >= 4, so its run() skips the image",
        "target_frame": "OpenCV's CharucoBoard((5, 7), 0.036195, 0.018256, DICT_6X6_250) corner coordinates",
        "bounds": {
            "from": f"{IC_TEST}: TEST(ExtrinsicHandEyeCalibration, ChArUcoGridTarget)",
            "rms_px": 1.5,
            "pos_diff_mean_m": 0.006,
            "ori_diff_mean_deg": 1.5,
            "meaning": "per image, the fitted camera_from_target (X^-1 M_i Y) against a PnP of that image's detections; the mean over images",
        },
    }
    write_set(out, "ic_charuco_eye_to_hand", frames, k, dist, size, peer, licence)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--visp", help="git directory of lagadic/visp")
    ap.add_argument("--industrial-calibration", help="git directory of ros-industrial/industrial_calibration")
    ap.add_argument("--out", required=True,
                    help="where to write the sets (one folder each); not inside the repository")
    a = ap.parse_args()
    if a.visp:
        visp_sets(a.visp, a.out)
    if a.industrial_calibration:
        ic_sets(a.industrial_calibration, a.out)


if __name__ == "__main__":
    main()
