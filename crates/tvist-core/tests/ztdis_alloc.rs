//! Proof that `Compensator::step` (and the block form built on it) never allocates: a counting
//! global allocator wraps the system one, and the count must not move while stepping.
//!
//! Its own test binary. Only allocations made by the measuring thread inside a measured window
//! are counted (a const thread-local flag), so the test harness's own threads cannot disturb
//! the count.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use tvist_core::ztdis::{Compensator, Discretization};
use tvist_core::{Mode, Status};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    /// Set only on the measuring thread, only inside a measured window. Const-initialized and
    /// without a destructor, so reading it from the allocator never allocates.
    static MEASURING: Cell<bool> = const { Cell::new(false) };
}

/// Counts an allocation if the calling thread is inside a measured window.
fn count() {
    if MEASURING.with(Cell::get) {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
    }
}

// SAFETY: forwards to the system allocator unchanged; only counts calls.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Runs `f` on this thread and returns how many allocations this thread made meanwhile
/// (other threads, such as the test harness's, are not counted).
fn allocations_in(f: impl FnOnce()) -> usize {
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    MEASURING.with(|m| m.set(true));
    f();
    MEASURING.with(|m| m.set(false));
    ALLOCATIONS.load(Ordering::SeqCst) - before
}

/// Guards against a vacuous pass (an allocation inside the window is counted) and against the
/// harness's threads disturbing the count (another thread allocating throughout the window
/// is not).
fn the_counter_sees_this_thread_only() {
    assert!(allocations_in(|| drop(std::hint::black_box(vec![1u8; 8]))) >= 1);
    let stop = Arc::new(AtomicBool::new(false));
    let progress = Arc::new(AtomicUsize::new(0));
    let worker = {
        let (stop, progress) = (Arc::clone(&stop), Arc::clone(&progress));
        std::thread::spawn(move || {
            while !stop.load(Ordering::SeqCst) {
                drop(std::hint::black_box(vec![1u8; 32]));
                progress.fetch_add(1, Ordering::SeqCst);
            }
        })
    };
    let n = allocations_in(|| {
        // Atomic loads only: this thread does not allocate while the worker does, 1000 times.
        let start = progress.load(Ordering::SeqCst);
        while progress.load(Ordering::SeqCst) < start + 1000 {
            std::hint::spin_loop();
        }
    });
    stop.store(true, Ordering::SeqCst);
    worker.join().expect("worker thread");
    assert_eq!(n, 0, "another thread's allocations were counted");
}

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
