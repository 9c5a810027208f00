//! The `TvistShaper` handle and the C functions that create, run and free it.
//!
//! Pointer rules (checked where C allows it): every pointer argument must be non-null and
//! aligned for its type, or the call returns [`TVIST_ERR_NULL`] without touching anything.
//! Lengths are checked against the handle before any array is read, so a wrong `n_dof` never
//! reads or writes out of bounds. What C cannot check (an array shorter than its stated
//! length, a dangling or foreign handle, a string without NUL) stays the caller's duty.

use crate::codes::{
    fail, fail_with, guard, TVIST_ERR_DIMENSION_MISMATCH, TVIST_ERR_INTERNAL,
    TVIST_ERR_INVALID_PARAMETER, TVIST_ERR_NULL, TVIST_ERR_UNKNOWN_ROBOT, TVIST_ERR_UNKNOWN_SHAPER,
    TVIST_OK,
};
use core::ffi::{c_char, CStr};
use core::ptr;
use tvist_core::robot_data::ur_e_series;
use tvist_core::{
    ConstantModes, DynamicMap, Error, MapDynamics, Mode, RigidBody, ShaperKind, Status, TvShaper,
    TvShaperConfig,
};

/// Largest number of joint channels a handle accepts (guards against garbage sizes).
pub const TVIST_MAX_DOF: usize = 4096;
/// Largest number of modes of a constant-mode shaper (one cascaded filter each).
pub const TVIST_MAX_MODES: usize = 64;
/// The robot the paper's dynamic map ([`DynamicMap::paper_ur5e`]) was identified on.
pub const PAPER_MAP_ROBOT: &str = "ur5e";

/// Where a shaper gets its modes from.
#[derive(Debug)]
enum Provider {
    Constant(TvShaper<ConstantModes>),
    Map(Box<TvShaper<MapDynamics>>),
}

/// An opaque shaper handle for C: one multi-mode FD-TVIST filter and its staging buffer.
///
/// A handle may move between threads but must not be used by two threads at once.
#[derive(Debug)]
pub struct TvistShaper {
    provider: Provider,
    /// Copy of the caller's input (`n_dof` values), so input and output may share memory.
    staging: Vec<f64>,
}

impl TvistShaper {
    fn new(provider: Provider) -> TvistShaper {
        let n_dof = match &provider {
            Provider::Constant(s) => s.n_dof(),
            Provider::Map(s) => s.n_dof(),
        };
        TvistShaper {
            provider,
            staging: vec![0.0; n_dof],
        }
    }

    /// Number of joint channels.
    pub fn n_dof(&self) -> usize {
        self.staging.len()
    }

    /// Current total delay of the cascade, s.
    pub fn delay_s(&self) -> f64 {
        match &self.provider {
            Provider::Constant(s) => s.delay_s(),
            Provider::Map(s) => s.delay_s(),
        }
    }

    /// One control cycle on raw arrays; allocation-free.
    ///
    /// # Safety
    /// If `n_dof == self.n_dof()`, `q_in` must be readable and `q_out` writable for `n_dof`
    /// doubles (they may be the same array). Otherwise nothing is accessed.
    unsafe fn step_raw(&mut self, q_in: *const f64, q_out: *mut f64, n_dof: usize) -> i32 {
        if n_dof != self.n_dof() {
            return Status::BAD_LENGTH.0;
        }
        // SAFETY: `q_in` is readable for `n_dof` doubles (caller) and `staging` is our own
        // allocation of exactly `n_dof`, so the two cannot overlap.
        unsafe { ptr::copy_nonoverlapping(q_in, self.staging.as_mut_ptr(), n_dof) };
        // SAFETY: `q_out` is writable for `n_dof` doubles (caller); the input was copied
        // above, so this is the only live reference to that memory even if it is `q_in`.
        let q_out = unsafe { core::slice::from_raw_parts_mut(q_out, n_dof) };
        let status = match &mut self.provider {
            Provider::Constant(s) => s.step(&self.staging, q_out),
            Provider::Map(s) => s.step(&self.staging, q_out),
        };
        status.0
    }

    /// Puts the filter at rest at `q0` (see `tvist_shaper_reset`).
    ///
    /// # Safety
    /// If `n_dof == self.n_dof()`, `q0` must be readable for `n_dof` doubles.
    unsafe fn reset_raw(&mut self, q0: *const f64, n_dof: usize) -> i32 {
        if n_dof != self.n_dof() {
            return TVIST_ERR_DIMENSION_MISMATCH;
        }
        // SAFETY: as in `step_raw`.
        unsafe { ptr::copy_nonoverlapping(q0, self.staging.as_mut_ptr(), n_dof) };
        match &mut self.provider {
            Provider::Constant(s) => s.reset(&self.staging),
            Provider::Map(s) => s.reset(&self.staging),
        }
        TVIST_OK
    }
}

