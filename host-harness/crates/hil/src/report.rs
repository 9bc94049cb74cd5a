//! What a `flinch hil` run reports: the run's summary with the firmware's figures (its timestamps,
//! the stop and escalation outputs, the controller's samples, the event log), each injected
//! fault's outcome, and the firmware signals of a recorded row.

use flinch_sim::{Sample, Summary};
use serde::Serialize;

/// One entry of the firmware's event log, in simulation seconds.
#[derive(Debug, Clone, Serialize, PartialEq, schemars::JsonSchema)]
pub struct LoggedEvent {
    /// Sequence number.
    pub seq: u16,
    /// Cause, as the firmware names it.
    pub cause: String,
    /// Flag bits.
    pub flags: u8,
    /// When the stop output was dropped, s.
    pub at_s: f64,
    /// When the sensor was first seen tripped, s.
    pub first_seen_s: f64,
    /// Travel at detection, m.
    pub travel_m: f64,
}

/// What the firmware in the loop adds to the run's summary. JSON names carry their unit
/// (docs/conventions.md).
#[derive(Debug, Clone, Serialize, PartialEq, schemars::JsonSchema)]
pub struct FirmwareFigures {
    /// The controller's scan cycle, s.
    #[serde(rename = "scan_cycle_s")]
    pub scan_cycle: f64,
    /// Phase of its first sample, fraction of a cycle.
    pub phase: f64,
    /// The firmware's tick period, s.
    #[serde(rename = "firmware_tick_s")]
    pub firmware_tick: f64,
    /// When the plant's travel crossed the switch threshold (located event), s.
    #[serde(rename = "switch_time_s")]
    pub switch_time: Option<f64>,
    /// The firmware's own detection timestamp, s.
    #[serde(rename = "firmware_detect_s")]
    pub firmware_detect: Option<f64>,
    /// firmware_detect - switch_time, s: never negative (the firmware's clock counts whole
    /// microseconds and is read at or after the edge: 0 to 1 us without a filter).
    #[serde(rename = "firmware_latency_s")]
    pub firmware_latency: Option<f64>,
    /// The controller sample that saw the stop request, s (braking follows
    /// `dead_time_model.reaction_time_s` later).
    #[serde(rename = "stop_seen_s")]
    pub stop_seen: Option<f64>,
    /// How the dead time was formed: board latency + scan wait + the robot's reaction (timing.rs).
    pub dead_time_model: crate::timing::DeadTimeModel,
    /// Observed dead time t_brake - switch_time, s.
    #[serde(rename = "observed_dead_time_s")]
    pub observed_dead_time: Option<f64>,
    /// The firmware asked for a category-0 stop (stroke budget exceeded).
    pub category0: bool,
    /// Drive power removed (the escalation output, plus its latency), s; null without category 0.
    #[serde(rename = "power_removed_s")]
    pub power_removed: Option<f64>,
    /// The robot's brakes acting after the power removal, s (plant/brake.rs).
    #[serde(rename = "brakes_engaged_s")]
    pub brakes_engaged: Option<f64>,
    /// Where the category-0 brake's figures came from.
    pub brake_source: String,
    /// The firmware's edge-to-stop latency the plant was given, s (hal_sim::latency: the board
    /// ELF's measured worst case at its clock, instructions a proxy for cycles).
    #[serde(rename = "edge_to_stop_latency_s")]
    pub edge_to_stop_latency: f64,
    /// The latency of an output written on a tick or by the edge's bookkeeping (a filtered trip,
    /// the escalation), s.
    #[serde(rename = "tick_to_output_latency_s")]
    pub tick_to_output_latency: f64,
    /// The firmware's glitch filter (`--filter`).
    pub filter: String,
    /// How a trip is cleared (`--reset-policy`).
    pub reset_policy: String,
    /// The firmware's event log.
    pub event_log: Vec<LoggedEvent>,
    /// From the demand (the switch) to the cell's first safe instant, s: the stop circuit open as
    /// the controller reads it, or drive power removed (category 0); 0 when it was safe already
    /// (a fault found before the demand). Null without a demand or without a safe instant.
    pub demand_to_safe_s: Option<f64>,
    /// The injected faults (`--fault`) and whether each ended in a stop.
    pub faults: Vec<FaultOutcome>,
    /// The stop output's level over the run as the robot controller's input sees it:
    /// `(t_s, stop_requested)` at t = 0 (the end of the self-test, armed: go) and at every change
    /// after, the firmware's write plus its latency. For the CSV and the plot; not part of the JSON.
    #[serde(skip)]
    #[schemars(skip)]
    pub stop_output: Vec<(f64, bool)>,
}

