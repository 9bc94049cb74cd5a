//! `flinch design`: size a module for a robot, or a robot's speed for a module.
//!
//! From the stopping-distance budget of `flinch check` (the firmware's own formula
//! `v DT + v^2 / (2 d_c)`, [`crate::check::check`]): after the switch fires at travel d_sw the flange
//! keeps closing for the stopping distance, so the module needs a stroke `C >= d_sw + v DT + v^2/2d`
//! and, for a given stroke, the robot may go up to the speed that solves `v DT + v^2/2d = C - d_sw`.
//! Both answers are then confirmed by simulating the scene: the smallest stroke (C1 and C2 scaled
//! together for a bi-stable module, L for a hydraulic one) and the largest speed at which the
//! flange does not reach the target, found by a scan and a bisection. The working mode (Fig. 46) and
//! the margins (formula and simulated) are reported with them.
//!
//! Every candidate is the scene file with keys set and re-validated ([`crate::sweep::Template`]).
//! Two keys are adjusted so a candidate stays a fair test, and the report says so: `duration` is
//! lengthened to cover contact, detection, the dead time and braking, and `target.gap` is raised
//! when the flange would otherwise meet the target before reaching V_c.

use crate::check;
pub use crate::search::boundary;
use flinch_model::scene::{Decoupler, Scene, Sensor};
use flinch_sim::Summary;
use crate::sweep::plot::{self as splot, Panel, Series, Style, XAxis, PALETTE};
use crate::sweep::{SweepError, Template};
use rayon::prelude::*;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// `flinch design SCENE [--stroke C] [--speed V] [--dead-time DT]`.
#[derive(clap::Args, Debug)]
pub struct DesignArgs {
    /// The scene: robot, tool, module (bi-stable or hydraulic, with a travel switch) and obstacle.
    pub scene: PathBuf,
    /// The module's total stroke C, m (default: the scene's; a bi-stable module keeps its C1:C2).
    #[arg(long, value_name = "M")]
    pub stroke: Option<f64>,
    /// The robot's speed V_c, m/s (default: the scene's motion.speed).
    #[arg(long, value_name = "M/S", value_parser = opt_speed)]
    pub speed: Option<f64>,
    /// The controller's dead time DT, s (default: the scene's motion.dead_time), e.g. 0.07.
    #[arg(long = "dead-time", value_name = "S", value_parser = opt_dead_time)]
    pub dead_time: Option<f64>,
    /// Draw peak forces and the stroke margin against speed, the safe limit marked (.svg or .png).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// A human body region (ISO/TS 15066 Annex A) or "all": the largest speed per region with the
    /// scene's module and with a rigid tool, beside the Annex A closed form (the scene's target must
    /// be kind = "body_region"; crate::body_design). --stroke, --speed and --plot do not apply.
    #[arg(long = "body-region", value_name = "REGION|all")]
    pub body_region: Option<String>,
    /// With --body-region: the force threshold of the rigid tool's sensor, N.
    #[arg(long = "rigid-sensor", value_name = "N", default_value_t = crate::body_design::RIGID_SENSOR_N)]
    pub rigid_sensor: f64,
    /// Set a scene key for this run: KEY=VALUE, repeatable (VALUE is TOML; a bare word is a
    /// string), validated like the file: e.g. --set motion.speed=0.5 --set target.region=face.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = flinch_model::overrides::Set::parse)]
    pub set: Vec<flinch_model::overrides::Set>,
}

/// `--speed`: held to `motion.speed`'s range, with its message (issue 27; exit 2 before any run).
fn opt_speed(text: &str) -> Result<f64, String> {
    flinch_model::scene::option_number("motion.speed", &flinch_model::scene::MOTION_SPEED, text)
}

/// `--dead-time`: held to `motion.dead_time`'s range.
fn opt_dead_time(text: &str) -> Result<f64, String> {
    flinch_model::scene::option_number("motion.dead_time", &flinch_model::scene::MOTION_DEAD_TIME, text)
}

/// One simulated candidate.
#[derive(Debug, Clone, Serialize, schemars::JsonSchema)]
pub struct Trial {
    /// Speed, m/s.
    #[serde(rename = "speed_mps")]
    pub speed: f64,
    /// Stroke, m.
    #[serde(rename = "stroke_m")]
    pub stroke: f64,
    /// The run: its `safe`, `failures`, `stroke_left_min_m` and `closest_approach_m` are the one
    /// definition of crate::verdict.
    pub summary: Summary,
}

