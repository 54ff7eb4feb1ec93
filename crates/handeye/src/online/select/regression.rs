//! The paper's cubic polynomial regression (sec. 3.2, Eq. (2)–(5)) and its threshold predictions
//! (Algorithms I–III), as SPEC sec. 4.4 fixes them.

use nalgebra::{Matrix3, Vector3};

/// Above this 2-norm condition number of the scaled matrix L of Eq. (3) the fit gives nothing.
pub(crate) const MAX_CONDITION: f64 = 1e14;

/// Fits Eq. (2), y = b₀ + b₁x + b₂x² + b₃x³, to four points by least squares and evaluates it at
/// `x_new` (Eq. (5)).
///
/// x is scaled by max|x| and y by max|y| (the paper's "normalised"; a scale of 0 counts as 1); the
/// centred normal equations of Eq. (3) give b₁..b₃ (solved by LU with partial pivoting), b₀ comes
/// from the means, and the value at `x_new / max|x|` is scaled back by max|y|. Returns `None` when
/// Eq. (3) is singular: its condition number (2-norm, on the scaled L) is above 1e14 or
/// not finite.
///
/// # Example
/// ```
/// use handeye::online::select::fit;
/// // Four points on y = 1 + 2x − x³ are fitted exactly.
/// let x = [0.1, 0.2, 0.4, 0.8];
/// let y = x.map(|v: f64| 1.0 + 2.0 * v - v.powi(3));
/// let at = fit(&x, &y, 0.5).unwrap();
/// assert!((at - (1.0 + 1.0 - 0.125)).abs() < 1e-9);
/// ```
pub fn fit(x: &[f64; 4], y: &[f64; 4], x_new: f64) -> Option<f64> {
    Cubic::of(x)?.at(y, x_new)
}

/// Eq. (3)'s matrix L for one set of four x values, checked and factored once: Algorithms I–III
/// fit two thresholds each against the same rmsR or rmsT records.
pub(crate) struct Cubic {
    /// max|x|, the scale of x.
    sx: f64,
    /// The scaled (x, x², x³) of the four points.
    powers: [Vector3<f64>; 4],
    /// Their means x̄₁, x̄₂, x̄₃.
    mean_p: Vector3<f64>,
    /// L, factored.
    lu: nalgebra::LU<f64, nalgebra::U3, nalgebra::U3>,
}

impl Cubic {
    /// L for these x values; `None` when they are not finite or L is singular (condition number
    /// above [`MAX_CONDITION`]).
    pub(crate) fn of(x: &[f64; 4]) -> Option<Self> {
        if !x.iter().all(|v| v.is_finite()) {
            return None;
        }
        let (l, mean_p, sx, powers) = centred_moments(x);
        if !surely_conditioned(&l) {
            let condition = condition_of(&l);
            if !condition.is_finite() || condition > MAX_CONDITION {
                return None;
            }
        }
        Some(Self {
            sx,
            powers,
            mean_p,
            lu: l.lu(),
        })
    }

    /// Eq. (4) and (5): the least-squares cubic through (x, y), evaluated at `x_new`.
    pub(crate) fn at(&self, y: &[f64; 4], x_new: f64) -> Option<f64> {
        if !(y.iter().all(|v| v.is_finite()) && x_new.is_finite()) {
            return None;
        }
        let sy = scale_of(y);
        let ys = y.map(|v| v / sy);
        let mean_y = ys.iter().sum::<f64>() / 4.0;
        // L_p0 = Σ (x^p − x̄_p)(y − ȳ).
        let mut l0 = Vector3::zeros();
        for (p, y) in self.powers.iter().zip(ys) {
            l0 += (p - self.mean_p) * (y - mean_y);
        }
        let b = self.lu.solve(&l0)?;
        let b0 = mean_y - b.dot(&self.mean_p);
        let u = x_new / self.sx;
        let value = (b0 + b[0] * u + b[1] * u * u + b[2] * u * u * u) * sy;
        value.is_finite().then_some(value)
    }
}

/// The 2-norm condition number of Eq. (3)'s matrix L for these x values (after scaling by
/// max|x|): how much the fit can amplify rounding. Infinite when L is singular.
pub fn fit_condition(x: &[f64; 4]) -> f64 {
    if !x.iter().all(|v| v.is_finite()) {
        return f64::INFINITY;
    }
    condition_of(&centred_moments(x).0)
}

/// (x, x², x³) of one scaled x value.
fn powers(v: f64) -> Vector3<f64> {
    Vector3::new(v, v * v, v * v * v)
}

/// Eq. (3)'s L_pq = Σ (x^p − x̄_p)(x^q − x̄_q) on x scaled by max|x|, the means x̄₁, x̄₂, x̄₃, the
/// scale max|x| and the scaled powers (x, x², x³) of each point.
fn centred_moments(x: &[f64; 4]) -> (Matrix3<f64>, Vector3<f64>, f64, [Vector3<f64>; 4]) {
    let sx = scale_of(x);
    let p = x.map(|v| powers(v / sx));
    let mean = p.iter().sum::<Vector3<f64>>() / 4.0;
    let mut l = Matrix3::zeros();
    for v in &p {
        let c = v - mean;
        l += c * c.transpose();
    }
    (l, mean, sx, p)
}

