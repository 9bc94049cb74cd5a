//! [`SimRig`]: the firmware wired to simulated pins, a simulated clock and (optionally) a simulated
//! ADC, stepped by the plant. This is the API `flinch hil` uses.
//!
//! Time: the rig maps simulation seconds to the firmware's wrapping microseconds through an epoch
//! fixed by [`SimRig::boot`] (sim time 0 is the end of the self-test). Ticks fall at sim times
//! `phase + k * T` (T = `Config::tick_period_us`, phase set by [`SimRig::set_tick_phase_us`]), so the
//! firmware's tick is not synchronised with the plant's steps or the robot's scan cycle unless asked.
//!
//! Sensor: [`SimRig::set_travel_m`] turns the plant's decoupler travel (back from the front stop,
//! metres) into a switch level (through [`SwitchKind::level_for`] and d_sw) or an ADC value (through
//! [`AnalogConfig::counts_for`]). When the switch input's observed level changes, the rig calls the
//! firmware's edge interrupt at once, as the EXTI line on both edges does on the board.
//!
//! Outputs, as on the board: two stop channels (K1, K2), each driving a relay whose force-guided
//! contacts are in series in the robot's stop circuit, and the category-0 escalation output, each on
//! its own port ([`OutputPort`]). What the robot sees ([`SimRig::stop_requested`]) is the stop
//! circuit: open as soon as either relay has released, and a welded relay never releases.

use crate::fakes::{PinFault, SimAdc, SimClock, SimPin};
use flinch_firmware::{
    AnalogConfig, AnalogTravel, Boot, Cause, ResetCause, Config, ConfigError, DigitalSwitch, DualSwitch, Edm, Firmware, Micros, Mm, Outputs, Sensor, State, SwitchKind,
    TripEvent,
};

/// The board's three output ports (`firmware/README.md`, pin map): one per output.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum OutputPort {
    /// Stop channel K1's port (GPIOD on the board, with the sensor supply).
    K1,
    /// Stop channel K2's port (GPIOE on the board).
    K2,
    /// The escalation output's port (GPIOB on the board).
    Escalation,
}

/// Event-log capacity of the simulated firmware.
pub const SIM_LOG: usize = 32;

#[derive(Clone, Debug)]
enum PlantInput {
    Switch { pin: SimPin, kind: SwitchKind, switch_travel_um: i32 },
    Analog { adc: SimAdc, cfg: AnalogConfig },
    Dual { a: SimPin, kind_a: SwitchKind, b: SimPin, kind_b: SwitchKind, switch_travel_um: i32 },
}

/// Firmware plus its simulated peripherals.
pub struct SimRig<S> {
    /// The firmware under test (read its state, log, verdicts directly if needed).
    pub fw: Firmware<SimClock, S, SimPin, SimPin, SimPin, SimPin, SIM_LOG, Edm<SimPin, SimPin>>,
    /// The clock handle (stall it with [`SimClock::set_stalled`]).
    pub clock: SimClock,
    /// Stop channel 1's output pin, relay K1's coil (low = released). A pin stuck high is
    /// `stop_k1.set_fault(PinFault::StuckHigh)`: the relay stays pulled in, the read-back sees it.
    pub stop_k1: SimPin,
    /// Stop channel 2's output pin, relay K2's coil, on another port.
    pub stop_k2: SimPin,
    /// The escalation output (low = category 0 requested).
    pub escalation: SimPin,
    /// The reset input (drive high for a reset press).
    pub reset: SimPin,
    /// The EDM inputs: the NC mirror contacts of the two stop relays K1, K2 (high = released). The
    /// rig's relays follow their stop channels before every tick; a welded relay is
    /// `k1.set_fault(PinFault::StuckLow)` (never reads released, and its contacts stay closed in the
    /// robot's stop circuit); a cut feedback wire is `StuckHigh` (the relay itself still works).
    pub k1: SimPin,
    /// See [`SimRig::k1`].
    pub k2: SimPin,
    /// The sensor supply output, digital sensors only.
    pub supply: Option<SimPin>,
    input: PlantInput,
    epoch: Micros,
    next_tick_us: i64,
    now_us: i64,
    tick_us: i64,
    phase_us: i64,
    edge_irq: bool,
}