/// The answers.
#[derive(Debug, Clone, Serialize, schemars::JsonSchema)]
pub struct DesignReport {
    /// Scene name.
    pub scene: String,
    /// "bistable" or "hydraulic".
    pub module: String,
    /// V_c, m/s.
    #[serde(rename = "speed_mps")]
    pub speed: f64,
    /// DT, s.
    #[serde(rename = "dead_time_s")]
    pub dead_time: f64,
    /// d_c, m/s^2 (with the robot's stopping table: its equivalent at V_c, plant/stopping.rs).
    #[serde(rename = "decel_mps2")]
    pub decel: f64,
    /// How the stopping distance after detection is computed: "v DT + v^2/2d", or from the
    /// robot's stopping table (`motion.stopping`; DT is then the delay to the stop signal).
    pub stopping_law: String,
    /// The stopping table's largest speed, m/s: no speed above it is answered (null without a table).
    pub stopping_table_max_speed_mps: Option<f64>,
    /// m_t, kg.
    #[serde(rename = "tool_mass_kg")]
    pub tool_mass: f64,
    /// d_sw, m.
    #[serde(rename = "switch_travel_m")]
    pub switch_travel: f64,
    /// C, m.
    #[serde(rename = "stroke_m")]
    pub stroke: f64,
    /// v DT + v^2/2d (firmware formula, micrometre resolution), m.
    #[serde(rename = "stopping_distance_m")]
    pub stopping_distance: f64,
    /// d_sw + stopping distance, m.
    #[serde(rename = "stroke_needed_formula_m")]
    pub stroke_needed_formula: f64,
    /// Smallest stroke at which the simulated flange does not reach the target, m.
    #[serde(rename = "stroke_needed_simulated_m")]
    pub stroke_needed_simulated: Option<f64>,
    /// Why the simulated stroke is missing, if it is.
    pub stroke_search_note: Option<String>,
    /// C - d_sw - stopping distance, m (the `flinch check` margin).
    #[serde(rename = "margin_formula_m")]
    pub margin_formula: f64,
    /// The design point simulated.
    pub design: Trial,
    /// Speed at which the budget is exactly used, m/s.
    #[serde(rename = "speed_limit_formula_mps")]
    pub speed_limit_formula: f64,
    /// Largest simulated speed with no stroke exhaustion, m/s.
    #[serde(rename = "speed_limit_simulated_mps")]
    pub speed_limit_simulated: Option<f64>,
    /// Why the simulated speed limit is missing, if it is.
    pub speed_search_note: Option<String>,
    /// The run at the simulated limit.
    pub at_limit: Option<Trial>,
    /// Adjustments made to candidates (duration, gap).
    pub notes: Vec<String>,
    /// The answer: the largest speed both the budget and the simulation call safe,
    /// min(speed_limit_formula, speed_limit_simulated), m/s; null when the simulated search failed.
    pub speed_limit_mps: Option<f64>,
    /// The verdict at the design point, the same as `flinch check`'s: the budget fits and the
    /// simulation is safe (crate::verdict).
    pub safe: bool,
    /// Why not, for people (empty when safe).
    pub failures: Vec<String>,
    /// Why the budget and the simulation disagree at the design point, for people.
    pub explanations: Vec<String>,
}

/// A module the design can scale.
#[derive(Debug, Clone, Copy)]
enum Module {
    Bistable { c1: f64, c2: f64 },
    Hydraulic { l: f64 },
}

impl Module {
    fn of(s: &Scene) -> Result<Self, String> {
        match &s.decoupler {
            Decoupler::Bistable(b) => Ok(Module::Bistable { c1: b.front_stroke, c2: b.back_stroke }),
            Decoupler::Hydraulic(h) => Ok(Module::Hydraulic { l: h.stroke }),
            _ => Err("decoupler.kind: flinch design needs a module with a stroke (\"bistable\" or \"hydraulic\")".into()),
        }
    }
    fn stroke(&self) -> f64 {
        match *self {
            Module::Bistable { c1, c2 } => c1 + c2,
            Module::Hydraulic { l } => l,
        }
    }
    fn keys(&self, c: f64) -> Vec<(&'static str, f64)> {
        match *self {
            Module::Bistable { c1, c2 } => {
                let k = c / (c1 + c2);
                vec![("decoupler.front_stroke", c1 * k), ("decoupler.back_stroke", c2 * k)]
            }
            Module::Hydraulic { .. } => vec![("decoupler.stroke", c)],
        }
    }
    fn name(&self) -> &'static str {
        match self {
            Module::Bistable { .. } => "bistable",
            Module::Hydraulic { .. } => "hydraulic",
        }
    }
}

