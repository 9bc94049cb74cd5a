//! The avoidance scene (`[avoid]`, thesis Ch. 5, docs/avoidance.md), read by the impact scenes'
//! loader machinery (`check.rs`): every key declared once in a [`Key`] table (type, unit, physical
//! range with its source, default, doc line), unknown keys refused with the list of the allowed
//! ones, wrong types, ranges, fixed-length points, increasing key frames, and the caps on the work
//! a scene can ask for (image size, calibration grid, mask growth, frames). Every problem at once,
//! each as `file:line: key: message`. [`parse`] builds `avoid::scene::Avoid`; nothing else parses
//! an avoidance scene file.
//!
//! Layout: `keys.rs` the keys and their tables, `values.rs` the readers of points, counts and lists,
//! `parse.rs` the tables read into `crate::avoid::scene::Avoid`, `checks.rs` the checks across keys.

mod checks;
mod keys;
mod parse;
#[cfg(test)]
mod tests;
mod values;

pub use checks::MAX_EVAL_SIGMA_OVER_SPACING;
pub use keys::*;
pub use parse::{default_safety, parse, without_file};
