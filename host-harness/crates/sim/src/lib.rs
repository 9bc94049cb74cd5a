//! A scene run: the plant integrated with its events, and what the summary reports.
//!
//! Events (located, not sampled): 0 tool-target contact onset/separation, 1 front end-stop
//! entry/exit, 2 back end-stop entry/exit, 3 the sensor's threshold, and 4-6 the instants where
//! the contact, the front stop or the back stop stops pushing (or starts again) while still
//! penetrated: its damping term cancels the spring term and the clamp at zero force (no adhesion)
//! takes over. That clamp is a kink in the right-hand side; located as an event, the step ends on
//! it instead of the error control hacking at it with a dozen rejected steps (docs/accuracy.md).
//! Event 7 switches a Coulomb slide (`decoupler.friction.law = "stick-slip"`, `plant::friction`)
//! between sticking and slipping. Breakpoints: end of the
//! acceleration, start and end of braking. Contact dampings chi are fixed at each onset from the
//! approach velocity (eq 7).
//!
//! Layout: `simulation.rs` the hybrid system (right-hand side, events, steps observed), `events.rs`
//! the event indices, `peaks.rs` the peaks inside a step, `rest.rs` the at-rest check, `run.rs` a
//! run and its summary, `record.rs` the instants recorded, `summary.rs` what a run reports, `verdict.rs` the one verdict,
//! `simplify.rs` the simplifications a scene may ask for.

mod events;
#[cfg(test)]
mod friction_tests;
mod peaks;
mod record;
mod rest;
mod run;
mod simplify;
mod simulation;
mod summary;
pub mod verdict;

pub use events::E;
pub use record::{record_due, recorded_rows};
pub use run::{run, run_to_conclusion, Run, LONGEST_RUN_S};
pub use simplify::simplified;
pub use simulation::{Probe, Simulation, Sink};
pub use summary::{achieved_restitution, detection_delay, reaction_time, Sample, Summary, RESTITUTION_SLACK};
