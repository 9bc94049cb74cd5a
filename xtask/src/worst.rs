//! The stage "board worst case": the board ELF's own tick-to-output and edge-to-stop, from the
//! longest run of each piece of work measured in the `qemu-io` edge run (`board_bench.rs`,
//! `report_worst`), which carries USART1 traffic, both channels, the EDM, the clock check, the
//! periodic self-tests and the avoidance step. Instruction counts under `-icount` are a proxy for
//! time (QEMU charges no cycles, no wait states, no exception entry, and its DWT cycle counter reads
//! 0); they are converted with the bounds of `hal-sim/src/latency.rs` (4 cycles an instruction, 12
//! an exception entry, the board's 16 MHz HSI). Exception entries counted on the tick-to-output
//! path: the tick, the same-priority handler it waits for, both edges, and one per USART byte in
//! the window (a masked section is thread mode or inside one of these: no entry of its own).

/// SysTick counts an instruction: the 168 MHz core clock under `-icount shift=3` (8 ns each).
const COUNTS_PER_INSTRUCTION_X1000: u64 = 1_344;
/// Asserted bounds, instructions. The largest measured (firmware/README.md, "The board's own worst
/// case", `cargo xtask board-qemu`, three runs after the USART entry calibration): edge to stop 57, tick to
/// output 4,649; the bounds leave 29 % and 22 % of themselves as margin for the run-to-run spread
/// (which USART path and how many bytes fall into the window) and small code changes. Exceeding
/// either fails the stage; the stage prints the margin left.
pub const BOARD_EDGE_TO_STOP_LIMIT: u32 = 80;
pub const BOARD_TICK_TO_OUTPUT_LIMIT: u32 = 6_000;
/// Asserted bound on the exception entries of the tick-to-output path (largest measured 18: the
/// tick, the bookkeeping, two edges and 14 USART bytes). The plant (`hal-sim/src/latency.rs`) uses
/// these three bounds, not one run's figures, so `flinch hil` never understates the board.
pub const BOARD_TICK_TO_OUTPUT_ENTRIES_LIMIT: u32 = 24;
/// One byte at 115,200 baud 8N1 (10 bits), seconds.
const BYTE_S: f64 = 10.0 / 115_200.0;

/// The board's worst case, instructions and seconds.
#[derive(Debug, Clone, PartialEq)]
pub struct BoardWorst {
    pub edge_to_stop: u32,
    pub tick_to_output: u32,
    /// Exception entries on the tick-to-output path.
    pub entries: u32,
    /// USART bytes that can arrive within the window.
    pub usart_bytes: u32,
    pub parts: String,
}

impl BoardWorst {
    pub fn edge_to_stop_s(&self) -> f64 {
        f64::from(12 + 4 * self.edge_to_stop) / 16e6
    }
    pub fn tick_to_output_s(&self) -> f64 {
        f64::from(12 * self.entries + 4 * self.tick_to_output) / 16e6
    }
}

fn instructions(counts: u32) -> u32 {
    ((u64::from(counts) * 1_000).div_ceil(COUNTS_PER_INSTRUCTION_X1000)) as u32
}

/// Parse the bench's `bench: worst counts ...` line and combine: a tick due just after a
/// same-priority handler began (the bookkeeping or the LSI capture) waits for it, waits for the
/// longest masked section (thread mode's drain or self-test, or the step's USART-masked send), is
/// preempted by both channels' edges and by every USART byte arriving meanwhile, then runs the
/// longest tick to its end (which bounds its output write). Conservative: a tick cannot wait for a
/// masked section and a same-priority handler begun before it both, but the sum counts both.
pub fn board_worst(out: &str) -> Result<BoardWorst, String> {
    let line = out.lines().find(|l| l.starts_with("bench: worst counts")).ok_or("no 'bench: worst counts' line from the board bench")?;
    let field = |k: &str| -> Result<u32, String> {
        line.split_whitespace()
            .find_map(|w| w.strip_prefix(&format!("{k}=")))
            .and_then(|v| v.parse().ok())
            .ok_or_else(|| format!("no {k}= in {line:?}"))
    };
    // The USART entry that took one byte: on the part a byte comes every 87 us, one an entry.
    // Each byte's entry also costs the instructions outside its measured window (`usart_entry`, the
    // bench's calibration), which the sections it preempted no longer carry.
    let usart_entry = instructions(field("usart_entry")?);
    let (tick, book, tim5, usart) = (instructions(field("tick")?), instructions(field("book")?), instructions(field("tim5")?), instructions(field("usart_1")?));
    let (edge_end, edge_stop) = (instructions(field("edge_end")?), instructions(field("edge_stop")?));
    let masked = instructions(field("mask_step")?.max(field("mask_drain")?).max(field("mask_diag")?));
    let irqs = field("usart_irqs")?;
    if tick == 0 || book == 0 || tim5 == 0 || edge_end == 0 || edge_stop == 0 || masked == 0 || usart == 0 || irqs == 0 || usart_entry == 0 {
        return Err(format!("a part was not measured (no USART traffic, no edge, no masked section?): {line}"));
    }
    let usart = usart + usart_entry;
    let same = book.max(tim5);
    let mut k = 1u32;
    let mut w = BoardWorst { edge_to_stop: edge_stop, tick_to_output: 0, entries: 0, usart_bytes: 0, parts: String::new() };
    for _ in 0..10 {
        w.tick_to_output = tick + same + 2 * edge_end + masked + k * usart;
        w.entries = 4 + k;
        let bytes = (w.tick_to_output_s() / BYTE_S).floor() as u32 + 1;
        if bytes <= k {
            break;
        }
        k = bytes;
    }
    w.usart_bytes = k;
    w.parts = format!(
        "tick {tick} + same-priority {same} (bookkeeping {book}, LSI capture {tim5}) + 2 edges x {edge_end} + masked {masked} + {k} USART bytes x {usart} (of which {usart_entry} outside the handler's measured window)"
    );
    Ok(w)
}

