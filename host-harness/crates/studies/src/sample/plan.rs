//! A study's plan ([`Plan`]): the scene, the keys and their distributions, the seed; the draws,
//! the chunks (`--chunk K/M`), and running them on all cores into rows and a tally.

use flinch_model::scene::TargetKind;
use flinch_sim::{self as sim};
use crate::sweep::{SweepError, Template};
use super::common::*;
use super::{keys::*, outcome::*, tally::*, dist::*, report::*};

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
    for (_, t) in flinch_model::scene::referenced_files(text, file) {
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

    /// Which of [`FAILURES`] apply to this study's scene (a body-region limit only to a body region).
    pub fn applies(&self) -> Vec<bool> {
        FAILURES.iter().map(|k| (k.applies)(&self.template.base)).collect()
    }

    pub(crate) fn report(&self, t: Tally, done: (u64, u64)) -> SampleReport {
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
            simulated: flinch_model::headline::headline(&self.template.base).simulated,
            name_mismatches: flinch_model::headline::headline(&self.template.base).mismatches,
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
