//! Rigid-body model of a serial revolute arm with a payload.
//!
//! The model runs on a chain of joint frames: frame `k + 1` is `T_{k+1} = T_k · Rz(q_k) S_k`
//! with a fixed step `S_k`; joint `k` (0-based) turns about `z` of frame `k`, link `k` is
//! fixed to frame `k + 1` and frame `n` is the flange. Two ways build it ([`Chain`]): standard
//! DH parameters (`S_k = Tz(d_k) Tx(a_k) Rx(α_k)`, frame 0 the base), or joints placed as URDF
//! places them ([`JointPlacement`]: an origin, then a turn about an axis), from which
//! [`crate::robot::placement`] derives the steps and the pose of frame 0 in the base. Gravity is
//! [`GRAVITY_M_S2`] along `−z` of the base; joint 0 turns about that axis in every DH chain
//! (and then nothing depends on `q_0`), about any axis in a placed one. Everything is link
//! side: no rotor inertia.
//!
//! All per-call methods are allocation-free: they work in a workspace preallocated by
//! [`Robot::new`] and write into caller buffers. A buffer of the wrong length returns
//! [`Status::BAD_LENGTH`] and leaves the output untouched; they never panic.
//! A non-finite joint angle (in any joint, also one nothing depends on) gives NaN entries.

use crate::error::{Error, Status};
use crate::math::mat3::{add3, apply3, cross3, dot3, mul3, rotate_pair, sub3, transpose3};
use crate::robot::chain::{Chain, DhJoint};
use crate::robot::frame_step::{StepConstants, Twist};
use crate::robot::inertia_pass::{leading_joint_inertias, AxialMoments, InertiaStep, Turn};
use crate::robot::mass_moments::{Moments, Momentum};
use crate::robot::placement::{joint_frames, JointPlacement, Origin, Pose};
use crate::robot::rigid_body::{principal_moments, RigidBody};

/// Standard gravity used for gravity torques, m/s².
pub const GRAVITY_M_S2: f64 = 9.81;

/// Per-call scratch, sized once for `n` joints.
#[derive(Debug, Clone)]
struct Workspace {
    /// World rotation (row-major 3×3) and origin of frames `0..=n` (flange pose, Jacobian).
    rot: Vec<[f64; 9]>,
    pos: Vec<[f64; 3]>,
    /// `(sin q_k, cos q_k)` of the current pose (entry 0 unused: nothing depends on `q_0`).
    sin_cos: Vec<(f64, f64)>,
    /// The base's `+z` (up) in the coordinates of frame `k`: `R_kᵀ e_z`.
    up: Vec<[f64; 3]>,
    /// Momentum of composite `j` moving with joint `j` at unit rate, carried down the chain
    /// to read `M[k, j]`, `k < j`.
    force: Vec<Momentum>,
    /// The turns of the current pose for the inertia-only pass.
    turns: Vec<Turn>,
}

impl Workspace {
    fn new(n: usize) -> Self {
        Workspace {
            rot: vec![[0.0; 9]; n + 1],
            pos: vec![[0.0; 3]; n + 1],
            sin_cos: vec![(0.0, 1.0); n],
            up: vec![[0.0, 0.0, 1.0]; n],
            force: vec![Momentum::ZERO; n],
            turns: vec![Turn::ZERO_ANGLE; n],
        }
    }
}

