//! JSON Schemas of the documents Flinch writes (`docs/schema/*.json`), generated from the types
//! that serialise them (`schemars`), with every numeric field's unit stated in a `unit` keyword.
//! A unit comes from the name: the convention's suffix (`_s`, `_m`, `_mps`, `_n`, ...;
//! docs/conventions.md), or, for the scene contract's older names (`t_contact`,
//! `peak_contact_force`, ...), the table below. A numeric field with neither fails the test that
//! keeps docs/schema/ current, so no field ships without its unit.

use flinch_report::{HilJson, RunJson, Versioned};
use flinch_model::scene::{Bound, Key, Need, Ty};
use schemars::{schema_for, Schema};
use serde_json::{Map, Value};

pub use flinch_output::units::{unit_of, NAMED, SUFFIXES};

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
        ("check.json", schema_for!(Versioned<'static, flinch_studies::check::BudgetCheck>), "`flinch check --json`: the stroke budget and the simulation that confirms it (`simulated`: the run's summary, docs/schema/run.json)"),
        ("design.json", schema_for!(Versioned<'static, flinch_studies::design::DesignReport>), "`flinch design --json`: the stroke a robot needs, the largest safe speed, the working mode"),
        ("avoid.json", schema_for!(flinch_avoid::AvoidMetrics), "`flinch avoid --json`: the metrics of one avoidance run"),
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
    let mut scene = scene_schema();
    missing.extend(scene_units_missing(&scene).into_iter().map(|m| format!("scene.json: {m}")));
    if let Some(o) = scene.as_object_mut() {
        o.insert("$id".into(), Value::String("https://flinch.invalid/schema/scene.json".into()));
    }
    let mut text = serde_json::to_string_pretty(&scene).unwrap_or_default();
    text.push('\n');
    docs.push(("scene.json", text));
    (docs, missing)
}

fn bound_into(o: &mut Map<String, Value>, b: Bound, incl: &str, excl: &str) {
    match b {
        Bound::Incl(x) => {
            o.insert(incl.into(), x.into());
        }
        Bound::Excl(x) => {
            o.insert(excl.into(), x.into());
        }
        Bound::Open => {}
    }
}

/// One scene key as a JSON Schema property: its type, range, unit, default and the docs' line.
fn key_schema(k: &Key, path: &str) -> Value {
    let mut o = Map::new();
    let mut desc = k.doc.to_string();
    match k.ty {
        Ty::Number(s) => {
            o.insert("type".into(), "number".into());
            bound_into(&mut o, s.lo, "minimum", "exclusiveMinimum");
            bound_into(&mut o, s.hi, "maximum", "exclusiveMaximum");
            o.insert("unit".into(), (if s.unit.is_empty() { "1" } else { s.unit }).into());
            if !s.source.is_empty() {
                desc.push_str(&format!(" (range: {})", s.source));
            }
        }
        Ty::Integer { lo, hi, .. } => {
            o.insert("type".into(), "integer".into());
            o.insert("minimum".into(), lo.into());
            if hi != u32::MAX {
                o.insert("maximum".into(), hi.into());
            }
            o.insert("unit".into(), "1".into());
        }
        Ty::Bool => {
            o.insert("type".into(), "boolean".into());
        }
        Ty::Text => {
            o.insert("type".into(), "string".into());
            o.insert("minLength".into(), 1.into());
        }
        Ty::Choice(opts) => {
            o.insert("enum".into(), opts.iter().map(|s| Value::String(s.to_string())).collect());
        }
        Ty::List(opts) => {
            o.insert("type".into(), "array".into());
            o.insert("uniqueItems".into(), true.into());
            o.insert("items".into(), serde_json::json!({ "enum": opts }));
        }
        Ty::Table(what) => {
            let sub = if path.is_empty() { k.name.to_string() } else { format!("{path}.{}", k.name) };
            if flinch_model::scene::key_tables().iter().any(|t| t.path == sub) {
                return table_schema(&sub, k.doc);
            }
            o.insert("type".into(), serde_json::json!(["object", "array"]));
            desc.push_str(&format!(" ({what})"));
        }
    }
    match k.need {
        Need::Default(x) => {
            o.insert("default".into(), x.into());
        }
        Need::Optional(absent) => desc.push_str(&format!(" Optional: {absent}.")),
        Need::Required => {}
    }
    o.insert("description".into(), desc.into());
    Value::Object(o)
}

/// A scene table: the union of its keys over the kinds it has (each key says when it applies).
fn table_schema(path: &str, doc: &str) -> Value {
    let mut props = Map::new();
    let mut required: Option<Vec<&str>> = None;
    for t in flinch_model::scene::key_tables().iter().filter(|t| t.path == path) {
        for k in t.keys {
            let mut p = key_schema(k, path);
            if !t.when.is_empty() {
                if let Some(Value::String(d)) = p.get_mut("description") {
                    d.push_str(&format!(" [with {}]", t.when));
                }
            }
            match props.get_mut(k.name) {
                // A key of several kinds (`kind` itself, the end-stops): one entry, every kind named,
                // the choices joined.
                // The same name with another meaning per kind (`sensor.threshold`: m for a travel
                // switch, N for a force sensor): either, each with its unit.
                Some(prev) if ["type", "unit", "minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum"].iter().any(|f| prev.get(f).is_some() && prev.get(f) != p.get(f)) || prev.get("anyOf").is_some() => {
                    let mut branches = match prev.get("anyOf") {
                        Some(Value::Array(b)) => b.clone(),
                        _ => vec![prev.clone()],
                    };
                    branches.push(p);
                    *prev = serde_json::json!({ "anyOf": branches });
                }
                Some(Value::Object(prev)) => {
                    let more = p.get("description").and_then(Value::as_str).and_then(|d| d.rfind(" [with ").map(|i| d[i..].to_string()));
                    if let (Some(more), Some(Value::String(d))) = (more, prev.get_mut("description")) {
                        d.push_str(&more);
                    }
                    if let (Some(Value::Array(all)), Some(Value::Array(add))) = (prev.get_mut("enum"), p.get("enum")) {
                        for v in add {
                            if !all.contains(v) {
                                all.push(v.clone());
                            }
                        }
                    }
                }
                _ => {
                    props.insert(k.name.to_string(), p);
                }
            }
        }
        if t.when.is_empty() {
            required = Some(t.keys.iter().filter(|k| k.need == Need::Required).map(|k| k.name).collect());
        }
    }
    let mut o = Map::new();
    o.insert("type".into(), "object".into());
    o.insert("description".into(), doc.into());
    o.insert("additionalProperties".into(), false.into());
    // No `required`: which keys a table needs depends on the others (a lumped robot or a URDF, the
    // decoupler's kind); the validator and docs/SCENES.md say which.
    let _ = required;
    o.insert("properties".into(), Value::Object(props));
    Value::Object(o)
}

/// The scene file (TOML, read as the same data model as JSON), from the one list of keys the
/// validator reads (`scene::key_tables`): every number with its `unit`, range and default.
pub fn scene_schema() -> Value {
    let mut root = table_schema("", "A Flinch scene (docs/SCENES.md), a TOML file. Units: the `unit` keyword of every numeric key.");
    if let Some(o) = root.as_object_mut() {
        o.insert("$schema".into(), "https://json-schema.org/draft/2020-12/schema".into());
        o.insert("title".into(), "Flinch scene".into());
    }
    root
}

/// Numeric scene keys without a unit, by dotted path.
fn scene_units_missing(v: &Value) -> Vec<String> {
    let mut out = Vec::new();
    fn walk(v: &Value, path: &str, out: &mut Vec<String>) {
        if let Some(Value::Object(props)) = v.get("properties") {
            for (k, p) in props {
                let here = if path.is_empty() { k.clone() } else { format!("{path}.{k}") };
                if is_numeric(p) && p.get("unit").is_none() {
                    out.push(here.clone());
                }
                walk(p, &here, out);
            }
        }
    }
    walk(v, "", &mut out);
    out
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
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../docs/schema");
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

    /// Problems of `v` against the subset of JSON Schema scene.json uses: known keys only, types,
    /// enums, numeric ranges.
    fn violations(schema: &Value, v: &Value, path: &str, out: &mut Vec<String>) {
        let num = |k: &str| schema.get(k).and_then(Value::as_f64);
        if let Some(Value::Array(branches)) = schema.get("anyOf") {
            let fits = branches.iter().any(|b| {
                let mut o = Vec::new();
                violations(b, v, path, &mut o);
                o.is_empty()
            });
            if !fits {
                out.push(format!("{path}: fits none of its meanings"));
            }
            return;
        }
        match v {
            Value::Object(m) if schema.get("properties").is_some() => {
                let props = schema["properties"].as_object().unwrap();
                for (k, x) in m {
                    let here = if path.is_empty() { k.clone() } else { format!("{path}.{k}") };
                    match props.get(k) {
                        Some(p) => violations(p, x, &here, out),
                        None => out.push(format!("{here}: not in the schema")),
                    }
                }
                for r in schema.get("required").and_then(Value::as_array).into_iter().flatten() {
                    if !m.contains_key(r.as_str().unwrap()) {
                        out.push(format!("{path}: lacks required {r}"));
                    }
                }
            }
            Value::Number(n) => {
                let x = n.as_f64().unwrap();
                let ty = schema.get("type").and_then(Value::as_str);
                if !matches!(ty, Some("number" | "integer")) && !schema.get("type").is_some_and(Value::is_array) {
                    out.push(format!("{path}: a number where the schema has {ty:?}"));
                }
                if num("minimum").is_some_and(|m| x < m) || num("exclusiveMinimum").is_some_and(|m| x <= m) || num("maximum").is_some_and(|m| x > m) || num("exclusiveMaximum").is_some_and(|m| x >= m) {
                    out.push(format!("{path} = {x}: out of the schema's range"));
                }
            }
            Value::String(s) => {
                if let Some(Value::Array(e)) = schema.get("enum") {
                    if !e.iter().any(|o| o == s) {
                        out.push(format!("{path} = {s:?}: not one of {e:?}"));
                    }
                }
            }
            _ => {}
        }
    }

    #[test]
    fn every_shipped_scene_meets_the_scene_schema_and_a_bad_one_does_not() {
        let schema = scene_schema();
        let mut n = 0;
        for name in flinch_model::shipped::names().filter(|n| !n.contains("avoid_")) {
            let text = flinch_model::shipped::get(name).unwrap();
            let v: Value = toml::from_str(text).unwrap();
            let mut out = Vec::new();
            violations(&schema, &v, "", &mut out);
            assert!(out.is_empty(), "{name}: {out:?}");
            n += 1;
        }
        assert!(n > 20, "{n} scenes");
        let bad: Value = toml::from_str(&flinch_model::shipped::get("tables5-7_bistable").unwrap().replace("speed = 0.05", "speed = 50.0\nsped = 1.0")).unwrap();
        let mut out = Vec::new();
        violations(&schema, &bad, "", &mut out);
        assert!(out.iter().any(|o| o.starts_with("motion.speed = 50")) && out.iter().any(|o| o.starts_with("motion.sped")), "{out:?}");
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
