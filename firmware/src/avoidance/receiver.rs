//! Frame receiver: byte-stream parser, double-buffered grid, counters.
//!
//! Bytes go in through [`Receiver::feed`] (or [`Receiver::poll`] from an `embedded-io` reader). A
//! frame is applied only when it is whole, its CRC is right, its header is valid, its sequence number
//! is newer than the last applied one and its image is younger than `max_age_ms`. It is decoded into
//! the inactive buffer and the buffers are swapped only then: the controller never sees a half-written
//! grid. Everything else is counted in [`RxStats`] and dropped; after a bad frame the parser resyncs
//! on the next sync pair already buffered. A frame that stops arriving for `byte_timeout_ms` is dropped
//! as short.

use super::field::Grid;
use super::frame::{self, FrameHeader, HEADER_LEN, MAX_FRAME, SYNC0, SYNC1};
use super::num::Real;

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
}

/// The receiving side of the weights link, holding two grids.
pub struct Receiver<R> {
    buf: [u8; MAX_FRAME],
    len: usize,
    last_byte_ms: u32,
    grids: [Grid<R>; 2],
    active: usize,
    have_grid: bool,
    last_seq: Option<u32>,
    applied_at_ms: u32,
    /// Longest image age accepted, ms.
    pub max_age_ms: u16,
    /// Longest gap between two bytes of one frame, ms.
    pub byte_timeout_ms: u32,
    /// Counters.
    pub stats: RxStats,
}

