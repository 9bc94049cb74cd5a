//! Stability at the extremes of what the scene validator accepts (issue 5): property tests over
//! the parameter box and one test per known pitfall of the contact and decoupler laws.
//!
//! Every generated scene goes through `scene::parse`, so only parameters a user can really give are
//! tried. For each run: no panic, no NaN or infinity in the summary, a result (a `SolveError` on an
//! accepted scene is a failure: the validator must refuse what cannot run); energy is never created (the plant is
//! passive: what it holds at the end is at most what it held at the start plus the work the
//! commanded motion did on it through the robot or the decoupler, integrated as an extra state with
//! the same solver); and the results are continuous in the parameters away from mode boundaries.
//!
//! Pitfalls already covered by unit tests and not repeated here: chi finite as v_in -> 0
//! (`plant::contact`), d^1.5 of a negative penetration (`plant::contact`), the orifice's sign
//! (`plant::decoupler::hydraulic`), two events in one step and an event on a breakpoint
//! (`solver::driver`, on a bouncing ball). Here each is exercised end to end through a scene.

use flinch_harness::plant::decoupler::Decoupler as PlantDecoupler;
use flinch_harness::plant::motion_law::Commanded;
use flinch_harness::plant::{Kinematics, Plant, State, N};
use flinch_harness::scene::{self, Scene};
use flinch_harness::sim::{self, Run, Simulation, Summary};
use flinch_harness::solver::dopri5::Dopri5;
use flinch_harness::solver::driver::{Crossing, Driver, Hybrid, Settings};
use flinch_harness::solver::System;
use proptest::prelude::*;

// ---------------------------------------------------------------------------------------------
// Scenes from parameters

#[derive(Debug, Clone)]
enum Dec {
    Rigid,
    Linear { k: f64, zeta: f64 },
    Bistable { h: f64, mu: Option<f64>, v0: f64 },
    Hydraulic { gas_volume_factor: f64 },
}

#[derive(Debug, Clone)]
struct Params {
    speed: f64,
    dead_time: f64,
    tool_mass: f64,
    object_mass: Option<f64>,
    robot: bool,
    k_c: f64,
    restitution: f64,
    law: &'static str,
    dec: Dec,
    gravity: f64,
}

impl Params {
    fn toml(&self) -> String {
        let v = self.speed;
        // Reach V_c within 5 ms, contact 10 ms later, then the dead time, the braking and 50 ms.
        let accel = (v / 0.005).max(0.1);
        let gap = v * 0.010 + 0.5 * v * 0.005;
        let decel = accel;
        let duration = 0.005 + 0.010 + self.dead_time + v / decel + 0.05;
        let robot = if self.robot { "[robot]\nmass = 8.4\nstiffness = 2.3e5\ndamping = 71.0\n" } else { "" };
        let (decoupler, sensor) = match &self.dec {
            Dec::Rigid => ("kind = \"rigid\"\n".to_string(), "kind = \"force\"\nthreshold = 1.0\n".to_string()),
            Dec::Linear { k, zeta } => (format!("kind = \"linear\"\nstiffness = {k:e}\ndamping_ratio = {zeta}\n"), "kind = \"travel\"\nthreshold = 0.0005\n".into()),
            Dec::Bistable { h, mu, v0 } => {
                let friction = mu.map_or(String::new(), |mu| format!("friction = {{ mu = {mu}, v0 = {v0:e} }}\n"));
                (
                    format!("kind = \"bistable\"\nsprings = 2\nspring_rate = 200.0\nfree_length = 0.05\nheight = {h:e}\nfront_stroke = 0.015\nback_stroke = 0.015\nfront_stop = {{ stiffness = 1e6, damping = 278.0 }}\nback_stop = {{ stiffness = 1e6, restitution = 0.6 }}\n{friction}"),
                    "kind = \"travel\"\nthreshold = 0.005\n".into(),
                )
            }
            Dec::Hydraulic { gas_volume_factor } => {
                // Swept volume pi R^2 L = 2.89e-5 m^3; the factor > 1 drives the gas towards its limit.
                let swept = std::f64::consts::PI * 0.02 * 0.02 * 0.023;
                (
                    format!("kind = \"hydraulic\"\nstroke = 0.023\npiston_radius = 0.020\norifice_radius = 0.008\ngas_pressure = 1000.0\ngas_volume = {:e}\ndischarge_coefficient = 3.0\nliquid_density = 900.0\ndry_friction = 0.2\nviscous_friction = 0.5\nfront_stop = {{ stiffness = 1e6, damping = 235.0 }}\nback_stop = {{ stiffness = 1e6, restitution = 0.3 }}\n", swept * gas_volume_factor),
                    "kind = \"travel\"\nthreshold = 0.0015\n".into(),
                )
            }
        };
        let target = match self.object_mass {
            Some(m) => format!("kind = \"object\"\nmass = {m:e}\n"),
            None => "kind = \"obstacle\"\n".into(),
        };
        format!(
            "name = \"extreme\"\nduration = {duration}\n[motion]\nspeed = {v:e}\naccel = {accel:e}\ndecel = {decel:e}\ndead_time = {dt}\ngravity = {g}\n{robot}[tool]\nmass = {mt:e}\n[decoupler]\n{decoupler}[target]\n{target}gap = {gap:e}\nstiffness = {kc:e}\nrestitution = {e}\ndamping_law = \"{law}\"\n[sensor]\n{sensor}",
            dt = self.dead_time,
            g = self.gravity,
            mt = self.tool_mass,
            kc = self.k_c,
            e = self.restitution,
            law = self.law,
        )
    }

