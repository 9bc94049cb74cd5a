//! The latency `flinch hil` gives the firmware is the measured one: the constants in
//! `src/latency.rs` equal firmware/README.md's "Measured figures" and lie within what
//! `cargo xtask test` asserts, and the clock is the board's.

use flinch_hal_sim::latency::*;
use std::path::Path;

fn read(rel: &str) -> String {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(rel);
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The first number in the second column of the README table row starting with `row`.
fn readme_figure(readme: &str, row: &str) -> u32 {
    let line = readme.lines().find(|l| l.starts_with(&format!("| {row}"))).unwrap_or_else(|| panic!("firmware/README.md: no row {row:?}"));
    let cell = line.split('|').nth(2).unwrap_or_else(|| panic!("row {row:?} has no value cell"));
    cell.split_whitespace().find_map(|w| w.parse().ok()).unwrap_or_else(|| panic!("row {row:?}: no number in {cell:?}"))
}

fn const_u32(src: &str, name: &str) -> u32 {
    let line = src.lines().find(|l| l.contains(&format!("const {name}: u32 ="))).unwrap_or_else(|| panic!("no const {name}"));
    line.split('=').nth(1).and_then(|v| v.trim().trim_end_matches(';').replace('_', "").parse().ok()).unwrap_or_else(|| panic!("{line}"))
}

#[test]
fn worst_edge_to_stop_is_the_readme_figure_and_within_what_xtask_asserts() {
    let readme = read("firmware/README.md");
    let edge = readme_figure(&readme, "QEMU edge-to-stop, worst");
    assert!(WORST_EDGE_TO_STOP_INSTRUCTIONS >= edge && WORST_EDGE_TO_STOP_INSTRUCTIONS <= edge + 1, "hal-sim/src/latency.rs: {WORST_EDGE_TO_STOP_INSTRUCTIONS}, the README's measured figure {edge} (a bound at most one above it)");
    assert_eq!(TRIP_TICK_INSTRUCTIONS, readme_figure(&readme, "QEMU trip tick"), "update hal-sim/src/latency.rs with the README's measured figure");
    assert_eq!(EDGE_HANDLER_INSTRUCTIONS, readme_figure(&readme, "QEMU edge handler"));
    assert_eq!(EDGE_AND_BOOK_INSTRUCTIONS, readme_figure(&readme, "QEMU edge and bookkeeping"));
    assert_eq!(DRAIN_MASKED_INSTRUCTIONS, readme_figure(&readme, "QEMU log drain, masked section"));
    assert_eq!(TICK_TO_OUTPUT_WORST_INSTRUCTIONS, readme_figure(&readme, "QEMU tick-to-output, worst"));
    assert_eq!(
        TICK_TO_OUTPUT_WORST_INSTRUCTIONS,
        TRIP_TICK_INSTRUCTIONS + EDGE_HANDLER_INSTRUCTIONS + EDGE_AND_BOOK_INSTRUCTIONS + DRAIN_MASKED_INSTRUCTIONS,
        "the tick-to-output bound includes the same- and higher-priority work and the drain's masked section"
    );
    let xtask = read("xtask/src/qemu.rs");
    let limit = const_u32(&xtask, "ICOUNT_WORST_LIMIT");
    assert!(WORST_EDGE_TO_STOP_INSTRUCTIONS <= limit, "{WORST_EDGE_TO_STOP_INSTRUCTIONS} > xtask's {limit}");
    let tick_limit = const_u32(&xtask, "ICOUNT_TICK_OUTPUT_LIMIT");
    assert!(TICK_TO_OUTPUT_WORST_INSTRUCTIONS <= tick_limit, "{TICK_TO_OUTPUT_WORST_INSTRUCTIONS} > xtask's {tick_limit}");
    let board = read("firmware/src/bin/support/board_hw.rs");
    assert_eq!(BOARD_CLOCK_HZ, const_u32(&board, "CORE_HZ"), "the board's clock changed");
}

#[test]
fn the_conversion_is_the_documented_one() {
    // (12 + 4 * 26) / 16 MHz and (4 * 12 + 4 * 1512) / 16 MHz.
    assert!((edge_to_stop_s() - 7.25e-6).abs() < 1e-12, "{}", edge_to_stop_s());
    assert!((tick_to_output_s() - 381e-6).abs() < 1e-12, "{}", tick_to_output_s());
    assert!(tick_to_output_s() > worst_seconds(TRIP_TICK_INSTRUCTIONS), "more than the trip tick alone");
    assert!(edge_to_stop_s() > 0.0, "never zero");
}
