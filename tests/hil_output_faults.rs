//! The board's output faults in the loop (issue 25 item 3, host side): `flinch hil --fault` injects
//! a stuck stop pin, a frozen port (K1, K2, the escalation) and welded relays (K2, K1 and K2) at the
//! worst instants; each ends in a safe state (the stop circuit open, or drive power removed), and
//! the time from the demand to it is what `hal_sim::output_faults` bounds and the run reports.

use flinch_harness::scene::{self, Controller, Scene};
use flinch_harness::{hil, sim};
use flinch_hal_sim::{latency, OutputFault};
use flinch_tests::scene_path;

const SCAN: f64 = 0.016;
const TICK: f64 = 1e-3;

fn bistable() -> Scene {
    scene::load(&scene_path("tables5-7_bistable.toml")).unwrap_or_else(|e| panic!("{e}"))
}

fn with_fault(sc: &Scene, two_channels: bool, kind: hil::FaultKind, at_s: f64) -> hil::HilReport {
    let opts = hil::HilOptions { faults: vec![hil::Injection { kind, at_s }], two_channels, ..Default::default() };
    hil::run_with(sc, &Controller::new(SCAN, 0.3, TICK), false, &opts).unwrap_or_else(|e| panic!("{e}")).0
}

fn output_faults() -> Vec<(&'static str, hil::FaultKind, OutputFault)> {
    hil::FAULTS.iter().filter_map(|&(n, k, _)| k.output().map(|f| (n, k, f))).collect()
}

#[test]
fn every_output_fault_has_its_hal_sim_name() {
    let named = output_faults();
    assert_eq!(named.len(), OutputFault::ALL.len());
    for f in OutputFault::ALL {
        assert!(named.iter().any(|&(n, _, g)| g == f && n == f.name()), "{f:?} not under --fault {}", f.name());
        let spec = format!("{}@0.1", f.name());
        assert_eq!(hil::parse_faults(&spec).unwrap()[0].kind, hil::FaultKind::Output(f));
    }
}

/// Right after the start, before the switch (found while armed, or not), at the switch instant,
/// half a scan later (the controller has not sampled yet), and once the trip has latched: with
/// one and two switch channels, every output fault ends in a safe state, never in "go".
#[test]
fn every_output_fault_at_the_worst_instants_ends_in_stop() {
    let sc = bistable();
    let t_sw = sim::run(&sc, false).unwrap().0.t_detect.unwrap();
    let instants = [0.0, t_sw - 5e-3, t_sw - 1e-4, t_sw, t_sw + SCAN / 2.0, t_sw + 3.0 * SCAN];
    for two in [false, true] {
        for (name, kind, _) in output_faults() {
            for &at_s in &instants {
                let h = with_fault(&sc, two, kind, at_s);
                let o = &h.firmware.faults[0];
                let label = format!("{name}@{at_s} ({} channels)", if two { 2 } else { 1 });
                assert!(!o.ended_in_go && o.stopped_s.is_some(), "{label}: {o:?}");
                assert!(o.reason.starts_with("stopped"), "{label}: {}", o.reason);
                // A fault found while armed stops the cell before the collision: no demand comes.
                let Some(t_demand) = h.firmware.switch_time else {
                    assert!(o.stopped_s.unwrap() < t_sw, "{label}: no demand, and no stop before it: {o:?}");
                    continue;
                };
                let safe = h.firmware.demand_to_safe_s.unwrap_or_else(|| panic!("{label}: never safe after the demand at {t_demand} s"));
                let bound = o.extra_dead_time_bound_s.unwrap() + latency::tick_to_output_s() + 2.0 * TICK;
                assert!(safe <= bound, "{label}: safe {safe} s after the demand, bound {bound} s");
            }
        }
    }
}

/// A fault that leaves one stop channel working costs nothing at the demand: the other channel
/// opens the stop circuit at the edge, as without the fault (or the fault was found while armed
/// and the cell was stopped before the demand).
#[test]
fn one_working_channel_stops_at_the_edge() {
    let sc = bistable();
    let t_sw = sim::run(&sc, false).unwrap().0.t_detect.unwrap();
    for (name, kind, f) in output_faults() {
        if f == OutputFault::WeldedK1K2 {
            continue;
        }
        let h = with_fault(&sc, false, kind, t_sw - 1e-4);
        let o = &h.firmware.faults[0];
        assert_eq!(o.extra_dead_time_bound_s, Some(0.0), "{name}");
        let safe = h.firmware.demand_to_safe_s.unwrap();
        assert!(safe <= latency::edge_to_stop_s() + 1e-9, "{name}: safe {safe} s after the demand");
    }
}

