//! How `flinch hil` forms the dead time from the switch to braking (issue 26 item 2), and says so.
//!
//! `flinch run` puts the scene's `motion.dead_time` (DT) in whole, from detection to braking. With
//! the firmware in the loop the dead time comes out of three parts instead:
//!
//! 1. the board's latency from the switch edge to its stop output (`hal_sim::latency`; more through
//!    a glitch filter, which confirms on ticks);
//! 2. the wait for the robot controller's next scan sample, anything from 0 to one `scan_cycle`
//!    (the phase decides; Ch. 3.1.2: "in the worst case ... it is necessary to wait a full scan
//!    cycle");
//! 3. the robot's reaction once a sample has seen the stop (brake engagement, drive delay):
//!    `[controller] reaction_time` (or `flinch hil --reaction-time`), by default the part of the
//!    scene's DT beyond one scan, so that DT = scan_cycle + reaction is the worst case of 2 + 3,
//!    and 0 (with a warning) when DT is shorter than one scan.
//!
//! With a `motion.stopping` table the reaction ends at the table's stop signal and the table's
//! equivalent dead time follows (model/src/stopping.rs), as in `flinch run`. Before this, `hil`
//! braked at the sample itself: the scene's DT was ignored, so a scene modelling "16 ms scan +
//! 30 ms brake reaction" lost its 30 ms (tests/hil_timing.rs).

use flinch_hal_sim::latency;
use flinch_model::scene::{Controller, ReactionSource, Scene};
use serde::Serialize;

/// The robot's reaction after the sample that saw the stop, s, and the words for where it came from.
pub fn reaction(scene: &Scene, ctl: &Controller) -> (f64, ReactionSource) {
    ctl.reaction(scene.motion.dead_time)
}

/// The dead time the firmware's stroke budget assumes, s: the board's edge-to-stop latency, a
/// whole scan cycle (the worst wait), the reaction, and with a stopping table its equivalent dead
/// time at V_c (what `Motion::total_dead_time` adds to DT).
pub fn budget_dead_time(scene: &Scene, ctl: &Controller) -> f64 {
    let m = &scene.motion;
    latency::edge_to_stop_s() + ctl.scan_cycle + reaction(scene, ctl).0 + (m.total_dead_time() - m.dead_time)
}

/// How the dead time of a `flinch hil` run was formed. JSON names carry their unit.
#[derive(Debug, Clone, Serialize, PartialEq, schemars::JsonSchema)]
pub struct DeadTimeModel {
    /// The controller's scan cycle, s.
    pub scan_cycle_s: f64,
    /// The robot's reaction after the sample that saw the stop, s.
    pub reaction_time_s: f64,
    /// Where `reaction_time_s` came from: `controller.reaction_time`, `motion.dead_time -
    /// scan_cycle`, or `0: motion.dead_time < scan_cycle`.
    pub reaction_time_source: String,
    /// The scene's `motion.dead_time`, s (what `flinch run` and `flinch check` use).
    pub scene_dead_time_s: f64,
    /// With a `motion.stopping` table, its equivalent dead time at V_c after the stop signal, s
    /// (0 without a table).
    pub stopping_table_dead_time_s: f64,
    /// Worst case of the dead time, s: the board's edge-to-stop latency + one scan cycle +
    /// the reaction (+ the stopping table's dead time); without a filter the observed dead time
    /// never exceeds it.
    pub worst_case_s: f64,
    /// From the switch to the stop output the controller reads, s (the board's latency; through a
    /// filter, its confirmation too). Null without a stop.
    pub stop_output_latency_s: Option<f64>,
    /// From that output to the scan sample that saw it, s (0 to one scan cycle).
    pub scan_wait_s: Option<f64>,
    /// The controller's phase was the worst one (`--worst-phase`): the wait was a whole scan.
    pub worst_phase: bool,
    /// The observed dead time, braking (or the stopping table's stop) minus the switch, s: the sum
    /// of the parts above. Null without braking.
    pub observed_s: Option<f64>,
    /// The same, in words: how the total was formed.
    pub formed: String,
    #[serde(skip)]
    #[schemars(skip)]
    source: Option<ReactionSource>,
}

