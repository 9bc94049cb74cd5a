//! [`DualSwitch`]: a two-channel travel switch with cross-monitoring and a discrepancy time.
//!
//! A single travel switch stuck at "rest" (a welded contact, a shorted sensor output, a sensor face
//! covered by swarf) is a dangerous undetected fault: the robot keeps its "go" through a collision.
//! The start-up supply pulse (`selftest.rs`) finds it only at the next start. ISO 13849-1 6.2.6
//! (category 3) asks that a single fault does not lose the safety function and is detected at or
//! before the next demand where reasonably practicable; this is the usual two-channel input of a
//! safety relay:
//!
//! * **1oo2 for the stop**: either channel showing a trip stops the robot (the edge interrupt reads
//!   both), so one channel stuck at rest does not lose the stop.
//! * **Discrepancy time**: the channels disagreeing for longer than `discrepancy_us` (the travel
//!   between their two switching points at the slowest closing speed, plus bounce) is a fault
//!   ([`Cause::Discrepancy`](crate::Cause::Discrepancy)): a channel stuck either way is found at the
//!   first demand that lasts longer than that.
//! * **Both channels must cycle**: after a trip the firmware re-arms only if both channels have
//!   shown the trip since it was armed; a trip shorter than the discrepancy time with one channel
//!   silent is a fault too. So a stuck channel is found at the first demand, however short.
//! * **Antivalent wiring** (one NC, one NO contact: [`SwitchKind`]s of opposite polarity) also turns a
//!   short between the two wires, or both inputs stuck at the same level, into a discrepancy while
//!   the tool is at rest, i.e. before any demand.
//!
//! What it does not cover: both channels failing the same way at once (a common cause: one connector,
//! one cable crushed); ISO 13849-1 Annex F scoring is the installer's. A channel read error is a trip
//! and a sensor fault, as for the single switch.

use crate::clock::Micros;
use crate::sensor::{Sample, Sensor, SwitchKind};
use embedded_hal::digital::{InputPin, OutputPin};

/// Two travel-switch channels on one tool, with an optional shared supply output.
#[derive(Debug)]
pub struct DualSwitch<A, B, Q = crate::pins::Unconnected> {
    a: A,
    b: B,
    supply: Q,
    has_supply: bool,
    a_trip_high: bool,
    b_trip_high: bool,
    switch_travel_um: i32,
    discrepancy_us: u32,
    disagree_since: Option<Micros>,
    seen_a: bool,
    seen_b: bool,
}

impl<A: InputPin, B: InputPin> DualSwitch<A, B, crate::pins::Unconnected> {
    /// Channels `a` (of `kind_a`) and `b` (of `kind_b`; opposite polarity for antivalent wiring),
    /// the travel at which the *later* of the two switches (`switch_travel_um`, d_sw) and the
    /// discrepancy time; no switchable supply (add one with [`DualSwitch::with_supply`]).
    pub fn new(a: A, kind_a: SwitchKind, b: B, kind_b: SwitchKind, switch_travel_um: i32, discrepancy_us: u32) -> Self {
        DualSwitch {
            a,
            b,
            supply: crate::pins::Unconnected,
            has_supply: false,
            a_trip_high: kind_a.trip_level_high(),
            b_trip_high: kind_b.trip_level_high(),
            switch_travel_um,
            discrepancy_us,
            disagree_since: None,
            seen_a: false,
            seen_b: false,
        }
    }

    /// The same channels on a supply the firmware can switch off (high = powered) for the start-up
    /// test. Wiring rule: both unpowered channels must read as a trip.
    pub fn with_supply<Q: OutputPin>(self, supply: Q) -> DualSwitch<A, B, Q> {
        DualSwitch {
            a: self.a,
            b: self.b,
            supply,
            has_supply: true,
            a_trip_high: self.a_trip_high,
            b_trip_high: self.b_trip_high,
            switch_travel_um: self.switch_travel_um,
            discrepancy_us: self.discrepancy_us,
            disagree_since: None,
            seen_a: false,
            seen_b: false,
        }
    }
}

impl<A: InputPin, B: InputPin, Q: OutputPin> DualSwitch<A, B, Q> {

    /// The discrepancy time, microseconds.
    pub const fn discrepancy_us(&self) -> u32 {
        self.discrepancy_us
    }

    /// Each channel's trip reading; a read error is a trip (and reported as a fault).
    #[inline(always)]
    fn read(&mut self) -> (bool, bool, bool) {
        let (ta, ea) = match self.a.is_high() {
            Ok(h) => (h == self.a_trip_high, false),
            Err(_) => (true, true),
        };
        let (tb, eb) = match self.b.is_high() {
            Ok(h) => (h == self.b_trip_high, false),
            Err(_) => (true, true),
        };
        (ta, tb, ea || eb)
    }
}

impl<A: InputPin, B: InputPin, Q: OutputPin> Sensor for DualSwitch<A, B, Q> {
    fn sample(&mut self, now: Micros) -> Sample {
        let (ta, tb, fault) = self.read();
        self.seen_a |= ta;
        self.seen_b |= tb;
        let discrepancy = if ta == tb {
            self.disagree_since = None;
            false
        } else {
            let since = *self.disagree_since.get_or_insert(now);
            now.since(since) > self.discrepancy_us
        };
        let trip = ta || tb;
        Sample {
            trip,
            travel_um: if trip { self.switch_travel_um } else { 0 },
            velocity_um_per_s: 0,
            fault,
            discrepancy,
        }
    }

    #[inline(always)]
    fn fast_trip(&mut self) -> bool {
        let (ta, tb, _) = self.read();
        // Remembered for `channels_cycled`: a trip shorter than a tick is seen only here.
        self.seen_a |= ta;
        self.seen_b |= tb;
        ta || tb
    }

    fn set_supply(&mut self, on: bool) -> bool {
        if !self.has_supply {
            return false;
        }
        let _ = if on { self.supply.set_high() } else { self.supply.set_low() };
        true
    }

    fn has_supply(&self) -> bool {
        self.has_supply
    }

    fn trip_travel_um(&self) -> i32 {
        self.switch_travel_um
    }

    fn channels_cycled(&self) -> bool {
        self.seen_a && self.seen_b
    }

    fn clear_cycle(&mut self) {
        self.seen_a = false;
        self.seen_b = false;
        self.disagree_since = None;
    }
}
