//! [`ModalDynamics`]: the [`ModalMap`] as a [`RobotModes`] law: every cycle the robot's
//! mass-matrix block of the flexible joints (and gravity torques, if the map's laws read them)
//! at the previous shaped output, and the map's eigenproblem.

use crate::error::{Error, Status};
use crate::modes::modal::modal_map::{ModalMap, ModeTrack};
use crate::modes::robot_law::{ModeLaw, RobotModes};
use crate::robot::model::Robot;
use crate::shaping::shapers::Mode;

/// Per-cycle modes from `robot`'s mass matrix + a [`ModalMap`]. Allocation-free after
/// construction.
///
/// [`ModalDynamics::new`] also rejects a map that gives an invalid mode (`ζ >= 1`, or a mass
/// block that is not positive definite) at any sampled configuration.
pub type ModalDynamics = RobotModes<ModalMap>;

impl ModalDynamics {
    /// Mass matrix of the latest [`crate::Dynamics::modes`] call, row-major `n × n`, kg m²
    /// (only the leading block of the joints the map reads is evaluated; other entries stay 0).
    /// With link hinges, that of the hinged arm ([`crate::Robot::with_link_hinges`]).
    pub fn last_mass_matrix(&self) -> &[f64] {
        self.last_evaluation()
    }

    /// The same robot and flexible joints shaping their `k` lowest-frequency modes
    /// ([`ModalMap::shaping_lowest`]; `1 <= k <=` the number of flexible joints). A setup call:
    /// it builds and checks a new provider.
    pub fn shaping_lowest(&self, k: usize) -> Result<ModalDynamics, Error> {
        // The robot check passed when `self` was built: the same robot and map robot.
        ModalDynamics::new_allowing_other_robot(self.robot().clone(), self.map().shaping_lowest(k)?)
    }
}

impl ModeLaw for ModalMap {
    const READS_MASS_MATRIX: bool = true;

    fn n_modes(&self) -> usize {
        ModalMap::n_modes(self)
    }

    fn robot(&self) -> Option<&str> {
        ModalMap::robot(self)
    }

    fn required_joints(&self) -> usize {
        ModalMap::required_joints(self)
    }

    fn link_hinges(&self) -> Vec<(usize, f64)> {
        self.hinge_placements()
    }

    fn model_joints(&self) -> usize {
        ModalMap::model_joints(self)
    }

    fn uses_gravity(&self) -> bool {
        ModalMap::uses_gravity(self)
    }

    /// The eigenmode branch each slot follows (module docs of [`crate::modes::modal::modal_map`]).
    type Track = ModeTrack;

    #[inline]
    fn modes_from_robot(
        &self,
        mass: &[f64],
        n_dof: usize,
        tau_g: &[f64],
        track: &mut ModeTrack,
        out: &mut [Mode],
    ) -> Status {
        self.modes_tracked(mass, n_dof, tau_g, track, out)
    }

    fn invalid_mode_message(&self, m: usize, q: &[f64], _mass: &[f64], mode: Mode) -> String {
        format!(
            "the modal map gives no underdamped mode {m} at q = {q:?}: \
             wn_rad_s = {}, zeta = {} (zeta must stay below 1)",
            mode.wn_rad_s, mode.zeta
        )
    }

    /// Rayleigh: ω² = φᵀKφ / φᵀMφ >= k_min / λ_max(M_ff), with k_min >= the smallest
    /// zero-load stiffness (the laws only grow with load; hinge stiffness is constant) and
    /// λ_max(M_ff) <= trace(M_ff) <= Σ of the coordinates' inertia upper bounds (of the
    /// evaluated arm `robot`: hinged if the map has hinges). A sound bound for every
    /// configuration and every eigenmode. A slot follows its eigenmode branch along a motion,
    /// which may be another slot's at the sampled poses: every slot is bounded by the highest
    /// sampled ζ of all of them.
    fn lower_frequency_bound(&self, robot: &Robot, _mass: &[f64], slowest: &mut [Mode]) {
        let zeta_max = slowest.iter().map(|s| s.zeta).fold(0.0, f64::max);
        for s in slowest.iter_mut() {
            s.zeta = zeta_max;
        }
        let j_max = robot.joint_inertia_upper_bound();
        let k_min = self
            .flex_joints()
            .iter()
            .map(|f| f.stiffness_nm_per_rad.at_zero)
            .chain(self.link_hinges().iter().map(|h| h.stiffness_nm_per_rad))
            .fold(f64::INFINITY, f64::min);
        let trace_max: f64 = self.coordinates().iter().map(|&c| j_max[c]).sum();
        let bound = (k_min / trace_max).sqrt();
        if bound.is_finite() && bound > 0.0 {
            for s in slowest {
                s.wn_rad_s = s.wn_rad_s.min(bound);
            }
        }
    }
}
