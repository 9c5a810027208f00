//! Return codes of the C API and the thread-local text of the last setup error.
//!
//! Setup and housekeeping calls return `TVIST_OK` (0) or one of the negative `TVIST_ERR_*`
//! codes below; `tvist_shaper_step` returns the core's [`tvist_core::Status`] bits (>= 0) or a
//! negative code. The values are part of the ABI and mirrored in `include/tvist.h`.

use std::cell::RefCell;
use std::panic::{catch_unwind, AssertUnwindSafe};
use tvist_core::Error;

/// Success.
pub const TVIST_OK: i32 = 0;
/// A required pointer is null or not aligned for its type.
pub const TVIST_ERR_NULL: i32 = -1;
/// The shaper name is not in the registry (`zv`, `zvd`, `zvdd`, `mzv`, `ei`, `2hump_ei`,
/// `3hump_ei`) or is not valid UTF-8.
pub const TVIST_ERR_UNKNOWN_SHAPER: i32 = -2;
/// A parameter outside its domain (`dt_s <= 0`, `n_dof == 0`, no modes, bad payload, …).
pub const TVIST_ERR_INVALID_PARAMETER: i32 = -3;
/// A mode `(wn_rad_s, zeta)` that is not finite, has `wn_rad_s <= 0` or `zeta` outside `[0, 1)`.
pub const TVIST_ERR_INVALID_MODE: i32 = -4;
/// An array length that does not match the shaper (for example `n_dof` of a reset).
pub const TVIST_ERR_DIMENSION_MISMATCH: i32 = -5;
/// A robot name without a dynamic map (the paper's map is identified for `"ur5e"` only).
pub const TVIST_ERR_UNKNOWN_ROBOT: i32 = -6;
/// An internal error was caught at the boundary (a bug: please report it). The handle it
/// happened on must not be used again except to free it.
pub const TVIST_ERR_INTERNAL: i32 = -7;
/// A map file that cannot be read or is not a valid map (the message names the field).
pub const TVIST_ERR_MAP_FILE: i32 = -8;
/// A map identified on another robot than the one named (the message names both).
pub const TVIST_ERR_ROBOT_MISMATCH: i32 = -9;
/// A request beyond a setup limit (`TVIST_MAX_DOF` channels, `TVIST_MAX_MODES` modes,
/// `TVIST_MAX_DELAY_LINE_BYTES` of delay lines): refused before anything is allocated.
pub const TVIST_ERR_TOO_LARGE: i32 = -10;
/// `tvist_shaper_set_map`, `tvist_shaper_set_shaped_modes` or `tvist_shaper_hold_modes_at` on
/// a shaper mid-move (its delay lines not at rest on the input).
pub const TVIST_ERR_MID_MOVE: i32 = -11;

/// Every error code with its C name, for the header-consistency test and documentation.
pub const ERROR_CODES: [(&str, i32); 12] = [
    ("TVIST_OK", TVIST_OK),
    ("TVIST_ERR_NULL", TVIST_ERR_NULL),
    ("TVIST_ERR_UNKNOWN_SHAPER", TVIST_ERR_UNKNOWN_SHAPER),
    ("TVIST_ERR_INVALID_PARAMETER", TVIST_ERR_INVALID_PARAMETER),
    ("TVIST_ERR_INVALID_MODE", TVIST_ERR_INVALID_MODE),
    ("TVIST_ERR_DIMENSION_MISMATCH", TVIST_ERR_DIMENSION_MISMATCH),
    ("TVIST_ERR_UNKNOWN_ROBOT", TVIST_ERR_UNKNOWN_ROBOT),
    ("TVIST_ERR_INTERNAL", TVIST_ERR_INTERNAL),
    ("TVIST_ERR_MAP_FILE", TVIST_ERR_MAP_FILE),
    ("TVIST_ERR_ROBOT_MISMATCH", TVIST_ERR_ROBOT_MISMATCH),
    ("TVIST_ERR_TOO_LARGE", TVIST_ERR_TOO_LARGE),
    ("TVIST_ERR_MID_MOVE", TVIST_ERR_MID_MOVE),
];

/// The C code of a core setup error.
pub fn error_code(error: &Error) -> i32 {
    match error {
        Error::UnknownShaper(_) => TVIST_ERR_UNKNOWN_SHAPER,
        Error::InvalidMode { .. } => TVIST_ERR_INVALID_MODE,
        Error::DimensionMismatch { .. } => TVIST_ERR_DIMENSION_MISMATCH,
        Error::InvalidParameter(_)
        | Error::UnknownInterpolation(_)
        | Error::InvalidImpulses(_)
        | Error::UnknownDelayBound => TVIST_ERR_INVALID_PARAMETER,
        Error::Document { .. } => TVIST_ERR_MAP_FILE,
        Error::RobotMismatch { .. } => TVIST_ERR_ROBOT_MISMATCH,
        Error::TooLarge(_) => TVIST_ERR_TOO_LARGE,
    }
}

