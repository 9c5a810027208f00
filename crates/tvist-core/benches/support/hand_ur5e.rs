//! The cycle of bench row #10 written out by hand for the one case it measures: the UR5e with
//! a payload on the flange axis, the paper's map (no ranges, no gravity term), two ZV modes,
//! six channels, linear reads. Nothing general is left: the joint structure (which twists are
//! quarter turns, which offsets are zero), the map's form and the shaper are fixed in the code,
//! there is no status, no NaN holding, no clamping and no pose cache. Its cost is what the
//! arithmetic of the cycle needs on this machine, the floor the general path is compared with.
//!
//! The arithmetic is the same as the library's (composite mass moments carried inwards, the
//! map's closed forms, `K = exp(−ζπ/√(1−ζ²))`), written independently; the harness checks that
//! both give the same output.

use std::f64::consts::PI;
use tvist_core::math::trig;
use tvist_core::{MapCoefficients, Robot};

/// Mass, first moment `h` and second moment `E = ∫ r rᵀ dm` (`[xx, yy, zz, xy, xz, yz]`) of a
/// body about a frame's origin, in that frame.
#[derive(Clone, Copy, Default)]
struct Moments {
    m: f64,
    h: [f64; 3],
    e: [f64; 6],
}

impl Moments {
    fn of(body: &tvist_core::RigidBody) -> Moments {
        let (m, c, i) = (body.mass_kg, body.com_m, body.inertia_kg_m2);
        let half_trace = 0.5 * (i[0] + i[1] + i[2]);
        Moments {
            m,
            h: [m * c[0], m * c[1], m * c[2]],
            e: [
                m * c[0] * c[0] + half_trace - i[0],
                m * c[1] * c[1] + half_trace - i[1],
                m * c[2] * c[2] + half_trace - i[2],
                m * c[0] * c[1] - i[3],
                m * c[0] * c[2] - i[4],
                m * c[1] * c[2] - i[5],
            ],
        }
    }

    #[inline(always)]
    fn add(&mut self, o: &Moments) {
        self.m += o.m;
        for k in 0..3 {
            self.h[k] += o.h[k];
        }
        for k in 0..6 {
            self.e[k] += o.e[k];
        }
    }

    /// `Rx(s π/2)`: `(y, z) ↦ (−s z, s y)`.
    #[inline(always)]
    fn quarter_x(&mut self, s: f64) {
        let (h, e) = (&mut self.h, &mut self.e);
        (e[1], e[2], e[5]) = (e[2], e[1], -e[5]);
        (e[3], e[4]) = (-s * e[4], s * e[3]);
        (h[1], h[2]) = (-s * h[2], s * h[1]);
    }

    /// Shift of the origin by `−(a, 0, 0)` (the body seen from the parent's origin).
    #[inline(always)]
    fn shift_x(&mut self, a: f64) {
        let (m, h, e) = (self.m, &mut self.h, &mut self.e);
        e[0] += a * (2.0 * h[0] + m * a);
        e[3] += a * h[1];
        e[4] += a * h[2];
        h[0] += m * a;
    }

    /// Shift along `z` by `d`.
    #[inline(always)]
    fn shift_z(&mut self, d: f64) {
        let (m, h, e) = (self.m, &mut self.h, &mut self.e);
        e[2] += d * (2.0 * h[2] + m * d);
        e[4] += d * h[0];
        e[5] += d * h[1];
        h[2] += m * d;
    }

    /// `Rz(θ)` with `(s, c) = (sin θ, cos θ)`.
    #[inline(always)]
    fn turn_z(&mut self, (s, c): (f64, f64)) {
        let (h, e) = (&mut self.h, &mut self.e);
        let (c2, s2) = (c * c - s * s, 2.0 * c * s);
        let mean = 0.5 * (e[0] + e[1]);
        let half_diff = 0.5 * (e[0] - e[1]);
        let turned = c2 * half_diff - s2 * e[3];
        e[3] = s2 * half_diff + c2 * e[3];
        e[0] = mean + turned;
        e[1] = mean - turned;
        (e[4], e[5]) = (c * e[4] - s * e[5], s * e[4] + c * e[5]);
        (h[0], h[1]) = (c * h[0] - s * h[1], s * h[0] + c * h[1]);
    }
}

