//! `flinch sample`: the estimates with their intervals, the report, merging chunks, its schema.

use super::{outcome::*, tally::*, dist::*};
use crate::sweep::SweepError;
use super::common::*;
use serde::{Deserialize, Serialize};
use super::stats;
use std::sync::atomic::AtomicBool;

// ---------------------------------------------------------------------------------------------
// The report and its estimates
// ---------------------------------------------------------------------------------------------

/// A varied key in the report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct VaryReport {
    /// Dotted key.
    pub key: String,
    /// Its CSV column (with the unit's suffix).
    pub column: String,
    /// The distribution, canonical.
    pub dist: String,
    /// The key's unit, if the key tables list it.
    pub unit: Option<String>,
    /// The key's accepted range, as the validator says it.
    pub accepted_range: Option<String>,
    /// Draws are confined to [within_lo, within_hi] (explicit :LO:HI, or --truncate), in the key's unit.
    pub within_lo: Option<f64>,
    /// See `within_lo`.
    pub within_hi: Option<f64>,
    /// The probability the truncation keeps (1 without one).
    pub kept_probability: f64,
    /// Without truncation, the probability of a draw outside the accepted range (refused).
    pub outside_probability: f64,
}

/// The estimate of one failure's probability.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Estimate {
    /// Which failure (`stroke_exhausted`, `mode_3`, `not_safe`; `body_limit_exceeded` for a body-region target).
    pub failure: String,
    /// What it is.
    pub what: String,
    /// Runs with it.
    pub failures: u64,
    /// Runs counted: samples that ran (not refused, not failed in the solver), less the
    /// inconclusive ones for every failure but `not_safe` (after the end of such a run it is
    /// unknown whether the stroke ran out; for `not_safe` an inconclusive run is a failure).
    pub runs: u64,
    /// failures / runs; null with no run.
    pub p: Option<f64>,
    /// The interval reported: "clopper-pearson" at 0 or all failures, "wilson" otherwise.
    pub interval: String,
    /// Its lower end.
    pub low: f64,
    /// Its upper end.
    pub high: f64,
    /// Wilson score interval, lower end.
    pub wilson_low: f64,
    /// Wilson score interval, upper end.
    pub wilson_high: f64,
    /// Clopper-Pearson exact interval, lower end.
    pub clopper_pearson_low: f64,
    /// Clopper-Pearson exact interval, upper end.
    pub clopper_pearson_high: f64,
    /// The bound that rests on nothing left out: the Clopper-Pearson upper end `h` if every
    /// refused, solver-failed or (for a failure other than `not_safe`) inconclusive sample were a
    /// failure (over all samples drawn), and, with truncated draws, `1 - K (1 - h)` where K is the
    /// product of the keys' `kept_probability`: the probability cut off counted as failing.
    pub high_if_unrun_failed: f64,
}

/// Computes an estimate from counts.
pub fn estimate(kind: &FailureKind, failures: u64, runs: u64, unrun: u64) -> Estimate {
    let alpha = 1.0 - CONFIDENCE;
    let z = stats::normal_quantile(1.0 - alpha / 2.0);
    let (wl, wh) = stats::wilson(failures, runs, z);
    let (cl, ch) = stats::clopper_pearson(failures, runs, alpha);
    let exact = runs == 0 || failures == 0 || failures == runs;
    let (_, worst) = stats::clopper_pearson(failures + unrun, runs + unrun, alpha);
    Estimate {
        failure: kind.name.into(),
        what: kind.what.into(),
        failures,
        runs,
        p: (runs > 0).then(|| failures as f64 / runs as f64),
        interval: if exact { "clopper-pearson" } else { "wilson" }.into(),
        low: if exact { cl } else { wl },
        high: if exact { ch } else { wh },
        wilson_low: wl,
        wilson_high: wh,
        clopper_pearson_low: cl,
        clopper_pearson_high: ch,
        high_if_unrun_failed: worst,
    }
}

