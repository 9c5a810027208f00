//! The `TvistShaper` handle and the C functions that create, run and free it.
//!
//! Pointer rules (checked where C allows it): every pointer argument must be non-null and
//! aligned for its type, or the call returns [`TVIST_ERR_NULL`] without touching anything.
//! Lengths are checked against the handle before any array is read, so a wrong `n_dof` never
//! reads or writes out of bounds. What C cannot check (an array shorter than its stated
//! length, a dangling or foreign handle, a string without NUL) stays the caller's duty.

use crate::codes::{
    fail, fail_with, guard, TVIST_ERR_DIMENSION_MISMATCH, TVIST_ERR_INTERNAL,
    TVIST_ERR_INVALID_PARAMETER, TVIST_ERR_MAP_FILE, TVIST_ERR_MID_MOVE, TVIST_ERR_NULL,
    TVIST_ERR_UNKNOWN_ROBOT, TVIST_ERR_UNKNOWN_SHAPER, TVIST_OK,
};
use core::ffi::{c_char, CStr};
use core::ptr;
use std::path::Path;
use tvist_core::error::N_STATUS_FLAGS;
use tvist_core::files::map_file::{MapFile, MapForm};
use tvist_core::files::robot_data::{robot_file, ur_e_series_entries, RobotEntry};
use tvist_core::modes::paper10::dynamic_map::PAPER_MAP_ROBOT;
use tvist_core::robot::model::Robot;
use tvist_core::{
    ConstantModes, DynamicMap, Interpolation, MapDynamics, ModalDynamics, Mode, Provider,
    RigidBody, ShaperKind, Status, StatusCounter, TvShaper, TvShaperConfig,
};

/// Largest number of joint channels a handle accepts (the core's limit).
pub const TVIST_MAX_DOF: usize = tvist_core::limits::MAX_DOF;
/// Largest number of modes of a shaper (one cascaded filter each; the core's limit, shared
/// by constant modes and map files).
pub const TVIST_MAX_MODES: usize = tvist_core::limits::MAX_MODES;
/// Largest total size of a handle's delay lines, bytes (the core's limit).
pub const TVIST_MAX_DELAY_LINE_BYTES: usize = tvist_core::limits::MAX_DELAY_LINE_BYTES;
/// Number of status flags (`tvist_shaper_status_counts`).
pub const TVIST_N_STATUS_FLAGS: usize = N_STATUS_FLAGS;
/// `TvistShaperOptions::interpolation`: linear (Lagrange order 1) fractional delays.
pub const TVIST_INTERP_LINEAR: i32 = 0;
/// `TvistShaperOptions::interpolation`: cubic (Lagrange order 3) fractional delays.
pub const TVIST_INTERP_CUBIC: i32 = 1;

/// Setup options of the `_ex` constructors. A zero-initialized struct holds the defaults.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TvistShaperOptions {
    /// [`TVIST_INTERP_LINEAR`] (0, default) or [`TVIST_INTERP_CUBIC`].
    pub interpolation: i32,
    /// Vibration tolerance of the `"ei"` shaper (fraction, e.g. 0.05); 0 for the default 5 %.
    /// Any other value with another shaper is an error.
    pub ei_tolerance: f64,
    /// Delay-line length over the longest expected shaper; 0 for the default 1.5.
    pub safety_factor: f64,
    /// Nonzero: accept a map identified on another robot (research use).
    pub allow_other_robot: i32,
}

/// An opaque shaper handle for C: one multi-mode FD-TVIST filter, its staging buffer and
/// the per-flag status counts.
///
/// A handle may move between threads but must not be used by two threads at once.
#[derive(Debug)]
pub struct TvistShaper {
    shaper: TvShaper<Provider>,
    /// Copy of the caller's input (`n_dof` values), so input and output may share memory.
    staging: Vec<f64>,
    counts: StatusCounter,
    /// How a map-driven handle was built, to build it again from another map file
    /// (`tvist_shaper_set_map`); `None` for constant modes.
    map_setup: Option<MapSetup>,
}

/// The robot, configuration and robot check a map-driven handle was built with.
#[derive(Debug, Clone)]
struct MapSetup {
    robot: Robot,
    config: TvShaperConfig,
    allow_other_robot: bool,
}

