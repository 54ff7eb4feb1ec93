//! Daniilidis' dual-quaternion solver, as OpenCV's `CALIB_HAND_EYE_DANIILIDIS` computes it.

use nalgebra::{Matrix3, Matrix4, SMatrix, SVector, SymmetricEigen, Vector3, Vector4};

use crate::model::error::Result;
use crate::model::motion::MotionPair;
use crate::model::pose::{rotation_matrix, skew};
use crate::solve::motions::{AllPairs, MotionSource};
use crate::solve::quaternion::{Signs, motion_quaternions, multiply, quaternion_of, rotation_of};
use crate::solve::scale::{Scaled, weighting_unit};
use crate::solve::{Calibration, Method, check_motions, finish, singular};

/// Daniilidis' simultaneous solution with dual quaternions.
///
/// Each motion gives 6 rows of Eq. (31) in the 8 entries of X's dual quaternion (q, q'):
/// `[a − b, [a + b]×, 0, 0; a' − b', [a' + b']×, a − b, [a + b]×]`, with a, a' (b, b') the vector
/// parts of the dual quaternion of A (B). X lies in the span of the two right singular vectors
/// of the smallest singular values (found from the 8×8 normal matrix); Eqs. (34)–(35) fix the
/// combination that is a unit dual quaternion (solved in a form that stays finite where OpenCV's
/// divides by zero).
///
/// Over every pair of a pose sequence ([`AllPairs`]) the normal matrix comes from per-pose sums in
/// O(n) (the same matrix up to rounding, see `pairs_normal`) instead of the n(n − 1)/2 motions.
///
/// # References
/// K. Daniilidis, "Hand-eye calibration using dual quaternions", IJRR 18(3), 1999.
///
/// # Example
/// ```
/// use handeye::{Method, MotionPair, Transform, solve};
/// use nalgebra::{Rotation3, Translation3, Vector3};
/// let x = Transform::from_parts(Translation3::new(0.1, 0.0, 0.05), Rotation3::from_euler_angles(0.1, 0.2, 0.3));
/// let a1 = Transform::new(Vector3::new(0.1, 0.2, 0.3), Vector3::new(0.5, 0.0, 0.0));
/// let a2 = Transform::new(Vector3::new(-0.2, 0.1, 0.4), Vector3::new(0.0, 0.4, 0.1));
/// let motions: Vec<_> = [a1, a2].iter().map(|a| MotionPair { a: *a, b: x.inverse() * a * x }).collect();
/// let cal = solve(Method::Daniilidis, &motions)?;
/// assert!((cal.x.to_homogeneous() - x.to_homogeneous()).norm() < 1e-9);
/// # Ok::<(), handeye::Error>(())
/// ```
pub fn daniilidis(motions: &(impl MotionSource + ?Sized)) -> Result<Calibration> {
    let check = check_motions(motions)?;
    // The rows of Eq. (31) mix the real parts (order 1) with the dual parts (order the data's
    // lengths): in the input's unit the eigenvectors lose digits as lengths grow or shrink (1e-2
    // at lengths ×1e8 on exact data), and on noisy data the answer depends on the unit (26° in
    // millimetres from the answer in metres, on a real recording). It is solved in units of the
    // data's own RMS length, where both are of order 1 whatever the input's unit, and t_x scaled
    // back (see `weighting_unit`).
    let unit = weighting_unit(motions);
    let r_x0 = check.andreff_rotation;
    let normal = match motions
        .all_pairs()
        .and_then(|p| pairs_normal(p, unit, &r_x0))
    {
        Some(normal) => normal,
        None => {
            let mut normal = SMatrix::<f64, 8, 8>::zeros();
            Scaled::new(motions, unit).for_each_motion(|m| {
                let t = rows(m, &r_x0);
                normal += t.transpose() * t;
            });
            normal
        }
    };
    let eigen = SymmetricEigen::new(normal);
    let mut order: [usize; 8] = std::array::from_fn(|k| k);
    order.sort_by(|&i, &j| eigen.eigenvalues[i].total_cmp(&eigen.eigenvalues[j]));
    // OpenCV's v6 and v7: the second-smallest and the smallest singular vectors.
    let v6: SVector<f64, 8> = eigen.eigenvectors.column(order[1]).into_owned();
    let v7: SVector<f64, 8> = eigen.eigenvectors.column(order[0]).into_owned();
    let (u1, w1) = split(&v6);
    let (u2, w2) = split(&v7);
    // Eq. (34): (λ₁, λ₂) makes the real part orthogonal to the dual part:
    // a λ₁² + b λ₁λ₂ + c λ₂² = 0. Its two root directions are taken by the stable quadratic formula,
    // in λ₁/λ₂ or λ₂/λ₁ whichever has the larger leading coefficient (OpenCV divides by a, which
    // fails when the solution lies along v7).
    let a = u1.dot(&w1);
    let b = u1.dot(&w2) + u2.dot(&w1);
    let c = u2.dot(&w2);
    let root = (b * b - 4.0 * a * c).max(0.0).sqrt();
    let q = -0.5 * (b + root.copysign(b));
    let directions = if a.abs() >= c.abs() {
        [(q / a, 1.0), (c / q, 1.0)]
    } else {
        [(1.0, q / c), (1.0, a / q)]
    };
    // Eq. (35): of the two, the one whose real part is longer (for unit (λ₁, λ₂), so that a
    // direction along v7 with its vanishing real part is not mistaken for the answer), scaled to a
    // unit real part.
    let norm = |(l1, l2): (f64, f64)| (u1 * l1 + u2 * l2).norm_squared() / (l1 * l1 + l2 * l2);
    let best = if norm(directions[0]) >= norm(directions[1]) {
        directions[0]
    } else {
        directions[1]
    };
    let scale = 1.0 / (u1 * best.0 + u2 * best.1).norm();
    let (lambda1, lambda2) = (best.0 * scale, best.1 * scale);
    let dual = v6 * lambda1 + v7 * lambda2;
    if !dual.iter().all(|v| v.is_finite()) {
        return Err(singular(check.conditioning));
    }
    let (q, q_prime) = split(&dual);
    let r_x = rotation_of(&q);
    let conjugate = Vector4::new(q[0], -q[1], -q[2], -q[3]);
    let t = multiply(&q_prime, &conjugate) * 2.0;
    let t_x = Vector3::new(t[1], t[2], t[3]) * unit;
    Ok(finish(
        Method::Daniilidis,
        motions.count(),
        check,
        &r_x,
        &t_x,
    ))
}

