//! The bench around the board ELF in QEMU (feature `qemu-io` only; never in the production build).
//!
//! QEMU 7.2's `netduinoplus2` (STM32F405) does not model GPIO: every GPIO read returns 0, and its
//! EXTI ignores writes to `EXTI_SWIER` (it keeps the value, raises nothing). So with the production
//! build the board never arms in QEMU and its edge handler can never run. This feature changes exactly
//! two things in `board_hw.rs`, both in the pin accessors:
//!
//! * an input register read (`IDR`) returns `PINS`, a RAM word this bench sets, for GPIOA, and for
//!   the output ports (B, D, E) the RAM image of their output register: the pins follow their
//!   outputs, as healthy pins do (the output read-back, `flinch_firmware::output_monitor`);
//! * every BSRR write still goes to the port's real BSRR address (QEMU logs it with `-d unimp`: that
//!   log is what `cargo xtask board-qemu` checks) and is also applied to the port's RAM image.
//!
//! Everything else (main, the register set-up, NVIC priorities, the vector table, SysTick, TIM2 as the
//! clock, the edge and bookkeeping handlers, the library, the retained latch) is the board binary's
//! own code. The bench runs in thread mode instead of `wfi` and plays the world outside the MCU:
//!
//! * wiring: with the sensor supply (PD14) off both channels read "tripped" (A low, B high); the two
//!   EDM relays follow the stop output (PD12) at once (released = high while the stop is low);
//! * the operator: a reset press of 100 ms (firmware time, TIM2);
//! * the obstacle: both channels of the switch go to "tripped", A first, and the edge is pended
//!   through `NVIC_ISPR`: on the F407 the GPIO edge detector sets `EXTI_PR` and pends the line, which
//!   QEMU 7.2 does not model. `EXTI_PR` is therefore 0 when the handler clears it (harmless).
//!
//! Each step writes a marker to GPIOI's BSRR (GPIOI is unused on the board; QEMU logs the write), so
//! the register trace shows where the bench acted. Scenario: reset, arm, an edge on channel A (EXTI0)
//! stops, obstacle gone, reset, re-arm, an edge on channel B (EXTI4) stops, end. The bench reports
//! over semihosting and exits QEMU; xtask compares the trace with `firmware/qemu/board-edge.txt`.
//! Other modes (semihosting argument): `panic`, `overflow`, `config` (the faults), and `serial`
//! (`cargo xtask board-serial`): the operator and the obstacle around the host's weights frames,
//! acting on the velocity frames' statuses, so that the frames show `stopped: latched` while the
//! firmware holds the robot and every other status after a reset press (`serial` below).

use crate::hw::{gpio, ESC_PIN, ESC_PORT, K1_PIN, K1_PORT, K2_PIN, K2_PORT, PI, SUPPLY_PIN, SUPPLY_PORT};
use core::sync::atomic::{AtomicU32, Ordering::Relaxed};
use cortex_m_semihosting::{debug, hprintln};

use crate::pin_image::{idr, PINS};

/// Stop channel K1's output is high.
fn k1_high() -> bool {
    idr(K1_PORT) & (1 << K1_PIN) != 0
}
/// Either stop channel's output is high (the stop circuit is closed only if both are).
fn stop_energised() -> bool {
    k1_high() && idr(K2_PORT) & (1 << K2_PIN) != 0
}
/// Both stop channels' outputs are low.
fn both_stopped() -> bool {
    idr(K1_PORT) & (1 << K1_PIN) == 0 && idr(K2_PORT) & (1 << K2_PIN) == 0
}
#[allow(dead_code)]
fn escalation_high() -> bool {
    idr(ESC_PORT) & (1 << ESC_PIN) != 0
}

const A: u32 = 1 << 0; // PA0: channel A, high at rest
const RESET: u32 = 1 << 1; // PA1
const EDM_K1: u32 = 1 << 2; // PA2: high = K1 released
const EDM_K2: u32 = 1 << 3; // PA3: high = K2 released
const B: u32 = 1 << 4; // PA4: channel B, high when tripped

