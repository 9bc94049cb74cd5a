//! Reading and validating scene files (`shared/SCENES.md`).
//!
//! [`load`] reads a file, [`parse`] checks a text. Every key is checked: an unknown key, a missing
//! required key, a wrong type, a non-finite number or a physically impossible value is refused, and
//! *all* problems found are reported at once in a [`SceneError`], one per line as
//! `file:line: key: message`, the message saying what is allowed. Integers are accepted where a
//! number is expected (`gap = 1` is 1.0); where an integer is expected (`springs`) a float is refused.
//!
//! Optional elements (SCENES.md): a missing `[robot]` is a rigid robot; a missing
//! `decoupler.friction` is a frictionless slide; a missing `[sensor]` means nothing detects the
//! collision, so the robot never brakes (allowed, e.g. to study the free response); a missing
//! `[controller]` is a plain run. Every other physics key is required.
//!
//! Keys accepted beyond SCENES.md, and their documented defaults:
//! - `motion.start_at_speed` (bool, default `false`): flange, robot and tool already cruise at V_c at
//!   t = 0 (the Ch. 2 set-ups); `motion.accel` is still required but unused.
//! - `target.floor_friction` (mu >= 0, `kind = "object"` only, default none).
//! - `target.chi` (N s/m^2.5 >= 0): a fixed chi (Table 12) instead of `restitution` + `damping_law`.
//! - `decoupler.front_stop = { stiffness, restitution }` as an alternative to `{ stiffness, damping }`
//!   (Table 11 gives e_fe): converted with the linear-oscillator relation
//!   `zeta = -ln(e) / sqrt(pi^2 + ln(e)^2)`, `c = 2 zeta sqrt(k m_t)` (e = 0 gives zeta = 1).
//! - `decoupler.back_stop = { stiffness, restitution, damping_law }` where `damping_law` defaults to
//!   [`DEFAULT_BACK_STOP_LAW`] (Hunt-Crossley, as the thesis, eq 29/37), or `{ stiffness, chi }`.
//! - hydraulic `adiabatic_exponent` (default [`DEFAULT_ADIABATIC_EXPONENT`], air, fixed by eq 47) and
//!   `friction_v0` (default [`DEFAULT_HYDRAULIC_FRICTION_V0`] m/s, regularises sgn in eq 48).
//! - `[solver]`: `method` ("dopri5" | "rk4" | "semi-implicit-euler"), `rtol`, `atol`, `max_step`,
//!   `output_interval`, defaults in the `DEFAULT_*` constants below.
//! - `[controller]` (firmware in the loop): `scan_cycle` (s > 0), `phase` in [0, 1),
//!   `firmware_tick` (s > 0), all required when the table is present.
use super::model::*;
use std::fmt;
use std::ops::Range;
use std::path::Path;
use toml_edit::{ImDocument, Item, TableLike, Value};

/// Default relative tolerance of the adaptive solver.
pub const DEFAULT_RTOL: f64 = 1e-7;
/// Default absolute tolerance of the adaptive solver (m and m/s).
pub const DEFAULT_ATOL: f64 = 1e-10;
/// Default largest step (adaptive) or fixed step (fixed-step methods), s.
pub const DEFAULT_MAX_STEP: f64 = 1e-3;
/// Default interval between recorded samples, s.
pub const DEFAULT_OUTPUT_INTERVAL: f64 = 1e-4;
/// Default integration method.
pub const DEFAULT_METHOD: Method = Method::Dopri5;
/// Adiabatic exponent of air (eq 47).
pub const DEFAULT_ADIABATIC_EXPONENT: f64 = 1.4;
/// Velocity regularising sgn() in the hydraulic dry friction (eq 48), m/s.
pub const DEFAULT_HYDRAULIC_FRICTION_V0: f64 = 1e-3;
/// Damping law of the back end-stop when only a restitution is given (the thesis, eq 29/37).
pub const DEFAULT_BACK_STOP_LAW: DampingLaw = DampingLaw::HuntCrossley;

/// Allowed tolerance ranges: tighter than 1e-13 is below f64 resolution, looser than the upper bound
/// is no longer a meaningful error control.
const RTOL_RANGE: (f64, f64) = (1e-13, 1e-1);
const ATOL_RANGE: (f64, f64) = (1e-15, 1e-2);

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
    /// The file name as given to [`load`] or [`parse`].
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

/// Reads and validates a scene file.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let file = path.display().to_string();
    match std::fs::read_to_string(path) {
        Ok(text) => parse(&text, &file),
        Err(e) => Err(SceneError {
            file,
            issues: vec![SceneIssue { line: None, key: String::new(), message: format!("cannot read the scene file: {e}") }],
        }),
    }
}

