//! Firmware in the loop (`flinch hil`): the plant and the very same firmware library that runs on
//! the MCU, stepped in lockstep through `hal-sim`'s stateful fakes.
//!
//! Each loop step (10 us by default) the plant is integrated to t, the firmware's ticks up to t
//! run, and the plant's travel drives the switch pin (edges reach the firmware's interrupt path at
//! once). The robot controller model samples the stop output once per scan cycle, at
//! `phase * scan_cycle + k * scan_cycle`, and brakes at the first sample that sees it: the dead
//! time is what comes out, between the firmware latency and one scan cycle more (Ch. 3.1.2: "in
//! the worst case ... it is necessary to wait a full scan cycle").

use crate::check::{um_down, um_up};
use crate::scene::{Controller, Decoupler, Scene, Sensor};
use crate::sim::{Run, Sample, Summary};
use flinch_firmware::{BudgetConfig, Config, ResetPolicy, SwitchKind};
use flinch_hal_sim::SimRig;
use serde::Serialize;

/// Default lockstep interval between plant and firmware, s.
pub const DEFAULT_STEP: f64 = 1e-5;

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
    /// firmware_detect - switch_time, s.
    #[serde(rename = "firmware_latency_s")]
    pub firmware_latency: Option<f64>,
    /// The controller sample that saw the stop request, s (= t_brake).
    #[serde(rename = "stop_seen_s")]
    pub stop_seen: Option<f64>,
    /// Observed dead time t_brake - switch_time, s.
    #[serde(rename = "observed_dead_time_s")]
    pub observed_dead_time: Option<f64>,
    /// The firmware asked for a category-0 stop (stroke budget exceeded).
    pub category0: bool,
    /// The firmware's event log.
    pub event_log: Vec<LoggedEvent>,
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

/// Total stroke the budget may use, m (front stop to back stop).
fn stroke(scene: &Scene) -> f64 {
    match &scene.decoupler {
        Decoupler::Bistable(b) => b.front_stroke + b.back_stroke,
        Decoupler::Hydraulic(h) => h.stroke,
        _ => 0.0,
    }
}

fn um(x: f64) -> u32 {
    (x * 1e6).round().clamp(0.0, u32::MAX as f64) as u32
}


/// Runs `scene` with the firmware in the loop and the controller `ctl`; `step` is the lockstep
/// interval in seconds. `record` keeps the time history.
pub fn run(scene: &Scene, ctl: &Controller, step: f64, record: bool) -> Result<(HilReport, Vec<Sample>), String> {
    let threshold = match (&scene.sensor, &scene.decoupler) {
        (Some(Sensor::Travel { threshold }), Decoupler::Bistable(_) | Decoupler::Hydraulic(_) | Decoupler::Linear(_)) => *threshold,
        (Some(Sensor::Force { .. }), _) | (_, Decoupler::Rigid) => {
            return Err("sensor.kind: flinch hil needs a travel switch (sensor.kind = \"travel\") on a decoupler; a rigid tool's force sensor is not read by this firmware".into())
        }
        (None, _) => return Err("[sensor]: flinch hil needs a travel switch; the scene has no [sensor]".into()),
    };
    // Inductive on the bi-stable slide (ON at the front stop), magnetic on the hydraulic piston, wired
    // low-on-trip so that a cut wire reads as a trip (fail-safe) for both.
    let kind = if matches!(scene.decoupler, Decoupler::Hydraulic(_)) { SwitchKind::Magnetic { trip_high: false } } else { SwitchKind::Inductive };
    let budget = BudgetConfig {
        robot_speed_um_per_s: um_up(scene.motion.speed),
        dead_time_us: um_up(ctl.scan_cycle),
        decel_um_per_s2: um_down(scene.motion.decel).max(1),
        stroke_um: um_down(stroke(scene)) as i32,
    };
    let mut cfg = Config::new(um(ctl.firmware_tick).max(1), budget);
    cfg.reset = ResetPolicy::Input; // latched for the whole run
    let mut rig = SimRig::digital(cfg, kind, um(threshold) as i32).map_err(|e| format!("[controller]: the firmware refused its configuration: {e:?}"))?;
    rig.boot(1_000_000).map_err(|s| format!("the firmware did not arm after 1 s of self-test (stuck in {s:?})"))?;

    let mut plant = Run::new(scene, true, record);
    let scan = ctl.scan_cycle;
    let mut next_sample = ctl.phase * scan;
    let mut stop_seen = None;
    let mut category0 = false;
    let threshold_um = um(threshold) as i32;
    // Floor to whole micrometres: the switch must not trip before the travel reaches d_sw.
    let travel_um = |m: f64| (m * 1e6).floor().clamp(i32::MIN as f64, i32::MAX as f64) as i32;
    let mut edge_given = false;
    let mut t = 0.0_f64;
    // Lockstep: every `step`, and exactly at each controller sample.
    while t < scene.duration_s {
        let t_next = (t + step).min(next_sample).min(scene.duration_s);
        plant.advance_to(t_next).map_err(|e| e.to_string())?;
        // The plant located the threshold crossing inside this step: give the firmware its edge at
        // that instant, not at the end of the step.
        if let (false, Some(t_sw)) = (edge_given, plant.switch_time()) {
            edge_given = true;
            rig.advance_to(t_sw);
            rig.set_travel_um(threshold_um.max(travel_um(plant.travel())));
        }
        rig.advance_to(t_next);
        rig.set_travel_um(travel_um(plant.travel()));
        if t_next >= next_sample {
            if stop_seen.is_none() && rig.stop_requested() {
                stop_seen = Some(next_sample);
                category0 = rig.category0_requested();
                plant.command_brake(next_sample);
            }
            next_sample += scan;
        }
        t = t_next;
    }
    let summary = plant.summary();
    let switch_time = summary.t_detect;
    let firmware_detect = rig.detected_at_s();
    let event_log = rig
        .events()
        .iter()
        .map(|e| LoggedEvent {
            seq: e.seq,
            cause: format!("{:?}", e.cause),
            flags: e.flags,
            at_s: rig.seconds_at(e.at),
            first_seen_s: rig.seconds_at(e.first_seen),
            travel_m: e.travel_um as f64 * 1e-6,
        })
        .collect();
    let firmware = FirmwareFigures {
        scan_cycle: scan,
        phase: ctl.phase,
        firmware_tick: ctl.firmware_tick,
        switch_time,
        firmware_detect,
        firmware_latency: firmware_detect.zip(switch_time).map(|(f, s)| f - s),
        stop_seen,
        observed_dead_time: summary.t_brake.zip(switch_time).map(|(b, s)| b - s),
        category0,
        event_log,
    };
    let history = std::mem::take(&mut plant.sim.history);
    Ok((HilReport { summary, firmware }, history))
}
