//! The damped modes of a small quadratic eigenproblem `(λ² A + λ G + I) z = 0` in (nearly)
//! undamped modal coordinates: `A` real symmetric positive definite and nearly diagonal, `G`
//! real symmetric, `n ≤` [`MAX_DIM`]. Any `M δ'' + C δ' + K δ = 0` with `M`, `K` symmetric
//! positive definite takes this form in the coordinates of its undamped modes (`A =
//! diag(1/ω_i²)`, `G = Φᵀ C Φ` for `K`-normalized `Φ`); a few Jacobi sweeps short of full
//! convergence leave `A` nearly diagonal, which is all the method needs. Simultaneous (Aberth)
//! iteration on the roots of the characteristic polynomial: fixed-size arrays, no allocation,
//! no panic, a bounded number of sweeps.
//!
//! **Why this method.** `p(λ) = det Q(λ)`, `Q(λ) = λ² A + λ G + I`, has real
//! coefficients and degree `2n`; an underdamped system has `n` complex-conjugate pairs of
//! roots. Aberth's iteration moves every root estimate by the Newton step `p/p'` corrected by
//! the repulsion of the other roots (their conjugates included), so two estimates never
//! converge to the same root — the failure of plain Newton from each start when two modes are
//! close, which is exactly where the exact damped modes differ from the projected ones. It
//! needs only `p'/p = tr(Q⁻¹ Q')` (Jacobi's formula): the sum of `d'/d` over the pivots of
//! one symmetric elimination of `Q` carried out on dual numbers `Q + ε Q'`. From the
//! modal-damping estimates (accurate to second order in the damping coupling) it converges
//! in two or three sweeps (cubically near the roots).
//!
//! **Elimination order.** The iteration for the root started at coordinate `k`'s undamped
//! mode eliminates `k` last, so only the last pivot approaches zero. The others are the
//! successive Schur complements of `Q` without row and column `k`: near `λ_k` the first is mode
//! `i`'s dynamic stiffness at mode `k`'s frequency, `1 − (ω_k/ω_i)² + 2iζ_i ω_k/ω_i` to first
//! order, never zero with damping; a pivot vanishes only where another root of the system
//! lies, so no pivoting is needed for distinct roots (a zero pivot ends the solve with a
//! failure instead; the log-derivative is exact in any order, the order only keeps it
//! accurate). The mode shape at a converged root eliminates last the coordinate whose diagonal
//! `λ² a_kk + λ g_kk + 1` is smallest, the direction in which `Q(λ)` is singular there (`A` is
//! nearly diagonal), whichever start the root came from.
//!
//! **Mode shapes.** Each root's null vector comes from the elimination that found it
//! converged (the last coordinate set to 1, the others by back substitution; unit length): at
//! the root's last iterate, within its last Newton correction (at most `CONVERGED_STEP`,
//! typically 1e-8, relative) of the root, so the shape carries that error divided by the
//! modes' relative separation while the root itself is exact to rounding. That saves an
//! elimination per mode (6 % of the modal map's step); the shapes only weigh the modes'
//! assignment. Where that elimination cannot give it (the root's own coordinate is not the
//! singular one there), a separate elimination at the root does.
//!
//! **Safeguards.** A step is at most a quarter of the root's size and never crosses the real
//! axis (it stops half way): from a start far off (two close modes with very different
//! damping, whose projected damping ratios are nearly equal) the Aberth correction can
//! otherwise overshoot into the lower half plane.
//!
//! Overdamped modes (real root pairs) cannot be represented by the conjugate-pair iteration:
//! the solve then reports failure and the caller decides (see
//! [`crate::modes::modal::modal_map::ModalMap::solve`]).

use crate::math::sym_eigen::MAX_DIM;
use num_complex::Complex64;

/// Upper bound on the sweeps (each sweep updates every root once). From the modal-damping
/// start 2–3 sweeps reach full precision, more where the start is far off; the bound only
/// guarantees termination (an overdamped mode runs into it).
pub const MAX_SWEEPS: usize = 40;

/// Largest update of a root in one step, relative to its size (from the modal-damping start
/// the first updates are about 3e-3 on the UR5e; only a start far off meets the limit).
const MAX_STEP: f64 = 0.25;

