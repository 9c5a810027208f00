//! A counting global allocator for allocation-free proofs, shared by the allocation tests
//! (each test file is its own binary, so each gets its own counter).
//!
//! Only allocations made by the measuring thread inside a measured window are counted (a
//! const thread-local flag, which itself never allocates), so the test harness's other threads
//! cannot disturb the count. [`the_counter_sees_this_thread_only`] guards both ways: an
//! allocation inside the window is counted, another thread's allocations are not.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    /// Set only on the measuring thread, only inside a measured window.
    static MEASURING: Cell<bool> = const { Cell::new(false) };
}

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

/// Runs `f` on this thread and returns how many allocations this thread made meanwhile.
pub fn allocations_in(f: impl FnOnce()) -> usize {
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    MEASURING.with(|m| m.set(true));
    f();
    MEASURING.with(|m| m.set(false));
    ALLOCATIONS.load(Ordering::SeqCst) - before
}

/// Guards against a vacuous pass (an allocation inside the window is counted) and against
/// other threads disturbing the count (another thread allocating 1000 times during a window
/// in which this thread does not allocate must give 0).
pub fn the_counter_sees_this_thread_only() {
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
        let start = progress.load(Ordering::SeqCst);
        while progress.load(Ordering::SeqCst) < start + 1000 {
            std::hint::spin_loop();
        }
    });
    stop.store(true, Ordering::SeqCst);
    worker.join().expect("worker thread");
    assert_eq!(n, 0, "another thread's allocations were counted");
}

/// Asserts that a robot-driven provider (two modes, 6 DOF) and a `kind` shaper driven by it
/// never allocate: per pose of `poses` (twice, so a repeated pose takes the stored result), on
/// a too-short pose, and through the shaper with a NaN pose and a too-short row, which must
/// report [`Status::INPUT_HELD`] and [`Status::BAD_LENGTH`]. `name` labels the messages.
#[allow(dead_code)] // not every allocation test has a robot-driven provider
pub fn assert_robot_provider_never_allocates<D: tvist_core::Dynamics>(
    mut provider: D,
    kind: tvist_core::ShaperKind,
    poses: &[Vec<f64>],
    name: &str,
) {
    use tvist_core::{Mode, Status, TvShaper, TvShaperConfig};

    let mut modes = vec![Mode::new(0.0, 0.0); provider.n_modes()];
    let n = allocations_in(|| {
        for q in poses {
            provider.modes(q, &mut modes);
            // The same pose again: the stored result.
            provider.modes(q, &mut modes);
        }
        provider.modes(&[0.0; 4], &mut modes);
        provider.restart();
        provider.modes(&poses[0], &mut modes);
    });
    assert_eq!(n, 0, "{name}::modes allocated {n} times");

    let config = TvShaperConfig::new(0.002, 6, kind);
    let mut shaper = TvShaper::new(provider, &config).expect("valid config");
    let mut out = [0.0; 6];
    let mut statuses = Status::OK;
    let n = allocations_in(|| {
        for q in poses {
            // Large jumps between random poses make the modes change every cycle.
            statuses |= shaper.step(q, &mut out);
        }
        // At rest on the last pose (longer than any delay line): the provider restarts.
        if let Some(q) = poses.last() {
            for _ in 0..2000 {
                statuses |= shaper.step(q, &mut out);
            }
        }
        let mut bad = [0.0; 6];
        bad[2] = f64::NAN;
        statuses |= shaper.step(&bad, &mut out);
        statuses |= shaper.step(&[0.0; 3], &mut out);
    });
    assert_eq!(n, 0, "TvShaper<{name}>::step allocated {n} times");
    assert!(statuses.contains(Status::INPUT_HELD) && statuses.contains(Status::BAD_LENGTH));
    // The modes of random poses jump: the slew limit binds (and allocates nothing).
    assert!(statuses.contains(Status::MODE_SLEW_LIMITED));
}
