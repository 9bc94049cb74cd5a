//! The robot's brakes in a category-0 stop (IEC 60204-1 9.2.2: "stopping by immediate removal of
//! power to the machine actuators"), the stop the firmware's escalation output asks for when the
//! controlled stop would not fit the stroke (stroke budget). Not the controlled-stop ramp of
//! `motion_law.rs`: once the drives lose power nothing follows the commanded trajectory any more.
//!
//! From the instant power is removed, t_off, with the flange moving at v_0:
//!
//! * for `delay` seconds the arm coasts at v_0 (no drive torque; the holding brakes are not yet
//!   engaged). Joint friction is neglected (it would shorten the stop); so is gravity along the
//!   motion, which would lengthen a downward stop: give brake figures for the worst pose, as
//!   manufacturers measure category-0 stops (ISO 10218-1 Annex B: full extension, full speed, full
//!   payload, moving down);
//! * then it decelerates at `decel` to standstill, and stays there.
//!
//! x(tau) = v_0 tau for tau <= delay, then v_0 delay + v_0 tau' - decel tau'^2 / 2 with
//! tau' = tau - delay, until v = 0 at tau = delay + v_0 / decel. Units: s, m, m/s, m/s^2.
//!
//! # Defaults (`[controller] brake_delay`, `brake_decel`)
//!
//! [`DEFAULT_DELAY_S`] and [`DEFAULT_DECEL_MPS2`], with their sources, are the scene loader's
//! (`flinch_model::scene::controller`): a scene without them gets them there.
//!
//! With the robot's own category-0 stopping data (`motion.stopping` with `category = 0`) the
//! plant uses that table's equivalent delay and deceleration at v_0 instead (model/src/stopping.rs).

pub use flinch_model::scene::{DEFAULT_BRAKE_DECEL_MPS2 as DEFAULT_DECEL_MPS2, DEFAULT_BRAKE_DELAY_S as DEFAULT_DELAY_S};
use flinch_model::scene::Controller;

/// The brakes that stop the arm once drive power is removed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PowerOffBrake {
    /// From power removal to braking, s, >= 0.
    pub delay: f64,
    /// Deceleration while braking, m/s^2, > 0.
    pub decel: f64,
}

impl Default for PowerOffBrake {
    fn default() -> Self {
        Self { delay: DEFAULT_DELAY_S, decel: DEFAULT_DECEL_MPS2 }
    }
}

impl PowerOffBrake {
    /// The brakes of a category-0 stop as the scene's `[controller]` gives them.
    pub fn of(ctl: &Controller) -> Self {
        Self { delay: ctl.brake_delay, decel: ctl.brake_decel }
    }

    /// Displacement, velocity and acceleration `tau` >= 0 s after power removal from speed `v0` >= 0.
    pub fn after(&self, v0: f64, tau: f64) -> (f64, f64, f64) {
        let tau = tau.max(0.0);
        if tau <= self.delay || v0 <= 0.0 {
            return (v0.max(0.0) * tau, v0.max(0.0), 0.0);
        }
        let t_rest = v0 / self.decel;
        let b = (tau - self.delay).min(t_rest);
        let moving = tau - self.delay < t_rest;
        (v0 * self.delay + v0 * b - 0.5 * self.decel * b * b, (v0 - self.decel * b).max(0.0), if moving { -self.decel } else { 0.0 })
    }

    /// From power removal to standstill, s.
    pub fn stop_time(&self, v0: f64) -> f64 {
        if v0 <= 0.0 { 0.0 } else { self.delay + v0 / self.decel }
    }

    /// Distance from power removal to standstill, m: v0 delay + v0^2 / (2 decel).
    pub fn stop_distance(&self, v0: f64) -> f64 {
        if v0 <= 0.0 { 0.0 } else { v0 * self.delay + v0 * v0 / (2.0 * self.decel) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coasts_for_the_delay_then_brakes_to_rest_continuously() {
        let b = PowerOffBrake { delay: 0.08, decel: 5.0 };
        let v0 = 0.25;
        let (x, v, a) = b.after(v0, 0.08);
        assert!((x - 0.02).abs() < 1e-15 && v == v0 && a == 0.0, "coasting: {x} {v} {a}");
        let (x1, v1, _) = b.after(v0, 0.08 + 1e-12);
        assert!((x1 - x).abs() < 1e-12 && (v1 - v).abs() < 1e-10, "continuous at the engagement");
        let ts = b.stop_time(v0);
        assert!((ts - 0.13).abs() < 1e-15);
        let (xe, ve, ae) = b.after(v0, 10.0);
        assert_eq!((ve, ae), (0.0, 0.0));
        assert!((xe - b.stop_distance(v0)).abs() < 1e-15 && (xe - (0.02 + 0.00625)).abs() < 1e-15, "{xe}");
        assert_eq!(b.after(0.0, 1.0), (0.0, 0.0, 0.0), "at rest it stays there");
    }
}
