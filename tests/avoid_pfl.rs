//! Issue 29: one safety concept, speed and separation monitoring (ISO/TS 15066 5.5.4) on the
//! tool's speed *towards* the person, with the module's power and force limit (5.5.5) beside it.
//! The thesis's cell must reach its goal (faster with the module than with a rigid tool), a hand
//! behind the tool must not freeze it, a contact is permitted only within the PFL speeds and only
//! in the directions the module yields, and every run is judged honestly from the true geometry.

use flinch_harness::avoid::path::{simulate, Engine, PathResult, Reason, Setup, Status};
use flinch_harness::avoid::scene::{Avoid, Keyframe};
use flinch_tests::scene_path;

fn load(name: &str) -> Avoid {
    let mut s = Avoid::load(&scene_path(name)).unwrap_or_else(|e| panic!("{e}"));
    flinch_harness::pfl::resolve_pfl(&mut s).unwrap_or_else(|e| panic!("{name}: {e}"));
    s
}

fn run(s: &Avoid, engine: Engine) -> PathResult {
    let setup = Setup::new(s, None).unwrap();
    simulate(s, &setup, engine).unwrap()
}

/// Never inside a person except a contact within the PFL speeds that ended the run; never over
/// the SSM bound outside PFL; the verdict's counters agree with the rows.
fn judged_safe(name: &str, s: &Avoid, r: &PathResult) {
    assert_eq!(r.ssm_violations, 0, "{name}: {} steps over both bounds, by up to {} m/s", r.ssm_violations, r.max_speed_over_ssm_mps);
    assert!(!matches!(r.status, Status::Collision(_) | Status::SsmViolation(_) | Status::Fault | Status::TooClose), "{name}: {:?}", r.status);
    if r.min_signed_distance_m < 0.0 {
        assert_eq!((r.status, r.contacts_within_pfl), (Status::Stopped(Reason::ContactStop), 1), "{name}: inside only by a contact within PFL");
    }
    assert!(r.max_speed_mps <= s.speed_mps + 1e-9, "{name}");
}

/// Done-when of issue 29: the thesis's cell (the hand reaching to the tool's line) reaches its goal
/// under SSM + PFL, with 0 steps over either bound, faster with the module than with a rigid tool;
/// the module's PFL speed along its axis is above the rigid one.
#[test]
fn the_thesis_cell_reaches_its_goal_and_the_module_is_faster_than_a_rigid_tool() {
    let module = load("avoid_thesis_reach_pfl.toml");
    let rigid = load("avoid_thesis_reach_rigid.toml");
    let (pm, pr) = (module.pfl.as_ref().unwrap().resolved.clone().unwrap(), rigid.pfl.as_ref().unwrap().resolved.clone().unwrap());
    assert!(pm.along_mps > 2.0 * pr.along_mps, "module {} m/s against rigid {} m/s along the axis", pm.along_mps, pr.along_mps);
    assert!((pm.across_mps - pr.across_mps).abs() < 1e-9, "across the axis both are the rigid tool");
    assert_eq!(pm.module_sha256.len(), 64);
    let rm = run(&module, Engine::Reference);
    let rr = run(&rigid, Engine::Reference);
    judged_safe("module", &module, &rm);
    judged_safe("rigid", &rigid, &rr);
    assert_eq!(rm.status, Status::Reached, "module: {:?}", rm.status);
    assert_eq!(rr.status, Status::Reached, "rigid: {:?}", rr.status);
    let (tm, tr) = (rm.time_to_goal_s.unwrap(), rr.time_to_goal_s.unwrap());
    assert!(tm < tr, "the module reaches the goal sooner: {tm} s against {tr} s");
    // The board's engine runs the same monitor.
    let mcu = run(&module, Engine::Mcu);
    judged_safe("module --mcu", &module, &mcu);
    assert_eq!(mcu.status, Status::Reached, "--mcu: {:?}", mcu.status);
}