/// The real and dual halves of an 8-vector.
fn split(v: &SVector<f64, 8>) -> (Vector4<f64>, Vector4<f64>) {
    (
        v.fixed_rows::<4>(0).into_owned(),
        v.fixed_rows::<4>(4).into_owned(),
    )
}

/// The dual part q' = ½ (0, t) ⊗ q of a motion's dual quaternion with real part q.
fn dual_part(q: &Vector4<f64>, t: &Vector3<f64>) -> Vector4<f64> {
    multiply(&Vector4::new(0.0, t.x, t.y, t.z), q) * 0.5
}

/// The 6 rows of Eq. (31) for one motion; `r_x0` is a first estimate of R_x.
///
/// Eq. (31) drops the scalar equations a₀ = b₀, a₀' = b₀' of the screw congruence theorem, which
/// hold only for one sign of B's dual quaternion (q_b, q_b') relative to A's. Away from 180° the
/// canonical w ≥ 0 of both real parts is that sign; at 180° (a₀ = b₀ = 0) it is rounding noise
/// and the wrong sign gives six false rows. The sign of q_b (and with it q_b') is taken from
/// `r_x0` (see `motion_quaternions`).
fn rows(m: &MotionPair, r_x0: &Matrix3<f64>) -> SMatrix<f64, 6, 8> {
    let (qa, qb) = motion_quaternions(
        &rotation_matrix(&m.a),
        &rotation_matrix(&m.b),
        r_x0,
        Signs::Agreeing,
    );
    let qa_ = dual_part(&qa, &m.a.translation.vector);
    let qb_ = dual_part(&qb, &m.b.translation.vector);
    rows_of(&qa, &qb, &qa_, &qb_)
}

