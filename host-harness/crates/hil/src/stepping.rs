//! One pass: the plant's steps and the firmware catching up after each (ticks on the dense output,
//! switch edges located by bisection), the controller's samples, the stop and escalation outputs
//! and their latencies, the category-0 brake, faults injected at their instants.

use flinch_plant::brake::PowerOffBrake;
use flinch_model::scene::{Controller, Scene};
use flinch_sim::{Run, Sample};
use flinch_firmware::State;
use flinch_hal_sim::{latency, SimRig};
use std::cell::RefCell;
use std::rc::Rc;
use crate::{report::*, options::*};

/// Two firmware decisions at most this far apart are the same instant, s: the firmware's clock
/// counts whole microseconds.
pub(crate) const SAME_INSTANT_S: f64 = 1e-6;

/// What one pass of [`run_loop`] ended with.
pub(crate) enum Pass {
    /// The run, complete.
    Done(Box<(HilReport, Vec<Sample>)>),
    /// The firmware removed drive power at `off` s, inside a plant step that had already gone past
    /// it with the arm not cruising (so the past could not be rewritten exactly): run again with
    /// the removal scheduled at `off` from the start. Rows up to `streamed_until` s have been
    /// handed to the stream already.
    Again { off: f64, streamed_until: f64 },
}

/// What the firmware must be given, in time order, found on the plant's dense output.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Input {
    /// The switch changes level at `t` (travel `um` just past it).
    Edge { t: f64, um: i32 },
    /// A firmware tick is due at `t` (travel `um` then).
    Tick { t: f64, um: i32 },
}

/// Reads the switch between the plant's steps: the travel at each firmware tick, and the instant
/// of every level change, located on the step's dense output.
pub(crate) struct SwitchProbe {
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
    fn read(plant: &flinch_plant::Plant, t: f64, dense: &dyn Fn(f64) -> flinch_plant::State) -> (f64, bool) {
        let k = plant.kinematics(t, &dense(t));
        let tripped = plant.detector.is_some_and(|d| d.signal(k.s, 0.0) > 0.0);
        (plant.travel(&k), tripped)
    }

    /// Travel in whole micrometres on the side of the threshold the plant says it is.
    fn um_for(&self, travel: f64, tripped: bool) -> i32 {
        let floor = (travel * 1e6).floor().clamp(i32::MIN as f64, i32::MAX as f64) as i32;
        if tripped { floor.max(self.threshold_um) } else { floor.min(self.threshold_um.saturating_sub(1)) }
    }

