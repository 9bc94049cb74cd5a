//! The board's log drain: thread mode copies the firmware's new events and state out under a
//! priority ceiling, stores the log in the backup SRAM and logs over defmt with every interrupt enabled.

use crate::backup::Bkp;
use crate::fw::{FW, PRIO_TICK};
use flinch_firmware::{backup, EventLog};


/// Logging from thread mode only. The library's own messages are compiled out on the board
/// (`DEFMT_LOG` in firmware/.cargo/config.toml: `flinch_firmware=off`), because they would run in
/// the tick and the bookkeeping interrupts; instead the tick and the bookkeeping fill the
/// firmware's event log (a fixed 16-entry ring, `EventLog`) and this drain, in thread mode between
/// ticks, copies the new entries and the state out under a priority ceiling (BASEPRI = the tick's
/// priority: the tick and the bookkeeping cannot run meanwhile, the edge interrupt still can) and
/// logs them afterwards, with every interrupt enabled. defmt-rtt runs with `drop-on-contention`
/// (no critical section: logging never masks the edge) and starts non-blocking (a full buffer
/// truncates the message; only an attached probe-rs switches it to blocking).
pub(crate) struct LogDrain {
    /// The drain's own copy of the firmware's log, brought up to date from a snapshot of the new
    /// events only (`EventLog::snapshot`/`follow`; its cursor is `None` until the first one, so
    /// the whole restored log is new then; sequence numbers compare wrap-safely and continue
    /// across resets). The backup SRAM store is made from this copy, with interrupts enabled.
    pub(crate) copy: EventLog<16>,
    pub(crate) state: Option<flinch_firmware::State>,
    /// The log's `next_seq` when it was last written to the backup SRAM.
    pub(crate) saved_seq: Option<u16>,
}

impl LogDrain {
    pub(crate) fn run(&mut self) {
        // SAFETY: BASEPRI = PRIO_TICK masks SysTick and the bookkeeping, FW's only other users
        // (the edge, at priority 0, never touches FW), so this is the one reference meanwhile.
        // Masked: at most DRAIN_BATCH new events (usually none), two counters and the state; this
        // section is measured as `drain_masked` (`src/bin/support/qemu_measure.rs`, README). A burst of events is
        // taken over a few runs (one per interrupt), so it reaches the backup SRAM a few ticks
        // later (the latch is stored at once by the tick and the bookkeeping).
        let (snap, state) = unsafe {
            cortex_m::register::basepri::write(PRIO_TICK);
            #[cfg(feature = "qemu-io")]
            let t0 = crate::bench::start();
            let fw = FW.get();
            let snap = fw.log().snapshot::<{ flinch_firmware::event_log::DRAIN_BATCH }>(self.copy.cursor());
            let state = fw.state();
            #[cfg(feature = "qemu-io")]
            crate::bench::note(&crate::bench::W_MASK_DRAIN, t0, false);
            cortex_m::register::basepri::write(0);
            (snap, state)
        };
        self.copy.follow(&snap);
        // The log into the backup SRAM, with every interrupt enabled (the latch is stored by the
        // tick and the bookkeeping themselves, 4 words, at once). The drain runs after every
        // interrupt (`wfi`), so an event reaches the backup SRAM within a few ticks; a reset in the
        // middle of the store loses the log (its CRC), never the latch (`backup.rs`).
        // Only a copy that has caught up is stored: a partial one (a burst taken one event a
        // run) would replace a whole record with a prefix of it.
        if snap.complete && self.saved_seq != Some(self.copy.next_seq()) {
            backup::store_log(&mut Bkp, &self.copy);
            self.saved_seq = Some(self.copy.next_seq());
        }
        let batch = &snap.new;
        for e in batch {
            defmt::warn!(
                "event {=u16}: {=str} flags {=u8:#x} at {=u32} us (first seen {=u32} us), travel {=i32} um",
                e.seq,
                e.cause.name(),
                e.flags,
                e.at.0,
                e.first_seen.0,
                e.travel_um
            );
        }
        if self.state != Some(state) {
            self.state = Some(state);
            match state {
                flinch_firmware::State::SelfTest(_) => defmt::info!("state: self-test"),
                flinch_firmware::State::Armed => defmt::info!("state: armed"),
                flinch_firmware::State::Tripped => defmt::warn!("state: tripped (stopped)"),
                flinch_firmware::State::Fault(c) => defmt::warn!("state: fault {=str} (stopped)", c.name()),
            }
        }
    }
}
