//! Event log: a fixed-size ring of trips and faults, readable by the host.
//!
//! Every stop the firmware commands is recorded with its timestamp, the travel at detection and
//! flags. The ring is a `heapless::Deque` sized at compile time; when it is full the oldest entry is
//! overwritten and [`EventLog::overwritten`] counts the loss, so the host can tell that a gap exists.
//!
//! Serialisation (all little-endian) is what a debugger, a UART dump or `flinch hil` reads:
//!
//! ```text
//! header, 8 bytes: b'F' b'L' version(1) count(u8) overwritten(u32)
//! event, 16 bytes: seq(u16) cause(u8) flags(u8) at_us(u32) first_seen_us(u32) travel_um(i32)
//! ```
//! events oldest first.

use crate::clock::Micros;
use heapless::Deque;

/// Why the firmware stopped.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Cause {
    /// The sensor showed a collision (confirmed by the filter).
    Trip = 1,
    /// Start-up self-test: the input did not follow the sensor supply (stuck input).
    StuckInput = 2,
    /// The input changed level too often (chatter guard).
    Chatter = 3,
    /// The clock did not advance between ticks.
    ClockStall = 4,
    /// A tick came later than its deadline (or the clock jumped).
    MissedDeadline = 5,
    /// The sensor reading was implausible (ADC window, read error).
    SensorFault = 6,
    /// An output pin reported an error when driven.
    OutputFault = 7,
    /// The MCU started (any reset): latched until a person resets (`reset.rs`). In the log, the
    /// event's flags hold the [`ResetCause`](crate::ResetCause) code instead of `FLAG_*` bits.
    Reset = 8,
    /// A fault handler (HardFault, NMI, an unexpected interrupt, a panic) ran and de-energised the
    /// outputs; the board records it in the retained latch before the part resets.
    FaultHandler = 9,
    /// The two channels of a [`DualSwitch`](crate::DualSwitch) disagreed longer than the
    /// discrepancy time, or a trip ended without both channels having shown it: one is stuck.
    Discrepancy = 10,
    /// External device monitoring: a stop relay did not follow the stop output within the settle
    /// time (welded, stuck, feedback wire cut or shorted), or was not released before arming.
    EdmMismatch = 11,
    /// The firmware's clock disagreed with the independent reference oscillator (`clock_check.rs`).
    ClockDrift = 12,
    /// A start-up integrity check failed (`integrity.rs`): the flash CRC or the RAM test. The board
    /// never arms after it; no reset press clears it, only a start whose checks pass.
    SelfCheck = 13,
    /// An output read back at its pin did not follow its command (`output_monitor.rs`): a pin or
    /// driver stuck high or low, or a frozen port (its clock gated). The event's flags name the
    /// channels ([`FLAG_K1`], [`FLAG_K2`], [`FLAG_ESC`]).
    OutputReadBack = 14,
    /// A periodic self-test failed while running (`diagnostics.rs`, IEC 60730-1 Annex H): the flash
    /// CRC, the RAM test of the safety state, or the read-back of the peripheral configuration. The
    /// event's travel field says which check and what it saw.
    Diagnostic = 15,
}

impl Cause {
    /// Decode a serialised cause.
    pub const fn from_u8(v: u8) -> Option<Cause> {
        Some(match v {
            1 => Cause::Trip,
            2 => Cause::StuckInput,
            3 => Cause::Chatter,
            4 => Cause::ClockStall,
            5 => Cause::MissedDeadline,
            6 => Cause::SensorFault,
            7 => Cause::OutputFault,
            8 => Cause::Reset,
            9 => Cause::FaultHandler,
            10 => Cause::Discrepancy,
            11 => Cause::EdmMismatch,
            12 => Cause::ClockDrift,
            13 => Cause::SelfCheck,
            14 => Cause::OutputReadBack,
            15 => Cause::Diagnostic,
            _ => return None,
        })
    }

    /// A short name, for reports.
    pub const fn name(self) -> &'static str {
        match self {
            Cause::Trip => "trip",
            Cause::StuckInput => "stuck-input",
            Cause::Chatter => "chatter",
            Cause::ClockStall => "clock-stall",
            Cause::MissedDeadline => "missed-deadline",
            Cause::SensorFault => "sensor-fault",
            Cause::OutputFault => "output-fault",
            Cause::Reset => "reset",
            Cause::FaultHandler => "fault-handler",
            Cause::Discrepancy => "discrepancy",
            Cause::EdmMismatch => "edm-mismatch",
            Cause::ClockDrift => "clock-drift",
            Cause::SelfCheck => "self-check",
            Cause::OutputReadBack => "output-read-back",
            Cause::Diagnostic => "diagnostic",
        }
    }
}