/// A root whose update is at most this (relative) is left alone from then on. Each update
/// is (to first order) the root's error before it, and the convergence is cubic: the error
/// left is of order `s³ / δ²` for an update `s` and a relative separation `δ` of the closest
/// roots, below 1e-13 for `s = 1e-6` and `δ ≥ 0.3 %` (measured: updates fall as
/// 3e-3 → 9e-9 → 7e-17 from the modal-damping start on the UR5e).
const CONVERGED_STEP: f64 = 1e-6;

/// The damped modes: one root `λ` with positive imaginary part and its unit null vector per
/// mode, in the order of the start values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DampedModes {
    /// Roots `λ_i` (upper half plane) of `det(λ² A + λ G + I)`.
    pub roots: [Complex64; MAX_DIM],
    /// Null vector of root `i` in **column** `i` (`vectors[row][i]`), unit 2-norm.
    pub vectors: [[Complex64; MAX_DIM]; MAX_DIM],
}

/// `1 / z` with one real division (the divisions dominate the cost of these small solves).
#[inline]
fn recip(z: Complex64) -> Complex64 {
    let s = 1.0 / z.norm_sqr();
    Complex64::new(z.re * s, -z.im * s)
}

/// The problem at a compile-time size: `A` and `G`, `N × N`.
struct Problem<const N: usize> {
    a: [[f64; N]; N],
    g: [[f64; N]; N],
}

// Index loops mirror the elimination formulas (two rows of one matrix are read and written).
#[allow(clippy::needless_range_loop)]
impl<const N: usize> Problem<N> {
    /// Writes the upper triangles of `Q(λ)` (`q`) and `Q'(λ) = 2λ A + G` (`dq`) with
    /// coordinate `k` moved last (the others keep their order).
    #[inline(always)]
    fn q_and_derivative(
        &self,
        lambda: Complex64,
        k: usize,
        q: &mut [[Complex64; N]; N],
        dq: &mut [[Complex64; N]; N],
    ) {
        let l2 = lambda * lambda;
        let two_l = 2.0 * lambda;
        for r in 0..N {
            let i = Self::coordinate(r, k);
            for c in r..N {
                let j = Self::coordinate(c, k);
                q[r][c] = l2 * self.a[i][j] + lambda * self.g[i][j];
                dq[r][c] = two_l * self.a[i][j] + self.g[i][j];
            }
            q[r][r] += 1.0;
        }
    }

    /// The coordinate to eliminate last at `λ`: the one whose diagonal `λ² a_ii + λ g_ii + 1`
    /// is smallest, the direction in which `Q(λ)` is nearly singular near a root (`A` is
    /// nearly diagonal), whichever start the root came from.
    #[inline]
    fn last_coordinate(&self, lambda: Complex64) -> usize {
        let l2 = lambda * lambda;
        let mut best = (0, f64::INFINITY);
        for i in 0..N {
            let d = (l2 * self.a[i][i] + lambda * self.g[i][i] + 1.0).norm_sqr();
            if d < best.1 {
                best = (i, d);
            }
        }
        best.0
    }

    /// The coordinate at elimination slot `slot` when coordinate `k` goes last.
    #[inline(always)]
    fn coordinate(slot: usize, k: usize) -> usize {
        if slot == N - 1 {
            k
        } else if slot < k {
            slot
        } else {
            slot + 1
        }
    }

