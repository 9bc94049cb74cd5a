//! Each adversarial scene's outcome: collisions reported as such, safe with the monitor (and on the
//! board's engine), the goal reached where there is room, an honest stop where there is none.

use super::*;
use flinch_harness::avoid::path::{simulate, Engine, Setup, Status};
use flinch_harness::avoid::scene::Avoid;
use flinch_harness::avoid;
use flinch_tests::scene_path;

/// The thesis's vortex law alone (eq 76, `--thesis`) goes through the operator on these scenes:
/// the report says so.
#[test]
fn crossings_are_reported_as_collisions() {
    for name in ["avoid_forearm_across.toml", "avoid_wall.toml", "avoid_goal_covered.toml", "avoid_head_on.toml"] {
        let (scene, r) = thesis(name);
        honest(name, &scene, &r);
        assert!(matches!(r.status, Status::Collision(_)), "{name}: {:?}, {} m", r.status, r.min_signed_distance_m);
        assert!(r.min_signed_distance_m < -0.01, "{name}: the depth is not clamped: {}", r.min_signed_distance_m);
        let json = avoid::metrics_json(&r, Engine::Reference, false);
        assert_eq!(json["status"], "collision", "{name}");
        assert_eq!(json["collided"], true);
        assert_ne!(json["status"], "reached", "{name}: never reached after a crossing");
    }
}

#[test]
fn every_adversarial_scene_is_safe_with_the_monitor() {
    for name in ADVERSARIAL {
        let (scene, r) = run(name);
        assert!(scene.safety.on(), "{name}: shipped with the monitor on");
        safe(name, &scene, &r);
        assert!(!matches!(r.status, Status::Collision(_)), "{name}: {:?}", r.status);
    }
}

/// The `--mcu` engine is the board's step (its number type `avoidance::BoardReal`, the lookup-table
/// Gaussian, the weights sent as serial frames, the weights-age watchdog): every shipped scene run
/// through it must be as safe as the reference, and end the same way (a number type that turned a
/// `stopped` into a `reached`, or the reverse, is a difference the host has to show, not hide).
#[test]
fn every_scene_is_safe_on_the_board_engine() {
    let names = flinch_tests::avoid::scene_names();
    assert!(names.len() >= 10, "{names:?}");
    for name in &names {
        let mut scene = Avoid::load(&scene_path(name)).unwrap_or_else(|e| panic!("{e}"));
        flinch_harness::pfl::resolve_pfl(&mut scene).unwrap();
        let setup = Setup::new(&scene, None).unwrap();
        let m = simulate(&scene, &setup, Engine::Mcu).unwrap();
        safe(name, &scene, &m);
        let rx = m.rx.expect("the board engine has a receiver");
        // A scene with no room at the start ends before the first frame; any run that moved took
        // its weights from frames, none refused on a clean line.
        if m.path_length_m > 0.0 {
            assert!(rx.good > 0, "{name}: moved without a frame applied");
        }
        assert_eq!((rx.bad_crc, rx.bad_header, rx.short, rx.stale), (0, 0, 0, 0), "{name}: frames refused on a clean line");
        let r = simulate(&scene, &setup, Engine::Reference).unwrap();
        assert_eq!(m.status, r.status, "{name}: board engine ({}) against the f64 reference", flinch_harness::avoid::path::board_real_name());
    }
}

/// An empty workspace is flat once the raised plane's own weights are removed before eq 71: a
/// diagonal move from 50 mm off one corner to 50 mm off the other arrives, at the cap speed. As the
/// thesis wrote it (`--thesis`), the border walls stop it short.
#[test]
fn empty_workspace_reaches_the_goal_near_the_borders() {
    let (scene, r) = run("avoid_empty_diagonal.toml");
    safe("avoid_empty_diagonal.toml", &scene, &r);
    assert_eq!(r.status, Status::Reached);
    let straight = 0.95 * 2f64.sqrt();
    assert!(r.path_length_m < straight * 1.02, "{} m", r.path_length_m);
    let (_, t) = thesis("avoid_empty_diagonal.toml");
    assert_ne!(t.status, Status::Reached, "the thesis's phantom walls: {:?}", t.status);
}

