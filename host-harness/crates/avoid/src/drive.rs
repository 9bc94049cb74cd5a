//! The robot's drive as the speed-and-separation monitor assumes it (ISO/TS 15066 5.5.4.2.3,
//! `firmware/src/avoidance/safe.rs`): `S_r = v_r T_r` and `S_s = v_r T_s / 2`.
//!
//! * **Reaction.** A command leaves the monitor at the start of a control step and stands for the
//!   whole step (the loop's zero-order hold: that is the control period in `T_r`); the drive starts
//!   to follow it `T_r - dt` later (the drive's own delay; the loader refuses `T_r < dt`). The
//!   sensing latency is not here: it is the frame's age.
//! * **Braking.** A command that asks the robot to slow down along its motion is followed at a
//!   deceleration of at most `a = cap / T_s` (`T_s`, the stopping time, is given from the cap):
//!   from `v` the robot stops within `v T_s / cap <= T_s`, over `v^2 T_s / (2 cap) <= v T_s / 2`.
//!   The velocity then moves in a straight line towards the command, at `a`: every velocity on the
//!   way is a convex combination of the old one and the command, so no direction is approached
//!   faster than by either. A command that does not slow the motion down (its component along the
//!   current velocity at least the current speed; from rest, any) is taken at once: the monitor
//!   does not budget acceleration, and taking it at once is the pessimistic choice for the verdict.
//!   `T_s = 0` brakes at once.
//!
//! The motion within a step is exact: constant-acceleration pieces, sampled by the verdict's swept
//! distance through [`Motion::at`].

use std::collections::VecDeque;

use crate::scene::Avoid;

/// One piece of a step's motion: constant acceleration from `t0` for `dur` seconds.
#[derive(Clone, Copy, Debug)]
struct Piece {
    t0: f64,
    p0: [f64; 2],
    u0: [f64; 2],
    acc: [f64; 2],
    dur: f64,
}

impl Piece {
    fn at(&self, t: f64) -> [f64; 2] {
        let s = (t - self.t0).clamp(0.0, self.dur);
        [self.p0[0] + self.u0[0] * s + 0.5 * self.acc[0] * s * s, self.p0[1] + self.u0[1] * s + 0.5 * self.acc[1] * s * s]
    }
}

/// The tool's motion over one control step.
#[derive(Clone, Debug)]
pub struct Motion {
    pieces: Vec<Piece>,
    /// Where the tool is at the step's end, m.
    pub end_m: [f64; 2],
    /// The tool's velocity at the step's end, m/s.
    pub end_mps: [f64; 2],
    /// The path length over the step, m.
    pub length_m: f64,
    /// The largest speed during the step, m/s.
    pub max_speed_mps: f64,
    /// The velocities at the pieces' ends (and the step's start): every velocity of the step is a
    /// convex combination of two consecutive ones, m/s.
    pub velocities_mps: Vec<[f64; 2]>,
}

impl Motion {
    /// The tool's position at time `t` (clamped to the step), m.
    pub fn at(&self, t: f64) -> [f64; 2] {
        match self.pieces.iter().rev().find(|q| t >= q.t0) {
            Some(q) => q.at(t),
            None => self.pieces.first().map_or(self.end_m, |q| q.p0),
        }
    }
}

/// The drive: the commands on their way to it, and its velocity.
#[derive(Clone, Debug)]
pub struct Drive {
    /// `T_r - dt`, s (at least 0).
    pub delay_s: f64,
    /// `cap / T_s`, m/s^2 (infinite when `T_s` is 0).
    pub decel_mps2: f64,
    queue: VecDeque<(f64, [f64; 2])>,
    target: [f64; 2],
    u: [f64; 2],
}

const EPS_S: f64 = 1e-12;

impl Drive {
    /// The drive of a scene, at rest.
    pub fn new(scene: &Avoid) -> Self {
        let s = &scene.safety;
        let decel = if s.stopping_time_s > 0.0 { scene.speed_mps / s.stopping_time_s } else { f64::INFINITY };
        Drive { delay_s: (s.reaction_time_s - scene.dt_s).max(0.0), decel_mps2: decel, queue: VecDeque::new(), target: [0.0; 2], u: [0.0; 2] }
    }

    /// A command leaving the monitor at `t_s`: the drive follows it from `t_s + delay_s`.
    pub fn command(&mut self, t_s: f64, v: [f64; 2]) {
        self.queue.push_back((t_s + self.delay_s, v));
    }

    /// The velocity now, m/s.
    pub fn velocity_mps(&self) -> [f64; 2] {
        self.u
    }

    /// Whether it still moves, or a command on its way may make it move.
    pub fn moving(&self) -> bool {
        self.u != [0.0, 0.0] || self.target != [0.0, 0.0] || self.queue.iter().any(|c| c.1 != [0.0, 0.0])
    }

