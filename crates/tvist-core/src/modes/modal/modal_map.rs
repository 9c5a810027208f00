//! The modal map: pose-dependent modes from the link-side mass matrix and identified joint
//! flexibility, for any serial arm.
//!
//! **Model.** Each flexible joint `j` (at least base, shoulder and elbow; any subset of at most
//! [`MAX_FLEX_JOINTS`] joints) is a torsional spring `k_j` and damper `c_j` between its motor
//! and its link. The motors are held rigidly by the position servo (the servo bandwidth is far
//! above the structural modes), and the joints not declared flexible are rigid, so the
//! deflections `δ` of the flexible joints obey
//!
//! ```text
//! M_ff(q) δ'' + C δ' + K δ = 0,   K = diag(k_j),  C = diag(c_j)
//! ```
//!
//! with `M_ff` the block of the link-side joint-space inertia matrix `M(q)` (CRBA, payload
//! included) on the flexible joints. Gravity stiffness `∂τ_g/∂q` (below 1 % of the gear
//! stiffness on UR arms) and the flexibility of joints left out are neglected.
//!
//! **Modes: the exact damped eigenproblem.** The modes are the roots `λ` of
//! `det(λ² M_ff + λ C + K) = 0` with `ω_n = |λ|` and `ζ = −Re λ / |λ|` (the natural frequency
//! and damping ratio of each damped mode, as a free-decay fit measures them). Two steps:
//!
//! 1. The undamped problem `K φ = ω² M_ff φ`: with `K` diagonal and positive it becomes the
//!    standard symmetric problem `B v = μ v`, `B = K^{-1/2} M_ff K^{-1/2}`, `μ = 1/ω²`,
//!    `φ = K^{-1/2} v`, brought to nearly diagonal form by a few Jacobi sweeps
//!    ([`crate::math::sym_eigen::sym_diagonalize`], [`JACOBI_TOLERANCE`]).
//! 2. In those coordinates `(λ² VᵀBV + λ Vᵀ(C/K)V + I) z = 0`, solved exactly by Aberth's
//!    iteration ([`crate::modes::modal::damped_roots`]) from the modal-damping estimates
//!    `ζ_i = (ω_i/2) Σ_j c_j v_ij² / k_j` (the damping projected on the undamped modes, its
//!    off-diagonal part neglected).
//!
//! Joint dampers are not proportional to `M` and `K`, so the projection alone is only
//! approximate: it neglects the damping coupling of the modes, which is small against their
//! frequency separation for most poses but not where two modes with very different damping
//! come close (the UR5e's base and shoulder at folded poses: 20.2 and 19.2 Hz with ζ 0.05 and
//! 0.22, where the projection puts the base mode several per cent off). `y = V z` is the mode in `K^{1/2}`-scaled joint coordinates:
//! `|y_j|² / |y|²` is the share of the mode's gear strain energy stored in joint `j`.
//!
//! **Overdamped modes.** A mode at or beyond critical damping has no oscillating root; the
//! exact solve then fails and the modes fall back to the projection (undamped frequencies,
//! projected damping): the overdamped mode comes out with `ζ ≥ 1`, which the shaper treats
//! as invalid (it holds its last valid modes and reports it), while the others stay usable.
//!
//! **Load dependence.** Gears stiffen and damp more under load. Both laws are
//! `v(L) = v_0 + v_1 |L|_s + v_2 L²` with `L` a static gravity torque (N m): for the
//! stiffness of joint `j` its own `τ_g,j`; for its damping the torque of `damping_load_joint`
//! (for a base joint, which carries no gravity torque, the shoulder's: the tilting moment on
//! its bearing). `|x|_s` is [`crate::modes::paper10::dynamic_map::smooth_abs_torque_nm`]. The coefficients are
//! non-negative and `k_0 > 0`, so stiffness is positive everywhere.
//!
//! **Which modes are shaped.** A map names its shaped modes in one of two ways
//! ([`ShapedModes`]); the rule picks one eigenmode per slot (cascade filter) at a pose:
//!
//! - **By joint** (`mode_joints`, e.g. `[0, 1]` for base then shoulder): slot `m` takes the
//!   (damped) eigenmode that stores the largest share of its strain energy in joint
//!   `mode_joints[m]`, among the eigenmodes not already taken by an earlier slot, so two slots
//!   never shape the same eigenmode (where one eigenmode strains both base and shoulder most,
//!   the shoulder slot takes the next one in the shoulder).
//! - **By frequency** (`shaped_modes: K`): the `K` lowest-frequency eigenmodes as a set, in
//!   slots ordered by the flexible joint each strains most, each slot taking the member of the
//!   set that strains its joint most.
//!
//! **Slots follow their branch.** Applied afresh at every pose, either rule makes a slot jump
//! between two far-apart eigenmodes where the dominance or the order changes: two modes that
//! both strain the shoulder swap which strains it most (measured on a simulated UR5e variant:
//! the shoulder slot from 14.9 to 30.9 Hz in one 2 ms cycle), or the `K`-th and the next
//! cross. A jump in a filter's delay is a step in the shaped reference. So the streaming
//! evaluation ([`ModalMap::modes_tracked`], used by the provider every cycle) remembers each
//! slot's eigenmode of the previous cycle (its mode shape `y` and frequency, [`ModeTrack`]):
//!
//! - for `shaped_modes`, the rule's set is given to the slots whose eigenmodes its members
//!   continue (the same shape at a nearby frequency, modal assurance criterion): where two
//!   modes of the set cross, each slot keeps its mode, frequency and damping continuous
//!   (slots in frequency order would swap there, and where the two differ in damping, the
//!   UR5e's base and shoulder near Q1 with ζ 0.28 and 0.14, a slot's ζ would jump: measured
//!   on the twin, Q3→Q1 left 88.9 % where slots that keep their mode leave 98.9 %);
//! - where a slot's eigenmode from the rule is another than the one it had (a joint's
//!   dominant eigenmode becomes another far-apart one, or the `K`-th and the next cross, so
//!   the set changes), the slot *hands over*: it starts from its previous mode and moves to
//!   the new eigenmode's by [`HANDOVER_STEP`] per cycle in `ln ω` and `ζ`, so its filter's
//!   delay and amplitudes change gradually, not in a step. The set the rule chooses is
//!   always the one shaped (modes that cross into the `K` lowest during a long move are
//!   shaped when it stops), only reached gradually;
//! - where two coupled modes veer, the rule's pick swaps branch at the swap of dominance, two
//!   frequencies a few per cent apart: a short handover. No blending of eigenmodes is needed
//!   (the per-pose rule once blended veering pairs to hide that jump); every shaped mode is an
//!   eigenmode, as a free decay measures it, except during a handover.
//!
//! After a start, a reset, a replacement of the map or a change of `K`, and whenever the
//! shaper has come to rest ([`crate::TvShaper`]: every delay line holds one value, so no mode
//! changes the output), the track is empty and the slots take the rule's picks as they are.
//!
//! The per-pose rule ([`ModalMap::modes_from_mass_matrix`]) remains for checks at
//! independent poses (a map against measured modes). Whatever the provider, the shaper also
//! limits how fast any slot's mode may change ([`crate::tv_shaper::MAX_LN_WN_RATE_PER_S`]) and
//! reports it when that binds, so a jump that reaches it anyway is spread out and flagged.
//!
//! **Bending links** ([`LinkHinge`]). A link that bends is modelled as a lumped hinge pair at a
//! point along it, about the two axes perpendicular to the link ([`crate::robot::link_hinges`]: the
//! link's inertia split between its two halves so that at zero hinge angle the arm is the
//! rigid one), with a rotational spring `k_h` and damper `c_h` per axis (the same about both
//! axes, as for a round tube). The flexible coordinates are then the flexible joints followed
//! by the hinge pairs (in link order), at most [`MAX_FLEX_JOINTS`] in all; `M_ff` is the
//! mass-matrix block of the hinged arm ([`crate::Robot::with_link_hinges`]) at the current
//! pose with straight hinges, and `K`, `C` carry `k_h`, `c_h` on the hinge coordinates. A
//! mode's strain shares then include the hinges'; the shaped modes stay named by joints (a
//! hinge-dominated mode is shaped by a frequency-ranked map). Without hinges the mass matrix is
//! the robot's own.
//!
//! Evaluation ([`ModalMap::modes_from_mass_matrix`]) uses fixed-size arrays only: no
//! allocation, no panic.