/// A hand beside the tool from the first frame (40 mm from its centre): the model-based robot
/// removal keeps it, the monitor never moves; the thesis's masks erase it and the tool runs into it.
#[test]
fn hand_beside_the_tool_is_not_erased() {
    let (scene, r) = run("avoid_hand_at_tool.toml");
    safe("avoid_hand_at_tool.toml", &scene, &r);
    assert!(r.max_speed_mps < 1e-9, "{}", r.max_speed_mps);
    let (_, t) = thesis("avoid_hand_at_tool.toml");
    // With the drive's reaction and braking (issue 29 item 7) the thesis's tool, turned late,
    // may pass the erased hand without touching it; it is never judged safe.
    eprintln!("thesis, hand at the tool: {:?}, min {:.4} m, {} steps over the SSM bound", t.status, t.min_signed_distance_m, t.ssm_violations);
    assert!(matches!(t.status, Status::Collision(_) | Status::SsmViolation(_)), "{:?}", t.status);
}

/// A hand and forearm lying flat (20 mm high) reach across the path. With the sense height below a
/// finger's thickness (14 mm, ISO 13855's d) the monitor sees them and the tool never enters. With the
/// old 30 mm nothing of this operator is above the sense height: the intrusion distance ISO 13855 then
/// asks for (128 mm, applied automatically) assumes some thicker part of the body is seen, and it is
/// not here, so the tool goes in: the test can tell the two apart, and the docs state the assumption.
#[test]
fn a_low_hand_is_seen() {
    let (scene, r) = run("avoid_low_hand.toml");
    assert!(scene.safety.sense_height_m < scene.operator.hand_height_m, "the scene is the adversarial one");
    safe("avoid_low_hand.toml", &scene, &r);
    assert!(!matches!(r.status, Status::Collision(_)), "{:?}", r.status);
    let mut blind = scene.clone();
    blind.safety.sense_height_m = 0.03;
    assert!((blind.safety.intrusion_used_m(blind.camera.m_per_px) - 0.128).abs() < 1e-9, "C = 8 (30 - 14) mm");
    let (_, b) = run_scene(blind);
    assert!(matches!(b.status, Status::Collision(_)), "30 mm sense height: {:?}, {} m", b.status, b.min_signed_distance_m);
}

/// The intrusion distance follows the detection capability (ISO 13855): 0 up to a finger (14 mm),
/// 8 (d - 14 mm) up to 40 mm, 850 mm beyond; a configured larger `intrusion_m` is kept; the pixel
/// pitch counts as well as the height.
#[test]
fn intrusion_distance_follows_the_detection_capability() {
    let mut scene = Avoid::load(&scene_path("avoid_low_hand.toml")).unwrap();
    let f = |s: &Avoid| s.safety.intrusion_used_m(s.camera.m_per_px);
    scene.camera.m_per_px = 0.005;
    for (h, c) in [(0.010, 0.0), (0.014, 0.0), (0.02, 0.048), (0.04, 0.208), (0.041, 0.85)] {
        scene.safety.sense_height_m = h;
        assert!((f(&scene) - c).abs() < 1e-9, "sense {h}: {} != {c}", f(&scene));
    }
    scene.safety.sense_height_m = 0.014;
    scene.safety.intrusion_m = 0.3;
    assert_eq!(f(&scene), 0.3);
    scene.safety.intrusion_m = 0.0;
    scene.camera.m_per_px = 0.02;
    assert!((f(&scene) - 8.0 * (20.0 * 2f64.sqrt() - 14.0) * 1e-3).abs() < 1e-9, "28 mm pixels miss a finger");
}

