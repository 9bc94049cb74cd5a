//! Potential-field command (eq 74-79) with speed scaling from the field height and a fail-safe on the
//! age of the weights.
//!
//! * Attraction (eq 74): `F_a = k_a e / |e|`, `e = p_goal - p`. Inside `capture_radius_m` the
//!   magnitude falls linearly to zero (`e / capture_radius`) so the tool settles on the goal instead
//!   of chattering around it (the thesis's constant magnitude never stops).
//! * Vortex repulsion (eq 76): `F_r = s k_r [df*/dy, -df*/dx]`, `s = +/-1`. The sign comes from the
//!   direction of motion `d = e / |e|`: `s` makes `F_r . d >= 0`, so the vortex carries the tool on
//!   around the hill rather than back. It is latched while `f*` at the tool stays above
//!   `latch_height_m` (and chosen afresh below it) so it cannot flip on the hill's axis.
//! * Command (eq 77-78): `p' = (F_a + F_r) * speed_scale(f*) * watchdog(age)`.
//! * Speed scaling: 1 below `slow_height_m`, 0 at and above `stop_height_m`, linear between.
//! * Fail-safe ([`Watchdog`]): full speed while the weights are younger than `slow_after_ms`, then a
//!   linear ramp to zero at `stop_after_ms`; zero with no weights at all.

use super::field::FieldSample;
use super::num::Real;

/// Which repulsion the step uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Repulsion {
    /// Eq 76: the vortex `s k_r [df*/dy, -df*/dx]`; `sign` 0 chooses it from the motion (see module
    /// docs), +1 or -1 fixes it.
    Vortex {
        /// 0 = from the direction of motion, otherwise the fixed sign.
        sign: i8,
    },
    /// Eq 75: `-k_r grad f*` (radial; has local minima, kept for comparison).
    Gradient,
}

/// Gains and thresholds of the step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gains<R> {
    /// Repulsion law.
    pub repulsion: Repulsion,
    /// `k_a`, the cruise speed towards the goal, m/s (eq 74).
    pub k_att: R,
    /// `k_r`, m/s per unit gradient (eq 76).
    pub k_rep: R,
    /// Radius around the goal inside which attraction falls off linearly, m.
    pub capture_radius_m: R,
    /// Field height above which the vortex sign is latched, m.
    pub latch_height_m: R,
    /// Field height where speed scaling starts, m.
    pub slow_height_m: R,
    /// Field height at which the command is zero, m (set above any reachable height to disable).
    pub stop_height_m: R,
    /// Ours (`false`: eq 74-78 as the thesis wrote them): the vortex's magnitude bounded by `k_att`,
    /// and instead of scaling the whole command by the height, a radial barrier: the command's
    /// uphill rate `v . grad f*` is at most `k_att (stop - f*) / (stop - slow)` above `slow_height_m`
    /// and zero at `stop_height_m` (the excess removed along the gradient), so the tool never climbs
    /// a hill but may still move along it or down.
    pub bounded: bool,
}

/// Fail-safe on the age of the last good weights.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Watchdog {
    /// Age up to which the command is not reduced, ms.
    pub slow_after_ms: u32,
    /// Age at and after which the command is zero, ms.
    pub stop_after_ms: u32,
}

impl Watchdog {
    /// Speed factor in `[0, 1]` for weights `age_ms` old (`None`: no weights ever received).
    pub fn factor<R: Real>(&self, age_ms: Option<u32>) -> R {
        let age = match age_ms {
            Some(a) => a,
            None => return R::ZERO,
        };
        if age <= self.slow_after_ms {
            R::ONE
        } else if age >= self.stop_after_ms || self.stop_after_ms <= self.slow_after_ms {
            R::ZERO
        } else {
            let left = self.stop_after_ms.saturating_sub(age) as i32;
            let span = self.stop_after_ms.saturating_sub(self.slow_after_ms) as i32;
            R::from_int(left.min(1 << 20)).div(R::from_int(span.min(1 << 20)))
        }
    }
}

