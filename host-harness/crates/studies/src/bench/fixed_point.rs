//! The firmware's fixed-point arithmetic against f64 (docs/accuracy.md, "Fixed point").
//!
//! Measured on the firmware's own code (`flinch_firmware::sensor`, `flinch_firmware::stroke_budget`),
//! not a copy, against the same formula in f64; the alternative Q formats are the same formulas
//! written here with the `fixed` crate, to show what another format would buy. Three computations:
//! - travel from raw ADC counts, `mm_per_count * (raw - zero)` in I16F16 millimetres, and the trip
//!   decision `travel >= trip` (alternatives: I20F12, I8F24);
//! - the travel-velocity estimate (finite difference, first-order smoothing) on a ramp sampled at
//!   the firmware tick, against the same estimator in f64 on the same counts (the arithmetic's own
//!   error) and against the true speed (what the ADC's resolution leaves); alternative I20F12;
//! - the stroke budget's stopping distance `v DT + v^2 / (2 d)` in integer micrometres against f64
//!   (alternatives: I16F16 and I32F32 millimetres).

use fixed::types::{I16F16, I20F12, I32F32, I8F24};
use flinch_firmware::clock::Micros;
use flinch_firmware::sensor::{Adc, AnalogConfig, AnalogTravel, Mm, Sensor};
use flinch_firmware::stroke_budget::{stopping_distance_m, stopping_distance_um};
use std::cell::Cell;
use std::fmt::Write as _;

/// Spans of the 12-bit sensor studied, mm (the Z prototype's 0.5 mm switch travel to the 47 mm
/// stroke of Table 15).
pub const SPANS_MM: [f64; 3] = [10.0, 25.0, 50.0];
/// Trip travels studied, mm (MODEL.md: 0.5, 1.5, 5 mm).
pub const TRIPS_MM: [f64; 3] = [0.5, 1.5, 5.0];

/// One line of the table.
#[derive(Debug, Clone, PartialEq)]
pub struct Line {
    /// What is computed.
    pub quantity: &'static str,
    /// Number format.
    pub format: &'static str,
    /// The case (span, speed, ...).
    pub case: String,
    /// Largest absolute error against f64.
    pub max_abs_error: f64,
    /// Its unit.
    pub unit: &'static str,
    /// Decisions (trip, escalate) that differ from f64, or saturated results.
    pub mismatches: u64,
    /// Evaluations compared.
    pub evaluations: u64,
    /// Note.
    pub note: String,
}

macro_rules! travel_in {
    ($t:ty, $span:expr, $trip:expr) => {{
        let per = <$t>::from_num($span).checked_div_int(4095).unwrap_or(<$t>::ZERO);
        let trip = <$t>::from_num($trip);
        let per_f = $span / 4095.0;
        let (mut worst, mut mism) = (0.0f64, 0u64);
        for raw in 0..=4095i32 {
            let counts = raw - 100;
            let x = per.saturating_mul_int(counts);
            let xf = per_f * f64::from(counts);
            worst = worst.max((x.to_num::<f64>() - xf).abs());
            mism += u64::from((x >= trip) != (xf >= $trip));
        }
        (worst, mism)
    }};
}

/// Travel from raw counts, and the trip decision, for each span, trip and format.
pub fn travel_lines() -> Vec<Line> {
    let mut v = Vec::new();
    for span in SPANS_MM {
        for trip in TRIPS_MM {
            // The firmware's own code path.
            let cfg = AnalogConfig::linear_12bit(100, Mm::from_num(span), Mm::from_num(trip));
            let per_f = span / 4095.0;
            let (mut worst, mut mism) = (0.0f64, 0u64);
            for raw in 0..=4095u16 {
                let x = cfg.travel_mm(raw);
                let xf = per_f * (f64::from(raw) - 100.0);
                worst = worst.max((x.to_num::<f64>() - xf).abs());
                mism += u64::from((x >= cfg.trip_mm) != (xf >= trip));
            }
            let case = format!("span {span} mm, trip {trip} mm");
            let count_um = per_f * 1e3;
            v.push(Line { quantity: "travel from ADC counts", format: "I16F16 mm (firmware)", case: case.clone(), max_abs_error: worst * 1e3, unit: "um", mismatches: mism, evaluations: 4096, note: format!("one count = {count_um:.2} um") });
            let (w, m) = travel_in!(I20F12, span, trip);
            v.push(Line { quantity: "travel from ADC counts", format: "I20F12 mm", case: case.clone(), max_abs_error: w * 1e3, unit: "um", mismatches: m, evaluations: 4096, note: String::new() });
            let (w, m) = travel_in!(I8F24, span, trip);
            v.push(Line { quantity: "travel from ADC counts", format: "I8F24 mm", case, max_abs_error: w * 1e3, unit: "um", mismatches: m, evaluations: 4096, note: "range +-128 mm".into() });
        }
    }
    v
}

