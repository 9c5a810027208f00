//! The exact EI solver's input domain: a tolerance must lie strictly inside (0, 1) and the
//! damping ratio in [0, 1); outside it there is no shaper, whatever Newton would converge to.

use tvist_core::shaping::ei;

#[test]
fn refine_refuses_a_tolerance_outside_the_open_unit_interval() {
    let start = ei::polynomial(0.05, 0.1);
    // Inside: the polynomial start refines to a solution.
    assert!(ei::refine(0.05, 0.1, &start).is_some());
    // A tolerance of 100 % (or more) or none at all is no design requirement.
    for v_tol in [0.0, 1.0, 1.5, -0.05, f64::NAN] {
        assert!(ei::refine(v_tol, 0.1, &start).is_none(), "v_tol {v_tol}");
    }
    for zeta in [1.0, -0.01, f64::NAN] {
        assert!(ei::refine(0.05, zeta, &start).is_none(), "zeta {zeta}");
    }
}
