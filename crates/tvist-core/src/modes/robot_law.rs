//! [`RobotModes`]: a [`Dynamics`] provider that evaluates a [`Robot`] at the previous shaped
//! output and turns what it reads of it into modes with a [`ModeLaw`], every cycle. The two
//! laws are the published ten-coefficient map ([`crate::MapDynamics`]: joint inertias) and
//! the modal map ([`crate::ModalDynamics`]: a mass-matrix block and its eigenproblem).
//!
//! The provider owns everything the laws share: the robot-name check, the check of the law
//! over the configuration space at construction (and the delay bound it gives), the one-pass
//! robot evaluation of only the joints the law reads, and the reuse of the previous modes for
//! a bit-identical pose. Allocation-free after construction.

use crate::error::{Error, Status};
use crate::modes::dynamics::Dynamics;
use crate::robot::link_hinges::hinged_index;
use crate::robot::model::Robot;
use crate::shaping::shapers::Mode;

/// Number of configurations checked at construction (and used for the delay bound).
///
/// The poses are a Halton sequence over `[−π, π]` per joint. Inertias and gravity torques are
/// 2π-periodic in every joint angle, so this box is the whole configuration space of any
/// revolute chain, whatever its joint limits. A Halton sequence is low-discrepancy: every
/// joint angle takes 4096 distinct values and pairs of joints are covered at a spacing of
/// roughly 2π/64. The check costs a few milliseconds at construction.
pub const VALIDATION_POSES: usize = 4096;

/// How modes follow from the robot at a pose: what the law reads, and the law itself.
pub trait ModeLaw {
    /// True if the law reads the mass-matrix block of its joints (row-major `n × n`), false if
    /// only the joint inertias (its diagonal, `n` values).
    const READS_MASS_MATRIX: bool;

    fn n_modes(&self) -> usize;
    /// The robot the law was identified on, if known.
    fn robot(&self) -> Option<&str>;
    /// Number of the robot's joints read (largest index + 1).
    fn required_joints(&self) -> usize;
    /// Hinges `(link, at_fraction)` the law inserts into the robot's links
    /// ([`Robot::with_link_hinges`]): the arm it evaluates. Empty (the default): the robot.
    fn link_hinges(&self) -> Vec<(usize, f64)> {
        Vec::new()
    }
    /// Number of joints of the evaluated arm read (largest index + 1): only these are
    /// evaluated. The robot's [`Self::required_joints`] without hinges.
    fn model_joints(&self) -> usize {
        self.required_joints()
    }
    /// Whether the law reads gravity torques.
    fn uses_gravity(&self) -> bool;
    /// What the law carries from one cycle to the next (the modal map: the eigenmode branch
    /// each slot follows); the default is the state of a fresh start.
    type Track: Clone + core::fmt::Debug + Default;
    /// Modes from the robot's inertias (or mass matrix) and gravity torques at one pose,
    /// continuing `track`. Allocation-free; invalid modes for input that gives none.
    fn modes_from_robot(
        &self,
        inertia: &[f64],
        n_dof: usize,
        tau_g: &[f64],
        track: &mut Self::Track,
        out: &mut [Mode],
    ) -> Status;
    /// The setup error for mode `m`, invalid at pose `q` where the robot gave `inertia`.
    fn invalid_mode_message(&self, m: usize, q: &[f64], inertia: &[f64], mode: Mode) -> String;
    /// Lowers the sampled `slowest[m].wn_rad_s` to an analytic bound valid at every pose, where
    /// the law has one. `robot` is the evaluated arm (hinged, if the law has hinges);
    /// `inertia` is the latest evaluation (a template for the joints the bound does not set).
    fn lower_frequency_bound(&self, robot: &Robot, inertia: &[f64], slowest: &mut [Mode]);
}

