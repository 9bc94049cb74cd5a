//! `flinch run SCENE --measured FILE.csv`: the user's own rig against the model, as the thesis
//! does in Figs. 34-35, 51 and 61. The file is CSV with a `t_s` column and any of the run's
//! columns by their convention names (`v_t_mps`, `v_r_mps`, `v_p_mps`, `v_c_mps`, `f_contact_n`,
//! `f_robot_n`, `travel_m`, `s_m`); `#` starts a comment line. For each column the run reports the
//! RMS error, the measured and simulated peaks and their difference, and the time shift that best
//! aligns the two (measured later than simulated is positive), with the RMS error after that shift.
//!
//! The simulated values are resampled onto a uniform grid over the measured span as the run
//! streams (no history is kept), the measured ones are interpolated onto the same grid.

use crate::trace::Trace;
use flinch_sim::Sample;
use schemars::JsonSchema;
use serde::Serialize;
use std::path::Path;

/// The columns a measured file may carry, with their units.
pub const COLUMNS: &[(&str, &str)] = &[("v_c_mps", "m/s"), ("v_r_mps", "m/s"), ("v_t_mps", "m/s"), ("v_p_mps", "m/s"), ("f_contact_n", "N"), ("f_robot_n", "N"), ("travel_m", "m"), ("s_m", "m")];

fn value(col: &str, s: &Sample, trace: &Trace) -> f64 {
    match col {
        "v_c_mps" => s.v_c,
        "v_r_mps" => s.v_r,
        "v_t_mps" => s.v_t,
        "v_p_mps" => s.v_p,
        "f_contact_n" => s.f_contact,
        "f_robot_n" => s.f_robot,
        "travel_m" => trace.travel(s),
        _ => s.s,
    }
}

/// A measured file, read and checked.
#[derive(Debug, Clone)]
pub struct Measured {
    /// The file, for messages.
    pub file: String,
    /// Times, s, increasing.
    pub t: Vec<f64>,
    /// (column, values) for every recognised column.
    pub columns: Vec<(String, Vec<f64>)>,
}

/// Most grid points a comparison uses (longer files are compared at this resolution).
const GRID_MAX: usize = 50_000;

impl Measured {
    /// Reads `path`; errors name the file, the line and the column.
    pub fn load(path: &Path) -> Result<Self, String> {
        // Through the one reader: regular files only, at most 256 MiB (docs/conventions.md).
        let text = flinch_output::input::read_text(path, flinch_output::input::Kind::Measured).map_err(|e| e.to_string())?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Parses CSV text.
    pub fn parse(text: &str, file: &str) -> Result<Self, String> {
        let mut rd = csv::ReaderBuilder::new().comment(Some(b'#')).trim(csv::Trim::All).from_reader(text.as_bytes());
        let header: Vec<String> = rd.headers().map_err(|e| format!("{file}: {e}"))?.iter().map(str::to_string).collect();
        let Some(ti) = header.iter().position(|h| h == "t_s") else {
            return Err(format!("{file}: no t_s column (time in seconds); the header is: {}", header.join(",")));
        };
        let mut cols: Vec<(usize, String)> = Vec::new();
        for (i, h) in header.iter().enumerate() {
            if i == ti {
                continue;
            }
            if COLUMNS.iter().any(|(c, _)| c == h) {
                cols.push((i, h.clone()));
            }
        }
        if cols.is_empty() {
            let known: Vec<&str> = COLUMNS.iter().map(|c| c.0).collect();
            return Err(format!("{file}: no column to compare; name at least one of {} (docs/conventions.md), got: {}", known.join(", "), header.join(",")));
        }
        let mut t = Vec::new();
        let mut values: Vec<Vec<f64>> = vec![Vec::new(); cols.len()];
        for rec in rd.records() {
            let rec = rec.map_err(|e| format!("{file}: {e}"))?;
            let line = rec.position().map_or(0, |p| p.line());
            let num = |i: usize, name: &str| -> Result<f64, String> {
                let cell = rec.get(i).unwrap_or("");
                cell.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| format!("{file}:{line}: {name}: expected a finite number, got {cell:?}"))
            };
            let ti_v = num(ti, "t_s")?;
            if let Some(&prev) = t.last() {
                if ti_v <= prev {
                    return Err(format!("{file}:{line}: t_s: times must increase, got {ti_v} after {prev}"));
                }
            }
            t.push(ti_v);
            for (k, (i, name)) in cols.iter().enumerate() {
                values[k].push(num(*i, name)?);
            }
        }
        if t.len() < 3 {
            return Err(format!("{file}: {} rows; a comparison needs at least 3", t.len()));
        }
        Ok(Self { file: file.to_string(), t, columns: cols.into_iter().map(|(_, n)| n).zip(values).collect() })
    }

    /// The uniform grid the comparison runs on.
    fn grid(&self) -> (f64, f64, usize) {
        let (a, b) = (self.t[0], self.t[self.t.len() - 1]);
        let n = self.t.len().clamp(3, GRID_MAX);
        (a, (b - a) / (n - 1) as f64, n)
    }
}

/// Linear interpolation of (t, y) at x (t increasing; clamped at the ends).
fn interp(t: &[f64], y: &[f64], x: f64) -> f64 {
    let i = t.partition_point(|&v| v < x);
    if i == 0 {
        return y[0];
    }
    if i >= t.len() {
        return y[t.len() - 1];
    }
    let (t0, t1) = (t[i - 1], t[i]);
    y[i - 1] + (y[i] - y[i - 1]) * (x - t0) / (t1 - t0)
}

