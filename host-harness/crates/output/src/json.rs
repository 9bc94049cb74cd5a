//! The JSON documents' common frame: the schema version every document carries, [`Versioned`]
//! (a document with its version in front) and [`to_json`] (pretty, one trailing newline).

use schemars::JsonSchema;
use serde::Serialize;

/// The version of every JSON document Flinch writes (`schema_version`): raised when a field is
/// renamed, removed or changes meaning; adding a field does not raise it.
pub const SCHEMA_VERSION: u32 = 1;

/// `flinch check --json`'s version: 2 since its lengths carry their unit (`margin` became
/// `margin_m`, `stroke` `stroke_m`, ...; docs/schema/check.json).
pub const CHECK_SCHEMA_VERSION: u32 = 2;

/// A JSON document with its schema version in front: `flinch check --json` and `flinch design
/// --json` (docs/schema/check.json, design.json).
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct Versioned<'a, T: JsonSchema> {
    /// Version of this document's schema.
    pub schema_version: u32,
    /// The document.
    #[serde(flatten)]
    pub doc: &'a T,
}

impl<'a, T: JsonSchema> Versioned<'a, T> {
    /// `doc` at the current [`SCHEMA_VERSION`].
    pub fn new(doc: &'a T) -> Self {
        Self { schema_version: SCHEMA_VERSION, doc }
    }

    /// `doc` at its own schema version.
    pub fn at(schema_version: u32, doc: &'a T) -> Self {
        Self { schema_version, doc }
    }
}

/// A JSON document, pretty-printed, with a trailing newline.
pub fn to_json<T: Serialize>(doc: &T) -> String {
    let mut s = serde_json::to_string_pretty(doc).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"));
    s.push('\n');
    s
}
