//! Stacked linear least squares through accumulated normal equations, with one step of iterative
//! refinement: constant memory however many motions, and the accuracy of a QR solve.

use nalgebra::{SMatrix, SVector};

use crate::model::motion::MotionPair;
use crate::solve::motions::MotionSource;

/// Defines a least-squares solver for R-row blocks in N unknowns (nalgebra's LU needs concrete
/// sizes).
macro_rules! stacked {
    ($name:ident, $r:literal, $n:literal) => {
        /// Solves `min Σ_k ‖C_k x − d_k‖²` over the motions, where `rows(m)` gives the block `C_k`
        /// and the vector `d_k` of one motion.
        ///
        /// The normal equations `(Σ CᵀC) x = Σ Cᵀd` are solved by LU, then corrected once with
        /// the residuals `d − C x` evaluated block by block: the normal equations' ε·κ² error
        /// becomes the ε·κ of an orthogonal factorisation. `None` when the normal matrix is
        /// singular.
        pub fn $name(
            motions: &(impl MotionSource + ?Sized),
            rows: impl Fn(&MotionPair) -> (SMatrix<f64, $r, $n>, SVector<f64, $r>),
        ) -> Option<SVector<f64, $n>> {
            let mut normal = SMatrix::<f64, $n, $n>::zeros();
            let mut rhs = SVector::<f64, $n>::zeros();
            motions.for_each_motion(|m| {
                let (c, d) = rows(m);
                normal += c.transpose() * c;
                rhs += c.transpose() * d;
            });
            let lu = normal.lu();
            let mut x = lu.solve(&rhs)?;
            let mut correction = SVector::<f64, $n>::zeros();
            motions.for_each_motion(|m| {
                let (c, d) = rows(m);
                correction += c.transpose() * (d - c * x);
            });
            x += lu.solve(&correction)?;
            x.iter().all(|v| v.is_finite()).then_some(x)
        }
    };
}

stacked!(least_squares_3, 3, 3);

/// The stacked least squares of [`least_squares_3`] in 12 unknowns, with each motion's
/// contributions given directly: `add_normal(m, n, r)` adds the upper triangle of CᵀC to `n` (the
/// lower one is filled from it once, at the end) and Cᵀd to `r`, and `correction(m, x)` is
/// Cᵀ(d − C x). For a structured C (Andreff's Eq. (10)) these cost a fraction of forming the 12×12
/// product.
pub(crate) fn least_squares_12(
    motions: &(impl MotionSource + ?Sized),
    add_normal: impl Fn(&MotionPair, &mut SMatrix<f64, 12, 12>, &mut SVector<f64, 12>),
    correction: impl Fn(&MotionPair, &SVector<f64, 12>) -> SVector<f64, 12>,
) -> Option<SVector<f64, 12>> {
    let mut lhs = SMatrix::<f64, 12, 12>::zeros();
    let mut rhs = SVector::<f64, 12>::zeros();
    motions.for_each_motion(|m| add_normal(m, &mut lhs, &mut rhs));
    lhs.fill_lower_triangle_with_upper_triangle();
    let lu = lhs.lu();
    let mut x = lu.solve(&rhs)?;
    let mut total = SVector::<f64, 12>::zeros();
    motions.for_each_motion(|m| total += correction(m, &x));
    x += lu.solve(&total)?;
    x.iter().all(|v| v.is_finite()).then_some(x)
}
