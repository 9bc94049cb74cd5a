//! The QEMU bench's pin image (feature `qemu-io` only; never in the production build): GPIOA's input
//! register as the bench drives it and the RAM images of the output ports' registers, which
//! `board_hw.rs`'s two pin accessors use in place of the GPIO that QEMU 7.2 does not model
//! (`board_bench.rs` says why). It reads only the pin map, so the registers' module and the bench
//! both use it without importing each other.

use crate::pins::{PA, PB, PD, PE};
use core::sync::atomic::{AtomicU32, Ordering::Relaxed};

/// GPIOA's input register as the bench drives it.
pub static PINS: AtomicU32 = AtomicU32::new(0);
/// The output registers of GPIOB, GPIOD and GPIOE as the BSRR writes leave them.
static ODR_B: AtomicU32 = AtomicU32::new(0);
static ODR_D: AtomicU32 = AtomicU32::new(0);
static ODR_E: AtomicU32 = AtomicU32::new(0);

/// The RAM image of an output port's register (`None` for a port without outputs).
fn image(port: u8) -> Option<&'static AtomicU32> {
    match port {
        PB => Some(&ODR_B),
        PD => Some(&ODR_D),
        PE => Some(&ODR_E),
        _ => None,
    }
}

/// An input register as the board reads it: GPIOA's from the bench, an output port's from its
/// image (the pins follow their outputs), 0 elsewhere (as QEMU reads every GPIO).
#[inline(always)]
pub fn idr(port: u8) -> u32 {
    if port == PA {
        PINS.load(Relaxed)
    } else {
        image(port).map_or(0, |i| i.load(Relaxed))
    }
}

/// Apply a BSRR write to the port's RAM image (set wins over reset, as on the part).
#[inline(always)]
pub fn bsrr(port: u8, v: u32) {
    if let Some(i) = image(port) {
        i.fetch_and(!(v >> 16), Relaxed);
        i.fetch_or(v & 0xFFFF, Relaxed);
    }
}

