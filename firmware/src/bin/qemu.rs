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
mod qemu {
    use super::isr_cell::IsrCell;
    use core::convert::Infallible;
    use core::ptr::read_volatile;
    use core::sync::atomic::{AtomicBool, AtomicU32, Ordering::Relaxed};
    use cortex_m::peripheral::syst::SystClkSource;
    use cortex_m::peripheral::NVIC;
    use cortex_m_rt::{entry, exception, ExceptionFrame};
    use cortex_m_semihosting::{debug, hprintln};
    use defmt_rtt as _;
    use embedded_hal::digital::{ErrorType, InputPin, OutputPin};
    use flinch_firmware::backup;
    use flinch_firmware::event_log::{self, FLAG_EDGE, FLAG_ESCALATED};
    use flinch_firmware::{
        stopping_distance_um, AnalogConfig, AnalogTravel, BudgetConfig, Cause, ChatterGuard, Clock, Config,
        Boot, DigitalSwitch, Filter, Firmware, Micros, Mm, ResetCause, ResetPolicy, ResetPress, Retained, StartPolicy,
        RamBackup, State, SwitchKind, Unconnected,
    };

    const SYST_CVR: u32 = 0xE000_E018;
    /// Edge-to-stop limits checked here and again by `cargo xtask test` (`check_icount`).
    const BEST_LIMIT: u32 = 40;
    const WORST_LIMIT: u32 = 60;
    const T: u32 = 1_000;

    /// The bench's configuration: it starts as after a clean power-on with auto start allowed (the
    /// scenarios are about detection; `reset_latch` checks the start latch), and its reset presses
    /// are one tick long, so the press window is 1 us to 1 s.
    const fn bench_config(budget: BudgetConfig) -> Config {
        let mut c = Config::new(T, budget);
        c.start = StartPolicy::AutoAfterPowerOn;
        c.reset_press = ResetPress { min_us: 1, max_us: 1_000_000 };
        c
    }

