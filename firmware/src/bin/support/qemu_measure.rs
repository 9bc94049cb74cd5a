//! The QEMU self-test's measured edge interrupt: the board's layout of the edge (highest priority,
//! atomics only), the tick and the bookkeeping (one lower priority) on a measured firmware, and the
//! instruction counts of `measure` (edge-to-stop best and worst, the trip tick, the edge and its
//! bookkeeping, the log drain's masked section) read from SysTick under `-icount`.

use crate::isr_cell::IsrCell;
use crate::scenarios::{bench_config, ensure, Check, Level, Switch, Time, BUDGET, T};
use core::convert::Infallible;
use core::ptr::read_volatile;
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering::Relaxed};
use cortex_m::peripheral::NVIC;
use embedded_hal::digital::{ErrorType, OutputPin};
use flinch_firmware::event_log::{self, FLAG_EDGE};
use flinch_firmware::{Boot, Cause, DigitalSwitch, Firmware, Micros, Outputs, State, SwitchKind};

pub(crate) const SYST_CVR: u32 = 0xE000_E018;

// ---- The measured edge interrupt ------------------------------------------------------------
//
// The layout of the board (`board.rs`): the edge interrupt has the highest priority and does not
// touch the `Firmware` object at all. It reads the switch and whether the stop is energised,
// writes the stop, and pends the bookkeeping interrupt, which runs `Firmware::edge_stopped`
// (timestamp, budget, latch, log) at the tick's lower priority. The tick and the bookkeeping
// share one priority, so `IsrCell`'s rule (no two `&mut` at once) holds between them; the edge
// only uses atomics.
pub(crate) const IRQ_EDGE: u16 = 31;
pub(crate) const IRQ_CAL: u16 = 30;
pub(crate) const IRQ_TICK: u16 = 29;
pub(crate) const IRQ_BOOK: u16 = 28;
/// NVIC priorities (lower number = more urgent): the edge above the tick and the bookkeeping.
pub(crate) const PRIO_EDGE: u8 = 0x00;
pub(crate) const PRIO_TICK: u8 = 0x80;
#[derive(Copy, Clone)]
pub(crate) struct Irq(u16);
// SAFETY: 28 to 31 exist on QEMU's AN386 NVIC (32 lines) and no model device drives them.
unsafe impl cortex_m::interrupt::InterruptNumber for Irq {
    fn number(self) -> u16 {
        self.0
    }
}

pub(crate) static STOP_LEVEL: AtomicBool = AtomicBool::new(true);
/// SysTick right after the edge handler's stop write; `NOT_WRITTEN` until it writes.
pub(crate) static STOP_CVR: AtomicU32 = AtomicU32::new(NOT_WRITTEN);
pub(crate) const NOT_WRITTEN: u32 = u32::MAX; // SysTick is 24-bit: never a reading
pub(crate) static CAL_CVR: AtomicU32 = AtomicU32::new(0);
pub(crate) static M_LEVEL: AtomicBool = AtomicBool::new(true);
pub(crate) static M_SUPPLY: AtomicBool = AtomicBool::new(false);
pub(crate) static M_STUCK: AtomicBool = AtomicBool::new(false);
pub(crate) static M_ESC: AtomicBool = AtomicBool::new(true);
/// Stop channel K2 (the library's writes and the edge handler's).
pub(crate) static M_STOP2: AtomicBool = AtomicBool::new(true);
pub(crate) static M_RESET: AtomicBool = AtomicBool::new(false);
pub(crate) static M_NOW: AtomicU32 = AtomicU32::new(0);
/// `Firmware::edge_stops_directly`, a configuration constant stored once before the edge runs.
pub(crate) static M_FAST: AtomicBool = AtomicBool::new(false);
/// The edge handler wrote the stop (and when): for the bookkeeping.
pub(crate) static EDGE_STOPPED: AtomicBool = AtomicBool::new(false);
pub(crate) static EDGE_AT: AtomicU32 = AtomicU32::new(0);
/// The tick handler pends the edge as its first act (the edge arriving during a tick).
pub(crate) static TICK_PENDS_EDGE: AtomicBool = AtomicBool::new(false);
pub(crate) static TICK_T0: AtomicU32 = AtomicU32::new(0);
pub(crate) static TICK_END: AtomicU32 = AtomicU32::new(0);
/// SysTick at the end of the edge handler and of the bookkeeping.
pub(crate) static EDGE_END: AtomicU32 = AtomicU32::new(0);
pub(crate) static BOOK_END: AtomicU32 = AtomicU32::new(0);

