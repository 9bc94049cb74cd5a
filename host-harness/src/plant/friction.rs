//! Dry friction of a slide, two ways (eq 31, 41, 48). Units: N, m/s.
//!
//! - [`TanhFriction`], regularised: `F = F_max tanh(v / v0)` (the sgn() of eq 48 smoothed the same
//!   way). Table 15 gives v0 = 1e-3 m/s, and that is the floor: smaller values are raised to it and
//!   the run says so. Near v = 0 the force changes at a rate F_max / v0 per m/s, which forces the
//!   solver into tiny steps through every stick phase (docs/accuracy.md, issue 12).
//! - [`Slide`], Coulomb as Tables 4, 8, 11 and 13 write it (v0 = 0): a hybrid state (Karnopp,
//!   "Computer simulation of stick-slip friction in mechanical dynamic systems", 1985). While
//!   *sticking*, the two sides move together and the friction is whatever force keeps them so
//!   ([`required`]), as long as its magnitude stays below mu |F_n|; while *slipping* in direction d,
//!   the force is -d mu |F_n| (opposing the relative velocity). The switches are located events
//!   (`sim.rs`): stick -> slip when the required force reaches the limit ([`Slide::event`]), slip
//!   -> stick or reversal when the relative velocity reaches zero ([`Slide::decide`] chooses). One
//!   coefficient for sticking and sliding: the thesis gives one mu.

/// Smallest regularisation velocity used, m/s (Table 15's own value).
pub const V0_MIN: f64 = 1e-3;

/// Friction opposing a relative velocity.
#[derive(Debug, Clone, Copy)]
pub struct TanhFriction {
    /// mu, or 1 when the magnitude is given directly in N.
    pub mu: f64,
    /// Effective regularisation velocity, m/s (>= V0_MIN).
    pub v0: f64,
    /// True when the scene's v0 was below V0_MIN and was raised.
    pub regularised: bool,
}

impl TanhFriction {
    /// mu and the scene's v0 (raised to V0_MIN if smaller).
    pub fn new(mu: f64, v0: f64) -> Self {
        Self { mu, v0: v0.max(V0_MIN), regularised: v0 < V0_MIN }
    }

    /// Friction force for normal force `normal` (N, its magnitude is used) and the velocity `v`
    /// the force acts along (positive `v` gives a positive force), N.
    pub fn force(&self, normal: f64, v: f64) -> f64 {
        self.mu * normal.abs() * (v / self.v0).tanh()
    }
}

/// How far past zero the relative velocity must go, against the slip, before a slip is taken to
/// have ended, m/s: the slip event fires at `d v = -SLIP_END`, so that it starts strictly positive
/// (at +SLIP_END) right after a break-away at v = 0, and a reversal is never missed. 1e-12 m/s
/// over any run of the scenes' length moves a body by less than 1e-12 m.
pub const SLIP_END: f64 = 1e-12;

/// The hybrid state of a Coulomb slide.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Slide {
    /// Both sides move together, at relative position `s` (m).
    Stick {
        /// The relative position held, m.
        s: f64,
    },
    /// Slipping with relative velocity of sign `dir` (+1 or -1).
    Slip {
        /// +1 or -1.
        dir: f64,
    },
}

/// The friction that keeps the relative acceleration zero, N: with relative acceleration
/// `a0 + b F` under a friction force F on the moving side (b > 0, the sum of the inverse masses),
/// F = -a0 / b.
pub fn required(a0: f64, b: f64) -> f64 {
    -a0 / b
}

impl Slide {
    /// The friction force on the slide for limit `limit` = mu |F_n| (N) and required force `req`
    /// (N, used while sticking).
    pub fn force(&self, limit: f64, req: f64) -> f64 {
        match *self {
            Self::Stick { .. } => req,
            Self::Slip { dir } => -dir * limit,
        }
    }

    /// The event function of the current state: positive while it holds. Sticking: `limit -
    /// |req|`; slipping: `dir v + SLIP_END` for relative velocity `v`.
    pub fn event(&self, limit: f64, req: f64, v: f64) -> f64 {
        match *self {
            Self::Stick { .. } => limit - req.abs(),
            Self::Slip { dir } => dir * v + SLIP_END,
        }
    }

