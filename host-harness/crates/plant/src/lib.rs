//! The plant: motion law, robot, decoupler, contact, target and sensor, one element per file,
//! assembled into one ODE (eq 33-45, 49-54). Coordinates are 1-D along the approach, +x towards
//! the target (MODEL.md): x_c commanded flange, x_r actual flange, x_t tool face, x_p object face;
//! the stroke coordinate is s = x_t - x_r.
//!
//! State (a stack array): [x_r, v_r, x_t, v_t, x_p, v_p, I], I the decoupler impulse of eq 21
//! accumulated while in contact. Entries an element does not use (x_r of a rigid robot, x_t of a
//! rigid tool, x_p of an obstacle) stay constant and are ignored.

pub mod brake;
pub mod contact;
pub mod decoupler;
pub mod friction;
pub mod motion_law;
pub mod planar;
pub mod robot;
pub mod sensor;
pub mod state;
pub mod target;

pub use state::*;

use flinch_model::scene::Scene;
use contact::Contact;
use decoupler::{Decoupler, DecouplerForce};
use friction::Slide;
use motion_law::MotionLaw;
use robot::CompliantRobot;
use sensor::Detector;
use target::Target;

/// The assembled plant, with the contact dampings fixed at their onsets.
#[derive(Debug, Clone)]
pub struct Plant {
    /// The commanded flange motion (braking is scheduled into it).
    pub motion: MotionLaw,
    /// Compliant robot, or `None` for x_r = x_c.
    pub robot: Option<CompliantRobot>,
    /// m_t, kg.
    pub tool_mass: f64,
    /// Gravity along the approach, m/s^2.
    pub gravity: f64,
    /// The decoupler.
    pub decoupler: Decoupler,
    /// Tool-target contact.
    pub contact: Contact,
    /// The target.
    pub target: Target,
    /// The detector, if any.
    pub detector: Option<Detector>,
    /// chi of the current (or last) tool-target contact.
    pub target_chi: f64,
    /// chi of the current (or last) back-stop contact.
    pub back_chi: f64,
    /// chi of the current (or last) landing on a Hunt-Crossley front stop (0 for eq 28's).
    pub front_chi: f64,
    /// Stroke coordinate at rest (static equilibrium), m.
    pub s_rest: f64,
    /// True between a located contact onset and its separation: the decoupler impulse (eq 21)
    /// accumulates. A discrete state set at the events, not `delta > 0` tested inside the
    /// right-hand side, which would make the impulse's rate jump inside a step: that jump alone
    /// cost a dozen rejected steps at every contact onset (docs/accuracy.md).
    pub in_contact: bool,
    /// The stick/slip state of a Coulomb slide (`decoupler.friction.law = "stick-slip"`), set at
    /// located events (`flinch-sim`); `None` for every other decoupler. While sticking, the tool's
    /// position is the flange's plus the stuck stroke, whatever the state vector says.
    pub slide: Option<Slide>,
    /// The planar parts (`planar/`), for a scene with planar keys or `solver.plant = "planar"`.
    pub planar: Option<planar::Planar>,
}

impl Plant {
    /// Assembles a scene, with every body at static equilibrium at t = 0.
    pub fn new(scene: &Scene) -> Self {
        let decoupler = Decoupler::new(&scene.decoupler, &scene.tool);
        let robot = scene.robot.as_ref().map(|r| CompliantRobot::new(r, if decoupler.is_rigid() { scene.tool.mass } else { 0.0 }));
        let mut plant = Self {
            motion: MotionLaw::new(&scene.motion),
            robot,
            tool_mass: scene.tool.mass,
            gravity: scene.motion.gravity,
            decoupler,
            contact: match scene.target.kind {
                // ISO/TS 15066 Annex A: the body is an undamped linear spring.
                flinch_model::scene::TargetKind::BodyRegion(b) => Contact::linear(b.stiffness_n_per_m),
                _ => Contact::new(scene.target.stiffness, &scene.target.damping),
            },
            target: Target::Obstacle { surface: 0.0 },
            detector: None,
            target_chi: 0.0,
            back_chi: 0.0,
            front_chi: 0.0,
            s_rest: 0.0,
            in_contact: false,
            slide: None,
            planar: None,
        };
        let obstacle = matches!(scene.target.kind, flinch_model::scene::TargetKind::Obstacle)
            || matches!(scene.target.kind, flinch_model::scene::TargetKind::BodyRegion(b) if b.contact == flinch_model::body::BodyContact::QuasiStatic);
        plant.planar = scene.planar.as_ref().map(|p| planar::Planar::new(p, plant.robot.is_some() && obstacle));
        plant.s_rest = plant.rest_stroke();
        // A tool resting on a Hunt-Crossley front stop at t = 0: a landing at (the floor of) zero speed.
        plant.front_chi = plant.decoupler.front_stop().map_or(0.0, |f| f.chi(0.0));
        let x_r0 = plant.robot.map_or(0.0, |r| r.static_offset(plant.tool_mass * plant.gravity));
        let face0 = match &plant.planar {
            // The tool's point along m: the flange lags along its path, the tool rides the guide.
            Some(p) => match &p.scene.rotational {
                Some(st) => {
                    let front = plant.decoupler.front_stop().map_or(plant.s_rest, |f| f.at);
                    let r = planar::rotational_stage::tool_offset(st, front, plant.s_rest, 0.0);
                    planar::frame::dot([x_r0 * p.dir.ep[0] + r[0], x_r0 * p.dir.ep[1] + r[1]], p.dir.m) + st.tool_radius
                }
                None => planar::frame::dot(planar::frame::comb(x_r0 * planar::frame::dot(p.dir.ep, p.dir.u) + plant.s_rest, p.dir.u, x_r0 * planar::frame::dot(p.dir.ep, p.dir.w), p.dir.w), p.dir.m),
            },
            None => x_r0 + plant.s_rest,
        };
        plant.target = Target::new(&scene.target.kind, face0, scene.target.gap);
        let reference = plant.decoupler.front_stop().map_or(plant.s_rest, |f| f.at);
        plant.detector = scene.sensor.as_ref().map(|s| Detector::new(s, reference));
        plant
    }