/// The scene a candidate runs: the template with the module's stroke, the speed and the dead time
/// set, `duration` and `target.gap` adjusted (see the module docs), re-validated.
struct Candidates<'a> {
    t: &'a Template,
    module: Module,
    dead_time: f64,
    base: &'a Scene,
    /// Candidates run so far (a bar on a terminal; issue 27).
    progress: indicatif::ProgressBar,
}

impl Candidates<'_> {
    fn gap_for(&self, v: f64) -> f64 {
        let m = &self.base.motion;
        if m.start_at_speed { self.base.target.gap } else { self.base.target.gap.max(1.2 * v * v / (2.0 * m.accel)) }
    }
    fn duration_for(&self, v: f64) -> f64 {
        let m = &self.base.motion;
        let gap = self.gap_for(v);
        let t_contact = if m.start_at_speed { gap / v } else { v / (2.0 * m.accel) + gap / v };
        // Contact, up to 0.5 s to detect, the dead time, braking, and 0.3 s for the back-stop
        // impacts and the ring-down.
        let stop = m.stop_after_detection(v, self.dead_time).map_or(self.dead_time + v / m.decel, |(_, t)| t);
        self.base.duration_s.max(t_contact + 0.5 + stop + 0.3)
    }
    fn scene(&self, v: f64, c: f64) -> Result<Scene, SweepError> {
        let mut sets = self.module.keys(c);
        sets.extend([("motion.speed", v), ("motion.dead_time", self.dead_time), ("target.gap", self.gap_for(v)), ("duration", self.duration_for(v))]);
        self.t.with(&sets)
    }
    fn trial(&self, v: f64, c: f64) -> Result<Trial, String> {
        let s = self.scene(v, c).map_err(|e| e.to_string())?;
        trial_of(&s, v, c)
    }
    fn safe(&self, v: f64, c: f64) -> Option<bool> {
        let s = self.scene(v, c).ok()?;
        let r = flinch_sim::run_to_conclusion(&s).ok().map(|r| r.safe);
        self.progress.inc(1);
        r
    }
}

/// The validator's reason for the first candidate it refuses, as "; first refused: ...", for a
/// search that found no answer (empty when it refused none).
fn first_refusal(e: &str, cand: &Candidates, xs: &[f64], at: impl Fn(f64) -> (f64, f64)) -> String {
    if !e.contains("refuses every candidate") {
        return String::new();
    }
    xs.iter()
        .find_map(|&x| {
            let (v, c) = at(x);
            cand.scene(v, c).err()
        })
        .map_or_else(String::new, |r| {
            let r = r.to_string();
            // The validator's own words, without the candidate's raw numbers before them.
            let why = r.split_once("refuses it: ").map_or(r.as_str(), |(_, w)| w);
            format!("; the first candidate is refused because {why}")
        })
}

/// Runs a scene (its verdict is in the summary).
fn trial_of(s: &Scene, v: f64, c: f64) -> Result<Trial, String> {
    let summary = flinch_sim::run_to_conclusion(s).map_err(|e| format!("V_c = {}, C = {}: {e}", flinch_sim::verdict::mps(v), flinch_sim::verdict::mm(c)))?;
    Ok(Trial { speed: v, stroke: c, summary })
}

/// Speed that uses the budget exactly for the scene's motion: `v DT + v^2 / (2 d) = room`, or with
/// the robot's stopping table `v DT + D(v) = room` by bisection (D increases with v). With a table
/// the answer is capped at its largest speed (`true`: capped, the budget is not used up there).
pub fn speed_for_room(m: &flinch_model::scene::Motion, room: f64, dead_time: f64) -> (f64, bool) {
    let Some(t) = &m.stopping else {
        return (speed_for_budget(room, dead_time, m.decel), false);
    };
    let used = |v: f64| m.stop_after_detection(v, dead_time).map_or(f64::INFINITY, |(d, _)| d);
    if room <= 0.0 {
        return (0.0, false);
    }
    let top = t.max_speed();
    if used(top) <= room {
        return (top, true);
    }
    let (mut lo, mut hi) = (0.0, top);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if used(mid) <= room { lo = mid } else { hi = mid }
    }
    (lo, false)
}

/// Speed that uses the budget exactly: v DT + v^2 / (2 d) = room.
pub fn speed_for_budget(room: f64, dead_time: f64, decel: f64) -> f64 {
    if room <= 0.0 {
        return 0.0;
    }
    decel * (-dead_time + (dead_time * dead_time + 2.0 * room / decel).sqrt())
}

