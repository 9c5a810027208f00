//! [`MapDynamics`]: a [`Dynamics`] provider that evaluates the robot's joint inertias at the
//! previous shaped output and turns them into modes with a [`DynamicMap`], every cycle.

use crate::dynamics::Dynamics;
use crate::dynmap::{DynamicMap, InertiaRange};
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
    last: LastCall,
}

impl MapDynamics {
    /// Builds the provider and checks the map against the robot.
    ///
    /// Rejected: a map reading more joints than the robot has, or a map that gives an invalid
    /// mode (non-positive stiffness or inertia term, `ζ >= 1`, non-finite) at any of the
    /// [`VALIDATION_POSES`] sampled configurations. The check evaluates the map exactly as
    /// every cycle does, i.e. with the robot's inertias clamped into the map's identified
    /// ranges (see [`crate::dynmap`]): a fitted map that would be overdamped only by
    /// extrapolation is accepted, one that is invalid at inertias inside its own range that the
    /// robot reaches is rejected.
    ///
    /// A map identified on another robot than `robot` (both names known and different) is
    /// refused with [`Error::RobotMismatch`]; [`Self::new_allowing_other_robot`] skips that
    /// check.
    pub fn new(robot: Robot, map: DynamicMap) -> Result<MapDynamics, Error> {
        if let (Some(map_robot), Some(name)) = (map.robot(), robot.name()) {
            if map_robot != name {
                return Err(Error::RobotMismatch {
                    map_robot: map_robot.to_string(),
                    robot: name.to_string(),
                });
            }
        }
        Self::new_allowing_other_robot(robot, map)
    }

