//! The time history as CSV: one row per recorded sample, names and units by docs/conventions.md
//! (`t_s`, `v_t_mps`, `f_contact_n`, ...; booleans 0/1; an empty cell where a value does not
//! exist), written through the `csv` crate into a 64 KiB buffer: rows stream out as the solver
//! makes them, so memory does not grow with the duration.

use crate::trace::Trace;
use flinch_sim::Sample;
use std::fmt::Write as _;
use std::io::{self, Write};

/// The columns every run writes, in order.
pub const COLUMNS: &[&str] = &["t_s", "v_c_mps", "v_r_mps", "v_t_mps", "v_p_mps", "s_m", "travel_m", "f_contact_n", "f_robot_n", "f_spring_n", "f_stops_n", "f_friction_n", "p_gas_pa"];
/// The columns `flinch hil` adds: the travel switch's level, the firmware's stop output and the
/// stop request as the robot controller last sampled it (0/1).
pub const HIL_COLUMNS: &[&str] = &["switch_tripped", "stop_requested", "stop_seen_by_controller"];

/// Streams rows of a run's history.
pub struct HistoryWriter<W: Write> {
    out: csv::Writer<W>,
    trace: Trace,
    cell: String,
    /// Rows written so far.
    pub rows: u64,
}

impl<W: Write> HistoryWriter<W> {
    /// Writes the header.
    pub fn new(out: W, trace: Trace) -> io::Result<Self> {
        let mut out = csv::WriterBuilder::new().buffer_capacity(1 << 16).from_writer(out);
        let mut header: Vec<&str> = COLUMNS.to_vec();
        if trace.hil.is_some() {
            header.extend_from_slice(HIL_COLUMNS);
        }
        out.write_record(&header).map_err(to_io)?;
        Ok(Self { out, trace, cell: String::with_capacity(32), rows: 0 })
    }

    fn field(&mut self, x: Option<f64>, exp: bool) -> io::Result<()> {
        self.cell.clear();
        match x {
            Some(v) if exp => { let _ = write!(self.cell, "{v:.6e}"); }
            Some(v) => { let _ = write!(self.cell, "{v:.9}"); }
            None => {}
        }
        self.out.write_field(&self.cell).map_err(to_io)
    }

    /// The column source (a `hil` run updates the firmware's signals as it goes).
    pub fn trace_mut(&mut self) -> &mut Trace {
        &mut self.trace
    }

    /// One row.
    pub fn row(&mut self, s: &Sample) -> io::Result<()> {
        self.field(Some(s.t), false)?;
        let travel = self.trace.travel(s);
        let gas = self.trace.gas_pressure(s);
        for v in [s.v_c, s.v_r, s.v_t, s.v_p, s.s, travel, s.f_contact, s.f_robot, s.f_spring, s.f_stops, s.f_friction] {
            self.field(Some(v), true)?;
        }
        self.field(gas, true)?;
        if self.trace.hil.is_some() {
            let bits = [self.trace.switch_tripped(s), self.trace.stop_requested(s.t), self.trace.stop_seen(s.t)];
            for b in bits {
                self.out.write_field(if b == Some(true) { "1" } else { "0" }).map_err(to_io)?;
            }
        }
        self.out.write_record(None::<&[u8]>).map_err(to_io)?;
        self.rows += 1;
        Ok(())
    }

    /// Flushes everything written so far to the underlying writer.
    pub fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }
}

fn to_io(e: csv::Error) -> io::Error {
    match e.into_kind() {
        csv::ErrorKind::Io(e) => e,
        other => io::Error::other(format!("{other:?}")),
    }
}

/// Writes a whole history (header and rows) and flushes.
pub fn write(out: &mut dyn Write, history: &[Sample], trace: &Trace) -> io::Result<()> {
    let mut w = HistoryWriter::new(out, trace.clone())?;
    for s in history {
        w.row(s)?;
    }
    w.flush()
}

/// Bytes a row takes, about (for the estimate printed before a long run).
pub const ROW_BYTES: u64 = 12 + 12 * 14;
