//! How Flinch reads and writes for people and for scripts, whatever the command
//! (docs/conventions.md): the one reader of every input file (`input`: regular files only, a size
//! cap per kind), the careful writer (`writer`: temporary file beside the target and rename, never
//! an input, no special files), where results and messages go and how a command ends (`output`:
//! `-`, exit codes, [`output::Failure`]), text made safe for a terminal (`terminal`), the JSON
//! documents' frame (`json`: schema version, pretty printing), units from field names (`units`),
//! and the figures (`figure`: panels of series drawn to SVG or PNG with plotters, the compiled-in
//! font of `font`). Knows no scene and no physics: every layer above may use it.

pub mod figure;
pub mod font;
pub mod input;
pub mod json;
pub mod output;
pub mod terminal;
pub mod units;
pub mod writer;

pub use json::{to_json, Versioned, CHECK_SCHEMA_VERSION, SCHEMA_VERSION};
