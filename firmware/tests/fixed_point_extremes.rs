//! The firmware's fixed-point arithmetic at the edges of its ranges (issue 5, "Fixed point"):
//! full stroke, full speed and the largest time values must saturate or wrap as documented, never
//! overflow into a wrong sign, never panic (tests build with overflow checks on).
//! The accuracy of the same arithmetic against f64 is measured by `flinch bench` (docs/accuracy.md).

use flinch_firmware::clock::Micros;
use flinch_firmware::sensor::{mm_to_um, Adc, AnalogConfig, AnalogTravel, Mm, Sensor};
use flinch_firmware::stroke_budget::{stopping_distance_m, stopping_distance_um, BudgetConfig};
use std::cell::Cell;

struct Raw<'a>(&'a Cell<u16>);
impl Adc for Raw<'_> {
    type Error = ();
    fn read(&mut self) -> Result<u16, ()> {
        Ok(self.0.get())
    }
}

/// Every raw reading is accepted (no plausibility window), so the arithmetic itself is exercised.
fn open_window(mut c: AnalogConfig) -> AnalogConfig {
    c.valid_min = 0;
    c.valid_max = u16::MAX;
    c
}

#[test]
fn travel_saturates_at_full_scale_and_is_monotone_in_the_counts() {
    // The largest span I16F16 can hold: every count is about 8 mm, full scale overflows the range.
    let c = open_window(AnalogConfig::linear_12bit(0, Mm::MAX, Mm::from_num(5)));
    let mut prev = c.travel_mm(0);
    for raw in 1..=u16::MAX {
        let x = c.travel_mm(raw);
        assert!(x >= prev, "travel fell from {prev} to {x} at raw {raw}: wrapped");
        prev = x;
    }
    assert_eq!(c.travel_mm(u16::MAX), Mm::MAX, "saturates, does not wrap");
    // Below the zero reading: negative travel, saturating at the bottom too.
    let c = open_window(AnalogConfig::linear_12bit(u16::MAX, Mm::MAX, Mm::from_num(5)));
    assert_eq!(c.travel_mm(0), Mm::MIN);
    // Micrometres of the extremes fit an i32 with the right sign.
    assert_eq!(mm_to_um(Mm::MAX), 32_767_999);
    assert_eq!(mm_to_um(Mm::MIN), -32_768_000);
}

#[test]
fn velocity_estimate_saturates_at_full_speed_with_the_right_sign() {
    let raw = Cell::new(0u16);
    let mut cfg = open_window(AnalogConfig::linear_12bit(0, Mm::MAX, Mm::from_num(5)));
    cfg.velocity_shift = 0; // raw difference quotient: the worst case
    let mut s = AnalogTravel::new(Raw(&raw), cfg);
    s.sample(Micros(0));
    // Full scale in one microsecond: 32 m in 1 us is far beyond I16F16 mm/s.
    raw.set(u16::MAX);
    let up = s.sample(Micros(1));
    assert_eq!(up.velocity_um_per_s, mm_to_um(Mm::MAX), "saturated high");
    // The same timestamp twice: no division by zero, the estimate is kept.
    let same = s.sample(Micros(1));
    assert_eq!(same.velocity_um_per_s, up.velocity_um_per_s);
    // Full scale down from rest: saturated low, not wrapped to positive.
    let raw = Cell::new(u16::MAX);
    let mut s = AnalogTravel::new(Raw(&raw), cfg);
    s.sample(Micros(0));
    raw.set(0);
    assert_eq!(s.sample(Micros(1)).velocity_um_per_s, mm_to_um(Mm::MIN));
}

