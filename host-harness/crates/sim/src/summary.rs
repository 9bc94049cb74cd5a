//! What a run reports: the recorded samples, the summary, and the null reasons of the summary's
//! derived fields (a field that cannot be defined for a run is null with a reason, never a number
//! outside its physical range, issue 18).

use serde::Serialize;

/// How far outside [0, 1] an achieved restitution may come out of the integration and still be
/// one (clamped): an elastic impact (e = 1) measures 1 + 1.7e-6 at the default tolerances
/// (tests/thesis.rs, `free_tool_gives_eq3_and_eq4`); 1e-3 is well above that and far below the
/// 2.5 to 2e21 of a driven contact.
pub const RESTITUTION_SLACK: f64 = 1e-3;

/// One recorded instant of the time history.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Sample {
    /// s.
    pub t: f64,
    /// x_c', m/s.
    pub v_c: f64,
    /// x_r', m/s.
    pub v_r: f64,
    /// x_t', m/s.
    pub v_t: f64,
    /// Object velocity (0 for an obstacle), m/s.
    pub v_p: f64,
    /// Stroke coordinate s = x_t - x_r, m.
    pub s: f64,
    /// Contact force, N.
    pub f_contact: f64,
    /// Force on the robot, N (signed: positive pulls the robot forward).
    pub f_robot: f64,
    /// Decoupler spring (or hydraulic) force on the tool, N.
    pub f_spring: f64,
    /// End-stop forces on the tool, N.
    pub f_stops: f64,
    /// Friction on the tool, N.
    pub f_friction: f64,
}

