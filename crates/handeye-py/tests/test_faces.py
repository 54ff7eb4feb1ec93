"""One verdict in every face: every real and realistic pose set (testdata's, and other projects' in
the shared folder), every method, through the command line (`handeye calibrate --method M --pairs
all`), Python's `calibrate(..., pairs="all")` and the OpenCV drop-in `calibrate_hand_eye(...,
method=M, setup=...)` gives one decision (answer, warn, refuse), one X (to 1e-9), one sigma and the
same words.

The drop-in's OpenCV constant for Tsai is the command line's `--method tsai --tsai-opencv-filter`.
The faces name poses in their own vocabulary (the command line `file:line`, Python `pose i`), and
the drop-in words a misread input and swapped sizes in OpenCV's arguments; everything else is the
same text.
"""
import json
import os
import pathlib
import subprocess
import warnings

import cv2
import numpy as np
import pytest

import handeye
from conftest import shared_path

REPO = pathlib.Path(__file__).resolve().parents[3]
TESTDATA = REPO / "testdata"
CLI = REPO / os.environ.get("CARGO_TARGET_DIR", "target") / "release" / "handeye"

#: handeye's methods; ("tsai", True) is OpenCV's Tsai (its motion filter).
METHODS = [("andreff", False), ("tsai", False), ("tsai", True), ("park", False), ("horaud", False),
           ("andreff-joint", False), ("daniilidis", False), ("refine", False)]


#: The peers' sets converted by testdata/peers/make_peers.py, in the shared folder, with their setup
#: (their peer.json says it too).
PEERS = {"visp_eye_in_hand": "eye-in-hand", "visp_eye_to_hand": "eye-to-hand",
         "ic_circle_grid_eye_in_hand": "eye-in-hand", "ic_charuco_eye_to_hand": "eye-to-hand"}


def _sets():
    """(id, CLI input arguments, read_recording keywords, setup, the shared set it reads or None) of
    every real and realistic set."""
    sets = []
    for path in sorted((TESTDATA / "kinhec" / "pairs").glob("*.jsonl")):
        setup = "eye-to-hand" if "_eth_" in path.name else "eye-in-hand"
        sets.append((f"kinhec/{path.stem}", [str(path)], {"path": str(path)}, setup, None))
    for path in sorted((TESTDATA / "opencv").glob("*.jsonl")):
        setup = "eye-to-hand" if "eye-to-hand" in path.name else "eye-in-hand"
        sets.append((f"opencv/{path.stem}", [str(path)], {"path": str(path)}, setup, None))
    # Other projects' data, read in place from the shared folder (conftest.py).
    camodocal = shared_path("camodocal/TransformPairsInput.yml")
    sets.append(("camodocal", [str(camodocal)], {"path": str(camodocal)}, "eye-in-hand", "camodocal"))
    for name in ("robot_arm_sim", "prime_sense_1"):
        robot, camera = (shared_path(f"ethz-asl/{name}_{s}.csv") for s in ("B_H", "W_E"))
        sets.append((f"ethz-asl/{name}", ["--robot", str(robot), "--camera", str(camera)],
                     {"robot": str(robot), "camera": str(camera)}, "eye-in-hand", "ethz-asl"))
    for name, setup in PEERS.items():
        path = shared_path(f"peers/{name}/poses.jsonl")
        sets.append((f"peers/{name}", [str(path)], {"path": str(path)}, setup, f"peers/{name}"))
    return sets


SETS = _sets()


def _cli(args, setup, method, opencv_filter):
    """The command line's decision: ("answer", report) or ("refuse", message)."""
    assert CLI.exists(), f"build the command line first ({CLI}): cargo build --release"
    extra = ["--tsai-opencv-filter"] if opencv_filter else []
    out = subprocess.run([str(CLI), "calibrate", *args, "--setup", setup, "--method", method, "--pairs", "all",
                          *extra, "--output", "json"], capture_output=True, text=True)
    if out.returncode == 0:
        return "answer", json.loads(out.stdout)
    assert out.returncode in (2, 3), out.stderr
    lines = [l for l in out.stderr.splitlines() if l.startswith("error: ")]
    assert lines, out.stderr
    return "refuse", lines[-1][len("error: "):]


def _python(g, c, setup, method, opencv_filter):
    try:
        return "answer", handeye.calibrate(g, c, method=method, setup=setup, pairs="all",
                                           tsai_opencv_filter=opencv_filter)
    except ValueError as e:
        return "refuse", str(e)