/// Validates a scene given as text; `file` names it in the messages.
pub fn parse(text: &str, file: &str) -> Result<Scene, SceneError> {
    let doc = match ImDocument::parse(text) {
        Ok(doc) => doc,
        Err(e) => {
            let line = Some(line_at(text, e.span().map_or(0, |s| s.start)));
            let message = format!("not valid TOML: {}", e.message().trim());
            return Err(SceneError { file: file.to_string(), issues: vec![SceneIssue { line, key: String::new(), message }] });
        }
    };
    let mut cx = Ctx { text, issues: Vec::new() };
    let scene = scene(&mut cx, doc.as_table());
    match scene {
        Some(scene) if cx.issues.is_empty() => Ok(scene),
        _ => {
            debug_assert!(!cx.issues.is_empty(), "a scene part failed without saying why");
            cx.issues.sort_by_key(|i| i.line);
            Err(SceneError { file: file.to_string(), issues: cx.issues })
        }
    }
}

fn line_at(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    text.as_bytes()[..end].iter().filter(|&&b| b == b'\n').count() + 1
}

/// A derived value for messages, to 6 significant digits.
fn approx(x: f64) -> String {
    num(format!("{x:.5e}").parse().unwrap_or(x))
}

/// Short, exact rendering of a number for messages.
fn num(x: f64) -> String {
    if x != 0.0 && (x.abs() < 1e-3 || x.abs() >= 1e6) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// An allowed range for a number, with its unit.
#[derive(Clone, Copy)]
struct Rule {
    lo: Option<(f64, bool)>,
    hi: Option<(f64, bool)>,
    unit: &'static str,
}

impl Rule {
    fn gt(lo: f64, unit: &'static str) -> Self {
        Rule { lo: Some((lo, false)), hi: None, unit }
    }
    fn ge(lo: f64, unit: &'static str) -> Self {
        Rule { lo: Some((lo, true)), hi: None, unit }
    }
    fn any(unit: &'static str) -> Self {
        Rule { lo: None, hi: None, unit }
    }
    /// `[lo, hi]` when `hi_incl`, else `[lo, hi)`.
    fn within(lo: f64, hi: f64, hi_incl: bool, unit: &'static str) -> Self {
        Rule { lo: Some((lo, true)), hi: Some((hi, hi_incl)), unit }
    }
    fn ok(&self, x: f64) -> bool {
        let lo = match self.lo {
            Some((l, true)) => x >= l,
            Some((l, false)) => x > l,
            None => true,
        };
        let hi = match self.hi {
            Some((h, true)) => x <= h,
            Some((h, false)) => x < h,
            None => true,
        };
        lo && hi
    }
    fn describe(&self) -> String {
        let unit = if self.unit.is_empty() { String::new() } else { format!(" {}", self.unit) };
        match (self.lo, self.hi) {
            (Some((l, true)), Some((h, hi))) => format!("in [{}, {}{}{unit}", num(l), num(h), if hi { "]" } else { ")" }),
            (Some((l, incl)), None) => format!("{} {}{unit}", if incl { ">=" } else { ">" }, num(l)),
            _ => format!("a finite number{unit}"),
        }
    }
}

/// A table being checked: its dotted path, contents and header line.
struct Tab<'d> {
    path: String,
    t: &'d dyn TableLike,
    line: Option<usize>,
}

impl Tab<'_> {
    fn key(&self, key: &str) -> String {
        if self.path.is_empty() {
            key.to_string()
        } else {
            format!("{}.{key}", self.path)
        }
    }
}