    /// `p(λ)/p'(λ)` (the Newton step of the characteristic polynomial) for the root started
    /// at coordinate `k`'s undamped mode, eliminating `k` last: `0` at an exact root, `None`
    /// on a vanishing pivot before the last or a non-finite result. Where the step is within
    /// `tol2` (squared) and `k` is the coordinate singular at `λ`, the same elimination also
    /// gives the unit null vector (written to `shape`; otherwise `shape` is left alone).
    fn newton_step(
        &self,
        lambda: Complex64,
        k: usize,
        tol2: f64,
        shape: &mut Option<[Complex64; N]>,
    ) -> Option<Complex64> {
        let zero = Complex64::new(0.0, 0.0);
        let (mut u, mut du) = ([[zero; N]; N], [[zero; N]; N]);
        self.q_and_derivative(lambda, k, &mut u, &mut du);
        let mut log_derivative = Complex64::new(0.0, 0.0);
        let mut inv_pivots = [zero; N];
        for p in 0..N {
            let (pivot, dpivot) = (u[p][p], du[p][p]);
            if pivot.norm_sqr() == 0.0 {
                return (p == N - 1).then_some(Complex64::new(0.0, 0.0));
            }
            let inv_pivot = recip(pivot);
            inv_pivots[p] = inv_pivot;
            log_derivative += dpivot * inv_pivot;
            for r in p + 1..N {
                // Dual elimination: l + ε l' = (u_pr + ε u'_pr) / (u_pp + ε u'_pp); symmetric,
                // so only the upper triangle is updated.
                let l = u[p][r] * inv_pivot;
                let dl = (du[p][r] - l * dpivot) * inv_pivot;
                for c in r..N {
                    let (upc, dupc) = (u[p][c], du[p][c]);
                    u[r][c] -= l * upc;
                    du[r][c] -= dl * upc + l * dupc;
                }
            }
        }
        let step = recip(log_derivative);
        // An infinite log-derivative is a last pivot short of exact zero: a zero step.
        let step = if log_derivative.is_finite() && step.is_finite() {
            step
        } else if log_derivative.is_nan() {
            return None;
        } else {
            zero
        };
        if step.norm_sqr() <= tol2 && self.last_coordinate(lambda) == k {
            *shape = Self::back_substitution(&u, &inv_pivots, k);
        }
        Some(step)
    }

    /// The unit null vector of an eliminated `Q` (upper triangle `u`, reciprocal pivots
    /// `inv_pivots`, coordinate `k` last) whose last pivot vanishes: the last coordinate set
    /// to 1, the others by back substitution, in the original coordinates.
    fn back_substitution(
        u: &[[Complex64; N]; N],
        inv_pivots: &[Complex64; N],
        k: usize,
    ) -> Option<[Complex64; N]> {
        let zero = Complex64::new(0.0, 0.0);
        let mut x = [zero; N];
        x[N - 1] = Complex64::new(1.0, 0.0);
        for r in (0..N - 1).rev() {
            let mut s = zero;
            for c in r + 1..N {
                s -= u[r][c] * x[c];
            }
            x[r] = s * inv_pivots[r];
        }
        let norm2: f64 = x.iter().map(|v| v.norm_sqr()).sum();
        if !(norm2.is_finite() && norm2 > 0.0) {
            return None;
        }
        let inv_norm = 1.0 / norm2.sqrt();
        let mut z = [zero; N];
        for (slot, &xs) in x.iter().enumerate() {
            z[Self::coordinate(slot, k)] = xs * inv_norm;
        }
        Some(z)
    }

    /// Unit null vector of `Q(λ)` at a converged root (module docs).
    fn null_vector(&self, lambda: Complex64) -> Option<[Complex64; N]> {
        let k = self.last_coordinate(lambda);
        let zero = Complex64::new(0.0, 0.0);
        let (mut u, mut unused) = ([[zero; N]; N], [[zero; N]; N]);
        self.q_and_derivative(lambda, k, &mut u, &mut unused);
        let mut inv_pivots = [zero; N];
        for p in 0..N - 1 {
            let inv_pivot = recip(u[p][p]);
            inv_pivots[p] = inv_pivot;
            for r in p + 1..N {
                let l = u[p][r] * inv_pivot;
                for c in r..N {
                    let upc = u[p][c];
                    u[r][c] -= l * upc;
                }
            }
        }
        Self::back_substitution(&u, &inv_pivots, k)
    }