def _drop_in(g, c, setup, method, opencv_filter):
    """The drop-in on OpenCV's arguments: gripper2base (base2gripper for a fixed camera) and target2cam."""
    robot = g if setup == "eye-in-hand" else np.linalg.inv(g)
    code = {v: k for k, v in handeye.METHODS.items()}["tsai"] if opencv_filter else method
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        try:
            r, t = handeye.calibrate_hand_eye(list(robot[:, :3, :3]), list(robot[:, :3, 3]), list(c[:, :3, :3]),
                                              list(c[:, :3, 3]), method=code, setup=setup)
        except ValueError as e:
            return "refuse", str(e)
    assert all(w.category is UserWarning for w in said), said
    x = np.eye(4)
    x[:3, :3], x[:3, 3] = r, t.ravel()
    return "answer", (x, [str(w.message) for w in said])


#: The poses' names differ by face: the command line's `file:line` (or `file at t = ...`), Python's `pose i`.
def _unnamed(text):
    import re

    text = re.sub(r"\S+\.(jsonl|yml|csv)(:\d+| at t = [\d.]+ s)", "POSE", text)
    return re.sub(r"pose \d+", "POSE", text)


#: Where a refusal's remedy starts, in the words of the command line and Python, and of the drop-in.
_REMEDIES = (", `--prior", "; OpenCV's arguments carry no prior", "; if one is in millimetres",
             "; give t_gripper2base and t_target2cam", "; use `--method", "; pass method=",
             "; pass `--reject-outliers`", "; X follows them")


def _reason(text):
    """A refusal without its remedy, the poses unnamed."""
    cut = min((i for i in (text.find(m) for m in _REMEDIES) if i >= 0), default=len(text))
    return _unnamed(text[:cut])


def _close(a, b, what, tolerance=1e-9):
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    assert a.shape == b.shape and np.allclose(a, b, rtol=tolerance, atol=tolerance), f"{what}: {a} != {b}"


@pytest.mark.parametrize("name, args, source, setup, needs", SETS, ids=[s[0] for s in SETS])
def test_every_face_gives_one_verdict(name, args, source, setup, needs, shared):
    if needs:
        shared(needs)
    if needs and needs.startswith("peers/"):
        assert json.loads((shared(needs) / "peer.json").read_text())["setup"] == setup, name
    read = handeye.read_recording(**source, setup=setup)
    g, c = read["base_from_gripper"], read["camera_from_target"]
    for method, opencv_filter in METHODS:
        what = f"{name} {method}{' (OpenCV filter)' if opencv_filter else ''}"
        cli, py, drop = (_cli(args, setup, method, opencv_filter), _python(g, c, setup, method, opencv_filter),
                         _drop_in(g, c, setup, method, opencv_filter))
        assert cli[0] == py[0] == drop[0], f"{what}: CLI {cli[0]}, Python {py[0]}, drop-in {drop[0]}: {cli[1] if cli[0] == 'refuse' else py[1] if py[0] == 'refuse' else drop[1]}"
        if cli[0] == "refuse":
            assert _unnamed(cli[1]) == _unnamed(py[1]), f"{what}: the refusal's words"
            if "misread" not in py[1]:
                # The same reason in the same words; the remedy in the drop-in's own terms (it
                # takes no prior, no fix, no flag).
                assert _reason(drop[1]) == _reason(py[1]), f"{what}: the drop-in's refusal"
                assert "`--" not in drop[1], f"{what}: the drop-in names a flag: {drop[1]}"
            continue
        report, ours = cli[1], py[1]
        x, said = drop[1]
        # The drop-in says what OpenCV's filter dropped (the command line, a note on stderr).
        filtered = [w for w in said if w.startswith("OpenCV's Tsai motion filter kept ")]
        said = [w for w in said if w not in filtered]
        dropped = report["motions"] < report["poses"] * (report["poses"] - 1) // 2
        assert len(filtered) == (1 if opencv_filter and dropped else 0), f"{what}: {filtered}"
        assert report["verdict"] == ours["verdict"], what
        _close(report["matrix"], ours["matrix"], f"{what}: X, CLI and Python")
        _close(report["matrix"], x, f"{what}: X, CLI and drop-in")
        for key in ("rotation_deg", "translation"):
            _close(report["uncertainty"][key], ours["uncertainty"][key], f"{what}: sigma {key}")
        # The drop-in warns exactly where the command line warns, with its words (its own for
        # the sizes that fit another setup, and the Python remedy for outliers).
        assert (len(said) > 0) == (report["verdict"] == "questionable"), f"{what}: {said}"
        assert len(said) == len(report["warnings"]) == len(ours["warnings"]), f"{what}: {said} / {report['warnings']}"
        for cli_w, py_w, text in zip(report["warnings"], ours["warnings"], said):
            assert cli_w["code"] == py_w["code"], what
            assert _unnamed(cli_w["message"]) == _unnamed(py_w["message"]), f"{what}: {cli_w['code']}"
            if cli_w["code"] != "swapped_sizes":
                assert _unnamed(text).startswith(_unnamed(py_w["message"])), f"{what}: {text!r} / {py_w['message']!r}"


