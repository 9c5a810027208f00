//! Mass moments of composite bodies and the spatial momentum of a turning composite, moved
//! exactly from one joint frame to its parent: the kernels of the robot model's composite
//! rigid body passes.

use crate::math::mat3::{add3, apply3, cross3, rotate_pair, rotate_sym_full};
use crate::robot::frame_step::{StepConstants, Twist};
use crate::robot::rigid_body::RigidBody;

/// Mass moments of one body about the origin of the frame it is fixed to, in that frame:
/// mass, first moment `h = m c` and second moment `E = ∫ r rᵀ dm` as `[xx, yy, zz, xy, xz,
/// yz]`. The inertia tensor about the origin is `tr(E) 1 − E`, so the inertia about the frame's
/// `z` axis is `E_xx + E_yy`. Moments of rigidly joined bodies add; a frame change transforms
/// them exactly ([`Moments::move_to_parent`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Moments {
    pub(crate) mass_kg: f64,
    pub(crate) first_kg_m: [f64; 3],
    pub(crate) second_kg_m2: [f64; 6],
}

impl Moments {
    pub(crate) const ZERO: Moments = Moments {
        mass_kg: 0.0,
        first_kg_m: [0.0; 3],
        second_kg_m2: [0.0; 6],
    };

    /// `E = m c cᵀ + ½ tr(I_c) 1 − I_c` from the inertia `I_c` about the centre of mass.
    pub(crate) fn of(body: &RigidBody) -> Moments {
        let m = body.mass_kg;
        let c = body.com_m;
        let [ixx, iyy, izz, ixy, ixz, iyz] = body.inertia_kg_m2;
        let half_trace = 0.5 * (ixx + iyy + izz);
        Moments {
            mass_kg: m,
            first_kg_m: [m * c[0], m * c[1], m * c[2]],
            second_kg_m2: [
                m * c[0] * c[0] + half_trace - ixx,
                m * c[1] * c[1] + half_trace - iyy,
                m * c[2] * c[2] + half_trace - izz,
                m * c[0] * c[1] - ixy,
                m * c[0] * c[2] - ixz,
                m * c[1] * c[2] - iyz,
            ],
        }
    }

    #[inline]
    pub(crate) fn add(&mut self, other: &Moments) {
        self.mass_kg += other.mass_kg;
        for (a, b) in self.first_kg_m.iter_mut().zip(&other.first_kg_m) {
            *a += b;
        }
        for (a, b) in self.second_kg_m2.iter_mut().zip(&other.second_kg_m2) {
            *a += b;
        }
    }

    /// From DH frame `k + 1` to frame `k` up to the final turn about `z`: `r ↦ (a, 0, d) +
    /// Rx(α) r`. The turn `Rz(q_k)` follows in [`Self::turn_z`]; it leaves the inertia about
    /// `z` (`E_xx + E_yy`) unchanged.
    #[inline]
    pub(crate) fn move_to_parent(&mut self, dh: &StepConstants) {
        if let Twist::Any = dh.twist {
            self.move_by(&dh.rot, &dh.shift);
            return;
        }
        let (m, h, e) = (self.mass_kg, &mut self.first_kg_m, &mut self.second_kg_m2);
        // Rx(α): the (y, z) plane turns.
        match dh.twist {
            Twist::None | Twist::Any => {}
            Twist::Quarter(s) => {
                (e[1], e[2], e[5]) = (e[2], e[1], -e[5]);
                (e[3], e[4]) = (-s * e[4], s * e[3]);
                (h[1], h[2]) = (-s * h[2], s * h[1]);
            }
            Twist::General => {
                rotate_sym_plane(e, 1, 2, 5, dh.cos_2alpha, dh.sin_2alpha);
                (e[3], e[4]) = rotate_pair(e[3], e[4], dh.cos_alpha, dh.sin_alpha);
                (h[1], h[2]) = rotate_pair(h[1], h[2], dh.cos_alpha, dh.sin_alpha);
            }
        }
        // Shift by p = (a, 0, d), along x then along z (zero offsets are common and skipped):
        // E += h pᵀ + p hᵀ + m p pᵀ, h += m p.
        let (a, d) = (dh.a_m, dh.d_m);
        if a != 0.0 {
            e[0] += a * (2.0 * h[0] + m * a);
            e[3] += a * h[1];
            e[4] += a * h[2];
            h[0] += m * a;
        }
        if d != 0.0 {
            e[2] += d * (2.0 * h[2] + m * d);
            e[4] += d * h[0];
            e[5] += d * h[1];
            h[2] += m * d;
        }
    }

