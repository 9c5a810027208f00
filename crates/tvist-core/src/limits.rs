//! Resource limits checked at setup, shared by every binding (Rust, Python, C).
//!
//! A request beyond a limit is refused with [`Error::TooLarge`] (or, inside a map file, an
//! [`Error::Document`] naming the field) before anything is allocated, so no input can make
//! setup abort the process on a failed allocation or build a shaper too slow for its cycle.

use crate::error::Error;

/// Largest number of joint channels of a shaper.
pub const MAX_DOF: usize = 4096;

/// Largest total size of a shaper's delay lines, bytes (256 MiB). A 6-DOF shaper at 500 Hz
/// holding 10 s of delay needs 6 · 5000 · 8 B = 240 kB per mode; the limit is reached only
/// by requests like `n_dof = 4096` with a 0.1 rad/s mode at 100 kHz (~154 GB).
pub const MAX_DELAY_LINE_BYTES: usize = 256 * 1024 * 1024;

/// Largest number of modes of a shaper, a dynamic map or a map file (one cascaded filter
/// per mode, evaluated every cycle). A robot arm has one structural mode per flexible joint
/// worth shaping (at most [`crate::modes::modal::modal_map::MAX_FLEX_JOINTS`] = 9 flexible coordinates in the modal map, 2 in
/// the published map); 64 leaves an order of magnitude of room while keeping the cycle cost
/// bounded (each mode costs one filter update per channel per cycle: 64 constant modes on 6
/// channels take about 2.5 µs per cycle, measured with the Python `TvShaper.shape`).
pub const MAX_MODES: usize = 64;

/// Largest map file read, bytes (1 MiB). A `paper10` mode takes about 0.4 kB of the indented
/// JSON tvist writes ([`MAX_MODES`] modes: 25 kB), fit statistics a few kB more: 1 MiB is
/// some 40 times the largest map. A longer file is not a map and is refused after reading at
/// most this many bytes (a device such as `/dev/zero` or a huge file is never read whole).
pub const MAX_MAP_FILE_BYTES: u64 = 1 << 20;

/// Refuses `n_dof` above [`MAX_DOF`].
pub fn check_n_dof(n_dof: usize) -> Result<(), Error> {
    if n_dof > MAX_DOF {
        return Err(Error::TooLarge(format!(
            "n_dof = {n_dof} exceeds the limit of {MAX_DOF} channels"
        )));
    }
    Ok(())
}

/// Refuses more than [`MAX_MODES`] modes; `what` names their owner ("a dynamic map").
pub fn check_n_modes(n_modes: usize, what: &str) -> Result<(), Error> {
    if n_modes > MAX_MODES {
        return Err(Error::TooLarge(format!(
            "{what} has {n_modes} modes, more than the limit of {MAX_MODES}"
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ConstantModes, Dynamics, Mode, ShaperKind, Status, TvShaper, TvShaperConfig};

    /// A provider of `n` fixed modes that does not check their number itself (as a binding's
    /// callback provider does not).
    #[derive(Debug)]
    struct Many(usize);

    impl Dynamics for Many {
        fn n_modes(&self) -> usize {
            self.0
        }
        fn modes(&mut self, _q: &[f64], out: &mut [Mode]) -> Status {
            out.fill(Mode::new(60.0, 0.05));
            Status::OK
        }
        fn slowest_mode(&self, _index: usize) -> Option<Mode> {
            Some(Mode::new(60.0, 0.05))
        }
    }

    #[test]
    fn every_way_to_more_modes_than_the_limit_is_refused() {
        let mode = Mode::new(60.0, 0.05);
        assert!(ConstantModes::new(vec![mode; MAX_MODES]).is_ok());
        let err = ConstantModes::new(vec![mode; MAX_MODES + 1]).expect_err("too many");
        assert!(matches!(err, Error::TooLarge(_)), "{err}");
        let config = TvShaperConfig::new(0.002, 1, ShaperKind::Zv);
        assert!(TvShaper::new(Many(MAX_MODES), &config).is_ok());
        let err = TvShaper::new(Many(MAX_MODES + 1), &config).expect_err("too many");
        assert_eq!(
            err.to_string(),
            "setup request too large: the dynamics provider has 65 modes, more than the \
             limit of 64"
        );
    }
}