/// The rows of Eq. (31) from the dual quaternions (q_a, q_a') of A and (q_b, q_b') of B.
fn rows_of(
    qa: &Vector4<f64>,
    qb: &Vector4<f64>,
    qa_: &Vector4<f64>,
    qb_: &Vector4<f64>,
) -> SMatrix<f64, 6, 8> {
    let vec = |q: &Vector4<f64>| Vector3::new(q[1], q[2], q[3]);
    let (a, b, a_, b_) = (vec(qa), vec(qb), vec(qa_), vec(qb_));
    let mut t = SMatrix::<f64, 6, 8>::zeros();
    t.fixed_view_mut::<3, 1>(0, 0).copy_from(&(a - b));
    t.fixed_view_mut::<3, 3>(0, 1).copy_from(&skew(&(a + b)));
    t.fixed_view_mut::<3, 1>(3, 0).copy_from(&(a_ - b_));
    t.fixed_view_mut::<3, 3>(3, 1).copy_from(&skew(&(a_ + b_)));
    t.fixed_view_mut::<3, 1>(3, 4).copy_from(&(a - b));
    t.fixed_view_mut::<3, 3>(3, 5).copy_from(&skew(&(a + b)));
    t
}

/// Per-pose dual quaternions of Q_k and C_k: (q_Q, q_Q', q_C, q_C'), translations in `unit`.
type PoseDual = SVector<f64, 16>;

/// A pose's disagreement with the common frame must stay within this angle in R⁴ of the
/// reference (41.4°: a rotation of 82.8°) for the per-pose signs to be the per-motion ones; the
/// pairwise angle is then below 90° and every pair's sign agreement has a clear sign.
const SIGN_AGREEMENT: f64 = 0.75;

