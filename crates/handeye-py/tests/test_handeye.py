"""handeye from Python: parity with cv2.calibrateHandEye, the paper fixtures, bad input."""
import json
import os
import pathlib
import sys
import warnings

import cv2
import numpy as np
import pytest

import handeye

TESTDATA = pathlib.Path(__file__).resolve().parents[3] / "testdata"
sys.path.insert(0, str(TESTDATA / "kinhec"))
from kinhec_poses import matrix4  # noqa: E402  (the kinhec files' pose reader, shared with their scripts)


def random_problem(rng, n=10, noise=True):
    """OpenCV's own test protocol (calib3d test_calibration_hand_eye.cpp), eye-in-hand."""

    def pose(tmin, tmax, lo, hi):
        axis = rng.uniform(-1, 1, 3)
        theta = rng.uniform(tmin, tmax) * rng.choice([-1, 1])
        r, _ = cv2.Rodrigues(axis * theta)
        t = rng.uniform(lo, hi, 3) * rng.choice([-1, 1], 3)
        return r, t

    d = np.pi / 180
    rx, tx = pose(10 * d, 50 * d, 0.05, 0.5)
    rw, tw = pose(5 * d, 85 * d, 0.5, 3.5)
    X = np.eye(4); X[:3, :3] = rx; X[:3, 3] = tx
    W = np.eye(4); W[:3, :3] = rw; W[:3, 3] = tw
    Rg, tg, Rc, tc = [], [], [], []
    for _ in range(n):
        r, t = pose(5 * d, 45 * d, 0.5, 1.5)
        G = np.eye(4); G[:3, :3] = r; G[:3, 3] = t
        C = np.linalg.inv(G @ X) @ W
        if noise:
            rv, _ = cv2.Rodrigues(C[:3, :3]); C[:3, :3], _ = cv2.Rodrigues(rv + rng.normal(0, 0.002, (3, 1)))
            C[:3, 3] += rng.normal(0, 0.005, 3)
            rv, _ = cv2.Rodrigues(G[:3, :3]); G[:3, :3], _ = cv2.Rodrigues(rv + rng.normal(0, 0.001, (3, 1)))
            G[:3, 3] += rng.normal(0, 0.001, 3)
        Rg.append(G[:3, :3].copy()); tg.append(G[:3, 3:4].copy())
        rvec, _ = cv2.Rodrigues(C[:3, :3])
        Rc.append(rvec); tc.append(C[:3, 3:4].copy())  # rotation vectors, as OpenCV accepts
    return Rg, tg, Rc, tc, X


METHODS = {
    "tsai": cv2.CALIB_HAND_EYE_TSAI,
    "park": cv2.CALIB_HAND_EYE_PARK,
    "horaud": cv2.CALIB_HAND_EYE_HORAUD,
    "andreff-joint": cv2.CALIB_HAND_EYE_ANDREFF,
    "daniilidis": cv2.CALIB_HAND_EYE_DANIILIDIS,
}


def camera_motion_rms(Rc, tc):
    """The RMS translation of the camera motions over every pair of poses: the unit handeye weighs
    andreff-joint's and Daniilidis' rows in (OpenCV weighs them in the input's unit)."""
    o = np.array([(cv2.Rodrigues(np.asarray(r, dtype=np.float64))[0] if np.size(r) == 3 else np.asarray(r)).T
                  @ np.ravel(t) for r, t in zip(Rc, tc)])
    d = o[:, None, :] - o[None, :, :]
    n = len(o)
    return np.sqrt((d ** 2).sum() / 2 / (n * (n - 1) / 2))


@pytest.mark.parametrize("seed", range(5))
def test_same_answers_as_opencv(seed):
    rng = np.random.default_rng(seed)
    Rg, tg, Rc, tc, _ = random_problem(rng)
    for name, code in METHODS.items():
        # andreff-joint and Daniilidis: OpenCV's answer for the data in units of the camera
        # motions' RMS length, which handeye weighs their rows in (one X in every unit).
        unit = camera_motion_rms(Rc, tc) if name in ("andreff-joint", "daniilidis") else 1.0
        r_cv, t_cv = cv2.calibrateHandEye(Rg, [t / unit for t in tg], Rc, [t / unit for t in tc], method=code)
        t_cv = t_cv * unit
        # OpenCV's Tsai filters motions; the constant asks for exactly that, the name does not.
        for m in (code,) if name == "tsai" else (name, code):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", UserWarning)
                r, t = handeye.calibrate_hand_eye(Rg, tg, Rc, tc, method=m)
            assert r.shape == (3, 3) and t.shape == (3, 1)
            assert np.abs(r - r_cv).max() <= 1e-6, name
            assert np.abs(t - t_cv).max() <= 1e-6, name


def test_every_form_of_the_arguments_gives_the_same_answer():
    # Lists of arrays are read in place by the extension; stacked arrays, tuples, views, lists of
    # lists and other dtypes take the other road. Each must give the same X, bit for bit.
    rng = np.random.default_rng(3)
    Rg, tg, Rc, tc, _ = random_problem(rng)
    homogeneous = [np.block([[r, t], [np.zeros((1, 3)), np.ones((1, 1))]]) for r, t in zip(Rg, tg)]
    forms = {
        "lists of arrays": (Rg, tg, Rc, tc),
        "tuples": (tuple(Rg), tuple(tg), tuple(Rc), tuple(tc)),
        "views of 4x4": ([h[:3, :3] for h in homogeneous], [h[:3, 3] for h in homogeneous], Rc, tc),
        "flat vectors": (Rg, [t.ravel() for t in tg], [r.ravel() for r in Rc], [t.T for t in tc]),
        "stacked arrays": (np.array(Rg), np.array(tg), np.array(Rc), np.array(tc)),
        "lists of lists": ([r.tolist() for r in Rg], [t.tolist() for t in tg], Rc, tc),
        "float32": ([r.astype(np.float32) for r in Rg], tg, Rc, tc),
    }
    for m in ("tsai", "park", "daniilidis", cv2.CALIB_HAND_EYE_TSAI):
        # OpenCV's constant selects OpenCV's Tsai, whose motion filter drops some of these motions
        # and says so; the names keep every motion and say nothing.
        said = "OpenCV's Tsai motion filter kept" if m == cv2.CALIB_HAND_EYE_TSAI else None
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            r0, t0 = handeye.calibrate_hand_eye(*forms["stacked arrays"], method=m)
        assert [str(w.message)[:len(said or "")] for w in caught] == ([said] if said else []), (m, [str(w.message) for w in caught])
        for name, args in forms.items():
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                r, t = handeye.calibrate_hand_eye(*args, method=m)
            assert len(caught) == (1 if said else 0), (name, m, [str(w.message) for w in caught])
            tol = 1e-6 if name == "float32" else 0.0
            assert np.abs(r - r0).max() <= tol and np.abs(t - t0).max() <= tol, (name, m)
    # Mixed rotation forms and bad sizes keep their messages whichever road they take.
    with pytest.raises(ValueError, match="rotation"):
        handeye.calibrate_hand_eye([Rg[0], Rc[1]] + Rg[2:], tg, Rc, tc)
    with pytest.raises(ValueError, match="translations"):
        handeye.calibrate_hand_eye(Rg, [np.zeros(2)] + tg[1:], Rc, tc)
    with pytest.raises(ValueError, match="orthonormal"):
        handeye.calibrate_hand_eye([2 * Rg[0]] + Rg[1:], tg, Rc, tc)


def test_noise_free_data_gives_the_truth_for_every_method():
    rng = np.random.default_rng(7)
    Rg, tg, Rc, tc, X = random_problem(rng, noise=False)
    for m in ["andreff", "andreff-joint", "tsai", "park", "horaud", "daniilidis", "refine"]:
        r, t = handeye.calibrate_hand_eye(Rg, tg, Rc, tc, method=m)
        assert np.abs(r - X[:3, :3]).max() < 1e-9, m
        assert np.abs(t.ravel() - X[:3, 3]).max() < 1e-9, m