/// A bench marker: a write to GPIOI's BSRR (GPIOI is unused on the board; QEMU logs the write).
fn mark(v: u32) {
    // SAFETY: BSRR takes any pattern; GPIOI's pins are not used.
    gpio(PI).bsrr().write(|w| unsafe { w.bits(v) });
}

/// Pend interrupt `irq` (the GPIO edge detector's or the capture unit's request, which QEMU does
/// not model) through the NVIC's set-pending register.
fn pend(irq: u32) {
    // SAFETY: one set-pending bit of a line the board owns; the NVIC's register block from cortex-m.
    unsafe { (*cortex_m::peripheral::NVIC::PTR).ispr[(irq / 32) as usize].write(1 << (irq % 32)) };
}
/// One TIM5 capture per 8 LSI periods at a nominal 32 kHz: every 250 us.
const LSI_CAPTURE_US: u32 = 250;

/// The switch as the obstacle leaves it, before the wiring model; and the LSI.
struct World<F: FnMut()> {
    /// The board's thread-mode work between interrupts (its log drain: `board.rs`, `LogDrain`),
    /// run on every pass so that its stack use and its backup-SRAM stores are part of the run.
    idle: F,
    a_tripped: bool,
    b_tripped: bool,
    reset: bool,
    /// The LSI runs: TIM5's capture interrupt is pended every `LSI_CAPTURE_US` (QEMU's TIM5 has no
    /// input capture; on the part the capture unit pends it).
    lsi_on: bool,
    lsi_next: Option<u32>,
}

impl<F: FnMut()> World<F> {
    /// The input register the MCU sees now.
    fn pins(&self) -> u32 {
        let powered = idr(SUPPLY_PORT) & (1 << SUPPLY_PIN) != 0;
        let mut p = 0;
        if powered && !self.a_tripped {
            p |= A;
        }
        if !powered || self.b_tripped {
            p |= B;
        }
        if self.reset {
            p |= RESET;
        }
        // Each relay follows its own stop channel (released while its coil's pin is low).
        if idr(K1_PORT) & (1 << K1_PIN) == 0 {
            p |= EDM_K1;
        }
        if idr(K2_PORT) & (1 << K2_PIN) == 0 {
            p |= EDM_K2;
        }
        p
    }

    /// One pass of the world: the pins, and the LSI's capture when it is due.
    fn step(&mut self, now: u32) {
        (self.idle)();
        PINS.store(self.pins(), Relaxed);
        if !self.lsi_on {
            return;
        }
        let next = *self.lsi_next.get_or_insert(now);
        if now.wrapping_sub(next) < 0x8000_0000 {
            pend(50);
            self.lsi_next = Some(next.wrapping_add(LSI_CAPTURE_US));
        }
    }
}

/// Run the world for `us` microseconds of TIM2 time (the bench's pins follow the outputs meanwhile).
fn run<F: FnMut()>(w: &mut World<F>, now: &impl Fn() -> u32, us: u32) {
    let start = now();
    while now().wrapping_sub(start) < us {
        w.step(now());
    }
    w.step(now());
}

/// Run until the stop output reads `want`, at most `us`; false on time-out.
fn until_stop<F: FnMut()>(w: &mut World<F>, now: &impl Fn() -> u32, want: bool, us: u32) -> bool {
    let start = now();
    while now().wrapping_sub(start) < us {
        w.step(now());
        if stop_energised() == want && (want || both_stopped()) {
            return true;
        }
    }
    false
}

fn fail(what: &str) -> ! {
    hprintln!("bench: FAIL {}", what);
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::nop();
    }
}

/// Press and release the reset input for `press_us`.
fn reset_press<F: FnMut()>(w: &mut World<F>, now: &impl Fn() -> u32, press_us: u32) {
    mark(1); // marker 1: reset pressed
    w.reset = true;
    run(w, now, press_us);
    mark(2); // marker 2: reset released
    w.reset = false;
    run(w, now, 1_000);
}

/// A 100 ms reset press, then the board must arm (the stop output energised) within 2 s; `failure`
/// is the bench's verdict if it does not.
fn arm<F: FnMut()>(w: &mut World<F>, now: &impl Fn() -> u32, failure: &str) {
    reset_press(w, now, 100_000);
    if !until_stop(w, now, true, 2_000_000) {
        fail(failure);
    }
}

