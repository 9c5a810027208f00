//! The extra-insensitive (EI) shaper for a damped mode, designed exactly.
//!
//! Everything here is dimensionless: impulse times as phases `τ = ω_n t` (rad) and other
//! frequencies of the same damping ratio as ratios `r = ω/ω_n`. With `s = ζ + i√(1−ζ²)`, the
//! residual vibration (eqs. 52–55) of impulses `A_i` at `τ_i` on the mode of ratio `r` is
//! `PRV(r) = |W(r)|`, `W(r) = Σ A_i e^{s r (τ_i − τ_3)}`; it vanishes where
//! `Z(r) = Σ A_i e^{s r τ_i} = W(r) e^{s r τ_3}` does.
//!
//! The EI shaper has three impulses `A = [A1, 1 − A1 − A3, A3]` at `τ = [0, τ2, τ3]` and meets,
//! for the vibration tolerance `V`,
//! 1. `PRV(1) = V` (the design point sits at the tolerance),
//! 2. `dPRV/dr (1) = 0` (it is the local maximum between the two zeros),
//! 3. `Z(r_lo) = 0` and `Z(r_hi) = 0` for two ratios `r_lo < 1 < r_hi` (real and imaginary
//!    parts: four equations).
//!
//! Six equations in `x = [A1, A3, τ2, τ3, r_lo, r_hi]`, solved by Newton's method with an
//! analytic Jacobian. The published polynomial-in-ζ fit ([`polynomial`]) is the initial guess;
//! the zeros are first located as the minima of its residual vibration. For `ζ = 0` the
//! solution is the closed form `A = [(1+V)/4, (1−V)/2, (1+V)/4]`, `τ = [0, π, 2π]`.
//!
//! Everything is allocation-free and panic-free (fixed-size arrays, bounded loops), so
//! [`design`] runs every control cycle. It converges in at most 8 iterations over the supported
//! range `V ∈ [MIN_TOLERANCE, MAX_TOLERANCE]`, `ζ <= max_zeta(V)` (checked on a dense grid by
//! the tests); the bound [`MAX_NEWTON_ITERATIONS`] leaves twice that.

use core::f64::consts::PI;
use core::ops::{Add, Mul, Sub};

/// Smallest supported vibration tolerance. Below it the two zeros merge towards the ZVD double
/// zero, the equations become singular and Newton's method no longer converges reliably
/// (it does down to about 0.002); a ZVD shaper is the right choice there.
pub const MIN_TOLERANCE: f64 = 0.005;

/// Largest supported vibration tolerance (the range of the published fit).
pub const MAX_TOLERANCE: f64 = 0.2;

/// Iteration cap of the Newton refinement (deterministic cost per design).
pub const MAX_NEWTON_ITERATIONS: usize = 16;

/// Newton has converged when no unknown moves by more than this (phases up to 2π/√(1−ζ²) rad,
/// ratios about 1, amplitudes below 1); quadratic convergence leaves an error far below it.
const STEP_TOLERANCE: f64 = 1e-12;

/// A converged solution further than this from the polynomial fit (largest amplitude change;
/// the measured maximum over the supported range is 0.023) belongs to another branch and is
/// rejected.
const MAX_AMPLITUDE_CHANGE: f64 = 0.05;

/// Same for the times, as a fraction of the damped period (measured maximum 0.048).
const MAX_TIME_CHANGE_PERIODS: f64 = 0.1;

/// Largest damping ratio of the EI shaper with tolerance `v_tol`: 0.4 up to `V = 0.1`, then
/// falling linearly to 0.28 at `V = 0.2`. Beyond it, for large `V`, the exact solution's upper
/// zero runs away (`r_hi → 3.9` before the solution ceases to exist near ζ = 0.39 at V = 0.2)
/// and the polynomial fit, the starting point, degrades (at V = 0.2, ζ = 0.4 its times are no
/// longer sorted); the residual vibration above `r_hi`, which tends to `A3` at high
/// frequencies, sinks below `V`. Newton still converges at least 0.019 beyond this bound
/// (measured for `V` in steps of 0.005).
pub fn max_zeta(v_tol: f64) -> f64 {
    (0.4 - 1.2 * (v_tol - 0.1).max(0.0)).clamp(0.0, 0.4)
}

/// An EI shaper: amplitudes (summing to 1), impulse phases `ω_n t_i` (rad) and the two
/// frequency ratios of zero vibration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EiSolution {
    pub amplitudes: [f64; 3],
    pub phases_rad: [f64; 3],
    /// `[r_lo, r_hi]`: `ω/ω_n` where the residual vibration is zero (same ζ).
    pub zero_ratios: [f64; 2],
    /// Newton iterations used (0 for the polynomial fit).
    pub iterations: usize,
}

