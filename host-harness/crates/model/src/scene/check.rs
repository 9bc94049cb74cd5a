//! The machinery every element's loader shares: the key tables, the messages, line numbers and the
//! collection of every problem at once.
//!
//! An element declares its keys once, as [`Key`] constants (name, type and unit, allowed range with
//! the source of each bound, default, one doc line), and reads them through [`Ctx`]. The validator,
//! the generated key list in docs/SCENES.md and the property tests all read these tables.
//! Problems are collected, never returned early: a scene with five mistakes gets five lines
//! `file:line: key: message`, sorted by line, each saying what is allowed.
use std::fmt;
use std::ops::Range;
use toml_edit::{Item, TableLike, Value};

/// One problem found in a scene file.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneIssue {
    /// 1-based line, `None` when the problem is not tied to a line (an unreadable file).
    pub line: Option<usize>,
    /// Dotted key path, e.g. `decoupler.front_stop.damping`; empty for a TOML syntax error.
    pub key: String,
    /// What is wrong and what is allowed.
    pub message: String,
}

/// Every problem found in one scene file.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    /// The file name as given to [`super::load`] or [`super::parse`].
    pub file: String,
    /// The problems, in the order found (never empty).
    pub issues: Vec<SceneIssue>,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, issue) in self.issues.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(f, "{}", self.file)?;
            if let Some(line) = issue.line {
                write!(f, ":{line}")?;
            }
            if !issue.key.is_empty() {
                write!(f, ": {}", issue.key)?;
            }
            write!(f, ": {}", issue.message)?;
        }
        Ok(())
    }
}

impl std::error::Error for SceneError {}

/// The TOML document of a scene, or the syntax error as a [`SceneError`] with its line.
pub(super) fn parse_toml<'t>(text: &'t str, file: &str) -> Result<toml_edit::ImDocument<&'t str>, SceneError> {
    toml_edit::ImDocument::parse(text).map_err(|e| {
        let line = Some(line_at(text, e.span().map_or(0, |s| s.start)));
        // One line: every line of a refusal starts with the file (toml_edit's message can run
        // over two lines, the second then lacking it; found by tests/fuzz.rs).
        let message = format!("not valid TOML: {}", e.message().trim().replace('\n', "; "));
        SceneError { file: file.to_string(), issues: vec![SceneIssue { line, key: String::new(), message }] }
    })
}

/// 1-based line of the byte `offset` in `text`.
pub(super) fn line_at(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    text.as_bytes()[..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// The candidate closest to `word` when it is close enough to be a typo (edit distance at most a
/// third of the word, at least 1), for "did you mean".
pub fn closest<'a>(word: &str, candidates: impl Iterator<Item = &'a str>) -> Option<&'a str> {
    let limit = (word.chars().count() / 3).max(1);
    candidates.map(|c| (strsim::levenshtein(word, c), c)).filter(|(d, _)| *d <= limit).min_by_key(|(d, _)| *d).map(|(_, c)| c)
}

/// A derived value for messages, to 6 significant digits.
pub(super) fn approx(x: f64) -> String {
    num(format!("{x:.5e}").parse().unwrap_or(x))
}

/// Short, exact rendering of a number for messages.
pub(super) fn num(x: f64) -> String {
    if x != 0.0 && (x.abs() < 1e-3 || x.abs() >= 1e6) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

// ---------------------------------------------------------------------------------------------
// Key tables

/// One end of an allowed range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bound {
    /// No limit on this side.
    Open,
    /// The value must be strictly beyond this (`> lo` or `< hi`).
    Excl(f64),
    /// The value may equal this (`>= lo` or `<= hi`).
    Incl(f64),
}

impl Bound {
    /// The limit's value, if any.
    pub fn value(self) -> Option<f64> {
        match self {
            Bound::Open => None,
            Bound::Excl(x) | Bound::Incl(x) => Some(x),
        }
    }
}

/// An allowed range for a number: both ends, the unit and where the bounds come from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Span {
    /// Lower end.
    pub lo: Bound,
    /// Upper end.
    pub hi: Bound,
    /// The unit as written in messages (`m/s`, `N s/m^2.5`, empty for a pure number).
    pub unit: &'static str,
    /// Why these bounds: the thesis table, the device, the physics.
    pub source: &'static str,
}

impl Span {
    /// True when `x` lies in the range.
    pub fn contains(&self, x: f64) -> bool {
        let lo = match self.lo {
            Bound::Incl(l) => x >= l,
            Bound::Excl(l) => x > l,
            Bound::Open => true,
        };
        let hi = match self.hi {
            Bound::Incl(h) => x <= h,
            Bound::Excl(h) => x < h,
            Bound::Open => true,
        };
        lo && hi
    }

