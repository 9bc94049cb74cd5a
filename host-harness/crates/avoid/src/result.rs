//! What a closed-loop run gives ([`PathResult`]): the path, one row per control step, snapshots of
//! the field, the separation and speed figures the verdict is judged on.

use flinch_firmware::avoidance::RxStats;
use crate::rbf::Field;
use crate::verdict::*;

/// The state of the scene at the moment of minimum clearance, for the plot.
#[derive(Clone, Debug)]
pub struct Snapshot {
    /// Time, s.
    pub t_s: f64,
    /// Tool, m.
    pub tool_m: [f64; 2],
    /// Hand, m.
    pub hand_m: [f64; 2],
    /// The field in use.
    pub field: Field,
}

/// One control step as the CSV writes it.
#[derive(Clone, Copy, Debug)]
pub struct StepRow {
    /// Time at the end of the step, s.
    pub t_s: f64,
    /// Tool at the end of the step, m.
    pub p_m: [f64; 2],
    /// Commanded velocity during the step, m/s.
    pub v_mps: [f64; 2],
    /// Signed distance from the tool to the operator's true footprint at the end of the step, m.
    pub separation_m: f64,
    /// Speed limit that applied during the step, m/s.
    pub speed_limit_mps: f64,
    /// What the controller did: `run`, `slow`, `pfl`, `protective_stop`, `no_data`, `field` (monitor off),
    /// `no_path` (`--mcu`: the board's step stopped on the field),
    /// or `stopped` on the run's last step when its command was zero and the run ended before the
    /// goal.
    pub state: &'static str,
    /// Lower bound of the signed distance over the step's whole segment (the obstacles moving
    /// meanwhile), m: [`swept_min_m`].
    pub swept_separation_m: f64,
    /// The SSM bound at the TRUE separation at the start of the step ([`SsmVerdict`]), m/s: on the
    /// tool's speed towards the person (ISO/TS 15066 5.5.4.2.3), [`approach_speed_mps`].
    pub ssm_bound_mps: f64,
    /// The verdict on the step: `Some(true)` beyond the SSM bound but within the PFL speeds,
    /// `Some(false)` beyond both (an `ssm_violation`), `None` within the SSM bound.
    pub beyond_ssm: Option<bool>,
}

/// Near the operator, for `max_speed_near_operator_mps`: signed distance below this, m.
pub const NEAR_OPERATOR_M: f64 = 0.1;

