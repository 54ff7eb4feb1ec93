//! The squared A X − X B residuals of a set of motions as one quadratic form in
//! z = [vec R_x; t_x; 1] ([`Quadratic`]): what the all-pairs sums accumulate
//! (`solve::accumulate::PairSums`) and the refinement minimises in O(1) per iteration
//! (`solve::residual`, its `Residuals` implementation).

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use crate::model::pose::skew;

/// A 9×9 matrix.
pub(crate) type Matrix9 = SMatrix<f64, 9, 9>;
/// A 13×13 matrix: the quadratic form of ΔT in z = [vec R_x; t_x; 1].
pub(crate) type Matrix13 = SMatrix<f64, 13, 13>;
/// z = [vec R_x; t_x; 1].
pub(crate) type Vector13 = SVector<f64, 13>;

/// The squared residuals of a set of motions as a quadratic form in z = [vec R_x; t_x; 1]:
/// Σ‖ΔR‖²_F = vec(R_x)ᵀ M_R vec(R_x) with M_R = Σ (2I − R_a ⊗ R_b − (R_a ⊗ R_b)ᵀ), Andreff's
/// rotation normal matrix, and Σ‖ΔT‖² = zᵀ M_T z with M_T = Σ L_kᵀ L_k,
/// L_k = [−(I ⊗ t_bᵀ), R_a − I, t_a] (module documentation).
///
/// With J_z the 13×6 derivative of z for the increment `R_x exp([δ]×)`, `t_x + Δt`, the normal
/// equations of the weighted residuals are `JᵀJ = J_zᵀ M J_z`, `Jᵀr = J_zᵀ M z`, M the weighted
/// sum of the two forms: O(1) whatever the number of motions. The sums of squares come out as
/// differences of large terms: they carry an absolute rounding error of about ε‖M‖‖z‖², which
/// on noise-free data is far above the residuals themselves.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Quadratic {
    /// M_R (9×9, acting on vec R_x).
    pub(crate) rotation: Matrix9,
    /// M_T (13×13, acting on z).
    pub(crate) translation: Matrix13,
    /// Motions summed.
    pub(crate) motions: usize,
}

/// z = [vec R_x; t_x; 1].
pub(crate) fn z_of(r_x: &Matrix3<f64>, t_x: &Vector3<f64>) -> Vector13 {
    let mut z = Vector13::zeros();
    for k in 0..9 {
        z[k] = r_x[(k / 3, k % 3)];
    }
    z.fixed_rows_mut::<3>(9).copy_from(t_x);
    z[12] = 1.0;
    z
}

/// J_z = ∂z/∂(δ, Δt) at R_x: column m < 3 is vec(R_x [e_m]×), columns 3..6 the identity on t_x.
pub(crate) fn z_jacobian(r_x: &Matrix3<f64>) -> SMatrix<f64, 13, 6> {
    let mut j = SMatrix::<f64, 13, 6>::zeros();
    for c in 0..3 {
        let d = r_x * skew(&Vector3::ith(c, 1.0));
        for k in 0..9 {
            j[(k, c)] = d[(k / 3, k % 3)];
        }
        j[(9 + c, 3 + c)] = 1.0;
    }
    j
}

impl Quadratic {
    /// The form of the same motions with every length divided by `unit` (a power of two, so
    /// exactly): ΔT/unit in z' = [vec R_x; t_x/unit; 1], i.e. `E M_T E / unit²`,
    /// E = diag(1₉, unit·1₃, 1).
    pub(crate) fn in_unit(&self, unit: f64) -> Self {
        let e = Vector13::from_fn(|k, _| if (9..12).contains(&k) { unit } else { 1.0 });
        let translation =
            Matrix13::from_fn(|r, c| self.translation[(r, c)] * e[r] * e[c] / (unit * unit));
        Self {
            rotation: self.rotation,
            translation,
            motions: self.motions,
        }
    }

    /// The weighted 13×13 form w_R² M_R ⊕ 0 + w_T² M_T.
    pub(crate) fn weighted(&self, weights: [f64; 2]) -> Matrix13 {
        let mut m = self.translation * (weights[1] * weights[1]);
        let rotation = self.rotation * (weights[0] * weights[0]);
        let mut top = m.fixed_view_mut::<9, 9>(0, 0);
        top += rotation;
        m
    }
}