/// The normal matrix of Eq. (31) over every pair of poses, from per-pose sums in O(n); `None` when
/// the per-pose signs cannot be shown to be the per-motion ones (then the motions are summed one
/// by one).
///
/// The motion from pose j to pose i is A = Q_j⁻¹ Q_i, B = C_j C_i⁻¹, so its dual quaternions are
/// q̂_A = q̂_Qj* ⊗ q̂_Qi and q̂_B = q̂_Cj ⊗ q̂_Ci*: bilinear in the poses' dual quaternions w_j, w_i
/// (16 numbers each), and so are the rows, T_ji = Σ_pq w_jp w_iq G_pq. Over all ordered pairs
/// (T_ij = −T_ji, T_ii = 0, so twice the sum over i < j) the normal matrix is then
/// Σ_r Σ_pqp'q' G_pq[r, k] M_pp' M_qq' G_p'q'[r, l] with M = Σ_k w_k w_kᵀ.
///
/// The rows hold for one relative sign of q_B and q_A per motion; [`motion_quaternions`] takes the
/// sign of (q_A ⊗ q_x) · (q_x ⊗ q_B) = f_i · f_j with f_k = q_Qk ⊗ q_x ⊗ q_Ck (q_x from `r_x0`).
/// The per-pose sign of q_Ck makes f_k agree with a reference f (the mean direction of the f_k);
/// when every f_k is within [`SIGN_AGREEMENT`] of it, every f_i · f_j > 0 and the signs of all
/// pairs are exactly those [`motion_quaternions`] chooses: the same system, up to rounding.
fn pairs_normal(pairs: &AllPairs, unit: f64, r_x0: &Matrix3<f64>) -> Option<SMatrix<f64, 8, 8>> {
    let n = pairs.poses();
    let q_x = quaternion_of(r_x0);
    let mut poses: Vec<(PoseDual, Vector4<f64>)> = Vec::with_capacity(n);
    let mut spread = Matrix4::zeros();
    for k in 0..n {
        let (hand, camera) = pairs.pose(k);
        let q_q = quaternion_of(&rotation_matrix(hand));
        let q_c = quaternion_of(&rotation_matrix(camera));
        let f = multiply(&multiply(&q_q, &q_x), &q_c);
        spread += f * f.transpose();
        let mut w = PoseDual::zeros();
        w.fixed_rows_mut::<4>(0).copy_from(&q_q);
        w.fixed_rows_mut::<4>(4)
            .copy_from(&dual_part(&q_q, &(hand.translation.vector / unit)));
        w.fixed_rows_mut::<4>(8).copy_from(&q_c);
        w.fixed_rows_mut::<4>(12)
            .copy_from(&dual_part(&q_c, &(camera.translation.vector / unit)));
        poses.push((w, f));
    }
    let eigen = SymmetricEigen::new(spread);
    let reference: Vector4<f64> = eigen
        .eigenvectors
        .column(eigen.eigenvalues.imax())
        .into_owned();
    let mut moments = SMatrix::<f64, 16, 16>::zeros();
    for (w, f) in &mut poses {
        let agreement = f.dot(&reference) / f.norm();
        if agreement.is_nan() || agreement.abs() <= SIGN_AGREEMENT {
            return None;
        }
        if agreement < 0.0 {
            // −q_C, and with it −q_C'.
            w.fixed_rows_mut::<8>(8).neg_mut();
        }
        moments += *w * w.transpose();
    }
    // Σ_r Σ G_k[p, q] G_l[p', q'] M[p, p'] M[q', q] over the non-zero entries of the G tables
    // (a few per table: the dense 16×16 products were 150 µs whatever n, more than the whole
    // per-motion sum at ten poses).
    let mut normal = SMatrix::<f64, 8, 8>::zeros();
    for row in sparse_pair_rows() {
        for k in 0..8 {
            for l in k..8 {
                let mut sum = 0.0;
                for &(p, q, a) in &row[k] {
                    for &(p2, q2, b) in &row[l] {
                        sum += a * b * moments[(p, p2)] * moments[(q2, q)];
                    }
                }
                normal[(k, l)] += 0.5 * sum;
                if l != k {
                    normal[(l, k)] += 0.5 * sum;
                }
            }
        }
    }
    normal.iter().all(|v| v.is_finite()).then_some(normal)
}

/// The tables of [`pair_rows`] as their non-zero entries (p, q, G_pq).
type SparseRows = [[Vec<(usize, usize, f64)>; 8]; 6];

/// The non-zero entries (p, q, G_pq) of each table of [`pair_rows`] (made once).
fn sparse_pair_rows() -> &'static SparseRows {
    static ROWS: std::sync::OnceLock<SparseRows> = std::sync::OnceLock::new();
    ROWS.get_or_init(|| {
        pair_rows().map(|row| {
            row.map(|g| {
                let mut entries = Vec::new();
                for p in 0..16 {
                    for q in 0..16 {
                        if g[(p, q)] != 0.0 {
                            entries.push((p, q, g[(p, q)]));
                        }
                    }
                }
                entries
            })
        })
    })
}

