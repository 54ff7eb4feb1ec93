//! Unit tests of refine's private linearisation (in their own file to keep `refine.rs` the
//! solver's).

use nalgebra::{Matrix3, SMatrix, Vector3};

use super::{jacobian, residual};
use crate::motion::MotionPair;
use crate::pose::{exp_so3, transform_from_parts};

/// Motions that no X fits, so that every residual and every column of the Jacobian is nonzero.
fn motions() -> [MotionPair; 3] {
    let t = |r: [f64; 3], t: [f64; 3]| {
        transform_from_parts(&exp_so3(&Vector3::from(r)), &Vector3::from(t))
    };
    [
        MotionPair {
            a: t([0.3, -0.2, 0.5], [0.4, 0.1, -0.2]),
            b: t([0.1, 0.6, -0.3], [-0.3, 0.2, 0.5]),
        },
        MotionPair {
            a: t([-1.2, 0.4, 0.9], [0.0, -0.7, 0.3]),
            b: t([0.8, -0.5, 1.1], [0.6, 0.4, -0.1]),
        },
        MotionPair {
            a: t([2.5, 0.3, -0.4], [1.5, 0.2, 0.9]),
            b: t([-0.2, 2.7, 0.6], [-0.8, 1.1, 0.0]),
        },
    ]
}

/// The weighted residual vector of one motion at (R_x, t_x), in the Jacobian's row order.
fn weighted(
    m: &MotionPair,
    r_x: &Matrix3<f64>,
    t_x: &Vector3<f64>,
    w: [f64; 2],
) -> SMatrix<f64, 12, 1> {
    let (dr, dt) = residual(m, r_x, t_x);
    jacobian(m, r_x, &dr, &dt, w).1
}

/// The analytic Jacobian of the increment R_x exp([δ]×), t_x + Δt against central differences
/// with step h: truncation O(h²) ≈ 1e-10 and rounding ε/h ≈ 1e-10 of the entries (about 1).
#[test]
fn jacobian_matches_central_differences() {
    let r_x = exp_so3(&Vector3::new(0.7, -1.1, 0.4));
    let t_x = Vector3::new(0.2, -0.5, 0.8);
    let w = [1.7, 0.6];
    let h = 1e-6;
    for m in &motions() {
        let (dr, dt) = residual(m, &r_x, &t_x);
        let (j, _) = jacobian(m, &r_x, &dr, &dt, w);
        for c in 0..3 {
            let e = Vector3::ith(c, h);
            let rotation = (weighted(m, &(r_x * exp_so3(&e)), &t_x, w)
                - weighted(m, &(r_x * exp_so3(&-e)), &t_x, w))
                / (2.0 * h);
            let translation =
                (weighted(m, &r_x, &(t_x + e), w) - weighted(m, &r_x, &(t_x - e), w)) / (2.0 * h);
            let (gap_r, gap_t) = (
                (j.column(c) - rotation).amax(),
                (j.column(3 + c) - translation).amax(),
            );
            assert!(gap_r < 1e-8, "∂/∂δ_{c}: {gap_r:e}");
            assert!(gap_t < 1e-8, "∂/∂t_{c}: {gap_t:e}");
            assert!(
                rotation.amax() > 0.1 && translation.amax() > 0.1,
                "column {c} is not exercised"
            );
        }
    }
}
