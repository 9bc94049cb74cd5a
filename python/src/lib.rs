//! `flinch._flinch`: the harness library (flinch-harness) called from Python. The public API is the
//! Python package `flinch` (python/flinch/): this module takes scenes as (file name, TOML text) and
//! hands back JSON text and column buffers, which the package turns into dicts, NumPy arrays and
//! pandas DataFrames. Errors are the package's exceptions (`flinch.errors`), with the messages the
//! command line prints.
//!
//! Every long call releases the GIL (`Python::detach`), so Dask's threads run in parallel; a
//! sample checks for Ctrl-C between blocks of samples.

use flinch_harness::report;
use flinch_harness::sample::{self as sampling, Outcome, Plan, Row, SampleReport};
use flinch_harness::scene::{self, SceneError};
use flinch_harness::shipped;
use flinch_harness::sim;
use flinch_harness::sweep::{self as sweeping, Progress, Sweep, Template};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

/// The file name a scene given as a dict has in messages.
const DICT: &str = "<dict>";

/// One of `flinch.errors`' exceptions, built with `args`.
fn error<'py, A: pyo3::call::PyCallArgs<'py>>(py: Python<'py>, kind: &str, args: A) -> PyErr {
    match py.import("flinch.errors").and_then(|m| m.getattr(kind)).and_then(|c| c.call1(args)) {
        Ok(e) => PyErr::from_value(e),
        Err(e) => e,
    }
}

fn input_error(py: Python<'_>, msg: impl Into<String>) -> PyErr {
    error(py, "InputError", (msg.into(),))
}

/// A scene the validator refuses: `flinch.errors.SceneError(message, file, issues)`, each issue a
/// (line or None, key, message) tuple. A dict's issues have no line (the TOML text was made here).
fn scene_error(py: Python<'_>, mut e: SceneError) -> PyErr {
    if e.file == DICT {
        for i in &mut e.issues {
            i.line = None;
        }
    }
    let issues: Vec<(Option<usize>, String, String)> = e.issues.iter().map(|i| (i.line, i.key.clone(), i.message.clone())).collect();
    error(py, "SceneError", (e.to_string(), e.file.clone(), issues))
}

/// Reads a scene argument as `flinch run` does: a file, or a shipped scene's name. Returns the
/// name messages use and the text.
#[pyfunction]
fn read_scene(py: Python<'_>, scene: &str) -> PyResult<(String, String)> {
    if scene == "-" {
        return Err(error(py, "SceneError", ("a scene from standard input is the command line's: give a path, a shipped scene's name or a dict".to_string(), "-".to_string(), Vec::<(Option<usize>, String, String)>::new())));
    }
    shipped::read(Path::new(scene)).map_err(|e| error(py, "SceneError", (e.0, scene.to_string(), Vec::<(Option<usize>, String, String)>::new())))
}

/// A scene given as a dict (as JSON text, from `json.dumps`) as TOML text.
#[pyfunction]
fn dict_to_toml(py: Python<'_>, json: &str) -> PyResult<String> {
    let bad = |why: String| error(py, "SceneError", (format!("{DICT}: {why}"), DICT.to_string(), Vec::<(Option<usize>, String, String)>::new()));
    let value: toml::Value = serde_json::from_str(json).map_err(|e| bad(format!("no TOML form: {e} (None has none: leave the key out)")))?;
    if !value.is_table() {
        return Err(bad("a scene is a table (a dict of keys)".into()));
    }
    toml::to_string(&value).map_err(|e| bad(format!("no TOML form: {e}")))
}

/// A scene's TOML text as JSON text (for `flinch.scene`, which returns it as a dict).
#[pyfunction]
fn toml_to_json(py: Python<'_>, file: &str, text: &str) -> PyResult<String> {
    let value: toml::Value = toml::from_str(text).map_err(|e| error(py, "SceneError", (format!("{file}: not valid TOML: {e}"), file.to_string(), Vec::<(Option<usize>, String, String)>::new())))?;
    serde_json::to_string(&value).map_err(|e| input_error(py, format!("{file}: {e}")))
}

/// Validates a scene: the validator of `flinch run`, with its messages.
fn template(py: Python<'_>, file: &str, text: &str) -> PyResult<Template> {
    scene::parse(text, file).map_err(|e| scene_error(py, e))?;
    Template::from_text(text, file).map_err(|e| input_error(py, e.0))
}

