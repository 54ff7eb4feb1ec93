//! The bundle with the intrinsics free (`refine_intrinsics`): X, Y and fx, fy, cx, cy, k1, k2, p1,
//! p2 on every frame's pixels, after the checks that the frames determine the intrinsics.
//!
//! k3 is held at the given value: over a frame that spans the image its column r⁶ is nearly
//! r⁴ (k2's), so the two trade against each other and k3 comes out with a sigma larger than
//! itself, and frees k2's sigma five-fold (measured in the test `k3_is_not_determined_beside_k2`).
//!
//! The determination of the intrinsics is checked before the solve, on the detections and the
//! start poses: more than 20 frames, at least 9 detections in a frame (median: a frame's points
//! must show the lens's curvature), detections in each corner cell of a 3×3 grid over the image
//! (the corners are where the principal point and the distortion show), and views tilted about
//! both image axes (views square to the line of sight trade focal length for distance in the
//! camera's own data; here the robot's motion would still tell them apart, through its
//! kinematics, whose errors would then go into the intrinsics). After the solve, the sigmas: fx,
//! fy within 2 % of themselves, cx, cy within 5 % of the image's size.
//!
//! # References
//! Z. Zhang, "A flexible new technique for camera calibration", IEEE PAMI 22(11), 2000 (sec. 5:
//! views must not be parallel); K. H. Strobl, G. Hirzinger, "More accurate pinhole camera
//! calibration with imperfect planar target", ICCV workshops 2011.

use nalgebra::{Matrix6, SMatrix, SVector, Vector2, Vector3};
use serde::{Deserialize, Serialize};

use super::{
    BEHIND_PX, Data, INLIER_FLOOR_PX, INLIER_SIGMAS, Loss, State, robust_sigma, station_meat,
};
use crate::model::camera::{Frame, Intrinsics};
use crate::model::error::{Error, Result};
use crate::model::pose::{Transform, exp_so3, proj_so3};
use crate::solve::lm::{
    LeastSquares, Linearisation, RefineOptions, Termination, levenberg_marquardt,
};

/// The intrinsic parameters refined: fx, fy, cx, cy, k1, k2, p1, p2.
const FREE: usize = 8;
/// X's 6, Y's 6 and the intrinsics'.
const ALL: usize = 12 + FREE;

/// The corner cells of a 3×3 grid over the image that must hold detections.
const CORNER_CELLS: usize = 4;
/// The least RMS tilt of the target about the less tilted of the two image axes, degrees.
pub(crate) const MIN_TILT_DEG: f64 = 8.0;
/// The least median number of detections per frame: a frame's points must show the lens's
/// curvature (the 4 corners of one tag fit a homography exactly, whatever the distortion).
const MIN_POINTS_PER_FRAME: usize = 9;
/// The largest sigma of a focal length, relative to it, taken as determined.
const MAX_FOCAL_SIGMA: f64 = 0.02;
/// The largest sigma of the principal point, relative to the image's size, taken as determined.
const MAX_CENTRE_SIGMA: f64 = 0.05;

/// The intrinsics refined with X (`refine_intrinsics`), in the report's `intrinsics`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RefinedIntrinsics {
    /// Focal length along u, pixels.
    pub fx: f64,
    /// Focal length along v, pixels.
    pub fy: f64,
    /// Principal point u, pixels.
    pub cx: f64,
    /// Principal point v, pixels.
    pub cy: f64,
    /// Distortion k1, k2, p1, p2, k3 (OpenCV's order); k3 is the given one.
    pub distortion: [f64; 5],
    /// One sigma of each, from the same covariance as X's.
    pub sigma: IntrinsicsSigma,
    /// The coefficients held at the given value: `k3` (see the decision in docs/DECISIONS.md).
    pub held: Vec<String>,
    /// Corner cells of a 3×3 grid over the image that hold detections (4 are needed).
    pub corner_cells: usize,
    /// RMS tilt of the target about the less tilted image axis, degrees.
    pub tilt_deg: f64,
}

