//! Collision avoidance on the adversarial scenes of issue 9 (`scenes/avoid_*.toml`): whatever the
//! law does, the outcome is reported honestly from the true geometry. A run that put the tool inside
//! the operator is never "reached", its signed distance is negative (not clamped at 0), and
//! `flinch avoid` exits 1 (unsafe); a safe stop before the goal exits 4.
use flinch_harness::avoid::path::{simulate, Engine, PathResult, Reason, Setup, Status, Verdict};
use flinch_harness::avoid::scene::Avoid;
use flinch_harness::avoid::{self, AvoidArgs};
use flinch_tests::scene_path;

fn run(name: &str) -> (Avoid, PathResult) {
    let scene = Avoid::load(&scene_path(name)).unwrap_or_else(|e| panic!("{e}"));
    run_scene(scene)
}

fn thesis(name: &str) -> (Avoid, PathResult) {
    let mut scene = Avoid::load(&scene_path(name)).unwrap_or_else(|e| panic!("{e}"));
    scene.thesis_mode();
    run_scene(scene)
}

fn run_scene(scene: Avoid) -> (Avoid, PathResult) {
    flinch_tests::avoid::run_reference(scene)
}

/// What every run must satisfy, whatever the scene.
fn honest(name: &str, scene: &Avoid, r: &PathResult) {
    // The minimum is over the swept segments, never above the step ends' minimum.
    let min = r.signed_distance_m.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(r.min_signed_distance_m <= min, "{name}: swept min {} above the step ends' {min}", r.min_signed_distance_m);
    let swept = r.rows.iter().map(|w| w.swept_separation_m).fold(r.signed_distance_m[0], f64::min);
    assert_eq!(swept, r.min_signed_distance_m, "{name}: min over the swept steps");
    for (k, w) in r.rows.iter().enumerate() {
        assert!(w.swept_separation_m <= r.signed_distance_m[k].min(r.signed_distance_m[k + 1]), "{name}: step {k}: swept above an end");
        // Conservative: never above any sample of the segment.
        let mut sampled = f64::INFINITY;
        for i in 0..=20 {
            let a = i as f64 / 20.0;
            let (p0, p1) = (r.points[k], r.points[k + 1]);
            let t = (k as f64 + a) * scene.dt_s;
            sampled = sampled.min(scene.signed_distance_m(t, [p0[0] + a * (p1[0] - p0[0]), p0[1] + a * (p1[1] - p0[1])]));
        }
        assert!(w.swept_separation_m <= sampled + 1e-12, "{name}: step {k}: swept {} above a sample {sampled}", w.swept_separation_m);
        // The 21 samples are within L / 40 of the segment's minimum (L: the step's Lipschitz term),
        // the swept bound within its resolution below it.
        let slack = flinch_harness::avoid::path::SWEPT_TOL_M + step_motion(scene, r, k) / 40.0 + 1e-12;
        assert!(w.swept_separation_m >= sampled - slack, "{name}: step {k}: swept {} far below {sampled}", w.swept_separation_m);
    }
    // Recomputed here from the true geometry at every step, not from the sensed image: from the
    // tool's surface (the wrist disc), not its centre.
    for (k, (p, s)) in r.points.iter().zip(&r.signed_distance_m).enumerate() {
        let t = k as f64 * scene.dt_s;
        // The obstacles where they stand at t (a moving one on its key frames).
        let surface = scene.operator_shape_at(t).signed_distance(scene.hand_at(t), *p) - scene.robot.wrist_radius_m;
        assert!((surface - s).abs() < 1e-9, "{name}: step {k}");
    }
    assert_eq!(r.clearance_m, scene.clearance_m);
    let inside_steps = r.rows.iter().filter(|w| w.swept_separation_m < 0.0).count();
    assert!((r.time_inside_s - inside_steps as f64 * scene.dt_s).abs() < 1e-9, "{name}: time inside");
    // The SSM verdict, recomputed here from the true geometry with the ISO/TS 15066 formula.
    let mut violations = 0;
    for (k, row) in r.rows.iter().enumerate() {
        let v_obs = flinch_harness::avoid::path::obstacle_speed_mps(scene, row.t_s - scene.dt_s, row.t_s);
        let bound = ssm_bound_at(scene, r.signed_distance_m[k], v_obs);
        assert!((row.ssm_bound_mps - bound).abs() < 1e-9, "{name}: step {k}: bound {} != {bound}", row.ssm_bound_mps);
        if row.v_mps[0].hypot(row.v_mps[1]) > bound + 1e-6 {
            violations += 1;
        }
    }
    assert_eq!(violations, r.ssm_violations, "{name}: SSM violations");
    assert_eq!(r.ssm_violations > 0, r.max_speed_over_ssm_mps > 0.0, "{name}");
    assert_eq!(r.ssm_violations > 0, r.first_ssm_violation_s.is_some(), "{name}");
    match r.status {
        Status::Reached | Status::TooClose => {
            if r.status == Status::Reached {
                assert!(r.min_signed_distance_m >= scene.clearance_m, "{name}: reached but came within {} m (clearance {} m)", r.min_signed_distance_m, scene.clearance_m);
            } else {
                assert!((0.0..scene.clearance_m).contains(&r.min_signed_distance_m), "{name}: too close is within the clearance, not inside");
            }
            let last = r.points.last().unwrap();
            let d = ((last[0] - scene.goal_m[0]).powi(2) + (last[1] - scene.goal_m[1]).powi(2)).sqrt();
            assert!(d <= scene.goal_tolerance_m, "{name}: reached but {d} m from the goal");
        }
        Status::Stopped(_) => assert!(r.min_signed_distance_m >= 0.0, "{name}: stopped is only for runs never inside"),
        Status::Collision(_) => {
            assert!(r.min_signed_distance_m < 0.0 && r.time_inside_s > 0.0, "{name}: collision needs a penetration");
        }
        Status::SsmViolation(_) => assert!(r.min_signed_distance_m >= 0.0 && r.ssm_violations > 0, "{name}: ssm_violation is for runs never inside"),
        // No synthetic run is unverified (only recorded frames are), and no shipped law gives a
        // non-finite command.
        Status::Fault | Status::Unverified(_) => panic!("{name}: {:?}", r.status),
    }
    assert_eq!(r.verdict_basis, flinch_harness::avoid::path::VerdictBasis::SceneModel, "{name}");
    if r.min_signed_distance_m < 0.0 {
        assert!(matches!(r.status, Status::Collision(_)), "{name}: inside but {:?}", r.status);
    } else if r.ssm_violations > 0 {
        assert!(matches!(r.status, Status::SsmViolation(_)), "{name}: over the SSM bound but {:?}", r.status);
    }
    assert_eq!(r.status.ok(), r.status == Status::Reached);
    // The speeds are those of the rows.
    let vmax = r.rows.iter().map(|w| w.v_mps[0].hypot(w.v_mps[1])).fold(0.0, f64::max);
    assert!((vmax - r.max_speed_mps).abs() < 1e-12, "{name}");
}

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
        assert_eq!(json["reached_goal"], false, "{name}: never reached after a crossing");
    }
}

