//! `flinch sweep`: every refusal names what is wrong before anything runs; points come back in
//! grid order whatever the thread count; one- and two-axis sweeps give what single runs give.

use flinch_harness::scene;
use flinch_harness::sim;
use flinch_harness::sweep::cli::axes;
use flinch_harness::sweep::{check_metric, plot, Axis, Progress, Spacing, Sweep, Template};
use flinch_tests::scene_path;

fn template() -> Template {
    Template::load(&scene_path("tables5-7_bistable.toml")).unwrap_or_else(|e| panic!("{e}"))
}

/// The error of a sweep built from `specs`, which must fail.
fn refused(specs: &[&str]) -> String {
    let specs: Vec<String> = specs.iter().map(|s| s.to_string()).collect();
    match axes(&specs, &[]).and_then(|a| Sweep::new(&template(), a)) {
        Ok(s) => panic!("{specs:?} accepted ({} points)", s.len()),
        Err(e) => e.to_string(),
    }
}

fn has(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "{msg:?} lacks {p:?}");
    }
}

#[test]
fn unknown_key_lists_close_matches() {
    let e = refused(&["motion.sped=0.05:0.1:3"]);
    has(&e, &["unknown key motion.sped", "close matches: motion.speed", "tables5-7_bistable.toml"]);
    let e = refused(&["decoupler.spring_rat=100:200:3"]);
    has(&e, &["unknown key decoupler.spring_rat", "decoupler.spring_rate"]);
    // Nothing close: every numeric key of the scene is listed instead.
    let e = refused(&["foo.bar=1:2:3"]);
    has(&e, &["unknown key foo.bar", "motion.speed", "target.stiffness"]);
}

#[test]
fn non_numeric_and_table_keys_are_refused() {
    has(&refused(&["decoupler.kind=1:2:3"]), &["decoupler.kind = \"bistable\" is not a number"]);
    has(&refused(&["decoupler.front_stop=1:2:3"]), &["decoupler.front_stop is a table", "decoupler.front_stop.stiffness"]);
    has(&refused(&["motion..speed=1:2:3"]), &["dotted path"]);
}

#[test]
fn bad_ranges_are_refused() {
    has(&refused(&["motion.speed=0.1:0.2:1"]), &["N must be at least 2", "got 1"]);
    has(&refused(&["motion.speed=0.2:0.1:5"]), &["START must be below STOP", "0.2 >= 0.1"]);
    has(&refused(&["motion.speed=0.1:0.1:5"]), &["START must be below STOP"]);
    has(&refused(&["motion.speed=log:0:0.1:5"]), &["log axis needs START > 0"]);
    has(&refused(&["motion.speed=0.1:x:5"]), &["STOP \"x\" is not a number"]);
    has(&refused(&["motion.speed=0.1:0.2:2.5"]), &["N \"2.5\" is not a whole number"]);
    has(&refused(&["motion.speed"]), &["expected KEY=START:STOP:N"]);
    has(&refused(&["motion.speed=0.1:0.2"]), &["three fields"]);
    has(&refused(&["motion.speed=0.1:inf:3"]), &["finite"]);
}

#[test]
fn a_value_the_validator_refuses_is_named_with_its_message() {
    // 0.001 m/s never closes the 10 mm gap in 0.6 s: the validator's own message is passed on.
    let e = refused(&["motion.speed=0.001:0.05:3"]);
    has(&e, &["1 of 3 points refused", "motion.speed = 0.001", "target.gap", "never reaches the target"]);
    // A mass of zero or less is physically impossible.
    let e = refused(&["tool.mass=-1:1:3"]);
    has(&e, &["tool.mass = -1", "tool.mass"]);
    // Two axes: the refused point names both values.
    let e = refused(&["motion.speed=0.001:0.05:2", "motion.dead_time=0:0.01:2"]);
    has(&e, &["motion.speed = 0.001, motion.dead_time = 0"]);
}

#[test]
fn axis_count_duplicates_log_and_metric_are_checked() {
    has(&refused(&["motion.speed=0.05:0.1:2", "motion.speed=0.05:0.1:2"]), &["given twice"]);
    has(&refused(&["motion.speed=0.05:0.1:2", "tool.mass=0.5:1:2", "motion.dead_time=0:0.1:2"]), &["3 --vary axes given"]);
    let e = axes(&["motion.speed=0.05:0.1:2".into()], &["tool.mass".into()]).unwrap_err().to_string();
    has(&e, &["--log tool.mass: not one of the swept keys"]);
    assert_eq!(axes(&["target.stiffness=1e6:1e8:3".into()], &["target.stiffness".into()]).unwrap()[0].spacing, Spacing::Log);
    has(&check_metric("peak_robot_forse").unwrap_err().to_string(), &["close matches: peak_robot_force"]);
    check_metric("mode").unwrap();
}