def _camera_rms(c):
    """The RMS translation of the camera motions over every pair of poses (the unit handeye weighs
    Daniilidis' and andreff-joint's rows in)."""
    o = np.array([m[:3, :3].T @ m[:3, 3] for m in c])
    d = o[:, None, :] - o[None, :, :]
    n = len(o)
    return np.sqrt((d ** 2).sum() / 2 / (n * (n - 1) / 2))


@pytest.mark.parametrize("path", sorted((TESTDATA / "opencv").glob("*noisy*.jsonl")), ids=lambda p: p.stem)
def test_the_weighted_solvers_give_opencvs_answer_in_the_datas_own_unit(path):
    # OpenCV weighs rotation rows against translation rows in the input's unit, handeye in the
    # camera motions' RMS length L (so that metres and millimetres give one X): handeye on the
    # data is OpenCV on the data in units of L, its translation times L.
    rows = [json.loads(l) for l in path.read_text().splitlines() if l.strip()]
    g = np.array([r["base_from_gripper"] for r in rows], dtype=np.float64)
    c = np.array([r["camera_from_target"] for r in rows], dtype=np.float64)
    if "eye-to-hand" in path.name:
        g = np.linalg.inv(g)
    unit = _camera_rms(c)
    args = (list(g[:, :3, :3]), list(g[:, :3, 3]), list(c[:, :3, :3]), list(c[:, :3, 3]))
    scaled = (args[0], [t / unit for t in args[1]], args[2], [t / unit for t in args[3]])
    for name, code in (("andreff-joint", cv2.CALIB_HAND_EYE_ANDREFF), ("daniilidis", cv2.CALIB_HAND_EYE_DANIILIDIS)):
        r_cv, t_cv = cv2.calibrateHandEye(*scaled, method=code)
        plain = (args[0], args[1], args[2], args[3])
        import handeye._handeye as native

        x = native.solve_x(g, c, method=name, pairs="all")
        assert np.abs(x[:3, :3] - r_cv).max() <= 1e-6, name
        assert np.abs(x[:3, 3] - t_cv.ravel() * unit).max() <= 1e-6 * unit, name
        r_in, _ = cv2.calibrateHandEye(*plain, method=code)
        # And OpenCV's own answer in the input's unit is another one (the weighting matters here).
        assert np.abs(r_in - r_cv).max() > 1e-6, name


def _sigmas(result, published):
    """How many of `result`'s own sigmas its transform is from `published`: (rotation, translation)."""
    a, b = np.asarray(result["matrix"]), np.asarray(published)
    angle = np.degrees(np.arccos(np.clip((np.trace(a[:3, :3].T @ b[:3, :3]) - 1) / 2, -1, 1)))
    u = result["uncertainty"]
    return angle / u["rotation_deg"], np.linalg.norm(a[:3, 3] - b[:3, 3]) / u["translation"]


@pytest.mark.parametrize("name", ["visp_eye_in_hand", "visp_eye_to_hand"])
def test_peers_python_gives_visps_published_answer(name, shared):
    """Python's `calibrate` on ViSP's sets (in the shared folder), as tests/peers.rs holds the command
    line: X within half a sigma of ViSP's published eMc / rMc (measured 0.495 at most: eye-to-hand's
    rotation), by the hand–eye default and by robot-world, and the target within one sigma of its
    published rMo / eMo (0.83 at most)."""
    folder = shared(f"peers/{name}")
    peer = json.loads((folder / "peer.json").read_text())
    read = handeye.read_recording(folder / "poses.jsonl", setup=peer["setup"])
    for robot_world in (False, True):
        got = handeye.calibrate(read["base_from_gripper"], read["camera_from_target"], setup=peer["setup"],
                                robot_world=robot_world)
        assert got["verdict"] == "good", (name, robot_world, got["warnings"])
        rotation, translation = _sigmas(got, peer["x"])
        assert rotation < 0.5 and translation < 0.5, (name, robot_world, rotation, translation)
        if robot_world:
            rotation, translation = _sigmas(got["target"], peer["target"])
            assert rotation < 1.0 and translation < 1.0, (name, "target", rotation, translation)


