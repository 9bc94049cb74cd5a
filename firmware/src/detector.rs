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
    /// A rising edge on the reset input (operator button or the robot controller), taken while the
    /// tool is back on the front stop.
    Input,
    /// Automatically, once the tool has been back on the front stop (sensor not tripped) continuously
    /// for `hold_us` microseconds.
    Auto {
        /// Required time on the front stop, microseconds.
        hold_us: u32,
    },
}

/// Reset bookkeeping while tripped.
#[derive(Copy, Clone, Debug, Default)]
pub struct ResetTracker {
    reset_prev: bool,
    at_rest_since: Option<Micros>,
}

impl ResetTracker {
    /// Feed one tick while tripped; returns `true` when the trip may be cleared. `trip` is the sensor
    /// reading, `reset_level` the reset input's level.
    pub fn tripped_tick(&mut self, policy: ResetPolicy, now: Micros, trip: bool, reset_level: bool) -> bool {
        let rising = reset_level && !self.reset_prev;
        self.reset_prev = reset_level;
        if trip {
            self.at_rest_since = None;
            return false;
        }
        let since = *self.at_rest_since.get_or_insert(now);
        match policy {
            ResetPolicy::Input => rising,
            ResetPolicy::Auto { hold_us } => now.since(since) >= hold_us,
        }
    }

    /// A trip just happened: restart the rest timer, keep the reset input's last level (a button held
    /// down before the trip is not a new press).
    pub fn begin_trip(&mut self) {
        self.at_rest_since = None;
    }

    /// Feed one tick while faulted; returns `true` on a rising edge of the reset input.
    pub fn fault_tick(&mut self, reset_level: bool) -> bool {
        let rising = reset_level && !self.reset_prev;
        self.reset_prev = reset_level;
        rising
    }

    /// Track the reset input outside of tripped/fault states (so a button held while arming is not
    /// taken as a new press later), and forget the rest timer.
    pub fn idle_tick(&mut self, reset_level: bool) {
        self.reset_prev = reset_level;
        self.at_rest_since = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn input_policy_needs_a_rising_edge_with_the_tool_at_rest() {
        let mut r = ResetTracker::default();
        let p = ResetPolicy::Input;
        assert!(!r.tripped_tick(p, Micros(0), true, true)); // pressed while still tripped: ignored
        assert!(!r.tripped_tick(p, Micros(1), false, true)); // still held: no new edge
        assert!(!r.tripped_tick(p, Micros(2), false, false));
        assert!(r.tripped_tick(p, Micros(3), false, true));
    }

    #[test]
    fn auto_policy_needs_a_continuous_hold_even_across_the_wrap() {
        let mut r = ResetTracker::default();
        let p = ResetPolicy::Auto { hold_us: 1000 };
        let t0 = Micros(u32::MAX - 400);
        assert!(!r.tripped_tick(p, t0, false, false));
        assert!(!r.tripped_tick(p, t0.plus(600), true, false)); // bounced back: restart the hold
        assert!(!r.tripped_tick(p, t0.plus(700), false, false));
        assert!(!r.tripped_tick(p, t0.plus(1699), false, false));
        assert!(r.tripped_tick(p, t0.plus(1700), false, false));
    }
}
