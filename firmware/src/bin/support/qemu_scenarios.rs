//! The QEMU self-test's scenarios: the firmware library on RAM pins and a settable clock (a trip
//! latched and reset, resets, the backup store, stuck input, cut wire, clock faults, chatter, the
//! stroke budget, the analog sensor, the event log), each returning Ok or its first failed check.

use core::convert::Infallible;
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering::Relaxed};
use embedded_hal::digital::{ErrorType, InputPin, OutputPin};
use flinch_firmware::backup;
use flinch_firmware::event_log::{self, FLAG_EDGE, FLAG_ESCALATED};
use flinch_firmware::{
    stopping_distance_um, AnalogConfig, AnalogTravel, BudgetConfig, Cause, ChatterGuard, Clock, Config,
    Boot, DigitalSwitch, Filter, Firmware, Micros, Mm, ResetCause, ResetPolicy, ResetPress, Retained, StartPolicy,
    Outputs, RamBackup, State, SwitchKind, Unconnected,
};

pub(crate) const T: u32 = 1_000;

/// The bench's configuration: it starts as after a clean power-on with auto start allowed (the
/// scenarios are about detection; `reset_latch` checks the start latch), and its reset presses
/// are one tick long, so the press window is 1 us to 1 s.
pub(crate) const fn bench_config(budget: BudgetConfig) -> Config {
    let mut c = Config::new(T, budget);
    c.start = StartPolicy::AutoAfterPowerOn;
    c.reset_press = ResetPress { min_us: 1, max_us: 1_000_000 };
    c
}

// ---- RAM pins and a settable clock ----------------------------------------------------------
pub(crate) struct Level<'a>(pub(crate) &'a AtomicBool);
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
pub(crate) struct Switch<'a> {
    pub(crate) level: &'a AtomicBool,
    pub(crate) supply: &'a AtomicBool,
    pub(crate) stuck_high: &'a AtomicBool,
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

pub(crate) struct Time<'a>(pub(crate) &'a AtomicU32);
impl Clock for Time<'_> {
    fn now(&mut self) -> Micros {
        Micros(self.0.load(Relaxed))
    }
}

/// Everything a scenario drives.
pub(crate) struct Bench {
    level: AtomicBool,
    supply: AtomicBool,
    stuck: AtomicBool,
    stop: AtomicBool,
    stop2: AtomicBool,
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
            stop2: AtomicBool::new(true),
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
        let outputs = Outputs { k1: Level(&self.stop), k2: Level(&self.stop2), escalation: Level(&self.esc) };
        Firmware::after_reset(cfg, boot, Time(&self.now), sensor, outputs, Level(&self.reset))
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
        !self.stop.load(Relaxed) && !self.stop2.load(Relaxed)
    }
    fn cat0_requested(&self) -> bool {
        !self.esc.load(Relaxed)
    }
}
pub(crate) type BenchFw<'a> = Firmware<Time<'a>, DigitalSwitch<Switch<'a>, Level<'a>>, Level<'a>, Level<'a>, Level<'a>, Level<'a>>;

/// Tables 5-7: V_c = 0.05 m/s, DT = 16 ms; d = 1 m/s^2, C = 10 mm chosen for the self-test.
pub(crate) const BUDGET: BudgetConfig =
    BudgetConfig { robot_speed_um_per_s: 50_000, dead_time_us: 16_000, decel_um_per_s2: 1_000_000, stroke_um: 10_000 };

// ---- Scenarios: each returns Ok or the first failed check ------------------------------------
pub(crate) type Check = Result<(), &'static str>;
pub(crate) type Scenario = (&'static str, fn() -> Check);
pub(crate) fn ensure(cond: bool, what: &'static str) -> Check {
    if cond {
        Ok(())
    } else {
        Err(what)
    }
}

pub(crate) fn trip_latch_reset() -> Check {
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

pub(crate) fn reset_latch() -> Check {
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
pub(crate) static mut BACKUP: RamBackup<80> = RamBackup::filled(0x6B6B_A5A5);

pub(crate) fn latch_and_log_survive_a_reset() -> Check {
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
pub(crate) fn run_until_trip(bkp: &mut RamBackup<80>) -> Check {
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
pub(crate) fn run_after_watchdog_reset(bkp: &mut RamBackup<80>) -> Check {
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

pub(crate) fn auto_reset_across_the_wrap() -> Check {
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

pub(crate) fn stuck_input_at_start_up() -> Check {
    let b = Bench::new(0);
    b.stuck.store(true, Relaxed);
    let mut fw = b.firmware(bench_config(BUDGET)).ok_or("config")?;
    ensure(!b.boot(&mut fw), "does not arm")?;
    ensure(fw.state() == State::Fault(Cause::StuckInput), "stuck-input fault")?;
    ensure(b.stop_requested() && b.cat0_requested(), "outputs low")
}

pub(crate) fn cut_wire() -> Check {
    let b = Bench::new(0);
    let mut fw = b.firmware(bench_config(BUDGET)).ok_or("config")?;
    ensure(b.boot(&mut fw), "arms")?;
    b.level.store(false, Relaxed); // a cut wire reads low, like a trip: caught by polling too
    b.ticks(&mut fw, 1);
    ensure(b.stop_requested() && fw.state() == State::Tripped, "trip")
}

pub(crate) fn clock_stall() -> Check {
    let b = Bench::new(0);
    let mut fw = b.firmware(bench_config(BUDGET)).ok_or("config")?;
    ensure(b.boot(&mut fw), "arms")?;
    fw.tick(); // same instant again
    ensure(fw.state() == State::Fault(Cause::ClockStall), "stall fault")?;
    ensure(b.stop_requested() && b.cat0_requested(), "outputs low")
}

pub(crate) fn missed_deadline() -> Check {
    let b = Bench::new(0);
    let mut fw = b.firmware(bench_config(BUDGET)).ok_or("config")?;
    ensure(b.boot(&mut fw), "arms")?;
    b.now.store(b.now.load(Relaxed).wrapping_add(2 * T), Relaxed);
    fw.tick();
    ensure(fw.state() == State::Fault(Cause::MissedDeadline), "deadline fault")?;
    ensure(b.stop_requested(), "stop")
}

pub(crate) fn chatter() -> Check {
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

pub(crate) fn stroke_budget() -> Check {
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

pub(crate) fn analog_fixed_point() -> Check {
    struct Raw<'a>(&'a AtomicU32);
    impl flinch_firmware::Adc for Raw<'_> {
        type Error = ();
        fn read(&mut self) -> Result<u16, ()> {
            u16::try_from(self.0.load(Relaxed)).map_err(|_| ())
        }
    }
    let acfg = AnalogConfig::linear_12bit(200, Mm::from_num(20), Mm::from_num(1.5));
    let raw = AtomicU32::new(u32::from(acfg.counts_for(Mm::ZERO)));
    let (stop, stop2, esc, now) = (AtomicBool::new(true), AtomicBool::new(true), AtomicBool::new(true), AtomicU32::new(0));
    let outputs = Outputs { k1: Level(&stop), k2: Level(&stop2), escalation: Level(&esc) };
    let sensor = AnalogTravel::new(Raw(&raw), acfg);
    let mut fw = Firmware::<_, _, _, _, _, _>::after_reset(bench_config(BUDGET), Boot::POWER_ON, Time(&now), sensor, outputs, Unconnected)
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

pub(crate) fn event_log_round_trip() -> Check {
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