    /// The refusal of `x`: `allowed range (0, 10] m/s (source), got x`.
    pub fn refuse(&self, x: f64) -> String {
        let shown = if x.is_finite() { num(x) } else { format!("{x}") };
        if self.source.is_empty() {
            format!("allowed range {}, got {shown}", self.range())
        } else {
            format!("allowed range {} ({}), got {shown}", self.range(), self.source)
        }
    }

    /// The range in interval notation with its unit: `(0, 10] m/s`, `[0, 1]`, `> 0 s` if open.
    pub fn range(&self) -> String {
        let d = self.describe();
        d.strip_prefix("in ").map(str::to_string).unwrap_or(d)
    }

    /// The range as a message says it: `> 0 m/s`, `in [0, 1]`, `in (0, 10] m/s`.
    pub fn describe(&self) -> String {
        let unit = if self.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", self.unit)
        };
        match (self.lo, self.hi) {
            (Bound::Open, Bound::Open) => format!("a finite number{unit}"),
            (lo, Bound::Open) => {
                let (l, incl) = end(lo);
                format!("{} {}{unit}", if incl { ">=" } else { ">" }, num(l))
            }
            (Bound::Open, hi) => {
                let (h, incl) = end(hi);
                format!("{} {}{unit}", if incl { "<=" } else { "<" }, num(h))
            }
            (lo, hi) => {
                let ((l, li), (h, hi)) = (end(lo), end(hi));
                format!(
                    "in {}{}, {}{}{unit}",
                    if li { "[" } else { "(" },
                    num(l),
                    num(h),
                    if hi { "]" } else { ")" }
                )
            }
        }
    }
}

fn end(b: Bound) -> (f64, bool) {
    match b {
        Bound::Incl(x) => (x, true),
        Bound::Excl(x) => (x, false),
        Bound::Open => (f64::NAN, false),
    }
}

/// What a key holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Ty {
    /// A finite number (an integer is accepted) within a range.
    Number(Span),
    /// An integer, `lo..=hi`.
    Integer {
        /// Smallest allowed.
        lo: u32,
        /// Largest allowed.
        hi: u32,
        /// Why these bounds.
        source: &'static str,
    },
    /// `true` or `false`.
    Bool,
    /// A non-empty string.
    Text,
    /// One of these strings.
    Choice(&'static [&'static str]),
    /// A list of distinct strings, each one of these.
    List(&'static [&'static str]),
    /// A sub-table; the text says what it holds (its keys are another table).
    Table(&'static str),
}

/// Whether a key must be given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Need {
    /// Required.
    Required,
    /// Optional, with this numeric default.
    Default(f64),
    /// Optional; the text says what its absence means.
    Optional(&'static str),
}

/// One key of a scene table, declared once: the validator, the docs and the tests read it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Key {
    /// The key as written in the file.
    pub name: &'static str,
    /// What it holds.
    pub ty: Ty,
    /// Required or optional (and the default).
    pub need: Need,
    /// One line for the docs: the thesis symbol and what it is.
    pub doc: &'static str,
}

impl Key {
    /// A required number in `[lo, hi]`-style bounds.
    pub const fn number(
        name: &'static str,
        unit: &'static str,
        lo: Bound,
        hi: Bound,
        source: &'static str,
        doc: &'static str,
    ) -> Key {
        Key {
            name,
            ty: Ty::Number(Span {
                lo,
                hi,
                unit,
                source,
            }),
            need: Need::Required,
            doc,
        }
    }

    /// A required integer in `lo..=hi`.
    pub const fn integer(
        name: &'static str,
        lo: u32,
        hi: u32,
        source: &'static str,
        doc: &'static str,
    ) -> Key {
        Key {
            name,
            ty: Ty::Integer { lo, hi, source },
            need: Need::Required,
            doc,
        }
    }

    /// A required key of another type.
    pub const fn of(name: &'static str, ty: Ty, doc: &'static str) -> Key {
        Key {
            name,
            ty,
            need: Need::Required,
            doc,
        }
    }

    /// The same key, optional with a numeric default.
    pub const fn default(self, x: f64) -> Key {
        Key {
            need: Need::Default(x),
            ..self
        }
    }

    /// The same key, optional; `absent` says what leaving it out means.
    pub const fn optional(self, absent: &'static str) -> Key {
        Key {
            need: Need::Optional(absent),
            ..self
        }
    }

