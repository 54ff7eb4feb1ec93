//! Writes the simulated low-DOF recordings of `testdata/low_dof` (JSON Lines pose pairs and a
//! `.truth.json` beside each) from `sim::simulate_low_dof`: a SCARA eye-in-hand and eye-to-hand,
//! and a gantry whose one wrist joint turns about an axis 30° off the flange's z.
//!
//! `cargo run --release -p handeye --example low_dof_recordings -- testdata/low_dof`

use std::fmt::Write as _;
use std::path::PathBuf;

use handeye::sim::{LowDofConfig, simulate_low_dof};
use handeye::{Setup, Transform, quaternion_xyzw};

fn json(t: &Transform) -> String {
    let v = t.translation.vector;
    let q = quaternion_xyzw(t);
    format!(
        "{{\"translation\": [{:.12}, {:.12}, {:.12}], \"quaternion_xyzw\": [{:.12}, {:.12}, {:.12}, {:.12}]}}",
        v.x, v.y, v.z, q[0], q[1], q[2], q[3]
    )
}

fn main() -> std::io::Result<()> {
    let dir = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "testdata/low_dof".into()),
    );
    std::fs::create_dir_all(&dir)?;
    let tilt = 30f64.to_radians();
    let recordings = [
        ("scara_eye-in-hand_s0", Setup::EyeInHand, [0.0, 0.0, 1.0], 0),
        ("scara_eye-to-hand_s1", Setup::EyeToHand, [0.0, 0.0, 1.0], 1),
        (
            "tilted_wrist_eye-in-hand_s2",
            Setup::EyeInHand,
            [0.0, -tilt.sin(), tilt.cos()],
            2,
        ),
    ];
    for (name, setup, axis, seed) in recordings {
        let config = LowDofConfig {
            setup,
            axis,
            ..LowDofConfig::default()
        };
        let s = simulate_low_dof(&config, seed, 0);
        let mut lines = String::new();
        for p in &s.poses {
            let _ = writeln!(
                lines,
                "{{\"base_from_gripper\": {}, \"camera_from_target\": {}}}",
                json(&p.base_from_gripper),
                json(&p.camera_from_target)
            );
        }
        std::fs::write(dir.join(format!("{name}.jsonl")), lines)?;
        let (x_name, fixed_name) = match setup {
            Setup::EyeInHand => ("gripper_from_camera", "base_from_target"),
            Setup::EyeToHand => ("base_from_camera", "gripper_from_target"),
        };
        let truth = format!(
            "{{\"{x_name}\": {}, \"{fixed_name}\": {}, \"setup\": \"{}\", \"axis\": [{:.12}, {:.12}, {:.12}], \"seed\": {seed}}}\n",
            json(&s.x),
            json(&s.fixed),
            setup.name(),
            axis[0],
            axis[1],
            axis[2]
        );
        std::fs::write(dir.join(format!("{name}.truth.json")), truth)?;
        println!("{name}: {} poses", s.poses.len());
    }
    Ok(())
}
