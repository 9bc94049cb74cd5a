//! The firmware library against the stateful fakes: one test per fault of issue 3, the reset
//! policies, the glitch filter's latency measured end to end, the event log and the stroke budget.

use flinch_firmware::event_log::{FLAG_EDGE, FLAG_ESCALATED, FLAG_FILTERED};
use flinch_firmware::{
    AnalogConfig, BudgetConfig, Cause, ChatterGuard, Config, Filter, Micros, Mm, ResetCause, ResetPolicy, State,
    SwitchKind,
};
use flinch_hal_sim::{AdcFault, PinFault, SimRig, SIM_LOG};

const T: u32 = 1_000; // 1 kHz tick

/// Tables 5-7: V_c = 0.05 m/s, DT = 16 ms; d = 1 m/s^2 and C = 10 mm chosen for the tests:
/// s_stop = 0.8 + 1.25 = 2.05 mm, which fits in the 5 mm left after a 5 mm d_sw.
fn budget() -> BudgetConfig {
    BudgetConfig { robot_speed_um_per_s: 50_000, dead_time_us: 16_000, decel_um_per_s2: 1_000_000, stroke_um: 10_000 }
}

fn cfg() -> Config {
    Config::new(T, budget())
}

fn booted(cfg: Config) -> SimRig<flinch_firmware::DigitalSwitch<flinch_hal_sim::SimPin, flinch_hal_sim::SimPin>> {
    let mut rig = SimRig::digital(cfg, SwitchKind::Inductive, 5_000).unwrap();
    rig.boot(50_000).unwrap();
    rig
}

#[test]
fn outputs_are_de_energised_until_the_self_test_passes() {
    let mut rig = SimRig::digital(cfg(), SwitchKind::Inductive, 5_000).unwrap();
    assert!(rig.stop_requested() && rig.category0_requested(), "dropped in Firmware::new");
    let boot_us = rig.boot(50_000).unwrap();
    // The release of the reset press starts the self-test (1st tick); supply off: trip seen on the
    // 3rd tick; supply on: rest from the 4th tick, 2 ms quiet -> 6th.
    assert_eq!(boot_us, 5 * T);
    assert!(!rig.stop_requested() && !rig.category0_requested());
    let starts: Vec<_> = rig.events().iter().map(|e| (e.cause, e.flags)).collect();
    assert_eq!(starts, [(Cause::Reset, ResetCause::Unknown as u8)], "only the start is logged");
}

#[test]
fn trip_on_the_edge_writes_stop_at_the_edge_instant() {
    let mut rig = booted(cfg());
    rig.advance_to(0.010_25);
    rig.set_travel_m(0.004_999);
    assert!(!rig.stop_requested());
    rig.set_travel_m(0.005);
    assert!(rig.stop_requested(), "same call: no tick needed");
    assert!(!rig.category0_requested(), "budget fits: controlled stop");
    assert_eq!(rig.detected_at_s(), Some(0.010_25));
    let ev = rig.events()[1];
    assert_eq!((ev.cause, ev.flags, ev.travel_um), (Cause::Trip, FLAG_EDGE, 5_000));
    // Latched: the tool going back does not release the stop (Input policy, no press).
    rig.set_travel_m(0.0);
    rig.advance_to(0.5);
    assert!(rig.stop_requested());
    assert_eq!(rig.fw.state(), State::Tripped);
}

#[test]
fn polling_alone_detects_within_one_tick_over_all_phases() {
    for phase in (0..T).step_by(97) {
        let mut rig = booted(cfg());
        rig.set_tick_phase_us(phase);
        rig.set_edge_interrupt(false);
        let edge_us = 20_000 + 333;
        rig.advance_to_us(edge_us);
        rig.set_travel_um(6_000);
        rig.advance_to_us(edge_us + 2 * i64::from(T));
        let lat = rig.detected_at_s().unwrap() * 1e6 - edge_us as f64;
        assert!((0.0..f64::from(T)).contains(&lat.round()), "phase {phase}: latency {lat} us");
    }
}

#[test]
fn board_split_edge_path_bookkeeping_after_the_stop_write() {
    // The board's EXTI0 writes the stop itself (highest priority) and hands over to
    // `edge_stopped` at the tick's priority: the trip is latched and logged at the edge's instant.
    let mut rig = booted(cfg());
    assert!(rig.fw.edge_stops_directly());
    rig.set_edge_interrupt(false);
    rig.advance_to(0.010_25);
    rig.set_travel_m(0.006);
    rig.stop.set(false); // the edge handler's BSRR write
    let at = rig.micros_at(0.010_25);
    rig.advance_to(0.010_3); // no tick in between
    rig.fw.edge_stopped(at);
    assert_eq!(rig.fw.state(), State::Tripped);
    assert!(rig.stop_requested() && rig.fw.stop_requested());
    assert_eq!(rig.detected_at_s(), Some(0.010_25));
    let ev = *rig.events().last().unwrap();
    assert_eq!((ev.cause, ev.flags, ev.travel_um), (Cause::Trip, FLAG_EDGE, 5_000));
    // The tick got there first (the edge preempted it, the tick then polled the trip): the
    // bookkeeping only writes the stop again, nothing is logged twice.
    let mut rig = booted(cfg());
    rig.set_edge_interrupt(false);
    rig.advance_to(0.010_25);
    rig.set_travel_m(0.006);
    rig.stop.set(false);
    rig.advance_to(0.011);
    let n = rig.events().len();
    rig.fw.edge_stopped(rig.micros_at(0.010_25));
    assert_eq!((rig.fw.state(), rig.events().len()), (State::Tripped, n));
    // With a glitch filter the edge must not stop by itself: the board asks first.
    let mut c = cfg();
    c.filter = Filter::Consecutive(3);
    assert!(!booted(c).fw.edge_stops_directly());
}

