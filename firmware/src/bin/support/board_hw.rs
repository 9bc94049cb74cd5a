//! The board's registers and pins: the `stm32f4` PAC's register blocks, the pin map, the clock
//! constants, the two pin accesses (GPIO, or the QEMU bench's RAM with `qemu-io`), the zero-sized
//! pin types, TIM2 as the firmware's `Clock` and TIM5's capture of the LSI (the clock check's
//! reference).

use core::convert::Infallible;
use core::sync::atomic::{AtomicU32, Ordering::Relaxed};
use embedded_hal::digital::{ErrorType, InputPin, OutputPin};
use flinch_firmware::{Clock, Micros};

// ---- Registers: the `stm32f4` PAC (feature stm32f407, generated from ST's SVD; RM0090 Rev 19) ---
use stm32f4::stm32f407 as pac;
// The pin map (support/board_pins.rs): re-exported, so `crate::hw::K1_PORT` names it as before.
pub(crate) use crate::pins::*;

/// The PAC's register blocks. SAFETY (all of them): fixed peripheral addresses of this part,
/// valid for the whole program; every access through them is a volatile register access.
#[inline(always)]
pub(crate) fn rcc() -> &'static pac::rcc::RegisterBlock {
    unsafe { &*pac::RCC::ptr() }
}
#[inline(always)]
pub(crate) fn tim2() -> &'static pac::tim2::RegisterBlock {
    unsafe { &*pac::TIM2::ptr() }
}
#[inline(always)]
pub(crate) fn iwdg() -> &'static pac::iwdg::RegisterBlock {
    unsafe { &*pac::IWDG::ptr() }
}
#[inline(always)]
pub(crate) fn tim5() -> &'static pac::tim5::RegisterBlock {
    unsafe { &*pac::TIM5::ptr() }
}
#[inline(always)]
pub(crate) fn exti() -> &'static pac::exti::RegisterBlock {
    unsafe { &*pac::EXTI::ptr() }
}
#[inline(always)]
pub(crate) fn syscfg() -> &'static pac::syscfg::RegisterBlock {
    unsafe { &*pac::SYSCFG::ptr() }
}
#[inline(always)]
pub(crate) fn flash() -> &'static pac::flash::RegisterBlock {
    unsafe { &*pac::FLASH::ptr() }
}
#[inline(always)]
pub(crate) fn pwr() -> &'static pac::pwr::RegisterBlock {
    unsafe { &*pac::PWR::ptr() }
}
#[inline(always)]
pub(crate) fn usart1() -> &'static pac::usart1::RegisterBlock {
    unsafe { &*pac::USART1::ptr() }
}
/// A GPIO port's registers (GPIOA..GPIOI share one layout, RM0090 sec. 8.4), from the PAC's own
/// pointer of each port (its `gpiob`/`gpioi` types have the same layout as `gpioa`'s). Only
/// MODER/PUPDR (modify), IDR/ODR (read) and BSRR (write from 0) are used, so GPIOA's reset values
/// in the PAC's type never leak into another port. `port` is one of the constants above (a
/// constant at every call, so the match folds away); the pin types check that at compile time.
#[inline(always)]
pub(crate) fn gpio(port: u8) -> &'static pac::gpioa::RegisterBlock {
    let p: *const pac::gpioa::RegisterBlock = match port {
        PA => pac::GPIOA::ptr(),
        PB => pac::GPIOB::ptr().cast(),
        PD => pac::GPIOD::ptr().cast(),
        PE => pac::GPIOE::ptr().cast(),
        _ => pac::GPIOI::ptr().cast(),
    };
    // SAFETY: a GPIO port's register block, valid for the whole program.
    unsafe { &*p }
}
/// Whether `port` is one the board uses (the pin types assert it at compile time).
const fn known_port(port: u8) -> bool {
    matches!(port, PA | PB | PD | PE | PI)
}

/// The core clock (SysTick) and TIM2's input clock: the 16 MHz HSI on the board. QEMU 7.2's
/// netduinoplus2 clocks the core at 168 MHz and its timers at 1 GHz whatever RCC says, so the
/// `qemu-io` build scales both to keep a 1 MHz `Clock` and a `TICK_US` tick there.
#[cfg(not(feature = "qemu-clock"))]
pub(crate) const CORE_HZ: u32 = 16_000_000;
#[cfg(not(feature = "qemu-clock"))]
pub(crate) const TIM2_HZ: u32 = 16_000_000;
#[cfg(feature = "qemu-clock")]
pub(crate) const CORE_HZ: u32 = 168_000_000;
#[cfg(feature = "qemu-clock")]
pub(crate) const TIM2_HZ: u32 = 1_000_000_000;
pub(crate) const TICK_US: u32 = 1_000;

/// The memory map: the MPU guard at the bottom of the stack, bytes (a power of two >= 32, RM0090/PM0214 MPU_RASR):
/// more than one exception frame with the FPU state (108 B), so that no frame push skips it.
pub(crate) const GUARD_BYTES: u32 = 256;

