//! `flinch design`: the stopping-distance budget and its simulated confirmation, on the Tables 5-7
//! bi-stable module where the formula's answer is known by hand.

use flinch_harness::design::{design, speed_for_budget};
use flinch_harness::plant::motion_law::MotionLaw;
use flinch_harness::sweep::Template;
use flinch_tests::scene_path;

fn template() -> Template {
    Template::load(&scene_path("tables5-7_bistable.toml")).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn speed_for_budget_inverts_the_stopping_distance() {
    for (room, dt, d) in [(0.025, 0.07, 2.0), (0.01, 0.016, 2.0), (0.0185, 0.0, 5.0)] {
        let v = speed_for_budget(room, dt, d);
        assert!((MotionLaw::stopping_distance(v, dt, d) - room).abs() < 1e-12, "{room} {dt} {d}: {v}");
    }
    assert_eq!(speed_for_budget(-0.001, 0.07, 2.0), 0.0);
}

#[test]
fn a_70_ms_controller_on_the_tables5_7_module() {
    // By hand (Tables 5-6): C = 30 mm, d_sw = 5 mm, d_c = 2 m/s^2, DT = 70 ms. At V_c = 0.05 m/s the
    // flange needs 0.05 * 0.07 + 0.05^2 / 4 = 4.125 mm after detection, so the stroke needed is
    // 9.125 mm; the fastest speed for 25 mm of room solves v 0.07 + v^2 / 4 = 0.025: 0.20583 m/s.
    let r = design(&template(), None, None, Some(0.07)).unwrap();
    assert!((r.stopping_distance - 0.004125).abs() < 2e-6, "{}", r.stopping_distance);
    assert!((r.stroke_needed_formula - 0.009125).abs() < 2e-6);
    assert!((r.margin_formula - (0.030 - 0.009125)).abs() < 2e-6);
    assert!((r.speed_limit_formula - 0.20583).abs() < 1e-5, "{}", r.speed_limit_formula);
    // The simulation confirms both within what the formula leaves out (the tool's own motion after
    // contact, the robot's compliance): the simulated stroke within 1 mm, the speed within 10 %.
    let c = r.stroke_needed_simulated.expect("stroke found by bisection");
    assert!((c - r.stroke_needed_formula).abs() < 1e-3, "simulated stroke {c}");
    let v = r.speed_limit_simulated.expect("speed found by bisection");
    assert!((v / r.speed_limit_formula - 1.0).abs() < 0.10, "simulated limit {v}");
    let at = r.at_limit.as_ref().unwrap();
    assert!(!at.summary.stroke_exhausted && at.summary.safe);
    // At the limit the tool uses its stroke up to the back end-stop (bisection resolution).
    let left = at.summary.stroke_left_min_m.unwrap();
    assert!((0.0..0.5e-3).contains(&left), "{left}");
    // The design point: mode 1, the flange stops about C - 9.1 mm short of the target.
    assert_eq!(r.design.summary.mode, Some(1));
    assert!(!r.design.summary.stroke_exhausted);
    let left = r.design.summary.stroke_left_min_m.unwrap();
    assert!((left - r.margin_formula).abs() < 1e-3, "{left}");
    assert!(r.safe && r.failures.is_empty());
}

#[test]
fn too_fast_for_the_stroke_is_reported() {
    // 0.3 m/s with 70 ms: 0.021 + 0.0225 = 43.5 mm after detection, far beyond 25 mm.
    let r = design(&template(), None, Some(0.3), Some(0.07)).unwrap();
    assert!(r.margin_formula < 0.0);
    assert!(r.design.summary.stroke_exhausted, "the simulated flange reaches the target");
    assert!(r.design.summary.stroke_left_min_m.unwrap() < 0.0);
    assert!(!r.safe && r.failures.len() == 2, "{:?}", r.failures);
    // A given stroke overrides the scene's (C1:C2 kept 1:1).
    let r = design(&template(), Some(0.06), Some(0.3), Some(0.07)).unwrap();
    assert!((r.stroke - 0.06).abs() < 1e-12 && r.margin_formula > 0.0);
}

#[test]
fn refusals_name_the_input() {
    let e = design(&template(), None, Some(-1.0), None).unwrap_err();
    assert!(e.contains("--speed") && e.contains("-1"), "{e}");
    let e = design(&template(), None, None, Some(f64::NAN)).unwrap_err();
    assert!(e.contains("--dead-time"), "{e}");
    let rigid = Template::load(&scene_path("tables5-7_rigid.toml")).unwrap();
    let e = design(&rigid, None, None, None).unwrap_err();
    assert!(e.contains("decoupler.kind"), "{e}");
}