impl TvistShaper {
    fn new(shaper: TvShaper<Provider>, map_setup: Option<MapSetup>) -> TvistShaper {
        TvistShaper {
            staging: vec![0.0; shaper.n_dof()],
            shaper,
            counts: StatusCounter::default(),
            map_setup,
        }
    }

    /// Number of joint channels.
    pub fn n_dof(&self) -> usize {
        self.staging.len()
    }

    /// Current total delay of the cascade, s.
    pub fn delay_s(&self) -> f64 {
        self.shaper.delay_s()
    }

    /// Steps per status flag since construction.
    pub fn status_counts(&self) -> &StatusCounter {
        &self.counts
    }

    /// One control cycle on raw arrays; allocation-free.
    ///
    /// # Safety
    /// If `n_dof == self.n_dof()`, `q_in` must be readable and `q_out` writable for `n_dof`
    /// doubles (they may be the same array). Otherwise nothing is accessed.
    unsafe fn step_raw(&mut self, q_in: *const f64, q_out: *mut f64, n_dof: usize) -> i32 {
        if n_dof != self.n_dof() {
            self.counts.add(Status::BAD_LENGTH);
            return Status::BAD_LENGTH.0;
        }
        // SAFETY: `q_in` is readable for `n_dof` doubles (caller) and `staging` is our own
        // allocation of exactly `n_dof`, so the two cannot overlap.
        unsafe { ptr::copy_nonoverlapping(q_in, self.staging.as_mut_ptr(), n_dof) };
        // SAFETY: `q_out` is writable for `n_dof` doubles (caller); the input was copied
        // above, so this is the only live reference to that memory even if it is `q_in`.
        let q_out = unsafe { core::slice::from_raw_parts_mut(q_out, n_dof) };
        let status = self.shaper.step(&self.staging, q_out);
        self.counts.add(status);
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
        self.shaper.reset(&self.staging);
        TVIST_OK
    }
}

