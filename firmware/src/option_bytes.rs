//! The brown-out reset level: programmed into the option bytes once, verified at the next boot.
//!
//! The STM32F407's brown-out reset (BOR) holds the part in reset while VDD is below the level set by
//! the option bits `BOR_LEV` (RM0090 sec. 3.6.3 and 3.9.10; level 3, `BOR_LEV = 00`, is about 2.7 V,
//! DS8626 "BOR thresholds"); the factory default is off (`11`). Reading `FLASH_OPTCR` right after
//! writing it proves nothing: the register holds the value written, whether or not the option
//! bytes were programmed. The option bits are loaded from the option bytes at reset, so the value
//! read at the start of a boot is the one in effect. Hence:
//!
//! 1. At boot, the level in effect is read. Level 3: done (a pending mark is cleared).
//! 2. Not level 3 and no mark in the backup store: program it. Error flags cleared first, the
//!    option bytes unlocked, `BOR_LEV` written, `OPTSTRT`, a bounded wait on `BSY`, then the error
//!    flags (`OPERR`, `WRPERR`, `PGAERR`, `PGPERR`, `PGSERR`, RM0090 sec. 3.9.5) read; relocked in
//!    every case. The mark is set and read back *before* the programming (a mark that does not
//!    stick, e.g. the backup domain not writable, ends in [`BorFailure::MarkLost`] with nothing
//!    programmed; without it every boot would program and reset for ever, nothing logged), cleared
//!    again on a time-out or an error flag, and read back once more before success asks for a reset
//!    ([`BorOutcome::ResetToVerify`]): the next boot reads the value the option bytes really hold.
//! 3. Not level 3 although the mark says it was programmed: the programming did not take. A
//!    time-out, an error flag or this end in [`BorOutcome::Failed`]: the board stops for good and
//!    logs [`Cause::SelfCheck`](crate::Cause::SelfCheck).
//!
//! The board calls this only after its flash CRC passed (a corrupt image never programs option
//! bytes). Every loop is bounded.

use crate::backup::BackupRam;

/// BOR level 3 (`BOR_LEV = 00`).
pub const BOR_LEVEL_3: u8 = 0b00;
/// `FLASH_SR` error flags on the F407: OPERR (1), WRPERR (4), PGAERR (5), PGPERR (6), PGSERR (7).
pub const SR_ERRORS: u32 = (1 << 1) | (1 << 4) | (1 << 5) | (1 << 6) | (1 << 7);
/// `FLASH_SR.BSY`.
pub const SR_BSY: u32 = 1 << 16;
/// Word of the backup store that marks "BOR level programmed, verify at the next boot" (after the
/// latch and the largest log `backup.rs` stores, `words_needed(16)` = 72).
pub const PENDING_AT: usize = 96;
/// The mark's value.
pub const PENDING_MAGIC: u32 = 0x424F_5233; // "BOR3"

/// The flash interface's option-byte registers (the board's `FLASH`; a fake in the tests).
pub trait OptionBytes {
    /// `FLASH_OPTCR.BOR_LEV` now.
    fn bor_level(&mut self) -> u8;
    /// `FLASH_SR`.
    fn status(&mut self) -> u32;
    /// Clear the error flags given (write 1 to clear).
    fn clear_status(&mut self, flags: u32);
    /// Write the two `FLASH_OPTKEYR` keys.
    fn unlock(&mut self);
    /// Write `BOR_LEV` into `FLASH_OPTCR` (read-modify-write, other bits kept) and set `OPTSTRT`.
    fn program_bor(&mut self, level: u8);
    /// Set `OPTLOCK`.
    fn lock(&mut self);
}

/// What the boot must do about the brown-out level.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum BorOutcome {
    /// Level 3 is in effect.
    InEffect,
    /// Programmed without error: reset the part, the next boot verifies it.
    ResetToVerify,
    /// Failed (why): stop for good, log it.
    Failed(BorFailure),
}

/// Why the brown-out level could not be set.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum BorFailure {
    /// `BSY` did not clear within the bound.
    Timeout = 1,
    /// An error flag was set after the programming (the flags are in the event's travel field).
    FlashError = 2,
    /// Programmed at the last boot, but the option bytes do not hold level 3 now.
    NotInEffect = 3,
    /// The pending mark did not read back from the backup store (backup domain not writable): a
    /// reset to verify would find no mark and program again, for ever, so nothing is programmed.
    MarkLost = 4,
}