/// Why `flinch design` refuses its input before simulating anything (exit 2): a bad `--plot`
/// name, a scene that cannot be read, a module or sensor it cannot size, an option out of range,
/// a design point the scene validator refuses, a body-region question it cannot answer. `None`:
/// the input is good; whatever fails after that is a runtime failure (exit 3). Issue 26 item 7:
/// these exited 3.
pub fn refusal_of(a: &DesignArgs) -> Option<String> {
    if let Some(p) = &a.plot {
        if let Err(e) = flinch_output::figure::check_extension(p) {
            return Some(format!("--plot {e}"));
        }
    }
    let t = match Template::load_with(&a.scene, &a.set) {
        Ok(t) => t,
        Err(e) => return Some(e.to_string()),
    };
    let at = |e: String| format!("{}: {e}", a.scene.display());
    if let Some(which) = &a.body_region {
        if a.stroke.is_some() || a.speed.is_some() || a.plot.is_some() {
            return Some("--body-region: --stroke, --speed and --plot do not apply (the speed is what it searches)".into());
        }
        return crate::body_design::refusal(&t, which, a.dead_time, a.rigid_sensor).map(at);
    }
    refusal(&t, a.stroke, a.speed, a.dead_time).map(at)
}

/// The input checks of [`design`], before it simulates: see [`refusal_of`].
pub fn refusal(t: &Template, stroke: Option<f64>, speed: Option<f64>, dead_time: Option<f64>) -> Option<String> {
    let base = &t.base;
    let module = match Module::of(base) {
        Ok(m) => m,
        Err(e) => return Some(e),
    };
    if !matches!(base.sensor, Some(Sensor::Travel { .. })) {
        return Some("sensor.kind: flinch design needs a travel switch (sensor.kind = \"travel\")".into());
    }
    for (name, v) in [("--stroke", stroke), ("--speed", speed), ("--dead-time", dead_time)] {
        if let Some(v) = v {
            let ok = if name == "--dead-time" { v >= 0.0 && v.is_finite() } else { v > 0.0 && v.is_finite() };
            if !ok {
                return Some(format!("{name}: must be {} and finite, got {v}", if name == "--dead-time" { ">= 0" } else { "> 0" }));
            }
        }
    }
    let c = stroke.unwrap_or(module.stroke());
    let v = speed.unwrap_or(base.motion.speed);
    let dt = dead_time.unwrap_or(base.motion.dead_time);
    let cand = Candidates { t, module, dead_time: dt, base, progress: indicatif::ProgressBar::hidden() };
    cand.scene(v, c).err().map(|e| format!("the design point (--stroke, --speed, --dead-time) is refused by the scene validator: {e}"))
}

/// Candidates the stroke search scans (in parallel), and its bisection rounds (one at a time).
const STROKE_SCAN: usize = 16;
const STROKE_ROUNDS: usize = 14;
/// Candidates the speed search scans, and its bisection rounds.
const SPEED_SCAN: usize = 20;
const SPEED_ROUNDS: usize = 16;

/// What a design search will cost, estimated from the design point's run before it starts.
#[derive(Debug, Clone, Copy)]
pub struct Cost {
    /// Candidate runs at most (a candidate the validator refuses does not run).
    pub runs: usize,
    /// Rounds, the scans taking `threads` candidates at once.
    pub rounds: usize,
    /// The design point's run, s (on this machine, now).
    pub point_s: f64,
    /// Threads.
    pub threads: usize,
    /// About this long, s: the stroke search's rounds x the design point's run, plus the speed
    /// search's rounds x the design point's run scaled by the candidates' mean simulated duration.
    pub seconds: f64,
}

impl Cost {
    /// The cost of the searches with `threads` threads and a design point that took `point_s`.
    pub fn of(point_s: f64, threads: usize, speed_ratio: f64) -> Self {
        let t = threads.max(1);
        let (stroke, speed) = (STROKE_SCAN.div_ceil(t) + STROKE_ROUNDS, SPEED_SCAN.div_ceil(t) + SPEED_ROUNDS);
        let seconds = point_s * (stroke as f64 + speed as f64 * speed_ratio.max(0.0));
        Cost { runs: STROKE_SCAN + STROKE_ROUNDS + SPEED_SCAN + SPEED_ROUNDS, rounds: stroke + speed, point_s, threads: t, seconds }
    }

