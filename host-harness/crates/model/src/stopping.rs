//! The robot's own stopping data (`[motion] stopping`, issue 17 item 3): stopping distance D and
//! stopping time T against speed, for one stop category, as manufacturers publish them (ISO 10218-1
//! Annex B; EN ISO 10218-1:2011 B.2: measured from the stop signal to standstill, so D and T
//! *include* the robot's reaction).
//!
//! # Interpolation
//!
//! Linear in speed between the table's points. Below the first point the stop is scaled from it
//! through the origin, D(v) = D_1 v / v_1, T(v) = T_1: an upper bound for every stop whose D / v
//! grows with speed, which a stop after a dead time at a constant deceleration does
//! (D / v = DT + v / 2d). Above the last point nothing is known: the scene loader refuses a speed
//! there ([`StoppingTable::covers`]); the table is not extrapolated.
//!
//! # What the plant brakes with
//!
//! The plant keeps its motion law (dead time, then constant deceleration, MODEL.md element 1) with
//! the *equivalent* pair that reproduces both D and T at the speed the stop is signalled at
//! ([`StoppingTable::equivalent`]): a stop at d after DT covers D = v DT + v^2 / 2d in T = DT + v / d,
//! so `d = v^2 / (2 (v T - D))` and `DT = 2 D / v - T`. This needs v T / 2 <= D < v T; the loader
//! refuses a table point outside it. Between points (the linear interpolation of D and T need not
//! keep D < v T - v^2 / 2 d_max, and in floating point may graze D = v T / 2) a d above
//! [`MAX_DECEL`] is lowered to it and DT lengthened so the distance is still D (the stop lasts longer
//! than T), and a negative DT is clamped to 0 with d keeping D: the distance is always D(v), and an
//! adjustment is said in the run's warnings. The stroke budget of `check` and `design` uses D(v) itself.
//! Units: m/s, m, s, m/s^2.

/// Most points a table holds (Annex B asks for 3 speeds; a few more for a finer curve).
pub const MAX_POINTS: usize = 16;

/// The largest equivalent deceleration, m/s^2: the bound of `motion.decel` (about 50 g).
pub const MAX_DECEL: f64 = 500.0;

/// A validated stopping table: speeds strictly increasing, distances strictly increasing, times
/// not decreasing, each point with v T / 2 <= D < v T. Fixed size so the motion stays `Copy`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StoppingTable {
    /// The stop category the data is for (0 or 1, IEC 60204-1 9.2.2).
    pub category: u8,
    n: usize,
    speed: [f64; MAX_POINTS],
    distance: [f64; MAX_POINTS],
    time: [f64; MAX_POINTS],
}

/// The dead time and deceleration that reproduce a stop, and whether they had to be adjusted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Equivalent {
    /// DT, s, >= 0: from the stop signal to the start of braking.
    pub dead_time: f64,
    /// d, m/s^2, in (0, MAX_DECEL].
    pub decel: f64,
    /// What was adjusted, for the warnings (None: D and T both reproduced).
    pub adjusted: Option<&'static str>,
}

impl StoppingTable {
    /// A table from its columns; `Err` says what is wrong (the loader names the key and line).
    /// Checks the lengths, the monotonicity and each point's physics, in that order.
    pub fn new(category: u8, speed: &[f64], distance: &[f64], time: &[f64]) -> Result<Self, TableError> {
        let n = speed.len();
        if n == 0 || n > MAX_POINTS {
            return Err(TableError::Speed(format!("must list 1 to {MAX_POINTS} speeds, got {n}")));
        }
        if distance.len() != n {
            return Err(TableError::Distance(format!("must list one distance per speed ({n}), got {}", distance.len())));
        }
        if time.len() != n {
            return Err(TableError::Time(format!("must list one time per speed ({n}), got {}", time.len())));
        }
        for i in 1..n {
            if speed[i] <= speed[i - 1] {
                return Err(TableError::Speed(format!("must increase strictly: item {} ({} m/s) is not above item {} ({} m/s)", i + 1, speed[i], i, speed[i - 1])));
            }
            if distance[i] <= distance[i - 1] {
                return Err(TableError::Distance(format!("must increase with speed (a stop from a faster motion is not shorter): item {} ({} m at {} m/s) is not above item {} ({} m at {} m/s)", i + 1, distance[i], speed[i], i, distance[i - 1], speed[i - 1])));
            }
            if time[i] < time[i - 1] {
                return Err(TableError::Time(format!("must not decrease with speed: item {} ({} s at {} m/s) is below item {} ({} s at {} m/s)", i + 1, time[i], speed[i], i, time[i - 1], speed[i - 1])));
            }
        }
        for i in 0..n {
            let (v, d, t) = (speed[i], distance[i], time[i]);
            let (lo, hi) = (v * t / 2.0, v * t);
            if !(d >= lo && d < hi) {
                return Err(TableError::Distance(format!(
                    "item {}: {} m is not a stop from {} m/s lasting {} s: a stop measured from the signal to standstill (reaction included) covers between v T / 2 = {} m (braking at once, at a constant rate) and v T = {} m (coasting, then stopping instantly), the upper end excluded; check the units and that distance and time are the same stop",
                    i + 1, d, v, t, round6(lo), round6(hi)
                )));
            }
            let decel = v * v / (2.0 * (hi - d));
            if decel > MAX_DECEL {
                return Err(TableError::Distance(format!(
                    "item {}: {} m in {} s from {} m/s needs a deceleration of {} m/s^2 after a dead time of {} s; above {MAX_DECEL} m/s^2 (about 50 g, the bound of motion.decel) no robot stops",
                    i + 1, d, t, v, round6(decel), round6(2.0 * d / v - t)
                )));
            }
        }
        let mut s = Self { category, n, speed: [0.0; MAX_POINTS], distance: [0.0; MAX_POINTS], time: [0.0; MAX_POINTS] };
        s.speed[..n].copy_from_slice(speed);
        s.distance[..n].copy_from_slice(distance);
        s.time[..n].copy_from_slice(time);
        Ok(s)
    }