/// One sigma of each refined intrinsic parameter; `null` (`None`) for a coefficient held.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IntrinsicsSigma {
    /// fx, pixels.
    pub fx: f64,
    /// fy, pixels.
    pub fy: f64,
    /// cx, pixels.
    pub cx: f64,
    /// cy, pixels.
    pub cy: f64,
    /// k1, k2, p1, p2, k3.
    pub distortion: [Option<f64>; 5],
}

/// What the frames show of the image: corner cells hit, RMS tilt about the weaker axis.
pub(super) struct Span {
    corner_cells: usize,
    tilt_deg: f64,
}

fn refuse(message: String) -> Error {
    Error::InvalidParameter {
        name: "refine_intrinsics",
        message,
    }
}

/// The image's width and height, pixels: twice the principal point's where the intrinsics do not
/// give them.
fn image_size(camera: &Intrinsics) -> (f64, f64) {
    if camera.width > 0 && camera.height > 0 {
        (f64::from(camera.width), f64::from(camera.height))
    } else {
        (2.0 * camera.cx, 2.0 * camera.cy)
    }
}

/// The frames determine the intrinsics only when they reach the image's corners and tilt the
/// target about two axes; refuses otherwise, saying what is missing and what to do.
pub(super) fn check_span(
    frames: &[Frame],
    camera: &Intrinsics,
    poses: &[Transform],
) -> Result<Span> {
    if frames.len() <= ALL {
        return Err(refuse(format!(
            "{} frames: refining the intrinsics needs more than {ALL} (X's and the target's 12 parameters and {FREE} intrinsic ones); record more frames",
            frames.len()
        )));
    }
    let (w, h) = image_size(camera);
    let mut hit = [false; CORNER_CELLS];
    // The detections a camera could have made (a pixel beyond is left out of the fit too).
    let seen = frames.iter().flat_map(|f| &f.detections.pixels);
    for u in seen.filter(|u| camera.could_see(u)) {
        let (i, j) = ((3.0 * u[0] / w).floor(), (3.0 * u[1] / h).floor());
        let corner = match (i as i64, j as i64) {
            (0, 0) => Some(0),
            (2, 0) => Some(1),
            (0, 2) => Some(2),
            (2, 2) => Some(3),
            _ => None,
        };
        if let Some(c) = corner {
            hit[c] = true;
        }
    }
    let corner_cells = hit.iter().filter(|h| **h).count();
    // The target's normal in the camera, per frame: its (x, y) spread about both image axes.
    let mut s = nalgebra::Matrix2::<f64>::zeros();
    for p in poses {
        let n = p.rotation.matrix().column(2).into_owned();
        let n = if n.z < 0.0 { -n } else { n };
        let v = Vector2::new(n.x, n.y);
        s += v * v.transpose();
    }
    s /= poses.len().max(1) as f64;
    let weaker = s.symmetric_eigenvalues().min().max(0.0).sqrt().min(1.0);
    let tilt_deg = weaker.asin().to_degrees();
    let mut counts: Vec<usize> = frames.iter().map(|f| f.detections.pixels.len()).collect();
    counts.sort_unstable();
    let points = counts[counts.len() / 2];
    let words = [
        (points < MIN_POINTS_PER_FRAME).then(|| {
            format!(
                "a frame has {points} detections (median), at least {MIN_POINTS_PER_FRAME} needed: the points of a frame must show the lens's curvature (the 4 corners of one tag fit any distortion), use a board (a chessboard, a ChArUco board or a grid of tags)"
            )
        }),
        (corner_cells < CORNER_CELLS).then(|| {
            format!(
                "the detections reach {corner_cells} of the image's 4 corner cells (a 3×3 grid): cover the corners of the image with the target"
            )
        }),
        (tilt_deg < MIN_TILT_DEG).then(|| {
            format!(
                "the target tilts {tilt_deg:.1}° (RMS, about the less tilted image axis), at least {MIN_TILT_DEG}° needed: tilt the target towards and away from the camera about both image axes (views square to the camera trade focal length for distance)"
            )
        }),
    ];
    let missing: Vec<String> = words.into_iter().flatten().collect();
    if !missing.is_empty() {
        return Err(refuse(format!(
            "the frames do not determine the intrinsics: {}; or calibrate with the given intrinsics (without --refine-intrinsics)",
            missing.join("; ")
        )));
    }
    Ok(Span {
        corner_cells,
        tilt_deg,
    })
}