#[test]
fn cut_wire_reads_as_a_trip() {
    let mut rig = booted(cfg());
    rig.advance_to(0.1);
    rig.inject_switch_fault(PinFault::CutWire);
    assert!(rig.stop_requested());
    assert_eq!(rig.fw.state(), State::Tripped);
    assert_eq!(rig.events()[1].cause, Cause::Trip);
}

#[test]
fn stuck_high_input_fails_the_start_up_self_test() {
    let mut rig = SimRig::digital(cfg(), SwitchKind::Inductive, 5_000).unwrap();
    rig.switch_pin().unwrap().set_fault(PinFault::StuckHigh);
    assert_eq!(rig.boot(50_000), Err(State::Fault(Cause::StuckInput)));
    assert!(rig.stop_requested() && rig.category0_requested());
    assert_eq!(rig.events()[1].cause, Cause::StuckInput);
    // It does not go away by itself; the reset input re-runs the self-test, which fails again while
    // the input is stuck and passes once it is repaired.
    rig.advance_to(0.1);
    assert_eq!(rig.fw.state(), State::Fault(Cause::StuckInput));
    rig.switch_pin().unwrap().set_fault(PinFault::None);
    rig.set_reset(true);
    rig.advance_to(0.160); // a 60 ms press: the reset acts on its release
    rig.set_reset(false);
    rig.advance_to(0.170);
    assert!(rig.fw.is_armed(), "{:?}", rig.fw.state());
    assert!(!rig.stop_requested());
}

#[test]
fn chattering_input_under_a_filter_is_a_fault() {
    let mut c = cfg();
    c.filter = Filter::Consecutive(3);
    c.chatter = Some(ChatterGuard { max_transitions: 6, window_us: 20_000 });
    let mut rig = booted(c);
    // Toggle every 1.5 ms: never three tripped ticks in a row, so the filter alone would never stop.
    let mut level = false;
    let mut t = 0.0;
    while t < 0.05 && !rig.stop_requested() {
        rig.advance_to(t);
        level = !level;
        rig.set_travel_um(if level { 6_000 } else { 0 });
        t += 0.0015;
    }
    assert_eq!(rig.fw.state(), State::Fault(Cause::Chatter));
    assert!(rig.stop_requested() && rig.category0_requested());
    assert!(t < 0.012, "7 changes at 1.5 ms: caught by {t} s");
}

#[test]
fn clock_stall_is_a_fault() {
    let mut rig = booted(cfg());
    rig.advance_to(0.050);
    rig.clock.set_stalled(true);
    rig.advance_to(0.050_999);
    assert!(rig.fw.is_armed(), "no tick yet since the stall");
    rig.advance_to(0.051);
    assert_eq!(rig.fw.state(), State::Fault(Cause::ClockStall));
    assert!(rig.stop_requested() && rig.category0_requested());
}

#[test]
fn missed_tick_deadline_is_a_fault() {
    let mut rig = booted(cfg());
    rig.advance_to(0.030);
    rig.skip_ticks_until(0.031); // the firmware was blocked for one tick
    rig.advance_to(0.032);
    assert_eq!(rig.fw.state(), State::Fault(Cause::MissedDeadline));
    assert!(rig.stop_requested());
}

#[test]
fn timer_wrap_during_a_trip() {
    let mut c = cfg();
    c.reset = ResetPolicy::Auto { hold_us: 20_000 };
    let mut rig = SimRig::digital(c, SwitchKind::Inductive, 5_000).unwrap();
    rig.start_clock_at(Micros(u32::MAX - 81_000)); // 50 ms reset press + 6 ms self-test: wraps about 25 ms into the plant run
    rig.boot(50_000).unwrap();
    let wrap_s = rig.seconds_at(Micros(0));
    assert!(wrap_s > 0.02 && wrap_s < 0.03, "{wrap_s}");
    rig.advance_to(0.020);
    rig.set_travel_m(0.006);
    let t_detect = rig.detected_at_s().unwrap();
    assert_eq!(t_detect, 0.020);
    rig.advance_to(0.030); // across the wrap while tripped
    assert!(rig.stop_requested());
    rig.set_travel_m(0.0); // back on the front stop at 30 ms
    // The first tick that sees the tool back is at 31 ms (the 30 ms tick ran before the plant moved).
    rig.advance_to(0.050);
    assert!(rig.stop_requested(), "19 ms of the 20 ms hold");
    rig.advance_to(0.051);
    assert!(!rig.stop_requested(), "re-armed 20 ms after, across the wrap");
    assert!(rig.fw.is_healthy());
    assert_eq!(rig.detected_at_s(), Some(t_detect), "timestamp still maps back across the wrap");
}

