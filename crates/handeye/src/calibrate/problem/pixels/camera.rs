//! The camera's intrinsics checked by the pixels: the focal length's scale and the radial
//! distortion k1 that fit the detections best, each found by Brent's minimisation with X and the
//! target's pose solved anew.

use crate::model::camera::{Frame, Intrinsics};
use crate::model::motion::Setup;
use crate::model::pose::Transform;
use crate::solve::reprojection::{PixelOptions, PixelSolution, reprojection_leaving_out};

/// A solve of the frames used with one of the camera's parameters changed: the focal length's
/// scale (fx and fy together), or k1.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CameraFit {
    /// The parameter's value: the focal length's scale, or k1.
    pub value: f64,
    /// Its value as given: 1 for the scale, the camera's k1.
    pub given: f64,
    /// The robust reprojection sigma with it, pixels.
    pub sigma_px: f64,
    /// The RMS over the detections kept with it, pixels.
    pub rms_px: f64,
    /// X with it.
    pub x: Transform,
}

/// The range of the focal length's scale searched by [`focal_check`]: a focal length off by a
/// factor of two is another camera or resolution, which the fit at the given one refuses.
const FOCAL_RANGE: (f64, f64) = (0.5, 2.0);

/// The focal length's scale that fits the detections best (the least RMS over the detections
/// `solved` kept, on its logarithm over [`FOCAL_RANGE`], to 0.1%: the maximum likelihood under
/// Gaussian detection noise) with X and the target's pose solved anew at each: the robot's metric
/// motions fix the depth that a focal length trades against, so wrong intrinsics show as a better
/// fit at another scale. The detections fitted are `solved`'s at every scale: a solve free to
/// leave out more would fit fewer and look better (measured: 54 of 1024 left out at ×0.5, RMS
/// 0.36 px against 1.02 px at ×1 on the same frames). Brent's minimisation ([`brent_minimum`])
/// from scale 1, `solved` itself: about 8 solves where the intrinsics are the camera's.
pub(crate) fn focal_check(
    frames: &[Frame],
    camera: &Intrinsics,
    setup: Setup,
    options: &PixelOptions,
    solved: &PixelSolution,
) -> Option<CameraFit> {
    let at = |log_scale: f64| {
        let scale = log_scale.exp();
        let scaled = Intrinsics {
            fx: camera.fx * scale,
            fy: camera.fy * scale,
            ..*camera
        };
        (scale, scaled)
    };
    let bracket = (FOCAL_RANGE.0.ln(), FOCAL_RANGE.1.ln());
    refit(
        (frames, setup, options, solved),
        at,
        (bracket, 0.0, 2.5e-4),
        1.0,
    )
}

/// The best fit over one camera parameter: `at` gives, at a point of the search, the parameter's
/// value and the camera with it; Brent's minimisation of the RMS over `bracket` from `start` (the
/// given camera, whose RMS is `solved`'s) to `tolerance`; every solve fits the detections `solved`
/// kept. `None` when no value fits better than `given`, the parameter as given.
fn refit(
    (frames, setup, options, solved): (&[Frame], Setup, &PixelOptions, &PixelSolution),
    at: impl Fn(f64) -> (f64, Intrinsics),
    (bracket, start, tolerance): ((f64, f64), f64, f64),
    given: f64,
) -> Option<CameraFit> {
    let mut best: Option<CameraFit> = None;
    let mut rms = |point: f64| {
        let (value, camera) = at(point);
        let Ok(s) = reprojection_leaving_out(frames, &camera, setup, options, &solved.outliers)
        else {
            return f64::INFINITY;
        };
        if best.as_ref().is_none_or(|b| s.rms_px < b.rms_px) {
            best = Some(CameraFit {
                value,
                given,
                sigma_px: s.sigma_px,
                rms_px: s.rms_px,
                x: s.calibration.x,
            });
        }
        s.rms_px
    };
    brent_minimum(&mut rms, bracket, (start, solved.rms_px), tolerance);
    best.filter(|b| b.rms_px < solved.rms_px)
}

/// How far from the given k1 [`k1_check`] searches, either way: at the corner of a typical image
/// (normalised radius 0.8, 900 px focal length) 0.5 moves a point by 230 px, another lens.
const K1_RANGE: f64 = 0.5;

/// The radial distortion k1 that fits the detections best, as [`focal_check`] finds the focal
/// length's scale (the same detections at every k1, X and the target's pose solved anew, Brent's
/// minimisation from the given k1 to 1e-4): a wrong k1 bends the image's outer detections, which
/// the robot's motions do not follow, so it shows as a better fit at another k1. The other
/// coefficients stay as given (k1 is the one a wrong calibration or model gets most wrong).
pub(crate) fn k1_check(
    frames: &[Frame],
    camera: &Intrinsics,
    setup: Setup,
    options: &PixelOptions,
    solved: &PixelSolution,
) -> Option<CameraFit> {
    let k1 = camera.distortion[0];
    let at = |value: f64| {
        let mut changed = *camera;
        changed.distortion[0] = value;
        (value, changed)
    };
    let bracket = (k1 - K1_RANGE, k1 + K1_RANGE);
    refit(
        (frames, setup, options, solved),
        at,
        (bracket, k1, 1e-4),
        k1,
    )
}

