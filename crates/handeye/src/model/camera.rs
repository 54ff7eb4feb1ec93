//! The camera: pinhole intrinsics with Brown–Conrady distortion (OpenCV's five-coefficient model),
//! and a frame's detections (the target's points and the pixels they were seen at).
//!
//! A point `p = (X, Y, Z)` in the camera frame projects to `x = X/Z, y = Y/Z`, `r² = x² + y²`,
//! ```text
//! x_d = x (1 + k1 r² + k2 r⁴ + k3 r⁶) + 2 p1 x y + p2 (r² + 2 x²)
//! y_d = y (1 + k1 r² + k2 r⁴ + k3 r⁶) + p1 (r² + 2 y²) + 2 p2 x y
//! u = fx x_d + cx,   v = fy y_d + cy
//! ```
//! as OpenCV's `projectPoints` (skew 0).
//!
//! # References
//! D. C. Brown, "Decentering distortion of lenses", Photogrammetric Engineering 32(3), 1966;
//! A. E. Conrady (1919); the coefficient order of OpenCV's `calib3d` (k1, k2, p1, p2, k3).

use nalgebra::{Matrix2, Matrix2x3, SMatrix, Vector2, Vector3};
use serde::{Deserialize, Serialize};

use crate::model::pose::Transform;

/// Pinhole intrinsics and Brown–Conrady distortion, pixels.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Intrinsics {
    /// Focal length along u, pixels.
    pub fx: f64,
    /// Focal length along v, pixels.
    pub fy: f64,
    /// Principal point u, pixels.
    pub cx: f64,
    /// Principal point v, pixels.
    pub cy: f64,
    /// Distortion k1, k2, p1, p2, k3 (OpenCV's order).
    pub distortion: [f64; 5],
    /// Image width, pixels (0 when unknown).
    pub width: u32,
    /// Image height, pixels (0 when unknown).
    pub height: u32,
}

/// A projected point and its Jacobian with respect to the point in the camera frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projection {
    /// The pixel (u, v).
    pub pixel: Vector2<f64>,
    /// ∂(u, v)/∂(X, Y, Z).
    pub jacobian: Matrix2x3<f64>,
}

impl Intrinsics {
    /// A camera without distortion.
    pub fn pinhole(fx: f64, fy: f64, cx: f64, cy: f64) -> Self {
        Self {
            fx,
            fy,
            cx,
            cy,
            distortion: [0.0; 5],
            width: 0,
            height: 0,
        }
    }