def test_calibrate_reports_quality():
    rng = np.random.default_rng(11)
    Rg, tg, Rc, tc, X = random_problem(rng, n=12)
    g = np.array([np.block([[r, t.reshape(3, 1)], [np.zeros((1, 3)), np.ones((1, 1))]]) for r, t in zip(Rg, tg)])
    c = np.array([np.block([[cv2.Rodrigues(r)[0], t.reshape(3, 1)], [np.zeros((1, 3)), np.ones((1, 1))]]) for r, t in zip(Rc, tc)])
    result = handeye.calibrate(g, c, method="refine", pairs="all")
    assert result["frame"] == "gripper_from_camera" and result["motions"] == 66
    assert np.abs(result["matrix"][:3, :3] - X[:3, :3]).max() < 0.01
    q = result["quality"]
    assert q["axis_spread_deg"] > 20
    # The same report as `handeye calibrate`: an honest one-sigma, the readings tried, outliers.
    u = result["uncertainty"]
    assert 0 < u["rotation_deg"] < 1 and u["translation"] > 0
    rot_err = np.degrees(np.arccos(np.clip((np.trace(result["matrix"][:3, :3].T @ X[:3, :3]) - 1) / 2, -1, 1)))
    assert rot_err < 4 * u["rotation_deg"]
    assert result["reading"]["applied"] == "as-given" and result["outliers"]["poses"] == []
    assert result["residual"]["rotation_deg_rms"] < 1
    # The robot poses inverted: refused with the fix, and read that way on request.
    inverted = np.linalg.inv(g)
    with pytest.raises(ValueError, match="--fix robot-inverted"):
        handeye.calibrate(inverted, c, method="refine", pairs="all")
    # Read that way, the same X. Compared by Andreff (closed form): refine stops on a relative cost
    # drop of 1e-15, which pins X only to ~3e-8, and the inverse of the inverse differs from the
    # poses in the last bits.
    fixed = handeye.calibrate(inverted, c, method="andreff", pairs="all", fix="robot-inverted")
    plain = handeye.calibrate(g, c, method="andreff", pairs="all")
    assert np.abs(fixed["matrix"] - plain["matrix"]).max() < 1e-9
    fixed = handeye.calibrate(inverted, c, method="refine", pairs="all", fix="robot-inverted")
    assert np.abs(fixed["matrix"] - result["matrix"]).max() < 1e-7


def test_degenerate_data_raises_where_opencv_returns_garbage():
    # All rotations about one axis.
    Rg = [cv2.Rodrigues(np.array([0.0, 0.0, 0.2 * (k + 1)]))[0] for k in range(5)]
    tg = [np.array([k, 0.0, 0.0]) for k in range(5)]
    Rc = [r.T for r in Rg]
    tc = [np.zeros(3) for _ in range(5)]
    # All motions about one axis: refused as a low-DOF recording (issue 30's words).
    with pytest.raises(ValueError, match="rotates about the same axis"):
        handeye.calibrate_hand_eye(Rg, tg, Rc, tc, method="park")


def opencv_arguments(path):
    """A kinhec pose file as OpenCV's four lists, and the true translation of X."""
    poses = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    g = [matrix4(p["base_from_gripper"]) for p in poses]
    c = [matrix4(p["camera_from_target"]) for p in poses]
    truth = json.loads(path.with_suffix(".truth.json").read_text())["gripper_from_camera"]["translation"]
    return ([x[:3, :3] for x in g], [x[:3, 3] for x in g], [x[:3, :3] for x in c], [x[:3, 3] for x in c]), truth


def test_noisy_motions_about_one_axis_raise_where_opencv_answers_far_off():
    # kinhec: two parallel joint axes move, with robot and PnP noise. No solver's own test sees a
    # singular system, and OpenCV's Park answers 63 cm from the truth; the drop-in must refuse.
    args, truth = opencv_arguments(TESTDATA / "kinhec" / "pairs" / "degenerate_parallel_axes_continuous_eih_s0.jsonl")
    _, t_cv = cv2.calibrateHandEye(*args, method=cv2.CALIB_HAND_EYE_PARK)
    assert np.linalg.norm(t_cv.ravel() - truth) > 0.3
    for m in (cv2.CALIB_HAND_EYE_PARK, "horaud", "andreff-joint", "daniilidis", "refine"):
        with pytest.raises(ValueError, match="not determined|rotates about the same axis"):
            handeye.calibrate_hand_eye(*args, method=m)
    # The same motions with the other axes moving too are answered (the check is not a blanket one).
    args, truth = opencv_arguments(TESTDATA / "kinhec" / "pairs" / "nominal_continuous_eih_s0.jsonl")
    _, t = handeye.calibrate_hand_eye(*args, method="park")
    assert np.linalg.norm(t.ravel() - truth) < 0.01


def test_misread_inputs_raise_naming_the_arrays_to_change():
    # kinhec's mistakes: the robot in millimetres, the camera poses inverted. OpenCV answers both.
    # The drop-in has no `fix=`: its message names OpenCV's arrays and what to pass instead.
    for name, says in (("robot_mm__nominal_stations_eih_s0", "t_gripper2base in millimetres"),
                       ("camera_inverted__nominal_stations_eih_s0", "inverses of R_target2cam and t_target2cam"),
                       ("robot_inverted__nominal_stations_eih_s0", "inverses of R_gripper2base and t_gripper2base")):
        args, _ = opencv_arguments(TESTDATA / "kinhec" / "mistakes" / f"{name}.jsonl")
        with pytest.raises(ValueError, match="misread") as e:
            handeye.calibrate_hand_eye(*args, method="park")
        assert says in str(e.value) and "--fix" not in str(e.value) and "fix=" not in str(e.value), str(e.value)


def test_all_four_arrays_inverted_are_not_answered_silently():
    # Eye-in-hand with every array inverted fits exactly, with X and the target's pose swapped:
    # X would come out half a metre from the truth. The sizes alone would fit a fixed camera too,
    # but the camera arrays put the target off the camera's axis where their inverses put it in
    # view: refused, with or without `setup` (issue 52), naming the inversion.
    args, truth = opencv_arguments(TESTDATA / "kinhec" / "mistakes" / "both_inverted__nominal_stations_eih_s0.jsonl")
    for setup in (None, "eye-in-hand"):
        with pytest.raises(ValueError, match="all four arrays look inverted"):
            handeye.calibrate_hand_eye(*args, method="park", setup=setup)
    # Inverted back, the arrays give the truth.
    inverse = [np.linalg.inv(np.block([[r, t.reshape(3, 1)], [np.zeros((1, 3)), np.ones((1, 1))]]))
               for r, t in zip(args[0] + args[2], args[1] + args[3])]
    n = len(args[0])
    r_g, t_g = [m[:3, :3] for m in inverse[:n]], [m[:3, 3] for m in inverse[:n]]
    r_c, t_c = [m[:3, :3] for m in inverse[n:]], [m[:3, 3] for m in inverse[n:]]
    _, t = handeye.calibrate_hand_eye(r_g, t_g, r_c, t_c, method="park", setup="eye-in-hand")
    assert np.linalg.norm(t.ravel() - truth) < 0.01


def test_outliers_are_named_not_mistaken_for_a_misread_input():
    # kinhec's series with a few flipped target poses (planar flip) or random poses: as given the
    # median fit is poor, and "both inverted" looked better, so the drop-in told the user to invert
    # correct data. Judged without the outlier poses the data fit as given: the outliers are named,
    # in a warning as the command line gives it (it answers, with the caution).
    for name in ("outliers_planar_flip_stations_eih_s0", "outliers_planar_flip_stations_eih_s2",
                 "outliers_random_pose_stations_eih_s2"):
        args, _ = opencv_arguments(TESTDATA / "kinhec" / "pairs" / f"{name}.jsonl")
        with warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always")
            handeye.calibrate_hand_eye(*args, method="park")
        texts = [str(w.message) for w in said]
        outliers = [t for t in texts if "disagree with the others" in t]
        assert len(outliers) == 1 and "reject_outliers=True" in outliers[0], texts
        assert not any("misread" in t for t in texts), texts


def test_outliers_that_leave_the_median_fit_good_are_named_where_opencv_answers_far_off():
    # kinhec's series with a few random poses whose median fit is good: the drop-in answered them
    # 10-15 degrees and 7-13 cm from the truth without a word. It warns now, as the command line
    # does, naming the poses; the same stations without outliers are answered without a word.
    for name in ("outliers_random_pose_stations_eih_s0", "outliers_random_pose_stations_eih_s1",
                 "outliers_gross_stations_eih_s1"):
        args, truth = opencv_arguments(TESTDATA / "kinhec" / "pairs" / f"{name}.jsonl")
        _, t_cv = cv2.calibrateHandEye(*args, method=cv2.CALIB_HAND_EYE_PARK)
        assert np.linalg.norm(t_cv.ravel() - truth) > 0.01, name
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            handeye.calibrate_hand_eye(*args, method="park")
        said = [str(w.message) for w in caught if issubclass(w.category, UserWarning)]
        # The outliers are named; what they do to the fit (large residuals, a weakly determined X)
        # is said too, as the command line says it.
        assert any("disagree with the others" in m for m in said), (name, said)
        assert any(m.startswith("rotation residuals of") for m in said), (name, said)
    args, truth = opencv_arguments(TESTDATA / "kinhec" / "pairs" / "nominal_stations_eih_s1.jsonl")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _, t = handeye.calibrate_hand_eye(*args, method="park")
    assert np.linalg.norm(t.ravel() - truth) < 0.002


