//! Sensor inputs: the digital travel switch and the analog displacement sensor.
//!
//! Both report, per [`Sample`], whether the tool has moved back far enough to count as a collision
//! (MODEL.md, "Sensor": the travel switch fires once the tool has moved `d_sw` back from the front
//! end-stop; 5 mm in the thesis's Ch. 3 simulations, 1.5 mm on the prototypes and the hydraulic
//! module, 0.5 mm on the Z prototype), how far it has travelled, and whether the reading is
//! trustworthy.
//!
//! * [`DigitalSwitch`]: an inductive switch is ON (high) while the tool sits on the front stop and
//!   turns OFF on detection, so a cut wire reads as a trip ([`SwitchKind::Inductive`]). A magnetic
//!   switch on the hydraulic piston has a polarity set by its wiring ([`SwitchKind::Magnetic`]); only
//!   the trip-on-low wiring is fail-safe against a cut wire, which the docs of that variant repeat.
//!   An optional supply output lets the start-up self-test switch the sensor off and check that the
//!   input follows (a stuck input is caught there, see `selftest.rs`).
//! * [`AnalogTravel`]: a displacement sensor read through our [`Adc`] trait, converted to millimetres
//!   and thresholded in fixed point (`fixed::types::I16F16`: 1/65536 mm resolution, +-32 m range),
//!   with a plausibility window (a cut wire reads 0 or full scale: fault) and a travel-velocity
//!   estimate that the stroke budget uses.

use crate::clock::Micros;
use embedded_hal::digital::{InputPin, OutputPin};
use fixed::types::I16F16;

/// Millimetres, signed fixed point with 16 fractional bits.
pub type Mm = I16F16;

/// One reading of a sensor.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct Sample {
    /// The tool is back from the front stop at least by the trip travel (or the reading is faulty,
    /// which the fail-safe rule turns into a trip).
    pub trip: bool,
    /// Travel back from the front end-stop, micrometres. The digital switch cannot measure it and
    /// reports its switching travel while tripped, 0 otherwise.
    pub travel_um: i32,
    /// Travel velocity (positive: tool moving back towards the flange), micrometres per second;
    /// 0 for the digital switch.
    pub velocity_um_per_s: i32,
    /// The reading is implausible (ADC out of its valid window, ADC error, pin read error).
    pub fault: bool,
    /// Two-channel sensors: the channels have disagreed for longer than the discrepancy time.
    pub discrepancy: bool,
}

/// A collision sensor as the detector sees it.
pub trait Sensor {
    /// Read the sensor; called from the periodic tick.
    fn sample(&mut self, now: Micros) -> Sample;

    /// The shortest possible read for the edge-interrupt path: `true` when the input shows a trip.
    /// A read error counts as a trip.
    fn fast_trip(&mut self) -> bool;

    /// Switch the sensor's supply for the start-up self-test. Returns `false` when the sensor has no
    /// switchable supply (the self-test then skips the supply pulse).
    fn set_supply(&mut self, on: bool) -> bool;

    /// Whether [`Sensor::set_supply`] does anything.
    fn has_supply(&self) -> bool;

    /// The travel at which this sensor trips, micrometres (the stroke budget's starting point).
    fn trip_travel_um(&self) -> i32;

    /// Two-channel sensors: every channel has shown a trip since [`Sensor::clear_cycle`] (the
    /// firmware re-arms after a trip only if so). Single-channel sensors: always `true`.
    fn channels_cycled(&self) -> bool {
        true
    }

    /// Start watching for a new cycle of every channel (called when the firmware arms).
    fn clear_cycle(&mut self) {}
}

/// How the digital travel switch is wired.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum SwitchKind {
    /// Inductive proximity switch: high (ON) while the tool sits on the front stop, low on detection.
    /// A cut wire or a dead sensor reads low, i.e. as a trip: fail-safe.
    Inductive,
    /// Magnetic switch on the hydraulic piston. `trip_high`: the input reads high on detection.
    /// With `trip_high = true` a cut wire reads as "no collision": not fail-safe against a cut wire;
    /// the supply pulse of the start-up self-test is then the only check of the wiring.
    Magnetic {
        /// Level of the input when the tool has moved back (tripped).
        trip_high: bool,
    },
}

impl SwitchKind {
    /// The input level that means "tripped".
    #[inline(always)]
    pub const fn trip_level_high(self) -> bool {
        match self {
            SwitchKind::Inductive => false,
            SwitchKind::Magnetic { trip_high } => trip_high,
        }
    }

