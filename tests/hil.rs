//! Firmware in the loop: the dead time that comes out of a scan-cycle controller (issue 3).
//!
//! Over the phases of the scan cycle the dead time spans [firmware latency, scan cycle + latency]
//! and is uniform; its worst case is the thesis's assumption DT = one scan cycle (Ch. 3.1.2), so
//! `flinch hil` at the worst phase must give the reaction time `flinch run` gives with DT = 16 ms.

use flinch_harness::scene::{self, Controller, Scene};
use flinch_harness::{hil, sim};
use flinch_tests::scene_path;

const SCAN: f64 = 0.016;

fn bistable() -> Scene {
    scene::load(&scene_path("tables5-7_bistable.toml")).unwrap_or_else(|e| panic!("{e}"))
}

fn hil_at(scene: &Scene, phase: f64) -> hil::HilReport {
    let ctl = Controller::new(SCAN, phase, 1e-4);
    hil::run(scene, &ctl, false).unwrap_or_else(|e| panic!("{e}")).0
}

#[test]
fn worst_phase_reproduces_flinch_run_with_one_scan_cycle_of_dead_time() {
    let sc = bistable();
    assert_eq!(sc.motion.dead_time, SCAN, "the scene's DT is the Viper's scan cycle");
    let plain = sim::run(&sc, false).unwrap().0;
    let t_sw = plain.t_detect.unwrap();
    // The controller sampled 0.1 ms before the switch fired: it sees the stop one cycle later, so
    // the dead time is one scan cycle less 0.1 ms (0.1 ms keeps the sample on the right side of the
    // crossing whatever the solver's error; the limit, a sample just before it, is DT = SCAN).
    const EARLY: f64 = 1e-4;
    let phase = ((t_sw - EARLY) / SCAN).fract();
    let h = hil_at(&sc, phase);
    let f = &h.firmware;
    // The two runs step differently (the lockstep lands on every controller sample), so they agree
    // to the solver's accuracy, not bit for bit: 1e-5 s on a 0.1 s detection delay.
    const SOLVER: f64 = 1e-5;
    assert!((f.switch_time.unwrap() - t_sw).abs() < SOLVER, "same plant, same crossing");
    let latency = f.firmware_latency.unwrap();
    // The firmware's clock counts whole microseconds and reads the first at or after the edge: its
    // timestamp is within 1 us after the edge, never before.
    assert!((0.0..1e-6).contains(&latency), "edge to timestamp: {latency}");
    let dt = f.observed_dead_time.unwrap();
    assert!((dt - (SCAN - EARLY)).abs() < SOLVER, "worst-case dead time {dt}");
    let dr = h.summary.reaction_time.unwrap() - (plain.reaction_time.unwrap() - EARLY);
    assert!(dr.abs() < SOLVER, "reaction time differs by {dr} s");
    assert!((h.summary.peak_contact_force - plain.peak_contact_force).abs() / plain.peak_contact_force < 1e-3);
    assert_eq!(h.summary.mode, plain.mode);
    // The start (latched until the operator's reset press, which the rig makes before sim time 0),
    // then the trip.
    assert_eq!(f.event_log.len(), 2);
    assert_eq!(f.event_log[0].cause, "Reset");
    assert!(f.event_log[0].at_s < 0.0, "before the plant run");
    assert_eq!(f.event_log[1].cause, "Trip");
    assert!(!f.category0, "5 mm + 1.2 mm stopping distance fits in 30 mm of stroke");
}

#[test]
fn dead_time_spans_latency_to_one_scan_cycle_uniformly_over_phases() {
    let sc = bistable();
    let n = 32;
    let mut dts: Vec<f64> = (0..n).map(|i| hil_at(&sc, (i as f64 + 0.5) / n as f64).firmware.observed_dead_time.unwrap()).collect();
    dts.sort_by(f64::total_cmp);
    let latency_max = flinch_hal_sim::latency::edge_to_stop_s() + 1e-6;
    assert!(dts[0] >= -1e-6, "never negative: {:?}", dts);
    assert!(dts[n - 1] <= SCAN + latency_max, "never beyond one scan cycle: {:?}", dts);
    // Uniform: phases (i + 0.5) / n hit the cycle at evenly spaced points, so the sorted dead times
    // are evenly spaced by SCAN / n too.
    for w in dts.windows(2) {
        assert!(((w[1] - w[0]) - SCAN / n as f64).abs() < 1e-5, "{:?}", dts);
    }
    let mean = dts.iter().sum::<f64>() / n as f64;
    assert!((mean - SCAN / 2.0).abs() < SCAN / n as f64, "mean {mean}");
}

