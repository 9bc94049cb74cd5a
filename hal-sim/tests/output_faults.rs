//! The output side's faults (issue 25), each named for the fault: a stop pin stuck high, a frozen
//! port, a welded K2, welded K1 and K2; the time from the demand to a safe state measured for each
//! over the tick's phases; every latched fault starving the watchdog; and the reset that follows
//! releasing the pins and finding the latch.

use flinch_firmware::event_log::{FLAG_ESC, FLAG_K1, FLAG_K2, FLAG_RETAINED};
use flinch_firmware::{Boot, Cause, DigitalSwitch, ResetCause, State, SwitchKind};
use flinch_hal_sim::output_faults::extra_dead_time_us;
use flinch_hal_sim::{OutputFault, OutputPort, PinFault, SimPin, SimRig};

mod common;
use common::{booted, cfg, T};

type Rig = SimRig<DigitalSwitch<SimPin, SimPin>>;

/// Safe: the robot's stop circuit is open, or drive power is off (category 0).
fn safe(rig: &Rig) -> bool {
    rig.stop_requested() || rig.category0_requested()
}

/// Demand a stop (the tool pushed past d_sw) at `at_us` of sim time, then step in 10 us until the
/// cell is safe; the time from the demand, microseconds (None: not within 100 ms).
fn demand_to_safe_us(rig: &mut Rig, at_us: i64) -> Option<i64> {
    rig.advance_to_us(at_us);
    rig.set_travel_um(6_000);
    let mut t = at_us;
    while t <= at_us + 100_000 {
        rig.advance_to_us(t);
        if safe(rig) {
            return Some(t - at_us);
        }
        t += 10;
    }
    None
}

/// The last event's cause and flags.
fn last_event(rig: &Rig) -> (Cause, u8) {
    let e = *rig.events().last().unwrap();
    (e.cause, e.flags)
}

/// The board's IWDG (~8 ms at LSI / 4, reload 64) around the rig: tick in 1 ms steps up to `until`
/// s, and reset the MCU when the firmware has not let it be fed for longer than that. Returns the
/// number of watchdog resets. `check` runs after every step.
fn run_with_iwdg(rig: &mut Rig, from: f64, until: f64, mut check: impl FnMut(&Rig, f64)) -> u32 {
    const IWDG_S: f64 = 0.008;
    let (mut last_feed, mut resets, mut t) = (from, 0, from);
    while t < until {
        rig.advance_to(t);
        if rig.fw.feeds_watchdog() {
            last_feed = t;
        } else if t - last_feed > IWDG_S {
            rig.mcu_reset(ResetCause::Watchdog);
            resets += 1;
            last_feed = t;
        }
        check(rig, t);
        t += 1e-3;
    }
    resets
}

#[test]
fn stuck_stop_pin_the_other_channel_stops_at_the_demand_and_the_read_back_latches_at_the_next_tick() {
    for phase in (0..T).step_by(97) {
        let mut rig = booted(cfg());
        rig.set_tick_phase_us(phase);
        rig.advance_to(0.1);
        rig.inject_output_fault(OutputFault::StuckStopPin);
        rig.advance_to(0.2);
        assert!(rig.fw.is_armed(), "a pin stuck high looks energised while armed: found at the demand");
        let at = 200_000 + 333;
        assert_eq!(demand_to_safe_us(&mut rig, at), Some(0), "phase {phase}: K2 opens the stop circuit in the edge");
        assert!(!rig.relay_released(1) && rig.relay_released(2));
        rig.advance_to_us(at + i64::from(T));
        assert_eq!(rig.fw.state(), State::Fault(Cause::OutputReadBack), "phase {phase}: the next tick reads K1 high");
        assert_eq!(last_event(&rig), (Cause::OutputReadBack, flinch_firmware::event_log::FLAG_ESCALATED | FLAG_K1));
        assert!(rig.category0_requested() && !rig.fw.feeds_watchdog());
    }
}