impl SimRig<DigitalSwitch<SimPin, SimPin>> {
    /// A rig with a digital travel switch of `kind` firing at `switch_travel_um` (d_sw), its supply
    /// switchable by the firmware (so the start-up stuck-input test runs), wired so that the unpowered
    /// switch reads as a trip. The plant starts with the tool on the front stop.
    pub fn digital(cfg: Config, kind: SwitchKind, switch_travel_um: i32) -> Result<Self, ConfigError> {
        SimRig::digital_after(cfg, Boot::UNKNOWN, kind, switch_travel_um)
    }

    /// [`SimRig::digital`] starting from the reset described by `boot` (its cause and the retained
    /// record the board would hand over).
    pub fn digital_after(cfg: Config, boot: Boot, kind: SwitchKind, switch_travel_um: i32) -> Result<Self, ConfigError> {
        let supply = SimPin::new(false);
        let pin = SimPin::powered_by(kind.level_for(false), supply.clone(), kind.level_for(true));
        let sensor = DigitalSwitch::with_supply(pin.clone(), supply.clone(), kind, switch_travel_um);
        let mut rig = SimRig::with_sensor(cfg, boot, sensor, PlantInput::Switch { pin, kind, switch_travel_um })?;
        rig.supply = Some(supply);
        Ok(rig)
    }

    /// The MCU resets (`cause`, e.g. the watchdog) at the current instant: the firmware starts again
    /// from the retained record it left, with the same pins and clock (the board's backup-SRAM latch).
    pub fn mcu_reset(&mut self, cause: ResetCause) {
        if let PlantInput::Switch { pin, kind, switch_travel_um } = &self.input {
            let supply = self.supply.clone().unwrap_or_else(|| SimPin::new(true));
            let sensor = DigitalSwitch::with_supply(pin.clone(), supply, *kind, *switch_travel_um);
            self.restart(cause, sensor);
        }
    }

    /// The switch input's pin handle (inject faults with [`SimRig::inject_switch_fault`]).
    pub fn switch_pin(&self) -> Option<&SimPin> {
        match &self.input {
            PlantInput::Switch { pin, .. } => Some(pin),
            PlantInput::Analog { .. } | PlantInput::Dual { .. } => None,
        }
    }
}

impl SimRig<DualSwitch<SimPin, SimPin, SimPin>> {
    /// A rig with a two-channel travel switch (`dual.rs`): channel A of `kind_a`, channel B of
    /// `kind_b` (opposite polarity: antivalent), both firing at `switch_travel_um`, on one switchable
    /// supply, wired so that unpowered channels read as a trip. Starts as [`SimRig::digital_after`].
    pub fn dual_after(
        cfg: Config,
        boot: Boot,
        kind_a: SwitchKind,
        kind_b: SwitchKind,
        switch_travel_um: i32,
        discrepancy_us: u32,
    ) -> Result<Self, ConfigError> {
        let supply = SimPin::new(false);
        let a = SimPin::powered_by(kind_a.level_for(false), supply.clone(), kind_a.level_for(true));
        let b = SimPin::powered_by(kind_b.level_for(false), supply.clone(), kind_b.level_for(true));
        let sensor = DualSwitch::new(a.clone(), kind_a, b.clone(), kind_b, switch_travel_um, discrepancy_us)
            .with_supply(supply.clone());
        let input = PlantInput::Dual { a, kind_a, b, kind_b, switch_travel_um };
        let mut rig = SimRig::with_sensor(cfg, boot, sensor, input)?;
        rig.supply = Some(supply);
        Ok(rig)
    }

