//! What Flinch publishes about every command at once, above the studies and the avoidance:
//!
//! * `schema`: the JSON Schemas of every document Flinch writes (`docs/schema/*.json`, generated from
//!   the types that serialise them, each numeric field's unit stated), and of the scene files;
//! * `html`: `flinch report`, one self-contained, printable HTML page of a scene (inputs and their
//!   sources, the verdicts, the safe speed, the time history, the design curve, a sweep);
//! * `document`: what makes that page a document to file (date, command, page footer, the
//!   ISO/TS 15066 table of a body-region scene).

pub mod document;
pub mod html;
pub mod schema;
