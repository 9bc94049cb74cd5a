//! `flinch check`: does the decoupler's stroke absorb the robot's stopping distance?
//!
//! After detection the flange keeps closing on the obstacle for `v DT + v^2 / (2 d)` (the
//! firmware's own formula, `flinch_firmware::stopping_distance_um`, so the MCU and this check agree
//! to the micrometre), while the stroke left is `C - d_sw`. The simulation then confirms it: the
//! largest travel it reaches and whether the flange reached the target.

use flinch_model::scene::{Decoupler, Scene, Sensor};
use flinch_sim::{self as sim, Summary};
use flinch_sim::verdict;
use flinch_firmware::stopping_distance_um;
use serde::Serialize;

pub use flinch_hil::units::{um_down, um_up};


/// Stopping distance after detection, m, rounded up to the micrometre: the firmware's formula
/// `v DT + v^2 / (2 d)`, or with the robot's stopping table `v DT + D(v)`, D read from the table
/// itself (DT then being the delay to the stop signal; model/src/stopping.rs).
pub fn stopping_distance(m: &flinch_model::scene::Motion) -> Result<f64, String> {
    match &m.stopping {
        None => Ok(stopping_distance_um(um_up(m.speed), um_up(m.dead_time), um_down(m.decel).max(1)) as f64 * 1e-6),
        Some(t) => {
            let d = t.distance(m.speed).ok_or_else(|| format!("motion.speed: {} m/s is above the stopping table's largest speed {} m/s (not extrapolated)", m.speed, t.max_speed()))?;
            Ok(um_up(m.speed * m.dead_time + d) as f64 * 1e-6)
        }
    }
}

/// How the stopping distance after detection was computed, for people.
pub fn stopping_law(m: &flinch_model::scene::Motion) -> String {
    match &m.stopping {
        None => "v DT + v^2/2d".into(),
        Some(t) if m.dead_time > 0.0 => format!("v DT + D(v), D from the robot's category-{} stopping table", t.category),
        Some(t) => format!("D(v) from the robot's category-{} stopping table", t.category),
    }
}

/// The budget and its confirmation.
#[derive(Debug, Clone, Serialize, schemars::JsonSchema)]
pub struct BudgetCheck {
    /// Stopping distance after detection, m (firmware formula, or v DT + D(v) from the robot's
    /// stopping table; rounded up to the micrometre).
    #[serde(rename = "stopping_distance_m")]
    pub stopping_distance: f64,
    /// How it was computed, for people ("v DT + v^2/2d" or the stopping table).
    pub stopping_law: String,
    /// Total stroke C (front stop to back stop), m.
    #[serde(rename = "stroke_m")]
    pub stroke: f64,
    /// Switch travel d_sw, m.
    #[serde(rename = "switch_travel_m")]
    pub switch_travel: f64,
    /// Stroke left at detection, C - d_sw, m.
    #[serde(rename = "remaining_m")]
    pub remaining: f64,
    /// remaining - stopping_distance, m (negative: does not fit).
    #[serde(rename = "margin_m")]
    pub margin: f64,
    /// The budget holds.
    pub fits: bool,
    /// The simulation of the same scene (its `safe` and `failures`: crate::verdict).
    pub simulated: Summary,
    /// The verdict of `check`: the budget fits and the simulation is safe (docs/verdicts.md).
    pub safe: bool,
    /// Why not, for people: the budget's failure and the simulation's (empty when safe).
    pub failures: Vec<String>,
    /// Why the budget and the simulation disagree, for people (crate::verdict::explain).
    pub explanations: Vec<String>,
    /// The board's output faults against the budget (issue 25; flinch_hil::output_fault_budget):
    /// shown, not part of `safe`. Only both relays welded (two faults) add dead time.
    pub output_faults: Vec<flinch_hil::OutputFaultBudget>,
}