/// Validates a scene; raises `SceneError` with every issue.
#[pyfunction]
fn check(py: Python<'_>, file: &str, text: &str) -> PyResult<()> {
    template(py, file, text).map(|_| ())
}

/// `flinch run --json`: the summary as JSON text.
#[pyfunction]
fn run(py: Python<'_>, file: &str, text: &str) -> PyResult<String> {
    let sc = scene::parse(text, file).map_err(|e| scene_error(py, e))?;
    let out = py.detach(|| sim::run(&sc, false).map(|(s, _)| report::json(&s)).map_err(|e| e.to_string()));
    out.map_err(|e| error(py, "SolverError", (format!("{file}: {e}"),)))
}

fn pool(py: Python<'_>, jobs: Option<usize>) -> PyResult<Option<rayon::ThreadPool>> {
    match jobs {
        None => Ok(None),
        Some(0) => Err(input_error(py, "jobs must be at least 1")),
        Some(j) => rayon::ThreadPoolBuilder::new().num_threads(j).build().map(Some).map_err(|e| input_error(py, format!("jobs={j}: {e}"))),
    }
}

/// `flinch sweep`: returns (the CSV text of `flinch sweep --csv`, points, solver failures,
/// refused). Bad axes, or every point refused, raise `InputError`; with `strict`, one refused point.
#[pyfunction]
#[pyo3(signature = (file, text, vary, log, strict, jobs))]
fn sweep(py: Python<'_>, file: &str, text: &str, vary: Vec<String>, log: Vec<String>, strict: bool, jobs: Option<usize>) -> PyResult<(String, usize, usize, usize)> {
    let t = template(py, file, text)?;
    let axes = sweeping::cli::axes(&vary, &log).map_err(|e| input_error(py, e.0))?;
    let built = if strict { Sweep::new(&t, axes) } else { Sweep::keep_going(&t, axes) };
    let sw = built.map_err(|e| input_error(py, e.0))?;
    if sw.refused_count() == sw.len() {
        let first = (0..sw.len()).find_map(|k| sw.refusal(k)).unwrap_or_default();
        return Err(input_error(py, format!("the validator refuses all {} points; the first: {first}", sw.len())));
    }
    let pool = pool(py, jobs)?;
    let result = py.detach(|| match &pool {
        Some(p) => p.install(|| sw.run(Progress::Hidden)),
        None => sw.run(Progress::Hidden),
    });
    Ok((result.csv(), result.points.len(), result.failures(), result.refused()))
}

/// The plan of a sample study, checked as `flinch sample` checks it.
#[allow(clippy::too_many_arguments)]
fn plan(py: Python<'_>, file: &str, text: &str, vary: &[String], samples: u64, seed: u64, truncate: bool, chunk: Option<(u64, u64)>) -> PyResult<Plan> {
    let t = template(py, file, text)?;
    if let Some((k, m)) = chunk {
        if k == 0 || m == 0 || k > m {
            return Err(input_error(py, format!("chunk ({k}, {m}): expected (K, M) with 1 <= K <= M")));
        }
    }
    Plan::new(t, text, vary, seed, samples, chunk, truncate).map_err(|e| input_error(py, e.0))
}

/// Checks a sample study without running it; returns the CSV header and the notes `flinch sample`
/// prints before running (the probability of draws outside a key's accepted range).
#[pyfunction]
#[pyo3(signature = (file, text, vary, samples, seed, truncate))]
fn sample_check(py: Python<'_>, file: &str, text: &str, vary: Vec<String>, samples: u64, seed: u64, truncate: bool) -> PyResult<(Vec<String>, Vec<String>)> {
    let p = plan(py, file, text, &vary, samples, seed, truncate, None)?;
    let notes = p
        .vary
        .iter()
        .filter(|v| v.outside > 0.0 && v.outside * samples as f64 >= 0.5)
        .map(|v| {
            format!(
                "{} ~ {} puts {:.3} % of its draws outside the accepted range {}: those samples are refused and counted (truncate=True draws within it)",
                v.spec.key,
                v.spec.dist.spec(),
                v.outside * 100.0,
                v.info.as_ref().map_or(String::new(), |i| i.range.clone())
            )
        })
        .collect();
    Ok((p.header(), notes))
}