/// What a run reports: the `--json` contract of SCENES.md plus extras.
#[derive(Debug, Clone, Serialize, PartialEq, schemars::JsonSchema)]
pub struct Summary {
    /// Scene name, as the scene file writes it (free text: it can be stale).
    pub scene: String,
    /// What was simulated: V_c, DT, the module, the tool, the target and gap
    /// (`flinch_model::headline`).
    pub simulated: String,
    /// Claims of the scene's name that the simulated scene contradicts (`V_c = 0.2 m/s` while
    /// 0.5 m/s ran, `(mode 3)` while the run reached mode 1, ...); empty when none.
    pub name_mismatches: Vec<String>,
    /// First tool-target contact, s.
    pub t_contact: Option<f64>,
    /// Detection, s.
    pub t_detect: Option<f64>,
    /// Start of braking, s.
    pub t_brake: Option<f64>,
    /// t_detect - t_contact, s.
    pub detection_delay: Option<f64>,
    /// t_brake - t_contact, s; null (with `reaction_time_null_reason`) when braking started
    /// before the contact.
    pub reaction_time: Option<f64>,
    /// Largest contact force, N.
    pub peak_contact_force: f64,
    /// Largest magnitude of the force on the robot, N.
    pub peak_robot_force: f64,
    /// Object velocity when it last left the tool (or at the end if still in contact), m/s.
    pub object_final_velocity: Option<f64>,
    /// Working mode of Fig. 46 (1, 2, 3), null without a back end-stop.
    pub mode: Option<u8>,
    /// True when the flange itself reached the target (through a bottomed or rigid tool): the
    /// back end-stop engaged while the tool touched the target (docs/verdicts.md).
    pub stroke_exhausted: bool,
    /// Separation over approach velocity of the first contact.
    pub achieved_restitution: Option<f64>,
    /// Accepted steps.
    pub steps: u64,
    /// Right-hand-side evaluations.
    pub rhs_evals: u64,
    /// Flange standstill, s.
    pub t_stop: Option<f64>,
    /// Approach speed of the first contact (tool towards target), m/s.
    pub approach_speed_mps: Option<f64>,
    /// False when the run did not simulate what the scene commands: the flange had not reached
    /// `motion.speed` when the tool met the target (the gap is shorter than V_c^2 / 2 a_c), so the
    /// impact is slower than V_c. The reasons are in `not_as_commanded`.
    pub as_commanded: bool,
    /// Why the run is not as commanded, one sentence each (empty when it is).
    pub not_as_commanded: Vec<String>,
    /// Number of tool-target contacts (bounces).
    pub contacts: u32,
    /// Largest object velocity, m/s.
    pub object_peak_velocity: Option<f64>,
    /// Largest travel back from the front stop (or rest), m.
    pub max_travel: f64,
    /// Decoupler impulse while in contact (eq 21), N s.
    pub decoupler_impulse: f64,
    /// Largest gas pressure (hydraulic), Pa.
    pub peak_gas_pressure: Option<f64>,
    /// Rejected steps.
    pub rejected_steps: u64,
    /// The plant was at rest from this instant to the end of the run, s: the robot had stopped and
    /// no body's velocity or acceleration, extrapolated to `duration`, would move it by more than
    /// the solver's tolerance, so the state was held from there (it costs no steps). Null when
    /// the plant was still moving (or the robot had not stopped) at the end.
    pub at_rest_from_s: Option<f64>,
    /// Located events.
    pub events: u64,
    /// Integration method.
    pub method: String,
    /// Things the user should know about this run (regularisations applied, ...).
    pub warnings: Vec<String>,
    /// `solver.fidelity` of the run: "fast", "default" or "reference".
    pub fidelity: String,
    /// The parts of the model this run left out (`solver.simplify`): "rigid-robot",
    /// "no-friction". Empty for the full model.
    pub simplified: Vec<String>,
    /// When the whole run's peak force on the robot (`peak_robot_force`) occurs, s (0 when the
    /// robot never feels a force).
    pub peak_robot_force_t_s: f64,
    /// What carries the force on the robot when `peak_robot_force` occurs, by its largest part at
    /// that instant: "front_stop" (the tool landing on or pressing the front end-stop) or
    /// "back_stop" (the tool on the flange) when that stop carries more than the decoupler's
    /// spring, gas or friction; otherwise "first_impact" (the first tool-target contact is on),
    /// "later_contact" (a second or later one is on), "decoupler" (spring, gas or friction with
    /// no contact on), "none" (no force at all). The whole run's peak
    /// is often not the first impact's (issue 15: Fig. 76's 34.8 N is the tool's return onto the
    /// front end-stop, 80 ms after a first impact of 30 N).
    pub peak_robot_force_event: String,
    /// Largest magnitude of the force on the robot from the first tool-target contact's onset to
    /// its end (or the end of the run), N; null without a contact.
    pub first_impact_peak_robot_force_n: Option<f64>,
    /// When `first_impact_peak_robot_force_n` occurs, s; null without a contact.
    pub first_impact_peak_robot_force_t_s: Option<f64>,
    /// Why `first_impact_peak_robot_force_n` and `first_impact_peak_robot_force_t_s` are null.
    pub first_impact_peak_robot_force_null_reason: Option<String>,
    /// Why `achieved_restitution` is null: no contact, a contact still going at the end, or a
    /// driven first contact (the decoupler or the robot pushed through it, so the tool left faster
    /// than it came or did not leave: not an isolated impact, and a restitution outside [0, 1]).
    pub achieved_restitution_null_reason: Option<String>,
    /// Why `detection_delay` is null: no contact, no detection, or a detection before the contact
    /// (the sensor fired on something else than the collision; t_detect is still reported).
    pub detection_delay_null_reason: Option<String>,
    /// Why `reaction_time` is null: no contact, no braking, or braking that started before the
    /// contact (the sensor fired on something else; t_brake is still reported).
    pub reaction_time_null_reason: Option<String>,
    /// Smallest travel left before the back end-stop while the tool touched the target, m:
    /// negative when the tool was pushed into the back end-stop while touching it (then
    /// `stroke_exhausted`), 0 for a rigid tool (docs/verdicts.md). Null when the tool never
    /// touched the target or the module has no back end-stop (see the reason).
    pub stroke_left_min_m: Option<f64>,
    /// Why `stroke_left_min_m` is null.
    pub stroke_left_min_m_null_reason: Option<String>,
    /// Largest deformation of the target (tool-target contact penetration) while touching, m.
    pub target_deformation_max_m: Option<f64>,
    /// Closest approach of the flange (the back end-stop plane) to the target's undeformed face
    /// while touching: the stroke left minus the target's deformation at the same instant, m.
    /// Negative when the target is compressed by more than the stroke left: the flange passes the
    /// undeformed surface without the tool bottoming. Informative; `safe` does not use it.
    pub closest_approach_m: Option<f64>,
    /// False when the tool touched the target and the robot had not come to a standstill by the
    /// end of the run (`t_stop` after `duration`, or never commanded), or its compliant arm could
    /// still advance far enough to use up the stroke left (`flange_reach_after_end_m`): what
    /// happened after the end is not simulated, so the run is not safe (a failure in `failures`;
    /// lengthen `duration`). True otherwise, and for a run without contact.
    pub concluded: bool,
    /// The run's end (the scene's `duration`), s.
    pub t_end_s: f64,
    /// How far the flange can still advance towards the target after the run's end, bounded by a
    /// compliant robot's energy at the end, m: `x_c + sqrt((x_r - x_c)^2 + m_r x_r'^2 / k_r) - x_r`
    /// with the command stopped (damping and the tool's push back only shorten it); 0 for a rigid
    /// robot (the flange is the command) and the command's remaining travel if it has not stopped.
    pub flange_reach_after_end_m: f64,
    /// The verdict (crate::verdict, one definition for every command): no entry in `failures`.
    pub safe: bool,
    /// Every reason the run is not safe, for people (empty when safe).
    pub failures: Vec<String>,
    /// The human body region hit (`target.kind = "body_region"`, ISO/TS 15066 Table A.2/A.3 name,
    /// e.g. "hand"); null for any other target, and then every `body_*` field is null.
    pub body_region: Option<String>,
    /// "transient" (free body part, limits 2x Table A.2) or "quasi_static" (clamped, Table A.2).
    pub body_contact: Option<String>,
    /// m_H used, kg (Table A.3 unless the scene overrides it).
    pub body_effective_mass_kg: Option<f64>,
    /// k used, N/m (Table A.3 unless the scene overrides it).
    pub body_stiffness_n_per_m: Option<f64>,
    /// The contact area of the scene, m^2.
    pub body_contact_area_m2: Option<f64>,
    /// Peak force on the body over the whole run (= peak_contact_force), N.
    pub body_peak_force_n: Option<f64>,
    /// The force limit that applies (transient: 2x Table A.2; quasi-static: Table A.2), N; null
    /// where the TS does not permit the contact (transient contact with the skull or the face).
    pub body_force_limit_n: Option<f64>,
    /// body_force_limit_n - body_peak_force_n, N (negative: exceeded).
    pub body_force_margin_n: Option<f64>,
    /// Peak pressure = body_peak_force_n / body_contact_area_m2, Pa.
    pub body_peak_pressure_pa: Option<f64>,
    /// The pressure limit that applies (the region's lowest in Table A.2; 2x for transient), Pa.
    pub body_pressure_limit_pa: Option<f64>,
    /// body_pressure_limit_pa - body_peak_pressure_pa, Pa (negative: exceeded).
    pub body_pressure_margin_pa: Option<f64>,
    /// The force and the pressure are within the limits and the contact is permitted (part of
    /// `safe`, crate::verdict).
    pub body_limits_pass: Option<bool>,
    /// Planar runs (issue 30, docs/planar.md): beta, the angle from the decoupler's axis to the
    /// flange's path, deg; absent for a 1-D run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub off_axis_deg: Option<f64>,
    /// Planar runs: theta of Fig. 68a, the surface's angle to the decoupler's axis, deg.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub surface_angle_deg: Option<f64>,
    /// The rotational module: Fig. 69's angle, the guide's angle to the surface (theta minus the
    /// stage's turn), at the instant the bi-stable mechanism starts to move (travel
    /// `ENGAGED_TRAVEL_M` while touching the target), deg.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub module_rotation_deg: Option<f64>,
    /// Why `module_rotation_deg` is null for a rotational module.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub module_rotation_deg_null_reason: Option<String>,
    /// The rotational module: that instant, s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub t_engaged_s: Option<f64>,
    /// The rotational module: the stage's largest turn from rest in the run (magnitude), deg.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_rotation_deg: Option<f64>,
    /// Planar runs: when the module was blocked (pushed for `BLOCKED_AFTER_S` far above its release
    /// force without yielding: locked by friction, a guide across the push, a stage that cannot
    /// turn), s; a failure of the verdict. Absent when it never was.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub module_blocked_t_s: Option<f64>,
    /// The contact force then, N.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub module_blocked_force_n: Option<f64>,
}

