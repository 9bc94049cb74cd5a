//! The human summary of `flinch run` and `flinch hil`, and their `--json` documents (versioned;
//! schemas in docs/schema/run.json, hil.json).

use crate::measured::Comparison;
use flinch_hil::HilReport;
use flinch_output::json::{to_json, SCHEMA_VERSION};
use flinch_sim::Summary;
use schemars::JsonSchema;
use serde::Serialize;
use std::fmt::Write;

fn ms(t: Option<f64>) -> String {
    t.map_or("-".into(), |t| format!("{:.1} ms", t * 1e3))
}

/// The short human summary printed by `flinch run`.
pub fn human(s: &Summary) -> String {
    let mut o = String::new();
    let _ = writeln!(o, "{}", s.scene);
    let _ = writeln!(o, "  simulated: {}", s.simulated);
    for m in &s.name_mismatches {
        let _ = writeln!(o, "  NAME MISMATCH: {m}");
    }
    for m in &s.not_as_commanded {
        let _ = writeln!(o, "  NOT AS COMMANDED: {m}");
    }
    let _ = writeln!(o, "  contact {}   detect {}   brake {}   flange stops {}", ms(s.t_contact), ms(s.t_detect), ms(s.t_brake), ms(s.t_stop));
    let _ = writeln!(o, "  detection delay {}   reaction time {}", ms(s.detection_delay), ms(s.reaction_time));
    let _ = writeln!(o, "  peak contact force {:.2} N   peak force on robot {:.2} N   contacts {}", s.peak_contact_force, s.peak_robot_force, s.contacts);
    if let (Some(f), Some(t), Some(tc)) = (s.first_impact_peak_robot_force_n, s.first_impact_peak_robot_force_t_s, s.t_contact) {
        let what = match s.peak_robot_force_event.as_str() {
            "first_impact" => "the first impact",
            "later_contact" => "a later contact",
            "front_stop" => "the front end-stop",
            "back_stop" => "the back end-stop",
            "decoupler" => "the decoupler's spring or friction",
            _ => "nothing",
        };
        let _ = writeln!(o, "  force on robot: first impact {f:.2} N at contact {:+.1} ms; whole run {:.2} N at contact {:+.1} ms, from {what}", (t - tc) * 1e3, s.peak_robot_force, (s.peak_robot_force_t_s - tc) * 1e3);
    }
    if let Some(v) = s.object_final_velocity {
        let _ = writeln!(o, "  object final velocity {:.3} m/s (peak {:.3} m/s)", v, s.object_peak_velocity.unwrap_or(v));
    }
    let mode = match s.mode {
        Some(1) => "1 (tool never reaches the back end-stop)",
        Some(2) => "2 (back end-stop reached after the robot stopped)",
        Some(3) => "3 (back end-stop reached before the robot stopped)",
        _ => "- (no back end-stop)",
    };
    let _ = writeln!(o, "  working mode {mode}   max travel {:.2} mm   stroke exhausted: {}", s.max_travel * 1e3, if s.stroke_exhausted { "YES" } else { "no" });
    let _ = writeln!(o, "  {}", flinch_sim::verdict::line(s));
    if let Some(b) = flinch_sim::verdict::body_line(s) {
        let _ = writeln!(o, "  {b}");
    }
    if let Some(e) = s.achieved_restitution {
        let _ = writeln!(o, "  first contact: approach {:.4} m/s, achieved restitution {:.3}", s.approach_speed_mps.unwrap_or(0.0), e);
    }
    if let Some(p) = s.peak_gas_pressure {
        let _ = writeln!(o, "  peak gas pressure {:.2} kPa", p * 1e-3);
    }
    let _ = writeln!(o, "  solver {}: {} steps ({} rejected), {} RHS evaluations, {} events", s.method, s.steps, s.rejected_steps, s.rhs_evals, s.events);
    if let Some(t) = s.at_rest_from_s {
        let _ = writeln!(o, "  at rest from t = {t:.3} s (robot stopped, every body settled): the state is held from there to the end");
    }
    for w in &s.warnings {
        let _ = writeln!(o, "  note: {w}");
    }
    o
}

/// The comparison with a measured file, for people.
pub fn human_measured(file: &str, c: &[Comparison]) -> String {
    let mut o = String::new();
    let _ = writeln!(o, "  measured ({file}):");
    for m in c {
        let (k, u) = match m.unit.as_str() {
            "m" => (1e3, "mm"),
            u => (1.0, u),
        };
        let _ = writeln!(
            o,
            "    {}: RMS error {:.3} {u}; peak {:.3} simulated vs {:.3} measured ({:+.3} {u}, {:+.1} %); time shift {:+.1} ms (RMS {:.3} {u} after it)",
            m.column, m.rms_error * k, m.peak_simulated * k, m.peak_measured * k, m.peak_error * k,
            if m.peak_measured != 0.0 { m.peak_error / m.peak_measured.abs() * 100.0 } else { f64::NAN },
            m.time_shift_s * 1e3, m.rms_error_shifted * k
        );
    }
    o
}

/// `flinch run --json`: the summary object of the scene contract (docs/SCENES.md), with its
/// schema version and, with `--measured`, the comparison.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct RunJson<'a> {
    /// Version of this document's schema (docs/schema/run.json).
    pub schema_version: u32,
    /// The summary (its field names are the scene contract's).
    #[serde(flatten)]
    pub summary: &'a Summary,
    /// With `--measured FILE.csv`: every measured column against the run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub measured: Option<&'a [Comparison]>,
}

/// `flinch hil --json`.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct HilJson<'a> {
    /// Version of this document's schema (docs/schema/hil.json).
    pub schema_version: u32,
    /// The run's summary and the firmware's figures.
    #[serde(flatten)]
    pub report: &'a HilReport,
}

/// The `--json` summary, one object.
pub fn json(s: &Summary) -> String {
    to_json(&RunJson { schema_version: SCHEMA_VERSION, summary: s, measured: None })
}
