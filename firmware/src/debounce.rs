//! Glitch filter and chatter guard for the sensor input.
//!
//! A single bounce of the travel switch must not stop the robot, but every microsecond of filtering
//! is added to the dead time between contact and braking (MODEL.md "Controller"). So the filter is a
//! configuration choice with its price stated:
//!
//! | [`Filter`]             | confirmed at                                  | added latency vs. no filter     |
//! |------------------------|-----------------------------------------------|---------------------------------|
//! | `None`                 | the edge interrupt (or the next tick)         | 0                               |
//! | `Consecutive(n)`       | the n-th consecutive tripped tick sample      | (n-1)·T exactly (T: tick period) on top of tick polling, i.e. [(n-1)·T, n·T) after the edge |
//! | `MinDuration(d)`       | the first tick at least d after the edge      | [d, d + T) after the edge       |
//!
//! The bounds are asserted by `tests::latency_*` below, and over many phases by the firmware tests.
//! `MinDuration` takes its start from the edge interrupt's timestamp, so it is not quantised to ticks
//! at the start; `Consecutive` sees only tick samples.
//!
//! The [`ChatterGuard`] is the other half: an input that keeps toggling (a loose connector, a switch
//! sitting exactly on its switching travel) never passes the filter, so instead of waiting for it the
//! guard counts level changes in a window and declares a fault, which stops the robot.

use crate::clock::Micros;

/// Glitch filter applied before a trip is confirmed.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Filter {
    /// No filtering: the edge interrupt stops the robot directly (the short path).
    None,
    /// Confirm after this many consecutive tripped tick samples (>= 1).
    Consecutive(u8),
    /// Confirm once the input has shown a trip continuously for at least this many microseconds.
    MinDuration(u32),
}

impl Filter {
    /// Worst-case latency the filter adds to detection, microseconds, for tick period `tick_us`
    /// (the upper ends of the table in the module docs, saturating).
    pub const fn max_added_latency_us(self, tick_us: u32) -> u32 {
        match self {
            Filter::None => 0,
            Filter::Consecutive(n) => (n as u32).saturating_mul(tick_us),
            Filter::MinDuration(d) => d.saturating_add(tick_us),
        }
    }
}

/// The state of a [`Filter`].
#[derive(Copy, Clone, Debug)]
pub struct Debouncer {
    filter: Filter,
    count: u8,
    since: Option<Micros>,
}

impl Debouncer {
    /// A filter in its idle state.
    pub const fn new(filter: Filter) -> Self {
        Debouncer { filter, count: 0, since: None }
    }

    /// The configured filter.
    pub const fn filter(&self) -> Filter {
        self.filter
    }

    /// Forget any partial confirmation.
    pub fn clear(&mut self) {
        self.count = 0;
        self.since = None;
    }

    /// When the input was first seen tripped in the current run, if it is.
    pub const fn first_seen(&self) -> Option<Micros> {
        self.since
    }

    /// Record an edge seen by the interrupt at `now`; `trip` is the level after the edge.
    pub fn note_edge(&mut self, now: Micros, trip: bool) {
        if trip {
            if self.since.is_none() {
                self.since = Some(now);
            }
        } else {
            self.clear();
        }
    }

    /// Feed one tick sample; returns `true` when the trip is confirmed.
    pub fn update(&mut self, now: Micros, trip: bool) -> bool {
        if !trip {
            self.clear();
            return false;
        }
        let since = *self.since.get_or_insert(now);
        self.count = self.count.saturating_add(1);
        match self.filter {
            Filter::None => true,
            Filter::Consecutive(n) => self.count >= n.max(1),
            Filter::MinDuration(d) => now.since(since) >= d,
        }
    }
}

/// Declares a fault when the raw input changes level more than `max_transitions` times within
/// `window_us`.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct ChatterGuard {
    /// Level changes tolerated within one window.
    pub max_transitions: u8,
    /// Window length, microseconds.
    pub window_us: u32,
}

/// The state of a [`ChatterGuard`].
#[derive(Copy, Clone, Debug)]
pub struct ChatterState {
    guard: Option<ChatterGuard>,
    last: Option<bool>,
    window_start: Micros,
    count: u8,
}

impl ChatterState {
    /// A guard that has seen nothing yet; `None` disables it.
    pub const fn new(guard: Option<ChatterGuard>) -> Self {
        ChatterState { guard, last: None, window_start: Micros(0), count: 0 }
    }

