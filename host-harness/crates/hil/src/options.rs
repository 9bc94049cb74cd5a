//! The options of a firmware-in-the-loop run (`flinch hil`): the faults to inject and their
//! instants, the glitch filter, the reset policy, the channels; parsed from the command line's
//! words, each refusal saying what is allowed.

use flinch_firmware::{Filter, ResetPolicy};
use flinch_hal_sim::{OutputFault, OutputPort};
pub use flinch_model::scene::whole_us;

pub(crate) fn um(x: f64) -> u32 {
    (x * 1e6).round().clamp(0.0, u32::MAX as f64) as u32
}


/// A fault `flinch hil --fault` can inject, and what it does to the simulated hardware.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FaultKind {
    /// The switch input (channel A of a two-channel switch) sticks at its "tool at rest" level.
    StuckRest,
    /// The switch input (channel A) sticks at its "tripped" level.
    StuckTrip,
    /// The switch input's wire (channel A) is cut: it reads its pull-down level.
    CutWire,
    /// Channel B of a two-channel switch sticks at rest (refused with one channel).
    StuckRestB,
    /// Stop relay K1's contacts weld: its mirror contact never reads "released" again.
    WeldedOutput,
    /// K1's feedback wire breaks towards "released" (reads released while pulled in).
    EdmWireCut,
    /// The firmware's clock stops.
    ClockStall,
    /// The MCU resets (as the watchdog does); the firmware restarts from its retained latch.
    Reset,
    /// An output fault of the board (issue 25): a stuck stop pin, a frozen port, welded relays
    /// (`hal_sim::OutputFault`).
    Output(OutputFault),
}

impl FaultKind {
    /// The output fault, if this is one.
    pub fn output(self) -> Option<OutputFault> {
        match self {
            FaultKind::Output(f) => Some(f),
            _ => None,
        }
    }
}

/// Every fault name `--fault` accepts, with what it does.
pub const FAULTS: &[(&str, FaultKind, &str)] = &[
    ("stuck-rest", FaultKind::StuckRest, "switch (channel A) stuck at the at-rest level"),
    ("stuck-trip", FaultKind::StuckTrip, "switch (channel A) stuck at the tripped level"),
    ("cut-wire", FaultKind::CutWire, "switch wire (channel A) cut"),
    ("stuck-rest-b", FaultKind::StuckRestB, "channel B of a two-channel switch stuck at rest (--channels 2)"),
    ("welded-output", FaultKind::WeldedOutput, "stop relay K1 welded (EDM never reads released)"),
    ("edm-wire-cut", FaultKind::EdmWireCut, "K1's feedback wire reads released while pulled in"),
    ("clock-stall", FaultKind::ClockStall, "the firmware's clock stops"),
    ("reset", FaultKind::Reset, "the MCU resets (watchdog); restart from the retained latch"),
    ("stuck-stop-pin", FaultKind::Output(OutputFault::StuckStopPin), "stop channel K1's pin stuck high (relay K1 stays pulled in)"),
    ("frozen-port-k1", FaultKind::Output(OutputFault::FrozenPort(OutputPort::K1)), "K1's GPIO port frozen (clock gated: writes lost, reads 0)"),
    ("frozen-port-k2", FaultKind::Output(OutputFault::FrozenPort(OutputPort::K2)), "K2's GPIO port frozen"),
    ("frozen-port-escalation", FaultKind::Output(OutputFault::FrozenPort(OutputPort::Escalation)), "the category-0 escalation's GPIO port frozen"),
    ("welded-k2", FaultKind::Output(OutputFault::WeldedK2), "stop relay K2 welded"),
    ("welded-k1-k2", FaultKind::Output(OutputFault::WeldedK1K2), "both stop relays welded: only category 0 (drive power) remains"),
];

/// The name `--fault` spells `kind` with.
pub fn fault_name(kind: FaultKind) -> &'static str {
    FAULTS.iter().find(|(_, k, _)| *k == kind).map_or("?", |(n, _, _)| *n)
}

/// One fault to inject at `at_s` seconds of simulation time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Injection {
    /// What.
    pub kind: FaultKind,
    /// When, s.
    pub at_s: f64,
}

