//! Firmware in the loop (`flinch hil`): the plant and the very same firmware library that runs on
//! the MCU, coupled through `hal-sim`'s stateful fakes.
//!
//! # How the two are stepped
//!
//! The plant takes the steps its solver takes in a plain run (one at a time, to the step the solver
//! proposes), and after each one the firmware catches up: the plant's dense output gives the travel
//! at every firmware tick inside the step, and a switch edge between two of those instants is
//! located on the dense output (bisection, to 1e-12 s) and handed to the firmware's interrupt path
//! at that instant. The plant is not restarted at every tick: it lands only where the firmware can
//! change it, at the controller's samples until the stop has been seen, and where drive power is
//! removed (category 0). So a `hil` run costs about what `flinch run` costs (docs/accuracy.md,
//! "Firmware in the loop").
//!
//! A category-0 removal the firmware decides inside a plant step is found after the step: where
//! the arm cruised at constant speed since, the plant takes it at its instant all the same
//! (`Run::remove_power`); elsewhere (accelerating, braking) the run starts again with the removal
//! scheduled at its instant from t = 0, a breakpoint the solver steps onto ([`run_passes`]). The
//! power-off instant is then the firmware's decision plus its output latency whatever the step
//! grid (`tests/hil.rs`, `a_category_0_power_removal_lands_at_its_instant_whatever_the_step_grid`).
//!
//! # What the robot sees
//!
//! The stop output reaches the controller `hal_sim::latency::edge_to_stop_s()` (20.75 us, the board
//! ELF's measured worst case at its clock; QEMU's instruction count is the proxy for cycles) after
//! the edge, or `tick_to_output_s()` (1,518 us) after a tick that confirms a filtered trip. The robot
//! controller model samples it once per scan cycle, at `phase * scan_cycle + k * scan_cycle`, and
//! the robot starts its controlled stop its reaction time after the first sample that sees it: the
//! dead time is what comes out, the firmware latency + a wait between 0 and one scan cycle (Ch.
//! 3.1.2: "in the worst case ... it is necessary to wait a full scan cycle") + the reaction
//! (`timing.rs`: `[controller] reaction_time`, by default the scene's DT less one scan). The escalation
//! output (category 0, IEC 60204-1 9.2.2) acts on the drives' power directly, not through the scan
//! cycle: `tick_to_output_s()` after the firmware's decision, drive power is removed and the robot's
//! brakes stop it (`plant/brake.rs`: `[controller] brake_delay`, `brake_decel`, or a category-0
//! `motion.stopping` table).
//!
//! Layout: `run.rs` the entry points and passes, `stepping.rs` one pass (plant steps, firmware
//! ticks, edges, the controller's samples), `timing.rs` how the dead time is formed,
//! `output_budget.rs` the board's output faults against the stroke budget, `options.rs`
//! the faults, filter and reset policy, `report.rs` what a run reports (and its text),
//! `units.rs` SI to the firmware's micro-units.

mod options;
mod output_budget;
mod report;
mod run;
mod stepping;
pub mod timing;
pub mod units;

pub use flinch_hal_sim::latency;
pub use options::*;
pub use output_budget::{output_fault_budget, OutputFaultBudget};
pub use report::*;
pub use run::{output_fault_bound_s, refusal, run, run_recording, run_with};
