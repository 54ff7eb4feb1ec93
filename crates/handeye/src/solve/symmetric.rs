//! The small symmetric eigenproblem behind Andreff's rotation system: the smallest, second
//! smallest and largest eigenvalues of a symmetric N×N matrix, and the eigenvector of the
//! smallest.
//!
//! nalgebra's `SymmetricEigen` computes all N eigenvalues and eigenvectors by accumulating every QR
//! rotation into an N×N matrix; on the 9×9 normal matrix that was 31,000 of the 37,000
//! instructions of a whole two-motion Andreff solve (callgrind), where the solver needs one
//! eigenvector and three eigenvalues. Here only those are computed:
//!
//! 1. Householder tridiagonalisation `M = Q T Qᵀ`, keeping the reflectors (G. H. Golub,
//!    C. F. Van Loan, *Matrix Computations*, 4th ed., 2013, Alg. 8.3.1);
//! 2. λ₁, λ₂ and λ_N of T by Laguerre's iteration on det(T − xI) (B. N. Parlett, "Laguerre's
//!    method applied to the matrix eigenvalue problem", Math. Comp. 18, 1964; T. Y. Li, Z. Zeng,
//!    SIAM J. Sci. Comput. 15, 1994), the determinant and its derivatives evaluated by the
//!    three-term recurrence of the leading principal minors, which also gives the Sturm count.
//!    For real-rooted polynomials Laguerre's iterates move monotonically to the adjacent root
//!    and converge cubically: λ₁ is approached from below, λ_N from above, and λ₂ from just above
//!    λ₁ with λ₁ divided out. The searches for λ₁ then λ₂ and for λ_N run side by side, so that
//!    their dependency chains overlap, and Sturm counts on both sides of each result confirm it.
//!    When a start is not where it must be (λ₂ within 3·10⁻⁹‖T‖ of λ₁), a search does not
//!    settle or a result is not confirmed, all eigenvalues are computed instead by the implicit
//!    symmetric QR step with Wilkinson shift (Alg. 8.3.2–8.3.3);
//! 3. the eigenvector of λ₁ by inverse iteration on `T − λ₁I` (sec. 8.2.2), LU with partial
//!    pivoting in O(N), mapped back through the reflectors; optionally one Newton correction
//!    against an accurately evaluated residual, with the same factorisation.
//!
//! The eigenvalues carry an absolute error of order ε‖M‖, as LAPACK's and nalgebra's, and the
//! eigenvector an error of order ε‖M‖ / (λ₂ − λ₁). Tests compare both against nalgebra's
//! `SymmetricEigen` on random matrices and random rotation systems, on both paths. The whole
//! two-motion Andreff solve went from 3.9 µs to 1.6 µs (`cargo bench -p handeye --bench solvers`).

use nalgebra::{SMatrix, SVector};

/// Largest number of implicit QR steps per eigenvalue before the iteration is declared stuck
/// (it converges cubically; LAPACK allows 30).
const MAX_STEPS_PER_EIGENVALUE: usize = 30;

/// Largest number of Laguerre passes (each evaluates both searches) before falling back to QR.
/// On the random rotation systems of the tests the searches finish in 6 to 12 passes, and in up
/// to 27 when λ_max is nearly double (nearly parallel axes), where convergence is linear at first.
const MAX_LAGUERRE_PASSES: usize = 40;

/// Where the search for λ₂ may start, above λ₁, on T scaled to ‖T‖∞ ≤ 1: the largest offset t
/// with exactly one eigenvalue below λ₁ + t. λ₁ is known to about 4ε, and dividing it out of
/// det(T − xI) leaves an error of about 8ε / t³ in Laguerre's H, whose value is at least
/// 1 / (λ₂ − x)². From the first offset that is below 0.2% of H for any λ₂ ≤ 1; each further
/// offset is tried only when λ₂ lies below the one before, that is within 32t of λ₁, and the error
/// is then below 8ε·32² / t, again under 0.2% down to the last offset. When λ₂ lies below that
/// (a conditioning below about 10⁻⁴·⁵), QR is used instead.
const SECOND_STARTS: [f64; 4] = [1e-4, 1e-4 / 32.0, 1e-4 / 1024.0, 1e-4 / 32768.0];

/// The three eigenvalues the solvers use, and the unit eigenvector of the smallest.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SmallestEigen<const N: usize> {
    /// λ₁, the smallest eigenvalue.
    pub smallest: f64,
    /// λ₂, the second smallest (counting multiplicity).
    pub second: f64,
    /// λ_N, the largest.
    pub largest: f64,
    /// Unit eigenvector of λ₁ (its sign is arbitrary).
    pub vector: SVector<f64, N>,
}

