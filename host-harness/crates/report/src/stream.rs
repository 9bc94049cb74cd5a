//! A run whose outputs stream: CSV rows leave as the solver makes them (through the simulation's
//! sample sink, so the integration takes exactly the steps it takes without outputs), the plot
//! keeps a bounded, peak-preserving decimation, a long run says what it will write and shows its
//! progress on a terminal, and Ctrl-C stops it with the rows written so far complete.

use crate::csv::{HistoryWriter, ROW_BYTES};
use crate::measured::Resampler;
use flinch_output::output::{self, Failure, EXIT_INTERRUPTED};
use crate::trace::Trace;
use flinch_model::scene::Scene;
use flinch_sim::{Run, Sample, Summary};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::cell::RefCell;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Once;
use std::time::{Duration, Instant};

/// Samples a plot keeps at most: below this a history is drawn whole.
pub const PLOT_SAMPLES: usize = 20_000;
/// Time buckets of a decimated plot; each keeps the extremes of every drawn quantity.
const BUCKETS: usize = 1_500;

/// The quantities whose extremes a bucket keeps.
const QUANTITIES: usize = 6;
fn quantity(s: &Sample, q: usize) -> f64 {
    match q {
        0 => s.v_r,
        1 => s.v_t,
        2 => s.v_p,
        3 => s.f_contact,
        4 => s.f_robot.abs(),
        _ => s.s,
    }
}

/// A bounded, peak-preserving subset of a history: every sample while there are few; past that,
/// per time bucket the first sample and the samples where each drawn quantity is lowest and
/// highest (min-max decimation: a peak is never thinned away).
#[derive(Debug, Clone)]
pub struct Decimator {
    t0: f64,
    width: f64,
    n: usize,
    whole: usize,
    all: Option<Vec<Sample>>,
    buckets: Vec<Option<Bucket>>,
}

/// One bucket: for every quantity the sample with its lowest and its highest value, and the
/// bucket's first sample.
type Bucket = ([Sample; QUANTITIES], [Sample; QUANTITIES], Sample);

impl Decimator {
    /// For `expected` samples over [0, duration]: whole up to [`PLOT_SAMPLES`], else [`BUCKETS`]
    /// buckets.
    pub fn new(duration: f64, expected: u64) -> Self {
        Self::with(duration, expected, PLOT_SAMPLES, BUCKETS)
    }

    /// Whole up to `whole` samples, else `buckets` buckets.
    pub fn with(duration: f64, expected: u64, whole: usize, buckets: usize) -> Self {
        let n = buckets.max(1);
        let width = duration.max(f64::MIN_POSITIVE) / n as f64;
        if expected as usize <= whole {
            return Self { t0: 0.0, width, n, whole, all: Some(Vec::with_capacity(expected as usize + 16)), buckets: Vec::new() };
        }
        Self { t0: 0.0, width, n, whole, all: None, buckets: vec![None; n] }
    }

    /// Takes one sample.
    pub fn push(&mut self, s: &Sample) {
        if let Some(all) = &mut self.all {
            if all.len() < 4 * self.whole.max(1) {
                all.push(*s);
                return;
            }
            // The estimate was low (output_interval = 0 records every step): decimate from here on.
            let kept = self.all.take().unwrap_or_default();
            self.buckets = vec![None; self.n];
            kept.iter().for_each(|k| self.bucket(k));
        }
        self.bucket(s);
    }

    fn bucket(&mut self, s: &Sample) {
        let i = (((s.t - self.t0) / self.width).max(0.0) as usize).min(self.n - 1);
        match &mut self.buckets[i] {
            None => self.buckets[i] = Some(([*s; QUANTITIES], [*s; QUANTITIES], *s)),
            Some((lo, hi, _)) => {
                for q in 0..QUANTITIES {
                    if quantity(s, q) < quantity(&lo[q], q) {
                        lo[q] = *s;
                    }
                    if quantity(s, q) > quantity(&hi[q], q) {
                        hi[q] = *s;
                    }
                }
            }
        }
    }

    /// The kept samples, in time order.
    pub fn finish(self) -> Vec<Sample> {
        let mut out = self.all.unwrap_or_default();
        for (lo, hi, first) in self.buckets.into_iter().flatten() {
            out.push(first);
            out.extend(lo);
            out.extend(hi);
        }
        out.sort_by(|a, b| a.t.total_cmp(&b.t));
        out.dedup_by(|a, b| a.t == b.t);
        out
    }
}

/// Decimates a whole history (see [`Decimator`]).
pub fn decimate(history: &[Sample], duration: f64) -> Vec<Sample> {
    decimate_to(history, duration, PLOT_SAMPLES, BUCKETS)
}

