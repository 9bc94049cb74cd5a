//! Flinch firmware library: hardware-independent detection, timestamping and fail-safe stop for a
//! collision decoupler module (MODEL.md "Sensor" and "Controller").
//!
//! `#![no_std]`, no heap, everything sized at compile time, integer and fixed-point arithmetic only on
//! the detect-to-stop path. It is generic over `embedded-hal` 1.0 pins and our [`Clock`] trait, so the
//! same code runs on the STM32F407 board (`src/bin/board.rs`), in QEMU on `mps2-an386`
//! (`src/bin/qemu.rs`) and against the plant simulation in `flinch hil` (through `flinch-hal-sim`).
//!
//! One concern per module: [`clock`] (wrap-safe microseconds), [`sensor`] (travel switch, analog
//! travel with velocity estimate), [`debounce`] (glitch filter with its latency, chatter guard),
//! [`detector`] (states and reset policy), [`selftest`] (stuck input at start-up), [`watchdog`] (clock
//! stall, missed tick deadline), [`stop_output`] (fail-safe outputs: two stop channels and the
//! category-0 escalation), [`output_monitor`] (each output read back at its pin and its relay),
//! [`diagnostics`] (periodic self-tests while running), [`serial_rx`] (the USART receive service),
//! [`backup`] (the latch and the
//! event log across resets, in backup SRAM), [`option_bytes`] (the brown-out level, verified at the
//! next boot), [`event_log`] (ring of trips,
//! serialisable), [`stroke_budget`] (stopping distance vs. remaining stroke), [`firmware`] (all of it
//! tied together).
//!
//! # Using it (the `flinch hil` harness, or a board)
//!
//! 1. Build a [`Config`]: tick period, [`Filter`], [`ResetPolicy`], [`BudgetConfig`] (robot speed,
//!    dead time, deceleration, stroke), self-test timing.
//! 2. Wrap the input in a sensor: [`DigitalSwitch`] (with a [`SwitchKind`] and the switching travel
//!    d_sw) or [`AnalogTravel`] (an [`Adc`] and an [`AnalogConfig`]).
//! 3. [`Firmware::after_reset`] with why the MCU started ([`Boot`]: the [`ResetCause`] and the
//!    [`Retained`] latch), a [`Clock`], the sensor, the [`Outputs`] (the two stop channels K1 and
//!    K2 and the escalation output, each read back at its pin) and the reset input ([`Unconnected`]
//!    if none). Every output is de-energised from here on until armed, and by default every start
//!    waits for a reset press and release ([`StartPolicy`]).
//! 4. Call [`Firmware::tick`] every `tick_period_us`, and [`Firmware::on_edge`] on every edge of the
//!    switch input. The first ticks run the self-test, then the firmware arms.
//! 5. Read the stop and escalation pins (low = stop / category 0), [`Firmware::detected_at`],
//!    [`Firmware::log`], [`Firmware::state`]; feed the hardware watchdog only while
//!    [`Firmware::feeds_watchdog`].
//!
//! `flinch_hal_sim::SimRig` packages exactly this for the harness, with simulated pins and clock.
//!
//! ```
//! use core::{cell::Cell, convert::Infallible};
//! use embedded_hal::digital::{ErrorType, InputPin, OutputPin};
//! use flinch_firmware::*;
//!
//! // Minimal fakes; flinch-hal-sim has shareable ones.
//! struct Pin<'a>(&'a Cell<bool>);
//! impl ErrorType for Pin<'_> { type Error = Infallible; }
//! impl InputPin for Pin<'_> {
//!     fn is_high(&mut self) -> Result<bool, Infallible> { Ok(self.0.get()) }
//!     fn is_low(&mut self) -> Result<bool, Infallible> { Ok(!self.0.get()) }
//! }
//! impl OutputPin for Pin<'_> {
//!     fn set_high(&mut self) -> Result<(), Infallible> { self.0.set(true); Ok(()) }
//!     fn set_low(&mut self) -> Result<(), Infallible> { self.0.set(false); Ok(()) }
//! }
//! struct Time<'a>(&'a Cell<u32>);
//! impl Clock for Time<'_> { fn now(&mut self) -> Micros { Micros(self.0.get()) } }
//!
//! let (switch, stop, stop2, esc, t) = (Cell::new(true), Cell::new(true), Cell::new(true), Cell::new(true), Cell::new(0));
//! let outputs = || Outputs { k1: Pin(&stop), k2: Pin(&stop2), escalation: Pin(&esc) };
//! // Tables 5-7: V_c = 0.05 m/s, DT = 16 ms; d = 1 m/s^2 and a 10 mm stroke chosen for the example.
//! let budget = BudgetConfig { robot_speed_um_per_s: 50_000, dead_time_us: 16_000,
//!                             decel_um_per_s2: 1_000_000, stroke_um: 10_000 };
//! let mut cfg = Config::new(1_000, budget);
//! cfg.reset = ResetPolicy::Auto { hold_us: 50_000 };
//! // No reset button on this rig: only a clean power-on may start by itself (reset.rs).
//! cfg.start = StartPolicy::AutoAfterPowerOn;
//!
//! // After a watchdog reset the firmware stays stopped: without a button, for ever.
//! let boot = Boot { cause: ResetCause::from_rcc_csr(1 << 29 | 1 << 26), retained: Retained::default() };
//! let sensor = DigitalSwitch::new(Pin(&switch), SwitchKind::Inductive, 5_000); // d_sw = 5 mm
//! let mut fw: Firmware<_, _, _, _, _, _> =
//!     Firmware::after_reset(cfg, boot, Time(&t), sensor, outputs(), Unconnected).unwrap();
//! for k in 0..100 { t.set(k * 1_000); fw.tick(); }
//! assert_eq!(fw.state(), State::Fault(Cause::Reset));
//! assert!(!stop.get() && !esc.get());
//!
//! // After a clean power-on it runs the self-test and arms.
//! t.set(0);
//! let sensor = DigitalSwitch::new(Pin(&switch), SwitchKind::Inductive, 5_000);
//! let mut fw: Firmware<_, _, _, _, _, _> =
//!     Firmware::after_reset(cfg, Boot::POWER_ON, Time(&t), sensor, outputs(), Unconnected).unwrap();
//! assert!(!stop.get(), "de-energised until armed");
//!
//! for k in 0..10 { t.set(k * 1_000); fw.tick(); }          // self-test, then armed
//! assert!(fw.is_armed() && stop.get() && esc.get());
//!
//! t.set(10_250); switch.set(false); fw.on_edge();            // the tool moves back 5 mm
//! assert!(!stop.get() && !stop2.get(), "both stop channels written from the edge interrupt");
//! assert!(esc.get(), "2.05 mm stopping distance fits the 5 mm left: no category 0");
//! assert_eq!(fw.detected_at(), Some(Micros(10_250)));
//! assert_eq!(fw.log().last().map(|e| e.cause), Some(Cause::Trip));
//! ```
//!
//! # Limits
//!
//! * A sensor without a switchable supply cannot be checked for a stuck-at-rest input at start-up
//!   (`selftest.rs`); the inductive switch with supply control can.
//! * [`Micros`] differences are exact up to 2^31 us (35.8 min); every interval used is far shorter.
//! * The analog sensor re-arms on "not above the trip threshold", without hysteresis.
#![no_std]
#![deny(missing_docs)]