/// Refuses refined intrinsics whose sigmas say the pixels do not determine them: fx, fy beyond
/// 2 % of themselves, cx, cy beyond 5 % of the image's size. Called by the jobs after their check
/// that the fit reaches detection noise (a fit far above it, a target in another unit, says so
/// first).
pub(crate) fn check_determined(k: &RefinedIntrinsics, given: &Intrinsics) -> Result<()> {
    let (w, h) = image_size(given);
    let g = &k.sigma;
    let spreads = [
        ("fx", g.fx / k.fx, MAX_FOCAL_SIGMA),
        ("fy", g.fy / k.fy, MAX_FOCAL_SIGMA),
        ("cx", g.cx / w, MAX_CENTRE_SIGMA),
        ("cy", g.cy / h, MAX_CENTRE_SIGMA),
    ];
    if let Some((name, v, most)) = spreads
        .iter()
        .find(|(_, v, most)| v.is_nan() || v.abs() > *most)
    {
        return Err(refuse(format!(
            "the pixels do not determine the intrinsics: {name}'s sigma is {:.2} % of {}, at most {:.0} % taken: tilt the target more, cover the corners of the image, record more frames; or calibrate with the given intrinsics (without --refine-intrinsics)",
            100.0 * v,
            if name.starts_with('f') {
                "itself"
            } else {
                "the image"
            },
            100.0 * most
        )));
    }
    Ok(())
}

/// X, Y and the camera.
type Full = (State, Intrinsics);

/// The result of [`refine`].
pub(super) struct Refined {
    pub(super) state: State,
    pub(super) camera: Intrinsics,
    pub(super) keep: Vec<bool>,
    pub(super) sigma_px: f64,
    pub(super) iterations: usize,
    pub(super) termination: Termination,
    /// X's and Y's covariances (solve unit), as [`super::Bundle::covariance`] chooses them.
    pub(super) covariance: Option<(Matrix6<f64>, Matrix6<f64>)>,
    pub(super) intrinsics: RefinedIntrinsics,
}

/// The bundle with the intrinsics from `start` (the fixed-intrinsics solution): a robust pass,
/// then plain least squares over the detections it keeps. The sigmas are judged by the jobs
/// ([`check_determined`]).
pub(super) fn refine(
    data: &Data,
    start: State,
    span: Span,
    cauchy_px: f64,
    lm: &RefineOptions,
) -> Refined {
    let camera = *data.camera;
    let scale = camera.fx;
    let robust = Free {
        data,
        loss: Loss::Cauchy(cauchy_px),
        keep: None,
        scale,
    };
    let first = levenberg_marquardt(&robust, (start, camera), lm);
    let norms = norms(data, &first.state);
    let sigma_px = robust_sigma(&norms);
    let threshold = (INLIER_SIGMAS * sigma_px).max(INLIER_FLOOR_PX);
    let keep: Vec<bool> = norms.iter().map(|r| *r <= threshold).collect();
    let plain = Free {
        data,
        loss: Loss::Squared,
        keep: Some(&keep),
        scale,
    };
    let last = levenberg_marquardt(&plain, first.state, lm);
    let (state, fitted) = last.state;
    let (covariance, intrinsic) = match plain.covariance(&last.state) {
        Some((x, y, k)) => (Some((x, y)), Some(k)),
        None => (None, None),
    };
    let sigma = |k: usize| {
        intrinsic
            .as_ref()
            .map_or(f64::INFINITY, |c: &SMatrix<f64, FREE, FREE>| {
                c[(k, k)].max(0.0).sqrt()
            })
    };
    let intrinsics = RefinedIntrinsics {
        fx: fitted.fx,
        fy: fitted.fy,
        cx: fitted.cx,
        cy: fitted.cy,
        distortion: fitted.distortion,
        sigma: IntrinsicsSigma {
            fx: sigma(0) * scale,
            fy: sigma(1) * scale,
            cx: sigma(2) * scale,
            cy: sigma(3) * scale,
            distortion: [
                Some(sigma(4)),
                Some(sigma(5)),
                Some(sigma(6)),
                Some(sigma(7)),
                None,
            ],
        },
        held: vec!["k3".into()],
        corner_cells: span.corner_cells,
        tilt_deg: span.tilt_deg,
    };
    Refined {
        state,
        camera: fitted,
        keep,
        sigma_px,
        iterations: first.iterations + last.iterations,
        termination: last.termination,
        covariance,
        intrinsics,
    }
}

