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

use crate::plant::{self, Forces, Kinematics, Plant, State, N};
use crate::scene::{Decoupler, Fidelity, Method, Scene, TargetKind};
use crate::solver::dopri5::Dopri5;
use crate::solver::driver::{Crossing, Driver, Hybrid, Settings, SolveError, Stats};
use crate::solver::fixed::{Fixed, FixedKind};
use crate::solver::{AnyStepper, System};
use std::cell::Cell;

mod summary;
#[cfg(test)]
mod friction_tests;
pub use summary::{achieved_restitution, detection_delay, reaction_time, Sample, Summary, RESTITUTION_SLACK};

/// Number of event functions.
pub const E: usize = 8;
const EV_CONTACT: usize = 0;
const EV_FRONT: usize = 1;
const EV_BACK: usize = 2;
const EV_SWITCH: usize = 3;
const EV_CONTACT_PUSH: usize = 4;
const EV_FRONT_PUSH: usize = 5;
const EV_BACK_PUSH: usize = 6;
const EV_SLIDE: usize = 7;

/// The scene as the simulator models it: `scene` without the parts its `[solver]` lets it drop,
/// and the names of those actually dropped (a simplification that changes nothing, such as
/// "rigid-robot" on a scene without `[robot]`, is not listed).
///
/// `fidelity = "fast"` drops nothing on its own: the study (docs/accuracy.md, `flinch bench`) found
/// no simplification safe within the 1 % target on the shipped scenes. A rigid robot moved the peak
/// contact force by 8.7 % even for a light free object (scenes/extremes/tables5-7_bistable_object:
/// the tool bounces on the front stop through the robot's 26 Hz mode) and up to 1990 % for a rigid
/// tool, and was not even faster (the compliant robot softens what the tool sees); dropping friction
/// moved the peak robot force by up to 170 % (friction decides whether a bi-stable module switches,
/// Ch. 3.3) while saving up to 3.3x. So both stay explicit `solver.simplify` options, reported in the
/// summary, for a user who accepts their measured cost.
pub fn simplified(scene: &Scene) -> (Scene, Vec<String>) {
    let mut s = scene.clone();
    let mut done = Vec::new();
    let want = scene.solver.simplify;
    if want.rigid_robot && s.robot.is_some() {
        s.robot = None;
        done.push("rigid-robot".to_string());
    }
    if want.no_friction {
        let mut any = false;
        match &mut s.decoupler {
            Decoupler::Bistable(b) if b.friction.is_some() => {
                b.friction = None;
                any = true;
            }
            Decoupler::Hydraulic(h) if h.dry_friction > 0.0 || h.viscous_friction > 0.0 => {
                h.dry_friction = 0.0;
                h.viscous_friction = 0.0;
                any = true;
            }
            _ => {}
        }
        if let TargetKind::Object { floor_friction, .. } = &mut s.target.kind {
            any |= floor_friction.take().is_some();
        }
        if any {
            done.push("no-friction".to_string());
        }
    }
    (s, done)
}

/// See [`Simulation::sink`].
pub type Sink = Box<dyn FnMut(&Sample)>;

/// See [`Simulation::probe`].
pub type Probe = Box<dyn FnMut(&Plant, f64, f64, &dyn Fn(f64) -> State)>;