/// The stage: the figures within their limits.
pub fn check_board_worst(out: &str) -> Result<String, String> {
    let w = board_worst(out)?;
    if w.edge_to_stop > BOARD_EDGE_TO_STOP_LIMIT {
        return Err(format!("board edge-to-stop {} > {BOARD_EDGE_TO_STOP_LIMIT} instructions", w.edge_to_stop));
    }
    if w.tick_to_output > BOARD_TICK_TO_OUTPUT_LIMIT {
        return Err(format!("board tick-to-output {} > {BOARD_TICK_TO_OUTPUT_LIMIT} instructions ({})", w.tick_to_output, w.parts));
    }
    if w.entries > BOARD_TICK_TO_OUTPUT_ENTRIES_LIMIT {
        return Err(format!("board tick-to-output with {} exception entries > {BOARD_TICK_TO_OUTPUT_ENTRIES_LIMIT} ({})", w.entries, w.parts));
    }
    let margin = |m: u32, limit: u32| 100.0 * f64::from(limit - m) / f64::from(limit);
    let bound = BoardWorst { edge_to_stop: BOARD_EDGE_TO_STOP_LIMIT, tick_to_output: BOARD_TICK_TO_OUTPUT_LIMIT, ..w.clone() };
    Ok(format!(
        "board ELF (qemu-io, -icount proxy: instructions, not cycles; at 16 MHz, <= 4 cycles an instruction + 12 an exception entry): edge-to-stop {} instructions (<= {BOARD_EDGE_TO_STOP_LIMIT}, margin {:.0} %) = {:.2} us (bound {:.2} us), 1 exception entry; tick-to-output {} instructions (<= {BOARD_TICK_TO_OUTPUT_LIMIT}, margin {:.0} %) = {:.2} us (the bound at as many entries {:.2} us) with {} exception entries ({})",
        w.edge_to_stop,
        margin(w.edge_to_stop, BOARD_EDGE_TO_STOP_LIMIT),
        w.edge_to_stop_s() * 1e6,
        bound.edge_to_stop_s() * 1e6,
        w.tick_to_output,
        margin(w.tick_to_output, BOARD_TICK_TO_OUTPUT_LIMIT),
        w.tick_to_output_s() * 1e6,
        bound.tick_to_output_s() * 1e6,
        w.entries,
        w.parts
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_parts_add_up_and_a_missing_one_fails() {
        let line = |usart: u32| {
            format!("bench: worst counts tick=1344 book=672 tim5=134 usart=9999 usart_1={usart} edge_end=134 edge_stop=67 mask_step=2688 mask_drain=134 mask_diag=269 usart_irqs=50 usart_entry=26 (x)\n")
        };
        let w = board_worst(&line(107)).unwrap();
        // 1000 + 500 + 2 x 100 + 2000 + k x (80 + 20) with k bytes in the window.
        assert_eq!(w.edge_to_stop, 50);
        assert_eq!(w.tick_to_output, 3_700 + w.usart_bytes * 100);
        assert!(w.usart_bytes >= 1 && (w.tick_to_output_s() / BYTE_S) < f64::from(w.usart_bytes) + 1.0);
        assert!(board_worst(&line(0)).is_err(), "no USART traffic measured");
        assert!(board_worst("bench: PASS\n").is_err());
    }
}