/// A channel of the switch.
#[derive(Clone, Copy)]
enum Channel {
    /// PA0, EXTI0 (IRQ 6).
    A,
    /// PA4, EXTI4 (IRQ 10).
    B,
}

impl Channel {
    fn other(self) -> Self {
        match self {
            Channel::A => Channel::B,
            Channel::B => Channel::A,
        }
    }

    /// Its EXTI line's interrupt (EXTI0 = 6, EXTI4 = 10).
    fn irq(self) -> u32 {
        match self {
            Channel::A => 6,
            Channel::B => 10,
        }
    }
}

/// The obstacle moves channel `ch`'s contact: marker `mark`, the channel reads "tripped" and its
/// edge is pended.
fn trip<F: FnMut()>(w: &mut World<F>, ch: Channel, mark: u32) {
    self::mark(mark);
    match ch {
        Channel::A => w.a_tripped = true,
        Channel::B => w.b_tripped = true,
    }
    PINS.store(w.pins(), Relaxed);
    PEND_AT.store(cvr(), Relaxed);
    pend(ch.irq());
}

/// The obstacle: channel `first`'s contact, then the other's 1 ms later, as a real actuator moves
/// both (`marks`: the bench's markers for the two edges); the stop must have been written when the
/// first edge's pend returned.
fn obstacle<F: FnMut()>(w: &mut World<F>, now: &impl Fn() -> u32, first: Channel, marks: [u32; 2]) {
    trip(w, first, marks[0]);
    // The edge has priority 0 and thread mode none: it ran before this line.
    let stopped = both_stopped();
    run(w, now, 1_000);
    trip(w, first.other(), marks[1]);
    run(w, now, 100_000);
    match (first, stopped) {
        (Channel::A, false) => fail("the stop was not written when the EXTI0 pend returned"),
        (Channel::B, false) => fail("the stop was not written when the EXTI4 pend returned"),
        (Channel::A, true) => hprintln!("bench: channel A edge: stop written before the pend returned"),
        (Channel::B, true) => hprintln!("bench: channel B edge: stop written before the pend returned"),
    }
}

/// The obstacle goes: both channels back at rest (marker 5), 100 ms.
fn obstacle_gone<F: FnMut()>(w: &mut World<F>, now: &impl Fn() -> u32) {
    mark(5); // marker 5: obstacle gone
    w.a_tripped = false;
    w.b_tripped = false;
    run(w, now, 100_000);
}

/// What this run does, from the semihosting command line (`-semihosting-config arg=...`): the edge
/// scenario, or one of the faults that end the run (a panic in thread mode, a stack overflow).
#[derive(Copy, Clone, PartialEq, Eq)]
enum Mode {
    Edges,
    Serial,
    Panic,
    Overflow,
    Config,
}

fn mode() -> Mode {
    let mut buf = [0u8; 64];
    let mut block = [buf.as_mut_ptr() as usize, buf.len()];
    // SAFETY: SYS_GET_CMDLINE writes at most `buf.len()` bytes into `buf` and the length into
    // `block[1]`; both outlive the call.
    let failed = unsafe { cortex_m_semihosting::syscall(cortex_m_semihosting::nr::GET_CMDLINE, &mut block) } != 0;
    let line = buf.get(..block[1].min(buf.len())).unwrap_or(&[]);
    let has = |w: &[u8]| !failed && line.windows(w.len()).any(|x| x == w);
    if has(b"panic") {
        Mode::Panic
    } else if has(b"overflow") {
        Mode::Overflow
    } else if has(b"config") {
        Mode::Config
    } else if has(b"serial") {
        Mode::Serial
    } else {
        Mode::Edges
    }
}