    /// The MCU resets: as [`SimRig::mcu_reset`] for the single switch.
    pub fn mcu_reset(&mut self, cause: ResetCause) {
        if let PlantInput::Dual { a, kind_a, b, kind_b, switch_travel_um } = &self.input {
            let supply = self.supply.clone().unwrap_or_else(|| SimPin::new(true));
            let disc = self.fw.sensor().discrepancy_us();
            let sensor =
                DualSwitch::new(a.clone(), *kind_a, b.clone(), *kind_b, *switch_travel_um, disc).with_supply(supply);
            self.restart(cause, sensor);
        }
    }

    /// Channel A's and channel B's pin handles (inject faults with [`SimRig::inject_pin_fault`]).
    pub fn channel_pins(&self) -> Option<(SimPin, SimPin)> {
        match &self.input {
            PlantInput::Dual { a, b, .. } => Some((a.clone(), b.clone())),
            _ => None,
        }
    }
}

impl SimRig<AnalogTravel<SimAdc>> {
    /// A rig with an analog displacement sensor calibrated by `acfg`; the plant starts at travel 0.
    pub fn analog(cfg: Config, acfg: AnalogConfig) -> Result<Self, ConfigError> {
        let adc = SimAdc::new(acfg.counts_for(Mm::ZERO));
        let sensor = AnalogTravel::new(adc.clone(), acfg);
        SimRig::with_sensor(cfg, Boot::UNKNOWN, sensor, PlantInput::Analog { adc, cfg: acfg })
    }

    /// The ADC handle (inject faults with [`SimAdc::set_fault`]).
    pub fn adc(&self) -> Option<&SimAdc> {
        match &self.input {
            PlantInput::Analog { adc, .. } => Some(adc),
            PlantInput::Switch { .. } | PlantInput::Dual { .. } => None,
        }
    }
}

impl<S: Sensor> SimRig<S> {
    fn with_sensor(cfg: Config, boot: Boot, sensor: S, input: PlantInput) -> Result<Self, ConfigError> {
        let clock = SimClock::new(Micros(0));
        // Whatever the pins were: the firmware must drop them at once.
        let (stop_k1, stop_k2, escalation) = (SimPin::new(true), SimPin::new(true), SimPin::new(true));
        let reset = SimPin::new(false);
        let (k1, k2) = (SimPin::new(true), SimPin::new(true));
        let outputs = Outputs { k1: stop_k1.clone(), k2: stop_k2.clone(), escalation: escalation.clone() };
        let fw = Firmware::after_reset(cfg, boot, clock.clone(), sensor, outputs, reset.clone())?
            .with_feedback(Edm::new(k1.clone(), k2.clone()));
        let tick_us = i64::from(cfg.tick_period_us);
        Ok(SimRig {
            fw,
            clock,
            stop_k1,
            stop_k2,
            escalation,
            reset,
            k1,
            k2,
            supply: None,
            input,
            epoch: Micros(0),
            next_tick_us: 0,
            now_us: 0,
            tick_us,
            phase_us: 0,
            edge_irq: true,
        })
    }

    fn restart(&mut self, cause: ResetCause, sensor: S) {
        let boot = Boot { cause, retained: self.fw.retained() };
        let cfg = *self.fw.config();
        let outputs = Outputs { k1: self.stop_k1.clone(), k2: self.stop_k2.clone(), escalation: self.escalation.clone() };
        // A reset releases every pin (they become inputs; the external pull-downs de-energise the
        // relays) and resets the ports: a frozen port works again, a pin stuck high stays high.
        for pin in [&self.stop_k1, &self.stop_k2, &self.escalation] {
            if pin.fault() == PinFault::Frozen {
                pin.set_fault(PinFault::None);
            }
            pin.set(false);
        }
        if let Some(supply) = &self.supply {
            if supply.fault() == PinFault::Frozen {
                supply.set_fault(PinFault::None);
            }
        }
        let reset = self.reset.clone();
        // The configuration was valid when the rig was built, so this cannot fail; if it did, the
        // old firmware would keep running, which the caller sees in the state.
        if let Ok(fw) = Firmware::after_reset(cfg, boot, self.clock.clone(), sensor, outputs, reset) {
            self.fw = fw.with_feedback(Edm::new(self.k1.clone(), self.k2.clone()));
        }
    }

