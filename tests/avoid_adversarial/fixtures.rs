//! Obstacle classes (issue 29 item 2): a fixture (`class = "fixture"`: a tray, a jig, a wall) is
//! kept clear of without a human approach; contact with it is a collision; the sensor, not the
//! scene's ground truth, tells a fixture's pixel from a person's, so a hand over the tray is a person.

use super::*;
use flinch_harness::avoid::path::{fit_and_sense_classed, Reason, Setup, Status};
use flinch_harness::avoid::scene::Avoid;

fn tray() -> Avoid {
    Avoid::load(&scene_path("avoid_tray_beside_goal.toml")).unwrap()
}

/// Acceptance of items 6 and 2: a 40 mm tray 0.15 m from the goal. As a fixture the tool reaches
/// the goal with 0 steps over either bound and never touches the tray; the same tray as a person
/// (as every sensed object was before) leaves no room at the goal (`no_room`).
#[test]
fn a_tray_beside_the_goal_is_reached() {
    let (scene, r) = run_scene(tray());
    honest("tray beside the goal", &scene, &r);
    eprintln!("tray: {:?}, {:.2} s, {:.3} m, min {:.4} m", r.status, r.time_to_goal_s.unwrap_or(f64::NAN), r.path_length_m, r.min_signed_distance_m);
    assert_eq!(r.status, Status::Reached, "{:?}", r.status);
    assert_eq!(r.ssm_violations, 0);
    assert!(r.min_signed_distance_m >= scene.clearance_m, "{}", r.min_signed_distance_m);
    let mut person = tray();
    person.operator.obstacles[0].fixture = false;
    let (_, p) = run_scene(person);
    assert_eq!(p.status, Status::Stopped(Reason::NoRoom), "{:?}", p.status);
}

/// A hand reaching over the tray, 120 mm high (above the tray's 40 mm and the 10 mm tolerance),
/// inside its footprint: the sensor classes its pixels as a person's, so the person bound (with K)
/// applies: the separation the monitor reads is the hand's, and the run stops at once (the goal is
/// within `S_p(0)` of the hand) with no step over the bound. Classed by footprint alone (ground
/// truth of where the tray is) the hand would be a fixture and the tool would drive up to it.
#[test]
fn a_hand_over_the_tray_is_a_person() {
    let mut s = tray();
    s.operator.entry_m = [0.80, -0.30];
    s.operator.keyframes[0].hand_m = [0.80, 0.27];
    s.operator.hand_height_m = 0.12;
    s.operator.forearm_height_m = 0.10;
    let setup = Setup::new(&s, None).unwrap();
    let mut rng = flinch_harness::avoid::depth::Rng::new(3);
    let sensed = fit_and_sense_classed(&s, &setup, s.goal_m, &s.operator_shape_at(0.0), s.hand_at(0.0), &mut rng);
    // The hand's edge from the tool's surface at the goal: 0.50 - 0.27 - 0.05 - 0.045 = 0.135 m.
    assert!(sensed.separation_m < 0.15 && sensed.separation_m > 0.10, "the hand is a person: {}", sensed.separation_m);
    assert!(sensed.goal_separation_m < 0.15, "{}", sensed.goal_separation_m);
    // The tray's pixels beside the hand are still the tray's.
    assert!(sensed.fixture_sectors_m.iter().any(|&d| d < 0.2), "{:?}", sensed.fixture_sectors_m);
    let (scene, r) = run_scene(s);
    honest("hand over the tray", &scene, &r);
    assert_eq!(r.ssm_violations, 0);
    assert_eq!(r.status, Status::Stopped(Reason::NoRoom), "{:?}", r.status);
}

/// Contact with a fixture is a collision (exit 1), never a permitted contact: the box wall as a
/// fixture, the thesis's law (no monitor) drives into or over it. With the monitor the tool keeps
/// clear of it (stopped, never inside, no step over the fixture's bound).
#[test]
fn contact_with_a_fixture_is_a_collision() {
    let mut s = Avoid::load(&scene_path("avoid_box_wall.toml")).unwrap();
    for o in &mut s.operator.obstacles {
        o.fixture = true;
    }
    let mut t = s.clone();
    t.thesis_mode();
    t.k_rep = 0.0;
    let (scene, r) = run_scene(t);
    honest("fixture wall, thesis", &scene, &r);
    assert!(matches!(r.status, Status::Collision(_)), "{:?}", r.status);
    assert_eq!(r.status.verdict().code(), 1);
    let (scene, r) = run_scene(s);
    honest("fixture wall", &scene, &r);
    eprintln!("fixture wall, monitor: {:?}, min {:.4} m", r.status, r.min_signed_distance_m);
    assert!(r.min_signed_distance_m >= 0.0, "{}", r.min_signed_distance_m);
    assert_eq!(r.ssm_violations, 0);
}
