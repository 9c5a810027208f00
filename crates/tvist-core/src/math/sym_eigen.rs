//! Eigenvalues and eigenvectors of small symmetric matrices (at most [`MAX_DIM`]), by the
//! cyclic Jacobi method: fixed-size arrays, no allocation, no panic, a bounded number of
//! sweeps.
//!
//! Jacobi is the method of choice here: the matrices are tiny (2-9), it is unconditionally
//! stable, gives orthonormal eigenvectors to machine precision even for (nearly) repeated
//! eigenvalues, and converges quadratically (3-6 sweeps for a 3 × 3 matrix to full
//! precision).

/// Largest matrix dimension handled.
pub const MAX_DIM: usize = 9;

/// A `MAX_DIM × MAX_DIM` matrix whose leading block is used.
pub type Matrix = [[f64; MAX_DIM]; MAX_DIM];

/// Upper bound on the number of sweeps. Quadratic convergence needs far fewer (about 6 for
/// n = 6 to double precision); the bound only guarantees termination for any input.
pub const MAX_SWEEPS: usize = 50;

/// Symmetric eigen-decomposition of the leading `n × n` block of `a`.
///
/// Returns `(eigenvalues, eigenvectors)` with eigenvector `i` in **column** `i`
/// (`vectors[row][i]`), orthonormal; entries beyond `n` are zero. Only the leading block of
/// `a` is read, and only its upper triangle is trusted to be the symmetric matrix (the lower
/// one is overwritten from it). `None` if `n` is 0 or larger than [`MAX_DIM`], if an entry is
/// not finite, or (never seen in practice) if the off-diagonal norm did not fall below
/// `1e-12` of the matrix norm within [`MAX_SWEEPS`] sweeps.
pub fn sym_eigen(
    a: &[[f64; MAX_DIM]; MAX_DIM],
    n: usize,
) -> Option<([f64; MAX_DIM], [[f64; MAX_DIM]; MAX_DIM])> {
    let (rotated, vectors) = sym_diagonalize(a, n, FULL_PRECISION)?;
    let mut values = [0.0; MAX_DIM];
    for (i, value) in values.iter_mut().enumerate().take(n) {
        *value = rotated[i][i];
    }
    Some((values, vectors))
}

/// Off-diagonal tolerance of [`sym_eigen`]: the eigenvalues then carry a relative error of
/// order `1e-24` (second order in the off-diagonal part) and the eigenvectors one of order
/// `1e-12`; one sweep short of full rounding precision.
pub const FULL_PRECISION: f64 = 1e-12;

/// Jacobi rotations of the leading `n × n` block of symmetric `a` until the off-diagonal norm
/// of the rotated matrix is at most `off_tolerance` times the norm of `a`.
///
/// Returns `(Vᵀ A V, V)`: the rotated matrix (symmetric, entries beyond `n` zero) and the
/// orthonormal rotation, column `i` its `i`-th vector. With `off_tolerance` [`FULL_PRECISION`]
/// the diagonal holds the eigenvalues ([`sym_eigen`]); a looser tolerance gives a nearly
/// diagonal form for fewer sweeps, exact as a change of coordinates (the rotation is
/// orthonormal to rounding whatever the tolerance). `None` as for [`sym_eigen`].
pub fn sym_diagonalize(
    a: &[[f64; MAX_DIM]; MAX_DIM],
    n: usize,
    off_tolerance: f64,
) -> Option<(Matrix, Matrix)> {
    // One instance per size: fixed-size loops the compiler unrolls.
    match n {
        1 => jacobi::<1>(a, off_tolerance),
        2 => jacobi::<2>(a, off_tolerance),
        3 => jacobi::<3>(a, off_tolerance),
        4 => jacobi::<4>(a, off_tolerance),
        5 => jacobi::<5>(a, off_tolerance),
        6 => jacobi::<6>(a, off_tolerance),
        7 => jacobi::<7>(a, off_tolerance),
        8 => jacobi::<8>(a, off_tolerance),
        9 => jacobi::<9>(a, off_tolerance),
        _ => None,
    }
}

