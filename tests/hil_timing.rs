//! `flinch hil`'s timing model (issue 26 item 2): the dead time from the switch to braking is the
//! board's latency + the wait for the controller's scan sample + the robot's reaction, the reaction
//! being `[controller] reaction_time` or, by default, the scene's `motion.dead_time` less one scan.
//! Before, `hil` braked at the sample itself and ignored `motion.dead_time` (identical results for
//! 0, 30 and 200 ms): a safety answer that silently differed from what was asked.

use flinch_harness::scene::{self, Controller, Scene};
use flinch_harness::{hil, sim};
use flinch_tests::scene_path;

const SCAN: f64 = 0.016;

fn load(name: &str) -> Scene {
    scene::load(&scene_path(name)).unwrap_or_else(|e| panic!("{e}"))
}

fn hil_run(sc: &Scene, ctl: &Controller) -> hil::HilReport {
    hil::run(sc, ctl, false).unwrap_or_else(|e| panic!("{e}")).0
}

/// The phase whose sample comes 0.1 ms before the switch: the stop is seen one scan later, the
/// worst case less 0.1 ms (which keeps the sample on its side of the crossing whatever the solver's
/// error).
fn worst_phase(sc: &Scene) -> f64 {
    let t_sw = sim::run(sc, false).unwrap().0.t_detect.unwrap();
    ((t_sw - 1e-4) / SCAN).rem_euclid(1.0)
}

/// The trap of the issue: with 0, 30 and 200 ms of `motion.dead_time` the old `hil` gave one
/// result. Now braking comes the reaction after the sample that saw the stop, the reaction being
/// DT less one scan (0 when DT is shorter, with a warning).
#[test]
fn hil_honours_the_scenes_dead_time() {
    let base = load("tables5-7_bistable.toml");
    let ctl = Controller::new(SCAN, 0.0, 1e-4);
    let mut brakes = Vec::new();
    for dt in [0.0, 0.03, 0.2] {
        let mut sc = base.clone();
        sc.motion.dead_time = dt;
        let h = hil_run(&sc, &ctl);
        let f = &h.firmware;
        let want = (dt - SCAN).max(0.0);
        assert_eq!(f.dead_time_model.reaction_time_s, want, "DT {dt}");
        let t_brake = h.summary.t_brake.unwrap();
        assert!((t_brake - (f.stop_seen.unwrap() + want)).abs() < 1e-9, "DT {dt}: braking at {t_brake}, sample {:?}", f.stop_seen);
        let parts = f.dead_time_model.stop_output_latency_s.unwrap() + f.dead_time_model.scan_wait_s.unwrap() + want;
        assert!((f.dead_time_model.observed_s.unwrap() - parts).abs() < 1e-9, "{:?}", f.dead_time_model);
        assert_eq!(f.dead_time_model.observed_s, f.observed_dead_time);
        assert!((f.dead_time_model.worst_case_s - (flinch_hal_sim::latency::edge_to_stop_s() + SCAN + want)).abs() < 1e-12);
        let warned = h.summary.warnings.iter().any(|w| w.contains("shorter than the scan cycle"));
        assert_eq!(warned, dt < SCAN, "DT {dt}: {:?}", h.summary.warnings);
        brakes.push((t_brake, h.summary.max_travel));
    }
    assert!(brakes.windows(2).all(|w| w[1].0 > w[0].0 + 0.01 && w[1].1 > w[0].1), "later braking, more travel: {brakes:?}");
}

#[test]
fn changing_the_reaction_time_changes_the_result() {
    let sc = load("tables5-7_bistable.toml");
    let mut out = Vec::new();
    for r in [0.0, 0.005, 0.05] {
        let mut ctl = Controller::new(SCAN, 0.3, 1e-4);
        ctl.reaction_time = Some(r);
        let h = hil_run(&sc, &ctl);
        let f = &h.firmware;
        assert_eq!(f.dead_time_model.reaction_time_source, "controller.reaction_time");
        assert!((h.summary.t_brake.unwrap() - f.stop_seen.unwrap() - r).abs() < 1e-9);
        // DT = 16 ms is the scan alone: any reaction but 0 contradicts it, and the run says so.
        let warned = h.summary.warnings.iter().any(|w| w.contains("differs from motion.dead_time"));
        assert_eq!(warned, r > 0.0, "{:?}", h.summary.warnings);
        out.push((f.stop_seen, h.summary.t_brake.unwrap(), h.summary.t_stop.unwrap(), h.summary.max_travel));
    }
    // The same sample sees the stop; what follows it moves by the reaction.
    assert!(out.iter().all(|o| o.0 == out[0].0));
    assert!((out[2].1 - out[0].1 - 0.05).abs() < 1e-9 && (out[2].2 - out[0].2 - 0.05).abs() < 1e-9, "{out:?}");
    assert!(out.windows(2).all(|w| w[1].3 > w[0].3), "more travel with a slower reaction: {out:?}");
}

