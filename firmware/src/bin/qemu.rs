//! QEMU flavour: the firmware library on an emulated Cortex-M4 (`qemu-system-arm -machine
//! mps2-an386`), run as a self-test over semihosting, plus the instruction count of the
//! detect-to-stop path. `cargo xtask qemu` builds and runs it; the expected output is
//! `firmware/qemu/expected.txt` (the `icount:` line is checked by value instead).
//!
//! QEMU's MPS2 models have no GPIO worth driving, so the pins are bytes in RAM (`AtomicBool`s); a
//! register write on the real part is one `str` as well, so the path length carries over.
//!
//! # The instruction counts
//!
//! QEMU has no cycle model, and DWT's cycle counter reads 0. With `-icount shift=6` every instruction
//! takes 2^6 = 64 ns of virtual time, and SysTick (clocked at the AN386's 25 MHz, 40 ns per count)
//! moves 1.6 counts per instruction, so `counts * 40 / 64` is an instruction count: a proxy for time.
//! We read SysTick, pend the edge interrupt by software, and the edge handler reads SysTick again
//! right after its stop write, so the count runs from the pend to the stop write. The edge has the
//! highest priority and the tick and the bookkeeping a lower one, as on the board (`measure`):
//!
//! * `best_pend_to_stop`: the edge alone on an idle core (asserted <= 40 here and in xtask).
//! * `worst_pend_to_stop`: the edge pended in the same instant as the trip tick (one `NVIC_ISPR`
//!   store), or pended by the trip tick itself; the larger over five rounds (asserted <= 60).
//! * `trip_tick`: the trip tick alone, pend to its end: what the edge waited for at equal priority.
//! * `entry_overhead`: the same measurement into a calibration handler written in assembly whose
//!   SysTick read is its 3rd instruction (`CAL_PREFIX`): the pend and exception-entry part.
//! * `edge_to_stop = best - entry_overhead + CAL_PREFIX - 3`: the edge handler's instructions from its
//!   first one to the stop write inclusive, within +-2 (SysTick rounding).
//!
//! These are instructions, not cycles: on the real M4 exception entry alone takes 12 cycles, loads
//! from flash add wait states, and nothing here models that.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!(
        "flinch QEMU self-test: this binary runs in qemu-system-arm (mps2-an386). Run it with\n  \
         cargo xtask qemu"
    );
}

#[cfg(target_os = "none")]
#[path = "support/isr_cell.rs"]
mod isr_cell;

#[cfg(target_os = "none")]
#[path = "support/qemu_scenarios.rs"]
mod scenarios;

#[cfg(target_os = "none")]
#[path = "support/qemu_measure.rs"]
mod measure;

#[cfg(target_os = "none")]
mod qemu {
    use crate::measure::{
        book_handler, edge_handler, flinch_cal_handler, measure, tick_handler, CAL_PREFIX, IRQ_BOOK, IRQ_CAL, IRQ_EDGE,
        IRQ_TICK, STOP_LEVEL,
    };
    use crate::scenarios::{
        analog_fixed_point, auto_reset_across_the_wrap, chatter, clock_stall, cut_wire, event_log_round_trip,
        latch_and_log_survive_a_reset, missed_deadline, reset_latch, stroke_budget, stuck_input_at_start_up,
        trip_latch_reset, Scenario,
    };
    use core::sync::atomic::Ordering::Relaxed;
    use cortex_m::peripheral::syst::SystClkSource;
    use cortex_m_rt::{entry, exception, ExceptionFrame};
    use cortex_m_semihosting::{debug, hprintln};
    use defmt_rtt as _;

    /// Edge-to-stop limits checked here and again by `cargo xtask test` (`check_icount`).
    const BEST_LIMIT: u32 = 40;
    const WORST_LIMIT: u32 = 60;

    /// Stack painting: `PAINT_BYTES` below main's frame are filled with `PAINT` before anything
    /// runs; after every scenario and the measurement (interrupts included) the lowest overwritten
    /// word gives the deepest stack use below main's frame.
    const PAINT: u32 = 0xA5A5_5A5A;
    const PAINT_BYTES: u32 = 16 * 1024;
    const PAINT_GAP: u32 = 256; // left unpainted right below the stack pointer at the start of main

    fn paint_stack() -> (u32, u32) {
        let sp = cortex_m::register::msp::read();
        let hi = sp - PAINT_GAP;
        let lo = hi - PAINT_BYTES;
        let mut a = lo;
        while a < hi {
            // SAFETY: RAM below the live stack (AN386 has 4 MiB of it, the statics sit at its
            // bottom), not in use yet: no interrupt is enabled and nothing has been called.
            unsafe { core::ptr::write_volatile(a as *mut u32, PAINT) };
            a += 4;
        }
        (sp, lo)
    }

    fn stack_used(sp: u32, lo: u32) -> u32 {
        let mut a = lo;
        // SAFETY: the region painted by `paint_stack`.
        while a < sp - PAINT_GAP && unsafe { core::ptr::read_volatile(a as *const u32) } == PAINT {
            a += 4;
        }
        sp - a
    }