    /// Observe the raw level at `now`; returns `true` when the input is chattering.
    pub fn observe(&mut self, now: Micros, level: bool) -> bool {
        let Some(g) = self.guard else { return false };
        let changed = matches!(self.last, Some(l) if l != level);
        self.last = Some(level);
        if !changed {
            return false;
        }
        if self.count == 0 || now.since(self.window_start) > g.window_us {
            self.window_start = now;
            self.count = 1;
        } else {
            self.count = self.count.saturating_add(1);
        }
        self.count > g.max_transitions
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Drive a filter with an input that steps to "trip" at `edge_us` (edge interrupt included when
    /// `with_edge`), sampled every `tick_us` starting at `phase_us`; return the confirmation instant.
    fn confirm_time(filter: Filter, tick_us: u32, phase_us: u32, edge_us: u32, with_edge: bool) -> u32 {
        let mut d = Debouncer::new(filter);
        let mut edge_seen = !with_edge;
        let mut t = phase_us;
        for _ in 0..10_000 {
            // The edge interrupt runs at the edge, i.e. between the last tick before it and this one.
            if !edge_seen && t >= edge_us {
                d.note_edge(Micros(edge_us), true);
                edge_seen = true;
            }
            if d.update(Micros(t), t >= edge_us) {
                return t;
            }
            t += tick_us;
        }
        panic!("never confirmed");
    }

    #[test]
    fn latency_consecutive_is_n_minus_one_ticks_after_the_first_sample() {
        let tick = 1000;
        for n in 1..=5u8 {
            for phase in (0..tick).step_by(37) {
                let edge = 10_000 + 13;
                let unfiltered = confirm_time(Filter::None, tick, phase, edge, false);
                let filtered = confirm_time(Filter::Consecutive(n), tick, phase, edge, false);
                assert_eq!(filtered - unfiltered, u32::from(n - 1) * tick);
                let lat = filtered - edge;
                assert!(lat >= u32::from(n - 1) * tick && lat < u32::from(n) * tick, "n={n} lat={lat}");
                assert!(lat <= Filter::Consecutive(n).max_added_latency_us(tick));
            }
        }
    }

    #[test]
    fn latency_min_duration_is_d_to_d_plus_tick() {
        let tick = 500;
        for d_us in [0u32, 200, 1000, 2750] {
            for phase in (0..tick).step_by(23) {
                let edge = 5_000 + 7;
                let lat = confirm_time(Filter::MinDuration(d_us), tick, phase, edge, true) - edge;
                assert!(lat >= d_us && lat < d_us + tick, "d={d_us} lat={lat}");
                assert!(lat <= Filter::MinDuration(d_us).max_added_latency_us(tick));
            }
        }
    }

    #[test]
    fn a_glitch_shorter_than_the_filter_is_rejected() {
        let mut d = Debouncer::new(Filter::Consecutive(3));
        assert!(!d.update(Micros(0), true));
        assert!(!d.update(Micros(100), true));
        assert!(!d.update(Micros(200), false)); // bounce back: restart
        assert!(!d.update(Micros(300), true));
        assert!(!d.update(Micros(400), true));
        assert!(d.update(Micros(500), true));

        let mut d = Debouncer::new(Filter::MinDuration(1000));
        d.note_edge(Micros(0), true);
        d.note_edge(Micros(400), false); // 400 us glitch
        assert!(!d.update(Micros(1000), false));
        assert!(d.first_seen().is_none());
    }

    #[test]
    fn min_duration_works_across_the_wrap() {
        let mut d = Debouncer::new(Filter::MinDuration(1000));
        let edge = Micros(u32::MAX - 300);
        d.note_edge(edge, true);
        assert!(!d.update(edge.plus(999), true));
        assert!(d.update(edge.plus(1000), true));
    }

    #[test]
    fn chatter_guard_fires_on_too_many_changes_in_the_window() {
        let mut c = ChatterState::new(Some(ChatterGuard { max_transitions: 4, window_us: 10_000 }));
        let mut level = true;
        let mut fired_at = None;
        for k in 0..20u32 {
            level = !level;
            if c.observe(Micros(k * 1000), level) {
                fired_at = Some(k);
                break;
            }
        }
        // The first sample only sets the reference level... every later one is a change: the 5th
        // change comes at k = 5.
        assert_eq!(fired_at, Some(5));
    }

    #[test]
    fn chatter_guard_tolerates_slow_changes() {
        let mut c = ChatterState::new(Some(ChatterGuard { max_transitions: 2, window_us: 1000 }));
        let mut level = true;
        for k in 0..50u32 {
            level = !level;
            assert!(!c.observe(Micros(k * 5000), level));
        }
        assert!(!ChatterState::new(None).observe(Micros(0), true));
    }
}
