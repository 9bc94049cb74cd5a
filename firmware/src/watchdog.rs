//! Software watchdog over the tick: a stopped clock or a missed tick deadline ends in stop.
//!
//! The tick is driven by a periodic interrupt (SysTick on the board) and time is read from a separate
//! free-running counter (TIM2), so the two check each other:
//!
//! * **clock stall**: `stall_ticks` consecutive ticks that read the same instant mean the counter
//!   stopped (a dead timer clock, a simulation clock that froze). A healthy 1 MHz counter advances by
//!   the tick period between ticks.
//! * **missed deadline**: a tick that comes more than `period + slack` after the previous one means the
//!   firmware was blocked (or the clock jumped, forwards or backwards: a backwards jump shows up as a
//!   wrapping difference near 2^32). With `slack < period` a single missed tick is caught.
//!
//! Either one latches a fault, which de-energises both outputs. What this cannot see is a firmware
//! that no longer ticks at all: that is the hardware independent watchdog's job on the board (IWDG,
//! fed from the main loop only while [`Firmware::is_healthy`](crate::Firmware::is_healthy)).

use crate::clock::Micros;
use crate::event_log::Cause;

/// Tick supervision state.
#[derive(Copy, Clone, Debug)]
pub struct Watchdog {
    period_us: u32,
    slack_us: u32,
    stall_ticks: u8,
    stalls: u8,
    last: Option<Micros>,
}

impl Watchdog {
    /// Supervise ticks of `period_us`, tolerating `slack_us` of lateness and `stall_ticks - 1` repeated
    /// instants.
    pub const fn new(period_us: u32, slack_us: u32, stall_ticks: u8) -> Self {
        Watchdog { period_us, slack_us, stall_ticks, stalls: 0, last: None }
    }

    /// Forget the previous tick (after a restart of the self-test).
    pub fn restart(&mut self) {
        self.last = None;
        self.stalls = 0;
    }

    /// Check the tick at `now`.
    pub fn check(&mut self, now: Micros) -> Result<(), Cause> {
        let Some(last) = self.last.replace(now) else { return Ok(()) };
        let dt = now.since(last);
        if dt == 0 {
            self.stalls = self.stalls.saturating_add(1);
            if self.stalls >= self.stall_ticks.max(1) {
                return Err(Cause::ClockStall);
            }
            return Ok(());
        }
        self.stalls = 0;
        if dt > self.period_us.saturating_add(self.slack_us) {
            return Err(Cause::MissedDeadline);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regular_ticks_pass_across_the_wrap() {
        let mut w = Watchdog::new(1000, 500, 1);
        let mut t = Micros(u32::MAX - 5_500);
        for _ in 0..20 {
            assert_eq!(w.check(t), Ok(()));
            t = t.plus(1000);
        }
    }

    #[test]
    fn a_frozen_clock_is_a_stall() {
        let mut w = Watchdog::new(1000, 500, 2);
        assert_eq!(w.check(Micros(0)), Ok(()));
        assert_eq!(w.check(Micros(1000)), Ok(()));
        assert_eq!(w.check(Micros(1000)), Ok(())); // one repeat tolerated with stall_ticks = 2
        assert_eq!(w.check(Micros(1000)), Err(Cause::ClockStall));
    }

    #[test]
    fn one_missed_tick_is_caught() {
        let mut w = Watchdog::new(1000, 500, 1);
        assert_eq!(w.check(Micros(0)), Ok(()));
        assert_eq!(w.check(Micros(1500)), Ok(())); // late but within slack
        assert_eq!(w.check(Micros(3500)), Err(Cause::MissedDeadline)); // the tick at 2500 was missed
    }

    #[test]
    fn a_clock_that_jumps_back_is_caught() {
        let mut w = Watchdog::new(1000, 500, 1);
        assert_eq!(w.check(Micros(10_000)), Ok(()));
        assert_eq!(w.check(Micros(9_000)), Err(Cause::MissedDeadline));
    }
}