struct Ctx<'t> {
    text: &'t str,
    issues: Vec<SceneIssue>,
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

    /// Refuses keys of `tab` not in `allowed`; `what` says which table (e.g. `for kind = "rigid"`).
    fn check_keys(&mut self, tab: &Tab, allowed: &[&str], what: &str) {
        for (key, _) in tab.t.iter() {
            if !allowed.contains(&key) {
                let line = self.key_line(tab, key);
                let list = allowed.join(", ");
                self.err(line, tab.key(key), format!("unknown key{what}; allowed keys: {list}"));
            }
        }
    }

    fn missing(&mut self, tab: &Tab, key: &str, what: &str) {
        let line = tab.line;
        self.err(line, tab.key(key), format!("missing required key: {what}"));
    }

    fn wrong_type(&mut self, tab: &Tab, key: &str, what: &str, item: &Item) {
        let line = self.key_line(tab, key);
        self.err(line, tab.key(key), format!("must be {what}, got a {}", item.type_name()));
    }

    fn bad(&mut self, tab: &Tab, key: &str, message: String) {
        let line = self.key_line(tab, key);
        self.err(line, tab.key(key), message);
    }

    /// A number checked against `rule`; `None` when absent (reported if `required`) or invalid.
    fn number(&mut self, tab: &Tab, key: &str, rule: Rule, required: bool) -> Option<f64> {
        let Some(item) = tab.t.get(key) else {
            if required {
                self.missing(tab, key, &format!("a number {}", rule.describe()));
            }
            return None;
        };
        let x = match item.as_value() {
            Some(Value::Integer(i)) => *i.value() as f64,
            Some(Value::Float(f)) => *f.value(),
            _ => {
                self.wrong_type(tab, key, &format!("a number {}", rule.describe()), item);
                return None;
            }
        };
        if !x.is_finite() {
            self.bad(tab, key, format!("must be a finite number {}, got {x}", rule.describe()));
            return None;
        }
        if !rule.ok(x) {
            self.bad(tab, key, format!("must be {}, got {}", rule.describe(), num(x)));
            return None;
        }
        Some(x)
    }

    /// An integer `>= min` that fits a u32.
    fn integer(&mut self, tab: &Tab, key: &str, min: u32, required: bool) -> Option<u32> {
        let what = format!("an integer >= {min}");
        let Some(item) = tab.t.get(key) else {
            if required {
                self.missing(tab, key, &what);
            }
            return None;
        };
        match item.as_value() {
            Some(Value::Integer(i)) => match u32::try_from(*i.value()) {
                Ok(n) if n >= min => Some(n),
                _ => {
                    self.bad(tab, key, format!("must be {what}, got {}", i.value()));
                    None
                }
            },
            Some(Value::Float(f)) => {
                self.bad(tab, key, format!("must be {what} (write it without a decimal point), got {:?}", f.value()));
                None
            }
            _ => {
                self.wrong_type(tab, key, &what, item);
                None
            }
        }
    }

    fn boolean(&mut self, tab: &Tab, key: &str) -> Option<Option<bool>> {
        let Some(item) = tab.t.get(key) else { return Some(None) };
        match item.as_value().and_then(Value::as_bool) {
            Some(b) => Some(Some(b)),
            None => {
                self.wrong_type(tab, key, "true or false", item);
                None
            }
        }
    }

    fn string(&mut self, tab: &Tab, key: &str, required: bool) -> Option<String> {
        let what = "a non-empty string";
        let Some(item) = tab.t.get(key) else {
            if required {
                self.missing(tab, key, what);
            }
            return None;
        };
        match item.as_value().and_then(Value::as_str) {
            Some(s) if !s.trim().is_empty() => Some(s.to_string()),
            Some(_) => {
                self.bad(tab, key, format!("must be {what}, got \"\""));
                None
            }
            None => {
                self.wrong_type(tab, key, what, item);
                None
            }
        }
    }

    /// One of the strings in `options`.
    fn choice<T: Copy>(&mut self, tab: &Tab, key: &str, options: &[(&str, T)], required: bool) -> Option<T> {
        let list = options.iter().map(|(s, _)| format!("\"{s}\"")).collect::<Vec<_>>().join(" | ");
        let what = format!("one of {list}");
        let Some(item) = tab.t.get(key) else {
            if required {
                self.missing(tab, key, &what);
            }
            return None;
        };
        let Some(s) = item.as_value().and_then(Value::as_str) else {
            self.wrong_type(tab, key, &what, item);
            return None;
        };
        match options.iter().find(|(name, _)| *name == s) {
            Some(&(_, v)) => Some(v),
            None => {
                self.bad(tab, key, format!("must be {what}, got \"{s}\""));
                None
            }
        }
    }

    /// A sub-table (`[a.b]`, `b = { ... }` or dotted keys).
    fn table<'d>(&mut self, tab: &Tab<'d>, key: &str, required: bool, what: &str) -> Option<Tab<'d>> {
        let Some(item) = tab.t.get(key) else {
            if required {
                self.missing(tab, key, &format!("a table ({what})"));
            }
            return None;
        };
        match item.as_table_like() {
            Some(t) => Some(Tab { path: tab.key(key), t, line: self.key_line(tab, key) }),
            None => {
                self.wrong_type(tab, key, &format!("a table ({what})"), item);
                None
            }
        }
    }
}

const ROOT_KEYS: &[&str] = &["name", "duration", "motion", "robot", "tool", "decoupler", "target", "sensor", "solver", "controller"];

const LAWS: &[(&str, DampingLaw)] = &[
    ("hunt-crossley", DampingLaw::HuntCrossley),
    ("lankarani-nikravesh", DampingLaw::LankaraniNikravesh),
    ("flores", DampingLaw::Flores),
    ("gonthier", DampingLaw::Gonthier),
    ("exact", DampingLaw::Exact),
];

