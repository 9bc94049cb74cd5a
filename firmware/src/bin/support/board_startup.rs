//! The board's start-up integrity (`flinch_firmware::integrity`, `flinch_firmware::option_bytes`):
//! the outputs driven low before RAM is used, the March C- RAM test, the flash CRC against
//! `FLINCH_FLASH_CRC`, the brown-out level through the option bytes, the `qemu-clock` guard, and the
//! permanent stop a failed check ends in.

use crate::backup::{backup_on, stored_boots, Bkp};
#[cfg(feature = "qemu-clock")]
use crate::backup::BKPSRAM_WORDS;
use crate::hw::{emergency_stop, flash, gpio, rcc, ESC_PIN, ESC_PORT, K1_PIN, K1_PORT, K2_PIN, K2_PORT, SUPPLY_PIN, SUPPLY_PORT};
use core::ptr::{read_volatile, write_volatile};
use flinch_firmware::option_bytes::{self, OptionBytes};
#[cfg(feature = "qemu-clock")]
use flinch_firmware::BackupRam;
use flinch_firmware::{backup, integrity, Cause, EventLog, Micros, Retained};

// ---- Start-up integrity checks (`flinch_firmware::integrity`) ---------------------------------
/// The CRC-32 of the flash image with this word counted as zeros; written into the ELF after the
/// link by `cargo xtask` (`patch_flash_crc`). An image that was not patched (0) or was changed
/// after patching fails the check and never arms.
#[no_mangle]
#[used]
pub(crate) static FLINCH_FLASH_CRC: u32 = 0;
/// The production build checks its image with the production seed; every `qemu-clock` build
/// (the `qemu-io` bench and the serial test: their tick is scaled for QEMU), which must never run
/// the machine, is patched (xtask) and checked with its own, so its stored CRC fails the
/// production check (`integrity::Seed`; host test `a_bench_image_fails_the_production_check`).
#[cfg(not(feature = "qemu-clock"))]
pub(crate) const FLASH_SEED: integrity::Seed = integrity::Seed::Production;
#[cfg(feature = "qemu-clock")]
pub(crate) const FLASH_SEED: integrity::Seed = integrity::Seed::QemuBench;

extern "C" {
    // cortex-m-rt's linker script (link.x): .data's run and load addresses, the end of .bss.
    static mut __sdata: u32;
    static mut __edata: u32;
    static mut __ebss: u32;
    static __sidata: u32;
}
pub(crate) const FLASH_START: u32 = 0x0800_0000;
pub(crate) const RAM_START: u32 = 0x2000_0000;
/// Stack kept out of the RAM test: main's and the test's own frames live there.
pub(crate) const STACK_KEEP: u32 = 1024;

/// The flash image: the vector table, .text and .rodata (contiguous from the start of flash, as
/// cortex-m-rt's link.x lays them out and xtask checks), then .data's load image.
pub(crate) fn flash_crc_ok() -> bool {
    let (image, crc_at, stored) = flash_image();
    integrity::image_crc_seeded(image, crc_at, FLASH_SEED) == stored
}

/// The flash image as the CRC covers it, the stored word's offset in it, and the stored word; for
/// the start-up check and the periodic one (`board_diag.rs`).
pub(crate) fn flash_image() -> (&'static [u8], usize, u32) {
    let end = core::ptr::addr_of!(__sidata) as u32 + (core::ptr::addr_of!(__edata) as u32 - core::ptr::addr_of!(__sdata) as u32);
    let crc_at = core::ptr::addr_of!(FLINCH_FLASH_CRC) as u32;
    // SAFETY: flash from its start to the end of .data's load image: mapped, read-only,
    // never written while running.
    let image = unsafe { core::slice::from_raw_parts(FLASH_START as *const u8, (end - FLASH_START) as usize) };
    // SAFETY: a static in flash; volatile so that the compiler does not fold in the 0 it was
    // linked with (xtask patched the ELF afterwards).
    let stored = unsafe { read_volatile(core::ptr::addr_of!(FLINCH_FLASH_CRC)) };
    (image, (crc_at - FLASH_START) as usize, stored)
}