/// True if `ptr` is non-null and aligned for `T`.
fn usable<T>(ptr: *const T) -> bool {
    !ptr.is_null() && ptr.is_aligned()
}

/// Reads a NUL-terminated C string; `None` if it is not UTF-8.
///
/// # Safety
/// `ptr` is non-null and points to a NUL-terminated string valid for the call.
unsafe fn c_str<'a>(ptr: *const c_char) -> Option<&'a str> {
    // SAFETY: guaranteed by the caller.
    unsafe { CStr::from_ptr(ptr) }.to_str().ok()
}

/// The registry shaper named by C string `name` (setup errors recorded).
///
/// # Safety
/// As [`c_str`].
unsafe fn shaper_kind(name: *const c_char) -> Result<ShaperKind, i32> {
    // SAFETY: forwarded from the caller.
    match unsafe { c_str(name) } {
        Some(name) => ShaperKind::from_name(name, None).map_err(|e| fail_with(&e)),
        None => Err(fail(
            TVIST_ERR_UNKNOWN_SHAPER,
            "the shaper name is not valid UTF-8",
        )),
    }
}

/// Checks `n_dof` against [`TVIST_MAX_DOF`] (the core checks `n_dof >= 1`).
fn check_n_dof(n_dof: usize) -> Result<(), i32> {
    if n_dof > TVIST_MAX_DOF {
        return Err(fail(
            TVIST_ERR_INVALID_PARAMETER,
            format!("n_dof = {n_dof} exceeds the limit of {TVIST_MAX_DOF} channels"),
        ));
    }
    Ok(())
}

/// Stores a built handle in `*out` (or leaves the null written at entry) and returns the code.
///
/// # Safety
/// `out` is non-null, aligned and writable.
unsafe fn publish(out: *mut *mut TvistShaper, built: Result<TvistShaper, i32>) -> i32 {
    match built {
        Ok(shaper) => {
            // SAFETY: guaranteed by the caller.
            unsafe { out.write(Box::into_raw(Box::new(shaper))) };
            TVIST_OK
        }
        Err(code) => code,
    }
}

/// A handle around a new [`TvShaper`] for `dynamics` (setup errors recorded).
fn build<D: tvist_core::Dynamics>(
    dynamics: D,
    config: &TvShaperConfig,
    wrap: fn(TvShaper<D>) -> Provider,
) -> Result<TvistShaper, i32> {
    let shaper = TvShaper::new(dynamics, config).map_err(|e: Error| fail_with(&e))?;
    Ok(TvistShaper::new(wrap(shaper)))
}

/// Creates a shaper for `n_modes` fixed modes (`wn_rad_s[m]`, `zeta[m]`), one cascaded filter
/// per mode, shaping `n_dof` channels sampled every `dt_s` seconds with registry shaper
/// `shaper_name`. Linear interpolation; delay lines sized 1.5 × the longest shaper.
///
/// Returns `TVIST_OK` and a new handle in `*out`, or a negative code with `*out = NULL` (when
/// `out` itself is usable) and the reason in `tvist_last_error_message`.
///
/// # Safety
/// `wn_rad_s` and `zeta` are readable for `n_modes` doubles; `shaper_name` is a NUL-terminated
/// string; `out` is writable.
#[no_mangle]
pub unsafe extern "C" fn tvist_shaper_new_constant(
    wn_rad_s: *const f64,
    zeta: *const f64,
    n_modes: usize,
    dt_s: f64,
    n_dof: usize,
    shaper_name: *const c_char,
    out: *mut *mut TvistShaper,
) -> i32 {
    guard(TVIST_ERR_INTERNAL, || {
        if !usable(out) {
            return fail(TVIST_ERR_NULL, "out is null or misaligned");
        }
        // SAFETY: `out` is non-null and aligned; the caller guarantees it is writable.
        unsafe { out.write(ptr::null_mut()) };
        if !(usable(wn_rad_s) && usable(zeta) && !shaper_name.is_null()) {
            return fail(
                TVIST_ERR_NULL,
                "wn_rad_s, zeta and shaper_name must be non-null (and aligned)",
            );
        }
        if n_modes > TVIST_MAX_MODES {
            return fail(
                TVIST_ERR_INVALID_PARAMETER,
                format!("n_modes = {n_modes} exceeds the limit of {TVIST_MAX_MODES}"),
            );
        }
        let built = (|| {
            check_n_dof(n_dof)?;
            // SAFETY: `shaper_name` is non-null and NUL-terminated (caller).
            let kind = unsafe { shaper_kind(shaper_name) }?;
            // SAFETY: both arrays are non-null, aligned and readable for `n_modes` doubles
            // (caller); `n_modes <= TVIST_MAX_MODES` keeps the byte size far below isize::MAX.
            let (wn, z) = unsafe {
                (
                    core::slice::from_raw_parts(wn_rad_s, n_modes),
                    core::slice::from_raw_parts(zeta, n_modes),
                )
            };
            let modes = wn.iter().zip(z).map(|(&w, &z)| Mode::new(w, z)).collect();
            let dynamics = ConstantModes::new(modes).map_err(|e| fail_with(&e))?;
            build(
                dynamics,
                &TvShaperConfig::new(dt_s, n_dof, kind),
                Provider::Constant,
            )
        })();
        // SAFETY: `out` checked above.
        unsafe { publish(out, built) }
    })
}

