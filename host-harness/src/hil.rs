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
use flinch_firmware::{Boot, BudgetConfig, Config, DigitalSwitch, DualSwitch, ResetCause, ResetPolicy, State, SwitchKind};
use flinch_hal_sim::{PinFault, SimPin, SimRig};
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
    /// The injected faults (`--fault`) and whether each ended in a stop.
    pub faults: Vec<FaultOutcome>,
    /// The stop output's level over the run as the firmware drove it: `(t_s, stop_requested)` at
    /// t = 0 (the end of the self-test, armed: go) and at every change after (a change inside a
    /// lockstep step is placed at the firmware's logged time when it logged one). For the CSV and
    /// the plot; not part of the JSON.
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


/// A fault `flinch hil --fault` can inject, and what it does to the simulated hardware.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FaultKind {
    /// The switch input (channel A of a two-channel switch) sticks at its "tool at rest" level.
    StuckRest,
    /// The switch input (channel A) sticks at its "tripped" level.
    StuckTrip,
    /// The switch input's wire (channel A) is cut: it reads its pull-down level.
    CutWire,
    /// Channel B of a two-channel switch sticks at rest (refused with one channel).
    StuckRestB,
    /// Stop relay K1's contacts weld: its mirror contact never reads "released" again.
    WeldedOutput,
    /// K1's feedback wire breaks towards "released" (reads released while pulled in).
    EdmWireCut,
    /// The firmware's clock stops.
    ClockStall,
    /// The MCU resets (as the watchdog does); the firmware restarts from its retained latch.
    Reset,
}

/// Every fault name `--fault` accepts, with what it does.
pub const FAULTS: &[(&str, FaultKind, &str)] = &[
    ("stuck-rest", FaultKind::StuckRest, "switch (channel A) stuck at the at-rest level"),
    ("stuck-trip", FaultKind::StuckTrip, "switch (channel A) stuck at the tripped level"),
    ("cut-wire", FaultKind::CutWire, "switch wire (channel A) cut"),
    ("stuck-rest-b", FaultKind::StuckRestB, "channel B of a two-channel switch stuck at rest (--channels 2)"),
    ("welded-output", FaultKind::WeldedOutput, "stop relay K1 welded (EDM never reads released)"),
    ("edm-wire-cut", FaultKind::EdmWireCut, "K1's feedback wire reads released while pulled in"),
    ("clock-stall", FaultKind::ClockStall, "the firmware's clock stops"),
    ("reset", FaultKind::Reset, "the MCU resets (watchdog); restart from the retained latch"),
];

/// One fault to inject at `at_s` seconds of simulation time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Injection {
    /// What.
    pub kind: FaultKind,
    /// When, s.
    pub at_s: f64,
}

/// Parse `--fault NAME@T[,NAME@T...]`; the error says what is allowed.
pub fn parse_faults(spec: &str) -> Result<Vec<Injection>, String> {
    let names = FAULTS.iter().map(|(n, _, _)| *n).collect::<Vec<_>>().join(", ");
    let mut out = Vec::new();
    for item in spec.split(',').map(str::trim).filter(|i| !i.is_empty()) {
        let (name, at) = item.split_once('@').ok_or_else(|| format!("--fault: NAME@SECONDS (names: {names}), got {item:?}"))?;
        let kind = FAULTS.iter().find(|(n, _, _)| *n == name).map(|(_, k, _)| *k).ok_or_else(|| format!("--fault: one of {names}, got {name:?}"))?;
        let at_s: f64 = at.parse().map_err(|_| format!("--fault {name}: a time in seconds >= 0 after @, got {at:?}"))?;
        if !(at_s.is_finite() && at_s >= 0.0) {
            return Err(format!("--fault {name}: a time in seconds >= 0 after @, got {at:?}"));
        }
        out.push(Injection { kind, at_s });
    }
    out.sort_by(|a, b| a.at_s.total_cmp(&b.at_s));
    Ok(out)
}