#[test]
fn order_is_deterministic_and_row_major_on_any_thread_count() {
    let a = vec![Axis::parse("motion.speed=0.04:0.1:3", false).unwrap(), Axis::parse("motion.dead_time=0:0.05:3", false).unwrap()];
    let s = Sweep::new(&template(), a).unwrap();
    let one = s.run_with_jobs(Progress::Hidden, Some(1)).unwrap();
    let two = s.run_with_jobs(Progress::Hidden, Some(2)).unwrap();
    assert_eq!(one.csv(), two.csv());
    let rows: Vec<(f64, f64)> = one.points.iter().map(|p| (p.values[0], p.values[1])).collect();
    let want: Vec<(f64, f64)> = [0.04, 0.07, 0.1].iter().flat_map(|&v| [0.0, 0.025, 0.05].map(|d| (v, d))).collect();
    for (r, w) in rows.iter().zip(&want) {
        assert!((r.0 - w.0).abs() < 1e-12 && (r.1 - w.1).abs() < 1e-12, "{rows:?}");
    }
    assert_eq!(rows.len(), 9);
    // The CSV: header with the swept keys, every summary field, status and reason; one row a point.
    let csv = one.csv();
    let header = csv.lines().next().unwrap();
    assert!(header.starts_with("motion.speed,motion.dead_time,scene,name_mismatches,t_contact,"), "{header}");
    assert!(header.ends_with(",status,reason"), "{header}");
    for f in ["peak_contact_force", "peak_robot_force", "mode", "stroke_exhausted", "max_travel", "warnings"] {
        assert!(header.split(',').any(|h| h == f), "{f} missing from {header}");
    }
    assert_eq!(csv.lines().count(), 10);
}

#[test]
fn one_axis_sweep_matches_single_runs() {
    let t = template();
    let a = vec![Axis::parse("motion.speed=0.03:0.12:4", false).unwrap()];
    let r = Sweep::new(&t, a).unwrap().run(Progress::Hidden);
    let peaks = r.metric("peak_contact_force");
    // Fig. 42: the peak contact force grows with V_c (while the flange reaches V_c before contact).
    assert!(peaks.windows(2).all(|w| w[1] > w[0]), "{peaks:?}");
    for p in &r.points {
        // The same scene edited by hand and run alone gives the same summary.
        let text = std::fs::read_to_string(scene_path("tables5-7_bistable.toml")).unwrap();
        let edited = text.replace("speed = 0.05 ", &format!("speed = {} ", p.values[0]));
        let alone = sim::run(&scene::parse(&edited, "x.toml").unwrap(), false).unwrap().0;
        assert_eq!(p.outcome.as_ref().unwrap().peak_contact_force, alone.peak_contact_force);
        assert_eq!(p.outcome.as_ref().unwrap().mode, alone.mode);
    }
    let dir = std::env::temp_dir().join(format!("flinch-sweep-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let svg = dir.join("one.svg");
    plot::draw(&svg, &r, "peak_robot_force").unwrap();
    let s = std::fs::read_to_string(&svg).unwrap();
    assert!(s.contains("peak contact force") && s.contains("working mode"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn two_axis_sweep_finds_the_working_modes_and_draws_them() {
    let t = template();
    let a = vec![Axis::parse("motion.speed=0.05:0.14:3", false).unwrap(), Axis::parse("motion.dead_time=0.0:0.1:3", false).unwrap()];
    let r = Sweep::new(&t, a).unwrap().run(Progress::Hidden);
    assert_eq!(r.failures(), 0);
    // Slow and prompt: mode 1 (Fig. 49, lower left); fast and late: the back stop is reached.
    assert_eq!(r.at(&[0, 0]).unwrap().mode, Some(1));
    assert!(r.at(&[2, 2]).unwrap().mode.unwrap() >= 2, "{:?}", r.at(&[2, 2]));
    let dir = std::env::temp_dir().join(format!("flinch-sweep-test2-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let svg = dir.join("two.svg");
    plot::draw(&svg, &r, "peak_robot_force").unwrap();
    let s = std::fs::read_to_string(&svg).unwrap();
    assert!(s.contains("mode 1") && s.contains("peak_robot_force"), "the heat map labels its mode regions");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn integer_keys_stay_integers_and_absent_optional_keys_can_be_swept() {
    let t = template();
    let s = Sweep::new(&t, vec![Axis::parse("decoupler.springs=1:2:2", false).unwrap()]).unwrap();
    assert!(matches!(s.scene(1).decoupler, scene::Decoupler::Bistable(b) if b.springs == 2));
    // solver.rtol is not in the file; the validator accepts it, so it can be swept.
    let s = Sweep::new(&t, vec![Axis::parse("solver.rtol=1e-8:1e-6:2", false).unwrap()]).unwrap();
    assert_eq!(s.scene(0).solver.rtol, 1e-8);
}

#[test]
fn metrics_cover_every_numeric_summary_field() {
    use flinch_harness::sweep::{summary_fields, METRICS};
    let mut numeric = std::collections::BTreeSet::new();
    let mut names = std::collections::BTreeSet::new();
    for f in ["table12_hydraulic_object.toml", "tables5-7_bistable.toml"] {
        let s = sim::run(&scene::load(&scene_path(f)).unwrap(), false).unwrap().0;
        for (k, v) in summary_fields(&s) {
            if v.is_number() || v.is_boolean() {
                numeric.insert(k.clone());
            }
            names.insert(k);
        }
    }
    for m in METRICS {
        assert!(names.contains(*m), "METRICS names {m}, which the summary lacks");
    }
    for n in &numeric {
        assert!(METRICS.contains(&n.as_str()), "summary field {n} is numeric but not in METRICS");
    }
}