/// The `flinch hil --json` object: the run's summary plus the firmware's figures.
#[derive(Debug, Clone, Serialize, schemars::JsonSchema)]
pub struct HilReport {
    /// Same fields as `flinch run --json`.
    #[serde(flatten)]
    pub summary: Summary,
    /// The firmware's figures.
    pub firmware: FirmwareFigures,
}

/// What became of one injected fault. JSON names carry their unit.
#[derive(Debug, Clone, Serialize, PartialEq, schemars::JsonSchema)]
pub struct FaultOutcome {
    /// The fault's name (`--fault` spelling).
    pub fault: String,
    /// When it was injected, s.
    pub at_s: f64,
    /// First lockstep instant at or after the injection with the stop output de-energised, s.
    pub stopped_s: Option<f64>,
    /// The stop output was energised ("go") at the end of the run: the fault was not made safe.
    pub ended_in_go: bool,
    /// Why the firmware was stopped at the end (its state), or why it was not.
    pub reason: String,
    /// For an output fault: how much later than with healthy outputs the cell is safe after a
    /// demand at most, s (`hal_sim::output_faults::extra_dead_time_us`, plus the board's
    /// tick-to-output when only category 0 is left); null for an input fault.
    pub extra_dead_time_bound_s: Option<f64>,
}

/// What the firmware had done by a recorded sample's instant, for its CSV row.
pub struct RowSignals<'a> {
    /// The stop output as the controller's input sees it (see [`FirmwareFigures::stop_output`]).
    pub stop_output: &'a [(f64, bool)],
    /// The controller sample that saw the stop, once there was one.
    pub stop_seen: Option<f64>,
}

/// Where the recorded time history goes.
pub enum Record<'a> {
    /// Nowhere.
    Nothing,
    /// Kept and returned (tests, short runs).
    History,
    /// Handed over sample by sample, once the firmware has caught up with its instant (a streamed
    /// CSV, a decimated plot: memory stays bounded whatever the duration).
    Stream(&'a mut dyn FnMut(&Sample, &RowSignals<'_>)),
}

/// The firmware's part of `flinch hil`'s text, under the run's summary: how the dead time was
/// formed first (timing.rs), then the firmware's timestamps, latencies, escalation and faults.
pub fn human(f: &FirmwareFigures) -> String {
    let ms = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{:.3} ms", v * 1e3));
    let mut t = format!("  dead time {}\n", f.dead_time_model.formed);
    let phase = if f.dead_time_model.worst_phase { "phase worst".to_string() } else { format!("phase {:.2}", f.phase) };
    t.push_str(&format!("  firmware in the loop: scan cycle {:.3} ms, {phase}, tick {:.3} ms, filter {}, reset {}\n", f.scan_cycle * 1e3, f.firmware_tick * 1e3, f.filter, f.reset_policy));
    t.push_str(&format!("    switch {}   firmware timestamp {}   latency {}   controller saw the stop {}\n", ms(f.switch_time), ms(f.firmware_detect), ms(f.firmware_latency), ms(f.stop_seen)));
    t.push_str(&format!("    observed dead time {}   event log: {} entr{}\n", ms(f.observed_dead_time), f.event_log.len(), if f.event_log.len() == 1 { "y" } else { "ies" }));
    t.push_str(&format!(
        "    board latency given to the plant: edge to stop {:.2} us, tick or bookkeeping to output {:.2} us ({})\n",
        f.edge_to_stop_latency * 1e6,
        f.tick_to_output_latency * 1e6,
        flinch_hal_sim::latency::SOURCE
    ));
    if f.category0 {
        let why = if f.faults.iter().any(|o| o.reason.contains("(category 0)")) { "the stop circuit could not open" } else { "stroke budget exceeded" };
        t.push_str(&format!("    CATEGORY 0 requested ({why}): drive power removed {}, brakes acting {} ({})\n", ms(f.power_removed), ms(f.brakes_engaged), f.brake_source));
    }
    for o in &f.faults {
        t.push_str(&format!("    fault {} at {:.3} s: stop {}; {}\n", o.fault, o.at_s, o.stopped_s.map_or("never".to_string(), |s| format!("from {s:.4} s")), o.reason));
        if let Some(x) = o.extra_dead_time_bound_s {
            t.push_str(&format!("      output fault: adds up to {} to the dead time after a demand (hal-sim output_faults); this run: safe {} after the switch\n", ms(Some(x)), ms(f.demand_to_safe_s)));
        }
    }
    t
}
