//! One definition of "safe" (host-harness/crates/sim/src/verdict.rs, docs/verdicts.md): the contradictions of
//! issue 17 as tests. Each would fail on the code before the verdict module: `check` said FITS
//! beside a travel beyond the stroke with no reason, `design` called a speed safe next to a
//! negative "closest approach", and printed raw floats among mm values.

use flinch_harness::check::check;
use flinch_harness::design::{design, human};
use flinch_harness::sim;
use flinch_harness::sweep::Template;
use flinch_harness::verdict;
use flinch_tests::scene_path;

fn scene(name: &str) -> flinch_harness::scene::Scene {
    flinch_harness::shipped::load(&scene_path(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn shipped() -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(scene_path("")).unwrap().filter_map(|e| e.ok()).map(|e| e.file_name().to_string_lossy().into_owned()).filter(|n| n.ends_with(".toml") && !n.starts_with("avoid_")).collect();
    v.sort();
    v
}

#[test]
fn one_definition_on_every_shipped_scene() {
    for name in shipped() {
        let sc = scene(&name);
        let (s, _) = sim::run(&sc, false).unwrap_or_else(|e| panic!("{name}: {e}"));
        // safe <=> no failure <=> the stroke is not exhausted (and, for a body region, its
        // ISO/TS 15066 limits hold).
        assert_eq!(s.safe, s.failures.is_empty(), "{name}");
        assert_eq!(s.safe, s.concluded && !s.stroke_exhausted && s.body_limits_pass != Some(false), "{name}: {:?}", s.failures);
        // The stroke left while touching is negative exactly when the stroke is exhausted (0 for a
        // rigid tool, which is exhausted on contact).
        match s.stroke_left_min_m {
            Some(l) => assert_eq!(s.stroke_exhausted, l < 0.0 || (l == 0.0 && s.t_contact.is_some()), "{name}: {l}"),
            None => assert!(s.stroke_left_min_m_null_reason.is_some() && !s.stroke_exhausted, "{name}"),
        }
        // Closest approach = stroke left - deformation, so never above the stroke left.
        if let (Some(c), Some(l)) = (s.closest_approach_m, s.stroke_left_min_m) {
            assert!(c <= l + 1e-12, "{name}: {c} > {l}");
        }
        // check agrees with the run and with its own budget.
        if let Ok(c) = check(&sc) {
            assert_eq!(c.simulated.safe, s.safe, "{name}");
            assert_eq!(c.safe, c.fits && s.safe, "{name}");
            assert_eq!(c.safe, c.failures.is_empty(), "{name}");
        }
    }
}

/// Review finding (issue 14): with a dead time longer than the run, the robot was still driving
/// the tool into the target when the run ended, and the run said SAFE (so did every such sample of
/// `flinch sample`). The same scene run long enough exhausts the stroke: the short run must not be
/// called safe, and must say why.
#[test]
fn a_run_that_ends_before_the_robot_stops_is_not_safe() {
    let mut sc = scene("tables5-7_bistable.toml");
    sc.motion.dead_time = 0.6;
    let (short, _) = sim::run(&sc, false).unwrap();
    assert!(short.t_stop.unwrap() > sc.duration_s, "the case needs t_stop after the end: {:?}", short.t_stop);
    assert!(!short.concluded && !short.safe, "{:?}", short.failures);
    assert!(short.failures[0].starts_with("not concluded"), "{:?}", short.failures);
    assert!(verdict::line(&short).contains("NOT SAFE: not concluded"), "{}", verdict::line(&short));
    // Long enough to see the end: the robot stops, the run concludes, and the stroke ran out.
    sc.duration_s = 3.0;
    let (long, _) = sim::run(&sc, false).unwrap();
    assert!(long.concluded && long.t_stop.unwrap() <= 3.0, "{:?}", long.t_stop);
    assert!(long.stroke_exhausted && !long.safe, "{:?}", long.failures);
    // A dead time that fits in the run: concluded, and the verdict is the stroke's.
    sc.motion.dead_time = 0.016;
    sc.duration_s = 0.6;
    let (ok, _) = sim::run(&sc, false).unwrap();
    assert!(ok.concluded && ok.safe, "{:?}", ok.failures);
    // The searches of design lengthen a candidate's duration until it concludes, and say so.
    sc.motion.dead_time = 0.6;
    let searched = sim::run_to_conclusion(&sc).unwrap();
    assert!(searched.concluded && searched.stroke_exhausted && !searched.safe, "{:?}", searched.failures);
    assert!(searched.warnings.iter().any(|w| w.contains("duration lengthened from 0.6 s to 1.2 s")), "{:?}", searched.warnings);
    // check and design agree with the run's verdict on the short run.
    sc.motion.dead_time = 0.6;
    if let Ok(c) = check(&sc) {
        assert!(!c.safe && !c.simulated.concluded, "check called a run that never concluded safe");
    }
}

/// Review of the merge (2026-11-26): a soft arm (k_r = 1,000 N/m, undamped) stopped at 0.27 s
/// rings on and runs out of stroke at about 0.37 s; a run cut at 0.35 s (after t_stop) was
/// called concluded and SAFE by run, check and hil, and `flinch sample` counted such runs safe.
#[test]
fn a_compliant_arm_still_ringing_at_the_end_is_not_concluded() {
    let text = std::fs::read_to_string(scene_path("tables5-7_bistable.toml"))
        .unwrap()
        .replace("speed = 0.05 ", "speed = 0.2 ")
        .replace("decel = 2.0 ", "decel = 20.0 ")
        .replace("stiffness = 2.3e5 ", "stiffness = 1000.0 ")
        .replace("damping = 71.0 ", "damping = 0.0 ");
    let t = Template::from_text(&text, "soft_arm.toml").unwrap();
    let mut sc = t.base.clone();
    sc.duration_s = 0.35;
    let (short, _) = sim::run(&sc, false).unwrap();
    assert!(short.t_stop.unwrap() < 0.35 && !short.stroke_exhausted, "the case: stopped before the end, stroke not yet exhausted: {:?}", short.t_stop);
    assert!(!short.concluded && !short.safe, "{:?}", short.failures);
    assert!(short.failures[0].contains("had not settled") && short.flange_reach_after_end_m > 0.01, "{:?}", short.failures);
    if let Ok(c) = check(&sc) {
        assert!(!c.safe, "check called the cut-off run safe");
    }
    // The same arm run on: the stroke runs out.
    sc.duration_s = 0.6;
    assert!(sim::run(&sc, false).unwrap().0.stroke_exhausted);
    // The shipped arm (Table 7: 2.3e5 N/m, 71 N s/m, a 38 ms period) settles within the run.
    let (ok, _) = sim::run(&scene("tables5-7_bistable.toml"), false).unwrap();
    assert!(ok.concluded && ok.safe && ok.flange_reach_after_end_m < 1e-4, "{:?} {}", ok.failures, ok.flange_reach_after_end_m);
}

#[test]
fn a_rigid_tool_is_not_safe() {
    let (s, _) = sim::run(&scene("tables5-7_rigid.toml"), false).unwrap();
    assert!(!s.safe && s.stroke_exhausted);
    assert_eq!(s.stroke_left_min_m, Some(0.0));
    assert!(s.failures[0].contains("rigid tool"), "{:?}", s.failures);
}

#[test]
fn travel_beyond_the_stroke_is_explained() {
    // Issue 17: "budget fits by 5.37 mm while the simulated travel is 31.39 mm on a 30 mm stroke".
    // The tool bounced off the hard surface and rode into the compliant back end-stop while not
    // touching it: safe, and the output says why.
    let c = check(&scene("tables5-7_bistable_v025.toml")).unwrap();
    assert!(c.fits && c.simulated.max_travel > c.stroke + 1e-3);
    assert!(c.safe && c.simulated.stroke_left_min_m.unwrap() > 1e-3);
    assert!(c.explanations.iter().any(|e| e.contains("NOT touching") && e.contains("back end-stop")), "{:?}", c.explanations);
    assert!(flinch_harness::check::human(&c).contains("why: the travel 31.39 mm exceeds the stroke 30.00 mm"));
}

#[test]
fn a_free_object_pushed_away_is_explained_and_the_budget_still_fails_safe() {
    // Issue 17: "DOES NOT FIT by 148.50 mm while the simulation shows the free object is pushed away".
    let c = check(&scene("table12_hydraulic_object.toml")).unwrap();
    assert!(!c.fits && c.simulated.safe);
    assert!(!c.safe, "the budget's verdict stands: fail safe");
    assert!(c.explanations.iter().any(|e| e.contains("free object") && e.contains("pushed away")), "{:?}", c.explanations);
    // The explanation must not contradict the verdict it explains: the budget's verdict stands.
    let why = c.explanations.iter().find(|e| e.contains("free object")).unwrap();
    assert!(why.contains("fail-safe: the budget's verdict stands") && !why.contains("is what applies"), "{why}");
    // A tool that ran past its stroke is not said to have travelled "only" so far.
    let c = check(&scene("table13_bistable_object.toml")).unwrap();
    assert!(c.simulated.stroke_exhausted && !c.safe);
    assert!(c.explanations.iter().all(|e| !e.contains("travelled only")), "{:?}", c.explanations);
}

#[test]
fn budget_fits_but_stroke_exhausted_is_not_safe() {
    // The worst case: a budget that fits must never hide an exhausted simulated stroke.
    let sc = scene("tables5-7_bistable.toml");
    let (mut s, _) = sim::run(&sc, false).unwrap();
    s.stroke_exhausted = true;
    s.stroke_left_min_m = Some(-1e-4);
    let f = verdict::failures(&s);
    assert_eq!(f.len(), 1);
    assert!(f[0].contains("stroke exhausted") && f[0].contains("0.10 mm"), "{f:?}");
    let b = verdict::Budget { stroke: 0.03, switch_travel: 0.005, stopping_distance: 0.001 };
    assert!(b.fits());
    assert!(verdict::explain(&sc, &b, &s).iter().any(|e| e.contains("NOT SAFE")));
}

#[test]
fn design_safe_means_what_check_means_and_the_curve_agrees() {
    // Issue 17: design called 0.182 m/s safe beside "stops -1.89 mm short of the target". Now the
    // speed limit is where the stroke left while touching crosses zero; the closest approach to
    // the undeformed (soft) target may be negative there and is printed as such, with its reason.
    let t = Template::load(&scene_path("table14_hydraulic_surface.toml")).unwrap();
    let r = design(&t, None, None, None).unwrap();
    let c = check(&t.base).unwrap();
    assert_eq!(r.safe, c.safe);
    assert_eq!(r.failures, c.failures);
    let at = r.at_limit.as_ref().expect("limit found");
    assert!(at.summary.safe);
    let left = at.summary.stroke_left_min_m.unwrap();
    assert!((0.0..0.3e-3).contains(&left), "stroke left at the limit {left}");
    // Just past the limit the stroke is exhausted.
    let v = r.speed_limit_simulated.unwrap();
    let past = design(&t, None, Some(v * 1.02), None).unwrap();
    assert!(!past.design.summary.safe && past.design.summary.stroke_left_min_m.unwrap() < 0.0);
    assert!(r.speed_limit_mps.unwrap() <= r.speed_limit_formula);
    let text = human(&r);
    assert!(text.contains("closest approach to the undeformed target -"), "{text}");
}

#[test]
fn design_prints_no_raw_floats() {
    // Issue 17: "smallest candidate 0.005268500000000001" among mm values. No number a person
    // reads has more than three decimals.
    let t = Template::load(&scene_path("tables5-7_bistable.toml")).unwrap();
    for dt in [None, Some(0.07)] {
        let text = human(&design(&t, None, None, dt).unwrap());
        let b = text.as_bytes();
        for i in 1..b.len() {
            if b[i] == b'.' && b[i - 1].is_ascii_digit() {
                let decimals = b[i + 1..].iter().take_while(|c| c.is_ascii_digit()).count();
                assert!(decimals <= 3, "{} in\n{text}", &text[i.saturating_sub(8)..(i + 1 + decimals).min(text.len())]);
            }
        }
    }
}
