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
pub mod stats;

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
// Random numbers
// ---------------------------------------------------------------------------------------------

const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

/// SplitMix64's output function (Steele, Lea, Flood 2014): a bijection of u64 that mixes well.
fn mix(z: u64) -> u64 {
    let mut z = z.wrapping_add(GOLDEN);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The uniform number in (0, 1) of draw `draw` (the key's position in `--vary`) of sample `index`
/// for `seed`: `mix(mix(mix(seed) ^ index) ^ draw)`, its top 53 bits, offset by half a step so
/// neither 0 nor 1 comes out. Counter-based: no state, so any sample can be drawn anywhere.
pub fn uniform01(seed: u64, index: u64, draw: u64) -> f64 {
    let h = mix(mix(mix(seed) ^ index) ^ draw);
    ((h >> 11) as f64 + 0.5) * (1.0 / (1u64 << 53) as f64)
}

// ---------------------------------------------------------------------------------------------
// Distributions
// ---------------------------------------------------------------------------------------------

/// A distribution a key is drawn from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Dist {
    /// `normal:MEAN:SD`.
    Normal {
        /// Mean.
        mean: f64,
        /// Standard deviation, > 0.
        sd: f64,
    },
    /// `lognormal:MU:SIGMA`: ln X is normal with mean MU and standard deviation SIGMA (as numpy's
    /// `lognormal(mean, sigma)`); the median is exp(MU).
    LogNormal {
        /// Mean of ln X.
        mu: f64,
        /// Standard deviation of ln X, > 0.
        sigma: f64,
    },
    /// `uniform:LO:HI`.
    Uniform {
        /// Lower end.
        lo: f64,
        /// Upper end, > LO.
        hi: f64,
    },
    /// `triangular:LO:MODE:HI`.
    Triangular {
        /// Lower end.
        lo: f64,
        /// Most likely value, in [LO, HI].
        mode: f64,
        /// Upper end, > LO.
        hi: f64,
    },
}

impl Dist {
    /// The distribution function.
    pub fn cdf(&self, x: f64) -> f64 {
        match *self {
            Dist::Normal { mean, sd } => stats::normal_cdf((x - mean) / sd),
            Dist::LogNormal { mu, sigma } => {
                if x <= 0.0 {
                    0.0
                } else {
                    stats::normal_cdf((x.ln() - mu) / sigma)
                }
            }
            Dist::Uniform { lo, hi } => ((x - lo) / (hi - lo)).clamp(0.0, 1.0),
            Dist::Triangular { lo, mode, hi } => {
                if x <= lo {
                    0.0
                } else if x >= hi {
                    1.0
                } else if x <= mode {
                    (x - lo) * (x - lo) / ((hi - lo) * (mode - lo))
                } else {
                    1.0 - (hi - x) * (hi - x) / ((hi - lo) * (hi - mode))
                }
            }
        }
    }

    /// The quantile (inverse distribution function) at u in (0, 1).
    pub fn quantile(&self, u: f64) -> f64 {
        match *self {
            Dist::Normal { mean, sd } => mean + sd * stats::normal_quantile(u),
            Dist::LogNormal { mu, sigma } => (mu + sigma * stats::normal_quantile(u)).exp(),
            Dist::Uniform { lo, hi } => lo + (hi - lo) * u,
            Dist::Triangular { lo, mode, hi } => {
                let f = (mode - lo) / (hi - lo);
                if u < f {
                    lo + (u * (hi - lo) * (mode - lo)).sqrt()
                } else {
                    hi - ((1.0 - u) * (hi - lo) * (hi - mode)).sqrt()
                }
            }
        }
    }

    /// As written on the command line (numbers in Rust's shortest round-trip form).
    pub fn spec(&self) -> String {
        match *self {
            Dist::Normal { mean, sd } => format!("normal:{mean}:{sd}"),
            Dist::LogNormal { mu, sigma } => format!("lognormal:{mu}:{sigma}"),
            Dist::Uniform { lo, hi } => format!("uniform:{lo}:{hi}"),
            Dist::Triangular { lo, mode, hi } => format!("triangular:{lo}:{mode}:{hi}"),
        }
    }
}

/// The forms `--vary` accepts, for messages.
pub const FORMS: &str = "normal:MEAN:SD, lognormal:MU:SIGMA (of ln X; median exp(MU)), uniform:LO:HI, triangular:LO:MODE:HI; normal and lognormal may end in :LO:HI to truncate them to [LO, HI]";

/// One `--vary KEY=DIST` as parsed: the key, the distribution and optional explicit bounds.
#[derive(Debug, Clone, PartialEq)]
pub struct VarySpec {
    /// Dotted key path.
    pub key: String,
    /// The distribution.
    pub dist: Dist,
    /// `:LO:HI` given after a normal or lognormal.
    pub bounds: Option<(f64, f64)>,
}

impl VarySpec {
    /// Parses `KEY=normal:MEAN:SD[:LO:HI]`, `KEY=lognormal:MU:SIGMA[:LO:HI]`, `KEY=uniform:LO:HI`,
    /// `KEY=triangular:LO:MODE:HI`.
    pub fn parse(spec: &str) -> Result<Self, SweepError> {
        let Some((key, dist)) = spec.split_once('=') else {
            return err(format!("--vary {spec:?}: expected KEY=DIST, e.g. motion.dead_time=uniform:0.016:0.032; DIST is one of {FORMS}"));
        };
        let key = key.trim();
        if key.is_empty() || key.split('.').any(|s| s.trim().is_empty()) {
            return err(format!("--vary {spec:?}: the key must be a dotted path such as motion.speed"));
        }
        let parts: Vec<&str> = dist.split(':').map(str::trim).collect();
        let kind = parts[0].to_ascii_lowercase();
        let mut nums = Vec::new();
        for p in &parts[1..] {
            match p.parse::<f64>() {
                Ok(x) if x.is_finite() => nums.push(x),
                _ => return err(format!("--vary {spec:?}: {p:?} is not a finite number")),
            }
        }
        let want = |n: &[usize], form: &str| -> Result<(), SweepError> {
            if n.contains(&nums.len()) {
                Ok(())
            } else {
                err(format!("--vary {spec:?}: expected {key}={form} ({} numbers after {kind}:), got {}", n.iter().map(usize::to_string).collect::<Vec<_>>().join(" or "), nums.len()))
            }
        };
        let (dist, bounds) = match kind.as_str() {
            "normal" => {
                want(&[2, 4], "normal:MEAN:SD[:LO:HI]")?;
                if nums[1] <= 0.0 {
                    return err(format!("--vary {spec:?}: SD must be > 0, got {}", nums[1]));
                }
                (Dist::Normal { mean: nums[0], sd: nums[1] }, (nums.len() == 4).then(|| (nums[2], nums[3])))
            }
            "lognormal" => {
                want(&[2, 4], "lognormal:MU:SIGMA[:LO:HI] (MU and SIGMA of ln X)")?;
                if nums[1] <= 0.0 {
                    return err(format!("--vary {spec:?}: SIGMA must be > 0, got {}", nums[1]));
                }
                (Dist::LogNormal { mu: nums[0], sigma: nums[1] }, (nums.len() == 4).then(|| (nums[2], nums[3])))
            }
            "uniform" => {
                want(&[2], "uniform:LO:HI")?;
                (Dist::Uniform { lo: nums[0], hi: nums[1] }, None)
            }
            "triangular" => {
                want(&[3], "triangular:LO:MODE:HI")?;
                if !(nums[0] <= nums[1] && nums[1] <= nums[2]) {
                    return err(format!("--vary {spec:?}: need LO <= MODE <= HI, got {} {} {}", nums[0], nums[1], nums[2]));
                }
                (Dist::Triangular { lo: nums[0], mode: nums[1], hi: nums[2] }, None)
            }
            _ => return err(format!("--vary {spec:?}: unknown distribution {:?}; one of {FORMS}", parts[0])),
        };
        match dist {
            Dist::Uniform { lo, hi } | Dist::Triangular { lo, hi, .. } if lo >= hi => {
                return err(format!("--vary {spec:?}: LO must be below HI, got {lo} >= {hi}"));
            }
            _ => {}
        }
        if let Some((lo, hi)) = bounds {
            if lo >= hi {
                return err(format!("--vary {spec:?}: the truncation LO must be below HI, got {lo} >= {hi}"));
            }
        }
        Ok(Self { key: key.to_string(), dist, bounds })
    }

    /// As written (canonical numbers).
    pub fn spec(&self) -> String {
        match self.bounds {
            Some((lo, hi)) => format!("{}={}:{lo}:{hi}", self.key, self.dist.spec()),
            None => format!("{}={}", self.key, self.dist.spec()),
        }
    }
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
    /// F at the lower end of `within` (0 without one).
    f_lo: f64,
    /// Without truncation: the probability of a draw outside the key's accepted range (those
    /// samples will be refused and counted).
    pub outside: f64,
}

impl Varied {
    /// The value of this key for uniform number u.
    pub fn value(&self, u: f64) -> f64 {
        self.spec.dist.quantile(self.f_lo + u * self.kept)
    }
}

/// A sample study: the scene, the keys, the seed, N and the chunk this process runs.
pub struct Plan {
    /// The scene's template.
    pub template: Template,
    /// FNV-1a 64 of the scene's text (merging refuses chunks of different scenes).
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
            if parsed[..i].iter().any(|b| b.key == a.key) {
                return err(format!("--vary {} is given twice: each key is drawn once", a.key));
            }
        }
        let mut vary = Vec::new();
        for spec in parsed {
            let info = key_info(&template.base, &spec.key);
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
            let (f_lo, kept) = match within {
                Some((a, b)) => {
                    let (fa, fb) = (d.cdf(a), d.cdf(b));
                    (fa, fb - fa)
                }
                None => (0.0, 1.0),
            };
            if let Some((a, b)) = within {
                if a >= b || kept.is_nan() || kept <= 1e-12 {
                    return err(format!(
                        "--vary {}: the distribution has no probability in [{a}, {b}]{}",
                        spec.spec(),
                        info.as_ref().filter(|_| truncate).map_or(String::new(), |i| format!(" (with --truncate, the accepted range of {} is {})", spec.key, i.range))
                    ));
                }
            }
            let outside = match (&info, within) {
                (Some(i), None) => d.cdf(i.lo.unwrap_or(f64::NEG_INFINITY)) + (1.0 - d.cdf(i.hi.unwrap_or(f64::INFINITY))),
                _ => 0.0,
            };
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
            let v = Varied { spec, column, info, within, kept, f_lo, outside };
            // The key must be settable, as for a sweep; probe it at the median draw.
            template.check_key(&v.spec.key, v.value(0.5))?;
            vary.push(v);
        }
        let range = match chunk {
            Some((k, m)) => chunk_range(samples, k, m),
            None => (0, samples),
        };
        Ok(Self { template, scene_hash: fnv1a64(scene_text), vary, seed, samples, range, truncate })
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
        h.extend(["stroke_exhausted", "mode", "peak_contact_force_n", "peak_robot_force_n", "stroke_left_min_m", "safe", "status", "reason"].map(String::from));
        h
    }

    /// Runs the plan's range on `pool` (None: the global rayon pool, all cores), in blocks of
    /// [`BLOCK`], writing each block's rows to `csv` in index order; stops after the block in
    /// which `stop` is raised. The report covers the samples that ran.
    pub fn run(&self, progress: Progress, csv: Option<&mut dyn Write>, stop: &AtomicBool, pool: Option<&rayon::ThreadPool>) -> io::Result<SampleReport> {
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
        let mut w = csv.map(csv::Writer::from_writer);
        if let Some(w) = w.as_mut() {
            w.write_record(self.header())?;
        }
        let mut tally = Tally::default();
        let mut at = first;
        while at < end && !stop.load(Ordering::SeqCst) {
            let len = (end - at).min(BLOCK as u64) as usize;
            let block = || (0..len).into_par_iter().map(|j| self.run_one(at + j as u64)).collect::<Vec<Row>>();
            let rows = match pool {
                Some(p) => p.install(block),
                None => block(),
            };
            for r in &rows {
                if let Some(w) = w.as_mut() {
                    w.write_record(r.record())?;
                }
                tally.add(r);
            }
            at += len as u64;
            bar.inc(len as u64);
        }
        if let Some(w) = w.as_mut() {
            w.flush()?;
        }
        bar.finish_and_clear();
        Ok(self.report(tally, (first, at)))
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
            confidence: CONFIDENCE,
            estimates: Vec::new(),
        };
        r.finish(&t.failures);
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
}