/// A serial revolute arm with link masses and a payload on the flange.
#[derive(Debug, Clone)]
pub struct Robot {
    chain: Chain,
    /// Per joint, the step to the next joint frame.
    dh: Vec<StepConstants>,
    /// Joint frame 0 in the base (the identity for a DH chain). Its `z` is vertical.
    base: Pose,
    /// The base's up direction in joint frame 0 (`(0, 0, ±1)` when joint 0 turns about the
    /// gravity axis, as in every DH chain).
    up_in_frame0: [f64; 3],
    /// Joint 0's axis is not the gravity axis: its angle changes the gravity torques.
    tilted_first_joint: bool,
    links: Vec<RigidBody>,
    payload: RigidBody,
    /// `links` in joint frames `1..=n` (link `k` in frame `k + 1`).
    frame_links: Vec<RigidBody>,
    /// `frame_links` with the payload merged into the last one: what the dynamics use.
    bodies: Vec<RigidBody>,
    /// [`Moments`] of `bodies[k]` in its own frame `k + 1`.
    moments: Vec<Moments>,
    /// The first joint `f >= 1` from which on the composite of bodies `f..n` in frame `f` is
    /// the same at every pose: each of the joints `f..n` turns a composite that is symmetric
    /// about its axis ([`Moments::is_turn_invariant`], for example the last wrist with a
    /// payload on the flange axis). `n` if the last joint's turn matters already.
    fixed_from: usize,
    /// That composite (bodies `fixed_from..n` in frame `fixed_from`; zero if `fixed_from == n`).
    fixed_composite: Moments,
    /// Bodies `fixed_from − 1..n` in frame `fixed_from − 1` before its joint's turn (also the
    /// same at every pose): where a pass that reads none of the joints from `fixed_from − 1`
    /// on starts.
    fixed_before_turn: Moments,
    /// Per joint, the constants of the inertia-only pass ([`crate::robot::inertia_pass`]).
    inertia_steps: Vec<InertiaStep>,
    /// [`Self::fixed_before_turn`] in that pass's form.
    fixed_start: AxialMoments,
    ws: Workspace,
    /// The robot's name (for example `"ur5e"`), if it has one: dynamic maps are checked
    /// against it.
    name: Option<String>,
}

impl Robot {
    /// Validates and builds the model of a DH chain. `links[i]` is expressed in DH frame
    /// `i + 1`; the payload in the flange frame `n`.
    pub fn new(
        joints: Vec<DhJoint>,
        links: Vec<RigidBody>,
        payload: RigidBody,
    ) -> Result<Robot, Error> {
        Robot::from_chain(Chain::Dh(joints), links, payload)
    }

    /// Validates and builds the model of joints placed as URDF places them: `links[i]` in the
    /// link frame after joint `i` (centre of mass and inertia axes in that frame), `flange`
    /// the flange frame's origin in the last link's frame, the payload in the flange frame.
    pub fn from_placements(
        joints: Vec<JointPlacement>,
        flange: Origin,
        links: Vec<RigidBody>,
        payload: RigidBody,
    ) -> Result<Robot, Error> {
        Robot::from_chain(Chain::Urdf { joints, flange }, links, payload)
    }

    /// Validates and builds the model of `chain` (links in the frames it names).
    pub fn from_chain(
        chain: Chain,
        links: Vec<RigidBody>,
        payload: RigidBody,
    ) -> Result<Robot, Error> {
        let n = chain.n_dof();
        if n == 0 {
            return Err(Error::InvalidParameter(
                "a robot needs at least one joint".into(),
            ));
        }
        if links.len() != n {
            return Err(Error::DimensionMismatch {
                what: "number of links",
                expected: n,
                got: links.len(),
            });
        }
        for (i, link) in links.iter().enumerate() {
            link.validate(&format!("link {i}"))?;
        }
        payload.validate("payload")?;
        let (dh, base, bodies) = match &chain {
            Chain::Dh(joints) => {
                for (i, j) in joints.iter().enumerate() {
                    if !(j.d_m.is_finite() && j.a_m.is_finite() && j.alpha_rad.is_finite()) {
                        return Err(Error::InvalidParameter(format!(
                            "joint {i}: DH parameters must be finite"
                        )));
                    }
                }
                let steps = joints.iter().map(StepConstants::of).collect();
                (steps, Pose::IDENTITY, links.clone())
            }
            Chain::Urdf { joints, flange } => {
                let frames = joint_frames(joints, flange, &links)?;
                let steps = frames.steps.iter().map(StepConstants::of_pose).collect();
                (steps, frames.base, frames.bodies)
            }
        };
        // R_baseᵀ e_z: the third row of the base rotation.
        let up_in_frame0 = [base.rot[6], base.rot[7], base.rot[8]];
        let tilted_first_joint = up_in_frame0[0] != 0.0 || up_in_frame0[1] != 0.0;
        let mut robot = Robot {
            dh,
            base,
            up_in_frame0,
            tilted_first_joint,
            frame_links: bodies.clone(),
            bodies,
            moments: vec![Moments::ZERO; n],
            fixed_from: n,
            fixed_composite: Moments::ZERO,
            fixed_before_turn: Moments::ZERO,
            inertia_steps: Vec::with_capacity(n),
            fixed_start: AxialMoments::ZERO,
            chain,
            links,
            payload,
            ws: Workspace::new(n),
            name: None,
        };
        robot.merge_payload();
        robot.check_bounds_finite()?;
        Ok(robot)
    }

