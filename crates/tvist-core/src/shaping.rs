//! Input shaping of one mode at a time: the shaper library, the exact EI design, residual
//! vibration, the fractional delay line, the single-mode time-varying filter and zero-delay
//! shaping.

pub mod delay_line;
pub mod ei;
pub(crate) mod held_input;
pub mod mode_filter;
pub mod prv;
pub mod shaper_names;
pub mod shapers;
pub mod ztdis;