/// The signed distance is from the tool's surface (the 45 mm wrist), and a run that reaches the goal
/// closer than `clearance_m` is `too_close`, not `reached` (exit 1). The thesis's law on the empty
/// diagonal with a hand placed 60 mm beside the straight line: the tool point misses it, the wrist
/// does not keep 20 mm. With the monitor, the clearance is part of the protective separation.
#[test]
fn clearance_is_from_the_surface_and_enforced() {
    let mut s = Avoid::load(&scene_path("avoid_empty_diagonal.toml")).unwrap();
    s.operator.entry_m = [1.05, 0.0];
    // Its edge 60 mm from the line y = x.
    let a = (0.06 + 0.05) / 2f64.sqrt();
    s.operator.keyframes[0].hand_m = [0.55 + a, 0.55 - a];
    // A hand beside the line of motion, low enough to barely shape the field.
    s.operator.hand_height_m = 0.05;
    s.operator.forearm_height_m = 0.05;
    let mut t = s.clone();
    t.thesis_mode();
    t.k_rep = 0.0;
    let (t, r) = run_scene(t);
    honest("thesis, hand beside the line", &t, &r);
    let centre = r.min_signed_distance_m + t.robot.wrist_radius_m;
    assert!(centre > t.clearance_m, "the tool point keeps {centre} m");
    assert!(r.min_signed_distance_m < t.clearance_m, "the surface does not: {}", r.min_signed_distance_m);
    if r.min_signed_distance_m >= 0.0 {
        // Too close, and (the thesis's law has no monitor) faster than SSM allows there: the
        // speed verdict takes precedence in `status`, `clearance_kept` says the rest.
        let json = avoid::metrics_json(&r, Engine::Reference, false);
        let expect = if r.ssm_violations > 0 { "ssm_violation" } else { "too_close" };
        assert_eq!((json["status"].as_str(), json["clearance_kept"].as_bool(), Some(json["status"] == "reached")), (Some(expect), Some(false), Some(false)));
        assert!(matches!(r.status, Status::TooClose | Status::SsmViolation(None)), "{:?}", r.status);
    } else {
        assert!(matches!(r.status, Status::Collision(_)));
    }
    // The monitor with a large clearance asked: whatever it does, it never comes closer.
    for c in [0.05, 0.15] {
        let mut m = s.clone();
        m.clearance_m = c;
        let (m, r) = run_scene(m);
        safe(&format!("clearance {c}"), &m, &r);
        assert!(r.min_signed_distance_m >= c, "clearance {c}: {}", r.min_signed_distance_m);
    }
}

/// The shipped demo needs avoidance and uses it: the hand rests on the straight line. As the thesis
/// wrote it with the field off (k_rep = 0) the tool runs into it; ours goes round beyond the
/// protective separation and reaches the goal keeping its clearance (and well beyond: the steering
/// barrier holds the tool where the monitor allows the cruise speed, about 0.45 m from the surface).
#[test]
fn the_demo_needs_avoidance_and_goes_round() {
    let (scene, r) = run("avoid_operator_hand.toml");
    safe("avoid_operator_hand.toml", &scene, &r);
    assert_eq!(r.status, Status::Reached, "{} m", r.min_signed_distance_m);
    let off_line = r.points.iter().map(|p| (p[1] - scene.start_m[1]).abs()).fold(0.0, f64::max);
    assert!(off_line > 0.4, "went round: {off_line} m off the line");
    assert!(r.min_signed_distance_m > 0.3, "{}", r.min_signed_distance_m);
    let mut off = scene.clone();
    off.k_rep = 0.0;
    off.thesis_mode();
    let (_, t) = run_scene(off);
    assert!(matches!(t.status, Status::Collision(_)) && t.min_signed_distance_m < -0.05, "{:?} {}", t.status, t.min_signed_distance_m);
}

/// Where there is room (a 2.1 m workspace): a hand head-on (a symmetric hill: Fig. 87's trap), a
/// hand beside the path and a hand that moves onto the path. Ours reaches the goal every time,
/// keeping the clearance asked (and the barrier's ~0.55 m), at the cruise speed (the barrier holds
/// the tool where the monitor allows it), never within 0.1 m of the operator; the SSM bound from the
/// true separation holds at every step (`safe`). Without the steering barrier (the monitor alone,
/// field as the thesis wrote it) the same scenes stop, or go through with the thesis's law alone.
#[test]
fn scenes_with_room_are_passed_at_speed() {
    for name in ["avoid_head_on_wide.toml", "avoid_hand_side_wide.toml", "avoid_moving_hand_wide.toml", "avoid_operator_hand.toml"] {
        let (scene, r) = run(name);
        safe(name, &scene, &r);
        assert_eq!(r.status, Status::Reached, "{name}: {:?}", r.status);
        assert!(r.min_signed_distance_m >= scene.clearance_m.max(0.4), "{name}: {} m", r.min_signed_distance_m);
        assert!(r.max_speed_mps >= 0.9 * scene.speed_mps, "{name}: {} m/s", r.max_speed_mps);
        assert_eq!(r.max_speed_near_operator_mps, 0.0, "{name}");
        // Cruise speed most of the way: at most twice the straight line's time.
        let straight = ((scene.goal_m[0] - scene.start_m[0]).powi(2) + (scene.goal_m[1] - scene.start_m[1]).powi(2)).sqrt();
        assert!(r.time_to_goal_s.unwrap() < 2.0 * straight / scene.speed_mps, "{name}: {:?} s", r.time_to_goal_s);
    }
    // The head-on hand without the barrier (the thesis's field and law): it does not keep the
    // clearance.
    let (scene, t) = thesis("avoid_head_on_wide.toml");
    honest("avoid_head_on_wide.toml", &scene, &t);
    assert_ne!(t.status, Status::Reached, "{:?} {}", t.status, t.min_signed_distance_m);
}