def test_millimetres_and_metres_give_one_x_in_every_face(shared):
    # A real recording (camodocal's, robot poses inverted as it stores them) in metres and in
    # millimetres: the same X (its translation ×1000) and sigma by every method, where
    # Daniilidis came out 26° apart.
    read = handeye.read_recording(shared("camodocal/TransformPairsInput.yml"))
    g, c = read["base_from_gripper"], read["camera_from_target"]
    g = np.linalg.inv(g)
    mm_g, mm_c = g.copy(), c.copy()
    mm_g[:, :3, 3] *= 1000
    mm_c[:, :3, 3] *= 1000
    for method, _ in METHODS[:2] + METHODS[3:]:
        m = handeye.calibrate(g, c, method=method, pairs="all")
        mm = handeye.calibrate(mm_g, mm_c, method=method, pairs="all")
        _close(m["matrix"][:3, :3], mm["matrix"][:3, :3], method)
        _close(m["matrix"][:3, 3] * 1000, mm["matrix"][:3, 3], method)
        assert m["uncertainty"]["rotation_deg"] == pytest.approx(mm["uncertainty"]["rotation_deg"], rel=1e-9)
        assert m["uncertainty"]["translation"] * 1000 == pytest.approx(mm["uncertainty"]["translation"], rel=1e-9)
        assert m["verdict"] == mm["verdict"], method


#: The robot-world methods: OpenCV's two and handeye's joint refinement.
ROBOT_WORLD = ("shah", "li", "refine")
#: The robot-world drop-in is OpenCV's eye-in-hand formulation (world2cam, base2gripper).
EYE_IN_HAND_SETS = [s for s in SETS if s[3] == "eye-in-hand"]


def _cli_robot_world(args, method):
    out = subprocess.run([str(CLI), "calibrate", *args, "--robot-world", "--method", method, "--output", "json"],
                         capture_output=True, text=True)
    if out.returncode == 0:
        return "answer", json.loads(out.stdout)
    assert out.returncode in (2, 3), out.stderr
    return "refuse", [l for l in out.stderr.splitlines() if l.startswith("error: ")][-1][len("error: "):]


def _rigid_inverse(m):
    """The inverses of (N, 4, 4) rigid transforms whose rotations are first made orthonormal (the
    recordings' are so only to 1e-10, as they were rounded when written; each face projects them
    onto the nearest rotation, and an inverse of the unprojected matrix would differ from the
    projected one's by that much in its translation)."""
    u, _, vt = np.linalg.svd(m[:, :3, :3])
    r = np.transpose(u @ vt, (0, 2, 1))
    out = np.zeros_like(m)
    out[:, :3, :3] = r
    out[:, :3, 3] = -np.einsum("nij,nj->ni", r, m[:, :3, 3])
    out[:, 3, 3] = 1.0
    return out


def _robot_world_drop_in(g, c, method):
    """cv2.calibrateRobotWorldHandEye's arguments: world2cam = camera_from_target, base2gripper =
    base_from_gripper⁻¹; X = gripper2cam⁻¹, the target = base2world⁻¹."""
    b = _rigid_inverse(g)
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        try:
            r_w, t_w, r_z, t_z = handeye.calibrate_robot_world_hand_eye(
                list(c[:, :3, :3]), list(c[:, :3, 3]), list(b[:, :3, :3]), list(b[:, :3, 3]), method=method)
        except ValueError as e:
            return "refuse", str(e)
    w, z = np.eye(4), np.eye(4)
    w[:3, :3], w[:3, 3] = r_w, t_w.ravel()
    z[:3, :3], z[:3, 3] = r_z, t_z.ravel()
    return "answer", (np.linalg.inv(z), np.linalg.inv(w), [str(m.message) for m in said])


@pytest.mark.parametrize("name, args, source, setup, needs", EYE_IN_HAND_SETS,
                         ids=[s[0] for s in EYE_IN_HAND_SETS])
def test_robot_world_gives_one_verdict_in_every_face(name, args, source, setup, needs, shared):
    """`calibrate --robot-world`, Python's `calibrate(robot_world=True)` and the drop-in for
    cv2.calibrateRobotWorldHandEye: one decision, one X and target pose (to 1e-9), one verdict,
    the same cautions."""
    if needs:
        shared(needs)
    read = handeye.read_recording(**source, setup=setup)
    g, c = read["base_from_gripper"], read["camera_from_target"]
    for method in ROBOT_WORLD:
        what = f"{name} {method}"
        cli = _cli_robot_world(args, method)
        try:
            py = "answer", handeye.calibrate(g, c, robot_world=True, method=method)
        except ValueError as e:
            py = "refuse", str(e)
        drop = _robot_world_drop_in(g, c, method)
        assert cli[0] == py[0] == drop[0], f"{what}: CLI {cli[0]}, Python {py[0]}, drop-in {drop[0]}: {cli[1]}"
        if cli[0] == "refuse":
            assert _unnamed(cli[1]) == _unnamed(py[1]), f"{what}: the refusal's words"
            assert "`--" not in drop[1], f"{what}: the drop-in names a flag: {drop[1]}"
            continue
        report, ours = cli[1], py[1]
        x, target, said = drop[1]
        assert report["verdict"] == ours["verdict"] in ("good", "questionable"), what
        _close(report["matrix"], ours["matrix"], f"{what}: X, CLI and Python")
        # The drop-in's robot poses are the inverses of the others' (OpenCV's base2gripper), equal
        # to theirs in the last bits only. The closed forms keep 1e-9; the joint refinement stops
        # when the cost drops by less than 1e-15 of itself, which fixes its parameters to about
        # √1e-15 ≈ 3e-8 (a 1e-15 change of the translations moves it by up to 1e-8 on the
        # outlier-laden sets): there the bound is 1e-7.
        tolerance = 1e-7 if method == "refine" else 1e-9
        _close(report["matrix"], x, f"{what}: X, CLI and drop-in", tolerance)
        _close(report["target"]["matrix"], target, f"{what}: the target, CLI and drop-in", tolerance)
        assert (len(said) > 0) == (report["verdict"] == "questionable"), f"{what}: {said}"
        assert len(said) == len(report["warnings"]) == len(ours["warnings"]), f"{what}: {said}"