    /// Refuses a model whose inertias or gravity torques can overflow (a finite but huge
    /// mass or centre of mass, e.g. a payload 1e200 m from the flange): every quantity the
    /// model computes is below these bounds, so finite bounds mean finite results.
    fn check_bounds_finite(&self) -> Result<(), Error> {
        let inertia = self.joint_inertia_upper_bound();
        let torque = self.gravity_torque_upper_bound();
        if inertia.iter().chain(&torque).all(|v| v.is_finite()) {
            return Ok(());
        }
        Err(Error::InvalidParameter(format!(
            "the masses and centres of mass give non-finite joint inertias or gravity torques \
             (payload {} kg at com_m = {:?} m): use physical values",
            self.payload.mass_kg, self.payload.com_m
        )))
    }

    /// The same robot with a name (checked against a dynamic map's robot).
    pub fn with_name(mut self, name: impl Into<String>) -> Robot {
        self.name = Some(name.into());
        self
    }

    /// The robot's name, if it has one.
    pub fn name(&self) -> Option<&str> {
        self.name.as_deref()
    }

    fn merge_payload(&mut self) {
        let n = self.dh.len();
        self.bodies.copy_from_slice(&self.frame_links);
        self.bodies[n - 1] = self.frame_links[n - 1].combined(&self.payload);
        for (m, b) in self.moments.iter_mut().zip(&self.bodies) {
            *m = Moments::of(b);
        }
        // The composite pass from the flange inwards, as long as no turn changes anything
        // (joint 0 is never turned; it is not folded in).
        self.fixed_from = n;
        self.fixed_composite = Moments::ZERO;
        let mut composite = Moments::ZERO;
        for k in (1..n).rev() {
            composite.add(&self.moments[k]);
            composite.move_to_parent(&self.dh[k]);
            if !composite.is_turn_invariant() {
                break;
            }
            self.fixed_from = k;
            self.fixed_composite = composite;
        }
        let last = self.fixed_from - 1;
        self.fixed_before_turn = self.fixed_composite;
        self.fixed_before_turn.add(&self.moments[last]);
        self.fixed_before_turn.move_to_parent(&self.dh[last]);
        self.fixed_start = AxialMoments::of(&self.fixed_before_turn);
        // Mass of the composite of bodies k..n, from the flange inwards.
        let mut beyond_kg = 0.0;
        self.inertia_steps.clear();
        for k in (0..n).rev() {
            beyond_kg += self.bodies[k].mass_kg;
            let step = InertiaStep::of(&self.dh[k], &self.moments[k], beyond_kg);
            self.inertia_steps.push(step);
        }
        self.inertia_steps.reverse();
    }

    /// Replaces the payload (setup-time call: validates).
    pub fn set_payload(&mut self, payload: RigidBody) -> Result<(), Error> {
        payload.validate("payload")?;
        let previous = self.payload;
        self.payload = payload;
        self.merge_payload();
        if let Err(e) = self.check_bounds_finite() {
            self.payload = previous;
            self.merge_payload();
            return Err(e);
        }
        Ok(())
    }

    pub fn n_dof(&self) -> usize {
        self.dh.len()
    }

    /// The DH parameters of a DH chain (`None` for URDF placement).
    pub fn joints(&self) -> Option<&[DhJoint]> {
        match &self.chain {
            Chain::Dh(joints) => Some(joints),
            Chain::Urdf { .. } => None,
        }
    }

    /// How the joints are placed, as given.
    pub fn chain(&self) -> &Chain {
        &self.chain
    }

    /// The links as given (in the frames [`Chain`] names).
    pub fn links(&self) -> &[RigidBody] {
        &self.links
    }

    pub fn payload(&self) -> &RigidBody {
        &self.payload
    }

