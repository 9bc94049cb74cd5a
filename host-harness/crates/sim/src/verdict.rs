//! One definition of "safe", used by every command: the run's summary, `flinch check`, `flinch
//! design`, `flinch sweep` (docs/verdicts.md says it in words).
//!
//! Three lengths, all measured while the tool touches the target (contact penetration > 0), at the
//! same instants the solver accepts a step:
//!
//! - **stroke left** (`stroke_left_min_m`): the tool's travel left before the back end-stop. It is
//!   negative when the tool is pushed into the (compliant) back end-stop while touching the target:
//!   the robot then pushes the target through a solid stack. That is **stroke exhausted**
//!   (`stroke_exhausted`), and a rigid tool is exhausted on contact (stroke left 0).
//! - **target deformation** (`target_deformation_max_m`): how far the tool's face is pressed into
//!   the target (the Hertz contact of eq 5).
//! - **closest approach** (`closest_approach_m`): the stroke left minus the deformation at the same
//!   instant: the flange's distance to where the target's face was before it was pressed in. It can
//!   be negative while the stroke is not exhausted (a soft target squashed by more than the stroke
//!   left); the force limits, not this length, say whether that squeeze is acceptable.
//!
//! **Safe** means the list of failures is empty. A failure is: a run that is not concluded (after
//! a contact the robot had not stopped by the end of the run, so the rest is not simulated), the
//! stroke exhausted, or, for a human
//! body region target (ISO/TS 15066 Annex A, flinch_model::body), the peak contact force or pressure over
//! the region's limit, or a transient contact the TS does not permit. The budget of
//! `flinch check` (`v DT + v^2/2d <= C - d_sw`) is a second, independent verdict; `check` and
//! `design` are favourable only when both are. Where the budget and the simulation disagree,
//! [`explain`] says why (a free object pushed away, the tool bouncing into the back end-stop, the
//! target's deformation, the robot's compliance).
//!
//! Human output rounds (lengths in mm to 0.01 mm, speeds in m/s to 1 mm/s, forces to 0.1 N); JSON
//! keeps full precision.

use flinch_model::scene::{Scene, TargetKind};
use crate::Summary;

/// A length for people: mm, two decimals.
pub fn mm(x: f64) -> String {
    format!("{:.2} mm", x * 1e3)
}

/// A signed length for people: mm, two decimals, with its sign.
pub fn mm_signed(x: f64) -> String {
    format!("{:+.2} mm", x * 1e3)
}

/// A speed for people: m/s, three decimals.
pub fn mps(x: f64) -> String {
    format!("{x:.3} m/s")
}

/// A time for people: ms, one decimal.
pub fn ms(x: f64) -> String {
    format!("{:.1} ms", x * 1e3)
}

/// Whether a run answers the question (`Summary::concluded`): after a contact, the robot must
/// have come to a standstill (`t_stop`, s) within the run (`duration`, s). Otherwise the flange was
/// still driving the tool into the target when the simulation ended, and the stroke can run out
/// after the end: a run that ends there says nothing about safety (a long dead time with a short
/// `duration` used to be reported SAFE).
///
/// A compliant robot keeps moving after its command stopped (its mass rings on k_r): the run is
/// concluded only if the flange's further advance towards the target, bounded by the robot's
/// energy at the end (`flange_reach_m`, see `sim`), cannot use up the stroke left at the end
/// (`stroke_left_end_m`, None without a back end-stop), and, against a body region, stays within
/// [`BODY_REACH_TOL_M`] (further advance presses the body harder, and the limits are on force).
///
/// The energy bound counts the robot only (not the decoupler's own stored energy: a bi-stable
/// spring past its dead centre drives the tool back by itself), so the run must also last one
/// period of the robot's compliance after the stop (`settle_s`, 2 pi sqrt(m_r / k_r)): the arm's
/// largest advance after a stop comes within half a period, and damping only shrinks the later
/// ones. A soft arm (k_r = 1,000 N/m, 8.4 kg: 0.58 s) stopped at 0.27 s ran out of stroke at
/// 0.37 s, after a 0.35 s run had been called SAFE (review, 2026-11-26).
pub fn concluded(t_contact: Option<f64>, t_stop: Option<f64>, duration: f64, settle_s: f64, flange_reach_m: f64, stroke_left_end_m: Option<f64>, body: bool) -> bool {
    t_contact.is_none()
        || (t_stop.is_some_and(|t| t + settle_s <= duration)
            // (a stroke already used up at the end is answered: exhausted)
            && stroke_left_end_m.is_none_or(|l| l <= 0.0 || flange_reach_m < l)
            && (!body || flange_reach_m <= BODY_REACH_TOL_M))
}

