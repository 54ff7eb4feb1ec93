//! Recordings on the pixels: a robot that shows a planar target (a chessboard or one square tag)
//! to a camera with distortion from varied viewpoints; detections with pixel noise (and, on
//! request, mis-detected corners), robot poses with their own noise.
//!
//! Lengths are metres. Every recording draws from its own generator seeded by `seed`, so tests,
//! benches and the committed test data are reproducible.

use nalgebra::{Matrix3, Point3, Vector2, Vector3};
use rand::{Rng, RngExt};
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use crate::model::camera::{Detections, Frame, Intrinsics};
use crate::model::motion::Setup;
use crate::model::pose::{Transform, exp_so3, transform_from_parts};
use crate::sim::series_rng;

/// The target.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Target {
    /// A chessboard's inner corners: `cols` × `rows`, `square` apart, the origin at the first
    /// corner (OpenCV's convention).
    Board {
        /// Corners along x.
        cols: usize,
        /// Corners along y.
        rows: usize,
        /// Square size, metres.
        square: f64,
    },
    /// One square marker's 4 corners, `size` wide, the origin at its centre (ArUco's convention).
    Tag {
        /// Side length, metres.
        size: f64,
    },
}

impl Target {
    /// The target's points, target frame.
    pub fn points(&self) -> Vec<[f64; 3]> {
        match *self {
            Target::Board { cols, rows, square } => (0..rows)
                .flat_map(|j| (0..cols).map(move |i| [i as f64 * square, j as f64 * square, 0.0]))
                .collect(),
            Target::Tag { size } => {
                let h = size / 2.0;
                vec![[-h, h, 0.0], [h, h, 0.0], [h, -h, 0.0], [-h, -h, 0.0]]
            }
        }
    }

    /// The target's centre, target frame.
    pub fn centre(&self) -> Vector3<f64> {
        let p = self.points();
        p.iter()
            .fold(Vector3::zeros(), |a, q| a + Vector3::from(*q))
            / p.len() as f64
    }
}

/// A simulated recording's parameters; the constructors give the issue's two cases.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PixelSimConfig {
    /// Frames. 30 in both constructors.
    pub frames: usize,
    /// The target.
    pub target: Target,
    /// Range of the camera's distance to the target's centre, metres.
    pub distance: (f64, f64),
    /// Largest angle between the line of sight and the target's normal, degrees. 40.
    pub tilt_deg: f64,
    /// The camera.
    pub intrinsics: Intrinsics,
    /// Range of the detection noise's sigma per coordinate, pixels (one sigma drawn per
    /// recording). (0.5, 1).
    pub pixel_noise: (f64, f64),
    /// Robot translation noise, metres (sigma per axis). 0.2 mm.
    pub robot_translation_noise: f64,
    /// Robot rotation noise, radians (sigma per axis). 0.2 mrad.
    pub robot_rotation_noise: f64,
    /// Detections moved 20–60 pixels off (mis-detections), in all.
    pub outliers: usize,
    /// The setup.
    pub setup: Setup,
    /// Where in the image the target's centre is placed: uniformly within this fraction of the
    /// image's half-width and half-height around the principal point (the camera turned about its
    /// centre), frames that leave the image drawn again. 0 in both constructors: the camera aims
    /// at the target's centre (within 3 cm); [`PixelSimConfig::spanning`] gives 0.75, frames that
    /// reach the image's corners (what refining the intrinsics needs).
    #[serde(default)]
    pub spread: f64,
}

/// Realistic intrinsics: 1280×720, f ≈ 900 px, barrel distortion.
fn realistic_intrinsics() -> Intrinsics {
    Intrinsics {
        fx: 905.0,
        fy: 903.5,
        cx: 641.2,
        cy: 358.7,
        distortion: [-0.21, 0.09, 0.0007, -0.0004, -0.015],
        width: 1280,
        height: 720,
    }
}

impl PixelSimConfig {
    /// A 9×6 chessboard of 25 mm squares at 0.35–0.6 m, eye-in-hand.
    pub fn board() -> Self {
        Self {
            frames: 30,
            target: Target::Board {
                cols: 9,
                rows: 6,
                square: 0.025,
            },
            distance: (0.35, 0.6),
            tilt_deg: 40.0,
            intrinsics: realistic_intrinsics(),
            pixel_noise: (0.5, 1.0),
            robot_translation_noise: 2e-4,
            robot_rotation_noise: 2e-4,
            outliers: 0,
            setup: Setup::EyeInHand,
            spread: 0.0,
        }
    }