/// Recurse with a 256-byte frame that the compiler cannot drop, until the stack runs into the MPU
/// guard (the fault handler never returns here).
#[inline(never)]
fn overflow(depth: u32) -> u32 {
    let mut frame = [0u32; 64];
    // SAFETY: a volatile write into this frame's own array, so the frame is really used.
    unsafe { core::ptr::write_volatile(frame.as_mut_ptr().wrapping_add((depth % 64) as usize), depth) };
    let below = if depth < u32::MAX { overflow(depth.wrapping_add(1)) } else { 0 };
    // SAFETY: as above (a read after the call keeps the frame alive across it).
    below.wrapping_add(unsafe { core::ptr::read_volatile(frame.as_ptr()) })
}

/// From the fault paths (`board_faults.rs`, qemu-io only): the outputs are low and the latch
/// written; hold 20 ms of TIM2 time with every interrupt masked (no tick, so no feed: xtask checks
/// the trace), then report and end the run.
pub fn fault_report(what: &str) -> ! {
    let t = || crate::hw::tim2().cnt().read().bits();
    let t0 = t();
    while t().wrapping_sub(t0) < 20_000 {}
    mark(12); // marker 12: the fault handler held 20 ms
    // SAFETY: a read of the SCB's configurable fault status register (cortex-m's register block).
    let cfsr = unsafe { (*cortex_m::peripheral::SCB::PTR).cfsr.read() };
    hprintln!("bench: {} ran: outputs low, FaultHandler latched, 20 ms held with no tick; CFSR {:#010x}", what, cfsr);
    hprintln!("bench: PASS");
    debug::exit(debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::nop();
    }
}

/// The scenario; `now` reads TIM2 (microseconds of firmware time).
pub fn run_scenario(now: impl Fn() -> u32, idle: impl FnMut()) -> ! {
    let mut w = World { idle, a_tripped: false, b_tripped: false, reset: false, lsi_on: true, lsi_next: None };
    let mode = mode();
    calibrate_usart_entry();
    if mode == Mode::Serial {
        serial(&mut w, &now);
    }
    run(&mut w, &now, 200_000); // latched after the reset: nothing happens untouched
    if mode != Mode::Edges {
        arm(&mut w, &now, "not armed within 2 s of the reset press");
        run(&mut w, &now, 50_000); // armed, the tick feeding the watchdog
        if mode == Mode::Panic {
            mark(10); // marker 10: a panic in thread mode
            panic!("bench: a panic in thread mode");
        }
        if mode == Mode::Config {
            // A configuration bit flips while armed (a stray write, an upset): EXTI0's NVIC priority
            // from 0x10 to 0x90, below the tick. The periodic read-back must latch and stop.
            mark(13); // marker 13: a configuration bit flipped
            // SAFETY: one priority byte of the NVIC (cortex-m's register block).
            unsafe { (*cortex_m::peripheral::NVIC::PTR).ipr[6].write(0x90) };
            let t0 = now();
            if !until_stop(&mut w, &now, false, 100_000) {
                fail("still 'go' 100 ms after a configuration bit flipped");
            }
            hprintln!("bench: a flipped configuration bit: stopped after {} us (read-back every 16 ticks)", now().wrapping_sub(t0));
            run(&mut w, &now, 10_000);
            hprintln!("bench: PASS");
            debug::exit(debug::EXIT_SUCCESS);
        }
        mark(11); // marker 11: a stack overflow in thread mode
        let n = overflow(0);
        fail(if n == 0 { "the stack overflow returned" } else { "the stack overflow returned a value" });
    }
    if k1_high() {
        fail("'go' before any reset press");
    }
    arm(&mut w, &now, "not armed within 2 s of the reset press");
    hprintln!("bench: armed after the reset press");
    run(&mut w, &now, 50_000);
    // The obstacle: channel A first (markers 3 and 4: EXTI0, then EXTI4).
    obstacle(&mut w, &now, Channel::A, [3, 4]);

    // Obstacle gone, then a reset: re-arm. This time channel B moves first (markers 6 and 7).
    obstacle_gone(&mut w, &now);
    if k1_high() {
        fail("re-armed without a reset press");
    }
    arm(&mut w, &now, "not re-armed within 2 s of the second reset press");
    hprintln!("bench: re-armed after the second reset press");
    run(&mut w, &now, 50_000);
    obstacle(&mut w, &now, Channel::B, [6, 7]);

    // A trip that the edge interrupt misses (both channels move, no EXTI pend): the tick polls it
    // and runs the trip itself (budget, latch, log): the longest tick, for the worst case.
    obstacle_gone(&mut w, &now);
    arm(&mut w, &now, "not re-armed within 2 s of the third reset press");
    run(&mut w, &now, 50_000);
    mark(14); // marker 14: both channels trip, no edge interrupt
    w.a_tripped = true;
    w.b_tripped = true;
    PINS.store(w.pins(), Relaxed);
    if !until_stop(&mut w, &now, false, 5_000) {
        fail("a trip without an edge interrupt was not stopped by the tick within 5 ms");
    }
    hprintln!("bench: a trip without an edge interrupt: stopped by the tick");

    // The clock check: obstacle gone, reset, re-arm; then the LSI stops (the reference dies) while
    // armed. The firmware must drop both outputs (ClockDrift) within a window (100 ms) and a tick.
    obstacle_gone(&mut w, &now);
    arm(&mut w, &now, "not re-armed within 2 s of the fourth reset press");
    run(&mut w, &now, 50_000);
    mark(9); // marker 9: the LSI stops
    w.lsi_on = false;
    let t0 = now();
    if !until_stop(&mut w, &now, false, 250_000) {
        fail("still 'go' 250 ms after the clock check's reference stopped");
    }
    let took_ms = now().wrapping_sub(t0) / 1_000;
    hprintln!("bench: LSI stopped while armed: stopped (clock check) after {} ms", took_ms);
    run(&mut w, &now, 10_000);
    mark(8); // marker 8: end
    report_worst();
    let (used, painted) = stack_used();
    hprintln!("bench: stack used={} B of the board ELF (painted {} B; main, the drain, the bench and every interrupt)", used, painted);
    hprintln!("bench: PASS");
    debug::exit(debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::nop();
    }
}