use crate::error::{Error, Status};
use crate::math::sym_eigen::{sym_diagonalize, MAX_DIM};
use crate::modes::modal::damped_roots::damped_modes;
use crate::modes::paper10::dynamic_map::smooth_abs_torque_nm;
use crate::robot::link_hinges::hinged_index;
use crate::shaping::shapers::Mode;
use num_complex::Complex64;

/// Largest number of flexible coordinates: flexible joints plus two per link hinge.
pub const MAX_FLEX_JOINTS: usize = MAX_DIM;
// A modal map shapes at most one mode per flexible joint: within the shared mode limit.
const _: () = assert!(MAX_FLEX_JOINTS <= crate::limits::MAX_MODES);

/// A quantity that grows with a joint's static load: `v_0 + v_1 |L|_s + v_2 L²`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoadLaw {
    /// Value at zero load (N m/rad for a stiffness, N m s/rad for a damping).
    pub at_zero: f64,
    /// Growth per N m of load.
    pub per_nm: f64,
    /// Growth per (N m)² of load.
    pub per_nm2: f64,
}

impl LoadLaw {
    /// A law that does not depend on the load.
    pub const fn constant(value: f64) -> LoadLaw {
        LoadLaw {
            at_zero: value,
            per_nm: 0.0,
            per_nm2: 0.0,
        }
    }

    /// The value at gravity torque `load_nm` (N m).
    #[inline]
    pub fn value(&self, load_nm: f64) -> f64 {
        // The smooth |L| only where it is read (it costs a square root).
        let linear = if self.per_nm == 0.0 {
            0.0
        } else {
            self.per_nm * smooth_abs_torque_nm(load_nm)
        };
        self.at_zero + linear + self.per_nm2 * load_nm * load_nm
    }

    fn uses_load(&self) -> bool {
        self.per_nm != 0.0 || self.per_nm2 != 0.0
    }

    fn validate(&self, what: &str, positive_at_zero: bool) -> Result<(), Error> {
        let finite =
            self.at_zero.is_finite() && self.per_nm.is_finite() && self.per_nm2.is_finite();
        let at_zero_ok = if positive_at_zero {
            self.at_zero > 0.0
        } else {
            self.at_zero >= 0.0
        };
        if !finite || !at_zero_ok || self.per_nm < 0.0 || self.per_nm2 < 0.0 {
            return Err(Error::InvalidParameter(format!(
                "{what}: needs finite coefficients, at_zero {} 0 and per_nm, per_nm2 >= 0, got \
                 {self:?}",
                if positive_at_zero { ">" } else { ">=" }
            )));
        }
        Ok(())
    }
}

/// One flexible joint: gear spring and damper between motor and link.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlexJoint {
    /// Joint index (0 = base).
    pub joint: usize,
    /// Spring stiffness, N m/rad, loaded by the joint's own gravity torque.
    pub stiffness_nm_per_rad: LoadLaw,
    /// Damping, N m s/rad, loaded by the gravity torque of `damping_load_joint`.
    pub damping_nms_per_rad: LoadLaw,
    /// The joint whose gravity torque loads the damper.
    pub damping_load_joint: usize,
}

/// A bending link: a hinge pair about the two axes perpendicular to link `link`, at
/// `at_fraction` of its joint-to-joint length from its joint (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkHinge {
    /// Link index (link `i` turns with joint `i`).
    pub link: usize,
    /// Position of the hinge along the link, a fraction in `(0, 1)` (0.5: the middle).
    pub at_fraction: f64,
    /// Bending stiffness about each of the two axes, N m/rad.
    pub stiffness_nm_per_rad: f64,
    /// Bending damping about each of the two axes, N m s/rad.
    pub damping_nms_per_rad: f64,
}