fn scene(cx: &mut Ctx, root: &toml_edit::Table) -> Option<Scene> {
    let root = Tab { path: String::new(), t: root, line: Some(1) };
    cx.check_keys(&root, ROOT_KEYS, "");
    let name = cx.string(&root, "name", true);
    let duration_s = cx.number(&root, "duration", Rule::gt(0.0, "s"), true);

    let motion_tab = cx.table(&root, "motion", true, "the commanded flange motion");
    let motion = motion_tab.as_ref().and_then(|t| motion(cx, t));
    let robot = match cx.table(&root, "robot", false, "the robot compliance; omit it for a rigid robot") {
        Some(t) => robot(cx, &t).map(Some),
        None if root.t.contains_key("robot") => None,
        None => Some(None),
    };
    let tool = cx.table(&root, "tool", true, "the tool").and_then(|t| tool(cx, &t));
    let gravity = motion.map(|m| m.gravity);
    let decoupler_tab = cx.table(&root, "decoupler", true, "what holds the tool on the flange");
    let decoupler = decoupler_tab.as_ref().and_then(|t| decoupler(cx, t, tool.map(|t| t.mass), gravity));
    let target_tab = cx.table(&root, "target", true, "what the tool runs into");
    let target = target_tab.as_ref().and_then(|t| target(cx, t));
    let sensor_tab = cx.table(&root, "sensor", false, "the collision detector; omit it and the robot never brakes");
    let sensor = match &sensor_tab {
        Some(t) => sensor(cx, t, decoupler.as_ref()).map(Some),
        None if root.t.contains_key("sensor") => None,
        None => Some(None),
    };
    let solver = match cx.table(&root, "solver", false, "integration settings") {
        Some(t) => solver(cx, &t, duration_s),
        None if root.t.contains_key("solver") => None,
        None => Some(default_solver()),
    };
    let controller = match cx.table(&root, "controller", false, "the robot controller for `flinch hil`") {
        Some(t) => controller(cx, &t).map(Some),
        None if root.t.contains_key("controller") => None,
        None => Some(None),
    };

    // The motion must bring the tool to the target: before contact nothing brakes.
    if let (Some(m), Some(d), Some(tg), Some(tt)) = (motion, duration_s, target, &target_tab) {
        let travel = cruise_travel(&m, d);
        if tg.gap >= travel {
            cx.bad(
                tt,
                "gap",
                format!(
                    "the commanded motion covers only {} m in duration = {} s, so the tool never reaches the target; must be < {} m, got {}",
                    approx(travel),
                    num(d),
                    approx(travel),
                    num(tg.gap)
                ),
            );
        }
    }

    Some(Scene {
        name: name?,
        duration_s: duration_s?,
        motion: motion?,
        robot: robot?,
        tool: tool?,
        decoupler: decoupler?,
        target: target?,
        sensor: sensor?,
        solver: solver?,
        controller: controller?,
    })
}

/// Commanded flange travel in `t` s with no braking (trapezoid, or cruising from t = 0).
fn cruise_travel(m: &Motion, t: f64) -> f64 {
    if m.start_at_speed {
        return m.speed * t;
    }
    let t_acc = m.speed / m.accel;
    if t <= t_acc {
        0.5 * m.accel * t * t
    } else {
        0.5 * m.speed * t_acc + m.speed * (t - t_acc)
    }
}

fn motion(cx: &mut Ctx, t: &Tab) -> Option<Motion> {
    cx.check_keys(t, &["speed", "accel", "decel", "dead_time", "gravity", "start_at_speed"], "");
    let speed = cx.number(t, "speed", Rule::gt(0.0, "m/s"), true);
    let accel = cx.number(t, "accel", Rule::gt(0.0, "m/s^2"), true);
    let decel = cx.number(t, "decel", Rule::gt(0.0, "m/s^2"), true);
    let dead_time = cx.number(t, "dead_time", Rule::ge(0.0, "s"), true);
    let gravity = cx.number(t, "gravity", Rule::any("m/s^2"), true);
    let start_at_speed = cx.boolean(t, "start_at_speed");
    Some(Motion {
        speed: speed?,
        accel: accel?,
        decel: decel?,
        dead_time: dead_time?,
        gravity: gravity?,
        start_at_speed: start_at_speed?.unwrap_or(false),
    })
}

fn robot(cx: &mut Ctx, t: &Tab) -> Option<Robot> {
    cx.check_keys(t, &["mass", "stiffness", "damping"], "");
    let mass = cx.number(t, "mass", Rule::gt(0.0, "kg"), true);
    let stiffness = cx.number(t, "stiffness", Rule::gt(0.0, "N/m"), true);
    let damping = cx.number(t, "damping", Rule::ge(0.0, "N s/m"), true);
    Some(Robot { mass: mass?, stiffness: stiffness?, damping: damping? })
}