struct RampAdc<'a>(&'a Cell<u16>);
impl Adc for RampAdc<'_> {
    type Error = ();
    fn read(&mut self) -> Result<u16, ()> {
        Ok(self.0.get())
    }
}

/// The firmware's velocity estimator in f64 on the same counts: difference quotient, then
/// `v += (v_new - v) / 2^shift`.
struct FloatEstimator {
    last: Option<(f64, f64)>,
    v: f64,
    shift: u32,
}

impl FloatEstimator {
    fn update(&mut self, t_s: f64, x_mm: f64) -> f64 {
        if let Some((t0, x0)) = self.last {
            let v_new = (x_mm - x0) / (t_s - t0);
            self.v += (v_new - self.v) / f64::from(1u32 << self.shift);
        }
        self.last = Some((t_s, x_mm));
        self.v
    }
}

/// The same estimator in I20F12 (an alternative format).
fn estimate_i20f12(xs_bits: &[i64], tick_us: u32, shift: u32) -> Vec<f64> {
    let mut v = I20F12::ZERO;
    let mut out = Vec::with_capacity(xs_bits.len());
    for w in xs_bits.windows(2) {
        let dx = w[1] - w[0];
        let v_bits = dx.saturating_mul(1_000_000) / i64::from(tick_us);
        let v_new = I20F12::from_bits(v_bits.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32);
        v = v.saturating_add(v_new.saturating_sub(v) >> shift);
        out.push(v.to_num::<f64>());
    }
    out
}

/// Velocity estimate on a ramp at each speed and tick.
pub fn velocity_lines() -> Vec<Line> {
    let mut lines = Vec::new();
    let span = 50.0;
    for tick_us in [100u32, 1000] {
        for v_m_s in [1e-4, 1e-3, 0.01, 0.05, 0.25, 1.0, 2.0] {
            let cfg = AnalogConfig::linear_12bit(100, Mm::from_num(span), Mm::from_num(5.0));
            let per_f = span / 4095.0;
            let raw = Cell::new(100u16);
            let mut fw = AnalogTravel::new(RampAdc(&raw), cfg);
            let mut fl = FloatEstimator { last: None, v: 0.0, shift: u32::from(cfg.velocity_shift) };
            let v_mm_s = v_m_s * 1e3;
            // Ramp until 40 mm of travel (the plausible window) or 4000 ticks.
            let n = ((40.0 / v_mm_s) / (f64::from(tick_us) * 1e-6)).min(4000.0) as usize;
            let (mut arith, mut truth_sum, mut truth_n, mut sat) = (0.0f64, 0.0f64, 0u64, 0u64);
            let mut bits12 = Vec::with_capacity(n + 1);
            let mut fl_hist = Vec::with_capacity(n + 1);
            for k in 0..=n {
                let t_s = k as f64 * f64::from(tick_us) * 1e-6;
                let counts = (v_mm_s * t_s / per_f).round() as i64;
                let r = (100 + counts).clamp(0, 4079) as u16;
                raw.set(r);
                let s = fw.sample(Micros((k as u32).wrapping_mul(tick_us)));
                let v_fw = f64::from(s.velocity_um_per_s) * 1e-3; // mm/s
                let x_f = per_f * (f64::from(r) - 100.0);
                let v_fl = fl.update(t_s, x_f);
                fl_hist.push(v_fl);
                bits12.push((x_f * 4096.0).round() as i64);
                // The firmware reports whole um/s: compare to the f64 estimator rounded the same way
                // (truncated), so the figure is the fixed-point arithmetic's own error.
                arith = arith.max((v_fw - (v_fl * 1e3).floor() * 1e-3).abs());
                sat += u64::from(s.velocity_um_per_s == i32::MAX || s.velocity_um_per_s == i32::MIN);
                if k > n / 2 {
                    truth_sum += v_fw - v_mm_s;
                    truth_n += 1;
                }
            }
            let case = format!("v = {v_m_s} m/s, tick {tick_us} us, span {span} mm");
            let bias = if truth_n > 0 { truth_sum / truth_n as f64 } else { 0.0 };
            lines.push(Line {
                quantity: "travel velocity estimate",
                format: "I16F16 mm/s (firmware)",
                case: case.clone(),
                max_abs_error: arith,
                unit: "mm/s",
                mismatches: sat,
                evaluations: n as u64 + 1,
                note: format!("mean error against the true speed over the second half: {bias:+.3} mm/s ({:+.2} %)", 100.0 * bias / v_mm_s),
            });
            let alt = estimate_i20f12(&bits12, tick_us, u32::from(cfg.velocity_shift));
            let worst = alt.iter().zip(fl_hist.iter().skip(1)).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            lines.push(Line { quantity: "travel velocity estimate", format: "I20F12 mm/s", case, max_abs_error: worst, unit: "mm/s", mismatches: 0, evaluations: n as u64, note: "travel also quantised to 1/4096 mm".into() });
        }
    }
    lines
}