/// All modes of the flexible joints at one pose, sorted by the flexible joints' order of
/// the eigen-solver (not by frequency). Plain data on the stack.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModalSolution {
    /// Number of modes (= number of flexible joints).
    pub n: usize,
    /// Natural frequencies `|λ|` of the damped modes, rad/s.
    pub wn_rad_s: [f64; MAX_FLEX_JOINTS],
    /// Damping ratios `−Re λ / |λ|`.
    pub zeta: [f64; MAX_FLEX_JOINTS],
    /// `strain_share[i][f]`: share of mode `i`'s strain energy in flexible coordinate `f`
    /// (the `f`-th entry of [`ModalMap::flex_joints`], then two per entry of
    /// [`ModalMap::link_hinges`]); each row sums to 1.
    pub strain_share: [[f64; MAX_FLEX_JOINTS]; MAX_FLEX_JOINTS],
    /// `shape[i][f]`: mode `i` as the unit vector `y` in `K^{1/2}`-scaled coordinates of the
    /// flexible joints (module docs; complex for a damped mode, its phase arbitrary):
    /// `strain_share[i][f] = |shape[i][f]|²`.
    pub shape: [[Complex64; MAX_FLEX_JOINTS]; MAX_FLEX_JOINTS],
}

/// Which eigenmodes a modal map shapes, in cascade order (module docs).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ShapedModes {
    /// Mode `m` is the eigenmode dominated by joint `joints[m]` (a joint index, 0 = base).
    ByJoint(Vec<usize>),
    /// The `k` lowest-frequency eigenmodes, in slots by the joint each strains most.
    Lowest(usize),
}

/// Flexible joints plus the modes to shape (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct ModalMap {
    flex: Vec<FlexJoint>,
    /// Bending links, in increasing link order.
    hinges: Vec<LinkHinge>,
    /// Per flexible coordinate (flex joints, then two per hinge) its index in the hinged
    /// arm's joints; per flex joint the hinged index of its damping load joint.
    coordinate: Vec<usize>,
    load_coordinate: Vec<usize>,
    shaped: ShapedModes,
    /// For [`ShapedModes::ByJoint`], per shaped mode the index into `flex` of the joint that
    /// must dominate it; empty for [`ShapedModes::Lowest`].
    mode_flex_index: Vec<usize>,
    /// The robot the map was identified on, if known.
    robot: Option<String>,
    /// Number of joints the map reads (largest joint or load-joint index + 1); set at
    /// construction, read every cycle.
    required_joints: usize,
    /// Whether any law reads a gravity torque; set at construction, read every cycle.
    uses_gravity: bool,
}

impl ModalMap {
    /// Validates and builds the map shaping the modes named by `mode_joints`
    /// ([`ShapedModes::ByJoint`]): the joints naming the shaped modes in cascade order, each
    /// one of the flexible joints, distinct, at least one. See [`Self::shaping`].
    pub fn new(flex: Vec<FlexJoint>, mode_joints: &[usize]) -> Result<ModalMap, Error> {
        ModalMap::shaping(flex, ShapedModes::ByJoint(mode_joints.to_vec()))
    }

    /// Validates and builds the map.
    ///
    /// `flex`: 1 to [`MAX_FLEX_JOINTS`] joints, distinct. `shaped`: by joint (see
    /// [`Self::new`]) or the `k` lowest-frequency modes, `1 <= k <= flex.len()`.
    /// The robot is unknown until [`Self::for_robot`].
    pub fn shaping(flex: Vec<FlexJoint>, shaped: ShapedModes) -> Result<ModalMap, Error> {
        ModalMap::shaping_hinged(flex, Vec::new(), shaped)
    }

    /// As [`Self::shaping`], with bending links ([`Self::with_link_hinges`]); `k` lowest modes
    /// up to the number of flexible coordinates (joints plus two per hinge).
    pub fn shaping_hinged(
        flex: Vec<FlexJoint>,
        hinges: Vec<LinkHinge>,
        shaped: ShapedModes,
    ) -> Result<ModalMap, Error> {
        let n_coordinates = flex.len() + 2 * hinges.len();
        if flex.is_empty() || flex.len() > MAX_FLEX_JOINTS {
            return Err(Error::InvalidParameter(format!(
                "a modal map needs 1 to {MAX_FLEX_JOINTS} flexible joints, got {}",
                flex.len()
            )));
        }
        for (i, f) in flex.iter().enumerate() {
            if flex[..i].iter().any(|g| g.joint == f.joint) {
                return Err(Error::InvalidParameter(format!(
                    "flexible joint {} is listed twice",
                    f.joint
                )));
            }
            f.stiffness_nm_per_rad
                .validate(&format!("stiffness of joint {}", f.joint), true)?;
            f.damping_nms_per_rad
                .validate(&format!("damping of joint {}", f.joint), false)?;
        }
        let mode_joints: &[usize] = match &shaped {
            ShapedModes::ByJoint(joints) => joints,
            ShapedModes::Lowest(k) => {
                if *k == 0 || *k > n_coordinates {
                    return Err(Error::InvalidParameter(format!(
                        "shaped_modes = {k}: a modal map with {n_coordinates} flexible \
                         coordinate(s) shapes 1 to {n_coordinates} of its lowest-frequency modes"
                    )));
                }
                &[]
            }
        };
        if mode_joints.is_empty() && matches!(shaped, ShapedModes::ByJoint(_)) {
            return Err(Error::InvalidParameter(
                "a modal map needs at least one mode to shape".into(),
            ));
        }
        let mut mode_flex_index = Vec::with_capacity(mode_joints.len());
        for (m, &joint) in mode_joints.iter().enumerate() {
            let Some(index) = flex.iter().position(|f| f.joint == joint) else {
                return Err(Error::InvalidParameter(format!(
                    "mode {m} is named by joint {joint}, which is not one of the flexible \
                     joints {:?}",
                    flex.iter().map(|f| f.joint).collect::<Vec<_>>()
                )));
            };
            if mode_flex_index.contains(&index) {
                return Err(Error::InvalidParameter(format!(
                    "joint {joint} names two modes"
                )));
            }
            mode_flex_index.push(index);
        }
        let required_joints = flex
            .iter()
            .map(|f| f.joint.max(f.damping_load_joint) + 1)
            .max()
            .unwrap_or(0);
        let uses_gravity = flex
            .iter()
            .any(|f| f.stiffness_nm_per_rad.uses_load() || f.damping_nms_per_rad.uses_load());
        let coordinate = flex.iter().map(|f| f.joint).collect();
        let load_coordinate = flex.iter().map(|f| f.damping_load_joint).collect();
        ModalMap {
            flex,
            hinges: Vec::new(),
            coordinate,
            load_coordinate,
            shaped,
            mode_flex_index,
            robot: None,
            required_joints,
            uses_gravity,
        }
        .with_link_hinges(hinges)
    }

