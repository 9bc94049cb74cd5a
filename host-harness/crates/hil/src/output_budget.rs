//! The board's output faults (issue 25 item 3) carried into the stroke budget, for `flinch check`:
//! for each one, how much later than with healthy outputs the cell is safe after a demand
//! (`hal_sim::output_faults`), which stop then acts, and whether its stopping distance still fits
//! the stroke left at detection.
//!
//! A stuck stop pin, a frozen port of one channel and a welded K2 leave the other relay to open the
//! stop circuit at the edge: the controlled stop of `motion.dead_time` as without the fault (a frozen
//! escalation port leaves both stop channels). Both relays welded leave only the escalation: drive
//! power is removed after the EDM's settle time, two ticks and the board's tick-to-output, and the
//! arm coasts for the category-0 brake's delay, then brakes (`[controller] brake_delay`,
//! `brake_decel`, or a category-0 `motion.stopping` table; plant/brake.rs). `flinch hil --fault NAME`
//! runs each of them in the loop (tests/hil_output_faults.rs).

use crate::run::{firmware_config, output_fault_bound_s};
use crate::stepping::cat0_brake;
use flinch_hal_sim::OutputFault;
use flinch_model::scene::{Controller, Scene};
use serde::Serialize;

/// One output fault against the stroke budget. JSON names carry their unit.
#[derive(Debug, Clone, Serialize, PartialEq, schemars::JsonSchema)]
pub struct OutputFaultBudget {
    /// The fault (`flinch hil --fault` spelling).
    pub fault: String,
    /// How much later the cell is safe after a demand, at most, s.
    pub extra_dead_time_s: f64,
    /// Which stop acts, for people.
    pub stop: String,
    /// Stopping distance after detection with the fault, m.
    pub stopping_distance_m: f64,
    /// It fits the stroke left at detection.
    pub fits: bool,
}

/// Every output fault of the board against the budget of `scene`: `healthy_m` is the stopping
/// distance after detection with healthy outputs, `remaining_m` the stroke left at detection. The
/// firmware's tick and the category-0 brake come from `[controller]` (else `flinch hil`'s defaults:
/// a 0.1 ms tick, plant/brake.rs's brake).
pub fn output_fault_budget(scene: &Scene, healthy_m: f64, remaining_m: f64) -> Vec<OutputFaultBudget> {
    let ctl = scene.controller.unwrap_or(Controller::new(0.016, 0.0, 1e-4));
    let cfg = firmware_config(scene, &ctl);
    let (brake, source) = cat0_brake(scene, &ctl);
    let v = scene.motion.speed;
    OutputFault::ALL
        .iter()
        .map(|&f| {
            let extra = output_fault_bound_s(&cfg, f);
            let (stop, d) = if extra > 0.0 {
                let d = v * (extra + brake.delay) + v * v / (2.0 * brake.decel);
                (format!("category 0 only (the stop circuit cannot open): drive power off {:.3} ms after the demand, then the brakes ({source})", extra * 1e3), d)
            } else if f == OutputFault::FrozenPort(flinch_hal_sim::OutputPort::Escalation) {
                ("both stop channels open the stop circuit; category 0 is lost".into(), healthy_m)
            } else {
                ("the other stop channel opens the stop circuit at the edge".into(), healthy_m)
            };
            OutputFaultBudget { fault: f.name().into(), extra_dead_time_s: extra, stop, stopping_distance_m: d, fits: d <= remaining_m }
        })
        .collect()
}
