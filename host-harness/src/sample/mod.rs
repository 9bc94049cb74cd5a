//! `flinch sample`: Monte Carlo over a scene's keys, and the probability of each failure with a
//! 95 % confidence interval (docs/sample.md).
//!
//! Each `--vary KEY=DIST` draws a scene key (a dotted path as in `flinch sweep`) from a
//! distribution; every sample's scene is the file with those keys set, re-validated by the same
//! validator as `flinch run` ([`Template::with`]). A sample the validator refuses (a normal draw
//! below a key's range, or a combination the scene contract forbids) is counted and reported by the
//! keys refused, with the first reason; it is never dropped silently or clamped. `--truncate` draws
//! each key within its accepted range instead (an exact truncated distribution, by the inverse
//! distribution function), and the report states how much probability that cut.
//!
//! Determinism: sample `i`'s draws depend only on `(seed, i, position of the key)` (a counter-based
//! generator, [`uniform01`]), so the result is the same on any number of threads, and a chunk
//! `K/M` (a range of sample indices) can run anywhere: the chunks' reports merge ([`merge`]) into the
//! report of the whole run, field for field. Samples run on the rayon pool in blocks of [`BLOCK`],
//! written in index order: memory does not grow with N.

pub mod cli;
mod dist;
pub mod parquet_file;
mod report;
pub mod stats;

pub use dist::*;
pub use report::*;

use crate::report::schema::SUFFIXES;
use crate::scene::{Decoupler, Scene, Sensor, TargetKind, Ty};
use crate::sim::{self, Summary};
use crate::sweep::{Progress, SweepError, Template};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::io::{self, Write};
use std::sync::atomic::{AtomicBool, Ordering};

/// Samples run together on the pool, then written in order; what memory holds at once.
pub const BLOCK: usize = 2048;

/// The version of the `--json` document (docs/conventions.md).
pub const SCHEMA_VERSION: u32 = 1;

/// Two-sided confidence of every interval.
pub const CONFIDENCE: f64 = 0.95;

fn err<T>(msg: impl Into<String>) -> Result<T, SweepError> {
    Err(SweepError(msg.into()))
}

// ---------------------------------------------------------------------------------------------
// Keys: unit and accepted range, from the scene's key tables
// ---------------------------------------------------------------------------------------------

/// What the scene's key tables say about a key: its unit and accepted range.
#[derive(Debug, Clone, PartialEq)]
pub struct KeyInfo {
    /// Unit as the contract writes it ("m/s", "N/m^1.5", "" for a pure number).
    pub unit: String,
    /// Lower end of the accepted range, if any.
    pub lo: Option<f64>,
    /// Upper end, if any.
    pub hi: Option<f64>,
    /// The range as the validator's messages say it.
    pub range: String,
    /// An integer key (a draw must be whole to be accepted).
    pub integer: bool,
}

/// The `kind` that selects a table's keys in this scene.
fn kind_of(base: &Scene, table: &str) -> Option<&'static str> {
    match table {
        "decoupler" | "decoupler.friction" => Some(match base.decoupler {
            Decoupler::Rigid => "rigid",
            Decoupler::Linear(_) => "linear",
            Decoupler::Bistable(_) => "bistable",
            Decoupler::Hydraulic(_) => "hydraulic",
        }),
        "target" => Some(match base.target.kind {
            TargetKind::Obstacle => "obstacle",
            TargetKind::Object { .. } => "object",
            TargetKind::BodyRegion(_) => "body_region",
        }),
        "sensor" => base.sensor.map(|s| match s {
            Sensor::Travel { .. } => "travel",
            Sensor::Force { .. } => "force",
        }),
        _ => None,
    }
}

/// The unit and range of a dotted key in this scene (None for a key the tables do not list, such
/// as an element of `robot.joints`, whose unit is the joint's).
pub fn key_info(base: &Scene, key: &str) -> Option<KeyInfo> {
    let (table, leaf) = key.rsplit_once('.').unwrap_or(("", key));
    let kind = kind_of(base, table);
    let k = crate::scene::key_tables()
        .iter()
        .filter(|t| t.path == table && (t.when.is_empty() || kind.is_some_and(|k| t.when == format!("kind = \"{k}\""))))
        .flat_map(|t| t.keys.iter())
        .find(|k| k.name == leaf)?;
    match k.ty {
        Ty::Number(span) => Some(KeyInfo { unit: span.unit.to_string(), lo: span.lo.value(), hi: span.hi.value(), range: span.range(), integer: false }),
        Ty::Integer { lo, hi, .. } => Some(KeyInfo { unit: String::new(), lo: Some(f64::from(lo)), hi: Some(f64::from(hi)), range: format!("whole numbers {lo} to {hi}"), integer: true }),
        _ => None,
    }
}

