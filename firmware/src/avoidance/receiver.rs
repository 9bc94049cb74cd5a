//! Frame receiver: a byte ring, an incremental parser with a per-call byte budget, a double-buffered
//! grid, counters.
//!
//! Bytes go in through [`Receiver::feed`] (or [`Receiver::poll`] from an `embedded-io` reader) into
//! a ring of [`RING`] bytes. [`Receiver::service`] parses at most `budget_bytes` of them per call, so
//! one control step's share of frame handling is bounded whatever arrives: the header is decoded
//! once per frame (when its `HEADER_LEN` bytes are in), the CRC is updated as the bytes go by (the 1 KiB
//! byte table: in QEMU's instruction count the 16 KiB sliced one saved nothing), and every weight is decoded into the inactive grid as soon as its four
//! bytes are parsed. At the frame's end only the CRC is compared and the two grids swapped: the
//! controller never sees a half-written grid, and no step pays for a whole frame.
//!
//! A frame is applied only when it is whole, its CRC is right, its header is valid, it is newer than
//! the last applied one and its image is younger than `max_age_ms`. Everything else is counted in
//! [`RxStats`] and dropped; after a refusal the parser restarts one byte after the refused frame's
//! first byte, so a frame that began inside it is still found. A frame whose bytes stop arriving for
//! `byte_timeout_ms` (everything held already parsed) is dropped as short.
//!
//! **Age.** The weights' age ([`Receiver::weights_age_ms`]) is the arrival of the frame's first byte
//! less the header's `age_ms` (the image's age when the host handed the frame to its serial port).
//! That is a **lower bound** on the true age, not the capture time: the time the frame spent in the
//! host's buffers (its driver, a USB-serial adapter) and queued behind earlier frames still being
//! sent is counted nowhere, so the capture can be earlier than this origin by that much. The host
//! must therefore write a frame only once its transmit queue has drained (`tcdrain`), so that at
//! most the frame's own line time is uncounted; a protocol-level bound (the host echoes an MCU clock
//! value it received, so the MCU measures the whole round trip) is an open item. It does not count from the frame's application: a frame parsed `budget_bytes` at a time, or
//! behind a backlog, is applied late, and counting from then would hide that delay (review finding:
//! about 160 ms for a 30 x 30 frame at a 256 B budget). The arrival time of each byte comes from the
//! `now_ms` of the [`Receiver::push`] that brought it (up to [`MARKS`] distinct push times are
//! kept; beyond that the newest bytes are stamped with an older time: conservative). Bytes read by
//! the first [`Receiver::poll`] are stamped with that poll's time although they may have waited in
//! the port since before it (see `poll`): not yet conservative, an open item.
//!
//! **Overrun and backlog stop the tool.** Bytes that find the ring full are dropped and counted
//! (`overrun`), and the weights in use are forgotten ([`Receiver::weights_age_ms`] is `None`: the
//! watchdog stops): the line brings more than the parser takes, so every later frame would be late.
//! Likewise when the oldest byte still held waited longer than `max_age_ms` (`backlog`): whatever
//! frame it belongs to would be refused as too old anyway. Either way the next whole, fresh frame
//! brings the tool back, which a link that stays overloaded never delivers.
//!
//! **Sessions** (byte 5). "Newer" within a session: a sequence number after the last applied one
//! (wrapping). A frame from another session is applied only when the weights in use are stale (none,
//! forgotten, or at least `new_session_after_ms` old: set it to the watchdog's `stop_after_ms`, so
//! the tool is already stopped), and never from a session applied before since boot (a 256-bit
//! set): a host that restarts with a fresh session is accepted once the old weights have stopped the
//! tool, and two writers on one port cannot take turns (the second is refused while the first keeps
//! the weights fresh, and once it has taken over the first is refused for good). "Before since boot"
//! rather than a wrapping order: a byte has no order that survives 256 restarts, and a set needs no
//! argument about wrap; the cost is that a host that picks a byte used earlier in this run is refused
//! (the tool stays stopped, counted as `old_session`) until it restarts with another, and that after
//! 256 distinct sessions applied in one MCU run every byte is used: every session is refused and the
//! tool stays stopped until the MCU is reset. Two writers that use the *same* session byte are one
//! session to the receiver: they are told apart only by the sequence number (the one behind is
//! refused as not newer, the one ahead is applied), so they can take turns when their numbers
//! interleave; the host must pick a byte no other writer uses.

