//! `flinch design SCENE --body-region REGION|all`: how fast may the robot go near a person's body
//! region (ISO/TS 15066 Annex A, flinch_model::body), with the scene's module and with a rigid tool.
//!
//! For each region the scene's body-region target is set to that region (its Table A.3 mass and
//! spring, its Table A.2 limits; the scene's contact kind, area and gap kept; a `mass` or
//! `stiffness` override applies to the scene's own region only) and `motion.speed` is searched
//! for the largest speed whose run holds, by a log-spaced scan from 5 mm/s to 5 m/s and a
//! bisection of the first boundary (the same search as `flinch design`'s speed limit):
//!
//! - **with the module** (the scene as it stands) and with a **rigid tool** (`[decoupler] kind =
//!   "rigid"`, the tool's mass joining the robot's as scenes/tables5-7_rigid.toml, with a force
//!   sensor in the tool: `--rigid-sensor`, default 25 N, the thesis's rigid end-effector, Ch.
//!   3.1.2), both judged on the body limits alone (`body_limits_pass`: the peak force and pressure
//!   of the whole run, including any push through a bottomed module), so the two compare fairly;
//! - and, with the module, the largest speed at which the run is `safe` (flinch_sim::verdict, the one
//!   definition: the body limits hold *and* the stroke is not exhausted while touching the body).
//!   That is the speed to quote for the module: beyond it the module has bottomed and the robot
//!   pushes through its stack, which the stroke rule does not accept whatever the force.
//!
//! Beside each, the Annex A closed form `v = F / sqrt(mu k)`, mu = (1/m_H + 1/m_R)^-1
//! (clamped: mu = m_R), F the limit that applies, with the moving mass m_R stated: the tool alone
//! (m_t) with the module, whose soft decoupler lets the tool meet the body on its own; the robot's
//! effective mass with the tool (m_r + m_t) for a rigid tool, infinite without `[robot]` (the
//! prescribed flange motion). It counts only the impact's kinetic energy: not the robot driving on
//! after contact until it has detected and braked, not the robot's compliance, not the stroke.
//!
//! Each candidate starts cruising at V_c ([`GAP_M`] from the body, `motion.start_at_speed = true`:
//! the contact happens at the commanded speed, Annex A's v) and its `duration` covers the contact,
//! 0.5 s to detect, the dead time, braking and 0.3 s of ring-down.

use flinch_model::body::{self, BodyContact, BodyTarget, Preset};
use flinch_model::scene::{Decoupler, Scene, TargetKind};
use crate::sweep::Template;
use flinch_sim::verdict::mps;
use serde::Serialize;

/// The default force threshold of the rigid tool's sensor, N (Ch. 3.1.2: the rigid end-effector of
/// Tables 6-7 stops on 25 N, scenes/tables5-7_rigid.toml).
pub const RIGID_SENSOR_N: f64 = 25.0;

/// Every candidate starts cruising at V_c (`motion.start_at_speed`) this far from the body, m: the
/// contact happens at the commanded speed, as Annex A's v, whatever the speed and the scene's
/// acceleration.
pub const GAP_M: f64 = 0.005;

/// The speeds scanned before the bisection: log-spaced from 5 mm/s to 5 m/s (the validator's
/// largest speed).
fn scan() -> Vec<f64> {
    let (lo, hi, n) = (0.005f64, 5.0f64, 24);
    (0..n).map(|i| (lo.ln() + (hi.ln() - lo.ln()) * i as f64 / (n - 1) as f64).exp()).collect()
}

/// One tool configuration's answer for one region.
#[derive(Debug, Clone, Serialize)]
pub struct Answer {
    /// Largest simulated speed at which the body-region limits hold (force and pressure, the
    /// whole run; `body_limits_pass`), m/s.
    pub speed_simulated_mps: Option<f64>,
    /// With the module: the largest simulated speed at which the run is `safe` (crate::verdict:
    /// the body limits hold *and* the stroke is not exhausted while touching the body), m/s; null
    /// for a rigid tool (its stroke rule always fails) or when not found (`safe_search_note`).
    pub speed_safe_mps: Option<f64>,
    /// Why `speed_safe_mps` is null with a module.
    pub safe_search_note: Option<String>,
    /// Why there is none (no speed holds, or every speed scanned does).
    pub search_note: Option<String>,
    /// The Annex A closed form with `moving_mass_kg`, m/s; null where the contact is not permitted
    /// or the moving mass is infinite in a clamped contact.
    pub speed_closed_form_mps: Option<f64>,
    /// m_R of the closed form, kg; null: infinite (the prescribed flange motion).
    pub moving_mass_kg: Option<f64>,
    /// The run at the simulated speed: its peak force on the body, N.
    pub peak_force_at_limit_n: Option<f64>,
    /// Whether the stroke held at the simulated speed (null for a rigid tool).
    pub stroke_held_at_limit: Option<bool>,
    /// True when every speed simulated held (no limit found up to the largest speed the scene
    /// validator accepts): `speed_simulated_mps` is then null.
    pub holds_at_every_speed: bool,
}

