//! `[decoupler]`: what holds the tool on the flange (MODEL.md element 3, `plant/decoupler/`).
//! `kind` picks the mechanism; each mechanism's keys are in its own file, named as its plant file.
//! A rigid decoupler (the tool fastened to the flange) has no key but `kind`. The table's own keys
//! are in `kind.rs`, the reader that dispatches on `kind` in `read.rs`.
pub mod bistable;
pub mod end_stop;
pub mod hydraulic;
pub mod linear;
pub mod rotational;
mod kind;
mod read;

pub use kind::{RIGID_KEYS, TABLE};
pub(in crate::scene) use read::decoupler;