/// |π(p) − u| per detection with the camera of `s`, pixels.
pub(super) fn norms(data: &Data, full: &Full) -> Vec<f64> {
    norms_of(&residual_vectors(data, full))
}

/// The sizes of [`residual_vectors`], pixels (a point behind the camera: [`BEHIND_PX`]).
pub(super) fn norms_of(vectors: &[Option<Vector2<f64>>]) -> Vec<f64> {
    vectors
        .iter()
        .map(|r| r.map_or(BEHIND_PX, |r| r.norm()))
        .collect()
}

/// Per detection, the detected pixel less the projected one (`None`: the point is behind the
/// camera).
pub(super) fn residual_vectors(data: &Data, (state, camera): &Full) -> Vec<Option<Vector2<f64>>> {
    let mut out = Vec::with_capacity(data.points.len());
    data.each(state, false, |_, k, p, _| {
        out.push((p.z > 0.0).then(|| data.pixels[k] - camera.pixel(p)));
    });
    out
}

/// The bundle with the intrinsics free, as a problem of the Levenberg–Marquardt loop. The
/// intrinsic parameters are fx, fy, cx, cy in units of `scale` (the given fx: all parameters of
/// the size of normalised coordinates), then k1, k2, p1, p2.
struct Free<'a> {
    data: &'a Data<'a>,
    loss: Loss,
    keep: Option<&'a [bool]>,
    scale: f64,
}