/// One region's answers.
#[derive(Debug, Clone, Serialize)]
pub struct RegionAnswer {
    /// The region's scene name (e.g. "hand").
    pub region: String,
    /// Table A.2's words.
    pub label: String,
    /// m_H, kg.
    pub effective_mass_kg: f64,
    /// k, N/m.
    pub stiffness_n_per_m: f64,
    /// The force limit that applies, N (null: the contact is not permitted).
    pub force_limit_n: Option<f64>,
    /// The pressure limit that applies, Pa.
    pub pressure_limit_pa: Option<f64>,
    /// With the scene's module (null when the scene's tool is already rigid).
    pub with_module: Option<Answer>,
    /// With a rigid tool.
    pub rigid_tool: Answer,
    /// with_module / rigid_tool simulated speeds, when both exist.
    pub speed_ratio: Option<f64>,
}

/// `flinch design --body-region`'s answers.
#[derive(Debug, Clone, Serialize)]
pub struct BodyDesign {
    /// Scene name.
    pub scene: String,
    /// "transient" or "quasi_static" (the scene's).
    pub contact: String,
    /// Contact area, m^2.
    pub contact_area_m2: f64,
    /// The module's kind ("bistable", "hydraulic", "linear"), null when the scene's tool is rigid.
    pub module: Option<String>,
    /// DT used, s.
    pub dead_time_s: f64,
    /// m_t, kg.
    pub tool_mass_kg: f64,
    /// m_r of `[robot]`, kg; null without it (a prescribed flange motion).
    pub robot_mass_kg: Option<f64>,
    /// The rigid tool's force-sensor threshold, N.
    pub rigid_sensor_threshold_n: f64,
    /// Per region, head to foot.
    pub regions: Vec<RegionAnswer>,
    /// How the answers were obtained and what they assume, for people.
    pub notes: Vec<String>,
}

/// One configuration's candidate scenes.
struct Cand<'a> {
    t: &'a Template,
    dead_time: f64,
    rigid: bool,
}

impl Cand<'_> {
    fn scene(&self, v: f64) -> Option<Scene> {
        let m = &self.t.base.motion;
        let duration = (GAP_M / v + 0.5 + self.dead_time + v / m.decel + 0.3).min(60.0);
        self.t.with(&[("motion.speed", v), ("motion.dead_time", self.dead_time), ("target.gap", GAP_M), ("duration", duration)]).ok()
    }
    /// Some(true) where the run holds (module: `safe`; rigid: the body limits), None where the
    /// candidate is refused or fails to run.
    fn holds(&self, v: f64, whole_verdict: bool) -> Option<bool> {
        let s = self.scene(v)?;
        let r = flinch_sim::run_to_conclusion(&s).ok()?;
        // A run whose tool never reached the body confirms nothing.
        r.t_contact?;
        Some(if whole_verdict { r.safe } else { r.body_limits_pass == Some(true) })
    }
    fn answer(&self, b: &BodyTarget, m_r: Option<f64>) -> Answer {
        let closed = b.closed_form_speed(m_r.unwrap_or(f64::INFINITY));
        let mut a = Answer { speed_simulated_mps: None, search_note: None, speed_closed_form_mps: closed, moving_mass_kg: m_r, peak_force_at_limit_n: None, stroke_held_at_limit: None, holds_at_every_speed: false, speed_safe_mps: None, safe_search_note: None };
        if b.limits().is_none() {
            a.search_note = Some(format!("transient contact with the {} is not permitted (ISO/TS 15066): no speed", b.region.label));
            return a;
        }
        let xs = scan();
        if !self.rigid {
            let g = |v: f64| self.holds(v, true);
            match crate::search::boundary(&xs, &g, true, 16, mps) {
                Ok((v, _)) => a.speed_safe_mps = Some(v),
                Err(e) => {
                    // Say why the slowest candidate is not safe: the run's own first failure (a
                    // free body part bounced off below the switching force is never detected, so
                    // the robot never stops: not concluded).
                    let why = self.scene(xs[0]).and_then(|s| flinch_sim::run_to_conclusion(&s).ok()).and_then(|r| r.failures.first().cloned());
                    a.safe_search_note = Some(format!(
                        "speed search over {}..{}: {e}{}",
                        mps(xs[0]),
                        mps(xs[xs.len() - 1]),
                        why.map_or_else(String::new, |w| format!("; at {}: {w}", mps(xs[0])))
                    ));
                }
            }
        }
        let f = |v: f64| self.holds(v, false);
        match crate::search::boundary(&xs, &f, true, 16, mps) {
            Ok((v, _)) => {
                a.speed_simulated_mps = Some(v);
                if let Some(r) = self.scene(v).and_then(|s| flinch_sim::run_to_conclusion(&s).ok()) {
                    a.peak_force_at_limit_n = r.body_peak_force_n;
                    a.stroke_held_at_limit = (!self.rigid).then_some(!r.stroke_exhausted);
                }
            }
            Err(e) => {
                a.holds_at_every_speed = e.starts_with("no boundary");
                a.search_note = Some(format!("speed search over {}..{}: {e}", mps(xs[0]), mps(xs[xs.len() - 1])));
            }
        }
        a
    }
}

