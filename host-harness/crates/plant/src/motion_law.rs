//! Motion law of the commanded flange x_c (MODEL.md element 1; Ch. 3.1.2, "trapezoidal velocity
//! profile"): accelerate at a_c to V_c, cruise, and, from t_brake = t_detect + DT, brake at d_c to
//! standstill without reversing. Units: s, m, m/s, m/s^2.
//!
//! With the robot's stopping table (`motion.stopping`, `model/src/stopping.rs`) the stop is signalled
//! ([`MotionLaw::stop_signal_at`]) and the law brakes with the table's equivalent dead time and
//! deceleration at the speed commanded at that instant, so it covers the table's D(v) in T(v).

use super::brake::PowerOffBrake;
use flinch_model::stopping::StoppingTable;
use flinch_model::scene::Motion;

/// The commanded flange motion, with the braking instant once it is known.
#[derive(Debug, Clone, Copy)]
pub struct MotionLaw {
    speed: f64,
    accel: f64,
    decel: f64,
    start_at_speed: bool,
    /// Start of braking, s; `None` until detection has scheduled it.
    t_brake: Option<f64>,
    /// The robot's stopping table, if the scene gives one.
    stopping: Option<StoppingTable>,
    /// Set when a stop signalled from the table needed its equivalent adjusted (the reason).
    pub adjusted: Option<&'static str>,
    /// Drive power removed (category-0 stop, `plant/brake.rs`): when, and the brakes that stop it.
    power_off: Option<(f64, PowerOffBrake)>,
    /// End of the acceleration phase, s ([`MotionLaw::t_cruise`]), kept: the law is evaluated at
    /// every right-hand side and event function, and its divisions were 8 % of a run's
    /// instructions (callgrind, docs/accuracy.md). The same arithmetic, so the same bits.
    t1: f64,
    /// At the start of braking: the commanded state there and the time to rest, s (set with
    /// `t_brake`, from the same expressions [`MotionLaw::controlled`] evaluated every call).
    brake_from: (Commanded, f64),
}

/// Commanded position, velocity and acceleration at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Commanded {
    /// x_c, m (x_c(0) = 0).
    pub x: f64,
    /// x_c', m/s.
    pub v: f64,
    /// x_c'', m/s^2.
    pub a: f64,
}

impl MotionLaw {
    /// The law of a scene's `[motion]`, not yet braking.
    pub fn new(m: &Motion) -> Self {
        let t1 = if m.start_at_speed { 0.0 } else { m.speed / m.accel };
        let rest = Commanded { x: 0.0, v: 0.0, a: 0.0 };
        Self { speed: m.speed, accel: m.accel, decel: m.decel, start_at_speed: m.start_at_speed, t_brake: None, stopping: m.stopping, adjusted: None, power_off: None, t1, brake_from: (rest, 0.0) }
    }

    /// The robot gets the stop signal at `t`: without a table braking starts then (`brake_at`);
    /// with one, the table's equivalent dead time later, at its equivalent deceleration, both for
    /// the speed commanded at `t` (model/src/stopping.rs). A second signal changes nothing.
    pub fn stop_signal_at(&mut self, t: f64) {
        if self.t_brake.is_some() {
            return;
        }
        let Some(table) = self.stopping else {
            self.brake_at(t);
            return;
        };
        // The loader holds V_c within the table, and the commanded speed never exceeds V_c; the
        // scene's own equivalent at V_c (self.decel) stands in if that ever failed.
        let v = self.unbraked(t).v;
        match table.equivalent(v) {
            Some(e) => {
                self.decel = e.decel;
                self.adjusted = e.adjusted;
                self.brake_at(t + e.dead_time);
            }
            None => {
                let dt = table.equivalent(self.speed).map_or(0.0, |e| e.dead_time);
                self.brake_at(t + dt);
            }
        }
    }

    /// End of the acceleration phase, s (0 when the scene starts at speed).
    pub fn t_cruise(&self) -> f64 {
        self.t1
    }

    /// Schedule braking at `t` (the first call wins: braking cannot be re-planned).
    pub fn brake_at(&mut self, t: f64) {
        if self.t_brake.is_none() {
            let tb = t.max(0.0);
            self.t_brake = Some(tb);
            let c0 = self.unbraked(tb);
            self.brake_from = (c0, c0.v / self.decel);
        }
    }

    /// Start of braking, if scheduled.
    pub fn t_brake(&self) -> Option<f64> {
        self.t_brake
    }

