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
//!   `output_interval`, defaults in the `DEFAULT_*` constants below (measured: docs/accuracy.md).
//!   `fidelity` ("fast" | "default" | "reference", default "default") picks the tolerance defaults:
//!   `REFERENCE_*` (dopri5 only, no other solver key, no simplification), `DEFAULT_*`, or `FAST_*`.
//!   `simplify` (a list of "rigid-robot" | "no-friction", default none) drops those parts of the
//!   model explicitly (`sim::simplified`; their measured cost is in docs/accuracy.md).
//! - `[controller]` (firmware in the loop): `scan_cycle` (s > 0), `phase` in [0, 1),
//!   `firmware_tick` (s > 0), all required when the table is present.
use super::model::*;
use std::fmt;
use std::ops::Range;
use std::path::Path;
use toml_edit::{ImDocument, Item, TableLike, Value};

/// Default relative tolerance of the adaptive solver. Measured (docs/accuracy.md, `flinch bench`):
/// with DEFAULT_ATOL and DEFAULT_MAX_STEP every shipped scene is within 1.1e-4 of the reference on
/// peak forces and detection time (the target is 1e-2), and Tables 5-7 runs about 1,400 times
/// faster than real time on one core (rtol 1e-7 with a 1 ms cap: 1.5e-5, about 900 times).
pub const DEFAULT_RTOL: f64 = 1e-6;
/// Default absolute tolerance of the adaptive solver (m and m/s): 1e-3 of DEFAULT_RTOL, i.e.
/// relative accuracy down to 1 mm and 1 mm/s.
pub const DEFAULT_ATOL: f64 = 1e-9;
/// Default largest step (adaptive) or fixed step (fixed-step methods), s. 10 ms: at rtol 1e-6 the
/// step control sets the step wherever something happens; a 1 ms cap only added steps in free
/// flight (600 of 861 on Tables 5-7) for no measurable accuracy, while no cap at all changed
/// nothing more (docs/accuracy.md). It still keeps a step from jumping a whole short excursion.
pub const DEFAULT_MAX_STEP: f64 = 1e-2;
/// Tolerances of `fidelity = "reference"` (docs/accuracy.md: the reference the others are
/// measured against; tightening further changes no reported figure by more than 1e-6).
pub const REFERENCE_RTOL: f64 = 1e-10;
/// Absolute tolerance of `fidelity = "reference"` (m and m/s).
pub const REFERENCE_ATOL: f64 = 1e-13;
/// Relative tolerance of `fidelity = "fast"`: within 1.2e-3 of the reference on peak forces and
/// detection time on every shipped scene (docs/accuracy.md).
pub const FAST_RTOL: f64 = 1e-5;
/// Absolute tolerance of `fidelity = "fast"`.
pub const FAST_ATOL: f64 = 1e-8;
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
            issues: vec![SceneIssue {
                line: None,
                key: String::new(),
                message: format!("cannot read the scene file: {e}"),
            }],
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
            return Err(SceneError {
                file: file.to_string(),
                issues: vec![SceneIssue {
                    line,
                    key: String::new(),
                    message,
                }],
            });
        }
    };
    let mut cx = Ctx {
        text,
        issues: Vec::new(),
    };
    let scene = scene(&mut cx, doc.as_table());
    match scene {
        Some(scene) if cx.issues.is_empty() => Ok(scene),
        _ => {
            debug_assert!(
                !cx.issues.is_empty(),
                "a scene part failed without saying why"
            );
            cx.issues.sort_by_key(|i| i.line);
            Err(SceneError {
                file: file.to_string(),
                issues: cx.issues,
            })
        }
    }
}

fn line_at(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    text.as_bytes()[..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
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
        Rule {
            lo: Some((lo, false)),
            hi: None,
            unit,
        }
    }
    fn ge(lo: f64, unit: &'static str) -> Self {
        Rule {
            lo: Some((lo, true)),
            hi: None,
            unit,
        }
    }
    fn any(unit: &'static str) -> Self {
        Rule {
            lo: None,
            hi: None,
            unit,
        }
    }
    /// `[lo, hi]` when `hi_incl`, else `[lo, hi)`.
    fn within(lo: f64, hi: f64, hi_incl: bool, unit: &'static str) -> Self {
        Rule {
            lo: Some((lo, true)),
            hi: Some((hi, hi_incl)),
            unit,
        }
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
        let unit = if self.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", self.unit)
        };
        match (self.lo, self.hi) {
            (Some((l, true)), Some((h, hi))) => format!(
                "in [{}, {}{}{unit}",
                num(l),
                num(h),
                if hi { "]" } else { ")" }
            ),
            (Some((l, incl)), None) => {
                format!("{} {}{unit}", if incl { ">=" } else { ">" }, num(l))
            }
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
                self.err(
                    line,
                    tab.key(key),
                    format!("unknown key{what}; allowed keys: {list}"),
                );
            }
        }
    }

    fn missing(&mut self, tab: &Tab, key: &str, what: &str) {
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
            self.bad(
                tab,
                key,
                format!("must be a finite number {}, got {x}", rule.describe()),
            );
            return None;
        }
        if !rule.ok(x) {
            self.bad(
                tab,
                key,
                format!("must be {}, got {}", rule.describe(), num(x)),
            );
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
                self.bad(
                    tab,
                    key,
                    format!(
                        "must be {what} (write it without a decimal point), got {:?}",
                        f.value()
                    ),
                );
                None
            }
            _ => {
                self.wrong_type(tab, key, &what, item);
                None
            }
        }
    }

    fn boolean(&mut self, tab: &Tab, key: &str) -> Option<Option<bool>> {
        let Some(item) = tab.t.get(key) else {
            return Some(None);
        };
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
    fn choice<T: Copy>(
        &mut self,
        tab: &Tab,
        key: &str,
        options: &[(&str, T)],
        required: bool,
    ) -> Option<T> {
        let list = options
            .iter()
            .map(|(s, _)| format!("\"{s}\""))
            .collect::<Vec<_>>()
            .join(" | ");
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
    fn table<'d>(
        &mut self,
        tab: &Tab<'d>,
        key: &str,
        required: bool,
        what: &str,
    ) -> Option<Tab<'d>> {
        let Some(item) = tab.t.get(key) else {
            if required {
                self.missing(tab, key, &format!("a table ({what})"));
            }
            return None;
        };
        match item.as_table_like() {
            Some(t) => Some(Tab {
                path: tab.key(key),
                t,
                line: self.key_line(tab, key),
            }),
            None => {
                self.wrong_type(tab, key, &format!("a table ({what})"), item);
                None
            }
        }
    }
}

const ROOT_KEYS: &[&str] = &[
    "name",
    "duration",
    "motion",
    "robot",
    "tool",
    "decoupler",
    "target",
    "sensor",
    "solver",
    "controller",
];

const LAWS: &[(&str, DampingLaw)] = &[
    ("hunt-crossley", DampingLaw::HuntCrossley),
    ("lankarani-nikravesh", DampingLaw::LankaraniNikravesh),
    ("flores", DampingLaw::Flores),
    ("gonthier", DampingLaw::Gonthier),
    ("exact", DampingLaw::Exact),
];

