//! `flinch sweep`: run a scene over a grid of one or two of its keys, on all cores.
//!
//! A sweep edits the scene's parsed TOML document (a dotted key path such as `motion.speed`,
//! `decoupler.spring_rate` or `decoupler.front_stop.stiffness`) and re-validates every edited
//! text with [`scene::parse`], the same validator `flinch run` uses. Every point of the grid is
//! built and checked *before* anything runs, so a bad key or a bad range stops the sweep with a
//! message naming what is wrong, and no time is spent simulating.
//!
//! Axes are `KEY=START:STOP:N` (linear steps) or `KEY=log:START:STOP:N` (geometric steps, START > 0);
//! `--log KEY` makes an axis geometric too. Points are ordered with the first axis varying slowest
//! (row-major), whatever the number of threads: the CSV is the same on one core or sixteen.
//!
//! The CSV has one row per point: the swept values, then every field of the run's [`Summary`] in
//! its declaration order (found by serialising it, so a field added to `Summary` appears here
//! without a change), then `status` (`ok`, `refused` by the validator, `failed` in the solver) and
//! `reason`. A point the validator refuses does not stop `flinch sweep`: it becomes such a row and
//! is drawn as such (`--strict` restores refusing the whole sweep, as [`Sweep::new`] does).
//!
//! Layout: `template.rs` a scene with keys set, `axis.rs` an axis, `grid.rs` the sweep and its
//! run, `metrics.rs` the summary fields it reports, `table.rs` its CSV, `plot.rs` its figures,
//! `error.rs` its error, `stream.rs` its run streamed in grid order (what `flinch sweep` uses:
//! memory flat in the number of points, Ctrl-C keeps the prefix), `cli.rs` the command.

mod axis;
pub mod cli;
mod error;
mod grid;
mod metrics;
pub mod plot;
pub mod stream;
mod table;
mod template;
#[cfg(test)]
mod tests;

pub use axis::*;
pub use error::*;
pub use grid::*;
pub use metrics::*;
pub use table::*;
pub use template::*;
