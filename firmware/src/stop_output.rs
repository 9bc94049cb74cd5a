//! Fail-safe outputs: de-energised means stop. Two stop channels and a category-0 output, each
//! read back at its pin.
//!
//! Three outputs, all energised (high) only while the firmware is armed and healthy:
//!
//! * **K1 and K2**, the two stop channels (ISO 13849-1 6.2.6, category 3): each drives one relay;
//!   their force-guided contacts sit in series in the robot's stop circuit, so either one released
//!   opens it (a controlled stop, category 1). Both are written on every stop, K1 first. On the board
//!   they are on different pins of different GPIO ports (different RCC clock-enable bits), so a
//!   frozen port or a stuck pin takes one channel, never both.
//! * **escalation**: low asks for a category-0 stop (drive power off) on a third, independent path
//!   (a third port on the board). It drops together with the stop channels when the stroke budget
//!   says a controlled stop would run out of stroke (`stroke_budget.rs`), and on every fault, since
//!   then the firmware cannot vouch for anything.
//!
//! A controller therefore reads (stop circuit, escalation) = (closed, high) as "go", (open, high) as
//! "controlled stop", (open, low) as "category 0". A driver error on a write is a fault
//! ([`Cause::OutputFault`]).
//!
//! Every output is also an input: [`StopOutputs::read_back`] reads the level *at the pin* (the
//! board's input data register, IDR, of an output pin), which a stuck pin, a shorted driver or a
//! frozen port (its clock gated: the writes are lost and the register reads a constant) no longer
//! makes follow the command. `output_monitor.rs` compares it with the command every tick.
//!
//! [`Cause::OutputFault`]: crate::Cause::OutputFault

use embedded_hal::digital::{InputPin, OutputPin};

/// The three outputs a [`Firmware`](crate::Firmware) drives, each an output whose pin can be read
/// back (`OutputPin + InputPin`).
#[derive(Debug)]
pub struct Outputs<K1, K2, ESC> {
    /// Stop channel 1 (relay K1).
    pub k1: K1,
    /// Stop channel 2 (relay K2), independent of K1 (another port on the board).
    pub k2: K2,
    /// The category-0 escalation output, independent of both.
    pub escalation: ESC,
}

/// What the three pins read back: `Some(high)`, or `None` on a read error.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct PinLevels {
    /// Stop channel 1's pin.
    pub k1: Option<bool>,
    /// Stop channel 2's pin.
    pub k2: Option<bool>,
    /// The escalation pin.
    pub escalation: Option<bool>,
}

/// The stop channels and the escalation output, with the levels last commanded.
#[derive(Debug)]
pub struct StopOutputs<K1, K2, ESC> {
    k1: K1,
    k2: K2,
    esc: ESC,
    energised: bool,
    escalated: bool,
}

impl<K1: OutputPin + InputPin, K2: OutputPin + InputPin, ESC: OutputPin + InputPin> StopOutputs<K1, K2, ESC> {
    /// Take the pins and de-energise all three at once. Returns the outputs and whether every write
    /// succeeded.
    pub fn new(pins: Outputs<K1, K2, ESC>) -> (Self, bool) {
        let mut o = StopOutputs { k1: pins.k1, k2: pins.k2, esc: pins.escalation, energised: true, escalated: false };
        let ok = o.drop_all();
        (o, ok)
    }

    /// Stop requested (both stop channels were last commanded low).
    pub const fn stop_requested(&self) -> bool {
        !self.energised
    }

    /// Category 0 requested (the escalation output was last commanded low).
    pub const fn category0_requested(&self) -> bool {
        self.escalated
    }

    /// Drop both stop channels, K1 first, then K2 (the other's write is not skipped when the first
    /// fails). Returns `false` on a pin error.
    #[inline(always)]
    pub fn drop_stop(&mut self) -> bool {
        let a = self.k1.set_low().is_ok();
        let b = self.k2.set_low().is_ok();
        self.energised = false;
        a && b
    }

    /// Drop the escalation output (category 0). Returns `false` on a pin error.
    pub fn escalate(&mut self) -> bool {
        self.escalated = true;
        self.esc.set_low().is_ok()
    }

    /// De-energise all three outputs. Returns `false` on a pin error.
    pub fn drop_all(&mut self) -> bool {
        // The stop channels first: they are the ones that matter most.
        let a = self.drop_stop();
        let b = self.escalate();
        a && b
    }

    /// Energise all three (armed and healthy). Returns `false` on a pin error, in which case the
    /// caller must fault, which drops them again.
    pub fn energise(&mut self) -> bool {
        // Escalation first, so that there is never an instant of "go" with category 0 pending.
        let c = self.esc.set_high().is_ok();
        self.escalated = false;
        let a = self.k1.set_high().is_ok();
        let b = self.k2.set_high().is_ok();
        self.energised = true;
        a && b && c
    }

    /// The level at each pin now (the board's IDR), for the output monitor.
    pub fn read_back(&mut self) -> PinLevels {
        PinLevels { k1: self.k1.is_high().ok(), k2: self.k2.is_high().ok(), escalation: self.esc.is_high().ok() }
    }
}
