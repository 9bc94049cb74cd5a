//! The receiver's proptests: random bytes, round trips in any chunks, corrupted and truncated
//! frames, and mixed streams parsed with random budgets.

use super::tests::{frame, header, rx, weights};
use super::RING;
use proptest::prelude::*;

extern crate std;
use std::vec::Vec;

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
