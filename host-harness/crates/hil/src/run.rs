//! The entry points of a firmware-in-the-loop run ([`run`], [`run_with`], [`run_recording`]), what
//! it refuses, the firmware configured from the scene, and the passes: a run starts again when the
//! firmware removes drive power while the arm is not cruising.

use crate::units::{um_down, um_up};
use flinch_model::scene::{Controller, Decoupler, Scene, Sensor};
use flinch_sim::Sample;
use flinch_firmware::{Boot, BudgetConfig, Config, DigitalSwitch, DualSwitch, ResetCause, SwitchKind};
use flinch_hal_sim::output_faults::extra_dead_time_us;
use flinch_hal_sim::{OutputFault, PinFault, SimPin, SimRig};
use crate::{report::*, options::*, stepping::*};

/// Total stroke the budget may use, m (front stop to back stop).
pub(crate) fn stroke(scene: &Scene) -> f64 {
    match &scene.decoupler {
        Decoupler::Bistable(b) => b.front_stroke + b.back_stroke,
        Decoupler::Hydraulic(h) => h.stroke,
        _ => 0.0,
    }
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

pub(crate) fn apply_common<S: flinch_firmware::Sensor>(rig: &mut SimRig<S>, kind: FaultKind) {
    match kind {
        FaultKind::WeldedOutput => rig.k1.set_fault(PinFault::StuckLow),
        FaultKind::EdmWireCut => rig.k1.set_fault(PinFault::StuckHigh),
        FaultKind::ClockStall => rig.clock.set_stalled(true),
        FaultKind::Output(f) => rig.inject_output_fault(f),
        _ => {}
    }
}

pub(crate) fn channel_fault(kind: FaultKind, sw: SwitchKind) -> Option<PinFault> {
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

/// The firmware's configuration for `scene` under `ctl`: its tick, and its stroke budget (the
/// speed, the dead time the budget assumes, the deceleration, the stroke).
pub(crate) fn firmware_config(scene: &Scene, ctl: &Controller) -> Config {
    let budget = BudgetConfig {
        robot_speed_um_per_s: um_up(scene.motion.speed),
        // The board's latency, a whole scan, the robot's reaction, and with the robot's stopping
        // table its equivalent dead time at V_c after the signal (timing.rs).
        dead_time_us: um_up(crate::timing::budget_dead_time(scene, ctl)),
        decel_um_per_s2: um_down(scene.motion.decel).max(1),
        stroke_um: um_down(stroke(scene)) as i32,
    };
    Config::new(um(ctl.firmware_tick).max(1), budget)
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
    let mut cfg = firmware_config(scene, ctl);
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
        run_passes(scene, ctl, &mut record, threshold, opts, make, apply).map(|r| with_bounds(r, &cfg))
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
        run_passes(scene, ctl, &mut record, threshold, opts, make, apply).map(|r| with_bounds(r, &cfg))
    }
}

/// Each output fault's bound on the time it adds after a demand (`hal_sim::output_faults`): the
/// EDM settle time and two ticks for both relays welded, plus the board's tick-to-output for the
/// escalation that is then the only way to a safe state.
pub fn output_fault_bound_s(cfg: &Config, f: OutputFault) -> f64 {
    let extra = f64::from(extra_dead_time_us(cfg, f)) * 1e-6;
    if extra > 0.0 { extra + flinch_hal_sim::latency::tick_to_output_s() } else { 0.0 }
}

fn with_bounds(mut r: (HilReport, Vec<Sample>), cfg: &Config) -> (HilReport, Vec<Sample>) {
    for o in &mut r.0.firmware.faults {
        let kind = FAULTS.iter().find(|(n, _, _)| *n == o.fault).map(|(_, k, _)| *k);
        o.extra_dead_time_bound_s = kind.and_then(FaultKind::output).map(|f| output_fault_bound_s(cfg, f));
    }
    r
}

/// How many passes a run may take to put a category-0 power removal at its instant (see
/// [`run_passes`]).
pub(crate) const MAX_PASSES: usize = 3;

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
pub(crate) fn run_passes<S: flinch_firmware::Sensor>(
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
