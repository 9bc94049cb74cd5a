//! `motion.stopping`, the robot's own stopping data (issue 17 item 3): the table is refused where no
//! stop could produce it (file, line, key), `check`'s budget is the table's D(v) at its points, the
//! run follows the table (T(v) from the signal to standstill), `design` inverts D(v), `run`,
//! `check` and `design` agree on the shipped scene, and a speed beyond the table is refused, not
//! extrapolated (below its first point D is scaled through the origin, an upper bound).

use flinch_harness::check::check;
use flinch_harness::design::design;
use flinch_harness::scene::{self, Scene};
use flinch_harness::sim;
use flinch_harness::sweep::Template;
use flinch_tests::scene_path;

const FILE: &str = "tables5-7_bistable_stopping_table.toml";
const TABLE: &str = "stopping = { category = 1, speed = [0.1, 0.2, 0.3], distance = [0.005, 0.014, 0.028], time = [0.070, 0.110, 0.155], payload = 1.0 }";
const POINTS: [(f64, f64, f64); 3] = [(0.1, 0.005, 0.070), (0.2, 0.014, 0.110), (0.3, 0.028, 0.155)];

fn text() -> String {
    let t = std::fs::read_to_string(scene_path(FILE)).unwrap();
    assert!(t.contains(TABLE), "the shipped table changed: update this test");
    t
}

fn with(pairs: &[(&str, &str)]) -> Result<Scene, scene::SceneError> {
    let mut t = text();
    for (a, b) in pairs {
        assert!(t.contains(a), "{a}");
        t = t.replacen(a, b, 1);
    }
    scene::parse(&t, "stop.toml")
}

/// The one message of a refused scene, as printed (`file:line: key: message`).
fn refused(pairs: &[(&str, &str)]) -> String {
    let e = with(pairs).expect_err("must be refused");
    assert_eq!(e.issues.len(), 1, "{e}");
    e.to_string()
}

fn line_of(needle: &str) -> usize {
    text().lines().position(|l| l.contains(needle)).unwrap() + 1
}

#[test]
fn tables_no_stop_could_produce_are_refused_with_file_line_and_key() {
    let l = line_of("stopping = {");
    let at = |key: &str| format!("stop.toml:{l}: motion.stopping.{key}: ");
    let cases: &[(&str, &str, &str)] = &[
        ("speed = [0.1, 0.2, 0.3]", "speed = [0.1, 0.3, 0.2]", "speed"),
        ("distance = [0.005, 0.014, 0.028]", "distance = [0.005, 0.028, 0.014]", "distance"),
        ("time = [0.070, 0.110, 0.155]", "time = [0.070, 0.160, 0.155]", "time"),
        // 50 mm from 0.3 m/s in 155 ms: faster than the speed it stops from (v T = 46.5 mm).
        ("0.014, 0.028]", "0.014, 0.050]", "distance"),
        // 3 mm from 0.1 m/s in 70 ms: below v T / 2 = 3.5 mm.
        ("[0.005, 0.014", "[0.003, 0.014", "distance"),
        ("distance = [0.005, 0.014, 0.028]", "distance = [0.005, 0.014]", "distance"),
        ("speed = [0.1, 0.2, 0.3]", "speed = [0.1, -0.2, 0.3]", "speed"),
        ("category = 1", "category = 2", "category"),
        ("payload = 1.0", "payload = 0.5", "payload"),
    ];
    for (a, b, key) in cases {
        let e = refused(&[(a, b)]);
        assert!(e.starts_with(&at(key)), "{a} -> {b}: {e}");
    }
    let e = refused(&[("0.014, 0.028]", "0.014, 0.050]")]);
    assert!(e.contains("v T = 0.0465 m"), "{e}");
    let e = refused(&[("[0.005, 0.014", "[0.003, 0.014")]);
    assert!(e.contains("v T / 2 = 0.0035 m"), "{e}");
    // decel and the table together, and neither.
    let e = refused(&[("dead_time = 0.0 ", "decel = 2.0\ndead_time = 0.0 ")]);
    assert!(e.contains("motion.decel: give either decel"), "{e}");
    let e = refused(&[(TABLE, "")]);
    assert!(e.contains("motion.decel: missing required key") && e.contains("or give stopping"), "{e}");
}

