//! C API of tvist-core: run the multi-mode time-varying input shaper from a C/C++ controller.
//!
//! The declarations are in `include/tvist.h`; build with `cargo build -p tvist-ffi --release`
//! and link `target/release/libtvist.a` (static) or `libtvist.so` (shared).
//!
//! - [`codes`]: return codes and the thread-local text of the last setup error.
//! - [`shaper`]: the opaque `TvistShaper` handle and its functions.
//!
//! No panic unwinds into C: every function runs inside [`codes::guard`]. Per-cycle calls
//! (`tvist_shaper_step`) never allocate or lock.

pub mod codes;
pub mod shaper;

pub use codes::*;
pub use shaper::*;
