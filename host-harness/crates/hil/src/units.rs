//! SI values in the firmware's integer micro-units (um, um/s, us, ...), rounded the safe way for
//! each: what lengthens a stop (speed, dead time) up, what shortens it or bounds it (deceleration,
//! stroke) down. `flinch check`'s budget and the firmware in the loop use the same rounding.

/// Micro-units rounded up: for what lengthens the stopping distance (speed, dead time), so the
/// integer budget never under-estimates it.
pub fn um_up(x: f64) -> u32 {
    (x * 1e6).ceil().clamp(0.0, u32::MAX as f64) as u32
}

/// Micro-units rounded down: for what shortens it or bounds it (deceleration, stroke).
pub fn um_down(x: f64) -> u32 {
    (x * 1e6).floor().clamp(0.0, u32::MAX as f64) as u32
}