/// Decimates a whole history: kept whole up to `whole` samples, else into `buckets` buckets.
pub fn decimate_to(history: &[Sample], duration: f64, whole: usize, buckets: usize) -> Vec<Sample> {
    let mut d = Decimator::with(duration, history.len() as u64, whole, buckets);
    history.iter().for_each(|s| d.push(s));
    d.finish()
}

static INTERRUPTED: AtomicBool = AtomicBool::new(false);
static HANDLER: Once = Once::new();

fn catch_ctrl_c() {
    HANDLER.call_once(|| {
        // If a handler cannot be installed, Ctrl-C keeps its default (the process ends at once).
        let _ = ctrlc::set_handler(|| INTERRUPTED.store(true, Ordering::SeqCst));
    });
}

/// What a streamed run produced.
#[derive(Debug, Clone)]
pub struct Streamed {
    /// The summary.
    pub summary: Summary,
    /// The samples to plot (all of them, or a decimation).
    pub plotted: Vec<Sample>,
    /// CSV rows written.
    pub rows: u64,
    /// The run resampled onto a measured file's grid, if one was given.
    pub resampled: Option<Resampler>,
}

/// Rows a run of `scene` records: one per output interval, both ends included (exact:
/// `sim::recorded_rows`); an estimate of a step's end each when it is 0.
pub fn expected_rows(scene: &Scene) -> u64 {
    let dt = scene.solver.output_interval;
    if dt > 0.0 {
        return flinch_sim::recorded_rows(scene.duration_s, dt);
    }
    let n = scene.duration_s / scene.solver.max_step.max(1e-9) * 4.0;
    if n.is_finite() { n.ceil().min(1e18) as u64 + 1 } else { u64::MAX }
}

fn human_bytes(b: f64) -> String {
    match b {
        b if b >= 1e9 => format!("{:.1} GB", b / 1e9),
        b if b >= 1e6 => format!("{:.0} MB", b / 1e6),
        b => format!("{:.0} kB", b / 1e3),
    }
}

/// A history on its way out: CSV rows written as they come, a bounded decimation for a plot, a
/// measured file's resampling, a progress bar on a terminal after 0.8 s, and Ctrl-C ending the
/// process (exit 130) with the rows so far flushed. `flinch run` and `flinch hil` both write
/// through it.
pub struct Streamer {
    csv: Option<(HistoryWriter<Box<dyn Write>>, PathBuf)>,
    plot: Option<Decimator>,
    measured: Option<Resampler>,
    bar: ProgressBar,
    started: Instant,
    shown: bool,
    count: u64,
    duration: f64,
}

impl Streamer {
    /// Opens the outputs for a run of `scene` with columns from `trace`: says on standard error
    /// what a large CSV will receive, creates it, and installs the Ctrl-C handler.
    pub fn open(scene: &Scene, csv: Option<&Path>, plot: bool, measured: Option<Resampler>, trace: Trace) -> Result<Self, Failure> {
        let rows = expected_rows(scene);
        if let Some(path) = csv {
            let bytes = rows as f64 * ROW_BYTES as f64;
            if bytes > 50e6 {
                output::note(&format!("note: {} will receive about {rows} rows ({}): one per solver.output_interval = {} s over duration = {} s", output::shown(path), human_bytes(bytes), scene.solver.output_interval, scene.duration_s));
            }
        }
        catch_ctrl_c();
        let csv = match csv {
            Some(path) => {
                let out = output::create(path)?;
                Some((HistoryWriter::new(out, trace).map_err(|e| output::write_error(path, &e))?, path.to_path_buf()))
            }
            None => None,
        };
        let bar = ProgressBar::with_draw_target(Some(1000), ProgressDrawTarget::hidden());
        if let Ok(style) = ProgressStyle::with_template(&format!("{{elapsed_precise}} [{{bar:40}}] {{percent}} % of {} s simulated, eta {{eta}}", scene.duration_s)) {
            bar.set_style(style.progress_chars("=> "));
        }
        Ok(Self { csv, plot: plot.then(|| Decimator::new(scene.duration_s, rows)), measured, bar, started: Instant::now(), shown: false, count: 0, duration: scene.duration_s })
    }

    /// The CSV's column source (to update the firmware's signals as a `hil` run goes on).
    pub fn trace_mut(&mut self) -> Option<&mut Trace> {
        self.csv.as_mut().map(|(w, _)| w.trace_mut())
    }

    /// Ends the outputs: flushes the CSV; returns the samples to plot, the rows written and the
    /// resampling.
    pub fn close(mut self) -> Result<(Vec<Sample>, u64, Option<Resampler>), Failure> {
        self.bar.finish_and_clear();
        let mut written = 0;
        if let Some((mut w, path)) = self.csv.take() {
            w.flush().map_err(|e| output::write_error(&path, &e))?;
            written = w.rows;
        }
        Ok((self.plot.map(Decimator::finish).unwrap_or_default(), written, self.measured))
    }