/// March C- with four data backgrounds over the RAM the firmware will use: .data and .bss, and
/// the stack region below the frames in use now (flip-link puts the stack at the bottom of RAM);
/// not the top `STACK_KEEP` bytes of the stack (the latch and the log are in backup SRAM, not RAM).
/// Restores .data from its load image afterwards (the test leaves zeros, which is .bss's value).
///
/// # Safety
/// Only as the first thing in `main`: no reference to a static may be live.
pub(crate) unsafe fn ram_test() -> bool {
    let sdata = core::ptr::addr_of_mut!(__sdata);
    let data_words = (core::ptr::addr_of!(__edata) as usize - sdata as usize) / 4;
    let ram_words = (core::ptr::addr_of!(__ebss) as usize - sdata as usize) / 4;
    let sp = cortex_m::register::msp::read();
    let stack_words = (sp.saturating_sub(STACK_KEEP).saturating_sub(RAM_START) / 4) as usize;
    let statics_ok = integrity::march_c_minus(&mut integrity::RawRam::new(sdata, ram_words), &integrity::BACKGROUNDS).is_ok();
    let stack_ok = integrity::march_c_minus(&mut integrity::RawRam::new(RAM_START as *mut u32, stack_words), &integrity::BACKGROUNDS).is_ok();
    let sidata = core::ptr::addr_of!(__sidata);
    for i in 0..data_words {
        write_volatile(sdata.wrapping_add(i), read_volatile(sidata.wrapping_add(i)));
    }
    statics_ok && stack_ok
}

/// What failed at start-up: the [`Cause::SelfCheck`] event's flags.
pub(crate) const SELF_RAM: u8 = 1;
pub(crate) const SELF_FLASH: u8 = 2;
pub(crate) const SELF_BOR: u8 = 3;
/// A `qemu-clock` image (bench or serial test) found real GPIO (it runs on silicon, not in QEMU).
#[cfg(feature = "qemu-clock")]
pub(crate) const SELF_NOT_QEMU: u8 = 4;

/// The backup SRAM word the qemu-clock guard writes and reads back: past every record (the
/// latch, the log, the BOR-pending mark at word 96), inside the 1 KB QEMU maps.
#[cfg(feature = "qemu-clock")]
pub(crate) const NOT_QEMU_PROBE_AT: usize = BKPSRAM_WORDS - 1;
#[cfg(feature = "qemu-clock")]
pub(crate) const NOT_QEMU_PROBE: u32 = 0x5153_4D55; // "QEMU"

/// The qemu-clock guard: `None` only when two independent checks both say "QEMU". (1) GPIOD's
/// MODER, written by `early_outputs_low` after the clock enable and a DSB, reads back the
/// outputs on silicon and 0 in QEMU 7.2 (GPIO not modelled). (2) A test word written to the
/// backup SRAM (clocked and opened by `backup_on`, with DSBs) reads back on silicon and 0 in QEMU
/// (unimplemented device: writes ignored). Any non-zero read of either stops: on silicon a lost
/// write leaves the other check, and a backup SRAM whose write was lost reads its old (power-on:
/// arbitrary) content. The flags' detail: bit 0 = MODER, bit 1 = backup SRAM.
#[cfg(feature = "qemu-clock")]
pub(crate) fn not_qemu() -> Option<i32> {
    let moder = gpio(K1_PORT).moder().read().bits() & ((0b11 << (2 * K1_PIN)) | (0b11 << (2 * SUPPLY_PIN))) != 0;
    let mut b = Bkp;
    b.write(NOT_QEMU_PROBE_AT, NOT_QEMU_PROBE);
    cortex_m::asm::dsb();
    let bkp = b.read(NOT_QEMU_PROBE_AT) != 0;
    let which = i32::from(moder) | (i32::from(bkp) << 1);
    if which != 0 {
        Some(which)
    } else {
        None
    }
}

/// The option bytes through the flash interface's registers (`flinch_firmware::option_bytes`:
/// BOR level 3 programmed once, error flags checked, verified at the next boot).
pub(crate) struct OptionRegs;
impl OptionBytes for OptionRegs {
    fn bor_level(&mut self) -> u8 {
        flash().optcr().read().bor_lev().bits()
    }
    fn status(&mut self) -> u32 {
        flash().sr().read().bits()
    }
    fn clear_status(&mut self, flags: u32) {
        // SAFETY: FLASH_SR's flags are write-1-to-clear; only error flags are passed.
        flash().sr().write(|w| unsafe { w.bits(flags & option_bytes::SR_ERRORS) });
    }
    fn unlock(&mut self) {
        // SAFETY (both): the option-byte unlock keys of RM0090 sec. 3.6.2.
        flash().optkeyr().write(|w| unsafe { w.optkeyr().bits(0x0819_2A3B) });
        flash().optkeyr().write(|w| unsafe { w.optkeyr().bits(0x4C5D_6E7F) });
    }
    fn program_bor(&mut self, level: u8) {
        // SAFETY: a 2-bit BOR_LEV value; read-modify-write keeps RDP, WRP and the user bits.
        flash().optcr().modify(|_, w| unsafe { w.bor_lev().bits(level) });
        flash().optcr().modify(|_, w| w.optstrt().set_bit());
    }
    fn lock(&mut self) {
        flash().optcr().modify(|_, w| w.optlock().set_bit());
    }
}
/// The bound on the wait for FLASH_SR.BSY after OPTSTRT: status reads, about 10 cycles each at
/// 16 MHz, so about 10 s (an option-byte write takes milliseconds).
pub(crate) const BOR_BUSY_SPINS: u32 = 16_000_000;

