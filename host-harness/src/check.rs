//! `flinch check`: does the decoupler's stroke absorb the robot's stopping distance?
//!
//! After detection the flange keeps closing on the obstacle for `v DT + v^2 / (2 d)` (the
//! firmware's own formula, `flinch_firmware::stopping_distance_um`, so the MCU and this check agree
//! to the micrometre), while the stroke left is `C - d_sw`. The simulation then confirms it: the
//! largest travel it reaches and whether the flange reached the target.

use crate::scene::{Decoupler, Scene, Sensor};
use crate::sim::{self, Summary};
use flinch_firmware::stopping_distance_um;
use serde::Serialize;

/// Micro-units rounded up: for what lengthens the stopping distance (speed, dead time), so the
/// integer budget never under-estimates it.
pub(crate) fn um_up(x: f64) -> u32 {
    (x * 1e6).ceil().clamp(0.0, u32::MAX as f64) as u32
}

/// Micro-units rounded down: for what shortens it or bounds it (deceleration, stroke).
pub(crate) fn um_down(x: f64) -> u32 {
    (x * 1e6).floor().clamp(0.0, u32::MAX as f64) as u32
}

/// The budget and its confirmation.
#[derive(Debug, Clone, Serialize)]
pub struct BudgetCheck {
    /// Stopping distance after detection, m (firmware formula, rounded up to the micrometre).
    pub stopping_distance: f64,
    /// Total stroke C (front stop to back stop), m.
    pub stroke: f64,
    /// Switch travel d_sw, m.
    pub switch_travel: f64,
    /// Stroke left at detection, C - d_sw, m.
    pub remaining: f64,
    /// remaining - stopping_distance, m (negative: does not fit).
    pub margin: f64,
    /// The budget holds.
    pub fits: bool,
    /// The simulation of the same scene.
    pub simulated: Summary,
}

/// Checks a scene with a travel switch on a bi-stable or hydraulic decoupler.
pub fn check(scene: &Scene) -> Result<BudgetCheck, String> {
    let stroke = match &scene.decoupler {
        Decoupler::Bistable(b) => b.front_stroke + b.back_stroke,
        Decoupler::Hydraulic(h) => h.stroke,
        _ => return Err("decoupler.kind: flinch check needs a decoupler with a stroke (\"bistable\" or \"hydraulic\")".into()),
    };
    let Some(Sensor::Travel { threshold }) = scene.sensor else {
        return Err("sensor.kind: flinch check needs a travel switch (sensor.kind = \"travel\")".into());
    };
    let m = &scene.motion;
    let stop = stopping_distance_um(um_up(m.speed), um_up(m.dead_time), um_down(m.decel).max(1)) as f64 * 1e-6;
    let remaining = stroke - threshold;
    let (simulated, _) = sim::run(scene, false).map_err(|e| e.to_string())?;
    Ok(BudgetCheck { stopping_distance: stop, stroke, switch_travel: threshold, remaining, margin: remaining - stop, fits: stop <= remaining, simulated })
}
