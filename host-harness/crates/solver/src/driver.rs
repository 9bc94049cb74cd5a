//! Runs a [`Stepper`] over a hybrid system: steps onto breakpoints, controls the step size of
//! adaptive methods, and locates events on each accepted step's interpolant (Illinois
//! regula falsi) to `event_tol` seconds. After an event the integration restarts from the located
//! instant, so two events in one step are found one after the other, and an event exactly on a
//! step boundary is found once.
//!
//! Step-size control of the adaptive method (Hairer, Norsett, Wanner, "Solving ODEs I", II.4 and
//! their DOPRI5 code): a PI controller (beta = 0.04), steps grow at most 10x and shrink at most 5x,
//! never grow right after a rejection, and restart from the HINIT estimate ([`crate::initial_step`])
//! at the start and after each event, where the right-hand side has just changed.

use crate::system::{initial_step, Stepper, System};
use std::fmt;

/// Which zero crossing of an event function counts. "Inside" means g > 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Crossing {
    /// From g <= 0 to g > 0.
    Up,
    /// From g > 0 to g <= 0.
    Down,
}

impl Crossing {
    fn new_side(self, g: f64) -> bool {
        match self {
            Crossing::Up => g > 0.0,
            Crossing::Down => g <= 0.0,
        }
    }
}

/// A system with event functions and discrete reactions to them.
pub trait Hybrid<const N: usize, const E: usize>: System<N> {
    /// Event function values at (t, y).
    fn events(&self, t: f64, y: &[f64; N]) -> [f64; E];
    /// The crossing watched for event `i`, or `None` if it is not armed.
    fn watching(&self, i: usize) -> Option<Crossing>;
    /// Reaction to event `i` located at `t`; may change `y` and the system's own state.
    fn on_event(&mut self, i: usize, t: f64, y: &mut [f64; N]);
    /// True for an event that must fire as soon as its function is found on the new side at the
    /// start of a step, without a crossing inside one: its function can jump (with the right-hand
    /// side at a breakpoint), so a crossing may happen between steps. Default: none.
    fn fires_at_once(&self, _i: usize) -> bool {
        false
    }
    /// The next instant strictly after `t` where the right-hand side is not smooth in time.
    fn next_breakpoint(&self, t: f64) -> Option<f64>;
    /// Called after each accepted (possibly event-truncated) step over [t0, t1], with the end
    /// state and the step's interpolant.
    fn on_step(&mut self, t0: f64, t1: f64, y1: &[f64; N], dense: &dyn Fn(f64) -> [f64; N]);
}

/// Driver settings.
#[derive(Debug, Clone, Copy)]
pub struct Settings {
    /// Largest step (and the step of fixed-step methods), s.
    pub max_step: f64,
    /// Events are located to this many seconds.
    pub event_tol: f64,
    /// Give up after this many steps (accepted plus rejected).
    pub max_steps: u64,
}

impl Default for Settings {
    fn default() -> Self {
        Self { max_step: 1e-3, event_tol: 1e-12, max_steps: 20_000_000 }
    }
}

/// What the integration cost.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Stats {
    /// Accepted steps.
    pub steps: u64,
    /// Rejected steps.
    pub rejected: u64,
    /// Events located.
    pub events: u64,
}

/// Why an integration stopped early.
#[derive(Debug, Clone, PartialEq)]
pub enum SolveError {
    /// The adaptive step fell below what f64 time can resolve: the problem is too stiff for the
    /// tolerance (or singular) at t.
    StepCollapse {
        /// Time, s.
        t: f64,
        /// Step size at the collapse, s.
        h: f64,
    },
    /// More steps than `Settings::max_steps`.
    TooManySteps {
        /// Time reached, s.
        t: f64,
    },
    /// The state became NaN or infinite (fixed-step methods: the step is too large).
    NonFinite {
        /// Time, s.
        t: f64,
    },
}

impl fmt::Display for SolveError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::StepCollapse { t, h } => write!(f, "step size collapsed to {h:.3e} s at t = {t:.6} s: the scene is too stiff for the tolerance; loosen solver.rtol/atol or soften the stiffest element"),
            Self::TooManySteps { t } => write!(f, "gave up after the step limit at t = {t:.6} s; raise solver.max_step or loosen the tolerance"),
            Self::NonFinite { t } => write!(f, "the state became non-finite at t = {t:.6} s: the fixed step is too large for this scene (lower solver.max_step or use dopri5)"),
        }
    }
}

impl std::error::Error for SolveError {}

