//! Reads a scene: [`load`] a file, [`parse`] a text, table by table, every problem at once.
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
//! - `decoupler.front_stop.law` ("linear" | "hunt-crossley", default "linear", eq 28/38) and, with
//!   "hunt-crossley", `exponent` (n in [1, 2], default 1): `F = k d^n (1 + alpha d' / v_in)`, no
//!   force jump at landing; alpha matches the restitution the linear law achieves with the same
//!   `stiffness` and `damping` for the tool mass (or the `restitution` given).
//! - `decoupler.back_stop = { stiffness, restitution, damping_law }` where `damping_law` defaults to
//!   [`DEFAULT_BACK_STOP_LAW`] (Hunt-Crossley, as the thesis, eq 29/37), or `{ stiffness, chi }`.
//! - hydraulic `adiabatic_exponent` (default [`DEFAULT_ADIABATIC_EXPONENT`], air, fixed by eq 47) and
//!   `friction_v0` (default [`DEFAULT_HYDRAULIC_FRICTION_V0`] m/s, regularises sgn in eq 48).
//! - `[solver]`: `method` ("dopri5" | "rk4" | "semi-implicit-euler"), `rtol`, `atol`, `max_step`,
//!   `output_interval`, defaults in the `DEFAULT_*` constants (measured: docs/accuracy.md).
//!   `fidelity` ("fast" | "default" | "reference", default "default") picks the tolerance defaults:
//!   `REFERENCE_*` (dopri5 only, no other solver key, no simplification), `DEFAULT_*`, or `FAST_*`.
//!   `simplify` (a list of "rigid-robot" | "no-friction", default none) drops those parts of the
//!   model explicitly (`sim::simplified`; their measured cost is in docs/accuracy.md).
//! - `[controller]` (firmware in the loop): `scan_cycle` (s > 0), `phase` in [0, 1),
//!   `firmware_tick` (s > 0), all required when the table is present.

use super::check::{approx, num, Ctx, Key, SceneError, SceneIssue, Tab};
use super::model::Scene;
use super::tables::{key_tables, DURATION, NAME, ROOT};
use super::{budget, controller, decoupler, motion_law, planar, robot, sensor, solver, target, tool};
use std::path::Path;

/// Reads and validates a scene file.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let file = path.display().to_string();
    match flinch_output::input::read_text(path, flinch_output::input::Kind::Scene) {
        Ok(text) => parse(&text, &file),
        Err(e) => Err(SceneError {
            file,
            issues: vec![SceneIssue {
                line: e.line,
                key: String::new(),
                message: format!("cannot read the scene file: {}", e.message),
            }],
        }),
    }
}

/// Validates a scene given as text; `file` names it in the messages.
pub fn parse(text: &str, file: &str) -> Result<Scene, SceneError> {
    let doc = super::check::parse_toml(text, file)?;
    let mut cx = Ctx {
        text,
        file,
        issues: Vec::new(),
        tables: key_tables(),
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

/// An optional element: `Some(None)` when its table is absent, `None` (reported) when it is
/// invalid.
fn optional<T>(
    cx: &mut Ctx,
    root: &Tab,
    key: &Key,
    read: impl FnOnce(&mut Ctx, &Tab) -> Option<T>,
) -> Option<Option<T>> {
    match cx.maybe_table(root, key)? {
        Some(t) => read(cx, &t).map(Some),
        None => Some(None),
    }
}

fn scene(cx: &mut Ctx, root: &toml_edit::Table) -> Option<Scene> {
    let root = Tab {
        path: String::new(),
        t: root,
        line: Some(1),
    };
    cx.check_keys(&root, ROOT, "");
    let name = cx.string(&root, &NAME);
    let duration_s = cx.number(&root, &DURATION);

    let tool = cx
        .table(&root, &tool::TABLE)
        .and_then(|t| tool::tool(cx, &t));
    let motion_tab = cx.table(&root, &motion_law::TABLE);
    let motion = motion_tab
        .as_ref()
        .and_then(|t| motion_law::motion(cx, t, tool.map(|t| t.mass)));
    let robot = optional(cx, &root, &robot::TABLE, robot::robot);
    let gravity = motion.map(|m| m.gravity);
    let decoupler_tab = cx.table(&root, &decoupler::TABLE);
    let decoupler = decoupler_tab
        .as_ref()
        .and_then(|t| decoupler::decoupler(cx, t, tool.map(|t| t.mass), gravity));
    let stage = match &decoupler_tab {
        Some(t) if matches!(decoupler, Some(super::model::Decoupler::Bistable(_))) => optional(cx, t, &decoupler::rotational::TABLE, decoupler::rotational::stage),
        _ => Some(None),
    };
    let target_tab = cx.table(&root, &target::TABLE);
    let target = target_tab.as_ref().and_then(|t| target::target(cx, t));
    let sensor = optional(cx, &root, &sensor::TABLE, |cx, t| {
        sensor::sensor(cx, t, decoupler.as_ref())
    });
    let solver_tab = cx.maybe_table(&root, &solver::TABLE);
    let solver = match &solver_tab {
        Some(Some(t)) => solver::solver(cx, t, duration_s),
        Some(None) => Some(solver::default_solver()),
        None => None,
    };
    let planar = planar::planar(cx, motion_tab.as_ref(), target_tab.as_ref(), solver_tab.flatten().as_ref(), stage);
    if let (Some(Some(p)), Some(d), Some(tg), Some(dt)) = (planar, &decoupler, target, &decoupler_tab) {
        planar::check_rotational(cx, dt, &p, d, &tg);
    }
    let controller = optional(cx, &root, &controller::TABLE, controller::controller);

    // The motion must bring the tool to the target: before contact nothing brakes.
    if let (Some(m), Some(d), Some(tg), Some(tt), Some(Some(p))) = (motion, duration_s, target, &target_tab, planar) {
        planar::check_gap(cx, tt, &p, motion_law::cruise_travel(&m, d), d, tg.gap);
    } else if let (Some(m), Some(d), Some(tg), Some(tt)) = (motion, duration_s, target, &target_tab) {
        let travel = motion_law::cruise_travel(&m, d);
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

    // A linear decoupler with k = 0 holds nothing: the flange accelerates away from a tool that
    // never moves and drives through it (and through the target: issue 26 item 6). That is the
    // free tool of Fig. 1b / 4b only when the tool already cruises with the flange.
    if let (Some(super::Decoupler::Linear(l)), Some(m)) = (&decoupler, motion) {
        if l.stiffness == 0.0 && !m.start_at_speed {
            if let Some(dt) = cx.table(&root, &decoupler::TABLE) {
                cx.bad(
                    &dt,
                    "stiffness",
                    "0 holds the tool to nothing: the flange would accelerate away from a tool at rest and pass through it; a free tool (k = 0, Fig. 1b / 4b) needs motion.start_at_speed = true (the tool already cruising with the flange), otherwise give k > 0".into(),
                );
            }
        }
    }

    let scene = Scene {
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
        planar: planar?,
    };
    if cx.issues.is_empty() {
        budget::check(cx, &root, &scene);
    }
    Some(scene)
}