    /// Moves the tool from `p` over `[t0, t1]`.
    pub fn advance(&mut self, p: [f64; 2], t0: f64, t1: f64) -> Motion {
        let mut pieces = Vec::new();
        let (mut t, mut p, mut length, mut vmax) = (t0, p, 0.0f64, norm(self.u));
        let mut velocities = vec![self.u];
        while t < t1 - EPS_S {
            while self.queue.front().is_some_and(|c| c.0 <= t + EPS_S) {
                if let Some((_, v)) = self.queue.pop_front() {
                    self.target = v;
                }
            }
            let until = self.queue.front().map_or(t1, |c| c.0.min(t1));
            let c = self.target;
            let (u, sp) = (self.u, norm(self.u));
            // Taken at once: no slowing down along the motion.
            if sp == 0.0 || dot(c, u) >= sp * sp || !self.decel_mps2.is_finite() {
                self.u = c;
            }
            let u = if self.u == c { c } else { u };
            let dv = [c[0] - u[0], c[1] - u[1]];
            let gap = norm(dv);
            let mut left = until - t;
            if gap > 0.0 {
                // Towards the command at the drive's deceleration.
                let a = [dv[0] / gap * self.decel_mps2, dv[1] / gap * self.decel_mps2];
                let dur = (gap / self.decel_mps2).min(left);
                let q = Piece { t0: t, p0: p, u0: u, acc: a, dur };
                let end = q.at(t + dur);
                length += ramp_length(u, a, dur);
                p = end;
                t += dur;
                left -= dur;
                self.u = if dur * self.decel_mps2 >= gap { c } else { [u[0] + a[0] * dur, u[1] + a[1] * dur] };
                pieces.push(q);
                velocities.push(self.u);
            }
            if left > EPS_S {
                let c = self.u;
                let q = Piece { t0: t, p0: p, u0: c, acc: [0.0; 2], dur: left };
                p = q.at(t + left);
                length += norm(c) * left;
                t += left;
                pieces.push(q);
                velocities.push(c);
                vmax = vmax.max(norm(c));
            } else {
                t = until.max(t);
            }
            vmax = vmax.max(norm(self.u));
        }
        Motion { pieces, end_m: p, end_mps: self.u, length_m: length, max_speed_mps: vmax, velocities_mps: velocities }
    }
}

fn norm(v: [f64; 2]) -> f64 {
    v[0].hypot(v[1])
}

fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// The length of the path `u s + a s^2 / 2` over `[0, dur]` (the speed is convex in `s`: sampled
/// finely enough for 1e-9 m; a straight braking ramp is exact).
fn ramp_length(u: [f64; 2], a: [f64; 2], dur: f64) -> f64 {
    let n = 64;
    let mut len = 0.0;
    let mut prev = [0.0, 0.0];
    for i in 1..=n {
        let s = dur * i as f64 / n as f64;
        let q = [u[0] * s + 0.5 * a[0] * s * s, u[1] * s + 0.5 * a[1] * s * s];
        len += norm([q[0] - prev[0], q[1] - prev[1]]);
        prev = q;
    }
    len
}

#[cfg(test)]
mod tests {
    use super::*;

    fn drive(delay: f64, decel: f64) -> Drive {
        Drive { delay_s: delay, decel_mps2: decel, queue: VecDeque::new(), target: [0.0; 2], u: [0.0; 2] }
    }

    /// From 0.25 m/s with `T_s` = 0.1 s (2.5 m/s^2) a stop takes 0.1 s and 12.5 mm
    /// (`v T_s / 2`), after the drive's delay at the old speed.
    #[test]
    fn a_stop_brakes_over_t_s_after_the_delay() {
        let mut d = drive(0.01, 2.5);
        let dt = 0.01;
        d.command(0.0, [0.25, 0.0]);
        let mut p = [0.0, 0.0];
        let mut t = 0.0;
        // Up to speed: the first command is followed after the delay.
        let m = d.advance(p, t, t + dt);
        assert_eq!(m.end_m, [0.0, 0.0]);
        p = m.end_m;
        t += dt;
        d.command(t, [0.25, 0.0]);
        p = d.advance(p, t, t + dt).end_m;
        t += dt;
        assert!((p[0] - 0.0025).abs() < 1e-12, "{p:?}");
        // Stop at t = 0.02: the drive still runs 0.25 m/s until 0.03, then brakes 0.1 s.
        let x0 = p[0];
        let mut len = 0.0;
        for _ in 0..30 {
            d.command(t, [0.0, 0.0]);
            let m = d.advance(p, t, t + dt);
            len += m.length_m;
            p = m.end_m;
            t += dt;
        }
        assert!((p[0] - x0 - (0.0025 + 0.0125)).abs() < 1e-9, "{}", p[0] - x0);
        assert!((len - (0.0025 + 0.0125)).abs() < 1e-6, "{len}");
        assert!(!d.moving());
    }

    /// A reversal passes through rest at the drive's deceleration; never faster than either end in
    /// any direction.
    #[test]
    fn a_reversal_brakes_first() {
        let mut d = drive(0.0, 2.5);
        d.command(0.0, [0.25, 0.0]);
        let m = d.advance([0.0; 2], 0.0, 0.01);
        assert_eq!(m.end_mps, [0.25, 0.0]);
        d.command(0.01, [-0.25, 0.0]);
        let m = d.advance(m.end_m, 0.01, 0.02);
        assert!((m.end_mps[0] - 0.225).abs() < 1e-12, "{:?}", m.end_mps);
        assert!(m.max_speed_mps <= 0.25 + 1e-12);
        // Speeding up is taken at once.
        let mut d = drive(0.0, 2.5);
        d.command(0.0, [0.1, 0.0]);
        d.advance([0.0; 2], 0.0, 0.01);
        d.command(0.01, [0.2, 0.0]);
        assert_eq!(d.advance([0.001, 0.0], 0.01, 0.02).end_mps, [0.2, 0.0]);
    }
}