/// The EI shaper for `(v_tol, zeta)`: the exact solution, or — if Newton's method does not
/// converge to it (never inside the supported range; possible for a tolerance or damping
/// ratio outside it) — the published polynomial fit.
pub fn design(v_tol: f64, zeta: f64) -> EiSolution {
    exact(v_tol, zeta).unwrap_or_else(|| polynomial(v_tol, zeta))
}

/// The published polynomial-in-ζ fit (amplitudes and middle time; last impulse at the damped
/// period). Its design-point vibration misses `V` by up to 1.2e-3 (V = 5 %, ζ <= 0.2),
/// 3.9e-3 (5 %, ζ <= 0.4), 4.8e-3 (10 %) and 1.2e-2 (20 %); it is the starting point of
/// [`exact`]. Its zero ratios are those of the undamped exact shaper.
pub fn polynomial(v_tol: f64, zeta: f64) -> EiSolution {
    let (v, z) = (v_tol, zeta);
    let a1 = (0.24968 + 0.24961 * v) + ((0.80008 + 1.23328 * v) + (0.49599 + 3.17316 * v) * z) * z;
    let a3 = (0.25149 + 0.21474 * v) + ((-0.83249 + 1.41498 * v) + (0.85181 - 4.90094 * v) * z) * z;
    let t2_periods = 0.4999
        + (((0.46159 + 8.57843 * v) * v)
            + (((4.26169 - 108.644 * v) * v) + ((1.75601 + 336.989 * v) * v) * z) * z)
            * z;
    let period_rad = 2.0 * PI / (1.0 - z * z).sqrt(); // ω_n T_d
    let r_lo = undamped_zero_ratio(v);
    EiSolution {
        amplitudes: [a1, 1.0 - a1 - a3, a3],
        phases_rad: [0.0, t2_periods * period_rad, period_rad],
        zero_ratios: [r_lo, 2.0 - r_lo],
        iterations: 0,
    }
}

/// The lower zero of the undamped EI shaper: `cos(π r) = −(1−V)/(1+V)`.
fn undamped_zero_ratio(v_tol: f64) -> f64 {
    (-(1.0 - v_tol) / (1.0 + v_tol)).acos() / PI
}

/// The exact EI shaper (see the module documentation), or `None` if `v_tol` is not in (0, 1),
/// `zeta` not in [0, 1), or Newton's method, started from the polynomial fit, did not converge
/// to a valid shaper ([`refine`]) close to that fit (the intended branch).
pub fn exact(v_tol: f64, zeta: f64) -> Option<EiSolution> {
    let fit = polynomial(v_tol, zeta);
    let s = Complex::new(zeta, (1.0 - zeta * zeta).sqrt());
    let [r_lo0, r_hi0] = fit.zero_ratios;
    let r_lo = vibration_minimum(&fit, s, r_lo0);
    let r_hi = vibration_minimum(&fit, s, r_hi0);
    let start = EiSolution {
        zero_ratios: if r_lo < 1.0 && r_hi > 1.0 {
            [r_lo, r_hi]
        } else {
            [r_lo0, r_hi0]
        },
        ..fit
    };
    refine(v_tol, zeta, &start).filter(|solution| is_near(solution, &fit))
}

/// Newton's method on the six EI conditions from `start` (its amplitudes `A1`, `A3`, phases
/// `τ2`, `τ3` and zero ratios; `A2` follows from `Σ A = 1`). `None` if `v_tol` is not in (0, 1),
/// `zeta` not in [0, 1), the iteration did not converge within [`MAX_NEWTON_ITERATIONS`], or
/// the result is not a valid shaper: positive amplitudes, `0 < τ2 < τ3`, `r_lo < 1 < r_hi`.
pub fn refine(v_tol: f64, zeta: f64, start: &EiSolution) -> Option<EiSolution> {
    if !(v_tol > 0.0 && v_tol < 1.0 && (0.0..1.0).contains(&zeta)) {
        return None;
    }
    let s = Complex::new(zeta, (1.0 - zeta * zeta).sqrt());
    let mut x = [
        start.amplitudes[0],
        start.amplitudes[2],
        start.phases_rad[1],
        start.phases_rad[2],
        start.zero_ratios[0],
        start.zero_ratios[1],
    ];
    for iteration in 1..=MAX_NEWTON_ITERATIONS {
        let (f, jacobian) = conditions(&x, v_tol, s);
        let step = solve_linear(jacobian, f)?;
        let mut largest = 0.0f64;
        for (xi, di) in x.iter_mut().zip(step) {
            *xi -= di;
            largest = largest.max(di.abs());
        }
        if !x.iter().all(|v| v.is_finite()) {
            return None;
        }
        if largest <= STEP_TOLERANCE {
            let [a1, a3, tau2, tau3, r_lo, r_hi] = x;
            let solution = EiSolution {
                amplitudes: [a1, 1.0 - a1 - a3, a3],
                phases_rad: [0.0, tau2, tau3],
                zero_ratios: [r_lo, r_hi],
                iterations: iteration,
            };
            let valid = solution.amplitudes.iter().all(|&a| a > 0.0)
                && 0.0 < tau2
                && tau2 < tau3
                && r_lo < 1.0
                && r_hi > 1.0;
            return valid.then_some(solution);
        }
    }
    // No convergence within the cap: `design` falls back to the polynomial fit.
    None
}