@pytest.mark.parametrize("path", sorted(p for p in (TESTDATA / "opencv").glob("*.jsonl") if "eye-in-hand" in p.name),
                         ids=lambda p: p.stem)
def test_the_robot_world_drop_in_gives_opencvs_answer(path):
    """On OpenCV's own test recordings: Shah is cv2.calibrateRobotWorldHandEye's answer; Li is
    OpenCV's for the data in the unit handeye weighs it in (the poses' RMS translation), and so
    the same in millimetres as in metres, where OpenCV's changes."""
    rows = [json.loads(l) for l in path.read_text().splitlines() if l.strip()]
    g = np.array([r["base_from_gripper"] for r in rows], dtype=np.float64)
    c = np.array([r["camera_from_target"] for r in rows], dtype=np.float64)
    b = np.linalg.inv(g)
    args = lambda u: ([m[:3, :3] for m in c], [m[:3, 3:4] / u for m in c], [m[:3, :3] for m in b], [m[:3, 3:4] / u for m in b])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ours = handeye.calibrate_robot_world_hand_eye(*args(1.0), method=cv2.CALIB_ROBOT_WORLD_HAND_EYE_SHAH)
        theirs = cv2.calibrateRobotWorldHandEye(*args(1.0), method=cv2.CALIB_ROBOT_WORLD_HAND_EYE_SHAH)
        for a, b_ in zip(ours, theirs):
            assert np.abs(a - b_).max() < 1e-9, (path.name, a, b_)
        unit = np.sqrt((np.linalg.norm(c[:, :3, 3], axis=1) ** 2 + np.linalg.norm(b[:, :3, 3], axis=1) ** 2).sum() / (2 * len(c)))
        li = handeye.calibrate_robot_world_hand_eye(*args(1.0), method=cv2.CALIB_ROBOT_WORLD_HAND_EYE_LI)
        theirs = cv2.calibrateRobotWorldHandEye(*args(unit), method=cv2.CALIB_ROBOT_WORLD_HAND_EYE_LI)
        for k, (a, b_) in enumerate(zip(li, theirs)):
            assert np.abs(a - (b_ * unit if k % 2 else b_)).max() < 1e-6, (path.name, k)
        mm = handeye.calibrate_robot_world_hand_eye(*args(1e-3), method="li")
        for k, (a, b_) in enumerate(zip(mm, li)):
            assert np.abs(a - (b_ * 1e3 if k % 2 else b_)).max() < 1e-6, (path.name, k)


def test_the_robot_world_drop_in_refuses_what_opencv_answers():
    """Every rotation about one axis: OpenCV answers; the drop-in raises, as the command line
    refuses. Two poses: too few. Inverted robot poses (gripper2base passed as base2gripper): a
    misread, raised."""
    rng = np.random.default_rng(3)
    n = 12
    world2cam, base2gripper = [], []
    for k in range(n):
        turn = cv2.Rodrigues(np.array([0.0, 0.0, 0.3 * k]))[0]
        base2gripper.append((turn, rng.normal(0, 0.2, (3, 1))))
        world2cam.append((cv2.Rodrigues(np.array([0.1, 0.0, 0.25 * k]))[0], np.array([[0.0], [0.0], [0.5]]) + rng.normal(0, 0.01, (3, 1))))
    split = lambda pairs: ([r for r, _ in pairs], [t for _, t in pairs])
    with pytest.raises(ValueError):
        handeye.calibrate_robot_world_hand_eye(*split(world2cam), *split(base2gripper))
    with pytest.raises(ValueError, match="record more poses"):
        handeye.calibrate_robot_world_hand_eye(*split(world2cam[:2]), *split(base2gripper[:2]))
    q, cam, _, _ = _series()
    b = np.linalg.inv(q)
    # Right: an answer near the truth; inverted robot poses: refused as a misread.
    handeye.calibrate_robot_world_hand_eye(list(cam[:, :3, :3]), list(cam[:, :3, 3]), list(b[:, :3, :3]), list(b[:, :3, 3]))
    with pytest.raises(ValueError) as inverted:
        handeye.calibrate_robot_world_hand_eye(list(cam[:, :3, :3]), list(cam[:, :3, 3]), list(q[:, :3, :3]), list(q[:, :3, 3]))
    # Worded in this function's own arguments, not calibrateHandEye's.
    words = str(inverted.value)
    assert "R_base2gripper" in words and "gripper2base" not in words.replace("base2gripper", ""), words
    with pytest.raises(ValueError) as mixed:
        handeye.calibrate_robot_world_hand_eye(list(cam[:, :3, :3]), list(cam[:, :3, 3] * 1000), list(b[:, :3, :3]), list(b[:, :3, 3]))
    assert "t_world2cam in millimetres" in str(mixed.value), str(mixed.value)