fn tool(cx: &mut Ctx, t: &Tab) -> Option<Tool> {
    cx.check_keys(t, &["mass"], "");
    Some(Tool { mass: cx.number(t, "mass", Rule::gt(0.0, "kg"), true)? })
}

const RIGID_KEYS: &[&str] = &["kind"];
const LINEAR_KEYS: &[&str] = &["kind", "stiffness", "damping_ratio"];
const BISTABLE_KEYS: &[&str] = &[
    "kind",
    "springs",
    "spring_rate",
    "free_length",
    "height",
    "front_stroke",
    "back_stroke",
    "front_stop",
    "back_stop",
    "friction",
];
const HYDRAULIC_KEYS: &[&str] = &[
    "kind",
    "stroke",
    "piston_radius",
    "orifice_radius",
    "gas_pressure",
    "gas_volume",
    "discharge_coefficient",
    "liquid_density",
    "dry_friction",
    "viscous_friction",
    "adiabatic_exponent",
    "friction_v0",
    "front_stop",
    "back_stop",
];

#[derive(Clone, Copy)]
enum DecKind {
    Rigid,
    Linear,
    Bistable,
    Hydraulic,
}

fn decoupler(cx: &mut Ctx, t: &Tab, tool_mass: Option<f64>, gravity: Option<f64>) -> Option<Decoupler> {
    let kinds = [
        ("rigid", DecKind::Rigid),
        ("linear", DecKind::Linear),
        ("bistable", DecKind::Bistable),
        ("hydraulic", DecKind::Hydraulic),
    ];
    // The allowed keys depend on the kind: without a valid kind only the kind is reported.
    match cx.choice(t, "kind", &kinds, true)? {
        DecKind::Rigid => {
            cx.check_keys(t, RIGID_KEYS, " for kind = \"rigid\"");
            Some(Decoupler::Rigid)
        }
        DecKind::Linear => {
            cx.check_keys(t, LINEAR_KEYS, " for kind = \"linear\"");
            let stiffness = cx.number(t, "stiffness", Rule::ge(0.0, "N/m"), true);
            let damping_ratio = cx.number(t, "damping_ratio", Rule::ge(0.0, ""), true);
            Some(Decoupler::Linear(LinearDecoupler { stiffness: stiffness?, damping_ratio: damping_ratio? }))
        }
        DecKind::Bistable => {
            cx.check_keys(t, BISTABLE_KEYS, " for kind = \"bistable\"");
            bistable(cx, t, tool_mass, gravity).map(Decoupler::Bistable)
        }
        DecKind::Hydraulic => {
            cx.check_keys(t, HYDRAULIC_KEYS, " for kind = \"hydraulic\"");
            hydraulic(cx, t, tool_mass).map(Decoupler::Hydraulic)
        }
    }
}

fn bistable(cx: &mut Ctx, t: &Tab, tool_mass: Option<f64>, gravity: Option<f64>) -> Option<Bistable> {
    let springs = cx.integer(t, "springs", 1, true);
    let spring_rate = cx.number(t, "spring_rate", Rule::gt(0.0, "N/m"), true);
    let free_length = cx.number(t, "free_length", Rule::gt(0.0, "m"), true);
    let height = cx.number(t, "height", Rule::gt(0.0, "m"), true);
    let front_stroke = cx.number(t, "front_stroke", Rule::gt(0.0, "m"), true);
    let back_stroke = cx.number(t, "back_stroke", Rule::gt(0.0, "m"), true);
    let front_stop = cx.table(t, "front_stop", true, "{ stiffness, damping } or { stiffness, restitution }");
    let front_stop = front_stop.and_then(|s| linear_stop(cx, &s, tool_mass));
    let back_stop = cx.table(t, "back_stop", true, "{ stiffness, restitution, damping_law } or { stiffness, chi }");
    let back_stop = back_stop.and_then(|s| nonlinear_stop(cx, &s));
    let friction = match cx.table(t, "friction", false, "{ mu, v0 }; omit it for a frictionless slide") {
        Some(f) => {
            cx.check_keys(&f, &["mu", "v0"], "");
            let mu = cx.number(&f, "mu", Rule::ge(0.0, ""), true);
            let v0 = cx.number(&f, "v0", Rule::ge(0.0, "m/s"), true);
            mu.zip(v0).map(|(mu, v0)| Some(TanhFriction { mu, v0 }))
        }
        None if t.t.contains_key("friction") => None,
        None => Some(None),
    };

    // At t = 0 the tool rests on the front stop: spring force at s = C1 plus its weight must push it there.
    if let (Some(n), Some(kb), Some(l0), Some(h), Some(c1), Some(mt), Some(gravity)) =
        (springs, spring_rate, free_length, height, front_stroke, tool_mass, gravity)
    {
        let l1 = (h * h + c1 * c1).sqrt();
        let f_spring = f64::from(n) * kb * (l0 - l1) * c1 / l1;
        let weight = mt * gravity;
        if f_spring + weight <= 0.0 {
            cx.bad(
                t,
                "free_length",
                format!(
                    "the tool would not rest on the front stop at t = 0: the springs push it with {} N at s = C1 and its weight with {} N; need free_length > sqrt(height^2 + front_stroke^2) = {} m (or enough gravity), got {}",
                    approx(f_spring),
                    approx(weight),
                    approx(l1),
                    num(l0)
                ),
            );
            return None;
        }
    }
    Some(Bistable {
        springs: springs?,
        spring_rate: spring_rate?,
        free_length: free_length?,
        height: height?,
        front_stroke: front_stroke?,
        back_stroke: back_stroke?,
        front_stop: front_stop?,
        back_stop: back_stop?,
        friction: friction?,
    })
}