#[test]
fn a_stroke_too_short_for_the_stopping_distance_escalates_to_category_0() {
    // V_c = 0.25 m/s with a 70 ms scan cycle: v DT + v^2/2d = 17.5 + 15.6 mm > 30 - 5 mm left.
    let sc = scene::load(&scene_path("tables5-7_bistable_v025.toml")).unwrap();
    let ctl = Controller::new(0.07, 0.0, 1e-4);
    let h = hil::run(&sc, &ctl, false).unwrap().0;
    assert!(h.firmware.category0, "{:?}", h.firmware);
}

#[test]
fn a_rigid_tool_is_refused_with_a_reason() {
    let sc = scene::load(&scene_path("tables5-7_rigid.toml")).unwrap();
    let ctl = Controller::new(SCAN, 0.0, 1e-4);
    let e = hil::run(&sc, &ctl, false).unwrap_err();
    assert!(e.contains("sensor.kind") && e.contains("travel"), "{e}");
}

// ---- Single faults in the loop (issue 10): each ends in stop until a person resets ---------------

fn with_faults(scene: &Scene, two_channels: bool, faults: Vec<hil::Injection>) -> hil::HilReport {
    let ctl = Controller::new(SCAN, 0.3, 1e-3);
    let opts = hil::HilOptions { faults, two_channels, ..Default::default() };
    hil::run_with(scene, &ctl, false, &opts).unwrap_or_else(|e| panic!("{e}")).0
}

/// The reason a run must end with when `kind` is injected at `at_s` (the switch fires at `t_sw`).
/// A fault the firmware can see while armed is latched under its own name; one it can only see at a
/// demand (a relay that does not release, a channel that does not follow) is latched under its own
/// name after the collision's trip; a fault that is indistinguishable from what a stopped machine
/// shows (the EDM wire reading "released" once the relays have released, a channel stuck at the
/// tripped level once both have tripped) leaves the trip latched.
fn expected_reason(kind: hil::FaultKind, at_s: f64, t_sw: f64, two_channels: bool) -> &'static str {
    use hil::FaultKind::*;
    let tick = 1e-3;
    let armed_for = |delay_s: f64| at_s + delay_s + 2.0 * tick < t_sw;
    match kind {
        StuckRest | StuckRestB if two_channels => "stopped: fault latched (discrepancy)",
        StuckRest if at_s <= t_sw => "GO: the firmware is armed with the fault present (not detected)",
        StuckRest => "stopped: trip latched",
        StuckTrip | CutWire if two_channels && armed_for(0.0) => "stopped: fault latched (discrepancy)",
        StuckTrip | CutWire => "stopped: trip latched",
        WeldedOutput => "stopped: fault latched (edm-mismatch)",
        EdmWireCut if armed_for(0.020) => "stopped: fault latched (edm-mismatch)",
        EdmWireCut => "stopped: trip latched",
        ClockStall => "stopped: fault latched (clock-stall)",
        Reset => "stopped: fault latched (reset)",
        StuckRestB => unreachable!("refused with one channel"),
        Output(_) => unreachable!("tests/hil_output_faults.rs"),
    }
}