use super::field::Grid;
use super::frame::{FrameHeader, MAX_FRAME};
use super::num::Real;

/// Bytes the ring holds: a power of two, at least one longest frame.
pub const RING: usize = 4096;
const _: () = assert!(RING >= MAX_FRAME && RING.is_power_of_two());

/// The frame's CRC (the same CRC-32/ISO-HDLC as [`frame::CRC`]), static so its digest can live in
/// the receiver.
static CRC16: crc::Crc<u32, crc::Table<1>> = crc::Crc::<u32, crc::Table<1>>::new(&crc::CRC_32_ISO_HDLC);

/// Counters of what the receiver saw.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RxStats {
    /// Frames applied.
    pub good: u32,
    /// Frames with a wrong CRC.
    pub bad_crc: u32,
    /// Headers out of range (version, grid size, geometry).
    pub bad_header: u32,
    /// Frames cut off (no byte for `byte_timeout_ms` mid-frame).
    pub short: u32,
    /// Whole, correct frames refused as old: sequence number not newer, or image too old.
    pub stale: u32,
    /// Bytes skipped while looking for a sync pair.
    pub skipped_bytes: u32,
    /// Bytes lost because the ring was full.
    pub overrun: u32,
    /// Frames accepted from a new session (a restarted host).
    pub new_sessions: u32,
    /// Whole, correct frames of another session refused: the weights in use were not stale yet, or
    /// the session was applied before since boot.
    pub old_session: u32,
    /// Times the weights were forgotten because a byte waited longer than `max_age_ms` unparsed.
    pub backlog: u32,
}

/// Distinct push times kept for the bytes held (each `(first byte's index, ms)`).
pub const MARKS: usize = 16;

/// The receiving side of the weights link, holding two grids.
pub struct Receiver<R> {
    ring: [u8; RING],
    /// Ring index of the candidate frame's first byte.
    start: usize,
    /// Bytes held from `start`.
    count: usize,
    /// Bytes of the candidate already parsed (0 = looking for SYNC0).
    done: usize,
    /// The candidate's header, once parsed, and its length.
    hdr: Option<(FrameHeader, usize)>,
    digest: crc::Digest<'static, u32, crc::Table<1>>,
    /// The weight being assembled (a shift register of the last four bytes).
    word: u32,
    /// The parser waits for bytes (everything it can parse is parsed).
    blocked: bool,
    last_byte_ms: u32,
    grids: [Grid<R>; 2],
    active: usize,
    have_grid: bool,
    last: Option<(u8, u32)>,
    /// Sessions applied since boot, one bit each.
    seen: [u32; 8],
    /// Capture bound of the grid in use: its first byte's arrival less its `age_ms`, ms.
    origin_ms: u32,
    /// The header of the frame whose grid is in use (its sensed separations and clock echo).
    in_use: FrameHeader,
    /// Index (counting every byte ever pushed, wrapping) of the byte at `start`.
    start_abs: u32,
    /// Arrival marks, a ring: `(index of the first byte pushed at that time, ms)`.
    marks: [(u32, u32); MARKS],
    mark_head: usize,
    mark_len: usize,
    /// Bytes still in the serial port were waiting since at least this time ([`Receiver::poll`]).
    polled_since_ms: Option<u32>,
    /// A backlog is being reported (counted once per episode).
    in_backlog: bool,
    /// Longest image age accepted, ms.
    pub max_age_ms: u16,
    /// Longest gap between two bytes of one frame, ms.
    pub byte_timeout_ms: u32,
    /// Most bytes parsed per [`Receiver::service`] call (and read per [`Receiver::poll`]).
    pub budget_bytes: usize,
    /// A frame of another session is applied only when the weights in use are at least this old
    /// (ms), or none: set it to the weights watchdog's `stop_after_ms`. [`Receiver::new`] sets
    /// [`EXPIRE_MS`] (conservative: a restarted host waits until the old weights are forgotten).
    pub new_session_after_ms: u32,
    /// Counters.
    pub stats: RxStats,
}

