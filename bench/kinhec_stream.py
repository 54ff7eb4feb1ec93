"""A long realistic stream for `handeye online -`'s throughput: kinhec (MIT) simulates a UR10e
eye-in-hand moving by joint sinusoids, seen by an HD camera at 30 Hz with the suite's nominal robot
and PnP noise (testdata/kinhec/generate.py's recipes), printed as handeye's JSON Lines with ten
significant digits, as kinhec's own recordings are. Frames where the target is out of view are left
out, as a detector would. Not part of CI (about 75 s for 6,000 s of motion, about 100,000 poses).

    python bench/kinhec_stream.py SECONDS OUT.jsonl   (needs kinhec==1.1.0, numpy, scipy, pandas)

Writes OUT.jsonl and OUT.truth.json (the true X and target pose, as testdata's truth files).
"""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "testdata" / "kinhec"))
import generate as suite  # noqa: E402  (the suite's recipes and writers)


def main():
    seconds, out = float(sys.argv[1]), Path(sys.argv[2])
    cfg = suite.make_cfg(
        f"throughput_30hz_eih_{int(seconds)}s",
        robot="ur10e",
        setup="eih",
        family="joint_sinusoid",
        fp=suite.TEMPORAL_EXCITATION,
        sampling=suite.continuous(seconds, 30, "synchronous"),
        rn=suite.robot_noise(),
        cn=suite.camera_noise(),
    )
    manifest, robot, camera, _ = suite.run_cfg(cfg.to_dict())
    base_from_gripper = suite.poses(robot, "base_ee_meas")
    camera_from_target = suite.poses(camera, "cam_target_meas")
    finite = np.isfinite(camera_from_target).all(axis=(1, 2)) & np.isfinite(base_from_gripper).all(axis=(1, 2))
    keep = np.flatnonzero(finite & camera["visible"].to_numpy())
    stamps = camera["t"].to_numpy()
    with out.open("w") as f:
        for i in keep:
            f.write(suite.record_line(stamps[i], base_from_gripper[i], camera_from_target[i], "matrix") + "\n")
    x, y = suite.kinhec_xy(manifest)
    suite.write_truth(out.with_suffix(".truth.json"), *suite.handeye_truth("eih", x, y))
    print(f"{out}: {len(keep)} poses of {len(camera)} frames (target in view)", file=sys.stderr)


if __name__ == "__main__":
    main()
