//! The cell the board ships for: one constant, [`BOARD_CELL`], that the board binary runs
//! ([`board_config`]) and the step's instruction count (`avoid-cost`) measures. It is what the
//! host's `flinch avoid --mcu` builds from the cell's scene (`flinch_avoid::board_engine::
//! link_config`, the one function that makes both): a host test (`tests/avoid_board.rs`) loads the
//! scene named in [`BOARD_CELL_SCENE`], resolves its PFL speeds as `flinch avoid` does and refuses
//! any difference, so the board never runs a second copy of the settings. For another cell: change
//! the scene, run that test with `FLINCH_BLESS=1` to print the new constant, paste it here.
//!
//! The PFL speeds (ISO/TS 15066 5.5.5) travel with their provenance ([`BOARD_PFL`]): the module
//! scene and its SHA-256, the body regions, and the region and force limit that set each speed.

use super::control::{Gains, Repulsion, Watchdog};
use super::link::LinkConfig;
use super::num::BoardReal;
use super::safe::{Pfl, SsmParams, Steer};

/// The avoidance scene the board's constant is made from (relative to the repository).
pub const BOARD_CELL_SCENE: &str = "scenes/avoid_board_cell.toml";

/// Where the PFL speeds of [`BOARD_CELL`] come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PflProvenance {
    /// The module scene (`[avoid.pfl] module`).
    pub module: &'static str,
    /// SHA-256 of its text, hex.
    pub module_sha256: &'static str,
    /// The body regions the cell allows to be touched.
    pub body_regions: &'static str,
    /// The region that set the speed along the module's axis.
    pub along_region: &'static str,
    /// Its force limit (ISO/TS 15066 Table A.2), N, in whole newtons.
    pub along_force_limit_n: u32,
    /// The region that set the speed across it (a rigid tool's).
    pub across_region: &'static str,
    /// "transient" or "quasi_static".
    pub contact: &'static str,
}

// BLESSED-BEGIN (tests/avoid_board.rs writes what is between these lines)
/// The board's cell settings, in `f64` (converted once at start-up).
pub const BOARD_CELL: LinkConfig<f64> = LinkConfig {
    gains: Gains { repulsion: Repulsion::Vortex { sign: 0 }, k_att: 0.25, k_rep: 0.6, capture_radius_m: 0.03, latch_height_m: 0.02, slow_height_m: 0.05, stop_height_m: 0.3, bounded: true },
    watchdog: Watchdog { slow_after_ms: 467, stop_after_ms: 1167 },
    start_m: [0.12, 0.5],
    goal_m: [0.93, 0.5],
    speed_cap_mps: 0.25,
    period_ms: 10,
    max_age_ms: 387,
    byte_timeout_ms: 20,
    budget_bytes: 256,
    ssm: Some(SsmParams {
        human_speed_mps: 1.6,
        reaction_time_s: 0.02,
        stopping_time_s: 0.1,
        margin_m: 0.035,
        speed_cap_mps: 0.25,
        whole_body_only: false,
        pfl: Some(Pfl { axis: [1.0, 0.0], along_mps: 0.2870589814356875, across_mps: 0.06344319576379467 }),
    }),
    steer: Some(Steer { barrier_m: 0.02, band_m: 0.05, view_m: [0.0, 0.0, 1.05, 1.05], edge_margin_m: 0.045 }),
    fixture_barrier_m: None,
};

/// The provenance of [`BOARD_CELL`]'s PFL speeds.
pub const BOARD_PFL: PflProvenance = PflProvenance {
    module: "body_hand.toml",
    module_sha256: "78069422089ed49b1ba07b7c2206e4f9a7b564ed742e043a3f901c1d9b35ff82",
    body_regions: "hand, lower_arm",
    along_region: "lower_arm",
    along_force_limit_n: 160,
    across_region: "hand",
    contact: "quasi_static",
};
// BLESSED-END

// The board's step timer runs at the library's period.
const _: () = assert!(BOARD_CELL.period_ms == super::link::BOARD_PERIOD_MS);

/// The board's settings in its number type.
pub fn board_config() -> LinkConfig<BoardReal> {
    BOARD_CELL.to_real::<BoardReal>()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_board_runs_the_monitor_with_pfl() {
        let c = board_config();
        let ssm = c.ssm.expect("the board ships the speed and separation monitor");
        let pfl = ssm.pfl.expect("and the PFL speeds of its module");
        assert!(pfl.along_mps > 0.0 && pfl.across_mps > 0.0 && pfl.across_mps <= pfl.along_mps);
        assert!(c.steer.is_some() && c.gains.bounded);
        assert!(!BOARD_PFL.module_sha256.is_empty() && BOARD_PFL.along_force_limit_n > 0);
        let _ = (SsmParams::<f64> { ..BOARD_CELL.ssm.unwrap() }, Steer::<f64> { ..BOARD_CELL.steer.unwrap() }, Pfl::<f64> { ..pfl_f64() });
    }

    fn pfl_f64() -> Pfl<f64> {
        BOARD_CELL.ssm.and_then(|s| s.pfl).unwrap()
    }
}