#[test]
fn stuck_stop_pin_while_stopped_never_arms_and_resets_until_repaired() {
    let mut rig = booted(cfg());
    rig.advance_to(0.01);
    rig.set_travel_m(0.006);
    rig.set_travel_m(0.0);
    rig.inject_output_fault(OutputFault::StuckStopPin);
    rig.advance_to(0.012);
    assert_eq!(rig.fw.state(), State::Fault(Cause::OutputReadBack), "read high while commanded low");
    // The watchdog resets the part again and again while the pin stays stuck; never "go".
    let resets = run_with_iwdg(&mut rig, 0.012, 2.0, |r, t| assert!(r.stop_requested() && r.relay_released(2), "{t}"));
    assert!(resets > 10, "{resets}");
    // A person presses reset: the self-test runs, the stuck pin is seen again, no arming.
    rig.set_reset(true);
    rig.advance_to(2.06);
    rig.set_reset(false);
    run_with_iwdg(&mut rig, 2.06, 3.0, |r, t| assert!(!r.fw.is_armed() && r.stop_requested(), "{t}"));
}

#[test]
fn frozen_port_of_any_output_latches_within_two_ticks_and_the_reset_releases_its_pins() {
    for (port, flag) in [(OutputPort::K1, FLAG_K1), (OutputPort::K2, FLAG_K2), (OutputPort::Escalation, FLAG_ESC)] {
        let mut rig = booted(cfg());
        rig.advance_to(0.100_5);
        rig.inject_output_fault(OutputFault::FrozenPort(port));
        rig.advance_to(0.102_5); // the ticks at 101 and 102 ms read it low
        assert_eq!(rig.fw.state(), State::Fault(Cause::OutputReadBack), "{port:?}");
        assert_eq!(last_event(&rig).1 & (FLAG_K1 | FLAG_K2 | FLAG_ESC), flag, "{port:?}: names the frozen channel");
        assert!(rig.stop_requested(), "{port:?}: the other relay opens the stop circuit");
        if port == OutputPort::Escalation {
            assert!(!rig.category0_requested(), "a frozen escalation port cannot drop until the reset");
        } else {
            assert!(rig.category0_requested(), "{port:?}: category 0 on the third port");
        }
        assert!(!rig.fw.feeds_watchdog(), "{port:?}: the watchdog is starved");
        // The IWDG resets the part within about 8 ms: every pin is released, and for ten seconds
        // nothing is energised again (the probe found both pins high 10 s later).
        let resets = run_with_iwdg(&mut rig, 0.1025, 10.0, |r, t| {
            if t > 0.12 {
                assert!(!r.stop_k1.level() && !r.stop_k2.level() && !r.escalation.level(), "{port:?} at {t}: a pin still high");
            }
        });
        assert_eq!(resets, 1, "{port:?}: one reset releases the port and the start latch holds");
        assert_eq!(rig.fw.state(), State::Fault(Cause::Reset));
        let found: Vec<_> = rig.events().iter().map(|e| (e.cause, e.flags)).collect();
        assert!(found.contains(&(Cause::OutputReadBack, FLAG_RETAINED)), "{port:?}: the next start finds the latch: {found:?}");
    }
}

#[test]
fn frozen_port_at_the_demand_the_other_channel_stops_in_the_edge() {
    for port in [OutputPort::K1, OutputPort::K2] {
        let mut rig = booted(cfg());
        rig.advance_to(0.200_2);
        rig.inject_output_fault(OutputFault::FrozenPort(port));
        assert_eq!(demand_to_safe_us(&mut rig, 200_200), Some(0), "{port:?}");
    }
}