/// The stop pin as the library drives it (its writes are not timed).
pub(crate) struct MeasuredStop;
impl ErrorType for MeasuredStop {
    type Error = Infallible;
}
impl embedded_hal::digital::InputPin for MeasuredStop {
    fn is_high(&mut self) -> Result<bool, Infallible> {
        Ok(STOP_LEVEL.load(Relaxed))
    }
    fn is_low(&mut self) -> Result<bool, Infallible> {
        Ok(!STOP_LEVEL.load(Relaxed))
    }
}
impl OutputPin for MeasuredStop {
    // The library's own writes (the bookkeeping's idempotent one, the tick's) are not timed: only
    // the edge handler's write is.
    fn set_low(&mut self) -> Result<(), Infallible> {
        STOP_LEVEL.store(false, Relaxed);
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        STOP_LEVEL.store(true, Relaxed);
        Ok(())
    }
}
#[inline(always)]
pub(crate) fn stop_write_and_time() {
    // The writes first (K1, then K2, as on the board), then the time: the count includes both.
    STOP_LEVEL.store(false, Relaxed);
    M_STOP2.store(false, Relaxed);
    // SAFETY: SysTick's current-value register, always readable.
    STOP_CVR.store(unsafe { read_volatile(SYST_CVR as *const u32) }, Relaxed);
}

pub(crate) type MeasuredFw = Firmware<
    Time<'static>,
    DigitalSwitch<Switch<'static>, Level<'static>>,
    MeasuredStop,
    Level<'static>,
    Level<'static>,
    Level<'static>,
>;
pub(crate) static MFW: IsrCell<MeasuredFw> = IsrCell::new();

/// The edge (highest priority), as on the board: the switch reads "tripped" (the inductive switch
/// reads low, or the supply is off, unless stuck high) -> both stop channels written, then hand over.
pub(crate) unsafe extern "C" fn edge_handler() {
    if M_FAST.load(Relaxed)
        && !M_STUCK.load(Relaxed)
        && !(M_SUPPLY.load(Relaxed) && M_LEVEL.load(Relaxed))
    {
        stop_write_and_time();
        EDGE_AT.store(M_NOW.load(Relaxed), Relaxed);
        EDGE_STOPPED.store(true, Relaxed);
    }
    NVIC::pend(Irq(IRQ_BOOK));
    // SAFETY: SysTick's current-value register (after the stop write: not on the edge's path).
    EDGE_END.store(unsafe { read_volatile(SYST_CVR as *const u32) }, Relaxed);
}

/// The bookkeeping (tick's priority): the trip's timestamp, budget, latch and log.
pub(crate) unsafe extern "C" fn book_handler() {
    // SAFETY: MFW is used only by this handler and the tick handler, which share one priority,
    // and by `measure` with both masked.
    let fw = unsafe { MFW.get() };
    if EDGE_STOPPED.swap(false, Relaxed) {
        fw.edge_stopped(Micros(EDGE_AT.load(Relaxed)));
    } else {
        fw.on_edge();
    }
    // SAFETY: SysTick's current-value register.
    BOOK_END.store(unsafe { read_volatile(SYST_CVR as *const u32) }, Relaxed);
}

/// The tick (lower priority than the edge).
pub(crate) unsafe extern "C" fn tick_handler() {
    if TICK_PENDS_EDGE.swap(false, Relaxed) {
        // SAFETY: SysTick's current-value register.
        TICK_T0.store(unsafe { read_volatile(SYST_CVR as *const u32) }, Relaxed);
        NVIC::pend(Irq(IRQ_EDGE));
        cortex_m::asm::dsb();
        cortex_m::asm::isb();
    }
    // SAFETY: as in `book_handler`.
    let fw = unsafe { MFW.get() };
    fw.tick();
    // SAFETY: SysTick's current-value register.
    TICK_END.store(unsafe { read_volatile(SYST_CVR as *const u32) }, Relaxed);
}

