//! [`Simulation`]: the plant as the solver sees it, a hybrid system (right-hand side, events, what
//! happens at each, the steps observed: peaks, first impact, the record), and what it has seen so far.

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

use flinch_plant::{self as plant, Forces, Kinematics, Plant, State, N};
use flinch_model::scene::{Fidelity, Scene, TargetKind};
use flinch_solver::driver::{Crossing, Hybrid};
use flinch_solver::System;
use std::cell::Cell;
use crate::events::*;
use crate::simplify::simplified;
use crate::record::record_due;
use crate::summary::Sample;

/// See [`Simulation::sink`].
pub type Sink = Box<dyn FnMut(&Sample)>;

/// See [`Simulation::probe`].
pub type Probe = Box<dyn FnMut(&Plant, f64, f64, &dyn Fn(f64) -> State)>;

/// The plant as a hybrid system, with the run's bookkeeping.
pub struct Simulation {
    /// The plant.
    pub plant: Plant,
    pub(crate) name: String,
    pub(crate) dead_time: f64,
    pub(crate) external_brake: bool,
    /// `motion.brake_after_contact` (0: off).
    pub(crate) brake_after_contact: u32,
    /// Detected, braking held until that contact ends.
    pub(crate) brake_pending: bool,
    pub(crate) in_contact: bool,
    pub(crate) on_front: bool,
    pub(crate) on_back: bool,
    /// While penetrated: the law's unclamped force pushes (false: clamped at zero).
    pub(crate) contact_push: bool,
    pub(crate) front_push: bool,
    pub(crate) back_push: bool,
    pub(crate) detected: bool,
    pub(crate) rhs_evals: Cell<u64>,
    pub(crate) t_contact: Option<f64>,
    pub(crate) t_detect: Option<f64>,
    pub(crate) t_back: Option<f64>,
    pub(crate) v_in_first: Option<f64>,
    pub(crate) v_out_first: Option<f64>,
    pub(crate) contacts: u32,
    pub(crate) object_velocity_at_separation: Option<f64>,
    pub(crate) peak_contact: f64,
    pub(crate) peak_robot: f64,
    /// When `peak_robot` occurred and what was pushing then.
    pub(crate) peak_robot_at: (f64, &'static str),
    /// Peak robot-force magnitude and its instant during the first tool-target contact.
    pub(crate) first_impact_robot: (f64, f64),
    pub(crate) peak_object_v: f64,
    pub(crate) peak_gas: f64,
    pub(crate) max_travel: f64,
    pub(crate) exhausted: bool,
    /// While touching the target: smallest stroke left, largest deformation, closest approach.
    pub(crate) stroke_left_min: Option<f64>,
    pub(crate) deformation_max: Option<f64>,
    pub(crate) closest_min: Option<f64>,
    pub(crate) record_every: Option<f64>,
    /// Rows recorded so far: the next is due at `records * dt` (see [`record_due`]).
    pub(crate) records: u64,
    /// The recorded time history (empty unless recording).
    pub history: Vec<Sample>,
    /// Where recorded samples go as each step makes them (a streamed CSV, a decimated plot: memory
    /// stays bounded whatever the duration); `None` keeps them in `history`.
    pub sink: Option<Sink>,
    /// Called after every accepted step with the plant, the step's span [t0, t1] and its dense
    /// output: firmware in the loop reads the switch between steps from it (`flinch-hil`).
    pub probe: Option<Probe>,
    pub(crate) warnings: Vec<String>,
    /// Contact and robot-force magnitude at the end of the last step (t, (N, N)).
    pub(crate) last_end: (f64, (f64, f64)),
    /// s' at the end of the last step, m/s.
    pub(crate) last_end_s_dot: f64,
    /// Relative accuracy the in-step peak search stops at.
    pub(crate) peak_rtol: f64,
    pub(crate) fidelity: Fidelity,
    pub(crate) simplified: Vec<String>,
    /// The body region hit, if the target is one (ISO/TS 15066 Annex A, flinch_model::body).
    pub(crate) body: Option<flinch_model::body::BodyTarget>,
    /// The scene's duration, s (the rest check extrapolates to it).
    pub(crate) duration: f64,
    /// The solver's tolerances (rtol, atol) and the velocity scale of the run (motion.speed, m/s),
    /// which set what "at rest" means.
    pub(crate) rest_tol: (f64, f64, f64),
    /// From this instant on the plant is at rest and held (`at_rest_from_s`).
    pub(crate) at_rest_from: Option<f64>,
    /// Instants a Coulomb slide switched between sticking and slipping (event 7), with the state
    /// taken.
    pub(crate) slide_switches: Vec<(f64, plant::friction::Slide)>,
    /// The rotational module's largest |stage turn| so far, rad.
    pub(crate) max_rotation: f64,
    /// When the rotational module engaged and its stage turn then (s, rad).
    pub(crate) engaged: Option<(f64, f64)>,
    /// Planar runs: since when (s) the module has been pushed far above its release force without
    /// moving, and the stage angle then (rad); see `BLOCKED_AFTER_S`.
    pub(crate) pushed_still: Option<(f64, f64)>,
    /// Planar runs: the first instant the module was blocked and the contact force then (s, N).
    pub(crate) blocked: Option<(f64, f64)>,
}

/// A planar module counts as blocked when, touching the target, the contact force has stayed above
/// `BLOCKED_FACTOR` times the force that releases it along the contact's normal for this long, s. An impact is shorter: the hits of
/// the Fig. 69 runs last a few ms and move the stage (tests/rotational.rs).
pub const BLOCKED_AFTER_S: f64 = 0.02;
/// The margin on the release force (the force builds up inside its friction cone before the module
/// yields).
pub const BLOCKED_FACTOR: f64 = 2.0;

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
        if self.plant.planar.is_some_and(|p| p.scene.rotational.is_some()) {
            self.note_rotation(t0, t1, &k, dense);
        }
        if self.plant.planar.is_some() {
            self.note_blocked(t1, &k, f.contact);
        }
        if let Some(p) = f.decoupler.gas_pressure {
            self.peak_gas = self.peak_gas.max(p);
        }
        if self.at_rest_from.is_none() && self.plant.motion.t_stop().is_some_and(|ts| t1 >= ts) && t1 < self.duration && self.at_rest(t1, y1) {
            self.at_rest_from = Some(t1);
        }
        if k.delta > 0.0 && self.plant.exhausted(&k) {
            self.exhausted = true;
        }
        // The same instants as `exhausted`, so stroke_left_min_m < 0 exactly when it is set (a
        // rigid tool: 0 and exhausted).
        if k.delta > 0.0 {
            let left = self.plant.stroke_left(&k);
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
            max_rotation: 0.0,
            engaged: None,
            pushed_still: None,
            blocked: None,
        };
        if let Some(TargetKind::Object { floor_friction: Some(_), .. }) = Some(scene.target.kind) {
            sim.warnings.push(format!("target.floor_friction regularised with v0 = {} m/s", plant::friction::V0_MIN));
        }
        sim
    }

    /// Kinematics and forces at (t, y).
    pub fn observe(&self, t: f64, y: &State) -> (Kinematics, Forces) {
        let k = self.plant.kinematics(t, y);
        let f = self.plant.forces(&k);
        (k, f)
    }

    pub(crate) fn refresh_push(&mut self, t: f64, y: &State) {
        let g = self.events(t, y);
        self.contact_push = g[EV_CONTACT_PUSH] > 0.0;
        self.front_push = g[EV_FRONT_PUSH] > 0.0;
        self.back_push = g[EV_BACK_PUSH] > 0.0;
    }

    pub(crate) fn init_flags(&mut self, t: f64, y: &State) {
        let g = self.events(t, y);
        self.in_contact = g[EV_CONTACT] > 0.0;
        self.plant.in_contact = self.in_contact;
        self.on_front = g[EV_FRONT] > 0.0;
        self.on_back = g[EV_BACK] > 0.0;
        self.refresh_push(t, y);
    }
}

