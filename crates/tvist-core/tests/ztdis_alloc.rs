//! Proof that `Compensator::step` (and the block form built on it) never allocates: a counting
//! global allocator wraps the system one, and the count must not move while stepping.
//!
//! Its own test binary. Only allocations made by the measuring thread inside a measured window
//! are counted (a const thread-local flag), so the test harness's own threads cannot disturb
//! the count.

mod alloc_support;

use alloc_support::{allocations_in, the_counter_sees_this_thread_only};
use tvist_core::shaping::ztdis::{Compensator, Discretization};
use tvist_core::{Mode, Status};

#[test]
fn compensator_step_does_not_allocate() {
    let modes = [
        Mode::new(2.0 * std::f64::consts::PI * 2.55, 0.04),
        Mode::new(60.0, 0.08),
    ];
    let n_dof = 6;
    let mut filters = [Discretization::Matched, Discretization::Tustin].map(|method| {
        Compensator::with_discretization(&modes, 0.6516, 0.002, n_dof, method).expect("valid")
    });
    // Inputs and outputs are prepared before the measured window.
    let n_samples = 2000;
    let block: Vec<f64> = (0..n_samples * n_dof)
        .map(|i| (i as f64 * 1e-3).sin())
        .collect();
    let mut block_out = vec![0.0; block.len()];
    let mut x = [0.0; 6];
    let mut y = [0.0; 6];
    let bad = [f64::NAN; 6];

    the_counter_sees_this_thread_only();
    let mut status = Status::OK;
    let n = allocations_in(|| {
        for c in &mut filters {
            c.reset(&x);
            for k in 0..n_samples {
                for (j, v) in x.iter_mut().enumerate() {
                    *v = (k as f64 * 0.002 * (j as f64 + 1.0)).sin();
                }
                status |= c.step(&x, &mut y);
            }
            status |= c.step(&bad, &mut y); // the held-input path
            let _ = c.step(&x[..3], &mut y); // the bad-length path
            c.clear();
            status |= c.filter_into(&block, &mut block_out);
        }
    });

    assert_eq!(n, 0, "step allocated {n} times");
    // The measured window really ran (outputs are finite and the held path was taken).
    assert!(status.contains(Status::INPUT_HELD));
    assert!(y.iter().chain(&block_out).all(|v| v.is_finite()));
}