/// The minimum of `f` on `(a, b)` by Brent's method (R. P. Brent, *Algorithms for Minimization
/// without Derivatives*, 1973, ch. 5: parabolic interpolation through the three best points,
/// golden-section steps where it does not shrink the bracket fast enough), from `(x, f(x))`
/// inside the bracket, to an absolute `tolerance` on x. Returns the best x and f(x). An
/// infinite value (a solve that fails) is taken as worse, never interpolated through.
fn brent_minimum(
    f: &mut impl FnMut(f64) -> f64,
    (mut a, mut b): (f64, f64),
    (x0, f0): (f64, f64),
    tolerance: f64,
) -> (f64, f64) {
    let golden = (3.0 - 5f64.sqrt()) / 2.0;
    let (mut x, mut w, mut v) = (x0, x0, x0);
    let (mut fx, mut fw, mut fv) = (f0, f0, f0);
    // d: the last step; e: the step before it (a parabolic step must be less than half of it).
    let (mut d, mut e) = (0.0_f64, 0.0_f64);
    loop {
        let middle = 0.5 * (a + b);
        let tol1 = 1e-8 * x.abs() + tolerance;
        let tol2 = 2.0 * tol1;
        if (x - middle).abs() <= tol2 - 0.5 * (b - a) {
            return (x, fx);
        }
        let mut parabolic = None;
        if e.abs() > tol1 && fx.is_finite() && fw.is_finite() && fv.is_finite() {
            let r = (x - w) * (fx - fv);
            let q = (x - v) * (fx - fw);
            let mut p = (x - v) * q - (x - w) * r;
            let mut q = 2.0 * (q - r);
            if q > 0.0 {
                p = -p;
            } else {
                q = -q;
            }
            if p.abs() < (0.5 * q * e).abs() && p > q * (a - x) && p < q * (b - x) {
                parabolic = Some(p / q);
            }
        }
        match parabolic {
            Some(step) => {
                e = d;
                d = step;
                let u = x + d;
                if u - a < tol2 || b - u < tol2 {
                    d = if x < middle { tol1 } else { -tol1 };
                }
            }
            None => {
                e = if x < middle { b - x } else { a - x };
                d = golden * e;
            }
        }
        let u = x + if d.abs() >= tol1 { d } else { tol1.copysign(d) };
        let fu = f(u);
        if fu <= fx {
            if u < x {
                b = x;
            } else {
                a = x;
            }
            (v, fv, w, fw, x, fx) = (w, fw, x, fx, u, fu);
        } else {
            if u < x {
                a = u;
            } else {
                b = u;
            }
            if fu <= fw || w == x {
                (v, fv, w, fw) = (w, fw, u, fu);
            } else if fu <= fv || v == x || v == w {
                (v, fv) = (u, fu);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::calibrate::problem::pixels::camera::brent_minimum;

    /// Finds `f`'s minimum on the focal check's bracket from 0, counting evaluations.
    fn minimum(f: impl Fn(f64) -> f64) -> (f64, usize) {
        let mut count = 0;
        let mut counted = |x: f64| {
            count += 1;
            f(x)
        };
        let (low, high) = (0.5f64.ln(), 2f64.ln());
        let (x, _) = brent_minimum(&mut counted, (low, high), (0.0, f(0.0)), 2.5e-4);
        (x, count)
    }

    #[test]
    fn brent_finds_the_minimum_to_the_tolerance_in_fewer_steps_than_golden_section() {
        // Golden section on the same bracket to 1e-3 takes 17 evaluations; these take 4 to 8.
        for centre in [-0.6, -0.2, -0.01, 0.0, 0.004, 0.05, 0.3, 0.65] {
            let (x, count) = minimum(|x| 1.0 + (x - centre).powi(2) + 0.3 * (x - centre).powi(4));
            assert!((x - centre).abs() < 1e-3, "{centre}: {x}");
            assert!(count <= 10, "{centre}: {count} evaluations");
        }
        // A kink (|x − c|: no parabola fits) still converges, by golden-section steps.
        let (x, count) = minimum(|x| 1.0 + (x - 0.21).abs());
        assert!((x - 0.21).abs() < 1e-3 && count <= 40, "{x} {count}");
    }

    #[test]
    fn failed_solves_are_worse_never_interpolated() {
        // Solves fail beyond 0.4: the minimum at 0.5 is out of reach, the best is at the edge.
        let f = |x: f64| {
            if x > 0.4 {
                f64::INFINITY
            } else {
                (x - 0.5).powi(2)
            }
        };
        let (x, _) = minimum(f);
        assert!((x - 0.4).abs() < 2e-3, "{x}");
        // All fail but the start: the start is kept.
        let (x, _) = minimum(|x| if x == 0.0 { 1.0 } else { f64::INFINITY });
        assert_eq!(x, 0.0);
    }
}