def _series():
    """A realistic kinhec recording (eye-in-hand): robot poses, camera poses."""
    read = handeye.read_recording(str(TESTDATA / "kinhec" / "pairs" / "nominal_stations_eih_s1.jsonl"))
    return read["base_from_gripper"], read["camera_from_target"], None, None


#: The committed recordings with detections and their setups.
PIXEL_SETS = [("tag_eih", "eye-in-hand"), ("board_eth", "eye-to-hand")]


def test_records_with_detections_alone_name_pythons_call():
    """The pose-based reading of records with `detections` and no camera pose refuses the first
    one by its line and names Python's call that calibrates them on the pixels, not a flag."""
    path = TESTDATA / "pixels" / "board_eth.jsonl"
    with pytest.raises(ValueError) as refused:
        handeye.read_recording(str(path), setup="eye-to-hand")
    words = str(refused.value)
    assert f"{path}:1:" in words and "calibrate_on_pixels(path, intrinsics=FILE)" in words, words
    assert "--" not in words, words


@pytest.mark.parametrize("robot_world", [False, True], ids=["hand-eye", "robot-world"])
@pytest.mark.parametrize("name,setup", PIXEL_SETS, ids=[n for n, _ in PIXEL_SETS])
def test_the_pixel_calibration_is_one_result_in_every_face(name, setup, robot_world):
    """`calibrate_on_pixels` prints what `handeye calibrate --method reprojection` prints (with
    `--robot-world`, the robot-world result with the target): the same object, field for field."""
    assert CLI.exists(), f"build the command line first ({CLI}): cargo build --release"
    path = TESTDATA / "pixels" / f"{name}.jsonl"
    intrinsics = TESTDATA / "pixels" / f"{name}.intrinsics.yml"
    args = [str(CLI), "calibrate", str(path), "--method", "reprojection", "--intrinsics",
            str(intrinsics), "--setup", setup, "--output", "json"]
    if robot_world:
        args.append("--robot-world")
    done = subprocess.run(args, capture_output=True, text=True, check=True)
    cli = json.loads(done.stdout)
    py = handeye.calibrate_on_pixels(path, intrinsics, setup=setup, robot_world=robot_world)
    py["matrix"] = py["matrix"].tolist()
    if robot_world:
        py["target"]["matrix"] = py["target"]["matrix"].tolist()
        assert py["method"] == "reprojection" and py["formulation"] == "robot-world"
        assert py["target"]["uncertainty"]["rotation_deg"] > 0
    assert py == cli


#: The frames of the committed ROS 2 recordings of a tag's detections (testdata/rosbag/make_tag_bags.py).
TAG_BAG = dict(base_frame="base_link", gripper_frame="tool0", camera_frame="camera",
               target_topic="/apriltag/detections", tag_size=0.06)


@pytest.mark.parametrize("bag", ["tag_eih_mcap", "tag_eih_sqlite3", "tag_eih_noinfo_sqlite3"])
def test_a_recording_of_tag_detections_is_one_result_in_every_face(bag):
    """`calibrate_on_pixels` reads a ROS 2 recording of a tag's detections as `handeye calibrate
    BAG --method reprojection --target-topic T --tag-size S` does: the same object, field for
    field; the intrinsics from the recording's CameraInfo, or from a file when it has none."""
    assert CLI.exists(), f"build the command line first ({CLI}): cargo build --release"
    path = TESTDATA / "rosbag" / bag
    intrinsics = TESTDATA / "pixels" / "tag_eih.intrinsics.yml" if "noinfo" in bag else None
    args = [str(CLI), "calibrate", str(path), "--method", "reprojection", "--output", "json",
            "--time-offset", "0"]
    for key, value in TAG_BAG.items():
        args += ["--" + key.replace("_", "-"), str(value)]
    if intrinsics is not None:
        args += ["--intrinsics", str(intrinsics)]
    done = subprocess.run(args, capture_output=True, text=True, check=True)
    cli = json.loads(done.stdout)
    py = handeye.calibrate_on_pixels(path, intrinsics, time_offset=0.0, **TAG_BAG)
    py["matrix"] = py["matrix"].tolist()
    assert py == cli
    assert py["reprojection"]["rms_px"] < 2.0


