//! Bending links as lumped hinges: a link cut into rigid segments joined by hinge pairs about
//! the two axes perpendicular to it, and the arm with such hinges inserted (the chain a modal
//! map with link hinges evaluates; setup-time only).
//!
//! **Splitting a link** ([`split_link`]). The link runs from its joint (the origin of its
//! frame) to the next joint at `offset`; its beam line is parallel to `offset`, shifted
//! sideways through the link's centre of mass. Hinges at fractions `0 < f_1 < … < 1` of the
//! length cut it into segments; segment `s` gets the mass fraction `w_s` of its length, the
//! centre of mass `c + (x_s − x̄) e` (`x_s` the segment's middle along the unit axis `e`,
//! `x̄ = Σ w_s x_s`, so the mean stays at `c`) and the inertia about its centre of mass
//! `w_s (I_c − I_spread)`, with `I_spread` the parallel-axis inertia of the segment masses
//! about `c`. With straight hinges the segments together are exactly the rigid link, so the
//! arm's mass matrix is unchanged. If the link's inertia is too small for that spread
//! (`I_c − I_spread` not a physical inertia) the spread is halved until it is. The twin's
//! bending links (`tvist.sim.beams`) are cut by this same function.
//!
//! **Hinge axes**: the first parallel to the link's own joint axis (`z` of its frame) made
//! perpendicular to the link (any perpendicular if the link runs along that axis), the
//! second perpendicular to both.
//!
//! **The hinged arm** ([`Robot::with_link_hinges`]): the robot's chain in URDF form with, per
//! hinged link, the link's first segment on its joint, then two hinge joints at the hinge
//! point (a massless body between them) and the second segment on the second hinge. At zero
//! hinge angles every body is where it was: the mass matrix of the hinged arm, restricted to
//! the real joints, is the robot's, and its hinge rows and columns are the inertia the
//! bending moves.

use crate::error::Error;
use crate::robot::chain::Chain;
use crate::robot::model::Robot;
use crate::robot::placement::{JointPlacement, Origin};
use crate::robot::rigid_body::RigidBody;

/// Shortest link (joint-to-joint distance, m) that can be cut into segments.
pub const MIN_LINK_LENGTH_M: f64 = 0.05;

/// One rigid segment of a split link, in the link's frame (m, kg, kg m²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkSegment {
    /// Where the segment is hinged to the previous one (`None` for the first segment).
    pub hinge_m: Option<[f64; 3]>,
    /// Mass, centre of mass and inertia about it.
    pub body: RigidBody,
}

