//! On-board collision-avoidance step (Ch. 5 of the thesis, section 5.3).
//!
//! The host fits a grid of Gaussian radial basis functions to the depth image (eq 65-71) and sends the
//! weights here over a framed serial protocol ([`frame`], [`receiver`]). Every control step the MCU
//! evaluates the interpolated field `f*` and its analytic gradient (eq 72-73) at the tool point
//! ([`field`]), adds the constant attraction (eq 74) and the vortex repulsion (eq 76), and turns the
//! sum into a velocity command (eq 77-78) scaled down by the field height and by the age of the weights
//! ([`control`]).
//!
//! Everything is generic over the number type ([`num::Real`]: `I16F16`, `I8F24`, `I20F12`, `f32`,
//! `f64`) and the Gaussian ([`gauss`]: lookup table, `micromath`, `libm`), so the host can measure the
//! error of each choice against an `f64` reference; the board runs [`BoardReal`] (`f32` on the
//! M4F, `I16F16` with the feature `avoid-fixed`). [`link`] is the step as the board runs it.
//!
//! [`safe`] then limits the command by speed and separation monitoring (ISO/TS 15066, 5.5.4), from
//! the sensed separation and not from the field, and caps it at the configured speed.
//!
//! Units: metres, seconds, metres per second; heights of `f*` in metres; gradients dimensionless.
//! No heap, no panics, bounded loops: like the detection modules, the non-test code is held to
//! clippy's `unwrap_used`, `expect_used`, `panic`, `indexing_slicing` and `arithmetic_side_effects`
//! (`cargo clippy -p flinch-firmware`).
#![cfg_attr(
    not(test),
    deny(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing,
        clippy::arithmetic_side_effects
    )
)]

pub mod cell;
pub mod control;
pub mod field;
pub mod frame;
pub mod gauss;
pub mod link;
pub mod num;
pub mod receiver;
pub mod safe;
pub mod velocity;

pub use control::{Command, Controller, Gains, Repulsion, Watchdog};
pub use field::{sample, FieldSample, Grid, MAX_AXIS, MAX_CENTRES, MAX_WINDOW, TRUNC_SIGMAS};
pub use frame::{encode_frame, frame_len, FrameHeader};
pub use gauss::{Gauss, GaussLibm, GaussLut, GaussMicromath};
pub use link::{Link, LinkConfig, Status, Velocity};
pub use cell::{board_config, BOARD_CELL};

pub use num::{BoardReal, Real};
pub use receiver::{Receiver, RxStats};
pub use safe::{sector_of, Pfl, SafeCommand, SafeController, SafeState, Sensed, SsmParams, Steer, SECTORS};
