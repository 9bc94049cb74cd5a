//! How long the board takes from a switch edge to its stop write (and to its escalation write), in
//! seconds, for the plant: `flinch hil` delays what the robot and its drives see by these, so the
//! firmware's latency in the loop is the measured worst case, not zero.
//!
//! # Where the numbers come from (kept in sync by `tests/latency.rs`)
//!
//! * [`WORST_EDGE_TO_STOP_INSTRUCTIONS`]: firmware/README.md, "Measured figures", row "QEMU
//!   edge-to-stop, worst" (`cargo xtask qemu`, `worst_pend_to_stop`: the edge pended in the same
//!   instant as the trip tick, pend to the stop write). `cargo xtask test` asserts it is at most
//!   `ICOUNT_WORST_LIMIT` (xtask/src/main.rs); the test here asserts the constant equals the README's
//!   figure and is within that limit.
//! * [`TRIP_TICK_INSTRUCTIONS`]: the same table, row "QEMU trip tick, pend to its end". The edge's
//!   bookkeeping (timestamp, stroke budget, escalation write, latch, log) and a tick that confirms a
//!   filtered trip run at the tick's priority; a whole trip tick bounds how long either takes to
//!   reach its output write.
//! * [`BOARD_CLOCK_HZ`]: the board runs on the 16 MHz HSI (firmware/src/bin/board.rs, `CORE_HZ` without the `qemu-io` feature).
//!
//! # Conversion
//!
//! QEMU counts instructions, not cycles. A Cortex-M4 instruction takes at most 1 + P cycles for a
//! taken branch with P <= 3 pipeline refill cycles (ARM Cortex-M4 TRM r0p1, 3.3.1), loads 2, most 1;
//! at 16 MHz the F407's flash needs no wait state (RM0090 3.5.1, table 10: 0 WS up to 30 MHz at
//! 2.7-3.6 V). So [`CYCLES_PER_INSTRUCTION_MAX`] = 4 bounds every instruction of the path, and
//! exception entry adds [`EXCEPTION_ENTRY_CYCLES`] = 12 (TRM 5.5.1, zero-wait-state memory):
//!
//! `t = (12 + 4 n) / 16 MHz`: edge to stop 26 instructions -> 116 cycles -> 7.25 us; trip tick 698
//! instructions -> 2,804 cycles -> 175.25 us.

/// Worst edge-to-stop, QEMU instructions (firmware/README.md, "QEMU edge-to-stop, worst").
pub const WORST_EDGE_TO_STOP_INSTRUCTIONS: u32 = 26;
/// A trip tick from pend to its end, QEMU instructions (firmware/README.md, "QEMU trip tick").
pub const TRIP_TICK_INSTRUCTIONS: u32 = 698;
/// The board's core clock, Hz (16 MHz HSI, firmware/src/bin/board.rs).
pub const BOARD_CLOCK_HZ: u32 = 16_000_000;
/// Cycles one instruction of the path takes at most (Cortex-M4: taken branch 1 + P, P <= 3).
pub const CYCLES_PER_INSTRUCTION_MAX: u32 = 4;
/// Exception entry, cycles (Cortex-M4, zero wait states).
pub const EXCEPTION_ENTRY_CYCLES: u32 = 12;

/// Seconds `instructions` take at most on the board, entry included.
pub fn worst_seconds(instructions: u32) -> f64 {
    f64::from(EXCEPTION_ENTRY_CYCLES + CYCLES_PER_INSTRUCTION_MAX * instructions) / f64::from(BOARD_CLOCK_HZ)
}

/// From the switch edge to the stop output's write, s (7.25 us).
pub fn edge_to_stop_s() -> f64 {
    worst_seconds(WORST_EDGE_TO_STOP_INSTRUCTIONS)
}

/// From a tick (or the edge's bookkeeping) being due to its output write, s (175.25 us): a stop
/// confirmed by a filter on a tick, and the escalation (category-0) output.
pub fn tick_to_output_s() -> f64 {
    worst_seconds(TRIP_TICK_INSTRUCTIONS)
}