    fn look(&mut self, plant: &flinch_plant::Plant, t: f64, dense: &dyn Fn(f64) -> flinch_plant::State) -> (f64, bool) {
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

    fn on_step(&mut self, plant: &flinch_plant::Plant, t0: f64, t1: f64, dense: &dyn Fn(f64) -> flinch_plant::State) {
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
pub(crate) enum Path {
    Edge,
    Tick,
}

pub(crate) fn latency_of(p: Path) -> f64 {
    match p {
        Path::Edge => latency::edge_to_stop_s(),
        Path::Tick => latency::tick_to_output_s(),
    }
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn run_loop<S: flinch_firmware::Sensor>(
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
    let (reaction, _) = crate::timing::reaction(scene, ctl);
    // With the worst phase the sample before the stop output just missed it: the next comes a whole
    // scan after the output, found once the firmware has written it (until then none is due).
    let mut next_sample = if opts.worst_phase { f64::INFINITY } else { ctl.phase * scan };
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
            if opts.worst_phase {
                // Not past the sample a whole scan after an output written in this step.
                target = target.min(t + scan);
            }
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
            // Safe: the stop circuit open, or drive power removed (category 0: both relays welded).
            let esc = rig.category0_requested();
            if level || esc {
                for o in outcomes.iter_mut().filter(|o| o.stopped_s.is_none() && o.at_s <= at + 1e-12) {
                    o.stopped_s = Some(at);
                }
            }
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
                    // The firmware's clock reads the first whole microsecond at or after the edge
                    // (never before it: a negative latency otherwise); and not before the plant's
                    // own located crossing, which the summary's t_detect reports (the two locators
                    // agree to 1e-12 s).
                    let located = plant.switch_time().filter(|sw| (sw - t).abs() < 1e-9).map_or(t, |sw| sw.max(t));
                    rig.advance_to_event(located);
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
        if opts.worst_phase && next_sample.is_infinite() {
            if let Some(&(at, _)) = stop_output.iter().find(|(_, l)| *l) {
                next_sample = at + scan;
            }
        }
        while next_sample <= now {
            if stop_seen.is_none() && level_at(&stop_output, next_sample) {
                stop_seen = Some(next_sample);
                // The robot reacts `reaction` after its sample saw the stop (timing.rs).
                plant.command_brake(next_sample + reaction);
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
    let switch_time = summary.t_detect;
    let dead_time = crate::timing::DeadTimeModel::new(scene, ctl, opts.worst_phase, switch_time, &stop_output, stop_seen, summary.t_brake);
    warnings.extend(dead_time.warning());
    summary.warnings.extend(warnings);
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
    // "Go" only with the stop circuit closed and drive power on.
    let go = !rig.stop_requested() && !rig.category0_requested();
    let mut reason = match rig.fw.state() {
        State::Fault(c) => format!("stopped: fault latched ({})", c.name()),
        State::Tripped => "stopped: trip latched".to_string(),
        State::SelfTest(_) => "stopped: in the self-test".to_string(),
        State::Armed => "GO: the firmware is armed with the fault present (not detected)".to_string(),
    };
    if !rig.stop_requested() && rig.category0_requested() {
        reason.push_str("; the stop circuit is still closed (welded), drive power removed (category 0)");
    } else if go && !matches!(rig.fw.state(), State::Armed) {
        reason = format!("GO: the stop circuit is closed and drive power on although the firmware is {reason}");
    }
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
        dead_time_model: dead_time,
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
        demand_to_safe_s: {
            let first_stop = stop_output.iter().find(|(_, l)| *l).map(|(at, _)| *at);
            let first_safe = [first_stop, power_removed].into_iter().flatten().min_by(f64::total_cmp);
            switch_time.zip(first_safe).map(|(s, f)| (f - s).max(0.0))
        },
        faults: outcomes,
        stop_output,
    };
    let history = if matches!(record, Record::History) { std::mem::take(&mut plant.sim.history) } else { Vec::new() };
    Ok(Pass::Done(Box::new((HilReport { summary, firmware }, history))))
}

/// The stop output's level at `t` (the last change at or before it).
pub(crate) fn level_at(output: &[(f64, bool)], t: f64) -> bool {
    output.iter().take_while(|&&(at, _)| at <= t).last().is_some_and(|&(_, l)| l)
}

pub(crate) type Note<'n, S> = dyn FnMut(&mut SimRig<S>, f64, Path, &mut Vec<FaultOutcome>) + 'n;

pub(crate) fn inject<S: flinch_firmware::Sensor>(rig: &mut SimRig<S>, f: Injection, apply: &mut impl FnMut(&mut SimRig<S>, FaultKind), outcomes: &mut Vec<FaultOutcome>, note: &mut Note<'_, S>) {
    // An injection is an event: the firmware's clock is not set before it.
    rig.advance_to_event(f.at_s);
    let before = rig.stop_requested();
    outcomes.push(FaultOutcome { fault: fault_name(f.kind).into(), at_s: f.at_s, stopped_s: None, ended_in_go: false, reason: String::new(), extra_dead_time_bound_s: None });
    apply(rig, f.kind);
    // A level change on a switch input reaches the edge interrupt at once.
    let path = if rig.stop_requested() != before { Path::Edge } else { Path::Tick };
    note(rig, f.at_s, path, outcomes);
}

/// The brakes of a category-0 stop, and where their figures come from: the robot's own
/// category-0 stopping table at the scene's speed when it has one, else `[controller]`.
pub(crate) fn cat0_brake(scene: &Scene, ctl: &Controller) -> (PowerOffBrake, String) {
    if let Some(table) = scene.motion.stopping.filter(|t| t.category == 0) {
        if let Some(e) = table.equivalent(scene.motion.speed) {
            return (PowerOffBrake { delay: e.dead_time, decel: e.decel }, format!("motion.stopping (category 0) at {} m/s: delay {} s, {} m/s^2", scene.motion.speed, e.dead_time, e.decel));
        }
    }
    let b = PowerOffBrake::of(ctl);
    let default = b.delay == flinch_plant::brake::DEFAULT_DELAY_S && b.decel == flinch_plant::brake::DEFAULT_DECEL_MPS2;
    (b, format!("[controller] brake_delay {} s, brake_decel {} m/s^2{}", b.delay, b.decel, if default { " (defaults, plant/brake.rs)" } else { "" }))
}