/// Options of a firmware-in-the-loop run beyond the controller.
#[derive(Debug, Clone, Default)]
pub struct HilOptions {
    /// Faults to inject.
    pub faults: Vec<Injection>,
    /// Two-channel (antivalent) travel switch instead of one channel.
    pub two_channels: bool,
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
}

/// Discrepancy time of the two-channel switch in `flinch hil --channels 2`, us: 20 ms.
pub const DISCREPANCY_US: u32 = 20_000;

/// Runs `scene` with the firmware in the loop and the controller `ctl`; `step` is the lockstep
/// interval in seconds. `record` keeps the time history.
pub fn run(scene: &Scene, ctl: &Controller, step: f64, record: bool) -> Result<(HilReport, Vec<Sample>), String> {
    run_with(scene, ctl, step, record, &HilOptions::default())
}

fn apply_common<S: flinch_firmware::Sensor>(rig: &mut SimRig<S>, kind: FaultKind) {
    match kind {
        FaultKind::WeldedOutput => rig.k1.set_fault(PinFault::StuckLow),
        FaultKind::EdmWireCut => rig.k1.set_fault(PinFault::StuckHigh),
        FaultKind::ClockStall => rig.clock.set_stalled(true),
        _ => {}
    }
}

fn channel_fault(kind: FaultKind, sw: SwitchKind) -> Option<PinFault> {
    let level = |tripped: bool| if sw.level_for(tripped) { PinFault::StuckHigh } else { PinFault::StuckLow };
    match kind {
        FaultKind::StuckRest | FaultKind::StuckRestB => Some(level(false)),
        FaultKind::StuckTrip => Some(level(true)),
        FaultKind::CutWire => Some(PinFault::CutWire),
        _ => None,
    }
}

/// [`run`] with faults injected and the sensor's channel count chosen. A fault list that the
/// configuration cannot take (channel B of a one-channel switch) is refused.
pub fn run_with(scene: &Scene, ctl: &Controller, step: f64, record: bool, opts: &HilOptions) -> Result<(HilReport, Vec<Sample>), String> {
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
        // With the robot's stopping table, its equivalent dead time at V_c follows the signal.
        dead_time_us: um_up(ctl.scan_cycle + scene.motion.total_dead_time() - scene.motion.dead_time),
        decel_um_per_s2: um_down(scene.motion.decel).max(1),
        stroke_um: um_down(stroke(scene)) as i32,
    };
    let mut cfg = Config::new(um(ctl.firmware_tick).max(1), budget);
    cfg.reset = ResetPolicy::Input; // latched for the whole run
    let refused = |e| format!("[controller]: the firmware refused its configuration: {e:?}");
    if opts.two_channels {
        // Antivalent pair: channel A as the single switch, channel B its complement (NO).
        let kind_b = SwitchKind::Magnetic { trip_high: !kind.trip_level_high() };
        let mut rig = SimRig::dual_after(cfg, Boot::UNKNOWN, kind, kind_b, um(threshold) as i32, DISCREPANCY_US).map_err(refused)?;
        let (a, b) = rig.channel_pins().ok_or("no channels")?;
        let apply = move |rig: &mut SimRig<DualSwitch<SimPin, SimPin, SimPin>>, f: FaultKind| match (f, channel_fault(f, if f == FaultKind::StuckRestB { kind_b } else { kind })) {
            (FaultKind::Reset, _) => rig.mcu_reset(ResetCause::Watchdog),
            (FaultKind::StuckRestB, Some(pf)) => rig.inject_pin_fault(&b, pf),
            (_, Some(pf)) => rig.inject_pin_fault(&a, pf),
            (_, None) => apply_common(rig, f),
        };
        run_loop(scene, ctl, step, record, threshold, &mut rig, opts, apply)
    } else {
        if opts.faults.iter().any(|f| f.kind == FaultKind::StuckRestB) {
            return Err("--fault stuck-rest-b: needs a two-channel switch (--channels 2); this run has one channel".into());
        }
        let mut rig = SimRig::digital(cfg, kind, um(threshold) as i32).map_err(refused)?;
        let apply = move |rig: &mut SimRig<DigitalSwitch<SimPin, SimPin>>, f: FaultKind| match (f, channel_fault(f, kind)) {
            (FaultKind::Reset, _) => rig.mcu_reset(ResetCause::Watchdog),
            (_, Some(pf)) => rig.inject_switch_fault(pf),
            (_, None) => apply_common(rig, f),
        };
        run_loop(scene, ctl, step, record, threshold, &mut rig, opts, apply)
    }
}