/// λ₁, λ₂, λ_N and the eigenvector of λ₁ of the symmetric matrix `m` (N ≥ 2). `None` if `m` is
/// not finite or no method converges.
///
/// `residual(v)` may return `m v` evaluated more accurately than through `m` itself (Andreff's
/// solver sums it motion by motion from the stacked rows); the eigenvector then takes one Newton
/// (Jacobi–Davidson) correction against it: `δ ⊥ v` solving `(M − λ₁I) δ = −(I − v vᵀ) r`,
/// with the factorisation of `T − λ₁I` the inverse iteration already made. This brings an
/// eigenvector whose error came from forming `m` (of order ε·κ² for a normal matrix) down to the
/// ε·κ of an SVD of the rows. A correction that is not finite or not small is not applied.
pub(crate) fn smallest_eigen<const N: usize>(
    m: &SMatrix<f64, N, N>,
    residual: impl FnOnce(&SVector<f64, N>) -> Option<SVector<f64, N>>,
) -> Option<SmallestEigen<N>> {
    let tri = Tridiagonal::of(m)?;
    let [smallest, second, largest] = tri.extremes()?;
    let lu = tri.shifted_lu(smallest);
    let y = lu.inverse_iteration();
    let mut vector = tri.back_transform(y);
    if let Some(r) = residual(&vector) {
        let r = tri.forward_transform(r);
        let along = y.iter().zip(&r).map(|(a, b)| a * b).sum::<f64>();
        let mut z: [f64; N] = std::array::from_fn(|i| r[i] - along * y[i]);
        lu.solve(&mut z);
        let along = y.iter().zip(&z).map(|(a, b)| a * b).sum::<f64>();
        z.iter_mut().zip(&y).for_each(|(z, y)| *z -= along * y);
        let delta = tri.back_transform(z);
        let corrected = (vector - delta).normalize();
        if delta.norm() < 0.1 && corrected.iter().all(|x| x.is_finite()) {
            vector = corrected;
        }
    }
    Some(SmallestEigen {
        smallest,
        second,
        largest,
        vector,
    })
}

/// `M = Q T Qᵀ` with T tridiagonal and `Q = P₀ P₁ … P_{N−3}`, each `P_k = I − β_k v_k v_kᵀ`
/// acting on the coordinates k+1..N.
struct Tridiagonal<const N: usize> {
    /// Diagonal of T.
    diagonal: [f64; N],
    /// Off-diagonal of T: `off[k]` couples k and k+1 (the last entry is unused).
    off: [f64; N],
    /// `reflectors[k][k+1..]` is v_k, with `v_k[k+1] = 1`.
    reflectors: [[f64; N]; N],
    /// β_k of each reflector (0 where no reflection was needed).
    betas: [f64; N],
}

impl<const N: usize> Tridiagonal<N> {
    /// Householder tridiagonalisation (Golub–Van Loan Alg. 8.3.1).
    fn of(m: &SMatrix<f64, N, N>) -> Option<Self> {
        // Column-major storage: a[j][i] = M[(i, j)]; symmetric, so a[k] is row k as well.
        let mut a: [[f64; N]; N] = m.data.0;
        if a.iter().flatten().any(|x| !x.is_finite()) {
            return None;
        }
        let mut tri = Self {
            diagonal: [0.0; N],
            off: [0.0; N],
            reflectors: [[0.0; N]; N],
            betas: [0.0; N],
        };
        for k in 0..N.saturating_sub(2) {
            tri.diagonal[k] = a[k][k];
            let (beta, norm) = householder(&a[k], k + 1, &mut tri.reflectors[k]);
            tri.off[k] = norm;
            tri.betas[k] = beta;
            if beta != 0.0 {
                reflect_trailing(&mut a, k + 1, &tri.reflectors[k], beta);
            }
        }
        if N >= 2 {
            tri.diagonal[N - 2] = a[N - 2][N - 2];
            tri.off[N - 2] = a[N - 2][N - 1];
        }
        if N >= 1 {
            tri.diagonal[N - 1] = a[N - 1][N - 1];
        }
        Some(tri)
    }

    /// λ₁, λ₂ and λ_N of T: by Laguerre's iteration, or by QR when that cannot be trusted.
    fn extremes(&self) -> Option<[f64; 3]> {
        if N >= 3
            && let Some(found) = self.extremes_by_laguerre()
        {
            return Some(found);
        }
        let all = self.all_eigenvalues()?;
        Some([all[0], all[1.min(N - 1)], all[N - 1]])
    }