#[test]
fn every_single_fault_at_the_worst_instants_ends_in_stop_with_its_own_reason() {
    let sc = bistable();
    let t_sw = sim::run(&sc, false).unwrap().0.t_detect.unwrap();
    // Right after the start, just before the switch fires (during detection), at the switch instant,
    // half a scan cycle later (the controller has not sampled yet), and once the trip has latched.
    let instants = [0.0, t_sw - 1e-4, t_sw, t_sw + SCAN / 2.0, t_sw + 3.0 * SCAN];
    for two in [true, false] {
        for &(name, kind, _) in hil::FAULTS {
            // The output faults have their own file (tests/hil_output_faults.rs).
            if (!two && kind == hil::FaultKind::StuckRestB) || kind.output().is_some() {
                continue;
            }
            for &at_s in &instants {
                let h = with_faults(&sc, two, vec![hil::Injection { kind, at_s }]);
                let o = &h.firmware.faults[0];
                let want = expected_reason(kind, at_s, t_sw, two);
                assert_eq!(o.reason, want, "{name}@{at_s} ({} channels)", if two { 2 } else { 1 });
                if !want.starts_with("GO") {
                    assert!(!o.ended_in_go && o.stopped_s.is_some(), "{name}@{at_s}: {o:?}");
                }
            }
        }
    }
}

/// The first logged event of `cause` at or after `from_s`, its instant in seconds.
fn logged(h: &hil::HilReport, cause: &str, from_s: f64) -> Option<f64> {
    h.firmware.event_log.iter().find(|e| e.cause == cause && e.at_s >= from_s - 1e-6).map(|e| e.at_s)
}

#[test]
fn faults_visible_while_armed_are_found_before_the_collision_by_their_own_detection() {
    // Injected at 50 ms, 276 ms before the switch would fire: each must be caught by its own
    // detection (the event log names it, within its detection time), the robot braked long before
    // the collision, and the switch never fires. With the detection removed, the run would end in
    // the collision's trip (or in go) and these fail.
    let sc = bistable();
    let t_sw = sim::run(&sc, false).unwrap().0.t_detect.unwrap();
    let at_s = 0.05;
    let tick = 1e-3;
    use hil::FaultKind::*;
    // (fault, channels, reason, logged cause, latest detection after the injection, s)
    let cases = [
        (StuckTrip, true, "stopped: fault latched (discrepancy)", "Discrepancy", 0.020 + 2.0 * tick),
        (CutWire, true, "stopped: fault latched (discrepancy)", "Discrepancy", 0.020 + 2.0 * tick),
        (EdmWireCut, true, "stopped: fault latched (edm-mismatch)", "EdmMismatch", 0.020 + 2.0 * tick),
        (EdmWireCut, false, "stopped: fault latched (edm-mismatch)", "EdmMismatch", 0.020 + 2.0 * tick),
        (ClockStall, true, "stopped: fault latched (clock-stall)", "ClockStall", 2.0 * tick),
        (ClockStall, false, "stopped: fault latched (clock-stall)", "ClockStall", 2.0 * tick),
        (Reset, true, "stopped: fault latched (reset)", "Reset", 0.0),
        (Reset, false, "stopped: fault latched (reset)", "Reset", 0.0),
    ];
    for (kind, two, reason, cause, delay_s) in cases {
        let h = with_faults(&sc, two, vec![hil::Injection { kind, at_s }]);
        let o = &h.firmware.faults[0];
        let what = format!("{kind:?} ({} channels)", if two { 2 } else { 1 });
        assert_eq!(o.reason, reason, "{what}");
        let found = logged(&h, cause, at_s).unwrap_or_else(|| panic!("{what}: no {cause} event: {:?}", h.firmware.event_log));
        assert!(found <= at_s + delay_s + 1e-9, "{what}: {cause} logged at {found} s, injected at {at_s} s");
        let stopped = o.stopped_s.unwrap();
        assert!(stopped <= at_s + delay_s + 1e-9, "{what}: stop at {stopped} s");
        let brake = h.summary.t_brake.unwrap_or_else(|| panic!("{what}: never braked"));
        assert!(brake < at_s + delay_s + SCAN + 1e-9 && brake < t_sw, "{what}: braked at {brake} s");
        assert!(h.summary.t_detect.is_none(), "{what}: the switch fired at {:?}: the collision was not avoided", h.summary.t_detect);
    }
    // One channel: a switch stuck or cut at the tripped level is a trip at once (the same signal as
    // a collision), logged from the edge at the injection instant.
    for kind in [StuckTrip, CutWire] {
        let h = with_faults(&sc, false, vec![hil::Injection { kind, at_s }]);
        assert_eq!(h.firmware.faults[0].reason, "stopped: trip latched", "{kind:?}");
        assert_eq!(logged(&h, "Trip", at_s), Some(at_s), "{kind:?}: {:?}", h.firmware.event_log);
        assert!(h.summary.t_detect.is_none(), "{kind:?}: the collision was not avoided");
    }
}

