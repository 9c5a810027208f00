//! The joint inertias `J_k = M[k, k]` of the leading joints alone (no gravity torques, no
//! off-diagonal entries): what a dynamic map reads every cycle. The same composite rigid body
//! algorithm as [`crate::Robot`]'s joint-space pass, specialised at setup:
//!
//! - every joint's step kind (twist `α ∈ {0, ±π/2, other}`, shift along `x` and/or `z` or
//!   none) is resolved when the robot is built, and each kind's step is compiled on its own
//!   (no per-cycle tests of `α`, `a` or `d`);
//! - the body carried into a frame and every term of the frame change that involves only
//!   the (pose-independent) composite mass are one constant per joint
//!   ([`InertiaStep::body`]), so a step is a linear map of the carried moments plus that
//!   constant;
//! - the `(x, y)` block of the second moment is carried as its trace, difference and doubled
//!   product ([`AxialMoments`]): a turn about `z` keeps the trace (the inertia about the
//!   axis, read directly) and rotates the other two as a plain vector by `2θ`;
//! - every angle's sine and cosine (and those of twice the angle) are taken before the chain
//!   of steps starts, from the top joint down (the order the steps need them): none depends
//!   on the carried moments, so they run ahead of the chain, which then needs no spare
//!   registers for them.
//!
//! The results equal the general pass to rounding (the sums are associated differently).

use crate::math::mat3::apply3;
use crate::math::mat3::{rotate_pair, rotate_sym_full};
use crate::robot::frame_step::{StepConstants, Twist};
use crate::robot::mass_moments::Moments;

/// The mass-free part of [`Moments`] (about the frame origin, in frame coordinates) in the
/// form a turn about `z` acts on simply: `sum = E_xx + E_yy` (the inertia about `z`, kept by
/// the turn), `diff = E_xx − E_yy` and `off2 = 2 E_xy` (turned by `2θ` as a vector), `zz`, `xz`,
/// `yz` (the other entries of `E`, kg m²) and `h` (the first moment, kg m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct AxialMoments {
    sum: f64,
    diff: f64,
    off2: f64,
    zz: f64,
    xz: f64,
    yz: f64,
    h: [f64; 3],
}

impl AxialMoments {
    pub(crate) const ZERO: AxialMoments = AxialMoments {
        sum: 0.0,
        diff: 0.0,
        off2: 0.0,
        zz: 0.0,
        xz: 0.0,
        yz: 0.0,
        h: [0.0; 3],
    };

    pub(crate) fn of(m: &Moments) -> AxialMoments {
        let e = &m.second_kg_m2;
        AxialMoments {
            sum: e[0] + e[1],
            diff: e[0] - e[1],
            off2: 2.0 * e[3],
            zz: e[2],
            xz: e[4],
            yz: e[5],
            h: m.first_kg_m,
        }
    }

    /// `E_xx`, kg m².
    #[inline(always)]
    fn e_xx(&self) -> f64 {
        0.5 * (self.sum + self.diff)
    }

    /// `E_yy`, kg m².
    #[inline(always)]
    fn e_yy(&self) -> f64 {
        0.5 * (self.sum - self.diff)
    }

    /// `(E_yy, E_zz, E_yz)` after the general twist `Rx(α)` of `step`.
    #[inline(always)]
    fn yz_block_twisted(&self, step: &InertiaStep) -> (f64, f64, f64) {
        rotate_sym(
            self.e_yy(),
            self.zz,
            self.yz,
            step.cos_2alpha,
            step.sin_2alpha,
        )
    }

    /// `Rz(θ)`: the moments in axes turned by `θ` about `z`.
    #[inline(always)]
    fn turn(&mut self, t: &Turn) {
        (self.diff, self.off2) = rotate_pair(self.diff, self.off2, t.cos_2, t.sin_2);
        (self.xz, self.yz) = rotate_pair(self.xz, self.yz, t.cos, t.sin);
        (self.h[0], self.h[1]) = rotate_pair(self.h[0], self.h[1], t.cos, t.sin);
    }

