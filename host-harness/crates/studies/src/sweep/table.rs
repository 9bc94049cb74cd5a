//! A sweep's CSV: a row per point with its status, reason and every metric.

use flinch_sim::Summary;
use serde_json::Value as Json;
use std::io::{self, Write};
use super::{axis::*, grid::*, metrics::*};


pub(crate) fn csv_cell(v: &Json) -> String {
    match v {
        Json::Null => String::new(),
        Json::Bool(b) => b.to_string(),
        Json::Number(n) => n.to_string(),
        Json::String(s) => s.clone(),
        Json::Array(a) => a.iter().map(|x| x.as_str().map_or_else(|| x.to_string(), str::to_string)).collect::<Vec<_>>().join("; "),
        Json::Object(_) => v.to_string(),
    }
}

/// A CSV writer's error as the I/O error it wraps, keeping its kind: `io::Error::from(csv::Error)`
/// has kind Other, so a closed reader (`| head`) was reported as an error, exit 3, instead of the
/// quiet exit 141 of docs/conventions.md.
pub fn csv_io(e: csv::Error) -> io::Error {
    if !matches!(e.kind(), csv::ErrorKind::Io(_)) {
        return io::Error::other(e);
    }
    match e.into_kind() {
        csv::ErrorKind::Io(e) => e,
        k => io::Error::other(format!("{k:?}")),
    }
}

/// The CSV's header: the swept keys, the summary fields `names`, `status`, `reason`.
pub(crate) fn header(axes: &[Axis], names: &[String]) -> Vec<String> {
    let mut header: Vec<String> = axes.iter().map(|a| a.key.clone()).collect();
    header.extend(names.iter().cloned());
    header.push("status".into());
    header.push("reason".into());
    header
}

/// The summary fields a sweep's CSV carries: every one but `simulated`, which is the same text at
/// every point but the swept keys (the sweep prints it once, on standard error); `name_mismatches`
/// stays, per point.
pub(crate) fn csv_names(s: &Summary) -> Vec<String> {
    summary_fields(s).into_iter().map(|(k, _)| k).filter(|k| k != "simulated").collect()
}

/// One point's CSV row under the summary fields `names`.
pub(crate) fn record(p: &Point, names: &[String]) -> Vec<String> {
    let mut row: Vec<String> = p.values.iter().map(|x| x.to_string()).collect();
    match &p.outcome {
        Ok(s) => {
            let fields = summary_map(s);
            row.extend(names.iter().map(|n| fields.get(n).map_or(String::new(), csv_cell)));
            // A point that ran but is not concluded is `inconclusive` (the set `sample` uses); the
            // reason says why, and why a point is not as commanded (issue 26 item 3).
            let mut why: Vec<String> = Vec::new();
            if !s.concluded {
                why.push(format!("not concluded: {}", s.failures.iter().find(|f| f.starts_with("not concluded")).map_or("the robot had not stopped by the run's end", |f| f.trim_start_matches("not concluded: "))));
            }
            why.extend(s.not_as_commanded.iter().map(|m| format!("not as commanded: {m}")));
            row.push(if s.concluded { p.status.as_str() } else { "inconclusive" }.into());
            row.push(why.join("; "));
        }
        Err(e) => {
            row.extend(names.iter().map(|_| String::new()));
            row.push(p.status.as_str().into());
            row.push(e.clone());
        }
    }
    row
}

/// A sweep's CSV written row by row as the points arrive in grid order (`flinch sweep`): the same
/// bytes as [`SweepResult::write_csv`] of the same points. The header needs a run's summary for its
/// field names: rows before the first point that ran wait (refused or failed rows, a few bytes each).
pub struct RowWriter<W: Write> {
    w: csv::Writer<W>,
    axes: Vec<Axis>,
    names: Option<Vec<String>>,
    waiting: Vec<Point>,
    /// Rows written.
    pub rows: usize,
}

impl<W: Write> RowWriter<W> {
    /// A writer for a sweep over `axes`.
    pub fn new(out: W, axes: &[Axis]) -> Self {
        Self { w: csv::Writer::from_writer(out), axes: axes.to_vec(), names: None, waiting: Vec::new(), rows: 0 }
    }

    /// Takes the next point in grid order.
    pub fn push(&mut self, p: Point) -> io::Result<()> {
        if self.names.is_none() {
            match &p.outcome {
                Ok(s) => {
                    let names = csv_names(s);
                    self.w.write_record(header(&self.axes, &names)).map_err(csv_io)?;
                    self.names = Some(names);
                    for q in std::mem::take(&mut self.waiting) {
                        self.write(&q)?;
                    }
                }
                Err(_) => {
                    self.waiting.push(p);
                    return Ok(());
                }
            }
        }
        self.write(&p)
    }

    fn write(&mut self, p: &Point) -> io::Result<()> {
        let names = self.names.as_deref().unwrap_or(&[]);
        self.w.write_record(record(p, names)).map_err(csv_io)?;
        self.rows += 1;
        Ok(())
    }

    /// Writes what waits (with no summary fields if no point ran) and flushes.
    pub fn finish(&mut self) -> io::Result<()> {
        if self.names.is_none() {
            self.w.write_record(header(&self.axes, &[])).map_err(csv_io)?;
            self.names = Some(Vec::new());
            for q in std::mem::take(&mut self.waiting) {
                self.write(&q)?;
            }
        }
        self.w.flush()
    }
}

impl SweepResult {
    /// Writes the CSV (the `csv` crate quotes): the swept keys, every `Summary` field, then
    /// `status` (ok, inconclusive: ran but not concluded, refused, failed) and `reason` (the
    /// validator's or the solver's message; for a point that ran, why it is not concluded or not
    /// as commanded).
    pub fn write_csv(&self, out: &mut dyn Write) -> io::Result<()> {
        // `simulated` is the same text at every point but the swept keys: the sweep prints it once
        // (standard error); `name_mismatches` stays, per point.
        let names: Vec<String> = self.points.iter().find_map(|p| p.outcome.as_ref().ok()).map(csv_names).unwrap_or_default();
        let mut w = csv::Writer::from_writer(out);
        w.write_record(header(&self.axes, &names)).map_err(csv_io)?;
        for p in &self.points {
            w.write_record(record(p, &names)).map_err(csv_io)?;
        }
        w.flush()
    }

    /// The CSV as a string.
    pub fn csv(&self) -> String {
        let mut v = Vec::new();
        let _ = self.write_csv(&mut v);
        String::from_utf8_lossy(&v).into_owned()
    }

    /// A metric at every point (NaN where missing or failed), row-major.
    pub fn metric(&self, name: &str) -> Vec<f64> {
        self.points.iter().map(|p| p.outcome.as_ref().ok().and_then(|s| metric(s, name)).unwrap_or(f64::NAN)).collect()
    }

    /// The summary at grid indices `idx` (one per axis), if that point ran.
    pub fn at(&self, idx: &[usize]) -> Option<&Summary> {
        let sizes: Vec<usize> = self.values.iter().map(Vec::len).collect();
        let mut k = 0;
        for (i, n) in idx.iter().zip(&sizes) {
            k = k * n + i;
        }
        self.points.get(k).and_then(|p| p.outcome.as_ref().ok())
    }

    /// Points whose solver failed.
    pub fn failures(&self) -> usize {
        self.points.iter().filter(|p| p.status == Status::Failed).count()
    }

    /// Points the validator refused.
    pub fn refused(&self) -> usize {
        self.points.iter().filter(|p| p.status == Status::Refused).count()
    }
}