    /// Start the firmware's clock at `start` (before [`SimRig::boot`]); e.g. just before the u32 wrap.
    pub fn start_clock_at(&mut self, start: Micros) {
        self.clock.set(start);
    }

    /// Offset of the firmware's ticks within its period, microseconds in `0..T` (default 0). Set it
    /// before [`SimRig::boot`] returns control to the plant loop, i.e. right after `boot`.
    pub fn set_tick_phase_us(&mut self, phase_us: u32) {
        let phase = i64::from(phase_us).rem_euclid(self.tick_us.max(1));
        // Keep the tick cadence: move the epoch so that the next tick lands at sim time `phase`.
        let next_clock = self.epoch.plus(self.next_tick_us as u32);
        self.phase_us = phase;
        self.epoch = Micros(next_clock.0.wrapping_sub(phase as u32));
        self.next_tick_us = phase;
        self.now_us = 0;
    }

    /// Enable or disable the edge interrupt (disabled: the firmware only polls on its ticks).
    pub fn set_edge_interrupt(&mut self, enabled: bool) {
        self.edge_irq = enabled;
    }

    /// Power the firmware up and tick it from the clock's current value until it arms, at most
    /// `max_us` after the operator's reset. The firmware starts latched (`flinch_firmware::reset`),
    /// so the rig first does what the operator does: presses the reset button for
    /// `Config::reset_press.min_us` (rounded up to whole ticks, after one tick released) and releases it. Returns the time
    /// from the release to arming in microseconds, or the state it got stuck in. Sim time 0 is one
    /// tick after the last boot tick, so the firmware's tick cadence carries on into the plant run.
    pub fn boot(&mut self, max_us: u32) -> Result<u32, State> {
        let mut t = self.clock.true_now();
        if self.fw.state() == State::Fault(Cause::Reset) {
            let tick = self.tick_us.max(1) as u32;
            let press_ticks = self.fw.config().reset_press.min_us.div_ceil(tick);
            // The firmware must see the button released before a press counts (a button held
            // through a reset is not a press): one tick released, then the press.
            self.reset.set(false);
            self.clock.set(t);
            self.relays_follow();
            self.fw.tick();
            t = t.plus(tick);
            self.reset.set(true);
            for _ in 0..press_ticks {
                self.clock.set(t);
                self.relays_follow();
                self.fw.tick();
                t = t.plus(tick);
            }
            self.reset.set(false);
        }
        let start = t;
        let limit = u64::from(max_us) / self.tick_us.max(1) as u64 + 1;
        for _ in 0..limit {
            self.clock.set(t);
            self.relays_follow();
            self.fw.tick();
            if self.fw.is_armed() {
                self.epoch = t.plus(self.tick_us as u32);
                self.next_tick_us = 0;
                self.now_us = 0;
                self.set_tick_phase_us(self.phase_us as u32);
                return Ok(t.since(start));
            }
            t = t.plus(self.tick_us as u32);
        }
        Err(self.fw.state())
    }

    /// The stop relays follow their stop channels (released while the coil's pin is low); faults
    /// injected on [`SimRig::k1`] / [`SimRig::k2`] override what their mirror contacts show.
    fn relays_follow(&mut self) {
        self.k1.set(!self.stop_k1.level());
        self.k2.set(!self.stop_k2.level());
    }

    /// Relay `k` (1 or 2) has released: its coil is de-energised and it is not welded
    /// (`PinFault::StuckLow` on its mirror contact).
    pub fn relay_released(&self, k: u8) -> bool {
        let (coil, mirror) = if k == 1 { (&self.stop_k1, &self.k1) } else { (&self.stop_k2, &self.k2) };
        !coil.level() && mirror.fault() != PinFault::StuckLow
    }