    /// Laguerre's iteration: lane 0 seeks λ₁ and then λ₂, lane 1 seeks λ_N. `None` when a start
    /// is not on the side of its eigenvalue it must be (checked by the Sturm count) or a search
    /// does not settle, or the results are not confirmed by Sturm counts; the caller then falls
    /// back to QR.
    fn extremes_by_laguerre(&self) -> Option<[f64; 3]> {
        let (mut low, mut high, mut scale) = (f64::INFINITY, f64::NEG_INFINITY, 0.0_f64);
        for k in 0..N {
            let radius = self.off[k].abs() + if k > 0 { self.off[k - 1].abs() } else { 0.0 };
            low = low.min(self.diagonal[k] - radius);
            high = high.max(self.diagonal[k] + radius);
            scale = scale.max(self.diagonal[k].abs() + radius);
        }
        if scale == 0.0 {
            return Some([0.0; 3]);
        }
        // The search runs on T / u, u the power of two at or above ‖T‖∞ (an exact scaling), so
        // that the minors of the Sturm sequence stay within (−3ᴺ, 3ᴺ).
        let unit = 2.0_f64.powi(scale.log2().ceil() as i32);
        let d: [f64; N] = std::array::from_fn(|k| self.diagonal[k] / unit);
        let e2: [f64; N] = std::array::from_fn(|k| (self.off[k] / unit).powi(2));
        let (low, high) = (low / unit, high / unit);
        // The normal matrices are positive semi-definite up to rounding, so λ₁ is sought from
        // just below zero, a step or two away; from the Gershgorin bound if it lies lower.
        let optimistic = (-64.0 * f64::EPSILON).max(low);
        let mut lanes = [
            Laguerre::new(optimistic, N, None, 0),
            Laguerre::new(high, N, None, N),
        ];
        let mut smallest = None;
        for _ in 0..MAX_LAGUERRE_PASSES {
            let sums = sturm_sums(&d, &e2, [lanes[0].x, lanes[1].x]);
            for (i, (lane, sums)) in lanes.iter_mut().zip(sums).enumerate() {
                if lane.step(sums).is_none() {
                    // λ₁ below the optimistic start (a matrix that is not semi-definite): search
                    // again from the Gershgorin bound.
                    if i == 0 && smallest.is_none() && lane.x == optimistic && optimistic > low {
                        *lane = Laguerre::new(low, N, None, 0);
                    } else {
                        return None;
                    }
                }
            }
            if lanes[0].done && smallest.is_none() {
                let l1 = lanes[0].x;
                smallest = Some(l1);
                let below = sturm_counts(&d, &e2, SECOND_STARTS.map(|t| l1 + t));
                let start = SECOND_STARTS.iter().zip(below).find(|&(_, b)| b == 1)?.0;
                lanes[0] = Laguerre::new(l1 + start, N - 1, Some(l1), 1);
            }
            if let (Some(l1), true, true) = (smallest, lanes[0].done, lanes[1].done) {
                let found = [l1, lanes[0].x, lanes[1].x];
                return bracketed(&d, &e2, found).then(|| found.map(|x| x * unit));
            }
        }
        None
    }

    /// All eigenvalues of T, ascending: implicit symmetric QR steps with Wilkinson shift on the
    /// lowest unreduced block, deflating off-diagonals below ε(|d_k| + |d_{k+1}|).
    fn all_eigenvalues(&self) -> Option<[f64; N]> {
        let mut d = self.diagonal;
        let mut e = self.off;
        let mut hi = N.saturating_sub(1);
        let mut steps = 0;
        while hi > 0 {
            if negligible(&d, &e, hi - 1) {
                hi -= 1;
                continue;
            }
            let mut lo = hi - 1;
            while lo > 0 && !negligible(&d, &e, lo - 1) {
                lo -= 1;
            }
            steps += 1;
            if steps > MAX_STEPS_PER_EIGENVALUE * N {
                return None;
            }
            qr_step(&mut d, &mut e, lo, hi);
        }
        d.sort_by(f64::total_cmp);
        Some(d)
    }

    /// The LU factorisation of `T − λI`, λ an eigenvalue.
    fn shifted_lu(&self, lambda: f64) -> BandedLu<N> {
        let scale = self
            .diagonal
            .iter()
            .chain(&self.off)
            .fold(0.0_f64, |s, x| s.max(x.abs()));
        BandedLu::of(&self.diagonal, &self.off, lambda, scale)
    }

    /// `Qᵀ r`, a vector of M's coordinates in T's.
    fn forward_transform(&self, r: SVector<f64, N>) -> [f64; N] {
        let mut y: [f64; N] = r.into();
        for k in 0..N.saturating_sub(2) {
            self.reflect(k, &mut y);
        }
        y
    }

    /// `Q y`, a vector of T's coordinates in M's (the eigenvector of M from that of T).
    fn back_transform(&self, mut y: [f64; N]) -> SVector<f64, N> {
        for k in (0..N.saturating_sub(2)).rev() {
            self.reflect(k, &mut y);
        }
        SVector::from(y)
    }

