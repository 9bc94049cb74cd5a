//! `flinch bench`: the speed/accuracy trade study behind the solver defaults (docs/accuracy.md).
//!
//! For every scene it runs the reference (`fidelity = "reference"`: DOPRI5 at rtol 1e-10,
//! atol 1e-13, the full model), then a sweep of methods and settings (fixed-step RK4 and
//! semi-implicit Euler over several steps, DOPRI5 over several tolerances and largest steps, the
//! fidelity levels and each simplification), and records against the reference the error on the
//! peak contact force, the peak robot force, the detection instant (relative to the detection
//! delay), the object's final velocity and the working mode, and the cost: RHS evaluations, steps
//! and the median wall time of repeated runs. All configurations of a scene are timed round-robin
//! in the same loop, so a burst of load on a shared machine hits them alike; read ratios, not
//! absolute times, when the machine is busy.
//!
//! Writes under the output directory: `runs.csv` (scene x configuration), `summary.csv`
//! (per configuration: worst error over the scenes, total time, times faster than real time),
//! `pareto.svg` (worst error against cost) and `fixed_point.csv` (the firmware's fixed-point
//! arithmetic against f64, [`fixed_point`]).

pub mod fixed_point;

use flinch_model::scene::{self, Fidelity, Method, Scene, Simplify};
use flinch_sim::{self as sim, Summary};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What to run and where to write it.
#[derive(Debug, Clone)]
pub struct Options {
    /// Scenes: files, or shipped scenes' names; empty means every shipped scene (top level and
    /// `extremes/`) except `avoid_*`, or those of `scenes_dir` when given.
    pub scenes: Vec<PathBuf>,
    /// Read the default scenes from this directory (and its `extremes/`) instead of the ones built
    /// into the binary.
    pub scenes_dir: Option<PathBuf>,
    /// Output directory (created).
    pub out: PathBuf,
    /// Timed repetitions per configuration and scene (the median is reported).
    pub repeats: usize,
    /// A shorter sweep (fewer fixed steps and tolerances) for a quick look.
    pub quick: bool,
}

/// One solver configuration of the sweep.
#[derive(Debug, Clone, PartialEq)]
pub struct Config {
    /// Short label, unique in the sweep (e.g. `dopri5 rtol=1e-7 hmax=1e-3`).
    pub label: String,
    /// Family for the plot's colours: "dopri5", "rk4", "semi-implicit-euler", "fidelity".
    pub family: &'static str,
    /// The method.
    pub method: Method,
    /// rtol (adaptive only).
    pub rtol: f64,
    /// atol (adaptive only).
    pub atol: f64,
    /// Largest (adaptive) or fixed step, s; `None` is the scene's duration (no limit).
    pub max_step: Option<f64>,
    /// Fidelity level.
    pub fidelity: Fidelity,
    /// Explicit simplifications.
    pub simplify: Simplify,
}

impl Config {
    fn apply(&self, base: &Scene) -> Scene {
        let mut s = base.clone();
        s.solver.method = self.method;
        s.solver.rtol = self.rtol;
        s.solver.atol = self.atol;
        s.solver.max_step = self.max_step.unwrap_or(base.duration_s).min(base.duration_s);
        s.solver.fidelity = self.fidelity;
        s.solver.simplify = self.simplify;
        s
    }
}

fn dopri(rtol: f64, max_step: Option<f64>) -> Config {
    let h = max_step.map_or("none".to_string(), |h| format!("{h:e}"));
    Config {
        label: format!("dopri5 rtol={rtol:e} hmax={h}"),
        family: "dopri5",
        method: Method::Dopri5,
        rtol,
        atol: rtol * 1e-3,
        max_step,
        fidelity: Fidelity::Default,
        simplify: Simplify::default(),
    }
}

fn fixed(method: Method, h: f64) -> Config {
    let family = if method == Method::Rk4 { "rk4" } else { "semi-implicit-euler" };
    Config { label: format!("{family} h={h:e}"), family, method, rtol: 1e-6, atol: 1e-9, max_step: Some(h), fidelity: Fidelity::Default, simplify: Simplify::default() }
}

/// The reference configuration (what `fidelity = "reference"` selects).
pub fn reference() -> Config {
    Config {
        label: "reference".into(),
        family: "reference",
        method: Method::Dopri5,
        rtol: scene::REFERENCE_RTOL,
        atol: scene::REFERENCE_ATOL,
        max_step: Some(scene::DEFAULT_MAX_STEP),
        fidelity: Fidelity::Reference,
        simplify: Simplify::default(),
    }
}

