//! Whether the detection firmware holds the robot stopped, published for the avoidance step
//! (`board_avoid.rs`), whose velocity frames then say `stopped: latched` (issue 25 item 7).
//!
//! A leaf: it imports only `core` and the library, so the tick and the bookkeeping (`board.rs`,
//! which write it) and the step (`board_avoid.rs`, which reads it) share it without importing each
//! other. One `AtomicBool`, written at the tick's priority (0x80: the tick and the bookkeeping, which
//! share that priority, so the last write is the firmware's state after its last handler) and read
//! by the step (0xC0, below them): lock-free, nothing masked, and a step always sees the state after
//! every tick and bookkeeping that ran before it began. An edge's stop write (0x10) is followed by
//! its bookkeeping, which publishes the trip; a step that read the flag just before can send one
//! frame without it (at most one 10 ms period late; the stop itself is the edge's, not the frame's).
//!
//! Held: every state but armed (the collision latch after a trip, a latched fault, the start latch
//! after a reset, and the self-test that a reset press starts, during which the stop outputs are
//! still low). Starts held: nothing is armed before the firmware is built.

use core::sync::atomic::{AtomicBool, Ordering::Relaxed};
use flinch_firmware::State;

static HELD: AtomicBool = AtomicBool::new(true);

/// From the tick and the bookkeeping, after every run of the firmware.
#[inline(always)]
pub(crate) fn publish(s: State) {
    HELD.store(!matches!(s, State::Armed), Relaxed);
}

/// The robot is held stopped by the detection firmware (any state but armed).
#[inline(always)]
pub(crate) fn held() -> bool {
    HELD.load(Relaxed)
}