    /// The table's points (v m/s, D m, T s).
    pub fn points(&self) -> impl Iterator<Item = (f64, f64, f64)> + '_ {
        (0..self.n).map(|i| (self.speed[i], self.distance[i], self.time[i]))
    }

    /// The largest speed in the table, m/s: above it the stop is not known.
    pub fn max_speed(&self) -> f64 {
        self.speed[self.n - 1]
    }

    /// True when the table holds the stop from `v` (0 < v <= the largest speed).
    pub fn covers(&self, v: f64) -> bool {
        v > 0.0 && v <= self.max_speed()
    }

    /// D(v) and T(v), m and s, interpolated (see the module docs); `None` above the table.
    pub fn at(&self, v: f64) -> Option<(f64, f64)> {
        if v.is_nan() || v < 0.0 || v > self.max_speed() {
            return None;
        }
        let (v1, d1, t1) = (self.speed[0], self.distance[0], self.time[0]);
        if v <= v1 {
            return Some((d1 * v / v1, t1));
        }
        let i = (1..self.n).find(|&i| v <= self.speed[i]).unwrap_or(self.n - 1);
        if v == self.speed[i] {
            return Some((self.distance[i], self.time[i]));
        }
        let (va, vb) = (self.speed[i - 1], self.speed[i]);
        let w = (v - va) / (vb - va);
        let lerp = |a: &[f64; MAX_POINTS]| a[i - 1] + w * (a[i] - a[i - 1]);
        Some((lerp(&self.distance), lerp(&self.time)))
    }

    /// Stopping distance from the stop signal at `v`, m; `None` above the table.
    pub fn distance(&self, v: f64) -> Option<f64> {
        self.at(v).map(|(d, _)| d)
    }

    /// The dead time and deceleration that reproduce D(v) and T(v) (see the module docs); `None`
    /// above the table. At v = 0 the first point's pair (nothing moves; any pair stops at once).
    pub fn equivalent(&self, v: f64) -> Option<Equivalent> {
        let v = if v > 0.0 { v } else { self.speed[0] };
        let (d, t) = self.at(v)?;
        let mut e = Equivalent { dead_time: 2.0 * d / v - t, decel: 0.0, adjusted: None };
        // Rounding on the edge D = v T / 2 (no dead time) is not an adjustment.
        if e.dead_time < -1e-12 * t.max(1.0) {
            e.adjusted = Some("D < v T / 2 between the table's points: dead time clamped to 0, the deceleration keeps the distance D (the stop is shorter in time than T)");
        }
        e.dead_time = e.dead_time.max(0.0);
        // D = v DT + v^2 / 2d.
        e.decel = v * v / (2.0 * (d - v * e.dead_time)).max(f64::MIN_POSITIVE);
        if e.decel > MAX_DECEL {
            // D > v T - v^2 / 2 d_max: the interpolation (v T is convex in v, D linear) can reach
            // past what a stop from v covers in T. Keep the distance, lengthen the time.
            e.decel = MAX_DECEL;
            e.dead_time = (d / v - v / (2.0 * MAX_DECEL)).max(0.0);
            e.adjusted = Some("between the table's points the interpolated distance needs a deceleration above 500 m/s^2 in the interpolated time: braking at 500 m/s^2 after a longer dead time, so the distance D is kept (the stop lasts longer than T)");
        }
        Some(e)
    }
}

fn round6(x: f64) -> f64 {
    format!("{x:.6e}").parse().unwrap_or(x)
}

/// What is wrong with a table, by the column to blame.
#[derive(Debug, Clone, PartialEq)]
pub enum TableError {
    /// The speeds.
    Speed(String),
    /// The distances (or a point's physics).
    Distance(String),
    /// The times.
    Time(String),
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table() -> StoppingTable {
        // D = v DT + v^2 / 2d with DT = 0.1 s, d = 5 m/s^2 at 0.5, 1, 2 m/s.
        let v = [0.5, 1.0, 2.0];
        let d: Vec<f64> = v.iter().map(|v| v * 0.1 + v * v / 10.0).collect();
        let t: Vec<f64> = v.iter().map(|v| 0.1 + v / 5.0).collect();
        StoppingTable::new(1, &v, &d, &t).unwrap()
    }