/// The column name of a key: the key and its unit's suffix (docs/conventions.md), e.g.
/// `motion.dead_time_s`, `decoupler.spring_rate_n_per_m`; a unit the convention has no suffix for
/// is spelled out (`target.stiffness_n_per_m1_5` for N/m^1.5); a pure number has none.
pub fn column(key: &str, unit: &str) -> String {
    if unit.is_empty() || unit.starts_with("of ") {
        return key.to_string();
    }
    if let Some((s, _)) = SUFFIXES.iter().find(|(_, u)| *u == unit) {
        return format!("{key}{s}");
    }
    let s = unit.to_ascii_lowercase().replace("n s", "ns").replace('/', "_per_").replace('^', "").replace(['.', ' '], "_");
    format!("{key}_{s}")
}

// ---------------------------------------------------------------------------------------------
// The plan: keys, distributions, truncation, the sample range
// ---------------------------------------------------------------------------------------------

/// A varied key, checked against the scene.
#[derive(Debug, Clone)]
pub struct Varied {
    /// As parsed.
    pub spec: VarySpec,
    /// CSV column.
    pub column: String,
    /// Unit and range from the key tables, if listed.
    pub info: Option<KeyInfo>,
    /// The interval draws are confined to (explicit bounds, and with `--truncate` the accepted
    /// range), if any.
    pub within: Option<(f64, f64)>,
    /// F(within.hi) - F(within.lo): the probability the truncation keeps (1 without one).
    pub kept: f64,
    /// F at the lower end of `within` (0 without one); in the upper tail (`upper`), the survival
    /// function 1 - F there instead.
    f_lo: f64,
    /// `within` lies in the upper tail (F at its lower end above 1/2): draws invert the survival
    /// function, whose small values keep their precision where F's round to 1.
    upper: bool,
    /// Without truncation: the probability of a draw outside the key's accepted range (those
    /// samples will be refused and counted).
    pub outside: f64,
}

impl Varied {
    /// The value of this key for uniform number u.
    pub fn value(&self, u: f64) -> f64 {
        if self.upper {
            self.spec.dist.isf(self.f_lo - u * self.kept)
        } else {
            self.spec.dist.quantile(self.f_lo + u * self.kept)
        }
    }
}

/// A dotted key as the scene reads it: an array index is a number, so `stopping.distance.02`,
/// `.+2` and `.2` are one key (each segment that parses as an index is written without sign or
/// leading zeros).
pub fn canonical_key(key: &str) -> String {
    key.split('.').map(|s| s.trim().parse::<usize>().map_or_else(|_| s.trim().to_string(), |i| i.to_string())).collect::<Vec<_>>().join(".")
}

/// A sample study: the scene, the keys, the seed, N and the chunk this process runs.
pub struct Plan {
    /// The scene's template.
    pub template: Template,
    /// FNV-1a 64 of the scene's text and of every file it refers to (its URDF): merging refuses
    /// chunks of different scenes.
    pub scene_hash: String,
    /// The varied keys, in `--vary` order (also the order of the draws).
    pub vary: Vec<Varied>,
    /// Seed.
    pub seed: u64,
    /// N, the whole study's samples.
    pub samples: u64,
    /// The sample indices this process runs, [first, end).
    pub range: (u64, u64),
    /// `--truncate`.
    pub truncate: bool,
}

/// FNV-1a 64 of a text, as 16 hex digits.
pub fn fnv1a64(text: &str) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in text.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// The study's scene hash: FNV-1a 64 of the scene's text alone when it refers to no file (as
/// before), else of the text followed, for each file it refers to, by a NUL, the file's text.
pub fn scene_hash(text: &str, file: &str) -> String {
    let mut all = text.to_string();
    for (_, t) in crate::scene::referenced_files(text, file) {
        all.push('\0');
        all.push_str(&t);
    }
    fnv1a64(&all)
}

