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
    /// What the scene simulates and what its name claims (`flinch_model::headline`).
    pub(crate) headline: flinch_model::headline::Headline,
    /// The commanded motion and the gap, for `Summary::as_commanded`.
    pub(crate) commanded: (flinch_model::scene::Motion, f64),
    /// The decoupler travel beyond which the flange has passed through the tool, m, and why.
    pub(crate) pass_through: Option<(f64, &'static str)>,
    /// m_t, kg, for the peak-force sanity bound.
    pub(crate) tool_mass: f64,
}

/// The sanity bound on a peak force, in g of the tool (m_t g): a force that would accelerate the
/// tool faster is not a physical number for a robot tool (a stop that halts 1 m/s within 0.05 mm).
/// The shipped scenes peak at 187 g (table2_bistable's front stop, 235 N s/m at 1 m/s; the others
/// at most 104 g), so 1,000 g is over 5 times the largest case the thesis's parameters give.
pub const PEAK_FORCE_SANITY_G: f64 = 1000.0;

/// Standard gravity, m/s^2.
const G0: f64 = 9.80665;

/// The warning for a peak force beyond [`PEAK_FORCE_SANITY_G`], naming where it came from and the
/// key to check. Not a failure: the verdict judges the stroke and the body limits; the warning says
/// the force figure is not physical.
pub fn implausible_force(what: &str, force_n: f64, event: &str, tool_mass_kg: f64) -> Option<String> {
    let g = force_n / (tool_mass_kg * G0);
    if !(g > PEAK_FORCE_SANITY_G) {
        return None;
    }
    let (source, key) = match event {
        "front_stop" => ("the front end-stop", "decoupler.front_stop (a linear-law stop jumps to c v on landing: its damping times the landing speed)"),
        "back_stop" => ("the back end-stop", "decoupler.back_stop"),
        "first_impact" | "later_contact" | "contact" => ("the tool-target contact", "target.stiffness and its damping"),
        _ => ("the decoupler", "the decoupler's keys"),
    };
    Some(format!(
        "{what} {force_n:.0} N (from {source}) would accelerate the {tool_mass_kg} kg tool at {g:.0} g, beyond the sanity bound of {PEAK_FORCE_SANITY_G:.0} g (5x the largest shipped case): the figure is not physical; check {key}"
    ))
}

/// The travel, m, beyond which the flange has passed through the tool (issue 26 item 6): a linear
/// module has no stop, so beyond 0.2 m (the largest stroke the validator accepts for any module);
/// a module with end-stops when the tool went into its back end-stop deeper than the module's
/// whole stroke C (travel beyond 2 C: the stop did not stop it). What follows is not modelled.
fn pass_through(d: &flinch_model::scene::Decoupler) -> Option<(f64, &'static str)> {
    use flinch_model::scene::Decoupler;
    match d {
        Decoupler::Rigid => None,
        Decoupler::Linear(_) => Some((0.2, "a linear module's travel beyond 0.2 m, the largest stroke the validator accepts for any module: the spring held nothing (decoupler.stiffness)")),
        Decoupler::Bistable(b) => Some((2.0 * (b.front_stroke + b.back_stroke), "the tool went into the back end-stop deeper than the module's whole stroke C1 + C2: the stop did not stop it (decoupler.back_stop.stiffness)")),
        Decoupler::Hydraulic(h) => Some((2.0 * h.stroke, "the piston went into the back end-stop deeper than the stroke L: the stop did not stop it (decoupler.back_stop.stiffness)")),
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
        let headline = flinch_model::headline::headline(scene);
        Self { sim, stepper, driver, method: s.method, duration: scene.duration_s, headline, commanded: (scene.motion, scene.target.gap), pass_through: pass_through(&scene.decoupler), tool_mass: scene.tool.mass }
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
            simulated: self.headline.simulated.clone(),
            name_mismatches: self.headline.mismatches.iter().cloned().chain(flinch_model::headline::mode_mismatch(&s.name, mode)).collect(),
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
            approach_speed_mps: s.v_in_first,
            as_commanded: true,
            not_as_commanded: self.not_as_commanded(s.t_contact, s.v_in_first),
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
        summary.as_commanded = summary.not_as_commanded.is_empty();
        let sane = [("peak force on the robot", summary.peak_robot_force, summary.peak_robot_force_event.as_str()), ("peak contact force", summary.peak_contact_force, "contact")];
        let insane: Vec<String> = sane.iter().filter_map(|(w, f, e)| implausible_force(w, *f, e, self.tool_mass)).collect();
        summary.warnings.extend(insane);
        summary.failures = crate::verdict::failures(&summary);
        // docs/verdicts.md: a flange that passed through the tool fails the run, whatever else.
        if let Some((limit, why)) = self.pass_through.filter(|(l, _)| summary.max_travel > *l) {
            summary.failures.push(format!("the flange passed through the tool: decoupler travel {:.1} mm beyond {:.1} mm, {why}; what follows is not modelled", summary.max_travel * 1e3, limit * 1e3));
        }
        summary.safe = summary.failures.is_empty();
        summary
    }
}

impl Run {
    /// What the run did not simulate as the scene commands it: the flange still accelerating
    /// when the tool met the target (exact from the motion law: the commanded speed at
    /// t_contact below `motion.speed`, before any braking).
    fn not_as_commanded(&self, t_contact: Option<f64>, approach: Option<f64>) -> Vec<String> {
        let (m, gap) = self.commanded;
        let Some(tc) = t_contact else { return Vec::new() };
        let braking = self.sim.plant.motion.t_brake().is_some_and(|tb| tb <= tc);
        let v = self.sim.plant.motion.at(tc).v;
        if m.start_at_speed || braking || v >= m.speed * (1.0 - 1e-9) {
            return Vec::new();
        }
        vec![format!(
            "the flange had reached only {:.3} m/s of motion.speed = {} m/s when the tool met the target (gap {:.1} mm < V_c^2/2a_c = {:.1} mm): the impact is at {}, not V_c; raise target.gap or set motion.start_at_speed",
            v,
            m.speed,
            gap * 1e3,
            m.speed * m.speed / (2.0 * m.accel) * 1e3,
            approach.map_or("the speed the flange had".to_string(), |a| format!("{a:.3} m/s")),
        )]
    }

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
