//! Scene files: TOML in SI units, the public contract of docs/SCENES.md.
//!
//! [`load`] reads a file, [`parse`] checks a text. Every key is checked: an unknown key, a missing
//! required key, a wrong type, a non-finite number or a physically impossible value is refused, and
//! *all* problems found are reported at once in a [`SceneError`], one per line as
//! `file:line: key: message`, the message saying what is allowed. Integers are accepted where a
//! number is expected (`gap = 1` is 1.0); where an integer is expected (`springs`) a float is refused.
//!
//! # Layout: the loader mirrors the plant
//!
//! One loader file per element, named as its plant file (`plant/decoupler/bistable.rs` is read by
//! `scene/decoupler/bistable.rs`), each declaring its keys once as [`Key`] constants: name, unit,
//! allowed range with the source of each bound, default, one doc line. The validator, the key list
//! in docs/SCENES.md and the property tests read those tables ([`key_tables`]). The shared
//! machinery (line numbers, messages, every problem at once) is `check.rs`; the validated values are
//! `model.rs`.
//!
//! | table | loader | plant |
//! |---|---|---|
//! | `name`, `duration` | this file | `sim.rs` |
//! | `[motion]` | `motion_law.rs` | `plant/motion_law.rs` |
//! | `motion.stopping` | `stopping.rs` | `plant/stopping.rs` |
//! | `[robot]` | `robot.rs` | `plant/robot.rs` |
//! | `[tool]` | `tool.rs` | `plant/mod.rs` (m_t) |
//! | `[decoupler]` | `decoupler/{mod,linear,bistable,hydraulic}.rs` | `plant/decoupler/...` |
//! | `front_stop`, `back_stop` | `decoupler/end_stop.rs` | `plant/decoupler/end_stop.rs` |
//! | `friction` | `friction.rs` | `plant/friction.rs` |
//! | `[target]` | `target.rs` (damping keys: `contact.rs`) | `plant/target.rs`, `plant/contact.rs` |
//! | `[sensor]` | `sensor.rs` | `plant/sensor.rs` |
//! | `[solver]` | `solver.rs` | `solver/` |
//! | `[controller]` | `controller.rs` | `hil.rs` |
//! | `[avoid]` (an avoidance scene, `flinch avoid`) | `avoid.rs` ([`avoid::parse`]) | `avoid/` |
//!
//! # Adding a decoupler
//!
//! One plant file, one loader file, one scene, and a line in each list that names the kinds:
//! 1. `plant/decoupler/spring_pack.rs`: the mechanism's force (equations, units), and its arm in
//!    `plant::decoupler::Decoupler`;
//! 2. `scene/decoupler/spring_pack.rs`: `pub const KEYS: &[Key] = &[decoupler::KIND, Key::number(
//!    "preload", "N", Incl(0.0), Incl(500.0), "source", "F_0, the preload"), ...]` and
//!    `fn spring_pack(cx, t) -> Option<SpringPack>` reading them; its struct in `model.rs`, its
//!    name in `decoupler::KIND`, its arm in `decoupler::decoupler` and its [`KeyTable`] in
//!    [`key_tables`] (a unit test fails if a key table is not listed there);
//! 3. `scenes/spring_pack.toml`, every value with its source in a comment.
//!
//! A new key in an existing table is one [`Key`] constant beside the others, added to the table's
//! `KEYS` list and read with `cx.number(t, &MY_KEY)` in that table's function.
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
pub mod avoid;
mod budget;
mod check;
mod contact;
mod controller;
mod decoupler;
pub mod doc;
mod friction;
mod model;
mod motion_law;
mod robot;
mod sensor;
mod solver;
mod stopping;
mod target;
#[cfg(test)]
mod tests;
mod tool;

pub use budget::{estimated_steps, fastest_rate, hydraulic_rest_travel, pressed_steps, MAX_SAMPLES, MAX_STEPS, PRESSED_FACTOR};
pub use check::{Bound, Key, KeyTable, Need, SceneError, SceneIssue, Span, Ty};
pub use decoupler::end_stop::DEFAULT_BACK_STOP_LAW;
pub use decoupler::hydraulic::{DEFAULT_ADIABATIC_EXPONENT, DEFAULT_HYDRAULIC_FRICTION_V0};
pub use model::*;
pub use robot::{referenced_files, urdf_robot, UrdfRobot, DAMPING as ROBOT_DAMPING, MASS as ROBOT_MASS, STIFFNESS as ROBOT_STIFFNESS};
pub use solver::{
    DEFAULT_ATOL, DEFAULT_MAX_STEP, DEFAULT_METHOD, DEFAULT_OUTPUT_INTERVAL, DEFAULT_RTOL,
    FAST_ATOL, FAST_RTOL, REFERENCE_ATOL, REFERENCE_RTOL,
};

use check::{approx, num, Bound::*, Ctx, Tab};
use std::path::Path;

/// `name`: echoed in every output.
const NAME: Key = Key::of("name", Ty::Text, "a human-readable name, echoed in the summary");
/// `duration`: simulated time.
const DURATION: Key = Key::number(
    "duration",
    "s",
    Excl(0.0),
    Incl(60.0),
    "a collision and the stop that follows last under a second (the thesis runs 0.06-0.8 s); 60 s bounds run time and output",
    "simulated time from the start of the motion (t = 0)",
);

