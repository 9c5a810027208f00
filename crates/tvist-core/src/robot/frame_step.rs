//! The fixed step from one joint frame (after its turn) to the next, with the constants the
//! specialised passes of the robot model use (the twist `Rx(α)` of a DH step by kind).

use crate::robot::chain::DhJoint;
use crate::robot::placement::Pose;

/// The twist `Rx(α)` of a DH step, by kind: most arms use only `α ∈ {0, ±π/2}`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Twist {
    /// `α = 0`: nothing turns.
    None,
    /// `α = ±π/2` (to within 1e-15 rad, below the rounding of `π/2` itself): `(y, z) ↦
    /// (−s z, s y)` with `s = sin α = ±1`, exact swaps.
    Quarter(f64),
    /// Any other angle.
    General,
    /// Not a DH step at all: any rotation and translation ([`StepConstants::rot`] and
    /// [`StepConstants::shift`]).
    Any,
}

/// Per-joint constants of the fixed step `S_k` from joint frame `k` after its turn to frame
/// `k + 1`: `r ↦ shift + rot r`. A DH step `Tz(d) Tx(a) Rx(α)` (`shift = (a, 0, d)`, `rot =
/// Rx(α)`) also keeps its parameters for the passes specialised to it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct StepConstants {
    pub(crate) twist: Twist,
    pub(crate) rot: [f64; 9],
    pub(crate) shift: [f64; 3],
    pub(crate) a_m: f64,
    pub(crate) d_m: f64,
    pub(crate) cos_alpha: f64,
    pub(crate) sin_alpha: f64,
    pub(crate) cos_2alpha: f64,
    pub(crate) sin_2alpha: f64,
}

impl StepConstants {
    pub(crate) fn of(joint: &DhJoint) -> StepConstants {
        let (s, c) = joint.alpha_rad.sin_cos();
        let twist = if joint.alpha_rad == 0.0 {
            Twist::None
        } else if (joint.alpha_rad.abs() - core::f64::consts::FRAC_PI_2).abs() <= 1e-15 {
            Twist::Quarter(joint.alpha_rad.signum())
        } else {
            Twist::General
        };
        StepConstants {
            twist,
            rot: [1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c],
            shift: [joint.a_m, 0.0, joint.d_m],
            a_m: joint.a_m,
            d_m: joint.d_m,
            cos_alpha: c,
            sin_alpha: s,
            cos_2alpha: c * c - s * s,
            sin_2alpha: 2.0 * c * s,
        }
    }

    /// Any rigid step; one that is exactly a DH step (a rotation about `x` only, no shift
    /// along `y`: URDF joints placed along DH frames) keeps the specialised passes.
    pub(crate) fn of_pose(pose: &Pose) -> StepConstants {
        let (r, p) = (&pose.rot, &pose.pos);
        let about_x = r[0] == 1.0 && r[1] == 0.0 && r[2] == 0.0 && r[3] == 0.0 && r[6] == 0.0;
        if about_x && r[4] == r[8] && r[5] == -r[7] && p[1] == 0.0 {
            let (c, s) = (r[4], r[7]);
            let twist = if s == 0.0 && c == 1.0 {
                Twist::None
            } else if c.abs() <= 1e-15 && (s.abs() - 1.0).abs() <= 1e-15 {
                Twist::Quarter(s.signum())
            } else {
                Twist::General
            };
            return StepConstants {
                twist,
                rot: *r,
                shift: *p,
                a_m: p[0],
                d_m: p[2],
                cos_alpha: c,
                sin_alpha: s,
                cos_2alpha: c * c - s * s,
                sin_2alpha: 2.0 * c * s,
            };
        }
        StepConstants {
            twist: Twist::Any,
            rot: *r,
            shift: *p,
            a_m: 0.0,
            d_m: 0.0,
            cos_alpha: 1.0,
            sin_alpha: 0.0,
            cos_2alpha: 1.0,
            sin_2alpha: 0.0,
        }
    }
}