    /// Forward kinematics of every frame into the workspace. False on a wrong `q` length.
    ///
    /// `R_{k+1} = R_k Rz(q_k) Rx(α_k)` column by column: with `u = cos q R e_x + sin q R e_y`
    /// and `v = −sin q R e_x + cos q R e_y`, the new columns are `u`, `cos α v + sin α R e_z`
    /// and `−sin α v + cos α R e_z`; the origin moves by `a u + d R e_z`.
    fn forward(&mut self, q: &[f64]) -> bool {
        if q.len() != self.dh.len() {
            return false;
        }
        let ws = &mut self.ws;
        let mut r = self.base.rot;
        let mut p = self.base.pos;
        ws.rot[0] = r;
        ws.pos[0] = p;
        let frames = ws.rot[1..].iter_mut().zip(&mut ws.pos[1..]);
        for ((qk, dh), (rot, pos)) in q.iter().zip(&self.dh).zip(frames) {
            let (st, ct) = crate::math::trig::sin_cos(*qk);
            if let Twist::Any = dh.twist {
                // R Rz(q) then the step: p += R Rz(q) shift, R ← R Rz(q) rot.
                let turn = [ct, -st, 0.0, st, ct, 0.0, 0.0, 0.0, 1.0];
                let turned = mul3(&r, &turn);
                let moved = apply3(&turned, &dh.shift);
                p = add3(&p, &moved);
                r = mul3(&turned, &dh.rot);
                *rot = r;
                *pos = p;
                continue;
            }
            let (ca, sa) = (dh.cos_alpha, dh.sin_alpha);
            let mut u = [0.0; 3];
            let mut v = [0.0; 3];
            for row in 0..3 {
                let (x, y, z) = (r[3 * row], r[3 * row + 1], r[3 * row + 2]);
                u[row] = ct * x + st * y;
                v[row] = ct * y - st * x;
                p[row] += dh.a_m * u[row] + dh.d_m * z;
                r[3 * row] = u[row];
                r[3 * row + 1] = ca * v[row] + sa * z;
                r[3 * row + 2] = ca * z - sa * v[row];
            }
            *rot = r;
            *pos = p;
        }
        true
    }

