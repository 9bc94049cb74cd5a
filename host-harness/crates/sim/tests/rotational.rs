//! Issue 30: the thesis's 2-D rotational module (Ch. 3.5, `plant/planar/rotational_stage.rs`) on the
//! scenes of Fig. 69: what the thesis reports qualitatively (the stage turns for theta >= 0 and the
//! mechanism engages at one angle; for theta < 0 it engages at once with no rotation), and the
//! adversarial cases (a tool ahead of the stage's axis, b = 0 at theta = 90).

use flinch_model::scene::{parse, Scene};
use flinch_sim::Summary;

fn text(theta: f64) -> String {
    let t = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../scenes/planar/fig69_rotational_theta0.toml")).unwrap();
    t.replace("surface_angle_deg = 0.0 ", &format!("surface_angle_deg = {theta} "))
}

fn scene(theta: f64, edit: &[(&str, &str)]) -> Scene {
    let mut t = text(theta);
    for (a, b) in edit {
        assert!(t.contains(a), "{a}");
        t = t.replace(a, b);
    }
    parse(&t, "fig69.toml").unwrap_or_else(|e| panic!("{e}"))
}

fn run(theta: f64, edit: &[(&str, &str)]) -> Summary {
    flinch_sim::run(&scene(theta, edit), false).unwrap().0
}

/// The turn of the stage at engagement, deg.
fn turn_at_engagement(theta: f64, s: &Summary) -> f64 {
    theta - s.module_rotation_deg.unwrap_or_else(|| panic!("theta {theta}: never engaged: {:?}", s.module_rotation_deg_null_reason))
}

#[test]
fn below_zero_the_mechanism_engages_at_once_with_no_rotation() {
    // Ch. 3.5: "for theta < 0 the bi-stable mechanism is engaged at once, no rotation".
    for th in [-30.0, -45.0, -60.0, -90.0] {
        let s = run(th, &[]);
        let turn = turn_at_engagement(th, &s);
        assert!(turn.abs() < 2.0, "theta {th}: turned {turn} deg before engaging");
        assert!(s.t_engaged_s.unwrap() < s.t_contact.unwrap() + 0.01, "theta {th}: engaged late");
        assert_eq!(s.surface_angle_deg, Some(th));
        assert!(s.safe, "theta {th}: {:?}", s.failures);
    }
}

#[test]
fn at_zero_and_ninety_the_stage_turns_first_and_engages_near_the_thesis_angle() {
    // Fig. 69: the stage turns from theta to the final angle, -24.73 +/- 0.64 deg measured for both.
    // The model's angle is quantised by the hits (docs/validation.md): asserted within 10 deg, the
    // figures themselves are in the docs.
    for th in [0.0, 90.0] {
        let s = run(th, &[]);
        let a = s.module_rotation_deg.unwrap();
        assert!(turn_at_engagement(th, &s) > 10.0, "theta {th}: engaged at {a} without turning");
        assert!((a + 24.73).abs() < 10.0, "theta {th}: engaged at {a} deg");
        assert!(s.max_rotation_deg.unwrap() >= th - a - 1e-9);
        assert!(s.t_detect.is_some() && s.safe && s.module_blocked_t_s.is_none(), "theta {th}: {:?}", s.failures);
    }
}

#[test]
fn a_module_that_cannot_turn_is_never_called_safe() {
    // b = 0 at theta = 90: the push runs through the stage's axis along the guide, onto the front
    // stop; nothing turns the stage (the caster's unstable equilibrium). A tool ahead of the axis
    // (lever < 0) turns the guide away from the push at theta = 0 and locks. Both push the beam with
    // the robot's drive: kilonewtons, nothing detected, not safe.
    for (th, edit) in [(90.0, ("offset_b = 0.02", "offset_b = 0.0")), (0.0, ("lever = 0.04", "lever = -0.04"))] {
        let s = run(th, &[edit]);
        assert!(s.module_rotation_deg.is_none() && s.module_rotation_deg_null_reason.is_some(), "theta {th}: {:?}", s.module_rotation_deg);
        assert!(s.peak_contact_force > 1000.0, "theta {th}: {}", s.peak_contact_force);
        assert!(!s.safe, "theta {th}: a locked module called safe");
        assert!(s.failures.iter().any(|f| f.starts_with("module blocked")), "theta {th}: {:?}", s.failures);
    }
    assert!(run(90.0, &[("offset_b = 0.02", "offset_b = 0.0")]).max_rotation_deg.unwrap() < 1e-6);
}

#[test]
fn the_1d_summary_has_no_planar_fields() {
    let s = flinch_sim::run(&parse(flinch_model::shipped::get("tables5-7_bistable").unwrap(), "x.toml").unwrap(), false).unwrap().0;
    assert!(s.off_axis_deg.is_none() && s.module_rotation_deg.is_none() && s.max_rotation_deg.is_none());
    let s = run(0.0, &[]);
    assert_eq!((s.off_axis_deg, s.surface_angle_deg), (Some(90.0), Some(0.0)));
}

/// Exploration (not a check): `EDIT="old=>new;..." THETAS=0,90 cargo test -p flinch-sim --test
/// rotational explore -- --ignored --nocapture` prints the engagement angle with the scene's text
/// edited (how docs/validation.md's calibration scans were made).
#[test]
#[ignore]
fn explore() {
    let edits = std::env::var("EDIT").unwrap_or_default();
    let pairs: Vec<(String, String)> = edits.split(';').filter(|e| !e.is_empty()).map(|e| { let (a, b) = e.split_once("=>").unwrap(); (a.to_string(), b.to_string()) }).collect();
    let ed: Vec<(&str, &str)> = pairs.iter().map(|(a, b)| (a.as_str(), b.as_str())).collect();
    let ths: Vec<f64> = std::env::var("THETAS").unwrap_or("0,90,45,-30".into()).split(',').map(|x| x.parse().unwrap()).collect();
    for th in ths {
        let s = run(th, &ed);
        eprintln!("{edits} theta {th:>5}: {:?} deg t {:?} max {:?} contacts {} N {:.2} safe {} {:?}", s.module_rotation_deg.map(|a| (a * 100.0).round() / 100.0), s.t_engaged_s, s.max_rotation_deg.map(|a| a.round()), s.contacts, s.peak_contact_force, s.safe, s.failures);
    }
}