    /// The stroke at which the decoupler holds the tool's weight at rest: the stable equilibrium
    /// nearest the front (scan from the front down, then bisect), or the front stop if none.
    fn rest_stroke(&self) -> f64 {
        let w = self.tool_mass * self.gravity;
        let net = |s: f64| self.decoupler.force(s, 0.0, 0.0, 0.0).total + w;
        match (&self.decoupler, self.decoupler.front_stop(), self.decoupler.back_stop()) {
            (Decoupler::Rigid, ..) => 0.0,
            (Decoupler::Linear(l), ..) if l.stiffness > 0.0 => w / l.stiffness,
            (Decoupler::Linear(_), ..) => 0.0,
            (_, Some(front), Some(back)) => {
                // Above the front stop the net force is negative (the stop pushes back) far enough in.
                let mut hi = front.at + (w.abs() + 1.0) / front.stiffness * 10.0 + 1e-9;
                while net(hi) > 0.0 && hi < front.at + 1.0 {
                    hi = front.at + 2.0 * (hi - front.at);
                }
                let n = 4000;
                let lo_end = back.at;
                let mut prev = hi;
                for k in 1..=n {
                    let s = hi - (hi - lo_end) * k as f64 / n as f64;
                    if net(s) >= 0.0 {
                        let (mut a, mut b) = (s, prev);
                        for _ in 0..200 {
                            let m = 0.5 * (a + b);
                            if net(m) >= 0.0 { a = m } else { b = m }
                        }
                        return 0.5 * (a + b);
                    }
                    prev = s;
                }
                back.at
            }
            _ => 0.0,
        }
    }

    /// Initial state: at rest (or cruising at V_c with `start_at_speed`), in static equilibrium.
    pub fn initial_state(&self, start_at_speed: bool, speed: f64) -> State {
        let v0 = if start_at_speed { speed } else { 0.0 };
        let x_r0 = self.robot.map_or(0.0, |r| r.static_offset(self.tool_mass * self.gravity));
        let mut y = [0.0; N];
        y[XR] = x_r0;
        y[VR] = v0;
        y[XT] = x_r0 + self.s_rest;
        y[VT] = v0;
        if let Some(p) = &self.planar {
            let along = planar::frame::dot(p.dir.ep, p.dir.u);
            y[XT] = x_r0 * along + self.s_rest;
            y[VT] = v0 * along;
            if p.scene.rotational.is_some() {
                y[XT] = self.s_rest;
                y[VT] = 0.0;
            }
        }
        if let Target::Object { start, .. } = self.target {
            y[XP] = start;
        }
        y
    }

    /// Positions and velocities of every body.
    pub fn kinematics(&self, t: f64, y: &State) -> Kinematics {
        if let Some(p) = &self.planar {
            return planar::kinematics(&self.parts(), p, t, y);
        }
        let c = self.motion.at(t);
        let (xr, vr) = if self.robot.is_some() { (y[XR], y[VR]) } else { (c.x, c.v) };
        let (xt, vt) = match self.slide {
            _ if self.decoupler.is_rigid() => (xr, vr),
            Some(Slide::Stick { s }) => (xr + s, vr),
            _ => (y[XT], y[VT]),
        };
        let (xp, vp) = match self.target {
            Target::Obstacle { surface } => (surface, 0.0),
            Target::Object { .. } => (y[XP], y[VP]),
        };
        Kinematics { xc: c.x, vc: c.v, ac: c.a, xr, vr, xt, vt, xp, vp, s: xt - xr, s_dot: vt - vr, delta: xt - xp, delta_dot: vt - vp, plane: PlaneKinematics::default() }
    }