    fn scene(&self) -> Scene {
        let text = self.toml();
        scene::parse(&text, "extreme.toml").unwrap_or_else(|e| panic!("the generator made a scene the validator refuses:\n{e}\n{text}"))
    }
}

fn log_uniform(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (0.0..=1.0f64).prop_map(move |u| lo * (hi / lo).powf(u))
}

fn restitution() -> impl Strategy<Value = f64> {
    prop_oneof![Just(0.0), Just(1.0), 0.0..=1.0f64]
}

fn law() -> impl Strategy<Value = &'static str> {
    prop_oneof![Just("hunt-crossley"), Just("lankarani-nikravesh"), Just("flores"), Just("gonthier"), Just("exact")]
}

fn decoupler() -> impl Strategy<Value = Dec> {
    prop_oneof![
        Just(Dec::Rigid),
        (log_uniform(1.0, 1e5), 0.0..=2.0f64).prop_map(|(k, zeta)| Dec::Linear { k, zeta }),
        // H towards 0; friction with v0 towards 0 (0 itself is the Coulomb limit, regularised).
        (log_uniform(1e-6, 0.04), prop::option::of(0.0..=0.3f64), prop_oneof![Just(0.0), log_uniform(1e-9, 1e-2)]).prop_map(|(h, mu, v0)| Dec::Bistable { h, mu, v0 }),
        // Gas volume from 1.0001 x the swept volume (driven to its limit) to 3 x.
        log_uniform(1.0001, 3.0).prop_map(|f| Dec::Hydraulic { gas_volume_factor: f }),
    ]
}

fn params() -> impl Strategy<Value = Params> {
    (
        log_uniform(1e-4, 2.0),
        0.0..=0.2f64,
        log_uniform(1e-3, 50.0),
        prop::option::of(log_uniform(1e-3, 1e2)),
        any::<bool>(),
        log_uniform(1e3, 1e9),
        restitution(),
        law(),
        decoupler(),
        prop_oneof![Just(0.0), Just(9.81)],
    )
        .prop_map(|(speed, dead_time, tool_mass, object_mass, robot, k_c, restitution, law, dec, gravity)| {
            // Flores and Gonthier divide by e: the validator refuses e = 0 with them (tested in
            // scene_errors); e = 0 is tried with the other laws.
            let law = if restitution == 0.0 && matches!(law, "flores" | "gonthier") { "exact" } else { law };
            Params { speed, dead_time, tool_mass, object_mass, robot, k_c, restitution, law, dec, gravity }
        })
}

fn finite(x: Option<f64>) -> bool {
    x.is_none_or(f64::is_finite)
}

