//! The physically based dynamic map (paper eqs. 42–51): modes `(ω_n, ζ)` from joint inertias.
//!
//! One [`ModeMap`] per mode holds the ten coefficients of eqs. 42–43 and says which joint
//! drives it. With `J_f` the inertia of the *frequency joint*, `J_d` that of the *damping
//! joint*, `τ_f` the gravity torque of the frequency joint and `K = k_0 + k_J J_f + k_g |τ_f|`:
//!
//! ```text
//! ω_n = √(1 + k_p/J_f) · √(K / J_f)
//! ζ   = (1 + k_p/J_d)^e_d · (1 + k_p/J_f)^e_f · (c_0 + c_1 √J_d + c_2 J_d)(1 + c_τ J_d) / (2 √(K J_f))
//! ```
//!
//! - General map (eqs. 42–43) for joint `j`: `J_f = J_d = J_j`, `e_d = ½`, `e_f = 0`
//!   ([`ModeMap::general`]); the reduced map (eqs. 44–45) is the same with `c_1 = k_g = 0`.
//! - UR5e base mode as printed (eqs. 47–48): `J_f = J_1`, `J_d = J_0`, `e_d = 1` (no square
//!   root on `1 + k_p/J_0`), `e_f = −½`. "Base frequency from `J_0`" (eq. 46) is
//!   `ModeMap::general(coefficients, 0)`.
//!
//! Evaluation is allocation-free. An input that gives no underdamped mode (`J <= 0`, `K <= 0`,
//! `1 + k_p/J <= 0`, non-finite values, or `ζ >= 1`) yields a mode that fails
//! [`Mode::is_valid`], which a [`crate::ModeFilter`] holds over.

use crate::error::{Error, Status};
use crate::shaper::Mode;

/// The ten coefficients of eqs. 42–43 (SI units: N m/rad, N m s, kg m²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapCoefficients {
    /// Stiffness at zero inertia, N m/rad.
    pub k_0: f64,
    /// Stiffness per unit inertia, N m/rad/(kg m²).
    pub k_j: f64,
    /// Stiffness per unit gravity torque, 1/rad.
    pub k_g: f64,
    /// Proportional-gain coefficient, kg m².
    pub k_p: f64,
    /// Damping coefficients: constant (N m s), per √J, per J.
    pub c_0: f64,
    pub c_1: f64,
    pub c_2: f64,
    /// Torque coefficient, 1/(kg m²).
    pub c_tau: f64,
}

impl MapCoefficients {
    /// The reduced map's coefficients (eqs. 44–45: `k_g = c_1 = 0`).
    pub const fn reduced(k_0: f64, k_j: f64, k_p: f64, c_0: f64, c_2: f64, c_tau: f64) -> Self {
        MapCoefficients {
            k_0,
            k_j,
            k_g: 0.0,
            k_p,
            c_0,
            c_1: 0.0,
            c_2,
            c_tau,
        }
    }

    fn as_array(&self) -> [(&'static str, f64); 8] {
        [
            ("k_0", self.k_0),
            ("k_j", self.k_j),
            ("k_g", self.k_g),
            ("k_p", self.k_p),
            ("c_0", self.c_0),
            ("c_1", self.c_1),
            ("c_2", self.c_2),
            ("c_tau", self.c_tau),
        ]
    }
}

/// The map of one mode: coefficients plus which joint inertias drive frequency and damping.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModeMap {
    pub coefficients: MapCoefficients,
    /// Joint whose inertia (and gravity torque) sets the frequency: `J_f`, `τ_f`.
    pub frequency_joint: usize,
    /// Joint whose inertia sets the damping numerator: `J_d`.
    pub damping_joint: usize,
    /// Exponent `e_d` of `(1 + k_p/J_d)` in `ζ`.
    pub damping_gain_exponent: f64,
    /// Exponent `e_f` of `(1 + k_p/J_f)` in `ζ`.
    pub frequency_gain_exponent: f64,
}

