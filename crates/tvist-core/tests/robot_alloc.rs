//! The robot model, the dynamic map and the map-driven shaper never allocate per call.
//!
//! Its own test binary with a counting global allocator. Only allocations made by the
//! measuring thread inside a measured window are counted (a const thread-local flag), so the
//! test harness's own threads cannot disturb the count.

mod robot_support;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use tvist_core::{
    DynamicMap, Dynamics, MapDynamics, Mode, ShaperKind, Status, TvShaper, TvShaperConfig,
};

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
fn robot_map_and_map_shaper_never_allocate() {
    the_counter_sees_this_thread_only();

    let mut robot = robot_support::ur_robot("ur5e", 5.0);
    let (mut m, mut jac, mut j, mut tau, mut pose) =
        ([0.0; 36], [0.0; 36], [0.0; 6], [0.0; 6], [0.0; 16]);
    let mut rng = robot_support::Rng(5);
    let poses: Vec<Vec<f64>> = (0..200).map(|_| rng.pose(6)).collect();
    let n = allocations_in(|| {
        for q in &poses {
            robot.mass_matrix(q, &mut m);
            robot.jacobian(q, &mut jac);
            robot.joint_inertia(q, &mut j);
            robot.gravity_torque(q, &mut tau);
            robot.flange_pose(q, &mut pose);
            robot.joint_inertia_and_gravity(q, &mut j, Some(&mut tau));
        }
        // Wrong lengths and NaN poses take the same allocation-free path.
        robot.mass_matrix(&[0.0; 5], &mut m);
        robot.joint_inertia(&[f64::NAN; 6], &mut j);
    });
    assert_eq!(n, 0, "robot model allocated {n} times");

    let map = DynamicMap::paper_ur5e();
    let mut modes = [Mode::new(0.0, 0.0); 2];
    let n = allocations_in(|| {
        map.modes_from_inertia(&[9.73, 9.25], &[], &mut modes);
        map.modes_from_inertia(&[-1.0, f64::NAN], &[], &mut modes);
        map.modes_from_inertia(&[1.0], &[], &mut modes);
    });
    assert_eq!(n, 0, "dynamic map allocated {n} times");

    let mut provider = MapDynamics::new(
        robot_support::ur_robot("ur5e", 5.0),
        DynamicMap::paper_ur5e(),
    )
    .expect("valid map");
    let n = allocations_in(|| {
        for q in &poses {
            provider.modes(q, &mut modes);
        }
        provider.modes(&[0.0; 4], &mut modes);
    });
    assert_eq!(n, 0, "MapDynamics::modes allocated {n} times");

    let config = TvShaperConfig::new(0.002, 6, ShaperKind::Zvd);
    let mut shaper = TvShaper::new(provider, &config).expect("valid config");
    let mut out = [0.0; 6];
    let mut statuses = Status::OK;
    let n = allocations_in(|| {
        for q in &poses {
            // Large jumps between random poses make the modes change every cycle.
            statuses |= shaper.step(q, &mut out);
        }
        let mut bad = [0.0; 6];
        bad[2] = f64::NAN;
        statuses |= shaper.step(&bad, &mut out);
        statuses |= shaper.step(&[0.0; 3], &mut out);
    });
    assert_eq!(n, 0, "TvShaper<MapDynamics>::step allocated {n} times");
    assert!(statuses.contains(Status::INPUT_HELD) && statuses.contains(Status::BAD_LENGTH));
}
