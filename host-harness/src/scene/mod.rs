//! Scene files: TOML in SI units, the public contract of `shared/SCENES.md`.
//!
//! `model` holds the validated values; `load` parses and validates a file with errors that name the
//! file, the key, the line and what is allowed.
mod load;
mod model;
pub use load::*;
pub use model::*;
