//! Stateful `embedded-hal` 1.0 fakes driven by the plant simulation, and [`SimRig`], the firmware
//! wired to them for `flinch hil`.
//!
//! These are not expectation mocks (embedded-hal-mock): nothing is scripted in advance. A [`SimPin`]
//! holds a level that whoever holds a handle can set or read, a [`SimClock`] holds the simulation time,
//! a [`SimAdc`] holds the raw value the plant's travel maps to. Handles are `Clone` and share state
//! (`Arc` + atomics, so they are `Send + Sync` and a rig can move to a worker thread), so the harness
//! and the firmware see the same pin. Each fake can be given a fault: a pin stuck low or high, a cut
//! wire, a read error; a clock that stalls; an ADC that reads its rail or fails.
//!
//! # `flinch hil` in five calls
//!
//! ```
//! use flinch_firmware::{BudgetConfig, Config, ResetPolicy, SwitchKind, Cause};
//! use flinch_hal_sim::SimRig;
//!
//! // Tables 5-7: V_c = 0.05 m/s, DT = 16 ms; d = 1 m/s^2 and C = 10 mm chosen for the example.
//! let budget = BudgetConfig { robot_speed_um_per_s: 50_000, dead_time_us: 16_000,
//!                             decel_um_per_s2: 1_000_000, stroke_um: 10_000 };
//! let mut cfg = Config::new(1_000, budget); // 1 kHz tick
//! cfg.reset = ResetPolicy::Auto { hold_us: 100_000 };
//! let mut rig = SimRig::digital(cfg, SwitchKind::Inductive, 5_000).unwrap(); // d_sw = 5 mm
//! rig.boot(100_000).unwrap();             // self-test passes, armed; sim time 0 starts here
//!
//! // Plant loop: advance the firmware to the plant's time, then hand it the plant's travel.
//! let dt = 1e-5;
//! for k in 0..6_000 {
//!     let t = k as f64 * dt;
//!     rig.advance_to(t);
//!     let travel_m = if t < 0.003 { 0.0 } else { (t - 0.003) * 0.05 * 2.0 }; // contact at 3 ms
//!     rig.set_travel_m(travel_m);
//!     // A robot controller model samples these once per scan cycle:
//!     let _ = (rig.stop_requested(), rig.category0_requested());
//! }
//! // 5 mm at 0.1 m/s after 3 ms: the edge at 53 ms, stop written in the same call.
//! let t_detect = rig.detected_at_s().unwrap();
//! assert!((t_detect - 0.053).abs() < 2e-5, "{t_detect}");
//! assert!(rig.stop_requested() && !rig.category0_requested());
//! assert_eq!(rig.events()[0].cause, Cause::Reset); // the start, latched until the reset press
//! assert_eq!(rig.events()[1].cause, Cause::Trip);
//! ```

pub mod latency;
pub mod output_faults;
mod fakes;
mod rig;
pub use output_faults::OutputFault;
pub use rig::{first_us_at_or_after, OutputPort, SimRig, SIM_LOG};
pub mod serial;
pub use fakes::{PinFault, SimPinError, SimPin, SimClock, AdcFault, SimAdc, SimAdcError};
