//! Rigid-body model of a serial revolute arm in standard DH form, with a payload.
//!
//! Frame `i` (1-based) is `T_i = T_{i−1} · Rz(q_i) Tz(d_i) Tx(a_i) Rx(α_i)`; frame 0 is the
//! base, frame `n` the flange. Joint `i` (0-based) turns about `z` of frame `i`; link `i`
//! (0-based) is fixed to frame `i + 1`. Gravity is [`GRAVITY_M_S2`] along `−z` of the base.
//! Everything is link side: no rotor inertia.
//!
//! All per-call methods are allocation-free: they work in a workspace preallocated by
//! [`Robot::new`] and write into caller buffers. A buffer of the wrong length returns
//! [`Status::BAD_LENGTH`] and leaves the output untouched; they never panic.

use crate::error::{Error, Status};

/// Standard gravity used for gravity torques, m/s².
pub const GRAVITY_M_S2: f64 = 9.81;

/// Standard DH parameters of one revolute joint (`θ = q`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DhJoint {
    pub d_m: f64,
    pub a_m: f64,
    pub alpha_rad: f64,
}

impl DhJoint {
    pub const fn new(d_m: f64, a_m: f64, alpha_rad: f64) -> Self {
        DhJoint {
            d_m,
            a_m,
            alpha_rad,
        }
    }
}

/// Mass properties of one rigid body.
///
/// `com_m` is the centre of mass in the body's frame; `inertia_kg_m2 = [ixx, iyy, izz, ixy,
/// ixz, iyz]` are inertia-tensor elements about the centre of mass in that frame's axes
/// (`ixy = −∫ x y dm`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidBody {
    pub mass_kg: f64,
    pub com_m: [f64; 3],
    pub inertia_kg_m2: [f64; 6],
}

impl RigidBody {
    /// No mass at all (for example: no payload).
    pub const NONE: RigidBody = RigidBody {
        mass_kg: 0.0,
        com_m: [0.0; 3],
        inertia_kg_m2: [0.0; 6],
    };

    /// A point mass at `com_m`.
    pub const fn point(mass_kg: f64, com_m: [f64; 3]) -> Self {
        RigidBody {
            mass_kg,
            com_m,
            inertia_kg_m2: [0.0; 6],
        }
    }

    /// Checks that the body is physical: finite values, `mass >= 0`, and an inertia tensor
    /// that is positive semi-definite and whose principal moments satisfy the triangle
    /// inequality (`I_a + I_b >= I_c`). A massless body must have zero inertia.
    pub fn validate(&self, what: &str) -> Result<(), Error> {
        let bad = |rule: &str| Err(Error::InvalidParameter(format!("{what}: {rule}")));
        let all_finite = self.mass_kg.is_finite()
            && self.com_m.iter().all(|v| v.is_finite())
            && self.inertia_kg_m2.iter().all(|v| v.is_finite());
        if !all_finite {
            return bad("mass, centre of mass and inertia must be finite");
        }
        if self.mass_kg < 0.0 {
            return bad(&format!("mass_kg = {} must be >= 0", self.mass_kg));
        }
        let [e0, e1, e2] = sym_eigenvalues(&sym_from_six(&self.inertia_kg_m2));
        let scale = e2.abs().max(1e-300);
        // Tolerance: the published tensors are rounded to 4-8 decimals; 1e-9 relative covers
        // round-off in the eigenvalue computation only, not data errors.
        let tol = 1e-9 * scale;
        if e0 < -tol {
            return bad(&format!(
                "inertia {:?} is not positive semi-definite (eigenvalues {e0:.3e}, {e1:.3e}, {e2:.3e})",
                self.inertia_kg_m2
            ));
        }
        if e0 + e1 < e2 - tol {
            return bad(&format!(
                "inertia {:?} violates the triangle inequality of principal moments \
                 ({e0:.3e} + {e1:.3e} < {e2:.3e})",
                self.inertia_kg_m2
            ));
        }
        if self.mass_kg == 0.0 && e2 > 0.0 {
            return bad("a massless body cannot have inertia");
        }
        Ok(())
    }