fn ms(x: f64) -> String {
    format!("{:.3} ms", x * 1e3)
}

impl DeadTimeModel {
    /// The model of `scene` under `ctl`, with what the run observed: the switch instant, the stop
    /// output as the controller's input saw it, the sample that saw it, and braking.
    pub fn new(scene: &Scene, ctl: &Controller, worst_phase: bool, switch: Option<f64>, stop_output: &[(f64, bool)], stop_seen: Option<f64>, t_brake: Option<f64>) -> Self {
        let (r, source) = reaction(scene, ctl);
        let table = scene.motion.total_dead_time() - scene.motion.dead_time;
        let worst = latency::edge_to_stop_s() + ctl.scan_cycle + r + table;
        // The last change to "stop" the sample can have read.
        let output = stop_seen.and_then(|seen| stop_output.iter().take_while(|(at, _)| *at <= seen).filter(|(_, l)| *l).last().map(|(at, _)| *at));
        let stop_output_latency = output.zip(switch).map(|(o, s)| o - s);
        let scan_wait = stop_seen.zip(output).map(|(seen, o)| seen - o);
        let observed = t_brake.zip(switch).map(|(b, s)| b - s);
        let source_words = match source {
            ReactionSource::Given => "controller.reaction_time",
            ReactionSource::DeadTimeLessScan => "motion.dead_time - scan_cycle",
            ReactionSource::DeadTimeShorterThanScan => "0: motion.dead_time < scan_cycle",
        };
        let table_words = if table > 0.0 { format!(" + stopping table {}", ms(table)) } else { String::new() };
        let parts = format!(
            "board {} + scan wait {} (scan cycle {}, {}) + robot reaction {} ({source_words}){table_words}",
            stop_output_latency.map_or("-".into(), |x| format!("{:.1} us", x * 1e6)),
            scan_wait.map_or("-".into(), ms),
            ms(ctl.scan_cycle),
            if worst_phase { "worst phase: the sample before just missed the stop".to_string() } else { format!("phase {:.2}; --worst-phase waits the whole scan", ctl.phase) },
            ms(r),
        );
        let formed = match observed {
            Some(o) => format!("{} = {parts}; worst case {} (a full scan's wait); the scene's motion.dead_time {}", ms(o), ms(worst), ms(scene.motion.dead_time)),
            None => format!("none observed (the controller saw no stop); the model: {parts}; worst case {} (a full scan's wait); the scene's motion.dead_time {}", ms(worst), ms(scene.motion.dead_time)),
        };
        Self {
            scan_cycle_s: ctl.scan_cycle,
            reaction_time_s: r,
            reaction_time_source: source_words.into(),
            scene_dead_time_s: scene.motion.dead_time,
            stopping_table_dead_time_s: table,
            worst_case_s: worst,
            stop_output_latency_s: stop_output_latency,
            scan_wait_s: scan_wait,
            worst_phase,
            observed_s: observed,
            formed,
            source: Some(source),
        }
    }

    /// What the user must know when the model and the scene's DT disagree (for the summary's
    /// warnings), if they do.
    pub fn warning(&self) -> Option<String> {
        let split = self.scan_cycle_s + self.reaction_time_s;
        match self.source {
            Some(ReactionSource::DeadTimeShorterThanScan) => Some(format!(
                "dead time: motion.dead_time {} is shorter than the scan cycle {}: the controller alone can take a whole cycle to see the stop, so this run's dead time (up to {}) exceeds the scene's DT, which `flinch run` and `flinch check` use; the robot's reaction is taken as 0 (set controller.reaction_time to model it)",
                ms(self.scene_dead_time_s), ms(self.scan_cycle_s), ms(self.worst_case_s)
            )),
            Some(ReactionSource::Given) if (split - self.scene_dead_time_s).abs() > 1e-9 => Some(format!(
                "dead time: scan cycle {} + reaction {} = {} differs from motion.dead_time {}: this run forms its dead time from the scan and the reaction; `flinch run` and `flinch check` use motion.dead_time",
                ms(self.scan_cycle_s), ms(self.reaction_time_s), ms(split), ms(self.scene_dead_time_s)
            )),
            _ => None,
        }
    }
}