    /// The carried moments of the bodies beyond joint `k` (in frame `k + 1`) moved into
    /// frame `k` before its turn, with body `k` and the mass terms added: `r ↦ (a, 0, d) +
    /// Rx(α) r` on the moments without their mass, plus [`InertiaStep::body`].
    /// `TWIST`: 0 none, 1 quarter, 2 general; `X`, `Z`: shifts along `x` (`a != 0`) and `z`
    /// (`d != 0`).
    #[inline(always)]
    fn carry<const TWIST: u8, const X: bool, const Z: bool>(&mut self, step: &InertiaStep) {
        let v = self;
        if TWIST == TWIST_QUARTER {
            // (y, z) ↦ (−s z, s y), s = ±1: E_yy and E_zz swap, E_yz changes sign,
            // (E_xy, E_xz) ↦ (−s E_xz, s E_xy), (h_y, h_z) ↦ (−s h_z, s h_y).
            let s = step.sin_alpha;
            let (e_xx, e_yy) = (v.e_xx(), v.e_yy());
            (v.sum, v.diff, v.zz) = (e_xx + v.zz, e_xx - v.zz, e_yy);
            v.yz = -v.yz;
            (v.off2, v.xz) = (-2.0 * s * v.xz, 0.5 * s * v.off2);
            (v.h[1], v.h[2]) = (-s * v.h[2], s * v.h[1]);
        } else if TWIST == TWIST_GENERAL {
            let (c, s) = (step.cos_alpha, step.sin_alpha);
            let e_xx = v.e_xx();
            let (e_yy, zz, yz) = v.yz_block_twisted(step);
            (v.sum, v.diff, v.zz, v.yz) = (e_xx + e_yy, e_xx - e_yy, zz, yz);
            let (xy, xz) = rotate_pair(0.5 * v.off2, v.xz, c, s);
            (v.off2, v.xz) = (2.0 * xy, xz);
            (v.h[1], v.h[2]) = rotate_pair(v.h[1], v.h[2], c, s);
        }
        // E += h pᵀ + p hᵀ (the m p pᵀ part and h += m p are in `body`), along x then z.
        if X {
            let shift = step.two_a * v.h[0];
            v.sum += shift;
            v.diff += shift;
            v.off2 += step.two_a * v.h[1];
            v.xz += step.a * v.h[2];
        }
        if Z {
            v.zz += step.two_d * v.h[2];
            v.xz += step.d * v.h[0];
            v.yz += step.d * v.h[1];
        }
        let b = &step.body;
        v.sum += b.sum;
        v.diff += b.diff;
        v.off2 += b.off2;
        v.zz += b.zz;
        v.xz += b.xz;
        v.yz += b.yz;
        v.h[0] += b.h[0];
        v.h[1] += b.h[1];
        v.h[2] += b.h[2];
    }

    /// [`Self::carry`]'s `sum` (the inertia about the parent's `z` axis) without the other
    /// entries.
    #[inline(always)]
    fn sum_after_carry(&self, step: &InertiaStep) -> f64 {
        let v = self;
        if step.kind == KIND_ANY {
            let mut moved = *v;
            moved.carry_any(step);
            return moved.sum;
        }
        let moved = match step.twist {
            Twist::None | Twist::Any => v.sum,
            Twist::Quarter(_) => v.e_xx() + v.zz,
            Twist::General => v.e_xx() + v.yz_block_twisted(step).0,
        };
        let shift = step.two_a * v.h[0];
        (moved + shift) + step.body.sum
    }

