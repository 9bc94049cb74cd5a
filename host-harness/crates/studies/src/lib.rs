//! The studies: what a user asks of many runs, or of a run against a budget or the thesis.
//!
//! * `check`: the stroke budget against the simulation (`flinch check`);
//! * `design`: sizing a module, the largest safe speed (`flinch design`), and `body_design`: the
//!   largest speed per ISO/TS 15066 body region, module against rigid tool (`--body-region`);
//! * `sweep`: any scene key over a grid (`flinch sweep`), `sample`: Monte Carlo over tolerances
//!   (`flinch sample`);
//! * `bench`: speed against accuracy (`flinch bench`), `validate`: the thesis's figures against
//!   ours (`flinch validate`), `robot`: a robot from its URDF reduced along the approach (`flinch robot`).
//!
//! Each command's arguments (clap) and entry function live beside its study; the conventions they
//! write by are `flinch-output`'s.

pub mod bench;
pub mod body_design;
pub mod pfl;
pub mod check;
pub mod design;
pub mod robot;
pub mod sample;
pub mod search;
pub mod sweep;
pub mod validate;
