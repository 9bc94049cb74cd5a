//! Monitoring against the stateful fakes: the two-channel switch (a stuck channel ends in stop,
//! ISO 13849-1 6.2.6 category 3), external device monitoring of the stop relays, and the clock
//! checked against an independent oscillator.

use flinch_firmware::{Boot, Cause, Config, ResetPolicy, State, SwitchKind};
use flinch_hal_sim::{PinFault, SimRig};

mod common;
use common::{booted, cfg};

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