/// G_pq[r][k] of [`pairs_normal`] as 16×16 matrices over (p, q): entry (r, k) of the rows of the
/// motion from a pose e_p to a pose e_q ([`sparse_pair_rows`] keeps their non-zero entries).
fn pair_rows() -> [[SMatrix<f64, 16, 16>; 8]; 6] {
    let conj = |q: &Vector4<f64>| Vector4::new(q[0], -q[1], -q[2], -q[3]);
    let basis = |p: usize| PoseDual::from_fn(|i, _| if i == p { 1.0 } else { 0.0 });
    let parts = |w: &PoseDual| {
        let q = |k: usize| w.fixed_rows::<4>(4 * k).into_owned();
        (q(0), q(1), q(2), q(3))
    };
    let mut g = [[SMatrix::<f64, 16, 16>::zeros(); 8]; 6];
    for p in 0..16 {
        let (qj, qj_, cj, cj_) = parts(&basis(p));
        for q in 0..16 {
            let (qi, qi_, ci, ci_) = parts(&basis(q));
            let qa = multiply(&conj(&qj), &qi);
            let qa_ = multiply(&conj(&qj_), &qi) + multiply(&conj(&qj), &qi_);
            let qb = multiply(&cj, &conj(&ci));
            let qb_ = multiply(&cj_, &conj(&ci)) + multiply(&cj, &conj(&ci_));
            let t = rows_of(&qa, &qb, &qa_, &qb_);
            for (r, row) in g.iter_mut().enumerate() {
                for (k, entry) in row.iter_mut().enumerate() {
                    entry[(p, q)] = t[(r, k)];
                }
            }
        }
    }
    g
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::motion::{Pairing, PosePair, Setup, motion_pairs};
    use crate::sim::{SimConfig, simulate};

    fn both(
        poses: &[PosePair],
        setup: Setup,
    ) -> (crate::model::pose::Transform, crate::model::pose::Transform) {
        let pairs = AllPairs::new(poses, setup);
        let listed = motion_pairs(poses, Pairing::All, setup);
        (
            daniilidis(&pairs).unwrap().x,
            daniilidis(&listed).unwrap().x,
        )
    }

    #[test]
    fn the_per_pose_sums_solve_the_same_system_as_the_pairs() {
        for (seed, setup) in [(1, Setup::EyeInHand), (2, Setup::EyeToHand)] {
            let config = SimConfig {
                poses: 60,
                ..SimConfig::default()
            };
            let s = simulate(&config, seed, 0);
            let pairs = AllPairs::new(&s.poses, setup);
            let r_x0 = check_motions(&pairs).unwrap().andreff_rotation;
            assert!(pairs_normal(&pairs, 1.0, &r_x0).is_some());
            let (fast, slow) = both(&s.poses, setup);
            let rotation = (fast.rotation.matrix() - slow.rotation.matrix())
                .abs()
                .max();
            let translation = (fast.translation.vector - slow.translation.vector).norm()
                / slow.translation.vector.norm();
            assert!(
                rotation < 1e-11 && translation < 1e-11,
                "{rotation:e} {translation:e}"
            );
        }
    }

    #[test]
    fn a_pose_far_from_the_others_falls_back_to_the_pairs() {
        let config = SimConfig {
            poses: 30,
            ..SimConfig::default()
        };
        let mut s = simulate(&config, 3, 0);
        let turn =
            crate::model::pose::Transform::new(Vector3::zeros(), Vector3::new(0.0, 2.8, 0.0));
        s.poses[7].camera_from_target = turn * s.poses[7].camera_from_target;
        let pairs = AllPairs::new(&s.poses, Setup::EyeInHand);
        let r_x0 = check_motions(&pairs).unwrap().andreff_rotation;
        assert!(pairs_normal(&pairs, 1.0, &r_x0).is_none());
        // The same motions summed one by one; only the unit differs, by rounding: the camera
        // motions' RMS length from the per-pose sums on one side, motion by motion on the other.
        let (fast, slow) = both(&s.poses, Setup::EyeInHand);
        let rotation = (fast.rotation.matrix() - slow.rotation.matrix())
            .abs()
            .max();
        let translation = (fast.translation.vector - slow.translation.vector).norm()
            / slow.translation.vector.norm();
        assert!(
            rotation < 1e-14 && translation < 1e-14,
            "{rotation:e} {translation:e}"
        );
    }
}