impl Free<'_> {
    fn counts(&self, k: usize) -> bool {
        self.keep.is_none_or(|keep| keep[k])
    }

    /// Visits each detection that counts and lies before the camera with its frame, its residual
    /// and its row of the Jacobian; returns the cost of those behind the camera.
    fn rows(
        &self,
        (state, camera): &Full,
        mut visit: impl FnMut(usize, Vector2<f64>, &SMatrix<f64, 2, ALL>),
    ) -> f64 {
        let mut behind = 0.0;
        let mut row = SMatrix::<f64, 2, ALL>::zeros();
        self.data.each(state, true, |i, k, p, j| {
            if !self.counts(k) {
                return;
            }
            let Some(pr) = camera.project(p) else {
                behind += self.loss.of(BEHIND_PX * BEHIND_PX).0;
                return;
            };
            row.fixed_view_mut::<2, 12>(0, 0)
                .copy_from(&(pr.jacobian * j));
            let ji = camera.intrinsic_jacobian(p);
            for c in 0..FREE {
                let s = if c < 4 { self.scale } else { 1.0 };
                row[(0, 12 + c)] = ji[(0, c)] * s;
                row[(1, 12 + c)] = ji[(1, c)] * s;
            }
            visit(i, pr.pixel - self.data.pixels[k], &row);
        });
        behind
    }

    fn cost(&self, s: &Full) -> f64 {
        let mut cost = 0.0;
        self.data.each(&s.0, false, |_, k, p, _| {
            if !self.counts(k) {
                return;
            }
            let r2 = if p.z > 0.0 {
                (s.1.pixel(p) - self.data.pixels[k]).norm_squared()
            } else {
                BEHIND_PX * BEHIND_PX
            };
            cost += self.loss.of(r2).0;
        });
        cost
    }

    /// The covariances of X, Y (6 each) and the intrinsics (8, in the
    /// solve's scaled units): each block the larger of the Gauss–Newton one and the sandwich over
    /// the robot's stations (as [`super::Bundle::covariance`]); `None` when singular or with too few frames.
    fn covariance(
        &self,
        s: &Full,
    ) -> Option<(Matrix6<f64>, Matrix6<f64>, SMatrix<f64, FREE, FREE>)> {
        let frames = self.data.motions.len();
        let mut per_frame = vec![SVector::<f64, ALL>::zeros(); frames];
        let mut jtj = SMatrix::<f64, ALL, ALL>::zeros();
        let (mut cost, mut count) = (0.0, 0usize);
        self.rows(s, |i, r, row| {
            jtj += row.transpose() * row;
            per_frame[i] += row.transpose() * r;
            cost += 0.5 * r.norm_squared();
            count += 1;
        });
        let (meat, stations) = station_meat(&per_frame, &self.data.stations);
        if count <= ALL || stations <= ALL {
            return None;
        }
        let inv = jtj.try_inverse()?;
        let classic = inv * (2.0 * cost / (count - ALL) as f64);
        let sandwich = inv * meat * inv * (stations as f64 / (stations - ALL) as f64);
        let pose_scale = |c: &Matrix6<f64>| {
            c.fixed_view::<3, 3>(0, 0).trace() * 1e4 + c.fixed_view::<3, 3>(3, 3).trace()
        };
        let pose = |at: usize| {
            let a: Matrix6<f64> = classic.fixed_view::<6, 6>(at, at).into_owned();
            let b: Matrix6<f64> = sandwich.fixed_view::<6, 6>(at, at).into_owned();
            let c = if pose_scale(&b) > pose_scale(&a) {
                b
            } else {
                a
            };
            c.iter().all(|v| v.is_finite()).then_some(c)
        };
        let a: SMatrix<f64, FREE, FREE> = classic.fixed_view::<FREE, FREE>(12, 12).into_owned();
        let b: SMatrix<f64, FREE, FREE> = sandwich.fixed_view::<FREE, FREE>(12, 12).into_owned();
        let k = if b.trace() > a.trace() { b } else { a };
        if !k.iter().all(|v| v.is_finite()) {
            return None;
        }
        Some((pose(0)?, pose(6)?, k))
    }
}