def test_a_recording_of_tag_detections_is_refused_in_words():
    """What the command line refuses on a tag recording, Python refuses with a ValueError naming
    its keyword: no tag size, tag keywords on a JSON Lines file, no intrinsics anywhere."""
    bag = TESTDATA / "rosbag" / "tag_eih_mcap"
    no_size = {k: v for k, v in TAG_BAG.items() if k != "tag_size"}
    with pytest.raises(ValueError, match="tag_size"):
        handeye.calibrate_on_pixels(bag, **no_size)
    jsonl = TESTDATA / "pixels" / "tag_eih.jsonl"
    with pytest.raises(ValueError, match="tag_size is for a ROS 2 recording"):
        handeye.calibrate_on_pixels(jsonl, TESTDATA / "pixels" / "tag_eih.intrinsics.yml", tag_size=0.06)
    with pytest.raises(ValueError, match="camera_info_topic"):
        handeye.calibrate_on_pixels(TESTDATA / "rosbag" / "tag_eih_noinfo_sqlite3", **TAG_BAG)
    with pytest.raises(ValueError, match="intrinsics=FILE"):
        handeye.calibrate_on_pixels(jsonl)


@pytest.mark.parametrize("robot_world", [False, True], ids=["hand-eye", "robot-world"])
def test_refined_intrinsics_are_one_result_in_every_face(robot_world):
    """`calibrate_on_pixels(..., refine_intrinsics=True)` prints what `--refine-intrinsics` prints,
    and from the wrong intrinsics of `board_span_eih` the refined ones are within 3 sigma of the
    true ones, k3 held (its sigma null)."""
    assert CLI.exists(), f"build the command line first ({CLI}): cargo build --release"
    path = TESTDATA / "pixels" / "board_span_eih.jsonl"
    wrong = TESTDATA / "pixels" / "board_span_eih.wrong.intrinsics.yml"
    args = [str(CLI), "calibrate", str(path), "--method", "reprojection", "--refine-intrinsics",
            "--intrinsics", str(wrong), "--setup", "eye-in-hand", "--output", "json"]
    if robot_world:
        args.append("--robot-world")
    cli = json.loads(subprocess.run(args, capture_output=True, text=True, check=True).stdout)
    py = handeye.calibrate_on_pixels(path, wrong, setup="eye-in-hand", robot_world=robot_world,
                                     refine_intrinsics=True)
    py["matrix"] = py["matrix"].tolist()
    if robot_world:
        py["target"]["matrix"] = py["target"]["matrix"].tolist()
    assert py == cli
    k = py["reprojection"]["intrinsics"]
    true = {"fx": 905.0, "fy": 903.5, "cx": 641.2, "cy": 358.7}
    for name, value in true.items():
        assert abs(k[name] - value) <= 3 * k["sigma"][name], (name, k[name], k["sigma"][name])
    assert k["held"] == ["k3"] and k["sigma"]["distortion"][4] is None
    # Without the flag the wrong intrinsics do not fit (refused), the right ones give no
    # `intrinsics`.
    with pytest.raises(ValueError, match="the intrinsics are this camera's"):
        handeye.calibrate_on_pixels(path, wrong, setup="eye-in-hand")
    right = TESTDATA / "pixels" / "board_span_eih.intrinsics.yml"
    plain = handeye.calibrate_on_pixels(path, right, setup="eye-in-hand")
    assert "intrinsics" not in plain["reprojection"]


def test_refining_the_intrinsics_of_one_tag_is_refused():
    """A single tag's 4 corners do not determine the intrinsics: a ValueError saying to use a
    board, as the command line refuses it (exit 2)."""
    path = TESTDATA / "pixels" / "tag_eih.jsonl"
    intrinsics = TESTDATA / "pixels" / "tag_eih.intrinsics.yml"
    with pytest.raises(ValueError, match="use a board"):
        handeye.calibrate_on_pixels(path, intrinsics, refine_intrinsics=True)