    /// Any rigid step `r ↦ p + R r`: `E ↦ R E Rᵀ`, `h ↦ R h`, then the shift by `p`:
    /// `E += h pᵀ + p hᵀ + m p pᵀ`, `h += m p`.
    pub(crate) fn move_by(&mut self, r: &[f64; 9], p: &[f64; 3]) {
        let m = self.mass_kg;
        let e = rotate_sym_full(&self.second_kg_m2, r);
        let h = apply3(r, &self.first_kg_m);
        self.second_kg_m2 = [
            e[0] + p[0] * (2.0 * h[0] + m * p[0]),
            e[1] + p[1] * (2.0 * h[1] + m * p[1]),
            e[2] + p[2] * (2.0 * h[2] + m * p[2]),
            e[3] + p[0] * h[1] + p[1] * h[0] + m * p[0] * p[1],
            e[4] + p[0] * h[2] + p[2] * h[0] + m * p[0] * p[2],
            e[5] + p[1] * h[2] + p[2] * h[1] + m * p[1] * p[2],
        ];
        self.first_kg_m = [h[0] + m * p[0], h[1] + m * p[1], h[2] + m * p[2]];
    }

    /// `E_xx + E_yy` after [`Self::move_to_parent`] (the inertia about the parent's `z` axis,
    /// which the turn about that axis leaves unchanged), without forming the other entries:
    /// `Rx(α)` keeps `E_xx` and turns the `(y, z)` block; of the shift only `x` moves `E_xx`.
    #[inline]
    pub(crate) fn z_inertia_in_parent(&self, dh: &StepConstants) -> f64 {
        if let Twist::Any = dh.twist {
            let mut moved = *self;
            moved.move_by(&dh.rot, &dh.shift);
            return moved.second_kg_m2[0] + moved.second_kg_m2[1];
        }
        let (m, h, e) = (self.mass_kg, &self.first_kg_m, &self.second_kg_m2);
        let e_yy = match dh.twist {
            Twist::None | Twist::Any => e[1],
            Twist::Quarter(_) => e[2],
            Twist::General => {
                let mean = 0.5 * (e[1] + e[2]);
                let half_diff = 0.5 * (e[1] - e[2]);
                mean + (dh.cos_2alpha * half_diff - dh.sin_2alpha * e[5])
            }
        };
        let a = dh.a_m;
        let shift = if a != 0.0 {
            a * (2.0 * h[0] + m * a)
        } else {
            0.0
        };
        (e[0] + shift) + e_yy
    }

    /// True if every turn about `z` leaves these moments exactly as they are: the centre of
    /// mass on the axis and the `(x, y)` block of `E` isotropic with no products involving
    /// `x` or `y` (a body symmetric about `z`, such as a flange with a payload on its axis).
    pub(crate) fn is_turn_invariant(&self) -> bool {
        let (h, e) = (&self.first_kg_m, &self.second_kg_m2);
        h[0] == 0.0 && h[1] == 0.0 && e[0] == e[1] && e[3] == 0.0 && e[4] == 0.0 && e[5] == 0.0
    }

