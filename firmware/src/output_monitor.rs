//! Cross-monitoring of the output side: each output read back at its pin, each stop relay read back
//! at its contacts (EDM), every tick, against the command and so against each other.
//!
//! ISO 13849-1 6.2.6 (category 3) asks that a single fault does not lose the safety function and is
//! detected at or before the next demand. The stop has two channels (K1, K2, `stop_output.rs`), the
//! category-0 escalation a third path; what can fail in each and what sees it:
//!
//! | fault | seen by | when |
//! |---|---|---|
//! | a pin (or its driver) stuck high while commanded low | the pin read-back (IDR reads high) | the next tick: a healthy pin follows its output register within nanoseconds |
//! | a pin stuck low, a frozen port (clock gated: writes lost, the register reads a constant) while commanded high | the pin read-back (reads low) | the second consecutive tick: the first sighting may be the board's edge handler, which writes the stop before the bookkeeping tells the library |
//! | a relay welded, stuck, or its feedback wire cut or shorted | EDM: each relay must follow its stop channel within `Config::edm_settle_us` | the relay's release time (the settle time) plus a tick, and before every arming (the start check) |
//! | a read error on any of them | the read itself | the next tick |
//!
//! Each ends in a latched fault ([`Cause::OutputReadBack`], [`Cause::EdmMismatch`]) whose event
//! flags name the channels ([`FLAG_K1`], [`FLAG_K2`], [`FLAG_ESC`]): every output is dropped, the
//! board stops feeding its watchdog (`Firmware::feeds_watchdog`), so the reset that follows
//! releases even a pin that its own port no longer obeys, and the next start finds the latch.
//!
//! [`Cause::OutputReadBack`]: crate::Cause::OutputReadBack
//! [`Cause::EdmMismatch`]: crate::Cause::EdmMismatch

use crate::clock::Micros;
use crate::edm::Reading;
use crate::event_log::{Cause, FLAG_ESC, FLAG_K1, FLAG_K2};
use crate::stop_output::PinLevels;

/// What the outputs were last commanded to.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct Commanded {
    /// Both stop channels energised (high).
    pub stop_energised: bool,
    /// The escalation output energised (high: no category 0).
    pub escalation_energised: bool,
}

/// A latched finding: the cause and the `FLAG_K1`/`FLAG_K2`/`FLAG_ESC` bits of the channels.
pub type Finding = (Cause, u8);

/// The monitor's state between ticks.
#[derive(Copy, Clone, Debug, Default)]
pub struct OutputMonitor {
    /// Channels (`FLAG_*` bits) that read low while commanded high at the previous check.
    low_seen: u8,
    /// Since when the relays disagree with the stop channels.
    edm_since: Option<Micros>,
}

impl OutputMonitor {
    /// A monitor with nothing seen yet.
    pub const fn new() -> Self {
        OutputMonitor { low_seen: 0, edm_since: None }
    }

    /// Forget what was seen (after the outputs were re-commanded by arming).
    pub fn restart(&mut self) {
        self.low_seen = 0;
        self.edm_since = None;
    }

    /// One check at `now`: the pins as read back, the relays as read back, the command; `settle_us`
    /// is the relays' time to follow. `Err` is a fault to latch.
    pub fn check(&mut self, now: Micros, cmd: Commanded, pins: PinLevels, relays: Reading, settle_us: u32) -> Result<(), Finding> {
        self.check_pins(cmd, pins)?;
        self.check_relays(now, cmd.stop_energised, relays, settle_us)
    }

    fn check_pins(&mut self, cmd: Commanded, pins: PinLevels) -> Result<(), Finding> {
        let mut stuck_high = 0u8;
        let mut low_now = 0u8;
        for (flag, level, want) in [
            (FLAG_K1, pins.k1, cmd.stop_energised),
            (FLAG_K2, pins.k2, cmd.stop_energised),
            (FLAG_ESC, pins.escalation, cmd.escalation_energised),
        ] {
            match level {
                // A read error, or high while commanded low: the output may be energised against
                // the command, now.
                None => stuck_high |= flag,
                Some(true) if !want => stuck_high |= flag,
                Some(false) if want => low_now |= flag,
                Some(_) => {}
            }
        }
        if stuck_high != 0 {
            return Err((Cause::OutputReadBack, stuck_high));
        }
        let twice = low_now & self.low_seen;
        self.low_seen = low_now;
        if twice != 0 {
            return Err((Cause::OutputReadBack, twice));
        }
        Ok(())
    }