/// Both relays welded: nothing opens the stop circuit; the EDM sees the mismatch after its settle
/// time and the escalation removes drive power (category 0), within the bound `hil` reports
/// (EDM settle 20 ms + two ticks + the board's tick-to-output). The robot's controller never sees
/// a stop; the brakes stop the arm (plant/brake.rs).
#[test]
fn both_relays_welded_end_in_category_0_within_the_reported_bound() {
    let sc = bistable();
    let t_sw = sim::run(&sc, false).unwrap().0.t_detect.unwrap();
    let h = with_fault(&sc, false, hil::FaultKind::Output(OutputFault::WeldedK1K2), t_sw - 5e-3);
    let f = &h.firmware;
    let o = &f.faults[0];
    assert!(f.category0, "{f:?}");
    assert!(o.reason.contains("drive power removed (category 0)"), "{}", o.reason);
    let bound = o.extra_dead_time_bound_s.unwrap();
    assert!((bound - (0.020 + 2.0 * TICK + latency::tick_to_output_s())).abs() < 1e-12, "{bound}");
    let off = f.power_removed.unwrap() - t_sw;
    assert!(off >= 0.020 && off <= bound + 1e-9, "power removed {off} s after the demand, bound {bound} s");
    let off_hil = f.power_removed.unwrap() - f.switch_time.unwrap();
    assert!((f.demand_to_safe_s.unwrap() - off_hil).abs() < 1e-12, "{:?} vs {off_hil}", f.demand_to_safe_s);
    assert!(f.stop_output.iter().all(|&(_, l)| !l), "the stop circuit never opened: {:?}", f.stop_output);
    assert!(f.stop_seen.is_none() && h.summary.t_stop.is_some(), "stopped by the brakes, not the controller");
    let text = hil::human(f);
    // 20 ms EDM settle + 2 ticks + the board's tick to output bound (1,518 us).
    assert!(text.contains("output fault: adds up to 23.518 ms"), "{text}");
}

/// `flinch check` carries the same faults into the stroke budget: five add no dead time (another
/// channel opens the stop circuit), both relays welded add the EDM settle time, two ticks and the
/// board's tick-to-output, and then only category 0 stops the arm (coast for the brake delay, then
/// the brake), which does not fit at 0.25 m/s.
#[test]
fn check_shows_the_output_faults_against_the_budget() {
    for (name, fits_welded) in [("tables5-7_bistable.toml", true), ("tables5-7_bistable_v025.toml", false)] {
        let sc = scene::load(&scene_path(name)).unwrap();
        let c = flinch_harness::check::check(&sc).unwrap();
        assert_eq!(c.output_faults.len(), OutputFault::ALL.len());
        let v = sc.motion.speed;
        for f in &c.output_faults {
            if f.fault == OutputFault::WeldedK1K2.name() {
                // hil's default tick (0.1 ms) and category-0 brake (80 ms, 5 m/s^2; plant/brake.rs).
                let extra = 0.020 + 2.0 * 1e-4 + latency::tick_to_output_s();
                assert!((f.extra_dead_time_s - extra).abs() < 1e-12, "{name}: {f:?}");
                let d = v * (extra + 0.08) + v * v / (2.0 * 5.0);
                assert!((f.stopping_distance_m - d).abs() < 1e-12, "{name}: {f:?}");
                assert_eq!(f.fits, fits_welded, "{name}: {f:?}");
            } else {
                assert_eq!((f.extra_dead_time_s, f.stopping_distance_m, f.fits), (0.0, c.stopping_distance, c.fits), "{name}: {f:?}");
            }
        }
        let text = flinch_harness::check::human(&c);
        assert!(text.contains("output faults of the board: 5 of 6 add no dead time"), "{text}");
        assert_eq!(text.contains("welded-k1-k2: +21.718 ms, category 0 only") && text.contains("DOES NOT FIT"), !fits_welded, "{text}");
    }
}
