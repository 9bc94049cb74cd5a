//! `[robot]`: the robot's compliance at the flange, a base-excited mass (eq 33,
//! `plant/robot.rs`); absent, the robot is rigid.
//!
//! Either given as lumped values (`mass`, `stiffness`, `damping`: Table 7's m_r, k_r, c_r) or
//! reduced from the robot's URDF at a configuration (`urdf`, `base_link`, `tip_link`, `joints`,
//! `direction`, `joint_stiffness`, `joint_damping`; thesis eq 10-16, `src/kinematics`). The
//! reduced values go into the same [`Robot`], so the plant uses them exactly as Table 7's, and
//! they must lie in the same ranges.
use super::check::{approx, num, Bound::*, Ctx, Key, SceneError, SceneIssue, Span, Tab, Ty};
use super::model::Robot;
use flinch_kinematics::{self as kinematics, Chain, KinError, Reduced};
use std::path::{Path, PathBuf};
use toml_edit::{ImDocument, Item, Value};

/// The `[robot]` table in the top level.
pub const TABLE: Key = Key::of(
    "robot",
    Ty::Table("the robot compliance; omit it for a rigid robot"),
    "the robot compliance",
)
.optional("a rigid robot: x_r = x_c");

/// m_r.
pub const MASS: Key = Key::number("mass", "kg", Incl(0.1), Incl(500.0), "effective mass at the flange: 8.4 kg for the Viper s650 (Table 7), a few hundred kg for the largest arms", "m_r, the robot's effective mass at the flange");
/// k_r.
pub const STIFFNESS: Key = Key::number("stiffness", "N/m", Incl(1e3), Incl(1e8), "flange stiffness of arms: 2.3e5 N/m for the Viper s650 (Table 7), 1e5-1e7 N/m for industrial arms", "k_r, the robot's stiffness at the flange along the approach");
/// c_r.
pub const DAMPING: Key = Key::number("damping", "N s/m", Incl(0.0), Incl(1e5), "71 N s/m for the Viper s650 (Table 7); 1e5 N s/m is beyond critical for the stiffest, heaviest arm in range", "c_r, the robot's damping at the flange");

/// The URDF (instead of mass, stiffness, damping).
pub const URDF: Key = Key::of("urdf", Ty::Text, "the robot's URDF file, relative to the scene file: m_r, k_r, c_r are then reduced from joint space (thesis eq 10-16); replaces mass, stiffness, damping")
    .optional("mass, stiffness and damping are given");
/// The chain's first link.
pub const BASE_LINK: Key = Key::of("base_link", Ty::Text, "the URDF link the chain starts from (fixed; `direction` is in its frame); with urdf");
/// The flange.
pub const TIP_LINK: Key = Key::of("tip_link", Ty::Text, "the URDF link at the flange: its frame's origin is where the tool is held; with urdf");
/// q.
pub const JOINTS: Key = Key::of("joints", Ty::Table(PER_JOINT), "q, the configuration just before the collision (Table 7), rad (revolute) or m (prismatic); with urdf");
/// u.
pub const DIRECTION: Key = Key::of("direction", Ty::Table("a list [x, y, z] of numbers, not all zero"), "the approach direction in the base_link frame (any length); with urdf");
/// diag K_q.
pub const JOINT_STIFFNESS: Key = Key::of("joint_stiffness", Ty::Table(PER_JOINT), "K_q's diagonal (eq 11), N m/rad (revolute) or N/m (prismatic); with urdf");
/// diag D_q.
pub const JOINT_DAMPING: Key = Key::of("joint_damping", Ty::Table(PER_JOINT), "D_q's diagonal (eq 11), N m s/rad (revolute) or N s/m (prismatic); with urdf");

const PER_JOINT: &str = "one number per moving joint: a list in chain order from base_link to tip_link, or a table by URDF joint name";

