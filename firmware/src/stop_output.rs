//! Fail-safe outputs: de-energised means stop.
//!
//! Two outputs, both energised (high) only while the firmware is armed and healthy:
//!
//! * **stop**: low asks the robot controller for a controlled stop (category 1). It is low at reset
//!   (GPIO reset state, pull-down), during the self-test, when tripped, on any fault, in the panic
//!   handler, and whenever the MCU is dead or unpowered.
//! * **escalation**: low asks for a category-0 stop (drive power off). It drops together with the
//!   stop output when the stroke budget says a controlled stop would run out of stroke
//!   (`stroke_budget.rs`), and on every fault, since then the firmware cannot vouch for anything.
//!
//! A controller therefore reads (stop, escalation) = (high, high) as "go", (low, high) as "controlled
//! stop", (low, low) as "category 0". A driver error on a pin is a fault ([`Cause::OutputFault`]).
//!
//! [`Cause::OutputFault`]: crate::Cause::OutputFault

use embedded_hal::digital::OutputPin;

/// The stop and escalation outputs, with the level last commanded.
#[derive(Debug)]
pub struct StopOutputs<STOP, ESC> {
    pub(crate) stop: STOP,
    esc: ESC,
    energised: bool,
    escalated: bool,
}

impl<STOP: OutputPin, ESC: OutputPin> StopOutputs<STOP, ESC> {
    /// Take the pins and de-energise both at once. Returns the outputs and whether both writes
    /// succeeded.
    pub fn new(stop: STOP, esc: ESC) -> (Self, bool) {
        let mut o = StopOutputs { stop, esc, energised: true, escalated: false };
        let ok = o.drop_all();
        (o, ok)
    }

    /// Stop requested (the stop output was last commanded low).
    pub const fn stop_requested(&self) -> bool {
        !self.energised
    }

    /// Category 0 requested (the escalation output was last commanded low).
    pub const fn category0_requested(&self) -> bool {
        self.escalated
    }

    /// Drop the stop output only: the edge interrupt's first write. Returns `false` on a pin error.
    #[inline(always)]
    pub fn drop_stop(&mut self) -> bool {
        let ok = self.stop.set_low().is_ok();
        self.energised = false;
        ok
    }

    /// Drop the escalation output (category 0). Returns `false` on a pin error.
    pub fn escalate(&mut self) -> bool {
        self.escalated = true;
        self.esc.set_low().is_ok()
    }

    /// De-energise both outputs. Returns `false` on a pin error.
    pub fn drop_all(&mut self) -> bool {
        // Stop first: it is the one that matters most.
        let a = self.drop_stop();
        let b = self.escalate();
        a && b
    }

    /// Energise both outputs (armed and healthy). Returns `false` on a pin error, in which case the
    /// caller must fault, which drops them again.
    pub fn energise(&mut self) -> bool {
        // Escalation first, so that there is never an instant of "go" with category 0 pending.
        let b = self.esc.set_high().is_ok();
        self.escalated = false;
        let a = self.stop.set_high().is_ok();
        self.energised = true;
        a && b
    }
}