const ADVERSARIAL: [&str; 19] = [
    "avoid_operator_hand.toml",
    "avoid_head_on_wide.toml",
    "avoid_hand_side_wide.toml",
    "avoid_moving_hand_wide.toml",
    "avoid_thesis_reach.toml",
    "avoid_hand_at_tool.toml",
    "avoid_head_on.toml",
    "avoid_forearm_across.toml",
    "avoid_forearm_across_30.toml",
    "avoid_goal_covered.toml",
    "avoid_wall.toml",
    "avoid_under_tool.toml",
    "avoid_low_hand.toml",
    "avoid_fast_hand.toml",
    "avoid_empty_diagonal.toml",
    "avoid_extreme_gain.toml",
    "avoid_u_trap.toml",
    "avoid_box_wall.toml",
    "avoid_moving_disc_wide.toml",
];

/// How far the tool and the fastest obstacle move over step `k`, m (the swept check's Lipschitz
/// term).
fn step_motion(scene: &Avoid, r: &PathResult, k: usize) -> f64 {
    let (p0, p1) = (r.points[k], r.points[k + 1]);
    (p1[0] - p0[0]).hypot(p1[1] - p0[1]) + flinch_harness::avoid::path::max_obstacle_speed_mps(scene) * scene.dt_s
}

/// The speed limit of ISO/TS 15066 5.5.4 at a true separation `s` (the bound the monitor must stay
/// under, whatever it sensed), m/s.
/// With the obstacles truly moving at `v_obs` (m/s): `v_h` is the faster of the scene's and that.
fn ssm_bound_at(scene: &Avoid, s: f64, v_obs: f64) -> f64 {
    let f = &scene.safety;
    let v_h = f.human_speed_mps.max(v_obs);
    let t = f.reaction_time_s + f.stopping_time_s;
    let margin = f.intrusion_used_m(scene.camera.m_per_px) + f.sensor_uncertainty_m + f.robot_uncertainty_m + scene.clearance_m;
    // ISO 13855:2010 6.2, formula (1): K = 2.0 m/s (v_h if faster) where the resulting separation
    // is at most 0.5 m; else K = v_h and the separation at least 0.5 m.
    let near = v_h.max(2.0) * t + margin;
    let stop = if near <= 0.5 { near } else { (v_h * t + margin).max(0.5) };
    ((s - stop) / (f.reaction_time_s + f.stopping_time_s / 2.0)).clamp(0.0, scene.speed_mps)
}