    /// `y ← P_k y`.
    fn reflect(&self, k: usize, y: &mut [f64; N]) {
        let beta = self.betas[k];
        if beta == 0.0 {
            return;
        }
        let v = &self.reflectors[k][k + 1..];
        let y = &mut y[k + 1..];
        let f = beta * v.iter().zip(y.iter()).map(|(a, b)| a * b).sum::<f64>();
        y.iter_mut().zip(v).for_each(|(y, v)| *y -= f * v);
    }
}

/// One Laguerre search for an eigenvalue of the tridiagonal T.
#[derive(Debug, Clone, Copy)]
struct Laguerre {
    /// The current iterate.
    x: f64,
    /// Degree of the polynomial searched: N, or N − 1 with λ₁ divided out.
    degree: f64,
    /// λ₁, when it is divided out of det(T − xI).
    deflated: Option<f64>,
    /// How many eigenvalues must lie below the start.
    below_start: usize,
    /// Whether the start has not been checked yet.
    fresh: bool,
    /// Whether the last step was below the tolerance.
    done: bool,
}

impl Laguerre {
    fn new(start: f64, degree: usize, deflated: Option<f64>, below_start: usize) -> Self {
        Self {
            x: start,
            degree: degree as f64,
            deflated,
            below_start,
            fresh: true,
            done: false,
        }
    }

    /// One Laguerre step from the sums at `x`: `x ← x − n / (G ± √((n − 1)(nH − G²)))`, the
    /// sign that of G, which moves toward the adjacent root on the side the search started.
    /// Stops when the step is below 4ε(1 + |x|) (on T scaled to ‖T‖∞ ≤ 1), or on an exact root.
    /// Convergence is cubic to a simple root but only linear while x is farther from the root
    /// than a nearly equal neighbour (λ_max of two motions about nearly parallel axes comes in
    /// such a pair), so a relative stopping rule like 10⁻¹⁰|x| would stop there 10⁻¹¹ short.
    /// `None` when the start is on the wrong side or the sums are not finite.
    fn step(&mut self, sums: SturmSums) -> Option<()> {
        if self.done {
            return Some(());
        }
        if self.fresh {
            if sums.below != self.below_start {
                return None;
            }
            self.fresh = false;
        }
        if sums.on_root {
            self.done = true;
            return Some(());
        }
        let (mut g, mut h) = (sums.g, sums.h);
        if let Some(l1) = self.deflated {
            let t = 1.0 / (self.x - l1);
            g -= t;
            h -= t * t;
        }
        let n = self.degree;
        let root = ((n - 1.0) * (n * h - g * g)).max(0.0).sqrt();
        let denominator = if g >= 0.0 { g + root } else { g - root };
        if denominator.is_nan() || denominator == 0.0 {
            return None;
        }
        let step = n / denominator;
        self.x -= step;
        self.done = step.abs() <= 4.0 * f64::EPSILON * (1.0 + self.x.abs());
        Some(())
    }
}

/// What one pass of the Sturm recurrence gives at a shift x.
#[derive(Debug, Clone, Copy, Default)]
struct SturmSums {
    /// Number of eigenvalues below x.
    below: usize,
    /// Whether det(T − xI) is exactly zero (x is an eigenvalue; G and H are not defined).
    on_root: bool,
    /// G = Σ 1/(x − λ_j).
    g: f64,
    /// H = Σ 1/(x − λ_j)².
    h: f64,
}

/// The Sturm count and Laguerre's sums G, H of the tridiagonal (d, e²) at two shifts.
///
/// The leading principal minors `p_k = det(T_k − xI)` follow the three-term recurrence
/// `p_k = (d_k − x) p_{k−1} − e²_{k−1} p_{k−2}` (J. H. Wilkinson, *The Algebraic Eigenvalue
/// Problem*, 1965, ch. 5 §37–39), and so do their first and second derivatives in x; the number
/// of eigenvalues below x is the number of sign changes along `p_0 = 1, p_1, …, p_N`, and
/// `G = p'_N / p_N`, `H = G² − p''_N / p_N`. The recurrence has no division, so a pass is a short
/// chain of multiply-adds; the two shifts run interleaved. T must be scaled to ‖T‖∞ ≤ 1 so that
/// the minors stay within 3ᴺ.
fn sturm_sums<const N: usize>(d: &[f64; N], e2: &[f64; N], x: [f64; 2]) -> [SturmSums; 2] {
    let mut out = [SturmSums::default(); 2];
    // Per shift: (p, p', p'') at k − 1 and at k − 2.
    let mut now = [[1.0, 0.0, 0.0]; 2];
    let mut before = [[0.0; 3]; 2];
    let mut negative = [false; 2];
    for k in 0..N {
        let c = if k > 0 { e2[k - 1] } else { 0.0 };
        for l in 0..2 {
            let a = d[k] - x[l];
            let [p, dp, ddp] = now[l];
            let [p2, dp2, ddp2] = before[l];
            before[l] = now[l];
            now[l] = [
                a * p - c * p2,
                a * dp - p - c * dp2,
                a * ddp - 2.0 * dp - c * ddp2,
            ];
            let p = now[l][0];
            let sign = if p == 0.0 { !negative[l] } else { p < 0.0 };
            out[l].below += usize::from(sign != negative[l]);
            negative[l] = sign;
        }
    }
    for (out, [p, dp, ddp]) in out.iter_mut().zip(now) {
        if p == 0.0 {
            out.on_root = true;
        } else {
            out.g = dp / p;
            out.h = out.g * out.g - ddp / p;
        }
    }
    out
}

