//! Which joint the residual follows, against truth (issue 29): `testdata/kinhec/joint` (made by
//! `testdata/kinhec/generate_joint.py` with kinhec 1.1.0) holds recordings of four robots in both
//! setups in which exactly one middle joint's zero offset (0.3°) or link length (2 mm) is wrong.
//!
//! `cargo test --release -p handeye --test systematic_joint -- --nocapture` prints the table.
//!
//! Measured (2026-12-05, `calibrate`'s default): 29 of 56 recordings flagged (offsets 27 of 36,
//! link lengths 2 of 20); `systematic.joint` names the wrong joint in 4 of the 29 flagged, 8 of
//! 56 in all: no better than naming one of six or seven at random. A joint's zero-offset error
//! turns the arm beyond it about the joint's own axis, so its effect does not change as that
//! joint turns: it follows the angles of the joints before it (eye-in-hand, the residual in the
//! base's frame) or after it (eye-to-hand, in the flange's). Naming the wrong parameter needs the
//! robot's kinematic model (the identification Jacobian), which the recordings do not give; the
//! field says which angle the residual follows, not which joint is wrong. The floors below are
//! the measured counts, so that a change that loses detection is seen.

use std::path::{Path, PathBuf};

use handeye::io::{Format, read_joints, read_pose_file};
use handeye::{Options, calibrate};
use handeye::{Setup, Warning};
use serde_json::Value;

fn suite() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata/kinhec")
}

#[test]
fn the_joint_named_against_the_one_made_wrong() {
    let text = std::fs::read_to_string(suite().join("joint/manifest.json")).unwrap();
    let manifest: Value = serde_json::from_str(&text).unwrap();
    let (mut runs, mut flagged, mut offsets_flagged, mut right, mut right_flagged) =
        (0, 0, 0, 0, 0);
    for e in manifest["files"].as_array().unwrap() {
        let file = e["file"].as_str().unwrap();
        let setup = if e["setup"] == "eye-to-hand" {
            Setup::EyeToHand
        } else {
            Setup::EyeInHand
        };
        let series = read_pose_file(&suite().join(file), Format::Auto).unwrap();
        let joints = read_joints(&std::fs::read_to_string(suite().join(file)).unwrap(), file)
            .unwrap()
            .unwrap();
        assert_eq!(joints.len(), series.pairs.len(), "{file}");
        let r = calibrate(
            &series.pairs,
            setup,
            &Options {
                joints,
                ..Options::default()
            },
        )
        .map(|r| r.into_hand_eye().expect("the hand–eye report"))
        .unwrap_or_else(|err| panic!("{file}: refused: {err}"));
        let s = r.systematic.as_ref().expect("tested");
        assert_eq!(s.configuration, "joints", "{file}");
        let named = s.joint.map(|j| j.joint);
        let wrong = e["wrong_joint"].as_u64().unwrap() as usize;
        let warned = r
            .warnings
            .iter()
            .any(|w| matches!(w, Warning::SystematicError { .. }));
        runs += 1;
        flagged += usize::from(warned);
        offsets_flagged += usize::from(warned && e["kind"] == "offset");
        right += usize::from(named == Some(wrong));
        right_flagged += usize::from(warned && named == Some(wrong));
        println!(
            "{file:<34} wrong joint {wrong}  flagged {warned:<5} p {:.1e}  named {named:?}",
            s.p_value
        );
    }
    println!(
        "{runs} recordings: flagged {flagged} (zero offsets {offsets_flagged}); the wrong joint named in {right_flagged} of the flagged, {right} of all"
    );
    assert_eq!(runs, 56);
    assert!(
        flagged >= 27 && offsets_flagged >= 24,
        "{flagged}, {offsets_flagged}"
    );
}