fn hydraulic(cx: &mut Ctx, t: &Tab, tool_mass: Option<f64>) -> Option<Hydraulic> {
    let stroke = cx.number(t, "stroke", Rule::gt(0.0, "m"), true);
    let piston_radius = cx.number(t, "piston_radius", Rule::gt(0.0, "m"), true);
    let orifice_radius = cx.number(t, "orifice_radius", Rule::gt(0.0, "m"), true);
    let gas_pressure = cx.number(t, "gas_pressure", Rule::gt(0.0, "Pa"), true);
    let gas_volume = cx.number(t, "gas_volume", Rule::gt(0.0, "m^3"), true);
    let discharge_coefficient = cx.number(t, "discharge_coefficient", Rule::gt(0.0, ""), true);
    let liquid_density = cx.number(t, "liquid_density", Rule::gt(0.0, "kg/m^3"), true);
    let dry_friction = cx.number(t, "dry_friction", Rule::ge(0.0, "N"), true);
    let viscous_friction = cx.number(t, "viscous_friction", Rule::ge(0.0, "N s/m"), true);
    // 1 is isothermal, 5/3 a monatomic gas: nothing outside is a gas.
    let adiabatic_exponent = match t.t.contains_key("adiabatic_exponent") {
        true => cx.number(t, "adiabatic_exponent", Rule::within(1.0, 5.0 / 3.0, true, ""), false),
        false => Some(DEFAULT_ADIABATIC_EXPONENT),
    };
    let friction_v0 = match t.t.contains_key("friction_v0") {
        true => cx.number(t, "friction_v0", Rule::gt(0.0, "m/s"), false),
        false => Some(DEFAULT_HYDRAULIC_FRICTION_V0),
    };
    let front_stop = cx.table(t, "front_stop", true, "{ stiffness, damping } or { stiffness, restitution }");
    let front_stop = front_stop.and_then(|s| linear_stop(cx, &s, tool_mass));
    let back_stop = cx.table(t, "back_stop", true, "{ stiffness, restitution, damping_law } or { stiffness, chi }");
    let back_stop = back_stop.and_then(|s| nonlinear_stop(cx, &s));

    if let (Some(rp), Some(ro)) = (piston_radius, orifice_radius) {
        if ro >= rp {
            cx.bad(t, "orifice_radius", format!("must be < decoupler.piston_radius = {} m, got {}", num(rp), num(ro)));
            return None;
        }
    }
    if let (Some(rp), Some(l), Some(vg)) = (piston_radius, stroke, gas_volume) {
        let swept = std::f64::consts::PI * rp * rp * l;
        if swept >= vg {
            cx.bad(
                t,
                "gas_volume",
                format!(
                    "must be > the volume the piston sweeps, pi * piston_radius^2 * stroke = {} m^3 (else the gas is driven to zero volume), got {}",
                    approx(swept),
                    num(vg)
                ),
            );
            return None;
        }
    }
    Some(Hydraulic {
        stroke: stroke?,
        piston_radius: piston_radius?,
        orifice_radius: orifice_radius?,
        gas_pressure: gas_pressure?,
        gas_volume: gas_volume?,
        discharge_coefficient: discharge_coefficient?,
        liquid_density: liquid_density?,
        dry_friction: dry_friction?,
        viscous_friction: viscous_friction?,
        adiabatic_exponent: adiabatic_exponent?,
        friction_v0: friction_v0?,
        front_stop: front_stop?,
        back_stop: back_stop?,
    })
}

