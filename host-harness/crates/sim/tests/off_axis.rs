//! Issue 30, item 4: what is left of the 1-D modules' protection when the flange's velocity is at
//! beta = `motion.off_axis_deg` from the decoupler's axis (the surface facing the motion). Physics
//! checked, not assumed: at beta = 0 the run is the 1-D run; the guide's share of the push is
//! cos(beta), so the travel needed and the force along the normal grow; at beta = 90 the guide runs
//! parallel to the surface and the module is a rigid tool (exhausted on contact, never safe).
//! `off_axis_table` prints the study of docs/planar.md (`cargo test -p flinch-sim --test off_axis
//! -- --ignored --nocapture`).

use flinch_model::scene::{parse, Scene};
use flinch_sim::Summary;

fn scene(name: &str, beta: f64, mu: f64) -> Scene {
    let text = flinch_model::shipped::get(name).unwrap();
    let mut sc = parse(text, name).unwrap();
    sc.planar = Some(flinch_model::scene::Planar { off_axis_deg: beta, surface_angle_deg: beta - 90.0, contact_mu: mu, rotational: None });
    sc
}

fn run(name: &str, beta: f64, mu: f64) -> Summary {
    flinch_sim::run(&scene(name, beta, mu), false).unwrap_or_else(|e| panic!("{name} at {beta}: {e}")).0
}

const MODULES: [&str; 3] = ["tables5-7_bistable", "table14_hydraulic_surface", "table15_bistable_surface"];

#[test]
fn across_the_axis_a_module_is_a_rigid_tool() {
    for name in MODULES {
        let s = run(name, 90.0, 0.0);
        assert!(s.stroke_exhausted && !s.safe, "{name}: {:?}", s.failures);
        assert_eq!(s.stroke_left_min_m, Some(0.0), "{name}");
        assert!(s.max_travel.abs() < 1e-6, "{name}: travelled {} m across its axis", s.max_travel);
        // Beyond 90 deg the guide leads into the target: the same.
        assert!(!run(name, 120.0, 0.0).safe, "{name} at 120 deg");
    }
}

#[test]
fn off_axis_the_guide_needs_more_force_and_the_stroke_left_shrinks() {
    for name in MODULES {
        let s0 = run(name, 0.0, 0.0);
        let s45 = run(name, 45.0, 0.0);
        // The tool moves along the guide: to yield a normal distance d it travels d / cos(beta), and
        // the stroke left along the normal is the guide's times cos(beta).
        let (l0, l45) = (s0.stroke_left_min_m.unwrap(), s45.stroke_left_min_m.unwrap());
        if s0.stroke_exhausted {
            // Already through its stroke head-on (Table 14's hydraulic): no better at an angle.
            assert!(s45.stroke_exhausted, "{name}");
        } else {
            assert!(l45 < l0, "{name}: {l45} >= {l0}");
        }
        assert!(s45.peak_contact_force > s0.peak_contact_force * 0.99, "{name}: {} < {}", s45.peak_contact_force, s0.peak_contact_force);
        assert_eq!(s0.off_axis_deg, Some(0.0));
    }
}

#[test]
fn the_sign_of_beta_does_not_matter_for_a_1d_module() {
    let (a, b) = (run("tables5-7_bistable", 30.0, 0.3), run("tables5-7_bistable", -30.0, 0.3));
    for (x, y) in [(a.peak_contact_force, b.peak_contact_force), (a.peak_robot_force, b.peak_robot_force), (a.max_travel, b.max_travel)] {
        assert!((x - y).abs() <= 1e-6 * x.abs().max(1e-9), "{x} vs {y}");
    }
}

#[test]
fn a_module_locked_by_contact_friction_is_blocked_even_when_detected() {
    // tables5-7_bistable at 80 deg with mu = 0.3: the push lies outside the friction cone around
    // the guide, the tool cannot slide, the module does not yield. With the shipped travel switch
    // nothing detects it; with a force sensor (25 N) the robot stops, and the kilonewtons on the
    // obstacle must still not be called safe.
    let s = run("tables5-7_bistable", 80.0, 0.3);
    assert!(!s.safe && s.module_blocked_t_s.is_some(), "{:?}", s.failures);
    assert!(s.failures.iter().any(|f| f.starts_with("module blocked")), "{:?}", s.failures);
    let mut sc = scene("tables5-7_bistable", 80.0, 0.3);
    let text = flinch_model::shipped::get("tables5-7_bistable").unwrap().replace("kind = \"travel\"", "kind = \"force\"").replace("threshold = 0.005", "threshold = 25.0");
    sc.sensor = parse(&text, "force.toml").unwrap().sensor;
    let s = flinch_sim::run(&sc, false).unwrap().0;
    assert!(s.t_detect.is_some(), "the force sensor detects it");
    assert!(!s.safe && s.module_blocked_t_s.is_some(), "detected but blocked: {:?} {}", s.failures, s.peak_contact_force);
    // Head-on, and at 45 deg, nothing is blocked.
    for beta in [0.0, 45.0] {
        assert!(run("tables5-7_bistable", beta, 0.3).module_blocked_t_s.is_none(), "{beta}");
    }
}

/// The largest beta (0.1 deg) up to which the run stays safe, by a 5-deg scan and bisection.
fn largest_safe_beta(name: &str, mu: f64) -> Option<f64> {
    if !run(name, 0.0, mu).safe {
        return None;
    }
    let mut lo = 0.0;
    let mut hi = 90.0;
    let mut b = 5.0;
    while b <= 90.0 {
        if !run(name, b, mu).safe {
            hi = b;
            break;
        }
        lo = b;
        b += 5.0;
    }
    while hi - lo > 0.1 {
        let m = 0.5 * (lo + hi);
        if run(name, m, mu).safe { lo = m } else { hi = m }
    }
    Some(lo)
}

#[test]
#[ignore]
fn off_axis_table() {
    for mu in [0.0, 0.3] {
        for name in MODULES {
            println!("\n{name}, contact mu = {mu}: largest safe beta {:?} deg", largest_safe_beta(name, mu).map(|b| (b * 10.0).round() / 10.0));
            println!("| beta deg | peak contact N | peak robot N | max travel mm | stroke left along the normal mm | safe | failure |");
            println!("|---|---|---|---|---|---|---|");
            for beta in [0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 80.0, 85.0, 89.0, 90.0] {
                let s = run(name, beta, mu);
                println!("| {beta} | {:.1} | {:.1} | {:.2} | {} | {} | {} |", s.peak_contact_force, s.peak_robot_force, s.max_travel * 1e3, s.stroke_left_min_m.map_or("-".into(), |l| format!("{:.2}", l * 1e3)), s.safe, s.failures.first().map_or("", |f| f.split(':').next().unwrap_or("")));
            }
        }
    }
}
