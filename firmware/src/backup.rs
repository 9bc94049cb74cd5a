//! What survives a reset: the latch and the event log in a word store that the start-up code does
//! not clear (the STM32F407's backup SRAM on the board, a RAM fake in the tests and in QEMU).
//!
//! IEC 60204-1 7.5 and ISO 13849-1 5.2.2 want a stop to stay latched across a reset until a person
//! resets it (`reset.rs`); an assessor also wants to read *why* the machine stopped after the part
//! reset, so the event log is kept too. Layout, in 32-bit words of [`BackupRam`]:
//!
//! ```text
//! [0..4)   the latch: a `Retained` record (magic, cause, boot count, CRC-32 over the three)
//! [4]      LOG_MAGIC
//! [5..7)   the serialised log header (event_log.rs: 'F' 'L' version count, overwritten)
//! [7..7+4n) the n events, 16 bytes = 4 words each, oldest first
//! [7+4n]   CRC-32 (integrity::crc32) over words 5 .. 7+4n as little-endian bytes
//! ```
//!
//! Both records are checked on load: a wrong magic, a count above the capacity, an event whose cause
//! does not decode or a CRC that fails means "no record". That is what a power-on leaves (backup
//! SRAM without a VBAT cell powers up with garbage, or zeros), so garbage reads as a clean
//! power-on, and it is also what a reset in the middle of a store leaves: a torn latch is no latch,
//! which can only make the start *more* latched (`reset.rs`: without a record every reset other
//! than a clean power-on is latched anyway); a torn log is lost, and the new boot's log starts with
//! its reset event. The latch (4 words) is stored apart from the log so that a torn log write never
//! loses the latch.

use crate::event_log::{EventLog, TripEvent, EVENT_LEN, FORMAT_VERSION};
use crate::integrity::Crc32;
use crate::reset::Retained;