/// The integration in progress: time, state, and the step size carried between calls.
#[derive(Debug, Clone)]
pub struct Driver<const N: usize, const E: usize> {
    /// Current time, s.
    pub t: f64,
    /// Current state.
    pub y: [f64; N],
    f: [f64; N],
    /// Next adaptive step, s; 0 until estimated (start, after an event).
    h: f64,
    /// Error of the last accepted step (the PI controller's memory).
    err_old: f64,
    /// True when the last attempt was rejected.
    rejected_last: bool,
    g: [f64; E],
    /// Cost so far.
    pub stats: Stats,
    settings: Settings,
}

impl<const N: usize, const E: usize> Driver<N, E> {
    /// Starts at (t0, y0).
    pub fn new<S: Hybrid<N, E>>(sys: &S, t0: f64, y0: [f64; N], settings: Settings) -> Self {
        let mut f = [0.0; N];
        sys.rhs(t0, &y0, &mut f);
        let g = sys.events(t0, &y0);
        Self { t: t0, y: y0, f, h: 0.0, err_old: 1e-4, rejected_last: false, g, stats: Stats::default(), settings }
    }

    /// Call after the system's own state changed outside an event (e.g. braking commanded from
    /// outside): re-reads f and the event functions at the current point.
    pub fn restart<S: Hybrid<N, E>>(&mut self, sys: &S) {
        sys.rhs(self.t, &self.y, &mut self.f);
        self.g = sys.events(self.t, &self.y);
    }

    /// The step the adaptive controller proposes next, s (0 before the first estimate). A caller
    /// that advances to `t + next_step()` takes the step the driver would have taken anyway, and can
    /// look at the state after each one (firmware in the loop, `flinch-hil`).
    pub fn next_step(&self) -> f64 {
        self.h
    }