/// The rotational module counts as engaged when its tool has travelled this far back from the front
/// stop while touching the target, m (Fig. 69 ends where "the bi-stable mechanism starts to push",
/// a camera judgement at 300 fps; docs/validation.md gives the angle's sensitivity to it).
pub const ENGAGED_TRAVEL_M: f64 = 1e-4;

/// The achieved restitution of the first contact, `-v_out / v_in`, or null with the reason: it is a
/// restitution only for an isolated impact, and only in [0, 1]. A driven contact (the issue's
/// `gap = 0.0001` on Table 2's linear module: the spring still accelerates the tool, which leaves
/// at 10.5 times its approach speed) is not one.
pub fn achieved_restitution(v_in: Option<f64>, v_out: Option<f64>) -> (Option<f64>, Option<String>) {
    match (v_in, v_out) {
        (None, _) => (None, Some("no tool-target contact in the run".into())),
        (Some(vi), _) if vi.is_nan() || vi <= 0.0 => (None, Some(format!("the first contact began at a relative approach velocity of {vi} m/s, not an impact"))),
        (Some(_), None) => (None, Some("the first contact had not ended at the end of the run".into())),
        (Some(vi), Some(vo)) => {
            let e = -vo / vi;
            if (-RESTITUTION_SLACK..=1.0 + RESTITUTION_SLACK).contains(&e) {
                (Some(e.clamp(0.0, 1.0)), None)
            } else {
                (None, Some(format!("the first contact was driven, not an isolated impact: the tool approached at {vi} m/s and left at {} m/s (ratio {e}), and a restitution is defined only in [0, 1]", -vo)))
            }
        }
    }
}