/// The number of eigenvalues of the tridiagonal (d, e²) below each of L shifts: the sign changes
/// of the leading principal minors, a zero minor taking the sign opposite to the one before (as
/// in [`sturm_sums`]; T scaled to ‖T‖∞ ≤ 1).
fn sturm_counts<const N: usize, const L: usize>(
    d: &[f64; N],
    e2: &[f64; N],
    x: [f64; L],
) -> [usize; L] {
    let mut below = [0; L];
    let mut now = [1.0; L];
    let mut before = [0.0; L];
    let mut negative = [false; L];
    for k in 0..N {
        let c = if k > 0 { e2[k - 1] } else { 0.0 };
        for l in 0..L {
            let p = (d[k] - x[l]) * now[l] - c * before[l];
            before[l] = now[l];
            now[l] = p;
            let sign = if p == 0.0 { !negative[l] } else { p < 0.0 };
            below[l] += usize::from(sign != negative[l]);
            negative[l] = sign;
        }
    }
    below
}

/// Whether λ₁, λ₂ and λ_N = `found` are those eigenvalues of the scaled tridiagonal (d, e²) to
/// within 10⁻⁹|λ| + 64ε, by Sturm counts on both sides of each. Laguerre's sums lose accuracy
/// where x is near an eigenvalue of a leading block of T, and a step can then stop at the wrong
/// place; the counts catch it.
fn bracketed<const N: usize>(d: &[f64; N], e2: &[f64; N], found: [f64; 3]) -> bool {
    if !found.iter().all(|v| v.is_finite()) {
        return false;
    }
    let margin = |x: f64| 1e-9 * x.abs() + 64.0 * f64::EPSILON;
    let shifts: [f64; 6] = std::array::from_fn(|i| {
        let x = found[i / 2];
        if i % 2 == 0 {
            x - margin(x)
        } else {
            x + margin(x)
        }
    });
    let below = sturm_counts(d, e2, shifts);
    below[0] == 0
        && below[1] >= 1
        && below[2] <= 1
        && below[3] >= 2
        && below[4] < N
        && below[5] == N
}

/// Builds the Householder reflector `P = I − β v vᵀ` with `P x = ‖x‖ e₁` for `x = column[start..]`
/// (Golub–Van Loan Alg. 5.1.1), writing v (with `v[start] = 1`) into `v`; returns (β, ‖x‖), with
/// β = 0 when x is already a multiple of e₁ with a non-negative first entry.
fn householder<const N: usize>(column: &[f64; N], start: usize, v: &mut [f64; N]) -> (f64, f64) {
    let x0 = column[start];
    let sigma: f64 = column[start + 1..].iter().map(|x| x * x).sum();
    if sigma == 0.0 {
        // Already reduced; a sign flip is not needed because T may have any sign off the diagonal.
        return (0.0, x0);
    }
    let mu = (x0 * x0 + sigma).sqrt();
    // v₀ = x₀ − ‖x‖, computed without cancellation when x₀ > 0.
    let v0 = if x0 <= 0.0 {
        x0 - mu
    } else {
        -sigma / (x0 + mu)
    };
    let beta = 2.0 * v0 * v0 / (sigma + v0 * v0);
    v[start] = 1.0;
    for i in start + 1..N {
        v[i] = column[i] / v0;
    }
    (beta, mu)
}

/// `A ← P A P` on the trailing block `start..N` (Golub–Van Loan eq. 8.3.2):
/// p = β A v, w = p − (β pᵀv / 2) v, A ← A − v wᵀ − w vᵀ.
fn reflect_trailing<const N: usize>(a: &mut [[f64; N]; N], start: usize, v: &[f64; N], beta: f64) {
    let v = &v[start..];
    let mut w = [0.0; N];
    let w = &mut w[start..];
    for (wi, row) in w.iter_mut().zip(&a[start..]) {
        *wi = beta * row[start..].iter().zip(v).map(|(x, y)| x * y).sum::<f64>();
    }
    let half = 0.5 * beta * w.iter().zip(v).map(|(x, y)| x * y).sum::<f64>();
    for (wi, vi) in w.iter_mut().zip(v) {
        *wi -= half * vi;
    }
    for ((row, vi), wi) in a[start..].iter_mut().zip(v).zip(w.iter()) {
        for ((x, vj), wj) in row[start..].iter_mut().zip(v).zip(w.iter()) {
            *x -= vi * wj + wi * vj;
        }
    }
}

