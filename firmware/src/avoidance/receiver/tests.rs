//! The receiver's unit tests: frames applied bit-exactly, refused and counted, sessions, ages,
//! backlogs and budgets (the proptests are in `proptests.rs`).

use super::*;
use crate::avoidance::frame::{self, encode_frame, frame_len, FrameHeader, MAX_FRAME, SYNC0, SYNC1};

extern crate std;
use std::vec;
use std::vec::Vec;

pub(super) fn header(nx: u8, ny: u8, seq: u32) -> FrameHeader {
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
        ..FrameHeader::default()
    }
}

pub(super) fn frame(h: &FrameHeader, w: &[i32]) -> Vec<u8> {
    let mut out = vec![0u8; MAX_FRAME];
    let n = encode_frame(h, w, &mut out).expect("encodes");
    out.truncate(n);
    out
}

pub(super) fn weights(n: usize, salt: i32) -> Vec<i32> {
    (0..n as i32).map(|k| k.wrapping_mul(2654435).wrapping_add(salt) % 40000).collect()
}

pub(super) fn rx() -> Receiver<Q16> {
    Receiver::new(100, 20)
}
pub(super) type Q16 = fixed::types::I16F16;

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

