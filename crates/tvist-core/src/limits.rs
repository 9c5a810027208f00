//! Resource limits checked at setup, shared by every binding (Rust, Python, C).
//!
//! A request beyond a limit is refused with [`Error::TooLarge`] before anything is
//! allocated, so no input can make setup abort the process on a failed allocation.

use crate::error::Error;

/// Largest number of joint channels of a shaper.
pub const MAX_DOF: usize = 4096;

/// Largest total size of a shaper's delay lines, bytes (256 MiB). A 6-DOF shaper at 500 Hz
/// holding 10 s of delay needs 6 · 5000 · 8 B = 240 kB per mode; the limit is reached only
/// by requests like `n_dof = 4096` with a 0.1 rad/s mode at 100 kHz (~154 GB).
pub const MAX_DELAY_LINE_BYTES: usize = 256 * 1024 * 1024;

/// Refuses `n_dof` above [`MAX_DOF`].
pub fn check_n_dof(n_dof: usize) -> Result<(), Error> {
    if n_dof > MAX_DOF {
        return Err(Error::TooLarge(format!(
            "n_dof = {n_dof} exceeds the limit of {MAX_DOF} channels"
        )));
    }
    Ok(())
}

/// Refuses a total delay-line size above [`MAX_DELAY_LINE_BYTES`]; `bytes` is `None` when
/// the size does not even fit in a `usize`.
pub fn check_delay_line_bytes(bytes: Option<usize>, what: &str) -> Result<(), Error> {
    match bytes {
        Some(b) if b <= MAX_DELAY_LINE_BYTES => Ok(()),
        _ => Err(Error::TooLarge(format!(
            "{what} would need {} of delay lines, more than the limit of {} MiB; use fewer \
             channels, a higher minimum frequency or a longer sample time",
            bytes.map_or_else(|| "more than usize::MAX bytes".to_string(), human_bytes),
            MAX_DELAY_LINE_BYTES >> 20
        ))),
    }
}

fn human_bytes(bytes: usize) -> String {
    let b = bytes as f64;
    if b >= 1e9 {
        format!("{:.1} GB", b / 1e9)
    } else {
        format!("{:.1} MB", b / 1e6)
    }
}