/// σ_max / σ_min of L. L = Σ c cᵀ is symmetric positive semi-definite, so its singular values
/// are its eigenvalues (their magnitudes, against rounding); infinite when L is singular.
fn condition_of(l: &Matrix3<f64>) -> f64 {
    // The eigenvalues alone (no eigenvectors): L is finite, and the implicit QR iteration
    // converges on every finite symmetric matrix.
    let magnitudes = l.symmetric_eigenvalues().abs();
    magnitudes.max() / magnitudes.min()
}

/// Whether L's condition number is surely below [`MAX_CONDITION`], from its trace and
/// determinant alone: for eigenvalues λ₁ ≥ λ₂ ≥ λ₃ > 0, λ₁ ≤ tr L and λ₁λ₂ ≤ (tr L / 2)², so
/// λ₃ = det L / (λ₁λ₂) ≥ 4 det L / tr² L and κ = λ₁/λ₃ ≤ tr³ L / (4 det L). Below 10¹⁰ that bound
/// leaves four orders of magnitude for the rounding of det L (relative error about κε), so the
/// eigenvalues of [`condition_of`] would find the fit conditioned too: the same verdict, without
/// the iteration (it was a third of the online calibrator's work on a calibration-dense stream).
fn surely_conditioned(l: &Matrix3<f64>) -> bool {
    const SURE: f64 = 1e10;
    let (trace, det) = (l.trace(), l.determinant());
    det > 0.0 && trace.powi(3) <= SURE * 4.0 * det
}

/// max|v|, or 1 when it is 0.
fn scale_of(v: &[f64; 4]) -> f64 {
    let m = v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    if m == 0.0 { 1.0 } else { m }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix4;
    use proptest::prelude::*;

    proptest! {
        /// The trace–determinant shortcut never accepts a fit the eigenvalues would refuse, over
        /// x values from well spread to nearly equal (spreads down to 1e-7 of their size), and it
        /// does accept the well-spread ones.
        #[test]
        fn the_shortcut_gives_the_eigenvalues_verdict(
            base in -10.0f64..10.0,
            offsets in prop::array::uniform4(0.0f64..1.0),
            log_spread in -7.0f64..1.0,
        ) {
            let spread = 10f64.powf(log_spread);
            let x = offsets.map(|o| base + o * spread);
            let l = centred_moments(&x).0;
            let condition = condition_of(&l);
            if surely_conditioned(&l) {
                prop_assert!(condition.is_finite() && condition <= 1e10 * (1.0 + 1e-6), "κ = {condition:e}");
            }
        }
    }

    #[test]
    fn the_shortcut_takes_well_spread_records() {
        for x in [
            [0.2, 0.35, 0.1, 0.4],
            [3.0, 1.0, 2.0, 5.0],
            [0.01, 0.02, 0.015, 0.03],
        ] {
            let l = centred_moments(&x).0;
            assert!(surely_conditioned(&l), "{x:?}: κ = {:e}", condition_of(&l));
        }
    }

    /// Eq. (4) solved directly: the 4×4 Vandermonde system interpolates four distinct points, and
    /// least squares with four coefficients on four points is the same interpolation.
    fn direct(x: &[f64; 4], y: &[f64; 4], x_new: f64) -> f64 {
        let v = Matrix4::from_fn(|r, c| x[r].powi(c as i32));
        let b = v.lu().solve(&nalgebra::Vector4::from(*y)).unwrap();
        (0..4).map(|c| b[c] * x_new.powi(c as i32)).sum()
    }

    #[test]
    fn matches_a_direct_four_by_four_solve() {
        let cases = [
            ([0.01, 0.02, 0.015, 0.03], [0.5, 0.55, 0.6, 0.52], 0.001),
            ([0.2, 0.35, 0.1, 0.4], [0.07, 0.066, 0.08, 0.05], 0.05),
            ([3.0, 1.0, 2.0, 5.0], [10.0, 12.0, 11.0, 9.0], 4.0),
        ];
        for (x, y, x_new) in cases {
            let ours = fit(&x, &y, x_new).unwrap();
            let reference = direct(&x, &y, x_new);
            assert!(
                (ours - reference).abs() <= 1e-8 * reference.abs().max(1.0),
                "{ours} vs {reference}"
            );
        }
    }

    #[test]
    fn constant_records_return_the_constant() {
        // Lock-in (SPEC sec. 4.4): equal y values fit a constant, whatever x is.
        let y = [0.3; 4];
        let at = fit(&[0.01, 0.02, 0.03, 0.05], &y, 0.001).unwrap();
        assert!((at - 0.3).abs() < 1e-12);
    }

    #[test]
    fn singular_inputs_give_nothing() {
        // All x equal: L is zero.
        assert_eq!(fit(&[0.1; 4], &[1.0, 2.0, 3.0, 4.0], 0.1), None);
        // Only two distinct x values: L has rank 1.
        assert_eq!(fit(&[0.1, 0.1, 0.2, 0.2], &[1.0, 2.0, 3.0, 4.0], 0.1), None);
        // Non-finite input.
        assert_eq!(
            fit(&[f64::NAN, 0.1, 0.2, 0.3], &[1.0, 2.0, 3.0, 4.0], 0.1),
            None
        );
    }

    #[test]
    fn zero_scales_count_as_one() {
        let at = fit(&[0.0, 1.0, 2.0, 3.0], &[0.0; 4], 1.5).unwrap();
        assert_eq!(at, 0.0);
    }
}