/// Parses `K/M`: chunk K (1-based) of M.
pub fn parse_chunk(s: &str) -> Result<(u64, u64), SweepError> {
    let bad = || SweepError(format!("--chunk {s:?}: expected K/M with 1 <= K <= M, e.g. 1/4"));
    let (k, m) = s.split_once('/').ok_or_else(bad)?;
    let (k, m) = (k.trim().parse::<u64>().map_err(|_| bad())?, m.trim().parse::<u64>().map_err(|_| bad())?);
    if k == 0 || m == 0 || k > m {
        return Err(bad());
    }
    Ok((k, m))
}

/// The sample indices of chunk K of M over N samples: [floor(N (K-1) / M), floor(N K / M)).
pub fn chunk_range(n: u64, k: u64, m: u64) -> (u64, u64) {
    let at = |j: u64| (u128::from(n) * u128::from(j) / u128::from(m)) as u64;
    (at(k - 1), at(k))
}

impl Plan {
    /// Checks everything before anything runs: the keys (as `flinch sweep` does), the
    /// distributions against the keys' ranges, the chunk.
    pub fn new(template: Template, scene_text: &str, specs: &[String], seed: u64, samples: u64, chunk: Option<(u64, u64)>, truncate: bool) -> Result<Self, SweepError> {
        if specs.is_empty() {
            return err(format!("nothing to vary: give --vary KEY=DIST at least once; DIST is one of {FORMS}"));
        }
        if samples == 0 {
            return err("--samples must be at least 1");
        }
        let parsed: Vec<VarySpec> = specs.iter().map(|s| VarySpec::parse(s)).collect::<Result<_, _>>()?;
        for (i, a) in parsed.iter().enumerate() {
            if let Some(b) = parsed[..i].iter().find(|b| canonical_key(&b.key) == canonical_key(&a.key)) {
                let same = if b.key == a.key { String::new() } else { format!(" (as {} and {}, the same key)", b.key, a.key) };
                return err(format!("--vary {} is given twice{same}: each key is drawn once", canonical_key(&a.key)));
            }
        }
        let mut vary = Vec::new();
        for spec in parsed {
            let info = key_info(&template.base, &spec.key);
            if let Some(i) = info.as_ref().filter(|i| i.integer) {
                return err(format!(
                    "--vary {}: {} takes {}, and every distribution of flinch sample is continuous (its draws are never whole): vary it with flinch sweep --vary {}=START:STOP:N (whole values), or run one study per value of it",
                    spec.spec(),
                    spec.key,
                    i.range,
                    spec.key
                ));
            }
            let mut within = spec.bounds;
            if truncate {
                if let Some(i) = &info {
                    let lo = i.lo.unwrap_or(f64::NEG_INFINITY);
                    let hi = i.hi.unwrap_or(f64::INFINITY);
                    within = Some(match within {
                        Some((a, b)) => (a.max(lo), b.min(hi)),
                        None => (lo, hi),
                    });
                }
            }
            let d = spec.dist;
            let (f_lo, kept, upper) = match within {
                Some((a, b)) => {
                    let (fa, fb) = (d.cdf(a), d.cdf(b));
                    if fa > 0.5 {
                        let (sa, sb) = (d.sf(a), d.sf(b));
                        (sa, sa - sb, true)
                    } else {
                        (fa, fb - fa, false)
                    }
                }
                None => (0.0, 1.0, false),
            };
            if let Some((a, b)) = within {
                if a >= b || kept.is_nan() || kept <= 1e-12 {
                    return err(format!(
                        "--vary {}: the distribution has no probability in [{}, {}] (less than 1e-12 of it lies there: no draw can be made){}",
                        spec.spec(),
                        num(a),
                        num(b),
                        info.as_ref().filter(|_| truncate).map_or(String::new(), |i| format!(" (with --truncate, the accepted range of {} is {})", spec.key, i.range))
                    ));
                }
            }
            let outside = match (&info, within) {
                (Some(i), None) => d.cdf(i.lo.unwrap_or(f64::NEG_INFINITY)) + d.sf(i.hi.unwrap_or(f64::INFINITY)),
                _ => 0.0,
            };
            if !kept.is_finite() || !outside.is_finite() {
                return err(format!("--vary {}: the distribution's probabilities are not finite numbers (kept {kept}, outside the accepted range {outside}); give finite, narrower parameters", spec.spec()));
            }
            if outside >= 1.0 - 1e-12 {
                return err(format!(
                    "--vary {}: every draw lies outside the accepted range of {} ({}): every sample would be refused",
                    spec.spec(),
                    spec.key,
                    info.as_ref().map_or(String::new(), |i| i.range.clone())
                ));
            }
            let unit = info.as_ref().map_or("", |i| i.unit.as_str());
            let column = column(&spec.key, unit);
            let v = Varied { spec, column, info, within, kept, f_lo, upper, outside };
            // The key must be settable, as for a sweep; probe it at the median draw.
            template.check_key(&v.spec.key, v.value(0.5))?;
            vary.push(v);
        }
        let range = match chunk {
            Some((k, m)) => chunk_range(samples, k, m),
            None => (0, samples),
        };
        Ok(Self { scene_hash: scene_hash(scene_text, template.file()), template, vary, seed, samples, range, truncate })
    }

