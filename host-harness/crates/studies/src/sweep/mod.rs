//! `flinch sweep`: run a scene over a grid of one or two of its keys, on all cores.
//!
//! A sweep edits the scene's parsed TOML document (a dotted key path such as `motion.speed`,
//! `decoupler.spring_rate` or `decoupler.front_stop.stiffness`) and re-validates every edited
//! text with [`scene::parse`], the same validator `flinch run` uses. Every point of the grid is
//! built and checked *before* anything runs, so a bad key or a bad range stops the sweep with a
//! message naming what is wrong, and no time is spent simulating.
//!
//! Axes are `KEY=START:STOP:N` (linear steps) or `KEY=log:START:STOP:N` (geometric steps, START > 0);
//! `--log KEY` makes an axis geometric too. Points are ordered with the first axis varying slowest
//! (row-major), whatever the number of threads: the CSV is the same on one core or sixteen.
//!
//! The CSV has one row per point: the swept values, then every field of the run's [`Summary`] in
//! its declaration order (found by serialising it, so a field added to `Summary` appears here
//! without a change), then `status` (`ok`, `refused` by the validator, `failed` in the solver) and
//! `reason`. A point the validator refuses does not stop `flinch sweep`: it becomes such a row and
//! is drawn as such (`--strict` restores refusing the whole sweep, as [`Sweep::new`] does).

pub mod cli;
pub mod plot;

use flinch_model::scene::{self, Scene};
use flinch_sim::{self as sim, Summary};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde::de::{Deserialize, Deserializer, MapAccess, Visitor};
use serde_json::Value as Json;
use std::fmt;
use std::io::{self, Write};
use std::path::Path;
use toml_edit::{DocumentMut, Item, Value};

/// A sweep the user asked for that cannot run; the message names what is wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepError(pub String);

impl fmt::Display for SweepError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for SweepError {}

fn err<T>(msg: impl Into<String>) -> Result<T, SweepError> {
    Err(SweepError(msg.into()))
}

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

/// A scene file's document, ready to have keys set and be re-validated.
#[derive(Debug, Clone)]
pub struct Template {
    doc: DocumentMut,
    file: String,
    /// The file's text, when printing `doc` reproduces it byte for byte: a point's text is then
    /// the file with its swept numbers spliced in ([`Template::splice_plan`]), the text the
    /// document would print after [`set`], without cloning and printing the document for every
    /// point (0.18M instructions a point, a quarter of a Table 1 sweep point; docs/accuracy.md).
    text: Option<String>,
    /// The validated scene as the file stands.
    pub base: Scene,
}

/// What a dotted path finds in a document.
enum Found<'a> {
    Number(&'a Value),
    Other(&'a Item),
    Missing,
}

fn lookup<'a>(doc: &'a DocumentMut, key: &str) -> Found<'a> {
    lookup_in(doc.as_item(), key)
}

fn lookup_in<'a>(root: &'a Item, key: &str) -> Found<'a> {
    let mut item: &Item = root;
    let segs: Vec<&str> = key.split('.').collect();
    for (i, seg) in segs.iter().enumerate() {
        // An element of an array of numbers (`robot.joints.1`, `robot.direction.2`): the last
        // segment is its index, counted from 0.
        if let Some(Value::Array(a)) = item.as_value() {
            let last = i + 1 == segs.len();
            return match seg.parse::<usize>().ok().and_then(|n| a.get(n)) {
                Some(v @ (Value::Integer(_) | Value::Float(_))) if last => Found::Number(v),
                _ => Found::Missing,
            };
        }
        let Some(next) = item.as_table_like().and_then(|t| t.get(seg)) else {
            return Found::Missing;
        };
        item = next;
    }
    match item.as_value() {
        Some(v @ (Value::Integer(_) | Value::Float(_))) => Found::Number(v),
        _ => Found::Other(item),
    }
}

