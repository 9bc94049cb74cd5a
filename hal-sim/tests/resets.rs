//! MCU resets against the stateful fakes: no reset of any cause re-arms by itself (IEC 60204-1
//! 7.5, ISO 13849-1 5.2.2), the latch in force survives the reset, stuck, too short and too long
//! reset presses never arm.

use flinch_firmware::{Boot, Cause, ResetCause, Retained, StartPolicy, State, SwitchKind};
use flinch_hal_sim::SimRig;

mod common;
use common::{booted, cfg};

// ---- Resets never re-arm by themselves (IEC 60204-1 7.5, ISO 13849-1 5.2.2) ---------------------

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