def test_what_calibrate_would_warn_about_is_a_python_warning_and_eye_to_hand_says_its_setup():
    # Eye-to-hand as OpenCV takes it: base2gripper poses, cam2base back. kinhec's PnP stations
    # leave a rotation of X weakly determined (calibrate warns, one-sigma about 1 degree). The
    # nominal stations warn of nothing once the caller says the setup; without it, X's size is
    # also what an eye-in-hand caller with every array inverted would get, and the drop-in asks.
    def base2gripper(name):
        poses = [json.loads(line) for line in (TESTDATA / "kinhec" / "pairs" / f"{name}.jsonl").read_text().splitlines()]
        g = [np.linalg.inv(matrix4(p["base_from_gripper"])) for p in poses]
        c = [matrix4(p["camera_from_target"]) for p in poses]
        return [x[:3, :3] for x in g], [x[:3, 3] for x in g], [x[:3, :3] for x in c], [x[:3, 3] for x in c]

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        handeye.calibrate_hand_eye(*base2gripper("pnp_stations_eth_s2"), method="park", setup="eye-to-hand")
    said = [str(w.message) for w in caught]
    # The PnP noise shows in the residuals (8.6 degrees RMS, as `handeye calibrate` prints it) and
    # leaves a rotation of X weakly determined.
    assert any("weakly determined" in m for m in said), said
    assert any(m.startswith("rotation residuals of") for m in said), said
    with pytest.warns(UserWarning, match="what a fixed camera gives"):
        r_unsaid, t_unsaid = handeye.calibrate_hand_eye(*base2gripper("nominal_stations_eth_s0"), method="park")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r, t = handeye.calibrate_hand_eye(*base2gripper("nominal_stations_eth_s0"), method="park", setup="eye-to-hand")
    # The same motions either way: the same X.
    assert np.abs(r - r_unsaid).max() < 1e-9 and np.abs(t - t_unsaid).max() < 1e-9


def test_bad_inputs_raise_and_never_crash():
    eye = np.eye(4)
    with pytest.raises(ValueError):
        handeye.calibrate(np.stack([eye, eye]), np.stack([eye]))
    bad = eye.copy(); bad[0, 0] = 2.0
    with pytest.raises(ValueError, match="orthonormal"):
        handeye.calibrate(np.stack([eye, bad, eye]), np.stack([eye, eye, eye]))
    nan = eye.copy(); nan[0, 3] = np.nan
    with pytest.raises(ValueError):
        handeye.calibrate(np.stack([eye, nan, eye]), np.stack([eye, eye, eye]))
    with pytest.raises(ValueError):
        handeye.calibrate_hand_eye([np.eye(3)], [np.zeros(2)], [np.eye(3)], [np.zeros(3)])
    with pytest.raises(ValueError):
        handeye.calibrate(np.stack([eye] * 3), np.stack([eye] * 3), method="magic")
    with pytest.raises(ValueError):
        handeye.OnlineCalibrator(selection="magic")
    for selection in ("fixed", "adaptive"):
        with pytest.raises(ValueError, match="n_init"):
            handeye.OnlineCalibrator(selection=selection, n_init=2**62)
    with pytest.raises(ValueError, match="alpha_min_deg"):
        handeye.OnlineCalibrator(alpha_min_deg=95.0)
    with pytest.raises(ValueError):
        handeye.OnlineCalibrator(alpha_min_deg=15.0, alpha_min=0.25)
    with pytest.raises(ValueError):
        handeye.OnlineCalibrator(rms_t_max=float("nan"))
    handeye.OnlineCalibrator(alpha_min_deg=15.0)
    with pytest.warns(DeprecationWarning, match="alpha_min_deg"):
        handeye.OnlineCalibrator(alpha_min=0.25)
    c = handeye.OnlineCalibrator()
    with pytest.raises(ValueError):
        c.push(np.eye(3), eye)
    assert c.poses == 0
    # The bootstrap's bounds are the command line's (issue 34 item 5: 2**30 aborted the
    # interpreter with a 60 GB allocation, 2**62 raised a PanicException).
    q, cam = load_series("series_2007_000_200")[:2]
    for bootstrap in (2**30, 2**62, 7, 0):
        with pytest.raises(ValueError, match="bootstrap"):
            handeye.calibrate(q[:20], cam[:20], bootstrap=bootstrap)
        with pytest.raises(ValueError, match="bootstrap"):
            handeye.calibrate(q[:20], cam[:20], bootstrap=bootstrap, robot_world=True)


def test_private_functions_and_the_online_bounds_raise_value_errors():
    # Issue 34 item 15: a 0-d array made a private function panic; shrink=nan, shrink=0 and
    # every=0 were taken where the command line refuses them; from_state of a 100 MB string
    # echoed it whole in its error.
    from handeye import _handeye
    for zero_d in (np.array(1.0), np.float64(1.0)):
        with pytest.raises(ValueError, match="0-d"):
            _handeye.solve_opencv(np.asarray(zero_d), np.zeros((1, 3)), np.asarray(zero_d), np.zeros((1, 3)))
    for bad in ({"shrink": float("nan")}, {"shrink": 0.0}, {"shrink": float("inf")}, {"every": 0},
                {"every": -1}, {"n_init": -3}, {"interval": -1},
                {"relax_up": 1e308}, {"explore": 1e-320}, {"relax_down": 1e-320}):
        name = next(iter(bad))
        with pytest.raises(ValueError, match=name):
            handeye.OnlineCalibrator(**bad)
    huge = "x" * (100 << 20)
    for state in (json.dumps(huge), huge):
        with pytest.raises(ValueError) as e:
            handeye.OnlineCalibrator.from_state(state)
        assert len(str(e.value)) < 1000
    # A saved state whose settings are out of range is refused as the constructor refuses them.
    saved = json.loads(handeye.OnlineCalibrator().state())
    saved["config"]["tracking"]["shrink"] = 0.0
    with pytest.raises(ValueError, match="shrink"):
        handeye.OnlineCalibrator.from_state(json.dumps(saved))


def load_series(name):
    lines = (TESTDATA / "paper" / f"{name}.jsonl").read_text().splitlines()
    poses = [json.loads(l) for l in lines if l.strip()]
    q = np.array([p["base_from_gripper"] for p in poses])
    c = np.array([np.linalg.inv(np.array(p["target_from_camera"])) for p in poses])
    truth = np.array(json.loads((TESTDATA / "paper" / f"{name}.truth.json").read_text())["gripper_from_camera"]["matrix"])
    expected = json.loads((TESTDATA / "paper" / f"{name}.expected.json").read_text())
    return q, c, truth, expected


def test_online_calibrator_reproduces_the_paper_fixture_and_resumes_from_state():
    q, c, truth, expected = load_series("series_2007_000_200")
    cal = handeye.OnlineCalibrator(selection="adaptive", estimator="paper", error_source="truth", truth=truth, d_max=100.0)
    events, resumed = [], None
    for k in range(len(q)):
        events.extend(cal.push(q[k], c[k]))
        if k == 60:
            resumed = handeye.OnlineCalibrator.from_state(cal.state())
    assert [e["poses"] for e in events] == [x["poses"] for x in expected["adaptive"]]
    for e, x in zip(events, expected["adaptive"]):
        assert np.abs(e["matrix"] - np.array(x["matrix"])).max() < 1e-8
    later = [e for k in range(61, len(q)) for e in resumed.push(q[k], c[k])]
    assert [e["poses"] for e in later] == [e["poses"] for e in events if e["poses"][2] > 61]


def test_the_accumulating_estimator_reports_on_its_own_schedule_with_an_honest_uncertainty():
    q, c, truth, _ = load_series("series_2007_000_200")
    cal = handeye.OnlineCalibrator(estimator="accumulate", every=50)
    assert cal.pending() is not None  # nothing yet, and it says why
    reports = []
    for k in range(len(q)):
        reports.extend(cal.push(q[k], c[k]))
    final = cal.finish()
    reports += [final] if final is not None else []
    estimates = [r for r in reports if "estimate" in r]
    assert len(estimates) >= 2 and estimates[-1]["reason"] == "end"
    assert not any("change" in r for r in reports)
    for r in estimates:
        assert r["matrix"].shape == (4, 4) and r["target"]["frame"] == "base_from_target"
        d = np.linalg.inv(truth) @ r["matrix"]
        angle = np.degrees(np.arccos(np.clip((np.trace(d[:3, :3]) - 1) / 2, -1, 1)))
        assert angle < 3 * r["uncertainty"]["rotation_deg"]
        assert np.linalg.norm(d[:3, 3]) < 3 * r["uncertainty"]["translation"]


