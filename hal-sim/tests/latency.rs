//! The latency `flinch hil` gives the firmware is the measured one: the constants in
//! `src/latency.rs` equal firmware/README.md's figures for the board ELF (and, for comparison, its
//! QEMU self-test's "Measured figures") and lie within what `cargo xtask test` asserts, and the
//! clock is the board's.

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

/// The number just before `after` in `text` (commas as thousands separators).
fn number_before(text: &str, after: &str) -> u32 {
    let at = text.find(after).unwrap_or_else(|| panic!("firmware/README.md: no {after:?}"));
    let word = text[..at].split_whitespace().last().unwrap_or_else(|| panic!("nothing before {after:?}"));
    word.replace(',', "").parse().unwrap_or_else(|_| panic!("{word:?} before {after:?} is not a number"))
}

#[test]
fn the_board_figures_are_the_readmes_and_within_what_xtask_asserts() {
    let readme = read("firmware/README.md");
    let section = &readme[readme.find("## The board's own worst case").expect("the board's worst-case section")..];
    let section = &section[..section[3..].find("\n## ").map_or(section.len(), |e| e + 3)];
    // The plant's figures are the stage's asserted bounds, and the README says so.
    let worst = read("xtask/src/worst.rs");
    assert_eq!(WORST_EDGE_TO_STOP_INSTRUCTIONS, const_u32(&worst, "BOARD_EDGE_TO_STOP_LIMIT"));
    assert_eq!(TICK_TO_OUTPUT_WORST_INSTRUCTIONS, const_u32(&worst, "BOARD_TICK_TO_OUTPUT_LIMIT"));
    assert_eq!(TICK_TO_OUTPUT_ENTRIES, const_u32(&worst, "BOARD_TICK_TO_OUTPUT_ENTRIES_LIMIT"));
    assert_eq!(WORST_EDGE_TO_STOP_INSTRUCTIONS, number_before(section, "instructions = 20.75 us"), "firmware/README.md: the plant's edge to stop");
    assert_eq!(TICK_TO_OUTPUT_WORST_INSTRUCTIONS, number_before(section, "instructions = 1,518 us"), "firmware/README.md: the plant's tick to output");
    assert_eq!(TICK_TO_OUTPUT_ENTRIES, number_before(section, "exception entries (the bound)"));
    // The board does more than the QEMU self-test: its figures are the larger.
    assert!(WORST_EDGE_TO_STOP_INSTRUCTIONS > QEMU_EDGE_TO_STOP_INSTRUCTIONS && TICK_TO_OUTPUT_WORST_INSTRUCTIONS > QEMU_TICK_TO_OUTPUT_INSTRUCTIONS);
    let board = read("firmware/src/bin/support/board_hw.rs");
    assert_eq!(BOARD_CLOCK_HZ, const_u32(&board, "CORE_HZ"), "the board's clock changed");
}

#[test]
fn the_qemu_self_test_figures_kept_for_comparison_are_the_readmes() {
    let readme = read("firmware/README.md");
    assert_eq!(QEMU_EDGE_TO_STOP_INSTRUCTIONS, readme_figure(&readme, "QEMU edge-to-stop, worst"));
    assert_eq!(TRIP_TICK_INSTRUCTIONS, readme_figure(&readme, "QEMU trip tick"), "update hal-sim/src/latency.rs with the README's measured figure");
    assert_eq!(EDGE_HANDLER_INSTRUCTIONS, readme_figure(&readme, "QEMU edge handler"));
    assert_eq!(EDGE_AND_BOOK_INSTRUCTIONS, readme_figure(&readme, "QEMU edge and bookkeeping"));
    assert_eq!(DRAIN_MASKED_INSTRUCTIONS, readme_figure(&readme, "QEMU log drain, masked section"));
    assert_eq!(QEMU_TICK_TO_OUTPUT_INSTRUCTIONS, readme_figure(&readme, "QEMU tick-to-output, worst"));
    assert_eq!(QEMU_TICK_TO_OUTPUT_INSTRUCTIONS, TRIP_TICK_INSTRUCTIONS + EDGE_HANDLER_INSTRUCTIONS + EDGE_AND_BOOK_INSTRUCTIONS + DRAIN_MASKED_INSTRUCTIONS);
    let xtask = read("xtask/src/qemu.rs");
    assert!(QEMU_EDGE_TO_STOP_INSTRUCTIONS <= const_u32(&xtask, "ICOUNT_WORST_LIMIT"));
    assert!(QEMU_TICK_TO_OUTPUT_INSTRUCTIONS <= const_u32(&xtask, "ICOUNT_TICK_OUTPUT_LIMIT"));
}

#[test]
fn the_conversion_is_the_documented_one() {
    // (12 + 4 * 80) / 16 MHz and (24 * 12 + 4 * 6000) / 16 MHz: the README's 20.75 us and 1,518 us.
    assert!((edge_to_stop_s() - 20.75e-6).abs() < 1e-12, "{}", edge_to_stop_s());
    assert!((tick_to_output_s() - 1518e-6).abs() < 1e-12, "{}", tick_to_output_s());
    assert!(tick_to_output_s() > worst_seconds(TRIP_TICK_INSTRUCTIONS), "more than the trip tick alone");
    assert!(edge_to_stop_s() > 0.0, "never zero");
}