    /// Forces at one instant.
    pub fn forces(&self, k: &Kinematics) -> Forces {
        if let Some(p) = &self.planar {
            return planar::forces(&self.parts(), p, k).0;
        }
        let contact = self.contact.force(k.delta, k.delta_dot, self.target_chi);
        let mut decoupler = self.decoupler.force(k.s, k.s_dot, self.front_chi, self.back_chi);
        if self.slide.is_some() {
            self.add_slide_friction(k, contact, &mut decoupler);
        }
        let robot = if self.decoupler.is_rigid() { -contact } else { -decoupler.total };
        Forces { contact, decoupler, robot }
    }

    /// Adds a Coulomb slide's friction to the decoupler's force. Kept out of [`Self::forces`] so
    /// that stays small enough to be inlined: with this code inside it, it was not, and every scene
    /// without a Coulomb slide ran 5 % more instructions (callgrind, Tables 5-7).
    #[inline(never)]
    fn add_slide_friction(&self, k: &Kinematics, contact: f64, decoupler: &mut DecouplerForce) {
        if let Some(slide) = self.slide {
            let (limit, req, _) = self.slide_terms(k, contact, decoupler.total);
            decoupler.friction = slide.force(limit, req);
            decoupler.total += decoupler.friction;
        }
    }

    /// For a Coulomb slide: the friction limit mu |F_n| (N), the friction that would keep s'' = 0
    /// (N), and s'' without friction (m/s^2), given the contact force and the decoupler's force
    /// without the Coulomb friction (`others`). s'' = a0 + b F_f with b = 1/m_t + 1/m_r (a rigid
    /// robot follows its law whatever the force: b = 1/m_t).
    fn slide_terms(&self, k: &Kinematics, contact: f64, others: f64) -> (f64, f64, f64) {
        if let Some(p) = &self.planar {
            return planar::slide_terms_at(&self.parts(), p, k, contact, others);
        }
        let limit = self.decoupler.friction_limit(k.s);
        let a_t = (others - contact + self.tool_mass * self.gravity) / self.tool_mass;
        let (a_r, inv_mr) = match &self.robot {
            Some(r) => {
                let c = motion_law::Commanded { x: k.xc, v: k.vc, a: k.ac };
                (r.accel(&c, k.xr, k.vr, -others), 1.0 / r.mass)
            }
            None => (k.ac, 0.0),
        };
        let a0 = a_t - a_r;
        (limit, friction::required(a0, 1.0 / self.tool_mass + inv_mr), a0)
    }

    /// The Coulomb slide's event function at (t, y) (positive while its state holds), or `None`
    /// without one.
    pub fn slide_event(&self, k: &Kinematics) -> Option<f64> {
        let slide = self.slide?;
        let contact = self.contact.force(k.delta, k.delta_dot, self.target_chi);
        let others = self.decoupler.force(k.s, k.s_dot, self.front_chi, self.back_chi).total;
        let (limit, req, _) = self.slide_terms(k, contact, others);
        Some(slide.event(limit, req, k.s_dot))
    }

    /// Switches the Coulomb slide at t (a located event, or the start): the tool's state is set to
    /// the relative velocity zero it has there (to within [`friction::SLIP_END`]; while sticking,
    /// to the stuck position), and the state is chosen again ([`Slide::decide`]).
    pub fn switch_slide(&mut self, t: f64, y: &mut State) {
        if self.slide.is_none() || self.stick_slip_off() {
            return;
        }
        let k = self.kinematics(t, y);
        y[XT] = k.xt;
        y[VT] = k.vr;
        self.slide = Some(Slide::Slip { dir: 1.0 });
        let k = self.kinematics(t, y);
        let contact = self.contact.force(k.delta, k.delta_dot, self.target_chi);
        let others = self.decoupler.force(k.s, k.s_dot, self.front_chi, self.back_chi).total;
        let (limit, req, a0) = self.slide_terms(&k, contact, others);
        self.slide = Some(Slide::decide(k.s, limit, req, a0));
    }

    fn stick_slip_off(&self) -> bool {
        self.decoupler.stick_slip_mu().is_none()
    }

    /// Arms the Coulomb slide's state at the start (t, y), if the decoupler has one.
    pub fn init_slide(&mut self, t: f64, y: &mut State) {
        if self.decoupler.stick_slip_mu().is_some() {
            self.slide = Some(Slide::Slip { dir: 1.0 });
            self.switch_slide(t, y);
        }
    }

