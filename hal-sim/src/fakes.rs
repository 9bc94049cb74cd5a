//! The stateful fakes the rig is built from: a GPIO pin with injectable faults ([`SimPin`],
//! [`PinFault`]), the firmware's clock ([`SimClock`]) and an ADC ([`SimAdc`], [`AdcFault`]), shared
//! by handle between the firmware under test and the test that drives them. Moved out of lib.rs so
//! that the rig and the output faults import them without importing the crate root (no import
//! circle, `cargo xtask structure`).
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU8, Ordering::SeqCst};
use std::sync::Arc;

use embedded_hal::digital::{ErrorKind, ErrorType, InputPin, OutputPin, StatefulOutputPin};
use flinch_firmware::{Adc, Clock, Micros};


/// A fault injected into a [`SimPin`].
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum PinFault {
    /// Healthy.
    None = 0,
    /// Reads low whatever is driven.
    StuckLow = 1,
    /// Reads high whatever is driven.
    StuckHigh = 2,
    /// The wire is cut: reads the input's pull level (set at construction, low by default).
    CutWire = 3,
    /// Every read and write returns an error.
    Broken = 4,
    /// Its port is frozen (the board's GPIO clock gated, or the port's logic dead): writes are lost
    /// without an error, reads return low (a gated register reads a constant; the F4 reads 0), and
    /// the pin itself keeps driving the level it had (which is what a relay on it sees).
    Frozen = 5,
}

impl PinFault {
    fn from_u8(v: u8) -> PinFault {
        match v {
            1 => PinFault::StuckLow,
            2 => PinFault::StuckHigh,
            3 => PinFault::CutWire,
            4 => PinFault::Broken,
            5 => PinFault::Frozen,
            _ => PinFault::None,
        }
    }
}

/// The error a [`PinFault::Broken`] pin returns.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct SimPinError;

impl embedded_hal::digital::Error for SimPinError {
    fn kind(&self) -> ErrorKind {
        ErrorKind::Other
    }
}

#[derive(Debug)]
struct PinInner {
    driven: AtomicBool,
    fault: AtomicU8,
    pull_high: bool,
    /// Supply pin and the level the input reads while that supply is off.
    supply: Option<(SimPin, bool)>,
}

/// A digital pin with a shared level. Clones are handles to the same pin.
///
/// The *driven* level is what was last set (by the plant for an input, by the firmware for an output);
/// the *observed* level ([`SimPin::level`], and `is_high` through `InputPin`) is the driven level
/// after faults and, for a sensor input, after its supply.
#[derive(Clone, Debug)]
pub struct SimPin(Arc<PinInner>);

impl SimPin {
    /// A healthy pin driven to `level`, pulled low when cut.
    pub fn new(level: bool) -> SimPin {
        SimPin::build(level, false, None)
    }

    /// A pin with a pull-up: a cut wire reads high.
    pub fn new_pulled_up(level: bool) -> SimPin {
        SimPin::build(level, true, None)
    }

    /// A sensor input powered by `supply` (an output the firmware drives: high = powered): while the
    /// supply is low it reads `unpowered_level`, pulled low when cut.
    pub fn powered_by(level: bool, supply: SimPin, unpowered_level: bool) -> SimPin {
        SimPin::build(level, false, Some((supply, unpowered_level)))
    }

    fn build(level: bool, pull_high: bool, supply: Option<(SimPin, bool)>) -> SimPin {
        SimPin(Arc::new(PinInner { driven: AtomicBool::new(level), fault: AtomicU8::new(0), pull_high, supply }))
    }

    /// Drive the pin (the plant sets a sensor level with this).
    pub fn set(&self, level: bool) {
        self.0.driven.store(level, SeqCst);
    }

    /// The level last driven, ignoring faults.
    pub fn driven(&self) -> bool {
        self.0.driven.load(SeqCst)
    }

    /// The level a reader sees: driven level after faults and supply.
    pub fn level(&self) -> bool {
        match self.fault() {
            PinFault::StuckLow | PinFault::Broken => false,
            PinFault::StuckHigh => true,
            PinFault::CutWire => self.0.pull_high,
            PinFault::None | PinFault::Frozen => match &self.0.supply {
                Some((supply, unpowered)) if !supply.level() => *unpowered,
                _ => self.driven(),
            },
        }
    }

    /// Inject a fault (or clear it with [`PinFault::None`]).
    pub fn set_fault(&self, fault: PinFault) {
        self.0.fault.store(fault as u8, SeqCst);
    }

    /// The injected fault.
    pub fn fault(&self) -> PinFault {
        PinFault::from_u8(self.0.fault.load(SeqCst))
    }

