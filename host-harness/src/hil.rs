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
//! The stop output reaches the controller `hal_sim::latency::edge_to_stop_s()` (7.25 us, the
//! measured QEMU worst case at the board's clock) after the edge, or `tick_to_output_s()` after a
//! tick that confirms a filtered trip. The robot controller model samples it once per scan cycle, at
//! `phase * scan_cycle + k * scan_cycle`, and starts its controlled stop at the first sample that
//! sees it: the dead time is what comes out, between the firmware latency and one scan cycle more
//! (Ch. 3.1.2: "in the worst case ... it is necessary to wait a full scan cycle"). The escalation
//! output (category 0, IEC 60204-1 9.2.2) acts on the drives' power directly, not through the scan
//! cycle: `tick_to_output_s()` after the firmware's decision, drive power is removed and the robot's
//! brakes stop it (`plant/brake.rs`: `[controller] brake_delay`, `brake_decel`, or a category-0
//! `motion.stopping` table).

use crate::check::{um_down, um_up};
use crate::plant::brake::PowerOffBrake;
use crate::scene::{Controller, Decoupler, Scene, Sensor};
use crate::sim::{Run, Sample, Summary};
use flinch_firmware::{Boot, BudgetConfig, Config, DigitalSwitch, DualSwitch, Filter, ResetCause, ResetPolicy, State, SwitchKind};
use flinch_hal_sim::{latency, PinFault, SimPin, SimRig};
use serde::Serialize;
use std::cell::RefCell;
use std::rc::Rc;

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
    /// Drive power removed (the escalation output, plus its latency), s; null without category 0.
    #[serde(rename = "power_removed_s")]
    pub power_removed: Option<f64>,
    /// The robot's brakes acting after the power removal, s (plant/brake.rs).
    #[serde(rename = "brakes_engaged_s")]
    pub brakes_engaged: Option<f64>,
    /// Where the category-0 brake's figures came from.
    pub brake_source: String,
    /// The firmware's edge-to-stop latency the plant was given, s (hal_sim::latency: the measured
    /// QEMU worst case at the board's clock).
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
#[derive(Debug, Clone)]
pub struct HilOptions {
    /// Faults to inject.
    pub faults: Vec<Injection>,
    /// Two-channel (antivalent) travel switch instead of one channel.
    pub two_channels: bool,
    /// The firmware's glitch filter (`Config::filter`; default none: the edge stops directly).
    pub filter: Filter,
    /// How a trip is cleared (`Config::reset`; default a reset input, never pressed in the run).
    pub reset: ResetPolicy,
}

impl Default for HilOptions {
    fn default() -> Self {
        Self { faults: Vec::new(), two_channels: false, filter: Filter::None, reset: ResetPolicy::Input }
    }
}

/// Parse `--filter`: `none`, `consecutive:N` (N tick samples, 1..=255) or `min-duration:S`
/// (seconds, whole microseconds up to 1 s).
pub fn parse_filter(spec: &str) -> Result<Filter, String> {
    let allowed = "none, consecutive:N (1 to 255 tick samples) or min-duration:SECONDS (1e-6 to 1 s)";
    match spec.split_once(':') {
        None if spec == "none" => Ok(Filter::None),
        Some(("consecutive", n)) => match n.parse::<u8>() {
            Ok(n) if n >= 1 => Ok(Filter::Consecutive(n)),
            _ => Err(format!("--filter consecutive:N: N from 1 to 255, got {n:?}")),
        },
        Some(("min-duration", s)) => match s.parse::<f64>() {
            Ok(x) if (1e-6..=1.0).contains(&x) && whole_us(x) => Ok(Filter::MinDuration(um(x))),
            _ => Err(format!("--filter min-duration:SECONDS: 1e-6 to 1 s in whole microseconds, got {s:?}")),
        },
        _ => Err(format!("--filter: one of {allowed}, got {spec:?}")),
    }
}