    /// The joint-space pass: for joints `k < joints`, the inertia `M[k, k]` into `inertia[k]`
    /// (or, with `mass`, the leading `joints × joints` block of the row-major `n × n` mass
    /// matrix) and the gravity torque into `tau_g[k]`. Caller checks lengths: `q`, `inertia`
    /// and `tau_g` have `n` entries, `mass` `n²`, `joints <= n`.
    ///
    /// The composite rigid body algorithm in link coordinates: from the flange inwards, the
    /// mass moments ([`Moments`]) of bodies `k..n` are carried from frame `k + 1` into frame
    /// `k` (`Rz(q_k) Tz(d_k) Tx(a_k) Rx(α_k)`), where joint `k` is the `z` axis through the
    /// origin, so `M[k, k] = E_xx + E_yy` and `τ_g,k = g (u_y h_x − u_x h_y)` with `u` the
    /// base's up direction in frame `k` (`∂V/∂q_k = g e_z · (z_k × h)`). Off the diagonal,
    /// `M[k, j]` is the `z` moment about joint `k` of the spatial momentum of composite `j`
    /// turning about joint `j` at unit rate, carried down with the composite. Nothing depends
    /// on `q_0` when joint 0 turns the arm about the gravity axis, so its sine is then never
    /// taken (a first joint off that axis turns the gravity torques: its sine is taken for them);
    /// the composite of the bodies beyond `fixed_from` is a constant formed at setup
    /// (their joints turn nothing that matters), so their sines are not taken either: one
    /// `sin_cos` per joint `1..fixed_from`, no world transforms.
    ///
    /// A non-finite angle in `q` (any joint, read or not) gives NaN for every entry evaluated.
    fn joint_space_pass(
        &mut self,
        q: &[f64],
        joints: usize,
        mut inertia: Option<&mut [f64]>,
        mut mass: Option<&mut [f64]>,
        mut tau_g: Option<&mut [f64]>,
    ) {
        let n = self.dh.len();
        if !q.iter().all(|v| v.is_finite()) {
            let nan = f64::NAN;
            for k in 0..joints {
                if let Some(out) = inertia.as_deref_mut() {
                    out[k] = nan;
                }
                if let Some(m) = mass.as_deref_mut() {
                    m[k * n..k * n + joints].fill(nan);
                }
                if let Some(t) = tau_g.as_deref_mut() {
                    t[k] = nan;
                }
            }
            return;
        }
        // The joints beyond `start` are folded into the constant composite of setup; the
        // mass-matrix entries and torques of joints read there would need their own terms, so
        // a pass reading them starts at the flange.
        let (start, mut composite) = if joints <= self.fixed_from {
            (self.fixed_from, self.fixed_composite)
        } else {
            (n, Moments::ZERO)
        };
        let ws = &mut self.ws;
        // q_0 matters only to the gravity torques of a first joint off the gravity axis.
        let tilted = self.tilted_first_joint && tau_g.is_some();
        let first = usize::from(!tilted);
        crate::math::trig::sin_cos_each(&q[first..start], &mut ws.sin_cos[first..start]);
        if tau_g.is_some() {
            // u_{k+1} = S_kᵀ Rz(q_k)ᵀ u_k from u_0, the base's up in frame 0 (Rz(q_0) leaves
            // it as it is when it is the axis).
            let mut u = self.up_in_frame0;
            for k in 1..joints {
                if k > 1 || tilted {
                    let (s, c) = ws.sin_cos[k - 1];
                    (u[0], u[1]) = rotate_pair(u[0], u[1], c, -s);
                }
                let dh = &self.dh[k - 1];
                if let Twist::Any = dh.twist {
                    u = apply3(&transpose3(&dh.rot), &u);
                } else {
                    (u[1], u[2]) = rotate_pair(u[1], u[2], dh.cos_alpha, -dh.sin_alpha);
                }
                ws.up[k] = u;
            }
        }
        // Joints nothing is read of: the composite alone, carried inwards (from setup's
        // composite before the first turn that matters, if none of those joints is read).
        let mut end = start;
        if joints < start && start == self.fixed_from {
            composite = self.fixed_before_turn;
            composite.turn_z(ws.sin_cos[start - 1]);
            end = start - 1;
        }
        let beyond = self.moments[joints..end]
            .iter()
            .zip(&self.dh[joints..end])
            .zip(&ws.sin_cos[joints..end]);
        for ((body, dh), &sc) in beyond.rev() {
            composite.add(body);
            composite.move_to_parent(dh);
            composite.turn_z(sc);
        }
        let read = self.moments[..joints]
            .iter()
            .zip(&self.dh[..joints])
            .zip(&ws.sin_cos[..joints]);
        for (k, ((body, dh), &sc)) in read.enumerate().rev() {
            composite.add(body);
            if k == 0 && mass.is_none() && !tilted {
                // Joint 0's inertia alone (its gravity torque is 0): no full frame change.
                if let Some(out) = inertia.as_deref_mut() {
                    out[0] = composite.z_inertia_in_parent(dh);
                }
                if let Some(t) = tau_g.as_deref_mut() {
                    t[0] = 0.0;
                }
                break;
            }
            composite.move_to_parent(dh);
            let e = &composite.second_kg_m2;
            let diagonal = e[0] + e[1];
            if let Some(out) = inertia.as_deref_mut() {
                out[k] = diagonal;
            }
            if let Some(m) = mass.as_deref_mut() {
                m[k * n + k] = diagonal;
                // M[k, j], j > k: the momenta of the composites beyond, carried into frame k.
                for (j, f) in ws.force.iter_mut().enumerate().take(joints).skip(k + 1) {
                    f.move_to_parent(dh);
                    m[k * n + j] = f.moment[2];
                    m[j * n + k] = f.moment[2];
                }
            }
            if k == 0 {
                if let Some(t) = tau_g.as_deref_mut() {
                    t[0] = if tilted {
                        composite.turn_z(sc);
                        let (h, u) = (&composite.first_kg_m, &self.up_in_frame0);
                        GRAVITY_M_S2 * (u[1] * h[0] - u[0] * h[1])
                    } else {
                        0.0 // joint 0 turns about the gravity axis
                    };
                }
                break;
            }
            composite.turn_z(sc);
            let h = &composite.first_kg_m;
            if let Some(t) = tau_g.as_deref_mut() {
                let u = &ws.up[k];
                t[k] = GRAVITY_M_S2 * (u[1] * h[0] - u[0] * h[1]);
            }
            if mass.is_some() {
                for f in &mut ws.force[k + 1..joints] {
                    f.turn_z(sc);
                }
                ws.force[k] = Momentum::of_joint(&composite);
            }
        }
    }

    /// Homogeneous transform of the flange in the base frame, row-major 4×4.
    pub fn flange_pose(&mut self, q: &[f64], out: &mut [f64; 16]) -> Status {
        if !self.forward(q) {
            return Status::BAD_LENGTH;
        }
        let n = self.dh.len();
        let (r, p) = (&self.ws.rot[n], &self.ws.pos[n]);
        *out = [
            r[0], r[1], r[2], p[0], r[3], r[4], r[5], p[1], r[6], r[7], r[8], p[2], 0.0, 0.0, 0.0,
            1.0,
        ];
        Status::OK
    }