    /// Integrates up to `t_end` (inclusive).
    pub fn advance_to<S: Hybrid<N, E>, M: Stepper<N>>(&mut self, sys: &mut S, stepper: &mut M, t_end: f64) -> Result<(), SolveError> {
        const SAFE: f64 = 0.9;
        const BETA: f64 = 0.04;
        const GROW_MAX: f64 = 10.0;
        const SHRINK_MAX: f64 = 5.0;
        let adaptive = stepper.adaptive();
        let expo = 1.0 / (stepper.order() + 1.0) - 0.75 * BETA;
        let (rtol, atol) = stepper.tolerances();
        // Events fired at once at the same instant (a guard against a reaction that does not
        // move its function off the new side).
        let mut at_once = 0u32;
        while self.t < t_end {
            if self.stats.steps + self.stats.rejected >= self.settings.max_steps {
                return Err(SolveError::TooManySteps { t: self.t });
            }
            if at_once < 4 {
                let now = (0..E).find(|&i| sys.fires_at_once(i) && sys.watching(i).is_some_and(|dir| dir.new_side(self.g[i])));
                if let Some(i) = now {
                    at_once += 1;
                    let mut y = self.y;
                    sys.on_event(i, self.t, &mut y);
                    self.stats.events += 1;
                    self.y = y;
                    sys.rhs(self.t, &self.y, &mut self.f);
                    self.g = sys.events(self.t, &self.y);
                    self.err_old = 1e-4;
                    continue;
                }
            }
            if adaptive && self.h <= 0.0 {
                self.h = initial_step(&*sys, self.t, &self.y, &self.f, stepper.order(), rtol, atol, self.settings.max_step);
            }
            let limit = sys.next_breakpoint(self.t).map_or(t_end, |b| b.min(t_end));
            let mut h = if adaptive { self.h.min(self.settings.max_step) } else { self.settings.max_step };
            let mut lands = false;
            if self.t + h >= limit {
                h = limit - self.t;
                lands = true;
            }
            if h <= 0.0 {
                // A breakpoint at the current instant: nothing to integrate over.
                self.t = limit;
                continue;
            }
            let (y1, err) = stepper.step(&*sys, self.t, &self.y, &self.f, h);
            let finite = y1.iter().all(|v| v.is_finite()) && err.is_finite();
            let mut h_next = h;
            if adaptive {
                if !finite || err > 1.0 {
                    self.stats.rejected += 1;
                    let mut shrink = if finite { (err.powf(expo) / SAFE).min(SHRINK_MAX) } else { SHRINK_MAX };
                    // A second rejection in a row: the error is not behaving like h^5 (a kink), so
                    // at least halve.
                    if self.rejected_last {
                        shrink = shrink.max(2.0);
                    }
                    self.h = h / shrink;
                    // The step ran into an event (a contact onset, a stop): the right-hand side is
                    // not smooth across it, so aim the retry just past the crossing instead of
                    // creeping up on it by error control. Where it is depends on the state before
                    // the event only: estimated on the tangent y0 + tau f0 (exact to first order;
                    // the failed step's own end is polluted by the force it should not have felt).
                    // Only on a first rejection: if the estimate was off, shrinking takes over.
                    if finite && !self.rejected_last {
                        let g1 = sys.events(self.t + h, &y1);
                        let mut aim = f64::INFINITY;
                        for (i, &g1_i) in g1.iter().enumerate() {
                            let Some(dir) = sys.watching(i) else { continue };
                            if dir.new_side(self.g[i]) || !dir.new_side(g1_i) {
                                continue;
                            }
                            let tangent = |tau: f64| {
                                let mut y = self.y;
                                for (yk, fk) in y.iter_mut().zip(&self.f) {
                                    *yk += tau * fk;
                                }
                                sys.events(self.t + tau, &y)[i]
                            };
                            if dir.new_side(tangent(h)) {
                                let theta = locate(|th| tangent(th * h), self.g[i], tangent(h), dir, 1e-3);
                                aim = aim.min((theta * 1.001).clamp(1e-3, 0.95) * h);
                            }
                        }
                        if aim.is_finite() {
                            self.h = aim;
                        }
                    }
                    self.rejected_last = true;
                    if self.h < 1e-14 * self.t.abs().max(1e-3) {
                        return Err(SolveError::StepCollapse { t: self.t, h: self.h });
                    }
                    continue;
                }
                let fac = (err.powf(expo) / self.err_old.powf(BETA) / SAFE).clamp(1.0 / GROW_MAX, SHRINK_MAX);
                h_next = h / fac;
                if self.rejected_last {
                    h_next = h_next.min(h);
                }
                self.err_old = err.max(1e-4);
                self.rejected_last = false;
            } else if !finite {
                return Err(SolveError::NonFinite { t: self.t });
            }
            self.stats.steps += 1;
            at_once = 0;
            let t1 = if lands { limit } else { self.t + h };
            let g1 = sys.events(t1, &y1);
            // Earliest armed event crossing in this step.
            let mut first: Option<(usize, f64)> = None;
            for (i, &g1_i) in g1.iter().enumerate() {
                let Some(dir) = sys.watching(i) else { continue };
                if dir.new_side(self.g[i]) || !dir.new_side(g1_i) {
                    continue;
                }
                let theta = locate(|th| sys.events(self.t + th * h, &stepper.dense(th))[i], self.g[i], g1_i, dir, self.settings.event_tol / h);
                if first.is_none_or(|(_, best)| theta < best) {
                    first = Some((i, theta));
                }
            }
            let t0 = self.t;
            let dense = |t: f64| stepper.dense(((t - t0) / h).clamp(0.0, 1.0));
            if let Some((i, theta)) = first {
                let te = if theta >= 1.0 { t1 } else { t0 + theta * h };
                let mut ye = if theta >= 1.0 { y1 } else { stepper.dense(theta) };
                sys.on_step(t0, te, &ye, &dense);
                sys.on_event(i, te, &mut ye);
                self.stats.events += 1;
                self.t = te;
                self.y = ye;
                sys.rhs(self.t, &self.y, &mut self.f);
                self.g = sys.events(self.t, &self.y);
                // The right-hand side just changed (a contact began, a damping was fixed): go on
                // from what the step that reached the event allowed, and forget the PI history.
                if adaptive {
                    self.h = h_next;
                }
                self.err_old = 1e-4;
            } else {
                sys.on_step(t0, t1, &y1, &dense);
                self.t = t1;
                self.y = y1;
                match stepper.f_end() {
                    Some(f) => self.f = f,
                    None => sys.rhs(self.t, &self.y, &mut self.f),
                }
                self.g = g1;
                if adaptive {
                    // A step cut short by a breakpoint says nothing about the next one's size.
                    self.h = if lands { self.h.max(h_next) } else { h_next };
                }
            }
        }
        Ok(())
    }
}

/// Finds theta in (0, 1] where g first reaches the new side, to `theta_tol`; returns the end of
/// the final bracket, which is on the new side.
fn locate(g: impl Fn(f64) -> f64, g0: f64, g1: f64, dir: Crossing, theta_tol: f64) -> f64 {
    let (mut a, mut ga, mut b, mut gb) = (0.0_f64, g0, 1.0_f64, g1);
    let mut last_side = 0i8;
    for _ in 0..200 {
        if b - a <= theta_tol {
            break;
        }
        let mut c = if gb != ga { b - gb * (b - a) / (gb - ga) } else { 0.5 * (a + b) };
        if !(c > a && c < b) {
            c = 0.5 * (a + b);
        }
        let gc = g(c);
        if dir.new_side(gc) {
            b = c;
            gb = gc;
            if last_side == 1 { ga *= 0.5; }
            last_side = 1;
        } else {
            a = c;
            ga = gc;
            if last_side == -1 { gb *= 0.5; }
            last_side = -1;
        }
    }
    b
}

#[cfg(test)]
mod tests {
    use crate::dopri5::Dopri5;
    use crate::fixed::{Fixed, FixedKind};
    use super::*;