/// A number as TOML, an integer when the key held one and `x` is whole, keeping the old decoration.
fn number_like(old: Option<&Value>, x: f64) -> Value {
    let was_int = matches!(old, Some(Value::Integer(_)));
    let mut v = if was_int && x.fract() == 0.0 && x.abs() < 9.0e15 { Value::from(x as i64) } else { Value::from(x) };
    if let Some(o) = old {
        *v.decor_mut() = o.decor().clone();
    }
    v
}

/// Sets `key` to `x` in `doc`, creating missing tables (the validator then judges them). Integer
/// keys stay integers when `x` is whole. An array element is addressed by its index
/// (`robot.joints.1`). Returns false when the path cannot be set (it runs into a number, a string
/// or past an array's end): the caller must not run the unchanged scene as if it were the point.
fn set(doc: &mut DocumentMut, key: &str, x: f64) -> bool {
    let segs: Vec<&str> = key.split('.').collect();
    let mut item: &mut Item = doc.as_item_mut();
    for (i, seg) in segs.iter().enumerate() {
        let last = i + 1 == segs.len();
        if let Some(Value::Array(a)) = item.as_value_mut() {
            let Some(n) = seg.parse::<usize>().ok().filter(|&n| last && n < a.len()) else {
                return false;
            };
            let old = a.get(n).cloned();
            if !matches!(old, Some(Value::Integer(_) | Value::Float(_))) {
                return false;
            }
            a.replace(n, number_like(old.as_ref(), x));
            return true;
        }
        let inline = item.is_inline_table();
        let Some(table) = item.as_table_like_mut() else {
            // A number or string where the path needs a table: nothing can be set.
            return false;
        };
        if last {
            let old = table.get(seg).and_then(Item::as_value).cloned();
            table.insert(seg, Item::Value(number_like(old.as_ref(), x)));
            return true;
        }
        if table.get(seg).is_none() {
            let fresh = if inline { Item::Value(Value::InlineTable(Default::default())) } else { Item::Table(Default::default()) };
            table.insert(seg, fresh);
        }
        item = table.get_mut(seg).expect("inserted above");
    }
    false
}

fn numeric_keys_of(item: &Item, prefix: &str, out: &mut Vec<String>) {
    if let Some(t) = item.as_table_like() {
        for (k, v) in t.iter() {
            let path = if prefix.is_empty() { k.to_string() } else { format!("{prefix}.{k}") };
            match v.as_value() {
                Some(Value::Integer(_) | Value::Float(_)) => out.push(path),
                Some(Value::Array(a)) => {
                    for (i, e) in a.iter().enumerate() {
                        if matches!(e, Value::Integer(_) | Value::Float(_)) {
                            out.push(format!("{path}.{i}"));
                        }
                    }
                }
                _ => numeric_keys_of(v, &path, out),
            }
        }
    }
}

/// Edit distance (Levenshtein, `strsim`), for "did you mean".
fn distance(a: &str, b: &str) -> usize {
    strsim::levenshtein(a, b)
}

/// Keys of `candidates` close to `key`: a small edit distance on the whole path or on its last
/// segment, best first, at most five.
pub fn close_matches(key: &str, candidates: &[String]) -> Vec<String> {
    let leaf = key.rsplit('.').next().unwrap_or(key);
    let mut scored: Vec<(usize, &String)> = candidates
        .iter()
        .filter_map(|c| {
            let d = distance(key, c);
            let cl = c.rsplit('.').next().unwrap_or(c);
            let dl = distance(leaf, cl);
            let near = d <= (key.len() / 3).max(2) || dl <= (leaf.len() / 3).max(1) || (leaf.len() >= 3 && cl.contains(leaf));
            near.then_some((d.min(dl + 1), c))
        })
        .collect();
    scored.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.cmp(b.1)));
    scored.into_iter().take(5).map(|(_, c)| c.clone()).collect()
}

impl Template {
    /// Reads and validates a scene file.
    /// Reads a scene argument (a file, `-`, or a shipped scene's name: [`flinch_model::shipped::read`]).
    pub fn load(path: &Path) -> Result<Self, SweepError> {
        let (file, text) = flinch_model::shipped::read(path).map_err(|e| SweepError(e.0))?;
        Self::from_text(&text, &file)
    }

