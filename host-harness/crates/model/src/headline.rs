//! What a scene simulates, in one line, and what its `name` claims that the scene contradicts.
//!
//! A scene's `name` is free text written once; after `--set motion.speed=0.5`, an edited copy of a
//! shipped scene or `design --speed`, the name can say "V_c = 0.2 m/s" while 0.5 m/s is simulated.
//! Every scene command prints the name, then `simulated: ...` (V_c, DT, the module, the tool, the
//! target), then one `NAME MISMATCH:` line per claim of the name the scene contradicts. The claims
//! read: `V_c = X m/s`, `DT = N ms|s`, `H = N mm`, `m_t = X kg`, `N g object`, the module word
//! (bi-stable, hydraulic, rigid tool, linear / spring-damper, free tool), a body region and
//! clamped / free, and `(mode N)` (checked against a run by [`mode_mismatch`]). Numbers compare at
//! the name's own precision: "V_c = 0.2" matches 0.2, 0.20 and 0.204, not 0.25.

use crate::body::{BodyContact, PRESETS};
use crate::scene::{Decoupler, Scene, Sensor, TargetKind};

/// A scene's headline.
#[derive(Debug, Clone, PartialEq)]
pub struct Headline {
    /// The scene's `name`, as written.
    pub name: String,
    /// What is simulated: V_c, DT, module, tool, target and gap.
    pub simulated: String,
    /// One sentence per claim of the name that the scene contradicts.
    pub mismatches: Vec<String>,
}

impl Headline {
    /// The lines every scene command prints first: the name, `  simulated: ...`, and a
    /// `  NAME MISMATCH: ...` line per contradiction.
    pub fn lines(&self) -> String {
        let mut o = format!("{}\n  simulated: {}\n", self.name, self.simulated);
        for m in &self.mismatches {
            o.push_str(&format!("  NAME MISMATCH: {m}\n"));
        }
        o
    }

    /// A title for a figure or a page: the name, what was simulated, and `(name says ...)` when
    /// the name is contradicted.
    pub fn title(&self) -> String {
        format!("{}\nsimulated: {}{}", self.name, self.short(), self.flag())
    }

    /// The name with its flag: `name (NAME MISMATCH: name says V_c = 0.2 m/s)`, or the name.
    pub fn flagged_name(&self) -> String {
        format!("{}{}", self.name, self.flag())
    }

    /// ` (NAME MISMATCH: name says ...)` when the name is contradicted, else empty.
    fn flag(&self) -> String {
        if self.mismatches.is_empty() {
            return String::new();
        }
        let says: Vec<&str> = self.mismatches.iter().map(|m| m.split(';').next().unwrap_or(m).trim_start_matches("the name says ")).collect();
        format!(" (NAME MISMATCH: name says {})", says.join(", "))
    }

    /// The simulated text up to its first `;` (V_c and DT), for titles.
    pub fn short(&self) -> &str {
        self.simulated.split(';').next().unwrap_or(&self.simulated)
    }
}

fn mm(x: f64) -> String {
    format!("{:.1} mm", x * 1e3)
}