/// The sweep: DOPRI5 over tolerances and largest steps, RK4 and semi-implicit Euler over fixed
/// steps, and the fidelity levels with each simplification at the default tolerance.
pub fn sweep(quick: bool) -> Vec<Config> {
    let mut v = Vec::new();
    let tols: &[f64] = if quick { &[1e-4, 1e-6, 1e-8] } else { &[1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9] };
    let hmaxes: &[Option<f64>] = if quick { &[Some(1e-3), None] } else { &[Some(1e-3), Some(1e-2), None] };
    for &h in hmaxes {
        for &r in tols {
            v.push(dopri(r, h));
        }
    }
    let rk4: &[f64] = if quick { &[1e-4, 1e-5] } else { &[1e-4, 3e-5, 1e-5, 3e-6] };
    for &h in rk4 {
        v.push(fixed(Method::Rk4, h));
    }
    let sie: &[f64] = if quick { &[1e-5, 1e-6] } else { &[1e-5, 3e-6, 1e-6] };
    for &h in sie {
        v.push(fixed(Method::SemiImplicitEuler, h));
    }
    let d = scene::DEFAULT_RTOL;
    let base = Config {
        label: "default".into(),
        family: "fidelity",
        method: scene::DEFAULT_METHOD,
        rtol: d,
        atol: scene::DEFAULT_ATOL,
        max_step: Some(scene::DEFAULT_MAX_STEP),
        fidelity: Fidelity::Default,
        simplify: Simplify::default(),
    };
    v.push(base.clone());
    v.push(Config { label: "default + rigid-robot".into(), simplify: Simplify { rigid_robot: true, no_friction: false }, ..base.clone() });
    v.push(Config { label: "default + no-friction".into(), simplify: Simplify { rigid_robot: false, no_friction: true }, ..base.clone() });
    v.push(Config { label: "fast".into(), rtol: scene::FAST_RTOL, atol: scene::FAST_ATOL, fidelity: Fidelity::Fast, ..base });
    v
}

/// Errors of one run against the reference (relative; `None` where the figure does not apply).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Errors {
    /// |peak contact force - reference| / reference.
    pub peak_contact: f64,
    /// |peak robot force - reference| / reference.
    pub peak_robot: f64,
    /// |t_detect - reference| / reference detection delay (infinite if only one detects).
    pub detect: Option<f64>,
    /// |object final velocity - reference| / |reference|.
    pub object_velocity: Option<f64>,
    /// Same working mode as the reference.
    pub mode_ok: bool,
}

impl Errors {
    /// The largest of the errors the 1 % target is on: peak forces and detection time.
    pub fn worst(&self) -> f64 {
        self.peak_contact.max(self.peak_robot).max(self.detect.unwrap_or(0.0))
    }
}

fn rel(a: f64, r: f64) -> f64 {
    if a == r {
        0.0
    } else {
        (a - r).abs() / r.abs().max(1e-300)
    }
}

/// Compares a run with the reference.
pub fn compare(run: &Summary, reference: &Summary) -> Errors {
    let detect = match (run.t_detect, reference.t_detect, reference.detection_delay) {
        (Some(a), Some(r), Some(dd)) => Some((a - r).abs() / dd.max(1e-9)),
        (None, None, _) => None,
        _ => Some(f64::INFINITY),
    };
    Errors {
        peak_contact: rel(run.peak_contact_force, reference.peak_contact_force),
        peak_robot: rel(run.peak_robot_force, reference.peak_robot_force),
        detect,
        object_velocity: run.object_final_velocity.zip(reference.object_final_velocity).map(|(a, r)| rel(a, r)),
        mode_ok: run.mode == reference.mode,
    }
}

/// One scene x configuration result.
#[derive(Debug, Clone)]
pub struct Row {
    /// Scene file stem.
    pub scene: String,
    /// Simulated time, s.
    pub duration: f64,
    /// The configuration.
    pub config: Config,
    /// The run's summary, or its error.
    pub result: Result<Summary, String>,
    /// Errors against the reference (when the run succeeded).
    pub errors: Option<Errors>,
    /// Median wall time of one run, s.
    pub wall_median: f64,
    /// Timed repetitions.
    pub repeats: usize,
}