    /// The right-hand side, with the kinematics and forces it used.
    pub fn eval(&self, t: f64, y: &State, dy: &mut State) -> (Kinematics, Forces) {
        if let Some(p) = &self.planar {
            return planar::eval(&self.parts(), p, t, y, dy);
        }
        let k = self.kinematics(t, y);
        let f = self.forces(&k);
        *dy = [0.0; N];
        let weight = self.tool_mass * self.gravity;
        if let Some(r) = &self.robot {
            let c = motion_law::Commanded { x: k.xc, v: k.vc, a: k.ac };
            // Rigid tool: contact and the tool's weight act on the joint mass m_r + m_t.
            let f_ext = if self.decoupler.is_rigid() { weight - f.contact } else { f.robot };
            dy[XR] = k.vr;
            dy[VR] = r.accel(&c, k.xr, k.vr, f_ext);
        }
        if !self.decoupler.is_rigid() {
            dy[XT] = k.vt;
            dy[VT] = match self.slide {
                // Sticking: the tool moves with the flange (the same acceleration to the last bit,
                // so the state stays with the kinematics above).
                Some(Slide::Stick { .. }) => if self.robot.is_some() { dy[VR] } else { k.ac },
                _ => (f.decoupler.total - f.contact + weight) / self.tool_mass,
            };
        }
        if self.target.is_object() {
            dy[XP] = k.vp;
            dy[VP] = self.target.accel(f.contact, k.vp);
        }
        dy[IMPULSE] = if self.in_contact { f.decoupler.total } else { 0.0 };
        (k, f)
    }

    /// The elements the planar plant reads, borrowed.
    pub fn parts(&self) -> Parts<'_> {
        Parts {
            motion: &self.motion,
            robot: self.robot.as_ref(),
            tool_mass: self.tool_mass,
            gravity: self.gravity,
            decoupler: &self.decoupler,
            contact: &self.contact,
            target: self.target,
            target_chi: self.target_chi,
            back_chi: self.back_chi,
            front_chi: self.front_chi,
            s_rest: self.s_rest,
            in_contact: self.in_contact,
            slide: self.slide,
        }
    }

    /// The planar plant's integrated degree of freedom in the XP/VP slots that is not the target
    /// (the flange across its path, or the rotational stage), as (position, velocity, mass or
    /// inertia) slots for the at-rest check; `None` in 1-D.
    pub fn planar_dof(&self) -> Option<(usize, usize, f64)> {
        let p = self.planar.as_ref()?;
        if let Some(st) = &p.scene.rotational {
            return Some((XP, VP, st.inertia));
        }
        let r = self.robot.as_ref()?;
        p.across_states.then_some((XP, VP, r.mass))
    }

    /// True when the tool cannot yield any further away from the target: it is fastened (rigid),
    /// on its back stop, or (planar) its guide does not lead away from the target
    /// (`planar::Planar::retreat_share` <= 0: a 1-D module hit across its axis is a rigid tool; the
    /// rotational module turns its guide instead, so only its back stop counts).
    pub fn exhausted(&self, k: &Kinematics) -> bool {
        let bottomed = self.decoupler.back_stop().is_some_and(|b| b.penetration(k.s) > 0.0);
        bottomed || self.decoupler.is_rigid() || self.planar.as_ref().is_some_and(|p| p.scene.rotational.is_none() && p.retreat_share(k) <= 0.0)
    }

    /// The stroke left along the contact's normal, m: the travel to the back stop times the share of
    /// it that moves the tool away from the target (1 in 1-D, `planar::Planar::retreat_share`);
    /// 0 for a rigid tool or a guide that does not lead away; `None` without a back stop.
    pub fn stroke_left(&self, k: &Kinematics) -> Option<f64> {
        if self.decoupler.is_rigid() {
            return Some(0.0);
        }
        let left = self.decoupler.back_stop().map(|b| -b.penetration(k.s))?;
        Some(match &self.planar {
            None => left,
            // The rotational module yields by turning as well: its stroke is the guide's.
            Some(p) if p.scene.rotational.is_some() => left,
            Some(p) => {
                let share = p.retreat_share(k);
                if share <= 0.0 { 0.0f64.min(left) } else { left * share }
            }
        })
    }

    /// The force along the guide that moves the tool 0.1 mm off its front stop (or rest), N: the
    /// decoupler's force there at rest (friction at zero speed is zero in the regularised law, so
    /// this is the lower bound: a "blocked" judged against it is judged early, on the safe side).
    pub fn release_force(&self) -> f64 {
        let s = self.decoupler.front_stop().map_or(self.s_rest, |f| f.at) - 1e-4;
        self.decoupler.force(s, 0.0, self.front_chi, self.back_chi).total.abs()
    }

    /// Travel of the tool back from its front stop (or rest position), m.
    pub fn travel(&self, k: &Kinematics) -> f64 {
        self.decoupler.front_stop().map_or(self.s_rest, |f| f.at) - k.s
    }
}