    /// The number's range (`None` for other types).
    pub fn span(&self) -> Option<Span> {
        match self.ty {
            Ty::Number(s) => Some(s),
            _ => None,
        }
    }

    /// What the key must hold, as messages say it (`a number > 0 m/s`, `one of "a" | "b"`).
    pub fn what(&self) -> String {
        match self.ty {
            Ty::Number(s) => format!("a number {}", s.describe()),
            Ty::Integer { lo, hi, .. } if hi == u32::MAX => format!("an integer >= {lo}"),
            Ty::Integer { lo, hi, .. } => format!("an integer in [{lo}, {hi}]"),
            Ty::Bool => "true or false".into(),
            Ty::Text => "a non-empty string".into(),
            Ty::Choice(options) => format!("one of {}", quoted(options, " | ")),
            Ty::List(options) => format!("a list of {}", quoted(options, " | ")),
            Ty::Table(what) => format!("a table ({what})"),
        }
    }
}

fn quoted(options: &[&str], sep: &str) -> String {
    options
        .iter()
        .map(|s| format!("\"{s}\""))
        .collect::<Vec<_>>()
        .join(sep)
}

/// The keys of one scene table (`[motion]`, or `[decoupler]` for one kind), for the docs and tests.
#[derive(Debug, Clone, Copy)]
pub struct KeyTable {
    /// Dotted path of the table (`""` for the top level, `decoupler.front_stop`).
    pub path: &'static str,
    /// When these keys apply (`kind = "bistable"`), empty if always.
    pub when: &'static str,
    /// The keys, in the order the docs list them.
    pub keys: &'static [Key],
}

// ---------------------------------------------------------------------------------------------
// Reading a table

/// A table being checked: its dotted path, contents and header line.
pub(super) struct Tab<'d> {
    pub path: String,
    pub t: &'d dyn TableLike,
    pub line: Option<usize>,
}

impl Tab<'_> {
    /// The dotted path of `key` in this table.
    pub fn key(&self, key: &str) -> String {
        if self.path.is_empty() {
            key.to_string()
        } else {
            format!("{}.{key}", self.path)
        }
    }

    /// True when the file gives `key`.
    pub fn has(&self, key: &str) -> bool {
        self.t.contains_key(key)
    }
}

/// The file's text and every problem found so far.
pub(super) struct Ctx<'t> {
    pub text: &'t str,
    /// The scene file as named in messages: a path a key may be relative to (`robot.urdf`).
    pub file: &'t str,
    pub issues: Vec<SceneIssue>,
    /// Every key table ([`super::key_tables`], given by the caller so that this file does not
    /// import the tables that import it): in debug builds `check_keys` asserts that the keys it
    /// checks are listed there. Empty: not asserted (the `[robot]` URDF reader, which reads one table).
    pub tables: &'static [KeyTable],
}