    /// The same map, marked as identified on robot `name` (for example `"ur5e"`).
    pub fn for_robot(mut self, name: impl Into<String>) -> ModalMap {
        self.robot = Some(name.into());
        self
    }

    /// The same map with bending links `hinges` (module docs): distinct links, each hinge at a
    /// fraction in `(0, 1)`, stiffness finite and `> 0`, damping finite and `>= 0`, and at
    /// most [`MAX_FLEX_JOINTS`] flexible coordinates (joints plus two per hinge). Whether a
    /// link is long enough to bend is checked against the robot
    /// ([`crate::Robot::with_link_hinges`]).
    pub fn with_link_hinges(mut self, mut hinges: Vec<LinkHinge>) -> Result<ModalMap, Error> {
        hinges.sort_by_key(|h| h.link);
        let n_coordinates = self.flex.len() + 2 * hinges.len();
        if n_coordinates > MAX_FLEX_JOINTS {
            return Err(Error::InvalidParameter(format!(
                "{} flexible joint(s) and {} link hinge(s) make {n_coordinates} flexible \
                 coordinates, at most {MAX_FLEX_JOINTS}",
                self.flex.len(),
                hinges.len()
            )));
        }
        for (i, h) in hinges.iter().enumerate() {
            if i > 0 && hinges[i - 1].link == h.link {
                return Err(Error::InvalidParameter(format!(
                    "link {} has two hinges",
                    h.link
                )));
            }
            let ok = h.at_fraction > 0.0
                && h.at_fraction < 1.0
                && h.stiffness_nm_per_rad > 0.0
                && h.stiffness_nm_per_rad.is_finite()
                && h.damping_nms_per_rad >= 0.0
                && h.damping_nms_per_rad.is_finite();
            if !ok {
                return Err(Error::InvalidParameter(format!(
                    "hinge of link {}: needs at_fraction in (0, 1), finite stiffness > 0 and \
                     damping >= 0, got {h:?}",
                    h.link
                )));
            }
        }
        let links: Vec<usize> = hinges.iter().map(|h| h.link).collect();
        self.coordinate = self
            .flex
            .iter()
            .map(|f| hinged_index(f.joint, &links))
            .collect();
        for &l in &links {
            let first = hinged_index(l, &links) + 1;
            self.coordinate.extend([first, first + 1]);
        }
        self.load_coordinate = self
            .flex
            .iter()
            .map(|f| hinged_index(f.damping_load_joint, &links))
            .collect();
        let longest = links.iter().map(|&l| l + 1).max().unwrap_or(0);
        self.required_joints = self.required_joints.max(longest);
        self.hinges = hinges;
        Ok(self)
    }

    /// The bending links, in increasing link order (empty for a map of joints only).
    pub fn link_hinges(&self) -> &[LinkHinge] {
        &self.hinges
    }

    /// `(link, at_fraction)` of every hinge: what [`crate::Robot::with_link_hinges`] needs.
    pub fn hinge_placements(&self) -> Vec<(usize, f64)> {
        self.hinges
            .iter()
            .map(|h| (h.link, h.at_fraction))
            .collect()
    }

    /// Number of flexible coordinates (joints plus two per hinge).
    pub fn n_coordinates(&self) -> usize {
        self.coordinate.len()
    }

    /// Index of each flexible coordinate (joints, then two per hinge) among the joints of the
    /// evaluated arm (the hinged arm if the map has hinges).
    pub fn coordinates(&self) -> &[usize] {
        &self.coordinate
    }

    /// Joints of the arm the map evaluates (the hinged arm if it has hinges) that it reads:
    /// largest coordinate or load index + 1.
    pub fn model_joints(&self) -> usize {
        self.coordinate
            .iter()
            .chain(&self.load_coordinate)
            .map(|&c| c + 1)
            .max()
            .unwrap_or(0)
    }

    /// The robot the map was identified on, if known.
    pub fn robot(&self) -> Option<&str> {
        self.robot.as_deref()
    }

    /// The flexible joints, in the order given.
    pub fn flex_joints(&self) -> &[FlexJoint] {
        &self.flex
    }

    /// Which modes the map shapes.
    pub fn shaped_modes(&self) -> &ShapedModes {
        &self.shaped
    }

    /// The joints naming the shaped modes, in cascade order; `None` for a map shaping its
    /// lowest-frequency modes.
    pub fn mode_joints(&self) -> Option<&[usize]> {
        match &self.shaped {
            ShapedModes::ByJoint(joints) => Some(joints),
            ShapedModes::Lowest(_) => None,
        }
    }

    /// The same flexible joints shaping their `k` lowest-frequency modes
    /// ([`ShapedModes::Lowest`]), `1 <= k <=` the number of flexible joints; the robot is kept.
    pub fn shaping_lowest(&self, k: usize) -> Result<ModalMap, Error> {
        let map = ModalMap::shaping_hinged(
            self.flex.clone(),
            self.hinges.clone(),
            ShapedModes::Lowest(k),
        )?;
        Ok(ModalMap {
            robot: self.robot.clone(),
            ..map
        })
    }

    /// Number of shaped modes.
    pub fn n_modes(&self) -> usize {
        match self.shaped {
            ShapedModes::ByJoint(_) => self.mode_flex_index.len(),
            ShapedModes::Lowest(k) => k,
        }
    }

    /// Number of joints the map reads (largest joint or load-joint index + 1).
    pub fn required_joints(&self) -> usize {
        self.required_joints
    }

    /// Whether any law reads a gravity torque.
    pub fn uses_gravity(&self) -> bool {
        self.uses_gravity
    }

    /// Stiffness (N m/rad) and damping (N m s/rad) of every flexible joint, in the order of
    /// [`Self::flex_joints`], under the gravity torques `tau_g` (N m, at least
    /// [`Self::required_joints`] values when [`Self::uses_gravity`]; otherwise not read).
    /// Entries past the flexible joints are 0; NaN for a `tau_g` too short.
    pub fn joint_laws_at(&self, tau_g: &[f64]) -> ([f64; MAX_FLEX_JOINTS], [f64; MAX_FLEX_JOINTS]) {
        let load = |j: usize| {
            if !self.uses_gravity {
                0.0
            } else {
                tau_g.get(j).copied().unwrap_or(f64::NAN)
            }
        };
        let mut stiffness = [0.0; MAX_FLEX_JOINTS];
        let mut damping = [0.0; MAX_FLEX_JOINTS];
        for (i, f) in self.flex.iter().enumerate() {
            stiffness[i] = f.stiffness_nm_per_rad.value(load(f.joint));
            damping[i] = f.damping_nms_per_rad.value(load(f.damping_load_joint));
        }
        (stiffness, damping)
    }

