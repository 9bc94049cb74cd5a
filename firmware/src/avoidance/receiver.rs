//! Frame receiver: a byte ring, an incremental parser with a per-call byte budget, a double-buffered
//! grid, counters.
//!
//! Bytes go in through [`Receiver::feed`] (or [`Receiver::poll`] from an `embedded-io` reader) into
//! a ring of [`RING`] bytes. [`Receiver::service`] parses at most `budget_bytes` of them per call, so
//! one control step's share of frame handling is bounded whatever arrives: the header is decoded
//! once per frame (when its 28 bytes are in), the CRC is updated as the bytes go by (the 1 KiB
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
use super::frame::{self, FrameHeader, HEADER_LEN, MAX_FRAME, SYNC0, SYNC1};
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

    /// Parse at most `budget_bytes` of what is held.
    pub fn service(&mut self, now_ms: u32) {
        let mut left = self.budget_bytes;
        // Each pass parses or drops at least one byte, or returns.
        for _ in 0..=self.budget_bytes {
            if self.done >= self.count {
                self.blocked = true;
                return;
            }
            if left == 0 {
                return;
            }
            match self.done {
                0 => {
                    left = left.saturating_sub(1);
                    if self.at(0) == SYNC0 {
                        self.done = 1;
                    } else {
                        self.stats.skipped_bytes = self.stats.skipped_bytes.saturating_add(1);
                        self.refuse();
                    }
                }
                1 => {
                    left = left.saturating_sub(1);
                    if self.at(1) == SYNC1 {
                        self.done = 2;
                    } else {
                        self.refuse();
                    }
                }
                d if d < HEADER_LEN => {
                    if self.count < HEADER_LEN {
                        self.blocked = true;
                        return;
                    }
                    left = left.saturating_sub(HEADER_LEN.saturating_sub(d));
                    if !self.header() {
                        self.stats.bad_header = self.stats.bad_header.saturating_add(1);
                        self.refuse();
                    }
                }
                d => {
                    let Some((hdr, flen)) = self.hdr else {
                        self.refuse();
                        continue;
                    };
                    let body_end = flen.saturating_sub(frame::CRC_LEN);
                    if d < body_end {
                        left = self.body(d, body_end, left);
                    } else {
                        if self.count < flen {
                            self.blocked = true;
                            return;
                        }
                        left = left.saturating_sub(flen.saturating_sub(d));
                        let got = u32::from_le_bytes([0usize, 1, 2, 3].map(|i| self.at(body_end.saturating_add(i))));
                        let crc = core::mem::replace(&mut self.digest, CRC16.digest()).finalize();
                        if crc == got {
                            self.apply(&hdr, now_ms);
                            self.advance(flen);
                            self.restart();
                        } else {
                            self.stats.bad_crc = self.stats.bad_crc.saturating_add(1);
                            self.refuse();
                        }
                    }
                }
            }
        }
    }

    /// The 28 header bytes are held: decode them once, start the CRC, set the inactive grid's
    /// geometry. `false` if the header is invalid.
    fn header(&mut self) -> bool {
        let mut h = [0u8; HEADER_LEN];
        for (k, b) in h.iter_mut().enumerate() {
            *b = self.at(k);
        }
        let Some(hdr) = frame::decode_header(&h) else { return false };
        let Some(flen) = frame::frame_len(hdr.nx as usize, hdr.ny as usize) else { return false };
        let inactive = if self.active == 0 { 1 } else { 0 };
        let Some(g) = self.grids.get_mut(inactive) else { return false };
        let ok = g.set_geometry(
            hdr.nx as usize,
            hdr.ny as usize,
            R::from_q16(hdr.x0_q16),
            R::from_q16(hdr.y0_q16),
            R::from_q16(hdr.spacing_q16),
            R::from_q16(hdr.sigma_q16),
        );
        if !ok {
            return false;
        }
        self.digest.update(h.get(2..).unwrap_or(&[]));
        self.hdr = Some((hdr, flen));
        self.done = HEADER_LEN;
        true
    }

    /// Parse weight bytes from `d` up to `body_end` (at most `left` and what is held): CRC, and
    /// each completed weight into the inactive grid. Returns the budget left.
    fn body(&mut self, d: usize, body_end: usize, left: usize) -> usize {
        let avail = self.count.min(body_end).saturating_sub(d).min(left);
        if avail == 0 {
            // Waiting for bytes, or out of budget.
            return 0;
        }
        let inactive = if self.active == 0 { 1 } else { 0 };
        let from = self.start.wrapping_add(d) & (RING - 1);
        // At most two contiguous runs (the ring wraps once).
        let first = avail.min(RING.saturating_sub(from));
        let mut k = d.saturating_sub(HEADER_LEN);
        let mut word = self.word;
        for (a, n) in [(from, first), (0, avail.saturating_sub(first))] {
            let Some(run) = self.ring.get(a..a.saturating_add(n)) else { break };
            self.digest.update(run);
            let Some(g) = self.grids.get_mut(inactive) else { break };
            // Bytes up to the next weight boundary through the shift register ...
            let lead = 4usize.saturating_sub(k % 4) % 4;
            let (head, rest) = run.split_at(lead.min(run.len()));
            for &b in head {
                word = (word >> 8) | ((b as u32) << 24);
                k = k.saturating_add(1);
                if k.is_multiple_of(4) {
                    if let Some(w) = g.weights.get_mut((k / 4).saturating_sub(1)) {
                        *w = R::from_q16(word as i32);
                    }
                }
            }
            // ... whole weights four bytes at a time ...
            let mut chunks = rest.chunks_exact(4);
            let mut idx = k / 4;
            for c in &mut chunks {
                if let (Some(w), [b0, b1, b2, b3]) = (g.weights.get_mut(idx), c) {
                    *w = R::from_q16(i32::from_le_bytes([*b0, *b1, *b2, *b3]));
                }
                idx = idx.saturating_add(1);
            }
            k = k.saturating_add(rest.len().saturating_sub(chunks.remainder().len()));
            // ... and the start of the next one.
            for &b in chunks.remainder() {
                word = (word >> 8) | ((b as u32) << 24);
                k = k.saturating_add(1);
            }
        }
        self.word = word;
        self.done = d.saturating_add(avail);
        left.saturating_sub(avail)
    }

    /// A whole frame with a good CRC, its weights already in the inactive grid: check freshness,
    /// swap.
    fn apply(&mut self, hdr: &FrameHeader, now_ms: u32) {
        // Capture bound: the first byte's arrival less the image's age when sent.
        let origin = self.arrival_ms(0).wrapping_sub(u32::from(hdr.age_ms));
        let age = now_ms.wrapping_sub(origin);
        let seen = |s: &[u32; 8], k: u8| s.get(usize::from(k >> 5)).is_some_and(|w| w & (1 << (k & 31)) != 0);
        let (newer, new_session) = match self.last {
            None => (true, false),
            Some((session, seq)) if session == hdr.session => ((hdr.seq.wrapping_sub(seq) as i32) > 0, false),
            Some(_) => {
                let stale = self.weights_age_ms(now_ms).is_none_or(|a| a >= self.new_session_after_ms);
                if !stale || seen(&self.seen, hdr.session) {
                    self.stats.old_session = self.stats.old_session.saturating_add(1);
                    return;
                }
                (true, true)
            }
        };
        if !newer || age > u32::from(self.max_age_ms) {
            self.stats.stale = self.stats.stale.saturating_add(1);
            return;
        }
        if new_session {
            self.stats.new_sessions = self.stats.new_sessions.saturating_add(1);
        }
        if let Some(w) = self.seen.get_mut(usize::from(hdr.session >> 5)) {
            *w |= 1 << (hdr.session & 31);
        }
        let inactive = if self.active == 0 { 1 } else { 0 };
        if let Some(g) = self.grids.get_mut(inactive) {
            g.seq = hdr.seq;
        }
        self.active = inactive;
        self.have_grid = true;
        self.last = Some((hdr.session, hdr.seq));
        self.origin_ms = origin;
        self.stats.good = self.stats.good.saturating_add(1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::avoidance::frame::{encode_frame, frame_len, FrameHeader, MAX_FRAME};
    use proptest::prelude::*;

    extern crate std;
    use std::vec;
    use std::vec::Vec;

    fn header(nx: u8, ny: u8, seq: u32) -> FrameHeader {
        FrameHeader {
            session: 0,
            nx,
            ny,
            seq,
            age_ms: 10,
            x0_q16: 1 << 14,
            y0_q16: 2 << 14,
            spacing_q16: 1 << 15,
            sigma_q16: 1 << 14,
        }
    }

    fn frame(h: &FrameHeader, w: &[i32]) -> Vec<u8> {
        let mut out = vec![0u8; MAX_FRAME];
        let n = encode_frame(h, w, &mut out).expect("encodes");
        out.truncate(n);
        out
    }

    fn weights(n: usize, salt: i32) -> Vec<i32> {
        (0..n as i32).map(|k| k.wrapping_mul(2654435).wrapping_add(salt) % 40000).collect()
    }

    fn rx() -> Receiver<Q16> {
        Receiver::new(100, 20)
    }
    type Q16 = fixed::types::I16F16;

    #[test]
    fn good_frame_is_applied_exactly() {
        let w = weights(15 * 15, 3);
        let f = frame(&header(15, 15, 1), &w);
        assert_eq!(f.len(), frame_len(15, 15).unwrap_or(0));
        let mut r = rx();
        r.feed(&f, 5);
        assert_eq!(r.stats.good, 1);
        assert_eq!(r.grid().nx, 15);
        for (k, w) in w.iter().enumerate() {
            assert_eq!(r.grid().weights[k].to_bits(), *w);
        }
        // From the first byte's arrival (5 ms) less the image's age when sent (10 ms).
        assert_eq!(r.weights_age_ms(25), Some(30));
    }

    /// Review finding: the age wrapped after 2^32 ms without a good frame and read as fresh.
    #[test]
    fn weights_expire_before_their_age_can_wrap() {
        let mut r = rx();
        let mut h = header(3, 3, 1);
        h.age_ms = 0;
        r.feed(&frame(&h, &weights(9, 1)), 5);
        r.tick(5 + EXPIRE_MS);
        assert_eq!(r.weights_age_ms(5 + EXPIRE_MS), Some(EXPIRE_MS));
        r.tick(5 + EXPIRE_MS + 1);
        assert_eq!(r.weights_age_ms(5 + EXPIRE_MS + 1), None);
        // Still None where the age would have wrapped to a few ms.
        r.tick(5u32.wrapping_add(u32::MAX).wrapping_add(3));
        assert_eq!(r.weights_age_ms(5u32.wrapping_add(u32::MAX).wrapping_add(3)), None);
        // A good frame brings it back.
        r.feed(&frame(&header(3, 3, 2), &weights(9, 2)), 10);
        assert_eq!(r.weights_age_ms(30), Some(30));
    }

    #[test]
    fn bad_frame_after_good_keeps_the_good_one() {
        let a = weights(9, 1);
        let b = weights(9, 7);
        let mut r = rx();
        r.feed(&frame(&header(3, 3, 1), &a), 0);
        let mut bad = frame(&header(3, 3, 2), &b);
        bad[40] ^= 0x10;
        r.feed(&bad, 1);
        assert_eq!(r.stats.bad_crc, 1);
        assert_eq!(r.grid().seq, 1);
        for (k, w) in a.iter().enumerate() {
            assert_eq!(r.grid().weights[k].to_bits(), *w);
        }
    }

    #[test]
    fn stale_and_old_frames_are_refused() {
        let w = weights(4, 0);
        let mut r = rx();
        r.feed(&frame(&header(2, 2, 10), &w), 0);
        r.feed(&frame(&header(2, 2, 10), &w), 1);
        r.feed(&frame(&header(2, 2, 9), &w), 2);
        let mut old = header(2, 2, 11);
        old.age_ms = 500;
        r.feed(&frame(&old, &w), 3);
        assert_eq!((r.stats.good, r.stats.stale), (1, 3));
        // Wrapping sequence numbers are still newer.
        let mut r = rx();
        r.feed(&frame(&header(2, 2, u32::MAX), &w), 0);
        r.feed(&frame(&header(2, 2, 0), &w), 1);
        assert_eq!(r.stats.good, 2);
    }

    #[test]
    fn short_frame_times_out_and_the_next_one_gets_through() {
        let w = weights(4, 0);
        let f = frame(&header(2, 2, 1), &w);
        let mut r = rx();
        r.feed(&f[..20], 0);
        r.tick(100);
        assert_eq!(r.stats.short, 1);
        r.service(100);
        assert_eq!(r.pending(), 0);
        r.feed(&frame(&header(2, 2, 2), &w), 101);
        assert_eq!(r.stats.good, 1);
    }

    #[test]
    fn resyncs_on_a_frame_inside_garbage() {
        let w = weights(4, 0);
        let f = frame(&header(2, 2, 1), &w);
        let mut stream = vec![SYNC0, SYNC1, frame::VERSION, 2, 2, 0, 0, 0, 0xA5, 0xA5];
        stream.extend_from_slice(&f[..10]); // cut-off start of a frame ...
        stream.extend_from_slice(&f); // ... then the whole one
        let mut r = rx();
        r.feed(&stream, 0);
        assert_eq!(r.stats.good, 1);
    }

    fn in_session(mut h: FrameHeader, session: u8) -> FrameHeader {
        h.session = session;
        h
    }

    /// Review finding (issue 11 follow-up): a new session was accepted at once, so two writers on one
    /// port took turns. Now the second is refused while the first keeps the weights fresh; once the
    /// first has gone quiet long enough for the watchdog to stop the tool, the second takes over, and
    /// the first is never accepted again.
    #[test]
    fn two_interleaved_writers_do_not_take_turns() {
        let w = weights(4, 0);
        let mut r = rx();
        r.max_age_ms = 1000;
        r.new_session_after_ms = 300;
        let mut t = 0u32;
        // A (session 1) and B (session 2) interleaved, each counting from 1.
        for k in 1..=20u32 {
            r.feed(&frame(&in_session(header(2, 2, k), 1), &w), t);
            r.feed(&frame(&in_session(header(2, 2, k + 100), 2), &w), t + 5);
            assert_eq!(r.last.map(|l| l.0), Some(1), "frame {k}: B's frame was applied");
            t += 10;
        }
        assert_eq!((r.stats.good, r.stats.old_session, r.stats.new_sessions), (20, 20, 0));
        // A goes quiet: B is still refused until A's weights are 300 ms old (the watchdog's stop) ...
        let last_a = t - 10;
        for k in 21..=60u32 {
            r.feed(&frame(&in_session(header(2, 2, k + 100), 2), &w), t);
            let age = r.weights_age_ms(t).unwrap_or(u32::MAX);
            if r.last.map(|l| l.0) == Some(2) {
                break;
            }
            assert!(t < last_a + 300, "B still refused at {t} ms");
            let _ = (k, age);
            t += 10;
        }
        // ... then it is accepted (A's weights counted from A's last frame's arrival less its age).
        assert_eq!(r.last.map(|l| l.0), Some(2));
        assert!(t >= last_a + 300 - 10 && t <= last_a + 300 + 10, "B taken over at {t} ms, A's last frame at {last_a}");
        assert_eq!(r.stats.new_sessions, 1);
        // A comes back: refused for good, even once B's weights are stale.
        let refused = r.stats.old_session;
        for k in 0..5u32 {
            r.feed(&frame(&in_session(header(2, 2, 1000 + k), 1), &w), t + 1000 + k);
        }
        assert_eq!(r.last.map(|l| l.0), Some(2));
        assert_eq!(r.stats.old_session, refused + 5);
    }

    /// A host that restarts (new session, sequence numbers from 1) is accepted once the old weights
    /// are stale (the watchdog has stopped the tool), with any sequence number.
    #[test]
    fn a_restarted_host_is_accepted_after_the_stop() {
        let w = weights(4, 0);
        let mut r = rx();
        r.new_session_after_ms = 300;
        r.feed(&frame(&in_session(header(2, 2, 1000), 7), &w), 0);
        // Still fresh (age 10 + 100 ms): refused.
        r.feed(&frame(&in_session(header(2, 2, 1), 8), &w), 100);
        assert_eq!((r.stats.good, r.stats.old_session, r.grid().seq), (1, 1, 1000));
        // Stale (290 + 10 ms): accepted.
        r.feed(&frame(&in_session(header(2, 2, 1), 8), &w), 290);
        assert_eq!((r.stats.good, r.stats.new_sessions, r.grid().seq), (2, 1, 1));
        // Within the session the order still holds: an older number is refused.
        r.feed(&frame(&in_session(header(2, 2, 0), 8), &w), 300);
        assert_eq!((r.stats.good, r.stats.stale), (2, 1));
        // With no weights at all (forgotten), a new session is taken at once.
        r.tick(300 + EXPIRE_MS);
        r.feed(&frame(&in_session(header(2, 2, 5), 9), &w), 300 + EXPIRE_MS + 1);
        assert_eq!((r.stats.good, r.stats.new_sessions), (3, 2));
        // The first frame of all is not a new session.
        let mut fresh = rx();
        fresh.feed(&frame(&in_session(header(2, 2, 3), 7), &w), 0);
        assert_eq!((fresh.stats.good, fresh.stats.new_sessions), (1, 0));
    }

    /// Review finding: the age counted from the frame's application. A 30 x 30 frame whose bytes all
    /// arrive at once (a line faster than the budget) is parsed 256 bytes a step and applied about
    /// 140 ms later; its age must count from its first byte (less the header's `age_ms`).
    #[test]
    fn age_counts_from_the_first_byte_not_from_application() {
        let f = frame(&header(30, 30, 1), &weights(900, 4));
        let mut r = rx();
        r.max_age_ms = 250;
        r.budget_bytes = 256;
        assert_eq!(r.push(&f, 1000), f.len());
        let mut t = 1000;
        while r.stats.good == 0 && t < 2000 {
            r.tick(t);
            r.service(t);
            t += 10;
        }
        let applied = t - 10;
        assert_eq!(r.stats.good, 1);
        assert!(applied >= 1000 + 140, "applied at {applied}");
        // Age from the first byte (1000 ms) less age_ms (10): not 0.
        assert_eq!(r.weights_age_ms(applied), Some(applied - 1000 + 10));
        // The same with a 100 ms bound: too old when whole, refused, and the backlog is reported.
        let mut r = rx();
        r.budget_bytes = 256;
        r.push(&f, 1000);
        for t in (1000..1300).step_by(10) {
            r.tick(t);
            r.service(t);
        }
        assert_eq!((r.stats.good, r.stats.stale, r.stats.backlog), (0, 1, 1));
    }

    /// A byte that waited longer than `max_age_ms` unparsed forgets the weights in use at once (the
    /// watchdog stops), instead of letting them run until their own age stops the tool.
    #[test]
    fn a_backlog_beyond_the_stale_bound_stops() {
        let mut r = rx();
        r.feed(&frame(&header(3, 3, 1), &weights(9, 1)), 0);
        assert_eq!(r.weights_age_ms(0), Some(10));
        r.budget_bytes = 16;
        r.push(&frame(&header(30, 30, 2), &weights(900, 2)), 5);
        let mut t = 5;
        while r.weights_age_ms(t).is_some() && t < 1000 {
            t += 10;
            r.tick(t);
            r.service(t);
        }
        // Forgotten as soon as a byte has waited 100 ms (the old weights were then only 115 ms old).
        assert!(t > 105 && t <= 115, "forgotten at {t}");
        assert_eq!(r.stats.backlog, 1);
        // Only a whole fresh frame brings it back.
        r.budget_bytes = RING;
        for _ in 0..8 {
            t += 1000;
            r.tick(t);
            r.service(t);
        }
        r.feed(&frame(&header(3, 3, 3), &weights(9, 3)), t);
        assert_eq!(r.weights_age_ms(t), Some(10));
    }

    /// Bytes lost to a full ring forget the weights (counted, and the tool stops), not only counted.
    #[test]
    fn an_overrun_stops() {
        let mut r = rx();
        r.feed(&frame(&header(3, 3, 1), &weights(9, 1)), 0);
        r.budget_bytes = 16;
        let f = frame(&header(30, 30, 2), &weights(900, 2));
        r.push(&f, 1);
        r.push(&f, 2);
        assert!(r.stats.overrun > 0);
        assert_eq!(r.weights_age_ms(3), None);
    }

    #[test]
    fn one_call_parses_at_most_the_budget() {
        let w = weights(15 * 15, 9);
        let f = frame(&header(15, 15, 1), &w);
        let mut r = rx();
        r.budget_bytes = 40;
        assert_eq!(r.push(&f, 0), f.len());
        let calls = f.len().div_ceil(40);
        for k in 1..calls {
            r.service(k as u32);
            assert_eq!(r.stats.good, 0, "after {k} calls of 40 bytes ({} of {})", 40 * k, f.len());
        }
        r.service(calls as u32);
        assert_eq!(r.stats.good, 1);
        for (k, w) in w.iter().enumerate() {
            assert_eq!(r.grid().weights[k].to_bits(), *w);
        }
    }

    #[test]
    fn a_full_ring_counts_what_it_loses() {
        let mut r = rx();
        assert_eq!(r.push(&vec![0u8; RING + 10], 0), RING);
        assert_eq!(r.stats.overrun, 10);
        r.service(0);
        assert_eq!(r.pending(), 0);
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 256, .. ProptestConfig::default() })]

        /// Random bytes never panic and are (practically) never applied.
        #[test]
        fn garbage_is_never_applied(bytes in proptest::collection::vec(any::<u8>(), 0..4000)) {
            let mut r = rx();
            r.feed(&bytes, 0);
            prop_assert_eq!(r.stats.good, 0);
            prop_assert_eq!(r.grid().nx, 0);
        }

        /// Encode then parse, whatever the grid, split into arbitrary chunks.
        #[test]
        fn roundtrip(nx in 1u8..=30, ny in 1u8..=30, seq: u32, salt: i32, cut in 0usize..4000) {
            let w = weights(nx as usize * ny as usize, salt);
            let f = frame(&header(nx, ny, seq), &w);
            let cut = cut % f.len();
            let mut r = rx();
            r.feed(&f[..cut], 0);
            r.feed(&f[cut..], 1);
            prop_assert_eq!(r.stats.good, 1);
            prop_assert_eq!(r.grid().seq, seq);
            for (k, w) in w.iter().enumerate() {
                prop_assert_eq!(r.grid().weights[k].to_bits(), *w);
            }
        }

        /// Any corrupted byte of a good frame gets it refused; the previous grid stays in use.
        #[test]
        fn corrupted_frame_is_refused(pos in 0usize..(28 + 36 + 4), flip in 1u8..=255) {
            let a = weights(9, 1);
            let b = weights(9, 2);
            let mut r = rx();
            r.feed(&frame(&header(3, 3, 1), &a), 0);
            let mut bad = frame(&header(3, 3, 2), &b);
            let pos = pos % bad.len();
            bad[pos] ^= flip;
            r.feed(&bad, 1);
            r.tick(1000);
            prop_assert_eq!(r.stats.good, 1);
            prop_assert_eq!(r.grid().seq, 1);
            for (k, w) in a.iter().enumerate() {
                prop_assert_eq!(r.grid().weights[k].to_bits(), *w);
            }
            let refused = r.stats.bad_crc + r.stats.bad_header + r.stats.short + r.stats.stale;
            prop_assert!(refused >= 1 || r.stats.skipped_bytes > 0);
        }

        /// A stream of good frames, frames with a flipped bit, cut frames and garbage, in random
        /// chunks parsed with random budgets: no panic; every good frame is applied and nothing
        /// else (the grid in use is always exactly a good frame's); every damaged frame is refused
        /// and counted.
        #[test]
        fn any_stream_applies_exactly_the_good_frames(
            parts in proptest::collection::vec((0u8..4, 1u8..=6, 1u8..=6, any::<u16>(), 1u8..=255, proptest::collection::vec(any::<u8>(), 0..40)), 1..12),
            chunk in 1usize..300,
            budget in 1usize..400,
        ) {
            let mut stream = Vec::new();
            let mut goods: Vec<(u32, Vec<i32>)> = Vec::new();
            let mut damaged = 0u32;
            let mut seq = 0u32;
            let mut cut: Vec<(usize, u32, Vec<i32>, Vec<u8>)> = Vec::new();
            for (kind, nx, ny, at, flip, junk) in &parts {
                seq += 1;
                let w = weights(*nx as usize * *ny as usize, seq as i32);
                let f = frame(&header(*nx, *ny, seq), &w);
                match kind {
                    0 => { stream.extend_from_slice(&f); goods.push((seq, w)); }
                    1 => { let mut b = f.clone(); let k = *at as usize % b.len(); b[k] ^= flip; stream.extend_from_slice(&b); damaged += 1; }
                    2 => { cut.push((stream.len(), seq, w, f.clone())); stream.extend_from_slice(&f[..2 + *at as usize % (f.len() - 2)]); damaged += 1; }
                    _ => stream.extend_from_slice(junk),
                }
            }
            // A cut frame whose missing tail the following bytes happen to supply is whole in the
            // stream: a good frame (proptest found one: the next frame's first byte 0xA5 equal to
            // the cut CRC's last byte).
            for (at, seq, w, f) in cut {
                if stream.get(at..at + f.len()) == Some(&f[..]) {
                    goods.push((seq, w));
                    damaged -= 1;
                }
            }
            let mut r = rx();
            // Parsing, not freshness, is under test: a budget of 1 byte takes seconds a frame.
            r.max_age_ms = u16::MAX;
            r.budget_bytes = budget;
            let mut now = 0u32;
            let mut applied = 0u32;
            for c in stream.chunks(chunk) {
                let mut rest = c;
                for _ in 0..=RING {
                    let n = r.push(rest, now);
                    rest = &rest[n..];
                    r.service(now);
                    if r.stats.good != applied {
                        applied = r.stats.good;
                        let g = r.grid();
                        let (_, w) = goods.iter().find(|(s, _)| *s == g.seq).expect("the grid in use is a good frame's");
                        for (k, w) in w.iter().enumerate() {
                            prop_assert_eq!(g.weights[k].to_bits(), *w);
                        }
                    }
                    if rest.is_empty() { break; }
                }
                now += 1;
            }
            // Drain, then let the line go quiet (each silence refuses one cut candidate).
            for _ in 0..64 {
                for _ in 0..(2 * RING) { r.service(now); }
                now += 1000;
                r.tick(now);
            }
            prop_assert_eq!(r.stats.overrun, 0);
            prop_assert_eq!(r.stats.good as usize, goods.len());
            // A damaged frame is refused as a frame (CRC, header, short) or, with its sync bytes
            // hit, skipped byte by byte: never silently.
            if damaged > 0 {
                prop_assert!(r.stats.bad_crc + r.stats.bad_header + r.stats.short + r.stats.skipped_bytes > 0, "{:?}", r.stats);
            }
        }

        /// A truncated frame is never applied and is counted as short once the line goes quiet.
        #[test]
        fn truncated_frame_is_short(nx in 1u8..=6, keep in 0usize..200) {
            let w = weights(nx as usize * 2, 5);
            let f = frame(&header(nx, 2, 1), &w);
            let keep = 2 + keep % (f.len() - 2);
            let mut r = rx();
            r.feed(&f[..keep], 0);
            r.tick(50);
            prop_assert_eq!(r.stats.good, 0);
            prop_assert_eq!(r.stats.short, 1);
        }
    }
}