/// Parse `--reset-policy`: `input` (a reset press; none comes during a run, so a trip stays
/// latched) or `auto:S` (cleared once the tool has been back on its front stop for S seconds).
pub fn parse_reset_policy(spec: &str) -> Result<ResetPolicy, String> {
    match spec.split_once(':') {
        None if spec == "input" => Ok(ResetPolicy::Input),
        Some(("auto", s)) => match s.parse::<f64>() {
            Ok(x) if (1e-6..=10.0).contains(&x) && whole_us(x) => Ok(ResetPolicy::Auto { hold_us: um(x) }),
            _ => Err(format!("--reset-policy auto:SECONDS: 1e-6 to 10 s in whole microseconds, got {s:?}")),
        },
        _ => Err(format!("--reset-policy: input, or auto:SECONDS (back on the front stop that long), got {spec:?}")),
    }
}

pub use crate::scene::whole_us;

fn describe_filter(f: Filter) -> String {
    match f {
        Filter::None => "none".into(),
        Filter::Consecutive(n) => format!("consecutive:{n}"),
        Filter::MinDuration(us) => format!("min-duration:{}", us as f64 / 1e6),
    }
}

fn describe_reset(r: ResetPolicy) -> String {
    match r {
        ResetPolicy::Input => "input".into(),
        ResetPolicy::Auto { hold_us } => format!("auto:{}", hold_us as f64 / 1e6),
    }
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

/// Runs `scene` with the firmware in the loop and the controller `ctl`. `record` keeps the time
/// history.
pub fn run(scene: &Scene, ctl: &Controller, record: bool) -> Result<(HilReport, Vec<Sample>), String> {
    run_with(scene, ctl, record, &HilOptions::default())
}

/// [`run`] with faults injected, the sensor's channel count, filter and reset policy chosen. A
/// fault list that the configuration cannot take (channel B of a one-channel switch) is refused.
pub fn run_with(scene: &Scene, ctl: &Controller, record: bool, opts: &HilOptions) -> Result<(HilReport, Vec<Sample>), String> {
    run_recording(scene, ctl, opts, if record { Record::History } else { Record::Nothing })
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

/// Why `flinch hil` cannot run this scene's module, if it cannot: the firmware reads a travel
/// switch and budgets the module's stroke.
pub fn refusal(scene: &Scene) -> Option<String> {
    match (&scene.sensor, &scene.decoupler) {
        (Some(Sensor::Force { .. }), _) | (_, Decoupler::Rigid) => {
            Some("sensor.kind: flinch hil needs a travel switch (sensor.kind = \"travel\") on a decoupler; a rigid tool's force sensor is not read by this firmware".into())
        }
        (None, _) => Some("[sensor]: flinch hil needs a travel switch; the scene has no [sensor]".into()),
        (_, Decoupler::Linear(_)) => Some(
            "decoupler.kind: flinch hil cannot run a \"linear\" spring-damper: it has no end-stops (eq 17, 23), so no stroke, and the firmware's stroke budget (stopping distance against the stroke left at detection, BudgetConfig::stroke_um) has nothing to budget; its travel is not bounded, so no stroke budget would be honest. Use a \"bistable\" or \"hydraulic\" module, or `flinch run` for the linear one".into(),
        ),
        _ => None,
    }
}

/// [`run_with`], with the history going where `record` says.
pub fn run_recording(scene: &Scene, ctl: &Controller, opts: &HilOptions, record: Record<'_>) -> Result<(HilReport, Vec<Sample>), String> {
    if let Some(why) = refusal(scene) {
        return Err(why);
    }
    let Some(Sensor::Travel { threshold }) = scene.sensor else { return Err("[sensor]: flinch hil needs a travel switch".into()) };
    if !whole_us(ctl.firmware_tick) {
        return Err(format!("controller.firmware_tick: a whole number of microseconds (the firmware's clock counts them), got {} s", ctl.firmware_tick));
    }
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
    cfg.filter = opts.filter;
    cfg.reset = opts.reset;
    let refused = |e: flinch_firmware::ConfigError| format!("the firmware refused its configuration: {}", e.message());
    let mut record = record;
    if opts.two_channels {
        // Antivalent pair: channel A as the single switch, channel B its complement (NO).
        let kind_b = SwitchKind::Magnetic { trip_high: !kind.trip_level_high() };
        let make = || SimRig::dual_after(cfg, Boot::UNKNOWN, kind, kind_b, um(threshold) as i32, DISCREPANCY_US).map_err(refused);
        let apply = move |rig: &mut SimRig<DualSwitch<SimPin, SimPin, SimPin>>, f: FaultKind| {
            let Some((a, b)) = rig.channel_pins() else { return };
            match (f, channel_fault(f, if f == FaultKind::StuckRestB { kind_b } else { kind })) {
                (FaultKind::Reset, _) => rig.mcu_reset(ResetCause::Watchdog),
                (FaultKind::StuckRestB, Some(pf)) => rig.inject_pin_fault(&b, pf),
                (_, Some(pf)) => rig.inject_pin_fault(&a, pf),
                (_, None) => apply_common(rig, f),
            }
        };
        run_passes(scene, ctl, &mut record, threshold, opts, make, apply)
    } else {
        if opts.faults.iter().any(|f| f.kind == FaultKind::StuckRestB) {
            return Err("--fault stuck-rest-b: needs a two-channel switch (--channels 2); this run has one channel".into());
        }
        let make = || SimRig::digital(cfg, kind, um(threshold) as i32).map_err(refused);
        let apply = move |rig: &mut SimRig<DigitalSwitch<SimPin, SimPin>>, f: FaultKind| match (f, channel_fault(f, kind)) {
            (FaultKind::Reset, _) => rig.mcu_reset(ResetCause::Watchdog),
            (_, Some(pf)) => rig.inject_switch_fault(pf),
            (_, None) => apply_common(rig, f),
        };
        run_passes(scene, ctl, &mut record, threshold, opts, make, apply)
    }
}

/// How many passes a run may take to put a category-0 power removal at its instant (see
/// [`run_passes`]).
const MAX_PASSES: usize = 3;

/// Two firmware decisions at most this far apart are the same instant, s: the firmware's clock
/// counts whole microseconds.
const SAME_INSTANT_S: f64 = 1e-6;

/// What one pass of [`run_loop`] ended with.
enum Pass {
    /// The run, complete.
    Done(Box<(HilReport, Vec<Sample>)>),
    /// The firmware removed drive power at `off` s, inside a plant step that had already gone past
    /// it with the arm not cruising (so the past could not be rewritten exactly): run again with
    /// the removal scheduled at `off` from the start. Rows up to `streamed_until` s have been
    /// handed to the stream already.
    Again { off: f64, streamed_until: f64 },
}

/// Runs [`run_loop`] with a fresh firmware from `make`, again with the power removal scheduled
/// where a pass found it late.
///
/// Why: the plant steps before the firmware catches up with it, so a category-0 escalation (IEC
/// 60204-1 9.2.2, removal of drive power) decided at an instant inside the plant's step is found
/// once the step has ended. Applying it at the step's end made the power-removal time, the coasting
/// and the stop depend on the solver's step grid (up to a step late: 639 us on Tables 5-7 with a
/// reset during braking). The motion law cannot be rewritten after the fact except where the arm
/// cruised at constant speed (`Run::remove_power`), so otherwise the pass stops there and the run
/// starts again with the removal scheduled at its instant: a motion-law breakpoint, which the
/// solver steps onto. Causality makes that exact: up to the removal the scheduled law is the same
/// law, so the firmware decides the same thing at the same instant (checked: to the firmware's
/// 1 us clock; a pass that disagrees is run again from its own instant, at most [`MAX_PASSES`]).
fn run_passes<S: flinch_firmware::Sensor>(
    scene: &Scene,
    ctl: &Controller,
    record: &mut Record<'_>,
    threshold: f64,
    opts: &HilOptions,
    make: impl Fn() -> Result<SimRig<S>, String>,
    mut apply: impl FnMut(&mut SimRig<S>, FaultKind),
) -> Result<(HilReport, Vec<Sample>), String> {
    let mut schedule: Option<f64> = None;
    let mut streamed_until = f64::NEG_INFINITY;
    let mut found = Vec::new();
    for _ in 0..MAX_PASSES {
        let mut rig = make()?;
        match run_loop(scene, ctl, record, threshold, &mut rig, opts, &mut apply, schedule, streamed_until)? {
            Pass::Done(r) => return Ok(*r),
            Pass::Again { off, streamed_until: s } => {
                found.push(off);
                schedule = Some(off);
                streamed_until = streamed_until.max(s);
            }
        }
    }
    Err(format!(
        "category 0: the firmware's drive power removal did not settle on one instant in {MAX_PASSES} passes (found at {found:?} s, each pass scheduled at the one before): the plant and the firmware disagree at the solver's tolerance; tighten [solver] rtol/atol"
    ))
}

/// What the firmware must be given, in time order, found on the plant's dense output.
#[derive(Debug, Clone, Copy)]
enum Input {
    /// The switch changes level at `t` (travel `um` just past it).
    Edge { t: f64, um: i32 },
    /// A firmware tick is due at `t` (travel `um` then).
    Tick { t: f64, um: i32 },
}

/// Reads the switch between the plant's steps: the travel at each firmware tick, and the instant
/// of every level change, located on the step's dense output.
struct SwitchProbe {
    tick_us: i64,
    /// The next tick, as a count of ticks from sim time 0.
    next_tick: i64,
    threshold_um: i32,
    /// Tripped at the last instant looked at, and that instant.
    level: bool,
    last_t: f64,
    inputs: Vec<Input>,
}

impl SwitchProbe {
    /// Travel (m) and tripped (the plant's own switch signal: > 0 as its event) at `t` of a step.
    fn read(plant: &crate::plant::Plant, t: f64, dense: &dyn Fn(f64) -> crate::plant::State) -> (f64, bool) {
        let k = plant.kinematics(t, &dense(t));
        let tripped = plant.detector.is_some_and(|d| d.signal(k.s, 0.0) > 0.0);
        (plant.travel(&k), tripped)
    }

    /// Travel in whole micrometres on the side of the threshold the plant says it is.
    fn um_for(&self, travel: f64, tripped: bool) -> i32 {
        let floor = (travel * 1e6).floor().clamp(i32::MIN as f64, i32::MAX as f64) as i32;
        if tripped { floor.max(self.threshold_um) } else { floor.min(self.threshold_um.saturating_sub(1)) }
    }

    fn look(&mut self, plant: &crate::plant::Plant, t: f64, dense: &dyn Fn(f64) -> crate::plant::State) -> (f64, bool) {
        let (travel, tripped) = Self::read(plant, t, dense);
        if tripped != self.level {
            // Bisect [last_t, t] for the first instant on the new side.
            let (mut a, mut b) = (self.last_t, t);
            let mut at_b = (travel, tripped);
            for _ in 0..60 {
                if b - a <= 1e-12 {
                    break;
                }
                let m = 0.5 * (a + b);
                let r = Self::read(plant, m, dense);
                if r.1 == tripped {
                    b = m;
                    at_b = r;
                } else {
                    a = m;
                }
            }
            let um = self.um_for(at_b.0, tripped);
            self.inputs.push(Input::Edge { t: b, um });
            self.level = tripped;
        }
        self.last_t = t;
        (travel, tripped)
    }

    fn on_step(&mut self, plant: &crate::plant::Plant, t0: f64, t1: f64, dense: &dyn Fn(f64) -> crate::plant::State) {
        if t1 < t0 {
            return;
        }
        loop {
            let tk = (self.next_tick * self.tick_us) as f64 * 1e-6;
            if tk > t1 {
                break;
            }
            let (travel, tripped) = self.look(plant, tk.max(t0), dense);
            let um = self.um_for(travel, tripped);
            self.inputs.push(Input::Tick { t: tk, um });
            self.next_tick += 1;
        }
        self.look(plant, t1, dense);
    }
}

/// Which firmware path wrote an output: its latency differs.
#[derive(Clone, Copy, PartialEq)]
enum Path {
    Edge,
    Tick,
}

fn latency_of(p: Path) -> f64 {
    match p {
        Path::Edge => latency::edge_to_stop_s(),
        Path::Tick => latency::tick_to_output_s(),
    }
}

#[allow(clippy::too_many_arguments)]
fn run_loop<S: flinch_firmware::Sensor>(
    scene: &Scene,
    ctl: &Controller,
    record: &mut Record<'_>,
    threshold: f64,
    rig: &mut SimRig<S>,
    opts: &HilOptions,
    mut apply: impl FnMut(&mut SimRig<S>, FaultKind),
    schedule: Option<f64>,
    streamed_until: f64,
) -> Result<Pass, String> {
    rig.boot(1_000_000).map_err(|s| format!("the firmware did not arm after 1 s of self-test (stuck in {s:?})"))?;
    let mut pending: std::collections::VecDeque<Injection> = opts.faults.iter().copied().collect();
    let mut outcomes: Vec<FaultOutcome> = Vec::new();
    let (brake, brake_source) = cat0_brake(scene, ctl);

    let keep = !matches!(record, Record::Nothing);
    let mut plant = Run::new(scene, true, keep);
    if let Some(off) = schedule {
        // Found by an earlier pass (run_passes): a breakpoint of the motion law from the start.
        plant.remove_power(off, brake);
    }
    let mut last_streamed = streamed_until;
    // Recorded samples wait here until the firmware has caught up with their instant.
    let rows: Rc<RefCell<Vec<Sample>>> = Rc::new(RefCell::new(Vec::new()));
    if let Record::Stream(_) = record {
        let buf = Rc::clone(&rows);
        plant.sim.sink = Some(Box::new(move |s: &Sample| buf.borrow_mut().push(*s)));
    }
    let tick_us = i64::from(um(ctl.firmware_tick).max(1));
    let probe = Rc::new(RefCell::new(SwitchProbe { tick_us, next_tick: 0, threshold_um: um(threshold) as i32, level: false, last_t: 0.0, inputs: Vec::new() }));
    {
        let (k, _) = plant.now();
        let tripped = plant.sim.plant.detector.is_some_and(|d| d.signal(k.s, 0.0) > 0.0);
        let mut p = probe.borrow_mut();
        p.level = tripped;
        let um0 = p.um_for(plant.travel(), tripped);
        drop(p);
        rig.set_travel_um(um0);
    }
    let pr = Rc::clone(&probe);
    plant.sim.probe = Some(Box::new(move |pl, t0, t1, dense| pr.borrow_mut().on_step(pl, t0, t1, dense)));

    let scan = ctl.scan_cycle;
    let mut next_sample = ctl.phase * scan;
    let mut stop_seen: Option<f64> = None;
    let mut category0 = false;
    let mut power_removed: Option<f64> = None;
    let mut warnings: Vec<String> = Vec::new();
    let mut stop_output = vec![(0.0, rig.stop_requested())];
    let mut esc_level = rig.category0_requested();
    let mut t = 0.0_f64;
    let max_step = scene.solver.max_step;
    // The probe's inputs of one solver step, swapped out each step: the two buffers keep their
    // capacity, where taking the vector left the probe a new one to grow again every step (its
    // reallocations were 10 % of a Tables 5-7 hil run's instructions, callgrind).
    let mut inputs: Vec<Input> = Vec::new();
    // A power removal this pass could not put at its instant (see run_passes).
    let mut late: Option<f64> = None;
    while t < scene.duration_s {
        // The step the solver would take anyway; until the controller has seen the stop, not past
        // its next sample (braking starts there if it sees the stop).
        let h = plant.next_step();
        let mut target = (t + if h > 0.0 { h } else { max_step }).min(scene.duration_s);
        if stop_seen.is_none() {
            target = target.min(next_sample.max(t));
        }
        if target <= t {
            target = (t + max_step).min(scene.duration_s);
        }
        plant.advance_to(target).map_err(|e| e.to_string())?;
        let now = plant.time();
        // The firmware catches up with the plant.
        inputs.clear();
        std::mem::swap(&mut probe.borrow_mut().inputs, &mut inputs);
        let mut note = |rig: &mut SimRig<S>, at: f64, path: Path, plant: &mut Run, outcomes: &mut Vec<FaultOutcome>| {
            let level = rig.stop_requested();
            let last = stop_output.last().map_or(!level, |l| l.1);
            if level != last {
                let seen_at = (at + latency_of(path)).max(stop_output.last().map_or(0.0, |l| l.0));
                stop_output.push((seen_at, level));
            }
            if level {
                for o in outcomes.iter_mut().filter(|o| o.stopped_s.is_none() && o.at_s <= at + 1e-12) {
                    o.stopped_s = Some(at);
                }
            }
            let esc = rig.category0_requested();
            if esc && !esc_level {
                category0 = true;
                if power_removed.is_none() {
                    // The escalation output drops the drives' power directly (a safety relay, STO),
                    // not through the controller's scan cycle.
                    let off = at + latency::tick_to_output_s();
                    match schedule {
                        // Scheduled by the pass before: the firmware must decide it again here.
                        Some(s) => {
                            if (off - s).abs() > SAME_INSTANT_S {
                                late = Some(off);
                            }
                            power_removed = Some(s);
                        }
                        None => {
                            // Exact if the plant has not passed `off` or the arm cruised since.
                            let applied = plant.remove_power(off, brake);
                            if applied > off + 1e-12 {
                                late = Some(off);
                            }
                            power_removed = Some(applied);
                        }
                    }
                }
            }
            esc_level = esc;
        };
        for &input in &inputs {
            let at = match input {
                Input::Edge { t, .. } | Input::Tick { t, .. } => t,
            };
            while let Some(f) = pending.front().copied().filter(|f| f.at_s <= at) {
                pending.pop_front();
                inject(rig, f, &mut apply, &mut outcomes, &mut |rig, at, path, outcomes| note(rig, at, path, &mut plant, outcomes));
            }
            match input {
                Input::Edge { t, um } => {
                    rig.advance_to(t);
                    rig.set_travel_um(um);
                    note(rig, t, Path::Edge, &mut plant, &mut outcomes);
                }
                Input::Tick { t, um } => {
                    rig.set_travel_um(um);
                    rig.advance_to(t);
                    note(rig, t, Path::Tick, &mut plant, &mut outcomes);
                }
            }
        }
        while let Some(f) = pending.front().copied().filter(|f| f.at_s <= now) {
            pending.pop_front();
            inject(rig, f, &mut apply, &mut outcomes, &mut |rig, at, path, outcomes| note(rig, at, path, &mut plant, outcomes));
        }
        if let Some(off) = late {
            // Nothing after the step's start has reached the stream: this pass ends here.
            return Ok(Pass::Again { off, streamed_until: last_streamed });
        }
        // The controller's samples up to now.
        while next_sample <= now {
            if stop_seen.is_none() && level_at(&stop_output, next_sample) {
                stop_seen = Some(next_sample);
                plant.command_brake(next_sample);
            }
            next_sample += scan;
        }
        if let Record::Stream(sink) = record {
            let signals = RowSignals { stop_output: &stop_output, stop_seen };
            for s in rows.borrow_mut().drain(..) {
                // An earlier pass streamed these already (run_passes).
                if s.t > last_streamed {
                    sink(&s, &signals);
                    last_streamed = s.t;
                }
            }
        }
        t = now;
    }
    plant.sim.probe = None;
    plant.sim.sink = None;
    if let (Some(off), None) = (schedule, power_removed) {
        return Err(format!(
            "category 0: the firmware removed drive power at {off} s in a first pass, but not when the removal was scheduled there from the start (the same plant up to that instant): the plant and the firmware disagree at the solver's tolerance; tighten [solver] rtol/atol"
        ));
    }
    let mut summary = plant.summary();
    if let Some(off) = power_removed {
        warnings.push(format!(
            "category 0: the firmware's escalation removed drive power at {off} s; the robot coasted and its brakes acted from {} s ({brake_source}); t_brake is the controller's controlled stop, which the power removal overrides, and t_stop is the brakes' standstill",
            off + brake.delay
        ));
    }
    summary.warnings.extend(warnings);
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
        power_removed,
        brakes_engaged: power_removed.map(|p| p + brake.delay),
        brake_source,
        edge_to_stop_latency: latency::edge_to_stop_s(),
        tick_to_output_latency: latency::tick_to_output_s(),
        filter: describe_filter(opts.filter),
        reset_policy: describe_reset(opts.reset),
        event_log,
        faults: outcomes,
        stop_output,
    };
    let history = if matches!(record, Record::History) { std::mem::take(&mut plant.sim.history) } else { Vec::new() };
    Ok(Pass::Done(Box::new((HilReport { summary, firmware }, history))))
}

/// The stop output's level at `t` (the last change at or before it).
fn level_at(output: &[(f64, bool)], t: f64) -> bool {
    output.iter().take_while(|&&(at, _)| at <= t).last().is_some_and(|&(_, l)| l)
}

type Note<'n, S> = dyn FnMut(&mut SimRig<S>, f64, Path, &mut Vec<FaultOutcome>) + 'n;

fn inject<S: flinch_firmware::Sensor>(rig: &mut SimRig<S>, f: Injection, apply: &mut impl FnMut(&mut SimRig<S>, FaultKind), outcomes: &mut Vec<FaultOutcome>, note: &mut Note<'_, S>) {
    rig.advance_to(f.at_s);
    let before = rig.stop_requested();
    let name = FAULTS.iter().find(|(_, k, _)| *k == f.kind).map_or("?", |(n, _, _)| *n);
    outcomes.push(FaultOutcome { fault: name.into(), at_s: f.at_s, stopped_s: None, ended_in_go: false, reason: String::new() });
    apply(rig, f.kind);
    // A level change on a switch input reaches the edge interrupt at once.
    let path = if rig.stop_requested() != before { Path::Edge } else { Path::Tick };
    note(rig, f.at_s, path, outcomes);
}

/// The brakes of a category-0 stop, and where their figures come from: the robot's own
/// category-0 stopping table at the scene's speed when it has one, else `[controller]`.
fn cat0_brake(scene: &Scene, ctl: &Controller) -> (PowerOffBrake, String) {
    if let Some(table) = scene.motion.stopping.filter(|t| t.category == 0) {
        if let Some(e) = table.equivalent(scene.motion.speed) {
            return (PowerOffBrake { delay: e.dead_time, decel: e.decel }, format!("motion.stopping (category 0) at {} m/s: delay {} s, {} m/s^2", scene.motion.speed, e.dead_time, e.decel));
        }
    }
    let b = PowerOffBrake::of(ctl);
    let default = b.delay == crate::plant::brake::DEFAULT_DELAY_S && b.decel == crate::plant::brake::DEFAULT_DECEL_MPS2;
    (b, format!("[controller] brake_delay {} s, brake_decel {} m/s^2{}", b.delay, b.decel, if default { " (defaults, plant/brake.rs)" } else { "" }))
}