    /// Freeze one output's port (the board's GPIO clock gated or its logic dead: writes lost, reads
    /// low, the pins keep their level). K1's port also carries the sensor supply, as PD12 and PD14
    /// share GPIOD on the board. A reset of the MCU ([`SimRig::mcu_reset`]) unfreezes it.
    pub fn freeze_port(&mut self, port: OutputPort) {
        match port {
            OutputPort::K1 => {
                self.stop_k1.set_fault(PinFault::Frozen);
                if let Some(s) = &self.supply {
                    s.set_fault(PinFault::Frozen);
                }
            }
            OutputPort::K2 => self.stop_k2.set_fault(PinFault::Frozen),
            OutputPort::Escalation => self.escalation.set_fault(PinFault::Frozen),
        }
    }

    /// Convert simulation seconds to the firmware's clock.
    pub fn micros_at(&self, t_s: f64) -> Micros {
        self.epoch.plus((t_s * 1e6).round() as i64 as u32)
    }

    /// Convert a firmware instant to simulation seconds (exact within +-35 min of sim time 0).
    pub fn seconds_at(&self, m: Micros) -> f64 {
        f64::from(self.sim_us_at(m)) / 1e6
    }

    /// Convert a firmware instant to integer microseconds of simulation time (exact within +-35 min).
    pub fn sim_us_at(&self, m: Micros) -> i32 {
        m.since(self.epoch) as i32
    }

    /// Run the firmware's ticks that fall at or before sim time `t_s`, then set the clock to `t_s`,
    /// rounded to the nearest whole microsecond: for instants that are whole microseconds (ticks,
    /// scheduled times) up to the rounding of the sums that make them. An event between two whole
    /// microseconds (a switch edge the plant located) goes through [`SimRig::advance_to_event`].
    /// The sensor holds the level last set (zero-order hold between plant steps).
    pub fn advance_to(&mut self, t_s: f64) {
        self.advance_to_us((t_s * 1e6).round() as i64);
    }

    /// [`SimRig::advance_to`] for an event at `t_s` that falls between whole microseconds (a switch
    /// edge, a fault): the firmware's clock is set to the first whole microsecond at or after it,
    /// so a timestamp the firmware takes of the event is never before the event. Rounding to the
    /// nearest (what [`SimRig::advance_to`] does) put it up to 0.5 us before: `flinch hil` reported
    /// a negative firmware latency (-35 to -482 ns) on most shipped scenes.
    /// Ticks due strictly after `t_s` (at that first whole microsecond, when the event fell
    /// inside it) are left for the next advance: they come after the event, and read what it did.
    pub fn advance_to_event(&mut self, t_s: f64) {
        let us = first_us_at_or_after(t_s);
        let on_the_us = us as f64 / 1e6 == t_s;
        self.advance_to_us(if on_the_us { us } else { us - 1 });
        self.now_us = us.max(self.now_us);
        self.clock.set(self.epoch.plus(self.now_us as u32));
    }

    /// [`SimRig::advance_to`] in integer microseconds of sim time.
    pub fn advance_to_us(&mut self, t_us: i64) {
        while self.next_tick_us <= t_us {
            self.clock.set(self.epoch.plus(self.next_tick_us as u32));
            self.relays_follow();
            self.fw.tick();
            self.next_tick_us += self.tick_us;
        }
        self.now_us = t_us.max(self.now_us);
        self.clock.set(self.epoch.plus(self.now_us as u32));
    }

    /// Skip the firmware's ticks up to sim time `t_s` without running them (a blocked firmware:
    /// the missed-deadline fault).
    pub fn skip_ticks_until(&mut self, t_s: f64) {
        let t_us = (t_s * 1e6).round() as i64;
        while self.next_tick_us <= t_us {
            self.next_tick_us += self.tick_us;
        }
    }

    /// Hand the plant's decoupler travel (metres back from the front end-stop) to the sensor.
    pub fn set_travel_m(&mut self, travel_m: f64) {
        let um = (travel_m * 1e6).round().clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32;
        self.set_travel_um(um);
    }