/// `flinch sample --json`: the study, its counts and estimates (docs/sample.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct SampleReport {
    /// docs/conventions.md.
    pub schema_version: u32,
    /// Scene name.
    pub scene: String,
    /// The scene as given.
    pub scene_file: String,
    /// FNV-1a 64 of the scene's text and of the files it refers to (its URDF).
    pub scene_fnv1a64: String,
    /// The version of flinch that ran it (merging refuses reports of different versions: the
    /// model may differ).
    pub flinch_version: String,
    /// Seed.
    pub seed: u64,
    /// N of the whole study.
    pub samples: u64,
    /// Draws truncated to the keys' accepted ranges.
    pub truncate: bool,
    /// The varied keys.
    pub vary: Vec<VaryReport>,
    /// The sample index ranges [first, end) this report covers, ascending.
    pub ranges: Vec<[u64; 2]>,
    /// The ranges are [[0, samples]]: the whole study.
    pub complete: bool,
    /// Samples drawn (in the ranges).
    pub drawn: u64,
    /// Samples that ran.
    pub ran: u64,
    /// Samples the validator refused.
    pub refused: u64,
    /// Samples the solver gave up on.
    pub solver_failed: u64,
    /// Runs by working mode.
    pub modes: Modes,
    /// Refusals by the keys refused, first sample ascending.
    pub refusals: Vec<RefusalGroup>,
    /// Solver failures, if any.
    pub solver_failures: Option<SolverFailures>,
    /// Samples that ran (counted in `ran`) but ended before the robot stopped: the run's
    /// `duration` is too short for them (the summary's "not concluded" failure). They are failures
    /// for `not_safe`, unknown for the other failures (not in their `runs`; failures in their
    /// `high_if_unrun_failed`), and in no working mode.
    pub inconclusive: u64,
    /// The first inconclusive sample and its reason, if any.
    pub inconclusive_first: Option<Inconclusive>,
    /// The runs' warnings (the summary's `warnings`), grouped by their text with the numbers
    /// masked, first sample ascending; at most 32 groups.
    pub warnings: Vec<WarningGroup>,
    /// Warnings of a group beyond the 32 listed.
    pub warnings_not_listed: u64,
    /// Two-sided confidence of the intervals.
    pub confidence: f64,
    /// One per failure.
    pub estimates: Vec<Estimate>,
}

impl SampleReport {
    /// Sets `complete` and the estimates from the failure counts (per [`FAILURES`]) of the kinds
    /// that `applies`.
    pub(super) fn finish(&mut self, failures: &[u64], unknown: &[u64], applies: &[bool]) {
        self.complete = self.ranges.len() == 1 && self.ranges[0] == [0, self.samples];
        let unrun = self.refused + self.solver_failed;
        let kept = self.kept_probability();
        let ran = self.ran;
        self.estimates = FAILURES
            .iter()
            .enumerate()
            .filter(|(i, _)| applies.get(*i).copied().unwrap_or(false))
            .map(|(i, k)| {
                let f = failures.get(i).copied().unwrap_or(0);
                // Inconclusive runs in which this failure was not seen are unknown: not runs.
                let u = if k.known_if_not_concluded { 0 } else { unknown.get(i).copied().unwrap_or(0) };
                let mut e = estimate(k, f, ran - u, unrun + u);
                if kept < 1.0 {
                    e.high_if_unrun_failed = 1.0 - kept * (1.0 - e.high_if_unrun_failed);
                }
                e
            })
            .collect();
    }

    /// The sample indices of the study [0, samples) this report does not cover, as ranges.
    pub fn missing(&self) -> Vec<[u64; 2]> {
        let mut out = Vec::new();
        let mut at = 0;
        for r in &self.ranges {
            if r[0] > at {
                out.push([at, r[0]]);
            }
            at = at.max(r[1]);
        }
        if at < self.samples {
            out.push([at, self.samples]);
        }
        out
    }

    /// K, the probability the truncations keep: the product of the keys' `kept_probability`
    /// (the keys are drawn independently).
    pub fn kept_probability(&self) -> f64 {
        self.vary.iter().map(|v| v.kept_probability).product()
    }