    /// The values of sample `index`, in `--vary` order.
    pub fn draw(&self, index: u64) -> Vec<f64> {
        self.vary.iter().enumerate().map(|(j, v)| v.value(uniform01(self.seed, index, j as u64))).collect()
    }

    /// Draws, validates and runs sample `index`.
    pub fn run_one(&self, index: u64) -> Row {
        let values = self.draw(index);
        let sets: Vec<(&str, f64)> = self.vary.iter().zip(&values).map(|(v, &x)| (v.spec.key.as_str(), x)).collect();
        let outcome = match self.template.with_refused_keys(&sets) {
            Err((e, keys)) => Outcome::Refused { keys, reason: e.0 },
            Ok(sc) => match sim::run(&sc, false) {
                Ok((s, _)) => Outcome::Ran(Brief::of(&s)),
                Err(e) => Outcome::Failed(e.to_string()),
            },
        };
        Row { index, values, outcome }
    }

    /// The CSV header.
    pub fn header(&self) -> Vec<String> {
        let mut h = vec!["sample".to_string()];
        h.extend(self.vary.iter().map(|v| v.column.clone()));
        h.extend(["stroke_exhausted", "mode", "peak_contact_force_n", "peak_robot_force_n", "stroke_left_min_m", "safe"].map(String::from));
        if self.body() {
            h.push("body_limits_pass".into());
        }
        h.extend(["status", "reason"].map(String::from));
        h
    }

    /// The scene's target is a human body region: the CSV has `body_limits_pass` and the report
    /// estimates `body_limit_exceeded`.
    pub fn body(&self) -> bool {
        matches!(self.template.base.target.kind, TargetKind::BodyRegion(_))
    }

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

    /// Which of [`FAILURES`] apply to this study's scene (a body-region limit only to a body region).
    pub fn applies(&self) -> Vec<bool> {
        FAILURES.iter().map(|k| (k.applies)(&self.template.base)).collect()
    }

    fn report(&self, t: Tally, done: (u64, u64)) -> SampleReport {
        let vary = self
            .vary
            .iter()
            .map(|v| VaryReport {
                key: v.spec.key.clone(),
                column: v.column.clone(),
                dist: v.spec.dist.spec(),
                unit: v.info.as_ref().map(|i| i.unit.clone()),
                accepted_range: v.info.as_ref().map(|i| i.range.clone()),
                within_lo: v.within.map(|w| w.0).filter(|x| x.is_finite()),
                within_hi: v.within.map(|w| w.1).filter(|x| x.is_finite()),
                kept_probability: v.kept,
                outside_probability: v.outside,
            })
            .collect();
        let mut r = SampleReport {
            schema_version: SCHEMA_VERSION,
            scene: self.template.base.name.clone(),
            scene_file: self.template.file().to_string(),
            scene_fnv1a64: self.scene_hash.clone(),
            flinch_version: env!("CARGO_PKG_VERSION").to_string(),
            seed: self.seed,
            samples: self.samples,
            truncate: self.truncate,
            vary,
            ranges: if done.1 > done.0 { vec![[done.0, done.1]] } else { Vec::new() },
            complete: false,
            drawn: t.ran + t.refused + t.solver_failed,
            ran: t.ran,
            refused: t.refused,
            solver_failed: t.solver_failed,
            modes: t.modes,
            refusals: t.refusals,
            solver_failures: t.solver_failures,
            inconclusive: t.inconclusive.as_ref().map_or(0, |x| x.count),
            inconclusive_first: t.inconclusive,
            warnings: t.warnings,
            warnings_not_listed: t.warnings_not_listed,
            confidence: CONFIDENCE,
            estimates: Vec::new(),
        };
        r.finish(&t.failures, &t.unknown, &self.applies());
        r
    }
}

// ---------------------------------------------------------------------------------------------
// Rows and counts
// ---------------------------------------------------------------------------------------------

