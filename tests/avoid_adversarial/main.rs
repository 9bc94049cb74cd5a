//! Collision avoidance on the adversarial scenes of issue 9 (`scenes/avoid_*.toml`): whatever the
//! law does, the outcome is reported honestly from the true geometry. A run that put the tool inside
//! the operator is never "reached", its signed distance is negative (not clamped at 0), and
//! `flinch avoid` exits 1 (unsafe); a safe stop before the goal exits 4.
//!
//! This file holds the runs and the checks every test applies (`honest`, `safe`); the tests are in
//! `scenes.rs`, `monitor.rs`, `random.rs` and `cli_docs.rs`.
use flinch_harness::avoid::path::{PathResult, Status};
use flinch_harness::avoid::scene::Avoid;
use flinch_tests::scene_path;

mod cli_docs;
mod fixtures;
mod monitor;
mod random;
mod scenes;

pub(crate) fn run(name: &str) -> (Avoid, PathResult) {
    let scene = Avoid::load(&scene_path(name)).unwrap_or_else(|e| panic!("{e}"));
    run_scene(scene)
}

pub(crate) fn thesis(name: &str) -> (Avoid, PathResult) {
    let mut scene = Avoid::load(&scene_path(name)).unwrap_or_else(|e| panic!("{e}"));
    scene.thesis_mode();
    run_scene(scene)
}

pub(crate) fn run_scene(scene: Avoid) -> (Avoid, PathResult) {
    flinch_tests::avoid::run_reference(scene)
}

/// What every run must satisfy, whatever the scene.
pub(crate) fn honest(name: &str, scene: &Avoid, r: &PathResult) {
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
    // With fixtures (issue 29 item 2) the people's bound at the people's separation, and the
    // fixtures' (the robot's own stop, no K: `v (T_r + T_s / 2) + margin <= s`) at theirs.
    let fixtures = scene.operator.obstacles.iter().any(|o| o.fixture);
    let w = scene.robot.wrist_radius_m;
    let person_at = |t: f64, p: [f64; 2]| {
        let mut op = scene.operator_shape_at(t);
        op.obstacles.retain(|o| !o.fixture);
        op.signed_distance(scene.hand_at(t), p) - w
    };
    let fixture_at = |p: [f64; 2]| scene.operator.obstacles.iter().filter(|o| o.fixture).map(|o| o.signed_distance(p) - w).fold(f64::INFINITY, f64::min);
    let f = &scene.safety;
    let margin = f.intrusion_used_m(scene.camera.m_per_px) + f.sensor_uncertainty_m + f.robot_uncertainty_m + scene.clearance_m;
    let mut violations = 0;
    for (k, row) in r.rows.iter().enumerate() {
        let t0 = row.t_s - scene.dt_s;
        let v_obs = flinch_harness::avoid::path::obstacle_speed_mps(scene, t0, row.t_s);
        let s_person = if fixtures { person_at(t0, r.points[k]) } else { r.signed_distance_m[k] };
        let bound = ssm_bound_at(scene, s_person, v_obs);
        assert!((row.ssm_bound_mps - bound).abs() < 1e-9, "{name}: step {k}: bound {} != {bound}", row.ssm_bound_mps);
        let towards = if fixtures { towards_by(&|p| person_at(t0, p), r.points[k], row.v_mps) } else { towards_mps(scene, t0, r.points[k], row.v_mps) };
        let over_fixture = fixtures && {
            let b = ((fixture_at(r.points[k]) - margin) / (f.reaction_time_s + f.stopping_time_s / 2.0)).clamp(0.0, scene.speed_mps);
            towards_by(&fixture_at, r.points[k], row.v_mps) > b + 1e-6
        };
        if over_fixture || (towards > bound + 1e-6 && !within_pfl(scene, row.v_mps)) {
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
            // Within the tolerance at the last control step; then the drive brakes to rest, at
            // most `v (T_r - dt) + v T_s / 2` farther on from the speed `v` it had there (drive.rs).
            let main = r.rows.iter().rposition(|w| w.state != "braking").unwrap();
            let at = r.rows[main].p_m;
            let d = ((at[0] - scene.goal_m[0]).powi(2) + (at[1] - scene.goal_m[1]).powi(2)).sqrt();
            assert!(d <= scene.goal_tolerance_m, "{name}: reached but {d} m from the goal");
            let last = r.points.last().unwrap();
            let v = r.max_speed_mps;
            let tail = v * (scene.safety.reaction_time_s - scene.dt_s).max(0.0) + v * scene.safety.stopping_time_s / 2.0;
            let d = ((last[0] - scene.goal_m[0]).powi(2) + (last[1] - scene.goal_m[1]).powi(2)).sqrt();
            assert!(d <= scene.goal_tolerance_m + tail + 1e-9, "{name}: {d} m from the goal after braking (at most {tail} m of braking)");
        }
        Status::Stopped(_) => assert!(r.min_signed_distance_m >= 0.0, "{name}: stopped is only for runs never inside"),
        Status::Collision(_) => {
            let tool = r.min_signed_distance_m < 0.0 && r.time_inside_s > 0.0;
            assert!(tool || r.link_min_signed_distance_m < 0.0, "{name}: collision needs a penetration, by the tool or the link");
        }
        Status::SsmViolation(_) => assert!(r.min_signed_distance_m >= 0.0 && r.ssm_violations > 0, "{name}: ssm_violation is for runs never inside"),
        // No synthetic run is unverified (only recorded frames are), and no shipped law gives a
        // non-finite command.
        Status::Fault | Status::Unverified(_) => panic!("{name}: {:?}", r.status),
    }
    assert_eq!(r.verdict_basis, flinch_harness::avoid::path::VerdictBasis::SceneModel, "{name}");
    if r.min_signed_distance_m < 0.0 || r.link_min_signed_distance_m < 0.0 {
        assert!(matches!(r.status, Status::Collision(_)), "{name}: inside but {:?}", r.status);
    } else if r.ssm_violations > 0 {
        assert!(matches!(r.status, Status::SsmViolation(_)), "{name}: over the SSM bound but {:?}", r.status);
    }
    assert_eq!(r.status.ok(), r.status == Status::Reached);
    // The drive is never faster than the fastest command (it takes a speed-up at once and slows
    // down towards a command in a straight line: drive.rs); a command it was still slowing
    // towards when the next came need not be reached.
    let vmax = r.rows.iter().map(|w| w.v_mps[0].hypot(w.v_mps[1])).fold(0.0, f64::max);
    assert!(r.max_speed_mps <= vmax + 1e-12, "{name}: {} over the commands' {vmax}", r.max_speed_mps);
    // After the run's last command only braking rows, at zero command.
    let main = r.rows.iter().rposition(|w| w.state != "braking").map_or(0, |k| k + 1);
    assert!(r.rows[main..].iter().all(|w| w.v_mps == [0.0, 0.0]), "{name}");
}