/// A word store that survives a reset (not cleared by the start-up code).
pub trait BackupRam {
    /// Words available.
    fn len(&self) -> usize;
    /// Read word `i`; a word outside the store reads 0.
    fn read(&mut self, i: usize) -> u32;
    /// Write word `i`; a write outside the store is ignored.
    fn write(&mut self, i: usize, v: u32);
    /// No words at all.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Word index of the latch record.
pub const LATCH_AT: usize = 0;
/// Word index of the log record.
pub const LOG_AT: usize = 4;
/// First word of a valid log record ("FLLG").
pub const LOG_MAGIC: u32 = 0x464C_4C47;

/// Words the store needs for a log of `n` events (latch included).
pub const fn words_needed(n: usize) -> usize {
    n.saturating_mul(4).saturating_add(LOG_AT + 4)
}

/// The latch record as stored (garbage after a power cycle: [`Retained::decode`] checks it).
pub fn load_latch<B: BackupRam>(b: &mut B) -> Retained {
    Retained {
        words: [b.read(LATCH_AT), b.read(LATCH_AT + 1), b.read(LATCH_AT + 2), b.read(LATCH_AT + 3)],
    }
}

/// Store the latch record.
pub fn store_latch<B: BackupRam>(b: &mut B, r: Retained) {
    for (i, w) in r.words.iter().enumerate() {
        b.write(LATCH_AT.saturating_add(i), *w);
    }
}

fn feed(crc: &mut Crc32, w: u32) {
    crc.update(&w.to_le_bytes());
}

/// Store `log` (its header and every event it holds). A store too small for it stores nothing
/// and returns false.
pub fn store_log<B: BackupRam, const N: usize>(b: &mut B, log: &EventLog<N>) -> bool {
    let n = log.len();
    if b.len() < words_needed(n) {
        return false;
    }
    let mut crc = Crc32::new();
    let count = u8::try_from(n).unwrap_or(u8::MAX);
    let head = [u32::from_le_bytes([b'F', b'L', FORMAT_VERSION, count]), log.overwritten()];
    // Invalidate first: a reset in the middle of this store leaves no magic, i.e. no record.
    b.write(LOG_AT, 0);
    let mut at = LOG_AT.saturating_add(1);
    for w in head {
        b.write(at, w);
        feed(&mut crc, w);
        at = at.saturating_add(1);
    }
    for e in log.iter() {
        let bytes = e.to_bytes();
        for chunk in bytes.chunks_exact(4) {
            let w = u32::from_le_bytes([
                chunk.first().copied().unwrap_or(0),
                chunk.get(1).copied().unwrap_or(0),
                chunk.get(2).copied().unwrap_or(0),
                chunk.get(3).copied().unwrap_or(0),
            ]);
            b.write(at, w);
            feed(&mut crc, w);
            at = at.saturating_add(1);
        }
    }
    b.write(at, crc.finish());
    b.write(LOG_AT, LOG_MAGIC);
    true
}

/// The log stored before the reset, if the record is intact; `None` after a power-on (garbage),
/// a torn store, a flipped bit, or a log larger than `N`.
pub fn load_log<B: BackupRam, const N: usize>(b: &mut B) -> Option<EventLog<N>> {
    if b.read(LOG_AT) != LOG_MAGIC {
        return None;
    }
    let mut crc = Crc32::new();
    let h0 = b.read(LOG_AT.saturating_add(1));
    let overwritten = b.read(LOG_AT.saturating_add(2));
    feed(&mut crc, h0);
    feed(&mut crc, overwritten);
    let [m0, m1, ver, count] = h0.to_le_bytes();
    let count = usize::from(count);
    if [m0, m1] != *b"FL" || ver != FORMAT_VERSION || count > N || b.len() < words_needed(count) {
        return None;
    }
    let mut events: heapless::Vec<TripEvent, N> = heapless::Vec::new();
    let mut at = LOG_AT.saturating_add(3);
    for _ in 0..count {
        let mut bytes = [0u8; EVENT_LEN];
        for chunk in bytes.chunks_exact_mut(4) {
            let w = b.read(at);
            feed(&mut crc, w);
            chunk.copy_from_slice(&w.to_le_bytes());
            at = at.saturating_add(1);
        }
        events.push(TripEvent::from_bytes(&bytes)?).ok()?;
    }
    if b.read(at) != crc.finish() {
        return None;
    }
    Some(EventLog::restored(overwritten, events.iter().copied()))
}

/// A plain RAM word array as the store: the host tests and the QEMU self-test (`src/bin/qemu.rs`,
/// mps2-an386 has no backup SRAM) run the same load/store logic on it as the board on its
/// backup SRAM.
#[derive(Clone, Debug)]
pub struct RamBackup<const W: usize> {
    /// The words, public so that a test can corrupt them.
    pub words: [u32; W],
}

impl<const W: usize> RamBackup<W> {
    /// A store filled with `fill` (power-on garbage, or zeros).
    pub const fn filled(fill: u32) -> Self {
        RamBackup { words: [fill; W] }
    }
}

impl<const W: usize> BackupRam for RamBackup<W> {
    fn len(&self) -> usize {
        W
    }
    fn read(&mut self, i: usize) -> u32 {
        self.words.get(i).copied().unwrap_or(0)
    }
    fn write(&mut self, i: usize, v: u32) {
        if let Some(w) = self.words.get_mut(i) {
            *w = v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clock::Micros;
    use crate::event_log::Cause;

    fn log_of(n: u32) -> EventLog<16> {
        let mut log = EventLog::new();
        for k in 0..n {
            log.push(Cause::Trip, 1, Micros(k * 1_000), Micros(k * 1_000 - k), -(k as i32));
        }
        log
    }

    #[test]
    fn latch_and_log_round_trip() {
        let mut b = RamBackup::<128>::filled(0xA5A5_A5A5);
        let r = Retained::new(Some(Cause::EdmMismatch), 3);
        store_latch(&mut b, r);
        for n in [0, 1, 16, 40] {
            let log = log_of(n);
            assert!(store_log(&mut b, &log));
            let back: EventLog<16> = load_log(&mut b).expect("an intact log loads");
            assert_eq!(back.iter().copied().collect::<heapless::Vec<_, 16>>(), log.iter().copied().collect::<heapless::Vec<_, 16>>());
            assert_eq!(back.overwritten(), log.overwritten());
            assert_eq!(back.next_seq(), log.next_seq(), "sequence numbers continue");
        }
        assert_eq!(load_latch(&mut b), r, "the log never overwrites the latch");
    }

    #[test]
    fn power_on_garbage_is_no_record() {
        for fill in [0, u32::MAX, 0xDEAD_BEEF, LOG_MAGIC] {
            let mut b = RamBackup::<128>::filled(fill);
            assert_eq!(load_latch(&mut b).decode(), None, "fill {fill:#x}");
            assert!(load_log::<_, 16>(&mut b).is_none(), "fill {fill:#x}");
        }
    }

    #[test]
    fn any_flipped_bit_or_torn_store_is_no_log() {
        let mut b = RamBackup::<128>::filled(0);
        store_log(&mut b, &log_of(5));
        let used = words_needed(5);
        for w in LOG_AT..used {
            for bit in [0, 13, 31] {
                let mut bad = b.clone();
                bad.words[w] ^= 1 << bit;
                assert!(load_log::<_, 16>(&mut bad).is_none(), "word {w} bit {bit}");
            }
        }
        // A store torn after any number of words (the part reset in the middle) leaves no record,
        // whatever was there before: the magic is invalidated first and written last.
        let old = b.clone();
        assert!(load_log::<_, 16>(&mut old.clone()).is_some(), "nothing written yet: the old record stands");
        // The store's writes: the invalidation, the record's words after the magic, the magic last.
        let writes = 1 + (words_needed(7) - LOG_AT - 1) + 1;
        for stop_after in 1..=writes {
            struct Torn<'a> {
                inner: &'a mut RamBackup<128>,
                left: usize,
            }
            impl BackupRam for Torn<'_> {
                fn len(&self) -> usize {
                    128
                }
                fn read(&mut self, i: usize) -> u32 {
                    self.inner.read(i)
                }
                fn write(&mut self, i: usize, v: u32) {
                    if self.left > 0 {
                        self.left -= 1;
                        self.inner.write(i, v);
                    }
                }
            }
            let mut m = old.clone();
            store_log(&mut Torn { inner: &mut m, left: stop_after }, &log_of(7));
            if stop_after < writes {
                // Up to and including "everything but the final magic" (stop_after = writes - 1).
                assert!(load_log::<_, 16>(&mut m).is_none(), "torn after {stop_after} of {writes} words");
            } else {
                // The count is exact: with every write the new record stands.
                assert_eq!(load_log::<_, 16>(&mut m).map(|l| l.len()), Some(7), "all {writes} writes");
            }
        }
    }

