//! A scene as a template ([`Template`]): its TOML kept as written, any numeric key set to a value
//! (the number's form kept: integer or float), the result validated as a scene file; unknown keys
//! refused with the close matches.

use flinch_model::scene::{self, Scene};
use std::path::Path;
use toml_edit::{DocumentMut, Item, Value};
use super::error::*;

/// A scene file's document, ready to have keys set and be re-validated.
#[derive(Debug, Clone)]
pub struct Template {
    pub(crate) doc: DocumentMut,
    pub(crate) file: String,
    /// The file's text, when printing `doc` reproduces it byte for byte: a point's text is then
    /// the file with its swept numbers spliced in ([`Template::splice_plan`]), the text the
    /// document would print after [`set`], without cloning and printing the document for every
    /// point (0.18M instructions a point, a quarter of a Table 1 sweep point; docs/accuracy.md).
    pub(crate) text: Option<String>,
    /// The validated scene as the file stands.
    pub base: Scene,
}

/// What a dotted path finds in a document.
pub(crate) enum Found<'a> {
    Number(&'a Value),
    Other(&'a Item),
    Missing,
}

pub(crate) fn lookup<'a>(doc: &'a DocumentMut, key: &str) -> Found<'a> {
    lookup_in(doc.as_item(), key)
}

pub(crate) fn lookup_in<'a>(root: &'a Item, key: &str) -> Found<'a> {
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
pub(crate) fn number_like(old: Option<&Value>, x: f64) -> Value {
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
pub(crate) fn set(doc: &mut DocumentMut, key: &str, x: f64) -> bool {
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

pub(crate) fn numeric_keys_of(item: &Item, prefix: &str, out: &mut Vec<String>) {
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
pub(crate) fn distance(a: &str, b: &str) -> usize {
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
        Self::load_with(path, &[])
    }

    /// Reads a scene argument and applies `--set` overrides to it
    /// ([`flinch_model::overrides::load`]): the template is the scene as overridden.
    pub fn load_with(path: &Path, sets: &[flinch_model::overrides::Set]) -> Result<Self, SweepError> {
        let l = flinch_model::overrides::load(path, sets).map_err(SweepError)?;
        Self::from_text(&l.text, &l.file)
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

    pub(crate) fn validated(&self, text: &str, sets: &[(&str, f64)]) -> Result<Scene, (SweepError, Vec<String>)> {
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
