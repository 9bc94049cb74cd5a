//! docs/validation.md is generated (`flinch validate --out docs/`): recompute every number in it
//! from the simulator and fail if the committed document differs, so it cannot drift from the code.

use flinch_harness::validate::{markdown, plots, tables, Section, Verdict};
use std::path::PathBuf;
use std::sync::OnceLock;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The validation tables of the shipped scenes, computed once for this binary: the two tests below
/// read the same tables (`tables` is deterministic), and computing them was most of this binary's
/// CPU time, twice (issue 28: `every_difference_is_explained` alone took 213 s on one thread).
fn sections() -> &'static [Section] {
    static SECTIONS: OnceLock<Result<Vec<Section>, String>> = OnceLock::new();
    SECTIONS.get_or_init(|| tables(&root().join("scenes"))).as_ref().unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn validation_doc_is_up_to_date() {
    let sections = sections();
    let fresh = markdown(sections);
    let path = root().join("docs/validation.md");
    let committed = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}; run `flinch validate --out docs/`", path.display()));
    if fresh != committed {
        let first = fresh.lines().zip(committed.lines()).enumerate().find(|(_, (a, b))| a != b);
        match first {
            Some((i, (a, b))) => panic!("docs/validation.md is out of date (run `flinch validate --out docs/` and commit); first difference at line {}:\n  now:       {a}\n  committed: {b}", i + 1),
            None => panic!("docs/validation.md is out of date: {} lines now, {} committed; run `flinch validate --out docs/`", fresh.lines().count(), committed.lines().count()),
        }
    }
    for p in plots(sections) {
        assert!(root().join("docs").join(&p).is_file(), "docs/{p} is referenced but missing; run `flinch validate --out docs/`");
    }
}

#[test]
fn every_difference_is_explained() {
    for s in sections() {
        assert!(!s.rows.is_empty() && !s.commands.is_empty() && !s.plots.is_empty(), "{}", s.title);
        if s.rows.iter().any(|r| r.verdict == Verdict::Differs) {
            assert!(!s.notes.is_empty(), "{}: a row differs and no note says why", s.title);
        }
    }
}

/// A shipped scene recorded every `dt` seconds.
fn recorded(name: &str, dt: f64) -> (flinch_harness::sim::Summary, Vec<flinch_harness::sim::Sample>) {
    let mut s = flinch_harness::scene::load(&root().join("scenes").join(name)).unwrap_or_else(|e| panic!("{e}"));
    s.solver.output_interval = dt;
    flinch_harness::sim::run(&s, true).unwrap_or_else(|e| panic!("{name}: {e}"))
}

#[test]
fn fig76_evidence_the_hydraulic_peak_is_eq28_jumping_at_the_front_stop_return() {
    use flinch_harness::validate::front_stop_return;
    let (s, h) = recorded("table12_hydraulic_object_dt10.toml", 1e-5);
    let tc = s.t_contact.unwrap();
    let (on, before) = front_stop_return(&h, tc).expect("the tool returns onto the front stop");
    // Issue 15: at +80 ms, s' about 0.147 m/s, c_fe s' = 235 x 0.147 = 34.5 N.
    assert!(((on.t - tc) - 0.080).abs() < 0.002, "return at +{} s", on.t - tc);
    let sd = before.v_t - before.v_r;
    assert!((sd - 0.147).abs() < 0.003, "s' {sd}");
    assert!(before.f_robot.abs() < 1.0 && (on.f_robot - 235.0 * sd).abs() < 0.02 * 235.0 * sd, "jump {} -> {} N, c_fe s' = {}", before.f_robot, on.f_robot, 235.0 * sd);
    assert!((on.f_robot - s.peak_robot_force).abs() < 0.02 * s.peak_robot_force, "the jump is the run's peak");
}

#[test]
fn table4_evidence_two_hits_and_braking_between_or_inside_them() {
    use flinch_harness::validate::hits;
    for (name, second_on, braking_before_second) in [("table4_bistable_136g.toml", 0.0968, true), ("table4_bistable_246g.toml", 0.0620, false)] {
        let (s, h) = recorded(name, 1e-5);
        let tc = s.t_contact.unwrap();
        let hs = hits(&h);
        assert_eq!(hs.len(), 2, "{name}: {hs:?}");
        assert!(((hs[1].on_s - tc) - second_on).abs() < 0.001, "{name}: second hit at +{}", hs[1].on_s - tc);
        assert!(hs[0].object_mps < 0.6 && hs[1].object_mps > hs[0].object_mps, "{name}: the second hit does most of the work {hs:?}");
        assert_eq!(s.t_brake.unwrap() < hs[1].on_s, braking_before_second, "{name}");
    }
    // And the document must not claim the thesis's account holds.
    let sections = tables(&root().join("scenes")).unwrap();
    let t4 = sections.iter().find(|s| s.title.starts_with("Table 4")).unwrap();
    let row = t4.rows.iter().find(|r| r.quantity.contains("detached")).unwrap();
    assert_eq!(row.verdict, Verdict::Differs);
}

