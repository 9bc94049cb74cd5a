//! Issue 30: every value the validator accepts for the planar keys runs without NaN, panic or
//! blow-up (the accepted ranges are the tested ranges): `motion.off_axis_deg`,
//! `target.surface_angle_deg`, `target.friction_mu` and every key of `[decoupler.rotational]`,
//! drawn over their whole ranges (and their ends) on a 1-D module and on the rotational module.
//! A combination the validator refuses (a flange that does not close on the surface, a tool over
//! the stage's axis) must be refused with the key named, never run.

use flinch_model::scene::parse;
use proptest::prelude::*;

const BASE: &str = include_str!("../../../../scenes/planar/fig69_rotational_theta0.toml");

fn finite(s: &flinch_sim::Summary) -> bool {
    let opt = |x: Option<f64>| x.is_none_or(f64::is_finite);
    s.peak_contact_force.is_finite() && s.peak_robot_force.is_finite() && s.max_travel.is_finite() && s.decoupler_impulse.is_finite()
        && opt(s.module_rotation_deg) && opt(s.max_rotation_deg) && opt(s.stroke_left_min_m) && opt(s.t_detect)
}

fn end_or_any(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    prop_oneof![Just(lo), Just(hi), lo..=hi]
}

fn log_end_or_any(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    prop_oneof![Just(lo), Just(hi), (0.0..=1.0f64).prop_map(move |u| lo * (hi / lo).powf(u))]
}

/// Runs `text`; refused scenes must name the key.
fn check(text: &str, keys: &[&str]) -> Result<(), TestCaseError> {
    match parse(text, "box.toml") {
        Err(e) => {
            let m = e.to_string();
            prop_assert!(keys.iter().any(|k| m.contains(k)), "refused without naming a planar key:\n{m}\n{text}");
        }
        Ok(sc) => {
            let start = std::time::Instant::now();
            let (s, _) = flinch_sim::run(&sc, false).map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
            prop_assert!(finite(&s), "{s:?}\n{text}");
            // Blow-up: a kilonewton-class drive against a locked module is real (tests/rotational.rs);
            // anything near the robot's whole stiffness over a metre is not.
            prop_assert!(s.peak_contact_force < 1e6 && s.peak_robot_force < 1e6, "{s:?}\n{text}");
            if start.elapsed().as_secs() > 20 {
                eprintln!("slow case ({} s, {} steps):\n{text}", start.elapsed().as_secs(), s.steps);
            }
        }
    }
    Ok(())
}

proptest! {
    // A fixed seed: the same cases on every machine (a slow corner found once is found again).
    #![proptest_config(ProptestConfig { cases: 16, failure_persistence: None, rng_seed: proptest::test_runner::RngSeed::Fixed(30), ..ProptestConfig::default() })]

    #[test]
    fn a_1d_module_at_any_accepted_angle(beta in end_or_any(-180.0, 180.0), theta in prop::option::of(end_or_any(-180.0, 180.0)), mu in end_or_any(0.0, 1.5)) {
        let text = flinch_model::shipped::get("tables5-7_bistable").unwrap();
        let mut t = text.replace("[motion]", &format!("[motion]\noff_axis_deg = {beta:?}"));
        let extra = match theta { Some(th) => format!("[target]\nsurface_angle_deg = {th:?}\nfriction_mu = {mu:?}"), None => format!("[target]\nfriction_mu = {mu:?}") };
        t = t.replace("[target]", &extra);
        check(&t, &["off_axis_deg", "surface_angle_deg", "gap"])?;
    }

    #[test]
    fn the_rotational_module_over_its_accepted_box(
        theta in end_or_any(-180.0, 180.0),
        inertia in log_end_or_any(1e-7, 1.0),
        lever in end_or_any(-0.2, 0.2),
        b in end_or_any(-0.1, 0.1),
        radius in end_or_any(0.0, 0.05),
        stiffness in end_or_any(0.0, 100.0),
        preload in end_or_any(0.0, 10.0),
        bearing in end_or_any(0.0, 0.01),
        mu in end_or_any(0.0, 1.5),
    ) {
        let stage = format!("rotational = {{ inertia = {inertia:?}, lever = {lever:?}, offset_b = {b:?}, tool_radius = {radius:?}, stiffness = {stiffness:?}, preload = {preload:?}, bearing_torque = {bearing:?} }}");
        let mut t = String::new();
        for line in BASE.lines() {
            let l = if line.starts_with("rotational = ") { stage.clone() }
                else if line.starts_with("surface_angle_deg") { format!("surface_angle_deg = {theta:?}") }
                else if line.starts_with("friction_mu") { format!("friction_mu = {mu:?}") }
                else if line.starts_with("duration") { "duration = 0.15".into() }
                else { line.to_string() };
            t.push_str(&l);
            t.push('\n');
        }
        check(&t, &["surface_angle_deg", "rotational", "gap"])?;
    }
}
