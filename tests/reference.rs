//! The reference mode (`[solver] fidelity = "reference"`: our DOPRI5 at rtol 1e-10, atol 1e-13,
//! events located) cross-checked on every shipped scene against an independent integrator: DOP853
//! of the `differential-equations` crate (8th order, its own step control and dense output).
//!
//! How the hybrid system is carried: that crate's event support (`Event`) watches one function and
//! skips the first step of each solve, so it cannot carry our four switching events directly.
//! Instead the plant is integrated event to event: each segment is one DOP853 solve from the last
//! event (or motion-law breakpoint) to the next breakpoint, with a `Solout` of this file that
//! watches every armed event function of the plant on each DOP853 step and, when one crosses,
//! bisects the crossing on DOP853's own interpolant, stops the solve, and applies the plant's
//! reaction (contact damping fixed at onset, braking scheduled, ...) before the next segment. The
//! peaks are sampled on DOP853's interpolant (16 points a step, golden-section refinement around the best), and the
//! figures (peak contact force, peak robot force, detection time, object final velocity, working
//! mode) are computed here from those events, not by `sim::Summary`'s bookkeeping. Shared with the
//! simulator: only the plant's right-hand side, event functions and event reactions (the model).

use differential_equations::prelude::*;
use flinch_harness::plant::{State, N, VP};
use flinch_harness::scene::{self, Fidelity, Scene};
use flinch_harness::sim::{self, Run, Simulation, Summary};
use flinch_harness::solver::driver::{Crossing, Hybrid};
use flinch_harness::solver::System;
use flinch_tests::scene_path;
use std::cell::RefCell;

const EV_CONTACT: usize = 0;
const EV_BACK: usize = 2;
const EV_SWITCH: usize = 3;

/// The plant as the crate's ODE.
struct Plant<'a>(&'a RefCell<Simulation>);

impl ODE<f64, [f64; N]> for Plant<'_> {
    fn diff(&self, t: f64, y: &[f64; N], dydt: &mut [f64; N]) {
        self.0.borrow().rhs(t, y, dydt);
    }
}

/// What one segment found.
#[derive(Default)]
struct Segment {
    /// The event that ended it: (index, t, y).
    event: Option<(usize, f64, State)>,
    /// The last state the solver reached.
    last: Option<(f64, State)>,
    peak_contact: f64,
    peak_robot: f64,
}

fn crossed(sim: &Simulation, t: f64, y: &State) -> Option<usize> {
    let g = sim.events(t, y);
    (0..sim::E).find(|&i| match sim.watching(i) {
        Some(Crossing::Up) => g[i] > 0.0,
        Some(Crossing::Down) => g[i] <= 0.0,
        None => false,
    })
}

/// Watches the events and samples the peaks on each DOP853 step.
struct Watch<'a> {
    sim: &'a RefCell<Simulation>,
    seg: &'a RefCell<Segment>,
}

impl Solout<f64, [f64; N]> for Watch<'_> {
    fn solout<I>(&mut self, t_curr: f64, t_prev: f64, y_curr: &[f64; N], _y_prev: &[f64; N], interp: &mut I, _sol: &mut Solution<f64, [f64; N]>) -> ControlFlag<f64, [f64; N]>
    where
        I: Interpolation<f64, [f64; N]> + ?Sized,
    {
        let sim = self.sim.borrow();
        let mut seg = self.seg.borrow_mut();
        let mut at = |t: f64| if t >= t_curr { *y_curr } else { interp.interpolate(t).expect("inside the step") };
        let mut t_end = t_curr;
        if crossed(&sim, t_curr, y_curr).is_some() {
            // Bisect for the earliest instant any armed event is on its new side.
            let (mut a, mut b) = (t_prev, t_curr);
            while b - a > 1e-13 {
                let m = 0.5 * (a + b);
                if crossed(&sim, m, &at(m)).is_some() { b = m } else { a = m }
            }
            let yb = at(b);
            let i = crossed(&sim, b, &yb).expect("the bracket's end has crossed");
            seg.event = Some((i, b, yb));
            t_end = b;
        }
        // Peaks: 16 samples of the interpolant, golden-section refinement around the best.
        let force = |t: f64, y: &State| {
            let (_, f) = sim.observe(t, y);
            (f.contact, f.robot.abs())
        };
        let n = 16;
        let ts: Vec<f64> = (0..=n).map(|k| t_prev + (t_end - t_prev) * k as f64 / n as f64).collect();
        let fs: Vec<(f64, f64)> = ts.iter().map(|&t| force(t, &at(t))).collect();
        for which in 0..2 {
            let val = |p: (f64, f64)| if which == 0 { p.0 } else { p.1 };
            let (k, best) = fs.iter().enumerate().fold((0, f64::MIN), |acc, (k, &p)| if val(p) > acc.1 { (k, val(p)) } else { acc });
            let mut peak = best;
            // Around the best sample, also when it is an end of the step (a peak just inside).
            {
                let (mut a, mut b) = (ts[k.saturating_sub(1)], ts[(k + 1).min(n)]);
                let g = 0.618_033_988_749_894_9;
                for _ in 0..60 {
                    let (c, d) = (b - g * (b - a), a + g * (b - a));
                    if val(force(c, &at(c))) > val(force(d, &at(d))) { b = d } else { a = c }
                }
                let m = 0.5 * (a + b);
                peak = peak.max(val(force(m, &at(m))));
            }
            if which == 0 { seg.peak_contact = seg.peak_contact.max(peak) } else { seg.peak_robot = seg.peak_robot.max(peak) }
        }
        seg.last = Some((t_end, at(t_end)));
        if seg.event.is_some() { ControlFlag::Terminate } else { ControlFlag::Continue }
    }
}