#[test]
fn reset_by_input_needs_the_tool_back_and_a_new_press() {
    let mut rig = booted(cfg());
    rig.advance_to(0.01);
    rig.set_travel_m(0.006);
    rig.set_reset(true); // pressed while the tool is still back: ignored
    rig.advance_to(0.02);
    rig.set_reset(false);
    rig.advance_to(0.03);
    assert!(rig.stop_requested());
    rig.set_travel_m(0.0);
    rig.advance_to(0.04);
    assert!(rig.stop_requested(), "back, but no press yet");
    rig.set_reset(true);
    rig.advance_to(0.2);
    assert!(rig.stop_requested(), "pressing does not reset (ISO 13849-1 5.2.2: on release)");
    rig.set_reset(false);
    rig.advance_to(0.201);
    assert!(!rig.stop_requested() && rig.fw.is_armed(), "the release does");
    // A button held across the next trip does not re-arm on its release.
    rig.set_reset(true);
    rig.advance_to(0.25);
    rig.set_travel_m(0.006);
    rig.set_travel_m(0.0);
    rig.advance_to(0.3);
    rig.set_reset(false);
    rig.advance_to(0.4);
    assert!(rig.stop_requested());
}

#[test]
fn automatic_reset_after_the_hold_time_on_the_front_stop() {
    let mut c = cfg();
    c.reset = ResetPolicy::Auto { hold_us: 100_000 };
    let mut rig = booted(c);
    rig.advance_to(0.01);
    rig.set_travel_m(0.006);
    rig.advance_to(0.05);
    rig.set_travel_m(0.0);
    rig.advance_to(0.10);
    rig.set_travel_m(0.0055); // bounced back towards the switch: the hold starts again
    rig.advance_to(0.101);
    rig.set_travel_m(0.0);
    rig.advance_to(0.200);
    assert!(rig.stop_requested());
    rig.advance_to(0.202);
    assert!(!rig.stop_requested(), "100 ms after the bounce");
}

#[test]
fn faults_are_not_cleared_by_the_automatic_reset() {
    let mut c = cfg();
    c.reset = ResetPolicy::Auto { hold_us: 1_000 };
    let mut rig = booted(c);
    rig.advance_to(0.01);
    rig.clock.set_stalled(true);
    rig.advance_to(0.02);
    rig.clock.set_stalled(false);
    rig.advance_to(0.5);
    assert_eq!(rig.fw.state(), State::Fault(Cause::ClockStall));
    assert_eq!(rig.fw.log().len(), 2, "the start, then the fault logged once, not once per tick");
}

#[test]
fn glitch_filter_latency_end_to_end() {
    for (filter, lo, hi) in [
        (Filter::Consecutive(3), 2 * T, 3 * T),
        (Filter::MinDuration(2_500), 2_500, 2_500 + T),
    ] {
        let mut c = cfg();
        c.filter = filter;
        for phase in (0..T).step_by(61) {
            let mut rig = booted(c);
            rig.set_tick_phase_us(phase);
            let edge_us = 10_000 + 17;
            rig.advance_to_us(edge_us);
            rig.set_travel_um(6_000);
            assert!(!rig.stop_requested(), "{filter:?}: the edge alone must not stop");
            rig.advance_to_us(edge_us + 5 * i64::from(T));
            let lat = (rig.detected_at_s().unwrap() * 1e6).round() as i64 - edge_us;
            assert!(lat >= i64::from(lo) && lat < i64::from(hi), "{filter:?} phase {phase}: {lat} us");
            assert!(lat <= i64::from(filter.max_added_latency_us(T)));
            let ev = rig.events()[1];
            assert_eq!(ev.flags & FLAG_FILTERED, FLAG_FILTERED);
            // first_seen: the edge itself for MinDuration (timestamped by the interrupt), the first
            // tripped tick for Consecutive.
            let first_us = i64::from(rig.sim_us_at(ev.first_seen));
            match filter {
                Filter::MinDuration(_) => assert_eq!(first_us, edge_us),
                _ => assert!(first_us >= edge_us && first_us < edge_us + i64::from(T)),
            }
        }
    }
}

#[test]
fn a_glitch_shorter_than_the_filter_does_not_stop() {
    let mut c = cfg();
    c.filter = Filter::MinDuration(2_000);
    let mut rig = booted(c);
    rig.advance_to(0.0100);
    rig.set_travel_um(6_000);
    rig.advance_to(0.0115);
    rig.set_travel_um(0);
    rig.advance_to(0.05);
    assert!(!rig.stop_requested() && rig.fw.is_armed());
}

