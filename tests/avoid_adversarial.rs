//! Collision avoidance on the adversarial scenes of issue 9 (`scenes/avoid_*.toml`): whatever the
//! law does, the outcome is reported honestly from the true geometry. A run that put the tool inside
//! the operator is never "reached", its signed distance is negative (not clamped at 0), and
//! `flinch avoid` answers `false` (exit 1).
use flinch_harness::avoid::path::{simulate, Engine, PathResult, Setup, Status};
use flinch_harness::avoid::scene::Avoid;
use flinch_harness::avoid::{self, AvoidArgs};
use flinch_tests::scene_path;

fn run(name: &str) -> (Avoid, PathResult) {
    let scene = Avoid::load(&scene_path(name)).unwrap_or_else(|e| panic!("{e}"));
    let setup = Setup::new(&scene, None).unwrap();
    let res = simulate(&scene, &setup, Engine::Reference).unwrap();
    (scene, res)
}

/// What every run must satisfy, whatever the scene.
fn honest(name: &str, scene: &Avoid, r: &PathResult) {
    let min = r.signed_distance_m.iter().copied().fold(f64::INFINITY, f64::min);
    assert_eq!(min, r.min_signed_distance_m, "{name}: min over the path");
    // Recomputed here from the true geometry at every step, not from the sensed image.
    let op = scene.operator_shape();
    for (k, (p, s)) in r.points.iter().zip(&r.signed_distance_m).enumerate() {
        let t = k as f64 * scene.dt_s;
        assert!((op.signed_distance(scene.hand_at(t), *p) - s).abs() < 1e-9, "{name}: step {k}");
    }
    let inside_steps = r.signed_distance_m.iter().skip(1).filter(|s| **s < 0.0).count();
    assert!((r.time_inside_s - inside_steps as f64 * scene.dt_s).abs() < 1e-9, "{name}: time inside");
    match r.status {
        Status::Reached => {
            assert!(r.min_signed_distance_m >= 0.0, "{name}: reached but went {} m deep", r.min_signed_distance_m);
            let last = r.points.last().unwrap();
            let d = ((last[0] - scene.goal_m[0]).powi(2) + (last[1] - scene.goal_m[1]).powi(2)).sqrt();
            assert!(d <= scene.goal_tolerance_m, "{name}: reached but {d} m from the goal");
        }
        Status::Stopped(_) => assert!(r.min_signed_distance_m >= 0.0, "{name}: stopped is only for runs never inside"),
        Status::Collision(_) => {
            assert!(r.min_signed_distance_m < 0.0 && r.time_inside_s > 0.0, "{name}: collision needs a penetration");
        }
    }
    assert_eq!(r.status.ok(), r.status == Status::Reached);
    // The speeds are those of the rows.
    let vmax = r.rows.iter().map(|w| w.v_mps[0].hypot(w.v_mps[1])).fold(0.0, f64::max);
    assert!((vmax - r.max_speed_mps).abs() < 1e-12, "{name}");
}

/// The thesis's vortex law (eq 76) goes through the operator on these scenes: the report says so.
/// (When the safety layer lands these become "never inside"; until then this pins the honesty.)
#[test]
fn crossings_are_reported_as_collisions() {
    for name in ["avoid_forearm_across.toml", "avoid_wall.toml", "avoid_goal_covered.toml", "avoid_head_on.toml"] {
        let (scene, r) = run(name);
        honest(name, &scene, &r);
        assert!(matches!(r.status, Status::Collision(_)), "{name}: {:?}, {} m", r.status, r.min_signed_distance_m);
        assert!(r.min_signed_distance_m < -0.01, "{name}: the depth is not clamped: {}", r.min_signed_distance_m);
        let json = avoid::metrics_json(&r, Engine::Reference);
        assert_eq!(json["status"], "collision", "{name}");
        assert_eq!(json["collided"], true);
        assert_eq!(json["reached_goal"], false, "{name}: never reached after a crossing");
    }
}

#[test]
fn every_adversarial_scene_is_reported_honestly() {
    for name in ["avoid_operator_hand.toml", "avoid_under_tool.toml", "avoid_fast_hand.toml", "avoid_empty_diagonal.toml", "avoid_extreme_gain.toml"] {
        let (scene, r) = run(name);
        honest(name, &scene, &r);
    }
}

/// `flinch avoid` answers false (exit 1) on a collision and true on the shipped scene, and the CSV
/// has the documented columns, one row per step.
#[test]
fn cli_verdict_and_csv() {
    let csv = std::env::temp_dir().join(format!("flinch-avoid-{}.csv", std::process::id()));
    let args = |name: &str, csv: Option<std::path::PathBuf>| AvoidArgs {
        scene: scene_path(name),
        plot: None,
        json: true,
        mcu: false,
        calibration: None,
        save_calibration: None,
        compare: false,
        csv,
        save_depth: None,
    };
    assert_eq!(avoid::run(&args("avoid_wall.toml", Some(csv.clone()))), Ok(false));
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t_s,x_m,y_m,vx_mps,vy_mps,separation_m,speed_limit_mps,state"));
    let rows: Vec<Vec<f64>> = lines.map(|l| l.split(',').take(7).map(|v| v.parse().unwrap()).collect()).collect();
    assert!(rows.iter().any(|r| r[5] < 0.0), "the crossing shows in the CSV's separation");
    std::fs::remove_file(&csv).ok();
    assert_eq!(avoid::run(&args("avoid_operator_hand.toml", None)), Ok(true));
}
