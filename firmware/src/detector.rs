//! Detection state machine: self-test, armed, tripped (latched), fault (latched), and the reset policy.
//!
//! ```text
//!            self-test passes             trip confirmed
//!  SelfTest ------------------> Armed ------------------> Tripped
//!     ^   \                      ^  |                        |
//!     |    \ stuck input         |  | watchdog, chatter,     | reset policy met and the
//!     |     v                    |  v sensor or output fault | tool back on the front stop
//!     +--- Fault <---------------+--+------------------------+
//!   reset input                  +-------- re-arm ------------+
//! ```
//!
//! Trips latch: the stop output stays de-energised until the [`ResetPolicy`] allows re-arming, and it
//! never re-arms while the sensor still reads a trip. Faults latch harder: only the reset input clears
//! them, and clearing one re-runs the self-test; [`ResetPolicy::Auto`] never clears a fault.

use crate::clock::Micros;
use crate::event_log::Cause;
use crate::reset::{ResetButton, ResetPress};
use crate::selftest::Phase;

/// The detector's state.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum State {
    /// Start-up self-test in progress (stop de-energised).
    SelfTest(Phase),
    /// Watching the sensor (stop energised).
    Armed,
    /// A collision was detected; stop de-energised until reset.
    Tripped,
    /// A fault was detected; both outputs de-energised until the reset input.
    Fault(Cause),
}

/// How a trip is cleared.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum ResetPolicy {
    /// A deliberate press and release of the reset input (operator button or the robot controller),
    /// acting on the release (ISO 13849-1 5.2.2), taken while the tool is back on the front stop.
    Input,
    /// Automatically, once the tool has been back on the front stop (sensor not tripped) continuously
    /// for `hold_us` microseconds.
    Auto {
        /// Required time on the front stop, microseconds.
        hold_us: u32,
    },
}

/// Reset bookkeeping while tripped or faulted.
#[derive(Copy, Clone, Debug, Default)]
pub struct ResetTracker {
    button: ResetButton,
    at_rest_since: Option<Micros>,
}

impl ResetTracker {
    /// Feed one tick while tripped; returns `true` when the trip may be cleared. `trip` is the sensor
    /// reading, `reset_level` the reset input's level. With [`ResetPolicy::Input`] the trip clears on
    /// the release of a press that began after the trip ([`ResetButton`]), with the tool back on the
    /// front stop at that instant.
    pub fn tripped_tick(
        &mut self,
        policy: ResetPolicy,
        press: ResetPress,
        now: Micros,
        trip: bool,
        reset_level: bool,
    ) -> bool {
        let released = self.button.released(press, now, reset_level);
        if trip {
            self.at_rest_since = None;
            return false;
        }
        let since = *self.at_rest_since.get_or_insert(now);
        match policy {
            ResetPolicy::Input => released,
            ResetPolicy::Auto { hold_us } => now.since(since) >= hold_us,
        }
    }

    /// A trip or a fault just latched: restart the rest timer and forget a press in progress (a
    /// button pressed or held before the latch is not a reset).
    pub fn begin_latch(&mut self) {
        self.at_rest_since = None;
        self.button.cancel();
    }

    /// Feed one tick while faulted (or latched after a reset); returns `true` on the release of a
    /// deliberate press ([`ResetButton`]).
    pub fn fault_tick(&mut self, press: ResetPress, now: Micros, reset_level: bool) -> bool {
        self.button.released(press, now, reset_level)
    }

    /// Track the reset input outside of tripped/fault states (so a button held while arming is not
    /// taken as a new press later), and forget the rest timer.
    pub fn idle_tick(&mut self, reset_level: bool) {
        self.button.track(reset_level);
        self.at_rest_since = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn input_policy_acts_on_release_with_the_tool_at_rest() {
        let mut r = ResetTracker::default();
        let p = ResetPolicy::Input;
        let k = ResetPress { min_us: 10, max_us: 1_000 };
        r.idle_tick(true); // held when the trip came
        r.begin_latch();
        assert!(!r.tripped_tick(p, k, Micros(0), true, true));
        assert!(!r.tripped_tick(p, k, Micros(20), false, false), "release of a press older than the trip");
        assert!(!r.tripped_tick(p, k, Micros(30), true, true)); // pressed while still tripped
        assert!(!r.tripped_tick(p, k, Micros(50), true, false), "released while still tripped: ignored");
        assert!(!r.tripped_tick(p, k, Micros(60), false, true), "pressing does not reset");
        assert!(!r.tripped_tick(p, k, Micros(65), false, true));
        assert!(r.tripped_tick(p, k, Micros(70), false, false), "the release does");
    }

    #[test]
    fn auto_policy_needs_a_continuous_hold_even_across_the_wrap() {
        let mut r = ResetTracker::default();
        let p = ResetPolicy::Auto { hold_us: 1000 };
        let t0 = Micros(u32::MAX - 400);
        let k = ResetPress::DEFAULT;
        assert!(!r.tripped_tick(p, k, t0, false, false));
        assert!(!r.tripped_tick(p, k, t0.plus(600), true, false)); // bounced back: restart the hold
        assert!(!r.tripped_tick(p, k, t0.plus(700), false, false));
        assert!(!r.tripped_tick(p, k, t0.plus(1699), false, false));
        assert!(r.tripped_tick(p, k, t0.plus(1700), false, false));
    }
}
