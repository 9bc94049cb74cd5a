//! The board's backup SRAM (`flinch_firmware::backup`): the latch and the event log across
//! resets, the backup domain switched on, and the latch stored only when it changes.

use crate::hw::{pwr, rcc};
use core::ptr::{read_volatile, write_volatile};
use core::sync::atomic::{AtomicU32, Ordering::Relaxed};
use flinch_firmware::{backup, BackupRam, Retained};

// ---- Backup SRAM: the latch and the event log across resets (`flinch_firmware::backup`) -----
/// The backup SRAM (RM0090 sec. 2.3 and 5.1.2): 4 KB at 0x4002_4000 in the backup domain, which
/// no system reset clears (watchdog, software, pin, a brown-out with VDD back). Only its first
/// 1 KB is used (the records need 72 words): QEMU 7.2's netduinoplus2 maps 1 KB there, as an
/// unimplemented device (reads 0, writes ignored).
pub(crate) const BKPSRAM: u32 = 0x4002_4000;
pub(crate) const BKPSRAM_WORDS: usize = 256;

/// The backup SRAM as the library's `BackupRam`.
pub(crate) struct Bkp;
impl BackupRam for Bkp {
    fn len(&self) -> usize {
        BKPSRAM_WORDS
    }
    fn read(&mut self, i: usize) -> u32 {
        if i >= BKPSRAM_WORDS {
            return 0;
        }
        // SAFETY: a word in the backup SRAM's first KB, clocked by `backup_on`.
        unsafe { read_volatile((BKPSRAM as *const u32).wrapping_add(i)) }
    }
    fn write(&mut self, i: usize, v: u32) {
        if i < BKPSRAM_WORDS {
            // SAFETY: as for `read`; DBP set by `backup_on`.
            unsafe { write_volatile((BKPSRAM as *mut u32).wrapping_add(i), v) }
        }
    }
}

/// Clock the backup SRAM and open the backup domain to writes: PWREN, BKPSRAMEN, PWR_CR.DBP
/// (RM0090 sec. 5.1.2). Register writes only, no RAM: usable before the RAM test has passed and
/// from the fault handlers. The backup regulator (BRE) is left off: without a VBAT cell the
/// content does not survive a power cycle, and what a power-on leaves fails the records' CRCs,
/// i.e. reads as a clean power-on (`backup.rs`).
pub(crate) fn backup_on() {
    rcc().apb1enr().modify(|_, w| w.pwren().set_bit());
    rcc().ahb1enr().modify(|_, w| w.bkpsramen().set_bit());
    // STM32F40x errata (ES0182, "Delay after an RCC peripheral clock enabling"): an access right
    // after the enable can be lost; the DSB completes the enable first.
    cortex_m::asm::dsb();
    pwr().cr().modify(|_, w| w.dbp().set_bit());
    cortex_m::asm::dsb();
}

/// The log's `next_seq` as `main` stored it (before any interrupt runs), for the drain.
pub(crate) static SAVED_SEQ: AtomicU32 = AtomicU32::new(u32::MAX);

/// The last latch written to the backup SRAM (cause, boot count): a store only when it changes,
/// so the tick writes 4 words of backup SRAM only on a change of the latch.
pub(crate) static STORED_CAUSE: AtomicU32 = AtomicU32::new(u32::MAX);
pub(crate) static STORED_BOOTS: AtomicU32 = AtomicU32::new(u32::MAX);

pub(crate) fn retained_store(r: Retained) {
    // Called from SysTick and the bookkeeping, which share one priority (EXTI0 never calls it).
    if STORED_CAUSE.load(Relaxed) == r.words[1] && STORED_BOOTS.load(Relaxed) == r.words[2] {
        return;
    }
    backup::store_latch(&mut Bkp, r);
    STORED_CAUSE.store(r.words[1], Relaxed);
    STORED_BOOTS.store(r.words[2], Relaxed);
}

/// The boot count of the record in the backup SRAM (0 if there is none).
pub(crate) fn stored_boots() -> u32 {
    backup::load_latch(&mut Bkp).decode().map_or(0, |(_, n)| n)
}
