//! How Flinch writes for people and for scripts, whatever the command (docs/conventions.md): where
//! results and messages go and how a command ends (`output`: `-`, exit codes, [`output::Failure`]),
//! the JSON documents' frame (`json`: schema version, pretty printing), units from field names
//! (`units`), and the figures (`figure`: panels of series drawn to SVG or PNG with plotters, the
//! compiled-in font of `font`). Knows no scene and no physics: every layer above may use it.

pub mod figure;
pub mod font;
pub mod json;
pub mod output;
pub mod units;

pub use json::{to_json, Versioned, CHECK_SCHEMA_VERSION, SCHEMA_VERSION};