    /// [`SimRig::set_travel_m`] in micrometres.
    pub fn set_travel_um(&mut self, travel_um: i32) {
        match &self.input {
            PlantInput::Switch { pin, kind, switch_travel_um } => {
                let before = pin.level();
                pin.set(kind.level_for(travel_um >= *switch_travel_um));
                let changed = pin.level() != before;
                self.edge_if(changed);
            }
            PlantInput::Analog { adc, cfg } => {
                let mm = Mm::saturating_from_num(travel_um) / 1000;
                adc.set(cfg.counts_for(mm));
            }
            PlantInput::Dual { a, kind_a, b, kind_b, switch_travel_um } => {
                let before = (a.level(), b.level());
                let tripped = travel_um >= *switch_travel_um;
                a.set(kind_a.level_for(tripped));
                b.set(kind_b.level_for(tripped));
                let changed = (a.level(), b.level()) != before;
                self.edge_if(changed);
            }
        }
    }

    /// Inject a fault into any input pin of the rig (a channel of the switch); an observed level
    /// change fires the edge interrupt, as EXTI on both edges of both channels does.
    pub fn inject_pin_fault(&mut self, pin: &SimPin, fault: PinFault) {
        let before = pin.level();
        pin.set_fault(fault);
        let changed = pin.level() != before;
        self.edge_if(changed);
    }

    /// Inject a fault into the switch input; an observed level change fires the edge interrupt.
    pub fn inject_switch_fault(&mut self, fault: PinFault) {
        if let PlantInput::Switch { pin, .. } = &self.input {
            let before = pin.level();
            pin.set_fault(fault);
            let changed = pin.level() != before;
            self.edge_if(changed);
        }
    }

    fn edge_if(&mut self, changed: bool) {
        if changed && self.edge_irq {
            self.fw.on_edge();
        }
    }

    /// Drive the reset input (a press is a low-to-high change seen by a tick).
    pub fn set_reset(&mut self, level: bool) {
        self.reset.set(level);
    }

    /// The robot's stop circuit is open: relay K1 or K2 has released (a welded one never does).
    pub fn stop_requested(&self) -> bool {
        self.relay_released(1) || self.relay_released(2)
    }

    /// The escalation output reads low: category 0 requested.
    pub fn category0_requested(&self) -> bool {
        !self.escalation.level()
    }

    /// Sim time of the last trip's stop write, seconds.
    pub fn detected_at_s(&self) -> Option<f64> {
        self.fw.detected_at().map(|m| self.seconds_at(m))
    }

    /// Sim time of the last trip's stop write, integer microseconds.
    pub fn detected_at_us(&self) -> Option<i32> {
        self.fw.detected_at().map(|m| self.sim_us_at(m))
    }

    /// The event log, oldest first.
    pub fn events(&self) -> Vec<TripEvent> {
        self.fw.log().iter().copied().collect()
    }

    /// The event log in its serialised form (see `flinch_firmware::event_log`).
    pub fn event_log_bytes(&self) -> Vec<u8> {
        let mut buf = vec![0u8; self.fw.log().serialized_len()];
        // The buffer is sized from the log itself, so this cannot fail.
        let n = self.fw.log().serialize(&mut buf).unwrap_or(0);
        buf.truncate(n);
        buf
    }

    /// Current sim time of the rig, microseconds.
    pub fn now_us(&self) -> i64 {
        self.now_us
    }
}

/// The first whole microsecond of sim time whose instant, as [`SimRig::seconds_at`] gives it, is
/// at or after `t_s`: where the firmware's clock can first read an event between two microseconds.
pub fn first_us_at_or_after(t_s: f64) -> i64 {
    let secs = |us: i64| us as f64 / 1e6;
    let mut us = (t_s * 1e6).ceil() as i64;
    // The product and the quotient round by an ulp at most: a step or two settles it.
    for _ in 0..4 {
        if secs(us) < t_s {
            us = us.saturating_add(1);
        } else if secs(us.saturating_sub(1)) >= t_s {
            us = us.saturating_sub(1);
        }
    }
    us
}