def test_the_pixel_calibration_refuses_inverted_robot_poses(tmp_path):
    """Robot poses that fit the pixels far better inverted: a ValueError naming the reading, as
    the command line refuses them."""
    text = (TESTDATA / "pixels" / "board_eth.jsonl").read_text()
    bad = tmp_path / "inverted.jsonl"
    bad.write_text(text.replace('"base_from_gripper"', '"gripper_from_base"'))
    intrinsics = TESTDATA / "pixels" / "board_eth.intrinsics.yml"
    with pytest.raises(ValueError, match="inverted"):
        handeye.calibrate_on_pixels(bad, intrinsics, setup="eye-to-hand", robot_world=True)


@pytest.mark.parametrize("turn_deg", [0.0, 1.0], ids=["true", "turned"])
def test_verify_on_the_pixels_is_one_result_in_every_face(tmp_path, turn_deg):
    """`verify_on_pixels` prints what `handeye verify --intrinsics` prints: the true X consistent,
    one turned by 1° inconsistent, in both."""
    truth = json.loads((TESTDATA / "pixels" / "tag_eih.truth.json").read_text())["gripper_from_camera"]
    half = np.radians(turn_deg) / 2
    x, y, z, w = truth["quaternion_xyzw"]
    # A turn about the parent frame's x axis: (sin, 0, 0, cos) ⊗ q.
    s, c = np.sin(half), np.cos(half)
    q = [c * x + s * w, c * y - s * z, c * z + s * y, c * w - s * x]
    saved = tmp_path / "saved.json"
    saved.write_text(json.dumps({"frame": "gripper_from_camera", "setup": "eye-in-hand",
                                 "translation": truth["translation"], "quaternion_xyzw": q}))
    path = TESTDATA / "pixels" / "tag_eih.jsonl"
    intrinsics = TESTDATA / "pixels" / "tag_eih.intrinsics.yml"
    done = subprocess.run([str(CLI), "verify", "--x", str(saved), str(path), "--intrinsics", str(intrinsics),
                           "--output", "json"], capture_output=True, text=True)
    cli = json.loads(done.stdout)
    py = handeye.verify_on_pixels(saved, path, intrinsics)
    assert py["verdict"] == ("consistent" if turn_deg == 0 else "inconsistent")
    py["saved"]["matrix"] = py["saved"]["matrix"].tolist()
    py["recording"]["matrix"] = py["recording"]["matrix"].tolist()
    assert py == cli


@pytest.mark.parametrize("name", ["outliers_gross_stations_eih_s0", "outliers_gross_stations_eih_s1"])
def test_online_tells_the_poses_it_holds_out_as_the_command_line_does(name):
    # Issue 31: Python's online calibrator tells what the command line tells; the accumulating
    # estimator's held-out poses are named with the same reason (by pose number, the file's line
    # here: these files have one record a line from the first).
    path = TESTDATA / "kinhec" / "pairs" / f"{name}.jsonl"
    out = subprocess.run([str(CLI), "online", str(path), "--output", "json"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    prefix = f"held out: {path}:"
    cli = [line[len(prefix):] for line in out.stderr.splitlines() if line.startswith(prefix)]
    assert cli, out.stderr
    r = handeye.read_recording(path)
    cal = handeye.OnlineCalibrator()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for a, b in zip(r["base_from_gripper"], r["camera_from_target"]):
            cal.push(a, b)
        cal.finish()
    said = [str(w.message)[len("held out: pose "):] for w in caught if str(w.message).startswith("held out: pose ")]
    assert said == cli, (said, cli)


@pytest.mark.parametrize("robot_world", [False, True], ids=["hand-eye", "robot-world"])
def test_calibrate_takes_the_pixels_as_calibrate_on_pixels_does(robot_world):
    """One `calibrate` for every problem and input kind: a path (positional or `path=`) with its
    intrinsics is the calibration on the pixels, `calibrate_on_pixels`' result field for field; a
    method other than the fit to the pixels, or poses beside the path, is refused."""
    name, setup = PIXEL_SETS[0]
    path = TESTDATA / "pixels" / f"{name}.jsonl"
    intrinsics = TESTDATA / "pixels" / f"{name}.intrinsics.yml"
    alias = handeye.calibrate_on_pixels(path, intrinsics, setup=setup, robot_world=robot_world)
    for one in (
        handeye.calibrate(path, intrinsics=intrinsics, setup=setup, robot_world=robot_world),
        handeye.calibrate(path=str(path), intrinsics=intrinsics, setup=setup, robot_world=robot_world),
    ):
        assert json.dumps(one, default=np.ndarray.tolist) == json.dumps(alias, default=np.ndarray.tolist)
    with pytest.raises(ValueError, match="reprojection"):
        handeye.calibrate(path, intrinsics=intrinsics, method="andreff")
    with pytest.raises(ValueError, match="not both"):
        handeye.calibrate(np.eye(4)[None], np.eye(4)[None], path=path, intrinsics=intrinsics)