def test_robot_world_matches_opencv_and_reports_the_target():
    """calibrate(..., robot_world=True): Shah and Li give cv2.calibrateRobotWorldHandEye's answer
    (OpenCV's A X = Z B with world2cam = camera_from_target, base2gripper = base_from_gripper⁻¹;
    X = gripper2cam⁻¹, target = base2world⁻¹), and refine reports X and the target near the truth."""
    rng = np.random.default_rng(5)
    Rg, tg, Rc, tc, X = random_problem(rng, n=15)
    g = np.array([np.block([[r, t.reshape(3, 1)], [np.zeros((1, 3)), np.ones((1, 1))]]) for r, t in zip(Rg, tg)])
    c = np.array([np.block([[cv2.Rodrigues(r)[0], t.reshape(3, 1)], [np.zeros((1, 3)), np.ones((1, 1))]]) for r, t in zip(Rc, tc)])
    b = np.linalg.inv(g)
    for name, flag in [("shah", cv2.CALIB_ROBOT_WORLD_HAND_EYE_SHAH), ("li", cv2.CALIB_ROBOT_WORLD_HAND_EYE_LI)]:
        # Li weighs rotations against lengths: handeye in the RMS translation of the poses it
        # solves with (camera_from_target and the hand's inverse), OpenCV in the input's unit, so
        # OpenCV's answer for the data in that unit is handeye's.
        unit = 1.0
        if name == "li":
            unit = np.sqrt((np.linalg.norm(c[:, :3, 3], axis=1) ** 2 + np.linalg.norm(b[:, :3, 3], axis=1) ** 2).sum() / (2 * len(c)))
        r_w, t_w, r_z, t_z = cv2.calibrateRobotWorldHandEye(
            [m[:3, :3] for m in c], [m[:3, 3:4] / unit for m in c], [m[:3, :3] for m in b], [m[:3, 3:4] / unit for m in b], method=flag
        )
        z = np.eye(4); z[:3, :3] = r_z; z[:3, 3] = t_z.ravel() * unit
        w = np.eye(4); w[:3, :3] = r_w; w[:3, 3] = t_w.ravel() * unit
        result = handeye.calibrate(g, c, robot_world=True, method=name)
        assert np.abs(result["matrix"] - np.linalg.inv(z)).max() < 1e-6, name
        assert np.abs(result["target"]["matrix"] - np.linalg.inv(w)).max() < 1e-6, name
    result = handeye.calibrate(g, c, robot_world=True)
    assert result["method"] == "refine" and result["target"]["frame"] == "base_from_target"
    assert np.abs(result["matrix"][:3, :3] - X[:3, :3]).max() < 0.01
    assert result["uncertainty"]["rotation_deg"] > 0 and result["target"]["uncertainty"]["translation"] > 0
    assert len(result["residual"]["per_pose"]) == 15
    with pytest.raises(ValueError):
        handeye.calibrate(g[:2], c[:2], robot_world=True)
    with pytest.raises(ValueError):
        handeye.calibrate(g, c, robot_world=True, method="tsai")


def test_advise_names_the_next_motions_and_what_they_would_give():
    q, c, _, _ = load_series("series_2007_000_200")
    advice = handeye.advise(q[:12], c[:12], count=2)
    assert advice["poses"] == 12 and len(advice["suggestions"]) == 2
    now = advice["current"]["rotation_deg"]
    assert advice["suggestions"][-1]["predicted"]["rotation_deg"] < now
    assert {w["kind"] for w in advice["weakest"]} == {"rotation", "translation"}
    with pytest.raises(ValueError):
        handeye.advise(q[:12], c[:12], count=0)


REPO = pathlib.Path(__file__).resolve().parents[3]
# The command line built by `cargo build --release`, in cargo's target directory.
CLI = REPO / os.environ.get("CARGO_TARGET_DIR", "target") / "release" / "handeye"