/// The scene files `flinch bench` uses by default: `dir/*.toml` except `avoid_*`, sorted.
pub fn shipped_scenes(dir: &Path) -> Result<Vec<PathBuf>, String> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| format!("{}: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml") && !p.file_name().is_some_and(|n| n.to_string_lossy().starts_with("avoid_")))
        .collect();
    v.sort();
    Ok(v)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        return f64::NAN;
    }
    if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) }
}

/// Runs the reference and the sweep on one scene; timings interleaved round-robin.
pub fn study_scene(name: &str, base: &Scene, configs: &[Config], repeats: usize) -> Result<Vec<Row>, String> {
    let ref_scene = reference().apply(base);
    let (reference_summary, _) = sim::run(&ref_scene, false).map_err(|e| format!("{name}: the reference run failed: {e}"))?;
    let scenes: Vec<Scene> = configs.iter().map(|c| c.apply(base)).collect();
    let mut results: Vec<Result<Summary, String>> = scenes.iter().map(|s| sim::run(s, false).map(|r| r.0).map_err(|e| e.to_string())).collect();
    let mut times: Vec<Vec<f64>> = vec![Vec::new(); configs.len()];
    // Round-robin: every repetition times each configuration once. A configuration slower than
    // 0.2 s a run is timed once (its first run above already warmed it).
    for rep in 0..repeats.max(1) {
        for (i, s) in scenes.iter().enumerate() {
            if results[i].is_err() || (rep > 0 && times[i].first().is_some_and(|&t| t > 0.2)) {
                continue;
            }
            let t0 = Instant::now();
            let r = sim::run(std::hint::black_box(s), false);
            times[i].push(t0.elapsed().as_secs_f64());
            if let Err(e) = r {
                results[i] = Err(e.to_string());
            }
        }
    }
    let mut rows = Vec::new();
    let ref_time = {
        let mut t = Vec::new();
        for _ in 0..repeats.max(1) {
            let t0 = Instant::now();
            let _ = sim::run(std::hint::black_box(&ref_scene), false);
            t.push(t0.elapsed().as_secs_f64());
        }
        median(t)
    };
    rows.push(Row { scene: name.into(), duration: base.duration_s, config: reference(), errors: Some(compare(&reference_summary, &reference_summary)), result: Ok(reference_summary.clone()), wall_median: ref_time, repeats: repeats.max(1) });
    for (i, c) in configs.iter().enumerate() {
        let result = std::mem::replace(&mut results[i], Err(String::new()));
        let errors = result.as_ref().ok().map(|s| compare(s, &reference_summary));
        rows.push(Row { scene: name.into(), duration: base.duration_s, config: c.clone(), result, errors, wall_median: median(std::mem::take(&mut times[i])), repeats: repeats.max(1) });
    }
    Ok(rows)
}

fn opt(x: Option<f64>) -> String {
    x.map_or(String::new(), |v| format!("{v:.6e}"))
}

/// CSV text from records, quoted by the csv crate.
fn csv_text(rows: impl IntoIterator<Item = Vec<String>>) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        // Writing to memory cannot fail.
        let _ = w.write_record(&r);
    }
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

/// The columns of `runs.csv` (docs/conventions.md: unit suffixes; the `err_*` are relative errors,
/// dimensionless; booleans 0/1).
pub const RUNS_COLUMNS: &[&str] = &[
    "scene", "config", "family", "method", "rtol", "atol", "max_step_s", "fidelity", "simplified", "status", "reason", "steps", "rejected_steps", "rhs_evals",
    "wall_median_s", "x_real_time", "peak_contact_force_n", "peak_robot_force_n", "t_detect_s", "object_final_velocity_mps", "mode", "err_peak_contact",
    "err_peak_robot", "err_detect", "err_object_velocity", "mode_ok", "worst_err",
];