impl Simulation {
    /// The rotational module's bookkeeping after a step [t0, t1] ending at `k`: the largest turn,
    /// and the first instant the tool has travelled `ENGAGED_TRAVEL_M` back while touching the
    /// target (bisected on the step's interpolant to 1e-12 s).
    fn note_rotation(&mut self, t0: f64, t1: f64, k: &Kinematics, dense: &dyn Fn(f64) -> State) {
        self.max_rotation = self.max_rotation.max(k.plane.phi[0].abs());
        if self.engaged.is_some() {
            return;
        }
        let engaged = |sim: &Self, k: &Kinematics| k.delta > 0.0 && sim.plant.travel(k) >= crate::summary::ENGAGED_TRAVEL_M;
        if !engaged(self, k) {
            return;
        }
        let (mut a, mut b) = (t0, t1);
        if t1 > t0 && !engaged(self, &self.plant.kinematics(t0, &dense(t0))) {
            while b - a > 1e-12 {
                let m = 0.5 * (a + b);
                if engaged(self, &self.plant.kinematics(m, &dense(m))) { b = m } else { a = m }
            }
        }
        let kb = self.plant.kinematics(b, &dense(b));
        self.engaged = Some((b, kb.plane.phi[0]));
    }
}

impl Simulation {
    /// Planar runs against a fixed target: is the module pushed far above what makes it yield
    /// ([`BLOCKED_AFTER_S`])? The share of the push that drives the tool along its guide is
    /// c - mu sqrt(1 - c^2), c = u . m, mu the contact's friction (the friction cone about the
    /// normal). A yielding module balances that share with its own force (spring, damper, slide
    /// friction: `DecouplerForce::spring + friction`, not the stops); a blocked one (its guide
    /// across the push, locked by friction, on its front stop with a stage that cannot turn) lets the
    /// contact force grow far above it. The bar is `BLOCKED_FACTOR` x (that force + the release
    /// force) over the share (over 1 when the share is not positive: the guide jams). A bottomed tool
    /// is `stroke_exhausted`, not this; an axial frictionless scene is the 1-D one and is not judged
    /// here (its runs stay identical to the 1-D plant's).
    fn note_blocked(&mut self, t: f64, k: &Kinematics, contact: f64) {
        if self.blocked.is_some() {
            return;
        }
        let Some(p) = self.plant.planar else { return };
        let c = p.retreat_share(k);
        let axial = p.scene.rotational.is_none() && p.scene.contact_mu == 0.0 && c == 1.0;
        let bottomed = self.plant.decoupler.back_stop().is_some_and(|b| b.penetration(k.s) > 0.0);
        if axial || self.plant.target.is_object() || bottomed {
            self.pushed_still = None;
            return;
        }
        let drive = c - p.scene.contact_mu * (1.0 - c * c).max(0.0).sqrt();
        let d = self.plant.decoupler.force(k.s, k.s_dot, self.plant.front_chi, self.plant.back_chi);
        let own = (d.spring + d.friction).abs() + self.plant.release_force();
        let release = own / if drive > 0.0 { drive } else { 1.0 };
        if self.in_contact && contact > BLOCKED_FACTOR * release {
            let phi = k.plane.phi[0];
            match self.pushed_still {
                // The rotational module yields by turning: a stage that turned 1 deg starts the clock again.
                Some((_, phi0)) if (phi - phi0).abs() > 1f64.to_radians() => self.pushed_still = Some((t, phi)),
                Some((t0, _)) if t - t0 >= BLOCKED_AFTER_S => self.blocked = Some((t, contact)),
                Some(_) => {}
                None => self.pushed_still = Some((t, phi)),
            }
        } else {
            self.pushed_still = None;
        }
    }
}