    /// The Aberth iteration (see [`damped_modes`]).
    fn solve(&self, start: &[Complex64; MAX_DIM]) -> Option<DampedModes> {
        let mut roots = [Complex64::new(0.0, 0.0); N];
        roots.copy_from_slice(&start[..N]);
        if roots.iter().any(|r| !(r.is_finite() && r.im > 0.0)) {
            return None;
        }
        // A root is left alone once its own update is below CONVERGED_STEP (it is then a
        // fixed point of its Newton step, whatever the others still do).
        let mut done = [false; N];
        // Each root's mode shape, from the elimination that found it converged (the root then
        // moves by at most CONVERGED_STEP, relative; the shape's error is that over the
        // modes' separation) or, where that elimination could not give it, from its own.
        let mut shapes: [Option<[Complex64; N]>; N] = [None; N];
        for _ in 0..MAX_SWEEPS {
            for k in 0..N {
                if done[k] {
                    continue;
                }
                let rk = roots[k];
                // Done when the Newton correction itself is small (relative, squared: no
                // hypot on this path), not a limited step, nor an Aberth step that the
                // repulsion of the root's own conjugate shrinks near the real axis.
                let tol2 = CONVERGED_STEP * CONVERGED_STEP * rk.norm_sqr();
                let newton = self.newton_step(rk, k, tol2, &mut shapes[k])?;
                // Repulsion of the other roots and of every conjugate (real coefficients):
                // `1/(λ_k − λ_j) + 1/(λ_k − λ̄_j) = 2 (λ_k − Re λ_j) / ((λ_k − λ_j)(λ_k − λ̄_j))`.
                let mut repulsion = recip(rk - rk.conj());
                for (j, &rj) in roots.iter().enumerate() {
                    if j != k {
                        let pair = (rk - rj) * (rk - rj.conj());
                        repulsion += 2.0 * (rk - rj.re) * recip(pair);
                    }
                }
                let mut step = newton * recip(1.0 - newton * repulsion);
                if !step.is_finite() {
                    return None;
                }
                done[k] = newton.norm_sqr() <= tol2 && step.norm_sqr() <= tol2;
                // Far from the roots (a start the projected damping put far off, where two
                // close modes have very different damping) the correction can overshoot:
                // at most MAX_STEP of the root's size, and never across the real axis (half
                // way to it instead; an overdamped mode then does not converge).
                let size = step.norm_sqr() / rk.norm_sqr();
                if size > MAX_STEP * MAX_STEP {
                    step *= MAX_STEP / size.sqrt();
                }
                if rk.im - step.im <= 0.0 {
                    step *= 0.5 * rk.im / step.im;
                }
                roots[k] = rk - step;
            }
            if done.iter().all(|&d| d) {
                // A pair of real roots (an overdamped mode) draws a root and its conjugate
                // together onto the real axis, where the Newton step vanishes too: refused.
                if roots.iter().any(|r| r.im * r.im <= 1e-12 * r.norm_sqr()) {
                    return None;
                }
                let zero = Complex64::new(0.0, 0.0);
                let mut out = DampedModes {
                    roots: [zero; MAX_DIM],
                    vectors: [[zero; MAX_DIM]; MAX_DIM],
                };
                for (k, &root) in roots.iter().enumerate() {
                    out.roots[k] = root;
                    let z = match shapes[k] {
                        Some(z) => z,
                        None => self.null_vector(root)?,
                    };
                    for (row, &zr) in out.vectors.iter_mut().zip(&z) {
                        row[k] = zr;
                    }
                }
                return Some(out);
            }
        }
        None
    }
}

/// Solves at the compile-time size `N` (copies the leading blocks).
fn solve_sized<const N: usize>(
    a: &[[f64; MAX_DIM]; MAX_DIM],
    g: &[[f64; MAX_DIM]; MAX_DIM],
    start: &[Complex64; MAX_DIM],
) -> Option<DampedModes> {
    let mut problem = Problem {
        a: [[0.0; N]; N],
        g: [[0.0; N]; N],
    };
    for i in 0..N {
        problem.a[i].copy_from_slice(&a[i][..N]);
        problem.g[i].copy_from_slice(&g[i][..N]);
    }
    // Non-finite entries make every step non-finite (refused there).
    if (0..N).any(|i| problem.a[i][i].is_nan() || problem.a[i][i] <= 0.0) {
        return None;
    }
    problem.solve(start)
}