    /// A ball falling onto a floor at x = 0 (event), reflected with restitution 0.5.
    struct Ball {
        bounces: Vec<f64>,
        breakpoint: Option<f64>,
    }
    impl System<2> for Ball {
        fn rhs(&self, _t: f64, _y: &[f64; 2], dy: &mut [f64; 2]) {
            dy[0] = _y[1];
            dy[1] = -9.81;
        }
    }
    impl Hybrid<2, 1> for Ball {
        fn events(&self, _t: f64, y: &[f64; 2]) -> [f64; 1] {
            [y[0]]
        }
        fn watching(&self, _i: usize) -> Option<Crossing> {
            Some(Crossing::Down)
        }
        fn on_event(&mut self, _i: usize, t: f64, y: &mut [f64; 2]) {
            self.bounces.push(t);
            y[0] = 0.0f64.max(y[0]) + 1e-300;
            y[1] *= -0.5;
        }
        fn next_breakpoint(&self, t: f64) -> Option<f64> {
            self.breakpoint.filter(|&b| b > t)
        }
        fn on_step(&mut self, _: f64, _: f64, _: &[f64; 2], _: &dyn Fn(f64) -> [f64; 2]) {}
    }

    fn first_bounce_exact() -> f64 {
        (2.0 * 1.0 / 9.81f64).sqrt()
    }

    #[test]
    fn events_are_located_not_sampled() {
        use crate::AnyStepper;
        for mut stepper in [AnyStepper::Dopri5(Dopri5::<2>::new(1e-9, 1e-12)), AnyStepper::Fixed(Fixed::<2>::new(FixedKind::Rk4))] {
            let mut ball = Ball { bounces: vec![], breakpoint: None };
            let mut d = Driver::<2, 1>::new(&ball, 0.0, [1.0, 0.0], Settings { max_step: 0.1, ..Default::default() });
            d.advance_to(&mut ball, &mut stepper, 0.5).unwrap();
            // With a 0.1 s step, sampling would be off by up to 0.1 s; located, it is exact
            // (the motion is a parabola, which both interpolants represent exactly).
            assert!((ball.bounces[0] - first_bounce_exact()).abs() < 1e-9, "{:?}", ball.bounces);
        }
    }

    #[test]
    fn event_exactly_on_a_breakpoint_is_found_once() {
        let tb = first_bounce_exact();
        let mut ball = Ball { bounces: vec![], breakpoint: Some(tb) };
        let mut d = Driver::<2, 1>::new(&ball, 0.0, [1.0, 0.0], Settings { max_step: 0.05, ..Default::default() });
        let mut s = Dopri5::<2>::new(1e-9, 1e-12);
        d.advance_to(&mut ball, &mut s, 0.6).unwrap();
        assert_eq!(ball.bounces.len(), 1, "{:?}", ball.bounces);
        assert!((ball.bounces[0] - tb).abs() < 1e-9);
    }

    #[test]
    fn two_events_in_one_step_are_both_found_in_order() {
        // Second bounce at tb + 2 (0.5 v) / g = 0.903 s; one 0.95 s step holds both bounces.
        let mut ball = Ball { bounces: vec![], breakpoint: None };
        let mut d = Driver::<2, 1>::new(&ball, 0.0, [1.0, 0.0], Settings { max_step: 1.0, ..Default::default() });
        let mut s = Fixed::<2>::new(FixedKind::Rk4);
        d.advance_to(&mut ball, &mut s, 0.95).unwrap();
        let tb = first_bounce_exact();
        let v = 9.81 * tb;
        let second = tb + 2.0 * 0.5 * v / 9.81;
        assert_eq!(ball.bounces.len(), 2, "{:?}", ball.bounces);
        assert!((ball.bounces[0] - tb).abs() < 1e-9 && (ball.bounces[1] - second).abs() < 1e-9, "{:?}", ball.bounces);
    }

    #[test]
    fn dense_output_is_continuous_and_fourth_order() {
        struct Decay;
        impl System<1> for Decay {
            fn rhs(&self, _t: f64, y: &[f64; 1], dy: &mut [f64; 1]) {
                dy[0] = -y[0];
            }
        }
        let mut s = Dopri5::<1>::new(1e-6, 1e-9);
        let mut f0 = [0.0];
        Decay.rhs(0.0, &[1.0], &mut f0);
        let (y1, _) = s.step(&Decay, 0.0, &[1.0], &f0, 0.1);
        assert!((s.dense(1.0)[0] - y1[0]).abs() < 1e-15);
        assert!((s.dense(0.0)[0] - 1.0).abs() < 1e-15);
        assert!((s.dense(0.5)[0] - (-0.05f64).exp()).abs() < 1e-8);
    }
}
