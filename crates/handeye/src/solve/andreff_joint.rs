//! Andreff's solver in its simultaneous 12-unknown form, as OpenCV's `CALIB_HAND_EYE_ANDREFF`.

use nalgebra::{Matrix3, SMatrix, SVector};

use crate::model::error::{Degeneracy, Error, Result};
use crate::model::motion::MotionPair;
use crate::model::pose::{proj_so3, rotation_matrix};
use crate::solve::least_squares::least_squares_12;
use crate::solve::motions::MotionSource;
use crate::solve::quadratic::Quadratic;
use crate::solve::scale::{Scaled, length_scale, weighting_unit};
use crate::solve::{Calibration, Method, REFUSE_CONDITIONING, check_motions, finish, singular};

/// Andreff et al.'s linear solution with R_x and t_x as one 12-vector.
///
/// Eq. (10), per motion: `[I₉ − R_a ⊗ R_b, 0; I₃ ⊗ t_bᵀ, I₃ − R_a] (vec R_x, t_x) = (0, t_a)`
/// (row-major vec), stacked and solved in least squares; then (Eq. (15)) R_x is scaled to unit
/// determinant and projected onto SO(3), while t_x is kept as solved.
///
/// # References
/// N. Andreff, R. Horaud, B. Espiau, "On-line hand-eye calibration", 3DIM 1999.
///
/// # Example
/// ```
/// use handeye::{Method, MotionPair, Transform, solve};
/// use nalgebra::{Rotation3, Translation3, Vector3};
/// let x = Transform::from_parts(Translation3::new(0.1, 0.0, 0.05), Rotation3::from_euler_angles(0.1, 0.2, 0.3));
/// let a1 = Transform::new(Vector3::new(0.1, 0.2, 0.3), Vector3::new(0.5, 0.0, 0.0));
/// let a2 = Transform::new(Vector3::new(-0.2, 0.1, 0.4), Vector3::new(0.0, 0.4, 0.1));
/// let motions: Vec<_> = [a1, a2].iter().map(|a| MotionPair { a: *a, b: x.inverse() * a * x }).collect();
/// let cal = solve(Method::AndreffJoint, &motions)?;
/// assert!((cal.x.to_homogeneous() - x.to_homogeneous()).norm() < 1e-9);
/// # Ok::<(), handeye::Error>(())
/// ```
pub fn andreff_joint(motions: &(impl MotionSource + ?Sized)) -> Result<Calibration> {
    let check = check_motions(motions)?;
    // Eq. (10) stacks rotation rows (entries of order 1) on translation rows (entries of the
    // order of the data's lengths, in the input's unit): in kilometres or micrometres its normal
    // equations lose the smaller block entirely (X 1e-2 off at lengths ×1e8, t_x 100 % off at
    // ×1e-8, on exact data), and on noisy data the answer depends on the unit. It is solved in
    // units of the data's own RMS length, where both blocks are of order 1 whatever the input's
    // unit, and t_x scaled back (see `weighting_unit`).
    let unit = weighting_unit(motions);
    let scaled = Scaled::new(motions, unit);
    // Eq. (10) has more solutions than X whenever the gripper translations are explained by
    // rotations alone: t_a = 0 (eye-in-hand gripper turning about its own origin), or every
    // motion a rotation about one point c, t_a = (I − R_a) c (then (s R_x, s t_x + (1 − s) c)
    // solves it for every s). Least squares then returns the member of least norm, X or not
    // (measured: t_x 0.6 for 0.37 in the input's unit, a refusal at ×1e-8). The system's own
    // conditioning decides, with the threshold of the rotation system, measured in units of the
    // data's own scale (where both blocks of rows are of order 1, so that it is unit-free).
    let joint = match motions.all_pairs() {
        Some(pairs) => form_normal(&pairs.sums().quadratic().in_unit(length_scale(motions))).0,
        None => {
            let (mut joint, mut unused) =
                (SMatrix::<f64, 12, 12>::zeros(), SVector::<f64, 12>::zeros());
            Scaled::new(motions, length_scale(motions))
                .for_each_motion(|m| add_normal(m, &mut joint, &mut unused));
            joint.fill_lower_triangle_with_upper_triangle();
            joint
        }
    };
    let eigenvalues = joint.symmetric_eigenvalues();
    let joint_conditioning = (eigenvalues.min().max(0.0) / eigenvalues.max()).sqrt();
    let no_translation = || {
        let mut largest = 0.0_f64;
        motions.for_each_motion(|m| largest = largest.max(m.a.translation.vector.norm()));
        Error::Degenerate {
            reason: Degeneracy::NoTranslation { largest },
            conditioning: check.conditioning,
        }
    };
    if joint_conditioning.is_nan() || joint_conditioning < REFUSE_CONDITIONING {
        return Err(no_translation());
    }
    let x = match motions.all_pairs() {
        Some(pairs) => solve_form(&pairs.sums().quadratic().in_unit(unit)),
        None => least_squares_12(&scaled, add_normal, correction),
    }
    .ok_or_else(|| singular(check.conditioning))?;
    let raw = Matrix3::new(x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], x[8]);
    let det = raw.determinant();
    // The scale of vec(R_x) is fixed only by the gripper translations t_a (the right-hand side of
    // Eq. (10)); with none, the solution is 0. det(raw) = s³ for a solution s (R_x, t_x) is
    // unit-free: it measures t_a against the rest of the system (camera translations, t_x) in
    // the solve's units, so exact data gives det = 1 (or 0 without translation) at every scale,
    // and the decision no longer flips with the unit once the normal equations stop losing the
    // translation rows. OpenCV refuses |det| below single-precision epsilon likewise.
    if det.is_nan() || det.abs() < f64::from(f32::EPSILON) {
        return Err(no_translation());
    }
    let r_x = proj_so3(&(raw * det.signum()));
    let t_x = x.fixed_rows::<3>(9) * unit;
    Ok(finish(
        Method::AndreffJoint,
        motions.count(),
        check,
        &r_x,
        &t_x,
    ))
}