/// A hand 0.4 m behind the tool (issue 29: it froze the tool for 40 s), the goal straight away from
/// it: moving away is not limited (ISO/TS 15066 5.5.4.2.3), so the tool leaves at once; a hand as
/// far ahead (the goal through it) still stops it short, SSM alone.
#[test]
fn a_hand_behind_the_tool_does_not_freeze_it() {
    let mut s = Avoid::load(&scene_path("avoid_thesis_reach.toml")).unwrap();
    s.start_m = [0.62, 0.50];
    s.goal_m = [0.95, 0.50];
    s.operator.entry_m = [0.0, 0.50];
    s.operator.keyframes = vec![Keyframe { t_s: 0.0, hand_m: [0.12, 0.50] }];
    let r = run(&s, Engine::Reference);
    judged_safe("behind", &s, &r);
    assert_eq!(r.status, Status::Reached, "{:?}", r.status);
    let moved = r.rows.iter().position(|w| w.v_mps[0] > 0.0).map(|k| r.rows[k].t_s);
    assert!(moved.is_some_and(|t| t < 0.2), "leaves within the first frames: {moved:?}");
    // Ahead: the same hand, the goal through it: it must stop short of the hand.
    let mut a = s.clone();
    a.goal_m = [0.10, 0.50];
    a.max_time_s = 8.0;
    let ra = run(&a, Engine::Reference);
    judged_safe("ahead", &a, &ra);
    assert!(ra.min_signed_distance_m > 0.0 && ra.time_to_goal_s.is_none(), "{} {:?}", ra.min_signed_distance_m, ra.status);
}

/// The goal inside the hand: with PFL the tool may approach and touch within the PFL speeds; it
/// then stops on the contact (the module's switch), a safe stop (exit 4) that a person resets,
/// never a collision. Without PFL the same scene is a stop before the hand.
#[test]
fn a_contact_within_pfl_ends_in_a_stop() {
    let mut s = Avoid::load(&scene_path("avoid_goal_covered.toml")).unwrap();
    let mut with = s.clone();
    let pfl_of = Avoid::load(&scene_path("avoid_thesis_reach_pfl.toml")).unwrap().pfl;
    with.pfl = pfl_of;
    flinch_harness::pfl::resolve_pfl(&mut with).unwrap();
    with.max_time_s = 30.0;
    let r = run(&with, Engine::Reference);
    judged_safe("goal covered, PFL", &with, &r);
    assert!(matches!(r.status, Status::Stopped(_)), "{:?}", r.status);
    if r.contacts_within_pfl > 0 {
        let p = with.pfl.as_ref().unwrap().resolved.as_ref().unwrap();
        assert!(r.max_contact_speed_mps <= p.along_mps + 1e-9, "{} m/s", r.max_contact_speed_mps);
        assert_eq!(r.status, Status::Stopped(Reason::ContactStop));
    }
    s.max_time_s = 10.0;
    let plain = run(&s, Engine::Reference);
    judged_safe("goal covered, SSM alone", &s, &plain);
    assert!(plain.min_signed_distance_m > 0.0);
}

/// The verdict on its own: the thesis's law (no monitor) driven along x into a hand on the path,
/// with PFL declared but the module's axis ACROSS the travel: the contact is at 0.25 m/s across
/// the axis, above the rigid PFL speed, so it is a collision (exit 1) whatever PFL allows along
/// the axis; with the axis along the travel the same contact is within PFL and a stop.
#[test]
fn a_contact_across_the_modules_axis_beyond_the_rigid_speed_is_a_collision() {
    let base = {
        let mut s = Avoid::load(&scene_path("avoid_head_on.toml")).unwrap();
        s.safety.mode = "off".into();
        // No repulsion: straight at the goal through the hand, the velocity along the travel.
        s.k_rep = 0.0;
        s.pfl = Avoid::load(&scene_path("avoid_thesis_reach_pfl.toml")).unwrap().pfl;
        s
    };
    let mut across = base.clone();
    across.pfl.as_mut().unwrap().axis = [0.0, 1.0];
    flinch_harness::pfl::resolve_pfl(&mut across).unwrap();
    let r = run(&across, Engine::Reference);
    assert!(matches!(r.status, Status::Collision(_)), "across: {:?}", r.status);
    assert_eq!(flinch_harness::avoid::path::Status::verdict(r.status).code(), 1);
    let mut along = base;
    flinch_harness::pfl::resolve_pfl(&mut along).unwrap();
    let dir = {
        let d = [along.goal_m[0] - along.start_m[0], along.goal_m[1] - along.start_m[1]];
        let n = d[0].hypot(d[1]);
        [d[0] / n, d[1] / n]
    };
    along.pfl.as_mut().unwrap().axis = dir;
    let r = run(&along, Engine::Reference);
    let p = along.pfl.as_ref().unwrap().resolved.as_ref().unwrap();
    if along.speed_mps <= p.along_mps {
        assert_eq!(r.status, Status::Stopped(Reason::ContactStop), "along: {:?}", r.status);
        assert_eq!(r.contacts_within_pfl, 1);
    } else {
        assert!(matches!(r.status, Status::Collision(_)), "along, faster than the module's PFL speed: {:?}", r.status);
    }
}