/// `runs.csv`: one line per scene and configuration.
pub fn runs_csv(rows: &[Row]) -> String {
    let head = std::iter::once(RUNS_COLUMNS.iter().map(|c| c.to_string()).collect::<Vec<_>>());
    let body = rows.iter().filter_map(|r| {
        let c = &r.config;
        let mut v = vec![r.scene.clone(), c.label.clone(), c.family.to_string(), format!("{:?}", c.method), format!("{:e}", c.rtol), format!("{:e}", c.atol), c.max_step.map_or(String::new(), |h| format!("{h:e}")), format!("{:?}", c.fidelity)];
        match (&r.result, &r.errors) {
            (Ok(sm), Some(e)) => v.extend([
                sm.simplified.join("+"),
                "ok".into(),
                String::new(),
                sm.steps.to_string(),
                sm.rejected_steps.to_string(),
                sm.rhs_evals.to_string(),
                format!("{:.6e}", r.wall_median),
                format!("{:.1}", r.duration / r.wall_median),
                format!("{:.9e}", sm.peak_contact_force),
                format!("{:.9e}", sm.peak_robot_force),
                opt(sm.t_detect),
                opt(sm.object_final_velocity),
                sm.mode.map_or(String::new(), |m| m.to_string()),
                format!("{:.3e}", e.peak_contact),
                format!("{:.3e}", e.peak_robot),
                e.detect.map_or(String::new(), |v| format!("{v:.3e}")),
                e.object_velocity.map_or(String::new(), |v| format!("{v:.3e}")),
                u8::from(e.mode_ok).to_string(),
                format!("{:.3e}", e.worst()),
            ]),
            (Err(msg), _) => {
                v.extend([String::new(), "failed".into(), msg.clone()]);
                v.resize(RUNS_COLUMNS.len(), String::new());
            }
            _ => return None,
        }
        Some(v)
    });
    csv_text(head.chain(body))
}

/// Per-configuration aggregate over the scenes.
#[derive(Debug, Clone)]
pub struct Aggregate {
    /// The configuration.
    pub config: Config,
    /// Scenes that ran.
    pub ok: usize,
    /// Scenes that failed (error or non-finite state).
    pub failed: usize,
    /// Worst error over the scenes: peak contact, peak robot, detection, object velocity.
    pub worst: [f64; 4],
    /// Scenes whose working mode differs from the reference.
    pub mode_wrong: usize,
    /// Sum of the median wall times, s.
    pub wall: f64,
    /// Sum of the simulated durations, s.
    pub simulated: f64,
    /// Smallest times-faster-than-real-time over the scenes.
    pub min_x_real_time: f64,
    /// Sum of RHS evaluations.
    pub rhs_evals: u64,
}

impl Aggregate {
    /// Worst error on the 1 % targets (peak forces, detection time).
    pub fn worst_target(&self) -> f64 {
        self.worst[0].max(self.worst[1]).max(self.worst[2])
    }
}

/// Aggregates rows by configuration label, in sweep order.
pub fn aggregate(rows: &[Row]) -> Vec<Aggregate> {
    let mut out: Vec<Aggregate> = Vec::new();
    for r in rows {
        let i = match out.iter().position(|a| a.config.label == r.config.label) {
            Some(i) => i,
            None => {
                out.push(Aggregate { config: r.config.clone(), ok: 0, failed: 0, worst: [0.0; 4], mode_wrong: 0, wall: 0.0, simulated: 0.0, min_x_real_time: f64::INFINITY, rhs_evals: 0 });
                out.len() - 1
            }
        };
        let a = &mut out[i];
        match (&r.result, &r.errors) {
            (Ok(sm), Some(e)) => {
                a.ok += 1;
                let w = [e.peak_contact, e.peak_robot, e.detect.unwrap_or(0.0), e.object_velocity.unwrap_or(0.0)];
                for (worst, v) in a.worst.iter_mut().zip(w) {
                    *worst = worst.max(v);
                }
                a.mode_wrong += usize::from(!e.mode_ok);
                a.wall += r.wall_median;
                a.simulated += r.duration;
                a.min_x_real_time = a.min_x_real_time.min(r.duration / r.wall_median);
                a.rhs_evals += sm.rhs_evals;
            }
            _ => a.failed += 1,
        }
    }
    out
}

/// The columns of `summary.csv` (worst relative errors, dimensionless; `within_1pct` 0/1).
pub const SUMMARY_COLUMNS: &[&str] = &[
    "config", "family", "scenes_ok", "scenes_failed", "worst_err_peak_contact", "worst_err_peak_robot", "worst_err_detect", "worst_err_object_velocity", "mode_wrong",
    "total_wall_s", "total_simulated_s", "x_real_time_overall", "x_real_time_worst_scene", "total_rhs_evals", "within_1pct",
];

