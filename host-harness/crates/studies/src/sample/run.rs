//! Running a plan: blocks of samples on the pool, their rows written in order to the CSV and the
//! Parquet file as they come, the tally, progress on a terminal, a clean stop on Ctrl-C.

use crate::sweep::Progress;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use std::io::{self, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use super::common::*;
use super::{outcome::*, tally::*, report::*};
use super::plan::Plan;
use super::parquet_file;

impl Plan {
    /// Runs the plan's range on `pool` (None: the global rayon pool, all cores), in blocks of
    /// [`BLOCK`], writing each block's rows to `csv` in index order; stops after the block in
    /// which `stop` is raised, keeping the samples before the first one that saw it (each sample
    /// checks `stop` before it starts): the CSV and the report cover exactly those, a prefix of
    /// the range in index order.
    pub fn run(&self, progress: Progress, csv: Option<&mut dyn Write>, stop: &AtomicBool, pool: Option<&rayon::ThreadPool>) -> io::Result<SampleReport> {
        self.run_to(progress, csv, None, stop, pool)
    }

    /// As [`Plan::run`], also handing every row to `parquet` (`--parquet`). The caller finishes
    /// the Parquet file ([`parquet_file::ParquetRows::finish`]) whatever this returns: on an error
    /// writing the CSV, the Parquet file then holds the rows written before it.
    pub fn run_to(&self, progress: Progress, csv: Option<&mut dyn Write>, mut parquet: Option<&mut parquet_file::ParquetRows>, stop: &AtomicBool, pool: Option<&rayon::ThreadPool>) -> io::Result<SampleReport> {
        let body = self.body();
        let mut w = csv.map(csv::Writer::from_writer);
        if let Some(w) = w.as_mut() {
            w.write_record(self.header()).map_err(crate::sweep::csv_io)?;
        }
        let report = self.run_rows(
            progress,
            &mut |r: &Row| {
                if let Some(w) = w.as_mut() {
                    w.write_record(r.record_with(body)).map_err(crate::sweep::csv_io)?;
                }
                match parquet.as_deref_mut() {
                    Some(p) => p.push(r),
                    None => Ok(()),
                }
            },
            stop,
            pool,
        )?;
        if let Some(w) = w.as_mut() {
            w.flush()?;
        }
        Ok(report)
    }

    /// As [`Plan::run`], handing every row to `sink` in index order instead of writing CSV (the
    /// Python package builds its columns so). `sink` runs on the calling thread, after each block;
    /// it may raise `stop`.
    pub fn run_rows(&self, progress: Progress, sink: &mut dyn FnMut(&Row) -> io::Result<()>, stop: &AtomicBool, pool: Option<&rayon::ThreadPool>) -> io::Result<SampleReport> {
        use std::io::IsTerminal;
        let (first, end) = self.range;
        let bar = if progress == Progress::Auto && io::stderr().is_terminal() {
            let b = ProgressBar::new(end - first);
            if let Ok(style) = ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {pos}/{len} samples, {per_sec}, eta {eta}") {
                b.set_style(style.progress_chars("=> "));
            }
            b
        } else {
            ProgressBar::hidden()
        };
        let mut tally = Tally::default();
        let mut at = first;
        while at < end && !stop.load(Ordering::SeqCst) {
            let len = (end - at).min(BLOCK as u64) as usize;
            // A sample that starts after `stop` is raised is not run (None): the block is kept up
            // to the first such sample, so a Ctrl-C takes effect within one sample per thread.
            let block = || (0..len).into_par_iter().map(|j| (!stop.load(Ordering::SeqCst)).then(|| self.run_one(at + j as u64))).collect::<Vec<Option<Row>>>();
            let rows = match pool {
                Some(p) => p.install(block),
                None => block(),
            };
            let done = rows.iter().take_while(|r| r.is_some()).count();
            for r in rows.iter().flatten().take(done) {
                sink(r)?;
                tally.add(r);
            }
            at += done as u64;
            bar.inc(done as u64);
            if done < len {
                break;
            }
        }
        bar.finish_and_clear();
        Ok(self.report(tally, (first, at)))
    }
}