    /// One 6 cm square tag (its 4 corners) at 0.5–0.9 m, eye-in-hand.
    pub fn tag() -> Self {
        Self {
            target: Target::Tag { size: 0.06 },
            distance: (0.5, 0.9),
            ..Self::board()
        }
    }

    /// The same without any noise.
    pub fn noise_free(self) -> Self {
        Self {
            pixel_noise: (0.0, 0.0),
            robot_translation_noise: 0.0,
            robot_rotation_noise: 0.0,
            outliers: 0,
            ..self
        }
    }

    /// The same with the target's centre anywhere in the central 75 % of the image (`spread`
    /// 0.75): frames that reach the image's corners.
    pub fn spanning(self) -> Self {
        Self {
            spread: 0.75,
            ..self
        }
    }

    /// The same in another setup.
    pub fn with_setup(self, setup: Setup) -> Self {
        Self { setup, ..self }
    }
}

/// A simulated recording and its truth.
#[derive(Debug, Clone, PartialEq)]
pub struct PixelSim {
    /// The frames: noisy robot poses, noisy detections, no camera pose.
    pub frames: Vec<Frame>,
    /// The camera.
    pub intrinsics: Intrinsics,
    /// The setup.
    pub setup: Setup,
    /// The true X (`gripper_from_camera` or `base_from_camera`).
    pub x: Transform,
    /// The true Y (`base_from_target` or `gripper_from_target`).
    pub y: Transform,
    /// The detection noise's sigma, pixels.
    pub pixel_sigma: f64,
    /// The mis-detections, (frame, point) each.
    pub outliers: Vec<(usize, usize)>,
}

/// Image margin kept free of detections, pixels.
const MARGIN_PX: f64 = 20.0;

/// Simulates a recording (see the module docs).
///
/// # Example
/// ```
/// use handeye::sim::pixels::{PixelSimConfig, simulate_pixels};
/// let a = simulate_pixels(&PixelSimConfig::tag(), 1);
/// assert_eq!(a.frames.len(), 30);
/// assert_eq!(a.frames[0].detections.pixels.len(), 4);
/// assert_eq!(a, simulate_pixels(&PixelSimConfig::tag(), 1));
/// ```
pub fn simulate_pixels(config: &PixelSimConfig, seed: u64) -> PixelSim {
    let mut rng = series_rng(seed, 0x5049_5845);
    let camera = config.intrinsics;
    let points = config.target.points();
    let centre = config.target.centre();
    // X: a camera a few centimetres off the flange (eye-in-hand), or a metre from the robot's
    // base looking at its workspace (eye-to-hand); Y the other way round.
    let small = |rng: &mut _, angle: f64, offset: Vector3<f64>| {
        transform_from_parts(
            &exp_so3(&gaussian(rng, angle)),
            &(offset + gaussian(rng, 0.01)),
        )
    };
    let (x, y) = match config.setup {
        Setup::EyeInHand => (
            small(&mut rng, 0.3, Vector3::new(0.04, -0.03, 0.08)),
            transform_from_parts(
                &exp_so3(&(Vector3::new(std::f64::consts::PI, 0.0, 0.0) + gaussian(&mut rng, 0.1))),
                &Vector3::new(0.6, 0.05, 0.0),
            ),
        ),
        Setup::EyeToHand => (
            transform_from_parts(
                &exp_so3(&(Vector3::new(-2.0, 0.0, 0.0) + gaussian(&mut rng, 0.1))),
                &Vector3::new(1.1, 0.1, 0.6),
            ),
            small(&mut rng, 0.3, Vector3::new(0.02, 0.0, 0.12)),
        ),
    };
    let pixel_sigma = if config.pixel_noise.1 > config.pixel_noise.0 {
        rng.random_range(config.pixel_noise.0..config.pixel_noise.1)
    } else {
        config.pixel_noise.0
    };
    let mut frames = Vec::with_capacity(config.frames);
    while frames.len() < config.frames {
        let camera_from_target = view(&mut rng, config, &centre);
        let true_pixels: Option<Vec<Vector2<f64>>> = points
            .iter()
            .map(|p| {
                let q = camera_from_target * Point3::from(*p);
                let u = camera.project(&q.coords)?.pixel;
                inside(&camera, &u).then_some(u)
            })
            .collect();
        let Some(true_pixels) = true_pixels else {
            continue;
        };
        // C = X⁻¹ M Y: M = X C Y⁻¹; Q = M⁻¹ eye-in-hand, M eye-to-hand.
        let m = x * camera_from_target * y.inverse();
        let q = match config.setup {
            Setup::EyeInHand => m.inverse(),
            Setup::EyeToHand => m,
        };
        let noisy_q = q * transform_from_parts(
            &exp_so3(&gaussian(&mut rng, config.robot_rotation_noise)),
            &gaussian(&mut rng, config.robot_translation_noise),
        );
        let pixels = true_pixels
            .iter()
            .map(|u| {
                let n = Vector2::new(normal(&mut rng), normal(&mut rng)) * pixel_sigma;
                [u.x + n.x, u.y + n.y]
            })
            .collect();
        frames.push(Frame {
            base_from_gripper: noisy_q,
            camera_from_target: None,
            detections: Detections {
                target: points.clone(),
                pixels,
            },
        });
    }
    let mut outliers = Vec::with_capacity(config.outliers);
    while outliers.len() < config.outliers.min(frames.len() * points.len()) {
        let f = rng.random_range(0..frames.len());
        let k = rng.random_range(0..points.len());
        if outliers.contains(&(f, k)) {
            continue;
        }
        let angle: f64 = rng.random_range(0.0..std::f64::consts::TAU);
        let size: f64 = rng.random_range(20.0..60.0);
        let p = &mut frames[f].detections.pixels[k];
        p[0] += size * angle.cos();
        p[1] += size * angle.sin();
        outliers.push((f, k));
    }
    PixelSim {
        frames,
        intrinsics: camera,
        setup: config.setup,
        x,
        y,
        pixel_sigma,
        outliers,
    }
}