    /// The note said before a long search.
    pub fn text(&self) -> String {
        format!(
            "design: up to {} candidate runs ({STROKE_SCAN} + {SPEED_SCAN} scanned {} at a time, {STROKE_ROUNDS} + {SPEED_ROUNDS} bisection steps one at a time); the design point's run took {:.2} s; scaled by each candidate's simulated duration, about {:.0} s",
            self.runs, self.threads, self.point_s, self.seconds
        )
    }

    /// A bar over the candidate runs, drawn on a terminal only.
    fn bar(&self) -> indicatif::ProgressBar {
        use std::io::IsTerminal;
        if !std::io::stderr().is_terminal() || self.seconds <= 3.0 {
            return indicatif::ProgressBar::hidden();
        }
        let b = indicatif::ProgressBar::new(self.runs as u64);
        if let Ok(style) = indicatif::ProgressStyle::with_template("{elapsed_precise} {msg}: {pos}/{len} candidate runs (at most), eta {eta}") {
            b.set_style(style);
        }
        b
    }
}

/// Answers the design questions for a scene with optional overrides.
pub fn design(t: &Template, stroke: Option<f64>, speed: Option<f64>, dead_time: Option<f64>) -> Result<DesignReport, String> {
    let base = &t.base;
    let module = Module::of(base)?;
    let Some(Sensor::Travel { threshold: d_sw }) = base.sensor else {
        return Err("sensor.kind: flinch design needs a travel switch (sensor.kind = \"travel\")".into());
    };
    for (name, v) in [("--stroke", stroke), ("--speed", speed), ("--dead-time", dead_time)] {
        if let Some(v) = v {
            let ok = if name == "--dead-time" { v >= 0.0 && v.is_finite() } else { v > 0.0 && v.is_finite() };
            if !ok {
                return Err(format!("{name}: must be {} and finite, got {v}", if name == "--dead-time" { ">= 0" } else { "> 0" }));
            }
        }
    }
    let c = stroke.unwrap_or(module.stroke());
    let v = speed.unwrap_or(base.motion.speed);
    let dt = dead_time.unwrap_or(base.motion.dead_time);
    let decel = base.motion.decel;
    let mut cand = Candidates { t, module, dead_time: dt, base, progress: indicatif::ProgressBar::hidden() };
    // The design point, validated, and the budget of `flinch check` on it.
    let design_scene = cand.scene(v, c).map_err(|e| e.to_string())?;
    let t0 = std::time::Instant::now();
    let budget = check::check(&design_scene)?;
    // The cost, known before the search (issue 27: a 92.5 s search was silent): the design point's
    // run times the rounds of the searches below; said when over 3 s, with a bar on a terminal.
    // A candidate's run is taken to cost in proportion to its simulated duration (slow speeds
    // take longer to reach the target); the speed candidates are those of the scan below.
    let (v_f, _) = speed_for_room(&base.motion, c - d_sw, dt);
    let top = base.motion.stopping.map_or(f64::INFINITY, |s| s.max_speed());
    let d0 = cand.duration_for(v).max(1e-9);
    let speed_ratio = if v_f > 0.0 { (0..SPEED_SCAN).map(|i| cand.duration_for((v_f * (0.1 + 2.9 * i as f64 / 19.0)).min(top)) / d0).sum::<f64>() / SPEED_SCAN as f64 } else { 1.0 };
    let cost = Cost::of(t0.elapsed().as_secs_f64(), rayon::current_num_threads(), speed_ratio);
    if cost.seconds > 3.0 {
        flinch_output::output::note(&cost.text());
    }
    cand.progress = cost.bar();
    let design = Trial { speed: v, stroke: c, summary: budget.simulated.clone() };
    let needed = d_sw + budget.stopping_distance;
    let mut notes = Vec::new();
    if cand.gap_for(v) > base.target.gap {
        notes.push(format!("target.gap raised from {:.1} mm to {:.1} mm so the flange reaches V_c before contact", base.target.gap * 1e3, cand.gap_for(v) * 1e3));
    }
    if cand.duration_for(v) > base.duration_s {
        notes.push(format!("duration lengthened from {} s to {:.2} s to cover detection, the dead time and braking", base.duration_s, cand.duration_for(v)));
    }
    // Smallest stroke, simulated: scan 0.4..2.5 x the formula's, then bisect.
    let strokes: Vec<f64> = (0..STROKE_SCAN).map(|i| needed * (0.4 + 2.1 * i as f64 / 15.0)).collect();
    let unsafe_at = |cc: f64| cand.safe(v, cc).map(|s| !s);
    cand.progress.set_message("stroke search");
    let (stroke_sim, stroke_note) = match boundary(&strokes, &unsafe_at, true, STROKE_ROUNDS, flinch_sim::verdict::mm) {
        Ok((_, first_safe)) => (Some(first_safe), None),
        Err(e) => (None, Some(format!("stroke search over {:.2}..{:.2} mm ({} C1:C2 scaled together): {e}{}", strokes[0] * 1e3, strokes[15] * 1e3, module.name(), first_refusal(&e, &cand, &strokes, |x| (v, x))))),
    };
    // Largest safe speed for this stroke, simulated: scan 0.1..3 x the formula's, then bisect.
    let (v_formula, formula_capped) = speed_for_room(&base.motion, c - d_sw, dt);
    let table_top = base.motion.stopping.map(|s| s.max_speed());
    if formula_capped {
        notes.push(format!("the budget still fits at the stopping table's largest speed {}: the formula limit is that speed (the table is not extrapolated)", flinch_sim::verdict::mps(v_formula)));
    }
    cand.progress.set_message("speed search");
    let speeds: Vec<f64> = (0..SPEED_SCAN).map(|i| (v_formula * (0.1 + 2.9 * i as f64 / 19.0)).min(table_top.unwrap_or(f64::INFINITY))).collect();
    let safe_at = |vv: f64| cand.safe(vv, c);
    let (speed_sim, speed_note, at_limit) = if v_formula <= 0.0 {
        (None, Some("the switch travel takes the whole stroke: no speed is safe".to_string()), None)
    } else {
        match boundary(&speeds, &safe_at, true, SPEED_ROUNDS, flinch_sim::verdict::mps) {
            Ok((vmax, _)) => (Some(vmax), None, cand.trial(vmax, c).ok()),
            // Safe up to the end of the robot's stopping table: the answer stops there.
            Err(_) if table_top.is_some_and(|top| safe_at(top) == Some(true)) => {
                let top = table_top.unwrap_or(0.0);
                notes.push(format!("simulated safe up to the stopping table's largest speed {}: faster is not in the robot's data", flinch_sim::verdict::mps(top)));
                (Some(top), None, cand.trial(top, c).ok())
            }
            // Safe at every candidate the validator accepts (no boundary above the formula's
            // limit, up to 3x it): the simulation confirms the budget's limit, which is the answer.
            Err(e) if e.starts_with("no boundary") => match speeds.iter().rev().copied().find(|&x| safe_at(x) == Some(true)) {
                Some(top) => {
                    notes.push(format!("simulated safe at every candidate speed up to {}: the budget's limit stands", flinch_sim::verdict::mps(top)));
                    (Some(top), None, cand.trial(top, c).ok())
                }
                None => (None, Some(format!("speed search over {:.3}..{:.3} m/s: {e}", speeds[0], speeds[19])), None),
            },
            Err(e) => (None, Some(format!("speed search over {:.3}..{:.3} m/s: {e}{}", speeds[0], speeds[19], first_refusal(&e, &cand, &speeds, |x| (x, c)))), None),
        }
    };
    cand.progress.finish_and_clear();
    Ok(DesignReport {
        scene: base.name.clone(),
        module: module.name().into(),
        speed: v,
        dead_time: dt,
        decel,
        stopping_law: check::stopping_law(&base.motion),
        stopping_table_max_speed_mps: table_top,
        tool_mass: base.tool.mass,
        switch_travel: d_sw,
        stroke: c,
        stopping_distance: budget.stopping_distance,
        stroke_needed_formula: needed,
        stroke_needed_simulated: stroke_sim,
        stroke_search_note: stroke_note,
        margin_formula: budget.margin,
        design,
        speed_limit_formula: v_formula,
        speed_limit_simulated: speed_sim,
        speed_search_note: speed_note,
        at_limit,
        notes,
        speed_limit_mps: speed_sim.map(|s| s.min(v_formula)),
        safe: budget.safe,
        failures: budget.failures,
        explanations: budget.explanations,
    })
}