    #[entry]
    fn main() -> ! {
        let (sp0, paint_lo) = paint_stack();
        let mut cp = match cortex_m::Peripherals::take() {
            Some(cp) => cp,
            None => exit(debug::EXIT_FAILURE),
        };
        cp.SYST.set_clock_source(SystClkSource::Core);
        cp.SYST.set_reload(0x00FF_FFFF);
        cp.SYST.clear_current();
        cp.SYST.enable_counter();

        hprintln!("flinch firmware self-test on mps2-an386");
        let scenarios: [Scenario; 12] = [
            ("trip on the edge, latch, reset by input", trip_latch_reset),
            ("automatic reset across the u32 wrap", auto_reset_across_the_wrap),
            ("a watchdog reset stays stopped until a reset press", reset_latch),
            ("latch and event log survive a reset in the backup store", latch_and_log_survive_a_reset),
            ("stuck input fails the start-up test", stuck_input_at_start_up),
            ("cut wire reads as a trip", cut_wire),
            ("clock stall is a fault", clock_stall),
            ("missed tick deadline is a fault", missed_deadline),
            ("chattering input is a fault", chatter),
            ("short stroke budget escalates to category 0", stroke_budget),
            ("analog travel thresholded in fixed point", analog_fixed_point),
            ("event log wraps and round-trips", event_log_round_trip),
        ];
        let (mut passed, mut failed) = (0u32, 0u32);
        for (name, run) in scenarios {
            match run() {
                Ok(()) => {
                    passed += 1;
                    hprintln!("ok   {}", name);
                }
                Err(what) => {
                    failed += 1;
                    hprintln!("FAIL {}: {}", name, what);
                }
            }
        }
        match measure(&mut cp.NVIC) {
            Ok(m) => {
                hprintln!(
                    "icount: best_pend_to_stop={} worst_pend_to_stop={} entry_overhead={} edge_to_stop={} trip_tick={} edge_handler={} edge_and_book={} drain_masked={} tick_to_output_worst={} (instructions under -icount, a proxy for time, not cycles)",
                    m.best,
                    m.worst,
                    m.overhead,
                    (m.best + CAL_PREFIX).saturating_sub(m.overhead + 3),
                    m.trip_tick,
                    m.edge_handler,
                    m.edge_and_book,
                    m.drain_masked,
                    // A tick due just after a trip's bookkeeping began waits for it (same priority,
                    // with its edge), may be preempted by the other channel's edge, then runs the
                    // trip tick to its output write (bounded by its end); plus, conservatively, the
                    // board's log drain's masked section, which a tick can also wait behind.
                    m.trip_tick + m.edge_and_book + m.edge_handler + m.drain_masked
                );
                for (ok, what) in [
                    (m.best <= BEST_LIMIT, "best-case edge-to-stop (idle) within 40 instructions"),
                    (m.worst <= WORST_LIMIT, "worst-case edge-to-stop (edge during the trip tick) within 60 instructions"),
                ] {
                    if ok {
                        passed += 1;
                        hprintln!("ok   {}", what);
                    } else {
                        failed += 1;
                        hprintln!("FAIL {}", what);
                    }
                }
            }
            Err(what) => {
                failed += 1;
                hprintln!("FAIL detect-to-stop measurement: {}", what);
            }
        }
        hprintln!("stack: used={} B below main's frame (painted {} B, measured over every scenario and the edge interrupt)", stack_used(sp0, paint_lo), PAINT_BYTES);
        hprintln!("self-test done: {} ok, {} failed", passed, failed);
        exit(if failed == 0 { debug::EXIT_SUCCESS } else { debug::EXIT_FAILURE })
    }

    /// End the QEMU run with `code` as its exit status.
    fn exit(code: debug::ExitStatus) -> ! {
        debug::exit(code);
        loop {
            cortex_m::asm::nop(); // not reached: QEMU has exited
        }
    }

    #[exception]
    unsafe fn HardFault(ef: &ExceptionFrame) -> ! {
        STOP_LEVEL.store(false, Relaxed);
        hprintln!("FAIL hard fault at pc {:#010x}", ef.pc());
        exit(debug::EXIT_FAILURE)
    }

    #[panic_handler]
    fn panic(info: &core::panic::PanicInfo) -> ! {
        STOP_LEVEL.store(false, Relaxed); // de-energise first
        hprintln!("FAIL panic: {}", info);
        exit(debug::EXIT_FAILURE)
    }

    // ---- Vector table: AN386's 32 lines, the two measured ones wired ------------------------------
    #[derive(Copy, Clone)]
    #[repr(C)]
    pub union Vector {
        handler: unsafe extern "C" fn(),
        reserved: usize,
    }
    extern "C" {
        fn DefaultHandler();
    }
    const fn vectors() -> [Vector; 32] {
        let mut v = [Vector { handler: DefaultHandler }; 32];
        v[IRQ_CAL as usize] = Vector { handler: flinch_cal_handler };
        v[IRQ_EDGE as usize] = Vector { handler: edge_handler };
        v[IRQ_TICK as usize] = Vector { handler: tick_handler };
        v[IRQ_BOOK as usize] = Vector { handler: book_handler };
        v
    }
    #[link_section = ".vector_table.interrupts"]
    #[no_mangle]
    pub static __INTERRUPTS: [Vector; 32] = vectors();
}
