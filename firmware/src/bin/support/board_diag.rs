//! The board's periodic self-tests (`flinch_firmware::diagnostics`, IEC 60730-1 Annex H style),
//! run in thread mode once per tick (after the log drain, between interrupts), never inside one:
//!
//! | check | per step | period |
//! |---|---|---|
//! | flash CRC (the start-up CRC again, incrementally) | `FLASH_CHUNK` = 32 B | one pass = image / 32 ticks (about 1.4 s for a 45 KB image); a flipped bit is found within two passes |
//! | RAM of the safety state (the `Firmware` object): March C-, one data background, `RAM_BLOCK` = 2 words saved, tested, restored, with the tick and the bookkeeping masked | 2 words | one pass = words / 2 ticks; all four backgrounds in four passes |
//! | peripheral configuration read back (`EXPECTED`) | all registers | every `CONFIG_EVERY` = 16 ticks |
//!
//! A failure is handed to the tick (`DIAG_FAULT`), which latches `Cause::Diagnostic`
//! (`Firmware::diagnostic_failed`): every output drops, the watchdog starves. In the `qemu-clock`
//! builds the registers QEMU 7.2 does not model (RCC, GPIO, IWDG: they read 0) are left out of the
//! read-back; everything else is the production code.

use crate::fw::{Fw, FW, PRIO_EDGE, PRIO_TICK};
use crate::hw::{exti, syscfg, tim2, CORE_HZ, TICK_US};
#[cfg(not(feature = "qemu-clock"))]
use crate::hw::{gpio, iwdg, rcc, ESC_PIN, ESC_PORT, K1_PIN, K1_PORT, K2_PIN, K2_PORT, PA, SUPPLY_PIN};
use crate::startup::{flash_image, FLASH_SEED};
use core::sync::atomic::{AtomicI32, AtomicU32, AtomicU8, Ordering::Relaxed};
use flinch_firmware::diagnostics::{check_config, march_block_transparent, Check, Expect, FlashCrc, Schedule};
use flinch_firmware::integrity::{RawRam, BACKGROUNDS};

/// Flash bytes a step.
const FLASH_CHUNK: usize = 32;
/// Words of the safety state a RAM step tests.
const RAM_BLOCK: usize = 2;
/// The configuration read-back every this many steps (ticks).
const CONFIG_EVERY: u32 = 16;

/// A failed check for the tick to latch: its `Check` code (0: none) and detail.
pub(crate) static DIAG_FAULT: AtomicU8 = AtomicU8::new(0);
pub(crate) static DIAG_DETAIL: AtomicI32 = AtomicI32::new(0);
/// Ticks counted by SysTick: one diagnostic step per tick.
pub(crate) static TICKS: AtomicU32 = AtomicU32::new(0);

/// The registers read back, by index (`read`).
#[derive(Copy, Clone)]
#[repr(u8)]
#[cfg_attr(feature = "qemu-clock", allow(dead_code))] // the unmodelled ones are read on the part only
enum Reg {
    ExtiImr,
    ExtiRtsr,
    ExtiFtsr,
    ExtiCr1,
    ExtiCr2,
    NvicIpr1,
    NvicIpr2,
    NvicIpr7,
    NvicIpr9,
    NvicIpr12,
    NvicIpr13,
    NvicIser0,
    NvicIser1,
    Shpr1,
    Shpr3,
    Shcsr,
    SystCsr,
    SystRvr,
    MpuCtrl,
    MpuRbar,
    MpuRasr,
    Tim2Cr1,
    Tim2Psc,
    GpioDModer,
    GpioEModer,
    GpioBModer,
    GpioAModer,
    GpioAPupdr,
    RccAhb1,
    RccApb1,
    RccApb2,
    IwdgPr,
    IwdgRlr,
}