impl Ctx<'_> {
    fn line(&self, span: Option<Range<usize>>) -> Option<usize> {
        span.map(|s| line_at(self.text, s.start))
    }

    fn err(&mut self, line: Option<usize>, key: String, message: String) {
        self.issues.push(SceneIssue { line, key, message });
    }

    /// Line of `key` in `tab`, falling back to the table's own line.
    fn key_line(&self, tab: &Tab, key: &str) -> Option<usize> {
        tab.t
            .get_key_value(key)
            .and_then(|(k, item)| self.line(k.span()).or_else(|| self.line(item.span())))
            .or(tab.line)
    }

    /// Refuses keys of `tab` not in `allowed`; `what` says which table (e.g. ` for kind = "rigid"`).
    pub fn check_keys(&mut self, tab: &Tab, allowed: &[Key], what: &str) {
        debug_assert!(
            self.tables.is_empty() || self.tables.iter().any(|t| t.keys == allowed),
            "the keys of {} are not listed in scene::key_tables()",
            tab.path
        );
        for (key, _) in tab.t.iter() {
            if !allowed.iter().any(|k| k.name == key) {
                let line = self.key_line(tab, key);
                let list = allowed.iter().map(|k| k.name).collect::<Vec<_>>().join(", ");
                let near = closest(key, allowed.iter().map(|k| k.name));
                let hint = near.map_or(String::new(), |n| format!("; did you mean `{n}`?"));
                self.err(
                    line,
                    tab.key(key),
                    format!("unknown key{what}; allowed keys: {list}{hint}"),
                );
            }
        }
    }

    /// Reports `key` missing; `what` says what it must hold.
    pub fn missing(&mut self, tab: &Tab, key: &str, what: &str) {
        let line = tab.line;
        self.err(line, tab.key(key), format!("missing required key: {what}"));
    }

    fn wrong_type(&mut self, tab: &Tab, key: &str, what: &str, item: &Item) {
        let line = self.key_line(tab, key);
        self.err(
            line,
            tab.key(key),
            format!("must be {what}, got {}", item.type_name()),
        );
    }

    /// Reports a problem with `key` at its line.
    pub fn bad(&mut self, tab: &Tab, key: &str, message: String) {
        let line = self.key_line(tab, key);
        self.err(line, tab.key(key), message);
    }

    /// The item of `key`, or `None` after reporting it missing if it is required.
    fn item<'d>(&mut self, tab: &Tab<'d>, key: &Key) -> Option<&'d Item> {
        let item = tab.t.get(key.name);
        if item.is_none() && key.need == Need::Required {
            self.missing(tab, key.name, &key.what());
        }
        item
    }

    /// A number key: its value, its default when absent, or `None` (reported) when it is missing
    /// or invalid. An optional key without a default reads with [`Ctx::maybe_number`].
    pub fn number(&mut self, tab: &Tab, key: &Key) -> Option<f64> {
        match (self.maybe_number(tab, key)?, key.need) {
            (Some(x), _) => Some(x),
            (None, Need::Default(d)) => Some(d),
            (None, _) => None,
        }
    }

    /// An optional number key: `Some(None)` when absent, `None` (reported) when invalid.
    pub fn maybe_number(&mut self, tab: &Tab, key: &Key) -> Option<Option<f64>> {
        let Some(span) = key.span() else {
            debug_assert!(false, "{} is not a number key", key.name);
            return None;
        };
        let Some(item) = self.item(tab, key) else {
            return if key.need == Need::Required { None } else { Some(None) };
        };
        let x = match item.as_value() {
            Some(Value::Integer(i)) => *i.value() as f64,
            Some(Value::Float(f)) => *f.value(),
            _ => {
                self.wrong_type(tab, key.name, &key.what(), item);
                return None;
            }
        };
        if !x.is_finite() {
            self.bad(
                tab,
                key.name,
                format!("must be a finite number; {}", span.refuse(x)),
            );
            return None;
        }
        if !span.contains(x) {
            self.bad(tab, key.name, span.refuse(x));
            return None;
        }
        Some(Some(x))
    }

    /// A required integer key.
    pub fn integer(&mut self, tab: &Tab, key: &Key) -> Option<u32> {
        let Ty::Integer { lo, hi, .. } = key.ty else {
            debug_assert!(false, "{} is not an integer key", key.name);
            return None;
        };
        let what = key.what();
        let item = self.item(tab, key)?;
        match item.as_value() {
            Some(Value::Integer(i)) => match u32::try_from(*i.value()) {
                Ok(n) if (lo..=hi).contains(&n) => Some(n),
                _ => {
                    self.bad(tab, key.name, format!("must be {what}, got {}", i.value()));
                    None
                }
            },
            Some(Value::Float(f)) => {
                self.bad(
                    tab,
                    key.name,
                    format!(
                        "must be {what} (write it without a decimal point), got {:?}",
                        f.value()
                    ),
                );
                None
            }
            _ => {
                self.wrong_type(tab, key.name, &what, item);
                None
            }
        }
    }

    /// An optional boolean key: `Some(None)` when absent, `None` (reported) when not a boolean.
    pub fn boolean(&mut self, tab: &Tab, key: &Key) -> Option<Option<bool>> {
        let Some(item) = self.item(tab, key) else {
            return Some(None);
        };
        match item.as_value().and_then(Value::as_bool) {
            Some(b) => Some(Some(b)),
            None => {
                self.wrong_type(tab, key.name, &key.what(), item);
                None
            }
        }
    }

    /// A string key.
    pub fn string(&mut self, tab: &Tab, key: &Key) -> Option<String> {
        let what = key.what();
        let item = self.item(tab, key)?;
        match item.as_value().and_then(Value::as_str) {
            Some(s) if !s.trim().is_empty() => Some(s.to_string()),
            Some(_) => {
                self.bad(tab, key.name, format!("must be {what}, got \"\""));
                None
            }
            None => {
                self.wrong_type(tab, key.name, &what, item);
                None
            }
        }
    }

    /// A required choice key: the value of `values` at the position of the chosen name in the
    /// key's options.
    pub fn choice<T: Copy>(&mut self, tab: &Tab, key: &Key, values: &[T]) -> Option<T> {
        self.maybe_choice(tab, key, values)?
    }

    /// An optional choice key: `Some(None)` when absent, `None` (reported) when invalid.
    pub fn maybe_choice<T: Copy>(&mut self, tab: &Tab, key: &Key, values: &[T]) -> Option<Option<T>> {
        let Ty::Choice(options) = key.ty else {
            debug_assert!(false, "{} is not a choice key", key.name);
            return None;
        };
        debug_assert_eq!(options.len(), values.len(), "{}", key.name);
        let Some(item) = self.item(tab, key) else {
            return if key.need == Need::Required { None } else { Some(None) };
        };
        let what = key.what();
        let Some(s) = item.as_value().and_then(Value::as_str) else {
            self.wrong_type(tab, key.name, &what, item);
            return None;
        };
        match options.iter().position(|name| *name == s) {
            Some(i) => values.get(i).copied().map(Some),
            None => {
                let hint = closest(s, options.iter().copied()).map_or(String::new(), |n| format!(" (did you mean \"{n}\"?)"));
                self.bad(tab, key.name, format!("must be {what}, got \"{s}\"{hint}"));
                None
            }
        }
    }

    /// A list key: the positions (in the key's options) of the names listed, each at most once;
    /// empty when absent.
    pub fn list(&mut self, tab: &Tab, key: &Key) -> Option<Vec<usize>> {
        let Ty::List(options) = key.ty else {
            debug_assert!(false, "{} is not a list key", key.name);
            return None;
        };
        let Some(item) = self.item(tab, key) else {
            return Some(Vec::new());
        };
        let what = key.what();
        let Some(list) = item.as_value().and_then(Value::as_array) else {
            self.wrong_type(tab, key.name, &what, item);
            return None;
        };
        let mut out = Vec::new();
        let mut ok = true;
        for v in list.iter() {
            let shown = v.to_string();
            let shown = shown.trim();
            match v.as_str().and_then(|s| options.iter().position(|o| *o == s)) {
                Some(i) if out.contains(&i) => {
                    self.bad(tab, key.name, format!("lists {shown} twice"));
                    ok = false;
                }
                Some(i) => out.push(i),
                None => {
                    self.bad(tab, key.name, format!("must be {what}, got {shown}"));
                    ok = false;
                }
            }
        }
        ok.then_some(out)
    }

    /// A required list of at most `max_len` numbers, item `i` within `span(i)`; `what` says what
    /// the list must be. `None` (reported) when missing or invalid.
    pub fn numbers(&mut self, tab: &Tab, key: &Key, what: &str, max_len: usize, span: impl Fn(usize) -> Span) -> Option<Vec<f64>> {
        let Some(item) = tab.t.get(key.name) else {
            self.missing(tab, key.name, what);
            return None;
        };
        let Some(list) = item.as_value().and_then(Value::as_array) else {
            self.bad(tab, key.name, format!("must be {what}, got {}", item.type_name()));
            return None;
        };
        if list.len() > max_len {
            self.bad(tab, key.name, format!("must be {what}, got {} numbers", list.len()));
            return None;
        }
        let mut out = Vec::new();
        for (i, v) in list.iter().enumerate() {
            let s = span(i);
            let x = match v {
                Value::Integer(n) => *n.value() as f64,
                Value::Float(f) => *f.value(),
                other => {
                    let unit = if s.unit.is_empty() { String::new() } else { format!(" ({})", s.unit) };
                    self.bad(tab, key.name, format!("item {} must be a number{unit}, got {}", i + 1, other.to_string().trim()));
                    return None;
                }
            };
            if !x.is_finite() || !s.contains(x) {
                self.bad(tab, key.name, format!("item {}: {}", i + 1, s.refuse(x)));
                return None;
            }
            out.push(x);
        }
        Some(out)
    }

    /// A required sub-table (`[a.b]`, `b = { ... }` or dotted keys).
    pub fn table<'d>(&mut self, tab: &Tab<'d>, key: &Key) -> Option<Tab<'d>> {
        self.maybe_table(tab, key)?
    }

    /// An optional sub-table: `Some(None)` when absent, `None` (reported) when not a table.
    pub fn maybe_table<'d>(&mut self, tab: &Tab<'d>, key: &Key) -> Option<Option<Tab<'d>>> {
        let Some(item) = self.item(tab, key) else {
            return if key.need == Need::Required { None } else { Some(None) };
        };
        match item.as_table_like() {
            Some(t) => Some(Some(Tab {
                path: tab.key(key.name),
                t,
                line: self.key_line(tab, key.name),
            })),
            None => {
                self.wrong_type(tab, key.name, &key.what(), item);
                None
            }
        }
    }
}