/// The plant as a hybrid system, with the run's bookkeeping.
pub struct Simulation {
    /// The plant.
    pub plant: Plant,
    name: String,
    dead_time: f64,
    external_brake: bool,
    /// `motion.brake_after_contact` (0: off).
    brake_after_contact: u32,
    /// Detected, braking held until that contact ends.
    brake_pending: bool,
    in_contact: bool,
    on_front: bool,
    on_back: bool,
    /// While penetrated: the law's unclamped force pushes (false: clamped at zero).
    contact_push: bool,
    front_push: bool,
    back_push: bool,
    detected: bool,
    rhs_evals: Cell<u64>,
    t_contact: Option<f64>,
    t_detect: Option<f64>,
    t_back: Option<f64>,
    v_in_first: Option<f64>,
    v_out_first: Option<f64>,
    contacts: u32,
    object_velocity_at_separation: Option<f64>,
    peak_contact: f64,
    peak_robot: f64,
    /// When `peak_robot` occurred and what was pushing then.
    peak_robot_at: (f64, &'static str),
    /// Peak robot-force magnitude and its instant during the first tool-target contact.
    first_impact_robot: (f64, f64),
    peak_object_v: f64,
    peak_gas: f64,
    max_travel: f64,
    exhausted: bool,
    /// While touching the target: smallest stroke left, largest deformation, closest approach.
    stroke_left_min: Option<f64>,
    deformation_max: Option<f64>,
    closest_min: Option<f64>,
    record_every: Option<f64>,
    /// Rows recorded so far: the next is due at `records * dt` (see [`record_due`]).
    records: u64,
    /// The recorded time history (empty unless recording).
    pub history: Vec<Sample>,
    /// Where recorded samples go as each step makes them (a streamed CSV, a decimated plot: memory
    /// stays bounded whatever the duration); `None` keeps them in `history`.
    pub sink: Option<Sink>,
    /// Called after every accepted step with the plant, the step's span [t0, t1] and its dense
    /// output: firmware in the loop reads the switch between steps from it (`hil.rs`).
    pub probe: Option<Probe>,
    warnings: Vec<String>,
    /// Contact and robot-force magnitude at the end of the last step (t, (N, N)).
    last_end: (f64, (f64, f64)),
    /// s' at the end of the last step, m/s.
    last_end_s_dot: f64,
    /// Relative accuracy the in-step peak search stops at.
    peak_rtol: f64,
    fidelity: Fidelity,
    simplified: Vec<String>,
    /// The body region hit, if the target is one (ISO/TS 15066 Annex A, crate::body).
    body: Option<crate::body::BodyTarget>,
    /// The scene's duration, s (the rest check extrapolates to it).
    duration: f64,
    /// The solver's tolerances (rtol, atol) and the velocity scale of the run (motion.speed, m/s),
    /// which set what "at rest" means.
    rest_tol: (f64, f64, f64),
    /// From this instant on the plant is at rest and held (`at_rest_from_s`).
    at_rest_from: Option<f64>,
    /// Instants a Coulomb slide switched between sticking and slipping (event 7), with the state
    /// taken.
    slide_switches: Vec<(f64, plant::friction::Slide)>,
}

impl System<N> for Simulation {
    fn rhs(&self, t: f64, y: &State, dy: &mut State) {
        self.rhs_evals.set(self.rhs_evals.get() + 1);
        self.plant.eval(t, y, dy);
        if self.at_rest_from.is_some() {
            // At rest (see `at_rest`): every body is held where it is. The decoupler impulse keeps
            // accumulating the (constant) force of a contact that is still on (eq 21).
            for v in &mut dy[..plant::IMPULSE] {
                *v = 0.0;
            }
        }
    }
}

impl Hybrid<N, E> for Simulation {
    fn events(&self, t: f64, y: &State) -> [f64; E] {
        let k = self.plant.kinematics(t, y);
        let mut g = [-1.0; E];
        g[EV_CONTACT] = k.delta;
        if let Some(f) = self.plant.decoupler.front_stop() {
            g[EV_FRONT] = k.s - f.at;
        }
        if let Some(b) = self.plant.decoupler.back_stop() {
            g[EV_BACK] = b.penetration(k.s);
        }
        if let Some(d) = &self.plant.detector {
            let fc = self.plant.contact.force(k.delta, k.delta_dot, self.plant.target_chi);
            g[EV_SWITCH] = d.signal(k.s, fc);
        }
        // Sign of the unclamped force per unit d^1.5 (or per metre for the linear front stop).
        g[EV_CONTACT_PUSH] = self.plant.contact.stiffness + self.plant.target_chi * k.delta_dot;
        if let Some(f) = self.plant.decoupler.front_stop() {
            g[EV_FRONT_PUSH] = f.push(k.s, k.s_dot, self.plant.front_chi);
        }
        if let Some(b) = self.plant.decoupler.back_stop() {
            g[EV_BACK_PUSH] = b.contact.stiffness - self.plant.back_chi * k.s_dot;
        }
        if let Some(v) = self.plant.slide_event(&k) {
            g[EV_SLIDE] = v;
        }
        g
    }

    fn fires_at_once(&self, i: usize) -> bool {
        // The required friction jumps with the motion law's acceleration at a breakpoint: a
        // stick that fails there must be let go there, not carried on.
        i == EV_SLIDE
    }

    fn watching(&self, i: usize) -> Option<Crossing> {
        let dir = |inside: bool| Some(if inside { Crossing::Down } else { Crossing::Up });
        match i {
            EV_CONTACT => dir(self.in_contact),
            EV_FRONT if self.plant.decoupler.front_stop().is_some() => dir(self.on_front),
            EV_BACK if self.plant.decoupler.back_stop().is_some() => dir(self.on_back),
            EV_SWITCH if self.plant.detector.is_some() && !self.detected => Some(Crossing::Up),
            EV_CONTACT_PUSH if self.in_contact => dir(self.contact_push),
            EV_FRONT_PUSH if self.on_front => dir(self.front_push),
            EV_BACK_PUSH if self.on_back => dir(self.back_push),
            EV_SLIDE if self.plant.slide.is_some() => Some(Crossing::Down),
            _ => None,
        }
    }

