//! How long the board takes from a switch edge to its stop write (and to its escalation write), in
//! seconds, for the plant: `flinch hil` delays what the robot and its drives see by these, so the
//! firmware's latency in the loop is the board's measured worst case, not zero.
//!
//! # Where the numbers come from (kept in sync by `tests/latency.rs`)
//!
//! The board ELF's own worst case (issue 25 item 4), firmware/README.md "The board's own worst
//! case, measured on the board ELF" (`cargo xtask board-qemu`, stage "board worst case" of `cargo
//! xtask test`, asserted there within `BOARD_EDGE_TO_STOP_LIMIT` and `BOARD_TICK_TO_OUTPUT_LIMIT`,
//! xtask/src/worst.rs): the board's code in QEMU with two stop channels, the EDM, the clock check,
//! USART1 traffic, the periodic self-tests and the avoidance step's masked sections.
//!
//! The plant takes the stage's asserted BOUNDS, not one run's figures (the measured worst case
//! varies from run to run with how many USART bytes fall into the window: 56-58 and 3,936-4,968
//! instructions have been seen), so `flinch hil` never understates the board:
//!
//! * [`WORST_EDGE_TO_STOP_INSTRUCTIONS`] = 80 (largest measured 57): from the edge's pend to the
//!   second stop channel's write, on the board's own handler.
//! * [`TICK_TO_OUTPUT_WORST_INSTRUCTIONS`] = 6,000 (largest measured 4,649) with
//!   [`TICK_TO_OUTPUT_ENTRIES`] = 24 (largest measured 18) exception
//!   entries: a tick due just after a same-priority handler began waits for it and for the longest
//!   masked section, is preempted by both channels' edges and every USART byte meanwhile, then runs
//!   the longest tick to its end (which bounds its output write). It bounds an output written on a
//!   tick (a filtered trip) and the escalation (category 0).
//!
//! These replaced the QEMU self-test's figures (26 and 1,512 instructions: the `qemu` binary on
//! mps2-an386, one channel, no EDM, no clock check, no USART), which left the board's extra work
//! out (issue 25: "the 1,463-instruction tick-to-output figure is not the board's"). The self-test's
//! figures below are kept, checked against the README, for comparison.
//!
//! # Conversion: instructions are a proxy for cycles
//!
//! QEMU counts instructions (`-icount`), not cycles: it charges no cycles per instruction, no wait
//! states and no exception entry, and DWT's cycle counter reads zero there. The count is turned into
//! a bound on time: a Cortex-M4 instruction takes at most 1 + P cycles for a taken branch with
//! P <= 3 pipeline refill cycles (ARM Cortex-M4 TRM r0p1, 3.3.1), loads 2, most 1; at 16 MHz the
//! F407's flash needs no wait state (RM0090 3.5.1, table 10: 0 WS up to 30 MHz at 2.7-3.6 V). So
//! [`CYCLES_PER_INSTRUCTION_MAX`] = 4 bounds every instruction of the path, and each exception
//! entry adds [`EXCEPTION_ENTRY_CYCLES`] = 12 (TRM 5.5.1, zero-wait-state memory), at
//! [`BOARD_CLOCK_HZ`] = 16 MHz (the HSI, firmware/src/bin/support/board_hw.rs `CORE_HZ`):
//!
//! `t = (12 e + 4 n) / 16 MHz`: edge to stop (one entry) 80 instructions -> 332 cycles -> 20.75 us;
//! tick to output (24 entries) 6,000 instructions -> 24,288 cycles -> 1,518 us.

/// Where these figures come from, for people (`flinch hil` prints it beside them).
pub const SOURCE: &str = "the board ELF's worst-case bounds asserted in QEMU, instructions (-icount, a proxy for cycles) at <= 4 cycles each + 12 per exception entry, 16 MHz: hal-sim/src/latency.rs";

/// The board ELF's edge-to-stop bound, instructions (`xtask/src/worst.rs`
/// `BOARD_EDGE_TO_STOP_LIMIT`, asserted by the stage "board worst case").
pub const WORST_EDGE_TO_STOP_INSTRUCTIONS: u32 = 80;
/// The board ELF's tick-to-output bound, instructions (`BOARD_TICK_TO_OUTPUT_LIMIT`).
pub const TICK_TO_OUTPUT_WORST_INSTRUCTIONS: u32 = 6_000;
/// Exception entries on the tick-to-output path, bound (`BOARD_TICK_TO_OUTPUT_ENTRIES_LIMIT`).
pub const TICK_TO_OUTPUT_ENTRIES: u32 = 24;

/// The QEMU self-test's worst edge-to-stop (firmware/README.md, "QEMU edge-to-stop, worst": 25
/// since the edge writes both stop channels), for comparison; not used by the plant.
pub const QEMU_EDGE_TO_STOP_INSTRUCTIONS: u32 = 25;
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
/// The QEMU self-test's worst tick to output write: the four above (firmware/README.md, "QEMU
/// tick-to-output, worst"), for comparison; not used by the plant.
pub const QEMU_TICK_TO_OUTPUT_INSTRUCTIONS: u32 = 1_512;
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

/// From the switch edge to the second stop channel's write, s (20.75 us).
pub fn edge_to_stop_s() -> f64 {
    worst_seconds(WORST_EDGE_TO_STOP_INSTRUCTIONS)
}

/// From a tick (or the edge's bookkeeping) being due to its output write, s (1,518 us): a stop
/// confirmed by a filter on a tick, and the escalation (category-0) output; the same- and
/// higher-priority work that can run first included.
pub fn tick_to_output_s() -> f64 {
    f64::from(TICK_TO_OUTPUT_ENTRIES * EXCEPTION_ENTRY_CYCLES + CYCLES_PER_INSTRUCTION_MAX * TICK_TO_OUTPUT_WORST_INSTRUCTIONS)
        / f64::from(BOARD_CLOCK_HZ)
}
