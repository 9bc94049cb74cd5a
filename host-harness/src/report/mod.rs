//! What a run produced (`flinch-report`), how Flinch writes (`flinch-output`), the JSON Schemas of
//! every document (schema.rs) and the one-page HTML report (html.rs).

pub use flinch_report::*;
pub mod html;
pub mod schema;
