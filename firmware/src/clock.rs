//! Monotonic time in microseconds, wrap-safe.
//!
//! The firmware counts time as a free-running `u32` of microseconds ([`Micros`]). It wraps every
//! 2^32 us = 71.58 min, so no code ever compares two instants with `<`: it takes the wrapping
//! difference ([`Micros::since`]), which is exact for any two instants less than 2^31 us (35.79 min)
//! apart. Every interval the firmware measures (tick period, filter window, reset hold time, self-test
//! settle time) is far shorter than that.
//!
//! On the board the clock is a 32-bit timer at 1 MHz (TIM2 on the STM32F407); in `flinch hil` it is
//! `flinch_hal_sim::SimClock`, whose value is the plant's simulation time.

/// An instant, in microseconds of a free-running `u32` counter that wraps.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(all(feature = "defmt", target_os = "none"), derive(defmt::Format))]
pub struct Micros(pub u32);

impl Micros {
    /// Microseconds elapsed from `earlier` to `self`, modulo 2^32.
    ///
    /// Exact across the wrap as long as the true interval is below 2^31 us; a result of 2^31 or more
    /// means `earlier` is really in the future (see [`Micros::is_before`]).
    #[inline(always)]
    pub const fn since(self, earlier: Micros) -> u32 {
        self.0.wrapping_sub(earlier.0)
    }

    /// `self + us`, wrapping.
    #[inline(always)]
    pub const fn plus(self, us: u32) -> Micros {
        Micros(self.0.wrapping_add(us))
    }

    /// True when `self` is strictly before `other`, judged by the sign of the wrapping difference
    /// (valid for instants less than 2^31 us apart).
    #[inline(always)]
    pub const fn is_before(self, other: Micros) -> bool {
        let d = other.0.wrapping_sub(self.0);
        d != 0 && d < (1 << 31)
    }
}

/// A monotonic microsecond clock.
///
/// Implementations must count up at 1 MHz and wrap at 2^32. They must not block and must not fail:
/// a clock that stops is caught by the firmware's watchdog (`watchdog.rs`), not by an error value.
pub trait Clock {
    /// The current instant.
    fn now(&mut self) -> Micros;

    /// A wrapping count of an oscillator independent of the one behind [`Clock::now`] (LSI, HSE,
    /// RTC crystal), for the plausibility check of `clock_check.rs`; `None` if there is none.
    fn reference_ticks(&mut self) -> Option<u32> {
        None
    }
}

impl<C: Clock + ?Sized> Clock for &mut C {
    #[inline(always)]
    fn now(&mut self) -> Micros {
        (**self).now()
    }
    #[inline(always)]
    fn reference_ticks(&mut self) -> Option<u32> {
        (**self).reference_ticks()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn since_is_exact_across_the_wrap() {
        let before = Micros(u32::MAX - 9); // 10 us before the wrap
        let after = Micros(5); // 5 us after it
        assert_eq!(after.since(before), 15);
        assert_eq!(before.plus(15), after);
        assert!(before.is_before(after));
        assert!(!after.is_before(before));
        assert!(!after.is_before(after));
    }

    #[test]
    fn ordering_holds_up_to_half_the_range() {
        let a = Micros(u32::MAX - 100);
        assert!(a.is_before(a.plus((1 << 31) - 1)));
        // At exactly half the range the order is ambiguous; the firmware never gets near it.
        assert!(!a.is_before(a.plus(1 << 31)));
    }
}