    /// The single body equivalent to `self` and `other` rigidly joined (same frame).
    pub fn combined(&self, other: &RigidBody) -> RigidBody {
        let m = self.mass_kg + other.mass_kg;
        if m <= 0.0 {
            return RigidBody::NONE;
        }
        let mut com = [0.0; 3];
        for (k, c) in com.iter_mut().enumerate() {
            *c = (self.mass_kg * self.com_m[k] + other.mass_kg * other.com_m[k]) / m;
        }
        let mut inertia = [0.0; 6];
        for body in [self, other] {
            let d = sub3(&body.com_m, &com);
            let dd = dot3(&d, &d);
            let shift = [
                body.mass_kg * (dd - d[0] * d[0]),
                body.mass_kg * (dd - d[1] * d[1]),
                body.mass_kg * (dd - d[2] * d[2]),
                -body.mass_kg * d[0] * d[1],
                -body.mass_kg * d[0] * d[2],
                -body.mass_kg * d[1] * d[2],
            ];
            for k in 0..6 {
                inertia[k] += body.inertia_kg_m2[k] + shift[k];
            }
        }
        RigidBody {
            mass_kg: m,
            com_m: com,
            inertia_kg_m2: inertia,
        }
    }
}

/// Per-call scratch, sized once for `n` joints.
#[derive(Debug, Clone)]
struct Workspace {
    /// World rotation (row-major 3×3) and origin of frames `0..=n`.
    rot: Vec<[f64; 9]>,
    pos: Vec<[f64; 3]>,
    /// Composite body `i` (links `i..n`): mass, first moment `Σ m c` and inertia about the
    /// world origin (row-major 3×3), all in world coordinates.
    comp_mass: Vec<f64>,
    comp_moment: Vec<[f64; 3]>,
    comp_inertia: Vec<[f64; 9]>,
    /// Joint `i` as a spatial motion about the world origin: `ω = z_i`, `v_O = p_i × z_i`.
    axis_w: Vec<[f64; 3]>,
    axis_v: Vec<[f64; 3]>,
    /// World position of each body's centre of mass.
    com: Vec<[f64; 3]>,
}

impl Workspace {
    fn new(n: usize) -> Self {
        Workspace {
            rot: vec![[0.0; 9]; n + 1],
            pos: vec![[0.0; 3]; n + 1],
            comp_mass: vec![0.0; n],
            comp_moment: vec![[0.0; 3]; n],
            comp_inertia: vec![[0.0; 9]; n],
            axis_w: vec![[0.0; 3]; n],
            axis_v: vec![[0.0; 3]; n],
            com: vec![[0.0; 3]; n],
        }
    }
}

/// A serial revolute arm with link masses and a payload on the flange.
#[derive(Debug, Clone)]
pub struct Robot {
    joints: Vec<DhJoint>,
    cos_alpha: Vec<f64>,
    sin_alpha: Vec<f64>,
    links: Vec<RigidBody>,
    payload: RigidBody,
    /// `links` with the payload merged into the last one: what the dynamics use.
    bodies: Vec<RigidBody>,
    ws: Workspace,
    /// The robot's name (for example `"ur5e"`), if it has one: dynamic maps are checked
    /// against it.
    name: Option<String>,
}

impl Robot {
    /// Validates and builds the model. `links[i]` is expressed in DH frame `i + 1`; the
    /// payload in the flange frame `n`.
    pub fn new(
        joints: Vec<DhJoint>,
        links: Vec<RigidBody>,
        payload: RigidBody,
    ) -> Result<Robot, Error> {
        let n = joints.len();
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
        for (i, j) in joints.iter().enumerate() {
            if !(j.d_m.is_finite() && j.a_m.is_finite() && j.alpha_rad.is_finite()) {
                return Err(Error::InvalidParameter(format!(
                    "joint {i}: DH parameters must be finite"
                )));
            }
        }
        for (i, link) in links.iter().enumerate() {
            link.validate(&format!("link {i}"))?;
        }
        payload.validate("payload")?;
        let mut robot = Robot {
            cos_alpha: joints.iter().map(|j| j.alpha_rad.cos()).collect(),
            sin_alpha: joints.iter().map(|j| j.alpha_rad.sin()).collect(),
            bodies: links.clone(),
            joints,
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
        let n = self.joints.len();
        self.bodies.copy_from_slice(&self.links);
        self.bodies[n - 1] = self.links[n - 1].combined(&self.payload);
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
        self.joints.len()
    }

    pub fn joints(&self) -> &[DhJoint] {
        &self.joints
    }

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
        self.forward_turned(q, true)
    }