/// A sample's rows, as columns.
#[derive(Default)]
struct Columns {
    sample: Vec<u8>,
    values: Vec<Vec<u8>>,
    /// 1, 0, or -1 where the sample did not run (or, for body_limits_pass, no body region).
    stroke_exhausted: Vec<u8>,
    safe: Vec<u8>,
    body_limits_pass: Vec<u8>,
    /// 1 to 3, 0 no mode, -1 did not run.
    mode: Vec<u8>,
    peak_contact_force_n: Vec<u8>,
    peak_robot_force_n: Vec<u8>,
    stroke_left_min_m: Vec<u8>,
    /// 0 ok, 1 refused, 2 failed.
    status: Vec<u8>,
    /// (row, reason) of the rows that did not run.
    reasons: Vec<(usize, String)>,
    len: usize,
}

fn tri(b: Option<bool>) -> u8 {
    match b {
        Some(true) => 1,
        Some(false) => 0,
        None => (-1i8) as u8,
    }
}

impl Columns {
    fn new(keys: usize) -> Self {
        Self { values: vec![Vec::new(); keys], ..Self::default() }
    }

    fn add(&mut self, r: &Row) {
        self.sample.extend_from_slice(&r.index.to_le_bytes());
        for (col, x) in self.values.iter_mut().zip(&r.values) {
            col.extend_from_slice(&x.to_le_bytes());
        }
        let f = |col: &mut Vec<u8>, x: f64| col.extend_from_slice(&x.to_le_bytes());
        match &r.outcome {
            Outcome::Ran(b) => {
                // Not concluded (the robot had not stopped by the run's end): the stroke, the mode
                // and the body limits are unknown (<NA>) unless their failure was already seen.
                // A failure seen before the end is known (as the CSV's cells).
                let known = b.not_concluded.is_none();
                self.stroke_exhausted.push(tri(Some(b.stroke_exhausted).filter(|&x| known || x)));
                self.safe.push(tri(Some(b.safe)));
                self.body_limits_pass.push(tri(b.body_limits_pass.filter(|&p| known || !p)));
                self.mode.push(b.mode.filter(|&m| known || m == 3).unwrap_or(0));
                f(&mut self.peak_contact_force_n, b.peak_contact_force_n);
                f(&mut self.peak_robot_force_n, b.peak_robot_force_n);
                f(&mut self.stroke_left_min_m, b.stroke_left_min_m.unwrap_or(f64::NAN));
                match &b.not_concluded {
                    None => self.status.push(0),
                    Some(why) => {
                        self.status.push(3);
                        self.reasons.push((self.len, why.clone()));
                    }
                }
            }
            Outcome::Refused { reason, .. } | Outcome::Failed(reason) => {
                for c in [&mut self.stroke_exhausted, &mut self.safe, &mut self.body_limits_pass, &mut self.mode] {
                    c.push((-1i8) as u8);
                }
                for c in [&mut self.peak_contact_force_n, &mut self.peak_robot_force_n, &mut self.stroke_left_min_m] {
                    f(c, f64::NAN);
                }
                self.status.push(if matches!(r.outcome, Outcome::Refused { .. }) { 1 } else { 2 });
                self.reasons.push((self.len, reason.clone()));
            }
        }
        self.len += 1;
    }

    fn into_dict<'py>(self, py: Python<'py>, plan: &Plan) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        let b = |v: &[u8]| PyBytes::new(py, v);
        d.set_item("sample", b(&self.sample))?;
        let values = PyList::empty(py);
        for (v, col) in plan.vary.iter().zip(&self.values) {
            values.append((v.column.clone(), b(col)))?;
        }
        d.set_item("values", values)?;
        for (name, col) in [
            ("stroke_exhausted", &self.stroke_exhausted),
            ("mode", &self.mode),
            ("peak_contact_force_n", &self.peak_contact_force_n),
            ("peak_robot_force_n", &self.peak_robot_force_n),
            ("stroke_left_min_m", &self.stroke_left_min_m),
            ("safe", &self.safe),
            ("body_limits_pass", &self.body_limits_pass),
            ("status", &self.status),
        ] {
            d.set_item(name, b(col))?;
        }
        d.set_item("reasons", self.reasons)?;
        d.set_item("body", plan.body())?;
        d.set_item("len", self.len)?;
        Ok(d)
    }
}