    /// The state to take at relative position `s` where the relative velocity is (about) zero,
    /// or where sticking has just failed: stick if the required force is strictly inside the
    /// limit, else slip the way the unresisted relative acceleration `a0` goes (positive when `a0`
    /// is 0, where the limit is 0 too and no force acts either way).
    pub fn decide(s: f64, limit: f64, req: f64, a0: f64) -> Self {
        if req.abs() < limit {
            Self::Stick { s }
        } else {
            Self::Slip { dir: if a0 < 0.0 { -1.0 } else { 1.0 } }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coulomb_limit_is_regularised_not_divided_by_zero() {
        let f = TanhFriction::new(0.2, 0.0);
        assert!(f.regularised);
        assert!(f.force(10.0, 0.0) == 0.0);
        assert!((f.force(10.0, 1.0) - 2.0).abs() < 1e-9);
        assert!(f.force(10.0, -1e-12).is_finite());
    }

    #[test]
    fn karnopp_states() {
        // Required force inside the limit sticks; at or beyond it slips the way a0 pushes, and the
        // sliding force then opposes that direction with the full limit.
        assert_eq!(Slide::decide(0.01, 2.0, 1.9, -3.8), Slide::Stick { s: 0.01 });
        assert_eq!(Slide::decide(0.01, 2.0, 2.0, -4.0), Slide::Slip { dir: -1.0 });
        let slip = Slide::decide(0.0, 2.0, -2.5, 5.0);
        assert_eq!(slip, Slide::Slip { dir: 1.0 });
        assert_eq!(slip.force(2.0, -2.5), -2.0);
        // A break-away starts the slip event strictly positive, so the event is armed at once.
        assert!(slip.event(2.0, -2.5, 0.0) > 0.0);
        // Zero normal force: nothing holds and nothing resists.
        assert_eq!(Slide::decide(0.0, 0.0, 0.0, 0.0).force(0.0, 0.0), 0.0);
        assert_eq!(required(-4.0, 2.0), 2.0);
    }

    use crate::plant::{Plant, XR, XT};
    use crate::scene::{parse, Scene};
    use crate::sim::Run;

    /// Table 8's paddle (stick-slip by default: v0 = 0), edited.
    fn table8(edit: &[(&str, &str)]) -> Scene {
        let mut text = crate::shipped::get("table8_bistable").unwrap().to_string();
        for (from, to) in edit {
            assert!(text.contains(from), "{from}");
            text = text.replacen(from, to, 1);
        }
        parse(&text, "table8_edit.toml").unwrap()
    }

    #[test]
    fn a_stuck_tool_never_drifts() {
        // No contact (the obstacle beyond the travel), mu = 1: the flange accelerates at 1 m/s^2
        // and brakes at 2 m/s^2, asking 0.048 N and 0.096 N of friction against a limit of 1.8 N.
        // The tool must not move on the slide at all: not one switch, and the stroke exactly
        // the rest stroke at every recorded instant (the regularised law creeps here).
        let scene = table8(&[("mu = 0.12, v0 = 0.0", "mu = 1.0, v0 = 0.0"), ("gap = 0.04 ", "gap = 0.16 ")]);
        let mut run = Run::new(&scene, true, true);
        run.advance_to(0.3).unwrap();
        run.command_brake(0.3);
        run.finish().unwrap();
        assert!(run.slide_switches().is_empty(), "{:?}", run.slide_switches());
        let s_rest = Plant::new(&scene).s_rest;
        let hist = &run.sim.history;
        assert!(hist.len() > 100);
        for h in hist {
            assert!((h.s - s_rest).abs() < 1e-15, "t {} s {} vs {}", h.t, h.s, s_rest);
            assert!((h.v_t - h.v_r).abs() < 1e-15, "t {}: {} vs {}", h.t, h.v_t, h.v_r);
        }
        // The state vector holds the same stroke: nothing to correct at a later break-away.
        // (A rigid robot: x_r is the law's, not y[XR].)
        let (y, xr) = (run.state(), run.now().0.xr);
        assert!((y[XT] - xr - s_rest).abs() < 1e-12, "{}", y[XT] - xr - s_rest);
        assert_eq!(y[XR], 0.0);

        let mut reg = scene.clone();
        if let crate::scene::Decoupler::Bistable(b) = &mut reg.decoupler {
            b.friction.as_mut().unwrap().law = crate::scene::FrictionLaw::Regularised;
        }
        let mut run = Run::new(&reg, true, true);
        run.advance_to(0.3).unwrap();
        run.command_brake(0.3);
        run.finish().unwrap();
        let creep = run.sim.history.iter().map(|h| (h.s - s_rest).abs()).fold(0.0, f64::max);
        // (4.3e-8 m: at v0 = 1 mm/s the law needs a slip velocity to push at all.)
        assert!(creep > 1e-8, "the regularised law should creep: {creep}");
    }

    #[test]
    fn breaks_away_when_the_contact_force_reaches_the_limit() {
        // The flange at constant speed v from t = 0 (no breakpoint), no sensor (no braking), the
        // tool stuck on it: penetration v (t - t_c), contact force k d^1.5 (1 + alpha) (chi =
        // alpha k / v); the friction holds the tool until that force reaches mu |F_n|, at
        // t_b = t_c + (mu |F_n| / (k (1 + alpha)))^(2/3) / v, where it must slip backwards.
        let scene = table8(&[("dead_time = 0.07 ", "start_at_speed = true\ndead_time = 0.07 ")]);
        let mut scene = scene;
        scene.sensor = None;
        let plant = Plant::new(&scene);
        let v = scene.motion.speed;
        let t_c = scene.target.gap / v;
        let limit = plant.decoupler.friction_limit(plant.s_rest);
        let alpha = plant.contact.chi(v) * v / plant.contact.stiffness;
        let t_b = t_c + (limit / (plant.contact.stiffness * (1.0 + alpha))).powf(2.0 / 3.0) / v;
        let mut run = Run::new(&scene, false, false);
        run.finish().unwrap();
        let sw = run.slide_switches();
        assert!(!sw.is_empty(), "never broke away");
        let (t, state) = sw[0];
        assert_eq!(state, Slide::Slip { dir: -1.0 });
        assert!((t - t_b).abs() < 1e-9, "broke away at {t}, expected {t_b} ({:e} s off)", t - t_b);
        // And the summary's contact instant is the one assumed.
        assert!((run.summary().t_contact.unwrap() - t_c).abs() < 1e-9);
    }

    #[test]
    fn no_chattering_on_the_stick_slip_scenes() {
        // Every shipped scene with a Coulomb slide: a handful of switches, not thousands, and far
        // fewer steps than the regularised law needs.
        for name in ["table4_bistable_136g", "table4_bistable_246g", "table8_bistable", "table11_z_prototype", "table13_bistable_object", "table13_bistable_object_dt10"] {
            let scene = parse(crate::shipped::get(name).unwrap(), name).unwrap();
            let mut run = Run::new(&scene, false, false);
            run.finish().unwrap();
            let n = run.slide_switches().len();
            eprintln!("{name}: {n} switches");
            assert!((1..=16).contains(&n), "{name}: {n} switches {:?}", run.slide_switches());
            // Consecutive switches are separated in time (no Zeno): at least 10 us.
            for w in run.slide_switches().windows(2) {
                assert!(w[1].0 - w[0].0 > 1e-5, "{name}: {:?}", w);
            }
        }
    }

    #[test]
    fn a_force_oscillating_about_the_limit_switches_a_bounded_number_of_times() {
        // The worst case for chattering: the compliant robot's 26 Hz ring-down makes the required
        // friction oscillate, and mu chosen so the limit sits inside that oscillation.
        for mu in ["0.02", "0.05", "0.12", "0.3"] {
            let mut scene = table8(&[("mu = 0.12, v0 = 0.0", &format!("mu = {mu}, v0 = 0.0"))]);
            scene.robot = Some(crate::scene::Robot { mass: 8.4, stiffness: 2.3e5, damping: 71.0 });
            let mut run = Run::new(&scene, false, false);
            run.finish().unwrap();
            let n = run.slide_switches().len();
            eprintln!("mu {mu}: {n} switches, {} steps", run.stats().steps);
            assert!(n <= 60, "mu {mu}: {n} switches");
            let st = run.stats();
            assert!(st.steps < 5000, "mu {mu}: {} steps", st.steps);
        }
    }
}