    /// [`Self::forward`]; with `turn_base == false` joint 0 is taken at angle 0. Joint 0 turns
    /// the whole arm about the base `z` axis, the gravity axis, so joint-axis inertias and
    /// gravity torques do not depend on it (its sine and cosine are then not needed).
    fn forward_turned(&mut self, q: &[f64], turn_base: bool) -> bool {
        let n = self.joints.len();
        if q.len() != n {
            return false;
        }
        let ws = &mut self.ws;
        let mut r = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        let mut p = [0.0; 3];
        ws.rot[0] = r;
        ws.pos[0] = p;
        let frames = ws.rot[1..].iter_mut().zip(&mut ws.pos[1..]);
        let dh = self.joints.iter().zip(&self.cos_alpha).zip(&self.sin_alpha);
        for (k, ((qk, ((joint, &ca), &sa)), (rot, pos))) in q.iter().zip(dh).zip(frames).enumerate()
        {
            let (st, ct) = if k == 0 && !turn_base {
                (0.0, 1.0)
            } else {
                qk.sin_cos()
            };
            let mut u = [0.0; 3];
            let mut v = [0.0; 3];
            for row in 0..3 {
                let (x, y, z) = (r[3 * row], r[3 * row + 1], r[3 * row + 2]);
                u[row] = ct * x + st * y;
                v[row] = ct * y - st * x;
                p[row] += joint.a_m * u[row] + joint.d_m * z;
                r[3 * row] = u[row];
                r[3 * row + 1] = ca * v[row] + sa * z;
                r[3 * row + 2] = ca * z - sa * v[row];
            }
            *rot = r;
            *pos = p;
        }
        true
    }

    /// World centres of mass of every body (needs [`Self::forward`] first).
    fn centres_of_mass(&mut self) {
        let ws = &mut self.ws;
        for (((c, body), r), p) in ws
            .com
            .iter_mut()
            .zip(&self.bodies)
            .zip(&ws.rot[1..])
            .zip(&ws.pos[1..])
        {
            *c = add3(p, &mat_vec(r, &body.com_m));
        }
    }

    /// Joint axes and composite-body inertias (needs [`Self::forward`] first).
    fn composites(&mut self) {
        let n = self.joints.len();
        let ws = &mut self.ws;
        let mut mass = 0.0;
        let mut moment = [0.0; 3];
        let mut inertia = [0.0; 9];
        for i in (0..n).rev() {
            let body = &self.bodies[i];
            let r = &ws.rot[i + 1];
            let c = add3(&ws.pos[i + 1], &mat_vec(r, &body.com_m));
            let ic = rotate_sym(r, &sym_from_six(&body.inertia_kg_m2));
            let m = body.mass_kg;
            let cc = dot3(&c, &c);
            mass += m;
            for k in 0..3 {
                moment[k] += m * c[k];
            }
            for a in 0..3 {
                for b in 0..3 {
                    let delta = if a == b { cc } else { 0.0 };
                    inertia[3 * a + b] += ic[3 * a + b] + m * (delta - c[a] * c[b]);
                }
            }
            ws.comp_mass[i] = mass;
            ws.comp_moment[i] = moment;
            ws.comp_inertia[i] = inertia;
            let rj = &ws.rot[i];
            let z = [rj[2], rj[5], rj[8]];
            ws.axis_w[i] = z;
            ws.axis_v[i] = cross3(&ws.pos[i], &z);
        }
    }

    /// `S_row · (I^C_col S_col)`: one entry of the mass matrix (`row <= col`).
    #[inline]
    fn crba_entry(&self, row: usize, col: usize) -> f64 {
        let ws = &self.ws;
        let (w, v) = (&ws.axis_w[col], &ws.axis_v[col]);
        let (m, h, io) = (
            ws.comp_mass[col],
            &ws.comp_moment[col],
            &ws.comp_inertia[col],
        );
        // Spatial momentum of composite `col` moving with joint `col` at unit rate.
        let angular = add3(&mat_vec(io, w), &cross3(h, v));
        let hw = cross3(h, w);
        let linear = [m * v[0] - hw[0], m * v[1] - hw[1], m * v[2] - hw[2]];
        dot3(&ws.axis_w[row], &angular) + dot3(&ws.axis_v[row], &linear)
    }