/// Bad `[avoid.pfl]` is refused by name before anything runs; an unresolved one never runs as
/// SSM alone.
#[test]
fn pfl_keys_are_checked_and_never_silently_dropped() {
    let text = std::fs::read_to_string(scene_path("avoid_thesis_reach_pfl.toml")).unwrap();
    let bad = |from: &str, to: &str| Avoid::parse(&text.replace(from, to)).err().unwrap_or_else(|| panic!("{to} accepted"));
    let e = bad("body_regions = [\"hand\", \"lower_arm\"]", "body_regions = [\"hand\", \"face\"]");
    assert!(e.contains("avoid.pfl.body_regions") && e.contains("face"), "{e}");
    let e = bad("axis = [1.0, 0.0]", "axis = [0.0, 0.0]");
    assert!(e.contains("avoid.pfl.axis") && e.contains("direction"), "{e}");
    let e = bad("body_regions = [\"hand\", \"lower_arm\"]", "body_regions = []");
    assert!(e.contains("avoid.pfl.body_regions"), "{e}");
    let e = bad("axis = [1.0, 0.0]", "axis = [1.0, 0.0]\nspeed_mps = 0.3");
    assert!(e.contains("speed_mps"), "{e}");
    // A module scene that is not there: the key and the file named.
    let mut s = Avoid::load(&scene_path("avoid_thesis_reach_pfl.toml")).unwrap();
    s.pfl.as_mut().unwrap().module = "no_such_module.toml".into();
    s.pfl.as_mut().unwrap().module_path = scene_path("no_such_module.toml");
    let e = flinch_harness::pfl::resolve_pfl(&mut s).unwrap_err();
    assert!(e.contains("avoid.pfl.module") && e.contains("no_such_module"), "{e}");
    // Not resolved: the run refuses.
    let s = Avoid::load(&scene_path("avoid_thesis_reach_pfl.toml")).unwrap();
    let setup = Setup::new(&s, None).unwrap();
    let e = simulate(&s, &setup, Engine::Reference).err().unwrap();
    assert!(e.contains("avoid.pfl") && e.contains("not computed"), "{e}");
    // The thesis's law has no PFL.
    let mut t = s;
    t.thesis_mode();
    assert!(t.pfl.is_none());
}

/// Issue 29 item 3: the whole arm. A person (1 m tall) standing between the tool's path and the
/// robot's base, beyond the camera's view (the plane ends at y = 1.05 m), where the link sweeps as
/// the tool crosses: the monitor, which sees only the view, lets the tool go, the link enters them,
/// and the run is a collision (exit 1), never `reached`, whatever the tool's own clearance. A part
/// lower than the link's underside at the same place passes beneath it.
#[test]
fn the_arm_sweeping_into_a_standing_person_is_a_collision() {
    let mut s = Avoid::load(&scene_path("avoid_thesis_reach.toml")).unwrap();
    s.operator.keyframes = vec![Keyframe { t_s: 0.0, hand_m: [0.50, 0.06] }];
    s.operator.entry_m = [0.50, 0.0];
    s.operator.obstacles.push(flinch_harness::avoid::depth::Obstacle {
        kind: "disc".into(),
        center_m: [0.55, 1.15],
        keyframes: vec![],
        radius_m: 0.08,
        size_m: [0.0; 2],
        height_m: 1.0,
        fixture: false,
    });
    let r = run(&s, Engine::Reference);
    assert!(r.link_min_signed_distance_m < 0.0, "the link sweeps into the person: {}", r.link_min_signed_distance_m);
    assert!(matches!(r.status, Status::Collision(_)), "{:?}", r.status);
    assert_eq!(r.status.verdict().code(), 1);
    let m = flinch_harness::avoid::metrics_json(&r, Engine::Reference, true);
    assert_eq!((m["status"].as_str(), m["collided"].as_bool()), (Some("collision"), Some(true)), "{m}");
    // Lower than the link's underside (0.33 m): beneath it, not touched.
    s.operator.obstacles[0].height_m = 0.2;
    let r = run(&s, Engine::Reference);
    assert!(r.link_min_signed_distance_m.is_infinite(), "{}", r.link_min_signed_distance_m);
    assert!(!matches!(r.status, Status::Collision(_)), "{:?}", r.status);
}