    /// Every mode of the flexible coordinates from the mass matrix `mass` (row-major
    /// `n_dof × n_dof`, kg m²) and gravity torques `tau_g` (`n_dof` values, N m; may be empty
    /// when [`Self::uses_gravity`] is false), both of the arm the map evaluates: the robot,
    /// or with [`Self::link_hinges`] the hinged arm ([`crate::Robot::with_link_hinges`]) with
    /// straight hinges. `None` on wrong lengths, non-finite input or a mass block that is not
    /// positive definite.
    #[allow(clippy::needless_range_loop)] // index loops mirror the matrix formulas
    pub fn solve(&self, mass: &[f64], n_dof: usize, tau_g: &[f64]) -> Option<ModalSolution> {
        let nf = self.coordinate.len();
        let need = self.model_joints();
        if mass.len() != n_dof * n_dof || n_dof < need {
            return None;
        }
        let gravity = self.uses_gravity();
        if gravity && tau_g.len() < need {
            return None;
        }
        let mut stiffness = [0.0; MAX_FLEX_JOINTS];
        let mut damping = [0.0; MAX_FLEX_JOINTS];
        let load = |c: usize| if gravity { tau_g[c] } else { 0.0 };
        for (i, f) in self.flex.iter().enumerate() {
            stiffness[i] = f.stiffness_nm_per_rad.value(load(self.coordinate[i]));
            damping[i] = f.damping_nms_per_rad.value(load(self.load_coordinate[i]));
        }
        for (h, hinge) in self.hinges.iter().enumerate() {
            for i in [self.flex.len() + 2 * h, self.flex.len() + 2 * h + 1] {
                stiffness[i] = hinge.stiffness_nm_per_rad;
                damping[i] = hinge.damping_nms_per_rad;
            }
        }
        let mut inv_sqrt_k = [0.0; MAX_FLEX_JOINTS];
        let mut c_over_k = [0.0; MAX_FLEX_JOINTS];
        for i in 0..nf {
            let (k, c) = (stiffness[i], damping[i]);
            if !(k > 0.0 && k.is_finite() && c.is_finite()) {
                return None;
            }
            inv_sqrt_k[i] = 1.0 / k.sqrt();
            c_over_k[i] = c / k;
        }
        let mut b = [[0.0; MAX_DIM]; MAX_DIM];
        for (r, &cr) in self.coordinate.iter().enumerate() {
            for (s, &cs) in self.coordinate.iter().enumerate().skip(r) {
                b[r][s] = mass[cr * n_dof + cs] * inv_sqrt_k[r] * inv_sqrt_k[s];
            }
        }
        // Nearly diagonal (module docs): the damped solve works with the rotated matrix as it is.
        let (rotated, v) = sym_diagonalize(&b, nf, JACOBI_TOLERANCE)?;
        let mu: [f64; MAX_DIM] = std::array::from_fn(|i| rotated[i][i]);
        let mut out = ModalSolution {
            n: nf,
            wn_rad_s: [0.0; MAX_FLEX_JOINTS],
            zeta: [0.0; MAX_FLEX_JOINTS],
            strain_share: [[0.0; MAX_FLEX_JOINTS]; MAX_FLEX_JOINTS],
            shape: [[Complex64::new(0.0, 0.0); MAX_FLEX_JOINTS]; MAX_FLEX_JOINTS],
        };
        // Undamped modes and their projected damping: the start of the damped solve, and the
        // answer where it fails (module docs).
        let mut start = [Complex64::new(0.0, 0.0); MAX_FLEX_JOINTS];
        for i in 0..nf {
            if mu[i].is_nan() || mu[i] <= 0.0 {
                return None;
            }
            let wn = 1.0 / mu[i].sqrt();
            let modal_c: f64 = (0..nf).map(|f| c_over_k[f] * v[f][i] * v[f][i]).sum();
            out.wn_rad_s[i] = wn;
            out.zeta[i] = 0.5 * wn * modal_c;
            let zeta = out.zeta[i].min(0.9);
            start[i] = Complex64::new(-zeta * wn, wn * (1.0 - zeta * zeta).sqrt());
        }
        // In the (nearly) undamped modal coordinates `y = V z`: `(λ² VᵀBV + λ G + I) z = 0`
        // with `G = Vᵀ diag(c/k) V`.
        let mut g = [[0.0; MAX_DIM]; MAX_DIM];
        for i in 0..nf {
            for j in i..nf {
                let gij: f64 = (0..nf).map(|f| v[f][i] * c_over_k[f] * v[f][j]).sum();
                g[i][j] = gij;
                g[j][i] = gij;
            }
        }
        if let Some(damped) = damped_modes(&rotated, &g, nf, &start) {
            for i in 0..nf {
                let root = damped.roots[i];
                let wn = root.norm_sqr().sqrt();
                out.wn_rad_s[i] = wn;
                out.zeta[i] = -root.re / wn;
                // Strain shares |y_f|² of the unit vector y = V z.
                for f in 0..nf {
                    let y: Complex64 = (0..nf).map(|j| v[f][j] * damped.vectors[j][i]).sum();
                    out.strain_share[i][f] = y.norm_sqr();
                    out.shape[i][f] = y;
                }
            }
        } else {
            // The fallback: the undamped modes' shares `v_fi²`.
            for i in 0..nf {
                for f in 0..nf {
                    out.strain_share[i][f] = v[f][i] * v[f][i];
                    out.shape[i][f] = Complex64::new(v[f][i], 0.0);
                }
            }
        }
        Some(out)
    }

    /// The shaped modes, in cascade order, from the mass matrix and gravity torques (see
    /// [`Self::solve`]), each slot's eigenmode picked by the map's rule at this pose alone
    /// ("Which modes are shaped" in the module docs). Writes NaN modes and returns
    /// [`Status::BAD_LENGTH`] on wrong lengths (`out` must hold [`Self::n_modes`]); NaN modes
    /// with [`Status::OK`] when the input is not finite or not positive definite (the shaper
    /// then holds its last valid modes).
    ///
    /// The per-pose rule, for accuracy checks at independent poses; along a motion the
    /// streaming shaper follows each slot's eigenmode branch instead ([`Self::modes_tracked`]).
    pub fn modes_from_mass_matrix(
        &self,
        mass: &[f64],
        n_dof: usize,
        tau_g: &[f64],
        out: &mut [Mode],
    ) -> Status {
        let mut fresh = ModeTrack::default();
        self.modes_tracked(mass, n_dof, tau_g, &mut fresh, out)
    }