#[test]
fn short_stroke_budget_escalates_to_category_0() {
    // Fig. 46: 0.25 m/s is mode 3; s_stop = 4 mm + 31.25 mm, far beyond the 5 mm left.
    let c = Config::new(T, BudgetConfig { robot_speed_um_per_s: 250_000, ..budget() });
    let mut rig = booted(c);
    assert!(!rig.category0_requested(), "armed: energised");
    rig.advance_to(0.01);
    rig.set_travel_m(0.005);
    assert!(rig.stop_requested() && rig.category0_requested());
    let ev = rig.events()[1];
    assert_eq!(ev.flags, FLAG_EDGE | FLAG_ESCALATED);
    let v = rig.fw.last_verdict().unwrap();
    assert_eq!((v.required_um, v.remaining_um), (35_250, 5_000));
}

#[test]
fn event_log_wraps_over_many_trips() {
    let mut c = cfg();
    c.reset = ResetPolicy::Auto { hold_us: 2_000 };
    let mut rig = booted(c);
    let trips = SIM_LOG + 8;
    for k in 0..trips {
        let t0 = 0.01 * k as f64;
        rig.advance_to(t0);
        rig.set_travel_m(0.006);
        rig.advance_to(t0 + 0.002);
        rig.set_travel_m(0.0);
    }
    rig.advance_to(0.01 * trips as f64);
    let log = rig.fw.log();
    assert_eq!(log.len(), SIM_LOG);
    assert_eq!(log.overwritten(), 9);
    let evs = rig.events();
    assert_eq!(evs.first().unwrap().seq, 9, "the start (seq 0) and the first 8 trips overwritten");
    assert_eq!(evs.last().unwrap().seq as usize, trips);
    let bytes = rig.event_log_bytes();
    let (h, decoded) = flinch_firmware::event_log::decode(&bytes).unwrap();
    assert_eq!(usize::from(h.count), SIM_LOG);
    assert_eq!(decoded.collect::<Vec<_>>(), evs);
}

#[test]
fn broken_stop_output_is_a_fault() {
    let mut rig = booted(cfg());
    rig.advance_to(0.01);
    rig.stop.set_fault(PinFault::Broken);
    rig.set_travel_m(0.006);
    assert_eq!(rig.fw.state(), State::Fault(Cause::OutputFault));
    assert!(rig.category0_requested(), "the escalation output still drops");
}

fn analog_cfg() -> AnalogConfig {
    // 12-bit, 20 mm span, zero at 200 counts, trip at 1.5 mm (prototype d_sw, MODEL.md "Sensor").
    AnalogConfig::linear_12bit(200, Mm::from_num(20), Mm::from_num(1.5))
}

#[test]
fn analog_sensor_trips_at_its_threshold_and_reports_travel() {
    let mut rig = SimRig::analog(cfg(), analog_cfg()).unwrap();
    rig.boot(50_000).unwrap();
    rig.set_travel_m(0.0014);
    rig.advance_to(0.01);
    assert!(!rig.stop_requested());
    rig.set_travel_m(0.0016);
    rig.advance_to(0.011);
    assert!(rig.stop_requested());
    let ev = rig.events()[1];
    assert!((ev.travel_um - 1600).abs() < 10, "{}", ev.travel_um);
}

#[test]
fn analog_cut_wire_is_a_sensor_fault() {
    let mut rig = SimRig::analog(cfg(), analog_cfg()).unwrap();
    rig.boot(50_000).unwrap();
    rig.advance_to(0.01);
    rig.adc().unwrap().set_fault(AdcFault::CutWire);
    rig.advance_to(0.011);
    assert_eq!(rig.fw.state(), State::Fault(Cause::SensorFault));
    assert!(rig.stop_requested() && rig.category0_requested());
}

#[test]
fn analog_measured_closing_speed_drives_the_budget() {
    // Configured 0.05 m/s fits; the tool is measured coming back at 1 m/s, which does not:
    // 1 * 0.016 + 1 / 2 = 516 mm.
    let mut rig = SimRig::analog(cfg(), analog_cfg()).unwrap();
    rig.boot(50_000).unwrap();
    for k in 0..40 {
        let t = 0.01 + k as f64 * 1e-4;
        rig.advance_to(t);
        rig.set_travel_m((t - 0.01) * 1.0);
    }
    assert!(rig.stop_requested());
    assert!(rig.category0_requested());
    let v = rig.fw.last_verdict().unwrap();
    // The smoothed estimate (velocity_shift = 1) lags the true 1 m/s; at 0.5 m/s it is already 133 mm.
    assert!(v.required_um > 100_000, "{v:?}");
}

// ---- Resets never re-arm by themselves (IEC 60204-1 7.5, ISO 13849-1 5.2.2) ---------------------

use flinch_firmware::{Boot, Retained, StartPolicy};