/// `TVIST_ERR_MID_MOVE` for the setup call `call` on a shaper whose delay lines are not at
/// rest on its input, with the message saying to call it between moves.
fn mid_move(call: &str) -> i32 {
    fail(
        TVIST_ERR_MID_MOVE,
        format!(
            "the shaper is mid-move (its delay lines are not at rest on the input); call {call} \
             between moves"
        ),
    )
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

/// C string `ptr` as a user typed it, in double quotes (`"ur6e"`); bytes that are not UTF-8
/// shown as U+FFFD.
///
/// # Safety
/// `ptr` is non-null and NUL-terminated.
unsafe fn quoted(ptr: *const c_char) -> String {
    // SAFETY: guaranteed by the caller.
    let text = unsafe { CStr::from_ptr(ptr) }.to_string_lossy();
    format!("{text:?}")
}

/// The options at `options`, or the defaults for a null pointer.
///
/// # Safety
/// `options` is null or readable (checked for alignment here).
unsafe fn read_options(options: *const TvistShaperOptions) -> Result<TvistShaperOptions, i32> {
    if options.is_null() {
        return Ok(TvistShaperOptions::default());
    }
    if !options.is_aligned() {
        return Err(fail(TVIST_ERR_NULL, "options is misaligned"));
    }
    // SAFETY: non-null, aligned and readable (caller).
    Ok(unsafe { options.read() })
}

/// The shaper configuration for `shaper_name` and `options` (setup errors recorded).
///
/// # Safety
/// `shaper_name` is non-null and NUL-terminated.
unsafe fn config(
    shaper_name: *const c_char,
    dt_s: f64,
    n_dof: usize,
    options: &TvistShaperOptions,
) -> Result<TvShaperConfig, i32> {
    // SAFETY: forwarded from the caller.
    let Some(name) = (unsafe { c_str(shaper_name) }) else {
        return Err(fail(
            TVIST_ERR_UNKNOWN_SHAPER,
            "the shaper name is not valid UTF-8",
        ));
    };
    let tolerance = (options.ei_tolerance != 0.0).then_some(options.ei_tolerance);
    let kind = ShaperKind::from_name(name, tolerance).map_err(|e| fail_with(&e))?;
    let mut config = TvShaperConfig::new(dt_s, n_dof, kind);
    config.interp = match options.interpolation {
        TVIST_INTERP_LINEAR => Interpolation::Linear,
        TVIST_INTERP_CUBIC => Interpolation::Cubic,
        other => {
            return Err(fail(
                TVIST_ERR_INVALID_PARAMETER,
                format!(
                    "interpolation = {other}: use TVIST_INTERP_LINEAR ({TVIST_INTERP_LINEAR}) \
                     or TVIST_INTERP_CUBIC ({TVIST_INTERP_CUBIC})"
                ),
            ))
        }
    };
    if options.safety_factor != 0.0 {
        config.safety_factor = options.safety_factor;
    }
    Ok(config)
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

/// Runs a constructor body: checks and nulls `out`, builds, publishes; never unwinds.
///
/// # Safety
/// `out` is null or writable when aligned.
unsafe fn construct(
    out: *mut *mut TvistShaper,
    body: impl FnOnce() -> Result<TvistShaper, i32>,
) -> i32 {
    guard(TVIST_ERR_INTERNAL, || {
        if !usable(out) {
            return fail(TVIST_ERR_NULL, "out is null or misaligned");
        }
        // SAFETY: `out` is non-null and aligned; the caller guarantees it is writable.
        unsafe { out.write(ptr::null_mut()) };
        let built = body();
        // SAFETY: `out` checked above.
        unsafe { publish(out, built) }
    })
}

/// A handle around a new [`TvShaper`] for `provider` (setup errors recorded).
fn build(
    provider: Provider,
    config: &TvShaperConfig,
    map_setup: Option<MapSetup>,
) -> Result<TvistShaper, i32> {
    let shaper = TvShaper::new(provider, config).map_err(|e| fail_with(&e))?;
    Ok(TvistShaper::new(shaper, map_setup))
}

/// The provider of the map in file `path` for `robot` (paper10 or modal; the file is fully
/// validated, setup errors recorded).
fn provider_from_file(robot: Robot, path: &str, allow_other_robot: bool) -> Result<Provider, i32> {
    let file = MapFile::load(Path::new(path)).map_err(|e| fail_with(&e))?;
    match file.into_form() {
        MapForm::Paper10(map) if allow_other_robot => {
            MapDynamics::new_allowing_other_robot(robot, map).map(|d| Provider::Map(Box::new(d)))
        }
        MapForm::Paper10(map) => MapDynamics::new(robot, map).map(|d| Provider::Map(Box::new(d))),
        MapForm::Modal(map) if allow_other_robot => {
            ModalDynamics::new_allowing_other_robot(robot, map)
                .map(|d| Provider::Modal(Box::new(d)))
        }
        MapForm::Modal(map) => ModalDynamics::new(robot, map).map(|d| Provider::Modal(Box::new(d))),
    }
    .map_err(|e| fail_with(&e))
}

/// The robot named by C string `robot_name`: an entry of the robot data (e-Series or
/// CB-series) or, for a name ending in `.json`, the one robot of that robot file (as
/// `tvist robot-file` writes it). Setup errors recorded.
///
/// # Safety
/// `robot_name` is non-null and NUL-terminated.
unsafe fn robot_entry(robot_name: *const c_char) -> Result<RobotEntry, i32> {
    let entries = ur_e_series_entries().map_err(|e| fail_with(&e))?;
    // SAFETY: forwarded from the caller.
    let name = unsafe { c_str(robot_name) };
    if let Some(path) = name.filter(|n| n.ends_with(".json")) {
        return robot_file(Path::new(path))
            .map_err(|e| fail(TVIST_ERR_UNKNOWN_ROBOT, e.to_string()));
    }
    entries
        .iter()
        .find(|e| Some(e.name.as_str()) == name)
        .cloned()
        .ok_or_else(|| {
            let known: Vec<&str> = entries.iter().map(|e| e.name.as_str()).collect();
            // SAFETY: forwarded from the caller.
            let shown = unsafe { quoted(robot_name) };
            fail(
                TVIST_ERR_UNKNOWN_ROBOT,
                format!(
                    "unknown robot {shown}; known: {} or a robot file (*.json)",
                    known.join(", ")
                ),
            )
        })
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
    // SAFETY: forwarded from the caller; null options are the defaults.
    unsafe {
        tvist_shaper_new_constant_ex(
            wn_rad_s,
            zeta,
            n_modes,
            dt_s,
            n_dof,
            shaper_name,
            ptr::null(),
            out,
        )
    }
}

/// [`tvist_shaper_new_constant`] with `options` (null: the defaults).
///
/// # Safety
/// As [`tvist_shaper_new_constant`]; `options` is null or readable.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn tvist_shaper_new_constant_ex(
    wn_rad_s: *const f64,
    zeta: *const f64,
    n_modes: usize,
    dt_s: f64,
    n_dof: usize,
    shaper_name: *const c_char,
    options: *const TvistShaperOptions,
    out: *mut *mut TvistShaper,
) -> i32 {
    // SAFETY: `out` forwarded from the caller.
    unsafe {
        construct(out, || {
            if !(usable(wn_rad_s) && usable(zeta) && !shaper_name.is_null()) {
                return Err(fail(
                    TVIST_ERR_NULL,
                    "wn_rad_s, zeta and shaper_name must be non-null (and aligned)",
                ));
            }
            // Before the arrays are read: the limit also bounds their byte size.
            tvist_core::limits::check_n_modes(n_modes, "the constant-mode request")
                .map_err(|e| fail_with(&e))?;
            let options = read_options(options)?;
            // SAFETY: `shaper_name` is non-null and NUL-terminated (caller).
            let config = config(shaper_name, dt_s, n_dof, &options)?;
            // SAFETY: both arrays are non-null, aligned and readable for `n_modes` doubles
            // (caller); `n_modes <= TVIST_MAX_MODES` keeps the byte size far below isize::MAX.
            let (wn, z) = (
                core::slice::from_raw_parts(wn_rad_s, n_modes),
                core::slice::from_raw_parts(zeta, n_modes),
            );
            let modes = wn.iter().zip(z).map(|(&w, &z)| Mode::new(w, z)).collect();
            let dynamics = ConstantModes::new(modes).map_err(|e| fail_with(&e))?;
            build(Provider::Constant(dynamics), &config, None)
        })
    }
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
    // SAFETY: `out` forwarded from the caller.
    unsafe {
        construct(out, || {
            if robot_name.is_null() || shaper_name.is_null() || !usable(payload_com_m) {
                return Err(fail(
                    TVIST_ERR_NULL,
                    "robot_name, payload_com_m and shaper_name must be non-null (and aligned)",
                ));
            }
            // SAFETY: non-null and NUL-terminated (caller).
            if c_str(robot_name) != Some(PAPER_MAP_ROBOT) {
                let shown = quoted(robot_name);
                return Err(fail(
                    TVIST_ERR_UNKNOWN_ROBOT,
                    format!(
                        "robot {shown}: the paper's dynamic map is identified for \
                         {PAPER_MAP_ROBOT:?} only; use tvist_shaper_new_map with a map file \
                         for other robots"
                    ),
                ));
            }
            // SAFETY: non-null, aligned and readable for 3 doubles (caller).
            let com_m = payload_com_m.cast::<[f64; 3]>().read();
            let entry = robot_entry(robot_name)?;
            let robot = entry
                .robot(RigidBody::point(payload_kg, com_m))
                .map_err(|e| fail_with(&e))?;
            let config = config(
                shaper_name,
                dt_s,
                robot.n_dof(),
                &TvistShaperOptions::default(),
            )?;
            let setup = MapSetup {
                robot: robot.clone(),
                config,
                allow_other_robot: false,
            };
            let dynamics =
                MapDynamics::new(robot, DynamicMap::paper_ur5e()).map_err(|e| fail_with(&e))?;
            let config = setup.config.clone();
            build(Provider::Map(Box::new(dynamics)), &config, Some(setup))
        })
    }
}

/// Creates a shaper driven by the map in file `map_json_path` (any map file tvist writes:
/// `tvist fit-map`, `DynamicMap.save`, `ModalMap.save`; a `"kind": "modal"` file drives the
/// modal provider, which solves the mass-matrix eigenproblem every cycle) for robot
/// `robot_name` (e-Series `"ur3e"`, `"ur5e"`, `"ur10e"`, `"ur16e"`, `"ur20"`, CB-series
/// `"ur3"`, `"ur5"`, `"ur10"`, or the path of a robot file ending in `.json`) with a point
/// payload of `payload_kg` at
/// `payload_com_m` (flange frame, m), shaping its joints sampled every `dt_s` seconds.
///
/// Returns as [`tvist_shaper_new_constant`]; `TVIST_ERR_UNKNOWN_ROBOT` for an unknown robot,
/// `TVIST_ERR_MAP_FILE` for a file that cannot be read or is not a valid map,
/// `TVIST_ERR_ROBOT_MISMATCH` for a map identified on another robot.
///
/// # Safety
/// `robot_name`, `map_json_path` and `shaper_name` are NUL-terminated strings;
/// `payload_com_m` is readable for 3 doubles; `out` is writable.
#[no_mangle]
pub unsafe extern "C" fn tvist_shaper_new_map(
    robot_name: *const c_char,
    payload_kg: f64,
    payload_com_m: *const f64,
    map_json_path: *const c_char,
    dt_s: f64,
    shaper_name: *const c_char,
    out: *mut *mut TvistShaper,
) -> i32 {
    // SAFETY: forwarded from the caller; null options are the defaults.
    unsafe {
        tvist_shaper_new_map_ex(
            robot_name,
            payload_kg,
            payload_com_m,
            map_json_path,
            dt_s,
            shaper_name,
            ptr::null(),
            out,
        )
    }
}

/// [`tvist_shaper_new_map`] with `options` (null: the defaults).
///
/// # Safety
/// As [`tvist_shaper_new_map`]; `options` is null or readable.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn tvist_shaper_new_map_ex(
    robot_name: *const c_char,
    payload_kg: f64,
    payload_com_m: *const f64,
    map_json_path: *const c_char,
    dt_s: f64,
    shaper_name: *const c_char,
    options: *const TvistShaperOptions,
    out: *mut *mut TvistShaper,
) -> i32 {
    // SAFETY: `out` forwarded from the caller.
    unsafe {
        construct(out, || {
            if robot_name.is_null()
                || map_json_path.is_null()
                || shaper_name.is_null()
                || !usable(payload_com_m)
            {
                return Err(fail(
                    TVIST_ERR_NULL,
                    "robot_name, payload_com_m, map_json_path and shaper_name must be \
                     non-null (and aligned)",
                ));
            }
            let options = read_options(options)?;
            // SAFETY: non-null and NUL-terminated (caller).
            let entry = robot_entry(robot_name)?;
            // SAFETY: non-null, aligned and readable for 3 doubles (caller).
            let com_m = payload_com_m.cast::<[f64; 3]>().read();
            let robot = entry
                .robot(RigidBody::point(payload_kg, com_m))
                .map_err(|e| fail_with(&e))?;
            // SAFETY: non-null and NUL-terminated (caller).
            let config = config(shaper_name, dt_s, robot.n_dof(), &options)?;
            // SAFETY: non-null and NUL-terminated (caller).
            let Some(path) = c_str(map_json_path) else {
                return Err(fail(TVIST_ERR_MAP_FILE, "map_json_path is not valid UTF-8"));
            };
            let setup = MapSetup {
                robot: robot.clone(),
                config,
                allow_other_robot: options.allow_other_robot != 0,
            };
            let provider = provider_from_file(robot, path, setup.allow_other_robot)?;
            let config = setup.config.clone();
            build(provider, &config, Some(setup))
        })
    }
}

