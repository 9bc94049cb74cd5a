//! `flinch sample --parquet FILE`: the CSV's rows as an Apache Parquet file, written a row group
//! at a time so memory holds one row group whatever N.
//!
//! The columns are the CSV's ([`Plan::header`]), with the same names and meaning, in Parquet's own
//! types: `sample` INT64; each varied key DOUBLE; `stroke_exhausted`, `safe`, `body_limits_pass`
//! BOOLEAN; `mode` INT32; the forces and `stroke_left_min_m` DOUBLE; `status` and `reason` UTF-8
//! strings. Where the CSV has an empty cell (a sample that did not run, no mode, no stroke left,
//! `reason` of a sample that ran) the Parquet value is null, not NaN or false.
//!
//! Rows are buffered column by column and written as one row group when [`ParquetRows::group_rows`]
//! of them are in (the command line uses [`ROW_GROUP`], a multiple of [`BLOCK`]); [`ParquetRows::finish`]
//! writes the rows still buffered as a last, shorter row group and the footer. The command line calls
//! it on every ending (normal end, Ctrl-C, a write error on the CSV); dropping an unfinished writer
//! (a panic unwinding) finishes it too, so the file on disk is always a valid Parquet file holding
//! whole rows, as the CSV always ends on a complete row.

use super::common::BLOCK;
use super::outcome::{Outcome, Row};
use super::plan::Plan;
use parquet::basic::{LogicalType, Repetition, Type as Physical};
use parquet::data_type::{BoolType, ByteArray, ByteArrayType, DataType, DoubleType, Int32Type, Int64Type};
use parquet::file::metadata::KeyValue;
use parquet::file::properties::{EnabledStatistics, WriterProperties};
use parquet::file::writer::{SerializedFileWriter, SerializedRowGroupWriter};
use parquet::schema::types::Type;
use std::io::{self, Write};
use std::sync::Arc;

/// Rows per row group on the command line: 16 blocks of [`BLOCK`] (32,768 rows). A row group is
/// what the writer holds before writing it; the footer lists every row group, so the groups are
/// not one block each (at N = 1e8 that footer would hold 48,829 row groups' metadata in memory).
pub const ROW_GROUP: usize = 16 * BLOCK;

/// A nullable column's buffer: the values present and a definition level per row (1 present, 0 null).
#[derive(Default)]
struct Nullable<T> {
    values: Vec<T>,
    defs: Vec<i16>,
}

impl<T> Nullable<T> {
    fn push(&mut self, v: Option<T>) {
        self.defs.push(i16::from(v.is_some()));
        self.values.extend(v);
    }
    fn clear(&mut self) {
        self.values.clear();
        self.defs.clear();
    }
}

/// The rows of a `flinch sample` run, streamed to a Parquet file (module documentation).
pub struct ParquetRows {
    writer: Option<SerializedFileWriter<Box<dyn Write + Send>>>,
    body: bool,
    group_rows: usize,
    sample: Vec<i64>,
    keys: Vec<Vec<f64>>,
    stroke_exhausted: Nullable<bool>,
    mode: Nullable<i32>,
    peak_contact_force_n: Nullable<f64>,
    peak_robot_force_n: Nullable<f64>,
    stroke_left_min_m: Nullable<f64>,
    safe: Nullable<bool>,
    body_limits_pass: Nullable<bool>,
    status: Vec<ByteArray>,
    reason: Nullable<ByteArray>,
    groups: Vec<usize>,
    failed: bool,
    /// `ok`, `refused`, `failed`, `inconclusive`: cloned per row (a reference count, not an allocation).
    statuses: [ByteArray; 4],
}

fn pq(e: parquet::errors::ParquetError) -> io::Error {
    match e {
        parquet::errors::ParquetError::External(e) => match e.downcast::<io::Error>() {
            Ok(e) => *e,
            Err(e) => io::Error::other(e),
        },
        e => io::Error::other(e),
    }
}

fn field(name: &str, ty: Physical, rep: Repetition, logical: Option<LogicalType>) -> io::Result<Arc<Type>> {
    Type::primitive_type_builder(name, ty).with_repetition(rep).with_logical_type(logical).build().map(Arc::new).map_err(pq)
}

