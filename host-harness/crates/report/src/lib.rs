//! What a run produced, for people and for scripts: the human summary, the `--json` documents
//! (versioned, their JSON Schemas in docs/schema/), the CSV time history and the plots, and how a
//! command writes them (docs/conventions.md).
//!
//! Layout: `summary.rs` the human summary and the `--json` documents, `trace.rs` the signals of a
//! time history, `csv.rs` and `stream.rs` the CSV written as the run goes, `plot.rs` the run's
//! figure, `measured.rs` the comparison with a rig's CSV. The conventions (streams, exit codes, the
//! JSON frame, figures) are `flinch-output`'s, re-exported here.

pub mod csv;
pub mod measured;
pub mod plot;
pub mod stream;
pub mod summary;
pub mod trace;

pub use flinch_output::json::{to_json, Versioned, CHECK_SCHEMA_VERSION, SCHEMA_VERSION};
pub use flinch_output::{figure, font, input, output};
pub use summary::{human, human_measured, json, HilJson, RunJson};