/// `flinch sample` (with `chunk`, `--chunk K/M`): returns the `--json` report as JSON text and,
/// with `rows`, the rows as column buffers. Runs on all cores, or on a pool of `jobs` threads.
/// Ctrl-C stops it after the current block and raises KeyboardInterrupt.
#[pyfunction]
#[pyo3(signature = (file, text, vary, samples, seed, truncate, chunk, jobs, rows))]
#[allow(clippy::too_many_arguments)]
fn sample<'py>(py: Python<'py>, file: &str, text: &str, vary: Vec<String>, samples: u64, seed: u64, truncate: bool, chunk: Option<(u64, u64)>, jobs: Option<usize>, rows: bool) -> PyResult<(String, Option<Bound<'py, PyDict>>)> {
    let p = plan(py, file, text, &vary, samples, seed, truncate, chunk)?;
    let pool = pool(py, jobs)?;
    let stop = AtomicBool::new(false);
    let mut cols = rows.then(|| Columns::new(p.vary.len()));
    let mut interrupted: Option<PyErr> = None;
    let ran = py.detach(|| {
        let mut sink = |r: &Row| {
            if let Some(c) = cols.as_mut() {
                c.add(r);
            }
            // After each block: Ctrl-C raises KeyboardInterrupt (only on the main thread).
            if (r.index + 1 - p.range.0).is_multiple_of(sampling::BLOCK as u64) {
                if let Err(e) = Python::attach(|py| py.check_signals()) {
                    interrupted = Some(e);
                    stop.store(true, Ordering::SeqCst);
                }
            }
            Ok(())
        };
        p.run_rows(Progress::Hidden, &mut sink, &stop, pool.as_ref()).map_err(|e| e.to_string())
    });
    if let Some(e) = interrupted {
        return Err(e);
    }
    let report = ran.map_err(|e| error(py, "SolverError", (e,)))?;
    let json = serde_json::to_string(&report).map_err(|e| input_error(py, e.to_string()))?;
    let cols = match cols {
        Some(c) => Some(c.into_dict(py, &p)?),
        None => None,
    };
    Ok((json, cols))
}

fn parse_report(py: Python<'_>, i: usize, text: &str) -> PyResult<SampleReport> {
    serde_json::from_str(text).map_err(|e| input_error(py, format!("report {}: not a `flinch sample` report: {e}", i + 1)))
}

/// `flinch sample --merge`: the reports (JSON texts) of chunks of one study merged.
#[pyfunction]
fn merge(py: Python<'_>, reports: Vec<String>) -> PyResult<String> {
    let parsed: Vec<SampleReport> = reports.iter().enumerate().map(|(i, t)| parse_report(py, i, t)).collect::<PyResult<_>>()?;
    let names: Vec<String> = (1..=parsed.len()).map(|i| format!("report {i}")).collect();
    let m = sampling::merge(&parsed, &names).map_err(|e| input_error(py, e.0))?;
    serde_json::to_string(&m).map_err(|e| input_error(py, e.to_string()))
}

/// The human summary `flinch sample` prints, of a report (JSON text).
#[pyfunction]
fn sample_human(py: Python<'_>, report: &str) -> PyResult<String> {
    Ok(parse_report(py, 0, report)?.human())
}

/// The shipped scenes' names.
#[pyfunction]
fn shipped_names() -> Vec<String> {
    shipped::names().map(String::from).collect()
}

#[pymodule]
fn _flinch(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("BLOCK", sampling::BLOCK)?;
    m.add("VERSION", env!("CARGO_PKG_VERSION"))?;
    for f in [
        wrap_pyfunction!(read_scene, m)?,
        wrap_pyfunction!(dict_to_toml, m)?,
        wrap_pyfunction!(toml_to_json, m)?,
        wrap_pyfunction!(check, m)?,
        wrap_pyfunction!(run, m)?,
        wrap_pyfunction!(sweep, m)?,
        wrap_pyfunction!(sample_check, m)?,
        wrap_pyfunction!(sample, m)?,
        wrap_pyfunction!(merge, m)?,
        wrap_pyfunction!(sample_human, m)?,
        wrap_pyfunction!(shipped_names, m)?,
    ] {
        m.add_function(f)?;
    }
    Ok(())
}