/// Per-cycle modes from `robot` and a mode law. Allocation-free after construction.
#[derive(Debug, Clone)]
pub struct RobotModes<L: ModeLaw> {
    robot: Robot,
    law: L,
    /// The arm evaluated when the law inserts link hinges ([`ModeLaw::link_hinges`]), its
    /// configuration (hinge angles stay 0) and where each real joint sits in it.
    hinged: Option<HingedArm>,
    /// Joint inertias (`n`) or mass matrix (`n × n`) of the latest evaluation, kg m² (only
    /// the joints the law reads are evaluated; other entries stay 0; `n` of the evaluated
    /// arm).
    inertia: Vec<f64>,
    tau_g: Vec<f64>,
    slowest: Vec<Mode>,
    /// The law's state carried from cycle to cycle ([`ModeLaw::Track`]).
    track: L::Track,
    last: LastCall,
    /// A pose (robot joints, rad) whose modes every cycle gives instead of those at the
    /// cycle's pose ([`Self::holding_at`]); `None`: the cycle's pose.
    held: Option<Vec<f64>>,
}

impl<L: ModeLaw> RobotModes<L> {
    /// Builds the provider and checks the law against the robot.
    ///
    /// Rejected: a law reading joints the robot does not have, or one that gives an invalid
    /// mode at any of the [`VALIDATION_POSES`] sampled configurations (evaluated exactly as
    /// every cycle does).
    ///
    /// A law identified on another robot than `robot` (both names known and different) is
    /// refused with [`Error::RobotMismatch`]; [`Self::new_allowing_other_robot`] skips that
    /// check.
    pub fn new(robot: Robot, law: L) -> Result<RobotModes<L>, Error> {
        if let (Some(law_robot), Some(name)) = (law.robot(), robot.name()) {
            if law_robot != name {
                return Err(Error::RobotMismatch {
                    map_robot: law_robot.to_string(),
                    robot: name.to_string(),
                });
            }
        }
        Self::new_allowing_other_robot(robot, law)
    }

    /// As [`Self::new`] without the robot-name check: for research, e.g. trying one robot's
    /// map on another. Every other check applies.
    pub fn new_allowing_other_robot(robot: Robot, law: L) -> Result<RobotModes<L>, Error> {
        let n = robot.n_dof();
        if law.required_joints() > n {
            return Err(Error::DimensionMismatch {
                what: if L::READS_MASS_MATRIX {
                    "joints read by the modal map (largest joint index + 1)"
                } else {
                    "joints read by the dynamic map (largest joint index + 1)"
                },
                expected: n,
                got: law.required_joints(),
            });
        }
        let hinges = law.link_hinges();
        let hinged = if hinges.is_empty() {
            None
        } else {
            let arm = robot.with_link_hinges(&hinges)?;
            let links: Vec<usize> = hinges.iter().map(|h| h.0).collect();
            Some(HingedArm {
                q: vec![0.0; arm.n_dof()],
                index: (0..n).map(|j| hinged_index(j, &links)).collect(),
                arm,
            })
        };
        let m = hinged.as_ref().map_or(n, |h| h.arm.n_dof());
        let mut provider = RobotModes {
            inertia: vec![0.0; if L::READS_MASS_MATRIX { m * m } else { m }],
            tau_g: vec![0.0; m],
            hinged,
            slowest: vec![Mode::new(f64::INFINITY, 0.0); law.n_modes()],
            last: LastCall::new(n, law.n_modes()),
            track: L::Track::default(),
            held: None,
            robot,
            law,
        };
        provider.check_workspace()?;
        Ok(provider)
    }