/// Weights this old (ms) are forgotten by [`Receiver::tick`]: far beyond any weights watchdog's
/// stop time, far below the 2^32 ms at which the age would wrap.
pub const EXPIRE_MS: u32 = 60_000;

impl<R: Real> Receiver<R> {
    /// A receiver with no grid yet; the budget is one ring per call (set `budget_bytes` for a
    /// bounded step).
    pub fn new(max_age_ms: u16, byte_timeout_ms: u32) -> Self {
        Receiver {
            ring: [0; RING],
            start: 0,
            count: 0,
            done: 0,
            hdr: None,
            digest: CRC16.digest(),
            word: 0,
            blocked: false,
            last_byte_ms: 0,
            grids: [Grid::empty(), Grid::empty()],
            active: 0,
            have_grid: false,
            last: None,
            seen: [0; 8],
            origin_ms: 0,
            in_use: FrameHeader::default(),
            start_abs: 0,
            marks: [(0, 0); MARKS],
            mark_head: 0,
            mark_len: 0,
            polled_since_ms: None,
            in_backlog: false,
            max_age_ms,
            byte_timeout_ms,
            budget_bytes: RING,
            new_session_after_ms: EXPIRE_MS,
            stats: RxStats::default(),
        }
    }

    /// The grid in use (empty, all-zero field, until the first good frame).
    pub fn grid(&self) -> &Grid<R> {
        let [a, b] = &self.grids;
        if self.active == 1 {
            b
        } else {
            a
        }
    }

    /// The header of the frame in use (the monitor's sensed separations and the MCU clock echo);
    /// `None` when [`Receiver::weights_age_ms`] is (no weights, or forgotten).
    pub fn header_in_use(&self) -> Option<&FrameHeader> {
        self.have_grid.then_some(&self.in_use)
    }

    /// Age of the grid in use, ms: from its capture bound (its first byte's arrival less its
    /// `age_ms`), not from its application. `None` if there is none (none yet, forgotten after
    /// [`EXPIRE_MS`], or dropped on an overrun or backlog).
    pub fn weights_age_ms(&self, now_ms: u32) -> Option<u32> {
        if self.have_grid {
            Some(now_ms.wrapping_sub(self.origin_ms))
        } else {
            None
        }
    }

    /// Arrival time (ms) of the byte `k` places after the candidate's first (the newest mark at or
    /// before it; bounded by [`MARKS`]).
    fn arrival_ms(&self, k: usize) -> u32 {
        let at = self.start_abs.wrapping_add(k as u32);
        let mut t = self.marks.get(self.mark_head).map_or(0, |m| m.1);
        for i in 1..self.mark_len.min(MARKS) {
            let Some(&(pos, ms)) = self.marks.get(self.mark_head.wrapping_add(i) % MARKS) else { break };
            if (at.wrapping_sub(pos) as i32) < 0 {
                break;
            }
            t = ms;
        }
        t
    }