/// No NaN or infinity anywhere in the summary.
fn check_finite(s: &Summary) -> Result<(), String> {
    let all = [s.peak_contact_force, s.peak_robot_force, s.max_travel, s.decoupler_impulse];
    let opts = [s.t_contact, s.t_detect, s.t_brake, s.object_final_velocity, s.achieved_restitution, s.approach_speed_mps, s.object_peak_velocity, s.peak_gas_pressure, s.t_stop];
    if all.iter().all(|x| x.is_finite()) && opts.iter().all(|&x| finite(x)) && s.peak_contact_force >= 0.0 {
        Ok(())
    } else {
        Err(format!("non-finite or negative figure in {s:?}"))
    }
}

/// Every summary field within its physical range (issue 18 item 4): event times in the run's
/// frame (>= 0), delays after the contact >= 0, a restitution in [0, 1], forces, travel and
/// impulse finite and non-negative; a field that cannot be defined is null with its reason.
fn check_physical(s: &Summary) -> Result<(), String> {
    let bad = |what: &str| Err(format!("{what} in {s:?}"));
    for (name, t) in [("t_contact", s.t_contact), ("t_detect", s.t_detect), ("t_brake", s.t_brake), ("t_stop", s.t_stop)] {
        if t.is_some_and(|t| t.is_nan() || t < 0.0) {
            return bad(&format!("{name} < 0"));
        }
    }
    for (name, d, why) in [
        ("detection_delay", s.detection_delay, &s.detection_delay_null_reason),
        ("reaction_time", s.reaction_time, &s.reaction_time_null_reason),
        ("achieved_restitution", s.achieved_restitution, &s.achieved_restitution_null_reason),
    ] {
        match (d, why) {
            (Some(x), _) if x.is_nan() || x < 0.0 => return bad(&format!("{name} = {x} < 0")),
            (Some(_), Some(_)) => return bad(&format!("{name} has a value and a null reason")),
            (None, None) if s.t_contact.is_some() => return bad(&format!("{name} null without a reason")),
            _ => {}
        }
    }
    if s.achieved_restitution.is_some_and(|e| e > 1.0) {
        return bad("achieved_restitution > 1");
    }
    if !(s.peak_robot_force >= 0.0 && s.max_travel.is_finite() && s.decoupler_impulse.is_finite()) {
        return bad("a negative or non-finite force");
    }
    Ok(())
}

/// A run of an accepted scene succeeds with finite figures within their physical ranges. A solver
/// error (a step-size collapse, the step limit) on a scene the validator accepted is a failure
/// (issue 18): the validator should have refused it, saying why. `Ok(None)` is never returned now;
/// the type is kept for the callers.
fn run_checked(sc: &Scene) -> Result<Option<Summary>, String> {
    match sim::run(sc, false) {
        Ok((s, _)) => check_finite(&s).and_then(|_| check_physical(&s)).map(|_| Some(s)),
        Err(e) => Err(format!("an accepted scene failed in the solver: {e}")),
    }
}

// ---------------------------------------------------------------------------------------------
// Energy: the plant plus the work of the commanded motion and its absolute value as extra states.

const NE: usize = N + 2;

struct Energy {
    sim: Simulation,
}

fn split(y: &[f64; NE]) -> State {
    let mut s = [0.0; N];
    s.copy_from_slice(&y[..N]);
    s
}

/// Power the commanded motion puts into the plant, W: through the robot's joint spring-damper
/// (compliant robot, the base moves at x_c'), or straight into the decoupler or the contact (rigid
/// robot: the flange is driven, whatever force it takes).
fn input_power(p: &Plant, k: &Kinematics, robot_force: f64) -> f64 {
    match &p.robot {
        Some(r) => r.drive_force(&Commanded { x: k.xc, v: k.vc, a: k.ac }, k.xr, k.vr) * k.vc,
        None => -robot_force * k.vc,
    }
}

impl System<NE> for Energy {
    fn rhs(&self, t: f64, y: &[f64; NE], dy: &mut [f64; NE]) {
        let mut d = [0.0; N];
        let (k, f) = self.sim.plant.eval(t, &split(y), &mut d);
        dy[..N].copy_from_slice(&d);
        let p = input_power(&self.sim.plant, &k, f.robot);
        dy[N] = p;
        dy[N + 1] = p.abs();
    }
}