/// `summary.csv`.
pub fn summary_csv(aggs: &[Aggregate]) -> String {
    let head = std::iter::once(SUMMARY_COLUMNS.iter().map(|c| c.to_string()).collect::<Vec<_>>());
    let body = aggs.iter().map(|a| {
        vec![
            a.config.label.clone(),
            a.config.family.to_string(),
            a.ok.to_string(),
            a.failed.to_string(),
            format!("{:.3e}", a.worst[0]),
            format!("{:.3e}", a.worst[1]),
            format!("{:.3e}", a.worst[2]),
            format!("{:.3e}", a.worst[3]),
            a.mode_wrong.to_string(),
            format!("{:.6e}", a.wall),
            format!("{:.3}", a.simulated),
            format!("{:.1}", a.simulated / a.wall),
            format!("{:.1}", a.min_x_real_time),
            a.rhs_evals.to_string(),
            u8::from(a.failed == 0 && a.mode_wrong == 0 && a.worst_target() <= 0.01).to_string(),
        ]
    });
    csv_text(head.chain(body))
}

/// The Pareto plot: worst error on the 1 % targets (over all scenes) against the total median
/// wall time, one point per configuration, the Pareto front drawn through the non-dominated ones.
pub fn pareto_svg(path: &Path, aggs: &[Aggregate]) -> Result<(), String> {
    use plotters::prelude::*;
    let pts: Vec<(&Aggregate, f64, f64)> = aggs
        .iter()
        .filter(|a| a.failed == 0 && a.config.family != "reference")
        .map(|a| (a, a.wall * 1e3, a.worst_target().max(1e-12)))
        .collect();
    if pts.is_empty() {
        return Err("no configuration ran on every scene: nothing to plot".into());
    }
    let (xmin, xmax) = pts.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), p| (lo.min(p.1), hi.max(p.1)));
    let (ymin, ymax) = pts.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), p| (lo.min(p.2), hi.max(p.2)));
    let root = SVGBackend::new(path, (1000, 700)).into_drawing_area();
    let err = |e: DrawingAreaErrorKind<std::io::Error>| format!("{}: {e}", path.display());
    root.fill(&WHITE).map_err(err)?;
    let mut chart = ChartBuilder::on(&root)
        .caption("Error against cost over the shipped scenes (flinch bench)", ("sans-serif", 22))
        .margin(15)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d((xmin / 1.5..xmax * 1.5).log_scale(), (ymin.min(1e-3) / 3.0..ymax.max(0.02) * 3.0).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("total median wall time over all scenes, ms (one core)")
        .y_desc("worst relative error: peak forces, detection time")
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()
        .map_err(err)?;
    chart
        .draw_series(LineSeries::new([(xmin / 1.5, 0.01), (xmax * 1.5, 0.01)], RED.mix(0.6)))
        .map_err(err)?
        .label("1 % target")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], RED.mix(0.6)));
    let families = [("dopri5", BLUE), ("rk4", GREEN), ("semi-implicit-euler", MAGENTA), ("fidelity", BLACK)];
    for (fam, colour) in families {
        let series: Vec<(f64, f64, String)> = pts.iter().filter(|p| p.0.config.family == fam).map(|p| (p.1, p.2, p.0.config.label.clone())).collect();
        if series.is_empty() {
            continue;
        }
        chart
            .draw_series(series.iter().map(|(x, y, _)| Circle::new((*x, *y), 5, colour.filled())))
            .map_err(err)?
            .label(fam)
            .legend(move |(x, y)| Circle::new((x + 10, y), 5, colour.filled()));
        chart
            .draw_series(series.iter().map(|(x, y, l)| Text::new(l.replace("dopri5 ", "").replace("semi-implicit-euler", "SIE"), (*x, *y), ("sans-serif", 11))))
            .map_err(err)?;
    }
    // Pareto front: sort by cost, keep those better than every cheaper one.
    let mut sorted: Vec<(f64, f64)> = pts.iter().map(|p| (p.1, p.2)).collect();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for (x, y) in sorted {
        if y < best {
            front.push((x, y));
            best = y;
        }
    }
    chart.draw_series(LineSeries::new(front, BLACK.mix(0.4))).map_err(err)?.label("Pareto front").legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLACK.mix(0.4)));
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).position(SeriesLabelPosition::UpperRight).draw().map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}

