//! [`Firmware`]: the sensor, filter, detector, watchdog, outputs, log and budget tied together.
//!
//! Two entry points, both cheap and non-blocking:
//!
//! * [`Firmware::tick`], from a periodic interrupt every [`Config::tick_period_us`]: watchdog, sensor
//!   sample, glitch filter, self-test, reset policy. It also detects trips on its own (polling), so a
//!   lost edge interrupt costs at most one tick.
//! * [`Firmware::on_edge`], from the switch's edge interrupt (both edges). With [`Filter::None`] and the
//!   detector armed it reads the pin and, on a trip, writes the stop pin before anything else: that is
//!   the detect-to-stop path whose length the QEMU build measures (README of `firmware/`). With a filter
//!   it only timestamps the edge for the filter and the chatter guard.

use crate::clock::{Clock, Micros};
use crate::debounce::{ChatterGuard, ChatterState, Debouncer, Filter};
use crate::detector::{ResetPolicy, ResetTracker, State};
use crate::event_log::{Cause, EventLog, FLAG_EDGE, FLAG_ESCALATED, FLAG_FILTERED, FLAG_RETAINED};
use crate::clock_check::{ClockCheck, ClockMonitor};
use crate::edm::{Feedback, NoFeedback};
use crate::output_monitor::{Commanded, OutputMonitor};
use crate::reset::{Boot, ResetCause, ResetPress, Retained, StartPolicy};
use crate::selftest::{self, Phase, SelfTestConfig, Step};
use crate::sensor::{Sample, Sensor};
use crate::stop_output::{Outputs, StopOutputs};
use crate::stroke_budget::{BudgetConfig, Verdict};
use embedded_hal::digital::{InputPin, OutputPin};

/// Everything the firmware is configured with. Build one with [`Config::new`] and adjust fields.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct Config {
    /// Period of [`Firmware::tick`], microseconds (> 0).
    pub tick_period_us: u32,
    /// Lateness tolerated on a tick before it counts as a missed deadline, microseconds. Below
    /// `tick_period_us` so that one missed tick is caught.
    pub deadline_slack_us: u32,
    /// Consecutive ticks reading the same instant that make a clock stall (>= 1).
    pub stall_ticks: u8,
    /// Glitch filter on the sensor.
    pub filter: Filter,
    /// Chatter guard, applied while armed or in the self-test; `None` disables it.
    pub chatter: Option<ChatterGuard>,
    /// How a trip is cleared.
    pub reset: ResetPolicy,
    /// Robot motion and stroke for the escalation decision.
    pub budget: BudgetConfig,
    /// Start-up self-test timing.
    pub selftest: SelfTestConfig,
    /// Whether a start (any MCU reset) waits for a person (`reset.rs`).
    pub start: StartPolicy,
    /// What counts as a deliberate reset press (acts on release; too short or too long is refused).
    pub reset_press: ResetPress,
    /// Time the stop relays have to follow a change of the stop output before a read-back mismatch
    /// is a fault (`edm.rs`), microseconds.
    pub edm_settle_us: u32,
    /// Check the clock against an independent reference (`clock_check.rs`); `None`: no check.
    pub clock_check: Option<ClockCheck>,
}

impl Config {
    /// Defaults around a tick period and a budget: no glitch filter (the edge stops directly), slack
    /// half a tick, stall after one repeated instant, chatter guard of 6 changes in 20 ms, reset by
    /// input acting on release of a 50 ms to 5 s press, every start latched until that reset,
    /// self-test 1 ms supply-off settle and 2 ms at rest.
    pub const fn new(tick_period_us: u32, budget: BudgetConfig) -> Config {
        Config {
            tick_period_us,
            deadline_slack_us: tick_period_us / 2,
            stall_ticks: 1,
            filter: Filter::None,
            chatter: Some(ChatterGuard { max_transitions: 6, window_us: 20_000 }),
            reset: ResetPolicy::Input,
            budget,
            selftest: SelfTestConfig { supply_off_settle_us: 1_000, rest_quiet_us: 2_000 },
            start: StartPolicy::ManualReset,
            reset_press: ResetPress::DEFAULT,
            edm_settle_us: 20_000,
            clock_check: None,
        }
    }