fn g(x: f64) -> String {
    let s = format!("{x:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

/// The module as simulated.
fn module(sc: &Scene) -> String {
    let switch = match sc.sensor {
        Some(Sensor::Travel { threshold }) => format!(", travel switch at {}", mm(threshold)),
        Some(Sensor::Force { threshold }) => format!(", force sensor at {} N", g(threshold)),
        None => ", no sensor".to_string(),
    };
    match &sc.decoupler {
        Decoupler::Rigid => format!("rigid tool{switch}"),
        Decoupler::Linear(l) if l.stiffness == 0.0 => format!("free tool (linear, k = 0, zeta = {}){switch}", g(l.damping_ratio)),
        Decoupler::Linear(l) => format!("linear spring-damper module (k = {} N/m, zeta = {}){switch}", g(l.stiffness), g(l.damping_ratio)),
        Decoupler::Bistable(b) => format!(
            "bi-stable module ({} springs x {} N/m, H = {}, C1 + C2 = {:.1} + {}{switch})",
            b.springs,
            g(b.spring_rate),
            mm(b.height),
            b.front_stroke * 1e3,
            mm(b.back_stroke)
        ),
        Decoupler::Hydraulic(h) => format!("hydraulic module (stroke L = {}, p10 = {} kPa{switch})", mm(h.stroke), g(h.gas_pressure * 1e-3)),
    }
}

fn target(sc: &Scene) -> String {
    let what = match sc.target.kind {
        TargetKind::Obstacle => "hard surface".to_string(),
        TargetKind::Object { mass, .. } => format!("free object of {} g", g(mass * 1e3)),
        TargetKind::BodyRegion(b) => format!("{} ({}), {}", b.region.label, if b.contact == BodyContact::QuasiStatic { "clamped, quasi-static" } else { "free, transient" }, if b.area_m2 > 0.0 { format!("{} cm^2", g(b.area_m2 * 1e4)) } else { String::new() }),
    };
    format!("{what} at a gap of {}", mm(sc.target.gap))
}

/// V_c and DT (or the stopping table and DT to its signal), as simulated.
fn motion(sc: &Scene) -> String {
    let m = &sc.motion;
    let start = if m.start_at_speed { " (cruising from t = 0)" } else { "" };
    match &m.stopping {
        Some(_) => format!("V_c = {:.3} m/s{start}, robot stopping table, DT = {:.1} ms to the stop signal", m.speed, m.dead_time * 1e3),
        None => format!("V_c = {:.3} m/s{start}, DT = {:.1} ms, d_c = {} m/s^2", m.speed, m.dead_time * 1e3, g(m.decel)),
    }
}

/// The number after `pat` in `name` (`0.2` in "V_c = 0.2 m/s"), its decimals and the word after it.
fn number_after<'a>(name: &'a str, pat: &str) -> Option<(f64, usize, &'a str)> {
    let i = name.find(pat)? + pat.len();
    let rest = &name[i..];
    let end = rest.find(|c: char| !(c.is_ascii_digit() || c == '.')).unwrap_or(rest.len());
    let num = rest[..end].trim_end_matches('.');
    let x: f64 = num.parse().ok()?;
    let decimals = num.split_once('.').map_or(0, |(_, d)| d.len());
    let unit = rest[end..].trim_start().split(|c: char| !c.is_alphanumeric() && c != '/' && c != '_').next().unwrap_or("");
    Some((x, decimals, unit))
}

/// True when `simulated` rounds to `claimed` at `decimals` decimals.
fn same(claimed: f64, decimals: usize, simulated: f64) -> bool {
    let k = 10f64.powi(decimals as i32);
    ((simulated * k).round() - (claimed * k).round()).abs() < 0.5
}

/// The module word the name uses first, as one of the decoupler kinds.
fn claimed_module(name: &str) -> Option<(&'static str, usize)> {
    let lower = name.to_lowercase();
    let words: [(&str, &str); 9] = [
        ("bi-stable", "bistable"),
        ("bistable", "bistable"),
        ("hydraulic", "hydraulic"),
        ("rigid tool", "rigid"),
        ("rigid end-effector", "rigid"),
        ("spring-damper", "linear"),
        ("linear", "linear"),
        ("free tool", "free"),
        ("decoupled tool", "free"),
    ];
    words.iter().filter_map(|(w, k)| lower.find(w).map(|i| (*k, i))).min_by_key(|(_, i)| *i)
}

fn simulated_module(d: &Decoupler) -> &'static str {
    match d {
        Decoupler::Rigid => "rigid",
        Decoupler::Linear(l) if l.stiffness == 0.0 => "free",
        Decoupler::Linear(_) => "linear",
        Decoupler::Bistable(_) => "bistable",
        Decoupler::Hydraulic(_) => "hydraulic",
    }
}

fn module_word(k: &str) -> &'static str {
    match k {
        "rigid" => "a rigid tool",
        "free" => "a free tool (linear, k = 0)",
        "linear" => "a linear spring-damper module",
        "bistable" => "a bi-stable module",
        _ => "a hydraulic module",
    }
}

/// The claims of the name the scene contradicts.
fn mismatches(sc: &Scene) -> Vec<String> {
    let mut out = number_mismatches(sc, &sc.name);
    out.extend(word_mismatches(sc, &sc.name));
    out
}

