"""`OnlineCalibrator(intrinsics=...)`: the online calibrator on the pixels of records with
detections (issue 35) gives what `handeye online --intrinsics` prints on the same stream, and
refuses what it refuses."""
import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

import handeye

REPO = pathlib.Path(__file__).resolve().parents[3]
PIXELS = REPO / "testdata" / "pixels"
CLI = REPO / os.environ.get("CARGO_TARGET_DIR", "target") / "release" / "handeye"
RECORDINGS = [("board_eth", "eye-to-hand"), ("tag_eih", "eye-in-hand")]


def _cli(path, name, setup):
    assert CLI.exists(), f"build the command line first ({CLI}): cargo build --release"
    done = subprocess.run([str(CLI), "online", str(path), "--intrinsics", str(PIXELS / f"{name}.intrinsics.yml"),
                           "--setup", setup, "--output", "json"], capture_output=True, text=True)
    return done.returncode, [json.loads(line) for line in done.stdout.splitlines()], done.stderr


def _listed(report):
    """A report with its arrays as lists, as the command line's JSON has them."""
    out = dict(report)
    out["matrix"] = np.asarray(out["matrix"]).tolist()
    out["target"] = dict(out["target"])
    out["target"]["matrix"] = np.asarray(out["target"]["matrix"]).tolist()
    return out


def _matrix(transform):
    x, y, z, w = transform["quaternion_xyzw"]
    r = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])
    m = np.eye(4)
    m[:3, :3] = r
    m[:3, 3] = transform["translation"]
    return m


@pytest.mark.parametrize("name,setup", RECORDINGS)
def test_records_give_the_command_lines_estimates(name, setup):
    """push_record on each line, and push_detections on the same numbers, give the objects
    `handeye online --intrinsics` prints, field for field."""
    path = PIXELS / f"{name}.jsonl"
    code, cli, err = _cli(path, name, setup)
    assert code == 0, err
    intrinsics = PIXELS / f"{name}.intrinsics.yml"
    by_record = handeye.OnlineCalibrator(intrinsics=str(intrinsics), setup=setup)
    by_arrays = handeye.OnlineCalibrator(intrinsics=str(intrinsics), setup=setup)
    on_the_way, by_arrays_on_the_way = [], []
    for line in path.read_text().splitlines():
        on_the_way += by_record.push_record(line)
        record = json.loads(line)
        by_arrays_on_the_way += by_arrays.push_detections(
            _matrix(record["base_from_gripper"]), record["detections"])
    reports = [_listed(r) for r in on_the_way] + [_listed(by_record.finish())]
    assert reports == cli
    assert by_record.poses == 30
    assert by_record.last_report()["estimate"] == 2
    # The arrays path reads the same record (the matrix to rounding).
    final = by_arrays.finish()
    assert len(by_arrays_on_the_way) == 1
    assert np.abs(np.asarray(final["matrix"]) - np.asarray(cli[-1]["matrix"])).max() < 1e-9
    assert final["reprojection"]["detections"] == cli[-1]["reprojection"]["detections"]


def test_a_bad_record_is_a_value_error_naming_its_field_and_is_not_kept():
    name, setup = RECORDINGS[1]
    c = handeye.OnlineCalibrator(intrinsics=str(PIXELS / f"{name}.intrinsics.yml"), setup=setup)
    record = json.loads((PIXELS / f"{name}.jsonl").read_text().splitlines()[0])
    q = _matrix(record["base_from_gripper"])
    bad = dict(record["detections"])
    bad["pixels"] = [[float("nan"), 1.0]] + bad["pixels"][1:]
    with pytest.raises(ValueError, match=r"record 1: field `detections\.pixels\[0\]"):
        c.push_detections(q, bad)
    with pytest.raises(ValueError, match="detections"):
        c.push_detections(q, {"target": record["detections"]["target"]})
    with pytest.raises(ValueError, match="record 1"):
        c.push_record("{not json")
    assert c.poses == 0
    c.push_detections(q, record["detections"])
    assert c.poses == 1
    # Poses are not taken on the pixels, nor detections without intrinsics.
    with pytest.raises(ValueError, match="push_detections"):
        c.push(q, np.eye(4))
    with pytest.raises(ValueError, match="intrinsics"):
        handeye.OnlineCalibrator().push_detections(q, record["detections"])


def test_refusals_on_the_pixels_are_value_errors(tmp_path):
    """Too few records, robot poses inverted: finish() raises as the command line exits 3."""
    name, setup = RECORDINGS[0]
    intrinsics = str(PIXELS / f"{name}.intrinsics.yml")
    lines = (PIXELS / f"{name}.jsonl").read_text().splitlines()
    c = handeye.OnlineCalibrator(intrinsics=intrinsics, setup=setup)
    for line in lines[:5]:
        c.push_record(line)
    with pytest.raises(ValueError, match="at least 12 needed"):
        c.finish()
    c = handeye.OnlineCalibrator(intrinsics=intrinsics, setup=setup)
    for line in lines:
        assert c.push_record(line.replace('"base_from_gripper"', '"gripper_from_base"')) == []
    with pytest.raises(ValueError, match="inverted"):
        c.finish()
    assert c.pending() is not None
    with pytest.raises(ValueError, match="paper"):
        handeye.OnlineCalibrator(intrinsics=intrinsics, estimator="paper")
    with pytest.raises(ValueError, match="prior"):
        handeye.OnlineCalibrator(intrinsics=intrinsics, prior="tz=0.1")
