//! `sample --merge`: every count of a chunk's report must add up before it is merged (issue 27).
//! A report edited by hand, cut short or from another build is refused naming the field, with
//! checked arithmetic (a count near 2^64 is a refusal, not a wrapped sum): `--merge m.json: not a
//! consistent `flinch sample --json` report: modes: mode_1 + mode_2 + mode_3 + no_mode = 5069, but
//! 99 of its 100 runs concluded`.
use super::common::CONFIDENCE;
use super::report::{merge, SampleReport};
use crate::sweep::SweepError;

/// [`merge`] after every report's counts are checked (`flinch sample --merge` calls this): the first
/// report whose counts do not add up is refused, naming it and the field.
pub fn merge_checked(reports: &[SampleReport], names: &[String]) -> Result<SampleReport, SweepError> {
    for (i, r) in reports.iter().enumerate() {
        if let Err((field, what)) = consistent(r) {
            let name = names.get(i).cloned().unwrap_or_else(|| format!("report {}", i + 1));
            return Err(SweepError(format!("--merge {name}: not a consistent `flinch sample --json` report: {field}: {what}")));
        }
    }
    merge(reports, names)
}

fn add(xs: &[u64]) -> Option<u64> {
    xs.iter().try_fold(0u64, |a, &x| a.checked_add(x))
}

fn shown(s: Option<u64>) -> String {
    s.map_or_else(|| "more than 2^64".to_string(), |s| s.to_string())
}

/// Every count of one report adds up; `Err((field, what))` names the first that does not.
pub(super) fn consistent(r: &SampleReport) -> Result<(), (String, String)> {
    let bad = |field: &str, what: String| Err((field.to_string(), what));
    if r.samples == 0 {
        return bad("samples", "0: a study has at least one sample".into());
    }
    // Ranges: ascending, disjoint, inside the study.
    let mut at = 0u64;
    let mut covered = 0u64;
    for x in &r.ranges {
        if x[0] >= x[1] || x[1] > r.samples || x[0] < at {
            return bad("ranges", format!("{}..{} is not an ascending, disjoint range within 0..{}", x[0], x[1], r.samples));
        }
        at = x[1];
        covered += x[1] - x[0]; // no overflow: disjoint and each end <= samples
    }
    let inside = |i: u64| r.ranges.iter().any(|x| x[0] <= i && i < x[1]);
    if covered != r.drawn {
        return bad("drawn", format!("{} but its ranges cover {covered} samples", r.drawn));
    }
    let complete = r.ranges.len() == 1 && r.ranges[0] == [0, r.samples];
    if r.complete != complete {
        return bad("complete", format!("{} but its ranges are {:?} of {} samples", r.complete, r.ranges, r.samples));
    }
    match add(&[r.ran, r.refused, r.solver_failed]) {
        Some(s) if s == r.drawn => {}
        s => return bad("ran", format!("ran {} + refused {} + solver_failed {} = {}, not drawn = {}", r.ran, r.refused, r.solver_failed, shown(s), r.drawn)),
    }
    if r.inconclusive > r.ran {
        return bad("inconclusive", format!("{} of {} runs", r.inconclusive, r.ran));
    }
    match &r.inconclusive_first {
        None if r.inconclusive == 0 => {}
        Some(f) if f.count == r.inconclusive && inside(f.first_sample) => {}
        Some(f) => return bad("inconclusive_first", format!("count {} from sample {}, but inconclusive = {} within the ranges {:?}", f.count, f.first_sample, r.inconclusive, r.ranges)),
        None => return bad("inconclusive_first", format!("missing with inconclusive = {}", r.inconclusive)),
    }
    let concluded = r.ran - r.inconclusive;
    let m = &r.modes;
    match add(&[m.mode_1, m.mode_2, m.mode_3, m.no_mode]) {
        Some(s) if s == concluded => {}
        s => return bad("modes", format!("mode_1 + mode_2 + mode_3 + no_mode = {}, but {concluded} of its {} runs concluded", shown(s), r.ran)),
    }
    let counts: Vec<u64> = r.refusals.iter().map(|g| g.count).collect();
    if add(&counts) != Some(r.refused) {
        return bad("refusals", format!("the groups' counts sum to {}, but refused = {}", shown(add(&counts)), r.refused));
    }
    if let Some(g) = r.refusals.iter().find(|g| g.count == 0 || g.keys.is_empty() || !inside(g.first_sample)) {
        return bad("refusals", format!("a group ({} of keys [{}], first sample {}) is empty or outside the ranges", g.count, g.keys.join(", "), g.first_sample));
    }
    match &r.solver_failures {
        None if r.solver_failed == 0 => {}
        Some(f) if f.count == r.solver_failed && inside(f.first_sample) => {}
        other => return bad("solver_failures", format!("{} but solver_failed = {}", other.as_ref().map_or_else(|| "absent".to_string(), |f| format!("count {} from sample {}", f.count, f.first_sample)), r.solver_failed)),
    }
    if let Some(w) = r.warnings.iter().find(|w| w.count == 0 || !inside(w.first_sample)) {
        return bad("warnings", format!("group \"{}\" counts {} from sample {}: empty or outside the ranges", w.kind, w.count, w.first_sample));
    }
    if r.confidence != CONFIDENCE {
        return bad("confidence", format!("{}; flinch sample reports {CONFIDENCE}", r.confidence));
    }
    for e in &r.estimates {
        let field = format!("estimates: {}", e.failure);
        if e.failures > e.runs || e.runs > r.ran || e.runs.saturating_add(r.inconclusive) < r.ran {
            return bad(&field, format!("{} failures of {} runs, and {} samples ran, {} of them inconclusive", e.failures, e.runs, r.ran, r.inconclusive));
        }
        let p = (e.runs > 0).then(|| e.failures as f64 / e.runs as f64);
        if p != e.p {
            return bad(&field, format!("p = {:?}, but {} failures of {} runs is {:?}", e.p, e.failures, e.runs, p));
        }
        if e.failure == "mode_3" && e.failures < r.modes.mode_3 {
            return bad(&field, format!("{} failures, but modes.mode_3 = {}", e.failures, r.modes.mode_3));
        }
        let ends = [e.low, e.high, e.wilson_low, e.wilson_high, e.clopper_pearson_low, e.clopper_pearson_high, e.high_if_unrun_failed];
        if ends.iter().any(|x| !(0.0..=1.0).contains(x)) || e.low > e.high {
            return bad(&field, format!("an interval end outside [0, 1] or low > high: {ends:?}"));
        }
    }
    Ok(())
}