/// A shipped scene with `law = "hunt-crossley"` added to its front stop, recorded every `dt`.
fn recorded_hunt_crossley(name: &str, dt: f64) -> (flinch_harness::sim::Summary, Vec<flinch_harness::sim::Sample>) {
    let text = std::fs::read_to_string(root().join("scenes").join(name)).unwrap();
    let from = "front_stop = { stiffness = 1e6, damping = 235.0 }";
    assert!(text.contains(from), "{name}");
    let mut s = flinch_harness::scene::parse(&text.replace(from, "front_stop = { stiffness = 1e6, damping = 235.0, law = \"hunt-crossley\" }"), name).unwrap_or_else(|e| panic!("{e}"));
    s.solver.output_interval = dt;
    flinch_harness::sim::run(&s, true).unwrap_or_else(|e| panic!("{name}: {e}"))
}

#[test]
fn fig76_under_hunt_crossley_the_jump_is_gone_but_the_landing_peak_is_not_smaller() {
    use flinch_harness::validate::front_stop_return;
    for name in ["table12_hydraulic_object_dt10.toml", "table12_hydraulic_object.toml"] {
        let (lin, hl) = recorded(name, 1e-5);
        let (hc, hh) = recorded_hunt_crossley(name, 1e-5);
        let tc = lin.t_contact.unwrap();
        let (on_l, _) = front_stop_return(&hl, tc).unwrap();
        let (on_h, before_h) = front_stop_return(&hh, tc).unwrap();
        // eq 28 jumps to its peak between two samples; Hunt-Crossley starts near zero and rises.
        assert!(on_l.f_robot > 0.95 * lin.peak_robot_force, "{name}: eq 28 at landing {} N", on_l.f_robot);
        assert!(on_h.f_robot < 0.25 * on_l.f_robot && before_h.f_robot.abs() < 1.5, "{name}: Hunt-Crossley at landing {} N (before {})", on_h.f_robot, before_h.f_robot);
        // Same energy loss taken later: the landing's peak is larger, not smaller (docs/validation.md).
        assert_eq!(hc.peak_robot_force_event, "front_stop", "{name}");
        assert!(hc.peak_robot_force > lin.peak_robot_force && hc.peak_robot_force < 1.3 * lin.peak_robot_force, "{name}: {} vs {}", hc.peak_robot_force, lin.peak_robot_force);
        // The first impact (orifice) does not depend on the front stop's law.
        let (f_l, f_h) = (lin.first_impact_peak_robot_force_n.unwrap(), hc.first_impact_peak_robot_force_n.unwrap());
        assert!((f_h / f_l - 1.0).abs() < 0.01, "{name}: first impact {f_l} vs {f_h}");
        // The tool comes back to rest on the stop under both laws.
        let end = |h: &[flinch_harness::sim::Sample]| h.last().unwrap().s;
        assert!((end(&hh) - end(&hl)).abs() < 1e-5, "{name}: rest {} vs {}", end(&hh), end(&hl));
    }
}

#[test]
fn shipped_variants_are_the_ones_the_document_describes() {
    // The Hunt-Crossley Fig. 76a scene is table12_hydraulic_object_dt10 with only the law added.
    let (shipped, _) = recorded("figures/fig76_hydraulic_hunt_crossley.toml", 1e-3);
    let (made, _) = recorded_hunt_crossley("table12_hydraulic_object_dt10.toml", 1e-3);
    assert_eq!(shipped.peak_robot_force, made.peak_robot_force);
    assert_eq!(shipped.first_impact_peak_robot_force_n, made.first_impact_peak_robot_force_n);
    // The H = 45 mm _detached scenes: Table 3's other height, far from the measured peaks.
    for (m, measured, sd) in [(136, 1.231, 0.054), (246, 1.430, 0.040)] {
        let (h45, _) = recorded(&format!("figures/table4_bistable_{m}g_detached_h45.toml"), 1e-3);
        let (h53, _) = recorded(&format!("figures/table4_bistable_{m}g_detached.toml"), 1e-3);
        let (p45, p53) = (h45.object_peak_velocity.unwrap(), h53.object_peak_velocity.unwrap());
        assert!((p53 - measured).abs() <= 2.0 * sd, "{m} g at 53 mm: {p53}");
        assert!((p45 - measured).abs() > 2.0 * sd, "{m} g at 45 mm: {p45}");
    }
}