    /// A template from scene text; `file` names it in messages.
    pub fn from_text(text: &str, file: &str) -> Result<Self, SweepError> {
        let base = scene::parse(text, file).map_err(|e| SweepError(e.to_string()))?;
        let doc: DocumentMut = text.parse().map_err(|e| SweepError(format!("{file}: {e}")))?;
        let text = (doc.to_string() == text).then(|| text.to_string());
        Ok(Self { doc, file: file.to_string(), base, text })
    }

    /// The file name used in messages.
    pub fn file(&self) -> &str {
        &self.file
    }

    /// Every numeric key the file sets, as dotted paths, in file order.
    pub fn numeric_keys(&self) -> Vec<String> {
        let mut out = Vec::new();
        numeric_keys_of(self.doc.as_item(), "", &mut out);
        out
    }

    /// The number a key holds in the file, if it holds one.
    pub fn value(&self, key: &str) -> Option<f64> {
        match lookup(&self.doc, key) {
            Found::Number(Value::Integer(i)) => Some(*i.value() as f64),
            Found::Number(Value::Float(f)) => Some(*f.value()),
            _ => None,
        }
    }

    /// Checks that `key` can be swept: a number the file sets, or a key the file leaves out that
    /// the validator accepts when set to `probe`.
    pub fn check_key(&self, key: &str, probe: f64) -> Result<(), SweepError> {
        match lookup(&self.doc, key) {
            Found::Number(_) => Ok(()),
            Found::Other(item) => {
                if let Some(t) = item.as_table_like() {
                    let keys: Vec<String> = t.iter().filter(|(_, v)| matches!(v.as_value(), Some(Value::Integer(_) | Value::Float(_)))).map(|(k, _)| format!("{key}.{k}")).collect();
                    err(format!("{}: {key} is a table, not a number; sweep one of its keys: {}", self.file, if keys.is_empty() { "(none is numeric)".into() } else { keys.join(", ") }))
                } else {
                    let shown = item.as_value().map_or_else(|| "?".to_string(), |v| {
                        let mut v = v.clone();
                        v.decor_mut().clear();
                        v.to_string()
                    });
                    err(format!("{}: {key} = {shown} is not a number; only numeric keys can be swept", self.file))
                }
            }
            Found::Missing => {
                let mut doc = self.doc.clone();
                if !set(&mut doc, key, probe) {
                    let near = close_matches(key, &self.numeric_keys());
                    let hint = if near.is_empty() { format!("the numeric keys this scene sets: {}", self.numeric_keys().join(", ")) } else { format!("close matches: {}", near.join(", ")) };
                    return err(format!("{}: {key} cannot be set: the path runs into a value that is not a table (an array element is addressed by its index from 0, within the array's length); {hint}", self.file));
                }
                match scene::parse(&doc.to_string(), &self.file) {
                    Ok(_) => Ok(()),
                    Err(e) => {
                        let near = close_matches(key, &self.numeric_keys());
                        let why = e.issues.iter().find(|i| i.key == key || key.ends_with(&format!(".{}", i.key)) || i.key.ends_with(key)).or(e.issues.first()).map(|i| i.message.clone()).unwrap_or_default();
                        let hint = if near.is_empty() {
                            format!("the numeric keys this scene sets: {}", self.numeric_keys().join(", "))
                        } else {
                            format!("close matches: {}", near.join(", "))
                        };
                        err(format!("{}: unknown key {key}: the scene does not set it and the validator refuses it ({why}); {hint}", self.file))
                    }
                }
            }
        }
    }

    /// A new template: this one with `sets` applied and re-validated (a sweep around a variant).
    pub fn with_base(&self, sets: &[(&str, f64)]) -> Result<Self, SweepError> {
        let base = self.with(sets)?;
        let mut doc = self.doc.clone();
        for &(k, x) in sets {
            set(&mut doc, k, x);
        }
        // `with` above refused any key that cannot be set.
        Ok(Self { doc, file: self.file.clone(), base, text: None })
    }