    fn check(&self) -> Result<(), SimPinError> {
        if self.fault() == PinFault::Broken {
            Err(SimPinError)
        } else {
            Ok(())
        }
    }
}

impl ErrorType for SimPin {
    type Error = SimPinError;
}

impl InputPin for SimPin {
    fn is_high(&mut self) -> Result<bool, SimPinError> {
        self.check()?;
        Ok(self.fault() != PinFault::Frozen && self.level())
    }
    fn is_low(&mut self) -> Result<bool, SimPinError> {
        self.is_high().map(|h| !h)
    }
}

impl OutputPin for SimPin {
    fn set_low(&mut self) -> Result<(), SimPinError> {
        self.check()?;
        if self.fault() != PinFault::Frozen {
            self.set(false);
        }
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), SimPinError> {
        self.check()?;
        if self.fault() != PinFault::Frozen {
            self.set(true);
        }
        Ok(())
    }
}

impl StatefulOutputPin for SimPin {
    fn is_set_high(&mut self) -> Result<bool, SimPinError> {
        self.check()?;
        Ok(self.driven())
    }
    fn is_set_low(&mut self) -> Result<bool, SimPinError> {
        self.is_set_high().map(|h| !h)
    }
}

#[derive(Debug, Default)]
struct ClockInner {
    now: AtomicU32,
    stalled: AtomicBool,
    frozen: AtomicU32,
    /// Reference oscillator rate in percent of nominal (1 MHz); 0: dead. Set by `set_reference_pct`.
    reference_pct: AtomicU32,
    reference_set: AtomicBool,
}

/// Simulation time as the firmware's [`Clock`]: microseconds the harness sets. Clones share it.
#[derive(Clone, Debug, Default)]
pub struct SimClock(Arc<ClockInner>);

impl SimClock {
    /// A clock reading `start`.
    pub fn new(start: Micros) -> SimClock {
        let c = SimClock::default();
        c.set(start);
        c
    }

    /// Set the time (wrapping microseconds).
    pub fn set(&self, t: Micros) {
        self.0.now.store(t.0, SeqCst);
    }

    /// Advance by `us`, wrapping.
    pub fn advance(&self, us: u32) {
        let t = self.true_now().plus(us);
        self.set(t);
    }

    /// The simulation's time, ignoring a stall.
    pub fn true_now(&self) -> Micros {
        Micros(self.0.now.load(SeqCst))
    }

    /// Run the independent reference oscillator ([`Clock::reference_ticks`], nominal 1 MHz) at `pct`
    /// percent of its nominal rate relative to the firmware's clock (100: both agree; 130: the
    /// firmware's oscillator runs 30 % slow; 0: the reference is dead). Without a call there is no
    /// reference. Exact only while sim time does not wrap the u32 (71 min) at a rate other than 100.
    pub fn set_reference_pct(&self, pct: u32) {
        self.0.reference_pct.store(pct, SeqCst);
        self.0.reference_set.store(true, SeqCst);
    }

    /// Stall (`true`: the firmware keeps reading the instant of the stall) or resume.
    pub fn set_stalled(&self, stalled: bool) {
        if stalled && !self.0.stalled.load(SeqCst) {
            self.0.frozen.store(self.0.now.load(SeqCst), SeqCst);
        }
        self.0.stalled.store(stalled, SeqCst);
    }
}

impl Clock for SimClock {
    fn now(&mut self) -> Micros {
        if self.0.stalled.load(SeqCst) {
            Micros(self.0.frozen.load(SeqCst))
        } else {
            self.true_now()
        }
    }

    fn reference_ticks(&mut self) -> Option<u32> {
        if !self.0.reference_set.load(SeqCst) {
            return None;
        }
        let pct = u64::from(self.0.reference_pct.load(SeqCst));
        Some((u64::from(self.true_now().0) * pct / 100) as u32)
    }
}

/// A fault injected into a [`SimAdc`].
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum AdcFault {
    /// Healthy.
    None,
    /// The signal wire is cut: the input is pulled to ground and reads 0.
    CutWire,
    /// Reads this raw value whatever the plant does.
    Stuck(u16),
    /// Every conversion fails.
    Error,
}

#[derive(Debug, Default)]
struct AdcInner {
    raw: AtomicU32,
    // 0 none, 1 cut, 2 stuck (value in `stuck`), 3 error
    fault: AtomicU8,
    stuck: AtomicU32,
}

/// An ADC channel whose raw value the plant sets. Clones share it.
#[derive(Clone, Debug, Default)]
pub struct SimAdc(Arc<AdcInner>);

