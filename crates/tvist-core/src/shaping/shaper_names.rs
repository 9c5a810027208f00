//! The names of the registry's shapers ([`crate::ShaperKind`]), with no dependencies: the
//! error type lists them without depending on the shaper library.

/// Registry names, in the order documented to users.
pub const SHAPER_NAMES: [&str; 7] = ["zv", "zvd", "zvdd", "mzv", "ei", "2hump_ei", "3hump_ei"];