/// The range of each configuration value: revolute.
pub const Q_REVOLUTE: Span = Span { lo: Incl(-2.0 * std::f64::consts::PI), hi: Incl(2.0 * std::f64::consts::PI), unit: "rad", source: "one turn either way holds every pose of a joint" };
/// Prismatic.
pub const Q_PRISMATIC: Span = Span { lo: Incl(-10.0), hi: Incl(10.0), unit: "m", source: "beyond the stroke of a robot's linear axis" };
/// Joint stiffness.
pub const K_JOINT: Span = Span { lo: Incl(1e2), hi: Incl(1e9), unit: "N m/rad or N/m", source: "joint stiffness of arms is 1e4-1e7 N m/rad (harmonic and cycloidal drives)" };
/// Joint damping.
pub const D_JOINT: Span = Span { lo: Incl(0.0), hi: Incl(1e6), unit: "N m s/rad or N s/m", source: "beyond critical for the stiffest joint at the largest inertia in range" };
/// Direction components.
const U_SPAN: Span = Span { lo: Incl(-1e3), hi: Incl(1e3), unit: "", source: "a direction: only its orientation matters" };

/// The keys of `[robot]`.
pub const KEYS: &[Key] = &[MASS, STIFFNESS, DAMPING, URDF, BASE_LINK, TIP_LINK, JOINTS, DIRECTION, JOINT_STIFFNESS, JOINT_DAMPING];

/// The URDF keys.
const URDF_KEYS: [&Key; 7] = [&URDF, &BASE_LINK, &TIP_LINK, &JOINTS, &DIRECTION, &JOINT_STIFFNESS, &JOINT_DAMPING];

/// The URDFs shipped in `scenes/robots/`, embedded so the shipped scenes run from any directory.
const SHIPPED_URDFS: &[(&str, &str)] = &[
    ("robots/two_link.urdf", include_str!("../../../../../scenes/robots/two_link.urdf")),
    ("robots/viper_s650_standin.urdf", include_str!("../../../../../scenes/robots/viper_s650_standin.urdf")),
];

/// A `[robot]` given by its URDF: what `flinch robot` prints and sweeps.
#[derive(Debug, Clone)]
pub struct UrdfRobot {
    /// The URDF as named in messages (resolved against the scene file).
    pub urdf: String,
    /// The chain base_link -> tip_link.
    pub chain: Chain,
    /// q, rad or m, chain order.
    pub joints: Vec<f64>,
    /// The approach direction, base frame.
    pub direction: [f64; 3],
    /// K_q's diagonal.
    pub joint_stiffness: Vec<f64>,
    /// D_q's diagonal.
    pub joint_damping: Vec<f64>,
}

impl UrdfRobot {
    /// m_r, k_r, c_r at the scene's configuration.
    pub fn reduce(&self) -> Result<Reduced, KinError> {
        self.reduce_at(&self.joints)
    }

    /// m_r, k_r, c_r at another configuration.
    pub fn reduce_at(&self, q: &[f64]) -> Result<Reduced, KinError> {
        kinematics::reduce(&self.chain, q, self.direction, &self.joint_stiffness, &self.joint_damping)
    }
}

/// The `[robot]` of a scene's text when it is given by a URDF (`None` for lumped values or a
/// rigid robot); `file` names the scene and is the path `urdf` is relative to.
pub fn urdf_robot(text: &str, file: &str) -> Result<Option<UrdfRobot>, SceneError> {
    let fail = |issues: Vec<SceneIssue>| SceneError { file: file.to_string(), issues };
    let doc = ImDocument::parse(text).map_err(|e| fail(vec![SceneIssue { line: None, key: String::new(), message: format!("not valid TOML: {}", e.message().trim()) }]))?;
    let Some(t) = doc.as_table().get("robot").and_then(Item::as_table_like) else { return Ok(None) };
    if !t.contains_key(URDF.name) {
        return Ok(None);
    }
    let mut cx = Ctx { text, file, issues: Vec::new(), tables: &[] };
    let tab = Tab { path: "robot".into(), t, line: None };
    let spec = read_urdf_robot(&mut cx, &tab);
    match spec {
        Some(s) if cx.issues.is_empty() => Ok(Some(s)),
        _ => {
            let mut issues = cx.issues;
            issues.sort_by_key(|i| i.line);
            Err(fail(issues))
        }
    }
}