    /// What the human summary prints.
    pub fn human(&self) -> String {
        let mut t = format!("{}\n", self.scene);
        let of = if self.complete { format!("{} samples", self.drawn) } else { format!("{} of {} samples (ranges {})", self.drawn, self.samples, self.ranges.iter().map(|r| format!("{}..{}", r[0], r[1])).collect::<Vec<_>>().join(", ")) };
        t.push_str(&format!("  {of}, seed {}: {} ran, {} refused by the validator, {} solver failures\n", self.seed, self.ran, self.refused, self.solver_failed));
        for v in &self.vary {
            let within = match (v.within_lo, v.within_hi) {
                (None, None) if v.kept_probability < 1.0 => "truncated".to_string(),
                (None, None) => String::new(),
                (lo, hi) => format!(
                    " within [{}, {}] (keeps {})",
                    lo.map_or("-inf".into(), num),
                    hi.map_or("+inf".into(), num),
                    pct(v.kept_probability)
                ),
            };
            // Only when it matters at this N: an expected 0.01 refused samples or more.
            let outside = if v.outside_probability * self.samples as f64 >= 0.01 { format!("; {} of draws outside the accepted range {} (refused)", pct(v.outside_probability), v.accepted_range.clone().unwrap_or_default()) } else { String::new() };
            // A lognormal's parameters are of ln X: its median exp(MU) said in the key's unit.
            let median = match VarySpec::parse(&format!("{}={}", v.key, v.dist)).map(|s| s.dist) {
                Ok(d @ Dist::LogNormal { .. }) => format!(" (median {}{})", num(d.median()), v.unit.as_deref().filter(|u| !u.is_empty()).map_or(String::new(), |u| format!(" {u}"))),
                _ => String::new(),
            };
            t.push_str(&format!("  {} ~ {}{median}{within}{outside}\n", v.key, v.dist));
        }
        t.push_str(&format!("  probability (95 % interval, over the {} runs):\n", self.ran));
        let width = self.estimates.iter().map(|e| e.failure.len()).max().unwrap_or(0).max(17);
        for e in &self.estimates {
            let p = e.p.map_or("-".to_string(), sig);
            t.push_str(&format!("    {:<width$} {:>8} of {:<8} p = {p:<9} [{}, {}] {}\n", e.failure, e.failures, e.runs, sig(e.low), sig(e.high), if e.interval == "wilson" { "Wilson" } else { "Clopper-Pearson" }));
        }
        t.push_str(&format!("  working modes: 1: {}, 2: {}, 3: {}, none: {}\n", self.modes.mode_1, self.modes.mode_2, self.modes.mode_3, self.modes.no_mode));
        for g in &self.refusals {
            t.push_str(&format!("  REFUSED {} ({}), first sample {}: {}\n", g.count, if g.keys.is_empty() { "?".into() } else { g.keys.join(", ") }, g.first_sample, g.first_reason));
        }
        if let Some(f) = &self.solver_failures {
            t.push_str(&format!("  SOLVER FAILED {}, first sample {}: {}\n", f.count, f.first_sample, f.first_reason));
        }
        let bounds = || self.estimates.iter().map(|e| format!("{} {}", e.failure, sig(e.high_if_unrun_failed))).collect::<Vec<_>>().join(", ");
        if let Some(x) = &self.inconclusive_first {
            t.push_str(&format!(
                "  NOT CONCLUDED: {} samples ended before the robot stopped: lengthen duration (first sample {}: {})\n  counting them as failures{}{}, the upper ends are: {}\n",
                x.count,
                x.first_sample,
                x.first_reason,
                if self.refused + self.solver_failed > 0 { format!(", and the {} samples that did not run", self.refused + self.solver_failed) } else { String::new() },
                if self.kept_probability() < 1.0 { format!(", and every draw the truncation cut off ({} of the probability)", pct(1.0 - self.kept_probability())) } else { String::new() },
                bounds()
            ));
        }
        for w in &self.warnings {
            t.push_str(&format!("  warning in {} runs, first sample {}: {}\n", w.count, w.first_sample, w.text));
        }
        if self.warnings_not_listed > 0 {
            t.push_str(&format!("  warning: {} more warnings not listed (more than {MAX_WARNINGS} kinds)\n", self.warnings_not_listed));
        }
        let unrun = self.refused + self.solver_failed;
        let kept = self.kept_probability();
        // The truncation matters when the bound counting the cut-off probability as failing is
        // materially above the conditional one (by more than a tenth of it).
        let truncation_matters = kept < 1.0 && self.estimates.iter().any(|e| e.high_if_unrun_failed > 1.1 * e.high);
        if self.inconclusive == 0 && (unrun > 0 || truncation_matters) {
            let what = match (unrun > 0, kept < 1.0) {
                (true, true) => format!("if the {unrun} samples that did not run were failures, and so was every draw the truncation cut off ({} of the probability)", pct(1.0 - kept)),
                (true, false) => format!("if the {unrun} that did not were failures"),
                (false, _) => format!("with the truncation the estimates are conditional on the kept draws; if every draw it cut off ({} of the probability) were a failure", pct(1.0 - kept)),
            };
            t.push_str(&format!("  the estimates are over the samples that ran; {what}, the upper ends would be: {}\n", bounds()));
        }
        t
    }
}

/// A probability for people: 3 significant digits, scientific below 1e-3.
pub fn sig(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else if x >= 1e-3 {
        let decimals = (2 - x.log10().floor() as i32).clamp(0, 6) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.2e}")
    }
}

fn pct(x: f64) -> String {
    format!("{} %", sig(x * 100.0))
}