    /// Geometric Jacobian of the flange origin in the base frame, row-major `6 × n` with rows
    /// `[linear velocity; angular velocity]`.
    pub fn jacobian(&mut self, q: &[f64], out: &mut [f64]) -> Status {
        let n = self.dh.len();
        if out.len() != 6 * n || !self.forward(q) {
            return Status::BAD_LENGTH;
        }
        let tip = self.ws.pos[n];
        for i in 0..n {
            let r = &self.ws.rot[i];
            let z = [r[2], r[5], r[8]];
            let lin = cross3(&z, &sub3(&tip, &self.ws.pos[i]));
            for k in 0..3 {
                out[k * n + i] = lin[k];
                out[(k + 3) * n + i] = z[k];
            }
        }
        Status::OK
    }

    /// Joint-space inertia matrix `M(q)` (composite rigid body algorithm), row-major `n × n`.
    pub fn mass_matrix(&mut self, q: &[f64], out: &mut [f64]) -> Status {
        let n = self.dh.len();
        self.leading_mass_matrix_and_gravity(q, n, out, None)
    }

    /// Diagonal of `M(q)`: `J_i = M[i, i]`, the inertia about joint `i` of everything
    /// beyond it, in kg m².
    pub fn joint_inertia(&mut self, q: &[f64], out: &mut [f64]) -> Status {
        self.joint_inertia_and_gravity(q, out, None)
    }

    /// Gravity torques `τ_g(q) = ∂V/∂q` (the torques that hold the arm still), N m.
    pub fn gravity_torque(&mut self, q: &[f64], out: &mut [f64]) -> Status {
        let n = self.dh.len();
        if out.len() != n || q.len() != n {
            return Status::BAD_LENGTH;
        }
        self.joint_space_pass(q, n, None, None, Some(out));
        Status::OK
    }

    /// Joint inertias and, if `tau_g` is given, gravity torques from one pass (the composite
    /// rigid body algorithm: the inertias are exactly the diagonal of [`Self::mass_matrix`]).
    pub fn joint_inertia_and_gravity(
        &mut self,
        q: &[f64],
        inertia: &mut [f64],
        tau_g: Option<&mut [f64]>,
    ) -> Status {
        let n = self.dh.len();
        if !Self::lengths_ok(n, q, inertia, n, &tau_g) {
            return Status::BAD_LENGTH;
        }
        self.joint_space_pass(q, n, Some(inertia), None, tau_g);
        Status::OK
    }

    /// [`Self::joint_inertia_and_gravity`] for joints `0..joints` only (for example the
    /// joints a dynamic map reads): entries from `joints` on are left untouched. Slices have
    /// length `n_dof`; `joints <= n_dof`. With `tau_g`, the same arithmetic as the full
    /// evaluation (the composites beyond the last joint read are still formed, but nothing is
    /// read from them); without, the inertias come from a pass specialised for them alone (the
    /// per-cycle evaluation of a dynamic map without a gravity term) and equal the full
    /// evaluation to rounding.
    pub fn leading_joint_inertia_and_gravity(
        &mut self,
        q: &[f64],
        joints: usize,
        inertia: &mut [f64],
        tau_g: Option<&mut [f64]>,
    ) -> Status {
        let n = self.dh.len();
        if !Self::lengths_ok(n, q, inertia, joints, &tau_g) {
            return Status::BAD_LENGTH;
        }
        // Inertias alone at angles the inline sine takes (finite ones, in practice all):
        // the specialised pass. Non-finite angles (NaN entries) and gravity: the general one.
        let in_range = || {
            q.iter().fold(true, |ok, v| {
                ok & (v.abs() <= crate::math::trig::FAST_RANGE_RAD)
            })
        };
        if tau_g.is_none() && in_range() {
            self.inertia_only_pass(q, &mut inertia[..joints]);
        } else {
            self.joint_space_pass(q, joints, Some(inertia), None, tau_g);
        }
        Status::OK
    }

    /// `q` and `inertia` of `n` entries, `tau_g` too if given, `joints <= n`.
    fn lengths_ok(
        n: usize,
        q: &[f64],
        inertia: &[f64],
        joints: usize,
        tau_g: &Option<&mut [f64]>,
    ) -> bool {
        let tau_ok = tau_g.as_ref().is_none_or(|t| t.len() == n);
        inertia.len() == n && q.len() == n && joints <= n && tau_ok
    }