/// The regions asked for: one name or "all".
pub fn regions(which: &str) -> Result<Vec<&'static Preset>, String> {
    if which == "all" {
        return Ok(body::PRESETS.iter().collect());
    }
    body::preset(which).map(|p| vec![p]).ok_or_else(|| format!("--body-region: must be one of \"all\" | {}, got {which:?}", body::REGION_NAMES.iter().map(|n| format!("\"{n}\"")).collect::<Vec<_>>().join(" | ")))
}

/// The input checks of [`design`], before it simulates (`design::refusal_of`): `None` when good.
pub fn refusal(t: &Template, which: &str, dead_time: Option<f64>, rigid_sensor_n: f64) -> Option<String> {
    if let Err(e) = regions(which) {
        return Some(e);
    }
    if !matches!(t.base.target.kind, TargetKind::BodyRegion(_)) {
        return Some("target.kind: flinch design --body-region needs a [target] with kind = \"body_region\" (its contact, area and gap are used for every region)".into());
    }
    if dead_time.is_some_and(|d| !(d >= 0.0 && d.is_finite())) {
        return Some(format!("--dead-time: must be >= 0 and finite, got {}", dead_time.unwrap_or(f64::NAN)));
    }
    (!(rigid_sensor_n.is_finite() && rigid_sensor_n > 0.0)).then(|| format!("--rigid-sensor: must be > 0 and finite, got {rigid_sensor_n}"))
}