    /// Samples the configuration space: rejects invalid modes and records per mode the lowest
    /// `ω_n` and the highest `ζ`; then lowers `ω_n` to the law's analytic bound.
    fn check_workspace(&mut self) -> Result<(), Error> {
        let n = self.robot.n_dof();
        let primes = first_primes(n);
        let mut q = vec![0.0; n];
        let mut modes = vec![Mode::new(0.0, 0.0); self.law.n_modes()];
        for k in 1..=VALIDATION_POSES {
            halton_pose_with(k, &primes, &mut q);
            // Unrelated poses: each is a fresh start.
            self.restart();
            self.modes(&q, &mut modes);
            for (m, mode) in modes.iter().enumerate() {
                if !mode.is_valid() {
                    let message = self.law.invalid_mode_message(m, &q, &self.inertia, *mode);
                    return Err(Error::InvalidParameter(message));
                }
                let s = &mut self.slowest[m];
                *s = Mode::new(s.wn_rad_s.min(mode.wn_rad_s), s.zeta.max(mode.zeta));
            }
        }
        self.restart();
        let arm = self.hinged.as_ref().map_or(&self.robot, |h| &h.arm);
        self.law
            .lower_frequency_bound(arm, &self.inertia, &mut self.slowest);
        Ok(())
    }

    pub fn robot(&self) -> &Robot {
        &self.robot
    }

    /// The mode law (the dynamic map or the modal map).
    pub fn map(&self) -> &L {
        &self.law
    }

    /// The per-mode bounds used for delay-line sizing, see [`Dynamics::slowest_mode`].
    pub fn slowest_modes(&self) -> &[Mode] {
        &self.slowest
    }

    /// The same provider giving, every cycle, the modes at `pose` (the robot's joints, rad):
    /// constant modes for a move whose shaping should not follow the pose (e.g. the modes
    /// at where it stops, [`crate::TvShaper::hold_modes_at`]). `None`: the pose of each cycle
    /// again. A setup call (it copies the provider); refused for a pose of the wrong length or
    /// one where the law gives an invalid mode.
    pub fn holding_at(&self, pose: Option<&[f64]>) -> Result<RobotModes<L>, Error>
    where
        L: Clone,
    {
        let mut next = self.clone();
        next.held = None;
        next.restart();
        let Some(pose) = pose else {
            return Ok(next);
        };
        if pose.len() != self.robot.n_dof() {
            return Err(Error::DimensionMismatch {
                what: "joints of the pose to hold the modes at",
                expected: self.robot.n_dof(),
                got: pose.len(),
            });
        }
        let mut modes = vec![Mode::new(f64::NAN, f64::NAN); self.law.n_modes()];
        let status = next.modes(pose, &mut modes);
        if let Some((m, mode)) = modes.iter().enumerate().find(|(_, m)| !m.is_valid()) {
            return Err(Error::InvalidParameter(self.law.invalid_mode_message(
                m,
                pose,
                &next.inertia,
                *mode,
            )));
        }
        if !status.is_ok() {
            return Err(Error::InvalidParameter(format!(
                "the modes at the pose to hold could not be evaluated (status {status:?})"
            )));
        }
        next.held = Some(pose.to_vec());
        Ok(next)
    }

    /// The pose whose modes every cycle gives ([`Self::holding_at`]), if any.
    pub fn held_pose(&self) -> Option<&[f64]> {
        self.held.as_deref()
    }

    /// What the latest [`Dynamics::modes`] call read of the robot (see the aliases'
    /// `last_inertia` and `last_mass_matrix`).
    pub(crate) fn last_evaluation(&self) -> &[f64] {
        &self.inertia
    }