/// Merges the reports of chunks of one study into the report of their union, equal field for
/// field to a single run over the same samples. Refuses reports of different studies (scene text,
/// seed, N, keys and distributions, truncation) and overlapping ranges.
pub fn merge(reports: &[SampleReport], names: &[String]) -> Result<SampleReport, SweepError> {
    let Some(first) = reports.first() else {
        return err("--merge: no reports given");
    };
    let name = |i: usize| names.get(i).cloned().unwrap_or_else(|| format!("report {}", i + 1));
    for (i, r) in reports.iter().enumerate() {
        if r.schema_version != SCHEMA_VERSION {
            return err(format!("--merge {}: schema_version {} is not {SCHEMA_VERSION}", name(i), r.schema_version));
        }
        let same = |what: &str, a: String, b: String| if a == b { Ok(()) } else { err(format!("--merge {}: another study: its {what} is {b}, {}'s is {a}", name(i), name(0))) };
        same("flinch version", first.flinch_version.clone(), r.flinch_version.clone())?;
        same("scene text and referenced files (FNV-1a 64)", first.scene_fnv1a64.clone(), r.scene_fnv1a64.clone())?;
        same("seed", first.seed.to_string(), r.seed.to_string())?;
        same("--samples", first.samples.to_string(), r.samples.to_string())?;
        same("--truncate", first.truncate.to_string(), r.truncate.to_string())?;
        let keys = |r: &SampleReport| r.vary.iter().map(|v| format!("{}={}", v.key, v.dist)).collect::<Vec<_>>().join(" ");
        same("--vary", keys(first), keys(r))?;
        if r.vary != first.vary {
            return err(format!("--merge {}: another study: its --vary bounds differ from {}'s", name(i), name(0)));
        }
        let names_of = |r: &SampleReport| r.estimates.iter().map(|e| e.failure.clone()).collect::<Vec<_>>().join(", ");
        same("failures estimated", names_of(first), names_of(r))?;
        // Counts that add up: a report edited by hand, or cut short, is not merged.
        let bad = |what: String| err(format!("--merge {}: not a consistent `flinch sample --json` report: {what}", name(i)));
        let covered: u64 = r.ranges.iter().map(|x| x[1].saturating_sub(x[0])).sum();
        if let Some(x) = r.ranges.iter().find(|x| x[0] >= x[1] || x[1] > r.samples) {
            return bad(format!("its range {}..{} is not within 0..{}", x[0], x[1], r.samples));
        }
        if covered != r.drawn || r.ran + r.refused + r.solver_failed != r.drawn {
            return bad(format!("its ranges cover {covered} samples, it drew {}, and ran + refused + solver_failed = {}", r.drawn, r.ran + r.refused + r.solver_failed));
        }
        // A failure's runs are the samples that ran less the inconclusive ones it was not seen in.
        if let Some(e) = r.estimates.iter().find(|e| e.runs > r.ran || e.runs + r.inconclusive < r.ran || e.failures > e.runs) {
            return bad(format!("{}: {} failures of {} runs, and {} samples ran, {} of them inconclusive", e.failure, e.failures, e.runs, r.ran, r.inconclusive));
        }
    }
    let mut ranges: Vec<([u64; 2], usize)> = reports.iter().enumerate().flat_map(|(i, r)| r.ranges.iter().map(move |x| (*x, i))).collect();
    ranges.sort();
    for w in ranges.windows(2) {
        if w[1].0[0] < w[0].0[1] {
            return err(format!("--merge: {} and {} overlap (samples {}..{} and {}..{}): each sample may be counted once", name(w[0].1), name(w[1].1), w[0].0[0], w[0].0[1], w[1].0[0], w[1].0[1]));
        }
    }
    let mut merged: Vec<[u64; 2]> = Vec::new();
    for (r, _) in ranges {
        match merged.last_mut() {
            Some(last) if last[1] == r[0] => last[1] = r[1],
            _ => merged.push(r),
        }
    }
    let mut out = first.clone();
    out.ranges = merged;
    out.drawn = reports.iter().map(|r| r.drawn).sum();
    out.ran = reports.iter().map(|r| r.ran).sum();
    out.refused = reports.iter().map(|r| r.refused).sum();
    out.solver_failed = reports.iter().map(|r| r.solver_failed).sum();
    out.modes = Modes::default();
    out.refusals = Vec::new();
    out.solver_failures = None;
    out.inconclusive = reports.iter().map(|r| r.inconclusive).sum();
    out.inconclusive_first = None;
    out.warnings = Vec::new();
    out.warnings_not_listed = reports.iter().map(|r| r.warnings_not_listed).sum();
    let mut failures = vec![0u64; FAILURES.len()];
    let mut unknown = vec![0u64; FAILURES.len()];
    for r in reports {
        out.modes.mode_1 += r.modes.mode_1;
        out.modes.mode_2 += r.modes.mode_2;
        out.modes.mode_3 += r.modes.mode_3;
        out.modes.no_mode += r.modes.no_mode;
        for g in &r.refusals {
            add_refusal(&mut out.refusals, g.clone());
        }
        if let Some(f) = &r.solver_failures {
            add_failure(&mut out.solver_failures, f.clone());
        }
        if let Some(f) = &r.inconclusive_first {
            add_inconclusive(&mut out.inconclusive_first, f.clone());
        }
        for w in &r.warnings {
            out.warnings_not_listed += add_warning(&mut out.warnings, w.clone());
        }
        for (i, k) in FAILURES.iter().enumerate() {
            if let Some(e) = r.estimates.iter().find(|e| e.failure == k.name) {
                failures[i] += e.failures;
                unknown[i] += r.ran - e.runs;
            }
        }
    }
    let applies: Vec<bool> = FAILURES.iter().map(|k| first.estimates.iter().any(|e| e.failure == k.name)).collect();
    out.finish(&failures, &unknown, &applies);
    Ok(out)
}

