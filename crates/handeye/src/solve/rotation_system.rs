//! Andreff's rotation system, accumulated as a 9×9 normal matrix.

use nalgebra::{Matrix3, SMatrix, SVector, SymmetricEigen};
use serde::{Deserialize, Serialize};

use crate::pose::proj_so3;

/// A 9×9 matrix.
type Matrix9 = SMatrix<f64, 9, 9>;

/// The normal matrix `M = Σ_k K_kᵀ K_k` of Andreff's rotation system, `K_k = I₉ − R_a,k ⊗ R_b,k`
/// (row-major vec, so that `K vec(R_x) = vec(R_x − R_a R_x R_bᵀ)` = 0 for the true R_x).
///
/// Since `R_a ⊗ R_b` is orthogonal, `KᵀK = 2I − (R_a ⊗ R_b) − (R_a ⊗ R_b)ᵀ`: each motion costs 81
/// products and the memory is constant however many motions are added. The right singular
/// vectors and singular values of the stacked 9m×9 matrix are the eigenvectors and square roots of
/// the eigenvalues of `M`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RotationSystem {
    normal: Matrix9,
    motions: usize,
}

impl Default for RotationSystem {
    fn default() -> Self {
        Self { normal: Matrix9::zeros(), motions: 0 }
    }
}

/// What the rotation system gives: R_x and how well it is determined.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RotationSolution {
    /// The rotation of X, projected onto SO(3).
    pub r_x: Matrix3<f64>,
    /// Second-smallest over largest singular value of the stacked system.
    pub conditioning: f64,
}

impl RotationSystem {
    /// Adds one motion pair's rotations (R_a, R_b).
    pub fn add(&mut self, r_a: &Matrix3<f64>, r_b: &Matrix3<f64>) {
        self.add_weighted(r_a, r_b, 1.0);
    }

    /// Adds one motion pair's rotations with weight `w` (its rows scaled by √w).
    pub fn add_weighted(&mut self, r_a: &Matrix3<f64>, r_b: &Matrix3<f64>, w: f64) {
        for i in 0..3 {
            for j in 0..3 {
                let a = r_a[(i, j)];
                for k in 0..3 {
                    for l in 0..3 {
                        // (R_a ⊗ R_b)[(3i+k, 3j+l)] = R_a[i,j] R_b[k,l]; it enters M as −K − Kᵀ.
                        let v = w * a * r_b[(k, l)];
                        self.normal[(3 * i + k, 3 * j + l)] -= v;
                        self.normal[(3 * j + l, 3 * i + k)] -= v;
                    }
                }
            }
        }
        for d in 0..9 {
            self.normal[(d, d)] += 2.0 * w;
        }
        self.motions += 1;
    }

    /// Number of motion pairs added.
    pub fn motions(&self) -> usize {
        self.motions
    }

    /// The accumulated 9×9 normal matrix.
    pub fn normal_matrix(&self) -> &SMatrix<f64, 9, 9> {
        &self.normal
    }

    /// Second-smallest over largest singular value of the stacked system (0 when empty).
    pub fn conditioning(&self) -> f64 {
        let eigen = SymmetricEigen::new(self.normal);
        conditioning_of(&eigen.eigenvalues)
    }

    /// Solves for R_x (SPEC sec. 3, `andreff`): the eigenvector of the smallest eigenvalue of `M`
    /// is vec(R_x) up to scale; its sign is chosen so that det > 0, then it is projected onto SO(3)
    /// with `U diag(1, 1, det(UVᵀ)) Vᵀ`.
    pub fn solve(&self) -> RotationSolution {
        let eigen = SymmetricEigen::new(self.normal);
        let smallest = eigen.eigenvalues.imin();
        let v: SVector<f64, 9> = eigen.eigenvectors.column(smallest).into_owned();
        // Row-major vec: v = (r11, r12, r13, r21, …).
        let mut m = Matrix3::new(v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8]);
        if m.determinant() < 0.0 {
            m = -m;
        }
        RotationSolution { r_x: proj_so3(&m), conditioning: conditioning_of(&eigen.eigenvalues) }
    }
}

/// √(λ₂ / λ_max) from the eigenvalues of the normal matrix, λ₂ the second smallest.
fn conditioning_of(eigenvalues: &SVector<f64, 9>) -> f64 {
    let mut sorted: [f64; 9] = eigenvalues.as_slice().try_into().unwrap_or([0.0; 9]);
    sorted.sort_by(f64::total_cmp);
    let largest = sorted[8];
    if largest.is_nan() || largest <= 0.0 {
        return 0.0;
    }
    (sorted[1].max(0.0) / largest).sqrt()
}