const fn e(reg: Reg, mask: u32, value: u32) -> Expect {
    Expect { reg: reg as u8, mask, value }
}
const fn prio(irq: u32, p: u8) -> (u32, u32) {
    (0xFF << (8 * (irq % 4)), (p as u32) << (8 * (irq % 4)))
}
const NVIC_EDGE0: (u32, u32) = prio(6, PRIO_EDGE); // EXTI0, IPR1
const NVIC_EDGE4: (u32, u32) = prio(10, PRIO_EDGE); // EXTI4, IPR2
const NVIC_STEP: (u32, u32) = prio(29, 0xC0); // TIM3's line, IPR7
const NVIC_USART: (u32, u32) = prio(37, 0x40); // USART1, IPR9
const NVIC_TIM5: (u32, u32) = prio(50, PRIO_TICK); // TIM5, IPR12
const NVIC_BOOK: (u32, u32) = prio(53, PRIO_TICK); // UART5's line, IPR13

/// What the board wrote at start-up (`board.rs` main, `board_faults.rs`, `board_avoid.rs`).
const COMMON: [Expect; 23] = [
    e(Reg::ExtiImr, 0x11, 0x11),
    e(Reg::ExtiRtsr, 0x11, 0x11),
    e(Reg::ExtiFtsr, 0x11, 0x11),
    e(Reg::ExtiCr1, 0xF, 0), // EXTI0 <- port A
    e(Reg::ExtiCr2, 0xF, 0), // EXTI4 <- port A
    e(Reg::NvicIpr1, NVIC_EDGE0.0, NVIC_EDGE0.1),
    e(Reg::NvicIpr2, NVIC_EDGE4.0, NVIC_EDGE4.1),
    e(Reg::NvicIpr7, NVIC_STEP.0, NVIC_STEP.1),
    e(Reg::NvicIpr9, NVIC_USART.0, NVIC_USART.1),
    e(Reg::NvicIpr12, NVIC_TIM5.0, NVIC_TIM5.1),
    e(Reg::NvicIpr13, NVIC_BOOK.0, NVIC_BOOK.1),
    e(Reg::NvicIser0, (1 << 6) | (1 << 10) | (1 << 29), (1 << 6) | (1 << 10) | (1 << 29)),
    e(Reg::NvicIser1, (1 << 5) | (1 << 18) | (1 << 21), (1 << 5) | (1 << 18) | (1 << 21)),
    e(Reg::Shpr1, 0x00FF_FFFF, 0), // MemManage, BusFault, UsageFault at 0
    e(Reg::Shpr3, 0xFF << 24, (PRIO_TICK as u32) << 24), // SysTick
    e(Reg::Shcsr, 0b111 << 16, 0b111 << 16), // MEMFAULTENA, BUSFAULTENA, USGFAULTENA
    e(Reg::SystCsr, 0b111, 0b111), // ENABLE, TICKINT, CLKSOURCE = core
    e(Reg::SystRvr, 0x00FF_FFFF, CORE_HZ / 1_000_000 * TICK_US - 1),
    e(Reg::MpuCtrl, 0b111, 0b101), // ENABLE, PRIVDEFENA, not HFNMIENA
    e(Reg::MpuRbar, 0xFFFF_FFE0, 0x2000_0000),
    e(Reg::MpuRasr, 0x1707_003F, (1 << 28) | ((crate::hw::GUARD_BYTES.trailing_zeros() - 1) << 1) | 1),
    e(Reg::Tim2Cr1, 1, 1), // CEN
    e(Reg::Tim2Psc, 0xFFFF, crate::hw::TIM2_HZ / 1_000_000 - 1),
];