    #[test]
    fn equivalent_reproduces_the_stop_at_every_point() {
        let s = table();
        for (v, d, t) in s.points().collect::<Vec<_>>() {
            let e = s.equivalent(v).unwrap();
            assert!((e.dead_time - 0.1).abs() < 1e-12 && (e.decel - 5.0).abs() < 1e-9, "{v}: {e:?}");
            assert!((v * e.dead_time + v * v / (2.0 * e.decel) - d).abs() < 1e-12);
            assert!((e.dead_time + v / e.decel - t).abs() < 1e-12);
            assert!(e.adjusted.is_none());
        }
    }

    #[test]
    fn interpolates_linearly_scales_below_and_refuses_above() {
        let s = table();
        let (d1, t1) = s.at(1.0).unwrap();
        let (d2, t2) = s.at(2.0).unwrap();
        let (d, t) = s.at(1.5).unwrap();
        assert!((d - 0.5 * (d1 + d2)).abs() < 1e-15 && (t - 0.5 * (t1 + t2)).abs() < 1e-15);
        // Below: through the origin, never below the physical stop (D/v grows with v).
        let (d, t) = s.at(0.25).unwrap();
        assert!((d - 0.075 * 0.25 / 0.5).abs() < 1e-15 && t == 0.2);
        assert!(d >= 0.25 * 0.1 + 0.25 * 0.25 / 10.0);
        assert!(s.at(2.0 + 1e-9).is_none() && s.equivalent(2.1).is_none() && !s.covers(2.1));
    }

    #[test]
    fn between_points_the_equivalent_keeps_the_distance() {
        // T not decreasing makes v T convex in v, so the linear D stays >= v T / 2 between points
        // that satisfy it: DT >= 0 everywhere. It can rise above v T - v^2 / 2 d_max (the second
        // table, steep braking at its first point): braking at d_max then lasts longer than T.
        let steep = StoppingTable::new(1, &[0.1, 2.0], &[0.0199, 0.5], &[0.2, 0.5]).unwrap();
        let mut adjusted = 0;
        for s in [StoppingTable::new(0, &[1.0, 3.0], &[0.1, 0.9], &[0.2, 0.6]).unwrap(), steep, table()] {
            for i in 1..=200 {
                let v = s.max_speed() * i as f64 / 200.0;
                let (d, t) = s.at(v).unwrap();
                let e = s.equivalent(v).unwrap();
                assert!(e.dead_time >= 0.0 && e.decel > 0.0 && e.decel <= MAX_DECEL, "{v}: {e:?}");
                assert!((v * e.dead_time + v * v / (2.0 * e.decel) - d).abs() < 1e-12, "{v}: the distance must be D");
                let too_steep = v * v / (2.0 * (v * t - d)) > MAX_DECEL || d >= v * t;
                assert_eq!(e.adjusted.is_some(), too_steep, "{v}: {e:?}");
                if too_steep {
                    adjusted += 1;
                    assert!(e.dead_time + v / e.decel > t);
                } else {
                    assert!((e.dead_time + v / e.decel - t).abs() < 1e-9, "{v}");
                }
            }
        }
        assert!(adjusted > 0, "the steep table must exercise the adjustment");
    }

    #[test]
    fn refuses_what_no_stop_does() {
        let bad = |v: &[f64], d: &[f64], t: &[f64]| StoppingTable::new(0, v, d, t).unwrap_err();
        assert!(matches!(bad(&[1.0, 0.5], &[0.1, 0.2], &[0.2, 0.3]), TableError::Speed(m) if m.contains("increase strictly")));
        assert!(matches!(bad(&[0.5, 1.0], &[0.2, 0.1], &[0.3, 0.3]), TableError::Distance(m) if m.contains("must increase")));
        assert!(matches!(bad(&[0.5, 1.0], &[0.1, 0.2], &[0.4, 0.3]), TableError::Time(m) if m.contains("must not decrease")));
        // D > v T: faster than the speed it stops from.
        assert!(matches!(bad(&[1.0], &[0.3], &[0.2]), TableError::Distance(m) if m.contains("v T = 0.2 m")));
        // D < v T / 2.
        assert!(matches!(bad(&[1.0], &[0.05], &[0.2]), TableError::Distance(m) if m.contains("v T / 2 = 0.1 m")));
        // D just under v T: 2500 m/s^2.
        assert!(matches!(bad(&[1.0], &[0.1998], &[0.2]), TableError::Distance(m) if m.contains("500 m/s^2")));
        assert!(matches!(bad(&[1.0, 2.0], &[0.1], &[0.2, 0.3]), TableError::Distance(m) if m.contains("one distance per speed")));
        assert!(matches!(bad(&[], &[], &[]), TableError::Speed(_)));
    }
}
