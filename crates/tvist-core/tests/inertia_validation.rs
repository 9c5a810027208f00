//! A body's inertia tensor is judged by its principal moments, whatever its orientation:
//! tensors `R diag(I) Rᵀ` with every product of inertia non-zero, on both sides of the
//! triangle inequality `I_a + I_b >= I_c`.

use tvist_core::RigidBody;

/// Rotation about the unit axis of `(2, 1, -1)` by 0.9 rad (Rodrigues), row-major.
fn rotation() -> [[f64; 3]; 3] {
    let n = (4.0f64 + 1.0 + 1.0).sqrt();
    let (x, y, z) = (2.0 / n, 1.0 / n, -1.0 / n);
    let (s, c) = 0.9f64.sin_cos();
    let t = 1.0 - c;
    [
        [c + x * x * t, x * y * t - z * s, x * z * t + y * s],
        [y * x * t + z * s, c + y * y * t, y * z * t - x * s],
        [z * x * t - y * s, z * y * t + x * s, c + z * z * t],
    ]
}

/// `[xx, yy, zz, xy, xz, yz]` of `R diag(principal) Rᵀ`.
fn rotated(principal: [f64; 3]) -> [f64; 6] {
    let r = rotation();
    let m = |i: usize, j: usize| {
        (0..3)
            .map(|k| r[i][k] * principal[k] * r[j][k])
            .sum::<f64>()
    };
    [m(0, 0), m(1, 1), m(2, 2), m(0, 1), m(0, 2), m(1, 2)]
}

fn body(principal: [f64; 3]) -> RigidBody {
    RigidBody {
        mass_kg: 2.0,
        com_m: [0.0, 0.0, 0.1],
        inertia_kg_m2: rotated(principal),
    }
}

#[test]
fn rotated_tensors_are_judged_by_their_principal_moments() {
    let tensor = rotated([1.0, 1.5, 2.5]);
    assert!(tensor[3..].iter().all(|p| p.abs() > 0.05), "{tensor:?}");
    // On the triangle boundary (1 + 1.5 = 2.5): physical; 1e-6 beyond it: not.
    assert!(body([1.0, 1.5, 2.5]).validate("b").is_ok());
    assert!(body([1.0, 1.5, 2.5 * (1.0 + 1e-6)]).validate("b").is_err());
    assert!(body([0.9, 1.3, 2.0]).validate("b").is_ok());
    // A negative principal moment is not physical.
    assert!(body([-1e-3, 2.0, 2.1]).validate("b").is_err());
}