impl Hybrid<NE, { sim::E }> for Energy {
    fn events(&self, t: f64, y: &[f64; NE]) -> [f64; sim::E] {
        self.sim.events(t, &split(y))
    }
    fn watching(&self, i: usize) -> Option<Crossing> {
        self.sim.watching(i)
    }
    fn on_event(&mut self, i: usize, t: f64, y: &mut [f64; NE]) {
        let mut s = split(y);
        self.sim.on_event(i, t, &mut s);
        y[..N].copy_from_slice(&s);
    }
    fn next_breakpoint(&self, t: f64) -> Option<f64> {
        self.sim.next_breakpoint(t)
    }
    fn on_step(&mut self, t0: f64, t1: f64, y1: &[f64; NE], dense: &dyn Fn(f64) -> [f64; NE]) {
        self.sim.on_step(t0, t1, &split(y1), &|t| split(&dense(t)));
    }
}

/// -integral of `force` from `a` to `b` (Gauss-Legendre, 8 points on 16 panels): the potential of a
/// conservative force known only as a function.
fn potential(force: impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    const X: [f64; 4] = [0.183_434_642_495_649_8, 0.525_532_409_916_329, 0.796_666_477_413_626_7, 0.960_289_856_497_536_3];
    const W: [f64; 4] = [0.362_683_783_378_362, 0.313_706_645_877_887_3, 0.222_381_034_453_374_5, 0.101_228_536_290_376_3];
    let panels = 16;
    let h = (b - a) / panels as f64;
    let mut sum = 0.0;
    for p in 0..panels {
        let c = a + (p as f64 + 0.5) * h;
        for k in 0..4 {
            sum += W[k] * (force(c - 0.5 * h * X[k]) + force(c + 0.5 * h * X[k]));
        }
    }
    -sum * 0.5 * h
}

/// Mechanical energy held by the plant at (t, y), J, relative to the stroke `s_ref` for the
/// decoupler's springs. Potentials: robot joint spring, decoupler spring or gas, end-stops and
/// contact (2/5 k d^2.5), gravity on whatever carries the tool's weight.
fn energy(p: &Plant, t: f64, y: &State, s_ref: f64) -> f64 {
    let k = p.kinematics(t, y);
    let mut e = 0.0;
    let rigid_dec = p.decoupler.is_rigid();
    if let Some(r) = &p.robot {
        e += 0.5 * r.mass * k.vr * k.vr + 0.5 * r.stiffness * (k.xc - k.xr).powi(2);
        if rigid_dec {
            e -= p.tool_mass * p.gravity * k.xr;
        }
    }
    if !rigid_dec {
        e += 0.5 * p.tool_mass * k.vt * k.vt - p.tool_mass * p.gravity * k.xt;
    }
    if let flinch_harness::plant::target::Target::Object { mass, .. } = p.target {
        e += 0.5 * mass * k.vp * k.vp;
    }
    let hertz = |stiffness: f64, d: f64| if d > 0.0 { 0.4 * stiffness * d.powf(2.5) } else { 0.0 };
    e += hertz(p.contact.stiffness, k.delta);
    match &p.decoupler {
        PlantDecoupler::Rigid => {}
        PlantDecoupler::Linear(l) => e += 0.5 * l.stiffness * k.s * k.s,
        PlantDecoupler::Bistable(b) => e += potential(|s| b.spring_force(s), s_ref, k.s),
        PlantDecoupler::Hydraulic(h) => e += potential(|s| h.gas_pressure(s) * h.area(), s_ref, k.s),
    }
    if let Some(f) = p.decoupler.front_stop() {
        let d = k.s - f.at;
        if d > 0.0 {
            e += 0.5 * f.stiffness * d * d;
        }
    }
    if let Some(b) = p.decoupler.back_stop() {
        e += hertz(b.contact.stiffness, b.penetration(k.s));
    }
    e
}

/// (energy at the end - energy at the start - work of the motion law, scale of the energies
/// involved), or `None` if the run failed with a clear error.
fn energy_balance(sc: &Scene) -> Option<(f64, f64)> {
    let run = Run::new(sc, false, false);
    let y0 = run.sim.plant.initial_state(sc.motion.start_at_speed, sc.motion.speed);
    let mut sys = Energy { sim: run.sim };
    let mut y = [0.0; NE];
    y[..N].copy_from_slice(&y0);
    let s_ref = sys.sim.plant.kinematics(0.0, &y0).s;
    let e0 = energy(&sys.sim.plant, 0.0, &y0, s_ref);
    let mut d = Driver::<NE, { sim::E }>::new(&sys, 0.0, y, Settings { max_step: sc.solver.max_step, ..Default::default() });
    let mut stepper = Dopri5::<NE>::new(1e-9, 1e-12);
    d.advance_to(&mut sys, &mut stepper, sc.duration_s).ok()?;
    let e1 = energy(&sys.sim.plant, d.t, &split(&d.y), s_ref);
    let w = d.y[N];
    let scale = e0.abs() + e1.abs() + d.y[N + 1] + 1e-12;
    Some((e1 - e0 - w, scale))
}

