//! Stroke budget: can the decoupler's remaining stroke absorb the robot's stopping distance?
//!
//! After detection the robot keeps moving at speed v for the dead time DT (at most one scan cycle,
//! MODEL.md "Controller": 16 ms on the Viper, 60-70 ms in the experiments, 100 us over EtherCAT), then
//! brakes at deceleration d to rest (MODEL.md "Motion law": braking at d_c, no reversal). Against a
//! fixed obstacle the tool does not move, so the flange closes on the tool by
//!
//! ```text
//!     s_stop = v * DT + v^2 / (2 d)
//! ```
//!
//! The stroke left when the detector fires is `C - x_trip`, with C = C1 + C2 the total stroke
//! (MODEL.md "Coordinates") and x_trip the travel at detection (d_sw for the switch, the measured
//! travel for the analog sensor). If `s_stop > C - x_trip` the flange would reach the tool before the
//! robot stops: a controlled stop (category 1) is too slow and the firmware also drops the
//! escalation output, which asks for a category-0 stop (power off the drives).
//!
//! [`stopping_distance_um`] is the firmware's version: integers only (no `f64`, no FPU needed), every
//! step checked, rounded *up* so it never under-estimates. [`stopping_distance_m`] is the same formula
//! in `f64` for the host (`flinch check` on a scene); the two agree to within 2 um (tested).
//! The formula assumes the worst case of a fixed obstacle; a free object that is pushed away eats less
//! stroke, so the check is conservative there.

/// The robot's motion as the budget needs it, and the decoupler's stroke.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct BudgetConfig {
    /// Robot approach speed v, micrometres per second (Tables 5-7: V_c = 0.05 m/s = 50 000).
    pub robot_speed_um_per_s: u32,
    /// Dead time DT between detection and the start of braking, microseconds (16 000 on the Viper).
    pub dead_time_us: u32,
    /// Braking deceleration d, micrometres per second squared (> 0).
    pub decel_um_per_s2: u32,
    /// Total stroke C = C1 + C2 of the decoupler, micrometres.
    pub stroke_um: i32,
}

/// The outcome of a budget check.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct Verdict {
    /// Stopping distance s_stop, micrometres (saturates at `u32::MAX`).
    pub required_um: u32,
    /// Stroke left at detection, micrometres (0 if none).
    pub remaining_um: u32,
    /// `required_um > remaining_um`: escalate to category 0.
    pub escalate: bool,
}

/// Stopping distance `v*DT + v^2/(2d)` in micrometres, integer-only, rounded up, saturating at
/// `u32::MAX` (also for `decel_um_per_s2 == 0`: a robot that cannot brake never stops).
pub const fn stopping_distance_um(speed_um_per_s: u32, dead_time_us: u32, decel_um_per_s2: u32) -> u32 {
    if decel_um_per_s2 == 0 {
        return u32::MAX;
    }
    let v = speed_um_per_s as u64;
    // v * DT: (um/s) * us / 1e6 = um. Both factors < 2^32, so the product fits u64.
    let during_dead_time = v.wrapping_mul(dead_time_us as u64).div_ceil(1_000_000);
    // v^2 / (2d): (um/s)^2 / (um/s^2) = um. v^2 < 2^64 fits; 2d < 2^33 fits.
    let braking = v.wrapping_mul(v).div_ceil((decel_um_per_s2 as u64).wrapping_mul(2));
    let total = during_dead_time.saturating_add(braking);
    if total > u32::MAX as u64 {
        u32::MAX
    } else {
        total as u32
    }
}

/// The same formula in SI units and `f64`, for the host: metres from m/s, s and m/s^2.
pub fn stopping_distance_m(speed_m_per_s: f64, dead_time_s: f64, decel_m_per_s2: f64) -> f64 {
    speed_m_per_s * dead_time_s + speed_m_per_s * speed_m_per_s / (2.0 * decel_m_per_s2)
}

impl BudgetConfig {
    /// Check the budget for a detection at travel `trip_travel_um`, with the robot closing at
    /// `closing_um_per_s` (the larger of the configured speed and a measured travel velocity).
    pub fn check_at(&self, trip_travel_um: i32, closing_um_per_s: u32) -> Verdict {
        let v = if closing_um_per_s > self.robot_speed_um_per_s { closing_um_per_s } else { self.robot_speed_um_per_s };
        let required_um = stopping_distance_um(v, self.dead_time_us, self.decel_um_per_s2);
        self.verdict_with(required_um, trip_travel_um)
    }