/// True if `solution` is within [`MAX_AMPLITUDE_CHANGE`] and [`MAX_TIME_CHANGE_PERIODS`] of
/// the polynomial fit `fit`.
fn is_near(solution: &EiSolution, fit: &EiSolution) -> bool {
    let largest_change = |a: &[f64; 3], b: &[f64; 3]| {
        a.iter()
            .zip(b)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
    };
    let period_rad = fit.phases_rad[2];
    largest_change(&solution.amplitudes, &fit.amplitudes) <= MAX_AMPLITUDE_CHANGE
        && largest_change(&solution.phases_rad, &fit.phases_rad)
            <= MAX_TIME_CHANGE_PERIODS * period_rad
}

/// The ratio of least residual vibration of `shaper` near `r`: Newton's method on
/// `d|W|²/dr = 0`, each step limited to 0.1, at most 12 steps; a rough starting point only.
fn vibration_minimum(shaper: &EiSolution, s: Complex, mut r: f64) -> f64 {
    let tau3 = shaper.phases_rad[2];
    for _ in 0..12 {
        let (mut w, mut dw, mut d2w) = (Complex::ZERO, Complex::ZERO, Complex::ZERO);
        for (&a, &tau) in shaper.amplitudes.iter().zip(&shaper.phases_rad) {
            let k = s * (tau - tau3); // d/dr of the exponent
            let term = (k * r).exp() * a;
            w = w + term;
            dw = dw + k * term;
            d2w = d2w + k * k * term;
        }
        let slope = w.dot(dw); // ½ d|W|²/dr
        let curvature = dw.norm_sqr() + w.dot(d2w); // ½ d²|W|²/dr²
        let step = if curvature > 0.0 {
            -slope / curvature
        } else {
            -0.05 * slope.signum()
        };
        let step = step.clamp(-0.1, 0.1);
        if !step.is_finite() {
            break;
        }
        r += step;
        if step.abs() < 1e-4 {
            break;
        }
    }
    r
}

/// The six conditions `F(x)` and their Jacobian `∂F/∂x` for `x = [A1, A3, τ2, τ3, r_lo, r_hi]`.
fn conditions(x: &[f64; 6], v_tol: f64, s: Complex) -> ([f64; 6], [[f64; 6]; 6]) {
    let [a1, a3, tau2, tau3, r_lo, r_hi] = *x;
    let a2 = 1.0 - a1 - a3;
    let mut f = [0.0; 6];
    let mut jac = [[0.0; 6]; 6];

    // Design point, r = 1: W = A1 E1 + A2 E2 + A3 with E1 = e^{−s τ3}, E2 = e^{s d}, d = τ2 − τ3.
    let d = tau2 - tau3;
    let e1 = (s * -tau3).exp();
    let e2 = (s * d).exp();
    let w = e1 * a1 + e2 * a2 + Complex::real(a3);
    // W' = dW/dr = s (−τ3 A1 E1 + d A2 E2)
    let dw = s * (e1 * (-tau3 * a1) + e2 * (d * a2));
    // ∂W/∂(A1, A3, τ2, τ3)
    let w_x = [
        e1 - e2,
        Complex::real(1.0) - e2,
        s * e2 * a2,
        (s * e1 * a1 + s * e2 * a2) * -1.0,
    ];
    // ∂W'/∂(A1, A3, τ2, τ3)
    let one = Complex::real(1.0);
    let dw_x = [
        s * (e1 * -tau3 - e2 * d),
        s * (e2 * -d),
        s * e2 * a2 * (one + s * d),
        s * ((e1 * a1 * (one - s * tau3)) + (e2 * a2 * (one + s * d))) * -1.0,
    ];
    f[0] = w.norm_sqr() - v_tol * v_tol;
    f[1] = w.dot(dw);
    for k in 0..4 {
        jac[0][k] = 2.0 * w.dot(w_x[k]);
        jac[1][k] = w_x[k].dot(dw) + w.dot(dw_x[k]);
    }

    // Zeros: Z(r) = A1 + A2 G2 + A3 G3 with G2 = e^{s r τ2}, G3 = e^{s r τ3}.
    for (row, col, r) in [(2, 4, r_lo), (4, 5, r_hi)] {
        let g2 = (s * (r * tau2)).exp();
        let g3 = (s * (r * tau3)).exp();
        let z = Complex::real(a1) + g2 * a2 + g3 * a3;
        let z_x = [one - g2, g3 - g2, s * g2 * (a2 * r), s * g3 * (a3 * r)];
        let z_r = s * (g2 * (a2 * tau2) + g3 * (a3 * tau3));
        f[row] = z.re;
        f[row + 1] = z.im;
        for k in 0..4 {
            jac[row][k] = z_x[k].re;
            jac[row + 1][k] = z_x[k].im;
        }
        jac[row][col] = z_r.re;
        jac[row + 1][col] = z_r.im;
    }
    (f, jac)
}