    /// The level a healthy switch of this kind shows for a tool that is (`tripped = true`) or is not
    /// back by the switching travel. The `flinch hil` harness uses this to drive the pin from the plant.
    #[inline(always)]
    pub const fn level_for(self, tripped: bool) -> bool {
        tripped == self.trip_level_high()
    }
}

/// A digital travel switch on an input pin, with an optional supply output for the self-test.
#[derive(Debug)]
pub struct DigitalSwitch<P, Q = crate::pins::Unconnected> {
    input: P,
    supply: Q,
    has_supply: bool,
    trip_high: bool,
    switch_travel_um: i32,
}

impl<P: InputPin> DigitalSwitch<P, crate::pins::Unconnected> {
    /// A switch without a switchable supply. `switch_travel_um` is d_sw, the travel back from the
    /// front stop at which it fires (MODEL.md "Sensor": 5000 in Ch. 3, 1500 on the prototypes).
    pub fn new(input: P, kind: SwitchKind, switch_travel_um: i32) -> Self {
        DigitalSwitch {
            input,
            supply: crate::pins::Unconnected,
            has_supply: false,
            trip_high: kind.trip_level_high(),
            switch_travel_um,
        }
    }
}

impl<P: InputPin, Q: OutputPin> DigitalSwitch<P, Q> {
    /// A switch whose supply the firmware can switch off (high = powered) for the start-up test.
    /// Wiring rule: the unpowered switch must read as a trip.
    pub fn with_supply(input: P, supply: Q, kind: SwitchKind, switch_travel_um: i32) -> Self {
        DigitalSwitch { input, supply, has_supply: true, trip_high: kind.trip_level_high(), switch_travel_um }
    }

    #[inline(always)]
    fn read_trip(&mut self) -> (bool, bool) {
        match self.input.is_high() {
            Ok(high) => (high == self.trip_high, false),
            // A pin that cannot be read is a trip (fail-safe) and a fault.
            Err(_) => (true, true),
        }
    }
}

impl<P: InputPin, Q: OutputPin> Sensor for DigitalSwitch<P, Q> {
    fn sample(&mut self, _now: Micros) -> Sample {
        let (trip, fault) = self.read_trip();
        Sample {
            trip,
            travel_um: if trip { self.switch_travel_um } else { 0 },
            velocity_um_per_s: 0,
            fault,
            discrepancy: false,
        }
    }

    #[inline(always)]
    fn fast_trip(&mut self) -> bool {
        self.read_trip().0
    }

    fn set_supply(&mut self, on: bool) -> bool {
        if !self.has_supply {
            return false;
        }
        // A supply pin that cannot be driven makes the pulse test fail on its own (the input will
        // not follow), so the error needs no separate path.
        let _ = if on { self.supply.set_high() } else { self.supply.set_low() };
        true
    }

    fn has_supply(&self) -> bool {
        self.has_supply
    }

    fn trip_travel_um(&self) -> i32 {
        self.switch_travel_um
    }
}

/// An analog-to-digital converter channel, as the firmware needs it: one conversion, raw counts.
pub trait Adc {
    /// Error of a conversion.
    type Error;
    /// Convert once and return the raw result (right-aligned counts).
    fn read(&mut self) -> Result<u16, Self::Error>;
}

/// Calibration and thresholds of the analog displacement sensor.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct AnalogConfig {
    /// Raw counts with the tool on the front end-stop (travel 0).
    pub zero_counts: u16,
    /// Millimetres of travel per count (positive: more counts = tool further back).
    pub mm_per_count: Mm,
    /// Travel at which the detector trips (the analog d_sw).
    pub trip_mm: Mm,
    /// Lowest plausible raw reading; a cut wire pulled to ground reads below it.
    pub valid_min: u16,
    /// Highest plausible raw reading; a short to the reference reads above it.
    pub valid_max: u16,
    /// Velocity smoothing: each tick moves the estimate by 1/2^shift of the way to the newest
    /// finite difference (0: raw difference). Adds about 2^shift - 1 ticks of lag.
    pub velocity_shift: u8,
}

impl AnalogConfig {
    /// A 12-bit sensor spanning `span_mm` over 0..4095 counts, zero at count `zero_counts`, tripping
    /// at `trip_mm`, valid window 16..4079 counts (a rail-to-rail reading is taken as a wiring fault).
    pub fn linear_12bit(zero_counts: u16, span_mm: Mm, trip_mm: Mm) -> Self {
        AnalogConfig {
            zero_counts,
            mm_per_count: span_mm.checked_div_int(4095).unwrap_or(Mm::ZERO),
            trip_mm,
            valid_min: 16,
            valid_max: 4079,
            velocity_shift: 1,
        }
    }