#[test]
fn faults_visible_only_at_a_demand_are_named_after_the_collision_trip() {
    // A welded relay shows nothing while the stop is energised; a channel stuck at rest shows nothing
    // until the other one trips. Injected at 50 ms, each is found at the collision, within the EDM
    // settle time or the discrepancy time after the switch fires, and named in the log.
    let sc = bistable();
    let t_sw = sim::run(&sc, false).unwrap().0.t_detect.unwrap();
    let at_s = 0.05;
    let tick = 1e-3;
    use hil::FaultKind::*;
    let cases = [
        (WeldedOutput, true, "stopped: fault latched (edm-mismatch)", "EdmMismatch"),
        (WeldedOutput, false, "stopped: fault latched (edm-mismatch)", "EdmMismatch"),
        (StuckRest, true, "stopped: fault latched (discrepancy)", "Discrepancy"),
        (StuckRestB, true, "stopped: fault latched (discrepancy)", "Discrepancy"),
    ];
    for (kind, two, reason, cause) in cases {
        let h = with_faults(&sc, two, vec![hil::Injection { kind, at_s }]);
        let o = &h.firmware.faults[0];
        let what = format!("{kind:?} ({} channels)", if two { 2 } else { 1 });
        assert_eq!(o.reason, reason, "{what}");
        let stopped = o.stopped_s.unwrap();
        assert!((stopped - t_sw).abs() < 1e-4, "{what}: stopped at {stopped} s, the switch fired at {t_sw} s");
        let found = logged(&h, cause, at_s).unwrap_or_else(|| panic!("{what}: no {cause} event: {:?}", h.firmware.event_log));
        assert!(found >= t_sw && found <= t_sw + 0.020 + 2.0 * tick, "{what}: {cause} at {found} s, switch at {t_sw} s");
    }
}

#[test]
fn one_channel_stuck_at_rest_is_the_fault_it_cannot_see_and_the_report_says_go() {
    let sc = bistable();
    let h = with_faults(&sc, false, vec![hil::Injection { kind: hil::FaultKind::StuckRest, at_s: 0.1 }]);
    let o = &h.firmware.faults[0];
    assert!(o.ended_in_go && o.stopped_s.is_none(), "{o:?}");
    assert!(h.summary.t_brake.is_none(), "the robot never braked: the collision went unnoticed");
    // The same fault with the second channel: stopped by channel B at the demand, latched.
    let h = with_faults(&sc, true, vec![hil::Injection { kind: hil::FaultKind::StuckRest, at_s: 0.1 }]);
    assert!(h.summary.t_brake.is_some());
    assert_eq!(h.firmware.faults[0].reason, "stopped: fault latched (discrepancy)");
}

#[test]
fn fault_specs_parse_and_bad_ones_say_what_is_allowed() {
    let f = hil::parse_faults("welded-output@0.3, stuck-rest@0.2,reset@0.25").unwrap();
    let kinds: Vec<_> = f.iter().map(|i| (i.kind, i.at_s)).collect();
    assert_eq!(kinds, [(hil::FaultKind::StuckRest, 0.2), (hil::FaultKind::Reset, 0.25), (hil::FaultKind::WeldedOutput, 0.3)]);
    assert!(hil::parse_faults("nope@1").unwrap_err().contains("stuck-rest"));
    assert!(hil::parse_faults("reset@-1").unwrap_err().contains(">= 0"));
    assert!(hil::parse_faults("reset").unwrap_err().contains("NAME@SECONDS"));
    assert!(hil::parse_faults("").unwrap().is_empty());
}

// ---- The board's latency, category 0, filter and reset policy, refusals (issue 10 item 7) --------