impl ParquetRows {
    /// Starts the file on `out` for `plan`'s columns, writing a row group every `group_rows` rows
    /// (at least 1). The study (scene, its hash, seed, N, the keys and distributions, the range of
    /// sample indices this run covers) goes in the file's key-value metadata under `flinch.*`.
    pub fn new(plan: &Plan, out: Box<dyn Write + Send>, group_rows: usize) -> io::Result<Self> {
        use Physical::{BOOLEAN, BYTE_ARRAY, DOUBLE, INT32, INT64};
        const OPTIONAL: Repetition = Repetition::OPTIONAL;
        const REQUIRED: Repetition = Repetition::REQUIRED;
        let body = plan.body();
        let mut fields = Vec::new();
        for name in plan.header() {
            let v = plan.vary.iter().any(|v| v.column == name);
            fields.push(match name.as_str() {
                _ if v => field(&name, DOUBLE, REQUIRED, None)?,
                "sample" => field(&name, INT64, REQUIRED, None)?,
                "stroke_exhausted" | "safe" | "body_limits_pass" => field(&name, BOOLEAN, OPTIONAL, None)?,
                "mode" => field(&name, INT32, OPTIONAL, None)?,
                "peak_contact_force_n" | "peak_robot_force_n" | "stroke_left_min_m" => field(&name, DOUBLE, OPTIONAL, None)?,
                "status" => field(&name, BYTE_ARRAY, REQUIRED, Some(LogicalType::String))?,
                "reason" => field(&name, BYTE_ARRAY, OPTIONAL, Some(LogicalType::String))?,
                other => return Err(io::Error::other(format!("no Parquet type for the column {other:?}"))),
            });
        }
        let schema = Type::group_type_builder("flinch_sample").with_fields(fields).build().map_err(pq)?;
        let kv = |k: &str, v: String| KeyValue::new(format!("flinch.{k}"), v);
        let vary: Vec<String> = plan.vary.iter().map(|v| v.spec.spec()).collect();
        let meta = vec![
            kv("scene", plan.template.base.name.clone()),
            kv("scene_file", plan.template.file().to_string()),
            kv("scene_fnv1a64", plan.scene_hash.clone()),
            kv("seed", plan.seed.to_string()),
            kv("samples", plan.samples.to_string()),
            kv("range", format!("{}..{}", plan.range.0, plan.range.1)),
            kv("truncate", plan.truncate.to_string()),
            kv("vary", vary.join(" ")),
        ];
        // Chunk statistics only (no page index): the footer's metadata per row group stays small.
        let props = WriterProperties::builder()
            .set_created_by(format!("flinch sample {} ({})", env!("CARGO_PKG_VERSION"), parquet::file::properties::DEFAULT_CREATED_BY))
            .set_statistics_enabled(EnabledStatistics::Chunk)
            .set_offset_index_disabled(true)
            .set_key_value_metadata(Some(meta))
            .build();
        let writer = SerializedFileWriter::new(out, Arc::new(schema), Arc::new(props)).map_err(pq)?;
        let group_rows = group_rows.max(1);
        let cap = group_rows.min(ROW_GROUP);
        Ok(Self {
            writer: Some(writer),
            body,
            group_rows,
            sample: Vec::with_capacity(cap),
            keys: vec![Vec::with_capacity(cap); plan.vary.len()],
            stroke_exhausted: Nullable::default(),
            mode: Nullable::default(),
            peak_contact_force_n: Nullable::default(),
            peak_robot_force_n: Nullable::default(),
            stroke_left_min_m: Nullable::default(),
            safe: Nullable::default(),
            body_limits_pass: Nullable::default(),
            status: Vec::with_capacity(cap),
            reason: Nullable::default(),
            groups: Vec::new(),
            failed: false,
            statuses: ["ok", "refused", "failed", "inconclusive"].map(ByteArray::from),
        })
    }

    /// Rows per row group.
    pub fn group_rows(&self) -> usize {
        self.group_rows
    }

    /// Rows buffered, not yet written (never more than [`Self::group_rows`]).
    pub fn buffered(&self) -> usize {
        self.sample.len()
    }

    /// The rows of each row group written so far.
    pub fn groups(&self) -> &[usize] {
        &self.groups
    }

    /// True once writing the file failed (an error from [`Self::push`] is this file's).
    pub fn failed(&self) -> bool {
        self.failed
    }

    /// Adds a row (rows come in sample order); writes a row group when one is full.
    pub fn push(&mut self, r: &Row) -> io::Result<()> {
        let pushed = self.push_row(r);
        self.failed |= pushed.is_err();
        pushed
    }

