//! The document's rows ([`Row`]: the thesis's value, ours, the difference and the verdict), its
//! sections, and how numbers are written in it.


/// How a row compares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Within the stated tolerance, or the stated trend holds.
    Match,
    /// Outside it: the section's notes say why.
    Differs,
}

/// One compared quantity.
#[derive(Debug, Clone)]
pub struct Row {
    /// What is compared.
    pub quantity: String,
    /// The thesis's value or statement.
    pub thesis: String,
    /// Ours, from the simulator.
    pub ours: String,
    /// The difference (or the check applied).
    pub diff: String,
    /// Verdict.
    pub verdict: Verdict,
    /// The inputs the thesis leaves open for this row and how much each moves our result (measured
    /// here); empty when the row has none worth stating.
    pub open: String,
}

impl Row {
    /// The row with its open inputs stated.
    pub(crate) fn open(mut self, text: String) -> Self {
        self.open = text;
        self
    }
}

/// `text` in the open-inputs cell of every row that states none of its own.
pub(crate) fn open_rest(rows: &mut [Row], text: &str) {
    for r in rows.iter_mut().filter(|r| r.open.is_empty()) {
        r.open = text.to_string();
    }
}

/// One figure group.
#[derive(Debug, Clone)]
pub struct Section {
    /// Heading.
    pub title: String,
    /// Commands that reproduce it.
    pub commands: Vec<String>,
    /// Pictures (relative to the document).
    pub plots: Vec<String>,
    /// The table.
    pub rows: Vec<Row>,
    /// Where we differ and why.
    pub notes: Vec<String>,
}

/// Decimals that show `x` to three significant digits.
pub(crate) fn decimals(x: f64) -> usize {
    if x == 0.0 || !x.is_finite() { 2 } else { (2 - x.abs().log10().floor() as i32).max(0) as usize }
}

/// Three significant digits.
pub fn sig(x: f64) -> String {
    if !x.is_finite() {
        return "-".into();
    }
    if x == 0.0 {
        return "0".into();
    }
    let d = (2 - x.abs().log10().floor() as i32).max(0) as usize;
    format!("{x:.d$}")
}

pub(crate) fn num_row(quantity: &str, thesis: f64, ours: f64, unit: &str, tol_rel: f64) -> Row {
    let d = ours - thesis;
    let rel = if thesis != 0.0 { d / thesis.abs() } else { f64::NAN };
    let verdict = if rel.abs() <= tol_rel { Verdict::Match } else { Verdict::Differs };
    Row {
        quantity: quantity.into(),
        thesis: format!("{} {unit}", sig(thesis)).trim().into(),
        ours: format!("{} {unit}", sig(ours)).trim().into(),
        // The absolute difference to the thesis value's own resolution (three significant digits),
        // so a change far below what the thesis states does not change the document.
        diff: format!("{} ({} %, tolerance {:.0} %)", signed(d, decimals(thesis)), signed(rel * 100.0, 1), tol_rel * 100.0),
        verdict,
        open: String::new(),
    }
}

pub(crate) fn claim_row(quantity: &str, thesis: &str, ours: String, check: &str, holds: bool) -> Row {
    Row { quantity: quantity.into(), thesis: thesis.into(), ours, diff: format!("{check}: {}", if holds { "holds" } else { "does not hold" }), verdict: if holds { Verdict::Match } else { Verdict::Differs }, open: String::new() }
}

/// Milliseconds after `t0`, one decimal, signed ([`signed`]: an instant that rounds to `t0` is
/// "+0.0 ms", never "-0.0 ms").
pub(crate) fn ms_after(t: f64, t0: f64) -> String {
    format!("{} ms", signed((t - t0) * 1e3, 1))
}

/// `x` with its sign and `decimals` decimals, for people: a value that rounds to zero is "+0.0"
/// whatever side of zero it was on (Rust's `{:+.1}` writes -0.04 and -0.0 as "-0.0").
pub fn signed(x: f64, decimals: usize) -> String {
    let s = format!("{x:+.decimals$}");
    match s.strip_prefix('-') {
        Some(rest) if rest.bytes().all(|b| b == b'0' || b == b'.') => format!("+{rest}"),
        _ => s,
    }
}

/// Index of the value nearest `x` on an axis.
pub(crate) fn near(values: &[f64], x: f64) -> usize {
    values.iter().enumerate().min_by(|a, b| (a.1 - x).abs().total_cmp(&(b.1 - x).abs())).map_or(0, |(i, _)| i)
}

pub(crate) fn fmt_mode(m: Option<u8>) -> String {
    m.map_or("-".into(), |m| m.to_string())
}

/// R^2 of the least-squares line through (x, y).
pub(crate) fn r_squared(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    let syy: f64 = y.iter().map(|b| (b - my) * (b - my)).sum();
    sxy * sxy / (sxx * syy)
}
