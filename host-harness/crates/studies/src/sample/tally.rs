//! Counting a study's samples: refusals grouped by reason, solver failures, working modes, runs
//! not concluded, warnings grouped by kind, and the failures' counts.

use serde::{Deserialize, Serialize};
use super::outcome::*;

/// Refusals of the same keys: how many, and the first (lowest index) with its reason.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct RefusalGroup {
    /// The keys the validator's issues name.
    pub keys: Vec<String>,
    /// Samples refused so.
    pub count: u64,
    /// The first such sample's index.
    pub first_sample: u64,
    /// Its message.
    pub first_reason: String,
}

/// Samples the solver gave up on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct SolverFailures {
    /// How many.
    pub count: u64,
    /// The first one's index.
    pub first_sample: u64,
    /// Its message.
    pub first_reason: String,
}

/// Runs by working mode.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Modes {
    /// Mode 1.
    pub mode_1: u64,
    /// Mode 2.
    pub mode_2: u64,
    /// Mode 3.
    pub mode_3: u64,
    /// No mode (no back end-stop).
    pub no_mode: u64,
}

/// Samples that ran but ended before the robot stopped (`inconclusive` rows).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Inconclusive {
    /// How many.
    pub count: u64,
    /// The first one's index.
    pub first_sample: u64,
    /// Its "not concluded" failure text.
    pub first_reason: String,
}

/// A warning of the runs' summaries (docs/verdicts.md), grouped by its text with the numbers
/// masked (`t_stop = # s is after ...`): how many runs gave it, the first one and its text.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct WarningGroup {
    /// The warning with every number written `#`: what groups it.
    pub kind: String,
    /// The first such run's warning, as its summary says it.
    pub text: String,
    /// Runs that gave it.
    pub count: u64,
    /// The first such sample's index.
    pub first_sample: u64,
}

/// A warning's text with each number written `#` (`t_stop = 0.71 s` -> `t_stop = # s`).
pub fn warning_kind(text: &str) -> String {
    let mut out = String::new();
    let mut it = text.chars().peekable();
    while let Some(c) = it.next() {
        if c.is_ascii_digit() {
            let mut last = c;
            while let Some(&d) = it.peek() {
                if d.is_ascii_digit() || d == '.' || d == 'e' || d == '-' && last == 'e' {
                    last = d;
                    it.next();
                } else {
                    break;
                }
            }
            out.push('#');
        } else {
            out.push(c);
        }
    }
    out
}

/// At most this many distinct warning kinds are kept (first samples first); the report says how
/// many runs gave a text beyond them (`warnings_not_listed`).
pub const MAX_WARNINGS: usize = 32;

#[derive(Debug, Default)]
pub(crate) struct Tally {
    pub(crate) ran: u64,
    pub(crate) inconclusive: Option<Inconclusive>,
    pub(crate) warnings: Vec<WarningGroup>,
    pub(crate) warnings_not_listed: u64,
    pub(crate) refused: u64,
    pub(crate) solver_failed: u64,
    pub(crate) failures: Vec<u64>,
    /// Per failure, the inconclusive runs in which it was not seen (unknown).
    pub(crate) unknown: Vec<u64>,
    pub(crate) modes: Modes,
    pub(crate) refusals: Vec<RefusalGroup>,
    pub(crate) solver_failures: Option<SolverFailures>,
}

impl Tally {
    pub(crate) fn add(&mut self, r: &Row) {
        if self.failures.is_empty() {
            self.failures = vec![0; FAILURES.len()];
            self.unknown = vec![0; FAILURES.len()];
        }
        match &r.outcome {
            Outcome::Ran(b) => {
                self.ran += 1;
                for w in &b.warnings {
                    self.warnings_not_listed += add_warning(&mut self.warnings, WarningGroup { kind: warning_kind(w), text: w.clone(), count: 1, first_sample: r.index });
                }
                if let Some(why) = &b.not_concluded {
                    add_inconclusive(&mut self.inconclusive, Inconclusive { count: 1, first_sample: r.index, first_reason: why.clone() });
                    // A failure seen before the end is a failure; one not seen is unknown.
                    for (((n, u), &f), k) in self.failures.iter_mut().zip(self.unknown.iter_mut()).zip(&b.failed).zip(FAILURES) {
                        if f {
                            *n += 1;
                        } else if !k.known_if_not_concluded {
                            *u += 1;
                        }
                    }
                    return;
                }
                for (n, &f) in self.failures.iter_mut().zip(&b.failed) {
                    *n += u64::from(f);
                }
                match b.mode {
                    Some(1) => self.modes.mode_1 += 1,
                    Some(2) => self.modes.mode_2 += 1,
                    Some(3) => self.modes.mode_3 += 1,
                    _ => self.modes.no_mode += 1,
                }
            }
            Outcome::Refused { keys, reason } => {
                self.refused += 1;
                add_refusal(&mut self.refusals, RefusalGroup { keys: keys.clone(), count: 1, first_sample: r.index, first_reason: reason.clone() });
            }
            Outcome::Failed(why) => {
                self.solver_failed += 1;
                add_failure(&mut self.solver_failures, SolverFailures { count: 1, first_sample: r.index, first_reason: why.clone() });
            }
        }
    }
}

pub(crate) fn add_refusal(groups: &mut Vec<RefusalGroup>, g: RefusalGroup) {
    match groups.iter_mut().find(|x| x.keys == g.keys) {
        Some(x) => {
            x.count += g.count;
            if g.first_sample < x.first_sample {
                x.first_sample = g.first_sample;
                x.first_reason = g.first_reason;
            }
        }
        None => groups.push(g),
    }
    groups.sort_by_key(|x| x.first_sample);
}

pub(crate) fn add_inconclusive(f: &mut Option<Inconclusive>, g: Inconclusive) {
    match f {
        Some(x) => {
            x.count += g.count;
            if g.first_sample < x.first_sample {
                x.first_sample = g.first_sample;
                x.first_reason = g.first_reason;
            }
        }
        None => *f = Some(g),
    }
}

/// Adds a warning group; returns the runs it could not list (a new text beyond [`MAX_WARNINGS`]).
pub(crate) fn add_warning(groups: &mut Vec<WarningGroup>, g: WarningGroup) -> u64 {
    let full = groups.len() >= MAX_WARNINGS;
    let not_listed = match groups.iter_mut().find(|x| x.kind == g.kind) {
        Some(x) => {
            x.count += g.count;
            if g.first_sample < x.first_sample {
                x.first_sample = g.first_sample;
                x.text = g.text;
            }
            0
        }
        None if !full => {
            groups.push(g);
            0
        }
        None => g.count,
    };
    groups.sort_by_key(|x| x.first_sample);
    not_listed
}

pub(crate) fn add_failure(f: &mut Option<SolverFailures>, g: SolverFailures) {
    match f {
        Some(x) => {
            x.count += g.count;
            if g.first_sample < x.first_sample {
                x.first_sample = g.first_sample;
                x.first_reason = g.first_reason;
            }
        }
        None => *f = Some(g),
    }
}