/// The top-level keys.
const ROOT: &[Key] = &[
    NAME,
    DURATION,
    motion_law::TABLE,
    robot::TABLE,
    tool::TABLE,
    decoupler::TABLE,
    target::TABLE,
    sensor::TABLE,
    solver::TABLE,
    controller::TABLE,
];

/// `KeyTable::when` of the avoidance scene's tables.
pub const AVOID_SCENE: &str = "avoidance scene";

/// Every table of a scene and its keys: the one source the validator, the docs and the property
/// tests read.
pub fn key_tables() -> &'static [KeyTable] {
    const TABLES: &[KeyTable] = &[
        KeyTable { path: "", when: "", keys: ROOT },
        KeyTable { path: "motion", when: "", keys: motion_law::KEYS },
        KeyTable { path: "motion.stopping", when: "", keys: stopping::KEYS },
        KeyTable { path: "robot", when: "", keys: robot::KEYS },
        KeyTable { path: "tool", when: "", keys: tool::KEYS },
        KeyTable { path: "decoupler", when: "kind = \"rigid\"", keys: decoupler::RIGID_KEYS },
        KeyTable { path: "decoupler", when: "kind = \"linear\"", keys: decoupler::linear::KEYS },
        KeyTable { path: "decoupler", when: "kind = \"bistable\"", keys: decoupler::bistable::KEYS },
        KeyTable { path: "decoupler", when: "kind = \"hydraulic\"", keys: decoupler::hydraulic::KEYS },
        KeyTable { path: "decoupler.front_stop", when: "", keys: decoupler::end_stop::FRONT_KEYS },
        KeyTable { path: "decoupler.back_stop", when: "", keys: decoupler::end_stop::BACK_KEYS },
        KeyTable { path: "decoupler.friction", when: "kind = \"bistable\"", keys: friction::KEYS },
        KeyTable { path: "target", when: "kind = \"obstacle\"", keys: target::OBSTACLE_KEYS },
        KeyTable { path: "target", when: "kind = \"object\"", keys: target::OBJECT_KEYS },
        KeyTable { path: "target", when: "kind = \"body_region\"", keys: target::BODY_KEYS },
        KeyTable { path: "sensor", when: "kind = \"travel\"", keys: sensor::TRAVEL_KEYS },
        KeyTable { path: "sensor", when: "kind = \"force\"", keys: sensor::FORCE_KEYS },
        KeyTable { path: "solver", when: "", keys: solver::KEYS },
        KeyTable { path: "controller", when: "", keys: controller::KEYS },
        // Avoidance scenes (`flinch avoid`, docs/avoidance.md): read by `avoid::parse`.
        KeyTable { path: "avoid", when: AVOID_SCENE, keys: avoid::KEYS },
        KeyTable { path: "avoid.safety", when: AVOID_SCENE, keys: avoid::SAFETY_KEYS },
        KeyTable { path: "avoid.camera", when: AVOID_SCENE, keys: avoid::CAMERA_KEYS },
        KeyTable { path: "avoid.fit", when: AVOID_SCENE, keys: avoid::FIT_KEYS },
        KeyTable { path: "avoid.robot", when: AVOID_SCENE, keys: avoid::ROBOT_KEYS },
        KeyTable { path: "avoid.operator", when: AVOID_SCENE, keys: avoid::OPERATOR_KEYS },
        KeyTable { path: "avoid.operator.keyframes[]", when: AVOID_SCENE, keys: avoid::KEYFRAME_KEYS },
        KeyTable { path: "avoid.depth_camera", when: AVOID_SCENE, keys: avoid::DEPTH_CAMERA_KEYS },
        KeyTable { path: "avoid.operator.obstacles[]", when: "avoidance scene, kind = \"disc\"", keys: avoid::DISC_KEYS },
        KeyTable { path: "avoid.operator.obstacles[]", when: "avoidance scene, kind = \"box\"", keys: avoid::BOX_KEYS },
        KeyTable { path: "avoid.operator.obstacles[].keyframes[]", when: AVOID_SCENE, keys: avoid::OBSTACLE_KEYFRAME_KEYS },
    ];
    TABLES
}

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
    let doc = check::parse_toml(text, file)?;
    let mut cx = Ctx {
        text,
        file,
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
    let motion = cx
        .table(&root, &motion_law::TABLE)
        .and_then(|t| motion_law::motion(cx, &t, tool.map(|t| t.mass)));
    let robot = optional(cx, &root, &robot::TABLE, robot::robot);
    let gravity = motion.map(|m| m.gravity);
    let decoupler = cx
        .table(&root, &decoupler::TABLE)
        .and_then(|t| decoupler::decoupler(cx, &t, tool.map(|t| t.mass), gravity));
    let target_tab = cx.table(&root, &target::TABLE);
    let target = target_tab.as_ref().and_then(|t| target::target(cx, t));
    let sensor = optional(cx, &root, &sensor::TABLE, |cx, t| {
        sensor::sensor(cx, t, decoupler.as_ref())
    });
    let solver = match cx.maybe_table(&root, &solver::TABLE) {
        Some(Some(t)) => solver::solver(cx, &t, duration_s),
        Some(None) => Some(solver::default_solver()),
        None => None,
    };
    let controller = optional(cx, &root, &controller::TABLE, controller::controller);

    // The motion must bring the tool to the target: before contact nothing brakes.
    if let (Some(m), Some(d), Some(tg), Some(tt)) = (motion, duration_s, target, &target_tab) {
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
    };
    if cx.issues.is_empty() {
        budget::check(cx, &root, &scene);
    }
    Some(scene)
}