const ALL_CAUSES: [ResetCause; 7] = [
    ResetCause::PowerOn,
    ResetCause::BrownOut,
    ResetCause::Watchdog,
    ResetCause::Software,
    ResetCause::Pin,
    ResetCause::LowPower,
    ResetCause::Unknown,
];

/// Tick a freshly reset rig for `secs` of healthy sensor at rest, without touching the reset button.
fn run_untouched(rig: &mut SimRig<flinch_firmware::DigitalSwitch<flinch_hal_sim::SimPin, flinch_hal_sim::SimPin>>, secs: f64) {
    let tick = 1e-3;
    let mut t = 0.0;
    while t < secs {
        rig.advance_to(t);
        assert!(rig.stop_requested() && rig.category0_requested(), "went to \"go\" by itself at {t} s");
        t += tick;
    }
}

#[test]
fn no_reset_of_any_cause_re_arms_by_itself_by_default() {
    for cause in ALL_CAUSES {
        let boot = Boot { cause, retained: Retained::default() };
        let mut rig = SimRig::digital_after(cfg(), boot, SwitchKind::Inductive, 5_000).unwrap();
        run_untouched(&mut rig, 10.0);
        assert_eq!(rig.fw.state(), State::Fault(Cause::Reset), "{cause:?}");
        let ev = rig.events()[0];
        assert_eq!((ev.cause, ev.flags), (Cause::Reset, cause as u8), "the reset cause is logged");
    }
}

#[test]
fn auto_start_only_after_a_clean_power_on() {
    let mut c = cfg();
    c.start = StartPolicy::AutoAfterPowerOn;
    for cause in ALL_CAUSES {
        let boot = Boot { cause, retained: Retained::default() };
        let mut rig = SimRig::digital_after(c, boot, SwitchKind::Inductive, 5_000).unwrap();
        rig.advance_to(1.0);
        if cause == ResetCause::PowerOn {
            assert!(rig.fw.is_armed(), "a clean power-on arms by itself under AutoAfterPowerOn");
        } else {
            assert!(rig.stop_requested(), "{cause:?} must wait for a person even under AutoAfterPowerOn");
            assert_eq!(rig.fw.state(), State::Fault(Cause::Reset));
        }
    }
}

#[test]
fn a_latch_in_force_when_the_part_reset_survives_the_reset() {
    // Trip, then the part resets (the board hands the retained record over), even at power-on with
    // auto start allowed: still stopped, and the log says why.
    let mut c = cfg();
    c.start = StartPolicy::AutoAfterPowerOn;
    let mut rig = booted(c);
    rig.advance_to(0.01);
    rig.set_travel_m(0.006);
    assert!(rig.stop_requested());
    let kept = rig.fw.retained();
    assert_eq!(kept.decode().map(|(l, _)| l), Some(Some(Cause::Trip)));
    for cause in [ResetCause::PowerOn, ResetCause::Watchdog, ResetCause::BrownOut] {
        let mut again = SimRig::digital_after(c, Boot { cause, retained: kept }, SwitchKind::Inductive, 5_000).unwrap();
        run_untouched(&mut again, 2.0);
        let evs: Vec<_> = again.events().iter().map(|e| (e.cause, e.flags)).collect();
        assert_eq!(evs, [(Cause::Reset, cause as u8), (Cause::Trip, flinch_firmware::event_log::FLAG_RETAINED)]);
        assert_eq!(again.fw.retained().decode(), Some((Some(Cause::Trip), 1)), "latch and boot count carried on");
    }
    // A fault handler that ran before a watchdog reset.
    let handler = Retained::new(Some(Cause::FaultHandler), 3);
    let mut again = SimRig::digital_after(c, Boot { cause: ResetCause::Watchdog, retained: handler }, SwitchKind::Inductive, 5_000).unwrap();
    run_untouched(&mut again, 1.0);
    assert_eq!(again.events()[1].cause, Cause::FaultHandler);
    // A corrupted record is no record: a watchdog reset is latched anyway, a power-on may auto-start.
    let mut torn = kept;
    torn.words[1] ^= 0x10;
    let mut again = SimRig::digital_after(c, Boot { cause: ResetCause::Watchdog, retained: torn }, SwitchKind::Inductive, 5_000).unwrap();
    run_untouched(&mut again, 1.0);
}

