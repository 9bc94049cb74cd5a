//! `flinch validate --out docs/`: the thesis's figures side by side with ours, `docs/validation.md`.
//!
//! Every number in the document's tables comes from running the simulator here, from the shipped
//! scenes (`scenes/*.toml`, `scenes/figures/*.toml`) with keys set through the sweep module, so the
//! document is regenerated, never edited. [`tables`] computes the numbers (coarse sweep grids, a few
//! seconds) and [`markdown`] renders them; `tests/validation.rs` does both and fails when
//! `docs/validation.md` differs. [`write`] also draws the pictures into `docs/validation/` (finer
//! grids; the test does not redraw them, it checks they exist).
//!
//! Layout: `tables.rs` the sections in order, computed in `ch2.rs`, `ch3.rs` and `ch4.rs` with the
//! helpers of `context.rs` (running scenes, reading histories) and `statics.rs`; `rows.rs` the rows
//! and number formats, `document.rs` the markdown, `pictures.rs` the SVGs, `cli.rs` the command.

mod ch2;
mod ch3;
mod ch4;
mod cli;
mod context;
mod document;
mod fig69;
mod pictures;
mod rows;
mod statics;
mod tables;
#[cfg(test)]
mod tests;

pub use cli::*;
pub use context::{back_stop_hit, front_stop_return, hits, Hit};
pub use document::*;
pub use pictures::*;
pub use rows::*;
pub use statics::*;
pub use tables::*;