    fn push_row(&mut self, r: &Row) -> io::Result<()> {
        if self.writer.is_none() {
            return Err(io::Error::other("the Parquet file is already finished"));
        }
        if r.values.len() != self.keys.len() {
            return Err(io::Error::other(format!("a row with {} values for {} keys", r.values.len(), self.keys.len())));
        }
        let index = i64::try_from(r.index).map_err(|_| io::Error::other(format!("sample index {} does not fit Parquet's INT64", r.index)))?;
        self.sample.push(index);
        for (k, &x) in self.keys.iter_mut().zip(&r.values) {
            k.push(x);
        }
        let ran = match &r.outcome {
            Outcome::Ran(b) => Some(b),
            _ => None,
        };
        // Not concluded: a failure seen before the run's end is known, else the stroke, the mode
        // and the body limits are unknown (null, as the CSV's empty cells); the peaks and the
        // stroke left are up to the end.
        let concluded = |b: &&super::outcome::Brief| b.not_concluded.is_none();
        self.stroke_exhausted.push(ran.filter(|b| concluded(b) || b.stroke_exhausted).map(|b| b.stroke_exhausted));
        self.mode.push(ran.filter(|b| concluded(b) || b.mode == Some(3)).and_then(|b| b.mode).map(i32::from));
        self.peak_contact_force_n.push(ran.map(|b| b.peak_contact_force_n));
        self.peak_robot_force_n.push(ran.map(|b| b.peak_robot_force_n));
        self.stroke_left_min_m.push(ran.and_then(|b| b.stroke_left_min_m));
        self.safe.push(ran.map(|b| b.safe));
        if self.body {
            self.body_limits_pass.push(ran.filter(|b| concluded(b) || b.body_limits_pass == Some(false)).and_then(|b| b.body_limits_pass));
        }
        let (status, reason) = match &r.outcome {
            Outcome::Ran(b) => match &b.not_concluded {
                None => (0, None),
                Some(why) => (3, Some(why.as_str())),
            },
            Outcome::Refused { reason, .. } => (1, Some(reason.as_str())),
            Outcome::Failed(why) => (2, Some(why.as_str())),
        };
        self.status.push(self.statuses[status].clone());
        self.reason.push(reason.map(ByteArray::from));
        if self.sample.len() >= self.group_rows {
            self.write_group()?;
        }
        Ok(())
    }

    /// Writes the buffered rows as one row group.
    fn write_group(&mut self) -> io::Result<()> {
        let n = self.sample.len();
        if n == 0 {
            return Ok(());
        }
        let Some(w) = self.writer.as_mut() else { return Ok(()) };
        let mut g = w.next_row_group().map_err(pq)?;
        let result = (|| {
            column::<Int64Type>(&mut g, &self.sample, None)?;
            for k in &self.keys {
                column::<DoubleType>(&mut g, k, None)?;
            }
            column::<BoolType>(&mut g, &self.stroke_exhausted.values, Some(&self.stroke_exhausted.defs))?;
            column::<Int32Type>(&mut g, &self.mode.values, Some(&self.mode.defs))?;
            for c in [&self.peak_contact_force_n, &self.peak_robot_force_n, &self.stroke_left_min_m] {
                column::<DoubleType>(&mut g, &c.values, Some(&c.defs))?;
            }
            column::<BoolType>(&mut g, &self.safe.values, Some(&self.safe.defs))?;
            if self.body {
                column::<BoolType>(&mut g, &self.body_limits_pass.values, Some(&self.body_limits_pass.defs))?;
            }
            column::<ByteArrayType>(&mut g, &self.status, None)?;
            column::<ByteArrayType>(&mut g, &self.reason.values, Some(&self.reason.defs))?;
            g.close().map_err(pq).map(|_| ())
        })();
        result?;
        self.groups.push(n);
        self.sample.clear();
        for k in &mut self.keys {
            k.clear();
        }
        self.stroke_exhausted.clear();
        self.mode.clear();
        self.peak_contact_force_n.clear();
        self.peak_robot_force_n.clear();
        self.stroke_left_min_m.clear();
        self.safe.clear();
        self.body_limits_pass.clear();
        self.status.clear();
        self.reason.clear();
        Ok(())
    }

    /// Writes the rows still buffered (a last, shorter row group) and the footer: after it the
    /// file is complete. Returns the rows written.
    pub fn finish(&mut self) -> io::Result<u64> {
        let grouped = self.write_group();
        let Some(mut w) = self.writer.take() else { return Ok(self.groups.iter().map(|&n| n as u64).sum()) };
        // The footer is written even when the last group could not be: the groups before it stand.
        let closed = w.finish().map_err(pq).and_then(|_| w.inner_mut().flush());
        grouped?;
        closed?;
        Ok(self.groups.iter().map(|&n| n as u64).sum())
    }
}

impl Drop for ParquetRows {
    /// An unfinished writer (a panic unwinding past it) still leaves a valid file.
    fn drop(&mut self) {
        if self.writer.is_some() {
            let _ = self.finish();
        }
    }
}

fn column<T: DataType>(g: &mut SerializedRowGroupWriter<'_, Box<dyn Write + Send>>, values: &[T::T], defs: Option<&[i16]>) -> io::Result<()> {
    let mut c = g.next_column().map_err(pq)?.ok_or_else(|| io::Error::other("more columns written than the schema has"))?;
    c.typed::<T>().write_batch(values, defs, None).map_err(pq)?;
    c.close().map_err(pq)
}
