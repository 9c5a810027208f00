//! Joint placement as URDF gives it (an origin, then a turn about an axis) and the rigid
//! transforms that turn it into the chain the robot model runs on (every joint about `z` of
//! its own frame). Setup-time only.

use crate::error::Error;
use crate::math::mat3::{add3, apply3, mul3, transpose3};
use crate::robot::rigid_body::RigidBody;

/// A fixed frame as URDF writes it: translation `xyz_m`, then the rotation by fixed-axis
/// roll, pitch and yaw, `R = Rz(yaw) Ry(pitch) Rx(roll)` (`rpy_rad = [roll, pitch, yaw]`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Origin {
    pub xyz_m: [f64; 3],
    pub rpy_rad: [f64; 3],
}

impl Origin {
    /// No translation, no rotation.
    pub const IDENTITY: Origin = Origin {
        xyz_m: [0.0; 3],
        rpy_rad: [0.0; 3],
    };

    pub const fn new(xyz_m: [f64; 3], rpy_rad: [f64; 3]) -> Origin {
        Origin { xyz_m, rpy_rad }
    }

    fn is_finite(&self) -> bool {
        self.xyz_m
            .iter()
            .chain(&self.rpy_rad)
            .all(|v| v.is_finite())
    }

    /// The frame as a rigid transform (points in the frame ↦ points in its parent).
    pub(crate) fn pose(&self) -> Pose {
        let [roll, pitch, yaw] = self.rpy_rad;
        let (sr, cr) = roll.sin_cos();
        let (sp, cp) = pitch.sin_cos();
        let (sy, cy) = yaw.sin_cos();
        Pose {
            rot: [
                cy * cp,
                cy * sp * sr - sy * cr,
                cy * sp * cr + sy * sr,
                sy * cp,
                sy * sp * sr + cy * cr,
                sy * sp * cr - cy * sr,
                -sp,
                cp * sr,
                cp * cr,
            ],
            pos: self.xyz_m,
        }
    }
}

/// A revolute joint placed as URDF places it: `origin` in the frame of the link before it,
/// then the turn `q` (right-handed, rad) about `axis` of that origin frame (normalised at
/// setup). The link after the joint is fixed to the turned frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointPlacement {
    pub origin: Origin,
    pub axis: [f64; 3],
}

impl JointPlacement {
    pub const fn new(origin: Origin, axis: [f64; 3]) -> JointPlacement {
        JointPlacement { origin, axis }
    }
}

/// A rigid transform: `r ↦ pos + rot r` (`rot` row-major 3×3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Pose {
    pub(crate) rot: [f64; 9],
    pub(crate) pos: [f64; 3],
}

impl Pose {
    pub(crate) const IDENTITY: Pose = Pose {
        rot: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        pos: [0.0; 3],
    };

    /// `self ∘ other` (first `other`, then `self`).
    pub(crate) fn then(&self, other: &Pose) -> Pose {
        Pose {
            rot: mul3(&self.rot, &other.rot),
            pos: add3(&self.pos, &apply3(&self.rot, &other.pos)),
        }
    }

    pub(crate) fn inverse(&self) -> Pose {
        let rt = transpose3(&self.rot);
        let p = apply3(&rt, &self.pos);
        Pose {
            rot: rt,
            pos: [-p[0], -p[1], -p[2]],
        }
    }

    /// A pure rotation.
    fn rotation(rot: [f64; 9]) -> Pose {
        Pose { rot, pos: [0.0; 3] }
    }

    /// `body` (centre of mass and inertia in this transform's source frame) in its target
    /// frame.
    pub(crate) fn move_body(&self, body: &RigidBody) -> RigidBody {
        let r = &self.rot;
        let [ixx, iyy, izz, ixy, ixz, iyz] = body.inertia_kg_m2;
        let i = [ixx, ixy, ixz, ixy, iyy, iyz, ixz, iyz, izz];
        let turned = mul3(&mul3(r, &i), &transpose3(r));
        RigidBody {
            mass_kg: body.mass_kg,
            com_m: add3(&self.pos, &apply3(r, &body.com_m)),
            inertia_kg_m2: [
                turned[0], turned[4], turned[8], turned[1], turned[2], turned[5],
            ],
        }
    }
}

/// A rotation that takes `e_z` to the unit vector `a`: exact signed permutations for the
/// coordinate axes (so chains of URDF joints about `±x`, `±y`, `±z` keep exact zeros), else
/// the shortest turn.
fn z_to(a: &[f64; 3]) -> [f64; 9] {
    match *a {
        [0.0, 0.0, 1.0] => Pose::IDENTITY.rot,
        [0.0, 0.0, -1.0] => [1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0],
        // Columns (images of e_x, e_y, e_z): (0, 0, −s), (0, 1, 0), (s, 0, 0): Ry(s π/2).
        [s, 0.0, 0.0] if s.abs() == 1.0 => [0.0, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, 0.0],
        // Rx(−s π/2): e_z ↦ (0, s, 0).
        [0.0, s, 0.0] if s.abs() == 1.0 => [1.0, 0.0, 0.0, 0.0, 0.0, s, 0.0, -s, 0.0],
        [x, y, z] => {
            // Rodrigues about e_z × a = (−y, x, 0) by the angle whose cosine is z.
            if z <= -1.0 + 1e-12 {
                return [1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0];
            }
            let k = 1.0 / (1.0 + z);
            [
                z + k * y * y,
                -k * x * y,
                x,
                -k * x * y,
                z + k * x * x,
                y,
                -x,
                -y,
                z,
            ]
        }
    }
}

