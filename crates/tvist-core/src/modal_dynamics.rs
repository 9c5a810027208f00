//! [`ModalDynamics`]: a [`Dynamics`] provider that evaluates the robot's mass matrix (and
//! gravity torques, if the map's laws read them) at the previous shaped output and solves the
//! [`ModalMap`]'s eigenproblem, every cycle.

use crate::dynamics::Dynamics;
use crate::error::{Error, Status};
use crate::map_dynamics::{halton_pose, LastCall, VALIDATION_POSES};
use crate::modal_map::ModalMap;
use crate::robot::Robot;
use crate::shaper::Mode;

/// Per-cycle modes from `robot`'s mass matrix + `map`. Allocation-free after construction.
#[derive(Debug, Clone)]
pub struct ModalDynamics {
    robot: Robot,
    map: ModalMap,
    mass: Vec<f64>,
    tau_g: Vec<f64>,
    slowest: Vec<Mode>,
    last: LastCall,
}

impl ModalDynamics {
    /// Builds the provider and checks the map against the robot.
    ///
    /// Rejected: a map reading joints the robot does not have, or one that gives an invalid
    /// mode (`ζ >= 1`, or a mass block that is not positive definite) at any of
    /// [`VALIDATION_POSES`] configurations sampled like [`crate::MapDynamics`] does.
    ///
    /// A map identified on another robot than `robot` (both names known and different) is
    /// refused with [`Error::RobotMismatch`]; [`Self::new_allowing_other_robot`] skips that
    /// check.
    pub fn new(robot: Robot, map: ModalMap) -> Result<ModalDynamics, Error> {
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

    /// As [`Self::new`] without the robot-name check (research use). Every other check
    /// applies.
    pub fn new_allowing_other_robot(robot: Robot, map: ModalMap) -> Result<ModalDynamics, Error> {
        let n = robot.n_dof();
        if map.required_joints() > n {
            return Err(Error::DimensionMismatch {
                what: "joints read by the modal map (largest joint index + 1)",
                expected: n,
                got: map.required_joints(),
            });
        }
        let mut dynamics = ModalDynamics {
            mass: vec![0.0; n * n],
            tau_g: vec![0.0; n],
            slowest: vec![Mode::new(f64::INFINITY, 0.0); map.n_modes()],
            last: LastCall::new(n, map.n_modes()),
            robot,
            map,
        };
        dynamics.check_workspace()?;
        Ok(dynamics)
    }

    /// Samples the configuration space: rejects invalid modes and records per mode the lowest
    /// `ω_n` and the highest `ζ`; then lowers `ω_n` to an analytic bound.
    fn check_workspace(&mut self) -> Result<(), Error> {
        let n = self.robot.n_dof();
        let mut q = vec![0.0; n];
        let mut modes = vec![Mode::new(0.0, 0.0); self.map.n_modes()];
        for k in 1..=VALIDATION_POSES {
            halton_pose(k, &mut q);
            self.modes(&q, &mut modes);
            for (m, mode) in modes.iter().enumerate() {
                if !mode.is_valid() {
                    return Err(Error::InvalidParameter(format!(
                        "the modal map gives no underdamped mode {m} at q = {q:?}: \
                         wn_rad_s = {}, zeta = {} (zeta must stay below 1)",
                        mode.wn_rad_s, mode.zeta
                    )));
                }
                let s = &mut self.slowest[m];
                *s = Mode::new(s.wn_rad_s.min(mode.wn_rad_s), s.zeta.max(mode.zeta));
            }
        }
        // Rayleigh: ω² = φᵀKφ / φᵀMφ >= k_min / λ_max(M_ff), with k_min >= the smallest
        // zero-load stiffness (the laws only grow with load) and λ_max(M_ff) <= trace(M_ff)
        // <= Σ of the joints' inertia upper bounds. A sound bound for every configuration.
        let j_max = self.robot.joint_inertia_upper_bound();
        let k_min = self
            .map
            .flex_joints()
            .iter()
            .map(|f| f.stiffness_nm_per_rad.at_zero)
            .fold(f64::INFINITY, f64::min);
        let trace_max: f64 = self.map.flex_joints().iter().map(|f| j_max[f.joint]).sum();
        let bound = (k_min / trace_max).sqrt();
        if bound.is_finite() && bound > 0.0 {
            for s in &mut self.slowest {
                s.wn_rad_s = s.wn_rad_s.min(bound);
            }
        }
        Ok(())
    }

    pub fn robot(&self) -> &Robot {
        &self.robot
    }

    pub fn map(&self) -> &ModalMap {
        &self.map
    }

    /// Mass matrix of the latest [`Dynamics::modes`] call, row-major `n × n`, kg m² (only the
    /// leading block of the joints the map reads is evaluated; other entries stay 0).
    pub fn last_mass_matrix(&self) -> &[f64] {
        &self.mass
    }

    /// The per-mode bounds used for delay-line sizing, see [`Dynamics::slowest_mode`].
    pub fn slowest_modes(&self) -> &[Mode] {
        &self.slowest
    }
}

impl Dynamics for ModalDynamics {
    fn n_modes(&self) -> usize {
        self.map.n_modes()
    }

    fn modes(&mut self, q: &[f64], out: &mut [Mode]) -> Status {
        if let Some(status) = self.last.repeat(q, out) {
            return status;
        }
        // One pass, only the block and the torques of the joints the map reads.
        let tau = if self.map.uses_gravity() {
            Some(self.tau_g.as_mut_slice())
        } else {
            None
        };
        let status = self.robot.leading_mass_matrix_and_gravity(
            q,
            self.map.required_joints(),
            &mut self.mass,
            tau,
        );
        if !status.is_ok() {
            out.fill(Mode::new(f64::NAN, f64::NAN));
            return status;
        }
        let n = self.robot.n_dof();
        let status = self
            .map
            .modes_from_mass_matrix(&self.mass, n, &self.tau_g, out);
        self.last.record(q, out, status);
        status
    }

    /// Lowest `ω_n` (sampled minimum, lowered to the Rayleigh bound) with the highest sampled
    /// `ζ`; see [`crate::MapDynamics`] for why the two extremes are paired.
    fn slowest_mode(&self, index: usize) -> Option<Mode> {
        self.slowest.get(index).copied()
    }

    fn n_dof(&self) -> Option<usize> {
        Some(self.robot.n_dof())
    }
}