/// A start-up integrity check failed: outputs low, the `SelfCheck` latch and an event (`what`,
/// `detail`) in the backup SRAM, then stopped for good. Nothing can re-arm: the IWDG is started
/// only after these checks (so no watchdog reset re-runs them), no interrupt is enabled, and no
/// `Firmware` exists; only a power cycle or the NRST pin starts the part again, and that start
/// is latched by the record until a reset press. Uses no static: after a failed RAM test
/// .data and .bss hold test patterns.
pub(crate) fn integrity_failed(what: u8, detail: i32) -> ! {
    emergency_stop();
    backup_on();
    let mut b = Bkp;
    backup::store_latch(&mut b, Retained::new(Some(Cause::SelfCheck), stored_boots()));
    let mut log: EventLog<16> = backup::load_log(&mut b).unwrap_or_default();
    log.push(Cause::SelfCheck, what, Micros(0), Micros(0), detail);
    backup::store_log(&mut b, &log);
    loop {
        emergency_stop();
        cortex_m::asm::wfi(); // no interrupt is enabled: sleeps for good
    }
}

/// Before anything else, by register writes that need no RAM: the three output ports clocked
/// (GPIOB, GPIOD, GPIOE), both stop channels, the escalation and the sensor supply written low
/// (BSRR) and made outputs. A RAM test that fails or hangs from here on leaves the outputs driven
/// low, not floating.
#[inline(always)]
pub(crate) fn early_outputs_low() {
    rcc().ahb1enr().modify(|_, w| w.gpioben().set_bit().gpioden().set_bit().gpioeen().set_bit());
    // The errata's delay after an RCC clock enable (see `backup_on`): without it the MODER writes
    // below can be lost on silicon, which would also blind the qemu-clock guard's MODER check.
    cortex_m::asm::dsb();
    // SAFETY (all four): BSRR takes any pattern (a reset request per pin). Written directly, not
    // through `hw::bsrr`: the qemu-io bench's RAM must not be touched before the RAM test.
    gpio(K1_PORT).bsrr().write(|w| unsafe { w.bits((1 << (K1_PIN + 16)) | (1 << (SUPPLY_PIN + 16))) });
    gpio(K2_PORT).bsrr().write(|w| unsafe { w.bits(1 << (K2_PIN + 16)) });
    gpio(ESC_PORT).bsrr().write(|w| unsafe { w.bits(1 << (ESC_PIN + 16)) });
    outputs_mode();
}

/// The output pins become outputs (after they were written low, so they never glitch high): K1,
/// the sensor supply, K2, the escalation. Read-modify-writes of MODER, registers only.
#[inline(always)]
pub(crate) fn outputs_mode() {
    const _: () = assert!(K1_PORT == SUPPLY_PORT, "one MODER write for K1 and the supply");
    let d = (0b11 << (2 * K1_PIN)) | (0b11 << (2 * SUPPLY_PIN));
    let d_out = (0b01 << (2 * K1_PIN)) | (0b01 << (2 * SUPPLY_PIN));
    // SAFETY (all three): two-bit mode fields, 0b01 = general-purpose output.
    gpio(K1_PORT).moder().modify(|r, w| unsafe { w.bits((r.bits() & !d) | d_out) });
    gpio(K2_PORT).moder().modify(|r, w| unsafe { w.bits((r.bits() & !(0b11 << (2 * K2_PIN))) | (0b01 << (2 * K2_PIN))) });
    gpio(ESC_PORT).moder().modify(|r, w| unsafe { w.bits((r.bits() & !(0b11 << (2 * ESC_PIN))) | (0b01 << (2 * ESC_PIN))) });
}