/// Creates a shaper driven by the paper's dynamic map of the UR5e
/// ([`DynamicMap::paper_ur5e`], base and shoulder modes), with the robot's rigid-body model
/// from the project's robot-data file and a point payload of `payload_kg` at `payload_com_m`
/// (flange frame, m). Shapes the robot's 6 joints sampled every `dt_s` seconds.
///
/// Returns as [`tvist_shaper_new_constant`]; `TVIST_ERR_UNKNOWN_ROBOT` for a robot other
/// than `"ur5e"`.
///
/// # Safety
/// `robot_name` and `shaper_name` are NUL-terminated strings; `payload_com_m` is readable for
/// 3 doubles; `out` is writable.
#[no_mangle]
pub unsafe extern "C" fn tvist_shaper_new_ur_map(
    robot_name: *const c_char,
    payload_kg: f64,
    payload_com_m: *const f64,
    dt_s: f64,
    shaper_name: *const c_char,
    out: *mut *mut TvistShaper,
) -> i32 {
    guard(TVIST_ERR_INTERNAL, || {
        if !usable(out) {
            return fail(TVIST_ERR_NULL, "out is null or misaligned");
        }
        // SAFETY: `out` is non-null and aligned; the caller guarantees it is writable.
        unsafe { out.write(ptr::null_mut()) };
        if robot_name.is_null() || shaper_name.is_null() || !usable(payload_com_m) {
            return fail(
                TVIST_ERR_NULL,
                "robot_name, payload_com_m and shaper_name must be non-null (and aligned)",
            );
        }
        let built = (|| {
            // SAFETY: non-null and NUL-terminated (caller).
            let robot_name = unsafe { c_str(robot_name) };
            if robot_name != Some(PAPER_MAP_ROBOT) {
                return Err(fail(
                    TVIST_ERR_UNKNOWN_ROBOT,
                    format!(
                        "robot {robot_name:?}: the paper's dynamic map is identified for \
                         {PAPER_MAP_ROBOT:?} only"
                    ),
                ));
            }
            // SAFETY: non-null and NUL-terminated (caller).
            let kind = unsafe { shaper_kind(shaper_name) }?;
            // SAFETY: non-null, aligned and readable for 3 doubles (caller).
            let com_m = unsafe { payload_com_m.cast::<[f64; 3]>().read() };
            let payload = RigidBody::point(payload_kg, com_m);
            let robot = ur_e_series(PAPER_MAP_ROBOT, payload).map_err(|e| fail_with(&e))?;
            let n_dof = robot.n_dof();
            let dynamics =
                MapDynamics::new(robot, DynamicMap::paper_ur5e()).map_err(|e| fail_with(&e))?;
            build(dynamics, &TvShaperConfig::new(dt_s, n_dof, kind), |s| {
                Provider::Map(Box::new(s))
            })
        })();
        // SAFETY: `out` checked above.
        unsafe { publish(out, built) }
    })
}