/// Checks a scene with a travel switch on a bi-stable or hydraulic decoupler.
pub fn check(scene: &Scene) -> Result<BudgetCheck, String> {
    let stroke = match &scene.decoupler {
        Decoupler::Bistable(b) => b.front_stroke + b.back_stroke,
        Decoupler::Hydraulic(h) => h.stroke,
        _ => return Err("decoupler.kind: flinch check needs a decoupler with a stroke (\"bistable\" or \"hydraulic\")".into()),
    };
    let Some(Sensor::Travel { threshold }) = scene.sensor else {
        return Err("sensor.kind: flinch check needs a travel switch (sensor.kind = \"travel\")".into());
    };
    let m = &scene.motion;
    let stop = stopping_distance(m)?;
    let remaining = stroke - threshold;
    let (simulated, _) = sim::run(scene, false).map_err(|e| e.to_string())?;
    let fits = stop <= remaining;
    let budget = verdict::Budget { stroke, switch_travel: threshold, stopping_distance: stop };
    let explanations = verdict::explain(scene, &budget, &simulated);
    let mut failures = Vec::new();
    if !fits {
        failures.push(format!("stroke budget: the stopping distance after detection {} exceeds the stroke left at detection {} (escalate to a category-0 stop)", verdict::mm(stop), verdict::mm(remaining)));
    }
    failures.extend(simulated.failures.iter().map(|f| format!("simulation: {f}")));
    let output_faults = flinch_hil::output_fault_budget(scene, stop, remaining);
    Ok(BudgetCheck { stopping_distance: stop, stopping_law: stopping_law(m), stroke, switch_travel: threshold, remaining, margin: remaining - stop, fits, safe: failures.is_empty(), failures, explanations, simulated, output_faults })
}

/// The name, what was simulated and each claim of the name it contradicts, as every scene
/// command starts (`flinch_model::headline`).
pub fn headline_lines(name: &str, simulated: &str, mismatches: &[String]) -> String {
    let mut t = format!("{name}\n  simulated: {simulated}\n");
    for m in mismatches {
        t.push_str(&format!("  NAME MISMATCH: {m}\n"));
    }
    t
}

/// The human text of `flinch check`.
pub fn human(c: &BudgetCheck) -> String {
    use flinch_sim::verdict::{mm, mm_signed};
    let s = &c.simulated;
    let mut t = headline_lines(&s.scene, &s.simulated, &s.name_mismatches);
    t.push_str(&format!("  stopping distance after detection {} = {}\n", c.stopping_law, mm(c.stopping_distance)));
    t.push_str(&format!("  stroke C = {}, switch travel {}, left at detection {}\n", mm(c.stroke), mm(c.switch_travel), mm(c.remaining)));
    t.push_str(&format!("  budget: {} (margin {})\n", if c.fits { "FITS" } else { "DOES NOT FIT: escalate to a category-0 stop" }, mm_signed(c.margin)));
    t.push_str(&format!("  simulation: max travel {}, flange reached the target: {}\n", mm(s.max_travel), if s.stroke_exhausted { "YES" } else { "no" }));
    t.push_str(&format!("  simulation {}\n", verdict::line(s)));
    for e in &c.explanations {
        t.push_str(&format!("  why: {e}\n"));
    }
    t.push_str(&output_faults_line(&c.output_faults));
    if c.safe {
        t.push_str("  CHECK: SAFE (the budget fits and the simulated stroke holds)\n");
    } else {
        t.push_str(&format!("  CHECK: NOT SAFE: {}\n", c.failures.join("; ")));
    }
    t
}

/// One line for the board's output faults: the ones that stop as healthy outputs do, and each one
/// that adds dead time with its stop and whether it fits.
fn output_faults_line(faults: &[flinch_hil::OutputFaultBudget]) -> String {
    use flinch_sim::verdict::mm;
    if faults.is_empty() {
        return String::new();
    }
    let same = faults.iter().filter(|f| f.extra_dead_time_s == 0.0).count();
    let mut t = format!("  output faults of the board: {same} of {} add no dead time (another channel opens the stop circuit)", faults.len());
    for f in faults.iter().filter(|f| f.extra_dead_time_s > 0.0) {
        t.push_str(&format!(
            "; {}: +{:.3} ms, category 0 only, stopping distance {}: {}",
            f.fault,
            f.extra_dead_time_s * 1e3,
            mm(f.stopping_distance_m),
            if f.fits { "fits" } else { "DOES NOT FIT (shown, not in the verdict: two welded relays are two faults)" }
        ));
    }
    t.push('\n');
    t
}