    /// `J_k` for `k < out.len()` by the specialised pass of [`crate::robot::inertia_pass`] (every
    /// `|q_k| <= trig::FAST_RANGE_RAD`, checked by the caller; lengths too). Kept out of line:
    /// inlined next to the general pass, the general pass (with gravity) ran slower.
    #[inline(never)]
    fn inertia_only_pass(&mut self, q: &[f64], out: &mut [f64]) {
        let n = self.dh.len();
        let (top, start) = if out.len() <= self.fixed_from {
            (self.fixed_from - 1, &self.fixed_start)
        } else {
            (n - 1, &self.inertia_steps[n - 1].body)
        };
        let turns = &mut self.ws.turns;
        leading_joint_inertias(q, &self.inertia_steps, top, start, turns, out);
    }

    /// The leading `joints × joints` block of `M(q)` into the row-major `n × n` `mass`
    /// (other entries untouched) and, if `tau_g` is given, gravity torques of joints
    /// `0..joints` (others untouched), from one pass: what a map reading the first `joints`
    /// joints needs. `joints <= n_dof`.
    pub fn leading_mass_matrix_and_gravity(
        &mut self,
        q: &[f64],
        joints: usize,
        mass: &mut [f64],
        tau_g: Option<&mut [f64]>,
    ) -> Status {
        let n = self.dh.len();
        let tau_ok = tau_g.as_ref().is_none_or(|t| t.len() == n);
        if mass.len() != n * n || q.len() != n || joints > n || !tau_ok {
            return Status::BAD_LENGTH;
        }
        self.joint_space_pass(q, joints, None, Some(mass), tau_g);
        Status::OK
    }

    /// An upper bound of `J_i` over all configurations, kg m², for every joint.
    ///
    /// `J_i = Σ_{k≥i} (z·I_k z + m_k r_k²) ≤ Σ_{k≥i} (λ_max(I_k) + m_k ρ_k²)`, where `ρ_k`
    /// bounds the distance of body `k`'s centre of mass from the origin of joint `i` by the
    /// triangle inequality along the chain (`Σ √(a² + d²)` plus `|com|`).
    pub fn joint_inertia_upper_bound(&self) -> Vec<f64> {
        (0..self.dh.len())
            .map(|i| {
                self.bodies_beyond(i)
                    .map(|(b, rho)| {
                        let lambda_max = principal_moments(&b.inertia_kg_m2)[2];
                        lambda_max.max(0.0) + b.mass_kg * rho * rho
                    })
                    .sum()
            })
            .collect()
    }

    /// An upper bound of `|τ_g,i|` over all configurations, N m (`g Σ_{k≥i} m_k ρ_k`).
    pub fn gravity_torque_upper_bound(&self) -> Vec<f64> {
        (0..self.dh.len())
            .map(|i| {
                let moment: f64 = self.bodies_beyond(i).map(|(b, rho)| b.mass_kg * rho).sum();
                GRAVITY_M_S2 * moment
            })
            .collect()
    }

    /// Bodies `k >= i` with `ρ_k`, a bound on the distance of their centre of mass from the
    /// origin of joint `i` over all configurations (triangle inequality along the chain:
    /// the step lengths `|shift|` of the joints up to `k`, plus `|com_k|`).
    fn bodies_beyond(&self, i: usize) -> impl Iterator<Item = (&RigidBody, f64)> {
        let mut reach = 0.0;
        self.dh.iter().zip(&self.bodies).skip(i).map(move |(j, b)| {
            reach += dot3(&j.shift, &j.shift).sqrt();
            (b, reach + dot3(&b.com_m, &b.com_m).sqrt())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn single_link_inertia_is_m_r_squared() {
        // A 1 kg point 0.5 m from a vertical joint axis: J = m r^2 = 0.25 kg m^2, any angle.
        let joints = vec![DhJoint::new(0.0, 0.0, 0.0)];
        let links = vec![RigidBody::point(1.0, [0.5, 0.0, 0.0])];
        let mut robot = Robot::new(joints, links, RigidBody::NONE).expect("valid robot");
        let mut j = [0.0];
        assert!(robot.joint_inertia(&[0.3], &mut j).is_ok());
        assert!((j[0] - 0.25).abs() < 1e-15);
    }
}