impl LeastSquares<ALL> for Free<'_> {
    type State = Full;

    fn linearise(&self, s: &Full) -> Linearisation<ALL> {
        let mut lin = Linearisation {
            jtj: SMatrix::<f64, ALL, ALL>::zeros(),
            jtr: SVector::<f64, ALL>::zeros(),
            cost: 0.0,
        };
        let loss = self.loss;
        let behind = self.rows(s, |_, r, row| {
            let (rho, weight) = loss.of(r.norm_squared());
            let rt = row.transpose();
            lin.jtj += (rt * weight) * row;
            lin.jtr += rt * (r * weight);
            lin.cost += rho;
        });
        lin.cost += behind;
        lin
    }

    fn step(&self, ((r_x, t_x, r_y, t_y), camera): &Full, d: &SVector<f64, ALL>) -> Full {
        let a: Vector3<f64> = d.fixed_rows::<3>(0).into_owned();
        let e: Vector3<f64> = d.fixed_rows::<3>(6).into_owned();
        let mut c = *camera;
        c.fx += self.scale * d[12];
        c.fy += self.scale * d[13];
        c.cx += self.scale * d[14];
        c.cy += self.scale * d[15];
        for k in 0..4 {
            c.distortion[k] += d[16 + k];
        }
        (
            (
                proj_so3(&(exp_so3(&a) * r_x)),
                t_x + d.fixed_rows::<3>(3),
                proj_so3(&(exp_so3(&e) * r_y)),
                t_y + d.fixed_rows::<3>(9),
            ),
            c,
        )
    }

    fn cost_drop(&self, _: &Full, to: &Full, cost: f64) -> f64 {
        cost - self.cost(to)
    }

    fn size(&self, ((_, t_x, _, t_y), _): &Full) -> f64 {
        1.0 + t_x.norm() + t_y.norm()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::camera::Detections;
    use crate::model::motion::Setup;
    use crate::model::pose::transform_from_parts;

    /// The rows' analytic Jacobian (X, Y and the scaled intrinsics) agrees with central
    /// differences of the pixels through `step`.
    #[test]
    fn free_jacobian_matches_central_differences() {
        let camera = Intrinsics {
            fx: 900.0,
            fy: 902.0,
            cx: 640.0,
            cy: 360.0,
            distortion: [-0.2, 0.08, 0.001, -0.0005, -0.01],
            width: 1280,
            height: 720,
        };
        let x = transform_from_parts(
            &exp_so3(&Vector3::new(0.1, -0.2, 0.3)),
            &Vector3::new(0.05, 0.02, 0.1),
        );
        let y = transform_from_parts(
            &exp_so3(&Vector3::new(2.9, 0.1, 0.0)),
            &Vector3::new(0.1, 0.05, 0.6),
        );
        let frame = Frame {
            base_from_gripper: transform_from_parts(
                &exp_so3(&Vector3::new(-0.1, 0.05, 0.2)),
                &Vector3::new(0.02, -0.03, 0.01),
            ),
            camera_from_target: None,
            detections: Detections {
                target: vec![
                    [0.0, 0.0, 0.0],
                    [0.15, 0.0, 0.0],
                    [0.0, 0.12, 0.0],
                    [0.15, 0.12, 0.01],
                ],
                pixels: vec![[0.0, 0.0]; 4],
            },
        };
        let data = Data::new(std::slice::from_ref(&frame), &camera, Setup::EyeInHand, 1.0);
        let s: Full = (
            (
                *x.rotation.matrix(),
                x.translation.vector,
                *y.rotation.matrix(),
                y.translation.vector,
            ),
            camera,
        );
        let free = Free {
            data: &data,
            loss: Loss::Squared,
            keep: None,
            scale: camera.fx,
        };
        let pixels_at = |s: &Full| {
            let mut out = Vec::new();
            data.each(&s.0, false, |_, _, p, _| out.push(s.1.pixel(p)));
            out
        };
        let mut analytic = Vec::new();
        // The pixels are all (0, 0): the residual is the pixel.
        free.rows(&s, |_, _, row| analytic.push(*row));
        assert_eq!(analytic.len(), 4);
        let h = 1e-7;
        for d in 0..ALL {
            let mut delta = SVector::<f64, ALL>::zeros();
            delta[d] = h;
            let plus = pixels_at(&free.step(&s, &delta));
            delta[d] = -h;
            let minus = pixels_at(&free.step(&s, &delta));
            for (k, a) in analytic.iter().enumerate() {
                let numeric = (plus[k] - minus[k]) / (2.0 * h);
                for r in 0..2 {
                    let scale = a[(r, d)].abs().max(1.0);
                    assert!(
                        (numeric[r] - a[(r, d)]).abs() < 1e-5 * scale,
                        "param {d} point {k}: {} vs {}",
                        numeric[r],
                        a[(r, d)]
                    );
                }
            }
        }
    }

    /// The decision to hold k3: over frames that span the image, with the noise of the
    /// simulated recordings, k3's column trades against k2's; k3 free, its sigma is larger than
    /// the value itself and k2's sigma grows many times. Printed with `--nocapture`.
    #[test]
    fn k3_is_not_determined_beside_k2() {
        use crate::sim::pixels::{PixelSimConfig, simulate_pixels};
        use nalgebra::DMatrix;
        for setup in [Setup::EyeInHand, Setup::EyeToHand] {
            let sim = simulate_pixels(&PixelSimConfig::board().spanning().with_setup(setup), 3);
            let camera = sim.intrinsics;
            let data = Data::new(&sim.frames, &camera, setup, 1.0);
            let (x, y) = (sim.x, sim.y);
            let s: State = (
                *x.rotation.matrix(),
                x.translation.vector,
                *y.rotation.matrix(),
                y.translation.vector,
            );
            let mut jtj = DMatrix::<f64>::zeros(21, 21);
            data.each(&s, true, |_, _, p, j| {
                let mut row = DMatrix::<f64>::zeros(2, 21);
                let pose = camera.project(p).unwrap().jacobian * j;
                let ji = camera.intrinsic_jacobian(p);
                for r in 0..2 {
                    for c in 0..12 {
                        row[(r, c)] = pose[(r, c)];
                    }
                    for c in 0..9 {
                        row[(r, 12 + c)] = ji[(r, c)];
                    }
                }
                jtj += row.transpose() * &row;
            });
            let s2 = sim.pixel_sigma * sim.pixel_sigma;
            let with_k3 = jtj.clone().try_inverse().unwrap() * s2;
            let without = jtj
                .view((0, 0), (20, 20))
                .into_owned()
                .try_inverse()
                .unwrap()
                * s2;
            let sigma_k3 = with_k3[(20, 20)].sqrt();
            let correlation = with_k3[(17, 20)] / (with_k3[(17, 17)] * with_k3[(20, 20)]).sqrt();
            let k2_growth = (with_k3[(17, 17)] / without[(17, 17)]).sqrt();
            println!(
                "{setup:?}: k3 {} ± {sigma_k3:.4}, correlation k2–k3 {correlation:.4}, k2's sigma {:.2} times larger with k3 free",
                camera.distortion[4], k2_growth
            );
            assert!(correlation.abs() > 0.9, "{correlation}");
            assert!(k2_growth > 2.0, "{k2_growth}");
            assert!(sigma_k3 > camera.distortion[4].abs(), "{sigma_k3}");
        }
    }

    /// Sigmas beyond their bounds are refused, naming the parameter; within them, taken.
    #[test]
    fn undetermined_sigmas_are_refused_by_name() {
        let given = Intrinsics {
            width: 1280,
            height: 720,
            ..Intrinsics::pinhole(900.0, 900.0, 640.0, 360.0)
        };
        let refined = |fx: f64, cy: f64| RefinedIntrinsics {
            fx: 900.0,
            fy: 900.0,
            cx: 640.0,
            cy: 360.0,
            distortion: [0.0; 5],
            sigma: IntrinsicsSigma {
                fx,
                fy: 2.0,
                cx: 5.0,
                cy,
                distortion: [Some(0.01), Some(0.01), Some(0.01), Some(0.01), None],
            },
            held: vec!["k3".into()],
            corner_cells: 4,
            tilt_deg: 20.0,
        };
        assert!(check_determined(&refined(2.0, 5.0), &given).is_ok());
        let e = check_determined(&refined(20.0, 5.0), &given).unwrap_err();
        assert!(e.to_string().contains("fx's sigma is 2.22 %"), "{e}");
        let e = check_determined(&refined(2.0, 40.0), &given).unwrap_err();
        assert!(
            e.to_string().contains("cy's sigma is 5.56 % of the image"),
            "{e}"
        );
        let e = check_determined(&refined(f64::NAN, 5.0), &given).unwrap_err();
        assert!(e.to_string().contains("fx's sigma"), "{e}");
    }
}