/// The normal equations of Eq. (10) from the quadratic form of the same motions' residuals
/// ([`Quadratic`], O(1) for every pair of n poses once its O(n) sums are made): Eq. (10)'s rows
/// are ΔR and ΔT up to a rotation and a sign, so Σ‖C x − d‖² = zᵀ M z for z = (x, 1) with
/// M = M_R ⊕ 0 + M_T. Hence CᵀC is M's leading 12×12 block and Cᵀd = −M[0..12, 12].
fn form_normal(form: &Quadratic) -> (SMatrix<f64, 12, 12>, SVector<f64, 12>) {
    let mut normal: SMatrix<f64, 12, 12> = form.translation.fixed_view::<12, 12>(0, 0).into_owned();
    let mut rotation = normal.fixed_view_mut::<9, 9>(0, 0);
    rotation += form.rotation;
    let rhs = -form.translation.fixed_view::<12, 1>(0, 12).into_owned();
    (normal, rhs)
}

/// Eq. (10) solved from its normal equations made by [`form_normal`] (LU). The refinement step of
/// [`least_squares_12`] would need the motions one by one; without it the error is the normal
/// equations' ε·κ², within the 1e-9 of the motion-by-motion solve that `tests/all_pairs.rs`
/// asserts (4e-12 on the whole report at 1,000 simulated poses).
fn solve_form(form: &Quadratic) -> Option<SVector<f64, 12>> {
    let (normal, rhs) = form_normal(form);
    let x = normal.lu().solve(&rhs)?;
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Adds one motion's share of the normal equations of Eq. (10) to `n` (its upper triangle) and
/// `r`: (CᵀC, Cᵀd) for its 12 rows C = [I₉ − K, 0; T, I₃ − R_a], d = (0, t_a), with K = R_a ⊗ R_b
/// and T = I₃ ⊗ t_bᵀ, formed block by block instead of as a 12×12 product (that product was half
/// of an all-pairs solve):
/// - (I − K)ᵀ(I − K) = I − K − Kᵀ + (R_aᵀR_a) ⊗ (R_bᵀR_b) (mixed product), plus
///   TᵀT = I₃ ⊗ t_b t_bᵀ;
/// - the coupling Tᵀ(I − R_a): entry (3i + k, j) = t_b[k] (δ_ij − R_a[i, j]);
/// - (I − R_a)ᵀ(I − R_a) for t_x; Cᵀd = (vec(t_a t_bᵀ), (I − R_a)ᵀ t_a).
fn add_normal(m: &MotionPair, n: &mut SMatrix<f64, 12, 12>, r: &mut SVector<f64, 12>) {
    let r_a = rotation_matrix(&m.a);
    let r_b = rotation_matrix(&m.b);
    let (t_a, t_b) = (m.a.translation.vector, m.b.translation.vector);
    let (a_a, b_b) = (r_a.transpose() * r_a, r_b.transpose() * r_b);
    let i_ra = Matrix3::identity() - r_a;
    for i in 0..3 {
        for k in 0..3 {
            let row = 3 * i + k;
            for j in i..3 {
                for l in 0..3 {
                    // K[(3i+k, 3j+l)] = R_a[i,j] R_b[k,l]; Kᵀ's entry is K's transposed one.
                    let col = 3 * j + l;
                    if col < row {
                        continue;
                    }
                    let delta = if row == col { 1.0 } else { 0.0 };
                    let t = if i == j { t_b[k] * t_b[l] } else { 0.0 };
                    n[(row, col)] += delta - r_a[(i, j)] * r_b[(k, l)] - r_a[(j, i)] * r_b[(l, k)]
                        + a_a[(i, j)] * b_b[(k, l)]
                        + t;
                }
            }
            for j in 0..3 {
                n[(row, 9 + j)] += t_b[k] * i_ra[(i, j)];
            }
            r[row] += t_a[i] * t_b[k];
        }
    }
    let mut block = n.fixed_view_mut::<3, 3>(9, 9);
    block += i_ra.transpose() * i_ra;
    let mut tail = r.fixed_rows_mut::<3>(9);
    tail += i_ra.transpose() * t_a;
}

/// One motion's share of the refinement step of [`least_squares_12`]: Cᵀ(d − C x) for the rows of
/// [`add_normal`], through 3×3 products: with X the row-major 3×3 of x[0..9], (I − K) vec X =
/// vec(X − R_a X R_bᵀ) and Kᵀ vec E = vec(R_aᵀ E R_b).
fn correction(m: &MotionPair, x: &SVector<f64, 12>) -> SVector<f64, 12> {
    let r_a = rotation_matrix(&m.a);
    let r_b = rotation_matrix(&m.b);
    let (t_a, t_b) = (m.a.translation.vector, m.b.translation.vector);
    let r_x = Matrix3::new(x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], x[8]);
    let t_x = x.fixed_rows::<3>(9).into_owned();
    let i_ra = Matrix3::identity() - r_a;
    // The residuals d − C x, of the rotation rows (as a 3×3) and of the translation rows.
    let e = -(r_x - r_a * r_x * r_b.transpose());
    let f = t_a - (r_x * t_b + i_ra * t_x);
    let rot = e - r_a.transpose() * e * r_b + f * t_b.transpose();
    let mut out = SVector::<f64, 12>::zeros();
    for i in 0..3 {
        for l in 0..3 {
            out[3 * i + l] = rot[(i, l)];
        }
    }
    out.fixed_rows_mut::<3>(9)
        .copy_from(&(i_ra.transpose() * f));
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::pose::Transform;
    use nalgebra::Vector3;

    /// The 12 rows of Eq. (10) for one motion, as the equation writes them.
    fn rows(m: &MotionPair) -> (SMatrix<f64, 12, 12>, SVector<f64, 12>) {
        let r_a = rotation_matrix(&m.a);
        let r_b = rotation_matrix(&m.b);
        let t_b = m.b.translation.vector;
        let mut c = SMatrix::<f64, 12, 12>::zeros();
        for i in 0..3 {
            for j in 0..3 {
                for k in 0..3 {
                    for l in 0..3 {
                        c[(3 * i + k, 3 * j + l)] = -r_a[(i, j)] * r_b[(k, l)];
                    }
                }
            }
        }
        for d in 0..9 {
            c[(d, d)] += 1.0;
        }
        for i in 0..3 {
            for l in 0..3 {
                c[(9 + i, 3 * i + l)] = t_b[l];
            }
            for j in 0..3 {
                c[(9 + i, 9 + j)] = if i == j { 1.0 } else { 0.0 } - r_a[(i, j)];
            }
        }
        let mut d = SVector::<f64, 12>::zeros();
        d.fixed_rows_mut::<3>(9).copy_from(&m.a.translation.vector);
        (c, d)
    }

    #[test]
    fn the_blocks_are_the_products_of_the_rows() {
        let motion = |w: [f64; 3], t: [f64; 3]| Transform::new(Vector3::from(t), Vector3::from(w));
        let m = MotionPair {
            a: motion([0.3, -0.2, 0.9], [0.4, -1.3, 0.25]),
            b: motion([-0.5, 0.7, 0.1], [2.0, 0.3, -0.8]),
        };
        let x = SVector::<f64, 12>::from_fn(|i, _| (i as f64 * 0.37).sin());
        let (c, d) = rows(&m);
        let (mut n, mut r) = (SMatrix::zeros(), SVector::zeros());
        add_normal(&m, &mut n, &mut r);
        n.fill_lower_triangle_with_upper_triangle();
        assert!(
            (n - c.transpose() * c).norm() < 1e-12,
            "{}",
            n - c.transpose() * c
        );
        assert!((r - c.transpose() * d).norm() < 1e-12);
        let want = c.transpose() * (d - c * x);
        assert!((correction(&m, &x) - want).norm() < 1e-12, "{want}");
    }
}