/// Check the brown-out level and program it if needed; `busy_spins` bounds the wait on `BSY` (the
/// board runs this before it starts the IWDG, so nothing needs feeding meanwhile). Returns the outcome and the `FLASH_SR` error flags seen (0 if none).
pub fn ensure_bor_level<F: OptionBytes, B: BackupRam>(f: &mut F, backup: &mut B, busy_spins: u32) -> (BorOutcome, u32) {
    let pending = backup.read(PENDING_AT) == PENDING_MAGIC;
    if f.bor_level() == BOR_LEVEL_3 {
        if pending {
            backup.write(PENDING_AT, 0);
        }
        return (BorOutcome::InEffect, 0);
    }
    if pending {
        backup.write(PENDING_AT, 0);
        return (BorOutcome::Failed(BorFailure::NotInEffect), 0);
    }
    // The mark first, read back: without it the next boot could not tell "programmed, did not
    // take" from "never programmed" and would program and reset for ever, with nothing logged.
    backup.write(PENDING_AT, PENDING_MAGIC);
    if backup.read(PENDING_AT) != PENDING_MAGIC {
        return (BorOutcome::Failed(BorFailure::MarkLost), 0);
    }
    f.clear_status(SR_ERRORS);
    f.unlock();
    f.program_bor(BOR_LEVEL_3);
    let mut spins: u32 = 0;
    let mut done = false;
    while spins < busy_spins {
        if f.status() & SR_BSY == 0 {
            done = true;
            break;
        }
        spins = spins.saturating_add(1);
    }
    let errors = f.status() & SR_ERRORS;
    f.lock();
    if !done {
        backup.write(PENDING_AT, 0);
        return (BorOutcome::Failed(BorFailure::Timeout), errors);
    }
    if errors != 0 {
        f.clear_status(errors);
        backup.write(PENDING_AT, 0);
        return (BorOutcome::Failed(BorFailure::FlashError), errors);
    }
    // Still there (read back again right before the reset that relies on it).
    if backup.read(PENDING_AT) != PENDING_MAGIC {
        return (BorOutcome::Failed(BorFailure::MarkLost), 0);
    }
    (BorOutcome::ResetToVerify, 0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backup::RamBackup;

    /// The option bytes as the part has them: `stored` is what a reset loads, `optcr` the register.
    struct Fake {
        stored: u8,
        optcr: u8,
        /// BSY stays set for this many status reads after OPTSTRT (`u32::MAX`: for ever).
        busy_reads: u32,
        /// Error flags the programming raises.
        raises: u32,
        /// The programming reaches the option bytes (false: it is lost, e.g. write-protected silently).
        takes: bool,
        sr: u32,
        unlocked: bool,
        programmed: u32,
    }
    impl Fake {
        fn new(stored: u8) -> Fake {
            Fake { stored, optcr: stored, busy_reads: 3, raises: 0, takes: true, sr: 0, unlocked: false, programmed: 0 }
        }
        fn reset(&mut self) {
            self.optcr = self.stored;
            self.unlocked = false;
        }
    }
    impl OptionBytes for Fake {
        fn bor_level(&mut self) -> u8 {
            self.optcr
        }
        fn status(&mut self) -> u32 {
            if self.busy_reads > 0 {
                if self.busy_reads != u32::MAX {
                    self.busy_reads -= 1;
                }
                return self.sr | SR_BSY;
            }
            self.sr
        }
        fn clear_status(&mut self, flags: u32) {
            self.sr &= !flags;
        }
        fn unlock(&mut self) {
            self.unlocked = true;
        }
        fn program_bor(&mut self, level: u8) {
            assert!(self.unlocked, "programmed while locked");
            self.optcr = level; // the register holds it at once, whatever happens to the option bytes
            self.programmed += 1;
            self.sr |= self.raises;
            if self.takes && self.raises == 0 {
                self.stored = level;
            }
        }
        fn lock(&mut self) {
            self.unlocked = false;
        }
    }

    #[test]
    fn level_3_in_effect_programs_nothing() {
        let mut f = Fake::new(BOR_LEVEL_3);
        let mut b = RamBackup::<128>::filled(0);
        assert_eq!(ensure_bor_level(&mut f, &mut b, 100), (BorOutcome::InEffect, 0));
        assert_eq!(f.programmed, 0);
    }

    #[test]
    fn factory_default_is_programmed_then_verified_at_the_next_boot() {
        let mut f = Fake::new(0b11);
        let mut b = RamBackup::<128>::filled(0);
        assert_eq!(ensure_bor_level(&mut f, &mut b, 100), (BorOutcome::ResetToVerify, 0));
        assert!(!f.unlocked, "relocked");
        f.reset();
        assert_eq!(ensure_bor_level(&mut f, &mut b, 100), (BorOutcome::InEffect, 0));
        assert_eq!(f.programmed, 1);
        assert_ne!(b.words[PENDING_AT], PENDING_MAGIC, "the mark is cleared");
    }

    #[test]
    fn a_programming_that_did_not_take_fails_at_the_next_boot_although_optcr_read_back_right() {
        let mut f = Fake::new(0b11);
        f.takes = false;
        let mut b = RamBackup::<128>::filled(0);
        assert_eq!(ensure_bor_level(&mut f, &mut b, 100), (BorOutcome::ResetToVerify, 0));
        assert_eq!(f.bor_level(), BOR_LEVEL_3, "the register reads back what was written: no proof");
        f.reset();
        assert_eq!(ensure_bor_level(&mut f, &mut b, 100), (BorOutcome::Failed(BorFailure::NotInEffect), 0));
        assert_eq!(f.programmed, 1, "not programmed again in a loop");
    }

    #[test]
    fn error_flags_and_a_stuck_busy_fail_and_relock() {
        for flag in [1 << 1, 1 << 4, 1 << 5, 1 << 6, 1 << 7] {
            let mut f = Fake::new(0b11);
            f.raises = flag;
            let mut b = RamBackup::<128>::filled(0);
            assert_eq!(ensure_bor_level(&mut f, &mut b, 100), (BorOutcome::Failed(BorFailure::FlashError), flag));
            assert!(!f.unlocked);
            assert_ne!(b.words[PENDING_AT], PENDING_MAGIC);
        }
        let mut f = Fake::new(0b11);
        f.busy_reads = u32::MAX;
        let mut b = RamBackup::<128>::filled(0);
        assert_eq!(ensure_bor_level(&mut f, &mut b, 1_000), (BorOutcome::Failed(BorFailure::Timeout), 0));
        assert!(!f.unlocked);
        // A stale error flag from before is cleared first and does not fail a good programming.
        let mut f = Fake::new(0b11);
        f.sr = 1 << 7;
        let mut b = RamBackup::<128>::filled(0);
        assert_eq!(ensure_bor_level(&mut f, &mut b, 100), (BorOutcome::ResetToVerify, 0));
    }

    /// A backup store whose writes are lost (DBP not set, the domain not clocked): reads `fill`.
    struct LostWrites(u32);
    impl BackupRam for LostWrites {
        fn len(&self) -> usize {
            128
        }
        fn read(&mut self, _: usize) -> u32 {
            self.0
        }
        fn write(&mut self, _: usize, _: u32) {}
    }

    #[test]
    fn a_mark_that_does_not_stick_fails_without_programming_instead_of_resetting_for_ever() {
        for fill in [0, 0xFFFF_FFFF, 0x1234_5678] {
            let mut f = Fake::new(0b11);
            f.takes = false;
            let mut b = LostWrites(fill);
            // Boot after boot: never a reset to verify (that would loop), never a programming.
            for _ in 0..3 {
                assert_eq!(ensure_bor_level(&mut f, &mut b, 100), (BorOutcome::Failed(BorFailure::MarkLost), 0));
                f.reset();
            }
            assert_eq!(f.programmed, 0);
            assert!(!f.unlocked);
        }
    }

    #[test]
    fn a_failed_programming_clears_its_mark() {
        let mut f = Fake::new(0b11);
        f.raises = 1 << 4;
        let mut b = RamBackup::<128>::filled(0);
        assert_eq!(ensure_bor_level(&mut f, &mut b, 100).0, BorOutcome::Failed(BorFailure::FlashError));
        assert_eq!(b.words[PENDING_AT], 0);
    }

    #[test]
    fn garbage_in_the_backup_store_is_no_mark() {
        let mut f = Fake::new(0b01);
        let mut b = RamBackup::<128>::filled(0xFFFF_FFFF);
        assert_eq!(ensure_bor_level(&mut f, &mut b, 100), (BorOutcome::ResetToVerify, 0));
    }
}