/// Damping ratio of a linear oscillator whose restitution is `e`.
fn zeta_from_restitution(e: f64) -> f64 {
    if e <= 0.0 {
        return 1.0;
    }
    let l = e.ln();
    -l / (std::f64::consts::PI.powi(2) + l * l).sqrt()
}

fn linear_stop(cx: &mut Ctx, t: &Tab, tool_mass: Option<f64>) -> Option<LinearStop> {
    cx.check_keys(t, &["stiffness", "damping", "restitution"], "");
    let stiffness = cx.number(t, "stiffness", Rule::gt(0.0, "N/m"), true);
    match (t.t.contains_key("damping"), t.t.contains_key("restitution")) {
        (true, true) => {
            cx.bad(t, "restitution", "give either damping (N s/m) or restitution, not both".into());
            None
        }
        (false, false) => {
            cx.missing(t, "damping", "damping (N s/m >= 0), or restitution in [0, 1] converted with the tool mass");
            None
        }
        (true, false) => {
            let damping = cx.number(t, "damping", Rule::ge(0.0, "N s/m"), true);
            Some(LinearStop { stiffness: stiffness?, damping: damping? })
        }
        (false, true) => {
            let e = cx.number(t, "restitution", Rule::within(0.0, 1.0, true, ""), true)?;
            let (k, m) = (stiffness?, tool_mass?);
            let damping = 2.0 * zeta_from_restitution(e) * (k * m).sqrt();
            Some(LinearStop { stiffness: k, damping })
        }
    }
}

/// `restitution` + `damping_law` or `chi`; `default_law` is used when `damping_law` is absent
/// (`None`: the law is required).
fn contact_damping(cx: &mut Ctx, t: &Tab, default_law: Option<DampingLaw>) -> Option<ContactDamping> {
    let has_chi = t.t.contains_key("chi");
    let has_e = t.t.contains_key("restitution");
    let has_law = t.t.contains_key("damping_law");
    if has_chi {
        if has_e || has_law {
            let other = if has_e { "restitution" } else { "damping_law" };
            cx.bad(t, other, "give either chi (a fixed damping) or restitution with damping_law, not both".into());
            return None;
        }
        return cx.number(t, "chi", Rule::ge(0.0, "N s/m^2.5"), true).map(ContactDamping::FixedChi);
    }
    if !has_e {
        cx.missing(t, "restitution", "restitution in [0, 1] (with damping_law), or chi (N s/m^2.5 >= 0)");
        if has_law {
            cx.choice(t, "damping_law", LAWS, false);
        }
        return None;
    }
    let e = cx.number(t, "restitution", Rule::within(0.0, 1.0, true, ""), true);
    let law = match default_law {
        Some(d) if !has_law => Some(d),
        _ => cx.choice(t, "damping_law", LAWS, true),
    };
    let (e, law) = (e?, law?);
    // These two laws divide by e.
    if e == 0.0 && matches!(law, DampingLaw::Flores | DampingLaw::Gonthier) {
        cx.bad(t, "restitution", "must be in (0, 1] with damping_law \"flores\" or \"gonthier\" (the law divides by e), got 0".into());
        return None;
    }
    Some(ContactDamping::Restitution { restitution: e, law })
}

fn nonlinear_stop(cx: &mut Ctx, t: &Tab) -> Option<NonlinearStop> {
    cx.check_keys(t, &["stiffness", "restitution", "damping_law", "chi"], "");
    let stiffness = cx.number(t, "stiffness", Rule::gt(0.0, "N/m^1.5"), true);
    let damping = contact_damping(cx, t, Some(DEFAULT_BACK_STOP_LAW));
    Some(NonlinearStop { stiffness: stiffness?, damping: damping? })
}

fn target(cx: &mut Ctx, t: &Tab) -> Option<Target> {
    #[derive(Clone, Copy)]
    enum K {
        Obstacle,
        Object,
    }
    let kind = cx.choice(t, "kind", &[("obstacle", K::Obstacle), ("object", K::Object)], true);
    let common = ["kind", "gap", "stiffness", "restitution", "damping_law", "chi"];
    match kind {
        Some(K::Obstacle) => cx.check_keys(t, &common, " for kind = \"obstacle\""),
        Some(K::Object) => cx.check_keys(t, &[&common[..], &["mass", "floor_friction"]].concat(), " for kind = \"object\""),
        None => {}
    }
    let gap = cx.number(t, "gap", Rule::gt(0.0, "m"), true);
    let stiffness = cx.number(t, "stiffness", Rule::gt(0.0, "N/m^1.5"), true);
    let damping = contact_damping(cx, t, None);
    let kind = match kind? {
        K::Obstacle => TargetKind::Obstacle,
        K::Object => {
            let mass = cx.number(t, "mass", Rule::gt(0.0, "kg"), true);
            let floor_friction = match t.t.contains_key("floor_friction") {
                true => Some(cx.number(t, "floor_friction", Rule::ge(0.0, ""), false)?),
                false => None,
            };
            TargetKind::Object { mass: mass?, floor_friction }
        }
    };
    Some(Target { kind, gap: gap?, stiffness: stiffness?, damping: damping? })
}