// The calibration handler, in assembly so that its SysTick read is exactly its 3rd instruction
// whatever the compiler does (CAL_PREFIX below): movw, movt, ldr.
core::arch::global_asm!(
    ".section .text.flinch_cal_handler,\"ax\",%progbits",
    ".global flinch_cal_handler",
    ".type flinch_cal_handler,%function",
    ".syntax unified",
    ".thumb_func",
    "flinch_cal_handler:",
    "    movw r0, #0xE018",
    "    movt r0, #0xE000",
    "    ldr r0, [r0]",
    "    movw r1, :lower16:{cvr}",
    "    movt r1, :upper16:{cvr}",
    "    str r0, [r1]",
    "    bx lr",
    cvr = sym CAL_CVR,
);
extern "C" {
    pub(crate) fn flinch_cal_handler();
}
/// Instructions of the calibration handler up to and including its SysTick read.
pub(crate) const CAL_PREFIX: u32 = 3;

/// Read SysTick, pend `irq`, let it run; return the SysTick value read before the pend.
#[inline(never)]
pub(crate) fn pend_and_wait(irq: u16) -> u32 {
    // SAFETY: SysTick's current-value register.
    let t0 = unsafe { read_volatile(SYST_CVR as *const u32) };
    NVIC::pend(Irq(irq));
    cortex_m::asm::dsb();
    cortex_m::asm::isb();
    t0
}

/// Read SysTick, pend the tick and the edge with one store to NVIC_ISPR0 (both arrive in the same
/// instant), let them run; return the SysTick value read before the pend.
#[inline(never)]
pub(crate) fn pend_tick_and_edge_together() -> u32 {
    const NVIC_ISPR0: u32 = 0xE000_E200;
    // SAFETY: SysTick's current-value register.
    let t0 = unsafe { read_volatile(SYST_CVR as *const u32) };
    // SAFETY: setting pending bits of two lines this program owns.
    unsafe { core::ptr::write_volatile(NVIC_ISPR0 as *mut u32, (1 << IRQ_EDGE) | (1 << IRQ_TICK)) };
    cortex_m::asm::dsb();
    cortex_m::asm::isb();
    t0
}

/// SysTick counts (down, 24-bit) to instructions: 25 MHz SysTick vs 64 ns per instruction.
pub(crate) fn counts_to_instructions(t0: u32, t1: u32) -> u32 {
    let counts = t0.wrapping_sub(t1) & 0x00FF_FFFF;
    (counts * 40 + 32) / 64
}

/// What `measure` found, in instructions.
pub(crate) struct Measured {
    /// Pend to stop write, the edge alone (idle core).
    pub(crate) best: u32,
    /// Pend to stop write, the edge arriving with or during the most expensive tick.
    pub(crate) worst: u32,
    /// Exception entry overhead (calibration handler).
    pub(crate) overhead: u32,
    /// The trip tick's own length, pend to its end: what the edge would wait behind at equal
    /// priority.
    pub(crate) trip_tick: u32,
    /// The edge handler, pend to its end (the stop write and the hand-over).
    pub(crate) edge_handler: u32,
    /// A trip's edge and its bookkeeping, pend to the end of the bookkeeping (budget, latch,
    /// log): the longest work at the tick's priority besides the tick itself.
    pub(crate) edge_and_book: u32,
    /// The board's log drain, its BASEPRI-masked section (`LogDrain::run` in src/bin/support/board_log.rs:
    /// a snapshot of at most `DRAIN_BATCH` new events, here of a full log, and the state): a tick due
    /// meanwhile waits for it.
    pub(crate) drain_masked: u32,
}