    /// The scene with `sets` applied, validated; the error names the values and the validator's
    /// message.
    pub fn with(&self, sets: &[(&str, f64)]) -> Result<Scene, SweepError> {
        self.with_refused_keys(sets).map_err(|(e, _)| e)
    }

    /// As [`Template::with`]; a refusal also names the keys the validator's issues are about (in
    /// the order found, without repeats), so refusals can be counted by key (`flinch sample`).
    pub fn with_refused_keys(&self, sets: &[(&str, f64)]) -> Result<Scene, (SweepError, Vec<String>)> {
        let mut doc = self.doc.clone();
        for &(k, x) in sets {
            if !set(&mut doc, k, x) {
                return Err((SweepError(format!("{}: {k} cannot be set to {x}: the path runs into a value that is not a table", self.file)), vec![k.to_string()]));
            }
        }
        self.validated(&doc.to_string(), sets)
    }

    /// Where each of `keys` sits in the file's text, and the value there, when every key is a
    /// number the file sets and the text prints back exactly; `None` otherwise (a point is then
    /// built by [`Template::with`]).
    pub fn splice_plan(&self, keys: &[&str]) -> Option<Vec<(std::ops::Range<usize>, Value)>> {
        let text = self.text.as_deref()?;
        let im = toml_edit::ImDocument::parse(text).ok()?;
        let mut plan: Vec<(std::ops::Range<usize>, Value)> = Vec::with_capacity(keys.len());
        for k in keys {
            let Found::Number(v) = lookup_in(im.as_item(), k) else { return None };
            let span = v.span()?;
            if plan.iter().any(|(r, _)| r.start < span.end && span.start < r.end) {
                return None;
            }
            plan.push((span, v.clone()));
        }
        Some(plan)
    }

    /// The file's text with the numbers of `plan` replaced by `xs` (in plan order), printed as
    /// [`set`] prints them (an integer stays one when the value is whole).
    pub fn spliced(&self, plan: &[(std::ops::Range<usize>, Value)], xs: &[f64]) -> String {
        let text = self.text.as_deref().unwrap_or_default();
        let mut order: Vec<usize> = (0..plan.len()).collect();
        order.sort_by_key(|&i| plan[i].0.start);
        let mut out = String::with_capacity(text.len() + 32);
        let mut at = 0;
        for i in order {
            let (span, old) = &plan[i];
            out.push_str(&text[at..span.start]);
            let mut v = number_like(Some(old), xs[i]);
            v.decor_mut().clear();
            out.push_str(&v.to_string());
            at = span.end;
        }
        out.push_str(&text[at..]);
        out
    }

    /// As [`Template::with`] for the keys of `plan`, on the spliced text: the same scene, or the
    /// same refusal.
    pub fn with_spliced(&self, plan: &[(std::ops::Range<usize>, Value)], sets: &[(&str, f64)]) -> Result<Scene, SweepError> {
        let xs: Vec<f64> = sets.iter().map(|&(_, x)| x).collect();
        self.validated(&self.spliced(plan, &xs), sets).map_err(|(e, _)| e)
    }

    fn validated(&self, text: &str, sets: &[(&str, f64)]) -> Result<Scene, (SweepError, Vec<String>)> {
        scene::parse(text, &self.file).map_err(|e| {
            let what: Vec<String> = sets.iter().map(|(k, x)| format!("{k} = {x}")).collect();
            let mut keys: Vec<String> = Vec::new();
            for i in &e.issues {
                if !keys.contains(&i.key) {
                    keys.push(i.key.clone());
                }
            }
            (SweepError(format!("{}: the scene validator refuses it: {e}", what.join(", "))), keys)
        })
    }

