//! One axis of a sweep ([`Axis`]): a key and its values, linear or logarithmic, parsed from
//! `KEY=START:STOP:N`.

use super::error::*;

/// How the values of an axis are spaced.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Spacing {
    /// Equal steps.
    Linear,
    /// Equal ratios (START > 0).
    Log,
}

/// One swept key and its values.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// Dotted key path in the scene file, e.g. `motion.speed`.
    pub key: String,
    /// First value.
    pub start: f64,
    /// Last value.
    pub stop: f64,
    /// Number of values, >= 2.
    pub n: usize,
    /// Linear or geometric.
    pub spacing: Spacing,
}

impl Axis {
    /// A checked axis: finite `start < stop`, `n >= 2`, `start > 0` when geometric.
    pub fn new(key: &str, start: f64, stop: f64, n: usize, spacing: Spacing) -> Result<Self, SweepError> {
        let key = key.trim();
        if key.is_empty() || key.split('.').any(|s| s.trim().is_empty()) {
            return err(format!("--vary {key:?}: the key must be a dotted path such as motion.speed"));
        }
        if !start.is_finite() || !stop.is_finite() {
            return err(format!("--vary {key}: START and STOP must be finite numbers, got {start} and {stop}"));
        }
        if n < 2 {
            return err(format!("--vary {key}: N must be at least 2 (a sweep of one value is `flinch run`), got {n}"));
        }
        if n > 100_000 {
            return err(format!("--vary {key}: N = {n} is more than 100000 points on one axis"));
        }
        if start >= stop {
            return err(format!("--vary {key}: START must be below STOP, got {start} >= {stop}"));
        }
        if spacing == Spacing::Log && start <= 0.0 {
            return err(format!("--vary {key}: a log axis needs START > 0, got {start}"));
        }
        Ok(Self { key: key.to_string(), start, stop, n, spacing })
    }

    /// Parses `KEY=START:STOP:N` or `KEY=log:START:STOP:N`; `log` forces geometric steps.
    pub fn parse(spec: &str, log: bool) -> Result<Self, SweepError> {
        let Some((key, range)) = spec.split_once('=') else {
            return err(format!("--vary {spec:?}: expected KEY=START:STOP:N (or KEY=log:START:STOP:N), e.g. motion.speed=0.01:0.3:30"));
        };
        let mut parts: Vec<&str> = range.split(':').map(str::trim).collect();
        let mut spacing = if log { Spacing::Log } else { Spacing::Linear };
        if parts.first().is_some_and(|p| p.eq_ignore_ascii_case("log")) {
            spacing = Spacing::Log;
            parts.remove(0);
        } else if parts.first().is_some_and(|p| p.eq_ignore_ascii_case("lin")) {
            parts.remove(0);
        }
        let key = key.trim();
        if parts.len() != 3 {
            return err(format!("--vary {spec:?}: expected {key}=START:STOP:N (three fields after '=', optionally prefixed by log:), got {}", parts.len()));
        }
        let number = |what: &str, s: &str| s.parse::<f64>().map_err(|_| SweepError(format!("--vary {spec:?}: {what} {s:?} is not a number")));
        let start = number("START", parts[0])?;
        let stop = number("STOP", parts[1])?;
        let n = parts[2].parse::<usize>().map_err(|_| SweepError(format!("--vary {spec:?}: N {:?} is not a whole number >= 2", parts[2])))?;
        Self::new(key, start, stop, n, spacing)
    }

    /// The values, first and last exact.
    pub fn values(&self) -> Vec<f64> {
        let last = (self.n - 1) as f64;
        (0..self.n)
            .map(|i| match i {
                0 => self.start,
                i if i == self.n - 1 => self.stop,
                i => {
                    let f = i as f64 / last;
                    let x = match self.spacing {
                        Spacing::Linear => self.start + (self.stop - self.start) * f,
                        Spacing::Log => (self.start.ln() + (self.stop.ln() - self.start.ln()) * f).exp(),
                    };
                    // 12 significant digits: 0.15, not 0.15000000000000002, in files and CSVs.
                    format!("{x:.11e}").parse().unwrap_or(x)
                }
            })
            .collect()
    }
}
