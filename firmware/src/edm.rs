//! External device monitoring (EDM): the stop output read back through the relays it drives.
//!
//! The stop output is a `set_low` on a pin: on the board an `Infallible` register write, so a welded
//! relay contact, a shorted driver or a broken wire downstream is invisible to the pin. ISO 13849-1
//! 6.2.6 (category 3) and IEC 60204-1 9.4.2 ask for the stop to be carried by two channels and for a
//! fault in one to be detected: the output drives two relays or contactors (K1, K2) and each one's
//! mechanically linked (force-guided) NC mirror contact comes back on an input ([`Edm`]), high when
//! the relay has *released*. The firmware checks, every tick:
//!
//! * **follow**: each channel reads "released" while the stop is requested and "pulled in" while it is
//!   energised, within `Config::edm_settle_us` of every change (the relays' release time). A channel
//!   that does not follow (welded contact, stuck relay, cut or shorted feedback wire) latches
//!   [`Cause::EdmMismatch`](crate::Cause::EdmMismatch): both outputs drop, so the escalation output
//!   (category 0, drive power) takes over from the failed stop channel.
//! * **before arming**: both channels must read "released" before the stop output is energised; a
//!   relay welded while the firmware was stopped is caught before "go", not after (the classic EDM
//!   start check).
//! * a feedback read error is the same fault.
//!
//! Without [`Edm`] ([`NoFeedback`], the default) nothing is read back: the output side is one
//! unmonitored channel, which the crate README states as the limit of that configuration.

use embedded_hal::digital::InputPin;

/// What the read-back shows.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Reading {
    /// No read-back wired.
    NotMonitored,
    /// Each channel's relay has released (its NC mirror contact is closed).
    Released(bool, bool),
    /// A feedback input could not be read.
    Error,
}

/// A read-back of the stop channels.
pub trait Feedback {
    /// Read both channels now.
    fn read(&mut self) -> Reading;
}

/// No read-back (one unmonitored stop channel).
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct NoFeedback;

impl Feedback for NoFeedback {
    #[inline(always)]
    fn read(&mut self) -> Reading {
        Reading::NotMonitored
    }
}

/// Two EDM inputs, one per relay, high when that relay has released.
#[derive(Debug)]
pub struct Edm<A, B> {
    k1: A,
    k2: B,
}

impl<A: InputPin, B: InputPin> Edm<A, B> {
    /// The NC mirror contacts of K1 and K2.
    pub const fn new(k1: A, k2: B) -> Self {
        Edm { k1, k2 }
    }
}

impl<A: InputPin, B: InputPin> Feedback for Edm<A, B> {
    fn read(&mut self) -> Reading {
        match (self.k1.is_high(), self.k2.is_high()) {
            (Ok(a), Ok(b)) => Reading::Released(a, b),
            _ => Reading::Error,
        }
    }
}