    /// Homogeneous transform of the flange in the base frame, row-major 4×4.
    pub fn flange_pose(&mut self, q: &[f64], out: &mut [f64; 16]) -> Status {
        if !self.forward(q) {
            return Status::BAD_LENGTH;
        }
        let n = self.joints.len();
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
        let n = self.joints.len();
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
        let n = self.joints.len();
        if out.len() != n * n || !self.forward(q) {
            return Status::BAD_LENGTH;
        }
        self.composites();
        for col in 0..n {
            for row in 0..=col {
                let v = self.crba_entry(row, col);
                out[row * n + col] = v;
                out[col * n + row] = v;
            }
        }
        Status::OK
    }

    /// Diagonal of `M(q)`: `J_i = M[i, i]`, the inertia about joint `i` of everything
    /// beyond it, in kg m².
    pub fn joint_inertia(&mut self, q: &[f64], out: &mut [f64]) -> Status {
        self.joint_inertia_and_gravity(q, out, None)
    }

    /// Gravity torques `τ_g(q) = ∂V/∂q` (the torques that hold the arm still), N m.
    pub fn gravity_torque(&mut self, q: &[f64], out: &mut [f64]) -> Status {
        let n = self.joints.len();
        if out.len() != n || !self.forward(q) {
            return Status::BAD_LENGTH;
        }
        self.composites();
        self.fill_gravity(out);
        Status::OK
    }

    /// Joint inertias and, if `tau_g` is given, gravity torques from one kinematics pass
    /// (the composite rigid body algorithm: the inertias are exactly the diagonal of
    /// [`Self::mass_matrix`]).
    pub fn joint_inertia_and_gravity(
        &mut self,
        q: &[f64],
        inertia: &mut [f64],
        tau_g: Option<&mut [f64]>,
    ) -> Status {
        let n = self.joints.len();
        let tau_ok = tau_g.as_ref().is_none_or(|t| t.len() == n);
        if inertia.len() != n || !tau_ok || !self.forward(q) {
            return Status::BAD_LENGTH;
        }
        self.composites();
        for (i, j) in inertia.iter_mut().enumerate() {
            *j = self.crba_entry(i, i);
        }
        if let Some(t) = tau_g {
            self.fill_gravity(t);
        }
        Status::OK
    }

    /// [`Self::joint_inertia_and_gravity`] for joints `0..joints` only (for example the
    /// joints a dynamic map reads), at a fraction of the cost: entries from `joints` on are
    /// left untouched. Slices have length `n_dof`; `joints <= n_dof`. Equal to the full
    /// evaluation to rounding (different arithmetic).
    ///
    /// `J_i = Σ_{k≥i} (a_kᵀ I_k a_k + m_k |a_i × (c_k − p_i)|²)`: the rotational inertia of
    /// body `k` about joint `i`'s axis (`a_k`: that axis in body `k`'s frame) plus the
    /// parallel-axis term of its centre of mass `c_k`. The diagonal of the composite rigid
    /// body algorithm, without forming the composite inertias.
    pub fn leading_joint_inertia_and_gravity(
        &mut self,
        q: &[f64],
        joints: usize,
        inertia: &mut [f64],
        tau_g: Option<&mut [f64]>,
    ) -> Status {
        let n = self.joints.len();
        let tau_ok = tau_g.as_ref().is_none_or(|t| t.len() == n);
        if inertia.len() != n || joints > n || !tau_ok || !self.forward_turned(q, false) {
            return Status::BAD_LENGTH;
        }
        self.centres_of_mass();
        let ws = &self.ws;
        let bodies = self.bodies.iter().zip(&ws.com).zip(&ws.rot[1..]);
        for (i, j) in inertia.iter_mut().enumerate().take(joints) {
            let r = &ws.rot[i];
            let axis = [r[2], r[5], r[8]];
            let origin = &ws.pos[i];
            let mut sum = 0.0;
            for ((body, c), rk) in bodies.clone().skip(i) {
                // The axis in body k's frame: R_kᵀ a (for joint 0, a = e_z: R_k's last row).
                let u = if i == 0 {
                    [rk[6], rk[7], rk[8]]
                } else {
                    [
                        rk[0] * axis[0] + rk[3] * axis[1] + rk[6] * axis[2],
                        rk[1] * axis[0] + rk[4] * axis[1] + rk[7] * axis[2],
                        rk[2] * axis[0] + rk[5] * axis[1] + rk[8] * axis[2],
                    ]
                };
                let [xx, yy, zz, xy, xz, yz] = body.inertia_kg_m2;
                let rotational = xx * u[0] * u[0]
                    + yy * u[1] * u[1]
                    + zz * u[2] * u[2]
                    + 2.0 * (xy * u[0] * u[1] + xz * u[0] * u[2] + yz * u[1] * u[2]);
                let d = sub3(c, origin);
                let along = dot3(&d, &axis);
                sum += rotational + body.mass_kg * (dot3(&d, &d) - along * along);
            }
            *j = sum;
        }
        if let Some(t) = tau_g {
            for (i, ti) in t.iter_mut().enumerate().take(joints) {
                let r = &ws.rot[i];
                let origin = &ws.pos[i];
                // ∂V/∂q_i = g · e_z · (z_i × Σ_{k≥i} m_k (c_k − p_i)).
                let mut arm = [0.0; 3];
                for (body, c) in self.bodies.iter().zip(&ws.com).skip(i) {
                    for ((a, ck), pk) in arm.iter_mut().zip(c).zip(origin) {
                        *a += body.mass_kg * (ck - pk);
                    }
                }
                *ti = GRAVITY_M_S2 * (r[2] * arm[1] - r[5] * arm[0]);
            }
        }
        Status::OK
    }