/// [`sym_diagonalize`] at a compile-time size `N ≤ MAX_DIM`.
#[allow(clippy::needless_range_loop)] // index loops mirror the textbook rotation formulas
fn jacobi<const N: usize>(
    a: &[[f64; MAX_DIM]; MAX_DIM],
    off_tolerance: f64,
) -> Option<(Matrix, Matrix)> {
    let n = N;
    let mut m = [[0.0; N]; N];
    let mut v = [[0.0; N]; N];
    let mut norm2 = 0.0;
    for p in 0..n {
        v[p][p] = 1.0;
        for q in p..n {
            let x = a[p][q];
            if !x.is_finite() {
                return None;
            }
            m[p][q] = x;
            m[q][p] = x;
            norm2 += if p == q { x * x } else { 2.0 * x * x };
        }
    }
    let mut converged = false;
    for _ in 0..MAX_SWEEPS {
        let mut off2 = 0.0;
        for p in 0..n {
            for q in p + 1..n {
                off2 += m[p][q] * m[p][q];
            }
        }
        // Squared norms; off2 counts each symmetric pair once.
        if off2 <= off_tolerance * off_tolerance * norm2 {
            converged = true;
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = m[p][q];
                if apq == 0.0 {
                    continue;
                }
                // Rotation in the (p, q) plane that zeroes m[p][q]: t = tan φ is the smaller
                // root of t² + 2θt − 1 = 0, θ = (m_qq − m_pp) / (2 m_pq).
                let theta = (m[q][q] - m[p][p]) / (2.0 * apq);
                let t = if theta.abs() > 1e150 {
                    0.5 / theta
                } else {
                    theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt())
                };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..n {
                    let (mkp, mkq) = (m[k][p], m[k][q]);
                    m[k][p] = c * mkp - s * mkq;
                    m[k][q] = s * mkp + c * mkq;
                }
                for k in 0..n {
                    let (mpk, mqk) = (m[p][k], m[q][k]);
                    m[p][k] = c * mpk - s * mqk;
                    m[q][k] = s * mpk + c * mqk;
                }
                for k in 0..n {
                    let (vkp, vkq) = (v[k][p], v[k][q]);
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
        }
    }
    if !converged {
        return None;
    }
    let mut rotated = [[0.0; MAX_DIM]; MAX_DIM];
    let mut vectors = [[0.0; MAX_DIM]; MAX_DIM];
    for i in 0..n {
        rotated[i][..n].copy_from_slice(&m[i]);
        vectors[i][..n].copy_from_slice(&v[i]);
    }
    Some((rotated, vectors))
}

/// The leading block `rows` in a [`Matrix`] (unit tests of the modules built on it).
#[cfg(test)]
pub(crate) fn embed(rows: &[&[f64]]) -> Matrix {
    let mut a = [[0.0; MAX_DIM]; MAX_DIM];
    for (i, r) in rows.iter().enumerate() {
        a[i][..r.len()].copy_from_slice(r);
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_by_two_matches_the_closed_form() {
        // Eigenvalues of [[a, b], [b, d]]: (a + d)/2 ± √(((a − d)/2)² + b²).
        let (a, b, d) = (3.0, 1.25, -0.5);
        let (vals, vecs) = sym_eigen(&embed(&[&[a, b], &[b, d]]), 2).expect("converges");
        let mid = 0.5 * (a + d);
        let rad = (0.25 * (a - d) * (a - d) + b * b).sqrt();
        let mut got = [vals[0], vals[1]];
        got.sort_by(f64::total_cmp);
        assert!((got[0] - (mid - rad)).abs() < 1e-14 && (got[1] - (mid + rad)).abs() < 1e-14);
        // A v = λ v for each column.
        for i in 0..2 {
            let (x, y) = (vecs[0][i], vecs[1][i]);
            assert!((a * x + b * y - vals[i] * x).abs() < 1e-14);
            assert!((b * x + d * y - vals[i] * y).abs() < 1e-14);
        }
    }

    #[test]
    #[allow(clippy::needless_range_loop)] // a symmetric fill reads clearest with indices
    fn six_by_six_residuals_and_orthonormality() {
        let mut a = [[0.0; MAX_DIM]; MAX_DIM];
        let mut seed = 7u64;
        for p in 0..6 {
            for q in p..6 {
                seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
                let x = ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5;
                a[p][q] = x;
                a[q][p] = x;
            }
        }
        let (vals, v) = sym_eigen(&a, 6).expect("converges");
        for i in 0..6 {
            for r in 0..6 {
                let av: f64 = (0..6).map(|k| a[r][k] * v[k][i]).sum();
                assert!((av - vals[i] * v[r][i]).abs() < 1e-13);
            }
            for j in 0..6 {
                let dot: f64 = (0..6).map(|k| v[k][i] * v[k][j]).sum();
                let expect = if i == j { 1.0 } else { 0.0 };
                assert!((dot - expect).abs() < 1e-13);
            }
        }
    }

    #[test]
    fn repeated_eigenvalues_and_bad_input() {
        let (vals, _) = sym_eigen(&embed(&[&[2.0, 0.0], &[0.0, 2.0]]), 2).expect("diagonal");
        assert_eq!(&vals[..2], &[2.0, 2.0]);
        assert!(sym_eigen(&embed(&[&[f64::NAN]]), 1).is_none());
        assert!(sym_eigen(&embed(&[&[1.0]]), 0).is_none());
        assert!(sym_eigen(&embed(&[&[1.0]]), MAX_DIM + 1).is_none());
    }
}