fn scene(cx: &mut Ctx, root: &toml_edit::Table) -> Option<Scene> {
    let root = Tab {
        path: String::new(),
        t: root,
        line: Some(1),
    };
    cx.check_keys(&root, ROOT_KEYS, "");
    let name = cx.string(&root, "name", true);
    let duration_s = cx.number(&root, "duration", Rule::gt(0.0, "s"), true);

    let motion_tab = cx.table(&root, "motion", true, "the commanded flange motion");
    let motion = motion_tab.as_ref().and_then(|t| motion(cx, t));
    let robot = match cx.table(
        &root,
        "robot",
        false,
        "the robot compliance; omit it for a rigid robot",
    ) {
        Some(t) => robot(cx, &t).map(Some),
        None if root.t.contains_key("robot") => None,
        None => Some(None),
    };
    let tool = cx
        .table(&root, "tool", true, "the tool")
        .and_then(|t| tool(cx, &t));
    let gravity = motion.map(|m| m.gravity);
    let decoupler_tab = cx.table(
        &root,
        "decoupler",
        true,
        "what holds the tool on the flange",
    );
    let decoupler = decoupler_tab
        .as_ref()
        .and_then(|t| decoupler(cx, t, tool.map(|t| t.mass), gravity));
    let target_tab = cx.table(&root, "target", true, "what the tool runs into");
    let target = target_tab.as_ref().and_then(|t| target(cx, t));
    let sensor_tab = cx.table(
        &root,
        "sensor",
        false,
        "the collision detector; omit it and the robot never brakes",
    );
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
    let controller = match cx.table(
        &root,
        "controller",
        false,
        "the robot controller for `flinch hil`",
    ) {
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
    cx.check_keys(
        t,
        &[
            "speed",
            "accel",
            "decel",
            "dead_time",
            "gravity",
            "start_at_speed",
        ],
        "",
    );
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
    Some(Robot {
        mass: mass?,
        stiffness: stiffness?,
        damping: damping?,
    })
}

fn tool(cx: &mut Ctx, t: &Tab) -> Option<Tool> {
    cx.check_keys(t, &["mass"], "");
    Some(Tool {
        mass: cx.number(t, "mass", Rule::gt(0.0, "kg"), true)?,
    })
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

fn decoupler(
    cx: &mut Ctx,
    t: &Tab,
    tool_mass: Option<f64>,
    gravity: Option<f64>,
) -> Option<Decoupler> {
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
            Some(Decoupler::Linear(LinearDecoupler {
                stiffness: stiffness?,
                damping_ratio: damping_ratio?,
            }))
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

fn bistable(
    cx: &mut Ctx,
    t: &Tab,
    tool_mass: Option<f64>,
    gravity: Option<f64>,
) -> Option<Bistable> {
    let springs = cx.integer(t, "springs", 1, true);
    let spring_rate = cx.number(t, "spring_rate", Rule::gt(0.0, "N/m"), true);
    let free_length = cx.number(t, "free_length", Rule::gt(0.0, "m"), true);
    let height = cx.number(t, "height", Rule::gt(0.0, "m"), true);
    let front_stroke = cx.number(t, "front_stroke", Rule::gt(0.0, "m"), true);
    let back_stroke = cx.number(t, "back_stroke", Rule::gt(0.0, "m"), true);
    let (front_stop, back_stop) = end_stops(cx, t, tool_mass);
    let friction = match cx.table(
        t,
        "friction",
        false,
        "{ mu, v0 }; omit it for a frictionless slide",
    ) {
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
    if let (Some(n), Some(kb), Some(l0), Some(h), Some(c1), Some(mt), Some(gravity)) = (
        springs,
        spring_rate,
        free_length,
        height,
        front_stroke,
        tool_mass,
        gravity,
    ) {
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
        true => cx.number(
            t,
            "adiabatic_exponent",
            Rule::within(1.0, 5.0 / 3.0, true, ""),
            false,
        ),
        false => Some(DEFAULT_ADIABATIC_EXPONENT),
    };
    let friction_v0 = match t.t.contains_key("friction_v0") {
        true => cx.number(t, "friction_v0", Rule::gt(0.0, "m/s"), false),
        false => Some(DEFAULT_HYDRAULIC_FRICTION_V0),
    };
    let (front_stop, back_stop) = end_stops(cx, t, tool_mass);

    if let (Some(rp), Some(ro)) = (piston_radius, orifice_radius) {
        if ro >= rp {
            cx.bad(
                t,
                "orifice_radius",
                format!(
                    "must be < decoupler.piston_radius = {} m, got {}",
                    num(rp),
                    num(ro)
                ),
            );
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

/// The `front_stop` (linear) and `back_stop` (nonlinear) tables that the bi-stable and hydraulic
/// decouplers share, both required.
fn end_stops(cx: &mut Ctx, t: &Tab, tool_mass: Option<f64>) -> (Option<LinearStop>, Option<NonlinearStop>) {
    let front_stop = cx.table(
        t,
        "front_stop",
        true,
        "{ stiffness, damping } or { stiffness, restitution }",
    );
    let front_stop = front_stop.and_then(|s| linear_stop(cx, &s, tool_mass));
    let back_stop = cx.table(
        t,
        "back_stop",
        true,
        "{ stiffness, restitution, damping_law } or { stiffness, chi }",
    );
    let back_stop = back_stop.and_then(|s| nonlinear_stop(cx, &s));
    (front_stop, back_stop)
}

fn linear_stop(cx: &mut Ctx, t: &Tab, tool_mass: Option<f64>) -> Option<LinearStop> {
    cx.check_keys(t, &["stiffness", "damping", "restitution"], "");
    let stiffness = cx.number(t, "stiffness", Rule::gt(0.0, "N/m"), true);
    match (t.t.contains_key("damping"), t.t.contains_key("restitution")) {
        (true, true) => {
            cx.bad(
                t,
                "restitution",
                "give either damping (N s/m) or restitution, not both".into(),
            );
            None
        }
        (false, false) => {
            cx.missing(
                t,
                "damping",
                "damping (N s/m >= 0), or restitution in [0, 1] converted with the tool mass",
            );
            None
        }
        (true, false) => {
            let damping = cx.number(t, "damping", Rule::ge(0.0, "N s/m"), true);
            Some(LinearStop {
                stiffness: stiffness?,
                damping: damping?,
            })
        }
        (false, true) => {
            let e = cx.number(t, "restitution", Rule::within(0.0, 1.0, true, ""), true)?;
            let (k, m) = (stiffness?, tool_mass?);
            let damping = 2.0 * zeta_from_restitution(e) * (k * m).sqrt();
            Some(LinearStop {
                stiffness: k,
                damping,
            })
        }
    }
}

/// `restitution` + `damping_law` or `chi`; `default_law` is used when `damping_law` is absent
/// (`None`: the law is required).
fn contact_damping(
    cx: &mut Ctx,
    t: &Tab,
    default_law: Option<DampingLaw>,
) -> Option<ContactDamping> {
    let has_chi = t.t.contains_key("chi");
    let has_e = t.t.contains_key("restitution");
    let has_law = t.t.contains_key("damping_law");
    if has_chi {
        if has_e || has_law {
            let other = if has_e { "restitution" } else { "damping_law" };
            cx.bad(
                t,
                other,
                "give either chi (a fixed damping) or restitution with damping_law, not both"
                    .into(),
            );
            return None;
        }
        return cx
            .number(t, "chi", Rule::ge(0.0, "N s/m^2.5"), true)
            .map(ContactDamping::FixedChi);
    }
    if !has_e {
        cx.missing(
            t,
            "restitution",
            "restitution in [0, 1] (with damping_law), or chi (N s/m^2.5 >= 0)",
        );
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
    Some(ContactDamping::Restitution {
        restitution: e,
        law,
    })
}

fn nonlinear_stop(cx: &mut Ctx, t: &Tab) -> Option<NonlinearStop> {
    cx.check_keys(t, &["stiffness", "restitution", "damping_law", "chi"], "");
    let stiffness = cx.number(t, "stiffness", Rule::gt(0.0, "N/m^1.5"), true);
    let damping = contact_damping(cx, t, Some(DEFAULT_BACK_STOP_LAW));
    Some(NonlinearStop {
        stiffness: stiffness?,
        damping: damping?,
    })
}

fn target(cx: &mut Ctx, t: &Tab) -> Option<Target> {
    #[derive(Clone, Copy)]
    enum K {
        Obstacle,
        Object,
    }
    let kind = cx.choice(
        t,
        "kind",
        &[("obstacle", K::Obstacle), ("object", K::Object)],
        true,
    );
    let common = [
        "kind",
        "gap",
        "stiffness",
        "restitution",
        "damping_law",
        "chi",
    ];
    match kind {
        Some(K::Obstacle) => cx.check_keys(t, &common, " for kind = \"obstacle\""),
        Some(K::Object) => cx.check_keys(
            t,
            &[&common[..], &["mass", "floor_friction"]].concat(),
            " for kind = \"object\"",
        ),
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
            TargetKind::Object {
                mass: mass?,
                floor_friction,
            }
        }
    };
    Some(Target {
        kind,
        gap: gap?,
        stiffness: stiffness?,
        damping: damping?,
    })
}

fn sensor(cx: &mut Ctx, t: &Tab, decoupler: Option<&Decoupler>) -> Option<Sensor> {
    #[derive(Clone, Copy)]
    enum K {
        Travel,
        Force,
    }
    cx.check_keys(t, &["kind", "threshold"], "");
    let kind = cx.choice(
        t,
        "kind",
        &[("travel", K::Travel), ("force", K::Force)],
        true,
    );
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
                Some(Decoupler::Bistable(b)) => Some((
                    b.front_stroke + b.back_stroke,
                    "total stroke front_stroke + back_stroke",
                )),
                Some(Decoupler::Hydraulic(h)) => Some((h.stroke, "stroke")),
                Some(Decoupler::Linear(_)) | None => None,
            };
            if let Some((c, what)) = stroke {
                if threshold >= c {
                    cx.bad(
                        t,
                        "threshold",
                        format!(
                            "must be < the decoupler's {what} = {} m, got {}",
                            approx(c),
                            num(threshold)
                        ),
                    );
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
        fidelity: Fidelity::Default,
        simplify: Simplify::default(),
    }
}

fn solver(cx: &mut Ctx, t: &Tab, duration: Option<f64>) -> Option<SolverSettings> {
    cx.check_keys(
        t,
        &[
            "method",
            "rtol",
            "atol",
            "max_step",
            "output_interval",
            "fidelity",
            "simplify",
        ],
        "",
    );
    let d = default_solver();
    let fidelities = [
        ("fast", Fidelity::Fast),
        ("default", Fidelity::Default),
        ("reference", Fidelity::Reference),
    ];
    let fidelity = match t.t.contains_key("fidelity") {
        true => cx.choice(t, "fidelity", &fidelities, false),
        false => Some(d.fidelity),
    };
    let (rtol_default, atol_default) = match fidelity {
        Some(Fidelity::Fast) => (FAST_RTOL, FAST_ATOL),
        Some(Fidelity::Reference) => (REFERENCE_RTOL, REFERENCE_ATOL),
        _ => (d.rtol, d.atol),
    };
    if fidelity == Some(Fidelity::Reference) {
        // The reference is one fixed thing: nothing may loosen it.
        for key in ["method", "rtol", "atol", "simplify"] {
            if t.t.contains_key(key) {
                cx.bad(
                    t,
                    key,
                    format!("must not be set with fidelity = \"reference\" (dopri5 at rtol = {}, atol = {}, the full model)", num(REFERENCE_RTOL), num(REFERENCE_ATOL)),
                );
            }
        }
    }
    let methods = [
        ("dopri5", Method::Dopri5),
        ("rk4", Method::Rk4),
        ("semi-implicit-euler", Method::SemiImplicitEuler),
    ];
    let method = match t.t.contains_key("method") {
        true => cx.choice(t, "method", &methods, false),
        false => Some(d.method),
    };
    let mut opt = |key: &str, rule: Rule, default: f64| match t.t.contains_key(key) {
        true => cx.number(t, key, rule, false),
        false => Some(default),
    };
    let rtol = opt(
        "rtol",
        Rule::within(RTOL_RANGE.0, RTOL_RANGE.1, true, ""),
        rtol_default,
    );
    let atol = opt(
        "atol",
        Rule::within(ATOL_RANGE.0, ATOL_RANGE.1, true, ""),
        atol_default,
    );
    let max_step = opt("max_step", Rule::gt(0.0, "s"), d.max_step);
    let output_interval = opt("output_interval", Rule::ge(0.0, "s"), d.output_interval);
    let simplify = simplify(cx, t);
    if let Some(dur) = duration {
        for (key, v) in [("max_step", max_step), ("output_interval", output_interval)] {
            if let Some(v) = v.filter(|&v| v > dur) {
                cx.bad(
                    t,
                    key,
                    format!("must be <= duration = {} s, got {}", num(dur), num(v)),
                );
                return None;
            }
        }
    }
    Some(SolverSettings {
        method: method?,
        rtol: rtol?,
        atol: atol?,
        max_step: max_step?,
        output_interval: output_interval?,
        fidelity: fidelity?,
        simplify: simplify?,
    })
}

/// `solver.simplify`: a list of distinct names of simplifications.
fn simplify(cx: &mut Ctx, t: &Tab) -> Option<Simplify> {
    let mut out = Simplify::default();
    let Some(item) = t.t.get("simplify") else {
        return Some(out);
    };
    let what = "a list of \"rigid-robot\" | \"no-friction\"";
    let Some(list) = item.as_value().and_then(Value::as_array) else {
        cx.wrong_type(t, "simplify", what, item);
        return None;
    };
    let mut ok = true;
    for v in list.iter() {
        let flag = match v.as_str() {
            Some("rigid-robot") => &mut out.rigid_robot,
            Some("no-friction") => &mut out.no_friction,
            _ => {
                cx.bad(t, "simplify", format!("must be {what}, got {}", v.to_string().trim()));
                ok = false;
                continue;
            }
        };
        if *flag {
            cx.bad(t, "simplify", format!("lists {} twice", v.to_string().trim()));
            ok = false;
        }
        *flag = true;
    }
    ok.then_some(out)
}

fn controller(cx: &mut Ctx, t: &Tab) -> Option<Controller> {
    cx.check_keys(t, &["scan_cycle", "phase", "firmware_tick"], "");
    let scan_cycle = cx.number(t, "scan_cycle", Rule::gt(0.0, "s"), true);
    let phase = cx.number(
        t,
        "phase",
        Rule::within(0.0, 1.0, false, "of a scan cycle"),
        true,
    );
    let firmware_tick = cx.number(t, "firmware_tick", Rule::gt(0.0, "s"), true);
    Some(Controller {
        scan_cycle: scan_cycle?,
        phase: phase?,
        firmware_tick: firmware_tick?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every element present: bi-stable module, compliant robot, sensor, solver, controller.
    const BASE: &str = r#"name = "base"
duration = 0.6
[motion]
speed = 0.05
accel = 1.0
decel = 2.0
dead_time = 0.016
gravity = 0.0
[robot]
mass = 8.4
stiffness = 2.3e5
damping = 71.0
[tool]
mass = 0.75
[decoupler]
kind = "bistable"
springs = 2
spring_rate = 200.0
free_length = 0.05
height = 0.03
front_stroke = 0.015
back_stroke = 0.015
front_stop = { stiffness = 1e6, damping = 278.0 }
back_stop = { stiffness = 1e6, restitution = 0.6 }
friction = { mu = 0.12, v0 = 0.001 }
[target]
kind = "obstacle"
gap = 0.01
stiffness = 1e8
restitution = 0.65
damping_law = "hunt-crossley"
[sensor]
kind = "travel"
threshold = 0.005
[solver]
method = "rk4"
rtol = 1e-6
atol = 1e-9
max_step = 1e-4
output_interval = 1e-3
[controller]
scan_cycle = 0.016
phase = 0.5
firmware_tick = 1e-4
"#;

    /// Hydraulic module against a free object, chi given directly.
    const HYD: &str = r#"name = "hyd"
duration = 0.8
[motion]
speed = 1.0
accel = 5.0
decel = 5.0
dead_time = 0.07
gravity = 0.0
[tool]
mass = 0.048
[decoupler]
kind = "hydraulic"
stroke = 0.023
piston_radius = 0.020
orifice_radius = 0.008
gas_pressure = 1000.0
gas_volume = 7.63e-5
discharge_coefficient = 3.0
liquid_density = 900.0
dry_friction = 0.0
viscous_friction = 0.5
front_stop = { stiffness = 1e6, damping = 235.0 }
back_stop = { stiffness = 1e6, chi = 2e5 }
[target]
kind = "object"
mass = 0.246
gap = 0.15
stiffness = 0.6e6
chi = 1.35e6
[sensor]
kind = "travel"
threshold = 0.0015
"#;

    /// `base` with the unique `from` replaced by `to`.
    fn mutate(base: &str, from: &str, to: &str) -> String {
        assert_eq!(base.matches(from).count(), 1, "{from:?} must occur once");
        base.replacen(from, to, 1)
    }

    /// Expects `text` refused with an issue on `key`, at the line of `at`, whose message holds `allowed`.
    fn refused(text: &str, key: &str, at: &str, allowed: &str) {
        let err = parse(text, "bad.toml").expect_err("scene should be refused");
        let line = line_at(
            text,
            text.find(at)
                .unwrap_or_else(|| panic!("{at:?} not in the text")),
        );
        let shown = err.to_string();
        let issue = err
            .issues
            .iter()
            .find(|i| i.key == key)
            .unwrap_or_else(|| panic!("no issue on {key}:\n{shown}"));
        assert_eq!(issue.line, Some(line), "{shown}");
        assert!(
            issue.message.contains(allowed),
            "{:?} lacks {allowed:?}",
            issue.message
        );
        assert!(
            shown.contains(&format!("bad.toml:{line}: {key}: ")),
            "{shown}"
        );
    }

    /// One test per error path: replace `from` by `to` in `base`, expect `key` refused at `at`.
    macro_rules! case {
        ($name:ident, $base:expr, $from:expr, $to:expr, $key:expr, $at:expr, $allowed:expr) => {
            #[test]
            fn $name() {
                refused(&mutate($base, $from, $to), $key, $at, $allowed);
            }
        };
    }

    #[test]
    fn bases_load() {
        let s = parse(BASE, "base.toml").unwrap();
        assert_eq!(s.solver.method, Method::Rk4);
        assert_eq!(
            s.controller,
            Some(Controller {
                scan_cycle: 0.016,
                phase: 0.5,
                firmware_tick: 1e-4
            })
        );
        let h = parse(HYD, "hyd.toml").unwrap();
        let Decoupler::Hydraulic(d) = h.decoupler else {
            panic!("not hydraulic")
        };
        assert_eq!(d.adiabatic_exponent, DEFAULT_ADIABATIC_EXPONENT);
        assert_eq!(d.friction_v0, DEFAULT_HYDRAULIC_FRICTION_V0);
        assert_eq!(d.back_stop.damping, ContactDamping::FixedChi(2e5));
        assert_eq!(
            h.target.kind,
            TargetKind::Object {
                mass: 0.246,
                floor_friction: None
            }
        );
        assert_eq!(h.robot, None);
    }

    #[test]
    fn optional_elements_and_defaults() {
        let text = mutate(BASE, "[sensor]\nkind = \"travel\"\nthreshold = 0.005\n", "");
        let text = mutate(
            &text,
            "method = \"rk4\"\nrtol = 1e-6\natol = 1e-9\nmax_step = 1e-4\noutput_interval = 1e-3\n",
            "",
        );
        let text = mutate(&text, "friction = { mu = 0.12, v0 = 0.001 }\n", "");
        let text = mutate(
            &text,
            "[controller]\nscan_cycle = 0.016\nphase = 0.5\nfirmware_tick = 1e-4\n",
            "",
        );
        let s = parse(&text, "opt.toml").unwrap();
        assert_eq!(s.sensor, None);
        assert_eq!(s.controller, None);
        assert_eq!(s.solver, default_solver());
        assert_eq!(s.solver.rtol, DEFAULT_RTOL);
        assert!(!s.motion.start_at_speed);
        let Decoupler::Bistable(b) = s.decoupler else {
            panic!("not bistable")
        };
        assert_eq!(b.friction, None);
        assert_eq!(
            b.back_stop.damping,
            ContactDamping::Restitution {
                restitution: 0.6,
                law: DEFAULT_BACK_STOP_LAW
            }
        );
    }

    #[test]
    fn integers_are_accepted_as_numbers() {
        let s = parse(
            &mutate(BASE, "stiffness = 1e8", "stiffness = 100000000"),
            "int.toml",
        )
        .unwrap();
        assert_eq!(s.target.stiffness, 1e8);
    }

    #[test]
    fn front_stop_restitution_converts_with_the_tool_mass() {
        let with = |e: &str| {
            let s = parse(
                &mutate(BASE, "damping = 278.0 }", &format!("restitution = {e} }}")),
                "e.toml",
            )
            .unwrap();
            let Decoupler::Bistable(b) = s.decoupler else {
                panic!("not bistable")
            };
            b.front_stop.damping
        };
        let crit = 2.0 * (1e6_f64 * 0.75).sqrt();
        // e = 0.4: zeta = -ln 0.4 / sqrt(pi^2 + ln^2 0.4) = 0.27999...
        assert!(
            (with("0.4") / crit - 0.279_997).abs() < 1e-5,
            "{}",
            with("0.4") / crit
        );
        assert_eq!(with("0.0"), crit);
        assert_eq!(with("1.0"), 0.0);
        assert!((zeta_from_restitution(0.5) - 0.215_454).abs() < 1e-6);
    }

    #[test]
    fn start_at_speed_travel() {
        let text = mutate(
            BASE,
            "gravity = 0.0\n",
            "gravity = 0.0\nstart_at_speed = true\n",
        );
        assert!(parse(&text, "s.toml").unwrap().motion.start_at_speed);
        // Cruising from t = 0, 0.6 s at 0.05 m/s covers 0.03 m: a 0.029 m gap is reached, 0.031 m is not.
        assert!(parse(&mutate(&text, "gap = 0.01", "gap = 0.029"), "s.toml").is_ok());
        refused(
            &mutate(&text, "gap = 0.01", "gap = 0.031"),
            "target.gap",
            "gap = 0.031",
            "covers only 0.03 m",
        );
    }

    #[test]
    fn all_errors_are_reported_in_line_order() {
        let text = mutate(BASE, "mass = 0.75", "mass = -1");
        let text = mutate(&text, "speed = 0.05", "speed = \"fast\"");
        let text = mutate(&text, "phase = 0.5", "phase = 1.0");
        let err = parse(&text, "many.toml").unwrap_err();
        let keys: Vec<_> = err.issues.iter().map(|i| i.key.as_str()).collect();
        assert_eq!(keys, ["motion.speed", "tool.mass", "controller.phase"]);
        assert_eq!(err.to_string().lines().count(), 3);
        assert!(err.to_string().lines().all(|l| l.starts_with("many.toml:")));
    }

    #[test]
    fn toml_syntax_error_names_the_line() {
        let text = mutate(BASE, "decel = 2.0", "decel = = 2.0");
        let err = parse(&text, "syntax.toml").unwrap_err();
        assert_eq!(err.issues.len(), 1);
        assert_eq!(err.issues[0].line, Some(6));
        assert!(
            err.to_string().starts_with("syntax.toml:6: not valid TOML"),
            "{err}"
        );
    }

    #[test]
    fn duplicate_key_is_a_syntax_error() {
        let text = mutate(BASE, "decel = 2.0", "decel = 2.0\ndecel = 3.0");
        let err = parse(&text, "dup.toml").unwrap_err();
        assert_eq!(err.issues[0].line, Some(7), "{err}");
        assert!(err.issues[0].message.contains("duplicate key"), "{err}");
    }

    #[test]
    fn unreadable_file_names_the_file() {
        let err = load(Path::new("/nonexistent/flinch/none.toml")).unwrap_err();
        assert_eq!(err.file, "/nonexistent/flinch/none.toml");
        assert_eq!(err.issues[0].line, None);
        assert!(
            err.to_string()
                .starts_with("/nonexistent/flinch/none.toml: cannot read"),
            "{err}"
        );
    }

    #[test]
    fn number_rendering() {
        assert_eq!(num(-1.0), "-1");
        assert_eq!(num(1e-10), "1e-10");
        assert_eq!(num(2.3e5), "230000");
        assert_eq!(num(1e8), "1e8");
        assert_eq!(approx(0.028749999999999998), "0.02875");
    }

    // Top level.
    case!(
        root_unknown_key,
        BASE,
        "duration = 0.6\n",
        "duration = 0.6\ncolour = 1\n",
        "colour",
        "colour",
        "allowed keys: name, duration, motion"
    );
    case!(
        name_missing,
        BASE,
        "name = \"base\"\n",
        "",
        "name",
        "duration",
        "missing required key: a non-empty string"
    );
    case!(
        name_empty,
        BASE,
        "name = \"base\"",
        "name = \" \"",
        "name",
        "name",
        "must be a non-empty string"
    );
    case!(
        name_wrong_type,
        BASE,
        "name = \"base\"",
        "name = 3",
        "name",
        "name",
        "must be a non-empty string, got integer"
    );
    case!(
        duration_missing,
        BASE,
        "duration = 0.6\n",
        "",
        "duration",
        "name",
        "missing required key: a number > 0 s"
    );
    case!(
        duration_zero,
        BASE,
        "duration = 0.6",
        "duration = 0",
        "duration",
        "duration",
        "must be > 0 s, got 0"
    );
    case!(
        duration_nan,
        BASE,
        "duration = 0.6",
        "duration = nan",
        "duration",
        "duration",
        "must be a finite number > 0 s, got NaN"
    );
    case!(
        duration_inf,
        BASE,
        "duration = 0.6",
        "duration = inf",
        "duration",
        "duration",
        "must be a finite number > 0 s, got inf"
    );
    case!(
        duration_string,
        BASE,
        "duration = 0.6",
        "duration = \"0.6\"",
        "duration",
        "duration",
        "must be a number > 0 s, got string"
    );
    case!(
        motion_missing,
        BASE,
        "[motion]\nspeed = 0.05\naccel = 1.0\ndecel = 2.0\ndead_time = 0.016\ngravity = 0.0\n",
        "",
        "motion",
        "name",
        "missing required key: a table"
    );
    case!(
        tool_not_a_table,
        BASE,
        "[tool]\nmass = 0.75\n",
        "",
        "tool",
        "name",
        "missing required key: a table"
    );
    case!(
        tool_array_of_tables,
        BASE,
        "[tool]\n",
        "[[tool]]\n",
        "tool",
        "[[tool]]",
        "must be a table (the tool), got array of tables"
    );
    case!(target_inline_wrong_type, BASE, "[target]\nkind = \"obstacle\"\ngap = 0.01\nstiffness = 1e8\nrestitution = 0.65\ndamping_law = \"hunt-crossley\"\n", "", "target", "name", "missing required key: a table");
    case!(
        robot_not_a_table,
        HYD,
        "duration = 0.8\n",
        "duration = 0.8\nrobot = 5\n",
        "robot",
        "robot = 5",
        "must be a table"
    );

    // Motion.
    case!(
        motion_unknown_key,
        BASE,
        "gravity = 0.0\n",
        "gravity = 0.0\njerk = 3\n",
        "motion.jerk",
        "jerk",
        "allowed keys: speed, accel, decel, dead_time, gravity, start_at_speed"
    );
    case!(
        speed_zero,
        BASE,
        "speed = 0.05",
        "speed = 0",
        "motion.speed",
        "speed",
        "must be > 0 m/s, got 0"
    );
    case!(
        speed_missing,
        BASE,
        "speed = 0.05\n",
        "",
        "motion.speed",
        "[motion]",
        "missing required key: a number > 0 m/s"
    );
    case!(
        accel_negative,
        BASE,
        "accel = 1.0",
        "accel = -1",
        "motion.accel",
        "accel",
        "must be > 0 m/s^2, got -1"
    );
    case!(
        decel_zero,
        BASE,
        "decel = 2.0",
        "decel = 0.0",
        "motion.decel",
        "decel",
        "must be > 0 m/s^2, got 0"
    );
    case!(
        dead_time_negative,
        BASE,
        "dead_time = 0.016",
        "dead_time = -0.01",
        "motion.dead_time",
        "dead_time",
        "must be >= 0 s, got -0.01"
    );
    case!(
        gravity_missing,
        BASE,
        "gravity = 0.0\n",
        "",
        "motion.gravity",
        "[motion]",
        "a finite number m/s^2"
    );
    case!(
        gravity_inf,
        BASE,
        "gravity = 0.0",
        "gravity = -inf",
        "motion.gravity",
        "gravity",
        "must be a finite number"
    );
    case!(
        start_at_speed_wrong_type,
        BASE,
        "gravity = 0.0\n",
        "gravity = 0.0\nstart_at_speed = 1\n",
        "motion.start_at_speed",
        "start_at_speed",
        "must be true or false, got integer"
    );

    // Robot and tool.
    case!(
        robot_unknown_key,
        BASE,
        "damping = 71.0\n",
        "damping = 71.0\ninertia = 2\n",
        "robot.inertia",
        "inertia",
        "allowed keys: mass, stiffness, damping"
    );
    case!(
        robot_mass_zero,
        BASE,
        "mass = 8.4",
        "mass = 0",
        "robot.mass",
        "mass = 0",
        "must be > 0 kg, got 0"
    );
    case!(
        robot_stiffness_negative,
        BASE,
        "stiffness = 2.3e5",
        "stiffness = -2.3e5",
        "robot.stiffness",
        "stiffness = -2.3e5",
        "must be > 0 N/m, got -230000"
    );
    case!(
        robot_damping_negative,
        BASE,
        "damping = 71.0",
        "damping = -71",
        "robot.damping",
        "damping = -71",
        "must be >= 0 N s/m, got -71"
    );
    case!(
        robot_damping_missing,
        BASE,
        "damping = 71.0\n",
        "",
        "robot.damping",
        "[robot]",
        "missing required key: a number >= 0 N s/m"
    );
    case!(
        tool_mass_negative,
        BASE,
        "mass = 0.75",
        "mass = -1",
        "tool.mass",
        "mass = -1",
        "must be > 0 kg, got -1"
    );
    case!(
        tool_mass_missing,
        BASE,
        "mass = 0.75\n",
        "",
        "tool.mass",
        "[tool]",
        "missing required key: a number > 0 kg"
    );
    case!(
        tool_unknown_key,
        BASE,
        "mass = 0.75\n",
        "mass = 0.75\nlength = 1\n",
        "tool.length",
        "length",
        "allowed keys: mass"
    );

    // Decoupler kinds.
    case!(
        decoupler_kind_bad,
        BASE,
        "kind = \"bistable\"",
        "kind = \"springy\"",
        "decoupler.kind",
        "springy",
        "must be one of \"rigid\" | \"linear\" | \"bistable\" | \"hydraulic\", got \"springy\""
    );
    case!(
        decoupler_kind_missing,
        BASE,
        "kind = \"bistable\"\n",
        "",
        "decoupler.kind",
        "[decoupler]",
        "missing required key: one of \"rigid\" | \"linear\""
    );
    case!(
        decoupler_missing,
        BASE,
        "[decoupler]\nkind = \"bistable\"\n",
        "[decoupler2]\n",
        "decoupler",
        "name",
        "missing required key: a table"
    );
    case!(
        rigid_with_bistable_keys,
        BASE,
        "kind = \"bistable\"",
        "kind = \"rigid\"",
        "decoupler.springs",
        "springs",
        "unknown key for kind = \"rigid\"; allowed keys: kind"
    );
    case!(linear_stiffness_negative, BASE, "kind = \"bistable\"\nsprings = 2\nspring_rate = 200.0\nfree_length = 0.05\nheight = 0.03\nfront_stroke = 0.015\nback_stroke = 0.015\nfront_stop = { stiffness = 1e6, damping = 278.0 }\nback_stop = { stiffness = 1e6, restitution = 0.6 }\nfriction = { mu = 0.12, v0 = 0.001 }\n", "kind = \"linear\"\nstiffness = -5\ndamping_ratio = 1\n", "decoupler.stiffness", "stiffness = -5", "must be >= 0 N/m, got -5");
    case!(linear_damping_ratio_negative, BASE, "kind = \"bistable\"\nsprings = 2\nspring_rate = 200.0\nfree_length = 0.05\nheight = 0.03\nfront_stroke = 0.015\nback_stroke = 0.015\nfront_stop = { stiffness = 1e6, damping = 278.0 }\nback_stop = { stiffness = 1e6, restitution = 0.6 }\nfriction = { mu = 0.12, v0 = 0.001 }\n", "kind = \"linear\"\nstiffness = 50\ndamping_ratio = -1\n", "decoupler.damping_ratio", "damping_ratio", "must be >= 0, got -1");
    case!(
        linear_unknown_key,
        BASE,
        "kind = \"bistable\"",
        "kind = \"linear\"",
        "decoupler.springs",
        "springs",
        "unknown key for kind = \"linear\"; allowed keys: kind, stiffness, damping_ratio"
    );

    // Bi-stable.
    case!(
        springs_float,
        BASE,
        "springs = 2",
        "springs = 2.0",
        "decoupler.springs",
        "springs",
        "must be an integer >= 1 (write it without a decimal point), got 2.0"
    );
    case!(
        springs_zero,
        BASE,
        "springs = 2",
        "springs = 0",
        "decoupler.springs",
        "springs",
        "must be an integer >= 1, got 0"
    );
    case!(
        springs_string,
        BASE,
        "springs = 2",
        "springs = \"two\"",
        "decoupler.springs",
        "springs",
        "must be an integer >= 1, got string"
    );
    case!(
        springs_missing,
        BASE,
        "springs = 2\n",
        "",
        "decoupler.springs",
        "[decoupler]",
        "missing required key: an integer >= 1"
    );
    case!(
        spring_rate_zero,
        BASE,
        "spring_rate = 200.0",
        "spring_rate = 0",
        "decoupler.spring_rate",
        "spring_rate",
        "must be > 0 N/m, got 0"
    );
    case!(
        free_length_negative,
        BASE,
        "free_length = 0.05",
        "free_length = -0.05",
        "decoupler.free_length",
        "free_length",
        "must be > 0 m, got -0.05"
    );
    case!(
        height_zero,
        BASE,
        "height = 0.03",
        "height = 0",
        "decoupler.height",
        "height",
        "must be > 0 m, got 0"
    );
    case!(
        front_stroke_zero,
        BASE,
        "front_stroke = 0.015",
        "front_stroke = 0",
        "decoupler.front_stroke",
        "front_stroke",
        "must be > 0 m, got 0"
    );
    case!(
        back_stroke_zero,
        BASE,
        "back_stroke = 0.015",
        "back_stroke = 0.0",
        "decoupler.back_stroke",
        "back_stroke",
        "must be > 0 m, got 0"
    );
    case!(
        bistable_unknown_key,
        BASE,
        "springs = 2\n",
        "springs = 2\nstroke = 0.02\n",
        "decoupler.stroke",
        "stroke",
        "unknown key for kind = \"bistable\"; allowed keys: kind, springs, spring_rate"
    );
    case!(
        springs_do_not_hold_the_tool,
        BASE,
        "free_length = 0.05",
        "free_length = 0.03",
        "decoupler.free_length",
        "free_length",
        "need free_length > sqrt(height^2 + front_stroke^2) = 0.033541 m"
    );
    case!(
        front_stop_missing,
        BASE,
        "front_stop = { stiffness = 1e6, damping = 278.0 }\n",
        "",
        "decoupler.front_stop",
        "[decoupler]",
        "missing required key: a table ({ stiffness, damping } or { stiffness, restitution })"
    );
    case!(
        front_stop_not_table,
        BASE,
        "front_stop = { stiffness = 1e6, damping = 278.0 }",
        "front_stop = 1e6",
        "decoupler.front_stop",
        "front_stop",
        "must be a table ({ stiffness, damping } or { stiffness, restitution }), got float"
    );
    case!(
        front_stop_damping_negative,
        BASE,
        "damping = 278.0 }",
        "damping = -278.0 }",
        "decoupler.front_stop.damping",
        "front_stop",
        "must be >= 0 N s/m, got -278"
    );
    case!(
        front_stop_stiffness_zero,
        BASE,
        "front_stop = { stiffness = 1e6",
        "front_stop = { stiffness = 0",
        "decoupler.front_stop.stiffness",
        "front_stop",
        "must be > 0 N/m, got 0"
    );
    case!(
        front_stop_both,
        BASE,
        "damping = 278.0 }",
        "damping = 278.0, restitution = 0.4 }",
        "decoupler.front_stop.restitution",
        "front_stop",
        "give either damping (N s/m) or restitution, not both"
    );
    case!(
        front_stop_neither,
        BASE,
        ", damping = 278.0 }",
        " }",
        "decoupler.front_stop.damping",
        "front_stop",
        "missing required key: damping (N s/m >= 0), or restitution in [0, 1]"
    );
    case!(
        front_stop_restitution_high,
        BASE,
        "damping = 278.0 }",
        "restitution = 1.5 }",
        "decoupler.front_stop.restitution",
        "front_stop",
        "must be in [0, 1], got 1.5"
    );
    case!(
        front_stop_unknown_key,
        BASE,
        "damping = 278.0 }",
        "damping = 278.0, chi = 3 }",
        "decoupler.front_stop.chi",
        "front_stop",
        "allowed keys: stiffness, damping, restitution"
    );
    case!(
        back_stop_stiffness_negative,
        BASE,
        "back_stop = { stiffness = 1e6",
        "back_stop = { stiffness = -1",
        "decoupler.back_stop.stiffness",
        "back_stop",
        "must be > 0 N/m^1.5, got -1"
    );
    case!(
        back_stop_restitution_negative,
        BASE,
        "restitution = 0.6 }",
        "restitution = -0.6 }",
        "decoupler.back_stop.restitution",
        "back_stop",
        "must be in [0, 1], got -0.6"
    );
    case!(
        back_stop_chi_and_restitution,
        BASE,
        "restitution = 0.6 }",
        "restitution = 0.6, chi = 5.0 }",
        "decoupler.back_stop.restitution",
        "back_stop",
        "give either chi (a fixed damping) or restitution with damping_law, not both"
    );
    case!(
        back_stop_chi_and_law,
        BASE,
        "restitution = 0.6 }",
        "damping_law = \"flores\", chi = 5.0 }",
        "decoupler.back_stop.damping_law",
        "back_stop",
        "give either chi"
    );
    case!(
        back_stop_chi_negative,
        BASE,
        "restitution = 0.6 }",
        "chi = -5.0 }",
        "decoupler.back_stop.chi",
        "back_stop",
        "must be >= 0 N s/m^2.5, got -5"
    );
    case!(
        back_stop_no_damping,
        BASE,
        ", restitution = 0.6 }",
        " }",
        "decoupler.back_stop.restitution",
        "back_stop",
        "missing required key: restitution in [0, 1] (with damping_law), or chi"
    );
    case!(back_stop_law_bad, BASE, "restitution = 0.6 }", "restitution = 0.6, damping_law = \"hertz\" }", "decoupler.back_stop.damping_law", "back_stop", "must be one of \"hunt-crossley\" | \"lankarani-nikravesh\" | \"flores\" | \"gonthier\" | \"exact\", got \"hertz\"");
    case!(
        back_stop_law_without_restitution,
        BASE,
        "restitution = 0.6 }",
        "damping_law = \"hertz\" }",
        "decoupler.back_stop.damping_law",
        "back_stop",
        "must be one of"
    );
    case!(
        back_stop_unknown_key,
        BASE,
        "restitution = 0.6 }",
        "restitution = 0.6, damping = 3 }",
        "decoupler.back_stop.damping",
        "back_stop",
        "allowed keys: stiffness, restitution, damping_law, chi"
    );
    case!(
        back_stop_gonthier_zero,
        BASE,
        "restitution = 0.6 }",
        "restitution = 0, damping_law = \"gonthier\" }",
        "decoupler.back_stop.restitution",
        "back_stop",
        "must be in (0, 1] with damping_law \"flores\" or \"gonthier\""
    );
    case!(
        friction_unknown_key,
        BASE,
        "v0 = 0.001 }",
        "v0 = 0.001, static = 0.2 }",
        "decoupler.friction.static",
        "friction",
        "allowed keys: mu, v0"
    );
    case!(
        friction_mu_negative,
        BASE,
        "mu = 0.12",
        "mu = -0.12",
        "decoupler.friction.mu",
        "friction",
        "must be >= 0, got -0.12"
    );
    case!(
        friction_v0_negative,
        BASE,
        "v0 = 0.001 }",
        "v0 = -0.001 }",
        "decoupler.friction.v0",
        "friction",
        "must be >= 0 m/s, got -0.001"
    );
    case!(
        friction_v0_missing,
        BASE,
        ", v0 = 0.001 }",
        " }",
        "decoupler.friction.v0",
        "friction",
        "missing required key: a number >= 0 m/s"
    );
    case!(
        friction_not_table,
        BASE,
        "friction = { mu = 0.12, v0 = 0.001 }",
        "friction = 0.12",
        "decoupler.friction",
        "friction",
        "must be a table ({ mu, v0 }"
    );

    // Hydraulic.
    case!(
        stroke_zero,
        HYD,
        "stroke = 0.023",
        "stroke = 0",
        "decoupler.stroke",
        "stroke = 0",
        "must be > 0 m, got 0"
    );
    case!(
        piston_radius_negative,
        HYD,
        "piston_radius = 0.020",
        "piston_radius = -0.02",
        "decoupler.piston_radius",
        "piston_radius",
        "must be > 0 m, got -0.02"
    );
    case!(
        orifice_radius_zero,
        HYD,
        "orifice_radius = 0.008",
        "orifice_radius = 0",
        "decoupler.orifice_radius",
        "orifice_radius",
        "must be > 0 m, got 0"
    );
    case!(
        orifice_not_smaller,
        HYD,
        "orifice_radius = 0.008",
        "orifice_radius = 0.02",
        "decoupler.orifice_radius",
        "orifice_radius",
        "must be < decoupler.piston_radius = 0.02 m, got 0.02"
    );
    case!(
        gas_pressure_zero,
        HYD,
        "gas_pressure = 1000.0",
        "gas_pressure = 0",
        "decoupler.gas_pressure",
        "gas_pressure",
        "must be > 0 Pa, got 0"
    );
    case!(
        gas_volume_negative,
        HYD,
        "gas_volume = 7.63e-5",
        "gas_volume = -1",
        "decoupler.gas_volume",
        "gas_volume",
        "must be > 0 m^3, got -1"
    );
    case!(
        gas_driven_to_zero,
        HYD,
        "gas_volume = 7.63e-5",
        "gas_volume = 2.8e-5",
        "decoupler.gas_volume",
        "gas_volume",
        "must be > the volume the piston sweeps, pi * piston_radius^2 * stroke = 2.89027e-5 m^3"
    );
    case!(
        discharge_coefficient_zero,
        HYD,
        "discharge_coefficient = 3.0",
        "discharge_coefficient = 0",
        "decoupler.discharge_coefficient",
        "discharge_coefficient",
        "must be > 0, got 0"
    );
    case!(
        liquid_density_zero,
        HYD,
        "liquid_density = 900.0",
        "liquid_density = 0",
        "decoupler.liquid_density",
        "liquid_density",
        "must be > 0 kg/m^3, got 0"
    );
    case!(
        dry_friction_negative,
        HYD,
        "dry_friction = 0.0",
        "dry_friction = -1",
        "decoupler.dry_friction",
        "dry_friction",
        "must be >= 0 N, got -1"
    );
    case!(
        viscous_friction_negative,
        HYD,
        "viscous_friction = 0.5",
        "viscous_friction = -0.5",
        "decoupler.viscous_friction",
        "viscous_friction",
        "must be >= 0 N s/m, got -0.5"
    );
    case!(
        adiabatic_exponent_out_of_range,
        HYD,
        "viscous_friction = 0.5\n",
        "viscous_friction = 0.5\nadiabatic_exponent = 2\n",
        "decoupler.adiabatic_exponent",
        "adiabatic_exponent",
        "must be in [1, 1.6666666666666667], got 2"
    );
    case!(
        friction_v0_zero,
        HYD,
        "viscous_friction = 0.5\n",
        "viscous_friction = 0.5\nfriction_v0 = 0\n",
        "decoupler.friction_v0",
        "friction_v0",
        "must be > 0 m/s, got 0"
    );
    case!(
        hydraulic_missing_key,
        HYD,
        "liquid_density = 900.0\n",
        "",
        "decoupler.liquid_density",
        "[decoupler]",
        "missing required key: a number > 0 kg/m^3"
    );
    case!(
        hydraulic_unknown_key,
        HYD,
        "stroke = 0.023\n",
        "stroke = 0.023\nsprings = 1\n",
        "decoupler.springs",
        "springs",
        "unknown key for kind = \"hydraulic\"; allowed keys: kind, stroke, piston_radius"
    );
    case!(hydraulic_back_stop_missing, HYD, "back_stop = { stiffness = 1e6, chi = 2e5 }\n", "", "decoupler.back_stop", "[decoupler]", "missing required key: a table ({ stiffness, restitution, damping_law } or { stiffness, chi })");

    // Target.
    case!(
        target_kind_bad,
        BASE,
        "kind = \"obstacle\"",
        "kind = \"wall\"",
        "target.kind",
        "wall",
        "must be one of \"obstacle\" | \"object\", got \"wall\""
    );
    case!(
        target_gap_zero,
        BASE,
        "gap = 0.01",
        "gap = 0",
        "target.gap",
        "gap",
        "must be > 0 m, got 0"
    );
    case!(target_gap_never_closed, BASE, "gap = 0.01", "gap = 1", "target.gap", "gap", "the commanded motion covers only 0.02875 m in duration = 0.6 s, so the tool never reaches the target; must be < 0.02875 m, got 1");
    case!(
        target_stiffness_zero,
        BASE,
        "stiffness = 1e8",
        "stiffness = 0",
        "target.stiffness",
        "stiffness = 0",
        "must be > 0 N/m^1.5, got 0"
    );
    case!(
        target_restitution_high,
        BASE,
        "restitution = 0.65",
        "restitution = 1.2",
        "target.restitution",
        "restitution = 1.2",
        "must be in [0, 1], got 1.2"
    );
    case!(
        target_law_missing,
        BASE,
        "damping_law = \"hunt-crossley\"\n",
        "",
        "target.damping_law",
        "[target]",
        "missing required key: one of \"hunt-crossley\" | \"lankarani-nikravesh\""
    );
    case!(
        target_law_bad,
        BASE,
        "damping_law = \"hunt-crossley\"",
        "damping_law = \"kelvin\"",
        "target.damping_law",
        "kelvin",
        "must be one of \"hunt-crossley\""
    );
    case!(
        target_flores_zero,
        BASE,
        "restitution = 0.65\ndamping_law = \"hunt-crossley\"",
        "restitution = 0\ndamping_law = \"flores\"",
        "target.restitution",
        "restitution = 0\n",
        "the law divides by e"
    );
    case!(
        target_chi_and_restitution,
        HYD,
        "chi = 1.35e6",
        "chi = 1.35e6\nrestitution = 0.5",
        "target.restitution",
        "restitution",
        "give either chi"
    );
    case!(
        target_chi_negative,
        HYD,
        "chi = 1.35e6",
        "chi = -1.35e6",
        "target.chi",
        "chi = -1.35e6",
        "must be >= 0 N s/m^2.5, got -1.35e6"
    );
    case!(
        target_no_damping,
        HYD,
        "chi = 1.35e6\n",
        "",
        "target.restitution",
        "[target]",
        "missing required key: restitution in [0, 1] (with damping_law), or chi"
    );
    case!(obstacle_with_mass, BASE, "kind = \"obstacle\"\n", "kind = \"obstacle\"\nmass = 1\n", "target.mass", "mass = 1", "unknown key for kind = \"obstacle\"; allowed keys: kind, gap, stiffness, restitution, damping_law, chi");
    case!(
        obstacle_with_floor_friction,
        BASE,
        "kind = \"obstacle\"\n",
        "kind = \"obstacle\"\nfloor_friction = 0.3\n",
        "target.floor_friction",
        "floor_friction",
        "unknown key for kind = \"obstacle\""
    );
    case!(
        object_mass_missing,
        HYD,
        "mass = 0.246\n",
        "",
        "target.mass",
        "[target]",
        "missing required key: a number > 0 kg"
    );
    case!(
        object_mass_zero,
        HYD,
        "mass = 0.246",
        "mass = 0",
        "target.mass",
        "mass = 0\n",
        "must be > 0 kg, got 0"
    );
    case!(
        object_floor_friction_negative,
        HYD,
        "mass = 0.246\n",
        "mass = 0.246\nfloor_friction = -0.2\n",
        "target.floor_friction",
        "floor_friction",
        "must be >= 0, got -0.2"
    );
    case!(
        object_unknown_key,
        HYD,
        "mass = 0.246\n",
        "mass = 0.246\nradius = 0.02\n",
        "target.radius",
        "radius = 0.02\n",
        "allowed keys: kind, gap, stiffness, restitution, damping_law, chi, mass, floor_friction"
    );

    // Sensor.
    case!(
        sensor_kind_bad,
        BASE,
        "kind = \"travel\"",
        "kind = \"camera\"",
        "sensor.kind",
        "camera",
        "must be one of \"travel\" | \"force\", got \"camera\""
    );
    case!(
        sensor_threshold_zero,
        BASE,
        "threshold = 0.005",
        "threshold = 0",
        "sensor.threshold",
        "threshold",
        "must be > 0 m, got 0"
    );
    case!(
        sensor_force_threshold_negative,
        BASE,
        "kind = \"travel\"\nthreshold = 0.005",
        "kind = \"force\"\nthreshold = -25",
        "sensor.threshold",
        "threshold",
        "must be > 0 N, got -25"
    );
    case!(
        sensor_threshold_missing,
        BASE,
        "threshold = 0.005\n",
        "",
        "sensor.threshold",
        "[sensor]",
        "missing required key: a number > 0 m"
    );
    case!(
        sensor_beyond_bistable_stroke,
        BASE,
        "threshold = 0.005",
        "threshold = 0.03",
        "sensor.threshold",
        "threshold",
        "must be < the decoupler's total stroke front_stroke + back_stroke = 0.03 m, got 0.03"
    );
    case!(
        sensor_beyond_hydraulic_stroke,
        HYD,
        "threshold = 0.0015",
        "threshold = 0.03",
        "sensor.threshold",
        "threshold",
        "must be < the decoupler's stroke = 0.023 m, got 0.03"
    );
    case!(sensor_travel_on_rigid_tool, BASE, "kind = \"bistable\"\nsprings = 2\nspring_rate = 200.0\nfree_length = 0.05\nheight = 0.03\nfront_stroke = 0.015\nback_stroke = 0.015\nfront_stop = { stiffness = 1e6, damping = 278.0 }\nback_stop = { stiffness = 1e6, restitution = 0.6 }\nfriction = { mu = 0.12, v0 = 0.001 }\n", "kind = \"rigid\"\n", "sensor.kind", "kind = \"travel\"", "must be \"force\" for decoupler.kind = \"rigid\"");
    case!(
        sensor_unknown_key,
        BASE,
        "threshold = 0.005\n",
        "threshold = 0.005\nhysteresis = 0.001\n",
        "sensor.hysteresis",
        "hysteresis",
        "allowed keys: kind, threshold"
    );

    // Solver.
    case!(
        solver_method_bad,
        BASE,
        "method = \"rk4\"",
        "method = \"euler\"",
        "solver.method",
        "euler",
        "must be one of \"dopri5\" | \"rk4\" | \"semi-implicit-euler\", got \"euler\""
    );
    case!(
        solver_rtol_too_loose,
        BASE,
        "rtol = 1e-6",
        "rtol = 0.5",
        "solver.rtol",
        "rtol",
        "must be in [1e-13, 0.1], got 0.5"
    );
    case!(
        solver_rtol_zero,
        BASE,
        "rtol = 1e-6",
        "rtol = 0",
        "solver.rtol",
        "rtol",
        "must be in [1e-13, 0.1], got 0"
    );
    case!(
        solver_atol_negative,
        BASE,
        "atol = 1e-9",
        "atol = -1e-9",
        "solver.atol",
        "atol",
        "must be in [1e-15, 0.01], got -1e-9"
    );
    case!(
        solver_max_step_zero,
        BASE,
        "max_step = 1e-4",
        "max_step = 0",
        "solver.max_step",
        "max_step",
        "must be > 0 s, got 0"
    );
    case!(
        solver_max_step_beyond_duration,
        BASE,
        "max_step = 1e-4",
        "max_step = 1",
        "solver.max_step",
        "max_step",
        "must be <= duration = 0.6 s, got 1"
    );
    case!(
        solver_output_interval_negative,
        BASE,
        "output_interval = 1e-3",
        "output_interval = -1",
        "solver.output_interval",
        "output_interval",
        "must be >= 0 s, got -1"
    );
    case!(
        solver_output_interval_beyond_duration,
        BASE,
        "output_interval = 1e-3",
        "output_interval = 2",
        "solver.output_interval",
        "output_interval",
        "must be <= duration = 0.6 s, got 2"
    );
    case!(
        solver_unknown_key,
        BASE,
        "method = \"rk4\"\n",
        "method = \"rk4\"\norder = 4\n",
        "solver.order",
        "order",
        "allowed keys: method, rtol, atol, max_step, output_interval, fidelity, simplify"
    );
    case!(
        solver_fidelity_bad,
        BASE,
        "method = \"rk4\"\n",
        "method = \"rk4\"\nfidelity = \"exact\"\n",
        "solver.fidelity",
        "fidelity",
        "must be one of \"fast\" | \"default\" | \"reference\", got \"exact\""
    );
    case!(
        solver_reference_refuses_a_method,
        BASE,
        "method = \"rk4\"\n",
        "method = \"rk4\"\nfidelity = \"reference\"\n",
        "solver.method",
        "method = \"rk4\"",
        "must not be set with fidelity = \"reference\""
    );
    case!(
        solver_simplify_unknown,
        BASE,
        "method = \"rk4\"\n",
        "method = \"rk4\"\nsimplify = [\"rigid-tool\"]\n",
        "solver.simplify",
        "simplify",
        "must be a list of \"rigid-robot\" | \"no-friction\", got \"rigid-tool\""
    );
    case!(
        solver_simplify_twice,
        BASE,
        "method = \"rk4\"\n",
        "method = \"rk4\"\nsimplify = [\"no-friction\", \"no-friction\"]\n",
        "solver.simplify",
        "simplify",
        "lists \"no-friction\" twice"
    );
    case!(
        solver_simplify_not_a_list,
        BASE,
        "method = \"rk4\"\n",
        "method = \"rk4\"\nsimplify = \"no-friction\"\n",
        "solver.simplify",
        "simplify",
        "must be a list of"
    );

    #[test]
    fn fidelity_sets_the_tolerance_defaults_and_explicit_keys_win() {
        let no_tol = BASE.replace("rtol = 1e-6\n", "").replace("atol = 1e-9\n", "").replace("method = \"rk4\"\n", "");
        let with = |extra: &str| parse(&no_tol.replace("[solver]\n", &format!("[solver]\n{extra}")), "f.toml").unwrap().solver;
        let r = with("fidelity = \"reference\"\n");
        assert_eq!((r.method, r.rtol, r.atol, r.fidelity), (Method::Dopri5, REFERENCE_RTOL, REFERENCE_ATOL, Fidelity::Reference));
        let f = with("fidelity = \"fast\"\n");
        assert_eq!((f.rtol, f.atol), (FAST_RTOL, FAST_ATOL));
        let f = with("fidelity = \"fast\"\nrtol = 1e-4\nsimplify = [\"rigid-robot\"]\n");
        assert_eq!((f.rtol, f.atol), (1e-4, FAST_ATOL));
        assert_eq!(f.simplify, Simplify { rigid_robot: true, no_friction: false });
        let d = with("");
        assert_eq!((d.rtol, d.atol, d.fidelity), (DEFAULT_RTOL, DEFAULT_ATOL, Fidelity::Default));
    }

    // Controller.
    case!(
        controller_scan_cycle_zero,
        BASE,
        "scan_cycle = 0.016",
        "scan_cycle = 0",
        "controller.scan_cycle",
        "scan_cycle",
        "must be > 0 s, got 0"
    );
    case!(
        controller_phase_one,
        BASE,
        "phase = 0.5",
        "phase = 1.0",
        "controller.phase",
        "phase",
        "must be in [0, 1) of a scan cycle, got 1"
    );
    case!(
        controller_phase_negative,
        BASE,
        "phase = 0.5",
        "phase = -0.1",
        "controller.phase",
        "phase",
        "must be in [0, 1) of a scan cycle, got -0.1"
    );
    case!(
        controller_tick_missing,
        BASE,
        "firmware_tick = 1e-4\n",
        "",
        "controller.firmware_tick",
        "[controller]",
        "missing required key: a number > 0 s"
    );
    case!(
        controller_unknown_key,
        BASE,
        "phase = 0.5\n",
        "phase = 0.5\nlatency = 0.01\n",
        "controller.latency",
        "latency",
        "allowed keys: scan_cycle, phase, firmware_tick"
    );
}