#[test]
fn a_stuck_or_too_short_reset_press_never_arms() {
    let boot = Boot { cause: ResetCause::Watchdog, retained: Retained::default() };
    // Button held from before the reset (stuck), released after 6 s: its release is not a reset.
    let mut rig = SimRig::digital_after(cfg(), boot, SwitchKind::Inductive, 5_000).unwrap();
    rig.set_reset(true);
    run_untouched(&mut rig, 6.0);
    rig.set_reset(false);
    run_untouched(&mut rig, 7.0);
    // Pressed after the reset but held 6 s (jammed): refused.
    let mut rig = SimRig::digital_after(cfg(), boot, SwitchKind::Inductive, 5_000).unwrap();
    rig.advance_to(0.1);
    rig.set_reset(true);
    run_untouched(&mut rig, 6.1);
    rig.set_reset(false);
    run_untouched(&mut rig, 7.0);
    // A 20 ms blip (below the 50 ms minimum): refused.
    let mut rig = SimRig::digital_after(cfg(), boot, SwitchKind::Inductive, 5_000).unwrap();
    rig.advance_to(0.1);
    rig.set_reset(true);
    rig.advance_to(0.12);
    rig.set_reset(false);
    run_untouched(&mut rig, 1.0);
    // A proper press: arms after the release, not before.
    rig.set_reset(true);
    rig.advance_to(1.2);
    assert!(rig.stop_requested(), "still pressed");
    rig.set_reset(false);
    rig.advance_to(1.21);
    assert!(rig.fw.is_armed(), "{:?}", rig.fw.state());
}

#[test]
fn a_reset_button_held_through_a_watchdog_reset_never_re_arms_on_its_release() {
    // The operator (or a jammed contact) holds the button while the part is armed; the watchdog
    // resets the MCU; the button is let go 0.1 s, 1 s or 3 s later, inside the 50 ms..5 s press
    // window. The press began before the reset, so its release is no reset: stay stopped.
    for release_s in [0.1, 1.0, 3.0] {
        let mut rig = booted(cfg());
        rig.advance_to(0.05);
        rig.set_reset(true);
        rig.advance_to(0.2);
        assert!(rig.fw.is_armed(), "pressing while armed does nothing");
        let t_reset = 0.2005;
        rig.advance_to(t_reset);
        rig.mcu_reset(ResetCause::Watchdog);
        assert_eq!(rig.fw.state(), State::Fault(Cause::Reset));
        rig.advance_to(t_reset + release_s);
        rig.set_reset(false);
        let mut t = t_reset + release_s;
        while t < t_reset + release_s + 2.0 {
            rig.advance_to(t);
            assert!(rig.stop_requested() && rig.category0_requested(), "released {release_s} s after the reset: \"go\" at {t} s");
            t += 1e-3;
        }
        assert_eq!(rig.fw.state(), State::Fault(Cause::Reset), "released {release_s} s after the reset");
        // A deliberate press that begins after the reset does re-arm.
        rig.set_reset(true);
        rig.advance_to(t + 0.1);
        rig.set_reset(false);
        rig.advance_to(t + 0.11);
        assert!(rig.fw.is_armed(), "a fresh press after the reset: {:?}", rig.fw.state());
    }
}

#[test]
fn a_fault_right_after_the_reset_replaces_the_start_latch() {
    let boot = Boot { cause: ResetCause::Watchdog, retained: Retained::default() };
    let mut rig = SimRig::digital_after(cfg(), boot, SwitchKind::Inductive, 5_000).unwrap();
    rig.advance_to(0.002);
    rig.clock.set_stalled(true); // the timer clock died with the reset
    rig.advance_to(0.01);
    assert_eq!(rig.fw.state(), State::Fault(Cause::ClockStall));
    assert_eq!(rig.fw.retained().decode().map(|(l, _)| l), Some(Some(Cause::ClockStall)));
    // A press cannot even be timed on a dead clock (it reads 0 us held): refused, still stopped.
    rig.set_reset(true);
    rig.advance_to(0.1);
    rig.set_reset(false);
    rig.advance_to(1.0);
    assert!(rig.stop_requested() && !rig.fw.is_armed());
}

// ---- Two-channel switch: a stuck channel ends in stop (ISO 13849-1 6.2.6, category 3) -----------

type DualRig = SimRig<flinch_firmware::DualSwitch<flinch_hal_sim::SimPin, flinch_hal_sim::SimPin, flinch_hal_sim::SimPin>>;

const NC: SwitchKind = SwitchKind::Inductive; // high at rest
const NO: SwitchKind = SwitchKind::Magnetic { trip_high: true }; // low at rest: antivalent to NC
const DISCREPANCY_US: u32 = 20_000;

fn dual() -> DualRig {
    let mut rig = SimRig::dual_after(cfg(), Boot::POWER_ON, NC, NO, 5_000, DISCREPANCY_US).unwrap();
    rig.boot(50_000).unwrap();
    rig
}

/// Press and release the reset button (60 ms) starting at `t`; returns the time after.
fn press_reset(rig: &mut DualRig, t: f64) -> f64 {
    rig.advance_to(t);
    rig.set_reset(true);
    rig.advance_to(t + 0.06);
    rig.set_reset(false);
    rig.advance_to(t + 0.07);
    t + 0.07
}

#[test]
fn dual_healthy_pair_trips_on_the_edge_and_re_arms_after_a_reset() {
    let mut rig = dual();
    assert!(rig.fw.is_armed());
    rig.advance_to(0.010);
    rig.set_travel_m(0.006);
    assert!(rig.stop_requested(), "stopped in the edge interrupt");
    assert_eq!(rig.detected_at_s(), Some(0.010));
    rig.advance_to(0.1); // both channels agree: no discrepancy however long the trip
    assert_eq!(rig.fw.state(), State::Tripped);
    rig.set_travel_m(0.0);
    press_reset(&mut rig, 0.2);
    assert!(rig.fw.is_armed(), "{:?}", rig.fw.state());
}

