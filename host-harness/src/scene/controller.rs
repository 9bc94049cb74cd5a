//! `[controller]`: the robot controller of firmware-in-the-loop runs (`flinch hil`, `hil.rs`):
//! inputs sampled once per scan cycle, the firmware ticking at its own period.
use super::check::{Bound::*, Ctx, Key, Tab, Ty};
use super::model::Controller;

/// The `[controller]` table in the top level.
pub const TABLE: Key = Key::of(
    "controller",
    Ty::Table("the robot controller for `flinch hil`"),
    "the robot controller for firmware-in-the-loop runs",
)
.optional("a plain run; `flinch hil` takes --scan-cycle and --tick instead");

/// Scan cycle.
pub const SCAN_CYCLE: Key = Key::number("scan_cycle", "s", Incl(1e-5), Incl(0.1), "robot controller cycles: 10 us to 100 ms (safety PLCs scan in 1-20 ms)", "the robot controller's scan cycle: inputs are sampled once per cycle");
/// Phase of the first sample.
pub const PHASE: Key = Key::number("phase", "of a scan cycle", Incl(0.0), Excl(1.0), "a phase is a fraction of one cycle", "phase of the first sample within a scan cycle");
/// Firmware tick.
pub const FIRMWARE_TICK: Key = Key::number("firmware_tick", "s", Incl(1e-6), Incl(0.01), "the firmware ticks at 1 us to 10 ms", "the firmware's tick period");

/// The keys of `[controller]`.
pub const KEYS: &[Key] = &[SCAN_CYCLE, PHASE, FIRMWARE_TICK];

/// Reads `[controller]`.
pub(super) fn controller(cx: &mut Ctx, t: &Tab) -> Option<Controller> {
    cx.check_keys(t, KEYS, "");
    let scan_cycle = cx.number(t, &SCAN_CYCLE);
    let phase = cx.number(t, &PHASE);
    let firmware_tick = cx.number(t, &FIRMWARE_TICK);
    Some(Controller {
        scan_cycle: scan_cycle?,
        phase: phase?,
        firmware_tick: firmware_tick?,
    })
}