#[test]
fn the_firmware_latency_is_the_measured_worst_case_not_zero() {
    // A controller sample inside the board's latency after the switch: with a zero latency it
    // would see the stop there; with the board's (20.75 us) it cannot, and braking comes one scan
    // cycle later.
    let sc = bistable();
    let t_sw = sim::run(&sc, false).unwrap().0.t_detect.unwrap();
    let lat = flinch_hal_sim::latency::edge_to_stop_s();
    assert_eq!(lat, flinch_hal_sim::latency::worst_seconds(flinch_hal_sim::latency::WORST_EDGE_TO_STOP_INSTRUCTIONS));
    assert!(lat > 2e-6, "{lat}");
    let after = lat / 2.0;
    let h = hil_at(&sc, ((t_sw + after) / SCAN).fract());
    let f = &h.firmware;
    assert_eq!(f.edge_to_stop_latency, lat);
    let dt = f.observed_dead_time.unwrap();
    assert!((dt - (after + SCAN)).abs() < 1e-6, "the sample {after} s after the edge is inside the latency: dead time {dt}");
    // The stop output as the controller sees it changes latency after the edge.
    let (at, level) = f.stop_output[1];
    assert!(level && (at - (f.switch_time.unwrap() + lat)).abs() < 1e-9, "{:?}", f.stop_output);
    // And a sample 3 us past the latency sees it at once.
    let past = lat + 3e-6;
    let h = hil_at(&sc, ((t_sw + past) / SCAN).fract());
    assert!((h.firmware.observed_dead_time.unwrap() - past).abs() < 1e-6);
}

fn v025() -> Scene {
    scene::load(&scene_path("tables5-7_bistable_v025.toml")).unwrap()
}

#[test]
fn category_0_removes_drive_power_and_the_brakes_stop_the_robot() {
    // V_c = 0.25 m/s, 70 ms scan cycle: the stroke budget escalates at the edge.
    let sc = v025();
    let mut ctl = Controller::new(0.07, 0.0, 1e-4);
    let h = hil::run(&sc, &ctl, false).unwrap().0;
    let f = &h.firmware;
    assert!(f.category0);
    let t_sw = f.switch_time.unwrap();
    let off = f.power_removed.unwrap();
    assert!((off - (t_sw + flinch_hal_sim::latency::tick_to_output_s())).abs() < 1e-9, "power off at {off}, switch at {t_sw}");
    assert!(off < f.stop_seen.unwrap(), "the escalation acts on the drives, not through the scan cycle");
    // The brakes: coast 80 ms at 0.25 m/s, then 5 m/s^2 to rest (plant/brake.rs defaults), not the
    // controlled stop at motion.decel after the controller's sample.
    let t_stop = h.summary.t_stop.unwrap();
    assert!((t_stop - (off + 0.08 + 0.25 / 5.0)).abs() < 1e-9, "t_stop {t_stop}");
    assert_eq!(f.brakes_engaged, Some(off + 0.08));
    let controlled = f.stop_seen.unwrap() + 0.25 / sc.motion.decel;
    assert!((t_stop - controlled).abs() > 1e-3, "the controlled stop would end at {controlled}");
    // Stronger brakes stop sooner: the plant follows the scene's brake keys.
    ctl.brake_decel = 50.0;
    ctl.brake_delay = 0.01;
    let h2 = hil::run(&sc, &ctl, false).unwrap().0;
    assert!((h2.summary.t_stop.unwrap() - (off + 0.01 + 0.25 / 50.0)).abs() < 1e-9);
    assert!(h2.summary.max_travel < h.summary.max_travel, "{} vs {}", h2.summary.max_travel, h.summary.max_travel);
    // Without escalation (a stroke that fits) nothing is removed.
    let h3 = hil_at(&bistable(), 0.0);
    assert!(!h3.firmware.category0 && h3.firmware.power_removed.is_none());
}