    fn on_event(&mut self, i: usize, t: f64, y: &mut State) {
        let k = self.plant.kinematics(t, y);
        match i {
            EV_CONTACT if !self.in_contact => {
                self.in_contact = true;
                self.plant.in_contact = true;
                self.contacts += 1;
                self.plant.target_chi = self.plant.contact.chi(k.delta_dot);
                if self.t_contact.is_none() {
                    self.t_contact = Some(t);
                    self.v_in_first = Some(k.delta_dot);
                }
            }
            EV_CONTACT => {
                self.in_contact = false;
                self.plant.in_contact = false;
                if self.contacts == 1 && self.v_out_first.is_none() {
                    self.v_out_first = Some(k.delta_dot);
                }
                if self.plant.target.is_object() {
                    self.object_velocity_at_separation = Some(k.vp);
                }
                if self.brake_pending && self.contacts >= self.brake_after_contact {
                    self.brake_pending = false;
                    let due = self.t_detect.map_or(t, |d| d + self.dead_time).max(t);
                    self.plant.motion.stop_signal_at(due);
                }
            }
            EV_FRONT => {
                self.on_front = !self.on_front;
                if self.on_front {
                    if let Some(f) = self.plant.decoupler.front_stop() {
                        self.plant.front_chi = f.chi(k.s_dot);
                    }
                }
            }
            EV_CONTACT_PUSH => self.contact_push = !self.contact_push,
            EV_FRONT_PUSH => self.front_push = !self.front_push,
            EV_BACK_PUSH => self.back_push = !self.back_push,
            EV_SLIDE => {
                self.plant.switch_slide(t, y);
                if let Some(now) = self.plant.slide {
                    self.slide_switches.push((t, now));
                }
            }
            EV_BACK => {
                self.on_back = !self.on_back;
                if self.on_back {
                    if let Some(b) = self.plant.decoupler.back_stop() {
                        self.plant.back_chi = b.contact.chi(-k.s_dot);
                    }
                    self.t_back.get_or_insert(t);
                }
            }
            EV_SWITCH => {
                self.detected = true;
                self.t_detect = Some(t);
                let n = self.brake_after_contact;
                let held = n > 0 && (self.contacts < n || (self.contacts == n && self.in_contact));
                if !self.external_brake {
                    if held {
                        self.brake_pending = true;
                    } else {
                        self.plant.motion.stop_signal_at(t + self.dead_time);
                    }
                }
            }
            _ => {}
        }
        // Entering a contact or a stop: does its law push right away? (A grazing entry may not.)
        if matches!(i, EV_CONTACT | EV_FRONT | EV_BACK) {
            self.refresh_push(t, y);
        }
    }

    fn next_breakpoint(&self, t: f64) -> Option<f64> {
        self.plant.motion.breakpoints().into_iter().flatten().filter(|&b| b > t).reduce(f64::min)
    }