    /// Check the values a user can get wrong; the error names the field.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if self.tick_period_us == 0 {
            return Err(ConfigError::TickPeriodZero);
        }
        if self.deadline_slack_us >= self.tick_period_us {
            return Err(ConfigError::SlackNotBelowPeriod);
        }
        if self.stall_ticks == 0 {
            return Err(ConfigError::StallTicksZero);
        }
        if self.filter == Filter::Consecutive(0) {
            return Err(ConfigError::FilterCountZero);
        }
        if self.budget.decel_um_per_s2 == 0 {
            return Err(ConfigError::DecelerationZero);
        }
        if self.budget.stroke_um <= 0 {
            return Err(ConfigError::StrokeNotPositive);
        }
        if matches!(self.chatter, Some(ChatterGuard { max_transitions: 0, .. })) {
            return Err(ConfigError::ChatterLimitZero);
        }
        if matches!(self.clock_check, Some(c) if c.reference_hz == 0 || c.window_us == 0 || c.window_us >= 1 << 30 || c.tolerance_pct >= 100) {
            return Err(ConfigError::ClockCheckRange);
        }
        if self.edm_settle_us >= 1 << 30 {
            return Err(ConfigError::EdmSettleRange);
        }
        if self.reset_press.min_us == 0
            || self.reset_press.min_us > self.reset_press.max_us
            || self.reset_press.max_us >= 1 << 30
        {
            return Err(ConfigError::ResetPressRange);
        }
        Ok(())
    }
}

/// A configuration value that cannot work.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum ConfigError {
    /// `tick_period_us` is 0.
    TickPeriodZero,
    /// `deadline_slack_us` is not below `tick_period_us`.
    SlackNotBelowPeriod,
    /// `stall_ticks` is 0.
    StallTicksZero,
    /// `filter` is `Consecutive(0)`.
    FilterCountZero,
    /// `budget.decel_um_per_s2` is 0.
    DecelerationZero,
    /// `budget.stroke_um` is not positive.
    StrokeNotPositive,
    /// `chatter.max_transitions` is 0.
    ChatterLimitZero,
    /// `reset_press` is not `0 < min_us <= max_us < 2^30`.
    ResetPressRange,
    /// `edm_settle_us` is not below 2^30.
    EdmSettleRange,
    /// `clock_check` needs `reference_hz > 0`, `0 < window_us < 2^30`, `tolerance_pct < 100`.
    ClockCheckRange,
}

impl ConfigError {
    /// A message naming the offending input.
    pub const fn message(self) -> &'static str {
        match self {
            ConfigError::TickPeriodZero => "tick_period_us must be > 0",
            ConfigError::SlackNotBelowPeriod => {
                "deadline_slack_us must be below tick_period_us, or a missed tick goes unnoticed"
            }
            ConfigError::StallTicksZero => "stall_ticks must be >= 1",
            ConfigError::FilterCountZero => "filter Consecutive(n) needs n >= 1",
            ConfigError::DecelerationZero => "budget.decel_um_per_s2 must be > 0",
            ConfigError::StrokeNotPositive => "budget.stroke_um must be > 0",
            ConfigError::ChatterLimitZero => "chatter.max_transitions must be >= 1",
            ConfigError::EdmSettleRange => "edm_settle_us must be below 2^30 us",
            ConfigError::ClockCheckRange => {
                "clock_check needs reference_hz > 0, 0 < window_us < 2^30 us and tolerance_pct < 100"
            }
            ConfigError::ResetPressRange => {
                "reset_press must have 0 < min_us <= max_us < 2^30 us (a zero minimum lets a glitch reset)"
            }
        }
    }
}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.message())
    }
}