#[test]
fn a_category_0_stopping_table_gives_the_brakes() {
    // Robot data for category 0: D = v 0.05 + v^2 / 4, T = 0.05 + v / 2 (delay 50 ms, 2 m/s^2).
    let mut sc = v025();
    let v = [0.1, 0.25];
    let d: Vec<f64> = v.iter().map(|v| v * 0.05 + v * v / 4.0).collect();
    let t: Vec<f64> = v.iter().map(|v| 0.05 + v / 2.0).collect();
    sc.motion.stopping = Some(flinch_harness::stopping::StoppingTable::new(0, &v, &d, &t).unwrap());
    let h = hil::run(&sc, &Controller::new(0.07, 0.0, 1e-4), false).unwrap().0;
    let f = &h.firmware;
    assert!(f.category0, "{f:?}");
    assert!(f.brake_source.contains("motion.stopping"), "{}", f.brake_source);
    let off = f.power_removed.unwrap();
    assert!((h.summary.t_stop.unwrap() - (off + t[1])).abs() < 1e-6, "T(0.25) = {} after power off", t[1]);
}

#[test]
fn a_linear_decoupler_with_a_travel_switch_is_refused_for_its_real_reason() {
    let mut sc = scene::load(&scene_path("table2_linear.toml")).unwrap();
    sc.sensor = Some(scene::Sensor::Travel { threshold: 0.005 });
    let e = hil::run(&sc, &Controller::new(SCAN, 0.0, 1e-4), false).unwrap_err();
    assert!(e.starts_with("decoupler.kind") && e.contains("no end-stops") && e.contains("stroke budget"), "{e}");
    assert!(!e.contains("StrokeNotPositive"), "{e}");
}

#[test]
fn a_filter_confirms_on_ticks_and_adds_its_latency() {
    let sc = bistable();
    let tick = 1e-4;
    let opts = hil::HilOptions { filter: hil::parse_filter("consecutive:3").unwrap(), ..Default::default() };
    let h = hil::run_with(&sc, &Controller::new(SCAN, 0.0, tick), false, &opts).unwrap().0;
    let f = &h.firmware;
    assert_eq!(f.filter, "consecutive:3");
    let t_sw = f.switch_time.unwrap();
    let (at, level) = f.stop_output[1];
    // Three tripped tick samples: the third tick after the edge, plus the tick path's latency.
    let third_tick = ((t_sw / tick).floor() + 3.0) * tick;
    assert!(level && (at - (third_tick + flinch_hal_sim::latency::tick_to_output_s())).abs() < 2e-6, "stop seen at {at}, switch {t_sw}, third tick {third_tick}");
    let plain = hil_at(&sc, 0.0);
    assert!(h.summary.t_brake.unwrap() >= plain.summary.t_brake.unwrap());
    assert!(hil::parse_filter("consecutive:0").unwrap_err().contains("1 to 255"));
    assert!(hil::parse_filter("min-duration:0.0000005").is_err());
    assert_eq!(hil::parse_filter("min-duration:0.002").unwrap(), flinch_firmware::Filter::MinDuration(2000));
    assert!(hil::parse_filter("median").unwrap_err().contains("consecutive:N"));
}

#[test]
fn an_automatic_reset_policy_clears_the_trip_once_the_tool_is_back() {
    // The hydraulic module returns to its front stop after the object has gone (table 12): with
    // auto:0.01 the stop output goes back to "go" 10 ms after; with the input policy it stays.
    let sc = scene::load(&scene_path("table12_hydraulic_object.toml")).unwrap();
    let ctl = Controller::new(SCAN, 0.0, 1e-4);
    let latched = hil::run(&sc, &ctl, false).unwrap().0;
    assert_eq!(latched.firmware.stop_output.len(), 2, "input policy: latched, {:?}", latched.firmware.stop_output);
    let opts = hil::HilOptions { reset: hil::parse_reset_policy("auto:0.01").unwrap(), ..Default::default() };
    let auto = hil::run_with(&sc, &ctl, false, &opts).unwrap().0;
    assert_eq!(auto.firmware.reset_policy, "auto:0.01");
    let out = &auto.firmware.stop_output;
    assert!(out.len() >= 3 && !out[2].1, "cleared after the tool returned: {out:?}");
    assert!(out[2].0 > out[1].0 + 0.01, "{out:?}");
    assert!(hil::parse_reset_policy("auto:-1").is_err() && hil::parse_reset_policy("button").unwrap_err().contains("auto:SECONDS"));
}