/// One ZV filter of six channels over a ring buffer (`cap` rows).
struct Zv {
    buf: Vec<[f64; 6]>,
    head: usize,
}

impl Zv {
    /// `A0 x + A1 ((1 − μ) x[age k] + μ x[age k + 1])` for a delay of `k + μ` samples.
    #[inline(always)]
    fn step(&mut self, x: &[f64; 6], a0: f64, delay_samples: f64) -> [f64; 6] {
        let cap = self.buf.len();
        self.head = if self.head + 1 == cap {
            0
        } else {
            self.head + 1
        };
        self.buf[self.head] = *x;
        let k = delay_samples as usize;
        let mu = delay_samples - k as f64;
        let i0 = if self.head >= k {
            self.head - k
        } else {
            self.head + cap - k
        };
        let i1 = if i0 == 0 { cap - 1 } else { i0 - 1 };
        let a1 = 1.0 - a0;
        let (w0, w1) = (a1 * (1.0 - mu), a1 * mu);
        let (r0, r1) = (self.buf[i0], self.buf[i1]);
        let mut y = [0.0; 6];
        for c in 0..6 {
            y[c] = a0 * x[c] + (w0 * r0[c] + w1 * r1[c]);
        }
        y
    }
}

/// The hand-written cycle. Built from the same robot and map as row #10 (checked to have the
/// structure the code assumes).
pub struct HandUr5eZv {
    /// Bodies 5.. (wrist 3 and payload) in frame 5: the same at every `q_5` (checked).
    beyond_4: Moments,
    /// Body `k` in frame `k + 1`, `k = 0..5`.
    body: [Moments; 5],
    a1: f64,
    a2: f64,
    d3: f64,
    d4: f64,
    base: MapCoefficients,
    shoulder: MapCoefficients,
    inv_dt_s: f64,
    filters: [Zv; 2],
    previous: [f64; 6],
}

impl HandUr5eZv {
    pub fn new(robot: &Robot, base: MapCoefficients, shoulder: MapCoefficients, dt_s: f64) -> Self {
        let j = robot.joints().expect("a DH chain");
        let alpha: Vec<f64> = j.iter().map(|j| j.alpha_rad).collect();
        let quarter = PI / 2.0;
        assert!(
            (alpha[0] - quarter).abs() < 1e-15
                && alpha[1] == 0.0
                && alpha[2] == 0.0
                && (alpha[3] - quarter).abs() < 1e-15
                && (alpha[4] + quarter).abs() < 1e-15
                && alpha[5] == 0.0,
            "the UR twists"
        );
        assert!(j[0].a_m == 0.0 && j[3].a_m == 0.0 && j[4].a_m == 0.0 && j[5].a_m == 0.0);
        assert!(j[1].d_m == 0.0 && j[2].d_m == 0.0);
        let links = robot.links();
        let last = links[5].combined(robot.payload());
        let mut beyond_4 = Moments::of(&last);
        beyond_4.shift_z(j[5].d_m);
        let (h, e) = (beyond_4.h, beyond_4.e);
        assert!(
            h[0] == 0.0 && h[1] == 0.0 && e[0] == e[1] && e[3] == 0.0 && e[4] == 0.0,
            "a payload on the flange axis"
        );
        for c in [&base, &shoulder] {
            assert!(c.c_1 == 0.0 && c.k_g == 0.0, "the reduced map");
        }
        let cap = 512;
        HandUr5eZv {
            beyond_4,
            body: std::array::from_fn(|k| Moments::of(&links[k])),
            a1: j[1].a_m,
            a2: j[2].a_m,
            d3: j[3].d_m,
            d4: j[4].d_m,
            base,
            shoulder,
            inv_dt_s: 1.0 / dt_s,
            filters: std::array::from_fn(|_| Zv {
                buf: vec![[0.0; 6]; cap],
                head: 0,
            }),
            previous: [0.0; 6],
        }
    }