/// Found by this suite, left to the firmware's owner (the issue forbids changing firmware
/// behaviour here): from a saturated +full-scale estimate, a full-scale reversal in one tick gives
/// -1 um/s instead of the saturated -full scale, because `v_new - v` saturates at I16F16::MIN and
/// adding it back to v = MAX lands on -1 LSB. Only a glitch of more than 32 m/s can get there (the
/// plausibility window and 2 m/s speeds keep real readings far below), and the stroke budget then
/// falls back on the configured speed. Fix: form `v + ((v_new - v) >> shift)` in i64 and clamp.
#[test]
#[ignore = "known firmware quirk, see the doc comment; run with --ignored"]
fn full_scale_reversal_saturates_low() {
    let raw = Cell::new(0u16);
    let mut cfg = open_window(AnalogConfig::linear_12bit(0, Mm::MAX, Mm::from_num(5)));
    cfg.velocity_shift = 0;
    let mut s = AnalogTravel::new(Raw(&raw), cfg);
    s.sample(Micros(0));
    raw.set(u16::MAX);
    s.sample(Micros(1));
    raw.set(0);
    assert_eq!(s.sample(Micros(2)).velocity_um_per_s, mm_to_um(Mm::MIN));
}

#[test]
fn velocity_estimate_is_right_across_the_clock_wrap() {
    // 2 m/s (the top of the accepted speeds) on a 50 mm 12-bit sensor, sampled every 100 us
    // through the u32 microsecond wrap (after 71.6 minutes of uptime).
    let raw = Cell::new(100u16);
    let mut cfg = AnalogConfig::linear_12bit(100, Mm::from_num(50), Mm::from_num(5));
    cfg.velocity_shift = 0;
    let per_count_mm = 50.0 / 4095.0;
    let mut s = AnalogTravel::new(Raw(&raw), cfg);
    let t0 = u32::MAX - 250;
    let mut last = None;
    for k in 0..6u32 {
        let t_us = t0.wrapping_add(k * 100);
        let x_mm = 2000.0 * f64::from(k) * 100e-6; // 2000 mm/s
        raw.set(100 + (x_mm / per_count_mm).round() as u16);
        last = Some(s.sample(Micros(t_us)));
    }
    let v = f64::from(last.unwrap().velocity_um_per_s) * 1e-6;
    // One count (12.2 um) in 100 us is 0.12 m/s of quantisation.
    assert!((v - 2.0).abs() < 0.13, "{v} m/s across the wrap");
}

#[test]
fn stroke_budget_saturates_and_never_underestimates_at_the_extremes() {
    assert_eq!(stopping_distance_um(u32::MAX, u32::MAX, 1), u32::MAX);
    assert_eq!(stopping_distance_um(u32::MAX, 0, u32::MAX), {
        // v^2 / 2d = (2^32-1)^2 / (2 (2^32-1)) = (2^32-1)/2, rounded up.
        (u32::MAX / 2) + 1
    });
    // Full speed (2 m/s), longest dead time (0.2 s), gentlest braking (0.1 m/s^2): 20.4 m.
    let um = stopping_distance_um(2_000_000, 200_000, 100_000);
    let exact = stopping_distance_m(2.0, 0.2, 0.1) * 1e6;
    assert!(f64::from(um) >= exact && f64::from(um) - exact <= 2.0, "{um} vs {exact}");
    // Travel and stroke at the ends of i32: no overflow, nothing left, escalate.
    let b = BudgetConfig { robot_speed_um_per_s: u32::MAX, dead_time_us: u32::MAX, decel_um_per_s2: 0, stroke_um: i32::MIN };
    let v = b.check_at(i32::MAX, u32::MAX);
    assert_eq!((v.required_um, v.remaining_um, v.escalate), (u32::MAX, 0, true));
    // A huge stroke with travel at i32::MIN: the remaining stroke saturates, it does not wrap.
    let b = BudgetConfig { robot_speed_um_per_s: 1, dead_time_us: 1, decel_um_per_s2: 1, stroke_um: i32::MAX };
    let v = b.check(i32::MIN);
    assert_eq!(v.remaining_um, u32::MAX);
    assert!(!v.escalate);
}
