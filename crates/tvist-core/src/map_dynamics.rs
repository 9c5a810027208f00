//! [`MapDynamics`]: a [`Dynamics`] provider that evaluates the robot's joint inertias at the
//! previous shaped output and turns them into modes with a [`DynamicMap`], every cycle.

use crate::dynamics::Dynamics;
use crate::dynmap::DynamicMap;
use crate::error::{Error, Status};
use crate::robot::Robot;
use crate::shaper::Mode;

/// Number of configurations checked at construction (and used for the delay bound).
///
/// The poses are a Halton sequence over `[−π, π]` per joint. Inertias and gravity torques are
/// 2π-periodic in every joint angle, so this box is the whole configuration space of any
/// revolute chain, whatever its joint limits. A Halton sequence is low-discrepancy: every
/// joint angle takes 4096 distinct values and pairs of joints are covered at a spacing of
/// roughly 2π/64. The check costs a few milliseconds at construction.
pub const VALIDATION_POSES: usize = 4096;

/// Per-cycle modes from `robot` inertia + `map`. Allocation-free after construction.
#[derive(Debug, Clone)]
pub struct MapDynamics {
    robot: Robot,
    map: DynamicMap,
    inertia: Vec<f64>,
    tau_g: Vec<f64>,
    slowest: Vec<Mode>,
}

impl MapDynamics {
    /// Builds the provider and checks the map against the robot.
    ///
    /// Rejected: a map reading more joints than the robot has, or a map that gives an invalid
    /// mode (non-positive stiffness or inertia term, `ζ >= 1`, non-finite) at any of the
    /// [`VALIDATION_POSES`] sampled configurations.
    pub fn new(robot: Robot, map: DynamicMap) -> Result<MapDynamics, Error> {
        let n = robot.n_dof();
        if map.required_joints() > n {
            return Err(Error::DimensionMismatch {
                what: "joints read by the dynamic map (largest joint index + 1)",
                expected: n,
                got: map.required_joints(),
            });
        }
        let mut dynamics = MapDynamics {
            inertia: vec![0.0; n],
            tau_g: vec![0.0; n],
            slowest: vec![Mode::new(f64::INFINITY, 0.0); map.n_modes()],
            robot,
            map,
        };
        dynamics.check_workspace()?;
        Ok(dynamics)
    }

    /// Samples the configuration space: rejects invalid modes and records, per mode, the
    /// lowest `ω_n` and the highest `ζ` seen; then lowers `ω_n` to the analytic bound.
    fn check_workspace(&mut self) -> Result<(), Error> {
        let n = self.robot.n_dof();
        let primes = first_primes(n);
        let mut q = vec![0.0; n];
        let mut modes = vec![Mode::new(0.0, 0.0); self.map.n_modes()];
        let mut lowest_wn = vec![f64::INFINITY; modes.len()];
        let mut highest_zeta = vec![0.0f64; modes.len()];
        for k in 1..=VALIDATION_POSES {
            for (qi, &p) in q.iter_mut().zip(&primes) {
                *qi = core::f64::consts::PI * (2.0 * radical_inverse(k, p) - 1.0);
            }
            self.modes(&q, &mut modes);
            for (m, mode) in modes.iter().enumerate() {
                if !mode.is_valid() {
                    return Err(Error::InvalidParameter(format!(
                        "the dynamic map gives no underdamped mode {m} at q = {q:?} \
                         (J = {:?}): wn_rad_s = {}, zeta = {} \
                         (needs positive stiffness and inertia terms and zeta < 1)",
                        self.inertia, mode.wn_rad_s, mode.zeta
                    )));
                }
                lowest_wn[m] = lowest_wn[m].min(mode.wn_rad_s);
                highest_zeta[m] = highest_zeta[m].max(mode.zeta);
            }
        }
        let j_max = self.robot.joint_inertia_upper_bound();
        let tau_max = self.robot.gravity_torque_upper_bound();
        for (m, mode_map) in self.map.mode_maps().iter().enumerate() {
            let c = &mode_map.coefficients;
            // ω_n² = (1 + k_p/J)(k_0 + k_g|τ|)/J + (1 + k_p/J) k_J is non-increasing in J when
            // k_p, k_0 >= 0 and k_g|τ| >= 0 is least at τ = 0 (k_g >= 0); then the value at
            // the inertia bound is a sound lower bound of ω_n over every configuration.
            if c.k_p >= 0.0 && c.k_0 >= 0.0 && c.k_g >= 0.0 {
                let mut j_bound = self.inertia.clone();
                j_bound[mode_map.frequency_joint] = j_max[mode_map.frequency_joint];
                j_bound[mode_map.damping_joint] = j_max[mode_map.damping_joint];
                let zero_tau = vec![0.0; n];
                let at_bound = mode_map.evaluate(&j_bound, &zero_tau);
                if at_bound.wn_rad_s.is_finite() && at_bound.wn_rad_s > 0.0 {
                    lowest_wn[m] = lowest_wn[m].min(at_bound.wn_rad_s);
                }
            } else if c.k_g < 0.0 {
                // Stiffness is lowest at the largest gravity torque: evaluate there too.
                let mut j_bound = self.inertia.clone();
                j_bound[mode_map.frequency_joint] = j_max[mode_map.frequency_joint];
                let at_bound = mode_map.evaluate(&j_bound, &tau_max);
                if at_bound.wn_rad_s.is_finite() && at_bound.wn_rad_s > 0.0 {
                    lowest_wn[m] = lowest_wn[m].min(at_bound.wn_rad_s);
                }
            }
            self.slowest[m] = Mode::new(lowest_wn[m], highest_zeta[m]);
        }
        Ok(())
    }