    /// The modes at `q` (the body of [`Dynamics::modes`], for the cycle's or the held pose).
    fn modes_at(&mut self, q: &[f64], out: &mut [Mode]) -> Status {
        if let Some(status) = self.last.repeat(q, out) {
            return status;
        }
        // One pass, only the joints (and torques) the law reads.
        let tau = if self.law.uses_gravity() {
            Some(self.tau_g.as_mut_slice())
        } else {
            None
        };
        let joints = self.law.model_joints();
        let (arm, q_arm) = match &mut self.hinged {
            None => (&mut self.robot, q),
            Some(h) => {
                if q.len() != h.index.len() {
                    out.fill(Mode::new(f64::NAN, f64::NAN));
                    return Status::BAD_LENGTH;
                }
                for (&i, &v) in h.index.iter().zip(q) {
                    h.q[i] = v;
                }
                (&mut h.arm, h.q.as_slice())
            }
        };
        let status = if L::READS_MASS_MATRIX {
            arm.leading_mass_matrix_and_gravity(q_arm, joints, &mut self.inertia, tau)
        } else {
            arm.leading_joint_inertia_and_gravity(q_arm, joints, &mut self.inertia, tau)
        };
        if !status.is_ok() {
            out.fill(Mode::new(f64::NAN, f64::NAN));
            return status;
        }
        let n = arm.n_dof();
        let status = self
            .law
            .modes_from_robot(&self.inertia, n, &self.tau_g, &mut self.track, out);
        self.last.record(q, out, status);
        status
    }
}

impl<L: ModeLaw> Dynamics for RobotModes<L> {
    fn n_modes(&self) -> usize {
        self.law.n_modes()
    }

    fn modes(&mut self, q: &[f64], out: &mut [Mode]) -> Status {
        // A held pose is evaluated once and then repeated (`last`); taken out and put back,
        // not copied, so that this stays allocation-free.
        match self.held.take() {
            None => self.modes_at(q, out),
            Some(pose) => {
                let status = self.modes_at(&pose, out);
                self.held = Some(pose);
                status
            }
        }
    }

    /// Lowest `ω_n` (sampled minimum, lowered to the law's analytic bound) paired with the
    /// highest sampled `ζ`. Pairing the two extremes gives the longest shaper a sampled pose
    /// can need; the shaper's safety factor covers `ζ` between samples, and any excess is
    /// clamped and reported as [`Status::DELAY_CLAMPED`].
    fn slowest_mode(&self, index: usize) -> Option<Mode> {
        self.slowest.get(index).copied()
    }

    fn n_dof(&self) -> Option<usize> {
        Some(self.robot.n_dof())
    }

    fn restart(&mut self) {
        self.track = L::Track::default();
        self.last.valid = false;
    }

    /// Held at a pose ([`RobotModes::holding_at`]): the same valid modes every call.
    fn modes_are_constant(&self) -> bool {
        self.held.is_some()
    }
}

/// The arm with link hinges a law evaluates, and the scratch configuration that carries the
/// robot's joint angles into it (hinge angles 0).
#[derive(Debug, Clone)]
struct HingedArm {
    arm: Robot,
    q: Vec<f64>,
    /// Index in `arm` of each of the robot's joints.
    index: Vec<usize>,
}

/// The pose and result of a provider's latest evaluation: modes are a function of the pose
/// alone, so a pose bit-identical to the previous one (an arm at rest: the shaped output
/// settles to a fixed value) returns the stored modes without evaluating anything.
#[derive(Debug, Clone)]
struct LastCall {
    q: Vec<f64>,
    modes: Vec<Mode>,
    status: Status,
    /// False until a result is recorded.
    valid: bool,
}

impl LastCall {
    fn new(n_dof: usize, n_modes: usize) -> LastCall {
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
    fn repeat(&self, q: &[f64], out: &mut [Mode]) -> Option<Status> {
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
    fn record(&mut self, q: &[f64], out: &[Mode], status: Status) {
        self.valid = q.len() == self.q.len() && out.len() == self.modes.len();
        if self.valid {
            self.q.copy_from_slice(q);
            self.modes.copy_from_slice(out);
            self.status = status;
        }
    }
}

/// Halton configuration `k` (`1..=VALIDATION_POSES`): joint `i` at `π (2 r(k, p_i) − 1)`
/// with `p_i` the `i`-th prime.
fn halton_pose_with(k: usize, primes: &[usize], q: &mut [f64]) {
    for (qi, &p) in q.iter_mut().zip(primes) {
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