    /// Takes one sample.
    pub fn take(&mut self, s: &Sample) {
        if let Some((w, path)) = &mut self.csv {
            if let Err(e) = w.row(s) {
                let f = output::write_error(path, &e);
                self.bar.finish_and_clear();
                if !f.message.is_empty() {
                    output::note(&format!("error: {f}"));
                }
                output::settle(output::keeps(f.code));
                std::process::exit(i32::from(f.code));
            }
        }
        if let Some(d) = &mut self.plot {
            d.push(s);
        }
        if let Some(m) = &mut self.measured {
            m.push(s);
        }
        self.count += 1;
        if self.count.is_multiple_of(256) {
            if !self.shown && self.started.elapsed() > Duration::from_millis(800) && std::io::stderr().is_terminal() {
                self.bar.set_draw_target(ProgressDrawTarget::stderr());
                self.shown = true;
            }
            self.bar.set_position((s.t / self.duration * 1000.0) as u64);
            if INTERRUPTED.load(Ordering::SeqCst) {
                self.bar.finish_and_clear();
                let mut written = String::new();
                if let Some((w, path)) = &mut self.csv {
                    let _ = w.flush();
                    written = format!("; {} is partial: it holds the {} rows up to it", output::shown(path), w.rows);
                }
                output::note(&format!("interrupted at t = {:.6} s of {} s{written}", s.t, self.duration));
                // The complete rows so far are kept: the temporary file is renamed into place.
                output::settle(true);
                std::process::exit(i32::from(EXIT_INTERRUPTED));
            }
        }
    }
}

/// Runs `scene`, streaming its history to `csv` (a path, or `-`), keeping a decimation for a plot
/// when `plot`, and resampling it for a comparison with `measured`. Prints to standard error what a
/// long run will write, and its progress on a terminal; Ctrl-C ends the process with exit 130 after
/// flushing the rows written.
pub fn run(scene: &Scene, csv: Option<&Path>, plot: bool, measured: Option<Resampler>) -> Result<Streamed, Failure> {
    let rows = expected_rows(scene);
    let long = scene.duration_s > 5.0 || rows > 1_000_000;
    let record = csv.is_some() || plot || measured.is_some() || (long && std::io::stderr().is_terminal());
    let mut r = Run::new(scene, false, record);
    if !record {
        r.finish().map_err(|e| Failure::runtime(e.to_string()))?;
        return Ok(Streamed { summary: r.summary(), plotted: Vec::new(), rows: 0, resampled: None });
    }
    let state = Rc::new(RefCell::new(Streamer::open(scene, csv, plot, measured, Trace::new(scene))?));
    let sink = Rc::clone(&state);
    r.sim.sink = Some(Box::new(move |s: &Sample| sink.borrow_mut().take(s)));
    let result = r.finish();
    r.sim.sink = None;
    let st = Rc::try_unwrap(state).map_err(|_| Failure::runtime("internal: the sample sink is still held"))?.into_inner();
    let (plotted, written, resampled) = st.close()?;
    result.map_err(|e| Failure::runtime(e.to_string()))?;
    Ok(Streamed { summary: r.summary(), plotted, rows: written, resampled })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(t: f64, f: f64) -> Sample {
        Sample { t, v_c: 0.0, v_r: 0.0, v_t: 0.0, v_p: 0.0, s: 0.0, f_contact: f, f_robot: 0.0, f_spring: 0.0, f_stops: 0.0, f_friction: 0.0 }
    }

    #[test]
    fn decimation_is_bounded_and_keeps_every_peak() {
        let n = 2_000_000u64;
        let mut d = Decimator::new(100.0, n);
        for i in 0..n {
            let t = i as f64 * 100.0 / n as f64;
            // A narrow spike every 10 s, 3 samples wide.
            let f = if i % 200_000 == 7 { 1000.0 + i as f64 * 1e-6 } else { (t * 3.0).sin() };
            d.push(&sample(t, f));
        }
        let kept = d.finish();
        assert!(kept.len() <= BUCKETS * (2 * QUANTITIES + 1), "{}", kept.len());
        let spikes = kept.iter().filter(|s| s.f_contact >= 1000.0).count();
        assert_eq!(spikes, 10, "every spike survives");
        assert!(kept.windows(2).all(|w| w[0].t < w[1].t));
    }

    #[test]
    fn a_short_history_is_kept_whole() {
        let h: Vec<Sample> = (0..1000).map(|i| sample(i as f64 * 1e-3, i as f64)).collect();
        assert_eq!(decimate(&h, 1.0).len(), 1000);
    }
}