/// In the thesis's 1.05 m workspace the protective separation leaves no way round: every scene
/// with the operator near the path stops (the status says why) and none is reported reached.
#[test]
fn no_room_in_the_thesis_workspace_is_an_honest_stop() {
    for name in ["avoid_head_on.toml", "avoid_thesis_reach.toml", "avoid_forearm_across.toml", "avoid_goal_covered.toml", "avoid_u_trap.toml", "avoid_box_wall.toml", "avoid_wall.toml"] {
        let (scene, r) = run(name);
        safe(name, &scene, &r);
        assert!(matches!(r.status, Status::Stopped(_)), "{name}: {:?}", r.status);
        assert_eq!(r.max_speed_near_operator_mps, 0.0, "{name}");
    }
}

/// The thesis's law on every scene: whatever it does, the report is honest.
#[test]
fn every_adversarial_scene_is_reported_honestly_without_the_monitor() {
    for name in ADVERSARIAL {
        let (scene, r) = thesis(name);
        honest(name, &scene, &r);
    }
}

/// Static obstacles (boxes and discs) are sensed, fitted and judged like the operator: the U-shaped
/// trap and the box wall with no way round end stopped and never inside with the monitor; the
/// thesis's law goes through; a bad obstacle is refused with its key.
#[test]
fn obstacles_trap_and_wall() {
    for name in ["avoid_u_trap.toml", "avoid_box_wall.toml"] {
        let (scene, r) = run(name);
        assert!(!scene.operator.obstacles.is_empty());
        safe(name, &scene, &r);
        assert!(matches!(r.status, Status::Stopped(_)), "{name}: {:?}", r.status);
        let (ts, t) = thesis(name);
        honest(name, &ts, &t);
        eprintln!("{name}: thesis {:?}, min {:.4} m, {} steps over the SSM bound", t.status, t.min_signed_distance_m, t.ssm_violations);
        // The box wall: with the drive's reaction and braking the thesis's tool may be turned out
        // of the view instead of through the wall; never judged safe.
        assert!(matches!(t.status, Status::Collision(_) | Status::SsmViolation(_)), "{name}: thesis {:?}", t.status);
        // The signed distance includes the obstacles: inside a box is negative.
        let o = &scene.operator.obstacles[0];
        assert!(scene.operator_shape().signed_distance(scene.hand_at(0.0), o.center_m) < 0.0);
    }
    let text = std::fs::read_to_string(scene_path("avoid_u_trap.toml")).unwrap();
    let e = Avoid::parse(&text.replacen("kind = \"box\"", "kind = \"cone\"", 1)).unwrap_err();
    assert!(e.contains("avoid.operator.obstacles[0].kind: must be one of \"disc\" | \"box\", got \"cone\""), "{e}");
    let e = Avoid::parse(&text.replacen("size_m = [0.05, 0.45]", "size_m = [0.05, -1]", 1)).unwrap_err();
    assert!(e.contains("avoid.operator.obstacles[0].size_m: y: allowed range (0, 10] m") && e.ends_with("got -1"), "{e}");
    let e = Avoid::parse(&text.replacen("height_m = 0.20", "height_m = 0.20\nradius = 1", 1)).unwrap_err();
    assert!(e.contains("radius"), "{e}");
}
