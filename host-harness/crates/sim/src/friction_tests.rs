//! The Karnopp slide (`flinch-plant`'s friction.rs) in whole runs: a stuck tool never drifts, it
//! breaks away when the contact force reaches the limit, and it does not chatter.

use flinch_plant::friction::Slide;
use flinch_plant::{Plant, XR, XT};
use flinch_model::scene::{parse, Scene};
use crate::Run;

/// Table 8's paddle (stick-slip by default: v0 = 0), edited.
fn table8(edit: &[(&str, &str)]) -> Scene {
    let mut text = flinch_model::shipped::get("table8_bistable").unwrap().to_string();
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
    if let flinch_model::scene::Decoupler::Bistable(b) = &mut reg.decoupler {
        b.friction.as_mut().unwrap().law = flinch_model::scene::FrictionLaw::Regularised;
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
        let scene = parse(flinch_model::shipped::get(name).unwrap(), name).unwrap();
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
        scene.robot = Some(flinch_model::scene::Robot { mass: 8.4, stiffness: 2.3e5, damping: 71.0 });
        let mut run = Run::new(&scene, false, false);
        run.finish().unwrap();
        let n = run.slide_switches().len();
        eprintln!("mu {mu}: {n} switches, {} steps", run.stats().steps);
        assert!(n <= 60, "mu {mu}: {n} switches");
        let st = run.stats();
        assert!(st.steps < 5000, "mu {mu}: {} steps", st.steps);
    }
}