// ---- The serial conversation (`cargo xtask board-serial`): the operator and the obstacle around
// the host's weights frames, so that the velocity frames show `stopped: latched` and every other
// status after a reset press -------------------------------------------------------------------------
/// The last velocity frame the step queued: its status code (`u32::MAX`: none yet) and the frames
/// applied (`board_avoid.rs`, qemu-io only).
static VEL_STATUS: AtomicU32 = AtomicU32::new(u32::MAX);
static VEL_GOOD: AtomicU32 = AtomicU32::new(0);
/// Velocity frames queued while the status was `stopped: latched`.
static VEL_LATCHED: AtomicU32 = AtomicU32::new(0);
const ST_OK: u32 = 0;
const ST_STALE: u32 = 2;
const ST_LATCHED: u32 = 4;
/// How long the bench waits for the host's next frame, firmware time.
const HOST_WAIT_US: u32 = 60_000_000;

/// From the step: the velocity frame it queued.
#[inline(always)]
pub fn velocity_sent(status: u32, good: u32) {
    VEL_STATUS.store(status, Relaxed);
    VEL_GOOD.store(good, Relaxed);
    if status == ST_LATCHED {
        VEL_LATCHED.fetch_add(1, Relaxed);
    }
}

/// Run until the last velocity frame had `status` and at least `good` frames applied, at most
/// `HOST_WAIT_US`; `what` is the verdict on time-out.
fn until_velocity<F: FnMut()>(w: &mut World<F>, now: &impl Fn() -> u32, status: u32, good: u32, what: &str) {
    let start = now();
    while now().wrapping_sub(start) < HOST_WAIT_US {
        w.step(now());
        if VEL_STATUS.load(Relaxed) == status && VEL_GOOD.load(Relaxed) >= good {
            return;
        }
    }
    fail(what);
}