/// With the monitor on (as shipped): never inside the operator, never above the cap, and at every
/// step the commanded speed is within the SSM bound computed from the TRUE separation at the start
/// of the step (a sensing chain that misses the operator, a blind zone, would break this).
fn safe(name: &str, scene: &Avoid, r: &PathResult) {
    honest(name, scene, r);
    // The tool never moves in contact: a person may walk into a tool held in a protective stop
    // (ISO/TS 15066 5.5.4 allows contact with a stopped robot), which is still reported as a
    // collision, but no step ever commands motion while touching or into the operator.
    for (k, row) in r.rows.iter().enumerate() {
        if row.separation_m < 0.0 || r.signed_distance_m[k] < 0.0 || row.swept_separation_m < 0.0 {
            assert!(row.v_mps[0].hypot(row.v_mps[1]) == 0.0, "{name}: t = {} s: moving in contact", row.t_s);
        }
    }
    if !matches!(r.status, Status::Collision(_)) {
        assert!(r.min_signed_distance_m > 0.0, "{name}: {} m", r.min_signed_distance_m);
    }
    assert_ne!(r.status, Status::TooClose, "{name}: {} m, clearance {} m", r.min_signed_distance_m, scene.clearance_m);
    if r.status == Status::Reached {
        assert!(r.min_signed_distance_m >= scene.clearance_m, "{name}: {} m < clearance {} m", r.min_signed_distance_m, scene.clearance_m);
    }
    assert!(r.max_speed_mps <= scene.speed_mps + 1e-9, "{name}: {} m/s", r.max_speed_mps);
    assert_eq!(r.ssm_violations, 0, "{name}: {} steps over the SSM bound, by up to {} m/s", r.ssm_violations, r.max_speed_over_ssm_mps);
    for (k, row) in r.rows.iter().enumerate() {
        let s_true = r.signed_distance_m[k];
        let v = row.v_mps[0].hypot(row.v_mps[1]);
        let b = ssm_bound_at(scene, s_true, flinch_harness::avoid::path::obstacle_speed_mps(scene, row.t_s - scene.dt_s, row.t_s));
        assert!(v <= b + 1e-6, "{name}: t = {} s: {v} m/s at {s_true} m (bound {b})", row.t_s);
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
        let scene = Avoid::load(&scene_path(name)).unwrap_or_else(|e| panic!("{e}"));
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
    assert!(matches!(t.status, Status::Collision(_)), "{:?}", t.status);
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
        assert_eq!((json["status"].as_str(), json["clearance_kept"].as_bool(), json["reached_goal"].as_bool()), (Some(expect), Some(false), Some(false)));
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

/// Randomised variants of the shipped scene (seeded, reproducible): the hand reaches from a random
/// point of the near edge to a random point, at up to 1.6 m/s; with the monitor on, zero
/// penetrations and the SSM bound holds at every step.
#[test]
fn random_variants_never_penetrate() {
    let base = Avoid::load(&scene_path("avoid_under_tool.toml")).unwrap();
    let setup = Setup::new(&base, None).unwrap();
    let mut seed: u64 = 0x5EED_F11C;
    let mut next = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    for k in 0..12 {
        let mut s = base.clone();
        let ex = 0.1 + 0.85 * next();
        s.operator.entry_m = [ex, 0.0];
        let (hx, hy) = (0.1 + 0.85 * next(), 0.2 + 0.75 * next());
        let t0 = 2.0 * next();
        let dist = ((hx - ex).powi(2) + (hy - 0.05).powi(2)).sqrt();
        let speed = 0.2 + 1.4 * next();
        s.operator.keyframes[0].t_s = t0;
        s.operator.keyframes[0].hand_m = [ex, 0.05];
        s.operator.keyframes[1].t_s = t0 + dist / speed;
        s.operator.keyframes[1].hand_m = [hx, hy];
        s.camera.seed = k;
        s.max_time_s = 6.0;
        let r = simulate(&s, &setup, Engine::Reference).unwrap();
        safe(&format!("variant {k} (hand to [{hx:.2}, {hy:.2}] at {speed:.2} m/s from t = {t0:.2} s)"), &s, &r);
    }
}

/// `flinch avoid` exits 1 on a collision, 4 on a safe stop before the goal (the wall with the
/// monitor: it was exit 1, the same as the collision) and 0 on the empty diagonal, and the CSV has
/// the documented columns, one row per step.
#[test]
fn cli_verdict_and_csv() {
    let csv = std::env::temp_dir().join(format!("flinch-avoid-{}.csv", std::process::id()));
    let args = |name: &str, csv: Option<std::path::PathBuf>, thesis: bool| AvoidArgs { csv, thesis, ..flinch_tests::avoid::args(scene_path(name)) };
    assert_eq!(avoid::run(&args("avoid_wall.toml", Some(csv.clone()), true)), Ok(Verdict::Unsafe), "a collision: exit 1");
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t_s,x_m,y_m,vx_mps,vy_mps,separation_m,speed_limit_mps,state,swept_separation_m,ssm_bound_mps"));
    assert_eq!(avoid::CSV_HEADER.split(',').count(), 10);
    let rows: Vec<Vec<f64>> = lines.map(|l| l.split(',').enumerate().filter(|(k, _)| *k != 7).map(|(_, v)| v.parse().unwrap()).collect()).collect();
    assert!(rows.iter().any(|r| r[5] < 0.0), "the crossing shows in the CSV's separation");
    assert!(rows.iter().all(|r| r[7] <= r[5]), "swept separation never above the step's end");
    assert!(rows.iter().any(|r| r[3].hypot(r[4]) > r[8] + 1e-6), "the thesis's law exceeds the SSM bound: the CSV shows where");
    std::fs::remove_file(&csv).ok();
    // With the monitor the wall is a safe stop: exit 4, told apart from the unsafe exit 1.
    let stop = avoid::run(&args("avoid_wall.toml", None, false));
    assert_eq!(stop, Ok(Verdict::SafeStop));
    assert_eq!(stop.map(|v| v.code()), Ok(4));
    let mut empty = args("avoid_empty_diagonal.toml", None, false);
    empty.json = false;
    assert_eq!(avoid::run(&empty).map(|v| v.code()), Ok(0));
}

/// One row of the docs' table: `| scene | law | status | reason | min_signed_distance_m |
/// max_speed_near_operator_mps | time_to_goal_s | ssm_violations | max_speed_over_ssm_mps |`.
fn table_row(name: &str, law: &str, r: &PathResult) -> String {
    format!(
        "| `{name}` | {law} | {} | {} | {:.4} | {:.3} | {} | {} | {:.3} |",
        r.status.name(),
        r.status.reason().map_or("-", |x| x.name()),
        r.min_signed_distance_m,
        r.max_speed_near_operator_mps,
        r.time_to_goal_s.map_or("-".to_string(), |t| format!("{t:.2}")),
        r.ssm_violations,
        r.max_speed_over_ssm_mps
    )
}

/// docs/avoidance.md's per-scene table (every `scenes/avoid_*.toml`, the thesis's law against ours)
/// is what the scenes give now: it cannot drift. `FLINCH_BLESS=1` rewrites it (then review the
/// diff). Every row of ours is also checked safe, every row of the thesis's honest.
#[test]
fn docs_table_is_current() {
    let names = flinch_tests::avoid::scene_names();
    let mut rows = vec![
        "| scene | law | status | reason | min_signed_distance_m | max_speed_near_operator_mps | time_to_goal_s | ssm_violations | max_speed_over_ssm_mps |".to_string(),
        "|---|---|---|---|---|---|---|---|---|".to_string(),
    ];
    for name in &names {
        let (ts, t) = thesis(name);
        honest(name, &ts, &t);
        let (os, o) = run(name);
        safe(name, &os, &o);
        rows.push(table_row(name, "thesis (`--thesis`)", &t));
        rows.push(table_row(name, "ours", &o));
    }
    let table = rows.join("\n");
    let doc_path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../docs/avoidance.md");
    let doc = std::fs::read_to_string(&doc_path).unwrap();
    let (begin, end) = ("<!-- avoid-table:begin -->\n", "\n<!-- avoid-table:end -->");
    let (a, b) = (doc.find(begin).expect("begin marker") + begin.len(), doc.find(end).expect("end marker"));
    if std::env::var_os("FLINCH_BLESS").is_some() {
        std::fs::write(&doc_path, format!("{}{table}{}", &doc[..a], &doc[b..])).unwrap();
    } else {
        assert_eq!(&doc[a..b], table, "docs/avoidance.md's table is out of date: FLINCH_BLESS=1 cargo test -p flinch-tests --test avoid_adversarial docs_table_is_current");
    }
}

/// The serial line: frames measured as the host encodes them (15 x 15: 932 bytes, 30 x 30: 3,632),
/// the baud each grid needs at 30 frames a second (8N1), a line too slow refused with the key and the
/// rate it needs, and a modelled line delays every frame by its transmission time.
#[test]
fn the_serial_line_takes_its_time() {
    use flinch_harness::avoid::path::{fit_frame, link_time, min_baud};
    let mut s = Avoid::load(&scene_path("avoid_forearm_across_30.toml")).unwrap();
    for (grid, bytes, baud) in [(15, 932, 282_425), (30, 3_632, 1_100_607)] {
        s.fit.grid = grid;
        s.baud = None;
        let setup = Setup::new(&s, None).unwrap();
        let mut rng = flinch_harness::avoid::depth::Rng::new(1);
        let frame = fit_frame(&s, &setup, s.start_m, s.hand_at(0.0), &mut rng).to_frame(0, 0).unwrap();
        assert_eq!(frame.len(), bytes, "grid {grid}");
        assert_eq!(link_time(grid, grid, 1_000_000).unwrap().0, bytes);
        assert_eq!(min_baud(bytes, s.frame_period_s), baud, "grid {grid}");
        s.baud = Some(115_200);
        let e = Setup::new(&s, None).err().unwrap();
        assert!(e.contains("avoid.baud = 115200") && e.contains(&format!("at least {baud} baud")), "{e}");
    }
    // 30 x 30 at 1.5 Mbaud: 24.2 ms on the line; the frame reaches the controller that much later.
    let s = Avoid::load(&scene_path("avoid_forearm_across_30.toml")).unwrap();
    assert!((link_time(30, 30, 1_500_000).unwrap().1 - 0.024213).abs() < 1e-5);
    let (scene, slow) = run_scene(s.clone());
    safe("30 x 30 at 1.5 Mbaud", &scene, &slow);
    let first_move = |r: &PathResult| r.rows.iter().find(|w| w.v_mps[0].hypot(w.v_mps[1]) > 0.0).map(|w| w.t_s);
    // Where the tool can move at once (the empty workspace), with and without the line.
    let mut s = Avoid::load(&scene_path("avoid_empty_diagonal.toml")).unwrap();
    s.fit.grid = 30;
    s.baud = Some(1_500_000);
    let (_, slow) = run_scene(s.clone());
    let mut fast = s;
    fast.baud = None;
    let (_, fast) = run_scene(fast);
    let (a, b) = (first_move(&slow).unwrap(), first_move(&fast).unwrap());
    assert!(a >= b + 0.015, "the first frame arrives 24 ms later (10 ms steps): moves at {a} s against {b} s");
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
        assert!(matches!(t.status, Status::Collision(_)), "{name}: thesis {:?}", t.status);
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

/// Item 1 of the follow-up to issue 9: the run's own verdict checks the commanded speed against the
/// SSM bound at the TRUE separation. Adversarial case: a hand faster than the `K` the monitor
/// assumes (3.2 m/s against ISO 13855's 2.0 m/s within 0.5 m), so the separation the monitor
/// believes (sensed, less `K` times the frame's age) is optimistic. The tool is moving when the
/// hand lands near it: the run is `ssm_violation` (or `collision`), never `reached` or a clean
/// stop, and `flinch avoid` exits 1. With the hand at 2.0 m/s no step violates.
///
/// The scene: `avoid_moving_hand_wide` with the hand waiting at the near edge until t = 3 s, then
/// reaching the path (0.95 m) at 3.2 m/s. (This test used `avoid_fast_hand` until the monitor took
/// ISO 13855's 2.0 m/s within 0.5 m: its larger separation holds the tool out of that hand's
/// reach, so that scene no longer exercises the verdict.)
#[test]
fn ssm_verdict_uses_the_true_separation() {
    let hand_at = |v: f64| {
        let mut s = Avoid::load(&scene_path("avoid_moving_hand_wide.toml")).unwrap();
        s.max_time_s = 8.0;
        let k = s.operator.keyframes.clone();
        let mut wait = k[0].clone();
        wait.t_s = 3.0;
        let mut arrive = k[1].clone();
        arrive.t_s = 3.0 + (k[1].hand_m[1] - k[0].hand_m[1]) / v;
        s.operator.keyframes = vec![k[0].clone(), wait, arrive];
        s
    };
    let s = hand_at(3.2);
    let (scene, r) = run_scene(s.clone());
    honest("hand at 3.2 m/s", &scene, &r);
    println!("hand at 3.2 m/s: {:?}, {} steps over the bound by up to {:.3} m/s, closest {:.3} m", r.status, r.ssm_violations, r.max_speed_over_ssm_mps, r.min_signed_distance_m);
    assert!(r.ssm_violations > 0, "the true separation fell below S_p while the tool moved: {:?}, {} m", r.status, r.min_signed_distance_m);
    assert!(r.max_speed_over_ssm_mps > 0.0);
    // Never inside: without the verdict this run would read "stopped, blocked", a clean stop
    // (measured: 8 steps over the bound by up to 0.250 m/s, the surface 0.251 m from the hand at
    // the closest).
    assert!(matches!(r.status, Status::SsmViolation(Some(_))), "{:?}", r.status);
    assert!(r.min_signed_distance_m > 0.0, "{}", r.min_signed_distance_m);
    let json = avoid::metrics_json(&r, Engine::Reference, true);
    assert_eq!(json["ssm_violations"].as_u64(), Some(r.ssm_violations as u64));
    assert!(json["max_speed_over_ssm_mps"].as_f64().unwrap() > 0.0);
    assert_eq!(json["reached_goal"], false);
    let args = flinch_tests::avoid::args(scene_path("avoid_moving_hand_wide.toml"));
    assert_eq!(avoid::run_scene(&args, s).map(|v| v.code()), Ok(1), "exit 1");
    // At ISO 13855's 2.0 m/s: within the bound at every step.
    let (scene, r) = run_scene(hand_at(2.0));
    safe("hand at 2.0 m/s", &scene, &r);
    assert_eq!(r.status, Status::Stopped(Reason::Blocked));
    // As shipped (`avoid_fast_hand`, 1.6 m/s): within the bound at every step.
    let (scene, r) = run("avoid_fast_hand.toml");
    safe("avoid_fast_hand.toml", &scene, &r);
}

/// Item 2: the distance is checked over each step's segment, not only at its ends. Adversarial
/// case: a thin wall (a 4 mm box) across the straight line, the tool at 3 m/s with 50 ms steps
/// (150 mm a step, more than the 90 mm wrist plus the wall) and the field and monitor off, placed so
/// that two step ends straddle it: every end is clear of it, the tool went through, and the run is
/// a collision (exit 1).
#[test]
fn a_thin_wall_between_two_steps_is_a_collision() {
    let mut s = Avoid::load(&scene_path("avoid_box_wall.toml")).unwrap();
    s.thesis_mode();
    s.k_rep = 0.0;
    s.speed_mps = 3.0;
    s.dt_s = 0.05;
    s.latency_s = 0.0;
    s.start_m = [0.12, 0.5];
    s.goal_m = [0.93, 0.5];
    let o = &mut s.operator.obstacles[0];
    o.size_m = [0.004, 0.9];
    // The hand and forearm out of the way.
    s.operator.entry_m = [1.0, 0.0];
    s.operator.keyframes.truncate(1);
    s.operator.keyframes[0].hand_m = [1.0, 0.05];
    s.operator.keyframes[0].t_s = 0.0;
    s.operator.obstacles.truncate(1);
    // Find the wall position where the step ends straddle it, from the run without it.
    let mut free = s.clone();
    free.operator.obstacles[0].center_m = [0.5, 5.0];
    let (_, f) = run_scene(free);
    let xs: Vec<f64> = f.points.iter().map(|p| p[0]).collect();
    let k = xs.iter().position(|x| *x > 0.5).unwrap();
    let wall_x = 0.5 * (xs[k - 1] + xs[k]);
    assert!(xs[k] - xs[k - 1] > 2.0 * s.robot.wrist_radius_m + 0.004 + 0.01, "steps of {} m", xs[k] - xs[k - 1]);
    s.operator.obstacles[0].center_m = [wall_x, 0.5];
    let (scene, r) = run_scene(s);
    honest("thin wall", &scene, &r);
    let ends = r.signed_distance_m.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(ends > 0.0, "every step end is clear of the wall: {ends} m");
    assert!(r.min_signed_distance_m < -0.04, "the swept check finds the crossing: {} m", r.min_signed_distance_m);
    assert!(matches!(r.status, Status::Collision(_)), "{:?}", r.status);
    assert!(r.time_inside_s > 0.0);
    assert_eq!(avoid::metrics_json(&r, Engine::Reference, false)["collided"], true);
}

/// The swept bound itself: a tool passing a static disc, and a disc moving across a still tool
/// between two step times, are found inside, and the bound is never above the true minimum.
#[test]
fn swept_bound_is_conservative_and_tight() {
    use flinch_harness::avoid::path::{max_obstacle_speed_mps, swept_min_m, SWEPT_TOL_M};
    let mut s = Avoid::load(&scene_path("avoid_box_wall.toml")).unwrap();
    s.operator.entry_m = [1.0, 0.0];
    s.operator.keyframes.truncate(1);
    s.operator.keyframes[0].hand_m = [1.0, 0.05];
    s.operator.keyframes[0].t_s = 0.0;
    s.operator.obstacles.truncate(1);
    let w = s.robot.wrist_radius_m;
    let o = &mut s.operator.obstacles[0];
    o.kind = "disc".into();
    o.radius_m = 0.01;
    o.center_m = [0.5, 0.5];
    let v = max_obstacle_speed_mps(&s);
    assert_eq!(v, 0.0);
    // Past the disc's side 5 mm from the wrist: ends 0.15 m away each side.
    let d = swept_min_m(&s, v, (0.0, [0.35, 0.5 + 0.01 + w + 0.005]), (0.1, [0.65, 0.5 + 0.01 + w + 0.005]));
    assert!(d <= 0.005 && d >= 0.005 - SWEPT_TOL_M, "{d}");
    // A step longer than the sample cap allows at 0.1 mm (0.6 m): still conservative, within
    // L / (2 n).
    let d = swept_min_m(&s, v, (0.0, [0.2, 0.5 + 0.01 + w + 0.005]), (0.1, [0.8, 0.5 + 0.01 + w + 0.005]));
    let cap = flinch_harness::avoid::path::SWEPT_MAX_SAMPLES as f64;
    assert!(d <= 0.005 && d >= 0.005 - 0.6 / (2.0 * cap), "{d}");
    // Straight through.
    let d = swept_min_m(&s, v, (0.0, [0.2, 0.5]), (0.1, [0.8, 0.5]));
    assert!(d <= -(0.01 + w) + 1e-12 && d >= -(0.01 + w) - SWEPT_TOL_M, "{d}");
    // The disc moves across a tool standing still, between two step times.
    let o = &mut s.operator.obstacles[0];
    o.keyframes = vec![
        flinch_harness::avoid::depth::ObstacleKeyframe { t_s: 0.0, x_m: 0.2, y_m: 0.5 },
        flinch_harness::avoid::depth::ObstacleKeyframe { t_s: 0.1, x_m: 0.8, y_m: 0.5 },
    ];
    let v = max_obstacle_speed_mps(&s);
    assert!((v - 6.0).abs() < 1e-9, "{v}");
    let ends = s.signed_distance_m(0.0, [0.5, 0.5]).min(s.signed_distance_m(0.1, [0.5, 0.5]));
    assert!(ends > 0.2);
    let d = swept_min_m(&s, v, (0.0, [0.5, 0.5]), (0.1, [0.5, 0.5]));
    assert!(d <= -(0.01 + w) + 1e-12 && d >= -(0.01 + w) - SWEPT_TOL_M, "{d}");
}

/// Item 3: no room. The goal under the hand, or the start already inside the protective
/// separation at rest: the tool does not move at all and the run says `no_room` at the first
/// frame, instead of waiting in a protective stop or stalling until the timeout. The thesis's law
/// (no monitor) has no such stop.
#[test]
fn no_room_stops_at_once() {
    for name in ["avoid_goal_covered.toml", "avoid_hand_at_tool.toml"] {
        let (scene, r) = run(name);
        safe(name, &scene, &r);
        assert_eq!(r.status, Status::Stopped(Reason::NoRoom), "{name}");
        assert_eq!(r.max_speed_mps, 0.0, "{name}");
        // Stopped as soon as the first frame reached the controller.
        let first = (scene.latency_s / scene.dt_s).ceil() as usize + 1;
        assert!(r.rows.len() <= first, "{name}: {} steps", r.rows.len());
        let json = avoid::metrics_json(&r, Engine::Reference, true);
        assert_eq!((json["status"].as_str(), json["reason"].as_str()), (Some("stopped"), Some("no_room")), "{name}");
        let (_, t) = thesis(name);
        assert_ne!(t.status.reason(), Some(Reason::NoRoom), "{name}");
    }
    // The start clear but the goal 0.1 m from a static hand (inside S_p at rest, about 0.27 m).
    let mut s = Avoid::load(&scene_path("avoid_empty_diagonal.toml")).unwrap();
    s.operator.keyframes.truncate(1);
    s.operator.keyframes[0].hand_m = [s.goal_m[0] - 0.2, s.goal_m[1]];
    s.operator.entry_m = [s.goal_m[0] - 0.2, 0.0];
    let (scene, r) = run_scene(s.clone());
    safe("goal near the hand", &scene, &r);
    assert_eq!(r.status, Status::Stopped(Reason::NoRoom));
    // The same hand far from the start, the goal and the line between them: room enough.
    s.operator.keyframes[0].hand_m = [0.8, 0.25];
    s.operator.entry_m = [0.8, 0.0];
    let (scene, r) = run_scene(s);
    safe("hand away from the goal", &scene, &r);
    assert_ne!(r.status.reason(), Some(Reason::NoRoom), "{:?}", r.status);
}

/// Item 4: variants nobody tuned for, seeded and reproducible (`FLINCH_AVOID_VARIANTS` sets how
/// many; 200 by default). The operator anywhere along the near edge, hand 30-80 mm, forearm
/// 40-100 mm wide, 50-250 mm high, still or moving at up to `v_h` (1.6 m/s); start and goal
/// anywhere at least 0.3 m apart; grid 15 x 15 or 30 x 30; latency 0 to 0.2 s. Our law (not
/// `--thesis`) every time: a run reported reached kept the clearance and the SSM bound; any run that
/// went inside is a collision and `flinch avoid` would exit 1; and, stronger, every run is safe
/// (`safe`: never over the SSM bound at the true separation, never moving in contact). A hand whose
/// key frames run into the tool held in a protective stop is a `collision` (ISO/TS 15066 5.5.4
/// allows contact with a stopped robot; the report still says so), with the tool at rest.
#[test]
fn random_variants_are_safe_and_honest() {
    let base = Avoid::load(&scene_path("avoid_fast_hand.toml")).unwrap();
    let n: usize = std::env::var("FLINCH_AVOID_VARIANTS").ok().and_then(|v| v.parse().ok()).unwrap_or(200);
    let mut seed: u64 = 0x0A70_1D09;
    let mut next = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let setups: Vec<(usize, Setup)> = [15, 30]
        .into_iter()
        .map(|g| {
            let mut s = base.clone();
            s.fit.grid = g;
            (g, Setup::new(&s, None).unwrap())
        })
        .collect();
    let mut tally = std::collections::BTreeMap::new();
    let mut reached_near = f64::INFINITY;
    let t_start = std::time::Instant::now();
    for k in 0..n {
        let mut s = base.clone();
        let mut pt = || [0.1 + 0.85 * next(), 0.1 + 0.85 * next()];
        let (start, goal) = loop {
            let (a, b) = (pt(), pt());
            if (a[0] - b[0]).hypot(a[1] - b[1]) > 0.3 {
                break (a, b);
            }
        };
        s.start_m = start;
        s.goal_m = goal;
        let ex = 0.05 + 0.95 * next();
        s.operator.entry_m = [ex, 0.0];
        s.operator.hand_radius_m = 0.03 + 0.05 * next();
        s.operator.forearm_width_m = 0.04 + 0.06 * next();
        s.operator.hand_height_m = 0.05 + 0.2 * next();
        s.operator.forearm_height_m = 0.05 + 0.2 * next();
        // The hand starts within 0.4 m of its edge (farther, its forearm leaves most starts or
        // goals inside S_p: `no_room` at once) and then reaches anywhere.
        let h0 = [ex, 0.02 + 0.38 * next()];
        let h1 = [0.05 + 0.9 * next(), 0.05 + 0.9 * next()];
        let t0 = 1.5 * next();
        let speed = 1.6 * next();
        let still = next() < 0.3;
        s.operator.keyframes.truncate(1);
        s.operator.keyframes[0].t_s = t0;
        s.operator.keyframes[0].hand_m = h0;
        if !still {
            let mut kf = s.operator.keyframes[0].clone();
            kf.t_s = t0 + (h1[0] - h0[0]).hypot(h1[1] - h0[1]) / speed.max(0.05);
            kf.hand_m = h1;
            s.operator.keyframes.push(kf);
        }
        let grid = if next() < 0.5 { 15 } else { 30 };
        s.fit.grid = grid;
        s.latency_s = 0.2 * next();
        s.camera.seed = k as u64;
        s.max_time_s = 5.0;
        let setup = &setups.iter().find(|(g, _)| *g == grid).unwrap().1;
        let r = simulate(&s, setup, Engine::Reference).unwrap();
        let name = format!(
            "variant {k}: start {start:.2?} goal {goal:.2?}, hand {h0:.2?} -> {h1:.2?} at {speed:.2} m/s from {t0:.2} s (still {still}), grid {grid}, latency {:.3} s",
            s.latency_s
        );
        // The brief's assertions first (they name the defect), then everything `safe` checks.
        if r.status == Status::Reached {
            assert!(r.min_signed_distance_m >= s.clearance_m && r.ssm_violations == 0, "{name}: reached unsafely");
        }
        if r.min_signed_distance_m < 0.0 {
            assert!(matches!(r.status, Status::Collision(_)) && !r.status.ok(), "{name}: inside but {:?}", r.status);
        }
        safe(&name, &s, &r);
        if r.status == Status::Reached { reached_near = reached_near.min(r.min_signed_distance_m); }
        *tally.entry(format!("{} {}", r.status.name(), r.status.reason().map_or("", |x| x.name()))).or_insert(0) += 1;
    }
    println!("{n} variants: {tally:?}; closest reached run {reached_near} m; {:.1} s", t_start.elapsed().as_secs_f64());
}

/// A command source that answers every step with a non-finite command (as the thesis's law can
/// with extreme weights: no monitor stands between it and the drive in `--thesis` mode).
struct NanEngine;

impl flinch_harness::avoid::path::StepEngine for NanEngine {
    fn new_field(&mut self, _: &flinch_harness::avoid::rbf::Field, _: u32, _: u32) -> Result<(), String> {
        Ok(())
    }
    fn command(&mut self, _: [f64; 2], _: [f64; 2], _: u32, _: Option<&flinch_firmware::avoidance::Sensed<f64>>) -> flinch_harness::avoid::path::Cmd {
        flinch_harness::avoid::path::Cmd { v: [f64::NAN, 0.1], limit_mps: 0.25, state: "field" }
    }
}

/// Follow-up to issue 9 (item 3): a NaN command in `--thesis` mode (the monitor off) is a fault:
/// the run's status is `fault`, the unfavourable verdict (exit 1), never `reached` nor a clean stop.
/// Before: the NaN position read as "left the view", `stopped`, a safe stop.
#[test]
fn a_non_finite_command_is_a_fault() {
    let mut s = Avoid::load(&scene_path("avoid_empty_diagonal.toml")).unwrap();
    s.thesis_mode();
    s.max_time_s = 1.0;
    let setup = Setup::new(&s, None).unwrap();
    let r = flinch_harness::avoid::path::simulate_with(&s, &setup, &mut NanEngine).unwrap();
    let m = avoid::metrics_json(&r, Engine::Reference, false);
    assert_eq!(m["status"], "fault", "{m}");
    assert_eq!(m["reason"], "non_finite_command", "{m}");
    assert_eq!(m["reached_goal"], false);
    assert!(!r.status.ok());
    // The tool did not move on a command it could not carry out; every reported number is finite.
    assert!(r.points.iter().all(|p| p[0].is_finite() && p[1].is_finite()), "{:?}", r.points.last());
    assert!(r.path_length_m.is_finite() && r.max_speed_mps.is_finite(), "{m}");
}

/// Follow-up to issue 9 (item 3): the CSV's last row is a control step like any other; it was
/// labelled `stopped` whenever the run ended, even when the tool moved in that step (a timeout at
/// cruise speed). Now `stopped` only where the step's command was zero.
#[test]
fn the_last_csv_row_is_stopped_only_when_the_tool_stood_still() {
    let mut s = Avoid::load(&scene_path("avoid_empty_diagonal.toml")).unwrap();
    s.max_time_s = 0.5;
    let (_, r) = run_scene(s);
    assert_eq!(r.status, Status::Stopped(Reason::Timeout), "{:?}", r.status);
    let last = r.rows.last().unwrap();
    assert!(last.v_mps[0].hypot(last.v_mps[1]) > 0.1, "moving at the timeout: {:?}", last.v_mps);
    assert_ne!(last.state, "stopped", "it moved in that step: {:?}", last);
    for w in &r.rows {
        if w.state == "stopped" {
            assert_eq!(w.v_mps, [0.0, 0.0], "{w:?}");
        }
    }
}

/// Follow-up to issue 9 (item 3): `reached_goal` says what it reports: `status` is `reached`, not
/// merely "the tool got to the goal" (a run that crossed the operator and then arrived reports
/// `false`, and `time_to_goal_s` says it arrived).
#[test]
fn reached_goal_is_documented_as_what_it_reports() {
    let schema: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(scene_path("../docs/schema/avoid.json")).unwrap()).unwrap();
    let d = schema["properties"]["reached_goal"]["description"].as_str().unwrap().to_string();
    assert!(d.contains("`status` is `reached`"), "{d}");
    assert!(d.contains("time_to_goal_s"), "{d}");
    let (scene, r) = thesis("avoid_wall.toml");
    let m = avoid::metrics_json(&r, Engine::Reference, scene.safety.on());
    assert_eq!(m["reached_goal"], m["status"] == "reached", "{m}");
}

/// Follow-up to issue 9 (item 4): ISO 13855:2010 6.2, formula (1) `S = K T + C`: K = 2,000 mm/s
/// where the resulting S is at most 500 mm. The monitor assumed `v_h` = 1.6 m/s at every distance,
/// so a hand reaching at 2.0 m/s (within 0.5 m: ISO 13855's own figure, and the loader's allowed
/// range) and stopping 50 mm from the tool's path gave steps over the bound that the verdict, which
/// takes the hand's true speed, reported as `ssm_violation`. Now the monitor takes K = 2.0 m/s where
/// its stop separation is within 0.5 m: no step over the bound, for hands stopping 30 to 70 mm from
/// the path at several instants.
#[test]
fn a_hand_at_iso_13855s_near_speed_stays_within_the_bound() {
    let base = Avoid::load(&scene_path("avoid_fast_hand.toml")).unwrap();
    let mut worst = (0usize, 0.0f64, String::new());
    for gap in [0.03, 0.05, 0.07] {
        for t0 in [0.3, 0.45, 0.6, 0.75, 0.9] {
            let mut s = base.clone();
            // The hand's edge `gap` from the wrist's edge on the straight line y = 0.5, reached at
            // 2.0 m/s from its rest at y = 0.06.
            let y = 0.5 - s.robot.wrist_radius_m - s.operator.hand_radius_m - gap;
            s.operator.keyframes[1].t_s = t0;
            s.operator.keyframes[2].t_s = t0 + (y - 0.06) / 2.0;
            s.operator.keyframes[2].hand_m = [0.45, y];
            let name = format!("hand to {gap} m from the path at 2.0 m/s from t = {t0} s");
            let (scene, r) = run_scene(s);
            println!("{name}: {:?}, {} steps over by up to {:.4} m/s, closest {:.3} m", r.status, r.ssm_violations, r.max_speed_over_ssm_mps, r.min_signed_distance_m);
            honest(&name, &scene, &r);
            if r.ssm_violations > worst.0 {
                worst = (r.ssm_violations, r.max_speed_over_ssm_mps, name);
            }
        }
    }
    assert_eq!(worst.0, 0, "{worst:?}");
}
