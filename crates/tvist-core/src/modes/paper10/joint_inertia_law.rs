//! [`MapDynamics`]: the published ten-coefficient [`DynamicMap`] as a [`RobotModes`] law:
//! every cycle the robot's joint inertias (and gravity torques, if the map reads them) at the
//! previous shaped output, turned into modes by the map.

use crate::error::Status;
use crate::modes::paper10::dynamic_map::{DynamicMap, InertiaRange};
pub use crate::modes::robot_law::VALIDATION_POSES;
use crate::modes::robot_law::{ModeLaw, RobotModes};
use crate::robot::model::Robot;
use crate::shaping::shapers::Mode;

/// Per-cycle modes from `robot` inertia + a [`DynamicMap`]. Allocation-free after
/// construction.
///
/// [`MapDynamics::new`] also rejects a map that gives an invalid mode (non-positive stiffness
/// or inertia term, `ζ >= 1`, non-finite) at any sampled configuration. The check evaluates
/// the map exactly as every cycle does, i.e. with the robot's inertias clamped into the map's
/// identified ranges (see [`crate::modes::paper10::dynamic_map`]): a fitted map that would be overdamped only by
/// extrapolation is accepted, one that is invalid at inertias inside its own range that the
/// robot reaches is rejected.
pub type MapDynamics = RobotModes<DynamicMap>;

impl MapDynamics {
    /// Joint inertias of the latest [`crate::Dynamics::modes`] call, kg m² (joints the map
    /// does not read are not evaluated and stay 0).
    pub fn last_inertia(&self) -> &[f64] {
        self.last_evaluation()
    }
}

impl ModeLaw for DynamicMap {
    const READS_MASS_MATRIX: bool = false;

    fn n_modes(&self) -> usize {
        DynamicMap::n_modes(self)
    }

    fn robot(&self) -> Option<&str> {
        DynamicMap::robot(self)
    }

    fn required_joints(&self) -> usize {
        DynamicMap::required_joints(self)
    }

    fn uses_gravity(&self) -> bool {
        DynamicMap::uses_gravity(self)
    }

    /// Modes are a function of the pose alone.
    type Track = ();

    #[inline]
    fn modes_from_robot(
        &self,
        inertia: &[f64],
        _n_dof: usize,
        tau_g: &[f64],
        _track: &mut (),
        out: &mut [Mode],
    ) -> Status {
        self.modes_from_inertia(inertia, tau_g, out)
    }

    fn invalid_mode_message(&self, m: usize, q: &[f64], inertia: &[f64], mode: Mode) -> String {
        let mode_map = &self.mode_maps()[m];
        format!(
            "the dynamic map gives no underdamped mode {m} at q = {q:?} \
             (J = {inertia:?}; inertia ranges J_f {}, J_d {}): wn_rad_s = {}, \
             zeta = {} (needs positive stiffness and inertia terms and zeta < 1)",
            range_text(mode_map.frequency_range),
            range_text(mode_map.damping_range),
            mode.wn_rad_s,
            mode.zeta
        )
    }

    fn lower_frequency_bound(&self, robot: &Robot, inertia: &[f64], slowest: &mut [Mode]) {
        let j_max = robot.joint_inertia_upper_bound();
        let zero_tau = vec![0.0; inertia.len()];
        for (mode_map, s) in self.mode_maps().iter().zip(slowest) {
            let c = &mode_map.coefficients;
            // ω_n² = (1 + k_p/J)(k_0 + k_g|τ|)/J + (1 + k_p/J) k_J is non-increasing in J when
            // k_p, k_0 >= 0, and k_g|τ| >= 0 is least at τ = 0 (k_g >= 0 in every map:
            // `ModeMap::check_physical`); then the value at the inertia bound is a sound lower
            // bound of ω_n over every configuration. With a range, J is clamped (a
            // non-decreasing function of J) before the map sees it, so the clamped value at
            // the bound still bounds every clamped evaluation.
            if !(c.k_p >= 0.0 && c.k_0 >= 0.0) {
                continue;
            }
            let mut j_bound = inertia.to_vec();
            j_bound[mode_map.frequency_joint] = j_max[mode_map.frequency_joint];
            j_bound[mode_map.damping_joint] = j_max[mode_map.damping_joint];
            let at_bound = mode_map.evaluate(&j_bound, &zero_tau);
            if at_bound.wn_rad_s.is_finite() && at_bound.wn_rad_s > 0.0 {
                s.wn_rad_s = s.wn_rad_s.min(at_bound.wn_rad_s);
            }
        }
    }
}

/// A map range for messages: `[min, max] kg m²` or `unbounded`.
fn range_text(range: Option<InertiaRange>) -> String {
    range.map_or_else(|| "unbounded".to_string(), |r| r.to_string())
}

#[cfg(all(test, feature = "json"))]
mod tests {
    use super::*;
    use crate::modes::dynamics::Dynamics;
    use crate::modes::paper10::dynamic_map::{MapCoefficients, ModeMap};
    use crate::robot::rigid_body::RigidBody;

    fn ur5e_5kg() -> Robot {
        let (joints, links) = crate::files::robot_data::robot_chain(
            crate::files::robot_data::UR_E_SERIES_JSON,
            "ur5e",
        )
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