/// One velocity command.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Command<R> {
    /// Commanded velocity along x, m/s.
    pub vx: R,
    /// Commanded velocity along y, m/s.
    pub vy: R,
    /// Combined speed factor applied (height scaling times watchdog), `[0, 1]`.
    pub scale: R,
    /// Vortex sign used this step (+1 or -1).
    pub vortex_sign: i8,
}

/// The per-step controller: holds only the latched vortex sign.
#[derive(Clone, Copy, Debug)]
pub struct Controller<R> {
    /// Gains and thresholds.
    pub gains: Gains<R>,
    latched: i8,
    /// `k_att / (stop_height - slow_height)`, 1/s (the barrier's uphill rate per metre below stop).
    barrier_rate: R,
}

impl<R: Real> Controller<R> {
    /// A controller with nothing latched.
    pub fn new(gains: Gains<R>) -> Self {
        let span = gains.stop_height_m.sub(gains.slow_height_m);
        let barrier_rate = if span > R::ZERO { gains.k_att.div(span) } else { R::ZERO };
        Controller { gains, latched: 0, barrier_rate }
    }

    /// Speed factor from the field height at the tool.
    pub fn height_scale(&self, h: R) -> R {
        let g = &self.gains;
        if h <= g.slow_height_m {
            R::ONE
        } else if h >= g.stop_height_m {
            R::ZERO
        } else {
            g.stop_height_m.sub(h).div(g.stop_height_m.sub(g.slow_height_m))
        }
    }

