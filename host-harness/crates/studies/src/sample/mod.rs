//! `flinch sample`: Monte Carlo over a scene's keys, and the probability of each failure with a
//! 95 % confidence interval (docs/sample.md).
//!
//! Each `--vary KEY=DIST` draws a scene key (a dotted path as in `flinch sweep`) from a
//! distribution; every sample's scene is the file with those keys set, re-validated by the same
//! validator as `flinch run` ([`Template::with`]). A sample the validator refuses (a normal draw
//! below a key's range, or a combination the scene contract forbids) is counted and reported by the
//! keys refused, with the first reason; it is never dropped silently or clamped. `--truncate` draws
//! each key within its accepted range instead (an exact truncated distribution, by the inverse
//! distribution function), and the report states how much probability that cut.
//!
//! Determinism: sample `i`'s draws depend only on `(seed, i, position of the key)` (a counter-based
//! generator, [`uniform01`]), so the result is the same on any number of threads, and a chunk
//! `K/M` (a range of sample indices) can run anywhere: the chunks' reports merge ([`merge`]) into the
//! report of the whole run, field for field. Samples run on the rayon pool in blocks of [`BLOCK`],
//! written in index order: memory does not grow with N.
//!
//! Layout: `plan.rs` the plan, `run.rs` running it, `common.rs` what the parts share, `keys.rs` the keys varied, `dist.rs` the
//! distributions, `outcome.rs` one sample's outcome and row, `tally.rs` the counting, `report.rs`
//! the report and merging chunks, `stats.rs` the intervals, `parquet_file.rs` the Parquet writer,
//! `cli.rs` the command.

pub mod cli;
mod common;
mod consistency;
mod dist;
mod keys;
mod outcome;
pub mod parquet_file;
mod plan;
mod report;
mod run;
pub mod stats;
mod tally;
#[cfg(test)]
mod tests;

pub use common::*;
pub use consistency::merge_checked;
pub use dist::*;
pub use keys::*;
pub use outcome::*;
pub use plan::*;
pub use report::*;
pub use tally::*;