fn mode_text(m: Option<u8>) -> &'static str {
    match m {
        Some(1) => "1 (the tool never reaches the back end-stop)",
        Some(2) => "2 (back end-stop reached after the robot stopped)",
        Some(3) => "3 (back end-stop reached while the robot still moves)",
        _ => "- (no back end-stop)",
    }
}

/// The human answer.
pub fn human(r: &DesignReport) -> String {
    use flinch_sim::verdict::{mm, mm_signed, mps, ms};
    use std::fmt::Write;
    let mut o = String::new();
    // The design point as simulated (after --speed, --stroke, --dead-time and --set).
    let s = &r.design.summary;
    o.push_str(&check::headline_lines(&r.scene, &s.simulated, &s.name_mismatches));
    match r.stopping_table_max_speed_mps {
        None => {
            let _ = writeln!(o, "  robot: V_c = {}, DT = {}, d_c = {} m/s^2; switch travel d_sw = {}", mps(r.speed), ms(r.dead_time), r.decel, mm(r.switch_travel));
        }
        Some(top) => {
            let _ = writeln!(o, "  robot: V_c = {}, its stopping table up to {} (equivalent d = {:.3} m/s^2 at V_c), delay to the stop signal DT = {}; switch travel d_sw = {}", mps(r.speed), mps(top), r.decel, ms(r.dead_time), mm(r.switch_travel));
        }
    }
    let _ = writeln!(o, "  stopping distance after detection {} = {}", r.stopping_law, mm(r.stopping_distance));
    let _ = writeln!(o, "stroke needed");
    let _ = writeln!(o, "  formula d_sw + {} = {}", r.stopping_law, mm(r.stroke_needed_formula));
    match (r.stroke_needed_simulated, &r.stroke_search_note) {
        (Some(s), _) => {
            let _ = writeln!(o, "  simulated: smallest stroke that the tool does not exhaust while touching the target = {} ({} vs the formula)", mm(s), mm_signed(s - r.stroke_needed_formula));
        }
        (None, Some(n)) => {
            let _ = writeln!(o, "  simulated: not found ({n}); the formula stands, with the simulated stroke left below");
        }
        _ => {}
    }
    let _ = writeln!(o, "this module, C = {}", mm(r.stroke));
    let _ = writeln!(o, "  budget margin C - d_sw - stopping distance = {}: {}", mm_signed(r.margin_formula), if r.margin_formula >= 0.0 { "FITS" } else { "DOES NOT FIT" });
    let d = &r.design.summary;
    let _ = writeln!(o, "  simulated at V_c = {}: max travel {}, working mode {}; peak force on the robot {:.1} N, peak contact force {:.1} N", mps(r.speed), mm(d.max_travel), mode_text(d.mode), d.peak_robot_force, d.peak_contact_force);
    let _ = writeln!(o, "  simulation {}", flinch_sim::verdict::line(d));
    for e in &r.explanations {
        let _ = writeln!(o, "  why: {e}");
    }
    let robot = match r.stopping_table_max_speed_mps {
        None => format!("a {} controller", ms(r.dead_time)),
        Some(_) => format!("this robot's stopping table and {} to the stop signal", ms(r.dead_time)),
    };
    let _ = writeln!(o, "largest safe speed with this stroke and {robot} (safe: docs/verdicts.md)");
    let _ = writeln!(o, "  formula ({} = C - d_sw): {}", r.stopping_law, mps(r.speed_limit_formula));
    match (r.speed_limit_simulated, &r.at_limit, &r.speed_search_note) {
        (Some(v), Some(t), _) => {
            let _ = writeln!(o, "  simulated: {} ({:+.1} % vs the formula); there: working mode {}, peak force on the robot {:.1} N, {}", mps(v), (v / r.speed_limit_formula - 1.0) * 100.0, mode_text(t.summary.mode), t.summary.peak_robot_force, flinch_sim::verdict::line(&t.summary));
        }
        (_, _, Some(n)) => {
            let _ = writeln!(o, "  simulated: not found ({n})");
        }
        _ => {}
    }
    match r.speed_limit_mps {
        Some(v) => {
            let _ = writeln!(o, "  => with this module and {robot} the robot may go up to {} (the smaller of the two)", mps(v));
        }
        None => {
            let _ = writeln!(o, "  => no safe speed could be confirmed by simulation: do not rely on the formula alone");
        }
    }
    for n in &r.notes {
        let _ = writeln!(o, "  note: {n}");
    }
    if r.safe {
        let _ = writeln!(o, "DESIGN: SAFE at V_c = {} (the budget fits and the simulated stroke holds)", mps(r.speed));
    } else {
        let _ = writeln!(o, "DESIGN: NOT SAFE at V_c = {}: {}", mps(r.speed), r.failures.join("; "));
    }
    o
}