    /// Travel for a raw reading, saturating at the I16F16 range.
    #[inline]
    pub fn travel_mm(&self, raw: u16) -> Mm {
        let counts = i32::from(raw).wrapping_sub(i32::from(self.zero_counts));
        self.mm_per_count.saturating_mul_int(counts)
    }

    /// The raw reading a healthy sensor gives at `travel_mm` (the inverse of [`Self::travel_mm`],
    /// rounded to the nearest count and clamped to `0..=u16::MAX`). The `flinch hil` harness uses it
    /// to feed the simulated ADC from the plant.
    pub fn counts_for(&self, travel_mm: Mm) -> u16 {
        if self.mm_per_count == 0 {
            return self.zero_counts;
        }
        let steps = travel_mm.saturating_div(self.mm_per_count).round().saturating_to_num::<i32>();
        let raw = i32::from(self.zero_counts).saturating_add(steps);
        raw.clamp(0, i32::from(u16::MAX)) as u16
    }
}

/// Convert millimetres (I16F16) to whole micrometres, saturating.
#[inline]
pub fn mm_to_um(mm: Mm) -> i32 {
    // bits * 1000 / 65536, in i64: |bits| < 2^31, so the product stays below 2^41.
    let um = i64::from(mm.to_bits()).wrapping_mul(1000).wrapping_shr(16);
    um.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32
}

/// An analog displacement sensor behind an [`Adc`].
#[derive(Debug)]
pub struct AnalogTravel<A> {
    adc: A,
    cfg: AnalogConfig,
    last: Option<(Micros, Mm)>,
    velocity: Mm, // mm/s
}

impl<A: Adc> AnalogTravel<A> {
    /// Wrap an ADC channel with its calibration.
    pub fn new(adc: A, cfg: AnalogConfig) -> Self {
        AnalogTravel { adc, cfg, last: None, velocity: Mm::ZERO }
    }

    /// The calibration in use.
    pub fn config(&self) -> &AnalogConfig {
        &self.cfg
    }

    fn read_travel(&mut self) -> (Mm, bool) {
        match self.adc.read() {
            Ok(raw) if raw >= self.cfg.valid_min && raw <= self.cfg.valid_max => (self.cfg.travel_mm(raw), false),
            // Implausible or failed conversion: report the worst case (a trip) and a fault.
            Ok(raw) => (self.cfg.travel_mm(raw), true),
            Err(_) => (self.cfg.trip_mm, true),
        }
    }

    /// Update the smoothed velocity from a new travel reading at `now`.
    fn update_velocity(&mut self, now: Micros, travel: Mm) {
        if let Some((t0, x0)) = self.last {
            let dt = now.since(t0);
            if dt > 0 {
                let dx_bits = i64::from(travel.to_bits()).wrapping_sub(i64::from(x0.to_bits()));
                // (mm * 2^16) * 1e6 / us = (mm/s) * 2^16; |dx_bits| < 2^33 so the product fits i64.
                let v_bits = dx_bits.saturating_mul(1_000_000).checked_div(i64::from(dt)).unwrap_or(0);
                let v_new = Mm::from_bits(v_bits.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32);
                let shift = u32::from(self.cfg.velocity_shift.min(15));
                let step = v_new.saturating_sub(self.velocity).wrapping_shr(shift);
                self.velocity = self.velocity.saturating_add(step);
            }
        }
        self.last = Some((now, travel));
    }
}

impl<A: Adc> Sensor for AnalogTravel<A> {
    fn sample(&mut self, now: Micros) -> Sample {
        let (travel, fault) = self.read_travel();
        if !fault {
            self.update_velocity(now, travel);
        }
        Sample {
            trip: fault || travel >= self.cfg.trip_mm,
            travel_um: mm_to_um(travel),
            velocity_um_per_s: mm_to_um(self.velocity),
            fault,
            discrepancy: false,
        }
    }

    fn fast_trip(&mut self) -> bool {
        let (travel, fault) = self.read_travel();
        fault || travel >= self.cfg.trip_mm
    }

    fn set_supply(&mut self, _on: bool) -> bool {
        false
    }

    fn has_supply(&self) -> bool {
        false
    }