impl<R: Real> Receiver<R> {
    /// A receiver with no grid yet.
    pub fn new(max_age_ms: u16, byte_timeout_ms: u32) -> Self {
        Receiver {
            buf: [0; MAX_FRAME],
            len: 0,
            last_byte_ms: 0,
            grids: [Grid::empty(), Grid::empty()],
            active: 0,
            have_grid: false,
            last_seq: None,
            applied_at_ms: 0,
            max_age_ms,
            byte_timeout_ms,
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

    /// Milliseconds since the grid in use was applied, `None` if none was.
    pub fn weights_age_ms(&self, now_ms: u32) -> Option<u32> {
        if self.have_grid {
            Some(now_ms.wrapping_sub(self.applied_at_ms))
        } else {
            None
        }
    }

    /// Bytes of an incomplete frame held.
    pub fn pending(&self) -> usize {
        self.len
    }

    /// Drop a frame that stopped arriving; call every control step.
    pub fn tick(&mut self, now_ms: u32) {
        if self.len > 0 && now_ms.wrapping_sub(self.last_byte_ms) > self.byte_timeout_ms {
            self.stats.short = self.stats.short.saturating_add(1);
            self.len = 0;
        }
    }

    /// Feed received bytes.
    pub fn feed(&mut self, bytes: &[u8], now_ms: u32) {
        self.tick(now_ms);
        for &b in bytes {
            self.push(b, now_ms);
        }
    }

    /// Read what `serial` has ready (bounded: at most two frames' worth per call) and feed it.
    pub fn poll<S: embedded_io::Read + embedded_io::ReadReady>(
        &mut self,
        serial: &mut S,
        now_ms: u32,
    ) -> Result<usize, S::Error> {
        let mut chunk = [0u8; 64];
        let mut total: usize = 0;
        self.tick(now_ms);
        for _ in 0..(2 * MAX_FRAME / 64 + 1) {
            if !serial.read_ready()? {
                break;
            }
            let n = serial.read(&mut chunk)?;
            if n == 0 {
                break;
            }
            self.feed(chunk.get(..n).unwrap_or(&[]), now_ms);
            total = total.saturating_add(n);
        }
        Ok(total)
    }

    fn push(&mut self, b: u8, now_ms: u32) {
        self.last_byte_ms = now_ms;
        if self.len == 0 && b != SYNC0 {
            self.stats.skipped_bytes = self.stats.skipped_bytes.saturating_add(1);
            return;
        }
        if let Some(slot) = self.buf.get_mut(self.len) {
            *slot = b;
            self.len = self.len.saturating_add(1);
        } else {
            // Cannot happen: a frame is processed at its full length. Start over rather than panic.
            self.len = 0;
            return;
        }
        self.process(now_ms);
    }

    /// Drop the first `k` buffered bytes.
    fn drop_front(&mut self, k: usize) {
        let k = k.min(self.len);
        self.buf.copy_within(k..self.len, 0);
        self.len = self.len.saturating_sub(k);
    }

    /// Act on the buffer: skip to a sync pair, check the header, then the whole frame.
    fn process(&mut self, now_ms: u32) {
        // Each pass either returns (waiting for bytes) or drops at least one byte.
        for _ in 0..=MAX_FRAME {
            let head = match self.buf.get(..self.len) {
                Some(h) => h,
                None => return,
            };
            // Skip to the first SYNC0.
            let skip = head.iter().position(|&c| c == SYNC0).unwrap_or(self.len);
            if skip > 0 {
                self.stats.skipped_bytes = self.stats.skipped_bytes.saturating_add(skip as u32);
                self.drop_front(skip);
                continue;
            }
            if self.len < 2 {
                return;
            }
            if self.buf.get(1) != Some(&SYNC1) {
                self.drop_front(1);
                continue;
            }
            if self.len < HEADER_LEN {
                return;
            }
            let hdr = match frame::decode_header(self.buf.get(..self.len.min(HEADER_LEN)).unwrap_or(&[])) {
                Some(h) => h,
                None => {
                    self.stats.bad_header = self.stats.bad_header.saturating_add(1);
                    self.drop_front(1);
                    continue;
                }
            };
            let flen = match frame::frame_len(hdr.nx as usize, hdr.ny as usize) {
                Some(l) => l,
                None => {
                    self.drop_front(1);
                    continue;
                }
            };
            if self.len < flen {
                return;
            }
            if !frame::crc_ok(self.buf.get(..flen).unwrap_or(&[])) {
                self.stats.bad_crc = self.stats.bad_crc.saturating_add(1);
                self.drop_front(1);
                continue;
            }
            self.apply(&hdr, flen, now_ms);
            self.drop_front(flen);
        }
    }

    /// A whole frame with a good CRC: check freshness, decode into the inactive grid, swap.
    fn apply(&mut self, hdr: &FrameHeader, flen: usize, now_ms: u32) {
        let newer = match self.last_seq {
            None => true,
            Some(last) => (hdr.seq.wrapping_sub(last) as i32) > 0,
        };
        if !newer || hdr.age_ms > self.max_age_ms {
            self.stats.stale = self.stats.stale.saturating_add(1);
            return;
        }
        let inactive = if self.active == 0 { 1 } else { 0 };
        let frame_bytes = match self.buf.get(..flen) {
            Some(b) => b,
            None => return,
        };
        let g = match self.grids.get_mut(inactive) {
            Some(g) => g,
            None => return,
        };
        let (nx, ny) = (hdr.nx as usize, hdr.ny as usize);
        let ok = g.set_geometry(
            nx,
            ny,
            R::from_q16(hdr.x0_q16),
            R::from_q16(hdr.y0_q16),
            R::from_q16(hdr.spacing_q16),
            R::from_q16(hdr.sigma_q16),
        );
        if !ok {
            self.stats.bad_header = self.stats.bad_header.saturating_add(1);
            return;
        }
        for (k, w) in g.weights.iter_mut().enumerate().take(nx.saturating_mul(ny)) {
            *w = R::from_q16(frame::weight_q16(frame_bytes, k).unwrap_or(0));
        }
        g.seq = hdr.seq;
        self.active = inactive;
        self.have_grid = true;
        self.last_seq = Some(hdr.seq);
        self.applied_at_ms = now_ms;
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
        assert_eq!(r.weights_age_ms(25), Some(20));
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
        assert_eq!(r.pending(), 0);
        r.feed(&frame(&header(2, 2, 2), &w), 101);
        assert_eq!(r.stats.good, 1);
    }

    #[test]
    fn resyncs_on_a_frame_inside_garbage() {
        let w = weights(4, 0);
        let f = frame(&header(2, 2, 1), &w);
        let mut stream = vec![SYNC0, SYNC1, 1, 2, 2, 0, 0, 0, 0xA5, 0xA5];
        stream.extend_from_slice(&f[..10]); // cut-off start of a frame ...
        stream.extend_from_slice(&f); // ... then the whole one
        let mut r = rx();
        r.feed(&stream, 0);
        assert_eq!(r.stats.good, 1);
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