/// The shipped scenes `flinch bench` uses by default, as built into the binary: the top level and
/// `extremes/` (the study scenes of docs/accuracy.md), except `avoid_*`.
pub fn default_scene_names() -> Vec<&'static str> {
    flinch_model::shipped::names()
        .filter(|n| {
            let top = n.strip_prefix("extremes/").unwrap_or(n);
            !top.contains('/') && !top.starts_with("avoid_")
        })
        .collect()
}

/// Reads and validates every scene of the study (bad input: the message names the scene).
pub fn load_scenes(o: &Options) -> Result<Vec<(String, Scene)>, String> {
    let stem = |f: &Path| f.file_stem().map_or("?".into(), |s| s.to_string_lossy().into_owned());
    if !o.scenes.is_empty() {
        return o.scenes.iter().map(|f| flinch_model::shipped::load(f).map(|sc| (stem(f), sc))).collect();
    }
    match &o.scenes_dir {
        Some(dir) => {
            // The thesis scenes, and the study scenes of docs/accuracy.md under extremes/.
            let mut v = shipped_scenes(dir)?;
            let extra = dir.join("extremes");
            if extra.is_dir() {
                v.extend(shipped_scenes(&extra)?);
            }
            v.iter().map(|f| scene::load(f).map(|sc| (stem(f), sc)).map_err(|e| e.to_string())).collect()
        }
        None => default_scene_names().into_iter().map(|n| flinch_model::shipped::load(Path::new(n)).map(|sc| (stem(Path::new(n)), sc))).collect(),
    }
}

/// The whole study over `scenes` ([`load_scenes`]): the CSVs, the plot, the fixed-point table.
/// Prints a summary.
pub fn run(o: &Options, scenes: &[(String, Scene)]) -> Result<(), String> {
    std::fs::create_dir_all(&o.out).map_err(|e| format!("{}: {e}", o.out.display()))?;
    let configs = sweep(o.quick);
    let mut rows = Vec::new();
    for (name, sc) in scenes {
        eprintln!("{name}: reference and {} configurations, {} repetitions", configs.len(), o.repeats);
        rows.extend(study_scene(name, sc, &configs, o.repeats)?);
    }
    let write = |name: &str, text: &str| std::fs::write(o.out.join(name), text).map_err(|e| format!("{}: {e}", o.out.join(name).display()));
    write("runs.csv", &runs_csv(&rows))?;
    let aggs = aggregate(&rows);
    write("summary.csv", &summary_csv(&aggs))?;
    pareto_svg(&o.out.join("pareto.svg"), &aggs)?;
    write("fixed_point.csv", &fixed_point::table())?;
    println!("{:<40} {:>6} {:>10} {:>10} {:>10} {:>10} {:>5} {:>10} {:>10}", "configuration", "failed", "err Fc", "err Fr", "err det", "err v_p", "mode", "x real", "worst sc.");
    for a in &aggs {
        println!(
            "{:<40} {:>6} {:>10.2e} {:>10.2e} {:>10.2e} {:>10.2e} {:>5} {:>10.0} {:>10.0}",
            a.config.label, a.failed, a.worst[0], a.worst[1], a.worst[2], a.worst[3], a.mode_wrong, a.simulated / a.wall, a.min_x_real_time
        );
    }
    eprintln!("wrote runs.csv, summary.csv, pareto.svg, fixed_point.csv under {}", o.out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_scenes_are_the_embedded_ones_from_any_directory() {
        let names = default_scene_names();
        assert!(names.contains(&"tables5-7_bistable") && names.contains(&"extremes/tables5-7_bistable_object"), "{names:?}");
        assert!(!names.iter().any(|n| n.contains("avoid_") || n.starts_with("figures/")), "{names:?}");
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../scenes");
        let on_disk = shipped_scenes(&dir).unwrap().len() + shipped_scenes(&dir.join("extremes")).unwrap().len();
        assert_eq!(names.len(), on_disk, "the same scenes as --scenes-dir scenes");
        let o = Options { scenes: vec![], scenes_dir: None, out: PathBuf::new(), repeats: 1, quick: true };
        assert_eq!(load_scenes(&o).unwrap().len(), on_disk);
    }

    #[test]
    fn the_fixed_point_table_does_not_overflow_in_a_debug_build() {
        // 2 d in I16F16 above 16.4 m/s^2 once panicked here ("attempt to multiply with overflow").
        let t = fixed_point::table();
        assert!(t.contains("I16F16 mm"), "{t}");
    }
}