/// Replaces the map of a map-driven shaper (`tvist_shaper_new_map`, `tvist_shaper_new_ur_map`)
/// by the map in file `map_json_path`, keeping its robot, payload, shaper, `dt_s` and options.
/// A setup call: it reads and validates the file as `tvist_shaper_new_map` does and allocates
/// new delay lines; never call it from the control loop.
///
/// Only between moves: the shaper must not have started, or every delay line must hold one
/// value per channel along its whole length (the input unchanged for longer than the longest
/// delay it can read, every filter output constant). The new map then starts at rest on the
/// held input, so the next move is shaped exactly as a new shaper built from that file would
/// shape it.
///
/// Returns `TVIST_OK`; `TVIST_ERR_MID_MOVE` mid-move; `TVIST_ERR_INVALID_PARAMETER` for a
/// shaper of constant modes; the codes of `tvist_shaper_new_map` for an invalid file
/// (`TVIST_ERR_MAP_FILE`, `TVIST_ERR_ROBOT_MISMATCH`, …); `TVIST_ERR_NULL`. On every error
/// the shaper is unchanged and the reason is in `tvist_last_error_message`.
///
/// # Safety
/// `shaper` comes from a constructor and is not freed; `map_json_path` is a NUL-terminated
/// string.
#[no_mangle]
pub unsafe extern "C" fn tvist_shaper_set_map(
    shaper: *mut TvistShaper,
    map_json_path: *const c_char,
) -> i32 {
    guard(TVIST_ERR_INTERNAL, || {
        if !usable(shaper) || map_json_path.is_null() {
            return fail(
                TVIST_ERR_NULL,
                "shaper and map_json_path must be non-null (and aligned)",
            );
        }
        // SAFETY: a live handle from a constructor (caller), used by this thread only.
        let handle = unsafe { &mut *shaper };
        let Some(setup) = handle.map_setup.clone() else {
            return fail(
                TVIST_ERR_INVALID_PARAMETER,
                "this shaper has constant modes; tvist_shaper_set_map replaces the map of a \
                 shaper from tvist_shaper_new_map",
            );
        };
        if !handle.shaper.is_at_rest() {
            return mid_move("tvist_shaper_set_map");
        }
        // SAFETY: non-null and NUL-terminated (caller).
        let Some(path) = (unsafe { c_str(map_json_path) }) else {
            return fail(TVIST_ERR_MAP_FILE, "map_json_path is not valid UTF-8");
        };
        let provider = match provider_from_file(setup.robot, path, setup.allow_other_robot) {
            Ok(provider) => provider,
            Err(code) => return code,
        };
        match handle.shaper.replace_dynamics(provider, &setup.config) {
            Ok(()) => TVIST_OK,
            Err(e) => fail_with(&e),
        }
    })
}