    /// The distorted normalised coordinates (x_d, y_d) of (x, y), and ∂(x_d, y_d)/∂(x, y).
    pub fn distort(&self, x: f64, y: f64) -> (Vector2<f64>, Matrix2<f64>) {
        let [k1, k2, p1, p2, k3] = self.distortion;
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
        // d(radial)/d(r²)
        let dradial = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);
        let xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
        let yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
        let j = Matrix2::new(
            radial + 2.0 * x * x * dradial + 2.0 * p1 * y + 6.0 * p2 * x,
            2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y,
            2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y,
            radial + 2.0 * y * y * dradial + 6.0 * p1 * y + 2.0 * p2 * x,
        );
        (Vector2::new(xd, yd), j)
    }

    /// The pixel of a point in the camera frame, with its Jacobian; `None` behind or on the
    /// camera's plane (Z ≤ 0).
    pub fn project(&self, p: &Vector3<f64>) -> Option<Projection> {
        if p.z <= 0.0 || !p.z.is_finite() {
            return None;
        }
        let inv_z = 1.0 / p.z;
        let (x, y) = (p.x * inv_z, p.y * inv_z);
        let (d, jd) = self.distort(x, y);
        let pixel = Vector2::new(self.fx * d.x + self.cx, self.fy * d.y + self.cy);
        // ∂(x, y)/∂(X, Y, Z)
        let jn = Matrix2x3::new(inv_z, 0.0, -x * inv_z, 0.0, inv_z, -y * inv_z);
        let jf = Matrix2::new(self.fx, 0.0, 0.0, self.fy);
        Some(Projection {
            pixel,
            jacobian: jf * jd * jn,
        })
    }

    /// The pixel of a point in the camera frame (Z > 0 assumed), without the Jacobian.
    pub fn pixel(&self, p: &Vector3<f64>) -> Vector2<f64> {
        let (d, _) = self.distort(p.x / p.z, p.y / p.z);
        Vector2::new(self.fx * d.x + self.cx, self.fy * d.y + self.cy)
    }

    /// ∂(u, v)/∂(fx, fy, cx, cy, k1, k2, p1, p2, k3) of the pixel of `p` (a point in the camera
    /// frame, Z > 0 assumed): the columns of the intrinsics a solve refines.
    pub(crate) fn intrinsic_jacobian(&self, p: &Vector3<f64>) -> SMatrix<f64, 2, 9> {
        let (x, y) = (p.x / p.z, p.y / p.z);
        let (d, _) = self.distort(x, y);
        let r2 = x * x + y * y;
        let (fx, fy) = (self.fx, self.fy);
        let mut j = SMatrix::<f64, 2, 9>::zeros();
        j[(0, 0)] = d.x;
        j[(1, 1)] = d.y;
        j[(0, 2)] = 1.0;
        j[(1, 3)] = 1.0;
        // ∂(x_d, y_d)/∂(k1, k2, p1, p2, k3), scaled by fx and fy.
        let columns = [
            (x * r2, y * r2),
            (x * r2 * r2, y * r2 * r2),
            (2.0 * x * y, r2 + 2.0 * y * y),
            (r2 + 2.0 * x * x, 2.0 * x * y),
            (x * r2 * r2 * r2, y * r2 * r2 * r2),
        ];
        for (c, (dx, dy)) in columns.into_iter().enumerate() {
            j[(0, 4 + c)] = fx * dx;
            j[(1, 4 + c)] = fy * dy;
        }
        j
    }

    /// The undistorted normalised coordinates (x, y) of a pixel: Gauss–Newton on
    /// [`Intrinsics::distort`] from the distorted coordinates (a few steps reach 1e-12 for any
    /// lens OpenCV's model describes within the image).
    pub fn normalised(&self, pixel: &Vector2<f64>) -> Vector2<f64> {
        let target = Vector2::new((pixel.x - self.cx) / self.fx, (pixel.y - self.cy) / self.fy);
        let mut xy = target;
        for _ in 0..UNDISTORT_ITERATIONS {
            let (d, j) = self.distort(xy.x, xy.y);
            let Some(inv) = j.try_inverse() else { break };
            let step = inv * (target - d);
            xy += step;
            if step.norm() < 1e-15 {
                break;
            }
        }
        xy
    }

    /// Whether a detection at `pixel` could be one of this camera's: finite, within a million
    /// pixels, and, where the image's size is known, within one image's size of the image (the
    /// corners of a board partly out of view are extrapolated a little beyond it). A detection
    /// beyond is a mis-detection, left out by name: no camera saw it.
    pub fn could_see(&self, pixel: &[f64; 2]) -> bool {
        let within = |v: f64, size: u32| {
            v.is_finite()
                && v.abs() <= MAX_PIXEL
                && (size == 0 || (-f64::from(size)..=2.0 * f64::from(size)).contains(&v))
        };
        within(pixel[0], self.width) && within(pixel[1], self.height)
    }

    /// Refuses intrinsics that cannot describe a camera: a focal length that is not a finite
    /// positive number, a principal point or a coefficient that is not finite. The message names
    /// the field.
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        for (name, f) in [("fx", self.fx), ("fy", self.fy)] {
            if !(f.is_finite() && f > 0.0) {
                return Err((name, format!("a focal length must be positive, got {f}")));
            }
            if !(MIN_FOCAL_PX..=MAX_PIXEL).contains(&f) {
                return Err((
                    name,
                    format!(
                        "{f:e} pixels is no camera's focal length (between {MIN_FOCAL_PX} and {MAX_PIXEL:e} pixels): check the file's units and fields"
                    ),
                ));
            }
        }
        for (name, c) in [("cx", self.cx), ("cy", self.cy)] {
            if !c.is_finite() {
                return Err((name, format!("must be finite, got {c}")));
            }
            if c.abs() > MAX_PIXEL {
                return Err((
                    name,
                    format!(
                        "{c:e} pixels is no image's principal point (at most {MAX_PIXEL:e} in size)"
                    ),
                ));
            }
        }
        if let Some(k) = self.distortion.iter().find(|k| !k.is_finite()) {
            return Err(("distortion", format!("must be finite, got {k}")));
        }
        if let Some(k) = self.distortion.iter().find(|k| k.abs() > MAX_DISTORTION) {
            return Err((
                "distortion",
                format!("a coefficient of {k:e} is no lens's (at most {MAX_DISTORTION} in size)"),
            ));
        }
        for (name, size) in [("width", self.width), ("height", self.height)] {
            if f64::from(size) > MAX_PIXEL {
                return Err((name, format!("{size} pixels is no image's size")));
            }
        }
        Ok(())
    }
}

/// The largest pixel coordinate, focal length, principal point or image size a camera has, in
/// pixels: a million (sensors are some ten thousand pixels a side; a telephoto's focal length some
/// tens of thousands).
pub const MAX_PIXEL: f64 = 1e6;

/// The smallest focal length a camera has, pixels.
pub const MIN_FOCAL_PX: f64 = 1.0;