/// Flag: the stop was commanded from the edge interrupt (not from a tick).
pub const FLAG_EDGE: u8 = 1 << 0;
/// Flag: the stroke budget was short and the escalation (category 0) output was dropped too.
pub const FLAG_ESCALATED: u8 = 1 << 1;
/// Flag: the glitch filter delayed this trip (`first_seen` before `at`).
pub const FLAG_FILTERED: u8 = 1 << 2;
/// Flag: this latch was found in retained RAM at start-up (it was in force when the part reset).
pub const FLAG_RETAINED: u8 = 1 << 3;
/// Flag of an output fault ([`Cause::OutputReadBack`], [`Cause::EdmMismatch`]): stop channel K1.
pub const FLAG_K1: u8 = 1 << 4;
/// Flag of an output fault: stop channel K2.
pub const FLAG_K2: u8 = 1 << 5;
/// Flag of an output fault: the category-0 escalation output.
pub const FLAG_ESC: u8 = 1 << 6;

/// One entry of the log.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct TripEvent {
    /// Sequence number, counting every event since start-up (wraps at 2^16).
    pub seq: u16,
    /// Why.
    pub cause: Cause,
    /// `FLAG_*` bits.
    pub flags: u8,
    /// When the stop output was dropped.
    pub at: Micros,
    /// When the sensor was first seen tripped (equal to `at` without a filter).
    pub first_seen: Micros,
    /// Travel at detection, micrometres (d_sw for the digital switch).
    pub travel_um: i32,
}

/// Bytes of a serialised [`TripEvent`].
pub const EVENT_LEN: usize = 16;
/// Bytes of the serialised log header.
pub const HEADER_LEN: usize = 8;
/// Serialisation format version.
pub const FORMAT_VERSION: u8 = 1;

impl TripEvent {
    /// Serialise to the 16-byte wire form.
    pub fn to_bytes(&self) -> [u8; EVENT_LEN] {
        let [s0, s1] = self.seq.to_le_bytes();
        let [a0, a1, a2, a3] = self.at.0.to_le_bytes();
        let [f0, f1, f2, f3] = self.first_seen.0.to_le_bytes();
        let [t0, t1, t2, t3] = self.travel_um.to_le_bytes();
        [s0, s1, self.cause as u8, self.flags, a0, a1, a2, a3, f0, f1, f2, f3, t0, t1, t2, t3]
    }

    /// Parse the 16-byte wire form; `None` for a short slice or an unknown cause.
    pub fn from_bytes(b: &[u8]) -> Option<TripEvent> {
        let b: &[u8; EVENT_LEN] = b.get(..EVENT_LEN)?.try_into().ok()?;
        let [s0, s1, c, flags, a0, a1, a2, a3, f0, f1, f2, f3, t0, t1, t2, t3] = *b;
        Some(TripEvent {
            seq: u16::from_le_bytes([s0, s1]),
            cause: Cause::from_u8(c)?,
            flags,
            at: Micros(u32::from_le_bytes([a0, a1, a2, a3])),
            first_seen: Micros(u32::from_le_bytes([f0, f1, f2, f3])),
            travel_um: i32::from_le_bytes([t0, t1, t2, t3]),
        })
    }
}

/// The serialised buffer was too small; `needed` bytes are required.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct BufferTooSmall {
    /// Bytes required.
    pub needed: usize,
}

/// Events the board's log drain copies per run under its priority ceiling (it runs after every
/// interrupt, so a burst is taken over a few ticks): what bounds that masked section (QEMU
/// `drain_masked`, firmware/README.md).
pub const DRAIN_BATCH: usize = 1;

/// The part of a log a reader has not taken yet ([`EventLog::snapshot`], [`EventLog::follow`]).
#[derive(Clone, Debug)]
pub struct LogSnapshot<const N: usize> {
    /// The events not taken yet, oldest first.
    pub new: heapless::Vec<TripEvent, N>,
    /// The log's next sequence number.
    pub next_seq: u16,
    /// The log's loss count.
    pub overwritten: u32,
    /// No new event was left behind: a copy that follows this snapshot equals the log (before, it
    /// holds a prefix of what is new: not a copy to store).
    pub complete: bool,
}