/// The numeric claims of `text` (V_c, DT, H, m_t, an object's grams) that the scene contradicts:
/// what a longer text about the scene (the report's description) is checked for, since its words
/// may speak of other scenes.
pub fn number_mismatches(sc: &Scene, text: &str) -> Vec<String> {
    let name = text;
    let mut out = Vec::new();
    if let Some((x, d, _)) = number_after(name, "V_c = ") {
        if !same(x, d, sc.motion.speed) {
            out.push(format!("the name says V_c = {} m/s; simulated V_c = {:.3} m/s", g(x), sc.motion.speed));
        }
    }
    if let Some((x, d, unit)) = number_after(name, "DT = ") {
        let (sim, shown) = if unit == "s" { (sc.motion.dead_time, format!("{} s", g(x))) } else { (sc.motion.dead_time * 1e3, format!("{} ms", g(x))) };
        if !same(x, d, sim) {
            out.push(format!("the name says DT = {shown}; simulated DT = {:.1} ms", sc.motion.dead_time * 1e3));
        }
    }
    if let Some((x, d, _)) = number_after(name, "H = ") {
        match &sc.decoupler {
            Decoupler::Bistable(b) if same(x, d, b.height * 1e3) => {}
            Decoupler::Bistable(b) => out.push(format!("the name says H = {} mm; simulated H = {:.1} mm", g(x), b.height * 1e3)),
            _ => out.push(format!("the name says H = {} mm (a bi-stable height); the module simulated has none", g(x))),
        }
    }
    if let Some((x, d, _)) = number_after(name, "m_t = ") {
        if !same(x, d, sc.tool.mass) {
            out.push(format!("the name says m_t = {} kg; simulated m_t = {} kg", g(x), g(sc.tool.mass)));
        }
    }
    if let Some(i) = name.find(" g object") {
        let digits: String = name[..i].chars().rev().take_while(|c| c.is_ascii_digit() || *c == '.').collect::<Vec<_>>().into_iter().rev().collect();
        if let Ok(x) = digits.parse::<f64>() {
            let d = digits.split_once('.').map_or(0, |(_, d)| d.len());
            match sc.target.kind {
                TargetKind::Object { mass, .. } if same(x, d, mass * 1e3) => {}
                TargetKind::Object { mass, .. } => out.push(format!("the name says a {} g object; simulated object {} g", g(x), g(mass * 1e3))),
                _ => out.push(format!("the name says a {} g object; the target simulated is not a free object", g(x))),
            }
        }
    }
    out
}

/// The module, body region and contact words of `name` that the scene contradicts.
fn word_mismatches(sc: &Scene, name: &str) -> Vec<String> {
    let mut out = Vec::new();
    if let Some((claim, _)) = claimed_module(name) {
        let sim = simulated_module(&sc.decoupler);
        // A free tool is a linear decoupler with k = 0: "linear" in the name allows either.
        if claim != sim && !(claim == "linear" && sim == "free") {
            out.push(format!("the name says {}; simulated {}", module_word(claim), module_word(sim)));
        }
    }
    let lower = name.to_lowercase();
    let named_region = PRESETS.iter().find(|p| {
        let word = p.name.replace('_', " ");
        lower.split(|c: char| !c.is_alphanumeric() && c != ' ').any(|part| part.split_whitespace().collect::<Vec<_>>().join(" ").contains(&word)) && (lower.contains("annex a") || lower.contains("iso/ts") || matches!(sc.target.kind, TargetKind::BodyRegion(_)))
    });
    match (sc.target.kind, named_region) {
        (TargetKind::BodyRegion(b), Some(p)) if b.region.name != p.name => {
            out.push(format!("the name says {}; simulated {}", p.label, b.region.label));
        }
        (TargetKind::BodyRegion(_), _) | (_, None) => {}
        (_, Some(p)) => out.push(format!("the name says {} (a body region); the target simulated is not a body region", p.label)),
    }
    if let TargetKind::BodyRegion(b) = sc.target.kind {
        let says_clamped = lower.contains("clamped") || lower.contains("quasi-static") || lower.contains("quasi_static");
        let says_free = lower.split(|c: char| !c.is_alphanumeric()).any(|w| w == "free" || w == "transient") && !says_clamped;
        if says_clamped && b.contact != BodyContact::QuasiStatic {
            out.push("the name says clamped (quasi-static); simulated free (transient) contact".to_string());
        }
        if says_free && b.contact != BodyContact::Transient {
            out.push("the name says free (transient); simulated clamped (quasi-static) contact".to_string());
        }
    }
    out
}