pub(crate) const ADVERSARIAL: [&str; 19] = [
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
pub(crate) fn step_motion(scene: &Avoid, r: &PathResult, k: usize) -> f64 {
    let (p0, p1) = (r.points[k], r.points[k + 1]);
    (p1[0] - p0[0]).hypot(p1[1] - p0[1]) + flinch_harness::avoid::path::max_obstacle_speed_mps(scene) * scene.dt_s
}

/// The speed limit of ISO/TS 15066 5.5.4 at a true separation `s` (the bound the monitor must stay
/// under, whatever it sensed), m/s: on the tool's speed towards the person ([`towards_mps`]).
/// With the obstacles truly moving at `v_obs` (m/s): `v_h` is the faster of the scene's and that.
pub(crate) fn ssm_bound_at(scene: &Avoid, s: f64, v_obs: f64) -> f64 {
    let f = &scene.safety;
    let v_h = f.human_speed_mps.max(v_obs);
    let t = f.reaction_time_s + f.stopping_time_s;
    let margin = f.intrusion_used_m(scene.camera.m_per_px) + f.sensor_uncertainty_m + f.robot_uncertainty_m + scene.clearance_m;
    // A hand or an arm: K = max(2.0 m/s, v_h) at every distance (at least 0.1 m). Only a scene
    // declared whole-body-only gets ISO 13855:2010 6.2 formula (1)'s rule: K = 2.0 m/s (v_h if
    // faster) where the resulting separation is at most 0.5 m; else K = v_h, at least 0.5 m.
    let near = v_h.max(2.0) * t + margin;
    let stop = if !f.whole_body_only {
        near.max(0.1)
    } else if near <= 0.5 {
        near.max(0.1)
    } else {
        (v_h * t + margin).max(0.5)
    };
    ((s - stop) / (f.reaction_time_s + f.stopping_time_s / 2.0)).clamp(0.0, scene.speed_mps)
}

/// The tool's speed towards the person (ISO/TS 15066 5.5.4.2.3), recomputed here from the true
/// geometry: how fast the signed distance at `p` (time `t`) falls along the command `v`, one-sided
/// over 10 um, m/s (0 when moving away).
pub(crate) fn towards_mps(scene: &Avoid, t: f64, p: [f64; 2], v: [f64; 2]) -> f64 {
    let speed = v[0].hypot(v[1]);
    if speed == 0.0 {
        return 0.0;
    }
    let h = 1e-5;
    let q = [p[0] + h * v[0] / speed, p[1] + h * v[1] / speed];
    ((scene.signed_distance_m(t, p) - scene.signed_distance_m(t, q)) / h * speed).clamp(0.0, speed)
}

/// [`towards_mps`] for any signed distance `d` (0 where it is infinite: nothing there).
pub(crate) fn towards_by(d: &dyn Fn([f64; 2]) -> f64, p: [f64; 2], v: [f64; 2]) -> f64 {
    let speed = v[0].hypot(v[1]);
    if speed == 0.0 {
        return 0.0;
    }
    let h = 1e-5;
    let q = [p[0] + h * v[0] / speed, p[1] + h * v[1] / speed];
    let fall = (d(p) - d(q)) / h;
    if fall.is_finite() {
        (fall * speed).clamp(0.0, speed)
    } else {
        0.0
    }
}

/// Within the scene's PFL speeds (`[avoid.pfl]` resolved): along the module's axis and across it.
pub(crate) fn within_pfl(scene: &Avoid, v: [f64; 2]) -> bool {
    let Some(p) = &scene.pfl else { return false };
    let Some(r) = &p.resolved else { return false };
    let along = (v[0] * p.axis[0] + v[1] * p.axis[1]).abs();
    let across = (v[0] * p.axis[1] - v[1] * p.axis[0]).abs();
    along <= r.along_mps + 1e-6 && across <= r.across_mps + 1e-6
}

/// With the monitor on (as shipped): never inside the operator, never above the cap, and at every
/// step the commanded speed is within the SSM bound computed from the TRUE separation at the start
/// of the step (a sensing chain that misses the operator, a blind zone, would break this).
pub(crate) fn safe(name: &str, scene: &Avoid, r: &PathResult) {
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
    // The people's bound (with K) at their true separation; with fixtures (issue 29 item 2) the
    // fixtures' (no K) at theirs.
    let fixtures = scene.operator.obstacles.iter().any(|o| o.fixture);
    let w = scene.robot.wrist_radius_m;
    let f = &scene.safety;
    let margin = f.intrusion_used_m(scene.camera.m_per_px) + f.sensor_uncertainty_m + f.robot_uncertainty_m + scene.clearance_m;
    for (k, row) in r.rows.iter().enumerate() {
        let t0 = row.t_s - scene.dt_s;
        let person_at = |p: [f64; 2]| {
            let mut op = scene.operator_shape_at(t0);
            op.obstacles.retain(|o| !o.fixture);
            op.signed_distance(scene.hand_at(t0), p) - w
        };
        let s_true = if fixtures { person_at(r.points[k]) } else { r.signed_distance_m[k] };
        let v = if fixtures { towards_by(&person_at, r.points[k], row.v_mps) } else { towards_mps(scene, t0, r.points[k], row.v_mps) };
        let b = ssm_bound_at(scene, s_true, flinch_harness::avoid::path::obstacle_speed_mps(scene, t0, row.t_s));
        assert!(v <= b + 1e-6 || within_pfl(scene, row.v_mps), "{name}: t = {} s: {v} m/s towards the person at {s_true} m (bound {b})", row.t_s);
        if fixtures {
            let fixture_at = |p: [f64; 2]| scene.operator.obstacles.iter().filter(|o| o.fixture).map(|o| o.signed_distance(p) - w).fold(f64::INFINITY, f64::min);
            let s_fix = fixture_at(r.points[k]);
            let bf = ((s_fix - margin) / (f.reaction_time_s + f.stopping_time_s / 2.0)).clamp(0.0, scene.speed_mps);
            let vf = towards_by(&fixture_at, r.points[k], row.v_mps);
            assert!(vf <= bf + 1e-6, "{name}: t = {} s: {vf} m/s towards a fixture at {s_fix} m (bound {bf})", row.t_s);
        }
    }
}