/// A ring of the last `N` events.
#[derive(Clone, Debug)]
pub struct EventLog<const N: usize> {
    ring: Deque<TripEvent, N>,
    next_seq: u16,
    overwritten: u32,
}

impl<const N: usize> Default for EventLog<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> EventLog<N> {
    /// An empty log.
    pub const fn new() -> Self {
        EventLog { ring: Deque::new(), next_seq: 0, overwritten: 0 }
    }

    /// A log continuing one saved before a reset (`backup.rs`): `events` keep their sequence
    /// numbers, the next event gets the newest one's plus one, and `overwritten` carries on (plus any
    /// event beyond the capacity, the oldest dropped).
    pub fn restored(overwritten: u32, events: impl Iterator<Item = TripEvent>) -> Self {
        let mut log = EventLog { ring: Deque::new(), next_seq: 0, overwritten };
        for e in events {
            if log.ring.is_full() {
                let _ = log.ring.pop_front();
                log.overwritten = log.overwritten.saturating_add(1);
            }
            log.next_seq = e.seq.wrapping_add(1);
            if log.ring.push_back(e).is_err() {
                log.overwritten = log.overwritten.saturating_add(1);
            }
        }
        log
    }

    /// The sequence number the next event will get.
    pub const fn next_seq(&self) -> u16 {
        self.next_seq
    }

    /// Append an event, assigning its sequence number; overwrites the oldest when full.
    pub fn push(&mut self, cause: Cause, flags: u8, at: Micros, first_seen: Micros, travel_um: i32) {
        let ev = TripEvent { seq: self.next_seq, cause, flags, at, first_seen, travel_um };
        self.next_seq = self.next_seq.wrapping_add(1);
        if self.ring.is_full() {
            let _ = self.ring.pop_front();
            self.overwritten = self.overwritten.saturating_add(1);
        }
        // Cannot fail: there is room now (N == 0 simply drops the event).
        if self.ring.push_back(ev).is_err() {
            self.overwritten = self.overwritten.saturating_add(1);
        }
    }

    /// Events oldest first.
    pub fn iter(&self) -> impl Iterator<Item = &TripEvent> {
        self.ring.iter()
    }

    /// The events not yet seen by a reader whose cursor is `cursor` (the sequence number after the
    /// last event it took; `None`: it took none, all are new), oldest first. Wrap-safe: an event is
    /// new when it is no further behind the next sequence number than the cursor is, so the test
    /// never compares two sequence numbers that may be more than the ring apart, and sequence
    /// numbers that continue across resets (`restored`) past 0x8000 or 0xFFFF are no special case.
    pub fn since(&self, cursor: Option<u16>) -> impl Iterator<Item = &TripEvent> {
        let head = self.next_seq;
        let behind = cursor.map_or(u16::MAX, |c| head.wrapping_sub(c));
        self.ring.iter().filter(move |e| head.wrapping_sub(e.seq) <= behind && head != e.seq)
    }

    /// What a reader whose cursor is `cursor` (as for [`EventLog::since`]) has not taken yet, at most
    /// `B` events of it (the oldest): those events, the sequence number after the last of them
    /// (the log's next one when none is left behind) and the loss count. What the board's log drain
    /// copies under its priority ceiling instead of the whole log ([`DRAIN_BATCH`] events a run):
    /// the snapshot is sized by the batch, so the section copies `B` events, not the ring.
    pub fn snapshot<const B: usize>(&self, cursor: Option<u16>) -> LogSnapshot<B> {
        let mut new = heapless::Vec::new();
        for e in self.since(cursor).take(B) {
            let _ = new.push(*e); // cannot fail: at most B are taken
        }
        let next_seq = match new.last() {
            Some(e) if new.len() == B => e.seq.wrapping_add(1),
            _ => self.next_seq,
        };
        LogSnapshot { new, next_seq, overwritten: self.overwritten, complete: next_seq == self.next_seq }
    }