    fn trip_travel_um(&self) -> i32 {
        mm_to_um(self.cfg.trip_mm)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::cell::Cell;
    use core::convert::Infallible;
    use embedded_hal::digital::ErrorType;

    struct Level<'a>(&'a Cell<bool>);
    impl ErrorType for Level<'_> {
        type Error = Infallible;
    }
    impl InputPin for Level<'_> {
        fn is_high(&mut self) -> Result<bool, Infallible> {
            Ok(self.0.get())
        }
        fn is_low(&mut self) -> Result<bool, Infallible> {
            Ok(!self.0.get())
        }
    }

    struct FakeAdc<'a>(&'a Cell<Option<u16>>);
    impl Adc for FakeAdc<'_> {
        type Error = ();
        fn read(&mut self) -> Result<u16, ()> {
            self.0.get().ok_or(())
        }
    }

    #[test]
    fn inductive_switch_reads_low_as_trip_so_a_cut_wire_trips() {
        let level = Cell::new(true); // on the front stop
        let mut s = DigitalSwitch::new(Level(&level), SwitchKind::Inductive, 5000);
        assert!(!s.sample(Micros(0)).trip);
        level.set(false); // moved back, or the wire is cut: the input floats low
        let smp = s.sample(Micros(1));
        assert!(smp.trip);
        assert_eq!(smp.travel_um, 5000);
        assert!(s.fast_trip());
    }

    #[test]
    fn magnetic_switch_polarity_is_configurable() {
        let level = Cell::new(false);
        let mut s = DigitalSwitch::new(Level(&level), SwitchKind::Magnetic { trip_high: true }, 1500);
        assert!(!s.fast_trip());
        level.set(true);
        assert!(s.fast_trip());
        assert!(SwitchKind::Magnetic { trip_high: true }.level_for(true));
        assert!(!SwitchKind::Inductive.level_for(true));
    }

    fn cfg() -> AnalogConfig {
        // 10 mm over 4095 counts, zero at 100 counts, trip at 1.5 mm (prototype d_sw, MODEL.md).
        AnalogConfig::linear_12bit(100, Mm::from_num(10), Mm::from_num(1.5))
    }

    #[test]
    fn analog_threshold_in_fixed_point() {
        let c = cfg();
        let raw_trip = c.counts_for(Mm::from_num(1.5));
        let v = Cell::new(Some(raw_trip - 2));
        let mut s = AnalogTravel::new(FakeAdc(&v), c);
        let below = s.sample(Micros(0));
        assert!(!below.trip && !below.fault);
        v.set(Some(raw_trip + 1));
        let above = s.sample(Micros(100));
        assert!(above.trip && !above.fault);
        assert!((above.travel_um - 1500).abs() < 10, "travel {} um", above.travel_um);
    }

    #[test]
    fn analog_cut_wire_and_adc_error_are_faults_that_trip() {
        let v = Cell::new(Some(0)); // pulled to ground
        let mut s = AnalogTravel::new(FakeAdc(&v), cfg());
        let smp = s.sample(Micros(0));
        assert!(smp.trip && smp.fault);
        v.set(None);
        let smp = s.sample(Micros(1));
        assert!(smp.trip && smp.fault);
        v.set(Some(4095)); // shorted to the reference
        assert!(s.sample(Micros(2)).fault);
    }

    #[test]
    fn velocity_estimate_tracks_a_constant_speed() {
        let mut c = cfg();
        c.velocity_shift = 1;
        let v = Cell::new(Some(100));
        let mut s = AnalogTravel::new(FakeAdc(&v), c);
        // 50 mm/s (Tables 5-7 approach speed V_c = 0.05 m/s) sampled every 1 ms.
        let mut last = Sample::default();
        for k in 0..40u32 {
            let travel = Mm::from_num(0.05) * Mm::from_num(k as i32); // 0.05 mm per ms
            v.set(Some(c.counts_for(travel)));
            last = s.sample(Micros(k * 1000));
        }
        // Count quantisation: one count is 2.44 um, i.e. 2.44 mm/s at 1 kHz.
        assert!((last.velocity_um_per_s - 50_000).abs() < 3_000, "v = {} um/s", last.velocity_um_per_s);
    }

    #[test]
    fn counts_round_trip() {
        let c = cfg();
        for raw in [100u16, 101, 500, 2000, 4000] {
            assert_eq!(c.counts_for(c.travel_mm(raw)), raw);
        }
    }
}