    /// Applies the step of `step.kind` (one compiled step per kind).
    #[inline(always)]
    fn carry_by_kind(&mut self, step: &InertiaStep) {
        match step.kind {
            0 => self.carry::<TWIST_NONE, false, false>(step),
            1 => self.carry::<TWIST_NONE, false, true>(step),
            2 => self.carry::<TWIST_NONE, true, false>(step),
            3 => self.carry::<TWIST_NONE, true, true>(step),
            4 => self.carry::<TWIST_QUARTER, false, false>(step),
            5 => self.carry::<TWIST_QUARTER, false, true>(step),
            6 => self.carry::<TWIST_QUARTER, true, false>(step),
            7 => self.carry::<TWIST_QUARTER, true, true>(step),
            8 => self.carry::<TWIST_GENERAL, false, false>(step),
            9 => self.carry::<TWIST_GENERAL, false, true>(step),
            10 => self.carry::<TWIST_GENERAL, true, false>(step),
            11 => self.carry::<TWIST_GENERAL, true, true>(step),
            _ => self.carry_any(step),
        }
    }

    /// [`Self::carry`] for a step that is no DH step: `E ↦ R E Rᵀ + h' pᵀ + p h'ᵀ` with
    /// `h' = R h` (the mass terms are in `body`), then the body added.
    #[inline(always)]
    fn carry_any(&mut self, step: &InertiaStep) {
        let v = self;
        let e = [v.e_xx(), v.e_yy(), v.zz, 0.5 * v.off2, v.xz, v.yz];
        let e = rotate_sym_full(&e, &step.rot);
        let h = apply3(&step.rot, &v.h);
        let p = &step.shift;
        let xx = e[0] + 2.0 * p[0] * h[0];
        let yy = e[1] + 2.0 * p[1] * h[1];
        let b = &step.body;
        v.sum = xx + yy + b.sum;
        v.diff = xx - yy + b.diff;
        v.off2 = 2.0 * (e[3] + p[0] * h[1] + p[1] * h[0]) + b.off2;
        v.zz = e[2] + 2.0 * p[2] * h[2] + b.zz;
        v.xz = e[4] + p[0] * h[2] + p[2] * h[0] + b.xz;
        v.yz = e[5] + p[1] * h[2] + p[2] * h[1] + b.yz;
        v.h = [h[0] + b.h[0], h[1] + b.h[1], h[2] + b.h[2]];
    }
}

const TWIST_NONE: u8 = 0;
const TWIST_QUARTER: u8 = 1;
const TWIST_GENERAL: u8 = 2;
/// The step kind of a step that is no DH step ([`Twist::Any`]).
const KIND_ANY: u8 = 12;

/// Setup-time constants of joint `k`'s step (frame `k + 1` into frame `k` before the turn).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct InertiaStep {
    /// `4 · twist + 2 · (a != 0) + (d != 0)`, twist 0 none, 1 quarter, 2 general; or
    /// [`KIND_ANY`] for a step that is no DH step.
    kind: u8,
    twist: Twist,
    a: f64,
    two_a: f64,
    d: f64,
    two_d: f64,
    cos_alpha: f64,
    sin_alpha: f64,
    cos_2alpha: f64,
    sin_2alpha: f64,
    /// The step's rotation and shift (read by [`KIND_ANY`] only).
    rot: [f64; 9],
    shift: [f64; 3],
    /// Body `k` (fixed to frame `k + 1`) moved into frame `k` as if it carried the mass of
    /// the whole composite `k..n` (`composite_mass_kg`): the frame change is affine in the
    /// moments for a given mass, so this is everything of the step that does not depend on
    /// the carried moments.
    pub(crate) body: AxialMoments,
}