    /// As [`Self::new`] without the robot-name check: for research, e.g. trying one robot's
    /// map on another. Every other check applies.
    pub fn new_allowing_other_robot(robot: Robot, map: DynamicMap) -> Result<MapDynamics, Error> {
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
            last: LastCall::new(n, map.n_modes()),
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
                    let mode_map = &self.map.mode_maps()[m];
                    return Err(Error::InvalidParameter(format!(
                        "the dynamic map gives no underdamped mode {m} at q = {q:?} \
                         (J = {:?}; inertia ranges J_f {}, J_d {}): wn_rad_s = {}, \
                         zeta = {} (needs positive stiffness and inertia terms and zeta < 1)",
                        self.inertia,
                        range_text(mode_map.frequency_range),
                        range_text(mode_map.damping_range),
                        mode.wn_rad_s,
                        mode.zeta
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
            // the inertia bound is a sound lower bound of ω_n over every configuration. With a
            // range, J is clamped (a non-decreasing function of J) before the map sees it, so
            // the clamped value at the bound still bounds every clamped evaluation.
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

    /// Joint inertias of the latest [`Dynamics::modes`] call, kg m² (joints the map does not
    /// read are not evaluated and stay 0).
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
        if let Some(status) = self.last.repeat(q, out) {
            return status;
        }
        let tau = if self.map.uses_gravity() {
            Some(self.tau_g.as_mut_slice())
        } else {
            None
        };
        // Only the joints the map reads (the base and shoulder for the UR5e map).
        let status = self.robot.leading_joint_inertia_and_gravity(
            q,
            self.map.required_joints(),
            &mut self.inertia,
            tau,
        );
        if !status.is_ok() {
            out.fill(Mode::new(f64::NAN, f64::NAN));
            return status;
        }
        let status = self.map.modes_from_inertia(&self.inertia, &self.tau_g, out);
        self.last.record(q, out, status);
        status
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

/// The pose and result of a provider's latest evaluation: modes are a function of the pose
/// alone, so a pose bit-identical to the previous one (an arm at rest: the shaped output
/// settles to a fixed value) returns the stored modes without evaluating anything.
#[derive(Debug, Clone)]
pub(crate) struct LastCall {
    q: Vec<f64>,
    modes: Vec<Mode>,
    status: Status,
    /// False until a result is recorded.
    valid: bool,
}

impl LastCall {
    pub(crate) fn new(n_dof: usize, n_modes: usize) -> LastCall {
        LastCall {
            q: vec![0.0; n_dof],
            modes: vec![Mode::new(f64::NAN, f64::NAN); n_modes],
            status: Status::OK,
            valid: false,
        }
    }

    /// The stored status (and the stored modes in `out`) if `q` is the recorded pose bit for
    /// bit and `out` has the recorded length.
    #[inline]
    pub(crate) fn repeat(&self, q: &[f64], out: &mut [Mode]) -> Option<Status> {
        let same = self.valid
            && q.len() == self.q.len()
            && out.len() == self.modes.len()
            && q.iter()
                .zip(&self.q)
                .all(|(a, b)| a.to_bits() == b.to_bits());
        if !same {
            return None;
        }
        out.copy_from_slice(&self.modes);
        Some(self.status)
    }

    /// Records a full evaluation (lengths as at construction; others are not recorded).
    #[inline]
    pub(crate) fn record(&mut self, q: &[f64], out: &[Mode], status: Status) {
        self.valid = q.len() == self.q.len() && out.len() == self.modes.len();
        if self.valid {
            self.q.copy_from_slice(q);
            self.modes.copy_from_slice(out);
            self.status = status;
        }
    }
}

/// A map range for messages: `[min, max] kg m²` or `unbounded`.
fn range_text(range: Option<InertiaRange>) -> String {
    range.map_or_else(|| "unbounded".to_string(), |r| r.to_string())
}

/// Halton configuration `k` (`1..=VALIDATION_POSES`), the same poses [`MapDynamics`] checks:
/// joint `i` at `π (2 r(k, p_i) − 1)` with `p_i` the `i`-th prime (setup time: allocates).
pub(crate) fn halton_pose(k: usize, q: &mut [f64]) {
    let primes = first_primes(q.len());
    for (qi, p) in q.iter_mut().zip(primes) {
        *qi = core::f64::consts::PI * (2.0 * radical_inverse(k, p) - 1.0);
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

#[cfg(all(test, feature = "json"))]
mod tests {
    use super::*;
    use crate::dynmap::{MapCoefficients, ModeMap};
    use crate::robot::RigidBody;

    fn ur5e_5kg() -> Robot {
        let (joints, links) =
            crate::robot_data::robot_chain(crate::robot_data::UR_E_SERIES_JSON, "ur5e")
                .expect("robot data");
        Robot::new(joints, links, RigidBody::point(5.0, [0.0, 0.0, 0.05])).expect("robot")
    }

    /// A base mode (J = J_0) that is overdamped below J_0 ~ 0.35 kg m² (the (1 + k_p/J) factor
    /// grows at small J): ζ = 2.1 at 0.2, 0.75 at 0.6. The UR5e with 5 kg reaches
    /// J_0 ~ 0.18 kg m² with the arm pointing up.
    fn overdamped_at_small_j(range: Option<(f64, f64)>) -> DynamicMap {
        let c = MapCoefficients::reduced(10_000.0, 763.0, 1.73, 60.0, 0.038, 0.0);
        let r = range.map(|(lo, hi)| InertiaRange::new(lo, hi).expect("valid range"));
        DynamicMap::new(vec![ModeMap::general(c, 0).with_ranges(r, r)]).expect("finite")
    }

    #[test]
    fn a_map_overdamped_only_outside_its_range_is_accepted_and_never_invalid() {
        let err = MapDynamics::new(ur5e_5kg(), overdamped_at_small_j(None))
            .expect_err("overdamped by extrapolation");
        assert!(err.to_string().contains("no underdamped mode 0"), "{err}");

        let mut provider = MapDynamics::new(ur5e_5kg(), overdamped_at_small_j(Some((0.6, 10.0))))
            .expect("valid inside its range");
        let mut rng = 0x9E37_79B9_7F4A_7C15_u64;
        let mut modes = [Mode::new(0.0, 0.0)];
        let mut clamped = 0;
        for _ in 0..20_000 {
            let q: Vec<f64> = (0..6)
                .map(|_| {
                    rng ^= rng << 13;
                    rng ^= rng >> 7;
                    rng ^= rng << 17;
                    core::f64::consts::PI * (2.0 * (rng >> 11) as f64 / (1u64 << 53) as f64 - 1.0)
                })
                .collect();
            assert!(provider.modes(&q, &mut modes).is_ok());
            assert!(modes[0].is_valid(), "q = {q:?}: {:?}", modes[0]);
            clamped += usize::from(provider.last_inertia()[0] < 0.6);
        }
        // The test means something only if the clamp was exercised.
        assert!(clamped > 100, "only {clamped} poses below the range");
        let (wn_lo, zeta_hi) = (
            provider.slowest_modes()[0].wn_rad_s,
            provider.slowest_modes()[0].zeta,
        );
        // The saturated map's extremes: ζ is largest at the range's lower bound, which the
        // soft clamp reaches exactly at and below 0.6 (1 − ε) = 0.57 kg m².
        let at_min = provider.map().mode_maps()[0].evaluate(&[0.5], &[]);
        assert!(
            (zeta_hi / at_min.zeta - 1.0).abs() < 1e-12,
            "{zeta_hi} vs {}",
            at_min.zeta
        );
        assert!(wn_lo > 0.0 && wn_lo.is_finite());
    }

    #[test]
    fn a_map_invalid_inside_its_own_range_is_rejected() {
        let err = MapDynamics::new(ur5e_5kg(), overdamped_at_small_j(Some((0.2, 10.0))))
            .expect_err("overdamped inside its range");
        assert!(err.to_string().contains("no underdamped mode 0"), "{err}");
        assert!(err.to_string().contains("J_f [0.2, 10] kg m²"), "{err}");
    }
}
