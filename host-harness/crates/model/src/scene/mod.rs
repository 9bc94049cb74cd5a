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
//! One loader file per element, named as its plant file (`plant/decoupler/bistable.rs`, in
//! `host-harness/crates/plant/src/`, is read by `scene/decoupler/bistable.rs`), each declaring its
//! keys once as [`Key`] constants: name, unit, allowed range with the source of each bound,
//! default, one doc line. The validator, the key list
//! in docs/SCENES.md and the property tests read those tables ([`key_tables`]). The shared
//! machinery (line numbers, messages, every problem at once) is `check.rs`; the validated values are
//! `model.rs`; [`load`] and [`parse`] are in `load.rs` (its first comment lists the keys accepted
//! beyond SCENES.md and their defaults), [`key_tables`] in `tables.rs`.
//!
//! | table | loader | plant |
//! |---|---|---|
//! | `name`, `duration` | `tables.rs`, `load.rs` | `flinch-sim` |
//! | `[motion]` | `motion_law.rs` | `plant/motion_law.rs` |
//! | `motion.stopping` | `stopping.rs` | `crate::stopping` (the table), `plant/motion_law.rs` |
//! | `[robot]` | `robot.rs` | `plant/robot.rs` |
//! | `[tool]` | `tool.rs` | `plant/mod.rs` (m_t) |
//! | `[decoupler]` | `decoupler/{mod,linear,bistable,hydraulic}.rs` | `plant/decoupler/...` |
//! | `front_stop`, `back_stop` | `decoupler/end_stop.rs` | `plant/decoupler/end_stop.rs` |
//! | `friction` | `friction.rs` | `plant/friction.rs` |
//! | `[target]` | `target.rs` (damping keys: `contact.rs`) | `plant/target.rs`, `plant/contact.rs` |
//! | `[sensor]` | `sensor.rs` | `plant/sensor.rs` |
//! | `[solver]` | `solver.rs` | `flinch-solver` |
//! | `[controller]` | `controller.rs` | `flinch-hil` |
//! | `[avoid]` (an avoidance scene, `flinch avoid`) | `avoid/` ([`avoid::parse`]) | `flinch-avoid` |
//!
//! # Adding a decoupler
//!
//! One plant file, one loader file, one scene, and a line in each list that names the kinds:
//! 1. `plant/decoupler/spring_pack.rs`: the mechanism's force (equations, units), and its arm in
//!    `plant::decoupler::Decoupler`;
//! 2. `scene/decoupler/spring_pack.rs`: `pub const KEYS: &[Key] = &[decoupler::KIND, Key::number(
//!    "preload", "N", Incl(0.0), Incl(500.0), "source", "F_0, the preload"), ...]` and
//!    `fn spring_pack(cx, t) -> Option<SpringPack>` reading them; its struct in `model.rs`, its
//!    name in `decoupler/kind.rs`'s `KIND`, its arm in `decoupler/read.rs` and its [`KeyTable`]
//!    in `tables.rs`'s [`key_tables`] (a unit test fails if a key table is not listed there);
//! 3. `scenes/spring_pack.toml`, every value with its source in a comment.
//!
//! A new key in an existing table is one [`Key`] constant beside the others, added to the table's
//! `KEYS` list and read with `cx.number(t, &MY_KEY)` in that table's function.
//!
pub mod avoid;
mod budget;
mod check;
mod contact;
mod controller;
mod decoupler;
pub mod doc;
mod friction;
mod load;
mod model;
mod motion_law;
pub mod planar;
mod robot;
mod sensor;
mod solver;
mod stopping;
mod tables;
mod target;
#[cfg(test)]
mod tests;
mod tool;

pub use budget::{estimated_steps, fastest_rate, hydraulic_rest_travel, pressed_steps, MAX_SAMPLES, MAX_STEPS, PRESSED_FACTOR};
pub use check::{Bound, Key, KeyTable, Need, SceneError, SceneIssue, Span, Ty};
pub use controller::whole_us;
pub use decoupler::end_stop::DEFAULT_BACK_STOP_LAW;
pub use decoupler::hydraulic::{DEFAULT_ADIABATIC_EXPONENT, DEFAULT_HYDRAULIC_FRICTION_V0};
pub use model::*;
pub use robot::{referenced_files, urdf_robot, UrdfRobot, DAMPING as ROBOT_DAMPING, MASS as ROBOT_MASS, STIFFNESS as ROBOT_STIFFNESS};
pub use solver::{
    DEFAULT_ATOL, DEFAULT_MAX_STEP, DEFAULT_METHOD, DEFAULT_OUTPUT_INTERVAL, DEFAULT_RTOL,
    FAST_ATOL, FAST_RTOL, REFERENCE_ATOL, REFERENCE_RTOL,
};
pub use load::{load, parse};
pub use controller::{FIRMWARE_TICK as CONTROLLER_FIRMWARE_TICK, PHASE as CONTROLLER_PHASE, SCAN_CYCLE as CONTROLLER_SCAN_CYCLE};
pub use motion_law::{DEAD_TIME as MOTION_DEAD_TIME, SPEED as MOTION_SPEED};

/// A command-line number that stands for a scene key (`hil --scan-cycle` for
/// `controller.scan_cycle`, `design --speed` for `motion.speed`, ...), held to that key's range
/// with the key's own refusal (issue 27): `controller.scan_cycle: allowed range [1e-5, 0.1] s
/// (...), got 9e-6`. Used as a clap value parser, so a bad value is refused (exit 2) before any
/// file is read. `key_path` is the key as a scene names it.
pub fn option_number(key_path: &str, key: &Key, text: &str) -> Result<f64, String> {
    let x: f64 = text.trim().parse().map_err(|_| format!("{key_path}: must be a number, got \"{text}\""))?;
    let Ty::Number(span) = key.ty else { return Err(format!("{key_path}: is not a number key")) };
    if !x.is_finite() || !span.contains(x) {
        return Err(format!("{key_path}: {}", span.refuse(x)));
    }
    if key_path == "controller.firmware_tick" && !whole_us(x) {
        return Err(format!("{key_path}: a whole number of microseconds (the firmware's clock counts them), got {text}"));
    }
    Ok(x)
}
pub use tables::{key_tables, AVOID_SCENE};