/// The example: "16 ms scan + 30 ms brake reaction" on Tables 5-7 at 0.25 m/s. `run` with
/// DT = 46 ms exhausts the stroke; so must `hil` at the worst phase, both with the reaction given
/// and with DT = 46 ms split by default. With no reaction (the old `hil`) the stroke holds.
#[test]
fn sixteen_ms_scan_and_thirty_ms_reaction_exhaust_the_stroke_as_run_does_with_46_ms() {
    let mut sc = load("tables5-7_bistable_v025.toml");
    let phase = worst_phase(&sc);
    let mut given = Controller::new(SCAN, phase, 1e-4);
    given.reaction_time = Some(0.03);
    let h = hil_run(&sc, &given);
    assert!(h.summary.stroke_exhausted && !h.summary.safe, "{}", h.firmware.dead_time_model.formed);
    // The firmware budgets the same dead time: 0.25 x 46 ms + 15.6 mm > the 25 mm left.
    assert!(h.firmware.category0);
    let observed = h.firmware.dead_time_model.observed_s.unwrap();
    assert!((observed - (0.046 - 1e-4)).abs() < 1e-5, "{observed}");

    sc.motion.dead_time = 0.046;
    let plain = sim::run(&sc, false).unwrap().0;
    assert!(plain.stroke_exhausted && !plain.safe);
    let split = hil_run(&sc, &Controller::new(SCAN, phase, 1e-4));
    assert_eq!(split.firmware.dead_time_model.reaction_time_source, "motion.dead_time - scan_cycle");
    assert!((split.firmware.dead_time_model.reaction_time_s - 0.03).abs() < 1e-12);
    assert!(split.summary.stroke_exhausted && split.summary.warnings.iter().all(|w| !w.starts_with("dead time")), "{:?}", split.summary.warnings);

    // What the old hil did: the reaction dropped, the stroke holds, the verdict is "safe".
    let mut none = given;
    none.reaction_time = Some(0.0);
    let old = hil_run(&load("tables5-7_bistable_v025.toml"), &none);
    assert!(!old.summary.stroke_exhausted && !old.firmware.category0);
}

/// Over the phases of the scan, the observed dead time runs from the board's latency plus the
/// reaction to the worst case the report gives, never beyond.
#[test]
fn the_worst_case_bounds_the_observed_dead_time_over_phases() {
    let mut sc = load("tables5-7_bistable.toml");
    sc.motion.dead_time = 0.046;
    let mut seen = Vec::new();
    for i in 0..8 {
        let h = hil_run(&sc, &Controller::new(SCAN, (i as f64 + 0.5) / 8.0, 1e-4));
        let d = &h.firmware.dead_time_model;
        let o = d.observed_s.unwrap();
        assert!(o >= d.reaction_time_s + flinch_hal_sim::latency::edge_to_stop_s() - 1e-9 && o <= d.worst_case_s + 1e-9, "{d:?}");
        seen.push(o);
    }
    let spread = seen.iter().cloned().fold(f64::MIN, f64::max) - seen.iter().cloned().fold(f64::MAX, f64::min);
    assert!(spread > 0.75 * SCAN, "the phase moves the wait across the scan: {seen:?}");
}

/// With the robot's stopping table, the reaction ends at the table's stop signal and the table's
/// own dead time follows, as in `flinch run`.
#[test]
fn with_a_stopping_table_the_reaction_comes_before_the_table() {
    let sc = load("tables5-7_bistable_stopping_table.toml");
    let mut ctl = Controller::new(SCAN, 0.0, 1e-4);
    let h0 = hil_run(&sc, &ctl);
    ctl.reaction_time = Some(0.02);
    let h = hil_run(&sc, &ctl);
    let d = &h.firmware.dead_time_model;
    assert!(d.stopping_table_dead_time_s > 0.0, "{d:?}");
    let want = h.firmware.stop_seen.unwrap() + 0.02;
    let t_brake = h.summary.t_brake.unwrap();
    assert!(t_brake > want, "braking after the table's dead time: {t_brake} vs the signal at {want}");
    assert!((t_brake - h0.summary.t_brake.unwrap() - 0.02).abs() < 2e-3, "{} vs {}", t_brake, h0.summary.t_brake.unwrap());
    assert!(d.formed.contains("stopping table"), "{}", d.formed);
}

