//! What every part of a study shares: the block of samples run at once, its JSON document's
//! version, the confidence of every interval, and the error a bad study gets.

use crate::sweep::SweepError;

/// Samples run together on the pool, then written in order; what memory holds at once.
pub const BLOCK: usize = 2048;

/// The version of the `--json` document (docs/conventions.md).
pub const SCHEMA_VERSION: u32 = 1;

/// Two-sided confidence of every interval.
pub const CONFIDENCE: f64 = 0.95;

pub(crate) fn err<T>(msg: impl Into<String>) -> Result<T, SweepError> {
    Err(SweepError(msg.into()))
}
