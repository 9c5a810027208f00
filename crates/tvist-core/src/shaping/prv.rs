//! Percent residual vibration (eqs. 52–55).
//!
//! For impulses `(A_i, t_i)` applied to an underdamped mode `(ω_n, ζ)`:
//! `PRV = e^{−ζω_n t_N} √(C² + S²)`, `C = Σ A_i e^{ζω_n t_i} cos(ω_d t_i)`,
//! `S = Σ A_i e^{ζω_n t_i} sin(ω_d t_i)`. It is the residual amplitude relative to an
//! unshaped step (a fraction: 1.0 = 100 %). The exponent is applied as `e^{ζω_n (t_i − t_N)}`
//! so large `ζω_n t` cannot overflow.

/// Residual vibration fraction of the sequence on mode `(wn_rad_s, zeta)`.
///
/// `amplitudes` and `times_s` have equal length (extra entries of the longer one are ignored).
/// Returns NaN for an invalid mode (`wn <= 0`, `zeta` outside `[0, 1)`).
pub fn prv(amplitudes: &[f64], times_s: &[f64], wn_rad_s: f64, zeta: f64) -> f64 {
    if !(wn_rad_s > 0.0 && (0.0..1.0).contains(&zeta)) {
        return f64::NAN;
    }
    let wd = wn_rad_s * (1.0 - zeta * zeta).sqrt();
    let times_s = &times_s[..times_s.len().min(amplitudes.len())];
    let t_last = times_s.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (mut c, mut s) = (0.0, 0.0);
    for (&a, &t) in amplitudes.iter().zip(times_s) {
        let w = a * (zeta * wn_rad_s * (t - t_last)).exp();
        let (sin, cos) = (wd * t).sin_cos();
        c += w * cos;
        s += w * sin;
    }
    (c * c + s * s).sqrt()
}