/// The chain of a URDF-placed arm in the model's form: the pose of joint frame 0 in the base,
/// per joint `k` the fixed step from joint frame `k` after its turn to joint frame `k + 1`
/// (the flange frame for the last joint), and every link in the frame `k + 1` after it.
pub(crate) struct JointFrames {
    pub(crate) base: Pose,
    pub(crate) steps: Vec<Pose>,
    pub(crate) bodies: Vec<RigidBody>,
}

/// Joint frame `k` is the origin frame of joint `k` turned so that its `z` is the joint axis
/// (`A_k e_z = axis_k`); the link after joint `k` is fixed to joint frame `k` turned by `q_k`
/// and turned back by `A_kᵀ` (`O_k A_k Rz(q_k) A_kᵀ` is URDF's origin, then the turn about the
/// axis). So the step is `A_kᵀ O_{k+1} A_{k+1}` (`A_kᵀ F` for the flange origin `F`) and link
/// `k` moves into frame `k + 1` by `step_k⁻¹ A_kᵀ`.
pub(crate) fn joint_frames(
    joints: &[JointPlacement],
    flange: &Origin,
    links: &[RigidBody],
) -> Result<JointFrames, Error> {
    let bad = |msg: String| Err(Error::InvalidParameter(msg));
    let mut turns = Vec::with_capacity(joints.len());
    for (i, j) in joints.iter().enumerate() {
        let norm = (j.axis[0] * j.axis[0] + j.axis[1] * j.axis[1] + j.axis[2] * j.axis[2]).sqrt();
        if !(j.origin.is_finite() && norm.is_finite() && norm > 0.0) {
            return bad(format!(
                "joint {i}: origin and axis must be finite and the axis non-zero"
            ));
        }
        let axis = if norm == 1.0 {
            j.axis
        } else {
            [j.axis[0] / norm, j.axis[1] / norm, j.axis[2] / norm]
        };
        turns.push(Pose::rotation(z_to(&axis)));
    }
    if !flange.is_finite() {
        return bad("flange origin must be finite".into());
    }
    let base = joints[0].origin.pose().then(&turns[0]);
    let n = joints.len();
    let mut steps = Vec::with_capacity(n);
    let mut bodies = Vec::with_capacity(n);
    for k in 0..n {
        let next = if k + 1 < n {
            joints[k + 1].origin.pose().then(&turns[k + 1])
        } else {
            flange.pose()
        };
        let step = turns[k].inverse().then(&next);
        bodies.push(
            step.inverse()
                .then(&turns[k].inverse())
                .move_body(&links[k]),
        );
        steps.push(step);
    }
    Ok(JointFrames {
        base,
        steps,
        bodies,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn z_to_takes_z_to_the_axis_with_a_proper_rotation() {
        for a in [
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.6, 0.0, 0.8],
            [0.48, -0.6, -0.64],
        ] {
            let r = z_to(&a);
            let z = apply3(&r, &[0.0, 0.0, 1.0]);
            let rrt = mul3(&r, &transpose3(&r));
            let det = r[0] * (r[4] * r[8] - r[5] * r[7]) - r[1] * (r[3] * r[8] - r[5] * r[6])
                + r[2] * (r[3] * r[7] - r[4] * r[6]);
            for k in 0..3 {
                assert!((z[k] - a[k]).abs() < 1e-15, "{a:?}: {z:?}");
            }
            for (k, v) in rrt.iter().enumerate() {
                let want = if k % 4 == 0 { 1.0 } else { 0.0 };
                assert!((v - want).abs() < 1e-15, "{a:?}: R Rᵀ = {rrt:?}");
            }
            assert!((det - 1.0).abs() < 1e-15, "{a:?}: det {det}");
        }
    }

    #[test]
    fn rpy_is_yaw_pitch_roll_about_fixed_axes() {
        // Roll π/2 alone takes y to z; yaw π/2 alone takes x to y.
        let roll = Origin::new([0.0; 3], [std::f64::consts::FRAC_PI_2, 0.0, 0.0]).pose();
        let y = apply3(&roll.rot, &[0.0, 1.0, 0.0]);
        assert!((y[2] - 1.0).abs() < 1e-15 && y[1].abs() < 1e-15, "{y:?}");
        let yaw = Origin::new([0.0; 3], [0.0, 0.0, std::f64::consts::FRAC_PI_2]).pose();
        let x = apply3(&yaw.rot, &[1.0, 0.0, 0.0]);
        assert!((x[1] - 1.0).abs() < 1e-15 && x[0].abs() < 1e-15, "{x:?}");
    }
}