/// The registers QEMU does not model (read 0 there): only in the production build.
#[cfg(not(feature = "qemu-clock"))]
const BOARD_ONLY: [Expect; 10] = [
    e(Reg::GpioDModer, (0b11 << (2 * K1_PIN)) | (0b11 << (2 * SUPPLY_PIN)), (0b01 << (2 * K1_PIN)) | (0b01 << (2 * SUPPLY_PIN))),
    e(Reg::GpioEModer, 0b11 << (2 * K2_PIN), 0b01 << (2 * K2_PIN)),
    e(Reg::GpioBModer, 0b11 << (2 * ESC_PIN), 0b01 << (2 * ESC_PIN)),
    e(Reg::GpioAModer, 0x3FF | (0b1111 << 18), 0b1010 << 18), // PA0..4 inputs, PA9/PA10 AF
    e(Reg::GpioAPupdr, 0x3FF, 0b01_10_10_10_10),
    e(Reg::RccAhb1, (1 << 0) | (1 << 1) | (1 << 3) | (1 << 4) | (1 << 18), (1 << 0) | (1 << 1) | (1 << 3) | (1 << 4) | (1 << 18)),
    e(Reg::RccApb1, (1 << 0) | (1 << 3) | (1 << 28), (1 << 0) | (1 << 3) | (1 << 28)), // TIM2, TIM5, PWR
    e(Reg::RccApb2, (1 << 4) | (1 << 14), (1 << 4) | (1 << 14)), // USART1, SYSCFG
    e(Reg::IwdgPr, 0b111, 0),
    e(Reg::IwdgRlr, 0xFFF, 64),
];

fn read(reg: u8) -> u32 {
    // SAFETY (the core registers): reads of cortex-m's NVIC, SCB, SysTick and MPU blocks.
    let (nvic, scb, syst, mpu) = unsafe {
        (
            &*cortex_m::peripheral::NVIC::PTR,
            &*cortex_m::peripheral::SCB::PTR,
            &*cortex_m::peripheral::SYST::PTR,
            &*cortex_m::peripheral::MPU::PTR,
        )
    };
    let ipr = |n: usize| -> u32 {
        (0..4).fold(0, |w, k| w | (u32::from(nvic.ipr.get(4 * n + k).map_or(0, |r| r.read())) << (8 * k)))
    };
    match reg {
        r if r == Reg::ExtiImr as u8 => exti().imr().read().bits(),
        r if r == Reg::ExtiRtsr as u8 => exti().rtsr().read().bits(),
        r if r == Reg::ExtiFtsr as u8 => exti().ftsr().read().bits(),
        r if r == Reg::ExtiCr1 as u8 => syscfg().exticr1().read().bits(),
        r if r == Reg::ExtiCr2 as u8 => syscfg().exticr2().read().bits(),
        r if r == Reg::NvicIpr1 as u8 => ipr(1),
        r if r == Reg::NvicIpr2 as u8 => ipr(2),
        r if r == Reg::NvicIpr7 as u8 => ipr(7),
        r if r == Reg::NvicIpr9 as u8 => ipr(9),
        r if r == Reg::NvicIpr12 as u8 => ipr(12),
        r if r == Reg::NvicIpr13 as u8 => ipr(13),
        r if r == Reg::NvicIser0 as u8 => nvic.iser[0].read(),
        r if r == Reg::NvicIser1 as u8 => nvic.iser[1].read(),
        r if r == Reg::Shpr1 as u8 => (0..3).fold(0, |w, k| w | (u32::from(scb.shpr[k].read()) << (8 * k))),
        r if r == Reg::Shpr3 as u8 => u32::from(scb.shpr[11].read()) << 24,
        r if r == Reg::Shcsr as u8 => scb.shcsr.read(),
        r if r == Reg::SystCsr as u8 => syst.csr.read(),
        r if r == Reg::SystRvr as u8 => syst.rvr.read(),
        r if r == Reg::MpuCtrl as u8 => mpu.ctrl.read(),
        r if r == Reg::MpuRbar as u8 => mpu.rbar.read(),
        r if r == Reg::MpuRasr as u8 => mpu.rasr.read(),
        r if r == Reg::Tim2Cr1 as u8 => tim2().cr1().read().bits(),
        r if r == Reg::Tim2Psc as u8 => tim2().psc().read().bits(),
        #[cfg(not(feature = "qemu-clock"))]
        r if r == Reg::GpioDModer as u8 => gpio(K1_PORT).moder().read().bits(),
        #[cfg(not(feature = "qemu-clock"))]
        r if r == Reg::GpioEModer as u8 => gpio(K2_PORT).moder().read().bits(),
        #[cfg(not(feature = "qemu-clock"))]
        r if r == Reg::GpioBModer as u8 => gpio(ESC_PORT).moder().read().bits(),
        #[cfg(not(feature = "qemu-clock"))]
        r if r == Reg::GpioAModer as u8 => gpio(PA).moder().read().bits(),
        #[cfg(not(feature = "qemu-clock"))]
        r if r == Reg::GpioAPupdr as u8 => gpio(PA).pupdr().read().bits(),
        #[cfg(not(feature = "qemu-clock"))]
        r if r == Reg::RccAhb1 as u8 => rcc().ahb1enr().read().bits(),
        #[cfg(not(feature = "qemu-clock"))]
        r if r == Reg::RccApb1 as u8 => rcc().apb1enr().read().bits(),
        #[cfg(not(feature = "qemu-clock"))]
        r if r == Reg::RccApb2 as u8 => rcc().apb2enr().read().bits(),
        #[cfg(not(feature = "qemu-clock"))]
        r if r == Reg::IwdgPr as u8 => u32::from(iwdg().pr().read().bits()),
        #[cfg(not(feature = "qemu-clock"))]
        r if r == Reg::IwdgRlr as u8 => u32::from(iwdg().rlr().read().bits()),
        _ => 0,
    }
}

