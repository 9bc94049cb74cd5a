//! [`Unconnected`]: a pin that is not wired, for optional inputs and outputs.
//!
//! The firmware takes every pin as a type parameter. Where a board has no such pin (no reset button
//! with [`ResetPolicy::Auto`](crate::ResetPolicy), no switchable sensor supply) pass `Unconnected`:
//! it reads low and ignores writes, so the generic code needs no `Option` on its hot path.

use core::convert::Infallible;
use embedded_hal::digital::{ErrorType, InputPin, OutputPin};

/// A pin that is not wired: reads low, ignores writes.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct Unconnected;

impl ErrorType for Unconnected {
    type Error = Infallible;
}

impl InputPin for Unconnected {
    fn is_high(&mut self) -> Result<bool, Infallible> {
        Ok(false)
    }
    fn is_low(&mut self) -> Result<bool, Infallible> {
        Ok(true)
    }
}

impl OutputPin for Unconnected {
    fn set_low(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
}