/// Whether the off-diagonal entry coupling k and k+1 can be set to zero.
fn negligible<const N: usize>(d: &[f64; N], e: &[f64; N], k: usize) -> bool {
    e[k].abs() <= f64::EPSILON * (d[k].abs() + d[k + 1].abs())
}

/// One implicit symmetric QR step with Wilkinson shift on the unreduced block `lo..=hi` of the
/// tridiagonal (d, e) (Golub–Van Loan Alg. 8.3.2): a Givens rotation on the first column of
/// `T − μI`, then the bulge chased down to the bottom of the block.
fn qr_step<const N: usize>(d: &mut [f64; N], e: &mut [f64; N], lo: usize, hi: usize) {
    let (a, b, c) = (d[hi - 1], e[hi - 1], d[hi]);
    let delta = 0.5 * (a - c);
    let sign = if delta >= 0.0 { 1.0 } else { -1.0 };
    let shift = c - b * b / (delta + sign * delta.hypot(b));
    let mut x = d[lo] - shift;
    let mut z = e[lo];
    for k in lo..hi {
        // Rotation in the plane (k, k+1) taking (x, z) to (r, 0).
        let r = (x * x + z * z).sqrt();
        let (cs, sn) = if r == 0.0 { (1.0, 0.0) } else { (x / r, z / r) };
        if k > lo {
            e[k - 1] = r;
        }
        let (dk, ek, dk1) = (d[k], e[k], d[k + 1]);
        let cross = 2.0 * cs * sn * ek;
        d[k] = cs * cs * dk + cross + sn * sn * dk1;
        d[k + 1] = sn * sn * dk - cross + cs * cs * dk1;
        e[k] = cs * sn * (dk1 - dk) + (cs * cs - sn * sn) * ek;
        if k + 1 < hi {
            z = sn * e[k + 1];
            e[k + 1] *= cs;
            x = e[k];
        }
    }
}

/// LU factorisation with partial pivoting of the tridiagonal `T − λI`: row interchanges give U an
/// upper bandwidth of 2 (Golub–Van Loan sec. 4.3.5).
struct BandedLu<const N: usize> {
    /// Row k of U: its entries in columns k, k+1, k+2.
    upper: [[f64; 3]; N],
    /// The multiplier eliminating column k from the row below the pivot.
    multiplier: [f64; N],
    /// Whether rows k and k+1 were interchanged at step k.
    swapped: [bool; N],
    /// 1 / U[k, k].
    inverse_pivot: [f64; N],
}

impl<const N: usize> BandedLu<N> {
    /// Factorises `T − λI`; a zero pivot (λ an exact eigenvalue) is replaced by ε·scale, as in
    /// inverse iteration it only sets the size of the growth.
    fn of(d: &[f64; N], e: &[f64; N], lambda: f64, scale: f64) -> Self {
        let tiny = f64::EPSILON * scale.max(f64::MIN_POSITIVE);
        let mut lu = Self {
            upper: [[0.0; 3]; N],
            multiplier: [0.0; N],
            swapped: [false; N],
            inverse_pivot: [0.0; N],
        };
        // The row carried down from the previous step: entries in columns k and k+1.
        let mut carried = [d.first().map_or(0.0, |d0| d0 - lambda), e[0], 0.0];
        for k in 0..N {
            if k + 1 == N {
                lu.upper[k] = carried;
                break;
            }
            let below = [
                e[k],
                d[k + 1] - lambda,
                if k + 2 < N { e[k + 1] } else { 0.0 },
            ];
            let (pivot, other) = if below[0].abs() > carried[0].abs() {
                lu.swapped[k] = true;
                (below, carried)
            } else {
                (carried, below)
            };
            let pivot = if pivot[0] == 0.0 {
                [tiny, pivot[1], pivot[2]]
            } else {
                pivot
            };
            let l = other[0] / pivot[0];
            lu.upper[k] = pivot;
            lu.multiplier[k] = l;
            carried = [other[1] - l * pivot[1], other[2] - l * pivot[2], 0.0];
        }
        if let Some(last) = lu.upper.last_mut()
            && last[0] == 0.0
        {
            last[0] = tiny;
        }
        for (inverse, u) in lu.inverse_pivot.iter_mut().zip(&lu.upper) {
            *inverse = 1.0 / u[0];
        }
        lu
    }