/// The collision module's firmware.
///
/// Type parameters: `C` the clock, `S` the sensor, `K1` and `K2` the two stop channels and `ESC` the
/// category-0 escalation output (each an output read back at its pin, `stop_output.rs`), `RST` the
/// reset input ([`Unconnected`](crate::Unconnected) if there is none), `LOG` the event-log
/// capacity, `FB` the stop output's read-back ([`NoFeedback`] unless [`Firmware::with_feedback`]).
pub struct Firmware<C, S, K1, K2, ESC, RST, const LOG: usize = 16, FB = NoFeedback> {
    cfg: Config,
    clock: C,
    sensor: S,
    out: StopOutputs<K1, K2, ESC>,
    reset: RST,
    state: State,
    fast_edge: bool,
    debounce: Debouncer,
    chatter: ChatterState,
    watchdog: crate::watchdog::Watchdog,
    resetter: ResetTracker,
    detected_at: Option<Micros>,
    verdict: Option<Verdict>,
    last_sample: Sample,
    log: EventLog<LOG>,
    retained: Retained,
    boots: u32,
    feedback: FB,
    monitor: OutputMonitor,
    clock_monitor: ClockMonitor,
    /// `cfg.budget`'s stopping distance at the configured speed, computed once.
    required_um: u32,
}

impl<C, S, K1, K2, ESC, RST, const LOG: usize> Firmware<C, S, K1, K2, ESC, RST, LOG, NoFeedback>
where
    C: Clock,
    S: Sensor,
    K1: OutputPin + InputPin,
    K2: OutputPin + InputPin,
    ESC: OutputPin + InputPin,
    RST: InputPin,
{
    /// Take the peripherals and de-energise every output, not knowing why the MCU started
    /// ([`Boot::UNKNOWN`]): latched in [`State::Fault`]`(`[`Cause::Reset`]`)` until a reset press,
    /// whatever [`Config::start`] says. A board passes what it knows with [`Firmware::after_reset`].
    pub fn new(cfg: Config, clock: C, sensor: S, outputs: Outputs<K1, K2, ESC>, reset: RST) -> Result<Self, ConfigError> {
        Self::after_reset(cfg, Boot::UNKNOWN, clock, sensor, outputs, reset)
    }

    /// Take the peripherals and de-energise every output after the reset described by `boot`. The
    /// reset cause is logged ([`Cause::Reset`], flags = [`ResetCause`] code), and so is a latch found
    /// in the retained record ([`FLAG_RETAINED`]). The firmware then waits for a reset press and
    /// release, unless [`StartPolicy::AutoAfterPowerOn`] is configured, the cause is a clean
    /// power-on and no latch survived: only then does the self-test start by itself.
    pub fn after_reset(
        cfg: Config,
        boot: Boot,
        clock: C,
        sensor: S,
        outputs: Outputs<K1, K2, ESC>,
        reset: RST,
    ) -> Result<Self, ConfigError> {
        cfg.validate()?;
        let (out, ok) = StopOutputs::new(outputs);
        let mut fw = Firmware {
            cfg,
            clock,
            sensor,
            out,
            reset,
            state: State::SelfTest(Phase::Start),
            fast_edge: cfg.filter == Filter::None,
            debounce: Debouncer::new(cfg.filter),
            chatter: ChatterState::new(cfg.chatter),
            watchdog: crate::watchdog::Watchdog::new(cfg.tick_period_us, cfg.deadline_slack_us, cfg.stall_ticks),
            resetter: ResetTracker::default(),
            detected_at: None,
            verdict: None,
            last_sample: Sample::default(),
            log: EventLog::new(),
            retained: Retained::default(),
            boots: 0,
            feedback: NoFeedback,
            monitor: OutputMonitor::new(),
            clock_monitor: ClockMonitor::new(cfg.clock_check),
            required_um: cfg.budget.configured_required_um(),
        };
        let now = fw.clock.now();
        let record = boot.retained.decode();
        let latched_before = record.and_then(|(c, _)| c);
        fw.boots = record.map_or(0, |(_, n)| n.wrapping_add(1));
        fw.log.push(Cause::Reset, boot.cause as u8, now, now, 0);
        if let Some(c) = latched_before {
            fw.log.push(c, FLAG_RETAINED, now, now, 0);
        }
        let auto = cfg.start == StartPolicy::AutoAfterPowerOn
            && boot.cause == ResetCause::PowerOn
            && latched_before.is_none();
        if auto {
            fw.retained = Retained::new(None, fw.boots);
        } else {
            fw.state = State::Fault(Cause::Reset);
            fw.retained = Retained::new(Some(latched_before.unwrap_or(Cause::Reset)), fw.boots);
            warn!("start latched after a {=str} reset: waiting for a reset press", boot.cause.name());
        }
        if !ok {
            let now = fw.clock.now();
            fw.fault(Cause::OutputFault, now);
        }
        Ok(fw)
    }

    /// Read the stop output back through `feedback` ([`Edm`](crate::Edm): the two relays' NC mirror
    /// contacts) from now on. Call it right after construction, before the first tick.
    pub fn with_feedback<FB: Feedback>(self, feedback: FB) -> Firmware<C, S, K1, K2, ESC, RST, LOG, FB> {
        Firmware {
            cfg: self.cfg,
            clock: self.clock,
            sensor: self.sensor,
            out: self.out,
            reset: self.reset,
            state: self.state,
            fast_edge: self.fast_edge,
            debounce: self.debounce,
            chatter: self.chatter,
            watchdog: self.watchdog,
            resetter: self.resetter,
            detected_at: self.detected_at,
            verdict: self.verdict,
            last_sample: self.last_sample,
            log: self.log,
            retained: self.retained,
            boots: self.boots,
            feedback,
            monitor: OutputMonitor::new(),
            clock_monitor: self.clock_monitor,
            required_um: self.required_um,
        }
    }
}