    /// The shaped modes as [`Self::modes_from_mass_matrix`], continuing the previous call with
    /// the same `track` ("Slots follow their branch" in the module docs): the rule's set, each
    /// member in the slot whose eigenmode it continues, and a slot whose eigenmode changed
    /// handing over gradually. With an empty track ([`ModeTrack::default`], or after
    /// [`ModeTrack::clear`]) the rule's picks as they are. A call without a valid solution
    /// leaves `track` as it was. Allocation-free, panic-free.
    pub fn modes_tracked(
        &self,
        mass: &[f64],
        n_dof: usize,
        tau_g: &[f64],
        track: &mut ModeTrack,
        out: &mut [Mode],
    ) -> Status {
        let bad_length = out.len() != self.n_modes()
            || mass.len() != n_dof * n_dof
            || n_dof < self.model_joints()
            || (self.uses_gravity() && tau_g.len() < self.model_joints());
        if bad_length {
            out.fill(Mode::new(f64::NAN, f64::NAN));
            return Status::BAD_LENGTH;
        }
        let Some(sol) = self.solve(mass, n_dof, tau_g) else {
            out.fill(Mode::new(f64::NAN, f64::NAN));
            return Status::OK;
        };
        let k = out.len().min(sol.n);
        let mut picks = [NO_MODE; MAX_FLEX_JOINTS];
        self.select(&sol, &mut picks[..k]);
        let following = track.slots == k && k > 0;
        if following && matches!(self.shaped, ShapedModes::Lowest(_)) {
            // The set's members to the slots whose eigenmodes they continue.
            track.follow(&sol, &mut picks[..k]);
        }
        for (s, o) in out.iter_mut().enumerate().take(k) {
            *o = track.output(s, &sol, picks[s], following);
        }
        track.record(&sol, &picks[..k], out);
        Status::OK
    }

    /// The map's rule at one pose (module docs): the eigenmode of each slot, into `picks`
    /// ([`NO_MODE`] where no eigenmode strains the slot's joint).
    fn select(&self, sol: &ModalSolution, picks: &mut [usize]) {
        match self.shaped {
            ShapedModes::Lowest(_) => {
                // Insertion sort of the (at most MAX_FLEX_JOINTS) eigenmodes by frequency; a
                // NaN frequency sorts last.
                let mut order: [usize; MAX_FLEX_JOINTS] = std::array::from_fn(|i| i);
                for i in 1..sol.n {
                    let mut j = i;
                    while j > 0
                        && sol.wn_rad_s[order[j]].total_cmp(&sol.wn_rad_s[order[j - 1]])
                            == std::cmp::Ordering::Less
                    {
                        order.swap(j, j - 1);
                        j -= 1;
                    }
                }
                // The K lowest as a set, in slots ordered by the flexible joint each strains
                // most, each slot taking the member of the set that strains its joint most.
                let k = picks.len().min(sol.n);
                let mut claimed = [true; MAX_FLEX_JOINTS];
                let mut slot_joint = [0usize; MAX_FLEX_JOINTS];
                for (r, &i) in order[..k].iter().enumerate() {
                    claimed[i] = false;
                    slot_joint[r] = dominant_joint(sol, i);
                }
                let slots = &mut slot_joint[..k];
                slots.sort_unstable();
                for (p, &f) in picks.iter_mut().zip(slots.iter()) {
                    *p = dominated_by(sol, f, &mut claimed);
                }
            }
            ShapedModes::ByJoint(_) => {
                // Each eigenmode is dominant for one shaped mode at most (cascade order).
                let mut claimed = [false; MAX_FLEX_JOINTS];
                for (p, &f) in picks.iter_mut().zip(&self.mode_flex_index) {
                    *p = dominated_by(sol, f, &mut claimed);
                }
            }
        }
    }
}

/// A slot without an eigenmode (its mode is NaN).
const NO_MODE: usize = usize::MAX;

/// Which eigenmode branch each shaped mode follows: the state of a streaming evaluation
/// ([`ModalMap::modes_tracked`]). Plain data on the stack; the default is empty (the map's
/// rule picks afresh).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModeTrack {
    /// Number of slots followed; 0 when empty.
    slots: usize,
    /// Per slot, the unit mode vector `y` (module docs) of its eigenmode at the latest call.
    shape: [[Complex64; MAX_FLEX_JOINTS]; MAX_FLEX_JOINTS],
    /// Per slot, that eigenmode's natural frequency, rad/s.
    wn_rad_s: [f64; MAX_FLEX_JOINTS],
    /// Number of entries of each `shape` (the map's flexible joints).
    n: usize,
    /// Per slot, the mode it gave at the latest call.
    given: [Mode; MAX_FLEX_JOINTS],
    /// Per slot, how far its mode still is from its eigenmode's after a handover:
    /// `ln ω_given − ln ω_eigenmode` and `ζ_given − ζ_eigenmode`, each brought to 0 by
    /// [`HANDOVER_STEP`] per call.
    offset: [(f64, f64); MAX_FLEX_JOINTS],
}

impl Default for ModeTrack {
    fn default() -> ModeTrack {
        ModeTrack {
            slots: 0,
            shape: [[Complex64::new(0.0, 0.0); MAX_FLEX_JOINTS]; MAX_FLEX_JOINTS],
            wn_rad_s: [0.0; MAX_FLEX_JOINTS],
            n: 0,
            given: [Mode::new(f64::NAN, f64::NAN); MAX_FLEX_JOINTS],
            offset: [(0.0, 0.0); MAX_FLEX_JOINTS],
        }
    }
}

impl ModeTrack {
    /// Forgets the branches: the next evaluation picks the slots by the map's rule.
    pub fn clear(&mut self) {
        self.slots = 0;
    }

    /// Whether slots are being followed.
    pub fn is_following(&self) -> bool {
        self.slots > 0
    }