#[test]
fn dual_channel_stuck_at_rest_fails_the_start_up_test() {
    let mut rig = SimRig::dual_after(cfg(), Boot::POWER_ON, NC, NO, 5_000, DISCREPANCY_US).unwrap();
    let (_, b) = rig.channel_pins().unwrap();
    b.set_fault(PinFault::StuckLow); // the NO channel stuck at rest: ignores the supply pulse
    assert_eq!(rig.boot(50_000), Err(State::Fault(Cause::StuckInput)));
    assert!(rig.stop_requested() && rig.category0_requested());
}

#[test]
fn dual_channel_sticking_at_rest_while_armed_still_stops_and_never_re_arms() {
    // The issue-10 case: a channel sticks at rest during operation, then the tool is pushed 6 mm back.
    for stuck in ["a", "b"] {
        let mut rig = dual();
        let (a, b) = rig.channel_pins().unwrap();
        rig.advance_to(0.5);
        if stuck == "a" {
            rig.inject_pin_fault(&a, PinFault::StuckHigh); // NC stuck at rest (high)
        } else {
            rig.inject_pin_fault(&b, PinFault::StuckLow); // NO stuck at rest (low)
        }
        assert!(rig.fw.is_armed(), "stuck at rest is invisible at rest");
        rig.advance_to(1.0);
        rig.set_travel_m(0.006);
        assert!(rig.stop_requested(), "{stuck}: the healthy channel stops at once (1oo2)");
        rig.advance_to(1.0 + f64::from(DISCREPANCY_US) * 1e-6 + 0.002);
        assert_eq!(rig.fw.state(), State::Fault(Cause::Discrepancy), "{stuck}: found within the discrepancy time");
        rig.set_travel_m(0.0);
        let t = press_reset(&mut rig, 1.5);
        rig.advance_to(t + 1.0);
        assert!(rig.stop_requested(), "{stuck}: the self-test after the reset finds the stuck channel");
        assert_eq!(rig.fw.state(), State::Fault(Cause::StuckInput));
    }
}

#[test]
fn dual_stuck_channel_found_even_by_a_trip_shorter_than_the_discrepancy_time() {
    let mut rig = dual();
    let (_, b) = rig.channel_pins().unwrap();
    rig.advance_to(0.2);
    rig.inject_pin_fault(&b, PinFault::StuckLow);
    rig.advance_to(0.3);
    rig.set_travel_m(0.006);
    assert!(rig.stop_requested());
    rig.advance_to(0.3005); // 0.5 ms: not even one tick
    rig.set_travel_m(0.0);
    rig.advance_to(0.302);
    assert_eq!(rig.fw.state(), State::Fault(Cause::Discrepancy), "B never showed the trip");
    rig.advance_to(2.0);
    assert!(rig.stop_requested());
}

#[test]
fn dual_channel_stuck_at_trip_or_wires_shorted_stop_without_a_demand() {
    // A stuck at "trip": stops at once (1oo2), then the discrepancy latches a fault.
    let mut rig = dual();
    let (a, b) = rig.channel_pins().unwrap();
    rig.advance_to(0.1);
    rig.inject_pin_fault(&a, PinFault::StuckLow);
    assert!(rig.stop_requested());
    rig.advance_to(0.15);
    assert_eq!(rig.fw.state(), State::Fault(Cause::Discrepancy));
    // The two wires shorted together at rest (both read high): antivalent wiring sees it as a
    // disagreement while the tool has not moved.
    drop((a, b));
    let mut rig = dual();
    rig.advance_to(0.1);
    let (_, b) = rig.channel_pins().unwrap();
    rig.inject_pin_fault(&b, PinFault::StuckHigh);
    assert!(rig.stop_requested(), "B reads 'trip': stop at once");
    rig.advance_to(0.15);
    assert_eq!(rig.fw.state(), State::Fault(Cause::Discrepancy));
    assert!(rig.category0_requested());
}

// ---- External device monitoring: a welded or stuck stop relay ends in a latched stop ------------