/// The `n` damped modes of `(λ² A + λ G + I) z = 0` from start values `start` (upper half
/// plane, distinct, root `k` near the mode of coordinate `k`). Only the leading `n × n`
/// blocks are read, and only their upper triangles (both must be symmetric). `None` if `n` is
/// 0 or above [`MAX_DIM`], on a non-positive diagonal of `A` or non-finite input, if a root leaves
/// the upper half plane (an overdamped mode), on a vanishing pivot (two roots together) or if
/// the iteration did not converge within [`MAX_SWEEPS`] sweeps.
pub fn damped_modes(
    a: &[[f64; MAX_DIM]; MAX_DIM],
    g: &[[f64; MAX_DIM]; MAX_DIM],
    n: usize,
    start: &[Complex64; MAX_DIM],
) -> Option<DampedModes> {
    // One instance per size: fixed-size loops the compiler unrolls (at most MAX_DIM).
    match n {
        1 => solve_sized::<1>(a, g, start),
        2 => solve_sized::<2>(a, g, start),
        3 => solve_sized::<3>(a, g, start),
        4 => solve_sized::<4>(a, g, start),
        5 => solve_sized::<5>(a, g, start),
        6 => solve_sized::<6>(a, g, start),
        7 => solve_sized::<7>(a, g, start),
        8 => solve_sized::<8>(a, g, start),
        9 => solve_sized::<9>(a, g, start),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::sym_eigen::embed;

    fn diagonal(values: &[f64]) -> [[f64; MAX_DIM]; MAX_DIM] {
        let mut a = [[0.0; MAX_DIM]; MAX_DIM];
        for (i, &v) in values.iter().enumerate() {
            a[i][i] = v;
        }
        a
    }

    fn starts(values: &[Complex64]) -> [Complex64; MAX_DIM] {
        let mut s = [Complex64::new(0.0, 1.0); MAX_DIM];
        s[..values.len()].copy_from_slice(values);
        s
    }

    #[test]
    fn one_degree_of_freedom_is_the_damped_oscillator() {
        // m λ² + c λ + 1 = 0 (k = 1): λ = (−c ± i √(4m − c²)) / (2m).
        let (m, c) = (2.5e-5, 1.2e-3);
        let got = damped_modes(
            &diagonal(&[m]),
            &embed(&[&[c]]),
            1,
            &starts(&[Complex64::new(-1.0, 150.0)]),
        )
        .expect("underdamped");
        let want = Complex64::new(-c / (2.0 * m), (4.0 * m - c * c).sqrt() / (2.0 * m));
        assert!((got.roots[0] - want).norm() < 1e-12 * want.norm());
        assert!((got.vectors[0][0].norm() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn close_modes_do_not_collapse_onto_one_root() {
        // Two modes 2 % apart with strongly coupled, very different damping: both roots are
        // found, distinct, each with its own null vector. The vector is that of the root's last
        // iterate, within its last correction (here 1e-8) of the root: residual 1.2e-8
        // measured, bound 1e-6 (CONVERGED_STEP).
        let mu = [1.0 / 400.0f64.powi(2), 1.0 / 408.0f64.powi(2)];
        let g = embed(&[
            &[2.0 * 0.05 / 400.0, 0.3 / 400.0],
            &[0.3 / 400.0, 2.0 * 0.2 / 408.0],
        ]);
        let start = starts(&[Complex64::new(-20.0, 400.0), Complex64::new(-80.0, 400.0)]);
        let got = damped_modes(&diagonal(&mu), &g, 2, &start).expect("underdamped");
        assert!((got.roots[0] - got.roots[1]).norm() > 1.0);
        for k in 0..2 {
            let l = got.roots[k];
            let z = [got.vectors[0][k], got.vectors[1][k]];
            for r in 0..2 {
                let mut res = (l * l * mu[r] + 1.0) * z[r];
                for (c, &zc) in z.iter().enumerate() {
                    res += l * g[r][c] * zc;
                }
                assert!(res.norm() < 1e-6, "root {k}: residual {res}");
            }
        }
    }

    #[test]
    fn overdamped_and_bad_input_are_refused() {
        let one = starts(&[Complex64::new(-1.0, 10.0)]);
        // c² > 4 m: two real roots.
        assert!(damped_modes(&diagonal(&[1e-4]), &embed(&[&[1.0]]), 1, &one).is_none());
        assert!(damped_modes(&diagonal(&[f64::NAN]), &embed(&[&[0.0]]), 1, &one).is_none());
        assert!(damped_modes(&diagonal(&[1.0]), &embed(&[&[f64::NAN]]), 1, &one).is_none());
        assert!(damped_modes(&diagonal(&[-1.0]), &embed(&[&[0.0]]), 1, &one).is_none());
        assert!(damped_modes(&diagonal(&[1.0]), &embed(&[&[0.0]]), 0, &one).is_none());
        assert!(damped_modes(&diagonal(&[1.0]), &embed(&[&[0.0]]), 7, &one).is_none());
        let lower = starts(&[Complex64::new(-1.0, -10.0)]);
        assert!(damped_modes(&diagonal(&[1e-2]), &embed(&[&[0.0]]), 1, &lower).is_none());
    }
}