/// The serial mode: the start latch (the host reads `stopped: latched`), a reset press, the host's
/// frames 1 to 3 and the line silent until `stopped: stale`; then the obstacle trips the switch (the
/// collision latch: `stopped: latched`), the host's frame 4 is taken while latched, the obstacle
/// goes and a reset press releases the latch (the weights of frame 4 are stale by then); the host's
/// frame 5 must give `ok`, and the host's frames 6 to 9 (the monitor's cases) end with `ok` again.
/// The host (xtask) checks the frames, the bench the stop outputs.
fn serial<F: FnMut()>(w: &mut World<F>, now: &impl Fn() -> u32) -> ! {
    run(w, now, 300_000); // the start latch: frames say `stopped: latched`
    if k1_high() || VEL_LATCHED.load(Relaxed) == 0 {
        fail("serial: not held, or no `stopped: latched` frame, before the reset press");
    }
    arm(w, now, "serial: not armed within 2 s of the reset press");
    hprintln!("bench: serial: armed after the reset press");
    until_velocity(w, now, ST_STALE, 2, "serial: the host's frames 1 and 3 never aged to `stopped: stale`");
    obstacle(w, now, Channel::A, [3, 4]);
    let before = VEL_LATCHED.load(Relaxed);
    until_velocity(w, now, ST_LATCHED, 3, "serial: the host's frame 4 was not taken while latched");
    // Held for 1.3 s more with frame 4 applied: it is stale (the board cell's 1,167 ms from its
    // clock echo) when the latch is released.
    run(w, now, 1_300_000);
    if !both_stopped() || VEL_LATCHED.load(Relaxed).wrapping_sub(before) < 100 {
        fail("serial: the collision latch did not hold with `stopped: latched` frames");
    }
    hprintln!("bench: serial: tripped, {} frames said `stopped: latched`", VEL_LATCHED.load(Relaxed).wrapping_sub(before));
    obstacle_gone(w, now);
    arm(w, now, "serial: not re-armed within 2 s of the second reset press");
    hprintln!("bench: serial: re-armed after the second reset press");
    until_velocity(w, now, ST_OK, 4, "serial: no `ok` after the release and the host's frame 5");
    // The host's monitor frames (a person ahead, one at the tool ahead, one behind, another boot's
    // echo, then nothing sensed): `ok` again with 9 frames applied.
    until_velocity(w, now, ST_OK, 9, "serial: no `ok` after the host's last frame");
    run(w, now, 200_000);
    hprintln!("bench: PASS");
    debug::exit(debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::nop();
    }
}

// ---- Stack painting: the board ELF's own stack use, measured in this run ---------------------------
/// flip-link puts the stack at the bottom of RAM: it grows down from `_stack_start` towards
/// 0x2000_0000. `paint_stack` (called by `main` right after the RAM test, which left the region
/// zeroed) fills it with `PAINT` up to just below main's frame; `stack_used` finds the lowest word no
/// longer holding it. Everything that ran afterwards is included: main, the drain (thread mode),
/// this bench, the tick, the bookkeeping, the LSI capture and both edges.
const PAINT: u32 = 0xA5A5_5A5A;
const RAM_START: u32 = 0x2000_0000;
const PAINT_GAP: u32 = 64;
extern "C" {
    static _stack_start: u32;
}

/// Paint the unused stack below the current stack pointer (less `PAINT_GAP`).
#[inline(always)]
pub fn paint_stack() {
    let sp = cortex_m::register::msp::read();
    let mut a = RAM_START;
    while a < sp.saturating_sub(PAINT_GAP) {
        // SAFETY: RAM below the live frames; nothing lives there (flip-link: only the stack).
        unsafe { core::ptr::write_volatile(a as *mut u32, PAINT) };
        a += 4;
    }
}

/// (bytes used below the stack's top, bytes painted). The MPU guard at the bottom is not read (no
/// access there).
fn stack_used() -> (u32, u32) {
    // The linker's symbol; only its address is used.
    let top = core::ptr::addr_of!(_stack_start) as u32;
    let mut a = RAM_START + crate::hw::GUARD_BYTES;
    // SAFETY: reads of the stack region, word-aligned.
    while a < top && unsafe { core::ptr::read_volatile(a as *const u32) } == PAINT {
        a += 4;
    }
    (top - a, top - RAM_START)
}