/// Solves `a · x = b` by Gaussian elimination with partial pivoting; `None` if `a` is singular
/// (a zero or non-finite pivot).
fn solve_linear(mut a: [[f64; 6]; 6], mut b: [f64; 6]) -> Option<[f64; 6]> {
    for col in 0..6 {
        let mut pivot = col;
        for row in col + 1..6 {
            if a[row][col].abs() > a[pivot][col].abs() {
                pivot = row;
            }
        }
        let p = a[pivot][col];
        if !(p.is_finite() && p != 0.0) {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        let pivot_row = a[col];
        for row in col + 1..6 {
            let factor = a[row][col] / p;
            for (target, &source) in a[row][col..].iter_mut().zip(&pivot_row[col..]) {
                *target -= factor * source;
            }
            b[row] -= factor * b[col];
        }
    }
    let mut x = [0.0; 6];
    for row in (0..6).rev() {
        let known: f64 = a[row][row + 1..]
            .iter()
            .zip(&x[row + 1..])
            .map(|(c, v)| c * v)
            .sum();
        x[row] = (b[row] - known) / a[row][row];
    }
    Some(x)
}

/// Nodes of an [`EiTable`]: with 6-point interpolation the table stays within 1e-13 of the
/// exact solution over the supported range (checked by the tests).
pub const TABLE_NODES: usize = 257;

/// Points of the interpolation stencil (degree 5: error `O(h⁶)`).
const STENCIL: usize = 6;

/// Lagrange weights of the nodes `0..6` at `t` (`t ∈ [0, 5]`); exactly `1, 0, …` at a node.
#[inline]
fn lagrange6(t: f64) -> [f64; STENCIL] {
    let d = [t, t - 1.0, t - 2.0, t - 3.0, t - 4.0, t - 5.0];
    // Products of all differences but one, from both sides.
    let mut left = [1.0; STENCIL];
    let mut right = [1.0; STENCIL];
    for j in 1..STENCIL {
        left[j] = left[j - 1] * d[j - 1];
        right[STENCIL - 1 - j] = right[STENCIL - j] * d[STENCIL - j];
    }
    // Π_{m≠j} (j − m): −120, 24, −12, 12, −24, 120.
    const DENOMINATORS: [f64; STENCIL] = [-120.0, 24.0, -12.0, 12.0, -24.0, 120.0];
    let mut w = [0.0; STENCIL];
    for j in 0..STENCIL {
        w[j] = left[j] * right[j] / DENOMINATORS[j];
    }
    w
}

/// The exact EI solution tabulated over the damping ratios `[0, max_zeta(v_tol)]`, for the
/// time-varying filter: a new `ζ` every cycle costs a 6-point interpolation instead of a
/// Newton solve.
///
/// The solution `[A1, A3, τ2, τ3]` is an analytic function of `ζ` (the conditions are
/// analytic and their Jacobian is regular on the supported range), so degree-5 interpolation on
/// a uniform grid of spacing `h` is accurate to `O(h⁶)`. Nodes are [`design`] itself, so at a
/// node (in particular at `max_zeta`, where out-of-range modes are designed) the table equals
/// the offline design bit for bit. Built once at setup (allocates); [`Self::shape`] is
/// allocation- and panic-free.
#[derive(Debug, Clone, PartialEq)]
pub struct EiTable {
    max_zeta: f64,
    /// `(TABLE_NODES − 1) / max_zeta`: nodes per unit of ζ.
    nodes_per_zeta: f64,
    /// `[A1, A3, τ2, τ3]` at `ζ_k = k · max_zeta / (TABLE_NODES − 1)`.
    nodes: Vec<[f64; 4]>,
}

impl EiTable {
    /// Solves the `TABLE_NODES` exact shapers for tolerance `v_tol` (setup time, about a
    /// millisecond).
    pub fn new(v_tol: f64) -> EiTable {
        let max_zeta = max_zeta(v_tol);
        let last = (TABLE_NODES - 1) as f64;
        let nodes = (0..TABLE_NODES)
            .map(|k| {
                // The last node is max_zeta exactly (the filter designs out-of-range modes there).
                let zeta = if k + 1 == TABLE_NODES {
                    max_zeta
                } else {
                    max_zeta * k as f64 / last
                };
                let s = design(v_tol, zeta);
                [
                    s.amplitudes[0],
                    s.amplitudes[2],
                    s.phases_rad[1],
                    s.phases_rad[2],
                ]
            })
            .collect();
        EiTable {
            max_zeta,
            nodes_per_zeta: if max_zeta > 0.0 { last / max_zeta } else { 0.0 },
            nodes,
        }
    }

    /// Largest damping ratio covered (larger ones read the last node).
    pub fn max_zeta(&self) -> f64 {
        self.max_zeta
    }

    /// Amplitudes (summing to 1) and phases `ω_n t_i` (rad) of the EI shaper for `zeta`
    /// (limited to `[0, max_zeta]`; NaN reads the last node).
    #[inline]
    pub fn shape(&self, zeta: f64) -> ([f64; 3], [f64; 3]) {
        let n = self.nodes.len();
        let [a1, a3, tau2, tau3] = if zeta.is_nan() || zeta >= self.max_zeta || n < STENCIL {
            self.nodes
                .last()
                .copied()
                .unwrap_or([0.25, 0.25, PI, 2.0 * PI])
        } else {
            let x = zeta.max(0.0) * self.nodes_per_zeta;
            // Stencil k0..k0+6 centred on the interval of x, shifted inwards at both ends.
            let k0 = (x as usize)
                .saturating_sub(STENCIL / 2 - 1)
                .min(n - STENCIL);
            let weights = lagrange6(x - k0 as f64);
            let mut v = [0.0; 4];
            if let Some(stencil) = self.nodes.get(k0..k0 + STENCIL) {
                for (node, w) in stencil.iter().zip(weights) {
                    for (vi, ni) in v.iter_mut().zip(node) {
                        *vi += w * ni;
                    }
                }
            }
            v
        };
        ([a1, 1.0 - a1 - a3, a3], [0.0, tau2, tau3])
    }
}

/// Minimal complex arithmetic for the conditions (no dependency needed).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Complex {
    re: f64,
    im: f64,
}

