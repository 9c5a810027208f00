//! Robots for the integration tests, read from the project's one robot-data file.

#![allow(dead_code)]

use tvist_core::{DhJoint, FlexJoint, JointPlacement, LoadLaw, Origin, RigidBody, Robot};

/// Joints and links of robot `name` from the project's robot-data file.
pub fn ur_chain(name: &str) -> (Vec<DhJoint>, Vec<RigidBody>) {
    tvist_core::files::robot_data::robot_chain(
        tvist_core::files::robot_data::UR_E_SERIES_JSON,
        name,
    )
    .expect("robot data")
}

/// UR robot `name` with a point payload of `payload_kg` 5 cm beyond the flange (flange z).
pub fn ur_robot(name: &str, payload_kg: f64) -> Robot {
    let (joints, links) = ur_chain(name);
    Robot::new(
        joints,
        links,
        RigidBody::point(payload_kg, [0.0, 0.0, 0.05]),
    )
    .expect("valid robot")
}

/// Joint `j` flexible with constant stiffness `k` (N m/rad) and damping `c` (N m s/rad).
pub fn flex_joint(j: usize, k: f64, c: f64) -> FlexJoint {
    FlexJoint {
        joint: j,
        stiffness_nm_per_rad: LoadLaw::constant(k),
        damping_nms_per_rad: LoadLaw::constant(c),
        damping_load_joint: j,
    }
}

/// Deterministic pseudo-random numbers in [0, 1) (xorshift64*), for reproducible poses.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_f64(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A pose with every angle uniform in [-pi, pi).
    pub fn pose(&mut self, n: usize) -> Vec<f64> {
        (0..n)
            .map(|_| std::f64::consts::PI * (2.0 * self.next_f64() - 1.0))
            .collect()
    }
}

type Mat3 = [[f64; 3]; 3];

fn mat_mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

fn mat_t(a: &Mat3) -> Mat3 {
    let mut t = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            t[i][j] = a[j][i];
        }
    }
    t
}

fn mat_vec(a: &Mat3, v: &[f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| (0..3).map(|k| a[i][k] * v[k]).sum())
}

/// `Rz(y) Ry(p) Rx(r)`.
fn from_rpy([r, p, y]: [f64; 3]) -> Mat3 {
    let (sr, cr) = r.sin_cos();
    let (sp, cp) = p.sin_cos();
    let (sy, cy) = y.sin_cos();
    let rx = [[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]];
    let ry = [[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]];
    let rz = [[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]];
    mat_mul(&rz, &mat_mul(&ry, &rx))
}

/// Roll, pitch, yaw of a rotation (`R = Rz(y) Ry(p) Rx(r)`, `|p| < π/2`).
fn to_rpy(m: &Mat3) -> [f64; 3] {
    [
        m[2][1].atan2(m[2][2]),
        (-m[2][0]).clamp(-1.0, 1.0).asin(),
        m[1][0].atan2(m[0][0]),
    ]
}

fn turn_body(w: &Mat3, b: &RigidBody) -> RigidBody {
    let [xx, yy, zz, xy, xz, yz] = b.inertia_kg_m2;
    let i = mat_mul(
        &mat_mul(w, &[[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]),
        &mat_t(w),
    );
    RigidBody {
        mass_kg: b.mass_kg,
        com_m: mat_vec(w, &b.com_m),
        inertia_kg_m2: [i[0][0], i[1][1], i[2][2], i[0][1], i[0][2], i[1][2]],
    }
}

/// UR robot `name` (payload as [`ur_robot`]) with its joints placed as a URDF places them:
/// link `k`'s frame is DH frame `k` turned by `q_k`, then by `turns[k]` (roll, pitch, yaw; a
/// frame the URDF's author is free to choose: the axis and the next origin follow it). With
/// no turns every step is a DH step; with turns none is.
pub fn ur_robot_placed(name: &str, payload_kg: f64, turns: &[[f64; 3]]) -> Robot {
    let (dh, links) = ur_chain(name);
    let n = dh.len();
    let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let w: Vec<Mat3> = (0..n)
        .map(|k| turns.get(k).map_or(identity, |t| from_rpy(*t)))
        .collect();
    // DH step k (frame k turned → frame k + 1): (a, 0, d) + Rx(α) r.
    let step = |k: usize| -> (Mat3, [f64; 3]) {
        (
            from_rpy([dh[k].alpha_rad, 0.0, 0.0]),
            [dh[k].a_m, 0.0, dh[k].d_m],
        )
    };
    let mut joints = Vec::with_capacity(n);
    let mut placed_links = Vec::with_capacity(n);
    for k in 0..n {
        // Joint k's origin in link k − 1's frame: W_{k−1}ᵀ S_{k−1} W_k (base: W_k).
        let (rot, xyz) = if k == 0 {
            (w[0], [0.0; 3])
        } else {
            let (r, p) = step(k - 1);
            let wt = mat_t(&w[k - 1]);
            (mat_mul(&wt, &mat_mul(&r, &w[k])), mat_vec(&wt, &p))
        };
        let axis = mat_vec(&mat_t(&w[k]), &[0.0, 0.0, 1.0]);
        joints.push(JointPlacement::new(Origin::new(xyz, to_rpy(&rot)), axis));
        // Link k: in frame k + 1 = (frame k turned) S_k; in link k's frame W_kᵀ S_k.
        let (r, p) = step(k);
        let in_turned = turn_body(&r, &links[k]);
        let in_turned = RigidBody {
            com_m: [0, 1, 2].map(|i| in_turned.com_m[i] + p[i]),
            ..in_turned
        };
        placed_links.push(turn_body(&mat_t(&w[k]), &in_turned));
    }
    let (r, p) = step(n - 1);
    let wt = mat_t(&w[n - 1]);
    let flange = Origin::new(mat_vec(&wt, &p), to_rpy(&mat_mul(&wt, &r)));
    Robot::from_placements(
        joints,
        flange,
        placed_links,
        RigidBody::point(payload_kg, [0.0, 0.0, 0.05]),
    )
    .expect("valid robot")
}

/// Link frame turns that make every step of a UR chain a general one (none about `z` alone,
/// pitches within ±π/2 so roll, pitch and yaw are unique).
pub const GENERAL_TURNS: [[f64; 3]; 6] = [
    [0.3, -0.2, 0.1],
    [-0.7, 0.4, 1.1],
    [1.2, 0.9, -2.0],
    [0.05, -1.1, 0.6],
    [2.5, 0.3, -0.4],
    [-1.3, 0.7, 2.9],
];

/// [`ur_robot_placed`] with the first joint's origin tilted by 0.2 rad about the base's `x`:
/// joint 0 no longer turns about the gravity axis.
pub fn ur_robot_tilted(name: &str, payload_kg: f64) -> Robot {
    let placed = ur_robot_placed(name, payload_kg, &GENERAL_TURNS);
    let (mut joints, flange) = match placed.chain().clone() {
        tvist_core::Chain::Urdf { joints, flange } => (joints, flange),
        tvist_core::Chain::Dh(_) => unreachable!("ur_robot_placed places by URDF joints"),
    };
    let rpy = joints[0].origin.rpy_rad;
    joints[0].origin.rpy_rad = [rpy[0] + 0.2, rpy[1], rpy[2]];
    Robot::from_placements(joints, flange, placed.links().to_vec(), *placed.payload())
        .expect("valid robot")
}
