//! Writes the simulated recordings on the pixels of `testdata/pixels` (issue 35):
//! `cargo run --release -p handeye --example pixel_recording -- testdata/pixels`
//!
//! `tag_eih`: one 6 cm tag (4 corners) at 0.5–0.9 m, eye-in-hand, seed 1, with each frame's
//! PnP pose (the smaller-residual pose of the planar ambiguity: flips included) and 3 corners
//! mis-detected. `board_eth`: a 9×6 board of 25 mm squares at 0.35–0.6 m, eye-to-hand, seed 2,
//! detections only. Both: 30 frames, 1280×720 intrinsics with distortion, pixel noise 0.5–1 px,
//! robot noise 0.2 mm / 0.2 mrad; metres. `board_span_eih`: the board eye-in-hand, seed 3, its
//! centre anywhere in the central 75 % of the image (`PixelSimConfig::spanning`: frames that reach
//! the image's corners), detections only, with `board_span_eih.wrong.intrinsics.yml` beside the
//! true intrinsics: fx 2.5 % long, fy 2.5 % short, cx 8 px and cy −6 px off, k1 off by 0.04 (for
//! `--refine-intrinsics`).

use std::fmt::Write as _;

use handeye::sim::pixels::{PixelSimConfig, simulate_pixels};
use handeye::{Intrinsics, Setup, Transform, planar_poses};
use nalgebra::{Vector2, Vector3};

fn pose(t: &Transform) -> String {
    let q = handeye::quaternion_xyzw(t);
    let v = t.translation.vector;
    format!(
        "{{\"translation\": [{:.9}, {:.9}, {:.9}], \"quaternion_xyzw\": [{:.12}, {:.12}, {:.12}, {:.12}]}}",
        v.x, v.y, v.z, q[0], q[1], q[2], q[3]
    )
}

fn yaml(k: &Intrinsics) -> String {
    let d = k.distortion;
    format!(
        "%YAML:1.0\n---\nimage_width: {}\nimage_height: {}\ncamera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [ {}, 0., {}, 0., {}, {}, 0., 0., 1. ]\ndistortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n   data: [ {}, {}, {}, {}, {} ]\n",
        k.width, k.height, k.fx, k.cx, k.fy, k.cy, d[0], d[1], d[2], d[3], d[4]
    )
}

fn main() -> std::io::Result<()> {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "testdata/pixels".into());
    let cases = [
        (
            "tag_eih",
            PixelSimConfig {
                outliers: 3,
                ..PixelSimConfig::tag()
            },
            1,
            true,
        ),
        (
            "board_eth",
            PixelSimConfig::board().with_setup(Setup::EyeToHand),
            2,
            false,
        ),
        (
            "board_span_eih",
            PixelSimConfig::board().spanning(),
            3,
            false,
        ),
    ];
    for (name, config, seed, with_pnp) in cases {
        let sim = simulate_pixels(&config, seed);
        let mut out = String::new();
        for f in &sim.frames {
            let d = &f.detections;
            let target: Vec<String> = d
                .target
                .iter()
                .map(|p| format!("[{}, {}, {}]", p[0], p[1], p[2]))
                .collect();
            let pixels: Vec<String> = d
                .pixels
                .iter()
                .map(|p| format!("[{:.4}, {:.4}]", p[0], p[1]))
                .collect();
            let camera = if with_pnp {
                let points: Vec<Vector3<f64>> =
                    d.target.iter().map(|p| Vector3::from(*p)).collect();
                let px: Vec<Vector2<f64>> = d.pixels.iter().map(|p| Vector2::from(*p)).collect();
                let best = planar_poses(&points, &px, &sim.intrinsics)
                    .expect("a planar target")
                    .into_iter()
                    .min_by(|a, b| a.1.total_cmp(&b.1))
                    .expect("two poses")
                    .0;
                format!(", \"camera_from_target\": {}", pose(&best))
            } else {
                String::new()
            };
            let _ = writeln!(
                out,
                "{{\"base_from_gripper\": {}{camera}, \"detections\": {{\"target\": [{}], \"pixels\": [{}]}}}}",
                pose(&f.base_from_gripper),
                target.join(", "),
                pixels.join(", ")
            );
        }
        std::fs::write(format!("{dir}/{name}.jsonl"), out)?;
        std::fs::write(
            format!("{dir}/{name}.intrinsics.yml"),
            yaml(&sim.intrinsics),
        )?;
        if name == "board_span_eih" {
            let mut wrong = sim.intrinsics;
            wrong.fx *= 1.025;
            wrong.fy *= 0.975;
            wrong.cx += 8.0;
            wrong.cy -= 6.0;
            wrong.distortion[0] += 0.04;
            std::fs::write(format!("{dir}/{name}.wrong.intrinsics.yml"), yaml(&wrong))?;
        }
        let (x_name, y_name) = match sim.setup {
            Setup::EyeInHand => ("gripper_from_camera", "base_from_target"),
            Setup::EyeToHand => ("base_from_camera", "gripper_from_target"),
        };
        std::fs::write(
            format!("{dir}/{name}.truth.json"),
            format!(
                "{{\"{x_name}\": {}, \"{y_name}\": {}, \"pixel_sigma\": {}, \"outliers\": {:?}}}\n",
                pose(&sim.x),
                pose(&sim.y),
                sim.pixel_sigma,
                sim.outliers
                    .iter()
                    .map(|(f, k)| [*f, *k])
                    .collect::<Vec<_>>()
            ),
        )?;
    }
    Ok(())
}