/// The board's log drain's masked section, as `LogDrain::run` has it (src/bin/support/board_log.rs): BASEPRI
/// to the tick's priority, a snapshot of `log`'s events new to `copy`, the firmware's state,
/// BASEPRI 0. Returns the SysTick values read right before and right after.
#[inline(never)]
pub(crate) fn drain_masked_section(log: &flinch_firmware::EventLog<16>, copy: &flinch_firmware::EventLog<16>, out: &mut Option<(flinch_firmware::LogSnapshot<{ event_log::DRAIN_BATCH }>, State)>) -> (u32, u32) {
    // SAFETY: SysTick's current-value register; BASEPRI as on the board; MFW's users (the tick
    // and the bookkeeping) are masked by it and by NVIC here.
    unsafe {
        let t0 = read_volatile(SYST_CVR as *const u32);
        cortex_m::register::basepri::write(PRIO_TICK);
        let snap = log.snapshot::<{ event_log::DRAIN_BATCH }>(copy.cursor());
        let state = MFW.get().state();
        cortex_m::register::basepri::write(0);
        let t1 = read_volatile(SYST_CVR as *const u32);
        *out = Some((snap, state));
        (t0, t1)
    }
}

/// Arm the measured firmware from thread mode (tick and bookkeeping masked), the switch at rest.
pub(crate) fn arm(round: u32) -> Check {
    NVIC::mask(Irq(IRQ_TICK));
    NVIC::mask(Irq(IRQ_BOOK));
    // SAFETY: both handlers that use MFW are masked, the edge never uses it.
    let fw = unsafe { MFW.get() };
    M_LEVEL.store(true, Relaxed);
    M_RESET.store(round % 2 == 1, Relaxed); // a fresh rising edge each odd round
    for _ in 0..10 {
        M_NOW.store(M_NOW.load(Relaxed).wrapping_add(T), Relaxed);
        fw.tick();
        if fw.is_armed() {
            break;
        }
        M_RESET.store(!M_RESET.load(Relaxed), Relaxed);
    }
    ensure(fw.is_armed() && STOP_LEVEL.load(Relaxed), "measurement firmware did not arm")?;
    STOP_CVR.store(NOT_WRITTEN, Relaxed);
    // SAFETY: the handlers' data is initialised; they share one priority.
    unsafe {
        NVIC::unmask(Irq(IRQ_TICK));
        NVIC::unmask(Irq(IRQ_BOOK));
    }
    Ok(())
}

