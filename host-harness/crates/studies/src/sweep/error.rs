//! [`SweepError`]: what a sweep (and a study built on one) refuses, as one message.

use std::fmt;

/// A sweep the user asked for that cannot run; the message names what is wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepError(pub String);

impl fmt::Display for SweepError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

pub(crate) fn err<T>(msg: impl Into<String>) -> Result<T, SweepError> {
    Err(SweepError(msg.into()))
}
