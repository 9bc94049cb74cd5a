//! Readers of the value shapes an avoidance scene has beyond the shared ones of `scene/check.rs`:
//! `[x, y]` points, whole numbers, lists of tables, choices with a default, increasing key frames.

use crate::scene::check::{line_at, num, Ctx, Key, Need, Tab, Ty};
use toml_edit::{TableLike, Value};

/// An optional choice key: the chosen name, `default` when absent, `None` (reported) when invalid.
pub(crate) fn choice_or(cx: &mut Ctx, tab: &Tab, key: &Key, default: &'static str) -> Option<String> {
    let Ty::Choice(options) = key.ty else { return None };
    cx.maybe_choice(tab, key, options).map(|c| c.unwrap_or(default).to_string())
}

/// A whole number written without a decimal point: `Some(None)` when absent (and optional),
/// `None` (reported) when missing, of another type, or out of the key's range.
pub(crate) fn whole(cx: &mut Ctx, tab: &Tab, key: &Key) -> Option<Option<i64>> {
    let what = key.what();
    let Some(item) = tab.t.get(key.name) else {
        if key.need == Need::Required {
            cx.missing(tab, key.name, &what);
            return None;
        }
        return Some(None);
    };
    let n = match item.as_value() {
        Some(Value::Integer(i)) => *i.value(),
        Some(Value::Float(f)) => {
            cx.bad(tab, key.name, format!("must be {what}, a whole number (write it without a decimal point), got {:?}", f.value()));
            return None;
        }
        _ => {
            cx.bad(tab, key.name, format!("must be {what}, got {}", item.type_name()));
            return None;
        }
    };
    let ok = match key.ty {
        Ty::Number(span) => span.contains(n as f64),
        Ty::Integer { lo, .. } => n >= i64::from(lo),
        _ => false,
    };
    if !ok {
        let msg = match key.span() {
            Some(span) => span.refuse(n as f64),
            None => format!("must be {what}, got {n}"),
        };
        cx.bad(tab, key.name, msg);
        return None;
    }
    Some(Some(n))
}

/// An integer key as a count.
pub(crate) fn count(cx: &mut Ctx, tab: &Tab, key: &Key) -> Option<usize> {
    cx.integer(tab, key).map(|n| n as usize)
}

/// The tables of a list key (`[[a.b]]` or `b = [{ ... }, ...]`), each with its path `a.b[i]` and
/// line; empty when an optional key is absent, `None` (reported) when missing or not a list of
/// tables.
pub(crate) fn tables<'d>(cx: &mut Ctx, tab: &Tab<'d>, key: &Key) -> Option<Vec<Tab<'d>>> {
    let Ty::Table(what) = key.ty else { return None };
    let Some(item) = tab.t.get(key.name) else {
        if key.need == Need::Required {
            cx.missing(tab, key.name, what);
            return None;
        }
        return Some(Vec::new());
    };
    let path = tab.key(key.name);
    let line_of = |cx: &Ctx, t: &dyn TableLike, span: Option<std::ops::Range<usize>>| {
        let first = t.iter().next().and_then(|(k, _)| t.get_key_value(k)).and_then(|(k, _)| k.span());
        first.or(span).map(|s| line_at(cx.text, s.start))
    };
    let mut out = Vec::new();
    if let Some(a) = item.as_array_of_tables() {
        for (i, t) in a.iter().enumerate() {
            let line = line_of(cx, t, t.span()).or(tab.line);
            out.push(Tab { path: format!("{path}[{i}]"), t, line });
        }
        return Some(out);
    }
    let Some(a) = item.as_value().and_then(Value::as_array) else {
        cx.bad(tab, key.name, format!("must be {what}, got {}", item.type_name()));
        return None;
    };
    let mut ok = true;
    for (i, v) in a.iter().enumerate() {
        match v.as_inline_table() {
            Some(t) => {
                let line = line_of(cx, t, t.span()).or(tab.line);
                out.push(Tab { path: format!("{path}[{i}]"), t, line });
            }
            None => {
                cx.bad(tab, key.name, format!("must be {what}, got {} at position {}", v.type_name(), i + 1));
                ok = false;
            }
        }
    }
    ok.then_some(out)
}

/// The value of the number key `name` of `keys` in `t` (its default when absent).
pub(crate) fn number_of(cx: &mut Ctx, t: &Tab, keys: &[Key], name: &str) -> Option<f64> {
    let key = keys.iter().find(|k| k.name == name)?;
    cx.number(t, key)
}

/// Key frames' `t_s` must increase: each later one refused naming the one before.
pub(crate) fn increasing(cx: &mut Ctx, frames: &[Tab], times: &[f64]) -> bool {
    let mut ok = true;
    for (i, w) in times.windows(2).enumerate() {
        if w[1] <= w[0] {
            cx.bad(&frames[i + 1], "t_s", format!("must be after the key frame before it ({}.t_s = {} s): key frames' t_s must increase, got {}", frames[i].path, num(w[0]), num(w[1])));
            ok = false;
        }
    }
    ok
}

/// The checks that need several keys; every value is in its range here.
pub(crate) fn tables_one<'d>(cx: &mut Ctx, tab: &Tab<'d>, key: &Key) -> Option<Tab<'d>> {
    cx.maybe_table(tab, key).flatten()
}

/// A point `[x, y]`: exactly two finite numbers in the key's range.
pub(crate) fn xy(cx: &mut Ctx, tab: &Tab, key: &Key) -> Option<[f64; 2]> {
    let span = key.span()?;
    let Some(item) = tab.t.get(key.name) else {
        cx.missing(tab, key.name, &format!("[x, y], two numbers {}", span.describe()));
        return None;
    };
    let Some(arr) = item.as_value().and_then(Value::as_array) else {
        cx.bad(tab, key.name, format!("must be [x, y], two numbers {}, got {}", span.describe(), item.type_name()));
        return None;
    };
    if arr.len() != 2 {
        cx.bad(tab, key.name, format!("must be [x, y], exactly two numbers, got {} values", arr.len()));
        return None;
    }
    let mut p = [0.0; 2];
    for (i, v) in arr.iter().enumerate() {
        let x = match v {
            Value::Integer(n) => *n.value() as f64,
            Value::Float(f) => *f.value(),
            other => {
                cx.bad(tab, key.name, format!("must be [x, y], two numbers, got {} at position {}", other.type_name(), i + 1));
                return None;
            }
        };
        if !x.is_finite() || !span.contains(x) {
            let coord = if i == 0 { "x" } else { "y" };
            cx.bad(tab, key.name, format!("{coord}: {}", span.refuse(x)));
            return None;
        }
        p[i] = x;
    }
    Some(p)
}