/// A failure whose probability is estimated: its name, what it is, and the test on a summary.
pub struct FailureKind {
    /// As in the JSON (`estimates[].failure`).
    pub name: &'static str,
    /// For people.
    pub what: &'static str,
    /// True when the run has this failure.
    pub test: fn(&Summary) -> bool,
    /// True when the failure can happen in this scene (estimated only then).
    pub applies: fn(&Scene) -> bool,
    /// True when a run that ended before the robot stopped (not concluded) is known to have it:
    /// only `not_safe` (such a run is not safe). For the others a failure already seen in such a
    /// run counts (they only grow: a stroke exhausted, a mode 3, a limit exceeded stay so after
    /// the end); one not seen is unknown: the run is left out of that failure's `runs` and counted
    /// in its `high_if_unrun_failed`.
    pub known_if_not_concluded: bool,
}

fn always(_: &Scene) -> bool {
    true
}

/// The failures estimated, each from the run's summary. The body-region limit is estimated only
/// for a scene whose target is a body region (elsewhere it cannot happen, and "0 of N" would read
/// as evidence).
pub const FAILURES: &[FailureKind] = &[
    FailureKind { name: "stroke_exhausted", what: "stroke exhausted (the tool in the back end-stop while touching the target; docs/verdicts.md)", test: |s| s.stroke_exhausted, applies: always, known_if_not_concluded: false },
    FailureKind { name: "mode_3", what: "working mode 3 (the tool hits the back end-stop while the robot still brakes; Fig. 46)", test: |s| s.mode == Some(3), applies: always, known_if_not_concluded: false },
    FailureKind { name: "not_safe", what: "not safe by the one definition (docs/verdicts.md: the summary's `failures` is not empty)", test: |s| !s.safe, applies: always, known_if_not_concluded: true },
    FailureKind {
        name: "body_limit_exceeded",
        what: "a body-region limit exceeded (ISO/TS 15066 Table A.2 force or pressure, or a transient contact the TS does not permit; the summary's body_limits_pass is false)",
        test: |s| s.body_limits_pass == Some(false),
        applies: |sc| matches!(sc.target.kind, TargetKind::BodyRegion(_)),
        known_if_not_concluded: false,
    },
];

/// The fields of a run's summary a sample keeps.
#[derive(Debug, Clone, PartialEq)]
pub struct Brief {
    /// `stroke_exhausted`.
    pub stroke_exhausted: bool,
    /// Working mode.
    pub mode: Option<u8>,
    /// N.
    pub peak_contact_force_n: f64,
    /// N.
    pub peak_robot_force_n: f64,
    /// m.
    pub stroke_left_min_m: Option<f64>,
    /// The one definition.
    pub safe: bool,
    /// ISO/TS 15066 limits kept (a body-region target only).
    pub body_limits_pass: Option<bool>,
    /// Per [`FAILURES`].
    pub failed: Vec<bool>,
    /// The run ended before the robot stopped (`Summary::concluded` false): the summary's
    /// "not concluded" failure text. Such a sample is `inconclusive`: what happened after the end
    /// is not simulated.
    pub not_concluded: Option<String>,
    /// The summary's warnings (things the user should know about the run).
    pub warnings: Vec<String>,
}

impl Brief {
    fn of(s: &Summary) -> Self {
        Self {
            stroke_exhausted: s.stroke_exhausted,
            mode: s.mode,
            peak_contact_force_n: s.peak_contact_force,
            peak_robot_force_n: s.peak_robot_force,
            stroke_left_min_m: s.stroke_left_min_m,
            safe: s.safe,
            body_limits_pass: s.body_limits_pass,
            failed: FAILURES.iter().map(|f| (f.test)(s)).collect(),
            not_concluded: (!s.concluded).then(|| s.failures.iter().find(|f| f.starts_with("not concluded")).cloned().unwrap_or_else(|| "not concluded: the run ended before the robot stopped: lengthen duration".into())),
            warnings: s.warnings.clone(),
        }
    }
}

/// What became of a sample.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Ran.
    Ran(Brief),
    /// The validator refused the drawn scene: the keys its issues name, and its message.
    Refused {
        /// Keys.
        keys: Vec<String>,
        /// Message.
        reason: String,
    },
    /// The solver gave up.
    Failed(String),
}

/// One sample: its index, drawn values and outcome.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// Sample index.
    pub index: u64,
    /// Values in `--vary` order.
    pub values: Vec<f64>,
    /// What happened.
    pub outcome: Outcome,
}