    /// Bring a reader's copy of a log up to date with a snapshot of it taken with this copy's cursor
    /// (`None` while the copy is empty): the copy then holds what the log holds (its events, next
    /// sequence number and loss count), without the whole log having been copied at once.
    pub fn follow<const B: usize>(&mut self, s: &LogSnapshot<B>) {
        for e in &s.new {
            if self.ring.is_full() {
                let _ = self.ring.pop_front();
            }
            let _ = self.ring.push_back(*e);
        }
        self.next_seq = s.next_seq;
        self.overwritten = s.overwritten;
    }

    /// The cursor of a reader whose copy this is (for [`EventLog::snapshot`]): `None` while empty.
    pub fn cursor(&self) -> Option<u16> {
        if self.ring.is_empty() && self.next_seq == 0 {
            None
        } else {
            Some(self.next_seq)
        }
    }

    /// The newest event.
    pub fn last(&self) -> Option<&TripEvent> {
        self.ring.back()
    }

    /// Number of events held.
    pub fn len(&self) -> usize {
        self.ring.len()
    }

    /// No events held.
    pub fn is_empty(&self) -> bool {
        self.ring.is_empty()
    }

    /// Events lost to overwriting since start-up.
    pub const fn overwritten(&self) -> u32 {
        self.overwritten
    }

    /// Bytes [`Self::serialize`] writes for the current content.
    pub fn serialized_len(&self) -> usize {
        EVENT_LEN.saturating_mul(self.ring.len()).saturating_add(HEADER_LEN)
    }

    /// Write header and events into `out`; returns the number of bytes written.
    pub fn serialize(&self, out: &mut [u8]) -> Result<usize, BufferTooSmall> {
        let needed = self.serialized_len();
        let Some(dst) = out.get_mut(..needed) else { return Err(BufferTooSmall { needed }) };
        let count = u8::try_from(self.ring.len()).unwrap_or(u8::MAX);
        let [o0, o1, o2, o3] = self.overwritten.to_le_bytes();
        let (head, body) = dst.split_at_mut(HEADER_LEN);
        head.copy_from_slice(&[b'F', b'L', FORMAT_VERSION, count, o0, o1, o2, o3]);
        for (chunk, ev) in body.chunks_exact_mut(EVENT_LEN).zip(self.ring.iter()) {
            chunk.copy_from_slice(&ev.to_bytes());
        }
        Ok(needed)
    }
}

/// Decoded header of a serialised log.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct LogHeader {
    /// Events that follow.
    pub count: u8,
    /// Events lost to overwriting.
    pub overwritten: u32,
}

