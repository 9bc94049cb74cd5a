//! How long the board takes from a switch edge to its stop write (and to its escalation write), in
//! seconds, for the plant: `flinch hil` delays what the robot and its drives see by these, so the
//! firmware's latency in the loop is the measured worst case, not zero.
//!
//! # Where the numbers come from (kept in sync by `tests/latency.rs`)
//!
//! * [`WORST_EDGE_TO_STOP_INSTRUCTIONS`]: firmware/README.md, "Measured figures", row "QEMU
//!   edge-to-stop, worst" (`cargo xtask qemu`, `worst_pend_to_stop`: the edge pended in the same
//!   instant as the trip tick, pend to the stop write). `cargo xtask test` asserts it is at most
//!   `ICOUNT_WORST_LIMIT` (xtask/src/qemu.rs); the test here asserts the constant equals the README's
//!   figure and is within that limit.
//! * [`TICK_TO_OUTPUT_WORST_INSTRUCTIONS`]: the same table, row "QEMU tick-to-output, worst": a
//!   tick that confirms a filtered trip (or the edge's bookkeeping, which writes the escalation)
//!   becomes due just after a trip's bookkeeping began; it waits for that bookkeeping (same
//!   priority; with its edge: [`EDGE_AND_BOOK_INSTRUCTIONS`], pend to the end of the bookkeeping),
//!   is preempted by the other channel's edge ([`EDGE_HANDLER_INSTRUCTIONS`], pend to its end), and
//!   then runs the whole trip tick ([`TRIP_TICK_INSTRUCTIONS`], pend to its end, which bounds its
//!   output write). The TIM5 capture (the LSI count, same priority on the board) is 21
//!   instructions at most (`llvm-objdump -d` of the board ELF, `tim5_entry`), shorter than the
//!   bookkeeping, and SysTick, the lowest exception number, is taken first among pending work of
//!   its priority, so one same-priority handler at most runs before it. `cargo xtask test` asserts
//!   the sum and `ICOUNT_TICK_OUTPUT_LIMIT`. Before issue 10 item 5 the figure was the trip tick
//!   alone (698), which left out the same- and higher-priority work. Added conservatively: the
//!   board's log drain's BASEPRI-masked section ([`DRAIN_MASKED_INSTRUCTIONS`], thread mode, no
//!   exception entry), which a due tick also waits behind; it was left out before, while it cloned
//!   the whole 16-event log (a snapshot of all 16 events measured 1,974 instructions); it now takes
//!   one new event per run (`event_log::DRAIN_BATCH`).
//! * [`BOARD_CLOCK_HZ`]: the board runs on the 16 MHz HSI (firmware/src/bin/support/board_hw.rs, `CORE_HZ` without the `qemu-clock` feature).
//!
//! # Conversion
//!
//! QEMU counts instructions, not cycles. A Cortex-M4 instruction takes at most 1 + P cycles for a
//! taken branch with P <= 3 pipeline refill cycles (ARM Cortex-M4 TRM r0p1, 3.3.1), loads 2, most 1;
//! at 16 MHz the F407's flash needs no wait state (RM0090 3.5.1, table 10: 0 WS up to 30 MHz at
//! 2.7-3.6 V). So [`CYCLES_PER_INSTRUCTION_MAX`] = 4 bounds every instruction of the path, and
//! exception entry adds [`EXCEPTION_ENTRY_CYCLES`] = 12 (TRM 5.5.1, zero-wait-state memory):
//!
//! `t = (12 + 4 n) / 16 MHz`: edge to stop (both channels written) at most 26 instructions -> 116
//! cycles -> 7.25 us. Tick to output: four exception entries (the bookkeeping's edge, the bookkeeping, the
//! other edge, the tick) and 1,512 instructions -> 48 + 6,048 cycles -> 381 us.

/// Worst edge-to-stop, QEMU instructions (firmware/README.md, "QEMU edge-to-stop, worst": 25 since
/// the edge writes both stop channels and no longer reads the output register; 26 is kept, an
/// upper bound, until the board ELF's own worst case replaces these figures).
pub const WORST_EDGE_TO_STOP_INSTRUCTIONS: u32 = 26;
/// A trip tick from pend to its end, QEMU instructions (firmware/README.md, "QEMU trip tick").
pub const TRIP_TICK_INSTRUCTIONS: u32 = 747;
/// The edge handler, pend to its end (firmware/README.md, "QEMU edge handler").
pub const EDGE_HANDLER_INSTRUCTIONS: u32 = 32;
/// A trip's edge and its bookkeeping, pend to the end of the bookkeeping (firmware/README.md,
/// "QEMU edge and bookkeeping").
pub const EDGE_AND_BOOK_INSTRUCTIONS: u32 = 647;
/// The board's log drain, its BASEPRI-masked section (firmware/README.md, "QEMU log drain, masked
/// section").
pub const DRAIN_MASKED_INSTRUCTIONS: u32 = 86;
/// Worst tick to output write: the four above (firmware/README.md, "QEMU tick-to-output, worst").
pub const TICK_TO_OUTPUT_WORST_INSTRUCTIONS: u32 = 1_512;
/// Exception entries on the worst tick-to-output path.
pub const TICK_TO_OUTPUT_ENTRIES: u32 = 4;
/// The board's core clock, Hz (16 MHz HSI, firmware/src/bin/support/board_hw.rs).
pub const BOARD_CLOCK_HZ: u32 = 16_000_000;
/// Cycles one instruction of the path takes at most (Cortex-M4: taken branch 1 + P, P <= 3).
pub const CYCLES_PER_INSTRUCTION_MAX: u32 = 4;
/// Exception entry, cycles (Cortex-M4, zero wait states).
pub const EXCEPTION_ENTRY_CYCLES: u32 = 12;

/// Seconds `instructions` take at most on the board, entry included.
pub fn worst_seconds(instructions: u32) -> f64 {
    f64::from(EXCEPTION_ENTRY_CYCLES + CYCLES_PER_INSTRUCTION_MAX * instructions) / f64::from(BOARD_CLOCK_HZ)
}

/// From the switch edge to the second stop channel's write, s (7.25 us).
pub fn edge_to_stop_s() -> f64 {
    worst_seconds(WORST_EDGE_TO_STOP_INSTRUCTIONS)
}

/// From a tick (or the edge's bookkeeping) being due to its output write, s (381 us): a stop
/// confirmed by a filter on a tick, and the escalation (category-0) output; the same- and
/// higher-priority work that can run first included.
pub fn tick_to_output_s() -> f64 {
    f64::from(TICK_TO_OUTPUT_ENTRIES * EXCEPTION_ENTRY_CYCLES + CYCLES_PER_INSTRUCTION_MAX * TICK_TO_OUTPUT_WORST_INSTRUCTIONS)
        / f64::from(BOARD_CLOCK_HZ)
}