    /// A new template: this one with its document changed by `edit` (a string key set, a table
    /// replaced) and re-validated; `what` names the change in the validator's message.
    pub fn edited(&self, what: &str, edit: impl FnOnce(&mut DocumentMut)) -> Result<Self, SweepError> {
        let mut doc = self.doc.clone();
        edit(&mut doc);
        let base = scene::parse(&doc.to_string(), &self.file).map_err(|e| SweepError(format!("{what}: the scene validator refuses it: {e}")))?;
        Ok(Self { doc, file: self.file.clone(), base, text: None })
    }
}

/// A sweep checked and built: every point's scene is valid, or (built with
/// [`Sweep::keep_going`]) refused with the validator's reason.
pub struct Sweep {
    /// The swept axes (one or two), first varying slowest.
    pub axes: Vec<Axis>,
    /// The values of each axis.
    pub values: Vec<Vec<f64>>,
    scenes: Vec<Scene>,
    /// Per point: the validator's reason when it refused the point's scene (the point does not run).
    refused: Vec<Option<String>>,
    /// Scene name, for titles.
    pub scene_name: String,
}

/// What became of a point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// Ran; the summary is there.
    Ok,
    /// The scene validator refused the point's values; it did not run.
    Refused,
    /// It ran and the solver gave up.
    Failed,
}

impl Status {
    /// As the CSV writes it.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Ok => "ok",
            Self::Refused => "refused",
            Self::Failed => "failed",
        }
    }
}

/// One point of a sweep and its outcome.
#[derive(Debug, Clone)]
pub struct Point {
    /// The swept values, in axis order.
    pub values: Vec<f64>,
    /// Index of each value on its axis.
    pub index: Vec<usize>,
    /// The summary, or why there is none (the validator's or the solver's message).
    pub outcome: Result<Summary, String>,
    /// Ok, refused or failed.
    pub status: Status,
}

/// A finished sweep, points in row-major order (first axis slowest).
#[derive(Debug, Clone)]
pub struct SweepResult {
    /// The axes.
    pub axes: Vec<Axis>,
    /// The values of each axis.
    pub values: Vec<Vec<f64>>,
    /// The points.
    pub points: Vec<Point>,
    /// Scene name.
    pub scene_name: String,
}

/// Progress reporting: a bar on a terminal, nothing when piped or in tests.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Progress {
    /// Draw an `indicatif` bar on stderr if stderr is a terminal.
    Auto,
    /// Never draw.
    Hidden,
}

fn grid_index(sizes: &[usize], mut k: usize) -> Vec<usize> {
    let mut idx = vec![0; sizes.len()];
    for a in (0..sizes.len()).rev() {
        idx[a] = k % sizes[a];
        k /= sizes[a];
    }
    idx
}

impl Sweep {
    /// Checks the axes against the template and builds every point's scene. Nothing runs. A point
    /// whose values the validator refuses refuses the whole sweep (`flinch sweep --strict`).
    pub fn new(template: &Template, axes: Vec<Axis>) -> Result<Self, SweepError> {
        Self::build(template, axes, true)
    }

    /// As [`Sweep::new`], but a refused point becomes a row with status `refused` and the
    /// validator's reason instead of refusing the sweep; bad axes or keys still refuse it.
    pub fn keep_going(template: &Template, axes: Vec<Axis>) -> Result<Self, SweepError> {
        Self::build(template, axes, false)
    }

