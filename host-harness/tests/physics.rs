//! Physics that must not pass quietly (issue 26 item 6): a decoupler that holds nothing, a flange
//! that passes through the tool, a peak force no robot tool can see. Each case failed before:
//! k = 0 was accepted and ran SAFE with the flange 0.5 m through the tool, k = 0.1 N/m ran SAFE,
//! and a front stop damped at 1e5 N s/m gave 78.9 kN on a 0.125 kg tool with no note.

mod common;
use common::{flinch, text};
use flinch_harness::overrides::{self, Set};
use flinch_harness::sim;

fn scene(name: &str, sets: &[&str]) -> Result<flinch_harness::scene::Scene, String> {
    let sets: Vec<Set> = sets.iter().map(|s| Set::parse(s).unwrap()).collect();
    overrides::apply(name, flinch_harness::shipped::get(name).unwrap().to_string(), &sets).map(|l| l.scene)
}

#[test]
fn a_linear_decoupler_that_holds_nothing_is_refused() {
    let e = scene("table2_linear", &["decoupler.stiffness=0"]).unwrap_err();
    assert!(e.contains("decoupler.stiffness: 0 holds the tool to nothing") && e.contains("motion.start_at_speed = true"), "{e}");
    // The free tool of Fig. 1b / 4b, already cruising with the flange, stays accepted.
    for ok in ["table1_free_tool", "figures/fig2_free_tool"] {
        scene(ok, &[]).unwrap_or_else(|e| panic!("{ok}: {e}"));
    }
    let o = flinch().args(["run", "table2_linear", "--set", "decoupler.stiffness=0"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
}

#[test]
fn a_flange_that_passes_through_the_tool_fails_the_run() {
    // k = 0.1 N/m is accepted, but holds the 0.125 kg tool to nothing at 1 m/s: the flange runs
    // 330 mm past a tool that never caught up.
    let (s, _) = sim::run(&scene("table2_linear", &["decoupler.stiffness=0.1"]).unwrap(), false).unwrap();
    assert!(s.max_travel > 0.2, "{}", s.max_travel);
    assert!(!s.safe);
    assert!(s.failures.iter().any(|f| f.starts_with("the flange passed through the tool")), "{:?}", s.failures);
    // The shipped stiffness holds: no such failure.
    let (s, _) = sim::run(&scene("table2_linear", &[]).unwrap(), false).unwrap();
    assert!(!s.failures.iter().any(|f| f.contains("passed through")), "{:?}", s.failures);
}

#[test]
fn an_implausible_peak_force_carries_a_warning() {
    let (s, _) = sim::run(&scene("table2_bistable", &["decoupler.front_stop={ stiffness = 1e6, damping = 1e5 }"]).unwrap(), false).unwrap();
    assert!(s.peak_robot_force > 5e4, "{}", s.peak_robot_force);
    let w = s.warnings.iter().find(|w| w.contains("sanity bound")).unwrap_or_else(|| panic!("no warning: {:?}", s.warnings));
    assert!(w.contains("from the front end-stop") && w.contains("decoupler.front_stop"), "{w}");
}

/// Every shipped scene: no sanity warning, no pass-through (the bounds are not tuned to fire on
/// the thesis's own parameters).
#[test]
fn no_shipped_scene_trips_the_new_checks() {
    let mut ran = 0;
    for name in flinch_harness::shipped::names() {
        let Ok(sc) = scene(name, &[]) else { continue };
        let Ok((s, _)) = sim::run(&sc, false) else { continue };
        ran += 1;
        assert!(!s.warnings.iter().any(|w| w.contains("sanity bound")), "{name}: {:?}", s.warnings);
        assert!(!s.failures.iter().any(|f| f.contains("passed through")), "{name}: {:?}", s.failures);
    }
    assert!(ran > 30, "{ran}");
}