/// Resamples a streamed run onto the measured grid, sample by sample.
#[derive(Debug, Clone)]
pub struct Resampler {
    grid: (f64, f64, usize),
    next: usize,
    prev: Option<Sample>,
    /// Simulated values on the grid, per measured column.
    sim: Vec<Vec<f64>>,
    names: Vec<String>,
    trace: Trace,
}

impl Resampler {
    /// For `m`.
    pub fn new(m: &Measured, trace: Trace) -> Self {
        let grid = m.grid();
        Self { grid, next: 0, prev: None, sim: vec![Vec::with_capacity(grid.2); m.columns.len()], names: m.columns.iter().map(|c| c.0.clone()).collect(), trace }
    }

    /// Takes the next sample of the run (time order).
    pub fn push(&mut self, s: &Sample) {
        let (a, dt, n) = self.grid;
        while self.next < n {
            let tg = a + dt * self.next as f64;
            if tg > s.t {
                break;
            }
            let w = match self.prev {
                Some(p) if s.t > p.t && tg >= p.t => (tg - p.t) / (s.t - p.t),
                _ => 1.0,
            };
            for (k, name) in self.names.iter().enumerate() {
                let now = value(name, s, &self.trace);
                let v = self.prev.map_or(now, |p| {
                    let before = value(name, &p, &self.trace);
                    before + (now - before) * w
                });
                self.sim[k].push(v);
            }
            self.next += 1;
        }
        self.prev = Some(*s);
    }

    /// The comparison, once the run is over (grid points past the run's end are left out).
    pub fn compare(&self, m: &Measured) -> Vec<Comparison> {
        let (a, dt, _) = self.grid;
        let mut out = Vec::new();
        for (k, (name, ys)) in m.columns.iter().enumerate() {
            let sim = &self.sim[k];
            let n = sim.len();
            if n < 3 {
                continue;
            }
            let meas: Vec<f64> = (0..n).map(|i| interp(&m.t, ys, a + dt * i as f64)).collect();
            let rms = |lag: isize| -> f64 {
                let (mut sum, mut cnt) = (0.0, 0usize);
                for i in 0..n as isize {
                    let j = i - lag;
                    if j < 0 || j >= n as isize {
                        continue;
                    }
                    let d = meas[i as usize] - sim[j as usize];
                    sum += d * d;
                    cnt += 1;
                }
                if cnt * 2 < n { f64::INFINITY } else { (sum / cnt as f64).sqrt() }
            };
            let max_lag = (n / 10).min(2_000) as isize;
            let (mut best, mut best_rms) = (0isize, rms(0));
            for lag in -max_lag..=max_lag {
                let r = rms(lag);
                if r < best_rms {
                    (best, best_rms) = (lag, r);
                }
            }
            let peak = |v: &[f64]| v.iter().copied().fold(0.0f64, |acc, x| if x.abs() > acc.abs() { x } else { acc });
            let (pm, ps) = (peak(&meas), peak(sim));
            let unit = COLUMNS.iter().find(|c| c.0 == name).map_or("", |c| c.1).to_string();
            out.push(Comparison {
                column: name.clone(),
                unit,
                points: n as u64,
                rms_error: rms(0),
                peak_measured: pm,
                peak_simulated: ps,
                peak_error: ps - pm,
                time_shift_s: best as f64 * dt,
                rms_error_shifted: best_rms,
            });
        }
        out
    }
}

/// One measured column against the run.
#[derive(Debug, Clone, Serialize, JsonSchema, PartialEq)]
pub struct Comparison {
    /// The column compared (a convention name: the unit is its suffix).
    pub column: String,
    /// Unit of the errors and peaks below ("m/s", "N", "m").
    pub unit: String,
    /// Grid points compared.
    pub points: u64,
    /// RMS of measured - simulated, in `unit`.
    pub rms_error: f64,
    /// The measured value of largest magnitude, in `unit`.
    pub peak_measured: f64,
    /// The simulated value of largest magnitude over the measured span, in `unit`.
    pub peak_simulated: f64,
    /// peak_simulated - peak_measured, in `unit`.
    pub peak_error: f64,
    /// The shift of the measured trace against the simulated one that minimises the RMS error
    /// (positive: the measurement happens later), s; searched within a tenth of the span.
    pub time_shift_s: f64,
    /// RMS error after that shift, in `unit`.
    pub rms_error_shifted: f64,
}

/// The measured traces to overlay on a plot: (column, points).
pub fn overlay(m: &Measured) -> Vec<(String, Vec<(f64, f64)>)> {
    m.columns.iter().map(|(n, v)| (n.clone(), m.t.iter().copied().zip(v.iter().copied()).collect())).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_name_the_file_line_and_column() {
        let e = Measured::parse("t_s,v_t_mps\n0,1\n0.1,x\n", "m.csv").unwrap_err();
        assert!(e.starts_with("m.csv:3: v_t_mps"), "{e}");
        let e = Measured::parse("time,v\n0,1\n", "m.csv").unwrap_err();
        assert!(e.contains("no t_s column"), "{e}");
        let e = Measured::parse("t_s,speed\n0,1\n", "m.csv").unwrap_err();
        assert!(e.contains("no column to compare"), "{e}");
        let e = Measured::parse("t_s,v_t_mps\n0,1\n0,2\n1,2\n", "m.csv").unwrap_err();
        assert!(e.contains("must increase"), "{e}");
    }
}