#[test]
fn the_report_says_how_the_total_was_formed() {
    let mut sc = load("tables5-7_bistable.toml");
    sc.motion.dead_time = 0.046;
    let h = hil_run(&sc, &Controller::new(SCAN, 0.0, 1e-4));
    let text = hil::human(&h.firmware);
    let first = text.lines().next().unwrap();
    let worst = format!("worst case {:.3} ms", (flinch_hal_sim::latency::edge_to_stop_s() + 0.046) * 1e3);
    for part in ["dead time", "board", "scan wait", "robot reaction 30.000 ms", "motion.dead_time - scan_cycle", &worst, "motion.dead_time 46.000 ms"] {
        assert!(first.contains(part), "{part:?} missing from {first:?}");
    }
    let json = serde_json::to_value(&h.firmware).unwrap();
    let d = &json["dead_time_model"];
    for key in ["scan_cycle_s", "reaction_time_s", "reaction_time_source", "scene_dead_time_s", "worst_case_s", "stop_output_latency_s", "scan_wait_s", "observed_s", "formed"] {
        assert!(!d[key].is_null(), "firmware.dead_time_model.{key} missing: {d}");
    }
}

/// Issue 26 item 6: `hil` reported a negative firmware latency (-35 to -482 ns) on most shipped
/// scenes: the rig set the firmware's clock to the nearest whole microsecond of the edge, up to
/// 0.5 us before it. Now the firmware reads the first whole microsecond at or after the edge: on
/// every shipped scene `hil` accepts, at several phases and ticks, the latency is in [0, 1 us).
#[test]
fn the_firmware_latency_is_never_negative_on_any_shipped_scene() {
    let mut names: Vec<_> = std::fs::read_dir(scene_path("")).unwrap().flatten().map(|e| e.path()).filter(|p| p.extension().is_some_and(|x| x == "toml")).collect();
    names.sort();
    let mut checked = 0;
    for p in names {
        let Ok(sc) = scene::load(&p) else { continue };
        if hil::refusal(&sc).is_some() {
            continue;
        }
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        for (phase, tick) in [(0.0, 1e-4), (0.37, 1e-3), (0.91, 3.7e-5)] {
            let h = hil::run(&sc, &Controller::new(SCAN, phase, tick), false).unwrap_or_else(|e| panic!("{name}: {e}")).0;
            let f = &h.firmware;
            let Some(lat) = f.firmware_latency else { continue };
            assert!((0.0..1e-6).contains(&lat), "{name} (phase {phase}, tick {tick}): firmware latency {lat} s (switch {:?}, timestamp {:?})", f.switch_time, f.firmware_detect);
            if let Some(l) = f.dead_time_model.stop_output_latency_s {
                assert!(l >= 0.0, "{name}: stop output {l} s after the switch");
            }
            checked += 1;
        }
    }
    assert!(checked >= 30, "only {checked} runs had a detection");
}

/// `--worst-phase`: the sample before the stop output just missed it, so the dead time is the worst
/// case the report gives, whatever the switch instant; the example then exhausts the
/// stroke without the user placing the phase by hand.
#[test]
fn the_worst_phase_gives_the_worst_case_dead_time() {
    let mut sc = load("tables5-7_bistable_v025.toml");
    sc.motion.dead_time = 0.046;
    let opts = hil::HilOptions { worst_phase: true, ..Default::default() };
    for tick in [1e-4, 1e-3] {
        let h = hil::run_with(&sc, &Controller::new(SCAN, 0.0, tick), false, &opts).unwrap().0;
        let d = &h.firmware.dead_time_model;
        assert!(d.worst_phase && d.formed.contains("worst phase"), "{}", d.formed);
        assert!((d.scan_wait_s.unwrap() - SCAN).abs() < 1e-9, "{d:?}");
        assert!((d.observed_s.unwrap() - d.worst_case_s).abs() < 1e-6, "{d:?}");
        assert!(h.summary.stroke_exhausted, "{}", d.formed);
    }
    // And on the plain bistable scene, the worst phase brakes no sooner than any phase tried.
    let sc = load("tables5-7_bistable.toml");
    let worst = hil::run_with(&sc, &Controller::new(SCAN, 0.0, 1e-4), false, &opts).unwrap().0;
    for i in 0..8 {
        let h = hil_run(&sc, &Controller::new(SCAN, i as f64 / 8.0, 1e-4));
        assert!(h.summary.t_brake.unwrap() <= worst.summary.t_brake.unwrap() + 1e-9);
        assert!(h.summary.max_travel <= worst.summary.max_travel * (1.0 + 1e-3));
    }
}
