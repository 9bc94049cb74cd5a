//! The metrics a sweep reports and plots: every numeric summary field by name, in the summary's
//! order ([`summary_fields`], [`METRICS`]).

use flinch_sim::Summary;
use serde::de::{Deserialize, Deserializer, MapAccess, Visitor};
use serde_json::Value as Json;
use std::fmt;
use super::{error::*, template::*};

/// A JSON object's entries in their serialised order (serde_json's map sorts without the
/// `preserve_order` feature; this keeps the declaration order of `Summary`).
pub(crate) struct Ordered(Vec<(String, Json)>);

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
    "approach_speed_mps", "contacts", "object_peak_velocity", "max_travel", "decoupler_impulse", "peak_gas_pressure",
    "rejected_steps", "events", "peak_robot_force_t_s", "first_impact_peak_robot_force_n", "first_impact_peak_robot_force_t_s",
    "stroke_left_min_m", "target_deformation_max_m", "closest_approach_m", "concluded", "t_end_s", "flange_reach_after_end_m", "safe", "as_commanded", "body_limits_pass",
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