// ---- hil against run (issue 12 item 3) ------------------------------------------------------------

/// Every shipped scene `flinch hil` accepts, run with a controller whose scan cycle is the scene's
/// dead time and whose samples fall on the switch instant: the stop (after the board's latency)
/// misses that sample and is seen one dead time later, which is what `flinch run` assumes. The two
/// must then agree to the solver's tolerance, up to where the firmware escalates to category 0
/// (which `run` does not model).
#[test]
fn hil_gives_the_plain_runs_results_on_every_shipped_scene() {
    let dir = scene_path("");
    let mut names: Vec<_> = std::fs::read_dir(&dir).unwrap().flatten().map(|e| e.path()).filter(|p| p.extension().is_some_and(|x| x == "toml")).collect();
    names.sort();
    let mut compared = 0;
    for p in names {
        let Ok(sc) = scene::load(&p) else { continue };
        if hil::refusal(&sc).is_some() || sc.motion.stopping.is_some() || sc.motion.brake_after_contact > 0 || sc.motion.dead_time <= 0.0 {
            continue;
        }
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        let plain = sim::run(&sc, false).unwrap().0;
        let Some(t_sw) = plain.t_detect else { continue };
        let ctl = Controller::new(sc.motion.dead_time, (t_sw / sc.motion.dead_time).fract(), 1e-4);
        let h = hil::run(&sc, &ctl, false).unwrap_or_else(|e| panic!("{name}: {e}")).0;
        let s = &h.summary;
        // The solver's accuracy: every shipped scene within 1.1e-4 of the reference at the default
        // tolerances (scene/solver.rs), so two runs stepping differently agree to about twice that;
        // times to 1e-5 s (the old lockstep test's figure).
        let close = |a: f64, b: f64, tol: f64| (a - b).abs() <= tol * b.abs().max(1e-3);
        const T: f64 = 1e-5;
        assert!((h.firmware.switch_time.unwrap() - t_sw).abs() < T, "{name}: switch {:?} vs {t_sw}", h.firmware.switch_time);
        assert_eq!(s.t_contact.is_some(), plain.t_contact.is_some(), "{name}");
        if h.firmware.category0 {
            // Up to the escalation the runs are the same plant.
            assert!((s.t_contact.unwrap() - plain.t_contact.unwrap()).abs() < T, "{name}");
            continue;
        }
        assert!((s.t_brake.unwrap() - plain.t_brake.unwrap()).abs() < T, "{name}: t_brake {:?} vs {:?}", s.t_brake, plain.t_brake);
        assert!((s.t_stop.unwrap() - plain.t_stop.unwrap()).abs() < T, "{name}");
        assert!(close(s.peak_contact_force, plain.peak_contact_force, 1e-3), "{name}: peak contact {} vs {}", s.peak_contact_force, plain.peak_contact_force);
        assert!(close(s.peak_robot_force, plain.peak_robot_force, 1e-3), "{name}: peak robot {} vs {}", s.peak_robot_force, plain.peak_robot_force);
        assert!(close(s.max_travel, plain.max_travel, 1e-3), "{name}: travel {} vs {}", s.max_travel, plain.max_travel);
        assert_eq!((s.mode, s.contacts, s.safe), (plain.mode, plain.contacts, plain.safe), "{name}");
        // And the cost: at most twice the plain run's right-hand sides.
        assert!(s.rhs_evals <= 2 * plain.rhs_evals, "{name}: {} RHS evaluations against {}", s.rhs_evals, plain.rhs_evals);
        compared += 1;
    }
    assert!(compared >= 5, "only {compared} scenes compared");
}

// ---- A category-0 power removal at its instant, not at the end of a solver step ------------------