    /// Drop `n` bytes from the ring's front (consumed or refused), and the marks they no longer
    /// need (the first mark kept is the one of the new first byte).
    fn advance(&mut self, n: usize) {
        let n = n.min(self.count);
        self.start = self.start.wrapping_add(n) & (RING - 1);
        self.count = self.count.saturating_sub(n);
        self.start_abs = self.start_abs.wrapping_add(n as u32);
        for _ in 0..MARKS {
            if self.count == 0 {
                self.mark_len = 0;
                return;
            }
            let next = self.marks.get(self.mark_head.wrapping_add(1) % MARKS).map_or(0, |m| m.0);
            if self.mark_len >= 2 && (self.start_abs.wrapping_sub(next) as i32) >= 0 {
                self.mark_head = self.mark_head.wrapping_add(1) % MARKS;
                self.mark_len = self.mark_len.saturating_sub(1);
            } else {
                return;
            }
        }
    }

    /// Forget the weights in use (the watchdog then stops).
    fn forget(&mut self) {
        self.have_grid = false;
    }

    /// Bytes held (a frame in progress and bytes not yet parsed).
    pub fn pending(&self) -> usize {
        self.count
    }

    #[inline]
    fn at(&self, k: usize) -> u8 {
        *self.ring.get(self.start.wrapping_add(k) & (RING - 1)).unwrap_or(&0)
    }

    /// Refuse, as short, a frame that stopped arriving (the parser waits for bytes and none came
    /// for `byte_timeout_ms`); the bytes after its first are parsed again. Call every control step.
    pub fn tick(&mut self, now_ms: u32) {
        // Weights older than EXPIRE_MS are forgotten (age `None`: the watchdog stops), so the age
        // can never wrap round to "fresh" after 2^32 ms (49.7 days) without a good frame.
        if self.have_grid && now_ms.wrapping_sub(self.origin_ms) > EXPIRE_MS {
            self.have_grid = false;
        }
        // Backlog: the oldest byte held waited longer than any frame may be old; whatever frame it
        // starts would be refused, and the weights in use are being replaced that late.
        let waited = if self.count > 0 { now_ms.wrapping_sub(self.arrival_ms(0)) } else { 0 };
        if waited > u32::from(self.max_age_ms) {
            if !self.in_backlog {
                self.stats.backlog = self.stats.backlog.saturating_add(1);
            }
            self.in_backlog = true;
            self.forget();
        } else {
            self.in_backlog = false;
        }
        if self.count > 0 && self.blocked && now_ms.wrapping_sub(self.last_byte_ms) > self.byte_timeout_ms {
            self.stats.short = self.stats.short.saturating_add(1);
            // Its bytes may hold the start of a whole frame (the cut one's length swallowed it):
            // parse again from its second byte.
            self.refuse();
            self.blocked = false;
        }
    }

    /// Copy bytes into the ring (what an interrupt handler does); what does not fit is counted as
    /// overrun. Returns the bytes taken.
    pub fn push(&mut self, bytes: &[u8], now_ms: u32) -> usize {
        let room = RING.saturating_sub(self.count);
        let n = bytes.len().min(room);
        if n > 0 {
            self.last_byte_ms = now_ms;
            self.blocked = false;
            self.mark(now_ms);
        }
        let w = self.start.wrapping_add(self.count) & (RING - 1);
        // At most two runs: to the ring's end, then from its start.
        let first = n.min(RING.saturating_sub(w));
        if let (Some(dst), Some(src)) = (self.ring.get_mut(w..w.saturating_add(first)), bytes.get(..first)) {
            dst.copy_from_slice(src);
        }
        if let (Some(dst), Some(src)) = (self.ring.get_mut(..n.saturating_sub(first)), bytes.get(first..n)) {
            dst.copy_from_slice(src);
        }
        self.count = self.count.saturating_add(n);
        let lost = bytes.len().saturating_sub(n);
        if lost > 0 {
            // The line brings more than the parser takes: every later frame would be late.
            self.stats.overrun = self.stats.overrun.saturating_add(u32::try_from(lost).unwrap_or(u32::MAX));
            self.forget();
        }
        n
    }