/// `t_detect - t_contact`, or null with the reason; a detection before the contact is not a
/// detection delay (the sensor fired on something else, e.g. the tool lagging as the flange
/// accelerates).
pub fn detection_delay(t_contact: Option<f64>, t_detect: Option<f64>) -> (Option<f64>, Option<String>) {
    match (t_contact, t_detect) {
        (None, _) => (None, Some("no tool-target contact in the run".into())),
        (Some(_), None) => (None, Some("nothing detected the collision within the run".into())),
        (Some(c), Some(d)) if d < c => (None, Some(format!("the sensor fired at t_detect = {d} s, before the first contact at t_contact = {c} s: not a detection of the collision"))),
        (Some(c), Some(d)) => (Some(d - c), None),
    }
}

/// `t_brake - t_contact`, or null with the reason: braking that started before the contact is not a
/// reaction to it (a tool lagging as the flange accelerates can trip the travel switch first: with
/// `spring_rate = 1` and `decel = 0.001` this was reported as -0.629 s).
pub fn reaction_time(t_contact: Option<f64>, t_brake: Option<f64>) -> (Option<f64>, Option<String>) {
    match (t_contact, t_brake) {
        (None, _) => (None, Some("no tool-target contact in the run".into())),
        (Some(_), None) => (None, Some("the robot was never commanded to brake".into())),
        (Some(c), Some(b)) if b < c => (None, Some(format!("braking started at t_brake = {b} s, before the first contact at t_contact = {c} s: not a reaction to the collision"))),
        (Some(c), Some(b)) => (Some(b - c), None),
    }
}