    /// Instant the flange comes to rest, if braking is scheduled or power removed.
    pub fn t_stop(&self) -> Option<f64> {
        let controlled = self.controlled_stop();
        match self.power_off {
            Some((t_off, _)) if controlled.is_some_and(|ts| ts <= t_off) => controlled,
            Some((t_off, b)) => Some(t_off + b.stop_time(self.controlled(t_off).v)),
            None => controlled,
        }
    }

    fn controlled_stop(&self) -> Option<f64> {
        self.t_brake.map(|tb| tb + self.brake_from.1)
    }

    /// Drive power is removed at `t` (a category-0 stop, IEC 60204-1 9.2.2): from then on the arm
    /// coasts and `brake` stops it (`plant/brake.rs`), whatever the controlled stop was doing. The
    /// first call wins.
    pub fn remove_power_at(&mut self, t: f64, brake: PowerOffBrake) {
        if self.power_off.is_none() {
            self.power_off = Some((t.max(0.0), brake));
        }
    }

    /// True when the controlled law moves at a constant speed over [t0, t1] (no acceleration and no
    /// breakpoint inside): there, an arm coasting since t0 moves exactly as commanded.
    pub fn steady_between(&self, t0: f64, t1: f64) -> bool {
        let cruise = if self.start_at_speed { None } else { Some(self.t_cruise()) };
        let kink = [cruise, self.t_brake, self.controlled_stop()].into_iter().flatten().any(|b| b > t0 && b < t1);
        !kink && self.controlled(t0).a == 0.0 && self.controlled(t1).a == 0.0 && self.power_off.is_none()
    }

    /// When drive power was removed, if it was.
    pub fn power_off_at(&self) -> Option<f64> {
        self.power_off.map(|(t, _)| t)
    }

    /// The instants where x_c'' jumps: the solver must not step across them.
    pub fn breakpoints(&self) -> [Option<f64>; 6] {
        let cruise = if self.start_at_speed { None } else { Some(self.t_cruise()) };
        let (off, engaged) = match self.power_off {
            Some((t, b)) => (Some(t), Some(t + b.delay)),
            None => (None, None),
        };
        [cruise, self.t_brake, self.controlled_stop(), off, engaged, self.t_stop()]
    }

    /// Commanded motion at `t`.
    pub fn at(&self, t: f64) -> Commanded {
        match self.power_off {
            Some((t_off, b)) if t > t_off => {
                let c0 = self.controlled(t_off);
                let (dx, v, a) = b.after(c0.v, t - t_off);
                Commanded { x: c0.x + dx, v, a }
            }
            _ => self.controlled(t),
        }
    }

    /// The trapezoid with the controlled stop, without power removal.
    fn controlled(&self, t: f64) -> Commanded {
        match self.t_brake {
            Some(tb) if t > tb => {
                let (c0, t_rest) = self.brake_from;
                let tau = (t - tb).min(t_rest);
                let moving = t - tb < t_rest;
                Commanded {
                    x: c0.x + c0.v * tau - 0.5 * self.decel * tau * tau,
                    v: (c0.v - self.decel * tau).max(0.0),
                    a: if moving { -self.decel } else { 0.0 },
                }
            }
            _ => self.unbraked(t),
        }
    }

    /// The trapezoid without braking.
    fn unbraked(&self, t: f64) -> Commanded {
        let t = t.max(0.0);
        let t1 = self.t1;
        if t < t1 {
            Commanded { x: 0.5 * self.accel * t * t, v: self.accel * t, a: self.accel }
        } else {
            let x1 = if self.start_at_speed { 0.0 } else { 0.5 * self.speed * t1 };
            Commanded { x: x1 + self.speed * (t - t1), v: self.speed, a: 0.0 }
        }
    }

    /// Flange travel from t = 0 to `t` if it never brakes, m (the validator's "gap never closed").
    pub fn travel_unbraked(&self, t: f64) -> f64 {
        self.unbraked(t).x
    }