thread_local! {
    /// Text of the latest failed setup call on this thread (empty if none).
    static LAST_ERROR: RefCell<String> = const { RefCell::new(String::new()) };
}

/// Records `message` as this thread's last error and returns `code` (setup paths only: this
/// allocates).
pub fn fail(code: i32, message: impl Into<String>) -> i32 {
    let message = message.into();
    // A thread being torn down has no slot left; the code alone is returned then.
    let _ = LAST_ERROR.try_with(|slot| {
        if let Ok(mut slot) = slot.try_borrow_mut() {
            *slot = message;
        }
    });
    code
}

/// Records a core error and returns its code.
pub fn fail_with(error: &Error) -> i32 {
    fail(error_code(error), error.to_string())
}

/// Copies this thread's last error text into `buf` (at most `buf.len() - 1` bytes, cut at a
/// character boundary, then a NUL) and returns the full length of the text in bytes.
pub fn copy_last_error(buf: &mut [u8]) -> usize {
    LAST_ERROR
        .try_with(|slot| {
            let Ok(text) = slot.try_borrow() else {
                return 0;
            };
            if let Some(room) = buf.len().checked_sub(1) {
                let mut n = text.len().min(room);
                while !text.is_char_boundary(n) {
                    n -= 1;
                }
                buf[..n].copy_from_slice(&text.as_bytes()[..n]);
                buf[n] = 0;
            }
            text.len()
        })
        .unwrap_or(0)
}

/// Runs `f`, turning a panic into `on_panic`: no unwinding ever crosses the C boundary.
///
/// Allocation-free unless `f` panics.
#[inline]
pub fn guard<T>(on_panic: T, f: impl FnOnce() -> T) -> T {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or(on_panic)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_becomes_the_fallback_value() {
        assert_eq!(guard(TVIST_OK, || TVIST_ERR_NULL), TVIST_ERR_NULL);
        #[allow(clippy::panic)]
        let caught = guard(TVIST_ERR_INTERNAL, || {
            panic!("deliberate panic of the guard test")
        });
        assert_eq!(caught, TVIST_ERR_INTERNAL);
    }

    #[test]
    fn every_core_error_maps_to_a_distinct_documented_code() {
        let cases = [
            (Error::UnknownShaper("x".into()), TVIST_ERR_UNKNOWN_SHAPER),
            (
                Error::InvalidMode {
                    index: 0,
                    wn_rad_s: -1.0,
                    zeta: 0.0,
                },
                TVIST_ERR_INVALID_MODE,
            ),
            (
                Error::DimensionMismatch {
                    what: "x",
                    expected: 1,
                    got: 2,
                },
                TVIST_ERR_DIMENSION_MISMATCH,
            ),
            (
                Error::InvalidParameter("x".into()),
                TVIST_ERR_INVALID_PARAMETER,
            ),
            (Error::UnknownDelayBound, TVIST_ERR_INVALID_PARAMETER),
            (Error::document("modes", "missing"), TVIST_ERR_MAP_FILE),
            (
                Error::RobotMismatch {
                    map_robot: "ur5e".into(),
                    robot: "ur10e".into(),
                },
                TVIST_ERR_ROBOT_MISMATCH,
            ),
            (Error::TooLarge("x".into()), TVIST_ERR_TOO_LARGE),
        ];
        for (error, code) in cases {
            assert_eq!(error_code(&error), code, "{error}");
            assert!(ERROR_CODES.iter().any(|&(_, c)| c == code));
        }
        let mut values: Vec<i32> = ERROR_CODES.iter().map(|&(_, c)| c).collect();
        values.sort_unstable();
        values.dedup();
        assert_eq!(values.len(), ERROR_CODES.len(), "codes must be distinct");
    }

    #[test]
    fn last_error_text_is_truncated_at_a_character_boundary_and_terminated() {
        // "ζ" is two bytes in UTF-8: a 3-byte buffer holds "a" and not half of it.
        fail(TVIST_ERR_INVALID_MODE, "aζb");
        let mut buf = [0xffu8; 3];
        assert_eq!(copy_last_error(&mut buf), 4);
        assert_eq!(&buf[..2], b"a\0");
        let mut big = [0xffu8; 16];
        assert_eq!(copy_last_error(&mut big), 4);
        assert_eq!(&big[..5], "aζb\0".as_bytes());
        assert_eq!(
            copy_last_error(&mut []),
            4,
            "an empty buffer gets the length only"
        );
    }
}