    fn on_step(&mut self, t0: f64, t1: f64, y1: &State, dense: &dyn Fn(f64) -> State) {
        if let Some(mut p) = self.probe.take() {
            p(&self.plant, t0, t1, dense);
            self.probe = Some(p);
        }
        match self.record_every {
            // output_interval = 0: every step's end (adding 0 to next_record would never end).
            Some(dt) if dt <= 0.0 => {
                let (k, f) = self.observe(t1, y1);
                self.history.push(sample(t1, &k, &f));
            }
            Some(dt) => {
                while let Some(tr) = record_due(self.records, dt, t0, t1) {
                    let y = if tr >= t1 { *y1 } else { dense(tr) };
                    let (k, f) = self.observe(tr, &y);
                    self.history.push(sample(tr, &k, &f));
                    self.records += 1;
                }
            }
            None => {}
        }
        if let Some(sink) = self.sink.as_mut() {
            self.history.drain(..).for_each(|s| sink(&s));
        }
        let (k, f) = self.observe(t1, y1);
        let at1 = (f.contact, f.robot.abs());
        // Peaks fall between step ends: while a contact is active, search the step's interpolant too.
        // On the front stop only while the tool moves against it (an impact), not at rest there.
        let front_impact = self.on_front && (k.s_dot.abs() > 1e-4 || self.last_end_s_dot.abs() > 1e-4);
        // Events end steps, so the flags hold through the whole step [t0, t1].
        let first_impact = self.in_contact && self.contacts == 1;
        if t1 > t0 && (self.in_contact || self.on_back || front_impact) {
            let at0 = if self.last_end.0 == t0 { self.last_end.1 } else {
                let f0 = self.observe(t0, &dense(t0)).1;
                (f0.contact, f0.robot.abs())
            };
            let (c, (tr, r)) = self.peaks_inside(t0, t1, at0, at1, dense, first_impact);
            self.peak_contact = self.peak_contact.max(c);
            let fr = if r > self.peak_robot { Some(self.observe(tr, &dense(tr)).1) } else { None };
            if let Some(fr) = fr {
                self.note_robot_peak(tr, r, first_impact, &fr);
            } else if first_impact {
                self.note_first_impact(tr, r);
            }
        }
        self.last_end = (t1, at1);
        self.last_end_s_dot = k.s_dot;
        self.peak_contact = self.peak_contact.max(f.contact);
        self.note_robot_peak(t1, f.robot.abs(), first_impact, &f);
        self.peak_object_v = self.peak_object_v.max(k.vp);
        self.max_travel = self.max_travel.max(self.plant.travel(&k));
        if let Some(p) = f.decoupler.gas_pressure {
            self.peak_gas = self.peak_gas.max(p);
        }
        if self.at_rest_from.is_none() && self.plant.motion.t_stop().is_some_and(|ts| t1 >= ts) && t1 < self.duration && self.at_rest(t1, y1) {
            self.at_rest_from = Some(t1);
        }
        let bottomed = self.plant.decoupler.back_stop().is_some_and(|b| b.penetration(k.s) > 0.0);
        if k.delta > 0.0 && (bottomed || self.plant.decoupler.is_rigid()) {
            self.exhausted = true;
        }
        // The same instants as `exhausted`, so stroke_left_min_m < 0 exactly when it is set (a
        // rigid tool: 0 and exhausted).
        if k.delta > 0.0 {
            let left = if self.plant.decoupler.is_rigid() { Some(0.0) } else { self.plant.decoupler.back_stop().map(|b| -b.penetration(k.s)) };
            self.deformation_max = Some(self.deformation_max.map_or(k.delta, |d| d.max(k.delta)));
            if let Some(l) = left {
                self.stroke_left_min = Some(self.stroke_left_min.map_or(l, |m| m.min(l)));
                self.closest_min = Some(self.closest_min.map_or(l - k.delta, |m| m.min(l - k.delta)));
            }
        }
    }
}

fn sample(t: f64, k: &Kinematics, f: &Forces) -> Sample {
    Sample {
        t, v_c: k.vc, v_r: k.vr, v_t: k.vt, v_p: k.vp, s: k.s,
        f_contact: f.contact, f_robot: f.robot, f_spring: f.decoupler.spring,
        f_stops: f.decoupler.front_stop + f.decoupler.back_stop, f_friction: f.decoupler.friction,
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

/// The inverse of the symmetric `n` x `n` (n <= 3) matrix `a` if it is positive definite
/// (Cholesky), else `None`.
fn spd_inverse(a: &[[f64; 3]; 3], n: usize) -> Option<[[f64; 3]; 3]> {
    let mut l = [[0.0; 3]; 3];
    for i in 0..n {
        for j in 0..=i {
            let s: f64 = a[i][j] - (0..j).map(|k| l[i][k] * l[j][k]).sum::<f64>();
            if i == j {
                if !s.is_finite() || s <= 0.0 {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    let mut inv = [[0.0; 3]; 3];
    for c in 0..n {
        // Solve L z = e_c, then L^T x = z.
        let mut z = [0.0; 3];
        for i in 0..n {
            let e = if i == c { 1.0 } else { 0.0 };
            z[i] = (e - (0..i).map(|k| l[i][k] * z[k]).sum::<f64>()) / l[i][i];
        }
        let mut x = [0.0; 3];
        for i in (0..n).rev() {
            x[i] = (z[i] - (i + 1..n).map(|k| l[k][i] * x[k]).sum::<f64>()) / l[i][i];
        }
        for (row, xi) in inv.iter_mut().zip(x).take(n) {
            row[c] = xi;
        }
    }
    Some(inv)
}

/// A scene's run in progress: the simulation, its stepper and its driver.
pub struct Run {
    /// The simulation (plant and bookkeeping).
    pub sim: Simulation,
    stepper: AnyStepper<N>,
    driver: Driver<N, E>,
    method: Method,
    duration: f64,
}

impl Simulation {
    /// A simulation of `scene`; with `external_brake` the sensor only records detection and the
    /// caller decides when braking starts (firmware in the loop).
    pub fn new(scene: &Scene, external_brake: bool, record: bool) -> Self {
        let (scene, simplified) = simplified(scene);
        let scene = &scene;
        let plant = Plant::new(scene);
        let mut warnings = Vec::new();
        for what in &simplified {
            warnings.push(format!("simplified model: {what} (solver.simplify; docs/accuracy.md gives its measured cost)"));
        }
        if plant.decoupler.friction_regularised() {
            warnings.push(format!("decoupler.friction.v0 below {} m/s was raised to it (Coulomb limit regularised, plant::friction)", plant::friction::V0_MIN));
        }
        if scene.motion.brake_after_contact > 0 {
            warnings.push(format!("motion.brake_after_contact = {}: braking held until tool-target contact {} has ended (a test of the thesis's account, not a controller; the robot never brakes if that contact does not happen)", scene.motion.brake_after_contact, scene.motion.brake_after_contact));
        }
        if scene.sensor.is_none() {
            warnings.push("no [sensor]: nothing detects the collision and the robot never brakes".into());
        }
        let mut sim = Self {
            plant,
            name: scene.name.clone(),
            dead_time: scene.motion.dead_time,
            external_brake,
            brake_after_contact: scene.motion.brake_after_contact,
            brake_pending: false,
            in_contact: false,
            on_front: false,
            on_back: false,
            contact_push: false,
            front_push: false,
            back_push: false,
            detected: false,
            rhs_evals: Cell::new(0),
            t_contact: None,
            t_detect: None,
            t_back: None,
            v_in_first: None,
            v_out_first: None,
            contacts: 0,
            object_velocity_at_separation: None,
            peak_contact: 0.0,
            peak_robot: 0.0,
            peak_robot_at: (0.0, "none"),
            first_impact_robot: (0.0, f64::NAN),
            peak_object_v: 0.0,
            peak_gas: 0.0,
            max_travel: 0.0,
            exhausted: false,
            stroke_left_min: None,
            deformation_max: None,
            closest_min: None,
            record_every: record.then_some(scene.solver.output_interval.max(0.0)),
            records: 0,
            history: Vec::new(),
            sink: None,
            probe: None,
            warnings,
            last_end: (f64::NAN, (0.0, 0.0)),
            last_end_s_dot: 0.0,
            fidelity: scene.solver.fidelity,
            simplified,
            peak_rtol: scene.solver.rtol.max(1e-12),
            body: match scene.target.kind {
                TargetKind::BodyRegion(b) => Some(b),
                _ => None,
            },
            duration: scene.duration_s,
            rest_tol: (scene.solver.rtol, scene.solver.atol, scene.motion.speed),
            at_rest_from: None,
            slide_switches: Vec::new(),
        };
        if let Some(TargetKind::Object { floor_friction: Some(_), .. }) = Some(scene.target.kind) {
            sim.warnings.push(format!("target.floor_friction regularised with v0 = {} m/s", plant::friction::V0_MIN));
        }
        sim
    }

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
    fn peaks_inside(&self, t0: f64, t1: f64, at0: (f64, f64), at1: (f64, f64), dense: &dyn Fn(f64) -> State, first_impact: bool) -> (f64, (f64, f64)) {
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

    fn note_first_impact(&mut self, t: f64, f: f64) {
        if f > self.first_impact_robot.0 || self.first_impact_robot.1.is_nan() {
            self.first_impact_robot = (f, t);
        }
    }

    /// Records a robot-force magnitude `f` at `t`: the whole run's peak with what was pushing
    /// then (from the `forces` at `t`, not from the event flags: a step ending on an event is
    /// evaluated just past it, before its flag flips), and the first impact's.
    fn note_robot_peak(&mut self, t: f64, f: f64, first_impact: bool, fs: &Forces) {
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
    fn robot_force_event(&self, fs: &Forces) -> &'static str {
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

    /// True when the plant is at rest at (t, y) for the rest of the run, so that holding the state
    /// from here to `duration` is the integration's answer to within the solver's tolerance. Called
    /// only once the commanded flange has stopped (t >= t_stop: x_c is constant from there, so the
    /// plant is autonomous and nothing outside it can move it again).
    ///
    /// The bodies the plant integrates (compliant robot, tool on a decoupler, free object) are
    /// near a static equilibrium: with every velocity set to zero the net forces F (springs,
    /// stops, contacts, weight; dampers and friction vanish at rest) are linearised, F(x + dx) =
    /// F - K dx, K by central differences (1e-7 m). If K is positive definite the equilibrium is
    /// stable and x_eq = x + K^-1 F; the energy about it, E = v^T M v / 2 + dx_eq^T K dx_eq / 2,
    /// can only fall (dampers and friction dissipate), so from here on every body stays within
    /// `|dx_eq_i| + sqrt(2 E (K^-1)_ii)` of where it is and below `sqrt(2 E / m_i)` in speed. The
    /// plant is at rest when those are within the solver's tolerance: `atol + rtol |x_i|` and
    /// `atol + rtol V_c` (V_c = motion.speed, the run's velocity scale). A body without any
    /// restoring force (a free object off the tool) must instead not move by the same tolerance
    /// when its velocity and static acceleration are extrapolated over the remaining time T:
    /// `|v| T + |a| T^2 / 2`. A tool balanced on the bi-stable's dead centre (K not positive), a
    /// body creeping under regularised friction or still swinging is not at rest.
    ///
    /// Why: a tool pressed into an end stop and the target at standstill can be the stiffest state
    /// of the run (a Hunt-Crossley damping chi d^1.5 grows with the penetration: the table11 scene
    /// with decel = 0.159 m/s^2 and duration = 19 s, 13.5 kN on the back stop, has about 7e5 1/s
    /// over the tool's mass, tests/box.rs). An explicit method's step is limited by stability there
    /// while nothing moves, and the integrated velocity does not even decay: it sits at 1.3e-9
    /// m/s (the stiff mode on the stability boundary, its damper and friction balancing 1e-6 N of
    /// static residual) while the position does not move in its last digit. That standstill cost
    /// 3.8 million steps for 17 s; its distance to the true equilibrium is 1e-12 m.
    fn at_rest(&self, t: f64, y: &State) -> bool {
        let rem = self.duration - t;
        let (rtol, atol, v_scale) = self.rest_tol;
        let tol_v = atol + rtol * v_scale;
        // (position, velocity, mass) of every integrated body.
        let mut dofs: Vec<(usize, usize, f64)> = Vec::with_capacity(3);
        if let Some(r) = self.plant.robot {
            dofs.push((plant::XR, plant::VR, r.mass));
        }
        if !self.plant.decoupler.is_rigid() {
            dofs.push((plant::XT, plant::VT, self.plant.tool_mass));
        }
        if let plant::target::Target::Object { mass, .. } = self.plant.target {
            dofs.push((plant::XP, plant::VP, mass));
        }
        if dofs.iter().any(|&(_, v, _)| y[v].is_nan() || tol_v.is_nan() || y[v].abs() > tol_v) {
            return false;
        }
        let mut still = *y;
        for &(_, v, _) in &dofs {
            still[v] = 0.0;
        }
        let force = |z: &State| {
            let mut dz = [0.0; N];
            self.plant.eval(t, z, &mut dz);
            let mut f = [0.0; 3];
            for (i, &(_, v, m)) in dofs.iter().enumerate() {
                f[i] = m * dz[v];
            }
            f
        };
        let f0 = force(&still);
        let n = dofs.len();
        const H: f64 = 1e-7;
        let mut k = [[0.0; 3]; 3];
        for j in 0..n {
            let (mut a, mut b) = (still, still);
            a[dofs[j].0] += H;
            b[dofs[j].0] -= H;
            let (fa, fb) = (force(&a), force(&b));
            for i in 0..n {
                k[i][j] = -(fa[i] - fb[i]) / (2.0 * H);
            }
        }
        // Bodies with no restoring force and no coupling (a free object off the tool): extrapolated.
        let mut bound = Vec::with_capacity(3);
        for i in 0..n {
            let (x, v, m) = dofs[i];
            if (0..n).all(|j| k[i][j] == 0.0 && k[j][i] == 0.0) {
                let a = f0[i] / m;
                if y[v].abs() * rem + 0.5 * a.abs() * rem * rem > atol + rtol * y[x].abs() || a.abs() * rem > tol_v {
                    return false;
                }
            } else {
                bound.push(i);
            }
        }
        let m = bound.len();
        if m == 0 {
            return true;
        }
        let mut ks = [[0.0; 3]; 3];
        for (p, &i) in bound.iter().enumerate() {
            for (q, &j) in bound.iter().enumerate() {
                ks[p][q] = 0.5 * (k[i][j] + k[j][i]);
            }
        }
        let Some(inv) = spd_inverse(&ks, m) else { return false };
        let mut dx = [0.0; 3];
        for p in 0..m {
            dx[p] = (0..m).map(|q| inv[p][q] * f0[bound[q]]).sum();
        }
        let potential: f64 = 0.5 * (0..m).map(|p| dx[p] * f0[bound[p]]).sum::<f64>();
        let kinetic: f64 = 0.5 * (0..m).map(|p| dofs[bound[p]].2 * y[dofs[bound[p]].1].powi(2)).sum::<f64>();
        let energy = potential.max(0.0) + kinetic;
        (0..m).all(|p| {
            let (x, _, mass) = dofs[bound[p]];
            dx[p].abs() + (2.0 * energy * inv[p][p]).sqrt() <= atol + rtol * y[x].abs() && (2.0 * energy / mass).sqrt() <= tol_v
        })
    }

    /// Kinematics and forces at (t, y).
    pub fn observe(&self, t: f64, y: &State) -> (Kinematics, Forces) {
        let k = self.plant.kinematics(t, y);
        let f = self.plant.forces(&k);
        (k, f)
    }

    fn refresh_push(&mut self, t: f64, y: &State) {
        let g = self.events(t, y);
        self.contact_push = g[EV_CONTACT_PUSH] > 0.0;
        self.front_push = g[EV_FRONT_PUSH] > 0.0;
        self.back_push = g[EV_BACK_PUSH] > 0.0;
    }

    fn init_flags(&mut self, t: f64, y: &State) {
        let g = self.events(t, y);
        self.in_contact = g[EV_CONTACT] > 0.0;
        self.plant.in_contact = self.in_contact;
        self.on_front = g[EV_FRONT] > 0.0;
        self.on_back = g[EV_BACK] > 0.0;
        self.refresh_push(t, y);
    }
}

impl Run {
    /// Prepares a run of `scene` (see [`Simulation::new`]).
    pub fn new(scene: &Scene, external_brake: bool, record: bool) -> Self {
        let mut sim = Simulation::new(scene, external_brake, record);
        let mut y0 = sim.plant.initial_state(scene.motion.start_at_speed, scene.motion.speed);
        sim.plant.init_slide(0.0, &mut y0);
        sim.init_flags(0.0, &y0);
        let s = &scene.solver;
        let stepper = match s.method {
            Method::Dopri5 => AnyStepper::Dopri5(Dopri5::<N>::new(s.rtol, s.atol)),
            Method::Rk4 => AnyStepper::Fixed(Fixed::<N>::new(FixedKind::Rk4)),
            Method::SemiImplicitEuler => AnyStepper::Fixed(Fixed::<N>::new(FixedKind::SemiImplicitEuler { pairs: 3 })),
        };
        let driver = Driver::new(&sim, 0.0, y0, Settings { max_step: s.max_step, ..Default::default() });
        sim.on_step(0.0, 0.0, &y0, &|_| y0);
        Self { sim, stepper, driver, method: s.method, duration: scene.duration_s }
    }

    /// Integrates to `t` (clamped to the scene's duration).
    pub fn advance_to(&mut self, t: f64) -> Result<(), SolveError> {
        self.driver.advance_to(&mut self.sim, &mut self.stepper, t.min(self.duration))
    }

    /// Integrates to the end of the scene.
    pub fn finish(&mut self) -> Result<(), SolveError> {
        self.advance_to(self.duration)
    }

    /// The state vector now.
    pub fn state(&self) -> State {
        self.driver.y
    }

    /// Current time, s.
    pub fn time(&self) -> f64 {
        self.driver.t
    }

    /// Kinematics and forces now.
    pub fn now(&self) -> (Kinematics, Forces) {
        self.sim.observe(self.driver.t, &self.driver.y)
    }

    /// The physical switch state now (true = threshold passed), if there is a sensor.
    pub fn sensor_tripped(&self) -> Option<bool> {
        let (k, f) = self.now();
        self.sim.plant.detector.map(|d| d.tripped(k.s, f.contact))
    }

    /// When the sensor's threshold was crossed (located event), s.
    pub fn switch_time(&self) -> Option<f64> {
        self.sim.t_detect
    }

    /// Travel back from the front stop now, m.
    pub fn travel(&self) -> f64 {
        let (k, _) = self.now();
        self.sim.plant.travel(&k)
    }

    /// The robot gets the stop signal at `t` (>= now), for an external controller: braking starts
    /// then, or with a stopping table the table's equivalent dead time later.
    pub fn command_brake(&mut self, t: f64) {
        self.sim.plant.motion.stop_signal_at(t.max(self.driver.t));
    }

    /// Drive power is removed at `t`: a category-0 stop, the arm's brakes stop it
    /// (`plant/brake.rs`). Returns the instant it takes effect: `t`, or now if `t` is already past
    /// and the arm did not move between `t` and now as a coasting arm would (then the caller says
    /// so). A `t` in the past is exact when the arm cruised at a constant speed since and the brakes
    /// had not engaged yet: coasting is that same motion.
    pub fn remove_power(&mut self, t: f64, brake: plant::brake::PowerOffBrake) -> f64 {
        let now = self.driver.t;
        let m = &self.sim.plant.motion;
        let at = if t >= now || (brake.delay >= now - t && m.steady_between(t, now)) { t } else { now };
        self.sim.plant.motion.remove_power_at(at, brake);
        at
    }

    /// The step the solver would take next, s (0 before its first estimate).
    pub fn next_step(&self) -> f64 {
        self.driver.next_step()
    }

    /// The Coulomb slide's stick/slip switches so far: instant and the state taken (empty without
    /// one).
    pub fn slide_switches(&self) -> &[(f64, plant::friction::Slide)] {
        &self.sim.slide_switches
    }

    /// Integration cost so far.
    pub fn stats(&self) -> Stats {
        self.driver.stats
    }

    /// The summary of the run so far.
    pub fn summary(&self) -> Summary {
        let s = &self.sim;
        let t_brake = s.plant.motion.t_brake();
        let (k, _) = self.now();
        let mode = s.plant.decoupler.back_stop().map(|_| match (s.t_back, s.plant.motion.t_stop()) {
            (None, _) => 1,
            (Some(tb), Some(ts)) if tb >= ts => 2,
            _ => 3,
        });
        let object = s.plant.target.is_object();
        let object_final = object.then(|| if s.in_contact { k.vp } else { s.object_velocity_at_separation.unwrap_or(k.vp) });
        let (achieved, achieved_null_reason) = achieved_restitution(s.v_in_first, s.v_out_first);
        let (detection_delay, detection_delay_null_reason) = detection_delay(s.t_contact, s.t_detect);
        let (reaction_time, reaction_time_null_reason) = reaction_time(s.t_contact, t_brake);
        let mut warnings = s.warnings.clone();
        if let Some(why) = s.plant.motion.adjusted {
            warnings.push(format!("motion.stopping: {why}"));
        }
        for (name, t) in [("t_brake", t_brake), ("t_stop", s.plant.motion.t_stop())] {
            if let Some(t) = t.filter(|&t| t > self.duration) {
                warnings.push(format!(
                    "{name} = {t} s is after the end of the run (duration = {} s): commanded by the motion law, not simulated; lengthen duration to see it",
                    self.duration
                ));
            }
        }
        let stats = self.driver.stats;
        let left_null = match (s.t_contact, s.stroke_left_min) {
            (None, _) => Some("the tool never touched the target".to_string()),
            (Some(_), None) => Some("the module has no back end-stop: its travel is not bounded by a stroke".to_string()),
            _ => None,
        };
        let mut summary = Summary {
            scene: s.name.clone(),
            t_contact: s.t_contact,
            t_detect: s.t_detect,
            t_brake,
            detection_delay,
            reaction_time,
            reaction_time_null_reason,
            peak_contact_force: s.peak_contact,
            peak_robot_force: s.peak_robot,
            object_final_velocity: object_final,
            mode,
            stroke_exhausted: s.exhausted,
            achieved_restitution: achieved,
            achieved_restitution_null_reason: achieved_null_reason,
            detection_delay_null_reason,
            steps: stats.steps,
            rhs_evals: s.rhs_evals.get(),
            t_stop: s.plant.motion.t_stop(),
            approach_velocity: s.v_in_first,
            contacts: s.contacts,
            object_peak_velocity: object.then_some(s.peak_object_v),
            max_travel: s.max_travel,
            decoupler_impulse: self.driver.y[plant::IMPULSE],
            peak_gas_pressure: matches!(s.plant.decoupler, plant::decoupler::Decoupler::Hydraulic(_)).then_some(s.peak_gas),
            rejected_steps: stats.rejected,
            at_rest_from_s: s.at_rest_from,
            events: stats.events,
            method: format!("{:?}", self.method),
            warnings,
            fidelity: format!("{:?}", s.fidelity).to_lowercase(),
            simplified: s.simplified.clone(),
            peak_robot_force_t_s: s.peak_robot_at.0,
            peak_robot_force_event: s.peak_robot_at.1.to_string(),
            first_impact_peak_robot_force_n: s.t_contact.map(|_| s.first_impact_robot.0),
            first_impact_peak_robot_force_t_s: s.t_contact.map(|_| s.first_impact_robot.1),
            first_impact_peak_robot_force_null_reason: s.t_contact.is_none().then(|| "no tool-target contact in the run".to_string()),
            stroke_left_min_m: s.stroke_left_min,
            stroke_left_min_m_null_reason: left_null,
            target_deformation_max_m: s.deformation_max,
            closest_approach_m: s.closest_min,
            concluded: {
                let (reach, left) = self.after_end();
                // One period of the robot's compliance (0 for a rigid robot).
                let settle = s.plant.robot.map_or(0.0, |r| if r.stiffness > 0.0 { std::f64::consts::TAU * (r.mass / r.stiffness).sqrt() } else { f64::INFINITY });
                crate::verdict::concluded(s.t_contact, s.plant.motion.t_stop(), self.duration, settle, reach, left, s.body.is_some())
            },
            t_end_s: self.duration,
            flange_reach_after_end_m: self.after_end().0,
            safe: false,
            failures: Vec::new(),
            body_region: None,
            body_contact: None,
            body_effective_mass_kg: None,
            body_stiffness_n_per_m: None,
            body_contact_area_m2: None,
            body_peak_force_n: None,
            body_force_limit_n: None,
            body_force_margin_n: None,
            body_peak_pressure_pa: None,
            body_pressure_limit_pa: None,
            body_pressure_margin_pa: None,
            body_limits_pass: None,
        };
        if let Some(b) = &s.body {
            let c = crate::body::check(b, s.peak_contact);
            summary.body_region = Some(b.region.name.to_string());
            summary.body_contact = Some(b.contact.name().to_string());
            summary.body_effective_mass_kg = Some(b.mass_kg);
            summary.body_stiffness_n_per_m = Some(b.stiffness_n_per_m);
            summary.body_contact_area_m2 = Some(b.area_m2);
            summary.body_peak_force_n = Some(c.peak_force_n);
            summary.body_peak_pressure_pa = Some(c.peak_pressure_pa);
            if let Some((f, p)) = c.limits {
                summary.body_force_limit_n = Some(f);
                summary.body_force_margin_n = Some(f - c.peak_force_n);
                summary.body_pressure_limit_pa = Some(p);
                summary.body_pressure_margin_pa = Some(p - c.peak_pressure_pa);
            }
            summary.body_limits_pass = Some(c.failures.is_empty());
        }
        summary.failures = crate::verdict::failures(&summary);
        summary.safe = summary.failures.is_empty();
        summary
    }
}

/// When row `k` of a history at interval `dt` falls in the step `[t0, t1]`: at `k dt`, a product,
/// not a running sum (6e5 additions of 1e-4 drifted to 1e-9 s past the end of a 60 s run, whose
/// last row was then lost); a row within `1e-9 dt` past the step's end is taken at its end (the
/// rounding of `k dt` itself). [`recorded_rows`] counts them.
pub fn record_due(k: u64, dt: f64, t0: f64, t1: f64) -> Option<f64> {
    let tk = k as f64 * dt;
    (tk <= t1 + 1e-9 * dt).then(|| tk.clamp(t0, t1))
}

/// Rows a run of `duration` s records at `dt` > 0: `k dt` for every `k` that [`record_due`] takes.
pub fn recorded_rows(duration: f64, dt: f64) -> u64 {
    let n = (duration / dt + 1e-9).floor();
    let Some(mut k) = (n.is_finite() && n >= 0.0).then(|| n.min(1e18) as u64) else { return u64::MAX };
    // The division's own rounding: the test `record_due` makes decides the last row.
    for _ in 0..3 {
        if record_due(k + 1, dt, duration, duration).is_some() {
            k += 1;
        } else if k > 0 && record_due(k, dt, duration, duration).is_none() {
            k -= 1;
        }
    }
    k + 1
}

impl Run {
    /// At the run's end: how far the flange can still advance towards the target (m; see
    /// `Summary::flange_reach_after_end_m`), and the stroke left (m; None without a back
    /// end-stop or for a rigid tool).
    fn after_end(&self) -> (f64, Option<f64>) {
        let y = &self.driver.y;
        let k = self.sim.plant.kinematics(self.duration, y);
        let reach = match self.sim.plant.robot {
            Some(r) if r.stiffness > 0.0 => {
                let amp = ((k.xr - k.xc).powi(2) + r.mass * k.vr * k.vr / r.stiffness).sqrt();
                (k.xc + amp - k.xr).max(0.0)
            }
            Some(_) => f64::INFINITY,
            None => 0.0,
        };
        // A rigid tool is exhausted on contact: no stroke to keep.
        let left = if self.sim.plant.decoupler.is_rigid() { None } else { self.sim.plant.decoupler.back_stop().map(|b| -b.penetration(k.s)) };
        (if reach.is_nan() { f64::INFINITY } else { reach }, left)
    }
}

/// The longest run [`run_to_conclusion`] makes, s: the validator's largest `duration`.
pub const LONGEST_RUN_S: f64 = 60.0;

/// Runs a scene, doubling its `duration` (up to [`LONGEST_RUN_S`]) until the run is concluded
/// (`Summary::concluded`: the robot stood still after the contact), for the searches of `design`
/// whose candidates' durations are estimates: a slow candidate detects late (the switch travel at
/// a few mm/s takes seconds), and a run cut off before the stop says nothing. The summary says so
/// in `warnings` when the duration was lengthened; a run still not concluded at 60 s stays not
/// concluded, so not safe.
pub fn run_to_conclusion(scene: &Scene) -> Result<Summary, SolveError> {
    let (mut summary, _) = run(scene, false)?;
    let mut s = scene.clone();
    while !summary.concluded && s.duration_s < LONGEST_RUN_S {
        s.duration_s = (2.0 * s.duration_s).min(LONGEST_RUN_S);
        summary = run(&s, false)?.0;
    }
    if s.duration_s != scene.duration_s {
        summary.warnings.push(format!(
            "duration lengthened from {} s to {} s so that the robot stops within the run{}",
            scene.duration_s,
            s.duration_s,
            if summary.concluded { "" } else { " (it did not: not concluded at the longest run)" }
        ));
    }
    Ok(summary)
}

/// Runs a scene to its end and returns the summary and, if `record`, the time history.
pub fn run(scene: &Scene, record: bool) -> Result<(Summary, Vec<Sample>), SolveError> {
    let mut r = Run::new(scene, false, record);
    r.finish()?;
    let summary = r.summary();
    Ok((summary, std::mem::take(&mut r.sim.history)))
}