    /// The eigenmodes of `picks` (the rule's set) reassigned to the slots whose eigenmodes
    /// they continue: the greedy assignment by [`Self::likeness`], the most alike (slot,
    /// member) pair first.
    fn follow(&self, sol: &ModalSolution, picks: &mut [usize]) {
        let k = picks.len();
        let mut scores = [[f64::NAN; MAX_FLEX_JOINTS]; MAX_FLEX_JOINTS];
        for (s, row) in scores.iter_mut().enumerate().take(k) {
            for (p, score) in row.iter_mut().enumerate().take(k) {
                if picks[p] < sol.n {
                    *score = self.likeness(s, sol, picks[p]);
                }
            }
        }
        let mut members = [NO_MODE; MAX_FLEX_JOINTS];
        members[..k].copy_from_slice(picks);
        let mut placed = [false; MAX_FLEX_JOINTS];
        let mut done = [false; MAX_FLEX_JOINTS];
        for _ in 0..k {
            let mut best: Option<(usize, usize, f64)> = None;
            for s in (0..k).filter(|&s| !done[s]) {
                for p in (0..k).filter(|&p| !placed[p]) {
                    let score = scores[s][p];
                    // A NaN score never wins.
                    if best.is_none_or(|(_, _, b)| score > b) && score >= 0.0 {
                        best = Some((s, p, score));
                    }
                }
            }
            let Some((s, p, _)) = best else {
                break; // the rest keep the rule's order
            };
            picks[s] = members[p];
            done[s] = true;
            placed[p] = true;
        }
        // Slots left without a member take the members left, in the rule's order.
        let mut rest = (0..k).filter(|&p| !placed[p]);
        for s in (0..k).filter(|&s| !done[s]) {
            picks[s] = rest.next().map_or(NO_MODE, |p| members[p]);
        }
    }

    /// Slot `s`'s mode with eigenmode `i` of `sol`: the eigenmode's, or, where the slot hands
    /// over from another eigenmode (`i` does not continue the slot's previous one), the slot's
    /// previous mode, brought to the eigenmode's by [`HANDOVER_STEP`] per call.
    fn output(&mut self, s: usize, sol: &ModalSolution, i: usize, following: bool) -> Mode {
        if i >= sol.n {
            return Mode::new(f64::NAN, f64::NAN);
        }
        let (wn, zeta) = (sol.wn_rad_s[i], sol.zeta[i]);
        if !following {
            self.offset[s] = (0.0, 0.0);
        } else if !self.continues(s, sol, i) {
            let given = self.given[s];
            self.offset[s] = if given.is_valid() {
                ((given.wn_rad_s / wn).ln(), given.zeta - zeta)
            } else {
                (0.0, 0.0)
            };
        }
        let (ln_wn, dz) = self.offset[s];
        if ln_wn == 0.0 && dz == 0.0 {
            return Mode::new(wn, zeta);
        }
        // ζ stays a damping ratio while the eigenmode's own ζ moves under the offset.
        let mode = Mode::new(wn * ln_wn.exp(), (zeta + dz).max(0.0));
        let toward_zero = |x: f64| x - x.clamp(-HANDOVER_STEP, HANDOVER_STEP);
        self.offset[s] = (toward_zero(ln_wn), toward_zero(dz));
        mode
    }

    /// Whether eigenmode `i` of `sol` continues slot `s`'s previous eigenmode: it is the most
    /// alike of all ([`Self::likeness`]).
    fn continues(&self, s: usize, sol: &ModalSolution, i: usize) -> bool {
        let own = self.likeness(s, sol, i);
        (0..sol.n).all(|j| {
            j == i
                || self.likeness(s, sol, j).partial_cmp(&own) != Some(std::cmp::Ordering::Greater)
        })
    }

    /// How much eigenmode `i` of `sol` is slot `s`'s previous eigenmode: its modal assurance
    /// criterion `|y_sᴴ y_i|² / (|y_s|² |y_i|²)` (1 for the same shape, 0 for orthogonal ones:
    /// the undamped modes are exactly orthogonal in `y`) divided by `1 + g /`
    /// [`TRACK_FREQUENCY_SCALE`], `g = |ln(ω_i/ω_s)|`.
    fn likeness(&self, s: usize, sol: &ModalSolution, i: usize) -> f64 {
        let (mut dot, mut norm_s, mut norm_i) = (Complex64::new(0.0, 0.0), 0.0, 0.0);
        for f in 0..self.n.min(sol.n) {
            let (a, b) = (self.shape[s][f], sol.shape[i][f]);
            dot += a.conj() * b;
            norm_s += a.norm_sqr();
            norm_i += b.norm_sqr();
        }
        let mac = dot.norm_sqr() / (norm_s * norm_i);
        let gap = (sol.wn_rad_s[i] / self.wn_rad_s[s]).ln().abs();
        mac / (1.0 + gap / TRACK_FREQUENCY_SCALE)
    }

    /// Keeps the eigenmodes of `picks` as the slots' branches and `given` as their modes; an
    /// empty track if any slot has none (the next call then starts afresh).
    fn record(&mut self, sol: &ModalSolution, picks: &[usize], given: &[Mode]) {
        if picks.is_empty() || picks.iter().any(|&i| i >= sol.n) {
            self.slots = 0;
            return;
        }
        for (s, &i) in picks.iter().enumerate() {
            self.shape[s] = sol.shape[i];
            self.wn_rad_s[s] = sol.wn_rad_s[i];
            self.given[s] = given[s];
        }
        self.slots = picks.len();
        self.n = sol.n;
    }
}

/// Index of the flexible joint that stores the largest share of eigenmode `i`'s strain
/// energy (the first on a tie; 0 if every share is NaN).
fn dominant_joint(sol: &ModalSolution, i: usize) -> usize {
    let mut best = 0;
    for f in 1..sol.n {
        if sol.strain_share[i][f] > sol.strain_share[i][best] {
            best = f;
        }
    }
    best
}

/// The eigenmode that stores the largest share of its strain energy in flexible joint `f`
/// among those not `claimed` by an earlier slot (then claimed); [`NO_MODE`] if none strains
/// the joint.
fn dominated_by(sol: &ModalSolution, f: usize, claimed: &mut [bool; MAX_FLEX_JOINTS]) -> usize {
    let share = |i: usize| sol.strain_share[i][f];
    let mut dominant: Option<usize> = None;
    for i in (0..sol.n).filter(|&i| !claimed[i]) {
        if dominant.is_none_or(|d| share(i) > share(d)) {
            dominant = Some(i);
        }
    }
    let Some(d) = dominant else {
        return NO_MODE;
    };
    claimed[d] = true;
    if share(d) > 0.0 {
        d
    } else {
        NO_MODE
    }
}