def _cli_json(*args):
    """What `handeye ARGS --output json` prints: one object, or a list for JSON Lines."""
    import subprocess

    assert CLI.exists(), f"build the command line first ({CLI}): cargo build --release"
    out = subprocess.run([str(CLI), *map(str, args), "--output", "json"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    if args[0] == "calibrate":
        return json.loads(out.stdout)
    return [json.loads(l) for l in out.stdout.splitlines() if l.strip()]


def _jsonl_poses(path):
    rows = [json.loads(l) for l in path.read_text().splitlines() if l.strip()]
    return (np.array([r["base_from_gripper"] for r in rows], dtype=np.float64),
            np.array([r["camera_from_target"] for r in rows], dtype=np.float64))


def _plain(v):
    """Arrays as lists, so that the CLI's JSON and Python's dict compare as values."""
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, dict):
        return {k: _plain(x) for k, x in v.items()}
    if isinstance(v, list):
        return [_plain(x) for x in v]
    return v


# Fields that name the poses: the command line names them `file:line`, Python by number.
NAMED = {"name", "shown", "disagree"}


def _same(cli, py, where=""):
    """The same fields, and the same values (names of poses apart), at every level."""
    if isinstance(cli, dict):
        assert isinstance(py, dict), where
        assert set(cli) == set(py), f"{where}: only in the CLI {set(cli) - set(py)}, only in Python {set(py) - set(cli)}"
        for k in cli:
            if k in NAMED:
                assert len(_plain(cli[k])) == len(_plain(py[k])) if isinstance(cli[k], list) else True, f"{where}.{k}"
                continue
            if k == "seconds":  # wall time of the event
                continue
            _same(cli[k], py[k], f"{where}.{k}")
    elif isinstance(cli, list):
        assert isinstance(py, list) and len(cli) == len(py), where
        for i, (a, b) in enumerate(zip(cli, py)):
            _same(a, b, f"{where}[{i}]")
    elif isinstance(cli, str) and isinstance(py, str):
        if where.endswith(".message"):  # a message may quote a pose's name
            return
        assert cli == py, where
    elif isinstance(cli, float) or isinstance(py, float):
        # The CLI parses the file's decimals, Python gets the same doubles (or, for the paper's
        # target_from_camera, numpy's inverse): equal to the last digits.
        assert py == pytest.approx(cli, rel=1e-9, abs=1e-12), f"{where}: {cli} != {py}"
    else:
        assert cli == py, f"{where}: {cli} != {py}"


@pytest.mark.parametrize(
    "name, setup, extra",
    [
        ("nominal_stations_eih_s0", "eye-in-hand", {}),
        ("outliers_gross_stations_eth_s0", "eye-to-hand", {}),
        ("near_degenerate_two_axes_continuous_eih_s0", "eye-in-hand", {"pairs": "all"}),
        ("pnp_stations_eth_s0", "eye-to-hand", {"method": "refine", "pairs": "all"}),
    ],
)
def test_the_command_line_and_python_give_the_same_report(name, setup, extra):
    path = TESTDATA / "kinhec" / "pairs" / f"{name}.jsonl"
    args = [a for k, v in extra.items() for a in (f"--{k}", v)]
    cli = _cli_json("calibrate", path, "--setup", setup, *args)
    g, c = _jsonl_poses(path)
    py = _plain(handeye.calibrate(g, c, setup=setup, **extra))
    _same(cli, py)
    for w in py["warnings"]:
        assert {"code", "message"} <= set(w) and "--" not in w["message"], w


def test_the_command_line_and_python_give_the_same_online_events(tmp_path):
    # 4x4 matrices as the file gives them, so that both faces solve from the same doubles.
    path = tmp_path / "walk.jsonl"
    import subprocess

    subprocess.run([str(CLI), "simulate", "--poses", "400", "--seed", "5", "--out", str(path)], check=True)
    q, c = _jsonl_poses(path)
    # The paper's estimator on both faces (both default to the accumulating one).
    cli = _cli_json("online", path, "--optimal", "--estimator", "paper")
    cal = handeye.OnlineCalibrator(selection="adaptive", optimal=True, estimator="paper")
    py = [e for k in range(len(q)) for e in cal.push(q[k], c[k])]
    assert len(cli) > 3 and any("optimal" in e for e in cli)
    _same(cli, _plain(py))


@pytest.mark.parametrize("name", ["paper/series_2007_000_200.jsonl", "kinhec/pairs/pnp_stations_eth_s1.jsonl",
                                  "kinhec/pairs/robot_error_stations_eih_s2.jsonl"])
def test_the_accumulating_estimator_gives_one_verdict_in_both_faces(name):
    # Every report of the default estimator, field for field: X, its uncertainty, the warnings
    # (a weakly determined direction, a systematic error) and the verdict. The last report comes
    # from finish() in Python, as the end of the stream in the command line.
    path = TESTDATA / name
    setup = "eye-to-hand" if "_eth_" in name else "eye-in-hand"
    cli = [e for e in _cli_json("online", path, "--setup", setup) if "estimate" in e]
    r = handeye.read_recording(path)
    cal = handeye.OnlineCalibrator(setup=setup)
    py = [e for a, b in zip(r["base_from_gripper"], r["camera_from_target"]) for e in cal.push(a, b)]
    last = cal.finish()
    py = [e for e in py if "estimate" in e] + ([last] if last is not None and last not in py else [])
    assert len(cli) >= 2
    assert [e["verdict"] for e in cli] == [e["verdict"] for e in py]
    _same(cli, _plain(py))
    # The paper's series: its first report leaves the translation weak (questionable, with the
    # batch's warning), its last is good.
    if name.startswith("paper/"):
        assert cli[0]["verdict"] == "questionable" and cli[-1]["verdict"] == "good", [e["verdict"] for e in cli]
        assert [w["code"] for w in cli[0]["warnings"]] == ["weak_direction"]


# read_recording: every input through the library's Recording, as the command line reads it.

GOLDEN = TESTDATA / "golden" / "outputs.jsonl"


def golden(args):
    """The command line's recorded output of `args` (paths relative to the repository)."""
    for line in GOLDEN.read_text().splitlines():
        entry = json.loads(line)
        if " ".join(entry["args"]) == args:
            return entry
    raise KeyError(args)


def test_read_recording_of_a_jsonl_file_names_each_pose_by_line():
    path = TESTDATA / "opencv" / "opencv_eye-in-hand_exact_10_11.jsonl"
    r = handeye.read_recording(path)
    assert r["base_from_gripper"].shape == (10, 4, 4) == r["camera_from_target"].shape
    assert r["names"] == [f"{path}:{k}" for k in range(1, 11)]
    assert r["lines"] == list(range(1, 11))
    assert r["time_offset"] is None and r["offset_curve"] is None and r["notes"] == []
    first = json.loads(path.read_text().splitlines()[0])
    np.testing.assert_allclose(r["base_from_gripper"][0], first["base_from_gripper"], atol=1e-12)
    X = handeye.calibrate(r["base_from_gripper"], r["camera_from_target"])["matrix"]
    assert X.shape == (4, 4)


def test_read_recording_of_two_streams_finds_the_cli_offset(shared):
    # ethz-asl's streams, read in place from the shared folder; the golden outputs name it {shared}.
    robot, camera = shared("ethz-asl/robot_arm_sim_B_H.csv", "ethz-asl/robot_arm_sim_W_E.csv")
    entry = golden(f"calibrate --robot {{shared}}/ethz-asl/{robot.name} --camera {{shared}}/ethz-asl/{camera.name} "
                   "--time-offset auto --output json")
    r = handeye.read_recording(robot=robot, camera=camera, time_offset="auto")
    report = json.loads(entry["stdout"])
    assert r["time_offset"] == report["time_offset_s"]
    assert len(r["names"]) == report["poses"] == r["camera_from_target"].shape[0]
    notes = [line.replace("{shared}", str(robot.parent.parent)) for line in entry["stderr"].splitlines()[:3]]
    assert r["notes"] == notes
    assert r["offset_curve"].shape[1] == 2
    assert r["names"][0] == f"{camera} at t = {r['stamps'][0]:.3f} s"


def test_read_recording_of_a_ros2_bag_with_auto_offset():
    bag = TESTDATA / "rosbag" / "eih_pose_offset_mcap"
    entry = golden(
        "calibrate testdata/rosbag/eih_pose_offset_mcap --base-frame base_link --gripper-frame tool0 "
        "--camera-frame camera_link --target-topic /board_pose --time-offset auto --pairs consecutive --output json"
    )
    r = handeye.read_recording(
        bag, base_frame="base_link", gripper_frame="tool0", camera_frame="camera_link",
        target_topic="/board_pose", time_offset="auto",
    )
    assert r["time_offset"] == json.loads(entry["stdout"])["time_offset_s"]
    assert r["base_from_gripper"].shape == (80, 4, 4)
    assert r["target_source"] == "/board_pose"
    assert r["notes"][1] == f"{bag}: 80 pose pair(s) from 80 observation(s) of the target (/board_pose)"
    fixed = handeye.read_recording(
        bag, base_frame="base_link", gripper_frame="tool0", camera_frame="camera_link",
        target_topic="/board_pose", time_offset=0.037,
    )
    assert fixed["time_offset"] == 0.037 and fixed["offset_curve"] is None


def test_read_recording_of_an_optical_camera_frame_says_what_to_publish():
    # Issue 33 item 12: the optical frame has a parent in tf (camera_link, from /tf_static), so X
    # found for it is published for camera_link, X @ inv(root_from_camera).
    bag = TESTDATA / "rosbag" / "eih_tf_mcap"
    frames = dict(base_frame="base_link", gripper_frame="tool0", target_frame="board")
    r = handeye.read_recording(bag, camera_frame="camera_color_optical_frame", **frames)
    assert any(
        "the camera frame `camera_color_optical_frame` has a parent in tf already" in n
        and "publish it for `camera_link`, the root of the camera's subtree" in n
        for n in r["notes"]
    ), r["notes"]
    m = r["camera_mount"]
    assert (m["camera"], m["root"], m["placed_under"], m["tf_x"]) == (
        "camera_color_optical_frame", "camera_link", None, None)
    truth = json.loads((TESTDATA / "rosbag" / "eih_tf_mcap.truth.json").read_text())
    link, optical = (np.array(truth[k]) for k in ("tool0_from_camera_link", "tool0_from_camera_color_optical_frame"))
    assert np.allclose(optical @ np.linalg.inv(m["root_from_camera"]), link, atol=1e-12)
    plain = handeye.read_recording(bag, camera_frame="camera_link", **frames)
    assert plain["camera_mount"] is None
    assert not any("has a parent in tf" in n for n in plain["notes"])


def test_read_recording_refuses_bad_input_with_a_clear_message(tmp_path):
    missing = tmp_path / "missing.jsonl"
    with pytest.raises(ValueError, match="missing.jsonl"):
        handeye.read_recording(missing)
    bag = TESTDATA / "rosbag" / "eih_tf_mcap"
    with pytest.raises(ValueError, match="name its frames with base_frame"):
        handeye.read_recording(bag)
    with pytest.raises(ValueError, match="base_lnk"):
        handeye.read_recording(bag, base_frame="base_lnk", gripper_frame="tool0", camera_frame="camera_link", target_frame="board")
    # Issue 33 item 13: the base below the gripper in the tf tree is the two names swapped.
    with pytest.raises(ValueError, match='swap the two frame flags.*base_frame="base_link", gripper_frame="tool0"'):
        handeye.read_recording(bag, base_frame="tool0", gripper_frame="base_link", camera_frame="camera_link", target_frame="board")
    with pytest.raises(ValueError, match="is for a ROS 2 recording"):
        handeye.read_recording(TESTDATA / "opencv" / "opencv_eye-in-hand_exact_10_11.jsonl", base_frame="base_link")
    with pytest.raises(ValueError, match="not both"):
        handeye.read_recording(bag, robot=bag, camera=bag)
    with pytest.raises(ValueError, match="time_offset"):
        handeye.read_recording(robot=bag, camera=bag, time_offset="soon")
    still = tmp_path / "still.txt"
    still.write_text("".join(f"{0.1 * k:.1f} 0 0 0 0 0 0 1\n" for k in range(30)))
    with pytest.raises(ValueError, match="time offset `auto` on .*still.txt"):
        handeye.read_recording(robot=still, camera=still, time_offset="auto")
    one = tmp_path / "one.jsonl"
    one.write_text((TESTDATA / "opencv" / "opencv_eye-in-hand_exact_10_11.jsonl").read_text().splitlines()[0])
    with pytest.raises(ValueError, match="at least 2"):
        handeye.read_recording(one)


def test_read_recording_reads_a_named_rotation_convention(tmp_path):
    # Issue 33 item 11: KUKA A, B, C columns read with rotation="kuka-abc" give SciPy's matrices
    # (testdata/rotation/fixtures.json); unnamed, they are refused naming the keyword.
    fixtures = json.loads((TESTDATA / "rotation" / "fixtures.json").read_text())["conventions"]
    cases = fixtures["kuka-abc"]
    header = ",".join(
        f"{frame}_{s}" for frame in ("base_from_gripper", "camera_from_target") for s in "xyzabc"
    )
    rows = []
    for k, case in enumerate(cases):
        pose = ",".join(repr(float(v)) for v in [0.1 * k, -0.2, 0.3, *case["values"]])
        rows.append(f"{pose},{pose}")
    path = tmp_path / "kuka.csv"
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    for rotation in ("kuka-abc", ["robot=kuka-abc", "camera=kuka-abc"], {"robot": "kuka-abc", "camera": "kuka-abc"}):
        r = handeye.read_recording(path, rotation=rotation)
        want = np.array([c["matrix"] for c in cases])
        assert np.abs(r["base_from_gripper"][:, :3, :3] - want).max() < 1e-12
        assert np.abs(r["camera_from_target"][:, :3, :3] - want).max() < 1e-12
    with pytest.raises(ValueError, match='rotation="kuka-abc"'):
        handeye.read_recording(path)
    with pytest.raises(ValueError, match="unknown rotation convention `kuka`"):
        handeye.read_recording(path, rotation="kuka")
    with pytest.raises(ValueError, match="rotation: expected"):
        handeye.read_recording(path, rotation=3)


def _push_all(calibrator, path):
    r = handeye.read_recording(path)
    for a, b in zip(r["base_from_gripper"], r["camera_from_target"]):
        calibrator.push(a, b)
    calibrator.finish()  # these files have 40 poses: a stream under 64 is checked at its end


def test_online_checks_the_first_poses_as_the_command_line_does():
    # The paper's estimator has no checks of its own: the first 64 poses (a shorter stream's, at
    # finish) get the command line's readings check (issue 31: Python's online calibrator has every check the CLI has).
    inverted = TESTDATA / "kinhec" / "mistakes" / "camera_inverted__nominal_stations_eih_s0.jsonl"
    paper = lambda: handeye.OnlineCalibrator(estimator="paper")  # noqa: E731
    with pytest.warns(UserWarning, match="read wrongly.*--fix camera-inverted"):
        _push_all(paper(), inverted)
    one_axis = TESTDATA / "kinhec" / "pairs" / "degenerate_single_joint_continuous_eih_s0.jsonl"
    with pytest.warns(UserWarning, match="about one axis"):
        _push_all(paper(), one_axis)
    # Data read right: no warning.
    right = TESTDATA / "kinhec" / "pairs" / "nominal_stations_eih_s0.jsonl"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _push_all(paper(), right)


def test_online_says_a_stuck_selection_as_the_command_line_does():
    # Issue 31: the paper's selection without a calibration is told at 200, 400, 800, ... poses
    # (the command line's words and schedule, from the one online calibrator).
    still = np.eye(4)
    target = np.eye(4)
    target[2, 3] = 0.5
    cal = handeye.OnlineCalibrator(estimator="paper")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for _ in range(500):
            cal.push(still, target)
        said = [str(w.message) for w in caught]
    stuck = [m.split(":")[0] for m in said if m.startswith("no calibration")]
    assert stuck == ["no calibration in 200 poses", "no calibration in 400 poses"], said
    # The accumulating estimator says why it has no estimate through pending(), not a warning.
    acc = handeye.OnlineCalibrator()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for _ in range(20):
            acc.push(still, target)
        acc.finish()
    assert acc.pending() is not None


def test_online_defaults_to_the_accumulating_estimator_and_push_returns_a_list():
    # Issue 33 items 2 and 19: Python's default is the command line's (every estimate with its
    # uncertainty, the readings checked), and push returns one type.
    cal = handeye.OnlineCalibrator()
    r = r_good = handeye.read_recording(TESTDATA / "kinhec" / "pairs" / "nominal_stations_eih_s0.jsonl")
    truth = json.loads((TESTDATA / "kinhec" / "pairs" / "nominal_stations_eih_s0.truth.json").read_text())
    x_true = np.array(truth["gripper_from_camera"]["matrix"])
    pushed = [cal.push(a, b) for a, b in zip(r["base_from_gripper"], r["camera_from_target"])]
    assert all(isinstance(p, list) for p in pushed)
    final = cal.finish()
    assert final is not None and "estimate" in final and "uncertainty" in final
    angle = np.degrees(np.arccos(np.clip((np.trace(x_true[:3, :3].T @ final["matrix"][:3, :3]) - 1) / 2, -1, 1)))
    assert angle < 3 * final["uncertainty"]["rotation_deg"] + 1e-9, (angle, final["uncertainty"])
    # An inverted camera stream: the accumulating estimator reports no X, and says why.
    inverted = handeye.OnlineCalibrator()
    r = handeye.read_recording(TESTDATA / "kinhec" / "mistakes" / "camera_inverted__nominal_stations_eih_s0.jsonl")
    reports = [e for a, b in zip(r["base_from_gripper"], r["camera_from_target"]) for e in inverted.push(a, b)]
    assert not any("estimate" in e for e in reports), reports
    assert inverted.finish() is None
    assert "camera" in (inverted.pending() or ""), inverted.pending()
    assert inverted.last_report() is None
    # The estimate to use is the last report, with its arrays; a camera moved on its mount
    # withdraws the one from before it (a report from before a change is not the current X).
    assert cal.last_report()["matrix"].shape == (4, 4)
    assert np.allclose(cal.last_report()["matrix"], final["matrix"])
    moved = np.eye(4)
    moved[:3, :3] = cv2.Rodrigues(np.array([0.0, 0.14, 0.0]))[0]
    moved[:3, 3] = [0.04, 0.0, 0.0]
    bumped = np.linalg.inv(moved) @ r_good["camera_from_target"]
    changes = []
    # The first poses after the move are held out before the change is confirmed, and told, as
    # the command line tells them (issue 31).
    with pytest.warns(UserWarning, match="held out: pose"):
        for a, b in zip(r_good["base_from_gripper"], bumped):
            events = cal.push(a, b)
            if any("change" in e for e in events):
                changes.append(cal.last_report())
        cal.finish()
    assert len(changes) == 1 and changes[0] is None, changes
    after = cal.last_report()
    assert after is not None
    expected = x_true @ moved
    angle = np.degrees(np.arccos(np.clip((np.trace(expected[:3, :3].T @ after["matrix"][:3, :3]) - 1) / 2, -1, 1)))
    assert angle < 3 * after["uncertainty"]["rotation_deg"] + 1e-9, (angle, after["uncertainty"])


def test_verify_decides_as_the_command_line_does(tmp_path):
    # Issue 28 in Python: X saved from the first half of a recording, checked against its second
    # half (the same rig), and against the second half with the camera turned 1 degree on its mount.
    import subprocess

    lines = (TESTDATA / "kinhec" / "pairs" / "nominal_stations_eih_s0.jsonl").read_text().splitlines()
    first, second = tmp_path / "first.jsonl", tmp_path / "second.jsonl"
    first.write_text("\n".join(lines[:20]) + "\n")
    second.write_text("\n".join(lines[20:]) + "\n")
    saved = tmp_path / "x.json"
    saved.write_text(subprocess.run([str(CLI), "calibrate", str(first), "--output", "json"], check=True, capture_output=True, text=True).stdout)
    other = handeye.read_recording(second)
    same = handeye.verify(saved, other["base_from_gripper"], other["camera_from_target"])
    cli = subprocess.run([str(CLI), "verify", "--x", str(saved), str(second), "--output", "json"], capture_output=True, text=True)
    assert same["verdict"] == json.loads(cli.stdout)["verdict"] == "consistent", same["message"]
    assert cli.returncode == 0
    assert same["saved"]["matrix"].shape == (4, 4)
    # The camera turned on its mount: camera_from_target changes by the inverse turn.
    c, s_ = np.cos(np.radians(1.0)), np.sin(np.radians(1.0))
    turn = np.array([[1, 0, 0, 0], [0, c, -s_, 0], [0, s_, c, 0], [0, 0, 0, 1.0]])
    moved = np.linalg.inv(turn) @ other["camera_from_target"]
    bumped = handeye.verify(saved, other["base_from_gripper"], moved)
    assert bumped["verdict"] == "inconsistent", bumped["message"]
    assert bumped["difference"]["rotation_deg"] > 0.5
    # A new recording with its camera poses inverted: refused as misread (as the command line
    # refuses it), and with fix="camera-inverted" read back to the consistent verdict.
    inverted = np.linalg.inv(other["camera_from_target"])
    with pytest.raises(ValueError, match="camera-inverted"):
        handeye.verify(saved, other["base_from_gripper"], inverted)
    fixed = handeye.verify(saved, other["base_from_gripper"], inverted, fix="camera-inverted")
    assert fixed["verdict"] == "consistent", fixed["message"]
    assert np.allclose(fixed["difference"]["rotation_deg"], same["difference"]["rotation_deg"], atol=1e-9)
    with pytest.raises(ValueError, match="fix"):
        handeye.verify(saved, other["base_from_gripper"], inverted, fix="upside-down")


def test_the_report_says_its_verdict_as_every_face_does():
    # Issue 33 item 7: the verdict is the library's, in Python's dict as in the CLI's JSON.
    for name, verdict in [
        ("outliers_gross_stations_eih_s0.jsonl", "questionable"),
        ("nominal_stations_eih_s0.jsonl", "good"),
    ]:
        r = handeye.read_recording(TESTDATA / "kinhec" / "pairs" / name)
        report = handeye.calibrate(r["base_from_gripper"], r["camera_from_target"])
        assert report["verdict"] == verdict, name
        assert (report["verdict"] == "questionable") == bool(report["warnings"]), name


def test_the_error_at_a_chosen_point_as_the_command_line_gives_it():
    # Issue 28: `point` is `--point`: the one-sigma error of that point (camera frame) through X.
    path = TESTDATA / "kinhec" / "pairs" / "nominal_stations_eih_s0.jsonl"
    r = handeye.read_recording(path)
    near = handeye.calibrate(r["base_from_gripper"], r["camera_from_target"], point=[0.0, 0.0, 0.2])
    far = handeye.calibrate(r["base_from_gripper"], r["camera_from_target"], point=(0.0, 0.0, 2.0))
    assert near["uncertainty"]["at_point"]["point"] == [0.0, 0.0, 0.2]
    cli = _cli_json("calibrate", path, "--point", "0,0,2")
    assert np.isclose(far["uncertainty"]["at_point"]["sigma"], cli["uncertainty"]["at_point"]["sigma"], rtol=1e-9)
    # Farther from the camera, the rotation's error counts more.
    assert far["uncertainty"]["at_point"]["sigma"] > near["uncertainty"]["at_point"]["sigma"]
    with pytest.raises(ValueError, match="point"):
        handeye.calibrate(r["base_from_gripper"], r["camera_from_target"], point=[0.0, 0.0])
    with pytest.raises(ValueError, match="point"):
        handeye.calibrate(r["base_from_gripper"], r["camera_from_target"], point=[0.0, float("nan"), 1.0])


def test_joint_angles_reach_the_systematic_test_in_python_as_on_the_command_line():
    # Issue 29 across faces: a JSON Lines file's joints order the poses for the systematic-error
    # test. Python's read_recording returns them and calibrate takes them, so both faces give
    # the same verdict (without them, 21 of the 72 suite files were judged differently).
    suite = TESTDATA / "kinhec" / "systematic"
    for name in ("dh1_panda_eih_s0", "dh2_ur5e_eth_s1", "ctl_pnp_ur10_eih_s0", "dh05_ur5_eih_s0"):
        path = suite / f"{name}.jsonl"
        setup = "eye-to-hand" if "_eth_" in name else "eye-in-hand"
        r = handeye.read_recording(path, setup=setup)
        assert r["joints"] is not None and len(r["joints"]) == len(r["base_from_gripper"])
        py = handeye.calibrate(r["base_from_gripper"], r["camera_from_target"], setup=setup, joints=r["joints"])
        cli = _cli_json("calibrate", path, "--setup", setup)
        assert py["verdict"] == cli["verdict"], name
        assert py["systematic"]["flagged"] == cli["systematic"]["flagged"], name
    with pytest.raises(ValueError, match="joints"):
        handeye.calibrate(r["base_from_gripper"], r["camera_from_target"], setup=setup, joints=r["joints"][:-1])


def test_the_robots_table_reaches_the_systematic_test_in_python_as_on_the_command_line():
    # Issue 29: robot_model= is --robot-model. A 1 mm DH error of a UR10 seen from outside is
    # flagged with its table, by the table's statistic, as the command line flags it; another
    # robot's table is refused with the command line's words.
    path = TESTDATA / "kinhec" / "systematic" / "dh1_ur10_eth_s0.jsonl"
    table = TESTDATA / "kinhec" / "robots" / "ur10.json"
    r = handeye.read_recording(path, setup="eye-to-hand")
    g, c = r["base_from_gripper"], r["camera_from_target"]
    py = handeye.calibrate(g, c, setup="eye-to-hand", joints=r["joints"], robot_model=table)
    cli = _cli_json("calibrate", path, "--setup", "eye-to-hand", "--robot-model", table)
    assert py["systematic"]["flagged"] and cli["systematic"]["flagged"]
    assert py["systematic"]["kinematic"] == cli["systematic"]["kinematic"]
    assert py["systematic"]["kinematic"]["z"] < -5
    assert py["verdict"] == cli["verdict"] == "questionable"
    rw = handeye.calibrate(g, c, setup="eye-to-hand", joints=r["joints"], robot_model=str(table), robot_world=True)
    assert rw["systematic"]["kinematic"]["parameters"] > 0
    with pytest.raises(ValueError, match="does not turn the hand"):
        handeye.calibrate(g, c, setup="eye-to-hand", joints=r["joints"], robot_model=table.with_name("irb120.json"))
    with pytest.raises(ValueError, match="joint angles of every pose"):
        handeye.calibrate(g, c, setup="eye-to-hand", robot_model=table)
    # Online, the same table: the accumulating estimator's test flags as the batch does; another
    # robot's table raises at the first test.
    online = handeye.OnlineCalibrator(setup="eye-to-hand", robot_model=table)
    for k in range(len(g)):
        online.push(g[k], c[k], joints=r["joints"][k])
    end = online.finish()
    assert end["verdict"] == "questionable" and end["systematic"]["kinematic"]["z"] < -5
    wrong = handeye.OnlineCalibrator(setup="eye-to-hand", robot_model=table.with_name("irb120.json"))
    with pytest.raises(ValueError, match="does not turn the hand"):
        for k in range(len(g)):
            wrong.push(g[k], c[k], joints=r["joints"][k])
        wrong.finish()


def test_the_online_estimator_flags_a_systematic_error_as_calibrate_and_the_command_line():
    # Issue 29 in Python's OnlineCalibrator: the joints pushed with each pose order the poses for
    # the systematic-error test; the final report is questionable with the warning, its joint
    # and its widened uncertainty, as `handeye online` prints them and as `calibrate` gives them.
    path = TESTDATA / "kinhec" / "systematic" / "dh2_iiwa14_eih_s1.jsonl"
    r = handeye.read_recording(path)
    cal = handeye.OnlineCalibrator()
    for g, c, q in zip(r["base_from_gripper"], r["camera_from_target"], r["joints"]):
        cal.push(g, c, joints=q)
    end = cal.finish()
    assert end["verdict"] == "questionable"
    assert [w["code"] for w in end["warnings"]] == ["systematic_error"]
    assert end["systematic"]["configuration"] == "joints" and end["systematic"]["joint"]["joint"] == 1
    batch = handeye.calibrate(r["base_from_gripper"], r["camera_from_target"], pairs="all", joints=r["joints"])
    assert abs(end["uncertainty"]["rotation_deg"] - batch["uncertainty"]["rotation_deg"]) < 1e-9
    cli = _cli_json("online", path)
    assert cli[-1]["verdict"] == "questionable" and cli[-1]["systematic"]["joint"] == end["systematic"]["joint"]
    # Without joints the test orders by the hand pose (not flagged on this stream, as calibrate).
    plain = handeye.OnlineCalibrator()
    for g, c in zip(r["base_from_gripper"], r["camera_from_target"]):
        plain.push(g, c)
    assert plain.finish()["verdict"] == "good"
    with pytest.raises(ValueError, match="joint 2 is NaN"):
        plain.push(r["base_from_gripper"][0], r["camera_from_target"][0], joints=[0.1, float("nan")])


def test_a_low_dof_robot_takes_its_prior_in_python_as_on_the_command_line(tmp_path):
    # Issue 30 in Python: a SCARA recording (every motion about the gripper's z) is refused without
    # the camera's height, naming Python's keyword; with it, X is the command line's. The drop-in
    # has no prior and no flags: its refusal names handeye.calibrate, never a command-line flag.
    import subprocess

    path = TESTDATA / "low_dof" / "scara_eye-in-hand_s0.jsonl"
    tz = json.loads(path.with_suffix(".truth.json").read_text())["gripper_from_camera"]["translation"][2]
    r = handeye.read_recording(path)
    g, c = r["base_from_gripper"], r["camera_from_target"]
    with pytest.raises(ValueError, match='prior="tz=VALUE\\+-SIGMA"'):
        handeye.calibrate(g, c)
    given = f"tz={tz!r}+-0.001"
    result = handeye.calibrate(g, c, prior=given)
    cli = _cli_json("calibrate", path, "--prior", given)
    assert np.abs(result["matrix"] - np.array(cli["matrix"])).max() < 1e-9
    assert result["prior"] == cli["prior"] == {"tz": {"value": tz, "sigma": 0.001}}
    assert result["low_dof"]["free"] == "tz"
    # The same prior as a dict and as a list; bad ones raise with the library's words.
    for same in ({"tz": (tz, 0.001)}, [given]):
        assert np.abs(handeye.calibrate(g, c, prior=same)["matrix"] - result["matrix"]).max() < 1e-12
    for bad, says in (("rz=0.1", "tx, ty, tz"), ({"tz": (1, 2, 3)}, "value, sigma"), (5, "prior"),
                      (f"tz={tz * 1000}", "another length unit")):
        with pytest.raises(ValueError, match=says):
            handeye.calibrate(g, c, prior=bad)
    # Robot-world: the same object as `calibrate --robot-world --prior`, and the same refusal
    # without a prior.
    rw = handeye.calibrate(g, c, robot_world=True, prior=given)
    cli_rw = _cli_json("calibrate", path, "--robot-world", "--prior", given)
    assert np.abs(rw["matrix"] - np.array(cli_rw["matrix"])).max() < 1e-12
    assert np.abs(rw["target"]["matrix"] - np.array(cli_rw["target"]["matrix"])).max() < 1e-12
    assert rw["prior"] == cli_rw["prior"] == {"tz": {"value": tz, "sigma": 0.001}}
    assert rw["low_dof"] == cli_rw["low_dof"] and rw["low_dof"]["free"] == "tz"
    assert rw["uncertainty"] == cli_rw["uncertainty"]
    assert rw["target"]["uncertainty"] == cli_rw["target"]["uncertainty"]
    assert rw["matrix"][2, 3] == tz
    with pytest.raises(ValueError, match='prior="tz=VALUE\\+-SIGMA"'):
        handeye.calibrate(g, c, robot_world=True)
    with pytest.raises(ValueError, match="another length unit"):
        handeye.calibrate(g, c, robot_world=True, prior=f"tz={tz * 1000}")
    # The drop-in refuses, naming what to call instead and no flag.
    with pytest.raises(ValueError) as e:
        handeye.calibrate_hand_eye([m[:3, :3] for m in g], [m[:3, 3] for m in g],
                                   [m[:3, :3] for m in c], [m[:3, 3] for m in c], method="park")
    words = str(e.value)
    assert "handeye.calibrate(" in words and 'prior="tz=VALUE+-SIGMA"' in words, words
    assert "--" not in words, words
    # verify: the saved X's height is taken, the rest checked, as `handeye verify` does.
    saved = tmp_path / "x.json"
    saved.write_text(subprocess.run([str(CLI), "calibrate", str(path), "--prior", given, "--output", "json"],
                                    check=True, capture_output=True, text=True).stdout)
    v = handeye.verify(saved, g, c)
    assert v["verdict"] == "consistent", v["message"]
    assert any("cannot check X's tz" in n for n in v["notes"]), v["notes"]
    off = handeye.verify(saved, g, c, prior=f"tz={tz + 0.02!r}")
    assert off["verdict"] == "inconsistent", off["message"]


def test_the_drop_in_says_what_opencvs_tsai_filter_dropped():
    # Issue 33 item 19: OpenCV's Tsai constant applies its motion filter silently; the drop-in
    # gives OpenCV's X and says how many motions the filter dropped and why. The name "tsai" keeps
    # every motion, and says nothing.
    def p_norm(rot):
        return 2 * np.sin(np.arccos(np.clip((np.trace(rot) - 1) / 2, -1, 1)) / 2)

    def h(R, tv):
        m = np.eye(4)
        m[:3, :3] = R if np.shape(R) == (3, 3) else cv2.Rodrigues(np.asarray(R, dtype=np.float64))[0]
        m[:3, 3] = np.ravel(tv)
        return m

    dropping = 0
    for seed in range(8):
        Rg, tg, Rc, tc, _ = random_problem(np.random.default_rng(seed), n=10)
        args = (Rg, tg, Rc, tc)
        with warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always")
            r, t = handeye.calibrate_hand_eye(*args, method=cv2.CALIB_HAND_EYE_TSAI)
        r_cv, t_cv = cv2.calibrateHandEye(*args, method=cv2.CALIB_HAND_EYE_TSAI)
        assert np.abs(r - r_cv).max() < 1e-6 and np.abs(t - t_cv).max() < 1e-6
        # What OpenCV's filter keeps, counted from the poses as OpenCV counts it.
        g, c = [h(*p) for p in zip(Rg, tg)], [h(*p) for p in zip(Rc, tc)]
        kept = sum(1 for i in range(10) for j in range(i + 1, 10)
                   if 0.3 <= p_norm((np.linalg.inv(g[j]) @ g[i])[:3, :3]) <= 1.7
                   and 0.3 <= p_norm((c[j] @ np.linalg.inv(c[i]))[:3, :3]) <= 1.7)
        notes = [str(w.message) for w in said if "Tsai motion filter" in str(w.message)]
        if kept < 45:
            dropping += 1
            assert len(notes) == 1 and f"kept {kept} of 45 motions" in notes[0], (seed, kept, notes)
            assert 'method="tsai"' in notes[0] and "--" not in notes[0], notes[0]
        else:
            assert notes == [], (seed, notes)
        with warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always")
            handeye.calibrate_hand_eye(*args, method="tsai")
        assert not [w for w in said if "Tsai motion filter" in str(w.message)]
    assert dropping > 0, "no seed had a motion dropped: the test tests nothing"


def test_the_online_calibrator_takes_a_prior_for_a_low_dof_robot_as_the_command_line():
    # Issue 30 online: a SCARA stream gives no estimate without the camera's height (the pending
    # reason names the prior), and with it the final report is `handeye online --prior`'s.
    path = TESTDATA / "low_dof" / "scara_eye-in-hand_s0.jsonl"
    tz = json.loads(path.with_suffix(".truth.json").read_text())["gripper_from_camera"]["translation"][2]
    r = handeye.read_recording(path)
    g, c = r["base_from_gripper"], r["camera_from_target"]

    def run(**params):
        online = handeye.OnlineCalibrator(setup="eye-in-hand", **params)
        for a, b in zip(g, c):
            online.push(a, b)
        return online, online.finish()

    online, final = run()
    assert final is None
    assert "--prior tz=" in online.pending()
    given = f"tz={tz!r}+-0.001"
    _, final = run(prior=given)
    cli = _cli_json("online", path, "--setup", "eye-in-hand", "--prior", given)[-1]
    assert np.abs(final["matrix"] - np.array(cli["matrix"])).max() < 1e-12
    assert final["prior"] == cli["prior"] == {"tz": {"value": tz, "sigma": 0.001}}
    assert final["low_dof"]["free"] == "tz"
    assert final["uncertainty"]["translation"] >= 0.001
    # A prior 1000 times off is refused once the first poses tell the unit.
    with pytest.raises(ValueError, match="another length unit"):
        run(prior={"tz": tz * 1000})
    with pytest.raises(ValueError, match="accumulating estimator"):
        handeye.OnlineCalibrator(estimator="paper", prior=given)


def test_advise_takes_a_prior_and_advises_a_scara_turns_it_makes():
    """advise(..., prior=...) as `handeye advise --prior`: on a SCARA recording X's uncertainty
    includes the prior's, and the turns suggested are about the robot's one axis."""
    path = pathlib.Path(__file__).resolve().parents[3] / "testdata" / "low_dof" / "scara_eye-in-hand_s0.jsonl"
    truth = json.loads(path.with_suffix("").with_suffix(".truth.json").read_text())
    tz = truth["gripper_from_camera"]["translation"][2]
    read = handeye.read_recording(str(path))
    g, c = read["base_from_gripper"], read["camera_from_target"]
    without = handeye.advise(g, c)
    assert "--prior tz=" in without["low_dof"]
    advice = handeye.advise(g, c, prior={"tz": (tz, 0.001)})
    assert "X's tz is the prior's" in advice["low_dof"]
    assert 0.001 <= advice["current"]["translation"] < 0.005
    assert all(abs(s["axis_gripper"][2]) > 0.999 for s in advice["suggestions"])
    with pytest.raises(ValueError, match="another length unit"):
        handeye.advise(g, c, prior=f"tz={tz * 1000}")


def test_advise_says_when_the_goal_is_reached():
    """advise(..., goal=(degrees, length)) as `handeye advise --goal`: done within it, no more
    suggestions; a goal that is not two positive sizes raises."""
    q, c, _, _ = load_series("series_2007_000_200")
    now = handeye.advise(q[:40], c[:40])["current"]
    done = handeye.advise(q[:40], c[:40], goal=(now["rotation_deg"] * 1.01, now["translation"] * 1.01))
    assert done["goal"]["done"] and done["suggestions"] == []
    far = handeye.advise(q[:40], c[:40], goal=(now["rotation_deg"] * 1e-3, now["translation"] * 1e-3))
    assert not far["goal"]["done"] and far["goal"]["after"] is None and len(far["suggestions"]) == 3
    for bad in [(0.0, 1.0), (1.0,), (float("nan"), 1.0)]:
        with pytest.raises(ValueError, match="goal"):
            handeye.advise(q[:40], c[:40], goal=bad)