/// The segments of a link from its joint (origin) to the next joint at `offset_m`, cut by
/// hinges at `hinge_fractions` of its length (strictly increasing, in `(0, 1)`), and the two
/// unit bending axes shared by its hinges (module docs). The composite of the segments is
/// `body` to rounding.
pub fn split_link(
    offset_m: [f64; 3],
    body: &RigidBody,
    hinge_fractions: &[f64],
) -> Result<(Vec<LinkSegment>, [[f64; 3]; 2]), Error> {
    let length = norm(&offset_m);
    if !(length >= MIN_LINK_LENGTH_M && length.is_finite()) {
        return Err(Error::InvalidParameter(format!(
            "a link of length {length:.3} m is too short to bend (needs >= {MIN_LINK_LENGTH_M} m)"
        )));
    }
    let increasing = hinge_fractions.windows(2).all(|w| w[0] < w[1]);
    let inside = hinge_fractions.iter().all(|f| *f > 0.0 && *f < 1.0);
    if hinge_fractions.is_empty() || !increasing || !inside {
        return Err(Error::InvalidParameter(format!(
            "hinge positions along a link must be increasing fractions in (0, 1), got \
             {hinge_fractions:?}"
        )));
    }
    let axis = scale(&offset_m, 1.0 / length);
    let mut first = sub(&[0.0, 0.0, 1.0], &scale(&axis, axis[2]));
    if norm(&first) < 0.1 {
        first = sub(&[1.0, 0.0, 0.0], &scale(&axis, axis[0]));
    }
    let first = scale(&first, 1.0 / norm(&first));
    let axes = [first, cross(&axis, &first)];

    let com = body.com_m;
    let sideways = sub(&com, &scale(&axis, dot(&com, &axis)));
    let n = hinge_fractions.len() + 1;
    let bound = |s: usize| match s {
        0 => 0.0,
        s if s == n => 1.0,
        s => hinge_fractions[s - 1],
    };
    let fraction = |s: usize| bound(s + 1) - bound(s);
    let middle = |s: usize| 0.5 * (bound(s) + bound(s + 1));
    let mean: f64 = (0..n).map(|s| fraction(s) * middle(s)).sum();
    let along = |s: usize| (middle(s) - mean) * length; // from the centre of mass, m
    let spread: f64 = body.mass_kg * (0..n).map(|s| fraction(s) * along(s).powi(2)).sum::<f64>();
    // spread · (1 − e eᵀ) as [xx, yy, zz, xy, xz, yz].
    let perpendicular = [
        1.0 - axis[0] * axis[0],
        1.0 - axis[1] * axis[1],
        1.0 - axis[2] * axis[2],
        -axis[0] * axis[1],
        -axis[0] * axis[2],
        -axis[1] * axis[2],
    ];
    let reduced = |shrink: f64| -> [f64; 6] {
        std::array::from_fn(|k| body.inertia_kg_m2[k] - shrink * shrink * spread * perpendicular[k])
    };
    let mut shrink = 1.0;
    while !physical(&reduced(shrink)) {
        shrink *= 0.5;
        if shrink < 1e-6 {
            shrink = 0.0;
            break;
        }
    }
    let inertia = reduced(shrink);
    let segments = (0..n)
        .map(|s| LinkSegment {
            hinge_m: (s > 0).then(|| add(&sideways, &scale(&offset_m, hinge_fractions[s - 1]))),
            body: RigidBody {
                mass_kg: body.mass_kg * fraction(s),
                com_m: add(&com, &scale(&axis, shrink * along(s))),
                inertia_kg_m2: inertia.map(|v| fraction(s) * v),
            },
        })
        .collect();
    Ok((segments, axes))
}

/// A rigid body's inertia about its centre of mass: positive definite, each principal moment
/// at most the sum of the other two (with a margin of rounding).
fn physical(inertia: &[f64; 6]) -> bool {
    let body = RigidBody {
        mass_kg: 1.0,
        com_m: [0.0; 3],
        inertia_kg_m2: *inertia,
    };
    let [e0, _, _] = crate::robot::rigid_body::principal_moments(inertia);
    e0 > 1e-9 && body.validate("segment").is_ok()
}

/// The robot's chain in URDF form: joint placements, flange origin, and every link in the
/// frame of the link after its joint.
fn urdf_form(robot: &Robot) -> (Vec<JointPlacement>, Origin, Vec<RigidBody>) {
    match robot.chain() {
        Chain::Urdf { joints, flange } => (joints.clone(), *flange, robot.links().to_vec()),
        Chain::Dh(dh) => {
            // DH frame k+1 in the URDF frame of link k (DH frame k turned by q_k):
            // Tz(d) Tx(a) Rx(α).
            let step = |k: usize| {
                let j = dh[k];
                Origin::new([j.a_m, 0.0, j.d_m], [j.alpha_rad, 0.0, 0.0])
            };
            let joints = (0..dh.len())
                .map(|k| {
                    let origin = if k == 0 {
                        Origin::IDENTITY
                    } else {
                        step(k - 1)
                    };
                    JointPlacement::new(origin, [0.0, 0.0, 1.0])
                })
                .collect();
            let links = robot
                .links()
                .iter()
                .enumerate()
                .map(|(k, link)| step(k).pose().move_body(link))
                .collect();
            (joints, step(dh.len() - 1), links)
        }
    }
}

/// Where a real joint and a hinge sit in the hinged arm's coordinates.
pub fn hinged_index(joint: usize, hinged_links: &[usize]) -> usize {
    joint + 2 * hinged_links.iter().filter(|&&l| l < joint).count()
}