    /// Stamp the bytes about to be pushed (at ring index `count`) with `now_ms`: a new mark, unless
    /// the newest has the same time or all [`MARKS`] are in use (then they keep the newest mark's
    /// older time: conservative).
    fn mark(&mut self, now_ms: u32) {
        let pos = self.start_abs.wrapping_add(self.count as u32);
        if self.count == 0 {
            self.mark_head = 0;
            self.mark_len = 0;
        }
        let last = self.marks.get(self.mark_head.wrapping_add(self.mark_len).wrapping_add(MARKS - 1) % MARKS).map(|m| m.1);
        if self.mark_len > 0 && (last == Some(now_ms) || self.mark_len >= MARKS) {
            return;
        }
        if let Some(m) = self.marks.get_mut(self.mark_head.wrapping_add(self.mark_len) % MARKS) {
            *m = (pos, now_ms);
            self.mark_len = self.mark_len.saturating_add(1);
        }
    }

    /// Feed received bytes and parse them all (a test and host convenience: unbounded by the
    /// budget, bounded by the input's length).
    pub fn feed(&mut self, bytes: &[u8], now_ms: u32) {
        self.tick(now_ms);
        let mut rest = bytes;
        // Each pass takes at least one byte or parses everything held.
        for _ in 0..=bytes.len() {
            let n = self.push(rest, now_ms);
            rest = rest.get(n..).unwrap_or(&[]);
            self.drain(now_ms);
            if rest.is_empty() {
                break;
            }
        }
    }

    /// Parse until everything held is parsed (bounded: every call parses or drops bytes).
    fn drain(&mut self, now_ms: u32) {
        for _ in 0..(2 * RING) {
            if self.blocked || self.count == 0 {
                return;
            }
            self.service(now_ms);
        }
    }

    /// Read what `serial` has ready, at most `budget_bytes` and what the ring holds, and parse at
    /// most `budget_bytes`: one control step's share of frame handling.
    ///
    /// The bytes read are stamped with the time of the last poll that left the port empty (they
    /// arrived after it; conservative by up to one poll period), or `now_ms` on the first poll. That
    /// first stamp is **not** conservative: bytes already in the port may have waited there since
    /// before it (open item: stamping them `max_age_ms` old refuses a frame already waiting at the
    /// first poll, which changes the host harness's runs, so it needs a decision; meanwhile poll once
    /// before the host may write).
    pub fn poll<S: embedded_io::Read + embedded_io::ReadReady>(&mut self, serial: &mut S, now_ms: u32) -> Result<usize, S::Error> {
        let mut chunk = [0u8; 64];
        let mut total: usize = 0;
        let stamp = self.polled_since_ms.unwrap_or(now_ms);
        for _ in 0..(RING / 64 + 1) {
            let want = self.budget_bytes.saturating_sub(total).min(RING.saturating_sub(self.count)).min(chunk.len());
            if want == 0 || !serial.read_ready()? {
                break;
            }
            let n = serial.read(chunk.get_mut(..want).unwrap_or(&mut []))?;
            if n == 0 {
                break;
            }
            self.push(chunk.get(..n).unwrap_or(&[]), stamp);
            // The byte-gap timeout counts from now: these bytes were read now.
            self.last_byte_ms = now_ms;
            total = total.saturating_add(n);
        }
        if !serial.read_ready()? {
            self.polled_since_ms = Some(now_ms);
        } else if self.polled_since_ms.is_none() {
            self.polled_since_ms = Some(stamp);
        }
        self.tick(now_ms);
        self.service(now_ms);
        Ok(total)
    }

    fn restart(&mut self) {
        self.done = 0;
        self.hdr = None;
        self.digest = CRC16.digest();
        self.word = 0;
    }

    /// Give up the candidate: drop its first byte and parse again from the next one.
    fn refuse(&mut self) {
        self.advance(1);
        self.restart();
    }
}

// Parsing (`service`, the header, the weights, the freshness checks), in its own file.
mod parse;

#[cfg(test)]
mod tests;
#[cfg(test)]
mod proptests;