/// The largest distortion coefficient in size a lens of the plumb-bob model has (fisheye lenses'
/// are of order one; fitted rational models' of order ten).
pub const MAX_DISTORTION: f64 = 1e3;

/// Gauss–Newton steps of [`Intrinsics::normalised`].
const UNDISTORT_ITERATIONS: usize = 20;

/// The least number of points a frame's detections must have (a planar pose needs 4).
pub const MIN_DETECTIONS: usize = 4;

/// What the camera saw in one frame: the target's points (target frame, input unit) and the pixels
/// they were detected at, in the same order.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Detections {
    /// The target's points, target frame, input unit.
    pub target: Vec<[f64; 3]>,
    /// Their detected pixels (u, v).
    pub pixels: Vec<[f64; 2]>,
}

/// One frame of a recording on the pixels.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Q, the robot's pose (`base_from_gripper`).
    pub base_from_gripper: Transform,
    /// The recording's pose of the target, when it gives one (a PnP of its own).
    pub camera_from_target: Option<Transform>,
    /// The target's points and their pixels.
    pub detections: Detections,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Intrinsics {
        Intrinsics {
            fx: 910.0,
            fy: 905.0,
            cx: 641.0,
            cy: 362.0,
            distortion: [-0.28, 0.11, 0.0012, -0.0008, -0.02],
            width: 1280,
            height: 720,
        }
    }

    /// The analytic Jacobian of the projection agrees with central differences.
    #[test]
    fn projection_jacobian_matches_central_differences() {
        let c = camera();
        for p in [
            Vector3::new(0.1, -0.05, 0.6),
            Vector3::new(-0.2, 0.15, 0.5),
            Vector3::new(0.0, 0.0, 1.0),
            Vector3::new(0.25, 0.14, 0.45),
        ] {
            let j = c.project(&p).unwrap().jacobian;
            let h = 1e-7;
            for k in 0..3 {
                let mut plus = p;
                let mut minus = p;
                plus[k] += h;
                minus[k] -= h;
                let d = (c.pixel(&plus) - c.pixel(&minus)) / (2.0 * h);
                for r in 0..2 {
                    let scale = j[(r, k)].abs().max(1.0);
                    assert!(
                        (d[r] - j[(r, k)]).abs() < 1e-5 * scale,
                        "{p:?} ({r},{k}): {} vs {}",
                        d[r],
                        j[(r, k)]
                    );
                }
            }
        }
    }

    /// The Jacobian with respect to the intrinsics agrees with central differences.
    #[test]
    fn intrinsic_jacobian_matches_central_differences() {
        let c = camera();
        let set = |c: &Intrinsics, k: usize, v: f64| {
            let mut c = *c;
            match k {
                0 => c.fx += v,
                1 => c.fy += v,
                2 => c.cx += v,
                3 => c.cy += v,
                4 => c.distortion[0] += v,
                5 => c.distortion[1] += v,
                6 => c.distortion[2] += v,
                7 => c.distortion[3] += v,
                _ => c.distortion[4] += v,
            }
            c
        };
        for p in [
            Vector3::new(0.1, -0.05, 0.6),
            Vector3::new(-0.2, 0.15, 0.5),
            Vector3::new(0.25, 0.14, 0.45),
        ] {
            let j = c.intrinsic_jacobian(&p);
            for k in 0..9 {
                let h = if k < 4 { 1e-4 } else { 1e-7 };
                let d = (set(&c, k, h).pixel(&p) - set(&c, k, -h).pixel(&p)) / (2.0 * h);
                for r in 0..2 {
                    let scale = j[(r, k)].abs().max(1.0);
                    assert!(
                        (d[r] - j[(r, k)]).abs() < 1e-6 * scale,
                        "{p:?} ({r},{k}): {} vs {}",
                        d[r],
                        j[(r, k)]
                    );
                }
            }
        }
    }

    #[test]
    fn undistortion_inverts_the_projection() {
        let c = camera();
        for p in [Vector3::new(0.2, -0.1, 0.5), Vector3::new(-0.3, 0.17, 0.6)] {
            let xy = c.normalised(&c.pixel(&p));
            assert!(
                (xy - Vector2::new(p.x / p.z, p.y / p.z)).norm() < 1e-12,
                "{xy}"
            );
        }
    }

    #[test]
    fn points_behind_the_camera_do_not_project() {
        assert!(camera().project(&Vector3::new(0.0, 0.0, -1.0)).is_none());
        assert!(camera().project(&Vector3::new(0.0, 0.0, 0.0)).is_none());
    }

    #[test]
    fn bad_intrinsics_name_the_field() {
        let mut c = camera();
        c.fy = 0.0;
        assert_eq!(c.check().unwrap_err().0, "fy");
        let mut c = camera();
        c.distortion[2] = f64::NAN;
        assert_eq!(c.check().unwrap_err().0, "distortion");
    }
}
