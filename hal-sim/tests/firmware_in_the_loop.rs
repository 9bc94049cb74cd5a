//! The firmware library against the stateful fakes: detection (edge and polling), the glitch
//! filter's latency measured end to end, the input faults of issue 3, the reset policies after a
//! trip, the event log, the stroke budget and the analog sensor. The resets of the MCU are in
//! `resets.rs`, the two-channel switch, EDM and clock check in `monitoring.rs`.

use flinch_firmware::event_log::{FLAG_EDGE, FLAG_ESCALATED, FLAG_FILTERED};
use flinch_firmware::{
    AnalogConfig, BudgetConfig, Cause, ChatterGuard, Config, Filter, Micros, Mm, ResetCause, ResetPolicy, State,
    SwitchKind,
};
use flinch_hal_sim::{AdcFault, PinFault, SimRig, SIM_LOG};
mod common;
use common::{booted, budget, cfg, T};

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

/// A switch edge between two whole microseconds is timestamped at the first whole microsecond at
/// or after it, never before (rounding to the nearest gave the firmware a timestamp up to 0.5 us
/// before the edge: `flinch hil`'s negative firmware latency, issue 26 item 6); a tick due inside
/// that microsecond runs after the edge and reads it.
#[test]
fn an_edge_between_microseconds_is_timestamped_at_or_after_it() {
    for frac in [1e-9, 0.035, 0.4999, 0.5, 0.5001, 0.9, 0.999_999] {
        let mut rig = booted(cfg());
        let t = (10_250.0 + frac) * 1e-6;
        rig.advance_to_event(t);
        rig.set_travel_m(0.005);
        let at = rig.detected_at_s().unwrap();
        assert!(at >= t && at - t < 1e-6, "edge at {t} s, timestamp {at} s");
    }
    // Exactly on a microsecond: that microsecond.
    assert_eq!(flinch_hal_sim::first_us_at_or_after(0.010_25), 10_250);
    for t in [0.3, 0.1 + 0.2, 1.0 / 3.0, 59.999_999_5, 7.25e-6] {
        let us = flinch_hal_sim::first_us_at_or_after(t);
        assert!(us as f64 / 1e6 >= t && ((us - 1) as f64 / 1e6) < t, "{t}: {us}");
    }
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
    rig.stop_k1.set(false); // the edge handler's BSRR writes, K1 then K2
    rig.stop_k2.set(false);
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
    rig.stop_k1.set(false);
    rig.stop_k2.set(false);
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
    rig.stop_k1.set_fault(PinFault::Broken);
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