// ---- The board's own worst case (xtask stage "board worst case"): the longest run of every piece
// of work that can delay a stop write, measured on this ELF in this run -------------------------------
/// SysTick's current value (modelled by QEMU: it counts the 168 MHz core clock, so under
/// `-icount shift=3`, 8 ns an instruction, 1.344 counts an instruction).
#[inline(always)]
pub fn cvr() -> u32 {
    // SAFETY: a read of SysTick's current-value register (cortex-m's register block).
    unsafe { (*cortex_m::peripheral::SYST::PTR).cvr.read() }
}
/// SysTick's period in counts (the qemu-clock build's 1 ms reload + 1).
const SYST_PERIOD: u32 = crate::hw::CORE_HZ / 1_000_000 * crate::hw::TICK_US;

fn elapsed(t0: u32, t1: u32) -> u32 {
    // SysTick counts down and reloads every period.
    if t0 >= t1 {
        t0 - t1
    } else {
        t0 + SYST_PERIOD - t1
    }
}

/// The longest of each, SysTick counts. Each includes whatever preempted it (an over-estimate).
pub static W_TICK: AtomicU32 = AtomicU32::new(0);
pub static W_BOOK: AtomicU32 = AtomicU32::new(0);
pub static W_TIM5: AtomicU32 = AtomicU32::new(0);
pub static W_USART: AtomicU32 = AtomicU32::new(0);
/// The longest USART entry that took one byte (the part's case at 115,200 baud: a byte every 87 us;
/// QEMU hands the next byte over at once, so its entries often take many).
pub static W_USART_1: AtomicU32 = AtomicU32::new(0);
pub static W_EDGE_END: AtomicU32 = AtomicU32::new(0);
pub static W_EDGE_STOP: AtomicU32 = AtomicU32::new(0);
pub static W_MASK_STEP: AtomicU32 = AtomicU32::new(0);
pub static W_MASK_DRAIN: AtomicU32 = AtomicU32::new(0);
pub static W_MASK_DIAG: AtomicU32 = AtomicU32::new(0);
/// USART1 interrupts taken (the traffic xtask sends during the run).
pub static N_USART: AtomicU32 = AtomicU32::new(0);
/// SysTick when the bench pended an edge (`u32::MAX`: none pending).
static PEND_AT: AtomicU32 = AtomicU32::new(u32::MAX);

/// Counts spent in measured handlers, net of what preempted them: a section subtracts what was added
/// while it ran, so each figure is its own work, not the interrupts that came in between (those are
/// added separately in the worst case).
static STOLEN: AtomicU32 = AtomicU32::new(0);

/// SysTick, the preemption total and the USART entries read together, with every interrupt held
/// off for the three reads (a few instructions; the bench pends its edges from thread mode, never
/// inside a snapshot), so a handler never falls between them. Before, the reads were retried up to
/// four times, and under QEMU's USART floods a snapshot could still pair a SysTick read after a
/// handler with a total read before it: one run measured the drain's masked section at 4,766
/// SysTick counts, the run before at 249.
#[inline(always)]
fn snap() -> (u32, u32, u32) {
    cortex_m::interrupt::free(|_| (cvr(), STOLEN.load(Relaxed), N_USART.load(Relaxed)))
}

/// What a USART entry costs the code it preempts beyond the net time it adds to `STOLEN`: the
/// instructions before its `start` and after its `note` (prologue, the `STOLEN` update, epilogue),
/// SysTick counts; calibrated at the start of the run (`calibrate_usart_entry`). QEMU floods USART
/// bytes (no baud rate), so a section can be preempted by dozens of entries; without this their
/// uncounted instructions inflated the sections (on main: a 9,215-instruction tick-to-output in
/// one run against 5,281 in another).
static USART_ENTRY_COST: AtomicU32 = AtomicU32::new(0);

/// The start of a measured section: SysTick now, the preemption total, the USART entries.
#[inline(always)]
pub fn start() -> (u32, u32, u32) {
    snap()
}

