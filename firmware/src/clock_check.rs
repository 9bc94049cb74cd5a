//! Clock plausibility: the firmware's time base checked against an independent oscillator.
//!
//! Every time the firmware measures (tick deadline, filter, discrepancy, EDM settle, reset press) is
//! read from one counter ([`Clock`](crate::Clock)). If its oscillator runs fast or slow, every one of
//! those intervals is wrong by the same factor and the tick supervision cannot see it, because the
//! tick (SysTick) and the counter (TIM2) share the oscillator on the board (the HSI). ISO 13849-1
//! Table E.1 lists "independent time base" monitoring for the logic; so the clock offers a second,
//! independent count ([`Clock::reference_ticks`](crate::Clock::reference_ticks): the LSI, an HSE or
//! an RTC crystal), and every `window_us` of firmware time the reference must have advanced by the
//! expected count within `tolerance_pct`, or the firmware latches
//! [`Cause::ClockDrift`](crate::Cause::ClockDrift). The firmware does not arm before the first window
//! has passed, so early ticks are checked too. A configured check with no reference is the same fault.
//! All differences are wrapping (`u32`), so both counters may wrap at any time.

use crate::clock::Micros;
use crate::event_log::Cause;

/// What to check the clock against.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct ClockCheck {
    /// Nominal frequency of the reference counter, hertz.
    pub reference_hz: u32,
    /// Length of one comparison window in firmware time, microseconds (well below 2^31).
    pub window_us: u32,
    /// Allowed deviation of the reference count from the expected one, percent (the reference's
    /// own tolerance plus the main clock's: the F4's LSI is specified only to about +-50 %).
    pub tolerance_pct: u8,
}

/// State of the clock check.
#[derive(Copy, Clone, Debug)]
pub struct ClockMonitor {
    cfg: Option<ClockCheck>,
    start: Option<(Micros, u32)>,
    passed: bool,
}

impl ClockMonitor {
    /// A monitor for `cfg` (`None`: no check, always plausible).
    pub const fn new(cfg: Option<ClockCheck>) -> Self {
        ClockMonitor { cfg, start: None, passed: cfg.is_none() }
    }

    /// At least one window has passed (or no check is configured): the firmware may arm.
    pub const fn passed(&self) -> bool {
        self.passed
    }

    /// Feed the firmware's time and the reference count at one tick.
    pub fn check(&mut self, now: Micros, reference: Option<u32>) -> Result<(), Cause> {
        let Some(cfg) = self.cfg else { return Ok(()) };
        let Some(r) = reference else { return Err(Cause::ClockDrift) };
        let Some((t0, r0)) = self.start else {
            self.start = Some((now, r));
            return Ok(());
        };
        let dt = now.since(t0);
        if dt < cfg.window_us {
            return Ok(());
        }
        self.start = Some((now, r));
        let counted = u64::from(r.wrapping_sub(r0));
        let expected = u64::from(dt).saturating_mul(u64::from(cfg.reference_hz)) / 1_000_000;
        let margin = expected.saturating_mul(u64::from(cfg.tolerance_pct)) / 100;
        if counted < expected.saturating_sub(margin) || counted > expected.saturating_add(margin) {
            return Err(Cause::ClockDrift);
        }
        self.passed = true;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CHECK: ClockCheck = ClockCheck { reference_hz: 32_000, window_us: 100_000, tolerance_pct: 10 };

    fn run(main_per_tick_us: u32, ref_per_tick: u32, start: (u32, u32)) -> Result<bool, Cause> {
        let mut m = ClockMonitor::new(Some(CHECK));
        let (mut t, mut r) = start;
        for _ in 0..500 {
            m.check(Micros(t), Some(r))?;
            t = t.wrapping_add(main_per_tick_us);
            r = r.wrapping_add(ref_per_tick);
        }
        Ok(m.passed())
    }

    #[test]
    fn matching_clocks_pass_across_both_wraps() {
        // 1 ms ticks, 32 reference counts per ms.
        assert_eq!(run(1_000, 32, (u32::MAX - 150_000, u32::MAX - 1_000)), Ok(true));
    }

    #[test]
    fn a_main_clock_off_by_more_than_the_tolerance_is_a_fault() {
        // The main oscillator runs 20 % slow: 1 ms of firmware time is 1.2 ms of real time, in which
        // the reference counts 38.4.
        assert_eq!(run(1_000, 38, (0, 0)), Err(Cause::ClockDrift));
        assert_eq!(run(1_000, 26, (0, 0)), Err(Cause::ClockDrift), "20 % fast");
        assert_eq!(run(1_000, 34, (0, 0)), Ok(true), "6 % is within 10 %");
    }

    #[test]
    fn a_missing_or_dead_reference_is_a_fault_and_nothing_passes_before_a_window() {
        let mut m = ClockMonitor::new(Some(CHECK));
        assert_eq!(m.check(Micros(0), None), Err(Cause::ClockDrift));
        let mut m = ClockMonitor::new(Some(CHECK));
        assert_eq!(m.check(Micros(0), Some(5)), Ok(()));
        assert!(!m.passed(), "early ticks: not yet checked");
        assert_eq!(m.check(Micros(100_000), Some(5)), Err(Cause::ClockDrift), "reference stopped");
        assert!(ClockMonitor::new(None).passed());
    }
}