    // ---- RAM pins and a settable clock ----------------------------------------------------------
    struct Level<'a>(&'a AtomicBool);
    impl ErrorType for Level<'_> {
        type Error = Infallible;
    }
    impl InputPin for Level<'_> {
        fn is_high(&mut self) -> Result<bool, Infallible> {
            Ok(self.0.load(Relaxed))
        }
        fn is_low(&mut self) -> Result<bool, Infallible> {
            Ok(!self.0.load(Relaxed))
        }
    }
    impl OutputPin for Level<'_> {
        fn set_high(&mut self) -> Result<(), Infallible> {
            self.0.store(true, Relaxed);
            Ok(())
        }
        fn set_low(&mut self) -> Result<(), Infallible> {
            self.0.store(false, Relaxed);
            Ok(())
        }
    }

    /// The switch: reads `level` while `supply` is on, low (a trip, for the inductive switch) while it
    /// is off, unless `stuck` forces it high.
    struct Switch<'a> {
        level: &'a AtomicBool,
        supply: &'a AtomicBool,
        stuck_high: &'a AtomicBool,
    }
    impl ErrorType for Switch<'_> {
        type Error = Infallible;
    }
    impl InputPin for Switch<'_> {
        #[inline(always)]
        fn is_high(&mut self) -> Result<bool, Infallible> {
            Ok(self.stuck_high.load(Relaxed) || (self.supply.load(Relaxed) && self.level.load(Relaxed)))
        }
        fn is_low(&mut self) -> Result<bool, Infallible> {
            self.is_high().map(|h| !h)
        }
    }

    struct Time<'a>(&'a AtomicU32);
    impl Clock for Time<'_> {
        fn now(&mut self) -> Micros {
            Micros(self.0.load(Relaxed))
        }
    }

    /// Everything a scenario drives.
    struct Bench {
        level: AtomicBool,
        supply: AtomicBool,
        stuck: AtomicBool,
        stop: AtomicBool,
        esc: AtomicBool,
        reset: AtomicBool,
        now: AtomicU32,
    }
    impl Bench {
        const fn new(start: u32) -> Bench {
            Bench {
                level: AtomicBool::new(true),
                supply: AtomicBool::new(false),
                stuck: AtomicBool::new(false),
                stop: AtomicBool::new(true),
                esc: AtomicBool::new(true),
                reset: AtomicBool::new(false),
                now: AtomicU32::new(start),
            }
        }
        fn firmware(&self, cfg: Config) -> Option<BenchFw<'_>> {
            self.firmware_after(cfg, Boot::POWER_ON)
        }
        fn firmware_after(&self, cfg: Config, boot: Boot) -> Option<BenchFw<'_>> {
            let sensor = DigitalSwitch::with_supply(
                Switch { level: &self.level, supply: &self.supply, stuck_high: &self.stuck },
                Level(&self.supply),
                SwitchKind::Inductive,
                5_000,
            );
            Firmware::after_reset(cfg, boot, Time(&self.now), sensor, Level(&self.stop), Level(&self.esc), Level(&self.reset))
                .ok()
        }
        fn ticks(&self, fw: &mut BenchFw<'_>, n: u32) {
            for _ in 0..n {
                self.now.store(self.now.load(Relaxed).wrapping_add(T), Relaxed);
                fw.tick();
            }
        }
        fn boot(&self, fw: &mut BenchFw<'_>) -> bool {
            for _ in 0..20 {
                self.ticks(fw, 1);
                if fw.is_armed() {
                    return true;
                }
            }
            false
        }
        fn stop_requested(&self) -> bool {
            !self.stop.load(Relaxed)
        }
        fn cat0_requested(&self) -> bool {
            !self.esc.load(Relaxed)
        }
    }
    type BenchFw<'a> = Firmware<Time<'a>, DigitalSwitch<Switch<'a>, Level<'a>>, Level<'a>, Level<'a>, Level<'a>>;

    /// Tables 5-7: V_c = 0.05 m/s, DT = 16 ms; d = 1 m/s^2, C = 10 mm chosen for the self-test.
    const BUDGET: BudgetConfig =
        BudgetConfig { robot_speed_um_per_s: 50_000, dead_time_us: 16_000, decel_um_per_s2: 1_000_000, stroke_um: 10_000 };

    // ---- Scenarios: each returns Ok or the first failed check ------------------------------------
    type Check = Result<(), &'static str>;
    type Scenario = (&'static str, fn() -> Check);
    fn ensure(cond: bool, what: &'static str) -> Check {
        if cond {
            Ok(())
        } else {
            Err(what)
        }
    }

    fn trip_latch_reset() -> Check {
        let b = Bench::new(0);
        let mut fw = b.firmware(bench_config(BUDGET)).ok_or("config")?;
        ensure(b.stop_requested() && b.cat0_requested(), "outputs low before the self-test")?;
        ensure(b.boot(&mut fw), "arms")?;
        ensure(!b.stop_requested() && !b.cat0_requested(), "energised when armed")?;
        let t_edge = b.now.load(Relaxed).wrapping_add(345); // between two ticks
        b.now.store(t_edge, Relaxed);
        b.level.store(false, Relaxed);
        fw.on_edge();
        ensure(b.stop_requested() && !b.cat0_requested(), "controlled stop on the edge")?;
        ensure(fw.detected_at() == Some(Micros(t_edge)), "timestamp")?;
        ensure(fw.log().last().map(|e| e.flags) == Some(FLAG_EDGE), "logged from the edge")?;
        b.level.store(true, Relaxed);
        b.ticks(&mut fw, 50);
        ensure(b.stop_requested() && fw.state() == State::Tripped, "latched")?;
        b.reset.store(true, Relaxed);
        b.ticks(&mut fw, 1);
        ensure(b.stop_requested(), "pressing does not re-arm")?;
        b.reset.store(false, Relaxed);
        b.ticks(&mut fw, 1);
        ensure(fw.is_armed() && !b.stop_requested(), "the release of the reset input re-arms")
    }

    fn reset_latch() -> Check {
        // RCC_CSR after an IWDG reset: IWDGRSTF | PINRSTF.
        let boot = Boot { cause: ResetCause::from_rcc_csr(1 << 29 | 1 << 26), retained: Retained::default() };
        let b = Bench::new(0);
        let mut fw = b.firmware_after(bench_config(BUDGET), boot).ok_or("config")?;
        b.ticks(&mut fw, 2_000);
        ensure(b.stop_requested() && b.cat0_requested(), "a watchdog reset stays stopped")?;
        ensure(fw.state() == State::Fault(Cause::Reset), "latched by the reset")?;
        b.reset.store(true, Relaxed);
        b.ticks(&mut fw, 2);
        b.reset.store(false, Relaxed);
        ensure(b.boot(&mut fw), "a reset press and release starts the self-test and arms")
    }

    /// The backup store on this machine: mps2-an386 has no backup SRAM, so a RAM word array
    /// (`flinch_firmware::RamBackup`) runs the same load/store code as the board's backup SRAM.
    /// Filled with garbage, as a power-on leaves an SRAM.
    static mut BACKUP: RamBackup<80> = RamBackup::filled(0x6B6B_A5A5);

    fn latch_and_log_survive_a_reset() -> Check {
        // SAFETY: thread mode only, one scenario at a time; no interrupt touches BACKUP.
        let bkp = unsafe { &mut *core::ptr::addr_of_mut!(BACKUP) };
        run_until_trip(bkp)?;
        run_after_watchdog_reset(bkp)?;
        // One flipped bit in the stored log: no log, the latch still holds.
        bkp.words[backup::LOG_AT + 5] ^= 1 << 3;
        ensure(backup::load_log::<_, 16>(bkp).is_none(), "a corrupt log is refused")?;
        ensure(backup::load_latch(bkp).decode() == Some((Some(Cause::Trip), 0)), "the latch is kept apart")
    }

    /// A power-on with garbage in the store: a clean power-on, arms by itself; then a trip.
    /// (Each run in its own frame: two firmware objects in one frame would double the stack.)
    #[inline(never)]
    fn run_until_trip(bkp: &mut RamBackup<80>) -> Check {
        let boot = Boot { cause: ResetCause::from_rcc_csr(1 << 27 | 1 << 26 | 1 << 25), retained: backup::load_latch(bkp) };
        let b = Bench::new(0);
        let mut fw = b.firmware_after(bench_config(BUDGET), boot).ok_or("config")?;
        fw = fw.with_saved_log(backup::load_log(bkp));
        ensure(b.boot(&mut fw), "garbage in the store reads as a clean power-on")?;
        b.level.store(false, Relaxed);
        fw.on_edge();
        backup::store_latch(bkp, fw.retained());
        ensure(backup::store_log(bkp, fw.log()), "log stored")?;
        ensure(b.stop_requested(), "tripped")
    }

    /// The part resets (IWDG); the obstacle is gone, the outputs float back high.
    #[inline(never)]
    fn run_after_watchdog_reset(bkp: &mut RamBackup<80>) -> Check {
        let b = Bench::new(0);
        let boot = Boot { cause: ResetCause::from_rcc_csr(1 << 29 | 1 << 26), retained: backup::load_latch(bkp) };
        let mut fw = b.firmware_after(bench_config(BUDGET), boot).ok_or("config")?;
        fw = fw.with_saved_log(backup::load_log(bkp));
        b.ticks(&mut fw, 100);
        ensure(b.stop_requested() && fw.state() == State::Fault(Cause::Reset), "stopped after the reset")?;
        let mut it = fw.log().iter().map(|e| (e.seq, e.cause));
        ensure(it.next() == Some((0, Cause::Reset)), "first run's power-on event kept")?;
        ensure(it.next() == Some((1, Cause::Trip)), "first run's trip kept")?;
        ensure(it.next() == Some((2, Cause::Reset)), "the watchdog reset logged after it")?;
        ensure(it.next() == Some((3, Cause::Trip)), "the retained latch logged")
    }

    fn auto_reset_across_the_wrap() -> Check {
        let b = Bench::new(u32::MAX - 30_000);
        let mut cfg = bench_config(BUDGET);
        cfg.reset = ResetPolicy::Auto { hold_us: 20_000 };
        let mut fw = b.firmware(cfg).ok_or("config")?;
        ensure(b.boot(&mut fw), "arms")?;
        b.level.store(false, Relaxed);
        fw.on_edge();
        let t_trip = fw.detected_at().ok_or("tripped")?;
        b.ticks(&mut fw, 5);
        b.level.store(true, Relaxed);
        b.ticks(&mut fw, 20); // rest seen from the 1st of these ticks: hold ends on the 21st
        ensure(b.stop_requested(), "still held")?;
        b.ticks(&mut fw, 1);
        ensure(!b.stop_requested(), "re-armed after 20 ms")?;
        ensure(b.now.load(Relaxed) < t_trip.0, "the clock wrapped during the trip")
    }

    fn stuck_input_at_start_up() -> Check {
        let b = Bench::new(0);
        b.stuck.store(true, Relaxed);
        let mut fw = b.firmware(bench_config(BUDGET)).ok_or("config")?;
        ensure(!b.boot(&mut fw), "does not arm")?;
        ensure(fw.state() == State::Fault(Cause::StuckInput), "stuck-input fault")?;
        ensure(b.stop_requested() && b.cat0_requested(), "outputs low")
    }

    fn cut_wire() -> Check {
        let b = Bench::new(0);
        let mut fw = b.firmware(bench_config(BUDGET)).ok_or("config")?;
        ensure(b.boot(&mut fw), "arms")?;
        b.level.store(false, Relaxed); // a cut wire reads low, like a trip: caught by polling too
        b.ticks(&mut fw, 1);
        ensure(b.stop_requested() && fw.state() == State::Tripped, "trip")
    }

    fn clock_stall() -> Check {
        let b = Bench::new(0);
        let mut fw = b.firmware(bench_config(BUDGET)).ok_or("config")?;
        ensure(b.boot(&mut fw), "arms")?;
        fw.tick(); // same instant again
        ensure(fw.state() == State::Fault(Cause::ClockStall), "stall fault")?;
        ensure(b.stop_requested() && b.cat0_requested(), "outputs low")
    }

    fn missed_deadline() -> Check {
        let b = Bench::new(0);
        let mut fw = b.firmware(bench_config(BUDGET)).ok_or("config")?;
        ensure(b.boot(&mut fw), "arms")?;
        b.now.store(b.now.load(Relaxed).wrapping_add(2 * T), Relaxed);
        fw.tick();
        ensure(fw.state() == State::Fault(Cause::MissedDeadline), "deadline fault")?;
        ensure(b.stop_requested(), "stop")
    }

    fn chatter() -> Check {
        let b = Bench::new(0);
        let mut cfg = bench_config(BUDGET);
        cfg.filter = Filter::Consecutive(3);
        cfg.chatter = Some(ChatterGuard { max_transitions: 6, window_us: 20_000 });
        let mut fw = b.firmware(cfg).ok_or("config")?;
        ensure(b.boot(&mut fw), "arms")?;
        for k in 0..10 {
            b.level.store(k % 2 == 1, Relaxed);
            fw.on_edge();
            b.ticks(&mut fw, 1);
        }
        ensure(fw.state() == State::Fault(Cause::Chatter), "chatter fault")
    }

    fn stroke_budget() -> Check {
        ensure(stopping_distance_um(50_000, 16_000, 1_000_000) == 2_050, "0.8 + 1.25 mm")?;
        let b = Bench::new(0);
        // Fig. 46 mode 3 speed, 0.25 m/s: 35.25 mm needed, 5 mm left.
        let fast = BudgetConfig { robot_speed_um_per_s: 250_000, ..BUDGET };
        let mut fw = b.firmware(bench_config(fast)).ok_or("config")?;
        ensure(b.boot(&mut fw), "arms")?;
        b.level.store(false, Relaxed);
        fw.on_edge();
        ensure(b.stop_requested() && b.cat0_requested(), "category 0")?;
        ensure(fw.log().last().map(|e| e.flags) == Some(FLAG_EDGE | FLAG_ESCALATED), "flagged")
    }

    fn analog_fixed_point() -> Check {
        struct Raw<'a>(&'a AtomicU32);
        impl flinch_firmware::Adc for Raw<'_> {
            type Error = ();
            fn read(&mut self) -> Result<u16, ()> {
                u16::try_from(self.0.load(Relaxed)).map_err(|_| ())
            }
        }
        let acfg = AnalogConfig::linear_12bit(200, Mm::from_num(20), Mm::from_num(1.5));
        let raw = AtomicU32::new(u32::from(acfg.counts_for(Mm::ZERO)));
        let (stop, esc, now) = (AtomicBool::new(true), AtomicBool::new(true), AtomicU32::new(0));
        let sensor = AnalogTravel::new(Raw(&raw), acfg);
        let mut fw = Firmware::<_, _, _, _, _>::after_reset(bench_config(BUDGET), Boot::POWER_ON, Time(&now), sensor, Level(&stop), Level(&esc), Unconnected)
            .map_err(|_| "config")?;
        for k in 1..10u32 {
            now.store(k * T, Relaxed);
            fw.tick();
        }
        ensure(fw.is_armed(), "arms")?;
        raw.store(u32::from(acfg.counts_for(Mm::from_num(1.4))), Relaxed);
        now.store(10 * T, Relaxed);
        fw.tick();
        ensure(stop.load(Relaxed), "1.4 mm: below")?;
        raw.store(u32::from(acfg.counts_for(Mm::from_num(1.6))), Relaxed);
        now.store(11 * T, Relaxed);
        fw.tick();
        ensure(!stop.load(Relaxed), "1.6 mm: trip")?;
        let travel = fw.log().last().map(|e| e.travel_um).unwrap_or(0);
        ensure((travel - 1_600).abs() < 10, "travel in um")
    }

    fn event_log_round_trip() -> Check {
        let mut log: flinch_firmware::EventLog<4> = flinch_firmware::EventLog::new();
        for k in 0..6u32 {
            log.push(Cause::Trip, 0, Micros(u32::MAX - k), Micros(u32::MAX - k), -1);
        }
        let mut buf = [0u8; event_log::HEADER_LEN + 4 * event_log::EVENT_LEN];
        let n = log.serialize(&mut buf).map_err(|_| "serialise")?;
        let (h, mut evs) = event_log::decode(buf.get(..n).ok_or("len")?).ok_or("decode")?;
        ensure(h.count == 4 && h.overwritten == 2, "header")?;
        ensure(evs.next().map(|e| e.seq) == Some(2), "oldest kept is seq 2")
    }

    // ---- The measured edge interrupt ------------------------------------------------------------
    //
    // The layout of the board (`board.rs`): the edge interrupt has the highest priority and does not
    // touch the `Firmware` object at all. It reads the switch and whether the stop is energised,
    // writes the stop, and pends the bookkeeping interrupt, which runs `Firmware::edge_stopped`
    // (timestamp, budget, latch, log) at the tick's lower priority. The tick and the bookkeeping
    // share one priority, so `IsrCell`'s rule (no two `&mut` at once) holds between them; the edge
    // only uses atomics.
    const IRQ_EDGE: u16 = 31;
    const IRQ_CAL: u16 = 30;
    const IRQ_TICK: u16 = 29;
    const IRQ_BOOK: u16 = 28;
    /// NVIC priorities (lower number = more urgent): the edge above the tick and the bookkeeping.
    const PRIO_EDGE: u8 = 0x00;
    const PRIO_TICK: u8 = 0x80;
    #[derive(Copy, Clone)]
    struct Irq(u16);
    // SAFETY: 28 to 31 exist on QEMU's AN386 NVIC (32 lines) and no model device drives them.
    unsafe impl cortex_m::interrupt::InterruptNumber for Irq {
        fn number(self) -> u16 {
            self.0
        }
    }

    static STOP_LEVEL: AtomicBool = AtomicBool::new(true);
    /// SysTick right after the edge handler's stop write; `NOT_WRITTEN` until it writes.
    static STOP_CVR: AtomicU32 = AtomicU32::new(NOT_WRITTEN);
    const NOT_WRITTEN: u32 = u32::MAX; // SysTick is 24-bit: never a reading
    static CAL_CVR: AtomicU32 = AtomicU32::new(0);
    static M_LEVEL: AtomicBool = AtomicBool::new(true);
    static M_SUPPLY: AtomicBool = AtomicBool::new(false);
    static M_STUCK: AtomicBool = AtomicBool::new(false);
    static M_ESC: AtomicBool = AtomicBool::new(true);
    static M_RESET: AtomicBool = AtomicBool::new(false);
    static M_NOW: AtomicU32 = AtomicU32::new(0);
    /// `Firmware::edge_stops_directly`, a configuration constant stored once before the edge runs.
    static M_FAST: AtomicBool = AtomicBool::new(false);
    /// The edge handler wrote the stop (and when): for the bookkeeping.
    static EDGE_STOPPED: AtomicBool = AtomicBool::new(false);
    static EDGE_AT: AtomicU32 = AtomicU32::new(0);
    /// The tick handler pends the edge as its first act (the edge arriving during a tick).
    static TICK_PENDS_EDGE: AtomicBool = AtomicBool::new(false);
    static TICK_T0: AtomicU32 = AtomicU32::new(0);
    static TICK_END: AtomicU32 = AtomicU32::new(0);
    /// SysTick at the end of the edge handler and of the bookkeeping.
    static EDGE_END: AtomicU32 = AtomicU32::new(0);
    static BOOK_END: AtomicU32 = AtomicU32::new(0);

    /// The stop pin as the library drives it (its writes are not timed).
    struct MeasuredStop;
    impl ErrorType for MeasuredStop {
        type Error = Infallible;
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
    fn stop_write_and_time() {
        // The write first, then the time: the count includes the write.
        STOP_LEVEL.store(false, Relaxed);
        // SAFETY: SysTick's current-value register, always readable.
        STOP_CVR.store(unsafe { read_volatile(SYST_CVR as *const u32) }, Relaxed);
    }

    type MeasuredFw = Firmware<
        Time<'static>,
        DigitalSwitch<Switch<'static>, Level<'static>>,
        MeasuredStop,
        Level<'static>,
        Level<'static>,
    >;
    static MFW: IsrCell<MeasuredFw> = IsrCell::new();

    /// The edge (highest priority): the stop reads back energised (armed) and the switch reads
    /// "tripped" (the inductive switch reads low, or the supply is off, unless stuck high) -> stop
    /// write, then hand over.
    unsafe extern "C" fn edge_handler() {
        if M_FAST.load(Relaxed)
            && STOP_LEVEL.load(Relaxed)
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
    unsafe extern "C" fn book_handler() {
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
    unsafe extern "C" fn tick_handler() {
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
        fn flinch_cal_handler();
    }
    /// Instructions of the calibration handler up to and including its SysTick read.
    const CAL_PREFIX: u32 = 3;

    /// Read SysTick, pend `irq`, let it run; return the SysTick value read before the pend.
    #[inline(never)]
    fn pend_and_wait(irq: u16) -> u32 {
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
    fn pend_tick_and_edge_together() -> u32 {
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
    fn counts_to_instructions(t0: u32, t1: u32) -> u32 {
        let counts = t0.wrapping_sub(t1) & 0x00FF_FFFF;
        (counts * 40 + 32) / 64
    }

    /// What `measure` found, in instructions.
    struct Measured {
        /// Pend to stop write, the edge alone (idle core).
        best: u32,
        /// Pend to stop write, the edge arriving with or during the most expensive tick.
        worst: u32,
        /// Exception entry overhead (calibration handler).
        overhead: u32,
        /// The trip tick's own length, pend to its end: what the edge would wait behind at equal
        /// priority.
        trip_tick: u32,
        /// The edge handler, pend to its end (the stop write and the hand-over).
        edge_handler: u32,
        /// A trip's edge and its bookkeeping, pend to the end of the bookkeeping (budget, latch,
        /// log): the longest work at the tick's priority besides the tick itself.
        edge_and_book: u32,
        /// The board's log drain, its BASEPRI-masked section (`LogDrain::run` in src/bin/board.rs:
        /// a snapshot of at most `DRAIN_BATCH` new events, here of a full log, and the state): a tick due
        /// meanwhile waits for it.
        drain_masked: u32,
    }

    /// The board's log drain's masked section, as `LogDrain::run` has it (src/bin/board.rs): BASEPRI
    /// to the tick's priority, a snapshot of `log`'s events new to `copy`, the firmware's state,
    /// BASEPRI 0. Returns the SysTick values read right before and right after.
    #[inline(never)]
    fn drain_masked_section(log: &flinch_firmware::EventLog<16>, copy: &flinch_firmware::EventLog<16>, out: &mut Option<(flinch_firmware::LogSnapshot<16>, State)>) -> (u32, u32) {
        // SAFETY: SysTick's current-value register; BASEPRI as on the board; MFW's users (the tick
        // and the bookkeeping) are masked by it and by NVIC here.
        unsafe {
            let t0 = read_volatile(SYST_CVR as *const u32);
            cortex_m::register::basepri::write(PRIO_TICK);
            let snap = log.snapshot(copy.cursor(), event_log::DRAIN_BATCH);
            let state = MFW.get().state();
            cortex_m::register::basepri::write(0);
            let t1 = read_volatile(SYST_CVR as *const u32);
            *out = Some((snap, state));
            (t0, t1)
        }
    }

    /// Arm the measured firmware from thread mode (tick and bookkeeping masked), the switch at rest.
    fn arm(round: u32) -> Check {
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
    fn check_stopped(what: &'static str) -> Result<u32, &'static str> {
        ensure(!STOP_LEVEL.load(Relaxed), what)?;
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

    fn measure(nvic: &mut NVIC) -> Result<Measured, &'static str> {
        let sensor = DigitalSwitch::with_supply(
            Switch { level: &M_LEVEL, supply: &M_SUPPLY, stuck_high: &M_STUCK },
            Level(&M_SUPPLY),
            SwitchKind::Inductive,
            5_000,
        );
        let fw = Firmware::after_reset(bench_config(BUDGET), Boot::POWER_ON, Time(&M_NOW), sensor, MeasuredStop, Level(&M_ESC), Level(&M_RESET))
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