/// Stopping distance over the accepted box: speed 1e-4..2 m/s, dead time 0..0.2 s, deceleration
/// 0.1..50 m/s^2.
pub fn budget_lines() -> Vec<Line> {
    let speeds: Vec<f64> = (0..=20).map(|i| 1e-4 * (2.0f64 / 1e-4).powf(i as f64 / 20.0)).collect();
    let dts = [0.0, 1e-4, 0.016, 0.07, 0.2];
    let decels = [0.1, 1.0, 2.0, 5.0, 50.0];
    let mut out = Vec::new();
    let (mut worst_int, mut under, mut n) = (0.0f64, 0u64, 0u64);
    let (mut worst_16, mut sat_16) = (0.0f64, 0u64);
    let (mut worst_32, mut sat_32) = (0.0f64, 0u64);
    for &v in &speeds {
        for &dt in &dts {
            for &d in &decels {
                n += 1;
                let exact_um = stopping_distance_m(v, dt, d) * 1e6;
                // The firmware's inputs are whole micrometres and microseconds (hil.rs rounds).
                let vi = (v * 1e6).round() as u32;
                let dti = (dt * 1e6).round() as u32;
                let di = (d * 1e6).round() as u32;
                let got = f64::from(stopping_distance_um(vi, dti, di));
                worst_int = worst_int.max((got - exact_um).abs());
                under += u64::from(got < exact_um - 1e-6 * exact_um.max(1.0));
                // I16F16 millimetres: v mm/s, dt s, d mm/s^2.
                let (v16, dt16, d16) = (I16F16::saturating_from_num(v * 1e3), I16F16::saturating_from_num(dt), I16F16::saturating_from_num(d * 1e3));
                // 2 d overflows I16F16 above 16.4 m/s^2 (a debug build panicked on `d16 * 2`): counted as overflowed.
                let r16 = v16.checked_mul(dt16).zip(v16.checked_mul(v16).and_then(|vv| d16.checked_mul_int(2).and_then(|dd| vv.checked_div(dd))));
                match r16 {
                    Some((a, b)) => match a.checked_add(b) {
                        Some(s) => worst_16 = worst_16.max((s.to_num::<f64>() * 1e3 - exact_um).abs()),
                        None => sat_16 += 1,
                    },
                    None => sat_16 += 1,
                }
                let (v32, dt32, d32) = (I32F32::from_num(v * 1e3), I32F32::from_num(dt), I32F32::from_num(d * 1e3));
                let r32 = v32.checked_mul(dt32).zip(v32.checked_mul(v32).and_then(|vv| d32.checked_mul_int(2).and_then(|dd| vv.checked_div(dd))));
                match r32.and_then(|(a, b)| a.checked_add(b)) {
                    Some(s) => worst_32 = worst_32.max((s.to_num::<f64>() * 1e3 - exact_um).abs()),
                    None => sat_32 += 1,
                }
            }
        }
    }
    let case = format!("v 1e-4..2 m/s x DT 0..0.2 s x d 0.1..50 m/s^2 ({n} points)");
    out.push(Line { quantity: "stopping distance v DT + v^2/2d", format: "u32/u64 integer um (firmware)", case: case.clone(), max_abs_error: worst_int, unit: "um", mismatches: under, evaluations: n, note: "mismatches = under-estimates (must be 0: rounded up)".into() });
    out.push(Line { quantity: "stopping distance v DT + v^2/2d", format: "I16F16 mm", case: case.clone(), max_abs_error: worst_16, unit: "um", mismatches: sat_16, evaluations: n, note: "mismatches = overflowed (v^2 in mm^2/s^2 exceeds 32767 above 0.18 m/s, 2d above 16.4 m/s^2)".into() });
    out.push(Line { quantity: "stopping distance v DT + v^2/2d", format: "I32F32 mm", case, max_abs_error: worst_32, unit: "um", mismatches: sat_32, evaluations: n, note: "mismatches = overflowed".into() });
    // The extremes: the largest inputs saturate, they do not wrap.
    let top = stopping_distance_um(u32::MAX, u32::MAX, 1);
    out.push(Line { quantity: "stopping distance at the largest inputs", format: "u32/u64 integer um (firmware)", case: "v = DT = u32::MAX, d = 1".into(), max_abs_error: 0.0, unit: "um", mismatches: u64::from(top != u32::MAX), evaluations: 1, note: "mismatches = 1 if it did not saturate at u32::MAX".into() });
    out
}

/// Every line, as CSV.
pub fn table() -> String {
    let mut s = String::from("quantity,format,case,max_abs_error,unit,mismatches,evaluations,note\n");
    for l in travel_lines().into_iter().chain(velocity_lines()).chain(budget_lines()) {
        let _ = writeln!(s, "{},{},\"{}\",{:.6e},{},{},{},\"{}\"", l.quantity, l.format, l.case, l.max_abs_error, l.unit, l.mismatches, l.evaluations, l.note);
    }
    s
}