/// Record a section begun at `t0` (`start`) that ends now, net of the handlers that preempted it
/// (their net time and, per USART entry, `USART_ENTRY_COST`); `handler`: it is an interrupt
/// handler, whose net time then counts as preemption for whatever it interrupted.
#[inline(always)]
pub fn note(w: &AtomicU32, t0: (u32, u32, u32), handler: bool) {
    let t1 = snap();
    let entries = t1.2.wrapping_sub(t0.2).saturating_mul(USART_ENTRY_COST.load(Relaxed));
    let net = elapsed(t0.0, t1.0).saturating_sub(t1.1.wrapping_sub(t0.1)).saturating_sub(entries);
    w.fetch_max(net, Relaxed);
    if handler {
        STOLEN.fetch_add(net, Relaxed);
    }
}

/// One calibration window: SysTick counts from a snapshot to the next around a pend of USART1's
/// interrupt (IRQ 37, no byte received: its shortest path), net of `STOLEN`, and the USART entries
/// seen; `masked`: BASEPRI holds the USART off until after the window (the same instructions, only
/// the value written differs).
#[inline(never)]
fn usart_window(masked: bool) -> (u32, u32, u32) {
    let level = core::hint::black_box(if masked { 0x40u8 } else { 0 });
    let old = cortex_m::register::basepri::read();
    // SAFETY: BASEPRI only masks; restored below (the masked pend is taken then).
    unsafe { cortex_m::register::basepri::write(level) };
    let t0 = snap();
    pend(37);
    let t1 = snap();
    // SAFETY: the value read above.
    unsafe { cortex_m::register::basepri::write(old) };
    (elapsed(t0.0, t1.0).saturating_sub(t1.1.wrapping_sub(t0.1)), t1.2.wrapping_sub(t0.2), t1.1.wrapping_sub(t0.1))
}

/// `USART_ENTRY_COST`: the smallest (pended window) - (masked window) over 32 tries each, only
/// windows that saw exactly their own entry (pended) or none (masked) and no other handler. The
/// minimum, so subtracting it per entry never takes off more than an entry costs.
fn calibrate_usart_entry() -> u32 {
    let (mut bare, mut with) = (u32::MAX, u32::MAX);
    for _ in 0..32 {
        let (d, n, _) = usart_window(true);
        if n == 0 {
            bare = bare.min(d);
        }
        let (d, n, stolen) = usart_window(false);
        if n == 1 && stolen > 0 {
            with = with.min(d);
        }
    }
    let cost = if with == u32::MAX || bare == u32::MAX { 0 } else { with.saturating_sub(bare) };
    USART_ENTRY_COST.store(cost, Relaxed);
    cost
}

/// From the edge handler, right after its second stop write: pend to stop, if the bench pended it
/// (nothing can preempt the edge but a fault). Includes the qemu-io build's RAM image update of the
/// K1 write (an atomic read-modify-write the production build does not have).
#[inline(always)]
pub fn edge_stop_written() {
    let p = PEND_AT.load(Relaxed);
    if p != u32::MAX {
        W_EDGE_STOP.fetch_max(elapsed(p, cvr()), Relaxed);
    }
}

/// From the edge handler's end: pend to end, if the bench pended it; the edge's time counts as
/// preemption for whatever it interrupted.
#[inline(always)]
pub fn edge_end() {
    let p = PEND_AT.swap(u32::MAX, Relaxed);
    if p != u32::MAX {
        let (c, _, _) = snap();
        let d = elapsed(p, c);
        W_EDGE_END.fetch_max(d, Relaxed);
        STOLEN.fetch_add(d, Relaxed);
    }
}

fn report_worst() {
    let l = |w: &AtomicU32| w.load(Relaxed);
    hprintln!(
        "bench: worst counts tick={} book={} tim5={} usart={} usart_1={} edge_end={} edge_stop={} mask_step={} mask_drain={} mask_diag={} usart_irqs={} usart_entry={} (SysTick counts of the 168 MHz core clock under -icount shift=3: 1.344 counts an instruction)",
        l(&W_TICK),
        l(&W_BOOK),
        l(&W_TIM5),
        l(&W_USART),
        l(&W_USART_1),
        l(&W_EDGE_END),
        l(&W_EDGE_STOP),
        l(&W_MASK_STEP),
        l(&W_MASK_DRAIN),
        l(&W_MASK_DIAG),
        l(&N_USART),
        l(&USART_ENTRY_COST)
    );
}