/// Parse a serialised log: its header and an iterator over its events (a corrupt event ends it).
pub fn decode(bytes: &[u8]) -> Option<(LogHeader, impl Iterator<Item = TripEvent> + '_)> {
    let [m0, m1, ver, count, o0, o1, o2, o3] = *<&[u8; HEADER_LEN]>::try_from(bytes.get(..HEADER_LEN)?).ok()?;
    if [m0, m1] != *b"FL" || ver != FORMAT_VERSION {
        return None;
    }
    let header = LogHeader { count, overwritten: u32::from_le_bytes([o0, o1, o2, o3]) };
    let body = bytes.get(HEADER_LEN..)?;
    let events = body.chunks_exact(EVENT_LEN).take(usize::from(count)).map_while(TripEvent::from_bytes);
    Some((header, events))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seqs<const N: usize>(log: &EventLog<N>, cursor: Option<u16>) -> heapless::Vec<u16, 16> {
        log.since(cursor).map(|e| e.seq).collect()
    }

    #[test]
    fn a_reader_sees_each_event_once_across_0x8000_and_the_u16_wrap() {
        // Sequence numbers continue across resets: a restored log may start anywhere, e.g. where
        // the drain's old filter (seq - cursor < 0x8000 with the cursor at 0) saw nothing.
        for start in [0u16, 5, 0x7FFE, 0x8000, 0x9000, 0xFFF0, 0xFFFE] {
            let ev = |k: u16| TripEvent {
                seq: start.wrapping_add(k),
                cause: Cause::Trip,
                flags: 0,
                at: Micros(0),
                first_seen: Micros(0),
                travel_um: 0,
            };
            let mut log: EventLog<4> = EventLog::restored(0, (0..3).map(ev));
            // A fresh reader (the drain at boot) sees the whole restored log.
            assert_eq!(&seqs(&log, None)[..], &[start, start.wrapping_add(1), start.wrapping_add(2)], "start {start:#x}");
            let mut cursor = log.last().map(|e| e.seq.wrapping_add(1));
            assert!(seqs(&log, cursor).is_empty());
            // Then each new event exactly once, past 0xFFFF too, and overwrites of unseen ones.
            for k in 0..40u16 {
                let pushes = 1 + k % 6;
                for _ in 0..pushes {
                    log.push(Cause::Trip, 0, Micros(0), Micros(0), 0);
                }
                let got = seqs(&log, cursor);
                let want: heapless::Vec<u16, 16> = (0..pushes.min(4)).rev().map(|b| log.next_seq().wrapping_sub(b + 1)).collect();
                assert_eq!(got, want, "start {start:#x} step {k}");
                cursor = got.last().map(|s| s.wrapping_add(1));
            }
        }
        // A cursor of 0 on a log far past 0x8000 still sees what is new (the old filter saw nothing).
        let log: EventLog<4> = EventLog::restored(0, (0x9000u16..0x9002).map(|seq| TripEvent { seq, cause: Cause::Trip, flags: 0, at: Micros(0), first_seen: Micros(0), travel_um: 0 }));
        assert_eq!(&seqs(&log, Some(0))[..], &[0x9000, 0x9001]);
    }

    #[test]
    fn a_copy_following_snapshots_equals_the_log_byte_for_byte() {
        for start in [0u16, 0x7FF0, 0xFFF5] {
            let ev = |k: u16| TripEvent { seq: start.wrapping_add(k), cause: Cause::Reset, flags: 1, at: Micros(7), first_seen: Micros(3), travel_um: -2 };
            let mut log: EventLog<16> = EventLog::restored(3, (0..9).map(ev));
            let mut copy: EventLog<16> = EventLog::new();
            for k in 0..60u32 {
                // 0 to 20 events between two snapshots (more than the ring: the oldest are lost).
                for j in 0..(k * 7 % 21) {
                    log.push(Cause::Trip, j as u8, Micros(k), Micros(j), k as i32);
                }
                // Followed DRAIN_BATCH events at a time until nothing is new.
                for _ in 0..16 {
                    let s = log.snapshot::<DRAIN_BATCH>(copy.cursor());
                    assert!(s.new.len() <= DRAIN_BATCH);
                    copy.follow(&s);
                    if s.complete {
                        break;
                    }
                }
                let (mut a, mut b) = ([0u8; 300], [0u8; 300]);
                let (na, nb) = (log.serialize(&mut a), copy.serialize(&mut b));
                assert_eq!(na, nb);
                assert_eq!(a, b, "start {start:#x} round {k}");
                assert_eq!(copy.next_seq(), log.next_seq());
                // Nothing new: an empty snapshot.
                assert!(log.snapshot::<16>(copy.cursor()).new.is_empty());
            }
        }
    }

    #[test]
    fn wraps_keeping_the_newest_and_counting_the_loss() {
        let mut log: EventLog<4> = EventLog::new();
        for k in 0..10u32 {
            log.push(Cause::Trip, 0, Micros(k * 10), Micros(k * 10), 5000);
        }
        assert_eq!(log.len(), 4);
        assert_eq!(log.overwritten(), 6);
        let seqs: heapless::Vec<u16, 4> = log.iter().map(|e| e.seq).collect();
        assert_eq!(&seqs[..], &[6, 7, 8, 9]);
        assert_eq!(log.last().map(|e| e.at), Some(Micros(90)));
    }

    #[test]
    fn serialisation_round_trips() {
        let mut log: EventLog<3> = EventLog::new();
        log.push(Cause::Trip, FLAG_EDGE | FLAG_ESCALATED, Micros(u32::MAX), Micros(u32::MAX - 5), -12);
        log.push(Cause::ClockStall, 0, Micros(7), Micros(7), 0);
        let mut buf = [0u8; 64];
        let n = log.serialize(&mut buf).unwrap();
        assert_eq!(n, HEADER_LEN + 2 * EVENT_LEN);
        let (h, evs) = decode(&buf[..n]).unwrap();
        assert_eq!(h, LogHeader { count: 2, overwritten: 0 });
        let got: heapless::Vec<TripEvent, 3> = evs.collect();
        let want: heapless::Vec<TripEvent, 3> = log.iter().copied().collect();
        assert_eq!(got, want);
        assert_eq!(log.serialize(&mut buf[..10]), Err(BufferTooSmall { needed: n }));
        assert!(decode(b"XX").is_none());
    }
}