/// Answers `--body-region` for a scene whose target is a body region.
pub fn design(t: &Template, which: &str, dead_time: Option<f64>, rigid_sensor_n: f64) -> Result<BodyDesign, String> {
    let base = &t.base;
    let TargetKind::BodyRegion(own) = base.target.kind else {
        return Err("target.kind: flinch design --body-region needs a [target] with kind = \"body_region\" (its contact, area and gap are used for every region)".into());
    };
    if let Some(d) = dead_time {
        if !(d >= 0.0 && d.is_finite()) {
            return Err(format!("--dead-time: must be >= 0 and finite, got {d}"));
        }
    }
    if !(rigid_sensor_n.is_finite() && rigid_sensor_n > 0.0) {
        return Err(format!("--rigid-sensor: must be > 0 and finite, got {rigid_sensor_n}"));
    }
    let dt = dead_time.unwrap_or(base.motion.dead_time);
    let module = match &base.decoupler {
        Decoupler::Rigid => None,
        Decoupler::Linear(_) => Some("linear"),
        Decoupler::Bistable(_) => Some("bistable"),
        Decoupler::Hydraulic(_) => Some("hydraulic"),
    };
    let m_t = base.tool.mass;
    let m_r = base.robot.map(|r| r.mass);
    let mut out = Vec::new();
    for p in regions(which)? {
        let name = p.name;
        let keep_overrides = name == own.region.name;
        let region_t = t
            .edited(&format!("target.region = \"{name}\""), |doc| {
                doc["motion"]["start_at_speed"] = toml_edit::value(true);
                let tg = &mut doc["target"];
                tg["region"] = toml_edit::value(name);
                if !keep_overrides {
                    if let Some(tab) = tg.as_table_like_mut() {
                        tab.remove("mass");
                        tab.remove("stiffness");
                    }
                }
            })
            .map_err(|e| e.to_string())?;
        let TargetKind::BodyRegion(b) = region_t.base.target.kind else {
            return Err("internal: the region's scene lost its body region".into());
        };
        let rigid_t = region_t
            .edited("decoupler.kind = \"rigid\" with a force sensor", |doc| {
                let mut d = toml_edit::Table::new();
                d["kind"] = toml_edit::value("rigid");
                doc["decoupler"] = toml_edit::Item::Table(d);
                let mut s = toml_edit::Table::new();
                s["kind"] = toml_edit::value("force");
                s["threshold"] = toml_edit::value(rigid_sensor_n);
                doc["sensor"] = toml_edit::Item::Table(s);
            })
            .map_err(|e| e.to_string())?;
        let with_module = module.map(|_| Cand { t: &region_t, dead_time: dt, rigid: false }.answer(&b, Some(m_t)));
        let rigid_tool = Cand { t: &rigid_t, dead_time: dt, rigid: true }.answer(&b, m_r.map(|m| m + m_t));
        let speed_ratio = with_module.as_ref().and_then(|a| a.speed_simulated_mps).zip(rigid_tool.speed_simulated_mps).map(|(a, r)| a / r);
        let limits = b.limits();
        out.push(RegionAnswer {
            region: name.into(),
            label: p.label.into(),
            effective_mass_kg: b.mass_kg,
            stiffness_n_per_m: b.stiffness_n_per_m,
            force_limit_n: limits.map(|l| l.0),
            pressure_limit_pa: limits.map(|l| l.1),
            with_module,
            rigid_tool,
            speed_ratio,
        });
    }
    let mut notes = vec![
        "limits: ISO/TS 15066:2016 Table A.2, body model Table A.3, as commonly reproduced: check them against the licensed text".to_string(),
        format!(
            "simulated: the largest motion.speed whose run holds, scan {}..{} then bisection; 'limits hold': the peak force and pressure of the whole run within the region's limits (both tools); SAFE: the run's verdict (docs/verdicts.md: the limits hold and the module's stroke is not exhausted while touching), the speed to quote for the module; gain: module over rigid, limits hold",
            mps(scan()[0]),
            mps(5.0)
        ),
        format!("rigid tool: decoupler.kind = \"rigid\" (m_t joins the robot) and a {rigid_sensor_n} N force sensor in the tool (--rigid-sensor; 25 N as tables5-7_rigid.toml, Ch. 3.1.2)"),
        format!(
            "closed form (ISO/TS 15066 Annex A): v = F / sqrt(mu k), {}, F the smaller of the force limit and the pressure limit x the contact area ({}: {}); m_R = m_t = {m_t} kg with the module (the tool alone meets the body), {} for the rigid tool. Impact energy only: the robot driving on until it detects and brakes, its compliance and the module's stroke are not in it",
            if own.contact == BodyContact::Transient { "mu = (1/m_H + 1/m_R)^-1, limits 2x Table A.2 (transient)" } else { "mu = m_R (clamped: the body cannot recoil), limits Table A.2 (quasi-static)" },
            own.region.name,
            own.closed_form_force().map_or("contact not permitted".to_string(), |(f, why)| format!("{f:.0} N, {why}")),
            match m_r {
                Some(m) => format!("m_R = m_r + m_t = {} kg", m + m_t),
                None => "m_R infinite (no [robot]: the flange follows its command)".into(),
            }
        ),
        format!("each candidate starts cruising at V_c {} mm from the body (motion.start_at_speed): the contact is at the commanded speed; its duration covers detection, the dead time and braking", GAP_M * 1e3),
    ];
    if let Some(TargetKind::BodyRegion(b)) = Some(base.target.kind) {
        if b.mass_kg != b.region.mass_kg || b.stiffness_n_per_m != b.region.stiffness_n_per_m {
            notes.push(format!("the scene's mass/stiffness override applies to {} only; the other regions use Table A.3", b.region.name));
        }
    }
    Ok(BodyDesign {
        scene: base.name.clone(),
        contact: own.contact.name().into(),
        contact_area_m2: own.area_m2,
        module: module.map(String::from),
        dead_time_s: dt,
        tool_mass_kg: m_t,
        robot_mass_kg: m_r,
        rigid_sensor_threshold_n: rigid_sensor_n,
        regions: out,
        notes,
    })
}