#[macro_use]
pub(crate) mod fmt;

pub mod avoidance;

/// Declares the detection modules with the lints that keep panics off their paths: no
/// unwrap/expect/panic, no indexing, no unchecked arithmetic (`cargo clippy -p flinch-firmware`
/// enforces it; tests may unwrap).
macro_rules! panic_free_modules {
    ($($(#[$doc:meta])* $m:ident;)*) => {$(
        $(#[$doc])*
        #[cfg_attr(not(test), deny(
            clippy::unwrap_used, clippy::expect_used, clippy::panic,
            clippy::indexing_slicing, clippy::arithmetic_side_effects
        ))]
        pub mod $m;
    )*};
}

panic_free_modules! {
    backup;
    clock;
    clock_check;
    debounce;
    detector;
    diagnostics;
    dual;
    edm;
    event_log;
    firmware;
    integrity;
    option_bytes;
    output_monitor;
    pins;
    reset;
    selftest;
    sensor;
    serial_rx;
    stop_output;
    stroke_budget;
    watchdog;
}

pub use backup::{BackupRam, RamBackup};
pub use clock::{Clock, Micros};
pub use clock_check::ClockCheck;
pub use debounce::{ChatterGuard, Filter};
pub use detector::{ResetPolicy, State};
pub use dual::DualSwitch;
pub use edm::{Edm, Feedback, NoFeedback};
pub use event_log::{Cause, EventLog, LogSnapshot, TripEvent};
pub use firmware::{Config, ConfigError, Firmware};
pub use output_monitor::OutputMonitor;
pub use pins::Unconnected;
pub use reset::{Boot, ResetCause, ResetPress, Retained, StartPolicy};
pub use selftest::SelfTestConfig;
pub use sensor::{Adc, AnalogConfig, AnalogTravel, DigitalSwitch, Mm, Sample, Sensor, SwitchKind};
pub use stop_output::{Outputs, PinLevels};
pub use stroke_budget::{stopping_distance_m, stopping_distance_um, BudgetConfig, Verdict};