#[allow(clippy::too_many_arguments)]
fn run_loop<S: flinch_firmware::Sensor>(
    scene: &Scene,
    ctl: &Controller,
    step: f64,
    record: bool,
    threshold: f64,
    rig: &mut SimRig<S>,
    opts: &HilOptions,
    mut apply: impl FnMut(&mut SimRig<S>, FaultKind),
) -> Result<(HilReport, Vec<Sample>), String> {
    rig.boot(1_000_000).map_err(|s| format!("the firmware did not arm after 1 s of self-test (stuck in {s:?})"))?;
    let mut pending: std::collections::VecDeque<Injection> = opts.faults.iter().copied().collect();
    let mut outcomes: Vec<FaultOutcome> = Vec::new();

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
    // The stop output's level as the firmware drives it, recorded at each change.
    let mut stop_output = vec![(0.0, rig.stop_requested())];
    let mut note_level = |rig: &SimRig<S>, at: f64| {
        let level = rig.stop_requested();
        let (since, last) = stop_output.last().copied().unwrap_or((0.0, !level));
        if level != last {
            // The firmware's own timestamp of the change, when it logged one inside this step.
            let logged = rig.events().last().map(|e| rig.seconds_at(e.at)).filter(|&l| l > since && l <= at + 1e-9);
            stop_output.push((logged.unwrap_or(at).max(since), level));
        }
    };
    // Lockstep: every `step`, and exactly at each controller sample.
    while t < scene.duration_s {
        let next_fault = pending.front().map_or(f64::INFINITY, |f| f.at_s);
        let t_next = (t + step).min(next_sample).min(scene.duration_s).min(next_fault.max(t));
        plant.advance_to(t_next).map_err(|e| e.to_string())?;
        // The plant located the threshold crossing inside this step: give the firmware its edge at
        // that instant, not at the end of the step.
        if let (false, Some(t_sw)) = (edge_given, plant.switch_time()) {
            edge_given = true;
            rig.advance_to(t_sw);
            rig.set_travel_um(threshold_um.max(travel_um(plant.travel())));
            note_level(rig, t_sw);
        }
        rig.advance_to(t_next);
        rig.set_travel_um(travel_um(plant.travel()));
        note_level(rig, t_next);
        while let Some(f) = pending.front().copied().filter(|f| f.at_s <= t_next) {
            pending.pop_front();
            apply(rig, f.kind);
            note_level(rig, t_next);
            let name = FAULTS.iter().find(|(_, k, _)| *k == f.kind).map_or("?", |(n, _, _)| *n);
            outcomes.push(FaultOutcome { fault: name.into(), at_s: f.at_s, stopped_s: None, ended_in_go: false, reason: String::new() });
        }
        for o in outcomes.iter_mut().filter(|o| o.stopped_s.is_none()) {
            if rig.stop_requested() {
                o.stopped_s = Some(t_next);
            }
        }
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
    let go = !rig.stop_requested();
    let reason = match rig.fw.state() {
        State::Fault(c) => format!("stopped: fault latched ({})", c.name()),
        State::Tripped => "stopped: trip latched".to_string(),
        State::SelfTest(_) => "stopped: in the self-test".to_string(),
        State::Armed => "GO: the firmware is armed with the fault present (not detected)".to_string(),
    };
    for o in &mut outcomes {
        o.ended_in_go = go;
        o.reason = reason.clone();
    }
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
        faults: outcomes,
        stop_output,
    };
    let history = std::mem::take(&mut plant.sim.history);
    Ok((HilReport { summary, firmware }, history))
}