/// Parse `--fault NAME@T[,NAME@T...]`; the error says what is allowed.
pub fn parse_faults(spec: &str) -> Result<Vec<Injection>, String> {
    let names = FAULTS.iter().map(|(n, _, _)| *n).collect::<Vec<_>>().join(", ");
    let mut out = Vec::new();
    for item in spec.split(',').map(str::trim).filter(|i| !i.is_empty()) {
        let (name, at) = item.split_once('@').ok_or_else(|| format!("--fault: NAME@SECONDS (names: {names}), got {item:?}"))?;
        let kind = FAULTS.iter().find(|(n, _, _)| *n == name).map(|(_, k, _)| *k).ok_or_else(|| format!("--fault: one of {names}, got {name:?}"))?;
        let at_s: f64 = at.parse().map_err(|_| format!("--fault {name}: a time in seconds >= 0 after @, got {at:?}"))?;
        if !(at_s.is_finite() && at_s >= 0.0) {
            return Err(format!("--fault {name}: a time in seconds >= 0 after @, got {at:?}"));
        }
        out.push(Injection { kind, at_s });
    }
    out.sort_by(|a, b| a.at_s.total_cmp(&b.at_s));
    Ok(out)
}

/// Options of a firmware-in-the-loop run beyond the controller.
#[derive(Debug, Clone)]
pub struct HilOptions {
    /// Faults to inject.
    pub faults: Vec<Injection>,
    /// Two-channel (antivalent) travel switch instead of one channel.
    pub two_channels: bool,
    /// The firmware's glitch filter (`Config::filter`; default none: the edge stops directly).
    pub filter: Filter,
    /// How a trip is cleared (`Config::reset`; default a reset input, never pressed in the run).
    pub reset: ResetPolicy,
    /// The controller's worst phase (`--worst-phase`): the sample before the stop output just
    /// missed it, so the stop is seen a whole scan cycle after the output (Ch. 3.1.2); the
    /// controller's `phase` is then unused.
    pub worst_phase: bool,
}

impl Default for HilOptions {
    fn default() -> Self {
        Self { faults: Vec::new(), two_channels: false, filter: Filter::None, reset: ResetPolicy::Input, worst_phase: false }
    }
}

/// Parse `--filter`: `none`, `consecutive:N` (N tick samples, 1..=255) or `min-duration:S`
/// (seconds, whole microseconds up to 1 s).
pub fn parse_filter(spec: &str) -> Result<Filter, String> {
    let allowed = "none, consecutive:N (1 to 255 tick samples) or min-duration:SECONDS (1e-6 to 1 s)";
    match spec.split_once(':') {
        None if spec == "none" => Ok(Filter::None),
        Some(("consecutive", n)) => match n.parse::<u8>() {
            Ok(n) if n >= 1 => Ok(Filter::Consecutive(n)),
            _ => Err(format!("--filter consecutive:N: N from 1 to 255, got {n:?}")),
        },
        Some(("min-duration", s)) => match s.parse::<f64>() {
            Ok(x) if (1e-6..=1.0).contains(&x) && whole_us(x) => Ok(Filter::MinDuration(um(x))),
            _ => Err(format!("--filter min-duration:SECONDS: 1e-6 to 1 s in whole microseconds, got {s:?}")),
        },
        _ => Err(format!("--filter: one of {allowed}, got {spec:?}")),
    }
}

/// Parse `--reset-policy`: `input` (a reset press; none comes during a run, so a trip stays
/// latched) or `auto:S` (cleared once the tool has been back on its front stop for S seconds).
pub fn parse_reset_policy(spec: &str) -> Result<ResetPolicy, String> {
    match spec.split_once(':') {
        None if spec == "input" => Ok(ResetPolicy::Input),
        Some(("auto", s)) => match s.parse::<f64>() {
            Ok(x) if (1e-6..=10.0).contains(&x) && whole_us(x) => Ok(ResetPolicy::Auto { hold_us: um(x) }),
            _ => Err(format!("--reset-policy auto:SECONDS: 1e-6 to 10 s in whole microseconds, got {s:?}")),
        },
        _ => Err(format!("--reset-policy: input, or auto:SECONDS (back on the front stop that long), got {spec:?}")),
    }
}

pub(crate) fn describe_filter(f: Filter) -> String {
    match f {
        Filter::None => "none".into(),
        Filter::Consecutive(n) => format!("consecutive:{n}"),
        Filter::MinDuration(us) => format!("min-duration:{}", us as f64 / 1e6),
    }
}

pub(crate) fn describe_reset(r: ResetPolicy) -> String {
    match r {
        ResetPolicy::Input => "input".into(),
        ResetPolicy::Auto { hold_us } => format!("auto:{}", hold_us as f64 / 1e6),
    }
}

/// Discrepancy time of the two-channel switch in `flinch hil --channels 2`, us: 20 ms.
pub const DISCREPANCY_US: u32 = 20_000;