fn bit(b: bool) -> String {
    if b { "1" } else { "0" }.to_string()
}

impl Row {
    /// The CSV record (booleans 0/1, empty cells where a sample did not run), without a
    /// `body_limits_pass` column.
    pub fn record(&self) -> Vec<String> {
        self.record_with(false)
    }

    /// The CSV record, with the `body_limits_pass` column when `body` (a body-region scene).
    pub fn record_with(&self, body: bool) -> Vec<String> {
        let blanks = if body { 7 } else { 6 };
        let mut r = vec![self.index.to_string()];
        r.extend(self.values.iter().map(f64::to_string));
        match &self.outcome {
            Outcome::Ran(b) => {
                // Not concluded: a failure seen before the end is known (stroke exhausted 1,
                // mode 3, body limits 0); otherwise the cell is empty (unknown). The peaks and
                // the stroke left are up to the end.
                let known = b.not_concluded.is_none();
                r.extend([
                    if known || b.stroke_exhausted { bit(b.stroke_exhausted) } else { String::new() },
                    b.mode.filter(|&m| known || m == 3).map_or(String::new(), |m| m.to_string()),
                    b.peak_contact_force_n.to_string(),
                    b.peak_robot_force_n.to_string(),
                    b.stroke_left_min_m.map_or(String::new(), |x| x.to_string()),
                    bit(b.safe),
                ]);
                if body {
                    r.push(b.body_limits_pass.filter(|&p| known || !p).map_or(String::new(), bit));
                }
                match &b.not_concluded {
                    None => r.extend(["ok".into(), String::new()]),
                    Some(why) => r.extend(["inconclusive".into(), why.clone()]),
                }
            }
            Outcome::Refused { reason, .. } => {
                r.extend((0..blanks).map(|_| String::new()));
                r.push("refused".into());
                r.push(reason.clone());
            }
            Outcome::Failed(why) => {
                r.extend((0..blanks).map(|_| String::new()));
                r.push("failed".into());
                r.push(why.clone());
            }
        }
        r
    }
}

/// Refusals of the same keys: how many, and the first (lowest index) with its reason.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct RefusalGroup {
    /// The keys the validator's issues name.
    pub keys: Vec<String>,
    /// Samples refused so.
    pub count: u64,
    /// The first such sample's index.
    pub first_sample: u64,
    /// Its message.
    pub first_reason: String,
}

/// Samples the solver gave up on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct SolverFailures {
    /// How many.
    pub count: u64,
    /// The first one's index.
    pub first_sample: u64,
    /// Its message.
    pub first_reason: String,
}

/// Runs by working mode.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Modes {
    /// Mode 1.
    pub mode_1: u64,
    /// Mode 2.
    pub mode_2: u64,
    /// Mode 3.
    pub mode_3: u64,
    /// No mode (no back end-stop).
    pub no_mode: u64,
}

/// Samples that ran but ended before the robot stopped (`inconclusive` rows).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Inconclusive {
    /// How many.
    pub count: u64,
    /// The first one's index.
    pub first_sample: u64,
    /// Its "not concluded" failure text.
    pub first_reason: String,
}

/// A warning of the runs' summaries (docs/verdicts.md), grouped by its text with the numbers
/// masked (`t_stop = # s is after ...`): how many runs gave it, the first one and its text.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct WarningGroup {
    /// The warning with every number written `#`: what groups it.
    pub kind: String,
    /// The first such run's warning, as its summary says it.
    pub text: String,
    /// Runs that gave it.
    pub count: u64,
    /// The first such sample's index.
    pub first_sample: u64,
}

/// A warning's text with each number written `#` (`t_stop = 0.71 s` -> `t_stop = # s`).
pub fn warning_kind(text: &str) -> String {
    let mut out = String::new();
    let mut it = text.chars().peekable();
    while let Some(c) = it.next() {
        if c.is_ascii_digit() {
            let mut last = c;
            while let Some(&d) = it.peek() {
                if d.is_ascii_digit() || d == '.' || d == 'e' || d == '-' && last == 'e' {
                    last = d;
                    it.next();
                } else {
                    break;
                }
            }
            out.push('#');
        } else {
            out.push(c);
        }
    }
    out
}

/// At most this many distinct warning kinds are kept (first samples first); the report says how
/// many runs gave a text beyond them (`warnings_not_listed`).
pub const MAX_WARNINGS: usize = 32;

