//! Flinch firmware library: hardware-independent detection, timestamping and stop logic.
#![no_std]

pub mod avoidance;