/// The files a scene's text refers to, as (name, text): its URDF, read as a run reads it (none
/// when the scene names none, or it cannot be read: the validator then refuses the scene). What a
/// study's hash must cover with the scene's text (`flinch sample --merge`).
pub fn referenced_files(text: &str, file: &str) -> Vec<(String, String)> {
    let Ok(doc) = ImDocument::parse(text) else { return Vec::new() };
    let rel = doc.as_table().get("robot").and_then(Item::as_table_like).and_then(|t| t.get(URDF.name)).and_then(Item::as_str).map(str::to_string);
    rel.and_then(|r| read_urdf(file, &r).ok()).into_iter().collect()
}

/// Where `urdf` points: relative to the scene file's folder, else, for a shipped scene run by name
/// only (its file name ends in " (shipped)"), the shipped URDF. A user's scene whose URDF is
/// missing is refused, never given the project's stand-in robot in its place. Returns the name for
/// messages and the text.
fn read_urdf(scene_file: &str, rel: &str) -> Result<(String, String), String> {
    let p = Path::new(rel);
    let path: PathBuf = if p.is_absolute() || scene_file == "<stdin>" {
        p.to_path_buf()
    } else {
        Path::new(scene_file).parent().map_or_else(|| p.to_path_buf(), |d| d.join(p))
    };
    // Through the one reader: a FIFO, a device or a directory is refused by name at once, and no
    // URDF is read past its cap (16 MiB).
    match flinch_output::input::read_text(&path, flinch_output::input::Kind::Urdf) {
        Ok(text) => Ok((path.display().to_string(), text)),
        Err(e) => {
            let key = rel.trim_start_matches("./");
            match SHIPPED_URDFS.iter().find(|(k, _)| *k == key) {
                Some((k, text)) if std::fs::symlink_metadata(&path).is_err() && scene_file.ends_with(" (shipped)") => Ok((format!("scenes/{k}"), text.to_string())),
                _ => Err(format!("cannot read the URDF: {e}")),
            }
        }
    }
}

/// Reports a [`KinError`] at the scene key it comes from.
fn kin_bad(cx: &mut Ctx, t: &Tab, e: &KinError) {
    let key = match e.element.as_str() {
        k @ ("joints" | "direction" | "joint_stiffness" | "joint_damping" | "base_link" | "tip_link") => k,
        _ => "urdf",
    };
    cx.bad(t, key, e.to_string());
}

/// One number per chain joint: a list in chain order, or a table by joint name.
fn per_joint(cx: &mut Ctx, t: &Tab, key: &Key, chain: &Chain, span: impl Fn(usize) -> Span) -> Option<Vec<f64>> {
    let n = chain.dof();
    let names = chain.joint_names.join(", ");
    if let Some(table) = t.t.get(key.name).and_then(Item::as_table_like) {
        let mut out = vec![f64::NAN; n];
        let mut ok = true;
        for (name, v) in table.iter() {
            let Some(i) = chain.joint_names.iter().position(|j| j == name) else {
                cx.bad(t, key.name, format!("\"{name}\" is not a moving joint of the chain \"{}\" -> \"{}\" ({names})", chain.base_link, chain.tip_link));
                ok = false;
                continue;
            };
            let x = match v.as_value() {
                Some(Value::Integer(k)) => *k.value() as f64,
                Some(Value::Float(f)) => *f.value(),
                _ => {
                    cx.bad(t, key.name, format!("{name} must be a number"));
                    ok = false;
                    continue;
                }
            };
            let s = span(i);
            if !x.is_finite() || !s.contains(x) {
                cx.bad(t, key.name, format!("{name}: {}", s.refuse(x)));
                ok = false;
                continue;
            }
            out[i] = x;
        }
        let missing: Vec<&str> = chain.joint_names.iter().zip(&out).filter(|(_, x)| x.is_nan()).map(|(j, _)| j.as_str()).collect();
        if ok && !missing.is_empty() {
            cx.bad(t, key.name, format!("gives no value for {}; the chain has {n} moving joints ({names})", missing.join(", ")));
            return None;
        }
        return ok.then_some(out);
    }
    // A list longer than the chain is refused by its length below; its extra items are checked
    // against the last joint's span (the span of an index past the chain does not exist).
    let out = cx.numbers(t, key, &key.what(), usize::MAX, |i| span(i.min(n.saturating_sub(1))))?;
    if out.len() != n {
        cx.bad(
            t,
            key.name,
            format!("has {} values; the chain \"{}\" -> \"{}\" has {n} moving joints ({names})", out.len(), chain.base_link, chain.tip_link),
        );
        return None;
    }
    Some(out)
}

