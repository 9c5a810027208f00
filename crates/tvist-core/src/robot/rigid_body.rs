//! Mass properties of one rigid body: validation (a physical inertia tensor), rigid joining,
//! principal moments.

use crate::error::Error;
use crate::math::mat3::{dot3, sub3, sym_from_six};
use crate::math::sym_eigen::{sym_eigen, Matrix, MAX_DIM};

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

/// Principal moments (ascending) of an inertia `[xx, yy, zz, xy, xz, yz]`; NaN for
/// non-finite input. Setup-time only.
pub(crate) fn principal_moments(inertia: &[f64; 6]) -> [f64; 3] {
    sym_eigenvalues(&sym_from_six(inertia))
}

/// Eigenvalues of a symmetric 3×3 matrix in ascending order, by the cyclic Jacobi method of
/// [`crate::math::sym_eigen`]: each within a few ulp of the matrix's largest entry of the exact one,
/// also for equal or nearly equal eigenvalues (a thin rod's two equal moments, a disc's
/// `k, k, 2k`), where the trigonometric closed form loses half the digits (`acos` near ±1).
/// NaN for non-finite input. Setup-time only.
fn sym_eigenvalues(m: &[f64; 9]) -> [f64; 3] {
    let mut a: Matrix = [[0.0; MAX_DIM]; MAX_DIM];
    for (r, row) in a.iter_mut().take(3).enumerate() {
        row[..3].copy_from_slice(&m[3 * r..3 * r + 3]);
    }
    match sym_eigen(&a, 3) {
        Some((values, _)) => {
            let mut d = [values[0], values[1], values[2]];
            d.sort_by(f64::total_cmp);
            d
        }
        None => [f64::NAN; 3],
    }
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

    /// `k (1 − u uᵀ) + l u uᵀ` for a unit `u`, as `[xx, yy, zz, xy, xz, yz]`: principal
    /// moments `l` about `u` and `k` (twice) across it, exactly.
    fn axisymmetric(u: [f64; 3], k: f64, l: f64) -> [f64; 6] {
        let w = l - k;
        [
            k + w * u[0] * u[0],
            k + w * u[1] * u[1],
            k + w * u[2] * u[2],
            w * u[0] * u[1],
            w * u[0] * u[2],
            w * u[1] * u[2],
        ]
    }

    /// Unit directions spread over the sphere (a spiral), and the coordinate axes.
    fn directions() -> Vec<[f64; 3]> {
        let mut dirs: Vec<[f64; 3]> = (0..2000)
            .map(|i| {
                let t = i as f64 * 0.37;
                let (st, ct) = t.sin_cos();
                let (sp, cp) = (0.3 * t).sin_cos();
                [ct * sp, st * sp, cp]
            })
            .collect();
        dirs.extend([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
        dirs
    }

    #[test]
    fn equal_principal_moments_are_found_to_rounding() {
        // A thin rod of mass m and length L along u: m L²/12 across it (twice), 0 along it. A
        // thin disc of radius R with normal u: m R²/4 across (twice), m R²/2 about u (the
        // triangle inequality holds with equality). A sphere: three equal moments. The
        // tensors are exact up to the rounding of their entries (a few ulp of k), so the
        // eigenvalues are too: 1e-14 of the largest moment is 50 ulp.
        let (m, length, radius) = (1.7, 0.6, 0.05);
        let rod = m * length * length / 12.0;
        let disc = m * radius * radius / 4.0;
        for u in directions() {
            for (six, want) in [
                (axisymmetric(u, rod, 0.0), [0.0, rod, rod]),
                (axisymmetric(u, disc, 2.0 * disc), [disc, disc, 2.0 * disc]),
                (axisymmetric(u, rod, rod), [rod, rod, rod]),
                (axisymmetric(u, rod, 1.0001 * rod), [rod, rod, 1.0001 * rod]),
            ] {
                let e = sym_eigenvalues(&sym_from_six(&six));
                for (got, w) in e.iter().zip(want) {
                    assert!(
                        (got - w).abs() <= 1e-14 * want[2],
                        "u = {u:?}: {e:?} vs {want:?}"
                    );
                }
                let body = RigidBody {
                    mass_kg: m,
                    com_m: [0.1, -0.2, 0.3],
                    inertia_kg_m2: six,
                };
                assert!(body.validate("body").is_ok(), "u = {u:?}: {six:?}");
            }
        }
        // Just outside the triangle inequality (1e-6 of the largest moment, far above the
        // validation's 1e-9 round-off allowance) is still refused, in any orientation.
        for u in directions().into_iter().step_by(97) {
            let six = axisymmetric(u, disc, 2.0 * disc * (1.0 + 1e-6));
            let body = RigidBody {
                mass_kg: m,
                com_m: [0.0; 3],
                inertia_kg_m2: six,
            };
            let err = body
                .validate("disc")
                .expect_err("violates the triangle inequality");
            assert!(err.to_string().contains("triangle"), "{err}");
        }
    }

    #[test]
    fn eigenvalues_of_a_rotated_diagonal_matrix() {
        // R diag(1, 2, 3) Rᵀ with R = Rz(0.7) Ry(−1.1) Rx(2.3): eigenvalues 1, 2, 3.
        let rx = |a: f64| {
            [
                [1.0, 0.0, 0.0],
                [0.0, a.cos(), -a.sin()],
                [0.0, a.sin(), a.cos()],
            ]
        };
        let ry = |a: f64| {
            [
                [a.cos(), 0.0, a.sin()],
                [0.0, 1.0, 0.0],
                [-a.sin(), 0.0, a.cos()],
            ]
        };
        let rz = |a: f64| {
            [
                [a.cos(), -a.sin(), 0.0],
                [a.sin(), a.cos(), 0.0],
                [0.0, 0.0, 1.0],
            ]
        };
        let mul = |a: [[f64; 3]; 3], b: [[f64; 3]; 3]| {
            let mut c = [[0.0; 3]; 3];
            for i in 0..3 {
                for j in 0..3 {
                    c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
                }
            }
            c
        };
        let r = mul(mul(rz(0.7), ry(-1.1)), rx(2.3));
        let d = [1.0, 2.0, 3.0];
        let mut m = [0.0; 9];
        for i in 0..3 {
            for j in 0..3 {
                m[3 * i + j] = (0..3).map(|k| r[i][k] * d[k] * r[j][k]).sum();
            }
        }
        let e = sym_eigenvalues(&m);
        for (got, want) in e.iter().zip(d) {
            assert!((got - want).abs() < 1e-14 * 3.0, "{e:?}");
        }
        // Diagonal input (no rotation needed) and the zero matrix.
        assert_eq!(
            sym_eigenvalues(&[5.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 2.0]),
            [-1.0, 2.0, 5.0]
        );
        assert_eq!(sym_eigenvalues(&[0.0; 9]), [0.0; 3]);
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
}