fn sensor(cx: &mut Ctx, t: &Tab, decoupler: Option<&Decoupler>) -> Option<Sensor> {
    #[derive(Clone, Copy)]
    enum K {
        Travel,
        Force,
    }
    cx.check_keys(t, &["kind", "threshold"], "");
    let kind = cx.choice(t, "kind", &[("travel", K::Travel), ("force", K::Force)], true);
    let rule = match kind {
        Some(K::Travel) => Rule::gt(0.0, "m"),
        Some(K::Force) => Rule::gt(0.0, "N"),
        None => Rule::gt(0.0, "(m for travel, N for force)"),
    };
    let threshold = cx.number(t, "threshold", rule, true);
    let (kind, threshold) = (kind?, threshold?);
    match kind {
        K::Force => Some(Sensor::Force { threshold }),
        K::Travel => {
            let stroke = match decoupler {
                Some(Decoupler::Rigid) => {
                    cx.bad(t, "kind", "must be \"force\" for decoupler.kind = \"rigid\" (a rigid tool has no travel), got \"travel\"".into());
                    return None;
                }
                Some(Decoupler::Bistable(b)) => Some((b.front_stroke + b.back_stroke, "total stroke front_stroke + back_stroke")),
                Some(Decoupler::Hydraulic(h)) => Some((h.stroke, "stroke")),
                Some(Decoupler::Linear(_)) | None => None,
            };
            if let Some((c, what)) = stroke {
                if threshold >= c {
                    cx.bad(t, "threshold", format!("must be < the decoupler's {what} = {} m, got {}", approx(c), num(threshold)));
                    return None;
                }
            }
            Some(Sensor::Travel { threshold })
        }
    }
}

fn default_solver() -> SolverSettings {
    SolverSettings {
        method: DEFAULT_METHOD,
        rtol: DEFAULT_RTOL,
        atol: DEFAULT_ATOL,
        max_step: DEFAULT_MAX_STEP,
        output_interval: DEFAULT_OUTPUT_INTERVAL,
    }
}

fn solver(cx: &mut Ctx, t: &Tab, duration: Option<f64>) -> Option<SolverSettings> {
    cx.check_keys(t, &["method", "rtol", "atol", "max_step", "output_interval"], "");
    let d = default_solver();
    let methods = [("dopri5", Method::Dopri5), ("rk4", Method::Rk4), ("semi-implicit-euler", Method::SemiImplicitEuler)];
    let method = match t.t.contains_key("method") {
        true => cx.choice(t, "method", &methods, false),
        false => Some(d.method),
    };
    let mut opt = |key: &str, rule: Rule, default: f64| match t.t.contains_key(key) {
        true => cx.number(t, key, rule, false),
        false => Some(default),
    };
    let rtol = opt("rtol", Rule::within(RTOL_RANGE.0, RTOL_RANGE.1, true, ""), d.rtol);
    let atol = opt("atol", Rule::within(ATOL_RANGE.0, ATOL_RANGE.1, true, ""), d.atol);
    let max_step = opt("max_step", Rule::gt(0.0, "s"), d.max_step);
    let output_interval = opt("output_interval", Rule::ge(0.0, "s"), d.output_interval);
    if let Some(dur) = duration {
        for (key, v) in [("max_step", max_step), ("output_interval", output_interval)] {
            if let Some(v) = v.filter(|&v| v > dur) {
                cx.bad(t, key, format!("must be <= duration = {} s, got {}", num(dur), num(v)));
                return None;
            }
        }
    }
    Some(SolverSettings { method: method?, rtol: rtol?, atol: atol?, max_step: max_step?, output_interval: output_interval? })
}

fn controller(cx: &mut Ctx, t: &Tab) -> Option<Controller> {
    cx.check_keys(t, &["scan_cycle", "phase", "firmware_tick"], "");
    let scan_cycle = cx.number(t, "scan_cycle", Rule::gt(0.0, "s"), true);
    let phase = cx.number(t, "phase", Rule::within(0.0, 1.0, false, "of a scan cycle"), true);
    let firmware_tick = cx.number(t, "firmware_tick", Rule::gt(0.0, "s"), true);
    Some(Controller { scan_cycle: scan_cycle?, phase: phase?, firmware_tick: firmware_tick? })
}