    /// Eq 74-78: the velocity command at `(x, y)` for goal `(gx, gy)`, field `f`, extra factor
    /// `watchdog` (from [`Watchdog::factor`]).
    pub fn command(&mut self, x: R, y: R, gx: R, gy: R, f: &FieldSample<R>, watchdog: R) -> Command<R> {
        let g = self.gains;
        let ex = gx.sub(x);
        let ey = gy.sub(y);
        let dist = if g.bounded {
            // Ours: `|e|` bounded from above by max + min / 2 (no square root): the attraction's
            // speed is 89.4-100 % of k_a by heading, which is what the monitor's own length bound
            // lets through at the cap anyway.
            let (ax, ay) = (ex.abs(), ey.abs());
            if ax > ay {
                ax.add(ay.halve())
            } else {
                ay.add(ax.halve())
            }
        } else {
            ex.mul(ex).add(ey.mul(ey)).sqrt()
        };
        let denom = if dist > g.capture_radius_m { dist } else { g.capture_radius_m };
        let (fax, fay) = if denom > R::ZERO {
            // One division: k_a / max(|e|, r_capture), then two products.
            let k = g.k_att.div(denom);
            (k.mul(ex), k.mul(ey))
        } else {
            (R::ZERO, R::ZERO)
        };

        if g.repulsion == Repulsion::Gradient {
            let scale = self.height_scale(f.height).mul(watchdog);
            let rx = fax.sub(g.k_rep.mul(f.grad_x));
            let ry = fay.sub(g.k_rep.mul(f.grad_y));
            return Command { vx: rx.mul(scale), vy: ry.mul(scale), scale, vortex_sign: 0 };
        }
        let fixed_sign = match g.repulsion {
            Repulsion::Vortex { sign } => sign.signum(),
            Repulsion::Gradient => 0,
        };
        // Vortex direction [df/dy, -df/dx] (eq 76) and its sign from the direction of motion.
        let vx = f.grad_y;
        let vy = f.grad_x.neg();
        let along = vx.mul(ex).add(vy.mul(ey));
        let fresh: i8 = if along < R::ZERO { -1 } else { 1 };
        let sign = if fixed_sign != 0 {
            fixed_sign
        } else if f.height > g.latch_height_m {
            if self.latched == 0 {
                self.latched = fresh;
            }
            self.latched
        } else {
            self.latched = 0;
            fresh
        };
        let mut k = g.k_rep;
        if g.bounded {
            // |F_r| <= k_att: |grad| bounded from above by max + min / 2, and `k` halved until the
            // bound holds (no division; at most 32 halvings, after which `k` is 0 in every type
            // used here): the vortex ends between k_att / 2 and k_att when it had to be bounded.
            let (ax, ay) = (vx.abs(), vy.abs());
            let gb = if ax > ay { ax.add(ay.halve()) } else { ay.add(ax.halve()) };
            let mut p = k.mul(gb);
            for _ in 0..32 {
                if p <= g.k_att {
                    break;
                }
                k = k.halve();
                p = p.halve();
            }
            if p > g.k_att {
                k = R::ZERO;
            }
        }
        let kr = if sign < 0 { k.neg() } else { k };
        let mut cx = fax.add(kr.mul(vx));
        let mut cy = fay.add(kr.mul(vy));

        if !g.bounded {
            let scale = self.height_scale(f.height).mul(watchdog);
            return Command { vx: cx.mul(scale), vy: cy.mul(scale), scale, vortex_sign: sign };
        }
        // The radial barrier: never uphill at `stop_height_m`, less and less so above `slow`.
        if f.height > g.slow_height_m {
            let allow = if f.height < g.stop_height_m { g.stop_height_m.sub(f.height).mul(self.barrier_rate) } else { R::ZERO };
            let up = cx.mul(f.grad_x).add(cy.mul(f.grad_y));
            let g2 = f.grad_x.mul(f.grad_x).add(f.grad_y.mul(f.grad_y));
            if up > allow && g2 > R::ZERO {
                // Remove `e' (grad f*)` with `e' = (up - allow) P`, `P` the power of two in
                // `[1 / g2, 2 / g2)` (no division; at most 32 steps): between the exact projection
                // and twice it, so the uphill rate ends at or below `allow`, never above.
                let (mut q, mut p) = (g2, R::ONE);
                for _ in 0..32 {
                    if q >= R::ONE {
                        break;
                    }
                    q = q.add(q);
                    p = p.add(p);
                }
                for _ in 0..32 {
                    if q < R::ONE.add(R::ONE) {
                        break;
                    }
                    q = q.halve();
                    p = p.halve();
                }
                let e = up.sub(allow).mul(p);
                cx = cx.sub(e.mul(f.grad_x));
                cy = cy.sub(e.mul(f.grad_y));
            }
        }
        Command { vx: cx.mul(watchdog), vy: cy.mul(watchdog), scale: watchdog, vortex_sign: sign }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gains() -> Gains<f64> {
        Gains {
            repulsion: Repulsion::Vortex { sign: 0 },
            k_att: 0.2,
            k_rep: 0.5,
            capture_radius_m: 0.02,
            latch_height_m: 0.01,
            slow_height_m: 0.2,
            stop_height_m: 0.4,
            bounded: false,
        }
    }

    #[test]
    fn attraction_has_constant_magnitude_then_settles() {
        let mut c = Controller::new(gains());
        let flat = FieldSample { height: 0.0, grad_x: 0.0, grad_y: 0.0 };
        let cmd = c.command(0.0, 0.0, 0.3, 0.4, &flat, 1.0);
        assert!((cmd.vx - 0.12).abs() < 1e-12 && (cmd.vy - 0.16).abs() < 1e-12);
        let near = c.command(0.0, 0.0, 0.01, 0.0, &flat, 1.0);
        assert!((near.vx - 0.1).abs() < 1e-12, "half speed at half the capture radius");
    }

    #[test]
    fn vortex_is_tangential_pushes_forward_and_latches() {
        let mut c = Controller::new(gains());
        // Hill ahead on +x: gradient points uphill (+x). Vortex is along y; sign is free (along = 0).
        let f = FieldSample { height: 0.05, grad_x: 1.0, grad_y: 0.2 };
        let cmd = c.command(0.0, 0.0, 1.0, 0.0, &f, 1.0);
        let rx = cmd.vx - 0.2;
        // F_r is perpendicular to the gradient.
        assert!((rx * f.grad_x + cmd.vy * f.grad_y).abs() < 1e-12);
        assert!(rx >= 0.0, "vortex does not push back against the motion");
        let first = cmd.vortex_sign;
        // Gradient tilts the other way: latched sign holds while on the hill.
        let f2 = FieldSample { height: 0.05, grad_x: 1.0, grad_y: -0.2 };
        assert_eq!(c.command(0.0, 0.0, 1.0, 0.0, &f2, 1.0).vortex_sign, first);
        let off = FieldSample { height: 0.0, grad_x: 1.0, grad_y: -0.2 };
        assert_eq!(c.command(0.0, 0.0, 1.0, 0.0, &off, 1.0).vortex_sign, -first);
        // A fixed sign is kept whatever the motion; the radial law of eq 75 pushes down the gradient.
        let mut fixed = Controller::new(Gains { repulsion: Repulsion::Vortex { sign: -1 }, ..gains() });
        assert_eq!(fixed.command(0.0, 0.0, 1.0, 0.0, &off, 1.0).vortex_sign, -1);
        let mut radial = Controller::new(Gains { repulsion: Repulsion::Gradient, ..gains() });
        let r = radial.command(0.0, 0.0, 1.0, 0.0, &f, 1.0);
        assert!((r.vx - (0.2 - 0.5)).abs() < 1e-12 && (r.vy + 0.1).abs() < 1e-12);
    }

    #[test]
    fn height_scaling_and_watchdog() {
        let c = Controller::new(gains());
        assert_eq!(c.height_scale(0.1), 1.0);
        assert!((c.height_scale(0.3) - 0.5).abs() < 1e-12);
        assert_eq!(c.height_scale(0.5), 0.0);
        let w = Watchdog { slow_after_ms: 100, stop_after_ms: 300 };
        assert_eq!(w.factor::<f64>(None), 0.0);
        assert_eq!(w.factor::<f64>(Some(50)), 1.0);
        assert!((w.factor::<f64>(Some(200)) - 0.5).abs() < 1e-12);
        assert_eq!(w.factor::<f64>(Some(300)), 0.0);
        assert_eq!(w.factor::<f64>(Some(u32::MAX)), 0.0);
    }

    /// Ours: the vortex is bounded by k_att whatever k_rep (between k_att / 2 and k_att when the
    /// bound applies), and the radial barrier never lets the command climb f* faster than allowed:
    /// not at all at `stop_height_m`. The thesis's law (bounded = false) is unchanged.
    #[test]
    fn bounded_vortex_and_radial_barrier() {
        let g = Gains { bounded: true, k_rep: 1e4, ..gains() };
        let mut c = Controller::new(g);
        let off_hill = FieldSample { height: 0.0, grad_x: 3.0, grad_y: -1.0 };
        let cmd = c.command(0.0, 0.0, 1.0, 0.0, &off_hill, 1.0);
        let (rx, ry) = (cmd.vx - 0.2, cmd.vy);
        assert!(rx.hypot(ry) <= 0.2 + 1e-12 && rx.hypot(ry) >= 0.2 / 2.0 / 1.1181, "{rx} {ry}");
        for h in [0.25, 0.3, 0.39, 0.4, 0.5] {
            for (gx, gy) in [(1.0, 0.0), (0.3, 0.4), (-2.0, 0.5), (0.01, 0.0)] {
                let f = FieldSample { height: h, grad_x: gx, grad_y: gy };
                let mut c = Controller::new(Gains { bounded: true, ..gains() });
                let cmd = c.command(0.0, 0.0, 1.0, 0.0, &f, 1.0);
                let up = cmd.vx * gx + cmd.vy * gy;
                let allow = if h < 0.4 { 0.2 * (0.4 - h) / 0.2 } else { 0.0 };
                assert!(up <= allow + 1e-9, "h {h} grad ({gx}, {gy}): uphill {up} > {allow}");
            }
        }
        let mut thesis = Controller::new(Gains { k_rep: 1e4, ..gains() });
        let t = thesis.command(0.0, 0.0, 1.0, 0.0, &off_hill, 1.0);
        assert!(t.vx.hypot(t.vy) > 1000.0, "eq 76 as written is unbounded");
    }
}