/// How far a compliant robot may still advance into a body region after the run's end for the
/// run to count as concluded, m: 0.1 mm (against the hand's 75 N/mm of ISO/TS 15066 Table A.3,
/// 7.5 N; the run must otherwise be lengthened).
pub const BODY_REACH_TOL_M: f64 = 1e-4;

/// Every reason a run is not safe (empty: safe). The one definition; see the module docs.
pub fn failures(s: &Summary) -> Vec<String> {
    let mut f = Vec::new();
    if !s.concluded {
        f.push(match s.t_stop {
            Some(t) if t <= s.t_end_s => format!(
                "not concluded: the robot's command stopped at t_stop = {t} s, but its compliant arm had not settled by the run's end (one period of its compliance after the stop, and an advance of up to {} still possible by its energy at the end), which is not simulated: lengthen duration",
                mm(s.flange_reach_after_end_m)
            ),
            Some(t) => format!("not concluded: the robot was still moving into the target when the run ended (it stands still at t_stop = {t} s); the stroke can still run out after the end, which is not simulated: lengthen duration"),
            None => "not concluded: the robot was never commanded to stop (the contact was not detected), so nothing stops it driving on after the run's end".to_string(),
        });
    }
    if s.stroke_exhausted {
        let how = match s.stroke_left_min_m {
            Some(l) if l < 0.0 => format!("the tool was pushed {} into the back end-stop while touching the target", mm(-l)),
            _ => "a rigid tool: nothing between the flange and the target absorbs the robot's stopping distance".to_string(),
        };
        f.push(format!("stroke exhausted: {how}, so the flange reached the target"));
    }
    if let (Some(t), Some(n)) = (s.module_blocked_t_s, s.module_blocked_force_n) {
        f.push(format!("module blocked: at t = {t} s the target was pushed with {n:.0} N for {} ms without the module yielding (its guide across the push, locked by friction, or a stage that cannot turn): it protected no more than a rigid tool", crate::simulation::BLOCKED_AFTER_S * 1e3));
    }
    f.extend(body_failures(s));
    f
}

/// The body-region part of [`failures`]: the run's peak contact force and pressure against the
/// limits of ISO/TS 15066 Table A.2 (flinch_model::body), rebuilt from the summary's `body_*` fields so
/// the verdict depends on the summary alone. Empty for a target that is not a body region.
pub fn body_failures(s: &Summary) -> Vec<String> {
    use flinch_model::body::{BodyContact, BodyTarget};
    let (Some(name), Some(contact), Some(area), Some(m), Some(k), Some(peak)) = (
        s.body_region.as_deref(),
        s.body_contact.as_deref(),
        s.body_contact_area_m2,
        s.body_effective_mass_kg,
        s.body_stiffness_n_per_m,
        s.body_peak_force_n,
    ) else {
        return Vec::new();
    };
    let Some(region) = flinch_model::body::preset(name) else {
        return vec![format!("body region {name:?} unknown: no limits to hold the run against")];
    };
    let contact = if contact == "transient" { BodyContact::Transient } else { BodyContact::QuasiStatic };
    let b = BodyTarget { region, contact, area_m2: area, mass_kg: m, stiffness_n_per_m: k };
    flinch_model::body::check(&b, peak).failures
}

/// One line stating the body-region check of a run, for people (None: not a body region).
pub fn body_line(s: &Summary) -> Option<String> {
    let name = s.body_region.as_deref()?;
    let label = flinch_model::body::preset(name).map_or(name, |p| p.label);
    let contact = s.body_contact.as_deref().unwrap_or("-").replace('_', "-");
    let peak_f = s.body_peak_force_n?;
    let peak_p = s.body_peak_pressure_pa?;
    let pass = if s.body_limits_pass == Some(true) { "PASS" } else { "FAIL" };
    Some(match (s.body_force_limit_n, s.body_pressure_limit_pa) {
        (Some(f), Some(p)) => format!(
            "body region {label} ({contact}, ISO/TS 15066 Table A.2): {pass}: peak force {:.1} N of {:.1} N (margin {:+.1} N), peak pressure {:.1} N/cm^2 of {:.1} N/cm^2 (margin {:+.1} N/cm^2) over {:.2} cm^2",
            peak_f, f, f - peak_f, peak_p * 1e-4, p * 1e-4, (p - peak_p) * 1e-4, s.body_contact_area_m2.unwrap_or(0.0) * 1e4
        ),
        _ => format!("body region {label} ({contact}): {pass}: transient contact is not permitted by ISO/TS 15066 (peak force {peak_f:.1} N)"),
    })
}

