//! What a recorded sample means beyond the plant's raw coordinates: the travel back from the front
//! stop (the quantity the summary's `max_travel` and the switch threshold use), the hydraulic's gas
//! pressure (eq 47, a function of the stroke coordinate alone), and, with the firmware in the loop,
//! the switch level, the firmware's stop output and what the robot controller's samples saw.

use flinch_hil::HilReport;
use flinch_plant::decoupler::hydraulic::HydraulicCylinder;
use flinch_plant::{decoupler::Decoupler, Plant};
use flinch_model::scene::{Scene, Sensor};
use flinch_sim::Sample;

/// The firmware-in-the-loop signals, as step functions of time.
#[derive(Debug, Clone, PartialEq)]
pub struct HilSignals {
    /// The travel switch trips at this travel, m (d_sw).
    pub threshold_m: f64,
    /// The firmware's stop output over the run, `(t_s, stop_requested)` at t = 0 and at each
    /// change: armed (go) after the self-test, dropped at the detection and latched until a reset.
    pub stop_output: Vec<(f64, bool)>,
    /// The controller sample that saw the stop request, s (braking starts there).
    pub stop_seen_s: Option<f64>,
    /// The controller's sampling instants, s: phase * scan_cycle + k * scan_cycle, up to the run's
    /// end.
    pub controller_samples_s: Vec<f64>,
}

impl HilSignals {
    /// From the firmware-in-the-loop report: the stop output as the firmware drove it (its boot
    /// "Reset" event, logged during the self-test before t = 0, is not a stop in the run), and the
    /// controller samples every scan cycle.
    pub fn new(scene: &Scene, rep: &HilReport) -> Self {
        let f = &rep.firmware;
        let mut s = Self::before_run(scene, f.scan_cycle, f.phase);
        s.stop_output = f.stop_output.clone();
        s.stop_seen_s = f.stop_seen;
        s
    }

    /// Before the run: the threshold and the controller's samples, no stop yet (a streamed CSV's
    /// columns; the run updates the stop as it goes).
    pub fn before_run(scene: &Scene, scan_cycle: f64, phase: f64) -> Self {
        let threshold_m = match scene.sensor {
            Some(Sensor::Travel { threshold }) => threshold,
            _ => f64::NAN,
        };
        let mut controller_samples_s = Vec::new();
        if scan_cycle > 0.0 {
            // Bounded: a plot or CSV needs no more than a few thousand ticks to be read.
            let n = ((scene.duration_s / scan_cycle).ceil() as usize).min(100_000);
            controller_samples_s.extend((0..=n).map(|k| (phase + k as f64) * scan_cycle).take_while(|&t| t <= scene.duration_s));
        }
        Self { threshold_m, stop_output: Vec::new(), stop_seen_s: None, controller_samples_s }
    }
}

/// Derived columns of a run's samples.
#[derive(Debug, Clone)]
pub struct Trace {
    /// Stroke coordinate of the front stop (or rest), m: travel = this - s.
    travel_origin_m: f64,
    gas: Option<HydraulicCylinder>,
    /// Firmware-in-the-loop signals, for `flinch hil`.
    pub hil: Option<HilSignals>,
}

impl Trace {
    /// For a run of `scene`.
    pub fn new(scene: &Scene) -> Self {
        let plant = Plant::new(scene);
        let travel_origin_m = plant.decoupler.front_stop().map_or(plant.s_rest, |f| f.at);
        let gas = match plant.decoupler {
            Decoupler::Hydraulic(h) => Some(h),
            _ => None,
        };
        Self { travel_origin_m, gas, hil: None }
    }

    /// With the firmware's signals.
    pub fn with_hil(mut self, signals: HilSignals) -> Self {
        self.hil = Some(signals);
        self
    }

    /// Travel back from the front stop (or rest), m.
    pub fn travel(&self, s: &Sample) -> f64 {
        self.travel_origin_m - s.s
    }

    /// Gas pressure p1, Pa (hydraulic only).
    pub fn gas_pressure(&self, s: &Sample) -> Option<f64> {
        self.gas.as_ref().map(|h| h.gas_pressure(s.s))
    }

    /// True for a hydraulic decoupler (a gas-pressure column and panel).
    pub fn has_gas(&self) -> bool {
        self.gas.is_some()
    }

    /// Switch tripped (travel at or past d_sw), with the firmware in the loop.
    pub fn switch_tripped(&self, s: &Sample) -> Option<bool> {
        self.hil.as_ref().map(|h| self.travel(s) >= h.threshold_m)
    }

    /// The firmware's stop output at `t`: true when it asks the robot to stop.
    pub fn stop_requested(&self, t: f64) -> Option<bool> {
        self.hil.as_ref().map(|h| h.stop_output.iter().take_while(|&&(at, _)| at <= t).last().is_some_and(|&(_, stop)| stop))
    }

    /// The stop request as the controller last sampled it at `t`.
    pub fn stop_seen(&self, t: f64) -> Option<bool> {
        self.hil.as_ref().map(|h| h.stop_seen_s.is_some_and(|at| t >= at))
    }
}
