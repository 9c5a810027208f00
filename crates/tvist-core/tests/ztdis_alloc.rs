//! Proof that `Compensator::step` (and the block form built on it) never allocates: a counting
//! global allocator wraps the system one, and the count must not move while stepping.
//!
//! This file is its own test binary, so no other test's allocations can interleave; the single
//! test below keeps the measured window free of the test harness's own work.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use tvist_core::ztdis::{Compensator, Discretization};
use tvist_core::{Mode, Status};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: defers every operation to `System`, only counting calls.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

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

    let before = ALLOCATIONS.load(Ordering::SeqCst);
    let mut status = Status::OK;
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
    let after = ALLOCATIONS.load(Ordering::SeqCst);

    assert_eq!(after - before, 0, "step allocated {} times", after - before);
    // The measured window really ran (outputs are finite and the held path was taken).
    assert!(status.contains(Status::INPUT_HELD));
    assert!(y.iter().chain(&block_out).all(|v| v.is_finite()));
    // The counter is live: an allocation outside the window is seen.
    let probe: Vec<u8> = Vec::with_capacity(64);
    assert!(ALLOCATIONS.load(Ordering::SeqCst) > after && probe.capacity() >= 64);
}
