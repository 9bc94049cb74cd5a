//! Speed and separation monitoring (ISO/TS 15066:2016, clause 5.5.4) on the commanded velocity,
//! independent of the potential field: whatever the field and its gains command, the speed that
//! leaves here is at most what the separation to the nearest sensed obstacle allows, and never above
//! the configured cap.
//!
//! # The protective separation (ISO/TS 15066, eq 1 of 5.5.4.2.3)
//!
//! `S_p = S_h + S_r + S_s + C + Z_d + Z_r` with
//!
//! * `S_h = v_h (T_r + T_s)`: the human approaching at `v_h` (ISO 13855:2010, 6.2 / 8: 1.6 m/s for
//!   a walking person or a reaching arm beyond 0.5 m; 2.0 m/s close by) during the robot's reaction
//!   time `T_r` and stopping time `T_s`;
//! * `S_r = v_r T_r`: the robot moving on at its commanded speed `v_r` until it reacts;
//! * `S_s = v_r T_s / 2`: the robot braking from `v_r` to rest in `T_s` (constant deceleration);
//! * `C`: the intrusion distance (ISO 13855, 5.3: how far a body part can reach into the sensing
//!   field before it is detected); `Z_d`, `Z_r`: the sensor's and the robot's position uncertainty.
//!
//! The separation `S` used is a lower bound of the true one *now*, built from the last sensed frame:
//! `S = S_capture - |p - p_capture| - v_h age`: the distance the sensor measured at capture, less the
//! distance the tool has moved since and the distance a person could have covered since the image
//! was taken (`age` counts from capture, so capture, fit and transmission latency are all in it).
//! Stale data therefore stops the robot by distance, not only by a timeout.
//!
//! Solving `S_p(v_r) <= S` for `v_r` gives the speed limit
//! `v_max = (S - v_h (T_r + T_s) - C - Z_d - Z_r) / (T_r + T_s / 2)`, clamped to `[0, cap]`.
//! When the numerator is not positive the robot is in a protective stop (command zero). It resumes by
//! itself when the separation grows again (ISO 10218-1:2011, 5.10.6: SSM may restart automatically).
//!
//! The clamp is the last operation on the command. Lengths are bounded from above by
//! `max + min / 2` (no square root; never below the true length, at most 11.8 % above), computed
//! without overflow, so a command of thousands of m/s from extreme but valid gains, or a non-finite
//! one, ends at or below the cap, or at zero.

use core::cmp::Ordering;

use super::num::Real;

/// Parameters of the monitor. All in metres, seconds, metres per second.
#[derive(Clone, Copy, Debug)]
pub struct SsmParams<R> {
    /// `v_h`, the human's approach speed (ISO 13855: 1.6 m/s).
    pub human_speed_mps: R,
    /// `T_r`, from the command leaving the monitor until the robot starts to brake (one control
    /// period plus the drive's own delay). The sensing latency is not in it: it is in `age`.
    pub reaction_time_s: R,
    /// `T_s`, the robot's stopping time from the cap speed.
    pub stopping_time_s: R,
    /// `C + Z_d + Z_r`: intrusion distance plus the sensor's and the robot's uncertainty.
    pub margin_m: R,
    /// Hard cap on the commanded speed (the configured cruise speed).
    pub speed_cap_mps: R,
}

/// What the sensor saw in the last frame.
#[derive(Clone, Copy, Debug)]
pub struct Sensed<R> {
    /// Distance from the tool to the nearest sensed obstacle when the image was taken, m.
    pub separation_m: R,
    /// Tool position when the image was taken, m.
    pub tool_x_m: R,
    /// See `tool_x_m`.
    pub tool_y_m: R,
    /// Time since the image was taken, s.
    pub age_s: R,
}

/// What the monitor did this step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SafeState {
    /// The command passed unchanged.
    Run,
    /// The command was scaled down to the limit.
    Slow,
    /// Separation below the protective separation: zero command.
    ProtectiveStop,
    /// No sensed frame yet: zero command.
    NoData,
}

/// The monitored command.
#[derive(Clone, Copy, Debug)]
pub struct SafeCommand<R> {
    /// Velocity along x, m/s.
    pub vx: R,
    /// Velocity along y, m/s.
    pub vy: R,
    /// The speed limit that applied, m/s.
    pub limit_mps: R,
    /// The lower bound of the separation now, m.
    pub separation_m: R,
    /// What happened.
    pub state: SafeState,
}

/// The monitor. Stateless between steps apart from its parameters (and three numbers derived from
/// them once, so that a step costs one division for the limit and two for a scaled command).
#[derive(Clone, Copy, Debug)]
pub struct SafeController<R> {
    params: SsmParams<R>,
    /// `v_h (T_r + T_s) + C + Z_d + Z_r`: the separation at which the limit reaches zero, m.
    stop_separation_m: R,
    /// `T_r + T_s / 2`, s.
    per_speed_s: R,
    /// One half.
    half: R,
}