#[test]
fn a_speed_beyond_the_table_is_refused_not_extrapolated() {
    let e = refused(&[("speed = 0.25 ", "speed = 0.31 ")]);
    let l = line_of("speed = 0.25 ");
    assert!(e.starts_with(&format!("stop.toml:{l}: motion.speed: must be at most the largest speed of motion.stopping, 0.3 m/s")), "{e}");
    assert!(e.contains("not extrapolated"), "{e}");
    // At the table's last point it is accepted; below its first, D is scaled through the origin.
    assert!(with(&[("speed = 0.25 ", "speed = 0.3 ")]).is_ok());
    let s = with(&[("speed = 0.25 ", "speed = 0.05 "), ("gap = 0.04 ", "gap = 0.01 ")]).unwrap();
    let c = check(&s).unwrap();
    assert!((c.stopping_distance - 0.005 * 0.05 / 0.1).abs() < 1.001e-6, "{}", c.stopping_distance);
    // design refuses a speed beyond the table, naming why.
    let t = Template::load(&scene_path(FILE)).unwrap();
    let e = design(&t, None, Some(0.35), None).unwrap_err();
    assert!(e.contains("not extrapolated"), "{e}");
}

#[test]
fn check_budget_is_the_tables_distance_and_the_run_follows_its_time() {
    for (v, d, t) in POINTS {
        // A gap the flange covers at V_c already (at 0.3 m/s it reaches V_c after 45 mm).
        let s = with(&[("speed = 0.25 ", &format!("speed = {v} ")), ("gap = 0.04 ", "gap = 0.06 "), ("duration = 0.8 ", "duration = 1.5 ")]).unwrap();
        let c = check(&s).unwrap();
        // D(v) rounded up to the micrometre, nothing added (dead_time = 0: the signal at detection).
        assert!(c.stopping_distance >= d - 1e-12 && c.stopping_distance - d < 1.001e-6, "{v}: {} vs {d}", c.stopping_distance);
        assert_eq!(c.stroke - c.switch_travel - c.stopping_distance, c.margin);
        let r = &c.simulated;
        let stop = r.t_stop.unwrap() - r.t_detect.unwrap();
        assert!((stop - t).abs() < 1e-9, "{v}: signal to standstill {stop} s vs the table's {t} s");
    }
    // A delay to the stop signal adds v DT to the distance and DT to the time.
    let s = with(&[("dead_time = 0.0 ", "dead_time = 0.02 ")]).unwrap();
    let c = check(&s).unwrap();
    let d = 0.014 + 0.5 * (0.028 - 0.014);
    assert!((c.stopping_distance - (0.25 * 0.02 + d)).abs() < 1.001e-6, "{}", c.stopping_distance);
    let r = &c.simulated;
    assert!((r.t_stop.unwrap() - r.t_detect.unwrap() - (0.02 + 0.1325)).abs() < 1e-9);
}

#[test]
fn run_check_and_design_agree_on_the_shipped_scene() {
    let s = scene::load(&scene_path(FILE)).unwrap();
    let (run, _) = sim::run(&s, false).unwrap();
    let c = check(&s).unwrap();
    let t = Template::load(&scene_path(FILE)).unwrap();
    let r = design(&t, None, None, None).unwrap();
    // By hand: D(0.25) = 14 + 0.5 (28 - 14) = 21 mm against 30 - 5 = 25 mm: fits by 4 mm.
    assert!((c.stopping_distance - 0.021).abs() < 1.001e-6 && (c.margin - 0.004).abs() < 1.001e-6);
    assert!(run.safe && c.safe && r.safe, "run {} check {} design {}", run.safe, c.safe, r.safe);
    assert_eq!(r.stopping_distance, c.stopping_distance);
    assert_eq!(r.design.summary.stroke_left_min_m, run.stroke_left_min_m);
    // design inverts D(v): 14 mm + (v - 0.2) / 0.1 x 14 mm = 25 mm at v = 0.27857 m/s.
    assert!((r.speed_limit_formula - (0.2 + 0.1 * 11.0 / 14.0)).abs() < 1e-9, "{}", r.speed_limit_formula);
    let v = r.speed_limit_mps.expect("a confirmed safe speed");
    assert!(v <= r.speed_limit_formula && v <= 0.3);
    // Just under the answer check says SAFE; just over the formula's limit the budget does not fit.
    let at = |v: f64| check(&t.with(&[("motion.speed", v)]).unwrap()).unwrap();
    assert!(at(v - 1e-4).safe);
    let over = at(r.speed_limit_formula + 1e-3);
    assert!(!over.fits && !over.safe, "{over:?}");
}