impl<C, S, K1, K2, ESC, RST, const LOG: usize, FB> Firmware<C, S, K1, K2, ESC, RST, LOG, FB>
where
    C: Clock,
    S: Sensor,
    K1: OutputPin + InputPin,
    K2: OutputPin + InputPin,
    ESC: OutputPin + InputPin,
    RST: InputPin,
    FB: Feedback,
{
    /// Continue the event log saved before the reset (`backup::load_log`): the saved events first,
    /// with their sequence numbers, then this start's (the reset cause, a retained latch) numbered
    /// after them. Timestamps of saved events are in the previous run's clock; the [`Cause::Reset`]
    /// event separates the runs. Call it right after construction, before the first tick.
    pub fn with_saved_log(mut self, saved: Option<EventLog<LOG>>) -> Self {
        if let Some(mut log) = saved {
            for e in self.log.iter() {
                log.push(e.cause, e.flags, e.at, e.first_seen, e.travel_um);
            }
            self.log = log;
        }
        self
    }

    /// The edge interrupt's entry point (call it on both edges of the switch input).
    ///
    /// Armed and unfiltered: read the pin; on a trip write the stop pin at once, then do the
    /// bookkeeping (timestamp, budget, log) out of line. Otherwise record the edge for the filter.
    #[inline(always)]
    pub fn on_edge(&mut self) {
        if self.fast_edge && self.state == State::Armed && self.sensor.fast_trip() {
            let ok = self.out.drop_stop();
            self.after_edge_stop(ok);
        } else {
            self.edge_slow();
        }
    }

    #[inline(never)]
    fn after_edge_stop(&mut self, ok: bool) {
        let now = self.clock.now();
        let travel = self.sensor.trip_travel_um();
        self.commit_trip(now, now, travel, 0, FLAG_EDGE);
        if !ok {
            self.fault(Cause::OutputFault, now);
        }
    }

    /// Whether the edge stops directly ([`Filter::None`]; with a glitch filter the tick decides).
    ///
    /// A board whose edge interrupt preempts the tick does not call into the firmware from it: its
    /// edge handler writes the stop pin itself when this holds (a configuration constant, read once),
    /// the stop output reads back energised (it is energised only while [`State::Armed`]) and the
    /// switch reads tripped; then it hands over to [`Firmware::edge_stopped`] at the tick's priority.
    /// Otherwise it hands over to [`Firmware::on_edge`] there. The one window this leaves: an edge
    /// inside the tick that arms, before that tick's energise write, is stopped by the
    /// [`Firmware::on_edge`] that follows the tick (bounded by one tick's length).
    pub const fn edge_stops_directly(&self) -> bool {
        self.fast_edge
    }

    /// The bookkeeping of a stop that the board's edge handler has already written at `at` (see
    /// [`Firmware::edge_stops_directly`]), run at the tick's priority: the stop output is written low
    /// again through the library (idempotent), and the trip is timestamped, budgeted, latched and
    /// logged as an edge trip. If the firmware has left `Armed` meanwhile (the tick saw the trip or a
    /// fault first) the stop is only written again: the state already says why it is stopped.
    pub fn edge_stopped(&mut self, at: Micros) {
        let ok = self.out.drop_stop();
        // Let the sensor see the channels as they are now (a two-channel switch records which
        // channels have shown the trip; one shorter than the hand-over is missed and ends, on the
        // safe side, in a discrepancy fault).
        let _ = self.sensor.fast_trip();
        if self.state == State::Armed {
            let travel = self.sensor.trip_travel_um();
            self.commit_trip(at, at, travel, 0, FLAG_EDGE);
        }
        if !ok {
            self.fault(Cause::OutputFault, at);
        }
    }

    #[inline(never)]
    fn edge_slow(&mut self) {
        let now = self.clock.now();
        let trip = self.sensor.fast_trip();
        if self.state == State::Armed {
            self.debounce.note_edge(now, trip);
            if self.chatter.observe(now, trip) {
                self.fault(Cause::Chatter, now);
            }
        }
    }

    /// The periodic entry point: call every [`Config::tick_period_us`].
    pub fn tick(&mut self) {
        let now = self.clock.now();
        if let Err(cause) = self.watchdog.check(now) {
            self.fault(cause, now);
        }
        let reference = self.clock.reference_ticks();
        if let Err(cause) = self.clock_monitor.check(now, reference) {
            self.fault(cause, now);
        }
        self.check_outputs(now);
        let sample = self.sensor.sample(now);
        self.last_sample = sample;
        let reset_level = self.reset.is_high().unwrap_or(false);
        match self.state {
            State::SelfTest(mut phase) => {
                if self.chatter.observe(now, sample.trip) {
                    self.resetter.idle_tick(reset_level);
                    return self.fault(Cause::Chatter, now);
                }
                self.resetter.idle_tick(reset_level);
                // With the supply off every channel must read the trip (a two-channel sensor with
                // one channel stuck at rest fails here); at rest, every channel must be at rest.
                let trip = match phase {
                    Phase::Start => {
                        self.sensor.clear_cycle();
                        sample.trip
                    }
                    Phase::SupplyOff(_) => sample.trip && self.sensor.channels_cycled(),
                    Phase::WaitRest(_) => sample.trip,
                };
                match selftest::step(&mut phase, &self.cfg.selftest, now, trip, self.sensor.has_supply()) {
                    Step::Continue(supply) => {
                        if let Some(on) = supply {
                            self.sensor.set_supply(on);
                        }
                        self.state = State::SelfTest(phase);
                    }
                    // Not before the clock has passed its first plausibility window.
                    Step::Arm if !self.clock_monitor.passed() => self.state = State::SelfTest(phase),
                    Step::Arm => self.arm(now),
                    Step::Fail(cause) => self.fault(cause, now),
                }
            }
            State::Armed => {
                self.resetter.idle_tick(reset_level);
                if sample.fault {
                    return self.fault(Cause::SensorFault, now);
                }
                if sample.discrepancy {
                    return self.fault(Cause::Discrepancy, now);
                }
                if self.chatter.observe(now, sample.trip) {
                    return self.fault(Cause::Chatter, now);
                }
                if self.debounce.update(now, sample.trip) {
                    let first = self.debounce.first_seen().unwrap_or(now);
                    let flags = if first == now { 0 } else { FLAG_FILTERED };
                    self.out.drop_stop();
                    let v = u32::try_from(sample.velocity_um_per_s).unwrap_or(0);
                    let travel = if sample.travel_um > 0 { sample.travel_um } else { self.sensor.trip_travel_um() };
                    self.commit_trip(now, first, travel, v, flags);
                }
            }
            State::Tripped => {
                // A stuck channel of a two-channel sensor: disagreeing too long, or the trip over
                // without every channel having shown it (dual.rs). Never re-arm on one channel.
                if sample.discrepancy || (!sample.trip && !self.sensor.channels_cycled()) {
                    self.resetter.idle_tick(reset_level);
                    return self.fault(Cause::Discrepancy, now);
                }
                let (policy, press) = (self.cfg.reset, self.cfg.reset_press);
                if self.resetter.tripped_tick(policy, press, now, sample.trip, reset_level) {
                    self.arm(now);
                }
            }
            State::Fault(_) => {
                if self.resetter.fault_tick(self.cfg.reset_press, now, reset_level) {
                    info!("fault cleared by the reset input: self-test again");
                    self.watchdog.restart();
                    self.watchdog.check(now).ok();
                    self.chatter = ChatterState::new(self.cfg.chatter);
                    self.clock_monitor = ClockMonitor::new(self.cfg.clock_check); // a fresh window first
                    self.state = State::SelfTest(Phase::Start);
                }
            }
        }
    }

    /// The output side, every tick (`output_monitor.rs`): each output read back at its pin, each
    /// relay at its contacts (EDM), against the command.
    fn check_outputs(&mut self, now: Micros) {
        let cmd = Commanded {
            stop_energised: !self.out.stop_requested(),
            escalation_energised: !self.out.category0_requested(),
        };
        let pins = self.out.read_back();
        let relays = self.feedback.read();
        if let Err((cause, channels)) = self.monitor.check(now, cmd, pins, relays, self.cfg.edm_settle_us) {
            self.fault_flags(cause, now, channels);
        }
    }

    /// Record a trip whose stop write has already happened.
    fn commit_trip(&mut self, now: Micros, first_seen: Micros, travel_um: i32, closing_um_per_s: u32, flags: u8) {
        // The configured speed's stopping distance was computed at configuration; only a measured
        // closing speed above it (analog sensor, from the tick) pays the u64 divisions here.
        let verdict = if closing_um_per_s > self.cfg.budget.robot_speed_um_per_s {
            self.cfg.budget.check_at(travel_um, closing_um_per_s)
        } else {
            self.cfg.budget.verdict_with(self.required_um, travel_um)
        };
        let mut flags = flags;
        if verdict.escalate {
            flags |= FLAG_ESCALATED;
            if !self.out.escalate() {
                self.fault(Cause::OutputFault, now);
            }
        }
        self.state = State::Tripped;
        self.detected_at = Some(now);
        self.verdict = Some(verdict);
        self.debounce.clear();
        self.resetter.begin_latch();
        self.retained = Retained::new(Some(Cause::Trip), self.boots);
        self.log.push(Cause::Trip, flags, now, first_seen, travel_um);
        warn!("trip at {=u32} us, travel {=i32} um, escalate {=bool}", now.0, travel_um, verdict.escalate);
    }

    fn arm(&mut self, now: Micros) {
        self.debounce.clear();
        self.sensor.clear_cycle();
        if let Err((cause, channels)) = OutputMonitor::relays_released(self.feedback.read()) {
            return self.fault_flags(cause, now, channels);
        }
        self.monitor.restart();
        if self.out.energise() {
            self.state = State::Armed;
            self.retained = Retained::new(None, self.boots);
            info!("armed at {=u32} us", now.0);
        } else {
            self.fault(Cause::OutputFault, now);
        }
    }

    /// Latch a fault: every output de-energised; logged once per fault episode.
    fn fault(&mut self, cause: Cause, now: Micros) {
        self.fault_flags(cause, now, 0);
    }

    /// [`Firmware::fault`] with extra event flags (the channels of an output fault).
    fn fault_flags(&mut self, cause: Cause, now: Micros, flags: u8) {
        self.fault_event(cause, now, flags, self.last_sample.travel_um);
    }

    /// [`Firmware::fault_flags`] with the event's travel field given (a diagnostic's detail).
    fn fault_event(&mut self, cause: Cause, now: Micros, flags: u8, travel_um: i32) {
        self.out.drop_all();
        match self.state {
            // A real fault found while latched after a reset replaces the start latch, so the state
            // and the retained record name the problem.
            State::Fault(Cause::Reset) if cause != Cause::Reset => {}
            State::Fault(_) => return,
            _ => {}
        }
        self.sensor.set_supply(true);
        self.resetter.begin_latch();
        self.retained = Retained::new(Some(cause), self.boots);
        self.state = State::Fault(cause);
        self.log.push(cause, FLAG_ESCALATED | flags, now, now, travel_um);
        warn!("fault {=str} at {=u32} us", cause.name(), now.0);
    }

    /// A periodic self-test failed (`diagnostics.rs`): latch [`Cause::Diagnostic`]; the event's flags
    /// carry the check in bits 4..6, its travel field `detail` (what was read).
    pub fn diagnostic_failed(&mut self, check: crate::diagnostics::Check, detail: i32) {
        let now = self.clock.now();
        self.fault_event(Cause::Diagnostic, now, (check as u8) << 4, detail);
    }

    /// The record to keep in retained RAM (backup SRAM): the latch in force and the boot count. The
    /// board copies it after every tick and edge; [`Firmware::after_reset`] reads it back.
    pub const fn retained(&self) -> Retained {
        self.retained
    }

    /// The current state.
    pub const fn state(&self) -> State {
        self.state
    }

    /// Armed and watching.
    pub fn is_armed(&self) -> bool {
        self.state == State::Armed
    }

    /// Not in a fault (the start latch after a reset counts as a fault here).
    pub fn is_healthy(&self) -> bool {
        !matches!(self.state, State::Fault(_))
    }

    /// Whether the board may feed its hardware watchdog: only while healthy and armed, or healthy
    /// and stopped (the self-test, a trip, and the start latch after a reset, which waits for a
    /// person and has found nothing wrong). Every latched fault starves it, so the reset that
    /// follows releases the pins to their reset state (inputs: the external pull-downs de-energise
    /// the relays, whatever the port's clock or driver does) and the next start finds the latch in
    /// the backup SRAM. A fault that persists across the reset is found again and resets again:
    /// the part stays stopped, reset every few tens of milliseconds, until it is repaired.
    pub fn feeds_watchdog(&self) -> bool {
        matches!(self.state, State::Armed | State::Tripped | State::SelfTest(_) | State::Fault(Cause::Reset))
    }

    /// The stop output is commanded low (stop requested).
    pub const fn stop_requested(&self) -> bool {
        self.out.stop_requested()
    }

    /// The escalation output is commanded low (category 0 requested).
    pub const fn category0_requested(&self) -> bool {
        self.out.category0_requested()
    }

    /// Instant of the last trip's stop write (the detection timestamp).
    pub const fn detected_at(&self) -> Option<Micros> {
        self.detected_at
    }

    /// The stroke-budget verdict of the last trip.
    pub const fn last_verdict(&self) -> Option<Verdict> {
        self.verdict
    }

    /// The latest tick's sensor sample.
    pub const fn last_sample(&self) -> Sample {
        self.last_sample
    }

    /// The event log.
    pub const fn log(&self) -> &EventLog<LOG> {
        &self.log
    }

    /// The configuration in force.
    pub const fn config(&self) -> &Config {
        &self.cfg
    }

    /// The sensor (for a harness that needs to reach its calibration).
    pub const fn sensor(&self) -> &S {
        &self.sensor
    }
}