/// One control cycle: shapes `q_in` into `q_out` (each `n_dof` doubles; they may be the same
/// array). Allocation-free and lock-free.
///
/// Returns the core's status bits (>= 0: `TVIST_STATUS_*`; `TVIST_STATUS_BAD_LENGTH` when
/// `n_dof` differs from the handle's, and then nothing is read or written), or
/// `TVIST_ERR_NULL`.
///
/// # Safety
/// `shaper` comes from a constructor and is not freed; `q_in`/`q_out` are readable/writable
/// for `n_dof` doubles.
#[no_mangle]
pub unsafe extern "C" fn tvist_shaper_step(
    shaper: *mut TvistShaper,
    q_in: *const f64,
    q_out: *mut f64,
    n_dof: usize,
) -> i32 {
    guard(TVIST_ERR_INTERNAL, || {
        if !(usable(shaper) && usable(q_in) && usable(q_out)) {
            return TVIST_ERR_NULL;
        }
        // SAFETY: a live handle from a constructor (caller), used by this thread only.
        let shaper = unsafe { &mut *shaper };
        // SAFETY: array validity forwarded from the caller.
        unsafe { shaper.step_raw(q_in, q_out, n_dof) }
    })
}

/// Puts the shaper at rest at `q0` (`n_dof` doubles): its history and previous output equal
/// `q0`, so a following constant input `q0` passes unchanged. Non-finite entries are taken as 0.
/// Modes are re-read on the next step.
///
/// Returns `TVIST_OK`, `TVIST_ERR_NULL`, or `TVIST_ERR_DIMENSION_MISMATCH` (nothing read).
///
/// # Safety
/// `shaper` comes from a constructor and is not freed; `q0` is readable for `n_dof` doubles.
#[no_mangle]
pub unsafe extern "C" fn tvist_shaper_reset(
    shaper: *mut TvistShaper,
    q0: *const f64,
    n_dof: usize,
) -> i32 {
    guard(TVIST_ERR_INTERNAL, || {
        if !(usable(shaper) && usable(q0)) {
            return TVIST_ERR_NULL;
        }
        // SAFETY: a live handle from a constructor (caller), used by this thread only.
        let shaper = unsafe { &mut *shaper };
        // SAFETY: array validity forwarded from the caller.
        unsafe { shaper.reset_raw(q0, n_dof) }
    })
}

/// Current total delay of the cascade in seconds (the sum of the last impulse times of the
/// latest cycle; 0 before the first step). NaN for a null handle.
///
/// # Safety
/// `shaper` is null or comes from a constructor and is not freed.
#[no_mangle]
pub unsafe extern "C" fn tvist_shaper_delay_s(shaper: *const TvistShaper) -> f64 {
    guard(f64::NAN, || {
        if !usable(shaper) {
            return f64::NAN;
        }
        // SAFETY: a live handle from a constructor (caller).
        unsafe { &*shaper }.delay_s()
    })
}

/// Number of joint channels of the shaper (0 for a null handle).
///
/// # Safety
/// `shaper` is null or comes from a constructor and is not freed.
#[no_mangle]
pub unsafe extern "C" fn tvist_shaper_n_dof(shaper: *const TvistShaper) -> usize {
    guard(0, || {
        if !usable(shaper) {
            return 0;
        }
        // SAFETY: a live handle from a constructor (caller).
        unsafe { &*shaper }.n_dof()
    })
}

/// Frees a shaper. Null-safe; the handle must not be used afterwards.
///
/// # Safety
/// `shaper` is null or comes from a constructor and has not been freed.
#[no_mangle]
pub unsafe extern "C" fn tvist_shaper_free(shaper: *mut TvistShaper) {
    guard((), || {
        if !shaper.is_null() {
            // SAFETY: it came from `Box::into_raw` in `publish` and is freed once (caller).
            drop(unsafe { Box::from_raw(shaper) });
        }
    })
}

/// Copies this thread's last setup-error text into `buf` (`len` bytes; truncated at a
/// character boundary and always NUL-terminated when `len > 0`) and returns the text's full
/// length in bytes, excluding the NUL (like `snprintf`). `buf` may be null when `len == 0`.
/// Set by a constructor that returned a negative code; 0 if there was none on this thread.
///
/// # Safety
/// `buf` is null or writable for `len` bytes.
#[no_mangle]
pub unsafe extern "C" fn tvist_last_error_message(buf: *mut c_char, len: usize) -> usize {
    guard(0, || {
        let buf: &mut [u8] = if buf.is_null() || len == 0 || len > isize::MAX as usize {
            &mut []
        } else {
            // SAFETY: non-null and writable for `len` bytes (caller); u8 and c_char have the
            // same size and alignment.
            unsafe { core::slice::from_raw_parts_mut(buf.cast::<u8>(), len) }
        };
        crate::codes::copy_last_error(buf)
    })
}