/// The thread-mode state of the checks.
pub(crate) struct Diag {
    flash: FlashCrc,
    schedule: Schedule,
    last_tick: u32,
}

impl Diag {
    pub(crate) const fn new() -> Self {
        Diag { flash: FlashCrc::new(FLASH_SEED), schedule: Schedule::new(), last_tick: 0 }
    }

    /// One step if a tick has come since the last one (thread mode, after the log drain).
    pub(crate) fn run(&mut self) {
        let t = TICKS.load(Relaxed);
        if t == self.last_tick {
            return;
        }
        self.last_tick = t;
        let (image, crc_at, stored) = flash_image();
        if self.flash.step(image, crc_at, stored, FLASH_CHUNK) == Some(false) {
            fail(Check::Flash, 0);
        }
        let words = core::mem::size_of::<crate::isr_cell::IsrCell<Fw>>() / 4;
        let due = self.schedule.next(words, RAM_BLOCK, 1, CONFIG_EVERY, BACKGROUNDS.len());
        if let Some((at, bg)) = due.ram {
            // SAFETY: BASEPRI = the tick's priority masks the tick and the bookkeeping, FW's only
            // users (the edge never touches it); the block is saved and restored before BASEPRI is
            // lowered, so no reader ever sees the test patterns. The words are inside FW's static.
            let r = unsafe {
                cortex_m::register::basepri::write(PRIO_TICK);
                #[cfg(feature = "qemu-io")]
                let t0 = crate::bench::start();
                let base = core::ptr::addr_of!(FW) as *mut u32;
                let r = march_block_transparent(&mut RawRam::new(base, words), at, RAM_BLOCK, BACKGROUNDS.get(bg..=bg).unwrap_or(&[]));
                #[cfg(feature = "qemu-io")]
                crate::bench::note(&crate::bench::W_MASK_DIAG, t0, false);
                cortex_m::register::basepri::write(0);
                r
            };
            if let Err(f) = r {
                fail(Check::Ram, f.index as i32);
            }
        }
        if due.config {
            let common = check_config(&COMMON, read);
            #[cfg(not(feature = "qemu-clock"))]
            let common = common.and_then(|()| check_config(&BOARD_ONLY, read));
            if let Err((reg, _)) = common {
                fail(Check::Config, i32::from(reg));
            }
        }
    }
}

fn fail(check: Check, detail: i32) {
    DIAG_DETAIL.store(detail, Relaxed);
    DIAG_FAULT.store(check as u8, Relaxed);
}

/// From the tick: a failed check, to latch.
pub(crate) fn take_failure() -> Option<(Check, i32)> {
    let code = DIAG_FAULT.swap(0, Relaxed);
    let check = match code {
        1 => Check::Flash,
        2 => Check::Ram,
        3 => Check::Config,
        _ => return None,
    };
    Some((check, DIAG_DETAIL.load(Relaxed)))
}