/// After a measured trip: the edge handler wrote the stop and the bookkeeping latched it as a
/// trip. Returns the SysTick value read right after the edge's stop write.
pub(crate) fn check_stopped(what: &'static str) -> Result<u32, &'static str> {
    ensure(!STOP_LEVEL.load(Relaxed) && !M_STOP2.load(Relaxed), what)?;
    let cvr = STOP_CVR.load(Relaxed);
    ensure(cvr != NOT_WRITTEN, "the edge handler did not write the stop itself (did it preempt?)")?;
    NVIC::mask(Irq(IRQ_TICK));
    NVIC::mask(Irq(IRQ_BOOK));
    // SAFETY: both handlers that use MFW are masked.
    let fw = unsafe { MFW.get() };
    ensure(fw.state() == State::Tripped && fw.stop_requested(), "the bookkeeping latched the trip")?;
    ensure(fw.log().last().map(|e| e.cause) == Some(Cause::Trip), "the trip is logged")?;
    Ok(cvr)
}

pub(crate) fn measure(nvic: &mut NVIC) -> Result<Measured, &'static str> {
    let sensor = DigitalSwitch::with_supply(
        Switch { level: &M_LEVEL, supply: &M_SUPPLY, stuck_high: &M_STUCK },
        Level(&M_SUPPLY),
        SwitchKind::Inductive,
        5_000,
    );
    let outputs = Outputs { k1: MeasuredStop, k2: Level(&M_STOP2), escalation: Level(&M_ESC) };
    let fw = Firmware::after_reset(bench_config(BUDGET), Boot::POWER_ON, Time(&M_NOW), sensor, outputs, Level(&M_RESET))
        .map_err(|_| "config")?;
    M_FAST.store(fw.edge_stops_directly(), Relaxed);
    // SAFETY: once, before the handlers that use it are unmasked.
    unsafe { MFW.init(fw) };
    // SAFETY: priorities of lines this program owns, set before any is unmasked.
    unsafe {
        nvic.set_priority(Irq(IRQ_EDGE), PRIO_EDGE);
        nvic.set_priority(Irq(IRQ_CAL), PRIO_EDGE);
        nvic.set_priority(Irq(IRQ_TICK), PRIO_TICK);
        nvic.set_priority(Irq(IRQ_BOOK), PRIO_TICK);
    }
    let mut m = Measured { best: 0, worst: 0, overhead: 0, trip_tick: 0, edge_handler: 0, edge_and_book: 0, drain_masked: 0 };
    let mut round = 0u32;
    for _ in 0..5 {
        // Calibration: pend to the first load of an empty handler.
        // SAFETY: cal_handler touches only CAL_CVR.
        unsafe { NVIC::unmask(Irq(IRQ_CAL)) };
        let t0 = pend_and_wait(IRQ_CAL);
        m.overhead = m.overhead.max(counts_to_instructions(t0, CAL_CVR.load(Relaxed)));
        NVIC::mask(Irq(IRQ_CAL));
        // SAFETY: the edge handler uses atomics only.
        unsafe { NVIC::unmask(Irq(IRQ_EDGE)) };

        // Best: the edge alone on an idle core.
        arm(round)?;
        round += 1;
        M_LEVEL.store(false, Relaxed);
        let t0 = pend_and_wait(IRQ_EDGE);
        let t1 = check_stopped("best: the edge did not stop")?;
        m.best = m.best.max(counts_to_instructions(t0, t1));
        // The edge ran to its end, then its bookkeeping (tail-chained), before the pend returned.
        m.edge_handler = m.edge_handler.max(counts_to_instructions(t0, EDGE_END.load(Relaxed)));
        m.edge_and_book = m.edge_and_book.max(counts_to_instructions(t0, BOOK_END.load(Relaxed)));

        // Worst (a): the edge and the tick pended in the same instant, the tick finding the trip
        // too (the trip tick: the most expensive one, budget and log).
        arm(round)?;
        round += 1;
        M_LEVEL.store(false, Relaxed);
        M_NOW.store(M_NOW.load(Relaxed).wrapping_add(T), Relaxed);
        let t0 = pend_tick_and_edge_together();
        let t1 = check_stopped("worst (a): the edge did not stop")?;
        m.worst = m.worst.max(counts_to_instructions(t0, t1));

        // Worst (b): the edge arrives while the trip tick runs (pended by the tick itself).
        arm(round)?;
        round += 1;
        M_LEVEL.store(false, Relaxed);
        M_NOW.store(M_NOW.load(Relaxed).wrapping_add(T), Relaxed);
        TICK_PENDS_EDGE.store(true, Relaxed);
        let _ = pend_and_wait(IRQ_TICK);
        let t1 = check_stopped("worst (b): the edge did not stop")?;
        m.worst = m.worst.max(counts_to_instructions(TICK_T0.load(Relaxed), t1));
        NVIC::mask(Irq(IRQ_EDGE));

        // The trip tick alone (the edge masked): what an edge at the tick's priority would wait.
        arm(round)?;
        round += 1;
        M_LEVEL.store(false, Relaxed);
        M_NOW.store(M_NOW.load(Relaxed).wrapping_add(T), Relaxed);
        let t0 = pend_and_wait(IRQ_TICK);
        ensure(!STOP_LEVEL.load(Relaxed), "the trip tick did not stop")?;
        m.trip_tick = m.trip_tick.max(counts_to_instructions(t0, TICK_END.load(Relaxed)));
    }
    NVIC::mask(Irq(IRQ_TICK));
    NVIC::mask(Irq(IRQ_BOOK));
    // The drain's masked section at its worst: a full 16-event log, all new (the board's first
    // drain after a restored log): it takes DRAIN_BATCH of them.
    let mut full: flinch_firmware::EventLog<16> = flinch_firmware::EventLog::new();
    for k in 0..20u32 {
        full.push(Cause::Trip, FLAG_EDGE, Micros(k), Micros(k), 5_000);
    }
    let copy: flinch_firmware::EventLog<16> = flinch_firmware::EventLog::new();
    let mut out = None;
    for _ in 0..5 {
        let (t0, t1) = drain_masked_section(&full, &copy, &mut out);
        m.drain_masked = m.drain_masked.max(counts_to_instructions(t0, t1));
    }
    ensure(out.as_ref().is_some_and(|(s, _)| s.new.len() == event_log::DRAIN_BATCH), "the drain's snapshot took a whole batch")?;
    Ok(m)
}