    /// The stopping distance at the configured speed: the constant part of every check, computed
    /// once at configuration ([`Firmware`](crate::Firmware) keeps it) so that a trip pays no `u64`
    /// division.
    pub const fn configured_required_um(&self) -> u32 {
        stopping_distance_um(self.robot_speed_um_per_s, self.dead_time_us, self.decel_um_per_s2)
    }

    /// The verdict for a precomputed stopping distance `required_um` and a detection at
    /// `trip_travel_um`: one subtraction and one comparison.
    pub fn verdict_with(&self, required_um: u32, trip_travel_um: i32) -> Verdict {
        let left = i64::from(self.stroke_um).wrapping_sub(i64::from(trip_travel_um));
        let remaining_um = left.clamp(0, u32::MAX as i64) as u32;
        Verdict { required_um, remaining_um, escalate: required_um > remaining_um }
    }

    /// Check the budget with the configured speed only.
    pub fn check(&self, trip_travel_um: i32) -> Verdict {
        self.check_at(trip_travel_um, 0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formula_by_hand() {
        // Tables 5-7: V_c = 0.05 m/s, DT = 16 ms; d = 1 m/s^2 chosen for the example.
        // 0.05 * 0.016 = 0.8 mm, 0.05^2 / 2 = 1.25 mm.
        assert_eq!(stopping_distance_um(50_000, 16_000, 1_000_000), 800 + 1250);
        assert_eq!(stopping_distance_um(0, 16_000, 1_000_000), 0);
        assert_eq!(stopping_distance_um(1, 1, 1_000_000), 2); // both terms round up
        assert_eq!(stopping_distance_um(50_000, 16_000, 0), u32::MAX);
        assert_eq!(stopping_distance_um(u32::MAX, u32::MAX, 1), u32::MAX);
    }

    #[test]
    fn fixed_point_agrees_with_the_f64_formula() {
        let mut worst = 0.0f64;
        for v in [1_000u32, 50_000, 200_000, 250_000, 1_000_000, 2_500_000] {
            for dt in [100u32, 16_000, 70_000, 100_000] {
                for d in [100_000u32, 1_000_000, 5_000_000, 20_000_000] {
                    let fixed = f64::from(stopping_distance_um(v, dt, d));
                    let float = stopping_distance_m(f64::from(v) * 1e-6, f64::from(dt) * 1e-6, f64::from(d) * 1e-6) * 1e6;
                    assert!(fixed >= float - 1e-6, "never under-estimates: {fixed} < {float}");
                    worst = worst.max(fixed - float);
                }
            }
        }
        assert!(worst <= 2.0, "rounding error {worst} um");
    }

    #[test]
    fn escalates_when_the_stroke_cannot_absorb_it() {
        // Stroke 10 mm, switch at 5 mm (Ch. 3 d_sw): 5 mm left.
        let b = BudgetConfig { robot_speed_um_per_s: 50_000, dead_time_us: 16_000, decel_um_per_s2: 1_000_000, stroke_um: 10_000 };
        let ok = b.check(5_000);
        assert_eq!(ok, Verdict { required_um: 2050, remaining_um: 5000, escalate: false });
        // At 0.25 m/s (Fig. 46 mode 3): 4 mm + 31.25 mm.
        let fast = BudgetConfig { robot_speed_um_per_s: 250_000, ..b };
        assert!(fast.check(5_000).escalate);
        // A measured closing speed above the configured one is used.
        assert!(b.check_at(5_000, 250_000).escalate);
        // Travel past the back stop leaves nothing.
        assert_eq!(b.check(12_000).remaining_um, 0);
        // The precomputed constant part gives the same verdicts.
        for travel in [-1_000, 0, 5_000, 7_950, 7_951, 12_000] {
            assert_eq!(b.verdict_with(b.configured_required_um(), travel), b.check(travel), "{travel}");
            assert_eq!(fast.verdict_with(fast.configured_required_um(), travel), fast.check(travel));
        }
    }
}