// ---------------------------------------------------------------------------------------------
// Properties

proptest! {
    // A fixed seed: CI must judge the same 48 cases every run (a random seed made this suite pass on
    // one run and fail on the next). Change the seed here to explore other cases.
    #![proptest_config(ProptestConfig {
        cases: 48,
        max_shrink_iters: 64,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x466c_696e_6368),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// Anything the validator accepts runs to the end with finite figures, or stops with an error
    /// that names the instant and the remedy.
    #[test]
    fn every_accepted_scene_gives_a_result_or_a_clear_error(p in params()) {
        let sc = p.scene();
        if let Err(e) = run_checked(&sc) {
            prop_assert!(false, "{e}\n{}", p.toml());
        }
    }

    /// The plant is passive: it never ends with more energy than the motion law put in.
    #[test]
    fn energy_is_never_created(p in params()) {
        let sc = p.scene();
        if let Some((excess, scale)) = energy_balance(&sc) {
            prop_assert!(excess <= 1e-5 * scale, "created {excess:e} J (scale {scale:e} J)\n{}", p.toml());
        }
    }

    /// A relative change of 1e-6 in the contact stiffness, the speed or the tool mass changes the
    /// peak forces and the detection instant by at most 1e-3 relative, unless the run crossed a
    /// boundary (a different working mode or number of contacts).
    #[test]
    fn results_are_continuous_in_the_parameters(p in params(), which in 0..3usize) {
        let mut q = p.clone();
        match which {
            0 => q.k_c *= 1.0 + 1e-6,
            1 => q.speed *= 1.0 + 1e-6,
            _ => q.tool_mass *= 1.0 + 1e-6,
        }
        let (Ok(Some(a)), Ok(Some(b))) = (run_checked(&p.scene()), run_checked(&q.scene())) else { return Ok(()) };
        if a.mode != b.mode || a.contacts != b.contacts || a.t_detect.is_some() != b.t_detect.is_some() {
            return Ok(());
        }
        let close = |x: f64, y: f64| (x - y).abs() <= 1e-3 * x.abs().max(y.abs()) + 1e-9;
        prop_assert!(close(a.peak_contact_force, b.peak_contact_force), "peak contact {} vs {}\n{}", a.peak_contact_force, b.peak_contact_force, p.toml());
        prop_assert!(close(a.peak_robot_force, b.peak_robot_force), "peak robot {} vs {}\n{}", a.peak_robot_force, b.peak_robot_force, p.toml());
        // The delay can be negative: a heavy tool lagging while the robot accelerates trips the
        // travel switch before any contact (inertial false trip, physical).
        if let (Some(x), Some(y), Some(dd)) = (a.t_detect, b.t_detect, a.detection_delay) {
            prop_assert!((x - y).abs() <= 1e-3 * dd.abs() + 1e-9, "detection {x} vs {y}\n{}", p.toml());
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Pitfalls, end to end

fn base() -> Params {
    Params { speed: 0.05, dead_time: 0.016, tool_mass: 0.75, object_mass: None, robot: true, k_c: 1e8, restitution: 0.65, law: "hunt-crossley", dec: Dec::Bistable { h: 0.03, mu: None, v0: 0.0 }, gravity: 0.0 }
}

#[test]
fn grazing_contact_keeps_chi_finite_and_the_run_finite() {
    // Approach at 0.1 mm/s: chi = alpha k / v_in would be 1e4 times the 1 m/s value.
    for dec in [Dec::Rigid, Dec::Bistable { h: 0.03, mu: None, v0: 0.0 }] {
        let p = Params { speed: 1e-4, dec, ..base() };
        let s = run_checked(&p.scene()).unwrap().expect("a grazing contact is no reason to fail");
        assert!(s.contacts >= 1 && s.peak_contact_force > 0.0, "{s:?}");
        let v = s.approach_speed_mps.unwrap();
        assert!(v > 0.0 && v < 2e-4, "approach {v}");
    }
}

#[test]
fn restitution_zero_and_one_at_every_law_run_and_keep_energy() {
    for law in ["hunt-crossley", "lankarani-nikravesh", "flores", "gonthier", "exact"] {
        for e in [0.0, 1.0] {
            if e == 0.0 && matches!(law, "flores" | "gonthier") {
                continue; // refused by the validator: the law divides by e
            }
            let p = Params { restitution: e, law, dec: Dec::Rigid, object_mass: Some(0.25), robot: false, speed: 1.0, ..base() };
            let sc = p.scene();
            let s = run_checked(&sc).unwrap().unwrap();
            let (excess, scale) = energy_balance(&sc).unwrap();
            assert!(excess <= 1e-6 * scale, "{law} e = {e}: created {excess} J of {scale}");
            if e == 1.0 {
                // chi = 0: elastic, the rigid tool driven at 1 m/s sends a light object off at about 2 m/s.
                assert!((s.object_final_velocity.unwrap() - 2.0).abs() < 0.02, "{law}: {s:?}");
            }
        }
    }
}

#[test]
fn contact_and_detection_inside_one_fixed_step_are_both_located() {
    // RK4 with a 1 ms step: the rigid tool's contact and its 1 N force threshold (40 um of
    // penetration at k_c = 1e8, 0.8 ms at 0.05 m/s) fall inside one step.
    let p = Params { dec: Dec::Rigid, robot: false, ..base() };
    let mut sc = p.scene();
    let (reference, _) = sim::run(&sc, false).unwrap();
    sc.solver.method = scene::Method::Rk4;
    sc.solver.max_step = 1e-3;
    let (s, _) = sim::run(&sc, false).unwrap();
    let (c, d) = (s.t_contact.unwrap(), s.t_detect.unwrap());
    assert!(d > c, "detection {d} must follow contact {c}");
    assert!((c - reference.t_contact.unwrap()).abs() < 1e-9, "contact {c} vs {:?}", reference.t_contact);
    assert!((s.detection_delay.unwrap() - reference.detection_delay.unwrap()).abs() < 0.05 * reference.detection_delay.unwrap(), "{s:?}\n{reference:?}");
}

#[test]
fn contact_exactly_on_a_step_boundary_is_found_once() {
    // Start at 1 m/s with a 10 mm gap: contact at t = 10 ms exactly, the end of the tenth 1 ms RK4
    // step, with the tool's own free flight (no decoupler force) making the gap close exactly.
    let text = "name = \"boundary\"\nduration = 0.03\n[motion]\nspeed = 1.0\naccel = 1.0\ndecel = 1.0\ndead_time = 0.0\ngravity = 0.0\nstart_at_speed = true\n[tool]\nmass = 0.1\n[decoupler]\nkind = \"rigid\"\n[target]\nkind = \"object\"\nmass = 0.1\ngap = 0.01\nstiffness = 1e7\nrestitution = 1.0\ndamping_law = \"hunt-crossley\"\n[solver]\nmethod = \"rk4\"\nmax_step = 1e-3\n";
    let sc = scene::parse(text, "boundary.toml").unwrap();
    let (s, _) = sim::run(&sc, false).unwrap();
    assert_eq!(s.contacts, 1, "{s:?}");
    assert!((s.t_contact.unwrap() - 0.01).abs() < 1e-12, "{:?}", s.t_contact);
}

#[test]
fn gas_driven_to_its_limit_stays_finite_and_passive() {
    // Gas volume 1.0001 x the swept volume, a heavy tool at full speed: the piston bottoms out.
    let p = Params { speed: 2.0, tool_mass: 50.0, dec: Dec::Hydraulic { gas_volume_factor: 1.0001 }, dead_time: 0.2, ..base() };
    let sc = p.scene();
    let s = run_checked(&sc).unwrap();
    if let Some(s) = &s {
        assert!(s.peak_gas_pressure.unwrap().is_finite());
    }
    if let Some((excess, scale)) = energy_balance(&sc) {
        assert!(excess <= 1e-5 * scale, "created {excess} J of {scale}");
    }
}

#[test]
fn stroke_exhausted_and_chattering_on_the_end_stops() {
    // Mode 3 at 2 m/s with the longest dead time: the tool hits the back stop while the robot still
    // drives, then chatters between the stops while the object goes; must finish, stay passive.
    let p = Params { speed: 2.0, dead_time: 0.2, tool_mass: 0.75, object_mass: None, ..base() };
    let sc = p.scene();
    let s = run_checked(&sc).unwrap().expect("runs to the end");
    assert!(s.stroke_exhausted, "{s:?}");
    assert_eq!(s.mode, Some(3));
    let (excess, scale) = energy_balance(&sc).unwrap();
    assert!(excess <= 1e-5 * scale, "created {excess} J of {scale}");
}

#[test]
fn coulomb_limit_and_vanishing_height_are_regularised_and_reported() {
    // v0 = 0 is integrated as stick-slip by default (issue 12); with law = "regularised" the
    // regularisation is applied and reported. Both run at H -> 0 and neither creates energy.
    let p = Params { dec: Dec::Bistable { h: 1e-6, mu: Some(0.3), v0: 0.0 }, ..base() };
    let mut sc = p.scene();
    let s = run_checked(&sc).unwrap().expect("runs");
    assert!(!s.warnings.iter().any(|w| w.contains("v0")), "{:?}", s.warnings);
    let (excess, scale) = energy_balance(&sc).unwrap();
    assert!(excess <= 1e-5 * scale, "stick-slip created {excess} J of {scale}");
    if let scene::Decoupler::Bistable(b) = &mut sc.decoupler {
        b.friction.as_mut().expect("friction").law = scene::FrictionLaw::Regularised;
    }
    let s = run_checked(&sc).unwrap().expect("runs");
    assert!(s.warnings.iter().any(|w| w.contains("v0")), "{:?}", s.warnings);
}

#[test]
fn output_interval_zero_records_every_step_and_ends() {
    // It used to hang: the recorder added output_interval = 0 to its next instant forever.
    let mut sc = base().scene();
    sc.solver.output_interval = 0.0;
    let (s, history) = sim::run(&sc, true).unwrap();
    assert!(history.len() as u64 >= s.steps, "{} samples for {} steps", history.len(), s.steps);
}

/// Issue 18: a summary field that cannot be defined is null with the reason, never a number
/// outside its physical range. Table 2's linear module with a 0.1 mm gap: the first contact comes
/// while the spring still accelerates the tool (a driven contact), which left at 10.5 times its
/// approach speed; a 5e-324 m gap gave 2e21.
#[test]
fn driven_first_contact_has_no_restitution_but_a_reason() {
    let text = std::fs::read_to_string(flinch_tests::scene_path("table2_linear.toml")).unwrap();
    for gap in ["1e-4", "1e-6", "1e-3"] {
        let t = text.replacen("gap = 0.15 ", &format!("gap = {gap} "), 1);
        let sc = scene::parse(&t, "driven.toml").unwrap_or_else(|e| panic!("{e}"));
        let s = run_checked(&sc).unwrap().expect("runs");
        match s.achieved_restitution {
            Some(e) => assert!((0.0..=1.0).contains(&e), "gap {gap}: restitution {e}"),
            None => {
                let why = s.achieved_restitution_null_reason.as_deref().unwrap_or_else(|| panic!("gap {gap}: null without a reason"));
                assert!(why.contains("driven") || why.contains("not an impact") || why.contains("had not ended"), "{why}");
            }
        }
        if gap == "1e-4" {
            assert!(s.achieved_restitution.is_none(), "gap 1e-4 is the issue's driven contact: {s:?}");
        }
    }
    // The isolated impact still reports its restitution, with no reason.
    let s = run_checked(&scene::parse(&text, "t2.toml").unwrap()).unwrap().unwrap();
    assert!(s.achieved_restitution.is_some_and(|e| (0.0..=1.0).contains(&e)), "{s:?}");
    assert_eq!(s.achieved_restitution_null_reason, None);
}

#[test]
fn undefined_summary_fields_say_why() {
    // Restitution: the ratio outside [0, 1] is refused, the edges kept.
    assert_eq!(sim::achieved_restitution(Some(0.019), Some(-0.2)).0, None);
    assert!(sim::achieved_restitution(Some(0.019), Some(-0.2)).1.unwrap().contains("driven"));
    assert_eq!(sim::achieved_restitution(Some(1.0), Some(-1.0)), (Some(1.0), None));
    assert_eq!(sim::achieved_restitution(Some(1.0), Some(0.0)), (Some(0.0), None));
    assert_eq!(sim::achieved_restitution(Some(1.0), Some(-1.0000017)), (Some(1.0), None), "integration error at e = 1");
    assert_eq!(sim::achieved_restitution(Some(1.0), Some(-1.01)).0, None);
    assert_eq!(sim::achieved_restitution(Some(1.0), Some(0.5)).0, None, "a tool still moving in: not a rebound");
    assert!(sim::achieved_restitution(None, None).1.unwrap().contains("no tool-target contact"));
    assert!(sim::achieved_restitution(Some(1.0), None).1.unwrap().contains("had not ended"));
    // Detection delay: never negative.
    assert_eq!(sim::detection_delay(Some(0.25), Some(0.2)).0, None);
    assert!(sim::detection_delay(Some(0.25), Some(0.2)).1.unwrap().contains("before the first contact"));
    assert_eq!(sim::detection_delay(Some(0.25), Some(0.25)), (Some(0.0), None));
    assert!(sim::detection_delay(Some(0.25), None).1.unwrap().contains("nothing detected"));
}

/// Braking commanded after the end of the run is reported as such, not as if simulated.
#[test]
fn events_after_the_run_are_flagged() {
    let text = std::fs::read_to_string(flinch_tests::scene_path("tables5-7_bistable.toml")).unwrap();
    // Contact near 0.3 s, detection a few ms later, 16 ms dead time, 25 ms braking: end at 0.3 s.
    let s0 = run_checked(&scene::parse(&text, "a.toml").unwrap()).unwrap().unwrap();
    let end = s0.t_detect.unwrap() + 0.005;
    let t = text.replacen("duration = 0.6 ", &format!("duration = {end} "), 1);
    let s = run_checked(&scene::parse(&t, "short.toml").unwrap_or_else(|e| panic!("{e}"))).unwrap().unwrap();
    assert!(s.t_brake.unwrap() > end && s.t_stop.unwrap() > end, "{s:?}");
    for name in ["t_brake", "t_stop"] {
        assert!(s.warnings.iter().any(|w| w.starts_with(name) && w.contains("after the end of the run")), "{name}: {:?}", s.warnings);
    }
    assert!(!s0.warnings.iter().any(|w| w.contains("after the end of the run")), "{:?}", s0.warnings);
}

/// Issue 18: braking that started before the contact is not a reaction to it. A weak bi-stable
/// spring (1 N/m) lets the tool lag as the flange accelerates, the travel switch trips before the
/// contact, and a slow brake (0.001 m/s^2) still lets the tool reach the target: Table 4's module
/// braked at 0.085 s and touched at 0.404 s, a reaction time of -0.319 s before; now null with the
/// reason.
#[test]
fn braking_before_contact_has_no_reaction_time_but_a_reason() {
    let text = std::fs::read_to_string(flinch_tests::scene_path("table4_bistable_136g.toml")).unwrap();
    let t = text.replacen("spring_rate = 490.0 ", "spring_rate = 1.0 ", 1).replacen("decel = 5.0 ", "decel = 0.001 ", 1);
    let s = run_checked(&scene::parse(&t, "early.toml").unwrap_or_else(|e| panic!("{e}"))).unwrap().expect("runs");
    let (c, b) = (s.t_contact.expect("a contact"), s.t_brake.expect("braking"));
    assert!(b < c, "the case must brake before the contact: t_brake {b}, t_contact {c}");
    assert_eq!(s.reaction_time, None, "{s:?}");
    assert!(s.reaction_time_null_reason.as_deref().is_some_and(|r| r.contains("before the first contact")), "{s:?}");
    assert_eq!(sim::reaction_time(Some(0.25), Some(0.25)), (Some(0.0), None));
    assert!(sim::reaction_time(Some(0.25), None).1.unwrap().contains("never commanded to brake"));
    assert!(sim::reaction_time(None, Some(0.2)).1.unwrap().contains("no tool-target contact"));
}