    /// Starts at rest at `x0`.
    pub fn fill(&mut self, x0: &[f64; 6]) {
        for f in &mut self.filters {
            f.buf.iter_mut().for_each(|row| *row = *x0);
        }
        self.previous = *x0;
    }

    /// `(J_0, J_1)` at pose `q`, kg m².
    #[inline(always)]
    fn inertias(&self, q: &[f64; 6]) -> (f64, f64) {
        let sc = [
            trig::sin_cos(q[1]),
            trig::sin_cos(q[2]),
            trig::sin_cos(q[3]),
            trig::sin_cos(q[4]),
        ];
        let mut c = self.beyond_4;
        c.add(&self.body[4]);
        c.quarter_x(-1.0);
        c.shift_z(self.d4);
        c.turn_z(sc[3]);
        c.add(&self.body[3]);
        c.quarter_x(1.0);
        c.shift_z(self.d3);
        c.turn_z(sc[2]);
        c.add(&self.body[2]);
        c.shift_x(self.a2);
        c.turn_z(sc[1]);
        c.add(&self.body[1]);
        c.shift_x(self.a1);
        let j1 = c.e[0] + c.e[1];
        c.turn_z(sc[0]);
        c.add(&self.body[0]);
        // Rx(π/2) makes the new E_yy the old E_zz; no x shift at joint 0.
        (c.e[0] + c.e[2], j1)
    }

    /// `(A0, delay in samples)` of the ZV shaper for `(ω_n, ζ)`.
    #[inline(always)]
    fn zv(&self, wn_rad_s: f64, zeta: f64) -> (f64, f64) {
        // π/√u as (π/u)·√u: the division beside the square root, not after it.
        let u = 1.0 - zeta * zeta;
        let (pi_per_u, root) = (PI / u, u.sqrt());
        let k = (-zeta * pi_per_u * root).exp();
        (1.0 / (1.0 + k), pi_per_u * root * self.inv_dt_s / wn_rad_s)
    }

    #[inline(always)]
    pub fn step(&mut self, x: &[f64; 6]) -> [f64; 6] {
        let (j0, j1) = self.inertias(&self.previous);
        // Both modes: K = k_0 + k_J J_1, P = (J_1 + k_p) K, ω_n = √P / J_1.
        let (b, s) = (&self.base, &self.shoulder);
        let p_b = (j1 + b.k_p) * (b.k_0 + b.k_j * j1);
        let p_s = (j1 + s.k_p) * (s.k_0 + s.k_j * j1);
        let (root_b, root_s) = (p_b.sqrt(), p_s.sqrt());
        // Base (eqs. 47-48): ζ = (1 + k_p/J_0) (c_0 + c_2 J_0)(1 + c_τ J_0) / (2 √P).
        let zeta_b =
            (1.0 + b.k_p / j0) * (b.c_0 + b.c_2 * j0) * (1.0 + b.c_tau * j0) / (2.0 * root_b);
        // Shoulder (eq. 43): ζ = (1 + k_p/J_1)^½ (c_0 + c_2 J_1)(1 + c_τ J_1) / (2 √(K J_1)).
        let zeta_s =
            (1.0 + s.k_p / j1) * (s.c_0 + s.c_2 * j1) * (1.0 + s.c_tau * j1) / (2.0 * root_s);
        let (a_b, d_b) = self.zv(root_b / j1, zeta_b);
        let (a_s, d_s) = self.zv(root_s / j1, zeta_s);
        let stage = self.filters[0].step(x, a_b, d_b);
        let y = self.filters[1].step(&stage, a_s, d_s);
        self.previous = y;
        y
    }
}