/// The headline of a scene.
pub fn headline(sc: &Scene) -> Headline {
    let robot = match sc.robot {
        Some(r) => format!("compliant robot m_r = {} kg", g(r.mass)),
        None => "rigid robot".to_string(),
    };
    let simulated = format!("{}; {}, m_t = {} kg; {}; {robot}", motion(sc), module(sc), g(sc.tool.mass), target(sc));
    Headline { name: sc.name.clone(), simulated, mismatches: mismatches(sc) }
}

/// The working mode the name claims (`(mode 3)`), if any.
pub fn claimed_mode(name: &str) -> Option<u8> {
    number_after(name, "(mode ").and_then(|(x, d, _)| (d == 0 && (1.0..=3.0).contains(&x)).then_some(x as u8))
}

/// The name's `(mode N)` against the mode a run reached.
pub fn mode_mismatch(name: &str, mode: Option<u8>) -> Option<String> {
    let claimed = claimed_mode(name)?;
    (Some(claimed) != mode).then(|| format!("the name says mode {claimed}; the run reached {}", mode.map_or("no working mode (no back end-stop)".to_string(), |m| format!("mode {m}"))))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::overrides::{apply, Set};

    fn shipped(name: &str, sets: &[&str]) -> Scene {
        let sets: Vec<Set> = sets.iter().map(|s| Set::parse(s).unwrap()).collect();
        apply(name, crate::shipped::get(name).unwrap().to_string(), &sets).unwrap().scene
    }

    #[test]
    fn no_shipped_scene_contradicts_its_name() {
        for name in crate::shipped::names() {
            let text = crate::shipped::get(name).unwrap();
            let Ok(sc) = crate::scene::parse(text, name) else { continue };
            let h = headline(&sc);
            assert!(h.mismatches.is_empty(), "{name}: {:?}", h.mismatches);
            // The report reads the first comment block the same way.
            let d = number_mismatches(&sc, &crate::shipped::description(text));
            assert!(d.is_empty(), "{name}'s description: {d:?}");
            assert!(h.simulated.starts_with("V_c = "), "{name}: {}", h.simulated);
        }
    }

    #[test]
    fn an_override_the_name_contradicts_is_flagged() {
        let h = headline(&shipped("body_hand", &["motion.speed=0.5"]));
        assert!(h.simulated.starts_with("V_c = 0.500 m/s, DT = 16.0 ms"), "{}", h.simulated);
        assert_eq!(h.mismatches, vec!["the name says V_c = 0.2 m/s; simulated V_c = 0.500 m/s".to_string()]);
        assert!(h.lines().contains("  NAME MISMATCH: the name says V_c = 0.2 m/s"));
        assert!(h.title().ends_with("V_c = 0.2 m/s\nsimulated: V_c = 0.500 m/s, DT = 16.0 ms, d_c = 2 m/s^2 (NAME MISMATCH: name says V_c = 0.2 m/s)"), "{}", h.title());
        // The name's precision: 0.2 matches 0.204, not 0.25.
        assert!(headline(&shipped("body_hand", &["motion.speed=0.204"])).mismatches.is_empty());
        assert_eq!(headline(&shipped("body_hand", &["motion.speed=0.25"])).mismatches.len(), 1);
        let h = headline(&shipped("body_hand", &["target.region=face", "target.contact=\"transient\""]));
        assert_eq!(h.mismatches.len(), 2, "{:?}", h.mismatches);
        let h = headline(&shipped("table12_hydraulic_object_dt10", &["motion.dead_time=0.03"]));
        assert_eq!(h.mismatches, vec!["the name says DT = 10 ms; simulated DT = 30.0 ms".to_string()]);
        let h = headline(&shipped("table4_bistable_136g", &["target.mass=0.246"]));
        assert_eq!(h.mismatches.len(), 1, "{:?}", h.mismatches);
        assert!(h.mismatches[0].contains("136 g object; simulated object 246 g"), "{:?}", h.mismatches);
    }

    #[test]
    fn the_mode_claim_is_checked_against_the_run() {
        assert_eq!(claimed_mode("Tables 5-7, V_c = 0.25 m/s (mode 3)"), Some(3));
        assert!(mode_mismatch("x (mode 3)", Some(3)).is_none());
        assert!(mode_mismatch("x (mode 3)", Some(1)).unwrap().contains("the run reached mode 1"));
        assert!(mode_mismatch("no claim", Some(1)).is_none());
    }
}