/// Peak forces and the simulated stroke margin against speed, limits marked.
pub fn draw(path: &Path, t: &Template, r: &DesignReport) -> Result<(), String> {
    let module = Module::of(&t.base)?;
    let cand = Candidates { t, module, dead_time: r.dead_time, base: &t.base, progress: indicatif::ProgressBar::hidden() };
    let top = r.speed_limit_simulated.unwrap_or(r.speed_limit_formula).max(r.speed).max(1e-3) * 1.5;
    let speeds: Vec<f64> = (1..=30).map(|i| top * i as f64 / 30.0).collect();
    let trials: Vec<Option<Trial>> = speeds.par_iter().map(|&v| cand.trial(v, r.stroke).ok()).collect();
    let pts = |f: &dyn Fn(&Trial) -> f64| speeds.iter().zip(&trials).map(|(&v, t)| (v, t.as_ref().map_or(f64::NAN, f))).collect::<Vec<_>>();
    let mut marks = vec![(r.speed_limit_formula, format!("formula limit {:.3} m/s", r.speed_limit_formula))];
    if let Some(v) = r.speed_limit_simulated {
        marks.push((v, format!("simulated safe limit {v:.3} m/s")));
    }
    let exhausted: Vec<(f64, f64)> = speeds.iter().zip(&trials).filter_map(|(&v, t)| t.as_ref().filter(|t| !t.summary.safe).map(|t| (v, t.summary.peak_robot_force))).collect();
    let mut force = vec![
        Series { name: "peak force on the robot".into(), points: pts(&|t| t.summary.peak_robot_force), color: PALETTE[0], style: Style::Line },
        Series { name: "peak contact force".into(), points: pts(&|t| t.summary.peak_contact_force), color: PALETTE[1], style: Style::Line },
    ];
    if !exhausted.is_empty() {
        force.push(Series { name: "not safe (stroke exhausted)".into(), points: exhausted, color: splot::PALETTE[3], style: Style::Points });
    }
    let m = &t.base.motion;
    let budget: Vec<(f64, f64)> = speeds.iter().map(|&v| (v, m.stop_after_detection(v, r.dead_time).map_or(f64::NAN, |(d, _)| (r.stroke - r.switch_travel - d) * 1e3))).collect();
    let panels = vec![
        Panel { caption: "peak forces".into(), y_label: "force [N]".into(), series: force, marks: marks.clone(), y_log: false },
        Panel {
            caption: format!("stroke margin, C = {:.1} mm (stroke left > 0: safe)", r.stroke * 1e3),
            y_label: "margin [mm]".into(),
            series: vec![
                Series { name: "simulated: stroke left while touching the target (< 0: exhausted, not safe)".into(), points: pts(&|t| t.summary.stroke_left_min_m.map_or(f64::NAN, |m| m * 1e3)), color: PALETTE[2], style: Style::Line },
                Series { name: "simulated: closest approach to the undeformed target (counts its deformation)".into(), points: pts(&|t| t.summary.closest_approach_m.map_or(f64::NAN, |m| m * 1e3)), color: PALETTE[3], style: Style::Dashed },
                Series { name: format!("formula: C - d_sw - ({})", r.stopping_law), points: budget, color: PALETTE[5], style: Style::Dashed },
            ],
            marks: marks.clone(),
            y_log: false,
        },
        Panel { caption: "working mode (Fig. 46)".into(), y_label: "mode".into(), series: vec![Series { name: "mode".into(), points: pts(&|t| t.summary.mode.map_or(f64::NAN, f64::from)), color: PALETTE[4], style: Style::Line }], marks, y_log: false },
    ];
    splot::lines(path, &format!("{}: DT = {} ms, C = {:.1} mm", r.scene, r.dead_time * 1e3, r.stroke * 1e3), &XAxis { label: "V_c [m/s]".into(), log: false }, &panels)
}

/// Runs `flinch design`.
pub fn run(a: &DesignArgs) -> Result<bool, String> {
    if let Some(which) = &a.body_region {
        if a.stroke.is_some() || a.speed.is_some() || a.plot.is_some() {
            return Err("--body-region: --stroke, --speed and --plot do not apply (the speed is what it searches)".into());
        }
        return crate::body_design::run(&a.scene, &a.set, which, a.dead_time, a.rigid_sensor, a.json);
    }
    let t = Template::load_with(&a.scene, &a.set).map_err(|e| e.to_string())?;
    let r = design(&t, a.stroke, a.speed, a.dead_time).map_err(|e| format!("{}: {e}", a.scene.display()))?;
    // Through output::print: a scene's name cannot carry terminal controls to the screen.
    let text = if a.json { flinch_output::to_json(&flinch_output::Versioned::new(&r)) } else { human(&r) };
    flinch_output::output::print(&text).map_err(flinch_output::output::message_or_end_on_closed_pipe)?;
    if let Some(p) = &a.plot {
        draw(p, &t, &r)?;
        flinch_output::output::note(&format!("wrote {} (plot)", p.display()));
    }
    Ok(r.safe)
}