/// Shapes the `n_modes` lowest-frequency modes of the shaper's modal map from the next move
/// on (the map's flexible joints, frequency-ranked as `"shaped_modes": n_modes` in a map
/// file, whatever modes the map shaped before), one cascaded filter each: the added delay is
/// that of those modes. `1 <= n_modes <=` the map's number of flexible joints. A setup call
/// (it builds a new provider and delay lines, sampling the workspace as a constructor does);
/// never call it from the control loop.
///
/// Only between moves, as `tvist_shaper_set_map`. Returns `TVIST_OK`; `TVIST_ERR_MID_MOVE`
/// mid-move; `TVIST_ERR_INVALID_PARAMETER` for a shaper not driven by a modal map or
/// `n_modes` out of range; `TVIST_ERR_NULL`. On every error the shaper is unchanged and the
/// reason is in `tvist_last_error_message`.
///
/// # Safety
/// `shaper` comes from a constructor and is not freed.
#[no_mangle]
pub unsafe extern "C" fn tvist_shaper_set_shaped_modes(
    shaper: *mut TvistShaper,
    n_modes: usize,
) -> i32 {
    guard(TVIST_ERR_INTERNAL, || {
        if !usable(shaper) {
            return fail(TVIST_ERR_NULL, "shaper must be non-null (and aligned)");
        }
        // SAFETY: a live handle from a constructor (caller), used by this thread only.
        let handle = unsafe { &mut *shaper };
        if !matches!(handle.shaper.dynamics(), Provider::Modal(_)) {
            return fail(
                TVIST_ERR_INVALID_PARAMETER,
                "this shaper is not driven by a modal map; tvist_shaper_set_shaped_modes sets \
                 the number of shaped modes of a shaper from a \"kind\": \"modal\" map file",
            );
        }
        if !handle.shaper.is_at_rest() {
            return mid_move("tvist_shaper_set_shaped_modes");
        }
        match handle.shaper.set_shaped_modes(n_modes) {
            Ok(()) => TVIST_OK,
            Err(e) => fail_with(&e),
        }
    })
}

