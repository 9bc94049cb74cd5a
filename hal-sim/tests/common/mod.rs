//! What the hal-sim integration tests share: the 1 kHz tick, the Tables 5-7 budget, a booted rig.
#![allow(dead_code)] // each test binary uses its own subset

use flinch_firmware::{BudgetConfig, Config, SwitchKind};
use flinch_hal_sim::SimRig;

pub const T: u32 = 1_000; // 1 kHz tick

/// Tables 5-7: V_c = 0.05 m/s, DT = 16 ms; d = 1 m/s^2 and C = 10 mm chosen for the tests:
/// s_stop = 0.8 + 1.25 = 2.05 mm, which fits in the 5 mm left after a 5 mm d_sw.
pub fn budget() -> BudgetConfig {
    BudgetConfig { robot_speed_um_per_s: 50_000, dead_time_us: 16_000, decel_um_per_s2: 1_000_000, stroke_um: 10_000 }
}

pub fn cfg() -> Config {
    Config::new(T, budget())
}

pub fn booted(cfg: Config) -> SimRig<flinch_firmware::DigitalSwitch<flinch_hal_sim::SimPin, flinch_hal_sim::SimPin>> {
    let mut rig = SimRig::digital(cfg, SwitchKind::Inductive, 5_000).unwrap();
    rig.boot(50_000).unwrap();
    rig
}
