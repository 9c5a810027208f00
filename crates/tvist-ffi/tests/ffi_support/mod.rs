//! Helpers shared by the C-API integration tests: C strings, the last error text, an owning
//! handle, and the payload and control period both test files build shapers with.

#![allow(dead_code)]

use std::ffi::{c_char, CStr, CString};
use tvist::{
    tvist_last_error_message, tvist_shaper_delay_s, tvist_shaper_free, tvist_shaper_step,
    TvistShaper,
};

/// Point payload mass (kg) of the test robots.
pub const PAYLOAD_KG: f64 = 5.0;
/// Payload centre of mass in the flange frame (m): 5 cm along flange z.
pub const PAYLOAD_COM_M: [f64; 3] = [0.0, 0.0, 0.05];
/// Control period (s).
pub const DT_S: f64 = 0.002;

/// `text` as a C string; panics on an interior NUL.
pub fn c(text: &str) -> CString {
    CString::new(text).expect("no interior NUL")
}

/// This thread's last error text, through the C function.
pub fn last_error() -> String {
    let mut buf = [0 as c_char; 1024];
    // SAFETY: `buf` is writable for its length.
    unsafe { tvist_last_error_message(buf.as_mut_ptr(), buf.len()) };
    // SAFETY: the function NUL-terminates a non-empty buffer.
    unsafe { CStr::from_ptr(buf.as_ptr()) }
        .to_string_lossy()
        .into_owned()
}

/// Owns a handle from a constructor (or null); frees it on drop.
pub struct Handle(pub *mut TvistShaper);

impl Drop for Handle {
    fn drop(&mut self) {
        // SAFETY: from a constructor (or null), freed exactly once here.
        unsafe { tvist_shaper_free(self.0) };
    }
}

impl Handle {
    /// One control step; returns the status bits.
    pub fn step(&mut self, q_in: &[f64], q_out: &mut [f64]) -> i32 {
        assert_eq!(q_in.len(), q_out.len());
        // SAFETY: live handle; both arrays hold `q_in.len()` doubles.
        unsafe { tvist_shaper_step(self.0, q_in.as_ptr(), q_out.as_mut_ptr(), q_in.len()) }
    }

    /// The shaper's current delay (s).
    pub fn delay_s(&self) -> f64 {
        // SAFETY: live handle.
        unsafe { tvist_shaper_delay_s(self.0) }
    }
}