/// What the independent integration found.
#[derive(Debug)]
struct Figures {
    peak_contact: f64,
    peak_robot: f64,
    t_detect: Option<f64>,
    object_final_velocity: Option<f64>,
    mode: Option<u8>,
    events: usize,
}

fn dop853_run(scene: &Scene) -> Figures {
    let run = Run::new(scene, false, false);
    let y0 = {
        let s = &run.sim;
        s.plant.initial_state(scene.motion.start_at_speed, scene.motion.speed)
    };
    let sim = RefCell::new(run.sim);
    let (mut t, mut y) = (0.0, y0);
    let (mut peak_contact, mut peak_robot) = (0.0f64, 0.0f64);
    let (mut t_detect, mut t_back, mut v_sep, mut in_contact) = (None, None, None, false);
    let mut events = 0;
    {
        let (_, f) = sim.borrow().observe(0.0, &y0);
        peak_contact = peak_contact.max(f.contact);
        peak_robot = peak_robot.max(f.robot.abs());
    }
    while t < scene.duration_s {
        assert!(events < 100_000, "{}: too many events", scene.name);
        let t_stop = sim.borrow().next_breakpoint(t).map_or(scene.duration_s, |b| b.min(scene.duration_s));
        let seg = RefCell::new(Segment::default());
        let ode = Plant(&sim);
        let method = ExplicitRungeKutta::dop853().rtol(1e-12).atol(1e-14).h_max(scene.solver.max_step).max_steps(10_000_000);
        let solved = IVP::ode(&ode, t, t_stop, y).solout(Watch { sim: &sim, seg: &seg }).method(method).solve();
        if let Err(e) = solved {
            panic!("{}: DOP853 failed at t = {t}: {e:?}", scene.name);
        }
        let seg = seg.into_inner();
        peak_contact = peak_contact.max(seg.peak_contact);
        peak_robot = peak_robot.max(seg.peak_robot);
        match seg.event {
            Some((i, te, mut ye)) => {
                let mut s = sim.borrow_mut();
                let entering = s.watching(i) == Some(Crossing::Up);
                match i {
                    EV_CONTACT if !entering => v_sep = Some(ye[VP]),
                    EV_BACK if entering => {
                        t_back.get_or_insert(te);
                    }
                    EV_SWITCH => t_detect = Some(te),
                    _ => {}
                }
                if i == EV_CONTACT {
                    in_contact = entering;
                }
                s.on_event(i, te, &mut ye);
                events += 1;
                (t, y) = (te, ye);
            }
            None => {
                let (tl, yl) = seg.last.unwrap_or((t_stop, y));
                assert!((tl - t_stop).abs() < 1e-12, "{}: segment ended at {tl}, not {t_stop}", scene.name);
                (t, y) = (t_stop, yl);
            }
        }
    }
    let s = sim.borrow();
    let object = s.plant.target.is_object();
    let mode = s.plant.decoupler.back_stop().map(|_| match (t_back, s.plant.motion.t_stop()) {
        (None, _) => 1,
        (Some(tb), Some(ts)) if tb >= ts => 2,
        _ => 3,
    });
    Figures {
        peak_contact,
        peak_robot,
        t_detect,
        object_final_velocity: object.then(|| if in_contact { y[VP] } else { v_sep.unwrap_or(y[VP]) }),
        mode,
        events,
    }
}