impl<R: Real> SafeController<R> {
    /// A monitor with these parameters.
    pub fn new(params: SsmParams<R>) -> Self {
        let half = R::ONE.div(R::from_int(2));
        SafeController {
            stop_separation_m: params.human_speed_mps.mul(params.reaction_time_s.add(params.stopping_time_s)).add(params.margin_m),
            per_speed_s: params.reaction_time_s.add(params.stopping_time_s.mul(half)),
            params,
            half,
        }
    }

    /// The parameters.
    pub fn params(&self) -> &SsmParams<R> {
        &self.params
    }

    /// The speed limit for a separation lower bound `s`, m/s (0: protective stop).
    pub fn speed_limit(&self, s: R) -> R {
        let cap = self.params.speed_cap_mps;
        let free = s.sub(self.stop_separation_m);
        // NaN-safe: only a positive margin gives a positive limit.
        if free > R::ZERO {
            // `free / per_speed <= cap` without dividing when the cap applies anyway.
            if free >= cap.mul(self.per_speed_s) {
                cap
            } else {
                let v = free.div(self.per_speed_s);
                if v < cap {
                    v
                } else {
                    cap
                }
            }
        } else {
            R::ZERO
        }
    }

    /// The monitored command for a requested `(vx, vy)` with the tool at `(x, y)`.
    ///
    /// Lengths are bounded from above without a square root: `|(a, b)| <= max + min / 2` (within
    /// 11.8 % above). The tool's motion since capture is over-estimated by it (the separation is
    /// under-estimated: conservative), and a command is passed unchanged only when that bound of its
    /// speed is within the limit, and otherwise scaled to the bound: its speed ends between 89.4 %
    /// of the limit and the limit.
    pub fn limit(&self, vx: R, vy: R, x: R, y: R, sensed: Option<&Sensed<R>>) -> SafeCommand<R> {
        let stop = |state, separation_m| SafeCommand { vx: R::ZERO, vy: R::ZERO, limit_mps: R::ZERO, separation_m, state };
        let Some(f) = sensed else { return stop(SafeState::NoData, R::ZERO) };
        let moved = self.norm_bound(x.sub(f.tool_x_m), y.sub(f.tool_y_m));
        let s = f.separation_m.sub(moved).sub(self.params.human_speed_mps.mul(f.age_s));
        let limit = self.speed_limit(s);
        // NaN-safe: anything but a positive limit stops.
        if limit.partial_cmp(&R::ZERO) != Some(Ordering::Greater) {
            return stop(SafeState::ProtectiveStop, s);
        }
        // `speed` may saturate in fixed point; it is then far above any limit.
        let speed = self.norm_bound(vx, vy);
        if speed <= limit {
            return SafeCommand { vx, vy, limit_mps: limit, separation_m: s, state: SafeState::Run };
        }
        let (ax, ay) = (vx.abs(), vy.abs());
        let m = if ax > ay { ax } else { ay };
        if speed > R::ZERO && m > R::ZERO {
            // Unit components `v / m` in [-1, 1] (no overflow), the bound over `m` in [1, 1.5]:
            // the result's bound is the limit (to rounding).
            let (ux, uy) = (vx.div(m), vy.div(m));
            let (bx, by) = (ux.abs(), uy.abs());
            let r = R::ONE.add(if bx < by { bx } else { by }.mul(self.half));
            let k = limit.div(r);
            SafeCommand { vx: ux.mul(k), vy: uy.mul(k), limit_mps: limit, separation_m: s, state: SafeState::Slow }
        } else {
            // Not comparable (NaN): stop.
            stop(SafeState::ProtectiveStop, s)
        }
    }