impl Robot {
    /// The robot with a hinge pair inserted in each link `(link, at_fraction)` (module docs),
    /// links distinct and in increasing order, fractions in `(0, 1)`. Its joints: each real
    /// joint `j` at [`hinged_index`]`(j, links)`, the hinges of link `l` right after joint
    /// `l`, first about the axis parallel to the link's joint. Payload and name are kept.
    pub fn with_link_hinges(&self, hinges: &[(usize, f64)]) -> Result<Robot, Error> {
        let n = self.n_dof();
        if hinges.windows(2).any(|w| w[0].0 >= w[1].0) || hinges.iter().any(|h| h.0 >= n) {
            return Err(Error::InvalidParameter(format!(
                "hinged links must be distinct link indices below {n} in increasing order, got \
                 {hinges:?}"
            )));
        }
        let (joints, flange, links) = urdf_form(self);
        let mut out_joints = Vec::with_capacity(n + 2 * hinges.len());
        let mut out_links = Vec::with_capacity(n + 2 * hinges.len());
        // The origin of the next joint (or flange) in the frame of the body carrying it: moved
        // when a link is split.
        let mut shift = [0.0; 3];
        for k in 0..n {
            let mut origin = joints[k].origin;
            origin.xyz_m = sub(&origin.xyz_m, &shift);
            out_joints.push(JointPlacement::new(origin, joints[k].axis));
            shift = [0.0; 3];
            let Some(&(_, at)) = hinges.iter().find(|h| h.0 == k) else {
                out_links.push(links[k]);
                continue;
            };
            let next = if k + 1 < n {
                joints[k + 1].origin.xyz_m
            } else {
                flange.xyz_m
            };
            let (segments, axes) = split_link(next, &links[k], &[at])
                .map_err(|e| Error::InvalidParameter(format!("link {k}: {e}")))?;
            let hinge = segments[1].hinge_m.unwrap_or([0.0; 3]);
            out_links.push(segments[0].body);
            out_joints.push(JointPlacement::new(Origin::new(hinge, [0.0; 3]), axes[0]));
            out_links.push(RigidBody::NONE);
            out_joints.push(JointPlacement::new(Origin::IDENTITY, axes[1]));
            let second = segments[1].body;
            out_links.push(RigidBody {
                com_m: sub(&second.com_m, &hinge),
                ..second
            });
            shift = hinge;
        }
        let mut flange = flange;
        flange.xyz_m = sub(&flange.xyz_m, &shift);
        let hinged = Robot::from_placements(out_joints, flange, out_links, *self.payload())?;
        Ok(match self.name() {
            Some(name) => hinged.with_name(name),
            None => hinged,
        })
    }
}

fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn norm(a: &[f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

fn scale(a: &[f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

fn add(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn sub(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segments_recombine_into_the_link() {
        let link = RigidBody {
            mass_kg: 8.4,
            com_m: [0.2125, 0.0, 0.138],
            inertia_kg_m2: [0.0236, 0.1373, 0.1373, 0.0, 0.0, 0.0],
        };
        let (segments, axes) = split_link([0.425, 0.0, 0.0], &link, &[0.5]).expect("long link");
        let whole = segments[0].body.combined(&segments[1].body);
        assert!((whole.mass_kg - link.mass_kg).abs() < 1e-12);
        for k in 0..3 {
            assert!((whole.com_m[k] - link.com_m[k]).abs() < 1e-12);
        }
        for k in 0..6 {
            assert!((whole.inertia_kg_m2[k] - link.inertia_kg_m2[k]).abs() < 1e-12);
        }
        // The hinge on the beam line through the centre of mass, halfway.
        assert_eq!(segments[1].hinge_m, Some([0.2125, 0.0, 0.138]));
        assert_eq!(axes, [[0.0, 0.0, 1.0], [0.0, -1.0, 0.0]]);
        assert!(split_link([0.01, 0.0, 0.0], &link, &[0.5]).is_err());
        assert!(split_link([0.4, 0.0, 0.0], &link, &[0.5, 0.5]).is_err());
    }
}