    fn fill_gravity(&self, out: &mut [f64]) {
        let ws = &self.ws;
        for (i, t) in out.iter_mut().enumerate() {
            // ∂V/∂q_i = g · e_z · (z_i × (Σ m c − M p_i)) over the composite beyond joint i.
            let m = ws.comp_mass[i];
            let p = &ws.pos[i];
            let h = &ws.comp_moment[i];
            let arm = [h[0] - m * p[0], h[1] - m * p[1], h[2] - m * p[2]];
            *t = GRAVITY_M_S2 * cross3(&ws.axis_w[i], &arm)[2];
        }
    }

    /// An upper bound of `J_i` over all configurations, kg m², for every joint.
    ///
    /// `J_i = Σ_{k≥i} (z·I_k z + m_k r_k²) ≤ Σ_{k≥i} (λ_max(I_k) + m_k ρ_k²)`, where `ρ_k`
    /// bounds the distance of body `k`'s centre of mass from the origin of joint `i` by the
    /// triangle inequality along the chain (`Σ √(a² + d²)` plus `|com|`).
    pub fn joint_inertia_upper_bound(&self) -> Vec<f64> {
        (0..self.joints.len())
            .map(|i| {
                self.bodies_beyond(i)
                    .map(|(b, rho)| {
                        let lambda_max = sym_eigenvalues(&sym_from_six(&b.inertia_kg_m2))[2];
                        lambda_max.max(0.0) + b.mass_kg * rho * rho
                    })
                    .sum()
            })
            .collect()
    }

    /// An upper bound of `|τ_g,i|` over all configurations, N m (`g Σ_{k≥i} m_k ρ_k`).
    pub fn gravity_torque_upper_bound(&self) -> Vec<f64> {
        (0..self.joints.len())
            .map(|i| {
                let moment: f64 = self.bodies_beyond(i).map(|(b, rho)| b.mass_kg * rho).sum();
                GRAVITY_M_S2 * moment
            })
            .collect()
    }

    /// Bodies `k >= i` with `ρ_k`, a bound on the distance of their centre of mass from the
    /// origin of joint `i` over all configurations (triangle inequality along the chain:
    /// `Σ √(a² + d²)` of the joints up to `k`, plus `|com_k|`).
    fn bodies_beyond(&self, i: usize) -> impl Iterator<Item = (&RigidBody, f64)> {
        let mut reach = 0.0;
        self.joints
            .iter()
            .zip(&self.bodies)
            .skip(i)
            .map(move |(j, b)| {
                reach += j.a_m.hypot(j.d_m);
                (b, reach + dot3(&b.com_m, &b.com_m).sqrt())
            })
    }
}

