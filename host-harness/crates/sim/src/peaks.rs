//! The peaks a step holds between its ends: the contact force and the force on the robot, refined
//! on the step's interpolant (successive parabolas), and which element the robot's peak came from.

//! A scene run: the plant integrated with its events, and what the summary reports.
//!
//! Events (located, not sampled): 0 tool-target contact onset/separation, 1 front end-stop
//! entry/exit, 2 back end-stop entry/exit, 3 the sensor's threshold, and 4-6 the instants where
//! the contact, the front stop or the back stop stops pushing (or starts again) while still
//! penetrated: its damping term cancels the spring term and the clamp at zero force (no adhesion)
//! takes over. That clamp is a kink in the right-hand side; located as an event, the step ends on
//! it instead of the error control hacking at it with a dozen rejected steps (docs/accuracy.md).
//! Event 7 switches a Coulomb slide (`decoupler.friction.law = "stick-slip"`, `plant::friction`)
//! between sticking and slipping. Breakpoints: end of the
//! acceleration, start and end of braking. Contact dampings chi are fixed at each onset from the
//! approach velocity (eq 7).

use flinch_plant::{Forces, State};
use crate::simulation::Simulation;

impl Simulation {
    /// The largest contact force and robot-force magnitude inside the step [t0, t1], N, given
    /// both at the step's ends (`at0`, `at1`).
    ///
    /// Three interior samples of the step's interpolant; where the largest sample is interior, a
    /// few successive parabolic interpolations (Brent's idea without the golden fallback, the
    /// bracket kept) refine it. A peak in the middle of a step is smooth, so the parabola converges
    /// in two or three evaluations; the old golden-section search spent 48 evaluations a step and
    /// was most of the run's cost (docs/accuracy.md).
    /// With `first_impact` the robot force is refined against the first impact's peak so far (the
    /// run's may be larger already, from the acceleration); returns (contact peak, (instant, robot
    /// peak)).
    pub(crate) fn peaks_inside(&self, t0: f64, t1: f64, at0: (f64, f64), at1: (f64, f64), dense: &dyn Fn(f64) -> State, first_impact: bool) -> (f64, (f64, f64)) {
        let forces = |t: f64| {
            let f = self.observe(t, &dense(t)).1;
            (f.contact, f.robot.abs())
        };
        let h = t1 - t0;
        let ts = [t0, t0 + 0.25 * h, t0 + 0.5 * h, t0 + 0.75 * h, t1];
        let mut fc = [at0.0, 0.0, 0.0, 0.0, at1.0];
        let mut fr = [at0.1, 0.0, 0.0, 0.0, at1.1];
        for i in 1..4 {
            (fc[i], fr[i]) = forces(ts[i]);
        }
        // Refining a local maximum that cannot become the run's peak is wasted work: a step
        // resolves the motion to rtol, so its maximum exceeds its best sample by far less than 5 %.
        let worth = |samples: &[f64; 5], peak: f64| samples.iter().fold(0.0f64, |m, &v| m.max(v)) >= 0.95 * peak;
        let c = if worth(&fc, self.peak_contact) { refine_max(|t| forces(t).0, ts, fc, self.peak_rtol).1 } else { 0.0 };
        let robot_ref = if first_impact { self.first_impact_robot.0 } else { self.peak_robot };
        let r = if worth(&fr, robot_ref) { refine_max(|t| forces(t).1, ts, fr, self.peak_rtol) } else { (t0, 0.0) };
        (c, r)
    }

    pub(crate) fn note_first_impact(&mut self, t: f64, f: f64) {
        if f > self.first_impact_robot.0 || self.first_impact_robot.1.is_nan() {
            self.first_impact_robot = (f, t);
        }
    }

    /// Records a robot-force magnitude `f` at `t`: the whole run's peak with what was pushing
    /// then (from the `forces` at `t`, not from the event flags: a step ending on an event is
    /// evaluated just past it, before its flag flips), and the first impact's.
    pub(crate) fn note_robot_peak(&mut self, t: f64, f: f64, first_impact: bool, fs: &Forces) {
        if first_impact {
            self.note_first_impact(t, f);
        }
        if f > self.peak_robot {
            self.peak_robot = f;
            self.peak_robot_at = (t, self.robot_force_event(fs));
        }
    }