/// Shapes from the next move on with the modes the shaper's map gives at the pose `q`
/// (`n_dof` doubles, the robot's joints in rad), held constant instead of followed cycle by
/// cycle; `q` null follows the pose of every cycle again. For a move whose time-varying
/// shaping leaves more ringing than the modes of its stop pose do: pass the move's end pose
/// (the Python toolbox's `set_modes_for_move` predicts which). `tvist_shaper_set_map` and
/// `tvist_shaper_set_shaped_modes` also end a hold. A setup call (it builds a new provider and
/// delay lines); never call it from the control loop.
///
/// Only between moves, as `tvist_shaper_set_map`. Returns `TVIST_OK`; `TVIST_ERR_MID_MOVE`
/// mid-move; `TVIST_ERR_DIMENSION_MISMATCH` for `n_dof` other than the handle's (nothing
/// read); `TVIST_ERR_INVALID_PARAMETER` for a shaper not driven by a map or a pose where the
/// map gives an invalid mode; `TVIST_ERR_NULL`. On every error the shaper is unchanged and
/// the reason is in `tvist_last_error_message`.
///
/// # Safety
/// `shaper` comes from a constructor and is not freed; `q` is null or readable for `n_dof`
/// doubles.
#[no_mangle]
pub unsafe extern "C" fn tvist_shaper_hold_modes_at(
    shaper: *mut TvistShaper,
    q: *const f64,
    n_dof: usize,
) -> i32 {
    guard(TVIST_ERR_INTERNAL, || {
        if !usable(shaper) || (!q.is_null() && !usable(q)) {
            return fail(
                TVIST_ERR_NULL,
                "shaper must be non-null (and aligned), q aligned",
            );
        }
        // SAFETY: a live handle from a constructor (caller), used by this thread only.
        let handle = unsafe { &mut *shaper };
        if !matches!(
            handle.shaper.dynamics(),
            Provider::Map(_) | Provider::Modal(_)
        ) {
            return fail(
                TVIST_ERR_INVALID_PARAMETER,
                "this shaper is not driven by a map; tvist_shaper_hold_modes_at holds the modes \
                 of a shaper from a map file",
            );
        }
        let pose = if q.is_null() {
            None
        } else {
            if n_dof != handle.n_dof() {
                return fail(
                    TVIST_ERR_DIMENSION_MISMATCH,
                    format!("the pose has {n_dof} joints, the shaper {}", handle.n_dof()),
                );
            }
            // SAFETY: `q` is readable for `n_dof` doubles (caller).
            Some(unsafe { core::slice::from_raw_parts(q, n_dof) })
        };
        if !handle.shaper.is_at_rest() {
            return mid_move("tvist_shaper_hold_modes_at");
        }
        match handle.shaper.hold_modes_at(pose) {
            Ok(()) => TVIST_OK,
            Err(e) => fail_with(&e),
        }
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

/// Copies the per-flag status counts of `shaper` into `counts` (`len` entries): `counts[k]` is
/// the number of `tvist_shaper_step` calls since construction whose status had bit `1 << k`
/// set (`TVIST_STATUS_INPUT_HELD` is k = 0, ...). Writes `min(len, TVIST_N_STATUS_FLAGS)`
/// entries and returns `TVIST_N_STATUS_FLAGS` (0 for a null handle). Allocation-free.
///
/// # Safety
/// `shaper` is null or comes from a constructor and is not freed; `counts` is null (then
/// `len` must be 0) or writable for `len` values.
#[no_mangle]
pub unsafe extern "C" fn tvist_shaper_status_counts(
    shaper: *const TvistShaper,
    counts: *mut u64,
    len: usize,
) -> usize {
    guard(0, || {
        if !usable(shaper) {
            return 0;
        }
        // SAFETY: a live handle from a constructor (caller).
        let all = unsafe { &*shaper }.status_counts().counts();
        if usable(counts) {
            let n = len.min(all.len());
            // SAFETY: writable for `len >= n` values (caller); our counts are our own memory.
            unsafe { ptr::copy_nonoverlapping(all.as_ptr(), counts, n) };
        }
        TVIST_N_STATUS_FLAGS
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
