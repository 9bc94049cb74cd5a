//! Which instants a run records: every `output_interval` from t = 0, whatever the steps, and how
//! many rows a run of a duration holds.

/// When row `k` of a history at interval `dt` falls in the step `[t0, t1]`: at `k dt`, a product,
/// not a running sum (6e5 additions of 1e-4 drifted to 1e-9 s past the end of a 60 s run, whose
/// last row was then lost); a row within `1e-9 dt` past the step's end is taken at its end (the
/// rounding of `k dt` itself). [`recorded_rows`] counts them.
pub fn record_due(k: u64, dt: f64, t0: f64, t1: f64) -> Option<f64> {
    let tk = k as f64 * dt;
    (tk <= t1 + 1e-9 * dt).then(|| tk.clamp(t0, t1))
}

/// Rows a run of `duration` s records at `dt` > 0: `k dt` for every `k` that [`record_due`] takes.
pub fn recorded_rows(duration: f64, dt: f64) -> u64 {
    let n = (duration / dt + 1e-9).floor();
    let Some(mut k) = (n.is_finite() && n >= 0.0).then(|| n.min(1e18) as u64) else { return u64::MAX };
    // The division's own rounding: the test `record_due` makes decides the last row.
    for _ in 0..3 {
        if record_due(k + 1, dt, duration, duration).is_some() {
            k += 1;
        } else if k > 0 && record_due(k, dt, duration, duration).is_none() {
            k -= 1;
        }
    }
    k + 1
}