// ---- small fixed-size linear algebra (row-major 3×3) ----

#[inline]
fn dot3(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
fn add3(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline]
fn sub3(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
fn cross3(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline]
fn mat_vec(m: &[f64; 9], v: &[f64; 3]) -> [f64; 3] {
    [
        m[0] * v[0] + m[1] * v[1] + m[2] * v[2],
        m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
        m[6] * v[0] + m[7] * v[1] + m[8] * v[2],
    ]
}

#[inline]
fn mat_mul(a: &[f64; 9], b: &[f64; 9]) -> [f64; 9] {
    let mut out = [0.0; 9];
    for r in 0..3 {
        for c in 0..3 {
            out[3 * r + c] = a[3 * r] * b[c] + a[3 * r + 1] * b[3 + c] + a[3 * r + 2] * b[6 + c];
        }
    }
    out
}

/// `R S Rᵀ` for a symmetric `S`.
#[inline]
fn rotate_sym(r: &[f64; 9], s: &[f64; 9]) -> [f64; 9] {
    let rs = mat_mul(r, s);
    let mut out = [0.0; 9];
    for a in 0..3 {
        for b in 0..3 {
            out[3 * a + b] =
                rs[3 * a] * r[3 * b] + rs[3 * a + 1] * r[3 * b + 1] + rs[3 * a + 2] * r[3 * b + 2];
        }
    }
    out
}

/// Row-major symmetric 3×3 from `[xx, yy, zz, xy, xz, yz]`.
#[inline]
fn sym_from_six(s: &[f64; 6]) -> [f64; 9] {
    [s[0], s[3], s[4], s[3], s[1], s[5], s[4], s[5], s[2]]
}

/// Eigenvalues of a symmetric 3×3 matrix in ascending order (closed form).
fn sym_eigenvalues(m: &[f64; 9]) -> [f64; 3] {
    let off = m[1] * m[1] + m[2] * m[2] + m[5] * m[5];
    if off == 0.0 {
        let mut d = [m[0], m[4], m[8]];
        d.sort_by(f64::total_cmp);
        return d;
    }
    let q = (m[0] + m[4] + m[8]) / 3.0;
    let p2 = (m[0] - q).powi(2) + (m[4] - q).powi(2) + (m[8] - q).powi(2) + 2.0 * off;
    let p = (p2 / 6.0).sqrt();
    let b = [
        (m[0] - q) / p,
        m[1] / p,
        m[2] / p,
        m[3] / p,
        (m[4] - q) / p,
        m[5] / p,
        m[6] / p,
        m[7] / p,
        (m[8] - q) / p,
    ];
    let det = b[0] * (b[4] * b[8] - b[5] * b[7]) - b[1] * (b[3] * b[8] - b[5] * b[6])
        + b[2] * (b[3] * b[7] - b[4] * b[6]);
    let phi = (det / 2.0).clamp(-1.0, 1.0).acos() / 3.0;
    let largest = q + 2.0 * p * phi.cos();
    let smallest = q + 2.0 * p * (phi + 2.0 * core::f64::consts::PI / 3.0).cos();
    [smallest, 3.0 * q - largest - smallest, largest]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eigenvalues_of_a_known_matrix() {
        // [[2,1,0],[1,2,0],[0,0,5]] has eigenvalues 1, 3, 5.
        let e = sym_eigenvalues(&[2.0, 1.0, 0.0, 1.0, 2.0, 0.0, 0.0, 0.0, 5.0]);
        for (got, want) in e.iter().zip([1.0, 3.0, 5.0]) {
            assert!((got - want).abs() < 1e-12, "{e:?}");
        }
    }

    #[test]
    fn combined_point_masses_match_parallel_axis() {
        // Two 1 kg points at x = ±1: centre at 0, Iyy = Izz = 2, Ixx = 0.
        let a = RigidBody::point(1.0, [1.0, 0.0, 0.0]);
        let b = RigidBody::point(1.0, [-1.0, 0.0, 0.0]);
        let c = a.combined(&b);
        assert_eq!(c.mass_kg, 2.0);
        assert_eq!(c.com_m, [0.0; 3]);
        assert_eq!(c.inertia_kg_m2, [0.0, 2.0, 2.0, 0.0, 0.0, 0.0]);
    }

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
