//! JSON Schemas of the documents Flinch writes (`docs/schema/*.json`), generated from the types
//! that serialise them (`schemars`), with every numeric field's unit stated in a `unit` keyword.
//! A unit comes from the name: the convention's suffix (`_s`, `_m`, `_mps`, `_n`, ...;
//! docs/conventions.md), or, for the scene contract's older names (`t_contact`,
//! `peak_contact_force`, ...), the table below. A numeric field with neither fails the test that
//! keeps docs/schema/ current, so no field ships without its unit.

use super::{HilJson, RunJson};
use schemars::{schema_for, Schema};
use serde_json::{Map, Value};

/// Units by suffix (docs/conventions.md).
pub const SUFFIXES: &[(&str, &str)] = &[
    ("_n_per_m", "N/m"), ("_ns_per_m", "N s/m"), ("_mps2", "m/s^2"), ("_mps", "m/s"), ("_pa", "Pa"), ("_kg", "kg"), ("_hz", "Hz"), ("_bps", "bit/s"),
    ("_m2", "m^2"), ("_px", "px"), ("_rad", "rad"), ("_j", "J"), ("_n_s", "N s"), ("_s", "s"), ("_m", "m"), ("_n", "N"),
];

/// Units of the scene contract's summary names and of the dimensionless fields ("1").
pub const NAMED: &[(&str, &str)] = &[
    ("t_contact", "s"), ("t_detect", "s"), ("t_brake", "s"), ("t_stop", "s"), ("detection_delay", "s"), ("reaction_time", "s"),
    ("peak_contact_force", "N"), ("peak_robot_force", "N"), ("object_final_velocity", "m/s"), ("object_peak_velocity", "m/s"),
    ("approach_velocity", "m/s"), ("max_travel", "m"), ("decoupler_impulse", "N s"), ("peak_gas_pressure", "Pa"),
    ("mode", "1"), ("achieved_restitution", "1"), ("steps", "1"), ("rhs_evals", "1"), ("contacts", "1"), ("rejected_steps", "1"),
    ("events", "1"), ("schema_version", "1"), ("points", "1"), ("seq", "1"), ("flags", "1"),
    // hil: the phase is a fraction of the scan cycle.
    ("phase", "1"),
    // --measured: each comparison states its unit in its own `unit` field.
    ("rms_error", "given by the comparison's `unit`"), ("rms_error_shifted", "given by the comparison's `unit`"), ("peak_measured", "given by the comparison's `unit`"),
    ("peak_simulated", "given by the comparison's `unit`"), ("peak_error", "given by the comparison's `unit`"),
];

/// The unit of a field name, if the convention or the table gives one.
pub fn unit_of(name: &str) -> Option<&'static str> {
    NAMED.iter().find(|(n, _)| *n == name).map(|(_, u)| *u).or_else(|| SUFFIXES.iter().find(|(s, _)| name.ends_with(s)).map(|(_, u)| *u))
}

fn is_numeric(prop: &Value) -> bool {
    let ty = |t: &Value| matches!(t.as_str(), Some("number" | "integer"));
    match prop.get("type") {
        Some(Value::Array(a)) => a.iter().any(ty),
        Some(t) => ty(t),
        None => false,
    }
}

/// Adds `unit` to every numeric property (of the root and of every definition); returns the
/// numeric properties that have none.
fn annotate(schema: &mut Schema) -> Vec<String> {
    let mut missing = Vec::new();
    let mut visit = |obj: &mut Map<String, Value>, path: &str| {
        if let Some(Value::Object(props)) = obj.get_mut("properties") {
            for (name, prop) in props.iter_mut() {
                if !is_numeric(prop) {
                    continue;
                }
                match unit_of(name) {
                    Some(u) => {
                        if let Value::Object(p) = prop {
                            p.insert("unit".into(), Value::String(u.into()));
                        }
                    }
                    None => missing.push(format!("{path}{name}")),
                }
            }
        }
    };
    if let Some(root) = schema.as_object_mut() {
        visit(root, "");
        if let Some(Value::Object(defs)) = root.get_mut("$defs") {
            for (k, d) in defs.iter_mut() {
                if let Value::Object(o) = d {
                    visit(o, &format!("{k}."));
                }
            }
        }
    }
    missing
}

/// Every schema: (file name under docs/schema/, JSON text), and the numeric fields without a unit.
pub fn documents() -> (Vec<(&'static str, String)>, Vec<String>) {
    let mut missing = Vec::new();
    let mut docs = Vec::new();
    for (file, mut schema, what) in [
        ("run.json", schema_for!(RunJson), "`flinch run --json`: the run's summary (the scene contract, docs/SCENES.md) and, with --measured, the comparison"),
        ("hil.json", schema_for!(HilJson), "`flinch hil --json`: the run's summary and the firmware's figures"),
    ] {
        if let Some(o) = schema.as_object_mut() {
            o.insert("description".into(), Value::String(format!("{what}. Units: the `unit` keyword of every numeric field (docs/conventions.md).")));
            o.insert("$id".into(), Value::String(format!("https://flinch.invalid/schema/{file}")));
        }
        missing.extend(annotate(&mut schema).into_iter().map(|m| format!("{file}: {m}")));
        let mut text = serde_json::to_string_pretty(&schema).unwrap_or_default();
        text.push('\n');
        docs.push((file, text));
    }
    (docs, missing)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// docs/schema/ is generated: `FLINCH_BLESS=1 cargo test -p flinch-harness --lib schema`
    /// rewrites it.
    #[test]
    fn schemas_in_docs_are_current_and_every_number_has_a_unit() {
        let (docs, missing) = documents();
        assert!(missing.is_empty(), "numeric fields without a unit (add a suffix per docs/conventions.md, or list a contract name in NAMED): {missing:?}");
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/schema");
        for (file, text) in docs {
            let path = dir.join(file);
            if std::env::var_os("FLINCH_BLESS").is_some() {
                std::fs::create_dir_all(&dir).unwrap();
                std::fs::write(&path, &text).unwrap();
            }
            let on_disk = std::fs::read_to_string(&path).unwrap_or_default();
            assert!(on_disk == text, "{} is out of date: FLINCH_BLESS=1 cargo test -p flinch-harness --lib schema", path.display());
        }
    }

    #[test]
    fn units_come_from_the_suffix() {
        assert_eq!(unit_of("t_s"), Some("s"));
        assert_eq!(unit_of("vx_mps"), Some("m/s"));
        assert_eq!(unit_of("decel_mps2"), Some("m/s^2"));
        assert_eq!(unit_of("k_eff_n_per_m"), Some("N/m"));
        assert_eq!(unit_of("peak_contact_force"), Some("N"));
        assert_eq!(unit_of("latency"), None);
    }
}