    /// `max(|a|, |b|) + min(|a|, |b|) / 2`: at least `sqrt(a^2 + b^2)` (since `max >= 3 min / 4`),
    /// at most 11.8 % more; saturates in fixed point, NaN in gives NaN.
    fn norm_bound(&self, a: R, b: R) -> R {
        let (aa, bb) = (a.abs(), b.abs());
        if !(aa >= R::ZERO && bb >= R::ZERO) {
            return a.add(b);
        }
        let (m, n) = if aa > bb { (aa, bb) } else { (bb, aa) };
        m.add(n.mul(self.half))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::avoidance::num::I16F16;

    fn params<R: Real>() -> SsmParams<R> {
        SsmParams {
            human_speed_mps: R::from_f64(1.6),
            reaction_time_s: R::from_f64(0.01),
            stopping_time_s: R::from_f64(0.1),
            margin_m: R::from_f64(0.02),
            speed_cap_mps: R::from_f64(0.25),
        }
    }

    fn sensed<R: Real>(sep: f64, age: f64) -> Sensed<R> {
        Sensed { separation_m: R::from_f64(sep), tool_x_m: R::ZERO, tool_y_m: R::ZERO, age_s: R::from_f64(age) }
    }

    #[test]
    fn limit_follows_the_protective_separation() {
        let c = SafeController::new(params::<f64>());
        // S_h + C = 1.6 * 0.11 + 0.02 = 0.196 m: below it, a protective stop.
        assert_eq!(c.speed_limit(0.19), 0.0);
        // 10 mm above it: v = 0.01 / (0.01 + 0.05) = 0.1667 m/s.
        assert!((c.speed_limit(0.206) - 0.01 / 0.06).abs() < 1e-9);
        assert_eq!(c.speed_limit(5.0), 0.25, "capped");
        // The limit satisfies S_p(v) <= S: check eq 1 directly.
        for s in [0.2, 0.21, 0.25, 0.3] {
            let v = c.speed_limit(s);
            let sp = 1.6 * 0.11 + v * 0.01 + v * 0.1 / 2.0 + 0.02;
            assert!(sp <= s + 1e-12, "S_p {sp} > S {s}");
        }
    }

    #[test]
    fn age_and_motion_since_capture_eat_the_separation() {
        let c = SafeController::new(params::<f64>());
        let fresh = c.limit(0.25, 0.0, 0.0, 0.0, Some(&sensed(0.5, 0.0)));
        assert_eq!(fresh.state, SafeState::Run);
        // 0.2 s old: a person may have come 0.32 m closer.
        let old = c.limit(0.25, 0.0, 0.0, 0.0, Some(&sensed(0.5, 0.2)));
        assert_eq!(old.state, SafeState::ProtectiveStop);
        assert_eq!((old.vx, old.vy), (0.0, 0.0));
        // The tool moved 0.31 m since capture.
        let moved = c.limit(0.25, 0.0, 0.31, 0.0, Some(&sensed(0.5, 0.0)));
        assert_eq!(moved.state, SafeState::ProtectiveStop);
        assert_eq!(c.limit(0.1, 0.0, 0.0, 0.0, None).state, SafeState::NoData);
    }

    #[test]
    fn the_length_bound_is_above_the_length_and_scaled_commands_end_near_the_limit() {
        let c = SafeController::new(params::<f64>());
        let q = SafeController::new(params::<I16F16>());
        let far = sensed::<f64>(10.0, 0.0);
        for k in 0..360 {
            let a = (k as f64).to_radians();
            for len in [0.01, 0.2, 0.3, 1.0, 50.0] {
                let (vx, vy) = (len * a.cos(), len * a.sin());
                let b = c.norm_bound(vx, vy);
                assert!(b >= len * (1.0 - 1e-12) && b <= len * 1.1181, "{a} {len}: {b}");
                let out = c.limit(vx, vy, 0.0, 0.0, Some(&far));
                let sp = out.vx.hypot(out.vy);
                if len <= 0.25 / 1.1181 {
                    assert_eq!((out.vx, out.vy), (vx, vy), "passed unchanged");
                } else if len > 0.25 {
                    assert!(sp <= 0.25 + 1e-12 && sp >= 0.25 / 1.1181, "{a} {len}: {sp}");
                } else {
                    assert!(sp <= 0.25 + 1e-12);
                }
                let (qx, qy) = (I16F16::from_f64(vx), I16F16::from_f64(vy));
                let o = q.limit(qx, qy, I16F16::ZERO, I16F16::ZERO, Some(&sensed(10.0, 0.0)));
                assert!(o.vx.to_f64().hypot(o.vy.to_f64()) <= 0.2502, "I16F16 {a} {len}");
            }
        }
        // Motion since capture is over-estimated, never under: the separation left is smaller.
        let moved = c.limit(0.0, 0.0, 0.03, 0.04, Some(&sensed(0.5, 0.0)));
        assert!(moved.separation_m <= 0.5 - 0.05 + 1e-12 && moved.separation_m >= 0.5 - 0.05 * 1.1181);
    }

    #[test]
    fn extreme_and_non_finite_commands_are_capped_or_stopped() {
        let c = SafeController::new(params::<f64>());
        let far = sensed::<f64>(10.0, 0.0);
        for (vx, vy) in [(3000.0, -4000.0), (1e300, 1e300), (-0.3, 0.0)] {
            let out = c.limit(vx, vy, 0.0, 0.0, Some(&far));
            let sp = (out.vx * out.vx + out.vy * out.vy).sqrt();
            assert!(sp <= 0.25 + 1e-12, "{vx} {vy} -> {sp}");
            assert_eq!(out.state, SafeState::Slow);
        }
        let nan = c.limit(f64::NAN, 0.0, 0.0, 0.0, Some(&far));
        assert_eq!((nan.vx, nan.vy, nan.state), (0.0, 0.0, SafeState::ProtectiveStop));
        let nan_sep = c.limit(0.1, 0.0, 0.0, 0.0, Some(&sensed(f64::NAN, 0.0)));
        assert_eq!(nan_sep.state, SafeState::ProtectiveStop);

        // The target's number type: saturated components still end at the cap.
        let q = SafeController::new(params::<I16F16>());
        let big = I16F16::from_f64(30000.0);
        let out = q.limit(big, big, I16F16::ZERO, I16F16::ZERO, Some(&sensed(10.0, 0.0)));
        let sp = (out.vx.to_f64().powi(2) + out.vy.to_f64().powi(2)).sqrt();
        assert!(sp <= 0.2501, "{sp}");
        // Scaled to the bound max + min / 2 = 1.5 m for a diagonal of true length sqrt 2 m.
        assert!(sp > 0.25 * 2f64.sqrt() / 1.5 - 1e-3, "{sp}");
    }
}