/// The MCU resets (watchdog) 7.3 ms into the controlled stop on Tables 5-7: the restarted firmware
/// latches its reset and drops both outputs, so drive power goes `tick_to_output_s()` after the
/// injection (IEC 60204-1 9.2.2, category 0), while the arm decelerates (not cruising, so the
/// plant's past cannot be rewritten after the step). Before the fix the removal landed on the end
/// of the solver step it was found in (639 us late at the defaults), so the power-off instant and
/// the stop moved with `solver.max_step` and with the injection's place in a step.
#[test]
fn a_category_0_power_removal_lands_at_its_instant_whatever_the_step_grid() {
    let lat = flinch_hal_sim::latency::tick_to_output_s();
    let base = bistable();
    let ctl0 = Controller::new(SCAN, 0.0, 1e-4);
    let plain = hil::run(&base, &ctl0, false).unwrap().0;
    let t_brake = plain.summary.t_brake.unwrap();
    let at = t_brake + 7.3e-3;
    assert!(at + lat < plain.summary.t_stop.unwrap(), "inside the controlled stop");
    let brake = flinch_harness::plant::brake::PowerOffBrake::of(&ctl0);
    let mut stops = Vec::new();
    for max_step in [1e-2, 1e-3, 2.7e-4] {
        for tick in [1e-4, 1e-3] {
            let mut sc = base.clone();
            sc.solver.max_step = max_step;
            let ctl = Controller::new(SCAN, 0.0, tick);
            let opts = hil::HilOptions { faults: vec![hil::Injection { kind: hil::FaultKind::Reset, at_s: at }], ..Default::default() };
            let h = hil::run_with(&sc, &ctl, false, &opts).unwrap_or_else(|e| panic!("{e}")).0;
            let f = &h.firmware;
            let label = format!("max_step {max_step} s, tick {tick} s");
            assert!(f.category0, "{label}");
            let off = f.power_removed.unwrap();
            // Exact: the instant is a breakpoint of the motion law the solver steps onto; 1e-12 s is
            // the rounding of the sums that make it.
            assert!((off - (at + lat)).abs() < 1e-12, "{label}: power removed at {off}, due at {}", at + lat);
            assert_eq!(f.stop_seen, plain.firmware.stop_seen, "{label}");
            // Coasting from v(off) = V_c - d_c (off - t_brake) for the brake delay, then the brakes:
            // t_stop follows in closed form from the motion law (plant/brake.rs).
            let v_off = sc.motion.speed - sc.motion.decel * (off - t_brake);
            let want = off + brake.delay + v_off / brake.decel;
            let t_stop = h.summary.t_stop.unwrap();
            assert!((t_stop - want).abs() < 1e-9, "{label}: t_stop {t_stop}, closed form {want}");
            assert!(!h.summary.warnings.iter().any(|w| w.contains("applied at")), "{label}: {:?}", h.summary.warnings);
            stops.push((label, t_stop, h.summary.max_travel));
        }
    }
    // And the plant after it: the largest travel agrees across step grids to the solver's accuracy
    // (the 1e-3 relative of the hil-against-run comparison below).
    let (_, _, x0) = &stops[0];
    for (label, _, x) in &stops {
        assert!((x - x0).abs() <= 1e-3 * x0, "{label}: max travel {x} vs {x0}");
    }
}

/// The same removal with the history streamed: the pass that found the removal late has handed
/// rows to the stream already; the run that follows must not hand them again or go back in time.
#[test]
fn a_rerun_for_category_0_streams_each_row_once() {
    let sc = bistable();
    let ctl = Controller::new(SCAN, 0.0, 1e-4);
    let t_brake = hil::run(&sc, &ctl, false).unwrap().0.summary.t_brake.unwrap();
    let opts = hil::HilOptions { faults: vec![hil::Injection { kind: hil::FaultKind::Reset, at_s: t_brake + 7.3e-3 }], ..Default::default() };
    let (kept, history) = hil::run_with(&sc, &ctl, true, &opts).unwrap();
    let mut ts = Vec::new();
    let mut sink = |s: &sim::Sample, _: &hil::RowSignals<'_>| ts.push(s.t);
    let (streamed, _) = hil::run_recording(&sc, &ctl, &opts, hil::Record::Stream(&mut sink)).unwrap();
    assert!(ts.windows(2).all(|w| w[1] > w[0]), "rows in time order, once each");
    assert_eq!(ts.len(), history.len());
    assert!(ts.iter().zip(&history).all(|(a, b)| (a - b.t).abs() < 1e-12));
    assert_eq!(streamed.firmware.power_removed, kept.firmware.power_removed);
}