/// A camera pose that sees the target's centre from `distance`, within `tilt_deg` of its normal,
/// rolled at random and aimed a little off the centre.
fn view(rng: &mut impl Rng, config: &PixelSimConfig, centre: &Vector3<f64>) -> Transform {
    let tilt = config.tilt_deg.to_radians() * rng.random_range(0.0_f64..1.0).sqrt();
    let azimuth = rng.random_range(0.0..std::f64::consts::TAU);
    let d = rng.random_range(config.distance.0..config.distance.1);
    // The camera's position in the target frame, on the +z side (the target's front).
    let dir = Vector3::new(
        tilt.sin() * azimuth.cos(),
        tilt.sin() * azimuth.sin(),
        tilt.cos(),
    );
    let eye = centre + dir * d;
    let aim = centre + gaussian(rng, 0.03).component_mul(&Vector3::new(1.0, 1.0, 0.0));
    let z = (aim - eye).normalize();
    let roll = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
    let helper = if z.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let x0 = helper.cross(&z).normalize();
    let y0 = z.cross(&x0);
    let (s, c) = roll.sin_cos();
    let xa = x0 * c + y0 * s;
    let ya = z.cross(&xa);
    // target_from_camera: columns are the camera's axes in the target frame.
    let r = Matrix3::from_columns(&[xa, ya, z]);
    let camera_from_target = transform_from_parts(&r, &eye).inverse();
    if config.spread <= 0.0 {
        return camera_from_target;
    }
    // Turn the camera about its centre so that the target's centre is seen at a pixel drawn
    // within `spread` of the image's half-size.
    let c = &config.intrinsics;
    let (w, h) = (f64::from(c.width), f64::from(c.height));
    let pixel = Vector2::new(
        c.cx + rng.random_range(-config.spread..config.spread) * w / 2.0,
        c.cy + rng.random_range(-config.spread..config.spread) * h / 2.0,
    );
    let xy = c.normalised(&pixel);
    let ray = Vector3::new(xy.x, xy.y, 1.0).normalize();
    let seen = (camera_from_target * Point3::from(*centre))
        .coords
        .normalize();
    let turn = nalgebra::Rotation3::rotation_between(&seen, &ray)
        .map_or_else(Matrix3::identity, |r| *r.matrix());
    transform_from_parts(&turn, &Vector3::zeros()) * camera_from_target
}

fn inside(camera: &Intrinsics, u: &Vector2<f64>) -> bool {
    let (w, h) = (f64::from(camera.width), f64::from(camera.height));
    u.x >= MARGIN_PX && u.y >= MARGIN_PX && u.x <= w - MARGIN_PX && u.y <= h - MARGIN_PX
}

fn normal(rng: &mut impl Rng) -> f64 {
    StandardNormal.sample(rng)
}

fn gaussian(rng: &mut impl Rng, sigma: f64) -> Vector3<f64> {
    Vector3::new(normal(rng), normal(rng), normal(rng)) * sigma
}