/// Off-diagonal tolerance (relative) of the Jacobi rotation into undamped modal coordinates.
/// The damped solve takes the rotated mass matrix as it is, so the tolerance does not limit
/// its accuracy; the start values and the projected modes (the fallback) neglect the
/// off-diagonal part, an error second order in it: about `1e-4` relative, divided by the
/// modes' relative separation. One or two sweeps on a 3 × 3 (measured: 1.45 against 1.52 µs
/// per full step at `1e-4`, `benches/modal_step.rs`).
pub const JACOBI_TOLERANCE: f64 = 1e-2;

/// Frequency gap `|ln(ω_i/ω_s)|` that halves how alike a tracked slot and an eigenmode count
/// ([`ModeTrack`]): 10 %. From one cycle to the next a slot's own eigenmode moves by about
/// `1e-3` in `ln ω` and keeps its shape (likeness near 1); any other eigenmode has a nearly
/// orthogonal shape. The gap decides only where the shapes cannot: a veering so sharp that
/// the shapes turn by about 45° within one cycle, where the branch nearer in frequency wins.
pub const TRACK_FREQUENCY_SCALE: f64 = 0.1;

/// Per call, how much of a handover's remaining gap a slot closes: `0.004` in `ln ω_n` and in
/// `ζ`. At a 2 ms cycle that is 2/s, below the shaper's slew limit of 5/s
/// ([`crate::tv_shaper::MAX_LN_WN_RATE_PER_S`]), so a handover is never reported as a jump
/// down to a 0.8 ms cycle; a handover from 15 to 31 Hz (`Δ ln ω = 0.73`) takes 0.37 s at
/// 2 ms.
pub const HANDOVER_STEP: f64 = 0.004;

#[cfg(test)]
mod tests {
    use super::*;

    fn joint(j: usize, k: f64, c: f64) -> FlexJoint {
        FlexJoint {
            joint: j,
            stiffness_nm_per_rad: LoadLaw::constant(k),
            damping_nms_per_rad: LoadLaw::constant(c),
            damping_load_joint: j,
        }
    }

    #[test]
    fn uncoupled_joints_give_the_single_joint_modes() {
        // Diagonal M: each mode is one joint, ω = √(k/J), ζ = c / (2 √(k J)).
        let map = ModalMap::new(vec![joint(0, 2.0e4, 50.0), joint(1, 1.8e4, 80.0)], &[1, 0])
            .expect("valid");
        let mass = [4.0, 0.0, 0.0, 9.0];
        let mut out = [Mode::new(0.0, 0.0); 2];
        assert!(map.modes_from_mass_matrix(&mass, 2, &[], &mut out).is_ok());
        let expect = |k: f64, j: f64, c: f64| Mode::new((k / j).sqrt(), c / (2.0 * (k * j).sqrt()));
        let (shoulder, base) = (expect(1.8e4, 9.0, 80.0), expect(2.0e4, 4.0, 50.0));
        assert!((out[0].wn_rad_s - shoulder.wn_rad_s).abs() < 1e-10);
        assert!((out[0].zeta - shoulder.zeta).abs() < 1e-14);
        assert!((out[1].wn_rad_s - base.wn_rad_s).abs() < 1e-10);
        assert!((out[1].zeta - base.zeta).abs() < 1e-14);
    }

    #[test]
    fn frequency_ranked_slots_do_not_swap_where_two_uncoupled_modes_cross() {
        // Diagonal M (no coupling): as the first joint's inertia sweeps, its mode (ζ 0.28)
        // crosses the second's (ζ 0.14) exactly. Each slot's ζ and frequency must change by
        // no more than a 0.2 % step in inertia explains (ζ not at all, the frequency of the
        // swept mode by 0.1 %); slots in frequency order swap there and jump by 0.14 in ζ.
        let modes_at = |j0: f64| {
            let (k, j1) = (2.0e4_f64, 8.0_f64);
            // c = 2 ζ √(k J) for ζ 0.28 on joint 0 and 0.14 on joint 1.
            let map = ModalMap::shaping(
                vec![
                    joint(0, k, 2.0 * 0.28 * (k * j0).sqrt()),
                    joint(1, k, 2.0 * 0.14 * (k * j1).sqrt()),
                ],
                ShapedModes::Lowest(2),
            )
            .expect("valid");
            let mut out = [Mode::new(0.0, 0.0); 2];
            assert!(map
                .modes_from_mass_matrix(&[j0, 0.0, 0.0, j1], 2, &[], &mut out)
                .is_ok());
            out
        };
        let mut previous = modes_at(7.0);
        for step in 1..=150 {
            let now = modes_at(7.0 * (1.002_f64).powi(step));
            for r in 0..2 {
                let jump = (now[r].zeta - previous[r].zeta).abs();
                assert!(jump < 1e-9, "slot {r} ζ jumps by {jump} at step {step}");
                let ratio = now[r].wn_rad_s / previous[r].wn_rad_s;
                assert!(
                    (ratio - 1.0).abs() < 1.1e-3,
                    "slot {r} ω jumps ×{ratio} at {step}"
                );
            }
            previous = now;
        }
        // Both modes are shaped, each with its own damping, on either side of the crossing.
        for j0 in [5.0, 12.0] {
            let out = modes_at(j0);
            assert!((out[0].zeta - 0.28).abs() < 1e-9 && (out[1].zeta - 0.14).abs() < 1e-9);
        }
    }

    #[test]
    fn bad_maps_are_refused() {
        assert!(ModalMap::new(vec![], &[0]).is_err());
        assert!(ModalMap::new(vec![joint(0, 1.0, 0.0), joint(0, 1.0, 0.0)], &[0]).is_err());
        assert!(ModalMap::new(vec![joint(0, 0.0, 0.0)], &[0]).is_err());
        assert!(ModalMap::new(vec![joint(0, 1.0, -1.0)], &[0]).is_err());
        assert!(ModalMap::new(vec![joint(0, 1.0, 0.0)], &[1]).is_err());
        assert!(ModalMap::new(vec![joint(0, 1.0, 0.0)], &[0, 0]).is_err());
        assert!(ModalMap::new(vec![joint(0, 1.0, 0.0)], &[]).is_err());
    }
}