    pub fn robot(&self) -> &Robot {
        &self.robot
    }

    pub fn map(&self) -> &DynamicMap {
        &self.map
    }

    /// Joint inertias of the latest [`Dynamics::modes`] call, kg m².
    pub fn last_inertia(&self) -> &[f64] {
        &self.inertia
    }

    /// The per-mode bounds used for delay-line sizing, see [`Dynamics::slowest_mode`].
    pub fn slowest_modes(&self) -> &[Mode] {
        &self.slowest
    }
}

impl Dynamics for MapDynamics {
    fn n_modes(&self) -> usize {
        self.map.n_modes()
    }

    fn modes(&mut self, q: &[f64], out: &mut [Mode]) -> Status {
        let tau = if self.map.uses_gravity() {
            Some(self.tau_g.as_mut_slice())
        } else {
            None
        };
        let status = self
            .robot
            .joint_inertia_and_gravity(q, &mut self.inertia, tau);
        if !status.is_ok() {
            out.fill(Mode::new(f64::NAN, f64::NAN));
            return status;
        }
        self.map.modes_from_inertia(&self.inertia, &self.tau_g, out)
    }

    /// Lowest `ω_n` (sampled minimum, lowered to the analytic bound at the largest possible
    /// inertia when `ω_n` provably decreases with `J`) paired with the highest sampled `ζ`.
    /// Pairing the two extremes gives the longest shaper a sampled pose can need; the
    /// shaper's safety factor covers `ζ` between samples, and any excess is clamped and
    /// reported as [`Status::DELAY_CLAMPED`].
    fn slowest_mode(&self, index: usize) -> Option<Mode> {
        self.slowest.get(index).copied()
    }

    fn n_dof(&self) -> Option<usize> {
        Some(self.robot.n_dof())
    }
}

/// Van der Corput radical inverse of `k` in base `base`, in `[0, 1)`.
fn radical_inverse(mut k: usize, base: usize) -> f64 {
    let inv = 1.0 / base as f64;
    let (mut value, mut scale) = (0.0, inv);
    while k > 0 {
        value += (k % base) as f64 * scale;
        k /= base;
        scale *= inv;
    }
    value
}

fn first_primes(count: usize) -> Vec<usize> {
    let mut primes: Vec<usize> = Vec::with_capacity(count);
    let mut candidate = 2;
    while primes.len() < count {
        if primes.iter().all(|p| candidate % p != 0) {
            primes.push(candidate);
        }
        candidate += 1;
    }
    primes
}
