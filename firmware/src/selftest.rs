//! Start-up self-test: the input must follow the sensor supply, then show the tool at rest.
//!
//! A travel switch stuck at "tool on the front stop" (for the inductive switch: stuck high) would never
//! trip, and nothing at run time can tell it from a quiet robot. So before arming, with the stop output
//! de-energised, the firmware switches the sensor's supply off and requires the input to read a trip
//! within `supply_off_settle_us` (wiring rule: the unpowered sensor reads as a trip, which the inductive
//! switch does by construction). If it does not, the input is stuck: latched fault
//! ([`Cause::StuckInput`]). Then it powers the sensor and waits until the input has shown "not tripped"
//! continuously for `rest_quiet_us`; only then does it arm. A stuck-at-trip input (cut wire) simply
//! never arms: the robot stays stopped, which is the safe outcome, and `Firmware::state` says why.
//!
//! A sensor without a switchable supply skips the first phase: for it a stuck-at-rest input is not
//! detectable at start-up, which the crate docs state as a limit.

use crate::clock::Micros;
use crate::event_log::Cause;

/// Self-test timing.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct SelfTestConfig {
    /// Time the input has, after the supply is switched off, to read a trip, microseconds.
    pub supply_off_settle_us: u32,
    /// Time the input must read "not tripped" continuously before the firmware arms, microseconds.
    pub rest_quiet_us: u32,
}

/// Where the self-test is.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Phase {
    /// Not started (the first tick starts it).
    Start,
    /// Supply off since the instant given; waiting for the input to read a trip.
    SupplyOff(Micros),
    /// Supply on; waiting for the input to read "not tripped" continuously (since the instant given).
    WaitRest(Option<Micros>),
}

/// What the self-test asks of the firmware after a step.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Step {
    /// Keep going; `Some(on)` asks to switch the supply.
    Continue(Option<bool>),
    /// Passed: arm.
    Arm,
    /// Failed.
    Fail(Cause),
}

/// Advance the self-test by one tick. `trip` is the sensor's reading now; `has_supply` whether the
/// sensor's supply can be switched.
pub fn step(phase: &mut Phase, cfg: &SelfTestConfig, now: Micros, trip: bool, has_supply: bool) -> Step {
    match *phase {
        Phase::Start => {
            if has_supply {
                *phase = Phase::SupplyOff(now);
                Step::Continue(Some(false))
            } else {
                *phase = Phase::WaitRest(None);
                step(phase, cfg, now, trip, has_supply)
            }
        }
        Phase::SupplyOff(since) => {
            if trip {
                *phase = Phase::WaitRest(None);
                Step::Continue(Some(true))
            } else if now.since(since) >= cfg.supply_off_settle_us {
                Step::Fail(Cause::StuckInput)
            } else {
                Step::Continue(None)
            }
        }
        Phase::WaitRest(since) => {
            if trip {
                *phase = Phase::WaitRest(None);
                return Step::Continue(None);
            }
            let since = since.unwrap_or(now);
            *phase = Phase::WaitRest(Some(since));
            if now.since(since) >= cfg.rest_quiet_us {
                Step::Arm
            } else {
                Step::Continue(None)
            }
        }
    }
}