impl ModeMap {
    /// The general map of eqs. 42–43 with `J = J_joint`.
    pub const fn general(coefficients: MapCoefficients, joint: usize) -> Self {
        ModeMap {
            coefficients,
            frequency_joint: joint,
            damping_joint: joint,
            damping_gain_exponent: 0.5,
            frequency_gain_exponent: 0.0,
        }
    }

    /// The UR5e base-mode form of eqs. 47–48 as printed: frequency from `J_1`, damping
    /// numerator from `J_0` with `(1 + k_p/J_0)` unsquared, divided by `√(1 + k_p/J_1)`.
    pub const fn base_from_shoulder(
        coefficients: MapCoefficients,
        base: usize,
        shoulder: usize,
    ) -> Self {
        ModeMap {
            coefficients,
            frequency_joint: shoulder,
            damping_joint: base,
            damping_gain_exponent: 1.0,
            frequency_gain_exponent: -0.5,
        }
    }

    /// Largest joint index used, plus one.
    pub fn required_joints(&self) -> usize {
        self.frequency_joint.max(self.damping_joint) + 1
    }

    /// True if the gravity-torque term is active (`k_g != 0`).
    pub fn uses_gravity(&self) -> bool {
        self.coefficients.k_g != 0.0
    }

    /// Mode for inertias `j` and gravity torques `tau_g` (ignored when `k_g == 0`). Returns an
    /// invalid mode (NaN) when the inputs give no positive stiffness or inertia.
    #[inline]
    pub fn evaluate(&self, j: &[f64], tau_g: &[f64]) -> Mode {
        let invalid = Mode::new(f64::NAN, f64::NAN);
        let (Some(&j_f), Some(&j_d)) = (j.get(self.frequency_joint), j.get(self.damping_joint))
        else {
            return invalid;
        };
        let c = &self.coefficients;
        let gravity = if c.k_g != 0.0 {
            match tau_g.get(self.frequency_joint) {
                Some(t) => c.k_g * t.abs(),
                None => return invalid,
            }
        } else {
            0.0
        };
        let stiffness = c.k_0 + c.k_j * j_f + gravity;
        let gain_f = 1.0 + c.k_p / j_f;
        let gain_d = 1.0 + c.k_p / j_d;
        // Written as positive tests so that NaN inputs fail them.
        if !(j_f > 0.0 && j_d > 0.0 && stiffness > 0.0 && gain_f > 0.0 && gain_d > 0.0) {
            return invalid;
        }
        let wn_rad_s = (gain_f * stiffness / j_f).sqrt();
        let numerator = (c.c_0 + c.c_1 * j_d.sqrt() + c.c_2 * j_d) * (1.0 + c.c_tau * j_d);
        let zeta = power(gain_d, self.damping_gain_exponent)
            * power(gain_f, self.frequency_gain_exponent)
            * numerator
            / (2.0 * (stiffness * j_f).sqrt());
        Mode::new(wn_rad_s, zeta)
    }
}

/// `x^e` for `x > 0`, with exact fast paths for the exponents the published forms use.
#[inline]
fn power(x: f64, e: f64) -> f64 {
    if e == 0.0 {
        1.0
    } else if e == 1.0 {
        x
    } else if e == 0.5 {
        x.sqrt()
    } else if e == -0.5 {
        1.0 / x.sqrt()
    } else {
        x.powf(e)
    }
}

/// A dynamic map: one [`ModeMap`] per mode, in cascade order.
#[derive(Debug, Clone, PartialEq)]
pub struct DynamicMap {
    modes: Vec<ModeMap>,
}