/// The failures estimated, each from the run's summary. A body-region limit joins this list once
/// the summary carries one.
pub const FAILURES: &[FailureKind] = &[
    FailureKind { name: "stroke_exhausted", what: "stroke exhausted (the tool in the back end-stop while touching the target; docs/verdicts.md)", test: |s| s.stroke_exhausted },
    FailureKind { name: "mode_3", what: "working mode 3 (the tool hits the back end-stop while the robot still brakes; Fig. 46)", test: |s| s.mode == Some(3) },
    FailureKind { name: "not_safe", what: "not safe by the one definition (docs/verdicts.md: the summary's `failures` is not empty)", test: |s| !s.safe },
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
    /// Per [`FAILURES`].
    pub failed: Vec<bool>,
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
            failed: FAILURES.iter().map(|f| (f.test)(s)).collect(),
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
    /// The CSV record (booleans 0/1, empty cells where a sample did not run).
    pub fn record(&self) -> Vec<String> {
        let mut r = vec![self.index.to_string()];
        r.extend(self.values.iter().map(f64::to_string));
        match &self.outcome {
            Outcome::Ran(b) => {
                r.extend([
                    bit(b.stroke_exhausted),
                    b.mode.map_or(String::new(), |m| m.to_string()),
                    b.peak_contact_force_n.to_string(),
                    b.peak_robot_force_n.to_string(),
                    b.stroke_left_min_m.map_or(String::new(), |x| x.to_string()),
                    bit(b.safe),
                    "ok".into(),
                    String::new(),
                ]);
            }
            Outcome::Refused { reason, .. } => {
                r.extend((0..6).map(|_| String::new()));
                r.push("refused".into());
                r.push(reason.clone());
            }
            Outcome::Failed(why) => {
                r.extend((0..6).map(|_| String::new()));
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

#[derive(Debug, Default)]
struct Tally {
    ran: u64,
    refused: u64,
    solver_failed: u64,
    failures: Vec<u64>,
    modes: Modes,
    refusals: Vec<RefusalGroup>,
    solver_failures: Option<SolverFailures>,
}

impl Tally {
    fn add(&mut self, r: &Row) {
        if self.failures.is_empty() {
            self.failures = vec![0; FAILURES.len()];
        }
        match &r.outcome {
            Outcome::Ran(b) => {
                self.ran += 1;
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

// ---------------------------------------------------------------------------------------------
// The report and its estimates
// ---------------------------------------------------------------------------------------------

/// A varied key in the report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct VaryReport {
    /// Dotted key.
    pub key: String,
    /// Its CSV column (with the unit's suffix).
    pub column: String,
    /// The distribution, canonical.
    pub dist: String,
    /// The key's unit, if the key tables list it.
    pub unit: Option<String>,
    /// The key's accepted range, as the validator says it.
    pub accepted_range: Option<String>,
    /// Draws are confined to [within_lo, within_hi] (explicit :LO:HI, or --truncate), in the key's unit.
    pub within_lo: Option<f64>,
    /// See `within_lo`.
    pub within_hi: Option<f64>,
    /// The probability the truncation keeps (1 without one).
    pub kept_probability: f64,
    /// Without truncation, the probability of a draw outside the accepted range (refused).
    pub outside_probability: f64,
}

/// The estimate of one failure's probability.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Estimate {
    /// Which failure (`stroke_exhausted`, `mode_3`, `not_safe`).
    pub failure: String,
    /// What it is.
    pub what: String,
    /// Runs with it.
    pub failures: u64,
    /// Runs (samples that ran: not refused, not failed in the solver).
    pub runs: u64,
    /// failures / runs; null with no run.
    pub p: Option<f64>,
    /// The interval reported: "clopper-pearson" at 0 or all failures, "wilson" otherwise.
    pub interval: String,
    /// Its lower end.
    pub low: f64,
    /// Its upper end.
    pub high: f64,
    /// Wilson score interval, lower end.
    pub wilson_low: f64,
    /// Wilson score interval, upper end.
    pub wilson_high: f64,
    /// Clopper-Pearson exact interval, lower end.
    pub clopper_pearson_low: f64,
    /// Clopper-Pearson exact interval, upper end.
    pub clopper_pearson_high: f64,
    /// The Clopper-Pearson upper end if every refused or solver-failed sample were a failure
    /// (over all samples drawn): the bound that does not rest on the accepted range.
    pub high_if_unrun_failed: f64,
}

/// Computes an estimate from counts.
pub fn estimate(kind: &FailureKind, failures: u64, runs: u64, unrun: u64) -> Estimate {
    let alpha = 1.0 - CONFIDENCE;
    let z = stats::normal_quantile(1.0 - alpha / 2.0);
    let (wl, wh) = stats::wilson(failures, runs, z);
    let (cl, ch) = stats::clopper_pearson(failures, runs, alpha);
    let exact = runs == 0 || failures == 0 || failures == runs;
    let (_, worst) = stats::clopper_pearson(failures + unrun, runs + unrun, alpha);
    Estimate {
        failure: kind.name.into(),
        what: kind.what.into(),
        failures,
        runs,
        p: (runs > 0).then(|| failures as f64 / runs as f64),
        interval: if exact { "clopper-pearson" } else { "wilson" }.into(),
        low: if exact { cl } else { wl },
        high: if exact { ch } else { wh },
        wilson_low: wl,
        wilson_high: wh,
        clopper_pearson_low: cl,
        clopper_pearson_high: ch,
        high_if_unrun_failed: worst,
    }
}

/// `flinch sample --json`: the study, its counts and estimates (docs/sample.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct SampleReport {
    /// docs/conventions.md.
    pub schema_version: u32,
    /// Scene name.
    pub scene: String,
    /// The scene as given.
    pub scene_file: String,
    /// FNV-1a 64 of the scene's text.
    pub scene_fnv1a64: String,
    /// Seed.
    pub seed: u64,
    /// N of the whole study.
    pub samples: u64,
    /// Draws truncated to the keys' accepted ranges.
    pub truncate: bool,
    /// The varied keys.
    pub vary: Vec<VaryReport>,
    /// The sample index ranges [first, end) this report covers, ascending.
    pub ranges: Vec<[u64; 2]>,
    /// The ranges are [[0, samples]]: the whole study.
    pub complete: bool,
    /// Samples drawn (in the ranges).
    pub drawn: u64,
    /// Samples that ran.
    pub ran: u64,
    /// Samples the validator refused.
    pub refused: u64,
    /// Samples the solver gave up on.
    pub solver_failed: u64,
    /// Runs by working mode.
    pub modes: Modes,
    /// Refusals by the keys refused, first sample ascending.
    pub refusals: Vec<RefusalGroup>,
    /// Solver failures, if any.
    pub solver_failures: Option<SolverFailures>,
    /// Two-sided confidence of the intervals.
    pub confidence: f64,
    /// One per failure.
    pub estimates: Vec<Estimate>,
}

impl SampleReport {
    fn finish(&mut self, failures: &[u64]) {
        self.complete = self.ranges.len() == 1 && self.ranges[0] == [0, self.samples];
        let unrun = self.refused + self.solver_failed;
        self.estimates = FAILURES.iter().enumerate().map(|(i, k)| estimate(k, failures.get(i).copied().unwrap_or(0), self.ran, unrun)).collect();
    }

    /// What the human summary prints.
    pub fn human(&self) -> String {
        let mut t = format!("{}\n", self.scene);
        let of = if self.complete { format!("{} samples", self.drawn) } else { format!("{} of {} samples (ranges {})", self.drawn, self.samples, self.ranges.iter().map(|r| format!("{}..{}", r[0], r[1])).collect::<Vec<_>>().join(", ")) };
        t.push_str(&format!("  {of}, seed {}: {} ran, {} refused by the validator, {} solver failures\n", self.seed, self.ran, self.refused, self.solver_failed));
        for v in &self.vary {
            let within = match (v.within_lo, v.within_hi) {
                (None, None) if v.kept_probability < 1.0 => "truncated".to_string(),
                (None, None) => String::new(),
                (lo, hi) => format!(
                    " within [{}, {}] (keeps {})",
                    lo.map_or("-inf".into(), |x| x.to_string()),
                    hi.map_or("+inf".into(), |x| x.to_string()),
                    pct(v.kept_probability)
                ),
            };
            // Only when it matters at this N: an expected 0.01 refused samples or more.
            let outside = if v.outside_probability * self.samples as f64 >= 0.01 { format!("; {} of draws outside the accepted range {} (refused)", pct(v.outside_probability), v.accepted_range.clone().unwrap_or_default()) } else { String::new() };
            t.push_str(&format!("  {} ~ {}{within}{outside}\n", v.key, v.dist));
        }
        t.push_str(&format!("  probability (95 % interval, over the {} runs):\n", self.ran));
        for e in &self.estimates {
            let p = e.p.map_or("-".to_string(), sig);
            t.push_str(&format!("    {:<17} {:>8} of {:<8} p = {p:<9} [{}, {}] {}\n", e.failure, e.failures, e.runs, sig(e.low), sig(e.high), if e.interval == "wilson" { "Wilson" } else { "Clopper-Pearson" }));
        }
        t.push_str(&format!("  working modes: 1: {}, 2: {}, 3: {}, none: {}\n", self.modes.mode_1, self.modes.mode_2, self.modes.mode_3, self.modes.no_mode));
        for g in &self.refusals {
            t.push_str(&format!("  REFUSED {} ({}), first sample {}: {}\n", g.count, if g.keys.is_empty() { "?".into() } else { g.keys.join(", ") }, g.first_sample, g.first_reason));
        }
        if let Some(f) = &self.solver_failures {
            t.push_str(&format!("  SOLVER FAILED {}, first sample {}: {}\n", f.count, f.first_sample, f.first_reason));
        }
        let unrun = self.refused + self.solver_failed;
        if unrun > 0 {
            t.push_str(&format!(
                "  the estimates are over the samples that ran; if the {unrun} that did not were failures, the upper ends would be: {}\n",
                self.estimates.iter().map(|e| format!("{} {}", e.failure, sig(e.high_if_unrun_failed))).collect::<Vec<_>>().join(", ")
            ));
        }
        t
    }
}

/// A probability for people: 3 significant digits, scientific below 1e-3.
pub fn sig(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else if x >= 1e-3 {
        let decimals = (2 - x.log10().floor() as i32).clamp(0, 6) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.2e}")
    }
}

fn pct(x: f64) -> String {
    format!("{} %", sig(x * 100.0))
}

/// Merges the reports of chunks of one study into the report of their union, equal field for
/// field to a single run over the same samples. Refuses reports of different studies (scene text,
/// seed, N, keys and distributions, truncation) and overlapping ranges.
pub fn merge(reports: &[SampleReport], names: &[String]) -> Result<SampleReport, SweepError> {
    let Some(first) = reports.first() else {
        return err("--merge: no reports given");
    };
    let name = |i: usize| names.get(i).cloned().unwrap_or_else(|| format!("report {}", i + 1));
    for (i, r) in reports.iter().enumerate() {
        if r.schema_version != SCHEMA_VERSION {
            return err(format!("--merge {}: schema_version {} is not {SCHEMA_VERSION}", name(i), r.schema_version));
        }
        let same = |what: &str, a: String, b: String| if a == b { Ok(()) } else { err(format!("--merge {}: another study: its {what} is {b}, {}'s is {a}", name(i), name(0))) };
        same("scene text (FNV-1a 64)", first.scene_fnv1a64.clone(), r.scene_fnv1a64.clone())?;
        same("seed", first.seed.to_string(), r.seed.to_string())?;
        same("--samples", first.samples.to_string(), r.samples.to_string())?;
        same("--truncate", first.truncate.to_string(), r.truncate.to_string())?;
        let keys = |r: &SampleReport| r.vary.iter().map(|v| format!("{}={}", v.key, v.dist)).collect::<Vec<_>>().join(" ");
        same("--vary", keys(first), keys(r))?;
        if r.vary != first.vary {
            return err(format!("--merge {}: another study: its --vary bounds differ from {}'s", name(i), name(0)));
        }
        let names_of = |r: &SampleReport| r.estimates.iter().map(|e| e.failure.clone()).collect::<Vec<_>>().join(", ");
        same("failures estimated", names_of(first), names_of(r))?;
    }
    let mut ranges: Vec<([u64; 2], usize)> = reports.iter().enumerate().flat_map(|(i, r)| r.ranges.iter().map(move |x| (*x, i))).collect();
    ranges.sort();
    for w in ranges.windows(2) {
        if w[1].0[0] < w[0].0[1] {
            return err(format!("--merge: {} and {} overlap (samples {}..{} and {}..{}): each sample may be counted once", name(w[0].1), name(w[1].1), w[0].0[0], w[0].0[1], w[1].0[0], w[1].0[1]));
        }
    }
    let mut merged: Vec<[u64; 2]> = Vec::new();
    for (r, _) in ranges {
        match merged.last_mut() {
            Some(last) if last[1] == r[0] => last[1] = r[1],
            _ => merged.push(r),
        }
    }
    let mut out = first.clone();
    out.ranges = merged;
    out.drawn = reports.iter().map(|r| r.drawn).sum();
    out.ran = reports.iter().map(|r| r.ran).sum();
    out.refused = reports.iter().map(|r| r.refused).sum();
    out.solver_failed = reports.iter().map(|r| r.solver_failed).sum();
    out.modes = Modes::default();
    out.refusals = Vec::new();
    out.solver_failures = None;
    let mut failures = vec![0u64; FAILURES.len()];
    for r in reports {
        out.modes.mode_1 += r.modes.mode_1;
        out.modes.mode_2 += r.modes.mode_2;
        out.modes.mode_3 += r.modes.mode_3;
        out.modes.no_mode += r.modes.no_mode;
        for g in &r.refusals {
            add_refusal(&mut out.refusals, g.clone());
        }
        if let Some(f) = &r.solver_failures {
            add_failure(&mut out.solver_failures, f.clone());
        }
        for (i, k) in FAILURES.iter().enumerate() {
            failures[i] += r.estimates.iter().find(|e| e.failure == k.name).map_or(0, |e| e.failures);
        }
    }
    out.finish(&failures);
    Ok(out)
}

/// Units of the report's numeric fields (docs/conventions.md): counts, indices and probabilities
/// are "1"; the truncation bounds are in the key's unit, which the entry's `unit` gives.
const UNITS: &[(&str, &str)] = &[
    ("schema_version", "1"), ("seed", "1"), ("samples", "1"), ("drawn", "1"), ("ran", "1"), ("refused", "1"), ("solver_failed", "1"),
    ("count", "1"), ("first_sample", "1"), ("mode_1", "1"), ("mode_2", "1"), ("mode_3", "1"), ("no_mode", "1"), ("confidence", "1"),
    ("failures", "1"), ("runs", "1"), ("p", "1"), ("low", "1"), ("high", "1"), ("wilson_low", "1"), ("wilson_high", "1"),
    ("clopper_pearson_low", "1"), ("clopper_pearson_high", "1"), ("high_if_unrun_failed", "1"), ("kept_probability", "1"),
    ("outside_probability", "1"), ("within_lo", "the key's unit, given in `unit`"), ("within_hi", "the key's unit, given in `unit`"),
];

/// The JSON Schema of `flinch sample --json` (docs/schema/sample.json), every numeric field with
/// its `unit`; and the numeric fields without one (none, or the test fails).
pub fn schema() -> (String, Vec<String>) {
    use serde_json::Value;
    let mut schema = schemars::schema_for!(SampleReport);
    let mut missing = Vec::new();
    let numeric = |p: &Value| {
        let ty = |t: &Value| matches!(t.as_str(), Some("number" | "integer"));
        match p.get("type") {
            Some(Value::Array(a)) => a.iter().any(ty),
            Some(t) => ty(t),
            None => false,
        }
    };
    let mut visit = |obj: &mut serde_json::Map<String, Value>, at: &str| {
        if let Some(Value::Object(props)) = obj.get_mut("properties") {
            for (name, prop) in props.iter_mut() {
                if !numeric(prop) {
                    continue;
                }
                match UNITS.iter().find(|(n, _)| n == name) {
                    Some((_, u)) => {
                        if let Value::Object(p) = prop {
                            p.insert("unit".into(), Value::String((*u).into()));
                        }
                    }
                    None => missing.push(format!("{at}{name}")),
                }
            }
        }
    };
    if let Some(root) = schema.as_object_mut() {
        root.insert("description".into(), Value::String("`flinch sample --json`: the study, its counts and each failure's probability with a 95 % interval (docs/sample.md). Units: the `unit` keyword of every numeric field (docs/conventions.md).".into()));
        root.insert("$id".into(), Value::String("https://flinch.invalid/schema/sample.json".into()));
        visit(root, "");
        if let Some(Value::Object(defs)) = root.get_mut("$defs") {
            for (k, d) in defs.iter_mut() {
                if let Value::Object(o) = d {
                    visit(o, &format!("{k}."));
                }
            }
        }
    }
    let mut text = serde_json::to_string_pretty(&schema).unwrap_or_default();
    text.push('\n');
    (text, missing)
}

/// Raised by Ctrl-C (installed by the command line): the run stops after the current block.
pub static STOP: AtomicBool = AtomicBool::new(false);

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