/// One line stating the verdict of a run, for people.
pub fn line(s: &Summary) -> String {
    let left = s.stroke_left_min_m.map_or_else(|| s.stroke_left_min_m_null_reason.clone().unwrap_or_default(), |l| format!("stroke left while touching the target {}", mm_signed(l)));
    let closest = match (s.closest_approach_m, s.target_deformation_max_m) {
        (Some(c), Some(d)) => format!("; closest approach to the undeformed target {} (target deformed up to {})", mm_signed(c), mm(d)),
        _ => String::new(),
    };
    if s.safe {
        format!("verdict: SAFE ({left}{closest})")
    } else {
        format!("verdict: NOT SAFE: {} ({left}{closest})", s.failures.join("; "))
    }
}

/// The stroke budget's inputs, for [`explain`].
#[derive(Debug, Clone, Copy)]
pub struct Budget {
    /// Total stroke C, m.
    pub stroke: f64,
    /// Switch travel d_sw, m.
    pub switch_travel: f64,
    /// v DT + v^2/2d, m.
    pub stopping_distance: f64,
}

impl Budget {
    /// The budget holds.
    pub fn fits(&self) -> bool {
        self.stopping_distance <= self.stroke - self.switch_travel
    }
}

/// Why the budget and the simulation of the same scene say different things, for people (empty
/// when they agree and there is nothing the user should know).
pub fn explain(scene: &Scene, b: &Budget, s: &Summary) -> Vec<String> {
    let mut out = Vec::new();
    let fits = b.fits();
    let predicted = b.switch_travel + b.stopping_distance;
    let free_mass = match scene.target.kind {
        TargetKind::Object { mass, .. } => Some(mass),
        // ISO/TS 15066 transient contact: the body part is a free effective mass m_H.
        TargetKind::BodyRegion(b) if b.contact == flinch_model::body::BodyContact::Transient => Some(b.mass_kg),
        _ => None,
    };
    if let Some(mass) = free_mass {
        out.push(format!(
            "the target is a free object (m_p = {mass} kg): the budget assumes a fixed obstacle and counts the robot's whole stopping distance ({}) as travel, but the object was pushed away (up to {}) and the tool travelled {}, keeping {} of stroke while touching it; {}",
            mm(b.stopping_distance),
            mps(s.object_peak_velocity.unwrap_or(0.0)),
            mm(s.max_travel),
            s.stroke_left_min_m.map_or("-".into(), mm_signed),
            if fits {
                "the simulation confirms the budget"
            } else {
                "fail-safe: the budget's verdict stands for check and design (an object that is held, or heavier, is not pushed away), while the run's own verdict is the simulation's"
            }
        ));
    }
    if s.max_travel > b.stroke + 1e-6 {
        let over = s.max_travel - b.stroke;
        if s.stroke_exhausted {
            out.push(format!("the travel {} exceeds the stroke {} by {}: the tool was pushed into the compliant back end-stop while touching the target", mm(s.max_travel), mm(b.stroke), mm(over)));
        } else {
            out.push(format!(
                "the travel {} exceeds the stroke {} by {}: the tool rode into the compliant back end-stop while NOT touching the target (it had bounced off it; {} contact{}), which does not bring the flange to the target",
                mm(s.max_travel),
                mm(b.stroke),
                mm(over),
                s.contacts,
                if s.contacts == 1 { "" } else { "s" }
            ));
        }
    }
    if let (Some(d), Some(c), Some(l)) = (s.target_deformation_max_m, s.closest_approach_m, s.stroke_left_min_m) {
        if d > 0.05e-3 && (c < 0.0) != (l < 0.0) {
            out.push(format!(
                "the target deformed by up to {}: counting it, the flange came within {} of the target's undeformed face, while the tool kept {} of stroke; safe is judged on the stroke left (the force on the target is what the deformation costs)",
                mm(d),
                mm_signed(c),
                mm_signed(l)
            ));
        }
    }
    let obstacle = free_mass.is_none();
    if fits && s.stroke_exhausted {
        out.push(format!(
            "the budget fits but the simulation exhausts the stroke: the budget assumes the flange stops on its command ({} of travel at most) and a rigid target; the simulated robot's compliance and the tool's own dynamics carry it further. The simulation decides: NOT SAFE",
            mm(predicted)
        ));
    } else if !fits && !s.stroke_exhausted && obstacle && s.t_contact.is_some() {
        out.push(format!(
            "the budget does not fit but the simulated tool kept stroke while touching the target: the budget counts the whole stopping distance as travel ({} needed, {} available); in the simulation the tool {}. Fail-safe: the budget's verdict stands",
            mm(predicted),
            mm(b.stroke),
            if s.contacts > 1 { "bounced off the target and the flange's motion was not all travel" } else { "travel was less than the flange's motion" }
        ));
    }
    if s.t_contact.is_none() {
        out.push("the tool never touched the target in the simulated duration: nothing was confirmed".into());
    }
    out
}