#[test]
fn welded_k2_k1_stops_at_the_demand_and_edm_latches_after_the_settle_time() {
    let mut rig = booted(cfg());
    rig.advance_to(0.1);
    rig.inject_output_fault(OutputFault::WeldedK2);
    rig.advance_to(0.2);
    assert!(rig.fw.is_armed(), "a welded relay looks pulled in while armed");
    assert_eq!(demand_to_safe_us(&mut rig, 200_333), Some(0));
    assert!(rig.relay_released(1) && !rig.relay_released(2));
    rig.advance_to(0.2 + 0.0225);
    assert_eq!(rig.fw.state(), State::Fault(Cause::EdmMismatch));
    assert_eq!(last_event(&rig).1 & (FLAG_K1 | FLAG_K2), FLAG_K2, "names K2 only");
    assert!(rig.category0_requested() && !rig.fw.feeds_watchdog());
}

#[test]
fn welded_k1_and_k2_only_category_0_remains_after_the_settle_time_and_two_ticks() {
    let c = cfg();
    let bound = i64::from(extra_dead_time_us(&c, OutputFault::WeldedK1K2));
    assert_eq!(bound, 22_000, "20 ms settle + two 1 ms ticks");
    let mut worst = 0;
    for phase in (0..T).step_by(50) {
        let mut rig = booted(c);
        rig.set_tick_phase_us(phase);
        rig.advance_to(0.1);
        rig.inject_output_fault(OutputFault::WeldedK1K2);
        let took = demand_to_safe_us(&mut rig, 200_017).unwrap_or_else(|| panic!("phase {phase}: never safe"));
        assert!(!rig.stop_requested(), "the stop circuit stays closed");
        assert!(rig.category0_requested(), "drive power off");
        assert_eq!(rig.fw.state(), State::Fault(Cause::EdmMismatch));
        assert!(took > 21_000 && took <= bound, "phase {phase}: {took} us");
        worst = worst.max(took);
    }
    assert!(worst > bound - 100, "the bound is reached within 0.1 ms: {worst} us");
    for f in OutputFault::ALL {
        if f != OutputFault::WeldedK1K2 {
            assert_eq!(extra_dead_time_us(&c, f), 0, "{}: one channel still stops", f.name());
        }
    }
}

#[test]
fn every_latched_fault_starves_the_watchdog_and_only_healthy_states_feed_it() {
    // Healthy: the start latch after a reset, the self-test, armed, tripped.
    let mut rig = SimRig::digital_after(cfg(), Boot { cause: ResetCause::Watchdog, retained: Default::default() }, SwitchKind::Inductive, 5_000).unwrap();
    rig.advance_to(0.05);
    assert_eq!(rig.fw.state(), State::Fault(Cause::Reset));
    assert!(rig.fw.feeds_watchdog(), "the start latch waits for a person: fed");
    let mut rig = booted(cfg());
    assert!(rig.fw.is_armed() && rig.fw.feeds_watchdog());
    rig.advance_to(0.01);
    rig.set_travel_m(0.006);
    rig.advance_to(0.1);
    assert!(rig.fw.state() == State::Tripped && rig.fw.feeds_watchdog());
    // Every fault: none feeds.
    let faults: [(&str, fn(&mut Rig)); 7] = [
        ("clock stall", |r| r.clock.set_stalled(true)),
        ("missed deadline", |r| r.skip_ticks_until(0.0515)),
        ("welded relays at a demand", |r| {
            r.inject_output_fault(OutputFault::WeldedK1K2);
            r.set_travel_m(0.006);
        }),
        ("stuck pin at rest", |r| {
            r.set_travel_m(0.006);
            r.inject_output_fault(OutputFault::StuckStopPin);
        }),
        ("frozen port", |r| r.inject_output_fault(OutputFault::FrozenPort(OutputPort::K2))),
        ("broken output", |r| r.stop_k2.set_fault(PinFault::Broken)),
        ("EDM wire cut", |r| r.k1.set_fault(PinFault::StuckHigh)),
    ];
    for (what, inject) in faults {
        let mut rig = booted(cfg());
        rig.advance_to(0.05);
        inject(&mut rig);
        rig.advance_to(0.2);
        assert!(matches!(rig.fw.state(), State::Fault(c) if c != Cause::Reset), "{what}: {:?}", rig.fw.state());
        assert!(!rig.fw.feeds_watchdog(), "{what}: still fed");
    }
}