    fn build(template: &Template, axes: Vec<Axis>, strict: bool) -> Result<Self, SweepError> {
        if axes.is_empty() {
            return err("nothing to sweep: give --vary KEY=START:STOP:N once or twice");
        }
        if axes.len() > 2 {
            return err(format!("{} --vary axes given: a sweep has one or two", axes.len()));
        }
        if axes.len() == 2 && axes[0].key == axes[1].key {
            return err(format!("--vary {} is given twice: the two axes must be different keys", axes[0].key));
        }
        for a in &axes {
            template.check_key(&a.key, a.start)?;
        }
        let values: Vec<Vec<f64>> = axes.iter().map(Axis::values).collect();
        let keys: Vec<&str> = axes.iter().map(|a| a.key.as_str()).collect();
        let plan = template.splice_plan(&keys);
        let sizes: Vec<usize> = values.iter().map(Vec::len).collect();
        let total: usize = sizes.iter().product();
        if total > 1_000_000 {
            return err(format!("{total} points: more than a million; use fewer steps"));
        }
        let built: Vec<Result<Scene, SweepError>> = (0..total)
            .into_par_iter()
            .map(|k| {
                let idx = grid_index(&sizes, k);
                let sets: Vec<(&str, f64)> = axes.iter().zip(&idx).zip(&values).map(|((a, &i), v)| (a.key.as_str(), v[i])).collect();
                match &plan {
                    Some(p) => template.with_spliced(p, &sets),
                    None => template.with(&sets),
                }
            })
            .collect();
        let n_refused = built.iter().filter(|b| b.is_err()).count();
        let mut scenes = Vec::with_capacity(total);
        let mut refused = Vec::with_capacity(total);
        for b in built {
            match b {
                Ok(s) => {
                    scenes.push(s);
                    refused.push(None);
                }
                Err(e) if strict => {
                    let of = if total > 1 { format!("{n_refused} of {total} points refused; the first: ") } else { String::new() };
                    return err(format!("{of}{e}"));
                }
                Err(e) => {
                    // Never run; the template's scene stands in so indices stay aligned.
                    scenes.push(template.base.clone());
                    refused.push(Some(e.0));
                }
            }
        }
        Ok(Self { axes, values, scenes, refused, scene_name: template.base.name.clone() })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.scenes.len()
    }

    /// True when there are no points (never, for a built sweep).
    pub fn is_empty(&self) -> bool {
        self.scenes.is_empty()
    }

    /// The scene of point `k` (row-major); for a refused point, the template's (it does not run).
    pub fn scene(&self, k: usize) -> &Scene {
        &self.scenes[k]
    }

    /// Why point `k` was refused, if it was.
    pub fn refusal(&self, k: usize) -> Option<&str> {
        self.refused.get(k).and_then(|r| r.as_deref())
    }

    /// Points the validator refused.
    pub fn refused_count(&self) -> usize {
        self.refused.iter().filter(|r| r.is_some()).count()
    }

    /// Runs every point on the current rayon pool; the order of the result does not depend on it.
    pub fn run(&self, progress: Progress) -> SweepResult {
        use std::io::IsTerminal;
        let bar = if progress == Progress::Auto && io::stderr().is_terminal() {
            let b = ProgressBar::new(self.len() as u64);
            if let Ok(style) = ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {pos}/{len} points, {per_sec}, eta {eta}") {
                b.set_style(style.progress_chars("=> "));
            }
            b
        } else {
            ProgressBar::hidden()
        };
        let sizes: Vec<usize> = self.values.iter().map(Vec::len).collect();
        let points = self
            .scenes
            .par_iter()
            .enumerate()
            .map(|(k, sc)| {
                let index = grid_index(&sizes, k);
                let values = index.iter().zip(&self.values).map(|(&i, v)| v[i]).collect();
                let (outcome, status) = match &self.refused[k] {
                    Some(why) => (Err(why.clone()), Status::Refused),
                    None => match sim::run(sc, false) {
                        Ok((s, _)) => (Ok(s), Status::Ok),
                        Err(e) => (Err(e.to_string()), Status::Failed),
                    },
                };
                bar.inc(1);
                Point { values, index, outcome, status }
            })
            .collect();
        bar.finish_and_clear();
        SweepResult { axes: self.axes.clone(), values: self.values.clone(), points, scene_name: self.scene_name.clone() }
    }

    /// Runs on a pool of `jobs` threads (None: all cores).
    pub fn run_with_jobs(&self, progress: Progress, jobs: Option<usize>) -> Result<SweepResult, SweepError> {
        match jobs {
            None => Ok(self.run(progress)),
            Some(0) => err("--jobs must be at least 1"),
            Some(j) => {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(j).build().map_err(|e| SweepError(format!("--jobs {j}: {e}")))?;
                Ok(pool.install(|| self.run(progress)))
            }
        }
    }
}

