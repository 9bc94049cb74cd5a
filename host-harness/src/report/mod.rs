//! What a run produced, for people and for scripts: the human summary, the `--json` object
//! (SCENES.md), the CSV time history and the plots.

pub mod csv;
pub mod plot;

use crate::sim::Summary;
use std::fmt::Write;

fn ms(t: Option<f64>) -> String {
    t.map_or("-".into(), |t| format!("{:.1} ms", t * 1e3))
}

/// The short human summary printed by `flinch run`.
pub fn human(s: &Summary) -> String {
    let mut o = String::new();
    let _ = writeln!(o, "{}", s.scene);
    let _ = writeln!(o, "  contact {}   detect {}   brake {}   flange stops {}", ms(s.t_contact), ms(s.t_detect), ms(s.t_brake), ms(s.t_stop));
    let _ = writeln!(o, "  detection delay {}   reaction time {}", ms(s.detection_delay), ms(s.reaction_time));
    let _ = writeln!(o, "  peak contact force {:.2} N   peak force on robot {:.2} N   contacts {}", s.peak_contact_force, s.peak_robot_force, s.contacts);
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
    if let Some(e) = s.achieved_restitution {
        let _ = writeln!(o, "  first contact: approach {:.4} m/s, achieved restitution {:.3}", s.approach_velocity.unwrap_or(0.0), e);
    }
    if let Some(p) = s.peak_gas_pressure {
        let _ = writeln!(o, "  peak gas pressure {:.0} Pa", p);
    }
    let _ = writeln!(o, "  solver {}: {} steps ({} rejected), {} RHS evaluations, {} events", s.method, s.steps, s.rejected_steps, s.rhs_evals, s.events);
    for w in &s.warnings {
        let _ = writeln!(o, "  note: {w}");
    }
    o
}

/// The `--json` summary, one object.
pub fn json(s: &Summary) -> String {
    serde_json::to_string_pretty(s).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
}