    /// The whole path the board takes: boot, arm, trip, the part resets (watchdog), the next start
    /// loads the latch and the log from the store: still stopped, the trip and both resets in the log.
    #[test]
    fn a_trip_and_the_log_survive_a_watchdog_reset_and_garbage_is_a_clean_power_on() {
        use crate::*;
        use core::cell::Cell;
        use core::convert::Infallible;
        use embedded_hal::digital::{ErrorType, InputPin, OutputPin};
        struct Pin<'a>(&'a Cell<bool>);
        impl ErrorType for Pin<'_> {
            type Error = Infallible;
        }
        impl InputPin for Pin<'_> {
            fn is_high(&mut self) -> Result<bool, Infallible> {
                Ok(self.0.get())
            }
            fn is_low(&mut self) -> Result<bool, Infallible> {
                Ok(!self.0.get())
            }
        }
        impl OutputPin for Pin<'_> {
            fn set_high(&mut self) -> Result<(), Infallible> {
                self.0.set(true);
                Ok(())
            }
            fn set_low(&mut self) -> Result<(), Infallible> {
                self.0.set(false);
                Ok(())
            }
        }
        struct Time<'a>(&'a Cell<u32>);
        impl Clock for Time<'_> {
            fn now(&mut self) -> Micros {
                Micros(self.0.get())
            }
        }
        let (switch, stop, stop2, esc, t) = (Cell::new(true), Cell::new(true), Cell::new(true), Cell::new(true), Cell::new(0));
        let outputs = || Outputs { k1: Pin(&stop), k2: Pin(&stop2), escalation: Pin(&esc) };
        let budget = BudgetConfig { robot_speed_um_per_s: 50_000, dead_time_us: 16_000, decel_um_per_s2: 1_000_000, stroke_um: 10_000 };
        let mut cfg = Config::new(1_000, budget);
        cfg.start = StartPolicy::AutoAfterPowerOn;
        // Power-on with garbage in the store: a clean power-on, it arms by itself.
        let mut bkp = RamBackup::<128>::filled(0x5A5A_1234);
        let boot = Boot { cause: ResetCause::PowerOn, retained: load_latch(&mut bkp) };
        let mut fw: Firmware<_, _, _, _, _, _> =
            Firmware::after_reset(cfg, boot, Time(&t), DigitalSwitch::new(Pin(&switch), SwitchKind::Inductive, 5_000), outputs(), Unconnected)
                .unwrap()
                .with_saved_log(load_log(&mut bkp));
        for k in 0..10 {
            t.set(k * 1_000);
            fw.tick();
            store_latch(&mut bkp, fw.retained());
            store_log(&mut bkp, fw.log());
        }
        assert!(fw.is_armed(), "garbage in the store is a clean power-on");
        t.set(10_250);
        switch.set(false);
        fw.on_edge();
        store_latch(&mut bkp, fw.retained());
        store_log(&mut bkp, fw.log());
        assert!(!stop.get());
        drop(fw);
        // The watchdog resets the part; the obstacle is gone, the outputs float back high.
        switch.set(true);
        stop.set(true);
        stop2.set(true);
        t.set(0);
        let boot = Boot { cause: ResetCause::from_rcc_csr(1 << 29 | 1 << 26), retained: load_latch(&mut bkp) };
        let mut fw: Firmware<_, _, _, _, _, _> =
            Firmware::after_reset(cfg, boot, Time(&t), DigitalSwitch::new(Pin(&switch), SwitchKind::Inductive, 5_000), outputs(), Unconnected)
                .unwrap()
                .with_saved_log(load_log(&mut bkp));
        for k in 0..100 {
            t.set(k * 1_000);
            fw.tick();
        }
        assert_eq!(fw.state(), State::Fault(Cause::Reset), "stays stopped after the reset");
        assert!(!stop.get() && !esc.get());
        let got: heapless::Vec<(u16, Cause, u8), 16> = fw.log().iter().map(|e| (e.seq, e.cause, e.flags)).collect();
        assert_eq!(
            &got[..],
            &[
                (0, Cause::Reset, ResetCause::PowerOn as u8),
                (1, Cause::Trip, crate::event_log::FLAG_EDGE),
                (2, Cause::Reset, ResetCause::Watchdog as u8),
                (3, Cause::Trip, crate::event_log::FLAG_RETAINED),
            ],
            "the first run's events, then the reset cause and the retained latch"
        );
        assert_eq!(fw.retained().decode(), Some((Some(Cause::Trip), 1)), "latched, boot counted");
    }

    #[test]
    fn a_log_larger_than_the_capacity_or_the_store_is_refused() {
        let mut b = RamBackup::<128>::filled(0);
        store_log(&mut b, &log_of(16));
        assert!(load_log::<_, 4>(&mut b).is_none(), "16 events do not fit a 4-entry log");
        let mut small = RamBackup::<20>::filled(7);
        assert!(!store_log(&mut small, &log_of(16)));
        assert!(small.words.iter().all(|&w| w == 7), "nothing stored");
    }
}