#[derive(Debug, Default)]
struct Tally {
    ran: u64,
    inconclusive: Option<Inconclusive>,
    warnings: Vec<WarningGroup>,
    warnings_not_listed: u64,
    refused: u64,
    solver_failed: u64,
    failures: Vec<u64>,
    /// Per failure, the inconclusive runs in which it was not seen (unknown).
    unknown: Vec<u64>,
    modes: Modes,
    refusals: Vec<RefusalGroup>,
    solver_failures: Option<SolverFailures>,
}

impl Tally {
    fn add(&mut self, r: &Row) {
        if self.failures.is_empty() {
            self.failures = vec![0; FAILURES.len()];
            self.unknown = vec![0; FAILURES.len()];
        }
        match &r.outcome {
            Outcome::Ran(b) => {
                self.ran += 1;
                for w in &b.warnings {
                    self.warnings_not_listed += add_warning(&mut self.warnings, WarningGroup { kind: warning_kind(w), text: w.clone(), count: 1, first_sample: r.index });
                }
                if let Some(why) = &b.not_concluded {
                    add_inconclusive(&mut self.inconclusive, Inconclusive { count: 1, first_sample: r.index, first_reason: why.clone() });
                    // A failure seen before the end is a failure; one not seen is unknown.
                    for (((n, u), &f), k) in self.failures.iter_mut().zip(self.unknown.iter_mut()).zip(&b.failed).zip(FAILURES) {
                        if f {
                            *n += 1;
                        } else if !k.known_if_not_concluded {
                            *u += 1;
                        }
                    }
                    return;
                }
                for (n, &f) in self.failures.iter_mut().zip(&b.failed) {
                    *n += u64::from(f);
                }
                match b.mode {
                    Some(1) => self.modes.mode_1 += 1,
                    Some(2) => self.modes.mode_2 += 1,
                    Some(3) => self.modes.mode_3 += 1,
                    _ => self.modes.no_mode += 1,
                }
            }
            Outcome::Refused { keys, reason } => {
                self.refused += 1;
                add_refusal(&mut self.refusals, RefusalGroup { keys: keys.clone(), count: 1, first_sample: r.index, first_reason: reason.clone() });
            }
            Outcome::Failed(why) => {
                self.solver_failed += 1;
                add_failure(&mut self.solver_failures, SolverFailures { count: 1, first_sample: r.index, first_reason: why.clone() });
            }
        }
    }
}

fn add_refusal(groups: &mut Vec<RefusalGroup>, g: RefusalGroup) {
    match groups.iter_mut().find(|x| x.keys == g.keys) {
        Some(x) => {
            x.count += g.count;
            if g.first_sample < x.first_sample {
                x.first_sample = g.first_sample;
                x.first_reason = g.first_reason;
            }
        }
        None => groups.push(g),
    }
    groups.sort_by_key(|x| x.first_sample);
}

fn add_inconclusive(f: &mut Option<Inconclusive>, g: Inconclusive) {
    match f {
        Some(x) => {
            x.count += g.count;
            if g.first_sample < x.first_sample {
                x.first_sample = g.first_sample;
                x.first_reason = g.first_reason;
            }
        }
        None => *f = Some(g),
    }
}

/// Adds a warning group; returns the runs it could not list (a new text beyond [`MAX_WARNINGS`]).
fn add_warning(groups: &mut Vec<WarningGroup>, g: WarningGroup) -> u64 {
    let full = groups.len() >= MAX_WARNINGS;
    let not_listed = match groups.iter_mut().find(|x| x.kind == g.kind) {
        Some(x) => {
            x.count += g.count;
            if g.first_sample < x.first_sample {
                x.first_sample = g.first_sample;
                x.text = g.text;
            }
            0
        }
        None if !full => {
            groups.push(g);
            0
        }
        None => g.count,
    };
    groups.sort_by_key(|x| x.first_sample);
    not_listed
}