/// A JSON object's entries in their serialised order (serde_json's map sorts without the
/// `preserve_order` feature; this keeps the declaration order of `Summary`).
struct Ordered(Vec<(String, Json)>);

impl<'de> Deserialize<'de> for Ordered {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Ordered;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a JSON object")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut m: A) -> Result<Ordered, A::Error> {
                let mut out = Vec::new();
                while let Some(e) = m.next_entry::<String, Json>()? {
                    out.push(e);
                }
                Ok(Ordered(out))
            }
        }
        d.deserialize_map(V)
    }
}

/// Every field of a summary, in declaration order, as JSON values.
pub fn summary_fields(s: &Summary) -> Vec<(String, Json)> {
    serde_json::to_string(s).ok().and_then(|t| serde_json::from_str::<Ordered>(&t).ok()).map(|o| o.0).unwrap_or_default()
}

/// Every field of a summary by name (sorted, not in declaration order: [`summary_fields`] gives
/// that). Straight to JSON values, without printing and parsing a JSON text: a sweep looks up
/// every point's fields, and that round trip was 6 % of a Tables 5-7 sweep point's instructions
/// (callgrind, docs/accuracy.md). Same values, so the same CSV cells.
pub fn summary_map(s: &Summary) -> serde_json::Map<String, Json> {
    match serde_json::to_value(s) {
        Ok(Json::Object(m)) => m,
        _ => serde_json::Map::new(),
    }
}

/// A numeric field of a summary by name (`None` when null, not numeric or unknown). Booleans are
/// 0/1 so `stroke_exhausted` can be drawn.
pub fn metric(s: &Summary, name: &str) -> Option<f64> {
    summary_map(s).remove(name).and_then(|v| match v {
        Json::Number(n) => n.as_f64(),
        Json::Bool(b) => Some(f64::from(u8::from(b))),
        _ => None,
    })
}

/// The summary fields a heat map or line can show (numbers, or booleans as 0/1).
pub const METRICS: &[&str] = &[
    "t_contact", "t_detect", "t_brake", "detection_delay", "reaction_time", "peak_contact_force", "peak_robot_force",
    "object_final_velocity", "mode", "stroke_exhausted", "achieved_restitution", "steps", "rhs_evals", "t_stop",
    "approach_velocity", "contacts", "object_peak_velocity", "max_travel", "decoupler_impulse", "peak_gas_pressure",
    "rejected_steps", "events", "peak_robot_force_t_s", "first_impact_peak_robot_force_n", "first_impact_peak_robot_force_t_s",
    "stroke_left_min_m", "target_deformation_max_m", "closest_approach_m", "concluded", "t_end_s", "flange_reach_after_end_m", "safe",
];

/// Checks a metric name before anything runs.
pub fn check_metric(name: &str) -> Result<(), SweepError> {
    if METRICS.contains(&name) {
        return Ok(());
    }
    let all: Vec<String> = METRICS.iter().map(|s| s.to_string()).collect();
    let near = close_matches(name, &all);
    err(format!("--metric {name}: not a numeric summary field; {}", if near.is_empty() { format!("one of: {}", METRICS.join(", ")) } else { format!("close matches: {}", near.join(", ")) }))
}