// ---- The three pin accesses: GPIO in the production build, the QEMU bench's RAM with
// `qemu-io` (QEMU 7.2 does not model the F405's GPIO; `support/board_pin_image.rs`) -------------------
/// A port's input register.
#[inline(always)]
pub(crate) fn idr(port: u8) -> u32 {
    #[cfg(not(feature = "qemu-io"))]
    return gpio(port).idr().read().bits();
    #[cfg(feature = "qemu-io")]
    return crate::pin_image::idr(port);
}
/// A write to a port's bit set/reset register.
#[inline(always)]
pub(crate) fn bsrr(port: u8, v: u32) {
    // SAFETY: BSRR takes any bit pattern (a set or reset request per pin).
    gpio(port).bsrr().write(|w| unsafe { w.bits(v) });
    #[cfg(feature = "qemu-io")]
    crate::pin_image::bsrr(port, v);
}

// ---- Pins: zero-sized, the port and pin are constants, so a write is a single `str` ------------
/// A push-pull output on `PORT`, pin `N`, written through BSRR (atomic, no read-modify-write), and
/// read back at the pin through IDR (`InputPin`): the level the pin really has, which a stuck pin
/// or a frozen port no longer makes follow the write (`flinch_firmware::output_monitor`).
pub(crate) struct Out<const PORT: u8, const N: u32>;
impl<const PORT: u8, const N: u32> Out<PORT, N> {
    const CHECKED: () = assert!(known_port(PORT) && N < 16);
}
impl<const PORT: u8, const N: u32> ErrorType for Out<PORT, N> {
    type Error = Infallible;
}
impl<const PORT: u8, const N: u32> OutputPin for Out<PORT, N> {
    #[inline(always)]
    fn set_low(&mut self) -> Result<(), Infallible> {
        let () = Self::CHECKED;
        bsrr(PORT, 1 << (N + 16));
        Ok(())
    }
    #[inline(always)]
    fn set_high(&mut self) -> Result<(), Infallible> {
        let () = Self::CHECKED;
        bsrr(PORT, 1 << N);
        Ok(())
    }
}
impl<const PORT: u8, const N: u32> InputPin for Out<PORT, N> {
    #[inline(always)]
    fn is_high(&mut self) -> Result<bool, Infallible> {
        Ok(idr(PORT) & (1 << N) != 0)
    }
    #[inline(always)]
    fn is_low(&mut self) -> Result<bool, Infallible> {
        Ok(idr(PORT) & (1 << N) == 0)
    }
}
/// An input on `PORT`, pin `N`, read from IDR.
pub(crate) struct In<const PORT: u8, const N: u32>;
impl<const PORT: u8, const N: u32> In<PORT, N> {
    const CHECKED: () = assert!(known_port(PORT) && N < 16);
}
impl<const PORT: u8, const N: u32> ErrorType for In<PORT, N> {
    type Error = Infallible;
}
impl<const PORT: u8, const N: u32> InputPin for In<PORT, N> {
    #[inline(always)]
    fn is_high(&mut self) -> Result<bool, Infallible> {
        let () = Self::CHECKED;
        Ok(idr(PORT) & (1 << N) != 0)
    }
    #[inline(always)]
    fn is_low(&mut self) -> Result<bool, Infallible> {
        Ok(idr(PORT) & (1 << N) == 0)
    }
}

/// TIM2 as a 1 MHz, 32-bit free-running counter.
pub(crate) struct Tim2;
impl Clock for Tim2 {
    #[inline(always)]
    fn now(&mut self) -> Micros {
        Micros(tim2().cnt().read().bits())
    }
    /// LSI periods counted by TIM5's channel 4 (`lsi_capture`): the independent reference.
    fn reference_ticks(&mut self) -> Option<u32> {
        Some(LSI_PERIODS.load(Relaxed))
    }
}

/// The clock check's reference: the LSI (the IWDG's own RC oscillator, independent of the HSI
/// behind TIM2 and SysTick). The F4 can only route it to TIM5's channel 4 capture input
/// (`TIM5_OR.TI4_RMP = 01`, RM0090 sec. 18.4.21), which timestamps edges and does not count
/// them; the counting adapter is the capture interrupt: every 8th LSI rising edge
/// (`IC4PSC = /8`) captures, and `lsi_capture` adds 8 (16 if the capture before was overwritten).
/// 4 kHz of a short interrupt at the tick's priority, below the edge.
pub(crate) static LSI_PERIODS: AtomicU32 = AtomicU32::new(0);
/// Nominal LSI, hertz; DS8626 specifies 17 to 47 kHz, hence the wide tolerance in `config`.
pub(crate) const LSI_HZ: u32 = 32_000;

pub(crate) fn lsi_capture() {
    let t = tim5();
    let _ = t.ccr4().read(); // reading CCR4 clears CC4IF
    let sr = t.sr().read().bits();
    let mut n = 8;
    if sr & (1 << 12) != 0 {
        // CC4OF: a capture was overwritten before this one was read: 8 more periods.
        n += 8;
        // SAFETY: rc_w0 flags: write 0 to CC4OF only, 1 elsewhere leaves the others.
        t.sr().write(|w| unsafe { w.bits(!(1 << 12)) });
    }
    LSI_PERIODS.fetch_add(n, Relaxed);
}

/// Drop every output with three register writes, K1, K2, then the escalation (usable from any
/// context, even before init or with no usable stack: no RAM besides the registers).
#[inline(always)]
pub(crate) fn emergency_stop() {
    bsrr(K1_PORT, 1 << (K1_PIN + 16));
    bsrr(K2_PORT, 1 << (K2_PIN + 16));
    bsrr(ESC_PORT, 1 << (ESC_PIN + 16));
}