fn add_failure(f: &mut Option<SolverFailures>, g: SolverFailures) {
    match f {
        Some(x) => {
            x.count += g.count;
            if g.first_sample < x.first_sample {
                x.first_sample = g.first_sample;
                x.first_reason = g.first_reason;
            }
        }
        None => *f = Some(g),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_numbers_are_in_the_open_interval_and_differ() {
        let a: Vec<f64> = (0..1000).map(|i| uniform01(1, i, 0)).collect();
        assert!(a.iter().all(|&u| u > 0.0 && u < 1.0));
        let mean = a.iter().sum::<f64>() / a.len() as f64;
        assert!((mean - 0.5).abs() < 0.03, "{mean}");
        assert_ne!(uniform01(1, 5, 0), uniform01(1, 5, 1));
        assert_ne!(uniform01(1, 5, 0), uniform01(2, 5, 0));
    }

    #[test]
    fn quantiles_invert_cdfs() {
        for d in [Dist::Normal { mean: 2.0, sd: 0.5 }, Dist::LogNormal { mu: -1.0, sigma: 0.3 }, Dist::Uniform { lo: 1.0, hi: 3.0 }, Dist::Triangular { lo: 0.0, mode: 1.0, hi: 4.0 }] {
            for u in [0.01, 0.2, 0.5, 0.77, 0.99] {
                let x = d.quantile(u);
                assert!((d.cdf(x) - u).abs() < 1e-12, "{d:?} at {u}: {}", d.cdf(x));
            }
        }
    }

    #[test]
    fn specs_parse_and_bad_ones_say_what_is_allowed() {
        let v = VarySpec::parse("motion.dead_time=normal:0.016:0.002:0.01:0.03").unwrap();
        assert_eq!(v.bounds, Some((0.01, 0.03)));
        assert_eq!(v.spec(), "motion.dead_time=normal:0.016:0.002:0.01:0.03");
        for (bad, says) in [
            ("motion.speed", "expected KEY=DIST"),
            ("motion.speed=gauss:1:2", "unknown distribution"),
            ("motion.speed=normal:1", "normal:MEAN:SD"),
            ("motion.speed=normal:1:0", "SD must be > 0"),
            ("motion.speed=uniform:2:1", "LO must be below HI"),
            ("motion.speed=triangular:0:5:4", "LO <= MODE <= HI"),
            ("motion.speed=uniform:0:x", "not a finite number"),
            ("motion.speed=lognormal:0:1:2:1", "truncation LO must be below HI"),
        ] {
            let e = VarySpec::parse(bad).unwrap_err().0;
            assert!(e.contains(says), "{bad}: {e}");
        }
    }

    #[test]
    fn columns_carry_units() {
        assert_eq!(column("motion.dead_time", "s"), "motion.dead_time_s");
        assert_eq!(column("decoupler.spring_rate", "N/m"), "decoupler.spring_rate_n_per_m");
        assert_eq!(column("target.stiffness", "N/m^1.5"), "target.stiffness_n_per_m1_5");
        assert_eq!(column("target.chi", "N s/m^2.5"), "target.chi_ns_per_m2_5");
        assert_eq!(column("decoupler.springs", ""), "decoupler.springs");
    }

    #[test]
    fn chunks_tile_the_range() {
        let n = 1001;
        let mut at = 0;
        for k in 1..=7 {
            let (a, b) = chunk_range(n, k, 7);
            assert_eq!(a, at);
            at = b;
        }
        assert_eq!(at, n);
        assert!(parse_chunk("0/3").is_err() && parse_chunk("4/3").is_err() && parse_chunk("x").is_err());
        assert_eq!(parse_chunk("2/3").unwrap(), (2, 3));
    }
    /// A report read back (`--merge`) has the numbers written, to the last bit: a far tail's
    /// probability (the outside probability of a normal draw 25 standard deviations from a bound)
    /// once came back one unit in the last place off, and the merged report differed from the
    /// whole run's.
    #[test]
    fn reports_read_back_have_the_numbers_written() {
        for x in [3.9262455345639715e-138_f64, 0.1 + 0.2, 1.0 / 3.0, 5e-324, 1.7976931348623157e308, 2.2250738585072014e-308] {
            let text = serde_json::to_string(&x).unwrap();
            let back: f64 = serde_json::from_str(&text).unwrap();
            assert_eq!(back.to_bits(), x.to_bits(), "{text}");
        }
    }

    /// docs/schema/sample.json is generated: `FLINCH_BLESS=1 cargo test -p flinch-harness --lib
    /// sample::tests::schema` rewrites it.
    #[test]
    fn schema_in_docs_is_current_and_every_number_has_a_unit() {
        let (text, missing) = schema();
        assert!(missing.is_empty(), "numeric fields of the sample report without a unit (add them to UNITS): {missing:?}");
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/schema/sample.json");
        if std::env::var_os("FLINCH_BLESS").is_some() {
            std::fs::write(&path, &text).unwrap();
        }
        let on_disk = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(on_disk == text, "{} is out of date: FLINCH_BLESS=1 cargo test -p flinch-harness --lib sample::tests::schema", path.display());
    }
}