fn csv_cell(v: &Json) -> String {
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

impl SweepResult {
    /// Writes the CSV (the `csv` crate quotes): the swept keys, every `Summary` field, then
    /// `status` (ok, refused, failed) and `reason` (the validator's or the solver's message).
    pub fn write_csv(&self, out: &mut dyn Write) -> io::Result<()> {
        let names: Vec<String> = self.points.iter().find_map(|p| p.outcome.as_ref().ok()).map(|s| summary_fields(s).into_iter().map(|(k, _)| k).collect()).unwrap_or_default();
        let mut w = csv::Writer::from_writer(out);
        let mut header: Vec<String> = self.axes.iter().map(|a| a.key.clone()).collect();
        header.extend(names.iter().cloned());
        header.push("status".into());
        header.push("reason".into());
        w.write_record(&header).map_err(csv_io)?;
        for p in &self.points {
            let mut row: Vec<String> = p.values.iter().map(|x| x.to_string()).collect();
            match &p.outcome {
                Ok(s) => {
                    let fields = summary_map(s);
                    row.extend(names.iter().map(|n| fields.get(n).map_or(String::new(), csv_cell)));
                    row.push(p.status.as_str().into());
                    row.push(String::new());
                }
                Err(e) => {
                    row.extend(names.iter().map(|_| String::new()));
                    row.push(p.status.as_str().into());
                    row.push(e.clone());
                }
            }
            w.write_record(&row).map_err(csv_io)?;
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_and_log_values_hit_both_ends() {
        let a = Axis::parse("motion.speed=0.01:0.3:30", false).unwrap();
        let v = a.values();
        assert_eq!(v.len(), 30);
        assert_eq!((v[0], v[29]), (0.01, 0.3));
        let l = Axis::parse("target.stiffness=log:1e3:1e5:3", false).unwrap();
        let v = l.values();
        assert_eq!(v[0], 1e3);
        assert!((v[1] - 1e4).abs() < 1e-6);
        assert_eq!(v[2], 1e5);
        assert_eq!(Axis::parse("target.stiffness=1e3:1e5:3", true).unwrap().spacing, Spacing::Log);
    }

    #[test]
    fn edit_distance() {
        assert_eq!(distance("speed", "sped"), 1);
        assert_eq!(distance("", "abc"), 3);
        assert_eq!(close_matches("motion.sped", &["motion.speed".into(), "motion.decel".into(), "tool.mass".into()]), vec!["motion.speed".to_string()]);
    }

    /// A point's spliced text is the text the edited document prints, for every shipped scene
    /// and a number of every kind (float, integer kept whole, integer made fractional, an array
    /// element), so the fast path validates exactly what the slow one did.
    #[test]
    fn spliced_text_is_the_edited_documents_text() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
        let mut checked = 0;
        for e in std::fs::read_dir(&dir).unwrap().flatten() {
            let path = e.path();
            if path.extension().is_none_or(|x| x != "toml") {
                continue;
            }
            let text = std::fs::read_to_string(&path).unwrap();
            let Ok(t) = Template::from_text(&text, "x.toml") else { continue };
            assert!(t.text.is_some(), "{}: the document does not print back its text", path.display());
            let keys = t.numeric_keys();
            for key in &keys {
                for x in [0.25, 3.0, 1e-7, 12345.678] {
                    let plan = t.splice_plan(&[key.as_str()]).unwrap_or_else(|| panic!("{}: {key}", path.display()));
                    let mut doc = t.doc.clone();
                    assert!(set(&mut doc, key, x));
                    assert_eq!(t.spliced(&plan, &[x]), doc.to_string(), "{}: {key} = {x}", path.display());
                    checked += 1;
                }
            }
            if keys.len() >= 2 {
                let (a, b) = (keys[keys.len() - 1].as_str(), keys[0].as_str());
                let plan = t.splice_plan(&[a, b]).unwrap();
                let mut doc = t.doc.clone();
                assert!(set(&mut doc, a, 0.5) && set(&mut doc, b, 7.0));
                assert_eq!(t.spliced(&plan, &[0.5, 7.0]), doc.to_string(), "{}: {a}, {b}", path.display());
            }
        }
        assert!(checked > 1000, "{checked}");
    }

    #[test]
    fn grid_is_row_major() {
        assert_eq!(grid_index(&[2, 3], 0), vec![0, 0]);
        assert_eq!(grid_index(&[2, 3], 2), vec![0, 2]);
        assert_eq!(grid_index(&[2, 3], 3), vec![1, 0]);
    }
}
