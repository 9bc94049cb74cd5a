//! The output side's faults (issue 25) as fakes a test or `flinch hil` injects into a [`SimRig`],
//! and how long each one lets the robot run after a demand before the cell is safe.
//!
//! The board has two stop channels (K1, K2: two relays whose contacts are in series in the robot's
//! stop circuit) and a category-0 escalation output, each on its own GPIO port, each read back at its
//! pin and each relay at its contacts (EDM). What a fault costs from the demand (a trip) to a safe
//! state (the stop circuit open, or drive power off):
//!
//! | fault | what happens | extra time |
//! |---|---|---|
//! | [`OutputFault::StuckStopPin`]: K1's pin stuck high | K2 releases in the same edge handler; the read-back latches `OutputReadBack` at the next tick | none |
//! | [`OutputFault::FrozenPort`]: a port's clock gated | the other channel stops; the read-back latches within two ticks of the freeze while armed (before any demand) | none |
//! | [`OutputFault::WeldedK2`] | K1 releases; EDM latches after the settle time | none |
//! | [`OutputFault::WeldedK1K2`] | nothing in the stop circuit opens; EDM latches after the settle time and drops the escalation: category 0 | `edm_settle_us` + two ticks ([`extra_dead_time_us`]), plus the board's tick-to-output ([`crate::latency::tick_to_output_s`]) |
//!
//! Each then starves the watchdog (`Firmware::feeds_watchdog`), so the part resets and every pin is
//! released ([`SimRig::mcu_reset`] models that reset).

use crate::rig::{OutputPort, SimRig};
use crate::fakes::PinFault;
use flinch_firmware::{Config, Sensor};

/// An output fault of the board.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum OutputFault {
    /// Stop channel K1's pin (or its driver) stuck high: relay K1 stays pulled in.
    StuckStopPin,
    /// A port frozen (its GPIO clock gated): its output keeps its level, writes are lost, reads 0.
    FrozenPort(OutputPort),
    /// Relay K2 welded: its contacts stay closed, its mirror contact never reads released.
    WeldedK2,
    /// Both relays welded: the stop circuit cannot open; only category 0 (drive power) remains.
    WeldedK1K2,
}

impl OutputFault {
    /// Every output fault (the frozen port of each output).
    pub const ALL: [OutputFault; 6] = [
        OutputFault::StuckStopPin,
        OutputFault::FrozenPort(OutputPort::K1),
        OutputFault::FrozenPort(OutputPort::K2),
        OutputFault::FrozenPort(OutputPort::Escalation),
        OutputFault::WeldedK2,
        OutputFault::WeldedK1K2,
    ];

    /// A short name, as `flinch hil --fault` spells it.
    pub const fn name(self) -> &'static str {
        match self {
            OutputFault::StuckStopPin => "stuck-stop-pin",
            OutputFault::FrozenPort(OutputPort::K1) => "frozen-port-k1",
            OutputFault::FrozenPort(OutputPort::K2) => "frozen-port-k2",
            OutputFault::FrozenPort(OutputPort::Escalation) => "frozen-port-escalation",
            OutputFault::WeldedK2 => "welded-k2",
            OutputFault::WeldedK1K2 => "welded-k1-k2",
        }
    }
}

/// How much later than with healthy outputs the cell is safe after a demand, in the firmware's
/// microseconds: 0 when one stop channel still opens the stop circuit; for both relays welded, the
/// EDM settle time and up to two ticks (the first tick that reads the relays comes up to one tick
/// after the demand, and the mismatch must last longer than the settle time, so it latches on the
/// tick after that). The board's tick-to-output (`latency::tick_to_output_s`) comes on top.
pub fn extra_dead_time_us(cfg: &Config, fault: OutputFault) -> u32 {
    match fault {
        OutputFault::WeldedK1K2 => cfg.edm_settle_us.saturating_add(cfg.tick_period_us.saturating_mul(2)),
        _ => 0,
    }
}

impl<S: Sensor> SimRig<S> {
    /// Inject `fault` now. A stuck pin or a frozen port is seen by the firmware's next ticks (no
    /// edge interrupt: nothing on the inputs changed).
    pub fn inject_output_fault(&mut self, fault: OutputFault) {
        match fault {
            OutputFault::StuckStopPin => self.stop_k1.set_fault(PinFault::StuckHigh),
            OutputFault::FrozenPort(port) => self.freeze_port(port),
            OutputFault::WeldedK2 => self.k2.set_fault(PinFault::StuckLow),
            OutputFault::WeldedK1K2 => {
                self.k1.set_fault(PinFault::StuckLow);
                self.k2.set_fault(PinFault::StuckLow);
            }
        }
    }
}
