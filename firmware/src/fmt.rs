//! Crate-private logging macros, after embassy's `fmt.rs`.
//!
//! `trace!` .. `error!` forward to [`defmt`](https://defmt.ferrous-systems.com) when the `defmt`
//! feature is on *and* the build is for a bare-metal target (`target_os = "none"`), where the defmt
//! dependency exists. Everywhere else (host tests, the `flinch hil` harness) they expand to nothing but
//! still type-check their arguments, so the same code builds on the MCU and on the host without link
//! errors about a missing global logger.
#![allow(unused_macros)]
// Used through `#[macro_use]` on the module in lib.rs, which must come before every other module.

#[cfg(all(feature = "defmt", target_os = "none"))]
macro_rules! trace { ($($x:tt)*) => { ::defmt::trace!($($x)*) }; }
#[cfg(all(feature = "defmt", target_os = "none"))]
macro_rules! debug { ($($x:tt)*) => { ::defmt::debug!($($x)*) }; }
#[cfg(all(feature = "defmt", target_os = "none"))]
macro_rules! info { ($($x:tt)*) => { ::defmt::info!($($x)*) }; }
#[cfg(all(feature = "defmt", target_os = "none"))]
macro_rules! warn { ($($x:tt)*) => { ::defmt::warn!($($x)*) }; }
#[cfg(all(feature = "defmt", target_os = "none"))]
macro_rules! error { ($($x:tt)*) => { ::defmt::error!($($x)*) }; }

// Without defmt: evaluate nothing at run time, but keep the arguments "used" so that a variable that
// exists only for logging does not raise a warning in one configuration and not the other.
#[cfg(not(all(feature = "defmt", target_os = "none")))]
macro_rules! trace { ($s:literal $(, $x:expr)* $(,)?) => { { $( let _ = &$x; )* } }; }
#[cfg(not(all(feature = "defmt", target_os = "none")))]
macro_rules! debug { ($s:literal $(, $x:expr)* $(,)?) => { { $( let _ = &$x; )* } }; }
#[cfg(not(all(feature = "defmt", target_os = "none")))]
macro_rules! info { ($s:literal $(, $x:expr)* $(,)?) => { { $( let _ = &$x; )* } }; }
#[cfg(not(all(feature = "defmt", target_os = "none")))]
macro_rules! warn { ($s:literal $(, $x:expr)* $(,)?) => { { $( let _ = &$x; )* } }; }
#[cfg(not(all(feature = "defmt", target_os = "none")))]
macro_rules! error { ($s:literal $(, $x:expr)* $(,)?) => { { $( let _ = &$x; )* } }; }