fn read_urdf_robot(cx: &mut Ctx, t: &Tab) -> Option<UrdfRobot> {
    let rel = cx.string(t, &URDF);
    let base = cx.string(t, &BASE_LINK);
    let tip = cx.string(t, &TIP_LINK);
    let direction = cx.numbers(t, &DIRECTION, &DIRECTION.what(), usize::MAX, |_| U_SPAN);
    let direction = match direction {
        Some(d) if d.len() == 3 && d.iter().any(|x| *x != 0.0) => Some([d[0], d[1], d[2]]),
        Some(d) => {
            cx.bad(t, DIRECTION.name, format!("must be {}, got {} values{}", DIRECTION.what(), d.len(), if d.len() == 3 { ", all zero" } else { "" }));
            None
        }
        None => None,
    };
    let (rel, base, tip) = (rel?, base?, tip?);
    let (label, text) = match read_urdf(cx.file, &rel) {
        Ok(x) => x,
        Err(m) => {
            cx.bad(t, URDF.name, m);
            return None;
        }
    };
    let chain = match Chain::from_urdf_str(&text, &label, &base, &tip) {
        Ok(c) => c,
        Err(e) => {
            kin_bad(cx, t, &e);
            return None;
        }
    };
    let kinds = chain.joint_kinds.clone();
    let joints = per_joint(cx, t, &JOINTS, &chain, |i| if kinds.get(i) == Some(&kinematics::JointKind::Revolute) { Q_REVOLUTE } else { Q_PRISMATIC });
    let k = per_joint(cx, t, &JOINT_STIFFNESS, &chain, |_| K_JOINT);
    let d = per_joint(cx, t, &JOINT_DAMPING, &chain, |_| D_JOINT);
    let joints = joints?;
    // Inside the URDF's own joint limits.
    for (i, q) in joints.iter().enumerate() {
        if let Some((lo, hi)) = chain.joint_limits[i] {
            if *q < lo || *q > hi {
                cx.bad(
                    t,
                    JOINTS.name,
                    format!("joint \"{}\" at {} is outside its URDF <limit> [{}, {}] ({label})", chain.joint_names[i], num(*q), num(lo), num(hi)),
                );
            }
        }
    }
    Some(UrdfRobot { urdf: label, chain, joints, direction: direction?, joint_stiffness: k?, joint_damping: d? })
}

/// Reads `[robot]`.
pub(super) fn robot(cx: &mut Ctx, t: &Tab) -> Option<Robot> {
    cx.check_keys(t, KEYS, "");
    if t.has(URDF.name) {
        for k in [&MASS, &STIFFNESS, &DAMPING] {
            if t.has(k.name) {
                cx.bad(t, k.name, format!("is given with urdf, which reduces {} from the URDF; give one or the other", k.name));
            }
        }
        let spec = read_urdf_robot(cx, t)?;
        let r = match spec.reduce() {
            Ok(r) => r,
            Err(e) => {
                kin_bad(cx, t, &e);
                return None;
            }
        };
        // The reduced values must lie where lumped ones would be accepted.
        let mut ok = true;
        for (key, x) in [(&MASS, r.mass_kg), (&STIFFNESS, r.stiffness_npm), (&DAMPING, r.damping_nspm)] {
            let s = key.span().expect("number keys");
            if !s.contains(x) {
                cx.bad(t, URDF.name, format!("reduces to {} = {} at this configuration and direction, outside the range of [robot] {}: {}", key.name, approx(x), key.name, s.refuse(x)));
                ok = false;
            }
        }
        return ok.then_some(Robot { mass: r.mass_kg, stiffness: r.stiffness_npm, damping: r.damping_nspm });
    }
    for k in URDF_KEYS {
        if t.has(k.name) {
            cx.bad(t, k.name, "is only read with urdf; give urdf, or remove it and give mass, stiffness, damping".to_string());
        }
    }
    let mass = cx.number(t, &MASS);
    let stiffness = cx.number(t, &STIFFNESS);
    let damping = cx.number(t, &DAMPING);
    Some(Robot {
        mass: mass?,
        stiffness: stiffness?,
        damping: damping?,
    })
}