/// A simulated path and its metrics.
#[derive(Clone, Debug)]
pub struct PathResult {
    /// Tool positions, one per control step (the first is the start), m.
    pub points: Vec<[f64; 2]>,
    /// Signed distance to the operator's true footprint at each point, m (negative inside).
    pub signed_distance_m: Vec<f64>,
    /// Smallest signed distance over the whole path, m, the segments between control steps
    /// included ([`swept_min_m`], to within [`SWEPT_TOL_M`] below): negative is the depth the tool
    /// went into the operator.
    pub min_signed_distance_m: f64,
    /// Steps whose commanded speed exceeded the SSM bound at the true separation ([`SsmVerdict`]),
    /// count.
    pub ssm_violations: usize,
    /// Largest excess of the commanded speed over that bound, m/s (0 when none).
    pub max_speed_over_ssm_mps: f64,
    /// Time of the first such step (its end), s.
    pub first_ssm_violation_s: Option<f64>,
    /// The clearance asked for (`clearance_m` of the scene), m.
    pub clearance_m: f64,
    /// Every control step.
    pub rows: Vec<StepRow>,
    /// How the run ended.
    pub status: Status,
    /// What the verdict was judged against.
    pub verdict_basis: VerdictBasis,
    /// Time spent with the tool inside the operator, s: every step whose segment entered it
    /// (swept distance below 0) counts whole.
    pub time_inside_s: f64,
    /// Largest commanded speed, m/s.
    pub max_speed_mps: f64,
    /// Largest commanded speed on a step that came within [`NEAR_OPERATOR_M`] of the operator
    /// (swept distance), m/s (0 if never).
    pub max_speed_near_operator_mps: f64,
    /// Steps at which the commanded direction turned by more than 90 degrees from the previous
    /// command (both above 1 mm/s).
    pub heading_reversals: usize,
    /// Length of the path, m.
    pub path_length_m: f64,
    /// Time at which the goal was reached, s.
    pub time_to_goal_s: Option<f64>,
    /// Stall episodes: local minima away from the goal.
    pub stalls: usize,
    /// Camera frames fitted.
    pub frames: usize,
    /// Control step `dt`, s.
    pub dt_s: f64,
    /// Receiver counters (MCU engine).
    pub rx: Option<RxStats>,
    /// Scene at the minimum clearance.
    pub snapshot: Snapshot,
    /// Steps beyond the SSM bound but within the PFL speeds (`[avoid.pfl]`), count.
    pub steps_in_pfl: usize,
    /// Largest commanded speed on such a step, m/s (0 when none).
    pub max_speed_in_pfl_mps: f64,
    /// Contacts (the tool's surface reaching a person) at a tool velocity within the PFL speeds,
    /// count: each ends the run in a stop (the module's switch fires; a person resets).
    pub contacts_within_pfl: usize,
    /// The tool's speed at the first contact, m/s (0 when none; the person's own speed is not in
    /// it).
    pub max_contact_speed_mps: f64,
    /// The PFL speeds used and their provenance (`None` without `[avoid.pfl]`).
    pub pfl: Option<PflSummary>,
    /// Smallest signed distance from the robot's link to a person or obstacle tall enough to reach
    /// it (3-D, `flinch_model::avoid::link`), over every step's sweep (a lower bound), m; infinite
    /// when nothing reaches the link's height. Below 0: the arm entered a person, a collision.
    pub link_min_signed_distance_m: f64,
    /// What the run's input looked wrong in, each naming why (`flinch avoid` prints them to stderr
    /// and the JSON's `warnings`): a recording's mis-timed or mis-scaled frames.
    pub warnings: Vec<String>,
}

/// The PFL speeds of `[avoid.pfl]` (ISO/TS 15066 5.5.5, Annex A) and where they come from.
#[derive(Debug, Clone, serde::Serialize, schemars::JsonSchema)]
pub struct PflSummary {
    /// Along the module's axis: the largest speed at which a contact with the module stays within
    /// Table A.2's limits and the stroke holds (`flinch design --body-region`'s `speed_safe_mps`),
    /// the smallest over the regions, m/s.
    pub pfl_speed_along_axis_mps: f64,
    /// The region that set it.
    pub along_region: String,
    /// Across the axis: a rigid tool's speed (the module does not yield there), m/s.
    pub pfl_speed_across_axis_mps: f64,
    /// The region that set it.
    pub across_region: String,
    /// The module's axis in the cell's plane (unit), [x, y].
    pub axis: [f64; 2],
    /// Table A.2's force limit for `along_region` and `contact`, N.
    pub force_limit_n: f64,
    /// "transient" or "quasi_static" (the module scene's contact).
    pub contact: String,
    /// The module scene as the avoidance scene names it.
    pub module: String,
    /// SHA-256 of the module scene's text, hex.
    pub module_sha256: String,
}

impl PflSummary {
    /// Of a scene whose PFL is resolved.
    pub fn of(scene: &crate::scene::Avoid) -> Option<Self> {
        let p = scene.pfl.as_ref()?;
        let r = p.resolved.as_ref()?;
        Some(PflSummary {
            pfl_speed_along_axis_mps: r.along_mps,
            along_region: r.along_region.clone(),
            pfl_speed_across_axis_mps: r.across_mps,
            across_region: r.across_region.clone(),
            axis: p.axis,
            force_limit_n: r.along_force_limit_n,
            contact: r.contact.clone(),
            module: p.module.clone(),
            module_sha256: r.module_sha256.clone(),
        })
    }
}