    fn check_relays(&mut self, now: Micros, stop_energised: bool, relays: Reading, settle_us: u32) -> Result<(), Finding> {
        let want_released = !stop_energised;
        let wrong = match relays {
            Reading::NotMonitored => return Ok(()),
            Reading::Released(a, b) => {
                (if a != want_released { FLAG_K1 } else { 0 }) | (if b != want_released { FLAG_K2 } else { 0 })
            }
            Reading::Error => FLAG_K1 | FLAG_K2,
        };
        if wrong == 0 {
            self.edm_since = None;
            return Ok(());
        }
        let since = *self.edm_since.get_or_insert(now);
        if now.since(since) > settle_us {
            return Err((Cause::EdmMismatch, wrong));
        }
        Ok(())
    }

    /// The EDM start check: both relays released (or no read-back) before the outputs are energised.
    pub fn relays_released(relays: Reading) -> Result<(), Finding> {
        match relays {
            Reading::NotMonitored | Reading::Released(true, true) => Ok(()),
            Reading::Released(a, b) => Err((Cause::EdmMismatch, (if a { 0 } else { FLAG_K1 }) | (if b { 0 } else { FLAG_K2 }))),
            Reading::Error => Err((Cause::EdmMismatch, FLAG_K1 | FLAG_K2)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GO: Commanded = Commanded { stop_energised: true, escalation_energised: true };
    const STOP: Commanded = Commanded { stop_energised: false, escalation_energised: true };
    const CAT0: Commanded = Commanded { stop_energised: false, escalation_energised: false };
    fn pins(k1: bool, k2: bool, esc: bool) -> PinLevels {
        PinLevels { k1: Some(k1), k2: Some(k2), escalation: Some(esc) }
    }

    #[test]
    fn a_stuck_high_pin_is_a_fault_at_once_and_names_its_channel() {
        let mut m = OutputMonitor::new();
        let r = Reading::NotMonitored;
        assert_eq!(m.check(Micros(0), STOP, pins(false, false, true), r, 20_000), Ok(()));
        assert_eq!(m.check(Micros(1), STOP, pins(true, false, true), r, 20_000), Err((Cause::OutputReadBack, FLAG_K1)));
        assert_eq!(m.check(Micros(1), STOP, pins(false, true, true), r, 20_000), Err((Cause::OutputReadBack, FLAG_K2)));
        assert_eq!(m.check(Micros(1), CAT0, pins(false, false, true), r, 20_000), Err((Cause::OutputReadBack, FLAG_ESC)));
        let err = PinLevels { k1: Some(false), k2: None, escalation: Some(true) };
        assert_eq!(m.check(Micros(1), STOP, err, r, 20_000), Err((Cause::OutputReadBack, FLAG_K2)));
    }

    #[test]
    fn a_pin_low_while_commanded_high_is_a_fault_on_its_second_sighting_only() {
        let mut m = OutputMonitor::new();
        let r = Reading::NotMonitored;
        // Once: the board's edge handler wrote the stop before the bookkeeping told the library.
        assert_eq!(m.check(Micros(0), GO, pins(false, false, true), r, 20_000), Ok(()));
        assert_eq!(m.check(Micros(1_000), STOP, pins(false, false, true), r, 20_000), Ok(()));
        // Twice in a row: a frozen port or a pin stuck low.
        assert_eq!(m.check(Micros(2_000), GO, pins(true, false, true), r, 20_000), Ok(()));
        assert_eq!(m.check(Micros(3_000), GO, pins(true, false, true), r, 20_000), Err((Cause::OutputReadBack, FLAG_K2)));
        // Sightings that are not consecutive are not added up.
        let mut m = OutputMonitor::new();
        for k in 0..10u32 {
            let p = if k % 2 == 0 { pins(false, true, true) } else { pins(true, true, true) };
            assert_eq!(m.check(Micros(k * 1_000), GO, p, r, 20_000), Ok(()), "{k}");
        }
    }

    #[test]
    fn a_relay_that_does_not_follow_is_a_fault_after_the_settle_time() {
        let mut m = OutputMonitor::new();
        let p = pins(false, false, true);
        // K2 welded: its mirror contact never reads released.
        for t in (0..=20_000).step_by(1_000) {
            assert_eq!(m.check(Micros(t), STOP, p, Reading::Released(true, false), 20_000), Ok(()), "{t}");
        }
        assert_eq!(m.check(Micros(21_000), STOP, p, Reading::Released(true, false), 20_000), Err((Cause::EdmMismatch, FLAG_K2)));
        // Both welded.
        let mut m = OutputMonitor::new();
        assert_eq!(m.check(Micros(u32::MAX - 500), STOP, p, Reading::Released(false, false), 20_000), Ok(()));
        assert_eq!(m.check(Micros(20_000), STOP, p, Reading::Released(false, false), 20_000), Err((Cause::EdmMismatch, FLAG_K1 | FLAG_K2)), "across the wrap");
        assert_eq!(OutputMonitor::relays_released(Reading::Released(false, true)), Err((Cause::EdmMismatch, FLAG_K1)));
        assert_eq!(OutputMonitor::relays_released(Reading::Released(true, true)), Ok(()));
    }
}