fn reference(name: &str) -> (Scene, Summary) {
    let mut s = scene::load(&scene_path(name)).unwrap_or_else(|e| panic!("{e}"));
    s.solver.fidelity = Fidelity::Reference;
    s.solver.rtol = scene::REFERENCE_RTOL;
    s.solver.atol = scene::REFERENCE_ATOL;
    let (summary, _) = sim::run(&s, false).unwrap_or_else(|e| panic!("{name}: {e}"));
    (s, summary)
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-12)
}

/// Agreement expected between two integrations at these tolerances: 1e-6 relative on forces and
/// velocities, 1e-8 s on the detection instant (both locate it to 1e-12 s on interpolants accurate
/// to about 1e-10).
fn cross_check(name: &str) {
    let (s, ours) = reference(name);
    assert_eq!(ours.fidelity, "reference");
    let other = dop853_run(&s);
    let msg = format!("{name}: ours {ours:?}\nDOP853 {other:?}");
    assert!(rel(ours.peak_contact_force, other.peak_contact) < 1e-6, "peak contact force\n{msg}");
    assert!(rel(ours.peak_robot_force, other.peak_robot) < 1e-6, "peak robot force\n{msg}");
    match (ours.t_detect, other.t_detect) {
        (Some(a), Some(b)) => assert!((a - b).abs() < 1e-8, "detection time\n{msg}"),
        (a, b) => assert_eq!(a.is_some(), b.is_some(), "detection\n{msg}"),
    }
    match (ours.object_final_velocity, other.object_final_velocity) {
        (Some(a), Some(b)) => assert!((a - b).abs() < 1e-6 * b.abs().max(1e-3), "object final velocity\n{msg}"),
        (a, b) => assert_eq!(a.is_some(), b.is_some(), "object\n{msg}"),
    }
    assert_eq!(ours.mode, other.mode, "mode\n{msg}");
    assert!(other.events > 0, "{msg}");
}

macro_rules! scenes {
    ($($test:ident => $file:expr;)*) => {$(
        #[test]
        fn $test() {
            cross_check($file);
        }
    )*};
}

scenes! {
    table11_z_prototype => "table11_z_prototype.toml";
    table12_hydraulic_object => "table12_hydraulic_object.toml";
    table12_hydraulic_object_dt10 => "table12_hydraulic_object_dt10.toml";
    table13_bistable_object => "table13_bistable_object.toml";
    table13_bistable_object_dt10 => "table13_bistable_object_dt10.toml";
    table14_hydraulic_surface => "table14_hydraulic_surface.toml";
    table14_hydraulic_surface_dt10 => "table14_hydraulic_surface_dt10.toml";
    table15_bistable_surface => "table15_bistable_surface.toml";
    table15_bistable_surface_dt10 => "table15_bistable_surface_dt10.toml";
    table1_free_tool => "table1_free_tool.toml";
    table1_rigid_tool => "table1_rigid_tool.toml";
    table2_bistable => "table2_bistable.toml";
    table2_linear => "table2_linear.toml";
    table2_rigid => "table2_rigid.toml";
    table4_bistable_136g => "table4_bistable_136g.toml";
    table4_bistable_246g => "table4_bistable_246g.toml";
    table4_rigid_136g => "table4_rigid_136g.toml";
    table8_bistable => "table8_bistable.toml";
    tables5_7_bistable => "tables5-7_bistable.toml";
    tables5_7_bistable_v020 => "tables5-7_bistable_v020.toml";
    tables5_7_bistable_v025 => "tables5-7_bistable_v025.toml";
    tables5_7_rigid => "tables5-7_rigid.toml";
    robot_two_link => "robot_two_link.toml";
    robot_viper_standin => "robot_viper_standin.toml";
    body_hand => "body_hand.toml";
    body_hand_free => "body_hand_free.toml";
    body_hand_rigid => "body_hand_rigid.toml";
    tables5_7_bistable_stopping_table => "tables5-7_bistable_stopping_table.toml";
}

#[test]
fn every_shipped_scene_is_cross_checked() {
    let listed = include_str!("reference.rs");
    for e in std::fs::read_dir(scene_path("")).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        if name.ends_with(".toml") && !name.starts_with("avoid_") {
            assert!(listed.contains(&format!("\"{name}\"")), "{name} is not cross-checked here");
        }
    }
}