    /// Stopping distance from `v` with dead time `dead_time`: v DT + v^2 / (2 d_c), m.
    pub fn stopping_distance(v: f64, dead_time: f64, decel: f64) -> f64 {
        v * dead_time + v * v / (2.0 * decel)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law() -> MotionLaw {
        MotionLaw::new(&Motion { speed: 0.05, accel: 1.0, decel: 2.0, dead_time: 0.016, stopping: None, stopping_payload: None, gravity: 0.0, start_at_speed: false, brake_after_contact: 0 })
    }

    #[test]
    fn trapezoid_then_braking_is_continuous_and_stops() {
        let mut m = law();
        m.brake_at(0.3);
        let tb = 0.3;
        let before = m.at(tb - 1e-12);
        let after = m.at(tb + 1e-12);
        assert!((before.x - after.x).abs() < 1e-12 && (before.v - after.v).abs() < 1e-9);
        let ts = m.t_stop().unwrap();
        assert!((ts - (0.3 + 0.025)).abs() < 1e-12);
        let end = m.at(10.0);
        assert_eq!(end.v, 0.0);
        // x at rest = x(tb) + v^2 / 2d
        let expect = m.at(tb).x + 0.05 * 0.05 / 4.0;
        assert!((end.x - expect).abs() < 1e-12);
    }

    #[test]
    fn braking_during_acceleration_starts_from_current_speed() {
        let mut m = law();
        m.brake_at(0.02); // v = 0.02 < V_c
        assert!((m.at(0.02).v - 0.02).abs() < 1e-12);
        assert!((m.t_stop().unwrap() - 0.03).abs() < 1e-12);
    }

    #[test]
    fn a_signalled_stop_follows_the_table_from_the_signal() {
        // D = v 0.1 + v^2 / 10 and T = 0.1 + v / 5 at 0.02 and 0.05 m/s.
        let v = [0.02, 0.05];
        let d: Vec<f64> = v.iter().map(|v| v * 0.1 + v * v / 10.0).collect();
        let t: Vec<f64> = v.iter().map(|v| 0.1 + v / 5.0).collect();
        let table = StoppingTable::new(1, &v, &d, &t).unwrap();
        let mut m = MotionLaw::new(&Motion { stopping: Some(table), ..law_motion() });
        let ts = 0.3; // cruising at 0.05
        m.stop_signal_at(ts);
        assert!((m.t_brake().unwrap() - (ts + 0.1)).abs() < 1e-12);
        let travel = m.at(10.0).x - m.at(ts).x;
        assert!((travel - d[1]).abs() < 1e-12, "{travel} vs {}", d[1]);
        assert!((m.t_stop().unwrap() - ts - t[1]).abs() < 1e-12);
        // Signalled while accelerating (v = 0.02 at t = 0.02): the table's stop from 0.02 m/s,
        // give or take the speed gained during the dead time.
        let mut m = MotionLaw::new(&Motion { stopping: Some(table), ..law_motion() });
        m.stop_signal_at(0.02);
        assert!((m.t_brake().unwrap() - 0.12).abs() < 1e-12);
    }

    fn law_motion() -> Motion {
        Motion { speed: 0.05, accel: 1.0, decel: 2.0, dead_time: 0.016, stopping: None, stopping_payload: None, gravity: 0.0, start_at_speed: false, brake_after_contact: 0 }
    }

    #[test]
    fn power_removal_overrides_the_controlled_stop_with_the_brakes() {
        use crate::brake::PowerOffBrake;
        let b = PowerOffBrake { delay: 0.08, decel: 5.0 };
        // Cruising at 0.05 m/s: coast 80 ms, then 10 ms of braking at 5 m/s^2.
        let mut m = law();
        m.remove_power_at(0.3, b);
        assert!((m.at(0.35).v - 0.05).abs() < 1e-15 && m.at(0.35).a == 0.0, "coasting, not the 2 m/s^2 ramp");
        assert!((m.t_stop().unwrap() - 0.39).abs() < 1e-12);
        let travel = m.at(10.0).x - m.at(0.3).x;
        assert!((travel - b.stop_distance(0.05)).abs() < 1e-12);
        // Half-way through a controlled stop (tb = 0.3, d = 2: 0.04 m/s at 0.305): the drives lose
        // power and the arm coasts at 0.04 m/s until the brakes engage.
        let mut m = law();
        m.brake_at(0.3);
        m.remove_power_at(0.305, b);
        assert!((m.at(0.35).v - 0.04).abs() < 1e-12, "{}", m.at(0.35).v);
        assert!((m.t_stop().unwrap() - (0.305 + 0.08 + 0.04 / 5.0)).abs() < 1e-12);
        assert!(m.breakpoints().contains(&Some(0.385)), "the engagement is a breakpoint");
        // After the controlled stop has ended, removing power changes nothing.
        let mut m = law();
        m.brake_at(0.3);
        m.remove_power_at(0.4, b);
        assert!((m.t_stop().unwrap() - 0.325).abs() < 1e-12);
        assert_eq!(m.at(0.5).v, 0.0);
    }

    #[test]
    fn braking_cannot_be_replanned() {
        let mut m = law();
        m.brake_at(0.3);
        m.brake_at(0.1);
        assert_eq!(m.t_brake(), Some(0.3));
    }
}