impl Complex {
    const ZERO: Complex = Complex { re: 0.0, im: 0.0 };

    const fn new(re: f64, im: f64) -> Complex {
        Complex { re, im }
    }

    const fn real(re: f64) -> Complex {
        Complex { re, im: 0.0 }
    }

    fn exp(self) -> Complex {
        let m = self.re.exp();
        let (sin, cos) = self.im.sin_cos();
        Complex::new(m * cos, m * sin)
    }

    fn norm_sqr(self) -> f64 {
        self.re * self.re + self.im * self.im
    }

    /// `Re(conj(self) · other)`.
    fn dot(self, other: Complex) -> f64 {
        self.re * other.re + self.im * other.im
    }
}

impl Add for Complex {
    type Output = Complex;
    fn add(self, o: Complex) -> Complex {
        Complex::new(self.re + o.re, self.im + o.im)
    }
}

impl Sub for Complex {
    type Output = Complex;
    fn sub(self, o: Complex) -> Complex {
        Complex::new(self.re - o.re, self.im - o.im)
    }
}

impl Mul for Complex {
    type Output = Complex;
    fn mul(self, o: Complex) -> Complex {
        Complex::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
}

impl Mul<f64> for Complex {
    type Output = Complex;
    fn mul(self, k: f64) -> Complex {
        Complex::new(self.re * k, self.im * k)
    }
}