impl InertiaStep {
    /// Joint `k`'s step: its DH constants, the moments of body `k` in frame `k + 1` and the
    /// mass of bodies `k..n`.
    pub(crate) fn of(dh: &StepConstants, body: &Moments, composite_mass_kg: f64) -> InertiaStep {
        let twist_index = match dh.twist {
            Twist::None => TWIST_NONE,
            Twist::Quarter(_) => TWIST_QUARTER,
            Twist::General | Twist::Any => TWIST_GENERAL,
        };
        let sin_alpha = match dh.twist {
            Twist::Quarter(s) => s,
            _ => dh.sin_alpha,
        };
        let mut moved = Moments {
            mass_kg: composite_mass_kg,
            ..*body
        };
        moved.move_to_parent(dh);
        InertiaStep {
            kind: match dh.twist {
                Twist::Any => KIND_ANY,
                _ => 4 * twist_index + 2 * u8::from(dh.a_m != 0.0) + u8::from(dh.d_m != 0.0),
            },
            rot: dh.rot,
            shift: dh.shift,
            twist: dh.twist,
            a: dh.a_m,
            two_a: 2.0 * dh.a_m,
            d: dh.d_m,
            two_d: 2.0 * dh.d_m,
            cos_alpha: dh.cos_alpha,
            sin_alpha,
            cos_2alpha: dh.cos_2alpha,
            sin_2alpha: dh.sin_2alpha,
            body: AxialMoments::of(&moved),
        }
    }
}

/// `sin`, `cos` of a joint angle and of twice it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Turn {
    sin: f64,
    cos: f64,
    sin_2: f64,
    cos_2: f64,
}

impl Turn {
    pub(crate) const ZERO_ANGLE: Turn = Turn {
        sin: 0.0,
        cos: 1.0,
        sin_2: 0.0,
        cos_2: 1.0,
    };

    /// For `|q| <= trig::FAST_RANGE_RAD` (checked by the caller).
    #[inline(always)]
    fn of(q: f64) -> Turn {
        let (sin, cos) = crate::math::trig::sin_cos_in_range(q);
        Turn {
            sin,
            cos,
            sin_2: 2.0 * cos * sin,
            cos_2: cos * cos - sin * sin,
        }
    }
}

/// `J_k` for `k < out.len()` at pose `q`, every `|q_k| <= trig::FAST_RANGE_RAD` (so finite).
///
/// `steps[k]` is joint `k`'s step; the bodies from joint `top + 1` on are folded into
/// `start`, the composite of bodies `top..n` in frame `top` before its turn (constant: the
/// turns of the joints beyond do not change it). `out.len() <= top + 1`; `turns` is scratch
/// of `q`'s length.
#[inline]
pub(crate) fn leading_joint_inertias(
    q: &[f64],
    steps: &[InertiaStep],
    top: usize,
    start: &AxialMoments,
    turns: &mut [Turn],
    out: &mut [f64],
) {
    if out.is_empty() {
        return;
    }
    let mut c = *start;
    if top == 0 {
        out[0] = c.sum;
        return;
    }
    // Every angle's sine first, in the order the turns need them: none depends on the
    // composite, so all are under way before the dependent chain of steps needs them.
    for (t, &qk) in turns[1..=top].iter_mut().zip(&q[1..=top]).rev() {
        *t = Turn::of(qk);
    }
    // Joints top..=2: read, turn, carry into the frame below; joint 1: read and turn; joint
    // 0: its inertia alone.
    for (k, (turn, step)) in turns[2..=top].iter().zip(&steps[1..top]).enumerate().rev() {
        if let Some(o) = out.get_mut(k + 2) {
            *o = c.sum;
        }
        c.turn(turn);
        c.carry_by_kind(step);
    }
    if let Some(o) = out.get_mut(1) {
        *o = c.sum;
    }
    c.turn(&turns[1]);
    out[0] = c.sum_after_carry(&steps[0]);
}

/// The symmetric block `[[uu, uv], [uv, vv]]` turned by `θ` (`c2 = cos 2θ`, `s2 = sin 2θ`):
/// `(uu, vv, uv)` after the turn.
#[inline(always)]
fn rotate_sym(uu: f64, vv: f64, uv: f64, c2: f64, s2: f64) -> (f64, f64, f64) {
    let mean = 0.5 * (uu + vv);
    let half_diff = 0.5 * (uu - vv);
    let diff_turned = c2 * half_diff - s2 * uv;
    (
        mean + diff_turned,
        mean - diff_turned,
        s2 * half_diff + c2 * uv,
    )
}