/// The error of a failing [`SimAdc`].
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct SimAdcError;

impl SimAdc {
    /// A channel reading `raw`.
    pub fn new(raw: u16) -> SimAdc {
        let a = SimAdc::default();
        a.set(raw);
        a
    }

    /// Set the raw value the plant produces.
    pub fn set(&self, raw: u16) {
        self.0.raw.store(u32::from(raw), SeqCst);
    }

    /// Inject a fault.
    pub fn set_fault(&self, fault: AdcFault) {
        let code = match fault {
            AdcFault::None => 0,
            AdcFault::CutWire => 1,
            AdcFault::Stuck(v) => {
                self.0.stuck.store(u32::from(v), SeqCst);
                2
            }
            AdcFault::Error => 3,
        };
        self.0.fault.store(code, SeqCst);
    }
}

impl Adc for SimAdc {
    type Error = SimAdcError;
    fn read(&mut self) -> Result<u16, SimAdcError> {
        let v = match self.0.fault.load(SeqCst) {
            1 => 0,
            2 => self.0.stuck.load(SeqCst),
            3 => return Err(SimAdcError),
            _ => self.0.raw.load(SeqCst),
        };
        Ok(u16::try_from(v).unwrap_or(u16::MAX))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clones_share_the_level_and_faults_override_it() {
        let plant = SimPin::new(true);
        let mut firmware_side = plant.clone();
        assert!(firmware_side.is_high().unwrap());
        plant.set(false);
        assert!(firmware_side.is_low().unwrap());
        plant.set_fault(PinFault::StuckHigh);
        assert!(firmware_side.is_high().unwrap());
        plant.set_fault(PinFault::CutWire);
        assert!(firmware_side.is_low().unwrap(), "pulled down");
        let up = SimPin::new_pulled_up(false);
        up.set_fault(PinFault::CutWire);
        assert!(up.level());
        plant.set_fault(PinFault::Broken);
        assert_eq!(firmware_side.is_high(), Err(SimPinError));
        assert_eq!(firmware_side.set_high(), Err(SimPinError));
    }

    #[test]
    fn output_pin_is_stateful() {
        let mut out = SimPin::new(false);
        let observer = out.clone();
        out.set_high().unwrap();
        assert!(observer.level());
        assert!(out.is_set_high().unwrap());
        out.toggle().unwrap();
        assert!(!observer.level());
        observer.set_fault(PinFault::StuckHigh); // a welded relay contact
        out.set_low().unwrap();
        assert!(out.is_set_low().unwrap(), "driven low");
        assert!(observer.level(), "but observed high");
    }

    #[test]
    fn a_frozen_pin_keeps_driving_ignores_writes_and_reads_low() {
        let mut out = SimPin::new(false);
        out.set_high().unwrap();
        out.set_fault(PinFault::Frozen);
        out.set_low().unwrap();
        assert!(out.level(), "the pin still drives high: the relay stays pulled in");
        assert!(!out.is_high().unwrap(), "the gated register reads 0");
        out.set_fault(PinFault::None);
        assert!(out.is_high().unwrap());
    }

    #[test]
    fn powered_input_reads_its_unpowered_level_without_supply() {
        let supply = SimPin::new(true);
        let input = SimPin::powered_by(true, supply.clone(), false);
        assert!(input.level());
        supply.set(false);
        assert!(!input.level());
        input.set_fault(PinFault::StuckHigh);
        assert!(input.level(), "a stuck input ignores its supply");
    }

    #[test]
    fn clock_is_shared_settable_and_stalls() {
        let harness = SimClock::new(Micros(u32::MAX - 1));
        let mut fw = harness.clone();
        harness.advance(3);
        assert_eq!(fw.now(), Micros(1), "wraps");
        harness.set_stalled(true);
        harness.advance(100);
        assert_eq!(fw.now(), Micros(1));
        assert_eq!(harness.true_now(), Micros(101));
        harness.set_stalled(false);
        assert_eq!(fw.now(), Micros(101));
    }

    #[test]
    fn adc_faults() {
        let plant = SimAdc::new(1234);
        let mut fw = plant.clone();
        assert_eq!(fw.read(), Ok(1234));
        plant.set_fault(AdcFault::CutWire);
        assert_eq!(fw.read(), Ok(0));
        plant.set_fault(AdcFault::Stuck(77));
        plant.set(2000);
        assert_eq!(fw.read(), Ok(77));
        plant.set_fault(AdcFault::Error);
        assert_eq!(fw.read(), Err(SimAdcError));
        plant.set_fault(AdcFault::None);
        assert_eq!(fw.read(), Ok(2000));
    }
}