    /// What carries the force on the robot at an instant: the largest of its parts. An end-stop
    /// carrying more than the decoupler's spring (or gas) and friction names itself; otherwise the
    /// decoupler passes on a tool-target contact if one is on ("first_impact" or "later_contact"),
    /// or its own spring and friction ("decoupler"). A rigid tool's is the contact's. Not a
    /// priority order: the 246 g Table 4 run's 45.5 N peak comes while the tool still touches the
    /// object, but the back stop carries 42.9 N of it (issue 15).
    pub(crate) fn robot_force_event(&self, fs: &Forces) -> &'static str {
        let d = &fs.decoupler;
        let (front, back) = (d.front_stop.abs(), d.back_stop.abs());
        let own = d.spring.abs().max(d.friction.abs());
        let contact = || if self.contacts == 0 || (self.contacts == 1 && self.in_contact) { "first_impact" } else { "later_contact" };
        if self.plant.decoupler.is_rigid() {
            return if fs.contact > 0.0 { contact() } else { "none" };
        }
        if front > back && front > own {
            "front_stop"
        } else if back >= front && back > own {
            "back_stop"
        } else if fs.contact > 0.0 {
            // Contact number 1, or the first one's onset instant (not yet counted).
            contact()
        } else if own > 0.0 {
            "decoupler"
        } else {
            "none"
        }
    }
}

/// The maximum of a smooth `f` given at five increasing instants `ts` with values `fs`: the
/// largest sample, refined by successive parabolic interpolation inside its bracket when it is
/// interior, until the gain is below `rtol` of the peak. Returns (instant, maximum).
fn refine_max(f: impl Fn(f64) -> f64, ts: [f64; 5], fs: [f64; 5], rtol: f64) -> (f64, f64) {
    let (mut i, mut best) = (0, fs[0]);
    for (k, &f) in fs.iter().enumerate().skip(1) {
        if f > best {
            (i, best) = (k, f);
        }
    }
    let vertex = |a: f64, fa: f64, b: f64, fb: f64, c: f64, fc: f64| {
        let p = (b - a) * (fb - fc);
        let q = (b - c) * (fb - fa);
        let den = p - q;
        if den == 0.0 { f64::NAN } else { b - 0.5 * ((b - a) * p - (b - c) * q) / den }
    };
    let (mut a, mut fa, mut b, mut fb, mut c, mut fcc);
    if i == 0 || i == 4 {
        // The largest sample is an end of the step: a peak just inside it would be missed by this
        // step and the next alike. The parabola through the three samples nearest that end says
        // whether one is there.
        let j = if i == 0 { 1 } else { 3 };
        let x = vertex(ts[j - 1], fs[j - 1], ts[j], fs[j], ts[j + 1], fs[j + 1]);
        let (lo, hi) = if i == 0 { (ts[0], ts[1]) } else { (ts[3], ts[4]) };
        if !(x > lo && x < hi) {
            return (ts[i], best);
        }
        let fx = f(x);
        if fx <= best {
            return (ts[i], best);
        }
        (a, fa, b, fb, c, fcc) = (lo, if i == 0 { fs[0] } else { fs[3] }, x, fx, hi, if i == 0 { fs[1] } else { fs[4] });
    } else {
        (a, fa, b, fb, c, fcc) = (ts[i - 1], fs[i - 1], ts[i], fs[i], ts[i + 1], fs[i + 1]);
    }
    for _ in 0..8 {
        let x = vertex(a, fa, b, fb, c, fcc);
        if !(x > a && x < c) || x == b {
            break;
        }
        let fx = f(x);
        let gain = fx - fb;
        if fx > fb {
            if x < b { (c, fcc) = (b, fb) } else { (a, fa) = (b, fb) }
            (b, fb) = (x, fx);
        } else if x < b {
            (a, fa) = (x, fx);
        } else {
            (c, fcc) = (x, fx);
        }
        if gain.abs() <= rtol * fb.abs() {
            break;
        }
    }
    if fb > best { (b, fb) } else { (ts[i], best) }
}