#[test]
fn edm_welded_relay_is_found_at_the_next_stop_and_escalates_to_category_0() {
    for k in 1..=2 {
        let mut rig = booted(cfg());
        let settle_s = f64::from(rig.fw.config().edm_settle_us) * 1e-6;
        rig.advance_to(0.1);
        let relay = if k == 1 { rig.k1.clone() } else { rig.k2.clone() };
        relay.set_fault(PinFault::StuckLow); // contacts welded: the mirror contact never closes again
        rig.advance_to(0.2);
        assert!(rig.fw.is_armed(), "K{k}: a welded relay looks like a pulled-in one while armed");
        rig.set_travel_m(0.006);
        assert!(rig.stop_requested() && !rig.category0_requested(), "K{k}: controlled stop first");
        rig.advance_to(0.2 + settle_s + 0.0025); // first mismatching tick + settle + one tick
        assert_eq!(rig.fw.state(), State::Fault(Cause::EdmMismatch), "K{k}: found within the settle time");
        assert!(rig.category0_requested(), "K{k}: the drive-power channel takes over from the welded one");
        // Reset with the tool back: the EDM start check refuses to energise while it is welded.
        rig.set_travel_m(0.0);
        rig.set_reset(true);
        rig.advance_to(0.4);
        rig.set_reset(false);
        rig.advance_to(2.0);
        assert!(rig.stop_requested() && !rig.fw.is_armed(), "K{k}: never 'go' with a welded relay");
    }
}

#[test]
fn edm_start_check_refuses_to_arm_over_a_relay_welded_while_stopped() {
    let mut rig = SimRig::digital(cfg(), SwitchKind::Inductive, 5_000).unwrap();
    rig.k2.set_fault(PinFault::StuckLow);
    assert_eq!(rig.boot(50_000), Err(State::Fault(Cause::EdmMismatch)));
    assert!(rig.stop_requested() && rig.category0_requested());
}

#[test]
fn edm_feedback_wire_cut_while_armed_is_a_fault_without_a_demand() {
    let mut rig = booted(cfg());
    rig.advance_to(0.1);
    rig.k1.set_fault(PinFault::StuckHigh); // reads "released" while the relay is pulled in
    rig.advance_to(0.1 + 0.0225); // first mismatching tick + 20 ms settle + one tick
    assert_eq!(rig.fw.state(), State::Fault(Cause::EdmMismatch));
    assert!(rig.stop_requested() && rig.category0_requested());
}

#[test]
fn edm_healthy_relays_never_false_alarm_over_many_trips_and_resets() {
    let mut c = cfg();
    c.reset = ResetPolicy::Auto { hold_us: 2_000 };
    let mut rig = booted(c);
    for k in 0..100 {
        let t0 = 0.05 * f64::from(k);
        rig.advance_to(t0);
        rig.set_travel_m(0.006);
        rig.advance_to(t0 + 0.01);
        rig.set_travel_m(0.0);
    }
    rig.advance_to(5.1);
    assert!(rig.fw.is_armed(), "{:?}", rig.fw.state());
}

// ---- Clock plausibility against an independent oscillator ----------------------------------------

fn clock_checked() -> Config {
    let mut c = cfg();
    c.clock_check = Some(flinch_firmware::ClockCheck { reference_hz: 1_000_000, window_us: 50_000, tolerance_pct: 10 });
    c
}

#[test]
fn clock_check_holds_arming_until_the_first_window_and_passes_a_good_clock() {
    let mut c = clock_checked();
    c.clock_check = Some(flinch_firmware::ClockCheck { reference_hz: 1_000_000, window_us: 200_000, tolerance_pct: 10 });
    let mut rig = SimRig::digital(c, SwitchKind::Inductive, 5_000).unwrap();
    rig.clock.set_reference_pct(100);
    // Clearing the start latch restarts the check: a fresh window opens on the tick after the
    // release; the self-test is done 5 ms after the release, but arming waits for the window (200 ms).
    let boot_us = rig.boot(400_000).unwrap();
    assert!((200_000..=202_000).contains(&boot_us), "{boot_us}");
    rig.advance_to(2.0);
    assert!(rig.fw.is_armed(), "{:?}", rig.fw.state());
}

#[test]
fn clock_check_a_slow_or_fast_main_oscillator_never_arms() {
    for pct in [0, 70, 130] {
        let mut rig = SimRig::digital(clock_checked(), SwitchKind::Inductive, 5_000).unwrap();
        rig.clock.set_reference_pct(pct);
        assert_eq!(rig.boot(1_000_000), Err(State::Fault(Cause::ClockDrift)), "reference at {pct} %");
        assert!(rig.stop_requested() && rig.category0_requested());
    }
    // Configured but no reference wired: the same fault.
    let mut rig = SimRig::digital(clock_checked(), SwitchKind::Inductive, 5_000).unwrap();
    assert_eq!(rig.boot(1_000_000), Err(State::Fault(Cause::ClockDrift)));
}

#[test]
fn clock_check_drift_while_armed_stops_within_two_windows() {
    let mut rig = SimRig::digital(clock_checked(), SwitchKind::Inductive, 5_000).unwrap();
    rig.clock.set_reference_pct(100);
    rig.boot(200_000).unwrap();
    rig.advance_to(1.0);
    assert!(rig.fw.is_armed());
    rig.clock.set_reference_pct(0); // the reference oscillator dies (or the main one runs away)
    rig.advance_to(1.0 + 2.0 * 0.050 + 0.001);
    assert_eq!(rig.fw.state(), State::Fault(Cause::ClockDrift));
    assert!(rig.stop_requested());
}