impl DynamicMap {
    /// Validates (at least one mode, finite coefficients and exponents).
    pub fn new(modes: Vec<ModeMap>) -> Result<DynamicMap, Error> {
        if modes.is_empty() {
            return Err(Error::InvalidParameter(
                "a dynamic map needs at least one mode".into(),
            ));
        }
        for (m, mode) in modes.iter().enumerate() {
            for (name, value) in mode.coefficients.as_array() {
                if !value.is_finite() {
                    return Err(Error::InvalidParameter(format!(
                        "dynamic map mode {m}: coefficient {name} = {value} must be finite"
                    )));
                }
            }
            if !(mode.damping_gain_exponent.is_finite() && mode.frequency_gain_exponent.is_finite())
            {
                return Err(Error::InvalidParameter(format!(
                    "dynamic map mode {m}: gain exponents must be finite"
                )));
            }
        }
        Ok(DynamicMap { modes })
    }

    /// The UR5e map of the paper: Table 1 for the base mode (eqs. 47–48, joint 0) and
    /// Table 2 for the shoulder mode (eqs. 50–51, joint 1).
    pub fn paper_ur5e() -> DynamicMap {
        let base = MapCoefficients::reduced(10_000.0, 1060.0, 2.54, 1.53, 0.39, 3.81);
        let shoulder = MapCoefficients::reduced(10_000.0, 763.0, 1.73, 0.27, 0.038, 47.2);
        DynamicMap {
            modes: vec![
                ModeMap::base_from_shoulder(base, 0, 1),
                ModeMap::general(shoulder, 1),
            ],
        }
    }

    pub fn n_modes(&self) -> usize {
        self.modes.len()
    }

    pub fn mode_maps(&self) -> &[ModeMap] {
        &self.modes
    }

    /// Number of joint inertias the map reads (largest index plus one).
    pub fn required_joints(&self) -> usize {
        self.modes
            .iter()
            .map(ModeMap::required_joints)
            .max()
            .unwrap_or(0)
    }

    /// True if any mode uses the gravity-torque term.
    pub fn uses_gravity(&self) -> bool {
        self.modes.iter().any(ModeMap::uses_gravity)
    }

    /// Modes from joint inertias `j` (kg m²) and gravity torques `tau_g` (N m; may be empty
    /// when [`Self::uses_gravity`] is false). `out` must hold [`Self::n_modes`] modes.
    /// Allocation-free; [`Status::BAD_LENGTH`] if `j` or `out` is too short.
    pub fn modes_from_inertia(&self, j: &[f64], tau_g: &[f64], out: &mut [Mode]) -> Status {
        if out.len() != self.modes.len() || j.len() < self.required_joints() {
            return Status::BAD_LENGTH;
        }
        if self.uses_gravity() && tau_g.len() < self.required_joints() {
            return Status::BAD_LENGTH;
        }
        for (o, mode) in out.iter_mut().zip(&self.modes) {
            *o = mode.evaluate(j, tau_g);
        }
        Status::OK
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn damped_hz(m: Mode) -> f64 {
        m.wd_rad_s() / (2.0 * core::f64::consts::PI)
    }

    #[test]
    fn paper_table3_q1() {
        // SPEC section 3: Q1 (J0, J1) = (9.73, 9.25) -> 8.018 Hz / 0.2645, 6.909 Hz / 0.3730.
        let map = DynamicMap::paper_ur5e();
        let mut out = [Mode::new(0.0, 0.0); 2];
        assert!(map.modes_from_inertia(&[9.73, 9.25], &[], &mut out).is_ok());
        // 1e-3 relative: the reference values are given to 4 significant digits.
        for (got, want) in [
            (damped_hz(out[0]), 8.018),
            (out[0].zeta, 0.2645),
            (damped_hz(out[1]), 6.909),
            (out[1].zeta, 0.3730),
        ] {
            assert!((got / want - 1.0).abs() < 1e-3, "{got} vs {want}");
        }
    }

    #[test]
    fn invalid_inertia_gives_invalid_mode() {
        let map = DynamicMap::paper_ur5e();
        let mut out = [Mode::new(0.0, 0.0); 2];
        map.modes_from_inertia(&[0.0, -1.0], &[], &mut out);
        assert!(!out[0].is_valid() && !out[1].is_valid());
        map.modes_from_inertia(&[f64::NAN, 1.0], &[], &mut out);
        assert!(!out[0].is_valid() && out[1].is_valid());
    }
}