    /// `Rz(θ)` with `sin_cos = (sin θ, cos θ)`.
    #[inline]
    pub(crate) fn turn_z(&mut self, (s, c): (f64, f64)) {
        let (h, e) = (&mut self.first_kg_m, &mut self.second_kg_m2);
        rotate_sym_plane(e, 0, 1, 3, c * c - s * s, 2.0 * c * s);
        (e[4], e[5]) = rotate_pair(e[4], e[5], c, s);
        (h[0], h[1]) = rotate_pair(h[0], h[1], c, s);
    }
}

/// A spatial momentum (or force): `moment` about the frame origin and `linear`, in frame
/// coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Momentum {
    pub(crate) moment: [f64; 3],
    pub(crate) linear: [f64; 3],
}

impl Momentum {
    pub(crate) const ZERO: Momentum = Momentum {
        moment: [0.0; 3],
        linear: [0.0; 3],
    };

    /// Of a composite turning about the frame's `z` axis at unit rate: `ω = e_z` through the
    /// origin, so `(I_O e_z, e_z × h)` with `I_O = tr(E) 1 − E`.
    #[inline]
    pub(crate) fn of_joint(composite: &Moments) -> Momentum {
        let (e, h) = (&composite.second_kg_m2, &composite.first_kg_m);
        Momentum {
            moment: [-e[4], -e[5], e[0] + e[1]],
            linear: [-h[1], h[0], 0.0],
        }
    }

    /// As [`Moments::move_to_parent`]: `Rx(α)`, then the moment about the new origin gains
    /// `(a, 0, d) × linear`.
    #[inline]
    pub(crate) fn move_to_parent(&mut self, dh: &StepConstants) {
        if let Twist::Any = dh.twist {
            let (n, f) = (apply3(&dh.rot, &self.moment), apply3(&dh.rot, &self.linear));
            let p = &dh.shift;
            self.moment = add3(&n, &cross3(p, &f));
            self.linear = f;
            return;
        }
        let (n, f) = (&mut self.moment, &mut self.linear);
        match dh.twist {
            Twist::None | Twist::Any => {}
            Twist::Quarter(s) => {
                (n[1], n[2]) = (-s * n[2], s * n[1]);
                (f[1], f[2]) = (-s * f[2], s * f[1]);
            }
            Twist::General => {
                (n[1], n[2]) = rotate_pair(n[1], n[2], dh.cos_alpha, dh.sin_alpha);
                (f[1], f[2]) = rotate_pair(f[1], f[2], dh.cos_alpha, dh.sin_alpha);
            }
        }
        let (a, d) = (dh.a_m, dh.d_m);
        n[0] -= d * f[1];
        n[1] += d * f[0] - a * f[2];
        n[2] += a * f[1];
    }

    /// `Rz(θ)` with `sin_cos = (sin θ, cos θ)`.
    #[inline]
    pub(crate) fn turn_z(&mut self, (s, c): (f64, f64)) {
        let (n, f) = (&mut self.moment, &mut self.linear);
        (n[0], n[1]) = rotate_pair(n[0], n[1], c, s);
        (f[0], f[1]) = rotate_pair(f[0], f[1], c, s);
    }
}

/// The `(u, v)` block of the symmetric `e` (entries `uu`, `vv`, `uv`) turned by `(s, c)`,
/// with `c2 = cos 2θ`, `s2 = sin 2θ`: the mean of the diagonal is invariant, the half
/// difference and the off-diagonal entry turn by `2θ`.
#[inline]
pub(crate) fn rotate_sym_plane(
    e: &mut [f64; 6],
    uu: usize,
    vv: usize,
    uv: usize,
    c2: f64,
    s2: f64,
) {
    let mean = 0.5 * (e[uu] + e[vv]);
    let half_diff = 0.5 * (e[uu] - e[vv]);
    let off = e[uv];
    let diff_turned = c2 * half_diff - s2 * off;
    e[uv] = s2 * half_diff + c2 * off;
    e[uu] = mean + diff_turned;
    e[vv] = mean - diff_turned;
}
