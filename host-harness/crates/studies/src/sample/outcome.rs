//! What one sample gives: the failures a study counts ([`FAILURES`]), a run's brief, the outcome
//! (ran, refused by the validator, the solver failed) and the row written for it.

use flinch_model::scene::{Scene, TargetKind};
use flinch_sim::Summary;

// ---------------------------------------------------------------------------------------------
// Rows and counts
// ---------------------------------------------------------------------------------------------

/// A failure whose probability is estimated: its name, what it is, and the test on a summary.
pub struct FailureKind {
    /// As in the JSON (`estimates[].failure`).
    pub name: &'static str,
    /// For people.
    pub what: &'static str,
    /// True when the run has this failure.
    pub test: fn(&Summary) -> bool,
    /// True when the failure can happen in this scene (estimated only then).
    pub applies: fn(&Scene) -> bool,
    /// True when a run that ended before the robot stopped (not concluded) is known to have it:
    /// only `not_safe` (such a run is not safe). For the others a failure already seen in such a
    /// run counts (they only grow: a stroke exhausted, a mode 3, a limit exceeded stay so after
    /// the end); one not seen is unknown: the run is left out of that failure's `runs` and counted
    /// in its `high_if_unrun_failed`.
    pub known_if_not_concluded: bool,
}

pub(crate) fn always(_: &Scene) -> bool {
    true
}

/// The failures estimated, each from the run's summary. The body-region limit is estimated only
/// for a scene whose target is a body region (elsewhere it cannot happen, and "0 of N" would read
/// as evidence).
pub const FAILURES: &[FailureKind] = &[
    FailureKind { name: "stroke_exhausted", what: "stroke exhausted (the tool in the back end-stop while touching the target; docs/verdicts.md)", test: |s| s.stroke_exhausted, applies: always, known_if_not_concluded: false },
    FailureKind { name: "mode_3", what: "working mode 3 (the tool hits the back end-stop while the robot still brakes; Fig. 46)", test: |s| s.mode == Some(3), applies: always, known_if_not_concluded: false },
    FailureKind { name: "not_safe", what: "not safe by the one definition (docs/verdicts.md: the summary's `failures` is not empty)", test: |s| !s.safe, applies: always, known_if_not_concluded: true },
    FailureKind {
        name: "body_limit_exceeded",
        what: "a body-region limit exceeded (ISO/TS 15066 Table A.2 force or pressure, or a transient contact the TS does not permit; the summary's body_limits_pass is false)",
        test: |s| s.body_limits_pass == Some(false),
        applies: |sc| matches!(sc.target.kind, TargetKind::BodyRegion(_)),
        known_if_not_concluded: false,
    },
];

/// The fields of a run's summary a sample keeps.
#[derive(Debug, Clone, PartialEq)]
pub struct Brief {
    /// `stroke_exhausted`.
    pub stroke_exhausted: bool,
    /// Working mode.
    pub mode: Option<u8>,
    /// N.
    pub peak_contact_force_n: f64,
    /// N.
    pub peak_robot_force_n: f64,
    /// m.
    pub stroke_left_min_m: Option<f64>,
    /// The one definition.
    pub safe: bool,
    /// ISO/TS 15066 limits kept (a body-region target only).
    pub body_limits_pass: Option<bool>,
    /// Per [`FAILURES`].
    pub failed: Vec<bool>,
    /// The run ended before the robot stopped (`Summary::concluded` false): the summary's
    /// "not concluded" failure text. Such a sample is `inconclusive`: what happened after the end
    /// is not simulated.
    pub not_concluded: Option<String>,
    /// The summary's warnings (things the user should know about the run).
    pub warnings: Vec<String>,
}

impl Brief {
    pub(crate) fn of(s: &Summary) -> Self {
        Self {
            stroke_exhausted: s.stroke_exhausted,
            mode: s.mode,
            peak_contact_force_n: s.peak_contact_force,
            peak_robot_force_n: s.peak_robot_force,
            stroke_left_min_m: s.stroke_left_min_m,
            safe: s.safe,
            body_limits_pass: s.body_limits_pass,
            failed: FAILURES.iter().map(|f| (f.test)(s)).collect(),
            not_concluded: (!s.concluded).then(|| s.failures.iter().find(|f| f.starts_with("not concluded")).cloned().unwrap_or_else(|| "not concluded: the run ended before the robot stopped: lengthen duration".into())),
            warnings: s.warnings.clone(),
        }
    }
}

/// What became of a sample.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Ran.
    Ran(Brief),
    /// The validator refused the drawn scene: the keys its issues name, and its message.
    Refused {
        /// Keys.
        keys: Vec<String>,
        /// Message.
        reason: String,
    },
    /// The solver gave up.
    Failed(String),
}

/// One sample: its index, drawn values and outcome.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// Sample index.
    pub index: u64,
    /// Values in `--vary` order.
    pub values: Vec<f64>,
    /// What happened.
    pub outcome: Outcome,
}

pub(crate) fn bit(b: bool) -> String {
    if b { "1" } else { "0" }.to_string()
}

impl Row {
    /// The CSV record (booleans 0/1, empty cells where a sample did not run), without a
    /// `body_limits_pass` column.
    pub fn record(&self) -> Vec<String> {
        self.record_with(false)
    }

    /// The CSV record, with the `body_limits_pass` column when `body` (a body-region scene).
    pub fn record_with(&self, body: bool) -> Vec<String> {
        let blanks = if body { 7 } else { 6 };
        let mut r = vec![self.index.to_string()];
        r.extend(self.values.iter().map(f64::to_string));
        match &self.outcome {
            Outcome::Ran(b) => {
                // Not concluded: a failure seen before the end is known (stroke exhausted 1,
                // mode 3, body limits 0); otherwise the cell is empty (unknown). The peaks and
                // the stroke left are up to the end.
                let known = b.not_concluded.is_none();
                r.extend([
                    if known || b.stroke_exhausted { bit(b.stroke_exhausted) } else { String::new() },
                    b.mode.filter(|&m| known || m == 3).map_or(String::new(), |m| m.to_string()),
                    b.peak_contact_force_n.to_string(),
                    b.peak_robot_force_n.to_string(),
                    b.stroke_left_min_m.map_or(String::new(), |x| x.to_string()),
                    bit(b.safe),
                ]);
                if body {
                    r.push(b.body_limits_pass.filter(|&p| known || !p).map_or(String::new(), bit));
                }
                match &b.not_concluded {
                    None => r.extend(["ok".into(), String::new()]),
                    Some(why) => r.extend(["inconclusive".into(), why.clone()]),
                }
            }
            Outcome::Refused { reason, .. } => {
                r.extend((0..blanks).map(|_| String::new()));
                r.push("refused".into());
                r.push(reason.clone());
            }
            Outcome::Failed(why) => {
                r.extend((0..blanks).map(|_| String::new()));
                r.push("failed".into());
                r.push(why.clone());
            }
        }
        r
    }
}
