//! The receiver's parser: [`Receiver::service`] takes at most `budget_bytes` of the ring per call,
//! decodes the header once per frame, runs the CRC and decodes each weight into the inactive grid as
//! its bytes go by, and at the frame's end checks the CRC, the session and the age and swaps the
//! grids ([`Receiver::apply`]). The ring, the counters and the timing live in `receiver.rs`.

use super::{Receiver, CRC16, RING};
use crate::avoidance::frame::{self, FrameHeader, HEADER_LEN, SYNC0, SYNC1};
use crate::avoidance::num::Real;

impl<R: Real> Receiver<R> {
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
                    // The header's bytes go through the CRC as they arrive (a step pays for the
                    // bytes it parses, not for the whole header at once); once all are in, it is
                    // decoded.
                    let avail = self.count.min(HEADER_LEN).saturating_sub(d).min(left);
                    if avail == 0 {
                        if self.count <= d {
                            self.blocked = true;
                        }
                        return;
                    }
                    self.crc_run(d, avail);
                    left = left.saturating_sub(avail);
                    self.done = d.saturating_add(avail);
                    if self.done >= HEADER_LEN && !self.header() {
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

    /// The CRC over `n` held bytes from the candidate's byte `d` (at most two runs of the ring).
    fn crc_run(&mut self, d: usize, n: usize) {
        let from = self.start.wrapping_add(d) & (RING - 1);
        let first = n.min(RING.saturating_sub(from));
        if let Some(run) = self.ring.get(from..from.saturating_add(first)) {
            self.digest.update(run);
        }
        if let Some(run) = self.ring.get(..n.saturating_sub(first)) {
            self.digest.update(run);
        }
    }

    /// The `HEADER_LEN` header bytes are held and through the CRC: decode them once, set the
    /// inactive grid's geometry. `false` if the header is invalid.
    fn header(&mut self) -> bool {
        let mut h = [0u8; HEADER_LEN];
        // At most two runs of the ring (it wraps once).
        let first = HEADER_LEN.min(RING.saturating_sub(self.start));
        let (a, b) = h.split_at_mut(first);
        if let Some(run) = self.ring.get(self.start..self.start.saturating_add(first)) {
            a.copy_from_slice(run);
        }
        if let Some(run) = self.ring.get(..b.len()) {
            b.copy_from_slice(run);
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
        self.in_use = *hdr;
        self.stats.good = self.stats.good.saturating_add(1);
    }
}