    /// The eigenvector of T for the eigenvalue λ of this factorisation: two steps of inverse
    /// iteration from a fixed start.
    fn inverse_iteration(&self) -> [f64; N] {
        // A start with components of both signs and no symmetry, so it is not orthogonal to the
        // wanted eigenvector (one exact zero component would be recovered by the second step).
        let mut y: [f64; N] =
            std::array::from_fn(|i| 1.0 - 0.37 * i as f64 + 0.05 * (i * i) as f64);
        for _ in 0..2 {
            self.solve(&mut y);
            let norm = y.iter().map(|v| v * v).sum::<f64>().sqrt();
            if !(norm.is_finite() && norm > 0.0) {
                break;
            }
            y.iter_mut().for_each(|v| *v /= norm);
        }
        y
    }

    /// Solves `(T − λI) y = b` in place.
    fn solve(&self, b: &mut [f64; N]) {
        for k in 0..N.saturating_sub(1) {
            if self.swapped[k] {
                b.swap(k, k + 1);
            }
            b[k + 1] -= self.multiplier[k] * b[k];
        }
        for k in (0..N).rev() {
            let u = &self.upper[k];
            let mut s = b[k];
            if k + 1 < N {
                s -= u[1] * b[k + 1];
            }
            if k + 2 < N {
                s -= u[2] * b[k + 2];
            }
            b[k] = s * self.inverse_pivot[k];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, Matrix3, Rotation3, SymmetricEigen, Vector3};
    use proptest::prelude::*;

    fn random_symmetric<const N: usize>(entries: &[f64]) -> SMatrix<f64, N, N> {
        let m = SMatrix::<f64, N, N>::from_fn(|i, j| entries[i * N + j]);
        m + m.transpose()
    }

    /// nalgebra's eigenvalues (ascending) and the eigenvector of the smallest.
    fn reference<const N: usize>(m: &SMatrix<f64, N, N>) -> ([f64; N], DMatrix<f64>) {
        let eigen = SymmetricEigen::new(DMatrix::from_iterator(N, N, m.iter().copied()));
        let mut values: [f64; N] = std::array::from_fn(|i| eigen.eigenvalues[i]);
        values.sort_by(f64::total_cmp);
        let vector = eigen
            .eigenvectors
            .column(eigen.eigenvalues.imin())
            .into_owned();
        (values, DMatrix::from_column_slice(N, 1, vector.as_slice()))
    }

    /// Checks λ₁, λ₂, λ_N from both paths against nalgebra's, and the eigenvector's residual and
    /// agreement. Returns whether Laguerre's path was taken.
    fn check<const N: usize>(m: &SMatrix<f64, N, N>) -> bool {
        let (expected, expected_vector) = reference(m);
        let norm = m.norm().max(1e-300);
        let close = |found: [f64; 3], path: &str| {
            let want = [expected[0], expected[1], expected[N - 1]];
            for (a, b) in found.iter().zip(&want) {
                assert!(
                    (a - b).abs() <= 1e-13 * norm,
                    "{path}: eigenvalue {a:e} vs {b:e}"
                );
            }
        };
        let tri = Tridiagonal::of(m).unwrap();
        let all = tri.all_eigenvalues().unwrap();
        close([all[0], all[1], all[N - 1]], "QR");
        let fast = tri.extremes_by_laguerre();
        if let Some(found) = fast {
            close(found, "Laguerre");
        }
        let ours = smallest_eigen(m, |_| None).expect("converges");
        let v = ours.vector;
        assert!((v.norm() - 1.0).abs() < 1e-13);
        let residual = (m * v - v * ours.smallest).norm();
        assert!(residual <= 1e-13 * norm, "residual {residual:e}");
        let gap = expected[1] - expected[0];
        if gap > 1e-6 * norm {
            let agreement = 1.0
                - v.dot(&SVector::<f64, N>::from_column_slice(
                    expected_vector.as_slice(),
                ))
                .abs();
            assert!(
                agreement < 1e-12 * (norm / gap).powi(2),
                "1 − |cos| = {agreement:e}"
            );
        }
        fast.is_some()
    }

    /// Andreff's normal matrix Σ 2I − K − Kᵀ, K = R_a ⊗ R_b, of motions with rotation vectors
    /// `a` and X's rotation vector `x`, with `noise` added to each B rotation vector.
    fn rotation_system(a: &[Vector3<f64>], x: Vector3<f64>, noise: f64) -> SMatrix<f64, 9, 9> {
        let r_x = Rotation3::new(x);
        let mut m = SMatrix::<f64, 9, 9>::zeros();
        for (i, a) in a.iter().enumerate() {
            let r_a = Rotation3::new(*a);
            let wobble = Vector3::new(1.0, -0.5, 0.25 * i as f64).normalize() * noise;
            let r_b = r_x.inverse() * r_a * r_x * Rotation3::new(wobble);
            let k: Matrix3<f64> = *r_a.matrix();
            let kron = k.kronecker(r_b.matrix());
            m += SMatrix::<f64, 9, 9>::identity() * 2.0 - kron - kron.transpose();
        }
        m
    }

    fn vector3() -> impl Strategy<Value = Vector3<f64>> {
        (-1.5..1.5f64, -1.5..1.5f64, -1.5..1.5f64).prop_map(|(x, y, z)| Vector3::new(x, y, z))
    }

    proptest! {
        #[test]
        fn agrees_with_nalgebra_on_random_matrices(entries in prop::collection::vec(-10.0..10.0f64, 81)) {
            check::<9>(&random_symmetric::<9>(&entries));
            check::<4>(&random_symmetric::<4>(&entries));
            check::<3>(&random_symmetric::<3>(&entries));
        }

        #[test]
        fn agrees_with_nalgebra_on_rotation_systems(
            a in prop::collection::vec(vector3(), 2..12),
            x in vector3(),
            noise in prop_oneof![Just(0.0), 1e-8..1e-2f64],
        ) {
            let m = rotation_system(&a, x, noise);
            let fast = check::<9>(&m);
            // Laguerre's path is the one taken unless λ₂ is within 3e-9‖T‖ of λ₁ (‖T‖∞ ≤ 3λ_N).
            let (values, _) = reference(&m);
            if values[1] - values[0] > 1e-7 * values[8] {
                prop_assert!(fast);
            }
        }

        #[test]
        fn agrees_with_nalgebra_on_nearly_parallel_axes(
            a in vector3(),
            tilt in vector3(),
            size in -6.0..-1.0f64,
            x in vector3(),
            noise in prop_oneof![Just(0.0), 1e-9..1e-4f64],
        ) {
            // Two motions whose axes are 10⁻⁶ to 10⁻¹ rad apart: weak conditioning.
            let second = (a + tilt.normalize() * 10f64.powf(size) * a.norm()) * 1.3;
            let m = rotation_system(&[a, second], x, noise);
            let fast = check::<9>(&m);
            let (values, _) = reference(&m);
            if values[1] - values[0] > 1e-7 * values[8] {
                prop_assert!(fast);
            }
        }

        #[test]
        fn finds_an_exact_null_vector(entries in prop::collection::vec(-1.0..1.0f64, 72)) {
            // B is 8×9, so BᵀB is positive semi-definite with a one-dimensional null space.
            let b = SMatrix::<f64, 8, 9>::from_row_slice(&entries);
            let m = b.transpose() * b;
            let ours = smallest_eigen(&m, |_| None).expect("converges");
            prop_assert!(ours.smallest.abs() < 1e-13 * m.norm());
            prop_assert!((b * ours.vector).norm() < 1e-12 * b.norm());
        }
    }

    #[test]
    fn handles_diagonal_and_repeated_eigenvalues() {
        let diag = SMatrix::<f64, 9, 9>::from_diagonal(&SVector::from([
            3.0, 1.0, 4.0, 1.0, 5.0, 9.0, 2.0, 6.0, 0.5,
        ]));
        let ours = smallest_eigen(&diag, |_| None).unwrap();
        assert_eq!([ours.smallest, ours.second, ours.largest], [0.5, 1.0, 9.0]);
        assert!((ours.vector[8].abs() - 1.0).abs() < 1e-15);
        let tri = Tridiagonal::of(&diag).unwrap();
        assert_eq!(
            tri.all_eigenvalues().unwrap(),
            [0.5, 1.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 9.0]
        );
        // One rotation: 2I − (R ⊗ R) − (R ⊗ R)ᵀ has a three-dimensional null space, so λ₂ = λ₁
        // and only QR can give it.
        let one = rotation_system(&[Vector3::new(0.3, -0.2, 0.5)], Vector3::zeros(), 0.0);
        assert!(!check::<9>(&one));
        // Two motions about the same axis: parallel axes, λ₂ ≈ λ₁ again.
        let axis = Vector3::new(0.2, 0.5, -0.1);
        let parallel = rotation_system(&[axis, axis * 2.0], Vector3::new(0.1, 0.2, 0.3), 0.0);
        check::<9>(&parallel);
        let zero = smallest_eigen(&SMatrix::<f64, 9, 9>::zeros(), |_| None).unwrap();
        assert_eq!([zero.smallest, zero.second, zero.largest], [0.0; 3]);
        let mut bad = diag;
        bad[(3, 2)] = f64::NAN;
        assert!(smallest_eigen(&bad, |_| None).is_none());
    }
}
