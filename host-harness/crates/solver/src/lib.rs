//! Integrators for the plant: adaptive Dormand-Prince 5(4) with dense output, and fixed-step RK4
//! and semi-implicit Euler for the speed/accuracy study. One [`driver`] runs them all, steps onto
//! breakpoints (where the motion law's acceleration jumps) and locates events on each step's
//! interpolant to a time tolerance, so contact onsets and threshold crossings are found, not
//! sampled. State is a stack array; nothing is allocated per step, and the right-hand side is
//! called through generics (no dynamic dispatch in the inner loop: `docs/accuracy.md`).

//!
//! Layout: `system.rs` the traits a plant and a method implement (and the step-size helpers they
//! share), `dopri5.rs` and `fixed.rs` the methods, `any.rs` the one type over them, `driver.rs` the
//! loop that steps, locates events and records. This crate knows no plant: `flinch-sim` gives it one.

pub mod any;
pub mod dopri5;
pub mod driver;
pub mod fixed;
pub mod system;

pub use any::AnyStepper;
pub use system::{error_norm, initial_step, Stepper, System};