/// Units of the report's numeric fields (docs/conventions.md): counts, indices and probabilities
/// are "1"; the truncation bounds are in the key's unit, which the entry's `unit` gives.
const UNITS: &[(&str, &str)] = &[
    ("schema_version", "1"), ("seed", "1"), ("samples", "1"), ("drawn", "1"), ("ran", "1"), ("refused", "1"), ("solver_failed", "1"),
    ("count", "1"), ("first_sample", "1"), ("mode_1", "1"), ("mode_2", "1"), ("mode_3", "1"), ("no_mode", "1"), ("confidence", "1"),
    ("failures", "1"), ("runs", "1"), ("p", "1"), ("low", "1"), ("high", "1"), ("wilson_low", "1"), ("wilson_high", "1"),
    ("clopper_pearson_low", "1"), ("inconclusive", "1"), ("warnings_not_listed", "1"), ("clopper_pearson_high", "1"), ("high_if_unrun_failed", "1"), ("kept_probability", "1"),
    ("outside_probability", "1"), ("within_lo", "the key's unit, given in `unit`"), ("within_hi", "the key's unit, given in `unit`"),
];

/// The JSON Schema of `flinch sample --json` (docs/schema/sample.json), every numeric field with
/// its `unit`; and the numeric fields without one (none, or the test fails).
pub fn schema() -> (String, Vec<String>) {
    use serde_json::Value;
    let mut schema = schemars::schema_for!(SampleReport);
    let mut missing = Vec::new();
    let numeric = |p: &Value| {
        let ty = |t: &Value| matches!(t.as_str(), Some("number" | "integer"));
        match p.get("type") {
            Some(Value::Array(a)) => a.iter().any(ty),
            Some(t) => ty(t),
            None => false,
        }
    };
    let mut visit = |obj: &mut serde_json::Map<String, Value>, at: &str| {
        if let Some(Value::Object(props)) = obj.get_mut("properties") {
            for (name, prop) in props.iter_mut() {
                if !numeric(prop) {
                    continue;
                }
                match UNITS.iter().find(|(n, _)| n == name) {
                    Some((_, u)) => {
                        if let Value::Object(p) = prop {
                            p.insert("unit".into(), Value::String((*u).into()));
                        }
                    }
                    None => missing.push(format!("{at}{name}")),
                }
            }
        }
    };
    if let Some(root) = schema.as_object_mut() {
        root.insert("description".into(), Value::String("`flinch sample --json`: the study, its counts and each failure's probability with a 95 % interval (docs/sample.md). Units: the `unit` keyword of every numeric field (docs/conventions.md).".into()));
        root.insert("$id".into(), Value::String("https://flinch.invalid/schema/sample.json".into()));
        visit(root, "");
        if let Some(Value::Object(defs)) = root.get_mut("$defs") {
            for (k, d) in defs.iter_mut() {
                if let Value::Object(o) = d {
                    visit(o, &format!("{k}."));
                }
            }
        }
    }
    let mut text = serde_json::to_string_pretty(&schema).unwrap_or_default();
    text.push('\n');
    (text, missing)
}

/// Raised by Ctrl-C (installed by the command line): no sample starts after it; the run keeps the
/// samples before the first that did not start.
pub static STOP: AtomicBool = AtomicBool::new(false);