fn cell(v: Option<f64>) -> String {
    v.map_or("-".into(), |v| format!("{v:.3}"))
}

fn sim_cell(a: &Answer) -> String {
    if a.holds_at_every_speed {
        "all".into()
    } else {
        cell(a.speed_simulated_mps)
    }
}

/// The human table.
pub fn human(r: &BodyDesign) -> String {
    use std::fmt::Write;
    let mut o = String::new();
    let _ = writeln!(o, "{}", r.scene);
    let _ = writeln!(
        o,
        "  {} contact over {:.2} cm^2, DT = {:.1} ms, m_t = {} kg{}",
        r.contact.replace('_', "-"),
        r.contact_area_m2 * 1e4,
        r.dead_time_s * 1e3,
        r.tool_mass_kg,
        r.robot_mass_kg.map_or(", no [robot] (prescribed flange motion)".into(), |m| format!(", m_r = {m} kg"))
    );
    let _ = writeln!(o, "largest speed, m/s, at which the ISO/TS 15066 Annex A limits hold (simulated; closed form beside it)");
    let module = r.module.clone().unwrap_or_else(|| "none".into());
    let _ = writeln!(o, "  {:<20} {:>5} {:>5} {:>6}   {:>31}   {:>20}   {:>5}", "region", "m_H", "k", "limit", format!("with the {module} module"), "rigid tool", "gain");
    let _ = writeln!(o, "  {:<20} {:>5} {:>5} {:>6}   {:>7} {:>11} {:>11}   {:>8} {:>11}", "", "kg", "N/mm", "N", "SAFE", "limits hold", "closed form", "simulated", "closed form");
    for g in &r.regions {
        let (msafe, ms, mc) = g.with_module.as_ref().map_or(("-".into(), "-".into(), "-".into()), |a| (if a.holds_at_every_speed && a.safe_search_note.as_deref().is_some_and(|n| n.contains("no boundary")) { "all".into() } else { cell(a.speed_safe_mps) }, sim_cell(a), cell(a.speed_closed_form_mps)));
        let limit = g.force_limit_n.map_or("banned".into(), |f| format!("{f:.0}"));
        let gain = g.speed_ratio.map_or("-".into(), |x| format!("{x:.1}x"));
        let _ = writeln!(
            o,
            "  {:<20} {:>5.1} {:>5.0} {:>6}   {:>7} {:>11} {:>11}   {:>8} {:>11}   {:>5}",
            g.label,
            g.effective_mass_kg,
            g.stiffness_n_per_m * 1e-3,
            limit,
            msafe,
            ms,
            mc,
            sim_cell(&g.rigid_tool),
            cell(g.rigid_tool.speed_closed_form_mps),
            gain
        );
    }
    for g in &r.regions {
        for (what, a) in [("with the module", g.with_module.as_ref()), ("rigid tool", Some(&g.rigid_tool))] {
            let Some(a) = a else { continue };
            if let Some(n) = &a.search_note {
                let _ = writeln!(o, "  {} {what}: {n}", g.label);
            } else if let (Some(n), true) = (&a.safe_search_note, a.speed_closed_form_mps.is_some()) {
                let _ = writeln!(o, "  {} {what} (SAFE): {n}", g.label);
            }
        }
    }
    for n in &r.notes {
        let _ = writeln!(o, "  note: {n}");
    }
    o
}

/// Runs `flinch design SCENE --body-region WHICH` (`design::run` passes its arguments).
pub fn run(scene: &std::path::Path, sets: &[flinch_model::overrides::Set], which: &str, dead_time: Option<f64>, rigid_sensor: f64, json: bool) -> Result<bool, String> {
    let t = Template::load_with(scene, sets).map_err(|e| e.to_string())?;
    let r = design(&t, which, dead_time, rigid_sensor).map_err(|e| format!("{}: {e}", scene.display()))?;
    if json {
        println!("{}", serde_json::to_string_pretty(&r).map_err(|e| e.to_string())?);
    } else {
        print!("{}", human(&r));
    }
    Ok(true)
}
