//! [`Run`]: a simulation driven step by step or to the end (`advance_to`, `command_brake`,
//! `remove_power`, `finish`), its summary, how many rows it records, and the one-call [`run`] and
//! [`run_to_conclusion`].

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

use flinch_plant::{self as plant, Forces, Kinematics, State, N};
use flinch_model::scene::{Method, Scene};
use flinch_solver::dopri5::Dopri5;
use flinch_solver::driver::{Driver, Hybrid, Settings, SolveError, Stats};
use flinch_solver::fixed::{Fixed, FixedKind};
use flinch_solver::AnyStepper;
use crate::simulation::Simulation;
use crate::summary::{achieved_restitution, detection_delay, reaction_time, Sample, Summary};
use crate::events::*;

/// A scene's run in progress: the simulation, its stepper and its driver.
pub struct Run {
    /// The simulation (plant and bookkeeping).
    pub sim: Simulation,
    pub(crate) stepper: AnyStepper<N>,
    pub(crate) driver: Driver<N, E>,
    pub(crate) method: Method,
    pub(crate) duration: f64,
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
            off_axis_deg: s.plant.planar.map(|p| p.scene.off_axis_deg),
            surface_angle_deg: s.plant.planar.map(|p| p.scene.surface_angle_deg),
            module_rotation_deg: None,
            module_rotation_deg_null_reason: None,
            t_engaged_s: None,
            max_rotation_deg: None,
            module_blocked_t_s: s.blocked.map(|b| b.0),
            module_blocked_force_n: s.blocked.map(|b| b.1),
        };
        if let Some(p) = s.plant.planar.filter(|p| p.scene.rotational.is_some()) {
            summary.max_rotation_deg = Some(s.max_rotation.to_degrees());
            match s.engaged {
                Some((t, phi)) => {
                    summary.t_engaged_s = Some(t);
                    summary.module_rotation_deg = Some(p.scene.surface_angle_deg - phi.to_degrees());
                }
                None => summary.module_rotation_deg_null_reason = Some(format!("the bi-stable mechanism never travelled {} mm back while the tool touched the target", crate::summary::ENGAGED_TRAVEL_M * 1e3)),
            }
        }
        if let Some(b) = &s.body {
            let c = flinch_model::body::check(b, s.peak_contact);
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
